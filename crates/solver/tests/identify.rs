//! The branch of a two-segment surface state is named from the state itself
//! ([`rodloop_solver::identify`]): a family followed by continuation in `D1/D0` from the
//! uniform rod's exact loop of `η` periods (its homotopy class: no fold, no branch point on
//! the path) is named `η` at every step, also where the soft segment's curvature
//! dominates the geodesic curvature and the count of `κ_g` itself is another.

use rodloop_solver::accuracy::solve_cells;
use rodloop_solver::identify::{identify_equilibrium, identify_periods};
use rodloop_solver::{Equilibrium, SolveOptions, StartShape, Stiffness};

/// The periods of `κ_g` alone (not the moment `D κ_g`), where they are named.
fn kappa_g_count(eq: &Equilibrium) -> Option<(u32, u32)> {
    let p = eq.profile();
    let s: Vec<f64> = p.iter().map(|q| q.s).collect();
    let kg: Vec<f64> = p.iter().map(|q| q.kappa_g).collect();
    identify_periods(&s, &kg, eq.length())
        .ok()
        .map(|x| (x.eta, x.harmonic))
}

#[test]
fn identify_two_segment_family_from_the_uniform_loop() {
    for (eta, lbar) in [(2u32, 2.94), (2, 1.0075)] {
        let opts = SolveOptions::default();
        let mut d1 = 1.0f64;
        let mut prev: Option<Equilibrium> = None;
        let mut differs = 0;
        while d1 > 0.1 + 1e-12 {
            d1 = (d1 * 0.9).max(0.1);
            let st = Stiffness::paper_sec5(d1);
            let eq = solve_cells(
                1.0,
                lbar,
                288,
                &st,
                &StartShape::Exact { eta },
                prev.as_ref(),
                &opts,
            )
            .unwrap_or_else(|e| panic!("D1/D0 = {d1} at {lbar}: {e}"));
            let p = identify_equilibrium(&eq).unwrap_or_else(|e| panic!("{d1} at {lbar}: {e}"));
            let kg = kappa_g_count(&eq);
            println!("L̄ = {lbar}, D1/D0 = {d1:.4}: {p:?}; κ_g alone: {kg:?}");
            assert_eq!(p.eta, eta, "D1/D0 = {d1} at {lbar}: {p:?}");
            if kg.map(|k| k.1) != Some(eta) {
                differs += 1;
            }
            prev = Some(eq);
        }
        println!("L̄ = {lbar}: the harmonic of κ_g alone differs from η at {differs} steps");
        // The path covers states where the dominant harmonic of κ_g is not η.
        assert!(differs > 0, "L̄ = {lbar}");
    }
}
