//! The assembled diagram: critical lengths, labels, great circles.
//!
//! | file | holds |
//! |---|---|
//! | `mod.rs` | the result types ([`NumericDiagram`], its rows and summary) and their queries |
//! | `assemble.rs` | [`assemble`]: everything after tracing, in named steps |
//! | `points.rs` | the special points ([`SpecialPoint`]) read from the traced branches |

mod assemble;
mod points;

pub use assemble::assemble;
pub use points::{SpecialKind, SpecialPoint};

use rodloop_solver::Accuracy;
use serde::Serialize;

use crate::buckling::BucklingReport;
use crate::critical::CriticalLength;
use crate::labels::{self, Label};
use crate::shapes::StateShape;
use crate::types::TracedBranch;
use crate::DiagramOptions;
use rodloop_exact::shape::ShapeTolerances;

/// Wall times of the phases, in seconds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Timings {
    /// Tracing all branches (wall time; 0 when [`assemble`] is called directly).
    pub tracing: f64,
    /// Locating the crossings and the folds and branch points (sum over the tasks, which
    /// run in parallel with the great circles).
    pub critical: f64,
    /// Great circles: buckling loads and branch switching (sum over the circles).
    pub great_circles: f64,
    /// Wall time of the parallel phase (crossings and great circles).
    pub parallel_wall: f64,
    /// Labels.
    pub labels: f64,
    /// Shape descriptors of the states (point group, self-intersections).
    pub shapes: f64,
    /// Everything ([`crate::compute`]) or the assembly alone ([`assemble`]).
    pub total: f64,
}

/// The numeric branch diagram.
#[derive(Clone, Debug, Serialize)]
pub struct NumericDiagram {
    /// Accuracy level.
    pub accuracy: Accuracy,
    /// Scene and resolution summary (human-readable).
    pub scene: String,
    /// Diagram range `(lbar_min, lbar_max)`.
    pub range: (f64, f64),
    /// Traced branches, by `η`.
    pub branches: Vec<TracedBranch>,
    /// Labels of the traced states, `labels[i][k]` for `branches[i].points[k]`.
    pub labels: Vec<Vec<Label>>,
    /// Point group and self-intersections of the traced states, `shapes[i][k]` for
    /// `branches[i].points[k]`.
    pub shapes: Vec<Vec<StateShape>>,
    /// Tolerances of [`NumericDiagram::shapes`].
    pub shape_tolerance: ShapeTolerances,
    /// Critical lengths in increasing order.
    pub critical: Vec<CriticalLength>,
    /// Folds, branch points, crossings and collapses, in increasing `L̄`.
    pub special: Vec<SpecialPoint>,
    /// Great-circle analysis (`None` if disabled).
    pub great_circles: Option<BucklingReport>,
    /// Anything suspicious met on the way.
    pub warnings: Vec<String>,
    /// Wall times.
    pub timings: Timings,
    /// Completeness certificate (two-segment surface diagrams; `None` where not run).
    pub certificate: Option<crate::certificate::Certificate>,
    /// Every traced state as its file holds it, verified against its row:
    /// `state_files[i][k]` for `branches[i].points[k]` (`None`: the state failed the
    /// verification and has no file; a warning says why).
    #[serde(skip)]
    pub state_files: Vec<Vec<Option<crate::StateFile>>>,
    /// How many traced states failed the verification.
    pub unverified_states: usize,
}

/// One row of the branch table (`branches.csv`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DiagramRow {
    /// Paper branch number.
    pub branch: u32,
    /// Periods of `κ_g`.
    pub eta: u32,
    /// Family within the branch ([`TracedBranch::family`]).
    pub family: u32,
    /// Position along the family: sheet number times 10⁶ plus the point's rank in the
    /// family's arclength order, so that sorting a family's rows by it draws the family
    /// as one path through its folds.
    pub arc: u64,
    /// Mirror multiplicity ([`TracedBranch::multiplicity`]).
    pub multiplicity: u32,
    /// Normalised length.
    pub lbar: f64,
    /// `E R/(π D0)`.
    pub energy: f64,
    /// `E_g R/(π D0)`.
    pub energy_g: f64,
    /// Estimated error of `energy` (`None` if unknown).
    pub energy_error: Option<f64>,
    /// Stability label.
    pub stability: Label,
    /// Stability index.
    pub index: usize,
    /// Minimum of `λR³/D0`.
    pub lambda_min: f64,
    /// Maximum of `λR³/D0`.
    pub lambda_max: f64,
    /// Point group and self-intersections ([`NumericDiagram::shapes`]).
    pub shape: StateShape,
}

/// A compact summary of a diagram (no states): what `summary.json` needs.
#[derive(Clone, Debug, Serialize)]
pub struct DiagramSummary<'a> {
    /// Accuracy level.
    pub accuracy: Accuracy,
    /// Scene and resolution summary.
    pub scene: &'a str,
    /// Diagram range.
    pub range: (f64, f64),
    /// One entry per branch.
    pub branches: Vec<BranchSummary<'a>>,
    /// Critical lengths.
    pub critical: &'a [CriticalLength],
    /// Special points.
    pub special: &'a [SpecialPoint],
    /// Great-circle analysis.
    pub great_circles: Option<&'a BucklingReport>,
    /// Warnings.
    pub warnings: &'a [String],
    /// Wall times.
    pub timings: Timings,
    /// Completeness certificate (`None` where not run).
    pub certificate: Option<&'a crate::certificate::Certificate>,
}

/// Summary of one traced branch.
#[derive(Clone, Debug, Serialize)]
pub struct BranchSummary<'a> {
    /// Paper branch number.
    pub branch: u32,
    /// Periods of `κ_g`.
    pub eta: u32,
    /// Number of traced states.
    pub points: usize,
    /// Traced span `(first, last)` of `L̄`.
    pub span: (f64, f64),
    /// Tracing resolution (cells).
    pub cells: usize,
    /// Reporting resolutions `(N_f, N_c)` of the critical lengths.
    pub reporting_cells: (usize, usize),
    /// How the lower end came about.
    pub low_end: &'a crate::BranchEnd,
    /// How the upper end came about.
    pub high_end: &'a crate::BranchEnd,
    /// Why the lower end stopped.
    pub stop_low: &'a str,
    /// Why the upper end stopped.
    pub stop_high: &'a str,
    /// Seed.
    pub seed: &'a str,
    /// Changes of the stability index.
    pub index_changes: &'a [crate::IndexChange],
    /// Continuation steps.
    pub steps: usize,
    /// Wall time of the tracing.
    pub seconds: f64,
}

impl NumericDiagram {
    /// A compact, serialisable summary (everything but the states).
    pub fn summary(&self, opts: &DiagramOptions) -> DiagramSummary<'_> {
        DiagramSummary {
            accuracy: self.accuracy,
            scene: &self.scene,
            range: self.range,
            branches: self
                .branches
                .iter()
                .map(|b| BranchSummary {
                    branch: b.branch,
                    eta: b.eta,
                    points: b.points.len(),
                    span: b.span(),
                    cells: b.cells,
                    reporting_cells: crate::refine::reporting_cells(opts, b.eta),
                    low_end: &b.low_end,
                    high_end: &b.high_end,
                    stop_low: &b.stop_low,
                    stop_high: &b.stop_high,
                    seed: &b.seed,
                    index_changes: &b.index_changes,
                    steps: b.steps,
                    seconds: b.seconds,
                })
                .collect(),
            critical: &self.critical,
            special: &self.special,
            great_circles: self.great_circles.as_ref(),
            warnings: &self.warnings,
            timings: self.timings,
            certificate: self.certificate.as_ref(),
        }
    }

    /// All traced states as flat rows, by branch then length.
    pub fn rows(&self) -> Vec<DiagramRow> {
        self.branches
            .iter()
            .zip(&self.labels)
            .zip(&self.shapes)
            .flat_map(|((b, ls), shapes)| {
                let n = b.points.len() as u64;
                b.points
                    .iter()
                    .zip(ls)
                    .zip(shapes)
                    .enumerate()
                    .map(move |(k, ((p, &l), shape))| DiagramRow {
                        branch: b.branch,
                        eta: b.eta,
                        family: b.family,
                        arc: u64::from(b.sheet) * 1_000_000
                            + if b.reversed {
                                n - 1 - k as u64
                            } else {
                                k as u64
                            },
                        multiplicity: b.multiplicity,
                        lbar: p.value,
                        energy: p.energy,
                        energy_g: p.energy_g,
                        energy_error: crate::states::sheet_estimate(&b.points, k),
                        stability: l,
                        index: p.index,
                        lambda_min: p.lambda_min,
                        lambda_max: p.lambda_max,
                        shape: shape.clone(),
                    })
            })
            .collect()
    }

    /// The branch with `eta`, if traced.
    pub fn branch_by_eta(&self, eta: u32) -> Option<&TracedBranch> {
        self.branches.iter().find(|b| b.eta == eta)
    }

    /// Label of the state of branch `eta` nearest to `lbar` (with its length).
    pub fn label_near(&self, eta: u32, lbar: f64) -> Option<(f64, Label)> {
        let i = self.branches.iter().position(|b| b.eta == eta)?;
        let b = &self.branches[i];
        let k = (0..b.points.len()).min_by(|&x, &y| {
            (b.points[x].value - lbar)
                .abs()
                .total_cmp(&(b.points[y].value - lbar).abs())
        })?;
        Some((b.points[k].value, self.labels[i][k]))
    }

    /// Positions in [`NumericDiagram::branches`] of the sheets lowest at `lbar` (two exactly
    /// at a critical length, none at a collapse).
    pub fn lowest_sheets_at(&self, lbar: f64) -> Vec<usize> {
        labels::lowest_sheets(&self.branches, &self.critical, lbar)
    }

    /// Paper branch numbers lowest at `lbar` (two exactly at a critical length).
    pub fn lowest_at(&self, lbar: f64) -> Vec<u32> {
        labels::lowest_etas(&self.branches, &self.critical, lbar)
            .into_iter()
            .map(rodloop_exact::branch_of_eta)
            .collect()
    }
}
