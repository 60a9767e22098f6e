//! Semismooth Newton on the enclosed KKT system, starting shapes, stability on the
//! tangent space of the active constraints, and the two-resolution error estimate.
//!
//! # Solver choice
//!
//! The complementarity `λ ≥ 0, g ≥ 0, λg = 0` is written as `min(λ, σg) = 0` and the whole
//! KKT system is solved by semismooth Newton (equivalently, the primal–dual active-set
//! method of Hintermüller, Ito & Kunisch, SIAM J. Optim. 13, 2003): each iteration picks the
//! contact set from the current iterate (`σg ≤ λ`) and takes the Newton step of the
//! equality-constrained KKT system for that set. Why this and not an interior point: the
//! converged state satisfies the complementarity exactly (no barrier bias, so the energy is
//! that of the discrete problem to round-off, which the `≤ 1e-8` target needs); a fully
//! attached surface equilibrium with `λ > 0` is a fixed point reached in one step; the
//! local convergence is quadratic once the contact set settles; and the Jacobian at the
//! solution is the KKT matrix of the active set, which is what stability and continuation
//! need. Globalisation: backtracking on the scaled residual norm.
//!
//! Linear algebra: the step comes from the `O(N)` block factorisation of [`super::lifted`];
//! where that reports a near-singular block, from the dense LU of [`EnclosedModel::evaluate`].

#![allow(clippy::needless_range_loop)] // index arithmetic over cells, nodes and unknowns

use std::f64::consts::PI;
use std::sync::Arc;
use std::time::Instant;

use nalgebra::{DMatrix, DVector, Vector3};
use rodloop_continuation::natural::NaturalSettings;

use super::model::{phase_slope, Complementarity, EnclosedModel, Gauge};
use super::stats::{self, Outcome};
use super::wall::{IntoWall, Wall};
use crate::stiffness::Stiffness;
use crate::SolverError;

/// Options of [`solve_enclosed`].
#[derive(Clone, Debug)]
pub struct EnclosedOptions {
    /// Newton iterations allowed to each form of the complementarity: the min-function's
    /// solve and, where it hands over ([`EnclosedOptions::hand_over`]), the
    /// Fischer–Burmeister solve after it (a failed solve runs at most twice this many).
    pub max_iterations: usize,
    /// Tolerance on [`EnclosedModel::residual_norm`].
    pub tolerance: f64,
    /// Step halvings allowed per iteration.
    pub max_backtracks: usize,
    /// Full steps that may raise the residual (watchdog): a full Newton step that changes
    /// the contact set is taken even when the residual grows, at most this many times per
    /// solve and one at a time; if the residual has not dropped below the value before such
    /// a step within [`WATCHDOG_ITERATIONS`] iterations, the solver returns there, backtracks
    /// and takes no more such steps. `0`
    /// (default): plain backtracking. For starts whose contact ends are off by a node or
    /// two (a coarse solution prolonged to a finer mesh), where the monotone line search
    /// crawls through the active-set changes in short steps.
    pub watchdog: usize,
    /// Give up when `stall_window` iterations in a row have not halved the residual (0:
    /// never). For continuation steps, where a failed step is retried shorter: a start
    /// whose contact set is far off is then shed node by node at nearly constant residual.
    pub stall_window: usize,
    /// Hand a crawling or failing min-function solve to the Fischer–Burmeister form
    /// (`true`, default; see [`solve_enclosed`]). Both forms have the same solutions, but from one
    /// start they may end at different ones: `false` runs the min-function's semismooth
    /// Newton alone, as far as it goes.
    pub hand_over: bool,
}

/// Iterations a watchdog step ([`EnclosedOptions::watchdog`]) has to bring the residual
/// below its value before the step.
pub const WATCHDOG_ITERATIONS: usize = 5;

impl Default for EnclosedOptions {
    fn default() -> Self {
        Self {
            max_iterations: 80,
            tolerance: 1e-10,
            max_backtracks: 40,
            watchdog: 0,
            stall_window: 0,
            hand_over: true,
        }
    }
}

/// A converged enclosed state.
#[derive(Clone, Debug)]
pub struct EnclosedState {
    /// The model.
    pub model: EnclosedModel,
    /// The KKT vector.
    pub z: Vec<f64>,
    /// Newton iterations used.
    pub iterations: usize,
    /// Final scaled residual norm.
    pub residual: f64,
}

/// Contact summary of a state.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Contact {
    /// Fraction of the nodes (length-weighted) touching the wall (`gap ≤ tol`).
    pub fraction: f64,
    /// Number of maximal runs of touching nodes (periodic; a single free node between
    /// touching neighbours does not split a run).
    pub intervals: usize,
    /// The contact runs as `(σ_start, σ_end)` (periodic; `σ = s/L`).
    pub runs: Vec<(f64, f64)>,
    /// Largest gap `R − |r|` and its `σ`.
    pub max_gap: (f64, f64),
    /// Smallest and largest contact force per unit length on the contact set.
    pub lambda_range: (f64, f64),
}

/// Least-squares multipliers `(μ, ν, λ)` for the primal part of `z` (stationarity is linear
/// in them): a start for Newton from a shape without multipliers.
pub fn least_squares_multipliers(model: &EnclosedModel, z: &mut [f64]) -> Result<(), SolverError> {
    let np = model.n_primal();
    let dim = model.dim();
    for v in z[np..].iter_mut() {
        *v = 0.0;
    }
    let ev = model.evaluate(z)?;
    let f0 = ev.residual.rows(0, np).into_owned();
    let a = ev.jacobian.view((0, np), (np, dim - np)).into_owned();
    let scales = model.residual_scales();
    let wv = DVector::from_iterator(np, scales[..np].iter().map(|s| s.sqrt()));
    let aw = DMatrix::from_fn(np, dim - np, |i, j| a[(i, j)] * wv[i]);
    let fw = f0.component_mul(&wv);
    let mut n = aw.transpose() * &aw;
    let tr = n.trace() / n.nrows() as f64;
    for i in 0..n.nrows() {
        n[(i, i)] += 1e-14 * tr;
    }
    let rhs = -(aw.transpose() * fw);
    let y = n
        .clone()
        .cholesky()
        .map(|c| c.solve(&rhs))
        .or_else(|| n.lu().solve(&rhs))
        .ok_or(SolverError::SingularJacobian { iteration: 0 })?;
    for (k, v) in y.iter().enumerate() {
        z[np + k] = *v;
    }
    Ok(())
}

/// How a Newton run ended, for the counters of [`super::stats`].
#[derive(Clone, Copy)]
struct Ended {
    outcome: Outcome,
    iterations: usize,
    dense: usize,
}

/// Semismooth Newton from `z0` (see the module docs): on the min-function, handed over to the
/// Fischer–Burmeister form where it crawls or fails ([`EnclosedOptions::hand_over`]).
/// Counted in [`super::stats`] when the thread has a scope open.
pub fn solve_enclosed(
    model: &EnclosedModel,
    z0: Vec<f64>,
    opts: &EnclosedOptions,
) -> Result<EnclosedState, SolverError> {
    let mut ended = Ended {
        outcome: Outcome::Other,
        iterations: 0,
        dense: 0,
    };
    if !stats::active() {
        return newton(model, z0, opts, &mut ended);
    }
    let start = Instant::now();
    let out = newton(model, z0, opts, &mut ended);
    let outcome = if out.is_ok() {
        Outcome::Converged
    } else {
        ended.outcome
    };
    stats::record(outcome, ended.iterations, ended.dense, start);
    out
}

/// Iterations in a row that do not halve the residual before semismooth Newton on the
/// min-function hands over to Fischer–Burmeister ([`newton`]).
pub const CRAWL_WINDOW: usize = 10;

/// [`solve_enclosed`]'s iteration; `ended` says where it stopped.
///
/// Semismooth Newton on the min-function first. Where its contact set cycles — a contact
/// point between two nodes: each full step moves the contact onto the other node, the
/// residual grows, and the line search takes short steps that change the set node by node —
/// the monotone search crawls ([`CRAWL_WINDOW`] iterations without halving the residual), hits
/// the iteration cap or fails. There (unless the caller gives up early,
/// [`EnclosedOptions::stall_window`]) Newton goes on from the best iterate on the
/// Fischer–Burmeister form ([`Complementarity::FischerBurmeister`]), whose squared residual is
/// continuously differentiable so that the backtracking search on it cannot stall at a kink;
/// it is run to `tolerance/1.75`, which puts the min-function's residual below `tolerance`
/// (`|min(a, b)| ≤ |φ_FB(a, b)|/(2 − √2)`), and the state is returned with the residual of the
/// min-function. Both forms have the same solutions. Where that fails after a crawl, the
/// min-function runs again from the start without the crawl stop (some crawls end in
/// convergence).
fn newton(
    model: &EnclosedModel,
    z0: Vec<f64>,
    opts: &EnclosedOptions,
    ended: &mut Ended,
) -> Result<EnclosedState, SolverError> {
    let mut best: (Vec<f64>, f64) = (z0.clone(), f64::INFINITY);
    let start = z0.clone();
    let mut crawled = false;
    if !opts.hand_over {
        return newton_min(model, z0, opts, ended, &mut best, None);
    }
    let out = newton_min(model, z0, opts, ended, &mut best, Some(&mut crawled));
    let rescue = model.complementarity() == Complementarity::Min
        && opts.stall_window == 0
        && best.1.is_finite()
        && matches!(out, Err(SolverError::NewtonNotConverged { .. }));
    if !rescue {
        return out;
    }
    let fb = model
        .clone()
        .with_complementarity(Complementarity::FischerBurmeister);
    let fopts = EnclosedOptions {
        tolerance: opts.tolerance / 1.75,
        watchdog: 0,
        ..opts.clone()
    };
    let mut inner = Ended {
        outcome: Outcome::Other,
        iterations: 0,
        dense: 0,
    };
    let before = ended.iterations;
    let mut fbest = (best.0.clone(), f64::INFINITY);
    let res = newton_min(&fb, best.0, &fopts, &mut inner, &mut fbest, None);
    ended.iterations = before + inner.iterations;
    ended.dense += inner.dense;
    ended.outcome = inner.outcome;
    match res {
        Ok(st) => {
            let residual = model.residual_norm(&model.residual(&st.z)?);
            Ok(EnclosedState {
                model: model.clone(),
                z: st.z,
                iterations: ended.iterations,
                residual,
            })
        }
        // Where the crawl stopped the min-function early, it runs again without the stop
        // (some crawls end in convergence).
        Err(_) if crawled => {
            let mut again = (start.clone(), f64::INFINITY);
            newton_min(model, start, opts, ended, &mut again, None)
        }
        Err(_) => out,
    }
}

/// Damped semismooth Newton on `model`'s residual (its [`Complementarity`]); `best` keeps the
/// iterate of the lowest residual seen; with `crawl`, the iteration stops where it crawls (see
/// [`newton`]) and sets it.
fn newton_min(
    model: &EnclosedModel,
    z0: Vec<f64>,
    opts: &EnclosedOptions,
    ended: &mut Ended,
    best: &mut (Vec<f64>, f64),
    mut crawl: Option<&mut bool>,
) -> Result<EnclosedState, SolverError> {
    let mut z = z0;
    let mut norm = f64::INFINITY;
    // Watchdog: (iterate, residual norm and Newton step before the nonmonotone step, the
    // iteration by which the residual must have dropped below that norm).
    let mut watch: Option<(Vec<f64>, f64, DVector<f64>, usize)> = None;
    let mut watch_left = opts.watchdog;
    let done = |z: Vec<f64>, iterations: usize, residual: f64| EnclosedState {
        model: model.clone(),
        z,
        iterations,
        residual,
    };
    // After a failed watchdog step: the Newton step at the restored iterate.
    let mut resume: Option<DVector<f64>> = None;
    let mut history: Vec<f64> = Vec::new();
    for it in 0..=opts.max_iterations {
        ended.iterations = it;
        let (residual, step) = match resume.take() {
            Some(dz) => (model.residual(&z)?, Err(dz)),
            None => match model.newton_step(&z) {
                Ok((f, dz)) => (f, Ok(Ok(dz))),
                Err(SolverError::SingularJacobian { .. }) => {
                    // The block factorisation cannot be trusted here: the dense Jacobian.
                    ended.dense += 1;
                    let ev = model.evaluate(&z)?;
                    let dz = ev.jacobian.lu().solve(&(-&ev.residual));
                    (
                        ev.residual,
                        Ok(dz.ok_or(SolverError::SingularJacobian { iteration: it })),
                    )
                }
                Err(e) => return Err(e),
            },
        };
        norm = model.residual_norm(&residual);
        if norm < best.1 {
            *best = (z.clone(), norm);
        }
        // The watchdog step paid off, or it is time to go back to where it was taken.
        let mut step = step;
        if let Some((_, wnorm, _, deadline)) = &watch {
            if norm.is_finite() && norm <= (1.0 - 1e-4) * wnorm {
                watch = None;
            } else if it >= *deadline || !norm.is_finite() {
                let (wz, wnorm, wdz, _) = watch.take().expect("watchdog state");
                z = wz;
                norm = wnorm;
                step = Err(wdz);
                watch_left = 0;
            }
        }
        if !norm.is_finite() {
            break;
        }
        // At least one step: a start that already meets the tolerance (a warm start a
        // hair away in L̄) is polished to round-off, so that energies of nearby solves
        // differ smoothly (the secant of the enclosed exchanges needs that).
        if norm < opts.tolerance && it > 0 {
            return Ok(done(z, it, norm));
        }
        if it == opts.max_iterations {
            ended.outcome = Outcome::Cap;
            break;
        }
        history.push(norm);
        let w = opts.stall_window;
        if w > 0
            && watch.is_none()
            && history.len() > w
            && norm > 0.5 * history[history.len() - 1 - w]
        {
            ended.outcome = Outcome::Stall;
            break;
        }
        // The line search crawls (see [`newton`]).
        if w == 0
            && crawl.is_some()
            && model.complementarity() == Complementarity::Min
            && watch.is_none()
            && history.len() > CRAWL_WINDOW
            && norm > 0.5 * history[history.len() - 1 - CRAWL_WINDOW]
        {
            if let Some(c) = crawl.as_deref_mut() {
                *c = true;
            }
            ended.outcome = Outcome::Stall;
            break;
        }
        let (dz, mut t) = match step {
            Ok(dz) => (dz?, 1.0),
            // The full step from this (restored) iterate failed before: from half of it.
            Err(dz) => (dz, 0.5),
        };
        let mut accepted = false;
        for k in 0..opts.max_backtracks {
            let zt: Vec<f64> = z.iter().zip(dz.iter()).map(|(a, b)| a + t * b).collect();
            if let Ok(f) = model.residual(&zt) {
                let nt = model.residual_norm(&f);
                if nt <= (1.0 - 1e-4 * t) * norm {
                    z = zt;
                    accepted = true;
                    // Round-off floor: a step that gains less than 10% on a residual
                    // already within 100× the tolerance (fine meshes, N ≥ 256).
                    if nt < 1e2 * opts.tolerance && nt > 0.9 * norm && model.cells() >= 256 {
                        return Ok(done(z, it + 1, nt));
                    }
                    break;
                }
                // A full step that changes the contact set is taken anyway (watchdog).
                if k == 0
                    && t == 1.0
                    && watch_left > 0
                    && watch.is_none()
                    && nt.is_finite()
                    && model.wall_active(&zt)? != model.wall_active(&z)?
                {
                    let prev = std::mem::replace(&mut z, zt);
                    watch = Some((prev, norm, dz.clone(), it + WATCHDOG_ITERATIONS));
                    watch_left -= 1;
                    accepted = true;
                    break;
                }
            }
            t *= 0.5;
        }
        if !accepted {
            if let Some((wz, wnorm, wdz, _)) = watch.take() {
                // The watchdog step led nowhere: back to it, and backtrack there.
                z = wz;
                norm = wnorm;
                resume = Some(wdz);
                watch_left = 0;
                continue;
            }
            // Round-off floor: accept a state that is already converged to near precision.
            if norm < 1e3 * opts.tolerance {
                return Ok(done(z, it, norm));
            }
            break;
        }
    }
    Err(SolverError::NewtonNotConverged {
        iterations: opts.max_iterations,
        residual: norm,
        closure: model
            .closure(&z)
            .map(|c| c.iter().map(|v| v * v).sum::<f64>().sqrt())
            .unwrap_or(f64::NAN),
    })
}

/// Semismooth Newton by a homotopy in the wall's allowed pull: a surface loop with
/// `λ_min < 0` satisfies the conditions of a wall that may pull up to `−λ_min`
/// ([`EnclosedModel::with_pull`]), so Newton starts at `pull = 1.1·(−λ_min)` next to a
/// solution and follows the pull down to 0 (the physical wall) in steps of an eighth of the
/// start, halving a failed step up to 12 times. For starts that plain Newton cannot bring
/// to the lifted-off state (sharp stiffness profiles, where the surface loop needs
/// `λ_min ≈ −100 D0/R³`).
pub fn solve_by_pull_homotopy(
    model: &EnclosedModel,
    z0: Vec<f64>,
    lambda_min: f64,
    opts: &EnclosedOptions,
) -> Result<EnclosedState, SolverError> {
    let top = 1.1 * (-lambda_min).max(0.0) + 1e-3;
    let state = solve_enclosed(&model.clone().with_pull(top)?, z0, opts)?;
    // The continuation crate's natural-parameter walk in the pull, from `top` to 0.
    let settings = NaturalSettings {
        max_step: top / 8.0,
        max_halvings: 12,
        arrive: 0.0,
        snap: 0.0,
    };
    rodloop_continuation::natural::walk(
        (state, top),
        None,
        0.0,
        |s: &(EnclosedState, f64)| s.1,
        &settings,
        |(cur, _), _, next, _| {
            let next = next.max(0.0);
            let m = model.clone().with_pull(next)?;
            Ok((solve_enclosed(&m, cur.z.clone(), opts)?, next))
        },
    )
    .map(|w| w.last.0)
    .map_err(|stuck| stuck.error)
}

/// The starting state built from a loop on the sphere: `κ1 = κ_g(σ)`, `κ2 = −1/R`, `r0 = R e3`
/// (the Darboux frame is rotation-minimising on a sphere; [`super::jet`]), multipliers by
/// least squares. The gauge takes this shape as reference; uniform rods get the arclength
/// phase condition.
pub fn start_from_surface<F: Fn(f64) -> f64>(
    wall: impl IntoWall,
    lbar: f64,
    cells: usize,
    stiffness: &Stiffness,
    kappa_g: F,
) -> Result<(EnclosedModel, Vec<f64>), SolverError> {
    let wall = wall.into_wall();
    let radius = wall.radius();
    start_from_curvature(
        wall,
        lbar,
        cells,
        stiffness,
        |s| (kappa_g(s), -1.0 / radius),
        [0.0, 0.0, radius],
    )
}

/// The starting state from curvature-vector functions `(κ1, κ2)(σ)` and a start point `r0`
/// (frame at `s = 0` the identity), multipliers by least squares; the gauge takes this
/// shape as reference (with the arclength phase condition for uniform rods).
pub fn start_from_curvature<F: Fn(f64) -> (f64, f64)>(
    wall: impl IntoWall,
    lbar: f64,
    cells: usize,
    stiffness: &Stiffness,
    kappa: F,
    r0: [f64; 3],
) -> Result<(EnclosedModel, Vec<f64>), SolverError> {
    let (model, mut z) =
        model_from_curvature(wall.into_wall(), lbar, cells, stiffness, &kappa, r0)?;
    start_multipliers(&model, &mut z, &kappa)?;
    Ok((model, z))
}

/// The model and shape of [`start_from_curvature`] with all multipliers 0.
fn model_from_curvature<F: Fn(f64) -> (f64, f64)>(
    wall: Arc<dyn Wall>,
    lbar: f64,
    cells: usize,
    stiffness: &Stiffness,
    kappa: F,
    r0: [f64; 3],
) -> Result<(EnclosedModel, Vec<f64>), SolverError> {
    let probe = EnclosedModel::new(
        &wall,
        lbar,
        cells,
        stiffness,
        Gauge {
            reference: vec![0.0; 4 * cells],
            slope: None,
            pin: None,
        },
    )?;
    let reference = probe.sample_gauss(kappa);
    let slope = if stiffness.is_uniform() && probe.uniform_mesh() {
        phase_slope(&reference, cells)?
    } else {
        None
    };
    let model = EnclosedModel::new(
        wall,
        lbar,
        cells,
        stiffness,
        Gauge {
            reference: reference.clone(),
            slope,
            pin: None,
        },
    )?;
    let mut z = vec![0.0; model.dim()];
    z[..4 * cells].copy_from_slice(&reference);
    z[4 * cells..4 * cells + 3].copy_from_slice(&r0);
    Ok((model, z))
}

/// Largest mesh on which starting multipliers come from the dense least-squares fit
/// ([`least_squares_multipliers`] forms the dense Jacobian, `O(N³)`); finer starts take them
/// from a fit at this many cells ([`transfer_multipliers`]).
pub const LEAST_SQUARES_MAX_CELLS: usize = 64;

/// Starting multipliers for the shape in `z` (curvature and start point set): the dense
/// least-squares fit up to [`LEAST_SQUARES_MAX_CELLS`] cells; above, the fit on that many
/// cells of the same curvature functions, carried over by [`transfer_multipliers`].
fn start_multipliers<F: Fn(f64) -> (f64, f64)>(
    model: &EnclosedModel,
    z: &mut [f64],
    kappa: F,
) -> Result<(), SolverError> {
    let n = model.cells();
    if n <= LEAST_SQUARES_MAX_CELLS {
        return least_squares_multipliers(model, z);
    }
    let r0 = model.start_point(z);
    let stiff = model.stiffness().kind().clone();
    let (cm, mut cz) = model_from_curvature(
        model.wall().clone(),
        model.lbar(),
        LEAST_SQUARES_MAX_CELLS,
        &stiff,
        kappa,
        [r0[0], r0[1], r0[2]],
    )?;
    least_squares_multipliers(&cm, &mut cz)?;
    transfer_multipliers(&cm, &cz, model, z);
    Ok(())
}

/// Carry the multipliers of `(from, zf)` over to `(to, zt)`: closure multipliers as they
/// are (resolution-independent), gauge multipliers 0, and the wall impulses through the
/// contact force density, interpolated linearly (periodically) in `σ` to the new nodes.
pub fn transfer_multipliers(from: &EnclosedModel, zf: &[f64], to: &EnclosedModel, zt: &mut [f64]) {
    let (npf, npt) = (from.n_primal(), to.n_primal());
    zt[npt..npt + 6].copy_from_slice(&zf[npf..npf + 6]);
    for k in 6..to.n_equalities() {
        zt[npt + k] = 0.0;
    }
    let dens = from.contact_force(zf);
    let nf = from.cells();
    let bf = from.bounds();
    let lo = to.lambda_offset();
    // The impulse that gives the interpolated density on the wall: `|∇g|` on the wall. A
    // prolonged node lies off the wall by its interpolation error; on the sphere the value on
    // the wall is `2R` everywhere, elsewhere the node's own `|∇g|` stands in for it.
    let grad = match to.wall().sphere() {
        Some(r) => vec![2.0 * r; to.cells()],
        None => to.wall_gradient_norms(zt),
    };
    for j in 0..to.cells() {
        let s = to.bounds()[j];
        // Coarse interval [bf[k], bf[k+1]) holding s.
        let k = bf[..nf].partition_point(|&b| b <= s).saturating_sub(1);
        let (a, b) = (bf[k], bf[k + 1]);
        let t = if b > a { (s - a) / (b - a) } else { 0.0 };
        let d = (1.0 - t) * dens[k] + t * dens[(k + 1) % nf];
        zt[lo + j] = if grad[j] > 0.0 {
            d * to.node_weight(j) / grad[j]
        } else {
            0.0
        };
    }
}

/// Branch 0: the planar circle of length `L = 2πR L̄` centred at the origin, free for
/// `L̄ < 1` (start point pinned: a free loop can translate), touching everywhere at `L̄ = 1`.
/// Exact in the discrete model (constant curvature: every Magnus step is an exact arc).
pub fn free_circle(
    wall: impl IntoWall,
    lbar: f64,
    cells: usize,
    stiffness: &Stiffness,
) -> Result<(EnclosedModel, Vec<f64>), SolverError> {
    let wall = wall.into_wall();
    let radius = wall.radius();
    if lbar > 1.0 + 1e-12 {
        return Err(SolverError::InvalidInput(format!(
            "the planar circle (branch 0) fits in the ball only for lbar <= 1 (got {lbar})"
        )));
    }
    let rho = radius * lbar;
    let reference: Vec<f64> = (0..2 * cells).flat_map(|_| [0.0, -1.0 / rho]).collect();
    let model = EnclosedModel::new(
        &wall,
        lbar,
        cells,
        stiffness,
        Gauge {
            reference: reference.clone(),
            slope: None,
            pin: Some([0.0, 0.0, rho]),
        },
    )?;
    let mut z = vec![0.0; model.dim()];
    z[..4 * cells].copy_from_slice(&reference);
    z[4 * cells + 2] = rho;
    if cells <= LEAST_SQUARES_MAX_CELLS {
        least_squares_multipliers(&model, &mut z)?;
    } else {
        let (cm, cz) = free_circle(&wall, lbar, LEAST_SQUARES_MAX_CELLS, stiffness)?;
        transfer_multipliers(&cm, &cz, &model, &mut z);
    }
    Ok((model, z))
}

impl EnclosedState {
    /// Energy `E R/(π D0)`.
    pub fn energy(&self) -> f64 {
        self.model.energy(&self.z).unwrap_or(f64::NAN)
    }

    /// Wall multipliers `λ_j`.
    pub fn multipliers(&self) -> &[f64] {
        let o = self.model.lambda_offset();
        &self.z[o..o + self.model.cells()]
    }

    /// First-order optimality: `(min λ_j, min g_j, max |λ_j g_j|, stationarity norm)` in
    /// units of the scene (`λ_j` as a force density `λ(s) R³/D0`, `g` as a gap `/R`).
    pub fn optimality(&self) -> Result<(f64, f64, f64, f64), SolverError> {
        let m = &self.model;
        let r = m.radius();
        let unit = r.powi(3) / m.stiffness().kind().reference();
        let force = m.contact_force(&self.z);
        let gaps = m.gaps(&self.z)?;
        let lmin = force.iter().fold(f64::INFINITY, |a, &b| a.min(b)) * unit;
        let gmin = gaps.iter().fold(f64::INFINITY, |a, &b| a.min(b)) / r;
        let comp = force
            .iter()
            .zip(&gaps)
            .map(|(l, g)| (l * unit * g / r).abs())
            .fold(0.0, f64::max);
        let f = m.residual(&self.z)?;
        let np = m.n_primal();
        let scales = m.residual_scales();
        let stat = (0..np).map(|i| scales[i] * f[i] * f[i]).sum::<f64>().sqrt();
        Ok((lmin, gmin, comp, stat))
    }

    /// Contact set, gaps and forces (`tol` on the gap in units of `R`).
    pub fn contact(&self, tol: f64) -> Result<Contact, SolverError> {
        let m = &self.model;
        let n = m.cells();
        let r = m.radius();
        let gaps = m.gaps(&self.z)?;
        let force = m.contact_force(&self.z);
        let unit = r.powi(3) / m.stiffness().kind().reference();
        let touch: Vec<bool> = gaps.iter().map(|g| *g / r <= tol).collect();
        let total: f64 = (0..n).map(|j| m.node_weight(j)).sum();
        let fraction = (0..n)
            .filter(|&j| touch[j])
            .map(|j| m.node_weight(j))
            .sum::<f64>()
            / total
            + 0.0;
        let sigma = |j: usize| m.bounds()[j];
        // Runs are counted at the mesh's resolution: a stretch of at most `JOIN_NODES` free
        // nodes between touching neighbours, all within `JOIN_GAP` R of the wall, does not
        // split a run. (On fine meshes the concentrated force at a contact end shows as a
        // touching pair one to three nodes past the arc, the nodes between lifted by
        // 1e-8–5e-8 R: the figure-eight at L̄ = 1.3, N = 384, counted six runs for two arcs.)
        const JOIN_NODES: usize = 3;
        const JOIN_GAP: f64 = 1e-6;
        let mut joined = touch.clone();
        if let Some(s0) = touch.iter().position(|&t| t) {
            // Sweep from a touching node so that free stretches do not wrap.
            let mut k = 1;
            while k < n {
                let j = (s0 + k) % n;
                if touch[j] {
                    k += 1;
                    continue;
                }
                let len = (k..n).take_while(|&q| !touch[(s0 + q) % n]).count();
                let shallow = (k..k + len).all(|q| gaps[(s0 + q) % n] / r <= JOIN_GAP);
                if len <= JOIN_NODES && shallow {
                    for q in k..k + len {
                        joined[(s0 + q) % n] = true;
                    }
                }
                k += len;
            }
        }
        let mut runs = Vec::new();
        if joined.iter().all(|&t| t) {
            runs.push((0.0, 1.0));
        } else if joined.iter().any(|&t| t) {
            // Start the sweep at a free node so that runs do not wrap.
            let s0 = joined.iter().position(|&t| !t).unwrap_or(0);
            let mut start: Option<usize> = None;
            for k in 1..=n {
                let j = (s0 + k) % n;
                match (joined[j], start) {
                    (true, None) => start = Some(j),
                    (false, Some(a)) => {
                        let b = (j + n - 1) % n;
                        runs.push((sigma(a), sigma(b)));
                        start = None;
                    }
                    _ => {}
                }
            }
            if let Some(a) = start {
                runs.push((sigma(a), sigma((s0 + n) % n)));
            }
        }
        let (mut gmax, mut at) = (f64::NEG_INFINITY, 0.0);
        for (j, g) in gaps.iter().enumerate() {
            if *g > gmax {
                gmax = *g;
                at = sigma(j);
            }
        }
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for j in 0..n {
            if touch[j] {
                lo = lo.min(force[j] * unit);
                hi = hi.max(force[j] * unit);
            }
        }
        if lo > hi {
            (lo, hi) = (0.0, 0.0);
        }
        Ok(Contact {
            fraction,
            intervals: runs.len(),
            runs,
            max_gap: (gmax / r, at),
            lambda_range: (lo, hi),
        })
    }

    /// The scaling `s_i = 1/√m_i` of the primal unknowns by their mass (node length share
    /// `h/2` for a curvature unknown, `L/R²` for the start point).
    pub(crate) fn mass_scaling(&self) -> Vec<f64> {
        let m = &self.model;
        let n = m.cells();
        (0..m.n_primal())
            .map(|a| {
                let mass = if a < 4 * n {
                    0.5 * m.cell_length(a / 4)
                } else {
                    m.length() / (m.radius() * m.radius())
                };
                1.0 / mass.sqrt()
            })
            .collect()
    }

    /// The blocks of the mass-scaled KKT matrix on the active set: `W = S ∇²ℒ S` (primal ×
    /// primal, symmetric) and the rows `B = ∇c S` of the closure, the gauges and the
    /// strongly active wall constraints (`λ_j > tol·max λ`), `S = diag(s)` of
    /// [`Self::mass_scaling`].
    pub(crate) fn scaled_kkt_blocks(
        &self,
        tol: f64,
    ) -> Result<(DMatrix<f64>, DMatrix<f64>), SolverError> {
        let m = &self.model;
        let np = m.n_primal();
        let n = m.cells();
        let ev = m.evaluate(&self.z)?;
        let lam = self.multipliers();
        let lmax = lam.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        let s = self.mass_scaling();
        let w = DMatrix::from_fn(np, np, |i, j| ev.jacobian[(i, j)] * s[i] * s[j]);
        let lo = m.lambda_offset();
        let mut rows: Vec<usize> = (np..lo).collect();
        for j in 0..n {
            if lam[j] > tol * lmax.max(1e-300) {
                rows.push(lo + j);
            }
        }
        // Constraint gradients are the (negated) columns ∂F_x/∂y.
        let a = DMatrix::from_fn(rows.len(), np, |r, i| ev.jacobian[(i, rows[r])] * s[i]);
        Ok((w, a))
    }

    /// The mass-scaled Hessian of the Lagrangian on the tangent space of the closure, the
    /// gauges and the strongly active wall constraints (`λ_j > tol·max λ`), as the symmetric
    /// matrix `P W P + β (I − P)` (`β` above every tangent eigenvalue, so the complement's
    /// eigenvalues sit apart), and the scaling `s_i = 1/√m_i` that maps its eigenvectors back
    /// to the primal unknowns. Shared by [`EnclosedState::stability`] and
    /// [`super::unstable_direction`].
    pub(crate) fn tangent_hessian(
        &self,
        tol: f64,
    ) -> Result<(DMatrix<f64>, Vec<f64>), SolverError> {
        let (w, a) = self.scaled_kkt_blocks(tol)?;
        let s = self.mass_scaling();
        let np = w.nrows();
        let svd = a.svd(false, true);
        let vt = svd.v_t.ok_or(SolverError::InvalidInput("svd".into()))?;
        let smax = svd.singular_values.iter().fold(0.0f64, |x, &y| x.max(y));
        // Orthonormal basis V of the constraint gradients' span (rank-revealing SVD); the
        // projector onto the tangent space is P = I − V Vᵀ.
        let keep: Vec<usize> = (0..svd.singular_values.len())
            .filter(|&k| svd.singular_values[k] > 1e-10 * smax)
            .collect();
        let v = DMatrix::from_fn(np, keep.len(), |i, k| vt[(keep[k], i)]);
        let wmax = w.amax();
        let beta = 10.0 * wmax + 1.0;
        // P W P + β (I − P) = W − V(WV)ᵀ − (WV)Vᵀ + V(VᵀWV + β)Vᵀ (W symmetric), in
        // O(N² rank) instead of two dense N³ products; β moves the complement of the
        // tangent space above every tangent eigenvalue.
        let wv = &w * &v;
        let mut t = v.transpose() * &wv;
        for k in 0..keep.len() {
            t[(k, k)] += beta;
        }
        let pw = &w - &v * wv.transpose() - &wv * v.transpose() + &v * (t * v.transpose());
        Ok((pw, s))
    }

    /// Stability: the index ([`Self::index`], from the inertia of the bordered KKT matrix)
    /// and the lowest eigenvalues (ascending, mass-normalised) of the Hessian of the
    /// Lagrangian on the tangent space of the closure, the gauges and the strongly active
    /// wall constraints (`λ_j > tol·max λ`), at most 8. Symmetry modes are removed by the
    /// gauges. The eigenvalues come from a dense symmetric eigen-decomposition, `O(N³)`:
    /// callers that need only the index call [`Self::index`].
    pub fn stability(&self, tol: f64) -> Result<(usize, Vec<f64>), SolverError> {
        let (pw, _) = self.tangent_hessian(tol)?;
        let mut vals: Vec<f64> = pw.symmetric_eigenvalues().iter().copied().collect();
        vals.sort_by(f64::total_cmp);
        vals.truncate(8);
        Ok((self.index(tol)?, vals))
    }

    /// The curvature vector `(κ1, κ2)` at `σ`, interpolated (four-point Lagrange through the
    /// nearest Gauss points, error `O(h⁴)`): a start for another resolution. Across the
    /// closing node the components are continued with the holonomy: the frame comes back
    /// turned by `α` about the tangent ([`super::model::TWIST_ROW`]), so a smooth loop has
    /// `κ(σ + 1) = R(−α) κ(σ)` in components, and values of the other lap are turned into
    /// the frame continued from this one before they enter the stencil.
    pub fn curvature_at(&self, sigma: f64) -> (f64, f64) {
        let m = &self.model;
        let ng = 2 * m.cells();
        let sig: Vec<f64> = (0..ng).map(|g| m.gauss_sigma(g)).collect();
        let s = sigma.rem_euclid(1.0);
        // First Gauss point at or after s (periodically).
        let k = sig.iter().position(|&x| x >= s).unwrap_or(ng);
        let z = &self.z;
        // The end frame's normals in the start frame (the identity): (cos α, sin α) and
        // (−sin α, cos α).
        let (ca, sa) = match m.transforms(z) {
            Ok(p) => {
                let x = &p[m.cells()];
                let a = (x[(2, 1)] - x[(1, 2)]).atan2(x[(1, 1)] + x[(2, 2)]);
                (a.cos(), a.sin())
            }
            Err(_) => (1.0, 0.0),
        };
        let mut out = (0.0, 0.0);
        let idx: Vec<(usize, f64, isize)> = (0..4)
            .map(|q| {
                let raw = k as isize + q as isize - 2;
                let wraps = raw.div_euclid(ng as isize);
                let g = raw.rem_euclid(ng as isize) as usize;
                (g, sig[g] + wraps as f64, wraps)
            })
            .collect();
        for (q, &(g, xq, wraps)) in idx.iter().enumerate() {
            let mut l = 1.0;
            for (p, &(_, xp, _)) in idx.iter().enumerate() {
                if p != q {
                    l *= (s - xp) / (xq - xp);
                }
            }
            let (k1, k2) = (z[2 * g], z[2 * g + 1]);
            // One lap back: end-frame components into the frame continued backwards from
            // the start, R(α) κ; one lap on: R(−α) κ.
            let (k1, k2) = match wraps {
                w if w < 0 => (ca * k1 - sa * k2, sa * k1 + ca * k2),
                w if w > 0 => (ca * k1 + sa * k2, -sa * k1 + ca * k2),
                _ => (k1, k2),
            };
            out.0 += l * k1;
            out.1 += l * k2;
        }
        out
    }

    /// Prolong this state to `2N` cells: curvature by [`Self::curvature_at`], the same start
    /// point and closure multipliers, the contact force density carried over node by node
    /// (coarse nodes are every other fine node; new nodes take the mean of their neighbours).
    pub fn refine(&self) -> Result<(EnclosedModel, Vec<f64>), SolverError> {
        let m = &self.model;
        let n = m.cells();
        let r0 = m.start_point(&self.z);
        let stiff = m.stiffness().kind().clone();
        let (fine, mut z) = model_from_curvature(
            m.wall().clone(),
            m.lbar(),
            2 * n,
            &stiff,
            |s| self.curvature_at(s),
            [r0[0], r0[1], r0[2]],
        )?;
        transfer_multipliers(m, &self.z, &fine, &mut z);
        Ok((fine, z))
    }

    /// Node positions `(σ, r)`.
    pub fn nodes(&self) -> Result<Vec<(f64, Vector3<f64>)>, SolverError> {
        let pos = self.model.positions(&self.z)?;
        Ok(pos
            .into_iter()
            .enumerate()
            .map(|(j, r)| (self.model.bounds()[j], r))
            .collect())
    }

    /// Curvature vector `(κ1, κ2)` at node `j`: the linear extrapolations from the two
    /// adjacent cells' Gauss points, averaged.
    pub fn node_curvature(&self, j: usize) -> (f64, f64) {
        let n = self.model.cells();
        let z = &self.z;
        let g1 = crate::model::GAUSS_OFFSETS[0];
        let g2 = crate::model::GAUSS_OFFSETS[1];
        let ext = |c: usize, at: f64| -> (f64, f64) {
            let t = (at - g1) / (g2 - g1);
            (
                z[4 * c] + t * (z[4 * c + 2] - z[4 * c]),
                z[4 * c + 1] + t * (z[4 * c + 3] - z[4 * c + 1]),
            )
        };
        let (a1, a2) = ext(j % n, 0.0);
        let (mut b1, mut b2) = ext((j + n - 1) % n, 1.0);
        let (mut a1, mut a2) = (a1, a2);
        // At the closing node the two cells' components are in frames that differ by a turn
        // about the tangent (the frame need not return: no twisting moment, `TWIST_ROW`):
        // express both in the frame of the node's own end before averaging.
        if j % n == 0 {
            if let Ok(x) = self.model.transforms(z) {
                let col = |m: &nalgebra::Matrix4<f64>, c: usize| {
                    nalgebra::Vector3::new(m[(0, c)], m[(1, c)], m[(2, c)])
                };
                let (d1s, d2s) = (col(&x[0], 1), col(&x[0], 2));
                let (d1e, d2e) = (col(&x[n], 1), col(&x[n], 2));
                if j == 0 {
                    // The last cell's end components into the start frame.
                    let v = d1e * b1 + d2e * b2;
                    (b1, b2) = (v.dot(&d1s), v.dot(&d2s));
                } else {
                    // The first cell's start components into the end frame.
                    let v = d1s * a1 + d2s * a2;
                    (a1, a2) = (v.dot(&d1e), v.dot(&d2e));
                }
            }
        }
        (0.5 * (a1 + b1), 0.5 * (a2 + b2))
    }
}

/// Energy of the free planar circle of length `2πR L̄`, `E R/(πD) = 1/L̄`.
pub fn free_circle_energy(lbar: f64) -> f64 {
    let _ = PI;
    1.0 / lbar
}
