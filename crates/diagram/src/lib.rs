//! The numeric branch diagram of elastic rod loops on a sphere (paper: Wang, Li & Yi, JMPS
//! 2024, Secs. 3.1, 4.2, 4.3, Figs. 2, 3, 7): every configuration branch followed in the
//! normalised length `L̄ = L/(2πR)`, the critical lengths where branches exchange global
//! stability, a stability label for every computed state, and the buckling of the m-fold
//! great circles with branch switching from them.
//!
//! The crate root holds the pipeline's description, the module table and the re-exports; the
//! error type, the options every stage reads and the stages are in the modules.
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
//! | `error.rs` | [`DiagramError`], the crate's one error type |
//! | `options.rs` | [`DiagramOptions`], [`TraceControls`], their validation and the scene's surface model |
//! | `progress.rs` | the [`Progress`] events |
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
//! | `engine/` | the [`Engine`] interface of every diagram model and its result in the schema |
//! | `refine.rs`, `critical.rs`, `labels.rs`, `buckling.rs`, `diagram/` | the assembly |
//! | `param_sweep/` | the sweep in a stiffness parameter at a fixed length (`diagram --param`) |
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
mod error;
mod estimate;
pub mod families;
mod labels;
pub mod march;
pub mod maxwell;
mod options;
mod parallel;
pub mod param_sweep;
pub mod phase;
mod placements;
mod progress;
pub mod refine;
pub mod reported;
pub mod representative;
mod resolve;
pub mod sampling;
mod seed;
pub mod shapes;
mod special;
mod state_file;
pub mod state_rows;
mod states;
pub mod trace;
pub mod types;

pub use buckling::{Buckling, BucklingReport, Switching};
pub use compute::{compute, BranchHook, Origin, Resume};
pub use critical::{CriticalKind, CriticalLength};
pub use diagram::{
    assemble, BranchSummary, DiagramRow, DiagramSummary, NumericDiagram, SpecialKind, SpecialPoint,
    Timings,
};
pub use engine::{
    BranchFileEvent, BranchFiles, EnclosedEngine, Engine, ExactEngine, ExactOutput, PhaseEngine,
    PointState, PointStates, RecordStates, StateTable, SurfaceEngine, SweepEngine, VerifiedPhase,
    VerifiedSweep,
};
pub use error::DiagramError;
pub use labels::Label;
pub use march::{
    march, march_switch, march_switch_until, march_until, FoldPolicy, March, MarchPoint,
    MarchSettings, MarchSpecial, MarchStop,
};
pub(crate) use options::{model_with_phase, surface_model};
pub use options::{DiagramOptions, TraceControls};
pub use parallel::parallel_map;
pub use progress::Progress;
/// The error type a [`BranchHook`] returns.
pub use rodloop_continuation::BoxError;
pub(crate) use rodloop_solver::accuracy::profile_cells;
pub use state_file::{
    branch_identification, BranchIdentification, StateFile, ESTIMATES, MAX_REFINEMENT,
    MAX_STATE_POINTS, NO_ESTIMATE_TOLERANCE, STATE_POINTS,
};
pub use trace::compute_branch;
pub use types::{BranchEnd, BranchTimings, IndexChange, PointSource, TracedBranch, TracedPoint};
