//! A state reported outside the diagrams in `L̄` (the two states of a `phase` row, a state
//! of a `diagram --param`, the finest state of `converge`) verified as its file holds it:
//! the same checks and the same file as the states of the `L̄` diagrams
//! ([`crate::StateFile`], [`rodloop_solver::verify_state`]). The loop closes (holonomy and
//! written points), lies on the sphere, and the energy recomputed from the written samples
//! (`½ ∮ D κ² ds`, Eq. (2)) equals the reported energy within [`crate::ESTIMATES`] times
//! its error estimate (or [`crate::NO_ESTIMATE_TOLERANCE`] without one) plus the
//! quadrature's own error; the periods `η` of the written `κ_g` are counted
//! ([`rodloop_solver::Verification::eta`]).
//!
//! The written profile (`κ_g = 𝓜·n/D` at the cell boundaries, Eq. (41)) carries the
//! resolution's own `O(h⁴)` error; where it exceeds the allowed gap the state is re-solved at
//! `2N`, `4N`, … (Newton from its resampled profile at the same `L̄` and stiffness), up to
//! [`crate::MAX_REFINEMENT`]` N`, and the file samples the finest state needed: the one
//! refinement loop of the states of the `L̄` diagrams, without their re-estimate.

use rodloop_solver::{
    solve_from_state, Equilibrium, Globalization, SolveOptions, SolverError, SurfaceSolve,
};

use crate::states::{newton_options, resolved, verify_refining, Ladder};
use crate::StateFile;

/// The error estimate `|E_N − E_{N/2}|/15` of the energy of `eq` (`N` cells), from the same
/// state at half the resolution (an even number of cells) at its length and stiffness:
/// Newton from the resampled profile with the closure multipliers carried over (the
/// resolution-independent moment; for uniform stiffness through `resolved`). Where the
/// coarser resolution has no state there (next to a fold, which moves with the resolution),
/// `16/15 |E_N − E_{2N}|` from the state at twice the resolution (`resolved`), as the
/// accuracy levels of `solve` fall back to.
pub fn half_resolution_estimate(eq: &Equilibrium) -> Result<f64, SolverError> {
    half_resolution(eq).or_else(|half| {
        let fine = resolved(eq, 2 * eq.model().cells()).map_err(|e| {
            SolverError::Unverified(format!(
                "no state at half the resolution ({half}) nor at twice it ({e})"
            ))
        })?;
        Ok((eq.energy().total - fine.energy().total).abs() * 16.0 / 15.0)
    })
}

/// [`half_resolution_estimate`] without the fallback.
fn half_resolution(eq: &Equilibrium) -> Result<f64, SolverError> {
    let m = eq.model();
    let nc = (m.cells() / 2).div_ceil(2) * 2;
    let coarse = if m.stiffness().kind().is_uniform() {
        resolved(eq, nc)?
    } else {
        let model = m.with_cells(nc)?;
        let mut z = eq.resample(nc)?;
        z.extend_from_slice(&eq.multiplier());
        let newton = SolveOptions {
            globalization: Globalization::Newton,
            ..newton_options()
        };
        solve_from_state(model, z, &newton)?
    };
    Ok(rodloop_solver::richardson_error(
        eq.energy().total,
        coarse.energy().total,
    ))
}

/// `eq` verified as its file holds it against the reported `energy` (`E R/(π D0)`) and its
/// error estimate (see the module docs). [`StateFile::cells`] is the resolution the file
/// samples; [`StateFile::row`] is `None` (the reported energy is not re-estimated).
///
/// Errors: [`SolverError::Unverified`] (with the last check that failed) when no resolution
/// up to the limit passes; the state's own errors when it cannot be re-solved.
pub fn verify_reported(
    eq: &Equilibrium,
    energy: f64,
    energy_error: Option<f64>,
) -> Result<StateFile, SolverError> {
    verify_refining(eq, energy, energy_error, Ladder::Keep)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ESTIMATES;
    use rodloop_solver::{solve_cells, StartShape, Stiffness};

    fn two_segment() -> Stiffness {
        Stiffness::Tanh {
            d0: 1.0,
            d1: 0.5,
            s0: 0.3,
            s1: 0.8,
            gamma: 200.0,
        }
    }

    /// A state passes against its own energy and estimate; the file's energy, recomputed
    /// here from the written profile by the trapezoidal rule, is that energy; a claim off by
    /// a hundred estimates is refused.
    #[test]
    fn a_state_passes_against_its_energy_and_not_against_a_wrong_one() {
        let st = two_segment();
        let eq = solve_cells(
            1.0,
            1.3,
            96,
            &st,
            &StartShape::Euler { l: 1 },
            None,
            &newton(),
        )
        .unwrap();
        let e = eq.energy().total;
        let est = half_resolution_estimate(&eq).unwrap();
        assert!(est > 0.0 && est < 1e-5 * e, "estimate {est:e}");
        let f = verify_reported(&eq, e, Some(est)).unwrap();
        let p = &f.profile;
        let n = p.len();
        let length = 2.0 * std::f64::consts::PI * 1.3;
        let trap: f64 = (0..n)
            .map(|j| {
                let (a, b) = (&p[j], &p[(j + 1) % n]);
                let ds = if j + 1 < n {
                    b.s - a.s
                } else {
                    length + b.s - a.s
                };
                0.25 * (a.d * a.kappa * a.kappa + b.d * b.kappa * b.kappa) * ds
            })
            .sum::<f64>()
            / std::f64::consts::PI;
        assert!((trap - e).abs() <= ESTIMATES * est + 1e-9, "{trap} vs {e}");
        assert_eq!(f.verification.eta, 1);
        let wrong = verify_reported(&eq, e + 100.0 * ESTIMATES * est, Some(est));
        assert!(matches!(wrong, Err(SolverError::Unverified(_))));
    }

    fn newton() -> SolveOptions {
        SolveOptions::default()
    }
}
