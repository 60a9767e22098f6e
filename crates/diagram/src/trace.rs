//! Tracing one branch: seed, pseudo-arclength continuation in `L̄`, the approach to the
//! great-circle ends, and the quantities of every traced state.
//!
//! # Resolution and scaling
//!
//! Branch `η` is traced with `N = c (η + 1)` cells ([`DiagramOptions::trace_cells`]).
//! The continuation runs on the KKT state with the curvature unknowns scaled by `R/√(2N)`
//! (so that the Euclidean norm of the curvature part is the root-mean-square of `κ_g R`):
//! step sizes are then independent of the resolution, and a coarse and a fine trace take
//! comparable steps.
//!
//! # Ends
//!
//! Near an end `L̄ → m` on the m-fold great circle the branch is a half pitchfork: the
//! amplitude of `κ_g` behaves like `a = √|L̄ − m|`, the continuation curve turns back through
//! the great circle onto the mirror image of the branch, and the KKT matrix becomes
//! singular. The pseudo-arclength run therefore stops `0.01` from `m` (and any point past a
//! turning point of `L̄` is dropped), and the last stretch is done by Newton's method at
//! `L̄ = m ± a²` with `a` halved at every step, from a predictor polynomial in `a` (in which
//! the branch is regular), down to [`DiagramOptions::end_distance`] from `m`. The reason for
//! stopping is recorded for each end ([`BranchEnd`], [`TracedBranch::stop_low`]).

use std::f64::consts::PI;
use std::time::Instant;

use nalgebra::{DMatrix, DVector};
use rodloop_continuation::{
    Continuation, Direction, Problem, PseudoArclength, SpecialKind, StopReason,
};
use rodloop_exact::branch_of_eta;
use rodloop_solver::{
    solve, solve_from_state, Equilibrium, Globalization, LbarProblem, Phase, SolveOptions,
    SolverError, StartShape, SurfaceModel,
};
use serde::{Deserialize, Serialize};

use crate::{DiagramError, DiagramOptions, Progress};

/// Threshold below which an eigenvalue (units of `D0`) counts as negative (the solver's
/// default, [`rodloop_solver::StabilityOptions`]).
const INDEX_TOLERANCE: f64 = 1e-6;

/// Distance from a great-circle end at which the pseudo-arclength run hands over to the
/// end approach.
const SWITCH_DISTANCE: f64 = 0.05;

/// Continuation steps per run; runs are chained until an end, a turning point or the budget.
const CHUNK: usize = 25;

/// Budget of continuation steps per direction.
const MAX_STEPS_PER_SIDE: usize = 1000;

/// How one end of a traced branch came about.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum BranchEnd {
    /// The branch ends on the `m`-fold great circle at `L̄ = m`; tracing stopped at `lbar`,
    /// `distance = |lbar − m|` from it.
    GreatCircle {
        /// Turns of the great circle.
        m: u32,
        /// Last traced length.
        lbar: f64,
        /// `|lbar − m|`.
        distance: f64,
    },
    /// Tracing stopped at the end of the diagram's range.
    Range {
        /// `lbar_min` or `lbar_max`.
        lbar: f64,
    },
    /// Tracing stopped before its target.
    Failed {
        /// Last traced length.
        lbar: f64,
        /// Where it should have stopped.
        target: f64,
        /// Why it stopped.
        reason: String,
    },
}

impl BranchEnd {
    /// Last traced length at this end.
    pub fn lbar(&self) -> f64 {
        match self {
            BranchEnd::GreatCircle { lbar, .. }
            | BranchEnd::Range { lbar }
            | BranchEnd::Failed { lbar, .. } => *lbar,
        }
    }

    /// The great circle `m` on which the branch ends here, if it does.
    pub fn great_circle(&self) -> Option<u32> {
        match self {
            BranchEnd::GreatCircle { m, .. } => Some(*m),
            _ => None,
        }
    }
}

/// How a traced state was obtained.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PointSource {
    /// The seed (Euler rotation curve, relaxed and solved).
    Seed,
    /// A pseudo-arclength continuation step.
    Continuation,
    /// A located change of the stability index.
    IndexChange,
    /// A Newton solve of the approach to a great-circle end.
    EndApproach,
}

/// One traced state.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TracedPoint {
    /// Normalised length `L̄`.
    pub lbar: f64,
    /// Energy `E R/(π D0)`: Richardson extrapolation of the tracing resolution `N` and `N/2`
    /// (the value at `N` if the `N/2` solve failed, or if `N/2` cells do not resolve the
    /// stiffness profile).
    pub energy: f64,
    /// Geodesic part `E_g R/(π D0)` (extrapolated like `energy`).
    pub energy_g: f64,
    /// Estimated error of `energy`: `|E_N − E_{N/2}|/15`, the error estimate of `E_N` (a
    /// conservative bound for the extrapolated value); `None` if the `N/2` solve failed.
    pub energy_error: Option<f64>,
    /// Energy at the tracing resolution itself.
    pub energy_trace: f64,
    /// `dE/dL̄` along the branch (normalised like `energy`), from the multiplier:
    /// `dE/dL̄ = ∂ℒ/∂L̄ = E/L̄ + μ·∂(−c)/∂L̄` (tracing resolution).
    pub slope: f64,
    /// Stability index (number of negative eigenvalues of the constrained Hessian).
    pub index: usize,
    /// Minimum of the contact force `λR³/D0` over the loop (extrapolated like `energy`).
    pub lambda_min: f64,
    /// Maximum of the contact force `λR³/D0` over the loop.
    pub lambda_max: f64,
    /// `max |κ_g R|` (tracing resolution).
    pub amplitude: f64,
    /// How the state was obtained.
    pub source: PointSource,
    /// KKT state `(κ, μ, ν)` at the tracing resolution ([`TracedBranch::cells`] cells).
    pub state: Vec<f64>,
}

/// A located change of the stability index along a branch.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct IndexChange {
    /// Where it happens.
    pub lbar: f64,
    /// Index below `lbar`.
    pub below: usize,
    /// Index above `lbar`.
    pub above: usize,
}

/// A traced branch (serialisable: the CLI writes one file per finished branch and passes
/// them back to [`crate::compute`] to resume).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TracedBranch {
    /// Paper branch number ([`rodloop_exact::branch_of_eta`]).
    pub branch: u32,
    /// Periods of `κ_g`.
    pub eta: u32,
    /// [`DiagramOptions::fingerprint`] of the options it was traced with.
    pub fingerprint: String,
    /// Tracing resolution (cells).
    pub cells: usize,
    /// Whether the states carry a phase multiplier (uniform stiffness).
    pub phase: bool,
    /// Traced states in increasing `L̄`.
    pub points: Vec<TracedPoint>,
    /// How the lower end came about.
    pub low_end: BranchEnd,
    /// How the upper end came about.
    pub high_end: BranchEnd,
    /// Where and why the lower end stopped (human-readable).
    pub stop_low: String,
    /// Where and why the upper end stopped (human-readable).
    pub stop_high: String,
    /// How the branch was seeded.
    pub seed: String,
    /// Located changes of the stability index.
    pub index_changes: Vec<IndexChange>,
    /// Continuation steps taken (both directions).
    pub steps: usize,
    /// Wall time of the tracing in seconds.
    pub seconds: f64,
    /// Where that time went.
    pub timings: BranchTimings,
}

/// Wall times of the phases of [`compute_branch`], in seconds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BranchTimings {
    /// Seed: Euler curve, relaxation, Newton.
    pub seed: f64,
    /// Pseudo-arclength runs, including the stability index at every point.
    pub continuation: f64,
    /// Newton solves approaching the great-circle ends (with their stability indices).
    pub end_approach: f64,
    /// Quantities of the traced states (re-solve, half-resolution partner, forces).
    pub states: f64,
}

impl TracedBranch {
    /// Range `(first, last)` of the traced lengths.
    pub fn span(&self) -> (f64, f64) {
        (
            self.points.first().map_or(f64::NAN, |p| p.lbar),
            self.points.last().map_or(f64::NAN, |p| p.lbar),
        )
    }

    /// Whether `lbar` lies within the traced lengths.
    pub fn covers(&self, lbar: f64) -> bool {
        let (a, b) = self.span();
        lbar >= a && lbar <= b
    }

    /// Energy at `lbar` by cubic Hermite interpolation of the traced energies and slopes
    /// (`None` outside the traced span).
    pub fn energy_at(&self, lbar: f64) -> Option<f64> {
        if !self.covers(lbar) {
            return None;
        }
        let k = self
            .points
            .partition_point(|p| p.lbar <= lbar)
            .clamp(1, self.points.len().max(2) - 1);
        if self.points.len() == 1 {
            return Some(self.points[0].energy);
        }
        let (p0, p1) = (&self.points[k - 1], &self.points[k]);
        let h = p1.lbar - p0.lbar;
        if h <= 0.0 {
            return Some(p0.energy);
        }
        let t = (lbar - p0.lbar) / h;
        let (h00, h10, h01, h11) = (
            (1.0 + 2.0 * t) * (1.0 - t) * (1.0 - t),
            t * (1.0 - t) * (1.0 - t),
            t * t * (3.0 - 2.0 * t),
            t * t * (t - 1.0),
        );
        Some(h00 * p0.energy + h10 * h * p0.slope + h01 * p1.energy + h11 * h * p1.slope)
    }

    /// The model of the tracing resolution at `lbar`, with a phase condition taken from
    /// `state` (uniform stiffness) so that `state` satisfies it exactly.
    pub(crate) fn model_for(
        &self,
        opts: &DiagramOptions,
        lbar: f64,
        state: &[f64],
    ) -> Result<SurfaceModel, SolverError> {
        model_with_phase(opts, lbar, self.cells, &state[..2 * self.cells])
    }

    /// Linear interpolation of the traced states at `lbar` (nearest end outside the span;
    /// empty for a branch without states).
    pub(crate) fn state_near(&self, lbar: f64) -> Vec<f64> {
        let pts = &self.points;
        let k = pts.partition_point(|p| p.lbar <= lbar);
        if pts.is_empty() {
            return Vec::new();
        }
        if k == 0 {
            return pts[0].state.clone();
        }
        if k >= pts.len() {
            return pts[pts.len() - 1].state.clone();
        }
        let (a, b) = (&pts[k - 1], &pts[k]);
        let t = if b.lbar > a.lbar {
            (lbar - a.lbar) / (b.lbar - a.lbar)
        } else {
            0.0
        };
        a.state
            .iter()
            .zip(&b.state)
            .map(|(x, y)| x + t * (y - x))
            .collect()
    }

    /// The equilibrium of this branch at `lbar` at the tracing resolution (Newton from the
    /// interpolated traced states).
    pub fn solve_at(&self, opts: &DiagramOptions, lbar: f64) -> Result<Equilibrium, SolverError> {
        let z = self.state_near(lbar);
        let dim = 2 * self.cells + 3 + usize::from(self.phase);
        if z.len() != dim {
            return Err(SolverError::WrongLength {
                expected: dim,
                found: z.len(),
            });
        }
        let model = self.model_for(opts, lbar, &z)?;
        solve_from_state(model, z, &newton_options())
    }
}

/// A model at `lbar` with `cells` cells and, for uniform stiffness, the phase condition of
/// the reference `kappa` (Gauss values).
pub(crate) fn model_with_phase(
    opts: &DiagramOptions,
    lbar: f64,
    cells: usize,
    kappa: &[f64],
) -> Result<SurfaceModel, SolverError> {
    let model = SurfaceModel::new(opts.radius, lbar, cells, &opts.stiffness)?;
    if opts.stiffness.is_uniform() {
        model.with_phase(Phase::from_gauss_values(kappa, cells)?)
    } else {
        Ok(model)
    }
}

/// Newton options for re-solving known states.
pub(crate) fn newton_options() -> SolveOptions {
    SolveOptions {
        globalization: Globalization::Newton,
        max_iterations: 30,
        ..SolveOptions::default()
    }
}

/// `dE/dL̄` along the branch at the KKT state `z` (normalised as `E R/(π D0)`):
/// `dE/dL̄ = ∂E/∂L̄ + ∇E·κ̇ = E/L̄ + μ·(∂(−c)/∂L̄)`, because `∇E = ∇cᵀμ + ν∇φ`,
/// `∇c κ̇ = −∂c/∂L̄` and `∇φ κ̇ = 0` (the phase condition does not depend on `L̄`).
pub(crate) fn energy_slope(model: &SurfaceModel, z: &[f64]) -> Result<f64, SolverError> {
    let (kappa, mu, _) = model.split(z)?;
    let e = model.energy(kappa)?;
    let d = model.kkt_dlbar(z)?;
    let nk = model.n_kappa();
    let de = e / model.lbar() + mu[0] * d[nk] + mu[1] * d[nk + 1] + mu[2] * d[nk + 2];
    Ok(de * model.radius() / (PI * model.stiffness().kind().reference()))
}

/// The KKT problem in `L̄` with the curvature unknowns scaled by `s = R/√(2N)`. Evaluation
/// errors (non-finite iterates) become NaN residuals, so that the continuation shrinks its
/// step instead of aborting.
struct Scaled<'a> {
    inner: &'a LbarProblem,
    nk: usize,
    s: f64,
}

impl Scaled<'_> {
    fn unscale(&self, xt: &DVector<f64>) -> DVector<f64> {
        let mut x = xt.clone();
        x.rows_mut(0, self.nk).scale_mut(1.0 / self.s);
        x
    }

    fn scale(&self, x: &[f64]) -> DVector<f64> {
        let mut xt = DVector::from_column_slice(x);
        xt.rows_mut(0, self.nk).scale_mut(self.s);
        xt
    }
}

impl Problem for Scaled<'_> {
    type Error = SolverError;

    fn dim(&self) -> usize {
        self.inner.dim()
    }

    fn residual(&self, x: &DVector<f64>, p: f64) -> Result<DVector<f64>, SolverError> {
        Ok(self
            .inner
            .residual(&self.unscale(x), p)
            .unwrap_or_else(|_| DVector::from_element(x.len(), f64::NAN)))
    }

    fn jacobian(&self, x: &DVector<f64>, p: f64) -> Result<DMatrix<f64>, SolverError> {
        Ok(match self.inner.jacobian(&self.unscale(x), p) {
            Ok(mut j) => {
                j.columns_mut(0, self.nk).scale_mut(1.0 / self.s);
                j
            }
            Err(_) => DMatrix::from_element(x.len(), x.len(), f64::NAN),
        })
    }

    fn dparam(&self, x: &DVector<f64>, p: f64) -> Result<DVector<f64>, SolverError> {
        Ok(self
            .inner
            .dparam(&self.unscale(x), p)
            .unwrap_or_else(|_| DVector::from_element(x.len(), f64::NAN)))
    }
}

/// What one end of the branch aims at.
#[derive(Clone, Copy, Debug)]
struct EndSpec {
    /// Where tracing should stop.
    target: f64,
    /// The great circle of the branch end near the target, if any (`|target − m| < 0.01`).
    circle: Option<u32>,
    /// Whether the target is the great-circle end itself (else the range end).
    at_circle: bool,
}

impl EndSpec {
    /// Where the pseudo-arclength run stops (`side`: direction of tracing; the branch lies
    /// on the other side of its great circle).
    fn run_limit(&self, side: f64) -> f64 {
        match self.circle {
            Some(m) => f64::from(m) - side * SWITCH_DISTANCE,
            None => self.target,
        }
    }
}

fn end_specs(opts: &DiagramOptions, eta: u32) -> (EndSpec, EndSpec) {
    let e = f64::from(eta);
    let d = opts.end_distance;
    let low = if eta >= 2 {
        let m = e - 1.0;
        if m + d >= opts.lbar_min {
            EndSpec {
                target: m + d,
                circle: Some(eta - 1),
                at_circle: true,
            }
        } else {
            EndSpec {
                target: opts.lbar_min,
                circle: (opts.lbar_min - m < SWITCH_DISTANCE).then_some(eta - 1),
                at_circle: false,
            }
        }
    } else {
        EndSpec {
            target: opts.lbar_min,
            circle: None,
            at_circle: false,
        }
    };
    let m = e + 1.0;
    let high = if m - d <= opts.lbar_max {
        EndSpec {
            target: m - d,
            circle: Some(eta + 1),
            at_circle: true,
        }
    } else {
        EndSpec {
            target: opts.lbar_max,
            circle: (m - opts.lbar_max < SWITCH_DISTANCE).then_some(eta + 1),
            at_circle: false,
        }
    };
    (low, high)
}

/// Settings of the pseudo-arclength runs per accuracy level: `(ds_max, ds_initial)` in the
/// scaled norm.
fn step_bounds(opts: &DiagramOptions) -> (f64, f64) {
    match opts.accuracy {
        rodloop_solver::Accuracy::Fast => (0.6, 0.1),
        rodloop_solver::Accuracy::Default => (0.25, 0.05),
        rodloop_solver::Accuracy::High => (0.2, 0.05),
    }
}

/// A raw traced state before post-processing.
struct Raw {
    x: Vec<f64>,
    p: f64,
    index: Option<usize>,
    source: PointSource,
}

/// Outcome of one direction.
struct SideResult {
    seconds_run: f64,
    seconds_end: f64,
    points: Vec<Raw>,
    end: BranchEnd,
    stop: String,
    steps: usize,
    changes: Vec<IndexChange>,
}

/// Trace branch `eta` (see the module docs): seed from the Euler rotation curve `l = η` in
/// the middle of `(η − 1, η + 1) ∩ [lbar_min, lbar_max]`, continuation in both directions,
/// approach to the great-circle ends, and the quantities of every state.
///
/// Problems at the ends (a step that cannot be taken, a Newton solve that fails near the
/// singular end) do not fail the call: the end is recorded as [`BranchEnd::Failed`] with
/// the reason. Errors: invalid options, a branch outside the range, a seed that cannot be
/// solved or a continuation that cannot start.
pub fn compute_branch(
    opts: &DiagramOptions,
    eta: u32,
    progress: &mut dyn FnMut(Progress),
) -> Result<TracedBranch, DiagramError> {
    opts.validate()?;
    let start_time = Instant::now();
    let branch = branch_of_eta(eta);
    let e = f64::from(eta);
    let (exist_lo, exist_hi) = (if eta == 1 { 0.0 } else { e - 1.0 }, e + 1.0);
    if eta == 0 || !(exist_hi > opts.lbar_min && exist_lo < opts.lbar_max) {
        return Err(DiagramError::BranchOutOfRange {
            eta,
            lo: exist_lo,
            hi: exist_hi,
            lbar_min: opts.lbar_min,
            lbar_max: opts.lbar_max,
        });
    }
    progress(Progress::BranchStarted { branch, eta });
    let (low, high) = end_specs(opts, eta);
    if low.target >= high.target {
        return Err(DiagramError::BranchOutOfRange {
            eta,
            lo: exist_lo,
            hi: exist_hi,
            lbar_min: opts.lbar_min,
            lbar_max: opts.lbar_max,
        });
    }
    let cells = opts.trace_cells(eta);

    // Seed: the middle of the range first, then a third of the way in from either end.
    let mut failure = None;
    let mut seeded = None;
    for fraction in [0.5, 0.3, 0.7] {
        let lbar = low.target + fraction * (high.target - low.target);
        match seed_at(opts, eta, cells, lbar) {
            Ok(found) => {
                seeded = Some(found);
                break;
            }
            Err(e) => failure = Some(e),
        }
    }
    let (eq, seed) = match (seeded, failure) {
        (Some(found), _) => found,
        (None, Some(e)) => return Err(e),
        (None, None) => unreachable!("at least one seed attempt"),
    };
    let (problem, x0, p0) = LbarProblem::from_equilibrium(&eq);
    let nk = eq.model().n_kappa();
    let scaled = Scaled {
        inner: &problem,
        nk,
        s: opts.radius / (nk as f64).sqrt(),
    };
    let index_fn = |x: &[f64], p: f64| -> usize {
        problem
            .model_at(p)
            .and_then(|m| rodloop_solver::stability::index(&m, x, INDEX_TOLERANCE))
            .unwrap_or(usize::MAX)
    };
    let seed_index = index_fn(x0.as_slice(), p0);

    let t_seed = start_time.elapsed().as_secs_f64();
    let ctx = SideContext {
        opts,
        scaled: &scaled,
        x0: &x0,
        p0,
        eta,
        index_fn: &index_fn,
    };
    let lowside = trace_side(&ctx, low, -1.0, progress)?;
    let highside = trace_side(&ctx, high, 1.0, progress)?;

    // Assemble the raw states in increasing L̄.
    let mut raw: Vec<Raw> = Vec::new();
    raw.extend(lowside.points.into_iter().rev());
    raw.push(Raw {
        x: x0.as_slice().to_vec(),
        p: p0,
        index: Some(seed_index),
        source: PointSource::Seed,
    });
    raw.extend(highside.points);
    raw.sort_by(|a, b| a.p.total_cmp(&b.p));
    raw.dedup_by(|b, a| (a.p - b.p).abs() <= 1e-14 * a.p.abs().max(1.0));

    let t_trace = start_time.elapsed().as_secs_f64();
    let points = raw
        .iter()
        .filter_map(|r| finish_point(opts, &problem, r))
        .collect::<Vec<_>>();

    if points.is_empty() {
        return Err(DiagramError::Continuation {
            eta,
            reason: "no traced state could be re-solved".into(),
        });
    }
    let mut index_changes = lowside.changes;
    index_changes.extend(highside.changes);
    index_changes.sort_by(|a, b| a.lbar.total_cmp(&b.lbar));
    let traced = TracedBranch {
        branch,
        eta,
        fingerprint: opts.fingerprint(),
        cells,
        phase: opts.stiffness.is_uniform(),
        points,
        low_end: lowside.end,
        high_end: highside.end,
        stop_low: lowside.stop,
        stop_high: highside.stop,
        seed,
        index_changes,
        steps: lowside.steps + highside.steps,
        seconds: start_time.elapsed().as_secs_f64(),
        timings: BranchTimings {
            seed: t_seed,
            continuation: lowside.seconds_run + highside.seconds_run,
            end_approach: lowside.seconds_end + highside.seconds_end,
            states: start_time.elapsed().as_secs_f64() - t_trace,
        },
    };
    progress(Progress::BranchFinished {
        branch,
        eta,
        points: traced.points.len(),
        seconds: traced.seconds,
    });
    Ok(traced)
}

/// Seed of branch `eta` at `lbar`: Euler rotation curve `l = η`, relaxed and solved
/// ([`Globalization::Auto`], then a longer relaxation). A uniform rod must relax to a loop
/// with `η` periods; for a non-uniform rod a different count is only noted.
fn seed_at(
    opts: &DiagramOptions,
    eta: u32,
    cells: usize,
    lbar: f64,
) -> Result<(Equilibrium, String), DiagramError> {
    let seed_err = |source: SolverError| DiagramError::Seed { eta, lbar, source };
    let model = SurfaceModel::new(opts.radius, lbar, cells, &opts.stiffness).map_err(seed_err)?;
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

/// Number of periods of `κ_g` of an equilibrium.
pub(crate) fn periods_of(eq: &Equilibrium) -> Result<usize, SolverError> {
    let r = eq.model().radius();
    let kg: Vec<f64> = eq.profile().iter().map(|p| p.kappa_g * r).collect();
    StartShape::from_kappa_g_samples(&kg)?.periods(eq.lbar())
}

/// What both directions of a trace share.
#[derive(Clone, Copy)]
struct SideContext<'a> {
    opts: &'a DiagramOptions,
    scaled: &'a Scaled<'a>,
    x0: &'a DVector<f64>,
    p0: f64,
    eta: u32,
    index_fn: &'a dyn Fn(&[f64], f64) -> usize,
}

/// Trace from the seed towards one end (`side = −1`: decreasing `L̄`).
fn trace_side(
    ctx: &SideContext<'_>,
    spec: EndSpec,
    side: f64,
    progress: &mut dyn FnMut(Progress),
) -> Result<SideResult, DiagramError> {
    let SideContext {
        opts,
        scaled,
        x0,
        p0,
        eta,
        index_fn,
    } = *ctx;
    let eta_err = |reason: String| DiagramError::Continuation { eta, reason };
    let t_run = Instant::now();
    let limit = spec.run_limit(side);
    let mut points: Vec<Raw> = Vec::new();
    let mut changes = Vec::new();
    let mut steps = 0;
    // Where the run ended and why, before the end approach.
    let mut run_note: Option<String> = None;
    if (limit - p0) * side > 0.0 {
        let (ds_max, ds) = step_bounds(opts);
        let (p_min, p_max) = if side < 0.0 {
            (limit, f64::INFINITY)
        } else {
            (f64::NEG_INFINITY, limit)
        };
        let direction = if side < 0.0 {
            Direction::Backward
        } else {
            Direction::Forward
        };
        let settings = PseudoArclength::new()
            .with_ds(ds)
            .and_then(|s| s.with_ds_bounds(1e-6, ds_max))
            .and_then(|s| s.with_range(p_min, p_max))
            .and_then(|s| s.with_direction(direction))
            .and_then(|s| s.with_max_steps(CHUNK))
            .and_then(|s| s.with_tol(1e-10))
            .and_then(|s| s.with_locate_tol(1e-8))
            .and_then(|s| s.with_detect_folds(false))
            .and_then(|s| s.with_detect_branch_points(false))
            .and_then(|s| s.with_detect_loops(false))
            .map_err(|e| eta_err(e.to_string()))?;
        // Runs of `CHUNK` steps, each continuing from the last point of the previous one, so
        // that a turning point ends the tracing promptly.
        let n = scaled.dim();
        let mut start = scaled.scale(x0.as_slice());
        let mut p_start = p0;
        let mut settings = settings;
        let mut stop = StopReason::MaxSteps;
        while steps < MAX_STEPS_PER_SIDE {
            let run = Continuation::new(scaled, settings.clone())
                .with_stability_fn(|x, p| index_fn(scaled.unscale(x).as_slice(), p))
                .run(&start, p_start)
                .map_err(|e| eta_err(e.to_string()))?;
            steps += run.points.len().saturating_sub(1);
            stop = run.stop;
            // Keep the points before the first turning point in L̄ (near a great circle the
            // curve runs through it onto the mirror image of the branch; elsewhere it is a
            // fold of the branch, which is not followed).
            let mut keep = run.points.len();
            for (k, pt) in run.points.iter().enumerate().skip(1) {
                if pt.tangent[n] * side <= 0.0 || (pt.p - run.points[k - 1].p) * side <= 0.0 {
                    keep = k;
                    let at = run.points[k - 1].p;
                    run_note = Some(match spec.circle {
                        Some(m) if (at - f64::from(m)).abs() <= 4.0 * SWITCH_DISTANCE => format!(
                            "the continuation turned back in L̄ near L̄ = {at:.6}, close to \
                             the {m}-fold great circle"
                        ),
                        _ => format!(
                            "the branch has a fold (turning point in L̄) near L̄ = {at:.6}; \
                             it is not followed beyond"
                        ),
                    });
                    break;
                }
            }
            for pt in run.points.iter().take(keep).skip(1) {
                points.push(Raw {
                    x: scaled.unscale(&pt.x).as_slice().to_vec(),
                    p: pt.p,
                    index: pt.index,
                    source: PointSource::Continuation,
                });
            }
            for sp in &run.special {
                if let SpecialKind::IndexChange { old, new } = sp.kind {
                    if sp.segment + 1 < keep {
                        let (below, above) = if side > 0.0 { (old, new) } else { (new, old) };
                        changes.push(IndexChange {
                            lbar: sp.p,
                            below,
                            above,
                        });
                        points.push(Raw {
                            x: scaled.unscale(&sp.x).as_slice().to_vec(),
                            p: sp.p,
                            index: Some(new),
                            source: PointSource::IndexChange,
                        });
                    }
                }
            }
            let last = &run.points[keep.max(1) - 1];
            progress(Progress::BranchStep {
                eta,
                lbar: last.p,
                steps,
            });
            if run_note.is_some() || !matches!(run.stop, StopReason::MaxSteps) || keep < 2 {
                break;
            }
            start = last.x.clone();
            p_start = last.p;
            settings = settings
                .with_ds(last.ds.abs().clamp(1e-6, ds_max))
                .map_err(|e| eta_err(e.to_string()))?;
        }
        points.sort_by(|a, b| ((a.p - b.p) * side).total_cmp(&0.0));
        if run_note.is_none() {
            run_note = match stop {
                StopReason::LeftRange { .. } => None,
                StopReason::StepTooSmall { ds, p } => Some(format!(
                    "the continuation step fell below its minimum ({ds:.1e}) at L̄ = {p:.6}"
                )),
                StopReason::MaxSteps => Some(format!(
                    "the continuation used up its budget of {MAX_STEPS_PER_SIDE} steps"
                )),
                StopReason::ClosedLoop => Some("the continuation closed a loop".into()),
                // `Continuation::run` never returns it.
                StopReason::Interrupted => Some("the continuation was interrupted".into()),
            };
        }
    }
    let last_p = points.last().map_or(p0, |r| r.p);
    let reached_limit = (last_p - limit).abs() <= 1e-12 * limit.abs().max(1.0);

    let seconds_run = t_run.elapsed().as_secs_f64();
    let t_end = Instant::now();
    // Approach to the end.
    let mut end_note = None;
    if let Some(m) = spec.circle {
        let near = (last_p - f64::from(m)).abs() <= 4.0 * SWITCH_DISTANCE;
        if near {
            let mut chain: Vec<(Vec<f64>, f64)> = Vec::new();
            if points.len() < 2 {
                chain.push((x0.as_slice().to_vec(), p0));
            }
            chain.extend(
                points
                    .iter()
                    .rev()
                    .take(3)
                    .rev()
                    .map(|r| (r.x.clone(), r.p)),
            );
            let found = approach_end(scaled.inner, &chain, f64::from(m), spec.target);
            for (x, p) in found.points {
                let index = Some(index_fn(&x, p));
                points.push(Raw {
                    x,
                    p,
                    index,
                    source: PointSource::EndApproach,
                });
            }
            end_note = found.failure;
        } else if run_note.is_none() && !reached_limit {
            end_note = Some("the continuation stopped short of the end".into());
        }
    }
    let last = points.last().map_or(p0, |r| r.p);
    let amplitude = points
        .last()
        .map(|r| {
            r.x[..scaled.nk]
                .iter()
                .fold(0.0f64, |a, v| a.max(v.abs() * opts.radius))
        })
        .unwrap_or(f64::NAN);
    let done = (last - spec.target).abs() <= 1e-9 * spec.target.abs().max(1.0);
    let (end, stop) = if done && spec.at_circle {
        let m = spec.circle.expect("circle end");
        let dist = (last - f64::from(m)).abs();
        (
            BranchEnd::GreatCircle {
                m,
                lbar: last,
                distance: dist,
            },
            format!(
                "stopped at L̄ = {last:.6}, {dist:.1e} {} the {m}-fold great circle at L̄ = {m}, \
                 where the branch ends: the loop collapses onto the great circle \
                 (max|κ_g R| = {amplitude:.2e} here), the closure Jacobian loses rank and the \
                 KKT matrix becomes singular",
                if side < 0.0 { "above" } else { "below" },
            ),
        )
    } else if done {
        (
            BranchEnd::Range { lbar: last },
            format!(
                "stopped at L̄ = {last}, the {} of the diagram's range",
                if side < 0.0 { "lower end" } else { "upper end" }
            ),
        )
    } else {
        let reason = end_note
            .or(run_note)
            .unwrap_or_else(|| "tracing stopped early".into());
        (
            BranchEnd::Failed {
                lbar: last,
                target: spec.target,
                reason: reason.clone(),
            },
            format!(
                "stopped at L̄ = {last:.6} before the target {:.6}: {reason}",
                spec.target
            ),
        )
    };
    Ok(SideResult {
        seconds_run,
        seconds_end: t_end.elapsed().as_secs_f64(),
        points,
        end,
        stop,
        steps,
        changes,
    })
}

/// Result of [`approach_end`].
struct Approach {
    points: Vec<(Vec<f64>, f64)>,
    failure: Option<String>,
}

/// Newton solves at `L̄ = m + side·a²`, `a` halved at every step, from `chain` (the last
/// states, the nearest to `m` last) down to `target`; the predictor is the polynomial in
/// `a` through the last (up to three) states. `side` is the side of `m` the branch lies on.
fn approach_end(problem: &LbarProblem, chain: &[(Vec<f64>, f64)], m: f64, target: f64) -> Approach {
    let side = if chain.last().map_or(target, |c| c.1) >= m {
        1.0
    } else {
        -1.0
    };
    let a_of = |p: f64| (side * (p - m)).max(0.0).sqrt();
    let a_target = a_of(target);
    let mut hist: Vec<(Vec<f64>, f64)> = chain.to_vec();
    let mut out = Vec::new();
    let opts = newton_options();
    let mut ratio: f64 = 0.5;
    for _ in 0..200 {
        let Some(&(_, p_last)) = hist.last() else {
            break;
        };
        let a_last = a_of(p_last);
        if a_last <= a_target * (1.0 + 1e-12) {
            return Approach {
                points: out,
                failure: None,
            };
        }
        let mut attempt = ratio;
        let mut solved = None;
        let mut last_err = String::new();
        for _ in 0..8 {
            let a_next = (a_last * attempt).max(a_target);
            let p_next = if a_next <= a_target {
                target
            } else {
                m + side * a_next * a_next
            };
            let pred = predict(&hist, a_of, a_next);
            match problem
                .model_at(p_next)
                .and_then(|model| solve_from_state(model, pred, &opts))
            {
                Ok(eq) => {
                    solved = Some((eq.state(), p_next));
                    break;
                }
                Err(e) => {
                    last_err = e.to_string();
                    attempt = attempt.sqrt();
                }
            }
        }
        match solved {
            Some(s) => {
                hist.push(s.clone());
                out.push(s);
                ratio = (ratio * 0.8).max(0.5);
            }
            None => {
                return Approach {
                    points: out,
                    failure: Some(format!(
                        "Newton's method failed approaching the great circle at L̄ = {m} \
                         ({last_err})"
                    )),
                }
            }
        }
    }
    Approach {
        points: out,
        failure: Some("too many steps approaching the great circle".into()),
    }
}

/// Polynomial extrapolation in `a` through the last (up to three) states of `hist`.
fn predict(hist: &[(Vec<f64>, f64)], a_of: impl Fn(f64) -> f64, a: f64) -> Vec<f64> {
    let k = hist.len().min(3);
    let pts = &hist[hist.len() - k..];
    let nodes: Vec<f64> = pts.iter().map(|(_, p)| a_of(*p)).collect();
    // Drop coincident nodes (fall back to fewer points).
    let distinct = nodes
        .windows(2)
        .all(|w| (w[0] - w[1]).abs() > 1e-14 * w[0].abs().max(1e-14));
    if k == 1 || !distinct {
        return pts[k - 1].0.clone();
    }
    let weights: Vec<f64> = (0..k)
        .map(|i| {
            (0..k)
                .filter(|&j| j != i)
                .map(|j| (a - nodes[j]) / (nodes[i] - nodes[j]))
                .product()
        })
        .collect();
    let n = pts[0].0.len();
    (0..n)
        .map(|c| pts.iter().zip(&weights).map(|((x, _), w)| w * x[c]).sum())
        .collect()
}

/// Quantities of a traced state: equilibrium at the tracing resolution (Newton check),
/// Richardson partner at half the resolution, slope, forces, index.
fn finish_point(opts: &DiagramOptions, problem: &LbarProblem, raw: &Raw) -> Option<TracedPoint> {
    let eq = match problem
        .model_at(raw.p)
        .and_then(|m| solve_from_state(m, raw.x.clone(), &newton_options()))
    {
        Ok(eq) => eq,
        Err(_) => return None,
    };
    let z = eq.state();
    let en = eq.energy();
    let (lmin, lmax) = eq.lambda_range();
    let slope = energy_slope(eq.model(), &z).unwrap_or(f64::NAN);
    let amplitude = eq
        .kappa()
        .iter()
        .fold(0.0f64, |a, v| a.max(v.abs() * opts.radius));
    let index = match raw.index {
        Some(i) if i != usize::MAX => i,
        _ => {
            rodloop_solver::stability::index(eq.model(), &z, INDEX_TOLERANCE).unwrap_or(usize::MAX)
        }
    };
    let cells = eq.model().cells();
    let partner = if cells / 2 >= crate::profile_cells(&opts.stiffness) {
        half_resolution(opts, &eq, cells / 2)
    } else {
        None
    };
    let (energy, energy_g, energy_error, lambda_min, lambda_max) = match partner {
        Some(h) => {
            let eh = h.energy();
            let (hmin, hmax) = h.lambda_range();
            let rich = |f: f64, c: f64| f + (f - c) / 15.0;
            (
                rich(en.total, eh.total),
                rich(en.geodesic, eh.geodesic),
                Some((en.total - eh.total).abs() / 15.0),
                rich(lmin, hmin),
                rich(lmax, hmax),
            )
        }
        None => (en.total, en.geodesic, None, lmin, lmax),
    };
    let values = [energy, energy_g, en.total, slope, lambda_min, lambda_max];
    if values.iter().any(|v| !v.is_finite()) || index == usize::MAX {
        return None;
    }
    Some(TracedPoint {
        lbar: raw.p,
        energy,
        energy_g,
        energy_error,
        energy_trace: en.total,
        slope,
        index,
        lambda_min,
        lambda_max,
        amplitude,
        source: raw.source,
        state: z,
    })
}

/// The equilibrium `eq` re-solved with `cells` cells (resampled start, phase condition from
/// the resampled profile so that the arclength origin is the same).
pub(crate) fn half_resolution(
    opts: &DiagramOptions,
    eq: &Equilibrium,
    cells: usize,
) -> Option<Equilibrium> {
    if cells < 4 {
        return None;
    }
    let kappa = eq.resample(cells).ok()?;
    let model = model_with_phase(opts, eq.lbar(), cells, &kappa).ok()?;
    solve(&model, &kappa, &newton_options()).ok()
}
