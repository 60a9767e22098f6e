//! Resuming from serialised branches gives identical results.

use rodloop_diagram::{
    assemble, compute, compute_branch, DiagramOptions, Progress, Resume, TracedBranch,
};
use rodloop_solver::Accuracy;

use crate::common::fast_diagram;

fn options() -> DiagramOptions {
    DiagramOptions::with_accuracy(Accuracy::Fast)
}

#[test]
fn json_round_trip_of_traced_branches_is_exact() {
    let d = fast_diagram();
    for b in &d.branches {
        let json = serde_json::to_string(b).unwrap();
        let back: TracedBranch = serde_json::from_str(&json).unwrap();
        // (No Debug output on failure: a branch holds thousands of numbers.)
        assert!(
            back == *b,
            "branch {} changed in the JSON round trip",
            b.branch
        );
    }
}

#[test]
fn resume_from_all_or_some_branches_reproduces_the_diagram() {
    let opts = options();
    let d = fast_diagram();
    let saved: Vec<TracedBranch> = d
        .branches
        .iter()
        .map(|b| serde_json::from_str(&serde_json::to_string(b).unwrap()).unwrap())
        .collect();
    // All branches resumed: nothing is traced again.
    let mut events = Vec::new();
    let r = compute(&opts, &mut Resume(&saved), &mut |p| events.push(p)).unwrap();
    assert!(!events
        .iter()
        .any(|e| matches!(e, Progress::BranchStarted { .. })));
    assert_eq!(
        events
            .iter()
            .filter(|e| matches!(e, Progress::BranchResumed { .. }))
            .count(),
        5
    );
    assert_eq!(r.critical, d.critical);
    assert_eq!(r.labels, d.labels);
    assert!(r.branches == d.branches, "resumed branches differ");
    assert_eq!(r.great_circles, d.great_circles);
    // Two branches resumed, the others traced again (deterministically).
    let partial = vec![saved[1].clone(), saved[3].clone()];
    let r = compute(&opts, &mut Resume(&partial), &mut |_| {}).unwrap();
    assert_eq!(r.critical, d.critical);
    assert_eq!(r.labels, d.labels);
    for (a, b) in r.branches.iter().zip(&d.branches) {
        assert!(
            a.points == b.points,
            "branch {} traced again differs",
            a.branch
        );
    }
}

#[test]
fn compute_branch_then_assemble_equals_compute() {
    let opts = options();
    let d = fast_diagram();
    let branches: Vec<TracedBranch> = opts
        .etas()
        .into_iter()
        .map(|eta| compute_branch(&opts, eta, &mut |_| {}).unwrap())
        .collect();
    let r = assemble(&opts, branches, &mut |_| {}).unwrap();
    assert_eq!(r.critical, d.critical);
    assert_eq!(r.labels, d.labels);
}

#[test]
fn branches_traced_with_other_options_are_not_reused() {
    let d = fast_diagram();
    let opts = DiagramOptions {
        end_distance: 2e-5,
        ..options()
    };
    let mut rejected = 0;
    let r = compute(&opts, &mut Resume(&d.branches), &mut |p| {
        if matches!(p, Progress::BranchResumeRejected { .. }) {
            rejected += 1;
        }
    })
    .unwrap();
    assert_eq!(rejected, 5);
    for b in &r.branches {
        if let rodloop_diagram::BranchEnd::GreatCircle { distance, .. } = b.low_end {
            assert!((distance - 2e-5).abs() < 1e-12);
        }
    }
}
