//! The enclosed model (`|r| ≤ R`, paper Sec. 3.2): exact derivatives, exact states, lift-off,
//! optimality and the order of convergence.

mod common;

use rodloop_exact::paper_branch_loop;
use rodloop_solver::enclosed::{start_from_surface, EnclosedModel, EnclosedOptions};
use rodloop_solver::Stiffness;

fn exact_start(eta: u32, lbar: f64, cells: usize, d: &Stiffness) -> (EnclosedModel, Vec<f64>) {
    let l = paper_branch_loop(eta, lbar).unwrap();
    start_from_surface(1.0, lbar, cells, d, |s| {
        l.point(s * l.length()).unwrap().kappa_g
    })
    .unwrap()
}

/// The semismooth Jacobian against central differences of the residual, at a perturbed
/// state with mixed contact rows (both branches of the min-function), uniform and Eq. (51),
/// with the physical wall and with the pull homotopy's wall (`pull = 0.7`).
#[test]
fn jacobian_matches_finite_differences() {
    for (stiff, pull) in [
        (Stiffness::uniform(1.0), 0.0),
        (Stiffness::uniform(1.0), 0.7),
        (common::mild_two_segment(), 0.0),
    ] {
        let (m, mut z) = exact_start(1, 1.5, 10, &stiff);
        let m = m.with_pull(pull).unwrap();
        // Perturb everything, make some multipliers clearly positive/negative.
        for (i, v) in z.iter_mut().enumerate() {
            *v += 0.01 * ((i as f64 * 1.7).sin());
        }
        let lo = m.lambda_offset();
        for j in 0..m.cells() {
            z[lo + j] = if j % 3 == 0 {
                -0.05
            } else {
                0.3 + 0.01 * j as f64
            };
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

/// The `O(N)` Newton step of the lifted block-tridiagonal system (`enclosed::lifted`) is the
/// dense semismooth Newton step `J dz = −F` (the `J` checked above against finite
/// differences): perturbed states with mixed contact rows, uniform and Eq. (51) stiffness,
/// the pull homotopy's wall, and the free circle's pinned start point.
#[test]
fn lifted_step_equals_dense_step() {
    let tanh = common::mild_two_segment();
    let mut cases = Vec::new();
    for (stiff, pull, cells) in [
        (Stiffness::uniform(1.0), 0.0, 12),
        (Stiffness::uniform(1.0), 0.7, 16),
        (tanh, 0.0, 20),
    ] {
        let (m, z) = exact_start(1, 1.5, cells, &stiff);
        cases.push((m.with_pull(pull).unwrap(), z, true));
    }
    let d = Stiffness::uniform(1.0);
    let (m, z) = rodloop_solver::enclosed::free_circle(1.0, 0.8, 16, &d).unwrap();
    cases.push((m, z, false));
    for (m, mut z, mixed) in cases {
        for (i, v) in z.iter_mut().enumerate() {
            *v += 0.01 * ((i as f64 * 1.7).sin());
        }
        if mixed {
            let lo = m.lambda_offset();
            for j in 0..m.cells() {
                z[lo + j] = if j % 3 == 0 {
                    -0.05
                } else {
                    0.3 + 0.01 * j as f64
                };
            }
        }
        let ev = m.evaluate(&z).unwrap();
        let dense = ev.jacobian.clone().lu().solve(&(-&ev.residual)).unwrap();
        let (f, step) = m.newton_step(&z).unwrap();
        assert!((&f - &ev.residual).amax() < 1e-13 * (1.0 + f.amax()));
        let err = (&step - &dense).amax() / dense.amax();
        assert!(
            err < 1e-9,
            "cells {}: lifted vs dense step {err:e}",
            m.cells()
        );
    }
}

fn branch(eta: u32, lbar: f64, cells: usize) -> rodloop_solver::enclosed::BranchSolve {
    common::enclosed_branch(eta, lbar, cells)
}

/// First-order optimality of a returned state: λ ≥ 0, gap ≥ 0, λ·gap = 0, stationarity.
fn assert_optimal(st: &rodloop_solver::enclosed::EnclosedState) {
    let (lmin, gmin, comp, stat) = st.optimality().unwrap();
    assert!(lmin >= -1e-10, "lambda_min {lmin}");
    assert!(gmin >= -1e-10, "gap_min {gmin}");
    assert!(comp <= 1e-9, "complementarity {comp}");
    assert!(stat <= 1e-8, "stationarity {stat}");
}

/// Where the exact surface loop has λ > 0 everywhere (branch 1 at L̄ = 1.2, branch 3 at
/// L̄ = 2.5; Eq. (38): λ_min = c²(1 − 2k²) > 0), the enclosed solve stays on the wall and
/// its energy is the exact layer's within the error estimate; it converges at fourth order.
#[test]
fn attached_loops_are_the_surface_loops() {
    for &(eta, lbar) in &[(2u32, 1.2), (3, 2.5)] {
        let exact = paper_branch_loop(eta, lbar).unwrap();
        assert!(exact.lambda_range().0 > 0.0);
        let e = exact.energy().unwrap();
        let b = branch(eta, lbar, 96);
        let c = b.fine.contact(1e-9).unwrap();
        assert_eq!(c.fraction, 1.0, "eta {eta}");
        assert!(c.max_gap.0.abs() < 1e-12);
        let err = (b.energy - e).abs();
        assert!(
            err <= 2.0 * b.energy_error + 1e-13,
            "eta {eta}: {err:e} vs {:e}",
            b.energy_error
        );
        // Measured order from N = 24, 48, 96 against the exact energy.
        let e48 = (b.coarse.energy() - e).abs();
        let order = (e48 / err).log2();
        assert!((order - 4.0).abs() < 0.3, "eta {eta}: order {order}");
        assert_optimal(&b.fine);
        // The contact force density reproduces Eq. (38) at the nodes.
        let lam = b.fine.model.contact_force(&b.fine.z);
        let (lo, hi) = exact.lambda_range();
        for v in lam {
            assert!(v > lo - 1e-2 && v < hi + 1e-2, "{v} outside [{lo}, {hi}]");
        }
    }
}

/// L̄ < 1: the free planar circle, E R/(πD) = 1/L̄ (exact in the discrete model), no contact.
#[test]
fn free_circle_below_one() {
    let d = Stiffness::uniform(1.0);
    let (m, z) = rodloop_solver::enclosed::free_circle(1.0, 0.7, 32, &d).unwrap();
    let st = rodloop_solver::enclosed::solve_enclosed(&m, z, &EnclosedOptions::default()).unwrap();
    assert!((st.energy() - 1.0 / 0.7).abs() < 1e-12);
    let c = st.contact(1e-9).unwrap();
    assert_eq!(c.intervals, 0);
    assert!((c.max_gap.0 - 0.3).abs() < 1e-12);
    assert_optimal(&st);
    assert_eq!(st.stability(1e-6).unwrap().0, 0);
}

/// Branch 2 (figure-eight) at L̄ = 1.4 needs λ < 0 on the surface: the enclosed loop lifts
/// off there, its energy is lower, the optimality conditions hold, and the energy converges
/// at fourth order over N = 64, 128, 256 and ≈ 2.6 over 128, 256, 512.
#[test]
fn figure_eight_lifts_off_with_lower_energy() {
    let exact = paper_branch_loop(1, 1.4).unwrap();
    assert!(exact.lambda_range().0 < 0.0);
    let b = branch(1, 1.4, 128);
    let c = b.fine.contact(1e-9).unwrap();
    assert!(c.max_gap.0 > 1e-3, "max gap {}", c.max_gap.0);
    assert!(c.fraction < 1.0 && c.intervals == 2, "{c:?}");
    let drop = exact.energy().unwrap() - b.energy;
    assert!(
        drop > 100.0 * b.energy_error && drop > 1e-5,
        "drop {drop:e}"
    );
    assert_optimal(&b.fine);
    assert_optimal(&b.coarse);
    // The contact ends fall between nodes: the order approaches 4 from below (3.06 over
    // N = 32, 64, 128; 3.87 over 64, 128, 256).
    let b256 = branch(1, 1.4, 256);
    let (e64, e128, e256) = (b.coarse.energy(), b.energy, b256.energy);
    assert!((b256.coarse.energy() - e128).abs() < 1e-10);
    let order = ((e128 - e64).abs() / (e256 - e128).abs()).log2();
    assert!(order > 3.5 && order < 4.5, "order {order}");
    // The reported estimates bound the errors against N = 256 (plus its own estimate) at
    // N = 64 (default accuracy) and N = 128 (high).
    let b64 = branch(1, 1.4, 64);
    for (e, est) in [(b64.energy, b64.energy_error), (b.energy, b.energy_error)] {
        let err = (e - e256).abs() + b256.energy_error;
        assert!(est >= 0.9 * err, "estimate {est:e} vs error {err:e}");
    }
    // With the O(N) step, N = 512 and 1024 are affordable: the order over 128, 256, 512
    // falls to ≈ 2.6. From N = 256 on the cascade has a fourth level (N/8) and the
    // estimate takes the smaller of the two observed orders and the larger of the last two
    // differences' estimates: at N = 256 (default accuracy) and 512 (high) it bounds the
    // error against N = 1024; the true error at N = 256 is below 1e-8 relative.
    let b512 = branch(1, 1.4, 512);
    let b1024 = branch(1, 1.4, 1024);
    let order = ((e256 - e128).abs() / (b512.energy - e256).abs()).log2();
    assert!(order > 2.0 && order < 3.5, "order {order}");
    assert!(b256.eighth.is_some() && !b256.point_contact);
    for b in [&b256, &b512] {
        let err = (b.energy - b1024.energy).abs();
        assert!(
            b.energy_error >= err,
            "N = {}: {:e} vs {err:e}",
            b.fine.model.cells(),
            b.energy_error
        );
    }
    assert!((e256 - b1024.energy).abs() < 1e-8 * e256);
    assert!(b512.energy_error < 1e-9 * e256);
    // At N = 512 Newton stops at its round-off floor (scaled residual ≈ 1.4e-9), where the
    // wall rows hold to ≈ 2e-9 R: looser bounds than `assert_optimal`'s.
    let (lmin, gmin, comp, stat) = b512.fine.optimality().unwrap();
    assert!(lmin >= -1e-8 && gmin >= -1e-8 && comp <= 1e-8 && stat <= 1e-7);
}

/// Point-like contact: at L̄ = 1.2 the enclosed figure-eight touches the wall near its
/// two lobe tips only (runs of at most 4 cells), at two points 0.007 L apart at each. On
/// the uniform mesh the energy converges irregularly there (errors of 1.1e-6, 3.9e-7,
/// 3.7e-9 relative at N = 64, 128, 256). With a node at every contact point
/// ([`rodloop_solver::enclosed::centre`]) the same ladder converges at fourth order, and
/// the node-centred N = 1024 ladder is the reference: every reported estimate from N = 64
/// to 512 bounds the error against it (the order-1 rule alone was 1.17× short at N = 128).
#[test]
fn point_contact_estimate_bounds_the_error() {
    use rodloop_solver::enclosed::centre::centre_levels;
    let b256 = branch(1, 1.2, 256);
    let c = b256.fine.contact(1e-9).unwrap();
    assert_eq!(c.intervals, 2, "{c:?}");
    assert!(b256.point_contact && b256.order == 1.0, "{c:?}");
    assert_optimal(&b256.fine);
    let b512 = branch(1, 1.2, 512);
    let b1024 = branch(1, 1.2, 1024);
    assert!(b1024.point_contact);
    let (e_ref, de_ref) = b1024.centred_energy.expect("contacts on nodes at N = 1024");
    assert!(de_ref < 1e-10 * e_ref, "{de_ref:e}");
    for b in [branch(1, 1.2, 64), branch(1, 1.2, 128), b256, b512.clone()] {
        let err = (b.energy - e_ref).abs() + de_ref;
        assert!(
            b.energy_error >= err,
            "N = {}: {:e} vs {err:e}",
            b.fine.model.cells(),
            b.energy_error
        );
    }
    // The node-centred ladder N = 64 … 512 converges at fourth order, to the reference.
    let levels = [
        b512.eighth.as_ref().unwrap(),
        &b512.quarter,
        &b512.coarse,
        &b512.fine,
    ];
    let centred = centre_levels(&levels, &EnclosedOptions::default()).expect("centred");
    let e: Vec<f64> = centred.iter().map(|s| s.energy()).collect();
    for k in 0..2 {
        let order = ((e[k + 1] - e[k]) / (e[k + 2] - e[k + 1])).log2();
        assert!((order - 4.0).abs() < 0.3, "order {order} from {e:?}");
    }
    assert!((e[3] - e_ref).abs() < 1e-9 * e_ref, "{} vs {e_ref}", e[3]);
    for s in &centred {
        assert_optimal(s);
    }
    // Extended contact is not point-like (L̄ = 1.4: two arcs over 40% of the length).
    assert!(!branch(1, 1.4, 256).point_contact);
}

/// The four-level estimate: exact on `E + C N^{−p}` for `1 ≤ p ≤ max_order`; a lucky small
/// last difference (errors `+1, −0.02, +0.01` in units of the truth's scale) does not make
/// it smaller than the error.
#[test]
fn four_level_estimate_is_exact_on_power_laws_and_guards_lucky_differences() {
    use rodloop_solver::enclosed::four_level_estimate;
    for &p in &[1.0, 2.0, 2.5] {
        let e = |n: f64| 3.0 + 0.7 * n.powf(-p);
        let (err, order) = four_level_estimate([e(32.0), e(64.0), e(128.0), e(256.0)], 2.5);
        assert!((order - p).abs() < 1e-6, "p {p}: {order}");
        let truth = e(256.0) - 3.0;
        assert!(
            (err - truth).abs() < 1e-6 * truth,
            "p {p}: {err} vs {truth}"
        );
    }
    // Errors 1e-6 · (8, 1, −0.02, 0.01): the last two levels err alike, the last
    // difference is 3e-8, the three-level rule would give 3e-8/(2^2.5 − 1) = 6.4e-9 < 1e-8.
    let e = [3.0 + 8e-6, 3.0 + 1e-6, 3.0 - 2e-8, 3.0 + 1e-8];
    let (err, order) = four_level_estimate(e, 2.5);
    assert_eq!(order, 2.5);
    assert!(err >= 1e-8, "{err:e}");
}

/// The lift-off and landing lengths are where Eq. (38)'s λ_min = c²(1 − 2k²) vanishes.
#[test]
fn detached_interval_ends_have_zero_lambda_min() {
    let iv = rodloop_solver::enclosed::detached_intervals(1, 1.0, 3.0).unwrap();
    assert_eq!(iv.len(), 1);
    let (a, b) = iv[0];
    assert_eq!(a, 1.0);
    let l = paper_branch_loop(1, b).unwrap();
    assert!(l.lambda_range().0.abs() < 1e-10, "{}", l.lambda_range().0);
    assert!(paper_branch_loop(1, b - 1e-6).unwrap().lambda_range().0 < 0.0);
    assert!(paper_branch_loop(1, b + 1e-6).unwrap().lambda_range().0 > 0.0);
    for eta in [2, 3] {
        assert!(rodloop_solver::enclosed::detached_intervals(eta, 1.0, 3.0)
            .unwrap()
            .is_empty());
    }
}

/// The intervals from the closure at `k² = 1/2` are those where the branch's own `k²`
/// (`paper_branch_loop`, a root search in `k²` at each length) exceeds `1/2`: for
/// `η = 1 … 5` over each branch's whole range, every end is a sign change of `k²(L̄) − 1/2`
/// within `10⁻¹⁰` (`k²` on both sides) and, on a grid of 2000 lengths, a length lies in an
/// interval exactly where `k² > 1/2`.
#[test]
fn detached_intervals_are_where_the_branch_modulus_exceeds_one_half() {
    for eta in 1u32..=5 {
        let e = f64::from(eta);
        let iv = rodloop_solver::enclosed::detached_intervals(eta, e - 1.0, e + 1.0).unwrap();
        let m = |l: f64| paper_branch_loop(eta, l).unwrap().m;
        for &(a, b) in &iv {
            assert!(a < b, "eta {eta}: {iv:?}");
            for end in [a, b] {
                if end > e - 1.0 + 1e-6 && end < e + 1.0 - 1e-6 {
                    let (lo, hi) = (m(end - 1e-10), m(end + 1e-10));
                    assert!(
                        (lo - 0.5) * (hi - 0.5) <= 0.0,
                        "eta {eta}: k² = {lo}, {hi} about the end {end}"
                    );
                }
            }
        }
        for i in 1..2000 {
            let l = e - 1.0 + 2.0 * i as f64 / 2000.0;
            let inside = iv.iter().any(|&(a, b)| a < l && l < b);
            let mk = m(l);
            if (mk - 0.5).abs() > 1e-9 {
                assert_eq!(inside, mk > 0.5, "eta {eta} at {l}: k² = {mk}, {iv:?}");
            }
        }
    }
}

/// The three-level estimate on model sequences `E_N = E + C N^{−p}`: it recovers `p` and
/// the error of the finest level exactly for `1 ≤ p ≤ 4`, and clamps outside.
#[test]
fn three_level_estimate_is_exact_on_power_laws() {
    use rodloop_solver::enclosed::three_level_estimate;
    for &p in &[1.0, 2.5, 4.0] {
        let e = |n: f64| 3.0 + 0.7 * n.powf(-p);
        let (err, order) = three_level_estimate(e(16.0), e(32.0), e(64.0), 4.0);
        assert!((order - p).abs() < 1e-6, "p {p}: {order}");
        let truth = (e(64.0) - 3.0).abs();
        // (round-off: the differences of E_N cancel 3.0 to ~1e-8 relative)
        assert!(
            (err - truth).abs() < 1e-6 * truth,
            "p {p}: {err} vs {truth}"
        );
    }
    // Faster than fourth order: clamped to 4, so the estimate exceeds the true error.
    let e = |n: f64| 3.0 + 0.7 * n.powf(-6.0);
    let (err, order) = three_level_estimate(e(16.0), e(32.0), e(64.0), 4.0);
    assert_eq!(order, 4.0);
    assert!(err > (e(64.0) - 3.0).abs());
    // A cap of 3 on a fourth-order sequence overestimates.
    let e = |n: f64| 3.0 + 0.7 * n.powf(-4.0);
    let (err, order) = three_level_estimate(e(16.0), e(32.0), e(64.0), 3.0);
    assert_eq!(order, 3.0);
    assert!(err > (e(64.0) - 3.0).abs());
}

/// The interpolated curvature of a state whose frame comes back turned about the tangent
/// (`EnclosedState::curvature_at`, the start of every finer level) is as accurate next to
/// the closing node as elsewhere: the two-segment rod of Eq. (51) (`D1/D0 = 0.5`, `γ = 200`)
/// at `L̄ = 1.35`, branch 2 lifted off (the lowest state of the stiffness path), holonomy
/// about 1 rad, at 24 cells, against the same state solved at 48 cells. Components of the
/// other lap enter the stencil turned by the holonomy; taken as they are, the Gauss points
/// next to the closing node would be off by `O(α |κ|)`.
#[test]
fn curvature_is_interpolated_across_the_closing_node_with_the_holonomy() {
    use rodloop_solver::enclosed::descent::stiffness_homotopy_states;
    use rodloop_solver::enclosed::solve_enclosed;
    let st = Stiffness::paper_sec5(0.5);
    let (lbar, eta) = (1.35, 1u32);
    let opts = EnclosedOptions::default();
    let coarse = stiffness_homotopy_states(1.0, lbar, eta, &st, 24, &opts)
        .unwrap()
        .into_iter()
        .next()
        .expect("a state from the stiffness path");
    let p = coarse.model.transforms(&coarse.z).unwrap();
    let x = &p[coarse.model.cells()];
    let alpha = (x[(2, 1)] - x[(1, 2)]).atan2(x[(1, 1)] + x[(2, 2)]);
    assert!(alpha.abs() > 0.5, "holonomy {alpha}");
    let (m2, z2) = coarse.refine().unwrap();
    let fine = solve_enclosed(&m2, z2, &opts).unwrap();
    assert!((fine.energy() - coarse.energy()).abs() < 1e-2 * coarse.energy());
    // Interpolation error at the fine Gauss points: the four next to the closing node
    // against the largest of all others.
    let ng = 2 * fine.model.cells();
    let err = |g: usize| {
        let (k1, k2) = coarse.curvature_at(fine.model.gauss_sigma(g));
        (k1 - fine.z[2 * g]).hypot(k2 - fine.z[2 * g + 1])
    };
    let near = [0, 1, ng - 2, ng - 1];
    let at_seam = near.iter().map(|&g| err(g)).fold(0.0, f64::max);
    let elsewhere = (0..ng)
        .filter(|g| !near.contains(g))
        .map(err)
        .fold(0.0, f64::max);
    assert!(
        at_seam <= elsewhere,
        "next to the closing node {at_seam:.3e}, elsewhere at most {elsewhere:.3e}"
    );
}

/// The prolongation inside the contact runs (`EnclosedState::refine_in_runs`) carries a
/// lifted-off two-segment figure-eight (Eq. (51), `D1/D0 = 0.5`, `γ = 200`, `L̄ = 1.358`,
/// branch 2 from the stiffness path on 32 cells) up a ladder to 1024 cells: every level
/// converges, the energy differences fall at every doubling (the ladder converges), and
/// each level's contact lies within the next coarser one's runs widened by one of its cells
/// (the runs shrink onto the contact arcs, the property the prolongation rests on).
#[test]
fn the_prolongation_inside_the_runs_climbs_a_ladder_of_meshes() {
    use rodloop_solver::enclosed::descent::stiffness_path_from_shift;
    use rodloop_solver::enclosed::solve_enclosed;
    let st = Stiffness::paper_sec5(0.5);
    let opts = EnclosedOptions::default();
    let wd = EnclosedOptions {
        watchdog: 2,
        ..opts.clone()
    };
    let mut level = stiffness_path_from_shift(1.0, 1.358, 1, &st, 32, &opts, 0.2)
        .unwrap()
        .expect("a state from the stiffness path");
    let mut energies = vec![level.energy()];
    while level.model.cells() < 1024 {
        let (m, z) = level.refine_in_runs().unwrap();
        let next = solve_enclosed(&m, z.clone(), &wd)
            .or_else(|_| solve_enclosed(&m, z, &opts))
            .unwrap_or_else(|e| panic!("{} cells: {e}", m.cells()));
        // Node 2j of the finer mesh is node j of the coarser one.
        let n = level.model.cells();
        let (lc, lf) = (level.model.lambda_offset(), next.model.lambda_offset());
        let coarse_on = |j: usize| level.z[lc + j % n] > 0.0;
        for k in 0..2 * n {
            if next.z[lf + k] > 0.0 {
                let j = k / 2;
                let near =
                    coarse_on(j) || coarse_on(j + 1) || coarse_on(j + n - 1) || coarse_on(j + 2);
                assert!(near, "{} cells: node {k} touches outside the runs", 2 * n);
            }
        }
        energies.push(next.energy());
        level = next;
    }
    let d: Vec<f64> = energies.windows(2).map(|w| (w[1] - w[0]).abs()).collect();
    for w in d.windows(2) {
        assert!(w[1] < 0.5 * w[0], "differences {d:?}");
    }
}
