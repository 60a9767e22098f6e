//! Quantities of a traced state: the equilibrium re-solved at the tracing resolution, its
//! Richardson partner at half the resolution (energy, geodesic energy and contact-force
//! extremes extrapolated like `h⁴`), the slope `dE/dL̄` from the multipliers, and the
//! stability index; plus the small model helpers the assembly shares (a model with the
//! phase condition of a reference state, Newton options for re-solving known states).

use std::f64::consts::PI;

use rodloop_solver::{
    solve, solve_from_state, Confinement, Equilibrium, Globalization, Param, ParamProblem, Phase,
    SolveOptions, SolverError, SurfaceModel,
};

use crate::march::MarchPoint;
use crate::types::{TracedBranch, TracedPoint};
use crate::DiagramOptions;

/// Threshold below which an eigenvalue (units of `D0`) counts as negative (the solver's
/// default, [`rodloop_solver::StabilityOptions`]).
pub(crate) const INDEX_TOLERANCE: f64 = 1e-6;

/// A model at `lbar` with `cells` cells and, for uniform stiffness, the phase condition of
/// the reference `kappa` (Gauss values).
pub(crate) fn model_with_phase(
    opts: &DiagramOptions,
    lbar: f64,
    cells: usize,
    kappa: &[f64],
) -> Result<SurfaceModel, SolverError> {
    let model = SurfaceModel::new(opts.radius, lbar, cells, &opts.stiffness)?;
    if opts.stiffness.is_uniform() {
        model.with_phase(Phase::from_gauss_values(kappa, cells)?)
    } else {
        Ok(model)
    }
}

/// Newton options for re-solving known states.
pub(crate) fn newton_options() -> SolveOptions {
    SolveOptions {
        globalization: Globalization::Newton,
        max_iterations: 30,
        ..SolveOptions::default()
    }
}

/// `dE/dL̄` along the branch at the KKT state `z` (normalised as `E R/(π D0)`):
/// `dE/dL̄ = ∂E/∂L̄ + ∇E·κ̇ = E/L̄ + μ·(∂(−c)/∂L̄)`, because `∇E = ∇cᵀμ + ν∇φ`,
/// `∇c κ̇ = −∂c/∂L̄` and `∇φ κ̇ = 0` (the phase condition does not depend on `L̄`).
pub(crate) fn energy_slope(model: &SurfaceModel, z: &[f64]) -> Result<f64, SolverError> {
    let (kappa, mu, _) = model.split(z)?;
    let e = model.energy(kappa)?;
    let d = model.kkt_dlbar(z)?;
    let nk = model.n_kappa();
    let de = e / model.lbar() + mu[0] * d[nk] + mu[1] * d[nk + 1] + mu[2] * d[nk + 2];
    Ok(de * model.radius() / (PI * model.stiffness().kind().reference()))
}

/// Quantities of a traced state: equilibrium at the tracing resolution (Newton check),
/// Richardson partner at half the resolution, slope, forces, index.
pub(crate) fn finish_point(
    opts: &DiagramOptions,
    problem: &ParamProblem<SurfaceModel>,
    raw: &MarchPoint,
) -> Option<TracedPoint> {
    let eq = match problem
        .model_at(raw.value)
        .and_then(|m| solve_from_state(m, raw.x.clone(), &newton_options()))
    {
        Ok(eq) => eq,
        Err(_) => return None,
    };
    let z = eq.state();
    let en = eq.energy();
    let (lmin, lmax) = eq.lambda_range();
    let slope = energy_slope(eq.model(), &z).unwrap_or(f64::NAN);
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
    let (energy, energy_g, energy_error, lambda_min, lambda_max) = match partner {
        Some(h) => {
            let eh = h.energy();
            let (hmin, hmax) = h.lambda_range();
            let rich = rodloop_solver::richardson;
            (
                rich(en.total, eh.total),
                rich(en.geodesic, eh.geodesic),
                Some(rodloop_solver::richardson_error(en.total, eh.total)),
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
    })
}

/// The equilibrium `eq` re-solved with `cells` cells (resampled start, phase condition from
/// the resampled profile so that the arclength origin is the same).
pub(crate) fn half_resolution(
    opts: &DiagramOptions,
    eq: &Equilibrium,
    cells: usize,
) -> Option<Equilibrium> {
    if cells < 4 {
        return None;
    }
    let kappa = eq.resample(cells).ok()?;
    let model = model_with_phase(opts, eq.lbar(), cells, &kappa).ok()?;
    solve(&model, &kappa, &newton_options()).ok()
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
    ) -> Result<SurfaceModel, SolverError> {
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
        solve_from_state(model, p.state.clone(), &accept)
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
        solve_from_state(model, z, &newton_options())
    }
}
