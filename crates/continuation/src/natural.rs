//! Natural-parameter continuation: the parameter itself is stepped towards a target and
//! each step is corrected at the new parameter value by the caller's solver.
//!
//! Where a branch is a graph over the parameter (no folds between the targets) this is
//! all a tracer needs, and it works with solvers that are not a smooth [`Problem`] (a
//! semismooth Newton on a contact set, a solver with its own fallbacks). It cannot pass a
//! fold: there the corrector fails, the step is halved until the budget of halvings is
//! spent, and the walk reports where it got stuck ([`Stuck`]); pseudo-arclength
//! ([`Continuation`](crate::Continuation)) passes folds.
//!
//! * [`walk`]: from a state to one target value of the parameter, with any state type
//!   `S` and any step function (`(current, previous, to, halvings) → next`), so that
//!   the caller keeps its predictors and fallbacks.
//! * [`walk_steps`]: the same loop with a fixed step that every step tries first (and a
//!   budget of halvings per step), for a coordinate in which equal steps are natural.
//! * [`walk_adaptive`]: steps that grow after a success and halve after a failure, with
//!   the caller's rescue where the step would fall below its minimum (a fold).
//! * [`natural_branch`]: the same loop for a [`Problem`], with the secant predictor
//!   through the last two points and Newton's method as corrector.
//!
//! Reference: E. L. Allgower & K. Georg, *Introduction to Numerical Continuation
//! Methods*, SIAM 2003, ch. 2 (embedding and natural parametrisation).
//!
//! Over 40 % of the file is its unit tests (the four loops on problems with known branches,
//! folds and failing correctors); the code is the four loops named above.

use nalgebra::DVector;

use crate::error::ContinuationError;
use crate::newton::newton;
use crate::problem::Problem;

/// Settings of a natural-parameter [`walk`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NaturalSettings {
    /// Largest parameter step (the first step is `target − p` clamped to this).
    pub max_step: f64,
    /// A failed step halves the step; the walk gives up after this many halvings (in
    /// total, not per step: the step never grows back).
    pub max_halvings: usize,
    /// The walk has arrived once `|target − p| ≤ arrive`.
    pub arrive: f64,
    /// The next step goes straight to the target when the remaining distance is at most
    /// `|h|·(1 + snap)`.
    pub snap: f64,
}

impl Default for NaturalSettings {
    /// Unbounded steps, 6 halvings, arrival to `1e-14`, no snapping tolerance.
    fn default() -> Self {
        Self {
            max_step: f64::INFINITY,
            max_halvings: 6,
            arrive: 1e-14,
            snap: 0.0,
        }
    }
}

/// A walk that reached its target.
#[derive(Debug, Clone, PartialEq)]
pub struct Walked<S> {
    /// The state at the target.
    pub last: S,
    /// The state before it (`None` if no step was taken and none was given).
    pub prev: Option<S>,
    /// Accepted steps.
    pub steps: usize,
    /// Halvings spent.
    pub halvings: usize,
}

/// A walk that could not reach its target: the last accepted state and the error of
/// the last failed step.
#[derive(Debug, Clone, PartialEq)]
pub struct Stuck<S, E> {
    /// The last accepted state.
    pub last: S,
    /// The accepted state before it.
    pub prev: Option<S>,
    /// The error of the step that spent the last halving.
    pub error: E,
    /// Accepted steps.
    pub steps: usize,
}

/// Walks from `start` (with `prev`, the state accepted before it, if any, for the
/// caller's predictor) to the parameter value `target`: each step asks
/// `step(current, previous, to, halvings)` for the state at `to`; a failed step halves
/// the step length and is retried from the same state, until `settings.max_halvings`
/// halvings are spent. `param` reads the parameter of a state.
///
/// # Errors
/// [`Stuck`] with the last accepted state when the halvings are spent.
pub fn walk<S, E, P, F>(
    start: S,
    prev: Option<S>,
    target: f64,
    param: P,
    settings: &NaturalSettings,
    mut step: F,
) -> Result<Walked<S>, Stuck<S, E>>
where
    P: Fn(&S) -> f64,
    F: FnMut(&S, Option<&S>, f64, usize) -> Result<S, E>,
{
    let mut cur = start;
    let mut prev = prev;
    let mut h = (target - param(&cur)).clamp(-settings.max_step, settings.max_step);
    let mut halvings = 0;
    let mut steps = 0;
    while (target - param(&cur)).abs() > settings.arrive {
        let p = param(&cur);
        let to = if (target - p).abs() <= h.abs() * (1.0 + settings.snap) {
            target
        } else {
            p + h
        };
        match step(&cur, prev.as_ref(), to, halvings) {
            Ok(next) => {
                prev = Some(std::mem::replace(&mut cur, next));
                steps += 1;
            }
            Err(error) => {
                halvings += 1;
                if halvings > settings.max_halvings {
                    return Err(Stuck {
                        last: cur,
                        prev,
                        error,
                        steps,
                    });
                }
                h *= 0.5;
            }
        }
    }
    Ok(Walked {
        last: cur,
        prev,
        steps,
        halvings,
    })
}

/// Settings of a [`walk_adaptive`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AdaptiveSettings {
    /// Largest step (also the first).
    pub max_step: f64,
    /// A failed step is halved while it stays at least this long; below it the walk asks
    /// the caller's rescue.
    pub min_step: f64,
    /// An accepted step grows the next one by this factor (up to `max_step`).
    pub growth: f64,
    /// Rescues the walk may use before it gives up.
    pub max_rescues: usize,
    /// The step after a rescue.
    pub restart_step: f64,
}

/// Walks from `start` at the parameter `p0` up to `target > p0` with steps that adapt:
/// `step(current, to)` gives the state at `to`; an accepted step grows the next by
/// `settings.growth` (up to `max_step`), a failed one is halved and retried from the same
/// state. Where the step would fall below `min_step` (a fold of the path, where a natural
/// parameter cannot go on), `rescue(current, p, error)` may carry the walk past it: it
/// returns a state and the parameter it lies at (e.g. a snap-through to a lower state
/// beyond the fold), after which the walk goes on with `restart_step`; at most
/// `max_rescues` times.
///
/// # Errors
/// The failed step's error when the halvings and rescues are spent, or the rescue's
/// error.
pub fn walk_adaptive<S, E, F, R>(
    start: S,
    p0: f64,
    target: f64,
    settings: &AdaptiveSettings,
    mut step: F,
    mut rescue: R,
) -> Result<S, E>
where
    F: FnMut(&S, f64) -> Result<S, E>,
    R: FnMut(&S, f64, E) -> Result<(S, f64), E>,
{
    let mut cur = start;
    let (mut t, mut h) = (p0, settings.max_step);
    let mut rescues = 0;
    while t < target {
        let tn = (t + h).min(target);
        match step(&cur, tn) {
            Ok(s) => {
                cur = s;
                t = tn;
                h = (settings.growth * h).min(settings.max_step);
            }
            Err(e) => {
                h *= 0.5;
                if h >= settings.min_step {
                    continue;
                }
                if rescues == settings.max_rescues {
                    return Err(e);
                }
                rescues += 1;
                let (s, tn) = rescue(&cur, t, e)?;
                cur = s;
                t = tn;
                h = settings.restart_step;
            }
        }
    }
    Ok(cur)
}

/// Settings of a [`walk_steps`]: every step tries the full step first.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepSettings {
    /// The step (its sign is taken towards the target); the last step goes straight to the
    /// target when the remaining distance is at most `|step|`.
    pub step: f64,
    /// A failed step is retried with half the step; a step that fails after this many
    /// halvings ends the walk. The budget is per step: the next step starts from `step`.
    pub max_halvings: usize,
    /// Accepted steps allowed.
    pub max_steps: usize,
    /// The walk has arrived once `|target − p| ≤ arrive`.
    pub arrive: f64,
}

/// Why a [`walk_steps`] did not reach its target.
#[derive(Debug, Clone, PartialEq)]
pub enum Halted<S, E> {
    /// A step failed after [`StepSettings::max_halvings`] halvings.
    Stuck(Stuck<S, E>),
    /// [`StepSettings::max_steps`] steps were accepted before the target.
    OutOfSteps {
        /// The last accepted state.
        last: S,
    },
}

/// Walks from `start` (with `prev`, the state accepted before it) to the parameter value
/// `target` in steps of `settings.step`, as [`walk`] does but with a fresh step and a
/// fresh budget of halvings at every step: for a coordinate in which equal steps are
/// natural (a step in `ln a` is a fixed ratio of `a`), where [`walk`]'s shrinking step
/// would lose that.
///
/// # Errors
/// [`Halted`]: a step failed after its halvings, or the step budget is spent.
pub fn walk_steps<S, E, P, F>(
    start: S,
    prev: Option<S>,
    target: f64,
    param: P,
    settings: &StepSettings,
    mut step: F,
) -> Result<Walked<S>, Halted<S, E>>
where
    P: Fn(&S) -> f64,
    F: FnMut(&S, Option<&S>, f64, usize) -> Result<S, E>,
{
    let mut cur = start;
    let mut prev = prev;
    let mut steps = 0;
    let mut spent = 0;
    while (target - param(&cur)).abs() > settings.arrive {
        if steps >= settings.max_steps {
            return Err(Halted::OutOfSteps { last: cur });
        }
        let p = param(&cur);
        let mut h = settings.step.abs().copysign(target - p);
        let mut halvings = 0;
        let next = loop {
            let to = if (target - p).abs() <= h.abs() {
                target
            } else {
                p + h
            };
            match step(&cur, prev.as_ref(), to, halvings) {
                Ok(next) => break next,
                Err(error) if halvings >= settings.max_halvings => {
                    return Err(Halted::Stuck(Stuck {
                        last: cur,
                        prev,
                        error,
                        steps,
                    }))
                }
                Err(_) => {
                    halvings += 1;
                    spent += 1;
                    h *= 0.5;
                }
            }
        };
        prev = Some(std::mem::replace(&mut cur, next));
        steps += 1;
    }
    Ok(Walked {
        last: cur,
        prev,
        steps,
        halvings: spent,
    })
}

/// A point of a [`natural_branch`].
#[derive(Debug, Clone, PartialEq)]
pub struct NaturalPoint {
    /// The state.
    pub x: DVector<f64>,
    /// The parameter.
    pub p: f64,
}

/// The result of [`natural_branch`]: the points at the start and at each target reached
/// (in order), and the error that stopped the walk before the last target, if any.
#[derive(Debug, Clone)]
pub struct NaturalBranch {
    /// The start (corrected) and the states at the targets reached.
    pub points: Vec<NaturalPoint>,
    /// The last state accepted before the walk got stuck (not at a target), and why.
    pub stuck: Option<(NaturalPoint, ContinuationError)>,
}

/// Natural-parameter continuation of a [`Problem`] from `(x0, p0)` through the parameter
/// values `targets` (in the order given): each step starts Newton's method (tolerance
/// `tol`, `max_iter` iterations) from the secant predictor through the last two
/// accepted states (the last state alone at the first step) and [`walk`]s with
/// `settings`.
///
/// # Errors
/// The correction of the start at `p0`. Trouble later ends the branch with
/// [`NaturalBranch::stuck`].
pub fn natural_branch<P: Problem + ?Sized>(
    problem: &P,
    x0: &DVector<f64>,
    p0: f64,
    targets: &[f64],
    settings: &NaturalSettings,
    tol: f64,
    max_iter: usize,
) -> Result<NaturalBranch, ContinuationError> {
    let (x, _) = newton(problem, x0, p0, tol, max_iter)?;
    let mut points = vec![NaturalPoint { x, p: p0 }];
    let mut prev: Option<NaturalPoint> = None;
    for &target in targets {
        let cur = points.last().cloned().expect("the start");
        let walked = walk(
            cur,
            prev.clone(),
            target,
            |s: &NaturalPoint| s.p,
            settings,
            |cur, prev, to, _| {
                let guess = match prev {
                    Some(q) if q.p != cur.p => {
                        &cur.x + (&cur.x - &q.x) * ((to - cur.p) / (cur.p - q.p))
                    }
                    _ => cur.x.clone(),
                };
                newton(problem, &guess, to, tol, max_iter).map(|(x, _)| NaturalPoint { x, p: to })
            },
        );
        match walked {
            Ok(w) => {
                prev = w.prev;
                points.push(w.last);
            }
            Err(s) => {
                return Ok(NaturalBranch {
                    points,
                    stuck: Some((s.last, s.error)),
                })
            }
        }
    }
    Ok(NaturalBranch {
        points,
        stuck: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DMatrix;
    use std::convert::Infallible;

    /// The fold `x² + λ = 0`: two branches `x = ±√(−λ)` for `λ ≤ 0`, a fold at `λ = 0`.
    struct Fold;
    impl Problem for Fold {
        type Error = Infallible;
        fn dim(&self) -> usize {
            1
        }
        fn residual(&self, x: &DVector<f64>, p: f64) -> Result<DVector<f64>, Infallible> {
            Ok(DVector::from_element(1, x[0] * x[0] + p))
        }
        fn jacobian(&self, x: &DVector<f64>, _p: f64) -> Result<DMatrix<f64>, Infallible> {
            Ok(DMatrix::from_element(1, 1, 2.0 * x[0]))
        }
        fn dparam(&self, _x: &DVector<f64>, _p: f64) -> Result<DVector<f64>, Infallible> {
            Ok(DVector::from_element(1, 1.0))
        }
    }

    /// The pitchfork `x³ − λx = 0`: the trivial branch and `x = ±√λ` for `λ > 0`.
    struct Pitchfork;
    impl Problem for Pitchfork {
        type Error = Infallible;
        fn dim(&self) -> usize {
            1
        }
        fn residual(&self, x: &DVector<f64>, p: f64) -> Result<DVector<f64>, Infallible> {
            Ok(DVector::from_element(1, x[0].powi(3) - p * x[0]))
        }
        fn jacobian(&self, x: &DVector<f64>, p: f64) -> Result<DMatrix<f64>, Infallible> {
            Ok(DMatrix::from_element(1, 1, 3.0 * x[0] * x[0] - p))
        }
        fn dparam(&self, x: &DVector<f64>, _p: f64) -> Result<DVector<f64>, Infallible> {
            Ok(DVector::from_element(1, -x[0]))
        }
    }

    fn grid(a: f64, b: f64, n: usize) -> Vec<f64> {
        (1..=n).map(|k| a + (b - a) * k as f64 / n as f64).collect()
    }

    /// A path whose state (here its parameter) cannot be continued from below `0.5` past
    /// it: steps there fail until they fall below the minimum, the rescue carries the walk
    /// to `0.55`, and it goes on to the target with the restart step and growth.
    #[test]
    fn adaptive_walk_grows_halves_and_is_rescued_past_a_fold() {
        let settings = AdaptiveSettings {
            max_step: 0.25,
            min_step: 1.0 / 64.0,
            growth: 1.5,
            max_rescues: 1,
            restart_step: 1.0 / 32.0,
        };
        let mut tried = Vec::new();
        let step = |cur: &f64, to: f64| {
            tried.push(to);
            if *cur <= 0.5 && to > 0.5 {
                Err("fold")
            } else {
                Ok(to)
            }
        };
        let mut rescued = Vec::new();
        let rescue = |cur: &f64, t: f64, e: &'static str| {
            rescued.push((*cur, t, e));
            Ok((0.55, 0.55))
        };
        let last = walk_adaptive(0.0, 0.0, 1.0, &settings, step, rescue).unwrap();
        assert_eq!(last, 1.0);
        assert_eq!(rescued, vec![(0.5, 0.5, "fold")]);
        // 0.25, 0.5 accepted; 0.75, 0.625, 0.5625, 0.53125, 0.515625 fail (the next half,
        // 1/128, is below the minimum); then 0.55 + 1/32, growing by half up to 0.25.
        assert_eq!(
            tried[..7],
            [0.25, 0.5, 0.75, 0.625, 0.5625, 0.53125, 0.515625]
        );
        assert_eq!(tried[7], 0.55 + 1.0 / 32.0);
        assert_eq!(*tried.last().unwrap(), 1.0);
        // Without rescues left, the failed step's error comes back.
        let none = AdaptiveSettings {
            max_rescues: 0,
            ..settings
        };
        let stuck = walk_adaptive(
            0.0,
            0.0,
            1.0,
            &none,
            |cur: &f64, to: f64| {
                if *cur <= 0.5 && to > 0.5 {
                    Err("fold")
                } else {
                    Ok(to)
                }
            },
            |_: &f64, _, e| Err(e),
        );
        assert_eq!(stuck, Err("fold"));
    }

    #[test]
    fn fold_branch_is_exact_and_stops_at_the_fold() {
        // From λ = −1 (x = 1) towards λ = 0.5: the states at the targets below the fold
        // are x = √(−λ); the walk gets stuck between the last target before the fold and
        // the fold λ = 0, never beyond it.
        let targets = grid(-1.0, 0.5, 31); // no target at the fold itself
        let s = NaturalSettings {
            max_step: 0.05,
            max_halvings: 20,
            ..NaturalSettings::default()
        };
        let b = natural_branch(
            &Fold,
            &DVector::from_element(1, 1.1),
            -1.0,
            &targets,
            &s,
            1e-13,
            30,
        )
        .unwrap();
        for pt in &b.points {
            assert!((pt.x[0] - (-pt.p).sqrt()).abs() < 1e-10, "{pt:?}");
        }
        let last = b.points.last().unwrap().p;
        assert!(last < 0.0 && last > -0.06, "{last}");
        let (at, _) = b.stuck.expect("stuck at the fold");
        assert!(at.p <= 0.0 && at.p > -1e-4, "stuck at {}", at.p);
        assert!((at.x[0] - (-at.p).sqrt()).abs() < 1e-8);
    }

    #[test]
    fn pitchfork_branches_follow_their_exact_curves() {
        // The upper branch x = √λ from λ = 1 down to λ = 0.01, and the trivial branch
        // x = 0 straight through the pitchfork at λ = 0.
        let s = NaturalSettings {
            max_step: 0.1,
            ..NaturalSettings::default()
        };
        let down = grid(1.0, 0.01, 20);
        let b = natural_branch(
            &Pitchfork,
            &DVector::from_element(1, 0.9),
            1.0,
            &down,
            &s,
            1e-14,
            30,
        )
        .unwrap();
        assert!(b.stuck.is_none());
        assert_eq!(b.points.len(), 21);
        for pt in &b.points {
            assert!((pt.x[0] - pt.p.sqrt()).abs() < 1e-9, "{pt:?}");
        }
        let through = grid(-1.0, 1.0, 8);
        let t = natural_branch(
            &Pitchfork,
            &DVector::from_element(1, 0.1),
            -1.0,
            &through,
            &s,
            1e-14,
            30,
        )
        .unwrap();
        // x = 0 at λ = 0 has a singular Jacobian but a zero residual: Newton accepts it.
        assert!(t.stuck.is_none());
        assert!(t.points.iter().all(|pt| pt.x[0].abs() < 1e-12));
        assert!((t.points.last().unwrap().p - 1.0).abs() < 1e-15);
    }

    #[test]
    fn walk_steps_starts_every_step_afresh() {
        // Steps of 0.25 from 0 to 1; a "solver" that refuses every first attempt at
        // 0.5 (so the second step is retried at 0.125 and the third at full length
        // again). Fixed-ratio steps: each step starts from 0.25, not from the last
        // halved length.
        let s = StepSettings {
            step: 0.25,
            max_halvings: 3,
            max_steps: 100,
            arrive: 1e-15,
        };
        let mut calls = Vec::new();
        let r = walk_steps(
            0.0f64,
            None,
            1.0,
            |x| *x,
            &s,
            |cur, _, to, h| {
                calls.push((*cur, to, h));
                if to == 0.5 && h == 0 {
                    Err(to)
                } else {
                    Ok(to)
                }
            },
        );
        let w = r.unwrap();
        assert_eq!(w.last, 1.0);
        assert_eq!(w.halvings, 1);
        let tos: Vec<f64> = calls.iter().map(|c| c.1).collect();
        assert_eq!(tos, vec![0.25, 0.5, 0.375, 0.625, 0.875, 1.0]);
        // The last step goes straight to the target: from 0.875 the remaining 0.125 is
        // within one step.
        assert_eq!(calls[5], (0.875, 1.0, 0));
        // A step that fails after its halvings: stuck at the last state, with its error.
        let e = walk_steps(
            0.0f64,
            None,
            1.0,
            |x| *x,
            &s,
            |_, _, to, _| {
                if to > 0.26 {
                    Err(to)
                } else {
                    Ok(to)
                }
            },
        )
        .unwrap_err();
        match e {
            Halted::Stuck(st) => {
                assert_eq!(st.last, 0.25);
                // Tries 0.5, 0.375, 0.3125, 0.28125 (3 halvings): the last error.
                assert_eq!(st.error, 0.25 + 0.25 / 8.0);
            }
            other => panic!("{other:?}"),
        }
        // The step budget.
        let tight = StepSettings { max_steps: 2, ..s };
        let e = walk_steps(
            0.0f64,
            None,
            1.0,
            |x| *x,
            &tight,
            |_, _, to, _| Ok::<f64, ()>(to),
        )
        .unwrap_err();
        assert_eq!(e, Halted::OutOfSteps { last: 0.5 });
    }

    #[test]
    fn walk_halves_failed_steps_and_reports_where_it_stuck() {
        // A "solver" that accepts only steps of at most 0.3 and never beyond 1.0: from
        // 0 to 2 the first step (2) is halved to 1, 0.5, 0.25; it then walks in steps of
        // 0.25 up to 1.0 and spends its halvings there.
        let s = NaturalSettings {
            max_halvings: 8,
            ..NaturalSettings::default()
        };
        let mut calls = Vec::new();
        let r = walk(
            0.0f64,
            None,
            2.0,
            |x| *x,
            &s,
            |cur, _, to, h| {
                calls.push((*cur, to, h));
                if (to - cur).abs() <= 0.3 && to <= 1.0 {
                    Ok(to)
                } else {
                    Err(to)
                }
            },
        );
        let stuck = r.unwrap_err();
        assert_eq!(stuck.last, 1.0);
        assert_eq!(stuck.prev, Some(0.75));
        assert_eq!(stuck.steps, 4);
        // Halvings: 2 → 1 → 0.5 → 0.25 (three), then at 1.0 six more (0.125 … 0.0039).
        assert_eq!(calls.iter().filter(|c| c.0 == 1.0).count(), 6);
        assert_eq!(calls[0], (0.0, 2.0, 0));
        assert_eq!(calls[3], (0.0, 0.25, 3));
        // An infallible step reaches the target in one step when nothing bounds it.
        let r: Result<_, Stuck<f64, Infallible>> = walk(
            0.0f64,
            None,
            2.0,
            |x| *x,
            &NaturalSettings::default(),
            |_, _, to, _| Ok(to),
        );
        let w = r.unwrap();
        assert_eq!((w.last, w.steps, w.halvings), (2.0, 1, 0));
    }
}
