//! The problem trait, the stability callback trait and finite-difference helpers.

use nalgebra::{DMatrix, DVector};

use crate::error::BoxError;
use crate::factorization::{DenseLu, Factorization};

/// A parameter-dependent system of `n` equations in `n` unknowns, `F(x, p) = 0`,
/// with `F: Rⁿ × R → Rⁿ`.
///
/// The continuation methods of this crate trace the solution curve
/// `{(x, p) : F(x, p) = 0}` in `Rⁿ⁺¹`. All three evaluations are required: analytic
/// derivatives are what makes Newton correctors converge quadratically. For small
/// problems, or to test analytic derivatives, [`fd_jacobian`] and [`fd_dparam`] compute
/// central finite-difference approximations from [`Problem::residual`].
///
/// Evaluations may fail (for instance when `x` leaves the domain of the model); the
/// error is returned as the associated [`Problem::Error`] type and surfaces as
/// [`ContinuationError::Problem`](crate::ContinuationError::Problem). Infallible
/// problems can use [`std::convert::Infallible`].
///
/// The methods take `&self`: a problem is immutable during continuation.
pub trait Problem {
    /// Error returned by failing evaluations.
    type Error: std::error::Error + Send + Sync + 'static;

    /// Number of unknowns `n` (and of equations).
    fn dim(&self) -> usize;

    /// The residual `F(x, p)`, a vector of length `n`.
    fn residual(&self, x: &DVector<f64>, p: f64) -> Result<DVector<f64>, Self::Error>;

    /// The Jacobian `∂F/∂x (x, p)`, an `n × n` matrix.
    fn jacobian(&self, x: &DVector<f64>, p: f64) -> Result<DMatrix<f64>, Self::Error>;

    /// The parameter derivative `∂F/∂p (x, p)`, a vector of length `n`.
    fn dparam(&self, x: &DVector<f64>, p: f64) -> Result<DVector<f64>, Self::Error>;

    /// A factorisation of the Jacobian `J = ∂F/∂x (x, p)`, used for every linear
    /// solve of the continuation's hot paths: Newton at fixed `p` ([`crate::newton`]),
    /// and the bordered systems `[J F_p; cᵀ] z = r` of the tangent, the corrector and
    /// the location of special points, which are solved by block elimination with it.
    ///
    /// The default is the dense LU factorisation [`DenseLu`] of
    /// [`Problem::jacobian`]; override it when `J` has structure (banded,
    /// block-tridiagonal, sparse) that an `O(n)` solver can exploit. The returned
    /// factorisation may borrow from `self`.
    ///
    /// [`Problem::jacobian`] stays required: the dense path is the fallback where
    /// block elimination is inaccurate (near-singular `J` at folds and branch points,
    /// see [`Continuation`](crate::Continuation)), and branch switching uses dense
    /// SVDs.
    fn factorize(
        &self,
        x: &DVector<f64>,
        p: f64,
    ) -> Result<Box<dyn Factorization + '_>, Self::Error> {
        Ok(Box::new(DenseLu::new(self.jacobian(x, p)?)))
    }
}

impl<P: Problem + ?Sized> Problem for &P {
    type Error = P::Error;

    fn dim(&self) -> usize {
        (**self).dim()
    }

    fn residual(&self, x: &DVector<f64>, p: f64) -> Result<DVector<f64>, Self::Error> {
        (**self).residual(x, p)
    }

    fn jacobian(&self, x: &DVector<f64>, p: f64) -> Result<DMatrix<f64>, Self::Error> {
        (**self).jacobian(x, p)
    }

    fn dparam(&self, x: &DVector<f64>, p: f64) -> Result<DVector<f64>, Self::Error> {
        (**self).dparam(x, p)
    }

    fn factorize(
        &self,
        x: &DVector<f64>,
        p: f64,
    ) -> Result<Box<dyn Factorization + '_>, Self::Error> {
        (**self).factorize(x, p)
    }
}

/// A stability index along a branch: the number of unstable directions of the
/// equilibrium `(x, p)`.
///
/// Typical choices: for a gradient system `F = ∇E`, the number of negative eigenvalues
/// of the Hessian `∂F/∂x` (the Morse index); for a dynamical system `ẋ = F(x, p)`, the
/// number of eigenvalues of `∂F/∂x` with positive real part. The continuation only
/// compares the integers it returns: it reports where they change, located by bisection
/// on the arclength (see [`Continuation::with_stability`](crate::Continuation::with_stability)).
///
/// For infallible closures use
/// [`Continuation::with_stability_fn`](crate::Continuation::with_stability_fn).
pub trait Stability {
    /// The index at the solution point `(x, p)`.
    fn index(&self, x: &DVector<f64>, p: f64) -> Result<usize, BoxError>;
}

impl<S: Stability + ?Sized> Stability for &S {
    fn index(&self, x: &DVector<f64>, p: f64) -> Result<usize, BoxError> {
        (**self).index(x, p)
    }
}

/// Relative step `ε^{1/3}` of central differences (balances the `O(h²)` truncation
/// error against the `O(ε/h)` rounding error).
fn central_step(v: f64) -> f64 {
    f64::EPSILON.cbrt() * v.abs().max(1.0)
}

/// Central finite-difference approximation of the Jacobian of `f` at `x`.
///
/// Column `j` is `(f(x + hⱼ eⱼ) − f(x − hⱼ eⱼ)) / (2hⱼ)` with
/// `hⱼ = ε^{1/3} max(1, |xⱼ|)`, accurate to about `1e-10` relative for smooth,
/// well-scaled `f`. Costs `2 len(x)` evaluations of `f`; meant for tests and small
/// problems, e.g. inside an implementation of [`Problem::jacobian`]:
///
/// ```
/// use nalgebra::{DMatrix, DVector};
/// use rodloop_continuation::{fd_jacobian, Problem};
///
/// struct Fold;
/// impl Problem for Fold {
///     type Error = std::convert::Infallible;
///     fn dim(&self) -> usize { 1 }
///     fn residual(&self, x: &DVector<f64>, p: f64) -> Result<DVector<f64>, Self::Error> {
///         Ok(DVector::from_element(1, p - x[0] * x[0]))
///     }
///     fn jacobian(&self, x: &DVector<f64>, p: f64) -> Result<DMatrix<f64>, Self::Error> {
///         fd_jacobian(|y| self.residual(y, p), x)
///     }
///     fn dparam(&self, _x: &DVector<f64>, _p: f64) -> Result<DVector<f64>, Self::Error> {
///         Ok(DVector::from_element(1, 1.0))
///     }
/// }
/// let j = Fold.jacobian(&DVector::from_element(1, 0.5), 0.0).unwrap();
/// assert!((j[(0, 0)] + 1.0).abs() < 1e-9);
/// ```
pub fn fd_jacobian<E, F>(f: F, x: &DVector<f64>) -> Result<DMatrix<f64>, E>
where
    F: Fn(&DVector<f64>) -> Result<DVector<f64>, E>,
{
    let n = x.len();
    let mut xp = x.clone();
    let mut jac: Option<DMatrix<f64>> = None;
    for j in 0..n {
        let h = central_step(x[j]);
        xp[j] = x[j] + h;
        let fp = f(&xp)?;
        xp[j] = x[j] - h;
        let fm = f(&xp)?;
        xp[j] = x[j];
        let m = jac.get_or_insert_with(|| DMatrix::zeros(fp.len(), n));
        let col = (fp - fm) / (2.0 * h);
        m.set_column(j, &col);
    }
    Ok(jac.unwrap_or_else(|| DMatrix::zeros(0, 0)))
}

/// Central finite-difference approximation of the derivative of `f` at `p`:
/// `(f(p + h) − f(p − h)) / (2h)` with `h = ε^{1/3} max(1, |p|)`.
///
/// Typical use inside [`Problem::dparam`]: `fd_dparam(|q| self.residual(x, q), p)`.
pub fn fd_dparam<E, F>(f: F, p: f64) -> Result<DVector<f64>, E>
where
    F: Fn(f64) -> Result<DVector<f64>, E>,
{
    let h = central_step(p);
    let fp = f(p + h)?;
    let fm = f(p - h)?;
    Ok((fp - fm) / (2.0 * h))
}
