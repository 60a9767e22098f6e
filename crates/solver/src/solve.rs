//! Globalised Newton's method on the KKT system, and the equilibrium it returns with its
//! energies, forces and profiles (Sec. 4.1, Eqs. (24)–(27), (38)–(42)).
//!
//! The file is over 600 lines because it holds one job end to end: the globalised Newton
//! iteration (restoration, relaxation, line search) and the [`Equilibrium`] it returns with the
//! derived quantities of Sec. 4.1 (energies, forces, profiles), which read the solver's
//! multipliers and are defined by the same equations.

use std::f64::consts::PI;

use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

use crate::kkt::KktFactor;
use crate::model::{Phase, SurfaceModel};
use crate::periodic::TrigInterpolant;
use crate::SolverError;

/// How [`solve`] globalises Newton's method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Globalization {
    /// Newton on the KKT system with a backtracking line search on `‖F‖²`: converges to
    /// the equilibrium near the start, stable or not (continuation, re-solving known
    /// states).
    Newton,
    /// First relax the start by energy minimisation on the constraint manifold (feasible
    /// reduced Newton steps with the reduced Hessian shifted to be positive definite, a
    /// restoration projection onto `c = 0` and an Armijo line search on the energy), then
    /// polish with [`Globalization::Newton`]. Converges to a local minimum.
    Minimize,
    /// [`Globalization::Newton`] when the start is already close (KKT residual below
    /// [`SolveOptions::relax_threshold`]), otherwise [`Globalization::Minimize`]; a Newton
    /// run that stalls is retried with `Minimize`.
    Auto,
}

/// Settings of [`solve`].
#[derive(Clone, Debug, PartialEq)]
pub struct SolveOptions {
    /// Globalisation strategy.
    pub globalization: Globalization,
    /// KKT residual norm below which [`Globalization::Auto`] goes straight to Newton, and
    /// reduced-gradient norm at which the relaxation hands over to Newton.
    pub relax_threshold: f64,
    /// Maximum number of relaxation iterations.
    pub max_relax_iterations: usize,
    /// Maximum number of Newton iterations.
    pub max_iterations: usize,
    /// Convergence tolerance on the KKT residual norm ([`SurfaceModel::residual_norm`]).
    pub tolerance: f64,
    /// Maximum number of step reductions in the backtracking line search (each to between a
    /// tenth and a half of the step, by the parabola through the merits seen).
    pub max_backtracks: usize,
}

impl Default for SolveOptions {
    fn default() -> Self {
        Self {
            globalization: Globalization::Auto,
            relax_threshold: 1e-2,
            max_relax_iterations: 200,
            max_iterations: 60,
            tolerance: 1e-10,
            max_backtracks: 40,
        }
    }
}

/// How a Newton solve went.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ConvergenceReport {
    /// Newton iterations performed.
    pub iterations: usize,
    /// Final KKT residual norm ([`SurfaceModel::residual_norm`]).
    pub residual: f64,
    /// Final closure violation `|c|` (holonomy skew part).
    pub closure: f64,
    /// Whether the tolerance was reached.
    pub converged: bool,
    /// Residual norm before every iteration and at the end.
    pub history: Vec<f64>,
    /// Step length accepted by the line search at every iteration.
    pub step_lengths: Vec<f64>,
    /// Energy-minimisation (relaxation) iterations before Newton (0 if none).
    pub relax_iterations: usize,
}

/// Energies of an equilibrium, normalised as `E R/(π D0)`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct EnergyReport {
    /// Total bending energy, Eq. (2).
    pub total: f64,
    /// Geodesic part `½∫Dκ_g²` (Sec. 3.1).
    pub geodesic: f64,
    /// Normal part `½∫D/R²` (`= L̄` for a uniform rod, Sec. 3.1).
    pub normal: f64,
}

/// Local quantities of an equilibrium at one arclength (dimensional in the model's `R`, `D`).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ProfilePoint {
    /// Arclength `s`.
    pub s: f64,
    /// Position `x` (`r = R n`).
    pub x: f64,
    /// Position `y`.
    pub y: f64,
    /// Position `z`.
    pub z: f64,
    /// Curvature `κ = sqrt(κ_g² + 1/R²)`.
    pub kappa: f64,
    /// Torsion `τ = κ_g'/(Rκ²)` (Eq. (36) for uniform rods).
    pub tau: f64,
    /// Geodesic curvature `κ_g = 𝓜·n/D` (Eq. (41)).
    pub kappa_g: f64,
    /// `dκ_g/ds = (𝓜·t/R − D'κ_g)/D`.
    pub kappa_g_prime: f64,
    /// Contact force `λ = −F_t/R + D''/R` (Eq. (27); Eq. (38) for uniform rods).
    pub lambda: f64,
    /// Tangential internal force `F_t = (𝓜·g − D/R)/R` (Eq. (26) via Eq. (40)).
    pub f_t: f64,
    /// Principal-normal internal force, Eq. (25).
    pub f_n: f64,
    /// Binormal internal force, Eq. (24).
    pub f_b: f64,
    /// Conormal internal force `F_g = F·g = −𝓜·t/R` (Eq. (40)).
    pub f_g: f64,
    /// Bending stiffness `D(s)`.
    pub d: f64,
}

/// A converged (or best-effort) equilibrium of the discrete model.
#[derive(Clone, Debug)]
pub struct Equilibrium {
    model: SurfaceModel,
    kappa: Vec<f64>,
    mu: [f64; 3],
    nu: f64,
    report: ConvergenceReport,
}

#[cfg(test)]
impl Equilibrium {
    /// A state with the given curvature, zero multipliers and an empty report, for tests of
    /// checks that must refuse it.
    pub(crate) fn for_test(model: SurfaceModel, kappa: Vec<f64>) -> Self {
        Self {
            model,
            kappa,
            mu: [0.0; 3],
            nu: 0.0,
            report: ConvergenceReport {
                iterations: 0,
                residual: 0.0,
                closure: 0.0,
                converged: true,
                history: Vec::new(),
                step_lengths: Vec::new(),
                relax_iterations: 0,
            },
        }
    }
}

/// Least-squares closure multiplier for a given `κ`: minimises the stationarity residual
/// `Σ_a (∇E_a − (∇cᵀμ)_a)²` over `μ`.
fn initial_multiplier(model: &SurfaceModel, kappa: &[f64]) -> Result<[f64; 3], SolverError> {
    let grad = DVector::from_vec(model.energy_gradient(kappa)?);
    let j = model.closure_jacobian(kappa)?;
    let a = &j * j.transpose();
    let b = &j * grad;
    // Regularise slightly: near a great circle one direction is nearly unconstrained.
    let reg = 1e-14 * a.trace().max(f64::MIN_POSITIVE);
    let a = a + DMatrix::identity(3, 3) * reg;
    let sol = a.lu().solve(&b).unwrap_or_else(|| DVector::zeros(3));
    Ok([sol[0], sol[1], sol[2]])
}

/// Solve the KKT system of `model` from the curvature `start` (values at the Gauss points,
/// see [`SurfaceModel::gauss_sigma`]).
///
/// For a uniform rod without a phase condition, one is built from `start`
/// ([`Phase::from_gauss_values`]). The closure multiplier starts at its least-squares value.
/// Globalisation ([`SolveOptions::globalization`], default [`Globalization::Auto`]):
///
/// * Newton: each step solves the bordered symmetric KKT system with the analytic Jacobian
///   (LU with partial pivoting) and is globalised by a backtracking (Armijo) line search on
///   the merit `‖F‖²` (weighted as in [`SurfaceModel::residual_norm`]), for which the Newton
///   direction is always a descent direction. Converges to the nearby equilibrium, stable or
///   not (quadratically: 1–3 iterations from an exact or continued state).
/// * Relaxation (for rough starts such as Euler curves, point clouds, or inhomogeneous rods
///   started from homogeneous shapes): the start is projected onto the constraints, then
///   the energy is decreased monotonically by reduced Newton steps on the constraint
///   manifold whose reduced Hessian is shifted until positive definite, with restoration of
///   `c = 0` after every step; Newton polishes the result. This finds local minima.
///
/// Converged when the residual norm is below `opts.tolerance`.
///
/// Errors: [`SolverError::NewtonNotConverged`] (with the residual and closure violation
/// reached), [`SolverError::SingularJacobian`], [`SolverError::WrongLength`],
/// [`SolverError::InvalidInput`] (a start without shift mode, a closure that cannot be
/// restored).
pub fn solve(
    model: &SurfaceModel,
    start: &[f64],
    opts: &SolveOptions,
) -> Result<Equilibrium, SolverError> {
    let model = with_start_phase(model, start)?;
    let state_of = |kappa: &[f64]| full_state(&model, kappa);
    let newton_opts = SolveOptions {
        globalization: Globalization::Newton,
        ..opts.clone()
    };
    let relax_then_newton = || -> Result<Equilibrium, SolverError> {
        let (kappa, iters) = relax(&model, start, opts)?;
        let mut eq = solve_from_state(model.clone(), state_of(&kappa)?, &newton_opts)?;
        eq.report.relax_iterations = iters;
        Ok(eq)
    };
    match opts.globalization {
        Globalization::Newton => solve_from_state(model.clone(), state_of(start)?, opts),
        Globalization::Minimize => relax_then_newton(),
        Globalization::Auto => {
            let z0 = state_of(start)?;
            let r0 = model.residual_norm(&model.kkt_residual(&z0)?);
            if r0 <= opts.relax_threshold {
                match solve_from_state(model.clone(), z0, &newton_opts) {
                    Ok(eq) => Ok(eq),
                    Err(SolverError::NewtonNotConverged { .. })
                    | Err(SolverError::SingularJacobian { .. }) => relax_then_newton(),
                    Err(e) => Err(e),
                }
            } else {
                relax_then_newton()
            }
        }
    }
}

/// All equality constraints `(c, φ)` and their Jacobian (3 or 4 rows).
fn constraints(
    model: &SurfaceModel,
    kappa: &[f64],
) -> Result<(DVector<f64>, DMatrix<f64>), SolverError> {
    let (c, j) = model.closure_with_jacobian(kappa)?;
    let m = model.n_multipliers();
    let n = model.n_kappa();
    let mut cv = DVector::zeros(m);
    let mut jm = DMatrix::zeros(m, n);
    jm.rows_mut(0, 3).copy_from(&j);
    for k in 0..3 {
        cv[k] = c[k];
    }
    if let Some(ph) = model.phase() {
        cv[3] = ph.value(kappa);
        for (a, g) in ph.gradient().iter().enumerate() {
            jm[(3, a)] = *g;
        }
    }
    Ok((cv, jm))
}

/// Project onto `{c = 0, φ = 0}` by Gauss–Newton minimum-norm corrections.
fn restore(model: &SurfaceModel, kappa: &[f64]) -> Result<Vec<f64>, SolverError> {
    let mut k = kappa.to_vec();
    for _ in 0..40 {
        let (c, j) = constraints(model, &k)?;
        if c.norm() < 1e-14 {
            return Ok(k);
        }
        let a = &j * j.transpose();
        let reg = 1e-13 * a.trace();
        let a = a + DMatrix::identity(c.len(), c.len()) * reg;
        let y = a
            .lu()
            .solve(&c)
            .ok_or(SolverError::SingularJacobian { iteration: 0 })?;
        let d = j.transpose() * y;
        for (ki, di) in k.iter_mut().zip(d.iter()) {
            *ki -= di;
        }
        if k.iter().any(|v| !v.is_finite()) {
            break;
        }
    }
    let (c, _) = constraints(model, &k)?;
    // The closure residual is zero only at H = I (see crate::model): |c| = 2 sin(θ/2) of the
    // holonomy angle θ, so a projection that stalls near |c| = 2 is stuck at a half-turn.
    let norm = c.norm();
    if norm < 1e-10 {
        Ok(k)
    } else if norm > 1.9 {
        Err(SolverError::InvalidInput(format!(
            "the start cannot be closed at this length: the nearest closure leaves the frame \
             turned by {:.3} rad (about a half-turn), so the start is too far from a loop of \
             this length; start from an Euler curve or from a state solved at a nearby length",
            2.0 * (0.5 * norm.min(2.0)).asin()
        )))
    } else {
        Err(SolverError::InvalidInput(format!(
            "could not restore closure of the start (|c| = {norm:.3e})"
        )))
    }
}

/// Energy minimisation on the constraint manifold (see [`Globalization::Minimize`]).
/// Returns the relaxed curvature and the number of iterations.
///
/// Each iteration minimises the quadratic model `½δᵀ(∇²ℒ + τW)δ + ∇ℒᵀδ` on the tangent
/// space of the constraints, with the smallest `τ ∈ {0, 1e-3, 4e-3, …}` (units of `D0`)
/// for which the shifted Hessian is positive definite there — checked by the inertia of the
/// shifted KKT matrix ([`crate::stability`], Sylvester's law), as interior-point codes
/// correct inertia. The step comes from one `O(N)` solve with that factorisation, then a
/// backtracking line search on the energy with closure restored at every trial.
fn relax(
    model: &SurfaceModel,
    start: &[f64],
    opts: &SolveOptions,
) -> Result<(Vec<f64>, usize), SolverError> {
    let n = model.n_kappa();
    let d0 = model.stiffness().kind().reference();
    let gscale = (model.radius() / d0) / model.weight() / (n as f64).sqrt();
    let mut kappa = restore(model, start)?;
    let mut energy = model.energy(&kappa)?;
    let mut quiet = 0;
    for it in 0..opts.max_relax_iterations {
        let g = DVector::from_vec(model.energy_gradient(&kappa)?);
        let (_, j) = constraints(model, &kappa)?;
        let m = j.nrows();
        // Least-squares multipliers and the reduced gradient r = g − Jᵀλ.
        let a = &j * j.transpose();
        let reg = 1e-13 * a.trace();
        let lam = (a + DMatrix::identity(m, m) * reg)
            .lu()
            .solve(&(&j * &g))
            .ok_or(SolverError::SingularJacobian { iteration: it })?;
        let r = &g - j.transpose() * &lam;
        if r.norm() * gscale < opts.relax_threshold.min(1e-3) || quiet >= 2 {
            return Ok((kappa, it));
        }
        let mut z = kappa.clone();
        z.extend(lam.iter());
        let mut tau = 0.0;
        let factor = loop {
            match KktFactor::new(model, &z, -tau) {
                Ok(f) if f.reduced_negative_count() == 0 => break f,
                Ok(_) | Err(SolverError::SingularJacobian { .. }) => {}
                Err(e) => return Err(e),
            }
            tau = if tau == 0.0 { 1e-3 } else { tau * 4.0 };
            if tau > 1e8 {
                return Err(SolverError::InvalidInput(
                    "relaxation: the constrained Hessian could not be made positive definite"
                        .into(),
                ));
            }
        };
        let mut rhs = DVector::zeros(model.dim());
        for a in 0..n {
            rhs[a] = -r[a];
        }
        let delta = factor
            .solve(&rhs)
            .ok_or(SolverError::SingularJacobian { iteration: it })?
            .rows(0, n)
            .into_owned();
        let slope = g.dot(&delta);
        let mut alpha = 1.0;
        let mut accepted = false;
        for _ in 0..40 {
            let trial: Vec<f64> = kappa
                .iter()
                .zip(delta.iter())
                .map(|(k, d)| k + alpha * d)
                .collect();
            if let Ok(kt) = restore(model, &trial) {
                let et = model.energy(&kt)?;
                if et <= energy + 1e-4 * alpha * slope.min(0.0) {
                    kappa = kt;
                    energy = et;
                    accepted = true;
                    break;
                }
            }
            alpha *= 0.5;
        }
        if !accepted {
            // No further decrease: hand over to Newton.
            return Ok((kappa, it + 1));
        }
        quiet = if tau == 0.0 && alpha == 1.0 {
            quiet + 1
        } else {
            0
        };
    }
    Ok((kappa, opts.max_relax_iterations))
}

/// The Newton step `−J⁻¹F` at `z`: the `O(N)` block factorisation ([`KktFactor`]) with
/// one step of iterative refinement, or
/// the dense matrix if a pivot block is singular. `None` if both fail.
fn newton_step(model: &SurfaceModel, z: &[f64], f: &DVector<f64>) -> Option<DVector<f64>> {
    let finite = |d: &DVector<f64>| d.iter().all(|v| v.is_finite());
    if let Ok(k) = KktFactor::new(model, z, 0.0) {
        if let Some(mut d) = k.solve(&(-f)).filter(finite) {
            // One step of iterative refinement with the exact O(N) product J d: near a
            // great circle the closure is nearly rank-deficient and the block elimination
            // loses digits that the refinement recovers.
            let r = -f - k.apply(&d);
            if let Some(c) = k.solve(&r).filter(finite) {
                d += c;
            }
            return Some(d);
        }
    }
    model.kkt_jacobian(z).ok()?.lu().solve(&(-f)).filter(finite)
}

/// Newton's method from a full KKT state `z = (κ, μ, ν)` (e.g. a continuation point).
pub fn solve_from_state(
    model: SurfaceModel,
    z0: Vec<f64>,
    opts: &SolveOptions,
) -> Result<Equilibrium, SolverError> {
    NewtonRun::start(model, z0)?.iterate(opts, None)
}

/// [`solve`] with [`Globalization::Newton`] that also keeps the iteration where a run to
/// the tolerance `keep` would stop or go on ([`NewtonRun`]): the run at the first pass whose
/// residual is at most `keep`, or else at its last pass. The run is `None` where the start
/// cannot be evaluated.
pub fn solve_newton_keeping(
    model: &SurfaceModel,
    start: &[f64],
    opts: &SolveOptions,
    keep: f64,
) -> (Result<Equilibrium, SolverError>, Option<NewtonRun>) {
    solve_newton_keeping_until(model, start, opts, keep, None)
}

/// Where a Newton run has stalled, for [`solve_newton_keeping_until`]: its last `passes`
/// accepted steps were all at most `max_step` of the full Newton step, and the line search
/// did not lengthen its step over them (the last is no longer than the first). The
/// residual along the Newton direction falls about in proportion to the step taken, so
/// such a run moves its residual by a few per cent over the stretch; a run that creeps
/// towards its solution lengthens its steps as it approaches it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stall {
    /// Passes in a row.
    pub passes: usize,
    /// Largest accepted step length (of the full Newton step) that counts as stalled.
    pub max_step: f64,
}

impl Stall {
    /// Whether the accepted step lengths `steps` (one per pass so far) end stalled.
    fn holds(&self, steps: &[f64]) -> bool {
        if self.passes == 0 || steps.len() < self.passes {
            return false;
        }
        let last = &steps[steps.len() - self.passes..];
        last.iter().all(|a| *a <= self.max_step) && last[last.len() - 1] <= last[0]
    }
}

/// [`solve`] with [`Globalization::Newton`] whose run also ends, unconverged, where it has
/// stalled (`stall`, see [`Stall`]).
pub fn solve_newton_until(
    model: &SurfaceModel,
    start: &[f64],
    opts: &SolveOptions,
    stall: Stall,
) -> Result<Equilibrium, SolverError> {
    let newton = SolveOptions {
        globalization: Globalization::Newton,
        ..opts.clone()
    };
    let (m, z0) = newton_start(model, start)?;
    let run = NewtonRun {
        stall: Some(stall),
        ..NewtonRun::start(m, z0)?
    };
    run.iterate(&newton, None)
}

/// [`solve_newton_keeping`] whose run also ends, unconverged, where it has stalled
/// (`stall`, see [`Stall`]); the kept run carries the rule, so a resumed run stops where
/// one run from the start with the resumed options would.
pub fn solve_newton_keeping_until(
    model: &SurfaceModel,
    start: &[f64],
    opts: &SolveOptions,
    keep: f64,
    stall: Option<Stall>,
) -> (Result<Equilibrium, SolverError>, Option<NewtonRun>) {
    let newton = SolveOptions {
        globalization: Globalization::Newton,
        ..opts.clone()
    };
    let run = newton_start(model, start).and_then(|(m, z0)| NewtonRun::start(m, z0));
    let run = run.map(|r| NewtonRun { stall, ..r });
    match run {
        Ok(run) => {
            let mut kept = None;
            let eq = run.iterate(&newton, Some((keep, &mut kept)));
            (eq, kept)
        }
        Err(e) => (Err(e), None),
    }
}

/// The model and full KKT state [`solve`] starts Newton's method from: `start` with the
/// least-squares closure multiplier, and for a uniform rod without a phase condition one
/// built from `start`.
fn newton_start(
    model: &SurfaceModel,
    start: &[f64],
) -> Result<(SurfaceModel, Vec<f64>), SolverError> {
    let model = with_start_phase(model, start)?;
    let z = full_state(&model, start)?;
    Ok((model, z))
}

/// `model` checked against the length of `start` and, for a uniform rod without a phase
/// condition, with one built from `start` ([`Phase::from_gauss_values`]).
fn with_start_phase(model: &SurfaceModel, start: &[f64]) -> Result<SurfaceModel, SolverError> {
    let mut model = model.clone();
    if start.len() != model.n_kappa() {
        return Err(SolverError::WrongLength {
            expected: model.n_kappa(),
            found: start.len(),
        });
    }
    if model.stiffness().kind().is_uniform() && model.phase().is_none() {
        let phase = Phase::from_gauss_values(start, model.cells())?;
        model = model.with_phase(phase)?;
    }
    Ok(model)
}

/// The full KKT state `(κ, μ, ν)` of the curvature `kappa`: the least-squares closure
/// multiplier, and `ν = 0`.
fn full_state(model: &SurfaceModel, kappa: &[f64]) -> Result<Vec<f64>, SolverError> {
    let mu = initial_multiplier(model, kappa)?;
    let mut z: Vec<f64> = kappa.to_vec();
    z.extend_from_slice(&mu);
    if model.phase().is_some() {
        z.push(0.0);
    }
    Ok(z)
}

/// Newton's method of [`solve_from_state`] at the top of one pass (before its convergence
/// test): everything the iteration carries from pass to pass, so that it can go on later,
/// with other options, exactly as one run from the start would.
///
/// [`solve_newton_keeping`] keeps the run where a run to a looser tolerance `keep` stops
/// (or, if it never gets there, where its own run stopped); [`NewtonRun::resume`] with
/// options of tolerance at most `keep` then gives the iterates, the result and the report of
/// a run from the start with those options, without repeating the passes before.
#[derive(Clone, Debug)]
pub struct NewtonRun {
    model: SurfaceModel,
    z: DVector<f64>,
    f: DVector<f64>,
    /// The merit `‖F‖²` (weighted) at `z`.
    m: f64,
    iterations: usize,
    history: Vec<f64>,
    steps: Vec<f64>,
    /// The tolerance the run was kept for (`+∞` for a run that was not kept).
    keep: f64,
    /// The line search's limit of the run so far.
    max_backtracks: usize,
    /// Where the run ends unconverged before its iteration limit ([`Stall`]).
    stall: Option<Stall>,
}

impl NewtonRun {
    /// The run at its start `z0`.
    fn start(model: SurfaceModel, z0: Vec<f64>) -> Result<Self, SolverError> {
        let z = DVector::from_vec(z0);
        let f = model.kkt_residual(z.as_slice())?;
        let m = merit(&model.residual_scales(), &f);
        Ok(Self {
            model,
            z,
            f,
            m,
            iterations: 0,
            history: Vec::new(),
            steps: Vec::new(),
            keep: f64::INFINITY,
            max_backtracks: 0,
            stall: None,
        })
    }

    /// The model the run solves.
    pub fn model(&self) -> &SurfaceModel {
        &self.model
    }

    /// Newton iterations done.
    pub fn iterations(&self) -> usize {
        self.iterations
    }

    /// The run continued with `opts` (its globalisation is ignored): the result of
    /// [`solve_from_state`] with `opts` from the run's start, or `None` if `opts` could have
    /// stopped the run before this pass (a tolerance above the one it was kept for, fewer
    /// iterations than it has done, another line-search limit).
    pub fn resume(self, opts: &SolveOptions) -> Option<Result<Equilibrium, SolverError>> {
        let fits = opts.tolerance <= self.keep
            && opts.max_iterations >= self.iterations
            && (self.iterations == 0 || opts.max_backtracks == self.max_backtracks);
        fits.then(|| self.iterate(opts, None))
    }

    /// [`NewtonRun::resume`] that also keeps the run where it stops (converged, or at the
    /// iteration limit of `opts`) to go on from with a larger limit: `None` where `resume`
    /// gives `None`.
    pub fn resume_keeping(
        self,
        opts: &SolveOptions,
    ) -> Option<(Result<Equilibrium, SolverError>, Option<NewtonRun>)> {
        let fits = opts.tolerance <= self.keep
            && opts.max_iterations >= self.iterations
            && (self.iterations == 0 || opts.max_backtracks == self.max_backtracks);
        fits.then(|| {
            let mut kept = None;
            let eq = self.iterate(opts, Some((opts.tolerance, &mut kept)));
            (eq, kept)
        })
    }

    /// The KKT residual norms of the run: before every pass so far, and at its current state.
    pub fn residuals(&self) -> Vec<f64> {
        let mut r = self.history.clone();
        r.push(self.m.sqrt());
        r
    }

    /// The iteration from this pass on (Sec. 4.1): a Newton step by the block factorisation,
    /// a backtracking line search on the merit, until the residual is below the tolerance.
    /// With `keep = Some((tol, kept))`, `kept` receives the run at the first pass whose
    /// residual is at most `tol`, or else at the last pass.
    fn iterate(
        mut self,
        opts: &SolveOptions,
        mut keep: Option<(f64, &mut Option<NewtonRun>)>,
    ) -> Result<Equilibrium, SolverError> {
        let scales = self.model.residual_scales();
        self.max_backtracks = opts.max_backtracks;
        // The kept run is cloned once: where it freezes (the first pass at most `tol`), or
        // else, after the last pass, rebuilt from the run at its exit (within a pass only the
        // history and the iteration count change before a step is accepted).
        let mut frozen = false;
        let mut top;
        let exit: Result<bool, SolverError> = loop {
            if let Some((tol, kept)) = keep.as_mut() {
                if !frozen && self.m.sqrt() <= *tol {
                    **kept = Some(NewtonRun {
                        keep: *tol,
                        ..self.clone()
                    });
                    frozen = true;
                }
            }
            top = (self.iterations, self.history.len());
            let m = self.m;
            self.history.push(m.sqrt());
            if !m.is_finite() {
                break Ok(false);
            }
            if m.sqrt() <= opts.tolerance {
                break Ok(true);
            }
            if self.iterations >= opts.max_iterations
                || self.stall.is_some_and(|st| st.holds(&self.steps))
            {
                break Ok(false);
            }
            self.iterations += 1;
            let (model, z) = (&self.model, &self.z);
            let Some(delta) = newton_step(model, z.as_slice(), &self.f) else {
                break Err(SolverError::SingularJacobian {
                    iteration: self.iterations,
                });
            };
            let mut alpha = 1.0;
            let mut accepted = None;
            for _ in 0..=opts.max_backtracks {
                let trial = z + &delta * alpha;
                let bound = (1.0 - 1e-4 * alpha) * m;
                if let Some(part) = closure_merit_above(model, &scales, trial.as_slice(), bound) {
                    alpha = shorter_step(alpha, m, part);
                    continue;
                }
                match model.kkt_residual(trial.as_slice()) {
                    Ok(ft) => {
                        let mt = merit(&scales, &ft);
                        if mt.is_finite() && mt <= bound {
                            accepted = Some(Ok((trial, ft, mt)));
                            break;
                        }
                        alpha = shorter_step(alpha, m, mt);
                    }
                    Err(SolverError::InvalidInput(_)) => alpha = shorter_step(alpha, m, f64::NAN),
                    Err(e) => {
                        accepted = Some(Err(e));
                        break;
                    }
                }
            }
            let (zn, fnew, mnew) = match accepted {
                Some(Ok(a)) => a,
                Some(Err(e)) => break Err(e),
                None => {
                    // No decrease possible: at the round-off floor or stuck.
                    let step_small = delta.norm() <= 1e-12 * (1.0 + z.norm());
                    break Ok(step_small && m.sqrt() <= 1e3 * opts.tolerance);
                }
            };
            self.steps.push(alpha);
            self.z = zn;
            self.f = fnew;
            self.m = mnew;
        };
        if let Some((tol, kept)) = keep {
            if !frozen {
                let mut last = NewtonRun {
                    keep: tol,
                    ..self.clone()
                };
                (last.iterations, _) = top;
                last.history.truncate(top.1);
                *kept = Some(last);
            }
        }
        let converged = exit?;
        let model = self.model;
        let (kappa, mu, nu) = model.split(self.z.as_slice())?;
        let cl = model.closure(kappa)?;
        let closure = (cl[0] * cl[0] + cl[1] * cl[1] + cl[2] * cl[2]).sqrt();
        let report = ConvergenceReport {
            iterations: self.iterations,
            residual: self.m.sqrt(),
            closure,
            converged,
            history: self.history,
            step_lengths: self.steps,
            relax_iterations: 0,
        };
        if !converged {
            return Err(SolverError::NewtonNotConverged {
                iterations: self.iterations,
                residual: report.residual,
                closure,
            });
        }
        Ok(Equilibrium {
            kappa: kappa.to_vec(),
            mu,
            nu,
            model,
            report,
        })
    }
}

/// The merit of the closure rows of the KKT residual at `z` alone
/// ([`SurfaceModel::kkt_closure_residual`], equal to the bit to those of the whole residual)
/// where it is above `bound`: then the whole merit is above it too, and a line search
/// rejects the trial without building the residual's stationarity rows (their derivatives
/// and adjoint sweep, most of its cost). The merit sums its nonnegative terms in order, the
/// closure rows after the stationarity rows, and rounded addition is monotone, so the whole
/// sum is at least these rows' terms summed alone. `None` where these rows' merit is at most
/// `bound`, or where the rows cannot be built (the whole residual then decides, with its own
/// error) or are not finite.
fn closure_merit_above(model: &SurfaceModel, scales: &[f64], z: &[f64], bound: f64) -> Option<f64> {
    let n = model.n_kappa();
    let rows = model.kkt_closure_residual(z).ok()?;
    let part = scales[n..n + 3]
        .iter()
        .zip(rows.iter())
        .map(|(s, v)| s * v * v)
        .sum::<f64>();
    (part > bound).then_some(part)
}

/// The next step length of Newton's line search after the step `alpha` was rejected with
/// the merit `at` there (or a lower bound of it; `NaN` where the trial could not be
/// evaluated), from the merit `m` at the start: safeguarded quadratic backtracking
/// (Nocedal & Wright, *Numerical Optimization*, Sec. 3.5). The merit `φ(α) = Σ sᵢ Fᵢ(z +
/// αδ)²` along the Newton step `δ` has `φ(0) = m` and `φ'(0) = −2m` (`J δ = −F`), so the
/// parabola through these and `φ(alpha) = at` has its minimum at `m alpha²/(at − m + 2m
/// alpha)`; the step is kept within `[alpha/10, alpha/2]`, so that it shrinks at least as
/// fast as by halving and at most tenfold per trial, and halves where the parabola has no
/// minimum or the merit is unknown. A lower bound of `φ(alpha)` gives a step at least as long as the
/// merit itself would. Where Newton's model of the residual holds only over a sliver of the
/// step (a run that creeps at a few per cent of it), the parabola reaches that sliver in two
/// or three trials instead of five to eight halvings.
fn shorter_step(alpha: f64, m: f64, at: f64) -> f64 {
    let curvature = at - m + 2.0 * m * alpha;
    let next = if curvature > 0.0 && curvature.is_finite() {
        m * alpha * alpha / curvature
    } else {
        0.5 * alpha
    };
    next.clamp(0.1 * alpha, 0.5 * alpha)
}

/// The weighted merit `Σ sᵢ Fᵢ²` ([`SurfaceModel::residual_scales`]).
fn merit(scales: &[f64], f: &DVector<f64>) -> f64 {
    scales
        .iter()
        .zip(f.iter())
        .map(|(s, v)| s * v * v)
        .sum::<f64>()
}

impl Equilibrium {
    /// The model (with the phase condition actually used).
    pub fn model(&self) -> &SurfaceModel {
        &self.model
    }

    /// Geodesic curvature at the Gauss points (the unknowns).
    pub fn kappa(&self) -> &[f64] {
        &self.kappa
    }

    /// Closure multiplier `μ`.
    pub fn multiplier(&self) -> [f64; 3] {
        self.mu
    }

    /// Phase multiplier `ν` (0 without phase condition). It measures how much the
    /// discretisation breaks the arclength-shift symmetry of a uniform rod.
    pub fn phase_multiplier(&self) -> f64 {
        self.nu
    }

    /// Full KKT state `z = (κ, μ, ν)`.
    pub fn state(&self) -> Vec<f64> {
        let mut z = self.kappa.clone();
        z.extend_from_slice(&self.mu);
        if self.model.phase().is_some() {
            z.push(self.nu);
        }
        z
    }

    /// Convergence report of the solve.
    pub fn report(&self) -> &ConvergenceReport {
        &self.report
    }

    /// Conserved moment about the sphere centre, `𝓜 = M + r × F` (Sec. 4.3, Eqs. (40)–(41)),
    /// in the frame where `X(0) = I`. It equals minus the closure multiplier, `𝓜 = −μ`
    /// (see [`crate::model`]); `|𝓜|` is Eq. (42) for uniform rods.
    pub fn moment(&self) -> [f64; 3] {
        [-self.mu[0], -self.mu[1], -self.mu[2]]
    }

    /// Energies normalised as `E R/(π D0)` (discrete Gauss quadrature of Eq. (2)).
    pub fn energy(&self) -> EnergyReport {
        let (total, geodesic, normal) =
            self.model
                .energy_normalized(&self.kappa)
                .unwrap_or((f64::NAN, f64::NAN, f64::NAN));
        EnergyReport {
            total,
            geodesic,
            normal,
        }
    }

    /// Local quantities at the cell boundaries `s_i = i h`, `i = 0..N`, computed from the
    /// conserved moment and the frame (no numerical differentiation):
    /// `κ_g = 𝓜·n/D`, `F_t = (𝓜·g − D/R)/R`, `F_g = −𝓜·t/R`, `λ = −F_t/R + D''/R`,
    /// `κ_g' = (𝓜·t/R − D'κ_g)/D`, `τ = κ_g'/(Rκ²)`, `F_b = −Dκ_g'/sqrt(1 + R²κ_g²)` (Eq. (24)),
    /// `F_n = −D' sqrt(1 + R²κ_g²)/R − DRκ_gκ_g'/sqrt(1 + R²κ_g²)` (Eq. (25)).
    ///
    /// `λ = −F_t/R + D''/R` follows from the force balance normal to the sphere,
    /// `F' = λ n` (Eq. (13)), with the internal force component along `n`,
    /// `F·n = D'/R` (nonzero for a non-uniform rod); it equals Eq. (27) and, for `D' = 0`,
    /// Eq. (38).
    pub fn profile(&self) -> Vec<ProfilePoint> {
        let frames = self
            .model
            .frames(&self.kappa)
            .expect("kappa has the model's length");
        let r = self.model.radius();
        let len = self.model.length();
        let bounds = self.model.bounds();
        let mm = Vector3::from(self.moment());
        (0..self.model.cells())
            .map(|i| {
                let s = bounds[i] * len;
                let x: &Matrix3<f64> = &frames[i];
                let t = Vector3::new(x[(0, 0)], x[(0, 1)], x[(0, 2)]);
                let g = Vector3::new(x[(1, 0)], x[(1, 1)], x[(1, 2)]);
                let n = Vector3::new(x[(2, 0)], x[(2, 1)], x[(2, 2)]);
                let (d, d1, d2) = self.model.stiffness().eval(s / len).per_arclength(len);
                let kg = mm.dot(&n) / d;
                let f_t = (mm.dot(&g) - d / r) / r;
                let f_g = -mm.dot(&t) / r;
                let lambda = -f_t / r + d2 / r;
                let kappa = (kg * kg + 1.0 / (r * r)).sqrt();
                let kgp = (mm.dot(&t) / r - d1 * kg) / d;
                let tau = kgp / (r * kappa * kappa);
                let root = (1.0 + r * r * kg * kg).sqrt();
                let f_b = -d * kgp / root;
                let f_n = -d1 * root / r - d * r * kg * kgp / root;
                ProfilePoint {
                    s,
                    x: r * n[0],
                    y: r * n[1],
                    z: r * n[2],
                    kappa,
                    tau,
                    kappa_g: kg,
                    kappa_g_prime: kgp,
                    lambda,
                    f_t,
                    f_n,
                    f_b,
                    f_g,
                    d,
                }
            })
            .collect()
    }

    /// Trigonometric interpolant of the geodesic curvature at the cell boundaries,
    /// `κ_g = 𝓜·n/D`, in the mesh coordinate `u` (`σ = s/L` on a uniform mesh; see
    /// [`crate::mesh`]): used to resample the equilibrium to another resolution.
    pub fn kappa_g_interpolant(&self) -> Result<TrigInterpolant, SolverError> {
        let kg: Vec<f64> = self.profile().iter().map(|p| p.kappa_g).collect();
        TrigInterpolant::new(&kg)
    }

    /// Geodesic curvature at the Gauss points of a grid of `cells` cells on the same mesh
    /// map (for Richardson extrapolation and continuation at another resolution).
    pub fn resample(&self, cells: usize) -> Result<Vec<f64>, SolverError> {
        let map = self.model.mesh();
        let bounds = map.bounds(cells)?;
        self.sample_at(
            &(0..2 * cells)
                .map(|a| {
                    let c = a / 2;
                    bounds[c] + crate::model::GAUSS_OFFSETS[a % 2] * (bounds[c + 1] - bounds[c])
                })
                .collect::<Vec<_>>(),
        )
    }

    /// Geodesic curvature at the normalised arclengths `sigma` (spectral interpolation in
    /// the mesh coordinate).
    pub fn sample_at(&self, sigma: &[f64]) -> Result<Vec<f64>, SolverError> {
        let t = self.kappa_g_interpolant()?;
        let map = self.model.mesh();
        Ok(t.eval_many(&map.u_of_sigmas(sigma.iter().copied())))
    }

    /// Extremes of the contact force `(λ_min, λ_max)`: the trigonometric interpolant of `λ`
    /// at the cell boundaries, maximised/minimised by Newton's method between the samples.
    pub fn lambda_range(&self) -> (f64, f64) {
        let lam: Vec<f64> = self.profile().iter().map(|p| p.lambda).collect();
        match TrigInterpolant::new(&lam) {
            Ok(t) => {
                let ((_, lo), (_, hi)) = t.extrema(4 * lam.len());
                (lo, hi)
            }
            Err(_) => (f64::NAN, f64::NAN),
        }
    }

    /// Normalised length `L̄`.
    pub fn lbar(&self) -> f64 {
        self.model.lbar()
    }

    /// Loop length `L`.
    pub fn length(&self) -> f64 {
        2.0 * PI * self.model.radius() * self.model.lbar()
    }
}

#[cfg(test)]
mod tests {
    use super::shorter_step;

    /// On a merit that is the parabola `φ(α) = m − 2mα + cα²` the next step is its minimiser
    /// `m/c` where that lies within `[α/10, α/2]`, else the nearer end; a lower bound of the
    /// merit never gives a shorter step; an unknown merit halves the step.
    #[test]
    fn shorter_step_is_the_safeguarded_minimiser_of_the_parabola() {
        let m = 2.5e-7;
        let alpha = 0.5;
        for c in [1.2 * m, 3.0 * m, 7.0 * m, 40.0 * m, 1e6 * m] {
            let at = m - 2.0 * m * alpha + c * alpha * alpha;
            let next = shorter_step(alpha, m, at);
            let expected = (m / c).clamp(0.1 * alpha, 0.5 * alpha);
            assert!(
                (next - expected).abs() <= 1e-12 * expected,
                "c/m = {}",
                c / m
            );
            assert!(shorter_step(alpha, m, 0.5 * at) >= next, "c/m = {}", c / m);
        }
        assert_eq!(shorter_step(alpha, m, f64::NAN), 0.5 * alpha);
        assert_eq!(shorter_step(alpha, m, f64::INFINITY), 0.5 * alpha);
        // A merit at or below the tangent line has no minimum on the parabola: halve.
        assert_eq!(shorter_step(alpha, m, m - 2.0 * m * alpha), 0.5 * alpha);
    }

    /// Trials until the Armijo test `φ(α) ≤ (1 − 10⁻⁴ α) φ(0)` passes, the next step from
    /// `next(α, φ(α))`.
    fn trials(phi: impl Fn(f64) -> f64, next: impl Fn(f64, f64) -> f64) -> (usize, f64) {
        let m = phi(0.0);
        let mut alpha = 1.0;
        for k in 1..=60 {
            let at = phi(alpha);
            if at <= (1.0 - 1e-4 * alpha) * m {
                return (k, alpha);
            }
            alpha = next(alpha, at);
        }
        panic!("no step accepted");
    }

    /// On merits whose Newton model holds over a sliver of the step (`φ(α) = m(1 − α)² +
    /// Kα⁴`, the residual's next term large), the quadratic backtracking accepts a step in
    /// no more trials than halving does and in fewer once `K ≥ 100` (3 against 6 at
    /// `K = 10⁴`, 4 against 10 at `10⁸`), and the step it accepts is at least a tenth of the
    /// one halving accepts.
    #[test]
    fn quadratic_backtracking_needs_fewer_trials_than_halving() {
        let m = 1e-6;
        for k in [1e-4, 1e-2, 1.0, 1e2, 1e4, 1e6, 1e8] {
            let phi = |a: f64| m * (1.0 - a).powi(2) + k * m * a.powi(4);
            let (nq, aq) = trials(phi, |a, at| shorter_step(a, m, at));
            let (nh, ah) = trials(phi, |a, _| 0.5 * a);
            assert!(nq <= nh, "K = {k}: {nq} trials against {nh}");
            assert!(aq >= 0.1 * ah, "K = {k}: step {aq} against {ah}");
            if k >= 1e2 {
                assert!(nq < nh, "K = {k}: {nq} trials against {nh}");
            }
        }
    }
}
