//! Step-by-step continuation: the [`Stepper`] and its [`Step`] reports.
//!
//! [`Continuation::run`] and [`Continuation::switch_branch`] are loops over
//! [`Stepper::step`], so that a caller stepping by hand gets exactly the same branch.

use nalgebra::DVector;

use crate::branch::{Branch, Point, SpecialPoint, StopReason};
use crate::error::ContinuationError;
use crate::linalg::{self, Evaluator, Tangent};
use crate::newton::{correct_bordered, newton_fixed, Corrected};
use crate::problem::Problem;
use crate::tracker::{Continuation, Node, Segment};

/// The outcome of one call of [`Stepper::step`].
#[derive(Debug, Clone, PartialEq)]
pub struct Step {
    /// The newly accepted point, or `None` if the run stopped without accepting one
    /// (step budget used up, step size below `ds_min`, a start on the range boundary
    /// heading out, or a stepper that had already stopped).
    pub point: Option<Point>,
    /// The special points located between the previous point and `point`, ordered by
    /// arclength (empty when `point` is `None`).
    pub special: Vec<SpecialPoint>,
    /// `Some(reason)` if the run has stopped: no further point will be accepted until
    /// the stepper is [restarted](Stepper::restart) or [reversed](Stepper::reverse).
    pub stop: Option<StopReason>,
}

/// A pseudo-arclength continuation that advances one accepted step at a time.
///
/// Created by [`Continuation::start`] (or [`Continuation::start_switch`] on the second
/// branch through a branch point). Each [`Stepper::step`] performs one accepted
/// predictor–corrector step, with the retries and step control of the
/// [`Continuation`] documentation, detects and locates the special points inside the
/// step and reports them in a [`Step`]. Between steps the caller may inspect the
/// current point, change the step size ([`Stepper::set_ds`]), stop
/// ([`Stepper::stop`]), take the branch traced so far ([`Stepper::finish`]) or begin a
/// new branch at the current point ([`Stepper::restart`], [`Stepper::reverse`]).
///
/// The stepper is also an [`Iterator`] over `Result<Step, ContinuationError>`: it
/// yields every step including the stopping one, and ends after it (or after an
/// error).
///
/// ```
/// use nalgebra::{DMatrix, DVector};
/// use rodloop_continuation::{Continuation, Problem, PseudoArclength, SpecialKind};
///
/// /// x² + p² = 1.
/// struct Circle;
/// impl Problem for Circle {
///     type Error = std::convert::Infallible;
///     fn dim(&self) -> usize { 1 }
///     fn residual(&self, x: &DVector<f64>, p: f64) -> Result<DVector<f64>, Self::Error> {
///         Ok(DVector::from_element(1, x[0] * x[0] + p * p - 1.0))
///     }
///     fn jacobian(&self, x: &DVector<f64>, _p: f64) -> Result<DMatrix<f64>, Self::Error> {
///         Ok(DMatrix::from_element(1, 1, 2.0 * x[0]))
///     }
///     fn dparam(&self, _x: &DVector<f64>, p: f64) -> Result<DVector<f64>, Self::Error> {
///         Ok(DVector::from_element(1, 2.0 * p))
///     }
/// }
///
/// let cont = Continuation::new(&Circle, PseudoArclength::new().with_ds(0.05)?);
/// let mut stepper = cont.start(&DVector::from_element(1, 1.0), 0.0)?;
/// // Step until the first fold (p = 1) has been passed.
/// let fold = loop {
///     let step = stepper.step()?;
///     if let Some(f) = step.special.into_iter().find(|s| s.kind == SpecialKind::Fold) {
///         break f;
///     }
///     assert!(step.stop.is_none());
/// };
/// assert!((fold.p - 1.0).abs() < 1e-10);
/// let branch = stepper.finish();
/// assert_eq!(branch.folds().count(), 1);
/// # Ok::<(), rodloop_continuation::ContinuationError>(())
/// ```
pub struct Stepper<'c, 'a, P: Problem + ?Sized> {
    cont: &'c Continuation<'a, P>,
    nodes: Vec<Node>,
    special: Vec<SpecialPoint>,
    ds: f64,
    /// Detection runs on segments with this index and later.
    detect_from: usize,
    /// Accepted steps of the current branch.
    steps: usize,
    /// Largest distance of a point of the current branch from its first point.
    max_dist: f64,
    stop: Option<StopReason>,
    /// Set when `step` returned an error; ends the iterator.
    failed: bool,
}

impl<P: Problem + ?Sized> std::fmt::Debug for Stepper<'_, '_, P> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Stepper")
            .field("points", &self.nodes.len())
            .field("special", &self.special.len())
            .field("ds", &self.ds)
            .field("steps", &self.steps)
            .field("stop", &self.stop)
            .finish()
    }
}

impl<'c, 'a, P: Problem + ?Sized> Stepper<'c, 'a, P> {
    /// A stepper from already accepted `nodes` (at least one) and step `ds`; detection
    /// runs on segments `detect_from` and later.
    pub(crate) fn from_nodes(
        cont: &'c Continuation<'a, P>,
        nodes: Vec<Node>,
        ds: f64,
        detect_from: usize,
    ) -> Self {
        let max_dist = match nodes.first() {
            Some(first) => nodes
                .iter()
                .map(|nd| (&nd.y - &first.y).norm())
                .fold(0.0, f64::max),
            None => 0.0,
        };
        Stepper {
            cont,
            nodes,
            special: Vec::new(),
            ds,
            detect_from,
            steps: 0,
            max_dist,
            stop: None,
            failed: false,
        }
    }

    fn ev(&self) -> Evaluator<'a, P> {
        Evaluator::new(self.cont.problem())
    }

    fn last_node(&self) -> &Node {
        // `nodes` is never empty: every constructor and `restart` put one node in.
        &self.nodes[self.nodes.len() - 1]
    }

    /// Performs one accepted pseudo-arclength step (Keller 1977; Allgower & Georg
    /// 2003, ch. 2): Euler predictor along the current tangent, bordered Newton
    /// corrector, the acceptance tests and step-size control described at
    /// [`Continuation`], then detection and location of the special points inside the
    /// step.
    ///
    /// Rejected trial steps are retried with a smaller step inside this call, so one
    /// call adds at most one point. When the run stops (see [`StopReason`]), the
    /// returned [`Step::stop`] says why; calling `step` again then returns the same
    /// reason without a point.
    ///
    /// # Errors
    /// Errors of the problem or of the stability callback. The stepper stays at its
    /// last accepted point; a later call retries from there.
    pub fn step(&mut self) -> Result<Step, ContinuationError> {
        match self.step_inner() {
            Ok(s) => Ok(s),
            Err(e) => {
                self.failed = true;
                Err(e)
            }
        }
    }

    fn stopped(&mut self, reason: StopReason) -> Step {
        self.stop = Some(reason);
        Step {
            point: None,
            special: Vec::new(),
            stop: Some(reason),
        }
    }

    fn step_inner(&mut self) -> Result<Step, ContinuationError> {
        if let Some(reason) = self.stop {
            return Ok(self.stopped(reason));
        }
        let cont = self.cont;
        let st = cont.settings();
        let ev = self.ev();
        let n = ev.n;
        let tol = cont.corrector_tol();
        let cos_max = st.max_turn.cos();
        if self.steps >= st.max_steps {
            return Ok(self.stopped(StopReason::MaxSteps));
        }
        let mut ds = self.ds;
        let (y1, tan1, iterations, stop) = loop {
            let last = self.last_node();
            if ds < st.ds_min {
                let p = last.y[n];
                self.ds = ds;
                return Ok(self.stopped(StopReason::StepTooSmall { ds, p }));
            }

            // Predictor and corrector.
            let pred = &last.y + &last.t * ds;
            let c = last.t.dot(&last.y) + ds;
            let (y1, iterations) = match correct_bordered(&ev, pred.clone(), &last.t, c, tol)? {
                Corrected::Converged { y, iterations } => (y, iterations),
                Corrected::Failed => {
                    ds *= st.shrink;
                    continue;
                }
            };
            if (&y1 - &pred).norm() > ds {
                ds *= st.shrink;
                continue;
            }
            let tan1 = linalg::tangent(&ev, &y1, &last.t)?;
            if tan1.t.dot(&last.t) < cos_max {
                ds *= st.shrink;
                continue;
            }

            // Range boundary and loop closure.
            let (mut y1, mut tan1) = (y1, tan1);
            let mut stop = None;
            let p1 = y1[n];
            // Where the step leaves the range: at its end, or inside it when it turns back
            // (a fold of the parameter beyond the boundary, between two points inside).
            let exit = if p1 > st.p_max || p1 < st.p_min {
                let pb = if p1 > st.p_max { st.p_max } else { st.p_min };
                let (xk, pk) = ev.split(&last.y);
                let (x1, _) = ev.split(&y1);
                let th = (pb - pk) / (p1 - pk);
                Some((pb, &xk + (x1 - &xk) * th))
            } else {
                let h = last.t.dot(&(&y1 - &last.y));
                range_exit(
                    (last.y[n], last.t[n]),
                    (p1, tan1.t[n]),
                    h,
                    (st.p_min, st.p_max),
                )
                .map(|(pb, sigma)| {
                    let (xk, _) = ev.split(&last.y);
                    let (tx, _) = ev.split(&last.t);
                    (pb, xk + tx * sigma)
                })
            };
            if let Some((pb, guess)) = exit {
                match newton_fixed(&ev, guess, pb, st.tol, st.max_iterations) {
                    Ok((xb, _)) => {
                        y1 = ev.join(&xb, pb);
                        tan1 = linalg::tangent(&ev, &y1, &last.t)?;
                        stop = Some(StopReason::LeftRange { boundary: pb });
                    }
                    Err(e @ ContinuationError::Problem(_)) => return Err(e),
                    Err(_) => {
                        ds *= st.shrink;
                        continue;
                    }
                }
            } else if st.detect_loops && self.nodes.len() >= 2 {
                let first = &self.nodes[0];
                let d = &y1 - &last.y;
                let w = &first.y - &last.y;
                let dn = d.norm();
                let tau = w.dot(&d) / (dn * dn);
                if tau > 0.0
                    && tau <= 1.0
                    && self.max_dist > 3.0 * dn
                    && tan1.t.dot(&first.t) >= cos_max
                    && (&w - &d * tau).norm() <= 0.1 * dn
                {
                    y1 = first.y.clone();
                    tan1 = Tangent {
                        t: first.t.clone(),
                        det_sign: first.det_sign,
                        log_det: first.log_det,
                    };
                    stop = Some(StopReason::ClosedLoop);
                }
            }

            // A start exactly on the boundary, heading out: nothing to add.
            if let Some(reason) = stop {
                if (&y1 - &last.y).amax() <= 1e-14 * (1.0 + last.y.amax()) {
                    self.ds = ds;
                    return Ok(self.stopped(reason));
                }
            }
            break (y1, tan1, iterations, stop);
        };

        // Accept.
        self.steps += 1;
        let last = self.last_node();
        let h = last.t.dot(&(&y1 - &last.y));
        let node1 = cont.make_node(&ev, y1, tan1, last.s + h.max(0.0), h)?;
        let seg = self.nodes.len() - 1;
        let mut found = if seg >= self.detect_from && h > 0.0 {
            cont.detect(
                &ev,
                &Segment {
                    a: &self.nodes[seg],
                    b: &node1,
                    h,
                    index: seg,
                },
            )?
        } else {
            Vec::new()
        };
        found.sort_by(|a, b| a.s.total_cmp(&b.s));
        self.special.extend(found.iter().cloned());
        self.max_dist = self.max_dist.max((&node1.y - &self.nodes[0].y).norm());
        let point = node_point(&ev, &node1);
        self.nodes.push(node1);

        // Step control (not needed once stopped).
        if stop.is_none() {
            let target = st.target_iterations;
            if iterations < target {
                ds *= st.growth;
            } else if iterations > target {
                ds *= st.shrink.max(target as f64 / iterations as f64);
            }
            ds = ds.clamp(st.ds_min, st.ds_max);
        }
        self.ds = ds;
        let stop = stop.or((self.steps >= st.max_steps).then_some(StopReason::MaxSteps));
        self.stop = stop;
        Ok(Step {
            point: Some(point),
            special: found,
            stop,
        })
    }

    /// The current (last accepted) point.
    pub fn current(&self) -> Point {
        node_point(&self.ev(), self.last_node())
    }

    /// The unit tangent `(ẋ, ṗ)` at the current point, oriented in the direction of
    /// continuation (length `n + 1`).
    pub fn tangent(&self) -> &DVector<f64> {
        &self.last_node().t
    }

    /// The step size the next step will try first.
    pub fn ds(&self) -> f64 {
        self.ds
    }

    /// Sets the step size the next step will try first; it must lie in
    /// `[ds_min, ds_max]` of the settings. Step control continues from it.
    ///
    /// # Errors
    /// [`ContinuationError::InvalidSetting`] (`"ds"`) if `ds` is not finite or lies
    /// outside the bounds.
    pub fn set_ds(&mut self, ds: f64) -> Result<(), ContinuationError> {
        let st = self.cont.settings();
        if !(ds >= st.ds_min && ds <= st.ds_max) {
            return Err(ContinuationError::invalid(
                "ds",
                format!(
                    "step {ds} outside [ds_min, ds_max] = [{}, {}]",
                    st.ds_min, st.ds_max
                ),
            ));
        }
        self.ds = ds;
        Ok(())
    }

    /// Number of steps accepted on the current branch (at most `max_steps`).
    pub fn steps(&self) -> usize {
        self.steps
    }

    /// Number of points of the current branch (accepted steps plus the starting
    /// point(s)).
    pub fn num_points(&self) -> usize {
        self.nodes.len()
    }

    /// The special points located so far on the current branch, ordered by arclength.
    pub fn special(&self) -> &[SpecialPoint] {
        &self.special
    }

    /// Why the run stopped, or `None` while it can still advance.
    pub fn stop_reason(&self) -> Option<StopReason> {
        self.stop
    }

    /// The continuation this stepper runs.
    pub fn continuation(&self) -> &'c Continuation<'a, P> {
        self.cont
    }

    /// Stops the run: later calls of [`Stepper::step`] accept no point, and the branch
    /// returned by [`Stepper::finish`] carries [`StopReason::Interrupted`]. Does
    /// nothing if the run has already stopped.
    pub fn stop(&mut self) {
        if self.stop.is_none() {
            self.stop = Some(StopReason::Interrupted);
        }
    }

    /// The branch traced so far. Its [`Branch::stop`] is the reason the run stopped, or
    /// [`StopReason::Interrupted`] if it had not.
    pub fn finish(mut self) -> Branch {
        self.take_branch()
    }

    /// Ends the current branch and begins a new one at the current point, in the same
    /// direction: the new branch's first point is the current point (arclength 0), the
    /// step budget `max_steps` starts afresh, loop detection refers to the new first
    /// point, and the step size is kept (clamped to `[ds_min, ds_max]`). Returns the
    /// branch that ended (as [`Stepper::finish`] would).
    pub fn restart(&mut self) -> Branch {
        self.restart_impl(false)
    }

    /// Like [`Stepper::restart`], but the new branch leaves the current point in the
    /// opposite direction (tangent `−t`). For instance, after the run left the
    /// parameter range, this traces the branch back from the boundary.
    pub fn reverse(&mut self) -> Branch {
        self.restart_impl(true)
    }

    fn restart_impl(&mut self, flip: bool) -> Branch {
        let mut first = self.last_node().clone();
        let old = self.take_branch();
        first.s = 0.0;
        first.ds = 0.0;
        if flip {
            // det [A; −tᵀ] = −det [A; tᵀ].
            first.t.neg_mut();
            first.det_sign = -first.det_sign;
        }
        let st = self.cont.settings();
        self.nodes = vec![first];
        self.special.clear();
        self.ds = self.ds.clamp(st.ds_min, st.ds_max);
        self.detect_from = 0;
        self.steps = 0;
        self.max_dist = 0.0;
        self.stop = None;
        self.failed = false;
        old
    }

    /// Moves the current branch out (leaving `nodes` and `special` empty).
    fn take_branch(&mut self) -> Branch {
        let ev = self.ev();
        let mut special = std::mem::take(&mut self.special);
        special.sort_by(|a, b| a.s.total_cmp(&b.s));
        let points = std::mem::take(&mut self.nodes)
            .iter()
            .map(|nd| node_point(&ev, nd))
            .collect();
        Branch {
            points,
            special,
            stop: self.stop.unwrap_or(StopReason::Interrupted),
        }
    }
}

/// Running a [`Continuation`]: [`Continuation::run`] and [`Continuation::start`] live here,
/// beside the [`Stepper`] they return, so that the tracker does not depend on the stepper.
impl<'a, P: Problem + ?Sized> Continuation<'a, P> {
    /// Traces the branch through the solution near `(x0, p0)`.
    ///
    /// `x0` is first corrected at fixed `p0` by Newton's method (skipped if
    /// `‖F(x0, p0)‖∞ ≤ tol` already, so that a run may start exactly at a singular
    /// point). The first tangent is oriented by the settings' direction (towards
    /// increasing `p` for [`Direction::Forward`](crate::Direction::Forward)); if the
    /// start is a fold, the tangent is the kernel vector of `[∂F/∂x ∂F/∂p]` with the
    /// sign of its `p`-component undetermined.
    ///
    /// # Errors
    /// Invalid settings, a wrong `x0` length, `p0` outside the range, failure of the
    /// initial Newton correction, and errors of the problem or the stability callback.
    /// Difficulties met later end the run with a [`StopReason`](crate::StopReason) instead.
    pub fn run(&self, x0: &DVector<f64>, p0: f64) -> Result<Branch, ContinuationError> {
        let mut stepper = self.start(x0, p0)?;
        while stepper.step()?.stop.is_none() {}
        Ok(stepper.finish())
    }

    /// Prepares a run from the solution near `(x0, p0)` without taking a step: the
    /// returned [`Stepper`] holds the corrected first point and its tangent, and
    /// advances one accepted step per [`Stepper::step`].
    ///
    /// `x0` is corrected and the first tangent oriented exactly as in
    /// [`Continuation::run`], which is this function followed by calls of
    /// [`Stepper::step`] until one reports a stop, and [`Stepper::finish`].
    ///
    /// # Errors
    /// As [`Continuation::run`] for the set-up: invalid settings, a wrong `x0` length,
    /// `p0` outside the range, failure of the initial Newton correction, and errors of
    /// the problem or the stability callback.
    pub fn start(
        &self,
        x0: &DVector<f64>,
        p0: f64,
    ) -> Result<Stepper<'_, 'a, P>, ContinuationError> {
        let st = self.settings();
        st.validate()?;
        let ev = Evaluator::new(self.problem());
        ev.check_state(x0)?;
        self.check_in_range(p0)?;
        let n = ev.n;
        let (x, _) = newton_fixed(&ev, x0.clone(), p0, st.tol, st.max_iterations)?;
        let y0 = ev.join(&x, p0);
        let mut border = DVector::zeros(n + 1);
        border[n] = st.direction.sign();
        let tan = linalg::tangent(&ev, &y0, &border)?;
        let node0 = self.make_node(&ev, y0, tan, 0.0, 0.0)?;
        Ok(Stepper::from_nodes(self, vec![node0], st.ds, 0))
    }
}

impl<P: Problem + ?Sized> Iterator for Stepper<'_, '_, P> {
    type Item = Result<Step, ContinuationError>;

    /// The next [`Stepper::step`]; `None` once the run has stopped or a step failed.
    fn next(&mut self) -> Option<Self::Item> {
        if self.stop.is_some() || self.failed {
            return None;
        }
        Some(self.step())
    }
}

/// The public [`Point`] of a node.
fn node_point<P: Problem + ?Sized>(ev: &Evaluator<'_, P>, nd: &Node) -> Point {
    let (x, p) = ev.split(&nd.y);
    Point {
        x,
        p,
        tangent: nd.t.clone(),
        ds: nd.ds,
        s: nd.s,
        index: nd.index,
    }
}

/// Where the step from `(p0, ṗ0)` to `(p1, ṗ1)` (arclength `h`, both ends inside
/// `[p_min, p_max]`) leaves the range on the way: the cubic Hermite interpolant of `p` over
/// the step exceeds a bound when the parameter turns (a fold) beyond it. Returns the bound
/// and the arclength of the first crossing, or `None` when the interpolant stays inside.
fn range_exit(
    (p0, dp0): (f64, f64),
    (p1, dp1): (f64, f64),
    h: f64,
    (p_min, p_max): (f64, f64),
) -> Option<(f64, f64)> {
    if h.is_nan() || h <= 0.0 || (p_min.is_infinite() && p_max.is_infinite()) {
        return None;
    }
    let p = |t: f64| {
        let (t2, t3) = (t * t, t * t * t);
        (2.0 * t3 - 3.0 * t2 + 1.0) * p0
            + (t3 - 2.0 * t2 + t) * h * dp0
            + (-2.0 * t3 + 3.0 * t2) * p1
            + (t3 - t2) * h * dp1
    };
    const SAMPLES: usize = 64;
    let outside = |v: f64| v > p_max || v < p_min;
    let k = (1..SAMPLES).find(|&k| outside(p(k as f64 / SAMPLES as f64)))?;
    let pb = if p(k as f64 / SAMPLES as f64) > p_max {
        p_max
    } else {
        p_min
    };
    let (mut a, mut b) = ((k - 1) as f64 / SAMPLES as f64, k as f64 / SAMPLES as f64);
    for _ in 0..60 {
        let m = 0.5 * (a + b);
        if outside(p(m)) {
            b = m;
        } else {
            a = m;
        }
    }
    Some((pb, 0.5 * (a + b) * h))
}
