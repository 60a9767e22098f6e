//! Critical lengths as curves in a scene parameter: two-parameter continuation of a Maxwell
//! point (paper Sec. 5, Figs. 8–10: how the exchange lengths `L̄_cr` of the lowest branch move
//! with the stiffness ratio `D1/D0` of Eq. (51)).
//!
//! A Maxwell point of branches `a` and `b` at the scene parameter `θ` is a length `L̄` at which
//! both equilibria exist and have the same energy. With the two discretised KKT systems
//! `F_a(z_a; L̄, θ) = 0`, `F_b(z_b; L̄, θ) = 0` ([`Confinement::residual`]) the augmented
//! system in `x = (z_a, z_b, L̄)` is
//!
//! ```text
//! G(x; θ) = ( F_a(z_a; L̄, θ),  F_b(z_b; L̄, θ),  E_a(z_a; L̄, θ) − E_b(z_b; L̄, θ) ) = 0,
//! ```
//!
//! energies `E R/(π D0)`. [`MaxwellProblem`] implements it as a
//! [`rodloop_continuation::Problem`] in `p` on the parameter's axis ([`Param::axis`]: `ln θ`
//! for `d1` and `gamma`, so that decades come at even steps; `θ` for `s0`, `s1`), with the
//! analytic derivatives
//!
//! * `∂E/∂z = (w_a D_a κ_a, 0)·R/(πD0)` (the energy gradient; zero on the multipliers),
//! * `∂E/∂L̄ = E/L̄` (every quadrature weight `w_a = h_c/2` is proportional to `L̄` at fixed
//!   `σ = s/L`, the profile being a function of `σ`),
//! * `∂E/∂θ = Σ_a ½ w_a (∂D/∂θ)(σ_a) (κ_a² + 1/R²)·R/(πD0)` (Eq. (2) with Eq. (51)),
//!
//! and a factorisation by bordering ([`Factorization`]): the Jacobian
//! `[[J_a, 0, F_a,L̄], [0, J_b, F_b,L̄], [∇E_aᵀ, −∇E_bᵀ, E_a,L̄ − E_b,L̄]]` is solved with the
//! two models' own factorisations ([`Confinement::Factor`], `O(N)` blocks for the surface
//! model) and one scalar Schur
//! complement (Govaerts 2000, ch. 3).
//!
//! [`trace_phase`](crate::phase::trace_phase) seeds every exchange of the uniform rod that lies in the scene's range just
//! below `D1/D0 = 1` (at `1 − 10⁻³`, where the arclength-shift symmetry of the uniform rod is
//! broken: the lowest placement of the soft segment is chosen among shifted exact loops),
//! solves `E_a = E_b` there by the exchange locator on re-solved equilibria, and continues the
//! Maxwell point in the parameter down to the lower end of the requested range and up
//! towards `D1/D0 = 1`, where the limit is extrapolated and compared with the uniform rod.
//! Along the way the stability index of both states is monitored: a curve ends where one of
//! them stops being a local minimum (a lower, asymmetric state then exists, so the Maxwell
//! point no longer separates lowest branches), at a fold in `θ` (a branch ceases to exist),
//! or when the continuation fails; the reason is returned with the curve.
//!
//! Every reported `L̄_cr` carries an error estimate from a companion Maxwell point at half the
//! resolution (`|L̄_N − L̄_{N/2}|/15`, the scheme converging like `h⁴`; `High`: `N` and `2N`,
//! Richardson-extrapolated), like the rest of rodloop.

use nalgebra::{DMatrix, DVector};
use rodloop_continuation::axis::Axis;
use rodloop_continuation::{DenseLu, Factorization, Problem};
use rodloop_solver::{
    Confinement, Equilibrium, Globalization, Param, SolveOptions, SolverError, SurfaceSolve,
};

/// Stability tolerance of the monitored indices (eigenvalues of the constrained Hessian
/// below `−INDEX_TOL` in the model's energy metric count as negative). Small: next to the
/// uniform rod the shift mode has an eigenvalue of order `10⁻⁴ (1 − D1/D0)²`-ish (measured
/// `±9·10⁻⁸` at `D1/D0 = 0.999`), and its sign decides which placement is the minimum.
pub const INDEX_TOL: f64 = 1e-10;

/// Distance below (or above) `D1/D0 = 1` at which the exchanges of the uniform rod are
/// seeded. Closer to 1 the placement of the soft segment is selected only at second order in
/// `1 − D1/D0` and energy minimisation does not find it reliably (measured: most starts fail
/// at 0.999, 0.99 and, for η = 2, 3 near L̄ = 2.43, at 0.95; all branches work at 0.9).
pub const SEED_OFFSET: f64 = 0.1;

/// Distances `t = |1 − D1/D0|` of the Maxwell points used to extrapolate the limit
/// `D1/D0 → 1`: quadratic in `t` through the three smallest, checked against the quadratic
/// through the three largest.
pub const LIMIT_OFFSETS: [f64; 4] = [1e-3, 2e-3, 4e-3, 8e-3];

/// Energy `E R/(π D0)` of the KKT state `z` (Eq. (2), two-point Gauss quadrature).
pub fn energy<M: Confinement>(model: &M, z: &[f64]) -> Result<f64, SolverError> {
    model.energy(z)
}

/// `∂E/∂z` of [`energy`] ([`Confinement::energy_gradient`]): `w_a D_a κ_a R/(πD0)` on the
/// curvatures, zero on the multipliers.
pub fn energy_gradient<M: Confinement>(model: &M, z: &[f64]) -> Result<DVector<f64>, SolverError> {
    model.energy_gradient(z)
}

/// `∂E/∂θ` of [`energy`] at fixed `z` ([`Confinement::energy_dparam`]): `E/L̄` for `lbar`
/// (the weights scale with `L̄`), and `Σ_a ½ w_a (∂D/∂θ)(σ_a)(κ_a² + 1/R²) R/(πD0)` for a
/// stiffness parameter.
pub fn energy_dparam<M: Confinement>(model: &M, z: &[f64], p: Param) -> Result<f64, SolverError> {
    model.energy_dparam(z, p)
}

/// Assemble `x = (z_a, z_b, L̄)`, the unknowns of a [`MaxwellProblem`].
pub fn join(za: &[f64], zb: &[f64], lbar: f64) -> DVector<f64> {
    let mut v = Vec::with_capacity(za.len() + zb.len() + 1);
    v.extend_from_slice(za);
    v.extend_from_slice(zb);
    v.push(lbar);
    DVector::from_vec(v)
}

/// The augmented system of a Maxwell point (see the module docs) as a continuation problem
/// in `p = q(θ)` on the parameter's axis ([`Param::axis`]: `ln θ` for `d1` and `gamma`, `θ`
/// for `s0` and `s1`).
#[derive(Clone, Debug)]
pub struct MaxwellProblem<M> {
    a: M,
    b: M,
    param: Param,
    axis: Axis,
}

impl<M: SurfaceSolve> MaxwellProblem<M> {
    /// The Maxwell point of the states of models `a` and `b` (their own resolutions, same
    /// stiffness profile), continued in `param`. Fails for `lbar` (the length is an unknown)
    /// and for a parameter the profile does not have.
    pub fn new(a: M, b: M, param: Param) -> Result<Self, SolverError> {
        if param == Param::Lbar {
            return Err(SolverError::InvalidInput(
                "a Maxwell point is continued in a stiffness parameter (d1, gamma, s0, s1); \
                 lbar is one of its unknowns"
                    .into(),
            ));
        }
        a.param(param)?;
        b.param(param)?;
        Ok(Self {
            a,
            b,
            param,
            axis: param.axis(),
        })
    }

    /// The continued parameter.
    pub fn param(&self) -> Param {
        self.param
    }

    /// `θ` of the continuation variable `p`.
    pub fn theta(&self, p: f64) -> f64 {
        self.axis.value(p)
    }

    /// The continuation variable `p` of `θ` (`ln θ` on a log axis).
    pub fn p_of(&self, theta: f64) -> f64 {
        self.axis.coordinate(theta)
    }

    /// Sizes `(dim z_a, dim z_b)`.
    pub fn dims(&self) -> (usize, usize) {
        (self.a.dim(), self.b.dim())
    }

    /// The models of the two branches (cells, mesh).
    pub fn models(&self) -> (&M, &M) {
        (&self.a, &self.b)
    }

    /// Split `x = (z_a, z_b, L̄)`.
    pub fn split<'x>(&self, x: &'x [f64]) -> Result<(&'x [f64], &'x [f64], f64), SolverError> {
        let (na, nb) = self.dims();
        if x.len() != na + nb + 1 {
            return Err(SolverError::WrongLength {
                expected: na + nb + 1,
                found: x.len(),
            });
        }
        Ok((&x[..na], &x[na..na + nb], x[na + nb]))
    }

    /// The two models at length `lbar` and continuation variable `p`.
    pub fn models_at(&self, lbar: f64, p: f64) -> Result<(M, M), SolverError> {
        let theta = self.theta(p);
        let at = |m: &M| -> Result<M, SolverError> {
            m.with_param(Param::Lbar, lbar)?
                .with_param(self.param, theta)
        };
        Ok((at(&self.a)?, at(&self.b)?))
    }

    /// Energies `(E_a, E_b)` at `(x, p)`.
    pub fn energies(&self, x: &DVector<f64>, p: f64) -> Result<(f64, f64), SolverError> {
        let (za, zb, lbar) = self.split(x.as_slice())?;
        let (ma, mb) = self.models_at(lbar, p)?;
        Ok((energy(&ma, za)?, energy(&mb, zb)?))
    }

    /// Stability indices `(index_a, index_b)` at `(x, p)` (tolerance [`INDEX_TOL`]).
    pub fn indices(&self, x: &DVector<f64>, p: f64) -> Result<(usize, usize), SolverError> {
        let (za, zb, lbar) = self.split(x.as_slice())?;
        let (ma, mb) = self.models_at(lbar, p)?;
        Ok((ma.index(za, INDEX_TOL)?, mb.index(zb, INDEX_TOL)?))
    }

    /// `(d(E_a − E_b)/dL̄, sign det J_a, sign det J_b)` at `(x, p)`. The first is the slope of
    /// the energy difference along the two equilibrium branches at fixed `θ` (states
    /// re-solved as `L̄` moves), which is the Schur complement `d − cᵀA⁻¹u` of the bordered
    /// factorisation: positive when branch `a` is the lower one below the crossing, zero
    /// where the two energy curves touch (a fold of the Maxwell curve in `θ`). A change of a
    /// determinant sign means the state itself passed a fold or branch point in `L̄`.
    pub fn crossing_slope(&self, x: &DVector<f64>, p: f64) -> Result<(f64, f64, f64), SolverError> {
        let (za, zb, lbar) = self.split(x.as_slice())?;
        let (ma, mb) = self.models_at(lbar, p)?;
        let slope_of = |m: &M, z: &[f64]| -> Result<(f64, f64), SolverError> {
            let f = m.factorize(z, 0.0)?;
            let dz = Factorization::solve(&f, &m.dparam(z, Param::Lbar)?)
                .ok_or(SolverError::SingularJacobian { iteration: 0 })?;
            // dE/dL̄ = ∂E/∂L̄ − ∇E·J⁻¹F_L̄.
            let de = energy_dparam(m, z, Param::Lbar)? - energy_gradient(m, z)?.dot(&dz);
            Ok((de, f.det_sign()))
        };
        let (da, sa) = slope_of(&ma, za)?;
        let (db, sb) = slope_of(&mb, zb)?;
        Ok((da - db, sa, sb))
    }

    /// The equilibria of the two branches at `(x, p)` (re-solved by Newton from `x`).
    pub fn equilibria(
        &self,
        x: &DVector<f64>,
        p: f64,
        opts: &SolveOptions,
    ) -> Result<(Equilibrium, Equilibrium), SolverError> {
        let (za, zb, lbar) = self.split(x.as_slice())?;
        let (ma, mb) = self.models_at(lbar, p)?;
        let newton = SolveOptions {
            globalization: Globalization::Newton,
            ..opts.clone()
        };
        Ok((
            ma.solve_from_state(za.to_vec(), &newton)?,
            mb.solve_from_state(zb.to_vec(), &newton)?,
        ))
    }

    /// The same Maxwell problem at other resolutions (`cells_a`, `cells_b` cells, same mesh
    /// map), with a first guess of the state: each curvature profile resampled
    /// ([`Equilibrium::resample`]), the closure multipliers (the resolution-independent
    /// moment) carried over. Newton on the augmented system polishes it.
    pub fn resampled(
        &self,
        x: &DVector<f64>,
        p: f64,
        cells_a: usize,
        cells_b: usize,
        opts: &SolveOptions,
    ) -> Result<(MaxwellProblem<M>, DVector<f64>), SolverError> {
        let (ea, eb) = self.equilibria(x, p, opts)?;
        let lbar = self.split(x.as_slice())?.2;
        let (at_a, at_b) = self.models_at(lbar, p)?;
        let redo = |eq: &Equilibrium, at: &M, cells: usize| -> Result<(M, Vec<f64>), SolverError> {
            let m = at.with_cells(cells)?;
            if m.dim() != 2 * cells + 3 {
                return Err(SolverError::InvalidInput(
                    "resampling a model with a phase condition".into(),
                ));
            }
            let mut z = eq.resample(cells)?;
            z.extend_from_slice(&eq.multiplier());
            Ok((m, z))
        };
        let (ma, za) = redo(&ea, &at_a, cells_a)?;
        let (mb, zb) = redo(&eb, &at_b, cells_b)?;
        let problem = MaxwellProblem::new(ma, mb, self.param)?;
        Ok((problem, join(&za, &zb, lbar)))
    }
}

impl<M: SurfaceSolve> Problem for MaxwellProblem<M> {
    type Error = SolverError;

    fn dim(&self) -> usize {
        self.a.dim() + self.b.dim() + 1
    }

    fn residual(&self, x: &DVector<f64>, p: f64) -> Result<DVector<f64>, SolverError> {
        let (za, zb, lbar) = self.split(x.as_slice())?;
        let (ma, mb) = self.models_at(lbar, p)?;
        let fa = ma.residual(za)?;
        let fb = mb.residual(zb)?;
        let mut out = DVector::zeros(self.dim());
        out.rows_mut(0, fa.len()).copy_from(&fa);
        out.rows_mut(fa.len(), fb.len()).copy_from(&fb);
        out[fa.len() + fb.len()] = energy(&ma, za)? - energy(&mb, zb)?;
        Ok(out)
    }

    fn jacobian(&self, x: &DVector<f64>, p: f64) -> Result<DMatrix<f64>, SolverError> {
        let (za, zb, lbar) = self.split(x.as_slice())?;
        let (ma, mb) = self.models_at(lbar, p)?;
        let (na, nb) = self.dims();
        let n = na + nb;
        let mut j = DMatrix::zeros(n + 1, n + 1);
        j.view_mut((0, 0), (na, na)).copy_from(&ma.jacobian(za)?);
        j.view_mut((na, na), (nb, nb)).copy_from(&mb.jacobian(zb)?);
        j.view_mut((0, n), (na, 1))
            .copy_from(&ma.dparam(za, Param::Lbar)?);
        j.view_mut((na, n), (nb, 1))
            .copy_from(&mb.dparam(zb, Param::Lbar)?);
        let ga = energy_gradient(&ma, za)?;
        let gb = energy_gradient(&mb, zb)?;
        j.view_mut((n, 0), (1, na)).copy_from(&ga.transpose());
        j.view_mut((n, na), (1, nb)).copy_from(&(-gb.transpose()));
        j[(n, n)] = energy_dparam(&ma, za, Param::Lbar)? - energy_dparam(&mb, zb, Param::Lbar)?;
        Ok(j)
    }

    fn dparam(&self, x: &DVector<f64>, p: f64) -> Result<DVector<f64>, SolverError> {
        let (za, zb, lbar) = self.split(x.as_slice())?;
        let (ma, mb) = self.models_at(lbar, p)?;
        let (na, nb) = self.dims();
        let mut out = DVector::zeros(na + nb + 1);
        out.rows_mut(0, na).copy_from(&ma.dparam(za, self.param)?);
        out.rows_mut(na, nb).copy_from(&mb.dparam(zb, self.param)?);
        out[na + nb] = energy_dparam(&ma, za, self.param)? - energy_dparam(&mb, zb, self.param)?;
        // d/dq = (dθ/dq) d/dθ (θ d/dθ on a log axis).
        Ok(out * self.axis.derivative(p))
    }

    fn factorize(
        &self,
        x: &DVector<f64>,
        p: f64,
    ) -> Result<Box<dyn Factorization + '_>, SolverError> {
        match Bordered::new(self, x, p) {
            Ok(f) => Ok(Box::new(f)),
            // A singular pivot block or Schur complement: the dense matrix (the
            // continuation's bordered solves then work where block elimination cannot).
            Err(SolverError::SingularJacobian { .. }) => {
                Ok(Box::new(DenseLu::new(self.jacobian(x, p)?)))
            }
            Err(e) => Err(e),
        }
    }
}

/// The augmented Jacobian `[[A, u], [cᵀ, d]]`, `A = diag(J_a, J_b)`, factorised by
/// bordering: `A` by the two models' block factorisations, then the scalar Schur complement
/// `s = d − cᵀA⁻¹u`; `det = det J_a · det J_b · s`.
struct Bordered<F> {
    fa: F,
    fb: F,
    na: usize,
    nb: usize,
    u: DVector<f64>,
    c: DVector<f64>,
    d: f64,
    /// `A⁻¹u`.
    ainv_u: DVector<f64>,
    schur: f64,
}

impl<F: Factorization> Bordered<F> {
    fn new<M: SurfaceSolve<Factor = F>>(
        pb: &MaxwellProblem<M>,
        x: &DVector<f64>,
        p: f64,
    ) -> Result<Self, SolverError> {
        let (za, zb, lbar) = pb.split(x.as_slice())?;
        let (ma, mb) = pb.models_at(lbar, p)?;
        let (na, nb) = pb.dims();
        let fa = ma.factorize(za, 0.0)?;
        let fb = mb.factorize(zb, 0.0)?;
        let mut u = DVector::zeros(na + nb);
        u.rows_mut(0, na).copy_from(&ma.dparam(za, Param::Lbar)?);
        u.rows_mut(na, nb).copy_from(&mb.dparam(zb, Param::Lbar)?);
        let mut c = DVector::zeros(na + nb);
        c.rows_mut(0, na).copy_from(&energy_gradient(&ma, za)?);
        c.rows_mut(na, nb).copy_from(&(-energy_gradient(&mb, zb)?));
        let d = energy_dparam(&ma, za, Param::Lbar)? - energy_dparam(&mb, zb, Param::Lbar)?;
        let mut me = Self {
            fa,
            fb,
            na,
            nb,
            u,
            c,
            d,
            ainv_u: DVector::zeros(0),
            schur: 0.0,
        };
        let ainv_u = me
            .solve_a(&me.u)
            .ok_or(SolverError::SingularJacobian { iteration: 0 })?;
        let schur = me.d - me.c.dot(&ainv_u);
        let scale = me.d.abs() + me.c.norm() * ainv_u.norm();
        if !schur.is_finite() || schur.abs() <= 1e-14 * scale {
            return Err(SolverError::SingularJacobian { iteration: 0 });
        }
        me.ainv_u = ainv_u;
        me.schur = schur;
        Ok(me)
    }

    fn solve_a(&self, b: &DVector<f64>) -> Option<DVector<f64>> {
        let xa = Factorization::solve(&self.fa, &b.rows(0, self.na).into_owned())?;
        let xb = Factorization::solve(&self.fb, &b.rows(self.na, self.nb).into_owned())?;
        let mut out = DVector::zeros(self.na + self.nb);
        out.rows_mut(0, self.na).copy_from(&xa);
        out.rows_mut(self.na, self.nb).copy_from(&xb);
        Some(out)
    }
}

impl<F: Factorization> Factorization for Bordered<F> {
    fn solve(&self, b: &DVector<f64>) -> Option<DVector<f64>> {
        let n = self.na + self.nb;
        if b.len() != n + 1 {
            return None;
        }
        let x1 = self.solve_a(&b.rows(0, n).into_owned())?;
        let y = (b[n] - self.c.dot(&x1)) / self.schur;
        let x = x1 - &self.ainv_u * y;
        let out = x.insert_row(n, y);
        out.iter().all(|v| v.is_finite()).then_some(out)
    }

    fn apply(&self, v: &DVector<f64>) -> DVector<f64> {
        let n = self.na + self.nb;
        if v.len() != n + 1 {
            return DVector::from_element(n + 1, f64::NAN);
        }
        let ya = Factorization::apply(&self.fa, &v.rows(0, self.na).into_owned());
        let yb = Factorization::apply(&self.fb, &v.rows(self.na, self.nb).into_owned());
        let mut out = DVector::zeros(n + 1);
        out.rows_mut(0, self.na).copy_from(&ya);
        out.rows_mut(self.na, self.nb).copy_from(&yb);
        for i in 0..n {
            out[i] += self.u[i] * v[n];
        }
        out[n] = self.c.dot(&v.rows(0, n)) + self.d * v[n];
        out
    }

    fn det_sign(&self) -> f64 {
        self.fa.det_sign() * self.fb.det_sign() * self.schur.signum()
    }

    fn log_abs_det(&self) -> f64 {
        self.fa.log_abs_det() + self.fb.log_abs_det() + self.schur.abs().ln()
    }
}

#[cfg(test)]
mod tests;
