//! A paper branch in an enclosed scene: start from the branch's surface loop (exact for
//! uniform rods, the surface model's equilibrium otherwise), let the semismooth Newton find
//! the contact set, and estimate the discretisation error from two resolutions.

use rodloop_exact::ExactLoop;

use super::solve::{solve_enclosed, start_from_surface, EnclosedOptions, EnclosedState};
use crate::solve::Equilibrium;
use crate::stiffness::Stiffness;
use crate::SolverError;

/// The surface loop an enclosed solve starts from.
#[derive(Clone, Debug)]
pub enum SurfaceSource {
    /// An exact homogeneous loop on the unit sphere (scaled to the ball's radius).
    Exact(ExactLoop),
    /// A numerical surface equilibrium.
    Numeric(Box<Equilibrium>),
}

impl SurfaceSource {
    /// `κ_g` at `σ = s/L` (units of the model).
    pub fn kappa_g(&self, radius: f64, sigma: &[f64]) -> Result<Vec<f64>, SolverError> {
        match self {
            SurfaceSource::Exact(l) => sigma
                .iter()
                .map(|&s| Ok(l.point(s * l.length())?.kappa_g / radius))
                .collect(),
            SurfaceSource::Numeric(eq) => eq.sample_at(sigma),
        }
    }

    /// Energy `E R/(π D0)` of the surface loop.
    pub fn energy(&self) -> Result<f64, SolverError> {
        match self {
            SurfaceSource::Exact(l) => Ok(l.energy()?),
            SurfaceSource::Numeric(eq) => Ok(eq.energy().total),
        }
    }

    /// Smallest contact force `λ_min R³/D0` of the surface loop (Eq. (38) for exact loops).
    pub fn lambda_min(&self, radius: f64, d0: f64) -> f64 {
        match self {
            SurfaceSource::Exact(l) => l.lambda_range().0,
            SurfaceSource::Numeric(eq) => eq.lambda_range().0 * radius.powi(3) / d0,
        }
    }
}

/// An enclosed equilibrium at two resolutions.
#[derive(Clone, Debug)]
pub struct BranchSolve {
    /// The state at `N` cells (reported).
    pub fine: EnclosedState,
    /// The companion at `N/2` cells.
    pub coarse: EnclosedState,
    /// Energy `E R/(π D0)` at `N` cells.
    pub energy: f64,
    /// `|E_N − E_{N/2}|/15` (fourth order; see `tests/enclosed.rs` for the measured order).
    pub energy_error: f64,
}

/// Solve one enclosed state at `cells` and `cells/2` from the surface loop `source`.
pub fn solve_branch(
    radius: f64,
    lbar: f64,
    stiffness: &Stiffness,
    source: &SurfaceSource,
    cells: usize,
    opts: &EnclosedOptions,
) -> Result<BranchSolve, SolverError> {
    let one = |n: usize| -> Result<EnclosedState, SolverError> {
        // Sample κ_g once at this mesh's Gauss points.
        let probe = super::model::EnclosedModel::new(
            radius,
            lbar,
            n,
            stiffness,
            super::model::Gauge {
                reference: vec![0.0; 4 * n],
                slope: None,
                pin: None,
            },
        )?;
        let sig: Vec<f64> = (0..2 * n).map(|g| probe.gauss_sigma(g)).collect();
        let kg = source.kappa_g(radius, &sig)?;
        let lookup = |s: f64| -> f64 {
            let g = sig
                .iter()
                .position(|&x| (x - s).abs() < 1e-15)
                .unwrap_or(0);
            kg[g]
        };
        let (model, z0) = start_from_surface(radius, lbar, n, stiffness, lookup)?;
        solve_enclosed(&model, z0, opts)
    };
    let fine = one(cells)?;
    let coarse = one(cells / 2)?;
    let energy = fine.energy();
    let energy_error = (energy - coarse.energy()).abs() / 15.0;
    Ok(BranchSolve {
        fine,
        coarse,
        energy,
        energy_error,
    })
}
