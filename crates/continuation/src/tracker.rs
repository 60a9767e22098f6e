//! The pseudo-arclength continuation driver: stepping, step control, detection and
//! location of special points.
//!
//! It is one file because stepping, step control and the location of special points all work on
//! the same predictor–corrector segments (Hermite interpolation between nodes, `SegEval`).

use nalgebra::DVector;

use crate::branch::{Branch, SpecialKind, SpecialPoint};
use crate::error::{BoxError, ContinuationError};
use crate::linalg::{self, Evaluator, Tangent};
use crate::newton::{correct_bordered, Corrected, CorrectorTol};
use crate::problem::{Problem, Stability};
use crate::settings::PseudoArclength;

/// Type of a user event function `g(x, p)`.
type EventFn<'a> = Box<dyn Fn(&DVector<f64>, f64) -> f64 + 'a>;

/// Iteration cap of the location loops (a safety net; with `locate_tol` relative to a
/// step of at most `ds_max`, bisection alone needs far fewer).
const MAX_LOCATE_ITERATIONS: usize = 200;

/// Adapter turning an infallible closure into a [`Stability`].
struct FnStability<F>(F);

impl<F: Fn(&DVector<f64>, f64) -> usize> Stability for FnStability<F> {
    fn index(&self, x: &DVector<f64>, p: f64) -> Result<usize, BoxError> {
        Ok((self.0)(x, p))
    }
}

/// A continuation run: a [`Problem`], the [`PseudoArclength`] settings, and optional
/// monitors (a stability index and event functions).
///
/// # Algorithm
/// Keller's pseudo-arclength continuation (H. B. Keller, *Numerical solution of
/// bifurcation and nonlinear eigenvalue problems*, 1977; E. L. Allgower & K. Georg,
/// *Introduction to Numerical Continuation Methods*, SIAM 2003, ch. 2, 6–9;
/// Yu. A. Kuznetsov, *Elements of Applied Bifurcation Theory*, ch. 10). With
/// `y = (x, p) ∈ Rⁿ⁺¹` and `A(y) = [∂F/∂x ∂F/∂p]`:
///
/// 1. **Tangent**: solve `[A(y); t_prevᵀ] z = [0; 1]`, `t = z/|z|`; the border keeps
///    the orientation (`tᵀ t_prev > 0`). At the start `t_prev = ±e_p` (the
///    [`Direction`](crate::Direction)).
/// 2. **Euler predictor**: `y_pred = y_k + ds t_k`.
/// 3. **Newton corrector** on `F(y) = 0`, `t_kᵀ (y − y_pred) = 0`, whose Jacobian is the
///    bordered matrix `[A(y); t_kᵀ]` (regular at folds, singular only at branch points).
/// 4. **Step control**: a step is rejected (and retried with `ds · shrink`) if the
///    corrector fails, if the corrected point is farther than `ds` from the predictor,
///    or if the tangent turns by more than `max_turn`; after an accepted step, `ds`
///    grows by `growth` if the corrector needed fewer than `target_iterations`
///    iterations and shrinks by `max(shrink, target/iterations)` if it needed more.
///    The run stops with [`StopReason::StepTooSmall`](crate::StopReason::StepTooSmall) when `ds < ds_min`.
///
/// # Detection along the branch
/// Between consecutive points, sign changes of test functions are located on the
/// curve by root finding in the arclength `σ ∈ (0, ds)` of the step: each trial point
/// is the corrected intersection of the curve with the hyperplane
/// `t_kᵀ (y − y_k) = σ`, started from the chord. Continuous test functions use the
/// Illinois variant of regula falsi with a bisection safeguard; the integer stability
/// index uses bisection. The bracket is reduced to `locate_tol`.
/// * **Folds**: the `p`-component of the tangent changes sign.
/// * **Simple branch points**: the sign of `det [A(y); tᵀ]` changes (the orientation of
///   the curve flips through a simple bifurcation, Allgower & Georg, Thm. 8.1.14); the
///   determinant comes from the tangent computation, as
///   `det J · (t_p − t_xᵀ J⁻¹ F_p)` with the sign and `ln|det J|` of the problem's
///   [`Factorization`](crate::Factorization).
///
/// # Linear algebra
/// The bordered systems `[J F_p; cᵀ] z = r` of steps 1 and 3 and of the location
/// loops are solved by block elimination with the factorisation of `J` returned by
/// [`Problem::factorize`]: `J a = F_p`, `J w = r_x`, then the scalar Schur complement
/// `δ = c_p − c_xᵀ a` gives `z`, and `det [J F_p; cᵀ] = det J · δ`. Since `J` is
/// singular at folds and branch points, where block elimination loses accuracy, each
/// solve is followed by one step of iterative refinement on the full bordered
/// residual (W. Govaerts, *Numerical Methods for Bifurcations of Dynamical
/// Equilibria*, SIAM 2000, ch. 3); if the factorisation fails or the refinement does
/// not reduce the residual (beyond rounding), the system is solved by dense LU of the
/// bordered matrix built from [`Problem::jacobian`].
///
/// # Stepping
/// [`Continuation::run`] is [`Continuation::start`] followed by
/// [`Stepper::step`](crate::Stepper::step) until a stop; callers wanting control between
/// steps use the [`Stepper`](crate::Stepper) directly (both live in the stepper module,
/// which depends on this one and not the other way round).
/// * **Index changes** (with a stability callback): the integer index differs between
///   the points.
/// * **Events**: a user function `g(x, p)` changes sign.
///
/// Sign changes that cancel within one step (two folds in one step) are not seen; the
/// step-size bounds control this.
pub struct Continuation<'a, P: Problem + ?Sized> {
    problem: &'a P,
    settings: PseudoArclength,
    stability: Option<Box<dyn Stability + 'a>>,
    events: Vec<(String, EventFn<'a>)>,
}

impl<P: Problem + ?Sized> std::fmt::Debug for Continuation<'_, P> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Continuation")
            .field("dim", &self.problem.dim())
            .field("settings", &self.settings)
            .field("stability", &self.stability.is_some())
            .field(
                "events",
                &self.events.iter().map(|e| &e.0).collect::<Vec<_>>(),
            )
            .finish()
    }
}

/// Internal record of an accepted point.
#[derive(Clone)]
pub(crate) struct Node {
    pub y: DVector<f64>,
    pub t: DVector<f64>,
    pub det_sign: f64,
    pub log_det: f64,
    pub index: Option<usize>,
    pub g: Vec<f64>,
    pub s: f64,
    pub ds: f64,
}

/// A point on the curve inside a step, at arclength `sigma` from its start.
#[derive(Clone)]
struct SegEval {
    sigma: f64,
    y: DVector<f64>,
    t: DVector<f64>,
    det_sign: f64,
    log_det: f64,
}

impl SegEval {
    fn from_node(node: &Node, sigma: f64) -> Self {
        SegEval {
            sigma,
            y: node.y.clone(),
            t: node.t.clone(),
            det_sign: node.det_sign,
            log_det: node.log_det,
        }
    }
}

/// The cubic Hermite interpolant at `sigma` of the curve points `lo` and `hi`, in the
/// step's parameter `σ = t_aᵀ (y − y_a)` (so `dy/dσ = t / (t_aᵀ t)`); `None` when the
/// bracket is empty or a tangent is nearly orthogonal to `t_a`.
fn hermite_guess(
    t_a: &DVector<f64>,
    lo: &SegEval,
    hi: &SegEval,
    sigma: f64,
) -> Option<DVector<f64>> {
    let w = hi.sigma - lo.sigma;
    let (ca, cb) = (t_a.dot(&lo.t), t_a.dot(&hi.t));
    if w.is_nan() || w <= 0.0 || ca.abs() < 0.1 || cb.abs() < 0.1 {
        return None;
    }
    let th = (sigma - lo.sigma) / w;
    let (th2, th3) = (th * th, th * th * th);
    let h00 = 2.0 * th3 - 3.0 * th2 + 1.0;
    let h10 = th3 - 2.0 * th2 + th;
    let h01 = -2.0 * th3 + 3.0 * th2;
    let h11 = th3 - th2;
    Some(&lo.y * h00 + &lo.t * (h10 * w / ca) + &hi.y * h01 + &hi.t * (h11 * w / cb))
}

/// A step between two accepted points.
pub(crate) struct Segment<'n> {
    pub a: &'n Node,
    pub b: &'n Node,
    pub h: f64,
    pub index: usize,
}

impl PseudoArclength {
    /// Shorthand for `Continuation::new(problem, self.clone()).run(x0, p0)`: a run
    /// without stability index or events.
    pub fn run<P: Problem + ?Sized>(
        &self,
        problem: &P,
        x0: &DVector<f64>,
        p0: f64,
    ) -> Result<Branch, ContinuationError> {
        Continuation::new(problem, self.clone()).run(x0, p0)
    }
}

impl<'a, P: Problem + ?Sized> Continuation<'a, P> {
    /// A run of `problem` with the given settings, without monitors.
    pub fn new(problem: &'a P, settings: PseudoArclength) -> Self {
        Continuation {
            problem,
            settings,
            stability: None,
            events: Vec::new(),
        }
    }

    /// Monitors a stability index (see [`Stability`]): it is stored in every
    /// [`Point::index`](crate::Point::index), and its changes are located by bisection on the arclength to
    /// `locate_tol` and reported as [`SpecialKind::IndexChange`] (several changes
    /// within one step are reported one by one). Replaces a previous callback.
    pub fn with_stability<S: Stability + 'a>(mut self, stability: S) -> Self {
        self.stability = Some(Box::new(stability));
        self
    }

    /// Like [`Continuation::with_stability`] for an infallible closure
    /// `|x, p| -> usize`.
    pub fn with_stability_fn<F: Fn(&DVector<f64>, f64) -> usize + 'a>(self, index: F) -> Self {
        self.with_stability(FnStability(index))
    }

    /// Adds an event function `g(x, p)`: its sign changes along the branch are located
    /// (regula falsi on the arclength, to `locate_tol`) and reported as
    /// [`SpecialKind::Event`] with `id` = number of events added before this one. `g`
    /// should be continuous along the branch; an exact zero at a computed point is
    /// reported at that point.
    pub fn with_event<G: Fn(&DVector<f64>, f64) -> f64 + 'a>(
        mut self,
        name: impl Into<String>,
        g: G,
    ) -> Self {
        self.events.push((name.into(), Box::new(g)));
        self
    }

    /// The settings.
    pub fn settings(&self) -> &PseudoArclength {
        &self.settings
    }

    /// The problem.
    pub fn problem(&self) -> &'a P {
        self.problem
    }

    pub(crate) fn check_in_range(&self, p: f64) -> Result<(), ContinuationError> {
        let st = &self.settings;
        if !(p >= st.p_min && p <= st.p_max) {
            return Err(ContinuationError::StartOutsideRange {
                p,
                p_min: st.p_min,
                p_max: st.p_max,
            });
        }
        Ok(())
    }

    pub(crate) fn corrector_tol(&self) -> CorrectorTol {
        CorrectorTol {
            tol: self.settings.tol,
            step_tol: self.settings.step_tol,
            max_iter: self.settings.max_iterations,
        }
    }

    fn index_at(
        &self,
        ev: &Evaluator<'_, P>,
        y: &DVector<f64>,
    ) -> Result<Option<usize>, ContinuationError> {
        match &self.stability {
            None => Ok(None),
            Some(s) => {
                let (x, p) = ev.split(y);
                s.index(&x, p)
                    .map(Some)
                    .map_err(|e| ContinuationError::Stability(e.into()))
            }
        }
    }

    pub(crate) fn make_node(
        &self,
        ev: &Evaluator<'_, P>,
        y: DVector<f64>,
        tan: Tangent,
        s: f64,
        ds: f64,
    ) -> Result<Node, ContinuationError> {
        let index = self.index_at(ev, &y)?;
        let g = if self.events.is_empty() {
            Vec::new()
        } else {
            let (x, p) = ev.split(&y);
            self.events.iter().map(|(_, g)| g(&x, p)).collect()
        };
        Ok(Node {
            y,
            t: tan.t,
            det_sign: tan.det_sign,
            log_det: tan.log_det,
            index,
            g,
            s,
            ds,
        })
    }

    /// The curve point at arclength `sigma` within the segment, or `None` if the
    /// corrector fails there. The corrector starts from the chord of the step or, with
    /// [`PseudoArclength::with_hermite_location`], from the cubic Hermite interpolant of
    /// `lo` and `hi`, points of the segment already evaluated with
    /// `lo.sigma < sigma < hi.sigma` (the current bracket of a location loop).
    fn eval_at(
        &self,
        ev: &Evaluator<'_, P>,
        seg: &Segment<'_>,
        lo: &SegEval,
        hi: &SegEval,
        sigma: f64,
    ) -> Result<Option<SegEval>, ContinuationError> {
        let hermite = if self.settings.hermite_location {
            hermite_guess(&seg.a.t, lo, hi, sigma)
        } else {
            None
        };
        let guess = hermite.unwrap_or_else(|| &seg.a.y + (&seg.b.y - &seg.a.y) * (sigma / seg.h));
        let c = seg.a.t.dot(&seg.a.y) + sigma;
        match correct_bordered(ev, guess, &seg.a.t, c, self.corrector_tol())? {
            Corrected::Converged { y, .. } => {
                let tan = linalg::tangent(ev, &y, &seg.a.t)?;
                Ok(Some(SegEval {
                    sigma,
                    y,
                    t: tan.t,
                    det_sign: tan.det_sign,
                    log_det: tan.log_det,
                }))
            }
            Corrected::Failed => Ok(None),
        }
    }

    fn special_point(
        &self,
        ev: &Evaluator<'_, P>,
        seg: &Segment<'_>,
        e: SegEval,
        kind: SpecialKind,
        accuracy: f64,
    ) -> SpecialPoint {
        let (x, p) = ev.split(&e.y);
        SpecialPoint {
            kind,
            x,
            p,
            tangent: e.t,
            s: seg.a.s + e.sigma,
            segment: seg.index,
            accuracy,
        }
    }

    /// Detects and locates all special points of one step.
    pub(crate) fn detect(
        &self,
        ev: &Evaluator<'_, P>,
        seg: &Segment<'_>,
    ) -> Result<Vec<SpecialPoint>, ContinuationError> {
        let st = &self.settings;
        let n = ev.n;
        let mut out = Vec::new();
        let ea = SegEval::from_node(seg.a, 0.0);
        let eb = SegEval::from_node(seg.b, seg.h);

        // Folds: sign change of the p-component of the tangent.
        if st.detect_folds {
            let (fa, fb) = (seg.a.t[n], seg.b.t[n]);
            if let Some((e, acc)) = self.locate_root(ev, seg, &ea, fa, &eb, fb, |e| Ok(e.t[n]))? {
                out.push(self.special_point(ev, seg, e, SpecialKind::Fold, acc));
            }
        }

        // Simple branch points: sign change of det [A; tᵀ]; the scaled determinant
        // sign · exp(ln|det| − ln|det_a|) is continuous and free of overflow. Not beside a
        // fold of this step unless asked for (`branch_points_beside_folds`).
        let fold_found = !out.is_empty();
        if st.detect_branch_points
            && (st.branch_points_beside_folds || !fold_found)
            && seg.a.det_sign * seg.b.det_sign < 0.0
        {
            let reference = seg.a.log_det;
            let scaled = move |e: &SegEval| {
                if e.det_sign == 0.0 {
                    0.0
                } else {
                    e.det_sign * (e.log_det - reference).clamp(-700.0, 700.0).exp()
                }
            };
            let (fa, fb) = (scaled(&ea), scaled(&eb));
            if let Some((mut e, acc)) =
                self.locate_root(ev, seg, &ea, fa, &eb, fb, |e| Ok(scaled(e)))?
            {
                e.t = interpolated_tangent(seg, e.sigma);
                out.push(self.special_point(ev, seg, e, SpecialKind::BranchPoint, acc));
            }
        }

        // Stability index changes.
        if let (Some(ia), Some(ib)) = (seg.a.index, seg.b.index) {
            if ia != ib {
                for (e, old, new, acc) in self.locate_index(ev, seg, &ea, ia, &eb, ib)? {
                    out.push(self.special_point(
                        ev,
                        seg,
                        e,
                        SpecialKind::IndexChange { old, new },
                        acc,
                    ));
                }
            }
        }

        // Events.
        for (id, (name, g)) in self.events.iter().enumerate() {
            let (fa, fb) = (seg.a.g[id], seg.b.g[id]);
            let f = |e: &SegEval| {
                let (x, p) = ev.split(&e.y);
                Ok(g(&x, p))
            };
            if let Some((e, acc)) = self.locate_root(ev, seg, &ea, fa, &eb, fb, f)? {
                let kind = SpecialKind::Event {
                    id,
                    name: name.clone(),
                    increasing: fb > fa,
                };
                out.push(self.special_point(ev, seg, e, kind, acc));
            }
        }
        Ok(out)
    }

    /// Locates a zero of the continuous test function `f` between the segment ends,
    /// whose values there are `fa` and `fb`. Returns `None` if there is no sign change
    /// (a zero exactly at the start is not reported: it belongs to the previous step).
    ///
    /// Illinois regula falsi with two safeguards: trial points are kept at least half
    /// the tolerance inside the bracket (so that a root close to an end collapses the
    /// bracket), and a bisection step is forced when two iterations failed to halve it.
    #[allow(clippy::too_many_arguments)]
    fn locate_root<F>(
        &self,
        ev: &Evaluator<'_, P>,
        seg: &Segment<'_>,
        ea: &SegEval,
        fa: f64,
        eb: &SegEval,
        fb: f64,
        mut f: F,
    ) -> Result<Option<(SegEval, f64)>, ContinuationError>
    where
        F: FnMut(&SegEval) -> Result<f64, ContinuationError>,
    {
        if !(fa.is_finite() && fb.is_finite()) || fa == 0.0 {
            return Ok(None);
        }
        if fb == 0.0 {
            return Ok(Some((eb.clone(), 0.0)));
        }
        if fa.signum() == fb.signum() {
            return Ok(None);
        }
        let tol = self.settings.locate_tol;
        let (mut a, mut b) = (ea.clone(), eb.clone());
        // True values, and the Illinois-weighted ones used for interpolation.
        let (mut fa_true, mut fb_true) = (fa, fb);
        let (mut wa, mut wb) = (fa, fb);
        let mut side = 0i8;
        let mut width_ref = b.sigma - a.sigma;
        let mut stalls = 0;
        for _ in 0..MAX_LOCATE_ITERATIONS {
            let w = b.sigma - a.sigma;
            if w <= tol {
                break;
            }
            let mid = 0.5 * (a.sigma + b.sigma);
            let mut sigma = if stalls >= 2 {
                stalls = 0;
                mid
            } else {
                (a.sigma * wb - b.sigma * wa) / (wb - wa)
            };
            let margin = (0.5 * tol).min(0.25 * w);
            if !sigma.is_finite() {
                sigma = mid;
            }
            sigma = sigma.clamp(a.sigma + margin, b.sigma - margin);
            let e = match self.eval_at(ev, seg, &a, &b, sigma)? {
                Some(e) => e,
                None if sigma != mid => match self.eval_at(ev, seg, &a, &b, mid)? {
                    Some(e) => e,
                    None => break,
                },
                None => break,
            };
            let fe = f(&e)?;
            if fe == 0.0 {
                return Ok(Some((e, 0.0)));
            }
            if !fe.is_finite() {
                break;
            }
            if fe.signum() == fa_true.signum() {
                a = e;
                fa_true = fe;
                wa = fe;
                if side == -1 {
                    wb *= 0.5;
                }
                side = -1;
            } else {
                b = e;
                fb_true = fe;
                wb = fe;
                if side == 1 {
                    wa *= 0.5;
                }
                side = 1;
            }
            let w_new = b.sigma - a.sigma;
            if w_new <= 0.5 * width_ref {
                width_ref = w_new;
                stalls = 0;
            } else {
                stalls += 1;
            }
        }
        let width = b.sigma - a.sigma;
        // Final secant estimate inside the (tiny) bracket.
        let mut best = if fa_true.abs() <= fb_true.abs() {
            (a.clone(), fa_true)
        } else {
            (b.clone(), fb_true)
        };
        let sigma = (a.sigma * fb_true - b.sigma * fa_true) / (fb_true - fa_true);
        if sigma.is_finite() && sigma > a.sigma && sigma < b.sigma {
            if let Some(e) = self.eval_at(ev, seg, &a, &b, sigma)? {
                let fe = f(&e)?;
                if fe.abs() < best.1.abs() {
                    best = (e, fe);
                }
            }
        }
        Ok(Some((best.0, width)))
    }

    /// Locates the changes of the integer stability index between the segment ends by
    /// bisection; returns `(first point with the new index, old, new, bracket width)`
    /// for each change found.
    fn locate_index(
        &self,
        ev: &Evaluator<'_, P>,
        seg: &Segment<'_>,
        ea: &SegEval,
        ia: usize,
        eb: &SegEval,
        ib: usize,
    ) -> Result<Vec<(SegEval, usize, usize, f64)>, ContinuationError> {
        let tol = self.settings.locate_tol;
        let mut out = Vec::new();
        let (mut lo, mut ilo) = (ea.clone(), ia);
        for _ in 0..64 {
            if ilo == ib {
                break;
            }
            let (mut l, mut h, mut ih) = (lo.clone(), eb.clone(), ib);
            for _ in 0..MAX_LOCATE_ITERATIONS {
                if h.sigma - l.sigma <= tol {
                    break;
                }
                let mid = 0.5 * (l.sigma + h.sigma);
                let Some(e) = self.eval_at(ev, seg, &l, &h, mid)? else {
                    break;
                };
                let im = self
                    .index_at(ev, &e.y)?
                    .expect("stability callback present");
                if im == ilo {
                    l = e;
                } else {
                    h = e;
                    ih = im;
                }
            }
            out.push((h.clone(), ilo, ih, h.sigma - l.sigma));
            lo = h;
            ilo = ih;
        }
        Ok(out)
    }
}

/// Tangent of the traced branch at arclength `sigma` within the segment: the linear
/// interpolant of the unit tangents at the segment's ends, normalised (error `O(h²)` for a
/// smooth branch). A located branch point reports this tangent instead of the kernel
/// vector of `A = [∂F/∂x ∂F/∂p]` there: at a branch point the kernel of `A` is two-
/// dimensional, so the kernel vector computed at a point within `locate_tol` of it is
/// any direction of that plane (the corrector's residual decides), often that of the
/// other branch. Branch switching ([`Continuation::secondary_tangent`]) needs the
/// current branch's direction to tell the two branches apart.
fn interpolated_tangent(seg: &Segment<'_>, sigma: f64) -> DVector<f64> {
    let w = if seg.h > 0.0 {
        (sigma / seg.h).clamp(0.0, 1.0)
    } else {
        0.5
    };
    let t = &seg.a.t * (1.0 - w) + &seg.b.t * w;
    let norm = t.norm();
    if norm > 0.0 && norm.is_finite() {
        t / norm
    } else {
        seg.a.t.clone()
    }
}
