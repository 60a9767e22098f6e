//! Analytic derivatives of the surface model against central finite differences.

use nalgebra::{DMatrix, DVector, Matrix3, Vector3};
use rodloop_continuation::{fd_dparam, fd_jacobian, Problem};
use rodloop_solver::frame::{
    exp_jet, exp_jet_last, expm_skew, hat, integrate, rodrigues_coefficients,
};
use rodloop_solver::{LbarProblem, Phase, StartShape, Stiffness, SurfaceModel};

mod common;
use common::lcg;

fn rel_err(a: &DMatrix<f64>, b: &DMatrix<f64>) -> f64 {
    (a - b).abs().max() / b.abs().max().max(1e-300)
}

fn tanh_profile() -> Stiffness {
    Stiffness::Tanh {
        d0: 1.0,
        d1: 0.4,
        s0: 0.3,
        s1: 0.8,
        gamma: 12.0,
    }
}

#[test]
fn rodrigues_coefficients_match_closed_forms_and_fd() {
    for &q in &[1e-6, 0.01, 0.3, 0.99, 1.01, 2.5, 7.0] {
        let c = rodrigues_coefficients(q);
        let th: f64 = q.sqrt();
        assert!((c[0] - th.sin() / th).abs() < 1e-15);
        let half = (0.5 * th).sin();
        assert!((c[3] - 2.0 * half * half / q).abs() < 1e-15);
        let e = 1e-5 * q.max(0.01);
        let cp = rodrigues_coefficients(q + e);
        let cm = rodrigues_coefficients(q - e);
        for k in [0usize, 1, 3, 4] {
            let fd = (cp[k] - cm[k]) / (2.0 * e);
            assert!(
                (fd - c[k + 1]).abs() < 1e-8,
                "q = {q}, k = {k}: {fd} vs {}",
                c[k + 1]
            );
        }
    }
}

#[test]
#[allow(clippy::needless_range_loop)]
fn exp_jet_matches_finite_differences() {
    // ω(x) = w0 + x0 v0 + x1 v1 + x0 x1 u + x1² u2 (second derivatives nonzero).
    let w0 = Vector3::new(0.3, -0.7, 0.2);
    let v = [Vector3::new(0.1, 0.4, -0.3), Vector3::new(-0.5, 0.2, 0.6)];
    let u = Vector3::new(0.2, 0.1, -0.1);
    let u2 = Vector3::new(-0.3, 0.05, 0.2);
    let omega =
        |x: [f64; 2]| w0 + v[0] * x[0] + v[1] * x[1] + u * (x[0] * x[1]) + u2 * (x[1] * x[1]);
    let x = [0.4, -0.8];
    let wi = [v[0] + u * x[1], v[1] + u * x[0] + u2 * (2.0 * x[1])];
    let wij = [[Vector3::zeros(), u], [u, u2 * 2.0]];
    let (e, d, dd) = exp_jet::<2>(&omega(x), &wi, &wij);
    assert!((e - expm_skew(&hat(&omega(x)))).norm() < 1e-15);
    let h = 1e-5;
    let ev = |x: [f64; 2]| expm_skew(&hat(&omega(x)));
    for i in 0..2 {
        let mut xp = x;
        let mut xm = x;
        xp[i] += h;
        xm[i] -= h;
        let fd = (ev(xp) - ev(xm)) / (2.0 * h);
        assert!((fd - d[i]).norm() < 1e-9, "first derivative {i}");
        for j in i..2 {
            let dj = |x: [f64; 2]| {
                let wi = [v[0] + u * x[1], v[1] + u * x[0] + u2 * (2.0 * x[1])];
                exp_jet::<2>(&omega(x), &wi, &wij).1[j]
            };
            let fd2 = (dj(xp) - dj(xm)) / (2.0 * h);
            assert!((fd2 - dd[i][j]).norm() < 1e-8, "second derivative {i}{j}");
        }
    }
}

/// The jet of the mixed derivatives in the last variable is the full jet's last column, bit
/// for bit, and leaves the other second derivatives zero.
#[test]
fn exp_jet_last_is_the_last_column_of_the_full_jet() {
    let w = Vector3::new(0.3, -0.7, 0.2);
    let wi = [
        Vector3::new(0.1, 0.4, -0.3),
        Vector3::new(-0.5, 0.2, 0.6),
        Vector3::new(0.25, -0.15, 0.05),
    ];
    let u = Vector3::new(0.2, 0.1, -0.1);
    let z = Vector3::zeros();
    let wij = [[z, z, u], [z, z, u * -0.5], [u, u * -0.5, u * 0.3]];
    let (e, d, dd) = exp_jet::<3>(&w, &wi, &wij);
    let (el, dl, ddl) = exp_jet_last::<3>(&w, &wi, &wij);
    assert_eq!(e, el);
    assert_eq!(d, dl);
    for i in 0..3 {
        for j in i..3 {
            if j == 2 {
                assert_eq!(dd[i][j], ddl[i][j], "∂{i}∂{j}");
                assert!(dd[i][j].norm() > 0.0);
            } else {
                assert_eq!(ddl[i][j], Matrix3::zeros(), "∂{i}∂{j} left zero");
            }
        }
    }
}

#[test]
fn holonomy_equals_frame_integration() {
    // Same Magnus scheme: the model's holonomy equals frame::integrate with the same κ_g.
    let kg = |s: f64| 0.9 * (1.1 * s).cos() + 0.3 * (2.3 * s).sin();
    let model = SurfaceModel::new(1.3, 1.4, 40, &Stiffness::uniform(1.0)).unwrap();
    let len = model.length();
    let kappa: Vec<f64> = model.gauss_sigma().iter().map(|&s| kg(s * len)).collect();
    let fc = integrate(kg, len, 1.3, 40, Matrix3::identity()).unwrap();
    let h = model.holonomy(&kappa).unwrap();
    assert!((h - fc.holonomy()).norm() < 1e-13);
    let frames = model.frames(&kappa).unwrap();
    for (a, b) in frames.iter().zip(&fc.frames) {
        assert!((a - b).norm() < 1e-13);
    }
}

fn random_state(model: &SurfaceModel, seed: u64) -> (Vec<f64>, [f64; 3]) {
    let mut s = seed;
    let len = model.length();
    let (p1, p2) = (lcg(&mut s), lcg(&mut s));
    let kappa: Vec<f64> = model
        .gauss_sigma()
        .iter()
        .map(|&x| {
            let t = 2.0 * std::f64::consts::PI * x;
            0.8 * (2.0 * t + p1).cos() + 0.3 * (3.0 * t + p2).sin() + 0.05 * lcg(&mut s) + 0.0 * len
        })
        .collect();
    let mu = [lcg(&mut s), lcg(&mut s), lcg(&mut s)];
    (kappa, mu)
}

fn check_model(model: &SurfaceModel, kappa: &[f64], mu: [f64; 3], tol: f64) {
    let n = model.n_kappa();
    let kv = DVector::from_column_slice(kappa);
    // ∇E.
    let grad = DMatrix::from_column_slice(n, 1, &model.energy_gradient(kappa).unwrap());
    let fd: DMatrix<f64> = fd_jacobian(
        |k: &DVector<f64>| {
            Ok::<_, ()>(DVector::from_element(
                1,
                model.energy(k.as_slice()).unwrap(),
            ))
        },
        &kv,
    )
    .unwrap()
    .transpose();
    assert!(
        rel_err(&grad, &fd) < tol,
        "energy gradient {}",
        rel_err(&grad, &fd)
    );
    // ∇c.
    let cj = model.closure_jacobian(kappa).unwrap();
    let fd = fd_jacobian(
        |k: &DVector<f64>| {
            Ok::<_, ()>(DVector::from_column_slice(
                &model.closure(k.as_slice()).unwrap(),
            ))
        },
        &kv,
    )
    .unwrap();
    assert!(
        rel_err(&cj, &fd) < tol,
        "closure jacobian {}",
        rel_err(&cj, &fd)
    );
    // ∇²ℒ = ∂/∂κ (∇E − ∇cᵀμ).
    let hess = model.lagrangian_hessian(kappa, &mu).unwrap();
    let mv = DVector::from_column_slice(&mu);
    let fd = fd_jacobian(
        |k: &DVector<f64>| {
            let g = DVector::from_vec(model.energy_gradient(k.as_slice()).unwrap());
            let j = model.closure_jacobian(k.as_slice()).unwrap();
            Ok::<_, ()>(g - j.transpose() * &mv)
        },
        &kv,
    )
    .unwrap();
    assert!(rel_err(&hess, &fd) < tol, "hessian {}", rel_err(&hess, &fd));
    assert!((&hess - hess.transpose()).abs().max() < 1e-14 * hess.abs().max());
    // Full KKT Jacobian and ∂F/∂L̄ through the continuation Problem.
    let mut z = kappa.to_vec();
    z.extend_from_slice(&mu);
    if model.phase().is_some() {
        z.push(0.37);
    }
    let zv = DVector::from_vec(z);
    let prob = LbarProblem::new(model.clone());
    let p = model.lbar();
    let jac = prob.jacobian(&zv, p).unwrap();
    let fd = fd_jacobian(|y: &DVector<f64>| prob.residual(y, p), &zv).unwrap();
    assert!(
        rel_err(&jac, &fd) < tol,
        "kkt jacobian {}",
        rel_err(&jac, &fd)
    );
    let dp = prob.dparam(&zv, p).unwrap();
    let fdp = fd_dparam(|q| prob.residual(&zv, q), p).unwrap();
    let (a, b) = (
        DMatrix::from_column_slice(dp.len(), 1, dp.as_slice()),
        DMatrix::from_column_slice(fdp.len(), 1, fdp.as_slice()),
    );
    assert!(rel_err(&a, &b) < tol, "dF/dlbar {}", rel_err(&a, &b));
}

#[test]
fn derivatives_at_random_states() {
    for (radius, lbar, cells, st) in [
        (1.0, 1.2, 12, Stiffness::uniform(1.0)),
        (1.7, 2.3, 20, Stiffness::uniform(0.6)),
        (1.0, 1.6, 16, tanh_profile()),
    ] {
        let mut model = SurfaceModel::new(radius, lbar, cells, &st).unwrap();
        let (kappa, mu) = random_state(&model, 7 + cells as u64);
        if st.is_uniform() {
            model = model
                .with_phase(Phase::from_gauss_values(&kappa, cells).unwrap())
                .unwrap();
        }
        check_model(&model, &kappa, mu, 1e-7);
    }
}

#[test]
fn derivatives_at_a_solution() {
    let model = SurfaceModel::new(1.0, 1.2, 16, &Stiffness::uniform(1.0)).unwrap();
    let start = StartShape::Exact { eta: 2 }.gauss_values(&model).unwrap();
    let eq = rodloop_solver::solve(&model, &start, &Default::default()).unwrap();
    check_model(eq.model(), eq.kappa(), eq.multiplier(), 1e-7);
}

#[test]
fn parameter_derivatives_match_finite_differences() {
    use rodloop_solver::{Confinement, Param, ParamProblem};
    // A sharp profile (graded mesh) and a smooth one (uniform mesh), every named parameter.
    for gamma in [12.0, 60.0] {
        let st = Stiffness::Tanh {
            d0: 1.0,
            d1: 0.3,
            s0: 0.3,
            s1: 0.8,
            gamma,
        };
        let m = SurfaceModel::new(1.0, 1.4, 24, &st).unwrap();
        let mut seed = 9;
        let mut z = StartShape::Euler { l: 2 }.gauss_values(&m).unwrap();
        for v in z.iter_mut() {
            *v += 0.1 * lcg(&mut seed);
        }
        z.extend([0.2, -0.1, 0.3]);
        let x = DVector::from_vec(z.clone());
        for p in Param::ALL {
            let prob = ParamProblem::new(m.clone(), p).unwrap();
            let v = Confinement::param(&m, p).unwrap();
            let an = prob.dparam(&x, v).unwrap();
            let fd = fd_dparam(|q| prob.residual(&x, q), v).unwrap();
            let err = (&an - &fd).amax() / fd.amax().max(1e-12);
            assert!(err < 1e-7, "γ = {gamma}, ∂F/∂{p}: relative error {err:e}");
        }
    }
}

/// The closure residual is zero only at the identity: over half of a small circle (constant
/// `κ_g`, for which the Magnus propagator is exact) the holonomy is a half-turn, where
/// `vee(skew H)` vanishes but the closure `2 sin(θ/2) u` has length 2.
#[test]
fn closure_residual_does_not_vanish_at_a_half_turn() {
    let kg = 0.75f64;
    let lbar = 0.5 / (1.0 + kg * kg).sqrt();
    let model = SurfaceModel::new(1.0, lbar, 16, &Stiffness::uniform(1.0)).unwrap();
    let kappa = vec![kg; model.n_kappa()];
    let h = model.holonomy(&kappa).unwrap();
    let skew = (h - h.transpose()).norm();
    assert!(skew < 1e-12, "a half-turn: skew part {skew:e}");
    assert!((h.trace() + 1.0).abs() < 1e-12, "trace {}", h.trace());
    let c = model.closure(&kappa).unwrap();
    let norm = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
    assert!((norm - 2.0).abs() < 1e-6, "|c| = {norm}");
}

/// Closure, its Jacobian, the Lagrangian Hessian, the KKT Jacobian and `∂F/∂L̄` against
/// finite differences near a half-turn holonomy (angle ≈ 3.0 rad), where the quaternion
/// closure's extra terms (`s(tr H)` far from 1) are large, and `|c| = 2 sin(θ/2)` there.
#[test]
fn derivatives_near_a_half_turn() {
    let kg = 0.75f64;
    let lbar = 0.5 / (1.0 + kg * kg).sqrt() * (3.0 / std::f64::consts::PI);
    for st in [Stiffness::uniform(1.0), tanh_profile()] {
        let model = SurfaceModel::new(1.0, lbar, 12, &st).unwrap();
        let mut seed = 3;
        let kappa: Vec<f64> = (0..model.n_kappa())
            .map(|_| kg + 0.01 * lcg(&mut seed))
            .collect();
        let h = model.holonomy(&kappa).unwrap();
        let angle = ((h.trace() - 1.0) / 2.0).acos();
        assert!((angle - 3.0).abs() < 0.05, "angle {angle}");
        let c = model.closure(&kappa).unwrap();
        let norm = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
        assert!(
            (norm - 2.0 * (angle / 2.0).sin()).abs() < 1e-12,
            "|c| = {norm}"
        );
        check_model(&model, &kappa, [0.4, -0.3, 0.7], 1e-6);
    }
}
