//! The seeds of a branch's families: the uniform rod's exact loop at each placement from
//! which a family leaves the uniform circle ([`crate::placements::PlacedProfile::placements`]),
//! continued in `D1/D0` from 1 to the scene's contrast; `rodloop solve --branch` where none
//! of these reaches the scene.

use rodloop_continuation::axis::{Axis, OnAxis};
use rodloop_continuation::natural::{walk, NaturalSettings};
use rodloop_continuation::target::{reach, ReachLimits};
use rodloop_continuation::{Direction, PseudoArclength};
use rodloop_solver::{Param, ParamProblem, SolveOptions, StartShape, Stiffness, SurfaceSolve};

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
    /// The uniform rod's exact loop with its origin moved by the fraction given, continued
    /// in `D1/D0` from 1 to the scene's contrast ([`uniform_seed`]).
    Uniform(f64),
    /// The Euler start `l = η` with its origin moved by the fraction given (a stiffness
    /// change at a phase of its `κ_g`), solved directly ([`seed_state`]).
    Shifted(f64),
    /// A state found by the diagram's completeness certificate (`crate::certificate`).
    Found,
}

/// A seed to solve: its length and how.
pub(super) type Job = (f64, Seed);

/// The seeds of branch `eta` at `l` from the uniform rod: every placement `shifts` of
/// [`crate::placements::PlacedProfile::placements`] there (the critical points of the placed
/// loop's energy and the mirror-symmetric placements) continued from the uniform rod.
pub(super) fn uniform_jobs(l: f64, shifts: &[f64]) -> Vec<Job> {
    shifts.iter().map(|&sh| (l, Seed::Uniform(sh))).collect()
}

/// The seeds of branch `eta` at `l` for where none of the [`uniform_jobs`] converges (a
/// family may fold away before the scene's contrast at this length, or reach it with
/// another dominant harmonic): the Euler start `l = η` with the stiffness change `s0*` at
/// the phases `j/(8η)`, `j = 0…3`, of its `κ_g` ([`crate::sampling::feature_shifts`]; half
/// a period, a shift by half a period is the reflection `κ_g → −κ_g`, and the profile's
/// mirror symmetry carries them to `s1*`), solved directly. A placement whose start is the
/// mirror image of an earlier one's ([`without_mirror_images`]) is left out: its states are
/// the images of the earlier one's, which the sheets count twice (multiplicity 2).
pub(super) fn euler_jobs(stiffness: &Stiffness, eta: u32, l: f64) -> Vec<Job> {
    let mut shifts = crate::sampling::feature_shifts(stiffness, eta, &[0, 1, 2, 3], false);
    if shifts.is_empty() {
        // A profile without named stiffness changes (a table): the phases at the origin.
        shifts = (0..4)
            .map(|j| f64::from(j) / (8.0 * f64::from(eta)))
            .collect();
    }
    let shifts = match super::images::mirror_axis(stiffness) {
        Some(axis) => without_mirror_images(&StartShape::Euler { l: eta }, l, axis, shifts),
        None => shifts,
    };
    shifts
        .into_iter()
        .map(|sh| (l, Seed::Shifted(sh)))
        .collect()
}

/// `shifts` less every shift whose start (`start` at `lbar` with its origin moved by it,
/// [`StartShape::shifted`]) is the mirror image `σ ↦ axis − σ` of an earlier kept one's, up
/// to the reflection `κ_g → −κ_g`: the two starts, compared on 256 points of the loop, agree
/// to 1e-9 of their largest value (distinct placements differ by a fraction of it). The
/// comparison is of the starts themselves, so it holds whatever the start's own symmetry.
pub(super) fn without_mirror_images(
    start: &StartShape,
    lbar: f64,
    axis: f64,
    shifts: Vec<f64>,
) -> Vec<f64> {
    let Ok(f) = start.interpolant(lbar) else {
        return shifts;
    };
    const POINTS: usize = 256;
    let sigma = |j: usize| j as f64 / POINTS as f64;
    let placed = |sh: f64| -> Vec<f64> { (0..POINTS).map(|j| f.eval(sigma(j) + sh)).collect() };
    let mirrored =
        |sh: f64| -> Vec<f64> { (0..POINTS).map(|j| f.eval(axis - sigma(j) + sh)).collect() };
    let scale = placed(0.0).iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let same = |a: &[f64], b: &[f64], sign: f64| {
        a.iter()
            .zip(b)
            .all(|(x, y)| (x - sign * y).abs() <= 1e-9 * scale)
    };
    // The kept shifts with the mirror images of their starts.
    let mut kept: Vec<(f64, Vec<f64>)> = Vec::new();
    for sh in shifts {
        let own = placed(sh);
        let image_of_kept = kept
            .iter()
            .any(|(_, m)| same(&own, m, 1.0) || same(&own, m, -1.0));
        if !image_of_kept {
            kept.push((sh, mirrored(sh)));
        }
    }
    kept.into_iter().map(|(sh, _)| sh).collect()
}

/// A seed length of [`seed_lengths`] with the placements
/// ([`crate::placements::PlacedProfile::placements`]) there.
pub(super) type SeedLength = (f64, Vec<f64>);

/// The lengths at which branch `eta` is seeded, by stretch, each with its placements: on
/// the certificate's sample lengths of `range` (those at least `2 ×` [`SWITCH_DISTANCE`]
/// from a great circle), the placements where families leave the uniform circle
/// ([`crate::placements::PlacedProfile::placements`]) are counted; each run of consecutive lengths
/// with the same count is a stretch, its lengths ordered from its middle outwards. Where
/// the count changes, families are born or end in pairs (a fold of the placed loop's
/// energy), so every stretch of the range with a different set of families gets its own
/// seeds.
pub(super) fn seed_lengths(
    stiffness: &Stiffness,
    eta: u32,
    range: (f64, f64),
    circles: &[f64],
) -> Vec<Vec<SeedLength>> {
    let (grid, _) = crate::sampling::sample_lengths(range.0, range.1);
    let placed = crate::placements::PlacedProfile::new(stiffness, eta)
        .map_err(|e| debug(|| format!("placements of eta {eta}: {e}")))
        .ok();
    let counted: Vec<SeedLength> = grid
        .into_iter()
        .filter(|l| {
            circles
                .iter()
                .all(|m| (l - m).abs() > 2.0 * SWITCH_DISTANCE)
        })
        .filter_map(|l| {
            let p = placed.as_ref()?.placements(l);
            match &p {
                Ok(p) => debug(|| format!("eta {eta} at {l:.4}: placements {p:.4?}")),
                Err(e) => debug(|| format!("placements of eta {eta} at {l}: {e}")),
            }
            p.ok().map(|p| (l, p))
        })
        .collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < counted.len() {
        let j = (i..counted.len())
            .find(|&j| counted[j].1.len() != counted[i].1.len())
            .unwrap_or(counted.len());
        let mid = (i + j - 1) / 2;
        let mut order: Vec<usize> = (i..j).collect();
        order.sort_by_key(|&k| (k.abs_diff(mid), k));
        out.push(order.into_iter().map(|k| counted[k].clone()).collect());
        i = j;
    }
    if out.is_empty() {
        let mid = 0.5 * (range.0 + range.1);
        let p = placed.and_then(|p| p.placements(mid).ok());
        out.push(vec![(mid, p.unwrap_or_default())]);
    }
    out
}

/// First step off the uniform rod in `ln(D1/D0)` (and the continuation's first step).
const FIRST_STEP: f64 = 0.05;

/// The state of branch `eta` at `lbar` on `model` (the tracing model, the scene's profile)
/// reached from the uniform rod's exact loop with its origin moved by `shift`: Newton at
/// `D1/D0 = e^{∓0.05}` from the loop ([`walk`], halving the step where Newton fails), then
/// pseudo-arclength continuation in `ln(D1/D0)` (the continuation crate's
/// [`reach`] on a log [`Axis`], through folds) to the scene's contrast, corrected there by
/// Newton. `None` where the family turns back before the scene's contrast (it does not exist
/// there at this length), or the state has another count of periods or does not close.
pub(super) fn uniform_seed<M: SurfaceSolve>(
    model: &M,
    stiffness: &Stiffness,
    eta: u32,
    lbar: f64,
    shift: f64,
) -> Option<Vec<f64>> {
    let fail = |what: &str, e: String| {
        debug(|| format!("uniform seed {eta} at {lbar:.4} shift {shift:.4}: {what}: {e}"));
    };
    let ratio = stiffness.param(Param::D1).ok()?;
    let qt = ratio.ln();
    let problem = ParamProblem::new(model.clone(), Param::D1).ok()?;
    let kappa = StartShape::Exact { eta }
        .shifted(lbar, shift)
        .and_then(|st| model.start_values(&st))
        .map_err(|e| fail("start", e.to_string()))
        .ok()?;
    let newton = crate::states::newton_options();
    let q1 = qt.signum() * qt.abs().min(FIRST_STEP);
    // The walk's state: `(z, q)`; the start `(κ, 0)` holds the Gauss values only.
    let first = walk(
        (kappa, 0.0),
        None,
        q1,
        |s: &(Vec<f64>, f64)| s.1,
        &NaturalSettings {
            max_halvings: 4,
            ..NaturalSettings::default()
        },
        |cur, _, to, _| {
            let m = problem.model_at(to.exp())?;
            let eq = if cur.1 == 0.0 {
                m.solve(&cur.0, &newton)?
            } else {
                m.solve_from_state(cur.0.clone(), &newton)?
            };
            Ok::<_, rodloop_solver::SolverError>((eq.state(), to))
        },
    )
    .map_err(|e| fail("first step", e.error.to_string()))
    .ok()?;
    let (mut z, q) = first.last;
    if (qt - q).abs() > 1e-14 {
        let settings = PseudoArclength::new()
            .with_ds(FIRST_STEP)
            .and_then(|s| s.with_ds_bounds(1e-7, 0.5))
            .and_then(|s| {
                s.with_direction(if qt < q {
                    Direction::Backward
                } else {
                    Direction::Forward
                })
            })
            .and_then(|s| s.with_max_steps(400))
            .and_then(|s| s.with_detect_branch_points(false))
            .ok()?;
        let log = OnAxis {
            problem: problem.clone(),
            axis: Axis::Log,
        };
        let x0 = nalgebra::DVector::from_vec(z);
        let r = reach(&log, &settings, &x0, q, qt, &ReachLimits::default(), || {
            true
        })
        .map_err(|e| {
            fail(
                "continuation in D1/D0",
                format!(
                    "reached {:.4} (folds at {:?})",
                    e.closest.exp(),
                    e.folds.iter().map(|f| f.exp()).collect::<Vec<_>>()
                ),
            )
        })
        .ok()?;
        z = r.x.as_slice().to_vec();
    }
    let eq = model
        .clone()
        .solve_from_state(z, &newton)
        .map_err(|e| fail("Newton at the scene's contrast", e.to_string()))
        .ok()?;
    let periods = periods_of(&eq).ok()?;
    if periods != eta as usize {
        fail("periods", format!("{periods} periods of κ_g"));
        return None;
    }
    open_dropped(&eq, eta, lbar).then(|| eq.state())
}

/// The state `rodloop solve --branch` finds for `eta` at `lbar` (`solve_robust` from the
/// Euler curve, fast accuracy), re-solved on `model` (the tracing resolution). Without
/// `rodloop solve`'s continuation in `L̄` (the tracer follows those families itself,
/// [`seed_jobs`]); with `starts`, its direct and shifted starts only, without, its
/// homotopies in `D1/D0` only.
pub(super) fn robust_seed<M: SurfaceSolve>(
    opts: &DiagramOptions,
    model: &M,
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
    model
        .solve(&kappa, &crate::states::newton_options())
        .ok()
        .filter(|eq| open_dropped(eq, eta, lbar))
        .map(|eq| eq.state())
}

/// `true` if `eq` closes ([`crate::sampling::closes`]); an open KKT point (half-turn
/// holonomy) is no seed.
fn open_dropped(eq: &rodloop_solver::Equilibrium, eta: u32, lbar: f64) -> bool {
    let ok = crate::sampling::closes(eq);
    if !ok {
        debug(|| format!("seed of eta {eta} at {lbar}: the loop does not close, dropped"));
    }
    ok
}

/// The state of an Euler start of `eta` periods with its origin moved by `shift`, relaxed
/// and solved on `model` (the tracing resolution), if it has `eta` periods of `κ_g` and
/// closes.
pub(super) fn seed_state<M: SurfaceSolve>(
    model: &M,
    eta: u32,
    lbar: f64,
    shift: f64,
) -> Option<Vec<f64>> {
    let start = StartShape::Euler { l: eta }.shifted(lbar, shift).ok()?;
    let kappa = model.start_values(&start).ok()?;
    let eq = model
        .solve(&kappa, &SolveOptions::default())
        .map_err(|e| debug(|| format!("seed solve failed: {e}")))
        .ok()?;
    (periods_of(&eq).ok()? == eta as usize && open_dropped(&eq, eta, lbar)).then(|| eq.state())
}
