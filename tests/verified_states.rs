//! Every state `solve` reports is verified: the written loop closes, lies on the sphere,
//! reproduces the printed energy and has the requested branch; impossible sizes and
//! magnitudes are refused before any work.

mod common;

use std::f64::consts::PI;
use std::path::Path;

use common::{fresh_dir, rodloop};

/// The written `config.csv` checked against `summary.json`: the chord from the last point
/// back to the first is no longer than the arclength between them, every point is on the
/// unit sphere, the trapezoidal energy of the file matches the summary's within the
/// tolerance the summary states (its error estimate plus that of the recomputation: the
/// file's `κ_g = 𝓜·n/D` is a second `O(h⁴)` discretisation of the state, compared with the
/// same recomputation on the companion solve) plus the rule's own (`|T_h − T_2h|`), and the
/// summary's periods of `kappa_g` are `eta`.
fn check_written_state(dir: &Path, eta: u32) {
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    let lbar = summary["lbar"].as_f64().unwrap();
    let energy = summary["energy"].as_f64().unwrap();
    let error = summary["error_estimate"].as_f64().unwrap();
    assert_eq!(summary["identified_eta"].as_u64(), Some(u64::from(eta)));
    let mut rdr = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .from_path(dir.join("config.csv"))
        .unwrap();
    let head = rdr.headers().unwrap().clone();
    let col = |n: &str| head.iter().position(|h| h == n).unwrap();
    let (is, ix, iy, iz, ik, id, ig) = (
        col("s"),
        col("x"),
        col("y"),
        col("z"),
        col("kappa"),
        col("D"),
        col("kappa_g"),
    );
    let rows: Vec<Vec<f64>> = rdr
        .records()
        .map(|r| r.unwrap().iter().map(|v| v.parse().unwrap()).collect())
        .collect();
    let n = rows.len();
    let length = 2.0 * PI * lbar;
    let dist = |a: &Vec<f64>, b: &Vec<f64>| {
        ((a[ix] - b[ix]).powi(2) + (a[iy] - b[iy]).powi(2) + (a[iz] - b[iz]).powi(2)).sqrt()
    };
    let chord = dist(&rows[n - 1], &rows[0]);
    let arc = length + rows[0][is] - rows[n - 1][is];
    assert!(
        chord <= arc * (1.0 + 1e-9),
        "open loop: chord {chord} over arc {arc}"
    );
    for r in &rows {
        let rad = (r[ix].powi(2) + r[iy].powi(2) + r[iz].powi(2)).sqrt();
        assert!((rad - 1.0).abs() < 1e-9, "off the sphere: |r| = {rad}");
    }
    let trap = |step: usize| {
        let idx: Vec<usize> = (0..n).step_by(step).collect();
        let m = idx.len();
        (0..m)
            .map(|j| {
                let (a, b) = (&rows[idx[j]], &rows[idx[(j + 1) % m]]);
                let ds = if j + 1 < m {
                    b[is] - a[is]
                } else {
                    length + b[is] - a[is]
                };
                0.25 * (a[id] * a[ik] * a[ik] + b[id] * b[ik] * b[ik]) * ds
            })
            .sum::<f64>()
            / PI
    };
    let (fine, coarse) = (trap(1), trap(2));
    let stated = summary["verification"]["energy_tolerance"]
        .as_f64()
        .unwrap();
    assert!(stated >= error, "{stated} below the estimate {error}");
    let tol = stated + (fine - coarse).abs() + 1e-9 * energy.abs().max(1.0);
    assert!(
        (fine - energy).abs() <= tol,
        "energy from the file {fine} against the printed {energy} (tolerance {tol:e})"
    );
    // Periods of κ_g: sign changes of κ_g − mean with a hysteresis of a tenth of the range.
    let kg: Vec<f64> = rows.iter().map(|r| r[ig]).collect();
    let mean = kg.iter().sum::<f64>() / n as f64;
    let amp = kg.iter().map(|v| (v - mean).abs()).fold(0.0, f64::max);
    let h = 0.1 * amp;
    let start = kg.iter().position(|v| (v - mean).abs() > h).unwrap();
    let mut sign = kg[start] > mean;
    let mut changes = 0;
    for i in 1..=n {
        let v = kg[(start + i) % n] - mean;
        if sign && v < -h {
            sign = false;
            changes += 1;
        } else if !sign && v > h {
            sign = true;
            changes += 1;
        }
    }
    assert!(changes >= 2, "κ_g does not oscillate");
}

/// `solve` either writes a verified state of the requested branch or fails cleanly.
fn solve_is_verified_or_refused(scene: &str, lbar: &str, branch: &str, extra: &[&str], eta: u32) {
    let out = fresh_dir("verified", &format!("{scene}-{lbar}-{branch}"));
    let path = format!("{}/data/scenes/{scene}.toml", env!("CARGO_MANIFEST_DIR"));
    let mut args = vec![
        "solve",
        "--scene",
        &path,
        "--lbar",
        lbar,
        "--branch",
        branch,
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let o = rodloop(&args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("panicked"), "{err}");
    if o.status.success() {
        check_written_state(&out, eta);
    } else {
        assert_eq!(o.status.code(), Some(1), "{err}");
        assert_eq!(err.trim().lines().count(), 1, "one line: {err}");
        assert!(
            !out.join("config.csv").exists(),
            "a refused state was written"
        );
    }
}

/// Scenes and lengths where Newton meets holonomies near a half-turn (an open loop with a
/// closure residual `vee(skew H) = 0`, up to 2 R from closing): `solve` writes a closed,
/// verified loop or refuses. On D1/D0 = 0.1 at L̄ = 1.4, branch 2 is the closed state of
/// energy 0.9445606845 (the open half-turn loop has 0.7856813854).
#[test]
fn half_turn_loops_are_not_reported() {
    solve_is_verified_or_refused("inhomogeneous-d1-0.1", "1.4", "2", &[], 1);
    solve_is_verified_or_refused("inhomogeneous-d1-0.001", "0.7", "2", &[], 1);
    solve_is_verified_or_refused(
        "inhomogeneous-d1-0.001",
        "0.6",
        "2",
        &["--accuracy", "fast"],
        1,
    );
    solve_is_verified_or_refused(
        "inhomogeneous-d1-0.1",
        "0.6",
        "2",
        &["--accuracy", "fast"],
        1,
    );
    let out = fresh_dir("verified", "energy-d1-0.1");
    let path = format!(
        "{}/data/scenes/inhomogeneous-d1-0.1.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    let o = rodloop(&[
        "solve",
        "--scene",
        &path,
        "--lbar",
        "1.4",
        "--branch",
        "2",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success());
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let e = s["energy"].as_f64().unwrap();
    assert!((e - 0.9445606845).abs() < 1e-6, "energy {e}");
}

/// A state reached by continuation in D1/D0 whose own κ_g has another number of periods
/// (3 for branch 1 at L̄ = 1.5 on D1/D0 = 0.001) is not reported as branch 1.
#[test]
fn states_of_another_branch_are_not_reported() {
    solve_is_verified_or_refused("inhomogeneous-d1-0.001", "1.5", "1", &[], 2);
}

/// Sizes that cannot be honoured are refused before any allocation, naming the limit.
#[test]
fn impossible_sizes_are_refused_up_front() {
    let out = fresh_dir("verified", "huge");
    let o = rodloop(&[
        "solve",
        "--lbar",
        "1000.5",
        "--branch",
        "1000",
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("56056 cells") && err.contains("4096"), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
}

/// Magnitudes double precision cannot resolve are refused at scene validation, naming the
/// field and the limit.
#[test]
fn unrepresentable_magnitudes_are_refused_by_the_scene() {
    let dir = fresh_dir("verified", "magnitudes");
    for (radius, d0, d1, field, limit) in [
        ("1.0", "1.0", "1e-300", "stiffness.d1", "1e-6"),
        ("1.0", "1e300", "0.5", "stiffness.d0", "1e3"),
        ("1e308", "1.0", "0.5", "radius", "1e3"),
        ("1.0", "1.0", "1e-7", "stiffness.d1", "1e-6"),
        ("1.0", "1.0", "1e5", "stiffness.d1", "1e4"),
    ] {
        let scene = dir.join(format!("{field}-{d1}.toml"));
        std::fs::write(
            &scene,
            format!(
                "name = \"m\"\nradius = {radius}\nconfinement = \"surface\"\nlbar_min = 1.0\n\
                 lbar_max = 3.0\n[stiffness]\nkind = \"tanh\"\nd0 = {d0}\nd1 = {d1}\ns0 = 0.3\n\
                 s1 = 0.8\ngamma = 200.0\n"
            ),
        )
        .unwrap();
        let o = rodloop(&[
            "solve",
            "--scene",
            scene.to_str().unwrap(),
            "--lbar",
            "1.3",
            "--branch",
            "1",
            "--out",
            dir.join("out").to_str().unwrap(),
        ]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{err}");
        assert!(
            err.contains(field) && err.contains(limit) && err.contains("scene file"),
            "{field}: {err}"
        );
        assert_eq!(err.trim().lines().count(), 1, "{err}");
    }
}
