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
        // [`EVAL_LANES`] harmonics summed side by side (independent sums, each in the order
        // of the samples).
        const L: usize = EVAL_LANES;
        for k0 in (1..=k_max).step_by(L) {
            let lanes = L.min(k_max + 1 - k0);
            let (mut sa, mut sb) = ([0.0f64; L], [0.0f64; L]);
            // `at` runs through (k j) mod m without a division per sample.
            let mut at = [0usize; L];
            for y in samples {
                for l in 0..lanes {
                    let (s, c) = table[at[l]];
                    sa[l] += y * c;
                    sb[l] += y * s;
                    at[l] += k0 + l;
                    if at[l] >= m {
                        at[l] -= m;
                    }
                }
            }
            for l in 0..lanes {
                a[k0 + l - 1] = 2.0 * sa[l] / m as f64;
                b[k0 + l - 1] = 2.0 * sb[l] / m as f64;
            }
        }
        Ok(Self { offset, a0, a, b })
    }

    /// The interpolant of `σ ↦ y(σ + shift)`: the same coefficients about the origin moved
    /// by `−shift` (a translate of a trigonometric polynomial is the polynomial of the same
    /// degree with its phases turned, so nothing is resampled).
    pub fn moved(&self, shift: f64) -> Self {
        Self {
            offset: self.offset - shift,
            ..self.clone()
        }
    }

    /// Value, first and second derivative in `σ` at `σ`.
    pub fn eval_all(&self, sigma: f64) -> (f64, f64, f64) {
        let x = 2.0 * PI * (sigma - self.offset);
        let (mut v, mut d1, mut d2) = (self.a0, 0.0, 0.0);
        harmonics(x, self.a.len(), |k, c, s| {
            let w = 2.0 * PI * (k + 1) as f64;
            let (ak, bk) = (self.a[k], self.b[k]);
            v += ak * c + bk * s;
            d1 += w * (-ak * s + bk * c);
            d2 -= w * w * (ak * c + bk * s);
        });
        (v, d1, d2)
    }

    /// Value at `σ` (the value of [`TrigInterpolant::eval_all`], bit for bit: the same
    /// angle-addition sequence, without the derivatives).
    pub fn eval(&self, sigma: f64) -> f64 {
        let mut v = self.a0;
        let x = 2.0 * PI * (sigma - self.offset);
        harmonics(x, self.a.len(), |k, c, s| {
            v += self.a[k] * c + self.b[k] * s;
        });
        v
    }

    /// Values at every `σ` of `sigmas`: those of [`TrigInterpolant::eval`], bit for bit
    /// (each value sees the same operations in the same order). `EVAL_LANES` points are
    /// evaluated side by side, so that their angle-addition recurrences, each a chain of
    /// dependent products, overlap instead of waiting on each other.
    pub fn eval_many(&self, sigmas: &[f64]) -> Vec<f64> {
        const L: usize = EVAL_LANES;
        let count = self.a.len();
        let mut out = Vec::with_capacity(sigmas.len());
        for chunk in sigmas.chunks(L) {
            let n = chunk.len();
            let mut x = [0.0f64; L];
            let (mut s1, mut c1) = ([0.0f64; L], [1.0f64; L]);
            for (l, &sigma) in chunk.iter().enumerate() {
                x[l] = 2.0 * PI * (sigma - self.offset);
                (s1[l], c1[l]) = x[l].sin_cos();
            }
            let (mut s, mut c) = (s1, c1);
            let mut v = [self.a0; L];
            for k in 0..count {
                let (ak, bk) = (self.a[k], self.b[k]);
                for l in 0..L {
                    v[l] += ak * c[l] + bk * s[l];
                }
                if (k + 1) % 64 == 0 {
                    for l in 0..L {
                        (s[l], c[l]) = ((k + 2) as f64 * x[l]).sin_cos();
                    }
                } else {
                    for l in 0..L {
                        let cn = c[l] * c1[l] - s[l] * s1[l];
                        s[l] = s[l] * c1[l] + c[l] * s1[l];
                        c[l] = cn;
                    }
                }
            }
            out.extend_from_slice(&v[..n]);
        }
        out
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

/// The trigonometric interpolants ([`TrigInterpolant`]) of several columns of samples at the
/// same points `σ_j = j/M` (e.g. the quantities of one profile), built and evaluated
/// together: the sine table, the harmonics `cos 2πkσ`, `sin 2πkσ` and the loops are shared,
/// and the coefficients are stored harmonic by harmonic. Every value equals the
/// [`TrigInterpolant::eval`] of its column bit for bit (the same sums in the same order).
#[derive(Clone, Debug, PartialEq)]
pub struct TrigColumns {
    columns: usize,
    a0: Vec<f64>,
    /// `(a_k, b_k)` of every column, for `k = 1..=K` in turn: `ab[2 (k−1) C + 2 i]`.
    ab: Vec<f64>,
}

impl TrigColumns {
    /// The interpolants of `columns` (each of the same length `M`, at `σ_j = j/M`).
    pub fn new(columns: &[Vec<f64>]) -> Result<Self, SolverError> {
        let m = columns.first().map_or(0, Vec::len);
        if m == 0 {
            return Err(SolverError::InvalidInput(
                "cannot interpolate an empty profile".into(),
            ));
        }
        if columns.iter().any(|c| c.len() != m) {
            return Err(SolverError::InvalidInput(
                "the columns of a profile differ in length".into(),
            ));
        }
        if let Some(v) = columns.iter().flatten().find(|v| !v.is_finite()) {
            return Err(SolverError::InvalidInput(format!(
                "profile sample is not finite ({v})"
            )));
        }
        let nc = columns.len();
        let k_max = (m - 1) / 2;
        let table: Vec<(f64, f64)> = (0..m)
            .map(|j| (2.0 * PI * j as f64 / m as f64).sin_cos())
            .collect();
        let a0 = columns
            .iter()
            .map(|c| c.iter().sum::<f64>() / m as f64)
            .collect();
        let mut ab = vec![0.0; 2 * k_max * nc];
        let mut sums = vec![(0.0, 0.0); nc];
        for k in 1..=k_max {
            sums.fill((0.0, 0.0));
            let mut at = 0;
            for j in 0..m {
                let (s, c) = table[at];
                for (sum, col) in sums.iter_mut().zip(columns) {
                    let y = col[j];
                    sum.0 += y * c;
                    sum.1 += y * s;
                }
                at += k;
                if at >= m {
                    at -= m;
                }
            }
            let row = &mut ab[2 * (k - 1) * nc..2 * k * nc];
            for (i, &(sa, sb)) in sums.iter().enumerate() {
                row[2 * i] = 2.0 * sa / m as f64;
                row[2 * i + 1] = 2.0 * sb / m as f64;
            }
        }
        Ok(Self {
            columns: nc,
            a0,
            ab,
        })
    }

    /// The values of every column at `σ`, into `out` (of one value per column).
    pub fn eval(&self, sigma: f64, out: &mut [f64]) {
        let nc = self.columns;
        out[..nc].copy_from_slice(&self.a0);
        let x = 2.0 * PI * sigma;
        let k_max = if nc == 0 { 0 } else { self.ab.len() / (2 * nc) };
        harmonics(x, k_max, |k, c, s| {
            let row = &self.ab[2 * k * nc..2 * (k + 1) * nc];
            for (o, ab) in out[..nc].iter_mut().zip(row.chunks_exact(2)) {
                *o += ab[0] * c + ab[1] * s;
            }
        });
    }
}

/// Points evaluated side by side by [`TrigInterpolant::eval_many`].
const EVAL_LANES: usize = 4;

/// Calls `f(k, cos (k+1)x, sin (k+1)x)` for `k = 0..count`, by angle addition
/// `(c, s) ← (c c1 − s s1, s c1 + c s1)`, re-seeded from `sin_cos` every 64 harmonics to keep
/// the rounding drift at the level of a few ulps (one sequence for every evaluation, so that
/// [`TrigInterpolant::eval`], [`TrigInterpolant::eval_all`] and
/// [`TrigInterpolant::eval_columns`] agree bit for bit).
#[inline]
pub(crate) fn harmonics(x: f64, count: usize, mut f: impl FnMut(usize, f64, f64)) {
    let (s1, c1) = x.sin_cos();
    let (mut s, mut c) = (s1, c1);
    for k in 0..count {
        f(k, c, s);
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
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The harmonics summed side by side give the coefficients of the plain sums, one
    /// harmonic at a time in the order of the samples, bit for bit (fewer harmonics than
    /// lanes, and a count that is not a multiple of them).
    #[test]
    fn coefficients_are_the_plain_sums_bit_for_bit() {
        for m in [5, 8, 301] {
            let samples: Vec<f64> = (0..m)
                .map(|j| ((j * j) as f64 * 0.37).sin() + 0.1 * j as f64)
                .collect();
            let t = TrigInterpolant::new(&samples).unwrap();
            for k in 1..=(m - 1) / 2 {
                let (mut sa, mut sb) = (0.0, 0.0);
                for (j, y) in samples.iter().enumerate() {
                    let (s, c) = (2.0 * PI * ((k * j) % m) as f64 / m as f64).sin_cos();
                    sa += y * c;
                    sb += y * s;
                }
                assert_eq!(t.a[k - 1].to_bits(), (2.0 * sa / m as f64).to_bits());
                assert_eq!(t.b[k - 1].to_bits(), (2.0 * sb / m as f64).to_bits());
            }
        }
    }

    /// `eval_many` gives the values of `eval` bit for bit, past the re-seeding of the
    /// harmonics (more than 64) and for a count of points that is not a multiple of the
    /// lanes.
    #[test]
    fn eval_many_matches_eval_bit_for_bit() {
        let f = |s: f64| (2.0 * PI * s).sin().exp() + 0.3 * (14.0 * PI * s).cos();
        for m in [7, 301] {
            let samples: Vec<f64> = (0..m).map(|j| f(j as f64 / m as f64)).collect();
            let t = TrigInterpolant::with_offset(&samples, 0.013).unwrap();
            assert_eq!(t.a.len(), (m - 1) / 2);
            let sigmas: Vec<f64> = (0..1003).map(|j| -0.4 + j as f64 * 0.0017).collect();
            let many = t.eval_many(&sigmas);
            assert_eq!(many.len(), sigmas.len());
            for (&sg, &v) in sigmas.iter().zip(&many) {
                assert_eq!(v.to_bits(), t.eval(sg).to_bits(), "m = {m}, σ = {sg}");
            }
        }
    }

    /// The moved interpolant is the interpolant of the shifted samples: a trigonometric
    /// polynomial of degree 5 (exactly representable on 64 samples) moved by `0.137` equals,
    /// to rounding, the interpolant built from its samples at `j/M + 0.137` and its own
    /// values at `σ + 0.137`; a smooth periodic function moved by `−0.41` still interpolates
    /// the function at the shifted points.
    #[test]
    fn moved_is_the_interpolant_of_the_shifted_samples() {
        let p = |s: f64| {
            0.7 + (2.0 * PI * s).cos() - 0.4 * (6.0 * PI * s).sin() + 0.2 * (10.0 * PI * s).cos()
        };
        let m = 64;
        let y: Vec<f64> = (0..m).map(|j| p(j as f64 / m as f64)).collect();
        let t = TrigInterpolant::new(&y).unwrap();
        let shift = 0.137;
        let moved = t.moved(shift);
        let ys: Vec<f64> = (0..m).map(|j| p(j as f64 / m as f64 + shift)).collect();
        let resampled = TrigInterpolant::new(&ys).unwrap();
        for j in 0..200 {
            let s = j as f64 / 200.0 - 0.3;
            assert!((moved.eval(s) - resampled.eval(s)).abs() < 1e-13, "σ = {s}");
            assert!((moved.eval(s) - t.eval(s + shift)).abs() < 1e-13, "σ = {s}");
            assert!((moved.eval(s) - p(s + shift)).abs() < 1e-13, "σ = {s}");
            let (v, d, dd) = moved.eval_all(s);
            let (v0, d0, dd0) = t.eval_all(s + shift);
            assert!((v - v0).abs() < 1e-13 && (d - d0).abs() < 1e-11 && (dd - dd0).abs() < 1e-9);
        }
        let f = |s: f64| (2.0 * PI * s).sin().exp();
        let y: Vec<f64> = (0..65).map(|j| f(j as f64 / 65.0)).collect();
        let moved = TrigInterpolant::new(&y).unwrap().moved(-0.41);
        for &s in &[0.0, 0.123, 0.5, 0.77] {
            assert!((moved.eval(s) - f(s - 0.41)).abs() < 1e-12);
        }
    }

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
    /// The columns built and evaluated together give each column's own interpolant bit for
    /// bit, and the value-only `eval` is the value of `eval_all`; both interpolate the data.
    #[test]
    fn columns_and_values_match_the_single_interpolant_exactly() {
        let m = 301;
        let cols: Vec<Vec<f64>> = (0..3)
            .map(|c| {
                (0..m)
                    .map(|j| {
                        let s = j as f64 / m as f64;
                        (2.0 * PI * (c + 1) as f64 * s).sin().exp() + 0.1 * c as f64
                    })
                    .collect()
            })
            .collect();
        let together = TrigColumns::new(&cols).unwrap();
        let single: Vec<TrigInterpolant> = cols
            .iter()
            .map(|c| TrigInterpolant::new(c).unwrap())
            .collect();
        let mut out = [0.0; 3];
        for &s in &[0.0, 0.0123, 0.31, 0.5, 0.999, 1.7] {
            together.eval(s, &mut out);
            for (c, t) in single.iter().enumerate() {
                assert_eq!(out[c].to_bits(), t.eval(s).to_bits());
                assert_eq!(t.eval(s).to_bits(), t.eval_all(s).0.to_bits());
            }
        }
        together.eval(7.0 / m as f64, &mut out);
        for c in 0..3 {
            assert!((out[c] - cols[c][7]).abs() < 1e-12);
        }
        assert!(TrigColumns::new(&[vec![1.0; 4], vec![1.0; 5]]).is_err());
    }
}
