//! Bending-stiffness profiles `D(s)` along the loop.
//!
//! Every profile is a periodic function of the normalised arclength `σ = s/L ∈ [0, 1)`, so a
//! profile stays attached to the material when the loop length changes (continuation in
//! `L̄`). Derivatives with respect to the arclength `s` follow from `d/ds = (1/L) d/dσ`.

use crate::SolverError;

/// Bending stiffness `D(s)` of the rod.
#[derive(Clone, Debug, PartialEq)]
pub enum Stiffness {
    /// Homogeneous rod, `D(s) = d`.
    Uniform {
        /// The stiffness `D`.
        d: f64,
    },
    /// Two-segment profile of Eq. (51):
    /// `D(s) = D0 − (D0 − D1)/2 [tanh(γ(s − s0*)/L) − tanh(γ(s − s1*)/L)]`,
    /// soft segment `s0* < s < s1*`.
    ///
    /// Eq. (51) is not exactly periodic on `[0, L)`; we use its periodic extension by images,
    /// `Σ_{j=−2}^{2}` of the bracket at `σ + j`, which differs from Eq. (51) on `[0, 1)` by at
    /// most `≈ 4 e^{−2γ δ}` relative, `δ = min(σ0, 1 − σ1)` (≈ 1e-52 for the paper's
    /// `γ = 200, σ0 = 0.3, σ1 = 0.8`), and makes `D` smooth across `s = 0`.
    Tanh {
        /// Stiffness `D0` of the stiffer segment.
        d0: f64,
        /// Stiffness `D1` of the softer segment.
        d1: f64,
        /// Start of the soft segment, `s0*/L`.
        s0: f64,
        /// End of the soft segment, `s1*/L`.
        s1: f64,
        /// Sharpness `γ` of the transitions.
        gamma: f64,
    },
    /// A user table `(s/L, D)` interpolated by a shape-preserving periodic cubic Hermite
    /// interpolant (period 1; Fritsch–Carlson type, slopes by the weighted harmonic mean of
    /// Fritsch & Butland): between two table points `D` is monotone, so it never leaves the
    /// range of its two end values (no overshoot; a positive table gives a positive `D`), and
    /// a local extremum of the data stays an extremum. `D` and `D'` are continuous; `D''` is
    /// piecewise linear and may jump at the table points. The abscissae must be strictly
    /// increasing in `[0, 1)`; at least three points, or one point (constant).
    Table {
        /// Abscissae `s/L ∈ [0, 1)`, strictly increasing.
        s: Vec<f64>,
        /// Stiffness values at those abscissae.
        d: Vec<f64>,
    },
}

/// `D`, `dD/dσ`, `d²D/dσ²` at one point (`σ = s/L`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StiffnessValue {
    /// `D`.
    pub d: f64,
    /// `dD/dσ`.
    pub d1: f64,
    /// `d²D/dσ²`.
    pub d2: f64,
}

impl StiffnessValue {
    /// Convert the σ-derivatives to arclength derivatives for a loop of length `length`:
    /// returns `(D, D'(s), D''(s))`.
    pub fn per_arclength(&self, length: f64) -> (f64, f64, f64) {
        (self.d, self.d1 / length, self.d2 / (length * length))
    }
}

/// A validated stiffness profile, ready for evaluation (interpolant slopes precomputed).
#[derive(Clone, Debug, PartialEq)]
pub struct StiffnessProfile {
    kind: Stiffness,
    /// Slopes `dD/dσ` of the shape-preserving interpolant at the table knots (tables only).
    slopes: Vec<f64>,
}

/// The profile in words, as a report or a summary shows it: `uniform D = 1`,
/// `two-segment (Eq. 51): D0 = 1, D1 = 0.5, s0*/L = 0.3, s1*/L = 0.8, γ = 200`,
/// `table of 5 points (s/L, D), D from 0.2 to 1`.
impl std::fmt::Display for Stiffness {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Stiffness::Uniform { d } => write!(f, "uniform D = {d}"),
            Stiffness::Tanh {
                d0,
                d1,
                s0,
                s1,
                gamma,
            } => write!(
                f,
                "two-segment (Eq. 51): D0 = {d0}, D1 = {d1}, s0*/L = {s0}, s1*/L = {s1}, γ = {gamma}"
            ),
            Stiffness::Table { s, d } => {
                let (lo, hi) = d
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                        (a.min(v), b.max(v))
                    });
                write!(
                    f,
                    "table of {} points (s/L, D), D from {lo} to {hi}",
                    s.len()
                )
            }
        }
    }
}

impl Stiffness {
    /// Homogeneous stiffness `d`.
    pub fn uniform(d: f64) -> Self {
        Stiffness::Uniform { d }
    }

    /// The two-segment rod of the paper's Sec. 5 (Eq. (51), Figs. 8–10, S6–S7): `D0 = 1`, a
    /// softer segment `s0*/L = 0.3 < s/L < s1*/L = 0.8` of stiffness `D1 = d1` (the paper
    /// takes `D1/D0 = 0.001, 0.1, 0.5`) and transitions of sharpness `γ = 200`.
    pub fn paper_sec5(d1: f64) -> Self {
        Stiffness::Tanh {
            d0: 1.0,
            d1,
            s0: 0.3,
            s1: 0.8,
            gamma: 200.0,
        }
    }

    /// `true` for the homogeneous rod (the arclength shift is then a symmetry).
    pub fn is_uniform(&self) -> bool {
        match self {
            Stiffness::Uniform { .. } => true,
            Stiffness::Table { d, .. } => d.iter().all(|&v| v == d[0]),
            Stiffness::Tanh { d0, d1, .. } => d0 == d1,
        }
    }

    /// The value of a named scene parameter of this profile (`d1` = `D1/D0`, `gamma`, `s0`,
    /// `s1`; Eq. (51) profiles only).
    pub fn param(&self, p: crate::param::Param) -> Result<f64, SolverError> {
        use crate::param::Param;
        match (self, p) {
            (Stiffness::Tanh { d0, d1, .. }, Param::D1) => Ok(d1 / d0),
            (Stiffness::Tanh { gamma, .. }, Param::Gamma) => Ok(*gamma),
            (Stiffness::Tanh { s0, .. }, Param::S0) => Ok(*s0),
            (Stiffness::Tanh { s1, .. }, Param::S1) => Ok(*s1),
            (_, Param::Lbar) => Err(SolverError::InvalidInput(
                "lbar is a parameter of the model, not of the stiffness profile".into(),
            )),
            (_, p) => Err(SolverError::InvalidInput(format!(
                "parameter {} needs a two-segment (tanh, Eq. (51)) stiffness profile",
                p.name()
            ))),
        }
    }

    /// The same profile with a named parameter set to `value` (validated by
    /// [`Stiffness::validate`] when a model is built).
    pub fn with_param(&self, p: crate::param::Param, value: f64) -> Result<Self, SolverError> {
        use crate::param::Param;
        self.param(p)?;
        let mut out = self.clone();
        if let Stiffness::Tanh {
            d0,
            d1,
            s0,
            s1,
            gamma,
        } = &mut out
        {
            match p {
                Param::D1 => *d1 = value * *d0,
                Param::Gamma => *gamma = value,
                Param::S0 => *s0 = value,
                Param::S1 => *s1 = value,
                Param::Lbar => {}
            }
        }
        Ok(out)
    }

    /// `∂D/∂θ` at `σ` for a named parameter `θ` of an Eq. (51) profile (analytic; `θ = d1`
    /// is `D1/D0`, so `∂D/∂θ = D0 ∂D/∂D1`).
    pub fn dparam(&self, p: crate::param::Param, sigma: f64) -> Result<f64, SolverError> {
        use crate::param::Param;
        self.param(p)?;
        let Stiffness::Tanh {
            d0,
            d1,
            s0,
            s1,
            gamma,
        } = self
        else {
            return Ok(0.0);
        };
        let sigma = sigma - sigma.floor();
        let half = 0.5 * (d0 - d1);
        let mut bracket = 0.0;
        let mut acc = 0.0;
        for j in -2..=2 {
            let x = sigma + j as f64;
            for (sign, c, which) in [(1.0, *s0, Param::S0), (-1.0, *s1, Param::S1)] {
                let t = (gamma * (x - c)).tanh();
                let sech2 = 1.0 - t * t;
                bracket += sign * t;
                acc += match p {
                    Param::Gamma => sign * (x - c) * sech2,
                    q if q == which => -sign * gamma * sech2,
                    _ => 0.0,
                };
            }
        }
        Ok(match p {
            // D = D0 − (D0 − D1)/2 · bracket ⇒ ∂D/∂D1 = bracket/2.
            Param::D1 => d0 * 0.5 * bracket,
            _ => -half * acc,
        })
    }

    /// Reference stiffness `D0` used to normalise energies (`E R/(π D0)`) and forces: `d` for
    /// uniform rods, `D0` (the stiffer segment) for Eq. (51), the largest value of a table.
    pub fn reference(&self) -> f64 {
        match self {
            Stiffness::Uniform { d } => *d,
            Stiffness::Tanh { d0, .. } => *d0,
            Stiffness::Table { d, .. } => d.iter().copied().fold(f64::MIN, f64::max),
        }
    }

    /// Validate the parameters and precompute the interpolant.
    ///
    /// Errors ([`SolverError::InvalidProfile`]): non-finite numbers, `D ≤ 0` anywhere (the
    /// table interpolant cannot undershoot, but the check on a fine sampling is kept), `s0* ≥ s1*`,
    /// `s0*, s1*` outside `[0, 1]`, `γ ≤ 0`, table abscissae not strictly increasing in
    /// `[0, 1)`, mismatched table lengths, or a table of two points.
    pub fn validate(&self) -> Result<StiffnessProfile, SolverError> {
        let bad = |m: String| Err(SolverError::InvalidProfile(m));
        match self {
            Stiffness::Uniform { d } => {
                if !(d.is_finite() && *d > 0.0) {
                    return bad(format!(
                        "uniform stiffness must be positive and finite (got {d})"
                    ));
                }
                Ok(StiffnessProfile {
                    kind: self.clone(),
                    slopes: Vec::new(),
                })
            }
            Stiffness::Tanh {
                d0,
                d1,
                s0,
                s1,
                gamma,
            } => {
                let all = [*d0, *d1, *s0, *s1, *gamma];
                if all.iter().any(|v| !v.is_finite()) {
                    return bad(format!(
                        "tanh profile parameters must be finite (got {all:?})"
                    ));
                }
                if *d0 <= 0.0 || *d1 <= 0.0 {
                    return bad(format!(
                        "tanh profile needs D0 > 0 and D1 > 0 (got D0 = {d0}, D1 = {d1})"
                    ));
                }
                if !(0.0..=1.0).contains(s0) || !(0.0..=1.0).contains(s1) || s0 >= s1 {
                    return bad(format!(
                        "tanh profile needs 0 <= s0*/L < s1*/L <= 1 (got {s0}, {s1})"
                    ));
                }
                if *gamma <= 0.0 {
                    return bad(format!("tanh profile needs gamma > 0 (got {gamma})"));
                }
                let p = StiffnessProfile {
                    kind: self.clone(),
                    slopes: Vec::new(),
                };
                // The bracket of Eq. (51) summed over the images is a sum of positive terms
                // tanh(γ(x − s0*)) − tanh(γ(x − s1*)) (s0* < s1*) whose total stays below 2, so
                // D lies between min(D0, D1) and max(D0, D1): positive since both are (checked
                // above). No sampling needed (it cost a millisecond per model).
                Ok(p)
            }
            Stiffness::Table { s, d } => {
                if s.len() != d.len() {
                    return bad(format!(
                        "stiffness table has {} abscissae but {} values",
                        s.len(),
                        d.len()
                    ));
                }
                if s.is_empty() || s.len() == 2 {
                    return bad(format!(
                        "stiffness table needs one point (constant) or at least three (got {})",
                        s.len()
                    ));
                }
                if s.iter().chain(d.iter()).any(|v| !v.is_finite()) {
                    return bad("stiffness table contains a non-finite number".into());
                }
                if s[0] < 0.0 || s[s.len() - 1] >= 1.0 {
                    return bad(format!(
                        "stiffness table abscissae s/L must lie in [0, 1) (got {} .. {})",
                        s[0],
                        s[s.len() - 1]
                    ));
                }
                if let Some(i) = (1..s.len()).find(|&i| s[i] <= s[i - 1]) {
                    return bad(format!(
                        "stiffness table abscissae must increase strictly (row {}: {} after {})",
                        i + 1,
                        s[i],
                        s[i - 1]
                    ));
                }
                if let Some(v) = d.iter().find(|&&v| v <= 0.0) {
                    return bad(format!("stiffness table contains D = {v} <= 0"));
                }
                let slopes = if s.len() >= 3 {
                    monotone_slopes(s, d)
                } else {
                    vec![0.0]
                };
                let p = StiffnessProfile {
                    kind: self.clone(),
                    slopes,
                };
                p.check_positive()?;
                Ok(p)
            }
        }
    }
}

impl StiffnessProfile {
    /// The profile description.
    pub fn kind(&self) -> &Stiffness {
        &self.kind
    }

    fn check_positive(&self) -> Result<(), SolverError> {
        let n = 4096;
        for i in 0..n {
            let sigma = i as f64 / n as f64;
            let v = self.eval(sigma).d;
            if !(v > 0.0 && v.is_finite()) {
                return Err(SolverError::InvalidProfile(format!(
                    "stiffness profile is not positive: D = {v} at s/L = {sigma}"
                )));
            }
        }
        Ok(())
    }

    /// `D`, `dD/dσ`, `d²D/dσ²` at `σ = s/L` (any real `σ`; the profile has period 1).
    pub fn eval(&self, sigma: f64) -> StiffnessValue {
        let sigma = sigma - sigma.floor();
        match &self.kind {
            Stiffness::Uniform { d } => StiffnessValue {
                d: *d,
                d1: 0.0,
                d2: 0.0,
            },
            Stiffness::Tanh {
                d0,
                d1,
                s0,
                s1,
                gamma,
            } => {
                let half = 0.5 * (d0 - d1);
                let (mut v, mut v1, mut v2) = (0.0, 0.0, 0.0);
                for j in -2..=2 {
                    let x = sigma + j as f64;
                    for (sign, c) in [(1.0, *s0), (-1.0, *s1)] {
                        let t = (gamma * (x - c)).tanh();
                        let sech2 = 1.0 - t * t;
                        v += sign * t;
                        v1 += sign * gamma * sech2;
                        v2 += sign * (-2.0 * gamma * gamma * t * sech2);
                    }
                }
                // The images j = ±1, ±2 contribute ±(1 − 1) pairs plus exponentially small
                // tails; the sum over j of the brackets has period 1.
                StiffnessValue {
                    d: d0 - half * v,
                    d1: -half * v1,
                    d2: -half * v2,
                }
            }
            Stiffness::Table { s, d } => {
                if s.len() == 1 {
                    return StiffnessValue {
                        d: d[0],
                        d1: 0.0,
                        d2: 0.0,
                    };
                }
                eval_hermite(s, d, &self.slopes, sigma)
            }
        }
    }
}

/// Interval `i` (from knot `i` to knot `i + 1`, cyclically) containing `σ ∈ [0, 1)`, with the
/// offset from knot `i` and the interval length.
fn locate(s: &[f64], sigma: f64) -> (usize, f64, f64) {
    let n = s.len();
    // Last knot <= sigma; sigma below the first knot belongs to the wrap-around interval.
    let idx = s.partition_point(|&x| x <= sigma);
    if idx == 0 {
        let i = n - 1;
        let hi = s[0] + 1.0 - s[n - 1];
        (i, sigma + 1.0 - s[n - 1], hi)
    } else {
        let i = idx - 1;
        let next = if i + 1 < n { s[i + 1] } else { s[0] + 1.0 };
        (i, sigma - s[i], next - s[i])
    }
}

/// Slopes `m_i` at the knots of the periodic shape-preserving cubic Hermite interpolant:
/// with the secants `δ_{i−1}`, `δ_i` on either side (cyclically, period 1), `m_i = 0` where
/// they differ in sign or one vanishes (a local extremum of the data stays one), otherwise
/// the weighted harmonic mean `m_i = 3(h_{i−1} + h_i) / ((2h_i + h_{i−1})/δ_{i−1} +
/// (h_i + 2h_{i−1})/δ_i)` (Fritsch & Butland 1984), which lies between the two secants and
/// below `3 min(|δ_{i−1}|, |δ_i|)`, so each cubic piece is monotone (Fritsch & Carlson 1980).
pub(crate) fn monotone_slopes(s: &[f64], d: &[f64]) -> Vec<f64> {
    let n = s.len();
    let h = |i: usize| {
        if i + 1 < n {
            s[i + 1] - s[i]
        } else {
            s[0] + 1.0 - s[n - 1]
        }
    };
    let delta = |i: usize| (d[(i + 1) % n] - d[i]) / h(i);
    (0..n)
        .map(|i| {
            let im = (i + n - 1) % n;
            let (d0, d1) = (delta(im), delta(i));
            let (h0, h1) = (h(im), h(i));
            if d0 * d1 <= 0.0 {
                0.0
            } else {
                3.0 * (h0 + h1) / ((2.0 * h1 + h0) / d0 + (h1 + 2.0 * h0) / d1)
            }
        })
        .collect()
}

/// The cubic Hermite piece through the knots around `σ` with slopes `m`: `D`, `dD/dσ`,
/// `d²D/dσ²`.
fn eval_hermite(s: &[f64], d: &[f64], m: &[f64], sigma: f64) -> StiffnessValue {
    let n = s.len();
    let (i, x, h) = locate(s, sigma);
    let j = (i + 1) % n;
    let (y0, y1, m0, m1) = (d[i], d[j], m[i] * h, m[j] * h);
    let t = x / h;
    let (t2, t3) = (t * t, t * t * t);
    let v = (2.0 * t3 - 3.0 * t2 + 1.0) * y0
        + (t3 - 2.0 * t2 + t) * m0
        + (-2.0 * t3 + 3.0 * t2) * y1
        + (t3 - t2) * m1;
    let v1 = ((6.0 * t2 - 6.0 * t) * y0
        + (3.0 * t2 - 4.0 * t + 1.0) * m0
        + (-6.0 * t2 + 6.0 * t) * y1
        + (3.0 * t2 - 2.0 * t) * m1)
        / h;
    let v2 = ((12.0 * t - 6.0) * y0
        + (6.0 * t - 4.0) * m0
        + (-12.0 * t + 6.0) * y1
        + (6.0 * t - 2.0) * m1)
        / (h * h);
    StiffnessValue {
        d: v,
        d1: v1,
        d2: v2,
    }
}

/// The periodic cubic spline (used to resample point clouds, not for stiffness tables, where
/// it can overshoot).
pub(crate) fn eval_periodic_spline(s: &[f64], d: &[f64], m: &[f64], sigma: f64) -> StiffnessValue {
    let n = s.len();
    let (i, x, h) = locate(s, sigma);
    let j = (i + 1) % n;
    let (y0, y1, m0, m1) = (d[i], d[j], m[i], m[j]);
    let a = (h - x) / h;
    let b = x / h;
    let v = a * y0 + b * y1 + ((a * a * a - a) * m0 + (b * b * b - b) * m1) * h * h / 6.0;
    let v1 = (y1 - y0) / h + (-(3.0 * a * a - 1.0) * m0 + (3.0 * b * b - 1.0) * m1) * h / 6.0;
    let v2 = a * m0 + b * m1;
    StiffnessValue {
        d: v,
        d1: v1,
        d2: v2,
    }
}

/// Second derivatives `M_i` of the periodic cubic spline through `(s_i, d_i)`, period 1:
/// `h_{i−1} M_{i−1} + 2(h_{i−1} + h_i) M_i + h_i M_{i+1} = 6 (δ_i − δ_{i−1})` cyclically,
/// `δ_i = (d_{i+1} − d_i)/h_i`; solved densely (tables are short).
pub(crate) fn periodic_spline_moments(s: &[f64], d: &[f64]) -> Vec<f64> {
    let n = s.len();
    let hs: Vec<f64> = (0..n)
        .map(|i| {
            if i + 1 < n {
                s[i + 1] - s[i]
            } else {
                s[0] + 1.0 - s[n - 1]
            }
        })
        .collect();
    let slope = |i: usize| (d[(i + 1) % n] - d[i]) / hs[i];
    let mut a = nalgebra::DMatrix::<f64>::zeros(n, n);
    let mut rhs = nalgebra::DVector::<f64>::zeros(n);
    for i in 0..n {
        let im = (i + n - 1) % n;
        a[(i, im)] += hs[im];
        a[(i, i)] += 2.0 * (hs[im] + hs[i]);
        a[(i, (i + 1) % n)] += hs[i];
        rhs[i] = 6.0 * (slope(i) - slope(im));
    }
    // The matrix is strictly diagonally dominant, hence invertible.
    let lu = a.lu();
    lu.solve(&rhs)
        .map(|v| v.iter().copied().collect())
        .unwrap_or_else(|| vec![0.0; n])
}

#[cfg(test)]
mod tests;
