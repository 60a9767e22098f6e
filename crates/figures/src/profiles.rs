//! Quantities along the loop against arclength: position `x, y, z`, curvature `κ`, torsion
//! `τ`, geodesic curvature `κ_g` (paper Fig. 5) and the contact force `λ(s)` (Fig. 6; Eq. 38
//! for a uniform rod), one panel each, for the columns the table has.

use crate::data::{column_label, LoopData};
use crate::plot::{Plot, Series};
use crate::svg::{Anchor, Svg};
use crate::FigureError;

/// Columns drawn, in order, when present.
pub const PROFILE_COLUMNS: [&str; 9] = [
    "x", "y", "z", "kappa", "tau", "kappa_g", "lambda", "D", "gap",
];

/// The profiles figure: a grid of panels, two per row, `panel_w × panel_h` pixels each.
pub fn profiles_figure(
    data: &LoopData,
    panel_w: f64,
    panel_h: f64,
    title: &str,
) -> Result<String, FigureError> {
    Ok(profiles_document(data, None, panel_w, panel_h, title)?.finish())
}

/// [`profiles_figure`] with a second curve drawn dashed in the panels of the columns it has
/// (e.g. the aligned Euler curve of [`crate::overlay::align`], the paper's Fig. 5), named by
/// `overlay.1` in a line under the title.
pub fn profiles_figure_overlay(
    data: &LoopData,
    overlay: Option<(&LoopData, &str)>,
    panel_w: f64,
    panel_h: f64,
    title: &str,
) -> Result<String, FigureError> {
    Ok(profiles_document(data, overlay, panel_w, panel_h, title)?.finish())
}

/// [`profiles_figure_overlay`] as a document (for [`crate::paint::to_png`]).
pub fn profiles_document(
    data: &LoopData,
    overlay: Option<(&LoopData, &str)>,
    panel_w: f64,
    panel_h: f64,
    title: &str,
) -> Result<Svg, FigureError> {
    if !(200.0..=3000.0).contains(&panel_w) || !(150.0..=3000.0).contains(&panel_h) {
        return Err(FigureError::Invalid(format!(
            "profile panels must be 200–3000 × 150–3000 pixels, got {panel_w} × {panel_h}"
        )));
    }
    // A constant stiffness (a uniform rod) says nothing along the loop: no panel, a note.
    let constant_d = data.column("D").and_then(|d| {
        let (lo, hi) = d
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        (hi - lo <= 1e-12 * hi.abs().max(1.0)).then_some(lo)
    });
    let cols: Vec<&str> = PROFILE_COLUMNS
        .iter()
        .copied()
        .filter(|c| data.column(c).is_some() && !(*c == "D" && constant_d.is_some()))
        .collect();
    let rows = cols.len().div_ceil(2).max(1);
    let top = if overlay.is_some() || constant_d.is_some() {
        60.0
    } else {
        40.0
    };
    let mut svg = Svg::new(2.0 * panel_w, top + rows as f64 * panel_h);
    svg.text_bold(12.0, 26.0, 16.0, Anchor::Start, title);
    if let Some(d) = constant_d {
        svg.text(
            2.0 * panel_w - 12.0,
            48.0,
            13.0,
            Anchor::End,
            &format!(
                "D/D₀ = {} along the whole loop (uniform rod)",
                crate::svg::tick_label(d)
            ),
        );
    }
    if let Some((_, label)) = overlay {
        svg.line(14.0, 44.0, 44.0, 44.0, "#1f4fd1", 1.8, "");
        svg.text(50.0, 48.0, 13.0, Anchor::Start, "this loop");
        svg.line(140.0, 44.0, 170.0, 44.0, "#d8600c", 1.8, "6 4");
        svg.text(176.0, 48.0, 13.0, Anchor::Start, label);
    }
    let s = data.s();
    let length = data.length();
    for (k, c) in cols.iter().enumerate() {
        let v = data.column(c).unwrap_or(&[]);
        // Close the loop: repeat the first point at s = L.
        let mut pts: Vec<(f64, f64)> = s.iter().zip(v).map(|(&a, &b)| (a / length, b)).collect();
        if let (Some(&first), Some(&s0)) = (v.first(), s.first()) {
            pts.push((s0 / length + 1.0, first));
        }
        let mut series = vec![Series {
            color: "#1f4fd1".into(),
            width: 1.8,
            dash: String::new(),
            points: pts,
        }];
        if let Some(o) = overlay.and_then(|(o, _)| o.column(c).map(|v| (o.s(), v))) {
            let (os, ov) = o;
            let mut q: Vec<(f64, f64)> =
                os.iter().zip(ov).map(|(&a, &b)| (a / length, b)).collect();
            if let (Some(&first), Some(&s0)) = (ov.first(), os.first()) {
                q.push((s0 / length + 1.0, first));
            }
            series.push(Series {
                color: "#d8600c".into(),
                width: 1.8,
                dash: "6 4".into(),
                points: q,
            });
        }
        let plot = Plot {
            title: column_label(c),
            xlabel: "s/L".into(),
            ylabel: column_label(c)
                .split(" (")
                .next()
                .unwrap_or_default()
                .to_string(),
            series,
            hlines: if *c == "lambda" || *c == "kappa_g" || *c == "tau" {
                vec![0.0]
            } else {
                Vec::new()
            },
            range: None,
            ..Default::default()
        };
        let (px, py) = ((k % 2) as f64 * panel_w, top + (k / 2) as f64 * panel_h);
        plot.render(&mut svg, px, py, panel_w, panel_h, &format!("prof{k}"));
    }
    Ok(svg)
}
