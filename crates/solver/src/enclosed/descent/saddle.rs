//! Leaving a saddle of an enclosed branch: the unstable directions of the tangent Hessian
//! ([`unstable_directions`]), the enclosed model's side of the one descent routine
//! ([`EnclosedSaddle`] for [`crate::descend::descend`], the branch of a state read from the
//! periods of its curvature, [`enclosed_periods`]), and a branch solve whose every level is
//! descended where it is a saddle ([`solve_branch_descended`]).

use nalgebra::SymmetricEigen;

use crate::descend::{descend as descend_saddle, Descent, DescentSettings, SaddleModel};
use crate::enclosed::branch::{
    resample_state, solve_branch, solve_levels, solve_levels_from_fine, BranchSolve, SurfaceSource,
};
use crate::enclosed::solve::{solve_enclosed, solve_prolonged, EnclosedOptions, EnclosedState};
use crate::enclosed::wall::IntoWall;
use crate::identify::Periods;
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

/// Periods of an enclosed loop's curvature, the branch number `η`
/// ([`crate::identify::identify_enclosed`]).
pub fn enclosed_periods(state: &EnclosedState) -> Result<Periods, SolverError> {
    crate::identify::identify_enclosed(state)
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
/// shortfall. Where the descent ends at a lower saddle of the branch (no local minimum
/// reached), the solve moves there too. Returns the (possibly new) solve and the descent
/// (`None` when the coarsest level has index 0); the ends of the descent's path carry the
/// energies at `N`.
pub fn descend_branch(
    b: BranchSolve,
    opts: &EnclosedOptions,
) -> Result<(BranchSolve, Option<Descent<EnclosedState>>), SolverError> {
    let saddle = EnclosedSaddle {
        opts: opts.clone(),
        ..EnclosedSaddle::default()
    };
    // The index of the state reported, its finest level ([`BranchSolve::index`]).
    if b.index(saddle.tol)? == 0 {
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
    // A descent that ends at a lower saddle of the branch (no local minimum reached) still
    // moves the solve there: the lowest state of the branch reached is the one reported.
    if !d.moved() {
        return Ok((b, Some(d)));
    }
    let n = b.fine.model.cells();
    let direct = || -> Result<BranchSolve, SolverError> {
        let (m, z) = resample_state(&d.state, n)?;
        let fine = solve_prolonged(&m, z, opts)?;
        solve_levels_from_fine(fine, opts)
    };
    let cascade = solve_levels(&d.state.model, d.state.z.clone(), None, opts);
    let eta = saddle.branch(&b.fine);
    for out in [cascade, direct()].into_iter().flatten() {
        if saddle.index(&out.quarter)? <= reached.index
            && out.energy < b.energy
            && saddle.branch(&out.fine) == eta
        {
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
                "at N/4 = {m} cells the descent reached an index-{} state of the same branch (E = {:.10} there), but the solves at {} and {n} cells did not converge from it",
                reached.index,
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
    wall: impl IntoWall,
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
    let wall = wall.into_wall();
    for &cells in ladder {
        let attempt = match &start {
            Some(s) => {
                notes.push(format!(
                    "at N = {cells} cells started from the index-0 state reached at {} cells",
                    s.model.cells()
                ));
                resample_state(s, cells / 4).and_then(|(m, z)| solve_levels(&m, z, None, opts))
            }
            None => solve_branch(&wall, lbar, stiffness, source, cells, opts),
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
        if b.index(saddle.tol)? == 0 {
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
