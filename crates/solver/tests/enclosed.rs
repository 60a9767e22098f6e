//! The enclosed model (issue 9): exact derivatives, exact states, lift-off, optimality and
//! the order of convergence.

use rodloop_exact::paper_branch_loop;
use rodloop_solver::enclosed::{
    solve_branch, start_from_surface, EnclosedModel, EnclosedOptions, SurfaceSource,
};
use rodloop_solver::Stiffness;

fn exact_start(eta: u32, lbar: f64, cells: usize, d: &Stiffness) -> (EnclosedModel, Vec<f64>) {
    let l = paper_branch_loop(eta, lbar).unwrap();
    start_from_surface(1.0, lbar, cells, d, |s| {
        l.point(s * l.length()).unwrap().kappa_g
    })
    .unwrap()
}

/// The semismooth Jacobian against central differences of the residual, at a perturbed
/// state with mixed contact rows (both branches of the min-function), uniform and Eq. (51).
#[test]
fn jacobian_matches_finite_differences() {
    for stiff in [
        Stiffness::uniform(1.0),
        Stiffness::Tanh {
            d0: 1.0,
            d1: 0.5,
            s0: 0.3,
            s1: 0.8,
            gamma: 10.0,
        },
    ] {
        let (m, mut z) = exact_start(1, 1.5, 10, &stiff);
        // Perturb everything, make some multipliers clearly positive/negative.
        for (i, v) in z.iter_mut().enumerate() {
            *v += 0.01 * ((i as f64 * 1.7).sin());
        }
        let lo = m.lambda_offset();
        for j in 0..m.cells() {
            z[lo + j] = if j % 3 == 0 { -0.05 } else { 0.3 + 0.01 * j as f64 };
        }
        let ev = m.evaluate(&z).unwrap();
        let eps = 1e-6;
        let mut worst: f64 = 0.0;
        for k in 0..m.dim() {
            let mut zp = z.clone();
            let mut zm = z.clone();
            zp[k] += eps;
            zm[k] -= eps;
            let fd = (m.residual(&zp).unwrap() - m.residual(&zm).unwrap()) / (2.0 * eps);
            for i in 0..m.dim() {
                let scale = 1.0 + ev.jacobian[(i, k)].abs();
                worst = worst.max((fd[i] - ev.jacobian[(i, k)]).abs() / scale);
            }
        }
        assert!(worst < 1e-6, "{stiff:?}: worst FD mismatch {worst:e}");
    }
}

#[test]
fn explore() {
    let d = Stiffness::uniform(1.0);
    for &(eta, lbar) in &[(1u32, 1.2), (1, 1.4)] {
        let l = paper_branch_loop(eta, lbar).unwrap();
        let e_exact = l.energy().unwrap();
        for &n in &[64usize, 128, 256] {
            let t = std::time::Instant::now();
            let r = solve_branch(1.0, lbar, &d, &SurfaceSource::Exact(l), n, &EnclosedOptions::default());
            match r {
                Ok(b) => {
                    let c = b.fine.contact(1e-9).unwrap();
                    let opt = b.fine.optimality().unwrap();
                    println!(
                        "{:?} eta {eta} lbar {lbar} N {n}: E {:.12} exact-surface {:.12} diff {:.3e} est {:.1e} it {} res {:.1e} frac {:.3} runs {} gap {:?} lam {:?} opt {:?} {:?}",
                        b.fine.contact(1e-9).unwrap().runs,
                        b.energy, e_exact, b.energy - e_exact, b.energy_error, b.fine.iterations, b.fine.residual,
                        c.fraction, c.intervals, c.max_gap, l.lambda_range(), opt, t.elapsed()
                    );
                }
                Err(e) => println!("eta {eta} lbar {lbar} N {n}: {e}"),
            }
        }
    }
}

#[test]
fn explore_mid() {
    let d = Stiffness::uniform(1.0);
    let l = paper_branch_loop(1, 1.2).unwrap();
    for &n in &[64usize, 128, 256] {
        let b = solve_branch(1.0, 1.2, &d, &SurfaceSource::Exact(l), n, &EnclosedOptions::default()).unwrap();
        let st = &b.fine;
        let m = &st.model;
        let p = m.transforms(&st.z).unwrap();
        let r0 = m.start_point(&st.z);
        let mut worst: f64 = 0.0;
        let mut at = 0.0;
        for c in 0..m.cells() {
            let h = m.cell_length(c);
            for q in 1..8 {
                let f = q as f64 / 8.0;
                let sg = |o: f64| st.curvature_at(m.bounds()[c] + (m.bounds()[c + 1] - m.bounds()[c]) * f * o);
                let (a1, a2) = sg(rodloop_solver::model::GAUSS_OFFSETS[0]);
                let (b1, b2) = sg(rodloop_solver::model::GAUSS_OFFSETS[1]);
                let e = rodloop_solver::enclosed::jet::cell_exp(h * f, [a1, a2, b1, b2]);
                let pm = p[c] * e;
                let r = r0 + nalgebra::Vector3::new(pm[(0, 3)], pm[(1, 3)], pm[(2, 3)]);
                if r.norm() - 1.0 > worst {
                    worst = r.norm() - 1.0;
                    at = m.bounds()[c];
                }
            }
        }
        let lam = m.contact_force(&st.z);
        let lmax = lam.iter().cloned().fold(0.0, f64::max);
        println!("N {n}: E {:.12} max overshoot between nodes {worst:.3e} at {at}, max lambda density {lmax:.4}", b.energy);
    }
}
