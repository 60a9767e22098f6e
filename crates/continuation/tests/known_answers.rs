//! Continuation tests against analytically known answers.
//!
//! One file of integration tests sharing the closure-defined test problem (`Fns`) and its
//! finite-difference checks; each test is a problem with an answer known in closed form.

use std::convert::Infallible;

use nalgebra::{DMatrix, DVector, Matrix3, Rotation3, Vector3};
use rodloop_continuation::{
    fd_dparam, fd_jacobian, newton, solve_all_at, solve_at, Continuation, ContinuationError,
    Direction, Problem, PseudoArclength, SpecialKind, StopReason,
};

/// A problem given by three closures (residual, Jacobian, parameter derivative).
struct Fns<F, J, D> {
    n: usize,
    f: F,
    j: J,
    d: D,
}

impl<F, J, D> Problem for Fns<F, J, D>
where
    F: Fn(&DVector<f64>, f64) -> DVector<f64>,
    J: Fn(&DVector<f64>, f64) -> DMatrix<f64>,
    D: Fn(&DVector<f64>, f64) -> DVector<f64>,
{
    type Error = Infallible;
    fn dim(&self) -> usize {
        self.n
    }
    fn residual(&self, x: &DVector<f64>, p: f64) -> Result<DVector<f64>, Infallible> {
        Ok((self.f)(x, p))
    }
    fn jacobian(&self, x: &DVector<f64>, p: f64) -> Result<DMatrix<f64>, Infallible> {
        Ok((self.j)(x, p))
    }
    fn dparam(&self, x: &DVector<f64>, p: f64) -> Result<DVector<f64>, Infallible> {
        Ok((self.d)(x, p))
    }
}

fn v1(a: f64) -> DVector<f64> {
    DVector::from_element(1, a)
}
fn m1(a: f64) -> DMatrix<f64> {
    DMatrix::from_element(1, 1, a)
}

/// x² + p² = 1: folds at (0, ±1).
fn circle() -> impl Problem<Error = Infallible> {
    Fns {
        n: 1,
        f: |x: &DVector<f64>, p: f64| v1(x[0] * x[0] + p * p - 1.0),
        j: |x: &DVector<f64>, _p: f64| m1(2.0 * x[0]),
        d: |_x: &DVector<f64>, p: f64| v1(2.0 * p),
    }
}

/// Fold normal form p − x²: fold at (0, 0).
fn fold_nf() -> impl Problem<Error = Infallible> {
    Fns {
        n: 1,
        f: |x: &DVector<f64>, p: f64| v1(p - x[0] * x[0]),
        j: |x: &DVector<f64>, _p: f64| m1(-2.0 * x[0]),
        d: |_x: &DVector<f64>, _p: f64| v1(1.0),
    }
}

/// Pitchfork normal form p x − x³: branch point at (0, 0), branches x = 0 and x² = p.
fn pitchfork() -> impl Problem<Error = Infallible> {
    Fns {
        n: 1,
        f: |x: &DVector<f64>, p: f64| v1(p * x[0] - x[0].powi(3)),
        j: |x: &DVector<f64>, p: f64| m1(p - 3.0 * x[0] * x[0]),
        d: |x: &DVector<f64>, _p: f64| v1(x[0]),
    }
}

/// Transcritical normal form p x − x²: branches x = 0 and x = p cross at (0, 0) at a
/// non-right angle.
fn transcritical() -> impl Problem<Error = Infallible> {
    Fns {
        n: 1,
        f: |x: &DVector<f64>, p: f64| v1(p * x[0] - x[0] * x[0]),
        j: |x: &DVector<f64>, p: f64| m1(p - 2.0 * x[0]),
        d: |x: &DVector<f64>, _p: f64| v1(x[0]),
    }
}

fn rotation() -> Matrix3<f64> {
    Rotation3::from_euler_angles(0.3, -0.7, 1.1).into_inner()
}

/// F(x, p) = Q G(Qᵀ x, p) with Q orthogonal and
/// G = (u₁³ − 3u₁ + u₂ + u₃ − p, u₂ − u₁/2, u₃ + u₁²).
/// Solutions: u₂ = u₁/2, u₃ = −u₁², p = u₁³ − u₁² − 5u₁/2; folds where
/// dp/du₁ = 3u₁² − 2u₁ − 5/2 = 0, u₁ = (2 ± √34)/6. Det ∂F/∂x = det ∂G/∂u, so the
/// folds do not depend on Q, which mixes all components.
struct Rotated3 {
    q: Matrix3<f64>,
}

impl Rotated3 {
    fn u_of(&self, x: &DVector<f64>) -> Vector3<f64> {
        self.q.transpose() * Vector3::new(x[0], x[1], x[2])
    }
    fn x_of_u1(&self, u1: f64) -> DVector<f64> {
        let x = self.q * Vector3::new(u1, 0.5 * u1, -u1 * u1);
        DVector::from_column_slice(x.as_slice())
    }
    fn p_of_u1(u1: f64) -> f64 {
        u1.powi(3) - u1 * u1 - 2.5 * u1
    }
}

impl Problem for Rotated3 {
    type Error = Infallible;
    fn dim(&self) -> usize {
        3
    }
    fn residual(&self, x: &DVector<f64>, p: f64) -> Result<DVector<f64>, Infallible> {
        let u = self.u_of(x);
        let g = Vector3::new(
            u[0].powi(3) - 3.0 * u[0] + u[1] + u[2] - p,
            u[1] - 0.5 * u[0],
            u[2] + u[0] * u[0],
        );
        Ok(DVector::from_column_slice((self.q * g).as_slice()))
    }
    fn jacobian(&self, x: &DVector<f64>, _p: f64) -> Result<DMatrix<f64>, Infallible> {
        let u = self.u_of(x);
        let jg = Matrix3::new(
            3.0 * u[0] * u[0] - 3.0,
            1.0,
            1.0,
            -0.5,
            1.0,
            0.0,
            2.0 * u[0],
            0.0,
            1.0,
        );
        let j = self.q * jg * self.q.transpose();
        Ok(DMatrix::from_column_slice(3, 3, j.as_slice()))
    }
    fn dparam(&self, _x: &DVector<f64>, _p: f64) -> Result<DVector<f64>, Infallible> {
        let d = self.q * Vector3::new(-1.0, 0.0, 0.0);
        Ok(DVector::from_column_slice(d.as_slice()))
    }
}

/// A rotated 2-D pitchfork with the branch point at p = 1:
/// G = ((p − 1) u₁ − u₁³, u₂ − u₁²), F = Q G(Qᵀx). Branches: u = 0, and u₁² = p − 1,
/// u₂ = p − 1.
struct Rotated2Pitchfork {
    c: f64,
    s: f64,
}

impl Rotated2Pitchfork {
    fn new(angle: f64) -> Self {
        Rotated2Pitchfork {
            c: angle.cos(),
            s: angle.sin(),
        }
    }
    fn q(&self) -> DMatrix<f64> {
        DMatrix::from_row_slice(2, 2, &[self.c, -self.s, self.s, self.c])
    }
    fn u_of(&self, x: &DVector<f64>) -> DVector<f64> {
        self.q().transpose() * x
    }
}

impl Problem for Rotated2Pitchfork {
    type Error = Infallible;
    fn dim(&self) -> usize {
        2
    }
    fn residual(&self, x: &DVector<f64>, p: f64) -> Result<DVector<f64>, Infallible> {
        let u = self.u_of(x);
        let g = DVector::from_column_slice(&[(p - 1.0) * u[0] - u[0].powi(3), u[1] - u[0] * u[0]]);
        Ok(self.q() * g)
    }
    fn jacobian(&self, x: &DVector<f64>, p: f64) -> Result<DMatrix<f64>, Infallible> {
        let u = self.u_of(x);
        let jg =
            DMatrix::from_row_slice(2, 2, &[p - 1.0 - 3.0 * u[0] * u[0], 0.0, -2.0 * u[0], 1.0]);
        Ok(self.q() * jg * self.q().transpose())
    }
    fn dparam(&self, x: &DVector<f64>, _p: f64) -> Result<DVector<f64>, Infallible> {
        let u = self.u_of(x);
        Ok(self.q() * DVector::from_column_slice(&[u[0], 0.0]))
    }
}

fn max_residual<P: Problem>(problem: &P, branch: &rodloop_continuation::Branch) -> f64 {
    branch
        .points
        .iter()
        .map(|pt| problem.residual(&pt.x, pt.p).ok().unwrap().amax())
        .fold(0.0, f64::max)
}

#[test]
fn circle_goes_around_and_locates_both_folds() {
    let problem = circle();
    let settings = PseudoArclength::new()
        .with_ds(0.05)
        .unwrap()
        .with_ds_bounds(1e-8, 0.1)
        .unwrap();
    let branch = Continuation::new(&problem, settings)
        .run(&v1(1.0), 0.0)
        .unwrap();
    assert_eq!(branch.stop, StopReason::ClosedLoop);
    let folds: Vec<_> = branch.folds().collect();
    assert_eq!(folds.len(), 2, "{:?}", branch.special);
    // Forward: p increases first, so the fold at p = +1 comes first.
    let (e1x, e1p) = (folds[0].x[0].abs(), (folds[0].p - 1.0).abs());
    let (e2x, e2p) = (folds[1].x[0].abs(), (folds[1].p + 1.0).abs());
    eprintln!("circle folds: |x| = {e1x:e}, {e2x:e}; |p ∓ 1| = {e1p:e}, {e2p:e}");
    assert!(e1x < 1e-8 && e1p < 1e-8);
    assert!(e2x < 1e-8 && e2p < 1e-8);
    assert!(folds.iter().all(|f| f.accuracy <= 1e-10));
    // No branch point on a smooth closed curve.
    assert_eq!(branch.branch_points().count(), 0);
    // The loop closes at the start. The pseudo-arclength of a step of angle θ on the
    // unit circle is sin θ, so the total lies in (2π (1 − ds_max²/6), 2π).
    let last = branch.last().unwrap();
    assert_eq!(last.p, 0.0);
    assert_eq!(last.x[0], 1.0);
    let s = last.s;
    let two_pi = 2.0 * std::f64::consts::PI;
    eprintln!("circle: pseudo-arclength {s}, 2π − s = {:e}", two_pi - s);
    assert!(s < two_pi && s > two_pi * (1.0 - 0.1f64.powi(2) / 6.0));
    // Every point is on the circle.
    let r = max_residual(&problem, &branch);
    eprintln!("circle: max residual {r:e}");
    assert!(r <= 1e-10);
}

#[test]
fn circle_events_are_located() {
    let problem = circle();
    let settings = PseudoArclength::new().with_ds(0.03).unwrap();
    let branch = Continuation::new(&problem, settings)
        .with_event("x = 1/2", |x: &DVector<f64>, _p: f64| x[0] - 0.5)
        .with_event("p = -0.3", |_x: &DVector<f64>, p: f64| p + 0.3)
        .run(&v1(1.0), 0.0)
        .unwrap();
    let half: Vec<_> = branch.events(0).collect();
    assert_eq!(half.len(), 2, "{:?}", branch.special);
    let root = 0.75f64.sqrt();
    // First crossing at p = +√3/2 with x decreasing, then p = −√3/2 with x increasing.
    let err1 = (half[0].x[0] - 0.5).abs().max((half[0].p - root).abs());
    let err2 = (half[1].x[0] - 0.5).abs().max((half[1].p + root).abs());
    eprintln!("event x=1/2: errors {err1:e}, {err2:e}");
    assert!(err1 < 1e-9 && err2 < 1e-9);
    assert!(matches!(
        half[0].kind,
        SpecialKind::Event {
            id: 0,
            increasing: false,
            ..
        }
    ));
    assert!(matches!(
        half[1].kind,
        SpecialKind::Event {
            id: 0,
            increasing: true,
            ..
        }
    ));
    let third: Vec<_> = branch.events(1).collect();
    assert_eq!(third.len(), 2);
    // p = −0.3 is reached at x = −√0.91 (going down) and x = +√0.91 (coming back).
    let xr = 0.91f64.sqrt();
    let err3 = (third[0].p + 0.3).abs().max((third[0].x[0] + xr).abs());
    let err4 = (third[1].p + 0.3).abs().max((third[1].x[0] - xr).abs());
    eprintln!("event p=-0.3: errors {err3:e}, {err4:e}");
    assert!(err3 < 1e-9 && err4 < 1e-9);
    // Special points are sorted by arclength.
    assert!(branch.special.windows(2).all(|w| w[0].s <= w[1].s));
}

#[test]
fn fold_normal_form_fold_and_exact_range_stop() {
    let problem = fold_nf();
    let settings = PseudoArclength::new()
        .with_ds(0.05)
        .unwrap()
        .with_range(-1.0, 1.0)
        .unwrap()
        .with_direction(Direction::Backward)
        .unwrap();
    let branch = Continuation::new(&problem, settings)
        .run(&v1(0.8), 0.64)
        .unwrap();
    let folds: Vec<_> = branch.folds().collect();
    assert_eq!(folds.len(), 1);
    let (ex, ep) = (folds[0].x[0].abs(), folds[0].p.abs());
    eprintln!("fold normal form: |x*| = {ex:e}, |p*| = {ep:e}");
    assert!(ex < 1e-8 && ep < 1e-12);
    // After the fold p increases again on the x < 0 half until the range ends.
    assert_eq!(branch.stop, StopReason::LeftRange { boundary: 1.0 });
    let last = branch.last().unwrap();
    assert_eq!(last.p, 1.0);
    let e_last = (last.x[0] + 1.0).abs();
    eprintln!("fold normal form: boundary point |x + 1| = {e_last:e}");
    assert!(e_last < 1e-10);
    assert!(branch.points[..branch.points.len() - 1]
        .iter()
        .all(|pt| pt.p > -1.0 && pt.p < 1.0));
    assert!(max_residual(&problem, &branch) <= 1e-10);
}

#[test]
fn fold_in_rotated_three_dimensional_system() {
    let problem = Rotated3 { q: rotation() };
    let u_start = -2.0;
    let p_start = Rotated3::p_of_u1(u_start);
    let settings = PseudoArclength::new()
        .with_ds(0.02)
        .unwrap()
        .with_ds_bounds(1e-8, 0.2)
        .unwrap()
        .with_range(-10.0, 10.0)
        .unwrap();
    // Perturbed start: the initial Newton correction must bring it onto the curve.
    let x0 = problem.x_of_u1(u_start) + DVector::from_element(3, 1e-3);
    let branch = Continuation::new(&problem, settings)
        .run(&x0, p_start)
        .unwrap();
    assert_eq!(branch.stop, StopReason::LeftRange { boundary: 10.0 });
    let folds: Vec<_> = branch.folds().collect();
    assert_eq!(folds.len(), 2, "{:?}", branch.special);
    assert_eq!(branch.branch_points().count(), 0);
    let s34 = 34f64.sqrt();
    for (fold, u1) in folds.iter().zip([(2.0 - s34) / 6.0, (2.0 + s34) / 6.0]) {
        let ep = (fold.p - Rotated3::p_of_u1(u1)).abs();
        let ex = (&fold.x - problem.x_of_u1(u1)).amax();
        eprintln!("3-D fold at u1 = {u1:.6}: |Δp| = {ep:e}, |Δx|∞ = {ex:e}");
        assert!(ep < 1e-10 && ex < 1e-8);
    }
    // The end point is solved at p = 10 exactly: u₁ is the real root of
    // u³ − u² − 2.5u − 10 = 0 (the cubic is increasing there).
    let last = branch.last().unwrap();
    assert_eq!(last.p, 10.0);
    let u1_end = problem.u_of(&last.x)[0];
    assert!((Rotated3::p_of_u1(u1_end) - 10.0).abs() < 1e-9);
    assert!(max_residual(&problem, &branch) <= 1e-10);
}

#[test]
fn pitchfork_branch_point_and_switch_to_nontrivial_branch() {
    let problem = pitchfork();
    let settings = PseudoArclength::new()
        .with_ds(0.03)
        .unwrap()
        .with_range(-0.5, 0.5)
        .unwrap();
    let cont = Continuation::new(&problem, settings);
    let trivial = cont.run(&v1(0.0), -0.4).unwrap();
    assert_eq!(trivial.stop, StopReason::LeftRange { boundary: 0.5 });
    let bps: Vec<_> = trivial.branch_points().collect();
    assert_eq!(bps.len(), 1, "{:?}", trivial.special);
    let bp = bps[0];
    eprintln!(
        "pitchfork BP: |x| = {:e}, |p| = {:e}",
        bp.x[0].abs(),
        bp.p.abs()
    );
    assert!(bp.x[0].abs() < 1e-12 && bp.p.abs() < 1e-8);
    assert_eq!(trivial.folds().count(), 0);

    for (direction, sign) in [(Direction::Forward, 1.0), (Direction::Backward, -1.0)] {
        let tau = cont.secondary_tangent(bp).unwrap() * sign;
        // The nontrivial branch p = x² is vertical at the branch point.
        assert!(tau[1].abs() < 1e-6 && (tau[0] - sign).abs() < 1e-9, "{tau}");
        let other = cont.switch_branch(bp, direction).unwrap();
        assert_eq!(other.stop, StopReason::LeftRange { boundary: 0.5 });
        assert!(other.points.len() > 5);
        let mut worst: f64 = 0.0;
        for pt in &other.points[1..] {
            let x = pt.x[0];
            assert!(x * sign > 0.0, "point on the wrong side: {x}");
            // x (p − x²) = F ≤ tol, so p − x² ≤ tol / |x|.
            worst = worst.max((pt.p - x * x).abs() * x.abs());
            assert!((pt.p - x * x).abs() <= 1e-10 / x.abs() + 1e-14);
        }
        eprintln!("pitchfork switch {direction:?}: max |x (p − x²)| = {worst:e}");
        let last = other.last().unwrap();
        assert_eq!(last.p, 0.5);
        assert!((last.x[0] - sign * 0.5f64.sqrt()).abs() < 1e-10);
    }
}

#[test]
fn pitchfork_index_change_on_trivial_branch() {
    let problem = pitchfork();
    let settings = PseudoArclength::new()
        .with_ds(0.037)
        .unwrap()
        .with_range(-0.5, 0.5)
        .unwrap();
    // Index = number of positive eigenvalues of ∂F/∂x = p − 3x².
    let branch = Continuation::new(&problem, settings)
        .with_stability_fn(|x: &DVector<f64>, p: f64| {
            let j = problem.jacobian(x, p).unwrap();
            usize::from(j[(0, 0)] > 0.0)
        })
        .run(&v1(0.0), -0.45)
        .unwrap();
    assert_eq!(branch.points[0].index, Some(0));
    assert_eq!(branch.last().unwrap().index, Some(1));
    assert!(branch
        .points
        .iter()
        .all(|pt| pt.index == Some(usize::from(pt.p > 0.0))));
    let changes: Vec<_> = branch.index_changes().collect();
    assert_eq!(changes.len(), 1);
    let c = changes[0];
    assert_eq!(c.kind, SpecialKind::IndexChange { old: 0, new: 1 });
    eprintln!(
        "index change at p = {:e} (bracket {:e}), x = {:e}",
        c.p, c.accuracy, c.x[0]
    );
    assert!(c.p.abs() <= 1e-10 && c.p >= 0.0 && c.accuracy <= 1e-10);
    assert_eq!(c.x[0], 0.0);
    // Located at the same place as the branch point.
    let bp = branch.branch_points().next().unwrap();
    assert!((bp.p - c.p).abs() < 1e-9);
}

#[test]
fn transcritical_switch_uses_bifurcation_equation() {
    let problem = transcritical();
    let settings = PseudoArclength::new()
        .with_ds(0.05)
        .unwrap()
        .with_range(-0.6, 0.6)
        .unwrap();
    let cont = Continuation::new(&problem, settings);
    let trivial = cont.run(&v1(0.0), -0.5).unwrap();
    let bp = trivial.branch_points().next().expect("branch point");
    assert!(bp.p.abs() < 1e-8);
    // The other branch x = p has tangent (1, 1)/√2: not orthogonal to the trivial one.
    let tau = cont.secondary_tangent(bp).unwrap();
    let r = std::f64::consts::FRAC_1_SQRT_2;
    let err = (tau[0] - r).abs().max((tau[1] - r).abs());
    eprintln!("transcritical secondary tangent error {err:e}");
    assert!(err < 1e-6, "{tau}");
    for direction in [Direction::Forward, Direction::Backward] {
        let other = cont.switch_branch(bp, direction).unwrap();
        let expect = if direction == Direction::Forward {
            0.6
        } else {
            -0.6
        };
        assert_eq!(other.stop, StopReason::LeftRange { boundary: expect });
        let worst = other.points[1..]
            .iter()
            .map(|pt| (pt.x[0] - pt.p).abs())
            .fold(0.0, f64::max);
        eprintln!("transcritical {direction:?}: max |x − p| = {worst:e}");
        assert!(worst < 1e-9);
    }
}

#[test]
fn rotated_two_dimensional_pitchfork() {
    let problem = Rotated2Pitchfork::new(0.7);
    let settings = PseudoArclength::new()
        .with_ds(0.04)
        .unwrap()
        .with_range(0.0, 2.0)
        .unwrap();
    let cont = Continuation::new(&problem, settings);
    let trivial = cont.run(&DVector::zeros(2), 0.2).unwrap();
    let bps: Vec<_> = trivial.branch_points().collect();
    assert_eq!(bps.len(), 1);
    assert!((bps[0].p - 1.0).abs() < 1e-8 && bps[0].x.amax() < 1e-12);
    let other = cont.switch_branch(bps[0], Direction::Forward).unwrap();
    assert_eq!(other.stop, StopReason::LeftRange { boundary: 2.0 });
    let mut worst: f64 = 0.0;
    for pt in &other.points[1..] {
        let u = problem.u_of(&pt.x);
        // u₁² = p − 1 and u₂ = p − 1.
        worst = worst.max((u[1] - (pt.p - 1.0)).abs());
        assert!((u[0] * u[0] - (pt.p - 1.0)).abs() * u[0].abs() < 1e-9);
        assert!(u[0].abs() > 1e-6);
    }
    eprintln!("rotated 2-D pitchfork: max |u2 − (p − 1)| = {worst:e}");
    assert!(worst < 1e-9);
}

#[test]
fn newton_at_fixed_parameter() {
    let problem = fold_nf();
    let (x, report) = newton(&problem, &v1(1.0), 2.0, 1e-13, 20).unwrap();
    let err = (x[0] - 2f64.sqrt()).abs();
    eprintln!("newton √2: error {err:e}, {} iterations", report.iterations);
    assert!(err < 1e-14);
    assert!(report.iterations <= 6 && report.residual_norm <= 1e-13);
    // Already converged guesses need no iteration.
    let (_, r0) = newton(&problem, &v1(2.0), 4.0, 1e-12, 5).unwrap();
    assert_eq!(r0.iterations, 0);
    assert!(matches!(
        newton(&problem, &DVector::zeros(2), 1.0, 1e-12, 5),
        Err(ContinuationError::WrongStateLength {
            expected: 1,
            found: 2
        })
    ));
    assert!(matches!(
        newton(&problem, &v1(0.0), 1.0, 1e-12, 5),
        Err(ContinuationError::SingularMatrix { .. })
    ));
    assert!(matches!(
        newton(&problem, &v1(10.0), 2.0, 1e-12, 2),
        Err(ContinuationError::CorrectorDiverged { iterations: 2, .. })
    ));
    assert!(matches!(
        newton(&problem, &v1(1.0), 1.0, 0.0, 2),
        Err(ContinuationError::InvalidSetting { name: "tol", .. })
    ));
}

#[test]
fn solve_at_exact_parameter() {
    let problem = fold_nf();
    let settings = PseudoArclength::new()
        .with_ds(0.1)
        .unwrap()
        .with_range(-1.0, 1.0)
        .unwrap()
        .with_direction(Direction::Backward)
        .unwrap();
    let branch = settings.run(&problem, &v1(1.0), 1.0).unwrap();
    let (x, report) = solve_at(&problem, &branch, 0.3, 1e-13, 20).unwrap();
    assert!(report.residual_norm <= 1e-13);
    // The point nearest to p = 0.3 lies on one of the two halves.
    assert!((x[0].abs() - 0.3f64.sqrt()).abs() < 1e-13);
    let all: Vec<_> = solve_all_at(&problem, &branch, 0.25, 1e-13, 20)
        .into_iter()
        .map(|r| r.unwrap().0[0])
        .collect();
    assert_eq!(all.len(), 2);
    assert!((all[0] - 0.5).abs() < 1e-13 && (all[1] + 0.5).abs() < 1e-13);
    let empty = rodloop_continuation::Branch {
        points: vec![],
        special: vec![],
        stop: StopReason::MaxSteps,
    };
    assert!(matches!(
        solve_at(&problem, &empty, 0.0, 1e-10, 5),
        Err(ContinuationError::EmptyBranch)
    ));
}

#[test]
fn finite_difference_helpers_match_analytic_derivatives() {
    let problem = Rotated3 { q: rotation() };
    let x = DVector::from_column_slice(&[0.3, -0.8, 1.7]);
    let p = 0.4;
    let exact = problem.jacobian(&x, p).unwrap();
    let fd = fd_jacobian(|y| problem.residual(y, p), &x).unwrap();
    let err = (&fd - &exact).amax();
    let dp = fd_dparam(|q| problem.residual(&x, q), p).unwrap();
    let errp = (&dp - problem.dparam(&x, p).unwrap()).amax();
    eprintln!("fd_jacobian error {err:e}, fd_dparam error {errp:e}");
    assert!(err < 1e-9 && errp < 1e-9);
}

#[test]
fn settings_are_validated() {
    let s = PseudoArclength::new();
    assert!(matches!(
        s.clone().with_ds(-1.0),
        Err(ContinuationError::InvalidSetting { name: "ds", .. })
    ));
    assert!(s.clone().with_ds(f64::NAN).is_err());
    assert!(s.clone().with_ds_bounds(0.1, 0.01).is_err());
    assert!(s.clone().with_range(1.0, 0.0).is_err());
    assert!(s.clone().with_range(f64::NAN, 0.0).is_err());
    assert!(s.clone().with_range(f64::NEG_INFINITY, 0.0).is_ok());
    assert!(s.clone().with_shrink(1.5).is_err());
    assert!(s.clone().with_growth(0.9).is_err());
    assert!(s.clone().with_max_iterations(0).is_err());
    assert!(s.clone().with_max_steps(0).is_err());
    assert!(s.clone().with_max_turn(2.0).is_err());
    assert!(s.clone().with_locate_tol(0.0).is_err());
    assert!(s.clone().with_tol(-1e-3).is_err());
    // Inconsistent settings are caught when the run starts.
    let bad = s.clone().with_ds(1.0).unwrap();
    let problem = fold_nf();
    assert!(matches!(
        bad.run(&problem, &v1(1.0), 1.0),
        Err(ContinuationError::InvalidSetting { name: "ds", .. })
    ));
    let ranged = s.clone().with_range(-1.0, 0.5).unwrap();
    assert!(matches!(
        ranged.run(&problem, &v1(1.0), 1.0),
        Err(ContinuationError::StartOutsideRange { .. })
    ));
    assert!(matches!(
        s.run(&problem, &DVector::zeros(3), 1.0),
        Err(ContinuationError::WrongStateLength {
            expected: 1,
            found: 3
        })
    ));
}

#[test]
fn max_steps_and_step_too_small_stops() {
    let problem = fold_nf();
    let settings = PseudoArclength::new().with_max_steps(7).unwrap();
    let branch = settings.run(&problem, &v1(1.0), 1.0).unwrap();
    assert_eq!(branch.stop, StopReason::MaxSteps);
    assert_eq!(branch.points.len(), 8);

    // The residual is NaN beyond p = 0.3: the step shrinks until ds < ds_min.
    let wall = Fns {
        n: 1,
        f: |x: &DVector<f64>, p: f64| v1(if p > 0.3 { f64::NAN } else { x[0] - p }),
        j: |_x: &DVector<f64>, _p: f64| m1(1.0),
        d: |_x: &DVector<f64>, _p: f64| v1(-1.0),
    };
    let settings = PseudoArclength::new().with_ds_bounds(1e-6, 0.1).unwrap();
    let branch = settings.run(&wall, &v1(0.0), 0.0).unwrap();
    match branch.stop {
        StopReason::StepTooSmall { ds, p } => {
            assert!(ds < 1e-6);
            assert!(p <= 0.3 && 0.3 - p < 1e-5, "stopped at {p}");
        }
        other => panic!("unexpected stop {other:?}"),
    }
}

#[derive(Debug)]
struct Domain;

impl std::fmt::Display for Domain {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "outside the domain")
    }
}

impl std::error::Error for Domain {}

struct Fallible;

impl Problem for Fallible {
    type Error = Domain;
    fn dim(&self) -> usize {
        1
    }
    fn residual(&self, x: &DVector<f64>, p: f64) -> Result<DVector<f64>, Domain> {
        if p > 0.3 {
            Err(Domain)
        } else {
            Ok(v1(x[0] - p))
        }
    }
    fn jacobian(&self, _x: &DVector<f64>, _p: f64) -> Result<DMatrix<f64>, Domain> {
        Ok(m1(1.0))
    }
    fn dparam(&self, _x: &DVector<f64>, _p: f64) -> Result<DVector<f64>, Domain> {
        Ok(v1(-1.0))
    }
}

#[test]
fn problem_errors_propagate() {
    let err = PseudoArclength::new()
        .run(&Fallible, &v1(0.0), 0.0)
        .unwrap_err();
    assert!(matches!(err, ContinuationError::Problem(_)));
    assert_eq!(
        err.to_string(),
        "problem evaluation failed: outside the domain"
    );
    assert!(std::error::Error::source(&err).is_some());
}

#[test]
fn switch_branch_rejects_other_special_points() {
    let problem = fold_nf();
    let settings = PseudoArclength::new()
        .with_range(-1.0, 1.0)
        .unwrap()
        .with_direction(Direction::Backward)
        .unwrap();
    let cont = Continuation::new(&problem, settings);
    let branch = cont.run(&v1(1.0), 1.0).unwrap();
    let fold = branch.folds().next().unwrap();
    assert!(matches!(
        cont.switch_branch(fold, Direction::Forward),
        Err(ContinuationError::NotABranchPoint { kind: "fold" })
    ));
}

/// F = x e^{−x} − p, with derivatives by finite differences: fold where
/// (1 − x) e^{−x} = 0, i.e. at x = 1, p = 1/e.
struct ExpFold;

impl Problem for ExpFold {
    type Error = Infallible;
    fn dim(&self) -> usize {
        1
    }
    fn residual(&self, x: &DVector<f64>, p: f64) -> Result<DVector<f64>, Infallible> {
        Ok(v1(x[0] * (-x[0]).exp() - p))
    }
    fn jacobian(&self, x: &DVector<f64>, p: f64) -> Result<DMatrix<f64>, Infallible> {
        fd_jacobian(|y| self.residual(y, p), x)
    }
    fn dparam(&self, x: &DVector<f64>, p: f64) -> Result<DVector<f64>, Infallible> {
        fd_dparam(|q| self.residual(x, q), p)
    }
}

#[test]
fn transcendental_fold_with_finite_difference_derivatives() {
    let settings = PseudoArclength::new()
        .with_ds(0.05)
        .unwrap()
        .with_range(0.0, 1.0)
        .unwrap();
    let branch = Continuation::new(&ExpFold, settings)
        .run(&v1(0.1), 0.1 * (-0.1f64).exp())
        .unwrap();
    let folds: Vec<_> = branch.folds().collect();
    assert_eq!(folds.len(), 1);
    let ex = (folds[0].x[0] - 1.0).abs();
    let ep = (folds[0].p - (-1.0f64).exp()).abs();
    eprintln!("x e^-x fold: |Δx| = {ex:e}, |Δp| = {ep:e}");
    assert!(ex < 1e-8 && ep < 1e-12);
    // Beyond the fold p decreases towards 0 as x → ∞; the range stops it at p = 0.
    assert_eq!(branch.stop, StopReason::LeftRange { boundary: 0.0 });
}

/// A 40-dimensional problem F = Q G(Qᵀx, p) with a dense orthogonal Q and the chain
/// G₁ = p − (u₁ − 1)², G_k = u_k − sin(u_{k−1}) (k ≥ 2): a single fold at p = 0,
/// u₁ = 1, u_k = sin(u_{k−1}).
struct Chain {
    q: DMatrix<f64>,
}

impl Chain {
    fn new(n: usize) -> Self {
        // Deterministic "random" matrix; Q from its QR factorisation.
        let a = DMatrix::from_fn(n, n, |i, j| ((i * 7 + j * 13 + 3) as f64 * 0.618).sin());
        Chain { q: a.qr().q() }
    }
    fn n(&self) -> usize {
        self.q.nrows()
    }
    fn u_fold(&self) -> DVector<f64> {
        let mut u: DVector<f64> = DVector::zeros(self.n());
        u[0] = 1.0;
        for k in 1..self.n() {
            u[k] = u[k - 1].sin();
        }
        u
    }
}

impl Problem for Chain {
    type Error = Infallible;
    fn dim(&self) -> usize {
        self.n()
    }
    fn residual(&self, x: &DVector<f64>, p: f64) -> Result<DVector<f64>, Infallible> {
        let u = self.q.transpose() * x;
        let mut g = DVector::zeros(self.n());
        g[0] = p - (u[0] - 1.0).powi(2);
        for k in 1..self.n() {
            g[k] = u[k] - u[k - 1].sin();
        }
        Ok(&self.q * g)
    }
    fn jacobian(&self, x: &DVector<f64>, _p: f64) -> Result<DMatrix<f64>, Infallible> {
        let u = self.q.transpose() * x;
        let n = self.n();
        let mut jg = DMatrix::zeros(n, n);
        jg[(0, 0)] = -2.0 * (u[0] - 1.0);
        for k in 1..n {
            jg[(k, k)] = 1.0;
            jg[(k, k - 1)] = -u[k - 1].cos();
        }
        Ok(&self.q * jg * self.q.transpose())
    }
    fn dparam(&self, _x: &DVector<f64>, _p: f64) -> Result<DVector<f64>, Infallible> {
        Ok(self.q.column(0).into_owned())
    }
}

#[test]
fn fold_in_forty_dimensional_chain() {
    let problem = Chain::new(40);
    // Start on the branch at u₁ = 1.5, p = 0.25.
    let mut u: DVector<f64> = DVector::zeros(40);
    u[0] = 1.5;
    for k in 1..40 {
        u[k] = u[k - 1].sin();
    }
    let x0 = &problem.q * u;
    let settings = PseudoArclength::new()
        .with_ds(0.05)
        .unwrap()
        .with_range(-1.0, 0.5)
        .unwrap()
        .with_direction(Direction::Backward)
        .unwrap();
    let branch = Continuation::new(&problem, settings)
        .run(&x0, 0.25)
        .unwrap();
    let folds: Vec<_> = branch.folds().collect();
    assert_eq!(folds.len(), 1);
    let x_star = &problem.q * problem.u_fold();
    let ex = (&folds[0].x - &x_star).amax();
    let ep = folds[0].p.abs();
    eprintln!("40-D chain fold: |Δx|∞ = {ex:e}, |Δp| = {ep:e}");
    assert!(ex < 1e-8 && ep < 1e-12);
    assert_eq!(branch.branch_points().count(), 0);
    assert_eq!(branch.stop, StopReason::LeftRange { boundary: 0.5 });
    // End: p = 0.5 on the other half, u₁ = 1 − √0.5.
    let u_end = problem.q.transpose() * &branch.last().unwrap().x;
    assert!((u_end[0] - (1.0 - 0.5f64.sqrt())).abs() < 1e-10);
}

#[test]
fn two_index_changes_within_one_step() {
    // Trivial branch x = 0 of F = (p x₁, (p − 10⁻³) x₂); index = number of positive
    // eigenvalues of diag(p, p − 10⁻³): 0 → 1 at p = 0 and 1 → 2 at p = 10⁻³, both
    // inside a single step of size ≥ 0.05.
    let problem = Fns {
        n: 2,
        f: |x: &DVector<f64>, p: f64| DVector::from_column_slice(&[p * x[0], (p - 1e-3) * x[1]]),
        j: |_x: &DVector<f64>, p: f64| {
            DMatrix::from_diagonal(&DVector::from_column_slice(&[p, p - 1e-3]))
        },
        d: |x: &DVector<f64>, _p: f64| x.clone(),
    };
    let settings = PseudoArclength::new()
        .with_ds(0.1)
        .unwrap()
        .with_ds_bounds(1e-8, 0.1)
        .unwrap()
        .with_range(-0.4137, 0.4)
        .unwrap();
    let branch = Continuation::new(&problem, settings)
        .with_stability_fn(|_x: &DVector<f64>, p: f64| usize::from(p > 0.0) + usize::from(p > 1e-3))
        .run(&DVector::zeros(2), -0.4137)
        .unwrap();
    let changes: Vec<_> = branch.index_changes().collect();
    assert_eq!(changes.len(), 2, "{:?}", branch.special);
    assert_eq!(changes[0].segment, changes[1].segment);
    assert_eq!(changes[0].kind, SpecialKind::IndexChange { old: 0, new: 1 });
    assert_eq!(changes[1].kind, SpecialKind::IndexChange { old: 1, new: 2 });
    let (e1, e2) = (changes[0].p.abs(), (changes[1].p - 1e-3).abs());
    eprintln!("two index changes: |Δp| = {e1:e}, {e2:e}");
    assert!(e1 <= 1e-10 && e2 <= 1e-10);
}

#[test]
fn start_exactly_at_a_fold() {
    let problem = fold_nf();
    let settings = PseudoArclength::new()
        .with_ds(0.05)
        .unwrap()
        .with_range(-1.0, 1.0)
        .unwrap();
    let branch = settings.run(&problem, &v1(0.0), 0.0).unwrap();
    assert_eq!(branch.stop, StopReason::LeftRange { boundary: 1.0 });
    assert_eq!(branch.folds().count(), 0);
    assert!((branch.last().unwrap().x[0].abs() - 1.0).abs() < 1e-10);
    assert!(max_residual(&problem, &branch) <= 1e-10);
}

#[test]
fn start_on_the_boundary_heading_out_adds_no_point() {
    let problem = fold_nf();
    let settings = PseudoArclength::new().with_range(-1.0, 1.0).unwrap();
    // At (1, 1), going towards increasing p leaves the range at once.
    let branch = settings.run(&problem, &v1(1.0), 1.0).unwrap();
    assert_eq!(branch.stop, StopReason::LeftRange { boundary: 1.0 });
    assert_eq!(branch.points.len(), 1);
}

/// Settings that follow the pitchfork's parabola `x² = p` from `(0.5, 0.25)` backwards
/// through its turn at `(0, 0)`, locating with the Hermite start.
fn parabola_through_its_turn() -> PseudoArclength {
    PseudoArclength::new()
        .with_ds(0.07)
        .unwrap()
        .with_ds_bounds(1e-8, 0.1)
        .unwrap()
        .with_range(-1.0, 0.3)
        .unwrap()
        .with_direction(Direction::Backward)
        .unwrap()
        .with_locate_tol(1e-9)
        .unwrap()
        .with_hermite_location(true)
        .unwrap()
}

/// The Hermite start of the location correctors finds the same folds as the chord start
/// (the circle's, at `p = ±1`), and on the parabola `x² = p` of the pitchfork, followed
/// through `x = 0`, the fold and the branch point there, both at `(0, 0)`.
#[test]
fn hermite_location_finds_the_known_folds_and_branch_point() {
    let problem = circle();
    for hermite in [false, true] {
        let settings = PseudoArclength::new()
            .with_ds(0.05)
            .unwrap()
            .with_ds_bounds(1e-8, 0.1)
            .unwrap()
            .with_hermite_location(hermite)
            .unwrap();
        let branch = Continuation::new(&problem, settings)
            .run(&v1(1.0), 0.0)
            .unwrap();
        let folds: Vec<_> = branch.folds().collect();
        assert_eq!(folds.len(), 2, "hermite {hermite}: {:?}", branch.special);
        assert!((folds[0].p - 1.0).abs() < 1e-8 && folds[0].x[0].abs() < 1e-8);
        assert!((folds[1].p + 1.0).abs() < 1e-8 && folds[1].x[0].abs() < 1e-8);
    }
    let problem = pitchfork();
    let branch = Continuation::new(&problem, parabola_through_its_turn())
        .run(&v1(0.5), 0.25)
        .unwrap();
    let fold = branch.folds().next().expect("the parabola's fold");
    let bp = branch.branch_points().next().expect("the branch point");
    for (what, x, p) in [("fold", fold.x[0], fold.p), ("branch point", bp.x[0], bp.p)] {
        eprintln!("pitchfork parabola: {what} at x = {x:e}, p = {p:e}");
        assert!(x.abs() < 1e-8 && p.abs() < 1e-8, "{what}: x = {x}, p = {p}");
    }
}

/// On the parabola `x² = p` of the pitchfork, followed through `x = 0`, the step that
/// turns crosses both the fold and the branch point at `(0, 0)`: both are reported by
/// default, only the fold without `branch_points_beside_folds`; the fold is the same.
#[test]
fn branch_point_beside_a_fold_is_located_only_when_asked() {
    let problem = pitchfork();
    let run = |beside: bool| {
        let settings = parabola_through_its_turn()
            .with_branch_points_beside_folds(beside)
            .unwrap();
        Continuation::new(&problem, settings)
            .run(&v1(0.5), 0.25)
            .unwrap()
    };
    let (with, without) = (run(true), run(false));
    assert_eq!(with.branch_points().count(), 1, "{:?}", with.special);
    assert_eq!(without.branch_points().count(), 0, "{:?}", without.special);
    let (f1, f0) = (
        with.folds().next().expect("fold"),
        without.folds().next().expect("fold"),
    );
    assert!(f0.x[0].abs() < 1e-8 && f0.p.abs() < 1e-8, "{f0:?}");
    assert_eq!((f1.x[0], f1.p, f1.s), (f0.x[0], f0.p, f0.s));
}
