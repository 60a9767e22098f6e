//! The model wrapper a `--param` sweep marches on: [`Continued`] puts the parameter on its
//! [`Axis`] (the logarithm for `d1` and `gamma`, the parameter itself otherwise), so the
//! generic stepping loop sees one more [`Confinement`].

use rodloop_continuation::axis::Axis;
use rodloop_solver::{Confinement, Param, SolverError};

use crate::march::{March, MarchStop};

/// A model continued on an [`Axis`] of its parameter: in `p = ln θ` for `d1` and `gamma` (the
/// decades at even steps, `∂F/∂p = θ ∂F/∂θ`), in the parameter itself otherwise.
#[derive(Clone, Debug)]
pub(super) struct Continued<M> {
    pub(super) model: M,
    pub(super) axis: Axis,
}

impl<M> Continued<M> {
    pub(super) fn theta(&self, p: f64) -> f64 {
        self.axis.value(p)
    }

    pub(super) fn p_of(&self, theta: f64) -> f64 {
        self.axis.coordinate(theta)
    }

    /// A march with its parameter values as `θ` (the tangents of its special points are
    /// left in `p`; branch switching uses the march as marched).
    pub(super) fn in_theta(&self, m: &March) -> March {
        let mut m = m.clone();
        for p in &mut m.points {
            p.value = self.theta(p.value);
        }
        for sp in &mut m.special {
            sp.value = self.theta(sp.value);
        }
        for ic in &mut m.index_changes {
            ic.value = self.theta(ic.value);
        }
        if let MarchStop::StepTooSmall { value, .. } | MarchStop::NearCircle { value, .. } =
            &mut m.stop
        {
            *value = self.theta(*value);
        }
        m
    }
}

impl<M: Confinement> Confinement for Continued<M> {
    type Factor = M::Factor;
    fn dim(&self) -> usize {
        Confinement::dim(&self.model)
    }
    fn n_constraints(&self) -> usize {
        self.model.n_constraints()
    }
    fn residual(&self, z: &[f64]) -> Result<nalgebra::DVector<f64>, SolverError> {
        self.model.residual(z)
    }
    fn jacobian(&self, z: &[f64]) -> Result<nalgebra::DMatrix<f64>, SolverError> {
        self.model.jacobian(z)
    }
    fn factorize(&self, z: &[f64], shift: f64) -> Result<M::Factor, SolverError> {
        Confinement::factorize(&self.model, z, shift)
    }
    fn apply(&self, z: &[f64], dz: &[f64]) -> Result<nalgebra::DVector<f64>, SolverError> {
        Confinement::apply(&self.model, z, dz)
    }
    fn param(&self, p: Param) -> Result<f64, SolverError> {
        Ok(self.p_of(Confinement::param(&self.model, p)?))
    }
    fn with_param(&self, p: Param, value: f64) -> Result<Self, SolverError> {
        Ok(Self {
            model: Confinement::with_param(&self.model, p, self.theta(value))?,
            axis: self.axis,
        })
    }
    fn dparam(&self, z: &[f64], p: Param) -> Result<nalgebra::DVector<f64>, SolverError> {
        let d = self.model.dparam(z, p)?;
        // d/dq = (dθ/dq) d/dθ (θ d/dθ on a log axis).
        let theta = Confinement::param(&self.model, p)?;
        Ok(d * self.axis.derivative(self.p_of(theta)))
    }
    fn index(&self, z: &[f64], tolerance: f64) -> Result<usize, SolverError> {
        self.model.index(z, tolerance)
    }
    fn energy(&self, z: &[f64]) -> Result<f64, SolverError> {
        Confinement::energy(&self.model, z)
    }
    fn residual_norm(&self, f: &nalgebra::DVector<f64>) -> f64 {
        Confinement::residual_norm(&self.model, f)
    }
    fn radius(&self) -> f64 {
        Confinement::radius(&self.model)
    }
    fn lbar(&self) -> f64 {
        Confinement::lbar(&self.model)
    }
    fn cells(&self) -> usize {
        Confinement::cells(&self.model)
    }
    fn stiffness(&self) -> &rodloop_solver::StiffnessProfile {
        Confinement::stiffness(&self.model)
    }
    fn energy_gradient(&self, z: &[f64]) -> Result<nalgebra::DVector<f64>, SolverError> {
        Confinement::energy_gradient(&self.model, z)
    }
    /// `dE/dq = (dθ/dq) ∂E/∂θ`, as [`Confinement::dparam`].
    fn energy_dparam(&self, z: &[f64], p: Param) -> Result<f64, SolverError> {
        let d = self.model.energy_dparam(z, p)?;
        let theta = Confinement::param(&self.model, p)?;
        Ok(d * self.axis.derivative(self.p_of(theta)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DVector;
    use rodloop_continuation::fd_dparam;
    use rodloop_solver::Stiffness;

    #[test]
    fn log_continued_parameter_derivative_matches_finite_differences() {
        let st = Stiffness::Tanh {
            d0: 1.0,
            d1: 0.3,
            s0: 0.3,
            s1: 0.8,
            gamma: 12.0,
        };
        let model = crate::surface_model(1.0, 1.4, 12, &st).unwrap();
        // A non-equilibrium state: the exact loop of two periods, arbitrary multipliers.
        let mut z = rodloop_solver::StartShape::Exact { eta: 2 }
            .gauss_values(&model)
            .unwrap();
        z.extend_from_slice(&[0.3, -0.2, 0.1]);
        for axis in [Axis::Log, Axis::Linear] {
            let c = Continued {
                model: model.clone(),
                axis,
            };
            let p0 = Confinement::param(&c, Param::D1).unwrap();
            assert!((c.theta(p0) - 0.3).abs() < 1e-15);
            let an = c.dparam(&z, Param::D1).unwrap();
            let fd = fd_dparam(
                |p| -> Result<DVector<f64>, SolverError> {
                    c.with_param(Param::D1, p)?.residual(&z)
                },
                p0,
            )
            .unwrap();
            let err = (&an - &fd).amax() / fd.amax();
            assert!(err < 1e-7, "{axis:?}: {err}");
        }
    }
}
