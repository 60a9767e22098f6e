//! Leaving a saddle: from an enclosed equilibrium with Hessian index ≥ 1 on the tangent
//! space of its active constraints, a step along the eigenvector of the most negative
//! eigenvalue (both signs) lowers the energy at second order; Newton from there finds
//! the equilibrium that the unstable direction leads to (the enclosed diagram uses it
//! where its lowest traced state is unstable, so that a lower state must exist).

use nalgebra::SymmetricEigen;

use super::solve::{solve_enclosed, EnclosedOptions, EnclosedState};
use crate::SolverError;

/// The most negative eigenvalue of the mass-normalised Hessian of the Lagrangian on the
/// tangent space of the closure, the gauges and the strongly active wall constraints
/// (`λ_j > tol·max λ`; the same space as [`EnclosedState::stability`]), with its
/// eigenvector in the primal unknowns (`κ` at the Gauss points and `r0`), normalised to
/// unit mass norm `Σ m_i v_i² = 1`. `None` when the index is 0.
pub fn unstable_direction(
    state: &EnclosedState,
    tol: f64,
) -> Result<Option<(f64, Vec<f64>)>, SolverError> {
    let np = state.model.n_primal();
    let (pw, s) = state.tangent_hessian(tol)?;
    let eig = SymmetricEigen::new(pw);
    let (k, &val) = eig
        .eigenvalues
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.total_cmp(b.1))
        .ok_or_else(|| SolverError::InvalidInput("empty Hessian".into()))?;
    let scale = eig
        .eigenvalues
        .iter()
        .fold(0.0f64, |x, y| x.max(y.abs()))
        .max(1e-300);
    if val >= -1e-9 * scale {
        return Ok(None);
    }
    let u = eig.eigenvectors.column(k);
    Ok(Some((val, (0..np).map(|i| u[i] * s[i]).collect())))
}

/// Equilibria reached from `state` by Newton after a step of `±amplitude` (relative to the
/// root-mean-square curvature, in the mass norm) along [`unstable_direction`]: the converged
/// ones below `state`'s energy, lowest first. Empty when the index is 0.
pub fn descend(
    state: &EnclosedState,
    amplitude: f64,
    opts: &EnclosedOptions,
) -> Result<Vec<EnclosedState>, SolverError> {
    let Some((_, v)) = unstable_direction(state, 1e-6)? else {
        return Ok(Vec::new());
    };
    let m = &state.model;
    let n = m.cells();
    // ‖κ‖ in the same mass norm: (∫|κ|² ds)^½.
    let norm = (0..4 * n)
        .map(|a| 0.5 * m.cell_length(a / 4) * state.z[a] * state.z[a])
        .sum::<f64>()
        .sqrt();
    let e0 = state.energy();
    let mut out = Vec::new();
    for sign in [1.0, -1.0] {
        let mut z = state.z.clone();
        for (i, vi) in v.iter().enumerate() {
            z[i] += sign * amplitude * norm * vi;
        }
        if let Ok(st) = solve_enclosed(m, z, opts) {
            if st.energy() < e0 - 1e-9 * e0.abs().max(1.0) {
                out.push(st);
            }
        }
    }
    out.sort_by(|a, b| a.energy().total_cmp(&b.energy()));
    Ok(out)
}
