//! An enclosed start from a saved shape (`rodloop solve --from` on enclosed scenes): the
//! curvature vectors `(κ1, κ2)` and node positions of a saved `config.csv`.
//!
//! The model fixes the frame at `s = 0` to the identity, so the shape built from the saved
//! curvature vectors is the saved one up to a rigid rotation about the ball's centre (the
//! ball is invariant under it). That rotation `Q` is recovered by the Kabsch fit of the
//! built node positions to the saved ones (`x ≈ Q p + c`, SVD of the cross-covariance), and
//! the start point is `r0 = Qᵀ c`. Curvature and positions are interpolated linearly and
//! periodically in `σ = s/L`; a start for Newton, so their `O(h²)` error is harmless.

use nalgebra::{Matrix3, Vector3};

use super::model::EnclosedModel;
use super::solve::start_from_curvature;
use super::wall::IntoWall;
use crate::stiffness::Stiffness;
use crate::SolverError;

/// A saved enclosed shape in the model's units (lengths and curvatures as saved times `R`
/// and `1/R`).
#[derive(Clone, Debug)]
pub struct SavedShape {
    /// `σ = s/L` of the rows, increasing in `[0, 1)`.
    pub sigma: Vec<f64>,
    /// Positions.
    pub points: Vec<[f64; 3]>,
    /// Curvature vectors `(κ1, κ2)` in the rotation-minimising frame.
    pub kappa: Vec<(f64, f64)>,
}

impl SavedShape {
    /// Check the rows (at least 8, finite, `σ` increasing in `[0, 1)`).
    pub fn validate(&self) -> Result<(), SolverError> {
        let n = self.sigma.len();
        if n < 8 || self.points.len() != n || self.kappa.len() != n {
            return Err(SolverError::InvalidInput(format!(
                "a saved enclosed shape needs at least 8 rows of s, x, y, z, kappa_1, kappa_2 (got {n})"
            )));
        }
        let finite = self.sigma.iter().all(|v| v.is_finite())
            && self.points.iter().flatten().all(|v| v.is_finite())
            && self
                .kappa
                .iter()
                .all(|(a, b)| a.is_finite() && b.is_finite());
        if !finite {
            return Err(SolverError::InvalidInput(
                "a saved enclosed shape has a non-finite value".into(),
            ));
        }
        if self.sigma[0] < 0.0
            || self.sigma[n - 1] >= 1.0
            || self.sigma.windows(2).any(|w| w[1] <= w[0])
        {
            return Err(SolverError::InvalidInput(
                "the arclength column of a saved enclosed shape must increase within one period"
                    .into(),
            ));
        }
        Ok(())
    }

    /// Periodic linear interpolation of row values `v` at `s`.
    fn interp<T: Copy + Fn(usize) -> [f64; 3]>(&self, v: T, s: f64) -> [f64; 3] {
        let n = self.sigma.len();
        let s = s.rem_euclid(1.0);
        let k = self.sigma.partition_point(|&x| x <= s);
        let (i0, i1, x0, x1) = if k == 0 {
            (n - 1, 0, self.sigma[n - 1] - 1.0, self.sigma[0])
        } else if k == n {
            (n - 1, 0, self.sigma[n - 1], self.sigma[0] + 1.0)
        } else {
            (k - 1, k, self.sigma[k - 1], self.sigma[k])
        };
        let t = (s - x0) / (x1 - x0);
        let (a, b) = (v(i0), v(i1));
        [
            a[0] + t * (b[0] - a[0]),
            a[1] + t * (b[1] - a[1]),
            a[2] + t * (b[2] - a[2]),
        ]
    }

    fn kappa_at(&self, s: f64) -> (f64, f64) {
        let v = self.interp(|i| [self.kappa[i].0, self.kappa[i].1, 0.0], s);
        (v[0], v[1])
    }

    fn point_at(&self, s: f64) -> [f64; 3] {
        self.interp(|i| self.points[i], s)
    }
}

/// The model at `lbar` with `cells` cells and its start vector from `shape` (see the
/// module docs).
pub fn start_from_shape(
    wall: impl IntoWall,
    lbar: f64,
    cells: usize,
    stiffness: &Stiffness,
    shape: &SavedShape,
) -> Result<(EnclosedModel, Vec<f64>), SolverError> {
    shape.validate()?;
    let wall = wall.into_wall();
    let kappa = |s: f64| shape.kappa_at(s);
    let (probe, z) = start_from_curvature(&wall, lbar, cells, stiffness, kappa, [0.0; 3])?;
    let p = probe.positions(&z)?;
    let x: Vec<Vector3<f64>> = probe.bounds()[..cells]
        .iter()
        .map(|&s| Vector3::from(shape.point_at(s)))
        .collect();
    let m = cells as f64;
    let pc = p.iter().sum::<Vector3<f64>>() / m;
    let xc = x.iter().sum::<Vector3<f64>>() / m;
    let mut h = Matrix3::zeros();
    for (pj, xj) in p.iter().zip(&x) {
        h += (pj - pc) * (xj - xc).transpose();
    }
    let svd = h.svd(true, true);
    let (u, vt) = match (svd.u, svd.v_t) {
        (Some(u), Some(vt)) => (u, vt),
        _ => {
            return Err(SolverError::InvalidInput(
                "the saved shape could not be aligned with the model's frame".into(),
            ))
        }
    };
    let v = vt.transpose();
    let d = (v * u.transpose()).determinant().signum();
    let q = v * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, d)) * u.transpose();
    let c = xc - q * pc;
    let r0 = q.transpose() * c;
    start_from_curvature(wall, lbar, cells, stiffness, kappa, [r0[0], r0[1], r0[2]])
}
