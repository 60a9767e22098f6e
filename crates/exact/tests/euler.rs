//! Independent checks of the Euler rotation curves, Eqs. (4)–(8) of Wang, Li & Yi (2024).
//!
//! One file of independent checks of one module (`euler.rs`), sharing the reference routes
//! (quadratures, finite differences) defined once at the top.
//!
//! The reference values here come from separate routes (literal formulas, fixed-grid
//! quadratures, Gauss–Legendre, finite differences, closed-form asymptotics), never from
//! numbers printed by the module itself.

use rodloop_exact::euler::{
    alpha_for_lbar, hippopede, lbar_of_alpha, tennis_ball, viviani, EulerCurve, EulerError,
};
use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI, TAU};

// ---------------------------------------------------------------- helpers

fn norm(u: [f64; 3]) -> f64 {
    (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt()
}

fn dot(u: [f64; 3], v: [f64; 3]) -> f64 {
    u[0] * v[0] + u[1] * v[1] + u[2] * v[2]
}

fn cross(u: [f64; 3], v: [f64; 3]) -> [f64; 3] {
    [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ]
}

/// Eq. (4) typed in again, literally, with R = 1.
fn eq4(l: u32, alpha: f64, t: f64) -> [f64; 3] {
    let lt = l as f64 * t;
    [
        -alpha.cos() * t.cos() * lt.cos() + t.sin() * lt.sin(),
        alpha.cos() * t.sin() * lt.cos() + t.cos() * lt.sin(),
        alpha.sin() * lt.cos(),
    ]
}

/// Plain trapezoidal rule with `n` points for a 2π-periodic integrand.
fn trapezoid<F: Fn(f64) -> f64>(f: F, n: usize) -> f64 {
    let h = TAU / n as f64;
    (0..n).map(|k| f(k as f64 * h)).sum::<f64>() * h
}

/// Gauss–Legendre nodes and weights on [−1, 1] (Newton on P_n).
fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let mut x = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 0.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, x);
            for k in 2..=n {
                let kf = k as f64;
                let p2 = ((2.0 * kf - 1.0) * x * p1 - (kf - 1.0) * p0) / kf;
                p0 = p1;
                p1 = p2;
            }
            dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
            let dx = p1 / dp;
            x -= dx;
            if dx.abs() < 1e-16 {
                break;
            }
        }
        out.push((x, 2.0 / ((1.0 - x * x) * dp * dp)));
    }
    out
}

/// Composite Gauss–Legendre integral of `f` over [a, b] with `panels` panels.
fn gl_integral<F: Fn(f64) -> f64>(f: &F, a: f64, b: f64, panels: usize, gl: &[(f64, f64)]) -> f64 {
    let h = (b - a) / panels as f64;
    let mut sum = 0.0;
    for p in 0..panels {
        let mid = a + (p as f64 + 0.5) * h;
        for &(x, w) in gl {
            sum += w * f(mid + 0.5 * h * x);
        }
    }
    sum * 0.5 * h
}

/// Sixth-order central finite-difference derivative of a vector function.
fn fd1<F: Fn(f64) -> [f64; 3]>(f: F, t: f64, h: f64) -> [f64; 3] {
    let c = [(1.0, 45.0), (2.0, -9.0), (3.0, 1.0)];
    let mut d = [0.0; 3];
    for &(k, w) in &c {
        let p = f(t + k * h);
        let m = f(t - k * h);
        for i in 0..3 {
            d[i] += w * (p[i] - m[i]);
        }
    }
    d.map(|v| v / (60.0 * h))
}

/// Sixth-order central second derivative.
fn fd2<F: Fn(f64) -> [f64; 3]>(f: F, t: f64, h: f64) -> [f64; 3] {
    let c = [(1.0, 270.0), (2.0, -27.0), (3.0, 2.0)];
    let f0 = f(t);
    let mut d = f0.map(|v| -490.0 * v);
    for &(k, w) in &c {
        let p = f(t + k * h);
        let m = f(t - k * h);
        for i in 0..3 {
            d[i] += w * (p[i] + m[i]);
        }
    }
    d.map(|v| v / (180.0 * h * h))
}

/// Fourth-order central third derivative.
fn fd3<F: Fn(f64) -> [f64; 3]>(f: F, t: f64, h: f64) -> [f64; 3] {
    let c = [(1.0, -13.0), (2.0, 8.0), (3.0, -1.0)];
    let mut d = [0.0; 3];
    for &(k, w) in &c {
        let p = f(t + k * h);
        let m = f(t - k * h);
        for i in 0..3 {
            d[i] += w * (p[i] - m[i]);
        }
    }
    d.map(|v| v / (8.0 * h * h * h))
}

const ALPHAS: [f64; 11] = [0.0, 0.01, 0.2, 0.5, 1.0, 1.5, 2.0, 2.5, 2.9, 3.1, PI];

fn ts() -> Vec<f64> {
    (0..37).map(|k| 0.0123 + k as f64 * TAU / 37.0).collect()
}

// ---------------------------------------------------------------- Eq. (5): length

#[test]
fn length_eq5_matches_quadrature_over_grid() {
    let mut worst: f64 = 0.0;
    for l in 1..=5 {
        for &alpha in &ALPHAS {
            if l == 1 && alpha == PI {
                continue; // point curve, tested separately
            }
            let c = EulerCurve::new(l, alpha).unwrap();
            let eq5 = c.length();
            // independent: fixed-grid trapezoid of |dr/dt| with r_t from the analytic derivative
            let n = if l == 1 && alpha > 3.0 { 1 << 17 } else { 4096 };
            let quad = trapezoid(|t| norm(c.velocity(t)), n);
            let rel = (eq5 - quad).abs() / quad;
            worst = worst.max(rel);
            assert!(
                rel < 1e-12,
                "l={l} a={alpha}: eq5={eq5} quad={quad} rel={rel}"
            );
            // the module's own adaptive quadrature
            let q = c.length_by_quadrature();
            assert!(q.converged);
            assert!((q.value - eq5).abs() < 1e-12 * eq5, "l={l} a={alpha}");
            // Eq. (5) read literally: incomplete integral up to 2lπ with m = -K^2
            let k = alpha.sin() / (l as f64 + alpha.cos());
            let lit = (l as f64 + alpha.cos()) / l as f64
                * ellip::ellipeinc(2.0 * l as f64 * PI, -k * k).unwrap();
            if alpha < 3.0 || l > 1 {
                assert!(
                    (lit - eq5).abs() < 1e-13 * eq5,
                    "l={l} a={alpha}: {lit} vs {eq5}"
                );
            }
        }
    }
    eprintln!("worst relative |L_eq5 - L_quad| / L = {worst:.2e}");
}

#[test]
fn point_curve_at_l1_alpha_pi() {
    let c = EulerCurve::new(1, PI).unwrap();
    assert!(c.length().abs() < 1e-14);
    for t in ts() {
        let p = c.position(t);
        assert!((p[0] - 1.0).abs() < 1e-15 && p[1].abs() < 1e-15 && p[2].abs() < 1e-15);
    }
}

#[test]
fn lbar_is_strictly_decreasing_with_correct_limits() {
    for l in 1..=6u32 {
        let lf = l as f64;
        let n = 2000;
        let mut prev = f64::INFINITY;
        for k in 0..=n {
            let a = PI * k as f64 / n as f64;
            let v = lbar_of_alpha(l, a);
            assert!(v < prev, "l={l}: not decreasing at alpha={a}");
            prev = v;
        }
        assert!((lbar_of_alpha(l, 0.0) - (lf + 1.0)).abs() < 1e-15);
        assert!((lbar_of_alpha(l, PI) - (lf - 1.0)).abs() < 1e-14);
        // Small-alpha asymptote: lbar = l+1 - (2l+1)/(4(l+1)) alpha^2 + O(alpha^4)
        let a = 1e-4;
        let c0 = (lf + 1.0 - lbar_of_alpha(l, a)) / (a * a);
        assert!(
            (c0 - (2.0 * lf + 1.0) / (4.0 * (lf + 1.0))).abs() < 1e-6,
            "l={l}: {c0}"
        );
        // Near alpha = pi, beta = pi - alpha
        let b = 1e-4;
        let v = lbar_of_alpha(l, PI - b);
        if l == 1 {
            // lbar = (4/pi) cos(alpha/2) E(sin^2(alpha/2)) -> 2 beta / pi
            assert!((v / b - 2.0 / PI).abs() < 1e-6, "{}", v / b);
        } else {
            let c1 = (v - (lf - 1.0)) / (b * b);
            assert!(
                (c1 - (2.0 * lf - 1.0) / (4.0 * (lf - 1.0))).abs() < 1e-6,
                "l={l}: {c1}"
            );
        }
    }
}

#[test]
fn real_modulus_form_of_eq5_agrees() {
    // Imaginary-modulus transformation: lbar = (2/pi) sqrt(Q) E(sin^2 a / Q), Q = l^2 + 2 l cos a + 1.
    for l in 1..=5u32 {
        for &a in &ALPHAS {
            let lf = l as f64;
            let q = lf * lf + 2.0 * lf * a.cos() + 1.0;
            let other = if q <= 0.0 {
                0.0
            } else {
                2.0 / PI * q.sqrt() * ellip::ellipe((a.sin().powi(2) / q).min(1.0)).unwrap()
            };
            let v = lbar_of_alpha(l, a);
            assert!(
                (v - other).abs() < 1e-13 * v.max(1e-3),
                "l={l} a={a}: {v} vs {other}"
            );
        }
    }
}

#[test]
fn endpoints_are_multiply_covered_equators() {
    for l in 1..=5u32 {
        for (alpha, turns) in [(0.0, l as f64 + 1.0), (PI, 1.0 - l as f64)] {
            if l == 1 && alpha == PI {
                continue;
            }
            let c = EulerCurve::new(l, alpha).unwrap();
            // unwrapped azimuth over one period
            let n = 4000;
            let mut total = 0.0;
            let mut prev = {
                let p = c.position(0.0);
                p[1].atan2(p[0])
            };
            for k in 1..=n {
                let p = c.position(TAU * k as f64 / n as f64);
                assert!(p[2].abs() < 1e-15);
                assert!((norm(p) - 1.0).abs() < 1e-15);
                let phi = p[1].atan2(p[0]);
                let mut d = phi - prev;
                d -= TAU * (d / TAU).round();
                total += d;
                prev = phi;
            }
            // alpha = 0: azimuth pi - (l+1) t; alpha = pi: azimuth (l-1) t.
            assert!(
                (total + TAU * turns).abs() < 1e-9,
                "l={l} a={alpha}: {total}"
            );
            assert!((c.lbar() - turns.abs()).abs() < 1e-14);
            for t in ts() {
                assert!((c.curvature(t) - 1.0).abs() < 1e-13);
                assert!(c.torsion(t).abs() < 1e-12);
            }
            let e = c.bending_energy();
            assert!((e.value - turns.abs()).abs() < 1e-13);
        }
    }
}

// ---------------------------------------------------------------- Eq. (5) inversion

#[test]
fn alpha_lbar_round_trip() {
    for l in 1..=5u32 {
        let lf = l as f64;
        for k in 1..40 {
            let lbar = lf - 1.0 + 2.0 * k as f64 / 40.0;
            let a = alpha_for_lbar(l, lbar).unwrap();
            assert!(a > 0.0 && a < PI);
            let back = lbar_of_alpha(l, a);
            assert!(
                (back - lbar).abs() <= 1e-14 * lbar,
                "l={l} lbar={lbar}: {back}"
            );
            let c = EulerCurve::from_lbar(l, lbar).unwrap();
            assert_eq!(c.alpha, a);
        }
        for k in 1..30 {
            let a = PI * k as f64 / 30.0;
            let back = alpha_for_lbar(l, lbar_of_alpha(l, a)).unwrap();
            assert!((back - a).abs() < 1e-12 * a, "l={l} a={a}: {back}");
        }
        // close to the ends of the range
        for lbar in [lf + 1.0 - 1e-9, lf - 1.0 + 1e-9] {
            if lbar <= 0.0 {
                continue;
            }
            let a = alpha_for_lbar(l, lbar).unwrap();
            // best achievable: rounding of lbar plus the change of lbar over one ulp of alpha
            // (for l = 1, lbar -> 0 means alpha -> pi, where one ulp of alpha is a sizeable
            // relative change of pi - alpha and hence of lbar)
            let up = f64::from_bits(a.to_bits() + 1);
            let down = f64::from_bits(a.to_bits() - 1);
            let spacing = (lbar_of_alpha(l, up) - lbar_of_alpha(l, down)).abs();
            let resid = (lbar_of_alpha(l, a) - lbar).abs();
            assert!(
                resid <= 4.0 * f64::EPSILON * lbar + spacing,
                "l={l} {lbar}: {resid}"
            );
        }
    }
}

#[test]
fn alpha_for_lbar_agrees_with_bisection_on_quadrature_length() {
    // Fully independent: bisect on a fixed-grid trapezoid of |r_t| from the literal Eq. (4)
    // differentiated by the chain rule (no elliptic integrals).
    fn lbar_quad(l: u32, a: f64) -> f64 {
        let lf = l as f64;
        trapezoid(
            |t| {
                // |r_t|^2 from Eq. (4) by hand
                let (st, ct) = t.sin_cos();
                let (sl, cl) = (lf * t).sin_cos();
                let ca = a.cos();
                let dx = ca * st * cl + ca * ct * lf * sl + ct * sl + st * lf * cl;
                let dy = ca * ct * cl - ca * st * lf * sl - st * sl + ct * lf * cl;
                let dz = -a.sin() * lf * sl;
                (dx * dx + dy * dy + dz * dz).sqrt()
            },
            2048,
        ) / TAU
    }
    for (l, lbar) in [(1, 1.7), (2, 1.2), (3, 2.2), (2, 2.8), (4, 3.2), (1, 0.4)] {
        let (mut lo, mut hi) = (0.0, PI);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if lbar_quad(l, mid) > lbar {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let a = alpha_for_lbar(l, lbar).unwrap();
        assert!(
            (a - 0.5 * (lo + hi)).abs() < 1e-12,
            "l={l} lbar={lbar}: {a} vs {lo}"
        );
    }
}

#[test]
fn out_of_range_lengths_are_rejected() {
    for (l, lbar) in [
        (2u32, 0.5),
        (2, 1.0),
        (2, 3.0),
        (2, 3.5),
        (1, 0.0),
        (1, 2.0),
        (1, -1.0),
    ] {
        match alpha_for_lbar(l, lbar) {
            Err(EulerError::LengthOutOfRange {
                l: el,
                lbar: eb,
                min,
                max,
            }) => {
                assert_eq!(el, l);
                assert_eq!(eb, lbar);
                assert_eq!(min, l as f64 - 1.0);
                assert_eq!(max, l as f64 + 1.0);
            }
            other => panic!("l={l} lbar={lbar}: {other:?}"),
        }
    }
    assert!(matches!(
        alpha_for_lbar(2, f64::NAN),
        Err(EulerError::LengthOutOfRange { .. })
    ));
    assert!(matches!(
        alpha_for_lbar(0, 0.5),
        Err(EulerError::InvalidL { l: 0 })
    ));
    assert!(matches!(
        EulerCurve::new(0, 1.0),
        Err(EulerError::InvalidL { .. })
    ));
    assert!(matches!(
        EulerCurve::new(2, -0.1),
        Err(EulerError::InvalidAlpha { .. })
    ));
    assert!(matches!(
        EulerCurve::new(2, 3.2),
        Err(EulerError::InvalidAlpha { .. })
    ));
    assert!(matches!(
        EulerCurve::new(2, f64::NAN),
        Err(EulerError::InvalidAlpha { .. })
    ));
    assert!(alpha_for_lbar(1, 1e-3).is_ok());
}

// ---------------------------------------------------------------- Eq. (4), (6): local geometry

#[test]
fn position_is_eq4_and_on_unit_sphere() {
    for l in 1..=5 {
        for &a in &ALPHAS {
            let c = EulerCurve { l, alpha: a };
            for t in ts() {
                let p = c.position(t);
                let q = eq4(l, a, t);
                let h = c.derivative(0, t);
                for i in 0..3 {
                    assert!((p[i] - q[i]).abs() < 1e-15);
                    assert!((h[i] - q[i]).abs() < 1e-14, "l={l} a={a} t={t}");
                }
                assert!((norm(p) - 1.0).abs() < 1e-15);
                assert!((norm(h) - 1.0).abs() < 1e-14);
            }
        }
    }
}

#[test]
fn derivatives_match_finite_differences() {
    let mut worst: f64 = 0.0;
    for l in 1..=5 {
        for &a in &[0.3, 1.1, 2.2, 2.9] {
            let c = EulerCurve { l, alpha: a };
            let scale = (l as f64 + 1.0).powi(3);
            for t in ts() {
                let pos = |t: f64| eq4(l, a, t);
                let d1 = fd1(pos, t, 1e-3);
                let d2 = fd2(pos, t, 1e-2);
                let d3 = fd3(pos, t, 1e-2);
                let d3b = fd1(|t| c.acceleration(t), t, 1e-3);
                let (v, acc, j) = (c.velocity(t), c.acceleration(t), c.jerk(t));
                for i in 0..3 {
                    worst = worst.max((d1[i] - v[i]).abs() / scale);
                    assert!((d1[i] - v[i]).abs() < 1e-9 * scale);
                    assert!((d2[i] - acc[i]).abs() < 1e-7 * scale * (l as f64 + 1.0));
                    assert!((d3[i] - j[i]).abs() < 1e-3 * scale * (l as f64 + 1.0).powi(2));
                    assert!((d3b[i] - j[i]).abs() < 1e-9 * scale * (l as f64 + 1.0));
                }
                assert!((c.speed(t) - norm(v)).abs() < 1e-13 * norm(v));
            }
        }
    }
    eprintln!("worst scaled |r_t - FD| = {worst:.2e}");
}

#[test]
fn curvature_and_torsion_match_finite_differences() {
    let mut worst_k: f64 = 0.0;
    let mut worst_t: f64 = 0.0;
    for l in 1..=4 {
        for &a in &[0.3, 1.1, 2.2] {
            let c = EulerCurve { l, alpha: a };
            for t in ts() {
                let pos = |t: f64| eq4(l, a, t);
                let r1 = fd1(pos, t, 1e-3);
                let r2 = fd2(pos, t, 1e-2);
                let r3 = fd3(pos, t, 2e-3);
                let v = norm(r1);
                let k_fd = norm(cross(r1, r2)) / (v * v * v);
                let cr = cross(r1, r2);
                let tau_fd = dot(r1, cross(r2, r3)) / dot(cr, cr);
                let k = c.curvature(t);
                let tau = c.torsion(t);
                worst_k = worst_k.max((k - k_fd).abs() / k);
                worst_t = worst_t.max((tau - tau_fd).abs() / (1.0 + tau.abs()));
                assert!(
                    (k - k_fd).abs() < 1e-7 * k,
                    "l={l} a={a} t={t}: {k} vs {k_fd}"
                );
                assert!(
                    (tau - tau_fd).abs() < 1e-4 * (1.0 + tau.abs()),
                    "{tau} vs {tau_fd}"
                );
                assert!(k >= 1.0 - 1e-14, "curvature on the unit sphere is >= 1");
            }
        }
    }
    eprintln!("worst rel kappa vs FD {worst_k:.2e}, tau vs FD {worst_t:.2e}");
}

#[test]
fn kappa_squared_is_one_plus_kappa_g_squared() {
    let mut worst: f64 = 0.0;
    for l in 1..=5 {
        for &a in &ALPHAS[1..10] {
            let c = EulerCurve { l, alpha: a };
            for t in ts() {
                let k = c.curvature(t);
                let kg = c.geodesic_curvature(t);
                let rel = (k * k - (1.0 + kg * kg)).abs() / (k * k);
                worst = worst.max(rel);
                assert!(rel < 1e-12, "l={l} a={a} t={t}: {k} {kg}");
                // normal curvature: r_ss . n = -1 with n = r
                let v = c.velocity(t);
                let acc = c.acceleration(t);
                let sp = norm(v);
                let r = c.position(t);
                let tan_part = dot(acc, v) / (sp * sp);
                let rss: Vec<f64> = (0..3)
                    .map(|i| (acc[i] - tan_part * v[i]) / (sp * sp))
                    .collect();
                assert!((rss[0] * r[0] + rss[1] * r[1] + rss[2] * r[2] + 1.0).abs() < 1e-12);
            }
        }
    }
    eprintln!("worst |k^2 - 1 - kg^2|/k^2 = {worst:.2e}");
}

#[test]
fn geodesic_curvature_sign_convention() {
    // Stated convention: kappa_g = T' . (n x T), n = r the outward normal, T the unit tangent,
    // prime = d/ds.  Check it with T' from finite differences of the unit tangent of Eq. (4).
    for (l, a) in [(1u32, 0.9), (2, 1.0), (3, 2.3)] {
        let c = EulerCurve { l, alpha: a };
        let unit_tangent = |t: f64| {
            let d = fd1(|u| eq4(l, a, u), t, 1e-3);
            let v = norm(d);
            d.map(|x| x / v)
        };
        for t in ts() {
            let tan = unit_tangent(t);
            let v = norm(fd1(|u| eq4(l, a, u), t, 1e-3));
            let dtds = fd1(unit_tangent, t, 1e-3).map(|x| x / v);
            let kg_fd = dot(dtds, cross(eq4(l, a, t), tan));
            let kg = c.geodesic_curvature(t);
            assert!(
                (kg - kg_fd).abs() < 1e-7 * (1.0 + kg.abs()),
                "l={l} t={t}: {kg} {kg_fd}"
            );
        }
        // the Euler curves turn both ways
        let vals: Vec<f64> = (0..400)
            .map(|k| c.geodesic_curvature(TAU * k as f64 / 400.0))
            .collect();
        assert!(vals.iter().any(|&v| v > 0.1) && vals.iter().any(|&v| v < -0.1));
    }
}

#[test]
fn total_torsion_vanishes() {
    let mut worst: f64 = 0.0;
    for l in 1..=5 {
        for &a in &[0.01, 0.2, 0.5, 1.0, 1.5, 2.0, 2.5, 2.9, 3.1] {
            let c = EulerCurve { l, alpha: a };
            let q = c.total_torsion();
            assert!(q.converged, "l={l} a={a}");
            worst = worst.max(q.value.abs());
            assert!(q.value.abs() < 1e-10, "l={l} a={a}: {}", q.value);
            // Eq. (4) has tau(-t) = -tau(t), so a grid symmetric about t = 0 cancels exactly;
            // a shifted grid does not pair points and tests the integral itself.
            let shifted = trapezoid(|t| c.torsion(t + 0.1234) * c.speed(t + 0.1234), 1 << 14);
            worst = worst.max(shifted.abs());
            assert!(shifted.abs() < 1e-10, "l={l} a={a}: shifted {shifted}");
            // ... and it is not trivially zero: the integral of |tau| is substantial
            if a > 0.1 && a < 3.0 {
                let abs = trapezoid(|t| c.torsion(t).abs() * c.speed(t), 4096);
                assert!(abs > 1e-2, "l={l} a={a}: {abs}");
            }
        }
    }
    eprintln!("worst |total torsion| = {worst:.2e}");
}

// ---------------------------------------------------------------- Eq. (2): energy

#[test]
fn energy_converges_and_splits_into_normal_and_geodesic_parts() {
    for l in 1..=5 {
        for &a in &[0.01, 0.3, 1.0, 1.8, 2.5, 2.9] {
            let c = EulerCurve { l, alpha: a };
            let e = c.bending_energy();
            assert!(e.converged);
            assert!(e.error_estimate < 1e-12 * e.value);
            // independent doubling check with a plain trapezoid on kappa^2 |r_t| / (2 pi)
            let n = 512 * (l as usize + 1) * if a > 2.8 { 8 } else { 1 };
            let f = |t: f64| c.curvature(t).powi(2) * norm(c.velocity(t)) / TAU;
            let e1 = trapezoid(f, n);
            let e2 = trapezoid(f, 2 * n);
            assert!((e1 - e2).abs() < 1e-12 * e2, "l={l} a={a}: {e1} {e2}");
            assert!(
                (e.value - e2).abs() < 1e-12 * e2,
                "l={l} a={a}: {} {e2}",
                e.value
            );
            // split: E = E_n + E_g with E_n = lbar
            let en = c.energy_n();
            let eg = c.energy_g();
            assert!(eg.converged);
            assert_eq!(en, c.lbar());
            assert!(eg.value >= 0.0);
            assert!((en + eg.value - e.value).abs() < 1e-12 * e.value);
            // E_n computed independently as (1/2pi) * integral of 1 ds
            let en_q = trapezoid(|t| norm(c.velocity(t)), 4096) / TAU;
            if a < 2.8 || l > 1 {
                assert!((en - en_q).abs() < 1e-12 * en);
            }
        }
    }
}

#[test]
fn large_l_limit_of_eq5() {
    // Paper: lbar -> l + cos(alpha) as l -> oo.  Expansion of Eq. (5):
    // lbar = (l + c)[1 + K^2/4 - 3 K^4/64 + ...], K = sin a / (l + c).
    for &a in &[0.5_f64, 1.0, 2.0] {
        for l in [10u32, 20, 40, 80] {
            let lc = l as f64 + a.cos();
            let k2 = (a.sin() / lc).powi(2);
            let expect = lc * (1.0 + k2 / 4.0 - 3.0 * k2 * k2 / 64.0);
            let v = lbar_of_alpha(l, a);
            assert!((v - expect).abs() < 1.0 / (l as f64).powi(5), "l={l} a={a}");
        }
        // E_g / E_n decreases with l (paper: -> 0)
        let ratio = |l: u32| {
            let c = EulerCurve { l, alpha: a };
            c.energy_g().value / c.energy_n()
        };
        let r: Vec<f64> = [2u32, 5, 10, 20].iter().map(|&l| ratio(l)).collect();
        eprintln!("alpha={a}: E_g/E_n at l=2,5,10,20: {r:?}");
        assert!(r.windows(2).all(|w| w[1] < w[0]));
    }
}

#[test]
fn reported_energies() {
    // Energies compared with the exact elastic solutions (Fig. 5 lengths).
    for (l, lbar) in [(2u32, 1.2), (1, 1.7), (3, 2.2), (2, 2.8)] {
        let c = EulerCurve::from_lbar(l, lbar).unwrap();
        let e = c.bending_energy();
        let eg = c.energy_g();
        eprintln!(
            "l={l} lbar={lbar}: alpha={:.15} E R/(pi D)={:.15} (err est {:.1e}, {} pts) E_n={:.15} E_g={:.15}",
            c.alpha, e.value, e.error_estimate, e.points, c.energy_n(), eg.value
        );
        assert!(e.value > lbar && e.converged);
    }
}

// ---------------------------------------------------------------- arclength sampling

#[test]
fn sampling_is_uniform_in_arclength() {
    let gl = gauss_legendre(20);
    for (l, a) in [
        (1u32, 1.0),
        (2, 0.7),
        (3, 2.0),
        (2, 2.8),
        (1, 2.9),
        (5, 1.3),
    ] {
        let c = EulerCurve { l, alpha: a };
        let total = c.length();
        let n = 48;
        let smp = c.sample(n);
        assert_eq!(smp.len(), n);
        assert_eq!(smp[0].t, 0.0);
        let speed = |t: f64| norm(c.velocity(t));
        for j in 0..n {
            let sj = smp[j];
            assert!((sj.s - total * j as f64 / n as f64).abs() < 1e-15 * total);
            let t_next = if j + 1 < n { smp[j + 1].t } else { TAU };
            assert!(t_next > sj.t);
            let ds = gl_integral(&speed, sj.t, t_next, 8, &gl);
            assert!(
                (ds - total / n as f64).abs() < 1e-12 * total,
                "l={l} a={a} j={j}: {ds} vs {}",
                total / n as f64
            );
            let p = eq4(l, a, sj.t);
            assert!((p[0] - sj.x).abs() < 1e-14 && (p[1] - sj.y).abs() < 1e-14);
            assert!((p[2] - sj.z).abs() < 1e-14);
            assert_eq!(sj.kappa, c.curvature(sj.t));
            assert_eq!(sj.tau, c.torsion(sj.t));
            assert_eq!(sj.kappa_g, c.geodesic_curvature(sj.t));
        }
        // cumulative arclength in closed form agrees with Gauss-Legendre
        for &t in &[0.3, 1.0, 2.5, 4.0, 6.0] {
            let s_gl = gl_integral(&speed, 0.0, t, 64, &gl);
            assert!((c.arclength(t) - s_gl).abs() < 1e-13 * total);
            let back = c.parameter_at_arclength(s_gl);
            assert!((back - t).abs() < 1e-12, "{back} vs {t}");
        }
        assert!((c.arclength(TAU) - total).abs() < 1e-14 * total);
    }
}

// ---------------------------------------------------------------- Eqs. (7), (8): tennis ball

#[test]
fn tennis_ball_equals_l2_euler_curve_pointwise() {
    for &a in &ALPHAS {
        let tb = tennis_ball(a);
        // paper's definitions of a, b with R = 1
        assert!((tb.a - (1.0 - a.cos()) / 2.0).abs() < 1e-15);
        assert!((tb.b - (1.0 + a.cos()) / 2.0).abs() < 1e-15);
        let c = EulerCurve { l: 2, alpha: a };
        for t in ts() {
            // Eq. (7) typed in literally
            let (aa, bb) = ((1.0 - a.cos()) / 2.0, (1.0 + a.cos()) / 2.0);
            let e7 = [
                aa * t.cos() - bb * (3.0 * t).cos(),
                aa * t.sin() + bb * (3.0 * t).sin(),
                2.0 * (aa * bb).sqrt() * (2.0 * t).cos(),
            ];
            let p = c.position(t);
            let q = tb.position(t);
            for i in 0..3 {
                assert!((e7[i] - p[i]).abs() < 1e-14, "a={a} t={t}");
                assert!((q[i] - p[i]).abs() < 1e-14);
            }
            assert!((tb.curvature(t) - c.curvature(t)).abs() < 1e-12 * c.curvature(t));
        }
    }
}

#[test]
fn tennis_ball_length_eq8() {
    let mut worst: f64 = 0.0;
    for &a in &ALPHAS[..10] {
        let tb = tennis_ball(a);
        let l8 = tb.length_eq8();
        let lq = trapezoid(
            |t| {
                let d = tb.derivative(1, t);
                norm(d)
            },
            4096,
        );
        let rel = (l8 - lq).abs() / lq;
        worst = worst.max(rel);
        assert!(rel < 1e-13, "a={a}: eq8={l8} quad={lq}");
        assert!((tb.length_by_quadrature().value - lq).abs() < 1e-13 * lq);
        let l5 = EulerCurve { l: 2, alpha: a }.length();
        assert!((l8 - l5).abs() < 1e-13 * l5);
        // range stated in the paper: lbar in [1, 3]
        assert!((1.0..=3.0).contains(&(l8 / TAU)));
    }
    eprintln!("worst relative |L_eq8 - L_quad|/L = {worst:.2e}");
}

/// Points uniform in arclength computed by a route independent of the module: composite
/// Gauss-Legendre cumulative length and bisection.
fn arclength_points<F, G>(pos: F, speed: G, n: usize) -> Vec<[f64; 3]>
where
    F: Fn(f64) -> [f64; 3],
    G: Fn(f64) -> f64,
{
    let gl = gauss_legendre(16);
    let total = gl_integral(&speed, 0.0, TAU, 256, &gl);
    (0..n)
        .map(|j| {
            let target = total * j as f64 / n as f64;
            let (mut lo, mut hi) = (0.0, TAU);
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                let panels = 1 + (256.0 * mid / TAU) as usize;
                if gl_integral(&speed, 0.0, mid, panels, &gl) < target {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            pos(0.5 * (lo + hi))
        })
        .collect()
}

#[test]
fn tennis_ball_rotation_invariants_match_euler_curve() {
    // Rigidly move the seam (rotation + reflection) and shift its parameter by a half period
    // t -> t + pi (which maps the seam to a rotated copy of itself); invariants must not change.
    let a = 1.3;
    let tb = tennis_ball(a);
    let c = EulerCurve { l: 2, alpha: a };
    // orthogonal matrix with det = -1: rotation about (1,2,2)/3 by 0.7 then reflection z -> -z
    let (s, co) = 0.7_f64.sin_cos();
    let u = [1.0 / 3.0, 2.0 / 3.0, 2.0 / 3.0];
    // Rodrigues: cos I + (1 - cos) u u^T + sin [u]_x
    let ux = [[0.0, -u[2], u[1]], [u[2], 0.0, -u[0]], [-u[1], u[0], 0.0]];
    let mut m = [[0.0; 3]; 3];
    for (i, row) in m.iter_mut().enumerate() {
        for (j, mij) in row.iter_mut().enumerate() {
            let kron = if i == j { 1.0 } else { 0.0 };
            *mij = co * kron + (1.0 - co) * u[i] * u[j] + s * ux[i][j];
        }
    }
    for row in m.iter_mut() {
        row[2] = -row[2];
    }
    // sanity: m is orthogonal with det -1
    for i in 0..3 {
        for j in 0..3 {
            let g: f64 = (0..3).map(|k| m[k][i] * m[k][j]).sum();
            assert!((g - if i == j { 1.0 } else { 0.0 }).abs() < 1e-15);
        }
    }
    assert!((dot(m[0], cross(m[1], m[2])) + 1.0).abs() < 1e-15);
    let moved = |t: f64| {
        let p = tb.position(t + PI);
        [
            m[0][0] * p[0] + m[0][1] * p[1] + m[0][2] * p[2],
            m[1][0] * p[0] + m[1][1] * p[1] + m[1][2] * p[2],
            m[2][0] * p[0] + m[2][1] * p[1] + m[2][2] * p[2],
        ]
    };
    let n = 40;
    let pts_tb = arclength_points(moved, |t| norm(tb.derivative(1, t + PI)), n);
    let smp = c.sample(n);
    let pts_e: Vec<[f64; 3]> = smp.iter().map(|s| [s.x, s.y, s.z]).collect();
    let mut worst: f64 = 0.0;
    for i in 0..n {
        for j in 0..n {
            let g1 = dot(pts_tb[i], pts_tb[j]);
            let g2 = dot(pts_e[i], pts_e[j]);
            worst = worst.max((g1 - g2).abs());
        }
    }
    assert!(worst < 1e-10, "Gram matrices differ by {worst}");
    // curvature as a function of arclength
    let kappas_tb: Vec<f64> = {
        let gl = gauss_legendre(16);
        let speed = |t: f64| norm(tb.derivative(1, t + PI));
        let total = gl_integral(&speed, 0.0, TAU, 256, &gl);
        (0..n)
            .map(|j| {
                let target = total * j as f64 / n as f64;
                let (mut lo, mut hi) = (0.0, TAU);
                for _ in 0..60 {
                    let mid = 0.5 * (lo + hi);
                    if gl_integral(&speed, 0.0, mid, 1 + (256.0 * mid / TAU) as usize, &gl) < target
                    {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                tb.curvature(0.5 * (lo + hi) + PI)
            })
            .collect()
    };
    for (k1, s) in kappas_tb.iter().zip(&smp) {
        assert!((k1 - s.kappa).abs() < 1e-10 * s.kappa);
    }
    // length and energy
    assert!((tb.length_eq8() - c.length()).abs() < 1e-13 * c.length());
    let e_tb = trapezoid(
        |t| tb.curvature(t).powi(2) * norm(tb.derivative(1, t)) / TAU,
        8192,
    );
    assert!((e_tb - c.bending_energy().value).abs() < 1e-12 * e_tb);
}

// ---------------------------------------------------------------- l = 1: hippopede, Viviani

/// Circle through three points of the plane: (centre, radius).
fn circumcircle(p: [f64; 2], q: [f64; 2], r: [f64; 2]) -> ([f64; 2], f64) {
    let d = 2.0 * (p[0] * (q[1] - r[1]) + q[0] * (r[1] - p[1]) + r[0] * (p[1] - q[1]));
    let (pp, qq, rr) = (
        p[0] * p[0] + p[1] * p[1],
        q[0] * q[0] + q[1] * q[1],
        r[0] * r[0] + r[1] * r[1],
    );
    let ux = (pp * (q[1] - r[1]) + qq * (r[1] - p[1]) + rr * (p[1] - q[1])) / d;
    let uy = (pp * (r[0] - q[0]) + qq * (p[0] - r[0]) + rr * (q[0] - p[0])) / d;
    ([ux, uy], (p[0] - ux).hypot(p[1] - uy))
}

#[test]
fn l1_curve_lies_on_tangent_cylinder_of_radius_cos2_half_alpha() {
    for &a in &[0.3, 0.8, FRAC_PI_4, FRAC_PI_2, 2.0, 2.8] {
        let c = EulerCurve { l: 1, alpha: a };
        // locate the axis (parallel to z) from three points projected on the xy-plane
        let xy = |t: f64| {
            let p = c.position(t);
            [p[0], p[1]]
        };
        let (centre, rho) = circumcircle(xy(0.1), xy(0.7), xy(1.3));
        for t in ts() {
            let p = c.position(t);
            assert!(((p[0] - centre[0]).hypot(p[1] - centre[1]) - rho).abs() < 1e-12);
        }
        // tangent: the axis is at distance 1 - rho from the sphere centre
        assert!((centre[0].hypot(centre[1]) + rho - 1.0).abs() < 1e-12);
        let half = 0.5 * a;
        assert!((rho - half.cos().powi(2)).abs() < 1e-12, "a={a}: rho={rho}");
        if (a - FRAC_PI_2).abs() > 1e-9 {
            // the paper's R sin^2(alpha/2) is NOT the radius for the parametrisation Eq. (4)
            assert!((rho - half.sin().powi(2)).abs() > 0.05, "a={a}");
        }
        // the module's hippopede: same cylinder, and its parametrisation with theta = pi - 2t
        let h = hippopede(a);
        assert!((h.radius - rho).abs() < 1e-12);
        assert!((h.alpha() - a).abs() < 1e-7);
        for t in ts() {
            let p = c.position(t);
            assert!(h.cylinder_residual(p).abs() < 1e-14);
            let q = h.position(PI - 2.0 * t);
            for i in 0..3 {
                assert!((p[i] - q[i]).abs() < 1e-14, "a={a} t={t}");
            }
        }
    }
}

#[test]
fn viviani_curve_is_alpha_half_pi_not_quarter_pi() {
    // Viviani: sphere of radius R with the cylinder of radius R/2 through the centre,
    // x = (1 + cos th)/2, y = sin(th)/2, z = sin(th/2), th in [0, 4 pi).
    let viv = |th: f64| [0.5 * (1.0 + th.cos()), 0.5 * th.sin(), (0.5 * th).sin()];
    let viv_len = trapezoid(|u| norm(fd1(viv, 2.0 * u, 1e-3)) * 2.0, 4096);
    let on_viviani_cylinder = |p: [f64; 3]| (p[0] * p[0] + p[1] * p[1] - p[0]).abs();
    let c = EulerCurve {
        l: 1,
        alpha: FRAC_PI_2,
    };
    for t in ts() {
        assert!(on_viviani_cylinder(c.position(t)) < 1e-15);
    }
    assert!(
        (c.length() - viv_len).abs() < 1e-9 * viv_len,
        "{} {viv_len}",
        c.length()
    );
    // ... and Viviani's curve is the module's viviani() = hippopede(pi/2)
    assert_eq!(viviani().radius, 0.5);
    assert!((hippopede(FRAC_PI_2).radius - 0.5).abs() < 1e-15);
    // the paper's alpha = pi/4 is not Viviani's curve
    let c4 = EulerCurve {
        l: 1,
        alpha: FRAC_PI_4,
    };
    let worst = ts()
        .into_iter()
        .map(|t| on_viviani_cylinder(c4.position(t)))
        .fold(0.0, f64::max);
    assert!(worst > 0.1, "{worst}");
    assert!((c4.length() - viv_len).abs() > 0.1);
}
