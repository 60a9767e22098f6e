//! Reconstruction of a spherical curve from its geodesic curvature by integrating the Darboux
//! frame (paper App. A) with a fourth-order Magnus method.
//!
//! The frame is stored as a rotation matrix `X` whose rows are `t, g, n`. Along the curve
//! `X' = Ω(s) X` with the skew matrix
//!
//! ```text
//!        ⎡  0     κ_g  −1/R ⎤
//! Ω(s) = ⎢ −κ_g   0     0   ⎥
//!        ⎣  1/R   0     0   ⎦
//! ```
//!
//! One step of the two-point Gauss Magnus method (Iserles & Nørsett, 1999; Blanes, Casas,
//! Oteo & Ros, Phys. Rep. 470, 2009, eq. (253)) is `X ← exp(Θ) X` with
//! `Θ = h/2 (Ω₁ + Ω₂) + (√3/12) h² [Ω₂, Ω₁]`, `Ω_i` at the Gauss nodes. The exponential of a
//! 3×3 skew matrix is evaluated by Rodrigues' formula, so every iterate is orthogonal to
//! round-off and the points stay on the sphere exactly. The global error is `O(h⁴)`.

use nalgebra::{Matrix3, Vector3};

use crate::SolverError;

/// Skew matrix of the Darboux system at geodesic curvature `kg` on a sphere of radius `r`.
pub fn omega(kg: f64, r: f64) -> Matrix3<f64> {
    Matrix3::new(0.0, kg, -1.0 / r, -kg, 0.0, 0.0, 1.0 / r, 0.0, 0.0)
}

/// `exp(W)` of a skew-symmetric 3×3 matrix `W` (Rodrigues' formula).
pub fn expm_skew(w: &Matrix3<f64>) -> Matrix3<f64> {
    // W v = ω × v with ω = (W[2,1], W[0,2], W[1,0]).
    let om = Vector3::new(w[(2, 1)], w[(0, 2)], w[(1, 0)]);
    let th2 = om.norm_squared();
    let th = th2.sqrt();
    // sin(θ)/θ and (1 − cos θ)/θ² with series near θ = 0.
    let (a, b) = if th < 1e-4 {
        (
            1.0 - th2 / 6.0 + th2 * th2 / 120.0,
            0.5 - th2 / 24.0 + th2 * th2 / 720.0,
        )
    } else {
        (th.sin() / th, (1.0 - th.cos()) / th2)
    };
    Matrix3::identity() + w * a + w * w * b
}

/// Rodrigues coefficients `a(q) = sin θ/θ`, `b(q) = (1 − cos θ)/θ²` as functions of
/// `q = θ²`, with their first and second derivatives in `q`:
/// returns `[a, a', a'', b, b', b'']`.
///
/// For `q < 1` the Maclaurin series `a = Σ (−q)^k/(2k+1)!`, `b = Σ (−q)^k/(2k+2)!` and their
/// derivatives are summed (`SERIES_TERMS` terms, Horner's rule); otherwise the closed forms
/// `a' = (cos θ − a)/(2q)`, `a'' = −(a/2 + 3a')/(2q)`, `b' = (a/2 − b)/q`,
/// `b'' = (a'/2 − 2b')/q` are used, which have no cancellation problem there.
///
/// A Newton pass evaluates every cell at the same `q` several times (the closure rows of a
/// trial, its residual, the next Newton matrix, `∂F/∂L̄`), so the coefficients are kept
/// per thread in a small table addressed by the bits of `q`; as they are a function of `q`
/// alone, a hit hands back the bits the computation gives.
pub fn rodrigues_coefficients(q: f64) -> [f64; 6] {
    if !q.is_finite() {
        return rodrigues(q);
    }
    let key = q.to_bits();
    let slot = (key.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> (64 - MEMO_BITS)) as usize;
    MEMO.with(|m| {
        let mut m = m.borrow_mut();
        let (k, v) = &mut m[slot];
        if *k != key {
            *k = key;
            *v = rodrigues(q);
        }
        *v
    })
}

/// `log₂` of the number of slots of the per-thread table of [`rodrigues_coefficients`]
/// (of the order of the cells of the finest models, to hold a model's cells at once).
const MEMO_BITS: u32 = 11;

thread_local! {
    /// `(q.to_bits(), coefficients)` per slot; the key of a non-finite `q` (never stored)
    /// marks an empty slot.
    static MEMO: std::cell::RefCell<Vec<(u64, [f64; 6])>> =
        std::cell::RefCell::new(vec![(f64::NAN.to_bits(), [0.0; 6]); 1 << MEMO_BITS]);
}

/// Terms of the Maclaurin series of [`rodrigues`] summed for `q < 1`: the first left out is
/// below `10⁻¹⁹` of its sum for every one of the six (at `q = 1`, `a''`'s is
/// `12·11/23! < 6·10⁻²¹` against `a''(0) = 1/60`).
const SERIES_TERMS: usize = 10;

/// `1/n!` for `n = 0 ..= 2·SERIES_TERMS + 4`.
const INV_FACTORIALS: [f64; 2 * SERIES_TERMS + 5] = {
    let mut out = [1.0; 2 * SERIES_TERMS + 5];
    let mut n = 1;
    while n < out.len() {
        out[n] = out[n - 1] / n as f64;
        n += 1;
    }
    out
};

/// Coefficients of the series in `x = −q` of `[a, a', a'', b, b', b'']`, term `k`:
/// `a = Σ x^k/(2k+1)!`, so `a' = −Σ (k+1) x^k/(2k+3)!` and `a'' = Σ (k+1)(k+2) x^k/(2k+5)!`;
/// `b` likewise with `(2k+2)!`.
const SERIES: [[f64; 6]; SERIES_TERMS] = {
    let f = INV_FACTORIALS;
    let mut out = [[0.0; 6]; SERIES_TERMS];
    let mut k = 0;
    while k < SERIES_TERMS {
        let (k1, k2) = ((k + 1) as f64, ((k + 1) * (k + 2)) as f64);
        out[k] = [
            f[2 * k + 1],
            -k1 * f[2 * k + 3],
            k2 * f[2 * k + 5],
            f[2 * k + 2],
            -k1 * f[2 * k + 4],
            k2 * f[2 * k + 6],
        ];
        k += 1;
    }
    out
};

/// The computation of [`rodrigues_coefficients`] (without its table).
fn rodrigues(q: f64) -> [f64; 6] {
    if q < 1.0 {
        // The six series by Horner's rule in `x = −q`, side by side (independent chains).
        let x = -q;
        let mut out = [0.0; 6];
        for term in SERIES.iter().rev() {
            for (o, c) in out.iter_mut().zip(term) {
                *o = *o * x + c;
            }
        }
        out
    } else {
        let th = q.sqrt();
        let (s, c) = th.sin_cos();
        let a = s / th;
        let b = (1.0 - c) / q;
        let a1 = (c - a) / (2.0 * q);
        let a2 = -(0.5 * a + 3.0 * a1) / (2.0 * q);
        let b1 = (0.5 * a - b) / q;
        let b2 = (0.5 * a1 - 2.0 * b1) / q;
        [a, a1, a2, b, b1, b2]
    }
}

/// `exp(hat(ω))` by Rodrigues' formula with the coefficients of [`rodrigues_coefficients`]:
/// the same matrix, to the bit, as the value of [`exp_jet1`] (and of the other jets), at a
/// fraction of their cost (no derivative matrices). [`crate::SurfaceModel`]'s closure
/// residual alone ([`crate::SurfaceModel::kkt_closure_residual`]) is built from it; the
/// coefficients it leaves in the table serve the jets at the same `ω`.
pub fn exp_value(w: &Vector3<f64>) -> Matrix3<f64> {
    let q = w.norm_squared();
    let [a, _, _, b, _, _] = rodrigues_coefficients(q);
    let wm = hat(w);
    let w2 = wm * wm;
    Matrix3::identity() + wm * a + w2 * b
}

/// Skew matrix `hat(w)` with `hat(w) v = w × v`.
pub fn hat(w: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -w[2], w[1], w[2], 0.0, -w[0], -w[1], w[0], 0.0)
}

/// `exp(W)`, its first derivatives `[∂_i]` and second derivatives `[[∂_i∂_j]]` (upper
/// triangle filled) with respect to `K` variables.
pub type ExpJet<const K: usize> = (Matrix3<f64>, [Matrix3<f64>; K], [[Matrix3<f64>; K]; K]);

/// `exp(hat(ω))` and its first and second derivatives with respect to `K` scalar variables
/// `x_i`, given `ω`, `∂ω/∂x_i` and `∂²ω/∂x_i∂x_j` (a second-order "jet" through Rodrigues'
/// formula `exp(W) = I + a(q) W + b(q) W²`, `q = |ω|²`).
///
/// With `q_i = 2 ω·ω_i`, `q_ij = 2(ω_i·ω_j + ω·ω_ij)`, `a_i = a' q_i`,
/// `a_ij = a'' q_i q_j + a' q_ij` (same for `b`):
/// `∂_i E = a_i W + a W_i + b_i W² + b (W_i W + W W_i)` and
/// `∂_ij E = a_ij W + a_i W_j + a_j W_i + a W_ij + b_ij W² + b_i (W_j W + W W_j)
///  + b_j (W_i W + W W_i) + b (W_ij W + W W_ij + W_i W_j + W_j W_i)`.
/// Only the upper triangle `i ≤ j` of the second derivatives is filled (symmetric).
pub fn exp_jet<const K: usize>(
    w: &Vector3<f64>,
    wi: &[Vector3<f64>; K],
    wij: &[[Vector3<f64>; K]; K],
) -> ExpJet<K> {
    jet(w, wi, Some(wij), false)
}

/// [`exp_jet`] with only the second derivatives in the last variable, `∂_i∂_{K−1}` for every
/// `i` (the other entries are left zero): the mixed derivatives that `∂F/∂L̄` needs with the
/// cell length as the last variable, at half the cost of the full jet for `K = 3`.
pub fn exp_jet_last<const K: usize>(
    w: &Vector3<f64>,
    wi: &[Vector3<f64>; K],
    wij: &[[Vector3<f64>; K]; K],
) -> ExpJet<K> {
    jet(w, wi, Some(wij), true)
}

/// [`exp_jet`] for `ω` affine in the variables (`∂²ω/∂x_i∂x_j = 0`), as for a cell
/// propagator in its two curvature unknowns: the terms in `W_ij` are skipped.
pub fn exp_jet_affine<const K: usize>(w: &Vector3<f64>, wi: &[Vector3<f64>; K]) -> ExpJet<K> {
    jet(w, wi, None, false)
}

/// `exp(hat(ω))` and its first derivatives only (see [`exp_jet`]).
pub fn exp_jet1<const K: usize>(
    w: &Vector3<f64>,
    wi: &[Vector3<f64>; K],
) -> (Matrix3<f64>, [Matrix3<f64>; K]) {
    let mut e = Matrix3::zeros();
    let mut d = [Matrix3::zeros(); K];
    exp_jet1_into(w, wi, &mut e, &mut d);
    (e, d)
}

/// [`exp_jet1`] written into `e` and `d` (the same values to the bit): a cell chain fills
/// its arrays in place, without moving the jet through a returned value.
#[inline(always)]
pub(crate) fn exp_jet1_into<const K: usize>(
    w: &Vector3<f64>,
    wi: &[Vector3<f64>; K],
    e: &mut Matrix3<f64>,
    d: &mut [Matrix3<f64>; K],
) {
    let q = w.norm_squared();
    let [a, a1, _, b, b1, _] = rodrigues_coefficients(q);
    let wm = hat(w);
    let w2 = wm * wm;
    *e = Matrix3::identity() + wm * a + w2 * b;
    for i in 0..K {
        let wim = hat(&wi[i]);
        let qi = 2.0 * w.dot(&wi[i]);
        d[i] = wm * (a1 * qi) + wim * a + w2 * (b1 * qi) + (wim * wm + wm * wim) * b;
    }
}

/// [`exp_jet_affine`] for two variables written into `e`, `d` and the upper triangle
/// `dd = [∂₁₁, ∂₁₂, ∂₂₂]` (the same values to the bit): what a cell propagator of the
/// surface model needs in its two curvature unknowns, filled in place.
#[inline(always)]
pub(crate) fn exp_jet2_affine_into(
    w: &Vector3<f64>,
    wi: &[Vector3<f64>; 2],
    e: &mut Matrix3<f64>,
    d: &mut [Matrix3<f64>; 2],
    dd: &mut [Matrix3<f64>; 3],
) {
    jet_into(w, wi, None, false, e, d, |i, j, m| dd[i + j] = m);
}

/// [`exp_jet_last`] written into `e` and `d`, each `∂_i∂_{K−1}` handed to `put(i, ·)` (the
/// same values to the bit, without the zero entries).
#[inline(always)]
pub(crate) fn exp_jet_last_into<const K: usize>(
    w: &Vector3<f64>,
    wi: &[Vector3<f64>; K],
    wij: &[[Vector3<f64>; K]; K],
    e: &mut Matrix3<f64>,
    d: &mut [Matrix3<f64>; K],
    mut put: impl FnMut(usize, Matrix3<f64>),
) {
    jet_into(w, wi, Some(wij), true, e, d, |i, _, m| put(i, m));
}

fn jet<const K: usize>(
    w: &Vector3<f64>,
    wi: &[Vector3<f64>; K],
    wij: Option<&[[Vector3<f64>; K]; K]>,
    only_last: bool,
) -> ExpJet<K> {
    let mut e = Matrix3::zeros();
    let mut d = [Matrix3::zeros(); K];
    let mut dd = [[Matrix3::zeros(); K]; K];
    jet_into(w, wi, wij, only_last, &mut e, &mut d, |i, j, m| {
        dd[i][j] = m
    });
    (e, d, dd)
}

/// The jet of [`exp_jet`]: the value into `e`, the first derivatives into `d`, and each
/// second derivative `∂_i∂_j` (`i ≤ j`, only `j = K − 1` with `only_last`) handed to
/// `put(i, j, ·)`.
#[inline(always)]
fn jet_into<const K: usize>(
    w: &Vector3<f64>,
    wi: &[Vector3<f64>; K],
    wij: Option<&[[Vector3<f64>; K]; K]>,
    only_last: bool,
    e: &mut Matrix3<f64>,
    d: &mut [Matrix3<f64>; K],
    mut put: impl FnMut(usize, usize, Matrix3<f64>),
) {
    let q = w.norm_squared();
    let [a, a1, a2, b, b1, b2] = rodrigues_coefficients(q);
    let wm = hat(w);
    let w2 = wm * wm;
    *e = Matrix3::identity() + wm * a + w2 * b;
    let mut wim = [Matrix3::zeros(); K];
    let mut qi = [0.0; K];
    let mut sym = [Matrix3::zeros(); K]; // W_i W + W W_i
    for i in 0..K {
        wim[i] = hat(&wi[i]);
        qi[i] = 2.0 * w.dot(&wi[i]);
        sym[i] = wim[i] * wm + wm * wim[i];
        d[i] = wm * (a1 * qi[i]) + wim[i] * a + w2 * (b1 * qi[i]) + sym[i] * b;
    }
    for i in 0..K {
        for j in i..K {
            if only_last && j + 1 != K {
                continue;
            }
            let (ai, aj) = (a1 * qi[i], a1 * qi[j]);
            let (bi, bj) = (b1 * qi[i], b1 * qi[j]);
            let mut qij = 2.0 * wi[i].dot(&wi[j]);
            let mut pair = wim[i] * wim[j] + wim[j] * wim[i];
            let mut lin = Matrix3::zeros();
            if let Some(wij) = wij {
                let wijm = hat(&wij[i][j]);
                qij += 2.0 * w.dot(&wij[i][j]);
                pair += wijm * wm + wm * wijm;
                lin = wijm * a;
            }
            let aij = a2 * qi[i] * qi[j] + a1 * qij;
            let bij = b2 * qi[i] * qi[j] + b1 * qij;
            put(
                i,
                j,
                wm * aij
                    + wim[j] * ai
                    + wim[i] * aj
                    + lin
                    + w2 * bij
                    + sym[j] * bi
                    + sym[i] * bj
                    + pair * b,
            );
        }
    }
}

/// Result of integrating the frame along a closed curve.
#[derive(Clone, Debug)]
pub struct FrameCurve {
    /// Arclength of each stored point (`n + 1` values from 0 to `L`).
    pub s: Vec<f64>,
    /// Frames (rows `t, g, n`) at those points.
    pub frames: Vec<Matrix3<f64>>,
    /// Sphere radius.
    pub radius: f64,
}

impl FrameCurve {
    /// Position `r = R n` of point `i`.
    pub fn position(&self, i: usize) -> Vector3<f64> {
        let f = &self.frames[i];
        Vector3::new(f[(2, 0)], f[(2, 1)], f[(2, 2)]) * self.radius
    }

    /// Unit tangent of point `i`.
    pub fn tangent(&self, i: usize) -> Vector3<f64> {
        let f = &self.frames[i];
        Vector3::new(f[(0, 0)], f[(0, 1)], f[(0, 2)])
    }

    /// Holonomy `X(L) X(0)ᵀ`: the identity exactly when the loop closes with continuous tangent.
    pub fn holonomy(&self) -> Matrix3<f64> {
        self.frames[self.frames.len() - 1] * self.frames[0].transpose()
    }

    /// Rotation angle of the holonomy, in `[0, π]`: a closure residual in radians.
    pub fn holonomy_angle(&self) -> f64 {
        let h = self.holonomy();
        let c = ((h.trace() - 1.0) / 2.0).clamp(-1.0, 1.0);
        // acos loses precision near 0; use the skew part for small angles.
        let skew = Vector3::new(
            h[(2, 1)] - h[(1, 2)],
            h[(0, 2)] - h[(2, 0)],
            h[(1, 0)] - h[(0, 1)],
        );
        let s = 0.5 * skew.norm();
        s.atan2(c)
    }
}

/// Integrate the Darboux frame over `[0, length]` in `steps` equal Magnus steps, starting from
/// the frame `x0` (rows `t, g, n`), for the geodesic curvature `kappa_g(s)`.
pub fn integrate<F: Fn(f64) -> f64>(
    kappa_g: F,
    length: f64,
    radius: f64,
    steps: usize,
    x0: Matrix3<f64>,
) -> Result<FrameCurve, SolverError> {
    if steps == 0 || length.is_nan() || length <= 0.0 || radius.is_nan() || radius <= 0.0 {
        return Err(SolverError::InvalidInput(format!(
            "frame integration needs steps > 0, length > 0, radius > 0 (got {steps}, {length}, {radius})"
        )));
    }
    let h = length / steps as f64;
    let c1 = 0.5 - 3f64.sqrt() / 6.0;
    let c2 = 0.5 + 3f64.sqrt() / 6.0;
    let mut x = x0;
    let mut s = Vec::with_capacity(steps + 1);
    let mut frames = Vec::with_capacity(steps + 1);
    s.push(0.0);
    frames.push(x);
    for i in 0..steps {
        let s0 = i as f64 * h;
        let o1 = omega(kappa_g(s0 + c1 * h), radius);
        let o2 = omega(kappa_g(s0 + c2 * h), radius);
        let comm = o2 * o1 - o1 * o2;
        let theta = (o1 + o2) * (0.5 * h) + comm * (3f64.sqrt() / 12.0 * h * h);
        x = expm_skew(&theta) * x;
        s.push(s0 + h);
        frames.push(x);
    }
    Ok(FrameCurve { s, frames, radius })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn rodrigues_matches_series() {
        let w = omega(0.7, 1.3) * 0.4;
        // Taylor series of exp to high order.
        let mut term = Matrix3::identity();
        let mut sum = Matrix3::identity();
        for k in 1..40 {
            term = term * w / k as f64;
            sum += term;
        }
        assert!((expm_skew(&w) - sum).norm() < 1e-15);
    }

    /// [`exp_value`] is the value of the jets to the bit (the closure residual built from it
    /// must equal the KKT residual's closure rows exactly), over rotation angles from the
    /// series' range (`q < 1`) to the closed forms', including the switch at `q = 1`.
    #[test]
    fn exp_value_is_the_jets_value_to_the_bit() {
        let v1 = Vector3::new(0.013, -0.2, 0.71);
        let v2 = Vector3::new(-0.4, 0.05, 0.3);
        for (i, scale) in [
            0.0, 1e-9, 1e-5, 1e-3, 0.1, 0.5, 0.999, 1.0, 1.0001, 2.0, 3.1,
        ]
        .into_iter()
        .enumerate()
        {
            let w = Vector3::new(0.3, -0.8, 0.52 + 0.01 * i as f64).normalize() * scale;
            let (e1, _) = exp_jet1::<2>(&w, &[v1, v2]);
            let (ea, _, _) = exp_jet_affine::<2>(&w, &[v1, v2]);
            let ev = exp_value(&w);
            for k in 0..9 {
                assert_eq!(ev[k].to_bits(), e1[k].to_bits(), "|w| = {scale}, entry {k}");
                assert_eq!(ev[k].to_bits(), ea[k].to_bits(), "|w| = {scale}, entry {k}");
            }
            assert!((ev - expm_skew(&hat(&w))).norm() < 1e-14, "|w| = {scale}");
        }
    }

    /// The per-thread table hands back the computation's bits: values of `q` in both
    /// branches, more of them than the table has slots (so slots are shared and
    /// overwritten), asked for twice in different orders.
    #[test]
    fn rodrigues_table_returns_the_computed_bits() {
        let qs: Vec<f64> = (0..3 * (1usize << MEMO_BITS))
            .map(|i| 1e-6 + 2.5 * (i as f64 * 0.618_033_988_749_895).fract())
            .collect();
        for pass in 0..2 {
            for (i, &q) in qs.iter().enumerate() {
                let q = if pass == 0 { q } else { qs[qs.len() - 1 - i] };
                let got = rodrigues_coefficients(q);
                let want = rodrigues(q);
                for k in 0..6 {
                    assert_eq!(got[k].to_bits(), want[k].to_bits(), "q = {q}, entry {k}");
                }
            }
        }
        assert!(rodrigues_coefficients(f64::NAN).iter().all(|v| v.is_nan()));
    }

    /// The six series summed by Horner's rule against the same series summed term by term
    /// (powers and factorials built in the loop, 30 terms) over `0 ≤ q < 1`: within a few
    /// units in the last place of each coefficient's size at `q = 0`.
    #[test]
    fn rodrigues_horner_sums_match_the_term_by_term_series() {
        for i in 0..=400 {
            let q = if i == 400 {
                1.0 - 1e-12
            } else {
                i as f64 / 400.0
            };
            let mut want = [0.0f64; 6];
            let (mut fact, mut pw) = (1.0f64, 1.0f64); // n!, (−q)^k for n = 2k + 1
            let mut facts = vec![1.0f64];
            for n in 1..70 {
                fact *= n as f64;
                facts.push(fact);
            }
            for k in 0..30usize {
                let kf = k as f64;
                want[0] += pw / facts[2 * k + 1];
                want[3] += pw / facts[2 * k + 2];
                let (d1, d2) = (-(kf + 1.0) * pw, (kf + 1.0) * (kf + 2.0) * pw);
                want[1] += d1 / facts[2 * k + 3];
                want[4] += d1 / facts[2 * k + 4];
                want[2] += d2 / facts[2 * k + 5];
                want[5] += d2 / facts[2 * k + 6];
                pw *= -q;
            }
            let got = rodrigues(q);
            let scale = [1.0, 1.0 / 6.0, 1.0 / 60.0, 0.5, 1.0 / 24.0, 1.0 / 180.0];
            for k in 0..6 {
                assert!(
                    (got[k] - want[k]).abs() <= 4.0 * f64::EPSILON * scale[k],
                    "q = {q}, coefficient {k}: {} vs {}",
                    got[k],
                    want[k]
                );
            }
        }
    }

    #[test]
    fn rodrigues_series_matches_closed_forms() {
        // The (truncated) series for q < 1 against sin θ/θ, (1 − cos θ)/θ² and the closed
        // forms of the derivatives, where those have no cancellation problem.
        for q in [1e-4f64, 1e-2, 0.25, 0.5, 0.81, 0.999_999] {
            let [a, a1, a2, b, b1, b2] = rodrigues_coefficients(q);
            let th = q.sqrt();
            let (s, c) = th.sin_cos();
            assert!((a - s / th).abs() < 1e-15, "a at q = {q}");
            assert!((b - (1.0 - c) / q).abs() < 1e-12, "b at q = {q}");
            if q >= 0.25 {
                let ea1 = (c - a) / (2.0 * q);
                let ea2 = -(0.5 * a + 3.0 * ea1) / (2.0 * q);
                let eb1 = (0.5 * a - b) / q;
                let eb2 = (0.5 * ea1 - 2.0 * eb1) / q;
                for (x, y) in [(a1, ea1), (a2, ea2), (b1, eb1), (b2, eb2)] {
                    assert!((x - y).abs() < 1e-13, "q = {q}: {x} vs {y}");
                }
            }
        }
        // Continuity across the switch at q = 1.
        let lo = rodrigues_coefficients(1.0 - 1e-13);
        let hi = rodrigues_coefficients(1.0);
        for k in 0..6 {
            assert!((lo[k] - hi[k]).abs() < 1e-12, "coefficient {k}");
        }
    }

    #[test]
    fn affine_and_first_order_jets_match_the_general_jet() {
        let w = Vector3::new(0.03, -0.2, 0.11);
        let wi = [
            Vector3::new(0.01, 0.0, -0.5),
            Vector3::new(-0.01, 0.0, -0.5),
        ];
        let zero = [[Vector3::zeros(); 2]; 2];
        let (e, d, dd) = exp_jet(&w, &wi, &zero);
        let (ea, da, dda) = exp_jet_affine(&w, &wi);
        let (e1, d1) = exp_jet1(&w, &wi);
        assert!((e - ea).amax() < 1e-16 && (e - e1).amax() < 1e-16);
        for i in 0..2 {
            assert!((d[i] - da[i]).amax() < 1e-16 && (d[i] - d1[i]).amax() < 1e-16);
            for j in i..2 {
                assert!((dd[i][j] - dda[i][j]).amax() < 1e-15);
            }
        }
        // The first derivative against a central difference of Rodrigues' formula.
        let step = 1e-6;
        for i in 0..2 {
            let fd = (expm_skew(&hat(&(w + wi[i] * step))) - expm_skew(&hat(&(w - wi[i] * step))))
                / (2.0 * step);
            assert!((fd - d1[i]).amax() < 1e-9, "derivative {i}");
        }
    }

    #[test]
    fn great_circle_closes_and_small_circle_has_known_radius() {
        // κ_g = 0: great circle of length 2πR closes exactly.
        let fc = integrate(|_| 0.0, 2.0 * PI, 1.0, 64, Matrix3::identity()).unwrap();
        assert!(fc.holonomy_angle() < 1e-13);
        // Constant κ_g on the unit sphere: a small circle of circumference 2π/sqrt(1+κ_g²).
        let kg = 0.75;
        let len = 2.0 * PI / (1.0f64 + kg * kg).sqrt();
        let fc = integrate(|_| kg, len, 1.0, 200, Matrix3::identity()).unwrap();
        assert!(fc.holonomy_angle() < 1e-12, "{}", fc.holonomy_angle());
        for i in 0..fc.frames.len() {
            assert!((fc.position(i).norm() - 1.0).abs() < 1e-14);
        }
    }

    #[test]
    fn magnus_is_fourth_order() {
        // Error of the end frame against a very fine reference for a varying κ_g.
        let kg = |s: f64| 0.8 * (1.3 * s).cos() + 0.2;
        let reference = integrate(kg, 5.0, 1.0, 20_000, Matrix3::identity()).unwrap();
        let xr = *reference.frames.last().unwrap();
        let err = |n: usize| {
            let fc = integrate(kg, 5.0, 1.0, n, Matrix3::identity()).unwrap();
            (fc.frames.last().unwrap() - xr).norm()
        };
        let (e1, e2) = (err(50), err(100));
        let order = (e1 / e2).log2();
        assert!((order - 4.0).abs() < 0.2, "observed order {order}");
    }
}
