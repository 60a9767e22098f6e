//! Lower states below unstable lowest ones (enclosed diagram of a non-uniform rod, see
//! `nonuniform.rs`). The surface families seed the lifted-off traces, but the enclosed
//! problem has equilibria that no surface family leads to: where the lowest traced state
//! has Hessian index ≥ 1 on the tangent space of its active constraints, a lower
//! equilibrium must exist. It is found by stepping from that state (coarsest level) along
//! its unstable direction, both signs, and Newton
//! ([`descend`](rodloop_solver::enclosed::descent::descend)); the state reached is
//! re-solved at `N/4, N/2, N` and traced through the parent sheet's sampled lengths as a
//! new family of the same branch. Where no descent leads lower, `solve`'s search for the
//! branch at that length is the last resort (its other starts reach other minima), on the
//! saddle's mesh and then as the `solve` command runs it. The new family's states are kept
//! where they lie below the parent's (elsewhere they have merged into it). An index-0 state
//! that the search reaches level with the saddle (one more contact node held, or the other
//! half of a fold) is traced too, through the parent's saddle samples around it, and its
//! states are kept where they are level with those saddles or below the parent: the
//! labeller then names the minimum lowest there, not the saddle. The index is that of the state
//! reported, its finest level ([`Levels::index`]). A sheet's search stops at the first of
//! its unstable lowest states that leads lower; the ones it did not reach stay candidates
//! of the next round (a family traced from one of them need not reach the others).

use rodloop_solver::enclosed::descent::{descend, solve_branch_lowest};
use rodloop_solver::enclosed::stats::{self, Stage};
use rodloop_solver::enclosed::{
    branch::{finer_check, solve_levels_from_fine},
    solve_levels, EnclosedOptions, EnclosedState, SurfaceSource,
};
use rodloop_solver::Accuracy;

use rodloop_continuation::exchange::lowest_state;

use super::levels::Levels;
use super::nonuniform_exchange::{interp, lowest_near_circle, ranked_at};
use super::nonuniform_sheet::SheetOut;
use super::trace::step_options;
use super::trace::{follow, TraceStop};
use super::{EnclosedPoint, PointSource, TOUCH};
use crate::enclosed_state::solve_state;
use crate::parallel::run_parallel;

/// Relative step amplitudes along the unstable direction, tried in turn.
const AMPLITUDES: [f64; 4] = [0.05, 0.15, 0.3, 0.5];

/// A lower (or level, index-0) state's trace, where it stopped, and whether it began level
/// with the saddle ([`Lower::Level`]).
type Found = (Vec<Levels>, Vec<TraceStop>, bool);

/// One sheet's descent job: the sheet, its candidates, the lengths searched, the family
/// found below, and `solve`'s index-0 states level with its saddles (`[L̄, E, estimate]`).
type Searched = (usize, Vec<f64>, Vec<f64>, Option<Found>, Vec<[f64; 3]>);

/// Most rounds of descent. A new family may itself be unstable where it is lowest, so the
/// rounds go on while one adds a family (each kept state lies below its parent's or is an
/// index-0 state level with one of its saddles, and each saddle is tried once); this bound
/// only guarantees the end (random seed 24 of `tests/random_enclosed.rs` needs three).
const ROUNDS: usize = 8;

/// Sheets whose lowest states are unstable: `(sheet, L̄ of the states whose energy is the
/// least of the sheets' there, L̄ of those only tied with the least)`. Tied means the
/// labeller ([`ranked_at`] without exchanges) would call the state lowest: within the
/// estimates of the least and no local minimum tied with it. The exchanges located later
/// can make such a state the lowest one (a crossing placed inside the tie prefers its
/// branch), and the labels must not name a saddle lowest that no descent was tried from.
fn unstable_lowest(outs: &[SheetOut], dbar: f64) -> Vec<(usize, Vec<f64>, Vec<f64>)> {
    let mut found = Vec::new();
    for (k, s) in outs.iter().enumerate() {
        let saddles = s
            .points
            .iter()
            .filter(|p| p.index > 0 && p.source == PointSource::Model);
        let (mut least, mut tied) = (Vec::new(), Vec::new());
        for p in saddles {
            if lowest_near_circle(outs, p.lbar) == Some(k) {
                least.push(p.lbar);
            } else if lowest_state(&ranked_at(outs, &[], &[], k, p, dbar)).contains(&0) {
                tied.push(p.lbar);
            }
        }
        if !least.is_empty() || !tied.is_empty() {
            found.push((k, least, tied));
        }
    }
    found
}

/// Up to three of a sheet's unstable lowest states to descend from, the least first, each
/// group from its middle outwards ([`unstable_lowest`]).
fn candidates(least: &[f64], tied: &[f64]) -> Vec<f64> {
    let from_middle = |xs: &[f64]| {
        let Some(&mid) = xs.get(xs.len() / 2) else {
            return Vec::new();
        };
        let mut order = xs.to_vec();
        order.sort_by(|u, v| (u - mid).abs().total_cmp(&(v - mid).abs()));
        order
    };
    let mut order = from_middle(least);
    order.extend(from_middle(tied));
    order.truncate(3);
    order
}

/// The lowest new state reached from `lv` (coarsest level) along its unstable direction,
/// cascaded to `N/2` and `N`: below `lv` and not a state another sheet already has there.
/// Where no descent leads lower and `accuracy` is given, `solve`'s search for the branch
/// (`[branch, η]`) at that length: on `lv`'s mesh ([`lowest_by_solve`]), then, where that
/// reaches nothing level with `lv` or lower, the `solve` command's
/// ([`lowest_by_solve_command`]).
fn lower_state(
    lv: &Levels,
    [branch, eta]: [u32; 2],
    outs: &[SheetOut],
    accuracy: Option<Accuracy>,
    opts: &EnclosedOptions,
) -> Lower {
    let x = lv.lbar;
    let e0 = lv.energy().0;
    let new_and_lower = |l: &Levels| {
        let e = l.energy().0;
        let known = outs
            .iter()
            .any(|s| interp(s, x).is_some_and(|es| (es - e).abs() < 1e-6));
        e < e0 - 1e-7 && !known
    };
    for amp in AMPLITUDES {
        let Ok(cands) = descend(&lv.states[0], amp, opts) else {
            continue;
        };
        for c in cands {
            let Ok(b) = solve_levels(&c.model, c.z.clone(), None, opts) else {
                continue;
            };
            let l = Levels {
                lbar: x,
                states: [b.quarter, b.coarse, b.fine],
            };
            if new_and_lower(&l) {
                return Lower::Below(Box::new(l));
            }
        }
    }
    let Some(accuracy) = accuracy else {
        return Lower::Nothing;
    };
    // The search on the saddle's own mesh, then the `solve` command's on the accuracy's
    // meshes, where the discrete minimum may exist only on finer ones.
    let searches: [&dyn Fn() -> Option<Levels>; 2] =
        [&|| lowest_by_solve(lv, eta, accuracy, opts), &|| {
            lowest_by_solve_command(lv, branch, accuracy, opts)
        }];
    for search in searches {
        let Some(l) = search() else {
            continue;
        };
        if new_and_lower(&l) {
            return Lower::Below(Box::new(l));
        }
        if level(lv, &l, opts) {
            return Lower::Level(Box::new(l));
        }
    }
    Lower::Nothing
}

/// What [`lower_state`] reached from a saddle.
enum Lower {
    /// A new state below it.
    Below(Box<Levels>),
    /// `solve`'s index-0 state there, level with the saddle within the two estimates: the
    /// other half of a fold, or the same loop on the other side of a contact node's release
    /// (the node held with a small force where the saddle has it free at the wall).
    Level(Box<Levels>),
    /// Nothing lower or level.
    Nothing,
}

/// `first` traced through `parent`'s sampled lengths from its own (natural-parameter steps,
/// [`follow`]), with the stops of the trace; `saddles`: only through the run of the
/// parent's samples of index > 0 that holds `first`'s length (where a state level with a
/// saddle can be kept).
fn trace_on(
    parent: &SheetOut,
    first: Levels,
    what: &str,
    saddles: bool,
) -> (Vec<Levels>, Vec<TraceStop>) {
    let x = first.lbar;
    let mut grid: Vec<f64> = parent.levels.iter().map(|l| l.lbar).collect();
    grid.sort_by(f64::total_cmp);
    grid.dedup_by(|a, b| (*a - *b).abs() < 1e-12);
    if saddles {
        let saddle = |g: f64| {
            parent
                .points
                .iter()
                .any(|p| (p.lbar - g).abs() < 1e-12 && p.index > 0)
        };
        let at = grid
            .iter()
            .position(|&g| (g - x).abs() < 1e-12)
            .unwrap_or(0);
        let lo = (0..at)
            .rev()
            .take_while(|&i| saddle(grid[i]))
            .last()
            .unwrap_or(at);
        let hi = (at + 1..grid.len())
            .take_while(|&i| saddle(grid[i]))
            .last()
            .unwrap_or(at);
        grid = grid[lo..=hi].to_vec();
    }
    let mid = grid
        .iter()
        .position(|&g| (g - x).abs() < 1e-12)
        .unwrap_or(0);
    let mut stops = Vec::new();
    let traced = follow(first, &grid, mid, what, &step_options(), true, &mut stops);
    (traced, stops)
}

/// The energy of `l` and its estimate as a row gets it: the three-level estimate, widened
/// to the bound of the check on twice the cells where that is larger
/// ([`finer_check`], as `check_rows_on_finer` widens every row that touches the wall).
fn checked_energy(l: &Levels, opts: &EnclosedOptions) -> (f64, f64) {
    let (e, de) = l.energy();
    let bound = finer_check(&l.states[2], l.states[1].energy(), opts).map_or(0.0, |c| c.0);
    (e, de.max(bound))
}

/// Whether `a` and `b` (one length, possibly different meshes) are level within their
/// estimates ([`checked_energy`]).
fn level(a: &Levels, b: &Levels, opts: &EnclosedOptions) -> bool {
    let ((ea, da), (eb, db)) = (a.energy(), b.energy());
    if (ea - eb).abs() <= da + db {
        return true;
    }
    let ((ea, da), (eb, db)) = (checked_energy(a, opts), checked_energy(b, opts));
    (ea - eb).abs() <= da + db
}

/// Whether sheet `k` has a saddle sampled at `l`'s length level with `l` ([`level`]).
fn level_with_saddle(outs: &[SheetOut], k: usize, l: &Levels, opts: &EnclosedOptions) -> bool {
    let s = &outs[k];
    s.points.iter().any(|q| {
        (q.lbar - l.lbar).abs() < 1e-12
            && q.index > 0
            && s.levels
                .iter()
                .find(|m| (m.lbar - l.lbar).abs() < 1e-12)
                .is_some_and(|m| level(m, l, opts))
    })
}

/// Whether a sheet other than `k` already has an index-0 state at `pt`'s length level with
/// `pt` within the two estimates (then `pt` adds nothing).
fn minimum_elsewhere(outs: &[SheetOut], k: usize, pt: &EnclosedPoint) -> bool {
    outs.iter().enumerate().any(|(j, s)| {
        j != k
            && s.points.iter().any(|q| {
                (q.lbar - pt.lbar).abs() < 1e-12
                    && q.index == 0
                    && (q.energy - pt.energy).abs() <= q.energy_error + pt.energy_error
            })
    })
}

/// The lowest local minimum of branch `eta` at `lv`'s length by `solve`'s search on `lv`'s
/// meshes ([`solve_branch_lowest`] with the surface loop there: Newton from the surface loop,
/// the stiffness paths and the minima of other lengths continued in `L̄`, each descended),
/// where it is lifted off and of index 0. The descents from a saddle end where Newton takes
/// the displaced state, which need not be the branch's lowest minimum; `solve`'s starts
/// reach minima the traces and descents do not (random seed 19 of
/// `tests/random_enclosed.rs`, branch 2 at `L̄ = 1.538165`: a saddle traced as the lowest
/// state, 5.2e-4 above the minimum that Newton reaches from the surface loop).
fn lowest_by_solve(
    lv: &Levels,
    eta: u32,
    accuracy: Accuracy,
    opts: &EnclosedOptions,
) -> Option<Levels> {
    let m = &lv.states[2].model;
    let stiffness = m.stiffness().kind();
    let (source, _) = SurfaceSource::numeric(m.radius(), lv.lbar, stiffness, eta, accuracy).ok()?;
    let ((b, _, _), _) = solve_branch_lowest(
        m.wall(),
        lv.lbar,
        eta,
        stiffness,
        &source,
        &[m.cells()],
        opts,
    )
    .ok()?;
    lifted_minimum(lv.lbar, [b.quarter, b.coarse, b.fine])
}

/// The levels `states` at `lbar` where the finest is lifted off and of index 0.
fn lifted_minimum(lbar: f64, states: [EnclosedState; 3]) -> Option<Levels> {
    let l = Levels { lbar, states };
    let lifted = l.states[2].contact(TOUCH).ok()?.fraction < 1.0;
    (lifted && l.index().ok()? == 0).then_some(l)
}

/// The state the `solve` command reports for `branch` at `lv`'s length
/// ([`crate::enclosed_state::solve_state`]: the meshes of the accuracy level, their check,
/// the last resorts), with its levels `N/2, N/4` re-solved from it (else those of `solve`'s
/// own estimate), where it is lifted off and of index 0. On random seed 10 of
/// `tests/random_enclosed.rs` the branch's minimum next to a saddle traced on 128 cells exists
/// on 384 only.
fn lowest_by_solve_command(
    lv: &Levels,
    branch: u32,
    accuracy: Accuracy,
    opts: &EnclosedOptions,
) -> Option<Levels> {
    let m = &lv.states[2].model;
    let res = solve_state(m.wall(), m.stiffness().kind(), lv.lbar, branch, accuracy).ok()?;
    if res.stability.0 != 0 || res.attached_loop.is_some() {
        return None;
    }
    let fine = res.state;
    let states = match solve_levels_from_fine(fine.clone(), opts) {
        Ok(b) => [b.quarter, b.coarse, b.fine],
        // Where the minimum has no state on the coarser meshes re-solved from it (a contact
        // node's release that they place elsewhere), the ladder of `solve`'s own estimate:
        // `solve` may reach it by continuing a minimum of another length level by level.
        Err(_) => {
            let [quarter, coarse] = res.levels?;
            [quarter, coarse, fine]
        }
    };
    lifted_minimum(lv.lbar, states)
}

/// Add the families found below unstable lowest states to `outs` (see the module docs).
/// Returns the warnings, the notes and, for each sheet appended to `outs`, the index of the sheet of
/// the surface diagram it descends from (`roots[k]` for the first `roots.len()` sheets).
/// `dbar` is the mean `D/D0` ([`super::nonuniform_exchange::mean_stiffness`]) for the
/// labeller ([`ranked_at`]).
pub(super) fn descend_unstable(
    outs: &mut Vec<SheetOut>,
    roots: &[usize],
    accuracy: Accuracy,
    threads: usize,
    dbar: f64,
) -> (Vec<String>, Vec<String>, Vec<usize>) {
    let mut warnings = Vec::new();
    let mut notes = Vec::new();
    let mut parents: Vec<usize> = Vec::new();
    let root_of = |k: usize, parents: &[usize]| -> usize {
        if k < roots.len() {
            roots[k]
        } else {
            parents[k - roots.len()]
        }
    };
    // The descent and its cascade get the full Newton budget (the shape moves far).
    let dopts = EnclosedOptions::default();
    let mut tried: Vec<(usize, f64)> = Vec::new();
    // Per sheet, `solve`'s index-0 states level with its saddles (`[L̄, E, estimate]`).
    let mut level_with: Vec<(usize, [f64; 3])> = Vec::new();
    for _ in 0..ROUNDS {
        let mut added: Vec<SheetOut> = Vec::new();
        let mut added_parents = Vec::new();
        // The sheets to try this round, with up to three untried unstable lowest states
        // each ([`candidates`]); the searches and traces run in parallel.
        let mut jobs: Vec<(usize, Vec<f64>)> = Vec::new();
        for (k, least, tied) in unstable_lowest(outs, dbar) {
            let cands: Vec<f64> = candidates(&least, &tied)
                .into_iter()
                .filter(|&x| {
                    !tried
                        .iter()
                        .any(|&(kk, xx)| kk == k && (xx - x).abs() < 1e-9)
                })
                .collect();
            if !cands.is_empty() {
                jobs.push((k, cands));
            }
        }
        let shared: &[SheetOut] = outs;
        let scope = stats::current();
        let results = run_parallel(
            threads,
            jobs,
            &mut |_| {},
            &mut |_: &Searched| {},
            |(k, cands), _| {
                let _counted = stats::reopen(&scope);
                let parent = &shared[k];
                let what = format!(
                    "branch {} (eta = {}) below family {}",
                    parent.branch, parent.eta, parent.family
                );
                let mut found = None;
                // `(L̄, E, estimate)` of `solve`'s index-0 states level with the saddle, and
                // the first such state, traced where nothing lower is found.
                let mut level = Vec::new();
                let mut twin: Option<Levels> = None;
                // The lengths searched: the search stops at the first lower state found, and
                // the others stay candidates of the next round.
                let mut searched = Vec::new();
                for (i, &x) in cands.iter().enumerate() {
                    searched.push(x);
                    // `solve`'s search (seconds) at the sheet's first candidate of the round.
                    let search = (i == 0).then_some(accuracy);
                    let Some(lv) = parent.levels.iter().find(|l| (l.lbar - x).abs() < 1e-12) else {
                        continue;
                    };
                    let lower = stats::stage(Stage::Descent, || {
                        lower_state(lv, [parent.branch, parent.eta], shared, search, &dopts)
                    });
                    match lower {
                        Lower::Below(l) => {
                            found = Some((trace_on(parent, *l, &what, false), false));
                            break;
                        }
                        Lower::Level(l) => {
                            let (e, de) = l.energy();
                            level.push([x, e, de]);
                            twin.get_or_insert(*l);
                        }
                        Lower::Nothing => {}
                    }
                }
                if found.is_none() {
                    found = twin.map(|l| (trace_on(parent, l, &what, true), true));
                }
                let found = found.map(|((traced, stops), level)| (traced, stops, level));
                (k, cands, searched, found, level)
            },
        );
        for (k, cands, searched, found, level) in results {
            tried.extend(searched.iter().map(|&x| (k, x)));
            level_with.extend(level.into_iter().map(|l| (k, l)));
            let parent = &outs[k];
            let Some((traced, stops, from_level)) = found else {
                warnings.push(format!(
                    "branch {} (eta = {}) below family {}: the lowest states at lbar = {} have index >= 1, but no lower equilibrium was reached along their unstable directions or by the search of solve there",
                    parent.branch,
                    parent.eta,
                    parent.family,
                    cands.iter().map(|x| format!("{x:.6}")).collect::<Vec<_>>().join(", ")
                ));
                continue;
            };
            let family = outs
                .iter()
                .chain(added.iter())
                .filter(|s| s.branch == parent.branch)
                .map(|s| s.family)
                .max()
                .unwrap_or(0)
                + 1;
            let mut new = SheetOut::empty(parent.branch, parent.eta, family);
            new.stops = stops;
            // The lengths of the states kept as level with a saddle of the parent.
            let mut level_at: Vec<f64> = Vec::new();
            for l in traced {
                let Some(pe) = interp(parent, l.lbar) else {
                    continue;
                };
                let Ok(mut pt) = l.point(parent.branch, parent.eta) else {
                    continue;
                };
                let below = pt.energy < pe - pt.energy_error;
                // Index-0 states level with the parent's saddles at their own lengths are kept
                // too: the saddle is then not the lowest state there (the labeller prefers the
                // minimum in a tie). A descent can reach one (random seed 24 at
                // `L̄ = 1.595175`: 5.6e-6 below the saddle, within the estimates).
                // (Tried only where the state is not below: the level test may re-solve both
                // states on twice their cells.)
                let twin_of_saddle = || {
                    pt.index == 0
                        && level_with_saddle(outs, k, &l, &dopts)
                        && !minimum_elsewhere(outs, k, &pt)
                };
                if !below {
                    if !twin_of_saddle() {
                        // Merged back into the parent (or not distinguishable from it).
                        continue;
                    }
                    level_at.push(l.lbar);
                }
                let surf = parent
                    .points
                    .iter()
                    .find(|p| (p.lbar - l.lbar).abs() < 1e-12)
                    .and_then(|p| p.surface_energy);
                pt.family = family;
                pt.sheet = 0;
                pt.multiplicity = parent.points.first().map_or(1, |p| p.multiplicity);
                pt.surface_energy = surf;
                new.points.push(pt);
                new.levels.push(l);
            }
            // A descent next to a great circle can reach another branch's state: not a row
            // of this branch (and no lowest state of it).
            warnings.extend(new.drop_other_branches());
            if !new.points.is_empty() {
                new.points.sort_by(|u, v| u.lbar.total_cmp(&v.lbar));
                let level_kept = new
                    .points
                    .iter()
                    .filter(|p| level_at.contains(&p.lbar))
                    .count();
                if from_level {
                    notes.push(format!(
                        "branch {} (eta = {}) family {}: traced from an index-0 state level with a saddle of family {} that solve's search reaches (the same loop with the wall held at a node where the saddle leaves it free at zero force, or the other half of a fold); {} state(s) in [{:.6}, {:.6}], {} level with the saddles of family {} at their lengths within the two estimates and {} below them: there the saddle is not the lowest state",
                        new.branch,
                        new.eta,
                        family,
                        parent.family,
                        new.points.len(),
                        new.points[0].lbar,
                        new.points[new.points.len() - 1].lbar,
                        level_kept,
                        parent.family,
                        new.points.len() - level_kept
                    ));
                }
                added.push(new);
                added_parents.push(root_of(k, &parents));
            }
        }
        if added.is_empty() {
            break;
        }
        outs.extend(added);
        parents.extend(added_parents);
    }
    for (k, least, tied) in unstable_lowest(outs, dbar) {
        // The saddles the labeller still calls lowest: not those tied with a minimum.
        let s = &outs[k];
        let mut xs: Vec<f64> = least
            .into_iter()
            .chain(tied)
            .filter(|&x| {
                s.points
                    .iter()
                    .find(|p| (p.lbar - x).abs() < 1e-12)
                    .is_some_and(|p| {
                        lowest_state(&ranked_at(outs, &[], &[], k, p, dbar)).contains(&0)
                    })
            })
            .collect();
        if xs.is_empty() {
            continue;
        }
        xs.sort_by(f64::total_cmp);
        // The two lowest eigenvalues (mass-normalised), to tell a clear saddle from a nearly
        // degenerate state.
        let mu = s
            .levels
            .iter()
            .find(|l| (l.lbar - xs[0]).abs() < 1e-12)
            .and_then(|l| l.states[2].stability(1e-6).ok())
            .map_or(String::new(), |(_, v)| {
                format!(
                    " (lowest eigenvalues {:.2e}, {:.2e})",
                    v[0],
                    v.get(1).copied().unwrap_or(f64::NAN)
                )
            });
        // Where `solve` reaches an index-0 state level with the saddle (the two halves of a
        // fold, or one state on either side of a contact node's release), nothing lower is
        // known.
        let level = level_with
            .iter()
            .find(|(kk, l)| *kk == k && xs.iter().any(|x| (x - l[0]).abs() < 1e-9))
            .map(|(_, l)| l);
        let tail = match level {
            Some([x, e, de]) => format!(
                "; at lbar = {x:.6} solve's search reaches an index-0 state level with it within the two estimates ({e:.10} ± {de:.1e}) whose trace did not keep a row there, and no lower equilibrium is known there: the index changes beside it (a fold, or a contact node whose force vanishes)"
            ),
            None => "; a lower equilibrium exists there that the traces did not find".into(),
        };
        warnings.push(format!(
            "branch {} (eta = {}) family {}: the lowest traced state has index >= 1 at {} sampled lengths in [{:.4}, {:.4}]{mu}{tail}",
            s.branch,
            s.eta,
            s.family,
            xs.len(),
            xs[0],
            xs[xs.len() - 1]
        ));
    }
    (warnings, notes, parents)
}
