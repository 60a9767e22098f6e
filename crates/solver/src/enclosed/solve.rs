//! Semismooth Newton on the enclosed KKT system and its starting shapes (surface loop,
//! curvature profile, free circle; the multipliers carried between meshes are in
//! `super::carry`); what is read off a converged state is in [`super::state`].
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
use std::time::Instant;

use nalgebra::{DMatrix, DVector};
use rodloop_continuation::natural::NaturalSettings;

use super::model::{Complementarity, EnclosedModel, Gauge};
use super::stats::{self, Outcome};
use super::wall::IntoWall;
use crate::stiffness::Stiffness;
use crate::SolverError;

use super::carry::model_from_curvature;
pub use super::carry::transfer_multipliers;
pub use super::state::{Contact, EnclosedState};

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

/// Newton iterations of one continuation step (in `L̄`, in the stiffness) and of one snap
/// past a fold of the stiffness path, in each form of the complementarity: a step that
/// needs more is retried shorter by its walk, and a snap that needs more is one of eight
/// tried, which is cheaper than letting Newton crawl on. Most steps take 2–6; with 12,
/// steps that were converging slowly (residuals 1e-8) stopped the diagram's traces; with the
/// default 80 a failing step costs 2.7 times as much.
pub const STEP_ITERATIONS: usize = 30;

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

/// [`solve_enclosed`] from a start prolonged from another mesh (its contact ends a node or
/// two off): up to two full steps that change the contact set are taken even where the
/// residual grows (the watchdog, at least 2), instead of crawling there in short steps; where
/// that solve fails, plain backtracking from the same start (unless `opts` has the watchdog
/// already, which would repeat the same solve). On the figure-eight at `L̄ = 1.36–1.45`,
/// `N = 128–512`, the finest level of a cascade takes 3–7 iterations instead of 4–18.
pub fn solve_prolonged(
    model: &EnclosedModel,
    z0: Vec<f64>,
    opts: &EnclosedOptions,
) -> Result<EnclosedState, SolverError> {
    let watchdog = EnclosedOptions {
        watchdog: opts.watchdog.max(2),
        ..opts.clone()
    };
    solve_enclosed(model, z0.clone(), &watchdog).or_else(|e| {
        if watchdog.watchdog == opts.watchdog {
            Err(e)
        } else {
            solve_enclosed(model, z0, opts)
        }
    })
}

/// Iterations in a row that do not halve the residual before semismooth Newton on the
/// min-function hands over to Fischer–Burmeister (`newton`).
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
/// min-function goes on from where the crawl stopped it, without the stop (some crawls end
/// in convergence).
fn newton(
    model: &EnclosedModel,
    z0: Vec<f64>,
    opts: &EnclosedOptions,
    ended: &mut Ended,
) -> Result<EnclosedState, SolverError> {
    let mut best: (Vec<f64>, f64) = (z0.clone(), f64::INFINITY);
    let mut crawled: Option<Paused> = None;
    if !opts.hand_over {
        return newton_min(model, z0, opts, ended, &mut best, None, None);
    }
    let out = newton_min(model, z0, opts, ended, &mut best, Some(&mut crawled), None);
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
    let res = newton_min(&fb, best.0, &fopts, &mut inner, &mut fbest, None, None);
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
        // Where the crawl stopped the min-function early, it goes on from where it stopped
        // without the stop (some crawls end in convergence): the same iterates as a run
        // from the start without the stop, whose first iterations it does not repeat.
        Err(_) if crawled.is_some() => {
            let paused = crawled.take().expect("crawl state");
            let mut again = (paused.z.clone(), f64::INFINITY);
            newton_min(
                model,
                Vec::new(),
                opts,
                ended,
                &mut again,
                None,
                Some(paused),
            )
        }
        Err(_) => out,
    }
}

/// Where [`newton_min`] stopped at a crawl: the iterate, the iteration, the residual norms
/// before it and the watchdog steps left (no watchdog step is pending at a crawl stop), so
/// that the iteration can go on from there as if it had not stopped.
struct Paused {
    z: Vec<f64>,
    iteration: usize,
    history: Vec<f64>,
    watch_left: usize,
}

/// Damped semismooth Newton on `model`'s residual (its [`Complementarity`]); `best` keeps the
/// iterate of the lowest residual seen; with `crawl`, the iteration stops where it crawls (see
/// [`newton`]) and leaves there its state; with `paused`, it goes on from such a state
/// (`z0` unused).
fn newton_min(
    model: &EnclosedModel,
    z0: Vec<f64>,
    opts: &EnclosedOptions,
    ended: &mut Ended,
    best: &mut (Vec<f64>, f64),
    mut crawl: Option<&mut Option<Paused>>,
    paused: Option<Paused>,
) -> Result<EnclosedState, SolverError> {
    let (mut z, first, mut history, mut watch_left) = match paused {
        Some(p) => (p.z, p.iteration, p.history, p.watch_left),
        None => (z0, 0, Vec::new(), opts.watchdog),
    };
    let mut norm = f64::INFINITY;
    // Watchdog: (iterate, residual norm and Newton step before the nonmonotone step, the
    // iteration by which the residual must have dropped below that norm).
    let mut watch: Option<(Vec<f64>, f64, DVector<f64>, usize)> = None;
    let done = |z: Vec<f64>, iterations: usize, residual: f64| EnclosedState {
        model: model.clone(),
        z,
        iterations,
        residual,
    };
    // After a failed watchdog step: the Newton step at the restored iterate.
    let mut resume: Option<DVector<f64>> = None;
    for it in first..=opts.max_iterations {
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
                history.pop();
                *c = Some(Paused {
                    z: z.clone(),
                    iteration: it,
                    history: std::mem::take(&mut history),
                    watch_left,
                });
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
                    // already within 100× the tolerance (fine meshes).
                    if nt < 1e2 * opts.tolerance
                        && nt > 0.9 * norm
                        && model.cells() >= ROUND_OFF_CELLS
                    {
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
            // On a coarser mesh a stalled line search above the tolerance is a kink of the
            // min-function, not round-off: accepted only where every node is inside the
            // wall ([`inside_wall`]), otherwise handed over like any failed solve.
            if norm < 1e3 * opts.tolerance
                && (model.cells() >= ROUND_OFF_CELLS || inside_wall(model, &z)?)
            {
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

/// Meshes from which the residual of a converged state can stall above the tolerance at
/// round-off (the wall rows then hold to about that residual: a gap of `−1.5·10⁻⁸ R` at 384
/// cells, `crates/diagram/tests/enclosed_twoseg_exchange.rs`).
const ROUND_OFF_CELLS: usize = 256;

/// `true` where no node of `z` lies outside the wall by more than the verification's
/// [`crate::verify::POSITION_SLACK`]` R`: below [`ROUND_OFF_CELLS`] the round-off floor of
/// [`newton_min`] accepts a residual above the tolerance only for such a state (the
/// min-function's line search can stall at a kink with a node `1.8·10⁻⁷ R` outside at a
/// residual of `6·10⁻⁸`, 128 cells).
fn inside_wall(model: &EnclosedModel, z: &[f64]) -> Result<bool, SolverError> {
    let slack = crate::verify::POSITION_SLACK * model.radius();
    Ok(model.gaps(z)?.iter().all(|&g| g >= -slack))
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

/// Energy of the free planar circle of length `2πR L̄`, `E R/(πD) = 1/L̄`.
pub fn free_circle_energy(lbar: f64) -> f64 {
    let _ = PI;
    1.0 / lbar
}
