//! Leaving a saddle: from an enclosed equilibrium with Hessian index ≥ 1 on the tangent
//! space of its active constraints, a step along the eigenvector of the most negative
//! eigenvalue (both signs) lowers the energy at second order; Newton from there finds
//! the equilibrium that the unstable direction leads to (the enclosed diagram uses it
//! where its lowest traced state is unstable, so that a lower state must exist).
//!
//! Every route to the lowest state of an enclosed branch ends in [`solve_branch_lowest`]
//! (this file), which compares the states they reach with one period count:
//!
//! * `saddle.rs`: descent from a saddle along its unstable directions;
//! * `homotopy.rs`: starts by continuation in the stiffness from the uniform rod's loop;
//! * [`crate::enclosed::length_path`]: local minima of other lengths continued in `L̄`
//!   (its lengths and continuation; the search over them is
//!   [`states_by_length_continuation`], here).
//!
//! [`EnclosedSaddle`] is the enclosed model's side of the one descent routine
//! ([`crate::descend::descend`]): the same unstable directions and Newton solves, with the
//! branch of a state read from the periods of its curvature ([`enclosed_periods`]).

mod homotopy;
mod saddle;

pub use homotopy::{
    distinct_lowest_first, homotopy_shifts, profile_features, stiffness_homotopy_starts,
    stiffness_homotopy_states, stiffness_path_from_shift,
};
pub use saddle::{
    descend, descend_branch, enclosed_periods, solve_branch_descended, unstable_direction,
    unstable_directions, DescendedSolve, EnclosedSaddle,
};

use crate::descend::{descend as descend_saddle, Descent, DescentSettings, SaddleModel};
use crate::enclosed::branch::{
    branch_from_levels, resample_state, solve_from_surface, solve_levels, solve_levels_from_fine,
    BranchSolve, SurfaceSource,
};
use crate::enclosed::length_path::{continue_in_length, continue_on_finer, probe_lengths};
use crate::enclosed::solve::{solve_enclosed, solve_prolonged, EnclosedOptions, EnclosedState};
use crate::enclosed::wall::IntoWall;
use crate::SolverError;
/// A state found on a coarse mesh as a solve with `cells` cells and its levels: its
/// curvature carried to `cells/4` and cascaded ([`solve_levels`]); where that does not
/// converge (point contacts, whose contact nodes move between meshes), the cascade on the
/// state's own mesh, its finest level carried to `cells` and its levels re-solved from
/// there ([`solve_levels_from_fine`]), else that cascade as it is.
fn carry_to_ladder(s: &EnclosedState, cells: usize, opts: &EnclosedOptions) -> Option<BranchSolve> {
    let here = s.model.cells();
    if here == cells / 4 {
        return solve_levels(&s.model, s.z.clone(), None, opts).ok();
    }
    if let Ok(b) = resample_state(s, cells / 4).and_then(|(m, z)| solve_levels(&m, z, None, opts)) {
        return Some(b);
    }
    let own = solve_levels(&s.model, s.z.clone(), None, opts).ok()?;
    let watchdog = EnclosedOptions {
        watchdog: opts.watchdog.max(2),
        ..opts.clone()
    };
    let fine = resample_state(&own.fine, cells)
        .and_then(|(m, z)| solve_enclosed(&m, z, &watchdog))
        .and_then(|f| solve_levels_from_fine(f, opts));
    Some(fine.unwrap_or(own))
}

/// The local minimum `probe` (at another length, on a coarse mesh) carried to a ladder of
/// `cells` cells there ([`carry_to_ladder`]) and continued in `L̄` to `lbar`
/// ([`continue_in_length`]) level by level, as the enclosed diagram walks the levels of its
/// traces. A level's walk can fail where another's does not (a point contact between two
/// nodes makes the contact set cycle on some meshes only): such a level is re-solved from one
/// that arrived (the finer first): prolonged with its contact runs kept
/// ([`EnclosedState::refine_in_runs`], [`solve_prolonged`]) from the level of half its cells,
/// else resampled to its cells (Newton with the watchdog of prolonged starts). `None` unless
/// the three levels' energies converge (the second difference smaller than the first: levels
/// continued separately may end on different families).
fn continue_ladder(
    probe: &EnclosedState,
    lbar: f64,
    cells: usize,
    opts: &EnclosedOptions,
) -> Option<BranchSolve> {
    let at_probe = carry_to_ladder(probe, cells, opts)?;
    let arrived: Vec<Option<EnclosedState>> = [&at_probe.fine, &at_probe.coarse, &at_probe.quarter]
        .iter()
        .map(|level| continue_in_length(level, lbar, opts).ok())
        .collect();
    let watchdog = EnclosedOptions {
        watchdog: opts.watchdog.max(2),
        ..opts.clone()
    };
    // A level of `n` cells re-solved from `there`, one that arrived.
    let from_level = |there: &EnclosedState, n: usize| -> Option<EnclosedState> {
        let prolonged = if there.model.cells() * 2 == n {
            there
                .refine_in_runs()
                .and_then(|(m, z)| solve_prolonged(&m, z, opts))
                .ok()
        } else {
            None
        };
        prolonged.or_else(|| {
            resample_state(there, n)
                .and_then(|(m, z)| solve_enclosed(&m, z, &watchdog))
                .ok()
        })
    };
    let sizes = [cells, cells / 2, cells / 4];
    let levels: Vec<EnclosedState> = sizes
        .iter()
        .zip(&arrived)
        .map(|(&n, own)| {
            own.clone()
                .or_else(|| arrived.iter().flatten().find_map(|t| from_level(t, n)))
        })
        .collect::<Option<_>>()?;
    let [f, c, q] = <[EnclosedState; 3]>::try_from(levels).ok()?;
    let (d1, d2) = (
        (c.energy() - q.energy()).abs(),
        (f.energy() - c.energy()).abs(),
    );
    (d2 < d1)
        .then(|| branch_from_levels(f, c, q).ok())
        .flatten()
}

/// What [`solve_branch_lowest`] returns: [`DescendedSolve`] and `true` where the state
/// reported is not the one reached from the surface loop but a lower local minimum from
/// [`stiffness_homotopy_states`].
pub type LowestSolve = (DescendedSolve, bool);

/// The lowest local minimum of branch `eta` that an enclosed `solve` finds at `lbar`:
/// [`solve_branch_descended`] from the surface loop `source`, and for a non-uniform rod
/// the states reached by continuation in the stiffness from the uniform rod's loop
/// ([`stiffness_homotopy_states`], on `8(2 + η)` cells and carried to `N/4` of the first
/// mesh of `ladder`), each cascaded to `N/2, N` ([`solve_levels`]) and descended where it is a saddle ([`descend_branch`]).
/// Then the local minima of the branch found at the nearest other lengths (on the same coarse
/// mesh, [`crate::enclosed::length_path`]) are cascaded there and continued in `L̄` to `lbar`
/// level by level (`continue_ladder`, as the enclosed diagram walks a stable family
/// through the branch's range), else continued on the coarse mesh and cascaded at `lbar`,
/// and descended in the same way; where none of the starts above is a local minimum, the
/// stiffness paths at the nearest lengths are continued too. On two-segment rods drawn at
/// random these are the routes to the branch's lowest minimum: `D1/D0 = 0.661` on
/// `0.299 ≤ s/L ≤ 0.866`, `γ = 49.2`, at `L̄ = 1.45` (the surface loop leads to a saddle
/// only, and the minimum continued from 1.35 on 24 cells does not cascade to 96), and
/// `D1/D0 = 0.268` on `0.492 ≤ s/L ≤ 0.822`, `γ = 47.7`, branch 1 at `L̄ = 2.468938` (the
/// surface loop leads to a minimum 4.8e-4 above the one continued from 2.368938).
/// Of the states of branch `eta`, an index-0 one goes before any with index > 0, and the
/// lowest of those is returned. The semismooth Newton from the surface loop stops at the
/// equilibrium next to it, which need not be the lowest minimum of the branch.
pub fn solve_branch_lowest(
    wall: impl IntoWall,
    lbar: f64,
    eta: u32,
    stiffness: &crate::Stiffness,
    source: &SurfaceSource,
    ladder: &[usize],
    opts: &EnclosedOptions,
) -> Result<LowestSolve, SolverError> {
    let wall = wall.into_wall();
    let base = solve_branch_descended(&wall, lbar, stiffness, source, ladder, opts);
    if stiffness.is_uniform() {
        return base.map(|b| (b, false));
    }
    let saddle = EnclosedSaddle {
        opts: opts.clone(),
        ..EnclosedSaddle::default()
    };
    let cells = ladder.first().copied().unwrap_or(0);
    let rank = |b: &BranchSolve| -> Option<(usize, f64)> {
        let index = b.index(saddle.tol).ok()?;
        let same = enclosed_periods(&b.fine).ok().map(|p| p.eta) == Some(eta);
        same.then_some((usize::from(index > 0), b.energy))
    };
    // Lower by more than round-off: the same state reached by another route (the minima
    // continued in L̄ end on the ones found here, to 1e-10) stays the first route's.
    let better = |x: (usize, f64), y: (usize, f64)| {
        x.0 < y.0 || (x.0 == y.0 && x.1 < y.1 - 1e-9 * y.1.abs().max(1.0))
    };
    // The best state of the other routes, with the route that reaches it.
    type Found = Option<(BranchSolve, Option<Descent<EnclosedState>>, String)>;
    let mut best: Found = None;
    let offer = |best: &mut Found, b: BranchSolve, d: Option<Descent<EnclosedState>>, route| {
        let Some(r) = rank(&b) else { return };
        if best
            .as_ref()
            .and_then(|(o, _, _)| rank(o))
            .is_none_or(|o| better(r, o))
        {
            *best = Some((b, d, route));
        }
    };
    // The path is followed on the coarsest mesh that resolves the profile (the `N/4` level
    // of the diagram's default mesh, `8(2 + η)` cells), so that every accuracy follows the
    // same path; its end is carried to this ladder's `N/4`.
    let search = (8 * (2 + eta as usize)).min(cells / 4);
    if cells >= 32 && cells % 4 == 0 {
        for (phi, s) in
            stiffness_homotopy_starts(&wall, lbar, eta, stiffness, search, opts).unwrap_or_default()
        {
            let Some(b) = carry_to_ladder(&s, cells, opts) else {
                continue;
            };
            let Ok((b, d)) = descend_branch(b, opts) else {
                continue;
            };
            offer(&mut best, b, d, format!("continuation in the stiffness from the uniform rod's loop with its arclength origin shifted by {phi:.4} L"));
        }
    }
    // Local minima reached at other lengths of the branch, continued in L̄: a lower one than
    // those found here, or where none was found, one at all (then also from the stiffness
    // paths at the probe lengths, the costly start).
    let stable = |b: &BranchSolve| rank(b).is_some_and(|r| r.0 == 0);
    let found_minimum = base.as_ref().is_ok_and(|b| stable(&b.0))
        || best.as_ref().is_some_and(|(b, _, _)| stable(b));
    if cells >= 32 && cells % 4 == 0 {
        let radius = wall.radius();
        let surface = |x: f64| {
            SurfaceSource::numeric(radius, x, stiffness, eta, crate::Accuracy::Fast)
                .ok()
                .map(|(s, _)| s)
        };
        for (x, s, probe) in states_by_length_continuation(
            &wall,
            lbar,
            eta,
            stiffness,
            search,
            opts,
            surface,
            !found_minimum,
        ) {
            // The probe length's minimum carried to the ladder there and its levels continued,
            // else the state continued on the coarse mesh carried to the ladder.
            let carried = continue_ladder(&probe, lbar, cells, opts)
                .or_else(|| carry_to_ladder(&s, cells, opts));
            let Some(b) = carried else {
                continue;
            };
            let Ok((b, d)) = descend_branch(b, opts) else {
                continue;
            };
            offer(
                &mut best,
                b,
                d,
                format!("continuation in lbar from a local minimum of the branch at lbar = {x:.4}"),
            );
        }
    }
    match (base, best) {
        (Ok(base), Some((b, d, route))) => {
            let replace = match (rank(&base.0), rank(&b)) {
                (Some(x), Some(y)) => better(y, x),
                (None, Some(_)) => true,
                _ => false,
            };
            if !replace {
                return Ok((base, false));
            }
            let mut notes = base.2;
            notes.push(format!(
                "the state reached from the surface loop (E R/(pi D0) = {:.10}) is not the lowest local minimum found: {route} reaches this one",
                base.0.energy
            ));
            Ok(((b, d, notes), true))
        }
        (Ok(base), None) => Ok((base, false)),
        (Err(_), Some((b, d, route))) => Ok((
            (
                b,
                d,
                vec![format!("the solve from the surface loop did not converge; the state comes from {route}")],
            ),
            true,
        )),
        (Err(e), None) => Err(e),
    }
}

/// Amplitudes of the descents of [`local_minima`] (as [`descend_branch`]).
const AMPLITUDES: [f64; 5] = [0.02, 0.05, 0.15, 0.3, 0.5];

/// Local minima (index 0) of branch `eta` at `lbar` on `cells` cells reached from `starts`,
/// each descended where it is a saddle ([`crate::descend::descend`]). Lowest first.
fn local_minima(
    starts: Vec<EnclosedState>,
    eta: u32,
    opts: &EnclosedOptions,
) -> Vec<EnclosedState> {
    let saddle = EnclosedSaddle {
        opts: opts.clone(),
        ..EnclosedSaddle::default()
    };
    let settings = DescentSettings {
        amplitudes: AMPLITUDES.to_vec(),
        ..DescentSettings::default()
    };
    let mut out: Vec<EnclosedState> = starts
        .into_iter()
        .filter_map(|s| descend_saddle(&saddle, s, &settings).ok())
        .map(|d| d.state)
        .filter(|s| saddle.index(s).ok() == Some(0))
        .filter(|s| enclosed_periods(s).ok().map(|p| p.eta) == Some(eta))
        .collect();
    out.sort_by(|a, b| a.energy().total_cmp(&b.energy()));
    out
}

/// Probe lengths ([`probe_lengths`], nearest first) at which the stiffness paths
/// ([`stiffness_homotopy_states`], one continuation per shift: the costly start) are
/// searched, after the surface loop has been tried at every probe length.
pub const STIFFNESS_PROBES: usize = 2;

/// A state of [`states_by_length_continuation`]: the probe length `x`, the state continued
/// to the length asked for, and the local minimum at `x` it was continued from.
pub type Continued = (f64, EnclosedState, EnclosedState);

/// Local minima of branch `eta` at lengths of [`probe_lengths`], continued to `lbar`: the
/// states at `lbar` on `cells` cells of branch `eta`, lowest first (their index may have
/// changed on the way), each with the length it comes from and the minimum there
/// ([`Continued`]). The starts at a probe length
/// `x`: the enclosed state from the surface loop `surface(x)` (where one is solved), at the
/// probe lengths in turn up to the first that gives a state at `lbar`, and, unless that
/// state arrives as a local minimum, the stiffness paths at the [`STIFFNESS_PROBES`] nearest
/// ones, every one of them (the families they reach differ from the surface loop's: on the
/// two-segment rod of Eq. (51), `D1/D0 = 0.5`,
/// at `L̄ = 1.328827` the surface loop's minimum from 1.5288 continues to the saddle
/// 1.8169945712 that the surface loop reaches there too, a stiffness path's from 1.4288 to
/// the stable state 1.7488917142 that the enclosed diagram traces there); each descended
/// where it is a saddle. Empty when none gives a state. `exhaustive = false` (the caller has a
/// local minimum already and looks for a lower one) searches the two nearest probe lengths
/// only and leaves the stiffness paths out.
#[allow(clippy::too_many_arguments)]
pub fn states_by_length_continuation<F>(
    wall: impl IntoWall,
    lbar: f64,
    eta: u32,
    stiffness: &crate::Stiffness,
    cells: usize,
    opts: &EnclosedOptions,
    surface: F,
    exhaustive: bool,
) -> Vec<Continued>
where
    F: Fn(f64) -> Option<SurfaceSource>,
{
    let wall = wall.into_wall();
    // The minima whose walk on their own mesh fails are kept for the walks on finer meshes.
    let mut stuck: Vec<(f64, EnclosedState)> = Vec::new();
    let of_branch = |s: &EnclosedState| enclosed_periods(s).ok().map(|p| p.eta) == Some(eta);
    let mut continued = |x: f64, minima: Vec<EnclosedState>| -> Vec<Continued> {
        let mut out: Vec<Continued> = Vec::new();
        for s in minima {
            match continue_in_length(&s, lbar, opts) {
                Ok(at) => out.push((x, at, s)),
                Err(_) => stuck.push((x, s)),
            }
        }
        out.retain(|(_, s, _)| of_branch(s));
        out.sort_by(|a, b| a.1.energy().total_cmp(&b.1.energy()));
        out
    };
    let lengths = probe_lengths(lbar, eta);
    let mut all = Vec::new();
    let searched = if exhaustive { lengths.len() } else { 2 };
    for &x in lengths.iter().take(searched) {
        let Some(src) = surface(x) else { continue };
        let Ok(s) = solve_from_surface(&wall, x, stiffness, &src, cells, opts) else {
            continue;
        };
        let out = continued(x, local_minima(vec![s], eta, opts));
        if !out.is_empty() {
            all.extend(out);
            break;
        }
    }
    // The stiffness paths where the surface loop's minimum does not arrive as a local
    // minimum (their continuations are the costly start).
    let arrived = |all: &[Continued]| all.iter().any(|(_, s, _)| s.index(1e-6).ok() == Some(0));
    if !arrived(&all) && exhaustive {
        for &x in lengths.iter().take(STIFFNESS_PROBES) {
            let starts = stiffness_homotopy_states(&wall, x, eta, stiffness, cells, opts)
                .unwrap_or_default();
            all.extend(continued(x, local_minima(starts, eta, opts)));
        }
    }
    // Where still none arrives as a local minimum, the minima whose walk failed are walked
    // on finer meshes ([`continue_on_finer`]): a fold of the coarse mesh's family that the
    // finer meshes do not have.
    if !arrived(&all) {
        for (x, s) in stuck {
            let Ok(at) = continue_on_finer(&s, lbar, opts) else {
                continue;
            };
            if of_branch(&at) {
                all.push((x, at, s));
            }
        }
    }
    all.sort_by(|a, b| a.1.energy().total_cmp(&b.1.energy()));
    all
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::enclosed::branch::solve_branch;
    use crate::Stiffness;

    /// Enclosed states started from the exact loops of the paper's branches (uniform rod):
    /// [`enclosed_periods`] names the branch of the state reached, attached (η = 2 at
    /// L̄ = 1.5, η = 3 at 2.5) or lifted off (the figure-eight, η = 1, at L̄ = 1.4).
    #[test]
    fn enclosed_states_are_identified_as_their_branch() {
        let st = Stiffness::Uniform { d: 1.0 };
        for (eta, lbar) in [(2u32, 1.5), (1, 1.4), (3, 2.5)] {
            let l = rodloop_exact::paper_branch_loop(eta, lbar).unwrap();
            let b = solve_branch(
                1.0,
                lbar,
                &st,
                &SurfaceSource::Exact(l),
                64,
                &EnclosedOptions::default(),
            )
            .unwrap();
            let p = enclosed_periods(&b.fine).unwrap();
            assert_eq!(p.eta, eta, "eta {eta} at {lbar}: {p:?}");
            assert!(p.consistent(), "eta {eta} at {lbar}: {p:?}");
            // Attached where the surface loop needs no pulling wall, lifted off otherwise.
            let attached = b.fine.contact(1e-9).unwrap().fraction >= 1.0;
            assert_eq!(attached, eta != 1, "eta {eta} at {lbar}");
        }
    }

    /// The rotation angle about the tangent with which the rotation-minimising frame of a
    /// state comes back after one loop (its holonomy, `−∮τ ds` mod 2π).
    fn holonomy(s: &EnclosedState) -> f64 {
        let p = s.model.transforms(&s.z).unwrap();
        let x = &p[s.model.cells()];
        (x[(2, 1)] - x[(1, 2)]).atan2(x[(1, 1)] + x[(2, 2)])
    }

    /// The two-segment rod of the paper's Sec. 5 (`D1/D0 = 0.5`) in the ball at `L̄ = 1.35`,
    /// branch 2 (η = 1), `N = 96`. Two routes that share no start: the uniform rod's
    /// loop continued in the stiffness ([`stiffness_homotopy_states`]), and a loop shrunk
    /// into the ball (the two-segment surface loop at `L̄/a` on the sphere of radius
    /// `a R`, `a = 0.95, 0.9`, which has the same length and touches nothing) relaxed by
    /// Newton and the descent from saddles. The lowest local minimum found is a bending-only equilibrium
    /// whose frame does not return (a pure-bending rod carries no twisting moment, so the
    /// holonomy is free), and no route finds a lower minimum.
    #[test]
    fn two_segment_figure_eight_minimum_needs_no_twisting_moment() {
        let st = Stiffness::Tanh {
            d0: 1.0,
            d1: 0.5,
            s0: 0.3,
            s1: 0.8,
            gamma: 200.0,
        };
        let (lbar, eta, cells) = (1.35, 1u32, 96usize);
        let opts = EnclosedOptions::default();
        let saddle = EnclosedSaddle::default();
        let minimum = |b: BranchSolve| -> Option<BranchSolve> {
            let (b, _) = descend_branch(b, &opts).ok()?;
            let ok =
                saddle.index(&b.quarter).ok()? == 0 && enclosed_periods(&b.fine).ok()?.eta == eta;
            ok.then_some(b)
        };
        // Route 1: the stiffness path.
        let path: Vec<BranchSolve> =
            stiffness_homotopy_states(1.0, lbar, eta, &st, cells / 4, &opts)
                .unwrap()
                .into_iter()
                .filter_map(|s| solve_levels(&s.model, s.z.clone(), None, &opts).ok())
                .filter_map(minimum)
                .collect();
        let best = path
            .iter()
            .min_by(|a, b| a.energy.total_cmp(&b.energy))
            .expect("an index-0 state of branch 2 from the stiffness path");
        // A bending-only equilibrium: stationary, the frame turned about the tangent.
        let (_, _, comp, stat) = best.fine.optimality().unwrap();
        assert!(comp < 1e-8 && stat < 1e-8, "{comp:e} {stat:e}");
        let alpha = holonomy(&best.fine);
        assert!(alpha.abs() > 1e-2, "holonomy {alpha}");
        // Route 2: loops shrunk into the ball (radius `a R`, touching nothing), relaxed by
        // Newton, cascaded and descended where they are saddles: every state of the branch
        // they reach lies no lower than the stiffness path's minimum.
        let mut reached = Vec::new();
        for a in [0.95, 0.9] {
            let (res, _) = crate::solve_robust(
                1.0,
                lbar / a,
                &st,
                &crate::StartShape::Euler { l: eta },
                crate::Accuracy::Default,
                Some(eta),
                &crate::SolveOptions::default(),
            )
            .unwrap();
            let (m, z) = crate::enclosed::solve::start_from_curvature(
                1.0,
                lbar,
                cells / 4,
                &st,
                |s| {
                    let k = res.equilibrium.sample_at(&[s]).unwrap()[0];
                    (k / a, -1.0 / a)
                },
                [0.0, 0.0, a],
            )
            .unwrap();
            let gmin = m
                .gaps(&z)
                .unwrap()
                .iter()
                .cloned()
                .fold(f64::INFINITY, f64::min);
            assert!(gmin > 0.03, "the loop shrunk to {a} R touches ({gmin})");
            let relaxed = solve_enclosed(&m, z, &opts)
                .ok()
                .and_then(|s| solve_levels(&s.model, s.z.clone(), None, &opts).ok())
                .and_then(|b| descend_branch(b, &opts).ok())
                .map(|(b, _)| b)
                .filter(|b| enclosed_periods(&b.fine).ok().map(|p| p.eta) == Some(eta));
            if let Some(b) = relaxed {
                println!(
                    "stiffness path {:.10} ± {:.1e} (holonomy {alpha:.4}), loop shrunk to {a} R: {:.10} ± {:.1e}, index {}",
                    best.energy,
                    best.energy_error,
                    b.energy,
                    b.energy_error,
                    saddle.index(&b.quarter).unwrap()
                );
                reached.push(b);
            }
        }
        assert!(
            !reached.is_empty(),
            "no shrunk loop relaxes to a state of the branch"
        );
        for b in &reached {
            assert!(
                best.energy <= b.energy + 3.0 * (best.energy_error + b.energy_error),
                "a shrunk loop relaxes below the lowest minimum found: {} against {}",
                b.energy,
                best.energy
            );
        }
    }
}
