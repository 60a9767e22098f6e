//! Driving a [`Stepper`] to the end: the one stepping loop of every tracer.
//!
//! A tracer reacts to each accepted step (records points, reads special points, ends the
//! walk on its own criteria) but the loop around [`Stepper::step`] is always the same:
//! step, hand the step to the caller, stop when the caller or the run says so, and, if
//! asked, retry a step that failed with an error of the problem with half the step size.
//! [`Stepper::drive`] is that loop, so that callers write only their visitor.

use crate::branch::StopReason;
use crate::error::ContinuationError;
use crate::problem::Problem;
use crate::stepper::{Step, Stepper};

/// What a visitor of [`Stepper::drive`] says after an accepted step.
#[derive(Debug, Clone, PartialEq)]
pub enum Flow<T> {
    /// Go on stepping (unless the step carried a stop reason).
    Go,
    /// End the drive with this value.
    Stop(T),
}

/// What [`Stepper::drive`] does when a step fails with an error (of the problem or of
/// the stability callback; the stepper stays at its last accepted point).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OnError {
    /// End the drive with [`Driven::Failed`].
    Fail,
    /// Retry from the last accepted point with half the step size; when the halved step
    /// falls below `ds_min` the drive ends with [`Driven::TooSmall`].
    Halve,
}

/// How a [`Stepper::drive`] ended.
#[derive(Debug)]
pub enum Driven<T> {
    /// The visitor stopped the drive.
    Visitor(T),
    /// The run stopped ([`Step::stop`]); `cause` is the last error met since the last
    /// accepted point (with [`OnError::Halve`]), if any.
    Stopped {
        /// Why the run stopped.
        reason: StopReason,
        /// The last error since the last accepted point.
        cause: Option<ContinuationError>,
    },
    /// A step failed ([`OnError::Fail`]).
    Failed(ContinuationError),
    /// Halving after errors ([`OnError::Halve`]) brought the step below `ds_min`.
    TooSmall {
        /// The rejected (halved) step size.
        ds: f64,
        /// The error of the last failed step.
        cause: ContinuationError,
    },
}

impl<P: Problem + ?Sized> Stepper<'_, '_, P> {
    /// Steps until the visitor, the run or an error ends the walk. `visit(stepper, step)`
    /// is called with every step that accepted a point (its special points, and its stop
    /// reason if the run stops with it); [`Flow::Stop`] ends the drive at once, and
    /// [`Flow::Go`] after a step that carries a stop reason ends it with
    /// [`Driven::Stopped`]. A step that stops without a point ends the drive without a
    /// visit. Errors are handled as `on_error` says.
    pub fn drive<T, V>(&mut self, on_error: OnError, mut visit: V) -> Driven<T>
    where
        V: FnMut(&Self, Step) -> Flow<T>,
    {
        let mut cause: Option<ContinuationError> = None;
        loop {
            let step = match self.step() {
                Ok(step) => step,
                Err(e) => match on_error {
                    OnError::Fail => return Driven::Failed(e),
                    OnError::Halve => {
                        let ds = self.ds() * 0.5;
                        if self.set_ds(ds).is_err() {
                            return Driven::TooSmall { ds, cause: e };
                        }
                        cause = Some(e);
                        continue;
                    }
                },
            };
            if step.point.is_none() {
                match step.stop {
                    Some(reason) => return Driven::Stopped { reason, cause },
                    None => continue,
                }
            }
            cause = None;
            let stop = step.stop;
            if let Flow::Stop(t) = visit(self, step) {
                return Driven::Visitor(t);
            }
            if let Some(reason) = stop {
                return Driven::Stopped {
                    reason,
                    cause: None,
                };
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Continuation, Direction, PseudoArclength, SpecialKind};
    use nalgebra::{DMatrix, DVector};
    use std::cell::Cell;

    /// `x² + p² = 1`, with an error at every evaluation while `fail` counts down.
    struct Circle {
        fail: Cell<usize>,
    }
    #[derive(Debug)]
    struct Refused;
    impl std::fmt::Display for Refused {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            f.write_str("refused")
        }
    }
    impl std::error::Error for Refused {}
    impl Circle {
        fn check(&self) -> Result<(), Refused> {
            match self.fail.get() {
                0 => Ok(()),
                k => {
                    self.fail.set(k - 1);
                    Err(Refused)
                }
            }
        }
    }
    impl Problem for Circle {
        type Error = Refused;
        fn dim(&self) -> usize {
            1
        }
        fn residual(&self, x: &DVector<f64>, p: f64) -> Result<DVector<f64>, Refused> {
            self.check()?;
            Ok(DVector::from_element(1, x[0] * x[0] + p * p - 1.0))
        }
        fn jacobian(&self, x: &DVector<f64>, _p: f64) -> Result<DMatrix<f64>, Refused> {
            Ok(DMatrix::from_element(1, 1, 2.0 * x[0]))
        }
        fn dparam(&self, _x: &DVector<f64>, p: f64) -> Result<DVector<f64>, Refused> {
            Ok(DVector::from_element(1, 2.0 * p))
        }
    }

    fn settings() -> PseudoArclength {
        PseudoArclength::new()
            .with_ds(0.1)
            .and_then(|s| s.with_ds_bounds(0.01, 0.1))
            .and_then(|s| s.with_range(-2.0, 0.5))
            .and_then(|s| s.with_direction(Direction::Forward))
            .unwrap()
    }

    #[test]
    fn drives_to_the_range_end_and_visits_every_point() {
        let c = Circle { fail: Cell::new(0) };
        let cont = Continuation::new(&c, settings());
        let mut st = cont.start(&DVector::from_element(1, 1.0), 0.0).unwrap();
        let mut seen = Vec::new();
        let end: Driven<()> = st.drive(OnError::Fail, |_, step| {
            let pt = step.point.expect("visited steps carry a point");
            // Every visited point lies on the circle.
            assert!((pt.x[0] * pt.x[0] + pt.p * pt.p - 1.0).abs() < 1e-9);
            seen.push(pt.p);
            Flow::Go
        });
        match end {
            Driven::Stopped { reason, cause } => {
                assert_eq!(reason, StopReason::LeftRange { boundary: 0.5 });
                assert!(cause.is_none());
            }
            other => panic!("{other:?}"),
        }
        assert_eq!(*seen.last().unwrap(), 0.5);
        assert!(seen.windows(2).all(|w| w[1] > w[0]));
        assert_eq!(seen.len(), st.steps());
    }

    #[test]
    fn a_step_over_a_fold_beyond_the_range_stops_at_the_boundary() {
        // Steps of 0.6 on the circle: the third runs from p = 0.88 over the fold at p = 1
        // and back to p = 0.9988, inside the range [-2, 0.9995]; the drive ends on the
        // boundary instead of turning, and no point or fold lies outside the range.
        let c = Circle { fail: Cell::new(0) };
        let s = settings()
            .with_range(-2.0, 0.9995)
            .and_then(|s| s.with_ds(0.6))
            .and_then(|s| s.with_ds_bounds(0.01, 0.6))
            .and_then(|s| s.with_max_turn(1.0))
            .unwrap();
        let cont = Continuation::new(&c, s);
        let mut st = cont.start(&DVector::from_element(1, 1.0), 0.0).unwrap();
        let mut seen = Vec::new();
        let mut folds = 0;
        let end: Driven<()> = st.drive(OnError::Fail, |_, step| {
            let pt = step.point.expect("visited steps carry a point");
            assert!((pt.x[0] * pt.x[0] + pt.p * pt.p - 1.0).abs() < 1e-9);
            seen.push(pt.p);
            folds += step
                .special
                .iter()
                .filter(|s| s.kind == SpecialKind::Fold)
                .count();
            Flow::Go
        });
        match end {
            Driven::Stopped { reason, .. } => {
                assert_eq!(reason, StopReason::LeftRange { boundary: 0.9995 })
            }
            other => panic!("{other:?}"),
        }
        assert_eq!(folds, 0, "{seen:?}");
        assert_eq!(*seen.last().unwrap(), 0.9995);
        assert!(seen.windows(2).all(|w| w[1] > w[0]), "{seen:?}");
    }

    #[test]
    fn the_visitor_ends_the_drive_with_its_value() {
        // Through the fold at p = 1 (range widened): the visitor stops at the fold.
        let c = Circle { fail: Cell::new(0) };
        let s = settings().with_range(-2.0, 2.0).unwrap();
        let cont = Continuation::new(&c, s);
        let mut st = cont.start(&DVector::from_element(1, 1.0), 0.0).unwrap();
        let end = st.drive(OnError::Fail, |_, step| {
            match step.special.iter().find(|s| s.kind == SpecialKind::Fold) {
                Some(f) => Flow::Stop(f.p),
                None => Flow::Go,
            }
        });
        match end {
            Driven::Visitor(p) => assert!((p - 1.0).abs() < 1e-8, "{p}"),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn errors_fail_or_halve_the_step() {
        let x0 = DVector::from_element(1, 1.0);
        // OnError::Fail: the first error ends the drive.
        let c = Circle { fail: Cell::new(0) };
        let cont = Continuation::new(&c, settings());
        let mut st = cont.start(&x0, 0.0).unwrap();
        c.fail.set(1);
        let end: Driven<()> = st.drive(OnError::Fail, |_, _| Flow::Go);
        assert!(matches!(end, Driven::Failed(_)), "{end:?}");
        assert_eq!(st.steps(), 0);
        // OnError::Halve: one failure halves the step (0.1 → 0.05) and the drive goes
        // on to the end of the range.
        let c = Circle { fail: Cell::new(0) };
        let cont = Continuation::new(&c, settings());
        let mut st = cont.start(&x0, 0.0).unwrap();
        c.fail.set(1);
        let mut first = None;
        let end: Driven<()> = st.drive(OnError::Halve, |_, step| {
            first.get_or_insert(step.point.unwrap().p);
            Flow::Go
        });
        assert!(matches!(end, Driven::Stopped { .. }), "{end:?}");
        let p1 = first.unwrap();
        assert!(p1 > 0.0 && p1 < 0.06, "first step at p = {p1}");
        // Failures without end: halving reaches ds_min = 0.01 (0.1 → 0.05 → 0.025 →
        // 0.0125 → 0.00625 < 0.01) and the drive ends there.
        let c = Circle { fail: Cell::new(0) };
        let cont = Continuation::new(&c, settings());
        let mut st = cont.start(&x0, 0.0).unwrap();
        c.fail.set(usize::MAX);
        let end: Driven<()> = st.drive(OnError::Halve, |_, _| Flow::Go);
        match end {
            Driven::TooSmall { ds, cause } => {
                assert_eq!(ds, 0.00625);
                assert!(cause.to_string().contains("refused"), "{cause}");
            }
            other => panic!("{other:?}"),
        }
    }
}
