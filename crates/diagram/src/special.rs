//! Folds and branch points located at the reporting resolution.
//!
//! The tracer finds a fold (turning point in `L̄`) or a branch point at its own, coarse
//! resolution. For the report each is located again on equilibria of the two reporting
//! resolutions `(N_f, N_c)` of [`crate::refine::reporting_cells`]: the traced state one
//! step before the sheet's end is re-solved at `N` cells and marched towards the end with
//! the continuation's own fold and branch-point location (the test functions of
//! `rodloop_continuation`, bisected to the march's locate width). From the asymmetric side a
//! pitchfork is a turning point in `L̄`, so either kind is accepted near the traced point
//! (the march stops at the first turning point and keeps its fold, so a branch point in the
//! same step is not located).
//! The two locations are Richardson-extrapolated like the critical lengths (`h⁴` scheme,
//! `N_c = N_f/2`): `X* = X_f + (X_f − X_c)/15`, with `2 |X_f − X_c|/15` as the error
//! estimate. (Using the tracer's own location as the coarse partner saves one march but
//! gave estimates up to 30 times below the difference to `--accuracy high`.)

use rodloop_continuation::SpecialKind as ContKind;
use rodloop_solver::{Confinement, Param, ParamProblem};

use crate::march::{march, FoldPolicy};
use crate::refine::{reporting_cells, resolve};
use crate::trace::march_settings;
use crate::types::TracedBranch;
use crate::DiagramOptions;

/// A fold or branch point located at the reporting resolutions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Located {
    /// Extrapolated `L̄`.
    pub lbar: f64,
    /// Extrapolated energy `E R/(π D0)`.
    pub energy: f64,
    /// Error estimate of `lbar`.
    pub error: f64,
}

/// Safety factor of the error estimate: without it the `D1/D0 = 0.5` scene's estimates
/// were up to 1.4 times below the difference to `--accuracy high`.
const SAFETY: f64 = 2.0;

/// Width (arclength) to which the marches locate the point.
const LOCATE_TOL: f64 = 1e-7;

/// Steps at most per march towards the end of a sheet.
const MAX_STEPS: usize = 80;

/// The reporting resolutions `(N_f, N_c)` at which the ends of sheet `b` are located.
pub(crate) fn end_cells(opts: &DiagramOptions, b: &TracedBranch) -> (usize, usize) {
    reporting_cells(opts, b.eta)
}

/// Locate the special point at the low (`at_low`) or high end of sheet `b` on equilibria
/// of `cells` cells (one of [`end_cells`], see the module docs): its `(L̄, E R/(π D0))`
/// there, or `None` if it is not found near the traced point. The two resolutions are
/// independent of each other, so the assembly locates them as separate tasks and combines
/// them with [`extrapolate_end`].
pub(crate) fn locate_end_at(
    opts: &DiagramOptions,
    b: &TracedBranch,
    at_low: bool,
    cells: usize,
) -> Option<(f64, f64)> {
    let n = b.points.len();
    if n < 2 {
        return None;
    }
    let back = 1;
    let (end, start) = if at_low {
        (&b.points[0], &b.points[back])
    } else {
        (&b.points[n - 1], &b.points[n - 1 - back])
    };
    let gap = (end.value - start.value).abs();
    if gap <= 0.0 {
        return None;
    }
    let eq_t = b.solve_at(opts, start.value).ok()?;
    let eq = resolve(opts, &eq_t, cells).ok()?;
    let model = eq.model().clone();
    let problem = ParamProblem::new(model.clone(), Param::Lbar).ok()?;
    let limit = end.value + (end.value - start.value) * 2.0;
    let shape = model.dim() - model.n_constraints();
    let mut settings = march_settings(opts, limit, shape);
    settings.folds = FoldPolicy::Stop;
    settings.detect_branch_points = true;
    settings.max_steps = MAX_STEPS;
    settings.track_index = false;
    settings.locate_tol = LOCATE_TOL;
    settings.hermite_location = true;
    // About three steps to the end (distance in the march's scaled norm).
    let dist = scaled_distance(&start.state, &end.state, shape, settings.scale)
        .hypot(end.value - start.value);
    settings.ds = (dist / 3.0).clamp(1e-4, settings.ds_max);
    let run = march(
        &problem,
        &eq.state(),
        start.value,
        &settings,
        &mut |_, _| {},
    )
    .ok()?;
    let sp = run.special.iter().find(|s| {
        matches!(s.kind, ContKind::Fold | ContKind::BranchPoint)
            && (s.value - end.value).abs() <= 2.0 * gap + 1e-6
    })?;
    Some((sp.value, energy_of(&problem, &sp.x, sp.value)?))
}

/// The located point from its locations `(L̄, E)` at the resolutions `(N_f, N_c)` of
/// [`end_cells`] (see the module docs).
pub(crate) fn extrapolate_end(
    (nf, nc): (usize, usize),
    (lf, ef): (f64, f64),
    (lc, ec): (f64, f64),
) -> Located {
    // `N_c = N_f/2` except at the high level (then `N_f/2` as well, see
    // `reporting_cells`): `q = (N_f/N_c)⁴ − 1`.
    let q = (nf as f64 / nc as f64).powi(4) - 1.0;
    Located {
        lbar: lf + (lf - lc) / q,
        energy: ef + (ef - ec) / q,
        // A located point is off by at most the locate width in arclength, so by as much
        // in `L̄` (unit tangent).
        error: SAFETY * (lf - lc).abs() / q + LOCATE_TOL,
    }
}

/// Distance of two states of the tracing resolution in the scaled norm of the march (the
/// first `shape` unknowns times `scale`); the distance of the shape parts at another
/// resolution is about the same (root-mean-square of `κ_g R`).
fn scaled_distance(a: &[f64], b: &[f64], shape_fine: usize, scale_fine: f64) -> f64 {
    let k = a.len().min(b.len()).saturating_sub(3);
    if k == 0 {
        return 0.0;
    }
    let rms = (a[..k]
        .iter()
        .zip(&b[..k])
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f64>()
        / k as f64)
        .sqrt();
    rms * scale_fine * (shape_fine as f64).sqrt()
}

/// `E R/(π D0)` of the state `x` at `lbar`.
fn energy_of<M: Confinement>(problem: &ParamProblem<M>, x: &[f64], lbar: f64) -> Option<f64> {
    problem.model_at(lbar).ok()?.energy(x).ok()
}
