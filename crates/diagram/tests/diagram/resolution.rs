//! Coarse and fine tracing resolutions give the same diagram.

use rodloop_diagram::{compute, DiagramOptions, Label};
use rodloop_solver::Accuracy;

use crate::common::{exact_diagram, fast_diagram};

fn labels_at(d: &rodloop_diagram::NumericDiagram, lbar: f64) -> Vec<(u32, Label)> {
    d.branches
        .iter()
        .filter(|b| b.covers(lbar))
        .map(|b| {
            let (_, l) = d.label_near(b.eta, lbar).unwrap();
            (b.branch, l)
        })
        .collect()
}

#[test]
fn coarse_and_fine_tracing_give_the_same_labels_and_critical_lengths() {
    let coarse = DiagramOptions {
        trace_cells_per_period: Some(6),
        ..DiagramOptions::with_accuracy(Accuracy::Fast)
    };
    let fine = DiagramOptions {
        trace_cells_per_period: Some(40),
        ..DiagramOptions::with_accuracy(Accuracy::Fast)
    };
    let dc = compute(&coarse, &mut (), &mut |_| {}).unwrap();
    let df = compute(&fine, &mut (), &mut |_| {}).unwrap();
    let d0 = fast_diagram();
    for d in [&dc, &df] {
        assert!(d.warnings.is_empty(), "{:#?}", d.warnings);
        assert_eq!(d.critical.len(), 9);
        for (a, b) in d.critical.iter().zip(&d0.critical) {
            assert_eq!(
                (a.kind, a.from_branch, a.to_branch),
                (b.kind, b.from_branch, b.to_branch)
            );
            // The located crossings do not depend on the tracing resolution beyond the
            // Newton tolerance of the re-solved equilibria.
            assert!(
                (a.lbar_cr - b.lbar_cr).abs() <= 1e-10,
                "{} vs {}",
                a.lbar_cr,
                b.lbar_cr
            );
        }
    }
    // Labels at lengths away from the critical ones.
    let crit: Vec<f64> = exact_diagram().critical.iter().map(|c| c.lbar_cr).collect();
    let mut l = 1.05;
    while l < 4.99 {
        if crit.iter().all(|c| (c - l).abs() > 0.1) {
            assert_eq!(labels_at(&dc, l), labels_at(&df, l), "L̄ = {l}");
        }
        l += 0.1;
    }
    // Tracing resolutions differ as asked.
    for (b, c) in df.branches.iter().zip(&dc.branches) {
        assert!(b.cells > 4 * c.cells);
    }
}
