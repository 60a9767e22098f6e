//! The march's continuation problem: the model's unknowns with the leading (shape) ones
//! scaled, its factorisation scaled alike, and the model's stability index at a scaled
//! state (see "Scaling" in the parent module).

use nalgebra::{DMatrix, DVector};
use rodloop_continuation::{BoxError, Factorization, Problem, Stability};
use rodloop_solver::{Confinement, ParamProblem, SolverError};

/// The continuation problem of a [`ParamProblem`] with the leading unknowns scaled.
pub(super) struct Scaled<'a, M> {
    pub(super) inner: &'a ParamProblem<M>,
    pub(super) k: usize,
    pub(super) s: f64,
}

impl<M> Scaled<'_, M> {
    pub(super) fn unscale(&self, xt: &DVector<f64>) -> DVector<f64> {
        let mut x = xt.clone();
        x.rows_mut(0, self.k).scale_mut(1.0 / self.s);
        x
    }

    pub(super) fn scale(&self, x: &[f64]) -> DVector<f64> {
        let mut xt = DVector::from_column_slice(x);
        xt.rows_mut(0, self.k).scale_mut(self.s);
        xt
    }
}

impl<M: Confinement> Problem for Scaled<'_, M> {
    type Error = SolverError;

    fn dim(&self) -> usize {
        self.inner.dim()
    }

    fn residual(&self, x: &DVector<f64>, p: f64) -> Result<DVector<f64>, SolverError> {
        self.inner.residual(&self.unscale(x), p)
    }

    fn jacobian(&self, x: &DVector<f64>, p: f64) -> Result<DMatrix<f64>, SolverError> {
        let mut j = self.inner.jacobian(&self.unscale(x), p)?;
        j.columns_mut(0, self.k).scale_mut(1.0 / self.s);
        Ok(j)
    }

    fn dparam(&self, x: &DVector<f64>, p: f64) -> Result<DVector<f64>, SolverError> {
        self.inner.dparam(&self.unscale(x), p)
    }

    fn factorize(
        &self,
        x: &DVector<f64>,
        p: f64,
    ) -> Result<Box<dyn Factorization + '_>, SolverError> {
        Ok(Box::new(ScaledFactor {
            inner: self.inner.factorize(&self.unscale(x), p)?,
            k: self.k,
            s: self.s,
        }))
    }
}

/// `J D` with `D = diag(1/s, …, 1/s, 1, …)` (`k` entries `1/s`), from a factorisation of `J`.
struct ScaledFactor<'a> {
    inner: Box<dyn Factorization + 'a>,
    k: usize,
    s: f64,
}

impl Factorization for ScaledFactor<'_> {
    fn solve(&self, b: &DVector<f64>) -> Option<DVector<f64>> {
        // (J D) y = b  ⇔  y = D⁻¹ J⁻¹ b.
        let mut y = self.inner.solve(b)?;
        y.rows_mut(0, self.k).scale_mut(self.s);
        Some(y)
    }

    fn apply(&self, v: &DVector<f64>) -> DVector<f64> {
        let mut w = v.clone();
        w.rows_mut(0, self.k).scale_mut(1.0 / self.s);
        self.inner.apply(&w)
    }

    fn det_sign(&self) -> f64 {
        self.inner.det_sign()
    }

    fn log_abs_det(&self) -> f64 {
        self.inner.log_abs_det() - self.k as f64 * self.s.ln()
    }
}

/// The model's stability index at a scaled state.
pub(super) struct Index<'a, M> {
    pub(super) scaled: &'a Scaled<'a, M>,
    pub(super) tolerance: f64,
}

impl<M: Confinement> Stability for Index<'_, M> {
    fn index(&self, x: &DVector<f64>, p: f64) -> Result<usize, BoxError> {
        let model = self.scaled.inner.model_at(p)?;
        Ok(model.index(self.scaled.unscale(x).as_slice(), self.tolerance)?)
    }
}
