//! Trigonometric interpolation of periodic samples (period 1 in `σ = s/L`).
//!
//! Used to move geodesic-curvature profiles between grids (starting shapes, resampling an
//! equilibrium to another resolution), to differentiate them spectrally (phase condition,
//! arclength-shift mode) and to locate extrema of output profiles between grid points.

use std::f64::consts::PI;

use crate::SolverError;

/// Trigonometric interpolant of `M` samples `y_j` at `σ_j = offset + j/M`:
/// `y(σ) = a_0 + Σ_{k=1}^{K} a_k cos 2πk(σ − offset) + b_k sin 2πk(σ − offset)`, `K = ⌊(M−1)/2⌋`.
///
/// For even `M` the Nyquist mode `cos πM(σ − offset)` is dropped (it has no well-defined
/// derivative); for well-resolved smooth data its amplitude is negligible.
#[derive(Clone, Debug, PartialEq)]
pub struct TrigInterpolant {
    offset: f64,
    a0: f64,
    a: Vec<f64>,
    b: Vec<f64>,
}

impl TrigInterpolant {
    /// Interpolant of samples at `σ_j = j/M`.
    pub fn new(samples: &[f64]) -> Result<Self, SolverError> {
        Self::with_offset(samples, 0.0)
    }

    /// Interpolant of samples at `σ_j = offset + j/M`.
    pub fn with_offset(samples: &[f64], offset: f64) -> Result<Self, SolverError> {
        let m = samples.len();
        if m == 0 {
            return Err(SolverError::InvalidInput(
                "cannot interpolate an empty profile".into(),
            ));
        }
        if let Some(v) = samples.iter().find(|v| !v.is_finite()) {
            return Err(SolverError::InvalidInput(format!(
                "profile sample is not finite ({v})"
            )));
        }
        let k_max = (m - 1) / 2;
        let table: Vec<(f64, f64)> = (0..m)
            .map(|j| (2.0 * PI * j as f64 / m as f64).sin_cos())
            .collect();
        let a0 = samples.iter().sum::<f64>() / m as f64;
        let mut a = vec![0.0; k_max];
        let mut b = vec![0.0; k_max];
        for k in 1..=k_max {
            let (mut sa, mut sb) = (0.0, 0.0);
            // `at` runs through (k j) mod m without a division per sample.
            let mut at = 0;
            for y in samples {
                let (s, c) = table[at];
                sa += y * c;
                sb += y * s;
                at += k;
                if at >= m {
                    at -= m;
                }
            }
            a[k - 1] = 2.0 * sa / m as f64;
            b[k - 1] = 2.0 * sb / m as f64;
        }
        Ok(Self { offset, a0, a, b })
    }

    /// Value, first and second derivative in `σ` at `σ`.
    pub fn eval_all(&self, sigma: f64) -> (f64, f64, f64) {
        let x = 2.0 * PI * (sigma - self.offset);
        let (s1, c1) = x.sin_cos();
        let (mut s, mut c) = (s1, c1);
        let (mut v, mut d1, mut d2) = (self.a0, 0.0, 0.0);
        for k in 0..self.a.len() {
            let w = 2.0 * PI * (k + 1) as f64;
            let (ak, bk) = (self.a[k], self.b[k]);
            v += ak * c + bk * s;
            d1 += w * (-ak * s + bk * c);
            d2 -= w * w * (ak * c + bk * s);
            // Angle addition: (c, s) ← (c c1 − s s1, s c1 + c s1). Re-seed now and then to
            // keep the rounding drift at the level of a few ulps.
            if (k + 1) % 64 == 0 {
                let (sn, cn) = ((k + 2) as f64 * x).sin_cos();
                s = sn;
                c = cn;
            } else {
                let cn = c * c1 - s * s1;
                s = s * c1 + c * s1;
                c = cn;
            }
        }
        (v, d1, d2)
    }

    /// Value at `σ`.
    pub fn eval(&self, sigma: f64) -> f64 {
        self.eval_all(sigma).0
    }

    /// Derivative `dy/dσ` at `σ`.
    pub fn derivative(&self, sigma: f64) -> f64 {
        self.eval_all(sigma).1
    }

    /// Mean value `a_0`.
    pub fn mean(&self) -> f64 {
        self.a0
    }

    /// Smallest and largest value over a period, located from `samples` dense samples and
    /// refined by Newton's method on the derivative: `((σ_min, y_min), (σ_max, y_max))`.
    pub fn extrema(&self, samples: usize) -> ((f64, f64), (f64, f64)) {
        let n = samples.max(8);
        let vals: Vec<f64> = (0..n).map(|i| self.eval(i as f64 / n as f64)).collect();
        let (mut imin, mut imax) = (0, 0);
        for i in 0..n {
            if vals[i] < vals[imin] {
                imin = i;
            }
            if vals[i] > vals[imax] {
                imax = i;
            }
        }
        let refine = |i: usize| {
            let h = 1.0 / n as f64;
            let mut x = i as f64 * h;
            for _ in 0..30 {
                let (_, d1, d2) = self.eval_all(x);
                if d2 == 0.0 {
                    break;
                }
                let step = (-d1 / d2).clamp(-h, h);
                x += step;
                if step.abs() < 1e-15 {
                    break;
                }
            }
            (x - x.floor(), self.eval(x))
        };
        let mut lo = refine(imin);
        let mut hi = refine(imax);
        // Newton may wander off to another stationary point: never report worse than sampled.
        if lo.1 > vals[imin] {
            lo = (imin as f64 / n as f64, vals[imin]);
        }
        if hi.1 < vals[imax] {
            hi = (imax as f64 / n as f64, vals[imax]);
        }
        (lo, hi)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolates_and_differentiates_smooth_periodic_data() {
        let f = |s: f64| (2.0 * PI * s).sin().exp() + 0.3 * (6.0 * PI * s).cos();
        let df = |s: f64| {
            (2.0 * PI * s).sin().exp() * 2.0 * PI * (2.0 * PI * s).cos()
                - 0.3 * 6.0 * PI * (6.0 * PI * s).sin()
        };
        for &(m, off) in &[(64usize, 0.0), (65, 0.013)] {
            let y: Vec<f64> = (0..m).map(|j| f(off + j as f64 / m as f64)).collect();
            let t = TrigInterpolant::with_offset(&y, off).unwrap();
            for &s in &[0.0, 0.123, 0.5, 0.77] {
                assert!((t.eval(s) - f(s)).abs() < 1e-12);
                assert!((t.derivative(s) - df(s)).abs() < 1e-10);
            }
        }
        let y: Vec<f64> = (0..64)
            .map(|j| (2.0 * PI * j as f64 / 64.0 - 1.0).cos())
            .collect();
        let t = TrigInterpolant::new(&y).unwrap();
        let ((smin, vmin), (smax, vmax)) = t.extrema(64);
        assert!((vmin + 1.0).abs() < 1e-14 && (vmax - 1.0).abs() < 1e-14);
        assert!((smax - 1.0 / (2.0 * PI)).abs() < 1e-10);
        assert!((smin - (0.5 + 1.0 / (2.0 * PI))).abs() < 1e-10);
    }
}
