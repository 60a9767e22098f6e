//! The linear-solver seam: a factorised Jacobian `J = ∂F/∂x`, and its dense LU
//! implementation.

use nalgebra::{DMatrix, DVector, Dyn, LU};

/// A factorised `n × n` Jacobian `J = ∂F/∂x (x, p)`, as returned by
/// [`Problem::factorize`](crate::Problem::factorize).
///
/// The continuation solves all its bordered systems `[J F_p; cᵀ] z = r` (tangent,
/// corrector, location of special points) by block elimination with this
/// factorisation (see [`Problem::factorize`](crate::Problem::factorize)), so a problem
/// with a structured Jacobian (banded, block-tridiagonal, sparse) can supply an `O(n)`
/// solver here instead of the dense LU of [`DenseLu`].
///
/// Contract: [`Factorization::solve`] and [`Factorization::apply`] return vectors of
/// length `n`; `det_sign` is `0.0` exactly when `J` is (numerically) singular, in which
/// case `solve` may return `None`. A factorisation is used for a single `(x, p)`; it is
/// never updated.
pub trait Factorization {
    /// Solves `J x = b`; `None` if `J` is singular or the solution is not finite.
    fn solve(&self, b: &DVector<f64>) -> Option<DVector<f64>>;

    /// The product `J v` with the factorised matrix (used for the residual of the
    /// iterative refinement of bordered solves).
    fn apply(&self, v: &DVector<f64>) -> DVector<f64>;

    /// Sign of `det J`: `+1.0`, `−1.0`, or `0.0` if `J` is singular.
    fn det_sign(&self) -> f64;

    /// `ln |det J|` (`−∞` if `J` is singular), computed without overflow (for instance
    /// as the sum of the logarithms of the pivots).
    fn log_abs_det(&self) -> f64;
}

impl<T: Factorization + ?Sized> Factorization for Box<T> {
    fn solve(&self, b: &DVector<f64>) -> Option<DVector<f64>> {
        (**self).solve(b)
    }
    fn apply(&self, v: &DVector<f64>) -> DVector<f64> {
        (**self).apply(v)
    }
    fn det_sign(&self) -> f64 {
        (**self).det_sign()
    }
    fn log_abs_det(&self) -> f64 {
        (**self).log_abs_det()
    }
}

/// Dense LU factorisation with partial pivoting (nalgebra's [`LU`]) of a square
/// matrix: the default [`Problem::factorize`](crate::Problem::factorize).
///
/// Keeps a copy of the matrix for [`Factorization::apply`]. A non-square matrix is
/// accepted and behaves as a singular one (`solve` returns `None`, `det_sign` is 0),
/// as does a right-hand side of the wrong length, so that no input makes it panic.
///
/// ```
/// use nalgebra::{DMatrix, DVector};
/// use rodloop_continuation::{DenseLu, Factorization};
///
/// let lu = DenseLu::new(DMatrix::from_row_slice(2, 2, &[0.0, 2.0, 3.0, 1.0]));
/// assert_eq!(lu.det_sign(), -1.0);
/// assert!((lu.log_abs_det() - 6f64.ln()).abs() < 1e-15);
/// let x = lu.solve(&DVector::from_column_slice(&[2.0, 4.0])).unwrap();
/// assert!((x - DVector::from_column_slice(&[1.0, 1.0])).amax() < 1e-15);
/// ```
#[derive(Debug, Clone)]
pub struct DenseLu {
    matrix: DMatrix<f64>,
    lu: Option<LU<f64, Dyn, Dyn>>,
    det_sign: f64,
    log_abs_det: f64,
}

impl DenseLu {
    /// Factorises `matrix` (`O(n³)`).
    pub fn new(matrix: DMatrix<f64>) -> Self {
        if !matrix.is_square() {
            return DenseLu {
                matrix,
                lu: None,
                det_sign: 0.0,
                log_abs_det: f64::NEG_INFINITY,
            };
        }
        let lu = LU::new(matrix.clone());
        let mut sign: f64 = lu.p().determinant();
        let mut log_abs_det = 0.0;
        for d in lu.u().diagonal().iter() {
            if *d < 0.0 {
                sign = -sign;
            }
            log_abs_det += d.abs().ln();
        }
        // A zero pivot makes the matrix singular; a NaN or infinite one (non-finite
        // entries) leaves it unusable.
        if !log_abs_det.is_finite() {
            sign = 0.0;
            log_abs_det = f64::NEG_INFINITY;
        }
        DenseLu {
            matrix,
            lu: Some(lu),
            det_sign: sign,
            log_abs_det,
        }
    }

    /// The factorised matrix.
    pub fn matrix(&self) -> &DMatrix<f64> {
        &self.matrix
    }
}

impl Factorization for DenseLu {
    fn solve(&self, b: &DVector<f64>) -> Option<DVector<f64>> {
        let lu = self.lu.as_ref()?;
        if b.len() != self.matrix.nrows() || self.det_sign == 0.0 {
            return None;
        }
        let x = lu.solve(b)?;
        x.iter().all(|v| v.is_finite()).then_some(x)
    }

    fn apply(&self, v: &DVector<f64>) -> DVector<f64> {
        if v.len() != self.matrix.ncols() {
            return DVector::from_element(self.matrix.nrows(), f64::NAN);
        }
        &self.matrix * v
    }

    fn det_sign(&self) -> f64 {
        self.det_sign
    }

    fn log_abs_det(&self) -> f64 {
        self.log_abs_det
    }
}
