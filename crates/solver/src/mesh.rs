//! Cell meshes along the loop: uniform, or graded where the stiffness changes.
//!
//! A mesh is the image of the uniform grid `u_i = i/N` under a smooth, increasing, periodic
//! map `σ(u)` (`σ = s/L`). Because the map does not depend on `N`, refining the mesh keeps
//! the scheme's order (fourth in `1/N`), and every quantity sampled on the mesh is periodic
//! and smooth in `u`, so trigonometric interpolation in `u` resamples it spectrally.
//!
//! The graded map spends cells where `D(s)` changes quickly. Its density (cells per unit
//! `σ`, up to a constant) is
//!
//! ```text
//! ρ(σ) = 1 + A Σ_k Σ_j sech(β (σ − σ_k − j)),   j = −2..2 (periodic images),
//! ```
//!
//! with one bump per stiffness transition `σ_k` (for Eq. (51): `s0*/L` and `s1*/L`), and
//! `u(σ) = ∫₀^σ ρ / ∫₀¹ ρ` in closed form through the Gudermannian
//! `gd(x) = 2 atan(tanh(x/2)) = ∫₀ˣ sech`. The inverse `σ(u)` is found by safeguarded Newton.

use crate::stiffness::Stiffness;
use crate::SolverError;

/// The map from the uniform grid to the mesh (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub enum MeshMap {
    /// `σ = u`.
    Uniform,
    /// Density bumps of height `amplitude` and width `1/sharpness` at `centers`.
    Graded {
        /// Transition points `σ_k ∈ [0, 1)`.
        centers: Vec<f64>,
        /// `β`.
        sharpness: f64,
        /// `A`.
        amplitude: f64,
    },
}

fn gd(x: f64) -> f64 {
    2.0 * (0.5 * x).tanh().atan()
}

impl MeshMap {
    /// The mesh rodloop uses for a stiffness profile: uniform unless the profile has sharp
    /// transitions (Eq. (51) with `γ > 20`), then bumps of the transitions' width `1/γ` at
    /// `s0*/L` and `s1*/L` whose cells are `1 + γ/40` times finer than elsewhere. These
    /// constants were chosen with `rodloop converge` over bump widths `0.5/γ … 10/γ` and
    /// refinements `1 + γ/10 … 1 + γ/160` at `D1/D0 = 0.5, 0.1, 0.001`.
    pub fn for_profile(stiffness: &Stiffness) -> Self {
        match stiffness {
            Stiffness::Tanh {
                s0,
                s1,
                gamma,
                d0,
                d1,
                ..
            } if *gamma > 20.0 && (d0 - d1).abs() > 1e-12 * d0.abs() => MeshMap::Graded {
                centers: vec![*s0, *s1],
                sharpness: *gamma,
                amplitude: gamma / 40.0,
            },
            _ => MeshMap::Uniform,
        }
    }

    /// Whether the map is the identity.
    pub fn is_uniform(&self) -> bool {
        matches!(self, MeshMap::Uniform)
    }

    /// Unnormalised `∫₀^σ ρ`.
    fn integral(&self, sigma: f64) -> f64 {
        match self {
            MeshMap::Uniform => sigma,
            MeshMap::Graded {
                centers,
                sharpness: b,
                amplitude: a,
            } => {
                let mut acc = sigma;
                for &ck in centers {
                    for j in -2..=2 {
                        let shift = ck + j as f64;
                        acc += a / b * (gd(b * (sigma - shift)) - gd(b * (-shift)));
                    }
                }
                acc
            }
        }
    }

    /// Density `ρ(σ)` (unnormalised).
    fn density(&self, sigma: f64) -> f64 {
        match self {
            MeshMap::Uniform => 1.0,
            MeshMap::Graded {
                centers,
                sharpness: b,
                amplitude: a,
            } => {
                let mut acc = 1.0;
                for &ck in centers {
                    for j in -2..=2 {
                        acc += a / (b * (sigma - ck - j as f64)).cosh();
                    }
                }
                acc
            }
        }
    }

    /// `u(σ)` for `σ ∈ [0, 1]` (extended periodically: `u(σ + 1) = u(σ) + 1`).
    pub fn u_of_sigma(&self, sigma: f64) -> f64 {
        if self.is_uniform() {
            return sigma;
        }
        let k = sigma.floor();
        let z = self.integral(1.0);
        k + self.integral(sigma - k) / z
    }

    /// `σ(u)`, the inverse of [`MeshMap::u_of_sigma`].
    pub fn sigma_of_u(&self, u: f64) -> f64 {
        self.sigma_of_u_near(u, None)
    }

    /// [`MeshMap::sigma_of_u`] with a first guess for `σ − floor(u)` (Newton then needs two
    /// or three steps when the guess comes from the neighbouring grid point).
    fn sigma_of_u_near(&self, u: f64, guess: Option<f64>) -> f64 {
        if self.is_uniform() {
            return u;
        }
        let k = u.floor();
        if u == k {
            return u;
        }
        let total = self.integral(1.0);
        let target = (u - k) * total;
        let (mut lo, mut hi) = (0.0, 1.0);
        let mut s = guess.filter(|g| *g > 0.0 && *g < 1.0).unwrap_or(u - k);
        let mut f = self.integral(s) - target;
        // Newton's method, safeguarded: a step that leaves the bracket or does not halve
        // |f| is replaced by bisection.
        for _ in 0..200 {
            if f == 0.0 || hi - lo <= 4.0 * f64::EPSILON {
                break;
            }
            if f > 0.0 {
                hi = s;
            } else {
                lo = s;
            }
            let mut next = s - f / self.density(s);
            if !(next > lo && next < hi) {
                next = 0.5 * (lo + hi);
            }
            let mut fn_ = self.integral(next) - target;
            if fn_.abs() > 0.5 * f.abs() {
                next = 0.5 * (lo + hi);
                fn_ = self.integral(next) - target;
            }
            let done = (next - s).abs() <= 2.0 * f64::EPSILON * next.abs().max(1e-3);
            s = next;
            f = fn_;
            if done {
                break;
            }
        }
        k + s
    }

    /// Cell boundaries `σ_0 = 0 < σ_1 < … < σ_N = 1` of an `N`-cell mesh.
    pub fn bounds(&self, cells: usize) -> Result<Vec<f64>, SolverError> {
        let total = self.integral(1.0);
        let mut b = Vec::with_capacity(cells + 1);
        let mut prev = 0.0f64;
        for i in 0..=cells {
            let v = if i == cells {
                1.0
            } else if i == 0 {
                0.0
            } else {
                // Guess: one grid step of u at the local density.
                let guess = prev + total / (cells as f64 * self.density(prev));
                self.sigma_of_u_near(i as f64 / cells as f64, Some(guess))
            };
            b.push(v);
            prev = v;
        }
        if b.windows(2).any(|w| w[1] <= w[0] || w[1].is_nan()) {
            return Err(SolverError::InvalidInput(format!(
                "mesh of {cells} cells is degenerate (a cell has no length)"
            )));
        }
        Ok(b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn graded() -> MeshMap {
        MeshMap::for_profile(&Stiffness::Tanh {
            d0: 1.0,
            d1: 0.5,
            s0: 0.3,
            s1: 0.8,
            gamma: 200.0,
        })
    }

    #[test]
    fn inverse_map_round_trips() {
        let m = graded();
        for i in 0..=200 {
            let u = i as f64 / 200.0;
            let s = m.sigma_of_u(u);
            assert!((m.u_of_sigma(s) - u).abs() < 1e-14, "u = {u}");
        }
        assert_eq!(m.sigma_of_u(0.0), 0.0);
        assert!((m.sigma_of_u(1.0) - 1.0).abs() < 1e-15);
    }

    #[test]
    fn density_is_the_derivative_of_the_map() {
        let m = graded();
        let z = m.integral(1.0);
        for &s in &[0.05, 0.29, 0.3, 0.31, 0.55, 0.8, 0.97] {
            let h = 1e-6;
            let fd = (m.u_of_sigma(s + h) - m.u_of_sigma(s - h)) / (2.0 * h);
            assert!((fd - m.density(s) / z).abs() < 1e-6 * fd, "σ = {s}");
        }
    }

    #[test]
    fn graded_cells_are_finer_at_the_transitions() {
        let m = graded();
        let b = m.bounds(200).unwrap();
        let width = |sigma: f64| {
            let i = b.iter().position(|&x| x > sigma).unwrap();
            b[i] - b[i - 1]
        };
        let ratio = width(0.55) / width(0.3);
        // The density ratio between the middle of a segment and a transition is 1 + A
        // (tails of the bumps aside): A = γ/40 = 5.
        assert!((ratio - 6.0).abs() < 0.2, "ratio {ratio}");
        assert!(MeshMap::Uniform.bounds(8).unwrap()[3] == 3.0 / 8.0);
    }
}
