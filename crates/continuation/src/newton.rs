//! Newton correctors: at fixed parameter (public) and on the pseudo-arclength
//! hyperplane (internal), plus re-solving a computed branch at a given parameter.

use nalgebra::DVector;

use crate::branch::Branch;
use crate::error::ContinuationError;
use crate::linalg::{self, Evaluator};
use crate::problem::Problem;

/// Convergence report of a successful Newton solve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NewtonReport {
    /// Number of Newton iterations (linear solves) performed; 0 if the initial guess
    /// already met the tolerance.
    pub iterations: usize,
    /// Max-norm `‖F(x, p)‖∞` of the residual at the returned solution.
    pub residual_norm: f64,
    /// Max-norm of the last Newton update (0 if no iteration was needed).
    pub step_norm: f64,
}

/// Newton's method for `F(x, p) = 0` at fixed `p`, starting from `x0`.
///
/// Iterates `x ← x − J(x, p)⁻¹ F(x, p)`, with the problem's factorisation of `J`
/// ([`Problem::factorize`], dense LU with partial pivoting by default; if a custom
/// factorisation fails, the dense LU of [`Problem::jacobian`] is tried), until
/// `‖F(x, p)‖∞ ≤ tol`, for at most `max_iter` iterations. Convergence is quadratic near
/// a regular solution (`J` invertible); at a fold or branch point (`J` singular) it
/// degrades or fails, which is why the continuation itself corrects on the bordered
/// system instead (see [`crate::PseudoArclength`]).
///
/// # Errors
/// [`ContinuationError::WrongStateLength`] if `x0.len() != problem.dim()`,
/// [`ContinuationError::InvalidSetting`] for a non-positive `tol`,
/// [`ContinuationError::SingularMatrix`] if a Jacobian is singular or gives a
/// non-finite update, [`ContinuationError::CorrectorDiverged`] if the tolerance is not
/// met within `max_iter` iterations or the residual becomes non-finite, and
/// [`ContinuationError::Problem`] for errors of the problem itself.
pub fn newton<P: Problem + ?Sized>(
    problem: &P,
    x0: &DVector<f64>,
    p: f64,
    tol: f64,
    max_iter: usize,
) -> Result<(DVector<f64>, NewtonReport), ContinuationError> {
    if !(tol > 0.0 && tol.is_finite()) {
        return Err(ContinuationError::invalid(
            "tol",
            format!("must be positive and finite, got {tol}"),
        ));
    }
    let ev = Evaluator::new(problem);
    ev.check_state(x0)?;
    newton_fixed(&ev, x0.clone(), p, tol, max_iter)
}

pub(crate) fn newton_fixed<P: Problem + ?Sized>(
    ev: &Evaluator<'_, P>,
    mut x: DVector<f64>,
    p: f64,
    tol: f64,
    max_iter: usize,
) -> Result<(DVector<f64>, NewtonReport), ContinuationError> {
    let mut step_norm = 0.0;
    for it in 0..=max_iter {
        let r = ev.residual(&x, p)?;
        let res = linalg::max_abs(&r);
        if !res.is_finite() {
            return Err(ContinuationError::CorrectorDiverged {
                iterations: it,
                residual: res,
            });
        }
        if res <= tol {
            return Ok((
                x,
                NewtonReport {
                    iterations: it,
                    residual_norm: res,
                    step_norm,
                },
            ));
        }
        if it == max_iter {
            return Err(ContinuationError::CorrectorDiverged {
                iterations: it,
                residual: res,
            });
        }
        let dx = ev
            .solve_jacobian(&x, p, &(-r))?
            .ok_or(ContinuationError::SingularMatrix { p })?;
        step_norm = dx.amax();
        x += dx;
    }
    unreachable!("the loop returns at it == max_iter")
}

/// Outcome of the bordered corrector.
pub(crate) enum Corrected {
    Converged { y: DVector<f64>, iterations: usize },
    Failed,
}

/// Tolerances of the bordered corrector.
#[derive(Clone, Copy)]
pub(crate) struct CorrectorTol {
    pub tol: f64,
    pub step_tol: f64,
    pub max_iter: usize,
}

/// Newton's method on the bordered system `F(y) = 0`, `normalᵀ y = c`, for
/// `y = (x, p) ∈ Rⁿ⁺¹`, starting from `y0`.
///
/// Converged when `max(‖F‖∞, |normalᵀy − c|) ≤ tol` and the last update satisfies
/// `‖Δy‖∞ ≤ step_tol (1 + ‖y‖∞)`. Fails (softly, so that the caller can reduce the
/// step) on a singular matrix, non-finite values, non-contracting updates, or after
/// `max_iter` iterations. Only problem errors are hard errors.
pub(crate) fn correct_bordered<P: Problem + ?Sized>(
    ev: &Evaluator<'_, P>,
    mut y: DVector<f64>,
    normal: &DVector<f64>,
    c: f64,
    tol: CorrectorTol,
) -> Result<Corrected, ContinuationError> {
    let n = ev.n;
    let mut last_step = 0.0;
    let mut prev_step = f64::INFINITY;
    let mut rhs = DVector::zeros(n + 1);
    for it in 0..=tol.max_iter {
        let (x, p) = ev.split(&y);
        let r = ev.residual(&x, p)?;
        let g = normal.dot(&y) - c;
        let rn = linalg::max_abs(&r);
        // f64::max ignores NaN, so keep a NaN residual explicitly.
        let res = if rn.is_nan() || g.is_nan() {
            f64::NAN
        } else {
            rn.max(g.abs())
        };
        if !res.is_finite() {
            return Ok(Corrected::Failed);
        }
        let step_ok = last_step <= tol.step_tol * (1.0 + y.amax());
        if res <= tol.tol && step_ok {
            return Ok(Corrected::Converged { y, iterations: it });
        }
        if it == tol.max_iter {
            return Ok(Corrected::Failed);
        }
        rhs.rows_mut(0, n).copy_from(&r);
        rhs[n] = g;
        rhs.neg_mut();
        let Some(dy) = linalg::bordered_solve(ev, &y, normal, &rhs)?.map(|s| s.z) else {
            return Ok(Corrected::Failed);
        };
        let step = dy.amax();
        y += dy;
        // Newton-Kantorovich style monotonicity test: updates must contract once the
        // iteration is under way (ignored at round-off level).
        if it >= 1 && step > prev_step && step > tol.step_tol * (1.0 + y.amax()) {
            return Ok(Corrected::Failed);
        }
        prev_step = step;
        last_step = step;
    }
    unreachable!("the loop returns at it == max_iter")
}

/// Re-solves `F(x, p_target) = 0` starting from the point of `branch` nearest in `p`.
///
/// Let `k` be the point minimising `|p_k − p_target|`. If one of the two segments
/// adjacent to it brackets `p_target`, the initial guess is the linear interpolation in
/// `p` on that segment; otherwise it is the first-order extrapolation along the tangent
/// of point `k` (or `x_k` itself when the tangent is nearly vertical, `|t_p| < 1e-3`).
/// Then [`newton`] at fixed `p_target`. Used to refine critical points of a computed
/// branch at an exact parameter value. Near a fold (`J` singular), a fixed-parameter
/// solve is ill-conditioned; prefer the special points reported by the continuation
/// there.
///
/// # Errors
/// [`ContinuationError::EmptyBranch`], and the errors of [`newton`].
pub fn solve_at<P: Problem + ?Sized>(
    problem: &P,
    branch: &Branch,
    p_target: f64,
    tol: f64,
    max_iter: usize,
) -> Result<(DVector<f64>, NewtonReport), ContinuationError> {
    let pts = &branch.points;
    if pts.is_empty() {
        return Err(ContinuationError::EmptyBranch);
    }
    let k = (0..pts.len())
        .min_by(|&a, &b| {
            (pts[a].p - p_target)
                .abs()
                .total_cmp(&(pts[b].p - p_target).abs())
        })
        .expect("non-empty");
    let brackets = |i: usize| {
        let (a, b) = (pts[i].p, pts[i + 1].p);
        (a - p_target) * (b - p_target) <= 0.0 && a != b
    };
    let guess = if k + 1 < pts.len() && brackets(k) {
        interpolate(&pts[k].x, pts[k].p, &pts[k + 1].x, pts[k + 1].p, p_target)
    } else if k >= 1 && brackets(k - 1) {
        interpolate(&pts[k - 1].x, pts[k - 1].p, &pts[k].x, pts[k].p, p_target)
    } else {
        let t = &pts[k].tangent;
        let n = pts[k].x.len();
        let tp = t[n];
        if tp.abs() >= 1e-3 {
            &pts[k].x + t.rows(0, n) * ((p_target - pts[k].p) / tp)
        } else {
            pts[k].x.clone()
        }
    };
    newton(problem, &guess, p_target, tol, max_iter)
}

/// Re-solves `F(x, p_target) = 0` once for every segment of `branch` whose end points
/// bracket `p_target` (on a folded branch there are several solutions at the same
/// parameter), starting from the linear interpolation in `p` on that segment.
///
/// Returns one result per bracketing segment, in branch order; a failed solve is
/// returned as its error instead of aborting the others. Consecutive segments sharing
/// an end point exactly at `p_target` yield duplicates.
pub fn solve_all_at<P: Problem + ?Sized>(
    problem: &P,
    branch: &Branch,
    p_target: f64,
    tol: f64,
    max_iter: usize,
) -> Vec<Result<(DVector<f64>, NewtonReport), ContinuationError>> {
    let pts = &branch.points;
    pts.windows(2)
        .filter(|w| (w[0].p - p_target) * (w[1].p - p_target) <= 0.0 && w[0].p != w[1].p)
        .map(|w| {
            let guess = interpolate(&w[0].x, w[0].p, &w[1].x, w[1].p, p_target);
            newton(problem, &guess, p_target, tol, max_iter)
        })
        .collect()
}

fn interpolate(xa: &DVector<f64>, pa: f64, xb: &DVector<f64>, pb: f64, p: f64) -> DVector<f64> {
    let th = (p - pa) / (pb - pa);
    xa + (xb - xa) * th
}
