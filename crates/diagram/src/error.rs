//! The one error type of the diagram crate, [`DiagramError`]: invalid options, branches
//! outside the range, solver and continuation failures, and the errors a [`crate::BranchHook`]
//! returns.

use rodloop_continuation::BoxError;
use rodloop_solver::SolverError;

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
    /// A traced branch passed to [`assemble`](crate::assemble) is unusable (no points, wrong state
    /// length, …).
    #[error("traced branch eta = {eta} is unusable: {reason}")]
    InvalidBranch {
        /// Periods of `κ_g`.
        eta: u32,
        /// What is wrong with it.
        reason: String,
    },
    /// The per-branch hook of [`compute`](crate::compute) failed (e.g. a branch file could not be
    /// written).
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
