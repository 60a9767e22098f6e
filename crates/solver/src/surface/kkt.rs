//! Linear algebra of the KKT system in `O(N)`: a block-tridiagonal ("lifted") form of the
//! Newton matrix, its block `LDLᵀ` factorisation, solves, determinant sign and inertia.
//!
//! # Why the dense matrix is never formed
//!
//! The closure `c(κ) = c(H)` (see [`crate::model`]) with the holonomy `H = E_{N−1}⋯E_0` couples every cell
//! with every other, so the Hessian of `ℒ = E − μ·c` in the curvature unknowns alone is
//! dense. Introducing the first variation of the prefix frames as auxiliary unknowns makes
//! it local, as multiple shooting does for boundary-value problems: with `P_c = E_{c−1}⋯E_0`
//! and `δP_c = hat(ξ_c) P_c`, the linearised recursion is
//!
//! ```text
//! ξ_{c+1} = E_c ξ_c + Σ_i a_ci δκ_ci,   a_ci = vee(∂_iE_c E_cᵀ),   ξ_0 = 0,
//! δc = J ξ_N,                            (J the derivative of c(H) along δH = hat(ξ)H),
//! ```
//!
//! and, with `D(μ·c)[X] = −½ tr(M X)` and `D²(μ·c)[hat(ξ)H, hat(ζ)H] = ξᵀKζ` (for the
//! quaternion closure of [`crate::model`]; `M = hat(μ)`, `K = 0` for `c = vee(skew H)`),
//! the second variation of `f = −μ·c` is a sum of cell terms plus one term in `ξ_N`,
//! `Σ_c [δκ_cᵀ A_c δκ_c + 2 δκ_cᵀ B_c ξ_c] − ξ_Nᵀ K ξ_N` with
//! `A_c,ij = ½ tr(M S_c ∂_ijE_c P_c)` and the rows `B_c,i = −vee(skew(P_c M S_c ∂_iE_c))`
//! (`S_c = E_{N−1}⋯E_{c+1}`).
//! The Newton matrix of [`SurfaceModel::kkt_jacobian`] is exactly the Schur complement of
//! the symmetric block-tridiagonal matrix in the unknowns
//!
//! ```text
//! [δκ_0] [η_1 ξ_1 δκ_1] … [η_{N−1} ξ_{N−1} δκ_{N−1}] [η_N ξ_N δμ]   (+ δν, a border)
//! ```
//!
//! (`η_c` the multipliers of the recursion) onto `(δκ, δμ, δν)`: eliminating the pairs
//! `(ξ_c, η_c)` reproduces the reduced Hessian `Zᵀ∇²ℒZ` and the closure Jacobian. So Newton
//! steps computed here are the same steps as with the dense matrix, at `O(N)` cost.
//!
//! # Inertia (Sylvester / Haynsworth)
//!
//! Each eliminated pair contributes inertia `(3, 3, 0)` (its block `[[0, −I], [−I, 0]]`
//! after the previous eliminations is `[[−S, −I], [−I, 0]]`, always nonsingular). So the
//! number of negative eigenvalues of the dense Newton matrix is that of the lifted matrix
//! minus `3N`, and, with `m` equality constraints of full rank, the number of negative
//! eigenvalues of the Hessian restricted to the constraint tangent space is that minus `m`
//! (Haynsworth's inertia additivity). Shifting the curvature block by `−σ W`
//! (`W = diag(w_a D0)`, the energy metric) counts the eigenvalues below `σ` of the
//! constrained generalised problem `Zᵀ∇²ℒZ y = λ ZᵀWZ y` that [`crate::stability`] reports.
//!
//! The block `LDLᵀ` uses no pivoting across blocks; a block whose pivot ratio falls below
//! `1e-13` is reported as [`SolverError::SingularJacobian`], and callers fall back to the
//! dense matrix (which can only happen at isolated points of a branch).
//!
//! # Size
//!
//! The file is one job, the block factorisation: the cell blocks, the `LDLᵀ` sweep with its
//! pivoting, the solves and the inertia count read the same block layout, documented once
//! above; splitting them would spread that layout over several files.

use nalgebra::{
    DMatrix, DVector, Matrix2, Matrix3, SMatrix, SVector, Vector2, Vector3, LU, U2, U9,
};

use crate::model::{tr_prod, vee_skew, Chain, Closure, SurfaceModel};
use crate::SolverError;

type M3 = Matrix3<f64>;
type V3 = Vector3<f64>;

/// Pivot ratio below which a diagonal block counts as singular.
const PIVOT_RATIO: f64 = 1e-13;

/// Per-cell coefficients of the lifted system (see the module docs).
pub(crate) struct CellTerms {
    /// `E_c`.
    pub e: Vec<M3>,
    /// `[a_c1, a_c2]`.
    pub a: Vec<[V3; 2]>,
    /// Rows of `B_c`.
    pub b: Vec<[V3; 2]>,
    /// `diag(w D) + A_c` (2×2, symmetric): `[q11, q12, q22]`.
    pub q: Vec<[f64; 3]>,
    /// Closure map `J` (`δc = J ξ_N`).
    pub closure: M3,
    /// `−K`, the `(ξ_N, ξ_N)` block (zero at a closed loop).
    pub xi_block: M3,
}

impl CellTerms {
    /// The terms at the chain `ch`, which they keep the propagators of.
    pub(crate) fn new(model: &SurfaceModel, ch: Chain, kappa_len: usize, mu: &V3) -> Self {
        let n = model.cells();
        debug_assert_eq!(kappa_len, 2 * n);
        let cl = Closure::of(&ch.prefix[n]);
        let m = cl.first(mu);
        let d = model.d_gauss();
        let mut a = Vec::with_capacity(n);
        let mut b = Vec::with_capacity(n);
        let mut q = Vec::with_capacity(n);
        for c in 0..n {
            let w = model.cell_weight(c);
            let ms = m * ch.suffix[c];
            let pms = ch.prefix[c] * ms;
            let et = ch.e[c].transpose();
            a.push([vee_skew(&(ch.de[c][0] * et)), vee_skew(&(ch.de[c][1] * et))]);
            b.push([
                -vee_skew(&(pms * ch.de[c][0])),
                -vee_skew(&(pms * ch.de[c][1])),
            ]);
            q.push([
                w * d[2 * c] + 0.5 * tr_prod(&ch.dde[c][0], &pms),
                0.5 * tr_prod(&ch.dde[c][1], &pms),
                w * d[2 * c + 1] + 0.5 * tr_prod(&ch.dde[c][2], &pms),
            ]);
        }
        Self {
            e: ch.e,
            a,
            b,
            q,
            closure: cl.jac,
            xi_block: -cl.second(mu),
        }
    }

    /// Exact product of the Lagrangian Hessian `∇²ℒ` (curvature block) with `v`, in `O(N)`:
    /// `Zᵀ 𝓗 Z v` with the forward recursion for `ξ = Z v` and its adjoint.
    pub(crate) fn hessian_vector(&self, v: &[f64]) -> Vec<f64> {
        let n = self.e.len();
        // ξ_c for c = 0..=N.
        let mut xi = vec![V3::zeros(); n + 1];
        for c in 0..n {
            xi[c + 1] = self.e[c] * xi[c] + self.a[c][0] * v[2 * c] + self.a[c][1] * v[2 * c + 1];
        }
        let mut out = vec![0.0; 2 * n];
        // Direct terms: Q v + B ξ, and the ξ-gradient g_c = B_cᵀ v_c (g_N = −K ξ_N).
        let mut g = vec![V3::zeros(); n + 1];
        g[n] = self.xi_block * xi[n];
        for c in 0..n {
            let [q11, q12, q22] = self.q[c];
            let (v1, v2) = (v[2 * c], v[2 * c + 1]);
            out[2 * c] = q11 * v1 + q12 * v2 + self.b[c][0].dot(&xi[c]);
            out[2 * c + 1] = q12 * v1 + q22 * v2 + self.b[c][1].dot(&xi[c]);
            g[c] = self.b[c][0] * v1 + self.b[c][1] * v2;
        }
        // Adjoint of ξ = L v: p_N = g_N, p_c = g_c + E_cᵀ p_{c+1}; (Lᵀg)_c = A'_cᵀ p_{c+1}.
        let mut p = g[n];
        for c in (0..n).rev() {
            out[2 * c] += self.a[c][0].dot(&p);
            out[2 * c + 1] += self.a[c][1].dot(&p);
            p = g[c] + self.e[c].transpose() * p;
        }
        out
    }
}

type M23 = SMatrix<f64, 2, 3>;
type M9 = SMatrix<f64, 9, 9>;
type V8 = SVector<f64, 8>;
type V9 = SVector<f64, 9>;
/// The three nonzero columns of `G_c = D_{c−1}⁻¹ C_cᵀ` (`C_c` couples only the rows `η_c`
/// of block `c` to block `c − 1`); rows beyond the previous block's size are zero.
type Gc = SMatrix<f64, 8, 3>;

/// The first block (`δκ_0`, 2×2).
struct FirstBlock {
    d: Matrix2<f64>,
    lu: LU<f64, U2, U2>,
}

/// A middle block `(η_c, ξ_c, δκ_c)`, `0 < c < N`: the 8×8 pivot block
/// `D_c = [[−S, −I, 0], [−I, 0, Bᵀ], [0, B, Q]]` kept by its parts. Its pair
/// `P = [[−S, −I], [−I, 0]]` has the exact inverse `[[0, −I], [−I, S]]` and `det P = −1`,
/// so `D_c` is factorised by eliminating the pair exactly onto the 2×2 Schur complement
/// `Σ = Q − B S Bᵀ` ([`MidBlock::solve`]): `det D_c = −det Σ`, and `D_c` is singular
/// exactly where `Σ` is.
struct MidBlock {
    /// `S` (3×3, symmetric): minus the `(η, η)` part, the update from the block before.
    s: M3,
    /// `B` (2×3): the `(δκ, ξ)` coupling.
    b: M23,
    /// `Σ = Q − B S Bᵀ` (2×2, symmetric), kept for the inertia.
    sigma: Matrix2<f64>,
    lu: LU<f64, U2, U2>,
    g: Gc,
}

impl MidBlock {
    /// `D_c x = r` for `K` right-hand sides (rows `η, ξ, δκ`): with `r = (r_η, r_ξ, r_κ)`,
    /// `x_κ = Σ⁻¹ (r_κ + B (r_η − S r_ξ))`, `x_η = Bᵀ x_κ − r_ξ`,
    /// `x_ξ = S (r_ξ − Bᵀ x_κ) − r_η`; `None` if `Σ` is singular.
    fn solve<const K: usize>(&self, r: &SMatrix<f64, 8, K>) -> Option<SMatrix<f64, 8, K>> {
        let re = r.fixed_rows::<3>(0);
        let rx = r.fixed_rows::<3>(3);
        let rk = r.fixed_rows::<2>(6);
        let xk = self.lu.solve(&(rk + self.b * (re - self.s * rx)))?;
        let btxk = self.b.tr_mul(&xk);
        let mut x = SMatrix::<f64, 8, K>::zeros();
        x.fixed_rows_mut::<3>(0).copy_from(&(btxk - rx));
        x.fixed_rows_mut::<3>(3)
            .copy_from(&(self.s * (rx - btxk) - re));
        x.fixed_rows_mut::<2>(6).copy_from(&xk);
        Some(x)
    }
}

/// The last block `(η_N, ξ_N, δμ)` (9×9).
struct LastBlock {
    d: M9,
    lu: LU<f64, U9, U9>,
    g: Gc,
}

/// Block `LDLᵀ` factorisation of the lifted KKT matrix (see the module docs), optionally
/// shifted by `−σW` in the curvature block, with the phase condition as a border.
pub struct KktFactor {
    cells: usize,
    first: FirstBlock,
    /// Blocks `c = 1..N` (index `c − 1`).
    mid: Vec<MidBlock>,
    last: LastBlock,
    /// Phase border: the column `b` (`−∇φ` on the curvature entries), `K₀⁻¹ b` and the
    /// Schur complement `s = −bᵀK₀⁻¹b`.
    border: Option<(DVector<f64>, DVector<f64>, f64)>,
    det_sign: f64,
    log_abs_det: f64,
    n_mult: usize,
    regularized: bool,
    /// What `J v` needs (kept so that refinement residuals do not recompute the chain).
    product: KktProduct,
}

/// The (shifted) Newton matrix as an operator, `v ↦ J v`, in `O(N)`: the cell terms, the
/// closure Jacobian, the phase gradient and the diagonal shift `shift · D0 · w_a`.
struct KktProduct {
    terms: CellTerms,
    closure_jac: DMatrix<f64>,
    phase_grad: Option<Vec<f64>>,
    shift_w: Vec<f64>,
}

impl KktProduct {
    fn new(model: &SurfaceModel, z: &[f64], shift: f64) -> Result<Self, SolverError> {
        let (kappa, mu, _) = model.split(z)?;
        model.check_kappa(kappa)?;
        let ch = model.chain(kappa);
        let d0 = model.stiffness().kind().reference();
        let closure_jac = model.closure_jacobian_from(&ch);
        Ok(Self {
            terms: CellTerms::new(model, ch, kappa.len(), &V3::from(mu)),
            closure_jac,
            phase_grad: model.phase().map(|ph| ph.gradient()),
            shift_w: (0..kappa.len())
                .map(|a| shift * d0 * model.cell_weight(a / 2))
                .collect(),
        })
    }

    /// `(∇²ℒ dκ − shift·W dκ − ∇cᵀdμ − ∇φ dν, −∇c dκ, −∇φᵀdκ)`.
    fn apply(&self, v: &DVector<f64>) -> DVector<f64> {
        let n = self.shift_w.len();
        let dk = &v.as_slice()[..n];
        let hv = self.terms.hessian_vector(dk);
        let cj = &self.closure_jac;
        let mut out = DVector::zeros(v.len());
        for a in 0..n {
            out[a] = hv[a]
                - self.shift_w[a] * dk[a]
                - (0..3).map(|k| cj[(k, a)] * v[n + k]).sum::<f64>();
        }
        for k in 0..3 {
            out[n + k] = -(0..n).map(|a| cj[(k, a)] * dk[a]).sum::<f64>();
        }
        if let Some(g) = &self.phase_grad {
            let dnu = v[n + 3];
            for a in 0..n {
                out[a] -= g[a] * dnu;
            }
            out[n + 3] = -g.iter().zip(dk).map(|(g, d)| g * d).sum::<f64>();
        }
        out
    }
}

/// `min |U_ii| / max |U_ii|` of the diagonal of an LU factor (0 if not finite).
fn pivot_ratio(diag: &[f64]) -> f64 {
    let big = diag.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let small = diag.iter().fold(f64::INFINITY, |m, v| m.min(v.abs()));
    let r = small / big;
    if r.is_finite() {
        r
    } else {
        0.0
    }
}

/// Sign and `ln |det|` of an LU factorisation from its permutation sign and `U` diagonal.
fn det_parts(perm_sign: f64, diag: &[f64]) -> (f64, f64) {
    let mut sign = perm_sign;
    let mut log = 0.0;
    for v in diag {
        if *v < 0.0 {
            sign = -sign;
        }
        log += v.abs().ln();
    }
    (sign, log)
}

/// The factorised block before block `c`: the first one or a middle one.
#[derive(Clone, Copy)]
enum Prev<'a> {
    First(&'a LU<f64, U2, U2>),
    Mid(&'a MidBlock),
}

/// `G_c = D_{c−1}⁻¹ C_cᵀ` (its three nonzero columns) and the update `C_c G_c` of the
/// `(η_c, η_c)` part of block `c`. `C_c` couples `η_c` with `(ξ_{c−1}, δκ_{c−1})`:
/// `C_c = [E_{c−1}, a_{c−1,1}, a_{c−1,2}]` (no `ξ_0`).
fn coupling(prev: Prev<'_>, e: &M3, a: &[V3; 2]) -> Option<(Gc, M3)> {
    match prev {
        Prev::First(lu) => {
            let ct = SMatrix::<f64, 2, 3>::from_rows(&[a[0].transpose(), a[1].transpose()]);
            let g2 = lu.solve(&ct)?;
            let upd = ct.tr_mul(&g2);
            let mut g = Gc::zeros();
            g.fixed_rows_mut::<2>(0).copy_from(&g2);
            Some((g, upd))
        }
        Prev::Mid(block) => {
            let mut ct = Gc::zeros();
            ct.fixed_rows_mut::<3>(3).copy_from(&e.transpose());
            ct.set_row(6, &a[0].transpose());
            ct.set_row(7, &a[1].transpose());
            let g = block.solve(&ct)?;
            let upd = ct.tr_mul(&g);
            Some((g, upd))
        }
    }
}

/// Block rows `(η, ξ)`: the `−I` couplings of an eliminated pair.
fn pair_couplings<const S: usize>(k: &mut SMatrix<f64, S, S>) {
    for i in 0..3 {
        k[(i, 3 + i)] = -1.0;
        k[(3 + i, i)] = -1.0;
    }
}

/// `[x_0 (2 entries), 0, …]` as an 8-vector, so that the first block's `G` (zero-padded
/// rows) applies uniformly.
fn pad2(x: &Vector2<f64>) -> V8 {
    let mut v = V8::zeros();
    v[0] = x[0];
    v[1] = x[1];
    v
}

impl KktFactor {
    /// Factorise the Newton matrix of `model` at the KKT state `z = (κ, μ, ν)`, with the
    /// curvature block shifted by `−shift · W` (`shift = 0` for Newton steps).
    pub fn new(model: &SurfaceModel, z: &[f64], shift: f64) -> Result<Self, SolverError> {
        Self::from_product(model, KktProduct::new(model, z, shift)?, shift)
    }

    fn from_product(
        model: &SurfaceModel,
        product: KktProduct,
        shift: f64,
    ) -> Result<Self, SolverError> {
        let singular = || SolverError::SingularJacobian { iteration: 0 };
        let t = &product.terms;
        let n = model.cells();
        let d0 = model.stiffness().kind().reference();
        let mut det_sign = 1.0;
        let mut log_abs_det = 0.0;
        let mut regularized = false;
        // Block 0: δκ_0.
        let first = {
            let sw = shift * d0 * model.cell_weight(0);
            let [q11, q12, q22] = t.q[0];
            let d = Matrix2::new(q11 - sw, q12, q12, q22 - sw);
            let lu = d.lu();
            let diag = lu.u().diagonal();
            if pivot_ratio(diag.as_slice()) <= PIVOT_RATIO {
                return Err(singular());
            }
            let (s, l) = det_parts(lu.p().determinant::<f64>(), diag.as_slice());
            det_sign *= s;
            log_abs_det += l;
            FirstBlock { d, lu }
        };
        // Blocks 1..N: (η_c, ξ_c, δκ_c).
        let mut mid: Vec<MidBlock> = Vec::with_capacity(n.saturating_sub(1));
        for c in 1..n {
            let sw = shift * d0 * model.cell_weight(c);
            let [q11, q12, q22] = t.q[c];
            let q = Matrix2::new(q11 - sw, q12, q12, q22 - sw);
            let b = M23::from_rows(&[t.b[c][0].transpose(), t.b[c][1].transpose()]);
            let prev = if c == 1 {
                Prev::First(&first.lu)
            } else {
                Prev::Mid(&mid[c - 2])
            };
            let (g, upd) = coupling(prev, &t.e[c - 1], &t.a[c - 1]).ok_or_else(singular)?;
            let s = (upd + upd.transpose()) * 0.5;
            let bsb = b * s * b.transpose();
            let sigma = q - (bsb + bsb.transpose()) * 0.5;
            let lu = sigma.lu();
            let diag = lu.u().diagonal();
            // The block's scale is that of its entries (the pair's ±1, `S`, `B`, `Q`): a pivot
            // of `Σ` that small against it makes a singular block, as the pivot ratio of the
            // block's LU did.
            let scale = [
                1.0,
                s.amax(),
                b.amax(),
                q.amax(),
                diag[0].abs(),
                diag[1].abs(),
            ]
            .into_iter()
            .fold(0.0f64, f64::max);
            let small = diag[0].abs().min(diag[1].abs());
            if small.is_nan() || small <= PIVOT_RATIO * scale {
                return Err(singular());
            }
            // det D_c = det P · det Σ with det P = −1.
            let (sg, l) = det_parts(lu.p().determinant::<f64>(), diag.as_slice());
            det_sign *= -sg;
            log_abs_det += l;
            mid.push(MidBlock { s, b, sigma, lu, g });
        }
        // Block N: (η_N, ξ_N, δμ).
        let last = {
            let mut k = M9::zeros();
            pair_couplings(&mut k);
            for i in 0..3 {
                for j in 0..3 {
                    k[(3 + i, 3 + j)] = t.xi_block[(i, j)];
                    k[(6 + i, 3 + j)] = -t.closure[(i, j)];
                    k[(3 + j, 6 + i)] = -t.closure[(i, j)];
                }
            }
            let prev = if n == 1 {
                Prev::First(&first.lu)
            } else {
                Prev::Mid(&mid[n - 2])
            };
            let (g, upd) = coupling(prev, &t.e[n - 1], &t.a[n - 1]).ok_or_else(singular)?;
            let mut ee = k.fixed_view_mut::<3, 3>(0, 0);
            ee -= upd;
            let mut d = (k + k.transpose()) * 0.5;
            let mut lu = d.lu();
            let mut ratio = pivot_ratio(lu.u().diagonal().as_slice());
            if ratio <= PIVOT_RATIO {
                // Closure constraints of deficient rank (a great circle, or a planar start):
                // regularise the multiplier block by −δI (δ = 1e-10 of the block's scale),
                // as interior-point codes do for degenerate equality constraints. The
                // rank-deficient direction then counts as a constraint in the inertia.
                let scale = d.amax().max(f64::MIN_POSITIVE);
                for i in 6..9 {
                    d[(i, i)] -= 1e-10 * scale;
                }
                lu = d.lu();
                ratio = pivot_ratio(lu.u().diagonal().as_slice());
                regularized = true;
            }
            if ratio <= PIVOT_RATIO {
                return Err(singular());
            }
            let diag = lu.u().diagonal();
            let (s, l) = det_parts(lu.p().determinant::<f64>(), diag.as_slice());
            det_sign *= s;
            log_abs_det += l;
            LastBlock { d, lu, g }
        };
        let mut f = Self {
            cells: n,
            first,
            mid,
            last,
            border: None,
            det_sign,
            log_abs_det,
            n_mult: model.n_multipliers(),
            regularized,
            product,
        };
        if let Some(ph) = model.phase() {
            let mut b = DVector::zeros(2 * n + 3);
            for (a, gv) in ph.gradient().iter().enumerate() {
                b[a] = -gv;
            }
            let x = f.solve_lifted(&b);
            let s = -b.dot(&x);
            if !(s.is_finite() && s != 0.0) {
                return Err(SolverError::SingularJacobian { iteration: 0 });
            }
            f.det_sign *= s.signum();
            f.log_abs_det += s.abs().ln();
            f.border = Some((b, x, s));
        }
        Ok(f)
    }

    /// Solve without the phase border: `b` and the result have the layout `(κ, μ)`.
    fn solve_lifted(&self, b: &DVector<f64>) -> DVector<f64> {
        let n = self.cells;
        // Scatter; forward elimination w_c −= G_cᵀ w_{c−1} (only the η_c rows change).
        let mut x0 = Vector2::new(b[0], b[1]);
        let mut xm: Vec<V8> = Vec::with_capacity(n.saturating_sub(1));
        for c in 1..n {
            let mut v = V8::zeros();
            v[6] = b[2 * c];
            v[7] = b[2 * c + 1];
            let prev = if c == 1 { pad2(&x0) } else { xm[c - 2] };
            let upd = self.mid[c - 1].g.tr_mul(&prev);
            let mut eta = v.fixed_rows_mut::<3>(0);
            eta -= upd;
            xm.push(v);
        }
        let mut xl = V9::zeros();
        for i in 0..3 {
            xl[6 + i] = b[2 * n + i];
        }
        let prev = if n == 1 { pad2(&x0) } else { xm[n - 2] };
        let upd = self.last.g.tr_mul(&prev);
        let mut eta = xl.fixed_rows_mut::<3>(0);
        eta -= upd;
        // Diagonal solves.
        fn nan_if<const S: usize>(ok: bool, v: &mut SVector<f64, S>) {
            if !ok {
                v.fill(f64::NAN);
            }
        }
        let ok = self.first.lu.solve_mut(&mut x0);
        nan_if(ok, &mut x0);
        for (v, bl) in xm.iter_mut().zip(&self.mid) {
            match bl.solve(v) {
                Some(x) => *v = x,
                None => v.fill(f64::NAN),
            }
        }
        let ok = self.last.lu.solve_mut(&mut xl);
        nan_if(ok, &mut xl);
        // Backward: x_{c−1} −= G_c x_c (G_c has nonzero columns only for η_c).
        let apply_g = |g: &Gc, eta: V3, c: usize, x0: &mut Vector2<f64>, xm: &mut [V8]| {
            let upd = g * eta;
            if c == 1 {
                x0[0] -= upd[0];
                x0[1] -= upd[1];
            } else {
                xm[c - 2] -= upd;
            }
        };
        apply_g(
            &self.last.g,
            xl.fixed_rows::<3>(0).into_owned(),
            n,
            &mut x0,
            &mut xm,
        );
        for c in (1..n).rev() {
            let eta = xm[c - 1].fixed_rows::<3>(0).into_owned();
            apply_g(&self.mid[c - 1].g, eta, c, &mut x0, &mut xm);
        }
        let mut out = DVector::zeros(2 * n + 3);
        out[0] = x0[0];
        out[1] = x0[1];
        for c in 1..n {
            out[2 * c] = xm[c - 1][6];
            out[2 * c + 1] = xm[c - 1][7];
        }
        for i in 0..3 {
            out[2 * n + i] = xl[6 + i];
        }
        out
    }

    /// Solve `J z = b` with the Newton matrix `J` of [`SurfaceModel::kkt_jacobian`] (layout
    /// `(κ, μ, ν)`); `None` if the result is not finite.
    pub fn solve(&self, b: &DVector<f64>) -> Option<DVector<f64>> {
        let n = self.cells;
        let main = b.rows(0, 2 * n + 3).into_owned();
        let out = match &self.border {
            None => self.solve_lifted(&main),
            Some((col, x1, s)) => {
                // [K₀ col; colᵀ 0] [x; ν] = [b; b_ν]: x = K₀⁻¹b − ν K₀⁻¹col,
                // ν = (b_ν − colᵀK₀⁻¹b)/s with s = −colᵀK₀⁻¹col.
                let x2 = self.solve_lifted(&main);
                let nu = (b[2 * n + 3] - col.dot(&x2)) / s;
                (x2 - x1 * nu).insert_row(2 * n + 3, nu)
            }
        };
        out.iter().all(|v| v.is_finite()).then_some(out)
    }

    /// The factorised (shifted) matrix applied to `v` (layout `(κ, μ, ν)`), in `O(N)`:
    /// the residual of an iterative refinement.
    pub fn apply(&self, v: &DVector<f64>) -> DVector<f64> {
        self.product.apply(v)
    }

    /// Sign of `det J`, `J` the dense Newton matrix.
    pub fn det_sign(&self) -> f64 {
        // det(lifted) = det(P) det(J) with P = [[0, −Gᵀ], [−G, 0]] the block of all
        // eliminated pairs, det P = (−1)^{3N} det(G)² = (−1)^N (G is block bidiagonal with
        // −I on its diagonal).
        let pairs_sign = if self.cells % 2 == 1 { -1.0 } else { 1.0 };
        self.det_sign * pairs_sign
    }

    /// Whether the closure block had to be regularised (constraints of deficient rank);
    /// solves are then least-squares-like in the deficient direction.
    pub fn is_regularized(&self) -> bool {
        self.regularized
    }

    /// `ln |det J|` (the pairs have `|det| = 1`).
    pub fn log_abs_det(&self) -> f64 {
        self.log_abs_det
    }

    /// Number of negative eigenvalues of the dense Newton matrix `J`.
    ///
    /// Only the `(η, η)` part of a pivot block is changed by the elimination of the block
    /// before it, so `D_c = [[−S, −I, 0], [−I, 0, Bᵀ], [0, B, Q]]`, whose inertia is that of
    /// the pair, `(3, 3, 0)`, plus that of `Σ_c = Q − B S Bᵀ` (2×2); the last block gives
    /// `(3, 3, 0)` plus the inertia of `−B_cl S B_clᵀ` (3×3, `B_cl` the closure map).
    pub fn negative_eigenvalues(&self) -> usize {
        let d = &self.first.d;
        let mut neg = negatives_2x2(d[(0, 0)], d[(0, 1)], d[(1, 1)]);
        for b in &self.mid {
            let sigma = &b.sigma;
            neg += 3 + negatives_2x2(sigma[(0, 0)], sigma[(0, 1)], sigma[(1, 1)]);
        }
        neg += last_block_negatives(&self.last.d);
        if let Some((_, _, s)) = &self.border {
            if *s < 0.0 {
                neg += 1;
            }
        }
        neg.saturating_sub(3 * self.cells)
    }

    /// Number of eigenvalues below the shift of the Hessian restricted to the tangent
    /// space of the constraints (closure and, if present, phase): the stability index
    /// when the shift is `−tolerance`.
    pub fn reduced_negative_count(&self) -> usize {
        self.negative_eigenvalues().saturating_sub(self.n_mult)
    }
}

/// Negative eigenvalues of the last pivot block `D = [[−S, −I, 0], [−I, K, Jᵀ], [0, J, Q]]`
/// (rows `η_N, ξ_N, δμ`). The pair `P = [[−S, −I], [−I, K]]` has inertia `(3, 3, 0)` while
/// `I + SK` stays invertible on the way from `K = 0` (`K` vanishes at a closed loop), and
/// `(P⁻¹)_ξξ = (I + SK)⁻¹S`, so `D` adds 3 plus the negatives of
/// `Σ = Q − J (I + SK)⁻¹S Jᵀ` (Haynsworth). If `I + SK` is (nearly) singular, the
/// eigenvalues of `D` itself are counted (Sylvester).
fn last_block_negatives(d: &M9) -> usize {
    let count = |m: &SMatrix<f64, 3, 3>| {
        let sym = (m + m.transpose()) * 0.5;
        sym.symmetric_eigenvalues()
            .iter()
            .filter(|v| **v < 0.0)
            .count()
    };
    let s = -d.fixed_view::<3, 3>(0, 0).into_owned();
    let k = d.fixed_view::<3, 3>(3, 3).into_owned();
    let dkx = d.fixed_view::<3, 3>(6, 3).into_owned();
    let pair = M3::identity() + s * k;
    let well_posed = pair.iter().all(|v| v.is_finite())
        && pair.lu().u().diagonal().iter().all(|v| v.abs() > 1e-8);
    if let (true, Some(inv)) = (well_posed, pair.try_inverse()) {
        let sigma = d.fixed_view::<3, 3>(6, 6) - dkx * inv * s * dkx.transpose();
        3 + count(&sigma)
    } else {
        let sym = (d + d.transpose()) * 0.5;
        sym.symmetric_eigenvalues()
            .iter()
            .filter(|v| **v < 0.0)
            .count()
    }
}

/// Number of negative eigenvalues of the symmetric 2×2 matrix `[[a, b], [b, c]]`.
fn negatives_2x2(a: f64, b: f64, c: f64) -> usize {
    let det = a * c - b * b;
    if det < 0.0 {
        1
    } else if a + c < 0.0 {
        if det > 0.0 {
            2
        } else {
            1
        }
    } else {
        0
    }
}

impl SurfaceModel {
    /// `∇²ℒ v` (curvature block of the Lagrangian Hessian times `v`) in `O(N)`, without
    /// forming the dense matrix of [`SurfaceModel::lagrangian_hessian`].
    pub fn hessian_vector(
        &self,
        kappa: &[f64],
        mu: &[f64; 3],
        v: &[f64],
    ) -> Result<Vec<f64>, SolverError> {
        if v.len() != self.n_kappa() {
            return Err(SolverError::WrongLength {
                expected: self.n_kappa(),
                found: v.len(),
            });
        }
        self.check_kappa(kappa)?;
        let ch = self.chain(kappa);
        Ok(CellTerms::new(self, ch, kappa.len(), &V3::from(*mu)).hessian_vector(v))
    }
}

impl SurfaceModel {
    /// The Newton matrix applied to a vector, `J dz` (layout `(κ, μ, ν)`), in `O(N)`:
    /// `(∇²ℒ dκ − ∇cᵀdμ − ∇φ dν, −∇c dκ, −∇φᵀdκ)`.
    pub fn kkt_apply(&self, z: &[f64], dz: &[f64]) -> Result<DVector<f64>, SolverError> {
        if dz.len() != self.dim() {
            return Err(SolverError::WrongLength {
                expected: self.dim(),
                found: dz.len(),
            });
        }
        Ok(KktProduct::new(self, z, 0.0)?.apply(&DVector::from_column_slice(dz)))
    }
}
