//! Buckling of the m-fold great circles (Sec. 4.2, Eqs. 33–34) and branch switching.

use crate::common::{default_diagram, fast_diagram};

#[test]
fn buckling_loads_agree_with_eqs_33_and_34() {
    for (d, tol) in [(default_diagram(), 1e-7), (fast_diagram(), 5e-6)] {
        let g = d.great_circles.as_ref().expect("analysed");
        for m in 1..=5u32 {
            let mf = f64::from(m);
            let up = g
                .loads
                .iter()
                .find(|l| l.m == m && l.mode_periods == m + 1)
                .unwrap_or_else(|| panic!("no m + 1 mode for m = {m}"));
            let f33 = (mf + 1.0).powi(2) / (mf * mf);
            assert_eq!(up.lambda_formula, Some(f33));
            assert_eq!(up.equation.as_deref(), Some("33"));
            assert_eq!(up.multiplicity, 2);
            let dev = (up.lambda_numeric - f33).abs();
            println!(
                "m = {m}, n = {}: λ = {:.12} vs {f33:.12} ({dev:.1e}, est. {:.1e})",
                m + 1,
                up.lambda_numeric,
                up.lambda_error
            );
            assert!(
                dev <= tol && dev <= up.lambda_error,
                "Eq. (33), m = {m}: {dev:e}"
            );
            if m >= 2 {
                let down = g
                    .loads
                    .iter()
                    .find(|l| l.m == m && l.mode_periods == m - 1)
                    .unwrap_or_else(|| panic!("no m − 1 mode for m = {m}"));
                let f34 = (mf - 1.0).powi(2) / (mf * mf);
                let dev = (down.lambda_numeric - f34).abs();
                println!(
                    "m = {m}, n = {}: λ = {:.12} vs {f34:.12} ({dev:.1e}, est. {:.1e})",
                    m - 1,
                    down.lambda_numeric,
                    down.lambda_error
                );
                assert_eq!(down.equation.as_deref(), Some("34"));
                assert!(
                    dev <= tol && dev <= down.lambda_error.max(1e-13),
                    "Eq. (34), m = {m}: {dev:e}"
                );
            }
        }
    }
}

#[test]
fn switching_from_great_circles_finds_the_traced_branches() {
    let d = default_diagram();
    let g = d.great_circles.as_ref().expect("analysed");
    // Every traced branch is found again from a great circle, and every switched branch
    // inside the range is merged with a traced one.
    for b in &d.branches {
        assert!(
            g.switching
                .iter()
                .any(|s| s.merged && s.joined_branch == Some(b.branch)),
            "branch {} not reached by switching",
            b.branch
        );
    }
    for s in &g.switching {
        println!("m = {}, mode {}: {}", s.m, s.mode_periods, s.note);
        assert_eq!(s.periods, s.mode_periods, "{}", s.note);
        // The m + 1 mode lives above L̄ = m, the m − 1 mode below.
        assert_eq!(s.side, if s.mode_periods > s.m { 1 } else { -1 });
        if s.lbar >= 1.0 && s.lbar <= 5.0 {
            assert!(s.merged, "{}", s.note);
            assert!(s.energy_difference.unwrap() < 1e-9);
        } else {
            assert!(!s.merged);
        }
    }
    // The collapse at the top of the range is named by switching (η = 6).
    let last = d.critical.last().unwrap();
    assert_eq!(
        (last.lbar_cr, last.from_branch, last.to_branch),
        (5.0, 4, 6)
    );
    assert_eq!(g.branch_above(5), Some(6));
}
