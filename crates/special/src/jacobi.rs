//! Jacobi elliptic functions `sn`, `cn`, `dn` and the amplitude `am`,
//! parameterised by the modulus `k` (not by `m = k²`).
//!
//! It is one file because the descending Landen transformation, its double-double quarter
//! period and the argument reduction share the `Landen` state; a tenth of it is unit tests.
//!
//! # Algorithm
//!
//! For `0 < k < 1` the values are computed with the descending Landen
//! transformation driven by the arithmetic–geometric mean (DLMF 22.7.1–22.7.3,
//! 22.20(ii); A&S 16.12, 16.4).  With `a₀ = 1`, `b₀ = k' = √((1−k)(1+k))`,
//! `c₀ = k` and
//!
//! ```text
//! a_{l+1} = (a_l + b_l)/2,   b_{l+1} = √(a_l b_l),   c_{l+1} = c_l² / (4 a_{l+1}),
//! ```
//!
//! the modulus of level `l` is `k_l = c_l / a_l` (so `1 − k_{l+1} = b_l / a_{l+1}`
//! is available without cancellation) and `K(k) = K(k_N) / a_N`.  The
//! iteration stops when `k_N < 10⁻⁵`, where the first-order small-modulus
//! expansions (DLMF 22.10.4–22.10.6) at `v = a_N u`
//!
//! ```text
//! sn ≈ sin v − ¼k_N² (v − sin v cos v) cos v,  cn ≈ cos v + ¼k_N² (v − sin v cos v) sin v,
//! dn ≈ 1 − ½k_N² sin² v
//! ```
//!
//! are exact to `O(k_N⁴) < 10⁻²⁰`.  The values are then carried up the levels
//! through the ratio `t = cn/sn` and `dn` (DLMF 22.7.1–22.7.3 divided by
//! `sn²`):
//!
//! ```text
//! t_{l−1} = t_l dn_l / (1 + k_l),   dn_{l−1} = (t_l² + 1 − k_l) / (t_l² + 1 + k_l),
//! sn = sgn(u)/√(1 + t_0²),   cn = t_0 sn,
//! ```
//!
//! in which every sum has non-negative terms, so no digits are lost even for
//! `k → 1` (no `asin` of arguments close to 1 as in the classical amplitude
//! recursion A&S 16.4.3, and no `cn² ≈ 1` of the lower levels as in the
//! direct form of 22.7.3, which loses a factor ≈ 2 per level for `k → 1`).
//!
//! Before that, `u` is reduced modulo the half period: `j = nint(u / 2K)`,
//! `r = u − 2jK ∈ [−K, K]`, with `2K` known to double-double precision
//! (a compensated replay of the same AGM, see [`Landen::quarter_dd`]), so that
//! the reduced argument is accurate to `O(ε |r|)` even after many periods.
//! Then `sn(u) = (−1)ʲ sn(r)`, `cn(u) = (−1)ʲ cn(r)`, `dn(u) = dn(r)` and
//! `am(u) = jπ + am(r)` with `am(r) = atan2(sn r, cn r) ∈ [−π/2, π/2]`.
//!
//! For `k > 1` the reciprocal-modulus transformation (DLMF 22.17.2–22.17.4) is
//! used with `k₁ = 1/k`, `k₁' = √((k−1)(k+1))/k` and the argument `k u` formed
//! exactly as a double-double product.

use std::f64::consts::FRAC_PI_2;

use crate::dd::{self, Dd};

/// Values of the Jacobi elliptic functions at one point `(u, k)`.
///
/// Produced by [`jacobi`] or [`JacobiModulus::eval`].  For every finite input
/// `sn = sin(am)`, `cn = cos(am)` and `dn² + k² sn² = 1` hold to rounding.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Jacobi {
    /// `sn(u, k)` (DLMF 22.2.4).
    pub sn: f64,
    /// `cn(u, k)` (DLMF 22.2.5).
    pub cn: f64,
    /// `dn(u, k)` (DLMF 22.2.6).
    pub dn: f64,
    /// The amplitude `am(u, k) = ∫₀ᵘ dn(t, k) dt` (DLMF 22.16.1 and 22.16.2,
    /// continued to all real `u`); see [`jacobi`] for what it means for
    /// `k ≥ 1`.
    pub am: f64,
}

impl Jacobi {
    const NAN: Jacobi = Jacobi {
        sn: f64::NAN,
        cn: f64::NAN,
        dn: f64::NAN,
        am: f64::NAN,
    };
}

/// Jacobi elliptic functions `sn, cn, dn` and amplitude `am` of real argument
/// `u` and modulus `k` (parameter `m = k²`; DLMF §22.2, A&S §16.1).
///
/// Only `k²` enters, so a negative `k` is treated as `|k|`.
///
/// * `k = 0`: `sn = sin u`, `cn = cos u`, `dn = 1`, `am = u` (DLMF 22.5.3).
/// * `0 < k < 1`: descending Landen transformation driven by the AGM
///   (DLMF 22.7.1–22.7.3, 22.20(ii); A&S 16.12), carried up the levels in a
///   form where every sum has non-negative terms (so full accuracy is kept
///   for `k → 1`, e.g. `k = 1 − 10⁻¹²`), after reducing `u` modulo `2K`.
///   `am(u, k) = ∫₀ᵘ dn` is the **unwrapped** amplitude: continuous and
///   strictly increasing for all real `u`, with `sn = sin am`, `cn = cos am`
///   and the quasi-periodicity `am(u + 2jK) = am(u) + jπ` (DLMF 22.16.2),
///   where `K = K(k)` is the complete integral of the first kind.  It is never
///   reduced to `[−π, π]`.  The argument is first reduced modulo `2K` (known
///   to double-double precision), so the accuracy does not degrade with
///   `|u|` beyond the unavoidable conditioning of the functions.
/// * `k = 1`: `sn = tanh u`, `cn = dn = sech u`, `am = gd(u) = atan(sinh u)`
///   (DLMF 22.5.8, 4.23.39).
/// * `k > 1`: reciprocal-modulus transformation (DLMF 22.17.2–22.17.4) with
///   `k₁ = 1/k`: `sn(u,k) = k₁ sn(ku,k₁)`, `cn(u,k) = dn(ku,k₁)`,
///   `dn(u,k) = cn(ku,k₁)`.  Here `cn(u,k) > 0` for every `u`, and `am` is
///   defined as the continuous angle with `sin am = sn`, `cos am = cn`, i.e.
///   `am(u,k) = asin(sn(u,k)) = ∫₀ᵘ dn(t,k) dt`: it **oscillates** in
///   `[−asin(1/k), asin(1/k)]` with period `4K(1/k)/k` and does not grow.
///   As `k → 1` from either side, all four outputs tend to the `k = 1` values
///   for fixed `u`.
///
/// Symmetries: `sn` and `am` are odd in `u`, `cn` and `dn` are even (exactly,
/// also in floating point).
///
/// Non-finite `u` or `k` (NaN or ±∞) give NaN in all four fields.  For
/// `|u| ≳ 10¹⁵ K` the argument reduction loses its meaning (the result is
/// finite but not accurate).
///
/// The function does not allocate; if many values are needed for one fixed
/// `k`, [`JacobiModulus`] avoids recomputing the `k`-dependent AGM data.
///
/// ```
/// let j = rodloop_special::jacobi(0.7, 0.5);
/// assert!((j.sn * j.sn + j.cn * j.cn - 1.0).abs() < 1e-15);
/// assert!((j.dn * j.dn + 0.25 * j.sn * j.sn - 1.0).abs() < 1e-15);
/// ```
pub fn jacobi(u: f64, k: f64) -> Jacobi {
    if !u.is_finite() || !k.is_finite() {
        return Jacobi::NAN;
    }
    let k = k.abs();
    if k == 0.0 {
        let (s, c) = u.sin_cos();
        return Jacobi {
            sn: s,
            cn: c,
            dn: 1.0,
            am: u,
        };
    }
    if k == 1.0 {
        return hyperbolic(u);
    }
    if k < 1.0 {
        let kc = ((1.0 - k) * (1.0 + k)).sqrt();
        let landen = Landen::new(k, kc);
        let (j, r) = landen.reduce(u, 0.0, || landen.quarter_dd(kc_correction_below(k, kc)));
        finish_below(&landen, j, r)
    } else {
        let k1 = 1.0 / k;
        let kc1 = ((k - 1.0) * (k + 1.0)).sqrt() / k;
        let landen = Landen::new(k1, kc1);
        let (vh, vl) = dd::two_prod(k, u);
        let (j, r) = landen.reduce(vh, vl, || landen.quarter_dd(kc_correction_above(k, kc1)));
        finish_above(&landen, k, j, r)
    }
}

/// `k = 1`: hyperbolic limit (DLMF 22.5.8).
fn hyperbolic(u: f64) -> Jacobi {
    let sech = 1.0 / u.cosh();
    Jacobi {
        sn: u.tanh(),
        cn: sech,
        dn: sech,
        am: u.sinh().atan(),
    }
}

/// Final assembly for `0 < k < 1` from the reduced argument.
#[inline]
fn finish_below(landen: &Landen, j: f64, r: f64) -> Jacobi {
    let (s, c, d) = landen.eval(r);
    let am_r = s.atan2(c);
    let sign = parity_sign(j);
    Jacobi {
        sn: sign * s,
        cn: sign * c,
        dn: d,
        am: if j == 0.0 {
            am_r
        } else {
            j * dd::PI.hi + (j * dd::PI.lo + am_r)
        },
    }
}

/// Final assembly for `k > 1` (reciprocal modulus, DLMF 22.17.2–22.17.4).
#[inline]
fn finish_above(landen: &Landen, k: f64, j: f64, r: f64) -> Jacobi {
    let (s, c, d) = landen.eval(r);
    let sign = parity_sign(j);
    let sn = sign * s / k;
    let cn = d;
    Jacobi {
        sn,
        cn,
        dn: sign * c,
        am: sn.atan2(cn),
    }
}

#[inline]
fn parity_sign(j: f64) -> f64 {
    if (j * 0.5).fract() != 0.0 {
        -1.0
    } else {
        1.0
    }
}

/// Maximal number of Landen levels.  Every double `k ≠ 1` has
/// `k' ≥ 1.4e-8` (resp. `k₁' ≥ 2.1e-8` for `k > 1`), which needs at most 6
/// levels; the cap only bounds the loop.
const MAX_LEVELS: usize = 12;
/// Stop the descent when the level modulus is below this value.
const LANDEN_TOL: f64 = 1e-5;

/// The AGM / descending-Landen data of one modulus `k ∈ (0, 1)`.
#[derive(Clone, Copy, Debug)]
struct Landen {
    levels: usize,
    /// `k_l` for `l = 1..=levels` (stored at index `l − 1`).
    k: [f64; MAX_LEVELS],
    /// `1 − k_l`, computed without cancellation.
    omk: [f64; MAX_LEVELS],
    /// `a_l` and `b_l` for `l = 0..=levels` (for [`Landen::quarter_dd`]).
    a: [f64; MAX_LEVELS + 1],
    b: [f64; MAX_LEVELS + 1],
    /// Modulus of the last level, `k_N < 1e-5`.
    kn: f64,
    /// `a_N`.
    a_n: f64,
    /// `K(k)` (double precision).
    quarter: f64,
}

impl Landen {
    fn new(k: f64, kc: f64) -> Landen {
        let mut lk = [0.0; MAX_LEVELS];
        let mut omk = [0.0; MAX_LEVELS];
        let mut aa = [0.0; MAX_LEVELS + 1];
        let mut bb = [0.0; MAX_LEVELS + 1];
        let (mut a, mut b, mut c) = (1.0_f64, kc, k);
        aa[0] = a;
        bb[0] = b;
        let mut levels = 0;
        while c > LANDEN_TOL * a && levels < MAX_LEVELS {
            let a1 = 0.5 * (a + b);
            let b1 = (a * b).sqrt();
            let c1 = 0.25 * c * c / a1;
            lk[levels] = c1 / a1;
            omk[levels] = b / a1;
            a = a1;
            b = b1;
            c = c1;
            levels += 1;
            aa[levels] = a;
            bb[levels] = b;
        }
        let kn = c / a;
        // K(k_N) = π/2 (1 + k_N²/4 + O(k_N⁴)), DLMF 19.5.1.
        let quarter = FRAC_PI_2 * (1.0 + 0.25 * kn * kn) / a;
        Landen {
            levels,
            k: lk,
            omk,
            a: aa,
            b: bb,
            kn,
            a_n: a,
            quarter,
        }
    }

    /// `(sn, cn, dn)(r, k)`; accurate for `|r| ≲ K` (valid for `|r| < 2K`).
    ///
    /// The transformation is carried up the levels in terms of the ratio
    /// `t = cn/sn` and `dn`:
    /// `t_{l−1} = t_l dn_l / (1 + k_l)`,
    /// `dn_{l−1} = (t_l² + 1 − k_l) / (t_l² + 1 + k_l)` (DLMF 22.7.1–22.7.3
    /// divided by `sn²`), and at the top `sn = sgn(r)/√(1 + t²)`,
    /// `cn = t sn`.  All sums have non-negative terms.  Carrying `cn` and
    /// `dn` themselves would lose about a factor 2 per level for `k → 1`
    /// (`dn_{l−1}` would depend on `cn_l² ≈ 1`), and this form also makes
    /// `sn² + cn² = 1` hold to about 2 ulps.
    #[inline]
    fn eval(&self, r: f64) -> (f64, f64, f64) {
        if r.abs() < 1e-9 {
            // sn = r (1 − (1 + k²) r²/6 + …), cn = 1 − r²/2 + …, dn = 1 − k² r²/2 + …
            // all round to these values for |r| < 1e-9.
            return (r, 1.0, 1.0);
        }
        let v = r * self.a_n;
        let (sv, cv) = v.sin_cos();
        let kn2 = self.kn * self.kn;
        let w = 0.25 * kn2 * (v - sv * cv);
        let mut t = (cv + w * sv) / (sv - w * cv);
        let mut d = 1.0 - 0.5 * kn2 * sv * sv;
        for l in (0..self.levels).rev() {
            let kl = self.k[l];
            let opk = 1.0 + kl;
            let t2 = t * t;
            t = t * d / opk;
            d = (t2 + self.omk[l]) / (t2 + opk);
        }
        let s = (1.0 / (1.0 + t * t).sqrt()).copysign(r);
        (s, t * s, d)
    }

    /// `K(k)` to double-double precision, given `δb₀ = k'_exact − k'` (the
    /// rounding error of the `b₀` used by [`Landen::new`]).
    ///
    /// Compensated AGM: the stored double-precision AGM steps are replayed with
    /// error-free transformations, propagating the first-order errors
    /// `δa, δb` of `a_l, b_l`
    /// (`δa_{l+1} = (e_sum + δa + δb)/2`,
    /// `δb_{l+1} = (a b − b_{l+1}² + a δb + b δa)/(2 b_{l+1})`, residuals
    /// exact), plus one further step and a final mean, so that `k_{N+2} < 10⁻²¹`
    /// and `M(1, k') = a_{N+2} + δa_{N+2}` to ~1e-32; then `K = π/(2M)`
    /// (DLMF 19.8.5).  Second-order terms are ~ε², i.e. negligible.
    fn quarter_dd(&self, db0: f64) -> Dd {
        let (mut a, mut b) = (self.a[0], self.b[0]);
        let (mut da, mut db) = (0.0, db0);
        for l in 0..=self.levels {
            let (a1, b1) = if l < self.levels {
                (self.a[l + 1], self.b[l + 1])
            } else {
                (0.5 * (a + b), (a * b).sqrt())
            };
            let (_, es) = dd::two_sum(a, b);
            let (p, ep) = dd::two_prod(a, b);
            let (q, eq) = dd::two_square(b1);
            let da1 = 0.5 * (es + da + db);
            let db1 = (((p - q) - eq) + ep + a * db + b * da) / (2.0 * b1);
            a = a1;
            b = b1;
            da = da1;
            db = db1;
        }
        // last half step: a_{N+2} = (a + b)/2 equals M to ~k_{N+2}² < 1e-42
        let (s, es) = dd::two_sum(a, b);
        let m = 0.5 * s;
        let dm = 0.5 * (es + da + db);
        // K = (π/2)/(m + dm): one Newton correction of the double quotient
        let half_pi = dd::PI.scale(0.5);
        let q = half_pi.hi / m;
        let (p, e) = dd::two_prod(q, m);
        let r = ((half_pi.hi - p) - e) + half_pi.lo - q * dm;
        Dd::new(q, r / m)
    }

    /// Reduce `v = vh + vl` modulo `2K`: returns `(j, r)` with
    /// `v = 2jK + r`, `|r| ≲ K`.  `quarter_dd` supplies `K` in double-double
    /// precision and is only called if a reduction is needed.
    #[inline]
    fn reduce(&self, vh: f64, vl: f64, quarter_dd: impl FnOnce() -> Dd) -> (f64, f64) {
        if vh.abs() <= self.quarter {
            // (keep the sign of −0.0)
            return (0.0, if vl == 0.0 { vh } else { vh + vl });
        }
        let two_k = 2.0 * self.quarter;
        let j = (vh / two_k).round();
        if j.abs() > 4.0e15 || !j.is_finite() {
            // beyond any meaningful accuracy (|u| ≳ 1e15 K): plain reduction,
            // kept finite
            let r = (vh / two_k - j) * two_k;
            return if r.is_finite() { (j, r) } else { (0.0, 0.0) };
        }
        let p = quarter_dd().scale(2.0);
        reduce_with(vh, vl, j, p)
    }
}

/// `r = (vh + vl) − j (p.hi + p.lo)` with the leading subtraction exact.
#[inline]
fn reduce_with(vh: f64, vl: f64, j: f64, p: Dd) -> (f64, f64) {
    let (q, qe) = dd::two_prod(j, p.hi);
    // vh and q agree to within a factor 2, so this is exact (Sterbenz).
    let rh = vh - q;
    (j, rh + ((vl - qe) - j * p.lo))
}

/// `√(1 − k²) − kc` (to first order) for `kc = fl(√((1−k)(1+k)))`, `0 < k < 1`.
fn kc_correction_below(k: f64, kc: f64) -> f64 {
    let (p, e) = dd::two_prod(k, k);
    let (h, l) = dd::two_sum(1.0, -p);
    let (q, eq) = dd::two_prod(kc, kc);
    // (1 − k²) − kc² = h + l − e − q − eq.  h − q is exact (Sterbenz), and
    // for k → 1 it nearly cancels against e: subtract e next (exact again),
    // before the smaller terms, or the result loses its relative accuracy.
    let diff = (((h - q) - e) + l) - eq;
    diff / (2.0 * kc)
}

/// `√(1 − 1/k²) − kc1` (to first order) for `kc1 = fl(√((k−1)(k+1))/k)`, `k > 1`.
fn kc_correction_above(k: f64, kc1: f64) -> f64 {
    let (p, e) = dd::two_prod(k, k);
    let (h, l) = dd::two_sum(p, -1.0);
    let (z, ez) = dd::two_prod(k, kc1);
    let (w, ew) = dd::two_prod(z, z);
    // (k² − 1) − (k kc1)² = h + l + e − w − ew − 2 z ez (+ ez², negligible);
    // same ordering as in `kc_correction_below`.
    let diff = (((h - w) + e) + l) - ew - 2.0 * z * ez;
    diff / (2.0 * kc1 * p)
}

/// `k' = √(1 − k²)` in double-double, for `0 < k < 1` (reference for tests).
#[cfg(test)]
fn kc_dd_below(k: f64) -> Dd {
    let (p, e) = dd::two_prod(k, k);
    Dd::ONE.sub(Dd { hi: p, lo: e }).sqrt()
}

/// `k₁' = √(1 − 1/k²) = √(k² − 1)/k` in double-double, for `k > 1`
/// (reference for tests).
#[cfg(test)]
fn kc_dd_above(k: f64) -> Dd {
    let (p, e) = dd::two_prod(k, k);
    Dd { hi: p, lo: e }.sub(Dd::ONE).sqrt().div_f64(k)
}

/// `K = π / (2 M(1, k'))` by a plain double-double AGM (DLMF 19.8.5);
/// reference for [`Landen::quarter_dd`] in the tests.
#[cfg(test)]
fn quarter_period_dd(kc: Dd) -> Dd {
    let mut a = Dd::ONE;
    let mut b = kc;
    for _ in 0..40 {
        let diff = a.sub(b);
        let converged = diff.hi.abs() < 1e-17 * a.hi;
        let a1 = a.add(b).scale(0.5);
        if converged {
            a = a1;
            break;
        }
        b = a.mul(b).sqrt();
        a = a1;
    }
    dd::PI.scale(0.5).div(a)
}

/// Precomputed data for evaluating the Jacobi functions many times at one
/// fixed modulus `k`; [`JacobiModulus::eval`] returns exactly what
/// [`jacobi`]`(u, k)` returns, without redoing the `k`-dependent AGM
/// iterations (including the double-double quarter period).
///
/// ```
/// use rodloop_special::{jacobi, JacobiModulus};
/// let jm = JacobiModulus::new(0.9);
/// assert_eq!(jm.eval(12.5), jacobi(12.5, 0.9));
/// ```
#[derive(Clone, Copy, Debug)]
pub struct JacobiModulus {
    k: f64,
    kind: Kind,
}

#[derive(Clone, Copy, Debug)]
enum Kind {
    Invalid,
    Circular,
    Hyperbolic,
    Below { landen: Landen, two_k: Dd },
    Above { landen: Landen, two_k: Dd },
}

impl JacobiModulus {
    /// Prepare the modulus `k` (any real; `|k|` is used, non-finite `k` makes
    /// every evaluation NaN).
    pub fn new(k: f64) -> JacobiModulus {
        let k = k.abs();
        let kind = if !k.is_finite() {
            Kind::Invalid
        } else if k == 0.0 {
            Kind::Circular
        } else if k == 1.0 {
            Kind::Hyperbolic
        } else if k < 1.0 {
            let kc = ((1.0 - k) * (1.0 + k)).sqrt();
            let landen = Landen::new(k, kc);
            Kind::Below {
                landen,
                two_k: landen.quarter_dd(kc_correction_below(k, kc)).scale(2.0),
            }
        } else {
            let kc1 = ((k - 1.0) * (k + 1.0)).sqrt() / k;
            let landen = Landen::new(1.0 / k, kc1);
            Kind::Above {
                landen,
                two_k: landen.quarter_dd(kc_correction_above(k, kc1)).scale(2.0),
            }
        };
        JacobiModulus { k, kind }
    }

    /// The modulus `|k|` this was built for.
    pub fn modulus(&self) -> f64 {
        self.k
    }

    /// The real quarter period of `sn(·, k)`: `K(k)` for `k < 1`,
    /// `K(1/k)/k` for `k > 1` (DLMF 22.17.2), `π/2` for `k = 0`, `+∞` for
    /// `k = 1`, NaN for non-finite `k`.
    pub fn quarter_period(&self) -> f64 {
        match self.kind {
            Kind::Invalid => f64::NAN,
            Kind::Circular => FRAC_PI_2,
            Kind::Hyperbolic => f64::INFINITY,
            Kind::Below { landen, .. } => landen.quarter,
            Kind::Above { landen, .. } => landen.quarter / self.k,
        }
    }

    /// Evaluate `sn, cn, dn, am` at `u`; identical to [`jacobi`]`(u, k)`.
    #[inline]
    pub fn eval(&self, u: f64) -> Jacobi {
        if !u.is_finite() {
            return Jacobi::NAN;
        }
        match self.kind {
            Kind::Invalid => Jacobi::NAN,
            Kind::Circular => {
                let (s, c) = u.sin_cos();
                Jacobi {
                    sn: s,
                    cn: c,
                    dn: 1.0,
                    am: u,
                }
            }
            Kind::Hyperbolic => hyperbolic(u),
            Kind::Below { landen, two_k } => {
                let (j, r) = landen.reduce(u, 0.0, || two_k.scale(0.5));
                finish_below(&landen, j, r)
            }
            Kind::Above { landen, two_k } => {
                let (vh, vl) = dd::two_prod(self.k, u);
                let (j, r) = landen.reduce(vh, vl, || two_k.scale(0.5));
                finish_above(&landen, self.k, j, r)
            }
        }
    }
}

/// `K(k)` computed by the same AGM as [`jacobi`] (used by the tests to
/// compare periods); `k ∈ [0, 1)`.
#[cfg(test)]
pub(crate) fn landen_quarter(k: f64) -> f64 {
    let kc = ((1.0 - k) * (1.0 + k)).sqrt();
    Landen::new(k, kc).quarter
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn compensated_agm_matches_double_double_agm() {
        for &k in &[1e-12_f64, 1e-6, 1e-3, 0.3, 0.5, 0.9, 0.999_999, 1.0 - 1e-12] {
            let kc = ((1.0 - k) * (1.0 + k)).sqrt();
            let fast = Landen::new(k, kc).quarter_dd(kc_correction_below(k, kc));
            let slow = quarter_period_dd(kc_dd_below(k));
            let diff = fast.sub(slow);
            assert!(
                diff.hi.abs() < 1e-30 * slow.hi,
                "k={k}: {fast:?} vs {slow:?}"
            );
        }
        for &k in &[1.0_f64 + 1e-12, 1.000_001, 1.5, 7.0, 50.0, 1e6] {
            let kc1 = ((k - 1.0) * (k + 1.0)).sqrt() / k;
            let fast = Landen::new(1.0 / k, kc1).quarter_dd(kc_correction_above(k, kc1));
            let slow = quarter_period_dd(kc_dd_above(k));
            let diff = fast.sub(slow);
            assert!(
                diff.hi.abs() < 1e-30 * slow.hi,
                "k={k}: {fast:?} vs {slow:?}"
            );
        }
    }

    #[test]
    fn quarter_period_matches_double() {
        for &k in &[1e-3, 0.3, 0.5, 0.9, 0.999_999, 1.0 - 1e-12] {
            let kdd = quarter_period_dd(kc_dd_below(k));
            let kd = landen_quarter(k);
            assert!(((kdd.hi - kd) / kd).abs() < 4e-16, "k={k}: {kdd:?} vs {kd}");
        }
        // K(0) = π/2 exactly in double-double
        let k0 = quarter_period_dd(Dd::ONE);
        assert_eq!(k0, dd::PI.scale(0.5));
    }

    #[test]
    fn eval_matches_jacobi() {
        for &k in &[0.0, 0.3, 0.999, 1.0, 1.7, 40.0] {
            let jm = JacobiModulus::new(k);
            for &u in &[0.0, 0.3, -2.0, 17.0, -49.5] {
                assert_eq!(jm.eval(u), jacobi(u, k));
            }
        }
    }

    #[test]
    fn nan_in_nan_out() {
        for j in [
            jacobi(f64::NAN, 0.5),
            jacobi(1.0, f64::NAN),
            jacobi(f64::INFINITY, 0.5),
            jacobi(1.0, f64::NEG_INFINITY),
        ] {
            assert!(j.sn.is_nan() && j.cn.is_nan() && j.dn.is_nan() && j.am.is_nan());
        }
    }

    #[test]
    fn pi_constant() {
        assert_eq!(std::f64::consts::PI, dd::PI.hi);
    }
}
