//! Starting shapes for the Newton solve: geodesic-curvature profiles `κ_g(σ)`, `σ = s/L`,
//! evaluated at the Gauss points of a model.
//!
//! Sign convention (checked in the tests): `κ_g = t'·g` with `g = n × t` and `n` the outward
//! normal, the convention of [`crate::frame`]; the Euler curves of the exact layer and the
//! exact loops use the same one, so their `κ_g` is used as is.

use std::f64::consts::PI;

use rodloop_exact::euler::EulerCurve;

use crate::model::SurfaceModel;
use crate::periodic::TrigInterpolant;
use crate::stiffness::{eval_periodic_spline, periodic_spline_moments};
use crate::SolverError;

/// A starting shape, as a function of `σ = s/L`.
#[derive(Clone, Debug, PartialEq)]
pub enum StartShape {
    /// Euler rotation curve of Eq. (4) with index `l`, built at the model's `L̄`
    /// (exists for `l − 1 < L̄ < l + 1`, Eq. (5)).
    Euler {
        /// Periodicity index `l` (a branch with `η` periods starts from `l = η`).
        l: u32,
    },
    /// Exact homogeneous equilibrium of the paper's branch with `eta` periods of `κ_g`
    /// (Sec. 4.3), at the model's `L̄`.
    Exact {
        /// Number of periods `η`.
        eta: u32,
    },
    /// A given dimensionless profile `κ_g R` as a function of `σ` (trigonometric interpolant),
    /// e.g. from [`from_points`] or a saved configuration.
    Profile(TrigInterpolant),
}

impl StartShape {
    /// Samples of `κ_g R` per period used for Euler curves and exact loops.
    fn samples(lbar: f64) -> usize {
        (96.0 * (lbar.max(1.0) + 1.0)).ceil() as usize
    }

    /// The dimensionless profile `κ_g R` of this start at normalised length `lbar`.
    pub fn interpolant(&self, lbar: f64) -> Result<TrigInterpolant, SolverError> {
        match self {
            StartShape::Euler { l } => {
                let curve = EulerCurve::from_lbar(*l, lbar)?;
                let kg: Vec<f64> = curve
                    .sample(Self::samples(lbar))
                    .iter()
                    .map(|p| p.kappa_g)
                    .collect();
                TrigInterpolant::new(&kg)
            }
            StartShape::Exact { eta } => {
                let lp = rodloop_exact::paper_branch_loop(*eta, lbar)?;
                let kg = lp
                    .sample(Self::samples(lbar))?
                    .iter()
                    .map(|p| p.kappa_g)
                    .collect::<Vec<_>>();
                TrigInterpolant::new(&kg)
            }
            StartShape::Profile(t) => Ok(t.clone()),
        }
    }

    /// Start from samples of the dimensionless geodesic curvature `κ_g R` uniform in
    /// arclength over one loop (`σ_j = j/M`), e.g. the `kappa_g` column of a saved
    /// configuration (times `R`).
    pub fn from_kappa_g_samples(kappa_g_r: &[f64]) -> Result<Self, SolverError> {
        Ok(StartShape::Profile(TrigInterpolant::new(kappa_g_r)?))
    }

    /// Start from any exact loop of the exact layer (e.g. one of
    /// [`rodloop_exact::all_loops`]), sampled with `samples` points.
    pub fn from_exact_loop(
        lp: &rodloop_exact::ExactLoop,
        samples: usize,
    ) -> Result<Self, SolverError> {
        let kg: Vec<f64> = lp.sample(samples)?.iter().map(|p| p.kappa_g).collect();
        Ok(StartShape::Profile(TrigInterpolant::new(&kg)?))
    }

    /// The same start with its arclength origin moved by `shift` (a fraction of the length):
    /// the shape is the same, but a non-uniform stiffness profile meets it at another
    /// place.
    pub fn shifted(&self, lbar: f64, shift: f64) -> Result<StartShape, SolverError> {
        if shift == 0.0 {
            return Ok(self.clone());
        }
        Ok(StartShape::Profile(self.interpolant(lbar)?.moved(shift)))
    }

    /// Number of oscillation periods of `κ_g` (half the number of sign changes of
    /// `κ_g − mean` over the loop, at least 1): `η` for the exact and Euler loops.
    pub fn periods(&self, lbar: f64) -> Result<usize, SolverError> {
        // Euler curves and exact loops have l (η) periods by construction; counting sign
        // changes of their samples over-counts at small L̄, where κ_g is nearly constant and
        // its tiny wiggles cross the mean many times (branch 2 at L̄ = 0.1 was given 5,376
        // cells).
        match self {
            StartShape::Euler { l } => return Ok((*l as usize).max(1)),
            StartShape::Exact { eta } => return Ok((*eta as usize).max(1)),
            StartShape::Profile(_) => {}
        }
        let t = self.interpolant(lbar)?;
        let m = 1024;
        let mean = t.mean();
        let v: Vec<f64> = (0..m).map(|i| t.eval(i as f64 / m as f64) - mean).collect();
        let scale = v.iter().map(|x| x.abs()).fold(0.0, f64::max);
        // Ignore wiggles below 1e-3 of the amplitude (noise of a point-cloud start).
        let thr = 1e-3 * scale;
        let mut last = 0.0;
        let mut changes = 0;
        // Two passes: the first only primes `last`, so the wrap-around crossing counts.
        for i in 0..2 * m {
            let x = v[i % m];
            if x.abs() > thr {
                if i >= m && last != 0.0 && (x > 0.0) != (last > 0.0) {
                    changes += 1;
                }
                last = x;
            }
        }
        Ok((changes / 2).max(1))
    }

    /// `κ_g` at the Gauss points of `model` (dimensional: `κ_g R / R`).
    pub fn gauss_values(&self, model: &SurfaceModel) -> Result<Vec<f64>, SolverError> {
        let t = self.interpolant(model.lbar())?;
        let r = model.radius();
        Ok(t.eval_many(&model.gauss_sigma())
            .iter()
            .map(|&v| v / r)
            .collect())
    }
}

/// Geodesic curvature of a closed curve given by points (in order, not repeated at the end)
/// on or near a sphere centred at the origin.
///
/// The points are projected radially onto the sphere of radius `ρ` = their mean distance
/// from the origin, interpolated by periodic cubic splines in the normalised chord-length
/// parameter, and `κ_g = (n × r_u)·r_uu/|r_u|³` is resampled uniformly in arclength
/// (arclength by 4-point Gauss–Legendre quadrature per interval). Returns the dimensionless
/// profile `κ_g ρ` as a [`StartShape::Profile`], the length `L̄ = L/(2πρ)` and `ρ`.
/// Accuracy is that of the splines (`O(Δ²)` in `κ_g`): enough for a Newton start.
pub fn from_points(points: &[[f64; 3]]) -> Result<(StartShape, f64, f64), SolverError> {
    let mut pts: Vec<[f64; 3]> = points.to_vec();
    if pts.len() >= 2 {
        let (a, b) = (pts[0], pts[pts.len() - 1]);
        if (0..3).all(|k| (a[k] - b[k]).abs() <= 1e-14 * (1.0 + a[k].abs())) {
            pts.pop();
        }
    }
    let n = pts.len();
    if n < 8 {
        return Err(SolverError::InvalidInput(format!(
            "a closed curve needs at least 8 points (got {n})"
        )));
    }
    if pts.iter().flatten().any(|v| !v.is_finite()) {
        return Err(SolverError::InvalidInput(
            "point coordinates must be finite".into(),
        ));
    }
    let rho = pts
        .iter()
        .map(|p| (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt())
        .sum::<f64>()
        / n as f64;
    if rho.is_nan() || rho <= 0.0 {
        return Err(SolverError::InvalidInput(
            "points must not all lie at the origin".into(),
        ));
    }
    let proj: Vec<[f64; 3]> = pts
        .iter()
        .map(|p| {
            let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
            [p[0] * rho / r, p[1] * rho / r, p[2] * rho / r]
        })
        .collect();
    let chord: Vec<f64> = (0..n)
        .map(|i| {
            let (a, b) = (proj[i], proj[(i + 1) % n]);
            ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
        })
        .collect();
    if let Some(i) = chord.iter().position(|&c| c <= 0.0) {
        return Err(SolverError::InvalidInput(format!(
            "points {} and {} coincide",
            i + 1,
            (i + 1) % n + 1
        )));
    }
    let total: f64 = chord.iter().sum();
    let mut u = Vec::with_capacity(n);
    let mut acc = 0.0;
    for c in &chord {
        u.push(acc / total);
        acc += c;
    }
    let coords: Vec<Vec<f64>> = (0..3)
        .map(|k| proj.iter().map(|p| p[k]).collect())
        .collect();
    let moments: Vec<Vec<f64>> = coords
        .iter()
        .map(|c| periodic_spline_moments(&u, c))
        .collect();
    let deriv = |x: f64| {
        let mut r = [0.0; 3];
        let mut r1 = [0.0; 3];
        let mut r2 = [0.0; 3];
        for k in 0..3 {
            let v = eval_periodic_spline(&u, &coords[k], &moments[k], x - x.floor());
            r[k] = v.d;
            r1[k] = v.d1;
            r2[k] = v.d2;
        }
        (r, r1, r2)
    };
    let speed = |x: f64| {
        let (_, r1, _) = deriv(x);
        (r1[0] * r1[0] + r1[1] * r1[1] + r1[2] * r1[2]).sqrt()
    };
    // Cumulative arclength at the knots by 4-point Gauss–Legendre per interval.
    let gl = [
        (-0.861_136_311_594_052_6, 0.347_854_845_137_453_85),
        (-0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
        (0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
        (0.861_136_311_594_052_6, 0.347_854_845_137_453_85),
    ];
    let knot = |i: usize| if i < n { u[i] } else { 1.0 };
    let seg_len = |a: f64, b: f64| {
        let (m, hw) = (0.5 * (a + b), 0.5 * (b - a));
        gl.iter().map(|(x, w)| w * speed(m + hw * x)).sum::<f64>() * hw
    };
    let mut cum = vec![0.0; n + 1];
    for i in 0..n {
        cum[i + 1] = cum[i] + seg_len(knot(i), knot(i + 1));
    }
    let length = cum[n];
    let m = (4 * n).max(256);
    let mut kg = Vec::with_capacity(m);
    for j in 0..m {
        let target = length * j as f64 / m as f64;
        let i = cum.partition_point(|&c| c <= target).clamp(1, n) - 1;
        // Newton (safeguarded) for s(x) = target inside [u_i, u_{i+1}].
        let (mut lo, mut hi) = (knot(i), knot(i + 1));
        let mut x = lo + (hi - lo) * (target - cum[i]) / (cum[i + 1] - cum[i]).max(1e-300);
        for _ in 0..50 {
            let f = cum[i] + seg_len(knot(i), x) - target;
            if f > 0.0 {
                hi = x;
            } else {
                lo = x;
            }
            let mut next = x - f / speed(x);
            if !(next > lo && next < hi) {
                next = 0.5 * (lo + hi);
            }
            if (next - x).abs() < 1e-15 {
                break;
            }
            x = next;
        }
        let (r, r1, r2) = deriv(x);
        let nv = [r[0] / rho, r[1] / rho, r[2] / rho];
        let cr = [
            nv[1] * r1[2] - nv[2] * r1[1],
            nv[2] * r1[0] - nv[0] * r1[2],
            nv[0] * r1[1] - nv[1] * r1[0],
        ];
        let sp = (r1[0] * r1[0] + r1[1] * r1[1] + r1[2] * r1[2]).sqrt();
        let k = (cr[0] * r2[0] + cr[1] * r2[1] + cr[2] * r2[2]) / (sp * sp * sp);
        kg.push(k * rho);
    }
    let lbar = length / (2.0 * PI * rho);
    Ok((StartShape::Profile(TrigInterpolant::new(&kg)?), lbar, rho))
}
