//! Every state file a command writes holds the state of its row: for each kind of diagram
//! (two-segment surface, uniform surface, enclosed, `--param`), for `phase` (both states of
//! each row of `phase.csv`) and for `converge` (the finest rung), every file named in the
//! command's table is read back and checked here, independently of rodloop's code: the
//! polyline closes (its closing chord is no longer than the arclength between its last and
//! first points, up to 1 % of that step for the interpolated points), it lies on the unit
//! sphere (surface) or inside the unit ball (enclosed), and the energy `(1/π) ∮ ½ D κ² ds`
//! recomputed from the file by the periodic trapezoidal rule equals the row's `energy` within
//! 5 times the row's `energy_error` (1e-4 relative where the row has none) plus the rule's
//! own error `|T_h − T_2h|`; for the surface commands other than the diagrams in `L̄`, the dominant
//! harmonic of the written `κ_g` (a DFT here) is also compared with the periods `η` of the
//! state's branch. States that fail the command's own verification have no file and are
//! counted in `summary.json` (`unverified_states`).

mod common;

use std::f64::consts::PI;
use std::path::Path;

use common::{fresh_dir, rodloop_ok, summary};

/// Multiple of a row's error estimate within which its file's energy must lie.
const ESTIMATES: f64 = 5.0;
/// Relative tolerance of a row without an error estimate.
const NO_ESTIMATE: f64 = 1e-4;

/// The columns `names` of a CSV file (comment lines `#` skipped), as numbers by row.
fn columns(path: &Path, names: &[&str]) -> Vec<Vec<f64>> {
    let mut rdr = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .from_path(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let head = rdr.headers().unwrap().clone();
    let idx: Vec<usize> = names
        .iter()
        .map(|n| {
            head.iter()
                .position(|h| h == *n)
                .unwrap_or_else(|| panic!("no column {n}"))
        })
        .collect();
    rdr.records()
        .map(|r| {
            let r = r.unwrap();
            idx.iter().map(|&i| r[i].parse::<f64>().unwrap()).collect()
        })
        .collect()
}

/// The problems of state file `file` (relative to `dir`) of a loop of length `2π lbar`
/// reported with `energy` and the error estimate `estimate` (see the module docs).
fn check_file(
    dir: &Path,
    file: &str,
    lbar: f64,
    energy: f64,
    estimate: Option<f64>,
    enclosed: bool,
) -> Vec<String> {
    let mut problems = Vec::new();
    let pts = columns(&dir.join(file), &["s", "x", "y", "z", "kappa", "D"]);
    let n = pts.len();
    assert!(n >= 8, "{file}: {n} points");
    assert!(
        pts.iter().flatten().all(|v| v.is_finite()),
        "{file}: a value is not finite"
    );
    let length = 2.0 * PI * lbar;
    let dist = |a: &[f64], b: &[f64]| {
        ((a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2) + (a[3] - b[3]).powi(2)).sqrt()
    };
    let chord = dist(&pts[n - 1], &pts[0]);
    let arc = length + pts[0][0] - pts[n - 1][0];
    if !(arc > 0.0 && chord <= arc * 1.01 + 1e-9) {
        problems.push(format!(
            "{file}: open, chord {chord:.3e} over arc {arc:.3e}"
        ));
    }
    // Enclosed files hold nodes (`node` 1) and the two Gauss points of each cell (`node` 0,
    // `weight` h/2). The wall holds the nodes; the chord between two nodes lies in the
    // (convex) ball, so a Gauss point lies at most its cell curve's bulge κ u (h − u) / 2 =
    // κ h²/12 beyond it (u = h/2 ∓ h/√12), counted here with a margin of 1.5 on κ.
    let marks = if enclosed {
        columns(&dir.join(file), &["node", "weight"])
    } else {
        vec![vec![1.0, 0.0]; n]
    };
    let worst = pts
        .iter()
        .zip(&marks)
        .map(|(p, m)| {
            let d = (p[1] * p[1] + p[2] * p[2] + p[3] * p[3]).sqrt() - 1.0;
            let h = 2.0 * m[1];
            let reach = if m[0] == 1.0 {
                0.0
            } else {
                1.5 * p[4].abs() * h * h / 12.0
            };
            if enclosed {
                d - reach
            } else {
                d.abs()
            }
        })
        .fold(f64::NEG_INFINITY, f64::max);
    if worst > 1e-9 {
        problems.push(format!(
            "{file}: a point {worst:.3e} R off the sphere or ball"
        ));
    }
    let trap = |step: usize| {
        let idx: Vec<usize> = (0..n).step_by(step).collect();
        let m = idx.len();
        (0..m)
            .map(|j| {
                let (a, b) = (&pts[idx[j]], &pts[idx[(j + 1) % m]]);
                let ds = if j + 1 < m {
                    b[0] - a[0]
                } else {
                    length + b[0] - a[0]
                };
                0.25 * (a[5] * a[4] * a[4] + b[5] * b[4] * b[4]) * ds
            })
            .sum::<f64>()
            / PI
    };
    // Enclosed files carry the model's quadrature: weights h/2 at the Gauss points, 0 at
    // the nodes (two-point Gauss, exact for the quartic energy density of a cell's curve to
    // the scheme's order); surface files, the periodic trapezoid on the written points.
    let (fine, coarse) = if enclosed {
        let e = pts
            .iter()
            .zip(&marks)
            .map(|(p, m)| m[1] * 0.5 * p[5] * p[4] * p[4])
            .sum::<f64>()
            / PI;
        (e, e)
    } else {
        (trap(1), trap(2))
    };
    let scale = energy.abs().max(1.0);
    let allowed = estimate.map_or(NO_ESTIMATE * scale, |e| ESTIMATES * e);
    let tol = allowed + (fine - coarse).abs() + 1e-9 * scale;
    if (fine - energy).abs() > tol {
        problems.push(format!(
            "{file} (L̄ = {lbar}): energy from the file {fine:.10} against {energy:.10} in \
             its row (tolerance {tol:.1e})"
        ));
    }
    problems
}

/// Check every state file of the diagram in `dir` against its row (see the module docs);
/// returns the problems found and the number of files checked.
fn check_diagram(dir: &Path, enclosed: bool) -> (Vec<String>, usize) {
    let mut rdr = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .from_path(dir.join("branches.csv"))
        .unwrap();
    let head = rdr.headers().unwrap().clone();
    let col = |n: &str| head.iter().position(|h| h == n).unwrap();
    let (il, ie, ier, ifile) = (
        col("lbar"),
        col("energy"),
        col("energy_error"),
        col("state_file"),
    );
    let mut problems = Vec::new();
    let mut checked = 0;
    for row in rdr.records() {
        let row = row.unwrap();
        let file = row[ifile].trim();
        if file.is_empty() {
            continue;
        }
        checked += 1;
        let lbar: f64 = row[il].parse().unwrap();
        let energy: f64 = row[ie].parse().unwrap();
        let estimate: Option<f64> = row[ier].trim().parse().ok();
        problems.extend(check_file(dir, file, lbar, energy, estimate, enclosed));
    }
    (problems, checked)
}

/// Run `diagram` with `args` into a fresh directory, check every state file, and require
/// at least `min_files` files and no problem. Surface diagrams report only verified states
/// (every row has its file; `unverified_states` counts the states left out); enclosed
/// diagrams keep a row without a file for each state counted in `unverified_states`.
fn diagram_files_hold_their_rows(name: &str, args: &[&str], enclosed: bool, min_files: usize) {
    let out = fresh_dir("state-files", name);
    let mut all = vec!["diagram", "--out", out.to_str().unwrap()];
    all.extend_from_slice(args);
    rodloop_ok(&all);
    let (problems, checked) = check_diagram(&out, enclosed);
    assert!(
        problems.is_empty(),
        "{name}: {} of {checked} state files do not hold their rows:\n{}",
        problems.len(),
        problems.join("\n")
    );
    assert!(checked >= min_files, "{name}: only {checked} state files");
    let rows = columns(&out.join("branches.csv"), &["lbar"]).len();
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let unverified = summary["unverified_states"].as_u64().unwrap() as usize;
    if enclosed {
        assert_eq!(unverified, rows - checked, "{name}: rows without a file");
    } else {
        assert_eq!(rows, checked, "{name}: rows without a file");
    }
}

fn scene(name: &str) -> String {
    format!("{}/data/scenes/{name}.toml", env!("CARGO_MANIFEST_DIR"))
}

/// A very soft segment (D1/D0 = 0.001), branch 2 around L̄ = 1: the tracing resolution's
/// profile is up to 1.6e-3 relative off the state's Richardson energy there, whose
/// estimate is 6e-6.
#[test]
fn two_segment_diagram_files_hold_their_rows() {
    let sc = scene("inhomogeneous-d1-0.001");
    diagram_files_hold_their_rows(
        "d1-0.001",
        &["--scene", &sc, "--lbar-min", "0.98", "--lbar-max", "1.05"],
        false,
        20,
    );
}

#[test]
fn uniform_diagram_files_hold_their_rows() {
    let sc = scene("homogeneous-surface");
    diagram_files_hold_their_rows("uniform", &["--scene", &sc], false, 50);
}

#[test]
fn enclosed_diagram_files_hold_their_rows() {
    let sc = scene("homogeneous-enclosed");
    diagram_files_hold_their_rows("enclosed", &["--scene", &sc], true, 50);
}

/// The periods `η` of a paper branch (1: η = 2, 2: η = 1, B ≥ 3: η = B).
fn eta_of(branch: u32) -> usize {
    match branch {
        1 => 2,
        2 => 1,
        b => b as usize,
    }
}

/// The dominant harmonic of the `kappa_g` column of a state file (samples uniform in
/// arclength): the periods `η` of its geodesic curvature, counted here by a plain DFT.
fn dominant_harmonic(dir: &Path, file: &str) -> usize {
    let kg: Vec<f64> = columns(&dir.join(file), &["kappa_g"])
        .into_iter()
        .map(|r| r[0])
        .collect();
    strongest_harmonic(&kg)
}

/// The dominant Fourier harmonic of the bending moment `D κ_g` about its mean: on a
/// two-segment rod `κ_g` alone is `D0/D1` times larger in the soft segment, whose bumps can
/// outweigh the loop's own periods; the moment is continuous across the stiffness step.
fn moment_harmonic(dir: &Path, file: &str) -> usize {
    let m: Vec<f64> = columns(&dir.join(file), &["kappa_g", "D"])
        .into_iter()
        .map(|r| r[0] * r[1])
        .collect();
    let mean = m.iter().sum::<f64>() / m.len() as f64;
    strongest_harmonic(&m.iter().map(|v| v - mean).collect::<Vec<_>>())
}

fn strongest_harmonic(kg: &[f64]) -> usize {
    let n = kg.len();
    (1..n / 2)
        .map(|k| {
            let (c, s) = kg.iter().enumerate().fold((0.0, 0.0), |(c, s), (j, v)| {
                let a = 2.0 * PI * (k * j) as f64 / n as f64;
                (c + v * a.cos(), s + v * a.sin())
            });
            (k, c * c + s * s)
        })
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap()
        .0
}

/// `phase`: both states of every Maxwell-point row are in `states/` (the limit row, an
/// extrapolation to the uniform rod, has none); each closes, lies on the sphere, has the
/// row's energy within its estimate, and has as many periods of `κ_g` as its branch.
#[test]
fn phase_files_hold_their_rows() {
    let out = fresh_dir("state-files", "phase");
    rodloop_ok(&[
        "phase",
        "--scene",
        &scene("inhomogeneous-d1-0.5"),
        "--param",
        "d1",
        "--to",
        "0.4",
        "--out",
        out.to_str().unwrap(),
    ]);
    let mut rdr = csv::Reader::from_path(out.join("phase.csv")).unwrap();
    let head = rdr.headers().unwrap().clone();
    let col = |n: &str| head.iter().position(|h| h == n).unwrap();
    let mut problems = Vec::new();
    let (mut checked, mut rows) = (0, 0);
    for row in rdr.records() {
        let row = row.unwrap();
        let num = |n: &str| row[col(n)].parse::<f64>().unwrap();
        let files = [
            row[col("state_file_from")].trim(),
            row[col("state_file_to")].trim(),
        ];
        if &row[col("source")] == "limit" {
            assert!(
                files.iter().all(|f| f.is_empty()),
                "the limit row has files"
            );
            continue;
        }
        rows += 1;
        let branches = [num("from_branch") as u32, num("to_branch") as u32];
        for (file, branch) in files.into_iter().zip(branches) {
            assert!(!file.is_empty(), "a row without its state files");
            checked += 1;
            problems.extend(check_file(
                &out,
                file,
                num("lbar_cr"),
                num("energy"),
                Some(num("energy_error")),
                false,
            ));
            let eta = dominant_harmonic(&out, file);
            if eta != eta_of(branch) {
                problems.push(format!(
                    "{file}: κ_g has {eta} periods, branch {branch} has {}",
                    eta_of(branch)
                ));
            }
        }
    }
    assert!(
        problems.is_empty(),
        "{} of {checked} state files do not hold their rows:\n{}",
        problems.len(),
        problems.join("\n")
    );
    assert!(rows >= 10, "only {rows} rows");
    assert!(summary(&out)["unverified_states"].as_u64().is_some());
}

/// `converge`: the finest rung's state is in `states/`, holds its row (energy within the
/// rung's estimate), and has as many periods of `κ_g` as the branch; on a uniform and a
/// two-segment rod.
#[test]
fn converge_finest_file_holds_its_row() {
    for (name, sc, branch) in [
        ("converge-uniform", scene("homogeneous-surface"), 2),
        ("converge-d1-0.5", scene("inhomogeneous-d1-0.5"), 1),
    ] {
        let out = fresh_dir("state-files", name);
        rodloop_ok(&[
            "converge",
            "--scene",
            &sc,
            "--lbar",
            "1.3",
            "--branch",
            &branch.to_string(),
            "--levels",
            "4",
            "--out",
            out.to_str().unwrap(),
        ]);
        let mut rdr = csv::Reader::from_path(out.join("converge.csv")).unwrap();
        let head = rdr.headers().unwrap().clone();
        let col = |n: &str| head.iter().position(|h| h == n).unwrap();
        let rows: Vec<csv::StringRecord> = rdr.records().map(|r| r.unwrap()).collect();
        let (last, rest) = rows.split_last().unwrap();
        assert!(rest.iter().all(|r| r[col("state_file")].is_empty()));
        let file = last[col("state_file")].trim();
        assert_eq!(file, "states/finest.csv", "{name}");
        let problems = check_file(
            &out,
            file,
            1.3,
            last[col("energy")].parse().unwrap(),
            Some(last[col("error_estimate")].parse().unwrap()),
            false,
        );
        assert!(problems.is_empty(), "{name}: {}", problems.join("\n"));
        assert_eq!(dominant_harmonic(&out, file), eta_of(branch), "{name}");
        assert_eq!(
            summary(&out)["unverified_states"].as_u64(),
            Some(0),
            "{name}"
        );
    }
}

/// `diagram --param`: every traced state is in `states/` and holds its row of
/// `branches.csv` (energy within its estimate), with as many periods of its bending moment `D κ_g` as its
/// branch; `unverified_states` counts the states left out.
#[test]
fn param_diagram_files_hold_their_rows() {
    let out = fresh_dir("state-files", "param");
    rodloop_ok(&[
        "diagram",
        "--scene",
        &scene("inhomogeneous-d1-0.5"),
        "--param",
        "d1",
        "--lbar",
        "1.3",
        "--to",
        "0.01",
        "--out",
        out.to_str().unwrap(),
    ]);
    let (mut problems, checked) = check_diagram(&out, false);
    let rows = columns(&out.join("branches.csv"), &["branch"]);
    assert_eq!(rows.len(), checked, "rows without a file");
    assert!(checked >= 20, "only {checked} state files");
    let mut rdr = csv::Reader::from_path(out.join("branches.csv")).unwrap();
    let head = rdr.headers().unwrap().clone();
    let (ib, ifile) = (
        head.iter().position(|h| h == "branch").unwrap(),
        head.iter().position(|h| h == "state_file").unwrap(),
    );
    let iv = head.iter().position(|h| h == "value").unwrap();
    let mut other = 0;
    for row in rdr.records() {
        let row = row.unwrap();
        let branch: u32 = row[ib].parse().unwrap();
        let eta = moment_harmonic(&out, &row[ifile]);
        if eta != eta_of(branch) {
            other += 1;
            problems.push(format!(
                "{} (d1 = {}): D κ_g has {eta} periods, branch {branch} has {}",
                &row[ifile],
                &row[iv],
                eta_of(branch)
            ));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
    let s = summary(&out);
    assert!(s["unverified_states"].as_u64().is_some());
    // Those are counted in the summary.
    assert_eq!(s["states_counted_other_eta"].as_u64(), Some(other));
}

/// The periods of a surface state file's bending moment `D κ_g` (samples `s`, loop `length`),
/// counted here as `rodloop_solver::identify` counts them (the count of
/// `scripts/state_check.py`, `named_periods`): half the sign changes of the moment about its
/// trapezoid-weighted mean, with hysteresis at 4 times the grid-scale noise (the largest
/// residual of the cubic through the two neighbours on either side) and at a tenth of the
/// amplitude; `None` unless both levels give the same non-zero count.
fn named_periods(s: &[f64], m: &[f64], length: f64) -> Option<usize> {
    let n = s.len();
    let gap = |j: usize, o: isize| {
        let i = (j as isize + o).rem_euclid(n as isize) as usize;
        let wrap = if j as isize + o >= n as isize {
            length
        } else if (j as isize + o) < 0 {
            -length
        } else {
            0.0
        };
        (i, s[i] - s[j] + wrap)
    };
    let w: Vec<f64> = (0..n).map(|j| 0.5 * (gap(j, 1).1 - gap(j, -1).1)).collect();
    let mean = m.iter().zip(&w).map(|(a, b)| a * b).sum::<f64>() / length;
    let dev: Vec<f64> = m.iter().map(|v| v - mean).collect();
    let amp = dev.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let scale = m.iter().fold(1.0 / length, |a, v| a.max(v.abs()));
    if amp <= 1e-9 * scale {
        return None;
    }
    let noise = (0..n)
        .map(|j| {
            let pts: Vec<(f64, f64)> = [-2, -1, 1, 2]
                .iter()
                .map(|&o| {
                    let (i, d) = gap(j, o);
                    (d, dev[i])
                })
                .collect();
            let p: f64 = (0..4)
                .map(|a| {
                    (0..4)
                        .filter(|&b| b != a)
                        .fold(pts[a].1, |t, b| t * pts[b].0 / (pts[b].0 - pts[a].0))
                })
                .sum();
            (dev[j] - p).abs()
        })
        .fold(0.0f64, f64::max);
    let changes = |h: f64| {
        let start = dev.iter().position(|v| v.abs() > h)?;
        let (mut positive, mut count) = (dev[start] > 0.0, 0);
        for i in 1..=n {
            let v = dev[(start + i) % n];
            if positive && v < -h {
                (positive, count) = (false, count + 1);
            } else if !positive && v > h {
                (positive, count) = (true, count + 1);
            }
        }
        Some(count)
    };
    let h = (4.0 * noise).max(1e-12 * scale);
    let (fine, coarse) = (changes(h)?, changes(h.max(0.1 * amp))?);
    (fine == coarse && coarse > 0).then_some(coarse / 2)
}

/// `summary.json` of a two-segment diagram says how the branch of each state file is
/// identified (`branch_identification`, docs/src/methods.md): on the very soft scene near
/// `L̄ = 1` most files' moments have no resolved periods, so their rows' branches come from
/// continuation only. The three counts are those of the files, each file's moment counted
/// here independently ([`named_periods`]) against its row's `η`.
#[test]
fn two_segment_summary_says_how_each_branch_is_identified() {
    let out = fresh_dir("state-files", "d1-0.001-identified");
    let sc = scene("inhomogeneous-d1-0.001");
    let args = ["--scene", &sc, "--lbar-min", "0.98", "--lbar-max", "1.05"];
    let mut all = vec!["diagram", "--out", out.to_str().unwrap()];
    all.extend_from_slice(&args);
    rodloop_ok(&all);
    let mut rdr = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .from_path(out.join("branches.csv"))
        .unwrap();
    let head = rdr.headers().unwrap().clone();
    let col = |n: &str| head.iter().position(|h| h == n).unwrap();
    let (il, ieta, ifile) = (col("lbar"), col("eta"), col("state_file"));
    let (mut own, mut none, mut other) = (0u64, 0u64, 0u64);
    for row in rdr.records() {
        let row = row.unwrap();
        let lbar: f64 = row[il].parse().unwrap();
        let eta: usize = row[ieta].parse().unwrap();
        let pts = columns(&out.join(row[ifile].trim()), &["s", "kappa_g", "D"]);
        let s: Vec<f64> = pts.iter().map(|p| p[0]).collect();
        let m: Vec<f64> = pts.iter().map(|p| p[1] * p[2]).collect();
        match named_periods(&s, &m, 2.0 * PI * lbar) {
            None => none += 1,
            Some(e) if e == eta => own += 1,
            Some(_) => other += 1,
        }
    }
    let named = &summary(&out)["branch_identification"];
    let count = |k: &str| {
        named[k]
            .as_u64()
            .unwrap_or_else(|| panic!("summary.json has no branch_identification.{k}: {named}"))
    };
    assert!(none > 0, "no file without resolved periods: {own}, {other}");
    assert_eq!(
        (
            count("by_own_periods"),
            count("by_continuation_no_periods"),
            count("by_continuation_other_periods")
        ),
        (own, none, other)
    );
}
