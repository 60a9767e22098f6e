//! The numeric branch diagram of elastic rod loops on a sphere (paper: Wang, Li & Yi, JMPS
//! 2024, Secs. 3.1, 4.2, 4.3, Figs. 2, 3, 7): every configuration branch followed in the
//! normalised length `L̄ = L/(2πR)`, the critical lengths where branches exchange global
//! stability, a stability label for every computed state, and the buckling of the m-fold
//! great circles with branch switching from them.
//!
//! As the crate root it holds the pipeline's description, the module table, the one error type
//! and the options every stage reads (`DiagramOptions`, `TraceControls` and their validation);
//! the stages are in the modules.
//!
//! # Pipeline
//!
//! 1. **Tracing** ([`compute_branch`], [`trace`]): branch `η` (number of periods of the
//!    geodesic curvature; paper branch [`rodloop_exact::branch_of_eta`]) is seeded from the
//!    Euler rotation curve with `l = η` near the middle of its range
//!    `(η − 1, η + 1) ∩ [L̄_min, L̄_max]`, relaxed and solved at a *coarse tracing resolution*,
//!    and followed by pseudo-arclength continuation in `L̄` in both directions
//!    ([`rodloop_solver::LbarProblem`], the phase condition held fixed in `s/L`), with the
//!    stability index monitored at every point. Where the branch ends on an `(η ± 1)`-fold
//!    great circle (the loop collapses, the constraint Jacobian loses rank and the KKT matrix
//!    becomes singular) the state behaves like `√|L̄ − m|`; the last stretch is therefore
//!    followed by Newton's method at prescribed lengths `L̄ = m ± a²` with `a` halved at every
//!    step and a predictor polynomial in `a`, down to [`DiagramOptions::end_distance`]
//!    (default `5·10⁻⁵`) from the great circle. Every traced state carries its energy
//!    (Richardson-extrapolated with a solve at half the tracing resolution, with an error
//!    estimate from the three-level ladder `N/2, N, 2N` and its observed order,
//!    `estimate.rs`), `dE/dL̄`, contact-force extremes and stability index.
//! 2. **Critical lengths** ([`critical`]): where the lowest branch changes between traced
//!    samples, `E_a(L̄) = E_b(L̄)` is solved by Newton's method in `L̄` (analytic slopes
//!    `dE/dL̄`, bracket safeguard), every evaluation *re-solving* both equilibria at the
//!    reporting resolution of the accuracy level and at half (or, for `High`, double) that
//!    resolution, Richardson-extrapolated. Collapses are the integer lengths `L̄ = m` where
//!    the lowest branch ends on the m-fold great circle (checked: the branch energy
//!    extrapolates to `E R/(πD) = m`).
//! 3. **Labels** ([`Label`]): stable / metastable / unstable for every traced state.
//! 4. **Great circles** ([`buckling`]): the loads at which the constrained Hessian of the
//!    m-fold great circle becomes singular (Eqs. 33–34), and branch switching from the null
//!    vectors onto the traced branches (merged when they coincide).
//!
//! [`compute`] runs it all, calling a [`BranchHook`] as each branch is ready (to save it) and
//! asking it for branches traced before (to resume an interrupted run); [`compute_branch`]
//! and [`assemble`] are the two halves for callers that schedule branches themselves.
//!
//! # Files
//!
//! | file | holds |
//! |---|---|
//! | `types.rs` | the serialisable [`TracedBranch`], [`TracedPoint`], [`BranchEnd`], [`IndexChange`] |
//! | `seed.rs` | seeding a branch from the Euler rotation curve |
//! | `march.rs` | [`march()`]: the stepping loop (one `Stepper`, any model and parameter) |
//! | `ends.rs` | the approach to the great-circle ends |
//! | `states.rs` | quantities of a traced state (Richardson partner, slope, index) |
//! | `reported.rs` | a state of `phase`, `--param` or `converge` verified as its file holds it |
//! | `estimate.rs` | the error estimate of a traced energy (three-level ladder) |
//! | `trace.rs` | [`compute_branch`]: seed, march both ways, ends, states |
//! | `compute.rs` | [`compute`] with its [`BranchHook`] (resume, save) |
//! | `parallel.rs` | the thread pool |
//! | `engine.rs` | the [`Engine`] interface of every diagram model and its result in the schema |
//! | `refine.rs`, `critical.rs`, `labels.rs`, `buckling.rs`, `diagram.rs` | the assembly |
//! | `enclosed_state.rs` | one enclosed state solved with its certificate (energy, estimate, index, method) |
//! | `detached.rs` | where the enclosed loops of a homogeneous rod leave the wall, scanned |
//!
//! Energies are `E R/(π D0)`, forces `λR³/D0` (with `R`, `D0` of the scene), as in the paper.

#![warn(missing_docs)]

pub mod buckling;
pub mod certificate;
pub mod compare;
mod compute;
pub mod critical;
pub mod detached;
mod diagram;
pub mod enclosed;
pub mod enclosed_state;
mod ends;
pub mod engine;
mod estimate;
pub mod families;
mod labels;
pub mod march;
pub mod maxwell;
mod parallel;
pub mod param_sweep;
pub mod phase;
mod placements;
pub mod refine;
pub mod reported;
pub mod representative;
pub mod sampling;
mod seed;
pub mod shapes;
mod special;
pub mod state_rows;
mod states;
pub mod trace;
pub mod types;

pub use buckling::{Buckling, BucklingReport, Switching};
pub use compute::{compute, BranchHook, Origin, Resume};
pub use engine::{EnclosedEngine, Engine, ExactEngine, ExactOutput, SurfaceEngine};
// (TraceControls is defined in this file.)
pub use critical::{CriticalKind, CriticalLength};
pub use diagram::{
    assemble, BranchSummary, DiagramRow, DiagramSummary, NumericDiagram, SpecialKind, SpecialPoint,
    Timings,
};
pub use labels::Label;
pub use march::{
    march, march_switch, march_switch_until, march_until, FoldPolicy, March, MarchPoint,
    MarchSettings, MarchSpecial, MarchStop,
};
/// The error type a [`BranchHook`] returns.
pub use rodloop_continuation::BoxError;
pub use states::{
    branch_identification, BranchIdentification, StateFile, ESTIMATES, MAX_REFINEMENT,
    MAX_STATE_POINTS, NO_ESTIMATE_TOLERANCE, STATE_POINTS,
};
pub use trace::compute_branch;
pub use types::{BranchEnd, BranchTimings, IndexChange, PointSource, TracedBranch, TracedPoint};

use rodloop_solver::{Accuracy, Param, SolverError, Stiffness};

/// Errors of the diagram engine.
#[derive(Debug, thiserror::Error)]
pub enum DiagramError {
    /// Options that cannot describe a diagram (non-positive radius, empty range, …).
    #[error("invalid diagram options: {0}")]
    InvalidOptions(String),
    /// A branch whose existence range `(η − 1, η + 1)` misses `[lbar_min, lbar_max]`.
    #[error(
        "branch eta = {eta} exists for {lo} < L̄ < {hi}, which misses the range \
         [{lbar_min}, {lbar_max}]"
    )]
    BranchOutOfRange {
        /// Periods of `κ_g`.
        eta: u32,
        /// Lower end of the branch.
        lo: f64,
        /// Upper end of the branch.
        hi: f64,
        /// Lower end of the diagram range.
        lbar_min: f64,
        /// Upper end of the diagram range.
        lbar_max: f64,
    },
    /// The seed of a branch could not be solved.
    #[error("seeding branch eta = {eta} at L̄ = {lbar} failed: {source}")]
    Seed {
        /// Periods of `κ_g`.
        eta: u32,
        /// Length of the seed.
        lbar: f64,
        /// The solver's error.
        #[source]
        source: SolverError,
    },
    /// The continuation could not even start from the seed.
    #[error("continuation of branch eta = {eta} failed: {reason}")]
    Continuation {
        /// Periods of `κ_g`.
        eta: u32,
        /// What went wrong.
        reason: String,
    },
    /// A critical length could not be located.
    #[error("critical length of branches {from_branch} → {to_branch} near L̄ = {lbar}: {reason}")]
    Critical {
        /// Lowest branch below.
        from_branch: u32,
        /// Lowest branch above.
        to_branch: u32,
        /// Approximate location.
        lbar: f64,
        /// What went wrong.
        reason: String,
    },
    /// A traced branch passed to [`assemble`] is unusable (no points, wrong state length, …).
    #[error("traced branch eta = {eta} is unusable: {reason}")]
    InvalidBranch {
        /// Periods of `κ_g`.
        eta: u32,
        /// What is wrong with it.
        reason: String,
    },
    /// The per-branch hook of [`compute`] failed (e.g. a branch file could not be written).
    #[error("branch hook: {0}")]
    Hook(#[source] rodloop_continuation::BoxError),
    /// A state that could not be solved on its branch (every start tried, each reason given).
    #[error("{0}")]
    Unsolved(String),
    /// A result that does not fit the result schema (a non-finite number, a value without a
    /// column).
    #[error("result schema: {0}")]
    Schema(#[from] rodloop_schema::SchemaError),
    /// An error of the solver outside the cases above.
    #[error("solver: {0}")]
    Solver(#[from] SolverError),
    /// A state asked for outside the range of lengths where its branch exists.
    #[error("{0}")]
    OutOfRange(String),
    /// An error of a lower layer with what was being computed when it happened.
    #[error("{what}")]
    Context {
        /// What was being computed.
        what: String,
        /// The lower layer's error.
        #[source]
        source: BoxError,
    },
    /// An error of a lower layer passed on as it is.
    #[error(transparent)]
    Passed(BoxError),
}

/// What to compute: the scene, the range of lengths and the accuracy level.
///
/// [`DiagramOptions::default`] is the default scene of the CLI: homogeneous rod (`D = 1`) on
/// the unit sphere, `1 ≤ L̄ ≤ 5`, [`Accuracy::Default`].
#[derive(Clone, Debug, PartialEq)]
pub struct DiagramOptions {
    /// Sphere radius `R`.
    pub radius: f64,
    /// Bending stiffness profile.
    pub stiffness: Stiffness,
    /// Smallest length of the diagram.
    pub lbar_min: f64,
    /// Largest length of the diagram.
    pub lbar_max: f64,
    /// Accuracy level: tracing resolution, reporting resolution of the critical lengths.
    pub accuracy: Accuracy,
    /// Largest `η` traced. `None`: every branch whose range `(η − 1, η + 1)` meets
    /// `[lbar_min, lbar_max]`.
    pub eta_max: Option<u32>,
    /// Cells per period of `κ_g` (times `η + 1`) of the tracing resolution; `None`: from the
    /// accuracy level (8, 12, 16 for fast, default, high).
    pub trace_cells_per_period: Option<usize>,
    /// Distance from the great circle at which a branch end stops (must be in `(0, 1e-2)`).
    pub end_distance: f64,
    /// Whether [`assemble`] analyses the great circles (buckling loads and branch switching).
    pub great_circles: bool,
    /// Worker threads for tracing and refinement (0: the available parallelism).
    pub threads: usize,
    /// The continued parameter of the branches. Only [`Param::Lbar`] makes a branch diagram
    /// (critical lengths, great circles); [`DiagramOptions::validate`] rejects the others.
    /// Continuing a branch in another parameter (e.g. `d1` at fixed `L̄`) is done with
    /// [`march()`] on a [`rodloop_solver::ParamProblem`].
    pub param: Param,
    /// Only these paper branch numbers ([`rodloop_exact::branch_of_eta`]); `None`: all of
    /// [`DiagramOptions::etas`]. Not part of the fingerprint.
    pub only_branches: Option<Vec<u32>>,
    /// Continuation controls of the tracing (`None` fields: the accuracy level's values).
    pub controls: TraceControls,
}

/// Continuation controls a user may set (`None`: the accuracy level's value). Steps are in
/// the tracer's scaled pseudo-arclength (unknowns scaled by `R/√n`, plus `L̄`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TraceControls {
    /// Largest step (default 0.6 / 0.25 / 0.2 for fast / default / high).
    pub max_step: Option<f64>,
    /// Smallest step before a branch end is declared (default 1e-6).
    pub min_step: Option<f64>,
    /// Most continuation points per direction of a branch (default 1000).
    pub max_points: Option<usize>,
    /// Newton tolerance of the corrector, max-norm of the scaled residual (default 1e-10).
    pub newton_tol: Option<f64>,
}

impl TraceControls {
    /// Whether every control is at its default.
    pub fn is_default(&self) -> bool {
        *self == Self::default()
    }

    fn validate(&self) -> Result<(), String> {
        if let Some(v) = self.max_step {
            if !(v.is_finite() && v > 0.0 && v <= 10.0) {
                return Err(format!("max_step must lie in (0, 10] (got {v})"));
            }
        }
        if let Some(v) = self.min_step {
            let hi = self.max_step.unwrap_or(0.2);
            if !(v.is_finite() && v > 0.0 && v < hi) {
                return Err(format!(
                    "min_step must be positive and below max_step = {hi} (got {v})"
                ));
            }
        }
        if let Some(v) = self.max_points {
            if !(10..=100_000).contains(&v) {
                return Err(format!("max_points must lie in [10, 100000] (got {v})"));
            }
        }
        if let Some(v) = self.newton_tol {
            if !(v.is_finite() && (1e-14..=1e-4).contains(&v)) {
                return Err(format!("newton_tol must lie in [1e-14, 1e-4] (got {v})"));
            }
        }
        Ok(())
    }
}

impl Default for DiagramOptions {
    fn default() -> Self {
        Self {
            radius: 1.0,
            stiffness: Stiffness::uniform(1.0),
            lbar_min: 1.0,
            lbar_max: 5.0,
            accuracy: Accuracy::Default,
            eta_max: None,
            trace_cells_per_period: None,
            end_distance: 5e-5,
            great_circles: true,
            threads: 0,
            param: Param::Lbar,
            only_branches: None,
            controls: TraceControls::default(),
        }
    }
}

/// A model at `lbar` with `cells` cells and, for uniform stiffness, the phase condition of
/// the reference `kappa` (Gauss values).
pub(crate) fn model_with_phase(
    opts: &DiagramOptions,
    lbar: f64,
    cells: usize,
    kappa: &[f64],
) -> Result<rodloop_solver::SurfaceModel, SolverError> {
    let model = opts.model(lbar, cells)?;
    if opts.stiffness.is_uniform() {
        model.with_phase(rodloop_solver::Phase::from_gauss_values(kappa, cells)?)
    } else {
        Ok(model)
    }
}

/// The scene's surface model (sphere radius, length `L̄`, cells, stiffness): the one
/// place the surface diagram chooses its confinement model. Everything downstream works
/// through the model seam ([`rodloop_solver::Confinement`], with the surface solvers of
/// [`rodloop_solver::SurfaceSolve`]).
pub(crate) fn surface_model(
    radius: f64,
    lbar: f64,
    cells: usize,
    stiffness: &Stiffness,
) -> Result<rodloop_solver::SurfaceModel, SolverError> {
    rodloop_solver::SurfaceModel::new(radius, lbar, cells, stiffness)
}

impl DiagramOptions {
    /// The scene's model at length `lbar` with `cells` cells ([`surface_model`]).
    pub fn model(
        &self,
        lbar: f64,
        cells: usize,
    ) -> Result<rodloop_solver::SurfaceModel, SolverError> {
        surface_model(self.radius, lbar, cells, &self.stiffness)
    }

    /// The default scene at another accuracy level.
    pub fn with_accuracy(accuracy: Accuracy) -> Self {
        Self {
            accuracy,
            ..Self::default()
        }
    }

    /// Check the options (finite positive radius, `0 < lbar_min < lbar_max`, a valid
    /// stiffness profile, a sensible end distance).
    pub fn validate(&self) -> Result<(), DiagramError> {
        let bad = |m: String| Err(DiagramError::InvalidOptions(m));
        if !(self.radius.is_finite() && self.radius > 0.0) {
            return bad(format!("radius must be positive (got {})", self.radius));
        }
        if !(self.lbar_min.is_finite() && self.lbar_max.is_finite()) {
            return bad("the length range must be finite".into());
        }
        if !(self.lbar_min > 0.0 && self.lbar_max > self.lbar_min) {
            return bad(format!(
                "need 0 < lbar_min < lbar_max (got {}, {})",
                self.lbar_min, self.lbar_max
            ));
        }
        if self.lbar_max > 1000.0 {
            return bad(format!("lbar_max = {} is beyond 1000", self.lbar_max));
        }
        if !(self.end_distance > 0.0 && self.end_distance < 1e-2) {
            return bad(format!(
                "end_distance must lie in (0, 0.01) (got {})",
                self.end_distance
            ));
        }
        if let Err(m) = self.controls.validate() {
            return bad(m);
        }
        if let Some(c) = self.trace_cells_per_period {
            if !(4..=400).contains(&c) {
                return bad(format!(
                    "trace_cells_per_period must lie in [4, 400] (got {c})"
                ));
            }
        }
        if self.param != Param::Lbar {
            return bad(format!(
                "a branch diagram is continued in lbar (got {}); use march() for other parameters",
                self.param
            ));
        }
        self.stiffness.validate()?;
        Ok(())
    }

    /// The branches `η` of the diagram, ascending (those of
    /// [`DiagramOptions::only_branches`] if given).
    pub fn etas(&self) -> Vec<u32> {
        let top = self.lbar_max.ceil() as u32 + 1;
        let max = self.eta_max.unwrap_or(top);
        (1..=max.min(top))
            .filter(|&eta| {
                let e = f64::from(eta);
                e - 1.0 < self.lbar_max && e + 1.0 > self.lbar_min
            })
            .filter(|&eta| {
                self.only_branches
                    .as_ref()
                    .is_none_or(|b| b.contains(&rodloop_exact::branch_of_eta(eta)))
            })
            .collect()
    }

    /// Cells per period of the tracing resolution.
    pub fn trace_cells_per_period(&self) -> usize {
        self.trace_cells_per_period
            .unwrap_or(self.accuracy.pick(rodloop_solver::accuracy::TRACE_CELLS))
    }

    /// Number of cells of the tracing resolution of branch `eta`:
    /// `c (η + 1)` with `c` = [`Self::trace_cells_per_period`], at least what the stiffness
    /// profile needs (`γ` cells for Eq. (51), one per table point; twice that for modest
    /// profiles (`≤ 64` cells) except at the fast level, so that the half-resolution partner
    /// of the energy extrapolation resolves the profile too; sharp profiles are traced
    /// without that partner, the reporting resolution resolves them), raised by the scene's
    /// bending factor ([`bending_factor`]: a very soft segment bends sharply; at
    /// `D1/D0 = 0.001` the transitions' 80 cells miss a family of branch 2 that 120 and 160
    /// cells both find, with the same refined exchanges), and 8, rounded up to a multiple
    /// of 4. The count grows continuously as `D1/D0` falls: no threshold on the contrast.
    pub fn trace_cells(&self, eta: u32) -> usize {
        let base = self.trace_cells_per_period() * (eta as usize + 1);
        let profile = profile_cells(&self.stiffness);
        let factor = if self.accuracy == Accuracy::Fast || profile > 64 {
            1
        } else {
            2
        };
        let resolved = bending_scaled(factor * profile, &self.stiffness);
        base.max(resolved).max(8).div_ceil(4) * 4
    }

    /// Worker threads actually used.
    pub fn worker_threads(&self) -> usize {
        if self.threads > 0 {
            self.threads
        } else {
            std::thread::available_parallelism()
                .map(|n| n.get())
                .unwrap_or(1)
        }
    }

    /// A string identifying everything that determines a traced branch (scene, range,
    /// accuracy, tracing resolution, end distance): [`compute`] reuses a resumed branch only
    /// if its fingerprint matches.
    pub fn fingerprint(&self) -> String {
        format!(
            "R={:e};D={:?};range=[{:e},{:e}];accuracy={:?};cpp={};end={:e};v=1",
            self.radius,
            self.stiffness,
            self.lbar_min,
            self.lbar_max,
            self.accuracy,
            self.trace_cells_per_period(),
            self.end_distance
        ) + &if self.controls.is_default() {
            String::new()
        } else {
            format!(";controls={:?}", self.controls)
        }
    }
}

/// How much finer than the transitions' width the cells must be to resolve the bending of a
/// soft segment (Eq. (51)), a number of the scene: the loop's contact forces are of order
/// `D0/R²`, under which a segment of stiffness `D1` bends over lengths of order
/// `ℓ = R √(D1/D0)` (its bending length); the cells at the transitions are as wide as the
/// transition, `L/γ` with `L = 2πR` for a loop of one great circle's length
/// ([`profile_cells`]), and must also be no wider than `2ℓ/3`. The factor
/// `max(1, (2πR/γ)/(2ℓ/3)) = max(1, 3π/(γ √(D1/D0)))` grows continuously as the soft
/// segment softens or the transition widens, whatever the scene: 1.49 at
/// `D1/D0 = 0.001, γ = 200`, 1 at `D1/D0 = 0.1` (any `γ ≥ 30`); 1 for every other profile.
pub(crate) fn bending_factor(stiffness: &Stiffness) -> f64 {
    match stiffness {
        Stiffness::Tanh { d0, d1, gamma, .. } if *d0 > 0.0 && *d1 > 0.0 && *gamma > 0.0 => {
            let ratio = (d1 / d0).min(1.0);
            (3.0 * std::f64::consts::PI / (gamma * ratio.sqrt())).max(1.0)
        }
        _ => 1.0,
    }
}

/// `cells` raised by [`bending_factor`] (rounded down: the factor refines a count that
/// already resolves the transitions).
pub(crate) fn bending_scaled(cells: usize, stiffness: &Stiffness) -> usize {
    ((cells as f64 * bending_factor(stiffness)).floor() as usize).max(cells)
}

/// Cells a stiffness profile needs to be resolved at all: for Eq. (51) on a uniform mesh
/// `γ` (one cell per transition width `L/γ`); on the graded mesh of
/// [`rodloop_solver::MeshMap::for_profile`] the cells at the transitions are
/// `ρ_max/∫ρ` times finer than the mean, so `γ ∫ρ/ρ_max` cells give them the same width;
/// one per table point; none for a uniform rod (the fast-level rule of [`Accuracy::cells`]).
pub(crate) fn profile_cells(stiffness: &Stiffness) -> usize {
    match stiffness {
        Stiffness::Tanh { gamma, .. } => {
            let refinement = match rodloop_solver::MeshMap::for_profile(stiffness) {
                rodloop_solver::MeshMap::Graded {
                    centers,
                    sharpness,
                    amplitude,
                } => {
                    // ∫ρ = 1 + A π k/β (k bumps of ∫sech = π/β); ρ_max ≥ 1 + A.
                    let integral =
                        1.0 + amplitude * std::f64::consts::PI * centers.len() as f64 / sharpness;
                    (1.0 + amplitude) / integral
                }
                rodloop_solver::MeshMap::Uniform => 1.0,
            };
            (gamma / refinement).ceil().min(4096.0) as usize
        }
        Stiffness::Table { s, .. } => s.len(),
        Stiffness::Uniform { .. } => 0,
    }
}

/// Progress events of [`compute`], [`compute_branch`] and [`assemble`] (for progress bars).
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum Progress {
    /// [`compute`] will produce these branches (`η` values), `resumed` of them from the
    /// resume list.
    Planned {
        /// Branches (`η`) of the diagram.
        etas: Vec<u32>,
        /// How many come from the resume list.
        resumed: usize,
    },
    /// Tracing of a branch started.
    BranchStarted {
        /// Paper branch number.
        branch: u32,
        /// Periods of `κ_g`.
        eta: u32,
    },
    /// Tracing of a branch progressed (every 25 continuation steps, and at the end of each
    /// direction).
    BranchStep {
        /// Periods of `κ_g`.
        eta: u32,
        /// Length reached.
        lbar: f64,
        /// Continuation steps so far in this direction.
        steps: usize,
    },
    /// A branch was traced.
    BranchFinished {
        /// Paper branch number.
        branch: u32,
        /// Periods of `κ_g`.
        eta: u32,
        /// Number of traced states.
        points: usize,
        /// Wall time of the branch in seconds.
        seconds: f64,
    },
    /// A branch was taken from the resume list.
    BranchResumed {
        /// Paper branch number.
        branch: u32,
        /// Periods of `κ_g`.
        eta: u32,
        /// Number of traced states.
        points: usize,
    },
    /// A branch could not be traced (it is left out of the diagram, with a warning).
    BranchFailed {
        /// Periods of `κ_g`.
        eta: u32,
        /// Why.
        reason: String,
    },
    /// A resumed branch did not match the options and is traced again.
    BranchResumeRejected {
        /// Periods of `κ_g`.
        eta: u32,
        /// Why it was rejected.
        reason: String,
    },
    /// [`assemble`] will locate this many crossings and analyse this many great circles
    /// (one [`Progress::CriticalLocated`] per crossing, one [`Progress::GreatCircleDone`] per
    /// circle follow, in any order).
    AssemblyPlanned {
        /// Number of crossings found on the samples.
        crossings: usize,
        /// Number of great circles to analyse.
        great_circles: usize,
    },
    /// A critical length was located.
    CriticalLocated {
        /// Crossing or collapse.
        kind: CriticalKind,
        /// The critical length.
        lbar_cr: f64,
        /// Lowest branch below.
        from_branch: u32,
        /// Lowest branch above.
        to_branch: u32,
    },
    /// The great circle with `m` turns was analysed (buckling loads and switching).
    GreatCircleDone {
        /// Number of turns.
        m: u32,
        /// Of this many.
        total: usize,
    },
}
