//! Quantities of a traced state: the equilibrium re-solved at the tracing resolution, its
//! Richardson partner at half the resolution (energy, geodesic energy and contact-force
//! extremes extrapolated like `h⁴`), the slope `dE/dL̄` from the multipliers, and the
//! stability index; plus the small model helpers the assembly shares (a model with the
//! phase condition of a reference state, Newton options for re-solving known states).

use std::f64::consts::PI;

use rodloop_solver::{
    solve, solve_from_state, Confinement, Equilibrium, Globalization, ParamProblem, Phase,
    SolveOptions, SolverError, SurfaceModel,
};

use crate::march::MarchPoint;
use crate::types::TracedPoint;
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
            let rich = |f: f64, c: f64| f + (f - c) / 15.0;
            (
                rich(en.total, eh.total),
                rich(en.geodesic, eh.geodesic),
                Some((en.total - eh.total).abs() / 15.0),
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
