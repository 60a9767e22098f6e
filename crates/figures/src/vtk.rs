//! A loop table as VTK PolyData (`.vtp`, XML, ASCII) for ParaView and other VTK readers: the
//! points `x, y, z`, one closed polyline cell through them (the last point joined to the
//! first), and every other column of the table (`s, kappa, tau, kappa_g, lambda, F_t, F_n,
//! F_b, D, gap, …`) as point data. Numbers are written in Rust's shortest round-trip form,
//! so that reading the file back gives the table's values bit for bit.

use std::fmt::Write as _;

use crate::data::LoopData;
use crate::FigureError;

/// Escape the characters XML reserves in attribute values.
fn attr(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Append `values` to `out`, a few per line.
fn numbers(out: &mut String, values: impl Iterator<Item = f64>) {
    for (k, v) in values.enumerate() {
        if k % 6 == 0 {
            out.push_str("\n          ");
        } else {
            out.push(' ');
        }
        let _ = write!(out, "{v:?}");
    }
    out.push_str("\n        ");
}

/// The `.vtp` document of a loop table; `field` adds named scalars for the whole loop
/// (`FieldData`, e.g. `lbar`, `energy`). Refuses a table without `x, y, z`, with fewer than
/// three points, or with a value that is not finite.
pub fn loop_vtp(data: &LoopData, field: &[(&str, f64)]) -> Result<String, FigureError> {
    let n = data.len();
    for c in ["x", "y", "z"] {
        if data.column(c).is_none() {
            return Err(FigureError::MissingColumn {
                path: data.source.clone(),
                column: c.into(),
                found: data.names.join(", "),
            });
        }
    }
    if n < 3 {
        return Err(FigureError::TooFewRows {
            path: data.source.clone(),
            needed: 3,
            found: n,
        });
    }
    if let Some((name, v)) = field.iter().find(|(_, v)| !v.is_finite()) {
        return Err(FigureError::Invalid(format!(
            "{}: field {name} is not finite ({v})",
            data.source
        )));
    }
    let point_data: Vec<&String> = data
        .names
        .iter()
        .filter(|c| !["x", "y", "z"].contains(&c.as_str()))
        .collect();
    let mut out = String::with_capacity(64 * n * (point_data.len() + 3));
    out.push_str("<?xml version=\"1.0\"?>\n");
    out.push_str(
        "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n  <PolyData>\n",
    );
    if !field.is_empty() {
        out.push_str("    <FieldData>\n");
        for (name, v) in field {
            let _ = writeln!(
                out,
                "      <DataArray type=\"Float64\" Name=\"{}\" NumberOfTuples=\"1\" format=\"ascii\">{v:?}</DataArray>",
                attr(name)
            );
        }
        out.push_str("    </FieldData>\n");
    }
    let _ = writeln!(
        out,
        "    <Piece NumberOfPoints=\"{n}\" NumberOfVerts=\"0\" NumberOfLines=\"1\" NumberOfStrips=\"0\" NumberOfPolys=\"0\">"
    );
    out.push_str("      <PointData");
    if let Some(first) = point_data.iter().find(|c| c.as_str() != "s") {
        let _ = write!(out, " Scalars=\"{}\"", attr(first));
    }
    out.push_str(">\n");
    for c in &point_data {
        let v = data.column(c).unwrap_or(&[]);
        if let Some(bad) = v.iter().position(|x| !x.is_finite()) {
            return Err(FigureError::NotFinite {
                path: data.source.clone(),
                row: bad + 2,
                column: (*c).clone(),
                value: v[bad].to_string(),
            });
        }
        let _ = write!(
            out,
            "        <DataArray type=\"Float64\" Name=\"{}\" format=\"ascii\">",
            attr(c)
        );
        numbers(&mut out, v.iter().copied());
        out.push_str("</DataArray>\n");
    }
    out.push_str("      </PointData>\n      <Points>\n        <DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">");
    let pts = data.points();
    numbers(&mut out, pts.iter().flat_map(|p| [p.x, p.y, p.z]));
    out.push_str("</DataArray>\n      </Points>\n      <Lines>\n");
    // One closed polyline: 0, 1, …, n − 1, 0.
    out.push_str("        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">");
    let mut conn = String::new();
    for i in (0..n).chain([0]) {
        if i % 12 == 0 {
            conn.push_str("\n          ");
        } else {
            conn.push(' ');
        }
        let _ = write!(conn, "{i}");
    }
    out.push_str(&conn);
    out.push_str("\n        </DataArray>\n");
    let _ = writeln!(
        out,
        "        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">{}</DataArray>",
        n + 1
    );
    out.push_str("      </Lines>\n    </Piece>\n  </PolyData>\n</VTKFile>\n");
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn circle(n: usize) -> LoopData {
        let names = ["s", "x", "y", "z", "kappa"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        let t: Vec<f64> = (0..n)
            .map(|i| 2.0 * std::f64::consts::PI * i as f64 / n as f64)
            .collect();
        let cols = vec![
            t.clone(),
            t.iter().map(|a| a.cos()).collect(),
            t.iter().map(|a| a.sin()).collect(),
            vec![0.0; n],
            vec![1.0; n],
        ];
        LoopData::new("circle", names, cols).unwrap()
    }

    #[test]
    fn closed_polyline_and_point_data() {
        let text = loop_vtp(&circle(8), &[("lbar", 1.0)]).unwrap();
        assert!(text.contains("NumberOfPoints=\"8\""));
        assert!(text.contains("Name=\"kappa\""));
        assert!(text.contains("Name=\"s\""));
        // The connectivity returns to the first point: 9 entries, one offset of 9.
        let conn = text
            .split("Name=\"connectivity\" format=\"ascii\">")
            .nth(1)
            .unwrap()
            .split("</DataArray>")
            .next()
            .unwrap();
        let ids: Vec<u32> = conn
            .split_whitespace()
            .map(|v| v.parse().unwrap())
            .collect();
        assert_eq!(ids, vec![0, 1, 2, 3, 4, 5, 6, 7, 0]);
        assert!(text.contains("Name=\"offsets\" format=\"ascii\">9<"));
    }
}
