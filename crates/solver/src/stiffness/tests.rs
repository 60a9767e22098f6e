use super::*;

fn fd_check(p: &StiffnessProfile, sigma: f64) {
    let e = 1e-5;
    let v = p.eval(sigma);
    let d1 = (p.eval(sigma + e).d - p.eval(sigma - e).d) / (2.0 * e);
    let d2 = (p.eval(sigma + e).d1 - p.eval(sigma - e).d1) / (2.0 * e);
    assert!(
        (d1 - v.d1).abs() < 1e-6 * (1.0 + v.d1.abs()),
        "{d1} {}",
        v.d1
    );
    assert!(
        (d2 - v.d2).abs() < 1e-5 * (1.0 + v.d2.abs()),
        "{d2} {}",
        v.d2
    );
}

#[test]
fn tanh_matches_eq51_and_derivatives() {
    let st = Stiffness::paper_sec5(0.5);
    let p = st.validate().unwrap();
    for &sigma in &[0.0f64, 0.1, 0.29, 0.3, 0.31, 0.5, 0.79, 0.8, 0.95] {
        let eq51 = 1.0 - 0.25 * ((200.0 * (sigma - 0.3)).tanh() - (200.0 * (sigma - 0.8)).tanh());
        assert!((p.eval(sigma).d - eq51).abs() < 1e-14, "{sigma}");
    }
    let soft = Stiffness::Tanh {
        d0: 1.0,
        d1: 0.1,
        s0: 0.3,
        s1: 0.8,
        gamma: 7.0,
    }
    .validate()
    .unwrap();
    for &sigma in &[0.0, 0.05, 0.3, 0.55, 0.99] {
        fd_check(&soft, sigma);
    }
    // Periodic: value and slope agree across σ = 0.
    let (a, b) = (soft.eval(1e-12), soft.eval(1.0 - 1e-12));
    assert!((a.d - b.d).abs() < 1e-9 && (a.d1 - b.d1).abs() < 1e-8);
}

#[test]
fn table_spline_interpolates_and_is_periodic() {
    let s: Vec<f64> = (0..12).map(|i| (i as f64 + 0.3) / 12.0).collect();
    let d: Vec<f64> = s
        .iter()
        .map(|&x| 1.0 + 0.3 * (2.0 * std::f64::consts::PI * x).sin())
        .collect();
    let p = Stiffness::Table {
        s: s.clone(),
        d: d.clone(),
    }
    .validate()
    .unwrap();
    for i in 0..s.len() {
        assert!((p.eval(s[i]).d - d[i]).abs() < 1e-14);
    }
    for &sigma in &[0.0, 0.01, 0.5, 0.999] {
        fd_check(&p, sigma);
        let exact = 1.0 + 0.3 * (2.0 * std::f64::consts::PI * sigma).sin();
        assert!((p.eval(sigma).d - exact).abs() < 1e-3);
    }
}

/// A step table between 1 and 0.01: a periodic cubic spline undershoots it to
/// D = −0.0041 near s/L = 0.32; the shape-preserving interpolant stays within the data
/// range between every pair of knots, and is continuous with a continuous slope.
#[test]
fn step_table_does_not_overshoot() {
    let s: Vec<f64> = (0..20).map(|i| i as f64 / 20.0).collect();
    let d: Vec<f64> = s
        .iter()
        .map(|&x| if (0.3..0.8).contains(&x) { 0.01 } else { 1.0 })
        .collect();
    let p = Stiffness::Table {
        s: s.clone(),
        d: d.clone(),
    }
    .validate()
    .unwrap();
    let n = s.len();
    for k in 0..20_000 {
        let sigma = k as f64 / 20_000.0;
        let (i, _, _) = locate(&s, sigma);
        let (lo, hi) = (d[i].min(d[(i + 1) % n]), d[i].max(d[(i + 1) % n]));
        let v = p.eval(sigma).d;
        assert!(
            v >= lo - 1e-15 && v <= hi + 1e-15,
            "D = {v} at {sigma} outside [{lo}, {hi}]"
        );
    }
    // Continuity of D and D' across every knot (D'' may jump there).
    for &x in &s {
        let (a, b) = (p.eval(x - 1e-12), p.eval(x + 1e-12));
        assert!(
            (a.d - b.d).abs() < 1e-9 && (a.d1 - b.d1).abs() < 1e-6,
            "{x}"
        );
    }
    // Between knots, the derivatives agree with finite differences.
    for &sigma in &[0.027, 0.31, 0.333, 0.79, 0.812, 0.97] {
        fd_check(&p, sigma);
    }
}

/// The interpolant passes through the knots, and monotone stretches of the data give a
/// monotone interpolant.
#[test]
fn monotone_data_monotone_interpolant() {
    let s = vec![0.0, 0.1, 0.35, 0.5, 0.9];
    let d = vec![1.0, 1.5, 4.0, 4.1, 2.0];
    let p = Stiffness::Table {
        s: s.clone(),
        d: d.clone(),
    }
    .validate()
    .unwrap();
    for (i, (&x, &y)) in s.iter().zip(&d).enumerate() {
        assert!((p.eval(x).d - y).abs() < 1e-14, "knot {i}");
    }
    // Increasing on [0, 0.5], decreasing on [0.5, 1): check the slope's sign.
    for k in 1..1000 {
        let sigma = k as f64 / 1000.0;
        let v = p.eval(sigma);
        if sigma < 0.5 {
            assert!(v.d1 >= -1e-12, "{sigma}: {}", v.d1);
        } else {
            assert!(v.d1 <= 1e-12, "{sigma}: {}", v.d1);
        }
    }
}

#[test]
fn invalid_profiles_are_rejected() {
    let cases = vec![
        Stiffness::Uniform { d: 0.0 },
        Stiffness::Uniform { d: f64::NAN },
        Stiffness::Tanh {
            d0: 1.0,
            d1: 0.5,
            s0: 0.8,
            s1: 0.3,
            gamma: 200.0,
        },
        Stiffness::Tanh {
            d0: 1.0,
            d1: -0.5,
            s0: 0.3,
            s1: 0.8,
            gamma: 200.0,
        },
        Stiffness::Table {
            s: vec![0.0, 0.5, 0.4],
            d: vec![1.0, 1.0, 1.0],
        },
        Stiffness::Table {
            s: vec![0.0, 0.5, 0.7],
            d: vec![1.0, 1.0],
        },
        Stiffness::Table {
            s: vec![0.0, 0.3, 0.6],
            d: vec![1.0, -1.0, 1.0],
        },
    ];
    for c in cases {
        assert!(
            matches!(c.validate(), Err(SolverError::InvalidProfile(_))),
            "{c:?}"
        );
    }
}
