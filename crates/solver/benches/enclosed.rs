//! One semismooth Newton step of the enclosed model (residual, lifted block system, its
//! `O(N)` factorisation, one refinement) for a two-segment rod (Eq. (51), D1/D0 = 0.5) at
//! `N = 256` cells and at `N = 64` (the finest level of the enclosed diagram's traces of
//! branch 1), at a state with a mixed contact set (both branches of the min-function).

use criterion::{criterion_group, criterion_main, Criterion};
use rodloop_solver::enclosed::start_from_surface;
use rodloop_solver::Stiffness;
use std::f64::consts::PI;

fn benches(c: &mut Criterion) {
    let st = Stiffness::Tanh {
        d0: 1.0,
        d1: 0.5,
        s0: 0.3,
        s1: 0.8,
        gamma: 200.0,
    };
    for cells in [256, 64] {
        // A figure-eight-like start on the sphere (geodesic curvature odd about half the loop).
        let (m, mut z) =
            start_from_surface(1.0, 1.35, cells, &st, |s| 2.0 * (2.0 * PI * s).sin()).unwrap();
        for (i, v) in z.iter_mut().enumerate() {
            *v += 1e-3 * (i as f64 * 1.7).sin();
        }
        let lo = m.lambda_offset();
        for j in 0..m.cells() {
            z[lo + j] = if j % 3 == 0 { -0.05 } else { 0.3 };
        }
        c.bench_function(
            &format!("enclosed_newton_step_d1_0.5_lbar1.35_N{cells}"),
            |b| b.iter(|| m.newton_step(&z).unwrap()),
        );
    }
}

criterion_group! {
    name = group;
    config = Criterion::default()
        .sample_size(20)
        .warm_up_time(std::time::Duration::from_secs(1))
        .measurement_time(std::time::Duration::from_secs(3));
    targets = benches
}
criterion_main!(group);
