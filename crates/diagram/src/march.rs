//! A march: one [`Stepper`](rodloop_continuation::Stepper) from a solved state towards a limit of the continued
//! parameter, for any confinement model ([`Confinement`]) and any named parameter
//! ([`ParamProblem`]).
//!
//! [`march`] lets the continuation crate's stepping loop
//! ([`Stepper::drive`](rodloop_continuation::Stepper::drive)) take the pseudo-arclength
//! steps and reacts to what each step reports:
//!
//! * **index changes** (located by the continuation's bisection on the stability index of
//!   [`Confinement::index`]) become points of the march and [`IndexChange`]s;
//! * **folds** (turning points of the parameter, located by the continuation): with
//!   [`FoldPolicy::Stop`] the march ends before the step that turned (what the branch
//!   diagram does today); with [`FoldPolicy::Follow`] the fold is recorded and the stepper
//!   simply goes on, so the march comes back in the parameter on the other sheet;
//! * **branch points** (when [`MarchSettings::detect_branch_points`] is on) are recorded with
//!   their state and tangent in [`March::branch_points`], unscaled: a caller switches onto
//!   the second branch with [`rodloop_continuation::Continuation::start_switch`] there and
//!   marches it with the same loop;
//! * **evaluation errors** of the model (a trial iterate it cannot evaluate, a stability
//!   index that fails) do not end the march: the step is retried with half the step size
//!   (the stepper stays at its last accepted point), down to `ds_min`.
//!
//! # Scaling
//!
//! The stepper works on the model's unknowns with the first [`MarchSettings::scaled`] of them
//! (the shape unknowns, e.g. the curvatures) multiplied by [`MarchSettings::scale`]; for the
//! surface model `R/√(2N)` makes the Euclidean norm of that part the root-mean-square of
//! `κ_g R`, so that step sizes do not depend on the resolution. The scaling is applied to
//! the model's own factorisation too ([`Confinement::factorize`], `O(N)`), not by forming a
//! dense matrix.
//!
//! The scaled problem, its factorisation and the stability index at a scaled state are
//! the child module `scaled`.

use nalgebra::DVector;
use rodloop_continuation::{
    Continuation, Direction, Driven, Flow, OnError, Problem, PseudoArclength, SpecialKind,
    StopReason,
};
use rodloop_solver::{Confinement, ParamProblem, SolverError};

use crate::types::{IndexChange, PointSource};

mod scaled;
use scaled::{Index, Scaled};

/// What [`march`] does at a fold (turning point) of the continued parameter.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FoldPolicy {
    /// End the march before the step that turned back (the points beyond are dropped).
    Stop,
    /// Record the fold and keep stepping through it.
    Follow,
}

/// Settings of one [`march`].
#[derive(Clone, Debug, PartialEq)]
pub struct MarchSettings {
    /// The value of the continued parameter where the march ends; its side of the start
    /// value gives the direction.
    pub limit: f64,
    /// First step size (scaled norm).
    pub ds: f64,
    /// Smallest step size: below it the march stops.
    pub ds_min: f64,
    /// Largest step size.
    pub ds_max: f64,
    /// Budget of accepted steps.
    pub max_steps: usize,
    /// Corrector tolerance (max-norm of the residual).
    pub tol: f64,
    /// Width to which special points are located (arclength).
    pub locate_tol: f64,
    /// Number of leading unknowns scaled by [`MarchSettings::scale`].
    pub scaled: usize,
    /// Scale of the leading unknowns (positive).
    pub scale: f64,
    /// What to do at a fold.
    pub folds: FoldPolicy,
    /// Whether to detect and locate simple branch points.
    pub detect_branch_points: bool,
    /// Eigenvalues below `−index_tolerance` count as negative in the stability index.
    pub index_tolerance: f64,
    /// Whether the stability index is monitored (index changes located, points carry their
    /// index); off, the points have no index.
    pub track_index: bool,
    /// Whether the location of special points starts its correctors from the Hermite
    /// interpolant of the current bracket
    /// ([`PseudoArclength::with_hermite_location`]): cheaper and more accurate location,
    /// used where the curve is already known (relocating special points).
    pub hermite_location: bool,
    /// Steps between two calls of the progress callback (which is also called at the end).
    pub progress_every: usize,
    /// With [`FoldPolicy::Follow`]: the far end of the range (the march then stays within
    /// `[min(limit, far_limit), max(limit, far_limit)]` whichever way it turns). `None`: the
    /// range is open beyond the start, as with [`FoldPolicy::Stop`].
    pub far_limit: Option<f64>,
    /// Values of the parameter the march must not run into (great-circle ends at integer
    /// `L̄`): it stops ([`MarchStop::NearCircle`]) at the first point within
    /// [`MarchSettings::circle_distance`] of one of them while heading towards it.
    pub circles: Vec<f64>,
    /// See [`MarchSettings::circles`].
    pub circle_distance: f64,
}

/// A state reached by the march (unscaled).
#[derive(Clone, Debug, PartialEq)]
pub struct MarchPoint {
    /// The model's unknowns.
    pub x: Vec<f64>,
    /// Value of the continued parameter.
    pub value: f64,
    /// Stability index, if known.
    pub index: Option<usize>,
    /// How it was obtained.
    pub source: PointSource,
}

/// A located special point that the march recorded (fold or branch point), unscaled.
#[derive(Clone, Debug, PartialEq)]
pub struct MarchSpecial {
    /// What it is.
    pub kind: SpecialKind,
    /// The model's unknowns there.
    pub x: Vec<f64>,
    /// Value of the continued parameter.
    pub value: f64,
    /// Unit tangent `(ẋ, ṗ)` in the scaled unknowns, oriented in the marching direction.
    pub tangent: Vec<f64>,
}

/// Why a march ended.
#[derive(Clone, Debug, PartialEq)]
pub enum MarchStop {
    /// The limit was reached; the last point lies on it.
    Reached,
    /// A fold with [`FoldPolicy::Stop`]: the parameter turned back at `value`.
    Fold {
        /// Where the parameter turned (the located fold, or the last point kept).
        value: f64,
    },
    /// The step size fell below its minimum.
    StepTooSmall {
        /// The rejected step size.
        ds: f64,
        /// Value of the last accepted point.
        value: f64,
        /// The last evaluation error, if errors shrank the step.
        cause: Option<String>,
    },
    /// The step budget was used up.
    MaxSteps,
    /// The branch closed a loop.
    ClosedLoop,
    /// [`march_switch`]: the first point off the branch point lies on a known branch; or
    /// ([`march_until`], [`march_switch_until`]) the caller's test `until` held for the
    /// points marched so far.
    Known,
    /// The march came within [`MarchSettings::circle_distance`] of one of
    /// [`MarchSettings::circles`], heading towards it.
    NearCircle {
        /// The value it approaches.
        circle: f64,
        /// Value of the last point.
        value: f64,
    },
}

/// The outcome of [`march`].
#[derive(Clone, Debug, PartialEq)]
pub struct March {
    /// The states reached, in marching order, without the start; located index changes
    /// are among them ([`PointSource::IndexChange`]).
    pub points: Vec<MarchPoint>,
    /// The located index changes, with `below`/`above` in increasing parameter.
    pub index_changes: Vec<IndexChange>,
    /// Located folds (followed or not) and branch points.
    pub special: Vec<MarchSpecial>,
    /// Accepted continuation steps.
    pub steps: usize,
    /// Why the march ended.
    pub stop: MarchStop,
}

impl March {
    /// The located branch points.
    pub fn branch_points(&self) -> impl Iterator<Item = &MarchSpecial> {
        self.special
            .iter()
            .filter(|s| s.kind == SpecialKind::BranchPoint)
    }
}

/// `problem` with the scaling of `st` (see the module docs), if the scaling is valid.
fn scaled_problem<'a, M: Confinement>(
    problem: &'a ParamProblem<M>,
    st: &MarchSettings,
) -> Result<Scaled<'a, M>, SolverError> {
    if !(st.scale.is_finite() && st.scale > 0.0) || st.scaled > problem.dim() {
        return Err(SolverError::InvalidInput(format!(
            "march scaling: {} unknowns by {} (dimension {})",
            st.scaled,
            st.scale,
            problem.dim()
        )));
    }
    Ok(Scaled {
        inner: problem,
        k: st.scaled,
        s: st.scale,
    })
}

/// The continuation with the model's stability index monitored, unless
/// [`MarchSettings::track_index`] is off.
fn with_index<'a, M: Confinement>(
    cont: Continuation<'a, Scaled<'a, M>>,
    scaled: &'a Scaled<'a, M>,
    st: &MarchSettings,
) -> Continuation<'a, Scaled<'a, M>> {
    if st.track_index {
        cont.with_stability(Index {
            scaled,
            tolerance: st.index_tolerance,
        })
    } else {
        cont
    }
}

/// Errors of [`march`]: the settings, or a start the continuation cannot correct.
fn start_error(e: impl std::fmt::Display) -> SolverError {
    SolverError::InvalidInput(format!("the march cannot start: {e}"))
}

/// March from the solved state `(x0, p0)` of `problem` towards `settings.limit` (see the
/// module docs). `progress(value, steps)` is called every
/// [`MarchSettings::progress_every`] steps and at the end.
///
/// Nothing is marched (an empty [`March`] that has [`MarchStop::Reached`]) if `p0` already
/// lies on the limit.
///
/// # Errors
/// Invalid settings, a state of the wrong length, or a start that the continuation cannot
/// correct or whose stability index cannot be computed. Trouble after the start ends the
/// march with a [`MarchStop`] instead.
pub fn march<M: Confinement>(
    problem: &ParamProblem<M>,
    x0: &[f64],
    p0: f64,
    settings: &MarchSettings,
    progress: &mut dyn FnMut(f64, usize),
) -> Result<March, SolverError> {
    march_until(problem, x0, p0, settings, &mut |_| false, progress)
}

/// [`march`], ending with [`MarchStop::Known`] as soon as `until(points)` holds for the
/// points marched so far (called after every continuation point).
///
/// # Errors
/// As [`march`].
pub fn march_until<M: Confinement>(
    problem: &ParamProblem<M>,
    x0: &[f64],
    p0: f64,
    settings: &MarchSettings,
    until: &mut dyn FnMut(&[MarchPoint]) -> bool,
    progress: &mut dyn FnMut(f64, usize),
) -> Result<March, SolverError> {
    let st = settings;
    let scaled = scaled_problem(problem, st)?;
    if x0.len() != problem.dim() {
        return Err(SolverError::WrongLength {
            expected: problem.dim(),
            found: x0.len(),
        });
    }
    let out = March {
        points: Vec::new(),
        index_changes: Vec::new(),
        special: Vec::new(),
        steps: 0,
        stop: MarchStop::Reached,
    };
    let side = if st.limit > p0 {
        1.0
    } else if st.limit < p0 {
        -1.0
    } else {
        return Ok(out);
    };
    let cont_settings = continuation_settings(st, side)?;
    let cont = with_index(Continuation::new(&scaled, cont_settings), &scaled, st);
    let stepper = cont.start(&scaled.scale(x0), p0).map_err(start_error)?;
    Ok(run_loop(
        stepper, &scaled, st, side, p0, out, until, progress,
    ))
}

/// The continuation settings of a march heading to `side` from `p0`.
fn continuation_settings(st: &MarchSettings, side: f64) -> Result<PseudoArclength, SolverError> {
    let (p_min, p_max) = match (st.folds, st.far_limit) {
        (FoldPolicy::Follow, Some(far)) => (st.limit.min(far), st.limit.max(far)),
        _ if side < 0.0 => (st.limit, f64::INFINITY),
        _ => (f64::NEG_INFINITY, st.limit),
    };
    let direction = if side < 0.0 {
        Direction::Backward
    } else {
        Direction::Forward
    };
    PseudoArclength::new()
        .with_ds(st.ds)
        .and_then(|s| s.with_ds_bounds(st.ds_min, st.ds_max))
        .and_then(|s| s.with_range(p_min, p_max))
        .and_then(|s| s.with_direction(direction))
        .and_then(|s| s.with_max_steps(st.max_steps))
        .and_then(|s| s.with_tol(st.tol))
        .and_then(|s| s.with_locate_tol(st.locate_tol))
        .and_then(|s| s.with_detect_folds(true))
        .and_then(|s| s.with_detect_branch_points(st.detect_branch_points))
        .and_then(|s| s.with_detect_loops(st.folds == FoldPolicy::Follow))
        // A stopping march keeps only the fold of the step that turns.
        .and_then(|s| s.with_branch_points_beside_folds(st.folds == FoldPolicy::Follow))
        .and_then(|s| s.with_hermite_location(st.hermite_location))
        .map_err(start_error)
}

/// March on the second branch through the branch point `bp` (recorded by an earlier
/// [`march`] of `problem` with the same [`MarchSettings::scaled`] and
/// [`MarchSettings::scale`]), leaving it along `±` the secondary tangent
/// (`direction`), with the continuation's branch switching
/// ([`Continuation::start_switch`]). The branch point itself is the first point of the
/// result ([`PointSource::BranchPoint`]). If `known(x, value)` holds for the first point off
/// the branch point, the march ends there with [`MarchStop::Known`]. `settings.limit` and `settings.far_limit` give the
/// range (the direction comes from `direction`).
///
/// # Errors
/// As [`march`], and when no first step off the branch point succeeds.
pub fn march_switch<M: Confinement>(
    problem: &ParamProblem<M>,
    bp: &MarchSpecial,
    direction: Direction,
    settings: &MarchSettings,
    known: &dyn Fn(&[f64], f64) -> bool,
    progress: &mut dyn FnMut(f64, usize),
) -> Result<March, SolverError> {
    march_switch_until(
        problem,
        bp,
        direction,
        settings,
        known,
        &mut |_| false,
        progress,
    )
}

/// [`march_switch`], ending with [`MarchStop::Known`] as soon as `until(points)` holds for
/// the points marched so far (called after every continuation point after the first).
///
/// # Errors
/// As [`march_switch`].
pub fn march_switch_until<M: Confinement>(
    problem: &ParamProblem<M>,
    bp: &MarchSpecial,
    direction: Direction,
    settings: &MarchSettings,
    known: &dyn Fn(&[f64], f64) -> bool,
    until: &mut dyn FnMut(&[MarchPoint]) -> bool,
    progress: &mut dyn FnMut(f64, usize),
) -> Result<March, SolverError> {
    let st = settings;
    let scaled = scaled_problem(problem, st)?;
    if bp.x.len() != problem.dim() || bp.tangent.len() != problem.dim() + 1 {
        return Err(SolverError::WrongLength {
            expected: problem.dim(),
            found: bp.x.len(),
        });
    }
    let side = if direction == Direction::Forward {
        1.0
    } else {
        -1.0
    };
    let cont_settings = continuation_settings(st, side)?;
    let cont = with_index(Continuation::new(&scaled, cont_settings), &scaled, st);
    let special = rodloop_continuation::SpecialPoint {
        kind: SpecialKind::BranchPoint,
        x: scaled.scale(&bp.x),
        p: bp.value,
        tangent: DVector::from_column_slice(&bp.tangent),
        s: 0.0,
        segment: 0,
        accuracy: 0.0,
    };
    let stepper = cont
        .start_switch(&special, direction)
        .map_err(|e| SolverError::InvalidInput(format!("branch switching failed: {e}")))?;
    let out = March {
        points: vec![MarchPoint {
            x: bp.x.clone(),
            value: bp.value,
            index: None,
            source: PointSource::BranchPoint,
        }],
        index_changes: Vec::new(),
        special: Vec::new(),
        steps: 0,
        stop: MarchStop::Reached,
    };
    // The first point off the branch point is already accepted by the stepper.
    let first = stepper.current();
    let mut out = out;
    out.points.push(MarchPoint {
        x: scaled.unscale(&first.x).as_slice().to_vec(),
        value: first.p,
        index: first.index,
        source: PointSource::Continuation,
    });
    let n = first.x.len();
    if known(&out.points[1].x, first.p) {
        out.stop = MarchStop::Known;
        return Ok(out);
    }
    let side = if first.tangent[n] >= 0.0 { 1.0 } else { -1.0 };
    Ok(run_loop(
        stepper, &scaled, st, side, first.p, out, until, progress,
    ))
}

/// The visitor of [`march`] and [`march_switch`]: what each accepted step adds to the
/// march, and when the march ends, over the continuation's own stepping loop
/// ([`Stepper::drive`](rodloop_continuation::Stepper::drive), which retries a step that
/// fails with an evaluation error with half the step size).
#[allow(clippy::too_many_arguments)]
fn run_loop<M: Confinement>(
    mut stepper: rodloop_continuation::Stepper<'_, '_, Scaled<'_, M>>,
    scaled: &Scaled<'_, M>,
    st: &MarchSettings,
    side: f64,
    p0: f64,
    mut out: March,
    until: &mut dyn FnMut(&[MarchPoint]) -> bool,
    progress: &mut dyn FnMut(f64, usize),
) -> March {
    let unscaled = |x: &DVector<f64>| scaled.unscale(x).as_slice().to_vec();
    let mut last_value = p0;
    let every = st.progress_every.max(1);
    let driven =
        stepper.drive(OnError::Halve, |stepper, step| {
            let Some(point) = step.point else {
                return Flow::Go;
            };
            let n = point.x.len();
            let turned = point.tangent[n] * side <= 0.0 || (point.p - last_value) * side <= 0.0;
            let fold = step.special.iter().find(|s| s.kind == SpecialKind::Fold);
            if st.folds == FoldPolicy::Stop && (turned || fold.is_some()) {
                // The step crossed a turning point of the parameter: keep what came before.
                out.special.extend(fold.map(|f| MarchSpecial {
                    kind: f.kind.clone(),
                    x: unscaled(&f.x),
                    value: f.p,
                    tangent: f.tangent.as_slice().to_vec(),
                }));
                return Flow::Stop(MarchStop::Fold { value: last_value });
            }
            for sp in &step.special {
                match &sp.kind {
                    SpecialKind::IndexChange { old, new } => {
                        // Orientation from the tangent there (a followed fold reverses it).
                        let up = sp.tangent[n] > 0.0;
                        let (below, above) = if up { (*old, *new) } else { (*new, *old) };
                        out.index_changes.push(IndexChange {
                            value: sp.p,
                            below,
                            above,
                        });
                        out.points.push(MarchPoint {
                            x: unscaled(&sp.x),
                            value: sp.p,
                            index: Some(*new),
                            source: PointSource::IndexChange,
                        });
                    }
                    SpecialKind::Fold | SpecialKind::BranchPoint => {
                        out.special.push(MarchSpecial {
                            kind: sp.kind.clone(),
                            x: unscaled(&sp.x),
                            value: sp.p,
                            tangent: sp.tangent.as_slice().to_vec(),
                        });
                        // Followed folds and branch points are states of the march too (the
                        // ends of the monotone pieces of a followed branch).
                        if st.folds == FoldPolicy::Follow {
                            out.points.push(MarchPoint {
                                x: unscaled(&sp.x),
                                value: sp.p,
                                index: None,
                                source: if sp.kind == SpecialKind::Fold {
                                    PointSource::Fold
                                } else {
                                    PointSource::BranchPoint
                                },
                            });
                        }
                    }
                    SpecialKind::Event { .. } => {}
                }
            }
            out.points.push(MarchPoint {
                x: unscaled(&point.x),
                value: point.p,
                index: point.index,
                source: PointSource::Continuation,
            });
            last_value = point.p;
            if stepper.steps() % every == 0 {
                progress(last_value, stepper.steps());
            }
            if step.stop.is_some() {
                // The drive ends with the step's stop reason.
                return Flow::Go;
            }
            if until(&out.points) {
                return Flow::Stop(MarchStop::Known);
            }
            let heading = point.tangent[n];
            match st.circles.iter().find(|&&m| {
                (point.p - m).abs() < st.circle_distance && heading * (m - point.p) > 0.0
            }) {
                Some(&m) => Flow::Stop(MarchStop::NearCircle {
                    circle: m,
                    value: point.p,
                }),
                None => Flow::Go,
            }
        });
    let stop = match driven {
        Driven::Visitor(stop) => stop,
        Driven::Stopped { reason, cause } => stop_of(Some(reason), cause.map(|e| e.to_string())),
        Driven::TooSmall { ds, cause } => MarchStop::StepTooSmall {
            ds,
            value: last_value,
            cause: Some(cause.to_string()),
        },
        // Not with `OnError::Halve`; reported as a step that could not be taken.
        Driven::Failed(e) => MarchStop::StepTooSmall {
            ds: stepper.ds(),
            value: last_value,
            cause: Some(e.to_string()),
        },
    };
    out.steps = stepper.steps();
    out.stop = stop;
    progress(last_value, out.steps);
    out
}

/// The [`MarchStop`] of a stepper's stop reason.
fn stop_of(reason: Option<StopReason>, cause: Option<String>) -> MarchStop {
    match reason {
        Some(StopReason::LeftRange { .. }) => MarchStop::Reached,
        Some(StopReason::StepTooSmall { ds, p }) => MarchStop::StepTooSmall {
            ds,
            value: p,
            cause,
        },
        Some(StopReason::ClosedLoop) => MarchStop::ClosedLoop,
        // A step without a point always carries a reason; the march never interrupts the
        // stepper.
        Some(StopReason::MaxSteps) | Some(StopReason::Interrupted) | None => MarchStop::MaxSteps,
    }
}
