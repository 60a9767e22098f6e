//! One-dimensional root finders: the secant method, the Illinois variant of regula
//! falsi and Brent's method.
//!
//! They know nothing about the functions they are given: a closure `x ↦ f(x)` that may
//! fail with the caller's error `E` (handed back unchanged as [`RootError::Function`]).
//! Every finder reports what it reached as a [`Root`] (with [`Root::converged`] and the
//! reason it stopped); only a missing sign change and the function's own errors are
//! errors, so that each caller decides what an unconverged iteration means for it.
//!
//! * [`secant`]: no bracket, superlinear (order `(1 + √5)/2 ≈ 1.618` at a simple root);
//!   carries a payload `T` of each evaluation (e.g. the states re-solved at `x`), and
//!   optionally clamps its steps.
//! * [`illinois`]: bracketed, the false position with the retained end's value halved
//!   when the same end is kept twice (order `3^{1/3} ≈ 1.442`; M. Dowell & P. Jarratt,
//!   BIT 11, 1971).
//! * [`brent`]: bracketed, inverse quadratic interpolation safeguarded by bisection
//!   (R. P. Brent, *Algorithms for Minimization without Derivatives*, 1973, ch. 4).

use crate::error::RootError;

/// Why a root finder stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RootStop {
    /// `|f(x)|` fell to the residual tolerance (an exact zero with tolerance 0).
    Residual,
    /// The last step (secant) or the bracket (Illinois, Brent) fell below the
    /// `x` tolerance.
    Step,
    /// The secant through the last two points was flat or not finite.
    FlatSlope,
    /// The iteration budget was used up.
    MaxIterations,
}

/// What a root finder reached.
#[derive(Debug, Clone, PartialEq)]
pub struct Root<T = ()> {
    /// The last iterate (the root estimate).
    pub x: f64,
    /// `f(x)`.
    pub fx: f64,
    /// Secant: the length of the last step; bracketed methods: the final bracket width.
    pub width: f64,
    /// Secant: the slope of the line through the last two iterates (for the bracketed
    /// methods, through the bracket ends' true values).
    pub slope: f64,
    /// Secant: the slope that made the last step (equal to `slope` before any step).
    pub step_slope: f64,
    /// Iterations taken (evaluations after the starting ones).
    pub iterations: usize,
    /// Why the iteration stopped.
    pub stop: RootStop,
    /// The payload of the evaluation at `x` (secant; `()` for the others).
    pub payload: T,
}

impl<T> Root<T> {
    /// `true` unless the iteration budget was used up or the secant went flat.
    pub fn converged(&self) -> bool {
        matches!(self.stop, RootStop::Residual | RootStop::Step)
    }
}

/// Settings of [`secant`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SecantSettings {
    /// Stop when a step is shorter than this (strictly).
    pub xtol: f64,
    /// Stop when `|f(x)|` is below this (strictly), or is exactly zero.
    pub ftol: f64,
    /// Largest step (steps are clamped to `±max_step`).
    pub max_step: f64,
    /// Iteration budget.
    pub max_iter: usize,
}

impl Default for SecantSettings {
    /// `xtol = 1e-12`, no residual test, no step clamp, 30 iterations.
    fn default() -> Self {
        Self {
            xtol: 1e-12,
            ftol: 0.0,
            max_step: f64::INFINITY,
            max_iter: 30,
        }
    }
}

/// The secant method on `f(x) = 0` from `x0` and `x1`; `f` returns its value and a
/// payload kept for the last iterate.
///
/// Each iteration first tests the newest point (`|f| < ftol` or `f = 0`: stop with
/// [`RootStop::Residual`]; a flat or non-finite secant: [`RootStop::FlatSlope`]), then
/// steps to `x₁ − f₁/s` (`s` the secant slope, the step clamped to `max_step`) and
/// stops with [`RootStop::Step`] once that step is shorter than `xtol`.
///
/// # Errors
/// [`RootError::Function`] with the function's error.
pub fn secant<T, E, F>(
    mut f: F,
    x0: f64,
    x1: f64,
    settings: &SecantSettings,
) -> Result<Root<T>, RootError<E>>
where
    F: FnMut(f64) -> Result<(f64, T), E>,
{
    let (mut xa, mut xb) = (x0, x1);
    let (mut fa, _) = f(xa).map_err(RootError::Function)?;
    let (mut fb, mut payload) = f(xb).map_err(RootError::Function)?;
    let mut step_slope = (fb - fa) / (xb - xa);
    for it in 0..settings.max_iter {
        let slope = (fb - fa) / (xb - xa);
        let stop = if fb == 0.0 || fb.abs() < settings.ftol {
            Some(RootStop::Residual)
        } else if !slope.is_finite() || slope == 0.0 {
            Some(RootStop::FlatSlope)
        } else {
            None
        };
        if let Some(stop) = stop {
            return Ok(Root {
                x: xb,
                fx: fb,
                width: (xb - xa).abs(),
                slope,
                step_slope: if it == 0 { slope } else { step_slope },
                iterations: it,
                stop,
                payload,
            });
        }
        let step = (-fb / slope).clamp(-settings.max_step, settings.max_step);
        let xn = xb + step;
        let (fnew, pn) = f(xn).map_err(RootError::Function)?;
        (xa, fa, xb, fb, payload) = (xb, fb, xn, fnew, pn);
        step_slope = slope;
        if (xb - xa).abs() < settings.xtol {
            return Ok(Root {
                x: xb,
                fx: fb,
                width: (xb - xa).abs(),
                slope: (fb - fa) / (xb - xa),
                step_slope,
                iterations: it + 1,
                stop: RootStop::Step,
                payload,
            });
        }
    }
    Ok(Root {
        x: xb,
        fx: fb,
        width: (xb - xa).abs(),
        slope: (fb - fa) / (xb - xa),
        step_slope,
        iterations: settings.max_iter,
        stop: RootStop::MaxIterations,
        payload,
    })
}

/// The Illinois method for a root of `f` in the bracket `[a, b]` (`f(a) f(b) ≤ 0`):
/// the false-position point `c` of the two retained ends replaces the end whose value
/// has the sign of `f(c)`; when the same end is retained twice in a row, its value is
/// halved. Stops when `|b − a| < tol` ([`RootStop::Step`]), at an exact zero
/// ([`RootStop::Residual`]) or after `max_iter` iterations. The returned `x` is the
/// newest iterate and `width` the final `|b − a|`.
///
/// # Errors
/// [`RootError::NoBracket`] if `f(a) f(b) > 0`; [`RootError::Function`].
pub fn illinois<E, F>(
    mut f: F,
    a: f64,
    b: f64,
    tol: f64,
    max_iter: usize,
) -> Result<Root, RootError<E>>
where
    F: FnMut(f64) -> Result<f64, E>,
{
    let (mut a, mut b) = (a, b);
    let (mut fa, mut fb) = (
        f(a).map_err(RootError::Function)?,
        f(b).map_err(RootError::Function)?,
    );
    if fa * fb > 0.0 {
        return Err(RootError::NoBracket { a, b, fa, fb });
    }
    // `b` is the newest iterate, `a` the retained end of the bracket; `fa` may be a
    // halved (weighted) value.
    let mut fa_true = fa;
    let mut stop = RootStop::MaxIterations;
    let mut iterations = 0;
    for _ in 0..max_iter {
        if (b - a).abs() < tol {
            stop = RootStop::Step;
            break;
        }
        if fb == 0.0 {
            stop = RootStop::Residual;
            break;
        }
        let c = (a * fb - b * fa) / (fb - fa);
        let fc = f(c).map_err(RootError::Function)?;
        iterations += 1;
        if fc * fb < 0.0 {
            (a, fa, fa_true) = (b, fb, fb);
        } else {
            fa *= 0.5;
        }
        (b, fb) = (c, fc);
    }
    if stop == RootStop::MaxIterations {
        if (b - a).abs() < tol {
            stop = RootStop::Step;
        } else if fb == 0.0 {
            stop = RootStop::Residual;
        }
    }
    Ok(Root {
        x: b,
        fx: fb,
        width: (b - a).abs(),
        slope: (fb - fa_true) / (b - a),
        step_slope: (fb - fa_true) / (b - a),
        iterations,
        stop,
        payload: (),
    })
}

/// Brent's method for a root of `f` in `[a, b]`, where `f(a)` and `f(b)` have opposite
/// signs (or one is zero). Stops when the bracket is narrower than
/// `xtol·max(1e-300, |x|)` plus a few ulps ([`RootStop::Step`]) or when `f(x) = 0`
/// ([`RootStop::Residual`]); after `max_iter` iterations it reports
/// [`RootStop::MaxIterations`].
///
/// # Errors
/// [`RootError::NoBracket`] if `f(a)` and `f(b)` have the same strict sign;
/// [`RootError::Function`].
pub fn brent<E, F>(
    mut f: F,
    a: f64,
    b: f64,
    xtol: f64,
    max_iter: usize,
) -> Result<Root, RootError<E>>
where
    F: FnMut(f64) -> Result<f64, E>,
{
    let (mut a, mut b) = (a, b);
    let mut fa = f(a).map_err(RootError::Function)?;
    let mut fb = f(b).map_err(RootError::Function)?;
    let done = |x: f64, fx: f64, width: f64, iterations: usize, stop: RootStop| Root {
        x,
        fx,
        width,
        slope: f64::NAN,
        step_slope: f64::NAN,
        iterations,
        stop,
        payload: (),
    };
    if fa == 0.0 {
        return Ok(done(a, fa, 0.0, 0, RootStop::Residual));
    }
    if fb == 0.0 {
        return Ok(done(b, fb, 0.0, 0, RootStop::Residual));
    }
    if (fa > 0.0) == (fb > 0.0) {
        return Err(RootError::NoBracket { a, b, fa, fb });
    }
    let (mut c, mut fc) = (a, fa);
    let mut d = b - a;
    let mut e = d;
    for it in 0..max_iter {
        if (fb > 0.0) == (fc > 0.0) {
            c = a;
            fc = fa;
            d = b - a;
            e = d;
        }
        if fc.abs() < fb.abs() {
            a = b;
            b = c;
            c = a;
            fa = fb;
            fb = fc;
            fc = fa;
        }
        let tol = 2.0 * f64::EPSILON * b.abs() + 0.5 * xtol * b.abs().max(1e-300);
        let xm = 0.5 * (c - b);
        if xm.abs() <= tol || fb == 0.0 {
            let stop = if fb == 0.0 {
                RootStop::Residual
            } else {
                RootStop::Step
            };
            return Ok(done(b, fb, (c - b).abs(), it, stop));
        }
        if e.abs() >= tol && fa.abs() > fb.abs() {
            let s = fb / fa;
            let (mut p, mut q);
            if a == c {
                p = 2.0 * xm * s;
                q = 1.0 - s;
            } else {
                let qq = fa / fc;
                let r = fb / fc;
                p = s * (2.0 * xm * qq * (qq - r) - (b - a) * (r - 1.0));
                q = (qq - 1.0) * (r - 1.0) * (s - 1.0);
            }
            if p > 0.0 {
                q = -q;
            } else {
                p = -p;
            }
            if 2.0 * p < (3.0 * xm * q - (tol * q).abs()).min((e * q).abs()) {
                e = d;
                d = p / q;
            } else {
                d = xm;
                e = d;
            }
        } else {
            d = xm;
            e = d;
        }
        a = b;
        fa = fb;
        b += if d.abs() > tol { d } else { tol.copysign(xm) };
        fb = f(b).map_err(RootError::Function)?;
    }
    Ok(done(
        b,
        fb,
        (c - b).abs(),
        max_iter,
        RootStop::MaxIterations,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::convert::Infallible;

    /// Errors `|x_k − r|` of the iterates of a finder, recorded by the closure.
    fn errors(xs: &[f64], r: f64) -> Vec<f64> {
        xs.iter().map(|x| (x - r).abs()).collect()
    }

    /// The order `ln(e_{k+1}/e_k) / ln(e_k/e_{k−1})` from the last three errors above
    /// `floor` (rounding would spoil smaller ones).
    fn order(e: &[f64], floor: f64) -> f64 {
        let e: Vec<f64> = e.iter().copied().filter(|v| *v > floor).collect();
        let n = e.len();
        assert!(n >= 3, "too few iterates: {e:?}");
        (e[n - 1] / e[n - 2]).ln() / (e[n - 2] / e[n - 3]).ln()
    }

    #[test]
    fn secant_finds_sqrt2_with_golden_order() {
        let mut xs = Vec::new();
        let r = secant(
            |x| {
                xs.push(x);
                Ok::<_, Infallible>((x * x - 2.0, x))
            },
            1.0,
            2.0,
            &SecantSettings {
                xtol: 1e-15,
                ..SecantSettings::default()
            },
        )
        .unwrap();
        let root = 2f64.sqrt();
        assert!(r.converged());
        assert!((r.x - root).abs() < 1e-15, "{}", r.x - root);
        assert_eq!(r.payload, r.x);
        // Slope of x² − 2 at the root: 2√2 (the last step's secant; the slope through
        // the last two iterates, 1e-15 apart, is rounding noise).
        assert_eq!(r.stop, RootStop::Step);
        assert!((r.step_slope - 2.0 * root).abs() < 1e-6);
        let p = order(&errors(&xs, root), 1e-13);
        let golden = 0.5 * (1.0 + 5f64.sqrt());
        assert!((p - golden).abs() < 0.15, "order {p}");
    }

    #[test]
    fn secant_stops_on_residual_and_clamps_steps() {
        // f = x − 3 is linear: one step lands on the root; with steps clamped to 0.5
        // it takes four from x = 1.
        let s = SecantSettings {
            xtol: 1e-14,
            ftol: 1e-12,
            max_step: 0.5,
            max_iter: 30,
        };
        let mut xs = Vec::new();
        let r = secant(
            |x| {
                xs.push(x);
                Ok::<_, Infallible>((x - 3.0, ()))
            },
            0.9,
            1.0,
            &s,
        )
        .unwrap();
        assert_eq!(r.stop, RootStop::Residual);
        assert!((r.x - 3.0).abs() < 1e-12);
        assert_eq!(r.iterations, 4);
        assert!(xs
            .windows(2)
            .skip(1)
            .all(|w| (w[1] - w[0]).abs() <= 0.5 + 1e-15));
        // A constant function has a flat secant.
        let r = secant(|_| Ok::<_, Infallible>((1.0, ())), 0.0, 1.0, &s).unwrap();
        assert_eq!(r.stop, RootStop::FlatSlope);
        assert!(!r.converged());
    }

    #[test]
    fn secant_passes_the_function_error_back() {
        let r = secant(
            |x| {
                if x > 1.5 {
                    Err("too far")
                } else {
                    Ok((x - 2.0, ()))
                }
            },
            0.0,
            1.0,
            &SecantSettings::default(),
        );
        assert!(matches!(r, Err(RootError::Function("too far"))));
    }

    #[test]
    fn illinois_finds_cos_fixed_point_superlinearly() {
        // x = cos x at 0.739085133215160641655312087673873404 (the Dottie number).
        let dottie = 0.739_085_133_215_160_6;
        let mut xs = Vec::new();
        let r = illinois(
            |x: f64| {
                xs.push(x);
                Ok::<_, Infallible>(x.cos() - x)
            },
            0.0,
            1.0,
            1e-14,
            60,
        )
        .unwrap();
        assert!(r.converged());
        assert!((r.x - dottie).abs() < 1e-15, "{}", r.x - dottie);
        // Far fewer evaluations than bisection's ~47 for a bracket of 1e-14: the
        // Illinois method converges superlinearly (order 3^{1/3} per evaluation).
        assert!(r.iterations < 15, "{} iterations", r.iterations);
        assert!(xs.len() == r.iterations + 2);
    }

    #[test]
    fn illinois_requires_a_bracket() {
        let r = illinois(
            |x: f64| Ok::<_, Infallible>(x * x + 1.0),
            -1.0,
            1.0,
            1e-12,
            60,
        );
        assert!(matches!(r, Err(RootError::NoBracket { .. })));
    }

    #[test]
    fn brent_finds_known_roots() {
        let r = brent(|x| Ok::<_, Infallible>(x * x - 2.0), 0.0, 2.0, 1e-16, 100).unwrap();
        assert!(r.converged());
        assert!((r.x - 2f64.sqrt()).abs() < 4e-16);
        let r = brent(
            |x: f64| Ok::<_, Infallible>(x.cos() - x),
            0.0,
            1.0,
            1e-16,
            100,
        )
        .unwrap();
        assert!((r.x.cos() - r.x).abs() < 1e-15);
        // A cubic with a triple root at 1: Brent still converges (by bisection), to the
        // cube root of rounding.
        let r = brent(
            |x: f64| Ok::<_, Infallible>((x - 1.0).powi(3)),
            0.0,
            3.0,
            1e-15,
            200,
        )
        .unwrap();
        assert!(r.converged() && (r.x - 1.0).abs() < 1e-5, "{}", r.x);
        assert!(matches!(
            brent(|x| Ok::<_, Infallible>(x * x + 1.0), -1.0, 1.0, 1e-12, 50),
            Err(RootError::NoBracket { .. })
        ));
        // One iteration is not enough for a bracket of width 2 at tolerance 1e-12.
        let r = brent(|x: f64| Ok::<_, Infallible>(x.sin()), -1.0, 1.5, 1e-12, 1).unwrap();
        assert_eq!(r.stop, RootStop::MaxIterations);
    }

    #[test]
    fn brent_is_faster_than_bisection_on_a_smooth_root() {
        // e^x − 2 on [0, 3]: bisection needs ~52 halvings for 1e-15; Brent's
        // interpolation converges superlinearly.
        let mut n = 0;
        let r = brent(
            |x: f64| {
                n += 1;
                Ok::<_, Infallible>(x.exp() - 2.0)
            },
            0.0,
            3.0,
            1e-15,
            100,
        )
        .unwrap();
        assert!((r.x - 2f64.ln()).abs() < 1e-15);
        assert!(n < 15, "{n} evaluations");
    }
}
