//! The enclosed model behind the model seam: [`EnclosedModel`] implements
//! [`Confinement`], so that [`ParamProblem`](crate::ParamProblem) and the continuation
//! crate's loops trace enclosed states as they trace surface ones.
//!
//! The KKT system is the model's semismooth one ([`EnclosedModel::residual`]: stationarity,
//! closure, gauges and `min(λ_j, σ g_j) = 0` at the nodes); its Jacobian is the generalised
//! (active-set) Jacobian of [`EnclosedModel::evaluate`], so Newton's method through the seam
//! is the semismooth Newton method without globalisation (the model's own
//! [`solve_enclosed`](super::solve_enclosed) adds backtracking). The factorisation is the
//! `O(N)` block form of [`super::lifted`] ([`LiftedFactor`]: solves, products and the
//! determinant), and a dense LU where the Jacobian is shifted (inertia) or a pivot block
//! is nearly singular. Parameter derivatives `∂F/∂θ` are central differences of the residual
//! ([`rodloop_continuation::fd_dparam`], error `O(δ²)`): the chain of cell propagators
//! depends on `L̄` through every cell length, and its analytic derivative is not written yet.
//!
//! Where the contact set changes (nodes touching down with zero force, or letting go),
//! `min(λ_j, σ g_j)` has a kink: Newton at a fixed parameter (the natural-parameter loop,
//! [`rodloop_continuation::natural`]) passes it, while the bordered corrector of
//! pseudo-arclength stalls there (measured on the lifted-off figure-eight at `L̄ ≈ 1.4198`,
//! `N = 64`, in this module's tests). A model with its contact set held fixed
//! ([`EnclosedModel::with_contact_set`], [`super::arclength`]) is smooth: pseudo-arclength
//! follows it through folds, with the piece's end (a contact impulse or a free gap reaching
//! zero, [`super::arclength::contact_slack`]) as an event where the set is switched
//! ([`super::arclength::follow_contacts`]); [`Confinement::with_param`] keeps the set.

use std::cell::OnceCell;

use nalgebra::{DMatrix, DVector};
use rodloop_continuation::{DenseLu, Factorization};

use super::lifted_factor::LiftedFactor;
use super::model::EnclosedModel;
use super::solve::EnclosedState;
use crate::param::Param;
use crate::seam::{Confinement, Inertia};
use crate::stiffness::StiffnessProfile;
use crate::SolverError;

/// A factorised enclosed KKT Jacobian, with the stability index of its state computed on
/// first request: the `O(N)` lifted block form ([`LiftedFactor`]) where it is unshifted
/// and its pivot blocks are regular, else the dense LU.
pub struct EnclosedFactor {
    lu: Inner,
    model: EnclosedModel,
    z: Vec<f64>,
    shift: f64,
    negative: OnceCell<usize>,
}

/// The factors of an [`EnclosedFactor`].
enum Inner {
    Dense(DenseLu),
    Lifted(Box<LiftedFactor>),
}

impl Inner {
    fn get(&self) -> &dyn Factorization {
        match self {
            Inner::Dense(lu) => lu,
            Inner::Lifted(f) => f.as_ref(),
        }
    }
}

impl Factorization for EnclosedFactor {
    fn solve(&self, b: &DVector<f64>) -> Option<DVector<f64>> {
        self.lu.get().solve(b)
    }
    fn apply(&self, v: &DVector<f64>) -> DVector<f64> {
        self.lu.get().apply(v)
    }
    fn det_sign(&self) -> f64 {
        self.lu.get().det_sign()
    }
    fn log_abs_det(&self) -> f64 {
        self.lu.get().log_abs_det()
    }
}

impl Inertia for EnclosedFactor {
    /// Eigenvalues below the shift of the mass-scaled Hessian of the Lagrangian on the
    /// tangent space of the equalities and the strongly active wall constraints (activity
    /// threshold `1e-6`), from the inertia of the bordered KKT matrix
    /// ([`EnclosedState::count_below`]). `usize::MAX` if the Hessian cannot be evaluated.
    fn reduced_negative_count(&self) -> usize {
        *self.negative.get_or_init(|| {
            state_of(&self.model, &self.z)
                .count_below(1e-6, self.shift)
                .unwrap_or(usize::MAX)
        })
    }
}

/// An [`EnclosedState`] view of `(model, z)` (no solve).
fn state_of(model: &EnclosedModel, z: &[f64]) -> EnclosedState {
    EnclosedState {
        model: model.clone(),
        z: z.to_vec(),
        iterations: 0,
        residual: f64::NAN,
    }
}

/// The mass of the primal unknowns (node length share for the curvatures, `L/R²` for the
/// start point), zero for the multipliers: the metric of the shift.
fn mass(model: &EnclosedModel) -> Vec<f64> {
    let n = model.cells();
    let np = model.n_primal();
    (0..model.dim())
        .map(|a| {
            if a < 4 * n {
                0.5 * model.cell_length(a / 4)
            } else if a < np {
                model.length() / (model.radius() * model.radius())
            } else {
                0.0
            }
        })
        .collect()
}

impl Confinement for EnclosedModel {
    type Factor = EnclosedFactor;

    fn dim(&self) -> usize {
        EnclosedModel::dim(self)
    }
    /// Closure, gauges and one wall constraint per node.
    fn n_constraints(&self) -> usize {
        self.n_equalities() + self.cells()
    }
    fn residual(&self, z: &[f64]) -> Result<DVector<f64>, SolverError> {
        EnclosedModel::residual(self, z)
    }
    fn jacobian(&self, z: &[f64]) -> Result<DMatrix<f64>, SolverError> {
        Ok(self.evaluate(z)?.jacobian)
    }
    fn factorize(&self, z: &[f64], shift: f64) -> Result<EnclosedFactor, SolverError> {
        let lifted = if shift == 0.0 {
            match LiftedFactor::new(self, z) {
                Ok(f) if f.log_abs_det().is_finite() => Some(f),
                Ok(_) | Err(SolverError::SingularJacobian { .. }) => None,
                Err(e) => return Err(e),
            }
        } else {
            None
        };
        if let Some(f) = lifted {
            return Ok(EnclosedFactor {
                lu: Inner::Lifted(Box::new(f)),
                model: self.clone(),
                z: z.to_vec(),
                shift,
                negative: OnceCell::new(),
            });
        }
        let mut j = self.evaluate(z)?.jacobian;
        if shift != 0.0 {
            for (a, m) in mass(self).into_iter().enumerate() {
                j[(a, a)] -= shift * m;
            }
        }
        let lu = DenseLu::new(j);
        if lu.log_abs_det() == f64::NEG_INFINITY {
            return Err(SolverError::SingularJacobian { iteration: 0 });
        }
        Ok(EnclosedFactor {
            lu: Inner::Dense(lu),
            model: self.clone(),
            z: z.to_vec(),
            shift,
            negative: OnceCell::new(),
        })
    }
    fn apply(&self, z: &[f64], dz: &[f64]) -> Result<DVector<f64>, SolverError> {
        Ok(self.evaluate(z)?.jacobian * DVector::from_column_slice(dz))
    }
    fn param(&self, p: Param) -> Result<f64, SolverError> {
        match p {
            Param::Lbar => Ok(self.lbar()),
            _ => self.stiffness().kind().param(p),
        }
    }
    /// The same mesh, gauge and pull with `p` changed.
    fn with_param(&self, p: Param, value: f64) -> Result<Self, SolverError> {
        let (lbar, stiffness) = match p {
            Param::Lbar => (value, self.stiffness().kind().clone()),
            _ => (self.lbar(), self.stiffness().kind().with_param(p, value)?),
        };
        let m = self
            .rebuilt(lbar, self.cells(), &stiffness, self.gauge().clone())?
            .with_pull(self.pull())?;
        match self.contact_set() {
            Some(set) => m.with_contact_set(set.to_vec()),
            None => Ok(m),
        }
    }
    /// Central difference of the residual in the parameter (see the module docs).
    fn dparam(&self, z: &[f64], p: Param) -> Result<DVector<f64>, SolverError> {
        let theta = Confinement::param(self, p)?;
        rodloop_continuation::fd_dparam(|t| Confinement::with_param(self, p, t)?.residual(z), theta)
    }
    /// The index of [`EnclosedState::index`] with activity threshold `tolerance`.
    fn index(&self, z: &[f64], tolerance: f64) -> Result<usize, SolverError> {
        state_of(self, z).index(tolerance)
    }
    fn energy(&self, z: &[f64]) -> Result<f64, SolverError> {
        EnclosedModel::energy(self, z)
    }
    fn residual_norm(&self, f: &DVector<f64>) -> f64 {
        EnclosedModel::residual_norm(self, f)
    }
    fn radius(&self) -> f64 {
        EnclosedModel::radius(self)
    }
    fn lbar(&self) -> f64 {
        EnclosedModel::lbar(self)
    }
    fn cells(&self) -> usize {
        EnclosedModel::cells(self)
    }
    fn stiffness(&self) -> &StiffnessProfile {
        EnclosedModel::stiffness(self)
    }
    /// `w_c D_g κ` on the two curvature components of every Gauss point `g` (the first
    /// `4N` unknowns), zero on the start point and the multipliers.
    fn energy_gradient(&self, z: &[f64]) -> Result<DVector<f64>, SolverError> {
        let scale = energy_scale(self);
        check_len(self, z)?;
        let mut out = DVector::zeros(EnclosedModel::dim(self));
        for c in 0..EnclosedModel::cells(self) {
            let w = 0.5 * self.cell_length(c);
            for i in 0..4 {
                let a = 4 * c + i;
                out[a] = w * self.d_gauss_at(2 * c + i / 2) * z[a] * scale;
            }
        }
        Ok(out)
    }
    /// `|κ_g|² = κ₁² + κ₂²` (the full curvature: no normal part imposed by a surface).
    fn energy_dparam(&self, z: &[f64], p: Param) -> Result<f64, SolverError> {
        if p == Param::Lbar {
            return Ok(EnclosedModel::energy(self, z)? / EnclosedModel::lbar(self));
        }
        check_len(self, z)?;
        let kind = EnclosedModel::stiffness(self).kind();
        let mut acc = 0.0;
        for c in 0..EnclosedModel::cells(self) {
            let w = 0.5 * self.cell_length(c);
            for j in 0..2 {
                let g = 2 * c + j;
                let (k1, k2) = (z[2 * g], z[2 * g + 1]);
                acc += 0.5 * w * kind.dparam(p, self.gauss_sigma(g))? * (k1 * k1 + k2 * k2);
            }
        }
        Ok(acc * energy_scale(self))
    }
}

/// `R/(π D0)`: the normalisation of [`EnclosedModel::energy`].
fn energy_scale(model: &EnclosedModel) -> f64 {
    EnclosedModel::radius(model) / (std::f64::consts::PI * model.stiffness().kind().reference())
}

/// `z` has the model's dimension.
fn check_len(model: &EnclosedModel, z: &[f64]) -> Result<(), SolverError> {
    let n = EnclosedModel::dim(model);
    if z.len() == n {
        Ok(())
    } else {
        Err(SolverError::WrongLength {
            expected: n,
            found: z.len(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::super::model::Gauge;
    use super::*;
    use crate::enclosed::{solve_branch, EnclosedOptions, SurfaceSource};
    use crate::{ParamProblem, Stiffness};
    use rodloop_continuation::natural::{natural_branch, NaturalSettings};

    /// The lifted-off figure-eight (branch 2) at `lbar`, `N = 64` cells.
    fn figure_eight(lbar: f64) -> EnclosedState {
        let l = rodloop_exact::paper_branch_loop(1, lbar).unwrap();
        solve_branch(
            1.0,
            lbar,
            &Stiffness::uniform(1.0),
            &SurfaceSource::Exact(l),
            64,
            &EnclosedOptions::default(),
        )
        .unwrap()
        .fine
    }

    #[test]
    fn parameter_derivative_matches_a_wider_difference() {
        // The central difference of the seam against one with a ten times wider step: both
        // O(δ²), so they agree to the scale of the second difference.
        let a = figure_eight(1.40);
        let d = Confinement::dparam(&a.model, &a.z, Param::Lbar).unwrap();
        let h = 1e-4;
        let fp = Confinement::with_param(&a.model, Param::Lbar, 1.40 + h)
            .unwrap()
            .residual(&a.z)
            .unwrap();
        let fm = Confinement::with_param(&a.model, Param::Lbar, 1.40 - h)
            .unwrap()
            .residual(&a.z)
            .unwrap();
        let wide = (fp - fm) / (2.0 * h);
        let err = (&d - &wide).amax() / d.amax();
        assert!(err < 1e-5, "relative difference {err:.3e}");
        assert!(d.amax() > 0.0);
    }

    #[test]
    fn the_continuation_loop_traces_an_enclosed_branch_through_the_seam() {
        // The natural-parameter loop of the continuation crate on ParamProblem<EnclosedModel>
        // (Newton with the seam's residual and factorisation, the gauge of the start held)
        // against the enclosed tracer's own steps (EnclosedState::step_to: a new gauge and
        // the backtracking semismooth Newton at every length): the same states, so the same
        // energies, at L̄ = 1.41, 1.42, 1.43.
        let a = figure_eight(1.40);
        let problem = ParamProblem::new(a.model.clone(), Param::Lbar).unwrap();
        let targets = [1.41, 1.42, 1.43];
        let settings = NaturalSettings {
            max_step: 0.005,
            ..NaturalSettings::default()
        };
        let z0 = DVector::from_column_slice(&a.z);
        let traced = natural_branch(&problem, &z0, 1.40, &targets, &settings, 1e-10, 30).unwrap();
        assert!(traced.stuck.is_none(), "{:?}", traced.stuck.map(|s| s.1));
        assert_eq!(traced.points.len(), 4);
        let opts = EnclosedOptions::default();
        let mut cur = a.clone();
        for (pt, &l) in traced.points[1..].iter().zip(&targets) {
            cur = cur.step_to(l, &opts).unwrap();
            let model = problem.model_at(l).unwrap();
            let e_seam = Confinement::energy(&model, pt.x.as_slice()).unwrap();
            let e_tracer = cur.energy();
            assert!(
                (e_seam - e_tracer).abs() < 1e-9 * e_tracer,
                "L̄ = {l}: seam {e_seam}, tracer {e_tracer}"
            );
            // A closed loop inside the ball at a KKT point of the enclosed model.
            let r = model.residual_norm(&model.residual(pt.x.as_slice()).unwrap());
            assert!(r < 1e-6, "L̄ = {l}: residual {r:.3e}");
            let gaps = model.gaps(pt.x.as_slice()).unwrap();
            assert!(gaps.iter().all(|g| *g > -1e-9), "L̄ = {l}");
        }
    }

    #[test]
    fn pseudo_arclength_through_the_seam_reaches_the_tracer_state() {
        // The continuation crate's pseudo-arclength homotopy (target::reach) on the seam from
        // L̄ = 1.40 to 1.415, corrected there by Newton through the seam: the energy of the
        // tracer's state at 1.415 (three step_to steps).
        use rodloop_continuation::target::{reach, ReachLimits};
        use rodloop_continuation::{newton, PseudoArclength};
        let a = figure_eight(1.40);
        let problem = ParamProblem::new(a.model.clone(), Param::Lbar).unwrap();
        let settings = PseudoArclength::new()
            .with_ds(0.005)
            .and_then(|s| s.with_ds_bounds(1e-6, 0.01))
            .and_then(|s| s.with_detect_branch_points(false))
            .unwrap();
        let z0 = DVector::from_column_slice(&a.z);
        let limits = ReachLimits::default();
        let r = reach(&problem, &settings, &z0, 1.40, 1.415, &limits, || true).unwrap();
        assert!(r.folds.is_empty());
        let (x, _) = newton(&problem, &r.x, 1.415, 1e-10, 30).unwrap();
        let model = problem.model_at(1.415).unwrap();
        let e_seam = Confinement::energy(&model, x.as_slice()).unwrap();
        let opts = EnclosedOptions::default();
        let mut cur = a.clone();
        for l in [1.405, 1.41, 1.415] {
            cur = cur.step_to(l, &opts).unwrap();
        }
        let e_tracer = cur.energy();
        assert!(
            (e_seam - e_tracer).abs() < 1e-9 * e_tracer,
            "seam {e_seam}, tracer {e_tracer}"
        );
        // Where the contact set changes (four nodes touch down with zero force near
        // L̄ = 1.4198) the semismooth residual has a kink and the bordered corrector stalls:
        // pseudo-arclength through the seam stops there (the natural-parameter loop, Newton
        // at fixed L̄, passes it; see the test above).
        let stop = reach(&problem, &settings, &z0, 1.40, 1.43, &limits, || true).unwrap_err();
        assert!((stop.closest - 1.4198).abs() < 1e-3, "{}", stop.closest);
    }

    #[test]
    fn factor_inertia_matches_the_state_stability() {
        let a = figure_eight(1.40);
        let f = Confinement::factorize(&a.model, &a.z, 0.0).unwrap();
        let (index, _) = a.stability(1e-6).unwrap();
        assert_eq!(f.reduced_negative_count(), index);
        assert_eq!(Confinement::index(&a.model, &a.z, 1e-6).unwrap(), index);
        // The factorisation solves with the Jacobian it factorised.
        let j = Confinement::jacobian(&a.model, &a.z).unwrap();
        let b = DVector::from_fn(j.nrows(), |i, _| (i as f64).sin());
        let x = f.solve(&b).unwrap();
        assert!((&j * &x - &b).amax() < 1e-8 * b.amax() * j.amax().max(1.0));
    }

    #[test]
    fn energy_derivatives_match_finite_differences() {
        // A non-equilibrium state of a two-segment rod (arbitrary curvatures, start point
        // and multipliers): the energy depends on the curvature unknowns only.
        let st = Stiffness::Tanh {
            d0: 1.0,
            d1: 0.4,
            s0: 0.3,
            s1: 0.8,
            gamma: 12.0,
        };
        let cells = 10;
        let gauge = Gauge {
            reference: (0..4 * cells).map(|a| (0.7 * a as f64).sin()).collect(),
            slope: None,
            pin: None,
        };
        let model = EnclosedModel::new(1.0, 1.3, cells, &st, gauge).unwrap();
        let z: Vec<f64> = (0..Confinement::dim(&model))
            .map(|a| 1.5 * (1.3 * a as f64 + 0.4).sin())
            .collect();
        let g = Confinement::energy_gradient(&model, &z).unwrap();
        let fd = rodloop_continuation::fd_jacobian(
            |v: &DVector<f64>| -> Result<DVector<f64>, SolverError> {
                Ok(DVector::from_element(
                    1,
                    Confinement::energy(&model, v.as_slice())?,
                ))
            },
            &DVector::from_column_slice(&z),
        )
        .unwrap();
        let err = (0..z.len())
            .map(|a| (g[a] - fd[(0, a)]).abs())
            .fold(0.0, f64::max);
        assert!(err < 1e-8 * g.amax(), "∂E/∂z: {err}");
        assert!(g.rows(4 * cells, z.len() - 4 * cells).amax() == 0.0);
        for p in [Param::Lbar, Param::D1, Param::Gamma, Param::S0, Param::S1] {
            let v = Confinement::param(&model, p).unwrap();
            let an = Confinement::energy_dparam(&model, &z, p).unwrap();
            let fd = rodloop_continuation::fd_dparam(
                |q| -> Result<DVector<f64>, SolverError> {
                    let m = Confinement::with_param(&model, p, q)?;
                    Ok(DVector::from_element(1, Confinement::energy(&m, &z)?))
                },
                v,
            )
            .unwrap()[0];
            assert!(
                (an - fd).abs() <= 1e-7 * fd.abs().max(1e-3),
                "∂E/∂{p}: analytic {an}, finite differences {fd}"
            );
        }
    }
}
