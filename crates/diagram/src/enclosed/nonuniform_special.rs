//! Special points of the lifted-off sheets of a non-uniform rod (see `nonuniform.rs`), and
//! what the traces that stop there stop at.
//!
//! * **Branch points.** Where the Hessian index of a lifted-off sheet changes between two
//!   sampled states, an eigenvalue on the tangent space of the active constraints crosses
//!   zero: a pitchfork (or a transcritical point) of the enclosed sheet, where another
//!   family meets it. It is located as the root of that eigenvalue on re-solved states on
//!   the levels `N/2` and `N`, or `N` and `2N` where `N/2` does not change its index there
//!   (`locate.rs`: Brent's method, the estimate the final bracket plus the distance between
//!   the two levels' roots). Where the eigenvalue jumps at the
//!   root instead, the contact set changes there and no eigenvalue crosses zero: no branch
//!   point is reported, and a note says where (as for uniform rods, `trace.rs`). Where the
//!   index changes by more than one between a sheet's end next to the great circle it
//!   collapses onto and the sample before ([`collapse_jump`]), several eigenvalues change
//!   sign in between: no branch point is reported, and a note says so. Where the
//!   location fails otherwise (a re-solve does not converge next to the singular point, or
//!   the index does not change next to the pair on the coarser level nor on twice the finer
//!   level's cells), the root of the eigenvalue
//!   interpolated linearly between the two states stands, with half the bracket as its
//!   estimate, and a warning says why, unless a fold of the same family located from a
//!   trace's stop lies in the bracket with the same index change ([`unlocated_at_folds`]):
//!   then the fold changes the index, and a note says so. The re-solves have the default
//!   Newton budget (80 iterations, no stall window, as for uniform rods), not the tracer's
//!   (30, given up after 6 that do not halve the residual): next to a singular point Newton
//!   converges slowly, and with the tracer's budget three index changes of the two-segment
//!   scene that are changes of the contact set (located to `2·10⁻⁸`–`10⁻⁶`) stay
//!   interpolated branch points, for 1.8 s less wall time of that diagram.
//! * **Stops.** A trace that stops where Newton fails under step halving is explained when
//!   it stops next to the end of its branch's range (the `m`-fold great circle, where the
//!   sheet collapses onto the wall: the collapse at `L̄ = m` is exact), where the family
//!   folds (located from the stop by pseudo-arclength, `fold.rs`; a fold event, once per
//!   fold), or next to a branch point or a fold of its branch (a family that ends where it
//!   meets another: natural parameter steps cannot pass the vertical tangent of a
//!   pitchfork's asymmetric side or a fold; within the point's estimate plus `2e-2`), or
//!   where the family's index changes at a change of its contact set located on re-solved
//!   states (to that location's bracket). Other stops stay warnings.

use rodloop_solver::enclosed::EnclosedOptions;
use rodloop_solver::SolverError;

use super::fold::{fold_at_stop, StopFold};
use super::levels::Levels;
use super::locate::{is_jump, jump_at, locate};
use super::nonuniform_sheet::SheetOut;
use super::trace::TraceStop;
use super::{EnclosedEvent, EventKind, PointSource};

/// The finest level of a sample's [`Levels`]: the state reported.
const FINEST: usize = 2;

/// Eigenvalue `k` (ascending) on the tangent space of the active constraints, level `lvl`.
fn eigenvalue(l: &Levels, lvl: usize, k: usize) -> Result<f64, SolverError> {
    let (_, vals) = l.states[lvl].stability(1e-6)?;
    vals.get(k)
        .copied()
        .ok_or_else(|| SolverError::InvalidInput("too few eigenvalues".into()))
}

/// Branch points of a lifted-off sheet (see the module docs), notes for index changes at a
/// change of the contact set (the eigenvalue jumps, no eigenvalue crosses zero: no branch
/// point) with where they were located, notes for the collapse onto a great circle, and the
/// index changes that were not located (placed by interpolation; [`unlocated_at_folds`]
/// decides whether they are written).
pub(super) fn branch_points(s: &SheetOut) -> SheetBranchPoints {
    let mut events = Vec::new();
    let mut warnings = Vec::new();
    let mut notes = Vec::new();
    let mut unlocated = Vec::new();
    let mut contact_changes = Vec::new();
    {
        let pts: Vec<_> = s
            .points
            .iter()
            .filter(|p| p.source == PointSource::Model)
            .collect();
        for w in pts.windows(2) {
            let (p, q) = (w[0], w[1]);
            if p.index == q.index {
                continue;
            }
            let find = |x: f64| s.levels.iter().find(|l| (l.lbar - x).abs() < 1e-12);
            let (Some(a), Some(b)) = (find(p.lbar), find(q.lbar)) else {
                continue;
            };
            // The indices are those of the finest levels ([`Levels::index`]), where the
            // crossing eigenvalue is interpolated below.
            let (ip, iq) = (p.index, q.index);
            if let Some(m) = collapse_jump(s, p.lbar, q.lbar, ip, iq) {
                notes.push(format!(
                    "branch {} (eta = {}) family {}: the index changes from {ip} to {iq} between lbar = {:.6} and {:.6}, the sheet's end next to the {m}-fold great circle onto which it collapses: {} eigenvalues change sign between them as the loop nears the circle; not one branch point, none reported",
                    s.branch,
                    s.eta,
                    s.family,
                    p.lbar,
                    q.lbar,
                    ip.abs_diff(iq),
                ));
                continue;
            }
            // Located on re-solved states (see the module docs).
            let mut sorted: Vec<&Levels> = s.levels.iter().collect();
            sorted.sort_by(|u, v| u.lbar.total_cmp(&v.lbar));
            let j = sorted.iter().position(|l| (l.lbar - a.lbar).abs() < 1e-12);
            let consecutive = j.is_some_and(|j| {
                sorted
                    .get(j + 1)
                    .is_some_and(|n| (n.lbar - b.lbar).abs() < 1e-12)
            });
            let mut why = String::from("the two states are not consecutive on the sheet");
            if let (Some(j), true) = (j, consecutive) {
                let got = locate(&sorted, j, [1, 2], &EnclosedOptions::default());
                if let Err(e) = &got {
                    if is_jump(e) {
                        if let Some(at) = jump_at(e) {
                            contact_changes.push(ContactChange {
                                branch: s.branch,
                                family: s.family,
                                at,
                            });
                        }
                        notes.push(format!(
                            "branch {} (eta = {}) family {}: the index changes from {ip} to {iq} between lbar = {:.6} and {:.6} at a change of the contact set, not at a branch point ({e})",
                            s.branch, s.eta, s.family, p.lbar, q.lbar
                        ));
                        continue;
                    }
                    why = e.to_string();
                }
                if let Ok(v) = got {
                    events.push(EnclosedEvent {
                        kind: EventKind::BranchPoint,
                        branch: s.branch,
                        family: s.family,
                        lbar: v.lbar,
                        error_estimate: v.error_estimate,
                        energy: v.energy,
                        index_before: v.index_below,
                        index_after: v.index_above,
                    });
                    continue;
                }
            }
            let k = ip.min(iq);
            // The crossing eigenvalue at the two states (on that level), interpolated
            // linearly; the estimate is half the bracket.
            let located = eigenvalue(a, FINEST, k).and_then(|fa| {
                let fb = eigenvalue(b, FINEST, k)?;
                let t = if fa * fb < 0.0 { fa / (fa - fb) } else { 0.5 };
                let x = a.lbar + t * (b.lbar - a.lbar);
                let energy = p.energy + t * (q.energy - p.energy);
                Ok((x, 0.5 * (b.lbar - a.lbar).abs(), energy))
            });
            match located {
                Ok((x, err, energy)) => unlocated.push(Unlocated {
                    warning: format!(
                        "branch {} (eta = {}) family {}: the branch point between lbar = {:.6} and {:.6} is placed by interpolation only (to half the bracket): not located on re-solved states ({why})",
                        s.branch, s.eta, s.family, p.lbar, q.lbar
                    ),
                    bracket: (p.lbar, q.lbar),
                    event: EnclosedEvent {
                        kind: EventKind::BranchPoint,
                        branch: s.branch,
                        family: s.family,
                        lbar: x,
                        error_estimate: err,
                        energy,
                        index_before: ip,
                        index_after: iq,
                    },
                }),
                Err(e) => warnings.push(format!(
                    "branch {} (eta = {}) family {}: the index changes from {} to {} between lbar = {:.6} and {:.6}, but the branch point was not located ({e})",
                    s.branch, s.eta, s.family, p.index, q.index, p.lbar, q.lbar
                )),
            }
        }
    }
    SheetBranchPoints {
        events,
        notes,
        warnings,
        unlocated,
        contact_changes,
    }
}

/// An index change of a sheet located on re-solved states as a change of the contact set
/// (the eigenvalue jumps; no branch point): at `L̄ = at.0 ± at.1`.
#[derive(Clone, Debug)]
pub(super) struct ContactChange {
    pub(super) branch: u32,
    pub(super) family: u32,
    pub(super) at: (f64, f64),
}

/// An index change of a sheet that was not located on re-solved states: the branch point
/// placed by interpolating the crossing eigenvalue between the two samples `bracket`, with
/// the warning that says so ([`unlocated_at_folds`] decides whether it is written).
#[derive(Clone, Debug)]
pub(super) struct Unlocated {
    pub(super) event: EnclosedEvent,
    pub(super) bracket: (f64, f64),
    pub(super) warning: String,
}

/// What [`branch_points`] finds on one sheet: located branch points, notes, warnings, and
/// the index changes placed by interpolation only.
pub(super) struct SheetBranchPoints {
    pub(super) events: Vec<EnclosedEvent>,
    pub(super) notes: Vec<String>,
    pub(super) warnings: Vec<String>,
    pub(super) unlocated: Vec<Unlocated>,
    pub(super) contact_changes: Vec<ContactChange>,
}

/// The index changes placed by interpolation only (`unlocated`) against the folds located
/// from the traces' stops (`folds`, [`fold_events`]): a fold of the same family inside the
/// bracket (to its estimate) that changes the index between the same two values is what
/// changes it (a fold changes the index by one; the two samples lie on its two sides), so no
/// branch point is written there and a note names the fold; the others are written as
/// branch points with their warnings. Returns `(events, notes, warnings)`.
pub(super) fn unlocated_at_folds(
    unlocated: Vec<Unlocated>,
    folds: &[EnclosedEvent],
) -> (Vec<EnclosedEvent>, Vec<String>, Vec<String>) {
    let (mut events, mut notes, mut warnings) = (Vec::new(), Vec::new(), Vec::new());
    for u in unlocated {
        let v = &u.event;
        let (lo, hi) = (u.bracket.0.min(u.bracket.1), u.bracket.0.max(u.bracket.1));
        let same_change = |f: &EnclosedEvent| {
            let mut a = [f.index_before, f.index_after];
            let mut b = [v.index_before, v.index_after];
            a.sort_unstable();
            b.sort_unstable();
            a == b
        };
        let fold = folds.iter().find(|f| {
            f.kind == EventKind::Fold
                && f.branch == v.branch
                && f.family == v.family
                && f.lbar >= lo - f.error_estimate
                && f.lbar <= hi + f.error_estimate
                && same_change(f)
        });
        match fold {
            Some(f) => notes.push(format!(
                "branch {} family {}: the index changes from {} to {} between lbar = {lo:.6} and {hi:.6} at the fold of the family at L̄ = {:.9} ± {:.1e} (located from a trace's stop), not at a branch point; none reported",
                v.branch, v.family, v.index_before, v.index_after, f.lbar, f.error_estimate
            )),
            None => {
                warnings.push(u.warning);
                events.push(u.event);
            }
        }
    }
    (events, notes, warnings)
}

/// The great circle `L̄ = m` where the index changes from `ip` to `iq` by more than one
/// between two samples of sheet `s` at `a < b`, one of them the sheet's end within
/// [`NEAR_CIRCLE`] of the circle that ends its branch's range, where the sheet collapses onto
/// the `m`-fold great circle: several eigenvalues change sign between the two samples (the
/// two-segment enclosed scene: index 0 or 1 up to `4·10⁻²` before `L̄ = 2` and `3`, index 7
/// or 8 at `5·10⁻⁵` before them), so what lies in between is not one branch point, and the
/// interpolated root of one eigenvalue would report a point that does not exist.
fn collapse_jump(s: &SheetOut, a: f64, b: f64, ip: usize, iq: usize) -> Option<u32> {
    if ip.abs_diff(iq) < 2 {
        return None;
    }
    let ends = [s.points.first(), s.points.last()].map(|p| p.map(|p| p.lbar));
    [a, b]
        .into_iter()
        .filter(|x| ends.iter().flatten().any(|e| (e - x).abs() < 1e-12))
        .find_map(|x| circle_next_to(s, x))
        .map(|m| m.round() as u32)
}

/// Distance within which a trace's stop is put down to a great circle `L̄ = m` ending its
/// branch's range.
const NEAR_CIRCLE: f64 = 5e-3;

/// Distance, beyond the own estimate of a branch point (half its bracket) or a fold, within
/// which a trace's stop is put down to it.
const NEAR_BRANCH_POINT: f64 = 2e-2;

/// The great circle `L̄ = m` ending the range of sheet `s`'s branch (`m = η ± 1`) that a stop
/// at `lbar` lies next to, if any.
fn circle_next_to(s: &SheetOut, lbar: f64) -> Option<f64> {
    let e = f64::from(s.eta);
    [e - 1.0, e + 1.0]
        .into_iter()
        .find(|m| (lbar - m).abs() < NEAR_CIRCLE)
}

/// The folds at the stops of sheet `s`, one entry per stop (`fold.rs`); none for a stop
/// next to a great circle ending the branch's range (a collapse, explained below).
pub(super) fn stop_folds(s: &SheetOut) -> Vec<StopFold> {
    s.stops
        .iter()
        .map(|st| match circle_next_to(s, st.lbar) {
            Some(_) => StopFold::None,
            None => fold_at_stop(&st.last, st.toward),
        })
        .collect()
}

/// The fold events of the stops' folds (`folds[i]` of sheet `outs[i]`): one per fold, a fold
/// reached from both of its sides (the two families that meet there) once.
pub(super) fn fold_events(outs: &[SheetOut], folds: &[Vec<StopFold>]) -> Vec<EnclosedEvent> {
    let mut events: Vec<EnclosedEvent> = Vec::new();
    for (s, fs) in outs.iter().zip(folds) {
        for f in fs.iter().filter_map(|f| match f {
            StopFold::Located(f) => Some(f),
            _ => None,
        }) {
            let seen = events.iter().any(|v| {
                v.branch == s.branch
                    && (v.lbar - f.lbar).abs() <= v.error_estimate + f.error_estimate
            });
            if !seen {
                events.push(EnclosedEvent {
                    kind: EventKind::Fold,
                    branch: s.branch,
                    family: s.family,
                    lbar: f.lbar,
                    error_estimate: f.error_estimate,
                    energy: f.energy,
                    index_before: f.index_before,
                    index_after: f.index_after,
                });
            }
        }
    }
    events
}

/// Sort the traces' stops into notes (explained: the end of the branch's range, a fold
/// located from the stop, or a branch point of the branch) and warnings (see the module
/// docs). Returns `(notes, warnings)`.
pub(super) fn classify_stops(
    outs: &[SheetOut],
    events: &[EnclosedEvent],
    contact_changes: &[ContactChange],
    folds: &[Vec<StopFold>],
) -> (Vec<String>, Vec<String>) {
    let (mut notes, mut warnings) = (Vec::new(), Vec::new());
    for (s, fs) in outs.iter().zip(folds) {
        for (st, fold) in s.stops.iter().zip(fs) {
            let text = match fold {
                StopFold::CoarseOnly(x) => format!(
                    "{} (the trace's level N/2 folds at L̄ = {x:.9}, {:.1e} from the stop, by pseudo-arclength from the last state across its contact changes, where level N meets no fold before the next sample: the walk of all levels cannot pass a fold of its coarser mesh)",
                    st.text,
                    (x - st.lbar).abs()
                ),
                _ => st.text.clone(),
            };
            let st = &TraceStop { text, ..st.clone() };
            if let Some(m) = circle_next_to(s, st.lbar) {
                notes.push(format!(
                    "{} — explained: {:.1e} from L̄ = {m}, where this branch's sheets end on the {m}-fold great circle (a collapse, exact)",
                    st.text,
                    (st.lbar - m).abs()
                ));
                continue;
            }
            if let StopFold::Located(f) = fold {
                notes.push(format!(
                    "{} — explained: the family folds at L̄ = {:.9} ± {:.1e}, {:.1e} from the stop (index {} before, {} past it; pseudo-arclength from the last state across its contact changes, levels N/2 and N)",
                    st.text,
                    f.lbar,
                    f.error_estimate,
                    (f.lbar - st.lbar).abs(),
                    f.index_before,
                    f.index_after
                ));
                continue;
            }
            let bp = events
                .iter()
                .filter(|v| matches!(v.kind, EventKind::BranchPoint | EventKind::Fold))
                .filter(|v| v.branch == s.branch)
                .min_by(|u, v| {
                    (u.lbar - st.lbar)
                        .abs()
                        .total_cmp(&(v.lbar - st.lbar).abs())
                });
            match bp {
                Some(v) if (v.lbar - st.lbar).abs() < v.error_estimate + NEAR_BRANCH_POINT => notes.push(format!(
                    "{} — consistent with an end where this family meets another: {:.1e} from the {} of branch {} family {} at L̄ = {:.6} ± {:.1e}",
                    st.text,
                    (st.lbar - v.lbar).abs(),
                    if v.kind == EventKind::Fold { "fold" } else { "branch point" },
                    v.branch,
                    v.family,
                    v.lbar,
                    v.error_estimate
                )),
                _ => {
                    // A stop where the family's index changes at a change of its contact set
                    // (to the located change's bracket): its Hessian on the tangent space
                    // changes there, and the walk does not get past it.
                    let at_change = contact_changes.iter().find(|c| {
                        c.branch == s.branch
                            && c.family == s.family
                            && (c.at.0 - st.lbar).abs() <= c.at.1 + 1e-6
                    });
                    match at_change {
                        Some(c) => notes.push(format!(
                            "{} — explained: the index of the family changes at a change of its contact set at L̄ = {:.6} ± {:.0e}, located on re-solved states (no eigenvalue crosses zero)",
                            st.text, c.at.0, c.at.1
                        )),
                        None => warnings.push(st.text.clone()),
                    }
                }
            }
        }
    }
    (notes, warnings)
}
