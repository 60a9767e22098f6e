//! Which branch a solved loop is on, read from the state itself.
//!
//! The paper's branches are told apart by the number `η` of periods of the geodesic
//! curvature `κ_g(s)` along the loop (Sec. 4.3: `κ_g = −2ck cn(cs, k)` with `η` periods of
//! `cn` per loop length, Eq. (49), so `κ_g` changes sign `2η` times). A starting shape (a
//! `--from` file, a resampled state) carries no branch label, and Newton may converge to a
//! state of another branch, so every returned state is identified here rather than trusted to
//! be on the branch that was asked for.
//!
//! **The signal** is the bending moment about the sphere's normal, `M = D κ_g`
//! (Eq. (41): `κ_g = 𝓜·n/D`). For a uniform rod it is `κ_g` times a constant. For a
//! two-segment rod it is continuous across the stiffness steps and carries the pattern of
//! the forces along the whole loop, while `κ_g = M/D` is magnified `D0/D1` times in the soft
//! segment, whose bumps would otherwise outnumber or outweigh the loop's periods (on
//! `D1/D0 = 0.1` the dominant Fourier harmonic of `κ_g` differs from the branch each state of
//! the diagram is traced on for 35 of its 199 states, and the sign changes of `κ_g` for 67;
//! the count below, on `M`, for none). An
//! enclosed state's signal is the moment of its central projection onto the sphere
//! ([`enclosed_signal`]).
//!
//! **The count** is the number of sign changes of `M − mean(M)` around the loop, halved,
//! counted with hysteresis: a change counts when the deviation crosses from below `−h` to
//! above `+h` or back. Two levels are used, and they must agree:
//!
//! * `h` = [`NOISE_FACTOR`] times the state's own noise level: the largest difference between
//!   a sample and the cubic through its two neighbours on either side (the discretisation's
//!   grid-scale error; a smooth signal sampled at the model's resolution leaves `O(h⁴ M⁗)`
//!   there). Oscillations below it are not resolved by the state and do not count;
//! * `h` = a tenth of the amplitude `max |M − mean|` (or the first level, if larger): small
//!   ripples on top of the loop's pattern do not count.
//!
//! Where the two counts differ, or the amplitude does not clear the noise level, the pattern
//! is not the one of a branch and the state is **not named** (an error saying which): near a
//! great circle the oscillation may sink into the discretisation noise, and on a very soft
//! segment (`D1/D0 = 10⁻³`) the stiff segment can be a geodesic arc to within that noise,
//! leaving a moment without periods. A traced family of such states keeps the branch of the
//! state it was continued from (its continuation history); `solve`, which has no history,
//! refuses such a state for a requested branch rather than reporting it under that branch.
//!
//! The dominant Fourier harmonic of the signal (the `k ≥ 1` maximising
//! `|∮ M e^{−2πiks/L} ds|`) is kept as a diagnostic ([`Periods::harmonic`]): for the exact
//! loops it is `η` (only odd multiples of `η` are present and the first is the largest).
//!
//! A third of the file is its unit tests (exact loops, the projection, the radial moment,
//! one-fold loops); the code is one job, the signal of a state and its count.

use std::f64::consts::PI;

use nalgebra::Vector3;

use crate::{Equilibrium, SolverError};

/// Multiple of a state's grid-scale noise level below which sign changes of its signal do
/// not count (see the module docs). The noise level is a maximum over the loop, and the
/// factor keeps a deviation that merely touches it from counting.
pub const NOISE_FACTOR: f64 = 4.0;

/// Fraction of the amplitude of the second hysteresis level (see the module docs).
pub const RIPPLE_FRACTION: f64 = 0.1;

/// The periods found along a loop.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Periods {
    /// Number of periods `η`: half the sign changes of the signal about its mean, the same at
    /// both hysteresis levels.
    pub eta: u32,
    /// The dominant Fourier harmonic of the signal (a diagnostic).
    pub harmonic: u32,
    /// Amplitude of the dominant harmonic divided by the next largest one (≥ 1).
    pub dominance: f64,
    /// Amplitude `max |signal − mean|` divided by the grid-scale noise level (large when the
    /// pattern is resolved).
    pub resolution: f64,
}

impl Periods {
    /// Whether the dominant Fourier harmonic agrees with the count.
    pub fn consistent(&self) -> bool {
        self.harmonic == self.eta
    }
}

/// Sign changes of `dev` around the closed loop with hysteresis `h` (`None`: no sample
/// deviates by more than `h`).
fn sign_changes(dev: &[f64], h: f64) -> Option<u32> {
    let n = dev.len();
    let start = dev.iter().position(|v| v.abs() > h)?;
    let mut positive = dev[start] > 0.0;
    let mut changes = 0u32;
    for i in 1..=n {
        let v = dev[(start + i) % n];
        if positive && v < -h {
            positive = false;
            changes += 1;
        } else if !positive && v > h {
            positive = true;
            changes += 1;
        }
    }
    Some(changes)
}

/// Grid-scale noise level of a periodic signal: the largest `|v_j − p_j(s_j)|` with `p_j` the
/// cubic through the samples `j − 2, j − 1, j + 1, j + 2`.
fn noise_level(s: &[f64], v: &[f64], length: f64) -> f64 {
    let n = s.len();
    let mut worst = 0.0f64;
    for j in 0..n {
        let mut xs = [0.0; 4];
        let mut ys = [0.0; 4];
        for (k, o) in [-2isize, -1, 1, 2].into_iter().enumerate() {
            let i = (j as isize + o).rem_euclid(n as isize) as usize;
            let wrap = if j as isize + o >= n as isize {
                length
            } else if j as isize + o < 0 {
                -length
            } else {
                0.0
            };
            xs[k] = s[i] - s[j] + wrap;
            ys[k] = v[i];
        }
        let mut p = 0.0;
        for a in 0..4 {
            let mut l = ys[a];
            for b in 0..4 {
                if b != a {
                    l *= xs[b] / (xs[b] - xs[a]);
                }
            }
            p += l;
        }
        worst = worst.max((v[j] - p).abs());
    }
    worst
}

/// Count the periods of a signal (`κ_g`, or the moment `D κ_g`) from samples `signal[j]`
/// at arclengths `s[j]` (strictly increasing, in `[0, length)`, the loop being closed: the
/// sample after the last is the first, at `s[0] + length`); see the module docs.
///
/// Errors ([`SolverError::InvalidInput`]): fewer than 8 samples, mismatched lengths,
/// non-finite values, `s` not increasing within one period, a constant signal (a circle,
/// which has no periods), an oscillation not above the noise level, or counts that differ
/// between the two hysteresis levels.
pub fn identify_periods(s: &[f64], signal: &[f64], length: f64) -> Result<Periods, SolverError> {
    let n = s.len();
    let bad = |m: String| Err(SolverError::InvalidInput(m));
    if n != signal.len() {
        return bad(format!(
            "identify_periods: {n} arclengths but {} curvature samples",
            signal.len()
        ));
    }
    if n < 8 {
        return bad(format!(
            "identify_periods needs at least 8 samples (got {n})"
        ));
    }
    if !(length.is_finite() && length > 0.0) {
        return bad(format!(
            "identify_periods: loop length {length} is not positive"
        ));
    }
    if s.iter().chain(signal).any(|v| !v.is_finite()) {
        return bad("identify_periods: a sample is not finite".into());
    }
    if s.windows(2).any(|w| w[1] <= w[0]) || s[n - 1] - s[0] >= length {
        return bad("identify_periods: arclengths must increase within one loop length".into());
    }
    // Trapezoidal weights of the closed loop (exact for trigonometric polynomials of low
    // degree on a uniform grid; second order on a graded one).
    let gap = |j: usize| {
        if j + 1 < n {
            s[j + 1] - s[j]
        } else {
            s[0] + length - s[n - 1]
        }
    };
    let w: Vec<f64> = (0..n)
        .map(|j| 0.5 * (gap(j) + gap((j + n - 1) % n)))
        .collect();
    let mean = signal.iter().zip(&w).map(|(k, w)| k * w).sum::<f64>() / length;
    let dev: Vec<f64> = signal.iter().map(|k| k - mean).collect();
    let amplitude = dev.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let scale = signal
        .iter()
        .fold(0.0f64, |m, v| m.max(v.abs()))
        .max(1.0 / length);
    if amplitude <= 1e-9 * scale {
        return bad(format!(
            "the curvature pattern is constant along the loop (a circle; relative variation \
             {:.1e}): it has no periods",
            amplitude / scale
        ));
    }
    let noise = noise_level(s, &dev, length);
    let h_noise = (NOISE_FACTOR * noise).max(1e-12 * scale);
    let resolution = amplitude / noise.max(1e-300);
    let (Some(fine), Some(coarse)) = (
        sign_changes(&dev, h_noise),
        sign_changes(&dev, h_noise.max(RIPPLE_FRACTION * amplitude)),
    ) else {
        return bad(format!(
            "the curvature pattern's amplitude {amplitude:.2e} does not clear {NOISE_FACTOR} \
             times the state's grid-scale noise {noise:.2e}: its periods are not resolved"
        ));
    };
    if coarse == 0 {
        return bad(format!(
            "the curvature pattern leaves its mean by more than a tenth of its amplitude \
             ({amplitude:.2e}) on one side only: it has no periods"
        ));
    }
    if fine != coarse {
        return bad(format!(
            "the curvature pattern changes sign {fine} times above {NOISE_FACTOR} times the \
             state's grid-scale noise ({noise:.2e}) but {coarse} times above a tenth of its \
             amplitude ({amplitude:.2e}): its periods are not those of one branch"
        ));
    }
    // Harmonics up to a quarter of the samples (higher ones are not resolved).
    let k_max = (n / 4).max(1);
    // One pass over the samples, the harmonics of each by angle addition.
    let (mut re, mut im) = (vec![0.0; k_max], vec![0.0; k_max]);
    for j in 0..n {
        let wd = w[j] * dev[j];
        crate::periodic::harmonics(2.0 * PI * s[j] / length, k_max, |k, co, si| {
            re[k] += wd * co;
            im[k] += wd * si;
        });
    }
    let amps: Vec<f64> = re.iter().zip(&im).map(|(r, i)| r.hypot(*i)).collect();
    let (best, &a_best) = amps
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))
        .expect("k_max >= 1");
    let second = amps
        .iter()
        .enumerate()
        .filter(|(i, _)| *i != best)
        .map(|(_, a)| *a)
        .fold(0.0f64, f64::max);
    let dominance = if second > 0.0 {
        a_best / second
    } else {
        f64::INFINITY
    };
    Ok(Periods {
        eta: coarse / 2,
        harmonic: (best + 1) as u32,
        dominance,
        resolution,
    })
}

/// The periods of a solved surface loop: of its bending moment `D κ_g` at the cell
/// boundaries ([`Equilibrium::profile`]).
pub fn identify_equilibrium(eq: &Equilibrium) -> Result<Periods, SolverError> {
    identify_profile(&eq.profile(), eq.length())
}

/// The periods of a written surface profile: of its bending moment `D κ_g`.
pub fn identify_profile(
    profile: &[crate::solve::ProfilePoint],
    length: f64,
) -> Result<Periods, SolverError> {
    let s: Vec<f64> = profile.iter().map(|p| p.s).collect();
    let moment: Vec<f64> = profile.iter().map(|p| p.d * p.kappa_g).collect();
    identify_periods(&s, &moment, length)
}

/// Geodesic curvature of the central projection `ρ = R r/|r|` of a space curve onto the
/// sphere of radius `R` about the origin, at a point `r` with unit tangent `t` and curvature
/// vector `κ = t'`: `κ_g = det(r, t, κ) / (R (1 − (r̂·t)²)^{3/2})` (from `ρ' ∝ t − (r̂·t) r̂`
/// and `det(ρ, ρ', ρ'') = det(r, t, κ)/|r|³`; the terms along `r` drop out). On the sphere
/// (`|r| = R`, `t ⊥ r`) it is the loop's own geodesic curvature; off it, the projection's.
/// `None` where the projection is not regular ([`PROJECTION_REGULARITY`]).
pub fn projected_geodesic_curvature(
    r: &Vector3<f64>,
    t: &Vector3<f64>,
    kappa: &Vector3<f64>,
    radius: f64,
) -> Option<f64> {
    let q = r.norm();
    // NaN compares false: a non-finite position is not regular either.
    if q.is_nan() || q < PROJECTION_REGULARITY * radius {
        return None;
    }
    let along = r.dot(t) / (q * t.norm());
    let sin2 = 1.0 - along * along;
    if sin2.is_nan() || sin2 < PROJECTION_REGULARITY * PROJECTION_REGULARITY {
        return None;
    }
    let v = r.dot(&t.cross(kappa)) / (radius * sin2.powf(1.5));
    v.is_finite().then_some(v)
}

/// Largest geodesic curvature of the central projection, relative to the largest `D |κ|`,
/// of a loop that counts as lying in a plane through the centre: far below the out-of-plane
/// pattern of a branch next to the great circle it collapses onto (1e-3 relative within
/// `5·10⁻⁵` of the collapse length on `D1/D0 = 0.1`), far above the out-of-plane round-off
/// of a planar state (1e-12–1e-9 on the diagram of the two-segment enclosed scene).
pub const PLANAR: f64 = 1e-6;

/// Where the central projection of an enclosed loop counts as regular: every point at least
/// this fraction of `R` from the centre, and its tangent at least `asin` of this from the
/// radial direction (the projection's speed `|ρ'| = R sin∠(t, r)/|r|` stays at least a
/// quarter of the loop's own at the wall).
pub const PROJECTION_REGULARITY: f64 = 0.25;

/// The signal whose periods name the branch of an enclosed state, at the Gauss points of its
/// cells (`(s, signal)`), and whether it comes from the central projection: the stiffness
/// `D` times a curvature, as on the surface.
///
/// Where the central projection of the loop is regular ([`PROJECTION_REGULARITY`]), the
/// curvature is the projection's geodesic curvature ([`projected_geodesic_curvature`]): on the
/// wall the loop's own `κ_g`, so an attached state counts as on the surface, and a state
/// that lifts off keeps the count of the surface loop it came from. It does not depend on
/// the rotation-minimising frame, which off the wall turns about the tangent by the torsion
/// picked up along the loop (near a great circle, where `κ_g` is small, that turn would
/// dominate the components `(κ1, κ2)` and their count).
///
/// Otherwise (a loop through the middle of the ball, or running radially) the signal is the
/// radial component of the bending moment weighted by `sin²∠(t, r)`,
/// `D det(r̂, t, κ) sin²∠(t, r)` (`radial_moment`). `M·r̂ = D det(r̂, t, κ)` has the sign of
/// the projection's geodesic curvature wherever that is defined
/// (`D κ_g = M·r̂ |r|/(R sin³∠(t, r))`), equals `D κ_g` on the wall, and stays bounded where
/// the projection is not regular: `M·r̂ = sin∠(t, r) M·n̂` (`M ⊥ t`; `n̂` the direction of the
/// part of `r` normal to `t`). Where the loop runs nearly radially `n̂` turns over and so may
/// the sign; the weight keeps such stretches below the tenth of the amplitude that counts
/// (without it, a state of the paper's two-segment rod at `L̄ = 1.164`, `0.08 R` from the
/// centre, counts 2 where its family, traced from states whose projection is regular, has 1).
/// A figure-eight lifted far off the wall (to within `0.06 R` of the centre on random seed 21
/// of `tests/random_enclosed.rs`) keeps the count of the surface loop it came from. Where that
/// moment vanishes too (a loop in a plane through the centre, whose moment is normal to the
/// plane), the curvature vector `(κ1, κ2)` in the rotation-minimising frame projected on its
/// principal axis (the direction of largest variance about its mean): a planar loop's signed
/// curvature.
pub fn enclosed_signal(
    state: &crate::enclosed::EnclosedState,
) -> Result<(Vec<f64>, Vec<f64>, bool), SolverError> {
    signal_at(state, &gauss_points(state)?)
}

/// [`enclosed_signal`] from the state's [`gauss_points`].
fn signal_at(
    state: &crate::enclosed::EnclosedState,
    points: &[GaussPoint],
) -> Result<(Vec<f64>, Vec<f64>, bool), SolverError> {
    let m = &state.model;
    let n = m.cells();
    let z = &state.z;
    let mut s = Vec::with_capacity(2 * n);
    let mut projected = Vec::with_capacity(2 * n);
    let mut regular = true;
    let mut scale = 0.0f64;
    for (g, p) in points.iter().enumerate() {
        let sigma = m.gauss_sigma(g);
        s.push(sigma * m.length());
        scale = scale.max(m.stiffness().eval(sigma).d * p.kappa.norm());
        match projected_geodesic_curvature(&p.r, &p.t, &p.kappa, m.radius()) {
            Some(v) if regular => projected.push(m.stiffness().eval(sigma).d * v),
            _ => regular = false,
        }
    }
    if regular {
        let spread = spread_about_mean(&projected);
        if spread <= PLANAR * scale {
            return Err(SolverError::InvalidInput(format!(
                "the loop lies in a plane through the centre of the ball (the geodesic \
                 curvature of its central projection is {spread:.1e} of its curvature): it \
                 projects onto a great circle, whose curvature has no periods to name a branch"
            )));
        }
        return Ok((s, projected, true));
    }
    let radial: Vec<f64> = points
        .iter()
        .enumerate()
        .map(|(g, p)| m.stiffness().eval(m.gauss_sigma(g)).d * radial_moment(p))
        .collect();
    let spread = spread_about_mean(&radial);
    if spread.is_finite() && spread > PLANAR * scale {
        return Ok((s, radial, false));
    }
    let w: Vec<f64> = (0..2 * n).map(|g| m.cell_length(g / 2)).collect();
    let total: f64 = w.iter().sum();
    let k = |g: usize| (z[2 * g], z[2 * g + 1]);
    let (mut m1, mut m2) = (0.0, 0.0);
    for (g, wg) in w.iter().enumerate() {
        m1 += wg * k(g).0 / total;
        m2 += wg * k(g).1 / total;
    }
    let (mut a, mut b, mut c) = (0.0, 0.0, 0.0);
    for (g, wg) in w.iter().enumerate() {
        let (u, v) = (k(g).0 - m1, k(g).1 - m2);
        a += wg * u * u;
        b += wg * u * v;
        c += wg * v * v;
    }
    // Principal axis of [[a, b], [b, c]].
    let theta = 0.5 * (2.0 * b).atan2(a - c);
    let (e1, e2) = (theta.cos(), theta.sin());
    let signal = (0..2 * n)
        .map(|g| {
            let d = m.stiffness().eval(m.gauss_sigma(g)).d;
            d * ((k(g).0 - m1) * e1 + (k(g).1 - m2) * e2)
        })
        .collect();
    Ok((s, signal, false))
}

/// `max |v − mean(v)|` (the mean unweighted): how far a signal leaves its mean.
fn spread_about_mean(v: &[f64]) -> f64 {
    let mean = v.iter().sum::<f64>() / v.len() as f64;
    v.iter().fold(0.0f64, |a, x| a.max((x - mean).abs()))
}

/// `det(r̂, t, κ) sin²∠(t, r)` at a Gauss point: the radial component of `t × κ` (the bending
/// moment over `D`), weighted down where the loop runs radially; 0 at the centre, where `r̂`
/// is not defined.
fn radial_moment(p: &GaussPoint) -> f64 {
    let q = p.r.norm();
    if q > 0.0 {
        let sin2 = p.r.cross(&p.t).norm_squared() / (q * q * p.t.norm_squared());
        sin2 * p.r.dot(&p.t.cross(&p.kappa)) / q
    } else {
        0.0
    }
}

/// Position, unit tangent and curvature vector of an enclosed state at the Gauss points of
/// its cells, in order along the loop.
struct GaussPoint {
    /// The point's share of the length (half its cell).
    ds: f64,
    r: Vector3<f64>,
    t: Vector3<f64>,
    kappa: Vector3<f64>,
}

fn gauss_points(state: &crate::enclosed::EnclosedState) -> Result<Vec<GaussPoint>, SolverError> {
    let m = &state.model;
    let z = &state.z;
    let x = m.transforms(z)?;
    let r0 = m.start_point(z);
    let col = |g: &nalgebra::Matrix4<f64>, c: usize| Vector3::new(g[(0, c)], g[(1, c)], g[(2, c)]);
    let mut out = Vec::with_capacity(2 * m.cells());
    for c in 0..m.cells() {
        let cell = [z[4 * c], z[4 * c + 1], z[4 * c + 2], z[4 * c + 3]];
        for (i, theta) in crate::model::GAUSS_OFFSETS.into_iter().enumerate() {
            let g = x[c] * crate::enclosed::jet::cell_exp_part(m.cell_length(c), cell, theta);
            out.push(GaussPoint {
                ds: 0.5 * m.cell_length(c),
                r: r0 + col(&g, 3),
                t: col(&g, 0),
                kappa: col(&g, 1) * cell[2 * i] + col(&g, 2) * cell[2 * i + 1],
            });
        }
    }
    Ok(out)
}

/// Smallest `|A|/(L²/4π)` (the area vector `A = ½∮ r × t ds` against the circle's) of a loop
/// that `turns_once` can call one-fold: a symmetric figure-eight's lobes cancel (`0`), a
/// circle gives `1`; below this the plane of `A` is not defined well enough to project on.
pub const ONE_FOLD_AREA: f64 = 0.1;

/// Smallest length of the projected unit tangent for which `turns_once` counts the turning
/// of the projection: below it the projection has (nearly) a cusp and its turning number is
/// not defined.
pub const ONE_FOLD_TANGENT: f64 = 0.1;

/// Whether an enclosed loop is one-fold: its projection onto the plane normal to its area
/// vector `A = ½∮ r × t ds` is regular and its tangent turns once around (the turning number
/// of a figure-eight's projection is 0). `None` where that is not decided: `|A|` below
/// [`ONE_FOLD_AREA`] of the circle's, or a projected tangent shorter than
/// [`ONE_FOLD_TANGENT`].
fn turns_once(points: &[GaussPoint], length: f64) -> Option<bool> {
    let n = points.len();
    let mut area = Vector3::zeros();
    for p in points {
        area += 0.5 * p.r.cross(&p.t) * p.ds;
    }
    if area.norm() < ONE_FOLD_AREA * length * length / (4.0 * PI) {
        return None;
    }
    let normal = area.normalize();
    let e1 = if normal.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let e1 = (e1 - normal * normal.dot(&e1)).normalize();
    let e2 = normal.cross(&e1);
    let mut angles = Vec::with_capacity(n);
    for p in points {
        let u = p.t - normal * normal.dot(&p.t);
        if u.norm() < ONE_FOLD_TANGENT {
            return None;
        }
        angles.push(u.dot(&e2).atan2(u.dot(&e1)));
    }
    let turn: f64 = (0..n)
        .map(|i| {
            let d = angles[(i + 1) % n] - angles[i];
            (d + PI).rem_euclid(2.0 * PI) - PI
        })
        .sum();
    Some((turn / (2.0 * PI)).round().abs() == 1.0)
}

/// The periods of an enclosed state's [`enclosed_signal`]: its branch `η`.
///
/// A loop shorter than the great circle (`L < 2πR`) whose moment counts `η = 1` but which
/// `turns_once` is the circle's family, branch 0, and is named `η = 0`: a non-uniform rod's
/// one-fold loop bends more where it is softer, so its moment varies once around the loop
/// about its mean as a figure-eight's does, but only the figure-eight crosses itself in its
/// plane (turning number 0). Without a self-contact in the model, a figure-eight that unwinds
/// through its crossing becomes that loop.
pub fn identify_enclosed(state: &crate::enclosed::EnclosedState) -> Result<Periods, SolverError> {
    let points = gauss_points(state)?;
    let (s, signal, _) = signal_at(state, &points)?;
    let length = state.model.length();
    let periods = identify_periods(&s, &signal, length)?;
    if periods.eta == 1
        && length < 2.0 * PI * state.model.radius()
        && turns_once(&points, length) == Some(true)
    {
        return Ok(Periods { eta: 0, ..periods });
    }
    Ok(periods)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The exact loops of the paper's branches η = 1..5 (independent elliptic-function
    /// solutions of the exact layer) are identified as η, on a uniform and a graded grid.
    #[test]
    fn exact_loops_are_identified() {
        for (eta, lbar) in [
            (1u32, 1.5),
            (1, 0.6),
            (2, 1.2),
            (2, 2.9),
            (3, 2.5),
            (4, 3.5),
            (5, 4.2),
        ] {
            let lp = rodloop_exact::paper_branch_loop(eta, lbar).unwrap();
            let pts = lp.sample(240).unwrap();
            let length = 2.0 * PI * lbar;
            let s: Vec<f64> = pts.iter().map(|p| p.s).collect();
            let kg: Vec<f64> = pts.iter().map(|p| p.kappa_g).collect();
            let p = identify_periods(&s, &kg, length).unwrap();
            assert_eq!(p.eta, eta, "uniform grid, eta {eta} at {lbar}: {p:?}");
            assert!(p.consistent(), "{p:?}");
            // Graded grid: s_j = L (u + 0.05 sin 2πu), u = j/n (monotone), κ_g there.
            let n = 300;
            let sg: Vec<f64> = (0..n)
                .map(|j| {
                    let u = j as f64 / n as f64;
                    length * (u + 0.05 * (2.0 * PI * u).sin())
                })
                .collect();
            let kgg: Vec<f64> = sg.iter().map(|&x| lp.point(x).unwrap().kappa_g).collect();
            let p = identify_periods(&sg, &kgg, length).unwrap();
            assert_eq!(p.eta, eta, "graded grid, eta {eta} at {lbar}: {p:?}");
            assert!(p.consistent(), "{p:?}");
        }
    }

    /// A sinusoid with 3 periods plus a smaller 7-period ripple and an offset is 3 periods.
    #[test]
    fn dominant_harmonic_and_sign_changes() {
        let n = 200;
        let length = 10.0;
        let s: Vec<f64> = (0..n).map(|j| length * j as f64 / n as f64).collect();
        let kg: Vec<f64> = s
            .iter()
            .map(|&x| {
                2.0 + (2.0 * PI * 3.0 * x / length + 0.4).sin()
                    + 0.2 * (2.0 * PI * 7.0 * x / length).cos()
            })
            .collect();
        let p = identify_periods(&s, &kg, length).unwrap();
        assert_eq!(p.eta, 3);
        assert_eq!(p.harmonic, 3);
        assert!((p.dominance - 5.0).abs() < 1e-9, "{}", p.dominance);
    }

    #[test]
    fn circles_and_bad_input_are_errors() {
        let s: Vec<f64> = (0..16).map(|j| j as f64).collect();
        assert!(identify_periods(&s, &[1.0; 16], 16.0).is_err());
        assert!(identify_periods(&s, &[1.0; 15], 16.0).is_err());
        let mut kg: Vec<f64> = s.iter().map(|x| x.sin()).collect();
        kg[3] = f64::NAN;
        assert!(identify_periods(&s, &kg, 16.0).is_err());
    }

    /// A small pattern of 2 periods on top of a large constant (a loop next to a great circle)
    /// with grid-scale noise: named 2 while the pattern clears the noise, refused (not named
    /// as whatever harmonic the noise happens to favour) when it sinks below it.
    #[test]
    fn identify_near_circle_with_noise() {
        let n = 384;
        let length = 2.0 * PI * 2.9972;
        let s: Vec<f64> = (0..n).map(|j| length * j as f64 / n as f64).collect();
        // Deterministic noise of amplitude 1e-4 at the grid scale (a fixed LCG).
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let noise: Vec<f64> = (0..n)
            .map(|_| {
                state = state
                    .wrapping_mul(6_364_136_223_846_793_005)
                    .wrapping_add(1_442_695_040_888_963_407);
                1e-4 * ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5)
            })
            .collect();
        let signal = |eps: f64| -> Vec<f64> {
            s.iter()
                .zip(&noise)
                .map(|(&x, e)| -1.0 + eps * (2.0 * PI * 2.0 * x / length).cos() + e)
                .collect()
        };
        for eps in [2e-2, 5e-3] {
            let p = identify_periods(&s, &signal(eps), length).unwrap();
            assert_eq!(p.eta, 2, "{eps}: {p:?}");
        }
        for eps in [1e-4, 2e-5] {
            let e = identify_periods(&s, &signal(eps), length).unwrap_err();
            assert!(e.to_string().contains("noise"), "{eps}: {e}");
        }
    }

    /// A pattern of 2 periods whose second lobe is a tenth of the first: the two hysteresis
    /// levels disagree (2 periods above the noise, 1 above a tenth of the amplitude), and the
    /// state is not named.
    #[test]
    fn identify_refuses_a_pattern_between_two_counts() {
        let n = 200;
        let length = 10.0;
        let s: Vec<f64> = (0..n).map(|j| length * j as f64 / n as f64).collect();
        let lobe = |x: f64, c: f64, a: f64| a * (-((x - c) / 0.8).powi(2)).exp();
        let v: Vec<f64> = s
            .iter()
            .map(|&x| {
                lobe(x, 2.5, 1.0) - lobe(x, 5.0, 0.3) + lobe(x, 7.5, 0.08)
                    - lobe(x, 0.0, 0.3)
                    - lobe(x, 10.0, 0.3)
            })
            .collect();
        let e = identify_periods(&s, &v, length).unwrap_err().to_string();
        assert!(e.contains("not those of one branch"), "{e}");
    }

    /// The central projection's geodesic curvature: a small circle of radius `a` at height
    /// `h` inside the unit ball projects onto the circle of geodesic curvature `h/a`; a
    /// circle in a plane through the centre onto a great circle (0); a radial tangent has no
    /// regular projection.
    #[test]
    fn identify_projection_of_circles() {
        let (a, h) = (0.6, 0.3);
        for phi in [0.0, 1.0, 2.5] {
            let (c, s) = (f64::cos(phi), f64::sin(phi));
            let r = Vector3::new(a * c, a * s, h);
            let t = Vector3::new(-s, c, 0.0);
            let k = Vector3::new(-c, -s, 0.0) / a;
            let kg = projected_geodesic_curvature(&r, &t, &k, 1.0).unwrap();
            assert!((kg.abs() - h / a).abs() < 1e-14, "{kg}");
            let flat = projected_geodesic_curvature(&Vector3::new(a * c, a * s, 0.0), &t, &k, 1.0);
            assert!(flat.unwrap().abs() < 1e-15);
        }
        let radial = Vector3::new(0.0, 0.0, 1.0);
        assert!(
            projected_geodesic_curvature(&(0.5 * radial), &radial, &Vector3::x(), 1.0).is_none()
        );
    }

    /// A circle of the paper's two-segment rod (Sec. 5, `D1/D0 = 0.5`) in a plane `0.3 R` from
    /// the centre: its moment `D κ` varies once about its mean (`η = 1` by the count), but it
    /// turns once around, so at `L̄ = 0.9` and 0.6 it is named the circle's family (`η = 0`);
    /// at `L̄ = 1.2`, longer than the great circle, it is not branch 0 and keeps `η = 1`. The
    /// closed figure-eight of a uniform rod with tangent angle `a sin 2πσ` (`J0(a) = 0`, turning
    /// number 0) keeps `η = 1`.
    #[test]
    fn a_one_fold_loop_with_a_varying_moment_is_the_circle_family() {
        use crate::enclosed::{EnclosedModel, EnclosedState, Gauge};
        use crate::stiffness::Stiffness;
        let state = |lbar: f64, stiffness: &Stiffness, kappa: &dyn Fn(f64) -> f64| {
            let gauge = Gauge {
                reference: vec![1.0; 256],
                slope: None,
                pin: Some([0.0, 0.3, lbar]),
            };
            let model = EnclosedModel::new(1.0, lbar, 64, stiffness, gauge).unwrap();
            let mut z = vec![0.0; model.dim()];
            for g in 0..128 {
                z[2 * g + 1] = kappa(model.gauss_sigma(g));
            }
            z[4 * 64 + 1] = 0.3;
            z[4 * 64 + 2] = lbar;
            EnclosedState {
                model,
                z,
                iterations: 0,
                residual: 0.0,
            }
        };
        let two_segment = Stiffness::paper_sec5(0.5);
        for (lbar, want) in [(0.9, 0), (0.6, 0), (1.2, 1)] {
            let st = state(lbar, &two_segment, &|_| -1.0 / lbar);
            let (s, signal, _) = enclosed_signal(&st).unwrap();
            let counted = identify_periods(&s, &signal, st.model.length()).unwrap();
            assert_eq!(counted.eta, 1, "lbar {lbar}: {counted:?}");
            let named = identify_enclosed(&st).unwrap();
            assert_eq!(named.eta, want, "lbar {lbar}: {named:?}");
        }
        // J0's first zero: the tangent angle a sin 2πσ closes the loop.
        let a = 2.404_825_557_695_773;
        let eight = state(0.9, &Stiffness::uniform(1.0), &|sigma| {
            -a * (2.0 * PI * sigma).cos() / 0.9
        });
        let points = gauss_points(&eight).unwrap();
        assert_ne!(turns_once(&points, eight.model.length()), Some(true));
        assert_eq!(identify_enclosed(&eight).unwrap().eta, 1);
    }

    /// The radial moment (over `D`) against the projection's geodesic curvature on random
    /// points, tangents and curvature vectors (`κ ⊥ t`): `radial_moment = κ_g R sin⁵θ/|r|`
    /// (`sinθ = |r̂ × t|`), so the two have one sign wherever the projection is regular; on
    /// the wall with `t ⊥ r` they are equal; and `|radial_moment| ≤ |κ|` everywhere, also where
    /// the projection is not regular (near the centre, or running radially).
    #[test]
    fn radial_moment_has_the_sign_of_the_projection_and_stays_bounded() {
        let mut seed = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let mut regular = 0;
        for _ in 0..2000 {
            let r = Vector3::new(next(), next(), next());
            let t = Vector3::new(next(), next(), next()).normalize();
            let k = Vector3::new(next(), next(), next()) * 3.0;
            let k = k - t * t.dot(&k);
            let p = GaussPoint {
                ds: 0.0,
                r,
                t,
                kappa: k,
            };
            let rm = radial_moment(&p);
            assert!(
                rm.abs() <= k.norm() * (1.0 + 1e-12),
                "{rm} against |κ| {}",
                k.norm()
            );
            if let Some(kg) = projected_geodesic_curvature(&r, &t, &k, 1.0) {
                regular += 1;
                let sin = r.normalize().cross(&t).norm();
                let want = kg * sin.powi(5) / r.norm();
                assert!(
                    (rm - want).abs() <= 1e-12 * (1.0 + want.abs()),
                    "{rm} against {want}"
                );
            }
        }
        // Both kinds of point are drawn (the bound is checked on the irregular ones too).
        assert!(regular > 0 && regular < 2000, "{regular} regular of 2000");
        // On the unit sphere with t ⊥ r: the loop's own geodesic curvature.
        for _ in 0..100 {
            let r = Vector3::new(next(), next(), next()).normalize();
            let t = r.cross(&Vector3::new(next(), next(), next())).normalize();
            let k = r.cross(&t) * next() - r * 1.0;
            let p = GaussPoint {
                ds: 0.0,
                r,
                t,
                kappa: k,
            };
            let kg = projected_geodesic_curvature(&r, &t, &k, 1.0).unwrap();
            assert!(
                (radial_moment(&p) - kg).abs() < 1e-12,
                "{} against {kg}",
                radial_moment(&p)
            );
        }
    }
}
