//! The default scene (uniform D, R = 1, 1 ≤ L̄ ≤ 5) at the default accuracy, against the
//! exact layer.

use rodloop_diagram::{BranchEnd, CriticalKind, Label};

use crate::common::{default_diagram, exact_diagram, exact_energy, fast_diagram};

#[test]
fn critical_lengths_match_the_exact_layer() {
    let d = default_diagram();
    let exact = &exact_diagram().critical;
    assert_eq!(d.critical.len(), exact.len(), "{:#?}", d.critical);
    assert_eq!(d.critical.len(), 9);
    for (c, e) in d.critical.iter().zip(exact) {
        let err = (c.lbar_cr - e.lbar_cr).abs();
        println!(
            "L{}cr = {:.12} ({}) exact {:.12}: error {err:.1e}, estimate {:.1e}",
            c.index, c.lbar_cr, c.kind, e.lbar_cr, c.error_estimate
        );
        assert_eq!(c.index, e.index);
        assert_eq!(c.kind.to_string(), e.kind.to_string());
        assert_eq!((c.from_branch, c.to_branch), (e.from_branch, e.to_branch));
        assert!(err <= 1e-6, "L{}cr off by {err:e}", c.index);
        assert!(
            err <= c.error_estimate.max(1e-15),
            "L{}cr: error {err:e} exceeds its estimate {:e}",
            c.index,
            c.error_estimate
        );
        assert!(
            (c.energy - e.energy).abs() <= 1e-6 * e.energy,
            "energy at L{}cr",
            c.index
        );
        if c.kind == CriticalKind::Collapse {
            assert_eq!(c.lbar_cr, c.lbar_cr.round());
            assert_eq!(c.error_estimate, 0.0);
        }
    }
}

#[test]
fn fast_critical_lengths_agree_within_their_estimates() {
    let d = fast_diagram();
    let exact = &exact_diagram().critical;
    assert_eq!(d.critical.len(), exact.len());
    for (c, e) in d.critical.iter().zip(exact) {
        let err = (c.lbar_cr - e.lbar_cr).abs();
        assert!(
            err <= c.error_estimate.max(1e-15),
            "L{}cr {err:e} > {:e}",
            c.index,
            c.error_estimate
        );
        assert!(err <= 1e-5);
        assert_eq!((c.from_branch, c.to_branch), (e.from_branch, e.to_branch));
    }
}

#[test]
fn paper_stable_branches_are_labelled_stable() {
    let d = default_diagram();
    // (branch, L̄, expected label); branch numbers are the paper's (η = 2 → 1, η = 1 → 2).
    let cases = [
        (1, 1.2, Label::Stable),
        (2, 1.7, Label::Stable),
        (3, 2.2, Label::Stable),
        (1, 2.8, Label::Stable),
        (4, 3.2, Label::Stable),
        (3, 3.8, Label::Stable),
        (5, 4.2, Label::Stable),
        (4, 4.8, Label::Stable),
        (2, 1.2, Label::Metastable),
        (1, 1.7, Label::Metastable),
        (1, 2.2, Label::Metastable),
        (3, 2.8, Label::Metastable),
        (3, 3.2, Label::Metastable),
        (4, 3.8, Label::Metastable),
    ];
    for (branch, lbar, want) in cases {
        let eta = rodloop_exact::eta_of_branch(branch);
        let (at, label) = d.label_near(eta, lbar).expect("branch traced");
        assert!(
            (at - lbar).abs() < 0.15,
            "no state of branch {branch} near {lbar}"
        );
        assert_eq!(label, want, "branch {branch} at L̄ = {at}");
    }
    // Every state of the default scene is a local minimum.
    for b in &d.branches {
        assert!(b.points.iter().all(|p| p.index == 0), "branch {}", b.branch);
    }
}

#[test]
fn labels_agree_with_the_exact_lowest_branch() {
    let d = default_diagram();
    let crit: Vec<f64> = exact_diagram().critical.iter().map(|c| c.lbar_cr).collect();
    for (b, labels) in d.branches.iter().zip(&d.labels) {
        for (p, &l) in b.points.iter().zip(labels) {
            // Lowest exact branch at this length (skip lengths at a critical value).
            if crit.iter().any(|c| (c - p.value).abs() < 1e-6) {
                continue;
            }
            let lowest = (1..=5)
                .filter(|&e| rodloop_exact::paper_branch_loop(e, p.value).is_ok())
                .min_by(|&a, &c| exact_energy(a, p.value).total_cmp(&exact_energy(c, p.value)))
                .unwrap();
            let want = if lowest == b.eta {
                Label::Stable
            } else {
                Label::Metastable
            };
            assert_eq!(l, want, "branch {} at L̄ = {}", b.branch, p.value);
        }
    }
}

#[test]
fn traced_energies_forces_and_slopes_match_the_exact_loops() {
    let d = default_diagram();
    for b in &d.branches {
        for p in &b.points {
            let ex = rodloop_exact::paper_branch_loop(b.eta, p.value).unwrap();
            let e = ex.energy().unwrap();
            let err = (p.energy - e).abs();
            let est = p.energy_error.expect("error estimate");
            assert!(
                err <= est + 1e-12,
                "branch {} at {}: error {err:e} > estimate {est:e}",
                b.branch,
                p.value
            );
            assert!(
                err <= 5e-6 * e,
                "branch {} at {}: {err:e}",
                b.branch,
                p.value
            );
            assert!((p.energy_g - ex.energy_g().unwrap()).abs() <= 5e-6 * e);
            let (lo, hi) = ex.lambda_range();
            let scale = lo.abs().max(hi.abs()).max(1.0);
            assert!(
                (p.lambda_min - lo).abs() <= 1e-3 * scale,
                "λ_min of {} at {}",
                b.branch,
                p.value
            );
            assert!(
                (p.lambda_max - hi).abs() <= 1e-3 * scale,
                "λ_max of {} at {}",
                b.branch,
                p.value
            );
            // dE/dL̄ from the multiplier against a difference quotient of the exact energies
            // (away from the ends, where the exact branch is not resolved by ±h).
            let h = 1e-4;
            let (e0, e1) = (f64::from(b.eta) - 1.0, f64::from(b.eta) + 1.0);
            if p.value - h > e0.max(0.0) + 1e-3 && p.value + h < e1 - 1e-3 {
                let fd = (exact_energy(b.eta, p.value + h) - exact_energy(b.eta, p.value - h))
                    / (2.0 * h);
                assert!(
                    (p.slope - fd).abs() <= 1e-3 * fd.abs().max(1.0),
                    "slope of {} at {}: {} vs {fd}",
                    b.branch,
                    p.value,
                    p.slope
                );
            }
        }
    }
}

#[test]
fn every_branch_end_is_reached_and_explained() {
    let d = default_diagram();
    assert_eq!(
        d.branches.iter().map(|b| b.eta).collect::<Vec<_>>(),
        vec![1, 2, 3, 4, 5]
    );
    for b in &d.branches {
        let e = f64::from(b.eta);
        for (end, stop, lbar) in [
            (&b.low_end, &b.stop_low, b.points[0].value),
            (&b.high_end, &b.stop_high, b.points.last().unwrap().value),
        ] {
            println!("branch {} (η = {}): {stop}", b.branch, b.eta);
            assert!(!stop.is_empty());
            match end {
                BranchEnd::GreatCircle {
                    m,
                    distance,
                    value: at,
                } => {
                    assert!(*m == b.eta - 1 || *m == b.eta + 1);
                    assert!(*distance <= 1e-4 && *distance > 0.0);
                    assert_eq!(*at, lbar);
                    assert!((lbar - f64::from(*m)).abs() <= 1e-4);
                    assert!(stop.contains("great circle"));
                }
                BranchEnd::Range { value: at } => {
                    assert!(*at == 1.0 || *at == 5.0, "range end at {at}");
                    assert_eq!(*at, lbar);
                    // Only η = 1 (starts at L̄ → 0) and η = 5 (ends at 6) meet the range ends.
                    assert!((b.eta == 1 && *at == 1.0) || (b.eta == 5 && *at == 5.0));
                }
                BranchEnd::Failed { reason, .. } => panic!("branch {} failed: {reason}", b.branch),
                BranchEnd::Fold { .. } | BranchEnd::BranchPoint { .. } => {
                    panic!("a uniform rod's branch {} has no fold: {end:?}", b.branch)
                }
            }
        }
        assert!(b.points.windows(2).all(|w| w[0].value < w[1].value));
        assert!(
            b.points[0].value >= (e - 1.0).max(1.0)
                && b.points.last().unwrap().value <= (e + 1.0).min(5.0)
        );
    }
    assert!(d.warnings.is_empty(), "{:#?}", d.warnings);
}

#[test]
fn outputs_are_finite_and_serialisable() {
    let d = default_diagram();
    let rows = d.rows();
    assert_eq!(
        rows.len(),
        d.branches.iter().map(|b| b.points.len()).sum::<usize>()
    );
    for r in &rows {
        for v in [r.lbar, r.energy, r.energy_g, r.lambda_min, r.lambda_max] {
            assert!(v.is_finite(), "{r:?}");
        }
        assert!(r.energy_error.is_some_and(|e| e.is_finite() && e >= 0.0));
    }
    for c in &d.critical {
        assert!(c.lbar_cr.is_finite() && c.energy.is_finite() && c.error_estimate.is_finite());
        assert!(!c.note.is_empty());
    }
    let g = d.great_circles.as_ref().unwrap();
    for l in &g.loads {
        assert!(l.lambda_numeric.is_finite() && l.lambda_error.is_finite());
    }
    let opts = rodloop_diagram::DiagramOptions::default();
    let json = serde_json::to_string(&d.summary(&opts)).unwrap();
    assert!(
        json.len() < 200_000,
        "the summary holds no states ({} bytes)",
        json.len()
    );
    assert!(json.contains("\"critical\"") && json.contains("\"stop_low\""));
    let t = d.timings;
    assert!(t.total > 0.0 && t.tracing > 0.0 && t.total >= t.tracing);
}
