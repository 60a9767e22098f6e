//! Leaving a saddle: from an enclosed equilibrium with Hessian index ≥ 1 on the tangent
//! space of its active constraints, a step along the eigenvector of the most negative
//! eigenvalue (both signs) lowers the energy at second order; Newton from there finds
//! the equilibrium that the unstable direction leads to (the enclosed diagram uses it
//! where its lowest traced state is unstable, so that a lower state must exist).
//!
//! [`EnclosedSaddle`] is the enclosed model's side of the one descent routine
//! ([`crate::descend::descend`]): the same unstable directions and Newton solves, with the
//! branch of a state read from the geodesic curvature of its radial projection
//! ([`enclosed_periods`]).

use nalgebra::SymmetricEigen;

use super::solve::{solve_enclosed, EnclosedOptions, EnclosedState};
use crate::descend::SaddleModel;
use crate::identify::{identify_periods, Periods};
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
    Ok(unstable_directions(state, tol, 1)?.into_iter().next())
}

/// The up to `count` most negative eigenvalues (below `−1e-9` of the largest in magnitude,
/// the threshold of [`EnclosedState::stability`]) of the tangent Hessian of
/// [`unstable_direction`], ascending, with their eigenvectors in the primal unknowns
/// (unit mass norm).
pub fn unstable_directions(
    state: &EnclosedState,
    tol: f64,
    count: usize,
) -> Result<Vec<(f64, Vec<f64>)>, SolverError> {
    let np = state.model.n_primal();
    let (pw, s) = state.tangent_hessian(tol)?;
    let eig = SymmetricEigen::new(pw);
    if eig.eigenvalues.is_empty() {
        return Err(SolverError::InvalidInput("empty Hessian".into()));
    }
    let scale = eig
        .eigenvalues
        .iter()
        .fold(0.0f64, |x, y| x.max(y.abs()))
        .max(1e-300);
    let mut order: Vec<usize> = (0..eig.eigenvalues.len())
        .filter(|&k| eig.eigenvalues[k] < -1e-9 * scale)
        .collect();
    order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    Ok(order
        .into_iter()
        .take(count)
        .map(|k| {
            let u = eig.eigenvectors.column(k);
            (eig.eigenvalues[k], (0..np).map(|i| u[i] * s[i]).collect())
        })
        .collect())
}

/// `(∫|κ|² ds)^½` of a state, the mass norm of its curvature unknowns: the scale of the
/// steps along unstable directions.
fn curvature_norm(state: &EnclosedState) -> f64 {
    let m = &state.model;
    (0..4 * m.cells())
        .map(|a| 0.5 * m.cell_length(a / 4) * state.z[a] * state.z[a])
        .sum::<f64>()
        .sqrt()
}

/// The state displaced by `amplitude · direction` (primal unknowns), solved by the
/// semismooth Newton.
fn step_and_solve(
    state: &EnclosedState,
    direction: &[f64],
    amplitude: f64,
    opts: &EnclosedOptions,
) -> Result<EnclosedState, SolverError> {
    let mut z = state.z.clone();
    for (zi, vi) in z.iter_mut().zip(direction) {
        *zi += amplitude * vi;
    }
    solve_enclosed(&state.model, z, opts)
}

/// Periods of the geodesic curvature of an enclosed loop's radial projection: at every
/// node `κ_g = κ·(u × t)` with `u = r/|r|`, the conormal of the surface model when the loop
/// lies on the wall ([`crate::identify`] counts them). Nodes closer to the centre than
/// `R/100`, where the projection is not defined, are left out.
pub fn enclosed_periods(state: &EnclosedState) -> Result<Periods, SolverError> {
    let m = &state.model;
    let p = m.transforms(&state.z)?;
    let r0 = m.start_point(&state.z);
    let (mut s, mut kg) = (Vec::new(), Vec::new());
    for j in 0..m.cells() {
        let rot = super::model::rotation(&p[j]);
        let r = r0 + p[j].fixed_view::<3, 1>(0, 3).into_owned();
        if r.norm() < 1e-2 * m.radius() {
            continue;
        }
        let u = r / r.norm();
        let (t, d1, d2) = (rot.column(0), rot.column(1), rot.column(2));
        let (k1, k2) = state.node_curvature(j);
        let kappa = d1 * k1 + d2 * k2;
        s.push(m.bounds()[j] * m.length());
        kg.push(kappa.dot(&u.cross(&t)));
    }
    identify_periods(&s, &kg, m.length())
}

/// The enclosed model as a [`SaddleModel`] (see [`crate::descend`]): index and directions
/// from the tangent Hessian on the active constraints (threshold `tol` on the multipliers),
/// semismooth Newton after a step scaled by the state's `(∫|κ|² ds)^½`, branches by
/// [`enclosed_periods`].
#[derive(Clone, Debug)]
pub struct EnclosedSaddle {
    /// Options of the Newton solves after a step.
    pub opts: EnclosedOptions,
    /// Wall multipliers above `tol · max λ` count as active.
    pub tol: f64,
}

impl Default for EnclosedSaddle {
    fn default() -> Self {
        Self {
            opts: EnclosedOptions::default(),
            tol: 1e-6,
        }
    }
}

impl SaddleModel for EnclosedSaddle {
    type State = EnclosedState;

    fn energy(&self, state: &EnclosedState) -> f64 {
        state.energy()
    }

    fn index(&self, state: &EnclosedState) -> Result<usize, SolverError> {
        Ok(state.stability(self.tol)?.0)
    }

    fn unstable_directions(
        &self,
        state: &EnclosedState,
        count: usize,
    ) -> Result<Vec<(f64, Vec<f64>)>, SolverError> {
        let norm = curvature_norm(state);
        Ok(unstable_directions(state, self.tol, count)?
            .into_iter()
            .map(|(mu, v)| (mu, v.into_iter().map(|x| x * norm).collect()))
            .collect())
    }

    fn step_and_solve(
        &self,
        state: &EnclosedState,
        direction: &[f64],
        amplitude: f64,
    ) -> Result<EnclosedState, SolverError> {
        step_and_solve(state, direction, amplitude, &self.opts)
    }

    fn branch(&self, state: &EnclosedState) -> Option<u32> {
        enclosed_periods(state).ok().map(|p| p.eta)
    }
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
    let norm = curvature_norm(state);
    let e0 = state.energy();
    let mut out = Vec::new();
    for sign in [1.0, -1.0] {
        if let Ok(st) = step_and_solve(state, &v, sign * amplitude * norm, opts) {
            if st.energy() < e0 - 1e-9 * e0.abs().max(1.0) {
                out.push(st);
            }
        }
    }
    out.sort_by(|a, b| a.energy().total_cmp(&b.energy()));
    Ok(out)
}
