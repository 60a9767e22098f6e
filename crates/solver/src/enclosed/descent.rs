//! Leaving a saddle: from an enclosed equilibrium with Hessian index ≥ 1 on the tangent
//! space of its active constraints, a step along the eigenvector of the most negative
//! eigenvalue (both signs) lowers the energy at second order; Newton from there finds
//! the equilibrium that the unstable direction leads to (the enclosed diagram uses it
//! where its lowest traced state is unstable, so that a lower state must exist).
//!
//! [`EnclosedSaddle`] is the enclosed model's side of the one descent routine
//! ([`crate::descend::descend`]): the same unstable directions and Newton solves, with the
//! branch of a state read from the periods of its curvature ([`enclosed_periods`]).

use nalgebra::SymmetricEigen;

use super::branch::{
    resample_state, solve_branch, solve_levels, solve_levels_from_fine, BranchSolve, SurfaceSource,
};
use super::solve::{solve_enclosed, EnclosedOptions, EnclosedState};
use crate::descend::{descend as descend_saddle, Descent, DescentSettings, SaddleModel};
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

/// Periods of an enclosed loop's curvature, the branch number `η` of [`crate::identify`]:
/// the curvature vector `(κ1, κ2)` in the rotation-minimising frame (periodic, since the
/// model closes the frame) at the Gauss points, projected on its principal axis (the
/// direction of largest variance about its mean), and the periods of that signal counted.
/// On the wall the frame is the Darboux frame, `(κ1, κ2) = (κ_g, −1/R)`, so the signal is
/// `κ_g` and the count is the surface one; a loop that lifts off keeps the count as long as
/// its curvature keeps its pattern (a planar figure-eight: the signed curvature, one
/// period).
pub fn enclosed_periods(state: &EnclosedState) -> Result<Periods, SolverError> {
    let m = &state.model;
    let ng = 2 * m.cells();
    let w: Vec<f64> = (0..ng).map(|g| m.cell_length(g / 2)).collect();
    let total: f64 = w.iter().sum();
    let k = |g: usize| (state.z[2 * g], state.z[2 * g + 1]);
    let (mut m1, mut m2) = (0.0, 0.0);
    for (g, wg) in w.iter().enumerate() {
        m1 += wg * k(g).0 / total;
        m2 += wg * k(g).1 / total;
    }
    let (mut a, mut b, mut c) = (0.0, 0.0, 0.0);
    for (g, wg) in w.iter().enumerate() {
        let (x, y) = (k(g).0 - m1, k(g).1 - m2);
        a += wg * x * x;
        b += wg * x * y;
        c += wg * y * y;
    }
    // Principal axis of [[a, b], [b, c]].
    let theta = 0.5 * (2.0 * b).atan2(a - c);
    let (e1, e2) = (theta.cos(), theta.sin());
    let s: Vec<f64> = (0..ng).map(|g| m.gauss_sigma(g) * m.length()).collect();
    let signal: Vec<f64> = (0..ng)
        .map(|g| (k(g).0 - m1) * e1 + (k(g).1 - m2) * e2)
        .collect();
    identify_periods(&s, &signal, m.length())
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
        state.index(self.tol)
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

/// [`crate::descend::descend`] for an enclosed solve with its levels. Where the coarsest
/// level ([`BranchSolve::coarsest`]) has index > 0, the descent runs at the `N/4` level and
/// the levels `N/2, N` with the error
/// estimate are redone from the state reached: by the cascade of [`solve_levels`], else
/// from that state carried to `N` directly ([`solve_levels_from_fine`]). Where neither
/// converges (point contacts: the coarse minimum's contact sits a node or two off the
/// finer one's), the solve is returned as it was, with the reason in the descent's
/// shortfall. Returns the (possibly new) solve and the descent (`None` when the coarsest
/// level has index 0); the ends of the descent's path carry the energies at `N`.
pub fn descend_branch(
    b: BranchSolve,
    opts: &EnclosedOptions,
) -> Result<(BranchSolve, Option<Descent<EnclosedState>>), SolverError> {
    let saddle = EnclosedSaddle {
        opts: opts.clone(),
        ..EnclosedSaddle::default()
    };
    // The index where callers compute it (the coarsest level: `N/8` where the cascade has
    // it, a dense eigen-decomposition).
    if saddle.index(b.coarsest())? == 0 {
        return Ok((b, None));
    }
    // Semismooth Newton from the displaced state does not decrease the energy on its way:
    // small steps fall back to the saddle, so larger ones are tried as well.
    let settings = DescentSettings {
        amplitudes: vec![0.02, 0.05, 0.15, 0.3, 0.5],
        ..DescentSettings::default()
    };
    let mut d = descend_saddle(&saddle, b.quarter.clone(), &settings)?;
    let reached = d.end();
    d.path[0].energy = b.energy;
    if !(d.moved() && reached.index == 0) {
        return Ok((b, Some(d)));
    }
    let n = b.fine.model.cells();
    let direct = || -> Result<BranchSolve, SolverError> {
        let (m, z) = resample_state(&d.state, n)?;
        let watchdog = EnclosedOptions {
            watchdog: opts.watchdog.max(2),
            ..opts.clone()
        };
        let fine =
            solve_enclosed(&m, z.clone(), &watchdog).or_else(|_| solve_enclosed(&m, z, opts))?;
        solve_levels_from_fine(fine, opts)
    };
    let cascade = solve_levels(&d.state.model, d.state.z.clone(), None, opts);
    for out in [cascade, direct()].into_iter().flatten() {
        if saddle.index(&out.quarter)? == 0 && out.energy < b.energy {
            let last = d.path.len() - 1;
            d.path[last].energy = out.energy;
            return Ok((out, Some(d)));
        }
    }
    let m = d.state.model.cells();
    Ok((
        b,
        Some(Descent {
            state: d.state,
            path: vec![d.path[0]],
            shortfall: Some(format!(
                "at N/4 = {m} cells the descent reached an index-0 state of the same branch (E = {:.10} there), but the solves at {} and {n} cells did not converge from it",
                reached.energy,
                n / 2
            )),
        }),
    ))
}

/// What [`solve_branch_descended`] returns: the solve, its descent, the meshes given up.
pub type DescendedSolve = (BranchSolve, Option<Descent<EnclosedState>>, Vec<String>);

/// An enclosed solve that ends at a local minimum where it can: [`solve_branch`] at the
/// first mesh of `ladder` (cells, increasing) from the surface loop `source`, then
/// [`descend_branch`]. Where that does not end at an index-0 state (the cascade does not
/// converge, or the finer levels do not converge from the state the descent reached — the
/// semismooth Newton cycles between contact nodes on some meshes of point-contact
/// states), the next mesh of the ladder is tried: from the index-0 state reached on a
/// coarser mesh, resampled to its `N/4` ([`resample_state`], [`solve_levels`]), else from
/// the surface loop. Returns the solve (the last one that converged where none ends at
/// index 0), its descent, and one line per mesh given up, saying why. Errors only when no
/// mesh of the ladder converges.
pub fn solve_branch_descended(
    radius: f64,
    lbar: f64,
    stiffness: &crate::Stiffness,
    source: &SurfaceSource,
    ladder: &[usize],
    opts: &EnclosedOptions,
) -> Result<DescendedSolve, SolverError> {
    let saddle = EnclosedSaddle {
        opts: opts.clone(),
        ..EnclosedSaddle::default()
    };
    let mut notes = Vec::new();
    let mut start: Option<EnclosedState> = None;
    let mut last: Option<(BranchSolve, Option<Descent<EnclosedState>>)> = None;
    let mut first_error = None;
    for &cells in ladder {
        let attempt = match &start {
            Some(s) => {
                notes.push(format!(
                    "at N = {cells} cells started from the index-0 state reached at {} cells",
                    s.model.cells()
                ));
                resample_state(s, cells / 4).and_then(|(m, z)| solve_levels(&m, z, None, opts))
            }
            None => solve_branch(radius, lbar, stiffness, source, cells, opts),
        };
        let b = match attempt {
            Ok(b) => b,
            Err(e) => {
                notes.push(format!(
                    "at N = {cells} cells the solve did not converge ({e})"
                ));
                first_error.get_or_insert(e);
                continue;
            }
        };
        let (b, d) = descend_branch(b, opts)?;
        if saddle.index(b.coarsest())? == 0 {
            return Ok((b, d, notes));
        }
        notes.push(format!(
            "at N = {cells} cells: {}",
            d.as_ref().map_or("index > 0".to_string(), |d| d.describe())
        ));
        if let Some(d) = &d {
            if saddle.index(&d.state)? == 0 && d.state.energy() < b.quarter.energy() {
                start = Some(d.state.clone());
            }
        }
        last = Some((b, d));
    }
    match (last, first_error) {
        (Some((b, d)), _) => Ok((b, d, notes)),
        (None, Some(e)) => Err(e),
        (None, None) => Err(SolverError::InvalidInput(
            "an empty ladder of meshes".into(),
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Stiffness;

    /// Enclosed states started from the exact loops of the paper's branches (uniform rod):
    /// [`enclosed_periods`] names the branch of the state reached, attached (η = 2 at
    /// L̄ = 1.5, η = 3 at 2.5) or lifted off (the figure-eight, η = 1, at L̄ = 1.4).
    #[test]
    fn enclosed_states_are_identified_as_their_branch() {
        let st = Stiffness::Uniform { d: 1.0 };
        for (eta, lbar) in [(2u32, 1.5), (1, 1.4), (3, 2.5)] {
            let l = rodloop_exact::paper_branch_loop(eta, lbar).unwrap();
            let b = solve_branch(
                1.0,
                lbar,
                &st,
                &SurfaceSource::Exact(l),
                64,
                &EnclosedOptions::default(),
            )
            .unwrap();
            let p = enclosed_periods(&b.fine).unwrap();
            assert_eq!(p.eta, eta, "eta {eta} at {lbar}: {p:?}");
            assert!(p.consistent(), "eta {eta} at {lbar}: {p:?}");
            // Attached where the surface loop needs no pulling wall, lifted off otherwise.
            let attached = b.fine.contact(1e-9).unwrap().fraction >= 1.0;
            assert_eq!(attached, eta != 1, "eta {eta} at {lbar}");
        }
    }
}
