//! The critical lengths of the enclosed diagram where a branch has lifted off (secant on
//! `E_a = E_b` with re-solved states), and the lowest-branch labels (see the parent
//! module's docs).

use rodloop_solver::enclosed::EnclosedOptions;
use rodloop_solver::SolverError;

use super::trace::{exact, Levels};
use super::{EnclosedCritical, EnclosedPoint};
use crate::labels::Label;

/// Is the surface loop of `eta` at `lbar` lifted off (`λ_min < 0`)?
pub(super) fn detached_at(eta: u32, lbar: f64) -> Result<bool, SolverError> {
    Ok(exact(eta, lbar)?.lambda_range().0 < 0.0)
}

/// Energy of branch `eta` at `lbar` with its error: the exact loop where attached,
/// otherwise the 3-D model warm-started from `track` (updated).
pub(super) fn branch_energy(
    eta: u32,
    lbar: f64,
    track: &mut Option<Levels>,
) -> Result<(f64, f64), SolverError> {
    if eta == 0 {
        return Ok((1.0 / lbar, 0.0));
    }
    let l = exact(eta, lbar)?;
    if l.lambda_range().0 >= 0.0 {
        let e = l.energy()?;
        return Ok((e, 1e-14 * e.abs().max(1.0)));
    }
    let t = track.as_ref().ok_or_else(|| {
        SolverError::InvalidInput(format!(
            "no lifted-off state of branch eta = {eta} near lbar = {lbar} to start from"
        ))
    })?;
    let next = t.step_to(lbar, &EnclosedOptions::default())?;
    let out = next.energy();
    *track = Some(next);
    Ok(out)
}

/// Secant iteration on `f(x) = 0` from `xa` and `xb` until the step is below `1e-12`;
/// returns `(x, f', last step, f's error, mean energy)`.
pub(super) fn secant<F>(
    mut f: F,
    mut xa: f64,
    mut xb: f64,
) -> Result<(f64, f64, f64, f64, f64), SolverError>
where
    F: FnMut(f64) -> Result<(f64, f64, f64), SolverError>,
{
    let (mut fa, _, _) = f(xa)?;
    let (mut fb, mut err, mut e) = f(xb)?;
    for _ in 0..30 {
        let slope = (fb - fa) / (xb - xa);
        if fb == 0.0 || !slope.is_finite() || slope == 0.0 {
            return Ok((xb, slope, (xb - xa).abs(), err, e));
        }
        let xn = xb - fb / slope;
        let (fnew, errn, en) = f(xn)?;
        let step = (xn - xb).abs();
        (xa, fa, xb, fb, err, e) = (xb, fb, xn, fnew, errn, en);
        if step < 1e-12 {
            return Ok((xn, slope, step, err, e));
        }
    }
    Err(SolverError::InvalidInput(
        "the secant iteration did not converge in 30 steps".into(),
    ))
}

/// Solve `E_a = E_b` near `x0` (see the module docs): a secant iteration with the
/// lifted-off states at the trace's levels `N/4, N/2, N`, then, from its root, the same at
/// `N/2, N, 2N` (first step with the coarse slope). Returns `(L̄_cr, error, energy)`.
pub(super) fn enclosed_crossing(
    eta_a: u32,
    eta_b: u32,
    x0: f64,
    tracks: &mut [Option<Levels>; 2],
) -> Result<(f64, f64, f64), SolverError> {
    let f = |x: f64, tr: &mut [Option<Levels>; 2]| -> Result<(f64, f64, f64), SolverError> {
        let (ea, da) = branch_energy(eta_a, x, &mut tr[0])?;
        let (eb, db) = branch_energy(eta_b, x, &mut tr[1])?;
        Ok((ea - eb, da + db, 0.5 * (ea + eb)))
    };
    let (xc, slope, _, _, _) = secant(|x| f(x, tracks), x0, x0 - 1e-3)?;
    let sopts = EnclosedOptions::default();
    let mut fine: [Option<Levels>; 2] = [None, None];
    for k in 0..2 {
        if let Some(t) = &tracks[k] {
            // Bring the track to the coarse root first, then double its cells.
            let at = t.step_to(xc, &sopts)?;
            fine[k] = Some(at.refine(&sopts)?);
        }
    }
    let (fc, _, _) = f(xc, &mut fine)?;
    let x1 = if fc == 0.0 {
        xc - 1e-9
    } else {
        xc - fc / slope
    };
    let (x, slope, step, err, e) = secant(|x| f(x, &mut fine), xc, x1)?;
    Ok((x, err / slope.abs().max(1e-300) + step, e))
}

/// The lowest branch at `lbar`: the branch the last critical length at or below `lbar`
/// hands over to (the first one's `from` branch below it).
pub(super) fn lowest_branch(critical: &[EnclosedCritical], lbar: f64) -> Option<u32> {
    let k = critical.partition_point(|c| c.critical.lbar_cr <= lbar + 1e-12);
    if k > 0 {
        Some(critical[k - 1].critical.to_branch)
    } else {
        critical.first().map(|c| c.critical.from_branch)
    }
}

/// Energy of `branch` at `lbar` interpolated linearly between its samples.
pub(super) fn interpolated(points: &[EnclosedPoint], branch: u32, lbar: f64) -> Option<f64> {
    let pts: Vec<&EnclosedPoint> = points.iter().filter(|p| p.branch == branch).collect();
    let k = pts.partition_point(|p| p.lbar < lbar);
    if k == 0 || k == pts.len() {
        return pts
            .iter()
            .find(|p| (p.lbar - lbar).abs() < 1e-12)
            .map(|p| p.energy);
    }
    let (a, b) = (pts[k - 1], pts[k]);
    let t = (lbar - a.lbar) / (b.lbar - a.lbar);
    Some(a.energy + t * (b.energy - a.energy))
}

/// Lowest flags and labels; a warning where a sampled state lies below the lowest branch
/// by more than the errors (an exchange the list does not have).
pub(super) fn label(
    points: &mut [EnclosedPoint],
    critical: &[EnclosedCritical],
    warnings: &mut Vec<String>,
) {
    let snapshot = points.to_vec();
    for p in points.iter_mut() {
        let lowest = match lowest_branch(critical, p.lbar) {
            Some(b) => b == p.branch,
            None => snapshot
                .iter()
                .filter(|q| q.branch != p.branch)
                .all(|q| interpolated(&snapshot, q.branch, p.lbar).is_none_or(|e| p.energy <= e)),
        };
        p.lowest = lowest;
        p.label = match (p.index, lowest) {
            (0, true) => Label::Stable,
            (0, false) => Label::Metastable,
            _ => Label::Unstable,
        };
    }
    for p in points.iter() {
        // Linear interpolation between samples errs by ~E''h²/8; skip the neighbourhood
        // of the located critical lengths and allow 1e-3.
        if p.lowest
            || critical
                .iter()
                .any(|c| (c.critical.lbar_cr - p.lbar).abs() < 0.05)
        {
            continue;
        }
        if let Some(b) = lowest_branch(critical, p.lbar) {
            if let Some(e) = interpolated(&snapshot, b, p.lbar) {
                if p.energy < e - 1e-3 {
                    warnings.push(format!(
                        "branch {} at lbar = {:.4} (E = {:.8}) lies below the lowest branch {} (E = {:.8}): an exchange not in the surface list",
                        p.branch, p.lbar, p.energy, b, e
                    ));
                }
            }
        }
    }
}
