//! Measured accuracy against the exact layer: order of convergence of the energy and of the
//! contact force λ for η = 1..4 across each branch (including within 1e-3 of its ends), the
//! targets of the default accuracy and Richardson extrapolation of the high accuracy.
//!
//! `cargo test -p rodloop-solver --release -- --nocapture convergence` prints the tables.

mod common;

use common::{compare, solve_uniform};
use rodloop_solver::{solve_with_accuracy, Accuracy, SolveOptions, StartShape, Stiffness};

/// States (η, L̄): ends of each branch (1e-3 inside) and interior points.
fn states() -> Vec<(u32, f64)> {
    vec![
        (1, 0.001),
        (1, 0.5),
        (1, 1.2),
        (1, 1.7),
        (1, 1.999),
        (2, 1.001),
        (2, 1.2),
        (2, 1.6),
        (2, 2.2),
        (2, 2.8),
        (2, 2.999),
        (3, 2.001),
        (3, 2.2),
        (3, 3.0),
        (3, 3.999),
        (4, 3.001),
        (4, 3.5),
        (4, 4.2),
        (4, 4.999),
    ]
}

#[test]
fn convergence_orders_of_energy_and_lambda() {
    println!("\nOrder of convergence against the exact layer (N cells, errors relative):");
    println!(
        "{:>3} {:>6} | {:>5} {:>9} {:>9} {:>9} | {:>6} {:>6} | {:>9} {:>9} {:>9} | {:>6} {:>6}",
        "eta",
        "lbar",
        "N",
        "E(N)",
        "E(2N)",
        "E(4N)",
        "p1",
        "p2",
        "lam(N)",
        "lam(2N)",
        "lam(4N)",
        "p1",
        "p2"
    );
    let mut worst: f64 = 10.0;
    for (eta, lbar) in states() {
        let ex = rodloop_exact::paper_branch_loop(eta, lbar).unwrap();
        let n0 = 16 * (1 + eta as usize);
        let mut e = Vec::new();
        let mut l = Vec::new();
        for k in 0..3 {
            let eq = solve_uniform(eta, lbar, n0 << k, &StartShape::Exact { eta });
            let c = compare(&eq, &ex);
            e.push(c.energy_rel);
            l.push(c.lambda_max_abs / c.lambda_scale);
        }
        let ord = |a: f64, b: f64| (a / b).log2();
        let (pe1, pe2) = (ord(e[0], e[1]), ord(e[1], e[2]));
        let (pl1, pl2) = (ord(l[0], l[1]), ord(l[1], l[2]));
        println!(
            "{eta:>3} {lbar:>6.3} | {n0:>5} {:>9.2e} {:>9.2e} {:>9.2e} | {pe1:>6.2} {pe2:>6.2} | {:>9.2e} {:>9.2e} {:>9.2e} | {pl1:>6.2} {pl2:>6.2}",
            e[0], e[1], e[2], l[0], l[1], l[2]
        );
        // Orders measured where the errors are well above rounding.
        if e[2] > 1e-12 {
            worst = worst.min(pe2);
            assert!(
                (3.6..4.6).contains(&pe2),
                "energy order {pe2} at eta {eta}, lbar {lbar}"
            );
        }
        if l[2] > 1e-11 {
            worst = worst.min(pl2);
            assert!(
                (3.6..4.6).contains(&pl2),
                "lambda order {pl2} at eta {eta}, lbar {lbar}"
            );
        }
    }
    println!("lowest measured order (finest pair): {worst:.2}");
}

#[test]
fn convergence_default_accuracy_meets_targets() {
    println!("\nDefault accuracy: errors against the exact layer and the built-in estimates:");
    println!(
        "{:>3} {:>6} {:>5} | {:>9} {:>9} | {:>9} {:>9} | {:>6}",
        "eta", "lbar", "N", "E rel", "E est", "lam rel", "lam est", "iters"
    );
    for (eta, lbar) in states() {
        let ex = rodloop_exact::paper_branch_loop(eta, lbar).unwrap();
        // Euler curves are used as starts inside the branches; at the ends use the exact loop.
        let near_end =
            (lbar - (eta as f64 - 1.0)).abs() < 0.01 || (lbar - (eta as f64 + 1.0)).abs() < 0.01;
        let start = if near_end {
            StartShape::Exact { eta }
        } else {
            StartShape::Euler { l: eta }
        };
        let acc = solve_with_accuracy(
            1.0,
            lbar,
            &Stiffness::uniform(1.0),
            &start,
            Accuracy::Default,
            &SolveOptions::default(),
        )
        .unwrap();
        let eq = &acc.equilibrium;
        let c = compare(eq, &ex);
        let exact_e = ex.energy().unwrap();
        let e_rel = (acc.energy.total - exact_e).abs() / exact_e;
        let lam_rel = c.lambda_max_abs / c.lambda_scale;
        println!(
            "{eta:>3} {lbar:>6.3} {:>5} | {e_rel:>9.2e} {:>9.2e} | {lam_rel:>9.2e} {:>9.2e} | {:>6}",
            eq.model().cells(),
            acc.energy_error / exact_e,
            acc.lambda_error / c.lambda_scale,
            eq.report().iterations
        );
        assert!(
            e_rel <= 1e-6,
            "energy error {e_rel} at eta {eta}, lbar {lbar}"
        );
        assert!(
            lam_rel <= 1e-4,
            "lambda error {lam_rel} at eta {eta}, lbar {lbar}"
        );
        // The estimate is of the right size (h⁴ asymptotics: close to the true error).
        assert!(
            acc.energy_error / exact_e > 0.3 * e_rel - 1e-13
                && acc.energy_error / exact_e < 3.0 * e_rel + 1e-12,
            "energy estimate {} vs error {e_rel}",
            acc.energy_error / exact_e
        );
    }
}

#[test]
fn convergence_high_accuracy_extrapolates() {
    println!("\nHigh accuracy (Richardson over N, 2N):");
    for (eta, lbar) in [(2u32, 1.2), (1, 0.5), (3, 2.6), (4, 3.6)] {
        let ex = rodloop_exact::paper_branch_loop(eta, lbar).unwrap();
        let exact_e = ex.energy().unwrap();
        let (elo, ehi) = ex.lambda_range();
        let run = |a| {
            solve_with_accuracy(
                1.0,
                lbar,
                &Stiffness::uniform(1.0),
                &StartShape::Euler { l: eta },
                a,
                &SolveOptions::default(),
            )
            .unwrap()
        };
        let (d, h) = (run(Accuracy::Default), run(Accuracy::High));
        let err = |x: &rodloop_solver::AccurateEquilibrium| {
            (
                (x.energy.total - exact_e).abs() / exact_e,
                (x.lambda_range.0 - elo)
                    .abs()
                    .max((x.lambda_range.1 - ehi).abs()),
            )
        };
        let (ed, ld) = err(&d);
        let (eh, lh) = err(&h);
        println!(
            "eta {eta} lbar {lbar}: default E {ed:.2e} lam {ld:.2e}; high E {eh:.2e} (estimate {:.2e}) lam {lh:.2e} (estimate {:.2e})",
            h.energy_error / exact_e,
            h.lambda_error
        );
        assert!(
            eh < 0.05 * ed + 1e-13,
            "extrapolation gains little: {eh} vs {ed}"
        );
        assert!(lh < 0.05 * ld + 1e-11);
        assert!(
            h.energy_error / exact_e >= eh,
            "estimate must bound the extrapolated error"
        );
        assert!(h.lambda_error >= lh);
    }
}
