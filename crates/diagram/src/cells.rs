//! Cell counts a stiffness profile implies: the cells that resolve the transitions of
//! Eq. (51) ([`profile_cells`]) and the refinement that resolves the bending length of a soft
//! segment ([`bending_factor`], [`bending_scaled`]).

use rodloop_solver::Stiffness;

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
/// one per table point; none for a uniform rod (the fast-level rule of [`rodloop_solver::Accuracy::cells`]).
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
