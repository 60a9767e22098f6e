//! Setup shared by the enclosed two-segment tests.

use rodloop_solver::Stiffness;

/// The stiffness of `data/scenes/inhomogeneous-d1-0.5-enclosed.toml` (Eq. (51), the
/// paper's Sec. 5 rod with `D1/D0 = 0.5`).
pub fn sharp() -> Stiffness {
    Stiffness::Tanh {
        d0: 1.0,
        d1: 0.5,
        s0: 0.3,
        s1: 0.8,
        gamma: 200.0,
    }
}
