//! Every derivative of the augmented system against central finite differences, and the
//! bordered factorisation against the dense LU of the same matrix.

use super::*;
use rodloop_continuation::{fd_dparam, fd_jacobian};
use rodloop_solver::{solve_from_state, StartShape, Stiffness};

fn profile(d1: f64) -> Stiffness {
    Stiffness::Tanh {
        d0: 1.0,
        d1,
        s0: 0.3,
        s1: 0.8,
        // Smooth enough for finite differences on a coarse mesh.
        gamma: 12.0,
    }
}

/// A non-equilibrium state: exact loops sampled on the models, arbitrary multipliers.
fn problem_and_state(param: Param) -> (MaxwellProblem<impl SurfaceSolve>, DVector<f64>, f64) {
    let st = profile(0.6);
    let lbar = 1.4;
    let ma = crate::surface_model(1.0, lbar, 12, &st).unwrap();
    let mb = crate::surface_model(1.0, lbar, 10, &st).unwrap();
    let mut za = StartShape::Exact { eta: 2 }.gauss_values(&ma).unwrap();
    za.extend_from_slice(&[0.3, -0.2, 0.1]);
    let mut zb = StartShape::Exact { eta: 1 }
        .shifted(lbar, 0.17)
        .unwrap()
        .gauss_values(&mb)
        .unwrap();
    zb.extend_from_slice(&[-0.1, 0.25, 0.05]);
    let pb = MaxwellProblem::new(ma, mb, param).unwrap();
    let p = pb.p_of(pb.models().0.param(param).unwrap());
    (pb, join(&za, &zb, lbar), p)
}

fn rel_err(a: &DMatrix<f64>, b: &DMatrix<f64>) -> f64 {
    (a - b).amax() / b.amax().max(1e-300)
}

#[test]
fn energy_derivatives_match_finite_differences() {
    let (pb, x, p) = problem_and_state(Param::D1);
    let (za, _, lbar) = pb.split(x.as_slice()).unwrap();
    let (ma, _) = pb.models_at(lbar, p).unwrap();
    // ∂E/∂z.
    let g = energy_gradient(&ma, za).unwrap();
    let fd = fd_jacobian(
        |z: &DVector<f64>| -> Result<DVector<f64>, SolverError> {
            Ok(DVector::from_element(1, energy(&ma, z.as_slice())?))
        },
        &DVector::from_column_slice(za),
    )
    .unwrap();
    let n = g.len();
    assert!(
        rel_err(&DMatrix::from_row_slice(1, n, g.as_slice()), &fd) < 1e-8,
        "∂E/∂z"
    );
    // ∂E/∂L̄ and ∂E/∂θ for every stiffness parameter.
    for param in [Param::Lbar, Param::D1, Param::Gamma, Param::S0, Param::S1] {
        let v = ma.param(param).unwrap();
        let an = energy_dparam(&ma, za, param).unwrap();
        let fd = fd_dparam(
            |q| -> Result<DVector<f64>, SolverError> {
                let m = ma.with_param(param, q)?;
                Ok(DVector::from_element(1, energy(&m, za)?))
            },
            v,
        )
        .unwrap()[0];
        assert!(
            (an - fd).abs() <= 1e-7 * fd.abs().max(1e-3),
            "∂E/∂{param}: analytic {an}, finite differences {fd}"
        );
    }
}

#[test]
fn augmented_jacobian_and_parameter_derivative_match_finite_differences() {
    for param in [Param::D1, Param::Gamma, Param::S0, Param::S1] {
        let (pb, x, p) = problem_and_state(param);
        let j = pb.jacobian(&x, p).unwrap();
        let fd = fd_jacobian(|y| pb.residual(y, p), &x).unwrap();
        assert!(
            rel_err(&j, &fd) < 1e-7,
            "{param}: ∂G/∂x {}",
            rel_err(&j, &fd)
        );
        let dp = pb.dparam(&x, p).unwrap();
        let fdp = fd_dparam(|q| pb.residual(&x, q), p).unwrap();
        let e = (&dp - &fdp).amax() / fdp.amax();
        assert!(e < 1e-7, "{param}: ∂G/∂p {e}");
    }
}

#[test]
fn bordered_factorisation_agrees_with_dense_lu() {
    let (pb, x, p) = problem_and_state(Param::D1);
    let f = pb.factorize(&x, p).unwrap();
    let j = pb.jacobian(&x, p).unwrap();
    let dense = DenseLu::new(j.clone());
    let b = DVector::from_fn(pb.dim(), |i, _| ((i * 7 + 3) % 11) as f64 - 5.0);
    let xs = f.solve(&b).unwrap();
    let xd = dense.solve(&b).unwrap();
    assert!((&xs - &xd).amax() <= 1e-8 * xd.amax(), "solve");
    assert!((&j * &xs - &b).amax() <= 1e-8 * b.amax(), "residual");
    let v = DVector::from_fn(pb.dim(), |i, _| (i as f64 * 0.37).sin());
    assert!((f.apply(&v) - &j * &v).amax() <= 1e-12 * (&j * &v).amax());
    assert_eq!(f.det_sign(), dense.det_sign());
    assert!((f.log_abs_det() - dense.log_abs_det()).abs() < 1e-8);
}

#[test]
fn crossing_slope_is_the_derivative_of_the_energy_gap_along_the_equilibria() {
    // At equilibria the Schur complement is d(E_a − E_b)/dL̄ with both states re-solved:
    // compare with central differences of re-solved energies.
    let st = Stiffness::paper_sec5(0.9);
    let opts = SolveOptions::default();
    let a = crate::phase::lowest_placement(1.0, 1.4, 2, 112, &st, &opts).unwrap();
    let b = crate::phase::lowest_placement(1.0, 1.4, 1, 84, &st, &opts).unwrap();
    let pb = MaxwellProblem::new(a.model().clone(), b.model().clone(), Param::D1).unwrap();
    let x = join(&a.state(), &b.state(), 1.4);
    let (slope, _, _) = pb.crossing_slope(&x, pb.p_of(0.9)).unwrap();
    let h = 1e-4;
    let newton = SolveOptions {
        globalization: Globalization::Newton,
        ..opts.clone()
    };
    let gap = |l: f64| {
        let ea = solve_from_state(a.model().with_lbar(l).unwrap(), a.state(), &newton).unwrap();
        let eb = solve_from_state(b.model().with_lbar(l).unwrap(), b.state(), &newton).unwrap();
        ea.energy().total - eb.energy().total
    };
    let fd = (gap(1.4 + h) - gap(1.4 - h)) / (2.0 * h);
    assert!(
        (slope - fd).abs() < 1e-6 * fd.abs().max(1.0),
        "{slope} vs {fd}"
    );
}

#[test]
fn bad_input_is_refused() {
    let st = profile(0.6);
    let m = crate::surface_model(1.0, 1.4, 12, &st).unwrap();
    assert!(MaxwellProblem::new(m.clone(), m.clone(), Param::Lbar).is_err());
    let u = crate::surface_model(1.0, 1.4, 12, &Stiffness::uniform(1.0)).unwrap();
    assert!(MaxwellProblem::new(u.clone(), u, Param::D1).is_err());
    let pb = MaxwellProblem::new(m.clone(), m, Param::D1).unwrap();
    assert!(pb.residual(&DVector::zeros(3), 0.0).is_err());
}
