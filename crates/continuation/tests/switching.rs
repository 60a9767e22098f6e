//! Branch switching at a pitchfork whose primary branch is curved, has a nonzero
//! parameter component in its tangent and is aligned with no coordinate axis.

use std::convert::Infallible;

use nalgebra::{DMatrix, DVector, Matrix2, Vector2};
use rodloop_continuation::{Branch, Continuation, Direction, Problem, PseudoArclength};

/// `G(u, p) = (u₁ (p − u₁² − u₂²), u₂ − g(p))` with `g(p) = p/2 + p²`, in the sheared
/// unknowns `x = S u` and with mixed equations `F = M G(S⁻¹ x, p)`.
///
/// Primary branch: `u₁ = 0`, `u₂ = g(p)` (tangent `(0, 1/2, 1)` at `p = 0`). Secondary
/// branch: `u₁² = p − g(p)²`, `u₂ = g(p)`, through the branch point `u = 0`, `p = 0`
/// with tangent `(1, 0, 0)`. In `x` the two tangents are `(S e₂/2, 1)` and `(S e₁, 0)`:
/// not orthogonal, since the shear `S` is not.
struct ShearedPitchfork {
    s: Matrix2<f64>,
    s_inv: Matrix2<f64>,
    m: Matrix2<f64>,
}

impl ShearedPitchfork {
    fn new() -> Self {
        let (c, sn) = (0.6f64.cos(), 0.6f64.sin());
        let rot = Matrix2::new(c, -sn, sn, c);
        let s = rot * Matrix2::new(1.0, 0.8, 0.0, 1.3);
        ShearedPitchfork {
            s,
            s_inv: s.try_inverse().unwrap(),
            m: Matrix2::new(2.0, 0.7, -0.4, 1.5),
        }
    }
    fn g(p: f64) -> f64 {
        0.5 * p + p * p
    }
    fn dg(p: f64) -> f64 {
        0.5 + 2.0 * p
    }
    fn u_of(&self, x: &DVector<f64>) -> Vector2<f64> {
        self.s_inv * Vector2::new(x[0], x[1])
    }
    /// The primary branch traced by `cont` from `p = −0.25`.
    fn primary(&self, cont: &Continuation<'_, Self>) -> Branch {
        let p0 = -0.25;
        let x0 = self.s * Vector2::new(0.0, Self::g(p0));
        cont.run(&DVector::from_column_slice(x0.as_slice()), p0)
            .unwrap()
    }
}

impl Problem for ShearedPitchfork {
    type Error = Infallible;
    fn dim(&self) -> usize {
        2
    }
    fn residual(&self, x: &DVector<f64>, p: f64) -> Result<DVector<f64>, Infallible> {
        let u = self.u_of(x);
        let g = Vector2::new(u[0] * (p - u[0] * u[0] - u[1] * u[1]), u[1] - Self::g(p));
        Ok(DVector::from_column_slice((self.m * g).as_slice()))
    }
    fn jacobian(&self, x: &DVector<f64>, p: f64) -> Result<DMatrix<f64>, Infallible> {
        let u = self.u_of(x);
        let jg = Matrix2::new(
            p - 3.0 * u[0] * u[0] - u[1] * u[1],
            -2.0 * u[0] * u[1],
            0.0,
            1.0,
        );
        let j = self.m * jg * self.s_inv;
        Ok(DMatrix::from_column_slice(2, 2, j.as_slice()))
    }
    fn dparam(&self, x: &DVector<f64>, p: f64) -> Result<DVector<f64>, Infallible> {
        let u = self.u_of(x);
        let d = self.m * Vector2::new(u[0], -Self::dg(p));
        Ok(DVector::from_column_slice(d.as_slice()))
    }
}

#[test]
fn switch_at_sheared_pitchfork_leaves_the_primary_branch() {
    let problem = ShearedPitchfork::new();
    for (ds, locate_tol) in [(0.04, 1e-10), (0.05, 1e-6), (0.033, 1e-8)] {
        let settings = PseudoArclength::new()
            .with_ds(ds)
            .unwrap()
            .with_locate_tol(locate_tol)
            .unwrap()
            .with_range(-0.3, 0.3)
            .unwrap();
        let cont = Continuation::new(&problem, settings);
        let primary = problem.primary(&cont);
        let bps: Vec<_> = primary.branch_points().collect();
        assert_eq!(bps.len(), 1, "{:?}", primary.special);
        let bp = bps[0];
        assert!(bp.p.abs() < 1e-6, "branch point at p = {}", bp.p);
        // The reported tangent is the primary branch's, (S e₂/2, 1) normalised.
        let tp = problem.s * Vector2::new(0.0, 0.5);
        let tp = DVector::from_column_slice(&[tp[0], tp[1], 1.0]).normalize();
        let cos = bp.tangent.dot(&tp).abs();
        eprintln!("ds {ds}: |cos(branch point tangent, primary tangent)| = {cos}");
        assert!(cos > 0.99, "tangent {}", bp.tangent);
        for direction in [Direction::Forward, Direction::Backward] {
            let stepper = cont.start_switch(bp, direction).unwrap();
            let first = stepper.current();
            let u = problem.u_of(&first.x);
            let p = first.p;
            // On the secondary branch: u₁ ≠ 0 (off the primary), u₁² = p − g(p)², u₂ = g(p).
            let off_primary = u[0].abs();
            let on_secondary = (u[0] * u[0] - (p - ShearedPitchfork::g(p).powi(2))).abs();
            eprintln!(
                "ds {ds}, locate_tol {locate_tol:e}, {direction:?}: first point p = {p:e}, \
                 |u1| = {off_primary:e}, |u1² − (p − g²)| = {on_secondary:e}, \
                 |u2 − g| = {:e}",
                (u[1] - ShearedPitchfork::g(p)).abs()
            );
            assert!(
                off_primary > 0.1 * ds,
                "first point on the primary branch: u = {u}, p = {p}"
            );
            assert!(on_secondary < 1e-9, "u = {u}, p = {p}");
            assert!((u[1] - ShearedPitchfork::g(p)).abs() < 1e-9);
            // The secondary branch is vertical at the branch point: p = O(u₁²).
            assert!(p.abs() < 2.0 * u[0] * u[0] + 1e-9, "p = {p}, u = {u}");
        }
    }
}

/// The secondary branch rises like `p ≈ u₁²`: a first step of `0.04` off the branch point
/// lands at `p ≈ 1.6e-3`, beyond a range ending at `5e-4`. The first point is inside the
/// range (the step shortened), and the run on the secondary branch ends on its boundary.
#[test]
fn the_first_point_off_a_branch_point_lies_inside_the_range() {
    let problem = ShearedPitchfork::new();
    let p_max = 5e-4;
    let settings = PseudoArclength::new()
        .with_ds(0.04)
        .and_then(|s| s.with_locate_tol(1e-10))
        .and_then(|s| s.with_range(-0.3, p_max))
        .unwrap();
    let cont = Continuation::new(&problem, settings);
    let primary = problem.primary(&cont);
    let bp = primary
        .branch_points()
        .next()
        .expect("the branch point at p = 0");
    for direction in [Direction::Forward, Direction::Backward] {
        let stepper = cont.start_switch(bp, direction).unwrap();
        let first = stepper.current();
        assert!(
            first.p <= p_max && first.p >= -0.3,
            "{direction:?}: first point at p = {}",
            first.p
        );
        assert!(
            problem.u_of(&first.x)[0].abs() > 1e-3,
            "on the primary branch"
        );
        let branch = cont.switch_branch(bp, direction).unwrap();
        assert!(
            branch.points.iter().all(|q| q.p <= p_max),
            "{direction:?}: {:?}",
            branch.points.iter().map(|q| q.p).collect::<Vec<_>>()
        );
    }
}
