//! The continuation controls of `diagram`: each one changes what the
//! tracer does, bad values and the exact model are refused with a message.

use std::path::Path;
use std::process::Output;

mod common;
use common::{bin, tmp};

/// Run the built binary with `--out out`.
fn rodloop(args: &[&str], out: &Path) -> Output {
    bin().args(args).arg("--out").arg(out).output().unwrap()
}

#[test]
fn max_points_and_max_step_bound_the_tracing() {
    // Ten points of at most 0.01 cannot cover a branch: every branch stops at the budget,
    // which the warnings name together with the flag that raises it.
    let out = tmp("controls-budget");
    let o = rodloop(
        &[
            "diagram",
            "--max-points",
            "10",
            "--max-step",
            "0.01",
            "--lbar-max",
            "2",
        ],
        &out,
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("budget of 10 steps (raise it with --max-points)"),
        "{err}"
    );
    // Without the controls the same range is traced to its ends (no budget warning).
    let out = tmp("controls-free");
    let o = rodloop(&["diagram", "--lbar-max", "2"], &out);
    assert!(o.status.success());
    assert!(!String::from_utf8_lossy(&o.stderr).contains("budget"));
}

#[test]
fn bad_controls_are_refused() {
    for (args, word) in [
        (vec!["diagram", "--max-points", "5"], "max_points"),
        (vec!["diagram", "--max-step", "-1"], "max_step"),
        (
            vec!["diagram", "--min-step", "1", "--max-step", "0.1"],
            "min_step",
        ),
        (vec!["diagram", "--newton-tol", "1"], "newton_tol"),
        (
            vec!["diagram", "--model", "exact", "--max-step", "0.1"],
            "numeric model",
        ),
    ] {
        let out = tmp("controls-bad");
        let o = rodloop(&args, &out);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{args:?}");
        assert!(
            err.contains(word) && !err.contains("panicked"),
            "{args:?}: {err}"
        );
        assert!(!out.join("summary.json").exists());
    }
}
