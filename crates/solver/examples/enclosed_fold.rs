//! The fold of branch 1 of the paper's two-segment rod inside the ball (`D1/D0 = 0.5`,
//! Sec. 5; the scene `data/scenes/inhomogeneous-d1-0.5-enclosed.toml`), followed by
//! pseudo-arclength continuation in `L̄` at the contact set of the state at the start:
//!
//! ```sh
//! cargo run --release -p rodloop-solver --example enclosed_fold -- 2.25 128
//! ```
//!
//! Arguments: the start length `L̄` and the cells `N` of the enclosed state (solved from
//! the surface loop as `rodloop solve` does). It prints each located fold and each end of the
//! piece (a contact impulse or a free gap reaching zero, where the contact set changes), with
//! the located point's slack ([`contact_slack`]). The step is at most `0.02` in the
//! continuation's norm of `(z, L̄)`: with steps ten times longer, the corrector lands on
//! other parts of the curve next to the point where the lowest eigenvalue nearly vanishes
//! and reports folds that shorter steps do not find. The Jacobian is factored in `O(N)`
//! (`rodloop_solver::enclosed::lifted_factor`): a run at `N = 128` takes about 2 s.

use nalgebra::DVector;
use rodloop_continuation::{Continuation, PseudoArclength, SpecialKind};
use rodloop_solver::enclosed::arclength::{contact_set_of, contact_slack};
use rodloop_solver::enclosed::{solve_branch, EnclosedOptions, SurfaceSource};
use rodloop_solver::{
    solve_robust, Accuracy, Param, ParamProblem, SolveOptions, StartShape, Stiffness,
};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let lbar: f64 = args.first().map_or(Ok(2.25), |a| a.parse())?;
    let cells: usize = args.get(1).map_or(Ok(128), |a| a.parse())?;
    let stiffness = Stiffness::paper_sec5(0.5);
    let (surface, _) = solve_robust(
        1.0,
        lbar,
        &stiffness,
        &StartShape::Euler { l: 2 },
        Accuracy::Default,
        Some(2),
        &SolveOptions::default(),
    )?;
    let source = SurfaceSource::Numeric(Box::new(surface.equilibrium));
    let solved = solve_branch(
        1.0,
        lbar,
        &stiffness,
        &source,
        cells,
        &EnclosedOptions::default(),
    )?;
    let state = &solved.fine;
    let model = state
        .model
        .clone()
        .with_contact_set(contact_set_of(state)?)?;
    let problem = ParamProblem::new(model, Param::Lbar)?;
    let settings = PseudoArclength::new()
        .with_ds(0.01)?
        .with_ds_bounds(1e-7, 0.02)?
        .with_tol(1e-9)?
        .with_range(lbar - 0.05, lbar + 0.1)?
        .with_max_steps(400)?;
    let slack = |x: &DVector<f64>, p: f64| {
        problem
            .model_at(p)
            .and_then(|m| contact_slack(&m, x.as_slice()))
            .unwrap_or(f64::NAN)
    };
    let start = std::time::Instant::now();
    let branch = Continuation::new(&problem, settings)
        .with_event("contact slack", slack)
        .run(&DVector::from_column_slice(&state.z), lbar)?;
    println!(
        "N = {cells}: start index {}, {} points, {:.1} s, {:?}",
        state.index(1e-6)?,
        branch.points.len(),
        start.elapsed().as_secs_f64(),
        branch.stop
    );
    for s in &branch.special {
        let what = match s.kind {
            SpecialKind::Fold => "fold",
            SpecialKind::Event { .. } => "contact set changes",
            _ => continue,
        };
        println!(
            "  {what} at lbar = {:.10} (arclength bracket {:.1e}), slack {:.2e}",
            s.p,
            s.accuracy,
            slack(&s.x, s.p)
        );
    }
    Ok(())
}
