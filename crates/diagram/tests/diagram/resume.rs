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

/// Saves and supplies the families of a non-uniform rod, as the CLI's files do.
#[derive(Default)]
struct FamilyStore {
    saved: Vec<(u32, rodloop_diagram::families::Families)>,
    supply: Vec<(u32, rodloop_diagram::families::Families)>,
}

impl rodloop_diagram::BranchHook for FamilyStore {
    fn resume_families(&mut self, eta: u32) -> Option<rodloop_diagram::families::Families> {
        self.supply
            .iter()
            .find(|(e, _)| *e == eta)
            .map(|(_, f)| f.clone())
    }

    fn finished_families(
        &mut self,
        eta: u32,
        families: &rodloop_diagram::families::Families,
    ) -> Result<(), rodloop_diagram::BoxError> {
        // Through JSON, as the files are.
        let json = serde_json::to_string(families)?;
        self.saved.push((eta, serde_json::from_str(&json)?));
        Ok(())
    }
}

/// A two-segment rod (γ = 20, fast): resuming every branch's families, or all but one,
/// gives the same branches (whose ends are the special points), critical lengths, labels and warnings as the
/// fresh run; families traced with other options are re-traced.
#[test]
fn resumed_families_of_a_two_segment_rod_reproduce_the_diagram() {
    let opts = DiagramOptions {
        stiffness: rodloop_solver::Stiffness::Tanh {
            d0: 1.0,
            d1: 0.5,
            s0: 0.3,
            s1: 0.8,
            gamma: 20.0,
        },
        lbar_max: 3.0,
        ..options()
    };
    let mut store = FamilyStore::default();
    let fresh = compute(&opts, &mut store, &mut |_| {}).unwrap();
    assert!(!store.saved.is_empty());
    let same = |d: &rodloop_diagram::NumericDiagram| {
        // The same sheets and states (a branch traced again has its own timings).
        assert_eq!(d.branches.len(), fresh.branches.len());
        for (a, b) in d.branches.iter().zip(&fresh.branches) {
            assert!(
                a.points == b.points && a.low_end == b.low_end && a.high_end == b.high_end,
                "branch {} family {} sheet {} differs",
                a.branch,
                a.family,
                a.sheet
            );
        }
        assert_eq!(d.critical, fresh.critical);
        assert_eq!(d.labels, fresh.labels);
        assert_eq!(d.warnings, fresh.warnings);
    };
    for drop in [None, Some(store.saved[0].0)] {
        let mut again = FamilyStore {
            supply: store
                .saved
                .iter()
                .filter(|(e, _)| Some(*e) != drop)
                .cloned()
                .collect(),
            ..FamilyStore::default()
        };
        let mut traced = 0;
        let d = compute(&opts, &mut again, &mut |p| {
            if matches!(p, Progress::BranchStarted { .. }) {
                traced += 1;
            }
        })
        .unwrap();
        same(&d);
        assert_eq!(traced, usize::from(drop.is_some()));
    }
    // Other options: the supplied families are rejected and every branch is traced.
    let other = DiagramOptions {
        end_distance: opts.end_distance * 2.0,
        ..opts.clone()
    };
    let mut again = FamilyStore {
        supply: store.saved.clone(),
        ..FamilyStore::default()
    };
    let mut rejected = 0;
    compute(&other, &mut again, &mut |p| {
        if matches!(p, Progress::BranchResumeRejected { .. }) {
            rejected += 1;
        }
    })
    .unwrap();
    assert_eq!(rejected, store.saved.len());
}
