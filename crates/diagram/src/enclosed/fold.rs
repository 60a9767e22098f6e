//! Folds where a lifted-off trace of a non-uniform rod stops.
//!
//! The traces step in `L̄` (natural parameter, `trace.rs`), which cannot pass a fold: where
//! the family turns back, Newton fails under every halving and the trace stops. From the
//! last state reached, the family is followed by pseudo-arclength continuation on the smooth
//! pieces of its contact set ([`rodloop_solver::enclosed::arclength::follow_contacts`]: a
//! contact set held fixed on each, switched where a contact impulse or a free gap reaches
//! zero, the Jacobian factored in `O(N)`) towards the sample length the trace could not reach
//! (a fold that stopped the walk lies before it). The first fold is located by the continuation crate (the
//! tangent's `L̄` component changing sign, to `1e-10` in arclength), on the levels `N/2` and
//! `N` of the trace: the value is the finer level's, the estimate the distance between the
//! two (the discretisation error of the coarser one, as for the branch points of
//! `locate.rs`). Where a level finds no fold before that sample, nothing is located.
//! A fold of level `N/2` alone is a fold of that mesh: the walk of all three levels cannot
//! pass it although the family goes on with `N` cells (branch 1 of the two-segment rod at
//! `L̄ = 2.2611218`, 64 cells, where 96 and 128 cells have none), and the stop's warning
//! says so.

use nalgebra::DVector;
use rodloop_continuation::{Direction, PseudoArclength};
use rodloop_solver::enclosed::arclength::{contact_slack, follow_contacts};
use rodloop_solver::enclosed::EnclosedState;
use rodloop_solver::{Confinement, Param, SolverError};

use super::levels::Levels;

/// Longest continuation step, in the continuation's norm of `(z, L̄)`. With steps ten times
/// longer the corrector lands on other parts of the curve next to a point where the lowest
/// eigenvalue nearly vanishes (branch 1 of the two-segment rod at `L̄ ≈ 2.2635`, 128 cells:
/// `3.2·10⁻⁵`) and reports folds that shorter steps do not find.
const MAX_STEP: f64 = 0.02;

/// Most pieces (contact sets) a search follows: every contact change starts one.
const MAX_PIECES: usize = 20;

/// Continuation steps past a fold, on its piece, before the index past it is taken.
const PAST: usize = 3;

/// A fold located from a trace's stop.
#[derive(Clone, Debug)]
pub(super) struct Fold {
    /// `L̄` of the fold (the finer level's).
    pub(super) lbar: f64,
    /// Its estimate: the distance between the two levels' folds.
    pub(super) error_estimate: f64,
    /// Energy `E R/(π D0)` of the fold state (finer level).
    pub(super) energy: f64,
    /// Index of the trace's state, and of the family past the fold (finer level).
    pub(super) index_before: usize,
    /// Index past the fold.
    pub(super) index_after: usize,
}

/// The fold of `state`'s family on its own mesh between its length and `toward`: its `L̄`, the fold state's energy, and the index of the first
/// continued state past it (`None` where no state past it lies on the piece). `Ok(None)`
/// where the piece ends first or no fold is met.
fn fold_on_level(
    state: &EnclosedState,
    toward: f64,
) -> Result<Option<(f64, f64, Option<usize>)>, SolverError> {
    let lbar = state.model.lbar();
    let direction = if toward > lbar {
        Direction::Forward
    } else {
        Direction::Backward
    };
    let invalid = |e: rodloop_continuation::ContinuationError| {
        SolverError::InvalidInput(format!("fold continuation: {e}"))
    };
    let settings = PseudoArclength::new()
        .with_ds(0.01)
        .and_then(|s| s.with_ds_bounds(1e-7, MAX_STEP))
        .and_then(|s| s.with_tol(1e-9))
        .and_then(|s| s.with_range(lbar.min(toward), lbar.max(toward)))
        .and_then(|s| s.with_max_steps(200))
        .and_then(|s| s.with_direction(direction))
        .map_err(invalid)?;
    let (pieces, _) = follow_contacts(state, Param::Lbar, &settings, MAX_PIECES)?;
    // The first fold along the run, and the point `PAST` steps beyond it on its piece (or
    // the piece's last): the index past the fold is taken there, since right at the fold
    // the eigenvalue that crossed zero is below any threshold.
    let Some((piece, fold)) = pieces
        .iter()
        .find_map(|piece| piece.folds.first().map(|f| (piece, f.clone())))
    else {
        return Ok(None);
    };
    let past = piece
        .points
        .iter()
        .filter(|q| q.s > fold.s)
        .take(PAST)
        .last()
        .cloned();
    // On its piece (a NaN slack, a model that cannot be built, counts as off it).
    let on_piece = state
        .model
        .clone()
        .with_contact_set(piece.contact.clone())
        .and_then(|m| m.with_param(Param::Lbar, fold.p))
        .and_then(|m| contact_slack(&m, fold.x.as_slice()));
    if !matches!(on_piece, Ok(v) if v > 0.0) {
        return Ok(None);
    }
    // The wall model (no contact set held) at a state of the run.
    let plain = |x: &DVector<f64>, p: f64| -> Result<EnclosedState, SolverError> {
        let m = state.model.with_param(Param::Lbar, p)?;
        Ok(EnclosedState {
            model: m,
            z: x.as_slice().to_vec(),
            iterations: 0,
            residual: f64::NAN,
        })
    };
    let energy = plain(&fold.x, fold.p)?.energy();
    let past = past
        .map(|q| plain(&q.x, q.p).and_then(|st| st.index(1e-6)))
        .transpose()?;
    Ok(Some((fold.p, energy, past)))
}

/// What the continuation finds past a trace's stop on its levels `N/2` and `N`.
#[derive(Clone, Debug)]
pub(super) enum StopFold {
    /// Both levels fold: the family's fold, located (see the module docs).
    Located(Fold),
    /// Only level `N/2` folds, at this `L̄`: a fold of the coarser mesh, which the walk of
    /// all three levels cannot pass, while on `N` cells the family goes on (its continuation
    /// reaches the unreached sample without a fold).
    CoarseOnly(f64),
    /// No fold on level `N/2`, or a level whose continuation could not be followed.
    None,
}

/// The fold of the trace stopped at `last` (levels `N/4, N/2, N`) on its way to `toward`
/// (see the module docs). [`StopFold::Located`] needs a continued state past the fine
/// level's fold on its piece (the index past the fold is taken there).
pub(super) fn fold_at_stop(last: &Levels, toward: f64) -> StopFold {
    let Ok(Some((coarse, _, _))) = fold_on_level(&last.states[1], toward) else {
        return StopFold::None;
    };
    let (fine, energy, past) = match fold_on_level(&last.states[2], toward) {
        Ok(Some(f)) => f,
        Ok(None) => return StopFold::CoarseOnly(coarse),
        // A continuation that could not be followed says nothing about level N.
        Err(_) => return StopFold::None,
    };
    let (Ok(index_before), Some(index_after)) = (last.states[2].index(1e-6), past) else {
        return StopFold::None;
    };
    StopFold::Located(Fold {
        lbar: fine,
        error_estimate: (fine - coarse).abs(),
        energy,
        index_before,
        index_after,
    })
}
