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

/// The `η` values of the lowest branch at `lbar` (two at a critical length).
///
/// Between consecutive critical lengths the lowest branch is the one the left critical
/// length hands over to (so labels agree with the located critical lengths, not with the
/// coarser sample energies); where that branch was not computed (`η = 0`, e.g. the circle
/// below `L̄ = 1`) or does not cover `lbar`, the branch of lowest interpolated energy.
/// Exactly at a collapse length the lowest state is the great circle, which is not a traced
/// state: the result is empty.
pub(crate) fn lowest_etas(
    branches: &[TracedBranch],
    critical: &[CriticalLength],
    lbar: f64,
) -> Vec<u32> {
    let tol = 1e-12 * lbar.abs().max(1.0);
    let mut out = Vec::new();
    // Exactly at a collapse the great circle itself is the lowest state: no traced branch.
    if critical
        .iter()
        .any(|c| c.kind == CriticalKind::Collapse && (c.lbar_cr - lbar).abs() <= tol)
    {
        return out;
    }
    if !critical.is_empty() {
        let k = critical.partition_point(|c| c.lbar_cr <= lbar + tol);
        let eta = if k == 0 {
            critical[0].from_eta
        } else {
            critical[k - 1].to_eta
        };
        if k > 0 && (critical[k - 1].lbar_cr - lbar).abs() <= tol {
            out.push(critical[k - 1].from_eta);
        }
        // Before a collapse from "branch 0" (the circle below L̄ = 1) the lowest state is
        // not a traced one.
        if eta == 0 && k == 0 && critical[0].kind == CriticalKind::Collapse && lbar < 1.0 {
            return Vec::new();
        }
        out.push(eta);
    }
    out.retain(|&eta| eta != 0 && branches.iter().any(|b| b.eta == eta && b.covers(lbar)));
    if out.is_empty() {
        if let Some((i, _)) = lowest_interpolated(branches, lbar) {
            out.push(branches[i].eta);
        }
    }
    out
}

/// Labels of every traced state of every branch.
pub(crate) fn label_all(branches: &[TracedBranch], critical: &[CriticalLength]) -> Vec<Vec<Label>> {
    branches
        .iter()
        .map(|b| {
            b.points
                .iter()
                .map(|p| {
                    if p.index > 0 {
                        Label::Unstable
                    } else if lowest_etas(branches, critical, p.value).contains(&b.eta) {
                        Label::Stable
                    } else {
                        Label::Metastable
                    }
                })
                .collect()
        })
        .collect()
}
