//! Loops enclosed in the ball, `|r(s)| ≤ R` (paper Sec. 3.2): contact that can let go.
//!
//! The wall can only push (`λ ≥ 0`), so where a surface equilibrium needs `λ < 0` the
//! enclosed loop lifts off. This model carries 3-D unknowns only because an enclosed scene
//! needs them: the curvature vector `(κ1, κ2)` in a rotation-minimising (Bishop) frame at
//! the Gauss points — untwisted isotropic rod, `E = ½∫D(κ1² + κ2²) ds` — plus the start
//! point; frame and position come from one fourth-order Magnus chain in SE(3)
//! ([`jet`]), so inextensibility holds by construction and closure is "position and
//! tangent return" (5 of the 6 rows of the SE(3) closure; the frame may come back turned
//! about the tangent, [`model::TWIST_ROW`]). The wall is an inequality at the nodes with multipliers `λ ≥ 0`,
//! solved by semismooth Newton on `min(λ, σg) = 0` ([`solve`]).
//!
//! * [`jet`]: second-order jets and the SE(3) cell propagator.
//! * [`model`]: [`EnclosedModel`] (energy, closure, wall, KKT residual and exact Jacobian).
//! * [`wall`]: the confining wall `g(r) ≥ 0` with its derivatives ([`SphereWall`]).
//! * [`lifted`]: the Newton step in `O(N)` from a block-tridiagonal form of that Jacobian.
//! * [`solve`](mod@solve): semismooth Newton (min-function, handed over to
//!   Fischer–Burmeister where it crawls), starts (surface loop, free circle).
//! * [`state`]: a converged [`EnclosedState`]: energy, contact summary and forces, the
//!   spectrum on the active constraints' tangent space, the two-resolution estimate, steps
//!   to a nearby length.
//! * [`from_shape`]: a start from a saved shape (`solve --from`).
//! * [`inertia`]: the stability index from the inertia of the bordered KKT matrix.
//! * [`descent`]: the enclosed solve that ends at the branch's lowest local minimum, over
//!   its routes: leaving a saddle along its unstable direction (the enclosed side of the one
//!   descent routine, [`crate::descend`]), starts by continuation in the stiffness from the
//!   uniform rod, minima of other lengths ([`length_path`]).
//! * [`continuation`]: natural-parameter steps in `L̄` (the enclosed diagram's tracer).
//! * [`length_path`]: local minima of a branch continued in `L̄` from other lengths.
//! * [`seam`]: the model behind [`crate::Confinement`] (continuation through the seam).
//! * [`centre`]: point contacts moved onto nodes (the origin shifted to a contact point).
//! * [`branch`]: a paper branch in an enclosed scene with the two-resolution error estimate.
//! * [`stats`]: counters of the Newton solves by stage of a caller.

pub mod arclength;
pub mod branch;
mod carry;
pub mod centre;
pub mod continuation;
pub mod descent;
pub mod from_shape;
pub mod inertia;
pub mod jet;
pub mod length_path;
pub mod lifted;
pub mod lifted_factor;
pub mod model;
pub mod seam;
pub mod solve;
pub mod state;
pub mod stats;
pub mod wall;

pub use crate::accuracy::{enclosed_cells, enclosed_solve_cells, nonuniform_cells};
pub use branch::{
    detached_intervals, finer_check, finest_energy, four_level_estimate, point_like_contact,
    solve_branch, solve_levels, three_level_estimate, BranchSolve, SurfaceSource,
    LIFTED_OFF_MAX_ORDER, POINT_CONTACT_CELLS,
};
pub use from_shape::{start_from_shape, SavedShape};
pub use model::{Complementarity, EnclosedModel, Gauge};
pub use seam::EnclosedFactor;
pub use solve::{
    free_circle, solve_enclosed, solve_prolonged, start_from_surface, Contact, EnclosedOptions,
    EnclosedState, STEP_ITERATIONS,
};
pub use wall::{IntoWall, SphereWall, Wall};
