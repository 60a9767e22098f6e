//! Exact equilibria of homogeneous rod loops lying on a sphere (paper Sec. 4.3, App. B).
//!
//! Units: sphere radius `R = 1`, bending stiffness `D = 1`. Lengths are in units of `R`,
//! energies are reported as `E R/(πD)`, forces as `F R²/D`, the contact force as `λ R³/D`.
//!
//! The geodesic curvature of every equilibrium is, Eq. (35) with the paper's sign choice,
//! `κ_g(s) = −2ck cn(cs, k)`. Two families exist:
//!
//! * [`Family::Wave`], `0 < k < 1`: `κ_g` changes sign; one period of `κ_g` is `4K(k)/c`.
//!   These are the paper's branches (saddle, figure-eight, orbit-like loops).
//! * [`Family::Orbit`], `k > 1` (reciprocal-modulus continuation, DLMF 22.17):
//!   `κ_g = −2c₁ dn(c₁s, k₁)` with `k₁ = 1/k`, `c₁ = ck`; `κ_g` keeps one sign and one period
//!   is `2K(k₁)/c₁`. These loops bifurcate from multiply covered small circles.
//!
//! For a loop with `η` periods of `κ_g` the period condition, Eq. (49), fixes `c`, and the
//! remaining closure condition is the azimuth condition of Eq. (50), `φ(L) = 2πp`, with `φ`
//! from Eq. (48). The azimuth is measured about the conserved moment, Eq. (42); when the
//! loop passes over a pole of that axis (at `cR = 1`) the integer `p` jumps (by `2η` for the
//! wave family, whose loop passes both poles once per period, and by `η` for the orbit family,
//! which passes one pole per period). The rotation of the Darboux frame after one turn, the
//! holonomy, is continuous, and so is `p_cont = p − jη·H(c²R² − 1)` (`j = 2` or `1`). Branches
//! are therefore traced with the continuous closure equation `p_cont = q`, `q` an integer that
//! is constant along a branch; the paper's branch `η` has `q = −(η + 1)`.
//!
//! Sign note: integrating Eq. (47) gives Eq. (48) with the opposite overall sign; the two
//! differ by a mirror reflection (`φ → −φ`, `p → −p`). We follow Eq. (48) so that the reported
//! `p` equals the paper's (Figs. 6 and 11, Eq. (B.4)).

use std::f64::consts::PI;

use rodloop_special::jacobi;

use crate::ExactError;

/// Which solution family of Eq. (35): `k < 1` (cn, sign-changing `κ_g`) or `k > 1` (dn).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Family {
    /// `0 < k < 1`: wave-like loops, the paper's branches.
    Wave,
    /// `k > 1`: orbit-like loops around one pole of the moment axis.
    Orbit,
}

impl Family {
    /// Jump of `p` (in units of `η`) when `cR` crosses 1: number of pole passages per period.
    pub fn pole_passages(self) -> i32 {
        match self {
            Family::Wave => 2,
            Family::Orbit => 1,
        }
    }
}

/// Largest elliptic parameter searched (`m = k²` for waves, `m = 1/k²` for orbits).
///
/// Beyond it `1 − m` is resolved to fewer than ten digits in double precision, so a closure
/// residual of 1e-10 cannot be guaranteed; loops with `k′ = sqrt(1−m) < 1e-3` are very
/// tightly wound (energies above ~15) and are not reported.
pub const M_MAX: f64 = 1.0 - 1e-6;

/// Complete elliptic integrals `K(m)`, `E(m)` (parameter convention).
fn complete_ke(m: f64) -> Result<(f64, f64), ExactError> {
    let k = ellip::ellipk(m).map_err(|e| ExactError::Special(e.to_string()))?;
    let e = ellip::ellipe(m).map_err(|e| ExactError::Special(e.to_string()))?;
    Ok((k, e))
}

/// Heuman's lambda function `Λ₀(φ|m)` (A&S 17.4.39), odd in `φ`.
fn heuman_lambda(phi: f64, m: f64) -> Result<f64, ExactError> {
    let v = ellip::heuman_lambda(phi.abs(), m).map_err(|e| ExactError::Special(e.to_string()))?;
    Ok(v.copysign(phi))
}

/// Value of the closure function at one parameter `m`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Closure {
    /// `c R`, from the period condition Eq. (49) (waves: `c = 4ηK(k)/L`).
    pub c: f64,
    /// Modulus `k` (`k > 1` for orbits).
    pub k: f64,
    /// `φ(L)/(2π)` from Eq. (48): the paper's `p` when the loop is closed.
    pub p_raw: f64,
    /// Continuous winding `p_raw − jη H(c²R² − 1)`.
    pub p_cont: f64,
}

/// Evaluate the closure of a loop with `eta` periods of `κ_g` and length `lbar` at parameter `m`
/// (`m = k²` for [`Family::Wave`], `m = 1/k²` for [`Family::Orbit`]); Eqs. (48)–(50).
pub fn closure(family: Family, eta: u32, lbar: f64, m: f64) -> Result<Closure, ExactError> {
    // m = 0 is the great-circle limit of the wave family (k = 0), where the closure is finite.
    let m_ok = match family {
        Family::Wave => (0.0..1.0).contains(&m),
        Family::Orbit => m > 0.0 && m < 1.0,
    };
    if !m_ok || lbar.is_nan() || lbar <= 0.0 || eta == 0 {
        return Err(ExactError::InvalidParameter(format!(
            "closure needs 0 <= m < 1 (0 < m for orbits), lbar > 0, eta >= 1 (got m = {m}, lbar = {lbar}, eta = {eta})"
        )));
    }
    let eta_f = f64::from(eta);
    let len = 2.0 * PI * lbar;
    let (kk, _) = complete_ke(m)?;
    // Φ = φ(L) of Eq. (48) contains (a+1)/(a−1)·Π(n|m) with n → −∞ as a = c²R² → 1. With
    // A&S 17.7.17 and the complete case of A&S 17.7.14 (Heuman's Λ₀) this product equals
    //   smooth part + sgn(a−1)·π√a/M̂          (waves; M̂ from Eq. (42)),
    // where the smooth part is (a+1)δK/M̂² − (π√a/M̂)Λ₀(asin(δ/M̂)|m), δ = a − 1. The sgn term is
    // exactly the jump of p at the pole passage, so p_cont = p_smooth − η needs no case split.
    let (c, k, p_smooth, p_cont_offset) = match family {
        Family::Wave => {
            let k = m.sqrt();
            let c = 4.0 * eta_f * kk / len;
            let a = c * c;
            let delta = a - 1.0;
            let mh = (delta * delta + 4.0 * m * a).sqrt();
            let lam = heuman_lambda((delta / mh).asin(), m)?;
            let product = (a + 1.0) * delta * kk / (mh * mh) - PI * c / mh * lam;
            // Eq. (48) over η periods: am(cs) advances by 2πη, Π by 4ηΠ(n|m).
            let phi = -(mh / (2.0 * c)) * eta_f * (4.0 * kk - 4.0 * product);
            (c, k, phi / (2.0 * PI), eta_f)
        }
        Family::Orbit => {
            // κ_g = −2c₁ dn(c₁ s, k₁), k₁² = m; one period is 2K(k₁)/c₁; am(c₁s, k₁) advances by π.
            let k1 = m.sqrt();
            let c1 = 2.0 * eta_f * kk / len;
            let k = 1.0 / k1;
            let c = c1 * k1;
            let a = c * c;
            let delta = a - 1.0;
            let mh = (delta * delta + 4.0 * c1 * c1).sqrt();
            // (a+1)/δ · Π(−4a/δ² | k₁²) = δK/(a+1) + sgn(δ)·π√a/(M̂k₁)·(1 − Λ₀(asin(|δ|/(a+1))|k₁²)).
            let lam = heuman_lambda((delta / (a + 1.0)).asin(), m)?;
            let product = delta * kk / (a + 1.0) - PI * c / (mh * k1) * lam;
            let phi = -eta_f * ((mh / 2.0) * (2.0 * kk / c1) - mh / (2.0 * c1) * 2.0 * product);
            (c, k, phi / (2.0 * PI), 0.5 * eta_f)
        }
    };
    let p_cont = p_smooth - p_cont_offset;
    let jump = if c * c > 1.0 {
        f64::from(family.pole_passages()) * eta_f
    } else {
        0.0
    };
    let p_raw = p_cont + jump;
    if !p_cont.is_finite() {
        return Err(ExactError::Special(format!(
            "closure is not finite at m = {m}, lbar = {lbar}, eta = {eta}"
        )));
    }
    Ok(Closure {
        c,
        k,
        p_raw,
        p_cont,
    })
}

/// Solve `p_cont(m) = q` for `m` in `[lo, hi]` (a bracket with a sign change) by Brent's
/// method on the closure, to full double precision.
pub fn solve_closure_bracket(
    family: Family,
    eta: u32,
    lbar: f64,
    q: i32,
    lo: f64,
    hi: f64,
) -> Result<f64, ExactError> {
    let f = |m: f64| closure(family, eta, lbar, m).map(|c| c.p_cont - f64::from(q));
    crate::roots::brent(f, lo, hi, 1e-16, 200)
}

/// An exact closed equilibrium loop on the unit sphere.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ExactLoop {
    /// Solution family (`k < 1` or `k > 1`).
    pub family: Family,
    /// Number of periods of `κ_g` along the loop.
    pub eta: u32,
    /// Normalised length `L̄ = L/(2πR)`.
    pub lbar: f64,
    /// Elliptic parameter solved for (`k²` or `1/k²`).
    pub m: f64,
    /// Modulus `k` of Eq. (35).
    pub k: f64,
    /// `cR` of Eq. (35).
    pub c: f64,
    /// The paper's winding number `p`, Eq. (50).
    pub p: i32,
    /// Continuous winding invariant `q` of the branch (see module docs).
    pub q: i32,
    /// `|φ(L) − 2πp|` in radians: the azimuth mismatch at `s = L` (an upper bound on the
    /// position gap `|r(L) − r(0)|/R`).
    pub closure_residual: f64,
}

/// Local quantities of an exact loop at one arclength.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct LoopPoint {
    /// Arclength `s/R`.
    pub s: f64,
    /// Position on the unit sphere.
    pub x: f64,
    /// Position `y/R`.
    pub y: f64,
    /// Position `z/R`.
    pub z: f64,
    /// Curvature `κR`, Eq. (36).
    pub kappa: f64,
    /// Torsion `τR`, Eq. (36).
    pub tau: f64,
    /// Geodesic curvature `κ_g R`, Eq. (35).
    pub kappa_g: f64,
    /// Contact force `λR³/D`, Eq. (38).
    pub lambda: f64,
    /// Tangential internal force `F_t R²/D`, Eq. (37).
    pub f_t: f64,
    /// Principal-normal internal force `F_n R²/D`, Eq. (37).
    pub f_n: f64,
    /// Binormal internal force `F_b R²/D`, Eq. (37).
    pub f_b: f64,
}

impl ExactLoop {
    /// Build the loop for a solved parameter `m` (no closure check beyond recording the residual).
    pub fn from_parameter(family: Family, eta: u32, lbar: f64, m: f64) -> Result<Self, ExactError> {
        let cl = closure(family, eta, lbar, m)?;
        let q = cl.p_cont.round();
        let jump = cl.p_raw - cl.p_cont;
        let p = (q + jump).round();
        let closure_residual = 2.0 * PI * (cl.p_cont - q).abs();
        Ok(Self {
            family,
            eta,
            lbar,
            m,
            k: cl.k,
            c: cl.c,
            p: p as i32,
            q: q as i32,
            closure_residual,
        })
    }

    /// Loop length `L/R = 2π L̄`.
    pub fn length(&self) -> f64 {
        2.0 * PI * self.lbar
    }

    /// `c₁ = ck` and `k₁ = 1/k` for orbits (the dn form); `(c, k)` for waves.
    fn dn_form(&self) -> (f64, f64) {
        (self.c * self.k, 1.0 / self.k)
    }

    /// Magnitude of the conserved moment about the sphere centre, Eq. (42): `𝓜 R/D`.
    pub fn conserved_moment(&self) -> f64 {
        let a = self.c * self.c;
        ((a - 1.0) * (a - 1.0) + 4.0 * self.k * self.k * a).sqrt()
    }

    /// Geodesic-curvature part of the energy, `E_g R/(πD) = (1/(2π)) ∫ κ_g² ds`.
    ///
    /// Waves: `∫₀^L κ_g² ds = 16ηc (E(k) − k′²K(k))`; orbits: `8ηc₁ E(k₁)`.
    pub fn energy_g(&self) -> Result<f64, ExactError> {
        let eta = f64::from(self.eta);
        let (kk, ee) = complete_ke(self.m)?;
        let integral = match self.family {
            Family::Wave => 16.0 * eta * self.c * (ee - (1.0 - self.m) * kk),
            Family::Orbit => {
                let (c1, _) = self.dn_form();
                8.0 * eta * c1 * ee
            }
        };
        Ok(integral / (2.0 * PI))
    }

    /// Normal-curvature part `E_n R/(πD) = L̄` (Sec. 3.1: `κ_n² = 1/R²`).
    pub fn energy_n(&self) -> f64 {
        self.lbar
    }

    /// Total bending energy `E R/(πD)`, Eq. (2).
    pub fn energy(&self) -> Result<f64, ExactError> {
        Ok(self.energy_n() + self.energy_g()?)
    }

    /// Extremes of the contact force `λR³/D` over the loop, from Eq. (38):
    /// waves `[c²(1 − 2k²), c²]`, orbits `[−c², c²]` (then `dn(cs,k) = cn(c₁s,k₁)` spans `[−1, 1]`).
    pub fn lambda_range(&self) -> (f64, f64) {
        let a = self.c * self.c;
        match self.family {
            Family::Wave => (a * (1.0 - 2.0 * self.m), a),
            Family::Orbit => (-a, a),
        }
    }

    /// Local quantities at arclength `s` (Eqs. (35)–(38), (45), (48)).
    pub fn point(&self, s: f64) -> Result<LoopPoint, ExactError> {
        let (c, k) = (self.c, self.k);
        let a = c * c;
        let mh = self.conserved_moment();
        let ratio = (a + 1.0) / (a - 1.0);
        // Jacobi functions of (cs, k); for k > 1 the special crate applies DLMF 22.17.
        let j = jacobi(c * s, k);
        let (sn, cn, dn) = (j.sn, j.cn, j.dn);
        let kappa_g = -2.0 * c * k * cn;
        let dkappa_g = 2.0 * c * c * k * sn * dn;
        let kappa2 = 1.0 + kappa_g * kappa_g;
        let kappa = kappa2.sqrt();
        // Eq. (48): φ(s), with the integral of 1/(1 + ν sn²) written as an incomplete Π.
        let phi = match self.family {
            Family::Wave => {
                let n = -4.0 * self.m * a / ((a - 1.0) * (a - 1.0));
                let pi_inc = rodloop_special::incomplete_pi(n, j.am, k)
                    .map_err(|e| ExactError::Special(e.to_string()))?;
                -(mh / (2.0 * c)) * (c * s - ratio * pi_inc)
            }
            Family::Orbit => {
                let (c1, k1) = self.dn_form();
                let j1 = jacobi(c1 * s, k1);
                let n1 = -4.0 * a / ((a - 1.0) * (a - 1.0));
                let pi_inc = rodloop_special::incomplete_pi(n1, j1.am, k1)
                    .map_err(|e| ExactError::Special(e.to_string()))?;
                -((mh / 2.0) * s - mh * ratio / (2.0 * c1) * pi_inc)
            }
        };
        // Eq. (45) with 𝓜 · n_S = D κ_g and 𝓜 = −𝓜 e_z.
        let cos_t = (-kappa_g / mh).clamp(-1.0, 1.0);
        let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
        Ok(LoopPoint {
            s,
            x: sin_t * phi.cos(),
            y: sin_t * phi.sin(),
            z: cos_t,
            kappa,
            tau: dkappa_g / kappa2,
            kappa_g,
            lambda: a * (2.0 * dn * dn - 1.0),
            f_t: a * (1.0 - 2.0 * dn * dn),
            f_n: -kappa_g * dkappa_g / kappa,
            f_b: -dkappa_g / kappa,
        })
    }

    /// `n` points uniformly spaced in arclength over `[0, L)`.
    pub fn sample(&self, n: usize) -> Result<Vec<LoopPoint>, ExactError> {
        let len = self.length();
        (0..n)
            .map(|i| self.point(len * i as f64 / n as f64))
            .collect()
    }

    /// First-order small-`k²` approximation of Eq. (B.4) for this loop's `(η, p)`.
    pub fn k2_small(&self) -> f64 {
        k2_small(self.lbar, self.eta, self.p)
    }
}

/// Eq. (B.4): `k² ≈ −(L̄² − η²)/(L̄η²) [L̄ + p sgn(L̄ − η)]`, valid when the loop stays close to
/// an (η±1)-fold great circle.
pub fn k2_small(lbar: f64, eta: u32, p: i32) -> f64 {
    let e = f64::from(eta);
    let sgn = if lbar > e { 1.0 } else { -1.0 };
    -(lbar * lbar - e * e) / (lbar * e * e) * (lbar + f64::from(p) * sgn)
}

/// Number of sample points in the bracketing scan of [`all_loops`] (per family), distributed
/// in `ln(1 − m)` so that the slow approach to `k → 1` is resolved.
const SCAN_POINTS: usize = 400;

fn scan_grid() -> Vec<f64> {
    // m from 1e-8 to M_MAX: uniform in sqrt(m) near 0 and in ln(1-m) near 1.
    let mut g = Vec::with_capacity(SCAN_POINTS + 32);
    // Very small m (loops within ~1e-12 of a great circle), log-spaced.
    for i in 0..24 {
        g.push(10f64.powf(-16.0 + 0.5 * i as f64));
    }
    let half = SCAN_POINTS / 2;
    for i in 0..half {
        let t = (i as f64 + 0.5) / half as f64;
        let k = (0.5f64).sqrt() * t;
        if k * k > 5e-5 {
            g.push(k * k);
        }
    }
    let (lo, hi) = ((0.5f64).ln(), (1.0 - M_MAX).ln());
    for i in 0..=half {
        let t = i as f64 / half as f64;
        g.push(1.0 - (lo + (hi - lo) * t).exp());
    }
    g
}

/// Every closed loop with `eta` periods of `κ_g` at length `lbar` in both families, with
/// `k′ ≥ 1e-3` (see [`M_MAX`]), sorted by energy.
///
/// `p_cont(m)` is continuous in `m`; each integer it crosses is one loop. Brackets come from a
/// fine scan, roots from Brent's method. The scan can miss two crossings of the same integer
/// closer than the grid spacing; the tests check the result against the branch tracer.
pub fn all_loops(eta: u32, lbar: f64) -> Result<Vec<ExactLoop>, ExactError> {
    if eta == 0 {
        return Err(ExactError::InvalidParameter(
            "eta must be at least 1".into(),
        ));
    }
    if !(lbar.is_finite() && lbar > 0.0) {
        return Err(ExactError::InvalidParameter(format!(
            "lbar must be a positive finite number (got {lbar})"
        )));
    }
    let grid = scan_grid();
    let mut out = Vec::new();
    for family in [Family::Wave, Family::Orbit] {
        let vals: Vec<Option<f64>> = grid
            .iter()
            .map(|&m| closure(family, eta, lbar, m).ok().map(|c| c.p_cont))
            .collect();
        for i in 0..grid.len() - 1 {
            let (Some(va), Some(vb)) = (vals[i], vals[i + 1]) else {
                continue;
            };
            let (lo, hi) = (va.min(vb), va.max(vb));
            let mut q = lo.floor() as i64 + 1;
            // Exact hits at a grid point are counted once (from the left interval).
            while (q as f64) <= hi {
                if (q as f64) == va {
                    q += 1;
                    continue;
                }
                let m = solve_closure_bracket(family, eta, lbar, q as i32, grid[i], grid[i + 1])?;
                let lp = ExactLoop::from_parameter(family, eta, lbar, m)?;
                if lp.closure_residual < 1e-9 {
                    out.push(lp);
                }
                q += 1;
            }
        }
    }
    let mut keyed = Vec::with_capacity(out.len());
    for l in out {
        keyed.push((l.energy()?, l));
    }
    keyed.sort_by(|a, b| a.0.total_cmp(&b.0));
    Ok(keyed.into_iter().map(|(_, l)| l).collect())
}

/// The loop of the paper's branch for `eta` (wave family, `q = −(η+1)`) at `lbar`, which exists
/// for `η − 1 < L̄ < η + 1`.
pub fn paper_branch_loop(eta: u32, lbar: f64) -> Result<ExactLoop, ExactError> {
    let e = f64::from(eta);
    if !(lbar > e - 1.0 && lbar < e + 1.0) {
        return Err(ExactError::OutOfRange {
            eta,
            lbar,
            min: e - 1.0,
            max: e + 1.0,
        });
    }
    let q = -(eta as i32 + 1);
    let f = |m: f64| closure(Family::Wave, eta, lbar, m).map(|c| c.p_cont - f64::from(q));
    // p_cont(0+) differs from q by |L̄ − (η±1)| and p_cont decreases through q once; bracket by
    // expanding from the small-k² estimate.
    let grid = scan_grid();
    let mut prev: Option<(f64, f64)> = None;
    for &m in &grid {
        let v = f(m)?;
        if let Some((mp, vp)) = prev {
            if (vp > 0.0) != (v > 0.0) {
                let m = crate::roots::brent(f, mp, m, 1e-16, 200)?;
                return ExactLoop::from_parameter(Family::Wave, eta, lbar, m);
            }
        }
        if v == 0.0 {
            return ExactLoop::from_parameter(Family::Wave, eta, lbar, m);
        }
        prev = Some((m, v));
    }
    Err(ExactError::NoSolution { eta, lbar })
}
