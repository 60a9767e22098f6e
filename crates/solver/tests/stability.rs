//! Stability: index of the constrained Hessian on exact stable and unstable loops, its
//! independence of the resolution, the split of the symmetry mode, and a direct check that
//! a negative direction lowers the energy at fixed closure.

mod common;

use common::solve_uniform;
use nalgebra::DVector;
use rodloop_exact::{ExactLoop, Family};
use rodloop_solver::{Equilibrium, StartShape};

/// An exact loop of `all_loops(eta, lbar)` by family and winding invariant `q`.
fn exact_loop(eta: u32, lbar: f64, family: Family, q: i32) -> ExactLoop {
    rodloop_exact::all_loops(eta, lbar)
        .unwrap()
        .into_iter()
        .find(|l| l.family == family && l.q == q)
        .unwrap_or_else(|| panic!("no loop eta {eta} lbar {lbar} {family:?} q {q}"))
}

fn solve_loop(lp: &ExactLoop, cells: usize) -> Equilibrium {
    let start = StartShape::from_exact_loop(lp, 512).unwrap();
    solve_uniform(lp.eta, lp.lbar, cells, &start)
}

#[test]
fn index_is_resolution_independent() {
    // (loop, expected index). Stable/metastable states of the paper's branches (Sec. 3.1,
    // Figs. 2–3) have index 0; other closed equilibria of the exact layer are saddles.
    let cases = vec![
        (rodloop_exact::paper_branch_loop(2, 1.2).unwrap(), 0),
        (rodloop_exact::paper_branch_loop(1, 1.7).unwrap(), 0),
        (rodloop_exact::paper_branch_loop(3, 2.2).unwrap(), 0),
        (rodloop_exact::paper_branch_loop(2, 2.8).unwrap(), 0),
        (exact_loop(2, 2.2, Family::Orbit, -3), 1),
        (exact_loop(2, 1.2, Family::Wave, -4), 2),
        (exact_loop(1, 2.2, Family::Wave, -3), 2),
        (exact_loop(3, 1.2, Family::Wave, -5), 2),
    ];
    for (lp, expected) in cases {
        let mut lowest = Vec::new();
        for cells in [64usize, 128, 256] {
            let eq = solve_loop(&lp, cells);
            let st = eq.stability().unwrap();
            println!(
                "eta {} lbar {} {:?} q {} N {cells}: index {} lowest {:?} symmetry {:?} tangency {:?}",
                lp.eta, lp.lbar, lp.family, lp.q, st.index, &st.eigenvalues[..3],
                st.symmetry_eigenvalues, st.symmetry_tangency
            );
            assert_eq!(st.index, expected, "N = {cells}");
            // Clean split: the shift mode is (numerically) a zero mode in the tangent space,
            // well separated from the reported spectrum.
            assert_eq!(st.symmetry_eigenvalues.len(), 1);
            assert!(st.symmetry_eigenvalues[0].abs() < 1e-6);
            assert!(st.symmetry_tangency[0] > 0.999);
            assert!(st.eigenvalues.iter().all(|e| e.abs() > 1e-3));
            assert_eq!(st.dimension, 2 * cells - 4);
            lowest.push(st.eigenvalues[0]);
        }
        // The eigenvalues converge with N (metric of the energy).
        assert!((lowest[1] - lowest[2]).abs() < 1e-3 * (1.0 + lowest[2].abs()));
    }
}

/// Restore closure by Gauss–Newton minimum-norm corrections `κ ← κ − ∇cᵀ(∇c∇cᵀ)⁻¹c`.
fn close(eq: &Equilibrium, mut kappa: Vec<f64>) -> Vec<f64> {
    let model = eq.model();
    for _ in 0..20 {
        let c = model.closure(&kappa).unwrap();
        let cv = DVector::from_column_slice(&c);
        if cv.norm() < 1e-15 {
            break;
        }
        let j = model.closure_jacobian(&kappa).unwrap();
        let y = (&j * j.transpose()).lu().solve(&cv).unwrap();
        let d = j.transpose() * y;
        for (k, dk) in kappa.iter_mut().zip(d.iter()) {
            *k -= dk;
        }
    }
    kappa
}

#[test]
fn negative_direction_lowers_the_energy_at_fixed_closure() {
    for (lp, cells) in [
        (exact_loop(2, 2.2, Family::Orbit, -3), 128usize),
        (exact_loop(2, 1.2, Family::Wave, -4), 128),
        (rodloop_exact::paper_branch_loop(2, 1.2).unwrap(), 128),
    ] {
        let eq = solve_loop(&lp, cells);
        let e0 = eq.model().energy(eq.kappa()).unwrap();
        let (vals, vecs) = eq.constrained_modes().unwrap();
        // Lowest mode that is not the (near-zero) shift mode.
        let i = (0..vals.len()).find(|&i| vals[i].abs() > 1e-4).unwrap();
        let (lam, v) = (vals[i], &vecs[i]);
        for eps in [1e-3, 2e-3] {
            let kappa: Vec<f64> = eq
                .kappa()
                .iter()
                .zip(v.iter())
                .map(|(k, d)| k + eps * d)
                .collect();
            let kappa = close(&eq, kappa);
            let de = eq.model().energy(&kappa).unwrap() - e0;
            let predicted = 0.5 * eps * eps * lam;
            println!(
                "eta {} lbar {} q {}: eigenvalue {lam:.5}, eps {eps}: dE {de:.4e}, predicted {predicted:.4e}",
                lp.eta, lp.lbar, lp.q
            );
            assert_eq!(de < 0.0, lam < 0.0);
            assert!((de / predicted - 1.0).abs() < 0.05, "{de} vs {predicted}");
        }
    }
}

/// A symmetric matrix `Q diag(λ) Qᵀ` of size `n` with the spectrum `lambda` (a deterministic
/// orthogonal `Q` from the QR factorisation of a pseudo-random matrix).
fn with_spectrum(lambda: &[f64]) -> nalgebra::DMatrix<f64> {
    let n = lambda.len();
    let mut seed = 0x9e37_79b9_7f4a_7c15u64;
    let g = nalgebra::DMatrix::from_fn(n, n, |_, _| common::lcg(&mut seed));
    let q = g.qr().q();
    &q * nalgebra::DMatrix::from_diagonal(&DVector::from_column_slice(lambda)) * q.transpose()
}

/// The extreme eigenpairs by block Lanczos ([`rodloop_solver::extreme_eigenpairs`]) are the
/// dense decomposition's: on matrices with the spectrum of a great circle's buckling pencil
/// (isolated extremes, one of them a degenerate pair, above a bulk near zero that holds
/// tight pairs of its own) and on one with a single extreme at each end and an even bulk,
/// the extreme eigenvalues agree to 1e-12 of the spectral radius, a degenerate extreme comes
/// with its partner, and the vectors span the dense eigenspaces (residuals and projections
/// to 1e-10).
#[test]
fn extreme_eigenpairs_are_those_of_the_dense_decomposition() {
    let pencil = |n: usize, top: &[f64], bottom: &[f64]| {
        let mut l: Vec<f64> = top.iter().chain(bottom).copied().collect();
        let bulk = n - l.len();
        for i in 0..bulk {
            // Tight pairs falling towards zero, as the high harmonics of the pencil.
            let k = (i / 2 + 3) as f64;
            l.push(0.05 / (k * k) * if i % 2 == 0 { 1.0 } else { 1.0 + 1e-9 });
        }
        l
    };
    let spectra = [
        pencil(
            200,
            &[1.8, 1.8, 1.125, 1.125],
            &[-1.2857, -1.2857, -0.5625, -0.5625],
        ),
        pencil(300, &[1.0], &[-1.0 / 3.0, -1.0 / 3.0, -0.125, -0.125]),
        (0..150)
            .map(|i| -1.0 + 2.0 * i as f64 / 149.0)
            .collect::<Vec<f64>>(),
        pencil(20, &[2.0, 2.0], &[-1.0]),
    ];
    for lambda in &spectra {
        let a = with_spectrum(lambda);
        let mut sorted = lambda.clone();
        sorted.sort_by(f64::total_cmp);
        let scale = sorted[0].abs().max(sorted[sorted.len() - 1].abs());
        let none = rodloop_solver::extreme_eigenpairs(&a, 0);
        assert!(none.low.is_empty() && none.high.is_empty());
        let ex = rodloop_solver::extreme_eigenpairs(&a, 2);
        let (lo, hi) = (sorted[0], sorted[sorted.len() - 1]);
        assert!(
            (ex.low[0].0 - lo).abs() <= 1e-12 * scale,
            "{} vs {lo}",
            ex.low[0].0
        );
        assert!(
            (ex.high[0].0 - hi).abs() <= 1e-12 * scale,
            "{} vs {hi}",
            ex.high[0].0
        );
        for (pairs, want) in [
            (&ex.low, &sorted[..2]),
            (
                &ex.high,
                &[sorted[sorted.len() - 1], sorted[sorted.len() - 2]][..],
            ),
        ] {
            let degenerate = (want[0] - want[1]).abs() <= 1e-6 * scale;
            let found = (pairs[0].0 - pairs[1].0).abs() <= 1e-6 * scale;
            assert_eq!(
                degenerate,
                found,
                "pair {want:?}: found {:?}",
                (pairs[0].0, pairs[1].0)
            );
            let count = if degenerate { 2 } else { 1 };
            for (theta, v) in &pairs[..count] {
                assert!((v.norm() - 1.0).abs() < 1e-12);
                assert!((&a * v - v * *theta).norm() <= 1e-10 * scale);
            }
            if degenerate {
                assert!(pairs[0].1.dot(&pairs[1].1).abs() < 1e-10);
            }
        }
    }
}
