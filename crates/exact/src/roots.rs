//! Scalar root finding used by the exact layer.

use crate::ExactError;

/// Brent's method (R. P. Brent, *Algorithms for Minimization without Derivatives*, 1973, ch. 4)
/// for a root of `f` in `[a, b]`, where `f(a)` and `f(b)` have opposite signs.
///
/// Stops when the bracket is narrower than `xtol·max(1, |x|)` plus a few ulps, or when
/// `f(x) = 0` exactly.
pub fn brent<F>(mut f: F, a: f64, b: f64, xtol: f64, max_iter: usize) -> Result<f64, ExactError>
where
    F: FnMut(f64) -> Result<f64, ExactError>,
{
    let (mut a, mut b) = (a, b);
    let mut fa = f(a)?;
    let mut fb = f(b)?;
    if fa == 0.0 {
        return Ok(a);
    }
    if fb == 0.0 {
        return Ok(b);
    }
    if (fa > 0.0) == (fb > 0.0) {
        return Err(ExactError::NoBracket { a, b, fa, fb });
    }
    let (mut c, mut fc) = (a, fa);
    let mut d = b - a;
    let mut e = d;
    for _ in 0..max_iter {
        if (fb > 0.0) == (fc > 0.0) {
            c = a;
            fc = fa;
            d = b - a;
            e = d;
        }
        if fc.abs() < fb.abs() {
            a = b;
            b = c;
            c = a;
            fa = fb;
            fb = fc;
            fc = fa;
        }
        let tol = 2.0 * f64::EPSILON * b.abs() + 0.5 * xtol * b.abs().max(1e-300);
        let xm = 0.5 * (c - b);
        if xm.abs() <= tol || fb == 0.0 {
            return Ok(b);
        }
        if e.abs() >= tol && fa.abs() > fb.abs() {
            let s = fb / fa;
            let (mut p, mut q);
            if a == c {
                p = 2.0 * xm * s;
                q = 1.0 - s;
            } else {
                let qq = fa / fc;
                let r = fb / fc;
                p = s * (2.0 * xm * qq * (qq - r) - (b - a) * (r - 1.0));
                q = (qq - 1.0) * (r - 1.0) * (s - 1.0);
            }
            if p > 0.0 {
                q = -q;
            } else {
                p = -p;
            }
            if 2.0 * p < (3.0 * xm * q - (tol * q).abs()).min((e * q).abs()) {
                e = d;
                d = p / q;
            } else {
                d = xm;
                e = d;
            }
        } else {
            d = xm;
            e = d;
        }
        a = b;
        fa = fb;
        b += if d.abs() > tol { d } else { tol.copysign(xm) };
        fb = f(b)?;
    }
    Err(ExactError::RootNotConverged { x: b, fx: fb })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn brent_finds_known_roots() {
        let r = brent(|x| Ok(x * x - 2.0), 0.0, 2.0, 1e-16, 100).unwrap();
        assert!((r - 2f64.sqrt()).abs() < 4e-16);
        let r = brent(|x| Ok(x.cos() - x), 0.0, 1.0, 1e-16, 100).unwrap();
        assert!((r.cos() - r).abs() < 1e-15);
        assert!(brent(|x| Ok(x * x + 1.0), -1.0, 1.0, 1e-12, 50).is_err());
    }
}
