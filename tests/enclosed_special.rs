//! The uniform enclosed diagram on a sub-range: the lifted-off figure-eight (branch 2) is
//! traced on every sample of the window, and its states there are the whole range's.

use std::path::{Path, PathBuf};
use std::process::Command;

fn out(name: &str) -> PathBuf {
    let p = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&p);
    p
}

/// `rodloop diagram` on the uniform enclosed scene with `extra` arguments; returns the
/// branch-2 rows of `branches.csv` as `(lbar, energy, energy_error)`.
fn branch2(name: &str, extra: &[&str]) -> Vec<(f64, f64, f64)> {
    let dir = out(name);
    let scene = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/data/scenes/homogeneous-enclosed.toml"
    );
    let o = Command::new(env!("CARGO_BIN_EXE_rodloop"))
        .args(["diagram", "--scene", scene, "--out", dir.to_str().unwrap()])
        .args(extra)
        .output()
        .expect("run rodloop");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(dir.join("branches.csv")).unwrap();
    let mut lines = text.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |n: &str| head.iter().position(|h| *h == n).unwrap();
    let (b, l, e, r) = (
        col("branch"),
        col("lbar"),
        col("energy"),
        col("energy_error"),
    );
    lines
        .map(|line| line.split(',').collect::<Vec<_>>())
        .filter(|f| f[b] == "2")
        .map(|f| {
            (
                f[l].parse().unwrap(),
                f[e].parse().unwrap(),
                f[r].parse().unwrap(),
            )
        })
        .collect()
}

#[test]
fn sub_range_traces_every_sample_like_the_whole_range() {
    // With `--lbar-max 1.2` the middle sample (1.1) lies 0.25 R off the wall, where Newton
    // from the surface loop does not converge: the trace is seeded at the next sample.
    let part = branch2("enclosed_special_sub", &["--lbar-max", "1.2"]);
    let whole = branch2("enclosed_special_whole", &[]);
    let xs: Vec<f64> = part.iter().map(|p| p.0).collect();
    for x in [1.05, 1.1, 1.15] {
        assert!(
            xs.iter().any(|&y| (y - x).abs() < 1e-9),
            "no branch-2 state at {x}: {xs:?}"
        );
    }
    for &(x, e, err) in &part {
        let Some(&(_, ew, errw)) = whole.iter().find(|w| (w.0 - x).abs() < 1e-9) else {
            continue;
        };
        assert!(
            (e - ew).abs() <= err + errw + 1e-12,
            "lbar = {x}: {e} ± {err} on the sub-range, {ew} ± {errw} on the whole range"
        );
    }
    assert!(
        part.iter()
            .filter(|p| whole.iter().any(|w| (w.0 - p.0).abs() < 1e-9))
            .count()
            >= 3
    );
}
