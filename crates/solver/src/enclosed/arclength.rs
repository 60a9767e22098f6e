//! An enclosed family followed by pseudo-arclength continuation on one smooth piece of the
//! complementarity: the contact set held fixed ([`EnclosedModel::with_contact_set`]), so
//! that Keller's method of [`rodloop_continuation`] passes the folds that natural-parameter
//! steps in `L̄` cannot.
//!
//! The enclosed KKT system (Eq. (51) discretised, [`super::model`]) writes the wall's
//! complementarity `λ_j ≥ 0, g_j ≥ 0, λ_j g_j = 0` as `min(λ_j, σ g_j) = 0`, which has a kink
//! wherever its two arguments are equal; the bordered corrector of pseudo-arclength stalls
//! there ([`super::seam`]). With the contact set `A` fixed (the nodes whose row is the wall at
//! a converged state, [`EnclosedModel::wall_active`]), the system is the smooth one of that piece: `σ g_j = 0` for `j ∈ A`,
//! `λ_j = 0` otherwise, the stationarity, closure and gauge rows unchanged. Its solutions are
//! equilibria of the wall as long as every contact impulse `λ_j` (`j ∈ A`) and every free gap
//! `g_j` (`j ∉ A`) stays nonnegative: [`contact_slack`] is the least of them (the gaps scaled
//! by `σ` like the min-function's argument), an event function for the continuation, whose
//! root is where the contact set changes.

use nalgebra::DVector;
use rodloop_continuation::{
    Continuation, ContinuationError, Direction, Point, PseudoArclength, SpecialKind, SpecialPoint,
    StopReason,
};

use super::model::EnclosedModel;
use super::state::EnclosedState;
use crate::{Confinement, Param, ParamProblem, SolverError};

/// How far the state `z` of `model` (a fixed contact set, [`EnclosedModel::with_contact_set`])
/// lies inside its piece: the least of the contact impulses `λ_j` on the set and of the
/// scaled gaps `σ g_j` off it ([`node_slacks`]). Negative once a contact would pull or a free
/// node would leave the ball; an error where no contact set is fixed.
pub fn contact_slack(model: &EnclosedModel, z: &[f64]) -> Result<f64, SolverError> {
    Ok(node_slacks(model, z)?
        .into_iter()
        .fold(f64::INFINITY, f64::min))
}

/// Each node's slack in its piece: `λ_j` on the contact set, `σ g_j` off it.
pub fn node_slacks(model: &EnclosedModel, z: &[f64]) -> Result<Vec<f64>, SolverError> {
    let set = model
        .contact_set()
        .ok_or_else(|| SolverError::InvalidInput("the model holds no contact set fixed".into()))?;
    let wall = model.wall();
    let sigma = model.wall_scale();
    let lo = model.lambda_offset();
    let positions = model.positions(z)?;
    Ok(set
        .iter()
        .enumerate()
        .map(|(j, &on)| {
            if on {
                z[lo + j]
            } else {
                sigma * wall.gap(&positions[j])
            }
        })
        .collect())
}

/// One smooth piece of a [`follow_contacts`] run: its contact set, the accepted points and
/// the folds located on it.
#[derive(Clone, Debug)]
pub struct ContactPiece {
    /// The contact set held on the piece.
    pub contact: Vec<bool>,
    /// Accepted continuation points, in order (the first is the piece's start).
    pub points: Vec<Point>,
    /// Folds located on the piece.
    pub folds: Vec<SpecialPoint>,
}

/// Why a [`follow_contacts`] run ended.
#[derive(Clone, Debug, PartialEq)]
pub enum ContactRunEnd {
    /// The continuation stopped by itself (the parameter range left, the step budget used
    /// up, the step below its minimum, a closed loop).
    Stopped(StopReason),
    /// A node switched at a piece's start reached zero again before the piece took a step:
    /// the switch does not continue the family (a contact that would both pull and
    /// penetrate), so the run ends there.
    SwitchReversed,
    /// `max_pieces` pieces were followed.
    Pieces,
}

/// Relative size, against the largest node slack, below which a node's slack at a located
/// piece end counts as zero: every such node switches there (a symmetric loop's contacts
/// touch down in pairs or fours at once).
const SWITCH_TOLERANCE: f64 = 1e-7;

/// The family of `state` followed by pseudo-arclength continuation in `param` across changes
/// of its contact set: each piece at a fixed contact set (its end, a node's slack reaching
/// zero, is the event [`contact_slack`]), then the nodes whose slack is zero there switched
/// (a contact whose impulse reached zero lets go, a free node whose gap reached zero touches
/// down) and the next piece started at that point, which solves both pieces, in the
/// direction the curve was going. `settings` apply to every piece (its direction to the
/// first). At most `max_pieces` pieces.
pub fn follow_contacts(
    state: &EnclosedState,
    param: Param,
    settings: &PseudoArclength,
    max_pieces: usize,
) -> Result<(Vec<ContactPiece>, ContactRunEnd), SolverError> {
    let invalid =
        |e: ContinuationError| SolverError::InvalidInput(format!("contact continuation: {e}"));
    let base = state.model.clone();
    let mut set = base.wall_active(&state.z)?;
    let mut x = DVector::from_column_slice(&state.z);
    let mut p = Confinement::param(&base, param)?;
    let mut direction = settings.direction();
    let mut switched: Vec<usize> = Vec::new();
    let mut pieces = Vec::new();
    while pieces.len() < max_pieces {
        let model = base.clone().with_contact_set(set.clone())?;
        let problem = ParamProblem::new(model, param)?;
        let slack = |v: &DVector<f64>, q: f64| {
            problem
                .model_at(q)
                .and_then(|m| contact_slack(&m, v.as_slice()))
                .unwrap_or(f64::NAN)
        };
        let run_settings = settings
            .clone()
            .with_direction(direction)
            .map_err(invalid)?;
        let run = Continuation::new(&problem, run_settings).with_event("contact slack", slack);
        let mut stepper = run.start(&x, p).map_err(invalid)?;
        let mut piece = ContactPiece {
            contact: set.clone(),
            points: vec![stepper.current()],
            folds: Vec::new(),
        };
        let end = loop {
            let step = stepper.step().map_err(invalid)?;
            let mut ended = None;
            for sp in step.special {
                match sp.kind {
                    SpecialKind::Fold => piece.folds.push(sp),
                    SpecialKind::Event {
                        increasing: false, ..
                    } => {
                        ended = Some(sp);
                        break;
                    }
                    _ => {}
                }
            }
            // The step's point lies past the piece's end: not on the piece.
            if let Some(sp) = ended {
                break sp;
            }
            if let Some(point) = step.point {
                piece.points.push(point);
            }
            if let Some(reason) = step.stop {
                pieces.push(piece);
                return Ok((pieces, ContactRunEnd::Stopped(reason)));
            }
        };
        // A piece with no accepted step beyond its start made no progress.
        let progressed = piece.points.len() > 1;
        pieces.push(piece);
        // The nodes whose slack is zero at the piece's end switch.
        let m = problem.model_at(end.p)?;
        let slacks = node_slacks(&m, end.x.as_slice())?;
        let scale = slacks.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let zero: Vec<usize> = (0..slacks.len())
            .filter(|&j| slacks[j] <= SWITCH_TOLERANCE * scale)
            .collect();
        if !progressed && zero.iter().any(|j| switched.contains(j)) {
            return Ok((pieces, ContactRunEnd::SwitchReversed));
        }
        for &j in &zero {
            set[j] = !set[j];
        }
        switched = zero;
        x = end.x.clone();
        p = end.p;
        let n = end.tangent.len() - 1;
        direction = if end.tangent[n] >= 0.0 {
            Direction::Forward
        } else {
            Direction::Backward
        };
    }
    Ok((pieces, ContactRunEnd::Pieces))
}
