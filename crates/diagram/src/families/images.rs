//! Symmetry images of a state of a two-segment rod and membership of a state in the
//! followed curves.

use rodloop_solver::{Stiffness, SurfaceSolve};

use super::{Curve, SAME_STATE};
use crate::march::MarchPoint;

/// The mirror axis of a stiffness profile: `a` with `D(a − σ) = D(σ)` (`s0* + s1*` for the
/// two-segment profile of Eq. (51)); `None` for profiles without one.
pub(super) fn mirror_axis(stiffness: &Stiffness) -> Option<f64> {
    match stiffness {
        Stiffness::Tanh { s0, s1, .. } => Some(s0 + s1),
        _ => None,
    }
}

/// The symmetry images of a state's curvatures: the mirror axis of the profile.
pub(super) struct Images {
    /// `σ` of the Gauss points (fraction of the length).
    sigma: Vec<f64>,
    /// `s0* + s1*` (mirror `σ ↦ axis − σ`), if the profile has a mirror axis.
    axis: Option<f64>,
    /// Shape unknowns.
    shape: usize,
    /// `R/√shape`: scaling to the root-mean-square of `κ_g R`.
    scale: f64,
}

impl Images {
    pub(super) fn new<M: SurfaceSolve>(model: &M, stiffness: &Stiffness) -> Self {
        let shape = model.dim() - model.n_constraints();
        Self {
            sigma: model.gauss_sigma(),
            axis: mirror_axis(stiffness),
            shape,
            scale: model.radius() / (shape as f64).sqrt(),
        }
    }

    /// `κ(axis − σ)` at the Gauss points (periodic linear interpolation).
    fn mirror(&self, kappa: &[f64]) -> Option<Vec<f64>> {
        let axis = self.axis?;
        let n = self.sigma.len();
        Some(
            self.sigma
                .iter()
                .map(|&s| {
                    let t = (axis - s).rem_euclid(1.0);
                    let k = self.sigma.partition_point(|&x| x <= t);
                    let (i0, i1) = ((k + n - 1) % n, k % n);
                    let (a, mut b) = (self.sigma[i0], self.sigma[i1]);
                    if b <= a {
                        b += 1.0;
                    }
                    let tt = if t < a { t + 1.0 } else { t };
                    let w = ((tt - a) / (b - a)).clamp(0.0, 1.0);
                    kappa[i0] + w * (kappa[i1] - kappa[i0])
                })
                .collect(),
        )
    }

    /// Root-mean-square of `(a − b) R` over the shape unknowns.
    pub(super) fn dist(&self, a: &[f64], b: &[f64]) -> f64 {
        a[..self.shape]
            .iter()
            .zip(&b[..self.shape])
            .map(|(x, y)| (x - y) * (x - y))
            .sum::<f64>()
            .sqrt()
            * self.scale
    }

    /// Smallest distance of `b` to `a`, `−a`, `M a`, `−M a`.
    pub(super) fn dist_images(&self, a: &[f64], b: &[f64]) -> f64 {
        let neg: Vec<f64> = a[..self.shape].iter().map(|v| -v).collect();
        let mut d = self.dist(a, b).min(self.dist(&neg, b));
        if let Some(m) = self.mirror(&a[..self.shape]) {
            let mneg: Vec<f64> = m.iter().map(|v| -v).collect();
            d = d.min(self.dist(&m, b)).min(self.dist(&mneg, b));
        }
        d
    }

    /// Whether the state equals its mirror image (up to the reflection `κ → −κ`); `true`
    /// for profiles without a mirror axis.
    pub(super) fn symmetric(&self, a: &[f64]) -> bool {
        let Some(m) = self.mirror(&a[..self.shape]) else {
            return true;
        };
        let mneg: Vec<f64> = m.iter().map(|v| -v).collect();
        let tol = SAME_STATE * 0.5;
        self.dist(&m, a) < tol || self.dist(&mneg, a) < tol
    }
}

/// Whether `(x, p)` lies on one of `curves` (or on an image of one), within [`SAME_STATE`].
pub(super) fn on_known(images: &Images, curves: &[Curve], x: &[f64], p: f64) -> bool {
    on_known_within(images, curves, x, p, SAME_STATE)
}

/// [`on_known`] with the distance `tol` instead of [`SAME_STATE`].
pub(super) fn on_known_within(
    images: &Images,
    curves: &[Curve],
    x: &[f64],
    p: f64,
    tol: f64,
) -> bool {
    curves.iter().any(|c| {
        c.points.windows(2).any(|w| {
            let (a, b) = (&w[0], &w[1]);
            let (lo, hi) = (a.value.min(b.value), a.value.max(b.value));
            if p < lo - 1e-9 || p > hi + 1e-9 {
                return false;
            }
            let t = if hi > lo {
                (p - a.value) / (b.value - a.value)
            } else {
                0.0
            };
            let xi: Vec<f64> = a.x.iter().zip(&b.x).map(|(u, v)| u + t * (v - u)).collect();
            images.dist_images(&xi, x) < tol
        })
    })
}

/// The four images `a, −a, M a, −M a` of a state's curvatures (two if the profile has no
/// mirror axis).
impl Images {
    fn all(&self, a: &[f64]) -> Vec<Vec<f64>> {
        let a = &a[..self.shape];
        let neg = |v: &[f64]| v.iter().map(|x| -x).collect::<Vec<f64>>();
        let mut out = vec![a.to_vec(), neg(a)];
        if let Some(m) = self.mirror(a) {
            out.push(neg(&m));
            out.push(m);
        }
        out
    }

    /// Root-mean-square of `κ_g R` of a state (its distance from the great circle).
    fn size(&self, a: &[f64]) -> f64 {
        a[..self.shape].iter().map(|x| x * x).sum::<f64>().sqrt() * self.scale
    }
}

/// Which part of a march [`image_match`] found on a traced curve: the index of the first of
/// the matched states, and whether the match is with the marched curve's own earlier part.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct ImageMatch {
    /// Index (in the marched points) of the first matched state.
    pub(super) first: usize,
    /// Matched with the marched curve itself (`own` and the marched points before).
    pub(super) own: bool,
}

/// Whether the last two continuation states of a march (`pts`) lie on a symmetry image of a
/// traced curve, with the same direction there: the march would only go on tracing that
/// image (a family that closes on itself through its mirror image or reflection, or a
/// branch switch onto the image of a known family).
///
/// The traced curves are `others` (any image, the identity included) and the marched curve
/// itself, `own` (states traced before this march, e.g. the other direction from the same
/// seed) followed by the marched states before the last three: there the state at the same
/// `L̄` must differ from the marched one, so that a mirror-symmetric curve (its own image
/// everywhere) or the stretch through a crossing does not count. Distances are
/// root-mean-square `κ_g R`, within `min(SAME_STATE / 3, size / 20)` of the interpolated
/// image (symmetry images lie at the same `L̄`), and the chords must be parallel (|cos| >
/// 0.8), so that a transversal crossing of two curves is not a match.
pub(super) fn image_match(
    images: &Images,
    others: &[Curve],
    own: &[MarchPoint],
    pts: &[MarchPoint],
) -> Option<ImageMatch> {
    use crate::types::PointSource;
    let n = pts.len();
    if n < 3 || pts[n - 1].source != PointSource::Continuation {
        return None;
    }
    let mut found = None;
    for k in [n - 1, n - 2] {
        let m = match_point(images, others, own, pts, k)?;
        found = Some(ImageMatch { first: k, own: m });
    }
    found
}

/// [`image_match`] for the state `k` of `pts` (with the chord from state `k − 1`): `Some(own)`
/// if it lies on an image.
fn match_point(
    images: &Images,
    others: &[Curve],
    own: &[MarchPoint],
    pts: &[MarchPoint],
    k: usize,
) -> Option<bool> {
    if k == 0 {
        return None;
    }
    let (x, p) = (&pts[k].x, pts[k].value);
    let d: Vec<f64> = pts[k].x[..images.shape]
        .iter()
        .zip(&pts[k - 1].x)
        .map(|(a, b)| a - b)
        .collect();
    let tol = (SAME_STATE / 3.0).min(images.size(x) / 20.0);
    let check = |seq: &[MarchPoint], own_curve: bool| -> bool {
        seq.windows(2).any(|w| {
            let (a, b) = (&w[0], &w[1]);
            let (lo, hi) = (a.value.min(b.value), a.value.max(b.value));
            if hi <= lo || p < lo - 1e-12 || p > hi + 1e-12 {
                return false;
            }
            let t = (p - a.value) / (b.value - a.value);
            let xi: Vec<f64> = a.x[..images.shape]
                .iter()
                .zip(&b.x)
                .map(|(u, v)| u + t * (v - u))
                .collect();
            if own_curve && images.dist(&xi, x) < 2.0 * tol {
                return false;
            }
            let chord: Vec<f64> = b.x[..images.shape]
                .iter()
                .zip(&a.x)
                .map(|(u, v)| u - v)
                .collect();
            images
                .all(&xi)
                .iter()
                .zip(images.all(&chord))
                .any(|(g_xi, g_chord)| {
                    if images.dist(g_xi, x) >= tol {
                        return false;
                    }
                    let dot: f64 = g_chord.iter().zip(&d).map(|(u, v)| u * v).sum();
                    let n1: f64 = g_chord.iter().map(|u| u * u).sum::<f64>().sqrt();
                    let n2: f64 = d.iter().map(|u| u * u).sum::<f64>().sqrt();
                    n1 > 0.0 && n2 > 0.0 && dot.abs() > 0.8 * n1 * n2
                })
        })
    };
    if check(own, true) || (k >= 3 && check(&pts[..k - 2], true)) {
        return Some(true);
    }
    if others.iter().any(|c| check(&c.points, false)) {
        return Some(false);
    }
    None
}
