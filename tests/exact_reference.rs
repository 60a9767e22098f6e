//! The exact layer against an independent 30-digit mpmath solution of Eqs. (48)-(50)
//! (`scripts/gen_exact_reference.py`, `data/reference/exact_*.csv`).

use rodloop_exact::diagram::{compute, CriticalKind, DiagramSettings};
use rodloop_exact::{branch_of_eta, paper_branch_loop};

fn rows(name: &str) -> Vec<Vec<String>> {
    let path = format!("{}/data/reference/{name}", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    text.lines()
        .filter(|l| !l.starts_with('#'))
        .skip(1)
        .map(|l| l.split(',').map(String::from).collect())
        .collect()
}

fn f(s: &str) -> f64 {
    s.parse().unwrap()
}

#[test]
fn loops_match_mpmath_to_1e_12() {
    let table = rows("exact_loops.csv");
    assert!(table.len() >= 10);
    let (mut wk, mut wc, mut we) = (0.0f64, 0.0f64, 0.0f64);
    for r in table {
        let (eta, lbar) = (r[0].parse::<u32>().unwrap(), f(&r[1]));
        let lp = paper_branch_loop(eta, lbar).unwrap();
        let rel = |a: f64, b: f64| (a - b).abs() / b.abs();
        assert!(
            rel(lp.k, f(&r[2])) < 1e-11,
            "k at {eta},{lbar}: {} vs {}",
            lp.k,
            r[2]
        );
        assert!(rel(lp.c, f(&r[3])) < 1e-12, "c at {eta},{lbar}");
        assert_eq!(lp.p, r[4].parse::<i32>().unwrap(), "p at {eta},{lbar}");
        assert!(
            rel(lp.energy().unwrap(), f(&r[5])) < 1e-13,
            "energy at {eta},{lbar}"
        );
        wk = wk.max(rel(lp.k, f(&r[2])));
        wc = wc.max(rel(lp.c, f(&r[3])));
        we = we.max(rel(lp.energy().unwrap(), f(&r[5])));
    }
    eprintln!("worst relative error vs mpmath: k {wk:.1e}, c {wc:.1e}, energy {we:.1e}");
}

#[test]
fn critical_crossings_match_mpmath_within_their_error_estimates() {
    let d = compute(&DiagramSettings::default()).unwrap();
    let crossings: Vec<_> = d
        .critical
        .iter()
        .filter(|c| c.kind == CriticalKind::Crossing)
        .collect();
    let table = rows("exact_critical.csv");
    assert_eq!(crossings.len(), table.len());
    let mut worst = 0.0f64;
    for (c, r) in crossings.iter().zip(&table) {
        let (ea, eb) = (r[0].parse::<u32>().unwrap(), r[1].parse::<u32>().unwrap());
        let pair = [branch_of_eta(ea), branch_of_eta(eb)];
        assert!(pair.contains(&c.from_branch) && pair.contains(&c.to_branch));
        let err = (c.lbar_cr - f(&r[2])).abs();
        assert!(
            err <= c.error_estimate.max(1e-15) * 2.0,
            "{}: error {err} > estimate {}",
            r[2],
            c.error_estimate
        );
        assert!(err < 1e-13, "{}: {err}", r[2]);
        assert!((c.energy - f(&r[3])).abs() < 1e-13 * c.energy);
        worst = worst.max(err);
    }
    eprintln!("worst critical-length error vs mpmath: {worst:.1e}");
}
