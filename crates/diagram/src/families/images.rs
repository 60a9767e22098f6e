//! Symmetry images of a state of a two-segment rod and membership of a state in the
//! followed curves.

use rodloop_solver::{Stiffness, SurfaceModel};

use super::{Curve, SAME_STATE};

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
    pub(super) fn new(model: &SurfaceModel, stiffness: &Stiffness) -> Self {
        let shape = model.n_kappa();
        Self {
            sigma: model.gauss_sigma(),
            axis: match stiffness {
                Stiffness::Tanh { s0, s1, .. } => Some(s0 + s1),
                _ => None,
            },
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
