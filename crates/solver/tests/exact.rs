//! Equilibria of homogeneous loops against the exact layer (Sec. 4.3): energies, contact force
//! (Eq. 38), internal forces (Eq. 37), curvature and torsion (Eqs. 35–36), conserved moment
//! (Eq. 42); sign conventions; starts from Euler curves, exact loops and point clouds.

mod common;

use common::{compare, solve_uniform};
use nalgebra::{Matrix3, Vector3};
use rodloop_exact::euler::EulerCurve;
use rodloop_solver::frame::integrate;
use rodloop_solver::start::from_points;
use rodloop_solver::{
    solve, Accuracy, Globalization, SolveOptions, SolverError, StartShape, Stiffness, SurfaceModel,
};

const STATES: [(u32, f64); 4] = [(2, 1.2), (1, 1.7), (3, 2.2), (2, 2.8)];

fn default_cells(eta: u32) -> usize {
    Accuracy::Default.cells(eta as usize, &Stiffness::uniform(1.0))
}

#[test]
fn exact_and_euler_starts_reproduce_the_exact_loops() {
    for &(eta, lbar) in &STATES {
        let ex = rodloop_exact::paper_branch_loop(eta, lbar).unwrap();
        let n = default_cells(eta);
        for start in [StartShape::Exact { eta }, StartShape::Euler { l: eta }] {
            let eq = solve_uniform(eta, lbar, n, &start);
            let rep = eq.report();
            assert!(rep.converged && rep.iterations <= 8, "{rep:?}");
            assert!(rep.closure < 1e-10, "closure {}", rep.closure);
            let c = compare(&eq, &ex);
            println!(
                "eta {eta} lbar {lbar} N {n} start {start:?}: iterations {}, {c:?}",
                rep.iterations
            );
            // Same sign convention of κ_g and τ as the exact layer (no mirror needed).
            assert_eq!(c.mirror, 1.0);
            assert!(c.energy_rel < 1e-6, "energy {}", c.energy_rel);
            assert!(
                c.lambda_max_abs < 1e-4 * c.lambda_scale,
                "lambda {}",
                c.lambda_max_abs
            );
            assert!(
                c.lambda_range < 1e-4 * c.lambda_scale,
                "lambda range {}",
                c.lambda_range
            );
            for (name, v) in [
                ("kappa_g", c.kappa_g),
                ("tau", c.tau),
                ("f_t", c.f_t),
                ("f_n", c.f_n),
                ("f_b", c.f_b),
                ("|M| (Eq. 42)", c.moment),
            ] {
                assert!(v < 2e-5, "{name}: {v}");
            }
            // The discretisation breaks the shift symmetry only weakly.
            assert!(eq.phase_multiplier().abs() < 1e-10);
        }
    }
}

#[test]
fn moment_gives_the_curvature_at_the_gauss_points() {
    // D κ_g = 𝓜·n (Eq. 41) with 𝓜 = −μ: the unknowns agree with the interpolant of 𝓜·n/D
    // built at the cell boundaries, to discretisation accuracy. The unknowns are stage
    // values of the Gauss collocation and converge like h³ (stage order), while 𝓜·n/D at
    // the boundaries converges like h⁴ (checked against the exact κ_g elsewhere).
    let mut errs = Vec::new();
    for &n in &[32usize, 64, 128] {
        let eq = solve_uniform(2, 1.2, n, &StartShape::Exact { eta: 2 });
        let t = eq.kappa_g_interpolant().unwrap();
        let err = eq
            .model()
            .gauss_sigma()
            .iter()
            .zip(eq.kappa())
            .map(|(&s, k)| (t.eval(s) - k).abs())
            .fold(0.0, f64::max);
        errs.push(err);
    }
    println!("max |κ_a − 𝓜·n/D| at N = 32, 64, 128: {errs:?}");
    assert!(errs[2] < 5e-5);
    for w in errs.windows(2) {
        let order = (w[0] / w[1]).log2();
        assert!(order > 2.8, "order {order}");
    }
}

#[test]
fn euler_curve_sign_convention_matches_the_frame() {
    // Integrating the Euler curve's κ_g from its own initial Darboux frame reproduces its
    // points: same sign convention (a flipped sign gives the mirror image, far off).
    let curve = EulerCurve::from_lbar(2, 1.3).unwrap();
    let samples = curve.sample(512);
    let t0 = curve.parameter_at_arclength(0.0);
    let r0 = Vector3::from(curve.position(t0));
    let v0 = Vector3::from(curve.velocity(t0)).normalize();
    let g0 = r0.cross(&v0);
    let x0 = Matrix3::from_rows(&[v0.transpose(), g0.transpose(), r0.transpose()]);
    let kg = |s: f64| curve.geodesic_curvature(curve.parameter_at_arclength(s));
    let fc = integrate(kg, curve.length(), 1.0, 512, x0).unwrap();
    let mut err: f64 = 0.0;
    for (i, p) in samples.iter().enumerate() {
        let q = fc.position(i);
        err = err.max((q - Vector3::new(p.x, p.y, p.z)).norm());
    }
    assert!(err < 1e-7, "position error {err}");
    assert!(fc.holonomy_angle() < 1e-7);
}

#[test]
fn positions_stay_on_the_sphere_with_unit_speed() {
    let r = 2.5;
    let model = SurfaceModel::new(r, 1.7, 96, &Stiffness::uniform(3.0)).unwrap();
    let start = StartShape::Euler { l: 1 }.gauss_values(&model).unwrap();
    let eq = solve(&model, &start, &SolveOptions::default()).unwrap();
    let prof = eq.profile();
    let h = model.h();
    for (i, p) in prof.iter().enumerate() {
        let norm = (p.x * p.x + p.y * p.y + p.z * p.z).sqrt();
        assert!((norm - r).abs() < 1e-13 * r);
        let q = &prof[(i + 1) % prof.len()];
        let chord = ((p.x - q.x).powi(2) + (p.y - q.y).powi(2) + (p.z - q.z).powi(2)).sqrt();
        // A chord of an arc of length h on a curve of curvature κ: h − κ²h³/24 + …
        assert!(chord <= h && chord > h * (1.0 - p.kappa.powi(2) * h * h / 20.0));
    }
    // Scaling: the same loop at R = 1, D = 1 has the same normalised energy, and
    // λR³/D, κR, F R²/D agree.
    let eq1 = solve_uniform(1, 1.7, 96, &StartShape::Euler { l: 1 });
    assert!((eq.energy().total - eq1.energy().total).abs() < 1e-12);
    let (lo, hi) = eq.lambda_range();
    let (lo1, hi1) = eq1.lambda_range();
    assert!((lo * r.powi(3) / 3.0 - lo1).abs() < 1e-9 && (hi * r.powi(3) / 3.0 - hi1).abs() < 1e-9);
}

#[test]
fn start_from_a_point_cloud() {
    // Non-uniformly spaced points of the exact η = 2 loop at L̄ = 1.4, scaled to R = 1.5.
    let ex = rodloop_exact::paper_branch_loop(2, 1.4).unwrap();
    let len = ex.length();
    let rho = 1.5;
    let pts: Vec<[f64; 3]> = (0..300)
        .map(|i| {
            let u = i as f64 / 300.0;
            let s = len * (u + 0.03 * (2.0 * std::f64::consts::PI * u).sin());
            let p = ex.point(s).unwrap();
            [rho * p.x, rho * p.y, rho * p.z]
        })
        .collect();
    let (start, lbar, radius) = from_points(&pts).unwrap();
    assert!((lbar - 1.4).abs() < 1e-4, "lbar from points {lbar}");
    assert!((radius - rho).abs() < 1e-12);
    assert_eq!(start.periods(lbar).unwrap(), 2);
    let model = SurfaceModel::new(radius, 1.4, 120, &Stiffness::uniform(1.0)).unwrap();
    let k0 = start.gauss_values(&model).unwrap();
    let eq = solve(&model, &k0, &SolveOptions::default()).unwrap();
    let e = ex.energy().unwrap();
    assert!((eq.energy().total - e).abs() < 1e-6 * e);
}

#[test]
fn bad_inputs_give_precise_errors() {
    let model = SurfaceModel::new(1.0, 1.2, 32, &Stiffness::uniform(1.0)).unwrap();
    assert!(matches!(
        solve(&model, &[0.0; 10], &SolveOptions::default()),
        Err(SolverError::WrongLength {
            expected: 64,
            found: 10
        })
    ));
    assert!(matches!(
        model.kkt_residual(&[0.0; 3]),
        Err(SolverError::WrongLength { .. })
    ));
    let start = StartShape::Euler { l: 2 }.gauss_values(&model).unwrap();
    let opts = SolveOptions {
        max_iterations: 1,
        globalization: Globalization::Newton,
        ..SolveOptions::default()
    };
    match solve(&model, &start, &opts) {
        Err(SolverError::NewtonNotConverged {
            iterations,
            residual,
            ..
        }) => {
            assert_eq!(iterations, 1);
            assert!(residual > 0.0 && residual.is_finite());
        }
        Ok(eq) => panic!("expected non-convergence, got {:?}", eq.report()),
        Err(e) => panic!("expected non-convergence, got {e}"),
    }
    // A circle (constant κ_g) has no shift mode to fix.
    let circle = vec![0.5; 64];
    assert!(matches!(
        solve(&model, &circle, &SolveOptions::default()),
        Err(SolverError::InvalidInput(_))
    ));
    assert!(SurfaceModel::new(-1.0, 1.2, 32, &Stiffness::uniform(1.0)).is_err());
    assert!(SurfaceModel::new(1.0, f64::NAN, 32, &Stiffness::uniform(1.0)).is_err());
    assert!(matches!(
        SurfaceModel::new(1.0, 1.2, 32, &Stiffness::uniform(-1.0)),
        Err(SolverError::InvalidProfile(_))
    ));
    // Branch out of range.
    assert!(matches!(
        StartShape::Exact { eta: 3 }.gauss_values(&model),
        Err(SolverError::Exact(_))
    ));
    assert!(from_points(&[[1.0, 0.0, 0.0]; 3]).is_err());
}

#[test]
fn restart_from_a_saved_profile_at_another_resolution() {
    // A saved configuration (κ_g at uniform s) restarts a solve at another resolution.
    let eq = solve_uniform(3, 2.6, 96, &StartShape::Euler { l: 3 });
    let saved: Vec<f64> = eq.profile().iter().map(|p| p.kappa_g).collect();
    let start = StartShape::from_kappa_g_samples(&saved).unwrap();
    let fine = solve_uniform(3, 2.6, 160, &start);
    assert!(fine.report().iterations <= 2 && fine.report().relax_iterations == 0);
    let e = rodloop_exact::paper_branch_loop(3, 2.6)
        .unwrap()
        .energy()
        .unwrap();
    assert!((fine.energy().total - e).abs() < 1e-6 * e);
    // Resampling the equilibrium directly works the same way.
    let k = eq.resample(160).unwrap();
    assert_eq!(k.len(), 320);
}
