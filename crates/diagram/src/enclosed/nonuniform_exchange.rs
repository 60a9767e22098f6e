//! Exchanges of the lowest branch in the enclosed diagram of a non-uniform rod (see
//! `nonuniform.rs`): the lowest sheet at a length, `E_a = E_b` solved on re-solved states
//! (secant, then a fitted line), and the energy of the `m`-fold great circle.

use rodloop_solver::SolverError;

use super::critical::secant;
use super::nonuniform_sheet::{surface_energy, walk, SheetOut};
use super::trace::Levels;
use super::{EnclosedDiagramOptions, PointSource};
use crate::types::TracedBranch;
use crate::DiagramOptions;

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

/// Locate `E_a = E_b` near `[x0, x1]` (see the module docs). Returns `(L̄, error, energy,
/// surface L̄, method)`.
pub(super) fn locate_crossing(
    dopts: &DiagramOptions,
    sheets: [&SheetOut; 2],
    surfaces: [&TracedBranch; 2],
    x0: f64,
    x1: f64,
) -> Result<(f64, f64, f64, f64, String), SolverError> {
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
    let f = |x: f64, tr: &mut [Option<Levels>; 2]| -> Result<(f64, f64, f64), SolverError> {
        let (ea, da) = sheet_energy(dopts, surfaces[0], x, &mut tr[0])?;
        let (eb, db) = sheet_energy(dopts, surfaces[1], x, &mut tr[1])?;
        Ok((ea - eb, da + db, 0.5 * (ea + eb)))
    };
    let h = 1e-3f64.min(0.25 * (x1 - x0).abs().max(1e-5));
    // The surface value on the same two sheets.
    let mut none: [Option<Levels>; 2] = [None, None];
    let (xs, _, _, _, _) = secant_loose(|x| f(x, &mut none), xg, xg - h)?;
    if !lifted {
        let (x, slope, step, err, e) = secant(|x| f(x, &mut none), xs, xs - 1e-6)?;
        return Ok((
            x,
            err / slope.abs().max(1e-300) + step,
            e,
            xs,
            "surface states (both attached: lambda_min > 0); secant on E_a = E_b, error from the N and 2N surface energies and the last secant step".into(),
        ));
    }
    let (xsec, _, _, _, _) = secant_loose(|x| f(x, &mut tracks), xg, xg - h)?;
    // The energies carry discretisation noise (contact ends crossing nodes) and the two
    // curves meet at a small angle, so the root is taken from the straight line fitted to
    // `E_a − E_b` at `x_s − d, x_s, x_s + d` (`d = 2e-3`) around the secant's root `x_s`.
    let d = 2e-3;
    let mut fs = [(0.0, 0.0, 0.0); 3];
    for (k, x) in [xsec - d, xsec, xsec + d].into_iter().enumerate() {
        fs[k] = f(x, &mut tracks)?;
    }
    let slope = (fs[2].0 - fs[0].0) / (2.0 * d);
    let mean = (fs[0].0 + fs[1].0 + fs[2].0) / 3.0;
    let x = xsec - mean / slope;
    let err = fs.iter().map(|v| v.1).fold(0.0, f64::max);
    // The line's misfit at the middle point (curvature and noise of E_a − E_b).
    let misfit = (fs[1].0 - 0.5 * (fs[0].0 + fs[2].0)).abs();
    // Plus the distance beyond the fitted points where the root is extrapolated.
    let step = misfit / slope.abs().max(1e-300) + ((x - xsec).abs() - d).max(0.0);
    // The mean energy at the root, from its values at the three points.
    let e = fs[1].2 + (x - xsec) * (fs[2].2 - fs[0].2) / (2.0 * d);
    let cells = tracks
        .iter()
        .flatten()
        .map(|t| t.states[2].model.cells())
        .max()
        .unwrap_or(0);
    Ok((
        x,
        err / slope.abs().max(1e-300) + step,
        e,
        xs,
        format!(
            "secant on E_a = E_b with the lifted-off state(s) re-solved (3-D model at N = {}, {}, {}), then the root of the line fitted at the secant root and 2e-3 on either side; error: the three levels' energy estimates over the slope plus the line's misfit over the slope; surface value on the same sheets",
            cells / 4,
            cells / 2,
            cells
        ),
    ))
}

/// Secant iteration on `f(x) = 0` from `xa`, `xb` until the step is below `1e-10` or 12
/// steps are taken (the energies of lifted-off states carry discretisation noise where
/// contact ends cross nodes, so the last step, which enters the error, may stay above the
/// tolerance); returns `(x, f', last step, f's error, mean energy)`.
fn secant_loose<F>(mut f: F, xa: f64, xb: f64) -> Result<(f64, f64, f64, f64, f64), SolverError>
where
    F: FnMut(f64) -> Result<(f64, f64, f64), SolverError>,
{
    use rodloop_continuation::roots::{self, SecantSettings};
    let settings = SecantSettings {
        xtol: 1e-10,
        max_iter: 12,
        ..SecantSettings::default()
    };
    if (xb - xa).abs() < settings.xtol {
        let (fa, _, _) = f(xa)?;
        let (fb, err, e) = f(xb)?;
        return Ok((xb, (fb - fa) / (xb - xa), (xb - xa).abs(), err, e));
    }
    let r = roots::secant(|x| f(x).map(|(v, err, e)| (v, (err, e))), xa, xb, &settings).map_err(
        |e| match e {
            rodloop_continuation::RootError::Function(e) => e,
            other => SolverError::InvalidInput(other.to_string()),
        },
    )?;
    let (err, e) = r.payload;
    Ok((r.x, r.slope, r.width, err, e))
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
