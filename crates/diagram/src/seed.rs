//! Seeding a branch from the Euler rotation curves.

use rodloop_solver::{solve, Equilibrium, Globalization, SolveOptions, SolverError, StartShape};

use crate::{DiagramError, DiagramOptions};

/// Seed of branch `eta` at `lbar`: Euler rotation curve `l = η`, relaxed and solved
/// ([`Globalization::Auto`], then a longer relaxation). A uniform rod must relax to a loop
/// with `η` periods; for a non-uniform rod a different count is only noted.
pub(crate) fn seed_at(
    opts: &DiagramOptions,
    eta: u32,
    cells: usize,
    lbar: f64,
) -> Result<(Equilibrium, String), DiagramError> {
    let seed_err = |source: SolverError| DiagramError::Seed { eta, lbar, source };
    let model = opts.model(lbar, cells).map_err(seed_err)?;
    let start = StartShape::Euler { l: eta }
        .gauss_values(&model)
        .map_err(seed_err)?;
    let eq = solve(&model, &start, &SolveOptions::default())
        .or_else(|_| {
            solve(
                &model,
                &start,
                &SolveOptions {
                    globalization: Globalization::Minimize,
                    max_relax_iterations: 2000,
                    max_iterations: 100,
                    ..SolveOptions::default()
                },
            )
        })
        .map_err(seed_err)?;
    let periods = periods_of(&eq).unwrap_or(0);
    let mut seed = format!(
        "Euler rotation curve l = {eta} at L̄ = {lbar}, relaxed ({} iterations) and solved by \
         Newton ({} iterations) with {cells} cells; {periods} period(s) of κ_g",
        eq.report().relax_iterations,
        eq.report().iterations
    );
    if periods != eta as usize {
        if opts.stiffness.is_uniform() {
            return Err(seed_err(SolverError::InvalidInput(format!(
                "the Euler curve relaxed to a loop with {periods} period(s) of κ_g"
            ))));
        }
        seed.push_str(&format!(" (note: {eta} expected for a uniform rod)"));
    }
    Ok((eq, seed))
}

/// Number of periods of `κ_g` of an equilibrium: the dominant Fourier harmonic in
/// arclength ([`rodloop_solver::identify::identify_equilibrium`], what `rodloop solve
/// --branch` checks). Counting sign changes of samples fails on graded meshes and where a
/// stiff segment lies on a great circle (`κ_g ≈ 0` with rounding-level wiggles).
pub(crate) fn periods_of(eq: &Equilibrium) -> Result<usize, SolverError> {
    Ok(rodloop_solver::identify::identify_equilibrium(eq)?.eta as usize)
}
