//! Benchmarks at the default resolution (branch η = 2 at L̄ = 1.2, `Accuracy::Default`):
//! one equilibrium solve from an Euler-curve start (start construction included), and one
//! stability evaluation of the converged equilibrium.

use criterion::{criterion_group, criterion_main, Criterion};
use rodloop_solver::{solve, Accuracy, SolveOptions, StartShape, Stiffness, SurfaceModel};

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
}

criterion_group! {
    name = group;
    config = Criterion::default().sample_size(30);
    targets = benches
}
criterion_main!(group);
