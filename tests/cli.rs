//! End-to-end tests: run the built `rodloop` binary as a user would.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn rodloop(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_rodloop"))
        .args(args)
        .output()
        .expect("run rodloop")
}

fn tmp(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| l.split(',').map(String::from).collect())
        .collect();
    (header, rows)
}

fn read_json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn assert_no_nan(path: &Path) {
    let text = std::fs::read_to_string(path).unwrap();
    assert!(
        !text.to_lowercase().contains("nan") && !text.contains("inf"),
        "{}",
        path.display()
    );
}

#[test]
fn analytic_writes_loops_and_summary() {
    let out = tmp("analytic");
    let o = rodloop(&[
        "analytic",
        "--lbar",
        "1.2",
        "--eta",
        "2",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary = read_json(&out.join("summary.json"));
    let loops = summary["loops"].as_array().unwrap();
    assert!(!loops.is_empty());
    let first = &loops[0];
    assert_eq!(first["p"], 1, "paper Fig. 6a: (eta, p) = (2, 1)");
    assert!(first["closure_residual"].as_f64().unwrap() <= 1e-10);
    for key in [
        "lbar",
        "eta",
        "p",
        "k",
        "c",
        "energy",
        "energy_n",
        "energy_g",
        "lambda_min",
        "lambda_max",
    ] {
        assert!(first.get(key).is_some(), "summary lacks {key}");
    }
    let file = out.join(first["file"].as_str().unwrap());
    let (header, rows) = read_csv(&file);
    assert_eq!(
        header,
        ["s", "x", "y", "z", "kappa", "tau", "kappa_g", "lambda", "F_t", "F_n", "F_b"]
    );
    assert_eq!(rows.len(), 512);
    assert_no_nan(&file);
    // Every point lies on the unit sphere.
    for r in &rows {
        let v: Vec<f64> = r[1..4].iter().map(|x| x.parse().unwrap()).collect();
        assert!(((v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt() - 1.0).abs() < 1e-12);
    }
}

#[test]
fn euler_writes_curve_and_summary() {
    let out = tmp("euler");
    let o = rodloop(&[
        "euler",
        "--l",
        "2",
        "--lbar",
        "1.2",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary = read_json(&out.join("summary.json"));
    let alpha = summary["alpha"].as_f64().unwrap();
    assert!(alpha > 0.0 && alpha < std::f64::consts::PI);
    assert!(summary["energy"].as_f64().unwrap() > 1.2);
    assert_no_nan(&out.join("curve.csv"));
}

#[test]
fn diagram_exact_reports_critical_lengths() {
    let out = tmp("diagram");
    let o = rodloop(&[
        "diagram",
        "--model",
        "exact",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("1.3799"), "{stdout}");
    let (header, rows) = read_csv(&out.join("critical.csv"));
    for col in ["lbar_cr", "kind", "from_branch", "to_branch", "energy"] {
        assert!(header.iter().any(|h| h == col), "critical.csv lacks {col}");
    }
    let lcol = header.iter().position(|h| h == "lbar_cr").unwrap();
    let values: Vec<f64> = rows.iter().map(|r| r[lcol].parse().unwrap()).collect();
    assert!(
        values.iter().any(|v| (v - 2.426).abs() < 5e-4),
        "{values:?}"
    );
    let (bh, brows) = read_csv(&out.join("branches.csv"));
    for col in [
        "branch",
        "eta",
        "p",
        "lbar",
        "energy",
        "energy_g",
        "lambda_min",
        "lambda_max",
    ] {
        assert!(bh.iter().any(|h| h == col), "branches.csv lacks {col}");
    }
    assert!(brows.len() > 400);
    assert_no_nan(&out.join("branches.csv"));
    for fig in ["diagram.svg", "diagram_g.svg"] {
        let svg = std::fs::read_to_string(out.join(fig)).unwrap();
        assert!(
            svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"),
            "{fig}"
        );
        // Five branches, each drawn as at least one path, and nine critical-length markers.
        assert!(svg.matches("<path").count() >= 5, "{fig}");
        assert!(
            svg.matches("stroke-dasharray=\"2 3\"").count() >= 9,
            "{fig}"
        );
        assert!(!svg.contains("NaN"), "{fig}");
    }
}

#[test]
fn bad_input_gives_clear_errors_without_panics() {
    let cases: &[(&[&str], &str)] = &[
        (&["analytic", "--lbar", "1.2", "--eta", "0"], "eta"),
        (&["analytic", "--lbar", "-1", "--eta", "2"], "lbar"),
        (&["euler", "--l", "2", "--lbar", "3.5"], "lbar"),
        (&["diagram", "--accuracy", "extreme"], "accuracy"),
        (&["diagram", "--lbar-min", "3", "--lbar-max", "2"], "lbar"),
        (&["euler", "--l", "1", "--lbar", "1e-9"], "degenerate"),
        (&["analytic", "--lbar", "2", "--eta", "4000000000"], "eta"),
    ];
    for (args, word) in cases {
        let out = tmp("bad");
        let mut a: Vec<&str> = args.to_vec();
        a.extend(["--out", out.to_str().unwrap()]);
        let o = rodloop(&a);
        assert!(!o.status.success(), "{args:?} should fail");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(word), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        assert!(
            !out.join("summary.json").exists(),
            "{args:?} wrote a summary"
        );
    }
}

/// `rodloop … | head` closes stdout early: that must end quietly, not in a panic.
#[test]
fn closed_stdout_is_not_a_panic() {
    use std::process::Stdio;
    let out = tmp("pipe");
    let mut child = Command::new(env!("CARGO_BIN_EXE_rodloop"))
        .args([
            "analytic",
            "--lbar",
            "3",
            "--eta",
            "2",
            "--out",
            out.to_str().unwrap(),
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("panicked"), "{err}");
    assert_ne!(o.status.code(), Some(101), "{err}");
}

#[test]
fn compare_puts_paper_values_next_to_exact_ones() {
    let out = tmp("compare");
    let o = rodloop(&["compare", "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (header, rows) = read_csv(&out.join("compare.csv"));
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    let (id, agrees) = (col("id"), col("within_resolution"));
    let nagrees = col("numeric_within_resolution");
    let numeric_rows = rows.iter().filter(|r| !r[nagrees].is_empty()).count();
    assert!(
        numeric_rows >= 10,
        "numeric column filled for critical lengths and loads"
    );
    for r in &rows {
        if !r[nagrees].is_empty() {
            assert_eq!(r[nagrees], "true", "{}", r[id]);
        }
    }
    let rows: Vec<_> = rows.iter().filter(|r| !r[agrees].is_empty()).collect();
    assert!(rows.len() >= 20);
    for r in rows {
        // The one known disagreement is the paper's p = 0 at L = 1.3 (README errata,
        // confirmed by the independent mpmath solution in data/reference/exact_loops.csv).
        let expected = if r[id] == "p_b2_13" { "false" } else { "true" };
        assert_eq!(r[agrees], expected, "{}", r[id]);
    }
}

#[test]
fn solve_matches_the_exact_loop_within_its_error_estimate() {
    for (branch, lbar) in [("1", 1.2), ("2", 1.7)] {
        let out = tmp(&format!("solve{branch}"));
        let l = lbar.to_string();
        let o = rodloop(&[
            "solve",
            "--lbar",
            &l,
            "--branch",
            branch,
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let s = read_json(&out.join("summary.json"));
        for key in [
            "lbar",
            "branch",
            "eta",
            "energy",
            "energy_g",
            "index",
            "eigenvalues",
            "symmetry_eigenvalues",
            "lambda_min",
            "lambda_max",
            "residual",
            "error_estimate",
            "nodes",
            "iterations",
        ] {
            assert!(s.get(key).is_some(), "summary lacks {key}");
        }
        let eta = rodloop_exact::eta_of_branch(branch.parse().unwrap());
        let exact = rodloop_exact::paper_branch_loop(eta, lbar)
            .unwrap()
            .energy()
            .unwrap();
        let (e, est) = (
            s["energy"].as_f64().unwrap(),
            s["error_estimate"].as_f64().unwrap(),
        );
        assert!(
            (e - exact).abs() <= 3.0 * est + 1e-12,
            "{e} vs {exact} (estimate {est})"
        );
        assert!((e - exact).abs() / exact <= 1e-6, "default accuracy target");
        assert_eq!(
            s["index"], 0,
            "the paper's stable branch is a local minimum"
        );
        let (header, rows) = read_csv(&out.join("config.csv"));
        for col in ["s", "x", "y", "z", "kappa", "tau", "kappa_g", "lambda", "D"] {
            assert!(header.iter().any(|h| h == col), "config.csv lacks {col}");
        }
        assert_eq!(rows.len() as u64, s["nodes"].as_u64().unwrap());
        assert_no_nan(&out.join("config.csv"));
        // Restart from the saved configuration: same state.
        let out2 = tmp(&format!("solve{branch}b"));
        let cfg = out.join("config.csv");
        let o = rodloop(&[
            "solve",
            "--lbar",
            &l,
            "--branch",
            branch,
            "--from",
            cfg.to_str().unwrap(),
            "--out",
            out2.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let s2 = read_json(&out2.join("summary.json"));
        assert!((s2["energy"].as_f64().unwrap() - e).abs() < 1e-9);
    }
}

#[test]
fn solve_bad_input_is_reported_clearly() {
    let dir = tmp("solve-bad");
    std::fs::create_dir_all(&dir).unwrap();
    let bad_scene = dir.join("bad.toml");
    std::fs::write(&bad_scene, "radius = 1.0\nradus = 2.0\n").unwrap();
    let enclosed = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/data/scenes/homogeneous-enclosed.toml"
    );
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec!["solve", "--lbar", "1.5", "--branch", "3"],
            "exists only for 2 < lbar < 4",
        ),
        (
            vec![
                "solve",
                "--lbar",
                "1.5",
                "--branch",
                "1",
                "--scene",
                bad_scene.to_str().unwrap(),
            ],
            "line 2",
        ),
        (
            vec![
                "solve", "--lbar", "1.5", "--branch", "1", "--scene", enclosed,
            ],
            "enclosed",
        ),
        (
            vec![
                "solve",
                "--lbar",
                "1.5",
                "--branch",
                "1",
                "--accuracy",
                "extreme",
            ],
            "accuracy",
        ),
        (
            vec![
                "solve",
                "--lbar",
                "1.5",
                "--branch",
                "1",
                "--from",
                "/nonexistent.csv",
            ],
            "nonexistent",
        ),
    ];
    for (args, word) in cases {
        let out = tmp("solve-bad-out");
        let mut a = args.clone();
        a.extend(["--out", out.to_str().unwrap()]);
        let o = rodloop(&a);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{args:?} should fail");
        assert!(err.contains(word), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        assert!(!out.join("summary.json").exists());
    }
}

/// A start that Newton cannot bring to this branch: the error names the residual and no
/// result files are written.
#[test]
fn non_converged_solve_writes_nothing() {
    let fig8 = tmp("fig8");
    let o = rodloop(&[
        "solve",
        "--lbar",
        "1.7",
        "--branch",
        "2",
        "--out",
        fig8.to_str().unwrap(),
    ]);
    assert!(o.status.success());
    let out = tmp("nonconv");
    let cfg = fig8.join("config.csv");
    let o = rodloop(&[
        "solve",
        "--lbar",
        "1.2",
        "--branch",
        "1",
        "--from",
        cfg.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("did not converge") && err.contains("residual"),
        "{err}"
    );
    assert!(!out.join("summary.json").exists() && !out.join("config.csv").exists());
}

/// The main job: the numeric diagram of the default scene. Its critical crossings must agree
/// with the exact layer's to 1e-6 at the default accuracy (issue 4), and the labels must
/// follow the paper (branch 1 stable at 1.2, branch 2 metastable there).
#[test]
fn numeric_diagram_of_the_default_scene() {
    let out = tmp("numeric");
    let o = rodloop(&["diagram", "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in [
        "branches.csv",
        "critical.csv",
        "summary.json",
        "diagram.svg",
    ] {
        assert!(out.join(f).exists(), "{f}");
    }
    let (bh, brows) = read_csv(&out.join("branches.csv"));
    for col in [
        "branch",
        "eta",
        "lbar",
        "energy",
        "energy_g",
        "stability",
        "index",
        "lambda_min",
        "lambda_max",
    ] {
        assert!(bh.iter().any(|h| h == col), "branches.csv lacks {col}");
    }
    assert_no_nan(&out.join("branches.csv"));
    let c = |n: &str| bh.iter().position(|h| h == n).unwrap();
    let label_near = |branch: &str, l: f64| -> String {
        brows
            .iter()
            .filter(|r| r[c("branch")] == branch)
            .min_by(|a, b| {
                let da = (a[c("lbar")].parse::<f64>().unwrap() - l).abs();
                let db = (b[c("lbar")].parse::<f64>().unwrap() - l).abs();
                da.total_cmp(&db)
            })
            .map(|r| r[c("stability")].clone())
            .unwrap()
    };
    assert_eq!(label_near("1", 1.2), "stable");
    assert_eq!(label_near("2", 1.2), "metastable");
    assert_eq!(label_near("2", 1.7), "stable");
    assert_eq!(label_near("3", 2.2), "stable");
    assert_eq!(label_near("1", 2.8), "stable");
    let (ch, crows) = read_csv(&out.join("critical.csv"));
    let k = |n: &str| ch.iter().position(|h| h == n).unwrap();
    let exact =
        rodloop_exact::diagram::compute(&rodloop_exact::diagram::DiagramSettings::default())
            .unwrap();
    assert_eq!(crows.len(), exact.critical.len());
    for (r, e) in crows.iter().zip(&exact.critical) {
        let x: f64 = r[k("lbar_cr")].parse().unwrap();
        let est: f64 = r[k("error_estimate")].parse().unwrap();
        assert!((x - e.lbar_cr).abs() < 1e-6, "{x} vs exact {}", e.lbar_cr);
        assert!(
            (x - e.lbar_cr).abs() <= 3.0 * est + 1e-12,
            "{x} vs {} (estimate {est})",
            e.lbar_cr
        );
        assert_eq!(r[k("kind")], e.kind.to_string());
    }
    let svg = std::fs::read_to_string(out.join("diagram.svg")).unwrap();
    assert!(
        svg.contains("stroke-dasharray=\"7 4\""),
        "metastable states are dashed"
    );
}

/// An interrupted run continues from the branch files already written.
#[test]
fn numeric_diagram_resumes_from_branch_files() {
    let out = tmp("resume");
    let args = [
        "diagram",
        "--accuracy",
        "fast",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ];
    let o = rodloop(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let first = std::fs::read_to_string(out.join("critical.csv")).unwrap();
    let branches: Vec<_> = std::fs::read_dir(out.join("branches")).unwrap().collect();
    assert_eq!(branches.len(), 5, "one file per branch");
    // Simulate an interruption: the summary and one branch are missing.
    std::fs::remove_file(out.join("summary.json")).unwrap();
    std::fs::remove_file(out.join("branches").join("eta-3.json")).unwrap();
    let mut resumed = args.to_vec();
    resumed.push("--resume");
    let o = rodloop(&resumed);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        String::from_utf8_lossy(&o.stderr).is_empty(),
        "--quiet prints nothing on stderr"
    );
    assert_eq!(
        std::fs::read_to_string(out.join("critical.csv")).unwrap(),
        first
    );
    assert!(out.join("branches").join("eta-3.json").exists());
}

#[test]
fn exact_model_rejects_inhomogeneous_scenes() {
    let scene = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/data/scenes/inhomogeneous-d1-0.5.toml"
    );
    let out = tmp("exact-inhom");
    let o = rodloop(&[
        "diagram",
        "--model",
        "exact",
        "--scene",
        scene,
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("homogeneous"));
}
