//! Linear algebra of the KKT system in `O(N)`: a block-tridiagonal ("lifted") form of the
//! Newton matrix, its block `LDLᵀ` factorisation, solves, determinant sign and inertia.
//!
//! # Why the dense matrix is never formed
//!
//! The closure `c(κ) = vee(skew H)` with the holonomy `H = E_{N−1}⋯E_0` couples every cell
//! with every other, so the Hessian of `ℒ = E − μ·c` in the curvature unknowns alone is
//! dense. Introducing the first variation of the prefix frames as auxiliary unknowns makes
//! it local, as multiple shooting does for boundary-value problems: with `P_c = E_{c−1}⋯E_0`
//! and `δP_c = hat(ξ_c) P_c`, the linearised recursion is
//!
//! ```text
//! ξ_{c+1} = E_c ξ_c + Σ_i a_ci δκ_ci,   a_ci = vee(∂_iE_c E_cᵀ),   ξ_0 = 0,
//! δc = B ξ_N,                            B e_k = vee(skew(hat(e_k) H)),
//! ```
//!
//! and the second variation of `f = −μ·c = ½ tr(hat(μ) H)` is a sum of cell terms,
//! `Σ_c [δκ_cᵀ A_c δκ_c + 2 δκ_cᵀ B_c ξ_c]` with `A_c,ij = ½ tr(hat(μ) S_c ∂_ijE_c P_c)` and
//! the rows `B_c,i = −vee(skew(P_c hat(μ) S_c ∂_iE_c))` (`S_c = E_{N−1}⋯E_{c+1}`).
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

use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

use crate::frame::hat;
use crate::model::{tr_prod, vee_skew, Chain, SurfaceModel};
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
    /// Closure map `B` (columns `vee(skew(hat(e_k) H))`).
    pub closure: M3,
}

impl CellTerms {
    pub(crate) fn new(model: &SurfaceModel, ch: &Chain, kappa_len: usize, mu: &V3) -> Self {
        let n = model.cells();
        debug_assert_eq!(kappa_len, 2 * n);
        let m = hat(mu);
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
        let hol = ch.prefix[n];
        let mut closure = M3::zeros();
        for k in 0..3 {
            let col = vee_skew(&(hat(&V3::ith(k, 1.0)) * hol));
            closure.set_column(k, &col);
        }
        Self {
            e: ch.e.clone(),
            a,
            b,
            q,
            closure,
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
        // Direct terms: Q v + B ξ, and the ξ-gradient g_c = B_cᵀ v_c.
        let mut g = vec![V3::zeros(); n + 1];
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

/// One block of the factorisation.
struct Block {
    /// The pivot block `D_c` (symmetric), kept for the inertia.
    d: DMatrix<f64>,
    lu: nalgebra::LU<f64, nalgebra::Dyn, nalgebra::Dyn>,
    /// `G_c = D_{c−1}⁻¹ C_cᵀ` (`n_{c−1} × n_c`); empty for the first block.
    g: DMatrix<f64>,
}

/// Block `LDLᵀ` factorisation of the lifted KKT matrix (see the module docs), optionally
/// shifted by `−σW` in the curvature block, with the phase condition as a border.
pub struct KktFactor {
    cells: usize,
    blocks: Vec<Block>,
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
        Ok(Self {
            terms: CellTerms::new(model, &ch, kappa.len(), &V3::from(mu)),
            closure_jac: model.closure_jacobian_from(&ch),
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

/// `min |U_ii| / max |U_ii|` of an LU factorisation (0 if not finite).
fn pivot_ratio(lu: &nalgebra::LU<f64, nalgebra::Dyn, nalgebra::Dyn>) -> f64 {
    let diag = lu.u().diagonal();
    let big = diag.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let small = diag.iter().fold(f64::INFINITY, |m, v| m.min(v.abs()));
    let r = small / big;
    if r.is_finite() {
        r
    } else {
        0.0
    }
}

fn block_size(c: usize, cells: usize) -> usize {
    if c == 0 {
        2
    } else if c < cells {
        8
    } else {
        9
    }
}

/// Offset of the curvature pair of cell `c` inside its block.
fn kappa_offset(c: usize) -> usize {
    if c == 0 {
        0
    } else {
        6
    }
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
        let t = &product.terms;
        let n = model.cells();
        let d0 = model.stiffness().kind().reference();
        let mut blocks: Vec<Block> = Vec::with_capacity(n + 1);
        let mut det_sign = 1.0;
        let mut log_abs_det = 0.0;
        let mut regularized = false;
        for c in 0..=n {
            let size = block_size(c, n);
            let mut k = DMatrix::zeros(size, size);
            if c > 0 {
                for i in 0..3 {
                    k[(i, 3 + i)] = -1.0;
                    k[(3 + i, i)] = -1.0;
                }
            }
            if c < n {
                let o = kappa_offset(c);
                let sw = shift * d0 * model.cell_weight(c);
                let [q11, q12, q22] = t.q[c];
                k[(o, o)] = q11 - sw;
                k[(o, o + 1)] = q12;
                k[(o + 1, o)] = q12;
                k[(o + 1, o + 1)] = q22 - sw;
                if c > 0 {
                    for i in 0..2 {
                        for j in 0..3 {
                            k[(o + i, 3 + j)] = t.b[c][i][j];
                            k[(3 + j, o + i)] = t.b[c][i][j];
                        }
                    }
                }
            } else {
                for i in 0..3 {
                    for j in 0..3 {
                        k[(6 + i, 3 + j)] = -t.closure[(i, j)];
                        k[(3 + j, 6 + i)] = -t.closure[(i, j)];
                    }
                }
            }
            let g = if c > 0 {
                // C_c: rows η_c (0..3) against (ξ_{c−1}, δκ_{c−1}) of the previous block.
                let prev = block_size(c - 1, n);
                let mut cc = DMatrix::zeros(size, prev);
                let po = kappa_offset(c - 1);
                for i in 0..3 {
                    if c - 1 > 0 {
                        for j in 0..3 {
                            cc[(i, 3 + j)] = t.e[c - 1][(i, j)];
                        }
                    }
                    cc[(i, po)] = t.a[c - 1][0][i];
                    cc[(i, po + 1)] = t.a[c - 1][1][i];
                }
                let g = blocks[c - 1]
                    .lu
                    .solve(&cc.transpose())
                    .ok_or(SolverError::SingularJacobian { iteration: 0 })?;
                k -= &cc * &g;
                g
            } else {
                DMatrix::zeros(0, 0)
            };
            let mut d = (&k + k.transpose()) * 0.5;
            let mut lu = d.clone().lu();
            let mut ratio = pivot_ratio(&lu);
            if c == n && ratio <= PIVOT_RATIO {
                // Closure constraints of deficient rank (a great circle, or a planar start):
                // regularise the multiplier block by −δI (δ = 1e-10 of the block's scale),
                // as interior-point codes do for degenerate equality constraints. The
                // rank-deficient direction then counts as a constraint in the inertia.
                let scale = d.amax().max(f64::MIN_POSITIVE);
                for i in 6..9 {
                    d[(i, i)] -= 1e-10 * scale;
                }
                lu = d.clone().lu();
                ratio = pivot_ratio(&lu);
                regularized = true;
            }
            if ratio <= PIVOT_RATIO {
                return Err(SolverError::SingularJacobian { iteration: 0 });
            }
            let diag = lu.u().diagonal();
            let mut sign = lu.p().determinant::<f64>();
            for v in diag.iter() {
                if *v < 0.0 {
                    sign = -sign;
                }
                log_abs_det += v.abs().ln();
            }
            det_sign *= sign;
            blocks.push(Block { d, lu, g });
        }
        let mut f = Self {
            cells: n,
            blocks,
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
        // Scatter.
        let mut w: Vec<DVector<f64>> = (0..=n).map(|c| DVector::zeros(block_size(c, n))).collect();
        for c in 0..n {
            let o = kappa_offset(c);
            w[c][o] = b[2 * c];
            w[c][o + 1] = b[2 * c + 1];
        }
        for i in 0..3 {
            w[n][6 + i] = b[2 * n + i];
        }
        // Forward: w_c −= G_cᵀ w_{c−1}.
        for c in 1..=n {
            let upd = self.blocks[c].g.tr_mul(&w[c - 1]);
            w[c] -= upd;
        }
        // Diagonal.
        let mut x: Vec<DVector<f64>> = w
            .iter()
            .zip(&self.blocks)
            .map(|(wc, bl)| {
                bl.lu
                    .solve(wc)
                    .unwrap_or_else(|| DVector::from_element(wc.len(), f64::NAN))
            })
            .collect();
        // Backward: x_{c−1} −= G_c x_c.
        for c in (1..=n).rev() {
            let upd = &self.blocks[c].g * &x[c];
            x[c - 1] -= upd;
        }
        let mut out = DVector::zeros(2 * n + 3);
        for c in 0..n {
            let o = kappa_offset(c);
            out[2 * c] = x[c][o];
            out[2 * c + 1] = x[c][o + 1];
        }
        for i in 0..3 {
            out[2 * n + i] = x[n][6 + i];
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
        let n = self.cells;
        let mut neg = 0usize;
        for (c, b) in self.blocks.iter().enumerate() {
            let d = &b.d;
            if c == 0 {
                neg += negatives_2x2(d[(0, 0)], d[(0, 1)], d[(1, 1)]);
                continue;
            }
            // S = −D[η, η]; Σ = D[κκ] + D[κξ] D[ηη] D[ξκ] (κ: rows 6.., ξ: 3..6, η: 0..3).
            let dee = d.view((0, 0), (3, 3));
            let tail = d.nrows() - 6;
            let dkx = d.view((6, 3), (tail, 3));
            let sigma = d.view((6, 6), (tail, tail)) + dkx * dee * dkx.transpose();
            neg += 3;
            neg += if c < n {
                negatives_2x2(
                    sigma[(0, 0)],
                    0.5 * (sigma[(0, 1)] + sigma[(1, 0)]),
                    sigma[(1, 1)],
                )
            } else {
                let sym = (&sigma + sigma.transpose()) * 0.5;
                sym.symmetric_eigenvalues()
                    .iter()
                    .filter(|v| **v < 0.0)
                    .count()
            };
        }
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
        Ok(CellTerms::new(self, &ch, kappa.len(), &V3::from(*mu)).hessian_vector(v))
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
