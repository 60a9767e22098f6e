//! Verification of a state before it is reported: every surface state that `solve`, a
//! diagram, `phase`, `report` or `converge` writes goes through [`verify_state`].
//!
//! A converged Newton run proves only that the KKT residual is small. The checks here are
//! made on the state itself and on the representation that is written (`config.csv`:
//! the profile of [`Equilibrium::profile`] at the cell boundaries):
//!
//! * **closed**: the holonomy `H = X(L) X(0)ᵀ` of the frame is within
//!   [`MAX_HOLONOMY_ANGLE`] of the identity, and the written polyline closes: the chord from
//!   its last point back to its first is no longer than the arclength between them (a
//!   chord of a closed smooth curve never is), up to [`CHORD_SLACK`] of the arclength
//!   (the written points between the mesh nodes are interpolated) and
//!   [`POSITION_SLACK`]`·R`;
//! * **on the sphere**: every written point has `||r| − R| ≤ `[`POSITION_SLACK`]`·R`;
//! * **energy**: `E R/(π D0) = (R/π D0) ∮ ½ D κ² ds` recomputed from the written `s`, `κ`
//!   and `D` columns by the periodic trapezoidal rule equals the reported energy within
//!   the sum of: the reported error estimate; the error estimate of the recomputation
//!   itself ([`Claim::profile_error`]: the written `κ_g = 𝓜·n/D` (Eq. (41)) at the cell
//!   boundaries is a second `O(h⁴)` discretisation of the state, so its energy is compared
//!   with the same recomputation on the companion solve of half (or, for `high`, the main)
//!   resolution); the quadrature's error (`|T_h − T_2h|`, the rule on every point against
//!   every other point); and [`ENERGY_RELATIVE_SLACK`] of the energy. As `κ_g` is computed
//!   from the conserved moment, not copied from the unknowns, the check also fails when
//!   the state does not satisfy the equilibrium equations;
//! * **branch**: the number `η` of periods of the written bending moment `D κ_g`
//!   ([`crate::identify`]) is the requested one.
//!
//! # How the branch of a state is identified
//!
//! Always from the state: `η` is half the number of sign changes of the written moment
//! `D κ_g(s)` about its mean, counted with hysteresis at the state's own grid-scale noise
//! level and at a tenth of the amplitude, which must agree
//! ([`crate::identify::identify_periods`]). A state reached by continuation (in `L̄` or in
//! `D1/D0`) is counted again at its end point; where the count is not the requested one, or
//! the state's pattern names no branch (near a great circle, below the noise; on a very soft
//! segment, `D1/D0 ≪ 1`, where the stiff segment is a geodesic arc to within the noise), the
//! state is refused rather than reported under the branch the path started from. `solve`
//! then tries its next fallback, and says so if none passes.
//!
//! The file is over 600 lines with its tests (about 200): the checks above are one routine,
//! [`verify_state`], and its helpers.

use std::f64::consts::PI;

use crate::identify::{identify_enclosed, identify_profile};
use crate::solve::{Equilibrium, ProfilePoint};
use crate::SolverError;

/// Largest holonomy angle (radians) of a verified state. Newton stops at a KKT residual
/// norm of `1e-10` (which includes the closure residual `2 sin(θ/2)`), so a converged state
/// has `θ ≤ 1e-10`; the bound leaves three orders of magnitude for states converged to a
/// looser tolerance by continuation.
pub const MAX_HOLONOMY_ANGLE: f64 = 1e-7;

/// Slack (in units of `R`) of the position checks: the points are `R n` with `n` a row of a
/// rotation matrix, exact to round-off.
pub const POSITION_SLACK: f64 = 1e-9;

/// Relative slack of the chord check: the written points are interpolated between the
/// mesh nodes, so where the loop is nearly straight over its last written step the chord can
/// exceed the arclength by the interpolation error (measured 1e-3 relative on a state of
/// 80 cells sampled at 128 points, `D1/D0 = 0.1`, branch 2 at `L̄ = 1.312`). A loop that
/// does not close misses by many steps (0.5–2 R against steps of 0.06 R).
pub const CHORD_SLACK: f64 = 1e-2;

/// Relative slack of the energy check (round-off of the sums).
pub const ENERGY_RELATIVE_SLACK: f64 = 1e-9;

/// What a reported state claims to be.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Claim {
    /// Reported energy `E R/(π D0)`.
    pub energy: f64,
    /// Reported error estimate of `energy` (absolute).
    pub energy_error: f64,
    /// Estimated error of the energy recomputed from the written profile (the difference
    /// of that recomputation between the state and its companion solve; see
    /// [`verify_accurate`] and [`profile_energy`]).
    pub profile_error: f64,
    /// Requested number of periods `η` (`None`: any branch).
    pub eta: Option<u32>,
}

/// The measured quantities of a verified state.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Verification {
    /// Rotation angle of the holonomy (radians).
    pub holonomy_angle: f64,
    /// Chord from the last written point to the first, in units of `R`.
    pub closing_chord: f64,
    /// Arclength from the last written point to the end of the loop, in units of `R`.
    pub closing_arc: f64,
    /// Largest `||r| − R|/R` over the written points.
    pub radius_deviation: f64,
    /// Energy `E R/(π D0)` recomputed from the written profile.
    pub energy_from_profile: f64,
    /// Allowed `|energy_from_profile − claimed energy|`.
    pub energy_tolerance: f64,
    /// Number of periods of the written `κ_g` (0 where it has none and no branch was
    /// requested).
    pub eta: u32,
}

/// Verify a state and the profile written for it (see the module docs). `profile` is what
/// the caller writes (normally `eq.profile()`, dimensional in the model's `R` and `D`).
///
/// Errors: [`SolverError::Unverified`] naming the first check that fails, with its numbers.
pub fn verify_state(
    eq: &Equilibrium,
    profile: &[ProfilePoint],
    claim: &Claim,
) -> Result<Verification, SolverError> {
    let model = eq.model();
    let r = model.radius();
    let length = model.length();
    let d0 = model.stiffness().kind().reference();
    let fail = |m: String| Err(SolverError::Unverified(m));
    let angle = check_holonomy(eq)?;
    let n = profile.len();
    if n < 8 {
        return fail(format!(
            "the profile has {n} points (at least 8 are needed)"
        ));
    }
    if profile.iter().any(|p| {
        ![p.s, p.x, p.y, p.z, p.kappa, p.kappa_g, p.d]
            .iter()
            .all(|v| v.is_finite())
    }) {
        return fail("the profile has a value that is not finite".into());
    }
    let pos = |p: &ProfilePoint| nalgebra::Vector3::new(p.x, p.y, p.z);
    let radius_deviation = profile
        .iter()
        .map(|p| (pos(p).norm() - r).abs() / r)
        .fold(0.0, f64::max);
    if radius_deviation > POSITION_SLACK {
        return fail(format!(
            "a written point is off the sphere by {radius_deviation:.3e} R"
        ));
    }
    let closing_chord = (pos(&profile[n - 1]) - pos(&profile[0])).norm() / r;
    let closing_arc = (length + profile[0].s - profile[n - 1].s) / r;
    if !(closing_arc > 0.0 && closing_chord <= closing_arc * (1.0 + CHORD_SLACK) + POSITION_SLACK) {
        return fail(format!(
            "the written polyline does not close: its last point is {closing_chord:.3e} R from \
             the first, {closing_arc:.3e} R of arclength away"
        ));
    }
    let (fine, coarse) = profile_energy(profile, length, r, d0);
    let energy_tolerance = check_energy(claim, fine, coarse, 1.0)?;
    let eta = check_periods(profile, length, claim.eta)?;
    Ok(Verification {
        holonomy_angle: angle,
        closing_chord,
        closing_arc,
        radius_deviation,
        energy_from_profile: fine,
        energy_tolerance,
        eta,
    })
}

/// The branch check of written samples (see the module docs): the periods `η` of the moment
/// `D κ_g` of `profile` (a loop of `length`, [`identify_profile`]), which must be `want`
/// where a branch is requested. Without one, a state whose periods are not named counts 0.
///
/// Errors: [`SolverError::Unverified`] where the periods are not the requested ones or
/// cannot be counted for a requested branch.
pub fn check_periods(
    profile: &[ProfilePoint],
    length: f64,
    want: Option<u32>,
) -> Result<u32, SolverError> {
    let fail = |m: String| Err(SolverError::Unverified(m));
    let eta = match (identify_profile(profile, length), want) {
        (Ok(p), _) => p.eta,
        (Err(_), None) => 0,
        (Err(e), Some(_)) => {
            return fail(format!("its branch cannot be identified ({e})"));
        }
    };
    match want {
        Some(want) if eta != want => fail(format!(
            "its bending moment D κ_g has {eta} periods, not the requested {want}"
        )),
        _ => Ok(eta),
    }
}

/// The closure check of the state itself (see the module docs): the rotation angle of the
/// holonomy of `eq`'s curvature, at most [`MAX_HOLONOMY_ANGLE`] (the angle, not `vee(skew H)`,
/// which also vanishes at a half-turn).
///
/// Errors: [`SolverError::Unverified`] with the angle where the loop does not close; the
/// model's own errors where the holonomy cannot be built.
pub fn check_holonomy(eq: &Equilibrium) -> Result<f64, SolverError> {
    let h = eq.model().holonomy(eq.kappa())?;
    let skew = nalgebra::Vector3::new(
        h[(2, 1)] - h[(1, 2)],
        h[(0, 2)] - h[(2, 0)],
        h[(1, 0)] - h[(0, 1)],
    );
    let angle = (0.5 * skew.norm()).atan2(0.5 * (h.trace() - 1.0));
    if angle.is_nan() || angle > MAX_HOLONOMY_ANGLE {
        return Err(SolverError::Unverified(format!(
            "the loop does not close: its frame comes back turned by {angle:.3e} rad (at most \
             {MAX_HOLONOMY_ANGLE:e})"
        )));
    }
    Ok(angle)
}

/// The energy check of written samples (see the module docs): `fine`, the periodic
/// trapezoidal energy `E R/(π D0)` of the samples, and `coarse`, that of every other sample,
/// against `claim`; the tolerance is the claim's error estimates, `|fine − coarse|` (the
/// quadrature's own error) and [`ENERGY_RELATIVE_SLACK`] of the energy, and the check fails
/// where the gap exceeds `margin` times it ([`verify_state`] uses `margin = 1`; a caller that
/// checks the energy of the samples before building the rest of the profile uses a larger
/// one, so that round-off between the two computations of the same sums cannot decide).
///
/// Returns the tolerance. Errors: [`SolverError::Unverified`] naming the energies and the
/// allowed gap.
pub fn check_energy(
    claim: &Claim,
    fine: f64,
    coarse: f64,
    margin: f64,
) -> Result<f64, SolverError> {
    let energy_tolerance = claim.energy_error.abs()
        + claim.profile_error.abs()
        + (fine - coarse).abs()
        + ENERGY_RELATIVE_SLACK * claim.energy.abs().max(1.0);
    let gap = (fine - claim.energy).abs();
    if gap.is_nan() || gap > margin * energy_tolerance {
        return Err(SolverError::Unverified(format!(
            "the energy recomputed from the written points, {fine:.10}, differs from the reported \
             {:.10} by more than {:.1e}",
            claim.energy,
            margin * energy_tolerance
        )));
    }
    Ok(energy_tolerance)
}

/// Energy `E R/(π D0)` of a written profile (dimensional, of a loop of length `length` on a
/// sphere of radius `radius`, reference stiffness `d0`) by the periodic trapezoidal rule on
/// every point and on every other point: `(T_h, T_2h)`.
pub fn profile_energy(profile: &[ProfilePoint], length: f64, radius: f64, d0: f64) -> (f64, f64) {
    let s: Vec<f64> = profile.iter().map(|p| p.s).collect();
    let density: Vec<f64> = profile
        .iter()
        .map(|p| 0.5 * p.d * p.kappa * p.kappa)
        .collect();
    periodic_trapezoid(&s, &density, length, radius / (PI * d0))
}

/// The periodic trapezoidal rule of `density` sampled at arclengths `s` on a loop of
/// `length`, scaled by `scale`, on every point and on every other point: `(T_h, T_2h)`.
fn periodic_trapezoid(s: &[f64], density: &[f64], length: f64, scale: f64) -> (f64, f64) {
    let n = s.len();
    let trapezoid = |step: usize| {
        let idx: Vec<usize> = (0..n).step_by(step).collect();
        let m = idx.len();
        (0..m)
            .map(|j| {
                let (a, b) = (idx[j], idx[(j + 1) % m]);
                let ds = if j + 1 < m {
                    s[b] - s[a]
                } else {
                    length + s[b] - s[a]
                };
                0.5 * (density[a] + density[b]) * ds
            })
            .sum::<f64>()
            * scale
    };
    (trapezoid(1), trapezoid(2))
}

/// [`verify_state`] of an accurate solve ([`crate::AccurateEquilibrium`]) against its own
/// reported energy and error estimate, with the profile of its finest state.
///
/// The error estimate of the energy recomputed from the profile is the difference of that
/// recomputation between the state and its companion solve (`|P_N − P_{N/2}|`, which bounds
/// the error of the coarser one, hence of the finer one, for an `O(h⁴)` quantity).
pub fn verify_accurate(
    acc: &crate::AccurateEquilibrium,
    eta: Option<u32>,
) -> Result<Verification, SolverError> {
    let eq = &acc.equilibrium;
    let profile = eq.profile();
    let model = eq.model();
    let d0 = model.stiffness().kind().reference();
    let energy = |eq: &Equilibrium, p: &[ProfilePoint]| {
        profile_energy(p, eq.model().length(), eq.model().radius(), d0).0
    };
    let companion = &acc.companion;
    let profile_error = (energy(eq, &profile) - energy(companion, &companion.profile())).abs();
    verify_state(
        eq,
        &profile,
        &Claim {
            energy: acc.energy.total,
            energy_error: acc.energy_error,
            profile_error,
            eta,
        },
    )
}

/// One written point of an enclosed state (dimensional: the model's `R` and `D`): a row of
/// `config.csv` of an enclosed state. The file holds every node (cell boundary) and, between
/// them, the two Gauss points of each cell, where the model evaluates its energy.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EnclosedPoint {
    /// Arclength.
    pub s: f64,
    /// Position.
    pub r: [f64; 3],
    /// Curvature vector `(κ1, κ2)` in the rotation-minimising frame: the unknowns at a
    /// Gauss point; at a node the linear extrapolations of the two adjacent cells' Gauss
    /// values, averaged.
    pub kappa: (f64, f64),
    /// Bending stiffness.
    pub d: f64,
    /// `true` at a node (cell boundary), `false` at a Gauss point.
    pub node: bool,
    /// Quadrature weight of the point in the energy (a length): `h_c/2` at the two Gauss
    /// points of cell `c` (two-point Gauss quadrature, the model's rule), 0 at a node, so
    /// `E = Σ weight · ½ D |κ|²` is the model's energy.
    pub weight: f64,
}

/// `E R/(π D0)` of written points by their quadrature weights, `(R/π D0) Σ w ½ D |κ|²`:
/// the model's energy (Eq. (2) with two-point Gauss quadrature per cell) from the file.
pub fn weighted_energy(points: &[EnclosedPoint], radius: f64, d0: f64) -> f64 {
    points
        .iter()
        .map(|p| p.weight * 0.5 * p.d * (p.kappa.0 * p.kappa.0 + p.kappa.1 * p.kappa.1))
        .sum::<f64>()
        * radius
        / (PI * d0)
}

/// How far (units of `R`) the curve of a cell can reach outside the ball at its Gauss
/// points when its two nodes are inside it, from the cell's two Gauss rows `a`, `b`: with
/// `f(u) = |r(u)|²`, `f'' = 2(1 + r·κ) ≤ 2(1 + R κmax)`, so between nodes with `f ≤ R²`,
/// `f(u) ≤ R² + u(h − u)(1 + R κmax)`; at the Gauss points `u(h − u) = h²/6`, and
/// `|r| − R ≤ (f − R²)/(2R)`. `κmax` is the larger `|κ|` of the cell's curvature (linear
/// through the Gauss values) at its two ends; `h = 2 (weight)`.
pub fn between_nodes_bound(a: &EnclosedPoint, b: &EnclosedPoint, radius: f64) -> f64 {
    let [g1, g2] = crate::model::GAUSS_OFFSETS;
    let end = |u: f64| {
        let t = (u - g1) / (g2 - g1);
        let k1 = a.kappa.0 + t * (b.kappa.0 - a.kappa.0);
        let k2 = a.kappa.1 + t * (b.kappa.1 - a.kappa.1);
        (k1 * k1 + k2 * k2).sqrt()
    };
    let kmax = end(0.0).max(end(1.0));
    let h = 2.0 * a.weight;
    h * h * (1.0 + radius * kmax) / (12.0 * radius * radius)
}

/// The written points of an enclosed state ([`EnclosedPoint`]): per cell its start node and
/// its two Gauss points, in increasing arclength. A Gauss point's position follows the
/// cell's curve from the node before it ([`crate::enclosed::jet::cell_exp_part`]).
pub fn enclosed_profile(
    st: &crate::enclosed::EnclosedState,
) -> Result<Vec<EnclosedPoint>, SolverError> {
    let m = &st.model;
    let x = m.transforms(&st.z)?;
    let r0 = m.start_point(&st.z);
    let z = &st.z;
    let mut out = Vec::with_capacity(3 * m.cells());
    for (j, (sigma, p)) in st.nodes()?.into_iter().enumerate() {
        out.push(EnclosedPoint {
            s: sigma * m.length(),
            r: [p[0], p[1], p[2]],
            kappa: st.node_curvature(j),
            d: m.stiffness().eval(sigma).d,
            node: true,
            weight: 0.0,
        });
        let h = m.cell_length(j);
        let cell = [z[4 * j], z[4 * j + 1], z[4 * j + 2], z[4 * j + 3]];
        for (i, theta) in crate::model::GAUSS_OFFSETS.into_iter().enumerate() {
            let g = x[j] * crate::enclosed::jet::cell_exp_part(h, cell, theta);
            let gs = m.gauss_sigma(2 * j + i);
            out.push(EnclosedPoint {
                s: gs * m.length(),
                r: [r0[0] + g[(0, 3)], r0[1] + g[(1, 3)], r0[2] + g[(2, 3)]],
                kappa: (cell[2 * i], cell[2 * i + 1]),
                d: m.stiffness().eval(gs).d,
                node: false,
                weight: 0.5 * h,
            });
        }
    }
    Ok(out)
}

/// What [`verify_enclosed`] measured.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct EnclosedVerification {
    /// Rotation angle of the frame's holonomy `X_N` (radians).
    pub holonomy_angle: f64,
    /// `|r_N − r_0|/R`: the end of the rod from its start.
    pub closing_gap: f64,
    /// Largest `(|r| − R)/R` over the written nodes (≤ 0 inside the ball).
    pub outside: f64,
    /// Largest `(|r| − R)/R` over the written Gauss points (between the nodes, where the
    /// model does not impose the wall).
    pub outside_between: f64,
    /// Energy `E R/(π D0)` recomputed from the written points ([`weighted_energy`]).
    pub energy_from_profile: f64,
    /// Allowed `|energy_from_profile − claimed energy|`.
    pub energy_tolerance: f64,
    /// Periods of the state ([`crate::identify::identify_enclosed`]; 0 where they are not
    /// named and no branch was requested).
    pub eta: u32,
}

/// Verify an enclosed state (3-D model, Eqs. (2)–(6) with the wall `|r| ≤ R`) and the points
/// written for it ([`enclosed_profile`]):
///
/// * **closed**: the tangent comes back within [`MAX_HOLONOMY_ANGLE`] of its start (the
///   frame may come back turned about it: no twisting moment) and the rod's end within [`MAX_HOLONOMY_ANGLE`]` R` of its start
///   (positions close), from the model's own transforms;
/// * **inside the ball**: every written node has `|r| ≤ R (1 + `[`POSITION_SLACK`]`)` (the
///   model imposes the wall there); every written Gauss point lies within the reach of its
///   cell's curve outside the ball ([`between_nodes_bound`]);
/// * **energy**: `(R/π D0) Σ w ½ D |κ|²` over the written points with their quadrature
///   weights ([`weighted_energy`]: the model's own two-point Gauss rule, exact for the
///   written state) equals the claim within `claim.energy_error + claim.profile_error` and
///   [`ENERGY_RELATIVE_SLACK`];
/// * **branch**: the periods of the moment of the state's central projection onto the
///   sphere ([`crate::identify::identify_enclosed`]) equal `claim.eta` when given.
///
/// Errors: [`SolverError::Unverified`] naming the first check that fails.
pub fn verify_enclosed(
    st: &crate::enclosed::EnclosedState,
    claim: &Claim,
) -> Result<EnclosedVerification, SolverError> {
    let fail = |m: String| Err(SolverError::Unverified(m));
    let m = &st.model;
    let r = m.radius();
    let d0 = m.stiffness().kind().reference();
    let x = m.transforms(&st.z)?;
    let end = &x[m.cells()];
    // The tangent is the frame's first column; the frame itself may come back
    // turned about the tangent (no twisting moment, see `enclosed::model::TWIST_ROW`).
    let tangent =
        |p: &nalgebra::Matrix4<f64>| nalgebra::Vector3::new(p[(0, 0)], p[(1, 0)], p[(2, 0)]);
    let (t0, t1) = (tangent(&x[0]), tangent(end));
    let angle = t0.cross(&t1).norm().atan2(t0.dot(&t1));
    let closing_gap = nalgebra::Vector3::new(end[(0, 3)], end[(1, 3)], end[(2, 3)]).norm() / r;
    if angle.is_nan() || angle > MAX_HOLONOMY_ANGLE {
        return fail(format!(
            "the rod does not close: its tangent comes back turned by {angle:.3e} rad (at most \
             {MAX_HOLONOMY_ANGLE:e})"
        ));
    }
    if closing_gap.is_nan() || closing_gap > MAX_HOLONOMY_ANGLE {
        return fail(format!(
            "the rod does not close: its end is {closing_gap:.3e} R from its start (at most \
             {MAX_HOLONOMY_ANGLE:e} R)"
        ));
    }
    let pts = enclosed_profile(st)?;
    let n = pts.len();
    if n < 8 {
        return fail(format!(
            "the profile has {n} points (at least 8 are needed)"
        ));
    }
    if pts.iter().any(|p| {
        ![p.s, p.r[0], p.r[1], p.r[2], p.kappa.0, p.kappa.1, p.d]
            .iter()
            .all(|v| v.is_finite())
    }) {
        return fail("the profile has a value that is not finite".into());
    }
    let excess = |p: &EnclosedPoint| -m.wall().clearance(&nalgebra::Vector3::from(p.r)) / r;
    let outside = pts
        .iter()
        .filter(|p| p.node)
        .map(excess)
        .fold(f64::NEG_INFINITY, f64::max);
    if outside.is_nan() || outside > POSITION_SLACK {
        return fail(format!(
            "a written node is {outside:.3e} R outside the ball"
        ));
    }
    let mut outside_between = f64::NEG_INFINITY;
    for c in 0..m.cells() {
        let bound = POSITION_SLACK + between_nodes_bound(&pts[3 * c + 1], &pts[3 * c + 2], r);
        for p in &pts[3 * c + 1..3 * c + 3] {
            let e = excess(p);
            outside_between = outside_between.max(e);
            if e.is_nan() || e > bound {
                return fail(format!(
                    "a written Gauss point is {e:.3e} R outside the ball (between two nodes \
                     inside it, the cell's curve reaches at most {bound:.1e} R out)"
                ));
            }
        }
    }
    // The written points carry the model's own Gauss weights ([`weighted_energy`]): no
    // every-other-point estimate of the quadrature's error.
    let fine = weighted_energy(&pts, r, d0);
    let energy_tolerance = check_energy(claim, fine, fine, 1.0)?;
    // Without a requested branch, a state whose periods are not named (the planar circle)
    // counts 0.
    let eta = match (identify_enclosed(st), claim.eta) {
        (Ok(p), _) => p.eta,
        (Err(_), None) => 0,
        (Err(e), Some(_)) => {
            return fail(format!("its branch cannot be identified ({e})"));
        }
    };
    if let Some(want) = claim.eta {
        if eta != want {
            return fail(format!(
                "the moment D κ_g of its central projection onto the sphere has {eta} periods, \
                 not the requested {want}"
            ));
        }
    }
    Ok(EnclosedVerification {
        holonomy_angle: angle,
        closing_gap,
        outside,
        outside_between,
        energy_from_profile: fine,
        energy_tolerance,
        eta,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{solve, Accuracy, SurfaceModel};
    use crate::{StartShape, Stiffness};

    fn solved() -> crate::AccurateEquilibrium {
        crate::solve_with_accuracy(
            1.0,
            1.2,
            &Stiffness::uniform(1.0),
            &StartShape::Exact { eta: 2 },
            Accuracy::Default,
            &Default::default(),
        )
        .unwrap()
    }

    /// A solved state passes; each kind of false claim or doctored profile is refused.
    #[test]
    fn accepts_a_solved_state_and_refuses_false_claims() {
        let acc = solved();
        let eq = &acc.equilibrium;
        let profile = eq.profile();
        let v0 = verify_accurate(&acc, Some(2)).unwrap();
        let claim = Claim {
            energy: acc.energy.total,
            energy_error: acc.energy_error,
            profile_error: v0.energy_tolerance,
            eta: Some(2),
        };
        let v = verify_state(eq, &profile, &claim).unwrap();
        assert_eq!(v.eta, 2);
        assert!(v.holonomy_angle < 1e-9, "{v:?}");
        assert!(v.closing_chord <= v.closing_arc, "{v:?}");
        assert!((v.energy_from_profile - acc.energy.total).abs() <= v.energy_tolerance);
        // The energy tolerance is the error estimates', not a blanket one.
        assert!(v.energy_tolerance < 1e-5, "{v:?}");
        let wrong_energy = Claim {
            energy: acc.energy.total * (1.0 + 1e-4),
            ..claim
        };
        assert!(matches!(
            verify_state(eq, &profile, &wrong_energy),
            Err(SolverError::Unverified(_))
        ));
        let wrong_branch = Claim {
            eta: Some(3),
            ..claim
        };
        assert!(verify_state(eq, &profile, &wrong_branch).is_err());
        let mut open = profile.clone();
        let last = open.len() - 1;
        // The last point turned by 0.3 rad about the x axis, away from the first (which is
        // on the z axis, X(0) = I), staying on the sphere.
        let (y, z) = (open[last].y, open[last].z);
        let (c, s) = (0.3f64.cos(), 0.3f64.sin());
        open[last].y = c * y - s * z;
        open[last].z = s * y + c * z;
        let e = verify_state(eq, &open, &claim).unwrap_err().to_string();
        assert!(e.contains("does not close"), "{e}");
        let mut off = profile.clone();
        off[3].z *= 1.001;
        assert!(verify_state(eq, &off, &claim).is_err());
    }

    /// A loop whose frame comes back turned by a half-turn is refused, although
    /// `vee(skew H)` vanishes there: constant `κ_g` over half a small circle.
    #[test]
    fn refuses_a_half_turn_holonomy() {
        let kg = 0.75f64;
        // Half of the small circle of circumference 2π/√(1 + κ_g²) (R = 1).
        let lbar = 0.5 / (1.0 + kg * kg).sqrt();
        let model = SurfaceModel::new(1.0, lbar, 16, &Stiffness::uniform(1.0)).unwrap();
        let kappa = vec![kg; model.n_kappa()];
        let eq = solve::Equilibrium::for_test(model, kappa);
        let claim = Claim {
            energy: 0.0,
            energy_error: 1.0,
            profile_error: 1.0,
            eta: None,
        };
        let e = verify_state(&eq, &eq.profile(), &claim)
            .unwrap_err()
            .to_string();
        assert!(e.contains("turned by 3.14"), "{e}");
    }

    /// The free planar circle (exact in the 3-D model: constant curvature, `E R/(π D) =
    /// 1/L̄`) passes [`verify_enclosed`]; a false energy, an opened rod and a circle moved
    /// out of the ball are refused.
    #[test]
    fn enclosed_circle_passes_and_doctored_states_are_refused() {
        let (lbar, cells) = (0.8, 32);
        let (model, z) =
            crate::enclosed::free_circle(1.0, lbar, cells, &Stiffness::uniform(1.0)).unwrap();
        let st = crate::enclosed::EnclosedState {
            model,
            z,
            iterations: 0,
            residual: 0.0,
        };
        let claim = Claim {
            energy: 1.0 / lbar,
            energy_error: 1e-12,
            profile_error: 0.0,
            eta: None,
        };
        let v = verify_enclosed(&st, &claim).unwrap();
        assert!(v.holonomy_angle < 1e-12 && v.closing_gap < 1e-12, "{v:?}");
        assert!((v.outside + (1.0 - lbar)).abs() < 1e-12, "{v:?}");
        let wrong = Claim {
            energy: 1.0 / lbar * (1.0 + 1e-6),
            ..claim
        };
        assert!(verify_enclosed(&st, &wrong).is_err());
        let mut open = st.clone();
        open.z[0] += 0.1;
        let e = verify_enclosed(&open, &claim).unwrap_err().to_string();
        assert!(e.contains("does not close"), "{e}");
        let mut out = st.clone();
        out.z[4 * cells + 2] += 0.5;
        let e = verify_enclosed(&out, &claim).unwrap_err().to_string();
        assert!(e.contains("outside the ball"), "{e}");
    }

    /// A lifted-off state (the figure-eight, branch 2, at `L̄ = 1.4`, 96 cells): the energy
    /// of its written points by their weights is the model's to round-off, while the
    /// periodic trapezoid over the nodes alone misses it by more than the state's error
    /// estimate (the curvature's extrapolations to the nodes are a second discretisation).
    /// The Gauss points lie within their cells' reach outside the ball, which is short of
    /// `0.01 R`.
    #[test]
    fn lifted_off_state_energy_is_recomputed_from_its_points() {
        use crate::enclosed::{solve_branch, EnclosedOptions, SurfaceSource};
        let l = rodloop_exact::paper_branch_loop(1, 1.4).unwrap();
        let b = solve_branch(
            1.0,
            1.4,
            &Stiffness::uniform(1.0),
            &SurfaceSource::Exact(l),
            96,
            &EnclosedOptions::default(),
        )
        .unwrap();
        let st = &b.fine;
        assert!(st.contact(1e-9).unwrap().fraction < 1.0, "lifted off");
        let pts = enclosed_profile(st).unwrap();
        assert_eq!(pts.len(), 3 * st.model.cells());
        assert!(pts.windows(2).all(|w| w[1].s > w[0].s));
        let weighted = weighted_energy(&pts, 1.0, 1.0);
        assert!(
            (weighted - b.energy).abs() < 1e-12 * b.energy,
            "{weighted} {}",
            b.energy
        );
        let nodes: Vec<_> = pts.iter().filter(|p| p.node).collect();
        let s: Vec<f64> = nodes.iter().map(|p| p.s).collect();
        let dens: Vec<f64> = nodes
            .iter()
            .map(|p| 0.5 * p.d * (p.kappa.0 * p.kappa.0 + p.kappa.1 * p.kappa.1))
            .collect();
        let (trap, _) = periodic_trapezoid(&s, &dens, st.model.length(), 1.0 / PI);
        eprintln!(
            "weighted {weighted:.12} trapezoid-of-nodes {trap:.12} energy {:.12} +- {:.2e}",
            b.energy, b.energy_error
        );
        assert!(
            (trap - b.energy).abs() > b.energy_error,
            "{trap} {}",
            b.energy
        );
        let claim = Claim {
            energy: b.energy,
            energy_error: b.energy_error,
            profile_error: 0.0,
            eta: Some(1),
        };
        let v = verify_enclosed(st, &claim).unwrap();
        eprintln!("{v:?}");
        assert_eq!(v.eta, 1);
        let wrong = Claim {
            energy: b.energy + 2.0 * b.energy_error + 1e-8,
            ..claim
        };
        assert!(verify_enclosed(st, &wrong).is_err());
        // Gauss points do leave the ball slightly where the loop presses on it (the wall
        // holds at the nodes), within the reach of their cells' curves; a point 0.01 R
        // outside is beyond it.
        assert!(v.outside_between > 0.0, "{v:?}");
        for c in 0..st.model.cells() {
            let bound = between_nodes_bound(&pts[3 * c + 1], &pts[3 * c + 2], 1.0);
            assert!(bound < 0.01, "cell {c}: {bound}");
        }
    }
}
