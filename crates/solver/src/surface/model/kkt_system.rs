//! The KKT system of [`SurfaceModel`]: the unknowns `z = (κ, μ, ν)`, the residual
//! `F(z)` (stationarity of the Lagrangian, closure, phase condition), its Jacobian, its
//! derivatives in the named parameters (`∂F/∂L̄`, `∂F/∂θ` of the stiffness) and the scales
//! of its convergence norm. The energy, the holonomy and their derivatives, which it is
//! built from, are in the parent module.

use super::*;

impl SurfaceModel {
    /// Split a KKT vector `z = (κ, μ, ν)` into its parts (`ν = 0` without phase condition).
    pub fn split<'a>(&self, z: &'a [f64]) -> Result<(&'a [f64], [f64; 3], f64), SolverError> {
        check_len(z.len(), self.dim())?;
        let n = self.n_kappa();
        let mu = [z[n], z[n + 1], z[n + 2]];
        let nu = if self.phase.is_some() { z[n + 3] } else { 0.0 };
        Ok((&z[..n], mu, nu))
    }

    /// KKT residual `F(z) = (∇E − ∇cᵀμ − ν∇φ, −c, −φ)`.
    pub fn kkt_residual(&self, z: &[f64]) -> Result<DVector<f64>, SolverError> {
        let (kappa, mu, nu) = self.split(z)?;
        self.check_kappa(kappa)?;
        let ch = self.chain1(kappa);
        Ok(self.kkt_residual_from(&ch, kappa, &V3::from(mu), nu))
    }

    /// The closure rows of the KKT residual, `F_{n..n+3}(z) = −c(κ)` (`n` = [`Self::n_kappa`]),
    /// equal to the bit to those of [`Self::kkt_residual`] (the same cell propagators,
    /// [`crate::frame::exp_value`], multiplied in the same order), with the same errors, at a
    /// fraction of its cost (no derivatives, no adjoint sweep): where these rows alone give a
    /// merit above a bound, the whole residual does (a line search rejects its trial from
    /// them, [`mod@crate::solve`]).
    pub fn kkt_closure_residual(&self, z: &[f64]) -> Result<[f64; 3], SolverError> {
        let (kappa, _, _) = self.split(z)?;
        self.check_kappa(kappa)?;
        let mut acc = M3::identity();
        for c in 0..self.cells {
            let (w0, v1, v2) = self.cell_vectors(self.cell_length(c));
            let w = w0 + v1 * kappa[2 * c] + v2 * kappa[2 * c + 1];
            acc = exp_value(&w) * acc;
        }
        let v = Closure::of(&acc).value;
        Ok([-v[0], -v[1], -v[2]])
    }

    fn kkt_residual_from(&self, ch: &Chain, kappa: &[f64], mu: &V3, nu: f64) -> DVector<f64> {
        let n = self.n_kappa();
        let mut f = DVector::zeros(self.dim());
        let closure = Closure::of(&ch.prefix[self.cells]);
        let m = closure.first(mu);
        for c in 0..self.cells {
            let w = self.cell_weight(c);
            let pk = ch.prefix[c] * (m * ch.suffix[c]);
            for i in 0..2 {
                let a = 2 * c + i;
                // ∂(μ·c)/∂κ_a = −½ tr(M S_c ∂E_c P_c) = −½ tr(∂E_c P_c M S_c).
                let dmuc = -0.5 * tr_prod(&ch.de[c][i], &pk);
                f[a] = w * self.d_gauss[a] * kappa[a] - dmuc;
            }
        }
        for k in 0..3 {
            f[n + k] = -closure.value[k];
        }
        if let Some(ph) = &self.phase {
            for (a, g) in ph.gradient().iter().enumerate() {
                f[a] -= nu * g;
            }
            f[n + 3] = -ph.value(kappa);
        }
        f
    }

    /// KKT Jacobian `[[∇²ℒ, −∇cᵀ, −∇φ], [−∇c, 0, 0], [−∇φᵀ, 0, 0]]` (symmetric).
    pub fn kkt_jacobian(&self, z: &[f64]) -> Result<DMatrix<f64>, SolverError> {
        let (kappa, mu, _) = self.split(z)?;
        self.check_kappa(kappa)?;
        let ch = self.chain(kappa);
        Ok(self.kkt_jacobian_from(&ch, &V3::from(mu)))
    }

    fn kkt_jacobian_from(&self, ch: &Chain, mu: &V3) -> DMatrix<f64> {
        let n = self.n_kappa();
        let dim = self.dim();
        let mut jac = DMatrix::zeros(dim, dim);
        jac.view_mut((0, 0), (n, n))
            .copy_from(&self.lagrangian_hessian_from(ch, mu));
        let cj = self.closure_jacobian_from(ch);
        for a in 0..n {
            for k in 0..3 {
                jac[(a, n + k)] = -cj[(k, a)];
                jac[(n + k, a)] = -cj[(k, a)];
            }
        }
        if let Some(ph) = &self.phase {
            for (a, g) in ph.gradient().iter().enumerate() {
                jac[(a, n + 3)] = -g;
                jac[(n + 3, a)] = -g;
            }
        }
        jac
    }

    /// Residual and Jacobian together (one pass over the cells).
    pub fn kkt_residual_and_jacobian(
        &self,
        z: &[f64],
    ) -> Result<(DVector<f64>, DMatrix<f64>), SolverError> {
        let (kappa, mu, nu) = self.split(z)?;
        self.check_kappa(kappa)?;
        let ch = self.chain(kappa);
        let mu = V3::from(mu);
        Ok((
            self.kkt_residual_from(&ch, kappa, &mu, nu),
            self.kkt_jacobian_from(&ch, &mu),
        ))
    }

    /// `∂F/∂L̄` at fixed `z`: `h = 2πR L̄/N` changes, the profile and the phase condition are
    /// held fixed in `σ = s/L`. `∂∇E/∂L̄ = ∇E/L̄`; the closure terms are differentiated
    /// through the cell propagators with a jet in `(κ_c1, κ_c2, h)`.
    pub fn kkt_dlbar(&self, z: &[f64]) -> Result<DVector<f64>, SolverError> {
        let (kappa, mu, _) = self.split(z)?;
        self.check_kappa(kappa)?;
        let n = self.cells;
        let r = self.radius;
        let avec = V3::new(0.0, 0.0, -1.0);
        let bvec = V3::new(0.0, -1.0 / r, 0.0);
        let cvec = V3::new(-1.0 / r, 0.0, 0.0);
        let mut e = vec![M3::zeros(); n];
        let mut dk = vec![[M3::zeros(); 2]; n]; // ∂E_c/∂κ_ci
        let mut dh = vec![M3::zeros(); n]; // ∂E_c/∂L̄ (through h_c = σ-width · 2πR L̄)
        let mut dkh = vec![[M3::zeros(); 2]; n]; // ∂²E_c/∂κ_ci∂L̄
        for c in 0..n {
            let h = self.cell_length(c);
            let dh_dlbar = h / self.lbar;
            let (w0, v1, v2) = self.cell_vectors(h);
            let (k1, k2) = (kappa[2 * c], kappa[2 * c + 1]);
            let w = w0 + v1 * k1 + v2 * k2;
            let wh = avec * (0.5 * (k1 + k2)) + bvec + cvec * (2.0 * MAGNUS_C * h * (k2 - k1));
            let w1h = avec * 0.5 - cvec * (2.0 * MAGNUS_C * h);
            let w2h = avec * 0.5 + cvec * (2.0 * MAGNUS_C * h);
            let whh = cvec * (2.0 * MAGNUS_C * (k2 - k1));
            let z3 = V3::zeros();
            let wij = [[z3, z3, w1h], [z3, z3, w2h], [w1h, w2h, whh]];
            let mut d = [M3::zeros(); 3];
            let dkhc = &mut dkh[c];
            exp_jet_last_into::<3>(&w, &[v1, v2, wh], &wij, &mut e[c], &mut d, |i, m| {
                if i < 2 {
                    dkhc[i] = m * dh_dlbar;
                }
            });
            dk[c] = [d[0], d[1]];
            dh[c] = d[2] * dh_dlbar;
        }
        let (prefix, suffix) = prefix_suffix(&e);
        // ∂_h P_c and ∂_h S_c by the product rule along the chain.
        let mut dprefix = vec![M3::zeros(); n + 1];
        for c in 0..n {
            dprefix[c + 1] = dh[c] * prefix[c] + e[c] * dprefix[c];
        }
        let mut dsuffix = vec![M3::zeros(); n];
        for c in (1..n).rev() {
            dsuffix[c - 1] = dsuffix[c] * e[c] + suffix[c] * dh[c];
        }
        let mu = V3::from(mu);
        let hol = prefix[n];
        let cl = Closure::of(&hol);
        let m = cl.first(&mu);
        let kxh = cl.second(&mu) * vee_skew(&(dprefix[n] * hol.transpose()));
        let mut out = DVector::zeros(self.dim());
        for c in 0..n {
            let wgt = self.cell_weight(c);
            for i in 0..2 {
                let a = 2 * c + i;
                // ∂_a∂_h H = ∂_hS_c ∂_aE_c P_c + S_c ∂_{ah}E_c P_c + S_c ∂_aE_c ∂_hP_c.
                let d2h = dsuffix[c] * dk[c][i] * prefix[c]
                    + suffix[c] * dkh[c][i] * prefix[c]
                    + suffix[c] * dk[c][i] * dprefix[c];
                // ∂_h∂_a(μ·c) = −½ tr(M ∂_a∂_h H) + Ξ_aᵀ K Ξ_h.
                let xa = vee_skew(&(suffix[c] * dk[c][i] * prefix[c] * hol.transpose()));
                let d2f = -0.5 * tr_prod(&m, &d2h) + xa.dot(&kxh);
                // F_a = ∇E_a − ∂_a(μ·c) − ν∂_aφ; ∇E_a ∝ h.
                out[a] = wgt * self.d_gauss[a] * kappa[a] / self.lbar - d2f;
            }
        }
        let dc = vee_skew(&dprefix[n]) * cl.s + cl.v * (cl.s1 * dprefix[n].trace());
        let nk = self.n_kappa();
        for k in 0..3 {
            out[nk + k] = -dc[k];
        }
        Ok(out)
    }

    /// The value of a named parameter ([`crate::Param`]).
    pub fn param(&self, p: crate::Param) -> Result<f64, SolverError> {
        match p {
            crate::Param::Lbar => Ok(self.lbar),
            _ => self.stiffness.kind().param(p),
        }
    }

    /// The same model (same mesh and phase condition) with a named parameter changed. A
    /// model with a phase condition must stay uniform (the condition fixes a symmetry that a
    /// non-uniform rod does not have).
    pub fn with_param(&self, p: crate::Param, value: f64) -> Result<Self, SolverError> {
        if p == crate::Param::Lbar {
            return self.with_lbar(value);
        }
        if !value.is_finite() {
            return Err(SolverError::InvalidInput(format!(
                "parameter {} must be finite (got {value})",
                p.name()
            )));
        }
        let kind = self.stiffness.kind().with_param(p, value)?;
        if self.phase.is_some() && !kind.is_uniform() {
            return Err(SolverError::InvalidInput(
                "a model with a phase condition (uniform rod) cannot be continued into a non-uniform one; drop the phase condition first".into(),
            ));
        }
        let mut m = self.clone();
        m.stiffness = kind.validate()?;
        m.d_gauss = (0..2 * m.cells)
            .map(|a| m.stiffness.eval(m.sigma_of(a)).d)
            .collect();
        Ok(m)
    }

    /// `∂F/∂θ` at fixed `z` for a named parameter: [`SurfaceModel::kkt_dlbar`] for `lbar`;
    /// for a stiffness parameter only the energy gradient depends on it,
    /// `∂F_a/∂θ = w_a (∂D/∂θ)(σ_a) κ_a`.
    pub fn kkt_dparam(&self, z: &[f64], p: crate::Param) -> Result<DVector<f64>, SolverError> {
        if p == crate::Param::Lbar {
            return self.kkt_dlbar(z);
        }
        let (kappa, _, _) = self.split(z)?;
        self.check_kappa(kappa)?;
        let kind = self.stiffness.kind();
        let mut out = DVector::zeros(self.dim());
        for (a, k) in kappa.iter().enumerate() {
            out[a] = self.cell_weight(a / 2) * kind.dparam(p, self.sigma_of(a))? * k;
        }
        Ok(out)
    }

    /// Resolution-independent norm of a KKT residual: the root-mean-square of the
    /// stationarity density `F_a/(h/2)` over the loop in units of `D0/R`, combined with the
    /// closure residual `|c|` and the phase residual.
    pub fn residual_norm(&self, f: &DVector<f64>) -> f64 {
        self.residual_scales()
            .iter()
            .zip(f.iter())
            .map(|(s, v)| s * v * v)
            .sum::<f64>()
            .sqrt()
    }

    /// Weights `s_i` of the squared residual norm `Σ s_i F_i²` (see [`Self::residual_norm`]).
    pub fn residual_scales(&self) -> Vec<f64> {
        let n = self.n_kappa();
        let unit = self.radius / self.stiffness.kind().reference();
        let mut s: Vec<f64> = (0..n)
            .map(|a| {
                let w = self.cell_weight(a / 2);
                unit * unit / (w * w) / n as f64
            })
            .collect();
        s.extend(std::iter::repeat_n(1.0, self.n_multipliers()));
        s
    }
}
