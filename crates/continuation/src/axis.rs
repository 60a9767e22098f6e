//! Parameter axes: a problem continued in its parameter `θ` itself or in `q = ln θ`.
//!
//! A positive scale parameter spanning decades (a stiffness ratio, a sharpness) is
//! best stepped in its logarithm: equal steps in `q` are equal factors in `θ`. The
//! continuation variable is then `q`, with `θ = e^q` and `∂F/∂q = θ ∂F/∂θ`.
//! [`OnAxis`] wraps any [`Problem`] so; which parameters take which axis is the model's
//! rule, not this crate's.

use nalgebra::{DMatrix, DVector};

use crate::factorization::Factorization;
use crate::problem::Problem;

/// How the continuation variable `q` maps to the parameter `θ`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Axis {
    /// `q = θ`.
    Linear,
    /// `q = ln θ` (`θ > 0`).
    Log,
}

impl Axis {
    /// `θ(q)`.
    pub fn value(self, q: f64) -> f64 {
        match self {
            Axis::Linear => q,
            Axis::Log => q.exp(),
        }
    }

    /// `q(θ)`.
    pub fn coordinate(self, theta: f64) -> f64 {
        match self {
            Axis::Linear => theta,
            Axis::Log => theta.ln(),
        }
    }

    /// `dθ/dq` at `q`.
    pub fn derivative(self, q: f64) -> f64 {
        match self {
            Axis::Linear => 1.0,
            Axis::Log => q.exp(),
        }
    }
}

/// A problem `F(x, θ)` continued in `q` of an [`Axis`]: `G(x, q) = F(x, θ(q))`.
#[derive(Debug, Clone)]
pub struct OnAxis<P> {
    /// The problem in `θ`.
    pub problem: P,
    /// The axis.
    pub axis: Axis,
}

impl<P: Problem> Problem for OnAxis<P> {
    type Error = P::Error;
    fn dim(&self) -> usize {
        self.problem.dim()
    }
    fn residual(&self, x: &DVector<f64>, q: f64) -> Result<DVector<f64>, P::Error> {
        self.problem.residual(x, self.axis.value(q))
    }
    fn jacobian(&self, x: &DVector<f64>, q: f64) -> Result<DMatrix<f64>, P::Error> {
        self.problem.jacobian(x, self.axis.value(q))
    }
    fn dparam(&self, x: &DVector<f64>, q: f64) -> Result<DVector<f64>, P::Error> {
        Ok(self.problem.dparam(x, self.axis.value(q))? * self.axis.derivative(q))
    }
    fn factorize(&self, x: &DVector<f64>, q: f64) -> Result<Box<dyn Factorization + '_>, P::Error> {
        self.problem.factorize(x, self.axis.value(q))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::problem::fd_dparam;
    use std::convert::Infallible;

    /// `F = x − θ²`.
    struct Square;
    impl Problem for Square {
        type Error = Infallible;
        fn dim(&self) -> usize {
            1
        }
        fn residual(&self, x: &DVector<f64>, p: f64) -> Result<DVector<f64>, Infallible> {
            Ok(DVector::from_element(1, x[0] - p * p))
        }
        fn jacobian(&self, _x: &DVector<f64>, _p: f64) -> Result<DMatrix<f64>, Infallible> {
            Ok(DMatrix::from_element(1, 1, 1.0))
        }
        fn dparam(&self, _x: &DVector<f64>, p: f64) -> Result<DVector<f64>, Infallible> {
            Ok(DVector::from_element(1, -2.0 * p))
        }
    }

    #[test]
    fn axes_round_trip_and_differentiate() {
        for axis in [Axis::Linear, Axis::Log] {
            for theta in [1e-3, 0.5, 7.0] {
                let q = axis.coordinate(theta);
                assert!((axis.value(q) - theta).abs() <= 1e-15 * theta);
                let h = 1e-6;
                let fd = (axis.value(q + h) - axis.value(q - h)) / (2.0 * h);
                assert!((fd - axis.derivative(q)).abs() <= 1e-8 * fd.abs());
            }
        }
    }

    #[test]
    fn log_axis_parameter_derivative_is_theta_times_the_plain_one() {
        // G(x, q) = x − e^{2q}: ∂G/∂q = −2 e^{2q}; checked against finite differences.
        let p = OnAxis {
            problem: Square,
            axis: Axis::Log,
        };
        let x = DVector::from_element(1, 0.3);
        let q = 0.4f64;
        let d = p.dparam(&x, q).unwrap()[0];
        assert!((d + 2.0 * (2.0 * q).exp()).abs() < 1e-13);
        let fd = fd_dparam(|q| p.residual(&x, q), q).unwrap()[0];
        assert!((fd - d).abs() < 1e-6 * d.abs(), "{fd} vs {d}");
    }
}
