//! The enclosed model's frame closure is zero only when the frame returns (`X_N = I`):
//! a loop whose end frame is a half-turn of its start frame is not closed, and the exact
//! derivatives of that residual hold far from closure too.

use rodloop_exact::paper_branch_loop;
use rodloop_solver::enclosed::{start_from_surface, EnclosedModel, Gauge};
use rodloop_solver::Stiffness;

/// A loop of constant curvature vector `(0, k)`: a planar arc whose frame turns by `k L`
/// about the binormal, so the end frame is the rotation by that angle.
fn arc(angle: f64) -> (EnclosedModel, Vec<f64>) {
    let cells = 16;
    let m = EnclosedModel::new(
        1.0,
        1.0,
        cells,
        &Stiffness::uniform(1.0),
        Gauge {
            reference: vec![0.0; 4 * cells],
            slope: None,
            pin: None,
        },
    )
    .unwrap();
    let k = angle / m.length();
    let mut z = vec![0.0; m.dim()];
    for c in 0..cells {
        z[4 * c + 1] = k;
        z[4 * c + 3] = k;
    }
    (m, z)
}

#[test]
fn a_half_turn_of_the_frame_is_not_closed() {
    // |c| = 2 sin(θ/2) for a rotation by θ: √2 at θ = π/2, 2 at θ = π (where
    // vee(skew X) = sin θ u vanishes), θ + O(θ³) near the identity.
    for (angle, expected) in [
        (std::f64::consts::PI, 2.0),
        (0.5 * std::f64::consts::PI, 2f64.sqrt()),
        (
            0.999 * std::f64::consts::PI,
            2.0 * (0.4995 * std::f64::consts::PI).sin(),
        ),
        (1e-3, 2.0 * (0.5e-3f64).sin()),
    ] {
        let (m, z) = arc(angle);
        let c = m.closure(&z).unwrap();
        let rot = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
        assert!(
            (rot - expected).abs() < 1e-9,
            "turn {angle}: frame residual {rot}, expected {expected}"
        );
        // The residual the KKT system carries is the same.
        let f = m.residual(&z).unwrap();
        let np = m.n_primal();
        let fr = (f[np] * f[np] + f[np + 1] * f[np + 1] + f[np + 2] * f[np + 2]).sqrt();
        assert!((fr - expected).abs() < 1e-9, "turn {angle}: KKT row {fr}");
    }
}

/// Far from closure (end frame turned by more than a radian) the residual's second
/// derivative terms do not vanish: the semismooth Jacobian against central differences,
/// and the `O(N)` lifted step against the dense step.
#[test]
fn derivatives_hold_far_from_closure() {
    let l = paper_branch_loop(1, 1.5).unwrap();
    let (m, mut z) = start_from_surface(1.0, 1.5, 10, &Stiffness::uniform(1.0), |s| {
        l.point(s * l.length()).unwrap().kappa_g
    })
    .unwrap();
    for (i, v) in z.iter_mut().enumerate() {
        *v += 0.01 * ((i as f64 * 1.7).sin());
    }
    // A constant extra curvature turns the end frame by more than a radian.
    for a in (0..4 * m.cells()).step_by(2) {
        z[a] += 0.4;
    }
    let lo = m.lambda_offset();
    for j in 0..m.cells() {
        z[lo + j] = if j % 3 == 0 {
            -0.05
        } else {
            0.3 + 0.01 * j as f64
        };
    }
    let c = m.closure(&z).unwrap();
    let turn = 2.0 * (0.5 * (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt()).asin();
    assert!(turn > 1.0, "the end frame is turned by only {turn} rad");
    let ev = m.evaluate(&z).unwrap();
    let eps = 1e-6;
    let mut worst: f64 = 0.0;
    for k in 0..m.dim() {
        let mut zp = z.clone();
        let mut zm = z.clone();
        zp[k] += eps;
        zm[k] -= eps;
        let fd = (m.residual(&zp).unwrap() - m.residual(&zm).unwrap()) / (2.0 * eps);
        for i in 0..m.dim() {
            let scale = 1.0 + ev.jacobian[(i, k)].abs();
            worst = worst.max((fd[i] - ev.jacobian[(i, k)]).abs() / scale);
        }
    }
    assert!(worst < 1e-6, "worst FD mismatch {worst:e}");
    let dense = ev.jacobian.clone().lu().solve(&(-&ev.residual)).unwrap();
    let (_, step) = m.newton_step(&z).unwrap();
    let err = (&step - &dense).amax() / dense.amax();
    assert!(err < 1e-9, "lifted vs dense step {err:e}");
}
