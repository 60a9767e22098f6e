//! Every state of an enclosed diagram verified as its file holds it, before the diagram is
//! returned: lifted-off 3-D states by [`rodloop_solver::verify_enclosed`] (the rod closes in
//! position and tangent, lies inside the ball, and the energy recomputed from its written
//! nodes equals the point's within [`crate::ESTIMATES`] times its error estimate plus the
//! rule's own error), attached surface states by [`rodloop_solver::verify_state`] on the
//! profile their file holds. Exact loops and the free circle are closed-form. A state that
//! fails keeps its row but loses its shape ([`PointShape::Missing`]: no file is written)
//! with a warning that says why.

use rodloop_solver::{verify_enclosed, verify_state, Claim};

use super::{EnclosedDiagram, PointShape};

/// `d` with every point's shape verified (see the module docs); failures become
/// [`PointShape::Missing`] and a warning each.
pub(crate) fn verified(mut d: EnclosedDiagram) -> EnclosedDiagram {
    for p in &mut d.points {
        let claim = Claim {
            energy: p.energy,
            energy_error: crate::ESTIMATES * p.energy_error,
            profile_error: 0.0,
            eta: None,
        };
        let checked = match &p.shape {
            PointShape::Model(st) => verify_enclosed(st, &claim).map(|_| ()),
            PointShape::Surface(eq) => eq
                .profile_uniform(crate::STATE_POINTS.max(eq.model().cells()))
                .and_then(|profile| verify_state(eq, &profile, &claim))
                .map(|_| ()),
            PointShape::Exact(_) | PointShape::Circle | PointShape::Missing => Ok(()),
        };
        if let Err(e) = checked {
            d.warnings.push(format!(
                "UNVERIFIED STATE LEFT WITHOUT A FILE: enclosed branch {} family {} sheet {} at \
                 L̄ = {}: {e}",
                p.branch, p.family, p.sheet, p.lbar
            ));
            p.shape = PointShape::Missing;
        }
    }
    d
}
