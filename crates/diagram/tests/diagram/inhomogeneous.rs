//! A two-segment rod (Eq. 51, D1/D0 = 0.5, s0 = 0.3, s1 = 0.8; γ = 20 to keep it cheap).

use rodloop_diagram::{compute, BranchEnd, CriticalKind, DiagramOptions, Label};
use rodloop_solver::{Accuracy, Stiffness};

#[test]
fn tanh_profile_diagram_runs_through() {
    let opts = DiagramOptions {
        stiffness: Stiffness::Tanh {
            d0: 1.0,
            d1: 0.5,
            s0: 0.3,
            s1: 0.8,
            gamma: 20.0,
        },
        ..DiagramOptions::with_accuracy(Accuracy::Fast)
    };
    let d = compute(&opts, &mut (), &mut |_| {}).unwrap();
    println!("{:#?}", d.warnings);
    // Every paper branch 1..5 is there (as one or more families and sheets).
    let mut numbers: Vec<u32> = d.branches.iter().map(|b| b.branch).collect();
    numbers.sort_unstable();
    numbers.dedup();
    assert_eq!(numbers, vec![1, 2, 3, 4, 5]);
    // Mean stiffness 0.75 D0: a great circle at L̄ = m has E R/(π D0) = 0.75 m.
    let collapses: Vec<_> = d
        .critical
        .iter()
        .filter(|c| c.kind == CriticalKind::Collapse)
        .collect();
    assert_eq!(collapses.len(), 5);
    for c in &collapses {
        assert!((c.energy - 0.75 * c.lbar_cr).abs() < 1e-6, "{c:?}");
    }
    let crossings: Vec<_> = d
        .critical
        .iter()
        .filter(|c| c.kind == CriticalKind::Crossing)
        .collect();
    assert!(crossings.len() >= 4, "{crossings:#?}");
    for w in d.critical.windows(2) {
        assert!(w[0].lbar_cr < w[1].lbar_cr);
    }
    for (b, labels) in d.branches.iter().zip(&d.labels) {
        for end in [&b.low_end, &b.high_end] {
            assert!(
                !matches!(end, BranchEnd::Failed { .. }),
                "branch {}: {end:?}",
                b.branch
            );
        }
        for (k, p) in b.points.iter().enumerate() {
            assert!(p.energy.is_finite() && p.energy > 0.0);
            // Energies are bounded below by the great-circle (normal) part and lie above
            // the geodesic part.
            assert!(p.energy >= 0.75 * p.value - 1e-6 && p.energy_g >= 0.0);
            assert!(p.energy_g < p.energy);
            assert_eq!(labels[k] == Label::Unstable, p.index > 0);
            // The slopes integrate to the energy differences (trapezoidal rule).
            // Near a fold or branch point E(L̄) has a square-root term: the trapezoidal
            // check applies away from such sheet ends.
            let turning =
                |e: &BranchEnd| matches!(e, BranchEnd::Fold { .. } | BranchEnd::BranchPoint { .. });
            let near_turn = (k <= 2 && turning(&b.low_end))
                || (k + 2 >= b.points.len() && turning(&b.high_end));
            if k > 0 && !near_turn {
                let q = &b.points[k - 1];
                let h = p.value - q.value;
                let de = p.energy - q.energy;
                let trap = 0.5 * h * (p.slope + q.slope);
                assert!(
                    (de - trap).abs() <= 0.05 * h * (p.slope.abs() + q.slope.abs()) + 1e-4,
                    "branch {} at {}: {de} vs {trap}",
                    b.branch,
                    p.value
                );
            }
        }
    }
    // There is a stable state at every length of the range away from the critical ones.
    let mut l = 1.02;
    while l < 5.0 {
        if d.critical.iter().all(|c| (c.lbar_cr - l).abs() > 0.05) {
            let lowest = d.lowest_at(l);
            assert_eq!(lowest.len(), 1, "L̄ = {l}");
        }
        l += 0.1;
    }
}
