//! The seeds of a branch's families: Euler starts with the soft segment at several offsets,
//! solved directly, through a homotopy in `D1/D0`, or as `rodloop solve --branch` does.

use rodloop_solver::{
    solve, Confinement, Param, ParamProblem, SolveOptions, StartShape, Stiffness, SurfaceModel,
};

use super::{debug, MAX_STEPS};
use crate::ends::SWITCH_DISTANCE;
use crate::march::{march, MarchStop};
use crate::seed::periods_of;
use crate::trace::march_settings;
use crate::DiagramOptions;

/// How a seed state is found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Seed {
    /// The state `rodloop solve --branch` finds ([`robust_seed`]); without `starts`, only
    /// by its homotopies in `D1/D0` (its direct and shifted starts failed before).
    Solve { starts: bool },
    /// The Euler start with its origin moved by the fraction given, solved directly or at
    /// strong contrast through a homotopy in `D1/D0` ([`seed_state`]).
    Shifted(f64),
    /// The same start solved directly at any contrast.
    Direct(f64),
}

/// The seeds of branch `eta` (existence interval `exist`, traced on `range`), in the order
/// they are followed.
///
/// At mild contrast, the Euler start `l = η` with its origin moved by `j/(8η)` (`j = 0…3`)
/// at each of `lengths`. At strong contrast (`strong`) the state `rodloop solve --branch`
/// finds at each of `lengths` (its direct and shifted starts and its homotopies in `D1/D0`)
/// and, where `solve` would follow a family in `L̄` from another length of the branch's
/// existence interval (its last fallback; [`rodloop_solver::Fallbacks::lbar_path`]), the
/// direct solves from the eight shifted starts it uses there, if that length lies in the
/// range: the tracer follows those families in `L̄` itself. (The range end `L̄ = 1` of
/// branch 2 is such a length: the family of `η = 1` that exists only on `1 ≤ L̄ < 1.045` at
/// `D1/D0 = 0.001` is found there.)
pub(super) fn seed_jobs(
    lengths: &[f64],
    eta: u32,
    exist: (f64, f64),
    range: (f64, f64),
    circles: &[f64],
    strong: bool,
) -> Vec<(f64, Seed)> {
    let e = f64::from(eta);
    if !strong {
        return lengths
            .iter()
            .flat_map(|&l| (0..4).map(move |j| (l, Seed::Shifted(j as f64 / (8.0 * e)))))
            .collect();
    }
    let mut jobs: Vec<(f64, Seed)> = lengths
        .iter()
        .map(|&l| (l, Seed::Solve { starts: true }))
        .collect();
    let per = 1.0 / e;
    for f in [0.5, 0.25, 0.75] {
        let l = exist.0 + f * (exist.1 - exist.0);
        let inside = l >= range.0 - 1e-12 && l <= range.1 + 1e-12;
        let seeded = lengths.iter().any(|&s| (s - l).abs() < 1e-9);
        let near_circle = circles
            .iter()
            .any(|m| (l - m).abs() <= 2.0 * SWITCH_DISTANCE);
        if inside && !seeded && !near_circle {
            jobs.extend((0..8).map(|j| (l, Seed::Direct(j as f64 / 8.0 * per))));
        }
    }
    jobs
}

/// The state `rodloop solve --branch` finds for `eta` at `lbar` (`solve_robust` from the
/// Euler curve, fast accuracy), re-solved on `model` (the tracing resolution). Without
/// `rodloop solve`'s continuation in `L̄` (the tracer follows those families itself,
/// [`seed_jobs`]); with `starts`, its direct and shifted starts only, without, its
/// homotopies in `D1/D0` only.
pub(super) fn robust_seed(
    opts: &DiagramOptions,
    model: &SurfaceModel,
    eta: u32,
    lbar: f64,
    starts: bool,
) -> Option<Vec<f64>> {
    let (acc, strategy) = rodloop_solver::solve_robust_with(
        opts.radius,
        lbar,
        &opts.stiffness,
        &StartShape::Euler { l: eta },
        rodloop_solver::Accuracy::Fast,
        Some(eta),
        &SolveOptions::default(),
        rodloop_solver::Fallbacks {
            starts,
            homotopy: !starts,
            lbar_path: false,
            ..rodloop_solver::Fallbacks::default()
        },
    )
    .map_err(|e| debug(|| format!("robust seed {eta} at {lbar}: {e}")))
    .ok()?;
    debug(|| format!("robust seed {eta} at {lbar}: {}", strategy.describe()));
    let kappa = acc.equilibrium.resample(model.cells()).ok()?;
    solve(model, &kappa, &crate::states::newton_options())
        .ok()
        .map(|eq| eq.state())
}

/// Contrast `D1/D0` below which seeds come from a mild contrast by continuation in `D1/D0`
/// (direct solves from Euler starts rarely converge there).
pub(super) const HOMOTOPY_BELOW: f64 = crate::STRONG_CONTRAST;
/// The mild contrast of those continuations.
const MILD_CONTRAST: f64 = 0.5;

/// The state of an Euler start of `eta` periods with its origin moved by `shift`, relaxed
/// and solved on `model` (the tracing resolution), if it has `eta` periods of `κ_g`. With
/// `homotopy` (used at strong contrast, `D1/D0 <` [`HOMOTOPY_BELOW`]) the start is solved
/// at [`MILD_CONTRAST`] and followed in `D1/D0` to the scene's value (the state is dropped
/// if the family folds back in `D1/D0` before it).
pub(super) fn seed_state(
    opts: &DiagramOptions,
    model: &SurfaceModel,
    eta: u32,
    lbar: f64,
    shift: f64,
    homotopy: bool,
) -> Option<Vec<f64>> {
    let start = StartShape::Euler { l: eta }.shifted(lbar, shift).ok()?;
    let contrast = match &opts.stiffness {
        Stiffness::Tanh { d0, d1, .. } => d1 / d0,
        _ => 1.0,
    };
    if !homotopy || contrast >= MILD_CONTRAST {
        let kappa = start.gauss_values(model).ok()?;
        let eq = solve(model, &kappa, &SolveOptions::default())
            .map_err(|e| debug(|| format!("seed solve failed: {e}")))
            .ok()?;
        return (periods_of(&eq).ok()? == eta as usize).then(|| eq.state());
    }
    let mild = opts.stiffness.with_param(Param::D1, MILD_CONTRAST).ok()?;
    let mild_model = SurfaceModel::new(opts.radius, lbar, model.cells(), &mild).ok()?;
    let kappa = start.gauss_values(&mild_model).ok()?;
    let eq = solve(&mild_model, &kappa, &SolveOptions::default())
        .map_err(|e| debug(|| format!("mild seed solve failed: {e}")))
        .ok()?;
    if periods_of(&eq).ok()? != eta as usize {
        return None;
    }
    let problem = ParamProblem::new(mild_model, Param::D1).ok()?;
    let shape = model.dim() - model.n_constraints();
    let mut settings = march_settings(opts, contrast, shape);
    settings.ds_min = 1e-6;
    settings.max_steps = MAX_STEPS;
    let run = march(
        &problem,
        &eq.state(),
        MILD_CONTRAST,
        &settings,
        &mut |_, _| {},
    )
    .ok()?;
    debug(|| {
        format!(
            "homotopy in D1/D0: {} steps, {:?}",
            run.steps,
            run.stop.clone()
        )
    });
    let last = run.points.last()?;
    if run.stop != MarchStop::Reached || (last.value - contrast).abs() > 1e-12 {
        return None;
    }
    let eq = rodloop_solver::solve_from_state(
        model.clone(),
        last.x.clone(),
        &crate::states::newton_options(),
    )
    .map_err(|e| debug(|| format!("after the homotopy: {e}")))
    .ok()?;
    let periods = periods_of(&eq);
    debug(|| format!("after the homotopy: periods {periods:?}"));
    (periods.ok()? == eta as usize).then(|| eq.state())
}
