//! Starts of a non-uniform rod's enclosed states by continuation in the stiffness from the
//! uniform rod's loop: where the profile's features sit ([`profile_features`]), the shifts of
//! the uniform loop that put its bends on them ([`homotopy_shifts`]), and the states those
//! starts lead to ([`stiffness_homotopy_states`], [`stiffness_homotopy_starts`]).

use super::saddle::enclosed_periods;
use crate::enclosed::solve::{solve_enclosed, EnclosedOptions, EnclosedState};
use crate::enclosed::wall::IntoWall;
use crate::SolverError;
/// Features of a periodic signal sampled at `n` equal steps of `σ ∈ [0, 1)`: the `σ` of
/// its local extrema and of its sign changes (zeros), by parabolic and linear interpolation.
fn signal_features(f: &[f64]) -> Vec<f64> {
    let n = f.len();
    let h = 1.0 / n as f64;
    let scale = f.iter().fold(0.0f64, |a, b| a.max(b.abs()));
    if scale == 0.0 {
        return Vec::new();
    }
    let mut out = Vec::new();
    for i in 0..n {
        let (a, b, c) = (f[(i + n - 1) % n], f[i], f[(i + 1) % n]);
        // An extremum (strict on one side: plateaus of a sharp profile count once).
        if ((b > a && b >= c) || (b < a && b <= c)) && (b - a).abs() + (b - c).abs() > 1e-9 * scale
        {
            let den = a - 2.0 * b + c;
            let off = if den.abs() > 0.0 {
                (0.5 * (a - c) / den).clamp(-0.5, 0.5)
            } else {
                0.0
            };
            out.push(((i as f64 + off) * h).rem_euclid(1.0));
        }
        if b != 0.0 && c != 0.0 && (b > 0.0) != (c > 0.0) {
            out.push(((i as f64 + b / (b - c)) * h).rem_euclid(1.0));
        }
    }
    out
}

/// Where the stiffness profile's features sit, `σ = s/L`: the extrema of `D` (the middles
/// of the segments) and of `dD/dσ` (the transitions). Empty for a uniform rod.
pub fn profile_features(stiffness: &crate::Stiffness) -> Result<Vec<f64>, SolverError> {
    if stiffness.is_uniform() {
        return Ok(Vec::new());
    }
    let prof = stiffness.validate()?;
    const SAMPLES: usize = 4096;
    let v: Vec<_> = (0..SAMPLES)
        .map(|i| prof.eval(i as f64 / SAMPLES as f64))
        .collect();
    let d: Vec<f64> = v.iter().map(|p| p.d).collect();
    let d1: Vec<f64> = v.iter().map(|p| p.d1).collect();
    let mut out = signal_features(&d);
    // Only the extrema of D' (its zeros are the extrema of D, already in).
    let n = d1.len();
    let top = d1.iter().fold(0.0f64, |a, b| a.max(b.abs()));
    out.extend(signal_features(&d1).into_iter().filter(|&s| {
        let i = ((s * n as f64).round() as usize) % n;
        d1[i].abs() > 1e-3 * top
    }));
    Ok(out)
}

/// Shifts `φ` of the arclength origin of the uniform rod's loop of branch `eta` at `lbar`
/// (its curvature taken at `σ + φ`) that put a feature of the loop (an extremum or a zero of
/// `κ_g`) on a feature of the stiffness profile ([`profile_features`]), modulo the loop's
/// period `1/η`, in `[0, 1/η)`, without repeats (closer than `1e-3`). `[0]` for a uniform
/// rod. The starts of [`stiffness_homotopy_states`]: where a loop's soft and stiff parts
/// fall relative to its bends decides which state of the non-uniform rod it leads to.
pub fn homotopy_shifts(
    stiffness: &crate::Stiffness,
    eta: u32,
    lbar: f64,
) -> Result<Vec<f64>, SolverError> {
    let prof = profile_features(stiffness)?;
    if prof.is_empty() {
        return Ok(vec![0.0]);
    }
    let l = rodloop_exact::paper_branch_loop(eta, lbar)?;
    const SAMPLES: usize = 1024;
    let kg = (0..SAMPLES)
        .map(|i| Ok(l.point(i as f64 / SAMPLES as f64 * l.length())?.kappa_g))
        .collect::<Result<Vec<f64>, SolverError>>()?;
    let period = 1.0 / f64::from(eta.max(1));
    let mut shifts: Vec<f64> = Vec::new();
    for &a in &signal_features(&kg) {
        for &b in &prof {
            let phi = (a - b).rem_euclid(period);
            let near = |x: f64| {
                let d = (x - phi).rem_euclid(period);
                d.min(period - d) < 1e-3
            };
            if !shifts.iter().any(|&x| near(x)) {
                shifts.push(phi);
            }
        }
    }
    shifts.sort_by(f64::total_cmp);
    Ok(shifts)
}

/// Enclosed states of the non-uniform rod `stiffness` at `lbar` on `cells` cells reached by
/// continuation in the stiffness ([`crate::enclosed::continuation::continue_in_stiffness`]) from the
/// uniform rod's enclosed loop of branch `eta` (the exact surface loop, lifted off by the
/// semismooth Newton where it needs a pulling wall), one per shift of [`homotopy_shifts`]:
/// those of branch `eta` ([`enclosed_periods`]), lowest first, without repeats (energies
/// within `1e-9` relative). Where the uniform rod's loop is attached, its continuation may
/// still lift off along the path.
pub fn stiffness_homotopy_states(
    wall: impl IntoWall,
    lbar: f64,
    eta: u32,
    stiffness: &crate::Stiffness,
    cells: usize,
    opts: &EnclosedOptions,
) -> Result<Vec<EnclosedState>, SolverError> {
    Ok(
        stiffness_homotopy_starts(wall, lbar, eta, stiffness, cells, opts)?
            .into_iter()
            .map(|(_, s)| s)
            .collect(),
    )
}

/// [`stiffness_homotopy_states`] with the shift `φ` (fraction of the length) of the uniform
/// rod's loop each state comes from: the start a `solve` names. The shifts run one after
/// the other; a caller with a thread pool runs [`stiffness_path_from_shift`] on each of
/// [`homotopy_shifts`] itself and keeps [`distinct_lowest_first`] of the results, the same
/// states in the same order.
pub fn stiffness_homotopy_starts(
    wall: impl IntoWall,
    lbar: f64,
    eta: u32,
    stiffness: &crate::Stiffness,
    cells: usize,
    opts: &EnclosedOptions,
) -> Result<Vec<(f64, EnclosedState)>, SolverError> {
    let wall = wall.into_wall();
    let mut reached = Vec::new();
    for phi in homotopy_shifts(stiffness, eta, lbar)? {
        if let Some(s) = stiffness_path_from_shift(&wall, lbar, eta, stiffness, cells, opts, phi)? {
            reached.push((phi, s));
        }
    }
    Ok(distinct_lowest_first(reached))
}

/// The state of branch `eta` that the continuation in the stiffness reaches from the uniform
/// rod's enclosed loop shifted by `phi` (one start of [`stiffness_homotopy_starts`]): `None`
/// where a solve on the way fails or the state reached belongs to another branch
/// ([`enclosed_periods`]). The shifts are independent of each other.
pub fn stiffness_path_from_shift(
    wall: impl IntoWall,
    lbar: f64,
    eta: u32,
    stiffness: &crate::Stiffness,
    cells: usize,
    opts: &EnclosedOptions,
    phi: f64,
) -> Result<Option<EnclosedState>, SolverError> {
    let wall = wall.into_wall();
    let radius = wall.radius();
    let l = rodloop_exact::paper_branch_loop(eta, lbar)?;
    let uniform = crate::Stiffness::Uniform {
        d: stiffness.reference(),
    };
    let lmin = l.lambda_range().0;
    let len = l.length();
    let kg = |s: f64| {
        l.point((s + phi).rem_euclid(1.0) * len)
            .map_or(0.0, |p| p.kappa_g / radius)
    };
    let Ok((m, z0)) = crate::enclosed::solve::start_from_surface(&wall, lbar, cells, &uniform, kg)
    else {
        return Ok(None);
    };
    let start = match solve_enclosed(&m, z0.clone(), opts) {
        Ok(s) => s,
        Err(_) if lmin < 0.0 => {
            match crate::enclosed::solve::solve_by_pull_homotopy(&m, z0, lmin, opts) {
                Ok(s) => s,
                Err(_) => return Ok(None),
            }
        }
        Err(_) => return Ok(None),
    };
    let Ok(s) = crate::enclosed::continuation::continue_in_stiffness(&start, stiffness, opts)
    else {
        return Ok(None);
    };
    if enclosed_periods(&s).ok().map(|p| p.eta) != Some(eta) || !s.energy().is_finite() {
        return Ok(None);
    }
    Ok(Some(s))
}

/// The states of `reached` (in the order of their shifts) without repeats, a state dropped
/// where an earlier one has its energy within `1e-9` relative, lowest energy first (ties in
/// the order of their shifts).
pub fn distinct_lowest_first(reached: Vec<(f64, EnclosedState)>) -> Vec<(f64, EnclosedState)> {
    let mut out: Vec<(f64, EnclosedState)> = Vec::new();
    for (phi, s) in reached {
        let e = s.energy();
        if out
            .iter()
            .any(|(_, o)| (o.energy() - e).abs() <= 1e-9 * e.abs())
        {
            continue;
        }
        out.push((phi, s));
    }
    out.sort_by(|a, b| a.1.energy().total_cmp(&b.1.energy()));
    out
}
