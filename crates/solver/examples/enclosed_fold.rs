//! The fold of branch 1 of the paper's two-segment rod inside the ball (`D1/D0 = 0.5`,
//! Sec. 5; the scene `data/scenes/inhomogeneous-d1-0.5-enclosed.toml`), followed by
//! pseudo-arclength continuation in `L̄` across the changes of its contact set
//! ([`follow_contacts`]: one piece per contact set):
//!
//! ```sh
//! cargo run --release -p rodloop-solver --example enclosed_fold -- 2.25 128
//! ```
//!
//! Arguments: the start length `L̄` and the cells `N` of the enclosed state (solved from
//! the surface loop as `rodloop solve` does). It prints each piece (its contact nodes and the
//! `L̄` where it begins and ends: a contact impulse or a free gap reaching zero) and each fold
//! located on it, from `L̄ − 0.05` to `L̄ + 0.1`. The step is at most `0.02` in the
//! continuation's norm of `(z, L̄)`: with steps ten times longer, the corrector lands on
//! other parts of the curve next to the point where the lowest eigenvalue nearly vanishes
//! and reports folds that shorter steps do not find. The Jacobian is factored in `O(N)`
//! (`rodloop_solver::enclosed::lifted_factor`): a run at `N = 128` takes about 2 s, at
//! `N = 192` about 4 s.

use rodloop_continuation::PseudoArclength;
use rodloop_solver::enclosed::arclength::follow_contacts;
use rodloop_solver::enclosed::{solve_branch, EnclosedOptions, SurfaceSource};
use rodloop_solver::{solve_robust, Accuracy, Param, SolveOptions, StartShape, Stiffness};

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
    let settings = PseudoArclength::new()
        .with_ds(0.01)?
        .with_ds_bounds(1e-7, 0.02)?
        .with_tol(1e-9)?
        .with_range(lbar - 0.05, lbar + 0.1)?
        .with_max_steps(400)?;
    let start = std::time::Instant::now();
    let (pieces, end) = follow_contacts(state, Param::Lbar, &settings, 50)?;
    println!(
        "N = {cells}: start index {}, {} piece(s), {:.1} s, {end:?}",
        state.index(1e-6)?,
        pieces.len(),
        start.elapsed().as_secs_f64()
    );
    for piece in &pieces {
        let (first, last) = (&piece.points[0], &piece.points[piece.points.len() - 1]);
        println!(
            "  contact set of {} nodes from lbar = {:.10} to {:.10} ({} points)",
            piece.contact.iter().filter(|&&c| c).count(),
            first.p,
            last.p,
            piece.points.len()
        );
        for fold in &piece.folds {
            println!(
                "    fold at lbar = {:.10} (arclength bracket {:.1e})",
                fold.p, fold.accuracy
            );
        }
    }
    Ok(())
}
