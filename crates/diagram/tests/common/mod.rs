//! Setup shared by the enclosed two-segment tests.

use rodloop_solver::Stiffness;

/// The stiffness of `data/scenes/inhomogeneous-d1-0.5-enclosed.toml` (Eq. (51), the
/// paper's Sec. 5 rod with `D1/D0 = 0.5`).
pub fn sharp() -> Stiffness {
    Stiffness::paper_sec5(0.5)
}
