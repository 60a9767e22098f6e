//! `solve` returns a local minimum of the requested branch: where Newton converges to a
//! saddle, the state is descended along its unstable directions to the index-0 state of the
//! same branch below it; `--keep-saddle` keeps the Newton state.
//!
//! The two-segment rod of the paper (D1/D0 = 0.5, Eq. (51)) at L̄ = 1.9, branch 1: Newton
//! from the Euler curve converges to the mirror-symmetric state, index 1; the branch has an
//! asymmetric index-0 state below it.

use std::path::Path;

mod common;
use common::{rodloop, rodloop_ok, tmp};

const SCENE: &str = "data/scenes/inhomogeneous-d1-0.5.toml";

fn solve(out: &Path, extra: &[&str]) -> serde_json::Value {
    let mut args = vec![
        "solve",
        "--scene",
        SCENE,
        "--lbar",
        "1.9",
        "--branch",
        "1",
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let o = rodloop_ok(&args);
    let s = std::fs::read_to_string(out.join("summary.json")).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&s).unwrap();
    v["stdout"] = String::from_utf8_lossy(&o.stdout).to_string().into();
    v
}

fn f(v: &serde_json::Value, key: &str) -> f64 {
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("{key} missing in {v}"))
}

/// The default solve descends from the index-1 symmetric state to an index-0 state of
/// branch 1 (identified from the state, η = 2) below it, and says so; an independent solve
/// from the written `config.csv` lands on the same energy within the two estimates;
/// `--keep-saddle` returns the index-1 state the descent started from.
#[test]
fn saddle_is_descended_to_the_minimum_of_its_branch() {
    let dir = tmp("descend-1.9");
    let min = solve(&dir.join("default"), &[]);
    assert_eq!(min["index"], 0, "{min}");
    assert_eq!(min["identified_eta"], 2, "{min}");
    let d = &min["descent"];
    assert_eq!(d["from_index"], 1, "{min}");
    assert_eq!(d["to_index"], 0, "{min}");
    assert!(
        min["stdout"]
            .as_str()
            .unwrap()
            .contains("descended from an index-1 state"),
        "{min}"
    );
    let (e, est) = (f(&min, "energy"), f(&min, "error_estimate"));
    assert!((f(d, "to_energy") - e).abs() <= 1e-14 * e, "{min}");

    let saddle = solve(&dir.join("keep"), &["--keep-saddle"]);
    assert_eq!(saddle["index"], 1, "{saddle}");
    assert_eq!(saddle["identified_eta"], 2, "{saddle}");
    assert!(saddle["descent"].is_null(), "{saddle}");
    let (es, ests) = (f(&saddle, "energy"), f(&saddle, "error_estimate"));
    // The descent started from that very state, and ended clearly below it.
    assert!(
        (f(d, "from_energy") - es).abs() <= 1e-12 * es,
        "{saddle} {min}"
    );
    assert!(e < es - 1e-4, "minimum {e} not below the saddle {es}");
    assert!(es - e > 100.0 * (est + ests));

    // Independent re-solve from the written state.
    let cfg = dir.join("default").join("config.csv");
    let again = solve(&dir.join("from"), &["--from", cfg.to_str().unwrap()]);
    assert_eq!(again["index"], 0, "{again}");
    let (ea, esta) = (f(&again, "energy"), f(&again, "error_estimate"));
    assert!(
        (ea - e).abs() <= est + esta,
        "re-solve {ea} ± {esta} against {e} ± {est}"
    );
}

/// Where Newton already lands on a local minimum nothing changes: no descent is reported
/// (L̄ = 1.3, index 0).
#[test]
fn minimum_is_returned_as_it_is() {
    let dir = tmp("descend-1.3");
    let out = dir.join("default");
    let o = rodloop(&[
        "solve",
        "--scene",
        SCENE,
        "--lbar",
        "1.3",
        "--branch",
        "1",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(s["index"], 0, "{s}");
    assert!(s["descent"].is_null(), "{s}");
    assert!(!String::from_utf8_lossy(&o.stdout).contains("descended"));
}

/// `solve` on the two-segment enclosed scene at `L̄`, branch 2, at `accuracy` (with `extra`
/// flags): its summary.
fn enclosed_run(dir: &Path, lbar: &str, acc: &str, extra: &[&str]) -> serde_json::Value {
    let out = dir.join(format!("{acc}{}", extra.len()));
    let mut args = vec![
        "solve",
        "--scene",
        "data/scenes/inhomogeneous-d1-0.5-enclosed.toml",
        "--lbar",
        lbar,
        "--branch",
        "2",
        "--accuracy",
        acc,
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    rodloop_ok(&args);
    serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap()
}

/// The two-segment enclosed scene at L̄ = 0.9, branch 2 (the figure-eight, η = 1): `solve`
/// reports one state at every accuracy level: the branch identified from the state, one
/// stability index, the energies within each other's estimates. Every start reaches a
/// saddle on the 96 cells of `fast` and `default` (the uniform rod's figure-eight held at its
/// lobe tips is a saddle too); on 128 cells the saddle reached from `high`'s surface loop
/// descends to a local minimum of the branch, which every level reports. Where the state
/// reported is a saddle, `solve` says so; the state Newton reaches from the surface loop
/// (`--keep-saddle`) does not lie below the one reported.
#[test]
fn enclosed_state_is_the_same_at_every_accuracy() {
    let dir = tmp("descend-enclosed-0.9");
    let run = |acc: &str, extra: &[&str]| enclosed_run(&dir, "0.9", acc, extra);
    let states: Vec<serde_json::Value> = ["fast", "default", "high"]
        .iter()
        .map(|a| run(a, &[]))
        .collect();
    let index = &states[0]["index"];
    for s in &states {
        assert_eq!(s["identified_eta"], 1, "{s}");
        assert_eq!(&s["index"], index, "{s}");
        if s["index"].as_u64().unwrap() > 0 {
            let method = s["method"].as_str().unwrap();
            assert!(
                method.contains("no local minimum of branch 2 was found"),
                "{method}"
            );
        }
    }
    for a in &states {
        for b in &states {
            let (ea, eb) = (f(a, "energy"), f(b, "energy"));
            let tol = f(a, "error_estimate") + f(b, "error_estimate");
            assert!((ea - eb).abs() <= tol, "{ea} vs {eb} (± {tol})");
        }
    }
    let kept = run("fast", &["--keep-saddle"]);
    assert_eq!(kept["identified_eta"], 1, "{kept}");
    let tol = f(&states[0], "error_estimate") + f(&kept, "error_estimate");
    assert!(
        f(&kept, "energy") >= f(&states[0], "energy") - tol,
        "{kept} {}",
        states[0]
    );
}
