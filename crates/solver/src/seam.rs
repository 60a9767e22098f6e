//! The model seam: what a confinement model provides so that solving, stability,
//! continuation and the branch diagram can work with it without knowing its unknowns.
//!
//! A model is a discretised equilibrium problem written as a KKT system `F(z; θ) = 0` in
//! its own unknowns `z` (curvatures, positions, multipliers, …), with the scene parameters
//! `θ` addressed by name ([`Param`]). [`ParamProblem`] turns any model and any parameter
//! into a [`rodloop_continuation::Problem`], factorising with the model's own linear
//! algebra (`O(N)` for [`SurfaceModel`]).

use nalgebra::{DMatrix, DVector};
use rodloop_continuation::Factorization;

use crate::kkt::KktFactor;
use crate::model::SurfaceModel;
use crate::param::Param;
use crate::SolverError;

/// A confinement model (surface today; enclosed loops next). Implementations must keep
/// every method consistent with [`Confinement::residual`]: the Jacobian, the factorised
/// Jacobian and the parameter derivatives are its exact derivatives (tests compare them
/// with finite differences).
pub trait Confinement: Clone + Send + Sync {
    /// The model's own factorisation of its Jacobian (block-banded for the surface
    /// model), which knows its inertia.
    type Factor: Factorization + Inertia + 'static;
    /// Number of unknowns (and equations) of the KKT system.
    fn dim(&self) -> usize;
    /// Number of equality constraints (their multipliers are among the unknowns).
    fn n_constraints(&self) -> usize;
    /// KKT residual `F(z)`.
    fn residual(&self, z: &[f64]) -> Result<DVector<f64>, SolverError>;
    /// Dense Jacobian `∂F/∂z` (for small problems and tests).
    fn jacobian(&self, z: &[f64]) -> Result<DMatrix<f64>, SolverError>;
    /// `∂F/∂z` factorised, shifted by `−shift·W` in the model's energy metric `W` (shift 0
    /// for Newton steps); the factorisation knows its inertia.
    fn factorize(&self, z: &[f64], shift: f64) -> Result<Self::Factor, SolverError>;
    /// `(∂F/∂z) dz` without forming the matrix.
    fn apply(&self, z: &[f64], dz: &[f64]) -> Result<DVector<f64>, SolverError>;
    /// The value of a named parameter.
    fn param(&self, p: Param) -> Result<f64, SolverError>;
    /// The same model with a named parameter changed (same discretisation).
    fn with_param(&self, p: Param, value: f64) -> Result<Self, SolverError>;
    /// `∂F/∂θ` at fixed `z`.
    fn dparam(&self, z: &[f64], p: Param) -> Result<DVector<f64>, SolverError>;
    /// Stability index at `z`: eigenvalues below `−tolerance` of the Hessian of the
    /// Lagrangian on the tangent space of the active constraints, symmetry modes removed.
    fn index(&self, z: &[f64], tolerance: f64) -> Result<usize, SolverError>;
    /// Energy `E R/(π D0)` of the state `z`.
    fn energy(&self, z: &[f64]) -> Result<f64, SolverError>;
    /// Resolution-independent norm of a residual (convergence tests).
    fn residual_norm(&self, f: &DVector<f64>) -> f64;
}

/// The inertia a model's factorisation reports: the stability index at a shift comes
/// from it (Sylvester's law), without an eigen-decomposition.
pub trait Inertia {
    /// Number of eigenvalues below the shift of the constrained Hessian.
    fn reduced_negative_count(&self) -> usize;
}

impl Inertia for ModelFactor {
    fn reduced_negative_count(&self) -> usize {
        self.inner.reduced_negative_count()
    }
}

/// A factorised model Jacobian with its inertia.
pub struct ModelFactor {
    inner: KktFactor,
}

impl ModelFactor {
    /// Number of eigenvalues below the shift of the constrained Hessian.
    pub fn reduced_negative_count(&self) -> usize {
        self.inner.reduced_negative_count()
    }

    /// The block factorisation.
    pub fn kkt(&self) -> &KktFactor {
        &self.inner
    }
}

impl Factorization for ModelFactor {
    fn solve(&self, b: &DVector<f64>) -> Option<DVector<f64>> {
        self.inner.solve(b)
    }
    fn apply(&self, v: &DVector<f64>) -> DVector<f64> {
        self.inner.apply(v)
    }
    fn det_sign(&self) -> f64 {
        self.inner.det_sign()
    }
    fn log_abs_det(&self) -> f64 {
        self.inner.log_abs_det()
    }
}

impl Confinement for SurfaceModel {
    type Factor = ModelFactor;
    fn dim(&self) -> usize {
        SurfaceModel::dim(self)
    }
    fn n_constraints(&self) -> usize {
        self.n_multipliers()
    }
    fn residual(&self, z: &[f64]) -> Result<DVector<f64>, SolverError> {
        self.kkt_residual(z)
    }
    fn jacobian(&self, z: &[f64]) -> Result<DMatrix<f64>, SolverError> {
        self.kkt_jacobian(z)
    }
    fn factorize(&self, z: &[f64], shift: f64) -> Result<ModelFactor, SolverError> {
        Ok(ModelFactor {
            inner: KktFactor::new(self, z, shift)?,
        })
    }
    fn apply(&self, z: &[f64], dz: &[f64]) -> Result<DVector<f64>, SolverError> {
        self.kkt_apply(z, dz)
    }
    fn param(&self, p: Param) -> Result<f64, SolverError> {
        SurfaceModel::param(self, p)
    }
    fn with_param(&self, p: Param, value: f64) -> Result<Self, SolverError> {
        SurfaceModel::with_param(self, p, value)
    }
    fn dparam(&self, z: &[f64], p: Param) -> Result<DVector<f64>, SolverError> {
        self.kkt_dparam(z, p)
    }
    fn index(&self, z: &[f64], tolerance: f64) -> Result<usize, SolverError> {
        crate::stability::index(self, z, tolerance)
    }
    fn energy(&self, z: &[f64]) -> Result<f64, SolverError> {
        let (kappa, _, _) = self.split(z)?;
        Ok(self.energy_normalized(kappa)?.0)
    }
    fn residual_norm(&self, f: &DVector<f64>) -> f64 {
        SurfaceModel::residual_norm(self, f)
    }
}

/// A model with one of its parameters free: the continuation problem `F(z; θ) = 0` in
/// `(z, θ)`, with the other parameters fixed at the model's values.
#[derive(Clone, Debug)]
pub struct ParamProblem<M> {
    model: M,
    param: Param,
}

impl<M: Confinement> ParamProblem<M> {
    /// Continue `model` in `param` (its current value is the start).
    pub fn new(model: M, param: Param) -> Result<Self, SolverError> {
        model.param(param)?;
        Ok(Self { model, param })
    }

    /// The free parameter.
    pub fn param(&self) -> Param {
        self.param
    }

    /// The model at parameter value `value`.
    pub fn model_at(&self, value: f64) -> Result<M, SolverError> {
        self.model.with_param(self.param, value)
    }

    /// The model as given.
    pub fn model(&self) -> &M {
        &self.model
    }
}

impl<M: Confinement> rodloop_continuation::Problem for ParamProblem<M> {
    type Error = SolverError;

    fn dim(&self) -> usize {
        self.model.dim()
    }

    fn residual(&self, x: &DVector<f64>, p: f64) -> Result<DVector<f64>, SolverError> {
        self.model_at(p)?.residual(x.as_slice())
    }

    fn jacobian(&self, x: &DVector<f64>, p: f64) -> Result<DMatrix<f64>, SolverError> {
        self.model_at(p)?.jacobian(x.as_slice())
    }

    fn dparam(&self, x: &DVector<f64>, p: f64) -> Result<DVector<f64>, SolverError> {
        self.model_at(p)?.dparam(x.as_slice(), self.param)
    }

    fn factorize(
        &self,
        x: &DVector<f64>,
        p: f64,
    ) -> Result<Box<dyn Factorization + '_>, SolverError> {
        let m = self.model_at(p)?;
        match m.factorize(x.as_slice(), 0.0) {
            Ok(f) => Ok(Box::new(f)),
            // A singular pivot block: the dense matrix (the continuation's bordered solves
            // then work where the block elimination cannot).
            Err(SolverError::SingularJacobian { .. }) => Ok(Box::new(
                rodloop_continuation::DenseLu::new(m.jacobian(x.as_slice())?),
            )),
            Err(e) => Err(e),
        }
    }
}
