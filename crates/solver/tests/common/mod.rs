//! Helpers shared by the integration tests: comparison of a numerical equilibrium with the
//! exact homogeneous loop after aligning the arclength origin.

#![allow(dead_code)]

use rodloop_exact::ExactLoop;
use rodloop_solver::enclosed::{
    solve_branch, BranchSolve, EnclosedOptions, EnclosedState, SurfaceSource,
};
use rodloop_solver::periodic::TrigInterpolant;
use rodloop_solver::{solve, Equilibrium, SolveOptions, StartShape, Stiffness, SurfaceModel};

/// Errors of a numerical equilibrium against the exact loop (R = D = 1).
#[derive(Clone, Copy, Debug)]
pub struct Comparison {
    /// Arclength shift `δ` with numeric(s) ≈ exact(s − δ).
    pub shift: f64,
    /// `+1` or `−1`: the numeric loop is the exact one or its mirror image.
    pub mirror: f64,
    pub energy_rel: f64,
    pub energy_g_rel: f64,
    pub lambda_max_abs: f64,
    pub lambda_scale: f64,
    pub kappa_g: f64,
    pub tau: f64,
    pub f_t: f64,
    pub f_n: f64,
    pub f_b: f64,
    pub moment: f64,
    pub lambda_range: f64,
}

pub fn compare(eq: &Equilibrium, ex: &ExactLoop) -> Comparison {
    let prof = eq.profile();
    let len = eq.length();
    let eta = ex.eta as f64;
    let kg: Vec<f64> = prof.iter().map(|p| p.kappa_g).collect();
    let t = TrigInterpolant::new(&kg).unwrap();
    let (_, (smax, _)) = t.extrema(8 * kg.len());
    let best = [1.0f64, -1.0]
        .iter()
        .map(|&mirror| {
            // Exact κ_g = −2ck cn(cs): maximal at s = L/(2η), minimal at s = 0.
            let target = if mirror > 0.0 { len / (2.0 * eta) } else { 0.0 };
            let shift = smax * len - target;
            let err = prof
                .iter()
                .map(|p| {
                    let e = ex.point(p.s - shift).unwrap();
                    (p.kappa_g - mirror * e.kappa_g).abs()
                })
                .fold(0.0, f64::max);
            (mirror, shift, err)
        })
        .min_by(|a, b| a.2.total_cmp(&b.2))
        .unwrap();
    let (mirror, shift, kerr) = best;
    let mut c = Comparison {
        shift,
        mirror,
        energy_rel: 0.0,
        energy_g_rel: 0.0,
        lambda_max_abs: 0.0,
        lambda_scale: 0.0,
        kappa_g: kerr,
        tau: 0.0,
        f_t: 0.0,
        f_n: 0.0,
        f_b: 0.0,
        moment: 0.0,
        lambda_range: 0.0,
    };
    for p in &prof {
        let e = ex.point(p.s - shift).unwrap();
        c.lambda_max_abs = c.lambda_max_abs.max((p.lambda - e.lambda).abs());
        c.lambda_scale = c.lambda_scale.max(e.lambda.abs());
        c.tau = c.tau.max((p.tau - mirror * e.tau).abs());
        c.f_t = c.f_t.max((p.f_t - e.f_t).abs());
        c.f_n = c.f_n.max((p.f_n - e.f_n).abs());
        c.f_b = c.f_b.max((p.f_b - mirror * e.f_b).abs());
    }
    let en = eq.energy();
    let exact_e = ex.energy().unwrap();
    c.energy_rel = (en.total - exact_e).abs() / exact_e;
    c.energy_g_rel = (en.geodesic - ex.energy_g().unwrap()).abs() / ex.energy_g().unwrap();
    let m = eq.moment();
    let mnorm = (m[0] * m[0] + m[1] * m[1] + m[2] * m[2]).sqrt();
    c.moment = (mnorm - ex.conserved_moment()).abs();
    let (lo, hi) = eq.lambda_range();
    let (elo, ehi) = ex.lambda_range();
    c.lambda_range = (lo - elo).abs().max((hi - ehi).abs());
    c
}

/// Solve a homogeneous loop of branch `eta` at `lbar` with `cells` cells on the unit sphere.
pub fn solve_uniform(eta: u32, lbar: f64, cells: usize, start: &StartShape) -> Equilibrium {
    let model = SurfaceModel::new(1.0, lbar, cells, &Stiffness::uniform(1.0)).unwrap();
    let k0 = start.gauss_values(&model).unwrap();
    solve(&model, &k0, &SolveOptions::default())
        .unwrap_or_else(|e| panic!("eta {eta} lbar {lbar} cells {cells}: {e}"))
}

/// The uniform rod's enclosed state of the surface branch `eta` at `lbar` on `cells` cells,
/// from the exact surface loop (R = D = 1).
pub fn enclosed_branch(eta: u32, lbar: f64, cells: usize) -> BranchSolve {
    let l = rodloop_exact::paper_branch_loop(eta, lbar).unwrap();
    solve_branch(
        1.0,
        lbar,
        &Stiffness::uniform(1.0),
        &SurfaceSource::Exact(l),
        cells,
        &EnclosedOptions::default(),
    )
    .unwrap()
}

/// The uniform rod's lifted-off figure-eight (branch 2) at `lbar` on `cells` cells.
pub fn enclosed_figure_eight(lbar: f64, cells: usize) -> EnclosedState {
    enclosed_branch(1, lbar, cells).fine
}

/// Small deterministic pseudo-random numbers in [-1, 1].
pub fn lcg(seed: &mut u64) -> f64 {
    *seed = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    ((*seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
}

/// The two-segment stiffness of the enclosed model's tests (Eq. (51), `D1/D0 = 0.5`,
/// `s0* = 0.3`, `s1* = 0.8`, mild transitions `γ = 10`).
pub fn mild_two_segment() -> Stiffness {
    Stiffness::Tanh {
        d0: 1.0,
        d1: 0.5,
        s0: 0.3,
        s1: 0.8,
        gamma: 10.0,
    }
}
