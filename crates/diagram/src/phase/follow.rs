//! Pseudo-arclength continuation of a Maxwell point in the parameter, with the reasons a
//! leg ends.

use rodloop_continuation::{
    Continuation, Direction, Driven, Flow, OnError, PseudoArclength, SpecialKind, StopReason,
};

use super::rows::branch_word;
use super::{CurveEnd, Exchange, Tracked};
use crate::maxwell::MaxwellProblem;
use crate::DiagramError;
use rodloop_solver::SurfaceSolve;

/// A leg of continuation: its accepted points and how it ended.
pub(super) struct Leg {
    pub(super) points: Vec<Tracked>,
    pub(super) end: CurveEnd,
}

/// Continue the Maxwell point from `(x0, p0)` towards `p_end` inside `[p_lo, p_hi]`. The
/// curve goes on through a fold where the two energy curves touch (two crossings merge: the
/// next arm is the other crossing, with the roles of the branches swapped) and stops where a
/// state loses stability, at a fold or branch point of one of the states, or where it leaves
/// the range.
pub(super) fn follow<M: SurfaceSolve>(
    problem: &MaxwellProblem<M>,
    start: &Tracked,
    p_end: f64,
    (p_lo, p_hi): (f64, f64),
    ex: Exchange,
    turns: &mut Vec<String>,
) -> Result<Leg, DiagramError> {
    let (x0, p0, index0) = (&start.x, start.p, start.index);
    let theta = |p: f64| problem.theta(p);
    let name = problem.param();
    if index0 != (0, 0) {
        return Ok(Leg {
            points: Vec::new(),
            end: CurveEnd {
                value: theta(p0),
                kind: "unstable".into(),
                reason: unstable_reason(ex, index0, theta(p0)),
            },
        });
    }
    if (p_end - p0).abs() < 1e-14 {
        return Ok(Leg {
            points: Vec::new(),
            end: CurveEnd {
                value: theta(p0),
                kind: "reached".into(),
                reason: "the start is the end of the range".into(),
            },
        });
    }
    let dir = if p_end < p0 {
        Direction::Backward
    } else {
        Direction::Forward
    };
    let settings = PseudoArclength::new()
        .with_ds(0.05)
        .and_then(|st| st.with_ds_bounds(1e-6, 2.0))
        .and_then(|st| st.with_range(p_lo.min(p0) - 1e-12, p_hi.max(p0) + 1e-12))
        .and_then(|st| st.with_direction(dir))
        .and_then(|st| st.with_max_steps(400))
        .and_then(|st| st.with_tol(1e-10))
        .and_then(|st| st.with_locate_tol(1e-6))
        .and_then(|st| st.with_detect_loops(false))
        .map_err(|e| DiagramError::InvalidOptions(e.to_string()))?;
    let cont = Continuation::new(problem, settings).with_stability_fn(|x, p| {
        match problem.indices(x, p) {
            Ok((a, b)) => a + 1000 * b,
            Err(_) => usize::MAX / 2,
        }
    });
    let mut stepper = cont.start(x0, p0).map_err(|e| DiagramError::Critical {
        from_branch: ex.from_branch,
        to_branch: ex.to_branch,
        lbar: x0[x0.len() - 1],
        reason: format!("continuation could not start: {e}"),
    })?;
    let mut points: Vec<Tracked> = Vec::new();
    let mut arm = start.arm;
    let mut prev = (x0.clone(), p0);
    // The continuation crate's stepping loop; this visitor ends the curve at the first
    // special point that ends it and records every accepted point.
    let driven = stepper.drive(OnError::Fail, |_, step| {
        for sp in &step.special {
            let lbar = sp.x[sp.x.len() - 1];
            let end = match &sp.kind {
                SpecialKind::IndexChange { old, new } if new > old => {
                    let idx = (new % 1000, new / 1000);
                    Some(CurveEnd {
                        value: theta(sp.p),
                        kind: "unstable".into(),
                        reason: unstable_reason(ex, idx, theta(sp.p)),
                    })
                }
                SpecialKind::Fold => {
                    // Which determinant changed sign across the step: a state's (it folds
                    // or branches in L̄) or only the slope of the energy difference
                    // (tangency of the two energy curves).
                    let before = problem.crossing_slope(&prev.0, prev.1).ok();
                    let after = step
                        .point
                        .as_ref()
                        .and_then(|pt| problem.crossing_slope(&pt.x, pt.p).ok());
                    match (before, after) {
                        (Some(b), Some(a)) if b.1 == a.1 && b.2 == a.2 && b.0 * a.0 < 0.0 => {
                            turns.push(format!(
                                "the crossing turns back in {name} at {:.6} (L̄ = {lbar:.6}): there the energy curves of {} and {} touch, and below it (in {name}) the two crossings merge and vanish",
                                theta(sp.p),
                                branch_word(ex.from_branch),
                                branch_word(ex.to_branch),
                            ));
                            arm += 1;
                            None
                        }
                        (b, a) => {
                            let who = match (b, a) {
                                (Some(b), Some(a)) if b.1 != a.1 && b.2 == a.2 => {
                                    format!("the state of {}", branch_word(ex.from_branch))
                                }
                                (Some(b), Some(a)) if b.1 == a.1 && b.2 != a.2 => {
                                    format!("the state of {}", branch_word(ex.to_branch))
                                }
                                _ => "one of the two states".to_string(),
                            };
                            Some(CurveEnd {
                                value: theta(sp.p),
                                kind: "fold".into(),
                                reason: format!(
                                    "the Maxwell point of {} and {} turns back in {name} at {:.6} (L̄ = {lbar:.6}) because {who} folds there: it merges with another state of its family and does not exist beyond",
                                    branch_word(ex.from_branch),
                                    branch_word(ex.to_branch),
                                    theta(sp.p),
                                ),
                            })
                        }
                    }
                }
                SpecialKind::BranchPoint => Some(CurveEnd {
                    value: theta(sp.p),
                    kind: "branch_point".into(),
                    reason: format!(
                        "a branch point of the Maxwell curve at {name} = {:.6} (L̄ = {lbar:.6}): a state meets another family (symmetry-breaking pitchfork)",
                        theta(sp.p),
                    ),
                }),
                _ => None,
            };
            if let Some(end) = end {
                return Flow::Stop(end);
            }
        }
        if let Some(pt) = &step.point {
            points.push(Tracked {
                x: pt.x.clone(),
                p: pt.p,
                index: pt
                    .index
                    .map(|i| (i % 1000, i / 1000))
                    .unwrap_or((usize::MAX, usize::MAX)),
                arm,
            });
            prev = (pt.x.clone(), pt.p);
        }
        Flow::Go
    });
    let v = theta(points.last().map(|t| t.p).unwrap_or(p0));
    let end = match driven {
        Driven::Visitor(end) => end,
        Driven::Failed(e) | Driven::TooSmall { cause: e, .. } => CurveEnd {
            value: v,
            kind: "failed".into(),
            reason: format!("the continuation failed after {name} = {v}: {e}"),
        },
        Driven::Stopped { reason: stop, .. } => {
            let (kind, reason) = match stop {
                StopReason::LeftRange { boundary } => {
                    if (boundary - p_end).abs() <= 1e-9 * p_end.abs().max(1.0) {
                        ("reached", "the end of the requested range".to_string())
                    } else {
                        (
                            "reached",
                            format!(
                                "the curve came back to {name} = {:.6} after turning (the other end of the traced range)",
                                theta(boundary)
                            ),
                        )
                    }
                }
                StopReason::StepTooSmall { ds, .. } => (
                    "failed",
                    format!("the continuation step fell below its minimum ({ds:.1e})"),
                ),
                StopReason::MaxSteps => ("failed", "the step budget (400) was used up".into()),
                other => ("failed", format!("{other:?}")),
            };
            CurveEnd {
                value: v,
                kind: kind.into(),
                reason,
            }
        }
    };
    Ok(Leg { points, end })
}

pub(super) fn unstable_reason(ex: Exchange, idx: (usize, usize), theta: f64) -> String {
    let who = match (idx.0 > 0, idx.1 > 0) {
        (true, true) => format!(
            "both states ({} and {})",
            branch_word(ex.from_branch),
            branch_word(ex.to_branch)
        ),
        (true, false) => format!("the state of {}", branch_word(ex.from_branch)),
        _ => format!("the state of {}", branch_word(ex.to_branch)),
    };
    format!(
        "{who} stops being a local minimum at {theta:.6} (indices {} and {}): a lower state of that branch family exists beyond, so this Maxwell point no longer separates the lowest branches",
        idx.0, idx.1
    )
}
