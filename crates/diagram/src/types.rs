//! The serialisable results of tracing: [`TracedBranch`] with its [`TracedPoint`]s, how its
//! ends came about ([`BranchEnd`]), its index changes and timings, and the queries the
//! assembly makes of a traced branch (energy interpolation, re-solving at a length).
//!
//! # Parameter and file format
//!
//! A branch is traced in one continued parameter, [`TracedBranch::param`] (`lbar` for the
//! branch diagram, the default when a file does not say). The Rust fields that hold its
//! value are called `value`; in the files they keep the name `lbar` of the first file
//! format, so that branch files of that format still resume (and the user-visible
//! `summary.json` keeps its keys).

use rodloop_solver::Param;
use serde::{Deserialize, Serialize};

/// How one end of a traced branch came about.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum BranchEnd {
    /// The branch ends on the `m`-fold great circle at `L̄ = m`; tracing stopped at `value`
    /// (a length `L̄`), `distance = |value − m|` from it.
    GreatCircle {
        /// Turns of the great circle.
        m: u32,
        /// Last traced length (`lbar` in files).
        #[serde(rename = "lbar")]
        value: f64,
        /// `|value − m|`.
        distance: f64,
    },
    /// Tracing stopped at the end of the diagram's range.
    Range {
        /// The end of the range of the continued parameter (`lbar` in files).
        #[serde(rename = "lbar")]
        value: f64,
    },
    /// A fold (turning point in `L̄`) of a followed branch: the family goes on, on the
    /// next sheet ([`TracedBranch::sheet`]).
    Fold {
        /// Where the parameter turns (`lbar` in files).
        #[serde(rename = "lbar")]
        value: f64,
    },
    /// A simple branch point (pitchfork) where this sheet starts or ends on another
    /// family.
    BranchPoint {
        /// Where (`lbar` in files).
        #[serde(rename = "lbar")]
        value: f64,
    },
    /// Tracing stopped before its target.
    Failed {
        /// Last traced value of the continued parameter (`lbar` in files).
        #[serde(rename = "lbar")]
        value: f64,
        /// Where it should have stopped.
        target: f64,
        /// Why it stopped.
        reason: String,
    },
}

impl BranchEnd {
    /// Last traced value of the continued parameter at this end.
    pub fn value(&self) -> f64 {
        match self {
            BranchEnd::GreatCircle { value, .. }
            | BranchEnd::Range { value }
            | BranchEnd::Fold { value }
            | BranchEnd::BranchPoint { value }
            | BranchEnd::Failed { value, .. } => *value,
        }
    }

    /// The great circle `m` on which the branch ends here, if it does.
    pub fn great_circle(&self) -> Option<u32> {
        match self {
            BranchEnd::GreatCircle { m, .. } => Some(*m),
            _ => None,
        }
    }
}

/// How a traced state was obtained.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PointSource {
    /// The seed (Euler rotation curve, relaxed and solved).
    Seed,
    /// A pseudo-arclength continuation step.
    Continuation,
    /// A located change of the stability index.
    IndexChange,
    /// A Newton solve of the approach to a great-circle end.
    EndApproach,
    /// A located fold (turning point of the continued parameter) of a followed branch.
    Fold,
    /// A located simple branch point (e.g. the pitchfork where a mirror-symmetric family
    /// meets a pair of mirror-image asymmetric ones).
    BranchPoint,
}

/// One traced state.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TracedPoint {
    /// Value of the continued parameter ([`TracedBranch::param`]; the normalised length `L̄`
    /// in the branch diagram). Named `lbar` in branch files.
    #[serde(rename = "lbar")]
    pub value: f64,
    /// Energy `E R/(π D0)`: Richardson extrapolation of the tracing resolution `N` and `N/2`
    /// (the value at `N` if the `N/2` solve failed, or if `N/2` cells do not resolve the
    /// stiffness profile).
    pub energy: f64,
    /// Geodesic part `E_g R/(π D0)` (extrapolated like `energy`).
    pub energy_g: f64,
    /// Estimated error of `energy`: at least `|E_N − E_{N/2}|/15` (the error estimate of
    /// `E_N`), and the bound of the three-level ladder `N/2, N, 2N` with its observed order
    /// (`crate::estimate`); `None` if the `N/2` solve failed.
    pub energy_error: Option<f64>,
    /// Energy at the tracing resolution itself.
    pub energy_trace: f64,
    /// `dE/dL̄` along the branch (normalised like `energy`), from the multiplier:
    /// `dE/dL̄ = ∂ℒ/∂L̄ = E/L̄ + μ·∂(−c)/∂L̄` (tracing resolution).
    pub slope: f64,
    /// Stability index (number of negative eigenvalues of the constrained Hessian).
    pub index: usize,
    /// Minimum of the contact force `λR³/D0` over the loop (extrapolated like `energy`).
    pub lambda_min: f64,
    /// Maximum of the contact force `λR³/D0` over the loop.
    pub lambda_max: f64,
    /// `max |κ_g R|` (tracing resolution).
    pub amplitude: f64,
    /// How the state was obtained.
    pub source: PointSource,
    /// KKT state `(κ, μ, ν)` at the tracing resolution ([`TracedBranch::cells`] cells).
    pub state: Vec<f64>,
    /// Newton's run at twice the tracing resolution from this state (the third rung of
    /// [`TracedPoint::energy_error`]), kept for the verification of its state file; not in
    /// files, and no part of comparisons.
    #[serde(skip)]
    pub(crate) finer: FinerRun,
}

/// The Newton run of a traced state at twice its resolution ([`TracedPoint`]'s third rung),
/// kept where a run to the tolerance of a state file's refinement would stop or go on
/// ([`rodloop_solver::solve_newton_keeping`]), with the start it ran from: the verification
/// of the state's file, which re-solves the state at that resolution from the same start
/// when its own resolution does not reproduce the row, goes on from here instead of
/// repeating the run. Equal to every other (a cache, not a value of the state).
#[derive(Clone, Debug, Default)]
pub(crate) struct FinerRun(Option<std::sync::Arc<(Vec<f64>, rodloop_solver::NewtonRun)>>);

impl FinerRun {
    /// The run of `start` (curvature at the Gauss points), if there is one.
    pub(crate) fn new(start: Vec<f64>, run: Option<rodloop_solver::NewtonRun>) -> Self {
        Self(run.map(|r| std::sync::Arc::new((start, r))))
    }

    /// The result of [`rodloop_solver::solve`] of `model` from `start` with Newton's
    /// `opts`, continued from the kept run, and the run where it stops: `None` unless the run
    /// is of this model and start and can go on with `opts`
    /// ([`rodloop_solver::NewtonRun::resume_keeping`]).
    pub(crate) fn resume_keeping(
        &self,
        model: &crate::options::Model,
        start: &[f64],
        opts: &rodloop_solver::SolveOptions,
    ) -> Option<(
        Result<rodloop_solver::Equilibrium, rodloop_solver::SolverError>,
        Option<rodloop_solver::NewtonRun>,
    )> {
        let (s, run) = self.0.as_deref()?;
        if s.as_slice() != start || run.model() != model {
            return None;
        }
        run.clone().resume_keeping(opts)
    }
}

impl PartialEq for FinerRun {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

/// A located change of the stability index along a branch.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct IndexChange {
    /// Where it happens (value of the continued parameter; `lbar` in files).
    #[serde(rename = "lbar")]
    pub value: f64,
    /// Index below `value`.
    pub below: usize,
    /// Index above `value`.
    pub above: usize,
}

/// A traced branch (serialisable: the CLI writes one file per finished branch and passes
/// them back to [`crate::compute`] to resume).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TracedBranch {
    /// Paper branch number ([`rodloop_exact::branch_of_eta`]).
    pub branch: u32,
    /// Periods of `κ_g`.
    pub eta: u32,
    /// The continued parameter of [`TracedPoint::value`] (`lbar` when a file does not say:
    /// files of version 1).
    #[serde(default = "default_param")]
    pub param: Param,
    /// Family of the branch (numbered from 1 within `η`; 0: the single family of a uniform
    /// rod). A non-uniform rod splits branch `η` into families by where the soft segment
    /// sits on the shape; a family is one continuous solution curve, followed through its
    /// folds and cut into sheets monotone in `L̄`.
    #[serde(default)]
    pub family: u32,
    /// Position of this sheet along its family (0, 1, … in the order of the curve's
    /// arclength).
    #[serde(default)]
    pub sheet: u32,
    /// Whether the curve's arclength runs against increasing `L̄` on this sheet (so that
    /// a figure draws the family as one path: sheets in order, points reversed where this
    /// is set).
    #[serde(default)]
    pub reversed: bool,
    /// Number of distinct loops the sheet stands for: 2 for a mirror-asymmetric state (its
    /// mirror image about the stiffness profile's axis is an equilibrium with the same
    /// energy, reported once), 1 otherwise.
    #[serde(default = "one")]
    pub multiplicity: u32,
    /// [`DiagramOptions::fingerprint`](crate::DiagramOptions::fingerprint) of the options it was traced with.
    pub fingerprint: String,
    /// Tracing resolution (cells).
    pub cells: usize,
    /// Whether the states carry a phase multiplier (uniform stiffness).
    pub phase: bool,
    /// Traced states in increasing `L̄`.
    pub points: Vec<TracedPoint>,
    /// How the lower end came about.
    pub low_end: BranchEnd,
    /// How the upper end came about.
    pub high_end: BranchEnd,
    /// Where and why the lower end stopped (human-readable).
    pub stop_low: String,
    /// Where and why the upper end stopped (human-readable).
    pub stop_high: String,
    /// How the branch was seeded.
    pub seed: String,
    /// Located changes of the stability index.
    pub index_changes: Vec<IndexChange>,
    /// Continuation steps taken (both directions).
    pub steps: usize,
    /// Wall time of the tracing in seconds.
    pub seconds: f64,
    /// Where that time went.
    pub timings: BranchTimings,
}

/// Wall times of the phases of [`crate::compute_branch`], in seconds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BranchTimings {
    /// Seed: Euler curve, relaxation, Newton.
    pub seed: f64,
    /// Pseudo-arclength runs, including the stability index at every point.
    pub continuation: f64,
    /// Newton solves approaching the great-circle ends (with their stability indices).
    pub end_approach: f64,
    /// Quantities of the traced states (re-solve, half-resolution partner, forces).
    pub states: f64,
}

impl TracedBranch {
    /// Range `(first, last)` of the traced values of [`TracedBranch::param`].
    pub fn span(&self) -> (f64, f64) {
        (
            self.points.first().map_or(f64::NAN, |p| p.value),
            self.points.last().map_or(f64::NAN, |p| p.value),
        )
    }

    /// Whether `value` lies within the traced values.
    pub fn covers(&self, value: f64) -> bool {
        let (a, b) = self.span();
        value >= a && value <= b
    }

    /// Energy at `value` by cubic Hermite interpolation of the traced energies and slopes
    /// (`None` outside the traced span).
    pub fn energy_at(&self, value: f64) -> Option<f64> {
        if !self.covers(value) {
            return None;
        }
        let lbar = value;
        let k = self
            .points
            .partition_point(|p| p.value <= lbar)
            .clamp(1, self.points.len().max(2) - 1);
        if self.points.len() == 1 {
            return Some(self.points[0].energy);
        }
        let (p0, p1) = (&self.points[k - 1], &self.points[k]);
        let h = p1.value - p0.value;
        if h <= 0.0 {
            return Some(p0.energy);
        }
        let t = (lbar - p0.value) / h;
        let (h00, h10, h01, h11) = (
            (1.0 + 2.0 * t) * (1.0 - t) * (1.0 - t),
            t * (1.0 - t) * (1.0 - t),
            t * t * (3.0 - 2.0 * t),
            t * t * (t - 1.0),
        );
        Some(h00 * p0.energy + h10 * h * p0.slope + h01 * p1.energy + h11 * h * p1.slope)
    }

    /// Linear interpolation of the traced states at `value` (nearest end outside the span;
    /// empty for a branch without states).
    pub(crate) fn state_near(&self, value: f64) -> Vec<f64> {
        let lbar = value;
        let pts = &self.points;
        let k = pts.partition_point(|p| p.value <= lbar);
        if pts.is_empty() {
            return Vec::new();
        }
        if k == 0 {
            return pts[0].state.clone();
        }
        if k >= pts.len() {
            return pts[pts.len() - 1].state.clone();
        }
        let (a, b) = (&pts[k - 1], &pts[k]);
        let t = if b.value > a.value {
            (lbar - a.value) / (b.value - a.value)
        } else {
            0.0
        };
        a.state
            .iter()
            .zip(&b.state)
            .map(|(x, y)| x + t * (y - x))
            .collect()
    }
}

/// Multiplicity of branch files that do not say.
fn one() -> u32 {
    1
}

/// The parameter of branch files that do not name one.
fn default_param() -> Param {
    Param::Lbar
}
