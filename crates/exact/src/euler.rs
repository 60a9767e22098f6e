//! Euler rotation curves on the unit sphere (Wang, Li & Yi, JMPS 2024, Section 3.1).
//!
//! It is one file because every quantity of the curve (position, derivatives, curvature,
//! torsion, lengths, energies, the inverse `α(L̄)`) reads the one Fourier form of Eq. (4)
//! derived below.
//!
//! The curves of Eq. (4) approximate the constrained rod loops on a sphere.  Units are
//! R = 1 (sphere radius) and D = 1 (bending stiffness); lengths are reported either as
//! L (in units of R) or as the normalised length L̄ = L/(2πR).  Energies are reported in
//! the normalisation of Fig. 3, E R/(πD) = (1/(2π)) ∮ κ² ds, from Eq. (2).
//!
//! # Useful rewriting of Eq. (4)
//!
//! With A = sin²(α/2), B = cos²(α/2), p = l − 1, q = l + 1, product-to-sum formulas turn
//! Eq. (4) into the finite Fourier series
//!
//! ```text
//! x = A cos(p t) − B cos(q t),   y = A sin(p t) + B sin(q t),   z = sin α cos(l t),
//! ```
//!
//! which gives all t-derivatives in closed form.  The same series also shows that the
//! curve is a great circle of tilt α traversed l times while the sphere turns once about z,
//! and that its speed is
//!
//! ```text
//! |r_t|² = (l + cos α)² + sin²α sin²(l t),
//! ```
//!
//! which is the integrand behind Eq. (5).
//!
//! # Findings about the paper's special-case statements (checked in `tests/euler.rs`)
//!
//! * Eq. (5) is confirmed: its length agrees with quadrature of |r_t| to about 1e-15
//!   (relative), and L̄(α) decreases strictly from l + 1 (α = 0) to l − 1 (α = π), because
//!   d|r_t|²/dα = −2 sin α (l + cos α cos²(l t)) < 0 on (0, π).
//! * At α = 0 the curve is the equator (z = 0) traversed l + 1 times; at α = π it is the
//!   equator traversed l − 1 times (a single point, (1, 0, 0), when l = 1).
//! * Eq. (7) with a = R(1 − cos α)/2, b = R(1 + cos α)/2 coincides with Eq. (4) at l = 2
//!   point by point with the same parameter t (no rotation needed).  Eq. (8) is correct once
//!   its imaginary modulus is read as the parameter m = 4a(a − R)/(3R − 2a)² < 0, and it
//!   equals Eq. (5) at l = 2 because 3R − 2a = R(2 + cos α) and 4ab = R² sin²α.
//! * For l = 1, Eq. (4) lies on the cylinder (x − sin²(α/2))² + y² = cos⁴(α/2), which is
//!   parallel to z and touches the sphere along the line x = R, y = 0.  The cylinder radius
//!   is therefore R cos²(α/2), **not** R sin²(α/2) as stated in the paper (the paper's value
//!   holds after the substitution α → π − α).  Both expressions agree only at α = π/2.
//! * ∮ τ ds = 0 holds to rounding (~1e-16).  Note that Eq. (4) is symmetric under
//!   t → −t, y → −y (a reflection), so τ(−t) = −τ(t) and the vanishing is also immediate
//!   from that symmetry; the tests therefore also integrate on a shifted grid.
//! * Consequently the Viviani curve (cylinder of radius R/2 through the centre) is the
//!   l = 1 curve at α = π/2, **not** at α = π/4 as stated in the paper; at α = π/4 the
//!   cylinder radius is cos²(π/8) ≈ 0.854 R.
//!
//! # Size
//!
//! The file is one curve family of Sec. 3.1 (Eq. (4) and its special cases, the tennis ball
//! and the hippopedes) with its geometry, lengths, energies and the quadrature they share;
//! its tests are in `crates/exact/tests`.

use serde::{Deserialize, Serialize};
use std::f64::consts::{PI, TAU};
use thiserror::Error;

/// Errors raised by the Euler-curve routines.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum EulerError {
    /// The periodicity index l of Eq. (4) must be a positive integer.
    #[error("the periodicity index l must be >= 1 (got {l})")]
    InvalidL {
        /// The offending index.
        l: u32,
    },
    /// The tilt angle α of Eq. (4) must be a finite number in [0, π].
    #[error("the angle alpha must lie in [0, pi] (got {alpha})")]
    InvalidAlpha {
        /// The offending angle.
        alpha: f64,
    },
    /// The requested normalised length lies outside the open range (l − 1, l + 1) that
    /// Eq. (5) covers for α ∈ (0, π).
    #[error("normalised length {lbar} is outside ({min}, {max}) covered by Eq. (5) for l = {l}")]
    LengthOutOfRange {
        /// Periodicity index.
        l: u32,
        /// Requested normalised length L̄ = L/(2πR).
        lbar: f64,
        /// Lower end of the admissible open interval, l − 1.
        min: f64,
        /// Upper end of the admissible open interval, l + 1.
        max: f64,
    },
    /// The root finder for Eq. (5) did not converge (should not happen: it is bracketed).
    #[error("root finder for Eq. (5) did not converge for l = {l}, lbar = {lbar}")]
    NoConvergence {
        /// Periodicity index.
        l: u32,
        /// Requested normalised length.
        lbar: f64,
    },
}

/// Result of an adaptive periodic trapezoidal quadrature over t ∈ [0, 2π].
///
/// The number of points is doubled until two successive estimates differ by less than
/// about 1e-14 times the L1 norm of the integrand (a target well below the 1e-12 the
/// rest of the code relies on).  Because every integrand here is smooth and 2π-periodic,
/// the rule converges exponentially and the last difference is a conservative bound on
/// the error of `value` (which uses the finer of the two rules).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Quadrature {
    /// The quadrature value (from the finest rule used).
    pub value: f64,
    /// |T_{2N} − T_N| of the last doubling, a bound on the error of `value`.
    pub error_estimate: f64,
    /// Number of points of the finest rule.
    pub points: usize,
    /// Whether the tolerance was met before the point cap (2²² points) was reached.
    pub converged: bool,
}

/// An Euler rotation curve, Eq. (4), on the unit sphere:
///
/// ```text
/// x = −cos α cos t cos(l t) + sin t sin(l t)
/// y =  cos α sin t cos(l t) + cos t sin(l t)
/// z =  sin α cos(l t),          t ∈ [0, 2π].
/// ```
///
/// Valid parameters are l ≥ 1 and α ∈ [0, π]; [`EulerCurve::new`] checks them.  The
/// methods assume valid parameters.  At (l, α) = (1, π) the curve degenerates to the single
/// point (1, 0, 0); curvature-based quantities are then undefined (NaN or infinite).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct EulerCurve {
    /// Periodicity index l ≥ 1 of Eq. (4).
    pub l: u32,
    /// Tilt angle α ∈ [0, π] of Eq. (4).
    pub alpha: f64,
}

/// One point of an arclength-uniform sampling of an [`EulerCurve`] (see
/// [`EulerCurve::sample`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct EulerSample {
    /// Arclength from t = 0 (units of R).
    pub s: f64,
    /// Curve parameter t of Eq. (4) at this arclength.
    pub t: f64,
    /// Position, x component (Eq. (4)).
    pub x: f64,
    /// Position, y component (Eq. (4)).
    pub y: f64,
    /// Position, z component (Eq. (4)).
    pub z: f64,
    /// Curvature κ by Eq. (6) (units of 1/R).
    pub kappa: f64,
    /// Torsion τ by Eq. (6) (units of 1/R).
    pub tau: f64,
    /// Geodesic curvature κ_g (sign convention of [`EulerCurve::geodesic_curvature`]).
    pub kappa_g: f64,
}

/// Tennis-ball seam line, Eq. (7), on the unit sphere (a + b = R = 1):
/// x = a cos t − b cos 3t, y = a sin t + b sin 3t, z = 2√(ab) cos 2t.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TennisBall {
    /// a = R(1 − cos α)/2 (stored as sin²(α/2) to avoid cancellation).
    pub a: f64,
    /// b = R(1 + cos α)/2 (stored as cos²(α/2)).
    pub b: f64,
}

/// Spherical hippopede: the intersection of the unit sphere with the circular cylinder
/// (x − (1 − ρ))² + y² = ρ², parallel to z, which touches the sphere along the line
/// x = 1, y = 0 (a "tangent cylinder"; Section 3.1, remark after Eq. (6)).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Hippopede {
    /// Cylinder radius ρ ∈ (0, 1] (units of R).
    pub radius: f64,
}

/// Shared sin(α/2), cos(α/2) and derived constants of the harmonic form of Eq. (4).
#[derive(Debug, Clone, Copy)]
struct Coeffs {
    /// A = sin²(α/2) = (1 − cos α)/2.
    a: f64,
    /// B = cos²(α/2) = (1 + cos α)/2.
    b: f64,
    /// sin α.
    sin_alpha: f64,
    /// l + cos α, computed as (l − 1) + 2cos²(α/2) without cancellation.
    l_plus_cos: f64,
}

fn coeffs(l: u32, alpha: f64) -> Coeffs {
    let (sh, ch) = (0.5 * alpha).sin_cos();
    let b = ch * ch;
    Coeffs {
        a: sh * sh,
        b,
        sin_alpha: 2.0 * sh * ch,
        l_plus_cos: (l as f64 - 1.0) + 2.0 * b,
    }
}

/// n-th derivative of cos(ω t) and sin(ω t) with respect to t.
fn dcos_dsin(n: u32, omega: f64, t: f64) -> (f64, f64) {
    let (s, c) = (omega * t).sin_cos();
    let w = omega.powi(n as i32);
    let (dc, ds) = match n % 4 {
        0 => (c, s),
        1 => (-s, c),
        2 => (-c, -s),
        _ => (s, -c),
    };
    (w * dc, w * ds)
}

fn cross(u: [f64; 3], v: [f64; 3]) -> [f64; 3] {
    [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ]
}

fn dot(u: [f64; 3], v: [f64; 3]) -> f64 {
    u[0] * v[0] + u[1] * v[1] + u[2] * v[2]
}

fn norm(u: [f64; 3]) -> f64 {
    dot(u, u).sqrt()
}

/// Curvature by Eq. (6) from the first two parameter derivatives.
fn kappa_eq6(r1: [f64; 3], r2: [f64; 3]) -> f64 {
    let v = norm(r1);
    norm(cross(r1, r2)) / (v * v * v)
}

/// Torsion by Eq. (6) from the first three parameter derivatives.
fn tau_eq6(r1: [f64; 3], r2: [f64; 3], r3: [f64; 3]) -> f64 {
    let c = cross(r1, r2);
    dot(r1, cross(r2, r3)) / dot(c, c)
}

/// Compensated (Neumaier) running sum.
#[derive(Default, Clone, Copy)]
struct Sum {
    s: f64,
    c: f64,
}

impl Sum {
    fn add(&mut self, x: f64) {
        let t = self.s + x;
        if self.s.abs() >= x.abs() {
            self.c += (self.s - t) + x;
        } else {
            self.c += (x - t) + self.s;
        }
        self.s = t;
    }
    fn value(&self) -> f64 {
        self.s + self.c
    }
}

const QUAD_REL_TOL: f64 = 1e-14;
const QUAD_MAX_POINTS: usize = 1 << 22;

/// Adaptive trapezoidal rule for ∫_0^{2π} f(t) dt with f smooth and 2π-periodic.
fn periodic_trapezoid<F: Fn(f64) -> f64>(f: F, n0: usize) -> Quadrature {
    let mut n = n0.max(8);
    let mut sum = Sum::default();
    let mut abs_sum = Sum::default();
    for k in 0..n {
        let v = f(TAU * k as f64 / n as f64);
        sum.add(v);
        abs_sum.add(v.abs());
    }
    let mut value = TAU * sum.value() / n as f64;
    loop {
        // Add the midpoints: the rule with 2n points.
        let h = TAU / n as f64;
        for k in 0..n {
            let v = f((k as f64 + 0.5) * h);
            sum.add(v);
            abs_sum.add(v.abs());
        }
        n *= 2;
        let new_value = TAU * sum.value() / n as f64;
        let l1 = TAU * abs_sum.value() / n as f64;
        let err = (new_value - value).abs();
        value = new_value;
        let converged = err <= QUAD_REL_TOL * l1 || err == 0.0;
        if converged || n >= QUAD_MAX_POINTS || !value.is_finite() {
            return Quadrature {
                value,
                error_estimate: err,
                points: n,
                converged: converged && value.is_finite(),
            };
        }
    }
}

/// Normalised length L̄ = L/(2πR) of the Euler curve (l, α) by Eq. (5).
///
/// Eq. (5) reads L = R (l + cos α)/l · E(2lπ, i sin α/(l + cos α)).  With an imaginary
/// modulus iK the incomplete integral is E(φ | m) with parameter m = −K², and since 2lπ is
/// 4l quarter periods, E(2lπ | m) = 4l E(m) with the complete integral E(m).  Hence
/// L̄ = (2/π)(l + cos α) E(−K²).  Returns 0 for the degenerate point curve (l, α) = (1, π)
/// and NaN for invalid input (l = 0, α ∉ [0, π]).
pub fn lbar_of_alpha(l: u32, alpha: f64) -> f64 {
    if l == 0 || !(0.0..=PI).contains(&alpha) {
        return f64::NAN;
    }
    let c = coeffs(l, alpha);
    if c.l_plus_cos == 0.0 {
        return 0.0;
    }
    let k = c.sin_alpha / c.l_plus_cos;
    let e = ellip::ellipe(-k * k).unwrap_or(f64::NAN);
    2.0 / PI * c.l_plus_cos * e
}

/// Picks, among α and its nearest floating-point neighbours (±4 ulp), the one with the
/// smallest residual |L̄(α) − lbar| (the last Newton step is below rounding level).
fn polish_alpha(l: u32, lbar: f64, alpha: f64) -> f64 {
    let mut best = (alpha, (lbar_of_alpha(l, alpha) - lbar).abs());
    let mut up = alpha;
    let mut down = alpha;
    for _ in 0..4 {
        up = f64::from_bits(up.to_bits() + 1);
        down = f64::from_bits(down.to_bits() - 1);
        for a in [up, down] {
            if a > 0.0 && a < PI {
                let r = (lbar_of_alpha(l, a) - lbar).abs();
                if r < best.1 {
                    best = (a, r);
                }
            }
        }
    }
    best.0
}

/// dL̄/dα, from the equivalent real-modulus form of Eq. (5) (imaginary-modulus
/// transformation E(−K²) = √(1 + K²) E(K²/(1 + K²))):
/// L̄ = (2/π) √Q E(μ), Q = l² + 2l cos α + 1, μ = sin²α / Q.
fn dlbar_dalpha(l: u32, alpha: f64) -> f64 {
    let lf = l as f64;
    let c = coeffs(l, alpha);
    let cos_a = c.b - c.a;
    let q = c.l_plus_cos * c.l_plus_cos + c.sin_alpha * c.sin_alpha;
    let mu = c.sin_alpha * c.sin_alpha / q;
    let e = ellip::ellipe(mu).unwrap_or(f64::NAN);
    // E'(μ) = (E − K)/(2μ); series −π/8 − 3πμ/64 for small μ (avoids cancellation).
    let de = if mu < 1e-6 {
        -PI / 8.0 - 3.0 * PI * mu / 64.0
    } else {
        let k = ellip::ellipk(mu).unwrap_or(f64::NAN);
        (e - k) / (2.0 * mu)
    };
    let sq = q.sqrt();
    let dq = -2.0 * lf * c.sin_alpha;
    let dmu = 2.0 * c.sin_alpha * (cos_a * q + lf * c.sin_alpha * c.sin_alpha) / (q * q);
    2.0 / PI * (0.5 * dq / sq * e + sq * de * dmu)
}

/// Solves Eq. (5) for the tilt α ∈ (0, π) that gives the normalised length
/// `lbar` = L/(2πR) for the periodicity index `l`.
///
/// L̄(α) decreases strictly from l + 1 at α = 0 to l − 1 at α = π (for l = 1 the lower
/// end is 0, the degenerate point curve), so the root is unique; an error is returned when
/// `lbar` is not in the open interval (l − 1, l + 1).  The solver is Newton's method with
/// the analytic derivative, safeguarded by bisection on a bracket.  It stops when the
/// residual |L̄(α) − lbar| ≤ ε·lbar, when the Newton step is below 2ε relative, or when the
/// bracket has collapsed to a few ulps; the residual is then at rounding level (the tests
/// require ≤ 1e-14 relative).  Near the ends of
/// the range L̄ − (l ± 1) = O(α²) or O((π − α)²), so there α itself is only determined to
/// about ε/|dL̄/dα| absolutely; elsewhere the relative accuracy in α is ~1e-15.  Conversely,
/// for l = 1 and L̄ → 0 (α → π, with L̄ ≈ 2(π − α)/π) one ulp of α near π is a relative
/// change 4.4e-16/(π − α) of L̄, which bounds the attainable residual there.
pub fn alpha_for_lbar(l: u32, lbar: f64) -> Result<f64, EulerError> {
    if l == 0 {
        return Err(EulerError::InvalidL { l });
    }
    let (min, max) = (l as f64 - 1.0, l as f64 + 1.0);
    if lbar.is_nan() || lbar <= min || lbar >= max {
        return Err(EulerError::LengthOutOfRange { l, lbar, min, max });
    }
    let (mut lo, mut hi) = (0.0_f64, PI);
    // Large-l asymptote L̄ ≈ l + cos α as a starting guess.
    let mut alpha = (lbar - l as f64)
        .clamp(-1.0, 1.0)
        .acos()
        .clamp(1e-3, PI - 1e-3);
    for _ in 0..200 {
        let f = lbar_of_alpha(l, alpha) - lbar;
        if f.abs() <= f64::EPSILON * lbar {
            return Ok(alpha);
        }
        // L̄ is decreasing: f > 0 means α is too small.
        if f > 0.0 {
            lo = alpha;
        } else {
            hi = alpha;
        }
        let d = dlbar_dalpha(l, alpha);
        let mut next = alpha - f / d;
        if !(next.is_finite() && next > lo && next < hi && d < 0.0) {
            next = 0.5 * (lo + hi);
        }
        let step = (next - alpha).abs();
        alpha = next;
        if step <= 2.0 * f64::EPSILON * alpha || hi - lo <= 4.0 * f64::EPSILON * hi {
            return Ok(polish_alpha(l, lbar, alpha));
        }
    }
    Err(EulerError::NoConvergence { l, lbar })
}

impl EulerCurve {
    /// Creates the curve of Eq. (4), checking l ≥ 1 and α ∈ [0, π].
    pub fn new(l: u32, alpha: f64) -> Result<Self, EulerError> {
        if l == 0 {
            return Err(EulerError::InvalidL { l });
        }
        if !(0.0..=PI).contains(&alpha) {
            return Err(EulerError::InvalidAlpha { alpha });
        }
        Ok(Self { l, alpha })
    }

    /// Creates the curve of index `l` whose normalised length is `lbar`, by solving
    /// Eq. (5) with [`alpha_for_lbar`].
    pub fn from_lbar(l: u32, lbar: f64) -> Result<Self, EulerError> {
        let alpha = alpha_for_lbar(l, lbar)?;
        Self::new(l, alpha)
    }

    fn c(&self) -> Coeffs {
        coeffs(self.l, self.alpha)
    }

    /// Position r(t) on the unit sphere, evaluated literally from Eq. (4).
    pub fn position(&self, t: f64) -> [f64; 3] {
        let (sa, ca) = self.alpha.sin_cos();
        let (st, ct) = t.sin_cos();
        let (slt, clt) = (self.l as f64 * t).sin_cos();
        [
            -ca * ct * clt + st * slt,
            ca * st * clt + ct * slt,
            sa * clt,
        ]
    }

    /// n-th derivative d^n r/dt^n of Eq. (4), analytic, from the harmonic form
    /// x = A cos((l−1)t) − B cos((l+1)t), y = A sin((l−1)t) + B sin((l+1)t),
    /// z = sin α cos(lt) with A = sin²(α/2), B = cos²(α/2) (module docs).  `n = 0` gives
    /// the position (equal to [`EulerCurve::position`] up to rounding).
    pub fn derivative(&self, n: u32, t: f64) -> [f64; 3] {
        let c = self.c();
        let l = self.l as f64;
        let (cp, sp) = dcos_dsin(n, l - 1.0, t);
        let (cq, sq) = dcos_dsin(n, l + 1.0, t);
        let (cl, _) = dcos_dsin(n, l, t);
        // ω⁰ = 1 even for ω = 0, so n = 0 with l = 1 is handled by powi(0) = 1.
        [c.a * cp - c.b * cq, c.a * sp + c.b * sq, c.sin_alpha * cl]
    }

    /// First derivative r_t (analytic).
    pub fn velocity(&self, t: f64) -> [f64; 3] {
        self.derivative(1, t)
    }

    /// Second derivative r_tt (analytic).
    pub fn acceleration(&self, t: f64) -> [f64; 3] {
        self.derivative(2, t)
    }

    /// Third derivative r_ttt (analytic).
    pub fn jerk(&self, t: f64) -> [f64; 3] {
        self.derivative(3, t)
    }

    /// Speed |r_t| = √((l + cos α)² + sin²α sin²(lt)), the integrand of Eq. (5).
    pub fn speed(&self, t: f64) -> f64 {
        let c = self.c();
        let s = c.sin_alpha * (self.l as f64 * t).sin();
        c.l_plus_cos.hypot(s)
    }

    /// Curvature κ = |r_t × r_tt| / |r_t|³, Eq. (6) (units of 1/R).
    pub fn curvature(&self, t: f64) -> f64 {
        kappa_eq6(self.velocity(t), self.acceleration(t))
    }

    /// Torsion τ = r_t · (r_tt × r_ttt) / |r_t × r_tt|², Eq. (6).  On the sphere κ ≥ 1/R,
    /// so the denominator never vanishes (except on the degenerate point curve).
    pub fn torsion(&self, t: f64) -> f64 {
        tau_eq6(self.velocity(t), self.acceleration(t), self.jerk(t))
    }

    /// Geodesic curvature κ_g = (r × r_t) · r_tt / |r_t|³ on the unit sphere.
    ///
    /// Sign convention: with the outward normal n = r and unit tangent T, κ_g = T' · (n × T)
    /// (prime = d/ds), so κ_g > 0 where the curve turns to the left when the sphere is
    /// viewed from outside.  The normal curvature is κ_n = −T'·n = 1/R, hence
    /// κ² = κ_n² + κ_g² = 1 + κ_g² (Section 3.1, Appendix A).
    pub fn geodesic_curvature(&self, t: f64) -> f64 {
        let r = self.position(t);
        let r1 = self.velocity(t);
        let r2 = self.acceleration(t);
        let v = norm(r1);
        dot(cross(r, r1), r2) / (v * v * v)
    }

    /// Length L (units of R) by Eq. (5): L = 4 (l + cos α) E(m), m = −sin²α/(l + cos α)²
    /// (see [`lbar_of_alpha`] for the reduction of the incomplete integral).
    pub fn length(&self) -> f64 {
        TAU * self.lbar()
    }

    /// Normalised length L̄ = L/(2πR) by Eq. (5).
    pub fn lbar(&self) -> f64 {
        lbar_of_alpha(self.l, self.alpha)
    }

    /// Length ∫_0^{2π} |r_t| dt by the adaptive periodic trapezoidal rule (independent of
    /// the elliptic integrals of Eq. (5)).
    pub fn length_by_quadrature(&self) -> Quadrature {
        periodic_trapezoid(|t| self.speed(t), self.start_points())
    }

    fn start_points(&self) -> usize {
        32 * (self.l as usize + 1)
    }

    /// Bending energy, Eq. (2), normalised as E R/(πD) = (1/(2π)) ∮ κ² ds with κ from
    /// Eq. (6); adaptive periodic trapezoidal rule in t (points doubled until successive
    /// estimates agree to ~1e-14 relative; see [`Quadrature`]).
    pub fn bending_energy(&self) -> Quadrature {
        let q = periodic_trapezoid(
            |t| {
                let k = self.curvature(t);
                k * k * self.speed(t)
            },
            self.start_points(),
        );
        scale_quadrature(q, 1.0 / TAU)
    }

    /// Normal-curvature part of the normalised energy, (1/(2π)) ∮ κ_n² ds = L̄, because
    /// κ_n² = 1/R² on the sphere (Section 3.1); evaluated with Eq. (5).
    pub fn energy_n(&self) -> f64 {
        self.lbar()
    }

    /// Geodesic part of the normalised energy, (1/(2π)) ∮ κ_g² ds (adaptive trapezoid).
    /// `energy_n() + energy_g().value` equals `bending_energy().value`.
    pub fn energy_g(&self) -> Quadrature {
        let q = periodic_trapezoid(
            |t| {
                let k = self.geodesic_curvature(t);
                k * k * self.speed(t)
            },
            self.start_points(),
        );
        scale_quadrature(q, 1.0 / TAU)
    }

    /// Total torsion ∮ τ ds (Eq. (6) integrated over the loop), which vanishes for every
    /// closed spherical curve (Section 3.1).  Adaptive trapezoid; the tolerance is relative
    /// to ∮ |τ| ds.
    pub fn total_torsion(&self) -> Quadrature {
        periodic_trapezoid(|t| self.torsion(t) * self.speed(t), self.start_points())
    }

    /// Arclength s(t) = ∫_0^t |r_t| dt' = (l + cos α)/l · E(l t | −K²), K = sin α/(l + cos α):
    /// Eq. (5) with the upper limit 2π replaced by t (incomplete elliptic integral of the
    /// second kind; accurate to a few ulps; any real t, monotone increasing).
    pub fn arclength(&self, t: f64) -> f64 {
        let c = self.c();
        if c.l_plus_cos == 0.0 {
            return 0.0;
        }
        let l = self.l as f64;
        let k = c.sin_alpha / c.l_plus_cos;
        c.l_plus_cos / l * ellip::ellipeinc(l * t, -k * k).unwrap_or(f64::NAN)
    }

    /// Parameter t ∈ [0, 2π] at which the arclength from t = 0 equals `s` ∈ [0, L]
    /// (inverse of [`EulerCurve::arclength`]; safeguarded Newton iteration, result such that
    /// |s(t) − s| ≲ 4ε L).
    pub fn parameter_at_arclength(&self, s: f64) -> f64 {
        let total = self.length();
        if total == 0.0 {
            return 0.0;
        }
        let target = s.clamp(0.0, total);
        self.invert_arclength(target, TAU * target / total, total)
    }

    fn invert_arclength(&self, target: f64, guess: f64, total: f64) -> f64 {
        let (mut lo, mut hi) = (0.0_f64, TAU);
        let mut t = guess.clamp(lo, hi);
        for _ in 0..200 {
            let f = self.arclength(t) - target;
            if f.abs() <= 2.0 * f64::EPSILON * total {
                return t;
            }
            if f > 0.0 {
                hi = t;
            } else {
                lo = t;
            }
            let d = self.speed(t);
            let mut next = t - f / d;
            if !(next.is_finite() && next > lo && next < hi) {
                next = 0.5 * (lo + hi);
            }
            let step = (next - t).abs();
            t = next;
            if step <= 1e-16 * TAU || hi - lo <= 4.0 * f64::EPSILON * TAU {
                return t;
            }
        }
        t
    }

    /// Samples the curve at `n` points uniform in ARCLENGTH: s_j = j L / n, j = 0..n−1.
    ///
    /// s(t) is evaluated in closed form with the incomplete elliptic integral (see
    /// [`EulerCurve::arclength`], accurate to a few ulps) and inverted by safeguarded Newton
    /// iteration with derivative |r_t|, so each sample satisfies |s(t_j) − s_j| ≲ 4ε L.
    /// The tests check the spacing against independent Gauss–Legendre quadrature to 1e-12.
    /// For the degenerate point curve all samples have s = 0.
    pub fn sample(&self, n: usize) -> Vec<EulerSample> {
        let total = self.length();
        let mut out = Vec::with_capacity(n);
        let mut t_prev = 0.0;
        for j in 0..n {
            let s = total * j as f64 / n as f64;
            let t = if total == 0.0 {
                TAU * j as f64 / n as f64
            } else if j == 0 {
                0.0
            } else {
                // Guess: advance from the previous sample by ds/|r_t|.
                let ds = total / n as f64;
                let guess = t_prev + ds / self.speed(t_prev);
                self.invert_arclength(s, guess, total)
            };
            t_prev = t;
            let p = self.position(t);
            out.push(EulerSample {
                s,
                t,
                x: p[0],
                y: p[1],
                z: p[2],
                kappa: self.curvature(t),
                tau: self.torsion(t),
                kappa_g: self.geodesic_curvature(t),
            });
        }
        out
    }
}

fn scale_quadrature(q: Quadrature, factor: f64) -> Quadrature {
    Quadrature {
        value: q.value * factor,
        error_estimate: q.error_estimate * factor,
        ..q
    }
}

/// The tennis-ball seam of Eq. (7) with a = R(1 − cos α)/2, b = R(1 + cos α)/2.
///
/// It coincides with the l = 2 Euler curve of Eq. (4) (same α, same parameter t).
pub fn tennis_ball(alpha: f64) -> TennisBall {
    let (sh, ch) = (0.5 * alpha).sin_cos();
    TennisBall {
        a: sh * sh,
        b: ch * ch,
    }
}

impl TennisBall {
    /// n-th t-derivative of Eq. (7) (n = 0: position).
    pub fn derivative(&self, n: u32, t: f64) -> [f64; 3] {
        let (c1, s1) = dcos_dsin(n, 1.0, t);
        let (c3, s3) = dcos_dsin(n, 3.0, t);
        let (c2, _) = dcos_dsin(n, 2.0, t);
        let z0 = 2.0 * (self.a * self.b).sqrt();
        [
            self.a * c1 - self.b * c3,
            self.a * s1 + self.b * s3,
            z0 * c2,
        ]
    }

    /// Position of Eq. (7).
    pub fn position(&self, t: f64) -> [f64; 3] {
        self.derivative(0, t)
    }

    /// Curvature by Eq. (6) applied to Eq. (7).
    pub fn curvature(&self, t: f64) -> f64 {
        kappa_eq6(self.derivative(1, t), self.derivative(2, t))
    }

    /// Length by Eq. (8), L = 4(3R − 2a) E(π/2, 2√(a(a − R))/(3R − 2a)).  Because a < R the
    /// modulus is imaginary; its square is the (negative) parameter
    /// m = 4a(a − R)/(3R − 2a)², so L = 4(3R − 2a) E(m) with the complete integral.
    pub fn length_eq8(&self) -> f64 {
        let r = self.a + self.b;
        let w = 3.0 * r - 2.0 * self.a;
        let m = 4.0 * self.a * (self.a - r) / (w * w);
        4.0 * w * ellip::ellipe(m).unwrap_or(f64::NAN)
    }

    /// Length ∫_0^{2π} |r_t| dt of Eq. (7) by the adaptive periodic trapezoidal rule.
    pub fn length_by_quadrature(&self) -> Quadrature {
        periodic_trapezoid(|t| norm(self.derivative(1, t)), 64)
    }
}

/// The l = 1 Euler curve (Eq. (4)) as a spherical hippopede.
///
/// The harmonic form gives x = sin²(α/2) − cos²(α/2) cos 2t, y = cos²(α/2) sin 2t, so the
/// curve lies on the cylinder parallel to z with axis (sin²(α/2), 0) and radius
/// **cos²(α/2)** (the paper's R sin²(α/2) corresponds to α → π − α).  With
/// θ = π − 2t, [`Hippopede::position`]`(θ)` equals Eq. (4) at l = 1.
pub fn hippopede(alpha: f64) -> Hippopede {
    let ch = (0.5 * alpha).cos();
    Hippopede { radius: ch * ch }
}

/// The Viviani curve: sphere ∩ cylinder of radius R/2 passing through the centre.
/// It is [`hippopede`]`(π/2)`, i.e. the l = 1 Euler curve at α = π/2 (not π/4).
pub fn viviani() -> Hippopede {
    Hippopede { radius: 0.5 }
}

impl Hippopede {
    /// Axis of the cylinder: the vertical line through (1 − ρ, 0).
    pub fn axis(&self) -> [f64; 2] {
        [1.0 - self.radius, 0.0]
    }

    /// Point on the sphere–cylinder intersection at cylinder angle θ ∈ [0, 4π):
    /// x = 1 − ρ + ρ cos θ, y = ρ sin θ, z = 2√(ρ(1 − ρ)) sin(θ/2).
    pub fn position(&self, theta: f64) -> [f64; 3] {
        let rho = self.radius;
        let (s, c) = theta.sin_cos();
        [
            1.0 - rho + rho * c,
            rho * s,
            2.0 * (rho * (1.0 - rho)).sqrt() * (0.5 * theta).sin(),
        ]
    }

    /// Signed distance of the point `p` from the cylinder surface (distance of (x, y) from
    /// the axis minus the radius).
    pub fn cylinder_residual(&self, p: [f64; 3]) -> f64 {
        let ax = self.axis();
        (p[0] - ax[0]).hypot(p[1] - ax[1]) - self.radius
    }

    /// The tilt α of the l = 1 Euler curve lying on this cylinder, from ρ = cos²(α/2).
    pub fn alpha(&self) -> f64 {
        2.0 * self.radius.sqrt().clamp(0.0, 1.0).acos()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_PI_2;

    #[test]
    fn dlbar_dalpha_matches_finite_difference() {
        for l in 1..=4 {
            for &a in &[0.05, 0.3, 1.0, 1.7, 2.5, 3.0] {
                let h = 1e-6;
                let fd = (lbar_of_alpha(l, a + h) - lbar_of_alpha(l, a - h)) / (2.0 * h);
                let an = dlbar_dalpha(l, a);
                assert!((fd - an).abs() < 1e-8, "l={l} a={a} fd={fd} an={an}");
            }
        }
    }

    #[test]
    fn quarter_period_constant() {
        assert!((FRAC_PI_2 - ellip::ellipe(0.0).unwrap()).abs() < 1e-15);
    }
}
