//! Stability of an equilibrium: the spectrum of the Hessian of the Lagrangian restricted to
//! the tangent space of the constraints, with the symmetry modes removed. This module is
//! the one place where that restriction is computed; `solve`, continuation, the diagram's
//! tracing and great-circle buckling all call it.
//!
//! * **Problem.** Second-order optimality for `min E` subject to `c = 0` is about
//!   `δκᵀ ∇²ℒ δκ` on `{δκ : ∇c δκ = 0}`, `ℒ = E − μ·c`. The metric is the energy's,
//!   `W = diag(w_a D0)` with the quadrature weights `w_a = h_c/2`, so that
//!   `δκᵀWδκ ≈ D0 ∫ δκ_g² ds`: the eigenvalues of `Zᵀ∇²ℒZ y = λ ZᵀWZ y` approximate those of
//!   the continuous second variation and converge as `N` grows. They are in units of `D0`.
//! * **Symmetry modes.** Rigid rotations do not appear (`κ_g` is invariant under them and
//!   the frame starts from `X(0) = I`). For a uniform rod the shift of the arclength origin
//!   is a symmetry; the phase condition `φ = 0` is then one more constraint, which removes
//!   that direction (its Rayleigh quotient on the closure tangent space is reported as the
//!   symmetry eigenvalue, ≈ 0 when the split is clean).
//! * **Index in `O(N)`.** By Sylvester's law of inertia (with Haynsworth's additivity), the
//!   number of eigenvalues below `σ` is the number of negative eigenvalues of the KKT
//!   matrix shifted by `−σW`, minus the number of constraints; [`crate::kkt`] computes that
//!   inertia from its block factorisation. The index uses `σ = −tolerance`.
//! * **Lowest eigenvalues in `O(N)` per iteration.** Shift-invert Lanczos in the `W` inner
//!   product with a shift `σ` below the spectrum (found by inertia counts): each iteration
//!   is one solve with the factorised shifted KKT matrix, whose curvature part is
//!   `(A − σW)⁻¹W` restricted to the constraint tangent space (C. Lanczos 1950; shift-invert
//!   as in Ericsson & Ruhe, Math. Comp. 35, 1980). Full reorthogonalisation.
//! * **Dense reduction** ([`TangentReduction`]): Householder reflections onto the null space
//!   of a constraint Jacobian, for small problems and when eigenvectors are needed
//!   ([`Equilibrium::constrained_modes`], the buckling pencil of a great circle).

use nalgebra::{DMatrix, DVector};

use crate::kkt::KktFactor;
use crate::model::{SurfaceModel, GAUSS_OFFSETS};
use crate::periodic::TrigInterpolant;
use crate::solve::Equilibrium;
use crate::SolverError;

/// Settings of [`Equilibrium::stability_with`].
#[derive(Clone, Debug, PartialEq)]
pub struct StabilityOptions {
    /// How many of the lowest eigenvalues to report.
    pub count: usize,
    /// Eigenvalues below `−tolerance` (units of `D0`) count as negative.
    pub tolerance: f64,
}

impl Default for StabilityOptions {
    fn default() -> Self {
        Self {
            count: 6,
            tolerance: 1e-6,
        }
    }
}

/// Constrained Hessian spectrum of an equilibrium.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Stability {
    /// Number of eigenvalues below `−tolerance` (0: local minimum).
    pub index: usize,
    /// The lowest eigenvalues (ascending), symmetry modes removed, units of `D0`.
    pub eigenvalues: Vec<f64>,
    /// Rayleigh quotients of the removed symmetry modes (the arclength shift for a uniform
    /// rod; empty otherwise), units of `D0`.
    pub symmetry_eigenvalues: Vec<f64>,
    /// Fraction of the shift mode lying in the constraint tangent space (`≈ 1` for a clean
    /// split; empty for non-uniform rods).
    pub symmetry_tangency: Vec<f64>,
    /// Dimension of the constrained space.
    pub dimension: usize,
    /// The threshold used for the index.
    pub tolerance: f64,
}

/// Number of eigenvalues below `−tolerance` of the constrained Hessian at the KKT state `z`
/// of `model` (symmetry modes removed): the stability index, in `O(N)`. Falls back to the
/// dense reduction if the block factorisation meets a singular pivot block.
pub fn index(model: &SurfaceModel, z: &[f64], tolerance: f64) -> Result<usize, SolverError> {
    match KktFactor::new(model, z, -tolerance) {
        Ok(f) => Ok(f.reduced_negative_count()),
        Err(SolverError::SingularJacobian { .. }) => {
            let vals = dense_spectrum(model, z)?;
            Ok(vals.iter().filter(|v| **v < -tolerance).count())
        }
        Err(e) => Err(e),
    }
}

/// Metric weights `W_aa = w_a D0` of the curvature unknowns.
fn metric(model: &SurfaceModel) -> DVector<f64> {
    let d0 = model.stiffness().kind().reference();
    DVector::from_fn(model.n_kappa(), |a, _| model.cell_weight(a / 2) * d0)
}

/// All constraint gradients (closure rows, then the phase row) as rows of a matrix.
fn constraint_rows(model: &SurfaceModel, kappa: &[f64]) -> Result<DMatrix<f64>, SolverError> {
    let cj = model.closure_jacobian(kappa)?;
    let n = model.n_kappa();
    let m = model.n_multipliers();
    let mut j = DMatrix::zeros(m, n);
    j.rows_mut(0, 3).copy_from(&cj);
    if let Some(ph) = model.phase() {
        for (a, g) in ph.gradient().iter().enumerate() {
            j[(3, a)] = *g;
        }
    }
    Ok(j)
}

/// Dense constrained spectrum (all eigenvalues, ascending) through [`TangentReduction`].
fn dense_spectrum(model: &SurfaceModel, z: &[f64]) -> Result<Vec<f64>, SolverError> {
    let (kappa, mu, _) = model.split(z)?;
    let h = model.lagrangian_hessian(kappa, &mu)?;
    let red = TangentReduction::new(&constraint_rows(model, kappa)?, &metric(model), 0.0)?;
    let mut vals: Vec<f64> = red
        .reduce(&h)
        .symmetric_eigenvalues()
        .iter()
        .copied()
        .collect();
    vals.sort_by(f64::total_cmp);
    Ok(vals)
}

/// Restriction of symmetric matrices to the null space of a constraint Jacobian `J`
/// (rows = constraint gradients), in the metric `W` (diagonal): with `u = W^{1/2} δκ`, the
/// null space of `J W^{−1/2}` is spanned by the last columns of a product of Householder
/// reflections (a QR factorisation of `(J W^{−1/2})ᵀ`).
#[derive(Clone, Debug)]
pub struct TangentReduction {
    reflectors: Vec<DVector<f64>>,
    sqrt_w: DVector<f64>,
}

/// Householder vector `v` (unit, zero above `start`) with `(I − 2vvᵀ) x` a multiple of
/// `e_start` on the rows `start..`; `None` if those rows vanish.
fn householder(x: &DVector<f64>, start: usize) -> Option<DVector<f64>> {
    let n = x.len();
    let norm = x.rows(start, n - start).norm();
    if norm == 0.0 || !norm.is_finite() {
        return None;
    }
    let mut v = DVector::zeros(n);
    v.rows_mut(start, n - start)
        .copy_from(&x.rows(start, n - start));
    v[start] += if x[start] >= 0.0 { norm } else { -norm };
    let vn = v.norm();
    (vn > 0.0).then(|| v / vn)
}

/// `A ← P A P` with `P = I − 2vvᵀ`, `A` symmetric.
fn reflect_both(a: &mut DMatrix<f64>, v: &DVector<f64>) {
    let w = &*a * v;
    let vav = v.dot(&w);
    // P A P = A − 2 v wᵀ − 2 w vᵀ + 4 (vᵀAv) v vᵀ.
    let u = &w - v * vav;
    a.ger(-2.0, v, &u, 1.0);
    a.ger(-2.0, &u, v, 1.0);
}

/// `x ← (I − 2vvᵀ) x`.
fn reflect_vec(x: &mut DVector<f64>, v: &DVector<f64>) {
    let d = 2.0 * v.dot(x);
    x.axpy(-d, v, 1.0);
}

impl TangentReduction {
    /// Reduction onto `{δκ : J δκ = 0}` in the metric `diag(weights)`. Rows of `J` whose
    /// norm (in the metric) is below `drop` times the largest are ignored (a great circle's
    /// closure has rank 2).
    pub fn new(j: &DMatrix<f64>, weights: &DVector<f64>, drop: f64) -> Result<Self, SolverError> {
        let n = j.ncols();
        if weights.len() != n {
            return Err(SolverError::WrongLength {
                expected: n,
                found: weights.len(),
            });
        }
        let sqrt_w = weights.map(f64::sqrt);
        let mut cols: Vec<DVector<f64>> = (0..j.nrows())
            .map(|k| j.row(k).transpose().component_div(&sqrt_w))
            .collect();
        let big = cols.iter().map(|c| c.norm()).fold(0.0, f64::max);
        cols.retain(|c| c.norm() > drop * big);
        let mut reflectors = Vec::new();
        for k in 0..cols.len() {
            if let Some(v) = householder(&cols[k], reflectors.len()) {
                for col in cols.iter_mut().skip(k) {
                    reflect_vec(col, &v);
                }
                reflectors.push(v);
            }
        }
        Ok(Self { reflectors, sqrt_w })
    }

    /// Number of independent constraints removed.
    pub fn removed(&self) -> usize {
        self.reflectors.len()
    }

    /// `Zᵀ (W^{−1/2} A W^{−1/2}) Z` (symmetrised), of size `n − removed`.
    pub fn reduce(&self, a: &DMatrix<f64>) -> DMatrix<f64> {
        let n = a.nrows();
        let mut b = a.clone();
        for i in 0..n {
            for k in 0..n {
                b[(i, k)] /= self.sqrt_w[i] * self.sqrt_w[k];
            }
        }
        for v in &self.reflectors {
            reflect_both(&mut b, v);
        }
        let p = self.removed();
        let block = b.view((p, p), (n - p, n - p)).into_owned();
        (&block + block.transpose()) * 0.5
    }

    /// The direction `δκ` (original unknowns) of a reduced vector `y`; `δκᵀWδκ = |y|²`.
    pub fn lift(&self, y: &DVector<f64>) -> DVector<f64> {
        let n = self.sqrt_w.len();
        let p = self.removed();
        let mut u = DVector::zeros(n);
        u.rows_mut(p, n - p).copy_from(y);
        for v in self.reflectors.iter().rev() {
            reflect_vec(&mut u, v);
        }
        u.component_div(&self.sqrt_w)
    }
}

/// The extreme eigenpairs of a symmetric matrix: its `per_end` lowest and `per_end` highest
/// eigenvalues with unit eigenvectors, by [`extreme_eigenpairs`]. The first pair of each end
/// is converged; a further one is converged too, or else lies more than `SEPARATED` (10⁻³) of the
/// spectral radius inside the spectrum (then it is a Ritz pair within its residual of an
/// eigenvalue: enough to tell that the extreme has no degenerate partner).
#[derive(Clone, Debug)]
pub struct Extremes {
    /// The lowest eigenvalues, ascending, with their eigenvectors.
    pub low: Vec<(f64, DVector<f64>)>,
    /// The highest eigenvalues, descending, with their eigenvectors.
    pub high: Vec<(f64, DVector<f64>)>,
}

/// Distance (relative to the spectral radius) from the extreme eigenvalue beyond which
/// [`extreme_eigenpairs`] does not wait for the next Ritz pair of its end to converge.
const SEPARATED: f64 = 1e-3;

/// Matrices up to this size are decomposed densely by [`extreme_eigenpairs`].
const EXTREMES_DENSE_LIMIT: usize = 48;

/// Relative residual `‖A y − θ y‖ / max|θ|` at which [`extreme_eigenpairs`] accepts a Ritz
/// pair: the Ritz value is then within the residual squared over the gap to the rest of the
/// spectrum, the vector within the residual over the gap.
const EXTREMES_RESIDUAL: f64 = 1e-12;

/// The `per_end` lowest and highest eigenpairs of the symmetric matrix `a` (the buckling
/// pencil of a great circle, whose spectrum has a few isolated extremes above a bulk near
/// zero): block Lanczos with block size 2 (a degenerate pair, the sine and cosine of one
/// mode, is found as a pair) and full reorthogonalisation, with Rayleigh–Ritz on the Krylov
/// basis every step until the wanted Ritz pairs have relative residuals below
/// `EXTREMES_RESIDUAL` (10⁻¹²) (C. Lanczos 1950; G. H. Golub & R. Underwood 1977 for the block
/// form; Golub & Van Loan §10.3). Each step costs two products with `a`, `O(n²)`, against
/// `O(n³)` for the dense decomposition, which small matrices and a basis that fills the space
/// fall back to.
pub fn extreme_eigenpairs(a: &DMatrix<f64>, per_end: usize) -> Extremes {
    let n = a.nrows();
    if per_end == 0 {
        return Extremes {
            low: Vec::new(),
            high: Vec::new(),
        };
    }
    let dense = || {
        let se = a.clone().symmetric_eigen();
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by(|&i, &j| se.eigenvalues[i].total_cmp(&se.eigenvalues[j]));
        let pair = |i: usize| (se.eigenvalues[i], se.eigenvectors.column(i).into_owned());
        Extremes {
            low: order.iter().take(per_end).map(|&i| pair(i)).collect(),
            high: order.iter().rev().take(per_end).map(|&i| pair(i)).collect(),
        }
    };
    if n <= EXTREMES_DENSE_LIMIT.max(4 * per_end) {
        return dense();
    }
    // Orthonormal Krylov basis and its images under `a`.
    let mut basis: Vec<DVector<f64>> = Vec::new();
    let mut images: Vec<DVector<f64>> = Vec::new();
    // Append `w` orthogonalised against the basis (twice: full reorthogonalisation); false
    // where nothing of it is left.
    let push = |basis: &mut Vec<DVector<f64>>, mut w: DVector<f64>| -> bool {
        let size = w.norm();
        for _ in 0..2 {
            for q in basis.iter() {
                let c = q.dot(&w);
                w.axpy(-c, q, 1.0);
            }
        }
        let left = w.norm();
        if left.is_nan() || left <= 1e-10 * size {
            return false;
        }
        basis.push(w / left);
        true
    };
    // Deterministic start with every harmonic present in both vectors.
    push(
        &mut basis,
        DVector::from_fn(n, |i, _| 1.0 + (i as f64 * 0.754_877_666_2).sin()),
    );
    push(
        &mut basis,
        DVector::from_fn(n, |i, _| (i as f64 * 0.569_840_291 + 0.5).cos()),
    );
    let mut next = 0;
    loop {
        // Images of the newest block, and the next block from them.
        let fresh: Vec<DVector<f64>> = basis[next..].iter().map(|q| a * q).collect();
        next = basis.len();
        images.extend(fresh.iter().cloned());
        let mut grew = false;
        for w in fresh {
            grew |= push(&mut basis, w);
        }
        let k = images.len();
        if k >= 4 * per_end {
            // Rayleigh–Ritz on the part of the basis with images.
            let q = DMatrix::from_columns(&basis[..k]);
            let aq = DMatrix::from_columns(&images);
            let h = q.transpose() * &aq;
            let h = (&h + h.transpose()) * 0.5;
            let se = h.symmetric_eigen();
            let mut order: Vec<usize> = (0..k).collect();
            order.sort_by(|&i, &j| se.eigenvalues[i].total_cmp(&se.eigenvalues[j]));
            let scale = se.eigenvalues.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let pair = |i: usize| {
                let y = se.eigenvectors.column(i);
                let theta = se.eigenvalues[i];
                let vector = &q * y;
                let residual = (&aq * y - &vector * theta).norm();
                (theta, vector, residual)
            };
            let ends: Vec<usize> = order
                .iter()
                .take(per_end)
                .chain(order.iter().rev().take(per_end))
                .copied()
                .collect();
            let pairs: Vec<(f64, DVector<f64>, f64)> = ends.iter().map(|&i| pair(i)).collect();
            // Converged: at each end the extreme pair, and the next one unless it lies well
            // inside the spectrum (a bulk whose Ritz pairs converge slowly; a degenerate
            // partner of the extreme converges with it, the block holding both).
            let tol = EXTREMES_RESIDUAL * scale.max(f64::MIN_POSITIVE);
            let done = pairs.chunks(per_end).all(|end| {
                let (first, _, r0) = &end[0];
                *r0 <= tol
                    && end[1..].iter().all(|(theta, _, r)| {
                        *r <= tol || (theta - first).abs() > SEPARATED * scale + r
                    })
            });
            if done {
                let mut it = pairs.into_iter().map(|(t, v, _)| (t, v));
                let low = it.by_ref().take(per_end).collect();
                let high = it.collect();
                return Extremes { low, high };
            }
        }
        if !grew || basis.len() + 2 > n {
            return dense();
        }
    }
}

/// Shift mode `dκ/dσ` at the Gauss points of a uniform mesh (spectral derivative on the two
/// interleaved sub-grids).
fn shift_mode(kappa: &[f64], cells: usize) -> Result<DVector<f64>, SolverError> {
    let mut d = DVector::zeros(2 * cells);
    for (j, off) in GAUSS_OFFSETS.iter().enumerate() {
        let sub: Vec<f64> = (0..cells).map(|c| kappa[2 * c + j]).collect();
        let t = TrigInterpolant::with_offset(&sub, off / cells as f64)?;
        for c in 0..cells {
            d[2 * c + j] = t.derivative((c as f64 + off) / cells as f64);
        }
    }
    Ok(d)
}

/// Lowest `count` eigenvalues of the constrained pencil by shift-invert Lanczos; stops when
/// the wanted Ritz values change by less than `1e-7` (relative) over five steps.
fn lanczos_lowest(
    model: &SurfaceModel,
    z: &[f64],
    count: usize,
    dim: usize,
) -> Result<Vec<f64>, SolverError> {
    let wdiag = metric(model);
    let n = model.n_kappa();
    // A shift below the spectrum, as close as the inertia allows (clusters of eigenvalues
    // separate better the closer the shift).
    let mut sigma = -0.05;
    let mut factor = None;
    for _ in 0..40 {
        match KktFactor::new(model, z, sigma) {
            Ok(f) if f.reduced_negative_count() == 0 => {
                factor = Some(f);
                break;
            }
            Ok(_) => sigma *= 4.0,
            Err(SolverError::SingularJacobian { .. }) => sigma *= 1.1,
            Err(e) => return Err(e),
        }
    }
    let factor = factor.ok_or_else(|| {
        SolverError::InvalidInput("no shift below the constrained spectrum was found".into())
    })?;
    let apply = |v: &DVector<f64>| -> Result<DVector<f64>, SolverError> {
        let mut b = DVector::zeros(model.dim());
        for a in 0..n {
            b[a] = wdiag[a] * v[a];
        }
        let x = factor
            .solve(&b)
            .ok_or(SolverError::SingularJacobian { iteration: 0 })?;
        Ok(x.rows(0, n).into_owned())
    };
    let mdot = |a: &DVector<f64>, b: &DVector<f64>| a.component_mul(&wdiag).dot(b);
    // Deterministic start with every harmonic present, projected by one application.
    let start = DVector::from_fn(n, |a, _| 1.0 + ((a as f64) * 0.7548776662).sin());
    let mut q = apply(&start)?;
    let nq = mdot(&q, &q).sqrt();
    q /= nq;
    let max_steps = dim.min(80);
    let mut basis: Vec<DVector<f64>> = vec![q];
    let mut alpha = Vec::new();
    let mut beta: Vec<f64> = Vec::new();
    let mut ritz: Vec<f64> = Vec::new();
    for j in 0..max_steps {
        let mut w = apply(&basis[j])?;
        let a = mdot(&basis[j], &w);
        alpha.push(a);
        for _ in 0..2 {
            for qi in &basis {
                let c = mdot(qi, &w);
                w.axpy(-c, qi, 1.0);
            }
        }
        let b = mdot(&w, &w).sqrt();
        let k = alpha.len();
        let last = b <= 1e-14 * a.abs().max(1e-300) || j + 1 == max_steps;
        // Ritz values of the tridiagonal matrix, every fifth step (an eigen-decomposition of
        // the k×k matrix each step would cost more than the Lanczos steps themselves).
        if !(last || (k >= count.min(dim) && k % 5 == 0)) {
            beta.push(b);
            basis.push(w / b);
            continue;
        }
        let theta = tridiagonal_largest(&alpha, &beta, count.min(k));
        // Converged when the wanted Ritz values moved by less than 1e-7 (relative) since
        // the previous check (five steps earlier).
        let converged = theta.len() == ritz.len()
            && theta
                .iter()
                .zip(&ritz)
                .all(|(a, b)| (a - b).abs() <= 1e-7 * a.abs().max(1e-300));
        ritz = theta;
        if converged || last {
            break;
        }
        beta.push(b);
        basis.push(w / b);
    }
    let mut vals: Vec<f64> = ritz
        .iter()
        .filter(|th| **th > 0.0)
        .map(|th| sigma + 1.0 / th)
        .collect();
    vals.sort_by(f64::total_cmp);
    Ok(vals)
}

/// The `count` largest eigenvalues (descending) of the symmetric tridiagonal matrix with
/// diagonal `alpha` and off-diagonal `beta`, by bisection on Sturm counts (W. Givens 1954;
/// Golub & Van Loan §8.4.1), `O(k)` per count.
fn tridiagonal_largest(alpha: &[f64], beta: &[f64], count: usize) -> Vec<f64> {
    let k = alpha.len();
    // Number of eigenvalues below x (LDLᵀ pivots of T − xI).
    let below = |x: f64| -> usize {
        let mut n = 0;
        let mut d = 1.0;
        for i in 0..k {
            let b2 = if i > 0 {
                beta[i - 1] * beta[i - 1]
            } else {
                0.0
            };
            d = alpha[i] - x - if i > 0 { b2 / d } else { 0.0 };
            if d == 0.0 {
                d = -f64::EPSILON * (alpha[i].abs() + x.abs()).max(f64::MIN_POSITIVE);
            }
            if d < 0.0 {
                n += 1;
            }
        }
        n
    };
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for i in 0..k {
        let r = if i > 0 { beta[i - 1].abs() } else { 0.0 }
            + if i + 1 < k { beta[i].abs() } else { 0.0 };
        lo = lo.min(alpha[i] - r);
        hi = hi.max(alpha[i] + r);
    }
    let mut out = Vec::with_capacity(count);
    for j in 0..count.min(k) {
        // The eigenvalue with exactly k − 1 − j eigenvalues below it.
        let target = k - 1 - j;
        let (mut a, mut b) = (lo, hi);
        for _ in 0..200 {
            let m = 0.5 * (a + b);
            if m <= a || m >= b || (b - a) <= 1e-15 * m.abs().max(1e-300) {
                break;
            }
            if below(m) <= target {
                a = m;
            } else {
                b = m;
            }
        }
        out.push(0.5 * (a + b));
    }
    out
}

/// Problems up to this many curvature unknowns use the dense reduction for the eigenvalues.
const DENSE_LIMIT: usize = 160;

impl Equilibrium {
    /// Stability with default options ([`StabilityOptions::default`]).
    pub fn stability(&self) -> Result<Stability, SolverError> {
        self.stability_with(&StabilityOptions::default())
    }

    /// Spectrum of the constrained Hessian (see the module docs): the index from the
    /// inertia of the shifted KKT matrix, the lowest eigenvalues (shift-invert Lanczos, or
    /// the dense reduction for small problems), and the symmetry eigenvalues.
    pub fn stability_with(&self, opts: &StabilityOptions) -> Result<Stability, SolverError> {
        let model = self.model();
        let z = self.state();
        let kappa = self.kappa();
        let n = model.n_kappa();
        let dimension = n - model.n_multipliers();
        let index = index(model, &z, opts.tolerance)?;
        let mut eigenvalues = if n <= DENSE_LIMIT {
            dense_spectrum(model, &z)?
        } else {
            lanczos_lowest(model, &z, opts.count, dimension)?
        };
        eigenvalues.truncate(opts.count);
        let mut symmetry = Vec::new();
        let mut tangency = Vec::new();
        if model.phase().is_some() {
            // Shift mode projected onto the closure tangent space in the metric W.
            let wdiag = metric(model);
            let s = shift_mode(kappa, model.cells())?;
            let cj = model.closure_jacobian(kappa)?;
            let winv_ct = DMatrix::from_fn(n, 3, |a, k| cj[(k, a)] / wdiag[a]);
            let g = &cj * &winv_ct;
            let rhs = &cj * &s;
            let y = (g + DMatrix::identity(3, 3) * 1e-300)
                .lu()
                .solve(&rhs)
                .unwrap_or_else(|| DVector::zeros(3));
            let st = &s - winv_ct * y;
            let norm = |v: &DVector<f64>| v.component_mul(&wdiag).dot(v);
            let hv = model.hessian_vector(kappa, &self.multiplier(), st.as_slice())?;
            let q = DVector::from_vec(hv).dot(&st) / norm(&st);
            symmetry.push(q);
            tangency.push((norm(&st) / norm(&s)).sqrt());
        }
        Ok(Stability {
            index,
            eigenvalues,
            symmetry_eigenvalues: symmetry,
            symmetry_tangency: tangency,
            dimension,
            tolerance: opts.tolerance,
        })
    }

    /// Constrained Hessian spectrum with eigenvectors (dense; for diagnostics, tests and
    /// small problems): the eigenvalues (ascending, units of `D0`) of the Hessian on the
    /// closure tangent space (the shift mode is not removed here) and the corresponding
    /// directions `δκ`, each with `∇c δκ = 0` and `δκᵀWδκ = 1`.
    pub fn constrained_modes(&self) -> Result<(Vec<f64>, Vec<DVector<f64>>), SolverError> {
        let model = self.model();
        let kappa = self.kappa();
        let h = model.lagrangian_hessian(kappa, &self.multiplier())?;
        let red = TangentReduction::new(&model.closure_jacobian(kappa)?, &metric(model), 0.0)?;
        let se = red.reduce(&h).symmetric_eigen();
        let mut order: Vec<usize> = (0..se.eigenvalues.len()).collect();
        order.sort_by(|&i, &j| se.eigenvalues[i].total_cmp(&se.eigenvalues[j]));
        let vals = order.iter().map(|&i| se.eigenvalues[i]).collect();
        let vecs = order
            .iter()
            .map(|&i| red.lift(&se.eigenvectors.column(i).into_owned()))
            .collect();
        Ok((vals, vecs))
    }
}
