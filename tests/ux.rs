//! End-to-end tests of what a user sees: progress and summary lines, figure titles and
//! markers, output folders, the VTK export, the convergence figure, `compare` and `phase`
//! messages, through the built binary.

use std::path::{Path, PathBuf};

mod common;
use common::{bin, read_json, run};

fn tmp(name: &str) -> PathBuf {
    common::fresh_dir("rodloop-ux", name)
}

/// A CSV as its header and rows of numbers (columns that are not numbers become NaN).
fn read_numbers(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| {
            l.split(',')
                .map(|c| c.parse().unwrap_or(f64::NAN))
                .collect()
        })
        .collect();
    (header, rows)
}

/// A two-segment diagram counts branches, not the families and sheets they are traced as:
/// one progress line per branch (stderr is not a terminal here), and the summary line names
/// the branches with their families and sheets. Its contact-force figure has no
/// great-circle buckling markers (Eqs. 33–34 hold for a uniform rod only), while a uniform
/// diagram's has them.
#[test]
fn two_segment_diagram_counts_branches_and_draws_no_uniform_markers() {
    let d = tmp("d05");
    let (ok, out, err) = run(bin()
        .args([
            "diagram",
            "--scene",
            "data/scenes/inhomogeneous-d1-0.5.toml",
            "--out",
        ])
        .arg(&d));
    assert!(ok, "{err}");
    let traced: Vec<&str> = err.lines().filter(|l| l.contains(" traced (")).collect();
    let branches: std::collections::BTreeSet<String> =
        std::fs::read_to_string(d.join("branches.csv"))
            .unwrap()
            .lines()
            .skip(1)
            .map(|l| l.split(',').next().unwrap().to_string())
            .collect();
    assert_eq!(traced.len(), branches.len(), "{err}");
    for b in &branches {
        assert_eq!(
            traced
                .iter()
                .filter(|l| l.starts_with(&format!("branch {b} traced")))
                .count(),
            1,
            "{err}"
        );
    }
    let summary = out
        .lines()
        .find(|l| l.contains(" states on "))
        .expect("summary line");
    assert!(
        summary.contains(&format!("on {} branches (", branches.len())),
        "{summary}"
    );
    let lambda = std::fs::read_to_string(d.join("diagram_lambda.svg")).unwrap();
    assert!(!lambda.contains("Eq. (33)") && !lambda.contains("Eq. (34)"));
    // The same figure of a uniform rod marks the buckling loads.
    let u = tmp("uniform-lambda");
    let (ok, _, err) = run(bin()
        .args(["diagram", "--model", "exact", "--lbar-max", "3", "--out"])
        .arg(&u));
    assert!(ok, "{err}");
    let lambda = std::fs::read_to_string(u.join("diagram_lambda.svg")).unwrap();
    assert!(lambda.contains("Eq. (33)") && lambda.contains("Eq. (34)"));
    // --model exact writes its geodesic-energy figure as SVG and PNG.
    assert!(u.join("diagram_g.svg").is_file() && u.join("diagram_g.png").is_file());
    // Energies relative to the stable state: the stable states lie at 0.
    let (ok, _, err) = run(bin()
        .arg("draw")
        .arg(d.join("branches.csv"))
        .arg("--relative")
        .arg("--out")
        .arg(d.join("rel")));
    assert!(ok, "{err}");
    let rel = std::fs::read_to_string(d.join("rel/diagram.svg")).unwrap();
    assert!(rel.contains("E_stable"));
    std::fs::remove_dir_all(&d).ok();
    std::fs::remove_dir_all(&u).ok();
}

/// A directory holds one run's outputs: the numeric diagram's branch files go when the exact
/// model writes into the same folder; a file of the user's stays.
#[test]
fn a_folder_holds_one_runs_outputs() {
    let d = tmp("one-run");
    let (ok, _, err) = run(bin()
        .args([
            "diagram",
            "--accuracy",
            "fast",
            "--lbar-max",
            "1.6",
            "--quiet",
            "--out",
        ])
        .arg(&d));
    assert!(ok, "{err}");
    let branch_files = |d: &Path| {
        std::fs::read_dir(d.join("branches"))
            .map(|r| r.count())
            .unwrap_or(0)
    };
    assert!(branch_files(&d) > 0);
    std::fs::write(d.join("notes.txt"), "mine").unwrap();
    let (ok, _, err) = run(bin()
        .args(["diagram", "--model", "exact", "--lbar-max", "1.6", "--out"])
        .arg(&d));
    assert!(ok, "{err}");
    assert_eq!(branch_files(&d), 0);
    assert!(!d.join("branches").exists());
    assert_eq!(
        std::fs::read_to_string(d.join("notes.txt")).unwrap(),
        "mine"
    );
    assert!(!d.join("states").exists());
    std::fs::remove_dir_all(&d).ok();
}

/// `draw` of a state file in a diagram's `states/` writes nothing into `states/`: the
/// pictures go to `out/draw` (relative to where the command runs) unless `--out` says.
#[test]
fn draw_keeps_a_diagrams_states_folder_clean() {
    let d = tmp("states-draw");
    let (ok, _, err) = run(bin()
        .args([
            "diagram",
            "--accuracy",
            "fast",
            "--lbar-max",
            "1.4",
            "--branch",
            "1",
            "--quiet",
            "--out",
        ])
        .arg(&d));
    assert!(ok, "{err}");
    let states = d.join("states");
    let before = std::fs::read_dir(&states).unwrap().count();
    let file = std::fs::read_dir(&states)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .find(|p| p.extension().is_some_and(|x| x == "csv"))
        .unwrap();
    let (ok, out, err) = run(bin().current_dir(&d).arg("draw").arg(&file));
    assert!(ok, "{err}");
    assert!(out.contains("out/draw"), "{out}");
    assert_eq!(std::fs::read_dir(&states).unwrap().count(), before);
    let stem = file.file_stem().unwrap().to_str().unwrap();
    let svg = std::fs::read_to_string(d.join(format!("out/draw/{stem}.svg"))).unwrap();
    // Titled with the state, not the path: the branch from the file name and the energy
    // integrated from the table.
    assert!(svg.contains("Branch 1, η = 2, L̄ = "), "title");
    assert!(svg.contains("(from the table)"));
    assert!(!svg.contains(&format!("states/{stem}.csv")));
    std::fs::remove_dir_all(&d).ok();
}

/// A solve's picture is titled with its state, and the contact-force extremes of its colour
/// bar are the ones `solve` prints (its summary's `lambda_min`, `lambda_max`).
#[test]
fn loop_picture_names_the_state_and_the_solves_force_range() {
    let d = tmp("solve-title");
    let (ok, _, err) = run(bin()
        .args(["solve", "--lbar", "1.2", "--branch", "1", "--draw", "--out"])
        .arg(&d));
    assert!(ok, "{err}");
    let sum = read_json(&d.join("summary.json"));
    let note = read_json(&d.join("config-draw.json"));
    assert_eq!(note["color_column"], "lambda");
    assert_eq!(note["color_range"][0], sum["lambda_min"]);
    assert_eq!(note["color_range"][1], sum["lambda_max"]);
    let svg = std::fs::read_to_string(d.join("config.svg")).unwrap();
    assert!(svg.contains("Branch 1, η = 2, L̄ = 1.2, E R/(πD₀) = 2.0097"));
    assert!(!svg.contains("config.csv"));
    std::fs::remove_dir_all(&d).ok();
}

/// A loop sampled at few points is labelled with its length: 24 points of the L̄ = 1.2 loop
/// give L̄ = 1.2 (equally spaced samples close the loop with one more spacing).
#[test]
fn coarse_analytic_loop_keeps_its_length() {
    let d = tmp("analytic24");
    let (ok, _, err) = run(bin()
        .args([
            "analytic", "--lbar", "1.2", "--eta", "2", "--points", "24", "--draw", "--out",
        ])
        .arg(&d));
    assert!(ok, "{err}");
    let note = read_json(&d.join("loop-01-draw.json"));
    let lbar = note["lbar"].as_f64().unwrap();
    assert!((lbar - 1.2).abs() < 1e-12, "{lbar}");
    let svg = std::fs::read_to_string(d.join("loop-01.svg")).unwrap();
    assert!(svg.contains("L̄ = 1.2"));
    assert!(!svg.contains("1.1997"));
    std::fs::remove_dir_all(&d).ok();
}

/// An invalid choice is a usage error (exit 2), as for every other option.
#[test]
fn invalid_accuracy_is_a_usage_error() {
    for cmd in ["diagram", "solve", "report", "phase"] {
        let o = bin().args([cmd, "--accuracy", "ultra"]).output().unwrap();
        assert_eq!(o.status.code(), Some(2), "{cmd}");
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(e.contains("fast, default, high"), "{cmd}: {e}");
    }
}

/// `export`: a solve's state as VTK PolyData that parses as XML, with one closed polyline
/// and the table's columns as point data, equal to the CSV's values bit for bit.
#[test]
fn export_writes_vtk_polydata_that_round_trips() {
    let d = tmp("export");
    let (ok, _, err) = run(bin()
        .args([
            "solve",
            "--scene",
            "data/scenes/inhomogeneous-d1-0.5.toml",
            "--lbar",
            "1.5",
            "--branch",
            "1",
            "--accuracy",
            "fast",
            "--out",
        ])
        .arg(&d));
    assert!(ok, "{err}");
    let (ok, out, err) = run(bin().arg("export").arg(d.join("config.csv")));
    assert!(ok, "{err}");
    assert!(out.contains("config.vtp"));
    let text = std::fs::read_to_string(d.join("config.vtp")).unwrap();
    let doc = roxmltree::Document::parse(&text).expect("the .vtp is XML");
    let root = doc.root_element();
    assert_eq!(root.tag_name().name(), "VTKFile");
    assert_eq!(root.attribute("type"), Some("PolyData"));
    let (header, rows) = read_numbers(&d.join("config.csv"));
    let n = rows.len();
    let piece = doc.descendants().find(|e| e.has_tag_name("Piece")).unwrap();
    assert_eq!(
        piece.attribute("NumberOfPoints"),
        Some(n.to_string().as_str())
    );
    let array = |parent: &str, name: Option<&str>| -> Vec<f64> {
        let p = doc.descendants().find(|e| e.has_tag_name(parent)).unwrap();
        let a = p
            .children()
            .find(|e| {
                e.has_tag_name("DataArray") && (name.is_none() || e.attribute("Name") == name)
            })
            .unwrap_or_else(|| panic!("{parent}/{name:?}"));
        a.text()
            .unwrap_or("")
            .split_whitespace()
            .map(|v| v.parse().unwrap())
            .collect()
    };
    for col in [
        "s", "kappa", "tau", "kappa_g", "lambda", "F_t", "F_n", "F_b",
    ] {
        let j = header.iter().position(|h| h == col).unwrap();
        let csv: Vec<f64> = rows.iter().map(|r| r[j]).collect();
        assert_eq!(array("PointData", Some(col)), csv, "{col}");
    }
    let pts = array("Points", None);
    assert_eq!(pts.len(), 3 * n);
    let x = header.iter().position(|h| h == "x").unwrap();
    for (i, r) in rows.iter().enumerate() {
        assert_eq!(&pts[3 * i..3 * i + 3], &r[x..x + 3]);
    }
    let conn = array("Lines", Some("connectivity"));
    assert_eq!(conn.len(), n + 1);
    assert_eq!(conn[0], 0.0);
    assert_eq!(conn[n], 0.0, "the polyline closes on the first point");
    assert_eq!(array("Lines", Some("offsets")), vec![(n + 1) as f64]);
    std::fs::remove_dir_all(&d).ok();
}

/// `converge` draws error against cells and time with the fitted order; on the uniform rod
/// the least-squares order of the errors against the exact loop agrees with the orders the
/// table observes from successive differences.
#[test]
fn converge_draws_the_fitted_order() {
    let d = tmp("converge");
    let (ok, out, err) = run(bin()
        .args([
            "converge", "--lbar", "1.2", "--branch", "1", "--levels", "5", "--out",
        ])
        .arg(&d));
    assert!(ok, "{err}");
    assert!(out.contains("fitted order of convergence"));
    let sum = read_json(&d.join("summary.json"));
    let fitted = sum["fitted_order"].as_f64().unwrap();
    let observed: Vec<f64> = sum["rungs"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|r| r["observed_order"].as_f64())
        .collect();
    assert!(!observed.is_empty());
    for o in observed {
        assert!((fitted - o).abs() < 0.2, "fitted {fitted}, observed {o}");
    }
    let svg = std::fs::read_to_string(d.join("converge.svg")).unwrap();
    assert!(svg.contains(&format!("order p = {fitted:.2}")));
    assert!(d.join("converge.png").is_file());
    std::fs::remove_dir_all(&d).ok();
}

/// `compare`: the exact buckling load of the great circle is (m ± 1)²/m² itself (Sec. 4),
/// not a contact force taken near the end of a branch; the console gives the tolerance of
/// every agreement.
#[test]
fn compare_uses_exact_buckling_loads_and_shows_tolerances() {
    let d = tmp("compare");
    let (ok, out, err) = run(bin().args(["compare", "--out"]).arg(&d));
    assert!(ok, "{err}");
    let header = out.lines().next().unwrap();
    assert!(header.contains(" tol "), "{header}");
    let line = out
        .lines()
        .find(|l| l.starts_with("lambda_1cr"))
        .expect("lambda_1cr row");
    assert!(line.contains("4.000000000000"), "{line}");
    assert!(line.contains('±'), "{line}");
    let (h, rows) = read_numbers(&d.join("compare.csv"));
    let text = std::fs::read_to_string(d.join("compare.csv")).unwrap();
    let k = text
        .lines()
        .skip(1)
        .position(|l| l.starts_with("lambda_1cr,"))
        .unwrap();
    let col = |c: &str| h.iter().position(|x| x == c).unwrap();
    assert_eq!(rows[k][col("exact")], 4.0);
    assert!(rows[k][col("tolerance")] > 0.0);
    std::fs::remove_dir_all(&d).ok();
}

/// `phase` on a scene of a user's own whose curves stop short of the requested range says
/// so: non-zero exit, `complete: false`, the scene's own value as a row, messages on one
/// short line, the axis over the requested range with the ends marked.
#[test]
fn phase_that_stops_short_says_so() {
    let d = tmp("phase-short");
    let scene = d.join("user.toml");
    std::fs::write(
        &scene,
        "name = \"user\"\nradius = 1.0\nlbar_min = 1.0\nlbar_max = 3.0\n[stiffness]\nkind = \"tanh\"\nd0 = 1.0\nd1 = 0.3\ns0 = 0.2\ns1 = 0.4\ngamma = 100.0\n",
    )
    .unwrap();
    let out = d.join("out");
    let o = bin()
        .args(["phase", "--scene"])
        .arg(&scene)
        .args(["--param", "d1", "--to", "0.01", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    let sum = read_json(&out.join("summary.json"));
    if sum["complete"] == true {
        // Every curve reached the requested end: nothing to report.
        assert!(o.status.success(), "{err}");
    } else {
        assert!(!o.status.success());
        assert!(err.contains("short of --to 0.01"), "{err}");
        let svg = std::fs::read_to_string(out.join("phase.svg")).unwrap();
        assert!(svg.contains("stops:"));
    }
    for l in err.lines() {
        assert!(
            l.chars().count() <= 260,
            "{} characters: {l}",
            l.chars().count()
        );
    }
    let (h, rows) = read_numbers(&out.join("phase.csv"));
    let value = h.iter().position(|c| c == "value").unwrap();
    assert!(
        rows.iter().any(|r| (r[value] - 0.3).abs() < 1e-12),
        "no row at the scene's d1"
    );
    let svg = std::fs::read_to_string(out.join("phase.svg")).unwrap();
    assert!(!svg.contains("--at row"));
    // The axis starts at log10(0.01) = −2 whatever the curves reach.
    assert!(svg.contains(">−2<"), "no tick at −2");
    std::fs::remove_dir_all(&d).ok();
}

/// The report speaks in words (no Rust debug output) and lists each branch's state once.
#[test]
fn report_is_readable_and_lists_each_branch_once() {
    let d = tmp("report05");
    let (ok, _, err) = run(bin()
        .args([
            "report",
            "--scene",
            "data/scenes/inhomogeneous-d1-0.5.toml",
            "--accuracy",
            "fast",
            "--quiet",
            "--out",
        ])
        .arg(&d));
    assert!(ok, "{err}");
    let html = std::fs::read_to_string(d.join("report.html")).unwrap();
    for internal in ["Tanh {", "Uniform {", "accuracy Default", "Some("] {
        assert!(!html.contains(internal), "{internal}");
    }
    assert!(html.contains("two-segment (Eq. 51): D0 = 1, D1 = 0.5"));
    let states = html
        .split("<table id=\"states-table\">")
        .nth(1)
        .unwrap()
        .split("</table>")
        .next()
        .unwrap();
    let rows = states.matches("<tr><td>").count();
    for b in 1..=3 {
        let n = states.matches(&format!("<tr><td>{b}</td>")).count();
        assert_eq!(n, 1, "branch {b} listed {n} times");
    }
    assert_eq!(rows, 3);
    std::fs::remove_dir_all(&d).ok();
}

/// `compare --scene` of a two-segment rod on the sphere checks the paper's Sec. 5
/// statements instead of refusing: branch 1's saddle-like states keep only a mirror plane
/// (Cs), and the stiff-segment energy estimate is shown (judged only for an extremely soft
/// segment).
#[test]
fn compare_checks_the_two_segment_statements() {
    let d = tmp("compare-two-segment");
    let (ok, out, err) = run(bin()
        .args([
            "compare",
            "--scene",
            "data/scenes/inhomogeneous-d1-0.5.toml",
            "--out",
        ])
        .arg(&d));
    assert!(ok, "{err}");
    let sym = out
        .lines()
        .find(|l| l.starts_with("sym_branch1"))
        .expect("symmetry row");
    assert!(sym.trim_end().ends_with("yes"), "{sym}");
    assert!(out.lines().any(|l| l.starts_with("soft_energy_")), "{out}");
    let sum = read_json(&d.join("summary.json"));
    assert_eq!(sum["disagreements"], 0);
    // The estimate E ≈ (1 − (s1 − s0)) L̄ is a lower bound here (the soft segment and the
    // stiff segment's geodesic curvature add energy): every deviation is positive.
    for v in sum["values"].as_array().unwrap() {
        if let Some(dev) = v["relative_deviation"].as_f64() {
            assert!(dev > 0.0, "{v}");
        }
    }
    std::fs::remove_dir_all(&d).ok();
}

/// The enclosed report does not try what does not apply: its atlas has no free planar circle
/// at L̄ = 1 (where the circle is the great circle on the wall and the free-circle solve is
/// singular), so every atlas state is solved.
#[test]
fn enclosed_report_atlas_solves_every_state() {
    let d = tmp("report-enclosed");
    let (ok, _, err) = run(bin()
        .args([
            "report",
            "--scene",
            "data/scenes/homogeneous-enclosed.toml",
            "--accuracy",
            "fast",
            "--quiet",
            "--out",
        ])
        .arg(&d));
    assert!(ok, "{err}");
    let html = std::fs::read_to_string(d.join("report.html")).unwrap();
    assert!(
        !html.contains("atlas: not solved"),
        "an atlas state was not solved"
    );
    assert!(!html.contains("singular KKT"));
    std::fs::remove_dir_all(&d).ok();
}
