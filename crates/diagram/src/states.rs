//! Quantities of a traced state: the equilibrium re-solved at the tracing resolution, its
//! Richardson partner at half the resolution (energy, geodesic energy and contact-force
//! extremes extrapolated like `h⁴`), the slope `dE/dL̄` from the multipliers, and the
//! stability index; and the re-solves of a traced branch's states. Three files share the
//! job by step: this one (the quantities of a row), [`crate::resolve`] (a known state
//! re-solved at another resolution) and [`crate::state_file`] (a state as its file holds
//! it, verified, with the refinement ladder); the helpers of the other two are re-exported
//! here for the tracers that use them with the row quantities.

use std::f64::consts::PI;

use rodloop_solver::{Confinement, Equilibrium, Param, ParamProblem, SolverError, SurfaceSolve};

use crate::march::MarchPoint;
use crate::types::{FinerRun, TracedBranch, TracedPoint};
use crate::DiagramOptions;

/// Threshold below which an eigenvalue (units of `D0`) counts as negative (the solver's
/// default, [`rodloop_solver::StabilityOptions`]).
pub(crate) const INDEX_TOLERANCE: f64 = 1e-6;

pub(crate) use crate::model_with_phase;
use crate::resolve::finer_resolution;
pub(crate) use crate::resolve::{half_resolution, newton_options, resolved};
pub(crate) use crate::state_file::{sheet_estimate, verify_all, verify_refining, Ladder};

/// `dE/dL̄` along the branch at the KKT state `z` (normalised as `E R/(π D0)`):
/// `dE/dL̄ = ∂E/∂L̄ + ∇E·κ̇ = E/L̄ + μ·(∂(−c)/∂L̄)`, because `∇E = ∇cᵀμ + ν∇φ`,
/// `∇c κ̇ = −∂c/∂L̄` and `∇φ κ̇ = 0` (the phase condition does not depend on `L̄`).
pub(crate) fn energy_slope(eq: &Equilibrium) -> Result<f64, SolverError> {
    let (model, z) = (eq.model(), &eq.state());
    let (kappa, mu, _) = model.split(z)?;
    let e = model.energy(kappa)?;
    let d = model.kkt_dlbar(z)?;
    let nk = model.n_kappa();
    let de = e / model.lbar() + mu[0] * d[nk] + mu[1] * d[nk + 1] + mu[2] * d[nk + 2];
    Ok(de * model.radius() / (PI * model.stiffness().kind().reference()))
}

/// Quantities of a traced state: equilibrium at the tracing resolution (Newton check),
/// Richardson partner at half the resolution, the error estimate from the ladder with twice
/// the resolution ([`crate::estimate::ladder_error`]), slope, forces, index.
pub(crate) fn finish_point<M: SurfaceSolve>(
    opts: &DiagramOptions,
    problem: &ParamProblem<M>,
    raw: &MarchPoint,
) -> Option<TracedPoint> {
    let eq = match problem
        .model_at(raw.value)
        .and_then(|m| m.solve_from_state(raw.x.clone(), &newton_options()))
    {
        Ok(eq) => eq,
        Err(_) => return None,
    };
    let z = eq.state();
    let en = eq.energy();
    let (lmin, lmax) = eq.lambda_range();
    let slope = energy_slope(&eq).unwrap_or(f64::NAN);
    let amplitude = eq
        .kappa()
        .iter()
        .fold(0.0f64, |a, v| a.max(v.abs() * opts.radius));
    let index = match raw.index {
        Some(i) => i,
        None => eq.model().index(&z, INDEX_TOLERANCE).ok()?,
    };
    let cells = eq.model().cells();
    let partner = if cells / 2 >= crate::profile_cells(&opts.stiffness) {
        half_resolution(opts, &eq, cells / 2)
    } else {
        None
    };
    let mut kept = FinerRun::default();
    let (energy, energy_g, energy_error, lambda_min, lambda_max) = match partner {
        Some(h) => {
            let eh = h.energy();
            let (hmin, hmax) = h.lambda_range();
            let rich = rodloop_solver::richardson;
            // The third rung of the estimate's ladder (`crate::estimate`), its run kept for
            // the verification's re-solve at the same resolution (`resolved`).
            let (finer, run) = finer_resolution(opts, &eq, 2 * cells);
            kept = run;
            let finer = finer.map(|d| d.energy().total);
            (
                rich(en.total, eh.total),
                rich(en.geodesic, eh.geodesic),
                Some(crate::estimate::ladder_error(en.total, eh.total, finer)),
                rich(lmin, hmin),
                rich(lmax, hmax),
            )
        }
        None => (en.total, en.geodesic, None, lmin, lmax),
    };
    let values = [energy, energy_g, en.total, slope, lambda_min, lambda_max];
    if values.iter().any(|v| !v.is_finite()) {
        return None;
    }
    Some(TracedPoint {
        value: raw.value,
        energy,
        energy_g,
        energy_error,
        energy_trace: en.total,
        slope,
        index,
        lambda_min,
        lambda_max,
        amplitude,
        source: raw.source,
        state: z,
        finer: kept,
    })
}

/// Re-solving a traced branch's states (here, beside the solver helpers they use, so that
/// the data type [`TracedBranch`] does not depend on this module).
impl TracedBranch {
    /// The model of the tracing resolution at `lbar`, with a phase condition taken from
    /// `state` (uniform stiffness) so that `state` satisfies it exactly.
    pub(crate) fn model_for(
        &self,
        opts: &DiagramOptions,
        lbar: f64,
        state: &[f64],
    ) -> Result<impl SurfaceSolve, SolverError> {
        model_with_phase(opts, lbar, self.cells, &state[..2 * self.cells])
    }

    /// The equilibrium of traced state `k` itself, at the tracing resolution: Newton from its
    /// own KKT state (already converged, so normally no step), giving its profile
    /// (positions, forces). Only for branches traced in `lbar`.
    pub fn equilibrium_of(
        &self,
        opts: &DiagramOptions,
        k: usize,
    ) -> Result<Equilibrium, SolverError> {
        let p = self.points.get(k).ok_or_else(|| {
            SolverError::InvalidInput(format!(
                "branch eta = {} has {} states, no state {k}",
                self.eta,
                self.points.len()
            ))
        })?;
        if self.param != Param::Lbar {
            return Err(SolverError::InvalidInput(format!(
                "branch eta = {} was traced in {}, not in lbar",
                self.eta, self.param
            )));
        }
        let dim = 2 * self.cells + 3 + usize::from(self.phase);
        if p.state.len() != dim {
            return Err(SolverError::WrongLength {
                expected: dim,
                found: p.state.len(),
            });
        }
        let model = self.model_for(opts, p.value, &p.state)?;
        // The traced state met the corrector's tolerance: accept it as it is unless its
        // residual has grown above 1e-8 (a state read from an older file).
        let accept = rodloop_solver::SolveOptions {
            tolerance: 1e-8,
            ..newton_options()
        };
        model.solve_from_state(p.state.clone(), &accept)
    }

    /// The equilibrium of this branch at `lbar` at the tracing resolution (Newton from the
    /// interpolated traced states). Only for branches traced in `lbar`.
    pub fn solve_at(&self, opts: &DiagramOptions, lbar: f64) -> Result<Equilibrium, SolverError> {
        if self.param != Param::Lbar {
            return Err(SolverError::InvalidInput(format!(
                "branch eta = {} was traced in {}, not in lbar",
                self.eta, self.param
            )));
        }
        let z = self.state_near(lbar);
        let dim = 2 * self.cells + 3 + usize::from(self.phase);
        if z.len() != dim {
            return Err(SolverError::WrongLength {
                expected: dim,
                found: z.len(),
            });
        }
        let model = self.model_for(opts, lbar, &z)?;
        model.solve_from_state(z, &newton_options())
    }
}
