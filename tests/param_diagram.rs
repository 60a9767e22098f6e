//! End-to-end tests of `rodloop diagram --param`: the equilibria of a two-segment rod at a
//! fixed length traced against D1/D0, through the built binary.

mod common;

use common::{assert_refused, rodloop, tmp};

/// The number after `key` in `text`.
fn number_after(text: &str, key: &str) -> f64 {
    let i = text.find(key).unwrap_or_else(|| panic!("{key} in {text}")) + key.len();
    let s: String = text[i..]
        .chars()
        .take_while(|c| c.is_ascii_digit() || *c == '.' || *c == '-' || *c == 'e')
        .collect();
    s.parse()
        .unwrap_or_else(|_| panic!("number after {key} in {text}"))
}

/// Two independent methods meet: `phase` (continuation of the Maxwell point of two states)
/// switches at the pitchfork of the figure-eight near D1/D0 = 0.157; tracing the states at
/// that length against D1/D0 (continuation of one state) finds a fold or branch point of
/// branch 2 at the same D1/D0. At the scene's value the sweep's seeds have the energies
/// `solve` finds for both branches on its own.
#[test]
fn sweep_meets_the_phase_switch_and_solve() {
    let out = tmp("pd-phase");
    let o = rodloop(&[
        "phase",
        "--scene",
        "data/scenes/inhomogeneous-d1-0.5.toml",
        "--to",
        "0.1",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary = common::summary(&out);
    let switch = summary["curves"][0]["switches"][0]
        .as_str()
        .unwrap()
        .to_string();
    let d1_switch = number_after(&switch, "past d1 = ");
    let lbar = number_after(&switch, "at L̄ = ");

    let sweep = tmp("pd-sweep");
    let o = rodloop(&[
        "diagram",
        "--scene",
        "data/scenes/inhomogeneous-d1-0.5.toml",
        "--param",
        "d1",
        "--lbar",
        &format!("{lbar}"),
        "--to",
        "0.1",
        "--out",
        sweep.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = common::summary(&sweep);
    let near: Vec<f64> = s["special_points"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|p| p["branch"] == 2 && p["kind"] != "index_change")
        .map(|p| p["value"].as_f64().unwrap())
        .collect();
    // The phase's L̄ is printed to 6 digits: the fold moves by |dθ/dL̄|·5e-7 at most.
    assert!(
        near.iter().any(|v| (v - d1_switch).abs() < 2e-5),
        "phase switch at {d1_switch}, sweep special points {near:?}"
    );
    for branch in [1, 2] {
        let fam = s["families"]
            .as_array()
            .unwrap()
            .iter()
            .find(|f| f["branch"] == branch && f["seed_value"] == 0.5)
            .expect("a family seeded at the scene's value");
        let (e, est) = (
            fam["seed_energy"].as_f64().unwrap(),
            fam["seed_energy_error"].as_f64().unwrap(),
        );
        let dir = tmp(&format!("pd-solve-{branch}"));
        let o = rodloop(&[
            "solve",
            "--scene",
            "data/scenes/inhomogeneous-d1-0.5.toml",
            "--lbar",
            &format!("{lbar}"),
            "--branch",
            &branch.to_string(),
            "--out",
            dir.to_str().unwrap(),
        ]);
        assert!(o.status.success());
        let so = common::summary(&dir);
        let (es, ests) = (
            so["energy"].as_f64().unwrap(),
            so["error_estimate"].as_f64().unwrap(),
        );
        assert!(
            (e - es).abs() <= 2.0 * (est + ests) + 1e-10,
            "branch {branch}: sweep {e} ± {est:.1e}, solve {es} ± {ests:.1e}"
        );
    }
    // Outputs: one row per state, labels, a figure.
    let csv = std::fs::read_to_string(sweep.join("branches.csv")).unwrap();
    let header = csv.lines().next().unwrap();
    assert!(header.contains("param") && header.contains("lbar") && header.contains("stability"));
    assert!(csv.contains(",stable,") && !csv.to_lowercase().contains("nan"));
    assert!(sweep.join("special_points.csv").exists());
    assert!(sweep.join("diagram.png").exists());
}

#[test]
fn bad_combinations_are_refused() {
    let out = tmp("pd-bad");
    let o = out.to_str().unwrap();
    let scene = "data/scenes/inhomogeneous-d1-0.5.toml";
    for (args, msg) in [
        (
            vec![
                "diagram", "--scene", scene, "--param", "d1", "--lbar", "1.4", "--model", "exact",
                "--out", o,
            ],
            "--model exact",
        ),
        (
            vec!["diagram", "--scene", scene, "--param", "d1", "--out", o],
            "needs --lbar",
        ),
        (
            vec!["diagram", "--scene", scene, "--lbar", "1.4", "--out", o],
            "belong to --param",
        ),
        (
            vec![
                "diagram", "--scene", scene, "--param", "gamma", "--lbar", "1.4", "--out", o,
            ],
            "needs --to",
        ),
        (
            vec![
                "diagram", "--scene", scene, "--param", "d1", "--lbar", "2", "--out", o,
            ],
            "great circle",
        ),
        (
            vec![
                "diagram", "--scene", scene, "--param", "d1", "--lbar", "1.4", "--to", "-1",
                "--out", o,
            ],
            "--to",
        ),
        (
            vec![
                "diagram",
                "--scene",
                "data/scenes/homogeneous-surface.toml",
                "--param",
                "d1",
                "--lbar",
                "1.4",
                "--out",
                o,
            ],
            "two-segment",
        ),
        // Options of the diagram in L̄, which --param would otherwise ignore silently.
        (
            vec![
                "diagram", "--scene", scene, "--param", "d1", "--lbar", "1.4", "--shapes", "3",
                "--out", o,
            ],
            "--shapes",
        ),
        (
            vec![
                "diagram",
                "--scene",
                scene,
                "--param",
                "d1",
                "--lbar",
                "1.4",
                "--max-step",
                "0.1",
                "--out",
                o,
            ],
            "--max-step",
        ),
    ] {
        assert_refused(&args, msg);
    }
    assert!(!out.join("branches.csv").exists());
}
