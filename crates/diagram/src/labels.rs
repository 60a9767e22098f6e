//! Stability labels of computed states.

use rodloop_continuation::exchange::{self, Ranked, Standing};
use serde::{Deserialize, Serialize};

use crate::critical::{lowest_interpolated, CriticalKind, CriticalLength};
use crate::types::{PointSource, TracedBranch, TracedPoint};

/// Stability label of an equilibrium (GUIDE §1, paper Sec. 3.1).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Label {
    /// Index 0 and the lowest energy among the computed branches at its length.
    Stable,
    /// Index 0 (a local minimum) but not the lowest.
    Metastable,
    /// Index > 0: the constrained Hessian has a negative direction.
    Unstable,
}

impl Label {
    /// `"stable"`, `"metastable"` or `"unstable"`.
    pub fn as_str(self) -> &'static str {
        match self {
            Label::Stable => "stable",
            Label::Metastable => "metastable",
            Label::Unstable => "unstable",
        }
    }
}

impl From<Standing> for Label {
    fn from(s: Standing) -> Self {
        match s {
            Standing::Stable => Label::Stable,
            Standing::Metastable => Label::Metastable,
            Standing::Unstable => Label::Unstable,
        }
    }
}

impl std::fmt::Display for Label {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// The sheets (positions in `branches`) of the lowest state at `lbar` (two at a critical
/// length).
///
/// Between consecutive critical lengths the lowest sheet is the one the left critical
/// length hands over to (so labels agree with the located critical lengths, not with the
/// coarser sample energies); where that sheet was not computed (e.g. the circle below
/// `L̄ = 1`) or does not cover `lbar`, the sheet of lowest interpolated energy. Exactly at
/// a collapse length the lowest state is the great circle, which is not a traced state:
/// the result is empty.
pub(crate) fn lowest_sheets(
    branches: &[TracedBranch],
    critical: &[CriticalLength],
    lbar: f64,
) -> Vec<usize> {
    let tol = 1e-12 * lbar.abs().max(1.0);
    let mut out: Vec<Option<usize>> = Vec::new();
    if critical
        .iter()
        .any(|c| c.kind == CriticalKind::Collapse && (c.lbar_cr - lbar).abs() <= tol)
    {
        return Vec::new();
    }
    if !critical.is_empty() {
        let k = critical.partition_point(|c| c.lbar_cr <= lbar + tol);
        let sheet = if k == 0 {
            critical[0].from_sheet
        } else {
            critical[k - 1].to_sheet
        };
        if k > 0 && (critical[k - 1].lbar_cr - lbar).abs() <= tol {
            out.push(critical[k - 1].from_sheet);
        }
        if untraced_lowest(critical, lbar) {
            return Vec::new();
        }
        out.push(sheet);
    }
    let mut out: Vec<usize> = out
        .into_iter()
        .flatten()
        .filter(|&i| i < branches.len() && branches[i].covers(lbar))
        .collect();
    if out.is_empty() {
        if let Some((i, _)) = lowest_interpolated(branches, lbar) {
            out.push(i);
        }
    }
    out
}

/// Whether the critical lengths name an untraced state as the lowest at `lbar`: the circle
/// below `L̄ = 1`, which the collapse onto the great circle hands over from (its energy is
/// exact, `E R/(πD) = 1/L̄` for a uniform rod, and no traced sheet lies below it).
fn untraced_lowest(critical: &[CriticalLength], lbar: f64) -> bool {
    let tol = 1e-12 * lbar.abs().max(1.0);
    critical.first().is_some_and(|c| {
        c.kind == CriticalKind::Collapse
            && c.from_sheet.is_none()
            && lbar < 1.0
            && lbar + tol < c.lbar_cr
    })
}

/// The `η` values of the lowest sheets at `lbar` ([`lowest_sheets`]).
pub(crate) fn lowest_etas(
    branches: &[TracedBranch],
    critical: &[CriticalLength],
    lbar: f64,
) -> Vec<u32> {
    lowest_sheets(branches, critical, lbar)
        .into_iter()
        .map(|i| branches[i].eta)
        .collect()
}

/// Relative allowance for the interpolation between traced states, added to each sheet's
/// energy estimate in the labeller's tie rule ([`rodloop_continuation::exchange`]; half of it
/// per sheet): the Hermite interpolation of traced energies between samples (their spacing
/// is at most a few `10⁻²` in `L̄`) is accurate to far better than this, and within it of a
/// located crossing the critical length decides.
const LABEL_MARGIN: f64 = 1e-7;

/// The error estimate of sheet `b`'s energy at `lbar` as the labeller sees it: the traced
/// state's own estimate there ([`crate::TracedPoint::energy_error`]), between two states the
/// larger of theirs, a state without one taking the largest of its sheet (none on the
/// sheet: 0), plus half of [`LABEL_MARGIN`] (relative) for the interpolation.
fn error_at(b: &TracedBranch, lbar: f64, energy: f64) -> f64 {
    let worst = b
        .points
        .iter()
        .filter_map(|p| p.energy_error)
        .fold(0.0, f64::max);
    let of = |p: &crate::TracedPoint| p.energy_error.unwrap_or(worst).abs();
    let k = b.points.partition_point(|p| p.value < lbar);
    let own = match (k.checked_sub(1).map(|i| &b.points[i]), b.points.get(k)) {
        (_, Some(p)) if p.value == lbar => of(p),
        (Some(a), Some(c)) => of(a).max(of(c)),
        (None, Some(c)) => of(c),
        (Some(a), None) => of(a),
        (None, None) => 0.0,
    };
    own + 0.5 * LABEL_MARGIN * energy.abs().max(1.0)
}

/// Whether sheet `b` has stability index 0 at `lbar`: at a traced state, that state's
/// index; between two, both neighbours' (`None` outside the traced span). A neighbour that
/// bounds the stretch carries its index on the stretch's side only where it is known there:
/// a located index change ([`TracedBranch::index_changes`], its own state or a branch point
/// where the index changes) counts with the change's index on that side (`above` after it,
/// `below` before it); a fold or branch point without one, where an eigenvalue of the
/// Hessian passes through zero, counts with none, and the stretch takes the other
/// neighbour's index (along a sheet the index is constant up to its singular end).
fn index0_at(b: &TracedBranch, lbar: f64) -> Option<bool> {
    if !b.covers(lbar) {
        return None;
    }
    let k = b.points.partition_point(|p| p.value < lbar);
    let at = |i: usize| b.points.get(i);
    // The index of the stretch beside `p` as `p` knows it: `after` the stretch above it.
    let side = |p: &TracedPoint, after: bool| -> Option<usize> {
        if let Some(c) = b.index_changes.iter().find(|c| c.value == p.value) {
            return Some(if after { c.above } else { c.below });
        }
        match p.source {
            PointSource::Fold | PointSource::BranchPoint => None,
            _ => Some(p.index),
        }
    };
    match (k.checked_sub(1).and_then(at), at(k)) {
        (_, Some(p)) if p.value == lbar => Some(p.index == 0),
        (Some(a), Some(c)) => Some(match (side(a, true), side(c, false)) {
            (Some(x), Some(y)) => x == 0 && y == 0,
            (Some(x), None) => x == 0,
            (None, Some(y)) => y == 0,
            (None, None) => a.index == 0 && c.index == 0,
        }),
        (None, Some(c)) => Some(c.index == 0),
        (Some(a), None) => Some(a.index == 0),
        _ => None,
    }
}

/// The sheets (positions in `branches`) of the stable state at `lbar`: the lowest state
/// of stability index 0 among the traced sheets (GUIDE §1: stable = global minimum among
/// the equilibria at that length, metastable = another local minimum).
///
/// The labeller [`rodloop_continuation::exchange::label`] on the sheets covering `lbar`,
/// each with its energy's error estimate ([`error_at`]), those the critical lengths name as
/// lowest ([`lowest_sheets`]) preferred in ties: where they have index 0 there and no other
/// index-0 sheet lies below them by more than the estimates, those (so labels agree with
/// the located critical lengths, not with the interpolated samples). A sheet of the same
/// branch tied with a preferred one is preferred too (two traced copies of one state, or
/// two families crossing there: one label for both). Where no preferred sheet is tied with
/// the least, every index-0 sheet tied with it is stable (its copies included). Otherwise
/// the index-0 sheet of lowest interpolated energy: the
/// critical lengths are exchanges between branches, and the lowest family within one branch
/// can change without one (two families of branch 1 at `D1/D0 = 0.001` near `L̄ = 2.85`),
/// or the lowest state can be a saddle (then a lower minimum was not traced, and the lowest
/// traced minimum is the stable state of the traced set). Empty where no traced state of
/// index 0 covers `lbar`, at a collapse length (the lowest state is the great circle) and
/// where the untraced circle below `L̄ = 1` is lowest ([`untraced_lowest`]).
pub(crate) fn stable_sheets(
    branches: &[TracedBranch],
    critical: &[CriticalLength],
    lbar: f64,
) -> Vec<usize> {
    let by_critical = lowest_sheets(branches, critical, lbar);
    let tol = 1e-12 * lbar.abs().max(1.0);
    if untraced_lowest(critical, lbar)
        || critical
            .iter()
            .any(|c| c.kind == CriticalKind::Collapse && (c.lbar_cr - lbar).abs() <= tol)
    {
        return Vec::new();
    }
    // Every sheet covering `lbar` as the labeller sees it: index 0 where the sheet has
    // index 0 there, the interpolated energy with its error estimate, preferred where the
    // critical lengths name it or it is tied with a named sheet of its branch.
    let mut sheets: Vec<(usize, Ranked)> = branches
        .iter()
        .enumerate()
        .filter_map(|(i, b)| {
            let index0 = index0_at(b, lbar)?;
            let energy = b.energy_at(lbar)?;
            Some((
                i,
                Ranked {
                    energy,
                    error: error_at(b, lbar, energy),
                    index: usize::from(!index0),
                    preferred: by_critical.contains(&i),
                },
            ))
        })
        .collect();
    let named: Vec<(u32, usize, Ranked)> = sheets
        .iter()
        .filter(|(_, r)| r.preferred)
        .map(|&(i, r)| (branches[i].branch, r.index, r))
        .collect();
    for (i, r) in &mut sheets {
        r.preferred |= named.iter().any(|(branch, index, n)| {
            *branch == branches[*i].branch
                && *index == r.index
                && (r.energy - n.energy).abs() <= r.error + n.error
        });
    }
    let ranked: Vec<Ranked> = sheets.iter().map(|(_, r)| *r).collect();
    exchange::label(&ranked)
        .into_iter()
        .zip(&sheets)
        .filter(|(l, _)| *l == Standing::Stable)
        .map(|(_, (i, _))| *i)
        .collect()
}

/// Labels of every traced state of every sheet: index > 0 "unstable"; index 0 "stable"
/// where its sheet is one of the [`stable_sheets`] at its length, else "metastable".
pub(crate) fn label_all(branches: &[TracedBranch], critical: &[CriticalLength]) -> Vec<Vec<Label>> {
    branches
        .iter()
        .enumerate()
        .map(|(i, b)| {
            b.points
                .iter()
                .map(|p| {
                    if p.index > 0 {
                        Label::Unstable
                    } else if stable_sheets(branches, critical, p.value).contains(&i) {
                        Label::Stable
                    } else {
                        Label::Metastable
                    }
                })
                .collect()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::types::{BranchEnd, BranchTimings};

    /// A sheet of branch 1 (η = 2) with energy `e0 + slope (L̄ − 1)` and the given indices at
    /// `L̄ = 1.0, 1.1, …`.
    fn sheet(family: u32, e0: f64, slope: f64, indices: &[usize]) -> TracedBranch {
        let points = indices
            .iter()
            .enumerate()
            .map(|(k, &index)| {
                let value = 1.0 + 0.1 * k as f64;
                TracedPoint {
                    value,
                    energy: e0 + slope * (value - 1.0),
                    energy_g: 0.0,
                    energy_error: None,
                    energy_trace: e0 + slope * (value - 1.0),
                    slope,
                    index,
                    lambda_min: 0.0,
                    lambda_max: 0.0,
                    amplitude: 0.0,
                    source: PointSource::Continuation,
                    state: Vec::new(),
                    finer: Default::default(),
                }
            })
            .collect();
        TracedBranch {
            branch: 1,
            eta: 2,
            param: rodloop_solver::Param::Lbar,
            family,
            sheet: 0,
            reversed: false,
            multiplicity: 1,
            fingerprint: String::new(),
            cells: 0,
            phase: false,
            points,
            low_end: BranchEnd::Range { value: 1.0 },
            high_end: BranchEnd::Range { value: 1.4 },
            stop_low: String::new(),
            stop_high: String::new(),
            seed: String::new(),
            index_changes: Vec::new(),
            steps: 0,
            seconds: 0.0,
            timings: BranchTimings::default(),
        }
    }

    /// A critical length that names `sheet` lowest above `lbar_cr`.
    fn handing_to(sheet: usize, lbar_cr: f64) -> CriticalLength {
        CriticalLength {
            index: 1,
            lbar_cr,
            kind: CriticalKind::Crossing,
            from_branch: 2,
            to_branch: 1,
            from_eta: 1,
            to_eta: 2,
            energy: 1.0,
            error_estimate: 0.0,
            slope_difference: 0.0,
            iterations: 0,
            note: String::new(),
            from_sheet: None,
            to_sheet: Some(sheet),
        }
    }

    /// Two index-0 families of one branch whose energies cross without a critical length
    /// (the critical lengths are exchanges between branches): the lower one is stable on
    /// each side of the crossing, the other metastable.
    #[test]
    fn lowest_family_of_one_branch_is_stable() {
        let a = sheet(1, 1.0, 1.0, &[0, 0, 0, 0, 0]);
        let b = sheet(2, 1.2, -1.0, &[0, 0, 0, 0, 0]);
        let branches = vec![a, b];
        let critical = vec![handing_to(0, 0.9)];
        let labels = label_all(&branches, &critical);
        // a: 1.0, 1.1, 1.2, 1.3, 1.4; b: 1.2, 1.1, 1.0, 0.9, 0.8 (equal at 1.1, where both
        // are the lowest: the family the critical length names and the one of its branch
        // tied with it).
        use Label::{Metastable as M, Stable as S};
        assert_eq!(labels[0], vec![S, S, M, M, M]);
        assert_eq!(labels[1], vec![M, S, S, S, S]);
    }

    /// The lowest traced state is a saddle: the lowest index-0 state is stable (and a length
    /// with no index-0 state has no stable label at all).
    #[test]
    fn lowest_minimum_is_stable_below_a_saddle() {
        let saddle = sheet(1, 1.0, 0.0, &[1, 1, 1, 1, 1]);
        let minimum = sheet(2, 1.5, 0.0, &[0, 0, 0, 1, 1]);
        let branches = vec![saddle, minimum];
        let critical = vec![handing_to(0, 0.9)];
        let labels = label_all(&branches, &critical);
        use Label::{Stable as S, Unstable as U};
        assert_eq!(labels[0], vec![U; 5]);
        assert_eq!(labels[1], vec![S, S, S, U, U]);
        assert!(stable_sheets(&branches, &critical, 1.35).is_empty());
        assert_eq!(stable_sheets(&branches, &critical, 1.15), vec![1]);
    }

    /// A located index change at `L̄ = 1.1` (index 1 below, 0 above) whose state carries the
    /// index below: the stretch after it is a local minimum, so the lower sheet is stable
    /// there, not the higher minimum beside it; before it the higher one is.
    #[test]
    fn the_stretch_after_a_located_index_change_takes_its_index() {
        let mut low = sheet(1, 1.0, 0.0, &[1, 1, 0, 0, 0]);
        low.points[1].source = PointSource::IndexChange;
        low.index_changes.push(crate::types::IndexChange {
            value: low.points[1].value,
            below: 1,
            above: 0,
        });
        let high = sheet(2, 1.5, 0.0, &[0, 0, 0, 0, 0]);
        let branches = vec![low, high];
        assert_eq!(stable_sheets(&branches, &[], 1.15), vec![0]);
        assert_eq!(stable_sheets(&branches, &[], 1.05), vec![1]);
        assert_eq!(index0_at(&branches[0], 1.15), Some(true));
        assert_eq!(index0_at(&branches[0], 1.05), Some(false));
        assert_eq!(index0_at(&branches[0], 1.1), Some(false));
    }

    /// A sheet that ends at a branch point whose own state counts index 1 (an eigenvalue
    /// passes through zero there): the stretch before it keeps the index of the sheet, 0,
    /// so the sheet is stable there below the higher minimum.
    #[test]
    fn the_stretch_before_a_singular_end_keeps_the_sheet_index() {
        let mut low = sheet(1, 1.0, 0.0, &[0, 0, 1]);
        low.points[2].source = PointSource::BranchPoint;
        let high = sheet(2, 1.5, 0.0, &[0, 0, 0]);
        let branches = vec![low, high];
        assert_eq!(index0_at(&branches[0], 1.15), Some(true));
        assert_eq!(stable_sheets(&branches, &[], 1.15), vec![0]);
        // An ordinary state of index 1 there is a located saddle: the stretch is not a
        // minimum.
        let mut plain = branches.clone();
        plain[0].points[2].source = PointSource::Continuation;
        assert_eq!(index0_at(&plain[0], 1.15), Some(false));
        assert_eq!(stable_sheets(&plain, &[], 1.15), vec![1]);
    }

    /// `b` with every state's energy raised by `shift` and given the error estimate `err`.
    fn copy_of(b: &TracedBranch, family: u32, shift: f64, err: f64) -> TracedBranch {
        let mut c = b.clone();
        c.family = family;
        for p in &mut c.points {
            p.energy += shift;
            p.energy_error = Some(err);
        }
        c
    }

    /// One state traced twice (two families of one branch whose energies agree to `7e-10`,
    /// each estimated to `5e-8`): both copies carry one label at every length, whether a
    /// critical length names one of them, none, or a lower minimum of another branch lies
    /// below both.
    #[test]
    fn copies_of_one_state_share_their_label() {
        use Label::{Metastable as M, Stable as S};
        let a = copy_of(&sheet(1, 1.0, 0.5, &[0, 0, 0, 0, 0]), 1, 0.0, 5e-8);
        for shift in [7e-10, -7e-10] {
            let b = copy_of(&a, 2, shift, 5e-8);
            // Named by a critical length, and named by none.
            for critical in [vec![handing_to(0, 0.9)], vec![handing_to(1, 0.9)], vec![]] {
                let labels = label_all(&[a.clone(), b.clone()], &critical);
                assert_eq!(labels[0], vec![S; 5], "shift {shift}, {critical:?}");
                assert_eq!(labels[1], vec![S; 5], "shift {shift}, {critical:?}");
            }
            // A minimum of branch 2 below both by 1e-3 (far beyond the estimates), which a
            // critical length names: both copies metastable.
            let mut low = copy_of(&a, 1, -1e-3, 5e-8);
            low.branch = 2;
            low.eta = 1;
            let labels = label_all(&[a.clone(), b.clone(), low], &[handing_to(2, 0.9)]);
            assert_eq!(labels[0], vec![M; 5]);
            assert_eq!(labels[1], vec![M; 5]);
            assert_eq!(labels[2], vec![S; 5]);
        }
    }

    /// A sheet's error estimate at a length: its own state's there, the larger of the two
    /// neighbours' between states, the sheet's largest for a state without one, plus the
    /// interpolation allowance.
    #[test]
    fn error_estimate_of_a_sheet_at_a_length() {
        let mut b = sheet(1, 1.0, 0.0, &[0, 0, 0, 0, 0]);
        b.points[1].energy_error = Some(2e-6);
        b.points[2].energy_error = Some(3e-6);
        let allowance = 0.5 * LABEL_MARGIN;
        let close = |x: f64, y: f64| (x - y).abs() <= 1e-15;
        assert!(close(error_at(&b, 1.1, 1.0), 2e-6 + allowance));
        assert!(close(error_at(&b, 1.15, 1.0), 3e-6 + allowance));
        // States 0, 3, 4 have none: the sheet's largest.
        assert!(close(error_at(&b, 1.0, 1.0), 3e-6 + allowance));
        assert!(close(error_at(&b, 1.35, 1.0), 3e-6 + allowance));
        assert!(close(error_at(&b, 1.35, 4.0), 3e-6 + 4.0 * allowance));
    }
}
