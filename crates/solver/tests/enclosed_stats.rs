//! The counters of enclosed Newton solves (`enclosed::stats`): a solve inside a scope is
//! counted under the stage named, with the iterations the state reports; a solve stopped by
//! the iteration cap is counted as failed there; a solve outside every scope is not counted.

mod common;

use rodloop_solver::enclosed::stats::{self, SolveStats, Stage};
use rodloop_solver::enclosed::{EnclosedOptions, EnclosedState};

/// The lifted-off figure-eight (branch 2) at `lbar`, `N = 32`.
fn figure_eight(lbar: f64) -> EnclosedState {
    common::enclosed_figure_eight(lbar, 32)
}

#[test]
fn solves_are_counted_by_stage_with_their_iterations_and_failures() {
    let a = figure_eight(1.40);
    let counters = SolveStats::new();
    let opts = EnclosedOptions::default();
    // Uncounted: no scope.
    a.step_to(1.405, &opts).unwrap();
    assert!(counters.snapshot().is_empty());
    let (ok, capped) = stats::scope(&counters, Stage::Trace, || {
        let ok = a.step_to(1.41, &opts).unwrap();
        // The min-function alone: with the hand-over, a failed solve also runs the
        // Fischer–Burmeister form, one more capped iteration.
        let one = EnclosedOptions {
            max_iterations: 1,
            hand_over: false,
            ..EnclosedOptions::default()
        };
        let capped = stats::stage(Stage::Creep, || a.step_to(1.45, &one));
        (ok, capped)
    });
    assert!(
        capped.is_err(),
        "one iteration from 0.05 away cannot converge"
    );
    let snap = counters.snapshot();
    assert_eq!(snap.len(), 2, "{snap:?}");
    let (s0, trace) = snap[0];
    let (s1, creep) = snap[1];
    assert_eq!((s0, s1), (Stage::Trace, Stage::Creep));
    assert_eq!(
        (trace.attempted, trace.converged, trace.failed()),
        (1, 1, 0)
    );
    assert_eq!(trace.iterations, ok.iterations as u64);
    assert!(trace.seconds > 0.0);
    assert_eq!(
        (creep.attempted, creep.converged, creep.failed_cap),
        (1, 0, 1)
    );
    assert_eq!(creep.failed_iterations, 1);
}

/// A capped solve that hands over to the Fischer–Burmeister form counts the iterations of
/// both forms, each capped (`EnclosedOptions::max_iterations` applies to each).
#[test]
fn a_capped_hand_over_counts_both_forms() {
    let a = figure_eight(1.40);
    let counters = SolveStats::new();
    let one = EnclosedOptions {
        max_iterations: 1,
        ..EnclosedOptions::default()
    };
    assert!(one.hand_over);
    let capped = stats::scope(&counters, Stage::Creep, || a.step_to(1.45, &one));
    assert!(capped.is_err(), "one iteration per form from 0.05 away");
    let snap = counters.snapshot();
    assert_eq!(snap.len(), 1, "{snap:?}");
    let (stage, creep) = snap[0];
    assert_eq!(stage, Stage::Creep);
    assert_eq!((creep.attempted, creep.converged), (1, 0));
    assert_eq!(creep.failed_iterations, 2);
}
