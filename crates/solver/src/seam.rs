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
use crate::solve::{Equilibrium, SolveOptions};
use crate::start::StartShape;
use crate::stiffness::StiffnessProfile;
use crate::SolverError;

/// A confinement model (the surface model and the enclosed one). Implementations must keep
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
    /// Radius `R` of the sphere (surface) or of the ball (enclosed).
    fn radius(&self) -> f64;
    /// Normalised length `L̄ = L/(2πR)` (the value of [`Param::Lbar`]).
    fn lbar(&self) -> f64;
    /// Number of cells of the discretisation.
    fn cells(&self) -> usize;
    /// The validated bending-stiffness profile `D(σ)` (uniform, or Eq. (51)).
    fn stiffness(&self) -> &StiffnessProfile;
    /// `∂E/∂z` of [`Confinement::energy`] (Eq. (2) by two-point Gauss quadrature,
    /// normalised as `E R/(π D0)`): `w_a D_a κ_a` on the curvature unknowns, zero on the
    /// others (the energy depends on the shape only through the curvatures).
    fn energy_gradient(&self, z: &[f64]) -> Result<DVector<f64>, SolverError>;
    /// `∂E/∂θ` of [`Confinement::energy`] at fixed `z`: `E/L̄` for [`Param::Lbar`] (every
    /// quadrature weight is proportional to `L̄` at fixed `σ = s/L`), and
    /// `Σ_a ½ w_a (∂D/∂θ)(σ_a) |κ_a|²` (normalised) for a stiffness parameter of Eq. (51).
    fn energy_dparam(&self, z: &[f64], p: Param) -> Result<f64, SolverError>;
}

/// What the surface diagram asks of a model beyond [`Confinement`]: its own solvers, which
/// return the surface state [`Equilibrium`] (geodesic curvature `κ_g` at the Gauss points of
/// the cells, Appendix A), start shapes sampled at those points, and the same scene at
/// another resolution. [`SurfaceModel`] implements it; an enclosed state carries 3-D
/// positions and contacts and has a solver of its own
/// ([`crate::enclosed::solve_enclosed`]).
pub trait SurfaceSolve: Confinement {
    /// The globalised solve ([`crate::solve::solve`]) from the Gauss values `start` of `κ_g`.
    fn solve(&self, start: &[f64], opts: &SolveOptions) -> Result<Equilibrium, SolverError>;
    /// Newton's method from a full KKT state `z0` ([`crate::solve_from_state`]).
    fn solve_from_state(
        self,
        z0: Vec<f64>,
        opts: &SolveOptions,
    ) -> Result<Equilibrium, SolverError>;
    /// The Gauss values of `κ_g` of a start shape ([`StartShape::gauss_values`]).
    fn start_values(&self, start: &StartShape) -> Result<Vec<f64>, SolverError>;
    /// `σ = s/L` of the Gauss points, one per curvature unknown.
    fn gauss_sigma(&self) -> Vec<f64>;
    /// Quadrature weight `h_c/2` of the Gauss points of cell `c`.
    fn cell_weight(&self, c: usize) -> f64;
    /// The same scene (radius, length, stiffness) with `cells` cells, the profile's default
    /// mesh and no phase condition.
    fn with_cells(&self, cells: usize) -> Result<Self, SolverError>;
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
    fn radius(&self) -> f64 {
        SurfaceModel::radius(self)
    }
    fn lbar(&self) -> f64 {
        SurfaceModel::lbar(self)
    }
    fn cells(&self) -> usize {
        SurfaceModel::cells(self)
    }
    fn stiffness(&self) -> &StiffnessProfile {
        SurfaceModel::stiffness(self)
    }
    fn energy_gradient(&self, z: &[f64]) -> Result<DVector<f64>, SolverError> {
        let (kappa, _, _) = self.split(z)?;
        let g = SurfaceModel::energy_gradient(self, kappa)?;
        let s = surface_energy_scale(self);
        let mut out = DVector::zeros(SurfaceModel::dim(self));
        for (a, v) in g.iter().enumerate() {
            out[a] = v * s;
        }
        Ok(out)
    }
    /// For the surface model `|κ_a|² = κ_a² + 1/R²` (geodesic and normal curvature).
    fn energy_dparam(&self, z: &[f64], p: Param) -> Result<f64, SolverError> {
        if p == Param::Lbar {
            return Ok(Confinement::energy(self, z)? / SurfaceModel::lbar(self));
        }
        let (kappa, _, _) = self.split(z)?;
        let kind = SurfaceModel::stiffness(self).kind();
        let sigma = SurfaceModel::gauss_sigma(self);
        let r2 = 1.0 / (SurfaceModel::radius(self) * SurfaceModel::radius(self));
        let mut acc = 0.0;
        for (a, (k, s)) in kappa.iter().zip(&sigma).enumerate() {
            acc +=
                0.5 * SurfaceModel::cell_weight(self, a / 2) * kind.dparam(p, *s)? * (k * k + r2);
        }
        Ok(acc * surface_energy_scale(self))
    }
}

/// `R/(π D0)`: the normalisation of the surface model's energy.
fn surface_energy_scale(model: &SurfaceModel) -> f64 {
    SurfaceModel::radius(model)
        / (std::f64::consts::PI * SurfaceModel::stiffness(model).kind().reference())
}

impl SurfaceSolve for SurfaceModel {
    fn solve(&self, start: &[f64], opts: &SolveOptions) -> Result<Equilibrium, SolverError> {
        crate::solve::solve(self, start, opts)
    }
    fn solve_from_state(
        self,
        z0: Vec<f64>,
        opts: &SolveOptions,
    ) -> Result<Equilibrium, SolverError> {
        crate::solve::solve_from_state(self, z0, opts)
    }
    fn start_values(&self, start: &StartShape) -> Result<Vec<f64>, SolverError> {
        start.gauss_values(self)
    }
    fn gauss_sigma(&self) -> Vec<f64> {
        SurfaceModel::gauss_sigma(self)
    }
    fn cell_weight(&self, c: usize) -> f64 {
        SurfaceModel::cell_weight(self, c)
    }
    fn with_cells(&self, cells: usize) -> Result<Self, SolverError> {
        SurfaceModel::new(
            SurfaceModel::radius(self),
            SurfaceModel::lbar(self),
            cells,
            SurfaceModel::stiffness(self).kind(),
        )
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
