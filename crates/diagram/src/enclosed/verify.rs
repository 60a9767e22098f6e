//! Every state of an enclosed diagram verified as its file holds it, before the diagram is
//! returned: lifted-off 3-D states by [`rodloop_solver::verify_enclosed`] (the rod closes in
//! position and tangent, lies inside the ball, and the energy recomputed from its written
//! nodes equals the point's within [`crate::ESTIMATES`] times its error estimate plus the
//! rule's own error), attached surface states by the routine that verifies every traced
//! surface state's file ([`crate::states::verify_refining`], the row's energy and estimate
//! kept): the profile `κ_g = 𝓜·n/D` (Eq. (41)) is a second discretisation of the state, and
//! where the tracing resolution's profile misses the row's energy the file samples the state
//! re-solved on `2N`, `4N`, … ([`PointShape::SurfaceFile`]). Exact loops and the free circle
//! are closed-form.
//!
//! **Branch.** Each state is verified with its row's branch: where the periods of its moment
//! (of its central projection onto the sphere for a 3-D state,
//! [`rodloop_solver::identify::identify_enclosed`]) can be counted they must equal the row's
//! `η` ([`BranchFrom::Periods`]); where they cannot (a loop in a plane through the centre
//! projects onto a great circle, a pattern within the noise) the row's branch is its family's,
//! continued from a named seed ([`BranchFrom::Continuation`]). A state whose periods name
//! another branch contradicts its row.
//!
//! A state that fails keeps its row but loses its shape ([`PointShape::Missing`]: no file is
//! written) with a warning that says why.

use rodloop_solver::identify::{identify_enclosed, identify_profile, Periods};
use rodloop_solver::{verify_enclosed, Claim, SolverError};

use crate::states::{verify_refining, Ladder};

use super::{BranchFrom, EnclosedDiagram, PointShape};

/// How the row's branch `eta` is known from the state's `periods`: `Ok` with the `η` to
/// claim in the verification (`None`: not counted), or the contradiction.
fn branch_claim(
    periods: Result<Periods, SolverError>,
    eta: u32,
) -> Result<(BranchFrom, Option<u32>), String> {
    match periods {
        Ok(p) if p.eta == eta => Ok((BranchFrom::Periods, Some(eta))),
        Ok(p) => Err(format!(
            "its moment has {} periods: a state of eta = {}, not of its row's eta = {eta}",
            p.eta, p.eta
        )),
        Err(_) => Ok((BranchFrom::Continuation, None)),
    }
}

/// `d` with every point's shape verified (see the module docs); failures become
/// [`PointShape::Missing`] and a warning each.
pub(crate) fn verified(mut d: EnclosedDiagram) -> EnclosedDiagram {
    for p in &mut d.points {
        let mut claim = Claim {
            energy: p.energy,
            energy_error: crate::ESTIMATES * p.energy_error,
            profile_error: 0.0,
            eta: None,
        };
        let checked = match &p.shape {
            PointShape::Model(st) => {
                branch_claim(identify_enclosed(st), p.eta).and_then(|(from, eta)| {
                    claim.eta = eta;
                    p.branch_from = from;
                    verify_enclosed(st, &claim)
                        .map(|_| ())
                        .map_err(|e| e.to_string())
                })
            }
            PointShape::Surface(eq) => {
                let length = eq.model().length();
                verify_refining(eq, p.energy, Some(p.energy_error), Ladder::Keep)
                    .map_err(|e| e.to_string())
                    .and_then(|file| {
                        let (from, _) =
                            branch_claim(identify_profile(&file.profile, length), p.eta)?;
                        p.branch_from = from;
                        p.shape = PointShape::SurfaceFile(Box::new(file), length);
                        Ok(())
                    })
            }
            PointShape::SurfaceFile(..)
            | PointShape::Exact(_)
            | PointShape::Circle
            | PointShape::Missing => Ok(()),
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
