//! The enclosed KKT Jacobian factorised in `O(N)` for the continuation crate: the lifted
//! block form of [`super::lifted`] kept as a [`Factorization`] (solves with any right-hand
//! side, products, determinant), so that pseudo-arclength continuation of an enclosed
//! family (at a fixed contact set, [`super::arclength`]) costs `O(N)` per corrector step
//! instead of the dense LU's `O(N³)`.
//!
//! A vector of the model's unknowns or equations maps to the lifted layout by the
//! Newton step's own assignment (`lift_layout`, `unlift_layout`): the
//! curvature unknowns and stationarity rows of cell `c`, the wall multiplier and row of node
//! `c + 1` in block `c`, and `(r0, μ, ν, λ_0)` in the border; the auxiliary recursion rows
//! have a zero right-hand side. A product `J v` fills the auxiliary unknowns of the lifted
//! `v` (`Lifted::complete`) and reads the model's rows of `M v`.

use nalgebra::DVector;
use rodloop_continuation::Factorization;

use super::lifted::{lift_layout, unlift_layout, Factor, LVec, Lifted, SolveBuffers};
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

    /// `v` (unknowns or equations of the model) in the lifted layout ([`lift_layout`]).
    fn lift(&self, v: &DVector<f64>) -> LVec {
        lift_layout(
            self.cells,
            self.n_primal,
            self.n_gauge,
            self.lambda_offset,
            v,
        )
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
    /// Block elimination and one step of iterative refinement against the lifted system
    /// (`Factor::solve_refined`, the Newton step's own); `None` where that fails.
    fn solve(&self, b: &DVector<f64>) -> Option<DVector<f64>> {
        let mut buf = SolveBuffers::default();
        self.fac
            .solve_refined(&self.sys, &self.lift(b), &mut buf)
            .then(|| self.rows(&buf.x))
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
