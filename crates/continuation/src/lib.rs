//! Generic numerical continuation of solution branches of `F(x, p) = 0`.
//!
//! The crate traces curves of solutions `x ∈ Rⁿ` of a parameter-dependent system
//! `F(x, p) = 0`, `F: Rⁿ × R → Rⁿ`, in the scalar parameter `p`, with Keller's
//! pseudo-arclength method, and detects and locates folds, simple branch points,
//! changes of a user-supplied stability index and zeros of user event functions along
//! the way. It knows nothing about the model behind `F`.
//!
//! * A model implements [`Problem`] (residual, Jacobian `∂F/∂x`, parameter derivative
//!   `∂F/∂p`; [`fd_jacobian`] and [`fd_dparam`] help for small problems and tests).
//! * [`PseudoArclength`] holds the settings (validated builder setters).
//! * [`Continuation`] runs it, with optional [`Stability`] index and event functions,
//!   and returns a [`Branch`] of [`Point`]s, [`SpecialPoint`]s and a [`StopReason`];
//!   [`Continuation::switch_branch`] follows the second branch at a branch point.
//! * [`Continuation::start`] (and [`Continuation::start_switch`]) return a [`Stepper`]
//!   that advances one accepted step per call, reporting each [`Step`]'s point,
//!   special points and stop; `run` and `switch_branch` are loops over it, and
//!   [`Stepper::drive`] is the loop a tracer runs with its own visitor of each step
//!   ([`Flow`], [`OnError`], [`Driven`]).
//! * [`newton`] solves at a fixed parameter; [`solve_at`] re-solves a computed branch
//!   at an exact parameter value.
//! * [`target::reach`] continues a solution until the parameter reaches a target value
//!   (a homotopy through folds); [`natural`] holds the natural-parameter loop (step the
//!   parameter, correct with the caller's solver, halve on failure) for any state type
//!   and corrector, and [`natural::natural_branch`] for a [`Problem`].
//! * [`axis`] continues a problem in `ln θ` instead of `θ` ([`axis::OnAxis`]).
//! * [`roots`] holds the one-dimensional root finders (secant, Illinois, Brent) used
//!   to locate special points and exchanges of stability; [`exchange`] locates the
//!   crossing of two branches' energies with an error estimate and labels the states at
//!   one parameter value (stable, metastable, unstable); [`sampled`] interpolates a
//!   sampled curve with an error bound from its own second differences.
//!
//! Linear algebra: every solve with the Jacobian goes through
//! [`Problem::factorize`], which returns a [`Factorization`] of `J = ∂F/∂x` — by
//! default the dense LU [`DenseLu`], replaceable by a structured (banded, block
//! tridiagonal, sparse) `O(n)` solver. The bordered systems of the continuation are
//! solved by block elimination with it, refined once, with dense bordered LU as the
//! fallback near singular `J`. Branch switching uses dense SVDs of `[J F_p]`.
//!
//! References: H. B. Keller, *Numerical solution of bifurcation and nonlinear
//! eigenvalue problems*, in Applications of Bifurcation Theory, Academic Press 1977;
//! E. L. Allgower & K. Georg, *Introduction to Numerical Continuation Methods*, SIAM
//! 2003; Yu. A. Kuznetsov, *Elements of Applied Bifurcation Theory*, 3rd ed., Springer
//! 2004, ch. 10; W. Govaerts, *Numerical Methods for Bifurcations of Dynamical
//! Equilibria*, SIAM 2000, ch. 3 (bordered systems).
//!
//! ```
//! use nalgebra::{DMatrix, DVector};
//! use rodloop_continuation::{Continuation, Problem, PseudoArclength, SpecialKind};
//!
//! /// The fold normal form F = p − x², with a fold at (x, p) = (0, 0).
//! struct Fold;
//! impl Problem for Fold {
//!     type Error = std::convert::Infallible;
//!     fn dim(&self) -> usize { 1 }
//!     fn residual(&self, x: &DVector<f64>, p: f64) -> Result<DVector<f64>, Self::Error> {
//!         Ok(DVector::from_element(1, p - x[0] * x[0]))
//!     }
//!     fn jacobian(&self, x: &DVector<f64>, _p: f64) -> Result<DMatrix<f64>, Self::Error> {
//!         Ok(DMatrix::from_element(1, 1, -2.0 * x[0]))
//!     }
//!     fn dparam(&self, _x: &DVector<f64>, _p: f64) -> Result<DVector<f64>, Self::Error> {
//!         Ok(DVector::from_element(1, 1.0))
//!     }
//! }
//!
//! let settings = PseudoArclength::new()
//!     .with_ds(0.05)?
//!     .with_range(-1.0, 1.0)?
//!     .with_direction(rodloop_continuation::Direction::Backward)?;
//! let branch = Continuation::new(&Fold, settings).run(&DVector::from_element(1, 0.8), 0.64)?;
//! let fold = branch.folds().next().expect("one fold");
//! assert!(fold.p.abs() < 1e-12 && fold.x[0].abs() < 1e-8);
//! assert_eq!(fold.kind, SpecialKind::Fold);
//! # Ok::<(), rodloop_continuation::ContinuationError>(())
//! ```

#![warn(missing_docs)]

pub mod axis;
mod branch;
mod drive;
mod error;
pub mod exchange;
mod factorization;
mod linalg;
pub mod natural;
mod newton;
mod problem;
pub mod roots;
pub mod sampled;
mod settings;
mod stepper;
mod switching;
pub mod target;
mod tracker;

pub use branch::{Branch, Point, SpecialKind, SpecialPoint, StopReason};
pub use drive::{Driven, Flow, OnError};
pub use error::{BoxError, ContinuationError, RootError, SharedError};
pub use factorization::{DenseLu, Factorization};
pub use newton::{newton, solve_all_at, solve_at, NewtonReport};
pub use problem::{fd_dparam, fd_jacobian, Problem, Stability};
pub use settings::{Direction, PseudoArclength};
pub use stepper::{Step, Stepper};
pub use tracker::Continuation;
