//! `Equilibrium::profile_uniform`: identity on a uniform mesh, convergence to the fine
//! solution's profile, points uniform in arclength on a graded mesh.

use rodloop_solver::{solve, Equilibrium, ProfilePoint, SolveOptions, StartShape, Stiffness};
use rodloop_solver::{MeshMap, SurfaceModel};

fn solved(st: &Stiffness, lbar: f64, cells: usize, l: u32) -> Equilibrium {
    let model = SurfaceModel::new(1.0, lbar, cells, st).unwrap();
    let k0 = StartShape::Euler { l }.gauss_values(&model).unwrap();
    solve(&model, &k0, &SolveOptions::default()).unwrap()
}

fn max_diff(a: &[ProfilePoint], b: &[ProfilePoint], f: fn(&ProfilePoint) -> f64) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(p, q)| (f(p) - f(q)).abs())
        .fold(0.0, f64::max)
}

/// A named quantity of a profile point.
type Field = (&'static str, fn(&ProfilePoint) -> f64);

const FIELDS: [Field; 7] = [
    ("x", |p| p.x),
    ("y", |p| p.y),
    ("z", |p| p.z),
    ("kappa_g", |p| p.kappa_g),
    ("tau", |p| p.tau),
    ("lambda", |p| p.lambda),
    ("F_t", |p| p.f_t),
];

#[test]
fn uniform_mesh_with_as_many_points_reproduces_the_profile() {
    let eq = solved(&Stiffness::uniform(1.0), 1.3, 48, 2);
    let a = eq.profile();
    let b = eq.profile_uniform(48).unwrap();
    for (name, f) in FIELDS {
        let d = max_diff(&a, &b, f);
        assert!(d < 1e-9, "{name}: {d:e}");
    }
    for (p, q) in a.iter().zip(&b) {
        assert!((p.s - q.s).abs() < 1e-12 && (p.kappa - q.kappa).abs() < 1e-9);
    }
}

#[test]
fn upsampled_profile_matches_the_finer_solution() {
    // The same state solved at N and 4N cells (same start, so the same phase and frame):
    // the N-cell state sampled at the 4N boundaries agrees with the 4N-cell profile to the
    // discretisation error, and the agreement improves with N.
    let st = Stiffness::uniform(1.0);
    let fine = solved(&st, 1.6, 256, 1).profile();
    let mut last = f64::INFINITY;
    for n in [32usize, 64] {
        let coarse = solved(&st, 1.6, n, 1).profile_uniform(256).unwrap();
        let worst = FIELDS
            .iter()
            .map(|(_, f)| max_diff(&coarse, &fine, *f))
            .fold(0.0, f64::max);
        assert!(worst < 1e-3, "N = {n}: {worst:e}");
        assert!(worst < last / 8.0, "N = {n}: {worst:e} after {last:e}");
        last = worst;
        for p in &coarse {
            let r = (p.x * p.x + p.y * p.y + p.z * p.z).sqrt();
            assert!((r - 1.0).abs() < 1e-14);
        }
    }
}

#[test]
fn graded_mesh_is_sampled_uniformly_in_arclength() {
    let st = Stiffness::Tanh {
        d0: 1.0,
        d1: 0.5,
        s0: 0.3,
        s1: 0.8,
        gamma: 60.0,
    };
    assert!(!MeshMap::for_profile(&st).is_uniform());
    let m = 128;
    let eqs: Vec<Equilibrium> = [96usize, 192, 384]
        .iter()
        .map(|&n| solved(&st, 1.5, n, 2))
        .collect();
    // The native boundaries are not uniform in s; the resampled points are.
    let native = eqs[0].profile();
    let h = native[1].s - native[0].s;
    assert!(native
        .windows(2)
        .any(|w| (w[1].s - w[0].s - h).abs() > 0.2 * h));
    let profs: Vec<Vec<ProfilePoint>> = eqs.iter().map(|e| e.profile_uniform(m).unwrap()).collect();
    let len = eqs[0].length();
    for (j, p) in profs[0].iter().enumerate() {
        assert!((p.s - len * j as f64 / m as f64).abs() < 1e-12);
        let d = eqs[0].model().stiffness().eval(p.s / len).d;
        assert!((p.d - d).abs() < 1e-14);
    }
    let diff = |a: &[ProfilePoint], b: &[ProfilePoint]| {
        FIELDS
            .iter()
            .map(|(_, f)| max_diff(a, b, *f))
            .fold(0.0, f64::max)
    };
    let (d1, d2) = (diff(&profs[0], &profs[1]), diff(&profs[1], &profs[2]));
    assert!(d1 < 1e-2 && d2 < d1 / 4.0, "{d1:e} then {d2:e}");
}
