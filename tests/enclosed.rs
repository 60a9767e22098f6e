//! `rodloop solve` and `rodloop compare --scene enclosed` on enclosed scenes.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn rodloop(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_rodloop"))
        .args(args)
        .output()
        .expect("run rodloop")
}

fn scene() -> String {
    concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/data/scenes/homogeneous-enclosed.toml"
    )
    .into()
}

fn out(name: &str) -> PathBuf {
    let p = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&p);
    p
}

/// `rodloop solve --scene SCENE --lbar LBAR --branch BRANCH --out DIR`, which must succeed
/// and name the branch of its written state as requested (`identified_eta`); returns its
/// `summary.json`.
fn solve_ok(dir: &Path, scene: &str, lbar: &str, branch: &str) -> serde_json::Value {
    let o = rodloop(&[
        "solve",
        "--scene",
        scene,
        "--lbar",
        lbar,
        "--branch",
        branch,
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    // The branch named from the written state is the one requested.
    if branch != "0" {
        assert_eq!(s["identified_eta"], s["eta"], "{s}");
    }
    s
}

/// `rodloop ARGS --out DIR` fails with a message containing `word`, no panic, no output.
fn assert_refused(all: Vec<&str>, word: &str, dir: &str) {
    let dir = out(dir);
    let d = dir.to_str().unwrap().to_string();
    let mut all: Vec<&str> = all;
    all.extend(["--out", d.as_str()]);
    let o = rodloop(&all);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(err.contains(word) && !err.contains("panicked"), "{err}");
    assert!(!dir.join("summary.json").exists());
}

/// The figure-eight at L̄ = 1.4 lifts off: config.csv has a gap column with positive gaps,
/// summary.json the contact fields; its energy is below the exact surface loop's.
#[test]
fn solve_lifted_off_state() {
    let dir = out("enclosed-solve");
    let s = solve_ok(&dir, &scene(), "1.4", "2");
    let surface = rodloop_exact::paper_branch_loop(1, 1.4).unwrap();
    let e = s["energy"].as_f64().unwrap();
    assert!(e < surface.energy().unwrap() - 1e-5);
    assert_eq!(s["contact_intervals"].as_u64(), Some(2));
    let f = s["contact_fraction"].as_f64().unwrap();
    assert!(f > 0.0 && f < 1.0);
    assert!(s["max_gap"].as_f64().unwrap() > 1e-3);
    assert!(s["optimality_lambda_min"].as_f64().unwrap() >= -1e-10);
    // The largest gap over the nodes (where the contact summary is taken) is the reported one.
    let csv = std::fs::read_to_string(dir.join("config.csv")).unwrap();
    let gmax = column(&csv, "gap")
        .iter()
        .zip(column(&csv, "node"))
        .filter(|(_, n)| *n == "1")
        .map(|(g, _)| g.parse::<f64>().unwrap())
        .fold(f64::MIN, f64::max);
    assert!((gmax - s["max_gap"].as_f64().unwrap()).abs() < 1e-12);
}

/// The numbers of column `name` of a CSV text.
fn numbers(text: &str, name: &str) -> Vec<f64> {
    column(text, name)
        .iter()
        .map(|v| v.parse().unwrap())
        .collect()
}

/// The energy of a lifted-off state (the figure-eight at L̄ = 1.4, 3-D model) recomputed
/// from its `config.csv` alone, `(1/π) Σ weight · ½ D κ²`, equals the reported energy within
/// its estimate; `node` marks every third row (a node, then the cell's two Gauss points).
/// The periodic trapezoid over the nodes alone misses it by more than the estimate: the
/// nodes' curvatures are extrapolated from the Gauss points, a second discretisation.
#[test]
fn enclosed_file_energy_is_recomputed_by_its_weights() {
    let dir = out("enclosed-file-energy");
    let s = solve_ok(&dir, &scene(), "1.4", "2");
    let (e, de) = (
        s["energy"].as_f64().unwrap(),
        s["error_estimate"].as_f64().unwrap(),
    );
    assert!(s["attached"] == false && de > 0.0, "{s}");
    let csv = std::fs::read_to_string(dir.join("config.csv")).unwrap();
    let (w, d, k, node, sc) = (
        numbers(&csv, "weight"),
        numbers(&csv, "D"),
        numbers(&csv, "kappa"),
        numbers(&csv, "node"),
        numbers(&csv, "s"),
    );
    assert_eq!(node.len() % 3, 0);
    for (i, n) in node.iter().enumerate() {
        assert_eq!(*n, if i % 3 == 0 { 1.0 } else { 0.0 }, "row {i}");
    }
    let density = |i: usize| 0.5 * d[i] * k[i] * k[i];
    let weighted: f64 = (0..w.len()).map(|i| w[i] * density(i)).sum::<f64>() / std::f64::consts::PI;
    assert!(
        (weighted - e).abs() <= de + 1e-12 * e,
        "weighted {weighted} against {e} ± {de}"
    );
    // The Gauss weights of a uniform mesh are half the node spacing each.
    let length = 2.0 * std::f64::consts::PI * 1.4;
    assert!(((w.iter().sum::<f64>()) - length).abs() < 1e-12 * length);
    let nodes: Vec<usize> = (0..node.len()).filter(|&i| node[i] == 1.0).collect();
    let trapezoid: f64 = (0..nodes.len())
        .map(|j| {
            let (a, b) = (nodes[j], nodes[(j + 1) % nodes.len()]);
            let ds = (sc[b] - sc[a]).rem_euclid(length);
            0.5 * (density(a) + density(b)) * ds
        })
        .sum::<f64>()
        / std::f64::consts::PI;
    assert!(
        (trapezoid - e).abs() > 10.0 * de,
        "node trapezoid {trapezoid} against {e} ± {de}"
    );
}

/// An attached state (branch 1 at L̄ = 1.2, λ > 0): the exact energy, gap 0.
#[test]
fn solve_attached_state_is_exact() {
    let dir = out("enclosed-attached");
    let s = solve_ok(&dir, &scene(), "1.2", "1");
    let exact = rodloop_exact::paper_branch_loop(2, 1.2)
        .unwrap()
        .energy()
        .unwrap();
    assert!((s["energy"].as_f64().unwrap() - exact).abs() <= 1e-8 * exact);
    assert_eq!(s["contact_fraction"].as_f64(), Some(1.0));
    assert!(s["max_gap"].as_f64().unwrap().abs() < 1e-12);
}

/// Bad enclosed inputs: one clear error, non-zero exit, nothing written.
#[test]
fn bad_enclosed_input() {
    for (args, word) in [
        (vec!["--lbar", "1.5", "--branch", "0"], "planar circle"),
        (vec!["--lbar", "2.5", "--branch", "2"], "exists only for"),
        (vec!["--lbar", "-1", "--branch", "1"], "lbar"),
    ] {
        let sc = scene();
        let mut all = vec!["solve", "--scene", sc.as_str()];
        all.extend(args.iter());
        assert_refused(all, word, "enclosed-bad");
    }
}

/// `rodloop diagram` on the enclosed scene writes the diagram outputs: branches.csv with the
/// contact columns, critical.csv next to the surface values, the landing of branch 2 in
/// special_points.csv, and the interval where the lowest state has lifted off.
#[test]
fn diagram_on_enclosed_scene() {
    let dir = out("enclosed-diagram");
    let sc = scene();
    let o = rodloop(&["diagram", "--scene", &sc, "--out", dir.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in [
        "branches.csv",
        "critical.csv",
        "special_points.csv",
        "diagram.svg",
        "diagram.png",
        "summary.json",
    ] {
        assert!(dir.join(f).exists(), "{f}");
    }
    let branches = std::fs::read_to_string(dir.join("branches.csv")).unwrap();
    let header = branches.lines().next().unwrap();
    for col in [
        "max_gap",
        "contact_fraction",
        "index",
        "label",
        "energy_error",
    ] {
        assert!(header.split(',').any(|c| c == col), "{header}");
    }
    let special = std::fs::read_to_string(dir.join("special_points.csv")).unwrap();
    assert!(
        special
            .lines()
            .any(|l| l.starts_with("landing,1.50612321743")),
        "{special}"
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    let lifted = summary["lowest_lifted_off"].as_array().unwrap();
    assert_eq!(lifted.len(), 1, "{summary}");
    let (a, b) = (
        lifted[0][0].as_f64().unwrap(),
        lifted[0][1].as_f64().unwrap(),
    );
    // From the enclosed 1 -> 2 exchange (below the surface one) to the landing.
    assert!(a > 1.3798 && a < 1.379941144287, "{a}");
    assert!((b - 1.506123217436).abs() < 1e-9, "{b}");
    assert!(text.contains("lifted off the wall"), "{text}");
    // The 3-D solves by stage: the lifted-off trace and the exchange solve, and every
    // solve either converged or failed for one of the three reasons.
    let solves = summary["solves"].as_object().unwrap();
    for stage in ["seed", "trace", "exchange"] {
        let c = &solves[stage];
        let n = |k: &str| c[k].as_u64().unwrap();
        assert!(n("converged") > 0, "{stage}: {c}");
        assert_eq!(
            n("attempted"),
            n("converged") + n("failed_cap") + n("failed_stall") + n("failed_other"),
            "{stage}: {c}"
        );
        assert!(n("iterations") >= n("converged"), "{stage}: {c}");
    }
}

#[test]
fn diagram_refuses_what_it_does_not_cover() {
    let sc = scene();
    let two = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/data/scenes/inhomogeneous-d1-0.5-enclosed.toml"
    );
    for (args, word) in [
        (
            vec!["--scene", sc.as_str(), "--model", "exact"],
            "--model exact",
        ),
        (
            vec!["--scene", sc.as_str(), "--max-step", "0.1"],
            "--max-step",
        ),
        (
            vec!["--scene", two, "--lbar-min", "0.5"],
            "starts at lbar = 1",
        ),
        (
            vec!["--scene", sc.as_str(), "--branch", "7"],
            "no such branch",
        ),
    ] {
        let mut all = vec!["diagram"];
        all.extend(args.iter());
        assert_refused(all, word, "enclosed-diagram-bad");
    }
}

/// The two-segment enclosed scene (D1/D0 = 0.5, gamma = 200): branch 1 at L̄ = 1.4 needs a
/// wall pulling with λ ≈ −98 D0/R³ on the surface; the enclosed solve (pull homotopy) returns
/// a first-order optimal state below the surface energy.
#[test]
fn two_segment_enclosed_state() {
    let dir = out("enclosed-two-segment");
    let sc = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/data/scenes/inhomogeneous-d1-0.5-enclosed.toml"
    );
    let s = solve_ok(&dir, sc, "1.4", "1");
    let f = |k: &str| s[k].as_f64().unwrap_or_else(|| panic!("{k}"));
    assert!(f("surface_lambda_min") < -50.0);
    assert!(f("energy") < f("surface_energy"));
    assert!(f("optimality_lambda_min") >= -1e-8);
    assert!(f("optimality_gap_min") >= -1e-10);
    assert!(f("optimality_complementarity_max") <= 1e-9);
    assert!(f("optimality_stationarity") <= 1e-8);
    assert!(f("max_gap") > 1e-4);
}

/// `solve --draw` on an enclosed scene draws the loop next to config.csv; `--from` a saved
/// enclosed state at another length reaches the state the surface-loop start reaches there
/// (the same discrete equilibrium from a different start); a file without the columns is
/// refused.
#[test]
fn solve_draw_and_from() {
    let dir = out("enclosed-draw");
    let sc = scene();
    let o = rodloop(&[
        "solve",
        "--scene",
        &sc,
        "--lbar",
        "1.4",
        "--branch",
        "2",
        "--draw",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in ["config.csv", "config.svg", "config.png", "config-draw.json"] {
        assert!(dir.join(f).exists(), "{f}");
    }
    let energy = |d: &Path| -> (f64, f64) {
        let s: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(d.join("summary.json")).unwrap())
                .unwrap();
        (
            s["energy"].as_f64().unwrap(),
            s["error_estimate"].as_f64().unwrap(),
        )
    };
    let from = dir.join("config.csv");
    let d1 = out("enclosed-from");
    let o = rodloop(&[
        "solve",
        "--scene",
        &sc,
        "--lbar",
        "1.3",
        "--branch",
        "2",
        "--from",
        from.to_str().unwrap(),
        "--out",
        d1.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let d2 = out("enclosed-direct");
    let o = rodloop(&[
        "solve",
        "--scene",
        &sc,
        "--lbar",
        "1.3",
        "--branch",
        "2",
        "--out",
        d2.to_str().unwrap(),
    ]);
    assert!(o.status.success());
    let ((e1, _), (e2, est)) = (energy(&d1), energy(&d2));
    assert!(
        (e1 - e2).abs() <= 1e-3 * est,
        "{e1} vs {e2} (estimate {est:e})"
    );
    let readme = concat!(env!("CARGO_MANIFEST_DIR"), "/README.md");
    assert_refused(
        vec![
            "solve", "--scene", &sc, "--lbar", "1.3", "--branch", "2", "--from", readme,
        ],
        "kappa_1",
        "enclosed-from-bad",
    );
}

/// The lifted-off figure-eight touches the wall along two arcs, images of each other under
/// its two-fold symmetry: `summary.json` counts two contact intervals of equal length at
/// lengths where the contact ends carry concentrated forces (at L̄ = 1.3 the touching pairs
/// just past each arc were once counted as six intervals).
#[test]
fn figure_eight_touches_along_two_equal_arcs() {
    for lbar in ["1.3", "1.45"] {
        let dir = out(&format!("enclosed-arcs-{lbar}"));
        let o = rodloop(&[
            "solve",
            "--scene",
            &scene(),
            "--lbar",
            lbar,
            "--branch",
            "2",
            "--out",
            dir.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let s: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap())
                .unwrap();
        assert_eq!(s["contact_intervals"].as_u64(), Some(2), "{lbar}: {s}");
        let runs = s["contact_runs"].as_array().unwrap();
        let len = |r: &serde_json::Value| {
            let (a, b) = (r[0].as_f64().unwrap(), r[1].as_f64().unwrap());
            (b - a).rem_euclid(1.0)
        };
        let (l0, l1) = (len(&runs[0]), len(&runs[1]));
        assert!(l0 > 0.0 && (l0 - l1).abs() < 1e-9, "{lbar}: {runs:?}");
    }
}

/// The column `name` of a CSV text (header in the first line) as strings.
fn column<'a>(text: &'a str, name: &str) -> Vec<&'a str> {
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let k = header
        .iter()
        .position(|h| *h == name)
        .unwrap_or_else(|| panic!("no column {name} in {header:?}"));
    lines.map(|l| l.split(',').nth(k).unwrap()).collect()
}

/// `rodloop diagram` on an enclosed scene writes every verified state's loop into
/// `states/` and names it in branches.csv: every file exists, lies in the ball and closes up, a
/// lifted-off state and an attached (exact) one re-solve from their files (`solve --from`)
/// to their row's energy within the two error estimates, and the free circle's file is the
/// circle of radius `L̄ R`.
#[test]
fn enclosed_diagram_writes_states() {
    let dir = out("enclosed-diagram-states");
    let sc = scene();
    let o = rodloop(&[
        "diagram",
        "--scene",
        &sc,
        "--lbar-min",
        "0.9",
        "--lbar-max",
        "1.7",
        "--step",
        "0.1",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let branches = std::fs::read_to_string(dir.join("branches.csv")).unwrap();
    let files = column(&branches, "state_file");
    let f64s = |name: &str| -> Vec<f64> {
        column(&branches, name)
            .iter()
            .map(|v| v.parse().unwrap())
            .collect()
    };
    let (branch, lbar, energy, error) = (
        column(&branches, "branch"),
        f64s("lbar"),
        f64s("energy"),
        f64s("energy_error"),
    );
    let source = column(&branches, "source");
    assert!(!files.is_empty());
    // A state that fails the diagram's verification has no file, counted in summary.json.
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    let unverified = files.iter().filter(|f| f.is_empty()).count();
    assert_eq!(
        summary["unverified_states"].as_u64(),
        Some(unverified as u64)
    );
    assert!(
        unverified < files.len() / 4,
        "{unverified} of {} without a file",
        files.len()
    );
    for f in files.iter().filter(|f| !f.is_empty()) {
        assert!(f.starts_with("states/"), "{f}");
        let text = std::fs::read_to_string(dir.join(f)).unwrap();
        let (x, y, z) = (column(&text, "x"), column(&text, "y"), column(&text, "z"));
        let pts: Vec<[f64; 3]> = (0..x.len())
            .map(|i| {
                [
                    x[i].parse().unwrap(),
                    y[i].parse().unwrap(),
                    z[i].parse().unwrap(),
                ]
            })
            .collect();
        assert!(pts.len() >= 32, "{f}");
        // Nodes inside the ball (the model's wall); Gauss points (node = 0) may lie beyond it
        // by the discretisation only, far less than 1e-4 R.
        for (p, n) in pts.iter().zip(column(&text, "node")) {
            let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
            let slack = if n == "1" { 1e-9 } else { 1e-4 };
            assert!(r <= 1.0 + slack, "{f}: |r| = {r}");
        }
        // Closed: the chord back to the first point is no longer than the longest step.
        let d = |a: &[f64; 3], b: &[f64; 3]| {
            ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
        };
        let step = pts.windows(2).map(|w| d(&w[0], &w[1])).fold(0.0, f64::max);
        assert!(d(&pts[pts.len() - 1], &pts[0]) <= 1.5 * step, "{f}");
    }
    let c = source
        .iter()
        .position(|s| *s == "circle")
        .expect("a circle state");
    let text = std::fs::read_to_string(dir.join(files[c])).unwrap();
    for (gap, k2) in column(&text, "gap").iter().zip(column(&text, "kappa_2")) {
        let (gap, k2): (f64, f64) = (gap.parse().unwrap(), k2.parse().unwrap());
        assert!((gap - (1.0 - lbar[c])).abs() < 1e-12, "{gap}");
        assert!((k2 + 1.0 / lbar[c]).abs() < 1e-12, "{k2}");
    }
    for kind in ["model", "exact"] {
        let k = (0..source.len())
            .position(|i| source[i] == kind && !files[i].is_empty())
            .unwrap_or_else(|| {
                panic!("no {kind} state in {branches}");
            });
        let re = out(&format!("enclosed-diagram-states-{kind}"));
        let from = dir.join(files[k]);
        let x = format!("{}", lbar[k]);
        let o = rodloop(&[
            "solve",
            "--scene",
            &sc,
            "--from",
            from.to_str().unwrap(),
            "--lbar",
            &x,
            "--branch",
            branch[k],
            "--out",
            re.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let s: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(re.join("summary.json")).unwrap())
                .unwrap();
        let (e, de) = (
            s["energy"].as_f64().unwrap(),
            s["error_estimate"].as_f64().unwrap(),
        );
        assert!(
            (e - energy[k]).abs() <= de + error[k] + 1e-12,
            "{kind} at {x}: re-solved {e} ± {de}, row {} ± {}",
            energy[k],
            error[k]
        );
    }
}

/// The enclosed diagram of a two-segment rod carries its completeness certificate in
/// summary.json: at lowest states spread over the range, `solve`'s state of every branch
/// there, none below the diagram's lowest state by more than the two estimates, and the
/// lowest branch's own `solve` state equal to the diagram's within them.
#[test]
fn two_segment_enclosed_diagram_certificate() {
    let dir = out("enclosed-diagram-certificate");
    let sc = Path::new(env!("CARGO_TARGET_TMPDIR")).join("mild-enclosed.toml");
    std::fs::write(
        &sc,
        "name = \"mild-enclosed\"\nradius = 1.0\nconfinement = \"enclosed\"\nlbar_min = 1.6\nlbar_max = 1.75\n\n[stiffness]\nkind = \"tanh\"\nd0 = 1.0\nd1 = 0.9\ns0 = 0.3\ns1 = 0.8\ngamma = 20.0\n",
    )
    .unwrap();
    let o = rodloop(&[
        "diagram",
        "--scene",
        sc.to_str().unwrap(),
        "--branch",
        "2",
        "--step",
        "0.02",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    let cert = summary["certificate"].as_array().expect("a certificate");
    assert!(cert.len() >= 2, "{cert:?}");
    for c in cert {
        assert_eq!(c["below"], false, "{c}");
        let e = c["solve_energy"][0]
            .as_f64()
            .expect("solve found the state");
        let de = c["solve_energy"][1].as_f64().unwrap();
        let (lb, le, lde) = (
            c["lowest"][0].as_u64().unwrap(),
            c["lowest"][2].as_f64().unwrap(),
            c["lowest"][3].as_f64().unwrap(),
        );
        assert!(e + de >= le - lde, "{c}");
        if c["branch"].as_u64() == Some(lb) {
            assert!((e - le).abs() <= de + lde + 1e-12, "{c}");
        }
    }
}

/// Next to the 3-fold great circle the two-segment rod's branch-1 state is named from the
/// moment of its central projection, or refused with the reason the state gives: at
/// `L̄ = 2.99` a lifted-off state of branch 1; at `L̄ = 2.9972` the descent reaches a loop in
/// a plane through the centre (three turns against the wall), which projects onto a great
/// circle and names no branch. Either way no file is written under a branch the state does
/// not have.
#[test]
fn two_segment_enclosed_branch_next_to_the_three_fold_circle() {
    let sc = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/data/scenes/inhomogeneous-d1-0.5-enclosed.toml"
    );
    for lbar in ["2.99", "2.9972"] {
        let dir = out(&format!("enclosed-three-fold-{lbar}"));
        let o = rodloop(&[
            "solve",
            "--scene",
            sc,
            "--lbar",
            lbar,
            "--branch",
            "1",
            "--out",
            dir.to_str().unwrap(),
        ]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!err.contains("panicked"), "{err}");
        if o.status.success() {
            let s: serde_json::Value =
                serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap())
                    .unwrap();
            assert_eq!(s["branch"], 1, "{s}");
            assert!(s["max_gap"].as_f64().unwrap() > 1e-4, "{s}");
        } else {
            assert_eq!(lbar, "2.9972", "{err}");
            assert!(
                err.contains("plane through the centre") && err.contains("great circle"),
                "{err}"
            );
            assert!(!dir.join("summary.json").exists());
        }
    }
}
