//! The paper's Sec. 5 statements on the two-segment rod (Eq. (51), s0*/L = 0.3, s1*/L = 0.8,
//! γ = 200), checked against computed lowest states:
//!
//! 1. for D1/D0 = 0.001, `E_el ≈ D0 (s1* − s0*) L/(2R²)`, i.e. `E R/(π D0) ≈ (s1* − s0*) L̄`;
//! 2. the lowest energy lies between those of uniform rods of stiffness D1 and D0 (exact
//!    layer, energies proportional to D).
//!
//! The lowest state at each length is the lowest index-0 state over branches η = 1, 2, 3
//! (those that exist there) and two placements of the soft segment (exact loops shifted by
//! 0 and 1/(4η), each solved with `solve_robust`, which continues in D1/D0 from a mild
//! contrast when the direct solve fails), at the fast accuracy (energies to ~1e-5; the
//! comparisons are at the 0.1 % level).
//!
//! Run: `cargo run --release -p rodloop-diagram --example sec5_checks`.

use rodloop_solver::{solve_robust, Accuracy, SolveOptions, StartShape, Stiffness};

/// The lowest state found: `(η, E R/(π D0), error estimate)`.
type Lowest = Option<(u32, f64, f64)>;

fn uniform_lowest(lbar: f64) -> (u32, f64) {
    let mut best = (0, f64::INFINITY);
    for eta in 1..=4u32 {
        if let Ok(lp) = rodloop_exact::paper_branch_loop(eta, lbar) {
            let e = lp.energy().expect("exact energy");
            if e < best.1 {
                best = (eta, e);
            }
        }
    }
    best
}

fn lowest(d1: f64, lbar: f64) -> Lowest {
    let st = Stiffness::paper_sec5(d1);
    let opts = SolveOptions::default();
    let mut best: Lowest = None;
    for eta in 1..=3u32 {
        let e = f64::from(eta);
        if !(lbar > e - 1.0 && lbar < e + 1.0) {
            continue;
        }
        for k in 0..2 {
            let shift = 0.5 / e * f64::from(k) / 2.0;
            let Ok(start) = StartShape::Exact { eta }.shifted(lbar, shift) else {
                continue;
            };
            let Ok((acc, _)) =
                solve_robust(1.0, lbar, &st, &start, Accuracy::Fast, Some(eta), &opts)
            else {
                continue;
            };
            let Ok(stab) = acc.equilibrium.stability() else {
                continue;
            };
            if stab.index == 0 && best.is_none_or(|b| acc.energy.total < b.1) {
                best = Some((eta, acc.energy.total, acc.energy_error));
            }
        }
    }
    best
}

fn main() {
    let t0 = std::time::Instant::now();
    let grid = [1.1, 1.5, 1.9, 2.1, 2.5, 2.9];
    let frac = 0.8 - 0.3;
    let soft: Vec<(f64, Lowest)> = grid.iter().map(|&l| (l, lowest(0.001, l))).collect();
    println!(
        "Check 1 (D1/D0 = 0.001): E R/(pi D0) of the lowest state vs the paper's (s1* - s0*) L̄\n"
    );
    println!("| L̄ | lowest η | E R/(π D0) | paper (s1*−s0*) L̄ | relative difference |");
    println!("|---|---|---|---|---|");
    let mut worst: f64 = 0.0;
    for (l, low) in &soft {
        match low {
            Some((eta, e, _)) => {
                let approx = frac * l;
                let rel = (e - approx) / approx;
                worst = worst.max(rel.abs());
                println!(
                    "| {l} | {eta} | {e:.6} | {approx:.6} | {:+.2} % |",
                    100.0 * rel
                );
            }
            None => println!("| {l} | – | no stable state found | {:.6} | – |", frac * l),
        }
    }
    println!("\nlargest relative difference: {:.2} %\n", 100.0 * worst);
    println!("Check 2: D1/D0 · E_uniform ≤ E_lowest ≤ E_uniform (E R/(π D0); uniform from the exact layer)\n");
    println!("| D1/D0 | L̄ | D1/D0 · E_u | E_lowest (η) | E_u (η) | inside |");
    println!("|---|---|---|---|---|---|");
    let mut all_inside = true;
    let mut cases: Vec<(f64, f64, Lowest)> =
        soft.iter().map(|(l, low)| (0.001, *l, *low)).collect();
    for d1 in [0.1, 0.5] {
        for l in [1.2, 1.6, 2.2, 2.8] {
            cases.push((d1, l, lowest(d1, l)));
        }
    }
    for (d1, l, low) in cases {
        let (eu_eta, eu) = uniform_lowest(l);
        match low {
            Some((eta, e, err)) => {
                let inside = d1 * eu - err <= e && e <= eu + err;
                all_inside &= inside;
                println!(
                    "| {d1} | {l} | {:.6} | {e:.6} ({eta}) | {eu:.6} ({eu_eta}) | {} |",
                    d1 * eu,
                    if inside { "yes" } else { "NO" }
                );
            }
            None => {
                all_inside = false;
                println!("| {d1} | {l} | {:.6} | not found | {eu:.6} | – |", d1 * eu);
            }
        }
    }
    println!(
        "\nall lowest energies between the uniform bounds: {}",
        if all_inside { "yes" } else { "NO" }
    );
    println!("time {:.1} s", t0.elapsed().as_secs_f64());
}
