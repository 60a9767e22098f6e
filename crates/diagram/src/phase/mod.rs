//! The phase diagram of a two-segment rod: every exchange of the lowest branch of the
//! uniform rod followed as a curve `L̄_cr(θ)` in a stiffness parameter `θ` (see
//! [`crate::maxwell`] for the augmented system and its continuation).

mod curve;
mod follow;
mod rows;
mod seed;
mod switch;

use nalgebra::DVector;
use rodloop_solver::{Accuracy, Param, SolveOptions, Stiffness};

use crate::DiagramError;

use curve::trace_exchange;
#[cfg(test)]
pub(crate) use seed::lowest_placement;
pub use seed::{maxwell_point, uniform_exchanges};

/// An exchange of the lowest branch of the uniform rod (a crossing `E_a = E_b`, from the
/// exact layer), the start of a curve.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Exchange {
    /// Lowest paper branch just below `L̄_cr`.
    pub from_branch: u32,
    /// Lowest paper branch just above.
    pub to_branch: u32,
    /// The exact critical length of the uniform rod.
    pub lbar_uniform: f64,
}

/// What [`trace_phase`] computes.
#[derive(Clone, Debug)]
pub struct PhaseSettings {
    /// Sphere radius `R`.
    pub radius: f64,
    /// The scene's stiffness profile (two-segment, Eq. (51)).
    pub stiffness: Stiffness,
    /// The continued parameter (`d1`, `gamma`, `s0`, `s1`).
    pub param: Param,
    /// The end value of the parameter (the start is the scene's value).
    pub target: f64,
    /// Length range of the scene: the exchanges of the uniform rod inside it are followed.
    pub lbar_min: f64,
    /// Upper end of the length range.
    pub lbar_max: f64,
    /// Resolution and error estimate ([`Accuracy`]).
    pub accuracy: Accuracy,
    /// Parameter values at which rows are solved exactly (Newton at fixed `θ`).
    pub at: Vec<f64>,
    /// Solver settings of the seeds and re-solves.
    pub solve: SolveOptions,
}

/// How a row of a curve was obtained.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RowSource {
    /// The Maxwell point by the exchange locator on re-solved equilibria (the curve's start).
    Seed,
    /// An accepted point of the pseudo-arclength continuation.
    Continuation,
    /// The Maxwell point of a new pair of states, found just beyond the end of the previous
    /// pair (fold, loss of stability, branch point) by the exchange locator on re-solved
    /// equilibria ([`switch`](self) module docs).
    Switch,
    /// Newton's method on the augmented system at an exact parameter value (`--at`, and the
    /// ladder towards `D1/D0 = 1`).
    Fixed,
    /// The limit `D1/D0 → 1`, extrapolated from the ladder of fixed rows.
    Limit,
}

impl RowSource {
    /// Name in output files.
    pub fn name(self) -> &'static str {
        match self {
            RowSource::Seed => "seed",
            RowSource::Continuation => "continuation",
            RowSource::Switch => "switch",
            RowSource::Fixed => "fixed",
            RowSource::Limit => "limit",
        }
    }
}

/// One Maxwell point of a curve.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PhaseRow {
    /// Parameter value `θ`.
    pub value: f64,
    /// Critical length `L̄_cr` (Richardson-extrapolated for `High`).
    pub lbar_cr: f64,
    /// Estimated absolute error of `lbar_cr`.
    pub error_estimate: f64,
    /// Common energy `E R/(π D0)` of the two states.
    pub energy: f64,
    /// Lowest branch just below `lbar_cr` (from the sign of the slope).
    pub from_branch: u32,
    /// Lowest branch just above.
    pub to_branch: u32,
    /// Stability indices of the states of the exchange's `from_branch` and `to_branch` (those
    /// of [`PhaseCurve::exchange`]).
    pub index: (usize, usize),
    /// Arm of the curve: 0 from the start, +1 after each fold where the energy curves touch.
    pub arm: usize,
    /// `d(E_from − E_to)/dL̄` of the exchange's branches at the crossing (re-solved states).
    pub slope: f64,
    /// How the row was obtained.
    pub source: RowSource,
    /// Estimated error of `energy` as the energy of each of the two states at its own length
    /// (see [`RowStates`]; for the limit row, from the ladder).
    pub energy_error: f64,
    /// The two states, as their files hold them.
    #[serde(skip)]
    pub states: RowStates,
}

/// The two states of a row (those of the exchange's `from_branch` and `to_branch`), each
/// verified as its file holds it ([`crate::reported::verify_reported`]) against the row's
/// energy within [`crate::ESTIMATES`] times the row's `energy_error`. The states written are
/// those of the finer resolution of the row's pair (the main one; the companion for `high`,
/// at its own `L̄`, which differs from the row's by about its estimate).
#[derive(Clone, Debug, Default, PartialEq)]
pub enum RowStates {
    /// No states: the limit row (extrapolated to the uniform rod, not a computed state).
    #[default]
    None,
    /// Both states passed: `[from_branch, to_branch]` of [`PhaseCurve::exchange`].
    Verified(Vec<crate::StateFile>),
    /// A state could not be re-solved or failed a check (why): the row is not reported.
    Unverified(String),
}

/// Why (and where) a curve ends in one direction.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct CurveEnd {
    /// Parameter value of the last Maxwell point of the curve in this direction.
    pub value: f64,
    /// `reached` (the end of the requested range), `unstable` (a state lost stability),
    /// `fold` (the Maxwell point turns back in the parameter), `branch_point`, `failed`, or
    /// `limit` (the uniform rod, `D1/D0 → 1`).
    pub kind: String,
    /// Explanation for people.
    pub reason: String,
}

/// The limit `D1/D0 → 1` of a curve compared with the uniform rod's exact critical length.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct UniformCheck {
    /// Extrapolated `L̄_cr` at `D1/D0 = 1`.
    pub lbar_cr: f64,
    /// Its estimated error (discretisation + extrapolation).
    pub error_estimate: f64,
    /// The exact critical length of the uniform rod.
    pub exact: f64,
    /// `lbar_cr − exact`.
    pub deviation: f64,
}

/// One followed exchange.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PhaseCurve {
    /// The exchange of the uniform rod it starts from.
    pub exchange: Exchange,
    /// Rows in increasing parameter value.
    pub rows: Vec<PhaseRow>,
    /// How the curve ends towards lower and higher parameter values.
    pub ends: Vec<CurveEnd>,
    /// The limit at the uniform rod (`d1` only).
    pub uniform: Option<UniformCheck>,
    /// Accepted continuation steps.
    pub steps: usize,
    /// Cells of the two models `(from_branch, to_branch)` at the main resolution.
    pub cells: (usize, usize),
    /// Folds of the curve where the two energy curves touch (the curve goes on, on its next
    /// arm).
    pub turns: Vec<String>,
    /// Switches onto another pair of states (where the followed pair stopped being the
    /// lowest: a fold, a loss of stability or a branch point of one of its states).
    pub switches: Vec<String>,
    /// Parameter values (the decades of `d1` on the way) at which a search for lower states of
    /// both branches at the curve's length found none.
    pub checks: Vec<f64>,
    /// Notes (requested `--at` values outside the traced range, …).
    pub notes: Vec<String>,
}

/// Result of [`trace_phase`].
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PhaseDiagram {
    /// The continued parameter.
    pub param: Param,
    /// The scene's value.
    pub scene_value: f64,
    /// The requested end value.
    pub target: f64,
    /// One curve per exchange of the uniform rod in the length range.
    pub curves: Vec<PhaseCurve>,
}

/// A state of the continuation with its companion (other resolution) for the error estimate.
#[derive(Clone)]
struct Tracked {
    x: DVector<f64>,
    p: f64,
    index: (usize, usize),
    /// Arm of the curve: the count of tangency folds passed before it and of switches onto
    /// another pair of states.
    arm: usize,
}

/// Follow every exchange of the uniform rod in the scene's length range (see the module
/// docs of [`crate::maxwell`]).
pub fn trace_phase(settings: &PhaseSettings) -> Result<PhaseDiagram, DiagramError> {
    let s = settings;
    let Stiffness::Tanh { .. } = &s.stiffness else {
        return Err(DiagramError::InvalidOptions(
            "phase needs a two-segment stiffness profile (kind = \"tanh\", Eq. (51)) in the scene"
                .into(),
        ));
    };
    if s.param == Param::Lbar {
        return Err(DiagramError::InvalidOptions(
            "the parameter of a phase diagram is d1, gamma, s0 or s1 (lbar is the unknown critical length)"
                .into(),
        ));
    }
    let scene_value = s.stiffness.param(s.param)?;
    if !s.target.is_finite() {
        return Err(DiagramError::InvalidOptions(format!(
            "--to must be finite (got {})",
            s.target
        )));
    }
    // The target profile must be valid.
    s.stiffness.with_param(s.param, s.target)?.validate()?;
    if s.param == Param::D1 {
        if s.target.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            return Err(DiagramError::InvalidOptions(format!(
                "--to for d1 = D1/D0 must be positive (got {})",
                s.target
            )));
        }
        let (lo, hi) = (scene_value.min(s.target), scene_value.max(s.target));
        if lo < 1.0 && hi > 1.0 {
            return Err(DiagramError::InvalidOptions(format!(
                "the range of d1 from {scene_value} to {} crosses the uniform rod d1 = 1, where the \
                 lowest placement of the segment changes; trace each side separately",
                s.target
            )));
        }
    } else if (s.target - scene_value).abs() == 0.0 {
        return Err(DiagramError::InvalidOptions(format!(
            "--to {} is the scene's value of {}: nothing to follow",
            s.target, s.param
        )));
    }
    for &v in &s.at {
        s.stiffness
            .with_param(s.param, v)?
            .validate()
            .map_err(|e| {
                DiagramError::InvalidOptions(format!(
                    "--at {v}: not a valid value of {}: {e}",
                    s.param
                ))
            })?;
        if s.param == Param::D1 && v.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            return Err(DiagramError::InvalidOptions(format!(
                "--at {v}: d1 = D1/D0 must be positive"
            )));
        }
    }
    let exchanges = uniform_exchanges(s.lbar_min, s.lbar_max)?;
    // One thread per exchange (the curves are independent).
    let results: Vec<Result<PhaseCurve, DiagramError>> = std::thread::scope(|scope| {
        let handles: Vec<_> = exchanges
            .iter()
            .map(|&ex| scope.spawn(move || trace_exchange(s, scene_value, ex)))
            .collect();
        handles
            .into_iter()
            .map(|h| {
                h.join().unwrap_or_else(|_| {
                    Err(DiagramError::InvalidOptions(
                        "internal error: a phase curve's thread panicked".into(),
                    ))
                })
            })
            .collect()
    });
    let curves = results.into_iter().collect::<Result<Vec<_>, _>>()?;
    Ok(PhaseDiagram {
        param: s.param,
        scene_value,
        target: s.target,
        curves,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rodloop_exact::eta_of_branch;

    fn scene(d1: f64) -> Stiffness {
        Stiffness::paper_sec5(d1)
    }

    fn settings(d1: f64, target: f64, at: Vec<f64>) -> PhaseSettings {
        PhaseSettings {
            radius: 1.0,
            stiffness: scene(d1),
            param: Param::D1,
            target,
            lbar_min: 1.0,
            lbar_max: 3.0,
            accuracy: Accuracy::Default,
            at,
            solve: SolveOptions::default(),
        }
    }

    /// The exact critical lengths of the uniform rod (the exact layer, Sec. 4.3).
    fn exact_crossings() -> Vec<f64> {
        let x = uniform_exchanges(1.0, 3.0).unwrap();
        x.iter().map(|e| e.lbar_uniform).collect()
    }

    #[test]
    fn maxwell_points_approach_the_uniform_critical_lengths() {
        let d = trace_phase(&settings(0.9, 0.9, vec![])).unwrap();
        let exact = exact_crossings();
        assert_eq!(d.curves.len(), 2);
        for (c, ex) in d.curves.iter().zip(&exact) {
            let u = c.uniform.expect("limit row");
            assert!((u.exact - ex).abs() < 1e-12);
            assert!(
                u.deviation.abs() <= 2.0 * u.error_estimate,
                "limit {} vs exact {ex}: deviation {:.2e}, estimate {:.2e}",
                u.lbar_cr,
                u.deviation,
                u.error_estimate
            );
            // The ladder 1 − t, t = 8e-3 … 1e-3: each within its estimate plus a term that
            // vanishes with t, and closer to the limit as t decreases.
            let ladder: Vec<&PhaseRow> = c
                .rows
                .iter()
                .filter(|r| r.source == RowSource::Fixed && r.value > 0.99)
                .collect();
            assert_eq!(ladder.len(), 4);
            let mut last = f64::INFINITY;
            for r in ladder {
                let t = 1.0 - r.value;
                assert!((r.lbar_cr - ex).abs() <= 2.0 * r.error_estimate + 0.05 * t);
                let to_limit = (r.lbar_cr - u.lbar_cr).abs();
                assert!(to_limit < last, "not approaching at t = {t}");
                last = to_limit;
            }
        }
    }

    #[test]
    fn at_rows_agree_with_an_independent_maxwell_point_solve() {
        let theta = 0.7;
        let d = trace_phase(&settings(0.9, 0.65, vec![theta])).unwrap();
        for c in &d.curves {
            let row = c
                .rows
                .iter()
                .find(|r| r.source == RowSource::Fixed && r.value == theta)
                .expect("an --at row");
            // Independent: the lowest stable states at θ from shifted exact loops, then the
            // exchange locator on re-solved equilibria (not the augmented system).
            let st = scene(theta);
            let (ea, eb) = (
                eta_of_branch(c.exchange.from_branch),
                eta_of_branch(c.exchange.to_branch),
            );
            let opts = SolveOptions::default();
            let a = lowest_placement(1.0, row.lbar_cr, ea, c.cells.0, &st, &opts).unwrap();
            let b = lowest_placement(1.0, row.lbar_cr, eb, c.cells.1, &st, &opts).unwrap();
            let (ma, _, slope) = maxwell_point(&a, &b, &opts).unwrap();
            assert!(slope > 0.0);
            assert!(
                (ma.lbar() - row.lbar_cr).abs() < 1e-9,
                "--at row {} vs Maxwell point {}",
                row.lbar_cr,
                ma.lbar()
            );
            assert!((ma.energy().total - row.energy).abs() < 1e-9);
        }
    }

    #[test]
    fn bad_input_gives_clear_errors() {
        let msg = |s: PhaseSettings| trace_phase(&s).unwrap_err().to_string();
        assert!(msg(settings(0.5, 2.0, vec![])).contains("crosses the uniform rod"));
        assert!(msg(settings(0.5, -1.0, vec![])).contains("invalid"));
        assert!(msg(settings(0.5, 0.1, vec![-0.3])).contains("--at"));
        let mut s = settings(0.5, 0.1, vec![]);
        s.stiffness = Stiffness::uniform(1.0);
        assert!(msg(s).contains("two-segment"));
        let mut s = settings(0.5, 0.1, vec![]);
        s.param = Param::Lbar;
        assert!(msg(s).contains("lbar"));
    }
}
