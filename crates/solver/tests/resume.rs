//! A Newton run kept at one tolerance and resumed with other options
//! ([`rodloop_solver::solve_newton_keeping`], [`rodloop_solver::NewtonRun::resume`]) gives
//! what a run from the start with those options gives, bit for bit: the state and the whole
//! convergence report.

use rodloop_solver::{
    solve, solve_newton_keeping, solve_newton_keeping_until, Equilibrium, Globalization,
    SolveOptions, SolverError, Stall, StartShape, Stiffness, SurfaceModel,
};

/// A two-segment rod solved at 24 cells, its curvature resampled to 48: the start of a
/// refinement, which Newton's method takes several iterations to converge from.
fn refinement_start(d1: f64) -> (SurfaceModel, Vec<f64>) {
    let st = Stiffness::Tanh {
        d0: 1.0,
        d1,
        s0: 0.3,
        s1: 0.8,
        gamma: 40.0,
    };
    let coarse = SurfaceModel::new(1.0, 1.6, 24, &st).unwrap();
    let k0 = StartShape::Euler { l: 2 }.gauss_values(&coarse).unwrap();
    let eq = solve(&coarse, &k0, &SolveOptions::default()).unwrap();
    let fine = SurfaceModel::new(1.0, 1.6, 48, &st).unwrap();
    (fine, eq.resample(48).unwrap())
}

fn newton(tolerance: f64, max_iterations: usize) -> SolveOptions {
    SolveOptions {
        globalization: Globalization::Newton,
        tolerance,
        max_iterations,
        ..SolveOptions::default()
    }
}

/// Equal states and reports, or equal errors.
fn assert_same(a: &Result<Equilibrium, SolverError>, b: &Result<Equilibrium, SolverError>) {
    match (a, b) {
        (Ok(a), Ok(b)) => {
            assert_eq!(a.state(), b.state());
            assert_eq!(a.report(), b.report());
            assert_eq!(a.model(), b.model());
        }
        (Err(a), Err(b)) => assert_eq!(a.to_string(), b.to_string()),
        (a, b) => panic!("{a:?} vs {b:?}"),
    }
}

/// A run to `1e-12` kept at `1e-6`, resumed to `1e-6`, `1e-7` and `1e-9`: each time the
/// result of a fresh run to that tolerance.
#[test]
fn resumed_run_equals_a_fresh_run() {
    let (model, start) = refinement_start(0.1);
    let (tight, kept) = solve_newton_keeping(&model, &start, &newton(1e-12, 30), 1e-6);
    let tight = tight.unwrap();
    assert!(
        tight.report().iterations >= 3,
        "{:?}",
        tight.report().history
    );
    let kept = kept.unwrap();
    assert!(kept.iterations() >= 1 && kept.iterations() < tight.report().iterations);
    for tol in [1e-6, 1e-7, 1e-9] {
        let fresh = solve(&model, &start, &newton(tol, 60));
        let resumed = kept.clone().resume(&newton(tol, 60)).unwrap();
        assert!(fresh.is_ok());
        assert_same(&resumed, &fresh);
    }
    // The tight run itself is the fresh run to its tolerance.
    assert_same(&Ok(tight), &solve(&model, &start, &newton(1e-12, 30)));
}

/// A run stopped by its iteration limit before the kept tolerance is kept at its last pass
/// and goes on from there; a resumed run with a limit it has passed fails as a fresh one
/// does.
#[test]
fn run_stopped_early_goes_on_from_its_last_pass() {
    let (model, start) = refinement_start(0.1);
    let (short, kept) = solve_newton_keeping(&model, &start, &newton(1e-12, 1), 1e-8);
    assert!(matches!(short, Err(SolverError::NewtonNotConverged { .. })));
    let kept = kept.unwrap();
    assert_eq!(kept.iterations(), 1);
    let fresh = solve(&model, &start, &newton(1e-8, 60));
    assert!(fresh.as_ref().unwrap().report().iterations > 1);
    assert_same(&kept.clone().resume(&newton(1e-8, 60)).unwrap(), &fresh);
    // A limit of exactly the iterations done stops where the fresh run stops.
    assert_same(
        &kept.clone().resume(&newton(1e-8, 1)).unwrap(),
        &solve(&model, &start, &newton(1e-8, 1)),
    );
}

/// Options that could have stopped the run before its kept pass are refused: a looser
/// tolerance than the one it was kept for, fewer iterations than it has done, another
/// line-search limit.
#[test]
fn resume_refuses_options_that_change_the_passes_before() {
    let (model, start) = refinement_start(0.1);
    let (_, kept) = solve_newton_keeping(&model, &start, &newton(1e-12, 2), 1e-8);
    let kept = kept.unwrap();
    assert_eq!(kept.iterations(), 2);
    assert!(kept.clone().resume(&newton(1e-7, 60)).is_none());
    assert!(kept.clone().resume(&newton(1e-8, 1)).is_none());
    let other = SolveOptions {
        max_backtracks: 10,
        ..newton(1e-8, 60)
    };
    assert!(kept.clone().resume(&other).is_none());
    assert!(kept.resume(&newton(1e-9, 60)).is_some());
}

/// A run resumed one pass at a time ([`rodloop_solver::NewtonRun::resume_keeping`], each
/// time from the run kept where the last one stopped) is the fresh run: the same result at
/// every limit, and residuals ([`rodloop_solver::NewtonRun::residuals`]) that are the fresh
/// run's history up to its pass.
#[test]
fn run_resumed_pass_by_pass_equals_a_fresh_run() {
    let (model, start) = refinement_start(0.1);
    let tol = 1e-10;
    let (mut result, mut kept) = solve_newton_keeping(&model, &start, &newton(tol, 1), tol);
    let mut limit = 1;
    while matches!(result, Err(SolverError::NewtonNotConverged { .. })) {
        let run = kept.take().expect("a run stopped by its limit is kept");
        assert_eq!(run.iterations(), limit);
        let fresh = solve(&model, &start, &newton(tol, 60)).unwrap();
        assert_eq!(run.residuals(), fresh.report().history[..=limit].to_vec());
        limit += 1;
        assert!(limit < 60, "no convergence");
        (result, kept) = run.resume_keeping(&newton(tol, limit)).unwrap();
        assert_same(&result, &solve(&model, &start, &newton(tol, limit)));
    }
    assert!(limit > 2, "converged after {limit} passes");
    assert!(result.is_ok());
}

/// A stall rule ([`Stall`]) ends a run unconverged at the first pass where its last accepted
/// steps are all short enough, as a run limited to that pass ends; a rule no step meets
/// leaves the run as it is; the kept run of a stalled run, resumed with a larger limit,
/// stops at the same pass.
#[test]
fn a_stall_rule_ends_the_run_where_its_steps_meet_it() {
    let (model, start) = refinement_start(0.1);
    let fresh = solve(&model, &start, &newton(1e-10, 60));
    let passes = fresh.as_ref().unwrap().report().iterations;
    assert!(passes >= 3, "{passes}");
    let never = Stall {
        passes: 1,
        max_step: 0.0,
    };
    let (run, _) =
        solve_newton_keeping_until(&model, &start, &newton(1e-10, 60), 1e-8, Some(never));
    assert_same(&run, &fresh);
    // Every step is at most a full step, and one step is not longer than itself: the rule
    // holds after the first pass.
    let always = Stall {
        passes: 1,
        max_step: 1.0,
    };
    let (run, kept) =
        solve_newton_keeping_until(&model, &start, &newton(1e-10, 60), 1e-8, Some(always));
    assert!(matches!(
        run,
        Err(SolverError::NewtonNotConverged { iterations: 1, .. })
    ));
    assert_same(&run, &solve(&model, &start, &newton(1e-10, 1)));
    let resumed = kept.unwrap().resume(&newton(1e-8, 60)).unwrap();
    assert_same(&resumed, &solve(&model, &start, &newton(1e-8, 1)));
    // Where the steps lengthen over the stretch, the rule does not hold: the first two
    // steps of the run, if the second is the longer, let it go on.
    let steps = &fresh.as_ref().unwrap().report().step_lengths;
    let two = Stall {
        passes: 2,
        max_step: 1.0,
    };
    let (run, _) = solve_newton_keeping_until(&model, &start, &newton(1e-10, 60), 1e-8, Some(two));
    if steps[1] > steps[0] {
        assert!(!matches!(
            run,
            Err(SolverError::NewtonNotConverged { iterations: 2, .. })
        ));
    } else {
        assert_same(&run, &solve(&model, &start, &newton(1e-10, 2)));
    }
}
