//! The step-by-step API: `Continuation::start`, `Stepper`.

use std::convert::Infallible;

use nalgebra::{DMatrix, DVector};
use rodloop_continuation::{
    Branch, Continuation, ContinuationError, Direction, Problem, PseudoArclength, SpecialKind,
    Step, StopReason,
};

/// A one-unknown problem given by three closures.
struct Scalar<F, J, D> {
    f: F,
    j: J,
    d: D,
}

impl<F, J, D> Problem for Scalar<F, J, D>
where
    F: Fn(f64, f64) -> f64,
    J: Fn(f64, f64) -> f64,
    D: Fn(f64, f64) -> f64,
{
    type Error = Infallible;
    fn dim(&self) -> usize {
        1
    }
    fn residual(&self, x: &DVector<f64>, p: f64) -> Result<DVector<f64>, Infallible> {
        Ok(DVector::from_element(1, (self.f)(x[0], p)))
    }
    fn jacobian(&self, x: &DVector<f64>, p: f64) -> Result<DMatrix<f64>, Infallible> {
        Ok(DMatrix::from_element(1, 1, (self.j)(x[0], p)))
    }
    fn dparam(&self, x: &DVector<f64>, p: f64) -> Result<DVector<f64>, Infallible> {
        Ok(DVector::from_element(1, (self.d)(x[0], p)))
    }
}

fn v1(a: f64) -> DVector<f64> {
    DVector::from_element(1, a)
}

/// x² + p² = 1: folds at (0, ±1).
fn circle() -> impl Problem<Error = Infallible> {
    Scalar {
        f: |x: f64, p: f64| x * x + p * p - 1.0,
        j: |x: f64, _p: f64| 2.0 * x,
        d: |_x: f64, p: f64| 2.0 * p,
    }
}

/// p − x²: fold at (0, 0).
fn fold_nf() -> impl Problem<Error = Infallible> {
    Scalar {
        f: |x: f64, p: f64| p - x * x,
        j: |x: f64, _p: f64| -2.0 * x,
        d: |_x: f64, _p: f64| 1.0,
    }
}

/// p x − x³: branch point at (0, 0).
fn pitchfork() -> impl Problem<Error = Infallible> {
    Scalar {
        f: |x: f64, p: f64| p * x - x * x * x,
        j: |x: f64, p: f64| p - 3.0 * x * x,
        d: |x: f64, _p: f64| x,
    }
}

/// Rebuilds a branch from the first point and the reported steps alone.
fn assemble(first: rodloop_continuation::Point, steps: &[Step]) -> Branch {
    let mut points = vec![first];
    let mut special = Vec::new();
    for s in steps {
        points.extend(s.point.clone());
        special.extend(s.special.iter().cloned());
    }
    Branch {
        points,
        special,
        stop: steps.last().and_then(|s| s.stop).expect("a final stop"),
    }
}

#[test]
fn stepping_to_the_end_reproduces_run_with_monitors() {
    let problem = circle();
    let settings = PseudoArclength::new().with_ds(0.03).unwrap();
    let cont = Continuation::new(&problem, settings)
        .with_event("x = 1/2", |x: &DVector<f64>, _p: f64| x[0] - 0.5)
        .with_stability_fn(|x: &DVector<f64>, _p: f64| usize::from(x[0] < 0.0));
    let reference = cont.run(&v1(1.0), 0.0).unwrap();
    // Two folds, two events, two index changes on the way round.
    assert_eq!(reference.stop, StopReason::ClosedLoop);
    assert_eq!(reference.folds().count(), 2);
    assert_eq!(reference.events(0).count(), 2);
    assert_eq!(reference.index_changes().count(), 2);

    // By hand: every step but the last reports no stop, and carries a point.
    let mut stepper = cont.start(&v1(1.0), 0.0).unwrap();
    let first = stepper.current();
    assert_eq!(stepper.num_points(), 1);
    let mut steps = Vec::new();
    loop {
        let step = stepper.step().unwrap();
        assert!(step.point.is_some());
        let done = step.stop.is_some();
        steps.push(step);
        if done {
            break;
        }
    }
    assert_eq!(steps.len(), reference.points.len() - 1);
    assert_eq!(stepper.stop_reason(), Some(StopReason::ClosedLoop));
    // The reports alone give the same branch, bit for bit, as does finish().
    assert_eq!(assemble(first, &steps), reference);
    // Special points are reported in the step that contains them.
    for (k, s) in steps.iter().enumerate() {
        assert!(s.special.iter().all(|sp| sp.segment == k));
    }
    // After the stop, step() adds nothing and repeats the reason.
    let again = stepper.step().unwrap();
    assert_eq!(again.point, None);
    assert_eq!(again.stop, Some(StopReason::ClosedLoop));
    assert!(again.special.is_empty());
    assert_eq!(stepper.finish(), reference);

    // As an iterator.
    let mut stepper = cont.start(&v1(1.0), 0.0).unwrap();
    let all: Vec<Step> = stepper.by_ref().collect::<Result<_, _>>().unwrap();
    assert_eq!(all, steps);
    assert!(stepper.next().is_none());
    assert_eq!(stepper.finish(), reference);
}

#[test]
fn stepping_reproduces_switch_branch() {
    let problem = pitchfork();
    let settings = PseudoArclength::new()
        .with_ds(0.03)
        .unwrap()
        .with_range(-0.5, 0.5)
        .unwrap();
    let cont = Continuation::new(&problem, settings);
    let trivial = cont.run(&v1(0.0), -0.4).unwrap();
    let bp = trivial.branch_points().next().unwrap();
    let reference = cont.switch_branch(bp, Direction::Backward).unwrap();
    let mut stepper = cont.start_switch(bp, Direction::Backward).unwrap();
    // The stepper starts with the branch point and the first point off it.
    assert_eq!(stepper.num_points(), 2);
    while stepper.step().unwrap().stop.is_none() {}
    assert_eq!(stepper.finish(), reference);
    // The lower half of the nontrivial branch p = x², to p = 0.5.
    let last = reference.last().unwrap();
    assert_eq!(reference.stop, StopReason::LeftRange { boundary: 0.5 });
    assert!((last.x[0] + 0.5f64.sqrt()).abs() < 1e-10);
}

#[test]
fn stop_at_first_fold_then_resume_or_reverse() {
    let problem = fold_nf();
    let settings = PseudoArclength::new()
        .with_ds(0.05)
        .unwrap()
        .with_range(-1.0, 1.0)
        .unwrap()
        .with_direction(Direction::Backward)
        .unwrap();
    let cont = Continuation::new(&problem, settings);
    let reference = cont.run(&v1(0.8), 0.64).unwrap();

    let run_to_fold = || {
        let mut stepper = cont.start(&v1(0.8), 0.64).unwrap();
        loop {
            let step = stepper.step().unwrap();
            assert!(step.stop.is_none());
            if let Some(f) = step.special.iter().find(|s| s.kind == SpecialKind::Fold) {
                // The step that contains the fold ends past it: x < 0.
                assert!(f.p.abs() < 1e-12 && f.x[0].abs() < 1e-8);
                assert!(step.point.as_ref().unwrap().x[0] < 0.0);
                return stepper;
            }
        }
    };

    // Resume: stopping to look changes nothing.
    let mut stepper = run_to_fold();
    assert!(
        stepper.tangent()[1] > 0.0,
        "past the fold p increases again"
    );
    while stepper.step().unwrap().stop.is_none() {}
    assert_eq!(stepper.finish(), reference);

    // Finish early: the branch so far, ending just past the fold.
    let stepper = run_to_fold();
    let k = stepper.num_points();
    let partial = stepper.finish();
    assert_eq!(partial.stop, StopReason::Interrupted);
    assert_eq!(partial.points[..], reference.points[..k]);
    assert_eq!(partial.folds().count(), 1);

    // Reverse at the point past the fold: the new branch goes back over the fold onto
    // the x > 0 half and leaves the range at p = 1 with x = +1 (not −1).
    let mut stepper = run_to_fold();
    let here = stepper.current();
    let t_before = stepper.tangent().clone();
    let old = stepper.reverse();
    assert_eq!(old.stop, StopReason::Interrupted);
    assert_eq!(old.points.len(), k);
    assert_eq!(stepper.num_points(), 1);
    assert_eq!(stepper.current().x, here.x);
    assert_eq!(stepper.current().s, 0.0);
    assert_eq!(stepper.tangent(), &(-t_before));
    while stepper.step().unwrap().stop.is_none() {}
    let back = stepper.finish();
    assert_eq!(back.stop, StopReason::LeftRange { boundary: 1.0 });
    let last = back.last().unwrap();
    assert!((last.x[0] - 1.0).abs() < 1e-10, "{}", last.x[0]);
    // It crosses the fold once more, and the flipped orientation creates no spurious
    // branch point (det [A; tᵀ] changes sign with t).
    assert_eq!(back.folds().count(), 1);
    assert_eq!(back.branch_points().count(), 0);
    assert!(back.folds().next().unwrap().p.abs() < 1e-12);
}

#[test]
fn restart_continues_the_same_step_sequence() {
    let problem = circle();
    let long = PseudoArclength::new()
        .with_ds(0.05)
        .unwrap()
        .with_max_steps(12)
        .unwrap();
    let reference = Continuation::new(&problem, long)
        .run(&v1(1.0), 0.0)
        .unwrap();
    assert_eq!(reference.stop, StopReason::MaxSteps);
    assert_eq!(reference.points.len(), 13);

    let short = PseudoArclength::new()
        .with_ds(0.05)
        .unwrap()
        .with_max_steps(5)
        .unwrap();
    let cont = Continuation::new(&problem, short);
    let mut stepper = cont.start(&v1(1.0), 0.0).unwrap();
    // The step that uses up the budget reports MaxSteps together with its point.
    for k in 1..=5 {
        let step = stepper.step().unwrap();
        assert!(step.point.is_some());
        assert_eq!(step.stop.is_some(), k == 5);
    }
    assert_eq!(stepper.stop_reason(), Some(StopReason::MaxSteps));
    assert_eq!(stepper.steps(), 5);
    let first = stepper.restart();
    assert_eq!(first.stop, StopReason::MaxSteps);
    assert_eq!(first.points[..], reference.points[..6]);
    // The second branch starts at point 5 (arclength reset) and, with the step size
    // kept, repeats the reference's steps 6.. exactly.
    for _ in 0..7 {
        stepper.step().unwrap();
    }
    let second = stepper.finish();
    assert_eq!(second.stop, StopReason::MaxSteps);
    assert_eq!(second.points.len(), 6);
    assert_eq!(second.points[0].s, 0.0);
    for (a, b) in second.points.iter().zip(&reference.points[5..11]) {
        assert_eq!((&a.x, a.p, &a.tangent), (&b.x, b.p, &b.tangent));
    }
}

#[test]
fn set_ds_stop_and_accessors() {
    let problem = fold_nf();
    let settings = PseudoArclength::new()
        .with_ds(0.01)
        .unwrap()
        .with_ds_bounds(1e-6, 0.2)
        .unwrap();
    let cont = Continuation::new(&problem, settings);
    let mut stepper = cont.start(&v1(1.0), 1.0).unwrap();
    assert_eq!(stepper.ds(), 0.01);
    assert!(matches!(
        stepper.set_ds(0.5),
        Err(ContinuationError::InvalidSetting { name: "ds", .. })
    ));
    assert!(stepper.set_ds(f64::NAN).is_err());
    assert!(stepper.set_ds(1e-7).is_err());
    stepper.set_ds(0.1).unwrap();
    // On p = x² at (1, 1) the tangent is (ẋ, ṗ) ∝ (1, 2x) = (1, 2), oriented towards
    // increasing p; the next point lies at pseudo-arclength 0.1 along it.
    let t0 = stepper.tangent().clone();
    let expect = DVector::from_column_slice(&[1.0, 2.0]) / 5f64.sqrt();
    assert!((&t0 - &expect).amax() < 1e-12);
    let step = stepper.step().unwrap();
    let pt = step.point.unwrap();
    assert!((pt.ds - 0.1).abs() < 1e-12, "{}", pt.ds);
    assert!((pt.p - pt.x[0] * pt.x[0]).abs() < 1e-10);
    assert_eq!(stepper.current(), pt);
    assert_eq!(stepper.continuation().settings().ds(), 0.01);

    stepper.stop();
    assert_eq!(stepper.stop_reason(), Some(StopReason::Interrupted));
    let after = stepper.step().unwrap();
    assert_eq!(after.point, None);
    assert_eq!(after.stop, Some(StopReason::Interrupted));
    let branch = stepper.finish();
    assert_eq!(branch.points.len(), 2);
    assert_eq!(branch.stop, StopReason::Interrupted);
}

#[test]
fn start_validates_like_run() {
    let problem = fold_nf();
    let cont = Continuation::new(
        &problem,
        PseudoArclength::new().with_range(0.0, 1.0).unwrap(),
    );
    assert!(matches!(
        cont.start(&v1(1.0), 2.0),
        Err(ContinuationError::StartOutsideRange { .. })
    ));
    assert!(matches!(
        cont.start(&DVector::zeros(2), 0.5),
        Err(ContinuationError::WrongStateLength { .. })
    ));
    // Starting on the boundary heading out: the first step stops without a point.
    let mut stepper = cont.start(&v1(1.0), 1.0).unwrap();
    let step = stepper.step().unwrap();
    assert_eq!(step.point, None);
    assert_eq!(step.stop, Some(StopReason::LeftRange { boundary: 1.0 }));
    assert_eq!(stepper.finish().points.len(), 1);
}
