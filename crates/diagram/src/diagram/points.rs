//! The special points of the `L̄` diagram ([`SpecialPoint`], `special_points.csv`): folds
//! and branch points read from the ends of the traced sheets, crossings and collapses from
//! the critical lengths.

use serde::Serialize;

use crate::critical::{CriticalKind, CriticalLength};
use crate::types::TracedBranch;

/// Folds and branch points (the ends of sheets), one record per point, with the sheet and
/// end (`true`: low) each was first seen at. Their lengths and energies are the traced ones
/// until [`crate::special::locate_end_at`] and [`crate::special::extrapolate_end`] refine them.
pub(super) fn end_points(branches: &[TracedBranch]) -> (Vec<SpecialPoint>, Vec<(usize, bool)>) {
    let mut out: Vec<SpecialPoint> = Vec::new();
    let mut sources = Vec::new();
    for (bi, b) in branches.iter().enumerate() {
        for (end, at_low) in [(&b.low_end, true), (&b.high_end, false)] {
            let kind = match end {
                crate::BranchEnd::Fold { .. } => SpecialKind::Fold,
                crate::BranchEnd::BranchPoint { .. } => SpecialKind::BranchPoint,
                _ => continue,
            };
            let (p, q) = if at_low {
                (b.points.first(), b.points.get(1))
            } else {
                (
                    b.points.last(),
                    b.points.len().checked_sub(2).and_then(|k| b.points.get(k)),
                )
            };
            let (Some(p), Some(q)) = (p, q) else { continue };
            let value = p.value;
            // One record per point: a fold is the end of two sheets, a branch point of
            // several (located from each within the tracing's width, up to ~1e-5 apart at
            // D1/D0 = 0.5; a pitchfork is a turning point of the asymmetric sheets that end
            // there).
            if let Some(s) = out.iter_mut().find(|s| {
                (s.lbar - value).abs() < 1e-4
                    && (s.energy - p.energy).abs() < 1e-4 * p.energy.abs().max(1.0)
            }) {
                s.index_after = s.index_after.max(q.index);
                s.index_before = s.index_before.min(q.index);
                if kind == SpecialKind::BranchPoint {
                    s.kind = kind;
                }
                continue;
            }
            out.push(SpecialPoint {
                kind,
                lbar: value,
                energy: p.energy,
                error_estimate: None,
                branch: b.branch,
                family: b.family,
                index_before: q.index,
                index_after: q.index,
            });
            sources.push((bi, at_low));
        }
    }
    (out, sources)
}

/// Special points of the diagram: folds and branch points (`ends`, see [`end_points`]),
/// crossings and collapses (the critical lengths), in increasing `L̄`.
pub(super) fn special_points(
    ends: Vec<SpecialPoint>,
    branches: &[TracedBranch],
    critical: &[CriticalLength],
) -> Vec<SpecialPoint> {
    let mut out = ends;
    // Before/after: the two sides of a fold are its two sheets, the lower index first.
    for c in critical {
        out.push(SpecialPoint {
            kind: match c.kind {
                CriticalKind::Crossing => SpecialKind::Crossing,
                CriticalKind::Collapse => SpecialKind::Collapse,
            },
            lbar: c.lbar_cr,
            energy: c.energy,
            error_estimate: Some(c.error_estimate),
            branch: c.to_branch,
            family: c.to_sheet.map_or(0, |i| branches[i].family),
            index_before: 0,
            index_after: 0,
        });
    }
    out.sort_by(|a, b| a.lbar.total_cmp(&b.lbar));
    out
}

/// Kind of a [`SpecialPoint`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SpecialKind {
    /// A turning point in `L̄` of a followed family (two sheets meet).
    Fold,
    /// A simple branch point: a mirror-symmetric family meets a pair of mirror-image
    /// asymmetric ones (pitchfork).
    BranchPoint,
    /// An exchange of the lowest state between two sheets (`E_a = E_b`).
    Crossing,
    /// The lowest state collapses onto a great circle (`L̄ = m`).
    Collapse,
}

impl SpecialKind {
    /// `fold`, `branch_point`, `crossing` or `collapse`.
    pub fn as_str(self) -> &'static str {
        match self {
            SpecialKind::Fold => "fold",
            SpecialKind::BranchPoint => "branch_point",
            SpecialKind::Crossing => "crossing",
            SpecialKind::Collapse => "collapse",
        }
    }
}

/// A special point of the diagram (`special_points.csv`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SpecialPoint {
    /// What it is.
    pub kind: SpecialKind,
    /// Where.
    pub lbar: f64,
    /// Energy `E R/(π D0)` there.
    pub energy: f64,
    /// Error estimate of `lbar`: folds and branch points located at the reporting
    /// resolutions (`crate::special`), crossings and collapses as in `critical.csv`; `None`
    /// where a fold or branch point is known only to the tracing's width (its re-location
    /// failed).
    pub error_estimate: Option<f64>,
    /// Paper branch (crossings and collapses: the branch lowest above).
    pub branch: u32,
    /// Family within the branch (0: uniform rod, or none).
    pub family: u32,
    /// Stability index on one side (folds and branch points: the smaller of the indices of
    /// the sheets that meet there; crossings and collapses: of the lowest state, 0).
    pub index_before: usize,
    /// Stability index on the other side (the larger).
    pub index_after: usize,
}
