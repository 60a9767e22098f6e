//! Every rule that turns an accuracy level and a scene into a number of cells: the
//! resolution table (cells per period of `κ_g` at the levels `[fast, default, high]`, one row
//! per use) and one function per use, so that a resolution is chosen in one place.
//!
//! | use | rule | function |
//! |---|---|---|
//! | surface solve | `c (1 + η)`, plus `c` on a graded mesh, at least what the profile needs | [`Accuracy::cells`] |
//! | surface tracing of a diagram | `c (η + 1)`, the profile's cells (twice for modest profiles), the bending factor | [`trace_cells`] |
//! | reporting pair of a diagram | `(N, N/2)` of the solve rule, `(2N, N)` at `high`, the bending factor | [`reporting_cells`] |
//! | companion of a pair (`phase`) | `N/2` (even), `2N` at `high` | [`companion_cells`] |
//! | buckling loads of the m-fold circle | `c (m + 2)` (even) | [`load_cells`] |
//! | enclosed diagram levels | `c (1 + η)`, at least 32 | [`enclosed_cells`] |
//! | enclosed two-segment traces | [`enclosed_cells`], at least `32 (2 + η)` | [`nonuniform_cells`] |
//! | enclosed solve | `c (1 + η)`, at least 32 | [`enclosed_solve_cells`] |
//! | enclosed solve of a scene | uniform: [`enclosed_solve_cells`]; two-segment: [`nonuniform_cells`] | [`enclosed_scene_cells`] |
//! | a stiffness profile at all | `γ ∫ρ/ρ_max` on the graded mesh, one per table point | [`profile_cells`] |
//! | a soft segment's bending length | `max(1, 3π/(γ √(D1/D0)))` | [`bending_factor`], [`bending_scaled`] |

use super::Accuracy;
use crate::stiffness::Stiffness;

/// Cells per period of `κ_g` (plus one) at the default accuracy.
pub const DEFAULT_CELLS_PER_PERIOD: usize = 56;
/// Cells per period of `κ_g` (plus one) at the fast accuracy.
pub const FAST_CELLS_PER_PERIOD: usize = 20;

/// The resolution table: cells per period of `κ_g` at the levels `[fast, default, high]`
/// for each use (each count is then multiplied by the use's number of periods, see the
/// functions named). One place for every level-to-cells rule of the workspace.
///
/// Surface solve, [`Accuracy::cells`]: `N = c (1 + η)` (plus `c` on a graded mesh).
pub const SOLVE_CELLS: [usize; 3] = [
    FAST_CELLS_PER_PERIOD,
    DEFAULT_CELLS_PER_PERIOD,
    DEFAULT_CELLS_PER_PERIOD,
];
/// Surface tracing resolution of the diagram ([`trace_cells`]):
/// `c (η + 1)`.
pub const TRACE_CELLS: [usize; 3] = [8, 12, 16];
/// Buckling loads of the m-fold great circle ([`load_cells`]): `c (m + 2)`.
pub const LOAD_CELLS: [usize; 3] = [4, 8, 16];
/// Enclosed diagram levels ([`enclosed_cells`]): `c (1 + η)`, at least 32.
pub const ENCLOSED_TRACE_CELLS: [usize; 3] = [16, 32, 64];
/// A single enclosed solve ([`enclosed_solve_cells`]): `c (1 + η)`.
pub const ENCLOSED_SOLVE_CELLS: [usize; 3] = [16, 192, 256];

impl Accuracy {
    /// The entry of a `[fast, default, high]` row (e.g. of the resolution table above).
    pub fn pick<T: Copy>(self, row: [T; 3]) -> T {
        match self {
            Accuracy::Fast => row[0],
            Accuracy::Default => row[1],
            Accuracy::High => row[2],
        }
    }

    /// Number of cells of the main solve for a loop whose geodesic curvature has `periods`
    /// oscillation periods (`η` of the branch; see
    /// [`StartShape::periods`](crate::StartShape::periods)):
    /// `N = c (1 + η)` with `c = 56` (default, high) or `20` (fast). The discretisation error
    /// grows with the number of oscillations, not with `L̄`; `c = 56` keeps the energy error
    /// of the homogeneous branches η = 1..4 below 1e-7 relative (`tests/convergence.rs`,
    /// `rodloop converge`). Sharp profiles (Eq. (51) with `γ > 20`) are resolved by the
    /// graded mesh ([`crate::MeshMap::for_profile`]) with `N = c (2 + η)` cells, whatever
    /// `γ` (measured: energy error ≤ 1e-7 relative for η = 1, 2 at `D1/D0 = 0.5`); smooth
    /// ones get at least `2γ` cells (`γ` for `Fast`), tables two per point. Rounded up to a
    /// multiple of 4. For `High` this is the coarse one of the pair `(N, 2N)`.
    pub fn cells(self, periods: usize, stiffness: &Stiffness) -> usize {
        let per = self.pick(SOLVE_CELLS);
        let mut n = per * (1 + periods.max(1));
        let factor = if self == Accuracy::Fast { 1.0 } else { 2.0 };
        if !crate::MeshMap::for_profile(stiffness).is_uniform() {
            n += per;
        }
        match stiffness {
            Stiffness::Tanh { gamma, .. } if *gamma <= 20.0 => {
                n = n.max((factor * gamma).ceil() as usize);
            }
            Stiffness::Table { s, .. } => n = n.max(s.len() * factor as usize),
            _ => {}
        }
        n.div_ceil(4) * 4
    }
}

/// Cells of the surface tracing resolution of a diagram's branch `eta`:
/// `c (η + 1)` with `c = per_period` (the level's row of [`TRACE_CELLS`] unless a caller sets
/// it), at least what the stiffness profile needs (`γ` cells for Eq. (51), one per table
/// point; twice that for modest profiles (`≤ 64` cells) except at the fast level, so that the
/// half-resolution partner of the energy extrapolation resolves the profile too; sharp
/// profiles are traced without that partner, the reporting resolution resolves them), raised
/// by the scene's [`bending_factor`] (a very soft segment bends sharply; at `D1/D0 = 0.001`
/// the transitions' 80 cells miss a family of branch 2 that 120 and 160 cells both find, with
/// the same refined exchanges), and 8, rounded up to a multiple of 4. The count grows
/// continuously as `D1/D0` falls: no threshold on the contrast.
pub fn trace_cells(
    accuracy: Accuracy,
    per_period: usize,
    stiffness: &Stiffness,
    eta: u32,
) -> usize {
    let base = per_period * (eta as usize + 1);
    let profile = profile_cells(stiffness);
    let factor = if accuracy == Accuracy::Fast || profile > 64 {
        1
    } else {
        2
    };
    let resolved = bending_scaled(factor * profile, stiffness);
    base.max(resolved).max(8).div_ceil(4) * 4
}

/// `(N_f, N_c)`: the two reporting resolutions (cells) of a diagram's branch `eta`: at the
/// fast and default levels `N_f` = [`Accuracy::cells`] and `N_c = N_f/2`; at the high level
/// `N_f = 2 N` and `N_c = N` with `N` the default level's count. Every count is raised by the
/// scene's [`bending_factor`] (rounded up to a multiple of 8 where it exceeds 1): a very soft
/// segment bends sharply, and at the unraised counts the exchanges of the `D1/D0 = 0.001`
/// scene (factor 1.49) carry error estimates of 1–3·10⁻⁷.
pub fn reporting_cells(accuracy: Accuracy, stiffness: &Stiffness, eta: u32) -> (usize, usize) {
    let periods = eta.max(1) as usize;
    let factor = bending_factor(stiffness);
    let scale = |n: usize| {
        if factor > 1.0 {
            ((n as f64 * factor).ceil() as usize).div_ceil(8) * 8
        } else {
            n
        }
    };
    match accuracy {
        Accuracy::Fast | Accuracy::Default => {
            let n = scale(accuracy.cells(periods, stiffness));
            (n, n / 2)
        }
        Accuracy::High => {
            let n = scale(Accuracy::Default.cells(periods, stiffness));
            (2 * n, n)
        }
    }
}

/// The companion of a resolution `n` in a pair of the level: `2n` at the high level, else
/// `n/2` rounded up to an even count.
pub fn companion_cells(accuracy: Accuracy, n: usize) -> usize {
    match accuracy {
        Accuracy::High => 2 * n,
        _ => (n / 2).div_ceil(2) * 2,
    }
}

/// Coarsest of the resolutions `(N, 2N, 4N)` of the buckling loads of the m-fold great
/// circle: `N = c (m + 2)` with `c` from [`LOAD_CELLS`] (4, 8, 16 for fast, default, high),
/// rounded up to an even count.
pub fn load_cells(accuracy: Accuracy, m: u32) -> usize {
    let base = accuracy.pick(LOAD_CELLS) * (m as usize + 2);
    base.div_ceil(2) * 2
}

/// Cells of an enclosed solve for a branch with `eta` periods: `c (1 + η)` with `c = 16`
/// (fast), `32` (default) or `64` (high), at least 32: the enclosed diagram's levels.
pub fn enclosed_cells(accuracy: Accuracy, eta: u32) -> usize {
    let c = accuracy.pick(ENCLOSED_TRACE_CELLS);
    (c * (1 + eta as usize)).max(32)
}

/// Cells `N` of the lifted-off traces of a non-uniform rod's branch `eta` (levels `N/4,
/// N/2, N`): [`enclosed_cells`] but at least `32(2+η)`, so that `N/4` resolves the profile.
pub fn nonuniform_cells(accuracy: Accuracy, eta: u32) -> usize {
    enclosed_cells(accuracy, eta).max(32 * (2 + eta as usize))
}

/// Cells of a single enclosed `solve` for a branch with `eta` periods: `c (1 + η)` with
/// `c = 16` (fast), `192` (default) or `256` (high). The Newton step is `O(N)`
/// ([`crate::enclosed::lifted`]), so one state affords the mesh the `≤ 1e-8` target needs with an
/// estimate that bounds the error: the figure-eight at `L̄ = 1.4` is estimated at 3.5e-9
/// relative at `N = 384` (1.25e-8 at 256, where the error against `N = 1024` is 3.9e-9). (The enclosed diagram
/// keeps [`enclosed_cells`]: its natural-parameter tracer stalls on the point contacts of
/// the figure-eight below `L̄ ≈ 1.3` at `N = 256`.)
pub fn enclosed_solve_cells(accuracy: Accuracy, eta: u32) -> usize {
    let c = accuracy.pick(ENCLOSED_SOLVE_CELLS);
    (c * (1 + eta as usize)).max(32)
}

/// Cells `N` of the finest level of an enclosed `solve` of branch `eta`. Uniform rods: the
/// fine mesh of the O(N) step ([`enclosed_solve_cells`]). Two-segment rods keep the diagram's
/// mesh ([`nonuniform_cells`]: observed order 1.0–1.4 there; the cascade started at
/// N/4 = 96 cells from the surface loop of branch 3 at `L̄ = 2.2` does not converge; sharp
/// profiles (Eq. (51), `γ = 200`) need the coarsest level of the cascade, `N/4`, to resolve
/// the transitions on the graded mesh).
pub fn enclosed_scene_cells(stiffness: &Stiffness, accuracy: Accuracy, eta: u32) -> usize {
    if stiffness.is_uniform() {
        enclosed_solve_cells(accuracy, eta)
    } else {
        nonuniform_cells(accuracy, eta)
    }
}

/// How much finer than the transitions' width the cells must be to resolve the bending of a
/// soft segment (Eq. (51)), a number of the scene: the loop's contact forces are of order
/// `D0/R²`, under which a segment of stiffness `D1` bends over lengths of order
/// `ℓ = R √(D1/D0)` (its bending length); the cells at the transitions are as wide as the
/// transition, `L/γ` with `L = 2πR` for a loop of one great circle's length
/// ([`profile_cells`]), and must also be no wider than `2ℓ/3`. The factor
/// `max(1, (2πR/γ)/(2ℓ/3)) = max(1, 3π/(γ √(D1/D0)))` grows continuously as the soft
/// segment softens or the transition widens, whatever the scene: 1.49 at
/// `D1/D0 = 0.001, γ = 200`, 1 at `D1/D0 = 0.1` (any `γ ≥ 30`); 1 for every other profile.
pub fn bending_factor(stiffness: &Stiffness) -> f64 {
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
pub fn bending_scaled(cells: usize, stiffness: &Stiffness) -> usize {
    ((cells as f64 * bending_factor(stiffness)).floor() as usize).max(cells)
}

/// Cells a stiffness profile needs to be resolved at all: for Eq. (51) on a uniform mesh
/// `γ` (one cell per transition width `L/γ`); on the graded mesh of
/// [`crate::MeshMap::for_profile`] the cells at the transitions are
/// `ρ_max/∫ρ` times finer than the mean, so `γ ∫ρ/ρ_max` cells give them the same width;
/// one per table point; none for a uniform rod (the fast-level rule of [`Accuracy::cells`]).
pub fn profile_cells(stiffness: &Stiffness) -> usize {
    match stiffness {
        Stiffness::Tanh { gamma, .. } => {
            let refinement = match crate::MeshMap::for_profile(stiffness) {
                crate::MeshMap::Graded {
                    centers,
                    sharpness,
                    amplitude,
                } => {
                    // ∫ρ = 1 + A π k/β (k bumps of ∫sech = π/β); ρ_max ≥ 1 + A.
                    let integral =
                        1.0 + amplitude * std::f64::consts::PI * centers.len() as f64 / sharpness;
                    (1.0 + amplitude) / integral
                }
                crate::MeshMap::Uniform => 1.0,
            };
            (gamma / refinement).ceil().min(4096.0) as usize
        }
        Stiffness::Table { s, .. } => s.len(),
        Stiffness::Uniform { .. } => 0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The tracing and reporting resolutions of a two-segment rod follow its contrast without
    /// a threshold: as `D1/D0` falls by 2 % steps from 0.9 to 1e-4 (for transitions from
    /// smooth to sharp) the counts never fall and never jump by more than the rounding to
    /// 4 or 8 cells plus 3 % (a contrast-independent cut would jump by half the count).
    #[test]
    fn resolutions_follow_the_contrast_without_a_threshold() {
        for gamma in [25.0, 60.0, 200.0, 300.0] {
            for accuracy in [Accuracy::Fast, Accuracy::Default, Accuracy::High] {
                let counts = |c: f64| {
                    let stiffness = Stiffness::Tanh {
                        d0: 1.0,
                        d1: c,
                        s0: 0.3,
                        s1: 0.8,
                        gamma,
                    };
                    let per_period = accuracy.pick(TRACE_CELLS);
                    (1..=3)
                        .map(|eta| {
                            (
                                trace_cells(accuracy, per_period, &stiffness, eta),
                                reporting_cells(accuracy, &stiffness, eta).0,
                            )
                        })
                        .collect::<Vec<_>>()
                };
                let mut c = 0.9;
                let mut prev = counts(c);
                while c > 1e-4 {
                    c *= 0.98;
                    let next = counts(c);
                    for ((t0, r0), (t1, r1)) in prev.iter().zip(&next) {
                        for (a, b, step) in [(t0, t1, 4), (r0, r1, 8)] {
                            assert!(
                                b >= a && b - a <= step + a.div_ceil(33),
                                "γ = {gamma}, {accuracy:?}, D1/D0 = {c}: {a} → {b} cells"
                            );
                        }
                    }
                    prev = next;
                }
            }
        }
    }
}
