//! Globalised solves for hard scenes: when Newton (with relaxation) from the start does not
//! reach an equilibrium of the requested branch, follow the branch by continuation in the
//! stiffness ratio `D1/D0` from a mild contrast where the direct solve is easy (a homotopy,
//! Allgower & Georg 2003, ch. 1), and say what was done.
//!
//! It is one file because the fallbacks are tried in one order by one routine and share its
//! budget, its record of what was tried and the branch check along each path.
//!
//! The branch is identified from the periods of `κ_g` ([`crate::identify`]) at the mild
//! contrast and again at the end of the path: every returned state passes
//! [`crate::verify::verify_state`] for the requested branch, and a state whose count changed
//! along the homotopy is not returned (the next fallback is tried).
//! A fold in `D1/D0` before the target means the branch does not exist at the target
//! contrast (it is reported as such).

use nalgebra::DVector;
use rodloop_continuation::axis::{Axis, OnAxis};
use rodloop_continuation::target::{reach, NotReached, ReachLimits};
use rodloop_continuation::{Direction, PseudoArclength};

use crate::accuracy::{finish_with_accuracy, solve_cells, Accuracy, AccurateEquilibrium};
use crate::identify::identify_equilibrium;
use crate::model::SurfaceModel;
use crate::param::Param;
use crate::seam::ParamProblem;
use crate::solve::{solve_from_state, Equilibrium, Globalization, SolveOptions};
use crate::start::StartShape;
use crate::stiffness::Stiffness;
use crate::verify::{verify_accurate, Verification};
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
    /// Continuation in `L̄` from another length `from` of the branch (solved directly, at the
    /// scene's stiffness) to the target.
    ContinuationInLbar {
        /// The shift of the start's origin used at `from`.
        shift: f64,
        /// The length the branch was solved at first.
        from: f64,
        /// Accepted continuation steps.
        steps: usize,
        /// Why the direct solve was not used.
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
            Strategy::ContinuationInLbar {
                shift,
                from,
                steps,
                reason,
            } => format!(
                "continuation in L̄ from {from} ({steps} steps, start origin moved by {shift}), because the direct solve {reason}"
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

/// Work budget of each of the two continuation fallbacks (in `D1/D0`, in `L̄`), counted in
/// continuation steps plus Newton solves (the direct solve is not limited): past it, no new
/// attempt is started and a running continuation stops, with a message. A count, not a
/// wall-clock time, so that a result does not depend on the machine's load.
pub const BUDGET: usize = 1500;

/// Largest number of cells of a solve (the finer one of an accuracy pair). Newton falls
/// back to the dense KKT matrix (`(2N + 4)²` numbers) where the block factorisation of
/// [`crate::kkt`] meets a singular pivot: at `N = 4096` that matrix takes 512 MiB and its
/// LU about `(2N)³·2/3 ≈ 4·10¹¹` operations (minutes), the most one solve can be asked to
/// afford on a workstation. Cells grow like `N = c (1 + η)` ([`Accuracy::cells`]), so this
/// admits `η` up to about 70 (default accuracy) or 35 (high).
pub const MAX_CELLS: usize = 4096;

/// Which attempts [`solve_robust_with`] makes: the direct and shifted starts, then the
/// continuation fallbacks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Fallbacks {
    /// Newton from the start and from the start with its origin moved (`false`: the caller
    /// has tried those already).
    pub starts: bool,
    /// Continuation in `D1/D0` from the contrasts of `HOMOTOPY_STARTS`.
    pub homotopy: bool,
    /// Continuation in `L̄` from other lengths of the branch's range.
    pub lbar_path: bool,
    /// Work budget of each of the two (see [`BUDGET`]).
    pub budget: usize,
}

impl Default for Fallbacks {
    /// Both fallbacks with the budget [`BUDGET`] (what [`solve_robust`] uses).
    fn default() -> Self {
        Self {
            starts: true,
            homotopy: true,
            lbar_path: true,
            budget: BUDGET,
        }
    }
}

/// Work spent by a fallback, against its budget.
struct Budget {
    spent: std::cell::Cell<usize>,
    limit: usize,
}

impl Budget {
    fn new(limit: usize) -> Self {
        Self {
            spent: std::cell::Cell::new(0),
            limit,
        }
    }

    /// Spend one unit; `false` once the budget is used up.
    fn spend(&self) -> bool {
        self.spent.set(self.spent.get() + 1);
        self.spent.get() <= self.limit
    }
}

/// Contrasts `D1/D0` at which the homotopy starts, in order: where the start shapes (the
/// uniform rod's loops) lie within Newton's reach of an equilibrium whose soft segment sits
/// firmly in place. They are properties of the start shapes and of Newton's method, not of a
/// scene: a contrast this mild moves the loop little from the uniform rod's, and one this
/// clear makes the shift of the soft segment along the loop stiff (near `D1/D0 = 1` that
/// shift is nearly a symmetry, and Newton from a start drifts along it: `solve` failed for
/// every `D1/D0 ≥ 0.95` at `L̄ = 1.3`).
const HOMOTOPY_STARTS: [f64; 2] = [0.9, 0.6];

/// First step of the homotopy, in `ln(D1/D0)` ([`follow_to`]).
const LOG_STEP: f64 = 0.05;

/// The homotopy starts for the contrast `target`: every [`HOMOTOPY_STARTS`] contrast more
/// than one first step ([`LOG_STEP`], in `ln(D1/D0)`) away from the target, on the target's
/// side of the uniform rod (a start within one step is the direct solve again; a path
/// through `D1/D0 = 1` would cross the uniform rod, where the placement of the soft segment
/// is free). Which starts are tried depends on no threshold on the scene's contrast: a
/// scene milder than a start continues from it towards `D1/D0 = 1`, a stronger one away
/// from it.
fn homotopy_sources(target: f64) -> Vec<f64> {
    HOMOTOPY_STARTS
        .iter()
        .copied()
        .filter(|&m| (m < 1.0) == (target < 1.0))
        .filter(|&m| (m.ln() - target.ln()).abs() > LOG_STEP)
        .collect()
}

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
    solve_robust_with(
        radius,
        lbar,
        stiffness,
        start,
        accuracy,
        eta,
        opts,
        Fallbacks::default(),
    )
}

/// [`solve_robust`] with the verification the state passed ([`verify_accurate`], which
/// every state it returns passes; with `eta = None` for a uniform rod): a caller that reports
/// the state as returned need not verify it again.
pub fn solve_robust_verified(
    radius: f64,
    lbar: f64,
    stiffness: &Stiffness,
    start: &StartShape,
    accuracy: Accuracy,
    eta: Option<u32>,
    opts: &SolveOptions,
) -> Result<(AccurateEquilibrium, Strategy, Verification), SolverError> {
    robust(
        radius,
        lbar,
        stiffness,
        start,
        accuracy,
        eta,
        opts,
        Fallbacks::default(),
    )
}

/// [`solve_robust`] with a choice of the attempts ([`Fallbacks`]): the direct and shifted
/// starts, the continuation fallbacks, and their budget. Used by the branch diagram of
/// two-segment rods, which runs the starts and the homotopies in separate passes and follows
/// families in `L̄` itself.
#[allow(clippy::too_many_arguments)]
pub fn solve_robust_with(
    radius: f64,
    lbar: f64,
    stiffness: &Stiffness,
    start: &StartShape,
    accuracy: Accuracy,
    eta: Option<u32>,
    opts: &SolveOptions,
    fallbacks: Fallbacks,
) -> Result<(AccurateEquilibrium, Strategy), SolverError> {
    robust(
        radius, lbar, stiffness, start, accuracy, eta, opts, fallbacks,
    )
    .map(|(acc, strategy, _)| (acc, strategy))
}

/// An error where a loop of `periods` periods at `n` cells (doubled for the companion of
/// [`Accuracy::High`]) exceeds [`MAX_CELLS`].
fn check_cells(periods: usize, n: usize, accuracy: Accuracy) -> Result<(), SolverError> {
    let finest = if accuracy == Accuracy::High { 2 * n } else { n };
    if finest > MAX_CELLS {
        Err(SolverError::InvalidInput(format!(
            "a loop with {periods} periods of κ_g needs {finest} cells at {} accuracy, above the \
             limit of {MAX_CELLS} cells (the dense fallback of Newton's method would need {:.0} \
             GiB)",
            format!("{accuracy:?}").to_lowercase(),
            8.0 * ((2 * finest + 4) as f64).powi(2) / 1024f64.powi(3)
        )))
    } else {
        Ok(())
    }
}

/// [`solve_robust_with`], with the verification of the state returned.
#[allow(clippy::too_many_arguments)]
fn robust(
    radius: f64,
    lbar: f64,
    stiffness: &Stiffness,
    start: &StartShape,
    accuracy: Accuracy,
    eta: Option<u32>,
    opts: &SolveOptions,
    fallbacks: Fallbacks,
) -> Result<(AccurateEquilibrium, Strategy, Verification), SolverError> {
    let periods = start.periods(lbar)?;
    let n = accuracy.cells(periods, stiffness);
    check_cells(periods, n, accuracy)?;
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
    // A solve at the main resolution that is on the branch, completed by its companion and
    // verified.
    let attempt = |start: &StartShape| -> Result<(AccurateEquilibrium, Verification), String> {
        let main = check(solve_cells(radius, lbar, n, stiffness, start, None, opts))?;
        let acc =
            finish_with_accuracy(main, radius, stiffness, start, accuracy, opts).map_err(|e| {
                format!("converged, but not its companion solve for the error estimate ({e})")
            })?;
        verified(acc, eta)
    };
    if stiffness.is_uniform() {
        // Nothing to gain from other arrangements or a homotopy: the result as it is (a
        // state on another branch is the caller's to refuse, with its own message), if it
        // passes the checks of every reported state.
        let main = solve_cells(radius, lbar, n, stiffness, start, None, opts)?;
        let acc = finish_with_accuracy(main, radius, stiffness, start, accuracy, opts)?;
        let v = verify_accurate(&acc, None)?;
        return Ok((acc, Strategy::Direct, v));
    }
    let reason = if fallbacks.starts {
        match attempt(start) {
            Ok((acc, v)) => return Ok((acc, Strategy::Direct, v)),
            Err(r) => r,
        }
    } else {
        "was not tried (nor the shifted starts)".to_string()
    };
    // The start with its origin moved along the loop: a non-uniform rod meets the shape
    // elsewhere, and another arrangement may be within Newton's reach.
    let per = 1.0 / periods.max(1) as f64;
    let shifts: Vec<f64> = [0.125, 0.25, 0.375, 0.5, 0.625, 0.75, 0.875]
        .iter()
        .map(|f| f * per)
        .collect();
    let budget = Budget::new(fallbacks.budget);
    for &shift in shifts.iter().filter(|_| fallbacks.starts) {
        if !budget.spend() {
            break;
        }
        let shifted = start.shifted(lbar, shift)?;
        if let Ok((acc, v)) = attempt(&shifted) {
            return Ok((acc, Strategy::Shifted { shift, reason }, v));
        }
    }
    let mut tried = Vec::new();
    // Continuation in ln(D1/D0) from a mild contrast, where the start is within reach.
    if let (true, Stiffness::Tanh { d0, d1, .. }) = (fallbacks.homotopy, stiffness) {
        let target = d1 / d0;
        // Energies of the mild-contrast states already followed: starts that relax to the same
        // state are not followed twice.
        let mut seen: Vec<f64> = Vec::new();
        for from in homotopy_sources(target) {
            for shift in std::iter::once(0.0).chain(shifts.iter().copied()) {
                if !budget.spend() {
                    tried.push((
                        "work budget".to_string(),
                        format!(
                            "stopped after {} continuation steps and solves",
                            fallbacks.budget
                        ),
                    ));
                    break;
                }
                let shifted = start.shifted(lbar, shift)?;
                let outcome = homotopy(
                    radius, lbar, n, stiffness, &shifted, from, target, eta, opts, &mut seen,
                    &budget,
                );
                match outcome {
                    Ok(Some((main, steps))) => {
                        let (acc, v) = match finish_with_accuracy(
                            main, radius, stiffness, &shifted, accuracy, opts,
                        )
                        .map_err(|e| format!("the companion solve failed ({e})"))
                        .and_then(|acc| verified(acc, eta))
                        {
                            Ok(verified) => verified,
                            Err(e) => {
                                tried.push((
                                    format!("continuation in D1/D0 from {from}"),
                                    format!("origin moved by {shift:.4}: {e}"),
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
                            v,
                        ));
                    }
                    Ok(None) => {}
                    Err(e) => tried.push((
                        format!("continuation in D1/D0 from {from}"),
                        format!("origin moved by {shift:.4}: {e}"),
                    )),
                }
            }
        }
    }
    // The same family at other lengths of the branch's range at the scene's stiffness,
    // followed in L̄ (its own work budget).
    let budget = Budget::new(fallbacks.budget);
    if let (true, Some(want), StartShape::Euler { .. } | StartShape::Exact { .. }) =
        (fallbacks.lbar_path, eta, start)
    {
        let e = f64::from(want);
        let (lo, hi) = (if want == 1 { 0.0 } else { e - 1.0 }, e + 1.0);
        let mut seeds: Vec<f64> = [0.5, 0.25, 0.75]
            .iter()
            .map(|f| lo + f * (hi - lo))
            .filter(|l| (l - lbar).abs() > 0.02)
            .collect();
        seeds.sort_by(|a, b| (a - lbar).abs().total_cmp(&(b - lbar).abs()));
        let mut seen: Vec<f64> = Vec::new();
        'seeds: for &from in &seeds {
            for shift in std::iter::once(0.0).chain(shifts.iter().copied()) {
                if !budget.spend() {
                    break 'seeds;
                }
                let shifted = start.shifted(from, shift)?;
                match lbar_path(
                    radius, lbar, n, stiffness, &shifted, from, want, opts, &mut seen, &budget,
                ) {
                    Ok(Some((main, steps))) => {
                        match check(Ok(main)).and_then(|main| {
                            finish_with_accuracy(main, radius, stiffness, start, accuracy, opts)
                                .map_err(|e| e.to_string())
                                .and_then(|acc| verified(acc, Some(want)))
                        }) {
                            Ok((acc, v)) => {
                                return Ok((
                                    acc,
                                    Strategy::ContinuationInLbar {
                                        shift,
                                        from,
                                        steps,
                                        reason,
                                    },
                                    v,
                                ));
                            }
                            Err(e) => tried.push((
                                format!("continuation in L̄ from {from}"),
                                format!("origin moved by {shift:.4}: {e}"),
                            )),
                        }
                    }
                    Ok(None) => {}
                    Err(e) => tried.push((
                        format!("continuation in L̄ from {from}"),
                        format!("origin moved by {shift:.4}: {e}"),
                    )),
                }
            }
        }
    }
    let moved: Vec<String> = shifts.iter().map(|s| format!("{s:.4}")).collect();
    Err(SolverError::InvalidInput(format!(
        "the direct solve {reason} (also with the start's origin moved by {}){}. \
         Try --from a state of this branch at a nearby length",
        moved.join(", "),
        summarize_tried(&tried)
    )))
}

/// `acc` and its verification if it passes [`verify_accurate`] for the requested `eta`, else
/// why not.
fn verified(
    acc: AccurateEquilibrium,
    eta: Option<u32>,
) -> Result<(AccurateEquilibrium, Verification), String> {
    match verify_accurate(&acc, eta) {
        Ok(v) => Ok((acc, v)),
        Err(e) => Err(format!("gave a state that fails verification ({e})")),
    }
}

/// The failed fallbacks in one clause each: the path, how many starts failed on it, and the
/// first failure (a full list repeats the same Newton failure a dozen times).
fn summarize_tried(tried: &[(String, String)]) -> String {
    let mut paths: Vec<(&str, usize, &str)> = Vec::new();
    for (path, err) in tried {
        match paths.iter_mut().find(|p| p.0 == path.as_str()) {
            Some(p) => p.1 += 1,
            None => paths.push((path, 1, err)),
        }
    }
    paths
        .iter()
        .map(|(path, count, first)| {
            if *count == 1 {
                format!("; {path}: {first}")
            } else {
                format!("; {path}: {count} starts failed (first: {first})")
            }
        })
        .collect()
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
    budget: &Budget,
) -> Result<Option<(Equilibrium, usize)>, SolverError> {
    let mild = stiffness.with_param(Param::D1, from)?;
    let eq0 = solve_cells(radius, lbar, cells, &mild, start, None, opts)?;
    if !first_seen(seen, &eq0) {
        return Ok(None);
    }
    if let Some(want) = eta {
        require_eta(&eq0, want, &format!("D1/D0 = {from}"))?;
    }
    let problem = ParamProblem::new(eq0.model().clone(), Param::D1)?;
    let (eq, steps) = follow_to(&problem, &eq0, from, target, true, opts, budget).map_err(
        |Stuck { folds, reached }| match folds.is_empty() {
            false => SolverError::InvalidInput(format!(
                "the branch turns back in D1/D0 at {} (folds) and reaches no lower than \
                 D1/D0 = {reached:.4}: it does not exist at {target} with this arrangement of \
                 the soft segment",
                fmt_list(&folds)
            )),
            true => SolverError::InvalidInput(format!(
                "continuation in D1/D0 stopped at {reached:.4} before {target}"
            )),
        },
    )?;
    Ok(Some((eq, steps)))
}

/// Solve the branch at another length `from` of its range, at the scene's stiffness, and
/// continue in `L̄` to `lbar`. `Ok(None)` when the state at `from` was already followed.
#[allow(clippy::too_many_arguments)]
fn lbar_path(
    radius: f64,
    lbar: f64,
    cells: usize,
    stiffness: &Stiffness,
    start: &StartShape,
    from: f64,
    want: u32,
    opts: &SolveOptions,
    seen: &mut Vec<f64>,
    budget: &Budget,
) -> Result<Option<(Equilibrium, usize)>, SolverError> {
    let eq0 = solve_cells(radius, from, cells, stiffness, start, None, opts)?;
    if !first_seen(seen, &eq0) {
        return Ok(None);
    }
    require_eta(&eq0, want, &format!("L̄ = {from}"))?;
    let problem = ParamProblem::new(eq0.model().clone(), Param::Lbar)?;
    let (eq, steps) = follow_to(&problem, &eq0, from, lbar, false, opts, budget).map_err(
        |Stuck { folds, reached }| {
            SolverError::InvalidInput(match folds.is_empty() {
                false => format!(
                    "the family seeded at L̄ = {from} turns back at L̄ = {} and reaches no \
                     closer than L̄ = {reached:.4}",
                    fmt_list(&folds)
                ),
                true => format!("continuation in L̄ from {from} stopped at L̄ = {reached:.4}"),
            })
        },
    )?;
    Ok(Some((eq, steps)))
}

/// Record the energy of `eq` in `seen`; `false` when a state of the same energy was
/// already followed (starts that relax to the same state are not followed twice).
fn first_seen(seen: &mut Vec<f64>, eq: &Equilibrium) -> bool {
    let e0 = eq.energy().total;
    if seen
        .iter()
        .any(|e| (e - e0).abs() <= 1e-9 * e0.abs().max(1.0))
    {
        return false;
    }
    seen.push(e0);
    true
}

/// Refuse a start that relaxed (at `place`) to a state with other than `want` periods.
fn require_eta(eq: &Equilibrium, want: u32, place: &str) -> Result<(), SolverError> {
    let p = identify_equilibrium(eq)?;
    if p.eta != want {
        return Err(SolverError::InvalidInput(format!(
            "at {place} the start relaxes to a state with {} periods of κ_g, not {want}",
            p.eta
        )));
    }
    Ok(())
}

/// The values to 4 decimals, repeats (a fold passed back and forth) once.
fn fmt_list(v: &[f64]) -> String {
    let mut seen: Vec<String> = Vec::new();
    for f in v {
        let t = format!("{f:.4}");
        if !seen.contains(&t) {
            seen.push(t);
        }
    }
    seen.join(", ")
}

/// Why [`follow_to`] did not reach its target: the folds passed and the closest parameter
/// value reached.
struct Stuck {
    folds: Vec<f64>,
    reached: f64,
}

/// Continue the equilibrium `eq0` of `problem` (a one-parameter family at `from`) until the
/// parameter reaches `target`, then correct there with Newton. `log`: continue in `ln θ`
/// (decades of `D1/D0` at even steps). Gives up after 4 folds, when the family turns away
/// from the target for good, when the work budget is spent or when the continuation stops.
fn follow_to(
    problem: &ParamProblem<SurfaceModel>,
    eq0: &Equilibrium,
    from: f64,
    target: f64,
    log: bool,
    opts: &SolveOptions,
    budget: &Budget,
) -> Result<(Equilibrium, usize), Stuck> {
    let axis = if log { Axis::Log } else { Axis::Linear };
    let (q0, qt) = (axis.coordinate(from), axis.coordinate(target));
    let value = |q: f64| axis.value(q);
    let stuck = |folds: Vec<f64>, reached: f64| Stuck { folds, reached };
    let direction = if qt < q0 {
        Direction::Backward
    } else {
        Direction::Forward
    };
    let (ds, ds_max) = if log { (LOG_STEP, 0.5) } else { (0.05, 1.0) };
    let settings = PseudoArclength::new()
        .with_ds(ds)
        .and_then(|s| s.with_ds_bounds(1e-7, ds_max))
        .and_then(|s| s.with_direction(direction))
        .and_then(|s| s.with_max_steps(400))
        .and_then(|s| s.with_detect_branch_points(false))
        .map_err(|_| stuck(vec![], from))?;
    let x0 = DVector::from_vec(eq0.state());
    // The continuation crate's homotopy loop: through at most 4 folds, giving up once the
    // family turns 0.05 back past its start (in q) or the shared work budget is spent.
    let limits = ReachLimits::default();
    let spend = || budget.spend();
    let outcome = if log {
        let lp = OnAxis {
            problem: problem.clone(),
            axis,
        };
        reach(&lp, &settings, &x0, q0, qt, &limits, spend)
    } else {
        reach(problem, &settings, &x0, q0, qt, &limits, spend)
    };
    let (z, steps) = outcome
        .map(|r| (r.x, r.steps))
        .map_err(|NotReached { folds, closest }| {
            stuck(folds.into_iter().map(value).collect(), value(closest))
        })?;
    let model = problem
        .model_at(target)
        .map_err(|_| stuck(vec![], target))?;
    let newton = SolveOptions {
        globalization: Globalization::Newton,
        ..opts.clone()
    };
    let eq = solve_from_state(model, z.as_slice().to_vec(), &newton)
        .map_err(|_| stuck(vec![], target))?;
    Ok((eq, steps))
}

#[cfg(test)]
mod tests {
    use super::summarize_tried;

    /// The homotopy starts lie on the target's side of the uniform rod, more than one first
    /// step away from it in `ln(D1/D0)`, by one rule for every contrast: a nearly uniform
    /// rod continues from both starts towards `D1/D0 = 1`, a contrast next to a start skips
    /// it, strong contrasts use both, and a stiffer segment (`D1 > D0`) none.
    #[test]
    fn homotopy_starts_follow_the_target() {
        use super::homotopy_sources;
        assert_eq!(homotopy_sources(0.001), vec![0.9, 0.6]);
        assert_eq!(homotopy_sources(0.5), vec![0.9, 0.6]);
        assert_eq!(homotopy_sources(0.95), vec![0.9, 0.6]);
        assert_eq!(homotopy_sources(0.999), vec![0.9, 0.6]);
        assert_eq!(homotopy_sources(0.88), vec![0.6]);
        assert_eq!(homotopy_sources(0.62), vec![0.9]);
        assert!(homotopy_sources(2.0).is_empty());
    }

    /// Each fallback path is named once, with how many of its starts failed and the first
    /// failure; the order of first appearance is kept.
    #[test]
    fn failed_fallbacks_are_summarised_per_path() {
        let t = |p: &str, e: &str| (p.to_string(), e.to_string());
        let tried = [
            t(
                "continuation in D1/D0 from 0.9",
                "origin moved by 0.0000: A",
            ),
            t(
                "continuation in D1/D0 from 0.9",
                "origin moved by 0.0625: B",
            ),
            t("continuation in L̄ from 1.5", "origin moved by 0.0000: C"),
            t(
                "continuation in D1/D0 from 0.9",
                "origin moved by 0.1250: D",
            ),
        ];
        assert_eq!(
            summarize_tried(&tried),
            "; continuation in D1/D0 from 0.9: 3 starts failed (first: origin moved by 0.0000: A)\
             ; continuation in L̄ from 1.5: origin moved by 0.0000: C"
        );
        assert_eq!(summarize_tried(&[]), "");
    }
}
