//! Globalised solves for hard scenes: when Newton (with relaxation) from the start does not
//! reach an equilibrium of the requested branch, follow the branch by continuation in the
//! stiffness ratio `D1/D0` from a mild contrast where the direct solve is easy (a homotopy,
//! Allgower & Georg 2003, ch. 1), and say what was done.
//!
//! The branch is identified once, at the mild contrast, from the periods of `κ_g`
//! ([`crate::identify`]); along the homotopy the state stays on that branch by continuity.
//! A fold in `D1/D0` before the target means the branch does not exist at the target
//! contrast (it is reported as such).

use nalgebra::DVector;
use rodloop_continuation::{Continuation, Direction, PseudoArclength};

use crate::accuracy::{finish_with_accuracy, solve_cells, Accuracy, AccurateEquilibrium};
use crate::identify::identify_equilibrium;
use crate::param::Param;
use crate::seam::ParamProblem;
use crate::solve::{solve_from_state, Equilibrium, Globalization, SolveOptions};
use crate::start::StartShape;
use crate::stiffness::Stiffness;
use crate::SolverError;

/// How a robust solve reached its equilibrium.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Strategy {
    /// Newton (with relaxation) from the start.
    Direct,
    /// Newton (with relaxation) from the start with its arclength origin moved by `shift`
    /// (a fraction of the length), after the start as given failed.
    Shifted {
        /// The shift of the start's origin.
        shift: f64,
        /// Why the unshifted start was not used.
        reason: String,
    },
    /// Continuation in `D1/D0` from `from` (solved directly) to the target.
    ContinuationInD1 {
        /// The shift of the start's origin used at the mild contrast.
        shift: f64,
        /// The mild contrast the branch was solved at first.
        from: f64,
        /// Accepted continuation steps.
        steps: usize,
        /// Why the direct solve was not used.
        reason: String,
    },
}

impl Strategy {
    /// One line for people.
    pub fn describe(&self) -> String {
        match self {
            Strategy::Direct => "Newton from the start".into(),
            Strategy::Shifted { shift, reason } => format!(
                "Newton from the start with its origin moved by {shift} of the length, because from the start as given the solve {reason}"
            ),
            Strategy::ContinuationInD1 {
                shift,
                from,
                steps,
                reason,
            } => format!(
                "continuation in D1/D0 from {from} ({steps} steps, start origin moved by {shift}), because the direct solve {reason}"
            ),
        }
    }
}

/// Wall-clock budget of the fallback strategies (the direct solve is not limited): past it,
/// no new attempt is started and a running continuation stops, with a message.
const BUDGET: std::time::Duration = std::time::Duration::from_secs(8);

/// Mild contrasts tried as homotopy starts, in order.
const MILD: [f64; 2] = [0.9, 0.6];

/// Solve a state of the branch with `eta` periods of `κ_g` at `lbar` (see
/// [`crate::solve_with_accuracy`]), falling back to continuation in `D1/D0` for two-segment
/// profiles when the direct solve fails or lands on another branch. `eta = None` accepts
/// whatever branch the direct solve finds (no fallback for a wrong branch).
pub fn solve_robust(
    radius: f64,
    lbar: f64,
    stiffness: &Stiffness,
    start: &StartShape,
    accuracy: Accuracy,
    eta: Option<u32>,
    opts: &SolveOptions,
) -> Result<(AccurateEquilibrium, Strategy), SolverError> {
    let periods = start.periods(lbar)?;
    let n = accuracy.cells(periods, stiffness);
    let check = |res: Result<Equilibrium, SolverError>| -> Result<Equilibrium, String> {
        let eq = res.map_err(|e| format!("failed ({e})"))?;
        match (eta, identify_equilibrium(&eq)) {
            (None, _) => Ok(eq),
            (Some(want), Ok(p)) if p.eta == want => Ok(eq),
            (Some(_), Ok(p)) => Err(format!(
                "converged onto a state with {} periods of κ_g",
                p.eta
            )),
            (Some(_), Err(e)) => Err(format!("gave a state whose branch is unclear ({e})")),
        }
    };
    // A solve at the main resolution that is on the branch, completed by its companion.
    let attempt = |start: &StartShape| -> Result<AccurateEquilibrium, String> {
        let main = check(solve_cells(radius, lbar, n, stiffness, start, None, opts))?;
        finish_with_accuracy(main, radius, stiffness, start, accuracy, opts).map_err(|e| {
            format!("converged, but not its companion solve for the error estimate ({e})")
        })
    };
    if stiffness.is_uniform() {
        // Nothing to gain from other arrangements or a homotopy: the result as it is (a
        // state on another branch is the caller's to refuse, with its own message).
        let main = solve_cells(radius, lbar, n, stiffness, start, None, opts)?;
        let acc = finish_with_accuracy(main, radius, stiffness, start, accuracy, opts)?;
        return Ok((acc, Strategy::Direct));
    }
    let reason = match attempt(start) {
        Ok(acc) => return Ok((acc, Strategy::Direct)),
        Err(r) => r,
    };
    // The start with its origin moved along the loop: a non-uniform rod meets the shape
    // elsewhere, and another arrangement may be within Newton's reach.
    let per = 1.0 / periods.max(1) as f64;
    let shifts: Vec<f64> = [0.25, 0.5, 0.75].iter().map(|f| f * per).collect();
    let t0 = std::time::Instant::now();
    let deadline = t0 + BUDGET;
    for &shift in &shifts {
        if std::time::Instant::now() > deadline {
            break;
        }
        let shifted = start.shifted(lbar, shift)?;
        if let Ok(acc) = attempt(&shifted) {
            return Ok((acc, Strategy::Shifted { shift, reason }));
        }
    }
    let Stiffness::Tanh { d0, d1, .. } = stiffness else {
        return Err(SolverError::InvalidInput(format!(
            "the solve {reason} (also with the start's origin moved by {shifts:?}); \
             try --from a state of this branch at a nearby length"
        )));
    };
    let target = d1 / d0;
    let mut tried = Vec::new();
    // Energies of the mild-contrast states already followed: starts that relax to the same
    // state are not followed twice.
    let mut seen: Vec<f64> = Vec::new();
    for &from in MILD.iter().filter(|&&m| m > target) {
        for shift in std::iter::once(0.0).chain(shifts.iter().copied()) {
            if std::time::Instant::now() > deadline {
                tried.push(format!(
                    "stopped after {:.0} s, the time budget of the fallbacks",
                    BUDGET.as_secs_f64()
                ));
                break;
            }
            let shifted = start.shifted(lbar, shift)?;
            let outcome = homotopy(
                radius, lbar, n, stiffness, &shifted, from, target, eta, opts, &mut seen, deadline,
            );
            match outcome {
                Ok(Some((main, steps))) => {
                    let acc = match finish_with_accuracy(
                        main, radius, stiffness, &shifted, accuracy, opts,
                    ) {
                        Ok(acc) => acc,
                        Err(e) => {
                            tried.push(format!(
                                "from D1/D0 = {from}, origin moved by {shift}: the companion solve failed ({e})"
                            ));
                            continue;
                        }
                    };
                    return Ok((
                        acc,
                        Strategy::ContinuationInD1 {
                            shift,
                            from,
                            steps,
                            reason,
                        },
                    ));
                }
                Ok(None) => {}
                Err(e) => tried.push(format!("from D1/D0 = {from}, origin moved by {shift}: {e}")),
            }
        }
    }
    Err(SolverError::InvalidInput(format!(
        "the direct solve {reason}; continuation in D1/D0 did not reach {target} either: {}. \
         Try --from a state of this branch at a nearby length",
        tried.join("; ")
    )))
}

/// A problem continued in `q = ln θ` instead of `θ` (three decades of `D1/D0` at even
/// steps).
struct LogParam<P>(P);

impl<P: rodloop_continuation::Problem> rodloop_continuation::Problem for LogParam<P> {
    type Error = P::Error;
    fn dim(&self) -> usize {
        self.0.dim()
    }
    fn residual(&self, x: &DVector<f64>, q: f64) -> Result<DVector<f64>, P::Error> {
        self.0.residual(x, q.exp())
    }
    fn jacobian(&self, x: &DVector<f64>, q: f64) -> Result<nalgebra::DMatrix<f64>, P::Error> {
        self.0.jacobian(x, q.exp())
    }
    fn dparam(&self, x: &DVector<f64>, q: f64) -> Result<DVector<f64>, P::Error> {
        Ok(self.0.dparam(x, q.exp())? * q.exp())
    }
    fn factorize(
        &self,
        x: &DVector<f64>,
        q: f64,
    ) -> Result<Box<dyn rodloop_continuation::Factorization + '_>, P::Error> {
        self.0.factorize(x, q.exp())
    }
}

/// Solve at `from` (mild contrast), check the branch, continue in `D1/D0` to `target`.
/// `Ok(None)` when the mild-contrast state is one already followed (`seen`).
#[allow(clippy::too_many_arguments)]
fn homotopy(
    radius: f64,
    lbar: f64,
    cells: usize,
    stiffness: &Stiffness,
    start: &StartShape,
    from: f64,
    target: f64,
    eta: Option<u32>,
    opts: &SolveOptions,
    seen: &mut Vec<f64>,
    deadline: std::time::Instant,
) -> Result<Option<(Equilibrium, usize)>, SolverError> {
    let mild = stiffness.with_param(Param::D1, from)?;
    let eq0 = solve_cells(radius, lbar, cells, &mild, start, None, opts)?;
    let e0 = eq0.energy().total;
    if seen
        .iter()
        .any(|e| (e - e0).abs() <= 1e-9 * e0.abs().max(1.0))
    {
        return Ok(None);
    }
    seen.push(e0);
    if let Some(want) = eta {
        let p = identify_equilibrium(&eq0)?;
        if p.eta != want {
            return Err(SolverError::InvalidInput(format!(
                "at D1/D0 = {from} the start relaxes to a state with {} periods of κ_g, not {want}",
                p.eta
            )));
        }
    }
    let problem = ParamProblem::new(eq0.model().clone(), Param::D1)?;
    let log_problem = LogParam(problem.clone());
    let settings = PseudoArclength::new()
        .with_ds(0.05)
        .and_then(|s| s.with_ds_bounds(1e-7, 0.5))
        .and_then(|s| s.with_direction(Direction::Backward))
        .and_then(|s| s.with_max_steps(400))
        .and_then(|s| s.with_detect_branch_points(false))
        .map_err(|e| SolverError::InvalidInput(e.to_string()))?;
    let cont = Continuation::new(&log_problem, settings);
    let x0 = DVector::from_vec(eq0.state());
    let mut stepper = cont
        .start(&x0, from.ln())
        .map_err(|e| SolverError::InvalidInput(format!("continuation in D1/D0: {e}")))?;
    let mut prev = (x0, from);
    // Folds passed (the branch may turn back in D1/D0 and come down again on its other
    // side); the lowest D1/D0 reached.
    let mut folds = Vec::new();
    let mut lowest = from;
    loop {
        if std::time::Instant::now() > deadline {
            return Err(SolverError::InvalidInput(format!(
                "continuation in D1/D0 ran out of its time budget at D1/D0 = {:.4}",
                prev.1
            )));
        }
        let step = stepper
            .step()
            .map_err(|e| SolverError::InvalidInput(format!("continuation in D1/D0: {e}")))?;
        folds.extend(
            step.special
                .iter()
                .filter(|sp| sp.kind == rodloop_continuation::SpecialKind::Fold)
                .map(|sp| sp.p.exp()),
        );
        if let Some(pt) = &step.point {
            let p = pt.p.exp();
            if p <= target {
                // Bracketed: interpolate linearly in D1/D0 and correct at the target.
                let t = (prev.1.ln() - target.ln()) / (prev.1.ln() - pt.p);
                let z = &prev.0 + (&pt.x - &prev.0) * t;
                let model = problem.model_at(target)?;
                let newton = SolveOptions {
                    globalization: Globalization::Newton,
                    ..opts.clone()
                };
                let eq = solve_from_state(model, z.as_slice().to_vec(), &newton)?;
                return Ok(Some((eq, stepper.steps())));
            }
            lowest = lowest.min(p);
            if p >= from.max(0.999f64.min(from + 0.05)) || folds.len() > 4 {
                return Err(SolverError::InvalidInput(format!(
                    "the branch turns back in D1/D0 at {} (folds) and reaches no lower than \
                     D1/D0 = {lowest:.4}: it does not exist at {target} with this arrangement of \
                     the soft segment",
                    folds
                        .iter()
                        .map(|f| format!("{f:.4}"))
                        .collect::<Vec<_>>()
                        .join(", ")
                )));
            }
            prev = (pt.x.clone(), p);
        }
        if let Some(reason) = step.stop {
            return Err(SolverError::InvalidInput(format!(
                "continuation in D1/D0 stopped at {:.4} ({reason:?}; lowest D1/D0 reached \
                 {lowest:.4}, folds at {folds:?})",
                prev.1
            )));
        }
    }
}
