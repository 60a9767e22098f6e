//! The seeds of a branch's families: Euler starts with the soft segment at several offsets,
//! solved directly or as `rodloop solve --branch` does.

use rodloop_solver::{solve, SolveOptions, StartShape, SurfaceModel};

use super::debug;
use crate::ends::SWITCH_DISTANCE;
use crate::seed::periods_of;
use crate::DiagramOptions;

/// How a seed state is found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Seed {
    /// The state `rodloop solve --branch` finds ([`robust_seed`]); without `starts`, only
    /// by its homotopies in `D1/D0` (its direct and shifted starts failed before).
    Solve { starts: bool },
    /// The Euler start with its origin moved by the fraction given, solved directly
    /// ([`seed_state`]).
    Shifted(f64),
    /// A state found by the diagram's completeness certificate (`crate::certificate`).
    Found,
}

/// The seeds of branch `eta` (existence interval `exist`, traced on `range`), in the order
/// they are followed.
///
/// For `0.05 ≤ D1/D0 ≤ 0.9`, the Euler start `l = η` placed by the profile's features
/// (`anchored`: the shifts that put its phases `j/(8η)`, `j = 0…3`, at `s0*`,
/// [`crate::certificate::feature_shifts`]) at each of `lengths`. At strong contrast and for nearly uniform rods
/// (`as_solve`) the state `rodloop solve --branch` finds at each of `lengths` (its direct and shifted starts and its homotopies in `D1/D0`)
/// and, where `solve` would follow a family in `L̄` from another length of the branch's
/// existence interval (its last fallback; [`rodloop_solver::Fallbacks::lbar_path`]), the
/// direct solves from the eight shifted starts it uses there, if that length lies in the
/// range: the tracer follows those families in `L̄` itself. (The range end `L̄ = 1` of
/// branch 2 is such a length: the family of `η = 1` that exists only on `1 ≤ L̄ < 1.052` at
/// `D1/D0 = 0.001` is found there.)
pub(super) fn seed_jobs(
    lengths: &[f64],
    eta: u32,
    exist: (f64, f64),
    range: (f64, f64),
    circles: &[f64],
    as_solve: bool,
    anchored: &[f64],
) -> Vec<(f64, Seed)> {
    let e = f64::from(eta);
    if !as_solve {
        // The start's phases j/(8η), j = 0…3, at the soft segment's first end (the mirror
        // symmetry of the profile carries these placements to its other end).
        let shifts = if anchored.is_empty() {
            (0..4).map(|j| j as f64 / (8.0 * e)).collect()
        } else {
            anchored.to_vec()
        };
        return lengths
            .iter()
            .flat_map(|&l| shifts.iter().map(move |&sh| (l, Seed::Shifted(sh))))
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
            jobs.extend((0..8).map(|j| (l, Seed::Shifted(j as f64 / 8.0 * per))));
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
        .filter(|eq| open_dropped(eq, eta, lbar))
        .map(|eq| eq.state())
}

/// `true` if `eq` closes ([`crate::certificate::closes`]); an open KKT point (half-turn
/// holonomy) is no seed.
fn open_dropped(eq: &rodloop_solver::Equilibrium, eta: u32, lbar: f64) -> bool {
    let ok = crate::certificate::closes(eq);
    if !ok {
        debug(|| format!("seed of eta {eta} at {lbar}: the loop does not close, dropped"));
    }
    ok
}

/// Contrast `D1/D0` below which the seeds are those of `rodloop solve --branch` (direct
/// solves from Euler starts rarely converge there).
pub(super) const STRONG_BELOW: f64 = crate::STRONG_CONTRAST;

/// Contrast `D1/D0` above which the seeds are those of `rodloop solve --branch` too: near
/// `D1/D0 = 1` the placement of the soft segment is nearly neutral and direct solves from
/// Euler starts drift along it (`solve` reaches these states by continuation in `D1/D0` from
/// a clearer contrast).
pub(super) const NEARLY_UNIFORM: f64 = 0.9;

/// The state of an Euler start of `eta` periods with its origin moved by `shift`, relaxed
/// and solved on `model` (the tracing resolution), if it has `eta` periods of `κ_g`.
pub(super) fn seed_state(
    model: &SurfaceModel,
    eta: u32,
    lbar: f64,
    shift: f64,
) -> Option<Vec<f64>> {
    let start = StartShape::Euler { l: eta }.shifted(lbar, shift).ok()?;
    let kappa = start.gauss_values(model).ok()?;
    let eq = solve(model, &kappa, &SolveOptions::default())
        .map_err(|e| debug(|| format!("seed solve failed: {e}")))
        .ok()?;
    (periods_of(&eq).ok()? == eta as usize && open_dropped(&eq, eta, lbar)).then(|| eq.state())
}
