//! Continuation to a target value of the parameter: pseudo-arclength steps (through
//! folds) until the branch crosses `p = target`, with the state there interpolated
//! between the two points that bracket it.
//!
//! This is the loop of a homotopy: a solution known at one parameter value is carried to
//! another, and the caller corrects the interpolated state at the target with its own
//! solver. The loop gives up when the branch turns back past its start, when it has
//! passed more folds than allowed, when the caller's budget says so, or when the
//! continuation stops.

use nalgebra::DVector;

use crate::branch::SpecialKind;
use crate::problem::Problem;
use crate::settings::PseudoArclength;
use crate::tracker::Continuation;

/// Limits of [`reach`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReachLimits {
    /// Give up after more than this many folds.
    pub max_folds: usize,
    /// Give up once the branch is this far (in the parameter) behind its start.
    pub turn_back: f64,
}

impl Default for ReachLimits {
    /// 4 folds, `0.05` behind the start.
    fn default() -> Self {
        Self {
            max_folds: 4,
            turn_back: 0.05,
        }
    }
}

/// The branch reached the target.
#[derive(Debug, Clone, PartialEq)]
pub struct Reached {
    /// The state linearly interpolated at the target between the bracketing points.
    pub x: DVector<f64>,
    /// Accepted steps.
    pub steps: usize,
    /// Parameter values of the folds passed.
    pub folds: Vec<f64>,
}

/// The branch did not reach the target.
#[derive(Debug, Clone, PartialEq)]
pub struct NotReached {
    /// Parameter values of the folds passed.
    pub folds: Vec<f64>,
    /// The parameter value closest to the target that the branch reached.
    pub closest: f64,
}

/// Continues the solution near `(x0, p0)` of `problem` with `settings` until the branch
/// crosses `p = target` (see the module docs). `spend()` is asked before each step and
/// ends the walk when it returns `false` (a work budget shared by several walks). The
/// settings' direction should point towards the target.
///
/// # Errors
/// [`NotReached`] with the folds passed and the closest value reached: the start cannot
/// be corrected, a step fails, the continuation stops, the budget is spent, the branch
/// turns back by more than [`ReachLimits::turn_back`] past `p0`, or it passes more than
/// [`ReachLimits::max_folds`] folds.
pub fn reach<P: Problem + ?Sized, B: FnMut() -> bool>(
    problem: &P,
    settings: &PseudoArclength,
    x0: &DVector<f64>,
    p0: f64,
    target: f64,
    limits: &ReachLimits,
    mut spend: B,
) -> Result<Reached, NotReached> {
    let cont = Continuation::new(problem, settings.clone());
    let mut stepper = cont.start(x0, p0).map_err(|_| NotReached {
        folds: vec![],
        closest: p0,
    })?;
    let sign = (target - p0).signum();
    let mut prev = (x0.clone(), p0);
    let mut folds = Vec::new();
    let mut closest = p0;
    loop {
        if !spend() {
            return Err(NotReached { folds, closest });
        }
        let step = match stepper.step() {
            Ok(s) => s,
            Err(_) => return Err(NotReached { folds, closest }),
        };
        folds.extend(
            step.special
                .iter()
                .filter(|sp| sp.kind == SpecialKind::Fold)
                .map(|sp| sp.p),
        );
        if let Some(pt) = &step.point {
            if (pt.p - target) * sign >= 0.0 {
                let t = (target - prev.1) / (pt.p - prev.1);
                return Ok(Reached {
                    x: &prev.0 + (&pt.x - &prev.0) * t,
                    steps: stepper.steps(),
                    folds,
                });
            }
            if (pt.p - closest) * sign > 0.0 {
                closest = pt.p;
            }
            if (pt.p - p0) * sign < -limits.turn_back || folds.len() > limits.max_folds {
                return Err(NotReached { folds, closest });
            }
            prev = (pt.x.clone(), pt.p);
        }
        if step.stop.is_some() {
            return Err(NotReached { folds, closest });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::settings::Direction;
    use nalgebra::DMatrix;
    use std::convert::Infallible;

    /// `x² + p² = 1`: from `(1, 0)` the branch reaches `p = 0.6` at `x = 0.8`; `p = 1.2`
    /// lies beyond the fold at `p = 1`, where the circle turns back.
    struct Circle;
    impl Problem for Circle {
        type Error = Infallible;
        fn dim(&self) -> usize {
            1
        }
        fn residual(&self, x: &DVector<f64>, p: f64) -> Result<DVector<f64>, Infallible> {
            Ok(DVector::from_element(1, x[0] * x[0] + p * p - 1.0))
        }
        fn jacobian(&self, x: &DVector<f64>, _p: f64) -> Result<DMatrix<f64>, Infallible> {
            Ok(DMatrix::from_element(1, 1, 2.0 * x[0]))
        }
        fn dparam(&self, _x: &DVector<f64>, p: f64) -> Result<DVector<f64>, Infallible> {
            Ok(DVector::from_element(1, 2.0 * p))
        }
    }

    fn settings() -> PseudoArclength {
        PseudoArclength::new()
            .with_ds(0.05)
            .and_then(|s| s.with_ds_bounds(1e-7, 0.1))
            .and_then(|s| s.with_direction(Direction::Forward))
            .and_then(|s| s.with_detect_branch_points(false))
            .unwrap()
    }

    #[test]
    fn reaches_a_target_on_the_circle() {
        let x0 = DVector::from_element(1, 1.0);
        let r = reach(
            &Circle,
            &settings(),
            &x0,
            0.0,
            0.6,
            &ReachLimits::default(),
            || true,
        )
        .unwrap();
        // Linear interpolation on a chord of length ≤ 0.1: error ≤ curvature·h²/8.
        assert!((r.x[0] - 0.8).abs() < 0.1 * 0.1 / 8.0, "{}", r.x[0]);
        assert!(r.folds.is_empty() && r.steps >= 6);
    }

    #[test]
    fn a_target_beyond_the_fold_is_not_reached() {
        let x0 = DVector::from_element(1, 1.0);
        let e = reach(
            &Circle,
            &settings(),
            &x0,
            0.0,
            1.2,
            &ReachLimits::default(),
            || true,
        )
        .unwrap_err();
        // The fold at p = 1 is passed and located; the branch turns back past p = 0.
        assert_eq!(e.folds.len(), 1);
        assert!((e.folds[0] - 1.0).abs() < 1e-8, "{:?}", e.folds);
        assert!((e.closest - 1.0).abs() < 0.01, "{}", e.closest);
        // A budget of three steps stops the walk early.
        let mut n = 0;
        let e = reach(
            &Circle,
            &settings(),
            &x0,
            0.0,
            0.9,
            &ReachLimits::default(),
            || {
                n += 1;
                n <= 3
            },
        )
        .unwrap_err();
        assert!(e.folds.is_empty() && e.closest > 0.0 && e.closest < 0.9);
    }
}
