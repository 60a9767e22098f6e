//! The error type of the crate.

use std::sync::Arc;

/// A shareable, type-erased error coming from user code (a [`Problem`](crate::Problem)
/// evaluation or a [`Stability`](crate::Stability) callback).
///
/// It is reference counted so that [`ContinuationError`] stays `Clone`.
pub type SharedError = Arc<dyn std::error::Error + Send + Sync + 'static>;

/// A boxed error, the error type of [`Stability::index`](crate::Stability::index).
pub type BoxError = Box<dyn std::error::Error + Send + Sync + 'static>;

/// Everything that can go wrong in this crate.
///
/// Conditions that merely end a continuation run (leaving the parameter range, a step
/// that became too small, the step budget) are *not* errors: they are reported as a
/// [`StopReason`](crate::StopReason) in the returned [`Branch`](crate::Branch).
#[derive(Debug, Clone, thiserror::Error)]
#[non_exhaustive]
pub enum ContinuationError {
    /// The user's [`Problem`](crate::Problem) returned an error.
    #[error("problem evaluation failed: {0}")]
    Problem(#[source] SharedError),

    /// The user's [`Stability`](crate::Stability) callback returned an error.
    #[error("stability index evaluation failed: {0}")]
    Stability(#[source] SharedError),

    /// A state vector passed in does not have the problem's dimension.
    #[error("state vector has length {found}, the problem has dimension {expected}")]
    WrongStateLength {
        /// `Problem::dim()`.
        expected: usize,
        /// Length of the vector that was passed.
        found: usize,
    },

    /// A problem method returned a vector or matrix of the wrong shape.
    #[error("{what} has shape {found:?}, expected {expected:?}")]
    WrongOutputShape {
        /// Which method (`"residual"`, `"jacobian"` or `"dparam"`).
        what: &'static str,
        /// Expected `(rows, columns)`.
        expected: (usize, usize),
        /// Returned `(rows, columns)`.
        found: (usize, usize),
    },

    /// A Newton corrector did not reach its tolerance.
    #[error("corrector did not converge after {iterations} iterations (residual {residual:e})")]
    CorrectorDiverged {
        /// Number of Newton iterations (linear solves) performed.
        iterations: usize,
        /// Max-norm of the residual at the last iterate (may be NaN or infinite).
        residual: f64,
    },

    /// A linear system of a Newton iteration was singular (or produced non-finite values).
    #[error("singular linear system in Newton iteration at p = {p}")]
    SingularMatrix {
        /// Parameter value at which it happened.
        p: f64,
    },

    /// No step, down to the minimal step size, could be taken (branch switching).
    #[error("step size {ds:e} fell below the minimum at p = {p}")]
    StepTooSmall {
        /// The step size that was rejected.
        ds: f64,
        /// Parameter value of the point the step started from.
        p: f64,
    },

    /// A setting was given an invalid value, or settings are mutually inconsistent.
    #[error("invalid setting `{name}`: {reason}")]
    InvalidSetting {
        /// Name of the setting.
        name: &'static str,
        /// Why it was rejected.
        reason: String,
    },

    /// The starting point lies outside the parameter range of the settings.
    #[error("starting parameter {p} lies outside the range [{p_min}, {p_max}]")]
    StartOutsideRange {
        /// Starting parameter.
        p: f64,
        /// Lower end of the range.
        p_min: f64,
        /// Upper end of the range.
        p_max: f64,
    },

    /// [`Continuation::switch_branch`](crate::Continuation::switch_branch) was given a
    /// special point that is not a branch point.
    #[error("special point is a {kind}, not a branch point")]
    NotABranchPoint {
        /// Kind of the special point that was passed.
        kind: &'static str,
    },

    /// An operation needing at least one point was given an empty branch.
    #[error("the branch has no points")]
    EmptyBranch,
}

impl ContinuationError {
    /// Wraps a user problem error.
    pub(crate) fn problem<E: std::error::Error + Send + Sync + 'static>(e: E) -> Self {
        ContinuationError::Problem(Arc::new(e))
    }

    pub(crate) fn invalid(name: &'static str, reason: impl Into<String>) -> Self {
        ContinuationError::InvalidSetting {
            name,
            reason: reason.into(),
        }
    }
}

/// Errors of the [root finders](crate::roots): the caller's function failed, or the
/// bracket has no sign change. Generic over the function's own error `E`, which is
/// handed back unchanged (an unconverged iteration is not an error: it is reported in
/// the [`Root`](crate::roots::Root)).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RootError<E> {
    /// The function failed at some `x`.
    #[error("{0}")]
    Function(E),
    /// `f(a)` and `f(b)` have the same strict sign.
    #[error("no sign change in [{a}, {b}] (f = {fa:e}, {fb:e})")]
    NoBracket {
        /// Left end.
        a: f64,
        /// Right end.
        b: f64,
        /// `f(a)`.
        fa: f64,
        /// `f(b)`.
        fb: f64,
    },
    /// A hunt for a sign change ([`exchange::locate`](crate::exchange::locate)) stepped
    /// out of its window.
    #[error("the hunt for a sign change left [{lo}, {hi}] at x = {x}")]
    LeftWindow {
        /// The point outside the window.
        x: f64,
        /// Window's left end.
        lo: f64,
        /// Window's right end.
        hi: f64,
    },
    /// [`exchange::locate`](crate::exchange::locate) met a flat or non-finite slope, or
    /// found no sign change within its budget.
    #[error("{what} (at x = {x})")]
    Degenerate {
        /// Where.
        x: f64,
        /// What happened.
        what: &'static str,
    },
}
