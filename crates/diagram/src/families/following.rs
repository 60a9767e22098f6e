//! Following the seeds of a branch through folds and branch points: the curves, their
//! ends, and branch switching.
//!
//! The file is just over 600 lines: following a seed, finishing its ends at the great
//! circles and switching at its branch points share the tracing context and the image tests
//! of the families, and are one job.

use std::time::Instant;

use rodloop_continuation::{Direction, SpecialKind};
use rodloop_solver::{ParamProblem, SurfaceSolve};

use super::images::{image_match, on_known, on_known_within, ImageMatch, Images};
use super::seeding::Seed;
use super::{debug, Curve, MAX_FAMILIES, MAX_STEPS, MAX_SWITCHES, SAME_STATE};
use crate::ends::approach_end;
use crate::march::{march_switch_until, march_until, MarchPoint, MarchSpecial, MarchStop};
use crate::types::{BranchEnd, PointSource};
use crate::{DiagramError, DiagramOptions, Progress};

/// The followed curves of a branch and what following them needs.
pub(super) struct Tracing<'a, M> {
    pub(super) ctx: &'a EndContext<'a, M>,
    pub(super) settings: &'a crate::MarchSettings,
    pub(super) images: &'a Images,
    pub(super) branch: u32,
    pub(super) eta: u32,
    pub(super) curves: Vec<Curve>,
    pub(super) notes: Vec<String>,
    /// Branch points met and not yet switched at.
    pub(super) pending: Vec<MarchSpecial>,
    /// Branch points switched at.
    pub(super) switched: Vec<MarchSpecial>,
    pub(super) steps: usize,
    /// The seed of each followed curve (`None`: found by branch switching).
    pub(super) seed_note: Vec<Option<String>>,
}

impl<M: SurfaceSolve> Tracing<'_, M> {
    /// Follow the state `seeded` (solved at `lbar` as `seed` in `secs` seconds) unless it
    /// is missing or on a known curve, then switch at every new branch point (a later seed
    /// may lie on a family found by switching). `false` once the cap of followed curves is
    /// reached.
    pub(super) fn take(
        &mut self,
        lbar: f64,
        seed: Seed,
        seeded: Option<Vec<f64>>,
        secs: f64,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<bool, DiagramError> {
        let (branch, eta) = (self.branch, self.eta);
        let what = match seed {
            Seed::Uniform(shift) => format!(
                "the uniform rod's loop with its origin moved by {shift:.4}, continued in D1/D0"
            ),
            Seed::Shifted(shift) => format!("Euler curve, origin moved by {shift:.4}"),
            Seed::Solve { .. } => "as `rodloop solve` finds it".to_string(),
            Seed::Found => "found below the traced states by the completeness certificate".into(),
        };
        debug(|| {
            format!(
                "eta {eta} seed at {lbar:.3} ({what}): {} in {secs:.3} s",
                seeded.is_some(),
            )
        });
        let Some(x0) = seeded else {
            return Ok(true);
        };
        if on_known(self.images, &self.curves, &x0, lbar) {
            return Ok(true);
        }
        if self.curves.len() >= MAX_FAMILIES {
            self.notes.push(format!(
                "branch {branch} (η = {eta}): the cap of {MAX_FAMILIES} followed curves was \
                 reached; further seeds were not followed"
            ));
            return Ok(false);
        }
        let ts = Instant::now();
        let curve = follow_seed(
            self.ctx,
            self.settings,
            self.images,
            &self.curves,
            &x0,
            lbar,
            &mut self.pending,
            &mut self.steps,
        )?;
        let (cmin, cmax) = curve
            .points
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
                (a.min(p.value), b.max(p.value))
            });
        if cmax - cmin < 1e-3 {
            let why = if curve.start_end.1 == curve.finish_end.1 {
                format!("both ways {}", curve.start_end.1)
            } else {
                format!("{}; {}", curve.start_end.1, curve.finish_end.1)
            };
            self.notes.push(format!(
                "branch {branch} (η = {eta}): a seed at L̄ = {lbar:.4} ({what}) could not be \
                 followed ({why}): left out"
            ));
            return Ok(true);
        }
        debug(|| {
            format!(
                "eta {eta} followed seed: {} points on {cmin:.4}–{cmax:.4} in {:.3} s",
                curve.points.len(),
                ts.elapsed().as_secs_f64()
            )
        });
        self.seed_note.resize(self.curves.len(), None);
        self.seed_note.push(Some(format!("L̄ = {lbar:.4}, {what}")));
        self.curves.push(curve);
        progress(Progress::BranchStep {
            eta,
            lbar,
            steps: self.steps,
        });
        switch_all(
            self.ctx,
            self.settings,
            self.images,
            &mut self.curves,
            &mut self.pending,
            &mut self.switched,
            &mut self.notes,
            &mut self.steps,
        );
        Ok(true)
    }
}

/// What the ends of followed curves need.
pub(super) struct EndContext<'a, M> {
    pub(super) opts: &'a DiagramOptions,
    pub(super) problem: &'a ParamProblem<M>,
    pub(super) lo: f64,
    pub(super) hi: f64,
    /// Smallest continuation step ([`crate::MarchSettings::ds_min`]).
    pub(super) ds_min: f64,
}

/// Follow a seed both ways; branch points go to `pending`. Each direction ends where it
/// goes on as a symmetry image of what is traced ([`image_match`]: of the known `curves` or
/// of the curve itself), cut back to the symmetric branch point where it turned into its
/// own mirror image.
#[allow(clippy::too_many_arguments)]
fn follow_seed<M: SurfaceSolve>(
    ctx: &EndContext<'_, M>,
    settings: &crate::MarchSettings,
    images: &Images,
    curves: &[Curve],
    x0: &[f64],
    p0: f64,
    pending: &mut Vec<MarchSpecial>,
    steps: &mut usize,
) -> Result<Curve, DiagramError> {
    let cont = |e: rodloop_solver::SolverError| DiagramError::Continuation {
        eta: 0,
        reason: e.to_string(),
    };
    let start = MarchPoint {
        x: x0.to_vec(),
        value: p0,
        index: None,
        source: PointSource::Seed,
    };
    let mut up_s = settings.clone();
    up_s.limit = ctx.hi;
    up_s.far_limit = Some(ctx.lo);
    let mut up_match = None;
    let own = [start.clone()];
    let mut until = |pts: &[MarchPoint]| {
        up_match = image_match(images, curves, &own, pts);
        up_match.is_some()
    };
    let mut up =
        march_until(ctx.problem, x0, p0, &up_s, &mut until, &mut |_, _| {}).map_err(cont)?;
    *steps += up.steps;
    let up_image = up_match.map(|m| cut_at_image(images, &mut up.points, m));
    pending.extend(
        up.branch_points()
            .filter(|b| up_image.as_ref().is_none_or(|c| c.keeps(b)))
            .cloned(),
    );
    let up_image = up_image.map(|c| c.end);
    if up.stop == MarchStop::ClosedLoop {
        let mut points = vec![start];
        points.extend(up.points);
        let e = (
            BranchEnd::Range { value: p0 },
            "the family closes on itself (a loop in the diagram)".to_string(),
        );
        return Ok(Curve {
            points,
            start_end: e.clone(),
            finish_end: e,
        });
    }
    let mut down_s = settings.clone();
    down_s.limit = ctx.lo;
    down_s.far_limit = Some(ctx.hi);
    let mut own: Vec<MarchPoint> = up.points.iter().rev().cloned().collect();
    own.push(start.clone());
    let mut down_match = None;
    let mut until = |pts: &[MarchPoint]| {
        down_match = image_match(images, curves, &own, pts);
        down_match.is_some()
    };
    let mut down =
        march_until(ctx.problem, x0, p0, &down_s, &mut until, &mut |_, _| {}).map_err(cont)?;
    *steps += down.steps;
    let down_image = down_match.map(|m| cut_at_image(images, &mut down.points, m));
    pending.extend(
        down.branch_points()
            .filter(|b| down_image.as_ref().is_none_or(|c| c.keeps(b)))
            .cloned(),
    );
    let down_image = down_image.map(|c| c.end);
    let mut down_pts = down.points;
    let start_end = match down_image {
        Some(e) => e,
        None => finish_end(ctx, &down.stop, &mut down_pts, (x0, p0)),
    };
    let mut up_pts = up.points;
    let finish = match up_image {
        Some(e) => e,
        None => finish_end(ctx, &up.stop, &mut up_pts, (x0, p0)),
    };
    let mut points: Vec<MarchPoint> = down_pts.into_iter().rev().collect();
    points.push(start);
    points.extend(up_pts);
    Ok(Curve {
        points,
        start_end,
        finish_end: finish,
    })
}

/// The end of a followed direction: the approach to a great circle where the march stopped
/// near one, else the record of why it stopped.
fn finish_end<M: SurfaceSolve>(
    ctx: &EndContext<'_, M>,
    stop: &MarchStop,
    points: &mut Vec<MarchPoint>,
    start: (&[f64], f64),
) -> (BranchEnd, String) {
    let last = points.last().map_or(start.1, |p| p.value);
    match stop {
        MarchStop::Reached => {
            let at = if (last - ctx.lo).abs() < (last - ctx.hi).abs() {
                ctx.lo
            } else {
                ctx.hi
            };
            (
                BranchEnd::Range { value: last },
                format!("stopped at L̄ = {at}, an end of the diagram's range"),
            )
        }
        MarchStop::NearCircle { circle, .. } => {
            let m = *circle;
            let d = ctx.opts.end_distance;
            let side = if last > m { 1.0 } else { -1.0 };
            let target = m + side * d;
            let mut chain: Vec<(Vec<f64>, f64)> = Vec::new();
            if points.len() < 2 {
                chain.push((start.0.to_vec(), start.1));
            }
            chain.extend(
                points
                    .iter()
                    .rev()
                    .take(3)
                    .rev()
                    .map(|r| (r.x.clone(), r.value)),
            );
            let found = approach_end(ctx.problem, &chain, m, target);
            for (x, p) in found.points {
                let index = ctx
                    .problem
                    .model_at(p)
                    .and_then(|model| model.index(&x, crate::states::INDEX_TOLERANCE))
                    .ok();
                points.push(MarchPoint {
                    x,
                    value: p,
                    index,
                    source: PointSource::EndApproach,
                });
            }
            let last = points.last().map_or(start.1, |p| p.value);
            match found.failure {
                None => (
                    BranchEnd::GreatCircle {
                        m: m.round() as u32,
                        value: last,
                        distance: (last - m).abs(),
                    },
                    format!(
                        "stopped at L̄ = {last:.6}, {:.1e} from the {}-fold great circle, where \
                         the family ends (the loop collapses onto it)",
                        (last - m).abs(),
                        m
                    ),
                ),
                Some(reason) => (
                    BranchEnd::Failed {
                        value: last,
                        target,
                        reason: reason.clone(),
                    },
                    format!("stopped at L̄ = {last:.6} approaching L̄ = {m}: {reason}"),
                ),
            }
        }
        other => {
            let reason = match other {
                MarchStop::StepTooSmall { ds, value, cause } => format!(
                    "the continuation step fell below its minimum {:.1e} (rejected step \
                     {ds:.1e}) at L̄ = {value:.6}{}",
                    ctx.ds_min,
                    cause
                        .as_ref()
                        .map(|c| format!(" ({c})"))
                        .unwrap_or_default()
                ),
                MarchStop::MaxSteps => {
                    format!("the continuation used up its budget of {MAX_STEPS} steps")
                }
                MarchStop::ClosedLoop => "the family closes on itself".into(),
                _ => "stopped".into(),
            };
            let failed = !matches!(other, MarchStop::ClosedLoop);
            (
                if failed {
                    BranchEnd::Failed {
                        value: last,
                        target: f64::NAN,
                        reason: reason.clone(),
                    }
                } else {
                    BranchEnd::Range { value: last }
                },
                format!("stopped at L̄ = {last:.6}: {reason}"),
            )
        }
    }
}

/// Switch at every pending branch point not met before, following the new curves (whose
/// branch points join the queue).
#[allow(clippy::too_many_arguments)]
fn switch_all<M: SurfaceSolve>(
    ctx: &EndContext<'_, M>,
    settings: &crate::MarchSettings,
    images: &Images,
    curves: &mut Vec<Curve>,
    pending: &mut Vec<MarchSpecial>,
    switched: &mut Vec<MarchSpecial>,
    notes: &mut Vec<String>,
    steps: &mut usize,
) {
    while let Some(bp) = pending.pop() {
        if bp.kind != SpecialKind::BranchPoint {
            continue;
        }
        let seen = switched.iter().any(|s| {
            (s.value - bp.value).abs() < 1e-5 && images.dist_images(&s.x, &bp.x) < SAME_STATE
        });
        if seen {
            continue;
        }
        if switched.len() >= MAX_SWITCHES {
            notes.push(format!(
                "the cap of {MAX_SWITCHES} branch points switched at was reached (branch point \
                 at L̄ = {:.6} not followed)",
                bp.value
            ));
            pending.clear();
            break;
        }
        switched.push(bp.clone());
        // Both branches through it already known (two followed curves pass through it).
        let through = curves
            .iter()
            .filter(|c| on_known(images, std::slice::from_ref(*c), &bp.x, bp.value))
            .count();
        if through >= 2 {
            continue;
        }
        let bp_symmetric = images.symmetric(&bp.x);
        // The curve followed forward from the branch point, where one was kept: a curve
        // followed backward too is the other half of the same family, joined to it.
        let mut forward: Option<usize> = None;
        for dir in [Direction::Forward, Direction::Backward] {
            if curves.len() >= MAX_FAMILIES {
                notes.push(format!(
                    "the cap of {MAX_FAMILIES} followed curves was reached at the branch point \
                     at L̄ = {:.6}",
                    bp.value
                ));
                break;
            }
            // The first point off the branch point is one step (or less) away from it: it
            // lies on a known curve only if much closer to that curve than to the branch
            // point (near a great circle, or after a shortened first step, distinct
            // branches are closer than SAME_STATE).
            let known = |x: &[f64], p: f64| {
                let tol = SAME_STATE.min(0.3 * images.dist(x, &bp.x));
                on_known_within(images, curves, x, p, tol)
            };
            let mut s = settings.clone();
            s.limit = ctx.hi;
            s.far_limit = Some(ctx.lo);
            let ts = Instant::now();
            let mut matched = None;
            let mut until = |pts: &[MarchPoint]| {
                matched = image_match(images, curves, &[], pts);
                matched.is_some()
            };
            let run = march_switch_until(
                ctx.problem,
                &bp,
                dir,
                &s,
                &known,
                &mut until,
                &mut |_, _| {},
            );
            debug(|| {
                format!(
                    "switch at {:.5} {dir:?}: {:?} in {:.3} s",
                    bp.value,
                    run.as_ref()
                        .map(|r| (
                            r.points.len(),
                            r.stop.clone(),
                            r.points
                                .iter()
                                .map(|p| p.value)
                                .fold(f64::INFINITY, f64::min),
                            r.points
                                .iter()
                                .map(|p| p.value)
                                .fold(f64::NEG_INFINITY, f64::max),
                            r.special.len(),
                            r.points.iter().filter_map(|p| p.index).max(),
                        ))
                        .map_err(|e| e.to_string()),
                    ts.elapsed().as_secs_f64()
                )
            });
            let mut run = match run {
                Ok(r) => r,
                Err(e) => {
                    notes.push(format!(
                        "branch switching at the branch point at L̄ = {:.6} failed: {e}",
                        bp.value
                    ));
                    continue;
                }
            };
            // Onto a known family (or an image of one) from its first point, or soon after.
            let image_end = match matched {
                Some(m) if !m.own => {
                    // The run is not kept, but the branch points it located before it met
                    // the known family are switched at too.
                    *steps += run.steps;
                    let first = m.first.min(run.points.len());
                    let met: Vec<f64> = run.points[..first]
                        .iter()
                        .filter(|p| p.source == PointSource::BranchPoint)
                        .map(|p| p.value)
                        .collect();
                    pending.extend(
                        run.branch_points()
                            .filter(|b| {
                                (b.value - bp.value).abs() > 1e-6
                                    && met.iter().any(|v| (v - b.value).abs() < 1e-12)
                            })
                            .cloned(),
                    );
                    continue;
                }
                Some(m) => Some(cut_at_image(images, &mut run.points, m)),
                None => None,
            };
            if run.stop == MarchStop::Known && image_end.is_none() {
                continue;
            }
            // From a symmetric branch point onto an asymmetric branch: the other direction
            // is its mirror image.
            let mirror_pair =
                bp_symmetric && run.points.get(1).is_some_and(|p| !images.symmetric(&p.x));
            *steps += run.steps;
            for b in run
                .branch_points()
                .filter(|b| image_end.as_ref().is_none_or(|c| c.keeps(b)))
            {
                if (b.value - bp.value).abs() > 1e-6 {
                    pending.push(b.clone());
                }
            }
            let mut pts = run.points;
            let bp_end = (
                BranchEnd::BranchPoint { value: bp.value },
                format!("branch point at L̄ = {:.6}", bp.value),
            );
            let end = match image_end {
                Some(c) => c.end,
                None => finish_end(ctx, &run.stop, &mut pts, (&bp.x, bp.value)),
            };
            let half = Curve {
                points: pts,
                start_end: bp_end,
                finish_end: end,
            };
            match (dir, forward) {
                (Direction::Backward, Some(f)) => {
                    let joined = join_halves(half, curves.remove(f));
                    curves.push(joined);
                }
                _ => {
                    if dir == Direction::Forward {
                        forward = Some(curves.len());
                    }
                    curves.push(half);
                }
            }
            if mirror_pair {
                break;
            }
        }
    }
}

/// The two halves of one family followed from a branch point in opposite directions
/// (each starting at the branch point) as one curve in arclength order through it: the
/// backward half reversed, the branch point, the forward half. A family through a branch
/// point is one curve in the diagram whichever side of it the tracer reached it from.
fn join_halves(backward: Curve, forward: Curve) -> Curve {
    let mut points: Vec<MarchPoint> = backward.points.into_iter().rev().collect();
    points.extend(forward.points.into_iter().skip(1));
    Curve {
        points,
        start_end: backward.finish_end,
        finish_end: forward.finish_end,
    }
}

/// Where a march that went on as a symmetry image of a traced curve was cut
/// ([`cut_at_image`]).
struct ImageCut {
    /// The end record of the cut curve.
    end: (BranchEnd, String),
    /// `L̄` of the branch points met before the cut (those to switch at).
    branch_points: Vec<f64>,
}

impl ImageCut {
    /// Whether the branch point `b` was met before the cut.
    fn keeps(&self, b: &MarchSpecial) -> bool {
        self.branch_points
            .iter()
            .any(|v| (v - b.value).abs() < 1e-12)
    }
}

/// Cut a march that went on as a symmetry image of a traced curve (`m`, see
/// [`image_match`]) where the image begins: at the pitchfork before the match where the
/// curve passed into its own mirror image (the last run of located branch points and folds
/// before the match, all mirror-symmetric, containing a branch point; of these only the
/// turning point in `L̄` is kept, the extreme in the direction of the march before it),
/// else at the first matched state.
fn cut_at_image(images: &Images, points: &mut Vec<MarchPoint>, m: ImageMatch) -> ImageCut {
    let first = m.first.min(points.len().saturating_sub(1));
    let located = |p: &MarchPoint| matches!(p.source, PointSource::BranchPoint | PointSource::Fold);
    let block = m
        .own
        .then(|| {
            let end = points[..=first].iter().rposition(located)?;
            let start = points[..=end]
                .iter()
                .rposition(|p| !located(p))
                .map_or(0, |i| i + 1);
            let ok = start >= 2
                && points[start..=end]
                    .iter()
                    .any(|p| p.source == PointSource::BranchPoint)
                && points[start..=end].iter().all(|p| images.symmetric(&p.x));
            ok.then_some((start, end))
        })
        .flatten();
    match block {
        Some((start, end)) => {
            let branch_points = points[..=end]
                .iter()
                .filter(|p| p.source == PointSource::BranchPoint)
                .map(|p| p.value)
                .collect();
            let up = points[start - 1].value >= points[start - 2].value;
            let turn = (start..=end)
                .max_by(|&a, &b| {
                    let (va, vb) = (points[a].value, points[b].value);
                    if up {
                        va.total_cmp(&vb)
                    } else {
                        vb.total_cmp(&va)
                    }
                })
                .unwrap_or(end);
            let mut kept = points[turn].clone();
            kept.source = PointSource::BranchPoint;
            points.truncate(start);
            let value = kept.value;
            points.push(kept);
            ImageCut {
                end: (
                    BranchEnd::BranchPoint { value },
                    format!(
                        "branch point at L̄ = {value:.6}, beyond which the family is the \
                         mirror image of its traced part"
                    ),
                ),
                branch_points,
            }
        }
        None => {
            points.truncate(first + 1);
            let value = points[first].value;
            ImageCut {
                end: (
                    BranchEnd::Range { value },
                    format!(
                        "at L̄ = {value:.6} the family goes on as a symmetry image (mirror, \
                         reflection) of a traced part: it closes on itself"
                    ),
                ),
                branch_points: points
                    .iter()
                    .filter(|p| p.source == PointSource::BranchPoint)
                    .map(|p| p.value)
                    .collect(),
            }
        }
    }
}
