//! Stability of an equilibrium: the spectrum of the Hessian of the Lagrangian restricted to
//! the tangent space of the closure constraints, with the symmetry modes removed.
//!
//! * **Constraint tangent space.** Second-order optimality for `min E` subject to `c = 0`
//!   is about `δκᵀ ∇²ℒ δκ` on `{δκ : ∇c δκ = 0}`, `ℒ = E − μ·c`.
//! * **Metric.** The unknowns are `κ_g` at Gauss points with quadrature weights `w = h/2`,
//!   so `δκᵀ W δκ ≈ ∫ δκ_g² ds`. We solve the generalised problem
//!   `Zᵀ∇²ℒZ y = λ ZᵀWZ y` by the substitution `u = W^{1/2} δκ`: the eigenvalues of
//!   `W^{−1/2} ∇²ℒ W^{−1/2}` on the null space of `∇c W^{−1/2}`. They approximate the
//!   eigenvalues of the continuous second variation (an operator `δκ ↦ D δκ − …`), so they
//!   converge as `N` grows instead of scaling with `h`. They are reported in units of `D0`.
//! * **Symmetry modes.** Rigid rotations do not appear in this formulation: `κ_g` is
//!   invariant under them and the frame starts from `X(0) = I`, so there is nothing to
//!   remove. For a uniform rod the shift of the arclength origin is a symmetry of the
//!   continuous problem (broken only at the level of the discretisation error): its mode is
//!   `δκ = dκ/ds`, obtained by spectral differentiation on the two Gauss sub-grids,
//!   projected onto the tangent space and removed; its Rayleigh quotient is reported as the
//!   symmetry eigenvalue (≈ 0 when the split is clean).
//!
//! Implementation: the null-space basis comes from three Householder reflections (QR of
//! `(∇c W^{−1/2})ᵀ`), the shift mode from a fourth; they are applied on both sides of the
//! Hessian (`O(n²)` each), and the remaining block is diagonalised with nalgebra's symmetric
//! eigenvalue routine.

use nalgebra::{DMatrix, DVector};

use crate::model::GAUSS_OFFSETS;
use crate::periodic::TrigInterpolant;
use crate::solve::Equilibrium;
use crate::SolverError;

/// Settings of [`Equilibrium::stability`].
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
    /// Dimension of the reduced space that was diagonalised.
    pub dimension: usize,
    /// The threshold used for the index.
    pub tolerance: f64,
}

/// Householder reflector `I − 2 v vᵀ` (unit `v`, zero above `start`) mapping `x[start..]` to
/// a multiple of `e_start`; `None` when `x[start..]` vanishes.
pub(crate) fn householder(x: &DVector<f64>, start: usize) -> Option<DVector<f64>> {
    let n = x.len();
    let mut v = DVector::zeros(n);
    let norm = x.rows(start, n - start).norm();
    if norm == 0.0 {
        return None;
    }
    for i in start..n {
        v[i] = x[i];
    }
    let alpha = if x[start] >= 0.0 { -norm } else { norm };
    v[start] -= alpha;
    let vn = v.norm();
    if vn == 0.0 {
        return None;
    }
    Some(v / vn)
}

/// `A ← (I − 2vvᵀ) A (I − 2vvᵀ)` for symmetric `A`.
pub(crate) fn reflect_both(a: &mut DMatrix<f64>, v: &DVector<f64>) {
    // P A P = A − 2 v wᵀ − 2 w vᵀ + 4 (vᵀAv) v vᵀ, w = A v.
    let w = &*a * v;
    let vav = v.dot(&w);
    let n = a.nrows();
    for j in 0..n {
        for i in 0..n {
            a[(i, j)] += -2.0 * v[i] * w[j] - 2.0 * w[i] * v[j] + 4.0 * vav * v[i] * v[j];
        }
    }
}

/// `x ← (I − 2vvᵀ) x`.
pub(crate) fn reflect_vec(x: &mut DVector<f64>, v: &DVector<f64>) {
    let d = 2.0 * v.dot(x);
    x.axpy(-d, v, 1.0);
}

impl Equilibrium {
    /// Stability with default options ([`StabilityOptions::default`]).
    pub fn stability(&self) -> Result<Stability, SolverError> {
        self.stability_with(&StabilityOptions::default())
    }

    /// Spectrum of the constrained Hessian (see the module docs), its index, the lowest
    /// eigenvalues and the symmetry eigenvalues.
    pub fn stability_with(&self, opts: &StabilityOptions) -> Result<Stability, SolverError> {
        let model = self.model();
        let kappa = self.kappa();
        let n = model.n_kappa();
        let w = model.weight();
        let d0 = model.stiffness().kind().reference();
        let mut a = model.lagrangian_hessian(kappa, &self.multiplier())? / (w * d0);
        let cj = model.closure_jacobian(kappa)? / w.sqrt();
        // Shift mode u = W^{1/2} dκ/dσ for uniform rods.
        let mut shift = if model.stiffness().kind().is_uniform() {
            let cells = model.cells();
            let mut d = DVector::zeros(n);
            for (j, off) in GAUSS_OFFSETS.iter().enumerate() {
                let sub: Vec<f64> = (0..cells).map(|c| kappa[2 * c + j]).collect();
                let t = TrigInterpolant::with_offset(&sub, off / cells as f64)?;
                for c in 0..cells {
                    d[2 * c + j] = t.derivative((c as f64 + off) / cells as f64) * w.sqrt();
                }
            }
            Some(d)
        } else {
            None
        };
        // Three reflections: Q = P1 P2 P3 with Qᵀ Cᵀ upper triangular; Z = Q[:, 3..].
        let mut ct: Vec<DVector<f64>> = (0..3).map(|k| cj.row(k).transpose()).collect();
        let mut used = 0;
        for k in 0..3 {
            if let Some(v) = householder(&ct[k], used) {
                for col in ct.iter_mut().skip(k) {
                    reflect_vec(col, &v);
                }
                reflect_both(&mut a, &v);
                if let Some(s) = shift.as_mut() {
                    reflect_vec(s, &v);
                }
                used += 1;
            }
        }
        let mut start = used;
        let mut symmetry = Vec::new();
        let mut tangency = Vec::new();
        if let Some(s) = shift {
            let total = s.norm();
            let tangent = s.rows(start, n - start).norm();
            if let Some(v) = householder(&s, start) {
                reflect_both(&mut a, &v);
                symmetry.push(a[(start, start)]);
                tangency.push(if total > 0.0 { tangent / total } else { 0.0 });
                start += 1;
            }
        }
        let m = n - start;
        let block = a.view((start, start), (m, m)).into_owned();
        // Symmetrise against rounding before diagonalising.
        let block = (&block + block.transpose()) * 0.5;
        let mut eig: Vec<f64> = block.symmetric_eigenvalues().iter().copied().collect();
        eig.sort_by(f64::total_cmp);
        let index = eig.iter().filter(|&&e| e < -opts.tolerance).count();
        Ok(Stability {
            index,
            eigenvalues: eig.into_iter().take(opts.count).collect(),
            symmetry_eigenvalues: symmetry,
            symmetry_tangency: tangency,
            dimension: m,
            tolerance: opts.tolerance,
        })
    }

    /// Constrained Hessian spectrum with eigenvectors, for diagnostics and tests: returns
    /// the eigenvalues (ascending, units of `D0`) and the corresponding directions `δκ` in
    /// the original unknowns (each satisfying `∇c δκ = 0`, normalised to `δκᵀWδκ = 1`). The
    /// shift mode is not removed here.
    pub fn constrained_modes(&self) -> Result<(Vec<f64>, Vec<DVector<f64>>), SolverError> {
        let model = self.model();
        let kappa = self.kappa();
        let n = model.n_kappa();
        let w = model.weight();
        let d0 = model.stiffness().kind().reference();
        let mut a = model.lagrangian_hessian(kappa, &self.multiplier())? / (w * d0);
        let cj = model.closure_jacobian(kappa)? / w.sqrt();
        let mut ct: Vec<DVector<f64>> = (0..3).map(|k| cj.row(k).transpose()).collect();
        let mut refl = Vec::new();
        for k in 0..3 {
            if let Some(v) = householder(&ct[k], refl.len()) {
                for col in ct.iter_mut().skip(k) {
                    reflect_vec(col, &v);
                }
                reflect_both(&mut a, &v);
                refl.push(v);
            }
        }
        let start = refl.len();
        let m = n - start;
        let block = a.view((start, start), (m, m)).into_owned();
        let block = (&block + block.transpose()) * 0.5;
        let se = block.symmetric_eigen();
        let mut order: Vec<usize> = (0..m).collect();
        order.sort_by(|&i, &j| se.eigenvalues[i].total_cmp(&se.eigenvalues[j]));
        let mut vals = Vec::with_capacity(m);
        let mut vecs = Vec::with_capacity(m);
        for i in order {
            vals.push(se.eigenvalues[i]);
            let mut u = DVector::zeros(n);
            u.rows_mut(start, m).copy_from(&se.eigenvectors.column(i));
            for v in refl.iter().rev() {
                reflect_vec(&mut u, v);
            }
            vecs.push(u / w.sqrt());
        }
        Ok((vals, vecs))
    }
}
