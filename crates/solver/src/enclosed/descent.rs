//! Leaving a saddle: from an enclosed equilibrium with Hessian index ≥ 1 on the tangent
//! space of its active constraints, a step along the eigenvector of the most negative
//! eigenvalue (both signs) lowers the energy at second order; Newton from there finds
//! the equilibrium that the unstable direction leads to (the enclosed diagram uses it
//! where its lowest traced state is unstable, so that a lower state must exist).
//!
//! It is one file because every route to the lowest state of an enclosed branch (descent from a
//! saddle, homotopy starts in the stiffness, minima of other lengths continued in `L̄`) ends in
//! `solve_branch_lowest`, which compares them with one period count; the steps of the last
//! route that need none of these (its lengths, the continuation) are in
//! [`super::length_path`].
//!
//! [`EnclosedSaddle`] is the enclosed model's side of the one descent routine
//! ([`crate::descend::descend`]): the same unstable directions and Newton solves, with the
//! branch of a state read from the periods of its curvature ([`enclosed_periods`]).

use nalgebra::SymmetricEigen;

use super::branch::{
    resample_state, solve_branch, solve_from_surface, solve_levels, solve_levels_from_fine,
    BranchSolve, SurfaceSource,
};
use super::length_path::{continue_in_length, probe_lengths};
use super::solve::{solve_enclosed, EnclosedOptions, EnclosedState};
use super::wall::IntoWall;
use crate::descend::{descend as descend_saddle, Descent, DescentSettings, SaddleModel};
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
    // A descent that ends at a lower saddle of the branch (no local minimum reached) still
    // moves the solve there: the lowest state of the branch reached is the one reported.
    if !d.moved() {
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

/// Features of a periodic signal sampled at `n` equal steps of `σ ∈ [0, 1)`: the `σ` of
/// its local extrema and of its sign changes (zeros), by parabolic and linear interpolation.
fn signal_features(f: &[f64]) -> Vec<f64> {
    let n = f.len();
    let h = 1.0 / n as f64;
    let scale = f.iter().fold(0.0f64, |a, b| a.max(b.abs()));
    if scale == 0.0 {
        return Vec::new();
    }
    let mut out = Vec::new();
    for i in 0..n {
        let (a, b, c) = (f[(i + n - 1) % n], f[i], f[(i + 1) % n]);
        // An extremum (strict on one side: plateaus of a sharp profile count once).
        if ((b > a && b >= c) || (b < a && b <= c)) && (b - a).abs() + (b - c).abs() > 1e-9 * scale
        {
            let den = a - 2.0 * b + c;
            let off = if den.abs() > 0.0 {
                (0.5 * (a - c) / den).clamp(-0.5, 0.5)
            } else {
                0.0
            };
            out.push(((i as f64 + off) * h).rem_euclid(1.0));
        }
        if b != 0.0 && c != 0.0 && (b > 0.0) != (c > 0.0) {
            out.push(((i as f64 + b / (b - c)) * h).rem_euclid(1.0));
        }
    }
    out
}

/// Where the stiffness profile's features sit, `σ = s/L`: the extrema of `D` (the middles
/// of the segments) and of `dD/dσ` (the transitions). Empty for a uniform rod.
pub fn profile_features(stiffness: &crate::Stiffness) -> Result<Vec<f64>, SolverError> {
    if stiffness.is_uniform() {
        return Ok(Vec::new());
    }
    let prof = stiffness.validate()?;
    const SAMPLES: usize = 4096;
    let v: Vec<_> = (0..SAMPLES)
        .map(|i| prof.eval(i as f64 / SAMPLES as f64))
        .collect();
    let d: Vec<f64> = v.iter().map(|p| p.d).collect();
    let d1: Vec<f64> = v.iter().map(|p| p.d1).collect();
    let mut out = signal_features(&d);
    // Only the extrema of D' (its zeros are the extrema of D, already in).
    let n = d1.len();
    let top = d1.iter().fold(0.0f64, |a, b| a.max(b.abs()));
    out.extend(signal_features(&d1).into_iter().filter(|&s| {
        let i = ((s * n as f64).round() as usize) % n;
        d1[i].abs() > 1e-3 * top
    }));
    Ok(out)
}

/// Shifts `φ` of the arclength origin of the uniform rod's loop of branch `eta` at `lbar`
/// (its curvature taken at `σ + φ`) that put a feature of the loop (an extremum or a zero of
/// `κ_g`) on a feature of the stiffness profile ([`profile_features`]), modulo the loop's
/// period `1/η`, in `[0, 1/η)`, without repeats (closer than `1e-3`). `[0]` for a uniform
/// rod. The starts of [`stiffness_homotopy_states`]: where a loop's soft and stiff parts
/// fall relative to its bends decides which state of the non-uniform rod it leads to.
pub fn homotopy_shifts(
    stiffness: &crate::Stiffness,
    eta: u32,
    lbar: f64,
) -> Result<Vec<f64>, SolverError> {
    let prof = profile_features(stiffness)?;
    if prof.is_empty() {
        return Ok(vec![0.0]);
    }
    let l = rodloop_exact::paper_branch_loop(eta, lbar)?;
    const SAMPLES: usize = 1024;
    let kg = (0..SAMPLES)
        .map(|i| Ok(l.point(i as f64 / SAMPLES as f64 * l.length())?.kappa_g))
        .collect::<Result<Vec<f64>, SolverError>>()?;
    let period = 1.0 / f64::from(eta.max(1));
    let mut shifts: Vec<f64> = Vec::new();
    for &a in &signal_features(&kg) {
        for &b in &prof {
            let phi = (a - b).rem_euclid(period);
            let near = |x: f64| {
                let d = (x - phi).rem_euclid(period);
                d.min(period - d) < 1e-3
            };
            if !shifts.iter().any(|&x| near(x)) {
                shifts.push(phi);
            }
        }
    }
    shifts.sort_by(f64::total_cmp);
    Ok(shifts)
}

/// Enclosed states of the non-uniform rod `stiffness` at `lbar` on `cells` cells reached by
/// continuation in the stiffness ([`super::continuation::continue_in_stiffness`]) from the
/// uniform rod's enclosed loop of branch `eta` (the exact surface loop, lifted off by the
/// semismooth Newton where it needs a pulling wall), one per shift of [`homotopy_shifts`]:
/// those of branch `eta` ([`enclosed_periods`]), lowest first, without repeats (energies
/// within `1e-9` relative). Where the uniform rod's loop is attached, its continuation may
/// still lift off along the path.
pub fn stiffness_homotopy_states(
    wall: impl IntoWall,
    lbar: f64,
    eta: u32,
    stiffness: &crate::Stiffness,
    cells: usize,
    opts: &EnclosedOptions,
) -> Result<Vec<EnclosedState>, SolverError> {
    Ok(
        stiffness_homotopy_starts(wall, lbar, eta, stiffness, cells, opts)?
            .into_iter()
            .map(|(_, s)| s)
            .collect(),
    )
}

/// [`stiffness_homotopy_states`] with the shift `φ` (fraction of the length) of the uniform
/// rod's loop each state comes from: the start a `solve` names.
pub fn stiffness_homotopy_starts(
    wall: impl IntoWall,
    lbar: f64,
    eta: u32,
    stiffness: &crate::Stiffness,
    cells: usize,
    opts: &EnclosedOptions,
) -> Result<Vec<(f64, EnclosedState)>, SolverError> {
    let wall = wall.into_wall();
    let radius = wall.radius();
    let l = rodloop_exact::paper_branch_loop(eta, lbar)?;
    let uniform = crate::Stiffness::Uniform {
        d: stiffness.reference(),
    };
    let lmin = l.lambda_range().0;
    let len = l.length();
    let mut out: Vec<(f64, EnclosedState)> = Vec::new();
    for phi in homotopy_shifts(stiffness, eta, lbar)? {
        let kg = |s: f64| {
            l.point((s + phi).rem_euclid(1.0) * len)
                .map_or(0.0, |p| p.kappa_g / radius)
        };
        let Ok((m, z0)) = super::solve::start_from_surface(&wall, lbar, cells, &uniform, kg) else {
            continue;
        };
        let start = match solve_enclosed(&m, z0.clone(), opts) {
            Ok(s) => s,
            Err(_) if lmin < 0.0 => {
                match super::solve::solve_by_pull_homotopy(&m, z0, lmin, opts) {
                    Ok(s) => s,
                    Err(_) => continue,
                }
            }
            Err(_) => continue,
        };
        let Ok(s) = super::continuation::continue_in_stiffness(&start, stiffness, opts) else {
            continue;
        };
        if enclosed_periods(&s).ok().map(|p| p.eta) != Some(eta) {
            continue;
        }
        let e = s.energy();
        if !e.is_finite()
            || out
                .iter()
                .any(|(_, o)| (o.energy() - e).abs() <= 1e-9 * e.abs())
        {
            continue;
        }
        out.push((phi, s));
    }
    out.sort_by(|a, b| a.1.energy().total_cmp(&b.1.energy()));
    Ok(out)
}

/// A state found on a coarse mesh as a solve with `cells` cells and its levels: its
/// curvature carried to `cells/4` and cascaded ([`solve_levels`]); where that does not
/// converge (point contacts, whose contact nodes move between meshes), the cascade on the
/// state's own mesh, its finest level carried to `cells` and its levels re-solved from
/// there ([`solve_levels_from_fine`]), else that cascade as it is.
fn carry_to_ladder(s: &EnclosedState, cells: usize, opts: &EnclosedOptions) -> Option<BranchSolve> {
    let here = s.model.cells();
    if here == cells / 4 {
        return solve_levels(&s.model, s.z.clone(), None, opts).ok();
    }
    if let Ok(b) = resample_state(s, cells / 4).and_then(|(m, z)| solve_levels(&m, z, None, opts)) {
        return Some(b);
    }
    let own = solve_levels(&s.model, s.z.clone(), None, opts).ok()?;
    let watchdog = EnclosedOptions {
        watchdog: opts.watchdog.max(2),
        ..opts.clone()
    };
    let fine = resample_state(&own.fine, cells)
        .and_then(|(m, z)| solve_enclosed(&m, z, &watchdog))
        .and_then(|f| solve_levels_from_fine(f, opts));
    Some(fine.unwrap_or(own))
}

/// What [`solve_branch_lowest`] returns: [`DescendedSolve`] and `true` where the state
/// reported is not the one reached from the surface loop but a lower local minimum from
/// [`stiffness_homotopy_states`].
pub type LowestSolve = (DescendedSolve, bool);

/// The lowest local minimum of branch `eta` that an enclosed `solve` finds at `lbar`:
/// [`solve_branch_descended`] from the surface loop `source`, and for a non-uniform rod
/// the states reached by continuation in the stiffness from the uniform rod's loop
/// ([`stiffness_homotopy_states`], on `8(2 + η)` cells and carried to `N/4` of the first
/// mesh of `ladder`), each cascaded to `N/2, N` ([`solve_levels`]) and descended where it is a saddle ([`descend_branch`]).
/// Where none of these is a local minimum, the local minima of the branch found at the
/// nearest other lengths are continued in `L̄` to `lbar` on the same coarse mesh
/// ([`super::length_path`]) and cascaded and descended in the same way (the enclosed
/// diagram follows a stable family through the branch's range likewise).
/// Of the states of branch `eta`, an index-0 one goes before any with index > 0, and the
/// lowest of those is returned. The semismooth Newton from the surface loop stops at the
/// equilibrium next to it, which need not be the lowest minimum of the branch.
pub fn solve_branch_lowest(
    wall: impl IntoWall,
    lbar: f64,
    eta: u32,
    stiffness: &crate::Stiffness,
    source: &SurfaceSource,
    ladder: &[usize],
    opts: &EnclosedOptions,
) -> Result<LowestSolve, SolverError> {
    let wall = wall.into_wall();
    let base = solve_branch_descended(&wall, lbar, stiffness, source, ladder, opts);
    if stiffness.is_uniform() {
        return base.map(|b| (b, false));
    }
    let saddle = EnclosedSaddle {
        opts: opts.clone(),
        ..EnclosedSaddle::default()
    };
    let cells = ladder.first().copied().unwrap_or(0);
    let rank = |b: &BranchSolve| -> Option<(usize, f64)> {
        let index = saddle.index(b.coarsest()).ok()?;
        let same = enclosed_periods(&b.fine).ok().map(|p| p.eta) == Some(eta);
        same.then_some((usize::from(index > 0), b.energy))
    };
    let better = |x: (usize, f64), y: (usize, f64)| x.0 < y.0 || (x.0 == y.0 && x.1 < y.1);
    // The best state of the other routes, with the route that reaches it.
    type Found = Option<(BranchSolve, Option<Descent<EnclosedState>>, String)>;
    let mut best: Found = None;
    let offer = |best: &mut Found, b: BranchSolve, d: Option<Descent<EnclosedState>>, route| {
        let Some(r) = rank(&b) else { return };
        if best
            .as_ref()
            .and_then(|(o, _, _)| rank(o))
            .is_none_or(|o| better(r, o))
        {
            *best = Some((b, d, route));
        }
    };
    // The path is followed on the coarsest mesh that resolves the profile (the `N/4` level
    // of the diagram's default mesh, `8(2 + η)` cells), so that every accuracy follows the
    // same path; its end is carried to this ladder's `N/4`.
    let search = (8 * (2 + eta as usize)).min(cells / 4);
    if cells >= 32 && cells % 4 == 0 {
        for (phi, s) in
            stiffness_homotopy_starts(&wall, lbar, eta, stiffness, search, opts).unwrap_or_default()
        {
            let Some(b) = carry_to_ladder(&s, cells, opts) else {
                continue;
            };
            let Ok((b, d)) = descend_branch(b, opts) else {
                continue;
            };
            offer(&mut best, b, d, format!("continuation in the stiffness from the uniform rod's loop with its arclength origin shifted by {phi:.4} L"));
        }
    }
    // No local minimum yet: one reached at other lengths of the branch, continued in L̄.
    let stable = |b: &BranchSolve| rank(b).is_some_and(|r| r.0 == 0);
    let found_minimum = base.as_ref().is_ok_and(|b| stable(&b.0))
        || best.as_ref().is_some_and(|(b, _, _)| stable(b));
    if !found_minimum && cells >= 32 && cells % 4 == 0 {
        let radius = wall.radius();
        let surface = |x: f64| {
            crate::solve_robust(
                radius,
                x,
                stiffness,
                &crate::StartShape::Euler { l: eta },
                crate::Accuracy::Fast,
                Some(eta),
                &crate::SolveOptions::default(),
            )
            .ok()
            .map(|(r, _)| SurfaceSource::Numeric(Box::new(r.equilibrium)))
        };
        for (x, s) in
            states_by_length_continuation(&wall, lbar, eta, stiffness, search, opts, surface)
        {
            let Some(b) = carry_to_ladder(&s, cells, opts) else {
                continue;
            };
            let Ok((b, d)) = descend_branch(b, opts) else {
                continue;
            };
            offer(
                &mut best,
                b,
                d,
                format!("continuation in lbar from a local minimum of the branch at lbar = {x:.4}"),
            );
        }
    }
    match (base, best) {
        (Ok(base), Some((b, d, route))) => {
            let replace = match (rank(&base.0), rank(&b)) {
                (Some(x), Some(y)) => better(y, x),
                (None, Some(_)) => true,
                _ => false,
            };
            if !replace {
                return Ok((base, false));
            }
            let mut notes = base.2;
            notes.push(format!(
                "the state reached from the surface loop (E R/(pi D0) = {:.10}) is not the lowest local minimum found: {route} reaches this one",
                base.0.energy
            ));
            Ok(((b, d, notes), true))
        }
        (Ok(base), None) => Ok((base, false)),
        (Err(_), Some((b, d, route))) => Ok((
            (
                b,
                d,
                vec![format!("the solve from the surface loop did not converge; the state comes from {route}")],
            ),
            true,
        )),
        (Err(e), None) => Err(e),
    }
}

/// Amplitudes of the descents of [`local_minima`] (as [`descend_branch`]).
const AMPLITUDES: [f64; 5] = [0.02, 0.05, 0.15, 0.3, 0.5];

/// Local minima (index 0) of branch `eta` at `lbar` on `cells` cells reached from `starts`,
/// each descended where it is a saddle ([`crate::descend::descend`]). Lowest first.
fn local_minima(
    starts: Vec<EnclosedState>,
    eta: u32,
    opts: &EnclosedOptions,
) -> Vec<EnclosedState> {
    let saddle = EnclosedSaddle {
        opts: opts.clone(),
        ..EnclosedSaddle::default()
    };
    let settings = DescentSettings {
        amplitudes: AMPLITUDES.to_vec(),
        ..DescentSettings::default()
    };
    let mut out: Vec<EnclosedState> = starts
        .into_iter()
        .filter_map(|s| descend_saddle(&saddle, s, &settings).ok())
        .map(|d| d.state)
        .filter(|s| saddle.index(s).ok() == Some(0))
        .filter(|s| enclosed_periods(s).ok().map(|p| p.eta) == Some(eta))
        .collect();
    out.sort_by(|a, b| a.energy().total_cmp(&b.energy()));
    out
}

/// Probe lengths ([`probe_lengths`], nearest first) at which the stiffness paths
/// ([`stiffness_homotopy_states`], one continuation per shift: the costly start) are
/// searched, after the surface loop has been tried at every probe length.
pub const STIFFNESS_PROBES: usize = 2;

/// Local minima of branch `eta` at one length of [`probe_lengths`], continued to `lbar`:
/// the states at `lbar` on `cells` cells of branch `eta`, lowest first (their index may have
/// changed on the way), each with the length it comes from. The starts at a probe length
/// `x`: the enclosed state from the surface loop `surface(x)` (where one is solved) at every
/// probe length in turn, then the stiffness paths at the [`STIFFNESS_PROBES`] nearest ones;
/// each descended where it is a saddle. The first probe length that gives a state at
/// `lbar` ends the search; empty when none does.
pub fn states_by_length_continuation<F>(
    wall: impl IntoWall,
    lbar: f64,
    eta: u32,
    stiffness: &crate::Stiffness,
    cells: usize,
    opts: &EnclosedOptions,
    surface: F,
) -> Vec<(f64, EnclosedState)>
where
    F: Fn(f64) -> Option<SurfaceSource>,
{
    let wall = wall.into_wall();
    let continued = |x: f64, minima: Vec<EnclosedState>| {
        let mut out: Vec<(f64, EnclosedState)> = minima
            .into_iter()
            .filter_map(|s| continue_in_length(&s, lbar, opts).ok())
            .filter(|s| enclosed_periods(s).ok().map(|p| p.eta) == Some(eta))
            .map(|s| (x, s))
            .collect();
        out.sort_by(|a, b| a.1.energy().total_cmp(&b.1.energy()));
        out
    };
    let lengths = probe_lengths(lbar, eta);
    for &x in &lengths {
        let Some(src) = surface(x) else { continue };
        let Ok(s) = solve_from_surface(&wall, x, stiffness, &src, cells, opts) else {
            continue;
        };
        let out = continued(x, local_minima(vec![s], eta, opts));
        if !out.is_empty() {
            return out;
        }
    }
    for &x in lengths.iter().take(STIFFNESS_PROBES) {
        let starts =
            stiffness_homotopy_states(&wall, x, eta, stiffness, cells, opts).unwrap_or_default();
        let out = continued(x, local_minima(starts, eta, opts));
        if !out.is_empty() {
            return out;
        }
    }
    Vec::new()
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

    /// The rotation angle about the tangent with which the rotation-minimising frame of a
    /// state comes back after one loop (its holonomy, `−∮τ ds` mod 2π).
    fn holonomy(s: &EnclosedState) -> f64 {
        let p = s.model.transforms(&s.z).unwrap();
        let x = &p[s.model.cells()];
        (x[(2, 1)] - x[(1, 2)]).atan2(x[(1, 1)] + x[(2, 2)])
    }

    /// The two-segment rod of the paper's Sec. 5 (`D1/D0 = 0.5`) in the ball at `L̄ = 1.35`,
    /// branch 2 (η = 1), `N = 96`. Two routes that share no start: the uniform rod's
    /// loop continued in the stiffness ([`stiffness_homotopy_states`]), and a loop shrunk
    /// into the ball (the two-segment surface loop at `L̄/a` on the sphere of radius
    /// `a R`, `a = 0.95, 0.9`, which has the same length and touches nothing) relaxed by
    /// Newton and the descent from saddles. The lowest local minimum found is a bending-only equilibrium
    /// whose frame does not return (a pure-bending rod carries no twisting moment, so the
    /// holonomy is free), and no route finds a lower minimum.
    #[test]
    fn two_segment_figure_eight_minimum_needs_no_twisting_moment() {
        let st = Stiffness::Tanh {
            d0: 1.0,
            d1: 0.5,
            s0: 0.3,
            s1: 0.8,
            gamma: 200.0,
        };
        let (lbar, eta, cells) = (1.35, 1u32, 96usize);
        let opts = EnclosedOptions::default();
        let saddle = EnclosedSaddle::default();
        let minimum = |b: BranchSolve| -> Option<BranchSolve> {
            let (b, _) = descend_branch(b, &opts).ok()?;
            let ok =
                saddle.index(&b.quarter).ok()? == 0 && enclosed_periods(&b.fine).ok()?.eta == eta;
            ok.then_some(b)
        };
        // Route 1: the stiffness path.
        let path: Vec<BranchSolve> =
            stiffness_homotopy_states(1.0, lbar, eta, &st, cells / 4, &opts)
                .unwrap()
                .into_iter()
                .filter_map(|s| solve_levels(&s.model, s.z.clone(), None, &opts).ok())
                .filter_map(minimum)
                .collect();
        let best = path
            .iter()
            .min_by(|a, b| a.energy.total_cmp(&b.energy))
            .expect("an index-0 state of branch 2 from the stiffness path");
        // A bending-only equilibrium: stationary, the frame turned about the tangent.
        let (_, _, comp, stat) = best.fine.optimality().unwrap();
        assert!(comp < 1e-8 && stat < 1e-8, "{comp:e} {stat:e}");
        let alpha = holonomy(&best.fine);
        assert!(alpha.abs() > 1e-2, "holonomy {alpha}");
        // Route 2: loops shrunk into the ball (radius `a R`, touching nothing), relaxed by
        // Newton, cascaded and descended where they are saddles: every state of the branch
        // they reach lies no lower than the stiffness path's minimum.
        let mut reached = Vec::new();
        for a in [0.95, 0.9] {
            let (res, _) = crate::solve_robust(
                1.0,
                lbar / a,
                &st,
                &crate::StartShape::Euler { l: eta },
                crate::Accuracy::Default,
                Some(eta),
                &crate::SolveOptions::default(),
            )
            .unwrap();
            let (m, z) = super::super::solve::start_from_curvature(
                1.0,
                lbar,
                cells / 4,
                &st,
                |s| {
                    let k = res.equilibrium.sample_at(&[s]).unwrap()[0];
                    (k / a, -1.0 / a)
                },
                [0.0, 0.0, a],
            )
            .unwrap();
            let gmin = m
                .gaps(&z)
                .unwrap()
                .iter()
                .cloned()
                .fold(f64::INFINITY, f64::min);
            assert!(gmin > 0.03, "the loop shrunk to {a} R touches ({gmin})");
            let relaxed = solve_enclosed(&m, z, &opts)
                .ok()
                .and_then(|s| solve_levels(&s.model, s.z.clone(), None, &opts).ok())
                .and_then(|b| descend_branch(b, &opts).ok())
                .map(|(b, _)| b)
                .filter(|b| enclosed_periods(&b.fine).ok().map(|p| p.eta) == Some(eta));
            if let Some(b) = relaxed {
                println!(
                    "stiffness path {:.10} ± {:.1e} (holonomy {alpha:.4}), loop shrunk to {a} R: {:.10} ± {:.1e}, index {}",
                    best.energy,
                    best.energy_error,
                    b.energy,
                    b.energy_error,
                    saddle.index(&b.quarter).unwrap()
                );
                reached.push(b);
            }
        }
        assert!(
            !reached.is_empty(),
            "no shrunk loop relaxes to a state of the branch"
        );
        for b in &reached {
            assert!(
                best.energy <= b.energy + 3.0 * (best.energy_error + b.energy_error),
                "a shrunk loop relaxes below the lowest minimum found: {} against {}",
                b.energy,
                best.energy
            );
        }
    }
}
