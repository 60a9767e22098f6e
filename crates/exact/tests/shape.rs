//! Shape descriptors of loops (point group, self-intersections): the paper's groups and
//! crossing counts for the exact branches (Sec. 3.1), invariance under rotation and
//! re-parametrisation, loss of symmetry under a generic perturbation, curves with known
//! crossings, and stability of the answers over a decade of tolerance.

use std::f64::consts::{PI, TAU};

use nalgebra::{Rotation3, Vector3};
use rodloop_exact::shape::{exact_loop_shape, loop_shape, SampledLoop, ShapeTolerances};
use rodloop_exact::topology::self_contacts;
use rodloop_exact::{paper_branch_loop, LoopShape};

/// A loop sampled at `n` points from arclength `s0`, moved by `f` (positions only).
fn sampled(
    eta: u32,
    lbar: f64,
    n: usize,
    s0: f64,
    f: impl Fn(Vector3<f64>, f64) -> Vector3<f64>,
    tol: ShapeTolerances,
) -> LoopShape {
    let lp = paper_branch_loop(eta, lbar).unwrap();
    let len = lp.length();
    let pts: Vec<_> = (0..n)
        .map(|i| lp.point(s0 + len * i as f64 / n as f64).unwrap())
        .collect();
    let s: Vec<f64> = pts.iter().map(|p| p.s).collect();
    let r: Vec<Vector3<f64>> = pts
        .iter()
        .map(|p| f(Vector3::new(p.x, p.y, p.z), p.s))
        .collect();
    let kg: Vec<f64> = pts.iter().map(|p| p.kappa_g).collect();
    on_unit_sphere(len, &s, &r, &kg, tol)
}

/// Sec. 3.1: branch 1 D2d (saddle), branch 2 C2v (figure-eight), branch 3 D3h, branch 4
/// D4d; self-intersections (Sec. 3.1, Fig. 2): none for the saddle, one for the
/// figure-eight, three for branch 3 below L̄_4cr ≈ 2.426, four for branch 1 beyond it.
#[test]
fn exact_branches_have_the_papers_groups_and_crossings() {
    let tol = ShapeTolerances::default();
    for (eta, lbar, group, order, crossings) in [
        (2, 1.2, "D2d", 8, Some(0)),
        (2, 2.6, "D2d", 8, Some(4)),
        (2, 2.8, "D2d", 8, Some(4)),
        (1, 1.7, "C2v", 4, Some(1)),
        (1, 1.3, "C2v", 4, Some(1)),
        (3, 2.2, "D3h", 12, Some(3)),
        (3, 2.4, "D3h", 12, Some(3)),
        (3, 3.5, "D3h", 12, None),
        (4, 3.5, "D4d", 16, None),
    ] {
        let lp = paper_branch_loop(eta, lbar).unwrap();
        let sh = exact_loop_shape(&lp, tol).unwrap();
        eprintln!(
            "eta {eta} lbar {lbar}: {} (order {:?}, residual {:.1e}), {:?} crossings",
            sh.point_group, sh.group_order, sh.symmetry_residual, sh.self_intersections
        );
        assert_eq!(sh.point_group, group, "eta {eta} lbar {lbar}");
        assert_eq!(sh.group_order, Some(order), "eta {eta} lbar {lbar}");
        assert!(sh.symmetry_residual < 1e-4, "{}", sh.symmetry_residual);
        // Where the paper gives no count, an independent one: the stereographic projection
        // is one-to-one on the sphere, so the loop's self-intersections are the crossings of
        // its image in the plane, counted here by brute force on 4000 points.
        let want = crossings.unwrap_or_else(|| stereographic_crossings(&lp));
        assert_eq!(sh.self_intersections, Some(want), "eta {eta} lbar {lbar}");
    }
}

/// Crossings of the stereographic image (from the point of the sphere farthest from the
/// loop's samples) of an exact loop, by testing every pair of segments.
fn stereographic_crossings(lp: &rodloop_exact::ExactLoop) -> usize {
    let n = 4000;
    let p: Vec<Vector3<f64>> = lp
        .sample(n)
        .unwrap()
        .iter()
        .map(|q| Vector3::new(q.x, q.y, q.z))
        .collect();
    // Projection centre: among a few candidate directions, the one farthest from the loop.
    let pole = [
        Vector3::x(),
        -Vector3::x(),
        Vector3::y(),
        -Vector3::y(),
        Vector3::z(),
        -Vector3::z(),
        Vector3::new(1.0, 1.0, 1.0).normalize(),
        Vector3::new(-1.0, 1.0, -1.0).normalize(),
    ]
    .into_iter()
    .max_by(|a, b| {
        let d = |c: &Vector3<f64>| p.iter().map(|q| (q - c).norm()).fold(f64::MAX, f64::min);
        d(a).total_cmp(&d(b))
    })
    .unwrap();
    // Orthonormal frame (e1, e2) of the plane through the centre perpendicular to the pole.
    let e1 = pole.cross(&Vector3::new(0.36, 0.48, 0.8)).normalize();
    let e2 = pole.cross(&e1);
    let uv: Vec<(f64, f64)> = p
        .iter()
        .map(|q| {
            let w = 1.0 / (1.0 - q.dot(&pole));
            (q.dot(&e1) * w, q.dot(&e2) * w)
        })
        .collect();
    let cross = |a: (f64, f64), b: (f64, f64)| a.0 * b.1 - a.1 * b.0;
    let mut count = 0;
    for i in 0..n {
        for j in i + 2..n {
            if i == 0 && j == n - 1 {
                continue;
            }
            let (a, b) = (uv[i], uv[(i + 1) % n]);
            let (c, d) = (uv[j], uv[(j + 1) % n]);
            let r = (b.0 - a.0, b.1 - a.1);
            let s = (d.0 - c.0, d.1 - c.1);
            let den = cross(r, s);
            if den == 0.0 {
                continue;
            }
            let q = (c.0 - a.0, c.1 - a.1);
            let t = cross(q, s) / den;
            let u = cross(q, r) / den;
            if (0.0..1.0).contains(&t) && (0.0..1.0).contains(&u) {
                count += 1;
            }
        }
    }
    count
}

/// The answer does not depend on where the sampling starts, on how many points there are
/// (no multiple of 4η needed), or on a rotation of the loop about the sphere's centre.
#[test]
fn group_is_invariant_under_rotation_and_resampling() {
    let tol = ShapeTolerances::default();
    let rot = Rotation3::from_axis_angle(
        &nalgebra::Unit::new_normalize(Vector3::new(0.3, -0.5, 0.8)),
        1.1,
    );
    for (eta, lbar, group) in [(2, 1.2, "D2d"), (1, 1.6, "C2v"), (3, 2.4, "D3h")] {
        for (n, s0) in [(301, 0.123), (517, 1.0), (1000, -0.7)] {
            let sh = sampled(eta, lbar, n, s0, |p, _| rot * p, tol);
            assert_eq!(sh.point_group, group, "eta {eta} n {n} s0 {s0}");
        }
    }
}

/// A generic smooth perturbation (kept on the sphere) lowers the group to C1; a perturbation
/// that keeps one mirror plane leaves Cs.
#[test]
fn perturbations_lower_the_group() {
    let tol = ShapeTolerances::default();
    // A bump of 0.02 R near one point of the saddle, pushed along a fixed direction.
    let lp = paper_branch_loop(2, 1.2).unwrap();
    let centre = lp.point(0.37).unwrap();
    let c = Vector3::new(centre.x, centre.y, centre.z);
    let bump = |p: Vector3<f64>, _s: f64| {
        let w = (-(p - c).norm_squared() / 0.1).exp();
        (p + Vector3::new(0.3, 0.7, -0.2) * (0.02 * w)).normalize()
    };
    let sh = sampled(2, 1.2, 400, 0.0, bump, tol);
    assert_eq!(sh.point_group, "C1");
    // Scaling y by 1.03 (then back onto the sphere) breaks every element that swaps the x
    // and y directions: of the saddle's D2d (S4 axis along the moment axis z, Eq. 45), the
    // two S4 and either the two diagonal C2 or the two diagonal mirrors go, leaving a group
    // of order 4 (D2 or C2v, depending on how the loop's phase places its C2 axes).
    let squeeze = |p: Vector3<f64>, _s: f64| Vector3::new(p.x, 1.03 * p.y, p.z).normalize();
    let sh = sampled(2, 1.2, 400, 0.0, squeeze, tol);
    assert!(
        sh.point_group == "C2v" || sh.point_group == "D2",
        "a squeezed saddle is a subgroup of D2d of order 4, got {}",
        sh.point_group
    );
    assert_eq!(sh.group_order, Some(4));
}

/// Over a decade of tolerance on either side of the default the groups and the counts stay
/// the same.
#[test]
fn descriptors_are_stable_over_a_decade_of_tolerance() {
    for (eta, lbar) in [(2, 1.2), (1, 1.6), (3, 2.2), (2, 2.6), (4, 3.3)] {
        let lp = paper_branch_loop(eta, lbar).unwrap();
        let answers: Vec<(String, Option<usize>)> = [1e-4, 3e-4, 1e-3, 3e-3, 1e-2]
            .iter()
            .map(|&t| {
                let sh = exact_loop_shape(
                    &lp,
                    ShapeTolerances {
                        symmetry: t,
                        contact: t,
                    },
                )
                .unwrap();
                (sh.point_group, sh.self_intersections)
            })
            .collect();
        assert!(
            answers.windows(2).all(|w| w[0] == w[1]),
            "eta {eta} lbar {lbar}: {answers:?}"
        );
    }
}

fn on_unit_sphere(
    length: f64,
    s: &[f64],
    p: &[Vector3<f64>],
    kg: &[f64],
    tol: ShapeTolerances,
) -> LoopShape {
    loop_shape(
        &SampledLoop {
            length,
            radius: 1.0,
            s,
            points: p,
            kappa_g_s: s,
            kappa_g: kg,
        },
        tol,
    )
    .unwrap()
}

/// A great circle is D∞h with no crossing; covered twice, it overlaps itself (no count).
#[test]
fn circles_have_continuous_groups() {
    let tol = ShapeTolerances::default();
    for (turns, want) in [(1usize, Some(0)), (2, None)] {
        let n = 400 * turns;
        let len = TAU * turns as f64;
        let s: Vec<f64> = (0..n).map(|i| len * i as f64 / n as f64).collect();
        let p: Vec<Vector3<f64>> = s
            .iter()
            .map(|&t| Vector3::new(t.cos(), 0.0, t.sin()))
            .collect();
        let sh = on_unit_sphere(len, &s, &p, &vec![0.0; n], tol);
        assert_eq!(sh.point_group, "D∞h");
        assert_eq!(sh.self_intersections, want, "{turns} turns");
    }
    // A small circle (latitude 30°): C∞v.
    let n = 300;
    let rho = (PI / 3.0).sin();
    let len = TAU * rho;
    let s: Vec<f64> = (0..n).map(|i| len * i as f64 / n as f64).collect();
    let p: Vec<Vector3<f64>> = s
        .iter()
        .map(|&t| Vector3::new(rho * (t / rho).cos(), rho * (t / rho).sin(), 0.5))
        .collect();
    let sh = on_unit_sphere(len, &s, &p, &vec![0.5 / rho; n], tol);
    assert_eq!((sh.point_group.as_str(), sh.group_order), ("C∞v", None));
}

/// Curves with known crossings: a figure-eight (the lemniscate of Gerono lifted onto the
/// sphere) crosses itself once at a known point, a limaçon with an inner loop once, a
/// three-petal rose three times at one point (a trefoil knot, which never touches itself,
/// is in `crates/figures/tests/figures.rs`).
#[test]
fn crossings_of_constructed_curves() {
    // Lemniscate of Gerono in the tangent plane at the north pole, projected onto the
    // sphere: one crossing, at the pole.
    let n = 800;
    let eight: Vec<Vector3<f64>> = (0..n)
        .map(|i| {
            let t = TAU * i as f64 / n as f64 + 0.1;
            Vector3::new(0.6 * t.sin(), 0.6 * t.sin() * t.cos(), 1.0).normalize()
        })
        .collect();
    let c = self_contacts(&eight, 1e-3);
    assert_eq!(c.len(), 1);
    assert!((c[0].point - Vector3::z()).norm() < 1e-3);
    // A limaçon r = 0.2 + 0.5 cos t with its inner loop, lifted onto the sphere: one crossing.
    let limacon: Vec<Vector3<f64>> = (0..n)
        .map(|i| {
            let t = TAU * i as f64 / n as f64;
            let r = 0.2 + 0.5 * t.cos();
            Vector3::new(r * t.cos(), r * t.sin(), 1.0).normalize()
        })
        .collect();
    assert_eq!(self_contacts(&limacon, 1e-3).len(), 1);
    // The three-petal rose r = cos 3t, t in [0, π), in the tangent plane: all three strands
    // pass through the pole, a triple point, which counts as its three pairwise crossings
    // (what any small generic perturbation splits it into).
    let rose: Vec<Vector3<f64>> = (0..1200)
        .map(|i| {
            let t = PI * i as f64 / 1200.0;
            let r = 0.5 * (3.0 * t).cos();
            Vector3::new(r * t.cos(), r * t.sin(), 1.0).normalize()
        })
        .collect();
    assert_eq!(self_contacts(&rose, 1e-3).len(), 3);
}

/// Bad input is refused with a message, not a panic.
#[test]
fn bad_input_is_refused() {
    let s = [0.0, 1.0, 2.0];
    let p = [Vector3::zeros(); 3];
    let err = loop_shape(
        &SampledLoop {
            length: 3.0,
            radius: 1.0,
            s: &s,
            points: &p,
            kappa_g_s: &s,
            kappa_g: &[0.0; 3],
        },
        ShapeTolerances::default(),
    );
    assert!(err.is_err());
    let lp = paper_branch_loop(2, 1.2).unwrap();
    let bad = ShapeTolerances {
        symmetry: 0.0,
        contact: 1e-3,
    };
    assert!(exact_loop_shape(&lp, bad).is_err());
}
