//! Linear algebra of the continuation (private): problem evaluation with shape checks,
//! bordered solves by block elimination with the problem's [`Factorization`] (with
//! iterative refinement and a dense fallback), and dense SVD helpers.

use nalgebra::{DMatrix, DVector, LU, SVD};

use crate::error::ContinuationError;
use crate::factorization::{DenseLu, Factorization};
use crate::problem::Problem;

/// Relative size `‖δz‖∞ ≤ REFINE_NOISE ‖z‖∞` (`√ε`) of a refinement correction below
/// which a block-elimination solution counts as accurate although the refinement did
/// not reduce the residual: both residuals are then at rounding level (when the first
/// solution is off by more than rounding, the refinement reduces its residual by the
/// factor `≈ ε cond(J)`, and the correction is as large as that error).
const REFINE_NOISE: f64 = 1.4901161193847656e-8;

/// Reduction `‖r₂‖ ≤ REFINE_CONTRACTION ‖r₁‖` of the bordered residual by the
/// refinement step that shows that block elimination works (`ε cond(J) ≲ ½`).
const REFINE_CONTRACTION: f64 = 0.5;

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

    pub fn check_vec(&self, what: &'static str, v: &DVector<f64>) -> Result<(), ContinuationError> {
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

    /// The problem's factorisation of `J(x, p)`.
    pub fn factorize(
        &self,
        x: &DVector<f64>,
        p: f64,
    ) -> Result<Box<dyn Factorization + 'a>, ContinuationError> {
        self.problem
            .factorize(x, p)
            .map_err(ContinuationError::problem)
    }

    /// Solves `J(x, p) dx = b` with the problem's factorisation, falling back to the
    /// dense LU of [`Problem::jacobian`] if it fails; `Ok(None)` if both fail (`J`
    /// singular).
    pub fn solve_jacobian(
        &self,
        x: &DVector<f64>,
        p: f64,
        b: &DVector<f64>,
    ) -> Result<Option<DVector<f64>>, ContinuationError> {
        let fact = self.factorize(x, p)?;
        if let Some(z) = fact.solve(b) {
            self.check_vec("factorization solve", &z)?;
            if z.iter().all(|v| v.is_finite()) {
                return Ok(Some(z));
            }
        }
        let j = self.jacobian(x, p)?;
        Ok(DenseLu::new(j).solve(b))
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

/// A basis of the two-dimensional kernel of the `n × (n+1)` matrix `a` of rank `n − 1` (a
/// simple branch point) and its left null vector, from one LU factorisation with complete
/// pivoting of the square matrix `[a; 0]`, `P [a; 0] Q = L U` (2m³/3 flops against the
/// SVD's ~12m³; Golub & Van Loan, *Matrix Computations*, §3.4.2, rank-revealing by complete
/// pivoting): the last two pivots are the small ones. The kernel is `Q [−U₁₁⁻¹U₁₂; I]`,
/// orthonormalised; the left kernel of `[a; 0]` is `Pᵀ L⁻ᵀ` of the last two unit vectors,
/// which spans `{(ψ, 0), e_{n+1}}`, so `ψ` is the combination without an `(n+1)`-th
/// component. Returns the two kernel vectors as `(|a v|, v)` pairs, smallest first, and
/// `ψ` (unit). Falls back to [`kernels_svd`] where `[a; 0]` has fewer than three rows or
/// the leading block is singular.
pub(crate) fn kernels(a: &DMatrix<f64>) -> (Vec<(f64, DVector<f64>)>, DVector<f64>) {
    let (n, m) = a.shape();
    if m < 3 {
        return kernels_svd(a);
    }
    let mut sq = DMatrix::zeros(m, m);
    sq.view_mut((0, 0), (n, m)).copy_from(a);
    let lu = sq.full_piv_lu();
    let u = lu.u();
    let l = lu.l();
    let r = m - 2;
    let u11 = u.view((0, 0), (r, r)).into_owned();
    let u12 = u.view((0, r), (r, 2)).into_owned();
    let Some(x) = u11.solve_upper_triangular(&(-u12)) else {
        return kernels_svd(a);
    };
    if !x.iter().all(|v| v.is_finite()) {
        return kernels_svd(a);
    }
    // Kernel of P[a;0]Q in the permuted coordinates, then undo Q.
    let mut basis: Vec<DVector<f64>> = (0..2)
        .map(|j| {
            let mut y = DVector::zeros(m);
            y.rows_mut(0, r).copy_from(&x.column(j));
            y[r + j] = 1.0;
            lu.q().inv_permute_rows(&mut y);
            y
        })
        .collect();
    // Modified Gram–Schmidt, twice.
    for _ in 0..2 {
        for j in 0..2 {
            for i in 0..j {
                let c = basis[i].dot(&basis[j]);
                let bi = basis[i].clone();
                basis[j].axpy(-c, &bi, 1.0);
            }
            let nrm = basis[j].norm();
            if !(nrm > 0.0 && nrm.is_finite()) {
                return kernels_svd(a);
            }
            basis[j] /= nrm;
        }
    }
    let mut pairs: Vec<(f64, DVector<f64>)> =
        basis.into_iter().map(|v| ((a * &v).norm(), v)).collect();
    pairs.sort_by(|p, q| p.0.total_cmp(&q.0));
    // Left kernel: wᵀ = yᵀ L⁻¹ P with y the last two unit vectors (yᵀ U = 0).
    let lt = l.transpose();
    let mut left: Vec<DVector<f64>> = Vec::with_capacity(2);
    for j in 0..2 {
        let mut y = DVector::zeros(m);
        y[r + j] = 1.0;
        let Some(mut w) = lt.solve_upper_triangular(&y) else {
            return kernels_svd(a);
        };
        lu.p().inv_permute_rows(&mut w);
        left.push(w);
    }
    let (c1, c2) = (left[0][n], left[1][n]);
    let comb: DVector<f64> = if c1.abs() <= c2.abs() {
        &left[0] * c2 - &left[1] * c1
    } else {
        &left[1] * c1 - &left[0] * c2
    };
    let mut psi = comb.rows(0, n).into_owned();
    let norm = psi.norm();
    if !(norm > 0.0 && norm.is_finite()) {
        return kernels_svd(a);
    }
    psi /= norm;
    (pairs, psi)
}

/// [`kernels`] by one SVD of the square matrix `[a; 0]`: the right singular pairs
/// (ascending, as [`right_singular_pairs`]) and the left singular vector for the smallest
/// singular value (as [`left_null_vector`]).
pub(crate) fn kernels_svd(a: &DMatrix<f64>) -> (Vec<(f64, DVector<f64>)>, DVector<f64>) {
    let (n, m) = a.shape();
    let mut sq = DMatrix::zeros(m, m);
    sq.view_mut((0, 0), (n, m)).copy_from(a);
    let svd = SVD::new(sq, true, true);
    let v_t = svd.v_t.expect("V requested");
    let u = svd.u.expect("U requested");
    let mut order: Vec<usize> = (0..m).collect();
    order.sort_by(|&i, &j| svd.singular_values[i].total_cmp(&svd.singular_values[j]));
    let pairs: Vec<(f64, DVector<f64>)> = order
        .iter()
        .map(|&i| (svd.singular_values[i], v_t.row(i).transpose()))
        .collect();
    // The zero row adds the left vector e_{n+1} to the two smallest: remove it.
    let (u1, u2) = (u.column(order[0]), u.column(order[1]));
    let (c1, c2) = (u1[n], u2[n]);
    let comb: DVector<f64> = if c1.abs() <= c2.abs() {
        u1 * c2 - u2 * c1
    } else {
        u2 * c1 - u1 * c2
    };
    let mut psi = comb.rows(0, n).into_owned();
    let norm = psi.norm();
    if norm > 0.0 {
        psi /= norm;
    } else {
        psi = left_null_vector(a);
    }
    (pairs, psi)
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
    let mut rhs = DVector::zeros(n + 1);
    rhs[n] = 1.0;
    if let Some(s) = bordered_solve(ev, y, t_prev, &rhs)? {
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
    let a = ev.augmented(y)?;
    Ok(Tangent {
        t: kernel_direction(&a, t_prev),
        det_sign: 0.0,
        log_det: f64::NEG_INFINITY,
    })
}

/// Solves the bordered system `[J F_p; borderᵀ] z = rhs` at `y = (x, p)`, with the
/// sign and `ln|det|` of its matrix; `Ok(None)` if it is singular.
///
/// Block elimination (Keller's bordering algorithm) with the problem's factorisation
/// of `J`: writing `border = (c, c_p)`, `rhs = (f, g)`, `z = (u, μ)`,
///
/// ```text
/// J a = F_p,   δ = c_p − cᵀ a,   J w = f,   μ = (g − cᵀ w) / δ,   u = w − μ a,
/// det [J F_p; borderᵀ] = det J · δ.
/// ```
///
/// Block elimination is unstable when `J` is nearly singular (at folds and branch
/// points) even though the bordered matrix is well conditioned there; one step of
/// iterative refinement on the full bordered residual, reusing `a` and `δ`, repairs
/// this as long as `ε cond(J)` is well below 1 (W. Govaerts, *Numerical Methods for
/// Bifurcations of Dynamical Equilibria*, SIAM 2000, ch. 3). The refined solution is
/// accepted if the refinement at least halved the residual, or if its correction was
/// at rounding level (`≤ √ε` relative, the residuals being rounding noise);
/// otherwise, and whenever the factorisation fails or is singular, the system is
/// solved by dense LU of the bordered matrix (`Problem::jacobian`), which also gives
/// the determinant.
pub(crate) fn bordered_solve<P: Problem + ?Sized>(
    ev: &Evaluator<'_, P>,
    y: &DVector<f64>,
    border: &DVector<f64>,
    rhs: &DVector<f64>,
) -> Result<Option<SolveWithDet>, ContinuationError> {
    let (x, p) = ev.split(y);
    let fact = ev.factorize(&x, p)?;
    let fp = ev.dparam(&x, p)?;
    if let Some(s) = block_elimination(ev, fact.as_ref(), &fp, border, rhs)? {
        return Ok(Some(s));
    }
    let j = ev.jacobian(&x, p)?;
    Ok(solve_with_det(bordered_matrix(&j, &fp, border), rhs))
}

/// The block-elimination part of [`bordered_solve`]; `Ok(None)` asks for the dense
/// fallback.
fn block_elimination<P: Problem + ?Sized>(
    ev: &Evaluator<'_, P>,
    fact: &dyn Factorization,
    fp: &DVector<f64>,
    border: &DVector<f64>,
    rhs: &DVector<f64>,
) -> Result<Option<SolveWithDet>, ContinuationError> {
    let n = ev.n;
    let det_j = fact.det_sign();
    let log_det_j = fact.log_abs_det();
    if det_j == 0.0 || !log_det_j.is_finite() {
        return Ok(None);
    }
    let solve = |b: &DVector<f64>| -> Result<Option<DVector<f64>>, ContinuationError> {
        match fact.solve(b) {
            Some(z) => {
                ev.check_vec("factorization solve", &z)?;
                Ok(z.iter().all(|v| v.is_finite()).then_some(z))
            }
            None => Ok(None),
        }
    };
    let c = border.rows(0, n);
    let c_p = border[n];
    let Some(a) = solve(fp)? else {
        return Ok(None);
    };
    let delta = c_p - c.dot(&a);
    if !(delta.is_finite() && delta != 0.0) {
        return Ok(None);
    }
    // One block-elimination solve with the factorisation and `a`, `δ`.
    let eliminate = |r: &DVector<f64>| -> Result<Option<DVector<f64>>, ContinuationError> {
        let Some(w) = solve(&r.rows(0, n).into_owned())? else {
            return Ok(None);
        };
        let mu = (r[n] - c.dot(&w)) / delta;
        let mut z = DVector::zeros(n + 1);
        z.rows_mut(0, n).copy_from(&(w - &a * mu));
        z[n] = mu;
        Ok(z.iter().all(|v| v.is_finite()).then_some(z))
    };
    // Residual rhs − M z of the full bordered system.
    let residual = |z: &DVector<f64>| -> Result<DVector<f64>, ContinuationError> {
        let u = z.rows(0, n).into_owned();
        let ju = fact.apply(&u);
        ev.check_vec("factorization apply", &ju)?;
        let mut r = DVector::zeros(n + 1);
        r.rows_mut(0, n)
            .copy_from(&(rhs.rows(0, n) - ju - fp * z[n]));
        r[n] = rhs[n] - border.dot(z);
        Ok(r)
    };
    let Some(z1) = eliminate(rhs)? else {
        return Ok(None);
    };
    let r1 = residual(&z1)?;
    let Some(dz) = eliminate(&r1)? else {
        return Ok(None);
    };
    let z2 = &z1 + &dz;
    let r2 = residual(&z2)?;
    let (n1, n2) = (max_abs(&r1), max_abs(&r2));
    let accurate = n2 <= REFINE_CONTRACTION * n1 || dz.amax() <= REFINE_NOISE * z2.amax();
    if !(accurate && n2.is_finite()) {
        return Ok(None);
    }
    Ok(Some(SolveWithDet {
        z: z2,
        det_sign: det_j * delta.signum(),
        log_det: log_det_j + delta.abs().ln(),
    }))
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

#[cfg(test)]
mod tests {
    use super::*;

    /// An `n × (n+1)` matrix of rank `n − 1` with entries of mixed sizes (the product of an
    /// `n × (n−1)` and an `(n−1) × (n+1)` factor, rows scaled over six decades), plus a
    /// perturbation of size `eps`.
    fn rank_deficient(n: usize, seed: u64, eps: f64) -> DMatrix<f64> {
        let mut x = seed;
        let mut next = move || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let b = DMatrix::from_fn(n, n - 1, |i, _| {
            next() * 10f64.powf(6.0 * i as f64 / n as f64)
        });
        let c = DMatrix::from_fn(n - 1, n + 1, |_, _| next());
        let e = DMatrix::from_fn(n, n + 1, |_, _| next() * eps);
        b * c + e
    }

    /// The kernels from complete pivoting: orthonormal, annihilated by `a` to rounding
    /// relative to `‖a‖`, the same plane as the SVD's two smallest right singular vectors
    /// (the projectors differ by rounding over the gap to the third singular value), and `ψ`
    /// a unit left null vector.
    #[test]
    fn lu_kernels_match_the_svd() {
        for (n, seed) in [(5usize, 1u64), (40, 7), (120, 99)] {
            let a = rank_deficient(n, seed, 0.0);
            let scale = a.norm();
            let (pairs, psi) = kernels(&a);
            let (svd_pairs, svd_psi) = kernels_svd(&a);
            let (v0, v1) = (&pairs[0].1, &pairs[1].1);
            assert!((v0.norm() - 1.0).abs() < 1e-12 && (v1.norm() - 1.0).abs() < 1e-12);
            assert!(v0.dot(v1).abs() < 1e-12);
            for v in [v0, v1] {
                assert!(
                    (&a * v).norm() < 1e-12 * scale,
                    "n {n}: |a v| = {:e}",
                    (&a * v).norm()
                );
            }
            let proj = |p: &DVector<f64>, q: &DVector<f64>| p * p.transpose() + q * q.transpose();
            // The plane is determined to rounding over the gap to the next singular value.
            let tol = 100.0 * f64::EPSILON * scale / svd_pairs[2].0;
            let diff = (proj(v0, v1) - proj(&svd_pairs[0].1, &svd_pairs[1].1)).norm();
            assert!(
                diff < tol,
                "n {n}: projectors differ by {diff:e} (tolerance {tol:e})"
            );
            assert!((psi.norm() - 1.0).abs() < 1e-12);
            assert!(
                (a.transpose() * &psi).norm() < 1e-12 * scale,
                "n {n}: |ψᵀa|"
            );
            assert!(
                psi.dot(&svd_psi).abs() > 1.0 - tol,
                "n {n}: ψ differs from the SVD's"
            );
        }
        // Near a branch point (rank n − 1 up to 1e-9 relative): the same plane to about that.
        let a = rank_deficient(60, 3, 1e-9);
        let (pairs, _) = kernels(&a);
        let (svd_pairs, _) = kernels_svd(&a);
        let proj = |p: &DVector<f64>, q: &DVector<f64>| p * p.transpose() + q * q.transpose();
        let diff = (proj(&pairs[0].1, &pairs[1].1) - proj(&svd_pairs[0].1, &svd_pairs[1].1)).norm();
        assert!(diff < 1e-5, "perturbed: projectors differ by {diff:e}");
    }
}
