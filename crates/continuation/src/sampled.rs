//! A curve known only at sampled parameter values: its value between samples by linear
//! interpolation, with an error estimate from the curve's own second differences.
//!
//! Linear interpolation of a smooth `f` on `[x_a, x_b]` errs at `x` by
//! `½ f''(ξ) (x − x_a)(x_b − x)` for some `ξ` in the interval (the Lagrange remainder). The
//! estimate [`interpolate`] returns takes `|f''|` as the largest second divided difference
//! (`2 f[x_{i−1}, x_i, x_{i+1}]`) of the sample triples that share a sample with the
//! interval, plus the larger of the two samples' own error estimates: exact for a parabola,
//! and off by the change of `f''` over about two sample spacings otherwise (a second-order
//! estimate of a second-order error). Where the curve has
//! fewer than three samples, nothing is known of its curvature: the estimate is then half the
//! change of `f` across the interval (the interpolant's own variation), so that a
//! two-sample curve never looks more accurate than its chord.
//!
//! The caller labels states at one parameter value against other curves interpolated to it
//! ([`crate::exchange::label`]): the estimate is what makes a tie between a sampled state and
//! an interpolated one honest where samples are sparse.

/// One sample of a curve: parameter `x`, value `f`, and the error estimate of `f`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Parameter value.
    pub x: f64,
    /// Value there.
    pub f: f64,
    /// Error estimate of `f` (≥ 0).
    pub error: f64,
}

/// The value of the sampled curve at `x` and its error estimate (see the module docs), or
/// `None` outside `[x_first, x_last]`. `samples` must be sorted by `x`; a sample within
/// `1e-12` of `x` is returned with its own error.
pub fn interpolate(samples: &[Sample], x: f64) -> Option<(f64, f64)> {
    let (first, last) = (samples.first()?, samples.last()?);
    if x < first.x - 1e-12 || x > last.x + 1e-12 {
        return None;
    }
    if let Some(s) = samples.iter().find(|s| (s.x - x).abs() <= 1e-12) {
        return Some((s.f, s.error));
    }
    let k = samples.partition_point(|s| s.x < x);
    let (a, b) = (samples[k - 1], samples[k]);
    let t = (x - a.x) / (b.x - a.x);
    let f = a.f + t * (b.f - a.f);
    let own = a.error.max(b.error);
    // Second divided differences of the triples centred on a and on b.
    let curvature = [k.checked_sub(1), Some(k)]
        .into_iter()
        .flatten()
        .filter(|&i| i >= 1 && i + 1 < samples.len())
        .map(|i| 2.0 * second_difference(samples[i - 1], samples[i], samples[i + 1]).abs())
        .fold(None, |m: Option<f64>, c| Some(m.map_or(c, |m| m.max(c))));
    let remainder = match curvature {
        Some(c) => 0.5 * c * (x - a.x) * (b.x - x),
        None => 0.5 * (b.f - a.f).abs(),
    };
    Some((f, own + remainder))
}

/// `f[u, v, w]`, the second divided difference (`f''/2` of the parabola through the three).
fn second_difference(u: Sample, v: Sample, w: Sample) -> f64 {
    ((w.f - v.f) / (w.x - v.x) - (v.f - u.f) / (v.x - u.x)) / (w.x - u.x)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn samples(xs: &[f64], f: impl Fn(f64) -> f64) -> Vec<Sample> {
        xs.iter()
            .map(|&x| Sample {
                x,
                f: f(x),
                error: 0.0,
            })
            .collect()
    }

    #[test]
    fn a_parabola_is_bounded_exactly() {
        // f'' is constant, so the bound is the Lagrange remainder itself: the true value
        // lies on the bound's edge.
        let xs = [0.0, 0.3, 0.5, 1.1, 1.4];
        let s = samples(&xs, |x| 3.0 * x * x - x + 2.0);
        for i in 0..200 {
            let x = 1.4 * f64::from(i) / 199.0;
            let (f, e) = interpolate(&s, x).unwrap();
            let exact = 3.0 * x * x - x + 2.0;
            assert!(((f - exact).abs() - e).abs() <= 1e-12, "x = {x}");
        }
    }

    #[test]
    fn the_estimate_tracks_a_smooth_curve_and_shrinks_at_second_order() {
        // exp on a uniform grid of spacing h: f'' changes by the factor e^h over one
        // spacing, so the estimate (from the neighbouring triples) is short by at most
        // about e^(2h) − 1 of itself at the ends, and it falls by ~4 when h halves.
        let worst = |n: usize| {
            let h = 1.0 / n as f64;
            let xs: Vec<f64> = (0..=n).map(|i| i as f64 / n as f64).collect();
            let s = samples(&xs, f64::exp);
            let mut bound: f64 = 0.0;
            for i in 0..997 {
                let x = f64::from(i) / 996.0;
                let (f, e) = interpolate(&s, x).unwrap();
                assert!(
                    (f - x.exp()).abs() <= e * (2.0 * h).exp(),
                    "n = {n}, x = {x}"
                );
                bound = bound.max(e);
            }
            bound
        };
        let ratio = worst(8) / worst(16);
        assert!((3.5..4.5).contains(&ratio), "ratio {ratio}");
    }

    #[test]
    fn sample_errors_add_and_samples_return_their_own() {
        let s = vec![
            Sample {
                x: 0.0,
                f: 1.0,
                error: 1e-3,
            },
            Sample {
                x: 1.0,
                f: 2.0,
                error: 2e-3,
            },
            Sample {
                x: 2.0,
                f: 3.0,
                error: 5e-4,
            },
        ];
        assert_eq!(interpolate(&s, 1.0), Some((2.0, 2e-3)));
        let (f, e) = interpolate(&s, 0.5).unwrap();
        assert!((f - 1.5).abs() < 1e-15 && (e - 2e-3).abs() < 1e-15);
        assert_eq!(interpolate(&s, 2.5), None);
        assert_eq!(interpolate(&s, -0.1), None);
    }

    #[test]
    fn two_samples_give_half_their_change() {
        let s = samples(&[1.0, 2.0], |x| x * x);
        let (f, e) = interpolate(&s, 1.5).unwrap();
        assert!((f - 2.5).abs() < 1e-15);
        assert!((e - 1.5).abs() < 1e-15);
        assert!((f - 2.25f64).abs() <= e);
    }
}
