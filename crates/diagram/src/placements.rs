//! Equilibria of one branch of a non-uniform rod from the exact loops of the uniform rod
//! (Sec. 4.3) placed at several offsets along it: where the soft segment sits on the loop
//! selects the state, so the starts are the exact loop of `η` periods shifted by
//! `k/8 · 1/(2η)` of the length (`κ_g²` has period `1/(2η)`).

use rodloop_solver::identify::identify_equilibrium;
use rodloop_solver::{
    solve, Confinement, Equilibrium, Globalization, SolveOptions, SolverError, StartShape,
    SurfaceModel,
};

/// The shift of start `k` (eighths of `1/(2η)`).
pub(crate) fn shift_of(eta: u32, k: u32) -> f64 {
    0.5 / f64::from(eta) * f64::from(k) / 8.0
}

/// Solve `model` from the exact loop of `eta` periods shifted by [`shift_of`]`(eta, k)`,
/// with energy minimisation where the start is far ([`Globalization::Auto`]).
pub(crate) fn solve_shifted(
    model: &SurfaceModel,
    eta: u32,
    k: u32,
    opts: &SolveOptions,
) -> Result<Equilibrium, SolverError> {
    let auto = SolveOptions {
        globalization: Globalization::Auto,
        ..opts.clone()
    };
    StartShape::Exact { eta }
        .shifted(model.lbar(), shift_of(eta, k))
        .and_then(|st| st.gauss_values(model))
        .and_then(|z| solve(model, &z, &auto))
}

/// What a solve reached: whether it has `eta` periods, its stability index (tolerance
/// `tol`; `usize::MAX` when it cannot be computed) and its energy `E R/(π D0)`.
pub(crate) fn classify(eq: &Equilibrium, eta: u32, tol: f64) -> (bool, usize, f64) {
    let ok_eta = identify_equilibrium(eq)
        .map(|p| p.eta == eta)
        .unwrap_or(false);
    let idx = eq.model().index(&eq.state(), tol).unwrap_or(usize::MAX);
    (ok_eta, idx, eq.energy().total)
}
