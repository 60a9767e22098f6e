//! Small dense linear-algebra helpers (private).

use nalgebra::{DMatrix, DVector, LU, SVD};

use crate::error::ContinuationError;
use crate::problem::Problem;

/// Evaluates a [`Problem`] on points `y = (x, p) ∈ Rⁿ⁺¹`, checking output shapes and
/// converting errors.
pub(crate) struct Evaluator<'a, P: Problem + ?Sized> {
    pub problem: &'a P,
    pub n: usize,
}

impl<'a, P: Problem + ?Sized> Evaluator<'a, P> {
    pub fn new(problem: &'a P) -> Self {
        Evaluator {
            problem,
            n: problem.dim(),
        }
    }

    /// Splits `y` into `(x, p)`.
    pub fn split(&self, y: &DVector<f64>) -> (DVector<f64>, f64) {
        (y.rows(0, self.n).into_owned(), y[self.n])
    }

    /// Joins `(x, p)` into `y`.
    pub fn join(&self, x: &DVector<f64>, p: f64) -> DVector<f64> {
        let mut y = DVector::zeros(self.n + 1);
        y.rows_mut(0, self.n).copy_from(x);
        y[self.n] = p;
        y
    }

    pub fn check_state(&self, x: &DVector<f64>) -> Result<(), ContinuationError> {
        if x.len() != self.n {
            return Err(ContinuationError::WrongStateLength {
                expected: self.n,
                found: x.len(),
            });
        }
        Ok(())
    }

    fn check_vec(&self, what: &'static str, v: &DVector<f64>) -> Result<(), ContinuationError> {
        if v.len() != self.n {
            return Err(ContinuationError::WrongOutputShape {
                what,
                expected: (self.n, 1),
                found: (v.len(), 1),
            });
        }
        Ok(())
    }

    pub fn residual(&self, x: &DVector<f64>, p: f64) -> Result<DVector<f64>, ContinuationError> {
        let r = self
            .problem
            .residual(x, p)
            .map_err(ContinuationError::problem)?;
        self.check_vec("residual", &r)?;
        Ok(r)
    }

    pub fn jacobian(&self, x: &DVector<f64>, p: f64) -> Result<DMatrix<f64>, ContinuationError> {
        let j = self
            .problem
            .jacobian(x, p)
            .map_err(ContinuationError::problem)?;
        if j.shape() != (self.n, self.n) {
            return Err(ContinuationError::WrongOutputShape {
                what: "jacobian",
                expected: (self.n, self.n),
                found: j.shape(),
            });
        }
        Ok(j)
    }

    pub fn dparam(&self, x: &DVector<f64>, p: f64) -> Result<DVector<f64>, ContinuationError> {
        let d = self
            .problem
            .dparam(x, p)
            .map_err(ContinuationError::problem)?;
        self.check_vec("dparam", &d)?;
        Ok(d)
    }

    /// The augmented Jacobian `[J F_p]`, `n × (n+1)`, at `y`.
    pub fn augmented(&self, y: &DVector<f64>) -> Result<DMatrix<f64>, ContinuationError> {
        let (x, p) = self.split(y);
        let j = self.jacobian(&x, p)?;
        let fp = self.dparam(&x, p)?;
        let n = self.n;
        let mut a = DMatrix::zeros(n, n + 1);
        a.view_mut((0, 0), (n, n)).copy_from(&j);
        a.set_column(n, &fp);
        Ok(a)
    }
}

/// Max-norm `‖v‖∞` that propagates NaN (nalgebra's `amax` skips NaN entries).
pub(crate) fn max_abs(v: &DVector<f64>) -> f64 {
    let mut m: f64 = 0.0;
    for a in v.iter() {
        if a.is_nan() {
            return f64::NAN;
        }
        m = m.max(a.abs());
    }
    m
}

/// `[J F_p; borderᵀ]`.
pub(crate) fn bordered_matrix(
    j: &DMatrix<f64>,
    fp: &DVector<f64>,
    border: &DVector<f64>,
) -> DMatrix<f64> {
    let n = j.nrows();
    let mut m = DMatrix::zeros(n + 1, n + 1);
    m.view_mut((0, 0), (n, n)).copy_from(j);
    m.view_mut((0, n), (n, 1)).copy_from(fp);
    m.view_mut((n, 0), (1, n + 1))
        .copy_from(&border.transpose());
    m
}

/// Solution of a linear system together with the sign and `ln|det|` of its matrix.
pub(crate) struct SolveWithDet {
    pub z: DVector<f64>,
    pub det_sign: f64,
    pub log_det: f64,
}

/// Solves `m z = rhs` by LU with partial pivoting; also returns the sign and the
/// logarithm of the absolute value of `det m` (computed from the diagonal of `U` and the
/// parity of the row permutation, without overflow). `None` if `m` is singular or the
/// solution is not finite.
pub(crate) fn solve_with_det(m: DMatrix<f64>, rhs: &DVector<f64>) -> Option<SolveWithDet> {
    let lu = LU::new(m);
    let z = lu.solve(rhs)?;
    if !z.iter().all(|v| v.is_finite()) {
        return None;
    }
    let mut sign: f64 = lu.p().determinant();
    let mut log_det = 0.0;
    for d in lu.u().diagonal().iter() {
        if *d < 0.0 {
            sign = -sign;
        }
        log_det += d.abs().ln();
    }
    Some(SolveWithDet {
        z,
        det_sign: sign,
        log_det,
    })
}

/// Solves `m z = rhs` by LU; `None` if singular or non-finite.
pub(crate) fn solve(m: DMatrix<f64>, rhs: &DVector<f64>) -> Option<DVector<f64>> {
    let z = LU::new(m).solve(rhs)?;
    z.iter().all(|v| v.is_finite()).then_some(z)
}

/// Right singular vectors of the `n × (n+1)` matrix `a`, sorted by increasing singular
/// value, as `(σ, v)` pairs; there are `n + 1` of them (the matrix is padded with a zero
/// row so that the SVD returns a full `V`). The first ones span the (numerical) kernel.
pub(crate) fn right_singular_pairs(a: &DMatrix<f64>) -> Vec<(f64, DVector<f64>)> {
    let (n, m) = a.shape();
    let mut sq = DMatrix::zeros(m, m);
    sq.view_mut((0, 0), (n, m)).copy_from(a);
    let svd = SVD::new(sq, false, true);
    let v_t = svd.v_t.expect("V requested");
    let mut pairs: Vec<(f64, DVector<f64>)> = (0..m)
        .map(|i| (svd.singular_values[i], v_t.row(i).transpose()))
        .collect();
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    pairs
}

/// Left singular vector of the `n × (n+1)` matrix `a` for its smallest singular value
/// (a unit vector `ψ ∈ Rⁿ` with `ψᵀ a ≈ 0` at a simple branch point).
pub(crate) fn left_null_vector(a: &DMatrix<f64>) -> DVector<f64> {
    let svd = SVD::new(a.clone(), true, false);
    let u = svd.u.expect("U requested");
    let mut k = 0;
    for i in 0..svd.singular_values.len() {
        if svd.singular_values[i] < svd.singular_values[k] {
            k = i;
        }
    }
    u.column(k).into_owned()
}

/// Unit tangent `t` of the solution curve at `y` with `tᵀ t_prev > 0`, from the
/// bordered system `[J F_p; t_prevᵀ] z = [0; 1]`, `t = z / |z|`.
pub(crate) struct Tangent {
    pub t: DVector<f64>,
    /// Sign of `det [J F_p; tᵀ]` (0 when the fallback below was used).
    pub det_sign: f64,
    /// `ln |det [J F_p; t_prevᵀ]|` (−∞ with the fallback).
    pub log_det: f64,
}

pub(crate) fn tangent<P: Problem + ?Sized>(
    ev: &Evaluator<'_, P>,
    y: &DVector<f64>,
    t_prev: &DVector<f64>,
) -> Result<Tangent, ContinuationError> {
    let n = ev.n;
    let a = ev.augmented(y)?;
    let mut m = DMatrix::zeros(n + 1, n + 1);
    m.view_mut((0, 0), (n, n + 1)).copy_from(&a);
    m.view_mut((n, 0), (1, n + 1))
        .copy_from(&t_prev.transpose());
    let mut rhs = DVector::zeros(n + 1);
    rhs[n] = 1.0;
    if let Some(s) = solve_with_det(m, &rhs) {
        let norm = s.z.norm();
        if norm.is_finite() && norm > 0.0 {
            // det [A; t_prevᵀ] = (t_prev·t) det [A; tᵀ] and t_prev·t = 1/|z| > 0.
            return Ok(Tangent {
                t: s.z / norm,
                det_sign: s.det_sign,
                log_det: s.log_det,
            });
        }
    }
    // Singular bordered matrix (y is exactly singular, e.g. a branch point hit exactly,
    // or t_prev is orthogonal to the kernel): project t_prev onto the numerical kernel.
    Ok(Tangent {
        t: kernel_direction(&a, t_prev),
        det_sign: 0.0,
        log_det: f64::NEG_INFINITY,
    })
}

/// The unit vector of the numerical kernel of `a` (`n × (n+1)`) closest to `guess`,
/// oriented with `guess`.
pub(crate) fn kernel_direction(a: &DMatrix<f64>, guess: &DVector<f64>) -> DVector<f64> {
    let pairs = right_singular_pairs(a);
    let smax = pairs.last().map(|p| p.0).unwrap_or(0.0).max(1.0);
    let mut proj = DVector::zeros(guess.len());
    for (i, (s, v)) in pairs.iter().enumerate() {
        if i == 0 || *s <= 1e-8 * smax {
            proj += v * v.dot(guess);
        }
    }
    let norm = proj.norm();
    if norm > 1e-12 {
        proj / norm
    } else {
        let v = pairs[0].1.clone();
        if v.dot(guess) < 0.0 {
            -v
        } else {
            v
        }
    }
}
