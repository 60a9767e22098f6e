//! Continuation in L̄ through the `rodloop_continuation::Problem` implementation.

mod common;

use common::solve_uniform;
use rodloop_continuation::{Continuation, Problem, PseudoArclength, StopReason};
use rodloop_solver::{LbarProblem, SolveOptions, StartShape};

#[test]
fn continue_branch_eta2_from_1_2_to_1_5() {
    let eq = solve_uniform(2, 1.2, 120, &StartShape::Euler { l: 2 });
    let (problem, x0, p0) = LbarProblem::from_equilibrium(&eq);
    assert_eq!(problem.dim(), x0.len());
    let settings = PseudoArclength::new()
        .with_ds(0.5)
        .unwrap()
        .with_ds_bounds(1e-4, 4.0)
        .unwrap()
        .with_range(1.0, 1.5)
        .unwrap()
        .with_max_steps(200)
        .unwrap()
        .with_tol(1e-10)
        .unwrap();
    let branch = Continuation::new(&problem, settings).run(&x0, p0).unwrap();
    assert!(
        matches!(branch.stop, StopReason::LeftRange { boundary } if boundary == 1.5),
        "{:?}",
        branch.stop
    );
    assert!(branch.folds().next().is_none());
    let last = branch.points.last().unwrap();
    assert!((last.p - 1.5).abs() < 1e-12);
    let mut worst: f64 = 0.0;
    for pt in &branch.points {
        let model = problem.model_at(pt.p).unwrap();
        let n = model.n_kappa();
        let (e, _, _) = model.energy_normalized(&pt.x.as_slice()[..n]).unwrap();
        let exact = rodloop_exact::paper_branch_loop(2, pt.p)
            .unwrap()
            .energy()
            .unwrap();
        worst = worst.max((e - exact).abs() / exact);
    }
    println!(
        "{} points, worst energy error {worst:.2e}",
        branch.points.len()
    );
    assert!(branch.points.len() >= 3);
    assert!(worst < 1e-6);
    // The end point re-solved as an equilibrium has the exact forces too.
    let end = problem
        .equilibrium(&last.x, last.p, &SolveOptions::default())
        .unwrap();
    let ex = rodloop_exact::paper_branch_loop(2, 1.5).unwrap();
    let (lo, hi) = end.lambda_range();
    let (elo, ehi) = ex.lambda_range();
    assert!((lo - elo).abs() < 1e-4 * ehi && (hi - ehi).abs() < 1e-4 * ehi);
    assert_eq!(end.stability().unwrap().index, 0);
}
