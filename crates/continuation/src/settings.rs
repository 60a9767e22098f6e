//! Settings of the pseudo-arclength continuation.

use crate::error::ContinuationError;

/// Orientation of a continuation run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Direction {
    /// `+1`: start towards increasing `p` (for
    /// [`Continuation::switch_branch`](crate::Continuation::switch_branch): along the
    /// canonically oriented secondary tangent).
    #[default]
    Forward,
    /// `−1`: the opposite orientation.
    Backward,
}

impl Direction {
    /// `+1.0` or `−1.0`.
    pub fn sign(self) -> f64 {
        match self {
            Direction::Forward => 1.0,
            Direction::Backward => -1.0,
        }
    }

    /// The opposite direction.
    pub fn reversed(self) -> Self {
        match self {
            Direction::Forward => Direction::Backward,
            Direction::Backward => Direction::Forward,
        }
    }
}

/// Settings of Keller's pseudo-arclength continuation (the solver).
///
/// Built with [`PseudoArclength::new`] (defaults below) and the `with_*` setters, each
/// of which validates its argument and returns `Result<Self, ContinuationError>`
/// ([`ContinuationError::InvalidSetting`]). Relations between settings (for instance
/// `ds_min ≤ ds ≤ ds_max`) are checked by [`PseudoArclength::validate`] when a run starts.
///
/// | setting | default | meaning |
/// |---|---|---|
/// | `ds` | `0.01` | initial step (pseudo-arclength) |
/// | `ds_min`, `ds_max` | `1e-8`, `0.1` | step bounds; a step below `ds_min` ends the run |
/// | `growth` | `1.5` | step factor after an easy corrector (fewer than `target_iterations` iterations) |
/// | `shrink` | `0.5` | step factor after a failed step (and lower bound of the factor after a hard one) |
/// | `target_iterations` | `4` | corrector iterations considered "normal" |
/// | `tol` | `1e-10` | corrector residual tolerance `max(‖F‖∞, |arclength eq.|)` |
/// | `step_tol` | `1e-8` | corrector update tolerance, `‖Δy‖∞ ≤ step_tol (1 + ‖y‖∞)` |
/// | `max_iterations` | `10` | Newton iterations per corrector |
/// | `p_min`, `p_max` | `−∞`, `+∞` | parameter range; leaving it ends the run exactly at the boundary |
/// | `max_steps` | `1000` | accepted steps per run |
/// | `direction` | `Forward` | initial orientation in `p` |
/// | `max_turn` | `0.5` rad | largest angle between consecutive tangents of an accepted step |
/// | `locate_tol` | `1e-10` | arclength accuracy of located special points |
/// | `detect_folds`, `detect_branch_points`, `detect_loops` | `true` | detections to run |
/// | `branch_points_beside_folds` | `true` | a branch point is located in a step that has a fold too |
/// | `hermite_location` | `false` | location correctors start from the bracket's Hermite interpolant |
#[derive(Debug, Clone, PartialEq)]
pub struct PseudoArclength {
    pub(crate) ds: f64,
    pub(crate) ds_min: f64,
    pub(crate) ds_max: f64,
    pub(crate) growth: f64,
    pub(crate) shrink: f64,
    pub(crate) target_iterations: usize,
    pub(crate) tol: f64,
    pub(crate) step_tol: f64,
    pub(crate) max_iterations: usize,
    pub(crate) p_min: f64,
    pub(crate) p_max: f64,
    pub(crate) max_steps: usize,
    pub(crate) direction: Direction,
    pub(crate) max_turn: f64,
    pub(crate) locate_tol: f64,
    pub(crate) detect_folds: bool,
    pub(crate) detect_branch_points: bool,
    pub(crate) detect_loops: bool,
    pub(crate) branch_points_beside_folds: bool,
    pub(crate) hermite_location: bool,
}

impl Default for PseudoArclength {
    fn default() -> Self {
        PseudoArclength {
            ds: 0.01,
            ds_min: 1e-8,
            ds_max: 0.1,
            growth: 1.5,
            shrink: 0.5,
            target_iterations: 4,
            tol: 1e-10,
            step_tol: 1e-8,
            max_iterations: 10,
            p_min: f64::NEG_INFINITY,
            p_max: f64::INFINITY,
            max_steps: 1000,
            direction: Direction::Forward,
            max_turn: 0.5,
            locate_tol: 1e-10,
            detect_folds: true,
            detect_branch_points: true,
            detect_loops: true,
            branch_points_beside_folds: true,
            hermite_location: false,
        }
    }
}

fn positive(name: &'static str, v: f64) -> Result<f64, ContinuationError> {
    if v > 0.0 && v.is_finite() {
        Ok(v)
    } else {
        Err(ContinuationError::invalid(
            name,
            format!("must be positive and finite, got {v}"),
        ))
    }
}

impl PseudoArclength {
    /// Default settings (see the table in the type documentation).
    pub fn new() -> Self {
        Self::default()
    }

    /// Initial step size `ds > 0`.
    pub fn with_ds(mut self, ds: f64) -> Result<Self, ContinuationError> {
        self.ds = positive("ds", ds)?;
        Ok(self)
    }

    /// Step bounds `0 < ds_min ≤ ds_max`.
    pub fn with_ds_bounds(mut self, ds_min: f64, ds_max: f64) -> Result<Self, ContinuationError> {
        positive("ds_min", ds_min)?;
        positive("ds_max", ds_max)?;
        if ds_min > ds_max {
            return Err(ContinuationError::invalid(
                "ds_min",
                format!("ds_min = {ds_min} exceeds ds_max = {ds_max}"),
            ));
        }
        self.ds_min = ds_min;
        self.ds_max = ds_max;
        Ok(self)
    }

    /// Step growth factor `> 1` after an easy corrector.
    pub fn with_growth(mut self, growth: f64) -> Result<Self, ContinuationError> {
        if !(growth > 1.0 && growth.is_finite()) {
            return Err(ContinuationError::invalid(
                "growth",
                format!("must be finite and > 1, got {growth}"),
            ));
        }
        self.growth = growth;
        Ok(self)
    }

    /// Step shrink factor in `(0, 1)` after a failed step.
    pub fn with_shrink(mut self, shrink: f64) -> Result<Self, ContinuationError> {
        if !(shrink > 0.0 && shrink < 1.0) {
            return Err(ContinuationError::invalid(
                "shrink",
                format!("must lie in (0, 1), got {shrink}"),
            ));
        }
        self.shrink = shrink;
        Ok(self)
    }

    /// Number of corrector iterations regarded as normal (`≥ 1`): fewer grow the step,
    /// more shrink it by `max(shrink, target / iterations)`.
    pub fn with_target_iterations(mut self, n: usize) -> Result<Self, ContinuationError> {
        if n == 0 {
            return Err(ContinuationError::invalid(
                "target_iterations",
                "must be at least 1",
            ));
        }
        self.target_iterations = n;
        Ok(self)
    }

    /// Corrector residual tolerance `> 0` (max-norm of `F` and of the arclength
    /// equation). Also used by the fixed-parameter solve at a range boundary.
    pub fn with_tol(mut self, tol: f64) -> Result<Self, ContinuationError> {
        self.tol = positive("tol", tol)?;
        Ok(self)
    }

    /// Corrector update tolerance `> 0`, relative: `‖Δy‖∞ ≤ step_tol (1 + ‖y‖∞)`.
    pub fn with_step_tol(mut self, step_tol: f64) -> Result<Self, ContinuationError> {
        self.step_tol = positive("step_tol", step_tol)?;
        Ok(self)
    }

    /// Maximum number of Newton iterations per corrector (`≥ 1`).
    pub fn with_max_iterations(mut self, n: usize) -> Result<Self, ContinuationError> {
        if n == 0 {
            return Err(ContinuationError::invalid(
                "max_iterations",
                "must be at least 1",
            ));
        }
        self.max_iterations = n;
        Ok(self)
    }

    /// Parameter range `p_min < p_max` (infinite ends allowed). The run stops with
    /// [`StopReason::LeftRange`](crate::StopReason::LeftRange) on leaving it.
    pub fn with_range(mut self, p_min: f64, p_max: f64) -> Result<Self, ContinuationError> {
        if p_min.is_nan() || p_max.is_nan() || p_min >= p_max {
            return Err(ContinuationError::invalid(
                "range",
                format!("need p_min < p_max, got [{p_min}, {p_max}]"),
            ));
        }
        self.p_min = p_min;
        self.p_max = p_max;
        Ok(self)
    }

    /// Maximum number of accepted steps of a run (`≥ 1`).
    pub fn with_max_steps(mut self, n: usize) -> Result<Self, ContinuationError> {
        if n == 0 {
            return Err(ContinuationError::invalid(
                "max_steps",
                "must be at least 1",
            ));
        }
        self.max_steps = n;
        Ok(self)
    }

    /// Initial orientation: [`Direction::Forward`] starts towards increasing `p`.
    pub fn with_direction(mut self, direction: Direction) -> Result<Self, ContinuationError> {
        self.direction = direction;
        Ok(self)
    }

    /// Largest angle (radians, in `(0, π/2]`) between the tangents at the two ends of an
    /// accepted step; larger turns are rejected and retried with a smaller step. This
    /// keeps the predictor from jumping between nearby branches.
    pub fn with_max_turn(mut self, angle: f64) -> Result<Self, ContinuationError> {
        if !(angle > 0.0 && angle <= std::f64::consts::FRAC_PI_2) {
            return Err(ContinuationError::invalid(
                "max_turn",
                format!("must lie in (0, π/2], got {angle}"),
            ));
        }
        self.max_turn = angle;
        Ok(self)
    }

    /// Arclength accuracy `> 0` to which special points (folds, branch points, index
    /// changes, events) are located.
    pub fn with_locate_tol(mut self, tol: f64) -> Result<Self, ContinuationError> {
        self.locate_tol = positive("locate_tol", tol)?;
        Ok(self)
    }

    /// Whether the location loops start each corrector from the cubic Hermite interpolant
    /// (points and tangents) of the current bracket instead of the chord of the whole step
    /// (default `false`). Its error falls like the fourth power of the bracket width, so
    /// late iterations converge without a Newton step (a chord guess needs three or four),
    /// and near a branch point the trial points stay on the branch being followed instead
    /// of converging onto the crossing one.
    pub fn with_hermite_location(mut self, on: bool) -> Result<Self, ContinuationError> {
        self.hermite_location = on;
        Ok(self)
    }

    /// Whether to detect and locate folds (default `true`).
    pub fn with_detect_folds(mut self, on: bool) -> Result<Self, ContinuationError> {
        self.detect_folds = on;
        Ok(self)
    }

    /// Whether to detect and locate simple branch points (default `true`).
    pub fn with_detect_branch_points(mut self, on: bool) -> Result<Self, ContinuationError> {
        self.detect_branch_points = on;
        Ok(self)
    }

    /// Whether a branch point is located in a step in which a fold was located (default
    /// `true`). Off, a step that turns reports only its fold: for a caller that ends at the
    /// first turning point and keeps only the fold of that step, the branch point's location
    /// (a sign change of the determinant, often many corrector solves next to a singular
    /// Jacobian) would be work thrown away.
    pub fn with_branch_points_beside_folds(mut self, on: bool) -> Result<Self, ContinuationError> {
        self.branch_points_beside_folds = on;
        Ok(self)
    }

    /// Whether to stop with [`StopReason::ClosedLoop`](crate::StopReason::ClosedLoop)
    /// when the branch returns to its starting point (default `true`).
    pub fn with_detect_loops(mut self, on: bool) -> Result<Self, ContinuationError> {
        self.detect_loops = on;
        Ok(self)
    }

    /// Checks the relations between settings: `ds_min ≤ ds ≤ ds_max`.
    pub fn validate(&self) -> Result<(), ContinuationError> {
        if self.ds < self.ds_min || self.ds > self.ds_max {
            return Err(ContinuationError::invalid(
                "ds",
                format!(
                    "initial step {} outside [ds_min, ds_max] = [{}, {}]",
                    self.ds, self.ds_min, self.ds_max
                ),
            ));
        }
        Ok(())
    }

    /// Initial step size.
    pub fn ds(&self) -> f64 {
        self.ds
    }
    /// Minimum step size.
    pub fn ds_min(&self) -> f64 {
        self.ds_min
    }
    /// Maximum step size.
    pub fn ds_max(&self) -> f64 {
        self.ds_max
    }
    /// Step growth factor.
    pub fn growth(&self) -> f64 {
        self.growth
    }
    /// Step shrink factor.
    pub fn shrink(&self) -> f64 {
        self.shrink
    }
    /// Normal number of corrector iterations.
    pub fn target_iterations(&self) -> usize {
        self.target_iterations
    }
    /// Corrector residual tolerance.
    pub fn tol(&self) -> f64 {
        self.tol
    }
    /// Corrector relative update tolerance.
    pub fn step_tol(&self) -> f64 {
        self.step_tol
    }
    /// Newton iterations per corrector.
    pub fn max_iterations(&self) -> usize {
        self.max_iterations
    }
    /// Parameter range `(p_min, p_max)`.
    pub fn range(&self) -> (f64, f64) {
        (self.p_min, self.p_max)
    }
    /// Maximum number of accepted steps.
    pub fn max_steps(&self) -> usize {
        self.max_steps
    }
    /// Initial orientation.
    pub fn direction(&self) -> Direction {
        self.direction
    }
    /// Largest tangent turn per step (radians).
    pub fn max_turn(&self) -> f64 {
        self.max_turn
    }
    /// Location accuracy of special points (arclength).
    pub fn locate_tol(&self) -> f64 {
        self.locate_tol
    }
}
