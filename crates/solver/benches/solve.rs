//! Benchmarks at the default resolution (branch η = 2 at L̄ = 1.2, `Accuracy::Default`):
//! one equilibrium solve from an Euler-curve start (start construction included), one
//! stability evaluation of the converged equilibrium, and one `O(N)` factorisation of the
//! Newton matrix with one solve (the core of a Newton step) at a two-segment rod's equilibrium,
//! the construction of a two-segment rod's model on its graded mesh, and a two-segment rod's
//! Newton run that keeps the run where a looser tolerance stops (what a diagram's state
//! verification runs for every state it writes), and the closure rows of a line-search trial
//! (`kkt_closure_residual` at states none of whose cells the per-thread table of Rodrigues
//! coefficients holds, as at a rejected trial).

use criterion::{criterion_group, criterion_main, Criterion};
use nalgebra::DVector;
use rodloop_solver::{
    solve, solve_newton_keeping, Accuracy, Globalization, KktFactor, SolveOptions, StartShape,
    Stiffness, SurfaceModel,
};

fn benches(c: &mut Criterion) {
    let st = Stiffness::uniform(1.0);
    let cells = Accuracy::Default.cells(2, &st);
    let model = SurfaceModel::new(1.0, 1.2, cells, &st).unwrap();
    let opts = SolveOptions::default();
    let start = StartShape::Euler { l: 2 };
    c.bench_function(&format!("solve_euler_start_eta2_lbar1.2_N{cells}"), |b| {
        b.iter(|| {
            let k0 = start.gauss_values(&model).unwrap();
            solve(&model, &k0, &opts).unwrap()
        })
    });
    let k0 = start.gauss_values(&model).unwrap();
    let eq = solve(&model, &k0, &opts).unwrap();
    c.bench_function(&format!("stability_eta2_lbar1.2_N{cells}"), |b| {
        b.iter(|| eq.stability().unwrap())
    });
    // The factorisation at an equilibrium of a two-segment rod (D1/D0 = 0.5, graded mesh,
    // no phase condition): at a uniform rod's equilibrium the unbordered matrix is singular
    // (the shift mode) and the factorisation declines.
    let st = Stiffness::Tanh {
        d0: 1.0,
        d1: 0.5,
        s0: 0.3,
        s1: 0.8,
        gamma: 200.0,
    };
    let cells = Accuracy::Default.cells(2, &st);
    let model = SurfaceModel::new(1.0, 1.2, cells, &st).unwrap();
    // A model of the graded mesh at the resolution of one already built (what every
    // continuation step, re-solve and verification of a two-segment diagram builds).
    c.bench_function(&format!("surface_model_new_d1_0.5_lbar1.2_N{cells}"), |b| {
        b.iter(|| SurfaceModel::new(1.0, 1.2, cells, &st).unwrap())
    });
    let k0 = start.gauss_values(&model).unwrap();
    let newton = SolveOptions {
        globalization: Globalization::Newton,
        tolerance: 1e-10,
        ..SolveOptions::default()
    };
    c.bench_function(
        &format!("solve_newton_keeping_d1_0.5_lbar1.2_N{cells}"),
        |b| {
            b.iter(|| {
                let (eq, kept) = solve_newton_keeping(&model, &k0, &newton, 1e-6);
                (eq.unwrap(), kept.unwrap())
            })
        },
    );
    let eq = solve(&model, &k0, &opts).unwrap();
    let (model, z) = (eq.model(), eq.state());
    let rhs = DVector::from_fn(model.dim(), |i, _| ((i * 7919) % 101) as f64 / 101.0 - 0.5);
    c.bench_function(
        &format!("kkt_factor_and_solve_d1_0.5_lbar1.2_N{cells}"),
        |b| b.iter(|| KktFactor::new(model, &z, 0.0).unwrap().solve(&rhs).unwrap()),
    );
    // 64 trial states, more cells in all than the table has slots.
    let trials: Vec<Vec<f64>> = (0..64)
        .map(|t| {
            let mut zt = z.clone();
            for (i, v) in zt.iter_mut().enumerate().take(model.n_kappa()) {
                *v += 1e-3 * (((i * 31 + t * 17) % 23) as f64 / 23.0 - 0.5);
            }
            zt
        })
        .collect();
    let mut next = 0;
    c.bench_function(
        &format!("kkt_closure_residual_d1_0.5_lbar1.2_N{cells}"),
        |b| {
            b.iter(|| {
                next = (next + 1) % trials.len();
                model.kkt_closure_residual(&trials[next]).unwrap()
            })
        },
    );
}

criterion_group! {
    name = group;
    config = Criterion::default().sample_size(30);
    targets = benches
}
criterion_main!(group);
