//! Output of a continuation run.

use nalgebra::DVector;

/// A converged point of a branch.
#[derive(Debug, Clone, PartialEq)]
pub struct Point {
    /// Solution `x` (length `n`).
    pub x: DVector<f64>,
    /// Parameter `p`.
    pub p: f64,
    /// Unit tangent `(ẋ, ṗ)` of the solution curve (length `n + 1`), oriented in the
    /// direction of continuation.
    pub tangent: DVector<f64>,
    /// Pseudo-arclength step that led to this point from the previous one (0 for the
    /// first point): the distance between the two points measured along the previous
    /// tangent.
    pub ds: f64,
    /// Cumulative pseudo-arclength from the first point.
    pub s: f64,
    /// Stability index at this point, if a [`Stability`](crate::Stability) callback was
    /// given.
    pub index: Option<usize>,
}

/// What a [`SpecialPoint`] is.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum SpecialKind {
    /// A fold (limit point, turning point) in `p`: the `p`-component of the tangent
    /// changes sign, `∂F/∂x` is singular there while `[∂F/∂x ∂F/∂p]` keeps full rank.
    Fold,
    /// A simple branch point (bifurcation point): `det [∂F/∂x ∂F/∂p; tᵀ]` changes sign,
    /// i.e. `[∂F/∂x ∂F/∂p]` loses rank and a second branch crosses. Use
    /// [`Continuation::switch_branch`](crate::Continuation::switch_branch) to follow it.
    BranchPoint,
    /// The stability index changes from `old` to `new`.
    IndexChange {
        /// Index before the point (in the direction of continuation).
        old: usize,
        /// Index after the point.
        new: usize,
    },
    /// A user event function `g(x, p)` crosses zero.
    Event {
        /// Position of the event function in registration order.
        id: usize,
        /// Name given at registration.
        name: String,
        /// `true` if `g` goes from negative to positive in the direction of continuation.
        increasing: bool,
    },
}

impl SpecialKind {
    /// Short name: `"fold"`, `"branch point"`, `"index change"` or `"event"`.
    pub fn name(&self) -> &'static str {
        match self {
            SpecialKind::Fold => "fold",
            SpecialKind::BranchPoint => "branch point",
            SpecialKind::IndexChange { .. } => "index change",
            SpecialKind::Event { .. } => "event",
        }
    }
}

/// A located special point of a branch.
///
/// It lies on the solution curve (corrected to the continuation tolerance) between
/// `points[segment]` and `points[segment + 1]`, at pseudo-arclength `s`; the defining
/// test function changes sign within an arclength interval of width `accuracy` around
/// it (normally `≤ locate_tol`).
#[derive(Debug, Clone, PartialEq)]
pub struct SpecialPoint {
    /// What was detected.
    pub kind: SpecialKind,
    /// Solution `x`.
    pub x: DVector<f64>,
    /// Parameter `p`.
    pub p: f64,
    /// Unit tangent of the branch there (length `n + 1`).
    pub tangent: DVector<f64>,
    /// Cumulative pseudo-arclength along the branch.
    pub s: f64,
    /// Index of the branch point preceding it.
    pub segment: usize,
    /// Width of the final bracketing interval (arclength).
    pub accuracy: f64,
}

/// Why a continuation run ended.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StopReason {
    /// The step budget `max_steps` was used up.
    MaxSteps,
    /// The branch left `[p_min, p_max]`; its last point was solved at fixed
    /// `p = boundary`.
    LeftRange {
        /// The boundary crossed (`p_min` or `p_max`).
        boundary: f64,
    },
    /// The step size fell below `ds_min` (repeated corrector failures).
    StepTooSmall {
        /// The rejected step size.
        ds: f64,
        /// Parameter of the last accepted point.
        p: f64,
    },
    /// The branch came back to its first point; the last point is a copy of the first.
    ClosedLoop,
    /// The caller ended the run before it stopped by itself: a
    /// [`Stepper`](crate::Stepper) that was [stopped](crate::Stepper::stop),
    /// [finished](crate::Stepper::finish), [restarted](crate::Stepper::restart) or
    /// [reversed](crate::Stepper::reverse) early. [`Continuation::run`](crate::Continuation::run)
    /// never returns it.
    Interrupted,
}

/// A computed solution branch.
#[derive(Debug, Clone, PartialEq)]
pub struct Branch {
    /// Accepted points, in continuation order.
    pub points: Vec<Point>,
    /// Special points, ordered by arclength.
    pub special: Vec<SpecialPoint>,
    /// Why the run ended.
    pub stop: StopReason,
}

impl Branch {
    /// The located folds.
    pub fn folds(&self) -> impl Iterator<Item = &SpecialPoint> {
        self.special
            .iter()
            .filter(|s| matches!(s.kind, SpecialKind::Fold))
    }

    /// The located simple branch points.
    pub fn branch_points(&self) -> impl Iterator<Item = &SpecialPoint> {
        self.special
            .iter()
            .filter(|s| matches!(s.kind, SpecialKind::BranchPoint))
    }

    /// The located stability index changes.
    pub fn index_changes(&self) -> impl Iterator<Item = &SpecialPoint> {
        self.special
            .iter()
            .filter(|s| matches!(s.kind, SpecialKind::IndexChange { .. }))
    }

    /// The located zeros of event function number `id`.
    pub fn events(&self, id: usize) -> impl Iterator<Item = &SpecialPoint> {
        self.special
            .iter()
            .filter(move |s| matches!(s.kind, SpecialKind::Event { id: i, .. } if i == id))
    }

    /// The last point, if any.
    pub fn last(&self) -> Option<&Point> {
        self.points.last()
    }

    /// The parameter values of the points.
    pub fn parameters(&self) -> Vec<f64> {
        self.points.iter().map(|pt| pt.p).collect()
    }
}
