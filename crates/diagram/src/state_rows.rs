//! The rows of every state file (`config.csv` of `solve`, `states/*.csv` of a diagram), in
//! units of the ball radius `R` and the reference stiffness `D0`: a surface equilibrium in
//! the columns of [`SURFACE_COLUMNS`], an enclosed state (3-D, attached surface loop, exact
//! loop or the free circle) in those of [`ENCLOSED_COLUMNS`]. The CLI writes them as they
//! are; re-solving (`solve --from`) and drawing read them back.

use std::f64::consts::PI;

use rodloop_solver::enclosed::{EnclosedState, SurfaceSource};
use rodloop_solver::ProfilePoint;

use crate::enclosed::{EnclosedPoint, PointShape};
use crate::enclosed_state::{attached_rows, AttachedLoop, EnclosedResult};
use crate::{DiagramError, STATE_POINTS};

/// The columns of a surface state file (`solve`'s `config.csv`).
pub const SURFACE_COLUMNS: [&str; 12] = [
    "s", "x", "y", "z", "kappa", "tau", "kappa_g", "lambda", "F_t", "F_n", "F_b", "D",
];

/// The columns of an enclosed state file: every row a point of the loop in increasing `s`;
/// `node` is 1 at a node of the 3-D model (or at every sample of a surface loop) and 0 at a
/// Gauss point; `weight` is the point's quadrature weight in units of `R`, so that
/// `E R/(π D0) = (1/π) Σ weight · ½ D κ²` is the reported state's energy by the rule that
/// computed it (two-point Gauss per cell for the 3-D model, the periodic trapezoid for the
/// uniform samples of a surface loop).
pub const ENCLOSED_COLUMNS: [&str; 12] = [
    "s", "x", "y", "z", "gap", "kappa", "kappa_1", "kappa_2", "lambda", "D", "node", "weight",
];

/// Index of the `node` column of [`ENCLOSED_COLUMNS`] (0 or 1, an integer in the file).
pub const NODE_COLUMN: usize = 10;

/// The rows of a surface state ([`SURFACE_COLUMNS`]) on the sphere of radius `r` with
/// reference stiffness `d0`.
pub fn surface_rows(profile: &[ProfilePoint], r: f64, d0: f64) -> Vec<[f64; 12]> {
    let (lam_unit, f_unit) = (r * r * r / d0, r * r / d0);
    profile
        .iter()
        .map(|p| {
            [
                p.s / r,
                p.x / r,
                p.y / r,
                p.z / r,
                p.kappa * r,
                p.tau * r,
                p.kappa_g * r,
                p.lambda * lam_unit,
                p.f_t * f_unit,
                p.f_n * f_unit,
                p.f_b * f_unit,
                p.d / d0,
            ]
        })
        .collect()
}

/// The enclosed rows ([`ENCLOSED_COLUMNS`]) of a loop on the sphere of radius `r` given as
/// `(s, x, y, z, κ_g, λ, D)` rows in the model's units, uniform in arclength over the length
/// `length`: the surface loop is the enclosed state where it is attached, with curvature
/// vector `(κ1, κ2) = (κ_g, −1/R)` in the Darboux frame (rotation-minimising on the sphere,
/// as in the 3-D model's start from a surface loop).
pub fn sphere_rows(rows: &[[f64; 7]], length: f64, r: f64, d0: f64) -> Vec<[f64; 12]> {
    let weight = length / rows.len() as f64;
    rows.iter()
        .map(|&[s, x, y, z, kg, lam, d]| {
            let rad = (x * x + y * y + z * z).sqrt();
            [
                s / r,
                x / r,
                y / r,
                z / r,
                (r - rad) / r,
                (kg * kg + 1.0 / (r * r)).sqrt() * r,
                kg * r,
                -1.0,
                lam * r * r * r / d0,
                d / d0,
                1.0,
                weight / r,
            ]
        })
        .collect()
}

/// The enclosed rows of a 3-D state ([`ENCLOSED_COLUMNS`], length unit `r`; `gap` the wall's
/// clearance): every node and the two Gauss points of each cell ([`rodloop_solver::enclosed_profile`]). The contact
/// force `λ` is nodal (the wall is imposed at the nodes); a Gauss row holds it interpolated
/// linearly between its cell's nodes.
pub fn model_rows(st: &EnclosedState, r: f64, d0: f64) -> Result<Vec<[f64; 12]>, DiagramError> {
    let m = &st.model;
    let lam = m.contact_force(&st.z);
    let n = m.cells();
    let bounds = m.bounds();
    Ok(rodloop_solver::enclosed_profile(st)?
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let c = k / 3;
            let lambda = if p.node {
                lam[c]
            } else {
                let t = (p.s / m.length() - bounds[c]) / (bounds[c + 1] - bounds[c]);
                lam[c] + t * (lam[(c + 1) % n] - lam[c])
            };
            let (k1, k2) = p.kappa;
            let gap = m.wall().clearance(&nalgebra::Vector3::from(p.r));
            [
                p.s / r,
                p.r[0] / r,
                p.r[1] / r,
                p.r[2] / r,
                gap / r,
                (k1 * k1 + k2 * k2).sqrt() * r,
                k1 * r,
                k2 * r,
                lambda * r * r * r / d0,
                p.d / d0,
                f64::from(u8::from(p.node)),
                p.weight / r,
            ]
        })
        .collect())
}

/// The enclosed rows of a solve's result: the surface loop where the energy reported is its
/// (attached), else the 3-D state.
pub fn result_rows(res: &EnclosedResult, r: f64, d0: f64) -> Result<Vec<[f64; 12]>, DiagramError> {
    match &res.attached_loop {
        Some(AttachedLoop::Exact(l, points)) => {
            let rows = attached_rows(&SurfaceSource::Exact(*l), *points, r, d0)?;
            Ok(sphere_rows(&rows, res.state.model.length(), r, d0))
        }
        Some(AttachedLoop::Numeric(file)) => Ok(file_rows(file, res.state.model.length(), r, d0)),
        None => model_rows(&res.state, r, d0),
    }
}

/// The enclosed rows of a verified surface state file ([`crate::StateFile`]: its profile,
/// uniform in arclength over `length`).
fn file_rows(file: &crate::StateFile, length: f64, r: f64, d0: f64) -> Vec<[f64; 12]> {
    let rows: Vec<[f64; 7]> = file
        .profile
        .iter()
        .map(|q| [q.s, q.x, q.y, q.z, q.kappa_g, q.lambda, q.d])
        .collect();
    sphere_rows(&rows, length, r, d0)
}

/// The enclosed rows of one point of an enclosed diagram (see [`sphere_rows`] for attached
/// ones; the free circle of radius `R L̄` about the centre in the plane `y = 0`, curvature
/// vector `(0, −1/ρ)` in the frame whose tangent starts along `x`, the model's start).
pub fn point_rows(p: &EnclosedPoint, r: f64, d0: f64) -> Result<Vec<[f64; 12]>, DiagramError> {
    match &p.shape {
        PointShape::Model(st) => model_rows(st, r, d0),
        PointShape::SurfaceFile(file, length) => Ok(file_rows(file, *length, r, d0)),
        PointShape::Exact(l) => {
            let source = SurfaceSource::Exact(*l);
            let rows = attached_rows(&source, STATE_POINTS, r, d0)?;
            Ok(sphere_rows(&rows, l.length() * r, r, d0))
        }
        PointShape::Circle => {
            let rho = p.lbar;
            Ok((0..STATE_POINTS)
                .map(|i| {
                    let a = 2.0 * PI * i as f64 / STATE_POINTS as f64;
                    [
                        rho * a,
                        rho * a.sin(),
                        0.0,
                        rho * a.cos(),
                        1.0 - rho,
                        1.0 / rho,
                        0.0,
                        -1.0 / rho,
                        0.0,
                        1.0,
                        1.0,
                        2.0 * PI * rho / STATE_POINTS as f64,
                    ]
                })
                .collect())
        }
        PointShape::Surface(_) => Err(DiagramError::Unsolved(
            "the surface state has not been verified as its file holds it".into(),
        )),
        PointShape::Missing => Err(DiagramError::Unsolved(
            "no verified shape (the diagram's warnings say why)".into(),
        )),
    }
}
