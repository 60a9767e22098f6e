//! Natural-parameter steps in `L̄` for enclosed states (the enclosed diagram's tracer,
//! `rodloop_diagram::enclosed`).
//!
//! A converged state at `L̄` starts Newton at a nearby `L̄'` unchanged: the same curvature
//! vectors, start point and multipliers (closure, gauges, wall), so only the cell lengths
//! change and the start misses closure by `O(L̄' − L̄)`. (A similarity rescaling, curvature
//! times `L/L'` and start point times `L'/L`, closes exactly but pushes every contact node
//! through the wall; the semismooth Newton then stalled at `N = 64` on the lifted-off
//! figure-eight near `L̄ = 1.38`, while the unscaled start converges in 3 iterations.) The
//! gauge takes the start as its reference, as in [`super::start_from_surface`].

use super::model::{phase_slope, EnclosedModel, Gauge};
use super::solve::{solve_enclosed, EnclosedOptions, EnclosedState};
use crate::SolverError;

impl EnclosedState {
    /// The model and start vector at `lbar` built from this state (see the module docs).
    pub fn continue_to(&self, lbar: f64) -> Result<(EnclosedModel, Vec<f64>), SolverError> {
        let m = &self.model;
        let n = m.cells();
        crate::model::check_lbar(lbar)?;
        let reference: Vec<f64> = self.z[..4 * n].to_vec();
        let stiffness = m.stiffness().kind().clone();
        let slope = if m.gauge().slope.is_some() {
            phase_slope(&reference, n)?
        } else {
            None
        };
        if slope.is_some() != m.gauge().slope.is_some() {
            return Err(SolverError::InvalidInput(
                "the phase condition of the enclosed state is degenerate at the new length".into(),
            ));
        }
        let pin = m.gauge().pin;
        let model = EnclosedModel::new(
            m.radius(),
            lbar,
            n,
            &stiffness,
            Gauge {
                reference: reference.clone(),
                slope,
                pin,
            },
        )?;
        Ok((model, self.z.clone()))
    }

    /// Newton at `lbar` from this state ([`Self::continue_to`], then [`solve_enclosed`]).
    pub fn step_to(&self, lbar: f64, opts: &EnclosedOptions) -> Result<EnclosedState, SolverError> {
        let (model, z) = self.continue_to(lbar)?;
        solve_enclosed(&model, z, opts)
    }
}
