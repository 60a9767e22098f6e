//! The KKT system as a [`rodloop_continuation::Problem`] with parameter `L̄` (the
//! [`ParamProblem`] of [`SurfaceModel`] and [`Param::Lbar`], with helpers to start from and
//! return to [`Equilibrium`]s).
//!
//! State `x = z = (κ, μ, ν)` (see [`SurfaceModel::kkt_residual`]), parameter `p = L̄`. The
//! number of cells, the stiffness profile (a function of `σ = s/L`) and the phase condition
//! (reference held fixed in `σ`) do not change with `L̄`; the cell length `h = 2πR L̄/N`
//! does, and `∂F/∂L̄` is analytic ([`SurfaceModel::kkt_dlbar`]).

use nalgebra::{DMatrix, DVector};

use crate::model::SurfaceModel;
use crate::param::Param;
use crate::seam::ParamProblem;
use crate::solve::{solve_from_state, Equilibrium, SolveOptions};
use crate::SolverError;

/// Continuation problem in `L̄` for a fixed discretisation.
#[derive(Clone, Debug)]
pub struct LbarProblem {
    inner: ParamProblem<SurfaceModel>,
}

impl LbarProblem {
    /// Wrap a model (its `L̄` is ignored: the parameter is passed to every evaluation). For a
    /// uniform rod the model should carry a phase condition, e.g. the one of an
    /// [`Equilibrium`] ([`LbarProblem::from_equilibrium`]).
    pub fn new(model: SurfaceModel) -> Self {
        Self {
            inner: ParamProblem::new(model, Param::Lbar).expect("every model has an L̄"),
        }
    }

    /// The problem of an equilibrium's model and its state `(x, L̄)` to start from.
    pub fn from_equilibrium(eq: &Equilibrium) -> (Self, DVector<f64>, f64) {
        (
            Self::new(eq.model().clone()),
            DVector::from_vec(eq.state()),
            eq.lbar(),
        )
    }

    /// The model at parameter `lbar`.
    pub fn model_at(&self, lbar: f64) -> Result<SurfaceModel, SolverError> {
        self.inner.model_at(lbar)
    }

    /// Re-solve at `(x, L̄)` (e.g. a continuation point) and return the equilibrium with its
    /// forces, energies and stability.
    pub fn equilibrium(
        &self,
        x: &DVector<f64>,
        lbar: f64,
        opts: &SolveOptions,
    ) -> Result<Equilibrium, SolverError> {
        solve_from_state(self.model_at(lbar)?, x.as_slice().to_vec(), opts)
    }
}

impl rodloop_continuation::Problem for LbarProblem {
    type Error = SolverError;

    fn dim(&self) -> usize {
        self.inner.dim()
    }

    fn residual(&self, x: &DVector<f64>, p: f64) -> Result<DVector<f64>, SolverError> {
        self.inner.residual(x, p)
    }

    fn jacobian(&self, x: &DVector<f64>, p: f64) -> Result<DMatrix<f64>, SolverError> {
        self.inner.jacobian(x, p)
    }

    fn dparam(&self, x: &DVector<f64>, p: f64) -> Result<DVector<f64>, SolverError> {
        self.inner.dparam(x, p)
    }

    fn factorize(
        &self,
        x: &DVector<f64>,
        p: f64,
    ) -> Result<Box<dyn rodloop_continuation::Factorization + '_>, SolverError> {
        self.inner.factorize(x, p)
    }
}
