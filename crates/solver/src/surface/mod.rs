//! The surface model: a loop on the sphere written in its geodesic curvature `κ_g(s)`
//! (Darboux frame, paper App. A), beside [`crate::enclosed`] for loops inside it.
//!
//! * [`frame`]: the Darboux-frame integrator (fourth-order Magnus) and the Rodrigues jet.
//! * [`model`]: the discretised model ([`SurfaceModel`](model::SurfaceModel)): energy,
//!   closure, KKT residual, analytic Jacobian and Hessian, parameter derivatives.
//! * [`kkt`]: the block factorisation of its KKT matrix (`O(N)`) with its inertia.
//! * [`periodic`]: trigonometric interpolation of periodic samples (resampling, spectral
//!   derivatives).
//! * [`stability`]: constrained Hessian spectrum, index and symmetry modes.
//!
//! The crate re-exports each module at its root (`rodloop_solver::model`, …).

pub mod frame;
pub mod kkt;
pub mod model;
pub mod periodic;
pub mod stability;
