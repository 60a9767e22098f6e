//! Second-order jets (value, gradient, Hessian in `K` variables) and the fourth-order Magnus
//! propagator of a cell in SE(3) with its exact first and second derivatives.
//!
//! The state of a point of the rod is the 4×4 matrix `G = [[X, r], [0, 1]]` whose rotation
//! block has the columns `t, d1, d2` (tangent and the two rotation-minimising (Bishop)
//! directors, world coordinates) and whose last column holds the position `r`. For an
//! untwisted rod with curvature vector `κ1 d1 + κ2 d2` (paper Sec. 2, Kirchhoff rod without
//! twist) the frame and the position obey `G' = G ξ(s)` with the body twist
//! `ξ = [[hat(w), e1], [0, 0]]`, `w = (0, −κ2, κ1)` (Darboux vector `t × κ` in body
//! coordinates) and the unit translational velocity `e1` (`r' = t`, inextensibility).
//!
//! On a sphere of radius `R` the Darboux frame (App. A, `t' = κ_g g − n/R`) is such a frame
//! with `κ1 = κ_g`, `κ2 = −1/R`, `d2 = n = r/R`: the surface model is the special case
//! `κ2 ≡ −1/R` of this one.
//!
//! One Magnus step of the two-point Gauss scheme (right-multiplied form of
//! [`crate::frame`]): `G(s + h) = G(s) exp(Θ)`, `Θ = (h/2)(ξ1 + ξ2) + (√3/12) h² [ξ1, ξ2]`,
//! with `ξ1, ξ2` at the Gauss points. In SE(3), `[ξ1, ξ2] = [[hat(w1 × w2), (w1 − w2) × e1],
//! [0, 0]]`, so `Θ = [[hat(ω), v], [0, 0]]` with
//! `ω = (C h²(κ1a κ2b − κ2a κ1b), −(h/2)(κ2a + κ2b), (h/2)(κ1a + κ1b))`,
//! `v = (h, C h²(κ1a − κ1b), C h²(κ2a − κ2b))`, `C = √3/12`, and
//! `exp(Θ) = [[I + aW + bW², (I + bW + cW²) v], [0, 1]]`, `W = hat(ω)`, `θ = |ω|`,
//! `a = sin θ/θ`, `b = (1 − cos θ)/θ²`, `c = (θ − sin θ)/θ³`. Frame and position are both
//! fourth-order accurate (the Magnus scheme applies to any linear matrix ODE).

#![allow(clippy::needless_range_loop)] // index arithmetic over cells, nodes and unknowns

use nalgebra::Matrix4;

use crate::frame::rodrigues_coefficients;

/// `√3/12`, the Magnus commutator coefficient.
pub const MAGNUS_C: f64 = 0.144_337_567_297_406_43;

/// A scalar with its gradient and Hessian in `K` variables.
#[derive(Clone, Copy, Debug)]
pub struct Jet<const K: usize> {
    /// Value.
    pub v: f64,
    /// Gradient.
    pub g: [f64; K],
    /// Hessian (symmetric, fully stored).
    pub h: [[f64; K]; K],
}

impl<const K: usize> Jet<K> {
    /// A constant.
    pub fn cst(v: f64) -> Self {
        Self {
            v,
            g: [0.0; K],
            h: [[0.0; K]; K],
        }
    }

    /// The variable `i` with value `v`.
    pub fn var(i: usize, v: f64) -> Self {
        let mut j = Self::cst(v);
        j.g[i] = 1.0;
        j
    }

    /// `self + o`.
    pub fn add(&self, o: &Self) -> Self {
        let mut r = *self;
        r.v += o.v;
        for i in 0..K {
            r.g[i] += o.g[i];
            for j in 0..K {
                r.h[i][j] += o.h[i][j];
            }
        }
        r
    }

    /// `self − o`.
    pub fn sub(&self, o: &Self) -> Self {
        self.add(&o.scale(-1.0))
    }

    /// `s · self`.
    pub fn scale(&self, s: f64) -> Self {
        let mut r = *self;
        r.v *= s;
        for i in 0..K {
            r.g[i] *= s;
            for j in 0..K {
                r.h[i][j] *= s;
            }
        }
        r
    }

    /// `self · o` (product rule to second order).
    pub fn mul(&self, o: &Self) -> Self {
        let mut r = Self::cst(self.v * o.v);
        for i in 0..K {
            r.g[i] = self.g[i] * o.v + self.v * o.g[i];
            for j in 0..K {
                r.h[i][j] = self.h[i][j] * o.v
                    + self.v * o.h[i][j]
                    + self.g[i] * o.g[j]
                    + self.g[j] * o.g[i];
            }
        }
        r
    }

    /// `f(self)` given `f, f', f''` at `self.v`.
    pub fn compose(&self, f: f64, f1: f64, f2: f64) -> Self {
        let mut r = Self::cst(f);
        for i in 0..K {
            r.g[i] = f1 * self.g[i];
            for j in 0..K {
                r.h[i][j] = f2 * self.g[i] * self.g[j] + f1 * self.h[i][j];
            }
        }
        r
    }
}

/// A scalar with its gradient in `K` variables (first-order jet): the residual needs the
/// cell propagators' first derivatives only, and skipping the Hessians makes a residual
/// evaluation (line search) about three times cheaper than [`Jet`].
#[derive(Clone, Copy, Debug)]
pub struct Grad<const K: usize> {
    /// Value.
    pub v: f64,
    /// Gradient.
    pub g: [f64; K],
}

/// The arithmetic [`cell_jet`] and [`cell_grad`] share.
trait JetOps: Copy {
    fn cst(v: f64) -> Self;
    fn var(i: usize, v: f64) -> Self;
    fn value(&self) -> f64;
    fn add(&self, o: &Self) -> Self;
    fn sub(&self, o: &Self) -> Self;
    fn scale(&self, s: f64) -> Self;
    fn mul(&self, o: &Self) -> Self;
    fn compose(&self, f: f64, f1: f64, f2: f64) -> Self;
}

impl<const K: usize> JetOps for Jet<K> {
    fn cst(v: f64) -> Self {
        Jet::cst(v)
    }
    fn var(i: usize, v: f64) -> Self {
        Jet::var(i, v)
    }
    fn value(&self) -> f64 {
        self.v
    }
    fn add(&self, o: &Self) -> Self {
        Jet::add(self, o)
    }
    fn sub(&self, o: &Self) -> Self {
        Jet::sub(self, o)
    }
    fn scale(&self, s: f64) -> Self {
        Jet::scale(self, s)
    }
    fn mul(&self, o: &Self) -> Self {
        Jet::mul(self, o)
    }
    fn compose(&self, f: f64, f1: f64, f2: f64) -> Self {
        Jet::compose(self, f, f1, f2)
    }
}

impl<const K: usize> JetOps for Grad<K> {
    fn cst(v: f64) -> Self {
        Self { v, g: [0.0; K] }
    }
    fn var(i: usize, v: f64) -> Self {
        let mut j = Self { v, g: [0.0; K] };
        j.g[i] = 1.0;
        j
    }
    fn value(&self) -> f64 {
        self.v
    }
    fn add(&self, o: &Self) -> Self {
        let mut r = *self;
        r.v += o.v;
        for i in 0..K {
            r.g[i] += o.g[i];
        }
        r
    }
    fn sub(&self, o: &Self) -> Self {
        let mut r = *self;
        r.v -= o.v;
        for i in 0..K {
            r.g[i] -= o.g[i];
        }
        r
    }
    fn scale(&self, s: f64) -> Self {
        let mut r = *self;
        r.v *= s;
        for i in 0..K {
            r.g[i] *= s;
        }
        r
    }
    fn mul(&self, o: &Self) -> Self {
        let mut r = Self {
            v: self.v * o.v,
            g: [0.0; K],
        };
        for i in 0..K {
            r.g[i] = self.g[i] * o.v + self.v * o.g[i];
        }
        r
    }
    fn compose(&self, f: f64, f1: f64, _f2: f64) -> Self {
        let mut r = Self { v: f, g: [0.0; K] };
        for i in 0..K {
            r.g[i] = f1 * self.g[i];
        }
        r
    }
}

/// `c(q) = (θ − sin θ)/θ³` (`q = θ²`) with `c'(q)`, `c''(q)`: Maclaurin series
/// `Σ (−q)^k/(2k+3)!` for `q < 1`, otherwise `c = (1 − a)/q`, `c' = −(a' + c)/q`,
/// `c'' = −(a'' + 2c')/q` with `a = sin θ/θ`.
pub fn third_coefficient(q: f64) -> [f64; 3] {
    if q < 1.0 {
        let mut out = [0.0; 3];
        let mut fact = 6.0; // (2k+3)!
        let mut pw = [1.0; 20];
        for k in 1..20 {
            pw[k] = pw[k - 1] * (-q);
        }
        for k in 0..18 {
            let kf = k as f64;
            out[0] += pw[k] / fact;
            if k >= 1 {
                out[1] += -kf * pw[k - 1] / fact;
            }
            if k >= 2 {
                out[2] += kf * (kf - 1.0) * pw[k - 2] / fact;
            }
            fact *= (2.0 * kf + 4.0) * (2.0 * kf + 5.0);
        }
        out
    } else {
        let [a, a1, a2, ..] = rodrigues_coefficients(q);
        let c = (1.0 - a) / q;
        let c1 = -(a1 + c) / q;
        let c2 = -(a2 + 2.0 * c1) / q;
        [c, c1, c2]
    }
}

/// A cell propagator `exp(Θ)` and its derivatives with respect to the four cell unknowns
/// `(κ1a, κ2a, κ1b, κ2b)` (Gauss points a, b).
#[derive(Clone, Debug)]
pub struct CellJet {
    /// `exp(Θ)`.
    pub e: Matrix4<f64>,
    /// First derivatives.
    pub d: [Matrix4<f64>; 4],
    /// Second derivatives (symmetric in the two indices).
    pub dd: [[Matrix4<f64>; 4]; 4],
}

/// `Θ`'s rotation vector `ω` and translation `v` as jets of the cell unknowns.
fn theta_jets<J: JetOps>(h: f64, x: [f64; 4]) -> ([J; 3], [J; 3]) {
    let k1a = J::var(0, x[0]);
    let k2a = J::var(1, x[1]);
    let k1b = J::var(2, x[2]);
    let k2b = J::var(3, x[3]);
    let ch2 = MAGNUS_C * h * h;
    let om = [
        k1a.mul(&k2b).sub(&k2a.mul(&k1b)).scale(ch2),
        k2a.add(&k2b).scale(-0.5 * h),
        k1a.add(&k1b).scale(0.5 * h),
    ];
    let v = [
        J::cst(h),
        k1a.sub(&k1b).scale(ch2),
        k2a.sub(&k2b).scale(ch2),
    ];
    (om, v)
}

/// The upper 3×4 block of `exp(Θ)` (rotation and translation) as jets of the cell unknowns.
fn exp_entries<J: JetOps>(h: f64, x: [f64; 4]) -> [[J; 4]; 3] {
    let (om, v) = theta_jets::<J>(h, x);
    let q = om[0]
        .mul(&om[0])
        .add(&om[1].mul(&om[1]))
        .add(&om[2].mul(&om[2]));
    let [a0, a1, a2, b0, b1, b2] = rodrigues_coefficients(q.value());
    let [c0, c1, c2] = third_coefficient(q.value());
    let a = q.compose(a0, a1, a2);
    let b = q.compose(b0, b1, b2);
    let c = q.compose(c0, c1, c2);
    let zero = J::cst(0.0);
    let w = [
        [zero, om[2].scale(-1.0), om[1]],
        [om[2], zero, om[0].scale(-1.0)],
        [om[1].scale(-1.0), om[0], zero],
    ];
    let ov = om[0]
        .mul(&v[0])
        .add(&om[1].mul(&v[1]))
        .add(&om[2].mul(&v[2]));
    let cross = [
        om[1].mul(&v[2]).sub(&om[2].mul(&v[1])),
        om[2].mul(&v[0]).sub(&om[0].mul(&v[2])),
        om[0].mul(&v[1]).sub(&om[1].mul(&v[0])),
    ];
    let mut out = [[zero; 4]; 3];
    for i in 0..3 {
        for j in 0..3 {
            let mut m = a.mul(&w[i][j]).add(&b.mul(&om[i].mul(&om[j])));
            if i == j {
                m = m.sub(&b.mul(&q)).add(&J::cst(1.0));
            }
            out[i][j] = m;
        }
        out[i][3] = v[i]
            .add(&b.mul(&cross[i]))
            .add(&c.mul(&om[i].mul(&ov).sub(&q.mul(&v[i]))));
    }
    out
}

/// The propagator of a cell of length `h` with the four unknowns `x` only (no derivatives).
pub fn cell_exp(h: f64, x: [f64; 4]) -> Matrix4<f64> {
    let ch2 = MAGNUS_C * h * h;
    let om = [
        ch2 * (x[0] * x[3] - x[1] * x[2]),
        -0.5 * h * (x[1] + x[3]),
        0.5 * h * (x[0] + x[2]),
    ];
    let v = [h, ch2 * (x[0] - x[2]), ch2 * (x[1] - x[3])];
    let q = om[0] * om[0] + om[1] * om[1] + om[2] * om[2];
    let [a, _, _, b, _, _] = rodrigues_coefficients(q);
    let c = third_coefficient(q)[0];
    let ov = om[0] * v[0] + om[1] * v[1] + om[2] * v[2];
    let cross = [
        om[1] * v[2] - om[2] * v[1],
        om[2] * v[0] - om[0] * v[2],
        om[0] * v[1] - om[1] * v[0],
    ];
    let w = [
        [0.0, -om[2], om[1]],
        [om[2], 0.0, -om[0]],
        [-om[1], om[0], 0.0],
    ];
    let mut m = Matrix4::identity();
    for i in 0..3 {
        for j in 0..3 {
            let d = if i == j { 1.0 } else { 0.0 };
            m[(i, j)] = d + a * w[i][j] + b * (om[i] * om[j] - q * d);
        }
        m[(i, 3)] = v[i] + b * cross[i] + c * (om[i] * ov - q * v[i]);
    }
    m
}

/// The propagator from the start of a cell of length `h` to the fraction `theta ∈ [0, 1]` of
/// it, along the cell's curve: the curvature vector linear in `s` through its values `x` at
/// the two Gauss points, integrated by the same two-point Gauss Magnus step on `[0, θh]`
/// (the curvature interpolated to that interval's Gauss points). `theta = 1` is
/// [`cell_exp`]`(h, x)` exactly; points inside the cell carry the scheme's fourth order.
pub fn cell_exp_part(h: f64, x: [f64; 4], theta: f64) -> Matrix4<f64> {
    let [g1, g2] = crate::model::GAUSS_OFFSETS;
    let at = |u: f64| {
        let t = (u - g1) / (g2 - g1);
        [x[0] + t * (x[2] - x[0]), x[1] + t * (x[3] - x[1])]
    };
    let (a, b) = (at(theta * g1), at(theta * g2));
    cell_exp(theta * h, [a[0], a[1], b[0], b[1]])
}

/// The propagator of a cell of length `h` and its first and second derivatives with
/// respect to the cell unknowns `x = (κ1a, κ2a, κ1b, κ2b)`.
pub fn cell_jet(h: f64, x: [f64; 4]) -> CellJet {
    let ent = exp_entries::<Jet<4>>(h, x);
    let mut out = CellJet {
        e: Matrix4::identity(),
        d: [Matrix4::zeros(); 4],
        dd: [[Matrix4::zeros(); 4]; 4],
    };
    for i in 0..3 {
        for j in 0..4 {
            let jet = &ent[i][j];
            out.e[(i, j)] = jet.v;
            for p in 0..4 {
                out.d[p][(i, j)] = jet.g[p];
                for r in 0..4 {
                    out.dd[p][r][(i, j)] = jet.h[p][r];
                }
            }
        }
    }
    out
}

/// The propagator of a cell and its first derivatives only (see [`cell_jet`]).
pub fn cell_grad(h: f64, x: [f64; 4]) -> (Matrix4<f64>, [Matrix4<f64>; 4]) {
    let ent = exp_entries::<Grad<4>>(h, x);
    let mut e = Matrix4::identity();
    let mut d = [Matrix4::zeros(); 4];
    for i in 0..3 {
        for j in 0..4 {
            e[(i, j)] = ent[i][j].v;
            for p in 0..4 {
                d[p][(i, j)] = ent[i][j].g[p];
            }
        }
    }
    (e, d)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The closed form of exp(Θ) against a Taylor series of the 4×4 exponential.
    #[test]
    fn se3_exponential_matches_series() {
        for &(h, x) in &[
            (0.3, [0.7, -1.1, 0.9, -0.8]),
            (1.7, [1.3, 0.4, -2.0, 0.6]),
            (1e-3, [0.2, 0.1, 0.3, -0.2]),
        ] {
            let ch2 = MAGNUS_C * h * h;
            let om = [
                ch2 * (x[0] * x[3] - x[1] * x[2]),
                -0.5 * h * (x[1] + x[3]),
                0.5 * h * (x[0] + x[2]),
            ];
            let v = [h, ch2 * (x[0] - x[2]), ch2 * (x[1] - x[3])];
            let mut th = Matrix4::zeros();
            th[(0, 1)] = -om[2];
            th[(0, 2)] = om[1];
            th[(1, 0)] = om[2];
            th[(1, 2)] = -om[0];
            th[(2, 0)] = -om[1];
            th[(2, 1)] = om[0];
            for i in 0..3 {
                th[(i, 3)] = v[i];
            }
            let mut term = Matrix4::identity();
            let mut sum = Matrix4::identity();
            for k in 1..60 {
                term = term * th / k as f64;
                sum += term;
            }
            assert!((cell_exp(h, x) - sum).norm() < 1e-13, "h = {h}");
            assert!((cell_jet(h, x).e - sum).norm() < 1e-13);
        }
    }

    /// A part of a cell: the whole cell is the cell's propagator, and a part is the flow of
    /// the linear-curvature ODE (integrated by 2000 Magnus steps) to the scheme's order: for
    /// a fixed curvature `κ(s) = κ0 + κ1 (s − h/2)` the defect falls about 32× (`O(h⁵)`)
    /// when `h` halves.
    #[test]
    fn cell_part_is_the_cells_curve() {
        let (k0, k1) = ([0.8, -0.95], [0.4, 0.3]);
        let [g1, g2] = crate::model::GAUSS_OFFSETS;
        let kappa = |u: f64, h: f64| [k0[0] + k1[0] * (u - h / 2.0), k0[1] + k1[1] * (u - h / 2.0)];
        let cell = |h: f64| {
            let (a, b) = (kappa(g1 * h, h), kappa(g2 * h, h));
            [a[0], a[1], b[0], b[1]]
        };
        for &h in &[0.3, 0.7] {
            assert!((cell_exp_part(h, cell(h), 1.0) - cell_exp(h, cell(h))).norm() < 1e-15);
        }
        let mut defects = Vec::new();
        for &h in &[0.8, 0.4] {
            let theta = g2;
            let steps = 2000;
            let dh = theta * h / steps as f64;
            let mut reference = Matrix4::identity();
            for k in 0..steps {
                let u = k as f64 * dh;
                let (a, b) = (kappa(u + g1 * dh, h), kappa(u + g2 * dh, h));
                reference *= cell_exp(dh, [a[0], a[1], b[0], b[1]]);
            }
            defects.push((cell_exp_part(h, cell(h), theta) - reference).norm());
        }
        assert!(defects[0] < 1e-3, "{defects:?}");
        assert!(defects[1] < defects[0] / 20.0, "{defects:?}");
    }

    /// Series and closed form of the third coefficient agree across `q = 1`.
    #[test]
    fn third_coefficient_is_continuous() {
        let lo = third_coefficient(1.0 - 1e-12);
        let hi = third_coefficient(1.0);
        for i in 0..3 {
            assert!((lo[i] - hi[i]).abs() < 1e-9, "{i}: {lo:?} {hi:?}");
        }
        // Against the definition at q = 0.25 and q = 4.
        for &q in &[0.25f64, 4.0] {
            let t = q.sqrt();
            let c = (t - t.sin()) / (t * t * t);
            assert!((third_coefficient(q)[0] - c).abs() < 1e-14);
        }
    }

    /// The first-order propagator is the second-order one without the Hessians.
    #[test]
    fn cell_grad_equals_cell_jet() {
        for &(h, x) in &[
            (0.9, [0.7, -1.1, 0.9, -0.8]),
            (0.01, [2.0, -1.0, 1.5, -0.9]),
        ] {
            let j = cell_jet(h, x);
            let (e, d) = cell_grad(h, x);
            assert!((e - j.e).norm() <= 1e-15 * (1.0 + j.e.norm()));
            for p in 0..4 {
                assert!(
                    (d[p] - j.d[p]).norm() <= 1e-15 * (1.0 + j.d[p].norm()),
                    "d{p}"
                );
            }
        }
    }

    /// The jet's derivatives against central finite differences.
    #[test]
    fn cell_jet_matches_finite_differences() {
        for &q in &[0.9, 1.1, 3.0] {
            let h = q;
            let x = [0.7, -1.1, 0.9, -0.8];
            let j = cell_jet(h, x);
            let eps = 1e-6;
            for p in 0..4 {
                let mut xp = x;
                let mut xm = x;
                xp[p] += eps;
                xm[p] -= eps;
                let fd = (cell_exp(h, xp) - cell_exp(h, xm)) / (2.0 * eps);
                assert!((fd - j.d[p]).norm() < 1e-8, "d{p}");
                let fd2 = (cell_jet(h, xp).d[0] - cell_jet(h, xm).d[0]) / (2.0 * eps);
                assert!((fd2 - j.dd[p][0]).norm() < 1e-7, "dd{p}0");
                let fd3 = (cell_jet(h, xp).d[3] - cell_jet(h, xm).d[3]) / (2.0 * eps);
                assert!((fd3 - j.dd[p][3]).norm() < 1e-7, "dd{p}3");
            }
        }
    }
}
