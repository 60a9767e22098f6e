//! The enclosed diagram of a non-uniform rod (two-segment stiffness, Eq. (51); paper Sec. 3.2
//! with the rods of Sec. 5).
//!
//! It is one file because the route below is one pipeline whose steps consume each other's
//! records (surface sheets, events, lifted-off sheets, exchanges).
//!
//! # Route
//!
//! * **Surface families first.** [`compute_families`] traces every family of each branch on
//!   the sphere (sheets monotone in `L̄`, mirror pairs once) with `λ(s)` at every state.
//!   Where a surface state has `λ_min > 0` it meets every enclosed KKT condition (the same
//!   argument as for uniform rods, Eq. (27) with the wall pushing), so it *is* the enclosed
//!   state: energy, error estimate and index are the surface ones (with every wall
//!   constraint strongly active, the tangent space of the active constraints is the
//!   sphere's, so the index is the surface index).
//! * **Events** are where `λ_min` of a sheet changes sign between traced states: the root of
//!   `λ_min(L̄)` is found by the Illinois method on surface states re-solved at the tracing
//!   resolution `N`, then at `4N` and `8N` (`λ` involves `κ_g''`, so the tracing resolution
//!   places it only to ~5e-4 on a mild rod); the `8N` root is reported, with `|x_8N − x_4N|`
//!   plus the bracket widths as its error estimate.
//! * **Lifted-off parts** (`λ_min < 0` on the sheet) are traced with the 3-D enclosed model:
//!   the run's middle sample is solved from its surface state ([`solve_branch`]: Newton,
//!   the pull homotopy where plain Newton fails), then natural-parameter steps in `L̄` with
//!   warm starts at three resolutions `N/4, N/2, N` ([`super::trace::follow`]), exactly as
//!   for uniform rods. `N = max(32(1+η), 32(2+η))` at default accuracy: the coarsest level
//!   must resolve the `tanh` transitions (as in `rodloop solve`).
//! * **Exchanges** of the lowest branch come from the enclosed energies themselves (the
//!   enclosed lowest branch need not change where the surface one does): where the lowest
//!   sampled state changes from a sheet of one branch to a sheet of another and both
//!   sheets cover the bracket, `E_a = E_b` is located by the exchange locator
//!   ([`rodloop_continuation::exchange::locate`]) on re-solved states (3-D model at
//!   `N/4, N/2, N`; surface states where attached): a hunt from the root of the
//!   interpolated difference to a sign change, then Brent's method to `1e-10` (the
//!   lifted-off energies carry discretisation noise where contact ends cross nodes, and the
//!   curves meet at a small angle). Error: `(δE_a + δE_b + m)/|d(E_a − E_b)/dL̄|` plus the
//!   final bracket, with the slope and the noise misfit `m` from the chord over `±2e-3`
//!   around the root. Where a lifted-off sheet cannot be re-solved next to the crossing,
//!   or where the trace of one side stops inside the bracket, the exchange is located on
//!   `solve`'s lowest minima of the two branches instead
//!   ([`super::nonuniform_exchange::locate_crossing_by_solve`]); where that is refused too,
//!   the root of the sampled energies' interpolated difference stands, with the distance
//!   to the farther sample as its estimate, and a warning. The surface value of the same
//!   exchange is located on the same two sheets for comparison. Where the lowest branch
//!   ends at the `m`-fold great circle and another
//!   begins there (the traces do not overlap), the exchange is a collapse at `L̄ = m`, with
//!   the distance of the last traced states from `m` as its estimate. A change between
//!   families of one branch is not an exchange (as in the surface diagram).

#![allow(clippy::needless_range_loop)]

use std::time::Instant;

use rodloop_continuation::exchange;
use rodloop_exact::branch_of_eta;
use rodloop_exact::diagram::{Critical, CriticalKind};
use rodloop_solver::enclosed::stats::{self, Stage};
use rodloop_solver::enclosed::{nonuniform_cells, solve_branch, EnclosedOptions, SurfaceSource};
use rodloop_solver::{solve_from_state, SolverError};

use super::levels::Levels;
use super::nonuniform_descent::descend_unstable;
use super::nonuniform_exchange::{
    interp, locate_crossing, locate_crossing_by_solve, lowest_at, mean_stiffness, ranked_at,
    Crossing, CIRCLE,
};
use super::nonuniform_seeds::seed_from_stiffness_path;
use super::nonuniform_sheet::{check_rows_on_finer, surface_at, surface_energy, SheetOut};
use super::nonuniform_special::{
    branch_points, classify_stops, fold_events, stop_folds, unlocated_at_folds, SheetBranchPoints,
};
use super::trace::follow;
use super::trace::step_options;
use super::{
    BranchFrom, EnclosedCritical, EnclosedDiagram, EnclosedDiagramOptions, EnclosedEvent,
    EnclosedPoint, EnclosedProgress, EnclosedTimings, EventKind, PointShape, PointSource,
};
use crate::families::compute_families;
use crate::labels::Label;
use crate::parallel::run_parallel;
use crate::states::newton_options;
use crate::types::TracedBranch;
use crate::{DiagramError, DiagramOptions};

/// The surface diagram options matching `opts`.
fn surface_options(opts: &EnclosedDiagramOptions) -> DiagramOptions {
    DiagramOptions {
        radius: opts.radius,
        stiffness: opts.stiffness.clone(),
        lbar_min: opts.lbar_min,
        lbar_max: opts.lbar_max,
        accuracy: opts.accuracy,
        great_circles: false,
        ..DiagramOptions::default()
    }
}

/// `λ_min R³/D0` of the surface state of `sheet` at `x` (`cells` cells).
fn lambda_min_at(
    dopts: &DiagramOptions,
    sheet: &TracedBranch,
    x: f64,
    cells: usize,
) -> Result<f64, SolverError> {
    let eq = surface_at(dopts, sheet, x, cells)?;
    let r = dopts.radius;
    Ok(eq.lambda_range().0 * r.powi(3) / dopts.stiffness.reference())
}

/// Root of `f` in `[a, b]` (`f(a) f(b) < 0`) by the Illinois method, to a bracket of `tol`.
/// Returns `(root, bracket width)`.
fn illinois<F>(f: F, a: f64, b: f64, tol: f64) -> Result<(f64, f64), SolverError>
where
    F: FnMut(f64) -> Result<f64, SolverError>,
{
    use rodloop_continuation::{roots, RootError};
    match roots::illinois(f, a, b, tol, 60) {
        Ok(r) => Ok((r.x, r.width)),
        Err(RootError::Function(e)) => Err(e),
        Err(RootError::NoBracket { .. }) => Err(SolverError::InvalidInput(format!(
            "no sign change of lambda_min in [{a}, {b}] at this resolution"
        ))),
        Err(other) => Err(SolverError::InvalidInput(other.to_string())),
    }
}

/// Locate the event between traced states at `a` and `b` of `sheet` (see the module docs).
/// Returns `(L̄, error estimate)`.
fn locate_event(
    dopts: &DiagramOptions,
    sheet: &TracedBranch,
    a: f64,
    b: f64,
) -> Result<(f64, f64), SolverError> {
    let n = sheet.cells;
    let (x0, w0) = illinois(|x| lambda_min_at(dopts, sheet, x, n), a, b, 1e-10)?;
    // At 4N and 8N, brackets around the previous root (widened until the sign changes).
    let refine = |c: usize, x_prev: f64, w_prev: f64| -> Result<(f64, f64), SolverError> {
        let f = |x: f64| lambda_min_at(dopts, sheet, x, c);
        let mut h = (2.0 * w_prev).max(1e-6);
        for _ in 0..12 {
            let (lo, hi) = ((x_prev - h).max(a), (x_prev + h).min(b));
            if f(lo)? * f(hi)? <= 0.0 {
                return illinois(f, lo, hi, 1e-10);
            }
            h *= 4.0;
        }
        Err(SolverError::InvalidInput(format!(
            "lambda_min has no sign change near lbar = {x_prev} at {c} cells"
        )))
    };
    let (x1, w1) = refine(4 * n, x0, w0 + 1e-4)?;
    let (x2, w2) = refine(8 * n, x1, w1 + 1e-5)?;
    Ok((x2, (x2 - x1).abs() + w1 + w2))
}

/// Sample states of `sheet` within `[lo, hi]`: its traced states at least `step` apart in
/// `L̄`, with both ends.
fn samples(sheet: &TracedBranch, lo: f64, hi: f64, step: f64) -> Vec<usize> {
    let idx: Vec<usize> = (0..sheet.points.len())
        .filter(|&k| {
            let x = sheet.points[k].value;
            x >= lo - 1e-12 && x <= hi + 1e-12
        })
        .collect();
    let mut out: Vec<usize> = Vec::new();
    for (j, &k) in idx.iter().enumerate() {
        let x = sheet.points[k].value;
        let last = j + 1 == idx.len();
        match out.last() {
            None => out.push(k),
            Some(&p) if x - sheet.points[p].value >= step - 1e-9 => out.push(k),
            Some(&p) if last && x - sheet.points[p].value > 1e-9 => {
                // The end: replace a sample closer than half a step.
                if x - sheet.points[p].value < 0.5 * step && out.len() > 1 {
                    out.pop();
                }
                out.push(k);
            }
            _ => {}
        }
    }
    out
}

/// An attached sample: the surface state itself (its equilibrium re-evaluated at the
/// tracing resolution for `states/`).
fn surface_point(dopts: &DiagramOptions, sheet: &TracedBranch, k: usize) -> EnclosedPoint {
    let p = &sheet.points[k];
    let shape = sheet
        .equilibrium_of(dopts, k)
        .map_or(PointShape::Missing, |eq| PointShape::Surface(Box::new(eq)));
    EnclosedPoint {
        branch: sheet.branch,
        eta: sheet.eta,
        lbar: p.value,
        energy: p.energy,
        energy_error: p.energy_error.unwrap_or((p.energy - p.energy_trace).abs()),
        attached: true,
        contact_fraction: 1.0,
        contact_intervals: 1,
        max_gap: 0.0,
        lambda_min: p.lambda_min,
        gap_min: 0.0,
        complementarity: 0.0,
        stationarity: 0.0,
        index: p.index,
        label: Label::Unstable,
        lowest: false,
        cells: sheet.cells,
        source: PointSource::Surface,
        family: sheet.family,
        sheet: sheet.sheet,
        multiplicity: sheet.multiplicity,
        branch_from: BranchFrom::Exact,
        surface_energy: Some(p.energy),
        shape,
    }
}

/// `E_N` of `sheet` at `x` by cubic Hermite interpolation of its traced states (energy at the
/// tracing resolution and `dE/dL̄`); `None` outside them.
fn hermite_energy(sheet: &TracedBranch, x: f64) -> Option<f64> {
    let pts = &sheet.points;
    let k = pts.iter().position(|p| p.value >= x)?;
    if k == 0 {
        return ((pts[0].value - x).abs() < 1e-12).then_some(pts[0].energy_trace);
    }
    let (a, b) = (&pts[k - 1], &pts[k]);
    let h = b.value - a.value;
    if h <= 0.0 {
        return None;
    }
    let t = (x - a.value) / h;
    let (h00, h10) = (
        2.0 * t.powi(3) - 3.0 * t * t + 1.0,
        t.powi(3) - 2.0 * t * t + t,
    );
    let (h01, h11) = (-2.0 * t.powi(3) + 3.0 * t * t, t.powi(3) - t * t);
    Some(h00 * a.energy_trace + h10 * h * a.slope + h01 * b.energy_trace + h11 * h * b.slope)
}

/// Largest relative energy difference by which a sheet's traced states duplicate
/// another's ([`duplicate_ranges`]).
const DUPLICATE_TOL: f64 = 1e-7;

/// For each sheet, the `L̄` ranges on which an earlier sheet of the same branch (in `order`)
/// carries the same surface states: every traced state of the sheet strictly inside the
/// other's range (at least 4) has the other's energy, Hermite-interpolated
/// ([`hermite_energy`]), to `DUPLICATE_TOL` relative, and the same index. Such states are
/// the same loop, or its mirror image or a shift of its arclength origin (the surface
/// families are seeded at several offsets of the soft segment), so their lifted-off states
/// have the same energies: tracing them again only repeats states.
fn duplicate_ranges(sheets: &[TracedBranch], order: &[usize]) -> Vec<Vec<(f64, f64)>> {
    let mut out = vec![Vec::new(); sheets.len()];
    for (pos, &j) in order.iter().enumerate() {
        let sj = &sheets[j];
        for &i in &order[..pos] {
            let si = &sheets[i];
            if si.branch != sj.branch || si.points.len() < 2 || sj.points.is_empty() {
                continue;
            }
            let (lo, hi) = (si.points[0].value, si.points[si.points.len() - 1].value);
            let inside: Vec<_> = sj
                .points
                .iter()
                .filter(|q| q.value > lo && q.value < hi)
                .collect();
            if inside.len() < 4 {
                continue;
            }
            let same = inside.iter().all(|q| {
                let near = si.points.iter().min_by(|u, v| {
                    (u.value - q.value)
                        .abs()
                        .total_cmp(&(v.value - q.value).abs())
                });
                hermite_energy(si, q.value).is_some_and(|e| {
                    (e - q.energy_trace).abs() <= DUPLICATE_TOL * q.energy_trace.abs().max(1.0)
                }) && near.is_some_and(|n| n.index == q.index)
            });
            if same {
                let a = lo.max(sj.points[0].value);
                let b = hi.min(sj.points[sj.points.len() - 1].value);
                out[j].push((a, b));
            }
        }
        // One range per overlapping run.
        let r = &mut out[j];
        r.sort_by(|u, v| u.0.total_cmp(&v.0));
        let mut merged: Vec<(f64, f64)> = Vec::new();
        for &(a, b) in r.iter() {
            match merged.last_mut() {
                Some(m) if a <= m.1 + 1e-9 => m.1 = m.1.max(b),
                _ => merged.push((a, b)),
            }
        }
        *r = merged;
    }
    out
}

/// Trace one sheet (see the module docs).
fn trace_sheet(
    opts: &EnclosedDiagramOptions,
    dopts: &DiagramOptions,
    sheet: &TracedBranch,
    repeats: &[(f64, f64)],
) -> Result<SheetOut, DiagramError> {
    let (lo, hi) = (opts.lbar_min, opts.lbar_max);
    let what = format!(
        "branch {} (eta = {}) family {} sheet {}",
        sheet.branch, sheet.eta, sheet.family, sheet.sheet
    );
    let mut out = SheetOut::empty(sheet.branch, sheet.eta, sheet.family);
    let pts = &sheet.points;
    // Events between consecutive traced states.
    let ta = Instant::now();
    for k in 1..pts.len() {
        let (a, b) = (&pts[k - 1], &pts[k]);
        if (a.lambda_min > 0.0) == (b.lambda_min > 0.0) || b.value < lo || a.value > hi {
            continue;
        }
        match locate_event(dopts, sheet, a.value, b.value) {
            Ok((x, err)) if x >= lo && x <= hi => {
                let (energy, _) = surface_energy(dopts, sheet, x).unwrap_or((f64::NAN, 0.0));
                out.events.push(EnclosedEvent {
                    kind: if a.lambda_min > 0.0 {
                        EventKind::LiftOff
                    } else {
                        EventKind::Landing
                    },
                    branch: sheet.branch,
                    family: sheet.family,
                    lbar: x,
                    error_estimate: err,
                    energy: if energy.is_finite() {
                        energy
                    } else {
                        a.energy + (x - a.value) / (b.value - a.value) * (b.energy - a.energy)
                    },
                    index_before: a.index,
                    index_after: b.index,
                });
            }
            Ok(_) => {}
            Err(e) => out.warnings.push(format!(
                "{what}: lambda_min changes sign between lbar = {:.6} and {:.6}, but the event was not located ({e})",
                a.value, b.value
            )),
        }
    }
    let mut chosen = samples(sheet, lo, hi, opts.step);
    // Not where another sheet carries the same states (`duplicate_ranges`).
    chosen.retain(|&k| {
        let x = pts[k].value;
        !repeats.iter().any(|&(a, b)| x > a - 1e-9 && x < b + 1e-9)
    });
    for &k in chosen.iter().filter(|&&k| pts[k].lambda_min > 0.0) {
        out.points.push(surface_point(dopts, sheet, k));
    }
    out.attached_s = ta.elapsed().as_secs_f64();
    // Lifted-off runs of consecutive samples.
    let td = Instant::now();
    let mut runs: Vec<Vec<usize>> = Vec::new();
    for &k in &chosen {
        if pts[k].lambda_min > 0.0 {
            runs.push(Vec::new());
        } else {
            match runs.last_mut() {
                Some(r) => r.push(k),
                None => runs.push(vec![k]),
            }
        }
    }
    runs.retain(|r| !r.is_empty());
    let n = nonuniform_cells(opts.accuracy, sheet.eta);
    let sopts = EnclosedOptions::default();
    let seed_at = |k: usize| -> Result<Levels, SolverError> {
        let p = &pts[k];
        let m = crate::surface_model(opts.radius, p.value, sheet.cells, &opts.stiffness)?;
        let eq = solve_from_state(m, p.state.clone(), &newton_options())?;
        let b = solve_branch(
            opts.radius,
            p.value,
            &opts.stiffness,
            &SurfaceSource::Numeric(Box::new(eq)),
            n,
            &sopts,
        )?;
        Ok(Levels {
            lbar: p.value,
            states: [b.quarter, b.coarse, b.fine],
        })
    };
    // Pieces of runs to trace: (samples, seed position or the middle, re-seeded). Where a
    // trace stops short of a run's end, the rest is seeded once more at its sample next to
    // the stop (past a singular point of the lifted-off sheet, e.g. where an asymmetric
    // family meets it) and traced from there both ways.
    let mut pieces: Vec<(Vec<usize>, Option<usize>, bool)> =
        runs.into_iter().map(|r| (r, None, false)).collect();
    while let Some((run, at, reseeded)) = pieces.pop() {
        let xs: Vec<f64> = run.iter().map(|&k| pts[k].value).collect();
        // Seed at `at` (or in the middle); if it fails, the next samples from there.
        let mid0 = at.unwrap_or(xs.len() / 2);
        let mut order: Vec<usize> = (0..xs.len()).collect();
        order.sort_by_key(|&i| (i as i64 - mid0 as i64).abs());
        let mut seeded = None;
        let mut last_err = None;
        for &i in order.iter().take(4) {
            match stats::stage(Stage::Seed, || seed_at(run[i])) {
                Ok(l) => {
                    seeded = Some((i, l));
                    break;
                }
                Err(e) => last_err = Some(e),
            }
        }
        let Some((mid, first)) = seeded else {
            out.warnings.push(format!(
                "{what}: no lifted-off state found between lbar = {:.4} and {:.4} (the enclosed solve from the surface state failed: {}); left out",
                xs[0],
                xs[xs.len() - 1],
                last_err.map_or_else(String::new, |e| e.to_string())
            ));
            continue;
        };
        let traced = follow(
            first,
            &xs,
            mid,
            &what,
            &step_options(),
            true,
            &mut out.stops,
        );
        if !reseeded {
            let (t_lo, t_hi) = (
                traced.first().map_or(f64::INFINITY, |l| l.lbar),
                traced.last().map_or(f64::NEG_INFINITY, |l| l.lbar),
            );
            let above: Vec<usize> = (0..xs.len()).filter(|&j| xs[j] > t_hi + 1e-9).collect();
            let below: Vec<usize> = (0..xs.len()).filter(|&j| xs[j] < t_lo - 1e-9).collect();
            // Seeded at the sample next to the stop (the nearest surface state past the
            // singular point), traced from there both ways.
            if above.len() > 1 {
                let r: Vec<usize> = above.iter().map(|&j| run[j]).collect();
                pieces.push((r, Some(0), true));
            }
            if below.len() > 1 {
                let r: Vec<usize> = below.iter().map(|&j| run[j]).collect();
                let at = r.len() - 1;
                pieces.push((r, Some(at), true));
            }
        }
        for lv in traced {
            let mut pt = lv.point(sheet.branch, sheet.eta)?;
            // The surface loop at the same length: the traced state, or (where the trace
            // stopped between samples) re-solved there, or, where that re-solve fails,
            // interpolated between the sheet's traced states with the change between them
            // as its error.
            let (surf, surf_err) = match xs.iter().position(|&x| (x - lv.lbar).abs() < 1e-12) {
                Some(i) => {
                    let p = &pts[run[i]];
                    (p.energy, p.energy_error.unwrap_or(0.0))
                }
                None => match surface_energy(dopts, sheet, lv.lbar) {
                    Ok(v) => v,
                    Err(e) => {
                        let k = pts.partition_point(|p| p.value < lv.lbar);
                        if k == 0 || k == pts.len() {
                            return Err(e.into());
                        }
                        let (a, b) = (&pts[k - 1], &pts[k]);
                        let t = (lv.lbar - a.value) / (b.value - a.value);
                        (
                            a.energy + t * (b.energy - a.energy),
                            (b.energy - a.energy).abs(),
                        )
                    }
                },
            };
            pt.family = sheet.family;
            pt.sheet = sheet.sheet;
            pt.multiplicity = sheet.multiplicity;
            pt.surface_energy = Some(surf);
            if pt.energy > surf + surf_err {
                // Not this sheet's lifted-off state: the wall that may pull no longer only
                // relaxes the surface loop here (the levels disagree, or the trace crossed
                // to another solution near a fold of the sheet).
                out.warnings.push(format!(
                    "{what} at lbar = {:.6}: the enclosed state found ({:.10} ± {:.1e}) lies above the sheet's surface loop ({:.10}); left out",
                    lv.lbar, pt.energy, pt.energy_error, surf
                ));
                continue;
            }
            out.points.push(pt);
            out.levels.push(lv);
        }
    }
    out.lifted_s = td.elapsed().as_secs_f64();
    out.points.sort_by(|u, v| u.lbar.total_cmp(&v.lbar));
    Ok(out)
}

/// The enclosed diagram of a non-uniform rod (see the module docs).
pub(super) fn nonuniform_diagram(
    opts: &EnclosedDiagramOptions,
    progress: &mut dyn FnMut(EnclosedProgress),
) -> Result<EnclosedDiagram, DiagramError> {
    let t0 = Instant::now();
    if opts.lbar_min < 1.0 {
        return Err(DiagramError::InvalidOptions(format!(
            "the enclosed diagram of a non-uniform rod starts at lbar = 1 (got lbar_min = {}): below it the loop is free and, with non-uniform stiffness, not a circle; that free loop is not modelled",
            opts.lbar_min
        )));
    }
    let dopts = surface_options(opts);
    let wanted = |b: u32| opts.branches.as_ref().is_none_or(|s| s.contains(&b));
    let etas: Vec<u32> = dopts
        .etas()
        .into_iter()
        .filter(|&e| wanted(branch_of_eta(e)))
        .collect();
    let threads = dopts.worker_threads();
    let mut warnings = Vec::new();
    let mut timings = EnclosedTimings::default();
    // 1. Surface families.
    let ts = Instant::now();
    // Tasks: the surface families of each branch, then (once they are known) the sheets,
    // and the three stages after them (descent, branch points, exchanges).
    progress(EnclosedProgress::Planned(etas.len() + 4));
    let fams = run_parallel(
        threads,
        etas.clone(),
        &mut |_| {},
        &mut |f: &Result<crate::families::Families, DiagramError>| {
            if let Ok(f) = f {
                progress(EnclosedProgress::Done(format!(
                    "surface families of branch {} traced ({} sheets)",
                    f.sheets.first().map_or(0, |s| s.branch),
                    f.sheets.len()
                )));
            }
        },
        |eta, _| compute_families(&dopts, eta, &mut |_| {}),
    );
    let mut sheets: Vec<TracedBranch> = Vec::new();
    for f in fams {
        let f = f?;
        warnings.extend(f.notes);
        sheets.extend(f.sheets);
    }
    let surface_s = ts.elapsed().as_secs_f64();
    // 2. Each sheet: attached samples, events, lifted-off traces (longest first).
    let mut order: Vec<usize> = (0..sheets.len()).collect();
    order.sort_by_key(|&i| {
        std::cmp::Reverse(
            samples(&sheets[i], opts.lbar_min, opts.lbar_max, opts.step).len() * sheets[i].cells,
        )
    });
    let repeats = duplicate_ranges(&sheets, &order);
    let mut notes: Vec<String> = Vec::new();
    for (j, r) in repeats.iter().enumerate() {
        for &(a, b) in r {
            notes.push(format!(
                "branch {} (eta = {}) family {} sheet {}: its surface states on {a:.6} < lbar < {b:.6} repeat another sheet's of the branch (energies within {DUPLICATE_TOL:.0e} relative, same index): the same loops, not traced again",
                sheets[j].branch, sheets[j].eta, sheets[j].family, sheets[j].sheet
            ));
        }
    }
    progress(EnclosedProgress::Planned(order.len()));
    let tsheets = Instant::now();
    let scope = stats::current();
    let outs = run_parallel(
        threads,
        order.clone(),
        &mut |_| {},
        &mut |o: &Result<SheetOut, DiagramError>| {
            if let Ok(o) = o {
                progress(EnclosedProgress::Done(format!(
                    "branch {} family {} traced ({} states)",
                    o.branch,
                    o.family,
                    o.points.len()
                )));
            }
        },
        |i, _| {
            stats::within(&scope, || {
                trace_sheet(opts, &dopts, &sheets[i], &repeats[i])
            })
        },
    );
    timings.sheets = tsheets.elapsed().as_secs_f64();
    let mut traced: Vec<(usize, SheetOut)> = Vec::new();
    for (i, o) in order.into_iter().zip(outs) {
        let o = o?;
        timings.attached += o.attached_s;
        timings.lifted_off += o.lifted_s;
        traced.push((i, o));
    }
    traced.sort_by_key(|(i, _)| *i);
    let (mut idx, mut outs): (Vec<usize>, Vec<SheetOut>) = traced.into_iter().unzip();
    // 2a. Lifted-off families the surface states do not lead to (the stiffness path).
    let tseed = Instant::now();
    let before = outs.len();
    notes.extend(seed_from_stiffness_path(opts, &mut outs, threads));
    // Each family found descends from no surface sheet: it is listed with the first sheet
    // of its branch.
    for k in before..outs.len() {
        let b = outs[k].branch;
        let root = (0..before)
            .find(|&j| outs[j].branch == b)
            .map_or(idx[0], |j| idx[j]);
        idx.push(root);
    }
    timings.stiffness_path = tseed.elapsed().as_secs_f64();
    timings.lifted_off += timings.stiffness_path;
    progress(EnclosedProgress::Done(
        "lifted-off families from the stiffness path".into(),
    ));
    // 2b. Lower states below unstable lowest ones (new families).
    let tdesc = Instant::now();
    // States that another branch's periods name are no rows of this one (before the descent,
    // which starts from the lowest rows, and after it, for the families it adds).
    warnings.extend(outs.iter_mut().filter_map(SheetOut::drop_other_branches));
    let dbar = mean_stiffness(opts)?;
    let (w, n, parents) = descend_unstable(&mut outs, &idx, opts.accuracy, threads, dbar);
    warnings.extend(w);
    notes.extend(n);
    idx.extend(parents);
    warnings.extend(outs.iter_mut().filter_map(SheetOut::drop_other_branches));
    timings.descent = tdesc.elapsed().as_secs_f64();
    timings.lifted_off += timings.descent;
    progress(EnclosedProgress::Done(
        "descent from unstable lowest states".into(),
    ));
    // 2c. Branch points where a lifted-off sheet's index changes; the traces' stops.
    let tbp = Instant::now();
    let found = run_parallel(
        threads,
        (0..outs.len()).collect(),
        &mut |_| {},
        &mut |_: &SheetBranchPoints| {},
        |i, _| branch_points(&outs[i]),
    );
    let mut special: Vec<EnclosedEvent> = Vec::new();
    let mut unlocated = Vec::new();
    let mut contact_changes = Vec::new();
    for f in found {
        special.extend(f.events);
        notes.extend(f.notes);
        warnings.extend(f.warnings);
        unlocated.extend(f.unlocated);
        contact_changes.extend(f.contact_changes);
    }
    timings.branch_points = tbp.elapsed().as_secs_f64();
    let tfold = Instant::now();
    let folds = run_parallel(
        threads,
        (0..outs.len()).collect(),
        &mut |_| {},
        &mut |_: &Vec<super::fold::StopFold>| {},
        |i, _| stop_folds(&outs[i]),
    );
    timings.folds = tfold.elapsed().as_secs_f64();
    let fold_points = fold_events(&outs, &folds);
    let (at, n, w) = unlocated_at_folds(unlocated, &fold_points);
    special.extend(at);
    notes.extend(n);
    warnings.extend(w);
    special.extend(fold_points);
    let (stop_notes, stop_warnings) = classify_stops(&outs, &special, &contact_changes, &folds);
    notes.extend(stop_notes);
    warnings.extend(stop_warnings);
    timings.lifted_off += tbp.elapsed().as_secs_f64();
    progress(EnclosedProgress::Done("branch points located".into()));
    let surf: Vec<&TracedBranch> = idx.iter().map(|&i| &sheets[i]).collect();
    // 2d. Each lifted-off row's estimate checked on twice its cells.
    let tcheck = Instant::now();
    let (widened, failed) = check_rows_on_finer(&mut outs, threads);
    notes.push(format!(
        "the estimates of the lifted-off rows that touch the wall are checked on twice their cells (the distance to that state plus its own estimate from N/2, N, 2N): {widened} widened to that bound{}",
        if failed > 0 {
            format!(", {failed} not checked (the re-solve on 2N cells failed)")
        } else {
            String::new()
        }
    ));
    timings.row_checks = tcheck.elapsed().as_secs_f64();
    timings.lifted_off += timings.row_checks;
    // 3. Exchanges of the lowest branch.
    let tc = Instant::now();
    let mut grid: Vec<f64> = outs
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.lbar))
        .collect();
    grid.sort_by(f64::total_cmp);
    grid.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
    let mut critical: Vec<EnclosedCritical> = Vec::new();
    // (x0, x1, a, b) brackets of located crossings, for the lowest flags.
    let mut brackets: Vec<(f64, f64, usize, usize)> = Vec::new();
    // Great circles inside the range where some sheet begins or ends.
    let ends: Vec<f64> = (1..=(opts.lbar_max.floor() as u32))
        .map(f64::from)
        .filter(|&m| m >= opts.lbar_min - CIRCLE)
        .filter(|&m| {
            outs.iter()
                .any(|s| [s.eta as f64 - 1.0, s.eta as f64 + 1.0].contains(&m))
        })
        .collect();
    let circles: Vec<f64> = ends
        .iter()
        .copied()
        .filter(|&m| m > opts.lbar_min + CIRCLE && m < opts.lbar_max - CIRCLE)
        .collect();
    // Brackets where the lowest sampled state changes branch: `(x0, x1, a, b, overlap)`.
    let changes: Vec<(f64, f64, usize, usize, bool)> = grid
        .windows(2)
        .filter_map(|w| {
            let (a, b) = (lowest_at(&outs, w[0])?, lowest_at(&outs, w[1])?);
            if a == b || outs[a].eta == outs[b].eta {
                return None;
            }
            let overlap = interp(&outs[a], w[1]).is_some() && interp(&outs[b], w[0]).is_some();
            Some((w[0], w[1], a, b, overlap))
        })
        .collect();
    // The exchanges are independent re-solves: located on the pool, recorded in order.
    let jobs: Vec<usize> = (0..changes.len()).filter(|&j| changes[j].4).collect();
    let mut located: Vec<Option<_>> =
        run_parallel(threads, jobs.clone(), &mut |_| {}, &mut |_| {}, |j, _| {
            let (x0, x1, a, b, _) = changes[j];
            stats::within(&scope, || {
                stats::stage(Stage::Exchange, || {
                    locate_crossing(&dopts, [&outs[a], &outs[b]], [surf[a], surf[b]], x0, x1)
                })
            })
        })
        .into_iter()
        .map(Some)
        .collect();
    // `solve`'s lowest minima of the two branches (where the traced sheets fail).
    let by_solve = |sa: &SheetOut, sb: &SheetOut, x0: f64, x1: f64| {
        stats::within(&scope, || {
            stats::stage(Stage::Exchange, || {
                locate_crossing_by_solve(opts, [sa.branch, sb.branch], x0, x1)
            })
        })
    };
    // A located exchange, its bracket `(x0, x1, a, b)` kept for the lowest flags.
    let mut record = |c: Crossing, base: Critical, method: String, bracket| {
        brackets.push(bracket);
        critical.push(EnclosedCritical {
            critical: Critical {
                lbar_cr: c.lbar,
                energy: c.energy,
                error_estimate: c.error,
                ..base
            },
            surface_lbar_cr: c.surface_lbar,
            method,
        });
    };
    for (j, &(x0, x1, a, b, overlap)) in changes.iter().enumerate() {
        let w = [x0, x1];
        let (sa, sb) = (&outs[a], &outs[b]);
        let base = Critical {
            index: 0,
            lbar_cr: f64::NAN,
            kind: CriticalKind::Crossing,
            from_branch: sa.branch,
            to_branch: sb.branch,
            energy: f64::NAN,
            error_estimate: f64::NAN,
        };
        if overlap {
            let k = jobs
                .binary_search(&j)
                .expect("an overlapping bracket is a job");
            match located[k].take().expect("each exchange is recorded once") {
                Ok(c) => {
                    // Placed by interpolation: `solve`'s lowest minima of the two branches,
                    // where they locate it more closely.
                    let c = match &c.not_located {
                        Some(_) => match by_solve(sa, sb, x0, x1) {
                            Ok(by) if by.error < c.error => Crossing {
                                method: format!(
                                    "{}; the traced sheets place it by interpolation only ({})",
                                    by.method,
                                    c.not_located.as_deref().unwrap_or_default()
                                ),
                                ..by
                            },
                            _ => c,
                        },
                        None => c,
                    };
                    if let Some(why) = &c.not_located {
                        warnings.push(format!(
                            "the exchange of branches {} -> {} between lbar = {:.6} and {:.6} is placed by interpolation of the sampled energies only (to {:.1e}): not located on re-solved states ({why})",
                            sa.branch, sb.branch, w[0], w[1], c.error
                        ));
                    }
                    let method = format!("{}; families {} -> {}", c.method, sa.family, sb.family);
                    record(c, base, method, (x0, x1, a, b));
                }
                Err(e) => warnings.push(format!(
                    "the exchange of branches {} -> {} between lbar = {:.6} and {:.6} was not located: {e}",
                    sa.branch, sb.branch, w[0], w[1]
                )),
            }
            continue;
        }
        if ends
            .iter()
            .any(|m| (w[0] - m).abs() < CIRCLE || (w[1] - m).abs() < CIRCLE)
        {
            // Sheets begin and end at the great circles: handled below.
            continue;
        }
        // A trace stopped inside the bracket.
        match by_solve(sa, sb, x0, x1) {
            Ok(c) => {
                let method = format!(
                    "{}; a trace stopped inside the bracket; the sampled lowest families {} -> {}",
                    c.method, sa.family, sb.family
                );
                record(c, base, method, (x0, x1, a, b));
            }
            Err(e) => warnings.push(format!(
                "the lowest state changes from branch {} to {} between lbar = {:.6} and {:.6} where a trace stopped; not located ({e})",
                sa.branch, sb.branch, w[0], w[1]
            )),
        }
    }
    // Collapses: the lowest sheet just below a great circle `L̄ = m` ends there and the
    // lowest just above begins there.
    for &m in &circles {
        let (Some(a), Some(b)) = (lowest_at(&outs, m - CIRCLE), lowest_at(&outs, m + CIRCLE))
        else {
            continue;
        };
        let (sa, sb) = (&outs[a], &outs[b]);
        if sa.eta == sb.eta {
            continue;
        }
        let a_end = sa.points.last().map_or(f64::NAN, |p| p.lbar);
        let b_start = sb.points.first().map_or(f64::NAN, |p| p.lbar);
        if sa.eta as f64 + 1.0 != m || sb.eta as f64 - 1.0 != m {
            warnings.push(format!(
                "the lowest state changes from branch {} to {} near the great circle lbar = {m} without both ending there; not located",
                sa.branch, sb.branch
            ));
            continue;
        }
        critical.push(EnclosedCritical {
            critical: Critical {
                index: 0,
                kind: CriticalKind::Collapse,
                lbar_cr: m,
                from_branch: sa.branch,
                to_branch: sb.branch,
                energy: m * dbar,
                error_estimate: (a_end - m).abs().max((b_start - m).abs()),
            },
            surface_lbar_cr: Some(m),
            method: format!(
                "the lowest branch {} ends at the {m}-fold great circle and branch {} begins there (E R/(pi D0) = m mean(D)/D0); the enclosed traces reach lbar = {a_end:.6} and {b_start:.6}, so the error estimate is their distance from {m}",
                sa.branch, sb.branch
            ),
        });
    }
    critical.sort_by(|u, v| u.critical.lbar_cr.total_cmp(&v.critical.lbar_cr));
    for (i, c) in critical.iter_mut().enumerate() {
        c.critical.index = i + 1;
    }
    timings.critical = tc.elapsed().as_secs_f64();
    progress(EnclosedProgress::Done(format!(
        "{} critical lengths located",
        critical.len()
    )));
    // 4. Lowest flags and labels.
    let mut points = Vec::new();
    let mut events = Vec::new();
    let mut cells = Vec::new();
    for (k, s) in outs.iter().enumerate() {
        for p in &s.points {
            let mut p = p.clone();
            let states = ranked_at(&outs, &brackets, &critical, k, &p, dbar);
            p.lowest = exchange::lowest_state(&states).contains(&0);
            p.label = exchange::label(&states)[0].into();
            points.push(p);
        }
        events.extend(s.events.iter().cloned());
        warnings.extend(s.warnings.iter().cloned());
        let n = nonuniform_cells(opts.accuracy, s.eta);
        if !cells.contains(&(s.branch, n)) {
            cells.push((s.branch, n));
        }
    }
    events.extend(special);
    events.sort_by(|u, v| u.lbar.total_cmp(&v.lbar));
    timings.surface = surface_s;
    timings.total = t0.elapsed().as_secs_f64();
    Ok(EnclosedDiagram {
        points,
        events,
        critical,
        warnings,
        notes,
        cells,
        seconds: timings,
        solves: Vec::new(),
    })
}
