//! Branch switching at simple branch points.

use nalgebra::DVector;

use crate::branch::{Branch, SpecialKind, SpecialPoint};
use crate::error::ContinuationError;
use crate::linalg::{self, Evaluator, Tangent};
use crate::newton::{correct_bordered, Corrected};
use crate::problem::Problem;
use crate::settings::Direction;
use crate::stepper::Stepper;
use crate::tracker::Continuation;

impl<'a, P: Problem + ?Sized> Continuation<'a, P> {
    /// Unit tangent of the *other* branch through a simple branch point.
    ///
    /// At a simple branch point `y*` the `n × (n+1)` matrix `A = [∂F/∂x ∂F/∂p]` has a
    /// two-dimensional kernel, spanned by `φ₁` (the projection of the located tangent
    /// `bp.tangent`, i.e. the current branch) and `φ₂ ⊥ φ₁` (both from an SVD), and a
    /// one-dimensional left kernel `ψ`. The tangents `τ = α φ₁ + β φ₂` of the branches
    /// through `y*` solve the *algebraic bifurcation equation*
    /// `c₁₁ α² + 2 c₁₂ α β + c₂₂ β² = 0`, `cᵢⱼ = ψᵀ D²F(y*)[φᵢ, φⱼ]` (Keller 1977;
    /// Allgower & Georg 2003, §8.3; Kuznetsov, §10.2). The second derivatives are
    /// central differences of `A` along `φ₁` and `φ₂`. Of the two roots, the one least
    /// aligned with `φ₁` is returned. If the quadratic form is degenerate (no two
    /// distinct real roots, e.g. second derivatives vanishing), the fallback is `φ₂`,
    /// the kernel direction orthogonal to the current branch — which is the exact
    /// answer for symmetric (pitchfork) bifurcations.
    ///
    /// Orientation (what [`Direction::Forward`] means in
    /// [`Continuation::switch_branch`]): the `p`-component is positive if
    /// `|τ_p| ≥ 10⁻³`; otherwise the component of largest magnitude is positive.
    ///
    /// # Errors
    /// [`ContinuationError::NotABranchPoint`] if `bp` is not a
    /// [`SpecialKind::BranchPoint`]; [`ContinuationError::WrongStateLength`]; problem
    /// errors.
    pub fn secondary_tangent(&self, bp: &SpecialPoint) -> Result<DVector<f64>, ContinuationError> {
        if !matches!(bp.kind, SpecialKind::BranchPoint) {
            return Err(ContinuationError::NotABranchPoint {
                kind: bp.kind.name(),
            });
        }
        let ev = Evaluator::new(self.problem());
        ev.check_state(&bp.x)?;
        let y = ev.join(&bp.x, bp.p);
        secondary_tangent_at(&ev, &y, &bp.tangent)
    }

    /// Starts a continuation on the second branch through the simple branch point `bp`.
    ///
    /// The first step goes from `bp` along `±τ` ([`Continuation::secondary_tangent`],
    /// the sign given by `direction`) with the bordered corrector on the hyperplane
    /// `τᵀ (y − y* − ds τ) = 0`; the step is accepted if the corrected point lies
    /// closer to the direction `τ` than to the current branch's tangent and inside the
    /// parameter range (otherwise the step is shortened, down to `ds_min`). The continuation then proceeds as in
    /// [`Continuation::run`], with the same settings and monitors. The returned branch
    /// starts at `bp` (first point, tangent `±τ`); no detection is done on its first
    /// step, where test functions are not reliable.
    ///
    /// # Errors
    /// Those of [`Continuation::secondary_tangent`], invalid settings, `bp` outside the
    /// parameter range, and [`ContinuationError::StepTooSmall`] if no first step off
    /// the branch point succeeds.
    pub fn switch_branch(
        &self,
        bp: &SpecialPoint,
        direction: Direction,
    ) -> Result<Branch, ContinuationError> {
        let mut stepper = self.start_switch(bp, direction)?;
        while stepper.step()?.stop.is_none() {}
        Ok(stepper.finish())
    }

    /// Prepares the continuation of the second branch through the simple branch point
    /// `bp` as a [`Stepper`]: takes the first step off `bp` as described at
    /// [`Continuation::switch_branch`] (which is this function followed by stepping to
    /// the end) and returns a stepper holding `bp` and that first point.
    ///
    /// # Errors
    /// As [`Continuation::switch_branch`].
    pub fn start_switch(
        &self,
        bp: &SpecialPoint,
        direction: Direction,
    ) -> Result<Stepper<'_, 'a, P>, ContinuationError> {
        let st = self.settings();
        st.validate()?;
        let tau = self.secondary_tangent(bp)? * direction.sign();
        self.check_in_range(bp.p)?;
        let ev = Evaluator::new(self.problem());
        let y_bp = ev.join(&bp.x, bp.p);
        let t1 = &bp.tangent;
        let cos_max = st.max_turn().cos();
        let mut ds = st.ds();
        let (y1, tan1) = loop {
            if ds < st.ds_min() {
                return Err(ContinuationError::StepTooSmall { ds, p: bp.p });
            }
            let pred = &y_bp + &tau * ds;
            let c = tau.dot(&y_bp) + ds;
            if let Corrected::Converged { y, .. } =
                correct_bordered(&ev, pred, &tau, c, self.corrector_tol())?
            {
                let d = &y - &y_bp;
                // Off the primary branch, and inside the range (a first point beyond it
                // would start the stepper outside: the step is shortened instead).
                let inside = (st.p_min..=st.p_max).contains(&y[ev.n]);
                if inside && d.dot(t1).abs() < d.dot(&tau) {
                    let tan = linalg::tangent(&ev, &y, &tau)?;
                    if tan.t.dot(&tau) >= cos_max {
                        break (y, tan);
                    }
                }
            }
            ds *= st.shrink();
        };
        let h = tau.dot(&(&y1 - &y_bp));
        let tan0 = Tangent {
            t: tau,
            det_sign: 0.0,
            log_det: f64::NEG_INFINITY,
        };
        let node0 = self.make_node(&ev, y_bp, tan0, 0.0, 0.0)?;
        let node1 = self.make_node(&ev, y1, tan1, h, h)?;
        Ok(Stepper::from_nodes(
            self,
            vec![node0, node1],
            ds.min(st.ds_max()),
            1,
        ))
    }
}

/// See [`Continuation::secondary_tangent`].
fn secondary_tangent_at<P: Problem + ?Sized>(
    ev: &Evaluator<'_, P>,
    y: &DVector<f64>,
    t1: &DVector<f64>,
) -> Result<DVector<f64>, ContinuationError> {
    let n = ev.n;
    let a = ev.augmented(y)?;
    // One SVD of the square matrix [A; 0] gives both kernels: its two smallest right
    // singular vectors span the kernel of A, and the left vectors of its two smallest
    // singular values span {(ψ, 0), e_{n+1}}.
    let (pairs, psi) = linalg::kernels(&a);
    let (v0, v1) = (&pairs[0].1, &pairs[1].1);
    let (c0, c1) = (t1.dot(v0), t1.dot(v1));
    let norm = c0.hypot(c1);
    let (phi1, phi2) = if norm > 1e-6 {
        ((v0 * c0 + v1 * c1) / norm, (v1 * c0 - v0 * c1) / norm)
    } else {
        (v0.clone(), v1.clone())
    };

    // Directional derivatives of A along φ₁ and φ₂ (central differences).
    let h = f64::EPSILON.cbrt() * (1.0 + y.amax());
    let d1 = (ev.augmented(&(y + &phi1 * h))? - ev.augmented(&(y - &phi1 * h))?) / (2.0 * h);
    let d2 = (ev.augmented(&(y + &phi2 * h))? - ev.augmented(&(y - &phi2 * h))?) / (2.0 * h);
    let c11 = psi.dot(&(&d1 * &phi1));
    let c22 = psi.dot(&(&d2 * &phi2));
    let c12 = 0.5 * (psi.dot(&(&d1 * &phi2)) + psi.dot(&(&d2 * &phi1)));

    let mut tau = phi2.clone();
    let scale = c11.abs().max(c12.abs()).max(c22.abs());
    if scale > 0.0 && scale.is_finite() {
        // Q(θ) = c11 cos²θ + 2 c12 cosθ sinθ + c22 sin²θ = m + r cos(2θ − φ).
        let m = 0.5 * (c11 + c22);
        let r = (0.5 * (c11 - c22)).hypot(c12);
        if r > 1e-8 * scale && m.abs() < r {
            let phi = c12.atan2(0.5 * (c11 - c22));
            let delta = (-m / r).acos();
            let (th1, th2) = (0.5 * (phi + delta), 0.5 * (phi - delta));
            let th = if th1.sin().abs() >= th2.sin().abs() {
                th1
            } else {
                th2
            };
            tau = &phi1 * th.cos() + &phi2 * th.sin();
        }
    }
    let tau = tau.normalize();
    let sign = if tau[n].abs() >= 1e-3 {
        tau[n].signum()
    } else {
        let k = tau.iamax();
        tau[k].signum()
    };
    Ok(tau * sign)
}
