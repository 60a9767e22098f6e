//! The writer and the reader of the result schema: what is written is read back equal, and a
//! diagram that cannot be written faithfully (a non-finite number, a value without a column,
//! a key the schema owns) is refused before any file is written.

use std::collections::BTreeMap;
use std::path::PathBuf;

use rodloop_schema::{Axis, Cell, Critical, Curve, Diagram, Point, SchemaError, SpecialPoint};

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("rodloop-schema-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A diagram using every kind of field: optional values present and absent, empty cells,
/// numbers that print in exponent form, extras of every type.
fn sample() -> Diagram {
    let mut d = Diagram::new(
        "numeric",
        "a scene, with a comma",
        vec![Axis {
            name: "lbar".into(),
            min: 1.0,
            max: 2.5,
        }],
        "energy E R/(pi D0)",
    );
    d.accuracy = Some("default".into());
    d.columns = [
        "branch",
        "eta",
        "lbar",
        "energy",
        "energy_g",
        "energy_error",
        "stability",
        "index",
        "family",
        "sheet",
        "arc",
        "point_group",
        "surface_energy",
        "state_file",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    for k in 0..5u32 {
        let x = 1.0 + 0.3 * f64::from(k) + 1e-13;
        d.points.push(Point {
            branch: 1 + k % 2,
            eta: 2 + k % 2,
            family: Some(k / 2),
            sheet: Some(k % 3),
            coords: vec![x],
            energy: 1.0 / x + 1e-9 * f64::from(k),
            energy_error: (k % 2 == 0).then_some(3.7e-12 * f64::from(k + 1)),
            index: Some(k as usize % 2),
            label: Some(["stable", "unstable"][k as usize % 2].into()),
            state_file: Some(format!("states/b{k}.csv")),
            extra: BTreeMap::from([
                ("energy_g".into(), Cell::F(-0.125 * f64::from(k))),
                ("arc".into(), Cell::I(1_000_000 * i64::from(k))),
                (
                    "point_group".into(),
                    Cell::S(if k == 0 { "" } else { "D2d" }.into()),
                ),
                (
                    "surface_energy".into(),
                    if k == 3 { Cell::Empty } else { Cell::F(1e-300) },
                ),
            ]),
        });
    }
    d.curves.push(Curve {
        branch: 1,
        eta: 2,
        family: 0,
        sheet: 1,
        multiplicity: 2,
        span: (1.0, 2.2),
        states: 3,
        cells: 48,
        low_end: "great circle m = 1".into(),
        high_end: "fold".into(),
        seed: "Euler curve".into(),
        seconds: 0.25,
    });
    d.critical.push(Critical {
        index: 2,
        lbar_cr: 1.234_567_890_123_4,
        kind: "crossing".into(),
        from_branch: 1,
        to_branch: 2,
        energy: 0.987_654_321,
        error_estimate: 2.5e-11,
        extra: BTreeMap::from([
            ("method".into(), serde_json::json!("re-solved")),
            ("iterations".into(), serde_json::json!(4)),
        ]),
    });
    d.special = Some(vec![
        SpecialPoint {
            kind: "fold".into(),
            lbar: 2.1,
            energy: 0.5,
            error_estimate: None,
            branch: 2,
            family: 1,
            index_before: Some(0),
            index_after: Some(1),
            value: None,
            energy_error: None,
            extra: BTreeMap::new(),
        },
        SpecialPoint {
            kind: "lift-off".into(),
            lbar: 2.2,
            energy: 0.6,
            error_estimate: Some(1e-9),
            branch: 1,
            family: 0,
            index_before: None,
            index_after: None,
            value: Some(0.25),
            energy_error: None,
            extra: BTreeMap::from([("method".into(), serde_json::json!("bisection"))]),
        },
    ]);
    d.set_certificate(&serde_json::json!({"checks": 3, "below": false}))
        .unwrap();
    d.warnings = Some(vec!["one warning".into()]);
    d.timings = Some(BTreeMap::from([
        ("total".into(), 1.5),
        ("tracing".into(), 1.0),
    ]));
    d.states_dir = Some("states".into());
    d.run_id = Some("abc-1".into());
    d.put("great_circles", &vec![(1u32, 8.0f64)]).unwrap();
    d.notes = Some(vec!["one note".into()]);
    d.lowest_lifted_off = Some(vec![(1.5, 1.75), (2.25, 2.5)]);
    d
}

#[test]
fn typed_keys_are_written_under_their_names() {
    let mut d = sample();
    let s = d.summary().unwrap();
    assert_eq!(s["notes"][0], "one note");
    assert_eq!(s["lowest_lifted_off"][1][0], 2.25);
    // No verdict: no key.
    d.lowest_lifted_off = None;
    assert!(d.summary().unwrap().get("lowest_lifted_off").is_none());
    // An engine's own key may not stand in for them.
    d.put("notes", &vec!["other"]).unwrap();
    assert!(matches!(d.summary(), Err(SchemaError::KeyClash(k)) if k == "notes"));
    // A non-finite interval end is refused, not written as null.
    let mut d = sample();
    d.lowest_lifted_off = Some(vec![(1.5, f64::NAN)]);
    assert!(d.summary().is_err());
}

#[test]
fn surface_value_of_an_enclosed_critical_length() {
    let mut c = sample().critical[0].clone();
    assert_eq!(c.surface_lbar_cr(), None);
    c.extra
        .insert("surface_lbar_cr".into(), serde_json::json!(1.25));
    assert_eq!(c.surface_lbar_cr(), Some(1.25));
}

#[test]
fn written_diagram_reads_back_equal() {
    let dir = scratch("roundtrip");
    let d = sample();
    d.write(&dir).unwrap();
    let back = Diagram::read(&dir).unwrap();
    assert_eq!(back, d);
    // Written twice, the files are the same bytes.
    let again = back.files().unwrap();
    assert_eq!(again, d.files().unwrap());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn exact_layer_shape_reads_back_equal() {
    // The exact layer: no family, index, label or state columns, no special points, no
    // warnings, a count under `branches` instead of a list of curves.
    let dir = scratch("exact");
    let mut d = Diagram::new(
        "exact",
        "homogeneous",
        vec![Axis {
            name: "lbar".into(),
            min: 1.0,
            max: 5.0,
        }],
        "u",
    );
    d.columns = ["branch", "eta", "lbar", "energy", "p", "lowest"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    d.points.push(Point {
        branch: 3,
        eta: 4,
        coords: vec![3.5],
        energy: 3.75,
        extra: BTreeMap::from([("p".into(), Cell::I(-1)), ("lowest".into(), Cell::I(0))]),
        ..Point::default()
    });
    d.put("branches", &1usize).unwrap();
    d.write(&dir).unwrap();
    let text = std::fs::read_to_string(dir.join("summary.json")).unwrap();
    assert!(!text.contains("null"), "{text}");
    assert!(!dir.join("special_points.csv").exists());
    assert_eq!(Diagram::read(&dir).unwrap(), d);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn summary_has_no_null() {
    let mut d = sample();
    d.put("absent", &None::<Vec<(f64, f64)>>).unwrap();
    d.put(
        "nested",
        &serde_json::json!({"a": null, "b": [1, {"c": null}]}),
    )
    .unwrap();
    let text = serde_json::to_string(&d.summary().unwrap()).unwrap();
    assert!(!text.contains("null"), "{text}");
    // The error estimate of the fold is absent, that of the lift-off present.
    let s = d.summary().unwrap();
    assert!(s["special_points"][0].get("error_estimate").is_none());
    assert_eq!(s["special_points"][1]["error_estimate"], 1e-9);
    // Indices that were not located are absent; what the engine adds is kept.
    assert_eq!(s["special_points"][0]["index_after"], 1);
    assert!(s["special_points"][1].get("index_before").is_none());
    assert_eq!(s["special_points"][1]["value"], 0.25);
    assert!(s["special_points"][0].get("value").is_none());
    assert_eq!(s["special_points"][1]["method"], "bisection");
    assert_eq!(s["schema_version"], rodloop_schema::VERSION);
}

#[test]
fn non_finite_numbers_are_refused() {
    let mut d = sample();
    d.points[3].energy = f64::NAN;
    match d.files() {
        Err(SchemaError::NotFinite { column, row, .. }) => {
            assert_eq!((column.as_str(), row), ("energy", 4))
        }
        other => panic!("expected NotFinite, got {other:?}"),
    }
    let mut d = sample();
    d.points[0]
        .extra
        .insert("energy_g".into(), Cell::F(f64::INFINITY));
    assert!(matches!(d.files(), Err(SchemaError::NotFinite { .. })));
    let mut d = sample();
    d.critical[0].error_estimate = f64::NAN;
    assert!(matches!(d.files(), Err(SchemaError::NotFinite { .. })));
    // A summary value: serde_json would write null; the checked setter refuses it.
    let mut d = sample();
    assert!(d.put("x", &vec![1.0, f64::NAN]).is_err());
    // Nothing is written into the directory on a refusal.
    let dir = scratch("refused");
    let mut d = sample();
    d.points[0].coords[0] = f64::NEG_INFINITY;
    assert!(d.write(&dir).is_err());
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn values_without_columns_and_clashing_keys_are_refused() {
    let mut d = sample();
    d.columns.retain(|c| c != "sheet");
    assert!(matches!(
        d.branches_csv(),
        Err(SchemaError::NoColumn { field: "sheet", .. })
    ));
    let mut d = sample();
    d.points[1].extra.insert("k".into(), Cell::F(0.5));
    assert!(matches!(
        d.branches_csv(),
        Err(SchemaError::NoColumn { .. })
    ));
    let mut d = sample();
    d.columns.push("no_such_column".into());
    assert!(matches!(
        d.branches_csv(),
        Err(SchemaError::UnknownColumn(_))
    ));
    for key in ["critical", "lbar_min", "branches"] {
        let mut d = sample();
        d.put(key, &1).unwrap();
        assert!(
            matches!(d.summary(), Err(SchemaError::KeyClash(_))),
            "{key}"
        );
    }
}

#[test]
fn two_axes_read_back_in_their_order() {
    // A diagram against a parameter at a fixed length: every point has (value, lbar).
    let dir = scratch("two-axes");
    let axis = |name: &str, min, max| Axis {
        name: name.into(),
        min,
        max,
    };
    let mut d = Diagram::new(
        "numeric",
        "two-segment",
        vec![axis("value", 1e-3, 0.5), axis("lbar", 1.2, 1.2)],
        "u",
    );
    d.columns = ["branch", "eta", "param", "value", "lbar", "energy"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    for (k, v) in [0.5, 0.1, 1e-3].into_iter().enumerate() {
        d.points.push(Point {
            branch: 1,
            eta: 2,
            coords: vec![v, 1.2],
            energy: 2.0 - 0.1 * k as f64,
            extra: BTreeMap::from([("param".into(), Cell::S("d1".into()))]),
            ..Point::default()
        });
    }
    d.write(&dir).unwrap();
    let csv = std::fs::read_to_string(dir.join("branches.csv")).unwrap();
    assert_eq!(csv.lines().nth(3), Some("1,2,d1,0.001,1.2,1.8"));
    assert_eq!(Diagram::read(&dir).unwrap(), d);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A phase diagram (critical lengths on curves in a parameter) and a diagram against a
/// parameter (families, special points at a parameter value) read back equal, with their
/// parameter, curves, rows and families typed.
#[test]
fn parameter_diagrams_read_back_equal() {
    use rodloop_schema::{
        CurveEnd, CurveRow, Exchange, ExchangeCurve, FamilyTrace, Parameter, UniformLimit,
    };
    let parameter = Parameter {
        name: "d1".into(),
        scene_value: 0.5,
        target: 1e-3,
    };
    // Phase: no axes, no points; two rows of one curve.
    let dir = scratch("phase");
    let mut d = Diagram::new("numeric", "two-segment", Vec::new(), "u");
    d.parameter = Some(parameter.clone());
    for (k, (value, source)) in [(0.5, "seed"), (0.1, "fixed")].into_iter().enumerate() {
        let mut c = Critical {
            index: k + 1,
            lbar_cr: 1.37 - 0.01 * k as f64,
            kind: "crossing".into(),
            from_branch: 1,
            to_branch: 2,
            energy: 0.9,
            error_estimate: 1e-8,
            extra: BTreeMap::new(),
        };
        let row = CurveRow {
            param: "d1".into(),
            value,
            source: source.into(),
            curve: 1,
            arm: k,
            index_from: 0,
            index_to: 1,
            slope: -0.75,
            energy_error: 2e-9,
        };
        c.set_curve_row(&row).unwrap();
        assert_eq!(c.curve_row(), Some(row));
        d.critical.push(c);
    }
    d.exchange_curves = Some(vec![ExchangeCurve {
        exchange: Exchange {
            from_branch: 1,
            to_branch: 2,
            lbar_uniform: 1.4,
        },
        rows: 2,
        steps: 7,
        cells: (64, 80),
        ends: vec![CurveEnd {
            value: 0.05,
            kind: "fold".into(),
            reason: "the Maxwell point turns back".into(),
        }],
        uniform: Some(UniformLimit {
            lbar_cr: 1.4 + 1e-9,
            error_estimate: 2e-9,
            exact: 1.4,
            deviation: 1e-9,
        }),
        turns: Vec::new(),
        switches: vec!["onto 2 -> 3".into()],
        checks: vec![0.1],
        notes: Vec::new(),
    }]);
    d.put("at", &[0.1]).unwrap();
    d.write(&dir).unwrap();
    let s = d.summary().unwrap();
    assert_eq!(
        (s["param"].as_str(), s["target"].as_f64()),
        (Some("d1"), Some(1e-3))
    );
    assert_eq!(s["critical"][1]["source"], "fixed");
    assert_eq!(s["curves"][0]["cells"], serde_json::json!([64, 80]));
    assert!(!dir.join("branches.csv").exists());
    let back = Diagram::read(&dir).unwrap();
    assert_eq!(back, d);
    assert_eq!(back.critical[1].curve_row().unwrap().arm, 1);
    // A critical length of a diagram in L̄ is on no curve.
    assert_eq!(sample().critical[0].curve_row(), None);
    std::fs::remove_dir_all(&dir).unwrap();

    // Against the parameter at a fixed length: axes value and lbar.
    let dir = scratch("sweep");
    let mut d = Diagram::new(
        "numeric",
        "two-segment",
        vec![
            Axis {
                name: "value".into(),
                min: 1e-3,
                max: 0.5,
            },
            Axis {
                name: "lbar".into(),
                min: 1.5,
                max: 1.5,
            },
        ],
        "u",
    );
    d.parameter = Some(parameter);
    d.columns = [
        "branch", "eta", "family", "param", "value", "lbar", "energy",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    d.points.push(Point {
        branch: 2,
        eta: 3,
        family: Some(0),
        coords: vec![0.25, 1.5],
        energy: 1.25,
        extra: BTreeMap::from([("param".into(), Cell::S("d1".into()))]),
        ..Point::default()
    });
    d.special = Some(vec![SpecialPoint {
        kind: "fold".into(),
        lbar: 1.5,
        energy: 1.3,
        error_estimate: None,
        branch: 2,
        family: 0,
        index_before: None,
        index_after: None,
        value: Some(0.125),
        energy_error: Some(3e-10),
        extra: BTreeMap::new(),
    }]);
    d.families = Some(vec![
        FamilyTrace {
            branch: 2,
            eta: 3,
            family: 0,
            cells: 96,
            seed_value: Some(0.5),
            seed_energy: Some(1.2),
            seed_energy_error: Some(1e-10),
            notes: Vec::new(),
            states: 1,
            end: "reached".into(),
        },
        FamilyTrace {
            branch: 3,
            eta: 4,
            family: 0,
            cells: 96,
            seed_value: None,
            seed_energy: None,
            seed_energy_error: None,
            notes: vec!["no seed".into()],
            states: 0,
            end: "not seeded".into(),
        },
    ]);
    d.write(&dir).unwrap();
    let text = std::fs::read_to_string(dir.join("summary.json")).unwrap();
    assert!(!text.contains("null"), "{text}");
    assert_eq!(Diagram::read(&dir).unwrap(), d);
    // The schema writes these keys itself: an engine's own key may not replace them.
    assert!(matches!(
        {
            let mut e = d.clone();
            e.put("families", &1).unwrap();
            e.summary()
        },
        Err(SchemaError::KeyClash(k)) if k == "families"
    ));
    std::fs::remove_dir_all(&dir).unwrap();
}
