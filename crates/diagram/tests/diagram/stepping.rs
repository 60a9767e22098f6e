//! Tracing with the stepping continuation: exact energies reproduced, the generic march in
//! another parameter (`d1` at fixed `L̄`), and the per-branch hook of `compute`.

use rodloop_diagram::{
    compute, compute_branch, march, BranchHook, DiagramError, DiagramOptions, FoldPolicy,
    MarchSettings, MarchStop, Origin, PointSource, Progress, TracedBranch,
};
use rodloop_solver::{
    solve, Accuracy, Confinement, Param, ParamProblem, SolveOptions, StartShape, Stiffness,
    SurfaceModel,
};

use crate::common::fast_diagram;

#[test]
fn a_branch_traced_with_the_stepper_has_the_exact_energies_within_its_estimates() {
    let opts = DiagramOptions::default();
    for eta in [2, 4] {
        let b = compute_branch(&opts, eta, &mut |_| {}).unwrap();
        let marched = b
            .points
            .iter()
            .filter(|p| p.source == PointSource::Continuation)
            .count();
        assert!(
            marched >= 8,
            "eta = {eta}: only {marched} continuation states"
        );
        // Both ends reach their great circles (η ± 1).
        assert_eq!(b.low_end.great_circle(), Some(eta - 1));
        assert_eq!(b.high_end.great_circle(), Some(eta + 1));
        for p in &b.points {
            let exact = rodloop_exact::paper_branch_loop(eta, p.value)
                .unwrap()
                .energy()
                .unwrap();
            let est = p.energy_error.expect("an error estimate");
            let err = (p.energy - exact).abs();
            assert!(
                err <= est + 1e-12,
                "eta = {eta} at L̄ = {}: error {err:e} above the estimate {est:e}",
                p.value
            );
            assert!(err <= 5e-6 * exact, "error {err:e} at L̄ = {}", p.value);
        }
    }
}

/// Branch 1 (η = 2) of the two-segment rod of Eq. (51) at `L̄ = 1.3`, solved from the Euler
/// curve at `D1/D0 = d1`.
fn two_segment_state(d1: f64, cells: usize) -> (SurfaceModel, Vec<f64>) {
    let stiffness = Stiffness::Tanh {
        d0: 1.0,
        d1,
        s0: 0.3,
        s1: 0.8,
        gamma: 20.0,
    };
    let model = SurfaceModel::new(1.0, 1.3, cells, &stiffness).unwrap();
    let start = StartShape::Euler { l: 2 }.gauss_values(&model).unwrap();
    let eq = solve(&model, &start, &SolveOptions::default()).unwrap();
    (eq.model().clone(), eq.state())
}

#[test]
fn the_same_march_continues_in_d1_at_fixed_length() {
    let cells = 96;
    let (model, z0) = two_segment_state(0.5, cells);
    let problem = ParamProblem::new(model.clone(), Param::D1).unwrap();
    let shape = model.n_kappa();
    let settings = MarchSettings {
        limit: 0.3,
        ds: 0.02,
        ds_min: 1e-6,
        ds_max: 0.1,
        max_steps: 200,
        tol: 1e-10,
        locate_tol: 1e-8,
        scaled: shape,
        scale: 1.0 / (shape as f64).sqrt(),
        folds: FoldPolicy::Stop,
        detect_branch_points: false,
        index_tolerance: 1e-6,
        track_index: true,
        hermite_location: false,
        progress_every: 5,
        far_limit: None,
        circles: Vec::new(),
        circle_distance: 0.05,
    };
    let mut calls = 0;
    let run = march(&problem, &z0, 0.5, &settings, &mut |_, _| calls += 1).unwrap();
    assert_eq!(run.stop, MarchStop::Reached);
    assert!(calls >= 1 && run.steps >= 2);
    let last = run.points.last().unwrap();
    assert!((last.value - 0.3).abs() < 1e-12);
    // Softening the second segment lowers the energy monotonically (dE/d(D1) = ½∫ ∂D/∂D1 κ² > 0).
    let energies: Vec<f64> = run
        .points
        .iter()
        .map(|p| Confinement::energy(&problem.model_at(p.value).unwrap(), &p.x).unwrap())
        .collect();
    assert!(energies.windows(2).all(|w| w[1] < w[0]), "{energies:?}");
    // The end of the march is the loop solved directly at D1/D0 = 0.3.
    let (direct, zd) = two_segment_state(0.3, cells);
    let e_direct = Confinement::energy(&direct, &zd).unwrap();
    let e_march = energies[energies.len() - 1];
    assert!(
        (e_march - e_direct).abs() <= 1e-9 * e_direct,
        "{e_march} vs {e_direct}"
    );
}

/// A hook that supplies one branch and records every call.
struct Recorder {
    supply: TracedBranch,
    asked: Vec<u32>,
    finished: Vec<(u32, Origin)>,
    fail: bool,
}

impl BranchHook for Recorder {
    fn resume(&mut self, eta: u32) -> Option<TracedBranch> {
        self.asked.push(eta);
        (eta == self.supply.eta).then(|| self.supply.clone())
    }

    fn finished(
        &mut self,
        branch: &TracedBranch,
        origin: Origin,
    ) -> Result<(), rodloop_diagram::BoxError> {
        self.finished.push((branch.eta, origin));
        if self.fail && origin == Origin::Traced {
            return Err("disk full".into());
        }
        Ok(())
    }
}

#[test]
fn the_hook_sees_every_branch_once_and_a_resumed_branch_is_not_traced() {
    let opts = DiagramOptions::with_accuracy(Accuracy::Fast);
    let reference = fast_diagram();
    let supplied = reference.branch_by_eta(3).unwrap().clone();
    let mut hook = Recorder {
        supply: supplied.clone(),
        asked: Vec::new(),
        finished: Vec::new(),
        fail: false,
    };
    let mut started = Vec::new();
    let d = compute(&opts, &mut hook, &mut |p| {
        if let Progress::BranchStarted { eta, .. } = p {
            started.push(eta)
        }
    })
    .unwrap();
    let etas = opts.etas();
    assert_eq!(hook.asked, etas);
    let mut seen: Vec<u32> = hook.finished.iter().map(|f| f.0).collect();
    seen.sort_unstable();
    assert_eq!(seen, etas, "one call per branch");
    for (eta, origin) in &hook.finished {
        let want = if *eta == 3 {
            Origin::Resumed
        } else {
            Origin::Traced
        };
        assert_eq!(*origin, want, "eta = {eta}");
    }
    assert!(!started.contains(&3), "the resumed branch was traced again");
    assert_eq!(started.len(), etas.len() - 1);
    assert!(d.branch_by_eta(3).unwrap() == &supplied);
    assert_eq!(d.critical, reference.critical);
}

#[test]
fn a_failing_hook_fails_compute() {
    let opts = DiagramOptions {
        only_branches: Some(vec![2]),
        lbar_min: 1.0,
        lbar_max: 1.5,
        ..DiagramOptions::with_accuracy(Accuracy::Fast)
    };
    let mut hook = Recorder {
        supply: fast_diagram().branch_by_eta(3).unwrap().clone(),
        asked: Vec::new(),
        finished: Vec::new(),
        fail: true,
    };
    let err = compute(&opts, &mut hook, &mut |_| {}).unwrap_err();
    assert!(matches!(err, DiagramError::Hook(_)), "{err}");
    assert!(err.to_string().contains("disk full"));
    assert_eq!(hook.finished.len(), 1);
}

#[test]
fn only_lbar_makes_a_diagram() {
    let opts = DiagramOptions {
        param: Param::D1,
        ..DiagramOptions::default()
    };
    assert!(matches!(
        opts.validate(),
        Err(DiagramError::InvalidOptions(_))
    ));
}
