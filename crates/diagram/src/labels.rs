//! Stability labels of computed states.

use serde::{Deserialize, Serialize};

use crate::critical::{lowest_interpolated, CriticalKind, CriticalLength};
use crate::types::TracedBranch;

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
        if sheet.is_none() && k == 0 && critical[0].kind == CriticalKind::Collapse && lbar < 1.0 {
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

/// Labels of every traced state of every sheet.
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
                    } else if lowest_sheets(branches, critical, p.value).contains(&i) {
                        Label::Stable
                    } else {
                        Label::Metastable
                    }
                })
                .collect()
        })
        .collect()
}
