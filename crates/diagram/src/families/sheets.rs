//! Cutting the followed curves of a branch into sheets monotone in `L̄`, with the
//! quantities of their states.

use rodloop_solver::{Param, ParamProblem, SurfaceSolve};

use super::images::Images;
use super::{Curve, SAME_STATE};
use crate::march::MarchPoint;
use crate::parallel::run_parallel;
use crate::states::finish_point;
use crate::types::{BranchEnd, BranchTimings, IndexChange, PointSource, TracedBranch};
use crate::DiagramOptions;

/// The sheets of the followed `curves` of branch `eta` (paper branch `branch`, traced with
/// `cells` cells): each curve is cut at its turning points into pieces monotone in `L̄`
/// (one [`TracedBranch`] each, with its family, position along the family and direction)
/// whose states are finished at the reporting resolutions ([`finish_point`]); pieces that
/// repeat a kept one (the mirror half of an asymmetric curve traced through its pitchfork)
/// are dropped, every asymmetric sheet gets multiplicity 2, and the families are numbered
/// 1, 2, … in the order kept. `seed_note[c]` says how curve `c` was seeded (`None`: by
/// branch switching).
pub(super) fn make_sheets<M: SurfaceSolve>(
    opts: &DiagramOptions,
    problem: &ParamProblem<M>,
    images: &Images,
    curves: &[Curve],
    seed_note: &[Option<String>],
    (branch, eta, cells): (u32, u32, usize),
) -> Vec<TracedBranch> {
    let mut sheets: Vec<TracedBranch> = Vec::new();
    let mut kept_states: Vec<(usize, Vec<f64>, f64)> = Vec::new();
    // Every state is finished independently of the others: all of them on the crate's
    // thread pool, then the curves are cut in order.
    let raw: Vec<(usize, &MarchPoint)> = curves
        .iter()
        .enumerate()
        .flat_map(|(ci, c)| thinned(images, &c.points).into_iter().map(move |r| (ci, r)))
        .collect();
    let mut done = run_parallel(
        opts.worker_threads(),
        raw,
        &mut |_| {},
        &mut |_| {},
        |(ci, r), _| (ci, finish_point(opts, problem, r).map(|p| (p, r.source))),
    )
    .into_iter()
    .peekable();
    for (ci, curve) in curves.iter().enumerate() {
        let mut finished = Vec::new();
        while let Some((_, f)) = done.next_if(|(c, _)| *c == ci) {
            finished.extend(f);
        }
        let mut pieces = split_monotone(&finished);
        let count = pieces.len();
        for (k, piece) in pieces.drain(..).enumerate() {
            if piece.len() < 2 {
                continue;
            }
            let reversed = piece[0].0.value > piece[piece.len() - 1].0.value;
            let mut pts: Vec<_> = piece;
            if reversed {
                pts.reverse();
            }
            // Ends: the curve's own ends, or the turning point / branch point between sheets
            // (in arclength order first, then by L̄).
            let inner = |src: PointSource, value: f64| match src {
                PointSource::BranchPoint => (
                    BranchEnd::BranchPoint { value },
                    format!("branch point at L̄ = {value:.6}"),
                ),
                _ => (
                    BranchEnd::Fold { value },
                    format!("fold (turning point in L̄) at L̄ = {value:.6}"),
                ),
            };
            let (lo_v, hi_v) = (pts[0].0.value, pts[pts.len() - 1].0.value);
            let (arc_first, arc_last) = if reversed {
                ((pts[pts.len() - 1].1, hi_v), (pts[0].1, lo_v))
            } else {
                ((pts[0].1, lo_v), (pts[pts.len() - 1].1, hi_v))
            };
            let first_end = if k == 0 {
                curve.start_end.clone()
            } else {
                inner(arc_first.0, arc_first.1)
            };
            let last_end = if k + 1 == count {
                curve.finish_end.clone()
            } else {
                inner(arc_last.0, arc_last.1)
            };
            let ((low_end, stop_low), (high_end, stop_high)) = if reversed {
                (last_end, first_end)
            } else {
                (first_end, last_end)
            };
            fill_corrections(&mut pts);
            let index_changes = index_changes_of(&pts);
            let midk = pts.len() / 2;
            let mid_state = pts[midk].0.state.clone();
            let mid_value = pts[midk].0.value;
            // A repetition of a kept sheet (its mirror image, its reflection)?
            let duplicate = kept_states.iter().any(|(si, _, _)| {
                let s: &TracedBranch = &sheets[*si];
                let (a, b) = s.span();
                if !(a <= lo_v + 1e-6 && b >= hi_v - 1e-6) {
                    return false;
                }
                let z = s.state_near(mid_value);
                images.dist_images(&z, &mid_state) < SAME_STATE
            });
            if duplicate {
                continue;
            }
            let multiplicity = if images.symmetric(&mid_state) { 1 } else { 2 };
            let tb = TracedBranch {
                branch,
                eta,
                param: Param::Lbar,
                family: ci as u32 + 1,
                sheet: k as u32,
                reversed,
                multiplicity,
                fingerprint: opts.fingerprint(),
                cells,
                phase: false,
                points: pts.into_iter().map(|(p, _)| p).collect(),
                low_end,
                high_end,
                stop_low,
                stop_high,
                seed: format!(
                    "family {} of branch {branch}: {}",
                    ci + 1,
                    seed_note
                        .get(ci)
                        .cloned()
                        .flatten()
                        .unwrap_or_else(|| "found by branch switching".into())
                ),
                index_changes,
                steps: 0,
                seconds: 0.0,
                timings: BranchTimings::default(),
            };
            kept_states.push((sheets.len(), mid_state, mid_value));
            sheets.push(tb);
        }
    }
    // Families numbered 1, 2, … in the order kept.
    let mut map: Vec<u32> = Vec::new();
    for s in &mut sheets {
        let pos = match map.iter().position(|&f| f == s.family) {
            Some(p) => p,
            None => {
                map.push(s.family);
                map.len() - 1
            }
        };
        s.family = pos as u32 + 1;
    }
    sheets
}

/// States of a sheet whose half-resolution partner failed (no `energy_error`; typically
/// right next to a branch point) get the Richardson correction `energy − energy_trace` of
/// the nearest state of the sheet that has one, so that the sheet's energies are of one
/// kind (a jump of the correction, ~10⁻⁴, would read as a kink). `energy_error` stays
/// `None`: these energies have no estimate of their own.
fn fill_corrections(pts: &mut [(crate::TracedPoint, PointSource)]) {
    let with: Vec<(f64, f64)> = pts
        .iter()
        .filter(|p| p.0.energy_error.is_some())
        .map(|p| (p.0.value, p.0.energy - p.0.energy_trace))
        .collect();
    if with.is_empty() {
        return;
    }
    for p in pts.iter_mut().filter(|p| p.0.energy_error.is_none()) {
        let v = p.0.value;
        let corr = with
            .iter()
            .min_by(|a, b| (a.0 - v).abs().total_cmp(&(b.0 - v).abs()))
            .map_or(0.0, |c| c.1);
        p.0.energy = p.0.energy_trace + corr;
    }
}

/// Index changes between consecutive states of a sheet (increasing `L̄`): at the later state
/// where it is a located index change, or a fold or branch point after a regular state (an
/// eigenvalue of the Hessian passes through zero there, so the index changes there and that
/// state's own index is one side's); otherwise at the earlier state. Between two singular
/// states (a sheet from a branch point to a fold) neither index is the sheet's, and no
/// change is recorded.
fn index_changes_of(pts: &[(crate::TracedPoint, PointSource)]) -> Vec<IndexChange> {
    let singular = |s: PointSource| matches!(s, PointSource::Fold | PointSource::BranchPoint);
    pts.windows(2)
        .filter(|w| w[0].0.index != w[1].0.index && !(singular(w[0].1) && singular(w[1].1)))
        .map(|w| IndexChange {
            value: if w[1].1 == PointSource::IndexChange || (singular(w[1].1) && !singular(w[0].1))
            {
                w[1].0.value
            } else {
                w[0].0.value
            },
            below: w[0].0.index,
            above: w[1].0.index,
        })
        .collect()
}

/// Least spacing in `L̄` of the continuation states a sheet keeps ([`thinned`]).
const MIN_SPACING: f64 = 5e-4;

/// The states of a curve that become sheet states: all but the continuation states closer
/// than [`MIN_SPACING`] in `L̄` and than `SAME_STATE` in shape to the previous one kept
/// (where a family creeps through a nearly singular stretch, e.g. branch 2 at
/// `D1/D0 = 0.001` near `L̄ = 1.1` with 400 steps in 0.025, those would be most of the
/// diagram's states); located points, the ends and the turning states in `L̄` are always
/// kept.
fn thinned<'p>(images: &Images, points: &'p [MarchPoint]) -> Vec<&'p MarchPoint> {
    let n = points.len();
    let mut out: Vec<&MarchPoint> = Vec::with_capacity(n);
    for (i, p) in points.iter().enumerate() {
        let keep = match out.last() {
            None => true,
            Some(last) => {
                let turning = i + 1 < n
                    && i > 0
                    && (points[i + 1].value - p.value) * (p.value - points[i - 1].value) <= 0.0;
                p.source != PointSource::Continuation
                    || i + 1 == n
                    || turning
                    || (p.value - last.value).abs() >= MIN_SPACING
                    || images.dist(&p.x, &last.x) >= SAME_STATE
            }
        };
        if keep {
            out.push(p);
        }
    }
    out
}

/// Cut a curve (arclength order) into pieces monotone in `L̄`; the turning state belongs
/// to both pieces.
fn split_monotone(
    pts: &[(crate::TracedPoint, PointSource)],
) -> Vec<Vec<(crate::TracedPoint, PointSource)>> {
    let mut out: Vec<Vec<_>> = Vec::new();
    let mut cur: Vec<(crate::TracedPoint, PointSource)> = Vec::new();
    let mut dir = 0.0f64;
    for p in pts {
        if let Some(last) = cur.last() {
            let d = p.0.value - last.0.value;
            if d.abs() <= 1e-13 * p.0.value.abs().max(1.0) {
                // Same length (a located point repeated): keep the located one.
                if p.1 != PointSource::Continuation {
                    cur.pop();
                    cur.push(p.clone());
                }
                continue;
            }
            let s = d.signum();
            if dir != 0.0 && s != dir {
                let turn = cur.last().cloned().expect("non-empty");
                out.push(std::mem::take(&mut cur));
                cur.push(turn);
            }
            dir = s;
        }
        cur.push(p.clone());
    }
    if !cur.is_empty() {
        out.push(cur);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::TracedPoint;

    fn pt(value: f64, src: PointSource) -> (TracedPoint, PointSource) {
        (
            TracedPoint {
                value,
                energy: value,
                energy_g: 0.0,
                energy_error: None,
                energy_trace: value,
                slope: 1.0,
                index: 0,
                lambda_min: 0.0,
                lambda_max: 0.0,
                amplitude: 0.0,
                source: src,
                state: vec![],
                finer: Default::default(),
            },
            src,
        )
    }

    /// A curve up to a fold, back down past the start, and up again is three monotone
    /// pieces sharing their turning states.
    #[test]
    fn split_at_turning_points() {
        let c = PointSource::Continuation;
        let pts: Vec<_> = [1.0, 1.2, 1.4, 1.3, 1.1, 0.9, 1.0, 1.5]
            .iter()
            .map(|&v| pt(v, c))
            .collect();
        let pieces = split_monotone(&pts);
        let values: Vec<Vec<f64>> = pieces
            .iter()
            .map(|p| p.iter().map(|q| q.0.value).collect())
            .collect();
        assert_eq!(
            values,
            vec![
                vec![1.0, 1.2, 1.4],
                vec![1.4, 1.3, 1.1, 0.9],
                vec![0.9, 1.0, 1.5]
            ]
        );
    }
}
