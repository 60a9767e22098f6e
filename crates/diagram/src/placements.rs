//! Equilibria of one branch of a non-uniform rod from the exact loops of the uniform rod
//! (Sec. 4.3) placed at several offsets along it: where the soft segment sits on the loop
//! selects the state, so the starts are the exact loop of `η` periods shifted by
//! `k/8 · 1/(2η)` of the length (`κ_g²` has period `1/(2η)`).
//!
//! [`PlacedProfile::placements`] gives the placements at which the families of a two-segment rod
//! leave the uniform rod's circle of loops as `D1/D0` departs from 1: the critical points of
//! the energy of the uniform rod's exact loop laid on the scene's profile, as a function of
//! its placement.

use rodloop_solver::identify::identify_equilibrium;
use rodloop_solver::{
    Confinement, Equilibrium, Globalization, SolveOptions, SolverError, StartShape, Stiffness,
    SurfaceSolve,
};

/// The shift of start `k` (eighths of `1/(2η)`).
pub(crate) fn shift_of(eta: u32, k: u32) -> f64 {
    0.5 / f64::from(eta) * f64::from(k) / 8.0
}

/// Solve `model` from the exact loop of `eta` periods shifted by [`shift_of`]`(eta, k)`,
/// with energy minimisation where the start is far ([`Globalization::Auto`]).
pub(crate) fn solve_shifted<M: SurfaceSolve>(
    model: &M,
    eta: u32,
    k: u32,
    opts: &SolveOptions,
) -> Result<Equilibrium, SolverError> {
    let auto = SolveOptions {
        globalization: Globalization::Auto,
        ..opts.clone()
    };
    StartShape::Exact { eta }
        .shifted(model.lbar(), shift_of(eta, k))
        .and_then(|st| model.start_values(&st))
        .and_then(|z| model.solve(&z, &auto))
}

/// What a solve reached: whether it has `eta` periods, its stability index (tolerance
/// `tol`; `usize::MAX` when it cannot be computed) and its energy `E R/(π D0)`.
pub(crate) fn classify(eq: &Equilibrium, eta: u32, tol: f64) -> (bool, usize, f64) {
    let ok_eta = identify_equilibrium(eq)
        .map(|p| p.eta == eta)
        .unwrap_or(false);
    let idx = eq.model().index(&eq.state(), tol).unwrap_or(usize::MAX);
    (ok_eta, idx, eq.energy().total)
}

/// Samples per half period of `κ_g²` at which [`PlacedProfile::placements`] evaluates the energy
/// (a resolution: the critical points are refined between samples by a parabola).
const HALF_PERIOD_SAMPLES: usize = 512;

/// The profile side of [`PlacedProfile::placements`] for one branch: the stiffness sampled where
/// the placed loop's energy is summed, the same at every length (so that a search over many
/// lengths samples it once), folded onto one half period of `κ_g²`.
pub(crate) struct PlacedProfile<'a> {
    stiffness: &'a Stiffness,
    eta: u32,
    /// `D` at the `m = 2η ·` [`HALF_PERIOD_SAMPLES`] samples `j/m`, folded onto the
    /// [`HALF_PERIOD_SAMPLES`] residues `r = j mod` [`HALF_PERIOD_SAMPLES`] and averaged over
    /// the `2η` half periods: `κ_g²` takes the same value at every sample of a residue, so
    /// `Σ_j D_j κ²_{j+k} / m = Σ_r D̄_r κ²_{r+k} / ` [`HALF_PERIOD_SAMPLES`].
    folded: Vec<f64>,
}

impl<'a> PlacedProfile<'a> {
    /// The samples of `stiffness` for branch `eta`.
    pub(crate) fn new(stiffness: &'a Stiffness, eta: u32) -> Result<Self, SolverError> {
        let profile = stiffness.validate()?;
        let halves = 2 * eta.max(1) as usize;
        let m = halves * HALF_PERIOD_SAMPLES;
        let mut folded = vec![0.0; HALF_PERIOD_SAMPLES];
        for j in 0..m {
            folded[j % HALF_PERIOD_SAMPLES] += profile.eval(j as f64 / m as f64).d;
        }
        for v in &mut folded {
            *v /= halves as f64;
        }
        Ok(Self {
            stiffness,
            eta,
            folded,
        })
    }

    /// The placements (origin shifts, fractions of the length in `[0, 1/(2η))`, as
    /// [`StartShape::shifted`] takes them) of the exact loop of branch `eta` of the uniform rod
    /// at `lbar` from which the families of the profile `stiffness` leave the uniform rod's
    /// circle of loops.
    ///
    /// At `D1/D0 = 1` every placement of the exact loop is an equilibrium (the arclength shift
    /// is a symmetry). For `D1/D0 = 1 − ε` the circle breaks (Lyapunov–Schmidt reduction onto
    /// the shift) into the critical points of the energy of the placed loop to first order in
    /// `ε`, `f(φ) = ½ ∫ D(σ) κ(σ + φ)² dσ` (paper Eq. (2) with the profile of Eq. (51); on the
    /// sphere `κ² = κ_g² + 1/R²`, and the constant part does not depend on `φ`): its maxima and
    /// minima over the half period `1/(2η)` of `κ_g²` (a shift by `1/(2η)` is the reflection
    /// `κ_g → −κ_g`). They follow from the profile's features (for Eq. (51), the soft segment's
    /// centre at an extreme or a zero of `κ_g`, and any asymmetric placements its length
    /// selects) and from the branch's period count. Where `f` is constant to rounding (a soft
    /// segment of a whole number of half periods: first order selects nothing) only the
    /// mirror-symmetric placements remain.
    pub(crate) fn placements(&self, lbar: f64) -> Result<Vec<f64>, SolverError> {
        let (stiffness, eta) = (self.stiffness, self.eta);
        let kg = StartShape::Exact { eta }.interpolant(lbar)?;
        let half = HALF_PERIOD_SAMPLES;
        let m = 2 * eta.max(1) as usize * half;
        // One half period of `κ_g²` (period `1/(2η)`: `half` samples of spacing `1/m`).
        let sigmas: Vec<f64> = (0..half).map(|j| j as f64 / m as f64).collect();
        let k2: Vec<f64> = kg.eval_many(&sigmas).iter().map(|v| v.powi(2)).collect();
        let f = placed_energies(&self.folded, &k2, half);
        let mut out: Vec<f64> = critical_points(&f)
            .into_iter()
            .map(|x| x / m as f64)
            .collect();
        // The mirror-symmetric placements are critical at every order (the energy is even
        // about them): the soft segment's centre `c` at the extreme of `κ_g` at the loop's
        // origin (shift `−c`) and at the zero a quarter period on (`1/(4η) − c`). They are the
        // only placements where a soft segment of a whole number of half periods makes `f`
        // constant.
        if let Stiffness::Tanh { s0, s1, .. } = stiffness {
            let hp = 0.5 / f64::from(eta.max(1));
            let c = 0.5 * (s0 + s1);
            for sh in [-c, 0.5 * hp - c] {
                let sh = sh.rem_euclid(hp);
                let dist = |o: f64| {
                    let d = (o - sh).rem_euclid(hp);
                    d.min(hp - d)
                };
                if out.iter().all(|&o| dist(o) > 1e-6 * hp) {
                    out.push(sh);
                }
            }
        }
        out.sort_by(f64::total_cmp);
        Ok(out)
    }
}

/// Lanes of [`placed_energies`]: shifts summed side by side (independent sums, so that they
/// do not wait on each other's additions).
const LANES: usize = 32;

/// `f_k = Σ_j d_j κ²_{(j+k) mod m} / m` for the shifts `k = 0..half` (`m` = the samples of
/// `d` and `k2`), each summed in the order of `j` from `0`. [`LANES`] shifts are summed side
/// by side over one copy of `k2` extended by its first `half + LANES` samples (no index
/// wraps); every sum sees the same additions in the same order as one summed alone.
fn placed_energies(d: &[f64], k2: &[f64], half: usize) -> Vec<f64> {
    let m = d.len();
    let ext: Vec<f64> = k2
        .iter()
        .chain(k2.iter().cycle().take(half + LANES))
        .copied()
        .collect();
    let mut f = Vec::with_capacity(half);
    for k0 in (0..half).step_by(LANES) {
        let mut acc = [0.0f64; LANES];
        for (j, dj) in d.iter().enumerate() {
            let w = &ext[j + k0..j + k0 + LANES];
            for (a, x) in acc.iter_mut().zip(w) {
                *a += dj * x;
            }
        }
        f.extend(acc.iter().take(half - k0).map(|a| a / m as f64));
    }
    f
}

/// The maxima and minima of the periodic samples `f` (positions in samples, refined by the
/// parabola through each extreme and its neighbours); empty where `f` varies by no more
/// than rounding.
fn critical_points(f: &[f64]) -> Vec<f64> {
    let n = f.len();
    let (lo, hi) = f
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let noise = 1e-11 * lo.abs().max(hi.abs());
    if n < 3 || hi - lo <= noise {
        return Vec::new();
    }
    // Differences below rounding count as zero; a plateau's extreme is its last sample.
    let sign = |d: f64| {
        if d > noise {
            1
        } else if d < -noise {
            -1
        } else {
            0
        }
    };
    let mut out = Vec::new();
    let mut last = (0..n)
        .rev()
        .map(|k| sign(f[k] - f[(k + n - 1) % n]))
        .find(|&s| s != 0)
        .unwrap_or(0);
    for k in 0..n {
        let next = sign(f[(k + 1) % n] - f[k]);
        if next != 0 {
            if next != last {
                let (a, b, c) = (f[(k + n - 1) % n], f[k], f[(k + 1) % n]);
                let den = a - 2.0 * b + c;
                let off = if den.abs() > 0.0 {
                    (0.5 * (a - c) / den).clamp(-0.5, 0.5)
                } else {
                    0.0
                };
                out.push((k as f64 + off).rem_euclid(n as f64));
            }
            last = next;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `f = cos(2πk/n)` has one maximum (at 0) and one minimum (at n/2); a sampled
    /// `cos(2π(k − 0.3)/n) + 0.5 cos(6π(k − 0.3)/n)` has its extremes where the derivative
    /// vanishes, found to the parabola's accuracy.
    #[test]
    fn critical_points_of_periodic_samples() {
        let n = 64;
        let c: Vec<f64> = (0..n)
            .map(|k| (2.0 * std::f64::consts::PI * k as f64 / n as f64).cos())
            .collect();
        let mut p = critical_points(&c);
        p.sort_by(f64::total_cmp);
        assert_eq!(p.len(), 2, "{p:?}");
        assert!(p[0].abs() < 1e-12 && (p[1] - 32.0).abs() < 1e-12, "{p:?}");
        let w = |x: f64| 2.0 * std::f64::consts::PI * (x - 0.3) / n as f64;
        let g: Vec<f64> = (0..n)
            .map(|k| w(k as f64).cos() + 0.5 * (3.0 * w(k as f64)).cos())
            .collect();
        let p = critical_points(&g);
        // g' ∝ −sin w − 1.5 sin 3w = 0: sin w = 0 or 1 + 1.5 (3 − 4 sin² w) = 0
        // (sin² w = 5.5/6, four roots), six extremes in all.
        assert_eq!(p.len(), 6, "{p:?}");
        for x in p {
            let d = w(x).sin() + 1.5 * (3.0 * w(x)).sin();
            assert!(d.abs() < 0.02, "derivative {d} at {x}");
        }
        assert!(critical_points(&vec![1.0; n]).is_empty());
    }

    /// The lanes of `placed_energies` give each shift's sum bit for bit as the sum over `j`
    /// taken alone with the index wrapped modulo `m`, including a count of shifts that is
    /// not a multiple of the lanes and more shifts than samples.
    #[test]
    fn placed_energies_are_the_wrapped_sums_in_order() {
        let mut x = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 11) as f64 / (1u64 << 53) as f64 - 0.3
        };
        for (m, half) in [(96, 48), (100, 13), (7, 20), (2048, 512)] {
            let d: Vec<f64> = (0..m).map(|_| next()).collect();
            let k2: Vec<f64> = (0..m).map(|_| next() * 1e3).collect();
            let f = placed_energies(&d, &k2, half);
            assert_eq!(f.len(), half);
            for (k, fk) in f.iter().enumerate() {
                let want = (0..m).fold(0.0, |acc, j| acc + d[j] * k2[(j + k) % m]) / m as f64;
                assert_eq!(fk.to_bits(), want.to_bits(), "m {m} half {half} k {k}");
            }
        }
    }

    /// The folded sums of [`PlacedProfile`] equal the placed energy summed over all
    /// `m = 2η ·` [`HALF_PERIOD_SAMPLES`] samples of the loop (`κ_g` evaluated at each, not
    /// tiled from one half period) to rounding: `κ_g²` of the exact loop has period `1/(2η)`.
    #[test]
    fn folded_placed_energy_equals_the_full_sum() {
        let st = Stiffness::Tanh {
            d0: 1.0,
            d1: 0.07,
            s0: 0.21,
            s1: 0.68,
            gamma: 140.0,
        };
        let profile = st.validate().unwrap();
        for (eta, lbar) in [(1u32, 1.3), (2, 1.9), (3, 2.4), (4, 3.3)] {
            let placed = PlacedProfile::new(&st, eta).unwrap();
            let half = HALF_PERIOD_SAMPLES;
            let m = 2 * eta as usize * half;
            let kg = StartShape::Exact { eta }.interpolant(lbar).unwrap();
            let sig: Vec<f64> = (0..half).map(|j| j as f64 / m as f64).collect();
            let k2: Vec<f64> = kg.eval_many(&sig).iter().map(|v| v * v).collect();
            let folded = placed_energies(&placed.folded, &k2, half);
            let all: Vec<f64> = (0..m).map(|j| j as f64 / m as f64).collect();
            let k2_all: Vec<f64> = kg.eval_many(&all).iter().map(|v| v * v).collect();
            let d: Vec<f64> = all.iter().map(|&s| profile.eval(s).d).collect();
            let scale = folded.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            for (k, fk) in folded.iter().enumerate() {
                let want = (0..m).map(|j| d[j] * k2_all[(j + k) % m]).sum::<f64>() / m as f64;
                assert!(
                    (fk - want).abs() <= 1e-12 * scale,
                    "eta {eta} k {k}: folded {fk} full {want}"
                );
            }
        }
    }

    /// The placements of a two-segment profile are critical points of the placed uniform
    /// loop's energy, computed here independently by central differences of the energy of
    /// the shifted start on a model with the scene's profile (the energy `E` of a start is
    /// its `½ ∫ D κ²`); the mirror symmetry of the profile makes the placement with the soft
    /// segment's centre at a zero or extreme of `κ_g` critical, so there are at least two.
    #[test]
    fn uniform_placements_are_critical_points_of_the_placed_energy() {
        let st = Stiffness::Tanh {
            d0: 1.0,
            d1: 0.2,
            s0: 0.3,
            s1: 0.62,
            gamma: 60.0,
        };
        let profile = st.validate().unwrap();
        for (eta, lbar) in [(1u32, 1.4), (2, 1.7), (3, 2.6)] {
            let ps = PlacedProfile::new(&st, eta)
                .and_then(|p| p.placements(lbar))
                .unwrap();
            assert!(ps.len() >= 2, "eta {eta}: {ps:?}");
            // The symmetric placements are among the critical points found from `f`: no
            // more than the critical points of `f` are returned for this (non-degenerate)
            // profile, and the count of extremes of a periodic function is even.
            assert_eq!(ps.len() % 2, 0, "eta {eta}: {ps:?}");
            let kg = StartShape::Exact { eta }.interpolant(lbar).unwrap();
            // f(φ) by the trapezoidal rule on 20000 points (independent of the samples).
            let f = |phi: f64| {
                let n = 20_000;
                (0..n)
                    .map(|j| {
                        let s = j as f64 / n as f64;
                        profile.eval(s).d * kg.eval(s + phi).powi(2)
                    })
                    .sum::<f64>()
                    / n as f64
            };
            let h = 1e-4;
            let scale = (f(0.0) - f(0.25 / f64::from(eta))).abs().max(1e-12);
            for &p in &ps {
                assert!((0.0..0.5 / f64::from(eta)).contains(&p), "{p}");
                let d = (f(p + h) - f(p - h)) / (2.0 * h);
                // Relative to the variation over a quarter period per unit shift.
                assert!(
                    d.abs() < 2e-3 * scale * f64::from(eta),
                    "eta {eta} placement {p}: f' = {d:e} (scale {scale:e})"
                );
            }
        }
    }
}
