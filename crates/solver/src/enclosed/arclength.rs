//! An enclosed family followed by pseudo-arclength continuation on one smooth piece of the
//! complementarity: the contact set held fixed ([`EnclosedModel::with_contact_set`]), so
//! that Keller's method of [`rodloop_continuation`] passes the folds that natural-parameter
//! steps in `L̄` cannot.
//!
//! The enclosed KKT system (Eq. (51) discretised, [`super::model`]) writes the wall's
//! complementarity `λ_j ≥ 0, g_j ≥ 0, λ_j g_j = 0` as `min(λ_j, σ g_j) = 0`, which has a kink
//! wherever its two arguments are equal; the bordered corrector of pseudo-arclength stalls
//! there ([`super::seam`]). With the contact set `A` fixed (the nodes whose row is the wall at
//! a converged state), the system is the smooth one of that piece: `σ g_j = 0` for `j ∈ A`,
//! `λ_j = 0` otherwise, the stationarity, closure and gauge rows unchanged. Its solutions are
//! equilibria of the wall as long as every contact impulse `λ_j` (`j ∈ A`) and every free gap
//! `g_j` (`j ∉ A`) stays nonnegative: [`contact_slack`] is the least of them (the gaps scaled
//! by `σ` like the min-function's argument), an event function for the continuation, whose
//! root is where the contact set changes.

use super::model::EnclosedModel;
use super::state::EnclosedState;
use crate::SolverError;

/// The contact set of `state`: the nodes whose min-function row is the wall
/// (`σ g_j ≤ λ_j`, [`EnclosedModel::evaluate`]).
pub fn contact_set_of(state: &EnclosedState) -> Result<Vec<bool>, SolverError> {
    let m = &state.model;
    let mut set = vec![false; m.cells()];
    for j in m.evaluate(&state.z)?.wall_rows {
        set[j] = true;
    }
    Ok(set)
}

/// How far the state `z` of `model` (a fixed contact set, [`EnclosedModel::with_contact_set`])
/// lies inside its piece: the least of the contact impulses `λ_j` on the set and of the
/// scaled gaps `σ g_j` off it. Negative once a contact would pull or a free node would leave
/// the ball; an error where no contact set is fixed.
pub fn contact_slack(model: &EnclosedModel, z: &[f64]) -> Result<f64, SolverError> {
    let set = model
        .contact_set()
        .ok_or_else(|| SolverError::InvalidInput("the model holds no contact set fixed".into()))?;
    let wall = model.wall();
    let sigma = model.wall_scale();
    let lo = model.lambda_offset();
    let positions = model.positions(z)?;
    Ok(set
        .iter()
        .enumerate()
        .map(|(j, &on)| {
            if on {
                z[lo + j]
            } else {
                sigma * wall.gap(&positions[j])
            }
        })
        .fold(f64::INFINITY, f64::min))
}
