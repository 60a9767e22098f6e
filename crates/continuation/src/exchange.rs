//! Exchanges between solution branches: where the energies of two branches cross
//! ([`locate`]), which of several states at one parameter value is the lowest
//! ([`lowest`]) and which is the stable one ([`label`]).
//!
//! Over a third of the file is its unit tests (synthetic energy curves with known crossings);
//! the code is the three routines named above.
//!
//! Like the rest of the crate it knows nothing about the model: a pair of branches is an
//! [`EnergyPair`] (the two energies at a parameter value `x`, optionally the analytic slope
//! of their difference, and an error estimate of that difference), and a state is a
//! [`Ranked`] (energy, error estimate, stability index).
//!
//! **Locating a crossing.** [`locate`] finds `x_cr` with `ΔE(x_cr) = E_a − E_b = 0`:
//!
//! 1. *Bracket.* Either the caller's bracket (the sign change seen on sampled branches),
//!    evaluated at both ends, or a hunt from a guess: Newton steps where the pair has an
//!    analytic slope, else secant steps (the first one the caller's `probe`), each taken a
//!    tenth further than predicted so that a one-sided approach still straddles the root,
//!    clamped to `max_step` and never leaving the caller's window.
//! 2. *Refine.* Brent's method ([`roots::brent`]) on that bracket, every evaluation one call
//!    of the pair (the bracket ends are not evaluated twice), to a bracket narrower than
//!    `xtol`.
//! 3. *Estimate.* The slope `s = dΔE/dx` at the root: analytic where the pair has it, else
//!    the chord over `x_cr ± baseline`, whose middle-point misfit
//!    `m = |ΔE(x_cr) − ½(ΔE(x_cr − h) + ΔE(x_cr + h))|` bounds the noise of `ΔE` there (it
//!    also holds the curvature term `|ΔE''| h²/2`, so it errs on the safe side). The error
//!    estimate of `x_cr` is
//!
//!    `δx = w + (δΔE + m)/|s| + 4 ε |x_cr|`
//!
//!    with `w` the final bracket width (0 at an exact zero of `ΔE`) and `δΔE` the pair's error estimate of `ΔE` at the
//!    root (the sum of both energies' estimates): an error `δ` in `ΔE` moves its zero by
//!    `δ/|s|` to first order.
//!
//! **Labelling.** At one parameter value, the lowest state is the one of least energy;
//! states whose energies lie within their combined error estimates of it are *tied* with
//! it. A tie is decided by the caller's preference (e.g. the branch a located critical
//! length names as lowest there, which is more accurate than sampled energies): the
//! preferred tied states are the lowest. With no preferred state among the tied ones,
//! nothing orders them (their energies are equal within what is known of them; two
//! copies of one state, or states related by a symmetry, are tied this way), and every tied
//! state is lowest: a state and its copy always share their standing, whichever of the two
//! numbers happens to be smaller. [`label`] applies this to the states of stability index 0:
//! the lowest of them are stable, the other index-0 states metastable, every state of
//! index > 0 unstable (stable = global minimum among the equilibria, metastable = another
//! local minimum, unstable = not a local minimum).

use crate::error::RootError;
use crate::roots::{self, RootStop};

/// The energies of the two branches at one parameter value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Energies {
    /// `E_a(x)`.
    pub a: f64,
    /// `E_b(x)`.
    pub b: f64,
    /// `d(E_a − E_b)/dx` where the model has it (`None`: [`locate`] takes a chord).
    pub slope: Option<f64>,
}

impl Energies {
    /// `E_a − E_b`.
    pub fn gap(&self) -> f64 {
        self.a - self.b
    }
}

/// A pair of branches whose crossing [`locate`] finds.
pub trait EnergyPair {
    /// The model's error.
    type Error;
    /// Both energies at `x` (re-solved there).
    ///
    /// # Errors
    /// The model's, handed back by [`locate`] as [`RootError::Function`].
    fn energies(&mut self, x: f64) -> Result<Energies, Self::Error>;
    /// The error estimate of `E_a − E_b` at `x` (the sum of both energies' estimates).
    /// [`locate`] asks for it once, at the located root, after evaluating
    /// [`energies`](Self::energies) there.
    ///
    /// # Errors
    /// The model's.
    fn error(&mut self, x: f64) -> Result<f64, Self::Error>;
}

/// Where [`locate`] starts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Start {
    /// `E_a − E_b` changes sign between these two values (both are evaluated first).
    Bracket(f64, f64),
    /// Hunt for the sign change from a guess `x`, never leaving `window`.
    Guess {
        /// The first point.
        x: f64,
        /// The range the hunt may explore (an error beyond it).
        window: (f64, f64),
    },
}

/// Settings of [`locate`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExchangeSettings {
    /// Absolute tolerance in `x`: Brent stops on a bracket narrower than this (plus a few
    /// ulps).
    pub xtol: f64,
    /// First step of a hunt from a guess when the pair has no analytic slope (its sign is
    /// the direction).
    pub probe: f64,
    /// Largest step of the hunt.
    pub max_step: f64,
    /// Half-width `h` of the chord that gives the slope and the noise misfit at the root
    /// when the pair has no analytic slope (0: the chord of the first bracket, no misfit).
    pub baseline: f64,
    /// Evaluations allowed in the hunt and in Brent's method each.
    pub max_evaluations: usize,
    /// Add the chord's misfit to the estimate (off where the pair's own error estimate
    /// already covers all noise, e.g. closed-form energies with rounding only: the misfit
    /// then adds nothing but the curvature term).
    pub misfit: bool,
}

impl Default for ExchangeSettings {
    /// `xtol = 1e-12`, `probe = −1e-3`, `max_step = 0.05`, `baseline = 1e-6`, 60
    /// evaluations, with the misfit.
    fn default() -> Self {
        Self {
            xtol: 1e-12,
            probe: -1e-3,
            max_step: 0.05,
            baseline: 1e-6,
            max_evaluations: 60,
            misfit: true,
        }
    }
}

/// A located crossing.
#[derive(Debug, Clone, PartialEq)]
pub struct Exchange {
    /// `x_cr`.
    pub x: f64,
    /// Estimated absolute error of `x_cr` (see the module docs).
    pub error: f64,
    /// The energies at `x_cr`.
    pub energies: Energies,
    /// `d(E_a − E_b)/dx` at `x_cr` (analytic or the chord) used by the estimate.
    pub slope: f64,
    /// The pair's error estimate of `E_a − E_b` at `x_cr`.
    pub gap_error: f64,
    /// The chord's middle-point misfit (0 with an analytic slope or without
    /// [`ExchangeSettings::misfit`]).
    pub misfit: f64,
    /// Width of Brent's final bracket.
    pub width: f64,
    /// Why Brent stopped (an exhausted budget is reported here, its bracket in `width` and
    /// so in the estimate).
    pub stop: RootStop,
    /// Calls of [`EnergyPair::energies`].
    pub evaluations: usize,
}

/// The pair with its evaluations remembered (Brent re-asks for the bracket ends).
struct Memo<'a, P: EnergyPair> {
    pair: &'a mut P,
    seen: Vec<(f64, Energies)>,
}

impl<P: EnergyPair> Memo<'_, P> {
    fn at(&mut self, x: f64) -> Result<Energies, P::Error> {
        if let Some((_, e)) = self.seen.iter().find(|(y, _)| *y == x) {
            return Ok(*e);
        }
        let e = self.pair.energies(x)?;
        self.seen.push((x, e));
        Ok(e)
    }
}

/// The next point of the hunt from `(x, e)` (with the previous point `prev` for a secant):
/// the predicted root, a tenth further, the step clamped to `max_step`.
fn hunt_step(x: f64, e: &Energies, prev: Option<(f64, f64)>, s: &ExchangeSettings) -> Option<f64> {
    let g = e.gap();
    let slope = match (e.slope, prev) {
        (Some(d), _) => d,
        (None, Some((xp, gp))) => (g - gp) / (x - xp),
        (None, None) => return Some(x + s.probe.clamp(-s.max_step, s.max_step)),
    };
    if !(slope.is_finite() && slope != 0.0) {
        return None;
    }
    let step = (-1.1 * g / slope).clamp(-s.max_step, s.max_step);
    Some(x + step)
}

/// Locate the crossing `E_a(x) = E_b(x)` of `pair` (see the module docs).
///
/// # Errors
/// [`RootError::Function`] with the pair's error; [`RootError::NoBracket`] when the given
/// bracket has no sign change; [`RootError::LeftWindow`] when the hunt leaves its window;
/// [`RootError::Degenerate`] when the slope of `E_a − E_b` is flat or not finite (a hunt
/// step or the estimate) or the hunt runs out of evaluations.
pub fn locate<P: EnergyPair>(
    pair: &mut P,
    start: Start,
    settings: &ExchangeSettings,
) -> Result<Exchange, RootError<P::Error>> {
    let mut memo = Memo {
        pair,
        seen: Vec::new(),
    };
    let f = RootError::Function;
    // 1. A bracket of the sign change.
    let (lo, hi) = match start {
        Start::Bracket(a, b) => {
            let (ga, gb) = (memo.at(a).map_err(f)?.gap(), memo.at(b).map_err(f)?.gap());
            if ga * gb > 0.0 || !(ga.is_finite() && gb.is_finite()) {
                return Err(RootError::NoBracket {
                    a,
                    b,
                    fa: ga,
                    fb: gb,
                });
            }
            (a, b)
        }
        Start::Guess { x, window } => {
            let (mut x, mut e) = (x, memo.at(x).map_err(f)?);
            let mut prev: Option<(f64, f64)> = None;
            let mut found = None;
            for _ in 0..settings.max_evaluations {
                if e.gap() == 0.0 {
                    found = Some((x, x));
                    break;
                }
                let next = hunt_step(x, &e, prev, settings).ok_or(RootError::Degenerate {
                    x,
                    what: "the hunt for a sign change met a flat energy difference",
                })?;
                if !(next >= window.0 && next <= window.1) {
                    return Err(RootError::LeftWindow {
                        x: next,
                        lo: window.0,
                        hi: window.1,
                    });
                }
                let en = memo.at(next).map_err(f)?;
                if en.gap() * e.gap() <= 0.0 {
                    found = Some((x, next));
                    break;
                }
                prev = Some((x, e.gap()));
                (x, e) = (next, en);
            }
            found.ok_or(RootError::Degenerate {
                x,
                what: "no sign change of the energy difference within the evaluation budget",
            })?
        }
    };
    // 2. Brent on the bracket.
    let (x, width, stop) = if lo == hi {
        (lo, 0.0, RootStop::Residual)
    } else {
        let scale = lo.abs().max(hi.abs()).max(f64::MIN_POSITIVE);
        let r = roots::brent(
            |x| memo.at(x).map(|e| e.gap()),
            lo.min(hi),
            lo.max(hi),
            settings.xtol / scale,
            settings.max_evaluations,
        )?;
        // At an exact zero the bracket says nothing more (the energies' errors do).
        let width = if r.stop == RootStop::Residual {
            0.0
        } else {
            r.width
        };
        (r.x, width, r.stop)
    };
    let energies = memo.at(x).map_err(f)?;
    // 3. Slope, noise and error estimate.
    let (slope, misfit) = match energies.slope {
        Some(s) => (s, 0.0),
        None if settings.baseline > 0.0 => {
            let h = settings.baseline;
            let gm = memo.at(x - h).map_err(f)?.gap();
            let gp = memo.at(x + h).map_err(f)?.gap();
            let misfit = if settings.misfit {
                (energies.gap() - 0.5 * (gm + gp)).abs()
            } else {
                0.0
            };
            ((gp - gm) / (2.0 * h), misfit)
        }
        None => {
            let (ga, gb) = (memo.at(lo).map_err(f)?.gap(), memo.at(hi).map_err(f)?.gap());
            ((gb - ga) / (hi - lo), 0.0)
        }
    };
    if !(slope.is_finite() && slope != 0.0) {
        return Err(RootError::Degenerate {
            x,
            what: "the slope of the energy difference at the crossing is flat or not finite",
        });
    }
    let evaluations = memo.seen.len();
    let gap_error = memo.pair.error(x).map_err(f)?;
    let error = width + (gap_error + misfit) / slope.abs() + 4.0 * f64::EPSILON * x.abs();
    Ok(Exchange {
        x,
        error,
        energies,
        slope,
        gap_error,
        misfit,
        width,
        stop,
        evaluations,
    })
}

/// One state at a parameter value, as [`lowest`] and [`label`] see it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ranked {
    /// Energy.
    pub energy: f64,
    /// Its error estimate (≥ 0).
    pub error: f64,
    /// Stability index (negative directions of the constrained Hessian).
    pub index: usize,
    /// Preferred in a tie (see the module docs).
    pub preferred: bool,
}

/// Stability of a state among the others at its parameter value.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Standing {
    /// Index 0 and the lowest such state.
    Stable,
    /// Index 0, not the lowest.
    Metastable,
    /// Index > 0.
    Unstable,
}

/// Positions of the lowest states among `states` (every index; see the module docs for
/// ties): empty only when `states` is empty or every energy is NaN.
pub fn lowest(states: &[Ranked]) -> Vec<usize> {
    let Some((m, least)) = states
        .iter()
        .enumerate()
        .filter(|(_, s)| !s.energy.is_nan())
        .min_by(|a, b| a.1.energy.total_cmp(&b.1.energy))
    else {
        return Vec::new();
    };
    let tied: Vec<usize> = states
        .iter()
        .enumerate()
        .filter(|(i, s)| *i == m || s.energy - s.error.abs() <= least.energy + least.error.abs())
        .map(|(i, _)| i)
        .collect();
    let preferred: Vec<usize> = tied
        .iter()
        .copied()
        .filter(|&i| states[i].preferred)
        .collect();
    if preferred.is_empty() {
        tied
    } else {
        preferred
    }
}

/// The [`lowest`] states at any index, where a local minimum (index 0) is among them only
/// the local minima: a saddle tied with a minimum within the estimates is not the lowest
/// state there (what lies lowest is then the minimum, which the saddle's own unstable
/// directions descend towards); with no minimum among the tied states, all of them are.
pub fn lowest_state(states: &[Ranked]) -> Vec<usize> {
    let tied = lowest(states);
    let minima: Vec<usize> = tied
        .iter()
        .copied()
        .filter(|&i| states[i].index == 0)
        .collect();
    if minima.is_empty() {
        tied
    } else {
        minima
    }
}

/// The [`Standing`] of every state: the [`lowest`] of the index-0 states are stable, the
/// other index-0 states metastable, states of index > 0 unstable.
pub fn label(states: &[Ranked]) -> Vec<Standing> {
    let minima: Vec<usize> = (0..states.len())
        .filter(|&i| states[i].index == 0)
        .collect();
    let picked: Vec<Ranked> = minima.iter().map(|&i| states[i]).collect();
    let stable: Vec<usize> = lowest(&picked).into_iter().map(|k| minima[k]).collect();
    (0..states.len())
        .map(|i| {
            if states[i].index > 0 {
                Standing::Unstable
            } else if stable.contains(&i) {
                Standing::Stable
            } else {
                Standing::Metastable
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::convert::Infallible;

    /// `e^x + x = 3`: `x = 3 − W(e³)` (Lambert's W), to 30 digits
    /// 0.792059968430677001418395877885.
    const ROOT: f64 = 0.792_059_968_430_677;

    /// A number in `[−1, 1]` fixed by the bits of `x` (splitmix64): noise that has no
    /// smoothness for an interpolating root finder to exploit.
    fn hash_noise(x: f64) -> f64 {
        let mut z = x.to_bits().wrapping_add(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        2.0 * (z >> 11) as f64 / (1u64 << 53) as f64 - 1.0
    }

    /// `E_a = e^x`, `E_b = 3 − x`, each with noise of size `noise` (declared as its
    /// error estimate), with or without the analytic slope `e^x + 1`.
    struct Curves {
        noise: f64,
        analytic: bool,
        calls: usize,
    }

    impl EnergyPair for Curves {
        type Error = Infallible;
        fn energies(&mut self, x: f64) -> Result<Energies, Infallible> {
            self.calls += 1;
            Ok(Energies {
                a: x.exp() + self.noise * hash_noise(x),
                b: 3.0 - x + self.noise * hash_noise(x + 1.0),
                slope: self.analytic.then(|| x.exp() + 1.0),
            })
        }
        fn error(&mut self, _x: f64) -> Result<f64, Infallible> {
            Ok(2.0 * self.noise)
        }
    }

    /// The pair with its branches swapped.
    struct Swapped(Curves);

    impl EnergyPair for Swapped {
        type Error = Infallible;
        fn energies(&mut self, x: f64) -> Result<Energies, Infallible> {
            let e = self.0.energies(x)?;
            Ok(Energies {
                a: e.b,
                b: e.a,
                slope: e.slope.map(|s| -s),
            })
        }
        fn error(&mut self, x: f64) -> Result<f64, Infallible> {
            self.0.error(x)
        }
    }

    fn curves(noise: f64, analytic: bool) -> Curves {
        Curves {
            noise,
            analytic,
            calls: 0,
        }
    }

    #[test]
    fn finds_a_known_crossing_to_the_tolerance() {
        for analytic in [false, true] {
            for start in [
                Start::Bracket(0.5, 1.0),
                Start::Guess {
                    x: 0.7,
                    window: (0.0, 2.0),
                },
            ] {
                let mut c = curves(0.0, analytic);
                let r = locate(&mut c, start, &ExchangeSettings::default()).unwrap();
                assert!((r.x - ROOT).abs() < 1e-12, "{start:?}: {}", r.x - ROOT);
                assert!(
                    (r.x - ROOT).abs() <= r.error,
                    "{} > {}",
                    r.x - ROOT,
                    r.error
                );
                assert!(r.error < 1e-11, "{}", r.error);
                // The slope e^x + 1 at the root (analytic, or a chord of half-width 1e-6).
                assert!((r.slope - (ROOT.exp() + 1.0)).abs() < 1e-8, "{}", r.slope);
                // The slope keeps its sign: E_b − E_a has the opposite one.
                let mut swapped = Swapped(curves(0.0, analytic));
                let q = locate(&mut swapped, start, &ExchangeSettings::default()).unwrap();
                assert!(
                    (q.slope + r.slope).abs() < 1e-8,
                    "{} vs {}",
                    q.slope,
                    r.slope
                );
                // Brent's interpolation converges superlinearly: far fewer calls than the
                // ~40 halvings of bisection.
                assert!(
                    c.calls < 16,
                    "{start:?}, analytic {analytic}: {} calls",
                    c.calls
                );
            }
        }
    }

    #[test]
    fn error_estimate_bounds_the_error_under_noise() {
        // Noise δ on each energy moves the zero of E_a − E_b by up to 2δ/|s|; the estimate
        // must cover the actual error and stay within a modest factor of that bound.
        let s = ROOT.exp() + 1.0;
        for noise in [1e-12, 1e-9, 1e-6, 1e-4] {
            for analytic in [false, true] {
                for start in [
                    Start::Bracket(0.6, 0.9),
                    Start::Guess {
                        x: 0.9,
                        window: (0.0, 2.0),
                    },
                ] {
                    let settings = ExchangeSettings {
                        baseline: 1e-3,
                        ..ExchangeSettings::default()
                    };
                    let r = locate(&mut curves(noise, analytic), start, &settings).unwrap();
                    let err = (r.x - ROOT).abs();
                    assert!(
                        err <= r.error,
                        "noise {noise}: error {err:e} > estimate {:e}",
                        r.error
                    );
                    let bound = 2.0 * noise / s;
                    // Chord misfit adds up to 2δ/|s| plus the curvature term e^x h²/2.
                    let loose = 3.0 * bound + 1e-6 * ROOT.exp() / s + 1e-11;
                    assert!(
                        r.error <= loose,
                        "noise {noise}: estimate {:e} > {loose:e}",
                        r.error
                    );
                }
            }
        }
    }

    #[test]
    fn reports_a_missing_bracket_and_a_hunt_out_of_its_window() {
        let r = locate(
            &mut curves(0.0, false),
            Start::Bracket(1.0, 2.0),
            &ExchangeSettings::default(),
        );
        assert!(matches!(r, Err(RootError::NoBracket { .. })), "{r:?}");
        // The crossing at 0.79 lies left of the window [0.9, 2]: the hunt from 1.5
        // steps out of it.
        let r = locate(
            &mut curves(0.0, true),
            Start::Guess {
                x: 1.5,
                window: (0.9, 2.0),
            },
            &ExchangeSettings::default(),
        );
        assert!(matches!(r, Err(RootError::LeftWindow { .. })), "{r:?}");
    }

    #[test]
    fn a_saddle_tied_with_a_minimum_is_not_the_lowest_state() {
        // Energies tied within the estimates: the saddle below by 1e-7, the minimum above.
        let tied = [
            state(1.0, 1e-6, 4, false),
            state(1.000_000_1, 1e-6, 0, false),
        ];
        assert_eq!(lowest(&tied), vec![0, 1]);
        assert_eq!(lowest_state(&tied), vec![1]);
        // Apart beyond the estimates, the saddle is the lowest state.
        let apart = [state(1.0, 1e-9, 4, false), state(1.001, 1e-9, 0, false)];
        assert_eq!(lowest_state(&apart), vec![0]);
        // Only saddles tied: all of them.
        let saddles = [
            state(1.0, 1e-6, 1, false),
            state(1.000_000_1, 1e-6, 2, false),
        ];
        assert_eq!(lowest_state(&saddles), vec![0, 1]);
    }

    fn state(energy: f64, error: f64, index: usize, preferred: bool) -> Ranked {
        Ranked {
            energy,
            error,
            index,
            preferred,
        }
    }

    #[test]
    fn labels_follow_the_index_and_the_least_energy() {
        use Standing::{Metastable as M, Stable as S, Unstable as U};
        // A saddle below two minima: the lower minimum is stable.
        let states = [
            state(0.5, 0.0, 1, false),
            state(1.0, 0.0, 0, false),
            state(1.2, 0.0, 0, false),
        ];
        assert_eq!(label(&states), vec![U, S, M]);
        assert_eq!(lowest(&states), vec![0]);
        // No index-0 state: nothing is stable.
        assert_eq!(label(&[state(1.0, 0.0, 2, false)]), vec![U]);
        assert!(lowest(&[]).is_empty());
    }

    #[test]
    fn ties_within_the_estimates_go_to_the_preferred_states() {
        use Standing::{Metastable as M, Stable as S};
        // Energies 1.0 ± 1e-6 and 1.0000015 ± 1e-6 overlap: the preferred higher one wins.
        let tied = [
            state(1.0, 1e-6, 0, false),
            state(1.000_001_5, 1e-6, 0, true),
        ];
        assert_eq!(label(&tied), vec![M, S]);
        // Apart by more than the estimates: the least energy wins against the preference.
        let apart = [
            state(1.0, 1e-7, 0, false),
            state(1.000_001_5, 1e-7, 0, true),
        ];
        assert_eq!(label(&apart), vec![S, M]);
        // A tie with no preferred state: nothing orders the two, both are lowest.
        let plain = [
            state(1.0, 1e-6, 0, false),
            state(1.000_000_5, 1e-6, 0, false),
        ];
        assert_eq!(label(&plain), vec![S, S]);
        // The tied pair above a third minimum that lies below both by more than the
        // estimates: both metastable.
        let below = [
            state(1.0, 1e-6, 0, false),
            state(1.000_000_5, 1e-6, 0, false),
            state(0.9, 1e-6, 0, false),
        ];
        assert_eq!(label(&below), vec![M, M, S]);
        // Tied with the least but not with each other: only the tied ones are lowest.
        let chain = [
            state(1.0, 1e-6, 0, false),
            state(1.000_001_5, 1e-6, 0, false),
            state(1.000_003, 1e-6, 0, false),
        ];
        assert_eq!(label(&chain), vec![S, S, M]);
        // Two preferred tied states (at a critical length): both stable.
        let both = [state(1.0, 1e-6, 0, true), state(1.000_000_5, 1e-6, 0, true)];
        assert_eq!(label(&both), vec![S, S]);
    }

    /// One state listed twice (two traced copies of one equilibrium, energies `7e-10` apart,
    /// each known to `5e-8`) shares one standing whichever copy comes first or is smaller,
    /// and both copies stay below a distinct minimum `10⁻⁴` above them.
    #[test]
    fn copies_of_one_state_share_their_label() {
        use Standing::{Metastable as M, Stable as S, Unstable as U};
        let (e, d, err) = (0.511_032_090_2, 7e-10, 5e-8);
        for (a, b) in [(e, e + d), (e + d, e)] {
            let copies = [
                state(a, err, 0, false),
                state(b, err, 0, false),
                state(e + 1e-4, err, 0, false),
                state(e - 1e-3, err, 1, false),
            ];
            assert_eq!(label(&copies), vec![S, S, M, U]);
            let mut low = lowest(&copies);
            low.sort_unstable();
            assert_eq!(low, vec![3]);
        }
        // A NaN energy is never tied.
        let nan = [state(1.0, 1e-6, 0, false), state(f64::NAN, 1e-6, 0, false)];
        assert_eq!(label(&nan), vec![S, M]);
    }
}
