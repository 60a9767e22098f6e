//! Numerical model of rod loops confined to a sphere.
//!
//! A curve on a sphere of radius `R` is determined, up to a rigid rotation, by its geodesic
//! curvature `κ_g(s)`: the Darboux frame `(t, g, n)` obeys (paper App. A, with `κ_n = −1/R`
//! and `τ_g = 0` on a sphere) `t' = κ_g g − n/R`, `g' = −κ_g t`, `n' = t/R`, and the position
//! is `r = R n`. Position on the sphere and inextensibility therefore hold by construction,
//! and closure of the loop is closure of the frame, a condition in SO(3). Module [`frame`]
//! integrates that system; the discretised equilibrium solver builds on it.

pub mod frame;

/// Errors of the solver crate.
#[derive(Debug, thiserror::Error)]
pub enum SolverError {
    /// Bad input to a solver routine.
    #[error("invalid input: {0}")]
    InvalidInput(String),
}
