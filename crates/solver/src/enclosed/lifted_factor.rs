//! The enclosed KKT Jacobian factorised in `O(N)` for the continuation crate: the lifted
//! block form of [`super::lifted`] kept as a [`Factorization`] (solves with any right-hand
//! side, products, determinant), so that pseudo-arclength continuation of an enclosed
//! family (at a fixed contact set, [`super::arclength`]) costs `O(N)` per corrector step
//! instead of the dense LU's `O(N³)`.
//!
//! A vector of the model's unknowns or equations maps to the lifted layout by the
//! Newton step's own assignment ([`EnclosedModel::unlift`] and its inverse here): the
//! curvature unknowns and stationarity rows of cell `c`, the wall multiplier and row of node
//! `c + 1` in block `c`, and `(r0, μ, ν, λ_0)` in the border; the auxiliary recursion rows
//! have a zero right-hand side. A product `J v` fills the auxiliary unknowns of the lifted
//! `v` ([`Lifted::complete`]) and reads the model's rows of `M v`.

use nalgebra::DVector;
use rodloop_continuation::Factorization;

use super::lifted::{unlift_layout, BVec, Factor, LVec, Lifted, K0, L0};
use super::model::EnclosedModel;
use crate::SolverError;

/// The lifted Jacobian of an enclosed state and its block factors.
pub struct LiftedFactor {
    sys: Lifted,
    fac: Factor,
    cells: usize,
    n_primal: usize,
    n_gauge: usize,
    lambda_offset: usize,
    det_sign: f64,
    log_abs_det: f64,
}

impl LiftedFactor {
    /// Assemble and factor the Jacobian of [`EnclosedModel::evaluate`] at `z` in the lifted
    /// form; [`SolverError::SingularJacobian`] where a pivot block is nearly singular.
    pub fn new(model: &EnclosedModel, z: &[f64]) -> Result<Self, SolverError> {
        let ch = model.checked_chain(z)?;
        let adj = model.adjoints(&ch, z);
        let f = model.residual_with(&ch, &adj, z);
        let (mut sys, mut rhs) = (Lifted::default(), LVec::default());
        model.lifted_system(z, &ch, &adj, &f, &mut sys, &mut rhs);
        let mut fac = Factor::default();
        fac.factor(&sys)?;
        let (det_sign, log_abs_det) = fac.determinant(model.cells());
        Ok(Self {
            sys,
            fac,
            cells: model.cells(),
            n_primal: model.n_primal(),
            n_gauge: model.n_gauge(),
            lambda_offset: model.lambda_offset(),
            det_sign,
            log_abs_det,
        })
    }

    /// `v` (unknowns or equations of the model) in the lifted layout, zero in the auxiliary
    /// rows and unknowns.
    fn lift(&self, v: &DVector<f64>) -> LVec {
        let (n, np, lo) = (self.cells, self.n_primal, self.lambda_offset);
        let mut x = LVec::default();
        x.reset(n);
        for c in 0..n {
            let b: &mut BVec = &mut x.blocks[c];
            for i in 0..4 {
                b[K0 + i] = v[4 * c + i];
            }
            if c + 1 < n {
                b[L0] = v[lo + c + 1];
            }
        }
        for k in 0..3 {
            x.border[k] = v[4 * n + k];
        }
        for k in 0..6 + self.n_gauge {
            x.border[3 + k] = v[np + k];
        }
        x.border[9 + self.n_gauge] = v[lo];
        x
    }

    /// The model's rows (or unknowns) of a lifted vector, the inverse of [`Self::lift`] on
    /// them ([`unlift_layout`]).
    fn rows(&self, y: &LVec) -> DVector<f64> {
        unlift_layout(
            self.cells,
            self.n_primal,
            self.n_gauge,
            self.lambda_offset,
            y,
        )
    }

    /// `M x` of the lifted system.
    fn apply_lifted(&self, x: &LVec) -> LVec {
        let mut out = LVec::default();
        self.sys.apply(x, &mut out);
        out
    }
}

impl Factorization for LiftedFactor {
    /// Block elimination and one step of iterative refinement against the lifted system;
    /// `None` where a pivot is zero or the refined residual stays above `1e-9 |b|` plus the
    /// round-off floor `1e-13 max|M| |x|` (the Newton step's own test).
    fn solve(&self, b: &DVector<f64>) -> Option<DVector<f64>> {
        let rhs = self.lift(b);
        let (mut y, mut x, mut dx) = (Vec::new(), LVec::default(), LVec::default());
        if !self.fac.solve(&self.sys, &rhs, &mut y, &mut x) {
            return None;
        }
        let mut r = self.apply_lifted(&x);
        for (a, b) in r.blocks.iter_mut().zip(&rhs.blocks) {
            *a = b - *a;
        }
        r.border = rhs.border - r.border;
        if !self.fac.solve(&self.sys, &r, &mut y, &mut dx) {
            return None;
        }
        for (a, b) in x.blocks.iter_mut().zip(&dx.blocks) {
            *a += b;
        }
        x.border += dx.border;
        let ax = self.apply_lifted(&x);
        let mut err = (ax.border - rhs.border).norm_squared();
        for (a, b) in ax.blocks.iter().zip(&rhs.blocks) {
            err += (a - b).norm_squared();
        }
        let scale = 1e-9 * rhs.norm() + 1e-13 * self.sys.amax() * x.norm();
        (err.sqrt() <= scale.max(1e-300)).then(|| self.rows(&x))
    }

    fn apply(&self, v: &DVector<f64>) -> DVector<f64> {
        let mut x = self.lift(v);
        self.sys.complete(&mut x);
        self.rows(&self.apply_lifted(&x))
    }

    fn det_sign(&self) -> f64 {
        self.det_sign
    }

    fn log_abs_det(&self) -> f64 {
        self.log_abs_det
    }
}
