//! Numerical equilibria of elastic rod loops confined to the surface of a sphere, for any
//! bending-stiffness profile `D(s)` (paper: Wang, Li & Yi, JMPS 2024, Secs. 2, 4.1, 4.3, 5).
//!
//! A curve on a sphere of radius `R` is determined, up to a rigid rotation, by its geodesic
//! curvature `κ_g(s)`: the Darboux frame `(t, g, n)` obeys (paper App. A, with `κ_n = −1/R`
//! and `τ_g = 0` on a sphere) `t' = κ_g g − n/R`, `g' = −κ_g t`, `n' = t/R`, and the position
//! is `r = R n`. Position on the sphere and inextensibility therefore hold by construction,
//! and closure of the loop is closure of the frame, a condition in SO(3).
//!
//! * [`surface`]: the folder of the surface model's files ([`frame`], [`model`], [`kkt`],
//!   [`periodic`], [`stability`]), re-exported here.
//! * [`frame`]: the Darboux-frame integrator (fourth-order Magnus) and the Rodrigues jet.
//! * [`stiffness`]: `D(s)` profiles (uniform, Eq. (51), tables).
//! * [`model`]: the discretised model ([`SurfaceModel`]): energy, closure, KKT residual,
//!   analytic Jacobian and Hessian, `∂F/∂L̄`.
//! * [`solve()`]: globalised Newton on the KKT system → [`Equilibrium`] (forces, profiles,
//!   energies) with a [`ConvergenceReport`].
//! * [`stability`]: constrained Hessian spectrum, index and symmetry modes.
//! * [`descend`](mod@descend): from a saddle along its unstable directions to a local minimum
//!   of the same branch (both confinement models).
//! * [`start`]: starting shapes (Euler rotation curves, exact loops, point clouds, resampled
//!   equilibria).
//! * [`accuracy`]: resolution choice and Richardson extrapolation.
//! * [`verify`]: the checks every reported state passes (closed, on the sphere, energy
//!   recomputable from the written profile, branch identified from the state).
//! * [`continuation`]: the KKT system as a [`rodloop_continuation::Problem`] in `L̄`.
//!
//! Units: everything is dimensional in the model's `R` and `D`; with `R = 1` and `D0 = 1`
//! the outputs are the paper's normalised quantities (`κR`, `λR³/D`, `F R²/D`), and energies
//! are reported as `E R/(π D0)`.

#![warn(missing_docs)]

pub mod accuracy;
pub mod continuation;
pub mod descend;
pub mod enclosed;
pub mod identify;
pub mod mesh;
pub mod param;
mod resample;
pub mod robust;
pub mod seam;
pub mod shape;
pub mod solve;
pub mod start;
pub mod stiffness;
pub mod surface;
pub mod verify;

pub use surface::{frame, kkt, model, periodic, stability};

pub use accuracy::{
    finish_with_accuracy, richardson, richardson_error, solve_cells, solve_with_accuracy, Accuracy,
    AccurateEquilibrium,
};
pub use continuation::LbarProblem;
pub use kkt::KktFactor;
pub use mesh::MeshMap;
pub use model::{Phase, SurfaceModel};
pub use param::Param;
pub use robust::{solve_robust, solve_robust_verified, solve_robust_with, Fallbacks, Strategy};
pub use seam::{Confinement, Inertia, ModelFactor, ParamProblem, SurfaceSolve};
pub use solve::{
    solve, solve_from_state, solve_newton_keeping, solve_newton_keeping_until, solve_newton_until,
    ConvergenceReport, EnergyReport, Equilibrium, Globalization, NewtonRun, ProfilePoint,
    SolveOptions, Stall,
};
pub use stability::{extreme_eigenpairs, Extremes, Stability, StabilityOptions};
pub use start::StartShape;
pub use stiffness::{Stiffness, StiffnessProfile};
pub use verify::{
    check_energy, check_holonomy, enclosed_profile, profile_energy, verify_accurate,
    verify_enclosed, verify_state, Claim, EnclosedVerification, Verification,
};

/// Errors of the solver crate.
#[derive(Debug, thiserror::Error)]
pub enum SolverError {
    /// Bad input to a solver routine.
    #[error("invalid input: {0}")]
    InvalidInput(String),
    /// A stiffness profile that is not positive, not finite or inconsistent.
    #[error("invalid stiffness profile: {0}")]
    InvalidProfile(String),
    /// A vector of the wrong length.
    #[error("wrong vector length: expected {expected}, found {found}")]
    WrongLength {
        /// Required length.
        expected: usize,
        /// Length given.
        found: usize,
    },
    /// Newton's method did not reach the tolerance.
    #[error(
        "Newton iteration did not converge after {iterations} iterations \
         (KKT residual {residual:.3e}, closure violation {closure:.3e})"
    )]
    NewtonNotConverged {
        /// Iterations performed.
        iterations: usize,
        /// Final KKT residual norm (see [`SurfaceModel::residual_norm`]).
        residual: f64,
        /// Final closure violation `|c|`.
        closure: f64,
    },
    /// The KKT matrix could not be factorised.
    #[error("singular KKT matrix at Newton iteration {iteration}")]
    SingularJacobian {
        /// Iteration at which it happened.
        iteration: usize,
    },
    /// A converged state that fails a check of [`verify::verify_state`] (not closed, off the
    /// sphere, an energy the written profile does not reproduce, or another branch): it is
    /// not reported.
    #[error("the state fails verification: {0}")]
    Unverified(String),
    /// An error of the exact layer (starting shapes, references).
    #[error("exact layer: {0}")]
    Exact(String),
}

impl From<rodloop_exact::ExactError> for SolverError {
    fn from(e: rodloop_exact::ExactError) -> Self {
        SolverError::Exact(e.to_string())
    }
}

impl From<rodloop_exact::euler::EulerError> for SolverError {
    fn from(e: rodloop_exact::euler::EulerError) -> Self {
        SolverError::Exact(e.to_string())
    }
}
