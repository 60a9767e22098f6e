//! Large structured problems with a custom O(n) `Factorization`: discretised 1-D
//! Bratu (`u'' + p eᵘ = 0`) through its fold, and the discretised elastica
//! (`u'' + p sin u = 0`) through branch points of its trivial branch, both with a
//! tridiagonal LU with partial pivoting implemented here.

use std::cell::Cell;
use std::convert::Infallible;
use std::time::Instant;

use nalgebra::{DMatrix, DVector};
use rodloop_continuation::{
    newton, Continuation, Direction, Factorization, Problem, PseudoArclength, SpecialKind,
    StopReason,
};

/// LU factorisation with partial pivoting of a tridiagonal matrix (the algorithm of
/// LAPACK's `dgttrf`, written from its description): `U` has two superdiagonals.
struct TridiagLu {
    /// The matrix: subdiagonal, diagonal, superdiagonal.
    sub: Vec<f64>,
    diag: Vec<f64>,
    sup: Vec<f64>,
    /// Multipliers, diagonal of U, first and second superdiagonal of U, interchanges.
    l: Vec<f64>,
    d: Vec<f64>,
    u1: Vec<f64>,
    u2: Vec<f64>,
    swapped: Vec<bool>,
}

impl TridiagLu {
    fn new(sub: Vec<f64>, diag: Vec<f64>, sup: Vec<f64>) -> Self {
        let n = diag.len();
        let (mut l, mut d, mut u1) = (sub.clone(), diag.clone(), sup.clone());
        let mut u2 = vec![0.0; n.saturating_sub(2)];
        let mut swapped = vec![false; n.saturating_sub(1)];
        for i in 0..n.saturating_sub(1) {
            if d[i].abs() >= l[i].abs() {
                let f = if d[i] != 0.0 { l[i] / d[i] } else { 0.0 };
                l[i] = f;
                d[i + 1] -= f * u1[i];
            } else {
                // Rows i and i+1 exchange: row i becomes (l_i, d_{i+1}, u1_{i+1}).
                let f = d[i] / l[i];
                d[i] = l[i];
                l[i] = f;
                let old_u1 = u1[i];
                u1[i] = d[i + 1];
                d[i + 1] = old_u1 - f * d[i + 1];
                if i + 2 < n {
                    u2[i] = u1[i + 1];
                    u1[i + 1] = -f * u2[i];
                }
                swapped[i] = true;
            }
        }
        TridiagLu {
            sub,
            diag,
            sup,
            l,
            d,
            u1,
            u2,
            swapped,
        }
    }
}

impl Factorization for TridiagLu {
    fn solve(&self, b: &DVector<f64>) -> Option<DVector<f64>> {
        let n = self.d.len();
        if b.len() != n || self.d.contains(&0.0) {
            return None;
        }
        let mut y = b.clone();
        for i in 0..n.saturating_sub(1) {
            if self.swapped[i] {
                let t = y[i];
                y[i] = y[i + 1];
                y[i + 1] = t - self.l[i] * y[i];
            } else {
                y[i + 1] -= self.l[i] * y[i];
            }
        }
        for i in (0..n).rev() {
            let mut v = y[i];
            if i + 1 < n {
                v -= self.u1[i] * y[i + 1];
            }
            if i + 2 < n {
                v -= self.u2[i] * y[i + 2];
            }
            y[i] = v / self.d[i];
        }
        y.iter().all(|v| v.is_finite()).then_some(y)
    }

    fn apply(&self, v: &DVector<f64>) -> DVector<f64> {
        let n = self.diag.len();
        DVector::from_fn(n, |i, _| {
            let mut s = self.diag[i] * v[i];
            if i > 0 {
                s += self.sub[i - 1] * v[i - 1];
            }
            if i + 1 < n {
                s += self.sup[i] * v[i + 1];
            }
            s
        })
    }

    fn det_sign(&self) -> f64 {
        if self.d.contains(&0.0) {
            return 0.0;
        }
        let neg = self.d.iter().filter(|v| **v < 0.0).count()
            + self.swapped.iter().filter(|s| **s).count();
        if neg % 2 == 0 {
            1.0
        } else {
            -1.0
        }
    }

    fn log_abs_det(&self) -> f64 {
        self.d.iter().map(|v| v.abs().ln()).sum()
    }
}

#[derive(Clone, Copy)]
enum Nonlinearity {
    /// `p eᵘ` (Bratu).
    Bratu,
    /// `p sin u` (elastica).
    Elastica,
}

/// `F_i = (u_{i−1} − 2u_i + u_{i+1}) / h² + g(u_i, p)`, `u_0 = u_{n+1} = 0`,
/// `h = 1/(n+1)`: central differences for `u'' + g(u, p) = 0` on `(0, 1)` with
/// Dirichlet conditions.
struct Discretised {
    n: usize,
    g: Nonlinearity,
    /// Use the tridiagonal factorisation (otherwise the default dense LU).
    tridiagonal: bool,
    /// Number of dense Jacobians requested (dense path or fallback).
    dense_jacobians: Cell<usize>,
}

impl Discretised {
    fn new(n: usize, g: Nonlinearity, tridiagonal: bool) -> Self {
        Discretised {
            n,
            g,
            tridiagonal,
            dense_jacobians: Cell::new(0),
        }
    }
    fn h(&self) -> f64 {
        1.0 / (self.n as f64 + 1.0)
    }
    /// `(g, ∂g/∂u, ∂g/∂p)` at `(u, p)`.
    fn g(&self, u: f64, p: f64) -> (f64, f64, f64) {
        match self.g {
            Nonlinearity::Bratu => {
                let e = u.exp();
                (p * e, p * e, e)
            }
            Nonlinearity::Elastica => (p * u.sin(), p * u.cos(), u.sin()),
        }
    }
    fn bands(&self, x: &DVector<f64>, p: f64) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let c = 1.0 / (self.h() * self.h());
        let off = vec![c; self.n - 1];
        let diag = (0..self.n).map(|i| -2.0 * c + self.g(x[i], p).1).collect();
        (off.clone(), diag, off)
    }
}

impl Problem for Discretised {
    type Error = Infallible;
    fn dim(&self) -> usize {
        self.n
    }
    fn residual(&self, x: &DVector<f64>, p: f64) -> Result<DVector<f64>, Infallible> {
        let n = self.n;
        let c = 1.0 / (self.h() * self.h());
        Ok(DVector::from_fn(n, |i, _| {
            let left = if i > 0 { x[i - 1] } else { 0.0 };
            let right = if i + 1 < n { x[i + 1] } else { 0.0 };
            (left - 2.0 * x[i] + right) * c + self.g(x[i], p).0
        }))
    }
    fn jacobian(&self, x: &DVector<f64>, p: f64) -> Result<DMatrix<f64>, Infallible> {
        self.dense_jacobians.set(self.dense_jacobians.get() + 1);
        let (sub, diag, sup) = self.bands(x, p);
        let n = self.n;
        let mut j = DMatrix::zeros(n, n);
        for i in 0..n {
            j[(i, i)] = diag[i];
            if i + 1 < n {
                j[(i + 1, i)] = sub[i];
                j[(i, i + 1)] = sup[i];
            }
        }
        Ok(j)
    }
    fn dparam(&self, x: &DVector<f64>, p: f64) -> Result<DVector<f64>, Infallible> {
        Ok(DVector::from_fn(self.n, |i, _| self.g(x[i], p).2))
    }
    fn factorize(
        &self,
        x: &DVector<f64>,
        p: f64,
    ) -> Result<Box<dyn Factorization + '_>, Infallible> {
        if !self.tridiagonal {
            let j = self.jacobian(x, p)?;
            return Ok(Box::new(rodloop_continuation::DenseLu::new(j)));
        }
        let (sub, diag, sup) = self.bands(x, p);
        Ok(Box::new(TridiagLu::new(sub, diag, sup)))
    }
}

/// The continuum Bratu fold: solutions `u = −2 ln(cosh((x − ½)θ/2) / cosh(θ/4))` with
/// `p = θ² / (2 cosh²(θ/4))`, maximal where `(θ/4) tanh(θ/4) = 1`.
fn continuum_bratu_fold() -> f64 {
    let theta = continuum_bratu_theta();
    theta * theta / (2.0 * (theta / 4.0).cosh().powi(2))
}

/// `θ` of the continuum Bratu fold: the root of `(θ/4) tanh(θ/4) = 1` (Newton).
fn continuum_bratu_theta() -> f64 {
    let mut z: f64 = 1.2; // z = θ/4
    for _ in 0..50 {
        let f = z * z.tanh() - 1.0;
        let df = z.tanh() + z / z.cosh().powi(2);
        z -= f / df;
    }
    4.0 * z
}

/// The fold of the *discrete* Bratu problem with `n` unknowns, by shooting, without
/// any continuation: the solution with `u_0 = 0`, `u_1 = s` of the recurrence
/// `u_{i+1} = 2u_i − u_{i−1} − h² p e^{u_i}` must end with `u_{n+1} = 0`; for each `s`
/// that fixes `p(s)` (bisection), and the fold is `max_s p(s)` (golden section).
fn discrete_bratu_fold(n: usize) -> f64 {
    let h = 1.0 / (n as f64 + 1.0);
    let end = |s: f64, p: f64| {
        let (mut um, mut u) = (0.0, s);
        for _ in 1..=n {
            let next = 2.0 * u - um - h * h * p * u.exp();
            um = u;
            u = next;
        }
        u
    };
    let p_of_s = |s: f64| {
        let (mut lo, mut hi) = (0.0, 10.0);
        assert!(end(s, lo) > 0.0 && end(s, hi) < 0.0);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if end(s, mid) > 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    };
    // u'(0) = 4 at the continuum fold; bracket the slope generously.
    let (mut a, mut b) = (2.0 * h, 6.0 * h);
    let r = 0.5 * (5f64.sqrt() - 1.0);
    let (mut c, mut d) = (b - r * (b - a), a + r * (b - a));
    let (mut fc, mut fd) = (p_of_s(c), p_of_s(d));
    for _ in 0..80 {
        if fc > fd {
            b = d;
            d = c;
            fd = fc;
            c = b - r * (b - a);
            fc = p_of_s(c);
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + r * (b - a);
            fd = p_of_s(d);
        }
    }
    fc.max(fd)
}

fn bratu_settings(n: usize) -> PseudoArclength {
    // Unknowns are nodal values, so the branch from u = 0 to the fold has length
    // ≈ ‖u_fold‖₂ ≈ √n; the step bounds scale with it. The residual contains
    // differences of size ~4|u|/h², whose rounding error ε·4|u|/h² limits the
    // attainable tolerance (≈ 5e-9 at n = 2000).
    let h = 1.0 / (n as f64 + 1.0);
    let tol = (1e3 * f64::EPSILON * 4.0 / (h * h)).max(1e-10);
    PseudoArclength::new()
        .with_ds(0.5)
        .unwrap()
        .with_ds_bounds(1e-8, 0.2 * (n as f64).sqrt())
        .unwrap()
        .with_range(0.5, 4.0)
        .unwrap()
        .with_tol(tol)
        .unwrap()
        .with_direction(Direction::Forward)
        .unwrap()
}

/// Steps until the first fold, returning it and the seconds it took.
fn trace_to_fold(problem: &Discretised) -> (rodloop_continuation::SpecialPoint, f64) {
    let t0 = Instant::now();
    let cont = Continuation::new(problem, bratu_settings(problem.n));
    let mut stepper = cont.start(&DVector::zeros(problem.n), 0.5).unwrap();
    loop {
        let step = stepper.step().unwrap();
        if let Some(f) = step.special.iter().find(|s| s.kind == SpecialKind::Fold) {
            return (f.clone(), t0.elapsed().as_secs_f64());
        }
        assert!(
            step.stop.is_none(),
            "stopped before the fold: {:?}",
            step.stop
        );
    }
}

#[test]
fn bratu_fold_with_tridiagonal_factorisation_n2000() {
    let n = 2000;
    let problem = Discretised::new(n, Nonlinearity::Bratu, true);
    let (fold, secs) = trace_to_fold(&problem);
    let p_discrete = discrete_bratu_fold(n);
    let p_continuum = continuum_bratu_fold();
    let h = problem.h();
    eprintln!(
        "Bratu n = {n}: fold p = {:.12} in {secs:.3} s (continuation); discrete shooting \
         {p_discrete:.12}; continuum {p_continuum:.12}; dense Jacobians {}",
        fold.p,
        problem.dense_jacobians.get()
    );
    // The continuum value is the classical one.
    assert!((p_continuum - 3.513830719).abs() < 1e-9);
    // The continuation finds the fold of the discrete problem, computed independently.
    assert!(
        (fold.p - p_discrete).abs() < 1e-9,
        "{} vs {p_discrete}",
        fold.p
    );
    // Second-order discretisation: |p_h − p*| = O(h²). The discrete Laplacian
    // underestimates the first eigenvalue by the relative amount π²h²/12, which
    // suggests |p_h − p*| of order (π²/12) p* h² ≈ 2.9 h²; allow a factor 2.
    let err = (fold.p - p_continuum).abs();
    eprintln!(
        "Bratu n = {n}: |p_h − p*| = {err:e} = {:.3} h²",
        err / (h * h)
    );
    assert!(err < 6.0 * h * h && err > 0.0);
    // At the fold u(1/2) = 2 ln cosh(θ/4) ≈ 1.18684 (nodes lie h/2 off the middle).
    let mid = fold.x[n / 2].max(fold.x[n / 2 - 1]);
    let mid_exact = 2.0 * (continuum_bratu_theta() / 4.0).cosh().ln();
    assert!(
        (mid - mid_exact).abs() < 1e-5,
        "u(1/2) = {mid}, {mid_exact}"
    );
    // The structured path did all the work: no dense Jacobian was ever formed.
    assert_eq!(problem.dense_jacobians.get(), 0);
}

#[test]
fn bratu_tridiagonal_agrees_with_dense_n200() {
    let n = 200;
    let fast = Discretised::new(n, Nonlinearity::Bratu, true);
    let dense = Discretised::new(n, Nonlinearity::Bratu, false);
    let t0 = Instant::now();
    let bf = bratu_settings(n)
        .run(&fast, &DVector::zeros(n), 0.5)
        .unwrap();
    let t_fast = t0.elapsed().as_secs_f64();
    let t0 = Instant::now();
    let bd = bratu_settings(n)
        .run(&dense, &DVector::zeros(n), 0.5)
        .unwrap();
    let t_dense = t0.elapsed().as_secs_f64();
    eprintln!(
        "Bratu n = {n}: tridiagonal {t_fast:.4} s ({} points), dense {t_dense:.4} s ({} points)",
        bf.points.len(),
        bd.points.len()
    );
    // Up the lower branch, round the fold, down the upper branch to p = 1/2.
    for b in [&bf, &bd] {
        assert_eq!(b.stop, StopReason::LeftRange { boundary: 0.5 });
        assert_eq!(b.folds().count(), 1);
        assert_eq!(b.branch_points().count(), 0);
    }
    let (ff, fd) = (bf.folds().next().unwrap(), bd.folds().next().unwrap());
    let dx = (&ff.x - &fd.x).amax();
    eprintln!("fold: |Δp| = {:e}, |Δx|∞ = {dx:e}", (ff.p - fd.p).abs());
    assert!((ff.p - fd.p).abs() < 1e-11 && dx < 1e-7);
    assert!((ff.p - discrete_bratu_fold(n)).abs() < 1e-9);
    // The end points (solved at p = 1/2 exactly on the upper branch) agree.
    let (lf, ld) = (bf.last().unwrap(), bd.last().unwrap());
    assert_eq!((lf.p, ld.p), (0.5, 0.5));
    assert!((&lf.x - &ld.x).amax() < 1e-9);
    // Upper branch at p = 1/2: θ = cosh(θ/4), i.e. θ = 4 arcosh θ, has the large root
    // θ ≈ 13.0, where u(1/2) = 2 ln cosh(θ/4) = 2 ln θ ≈ 5.14; the boundary layers are
    // steep there, so allow for a discretisation error of O(θ² h²).
    let mut theta: f64 = 10.0;
    for _ in 0..100 {
        theta = 4.0 * theta.acosh();
    }
    let mid = 2.0 * (theta / 4.0).cosh().ln();
    eprintln!(
        "upper branch at p = 1/2: u(1/2) = {}, continuum {mid}",
        lf.x[n / 2]
    );
    assert!((lf.x[n / 2].max(lf.x[n / 2 - 1]) - mid).abs() < 2e-3);
    // The same step sequence.
    assert_eq!(bf.points.len(), bd.points.len());
    let worst = bf
        .points
        .iter()
        .zip(&bd.points)
        .map(|(a, b)| (&a.x - &b.x).amax().max((a.p - b.p).abs()))
        .fold(0.0, f64::max);
    eprintln!("Bratu n = {n}: max point difference {worst:e}");
    assert!(worst < 1e-8);
    assert_eq!(fast.dense_jacobians.get(), 0);
}

#[test]
fn elastica_branch_points_with_tridiagonal_factorisation() {
    // Trivial branch u = 0 of u'' + p sin u = 0: J = D + p I (D the discrete
    // Laplacian) is singular at the eigenvalues p_k = (4/h²) sin²(kπh/2) of −D, where
    // F_p = sin u = 0 as well: simple branch points (buckling loads).
    let n = 400;
    let problem = Discretised::new(n, Nonlinearity::Elastica, true);
    let h = problem.h();
    let p_k = |k: f64| 4.0 / (h * h) * (k * std::f64::consts::PI * h / 2.0).sin().powi(2);
    let settings = PseudoArclength::new()
        .with_ds(0.5)
        .unwrap()
        .with_ds_bounds(1e-8, 2.0)
        .unwrap()
        .with_range(0.0, 45.0)
        .unwrap();
    let cont = Continuation::new(&problem, settings);
    let branch = cont.run(&DVector::zeros(n), 0.0).unwrap();
    let bps: Vec<_> = branch.branch_points().collect();
    assert_eq!(bps.len(), 2, "{:?}", branch.special);
    for (bp, k) in bps.iter().zip([1.0, 2.0]) {
        let err = (bp.p - p_k(k)).abs();
        eprintln!(
            "elastica BP {k}: p = {:.10}, exact {:.10}, |Δ| = {err:e}",
            bp.p,
            p_k(k)
        );
        assert!(err < 1e-8 * p_k(k));
        assert!(bp.x.amax() < 1e-12);
    }
    assert_eq!(branch.folds().count(), 0);
    assert_eq!(branch.stop, StopReason::LeftRange { boundary: 45.0 });
}

#[test]
fn newton_uses_the_custom_factorisation() {
    let n = 1000;
    let problem = Discretised::new(n, Nonlinearity::Bratu, true);
    // Lower Bratu branch at p = 1 from u = 0.
    let (x, report) = newton(&problem, &DVector::zeros(n), 1.0, 1e-10, 20).unwrap();
    assert!(report.residual_norm <= 1e-10 && report.iterations >= 2);
    // u(1/2) on the lower branch at p = 1: θ = √2 cosh(θ/4), u(½) = 2 ln cosh(θ/4).
    let mut theta: f64 = 1.5;
    for _ in 0..100 {
        theta = 2f64.sqrt() * (theta / 4.0).cosh();
    }
    let mid = 2.0 * (theta / 4.0).cosh().ln();
    assert!((x[n / 2] - mid).abs() < 1e-5, "{} vs {mid}", x[n / 2]);
    assert_eq!(problem.dense_jacobians.get(), 0);
}

/// Timing of the tridiagonal against the dense factorisation (run with `--ignored`).
#[test]
#[ignore = "timing report, slow with the dense factorisation"]
fn bratu_timing_report() {
    for (n, dense_too) in [(200, true), (500, true), (2000, false), (20000, false)] {
        let fast = Discretised::new(n, Nonlinearity::Bratu, true);
        let t0 = Instant::now();
        let b = bratu_settings(n)
            .run(&fast, &DVector::zeros(n), 0.5)
            .unwrap();
        let t_fast = t0.elapsed().as_secs_f64();
        let fold = b.folds().next().map(|f| f.p).unwrap_or(f64::NAN);
        eprintln!(
            "n = {n}: tridiagonal {t_fast:.4} s, {} points, fold p = {fold:.12}",
            b.points.len()
        );
        if dense_too {
            let dense = Discretised::new(n, Nonlinearity::Bratu, false);
            let t0 = Instant::now();
            let b = bratu_settings(n)
                .run(&dense, &DVector::zeros(n), 0.5)
                .unwrap();
            eprintln!(
                "n = {n}: dense LU {:.4} s, {} points",
                t0.elapsed().as_secs_f64(),
                b.points.len()
            );
        }
    }
}

/// A factorisation that always fails (as a structured solver might on a pivot
/// breakdown).
struct Broken;

impl Factorization for Broken {
    fn solve(&self, _b: &DVector<f64>) -> Option<DVector<f64>> {
        None
    }
    fn apply(&self, v: &DVector<f64>) -> DVector<f64> {
        v.map(|_| f64::NAN)
    }
    fn det_sign(&self) -> f64 {
        1.0
    }
    fn log_abs_det(&self) -> f64 {
        0.0
    }
}

/// Bratu whose factorisation always fails.
struct BrokenBratu(Discretised);

impl Problem for BrokenBratu {
    type Error = Infallible;
    fn dim(&self) -> usize {
        self.0.dim()
    }
    fn residual(&self, x: &DVector<f64>, p: f64) -> Result<DVector<f64>, Infallible> {
        self.0.residual(x, p)
    }
    fn jacobian(&self, x: &DVector<f64>, p: f64) -> Result<DMatrix<f64>, Infallible> {
        self.0.jacobian(x, p)
    }
    fn dparam(&self, x: &DVector<f64>, p: f64) -> Result<DVector<f64>, Infallible> {
        self.0.dparam(x, p)
    }
    fn factorize(
        &self,
        _x: &DVector<f64>,
        _p: f64,
    ) -> Result<Box<dyn Factorization + '_>, Infallible> {
        Ok(Box::new(Broken))
    }
}

#[test]
fn failing_factorisation_falls_back_to_dense_bordered_lu() {
    let n = 60;
    let broken = BrokenBratu(Discretised::new(n, Nonlinearity::Bratu, true));
    let fine = Discretised::new(n, Nonlinearity::Bratu, true);
    // The continuation itself still works (dense bordered LU throughout) …
    let bb = bratu_settings(n)
        .run(&broken, &DVector::zeros(n), 0.5)
        .unwrap();
    let bf = bratu_settings(n)
        .run(&fine, &DVector::zeros(n), 0.5)
        .unwrap();
    assert!(broken.0.dense_jacobians.get() > 0);
    assert_eq!(bb.stop, StopReason::LeftRange { boundary: 0.5 });
    let (fb, ff) = (bb.folds().next().unwrap(), bf.folds().next().unwrap());
    assert!((fb.p - ff.p).abs() < 1e-12 && (&fb.x - &ff.x).amax() < 1e-8);
    // … and so does Newton at fixed p (dense LU of the Jacobian).
    let (xb, _) = newton(&broken, &DVector::zeros(n), 1.0, 1e-10, 20).unwrap();
    let (xf, _) = newton(&fine, &DVector::zeros(n), 1.0, 1e-10, 20).unwrap();
    assert!((xb - xf).amax() < 1e-12);
    assert_eq!(fine.dense_jacobians.get(), 0);
}
