//! Shape descriptors (point group, self-intersections; [`rodloop_exact::shape`]) of a state
//! of the surface model, from its unknowns alone: the positions come from the Darboux frame
//! integrated over sub-steps of each cell (App. A), no equilibrium solve needed.

use nalgebra::Vector3;
use rodloop_exact::shape::{loop_shape, LoopShape, SampledLoop, ShapeTolerances};
use rodloop_exact::topology::periodic_lagrange;

use crate::frame::{expm_skew, omega};
use crate::{SolverError, SurfaceModel};

/// Sub-steps per cell of [`SurfaceModel::positions`] used by [`SurfaceModel::shape`].
pub const SHAPE_SUBSTEPS: usize = 8;

impl SurfaceModel {
    /// Positions `r = R n` of the curve with geodesic curvature `kappa` (Gauss values) at
    /// `per_cell` equal sub-steps of every cell: `(s, r)` with `s` from 0 up to, not
    /// including, `L`. The frame at each cell boundary is the model's own
    /// ([`SurfaceModel::frames`]); inside a cell it is advanced by two-point Gauss Magnus
    /// sub-steps with `κ_g` from the periodic 4-point interpolant of the Gauss values, so the
    /// sub-cell points carry the model's accuracy.
    pub fn positions(
        &self,
        kappa: &[f64],
        per_cell: usize,
    ) -> Result<(Vec<f64>, Vec<Vector3<f64>>), SolverError> {
        if per_cell == 0 {
            return Err(SolverError::InvalidInput(
                "positions need at least one point per cell".into(),
            ));
        }
        let frames = self.frames(kappa)?;
        let len = self.length();
        let r = self.radius();
        let sg: Vec<f64> = self.gauss_sigma().iter().map(|x| x * len).collect();
        let bounds = self.bounds();
        let (c1, c2) = (0.5 - 3f64.sqrt() / 6.0, 0.5 + 3f64.sqrt() / 6.0);
        let mut s_out = Vec::with_capacity(self.cells() * per_cell);
        let mut r_out = Vec::with_capacity(self.cells() * per_cell);
        let mut hint = 0isize;
        for c in 0..self.cells() {
            let (a, b) = (bounds[c] * len, bounds[c + 1] * len);
            let h = (b - a) / per_cell as f64;
            let mut x = frames[c];
            for k in 0..per_cell {
                let s0 = a + h * k as f64;
                s_out.push(s0);
                r_out.push(Vector3::new(x[(2, 0)], x[(2, 1)], x[(2, 2)]) * r);
                if k + 1 < per_cell {
                    let mut kg = |s: f64| periodic_lagrange(&sg, kappa, len, s, &mut hint);
                    let o1 = omega(kg(s0 + c1 * h), r);
                    let o2 = omega(kg(s0 + c2 * h), r);
                    let comm = o2 * o1 - o1 * o2;
                    let theta = (o1 + o2) * (0.5 * h) + comm * (3f64.sqrt() / 12.0 * h * h);
                    x = expm_skew(&theta) * x;
                }
            }
        }
        Ok((s_out, r_out))
    }

    /// Point group and self-intersections of the state with geodesic curvature `kappa`
    /// (positions from [`SurfaceModel::positions`] with [`SHAPE_SUBSTEPS`] sub-steps, `κ_g`
    /// at the Gauss points).
    /// `kappa` may be a whole KKT state: only its first [`SurfaceModel::n_kappa`] values are
    /// read.
    pub fn shape(&self, kappa: &[f64], tol: ShapeTolerances) -> Result<LoopShape, SolverError> {
        let kappa = kappa
            .get(..self.n_kappa())
            .ok_or(SolverError::WrongLength {
                expected: self.n_kappa(),
                found: kappa.len(),
            })?;
        let (s, points) = self.positions(kappa, SHAPE_SUBSTEPS)?;
        let len = self.length();
        let sg: Vec<f64> = self.gauss_sigma().iter().map(|x| x * len).collect();
        Ok(loop_shape(
            &SampledLoop {
                length: len,
                radius: self.radius(),
                s: &s,
                points: &points,
                kappa_g_s: &sg,
                kappa_g: kappa,
            },
            tol,
        )?)
    }
}
