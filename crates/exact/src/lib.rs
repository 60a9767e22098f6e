//! Exact solutions of the rod-loop problem: closed elastic curves on a sphere with uniform
//! bending stiffness (paper Secs. 3.1, 4.2, 4.3 and App. B), Euler rotation curves (Eqs. 4–8)
//! and the exact energy-versus-length diagram.
//!
//! Everything here is "exact" in the sense of closed forms in Jacobi elliptic functions and
//! elliptic integrals; the only numerical steps are scalar root finding to full double
//! precision and, for Euler curves, exponentially convergent periodic quadrature.

pub mod diagram;
pub mod euler;
pub mod homogeneous;
pub mod roots;
pub mod shape;
pub mod symmetry;
pub mod topology;

pub use homogeneous::{all_loops, paper_branch_loop, ExactLoop, Family, LoopPoint};
pub use shape::{loop_shape, LoopShape, SampledLoop, ShapeTolerances};

/// Paper branch number for a loop with `eta` periods of geodesic curvature (Sec. 3.1):
/// η = 2 → 1 (saddle), η = 1 → 2 (figure-eight), η ≥ 3 → η.
pub fn branch_of_eta(eta: u32) -> u32 {
    match eta {
        1 => 2,
        2 => 1,
        e => e,
    }
}

/// Inverse of [`branch_of_eta`].
pub fn eta_of_branch(branch: u32) -> u32 {
    branch_of_eta(branch)
}

/// Errors of the exact layer.
#[derive(Debug, thiserror::Error)]
pub enum ExactError {
    /// A parameter outside its domain.
    #[error("invalid parameter: {0}")]
    InvalidParameter(String),
    /// A length outside the range where the branch exists.
    #[error("branch with eta = {eta} exists only for {min} < lbar < {max}, not at lbar = {lbar}")]
    OutOfRange {
        /// Periods of κ_g.
        eta: u32,
        /// Requested length.
        lbar: f64,
        /// Lower end (exclusive).
        min: f64,
        /// Upper end (exclusive).
        max: f64,
    },
    /// No closed loop found where one was expected.
    #[error("no closed loop with eta = {eta} found at lbar = {lbar}")]
    NoSolution {
        /// Periods of κ_g.
        eta: u32,
        /// Requested length.
        lbar: f64,
    },
    /// An elliptic-function evaluation failed.
    #[error("special function: {0}")]
    Special(String),
    /// A root bracket without a sign change.
    #[error("no sign change in [{a}, {b}] (f = {fa}, {fb})")]
    NoBracket {
        /// Left end.
        a: f64,
        /// Right end.
        b: f64,
        /// f(a).
        fa: f64,
        /// f(b).
        fb: f64,
    },
    /// Root finder hit its iteration limit.
    #[error("root finder did not converge (x = {x}, f = {fx})")]
    RootNotConverged {
        /// Last iterate.
        x: f64,
        /// Residual there.
        fx: f64,
    },
    /// Continuation of a branch failed.
    #[error("continuation: {0}")]
    Continuation(String),
}
