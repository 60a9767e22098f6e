//! A fast stability index for traced states.
//!
//! The same reduction as [`rodloop_solver::Equilibrium::stability`] (Hessian of the
//! Lagrangian in the metric of the quadrature weights, restricted to the tangent space of
//! the closure constraints by Householder reflections, the arclength-shift mode of a uniform
//! rod removed), but the reduced matrix is first tried with a Cholesky factorisation of
//! `Hr + tol·I`: if it succeeds, every eigenvalue exceeds `−tol` and the index is 0 at a
//! third of the cost of one eigenvalue sweep; only otherwise are the eigenvalues computed
//! and counted. The two agree by construction (same matrix, same threshold).

use nalgebra::{DMatrix, DVector};
use rodloop_solver::model::GAUSS_OFFSETS;
use rodloop_solver::periodic::TrigInterpolant;
use rodloop_solver::{SolverError, SurfaceModel};

/// Threshold below which an eigenvalue (units of `D0`) counts as negative (the solver's
/// default, [`rodloop_solver::StabilityOptions`]).
pub(crate) const INDEX_TOLERANCE: f64 = 1e-6;

/// Householder vector `v` (unit, zero above `start`) with `(I − 2vvᵀ) x` a multiple of
/// `e_start` on the rows `start..`; `None` if those rows vanish.
pub(crate) fn householder(x: &DVector<f64>, start: usize) -> Option<DVector<f64>> {
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
pub(crate) fn reflect_both(a: &mut DMatrix<f64>, v: &DVector<f64>) {
    let w = &*a * v;
    let vav = v.dot(&w);
    // P A P = A − 2 v wᵀ − 2 w vᵀ + 4 (vᵀAv) v vᵀ.
    let u = &w - v * vav;
    a.ger(-2.0, v, &u, 1.0);
    a.ger(-2.0, &u, v, 1.0);
}

/// `x ← (I − 2vvᵀ) x`.
pub(crate) fn reflect_vec(x: &mut DVector<f64>, v: &DVector<f64>) {
    let d = 2.0 * v.dot(x);
    x.axpy(-d, v, 1.0);
}

/// Shift mode `dκ/dσ` at the Gauss points (spectral derivative on the two sub-grids).
pub(crate) fn shift_mode(kappa: &[f64], cells: usize) -> Result<DVector<f64>, SolverError> {
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

/// Stability index of the KKT state `z` of `model` (number of eigenvalues of the reduced
/// constrained Hessian below `−INDEX_TOLERANCE`, symmetry mode removed).
pub(crate) fn index(model: &SurfaceModel, z: &[f64]) -> Result<usize, SolverError> {
    let (kappa, mu, _) = model.split(z)?;
    let n = model.n_kappa();
    let w = model.weight();
    let d0 = model.stiffness().kind().reference();
    let mut a = model.lagrangian_hessian(kappa, &mu)? / (w * d0);
    let cj = model.closure_jacobian(kappa)? / w.sqrt();
    let mut shift = if model.stiffness().kind().is_uniform() {
        Some(shift_mode(kappa, model.cells())? * w.sqrt())
    } else {
        None
    };
    let mut cols: Vec<DVector<f64>> = (0..3).map(|k| cj.row(k).transpose()).collect();
    let mut used = 0;
    for k in 0..3 {
        if let Some(v) = householder(&cols[k], used) {
            for col in cols.iter_mut().skip(k) {
                reflect_vec(col, &v);
            }
            reflect_both(&mut a, &v);
            if let Some(s) = shift.as_mut() {
                reflect_vec(s, &v);
            }
            used += 1;
        }
    }
    if let Some(s) = shift {
        if let Some(v) = householder(&s, used) {
            reflect_both(&mut a, &v);
            used += 1;
        }
    }
    let m = n - used;
    let block = a.view((used, used), (m, m)).into_owned();
    let block = (&block + block.transpose()) * 0.5;
    let shifted = &block + DMatrix::identity(m, m) * INDEX_TOLERANCE;
    if shifted.cholesky().is_some() {
        return Ok(0);
    }
    Ok(block
        .symmetric_eigenvalues()
        .iter()
        .filter(|&&e| e < -INDEX_TOLERANCE)
        .count())
}
