//! Legendre's elliptic integrals in the modulus convention (`k`) and in the
//! parameter convention (`m = k²`, functions ending in `_m`, which also accept
//! negative `m`, i.e. an imaginary modulus `k = i√(−m)`).
//!
//! Everything is expressed through Carlson's symmetric integrals `R_F`,
//! `R_D`, `R_J`, `R_G` (DLMF §19.16) evaluated by the `ellip` crate, but with
//! arguments formed here so that no precision is lost:
//!
//! * the complementary parameter `m' = 1 − m` is formed as `(1 − k)(1 + k)`
//!   from the modulus (forming `m = k²` first and then `1 − m`, as a
//!   parameter-based library must, loses all digits of `m'` near `k = 1`:
//!   for `k = 1 − 10⁻¹²`, `1 − k²` is only known to ~4 digits);
//! * `Δ² = 1 − m sin²φ` is formed as `cos²φ + m' sin²φ` and
//!   `1 − n sin²φ` as `cos²φ + (1 − n) sin²φ` for `n > 0`;
//! * `E` uses, for `m ≥ ½`, the cancellation-free form DLMF 19.25.10 instead
//!   of `F − (m/3) sin³φ R_D` (which loses digits as `k → 1`);
//! * `Π(n, φ, m)` for `n < 0` (where `F + (n/3) sin³φ R_J` cancels badly, e.g.
//!   1 digit lost per decade of `|n|`) is transformed to the characteristic
//!   `N = (m − n)/(1 − n) ∈ (m, 1)` (DLMF 19.7.9, derived below);
//! * an amplitude `φ` outside `[−π/2, π/2]` is reduced with the
//!   quasi-periodicity `X(φ + jπ) = X(φ) + 2j X(π/2)` (DLMF 19.2.10), using a
//!   two-part π so that the reduced angle is accurate to `O(ε)`.

use std::f64::consts::FRAC_PI_2;

use crate::dd;
use crate::error::{from_ellip, SpecialError};

type Result<T> = std::result::Result<T, SpecialError>;

// ---------------------------------------------------------------------------
// argument checks

/// Validate a modulus and return `(m, m') = (k², (1 − k)(1 + k))`.
pub(crate) fn modulus(k: f64) -> Result<(f64, f64)> {
    if !k.is_finite() {
        return Err(SpecialError::NotFinite {
            name: "k",
            value: k,
        });
    }
    let a = k.abs();
    if a > 1.0 {
        return Err(SpecialError::ModulusOutOfRange { k });
    }
    Ok((a * a, (1.0 - a) * (1.0 + a)))
}

/// Validate a parameter and return `(m, 1 − m)`.
fn parameter(m: f64) -> Result<(f64, f64)> {
    if !m.is_finite() {
        return Err(SpecialError::NotFinite {
            name: "m",
            value: m,
        });
    }
    if m > 1.0 {
        return Err(SpecialError::ParameterOutOfRange { m });
    }
    Ok((m, 1.0 - m))
}

pub(crate) fn characteristic(n: f64) -> Result<f64> {
    if !n.is_finite() {
        return Err(SpecialError::NotFinite {
            name: "n",
            value: n,
        });
    }
    if n >= 1.0 {
        return Err(SpecialError::CharacteristicOutOfRange { n });
    }
    Ok(n)
}

fn amplitude(phi: f64) -> Result<f64> {
    if !phi.is_finite() {
        return Err(SpecialError::NotFinite {
            name: "phi",
            value: phi,
        });
    }
    Ok(phi)
}

// ---------------------------------------------------------------------------
// Carlson wrappers

#[inline]
fn rf(x: f64, y: f64, z: f64) -> Result<f64> {
    ellip::elliprf(x, y, z).map_err(from_ellip)
}

#[inline]
fn rd(x: f64, y: f64, z: f64) -> Result<f64> {
    ellip::elliprd(x, y, z).map_err(from_ellip)
}

#[inline]
fn rj(x: f64, y: f64, z: f64, p: f64) -> Result<f64> {
    ellip::elliprj(x, y, z, p).map_err(from_ellip)
}

// ---------------------------------------------------------------------------
// amplitude reduction

/// `phi = jπ + r` with `r ∈ [−π/2, π/2]` (to rounding); returns `(j, r)`.
#[inline]
fn reduce_amplitude(phi: f64) -> (f64, f64) {
    if phi.abs() <= FRAC_PI_2 {
        return (0.0, phi);
    }
    let j = (phi / dd::PI.hi).round();
    let (q, qe) = dd::two_prod(j, dd::PI.hi);
    // phi and q are within a factor of 2 of each other for |j| >= 1: exact.
    let rh = phi - q;
    (j, rh - (qe + j * dd::PI.lo))
}

/// Quasi-periodic extension `X(φ) = 2j X_c + X(r)` (DLMF 19.2.10 and the
/// corresponding relations for E and Π, which follow from the π-periodicity
/// of the integrands).
#[inline]
fn extend(
    phi: f64,
    reduced: impl FnOnce(f64) -> Result<f64>,
    complete: impl FnOnce() -> Result<f64>,
) -> Result<f64> {
    let (j, r) = reduce_amplitude(phi);
    let x = reduced(r)?;
    if j == 0.0 {
        Ok(x)
    } else {
        Ok(2.0 * j * complete()? + x)
    }
}

// ---------------------------------------------------------------------------
// cores on (m, m'), amplitude already reduced to [−π/2, π/2]

/// `Δ² = 1 − m s² = c² + m' s²` (non-negative terms for m ≤ 1).
#[inline]
fn delta2(s: f64, c: f64, mc: f64) -> f64 {
    c * c + mc * s * s
}

fn f_reduced(r: f64, mc: f64) -> Result<f64> {
    if r == 0.0 {
        return Ok(r);
    }
    let (s, c) = r.sin_cos();
    Ok(s * rf(c * c, delta2(s, c, mc), 1.0)?)
}

fn e_reduced(r: f64, m: f64, mc: f64) -> Result<f64> {
    if r == 0.0 {
        return Ok(r);
    }
    let (s, c) = r.sin_cos();
    if m == 1.0 {
        // E(φ, 1) = sin φ on [−π/2, π/2] (DLMF 19.6.9)
        return Ok(s);
    }
    let c2 = c * c;
    let d2 = delta2(s, c, mc);
    let s3 = s * s * s;
    if m < 0.5 {
        // DLMF 19.25.9: E = sin φ R_F − (m/3) sin³φ R_D(c², Δ², 1)
        Ok(s * rf(c2, d2, 1.0)? - m / 3.0 * s3 * rd(c2, d2, 1.0)?)
    } else {
        // DLMF 19.25.10 (all terms ≥ 0 on [0, π/2]):
        // E = m' F + (m m'/3) sin³φ R_D(c², 1, Δ²) + m sin φ cos φ / Δ
        let f = s * rf(c2, d2, 1.0)?;
        Ok(mc * f + m * mc / 3.0 * s3 * rd(c2, 1.0, d2)? + m * s * c / d2.sqrt())
    }
}

/// Direct Carlson form (DLMF 19.25.14), used for `n ≥ 0` (all terms ≥ 0) and
/// for moderate `n < 0`:
/// `Π = sin φ R_F(c², Δ², 1) + (n/3) sin³φ R_J(c², Δ², 1, 1 − n sin²φ)`,
/// with `p1mn = 1 − n` supplied accurately by the caller.
fn pi_reduced_direct(n: f64, p1mn: f64, r: f64, mc: f64) -> Result<f64> {
    if r == 0.0 {
        return Ok(r);
    }
    let (s, c) = r.sin_cos();
    let c2 = c * c;
    let d2 = delta2(s, c, mc);
    let f = s * rf(c2, d2, 1.0)?;
    if n == 0.0 {
        return Ok(f);
    }
    let p = if n > 0.0 {
        c2 + p1mn * s * s
    } else {
        1.0 - n * s * s
    };
    Ok(f + n / 3.0 * s * s * s * rj(c2, d2, 1.0, p)?)
}

/// Whether the `n < 0` transformation is used (see [`pi_reduced`]).
#[inline]
fn use_negative_n_transform(n: f64, m: f64) -> bool {
    n < 0.0 && (m >= 0.0 || n < 2.0 * m)
}

/// `Π(n, φ | m)` for `n < 1`, `r ∈ [−π/2, π/2]`.
///
/// For `n = −ν < 0` the identity (DLMF 19.7.9 rearranged; obtained by
/// differentiating `atan(λ sin φ cos φ / Δ)`)
///
/// ```text
/// Π(n, φ) = √(ν / ((1+ν)(m+ν))) · atan(λ sin φ cos φ / Δ)
///         + m/(m+ν) · F(φ) + ν m' / ((1+ν)(m+ν)) · Π(N, φ),
/// N = (m + ν)/(1 + ν),   1 − N = m'/(1 + ν),   λ = √(ν (m+ν)/(1+ν)),
/// ```
///
/// has only non-negative terms for `m ≥ 0` and `φ ∈ [0, π/2]`, and `Π(N, φ)`
/// with `0 < N < 1` is evaluated by the direct form without cancellation.
fn pi_reduced(n: f64, r: f64, m: f64, mc: f64) -> Result<f64> {
    if !use_negative_n_transform(n, m) {
        return pi_reduced_direct(n, 1.0 - n, r, mc);
    }
    if r == 0.0 {
        return Ok(r);
    }
    // (products arranged so that nothing overflows even for n ~ −1e300)
    let nu = -n;
    let one_p_nu = 1.0 + nu;
    let m_p_nu = m + nu;
    let big_n = m_p_nu / one_p_nu;
    let one_m_big_n = mc / one_p_nu;
    let nu_ratio = nu / one_p_nu;
    let (s, c) = r.sin_cos();
    let d = delta2(s, c, mc).sqrt();
    let lambda = nu_ratio.sqrt() * m_p_nu.sqrt();
    let t1 = (nu_ratio.sqrt() / m_p_nu.sqrt()) * (lambda * s * c / d).atan();
    let t2 = if m == 0.0 {
        0.0
    } else {
        m / m_p_nu * f_reduced(r, mc)?
    };
    let t3 = nu_ratio * (mc / m_p_nu) * pi_reduced_direct(big_n, one_m_big_n, r, mc)?;
    Ok(t1 + t2 + t3)
}

fn k_core(mc: f64) -> Result<f64> {
    if mc == 0.0 {
        return Ok(f64::INFINITY);
    }
    rf(0.0, mc, 1.0)
}

fn e_core(m: f64, mc: f64) -> Result<f64> {
    if mc == 0.0 {
        return Ok(1.0);
    }
    if m < 0.5 {
        // DLMF 19.25.1: K − E = (m/3) R_D(0, m', 1)
        Ok(rf(0.0, mc, 1.0)? - m / 3.0 * rd(0.0, mc, 1.0)?)
    } else {
        // DLMF 19.25.1: E − m'K = (m m'/3) R_D(0, 1, m')
        Ok(mc * rf(0.0, mc, 1.0)? + m * mc / 3.0 * rd(0.0, 1.0, mc)?)
    }
}

fn pi_core(n: f64, m: f64, mc: f64) -> Result<f64> {
    if mc == 0.0 {
        return Ok(f64::INFINITY);
    }
    let direct = |n: f64, p1mn: f64| -> Result<f64> {
        let kk = rf(0.0, mc, 1.0)?;
        if n == 0.0 {
            return Ok(kk);
        }
        Ok(kk + n / 3.0 * rj(0.0, mc, 1.0, p1mn)?)
    };
    if !use_negative_n_transform(n, m) {
        return direct(n, 1.0 - n);
    }
    // complete case of the n < 0 transformation (DLMF 19.7.9 / 19.7.10)
    let nu = -n;
    let one_p_nu = 1.0 + nu;
    let m_p_nu = m + nu;
    let t2 = if m == 0.0 {
        0.0
    } else {
        m / m_p_nu * rf(0.0, mc, 1.0)?
    };
    let t3 = (nu / one_p_nu) * (mc / m_p_nu) * direct(m_p_nu / one_p_nu, mc / one_p_nu)?;
    Ok(t2 + t3)
}

// ---------------------------------------------------------------------------
// public API: modulus convention

/// Complete elliptic integral of the first kind in the modulus convention,
/// `K(k) = ∫₀^{π/2} dθ / √(1 − k² sin²θ) = R_F(0, 1 − k², 1)`
/// (DLMF 19.2.8, 19.25.1; A&S 17.3.1).
///
/// `k ∈ [−1, 1]`; `K(±1) = +∞`.  `1 − k²` is formed as `(1 − k)(1 + k)`, so
/// `K` keeps full relative accuracy for `k = 1 − 10⁻¹²` (where `K ≈ 15.2`).
///
/// # Errors
/// [`SpecialError::ModulusOutOfRange`] for `|k| > 1`,
/// [`SpecialError::NotFinite`] for NaN/∞.
pub fn complete_k(k: f64) -> Result<f64> {
    let (_, mc) = modulus(k)?;
    k_core(mc)
}

/// Complete elliptic integral of the second kind in the modulus convention,
/// `E(k) = ∫₀^{π/2} √(1 − k² sin²θ) dθ` (DLMF 19.2.8; A&S 17.3.3).
///
/// Evaluated as `K − (k²/3) R_D(0, k'², 1)` for `k² < ½` and as
/// `k'² K + (k² k'²/3) R_D(0, 1, k'²)` for `k² ≥ ½` (DLMF 19.25.1), both free
/// of cancellation.  `E(±1) = 1`.
///
/// # Errors
/// As [`complete_k`].
pub fn complete_e(k: f64) -> Result<f64> {
    let (m, mc) = modulus(k)?;
    e_core(m, mc)
}

/// Complete elliptic integral of the third kind in the modulus convention,
/// `Π(n | k²) = ∫₀^{π/2} dθ / ((1 − n sin²θ) √(1 − k² sin²θ))`
/// (DLMF 19.2.7 with `α² = n`; A&S 17.7.2 with A&S's `n` of the same sign).
///
/// Defined for `n < 1` (any negative `n`, e.g. `−10⁸`), `|k| ≤ 1`.
/// `Π(0 | k²) = K(k)`, `Π(n | 0) = π / (2√(1 − n))` (DLMF 19.6.1, 19.6.2).
/// For `n ≥ 0`: `K + (n/3) R_J(0, k'², 1, 1 − n)` (DLMF 19.25.2); for `n < 0`
/// the transformation to `N = (k² − n)/(1 − n)` (DLMF 19.7.10) avoids the
/// cancellation of that form.  `Π(n | 1) = +∞`.
///
/// # Errors
/// [`SpecialError::CharacteristicOutOfRange`] for `n ≥ 1`, plus those of
/// [`complete_k`].
pub fn complete_pi(n: f64, k: f64) -> Result<f64> {
    let n = characteristic(n)?;
    let (m, mc) = modulus(k)?;
    pi_core(n, m, mc)
}

/// Incomplete elliptic integral of the first kind,
/// `F(φ, k) = ∫₀^φ dθ / √(1 − k² sin²θ)` (DLMF 19.2.4; A&S 17.2.7),
/// for **any** real `φ`.
///
/// Odd in `φ`; quasi-periodic, `F(φ + jπ, k) = F(φ, k) + 2j K(k)`
/// (DLMF 19.2.10).  On `[−π/2, π/2]`:
/// `F = sin φ R_F(cos²φ, 1 − k² sin²φ, 1)` (DLMF 19.25.5).  For `|k| = 1`,
/// `F(φ, 1) = atanh(sin φ)` (DLMF 19.6.8) and `±∞` beyond `|φ| ≥ π/2`.
///
/// # Errors
/// As [`complete_k`], plus [`SpecialError::NotFinite`] for a non-finite `φ`.
pub fn incomplete_f(phi: f64, k: f64) -> Result<f64> {
    let phi = amplitude(phi)?;
    let (_, mc) = modulus(k)?;
    extend(phi, |r| f_reduced(r, mc), || k_core(mc))
}

/// Incomplete elliptic integral of the second kind,
/// `E(φ, k) = ∫₀^φ √(1 − k² sin²θ) dθ` (DLMF 19.2.5; A&S 17.2.8), for any
/// real `φ`.
///
/// Odd in `φ`; `E(φ + jπ, k) = E(φ, k) + 2j E(k)` (DLMF 19.2.10).  On
/// `[−π/2, π/2]`: `F − (k²/3) sin³φ R_D(cos²φ, Δ², 1)` for `k² < ½`
/// (DLMF 19.25.9) and
/// `k'² F + (k² k'²/3) sin³φ R_D(cos²φ, 1, Δ²) + k² sin φ cos φ / Δ` for
/// `k² ≥ ½` (DLMF 19.25.10), `Δ² = 1 − k² sin²φ`.
///
/// # Errors
/// As [`incomplete_f`].
pub fn incomplete_e(phi: f64, k: f64) -> Result<f64> {
    let phi = amplitude(phi)?;
    let (m, mc) = modulus(k)?;
    extend(phi, |r| e_reduced(r, m, mc), || e_core(m, mc))
}

/// Incomplete elliptic integral of the third kind,
/// `Π(n; φ | k²) = ∫₀^φ dθ / ((1 − n sin²θ) √(1 − k² sin²θ))`
/// (DLMF 19.2.7 with `α² = n`; A&S 17.2.14), for `n < 1` and any real `φ`.
///
/// Odd in `φ`; `Π(n; φ + jπ) = Π(n; φ) + 2j Π(n | k²)`.  On `[−π/2, π/2]`:
/// `sin φ R_F(c², Δ², 1) + (n/3) sin³φ R_J(c², Δ², 1, 1 − n sin²φ)`
/// (DLMF 19.25.14) for `n ≥ 0`, and for `n < 0` the transformation to the
/// characteristic `N = (k² − n)/(1 − n)` (DLMF 19.7.9), which keeps full
/// accuracy for large negative `n` (e.g. `n = −10⁸`, where the direct form
/// would lose 4 digits).
///
/// # Errors
/// As [`complete_pi`], plus [`SpecialError::NotFinite`] for a non-finite `φ`.
pub fn incomplete_pi(n: f64, phi: f64, k: f64) -> Result<f64> {
    let n = characteristic(n)?;
    let phi = amplitude(phi)?;
    let (m, mc) = modulus(k)?;
    extend(phi, |r| pi_reduced(n, r, m, mc), || pi_core(n, m, mc))
}

// ---------------------------------------------------------------------------
// public API: parameter convention (m may be negative)

/// `K(m) = ∫₀^{π/2} dθ / √(1 − m sin²θ)` in the parameter convention
/// (A&S 17.3.1), for any `m ≤ 1` including negative `m` (imaginary modulus
/// `k = i√(−m)`, DLMF 19.7.5).  Same as [`complete_k`]`(√m)` for `m ≥ 0`.
///
/// # Errors
/// [`SpecialError::ParameterOutOfRange`] for `m > 1`,
/// [`SpecialError::NotFinite`] for NaN/∞.
pub fn complete_k_m(m: f64) -> Result<f64> {
    let (_, mc) = parameter(m)?;
    k_core(mc)
}

/// `E(m) = ∫₀^{π/2} √(1 − m sin²θ) dθ` for `m ≤ 1` (A&S 17.3.3), including
/// negative `m`; see [`complete_e`].
///
/// # Errors
/// As [`complete_k_m`].
pub fn complete_e_m(m: f64) -> Result<f64> {
    let (m, mc) = parameter(m)?;
    e_core(m, mc)
}

/// `Π(n | m) = ∫₀^{π/2} dθ / ((1 − n sin²θ) √(1 − m sin²θ))` for `n < 1`,
/// `m ≤ 1` (negative `m` allowed); see [`complete_pi`].
///
/// # Errors
/// [`SpecialError::CharacteristicOutOfRange`] for `n ≥ 1`, plus those of
/// [`complete_k_m`].
pub fn complete_pi_m(n: f64, m: f64) -> Result<f64> {
    let n = characteristic(n)?;
    let (m, mc) = parameter(m)?;
    pi_core(n, m, mc)
}

/// `F(φ | m) = ∫₀^φ dθ / √(1 − m sin²θ)` for any real `φ` and `m ≤ 1`
/// (negative `m` allowed; A&S 17.2.7); see [`incomplete_f`].
///
/// # Errors
/// As [`complete_k_m`], plus [`SpecialError::NotFinite`] for a non-finite `φ`.
pub fn incomplete_f_m(phi: f64, m: f64) -> Result<f64> {
    let phi = amplitude(phi)?;
    let (_, mc) = parameter(m)?;
    extend(phi, |r| f_reduced(r, mc), || k_core(mc))
}

/// `E(φ | m) = ∫₀^φ √(1 − m sin²θ) dθ` for any real `φ` and `m ≤ 1`
/// (A&S 17.2.8); see [`incomplete_e`].
///
/// With a negative parameter this is the integral with imaginary modulus,
/// `E(φ, i x) = E(φ | −x²) = ∫₀^φ √(1 + x² sin²θ) dθ` (DLMF 19.7.5), e.g.
/// `incomplete_e_m(phi, -x * x)`.
///
/// # Errors
/// As [`incomplete_f_m`].
pub fn incomplete_e_m(phi: f64, m: f64) -> Result<f64> {
    let phi = amplitude(phi)?;
    let (m, mc) = parameter(m)?;
    extend(phi, |r| e_reduced(r, m, mc), || e_core(m, mc))
}

/// `Π(n; φ | m) = ∫₀^φ dθ / ((1 − n sin²θ) √(1 − m sin²θ))` for `n < 1`,
/// any real `φ` and `m ≤ 1` (A&S 17.2.14); see [`incomplete_pi`].
///
/// # Errors
/// As [`complete_pi_m`], plus [`SpecialError::NotFinite`] for a non-finite
/// `φ`.
pub fn incomplete_pi_m(n: f64, phi: f64, m: f64) -> Result<f64> {
    let n = characteristic(n)?;
    let phi = amplitude(phi)?;
    let (m, mc) = parameter(m)?;
    extend(phi, |r| pi_reduced(n, r, m, mc), || pi_core(n, m, mc))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reduce_amplitude_is_accurate() {
        let (j, r) = reduce_amplitude(20.0);
        assert_eq!(j, 6.0);
        // 20 − 6π = 1.15044407846124056922...
        assert!((r - 1.150_444_078_461_240_6).abs() < 3e-16);
        assert_eq!(reduce_amplitude(-20.0), (-6.0, -r));
    }

    #[test]
    fn errors() {
        assert_eq!(
            complete_k(1.5),
            Err(SpecialError::ModulusOutOfRange { k: 1.5 })
        );
        assert_eq!(
            complete_pi(1.0, 0.5),
            Err(SpecialError::CharacteristicOutOfRange { n: 1.0 })
        );
        assert_eq!(
            complete_e_m(1.1),
            Err(SpecialError::ParameterOutOfRange { m: 1.1 })
        );
        assert!(matches!(
            incomplete_f(f64::NAN, 0.5),
            Err(SpecialError::NotFinite { name: "phi", .. })
        ));
        assert!(matches!(
            incomplete_e_m(1.0, f64::NEG_INFINITY),
            Err(SpecialError::NotFinite { name: "m", .. })
        ));
    }

    #[test]
    fn k_equal_one() {
        assert_eq!(complete_k(1.0), Ok(f64::INFINITY));
        assert_eq!(complete_e(-1.0), Ok(1.0));
        assert!((incomplete_e(2.0, 1.0).unwrap() - (2.0 - 2.0_f64.sin())).abs() < 1e-15);
        let f = incomplete_f(1.0, 1.0).unwrap();
        assert!((f - 1.0_f64.sin().atanh()).abs() < 1e-15 * f);
    }
}
