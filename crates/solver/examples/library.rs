//! rodloop as a library: the exact saddle loop (branch 1, η = 2) at L̄ = 1.2, the same state
//! solved numerically, and the two-segment rod of Eq. (51) with D1/D0 = 0.5 at that length.
//!
//! `cargo run --release -p rodloop-solver --example library`
//!
//! The user guide (docs/src/library.md) shows this file; tests/readme.rs checks that the two
//! agree and runs `main`.

use rodloop_exact::paper_branch_loop;
use rodloop_solver::{solve_robust, Accuracy, SolveOptions, StartShape, Stiffness};

pub fn main() -> Result<(), Box<dyn std::error::Error>> {
    let (radius, lbar, eta) = (1.0, 1.2, 2);

    // The closed-form loop of Sec. 4.3 (energies are E R/(π D)).
    let exact = paper_branch_loop(eta, lbar)?;
    let e_exact = exact.energy()?;
    println!("exact:   E = {e_exact:.10}, k = {:.6}", exact.k);

    // The same state from the numerical model, started from the Euler curve l = η.
    let uniform = Stiffness::uniform(1.0);
    let start = StartShape::Euler { l: eta };
    let opts = SolveOptions::default();
    let (sol, _) = solve_robust(
        radius,
        lbar,
        &uniform,
        &start,
        Accuracy::Default,
        Some(eta),
        &opts,
    )?;
    let index = sol.equilibrium.stability()?.index;
    println!(
        "numeric: E = {:.10} ± {:.1e}, index {index}",
        sol.energy.total, sol.energy_error
    );
    assert!((sol.energy.total - e_exact).abs() <= 2.0 * sol.energy_error);
    assert_eq!(index, 0, "the saddle loop is a local minimum");

    // A two-segment rod (Eq. (51)): soft segment 0.3 < s/L < 0.8 with D1/D0 = 0.5, written
    // out as a user writes their own profile (`Stiffness::paper_sec5(0.5)` is the same rod).
    let rod = Stiffness::Tanh {
        d0: 1.0,
        d1: 0.5,
        s0: 0.3,
        s1: 0.8,
        gamma: 200.0,
    };
    let (two, strategy) = solve_robust(
        radius,
        lbar,
        &rod,
        &start,
        Accuracy::Default,
        Some(eta),
        &opts,
    )?;
    println!(
        "D1/D0 = 0.5: E = {:.10} ± {:.1e} ({})",
        two.energy.total,
        two.energy_error,
        strategy.describe()
    );
    // Softening part of the rod lowers the energy, but not below the uniformly soft rod's.
    assert!(two.energy.total < e_exact && two.energy.total > 0.5 * e_exact);
    Ok(())
}
