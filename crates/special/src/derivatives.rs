//! Derivatives of the complete integrals with respect to the modulus `k` and
//! the characteristic `n` (for Newton solves).
//!
//! * `dK/dk = (E − k'²K)/(k k'²)` and `dE/dk = (E − K)/k` (DLMF 19.4.1) are
//!   evaluated in the cancellation-free Carlson forms
//!   `dK/dk = (k/3) R_D(0, 1, k'²)` and `dE/dk = −(k/3) R_D(0, k'², 1)`
//!   (DLMF 19.25.1), which stay accurate down to `k = 0`.
//! * The closed forms for `Π` (DLMF 19.4.4)
//!
//!   ```text
//!   ∂Π/∂n = [E + (k² − n)K/n + (n² − k²)Π/n] / (2(k² − n)(n − 1)),
//!   ∂Π/∂k = k/(n − k²) · [E/(k² − 1) + Π]
//!   ```
//!
//!   (both verified against finite differences and mpmath in the tests, see
//!   [`complete_pi_dn_closed_form`] and [`complete_pi_dk_closed_form`]) have
//!   removable singularities at `n = k²` (and `n = 0` for `∂Π/∂n`), near
//!   which they cancel catastrophically — and `n = k²` lies inside the range
//!   the project uses.  [`complete_pi_derivatives`] therefore differentiates
//!   Bulirsch's algorithm `cel` (Bulirsch 1969, DLMF 19.2.11, 19.36(i))
//!   exactly, in forward mode: with `p = 1 − n`,
//!   `Π(n | k²) = cel(k', p, 1, 1)`, and for `p > 0` that algorithm is a
//!   Gauss/Landen (AGM-type) iteration whose every step is a sum of positive
//!   terms, so neither the value nor `∂/∂p` suffers cancellation.  The
//!   `k'`-derivative of the iteration, however, loses accuracy (up to ~1e-12
//!   relative) for `n → −∞`, `k → 1`; so wherever the closed form for `∂Π/∂k`
//!   does not cancel, `|Π − E/k'²| ≥ E/(4k'²)` (i.e. away from `n = k²`), that
//!   closed form is used instead, and the differentiated iteration only near
//!   `n = k²`.

use std::f64::consts::FRAC_PI_2;

use crate::error::SpecialError;
use crate::integrals::{characteristic, complete_e, complete_k, complete_pi, modulus};

type Result<T> = std::result::Result<T, SpecialError>;

/// Validate a modulus (finite, `|k| ≤ 1`) with the integrals' check, returning it unchanged.
fn check_k(k: f64) -> Result<f64> {
    modulus(k).map(|_| k)
}

fn rd(x: f64, y: f64, z: f64) -> Result<f64> {
    ellip::elliprd(x, y, z).map_err(crate::error::from_ellip)
}

/// `dK/dk = (E − k'²K) / (k k'²) = (k/3) R_D(0, 1, k'²)` (DLMF 19.4.1,
/// 19.25.1), for `|k| < 1` (odd in `k`; `+∞` at `k = ±1` with the sign of `k`).
///
/// # Errors
/// [`SpecialError::ModulusOutOfRange`] for `|k| > 1`,
/// [`SpecialError::NotFinite`] for NaN/∞.
pub fn complete_k_dk(k: f64) -> Result<f64> {
    let k = check_k(k)?;
    if k == 0.0 {
        return Ok(0.0);
    }
    let a = k.abs();
    let mc = (1.0 - a) * (1.0 + a);
    if mc == 0.0 {
        return Ok(f64::INFINITY.copysign(k));
    }
    Ok(k / 3.0 * rd(0.0, 1.0, mc)?)
}

/// `dE/dk = (E − K)/k = −(k/3) R_D(0, k'², 1)` (DLMF 19.4.1, 19.25.1), for
/// `|k| < 1` (odd in `k`; `∓∞` at `k = ±1`).
///
/// # Errors
/// As [`complete_k_dk`].
pub fn complete_e_dk(k: f64) -> Result<f64> {
    let k = check_k(k)?;
    if k == 0.0 {
        return Ok(0.0);
    }
    let a = k.abs();
    let mc = (1.0 - a) * (1.0 + a);
    if mc == 0.0 {
        return Ok(f64::NEG_INFINITY.copysign(k));
    }
    Ok(-k / 3.0 * rd(0.0, mc, 1.0)?)
}

/// Value and first partial derivatives of the complete integral of the third
/// kind `Π(n | k²)` (see [`complete_pi`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PiDerivatives {
    /// `Π(n | k²)`.
    pub value: f64,
    /// `∂Π/∂n` (DLMF 19.4.4, first formula).
    pub d_n: f64,
    /// `∂Π/∂k` at fixed `n` (DLMF 19.4.4, second formula; odd in `k`).
    pub d_k: f64,
}

/// `Π(n | k²)` together with `∂Π/∂n` and `∂Π/∂k`, for `n < 1`, `|k| < 1`.
///
/// Computed by forward-mode differentiation of Bulirsch's `cel(k', 1 − n, 1, 1)`
/// (an AGM-type iteration whose steps only add positive terms); accurate to a few ulps including at the
/// removable singularities `n = k²` and `n = 0` of the closed forms.  Away
/// from `n = k²` (where `|Π − E/k'²| ≥ E/(4k'²)`) `∂Π/∂k` is taken from the
/// closed form instead, which is then free of cancellation and more accurate
/// than the differentiated iteration for `n → −∞`, `k → 1`.  The closed forms
/// are (DLMF 19.4.4)
/// `∂Π/∂n = [E + (k² − n)K/n + (n² − k²)Π/n] / (2(k² − n)(n − 1))` and
/// `∂Π/∂k = k/(n − k²) · [E/(k² − 1) + Π]`.
/// `∂Π/∂k = 0` at `k = 0`.
///
/// # Errors
/// [`SpecialError::CharacteristicOutOfRange`] for `n ≥ 1`,
/// [`SpecialError::ModulusOutOfRange`] for `|k| ≥ 1` (the derivatives are
/// infinite at `|k| = 1`), [`SpecialError::NotFinite`] for NaN/∞.
pub fn complete_pi_derivatives(n: f64, k: f64) -> Result<PiDerivatives> {
    let n = characteristic(n)?;
    let k = check_k(k)?;
    let a = k.abs();
    if a == 1.0 {
        return Err(SpecialError::ModulusOutOfRange { k });
    }
    let kc2 = (1.0 - a) * (1.0 + a);
    let kc = kc2.sqrt();
    let c = cel_p_positive(kc, 1.0 - n);
    let d_k = if k == 0.0 {
        0.0
    } else {
        // DLMF 19.4.4: ∂Π/∂k = k (Π − E/k'²) / (n − k²).  Where the bracket does
        // not cancel (n not close to k²) this is more accurate than the
        // derivative of the iteration, whose k'-derivative cancels for
        // n → −∞, k → 1.
        let q = complete_e(k)? / kc2;
        let diff = c.v - q;
        if diff.abs() >= 0.25 * q {
            let (k2, k2e) = crate::dd::two_prod(k, k);
            k * diff / ((n - k2) - k2e)
        } else {
            // dk'/dk = −k/k'
            -c.dkc * k / kc
        }
    };
    Ok(PiDerivatives {
        value: c.v,
        d_n: -c.dp,
        d_k,
    })
}

/// `∂Π(n | k²)/∂n`; see [`complete_pi_derivatives`].
///
/// # Errors
/// As [`complete_pi_derivatives`].
pub fn complete_pi_dn(n: f64, k: f64) -> Result<f64> {
    Ok(complete_pi_derivatives(n, k)?.d_n)
}

/// `∂Π(n | k²)/∂k`; see [`complete_pi_derivatives`].
///
/// # Errors
/// As [`complete_pi_derivatives`].
pub fn complete_pi_dk(n: f64, k: f64) -> Result<f64> {
    Ok(complete_pi_derivatives(n, k)?.d_k)
}

/// The closed form DLMF 19.4.4 for `∂Π/∂n`,
/// `[E + (k² − n)K/n + (n² − k²)Π/n] / (2(k² − n)(n − 1))`, evaluated
/// literally.  Provided for cross-checks only: it loses accuracy near `n = 0`
/// and `n = k²` (use [`complete_pi_dn`]).
///
/// # Errors
/// As [`complete_pi`].
pub fn complete_pi_dn_closed_form(n: f64, k: f64) -> Result<f64> {
    let e = complete_e(k)?;
    let kk = complete_k(k)?;
    let p = complete_pi(n, k)?;
    let k2 = k * k;
    Ok((e + (k2 - n) * kk / n + (n * n - k2) * p / n) / (2.0 * (k2 - n) * (n - 1.0)))
}

/// The closed form DLMF 19.4.4 for `∂Π/∂k`, `k/(n − k²) · [E/(k² − 1) + Π]`,
/// evaluated literally.  For cross-checks only: it loses accuracy near
/// `n = k²` (use [`complete_pi_dk`]).
///
/// # Errors
/// As [`complete_pi`].
pub fn complete_pi_dk_closed_form(n: f64, k: f64) -> Result<f64> {
    let e = complete_e(k)?;
    let p = complete_pi(n, k)?;
    let a = k.abs();
    let k2m1 = -((1.0 - a) * (1.0 + a));
    Ok(k / (n - k * k) * (e / k2m1 + p))
}

// ---------------------------------------------------------------------------
// forward-mode differentiation of Bulirsch's cel

/// A value with its partial derivatives with respect to `k'` and `p`.
#[derive(Clone, Copy, Debug)]
struct Jet {
    v: f64,
    dkc: f64,
    dp: f64,
}

impl Jet {
    #[inline]
    fn cst(v: f64) -> Jet {
        Jet {
            v,
            dkc: 0.0,
            dp: 0.0,
        }
    }
    #[inline]
    fn add(self, o: Jet) -> Jet {
        Jet {
            v: self.v + o.v,
            dkc: self.dkc + o.dkc,
            dp: self.dp + o.dp,
        }
    }
    #[inline]
    fn mul(self, o: Jet) -> Jet {
        Jet {
            v: self.v * o.v,
            dkc: self.dkc * o.v + self.v * o.dkc,
            dp: self.dp * o.v + self.v * o.dp,
        }
    }
    #[inline]
    fn div(self, o: Jet) -> Jet {
        let q = self.v / o.v;
        Jet {
            v: q,
            dkc: (self.dkc - q * o.dkc) / o.v,
            dp: (self.dp - q * o.dp) / o.v,
        }
    }
    #[inline]
    fn scale(self, s: f64) -> Jet {
        Jet {
            v: self.v * s,
            dkc: self.dkc * s,
            dp: self.dp * s,
        }
    }
    #[inline]
    fn sqrt(self) -> Jet {
        let r = self.v.sqrt();
        let h = 0.5 / r;
        Jet {
            v: r,
            dkc: self.dkc * h,
            dp: self.dp * h,
        }
    }
}

/// Result of [`cel_p_positive`]: `cel(k', p, 1, 1)` and its partials.
#[derive(Clone, Copy, Debug)]
struct CelJet {
    v: f64,
    dkc: f64,
    dp: f64,
}

/// Bulirsch's general complete integral
/// `cel(k', p, a, b) = ∫₀^{π/2} (a cos²θ + b sin²θ) / ((cos²θ + p sin²θ) √(cos²θ + k'² sin²θ)) dθ`
/// (DLMF 19.2.11) for `a = b = 1`, `p > 0`, `0 < k' ≤ 1`, together with its
/// exact partial derivatives with respect to `k'` and `p` (forward-mode
/// differentiation of the iteration).
///
/// The iteration (Bulirsch 1969) keeps `m_l, k'_l` = 2ˡ × the AGM pair of
/// `(1, k')`, and updates `a, b, p` by Landen-type steps that only add positive
/// quantities; it converges quadratically.  It is iterated until the AGM gap
/// is below `1e-15` (one step more than needed for the value) so that the
/// derivatives are converged too.
fn cel_p_positive(kc: f64, p: f64) -> CelJet {
    let mut kc = Jet {
        v: kc,
        dkc: 1.0,
        dp: 0.0,
    };
    let p0 = Jet {
        v: p,
        dkc: 0.0,
        dp: 1.0,
    };
    let mut e = kc;
    let mut m = Jet::cst(1.0);
    let mut p = p0.sqrt();
    let mut a = Jet::cst(1.0);
    let mut b = Jet::cst(1.0).div(p);
    for _ in 0..60 {
        let f = a;
        a = a.add(b.div(p));
        let g = e.div(p);
        b = b.add(f.mul(g)).scale(2.0);
        p = g.add(p);
        let g = m;
        m = kc.add(m);
        if (g.v - kc.v).abs() <= 1e-15 * g.v {
            break;
        }
        kc = e.sqrt().scale(2.0);
        e = kc.mul(m);
    }
    let res = a.mul(m).add(b).div(m.mul(m.add(p))).scale(FRAC_PI_2);
    CelJet {
        v: res.v,
        dkc: res.dkc,
        dp: res.dp,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cel_reproduces_pi() {
        for &k in &[0.0_f64, 0.3, 0.9, 0.999_999] {
            for &n in &[-1e8, -3.0, 0.0, 0.5, 0.9] {
                let kc = ((1.0 - k) * (1.0 + k)).sqrt();
                let v = cel_p_positive(kc, 1.0 - n).v;
                let r = complete_pi(n, k).unwrap();
                assert!(((v - r) / r).abs() < 1e-14, "n={n} k={k}: {v} vs {r}");
            }
        }
    }
}
