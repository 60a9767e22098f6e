//! Branch 2 of a uniform rod in the ball below `L̄ = 1`: the lifted-off figure-eight touches
//! the wall at two points whose force falls to zero at the length where Euler's free
//! figure-eight elastica just fits in the ball, `L̄* = K(k)/(πk)` with `2E(k) = K(k)`; below
//! it the branch is that free elastica, `E R/(πD) = 16K²(k² − 1/2)/(π² L̄)`. Both are
//! computed here from the complete elliptic integrals (AGM), independently of the solver,
//! and the diagram's detachment is bracketed by independent 3-D solves started from the
//! exact elastica.

use std::f64::consts::PI;
use std::sync::OnceLock;

use rodloop_diagram::enclosed::{
    enclosed_diagram, EnclosedDiagram, EnclosedDiagramOptions, EventKind,
};
use rodloop_solver::enclosed::model::phase_slope;
use rodloop_solver::enclosed::solve::{least_squares_multipliers, start_from_curvature};
use rodloop_solver::enclosed::{solve_enclosed, EnclosedModel, EnclosedOptions, Gauge};
use rodloop_solver::Stiffness;

fn uniform() -> Stiffness {
    Stiffness::Uniform { d: 1.0 }
}

/// `(K(m), E(m))` by the arithmetic-geometric mean (A&S 17.6).
fn complete(m: f64) -> (f64, f64) {
    let (mut a, mut b) = (1.0f64, (1.0 - m).sqrt());
    let (mut s, mut p) = (0.5 * m, 0.5);
    for _ in 0..40 {
        let c = 0.5 * (a - b);
        (a, b) = (0.5 * (a + b), (a * b).sqrt());
        p *= 2.0;
        s += p * c * c;
    }
    let k = PI / (2.0 * a);
    (k, k * (1.0 - s))
}

/// `m = k²` of Euler's figure-eight (`2E(m) = K(m)`), by bisection.
fn figure_eight_m() -> f64 {
    let f = |m: f64| {
        let (k, e) = complete(m);
        2.0 * e - k
    };
    let (mut lo, mut hi) = (0.5, 0.99);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if f(lo) * f(mid) <= 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    0.5 * (lo + hi)
}

/// `(L̄*, E L̄)`: the length at which the free figure-eight's tips (distance `2kℓ` from its
/// crossing, `L = 4Kℓ`) reach the wall, and its energy times `L̄`.
fn free_figure_eight() -> (f64, f64) {
    let m = figure_eight_m();
    let (k, _) = complete(m);
    let lstar = k / (PI * m.sqrt());
    let el = 16.0 * k * k * (m - 0.5) / (PI * PI);
    (lstar, el)
}

/// Jacobi `cn(u | m)` by the descending AGM (A&S 16.4).
fn cn(u: f64, m: f64) -> f64 {
    let (mut a, mut b) = (1.0f64, (1.0 - m).sqrt());
    let mut ca = vec![];
    for _ in 0..30 {
        let c = 0.5 * (a - b);
        (a, b) = (0.5 * (a + b), (a * b).sqrt());
        ca.push(c / a);
    }
    let mut phi = 2f64.powi(ca.len() as i32) * a * u;
    for r in ca.iter().rev() {
        phi = 0.5 * (phi + (r * phi.sin()).asin());
    }
    phi.cos()
}

fn diagram() -> &'static EnclosedDiagram {
    static D: OnceLock<EnclosedDiagram> = OnceLock::new();
    D.get_or_init(|| {
        // Up to 1.6 so that the trace is seeded where the whole diagram's is (1.05).
        let mut o = EnclosedDiagramOptions::new(1.0, uniform(), 0.5, 1.6);
        o.branches = Some(vec![2]);
        enclosed_diagram(&o).expect("enclosed diagram of branch 2 on [0.5, 1.6]")
    })
}

#[test]
fn the_elliptic_helpers_are_right() {
    // K(1/2) and E(1/2) (A&S Table 17.1), and cn at the quarter period.
    let (k, e) = complete(0.5);
    assert!((k - 1.854_074_677_301_372).abs() < 1e-14, "{k}");
    assert!((e - 1.350_643_881_047_675).abs() < 1e-14, "{e}");
    let m = figure_eight_m();
    assert!(cn(complete(m).0, m).abs() < 1e-12);
    assert!((cn(0.0, m) - 1.0).abs() < 1e-15);
}

#[test]
fn branch_two_is_traced_without_warnings() {
    let d = diagram();
    assert!(d.warnings.is_empty(), "{:?}", d.warnings);
}

#[test]
fn branch_two_is_traced_down_through_its_detachment() {
    let d = diagram();
    // Warnings other than states left without a file (those: `branch_two_is_traced_without_warnings`).
    let other: Vec<_> = d
        .warnings
        .iter()
        .filter(|w| !w.starts_with("UNVERIFIED STATE LEFT WITHOUT A FILE"))
        .collect();
    assert!(other.is_empty(), "{other:?}");
    let (lstar, el) = free_figure_eight();
    let ev: Vec<_> = d
        .events
        .iter()
        .filter(|e| e.kind == EventKind::Detachment)
        .collect();
    assert_eq!(ev.len(), 1, "{:?}", d.events);
    let ev = ev[0];
    // The located point agrees with the exact one within its estimate, which is small.
    assert!(ev.error_estimate < 1e-6, "{ev:?}");
    assert!(
        (ev.lbar - lstar).abs() <= ev.error_estimate,
        "{ev:?} against {lstar}"
    );
    assert!((ev.energy - el / lstar).abs() < 1e-5, "{ev:?}");
    let b2: Vec<_> = d.points.iter().filter(|p| p.branch == 2).collect();
    assert!(
        b2.first().unwrap().lbar < 0.55 + 1e-9,
        "traced down to 0.55"
    );
    let mut free = 0;
    for p in &b2 {
        // First-order optimality everywhere.
        assert!(p.lambda_min >= -1e-8 && p.gap_min >= -1e-10, "{p:?}");
        assert!(p.complementarity <= 1e-9 && p.stationarity <= 1e-8, "{p:?}");
        if p.lbar < lstar {
            // Off the wall, and the free elastica's energy within the estimate.
            free += 1;
            assert_eq!(p.contact_fraction, 0.0, "{p:?}");
            assert!(p.gap_min > 1e-3, "{p:?}");
            let exact = el / p.lbar;
            assert!(
                (p.energy - exact).abs() <= p.energy_error,
                "{p:?} against {exact}"
            );
            assert!(p.energy_error < 2e-5 * exact, "{p:?}");
        } else {
            assert!(p.contact_fraction > 0.0, "{p:?}");
        }
    }
    assert!(free >= 6, "{free} free states");
}

/// The exact figure-eight of length `2πR L̄` as curvature vectors in the frame with the
/// tangent `e1` at the tip `s = 0` (bending towards `e2`, in the `e1 e2` plane), and the tip
/// at `−2kℓ e2` so that the crossing is at the centre.
fn elastica_start(lbar: f64) -> (impl Fn(f64) -> (f64, f64), [f64; 3]) {
    let m = figure_eight_m();
    let (kk, _) = complete(m);
    let len = 2.0 * PI * lbar;
    let ell = len / (4.0 * kk);
    let k = m.sqrt();
    let kappa = move |sigma: f64| (2.0 * k / ell * cn(sigma * len / ell, m), 0.0);
    (kappa, [0.0, -2.0 * k * ell, 0.0])
}

#[test]
fn independent_solves_bracket_the_detachment() {
    let ev = diagram()
        .events
        .iter()
        .find(|e| e.kind == EventKind::Detachment)
        .expect("a detachment")
        .clone();
    let (_, el) = free_figure_eight();
    let opts = EnclosedOptions::default();
    let n = 64;
    // Below: the free elastica with its start point pinned stays off the wall.
    let below = ev.lbar - 5e-3;
    let (kappa, r0) = elastica_start(below);
    let probe = EnclosedModel::new(
        1.0,
        below,
        n,
        &uniform(),
        Gauge {
            reference: vec![0.0; 4 * n],
            slope: None,
            pin: None,
        },
    )
    .unwrap();
    let reference = probe.sample_gauss(&kappa);
    let model = EnclosedModel::new(
        1.0,
        below,
        n,
        &uniform(),
        Gauge {
            slope: phase_slope(&reference, n).unwrap(),
            reference: reference.clone(),
            // The start point (a tip) pinned: the translations are symmetry modes here.
            pin: Some(r0),
        },
    )
    .unwrap();
    let mut z = vec![0.0; model.dim()];
    z[..4 * n].copy_from_slice(&reference);
    z[4 * n..4 * n + 3].copy_from_slice(&r0);
    // The tip (node 0) is pinned inside the wall here: 2kℓ < R below L̄*.
    assert!(r0[1].abs() < 1.0 - 1e-4);
    least_squares_multipliers(&model, &mut z).unwrap();
    // Off the wall: no wall force to start with.
    let lo = model.lambda_offset();
    z[lo..].iter_mut().for_each(|v| *v = 0.0);
    let st = solve_enclosed(&model, z, &opts).unwrap();
    let (lmin, gmin, comp, _) = st.optimality().unwrap();
    assert!(st.multipliers().iter().all(|&l| l == 0.0));
    assert!(gmin > 1e-3 && lmin >= 0.0 && comp == 0.0, "{gmin} {lmin}");
    assert!((st.energy() - el / below).abs() < 1e-5 * el / below);
    // Above: from the same elastica (its tips 0.6% outside the wall), unpinned, the loop is
    // held by two point contacts with positive force.
    let above = ev.lbar + 5e-3;
    let (kappa, r0) = elastica_start(above);
    assert!(r0[1].abs() > 1.0 + 1e-3);
    let (model, mut z) = start_from_curvature(1.0, above, n, &uniform(), kappa, r0).unwrap();
    // Wall impulses only at the two tips (nodes 0 and N/2), small and positive.
    let lo = model.lambda_offset();
    z[lo..].iter_mut().for_each(|v| *v = 0.0);
    z[lo] = 1e-2;
    z[lo + n / 2] = 1e-2;
    let st = solve_enclosed(&model, z, &opts).unwrap();
    let c = st.contact(1e-9).unwrap();
    let (lmin, gmin, comp, stat) = st.optimality().unwrap();
    assert!(lmin >= 0.0 && gmin >= -1e-12 && comp < 1e-10 && stat < 1e-8);
    assert_eq!(c.intervals, 2, "{c:?}");
    assert!(c.lambda_range.0 > 0.0, "{c:?}");
    // It lies above the free elastica's energy (the wall holds it).
    assert!(st.energy() > el / above, "{} {}", st.energy(), el / above);
}

/// The planar elastica held at its two tips by the wall, solved by shooting (independent of
/// the 3-D model): a quarter from the tip `(0, −R)` (tangent `e1`, curvature `κ0`) to the
/// crossing at the centre, where the curvature vanishes by symmetry, under a constant
/// internal force `(n_x, n_y)` (`D κ' = n_x sin θ − n_y cos θ`, `D = R = 1`), RK4 with 4000
/// steps. Returns `(E R/(πD), tip force 2|n_y|, sign of n_y)`; `n_y < 0` where the wall
/// pushes.
fn two_point_elastica(lbar: f64) -> (f64, f64, f64) {
    let m = figure_eight_m();
    let (kk, _) = complete(m);
    let len = 2.0 * PI * lbar;
    let quarter = len / 4.0;
    let ell = len / (4.0 * kk);
    let f = |u: [f64; 5], nx: f64, ny: f64| -> [f64; 5] {
        [
            u[1],
            nx * u[0].sin() - ny * u[0].cos(),
            u[0].cos(),
            u[0].sin(),
            u[1] * u[1],
        ]
    };
    let shoot = |p: [f64; 3]| -> [f64; 5] {
        let steps = 4000;
        let h = quarter / steps as f64;
        let mut u = [0.0, p[0], 0.0, -1.0, 0.0];
        for _ in 0..steps {
            let a = f(u, p[1], p[2]);
            let add = |u: [f64; 5], k: [f64; 5], c: f64| -> [f64; 5] {
                let mut o = u;
                for i in 0..5 {
                    o[i] += c * k[i];
                }
                o
            };
            let b = f(add(u, a, 0.5 * h), p[1], p[2]);
            let c = f(add(u, b, 0.5 * h), p[1], p[2]);
            let d = f(add(u, c, h), p[1], p[2]);
            for i in 0..5 {
                u[i] += h / 6.0 * (a[i] + 2.0 * b[i] + 2.0 * c[i] + d[i]);
            }
        }
        u
    };
    let k = m.sqrt();
    let mut p = [2.0 * k / ell, -1.0 / (ell * ell), 0.0];
    for _ in 0..30 {
        let u = shoot(p);
        let r = [u[2], u[3], u[1]];
        if r.iter().all(|v| v.abs() < 1e-12) {
            break;
        }
        let mut jac = nalgebra::Matrix3::zeros();
        for j in 0..3 {
            let mut q = p;
            let d = 1e-7 * q[j].abs().max(1.0);
            q[j] += d;
            let v = shoot(q);
            let g = [v[2], v[3], v[1]];
            for i in 0..3 {
                jac[(i, j)] = (g[i] - r[i]) / d;
            }
        }
        let dx = jac
            .lu()
            .solve(&nalgebra::Vector3::new(-r[0], -r[1], -r[2]))
            .expect("shooting Jacobian");
        for i in 0..3 {
            p[i] += dx[i];
        }
    }
    let u = shoot(p);
    assert!(u[2].abs() < 1e-10 && u[3].abs() < 1e-10 && u[1].abs() < 1e-10);
    (4.0 * 0.5 * u[4] / PI, 2.0 * p[2].abs(), p[2].signum())
}

#[test]
fn the_held_figure_eight_is_the_two_point_loaded_elastica() {
    let (lstar, el) = free_figure_eight();
    // Just below L̄* the exact elastica held at ±R would need a pulling wall; above, the wall
    // pushes: the sign change of the tip force is at L̄* (the free figure-eight's size).
    assert!(two_point_elastica(lstar - 1e-4).2 > 0.0);
    assert!(two_point_elastica(lstar + 1e-4).2 < 0.0);
    // Its energy tends to the free one at L̄*.
    let (e_star, p_star, _) = two_point_elastica(lstar + 1e-9);
    assert!(
        (e_star - el / lstar).abs() < 1e-7 && p_star < 1e-6,
        "{e_star} {p_star}"
    );
    // At L̄ = 0.825 (planar, held at its tips): the 3-D model at N = 64 and 128, started from
    // the free elastica at L̄* + 5e-3 (tips 0.6% outside) and stepped to 0.825 in steps of
    // 2.5e-3, against the shooting.
    let lbar = 0.825;
    let (e_ex, force_ex, _) = two_point_elastica(lbar);
    let opts = EnclosedOptions::default();
    let mut errs = Vec::new();
    let start = lstar + 5e-3;
    let (kappa, r0) = elastica_start(start);
    let n = 64;
    let (model, mut z) = start_from_curvature(1.0, start, n, &uniform(), kappa, r0).unwrap();
    let lo = model.lambda_offset();
    z[lo..].iter_mut().for_each(|v| *v = 0.0);
    z[lo] = 1e-2;
    z[lo + n / 2] = 1e-2;
    let coarse = solve_enclosed(&model, z, &opts).unwrap();
    // N = 128: the N = 64 state prolonged and re-solved.
    let (m2, z2) = coarse.refine().unwrap();
    let fine = solve_enclosed(&m2, z2, &opts).unwrap();
    for mut st in [coarse, fine] {
        let n = st.model.cells();
        // Stepped with the translations pinned (next to L̄* they are nearly free: the wall
        // holds them with a stiffness ∝ the vanishing tip force); the pin carries no force
        // (checked below), so these are the free problem's states.
        let mut x = start;
        while x < lbar - 1e-12 {
            x = (x + 2.5e-3).min(lbar);
            st = st.step_free(x, &opts).unwrap();
        }
        assert!(st.net_wall_force().unwrap() < 1e-8);
        let c = st.contact(1e-9).unwrap();
        assert_eq!(c.intervals, 2, "{c:?}");
        // The concentrated force at a tip: the impulse 2Rλ_j of the touching node.
        let lam = st.multipliers();
        let tip = 2.0 * lam.iter().fold(0.0f64, |a, &b| a.max(b));
        assert!(
            (tip - force_ex).abs() < 1e-3 * force_ex,
            "N = {n}: tip force {tip} against {force_ex}"
        );
        errs.push((st.energy() - e_ex).abs());
    }
    // Converging to the exact value: 2.7e-6 at N = 64 (fourth order would give 1.7e-7 at
    // N = 128).
    assert!(errs[0] < 1e-5 && errs[1] < 0.25 * errs[0], "{errs:?}");
}
