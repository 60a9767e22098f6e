//! Which branch a solved loop is on, read from the state itself.
//!
//! The paper's branches are told apart by the number `η` of periods of the geodesic
//! curvature `κ_g(s)` along the loop (Sec. 4.3: `κ_g = −2ck cn(cs, k)` with `η` periods of
//! `cn` per loop length, Eq. (49)). A starting shape (a `--from` file, a resampled state)
//! carries no branch label, and Newton may converge to a state of another branch, so every
//! returned state is identified here rather than trusted to be on the branch that was asked
//! for.
//!
//! Two independent counts are made:
//!
//! * the **dominant Fourier harmonic** of `κ_g(s)`: the `k ≥ 1` maximising
//!   `|∮ κ_g e^{−2πiks/L} ds|`. For the exact loops `κ_g ∝ cn` has period `L/η`, so only
//!   harmonics that are odd multiples of `η` are present and the first is the largest;
//! * the **sign changes** of `κ_g − mean(κ_g)` around the loop, counted with a hysteresis of
//!   a tenth of the amplitude (so that noise near a zero does not count), divided by two.
//!
//! [`Periods::eta`] is the Fourier count; [`Periods::consistent`] says whether the
//! sign-change count agrees.

use std::f64::consts::PI;

use crate::{Equilibrium, SolverError};

/// The periods of `κ_g` found along a loop.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Periods {
    /// Number of periods `η` (the dominant Fourier harmonic of `κ_g`).
    pub eta: u32,
    /// Half the number of sign changes of `κ_g − mean`, if that number is even.
    pub sign_change_eta: Option<u32>,
    /// Amplitude of the dominant harmonic divided by the next largest one (≥ 1; large when
    /// the identification is clear-cut).
    pub dominance: f64,
}

impl Periods {
    /// Whether the sign-change count agrees with the Fourier count.
    pub fn consistent(&self) -> bool {
        self.sign_change_eta == Some(self.eta)
    }
}

/// Count the periods of `κ_g` from samples `kappa_g[j]` at arclengths `s[j]` (strictly
/// increasing, in `[0, length)`, the loop being closed: the sample after the last is the
/// first, at `s[0] + length`).
///
/// Errors ([`SolverError::InvalidInput`]): fewer than 8 samples, mismatched lengths,
/// non-finite values, `s` not increasing within one period, or a constant `κ_g` (a circle,
/// which has no periods).
pub fn identify_periods(s: &[f64], kappa_g: &[f64], length: f64) -> Result<Periods, SolverError> {
    let n = s.len();
    let bad = |m: String| Err(SolverError::InvalidInput(m));
    if n != kappa_g.len() {
        return bad(format!(
            "identify_periods: {n} arclengths but {} curvature samples",
            kappa_g.len()
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
    if s.iter().chain(kappa_g).any(|v| !v.is_finite()) {
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
    let mean = kappa_g.iter().zip(&w).map(|(k, w)| k * w).sum::<f64>() / length;
    let dev: Vec<f64> = kappa_g.iter().map(|k| k - mean).collect();
    let amplitude = dev.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let scale = kappa_g
        .iter()
        .fold(0.0f64, |m, v| m.max(v.abs()))
        .max(1.0 / length);
    if amplitude <= 1e-9 * scale {
        return bad(
            "the geodesic curvature is constant along the loop (a circle): it has no periods"
                .into(),
        );
    }
    // Harmonics up to a quarter of the samples (higher ones are not resolved).
    let k_max = (n / 4).max(1);
    let mut amps = Vec::with_capacity(k_max);
    for k in 1..=k_max {
        let (mut re, mut im) = (0.0, 0.0);
        for j in 0..n {
            let (si, co) = (2.0 * PI * k as f64 * s[j] / length).sin_cos();
            re += w[j] * dev[j] * co;
            im += w[j] * dev[j] * si;
        }
        amps.push(re.hypot(im));
    }
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
    // Sign changes with hysteresis: a change counts when the deviation crosses from below
    // −h to above +h or back.
    let h = 0.1 * amplitude;
    let start = dev.iter().position(|v| v.abs() > h).expect("amplitude > h");
    let mut sign = dev[start] > 0.0;
    let mut changes = 0u32;
    for i in 1..=n {
        let v = dev[(start + i) % n];
        if sign && v < -h {
            sign = false;
            changes += 1;
        } else if !sign && v > h {
            sign = true;
            changes += 1;
        }
    }
    Ok(Periods {
        eta: (best + 1) as u32,
        sign_change_eta: (changes % 2 == 0).then_some(changes / 2),
        dominance,
    })
}

/// Count the periods of `κ_g` of a solved loop (from its profile at the cell boundaries).
pub fn identify_equilibrium(eq: &Equilibrium) -> Result<Periods, SolverError> {
    let profile = eq.profile();
    let s: Vec<f64> = profile.iter().map(|p| p.s).collect();
    let kg: Vec<f64> = profile.iter().map(|p| p.kappa_g).collect();
    identify_periods(&s, &kg, eq.length())
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
        assert_eq!(p.sign_change_eta, Some(3));
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
}
