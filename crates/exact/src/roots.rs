//! Scalar root finding used by the exact layer.

use crate::ExactError;

/// Brent's method (R. P. Brent, *Algorithms for Minimization without Derivatives*, 1973, ch. 4)
/// for a root of `f` in `[a, b]`, where `f(a)` and `f(b)` have opposite signs: the
/// continuation crate's [`rodloop_continuation::roots::brent`] with the exact layer's errors.
///
/// Stops when the bracket is narrower than `xtol·max(1, |x|)` plus a few ulps, or when
/// `f(x) = 0` exactly.
pub fn brent<F>(f: F, a: f64, b: f64, xtol: f64, max_iter: usize) -> Result<f64, ExactError>
where
    F: FnMut(f64) -> Result<f64, ExactError>,
{
    use rodloop_continuation::roots::{self, RootStop};
    match roots::brent(f, a, b, xtol, max_iter) {
        Ok(r) if r.stop == RootStop::MaxIterations => {
            Err(ExactError::RootNotConverged { x: r.x, fx: r.fx })
        }
        Ok(r) => Ok(r.x),
        Err(e) => Err(root_error(e)),
    }
}

/// The exact layer's error for a root finder's error.
pub(crate) fn root_error(e: rodloop_continuation::RootError<ExactError>) -> ExactError {
    use rodloop_continuation::RootError;
    match e {
        RootError::Function(e) => e,
        RootError::NoBracket { a, b, fa, fb } => ExactError::NoBracket { a, b, fa, fb },
        other => ExactError::InvalidParameter(other.to_string()),
    }
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
