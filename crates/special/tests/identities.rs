//! Identities of the Jacobi functions and elliptic integrals over the ranges
//! the project uses: k ∈ [0, 0.999999] (and k up to 1 − 1e-12), k ∈ (1, 50],
//! u ∈ [−50, 50], n ∈ [−1e8, 0.9], φ ∈ [−20, 20].

use std::f64::consts::{FRAC_PI_2, PI};

use rodloop_special::{
    complete_e, complete_k, complete_pi, complete_pi_dn, incomplete_e, incomplete_f, incomplete_pi,
    jacobi, Jacobi, JacobiModulus,
};

const K_BELOW: [f64; 14] = [
    0.0,
    1e-10,
    1e-4,
    0.05,
    0.3,
    0.5,
    0.7,
    0.9,
    0.99,
    0.999,
    0.9999,
    0.999_999,
    1.0 - 1e-9,
    1.0 - 1e-12,
];
const K_ABOVE: [f64; 9] = [
    1.0 + 1e-12,
    1.0 + 1e-7,
    1.001,
    1.2,
    2.0,
    3.3,
    10.0,
    25.0,
    50.0,
];

fn all_k() -> Vec<f64> {
    let mut v = K_BELOW.to_vec();
    v.push(1.0);
    v.extend_from_slice(&K_ABOVE);
    v
}

/// u ∈ [−50, 50] on an irregular grid (1001 points).
fn u_grid() -> Vec<f64> {
    (0..=1000)
        .map(|i| -50.0 + 0.1 * i as f64 + 1e-3 * ((i * 7919) % 13) as f64)
        .filter(|u: &f64| u.abs() <= 50.0)
        .collect()
}

#[test]
fn pythagorean_identities() {
    for k in all_k() {
        for u in u_grid() {
            let j = jacobi(u, k);
            let e1 = j.sn * j.sn + j.cn * j.cn - 1.0;
            let e2 = j.dn * j.dn + k * k * j.sn * j.sn - 1.0;
            // a few ulps of 1 (the sums themselves are rounded too)
            assert!(
                e1.abs() <= 8.0 * f64::EPSILON,
                "sn²+cn²−1 = {e1:e} at u={u}, k={k}"
            );
            assert!(
                e2.abs() <= 8.0 * f64::EPSILON,
                "dn²+k²sn²−1 = {e2:e} at u={u}, k={k}"
            );
            // the amplitude is consistent with sn, cn
            let (s, c) = j.am.sin_cos();
            let tol = 6.0 * f64::EPSILON * (1.0 + j.am.abs());
            assert!((s - j.sn).abs() < tol, "sin am ≠ sn at u={u}, k={k}");
            assert!((c - j.cn).abs() < tol, "cos am ≠ cn at u={u}, k={k}");
        }
    }
}

#[test]
fn symmetry_in_u_is_exact() {
    for k in all_k() {
        for u in u_grid() {
            let p = jacobi(u, k);
            let m = jacobi(-u, k);
            assert_eq!(m.sn, -p.sn, "u={u} k={k}");
            assert_eq!(m.cn, p.cn, "u={u} k={k}");
            assert_eq!(m.dn, p.dn, "u={u} k={k}");
            assert_eq!(m.am, -p.am, "u={u} k={k}");
        }
        // and in k
        assert_eq!(jacobi(1.3, -k), jacobi(1.3, k));
        // signed zero
        let z = jacobi(-0.0, k);
        assert!(z.sn.is_sign_negative() && z.am.is_sign_negative(), "k={k}");
    }
}

#[test]
fn special_moduli() {
    for u in u_grid() {
        let j = jacobi(u, 0.0);
        assert_eq!(
            j,
            Jacobi {
                sn: u.sin(),
                cn: u.cos(),
                dn: 1.0,
                am: u
            }
        );
        let h = jacobi(u, 1.0);
        assert_eq!(h.sn, u.tanh());
        assert!((h.cn - 1.0 / u.cosh()).abs() <= 1e-16 / u.cosh());
        assert_eq!(h.cn, h.dn);
        // gd(u) = 2 atan(tanh(u/2))
        assert!((h.am - 2.0 * (0.5 * u).tanh().atan()).abs() < 4e-16);
    }
}

/// Central differences of 4th order with step h.
fn fd4(f: impl Fn(f64) -> f64, x: f64, h: f64) -> f64 {
    (-f(x + 2.0 * h) + 8.0 * f(x + h) - 8.0 * f(x - h) + f(x - 2.0 * h)) / (12.0 * h)
}

#[test]
fn derivatives_in_u_match_finite_differences() {
    for k in all_k() {
        // the functions vary on the scale 1/max(1, k)
        let h = 1e-3 / k.max(1.0);
        let scale = k.max(1.0);
        for u in u_grid().into_iter().step_by(7) {
            let j = jacobi(u, k);
            let d_sn = fd4(|x| jacobi(x, k).sn, u, h);
            let d_cn = fd4(|x| jacobi(x, k).cn, u, h);
            let d_dn = fd4(|x| jacobi(x, k).dn, u, h);
            let d_am = fd4(|x| jacobi(x, k).am, u, h);
            // DLMF 22.13.1–22.13.3 and 22.16.1
            let tol = 2e-9 * scale;
            assert!((d_sn - j.cn * j.dn).abs() < tol, "sn' at u={u} k={k}");
            assert!((d_cn + j.sn * j.dn).abs() < tol, "cn' at u={u} k={k}");
            assert!(
                (d_dn + k * k * j.sn * j.cn).abs() < tol * scale,
                "dn' at u={u} k={k}"
            );
            assert!((d_am - j.dn).abs() < tol, "am' at u={u} k={k}");
        }
    }
}

#[test]
fn periodicity() {
    for &k in &K_BELOW[1..] {
        let kk = complete_k(k).unwrap();
        for u in u_grid().into_iter().step_by(3) {
            let a = jacobi(u, k);
            let b = jacobi(u + 4.0 * kk, k);
            let c = jacobi(u + 2.0 * kk, k);
            // the shifted argument u + 4K is itself rounded: allow for that
            let tol = 4.0 * f64::EPSILON * (u.abs() + 4.0 * kk + 1.0);
            assert!((a.sn - b.sn).abs() < tol, "sn(u+4K) at u={u} k={k}");
            assert!((a.cn - b.cn).abs() < tol, "cn(u+4K) at u={u} k={k}");
            assert!((a.dn - b.dn).abs() < tol, "dn(u+4K) at u={u} k={k}");
            assert!((a.sn + c.sn).abs() < tol, "sn(u+2K) at u={u} k={k}");
            assert!((a.cn + c.cn).abs() < tol, "cn(u+2K) at u={u} k={k}");
            let tol_am = tol + 4.0 * f64::EPSILON * a.am.abs();
            assert!(
                (c.am - a.am - PI).abs() < tol_am,
                "am(u+2K) − am(u) − π = {:e} at u={u} k={k}",
                c.am - a.am - PI
            );
            assert!((b.am - a.am - 2.0 * PI).abs() < tol_am + tol);
        }
        // sn(K) = 1, cn(K) = 0, dn(K) = k'
        let q = jacobi(kk, k);
        let kc = ((1.0 - k) * (1.0 + k)).sqrt();
        assert!((q.sn - 1.0).abs() < 1e-15, "k={k}");
        assert!(q.cn.abs() < 4e-16 * kk, "cn(K) = {:e} k={k}", q.cn);
        assert!((q.dn - kc).abs() < 1e-15 * kc.max(1e-3), "k={k}");
        assert!((q.am - FRAC_PI_2).abs() < 1e-15);
    }
    // k > 1: period 4K(1/k)/k of sn, and am oscillates
    for &k in &K_ABOVE {
        let jm = JacobiModulus::new(k);
        let q = jm.quarter_period();
        if k >= 1.2 {
            // (closer to 1 the rounding of 1/k makes complete_k(1/k) inaccurate)
            assert!((q - complete_k(1.0 / k).unwrap() / k).abs() < 1e-15 * q);
        }
        let amax = (1.0 / k).asin();
        for u in u_grid().into_iter().step_by(5) {
            let a = jm.eval(u);
            let b = jm.eval(u + 4.0 * q);
            let tol = 4.0 * f64::EPSILON * (u.abs() + 4.0 * q + 1.0) * k;
            assert!((a.sn - b.sn).abs() < tol, "sn(u+4K) at u={u} k={k}");
            assert!(a.cn > 0.0, "cn > 0 for k > 1");
            assert!(a.am.abs() <= amax * (1.0 + 1e-15), "am bounded for k > 1");
        }
    }
}

#[test]
fn amplitude_is_unwrapped_and_monotone() {
    for &k in &K_BELOW {
        let mut prev = f64::NEG_INFINITY;
        let n = 20_000;
        for i in 0..=n {
            let u = -50.0 + 100.0 * i as f64 / n as f64;
            let am = jacobi(u, k).am;
            assert!(
                am > prev,
                "am not increasing at u={u}, k={k}: {am} <= {prev}"
            );
            prev = am;
        }
        // am grows like πu/(2K) over many periods
        let kk = complete_k(k).unwrap();
        let am50 = jacobi(50.0, k).am;
        assert!((am50 - FRAC_PI_2 * 50.0 / kk).abs() <= FRAC_PI_2, "k={k}");
    }
}

#[test]
fn am_inverts_incomplete_f() {
    // am(F(φ|k)|k) = φ for φ up to several periods, DLMF 22.16.1
    for &k in &K_BELOW {
        for i in 0..=400 {
            let phi = -20.0 + 0.1 * i as f64 + 0.0123;
            let u = incomplete_f(phi, k).unwrap();
            let back = jacobi(u, k).am;
            // the round trip is limited by the rounding of u = F(φ) (|u| ≤ 170
            // here): |δφ| ≲ dn(u) · few ε |u|.
            let tol = 4.0 * f64::EPSILON * (phi.abs() + u.abs() + 1.0);
            assert!(
                (back - phi).abs() < tol,
                "am(F(φ)) − φ = {:e} at φ={phi}, k={k}",
                back - phi
            );
        }
    }
    // and F(am(u)) = u
    for &k in &[0.3, 0.9, 0.999_999] {
        for u in u_grid().into_iter().step_by(11) {
            let am = jacobi(u, k).am;
            let f = incomplete_f(am, k).unwrap();
            let kc = ((1.0 - k) * (1.0 + k)).sqrt();
            // dF/dφ = 1/dn ≤ 1/k'
            let tol = 8.0 * f64::EPSILON * (u.abs() + 1.0) / kc;
            assert!(
                (f - u).abs() < tol,
                "F(am(u)) − u = {:e} at u={u}, k={k}",
                f - u
            );
        }
    }
}

#[test]
fn reciprocal_modulus_continuity_at_one() {
    // For fixed u the functions are analytic in m = k² across m = 1:
    // the values at k = 1 ± ε agree with the k = 1 limit to O(ε e^{2|u|})
    // (DLMF 22.10.7–22.10.9), and the two one-sided differences are opposite
    // to O(ε² e^{4|u|}).
    for &eps in &[1e-12, 1e-9, 1e-6] {
        for i in 0..=100 {
            let u = -5.0 + 0.1 * i as f64;
            let lo = jacobi(u, 1.0 - eps);
            let mid = jacobi(u, 1.0);
            let hi = jacobi(u, 1.0 + eps);
            for (name, a, b, c) in [
                ("sn", lo.sn, mid.sn, hi.sn),
                ("cn", lo.cn, mid.cn, hi.cn),
                ("dn", lo.dn, mid.dn, hi.dn),
                ("am", lo.am, mid.am, hi.am),
            ] {
                let first = 2.0 * eps * (2.0 * u.abs()).exp();
                assert!((a - b).abs() < first, "{name} below 1 at u={u}, eps={eps}");
                assert!((c - b).abs() < first, "{name} above 1 at u={u}, eps={eps}");
                let second = 1e3 * eps * eps * (4.0 * u.abs()).exp() * (1.0 + u.abs()) + 3e-15;
                assert!(
                    (a + c - 2.0 * b).abs() < second,
                    "{name} not smooth across k=1 at u={u}, eps={eps}: {:e}",
                    a + c - 2.0 * b
                );
            }
        }
    }
}

#[test]
fn legendre_relation() {
    // DLMF 19.7.1: E K' + E' K − K K' = π/2
    for &k in &[
        1e-6_f64,
        0.01,
        0.2,
        0.5,
        0.7,
        0.8,
        0.9,
        0.99,
        0.999,
        0.999_999,
        1.0 - 1e-12,
    ] {
        let kc = ((1.0 - k) * (1.0 + k)).sqrt();
        let (kk, ee) = (complete_k(k).unwrap(), complete_e(k).unwrap());
        let (kp, ep) = (complete_k(kc).unwrap(), complete_e(kc).unwrap());
        let lhs = ee * kp + ep * kk - kk * kp;
        let scale = ee * kp + ep * kk + kk * kp;
        assert!(
            (lhs - FRAC_PI_2).abs() < 2.0 * f64::EPSILON * scale,
            "Legendre relation off by {:e} at k={k}",
            lhs - FRAC_PI_2
        );
    }
}

#[test]
fn third_kind_special_values() {
    for &k in &[0.0, 1e-8, 0.3, 0.5, 0.9, 0.999_999, 1.0 - 1e-12] {
        // Π(0|k) = K(k)
        let kk = complete_k(k).unwrap();
        assert!((complete_pi(0.0, k).unwrap() - kk).abs() <= 2.0 * f64::EPSILON * kk);
        // Π(k²|k) = E/k'² (DLMF 19.6.1); n = k·k is rounded, which moves Π
        // by up to ε k² ∂Π/∂n (large for k → 1)
        let kc2 = (1.0 - k) * (1.0 + k);
        let n = k * k;
        let p = complete_pi(n, k).unwrap();
        let e = complete_e(k).unwrap() / kc2;
        let tol = 4.0 * f64::EPSILON * e + f64::EPSILON * n * complete_pi_dn(n, k).unwrap();
        assert!((p - e).abs() < tol, "Π(k²|k) at k={k}: {p} vs {e}");
        for &phi in &[0.3, 1.0, -2.5, 13.0] {
            let f = incomplete_f(phi, k).unwrap();
            let p0 = incomplete_pi(0.0, phi, k).unwrap();
            assert!((p0 - f).abs() <= 4.0 * f64::EPSILON * f.abs());
        }
    }
    for &n in &[-1e8_f64, -1e5, -37.0, -1.0, -1e-7, 0.0, 1e-7, 0.3, 0.9] {
        // Π(n|0) = π / (2√(1−n))  (DLMF 19.6.1)
        let exact = FRAC_PI_2 / (1.0 - n).sqrt();
        let p = complete_pi(n, 0.0).unwrap();
        assert!((p - exact).abs() < 4.0 * f64::EPSILON * exact, "Π({n}|0)");
        // Π(n, φ|0) = atan(√(1−n) tan φ)/√(1−n) on (−π/2, π/2)  (DLMF 19.6.12)
        for &phi in &[0.1_f64, 0.7, 1.2, -1.5] {
            let s = (1.0 - n).sqrt();
            let exact = (s * phi.tan()).atan() / s;
            let p = incomplete_pi(n, phi, 0.0).unwrap();
            assert!(
                (p - exact).abs() < 8.0 * f64::EPSILON * exact.abs(),
                "Π({n}, {phi}|0) = {p} vs {exact}"
            );
        }
    }
}

#[test]
fn third_kind_extreme_characteristic() {
    // Π(n|k) → π/(2√(1−n)) (1 + O(k² ln(1/k')/√|n|)) as n → −∞ (exact for
    // k = 0); no overflow in the transformation even at n = −1e300
    for &n in &[-1e12_f64, -1e100, -1e300] {
        let lead = FRAC_PI_2 / (1.0 - n).sqrt();
        for &k in &[0.0, 0.5, 0.999_999] {
            let tol = 4.0 * f64::EPSILON + 10.0 * k * k / (-n).sqrt();
            let p = complete_pi(n, k).unwrap();
            assert!((p - lead).abs() < tol * lead, "n={n} k={k}: {p}");
            // 7 = 2π + r: Π(n, 7) = 4Π(n) + Π(n, r), and for k = 0
            // Π(n, r|0) = atan(√(1−n) tan r)/√(1−n)  (DLMF 19.6.12)
            let q = incomplete_pi(n, 7.0, k).unwrap();
            let r = 7.0 - 2.0 * PI;
            let s = (1.0 - n).sqrt();
            let exact0 = 4.0 * lead + (s * r.tan()).atan() / s;
            assert!((q - exact0).abs() < tol * exact0, "n={n} k={k}: {q}");
        }
    }
}

#[test]
fn incomplete_integrals_are_odd_and_quasi_periodic() {
    for &k in &[0.0_f64, 0.4, 0.9, 0.999_999] {
        let kk = complete_k(k).unwrap();
        let ee = complete_e(k).unwrap();
        for &phi in &[0.2, 1.0, 1.5, 2.9] {
            for j in [-6.0, -1.0, 1.0, 3.0] {
                let shifted = phi + j * PI;
                let f0 = incomplete_f(phi, k).unwrap();
                let f1 = incomplete_f(shifted, k).unwrap();
                let tol = 8.0 * f64::EPSILON * (f1.abs() + 2.0 * kk);
                // phi + jπ is rounded: allow dF/dφ ≤ 1/k' times that rounding
                let kc = ((1.0 - k) * (1.0 + k)).sqrt();
                let tol = tol + f64::EPSILON * shifted.abs() / kc;
                assert!(
                    (f1 - f0 - 2.0 * j * kk).abs() < tol,
                    "F k={k} φ={phi} j={j}"
                );
                let e0 = incomplete_e(phi, k).unwrap();
                let e1 = incomplete_e(shifted, k).unwrap();
                assert!((e1 - e0 - 2.0 * j * ee).abs() < 8.0 * f64::EPSILON * (e1.abs() + 4.0));
                for &n in &[-1e8, -3.0, 0.5] {
                    let pc = complete_pi(n, k).unwrap();
                    let p0 = incomplete_pi(n, phi, k).unwrap();
                    let p1 = incomplete_pi(n, shifted, k).unwrap();
                    let tol = 8.0 * f64::EPSILON * (p1.abs() + 2.0 * pc)
                        + f64::EPSILON * shifted.abs() / (kc * (1.0 - n.min(0.0)).sqrt());
                    assert!(
                        (p1 - p0 - 2.0 * j * pc).abs() < tol,
                        "Π n={n} k={k} φ={phi} j={j}"
                    );
                }
            }
            assert_eq!(incomplete_f(-phi, k), incomplete_f(phi, k).map(|x| -x));
            assert_eq!(incomplete_e(-phi, k), incomplete_e(phi, k).map(|x| -x));
            assert_eq!(
                incomplete_pi(-7.0, -phi, k),
                incomplete_pi(-7.0, phi, k).map(|x| -x)
            );
        }
    }
}

#[test]
fn imaginary_modulus_second_kind() {
    // E(φ, i x) = E(φ | −x²) = ∫₀^φ √(1 + x² sin²θ) dθ, checked against
    // composite Simpson quadrature (smooth integrand, 20000 panels).
    use rodloop_special::incomplete_e_m;
    for &x in &[0.1, 1.0, 3.0, 10.0] {
        for &phi in &[0.4, 1.3, 2.8] {
            let n = 20_000;
            let h = phi / n as f64;
            let f = |t: f64| (1.0 + x * x * t.sin().powi(2)).sqrt();
            let mut s = f(0.0) + f(phi);
            for i in 1..n {
                let w = if i % 2 == 1 { 4.0 } else { 2.0 };
                s += w * f(i as f64 * h);
            }
            let simpson = s * h / 3.0;
            let e = incomplete_e_m(phi, -x * x).unwrap();
            assert!(
                (e - simpson).abs() < 1e-11 * simpson,
                "E({phi}, i{x}) = {e} vs {simpson}"
            );
        }
    }
}
