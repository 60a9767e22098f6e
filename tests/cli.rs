//! End-to-end tests: run the built `rodloop` binary as a user would.

use std::path::{Path, PathBuf};
use std::process::Output;

mod common;
use common::{bin, read_csv, read_json, rodloop, tmp};

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
        // Branch 0 exists only inside the sphere.
        (
            &["solve", "--lbar", "0.7", "--branch", "0"],
            "enclosed scenes only",
        ),
        // --min-cells 0 was silently raised to 8; 2^62 overflowed the shift to the finest
        // rung, passed the cap and panicked with "capacity overflow".
        (
            &[
                "converge",
                "--lbar",
                "1.2",
                "--branch",
                "1",
                "--min-cells",
                "0",
            ],
            "--min-cells must be at least 8",
        ),
        (
            &[
                "converge",
                "--lbar",
                "1.2",
                "--branch",
                "1",
                "--min-cells",
                "4611686018427387904",
                "--levels",
                "3",
            ],
            "cap 65536",
        ),
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
    let mut child = bin()
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
        // The one known disagreement is the paper's p = 0 at L = 1.3 (docs/src/methods.md, errata,
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
                "solve", "--lbar", "1.5", "--branch", "0", "--scene", enclosed,
            ],
            "planar circle",
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

/// A start that cannot be brought to the requested branch (a figure-eight asked to be a
/// saddle): the run fails with a one-line explanation that names what to do, and no result
/// files are written.
#[test]
fn solve_from_a_far_start_fails_cleanly() {
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
        err.starts_with("error: ") && err.contains("start from") && !err.contains("panicked"),
        "{err}"
    );
    assert!(!out.join("summary.json").exists() && !out.join("config.csv").exists());
}

/// The main job: the numeric diagram of the default scene. Its critical crossings must agree
/// with the exact layer's to 1e-6 at the default accuracy, and the labels must
/// follow the paper (branch 1 stable at 1.2, branch 2 metastable there).
#[test]
fn numeric_diagram_of_the_default_scene() {
    let out = tmp("numeric");
    let o = rodloop(&["diagram", "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("mode with 1 period of kappa_g"), "{stdout}");
    assert!(!stdout.contains("1 periods"), "grammar: {stdout}");
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
    std::fs::remove_file(out.join("branches").join("branch-3.json")).unwrap();
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
    assert!(out.join("branches").join("branch-3.json").exists());
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

fn ok(o: &Output) -> String {
    assert!(
        o.status.success(),
        "{}\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout).to_string()
}

fn fails(o: &Output, words: &[&str]) -> String {
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(!o.status.success(), "should fail: {err}");
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    for w in words {
        assert!(err.contains(w), "expected {w:?} in: {err}");
    }
    err
}

/// Leftovers of a run: temporary files, staging directories, the lock.
fn leftovers(dir: &Path) -> Vec<String> {
    let mut out = Vec::new();
    for d in [dir.to_path_buf(), dir.join("branches")] {
        if let Ok(entries) = std::fs::read_dir(&d) {
            for e in entries.flatten() {
                let n = e.file_name().to_string_lossy().to_string();
                if n.starts_with('.') {
                    out.push(n);
                }
            }
        }
    }
    out
}

fn write_scene(name: &str, text: &str) -> PathBuf {
    let dir = tmp(&format!("scene-{name}"));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(format!("{name}.toml"));
    std::fs::write(&p, text).unwrap();
    p
}

/// A state of another branch given with --from is refused, and nothing is written.
#[test]
fn solve_refuses_a_state_of_another_branch() {
    let xa = tmp("xa");
    ok(&rodloop(&[
        "solve",
        "--lbar",
        "1.2",
        "--branch",
        "1",
        "--out",
        xa.to_str().unwrap(),
    ]));
    let xm = tmp("xm");
    let cfg = xa.join("config.csv");
    let o = rodloop(&[
        "solve",
        "--lbar",
        "1.5",
        "--branch",
        "2",
        "--from",
        cfg.to_str().unwrap(),
        "--out",
        xm.to_str().unwrap(),
    ]);
    fails(&o, &["branch 1 (eta = 2)", "not the requested branch 2"]);
    assert!(!xm.join("summary.json").exists() && !xm.join("config.csv").exists());
    assert!(leftovers(&xm).is_empty(), "{:?}", leftovers(&xm));
    // An eta = 2 state at 2.5 given as a start of branch 3.
    let xb = tmp("xb");
    ok(&rodloop(&[
        "solve",
        "--lbar",
        "2.5",
        "--branch",
        "1",
        "--out",
        xb.to_str().unwrap(),
    ]));
    let x3 = tmp("x3");
    let cfg = xb.join("config.csv");
    let o = rodloop(&[
        "solve",
        "--lbar",
        "2.5",
        "--branch",
        "3",
        "--from",
        cfg.to_str().unwrap(),
        "--out",
        x3.to_str().unwrap(),
    ]);
    fails(&o, &["branch 1 (eta = 2)", "not the requested branch 3"]);
    // Without --from, branch 2 at 1.5 is the figure-eight: its energy is the exact loop's.
    let x2 = tmp("x2");
    ok(&rodloop(&[
        "solve",
        "--lbar",
        "1.5",
        "--branch",
        "2",
        "--out",
        x2.to_str().unwrap(),
    ]));
    let s = read_json(&x2.join("summary.json"));
    assert_eq!(s["branch"], 2);
    assert_eq!(s["identified_eta"], 1);
    let exact = rodloop_exact::paper_branch_loop(1, 1.5)
        .unwrap()
        .energy()
        .unwrap();
    assert!((s["energy"].as_f64().unwrap() - exact).abs() < 1e-6);
}

/// Forces and lengths are normalised by D0 and R, so that a uniform scene
/// with d = 2 or radius = 2 gives the default scene's numbers.
#[test]
fn outputs_are_normalised_by_d0_and_r() {
    let run = |scene: Option<&Path>, name: &str| {
        let out = tmp(name);
        let mut a = vec![
            "solve",
            "--lbar",
            "1.2",
            "--branch",
            "1",
            "--out",
            out.to_str().unwrap(),
        ];
        if let Some(s) = scene {
            a.extend(["--scene", s.to_str().unwrap()]);
        }
        ok(&rodloop(&a));
        (
            read_json(&out.join("summary.json")),
            read_csv(&out.join("config.csv")),
        )
    };
    let (base, (h, rows0)) = run(None, "units-default");
    let d2 = write_scene(
        "d2",
        "name = \"d2\"\n[stiffness]\nkind = \"uniform\"\nd = 2.0\n",
    );
    let r2 = write_scene("r2", "name = \"r2\"\nradius = 2.0\n");
    // The exact loop's contact-force range (Eq. 38), independent of the solver.
    let (lmin, lmax) = rodloop_exact::paper_branch_loop(2, 1.2)
        .unwrap()
        .lambda_range();
    for (scene, name) in [(&d2, "units-d2"), (&r2, "units-r2")] {
        let (s, (_, rows)) = run(Some(scene), name);
        for key in ["lambda_min", "lambda_max", "energy"] {
            let (a, b) = (s[key].as_f64().unwrap(), base[key].as_f64().unwrap());
            assert!(
                (a - b).abs() < 1e-9 * b.abs().max(1.0),
                "{name} {key}: {a} vs {b}"
            );
        }
        assert!(
            (s["lambda_min"].as_f64().unwrap() - lmin).abs() < 1e-4,
            "{name}"
        );
        assert!(
            (s["lambda_max"].as_f64().unwrap() - lmax).abs() < 1e-4,
            "{name}"
        );
        // Every CSV column agrees with the default scene's (positions on the unit sphere,
        // kappa in 1/R, forces in D0/R^2, D/D0).
        assert_eq!(rows.len(), rows0.len());
        for (r, r0) in rows.iter().zip(&rows0) {
            for (j, col) in h.iter().enumerate() {
                let (a, b): (f64, f64) = (r[j].parse().unwrap(), r0[j].parse().unwrap());
                assert!(
                    (a - b).abs() < 1e-8 * b.abs().max(1.0),
                    "{name} {col}: {a} vs {b}"
                );
            }
        }
    }
}

/// The full exact diagram (default range, computed by the library directly).
fn full_exact() -> rodloop_exact::diagram::Diagram {
    rodloop_exact::diagram::compute(&rodloop_exact::diagram::DiagramSettings::default()).unwrap()
}

/// Three exact sub-ranges give the full diagram's branches,
/// critical lengths (with their indices) and labels restricted to the window.
#[test]
fn exact_sub_ranges_match_the_full_diagram() {
    let full = full_exact();
    for (lo, hi, branches) in [
        (1.0, 1.5, vec![1u32, 2]),
        (1.2, 2.6, vec![1, 2, 3]),
        (0.5, 1.5, vec![1, 2]),
    ] {
        let out = tmp(&format!("sub-{lo}-{hi}"));
        let o = rodloop(&[
            "diagram",
            "--model",
            "exact",
            "--lbar-min",
            &lo.to_string(),
            "--lbar-max",
            &hi.to_string(),
            "--out",
            out.to_str().unwrap(),
        ]);
        ok(&o);
        let (ch, crows) = read_csv(&out.join("critical.csv"));
        let k = |n: &str| ch.iter().position(|h| h == n).unwrap();
        let want: Vec<_> = full
            .critical
            .iter()
            .filter(|c| c.lbar_cr >= lo && c.lbar_cr <= hi)
            .collect();
        assert_eq!(crows.len(), want.len(), "[{lo}, {hi}]: {crows:?}");
        for (r, c) in crows.iter().zip(&want) {
            assert_eq!(r[k("index")], c.index.to_string());
            assert_eq!(r[k("from_branch")], c.from_branch.to_string());
            assert_eq!(r[k("to_branch")], c.to_branch.to_string());
            let x: f64 = r[k("lbar_cr")].parse().unwrap();
            assert!((x - c.lbar_cr).abs() < 1e-12, "{x} vs {}", c.lbar_cr);
        }
        let (bh, brows) = read_csv(&out.join("branches.csv"));
        let b = |n: &str| bh.iter().position(|h| h == n).unwrap();
        let mut seen: Vec<u32> = brows
            .iter()
            .map(|r| r[b("branch")].parse().unwrap())
            .collect();
        seen.sort_unstable();
        seen.dedup();
        assert_eq!(seen, branches, "[{lo}, {hi}]");
        let summary = read_json(&out.join("summary.json"));
        assert_eq!(summary["branches"], branches.len());
        assert_eq!(summary["states"], brows.len());
        assert!(summary["units"].as_str().unwrap().contains("R^3/D0"));
        for r in &brows {
            let l: f64 = r[b("lbar")].parse().unwrap();
            let e: f64 = r[b("energy")].parse().unwrap();
            let lowest = &r[b("lowest")] == "1";
            if l < 1.0 {
                // The circle, E R/(pi D) = 1/lbar, lies below every branch there.
                assert!(1.0 / l < e, "{l}");
                assert!(!lowest, "branch {} flagged lowest at {l}", r[b("branch")]);
            } else if let Some(p) = full
                .points
                .iter()
                .find(|p| (p.lbar - l).abs() < 1e-9 && p.branch.to_string() == r[b("branch")])
            {
                assert_eq!(p.lowest, lowest, "label at {l}, branch {}", p.branch);
            }
        }
    }
}

/// On a sub-range the "exact deviation" is
/// computed against the same critical length only; stderr that is not a terminal gets one
/// line per traced branch; --resume with another accuracy says it re-traces.
#[test]
fn numeric_sub_range_progress_and_resume_note() {
    let out = tmp("numeric-sub");
    let o = rodloop(&[
        "diagram",
        "--accuracy",
        "fast",
        "--lbar-max",
        "1.5",
        "--out",
        out.to_str().unwrap(),
    ]);
    let stdout = ok(&o);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains("branch 1 traced") && stderr.contains("branch 2 traced"),
        "{stderr}"
    );
    let line = stdout
        .lines()
        .find(|l| l.contains("crossing") && l.contains("1->2"))
        .unwrap_or_else(|| panic!("{stdout}"));
    let dev: f64 = line.split_whitespace().last().unwrap().parse().unwrap();
    assert!(dev.abs() < 1e-5, "{line}");
    let s = read_json(&out.join("summary.json"));
    assert!(s["units"].as_str().is_some() && s["run_id"].as_str().is_some());
    let o = rodloop(&[
        "diagram",
        "--accuracy",
        "default",
        "--lbar-max",
        "1.5",
        "--resume",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]);
    ok(&o);
    assert!(String::from_utf8_lossy(&o.stderr).contains("re-tracing"));
}

/// Options that do not apply are rejected, --branch works everywhere, the
/// two branches.csv share their common columns.
#[test]
fn flags_work_or_are_rejected() {
    let out = tmp("flags");
    let o_ = out.to_str().unwrap();
    fails(
        &rodloop(&["diagram", "--step", "0.001", "--out", o_]),
        &["--step", "exact"],
    );
    fails(
        &rodloop(&[
            "diagram",
            "--model",
            "exact",
            "--accuracy",
            "high",
            "--out",
            o_,
        ]),
        &["--accuracy", "numeric"],
    );
    fails(
        &rodloop(&["diagram", "--model", "exact", "--resume", "--out", o_]),
        &["--resume", "numeric"],
    );
    fails(
        &rodloop(&["diagram", "--model", "exact", "--branch", "9", "--out", o_]),
        &["--branch 9"],
    );
    ok(&rodloop(&[
        "diagram", "--model", "exact", "--branch", "1,3", "--out", o_,
    ]));
    let (eh, erows) = read_csv(&out.join("branches.csv"));
    let mut seen: Vec<&str> = erows.iter().map(|r| r[0].as_str()).collect();
    seen.dedup();
    assert_eq!(seen, ["1", "3"]);
    let (ch, crows) = read_csv(&out.join("critical.csv"));
    let (f, t) = (
        ch.iter().position(|h| h == "from_branch").unwrap(),
        ch.iter().position(|h| h == "to_branch").unwrap(),
    );
    assert!(crows
        .iter()
        .all(|r| ["1", "3"].contains(&r[f].as_str()) || ["1", "3"].contains(&r[t].as_str())));
    let nout = tmp("flags-numeric");
    ok(&rodloop(&[
        "diagram",
        "--accuracy",
        "fast",
        "--lbar-max",
        "1.5",
        "--quiet",
        "--out",
        nout.to_str().unwrap(),
    ]));
    let (nh, _) = read_csv(&nout.join("branches.csv"));
    let common = [
        "branch",
        "eta",
        "lbar",
        "energy",
        "energy_g",
        "lambda_min",
        "lambda_max",
    ];
    assert_eq!(&eh[..7], common);
    assert_eq!(&nh[..7], common);
    // analytic --branch 1 is --eta 2; euler --branch 1 is --l 2.
    let (a1, a2) = (tmp("an-b"), tmp("an-e"));
    ok(&rodloop(&[
        "analytic",
        "--lbar",
        "1.2",
        "--branch",
        "1",
        "--out",
        a1.to_str().unwrap(),
    ]));
    ok(&rodloop(&[
        "analytic",
        "--lbar",
        "1.2",
        "--eta",
        "2",
        "--out",
        a2.to_str().unwrap(),
    ]));
    assert_eq!(
        std::fs::read_to_string(a1.join("loop-01.csv")).unwrap(),
        std::fs::read_to_string(a2.join("loop-01.csv")).unwrap()
    );
    let (e1, e2) = (tmp("eu-b"), tmp("eu-l"));
    ok(&rodloop(&[
        "euler",
        "--lbar",
        "1.2",
        "--branch",
        "1",
        "--out",
        e1.to_str().unwrap(),
    ]));
    let stdout = ok(&rodloop(&[
        "euler",
        "--lbar",
        "1.2",
        "--l",
        "2",
        "--out",
        e2.to_str().unwrap(),
    ]));
    assert_eq!(
        std::fs::read_to_string(e1.join("curve.csv")).unwrap(),
        std::fs::read_to_string(e2.join("curve.csv")).unwrap()
    );
    // Item 9: no "quadrature error <= 0.0e0".
    assert!(!stdout.contains("<= 0.0e0"), "{stdout}");
    // solve accepts --eta as the alternative to --branch.
    let (s1, s2) = (tmp("so-b"), tmp("so-e"));
    ok(&rodloop(&[
        "solve",
        "--lbar",
        "1.2",
        "--branch",
        "1",
        "--accuracy",
        "fast",
        "--out",
        s1.to_str().unwrap(),
    ]));
    ok(&rodloop(&[
        "solve",
        "--lbar",
        "1.2",
        "--eta",
        "2",
        "--accuracy",
        "fast",
        "--out",
        s2.to_str().unwrap(),
    ]));
    assert_eq!(
        std::fs::read_to_string(s1.join("config.csv")).unwrap(),
        std::fs::read_to_string(s2.join("config.csv")).unwrap()
    );
}

/// Sizes and values the commands cannot honour are clear errors.
#[test]
fn huge_and_negative_values_are_clear_errors() {
    let out = tmp("huge");
    let o_ = out.to_str().unwrap();
    let cases: Vec<(Vec<&str>, Vec<&str>)> = vec![
        (
            vec![
                "analytic",
                "--lbar",
                "1.2",
                "--eta",
                "2",
                "--points",
                "100000000",
            ],
            vec!["cap of 1000000", "RODLOOP_MAX_POINTS"],
        ),
        (
            vec![
                "euler",
                "--l",
                "2",
                "--lbar",
                "1.2",
                "--points",
                "100000000",
            ],
            vec!["cap of 1000000"],
        ),
        (
            vec![
                "euler",
                "--l",
                "2",
                "--lbar",
                "1.2",
                "--points",
                "18446744073709551615",
            ],
            vec!["cap"],
        ),
        (
            vec!["euler", "--l", "4294967295", "--lbar", "4294967295"],
            vec!["--l must be"],
        ),
        (
            vec!["euler", "--l", "2", "--lbar", "4294967295"],
            vec!["exists only for 1 < lbar < 3"],
        ),
        (
            vec!["solve", "--lbar", "-1", "--branch", "1"],
            vec!["lbar must be positive"],
        ),
        (
            vec!["euler", "--l", "2", "--lbar", "-1"],
            vec!["lbar must be positive"],
        ),
        (
            vec!["analytic", "--lbar", "-1", "--eta", "2"],
            vec!["lbar must be positive"],
        ),
        (
            vec!["solve", "--lbar", "1.2", "--branch", "18446744073709551615"],
            vec!["--branch must be"],
        ),
        (
            vec!["diagram", "--model", "exact", "--step", "inf"],
            vec!["--step"],
        ),
    ];
    for (args, words) in cases {
        let mut a = args.clone();
        a.extend(["--out", o_]);
        fails(&rodloop(&a), &words);
        assert!(!out.join("summary.json").exists(), "{args:?}");
        assert!(
            leftovers(&out).is_empty(),
            "{args:?}: {:?}",
            leftovers(&out)
        );
    }
}

/// --from a directory, non-finite or unusable coordinates name the file.
#[test]
fn from_file_errors_name_the_file() {
    let dir = tmp("from-bad");
    std::fs::create_dir_all(&dir).unwrap();
    let out = tmp("from-bad-out");
    let o_ = out.to_str().unwrap();
    fails(
        &rodloop(&[
            "solve",
            "--lbar",
            "1.2",
            "--branch",
            "1",
            "--from",
            dir.to_str().unwrap(),
            "--out",
            o_,
        ]),
        &["is a directory"],
    );
    let inf = dir.join("inf.csv");
    let mut text = String::from("x,y,z\n");
    for i in 0..20 {
        let t = i as f64 * 0.3;
        text.push_str(&format!("{},{},0\n", t.cos(), t.sin()));
    }
    text.push_str("1e400,0,0\n");
    std::fs::write(&inf, &text).unwrap();
    fails(
        &rodloop(&[
            "solve",
            "--lbar",
            "1.2",
            "--branch",
            "1",
            "--from",
            inf.to_str().unwrap(),
            "--out",
            o_,
        ]),
        &["inf.csv", "row 22", "not finite"],
    );
    let big = dir.join("big.csv");
    std::fs::write(&big, text.replace("1e400", "1e300")).unwrap();
    fails(
        &rodloop(&[
            "solve",
            "--lbar",
            "1.2",
            "--branch",
            "1",
            "--from",
            big.to_str().unwrap(),
            "--out",
            o_,
        ]),
        &["big.csv"],
    );
}

/// A scene called "nullable" works (finiteness is checked on typed values);
/// a run removes the outputs of a previous run it does not write (diagram_g.svg after
/// switching model), records a run id, and leaves no temporary file.
#[test]
fn outputs_are_one_consistent_set() {
    let scene = write_scene("nullable", "name = \"nullable\"\n");
    let out = tmp("nullable");
    ok(&rodloop(&[
        "solve",
        "--lbar",
        "1.2",
        "--branch",
        "1",
        "--accuracy",
        "fast",
        "--scene",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]));
    let s = read_json(&out.join("summary.json"));
    assert_eq!(s["scene"], "nullable");
    let dir = tmp("switch");
    ok(&rodloop(&[
        "diagram",
        "--model",
        "exact",
        "--out",
        dir.to_str().unwrap(),
    ]));
    assert!(dir.join("diagram_g.svg").exists());
    let id1 = read_json(&dir.join("summary.json"))["run_id"].clone();
    ok(&rodloop(&[
        "diagram",
        "--accuracy",
        "fast",
        "--lbar-max",
        "1.5",
        "--quiet",
        "--out",
        dir.to_str().unwrap(),
    ]));
    assert!(!dir.join("diagram_g.svg").exists(), "stale diagram_g.svg");
    let s2 = read_json(&dir.join("summary.json"));
    assert_eq!(s2["model"], "numeric");
    assert_ne!(s2["run_id"], id1);
    assert!(leftovers(&dir).is_empty(), "{:?}", leftovers(&dir));
}

/// A directory locked by a running rodloop process is refused; a lock left
/// by a dead process is taken over; --resume removes temporaries of a killed run.
#[test]
fn output_directory_lock_and_cleanup() {
    let dir = tmp("locked");
    std::fs::create_dir_all(dir.join("branches")).unwrap();
    // A live process: this test itself.
    std::fs::write(
        dir.join(".rodloop.lock"),
        format!("{}\n", std::process::id()),
    )
    .unwrap();
    fails(
        &rodloop(&[
            "diagram",
            "--model",
            "exact",
            "--out",
            dir.to_str().unwrap(),
        ]),
        &[
            "in use by another rodloop run",
            &std::process::id().to_string(),
        ],
    );
    assert!(!dir.join("summary.json").exists());
    // A dead process: a child that has exited.
    let mut child = bin()
        .arg("--version")
        .stdout(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let dead = child.id();
    child.wait().unwrap();
    std::fs::write(dir.join(".rodloop.lock"), format!("{dead}\n")).unwrap();
    // Leftovers of a killed run.
    std::fs::write(dir.join(".branches.csv.99999.tmp"), "partial").unwrap();
    std::fs::write(
        dir.join("branches").join(".branch-1.json.99999.tmp"),
        "partial",
    )
    .unwrap();
    std::fs::create_dir_all(dir.join(".staging-dead-99999")).unwrap();
    ok(&rodloop(&[
        "diagram",
        "--accuracy",
        "fast",
        "--lbar-max",
        "1.5",
        "--resume",
        "--quiet",
        "--out",
        dir.to_str().unwrap(),
    ]));
    assert!(dir.join("summary.json").exists());
    assert!(leftovers(&dir).is_empty(), "{:?}", leftovers(&dir));
}

/// A failed run prints one line that names the problem (the context and its cause joined, a
/// cause the message already quotes not repeated), exits non-zero and leaves no empty output
/// directory behind (no empty `OUT/`, and the OS error once, on one line).
#[test]
fn failed_runs_print_one_line_and_leave_no_directory() {
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/scenes");
    let uniform = scenes.join("homogeneous-surface.toml");
    let missing = scenes.join("no-such-scene.toml");
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec!["phase", "--scene", uniform.to_str().unwrap(), "--to", "0.1"],
            "two-segment stiffness profile",
        ),
        (
            vec![
                "solve",
                "--lbar",
                "1.2",
                "--branch",
                "1",
                "--scene",
                missing.to_str().unwrap(),
            ],
            "no-such-scene.toml",
        ),
        (
            vec!["draw", missing.to_str().unwrap()],
            "no-such-scene.toml",
        ),
    ];
    for (args, word) in cases {
        let out = tmp("failed-run");
        let mut a = args.clone();
        a.extend(["--out", out.to_str().unwrap()]);
        let o = rodloop(&a);
        assert!(!o.status.success(), "{args:?} should fail");
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
        assert!(
            err.starts_with("error: ") && err.contains(word),
            "{args:?}: {err}"
        );
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        assert!(
            err.matches("No such file").count() <= 1,
            "{args:?} repeats its cause: {err}"
        );
        assert!(!out.exists(), "{args:?} left {}", out.display());
    }
}

/// The pictures `--draw` wrote belong to that run: a later run into the same directory that
/// does not draw (or writes fewer loops) removes them, as it removes its other stale outputs.
#[test]
fn pictures_of_a_previous_run_are_removed() {
    let out = tmp("stale-pictures");
    let dir = out.to_str().unwrap();
    ok(&rodloop(&[
        "analytic", "--eta", "1", "--lbar", "1.6", "--draw", "--out", dir,
    ]));
    assert!(out.join("loop-03.svg").exists() && out.join("loop-01-draw.json").exists());
    ok(&rodloop(&[
        "analytic", "--eta", "2", "--lbar", "1.2", "--out", dir,
    ]));
    let mut names: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .collect();
    names.sort();
    assert_eq!(names, ["loop-01.csv", "loop-02.csv", "summary.json"]);

    let out = tmp("stale-pictures-solve");
    let dir = out.to_str().unwrap();
    let o = rodloop(&[
        "solve", "--lbar", "1.2", "--branch", "1", "--draw", "--out", dir,
    ]);
    ok(&o);
    // The "wrote" line names the pictures.
    assert!(
        String::from_utf8_lossy(&o.stdout).contains("config-profiles.png"),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
    ok(&rodloop(&[
        "solve", "--lbar", "1.2", "--branch", "1", "--out", dir,
    ]));
    for name in [
        "config.svg",
        "config.png",
        "config-profiles.svg",
        "config-draw.json",
    ] {
        assert!(!out.join(name).exists(), "stale {name}");
    }
}

/// `rodloop diagram --param … | head -1` ends quietly (it printed with `println!`, which
/// panics on a closed pipe).
#[test]
fn param_diagram_with_closed_stdout_is_not_a_panic() {
    use std::process::Stdio;
    let out = tmp("param-pipe");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/scenes/inhomogeneous-d1-0.5.toml");
    let mut child = bin()
        .args([
            "diagram",
            "--scene",
            scene.to_str().unwrap(),
            "--param",
            "d1",
            "--lbar",
            "1.3",
            "--to",
            "0.4",
            "--accuracy",
            "fast",
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

/// `draw` names the option at fault: `--width` of a loop picture (the message spoke of a
/// "panel size" of width/2.5) and a negative `--tol` (clap took `-1` for an option).
#[test]
fn draw_rejects_bad_width_and_tol_by_name() {
    let out = tmp("draw-bad");
    let dir = out.to_str().unwrap();
    ok(&rodloop(&[
        "analytic", "--eta", "2", "--lbar", "1.2", "--out", dir,
    ]));
    let file = out.join("loop-01.csv");
    for (flag, value) in [("--width", "50000"), ("--tol", "-1"), ("--tol", "2")] {
        let pics = tmp("draw-bad-pics");
        let o = rodloop(&[
            "draw",
            file.to_str().unwrap(),
            flag,
            value,
            "--out",
            pics.to_str().unwrap(),
        ]);
        assert!(!o.status.success(), "{flag} {value}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(err.starts_with(&format!("error: {flag} {value}:")), "{err}");
        assert!(!pics.exists(), "{flag} {value} wrote {}", pics.display());
    }
}

/// Every `summary.json` has a `units` field (docs/src/commands.md, Units), `compare --scene
/// enclosed`'s included.
#[test]
fn enclosed_compare_summary_has_units() {
    let out = tmp("compare-enclosed-units");
    ok(&rodloop(&[
        "compare",
        "--scene",
        "enclosed",
        "--out",
        out.to_str().unwrap(),
    ]));
    let s = read_json(&out.join("summary.json"));
    assert!(
        s["units"].as_str().is_some_and(|u| u.contains("lbar")),
        "{s}"
    );
}

/// With `--branch`, a stretch without an index-0 state says that only those branches were
/// traced (it said "the lowest state there was not found", an alarm about the solver).
#[test]
fn no_stable_state_warning_names_the_branch_filter() {
    let out = tmp("branch-filter-warning");
    let o = rodloop(&[
        "diagram",
        "--branch",
        "1",
        "--accuracy",
        "fast",
        "--lbar-max",
        "3.5",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]);
    ok(&o);
    let err = String::from_utf8_lossy(&o.stderr);
    // Branch 1 lives on 1 < L̄ < 3: nothing was traced on (3, 3.5).
    assert!(
        err.contains("NO STABLE STATE FOUND") && err.contains("only branch(es) 1 were traced"),
        "{err}"
    );
}

/// Mistakes on the command line that clap catches (an invalid choice, a misspelt option, a
/// missing argument) are one line too, with clap's tip and the usage, and exit code 2 (clap
/// printed five to seven lines).
#[test]
fn usage_mistakes_are_one_line() {
    for (args, words) in [
        (
            &["diagram", "--model", "exakt"][..],
            &[
                "'exakt'",
                "--model",
                "numeric, exact",
                "similar value exists: 'exact'",
            ][..],
        ),
        (
            &[
                "solve",
                "--lbar",
                "1.2",
                "--branch",
                "1",
                "--acuracy",
                "high",
            ][..],
            &["'--acuracy'", "'--accuracy'", "usage: rodloop solve"][..],
        ),
        (
            &["solve", "--branch", "1"][..],
            &["--lbar <LBAR>", "usage: rodloop solve"][..],
        ),
    ] {
        let o = rodloop(args);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
        assert!(err.starts_with("error: "), "{err}");
        for w in words {
            assert!(err.contains(w), "{args:?}: {w} not in {err}");
        }
    }
    // --help still prints the help, on stdout, with success.
    let o = rodloop(&["solve", "--help"]);
    assert!(o.status.success());
    assert!(String::from_utf8_lossy(&o.stdout).contains("--lbar"));
}

/// The surface-only commands refuse an enclosed scene with one line that names the scene and
/// the commands that handle it, exit non-zero, and write no output directory.
#[test]
fn surface_only_commands_refuse_an_enclosed_scene() {
    let scene = "data/scenes/homogeneous-enclosed.toml";
    let cases: [&[&str]; 2] = [
        &["phase", "--to", "0.5"],
        &["diagram", "--param", "d1", "--lbar", "1.2"],
    ];
    for (i, case) in cases.iter().enumerate() {
        let out = tmp(&format!("surface-only-{i}"));
        let mut args = case.to_vec();
        args.extend(["--scene", scene, "--out", out.to_str().unwrap()]);
        let o = rodloop(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{args:?} succeeded");
        assert_eq!(err.trim().lines().count(), 1, "{args:?}: {err}");
        assert!(
            err.contains("homogeneous-enclosed") && err.contains("surface model only"),
            "{args:?}: {err}"
        );
        assert!(!out.exists(), "{args:?} wrote {}", out.display());
    }
}
