//! Derivatives of the complete integrals against central finite differences,
//! and the closed forms DLMF 19.4.1 / 19.4.4 against both.

use rodloop_special::{
    complete_e, complete_e_dk, complete_k, complete_k_dk, complete_pi, complete_pi_derivatives,
    complete_pi_dk, complete_pi_dk_closed_form, complete_pi_dn, complete_pi_dn_closed_form,
};

/// 4th-order central difference; `h` is rounded down to a power of two so
/// that the stencil points `x ± h`, `x ± 2h` are exact.
fn fd4(f: impl Fn(f64) -> f64, x: f64, h: f64) -> f64 {
    let h = 2.0_f64.powi(h.log2().floor() as i32);
    (-f(x + 2.0 * h) + 8.0 * f(x + h) - 8.0 * f(x - h) + f(x - 2.0 * h)) / (12.0 * h)
}

fn close(a: f64, b: f64, rel: f64, abs: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()) + abs
}

const K_GRID: [f64; 10] = [
    0.01, 0.1, 0.3, 0.5, 0.7, 0.9, 0.99, 0.999, 0.9999, 0.999_999,
];
const N_GRID: [f64; 13] = [
    -1e8, -1e5, -300.0, -10.0, -1.0, -0.2, -1e-9, 0.0, 1e-9, 0.2, 0.5, 0.8, 0.9,
];

/// A step that keeps the 5-point stencil inside (0, 1) and is small on the
/// scale on which the function varies.
fn k_step(k: f64) -> f64 {
    1e-3 * k.min(1.0 - k)
}

fn n_step(n: f64) -> f64 {
    1e-3 * (1.0 - n).min(n.abs().max(0.1))
}

#[test]
fn dk_and_de_match_finite_differences() {
    for &k in &K_GRID {
        let h = k_step(k);
        let fd_k = fd4(|x| complete_k(x).unwrap(), k, h);
        let fd_e = fd4(|x| complete_e(x).unwrap(), k, h);
        let dk = complete_k_dk(k).unwrap();
        let de = complete_e_dk(k).unwrap();
        assert!(close(dk, fd_k, 1e-8, 0.0), "dK/dk at k={k}: {dk} vs {fd_k}");
        assert!(close(de, fd_e, 1e-8, 0.0), "dE/dk at k={k}: {de} vs {fd_e}");
        // DLMF 19.4.1 closed forms
        let (kk, ee) = (complete_k(k).unwrap(), complete_e(k).unwrap());
        let kc2 = (1.0 - k) * (1.0 + k);
        let cf_k = (ee - kc2 * kk) / (k * kc2);
        let cf_e = (ee - kk) / k;
        // the closed forms cancel for small k: compare at their own accuracy
        let cancel_k = (ee + kc2 * kk) / (ee - kc2 * kk);
        let cancel_e = (ee + kk) / (kk - ee);
        assert!(close(dk, cf_k, 8.0 * f64::EPSILON * cancel_k, 0.0), "k={k}");
        assert!(close(de, cf_e, 8.0 * f64::EPSILON * cancel_e, 0.0), "k={k}");
    }
    // even functions of k: derivatives are odd and vanish at 0
    assert_eq!(complete_k_dk(0.0), Ok(0.0));
    assert_eq!(complete_e_dk(0.0), Ok(0.0));
    assert_eq!(complete_k_dk(-0.4), complete_k_dk(0.4).map(|x| -x));
    assert_eq!(complete_e_dk(-0.4), complete_e_dk(0.4).map(|x| -x));
}

#[test]
fn pi_derivatives_match_finite_differences() {
    for &k in &[0.0_f64, 0.01, 0.3, 0.5, 0.9, 0.99, 0.999_999] {
        let mut ns = N_GRID.to_vec();
        ns.push(k * k); // removable singularity of the closed forms
        ns.push(k * k * (1.0 + 1e-7));
        for &n in &ns {
            if n >= 1.0 {
                continue;
            }
            let d = complete_pi_derivatives(n, k).unwrap();
            assert!(close(d.value, complete_pi(n, k).unwrap(), 1e-14, 0.0));
            assert_eq!(d.d_n, complete_pi_dn(n, k).unwrap());
            assert_eq!(d.d_k, complete_pi_dk(n, k).unwrap());

            // finite differences are limited by rounding: ~ε|Π|/h
            let hn = n_step(n);
            let fd_n = fd4(|x| complete_pi(x, k).unwrap(), n, hn);
            assert!(
                close(d.d_n, fd_n, 1e-8, 100.0 * f64::EPSILON * d.value / hn),
                "∂Π/∂n at n={n}, k={k}: {} vs FD {fd_n}",
                d.d_n
            );
            if k > 0.0 {
                let hk = k_step(k);
                let fd_k = fd4(|x| complete_pi(n, x).unwrap(), k, hk);
                assert!(
                    close(d.d_k, fd_k, 1e-8, 100.0 * f64::EPSILON * d.value / hk),
                    "∂Π/∂k at n={n}, k={k}: {} vs FD {fd_k}",
                    d.d_k
                );
            } else {
                assert_eq!(d.d_k, 0.0);
            }
        }
    }
}

/// The closed forms of DLMF 19.4.4 as given in the design notes,
/// `∂Π/∂n = [E + (k² − n)K/n + (n² − k²)Π/n] / (2(k² − n)(n − 1))` and
/// `∂Π/∂k = k/(n − k²) · [E/(k² − 1) + Π]`, are correct: away from their
/// removable singularities (n = 0, n = k²) they agree with finite differences
/// and with the cancellation-free derivatives of this crate.
#[test]
fn dlmf_closed_forms_are_correct() {
    for &k in &[0.2_f64, 0.5, 0.8, 0.95] {
        for &n in &[-50.0, -2.0, -0.5, 0.5 * k * k + 0.3, 0.95] {
            if (n - k * k).abs() < 0.05 {
                continue;
            }
            let cf_n = complete_pi_dn_closed_form(n, k).unwrap();
            let cf_k = complete_pi_dk_closed_form(n, k).unwrap();
            let fd_n = fd4(|x| complete_pi(x, k).unwrap(), n, n_step(n));
            let fd_k = fd4(|x| complete_pi(n, x).unwrap(), k, k_step(k));
            assert!(
                close(cf_n, fd_n, 1e-8, 0.0),
                "n={n} k={k}: {cf_n} vs {fd_n}"
            );
            assert!(
                close(cf_k, fd_k, 1e-8, 0.0),
                "n={n} k={k}: {cf_k} vs {fd_k}"
            );
            let d = complete_pi_derivatives(n, k).unwrap();
            assert!(close(cf_n, d.d_n, 1e-12, 0.0), "n={n} k={k}");
            assert!(close(cf_k, d.d_k, 1e-12, 0.0), "n={n} k={k}");
        }
    }
}

#[test]
fn removable_singularity_n_equals_k_squared() {
    // At n = k² the closed forms are 0/0; the derivatives are smooth there.
    for &k in &[0.3_f64, 0.7, 0.9] {
        let n0 = k * k;
        let at = complete_pi_derivatives(n0, k).unwrap();
        let lo = complete_pi_derivatives(n0 - 1e-6, k).unwrap();
        let hi = complete_pi_derivatives(n0 + 1e-6, k).unwrap();
        assert!(at.d_n.is_finite() && at.d_k.is_finite());
        // linear in n across the point to O(h²)
        assert!(close(0.5 * (lo.d_n + hi.d_n), at.d_n, 1e-10, 0.0), "k={k}");
        assert!(close(0.5 * (lo.d_k + hi.d_k), at.d_k, 1e-10, 0.0), "k={k}");
        // the literal closed form is useless right there
        let cf = complete_pi_dn_closed_form(n0, k).unwrap();
        assert!(!cf.is_finite() || (cf - at.d_n).abs() > 1e-6 * at.d_n.abs());
    }
}
