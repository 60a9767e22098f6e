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

    /// Unnormalised `∫₀^σ ρ` (the code evaluates it in batches, [`MeshMap::integral_with`]).
    #[cfg(test)]
    fn integral(&self, sigma: f64) -> f64 {
        self.integral_with(sigma, &self.images())
    }

    /// The periodic images of the bumps with their `gd` at `σ = 0`: `(σ_k + j, gd(−β(σ_k + j)))`
    /// (constants of [`MeshMap::integral`], computed once per batch of evaluations).
    fn images(&self) -> Vec<(f64, f64)> {
        match self {
            MeshMap::Uniform => Vec::new(),
            MeshMap::Graded {
                centers,
                sharpness: b,
                ..
            } => centers
                .iter()
                .flat_map(|&ck| {
                    (-2..=2).map(move |j| {
                        let shift = ck + j as f64;
                        (shift, gd(b * (-shift)))
                    })
                })
                .collect(),
        }
    }

    /// [`MeshMap::integral`] with the constants of [`MeshMap::images`].
    fn integral_with(&self, sigma: f64, images: &[(f64, f64)]) -> f64 {
        match self {
            MeshMap::Uniform => sigma,
            MeshMap::Graded {
                sharpness: b,
                amplitude: a,
                ..
            } => {
                let mut acc = sigma;
                for &(shift, at_zero) in images {
                    acc += a / b * (gd(b * (sigma - shift)) - at_zero);
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
        let images = self.images();
        let z = self.integral_with(1.0, &images);
        self.u_with(sigma, z, &images)
    }

    /// [`MeshMap::u_of_sigma`] at every one of `sigmas` (the map's constants computed once).
    pub fn u_of_sigmas(&self, sigmas: impl IntoIterator<Item = f64>) -> Vec<f64> {
        if self.is_uniform() {
            return sigmas.into_iter().collect();
        }
        let images = self.images();
        let z = self.integral_with(1.0, &images);
        sigmas
            .into_iter()
            .map(|s| self.u_with(s, z, &images))
            .collect()
    }

    fn u_with(&self, sigma: f64, z: f64, images: &[(f64, f64)]) -> f64 {
        let k = sigma.floor();
        k + self.integral_with(sigma - k, images) / z
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
        self.sigma_of_u_with(u, guess, &self.images())
    }

    /// [`MeshMap::sigma_of_u_near`] with the constants of [`MeshMap::images`].
    fn sigma_of_u_with(&self, u: f64, guess: Option<f64>, images: &[(f64, f64)]) -> f64 {
        let k = u.floor();
        if u == k {
            return u;
        }
        let total = self.integral_with(1.0, images);
        let target = (u - k) * total;
        let (mut lo, mut hi) = (0.0, 1.0);
        let mut s = guess.filter(|g| *g > 0.0 && *g < 1.0).unwrap_or(u - k);
        let mut f = self.integral_with(s, images) - target;
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
            let mut fn_ = self.integral_with(next, images) - target;
            if fn_.abs() > 0.5 * f.abs() {
                next = 0.5 * (lo + hi);
                fn_ = self.integral_with(next, images) - target;
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
    ///
    /// The boundaries depend on the map and `N` only, and every model of a scene at a
    /// resolution (each continuation step, re-solve and verification) asks for the same
    /// ones: the last few are kept per thread and handed back as computed.
    pub fn bounds(&self, cells: usize) -> Result<Vec<f64>, SolverError> {
        if self.is_uniform() {
            return self.compute_bounds(cells);
        }
        thread_local! {
            static RECENT: std::cell::RefCell<Vec<(MeshMap, usize, Vec<f64>)>> =
                const { std::cell::RefCell::new(Vec::new()) };
        }
        let hit = RECENT.with(|r| {
            r.borrow()
                .iter()
                .find(|(m, n, _)| *n == cells && m == self)
                .map(|(_, _, b)| b.clone())
        });
        if let Some(b) = hit {
            return Ok(b);
        }
        let b = self.compute_bounds(cells)?;
        RECENT.with(|r| {
            let mut r = r.borrow_mut();
            if r.len() >= RECENT_MESHES {
                r.remove(0);
            }
            r.push((self.clone(), cells, b.clone()));
        });
        Ok(b)
    }

    fn compute_bounds(&self, cells: usize) -> Result<Vec<f64>, SolverError> {
        let images = self.images();
        let total = self.integral_with(1.0, &images);
        let mut b = Vec::with_capacity(cells + 1);
        let mut prev = 0.0f64;
        for i in 0..=cells {
            let v = if i == cells {
                1.0
            } else if i == 0 {
                0.0
            } else if self.is_uniform() {
                self.sigma_of_u_near(i as f64 / cells as f64, None)
            } else {
                // Guess: one grid step of u at the local density.
                let guess = prev + total / (cells as f64 * self.density(prev));
                self.sigma_of_u_with(i as f64 / cells as f64, Some(guess), &images)
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

/// Meshes [`MeshMap::bounds`] keeps per thread (a diagram uses one map at a few resolutions:
/// tracing, half, and the refinements of its state files, for a few branches).
const RECENT_MESHES: usize = 16;

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

    /// The boundaries kept per thread are those of the map and resolution asked for: with
    /// two maps and three resolutions asked in turn (more than are kept), every answer equals
    /// a fresh computation bit for bit, and the batched `u(σ)` equals the pointwise one.
    #[test]
    fn kept_bounds_are_those_of_the_map_and_resolution_asked() {
        let other = MeshMap::for_profile(&Stiffness::Tanh {
            d0: 1.0,
            d1: 0.1,
            s0: 0.2,
            s1: 0.7,
            gamma: 120.0,
        });
        let maps = [graded(), other];
        for round in 0..2 {
            for cells in [40, 80, 160] {
                for (k, m) in maps.iter().enumerate() {
                    let kept = m.bounds(cells + round * (RECENT_MESHES + k)).unwrap();
                    let fresh = m
                        .compute_bounds(cells + round * (RECENT_MESHES + k))
                        .unwrap();
                    assert_eq!(kept, fresh, "map {k}, {cells} cells, round {round}");
                    let again = m.bounds(cells + round * (RECENT_MESHES + k)).unwrap();
                    assert_eq!(again, fresh);
                }
            }
        }
        let m = graded();
        let sigmas: Vec<f64> = (0..37).map(|j| j as f64 / 37.0 + 0.003).collect();
        let batched = m.u_of_sigmas(sigmas.iter().copied());
        for (s, u) in sigmas.iter().zip(batched) {
            assert_eq!(u, m.u_of_sigma(*s));
        }
        assert_ne!(maps[0].bounds(40).unwrap(), maps[1].bounds(40).unwrap());
    }
}
