//! The files `rodloop diagram` writes are the result schema: `rodloop_schema::Diagram::read`
//! reads a diagram directory of each model, and writing what it read gives the same bytes
//! (`run_id` and all), so the schema's one writer is what wrote them.

mod common;

use std::path::Path;

use common::{rodloop_ok, tmp};
use rodloop_schema::Diagram;

/// Read `dir`, write it again in memory, compare with the files on disk.
fn reads_back_byte_for_byte(dir: &Path) -> Diagram {
    let d = Diagram::read(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    for (name, bytes) in d.files().unwrap() {
        let disk = std::fs::read(dir.join(&name)).unwrap();
        assert!(
            disk == bytes,
            "{name} of {} differs when written again:\n{}\n---\n{}",
            dir.display(),
            String::from_utf8_lossy(&disk),
            String::from_utf8_lossy(&bytes)
        );
    }
    d
}

#[test]
fn exact_diagram_is_the_schema() {
    let out = tmp("schema-exact");
    rodloop_ok(&[
        "diagram",
        "--model",
        "exact",
        "--lbar-max",
        "3",
        "--out",
        out.to_str().unwrap(),
    ]);
    let d = reads_back_byte_for_byte(&out);
    assert_eq!(d.model, "exact");
    assert_eq!(d.axes[0].name, "lbar");
    assert_eq!((d.axes[0].min, d.axes[0].max), (1.0, 3.0));
    // Branches 1 and 2 exchange the lowest energy between L̄ = 1 and 3 (paper Table 1).
    assert!(d.critical.iter().any(|c| c.kind == "crossing"));
    assert!(d.special.is_none() && d.warnings.is_none());
    assert!(d
        .points
        .iter()
        .all(|p| p.index.is_none() && p.family.is_none()));
}

#[test]
fn numeric_diagram_is_the_schema() {
    let out = tmp("schema-numeric");
    rodloop_ok(&[
        "diagram",
        "--accuracy",
        "fast",
        "--lbar-max",
        "2.5",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]);
    let d = reads_back_byte_for_byte(&out);
    assert_eq!(d.model, "numeric");
    assert_eq!(d.accuracy.as_deref(), Some("fast"));
    // Every state names its loop table, and the file is there.
    for p in &d.points {
        let f = p.state_file.as_deref().expect("state_file column");
        assert!(out.join(f).is_file(), "{f}");
        assert_eq!(p.coords.len(), 1);
        assert!(p.coords[0] >= 1.0 - 1e-12 && p.coords[0] <= 2.5 + 1e-12);
    }
    // The curves cover the points: every state belongs to a traced curve of its branch.
    assert!(!d.curves.is_empty());
    for p in &d.points {
        assert!(d.curves.iter().any(|c| c.branch == p.branch
            && c.span.0 <= p.coords[0] + 1e-12
            && p.coords[0] <= c.span.1 + 1e-12));
    }
}

#[test]
fn enclosed_diagram_is_the_schema() {
    let out = tmp("schema-enclosed");
    rodloop_ok(&[
        "diagram",
        "--scene",
        "data/scenes/homogeneous-enclosed.toml",
        "--lbar-max",
        "2.5",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]);
    let d = reads_back_byte_for_byte(&out);
    assert_eq!(d.model, "enclosed");
    // Lift-off and landing events are special points; a homogeneous scene needs no
    // certificate search (an empty list).
    let special = d.special.as_ref().expect("special_points.csv");
    assert!(special
        .iter()
        .all(|s| ["lift-off", "landing", "detachment", "branch_point"].contains(&s.kind.as_str())));
    assert_eq!(d.certificate, Some(serde_json::json!([])));
    // Every state names its loop table; one that could not be written is a warning.
    let mut unwritten = 0;
    for p in &d.points {
        assert!(matches!(
            p.label.as_deref(),
            Some("stable" | "metastable" | "unstable")
        ));
        match p.state_file.as_deref() {
            Some("") => unwritten += 1,
            Some(f) => assert!(out.join(f).is_file(), "{f}"),
            None => panic!("no state_file column"),
        }
    }
    assert!(unwritten <= d.warnings.as_ref().map_or(0, Vec::len));
}

/// `rodloop phase` writes the schema's `summary.json`: read back, it is written again to the
/// same bytes; every row of `phase.csv` is the schema's critical length of the same position,
/// placed on the curve it names, and each curve counts its rows.
#[test]
fn phase_diagram_is_the_schema() {
    let out = tmp("schema-phase");
    rodloop_ok(&[
        "phase",
        "--scene",
        "data/scenes/inhomogeneous-d1-0.5.toml",
        "--to",
        "0.3",
        "--accuracy",
        "fast",
        "--out",
        out.to_str().unwrap(),
    ]);
    let d = Diagram::read(&out).unwrap();
    assert_eq!(
        d.summary_json().unwrap(),
        std::fs::read(out.join("summary.json")).unwrap()
    );
    let p = d.parameter.as_ref().expect("the parameter");
    assert_eq!((p.name.as_str(), p.scene_value, p.target), ("d1", 0.5, 0.3));
    let curves = d.exchange_curves.as_ref().expect("the curves");
    assert!(!curves.is_empty() && !d.critical.is_empty());
    let (header, rows) = common::read_csv(&out.join("phase.csv"));
    assert_eq!(rows.len(), d.critical.len());
    let cell = |r: &[String], name: &str| r[common::col(&header, name)].clone();
    let num = |r: &[String], name: &str| cell(r, name).parse::<f64>().unwrap();
    for (r, c) in rows.iter().zip(&d.critical) {
        let at = c.curve_row().expect("a row of a curve");
        assert_eq!(num(r, "lbar_cr"), c.lbar_cr);
        assert_eq!(num(r, "value"), at.value);
        assert_eq!(num(r, "slope"), at.slope);
        assert_eq!(cell(r, "source"), at.source);
        assert_eq!(cell(r, "curve"), at.curve.to_string());
        assert_eq!(cell(r, "from_branch"), c.from_branch.to_string());
        // The row lies on its curve's exchange (the lowest pair at the scene's value).
        assert!(at.curve >= 1 && at.curve <= curves.len());
        assert!(at.value >= 0.3 - 1e-12 && at.value <= 1.0 + 1e-12);
    }
    for (k, c) in curves.iter().enumerate() {
        let named = d
            .critical
            .iter()
            .filter(|r| r.curve_row().unwrap().curve == k + 1)
            .count();
        assert_eq!(c.rows, named, "curve {}", k + 1);
    }
}

/// `rodloop diagram --param` writes the schema's `branches.csv` and `summary.json`: read
/// back, both are written again to the same bytes; `special_points.csv` holds the schema's
/// special points with the parameter's value, and every point belongs to a family.
#[test]
fn param_diagram_is_the_schema() {
    let out = tmp("schema-param");
    rodloop_ok(&[
        "diagram",
        "--scene",
        "data/scenes/inhomogeneous-d1-0.5.toml",
        "--param",
        "d1",
        "--lbar",
        "1.5",
        "--to",
        "0.3",
        "--accuracy",
        "fast",
        "--out",
        out.to_str().unwrap(),
    ]);
    let d = Diagram::read(&out).unwrap();
    assert_eq!(
        d.branches_csv().unwrap(),
        std::fs::read(out.join("branches.csv")).unwrap()
    );
    assert_eq!(
        d.summary_json().unwrap(),
        std::fs::read(out.join("summary.json")).unwrap()
    );
    let axes: Vec<&str> = d.axes.iter().map(|a| a.name.as_str()).collect();
    assert_eq!(axes, ["value", "lbar"]);
    let p = d.parameter.as_ref().expect("the parameter");
    assert_eq!((p.name.as_str(), p.scene_value, p.target), ("d1", 0.5, 0.3));
    let families = d.families.as_ref().expect("the families");
    assert!(!d.points.is_empty());
    for q in &d.points {
        assert_eq!(q.coords[1], 1.5);
        assert!(q.coords[0] >= 0.3 - 1e-12 && q.coords[0] <= 0.5 + 1e-12);
        assert!(families
            .iter()
            .any(|f| f.branch == q.branch && Some(f.family as u32) == q.family));
    }
    assert_eq!(
        families.iter().map(|f| f.states).sum::<usize>(),
        d.points.len()
    );
    let special = d.special.as_ref().expect("special points");
    let (header, rows) = common::read_csv(&out.join("special_points.csv"));
    assert_eq!(rows.len(), special.len());
    for (r, s) in rows.iter().zip(special) {
        assert_eq!(r[common::col(&header, "kind")], s.kind);
        assert_eq!(
            r[common::col(&header, "value")].parse::<f64>().unwrap(),
            s.value.expect("the parameter's value")
        );
        assert_eq!(
            r[common::col(&header, "energy")].parse::<f64>().unwrap(),
            s.energy
        );
    }
}
