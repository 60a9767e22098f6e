//! The approach to the great-circle ends of a branch.
//!
//! Near an end `L̄ → m` on the m-fold great circle the branch is a half pitchfork: the
//! amplitude of `κ_g` behaves like `a = √|L̄ − m|`, the continuation curve turns back through
//! the great circle onto the mirror image of the branch, and the KKT matrix becomes
//! singular. The pseudo-arclength march therefore stops [`SWITCH_DISTANCE`] from `m`, and
//! the last stretch is done by Newton's method at `L̄ = m ± a²` with `a` halved at every
//! step, from a predictor polynomial in `a` (in which the branch is regular), down to
//! [`DiagramOptions::end_distance`] from `m` ([`approach_end`]).

use rodloop_continuation::natural::{walk_steps, Halted, StepSettings};
use rodloop_solver::{Param, ParamProblem, SolverError, SurfaceSolve};

use crate::states::newton_options;
use crate::DiagramOptions;

/// Distance from a great-circle end at which the pseudo-arclength march hands over to the
/// end approach.
pub(crate) const SWITCH_DISTANCE: f64 = 0.05;

/// What one end of the branch aims at.
#[derive(Clone, Copy, Debug)]
pub(crate) struct EndSpec {
    /// Where tracing should stop.
    pub target: f64,
    /// The great circle of the branch end near the target, if any (`|target − m| < 0.01`).
    pub circle: Option<u32>,
    /// Whether the target is the great-circle end itself (else the range end).
    pub at_circle: bool,
}

impl EndSpec {
    /// Where the pseudo-arclength run stops (`side`: direction of tracing; the branch lies
    /// on the other side of its great circle).
    pub(crate) fn run_limit(&self, side: f64) -> f64 {
        match self.circle {
            Some(m) => f64::from(m) - side * SWITCH_DISTANCE,
            None => self.target,
        }
    }
}

/// The targets of the lower and upper ends of branch `eta` within the diagram's range.
pub(crate) fn end_specs(opts: &DiagramOptions, eta: u32) -> (EndSpec, EndSpec) {
    let e = f64::from(eta);
    let d = opts.end_distance;
    let low = if eta >= 2 {
        let m = e - 1.0;
        if m + d >= opts.lbar_min {
            EndSpec {
                target: m + d,
                circle: Some(eta - 1),
                at_circle: true,
            }
        } else {
            EndSpec {
                target: opts.lbar_min,
                circle: (opts.lbar_min - m < SWITCH_DISTANCE).then_some(eta - 1),
                at_circle: false,
            }
        }
    } else {
        EndSpec {
            target: opts.lbar_min,
            circle: None,
            at_circle: false,
        }
    };
    let m = e + 1.0;
    let high = if m - d <= opts.lbar_max {
        EndSpec {
            target: m - d,
            circle: Some(eta + 1),
            at_circle: true,
        }
    } else {
        EndSpec {
            target: opts.lbar_max,
            circle: (m - opts.lbar_max < SWITCH_DISTANCE).then_some(eta + 1),
            at_circle: false,
        }
    };
    (low, high)
}

/// Result of [`approach_end`].
pub(crate) struct Approach {
    /// The solved states `(z, L̄)`, approaching `m`.
    pub points: Vec<(Vec<f64>, f64)>,
    /// Why the approach stopped short of its target, if it did.
    pub failure: Option<String>,
}

/// Newton solves at `L̄ = m + side·a²`, `a` halved at every step, from `chain` (the last
/// states, the nearest to `m` last) down to `target`; the predictor is the polynomial in
/// `a` through the last (up to three) states. `side` is the side of `m` the branch lies on.
///
/// The steps are the continuation crate's natural-parameter walk in `ln a`
/// ([`walk_steps`]): each step tries `ln ½` first, and a failed try is retried with half
/// the step in `ln a` (the square root of the ratio in `a`), 7 times at most; at most
/// [`APPROACH_STEPS`] steps.
pub(crate) fn approach_end<M: SurfaceSolve>(
    problem: &ParamProblem<M>,
    chain: &[(Vec<f64>, f64)],
    m: f64,
    target: f64,
) -> Approach {
    debug_assert_eq!(problem.param(), Param::Lbar);
    let side = if chain.last().map_or(target, |c| c.1) >= m {
        1.0
    } else {
        -1.0
    };
    let a_of = |p: f64| (side * (p - m)).max(0.0).sqrt();
    let a_target = a_of(target);
    let too_many = || Approach {
        points: Vec::new(),
        failure: Some("too many steps approaching the great circle".into()),
    };
    let Some(last) = chain.last().cloned() else {
        return too_many();
    };
    // Arrived (to 1e-12 relative in `a`) before any step.
    let arrive = (1.0 + 1e-12f64).ln();
    let u_target = a_target.ln();
    if a_of(last.1) <= a_target * (1.0 + 1e-12) {
        return Approach {
            points: Vec::new(),
            failure: None,
        };
    }
    let mut hist: Vec<(Vec<f64>, f64)> = chain.to_vec();
    let mut out = Vec::new();
    let opts = newton_options();
    let settings = StepSettings {
        step: std::f64::consts::LN_2,
        max_halvings: 7,
        max_steps: APPROACH_STEPS,
        arrive,
    };
    let walked = walk_steps(
        last,
        None,
        u_target,
        |s: &(Vec<f64>, f64)| a_of(s.1).ln(),
        &settings,
        |_, _, u_next, _| {
            let a_next = u_next.exp().max(a_target);
            let p_next = if u_next <= u_target {
                target
            } else {
                m + side * a_next * a_next
            };
            let pred = predict(&hist, a_of, a_next);
            let eq = problem
                .model_at(p_next)
                .and_then(|model| model.solve_from_state(pred, &opts))?;
            let s = (eq.state(), p_next);
            hist.push(s.clone());
            out.push(s.clone());
            Ok::<_, SolverError>(s)
        },
    );
    let failure = match walked {
        Ok(_) => None,
        Err(Halted::OutOfSteps { .. }) => too_many().failure,
        Err(Halted::Stuck(stuck)) => Some(format!(
            "Newton's method failed approaching the great circle at L̄ = {m} ({})",
            stuck.error
        )),
    };
    Approach {
        points: out,
        failure,
    }
}

/// Steps of [`approach_end`] at most.
const APPROACH_STEPS: usize = 200;

/// Polynomial extrapolation in `a` through the last (up to three) states of `hist`.
fn predict(hist: &[(Vec<f64>, f64)], a_of: impl Fn(f64) -> f64, a: f64) -> Vec<f64> {
    let k = hist.len().min(3);
    let pts = &hist[hist.len() - k..];
    let nodes: Vec<f64> = pts.iter().map(|(_, p)| a_of(*p)).collect();
    // Drop coincident nodes (fall back to fewer points).
    let distinct = nodes
        .windows(2)
        .all(|w| (w[0] - w[1]).abs() > 1e-14 * w[0].abs().max(1e-14));
    if k == 1 || !distinct {
        return pts[k - 1].0.clone();
    }
    let weights: Vec<f64> = (0..k)
        .map(|i| {
            (0..k)
                .filter(|&j| j != i)
                .map(|j| (a - nodes[j]) / (nodes[i] - nodes[j]))
                .product()
        })
        .collect();
    let n = pts[0].0.len();
    (0..n)
        .map(|c| pts.iter().zip(&weights).map(|((x, _), w)| w * x[c]).sum())
        .collect()
}
