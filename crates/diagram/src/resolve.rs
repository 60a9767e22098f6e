//! Re-solving a known state at another resolution: Newton from its resampled profile at the
//! same length (and, for uniform stiffness, the phase condition of that profile), for the
//! Richardson partner at half the resolution, the kept run at twice it, and the refined
//! states of the verification ladder ([`crate::state_file`]).

use rodloop_solver::{
    solve_newton_keeping_until, solve_newton_until, Equilibrium, Globalization, Phase,
    SolveOptions, SolverError, Stall, SurfaceSolve,
};

use crate::options::model_with_phase;
use crate::types::FinerRun;
use crate::DiagramOptions;

/// Newton options for re-solving known states.
pub(crate) fn newton_options() -> SolveOptions {
    SolveOptions {
        globalization: Globalization::Newton,
        max_iterations: 30,
        ..SolveOptions::default()
    }
}

/// The equilibrium `eq` re-solved with `cells` cells (resampled start, phase condition from
/// the resampled profile so that the arclength origin is the same), given up where the run
/// stalls ([`STALLED`]).
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
    solve_newton_until(&model, &kappa, &newton_options(), STALLED).ok()
}

/// `eq` re-solved at `cells` (more than its own) cells by
/// [`rodloop_solver::solve_newton_keeping_until`] from its resampled curvature: the
/// equilibrium, and the run kept for [`resolved`]. Its tolerance is [`resolved`]'s,
/// [`RESOLVED_TOLERANCE`]: the run gives the energy of the estimate's third rung, and the
/// energy is stationary at an equilibrium, so a KKT residual `r` moves it by about
/// `r²/λ_min` (1e-16 over the smallest Hessian eigenvalue), far below any estimate; a
/// tighter tolerance only adds passes, and on a very soft segment (`D1/D0 = 0.001`) the
/// residual at twice the tracing resolution stalls at about 5e-10 after reaching 1e-8.
pub(crate) fn finer_resolution(
    opts: &DiagramOptions,
    eq: &Equilibrium,
    cells: usize,
) -> (Option<Equilibrium>, FinerRun) {
    let none = || (None, FinerRun::default());
    if cells < 4 {
        return none();
    }
    let Ok(kappa) = eq.resample(cells) else {
        return none();
    };
    let Ok(model) = model_with_phase(opts, eq.lbar(), cells, &kappa) else {
        return none();
    };
    let newton = SolveOptions {
        tolerance: RESOLVED_TOLERANCE,
        ..newton_options()
    };
    let (r, run) =
        solve_newton_keeping_until(&model, &kappa, &newton, RESOLVED_TOLERANCE, Some(STALLED));
    (r.ok(), FinerRun::new(kappa, run))
}

/// `eq` re-solved with `cells` cells at its own length and stiffness for a state file, by the
/// diagrams ([`crate::TracedBranch::verified_state`]) and by `phase`, `converge` and
/// `--param` alike: the resampled profile as start (and, for uniform stiffness, as phase
/// reference), Newton to the tolerance a traced state is accepted with (`1e-8`, as in
/// [`crate::TracedBranch::equilibrium_of`]; on a very soft segment, `D1/D0 = 0.001`, the
/// residual of the finer resolutions can stall above the solver's default `1e-10`), for as
/// long as the run converges ([`newton_until_stall`]).
pub(crate) fn resolved(eq: &Equilibrium, cells: usize) -> Result<Equilibrium, SolverError> {
    resolved_from(eq, cells, &FinerRun::default())
}

/// The tolerance of [`resolved`]'s Newton run.
const RESOLVED_TOLERANCE: f64 = 1e-8;

/// Newton passes of [`resolved`] between two looks at its progress.
const NEWTON_STRETCH: usize = 20;

/// Least factor by which the KKT residual falls over [`NEWTON_STRETCH`] passes for
/// [`newton_until_stall`] to go on: a steady linear rate of at least 3.5 % per pass (a
/// Newton-like run falls far faster; damped steps from a start that its resolution moves,
/// a very soft segment bent sharply, creep at such rates); a run that falls slower has
/// stalled.
const STEADY_FALL: f64 = 2.0;

/// Where the re-solves at another resolution ([`half_resolution`], [`finer_resolution`],
/// [`resolved`]) give up before their iteration limit: four passes in a row whose line
/// search accepts at most 1/128 of the Newton step without lengthening it
/// ([`rodloop_solver::Stall`]). Such a run sits where Newton's model of the residual holds
/// over a sliver of its step: on a very soft segment bent more sharply than the tracing
/// resolution resolves, the start lies far from any equilibrium of the other mesh, and the
/// residual moves by a fraction of a per cent per pass. Runs that converge take longer
/// steps: of the 2,970 re-solves of the four surface diagrams of `data/scenes` and of
/// three random two-segment scenes, run without the rule, no run that converges accepts a
/// step of 1/128 or less twice in a row, and on `D1/D0 = 0.001` the rule ends 58 % of the
/// failing runs' 12,500 passes (the line search shortens a rejected step to between a
/// tenth and a half of it, so its steps are not powers of two).
const STALLED: Stall = Stall {
    passes: 4,
    max_step: 1.0 / 128.0,
};

/// [`resolved`], going on from the kept run `finer` where it is a run of the same model
/// from the same start ([`FinerRun::resume_keeping`]; the same iterates, so the same result).
pub(crate) fn resolved_from(
    eq: &Equilibrium,
    cells: usize,
    finer: &FinerRun,
) -> Result<Equilibrium, SolverError> {
    let m = eq.model();
    let kappa = eq.resample(cells)?;
    let kind = m.stiffness().kind();
    let mut model = m.with_cells(cells)?;
    if kind.is_uniform() {
        model = model.with_phase(Phase::from_gauss_values(&kappa, cells)?)?;
    }
    newton_until_stall(&model, &kappa, finer)
}

/// Newton's method for `model` from `start` (curvature at the Gauss points) to
/// [`RESOLVED_TOLERANCE`], its iteration limit following the run's own convergence: the run
/// goes on by [`NEWTON_STRETCH`] passes at a time while its residual keeps falling at least
/// [`STEADY_FALL`]-fold per stretch, and stops where it stalls, by that test or, earlier,
/// by [`STALLED`] (then the error of the last pass). The residual falls that much per stretch from a finite start to the tolerance, so
/// the run ends. Goes on from the kept run `finer` where that is a run of this model and
/// start.
fn newton_until_stall(
    model: &crate::options::Model,
    start: &[f64],
    finer: &FinerRun,
) -> Result<Equilibrium, SolverError> {
    let mut newton = SolveOptions {
        tolerance: RESOLVED_TOLERANCE,
        max_iterations: 3 * NEWTON_STRETCH,
        ..newton_options()
    };
    let (mut result, mut run) = match finer.resume_keeping(model, start, &newton) {
        Some(r) => r,
        None => {
            let (r, run) = solve_newton_keeping_until(
                model,
                start,
                &newton,
                RESOLVED_TOLERANCE,
                Some(STALLED),
            );
            (r, run)
        }
    };
    loop {
        let Err(SolverError::NewtonNotConverged { iterations, .. }) = result else {
            return result;
        };
        let Some(kept) = run.take() else {
            return result;
        };
        let residuals = kept.residuals();
        let n = residuals.len();
        let steady = iterations == newton.max_iterations
            && n > NEWTON_STRETCH
            && residuals[n - 1] * STEADY_FALL <= residuals[n - 1 - NEWTON_STRETCH];
        if !steady {
            return result;
        }
        newton.max_iterations += NEWTON_STRETCH;
        match kept.resume_keeping(&newton) {
            Some((r, k)) => (result, run) = (r, k),
            None => return result,
        }
    }
}
