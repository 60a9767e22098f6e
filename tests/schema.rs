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
