//! Starts carried between models of one loop: the shape of curvature-vector functions on a
//! mesh ([`model_from_curvature`]) and the multipliers of a converged state carried to
//! another mesh ([`transfer_multipliers`]). The starts (`solve.rs`) and the refinement of a
//! converged state (`state.rs`) both use them.

use std::sync::Arc;

use super::model::{phase_slope, EnclosedModel, Gauge};
use super::wall::Wall;
use crate::stiffness::Stiffness;
use crate::SolverError;

/// The model and shape of [`start_from_curvature`] with all multipliers 0.
pub(super) fn model_from_curvature<F: Fn(f64) -> (f64, f64)>(
    wall: Arc<dyn Wall>,
    lbar: f64,
    cells: usize,
    stiffness: &Stiffness,
    kappa: F,
    r0: [f64; 3],
) -> Result<(EnclosedModel, Vec<f64>), SolverError> {
    let probe = EnclosedModel::new(
        &wall,
        lbar,
        cells,
        stiffness,
        Gauge {
            reference: vec![0.0; 4 * cells],
            slope: None,
            pin: None,
        },
    )?;
    let reference = probe.sample_gauss(kappa);
    let slope = if stiffness.is_uniform() && probe.uniform_mesh() {
        phase_slope(&reference, cells)?
    } else {
        None
    };
    let model = EnclosedModel::new(
        wall,
        lbar,
        cells,
        stiffness,
        Gauge {
            reference: reference.clone(),
            slope,
            pin: None,
        },
    )?;
    let mut z = vec![0.0; model.dim()];
    z[..4 * cells].copy_from_slice(&reference);
    z[4 * cells..4 * cells + 3].copy_from_slice(&r0);
    Ok((model, z))
}

/// Carry the multipliers of `(from, zf)` over to `(to, zt)`: closure multipliers as they
/// are (resolution-independent), gauge multipliers 0, and the wall impulses through the
/// contact force density, interpolated linearly (periodically) in `σ` to the new nodes.
pub fn transfer_multipliers(from: &EnclosedModel, zf: &[f64], to: &EnclosedModel, zt: &mut [f64]) {
    let (npf, npt) = (from.n_primal(), to.n_primal());
    zt[npt..npt + 6].copy_from_slice(&zf[npf..npf + 6]);
    for k in 6..to.n_equalities() {
        zt[npt + k] = 0.0;
    }
    let dens = from.contact_force(zf);
    let nf = from.cells();
    let bf = from.bounds();
    let lo = to.lambda_offset();
    // The impulse that gives the interpolated density on the wall: `|∇g|` at the wall point
    // nearest each node (a prolonged node lies off the wall by its interpolation error).
    let wall = to.wall();
    let grad: Vec<f64> = to.positions(zt).map_or_else(
        |_| Vec::new(),
        |pos| pos.iter().map(|r| wall.gradient_norm_on_wall(r)).collect(),
    );
    for j in 0..to.cells() {
        let s = to.bounds()[j];
        // Coarse interval [bf[k], bf[k+1]) holding s.
        let k = bf[..nf].partition_point(|&b| b <= s).saturating_sub(1);
        let (a, b) = (bf[k], bf[k + 1]);
        let t = if b > a { (s - a) / (b - a) } else { 0.0 };
        let d = (1.0 - t) * dens[k] + t * dens[(k + 1) % nf];
        let g = grad.get(j).copied().unwrap_or(0.0);
        zt[lo + j] = if g > 0.0 {
            d * to.node_weight(j) / g
        } else {
            0.0
        };
    }
}
