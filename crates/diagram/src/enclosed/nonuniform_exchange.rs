//! Exchanges of the lowest branch in the enclosed diagram of a non-uniform rod (see
//! `nonuniform.rs`): the lowest sheet at a length, `E_a = E_b` located on re-solved states
//! (the exchange locator, [`rodloop_continuation::exchange::locate`]), and the energy of
//! the `m`-fold great circle.
//!
//! A lifted-off exchange is located first on the trace's levels `N/4, N/2, N`, then again
//! on the ladder of meshes of the uniform rod's exchanges ([`Ladder`]: the finest level
//! prolonged and re-solved once more per accuracy step, the last four levels kept) where
//! every lifted-off state re-solves on it. Where one does not (the far lifted-off
//! figure-eight of `D1/D0 = 0.5` has point contacts between nodes, so its prolonged contact
//! set is the wrong one: Newton converges there through the Fischer–Burmeister form of the
//! complementarity, [`rodloop_solver::enclosed::Complementarity`]), or where the ladder's
//! root lies outside the levels' estimate, the levels' result stands. The surface value on the
//! same two sheets is located first, for comparison only: where a sheet has lifted off, its
//! failure leaves the exchange standing without it (`surface_lbar_cr` is then absent).

use rodloop_solver::SolverError;

use rodloop_continuation::exchange::{ExchangeSettings, Ranked};

use super::critical::{exchange_doublings, interpolated_rows, locate_from, EnclosedPair, Ladder};
use super::levels::Levels;
use super::nonuniform_sheet::{surface_energy, surface_energy_doubled, walk, SheetOut};
use super::{EnclosedCritical, EnclosedDiagramOptions, EnclosedPoint, PointSource};
use crate::enclosed_state::solve_state;
use crate::types::TracedBranch;
use crate::{DiagramError, DiagramOptions};

/// Energy of sheet `s` at `lbar` interpolated linearly between its samples (`None`
/// outside them).
pub(super) fn interp(s: &SheetOut, lbar: f64) -> Option<f64> {
    let p = &s.points;
    let (first, last) = (p.first()?, p.last()?);
    if lbar < first.lbar - 1e-12 || lbar > last.lbar + 1e-12 {
        return None;
    }
    let k = p.partition_point(|q| q.lbar < lbar);
    if k == 0 {
        return Some(first.energy);
    }
    if k == p.len() {
        return Some(last.energy);
    }
    let (a, b) = (&p[k - 1], &p[k]);
    let t = (lbar - a.lbar) / (b.lbar - a.lbar);
    Some(a.energy + t * (b.energy - a.energy))
}

/// The sheet with the lowest (interpolated) energy at `lbar`.
pub(super) fn lowest_at(sheets: &[SheetOut], lbar: f64) -> Option<usize> {
    sheets
        .iter()
        .enumerate()
        .filter_map(|(i, s)| interp(s, lbar).map(|e| (i, e)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(i, _)| i)
}

/// [`lowest_at`], where within [`CIRCLE`] of a great circle `L̄ = m` a sheet that begins or
/// ends within `CIRCLE` of `lbar` competes with its end state (the sheets of branch
/// `η = m + 1` begin `5·10⁻⁵` after the circle, so at `L̄ = m` itself only the sheets of the
/// other branches are sampled).
pub(super) fn lowest_near_circle(sheets: &[SheetOut], lbar: f64) -> Option<usize> {
    let at_circle = (lbar - lbar.round()).abs() < CIRCLE;
    sheets
        .iter()
        .enumerate()
        .filter_map(|(i, s)| {
            let end = || {
                [s.points.first(), s.points.last()]
                    .into_iter()
                    .flatten()
                    .find(|u| at_circle && (u.lbar - lbar).abs() < CIRCLE)
                    .map(|u| u.energy)
            };
            interp(s, lbar).or_else(end).map(|e| (i, e))
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(i, _)| i)
}

/// The labeller's view ([`rodloop_continuation::exchange`]) of the sampled state `p` of
/// sheet `k` and of the other sheets at its length, `p` first. Another sheet's energy is
/// interpolated linearly between its samples, with the error estimate of
/// [`interpolated_rows`] (the samples' own estimates plus `|E''|(x − x_a)(x_b − x)/2`
/// from the sheet's second differences), and has index 0 where both neighbouring samples
/// have it. Within `CIRCLE` of a great circle, a sheet that ends there competes with its
/// end state. On the other side of the circle from `p`, the two are the ends of the
/// collapse there (located to their distance from the circle) and tied; on `p`'s side, the
/// end state's estimate adds the sheet's end slope times its distance from `p` (of a
/// one-sample sheet, the slope of its chord to the circle's energy `m D̄/D0`,
/// `dbar = D̄/D0`). In the closed bracket of a
/// located crossing, the sheets of the branch its critical length names as lowest on `p`'s
/// side are preferred in ties; elsewhere the least energy decides.
pub(super) fn ranked_at(
    outs: &[SheetOut],
    brackets: &[(f64, f64, usize, usize)],
    critical: &[EnclosedCritical],
    k: usize,
    p: &EnclosedPoint,
    dbar: f64,
) -> Vec<Ranked> {
    let mut named: Option<usize> = None;
    for &(x0, x1, a, b) in brackets {
        if p.lbar >= x0 && p.lbar <= x1 {
            let c = critical
                .iter()
                .find(|c| c.critical.lbar_cr >= x0 - 0.05 && c.critical.lbar_cr <= x1 + 0.05)
                .map_or(0.5 * (x0 + x1), |c| c.critical.lbar_cr);
            named = Some(if p.lbar < c { a } else { b });
        }
    }
    // The critical length names a branch: each of its families is preferred.
    let prefers = |j: usize| named.is_some_and(|n| outs[n].branch == outs[j].branch);
    let mut states = vec![Ranked {
        energy: p.energy,
        error: p.energy_error,
        index: p.index,
        preferred: prefers(k),
    }];
    let at_circle = (p.lbar - p.lbar.round()).abs() < CIRCLE;
    for (j, s) in outs.iter().enumerate().filter(|(j, _)| *j != k) {
        let q = &s.points;
        let rows: Vec<&EnclosedPoint> = q.iter().collect();
        let Some((energy, error, index0)) = interpolated_rows(&rows, p.lbar) else {
            // The end state of a sheet that ends next to the circle (see the doc comment).
            let ends = [
                (q.first(), q.get(1)),
                (q.last(), q.len().checked_sub(2).and_then(|i| q.get(i))),
            ];
            for (u, v) in ends {
                let Some(u) = u.filter(|u| at_circle && (u.lbar - p.lbar).abs() < CIRCLE) else {
                    continue;
                };
                let m = p.lbar.round();
                let (x, e) = v.map_or((m, m * dbar), |v| (v.lbar, v.energy));
                let shift = if (u.lbar - m) * (p.lbar - m) < 0.0 {
                    // The two ends of the collapse at `m`, on either side of it within its
                    // estimate: tied.
                    (u.energy - p.energy).abs()
                } else if (x - u.lbar).abs() > 1e-12 {
                    // The end chord's slope; of a one-sample sheet, the chord to the
                    // circle's own energy `m D̄/D0`.
                    ((e - u.energy) / (x - u.lbar) * (u.lbar - p.lbar)).abs()
                } else {
                    (e - u.energy).abs()
                };
                states.push(Ranked {
                    energy: u.energy,
                    error: u.energy_error + shift,
                    index: u.index,
                    preferred: prefers(j),
                });
                break;
            }
            continue;
        };
        states.push(Ranked {
            energy,
            error,
            index: usize::from(!index0),
            preferred: prefers(j),
        });
    }
    states
}

/// Energy of sheet `s` at `x`: the 3-D model stepped from `track` where the sheet has
/// lifted off near `x`, the surface state otherwise.
pub(super) fn sheet_energy(
    dopts: &DiagramOptions,
    surface: &TracedBranch,
    x: f64,
    track: &mut Option<Levels>,
) -> Result<(f64, f64), SolverError> {
    match track {
        Some(t) => {
            let next = walk(t, x)?;
            let e = next.energy();
            *track = Some(next);
            Ok(e)
        }
        None => surface_energy(dopts, surface, x),
    }
}

/// Sampled states of a sheet from which [`sheet_energy_restarted`] walks again.
const RESTARTS: usize = 2;

/// [`sheet_energy`]; where the walk from the track fails, the walk from the sheet's sampled
/// states nearest `x` (up to [`RESTARTS`] of them, the nearest first), which then becomes the
/// track. Next to a sample where the contact set of a lifted-off family changes, the walk
/// from one side stalls while the one from the other side arrives (random seed 32 of
/// `tests/random_enclosed.rs`, the exchange 3 → 1: the walk from the nearer sample ends at a
/// KKT residual of `2·10⁻⁵`).
fn sheet_energy_restarted(
    dopts: &DiagramOptions,
    sheet: &SheetOut,
    surface: &TracedBranch,
    x: f64,
    track: &mut Option<Levels>,
) -> Result<(f64, f64), SolverError> {
    let first = sheet_energy(dopts, surface, x, track);
    if first.is_ok() || track.is_none() {
        return first;
    }
    let mut near: Vec<&Levels> = sheet.levels.iter().collect();
    near.sort_by(|u, v| (u.lbar - x).abs().total_cmp(&(v.lbar - x).abs()));
    for l in near.into_iter().take(RESTARTS) {
        if let Ok(next) = walk(l, x) {
            let e = next.energy();
            *track = Some(next);
            return Ok(e);
        }
    }
    first
}

/// An exchange located by [`locate_crossing`].
pub(super) struct Crossing {
    /// `L̄` of the exchange.
    pub(super) lbar: f64,
    /// Its estimate.
    pub(super) error: f64,
    /// `E R/(π D0)` there.
    pub(super) energy: f64,
    /// The surface value on the same two sheets, where it was located.
    pub(super) surface_lbar: Option<f64>,
    /// How it was located.
    pub(super) method: String,
    /// Why it was not located on re-solved states, where it comes from the sampled energies.
    pub(super) not_located: Option<String>,
}

/// Locate `E_a = E_b` near `[x0, x1]` (see the module docs).
pub(super) fn locate_crossing(
    dopts: &DiagramOptions,
    sheets: [&SheetOut; 2],
    surfaces: [&TracedBranch; 2],
    x0: f64,
    x1: f64,
) -> Result<Crossing, SolverError> {
    // First guess: the root of the interpolated difference.
    let d = |x: f64| interp(sheets[0], x).unwrap_or(0.0) - interp(sheets[1], x).unwrap_or(0.0);
    let (d0, d1) = (d(x0), d(x1));
    let xg = if (d1 - d0).abs() > 0.0 {
        (x0 - d0 * (x1 - x0) / (d1 - d0)).clamp(x0, x1)
    } else {
        0.5 * (x0 + x1)
    };
    let nearest_levels = |s: &SheetOut| -> Option<Levels> {
        let near = s
            .points
            .iter()
            .min_by(|u, v| (u.lbar - xg).abs().total_cmp(&(v.lbar - xg).abs()))?;
        if near.source != PointSource::Model {
            return None;
        }
        s.levels
            .iter()
            .min_by(|u, v| (u.lbar - xg).abs().total_cmp(&(v.lbar - xg).abs()))
            .cloned()
    };
    let mut tracks = [nearest_levels(sheets[0]), nearest_levels(sheets[1])];
    let lifted = tracks.iter().any(|t| t.is_some());
    let h = 1e-3f64.min(0.25 * (x1 - x0).abs().max(1e-5));
    // The surface value on the same two sheets (and the result where both are attached).
    let surface = ExchangeSettings {
        probe: -h,
        baseline: 1e-5,
        ..ExchangeSettings::default()
    };
    // On the doublings of the tracing resolution of the lifted-off exchanges' ladders.
    let doublings = exchange_doublings(dopts.accuracy);
    let on_surface = {
        let mut pair = EnclosedPair::new(
            |x| surface_energy_doubled(dopts, surfaces[0], x, doublings),
            |x| surface_energy_doubled(dopts, surfaces[1], x, doublings),
        );
        locate_from(&mut pair, xg, &surface)
    };
    // Where a sheet is lifted off, the surface value is only a comparison: its failure (a
    // surface sheet that cannot be re-solved there) leaves the enclosed exchange standing.
    if !lifted {
        let on_surface = on_surface?;
        let xs = on_surface.x;
        return Ok(Crossing {
            lbar: xs,
            error: on_surface.error,
            energy: 0.5 * (on_surface.energies.a + on_surface.energies.b),
            surface_lbar: Some(xs),
            method: format!("surface states (both attached: lambda_min > 0), each on 2^k N and 2^(k+1) N cells (tracing resolutions N = {}, {}; k = {doublings}); the exchange locator on E_a = E_b (hunt from the interpolated root, Brent), error from the two resolutions' energies, the chord's noise over +-1e-5 and the final bracket", surfaces[0].cells, surfaces[1].cells),
            not_located: None,
        });
    }
    // The energies of lifted-off states carry discretisation noise (contact ends crossing
    // nodes) and the two curves meet at a small angle: the slope and the noise misfit come
    // from the chord over `x ± 2e-3`, and the root is refined to `1e-10` only.
    let lifted_settings = ExchangeSettings {
        xtol: 1e-10,
        probe: -h,
        baseline: 2e-3,
        ..ExchangeSettings::default()
    };
    let ex = {
        let [ta, tb] = &mut tracks;
        let mut pair = EnclosedPair::new(
            |x| sheet_energy_restarted(dopts, sheets[0], surfaces[0], x, ta),
            |x| sheet_energy_restarted(dopts, sheets[1], surfaces[1], x, tb),
        );
        locate_from(&mut pair, xg, &lifted_settings)
    };
    // Where a lifted-off sheet cannot be re-solved next to the crossing (a fold or a change
    // of the contact set of its family there), the crossing of the sampled energies stands:
    // the root of their interpolated difference, which lies in the bracket, with the
    // distance to the bracket's farther end as its estimate.
    let (xs, surface_note) = match on_surface {
        Ok(s) => (Some(s.x), "surface value on the same sheets".to_string()),
        Err(e) => (
            None,
            format!("no surface value (the same sheets' surface states not located: {e})"),
        ),
    };
    let ex = match ex {
        Ok(ex) => ex,
        Err(e) => {
            let energy = interp(sheets[0], xg)
                .or_else(|| interp(sheets[1], xg))
                .ok_or_else(|| SolverError::InvalidInput(e.to_string()))?;
            return Ok(Crossing {
                lbar: xg,
                error: (xg - x0).abs().max((x1 - xg).abs()),
                energy,
                surface_lbar: xs,
                method: format!(
                    "the root of the sampled energies' interpolated difference between lbar = {x0:.6} and {x1:.6}, its estimate the distance to the farther sample; not located on re-solved states ({e}); {surface_note}"
                ),
                not_located: Some(e.to_string()),
            });
        }
    };
    if let Ok((fine, ladder_cells)) = ladder_crossing(
        dopts,
        surfaces,
        &tracks,
        ex.x,
        exchange_doublings(dopts.accuracy),
    ) {
        if (fine.x - ex.x).abs() <= ex.error {
            let cells: Vec<String> = ladder_cells.iter().map(|c| c.to_string()).collect();
            return Ok(Crossing {
                lbar: fine.x,
                error: fine.error,
                energy: 0.5 * (fine.energies.a + fine.energies.b),
                surface_lbar: xs,
                method: format!(
                    "the exchange locator on E_a = E_b with the lifted-off state(s) re-solved on a ladder of meshes (3-D model at N = {}; the trace's levels N/4, N/2, N first, hunt from the interpolated root, Brent to 1e-10, then the ladder from that root); error: the ladder's energy estimates (four levels) plus the misfit of the chord over +-1e-5, over its slope, plus the final bracket; {}",
                    cells.join(", "),
                    surface_note
                ),
                not_located: None,
            });
        }
    }
    let cells = tracks
        .iter()
        .flatten()
        .map(|t| t.states[2].model.cells())
        .max()
        .unwrap_or(0);
    Ok(Crossing {
        lbar: ex.x,
        error: ex.error,
        energy: 0.5 * (ex.energies.a + ex.energies.b),
        surface_lbar: xs,
        method: format!(
            "the exchange locator on E_a = E_b with the lifted-off state(s) re-solved (3-D model at N = {}, {}, {}; hunt from the interpolated root, Brent to 1e-10); error: the three levels' energy estimates plus the misfit of the chord over +-2e-3, over its slope, plus the final bracket; {surface_note}",
            cells / 4,
            cells / 2,
            cells
        ),
        not_located: None,
    })
}

/// `E_a = E_b` near `x` on ladders of meshes ([`Ladder::from_levels`] with `doublings`
/// more levels) for the lifted-off sheets (`tracks`, walked to `x` first) and the surface
/// energies for the others, on `doublings` doublings of their tracing resolution as well
/// ([`surface_energy_doubled`]); first step `−10⁻⁵`, slope and noise from the chord over
/// `±10⁻⁵`. Returns the exchange and the cells of the finest ladder's levels.
fn ladder_crossing(
    dopts: &DiagramOptions,
    surfaces: [&TracedBranch; 2],
    tracks: &[Option<Levels>; 2],
    x: f64,
    doublings: usize,
) -> Result<(rodloop_continuation::exchange::Exchange, Vec<usize>), SolverError> {
    let mut ladders: [Option<Ladder>; 2] = [None, None];
    let mut cells = Vec::new();
    for (k, t) in tracks.iter().enumerate() {
        if let Some(t) = t {
            let at = walk(t, x)?;
            let lad = Ladder::from_levels(&at, x, doublings)?;
            if lad.cells().last() > cells.last() {
                cells = lad.cells();
            }
            ladders[k] = Some(lad);
        }
    }
    let settings = ExchangeSettings {
        probe: -1e-5,
        baseline: 1e-5,
        ..ExchangeSettings::default()
    };
    let side = |lad: &mut Option<Ladder>, surface: &TracedBranch, y: f64| match lad {
        Some(lad) => {
            let next = lad.step_to(y)?;
            let e = next.energy()?;
            *lad = next;
            Ok(e)
        }
        None => surface_energy_doubled(dopts, surface, y, doublings),
    };
    let [la, lb] = &mut ladders;
    let mut pair = EnclosedPair::new(|y| side(la, surfaces[0], y), |y| side(lb, surfaces[1], y));
    let ex = locate_from(&mut pair, x, &settings)?;
    Ok((ex, cells))
}

/// Distance from a great circle `L̄ = m` within which a change of the lowest sheet is
/// a collapse, not a crossing.
pub(super) const CIRCLE: f64 = 2e-3;

/// Mean `D/D0` of the profile (the energy of the `m`-fold great circle is `m D̄/D0`).
pub(super) fn mean_stiffness(opts: &EnclosedDiagramOptions) -> Result<f64, SolverError> {
    let prof = opts.stiffness.validate()?;
    let n = 20000;
    let sum: f64 = (0..n)
        .map(|i| prof.eval((i as f64 + 0.5) / n as f64).d)
        .sum();
    Ok(sum / n as f64 / opts.stiffness.reference())
}

/// Root evaluations that [`locate_crossing_by_solve`] allows.
const SOLVE_ROOT_ITERATIONS: usize = 8;

/// Largest ratio of the slope of `E_a − E_b` across the final bracket to its slope across
/// the samples' bracket that [`locate_crossing_by_solve`] accepts as one smooth crossing;
/// a jump (the lowest minimum of one branch changing family inside the bracket) makes the
/// final slope grow without bound as the bracket shrinks.
const SOLVE_ROOT_STEEPENING: f64 = 10.0;

/// Locate `E_a = E_b` in `[x0, x1]` where the traced sheets do not (the trace of one side
/// stopped inside the bracket, or a walk there fails at a fold or a change of the contact
/// set, so the crossing would be placed by interpolation): the root of the difference of
/// `solve`'s lowest local minima of the two branches ([`crate::enclosed_state::solve_state`]
/// at the diagram's accuracy, the two branches on two threads), by the Illinois method
/// ([`rodloop_continuation::roots::illinois`]) until the bracket is inside the two energies'
/// estimates over the chord's slope. The estimate is the final bracket plus the estimates
/// over the slope there. Refused: a state of index > 0 (`solve` found only saddles), no sign
/// change, or a jump of the difference ([`SOLVE_ROOT_STEEPENING`]).
pub(super) fn locate_crossing_by_solve(
    opts: &EnclosedDiagramOptions,
    branches: [u32; 2],
    x0: f64,
    x1: f64,
) -> Result<Crossing, DiagramError> {
    use rodloop_continuation::{roots, RootError};
    use rodloop_solver::enclosed::stats;
    let scope = stats::current();
    let refused = |lbar: f64, reason: String| DiagramError::Critical {
        from_branch: branches[0],
        to_branch: branches[1],
        lbar,
        reason,
    };
    // (lbar, [E_a, E_b], [error_a, error_b]) of every evaluation.
    let mut seen: Vec<(f64, [f64; 2], [f64; 2])> = Vec::new();
    let mut solve_both = |x: f64| -> Result<([f64; 2], [f64; 2]), DiagramError> {
        if let Some(&(_, e, err)) = seen.iter().find(|s| s.0 == x) {
            return Ok((e, err));
        }
        let solve_one = |branch: u32| {
            stats::within(&scope, || {
                let res = solve_state(&opts.wall, &opts.stiffness, x, branch, opts.accuracy)?;
                if res.stability.0 > 0 {
                    return Err(refused(
                        x,
                        format!(
                            "solve finds no local minimum of branch {branch} there (the lowest state it reaches has index {})",
                            res.stability.0
                        ),
                    ));
                }
                Ok(res.energy)
            })
        };
        let (a, b) = std::thread::scope(|s| {
            let a = s.spawn(|| solve_one(branches[0]));
            let b = solve_one(branches[1]);
            (a.join(), b)
        });
        let a = a.map_err(|_| refused(x, "a solve thread panicked".into()))??;
        let b = b?;
        let out = ([a.0, b.0], [a.1, b.1]);
        seen.push((x, out.0, out.1));
        Ok(out)
    };
    let (e0, r0) = solve_both(x0)?;
    let (e1, r1) = solve_both(x1)?;
    let chord = ((e1[0] - e1[1]) - (e0[0] - e0[1])) / (x1 - x0);
    let noise = (r0[0] + r0[1]).max(r1[0] + r1[1]);
    let tol = if chord.abs() > 0.0 {
        noise / chord.abs()
    } else {
        x1 - x0
    };
    let root = roots::illinois(
        |x| solve_both(x).map(|(e, _)| e[0] - e[1]),
        x0,
        x1,
        tol,
        SOLVE_ROOT_ITERATIONS,
    )
    .map_err(|e| match e {
        RootError::Function(e) => e,
        RootError::NoBracket { a, b, fa, fb } => refused(
            a,
            format!(
                "solve's lowest minima do not cross in [{a:.6}, {b:.6}] (E_a - E_b = {fa:.3e}, {fb:.3e})"
            ),
        ),
        other => refused(x0, other.to_string()),
    })?;
    if root.slope.abs() > SOLVE_ROOT_STEEPENING * chord.abs() {
        return Err(refused(
            root.x,
            format!(
                "E_a - E_b jumps there (slope {:.3e} across the final bracket, {chord:.3e} across the samples): the lowest minimum of a branch changes family",
                root.slope
            ),
        ));
    }
    let (e, err) = solve_both(root.x)?;
    Ok(Crossing {
        lbar: root.x,
        error: root.width + (err[0] + err[1]) / root.slope.abs(),
        energy: 0.5 * (e[0] + e[1]),
        surface_lbar: None,
        method: format!(
            "the root of E_a - E_b on solve's lowest local minima of branches {} and {} (the solve command's search at this accuracy), Illinois from lbar = {x0:.6}, {x1:.6} in {} evaluations; error: the final bracket plus the two energies' estimates over the slope",
            branches[0],
            branches[1],
            root.iterations + 2
        ),
        not_located: None,
    })
}

#[cfg(test)]
#[path = "nonuniform_exchange_tests.rs"]
mod tests;
