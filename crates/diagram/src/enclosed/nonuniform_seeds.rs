//! Lifted-off families that the surface families do not lead to (enclosed diagram of a
//! non-uniform rod, see `nonuniform.rs`). The Newton solve from a surface state stops at the
//! equilibrium next to it; the loop that lifts far off the wall (the two-segment figure-eight
//! with `D1/D0 = 0.5` at `L̄ = 1.35` touches on a quarter of its length and reaches `0.63 R`
//! inside, 2.5 % below the state next to the surface loop) is reached instead by continuation
//! in the stiffness from the uniform rod's loop of the branch (`stiffness_homotopy_states`,
//! its shifts on the crate's pool). At the sampled lengths of a branch that no family found
//! here covers yet (at least [`SEED_SPACING`] apart, and only where the branch lies within
//! [`RELEVANT`] of the lowest traced state), that search runs on the `N/4` mesh of the
//! traces; each state found is cascaded to `N/2, N` and descended where it is a saddle (as
//! `solve`'s search does), and one below the branch's traced states is traced through the
//! branch's sampled lengths as a new family.

use rodloop_exact::eta_of_branch;
use rodloop_solver::enclosed::descent::{
    descend_branch, distinct_lowest_first, homotopy_shifts, stiffness_path_from_shift,
};
use rodloop_solver::enclosed::solve_levels;
use rodloop_solver::enclosed::stats::{self, Stage};

use super::levels::Levels;
use super::nonuniform_exchange::interp;
use super::nonuniform_sheet::SheetOut;
use super::trace::follow;
use super::trace::step_options;
use super::EnclosedDiagramOptions;
use crate::parallel::{parallel_map, run_parallel};
use rodloop_solver::enclosed::nonuniform_cells;

/// Least distance in `L̄` between two lengths searched for one branch: a family found is
/// traced through all the branch's sampled lengths, so the search needs to meet it once.
const SEED_SPACING: f64 = 0.1;

/// A branch is searched where its lowest traced state lies within this fraction of the
/// lowest traced state of any branch: the states the stiffness path finds lie a few percent
/// below the traced ones (2.5 % for the two-segment figure-eight at `L̄ = 1.35`), so a
/// branch further above cannot become the lowest through them.
const RELEVANT: f64 = 0.1;

/// How far below the branch's lowest traced energy a state found must lie to seed a family:
/// three times its error estimate plus `1e-6` relative (as the surface certificate's margin).
fn below(energy: f64, error: f64, lowest: Option<f64>) -> bool {
    lowest.is_none_or(|e| energy < e - 3.0 * error - 1e-6 * energy.abs().max(1.0))
}

/// The lowest energy at `x` among `sheets` of branch `branch`.
fn lowest_of_branch(sheets: &[SheetOut], branch: u32, x: f64) -> Option<f64> {
    sheets
        .iter()
        .filter(|s| s.branch == branch)
        .filter_map(|s| interp(s, x))
        .min_by(f64::total_cmp)
}

/// The states of branch `eta` at `lbar` on `cells` cells that the stiffness path reaches,
/// one continuation per shift of the uniform rod's loop, the shifts on the crate's pool (the
/// branches' searches run as tasks of their own, and one branch's lengths one after the
/// other, so the shifts are where the cores find work): the states of
/// `stiffness_homotopy_states`, in its order.
fn stiffness_paths(
    opts: &EnclosedDiagramOptions,
    lbar: f64,
    eta: u32,
    cells: usize,
    dopts: &rodloop_solver::enclosed::EnclosedOptions,
) -> Result<Vec<(f64, rodloop_solver::enclosed::EnclosedState)>, rodloop_solver::SolverError> {
    let shifts = homotopy_shifts(&opts.stiffness, eta, lbar)?;
    let scope = stats::current();
    let reached = parallel_map(&shifts, |&phi| {
        stats::within(&scope, || {
            stats::stage(Stage::StiffnessPath, || {
                stiffness_path_from_shift(
                    opts.radius,
                    lbar,
                    eta,
                    &opts.stiffness,
                    cells,
                    dopts,
                    phi,
                )
            })
        })
    });
    let mut kept = Vec::new();
    for (phi, r) in shifts.into_iter().zip(reached) {
        if let Some(s) = r? {
            kept.push((phi, s));
        }
    }
    Ok(distinct_lowest_first(kept))
}

/// The families of one branch found from the stiffness path (see the module docs), traced
/// through `grid` (the branch's sampled lengths), with the lengths searched.
fn seed_branch(
    opts: &EnclosedDiagramOptions,
    outs: &[SheetOut],
    branch: u32,
    grid: &[f64],
) -> (Vec<SheetOut>, usize) {
    let eta = eta_of_branch(branch);
    let n = nonuniform_cells(opts.accuracy, eta);
    let sopts = step_options();
    let dopts = rodloop_solver::enclosed::EnclosedOptions::default();
    let mut added: Vec<SheetOut> = Vec::new();
    let mut searched = 0;
    // From the middle of the range outward: a family traced from there covers most of it.
    let mid = grid.len() / 2;
    let mut order: Vec<usize> = (0..grid.len()).collect();
    order.sort_by_key(|&i| (i as i64 - mid as i64).abs());
    let next_family = outs
        .iter()
        .filter(|s| s.branch == branch)
        .map(|s| s.family)
        .max()
        .unwrap_or(0)
        + 1;
    let mut at: Vec<f64> = Vec::new();
    for i in order {
        let x = grid[i];
        if added.iter().any(|s| interp(s, x).is_some())
            || at.iter().any(|&y| (y - x).abs() < SEED_SPACING - 1e-9)
        {
            continue;
        }
        // Only where the branch can be lowest: its traced states within `RELEVANT` of the
        // lowest traced state of any branch.
        let (Some(eb), Some(ea)) = (
            lowest_of_branch(outs, branch, x),
            outs.iter()
                .filter_map(|s| interp(s, x))
                .min_by(f64::total_cmp),
        ) else {
            continue;
        };
        if eb > (1.0 + RELEVANT) * ea {
            continue;
        }
        at.push(x);
        searched += 1;
        let Ok(found) = stiffness_paths(opts, x, eta, n / 4, &dopts) else {
            continue;
        };
        for (_, s) in found {
            // Cascaded, and descended where it is a saddle, as `solve`'s search treats the
            // states of the stiffness paths (`solve_branch_lowest`): on random seed 6 of
            // `tests/random_enclosed.rs` (`D1/D0 = 0.289` on `0.502 ≤ s/L ≤ 0.921`) the path
            // at `L̄ = 1.3276` ends at a saddle above the traced branch-2 states whose descent
            // reaches a minimum 2.2e-2 below them, lifted to within `0.03 R` of the centre.
            let levels = stats::stage(Stage::StiffnessPath, || {
                solve_levels(&s.model, s.z.clone(), None, &dopts)
                    .and_then(|b| descend_branch(b, &dopts))
            });
            let Ok((b, _)) = levels else {
                continue;
            };
            let first = Levels {
                lbar: x,
                states: [b.quarter, b.coarse, b.fine],
            };
            let (e, err) = first.energy();
            let traced_low = lowest_of_branch(outs, branch, x);
            let added_low = added
                .iter()
                .filter_map(|s| interp(s, x))
                .min_by(f64::total_cmp);
            if !below(e, err, traced_low) || !below(e, err, added_low) {
                continue;
            }
            let family = next_family + added.len() as u32;
            let what = format!("branch {branch} (eta = {eta}) family {family} (stiffness path)");
            let mut out = SheetOut::empty(branch, eta, family);
            let traced = follow(first, grid, i, &what, &sopts, true, &mut out.stops);
            for l in traced {
                let Ok(mut pt) = l.point(branch, eta) else {
                    continue;
                };
                pt.family = family;
                pt.sheet = 0;
                pt.multiplicity = 1;
                pt.surface_energy = None;
                out.points.push(pt);
                out.levels.push(l);
            }
            if !out.points.is_empty() {
                out.points.sort_by(|u, v| u.lbar.total_cmp(&v.lbar));
                out.levels.sort_by(|u, v| u.lbar.total_cmp(&v.lbar));
                added.push(out);
                break;
            }
        }
    }
    (added, searched)
}

/// Add the families found from the stiffness path to `outs` (see the module docs); one
/// branch per task on `threads` threads. Returns a note per branch searched.
pub(super) fn seed_from_stiffness_path(
    opts: &EnclosedDiagramOptions,
    outs: &mut Vec<SheetOut>,
    threads: usize,
) -> Vec<String> {
    if opts.stiffness.is_uniform() {
        return Vec::new();
    }
    let mut branches: Vec<u32> = outs.iter().map(|s| s.branch).collect();
    branches.sort_unstable();
    branches.dedup();
    let jobs: Vec<(u32, Vec<f64>)> = branches
        .into_iter()
        .map(|b| {
            let mut grid: Vec<f64> = outs
                .iter()
                .filter(|s| s.branch == b)
                .flat_map(|s| s.points.iter().map(|p| p.lbar))
                .collect();
            grid.sort_by(f64::total_cmp);
            grid.dedup_by(|a, c| (*a - *c).abs() < 1e-9);
            (b, grid)
        })
        .filter(|(_, g)| !g.is_empty())
        .collect();
    let shared: &[SheetOut] = outs;
    let scope = stats::current();
    let results = run_parallel(
        threads,
        jobs,
        &mut |_| {},
        &mut |_: &(u32, Vec<SheetOut>, usize)| {},
        |(b, grid), _| {
            let (added, searched) = stats::within(&scope, || seed_branch(opts, shared, b, &grid));
            (b, added, searched)
        },
    );
    let mut notes = Vec::new();
    for (b, added, searched) in results {
        notes.push(format!(
            "branch {b}: the stiffness path from the uniform rod's loop searched at {searched} sampled lengths; {} families below the traced ones found and traced",
            added.len()
        ));
        outs.extend(added);
    }
    notes
}
