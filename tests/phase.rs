//! End-to-end tests of `rodloop phase`: the critical lengths of a two-segment rod as curves
//! in D1/D0, through the built binary.

mod common;

use common::{assert_refused, rodloop, tmp};

/// The exact critical lengths of the uniform rod in [1, 3] (exact layer, Sec. 4.3).
fn exact_crossings() -> Vec<f64> {
    let x = rodloop_diagram::phase::uniform_exchanges(1.0, 3.0).unwrap();
    x.iter().map(|e| e.lbar_uniform).collect()
}

#[test]
fn phase_follows_both_exchanges_to_the_uniform_rod_and_down() {
    let out = tmp("phase-d1");
    let o = rodloop(&[
        "phase",
        "--scene",
        "data/scenes/inhomogeneous-d1-0.5.toml",
        "--param",
        "d1",
        "--to",
        "0.01",
        "--at",
        "0.5,0.05",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(out.join("phase.csv")).unwrap();
    assert!(!text.to_lowercase().contains("nan") && !text.contains("inf"));
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    for col in [
        "param",
        "value",
        "lbar_cr",
        "kind",
        "from_branch",
        "to_branch",
        "energy",
        "error_estimate",
    ] {
        assert!(header.contains(&col), "column {col}");
    }
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    let f = |r: &Vec<&str>, name: &str| r[col(name)].parse::<f64>().unwrap();
    let exact = exact_crossings();
    for (k, ex) in exact.iter().enumerate() {
        let curve: Vec<&Vec<&str>> = rows
            .iter()
            .filter(|r| r[col("curve")] == (k + 1).to_string())
            .collect();
        assert!(curve.len() > 10, "curve {k} has {} rows", curve.len());
        // The limit at D1/D0 = 1 meets the uniform rod's exact value to its estimate.
        let lim = curve
            .iter()
            .find(|r| r[col("source")] == "limit")
            .expect("limit row");
        assert_eq!(f(lim, "value"), 1.0);
        let dev = (f(lim, "lbar_cr") - ex).abs();
        assert!(
            dev <= 2.0 * f(lim, "error_estimate"),
            "curve {k}: deviation {dev:.2e}"
        );
        // --at 0.5 gives a row on both curves, exactly at 0.5.
        assert!(curve
            .iter()
            .any(|r| r[col("source")] == "fixed" && f(r, "value") == 0.5));
        // Every row's L̄_cr stays near its exchange and has a finite positive estimate.
        for r in &curve {
            assert!((f(r, "lbar_cr") - ex).abs() < 0.1);
            assert!(f(r, "error_estimate") >= 0.0 && f(r, "error_estimate") < 1e-5);
        }
    }
    // Both curves reach the target; the first switches onto another pair of states past the
    // pitchfork of the figure-eight near D1/D0 = 0.157 (said in summary.json and on stderr),
    // and has a row of the new pair.
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    // Every summary.json has a `units` field (docs/src/commands.md, Units).
    assert!(summary["units"]
        .as_str()
        .is_some_and(|u| u.contains("E R/(pi D0)")));
    let curves = summary["curves"].as_array().unwrap();
    assert_eq!(curves.len(), 2);
    let kinds: Vec<&str> = curves
        .iter()
        .map(|c| c["ends"][0]["kind"].as_str().unwrap())
        .collect();
    assert_eq!(kinds, ["reached", "reached"]);
    // At the decade 0.1 on the way a search for lower states of both branches found none.
    for c in curves {
        let checks = c["checks"].as_array().unwrap();
        assert!(
            checks
                .iter()
                .any(|v| (v.as_f64().unwrap() - 0.1).abs() < 1e-9),
            "{checks:?}"
        );
    }
    assert_eq!(curves[0]["switches"].as_array().unwrap().len(), 1);
    assert!(rows
        .iter()
        .any(|r| r[col("curve")] == "1" && r[col("source")] == "switch"));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("switched"), "{stderr}");
    for k in ["1", "2"] {
        assert!(rows
            .iter()
            .any(|r| r[col("curve")] == k && r[col("source")] == "fixed" && f(r, "value") == 0.05));
    }
    let svg = std::fs::read_to_string(out.join("phase.svg")).unwrap();
    assert!(svg.contains("log₁₀(D1/D0)") && svg.contains("lowest"));
    assert!(out.join("phase.png").exists());
}

#[test]
fn phase_refuses_bad_input() {
    let out = tmp("phase-bad");
    let o = out.to_str().unwrap();
    let scene = "data/scenes/inhomogeneous-d1-0.5.toml";
    for (args, msg) in [
        (
            vec![
                "phase", "--scene", scene, "--param", "d2", "--to", "0.1", "--out", o,
            ],
            "unknown parameter",
        ),
        (
            vec![
                "phase", "--scene", scene, "--param", "d1", "--to", "2", "--out", o,
            ],
            "crosses the uniform rod",
        ),
        (
            vec![
                "phase", "--scene", scene, "--param", "lbar", "--to", "2", "--out", o,
            ],
            "lbar",
        ),
        (
            vec![
                "phase",
                "--scene",
                "data/scenes/homogeneous-surface.toml",
                "--to",
                "0.1",
                "--out",
                o,
            ],
            "two-segment",
        ),
        (
            vec![
                "phase", "--scene", scene, "--to", "0.1", "--at", "0.2,-1", "--out", o,
            ],
            "--at",
        ),
    ] {
        assert_refused(&args, msg);
    }
    assert!(!out.join("phase.csv").exists());
}

/// Past the switch of the first curve (the figure-eight's pitchfork near D1/D0 = 0.157) the
/// `--at 0.1` row is a Maxwell point of the states `solve` finds on its own (robust starts,
/// no continuation in D1/D0 from the curve): at the row's L̄_cr both branches have index 0 and
/// the row's energy, to the solve's error estimates.
#[test]
fn switched_rows_agree_with_independent_solves() {
    let out = tmp("phase-switch");
    let o = rodloop(&[
        "phase",
        "--scene",
        "data/scenes/inhomogeneous-d1-0.5.toml",
        "--to",
        "0.1",
        "--at",
        "0.1",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(out.join("phase.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let row: Vec<&str> = lines
        .map(|l| l.split(',').collect::<Vec<_>>())
        .find(|r| r[col("curve")] == "1" && r[col("source")] == "fixed" && r[col("value")] == "0.1")
        .expect("--at 0.1 row of the first curve");
    let f = |name: &str| row[col(name)].parse::<f64>().unwrap();
    let (lbar, energy) = (f("lbar_cr"), f("energy"));
    let mut estimates = 0.0;
    for branch in [row[col("from_branch")], row[col("to_branch")]] {
        let dir = tmp(&format!("phase-switch-solve-{branch}"));
        let s = rodloop(&[
            "solve",
            "--scene",
            "data/scenes/inhomogeneous-d1-0.1.toml",
            "--lbar",
            &format!("{lbar:.12}"),
            "--branch",
            branch,
            "--out",
            dir.to_str().unwrap(),
        ]);
        assert!(s.status.success(), "{}", String::from_utf8_lossy(&s.stderr));
        let sum: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap())
                .unwrap();
        assert_eq!(sum["index"], 0, "branch {branch}");
        let (e, est) = (
            sum["energy"].as_f64().unwrap(),
            sum["error_estimate"].as_f64().unwrap(),
        );
        estimates += est;
        assert!(
            (e - energy).abs() <= 2.0 * est + 1e-9,
            "branch {branch}: solve {e} ± {est:.1e}, phase row {energy}"
        );
    }
    assert!(estimates > 0.0);
}
