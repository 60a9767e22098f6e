//! Tracing one branch of the diagram: seed (`seed.rs`), one pseudo-arclength march in
//! `L̄` in each direction ([`march()`](crate::march::march)), the approach to the great-circle ends
//! (`ends.rs`), and the quantities of every traced state (`states.rs`).
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
//! Each direction is one [`Stepper`](rodloop_continuation::Stepper) run up to
//! `SWITCH_DISTANCE` (0.05) from a great-circle end (or to the end
//! of the range); a fold of `L̄` ends the march there (it is located by the continuation and
//! not followed). The last stretch to a great circle is the end approach of
//! `ends.rs`. The reason for stopping is recorded for each end ([`BranchEnd`],
//! [`TracedBranch::stop_low`]).

use std::time::Instant;

use rodloop_exact::branch_of_eta;
use rodloop_solver::{Confinement, Param, ParamProblem, SurfaceSolve};

use crate::ends::{approach_end, end_specs, EndSpec, SWITCH_DISTANCE};
use crate::march::{march, FoldPolicy, MarchPoint, MarchSettings, MarchStop};
use crate::seed::seed_at;
use crate::states::{finish_point, INDEX_TOLERANCE};
use crate::types::{BranchEnd, BranchTimings, IndexChange, PointSource, TracedBranch};
use crate::{DiagramError, DiagramOptions, Progress};

/// Budget of continuation steps per direction.
const MAX_STEPS_PER_SIDE: usize = 1000;

/// Steps between two [`Progress::BranchStep`] events.
const PROGRESS_EVERY: usize = 25;

/// Settings of the pseudo-arclength runs per accuracy level: `(ds_max, ds_initial)` in the
/// scaled norm.
fn step_bounds(opts: &DiagramOptions) -> (f64, f64) {
    match opts.accuracy {
        rodloop_solver::Accuracy::Fast => (0.6, 0.1),
        rodloop_solver::Accuracy::Default => (0.25, 0.05),
        rodloop_solver::Accuracy::High => (0.2, 0.05),
    }
}

/// The march settings of the diagram towards `limit` for a model with `shape` shape
/// unknowns.
pub(crate) fn march_settings(opts: &DiagramOptions, limit: f64, shape: usize) -> MarchSettings {
    let (ds_max, ds) = step_bounds(opts);
    let c = &opts.controls;
    let ds_max = c.max_step.unwrap_or(ds_max);
    MarchSettings {
        limit,
        ds: ds.min(ds_max),
        ds_min: c.min_step.unwrap_or(1e-6),
        ds_max,
        max_steps: c.max_points.unwrap_or(MAX_STEPS_PER_SIDE),
        tol: c.newton_tol.unwrap_or(1e-10),
        locate_tol: 1e-8,
        scaled: shape,
        scale: opts.radius / (shape.max(1) as f64).sqrt(),
        folds: FoldPolicy::Stop,
        detect_branch_points: false,
        index_tolerance: INDEX_TOLERANCE,
        track_index: true,
        hermite_location: false,
        progress_every: PROGRESS_EVERY,
        far_limit: None,
        circles: Vec::new(),
        circle_distance: SWITCH_DISTANCE,
    }
}

/// Outcome of one direction.
struct SideResult {
    seconds_run: f64,
    seconds_end: f64,
    points: Vec<MarchPoint>,
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
    let out_of_range = || DiagramError::BranchOutOfRange {
        eta,
        lo: exist_lo,
        hi: exist_hi,
        lbar_min: opts.lbar_min,
        lbar_max: opts.lbar_max,
    };
    if eta == 0 || !(exist_hi > opts.lbar_min && exist_lo < opts.lbar_max) {
        return Err(out_of_range());
    }
    progress(Progress::BranchStarted { branch, eta });
    let (low, high) = end_specs(opts, eta);
    if low.target >= high.target {
        return Err(out_of_range());
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
        (None, None) => return Err(out_of_range()),
    };
    let problem = ParamProblem::new(eq.model().clone(), Param::Lbar)?;
    let (x0, p0) = (eq.state(), eq.lbar());
    let cont_err = |reason: String| DiagramError::Continuation { eta, reason };
    let seed_index = eq
        .model()
        .index(&x0, INDEX_TOLERANCE)
        .map_err(|e| cont_err(format!("stability index of the seed: {e}")))?;

    let t_seed = start_time.elapsed().as_secs_f64();
    let ctx = SideContext {
        opts,
        problem: &problem,
        x0: &x0,
        p0,
        eta,
    };
    let lowside = trace_side(&ctx, low, -1.0, progress)?;
    let highside = trace_side(&ctx, high, 1.0, progress)?;

    // The raw states in increasing L̄.
    let mut raw: Vec<MarchPoint> = Vec::new();
    raw.extend(lowside.points.into_iter().rev());
    raw.push(MarchPoint {
        x: x0.clone(),
        value: p0,
        index: Some(seed_index),
        source: PointSource::Seed,
    });
    raw.extend(highside.points);
    raw.sort_by(|a, b| a.value.total_cmp(&b.value));
    raw.dedup_by(|b, a| (a.value - b.value).abs() <= 1e-14 * a.value.abs().max(1.0));

    let t_trace = start_time.elapsed().as_secs_f64();
    let points = raw
        .iter()
        .filter_map(|r| finish_point(opts, &problem, r))
        .collect::<Vec<_>>();

    if points.is_empty() {
        return Err(cont_err("no traced state could be re-solved".into()));
    }
    let mut index_changes = lowside.changes;
    index_changes.extend(highside.changes);
    index_changes.sort_by(|a, b| a.value.total_cmp(&b.value));
    let traced = TracedBranch {
        branch,
        eta,
        param: Param::Lbar,
        family: 0,
        sheet: 0,
        reversed: false,
        multiplicity: 1,
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

/// What both directions of a trace share.
struct SideContext<'a, M> {
    opts: &'a DiagramOptions,
    problem: &'a ParamProblem<M>,
    x0: &'a [f64],
    p0: f64,
    eta: u32,
}

// Copy for every model type (the context holds references only).
impl<M> Clone for SideContext<'_, M> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<M> Copy for SideContext<'_, M> {}

/// Trace from the seed towards one end (`side = −1`: decreasing `L̄`): the march, then the
/// end approach, and the record of how the end came about.
fn trace_side<M: SurfaceSolve>(
    ctx: &SideContext<'_, M>,
    spec: EndSpec,
    side: f64,
    progress: &mut dyn FnMut(Progress),
) -> Result<SideResult, DiagramError> {
    let SideContext {
        opts,
        problem,
        x0,
        p0,
        eta,
    } = *ctx;
    let t_run = Instant::now();
    let limit = spec.run_limit(side);
    let mut points: Vec<MarchPoint> = Vec::new();
    let mut changes = Vec::new();
    let mut steps = 0;
    // Why the march ended short of its limit, before the end approach.
    let mut run_note: Option<String> = None;
    if (limit - p0) * side > 0.0 {
        let shape = problem.model().dim() - problem.model().n_constraints();
        let settings = march_settings(opts, limit, shape);
        let run = march(problem, x0, p0, &settings, &mut |lbar, steps| {
            progress(Progress::BranchStep { eta, lbar, steps })
        })
        .map_err(|e| DiagramError::Continuation {
            eta,
            reason: e.to_string(),
        })?;
        steps = run.steps;
        points = run.points;
        changes = run.index_changes;
        run_note = match run.stop {
            MarchStop::Reached => None,
            MarchStop::Fold { value: at } => Some(match spec.circle {
                Some(m) if (at - f64::from(m)).abs() <= 4.0 * SWITCH_DISTANCE => format!(
                    "the continuation turned back in L̄ near L̄ = {at:.6}, close to the \
                     {m}-fold great circle"
                ),
                _ => format!(
                    "the branch has a fold (turning point in L̄) near L̄ = {at:.6}; it is not \
                     followed beyond"
                ),
            }),
            MarchStop::StepTooSmall { ds, value, cause } => Some(format!(
                "the continuation step fell below its minimum ({ds:.1e}) at L̄ = {value:.6}{}",
                cause.map(|c| format!(" ({c})")).unwrap_or_default()
            )),
            MarchStop::MaxSteps => Some(format!(
                "the continuation used up its budget of {} steps (raise it with --max-points)",
                opts.controls.max_points.unwrap_or(MAX_STEPS_PER_SIDE)
            )),
            MarchStop::ClosedLoop => Some("the continuation closed a loop".into()),
            MarchStop::Known => Some("the continuation met a known branch".into()),
            MarchStop::NearCircle { value, .. } => Some(format!(
                "the continuation came close to a great circle at L̄ = {value:.6}"
            )),
        };
    }
    let last_p = points.last().map_or(p0, |r| r.value);
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
                chain.push((x0.to_vec(), p0));
            }
            chain.extend(
                points
                    .iter()
                    .rev()
                    .take(3)
                    .rev()
                    .map(|r| (r.x.clone(), r.value)),
            );
            let found = approach_end(problem, &chain, f64::from(m), spec.target);
            for (x, p) in found.points {
                let index = problem
                    .model_at(p)
                    .and_then(|model| model.index(&x, INDEX_TOLERANCE))
                    .ok();
                points.push(MarchPoint {
                    x,
                    value: p,
                    index,
                    source: PointSource::EndApproach,
                });
            }
            end_note = found.failure;
        } else if run_note.is_none() && !reached_limit {
            end_note = Some("the continuation stopped short of the end".into());
        }
    }
    let last = points.last().map_or(p0, |r| r.value);
    let shape = problem.model().dim() - problem.model().n_constraints();
    let amplitude = points
        .last()
        .map(|r| {
            r.x[..shape]
                .iter()
                .fold(0.0f64, |a, v| a.max(v.abs() * opts.radius))
        })
        .unwrap_or(f64::NAN);
    let done = (last - spec.target).abs() <= 1e-9 * spec.target.abs().max(1.0);
    let (end, stop) = match spec.circle {
        Some(m) if done && spec.at_circle => {
            let dist = (last - f64::from(m)).abs();
            (
                BranchEnd::GreatCircle {
                    m,
                    value: last,
                    distance: dist,
                },
                format!(
                    "stopped at L̄ = {last:.6}, {dist:.1e} {} the {m}-fold great circle at L̄ = \
                     {m}, where the branch ends: the loop collapses onto the great circle \
                     (max|κ_g R| = {amplitude:.2e} here), the closure Jacobian loses rank and \
                     the KKT matrix becomes singular",
                    if side < 0.0 { "above" } else { "below" },
                ),
            )
        }
        _ if done => (
            BranchEnd::Range { value: last },
            format!(
                "stopped at L̄ = {last}, the {} of the diagram's range",
                if side < 0.0 { "lower end" } else { "upper end" }
            ),
        ),
        _ => {
            let reason = end_note
                .or(run_note)
                .unwrap_or_else(|| "tracing stopped early".into());
            (
                BranchEnd::Failed {
                    value: last,
                    target: spec.target,
                    reason: reason.clone(),
                },
                format!(
                    "stopped at L̄ = {last:.6} before the target {:.6}: {reason}",
                    spec.target
                ),
            )
        }
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
