//! The O(N) block factorisation of the KKT matrix against the dense matrix it replaces:
//! solves, determinant sign and modulus, inertia, Hessian–vector products, on uniform and
//! graded meshes, with and without the phase border, at equilibria and away from them.

use nalgebra::{DMatrix, DVector};
use rodloop_solver::{
    solve, KktFactor, MeshMap, Phase, SolveOptions, StartShape, Stiffness, SurfaceModel,
};

fn lcg(seed: &mut u64) -> f64 {
    *seed = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    ((*seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
}

fn sharp() -> Stiffness {
    Stiffness::paper_sec5(0.5)
}

/// A KKT state near an Euler start, perturbed, with a random multiplier.
fn state(model: &SurfaceModel, seed: &mut u64) -> Vec<f64> {
    let k0 = StartShape::Euler { l: 2 }.gauss_values(model).unwrap();
    let mut z: Vec<f64> = k0.iter().map(|k| k + 0.05 * lcg(seed)).collect();
    z.extend([0.3 * lcg(seed), 0.3 * lcg(seed), 0.3 * lcg(seed)]);
    if model.phase().is_some() {
        z.push(0.01 * lcg(seed));
    }
    z
}

fn dense_negatives(j: &DMatrix<f64>) -> usize {
    let s = (j + j.transpose()) * 0.5;
    s.symmetric_eigenvalues()
        .iter()
        .filter(|v| **v < 0.0)
        .count()
}

fn check(model: &SurfaceModel, z: &[f64], seed: &mut u64, what: &str) {
    let j = model.kkt_jacobian(z).unwrap();
    let f = KktFactor::new(model, z, 0.0).unwrap();
    // Solves against dense LU.
    for _ in 0..3 {
        let b = DVector::from_fn(model.dim(), |_, _| lcg(seed));
        let x = f.solve(&b).unwrap();
        let xd = j.clone().lu().solve(&b).unwrap();
        let err = (&x - &xd).amax() / xd.amax();
        assert!(err < 1e-8, "{what}: solve differs by {err:e}");
        let res = (&j * &x - &b).amax() / b.amax();
        assert!(res < 1e-9, "{what}: residual {res:e}");
    }
    // Determinant.
    let lu = j.clone().lu();
    let mut sign = lu.p().determinant::<f64>();
    let mut logdet = 0.0;
    for d in lu.u().diagonal().iter() {
        if *d < 0.0 {
            sign = -sign;
        }
        logdet += d.abs().ln();
    }
    assert_eq!(f.det_sign(), sign, "{what}: determinant sign");
    assert!(
        (f.log_abs_det() - logdet).abs() < 1e-8 * logdet.abs().max(1.0),
        "{what}: ln|det| {} vs {}",
        f.log_abs_det(),
        logdet
    );
    // Inertia.
    assert_eq!(
        f.negative_eigenvalues(),
        dense_negatives(&j),
        "{what}: number of negative eigenvalues"
    );
}

#[test]
fn factorisation_matches_the_dense_matrix_uniform_with_phase() {
    let mut seed = 7;
    for &(lbar, cells) in &[(1.2, 12usize), (1.6, 20), (2.3, 32)] {
        let m = SurfaceModel::new(1.0, lbar, cells, &Stiffness::uniform(1.0)).unwrap();
        let k0 = StartShape::Euler { l: 2 }.gauss_values(&m).unwrap();
        let m = m
            .with_phase(Phase::from_gauss_values(&k0, cells).unwrap())
            .unwrap();
        let z = state(&m, &mut seed);
        check(
            &m,
            &z,
            &mut seed,
            &format!("uniform L̄ = {lbar}, N = {cells}"),
        );
    }
}

#[test]
fn factorisation_matches_the_dense_matrix_graded_and_without_phase() {
    let mut seed = 11;
    let m = SurfaceModel::new(1.0, 1.3, 24, &sharp()).unwrap();
    assert!(!m.mesh().is_uniform());
    let z = state(&m, &mut seed);
    check(&m, &z, &mut seed, "graded γ = 200");
    let m = SurfaceModel::new(1.0, 1.7, 16, &Stiffness::uniform(1.0)).unwrap();
    let z = state(&m, &mut seed);
    check(&m, &z, &mut seed, "uniform without phase");
}

#[test]
fn shifted_inertia_counts_the_constrained_eigenvalues_below_the_shift() {
    // At an equilibrium, the number of constrained Hessian eigenvalues below σ (dense
    // reduction on a uniform mesh) equals the shifted inertia count.
    let m = SurfaceModel::new(1.0, 1.5, 24, &sharp())
        .unwrap()
        .with_mesh(MeshMap::Uniform)
        .unwrap();
    let k0 = StartShape::Euler { l: 1 }.gauss_values(&m).unwrap();
    let eq = solve(&m, &k0, &SolveOptions::default()).unwrap();
    let (vals, _) = eq.constrained_modes().unwrap();
    let z = eq.state();
    for &sigma in &[-50.0, -1.0, -1e-6, 0.05, 0.5, 2.0, 10.0] {
        let expected = vals.iter().filter(|v| **v < sigma).count();
        let f = KktFactor::new(eq.model(), &z, sigma).unwrap();
        assert_eq!(f.reduced_negative_count(), expected, "σ = {sigma}");
    }
}

#[test]
fn hessian_vector_product_matches_the_dense_hessian() {
    let mut seed = 3;
    for map in [MeshMap::Uniform, MeshMap::for_profile(&sharp())] {
        let m = SurfaceModel::new(1.0, 2.2, 20, &sharp())
            .unwrap()
            .with_mesh(map)
            .unwrap();
        let z = state(&m, &mut seed);
        let (kappa, mu, _) = m.split(&z).unwrap();
        let h = m.lagrangian_hessian(kappa, &mu).unwrap();
        let v = DVector::from_fn(m.n_kappa(), |_, _| lcg(&mut seed));
        let hv = m.hessian_vector(kappa, &mu, v.as_slice()).unwrap();
        let dense = &h * &v;
        let err = (DVector::from_vec(hv) - &dense).amax() / dense.amax();
        assert!(err < 1e-12, "Hv differs by {err:e}");
    }
}

#[test]
fn matrix_vector_product_matches_the_dense_matrix() {
    let mut seed = 5;
    let m = SurfaceModel::new(1.0, 1.4, 16, &Stiffness::uniform(1.0)).unwrap();
    let k0 = StartShape::Euler { l: 2 }.gauss_values(&m).unwrap();
    let m = m
        .with_phase(Phase::from_gauss_values(&k0, 16).unwrap())
        .unwrap();
    let z = state(&m, &mut seed);
    let dz = DVector::from_fn(m.dim(), |_, _| lcg(&mut seed));
    let jd = m.kkt_apply(&z, dz.as_slice()).unwrap();
    let dense = m.kkt_jacobian(&z).unwrap() * &dz;
    let err = (jd - &dense).amax() / dense.amax();
    assert!(err < 1e-12, "J dz differs by {err:e}");
}

#[test]
fn factor_apply_is_the_shifted_matrix() {
    let mut seed = 21;
    let m = SurfaceModel::new(1.0, 1.3, 20, &sharp()).unwrap();
    let z = state(&m, &mut seed);
    let shift = 0.7;
    let f = KktFactor::new(&m, &z, shift).unwrap();
    let mut dense = m.kkt_jacobian(&z).unwrap();
    for a in 0..m.n_kappa() {
        dense[(a, a)] -= shift * m.cell_weight(a / 2);
    }
    let v = DVector::from_fn(m.dim(), |_, _| lcg(&mut seed));
    let err = (f.apply(&v) - &dense * &v).amax() / (&dense * &v).amax();
    assert!(err < 1e-12, "apply differs by {err:e}");
    let x = f.solve(&v).unwrap();
    assert!((&dense * &x - &v).amax() < 1e-9 * v.amax());
}

/// At an equilibrium of the uniform rod the KKT matrix without its phase border is singular
/// (the arclength shift), and the block elimination meets a nearly singular block half-way
/// round the loop: the factorisation either reports it (callers then use the dense matrix)
/// or solves to the dense matrix's accuracy, never returns a solve that misses.
#[test]
fn a_nearly_singular_block_is_reported_or_solved_accurately() {
    let mut seed = 3;
    let mut reported = 0;
    for k in 0..=20 {
        let lbar = 1.30 + 0.005 * k as f64;
        let m0 = SurfaceModel::new(1.0, lbar, 120, &Stiffness::uniform(1.0)).unwrap();
        let k0 = StartShape::Exact { eta: 2 }.gauss_values(&m0).unwrap();
        let m = m0
            .with_phase(Phase::from_gauss_values(&k0, 120).unwrap())
            .unwrap();
        let eq = solve(&m, &k0, &SolveOptions::default()).unwrap();
        let z = eq.state();
        let j = m.kkt_jacobian(&z).unwrap();
        match KktFactor::new(&m, &z, 0.0) {
            Ok(f) => {
                let b = DVector::from_fn(m.dim(), |_, _| lcg(&mut seed));
                let x = f.solve(&b).unwrap();
                let res = (&j * &x - &b).amax() / b.amax();
                assert!(res < 1e-8, "L̄ = {lbar}: residual {res:e}");
            }
            Err(rodloop_solver::SolverError::SingularJacobian { .. }) => reported += 1,
            Err(e) => panic!("L̄ = {lbar}: {e}"),
        }
    }
    println!("{reported} of 21 factorisations reported singular");
}

/// The closure rows alone ([`SurfaceModel::kkt_closure_residual`]) are those of the whole
/// KKT residual to the bit (a line search rejects a trial from them, which must be the
/// decision the whole residual gives), on a graded and a uniform mesh with a phase border,
/// at states near an Euler start and with large curvatures (rotation angles per cell past
/// the switch of the Rodrigues coefficients); a non-finite curvature is refused like the
/// whole residual refuses it.
#[test]
fn closure_rows_alone_are_the_residuals_to_the_bit() {
    let mut seed = 23;
    let uniform = SurfaceModel::new(1.0, 1.6, 20, &Stiffness::uniform(1.0)).unwrap();
    let k0 = StartShape::Euler { l: 2 }.gauss_values(&uniform).unwrap();
    let uniform = uniform
        .with_phase(Phase::from_gauss_values(&k0, 20).unwrap())
        .unwrap();
    let graded = SurfaceModel::new(1.0, 1.3, 24, &sharp()).unwrap();
    for m in [&uniform, &graded] {
        let n = m.n_kappa();
        for scale in [1.0, 30.0] {
            let mut z = state(m, &mut seed);
            for k in &mut z[..n] {
                *k *= scale;
            }
            let f = m.kkt_residual(&z).unwrap();
            let c = m.kkt_closure_residual(&z).unwrap();
            assert!(c.iter().any(|v| *v != 0.0));
            for k in 0..3 {
                assert_eq!(c[k].to_bits(), f[n + k].to_bits(), "row {k}, scale {scale}");
            }
        }
        let mut z = state(m, &mut seed);
        z[3] = f64::NAN;
        assert!(m.kkt_residual(&z).is_err() && m.kkt_closure_residual(&z).is_err());
        assert!(m.kkt_closure_residual(&z[1..]).is_err());
    }
}
