//! Local minima of an enclosed branch reached by continuation in `L̄` from other lengths of
//! the branch (a route of [`super::descent::solve_branch_lowest`], which runs the search:
//! [`super::descent::states_by_length_continuation`]).
//!
//! The semismooth Newton from the surface loop stops at the equilibrium next to it, and the
//! descent from a saddle along its unstable directions ends at the equilibrium that Newton
//! reaches from the displaced state; neither need be the lowest local minimum of the
//! branch. A stable family that these starts reach at some lengths of the branch is followed
//! by the enclosed diagram through the branch's whole range. This route does the same for
//! one length: at lengths of the branch nearest the one asked for ([`probe_lengths`]) it
//! finds a local minimum of the branch on a coarse mesh (from the surface loop, else from the
//! stiffness paths of [`stiffness_homotopy_states`](super::descent::stiffness_homotopy_states),
//! each descended where it is a saddle), and continues it in `L̄` to the length asked for
//! ([`continue_in_length`]): [`super::descent::states_by_length_continuation`].

use rodloop_continuation::natural::{walk_adaptive, AdaptiveSettings};

use super::branch::resample_state;
use super::solve::{solve_prolonged, EnclosedOptions, EnclosedState};
use crate::SolverError;

/// Spacing in `L̄` of the lengths searched: a twentieth of a branch's range
/// `η − 1 < L̄ < η + 1`.
pub const LENGTH_STEP: f64 = 0.1;

/// The lengths of branch `eta` at which [`super::descent::states_by_length_continuation`] searches for a state to continue
/// to `lbar`: `lbar ∓ k·LENGTH_STEP`, `k = 1, 2, …`, nearest first (the shorter one first at
/// equal distance), inside the branch's range and at least `LENGTH_STEP` from its ends
/// (where the loop degenerates).
pub fn probe_lengths(lbar: f64, eta: u32) -> Vec<f64> {
    let e = f64::from(eta);
    let (lo, hi) = (e - 1.0 + LENGTH_STEP, e + 1.0 - LENGTH_STEP);
    let mut out = Vec::new();
    for k in 1..=(2.0 / LENGTH_STEP).round() as usize {
        for x in [lbar - k as f64 * LENGTH_STEP, lbar + k as f64 * LENGTH_STEP] {
            if x >= lo - 1e-12 && x <= hi + 1e-12 {
                out.push(x);
            }
        }
    }
    out
}

/// `state` continued in `L̄` to `lbar` on its own mesh: natural-parameter steps
/// ([`EnclosedState::step_to`]) walked by the continuation crate's [`walk_adaptive`], at most
/// a quarter of the distance each, halved on a failed Newton solve down to a sixty-fourth.
pub fn continue_in_length(
    state: &EnclosedState,
    lbar: f64,
    opts: &EnclosedOptions,
) -> Result<EnclosedState, SolverError> {
    let from = state.model.lbar();
    let settings = AdaptiveSettings {
        max_step: 0.25,
        min_step: 1.0 / 64.0,
        growth: 1.5,
        max_rescues: 0,
        restart_step: 1.0 / 64.0,
    };
    // The walk's parameter `t ∈ [0, 1]`: the length `from + t (lbar − from)`.
    let at = |t: f64| {
        if t >= 1.0 {
            lbar
        } else {
            from + t * (lbar - from)
        }
    };
    walk_adaptive(
        state.clone(),
        0.0,
        1.0,
        &settings,
        |cur: &EnclosedState, t| cur.step_to(at(t), opts),
        |_, _, e| Err(e),
    )
}

/// Doublings of a state's cells on which [`continue_on_finer`] walks.
pub const REFINEMENTS: usize = 2;

/// `state`, whose walk in `L̄` to `lbar` on its own mesh failed ([`continue_in_length`]),
/// resampled to twice its cells, re-solved and walked again, up to [`REFINEMENTS`]
/// doublings. A coarse mesh can fold where the family does not: on a two-segment rod whose
/// soft part the coarse mesh resolves with a few cells, the discrete family turns back
/// before the length the finer meshes reach (the walk then ends in Newton failures at the
/// fold), and the minimum would be lost to the search.
pub fn continue_on_finer(
    state: &EnclosedState,
    lbar: f64,
    opts: &EnclosedOptions,
) -> Result<EnclosedState, SolverError> {
    let mut failure = SolverError::InvalidInput("no finer mesh walked".into());
    for k in 1..=REFINEMENTS {
        let cells = state.model.cells() << k;
        let walked = resample_state(state, cells)
            .and_then(|(m, z)| solve_prolonged(&m, z, opts))
            .and_then(|fine| continue_in_length(&fine, lbar, opts));
        match walked {
            Ok(s) => return Ok(s),
            Err(e) => failure = e,
        }
    }
    Err(failure)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The probe lengths stay inside the branch's range, away from its ends, nearest first.
    #[test]
    fn probe_lengths_are_nearest_first_inside_the_range() {
        let p = probe_lengths(1.55, 2);
        assert!(
            (p[0] - 1.45).abs() < 1e-12 && (p[1] - 1.65).abs() < 1e-12,
            "{p:?}"
        );
        assert!(p.iter().all(|&x| (1.1 - 1e-12..=2.9 + 1e-12).contains(&x)));
        let d: Vec<f64> = p.iter().map(|x| (x - 1.55f64).abs()).collect();
        assert!(d.windows(2).all(|w| w[0] <= w[1] + 1e-12), "{d:?}");
        // Near the end of the range only one side remains.
        let q = probe_lengths(1.05, 2);
        assert!(q.iter().all(|&x| x > 1.05), "{q:?}");
    }
}
