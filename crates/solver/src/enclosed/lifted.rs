//! The semismooth Newton step of the enclosed model in `O(N)`: a block-tridiagonal
//! ("lifted") form of the Jacobian of [`EnclosedModel`], with a small dense border.
//!
//! It is one file because the lifted form, its block factorisation and the border solve share
//! the two chains and the block layout described below.
//!
//! # Why the dense matrix is not needed
//!
//! The Bishop-frame chain `P_{c+1} = P_c E_c(κ_c)` makes every node depend on every earlier
//! cell, so the Jacobian in the unknowns `(κ, r0, μ, ν, λ)` is dense (`O(N³)` to factor).
//! The residual itself is local once two chains are named (see [`super::model`]):
//!
//! * the node transforms `P_j`; perturbed in the spatial frame, `δP_j = hat(ξ_j) P_j`
//!   (`ξ = (ω, v) ∈ se(3)`), they obey `ξ_{c+1} = ξ_c + Σ_i b_ci δκ_ci`, `ξ_0 = 0`, with
//!   `b_ci = vee(P_c ∂_iE_c E_c⁻¹ P_c⁻¹)`;
//! * the adjoint carried to the spatial frame, `M_c = P_{c+1} A_c`, whose recursion
//!   `A_c = E_{c+1}A_{c+1} + 2λ_{c+1} e4 ρ_{c+1}ᵀ` becomes a plain sum,
//!   `M_c = M_{c+1} + 2λ_{c+1} (p_{c+1}; 1)(r_{c+1}; 0)ᵀ`, `M_{N−1} = −P_N K(μ)`. Only its
//!   pairing with `se(3)`, `m_c = (tr(hat(e_k) M_c))_k = Σ_{j>c} 2λ_j u_j − …`, with
//!   `u_j = (p_j × r_j, r_j)`, enters the residual.
//!
//! Stationarity in cell `c` is then `w D κ_ci + b_ci · m_c − ν · ∂φ/∂κ_ci = 0`, which
//! involves only cell `c`, `ξ_c` and `m_c`. Linearising every one of these relations
//! (`δb_ci` has the bracket term `[hat ξ_c, B_ci]` and the cell's own second derivatives;
//! `δu_j` is linear in `ξ_j` and `δr0`; `δm_{N−1}` in `ξ_N` and `δμ`) gives a linear system
//! in the unknowns, per cell `c`,
//!
//! ```text
//! [δκ_c (4), ξ_{c+1} (6), δm_c (6), δλ_{c+1} (1)]     (17; δλ_N a dummy, fixed to 0)
//! ```
//!
//! with equations `[stationarity (4), forward ξ (6), backward m (6), wall row of node c+1]`,
//! which is block tridiagonal, plus the global unknowns `(δr0, δμ, δν, δλ_0)` and global
//! rows (`r0` stationarity, closure, gauges, wall row of node 0) as a dense border. Eliminating
//! `ξ` and `δm` reproduces the dense semismooth Jacobian of [`EnclosedModel::evaluate`]
//! exactly, so the step is the same Newton step (`tests/enclosed.rs` compares the two).
//!
//! # Factorisation
//!
//! Block LU from the first cell to the last (partial pivoting inside each 17×17 block, no
//! pivoting across blocks), the border by its Schur complement, then one step of iterative
//! refinement against the lifted system. Only the border columns in use (`10 + gauges`) are
//! eliminated, and the system, its factors and the solve buffers live in a per-thread
//! workspace kept across Newton steps. `O(N)` work: about `6·10⁴` flops per cell. A
//! near-singular pivot block, or a refined residual above `1e-9 |rhs| + 1e-13 max|M| |x|` (the
//! second term is the round-off floor near convergence, where the right-hand side is tiny), is
//! reported as [`SolverError::SingularJacobian`] so that the caller can fall back to the dense
//! factorisation.

#![allow(clippy::needless_range_loop)] // index arithmetic over cells, nodes and unknowns

use nalgebra::{Const, DVector, Matrix3, Matrix4, SMatrix, SVector, Vector3};

use super::model::{closure_rotation, tr4, translation, vee_skew3, EnclosedModel, TWIST_ROW};
use crate::SolverError;

pub(super) const B: usize = 17;
type Blk = SMatrix<f64, B, B>;
pub(super) type BVec = SVector<f64, B>;
/// Border size, padded: `10 + gauges` unknowns (at most 15) with identity rows after them,
/// so that every block of the factorisation has a fixed size.
const G: usize = 15;
type BCol = SMatrix<f64, B, G>;
type BRow = SMatrix<f64, G, B>;
type GMat = SMatrix<f64, G, G>;
pub(super) type GVec = SVector<f64, G>;
type M4 = Matrix4<f64>;
type M3 = Matrix3<f64>;
type V3 = Vector3<f64>;

// Local layout of a cell block (unknowns and equations).
pub(super) const K0: usize = 0; // δκ_c / stationarity
pub(super) const X0: usize = 4; // ξ_{c+1} / forward recursion
pub(super) const M0: usize = 10; // δm_c / backward recursion
pub(super) const L0: usize = 16; // δλ_{c+1} / wall row of node c+1

/// Pivot ratio below which a block counts as singular.
const PIVOT_RATIO: f64 = 1e-14;

fn hat3(v: &V3) -> M3 {
    M3::new(0.0, -v[2], v[1], v[2], 0.0, -v[0], -v[1], v[0], 0.0)
}

/// `hat(e_k)` of `se(3)`, `k = 0..6` (rotations first).
fn se3_basis() -> [M4; 6] {
    let mut out = [M4::zeros(); 6];
    for k in 0..3 {
        let mut e = V3::zeros();
        e[k] = 1.0;
        out[k].fixed_view_mut::<3, 3>(0, 0).copy_from(&hat3(&e));
        out[3 + k][(k, 3)] = 1.0;
    }
    out
}

/// The bracket `e m − m e` for a basis element `e` of [`se3_basis`] (at most one entry, ±1,
/// in each row and each column): its products only pick and sign rows and columns of `m`,
/// which gives the numbers of the full products (up to the sign of zero entries) without
/// their multiplications.
fn bracket(e: &M4, m: &M4) -> M4 {
    let (mut em, mut me) = (M4::zeros(), M4::zeros());
    for r in 0..4 {
        for s in 0..4 {
            let v = e[(r, s)];
            if v != 0.0 {
                debug_assert!(v.abs() == 1.0);
                for j in 0..4 {
                    // Row r of e m is v · (row s of m); column s of m e is v · (column r of m).
                    em[(r, j)] = v * m[(s, j)];
                    me[(j, s)] = v * m[(j, r)];
                }
            }
        }
    }
    em - me
}

/// `tr(a b c)` for `b` with a zero last row (a derivative of a cell propagator) and `a` with
/// zeros in the first three entries of its last row: the numbers of `tr4(&(a * b), c)`
/// (up to the sign of zeros) without the terms that vanish.
fn tr_prod(a: &M4, b: &M4, c: &M4) -> f64 {
    debug_assert!((0..4).all(|j| b[(3, j)] == 0.0) && (0..3).all(|j| a[(3, j)] == 0.0));
    let mut s = 0.0;
    for i in 0..3 {
        for j in 0..4 {
            let p = a[(i, 0)] * b[(0, j)] + a[(i, 1)] * b[(1, j)] + a[(i, 2)] * b[(2, j)];
            s += p * c[(j, i)];
        }
    }
    s
}

/// `vee` of an `se(3)` matrix: `(ω, v)`.
fn vee6(m: &M4) -> [f64; 6] {
    let w = vee_skew3(m);
    let t = translation(m);
    [w[0], w[1], w[2], t[0], t[1], t[2]]
}

/// Inverse of a rigid transform `[[R, p], [0, 1]]`.
fn se3_inverse(m: &M4) -> M4 {
    let r = m.fixed_view::<3, 3>(0, 0).transpose();
    let p = -(r * translation(m));
    let mut out = M4::identity();
    out.fixed_view_mut::<3, 3>(0, 0).copy_from(&r);
    for k in 0..3 {
        out[(k, 3)] = p[k];
    }
    out
}

/// Rows `K` (stationarity), columns `X` (`ξ_c`) of the sub-diagonal block.
type Low = SMatrix<f64, 4, 6>;
/// Six columns of a block (the `δm` columns).
type B6 = SMatrix<f64, B, 6>;

/// The lifted system before factorisation.
///
/// The off-diagonal blocks are mostly constant: block row `c` couples to block `c − 1`
/// through `−ξ_c` in its forward rows and through the bracket terms `low[c]` in its
/// stationarity rows (columns `ξ_c` only), and to block `c + 1` through `−δm_{c+1}` in its
/// backward rows (`U_c = −E_M`, `c ≤ N − 2`). Only `low` is stored.
#[derive(Default)]
pub(super) struct Lifted {
    n: usize,
    /// Border columns in use (`10 + gauges`); the rest are padding.
    g: usize,
    diag: Vec<Blk>,
    /// Rows `K` of block `c`, columns `X` of block `c − 1` (`c ≥ 1`; index `c`).
    low: Vec<Low>,
    /// Block rows, border columns.
    bcol: Vec<BCol>,
    /// Border rows, block columns.
    brow: Vec<BRow>,
    corner: GMat,
}

/// Right-hand side or solution of the lifted system.
#[derive(Clone, Default)]
pub(super) struct LVec {
    pub(super) blocks: Vec<BVec>,
    pub(super) border: GVec,
}

impl LVec {
    /// `n` zero blocks and a zero border, reusing the allocation.
    pub(super) fn reset(&mut self, n: usize) {
        self.blocks.clear();
        self.blocks.resize(n, BVec::zeros());
        self.border = GVec::zeros();
    }

    pub(super) fn norm(&self) -> f64 {
        (self.blocks.iter().map(|b| b.norm_squared()).sum::<f64>() + self.border.norm_squared())
            .sqrt()
    }
}

impl Lifted {
    /// An all-zero system of `n` cells and `g` border columns, reusing the allocations.
    fn reset(&mut self, n: usize, g: usize) {
        self.n = n;
        self.g = g;
        self.diag.clear();
        self.diag.resize(n, Blk::zeros());
        self.low.clear();
        self.low.resize(n, Low::zeros());
        self.bcol.clear();
        self.bcol.resize(n, BCol::zeros());
        self.brow.clear();
        self.brow.resize(n, BRow::zeros());
        self.corner = GMat::zeros();
    }

    /// `v −= L_c x` for the sub-diagonal block of row `c` (`x` the block `c − 1`).
    fn sub_lower(&self, c: usize, x: &BVec, v: &mut BVec) {
        let xi = x.fixed_rows::<6>(X0);
        let k = self.low[c] * xi;
        for i in 0..4 {
            v[K0 + i] -= k[i];
        }
        for i in 0..6 {
            v[X0 + i] += xi[i];
        }
    }

    /// `out = M x`.
    pub(super) fn apply(&self, x: &LVec, out: &mut LVec) {
        let n = self.n;
        let blocks = &mut out.blocks;
        blocks.clear();
        let mut border = self.corner * x.border;
        for c in 0..n {
            let mut y = self.diag[c] * x.blocks[c] + self.bcol[c] * x.border;
            if c >= 1 {
                let mut t = BVec::zeros();
                self.sub_lower(c, &x.blocks[c - 1], &mut t);
                y -= t;
            }
            if c + 1 < n {
                // U_c = −E_M.
                for k in 0..6 {
                    y[M0 + k] -= x.blocks[c + 1][M0 + k];
                }
            }
            blocks.push(y);
            border += self.brow[c] * x.blocks[c];
        }
        out.border = border;
    }

    /// Fills the auxiliary unknowns of `x` (`ξ_{c+1}` and `δm_c` of every block) from its
    /// others so that the forward and backward recursion rows of `M x` vanish: `ξ` by a
    /// forward sweep from `ξ_0 = 0`, `δm` by a backward one (both rows have the identity on
    /// their own unknown). `M x` then holds `J v` in its other rows, `v` the unknowns of the
    /// model that `x` lifts ([`super::lifted_factor`]).
    pub(super) fn complete(&self, x: &mut LVec) {
        let n = self.n;
        let mut xi_prev = SVector::<f64, 6>::zeros();
        for c in 0..n {
            let xc = &mut x.blocks[c];
            for k in 0..6 {
                xc[X0 + k] = 0.0;
                xc[M0 + k] = 0.0;
            }
            let r = self.diag[c] * *xc + self.bcol[c] * x.border;
            for k in 0..6 {
                xc[X0 + k] = -(r[X0 + k] - xi_prev[k]);
            }
            xi_prev = xc.fixed_rows::<6>(X0).into_owned();
        }
        let mut m_next = SVector::<f64, 6>::zeros();
        for c in (0..n).rev() {
            let xc = &mut x.blocks[c];
            let r = self.diag[c] * *xc + self.bcol[c] * x.border;
            for k in 0..6 {
                xc[M0 + k] = -(r[M0 + k] - m_next[k]);
            }
            m_next = if c >= 1 {
                xc.fixed_rows::<6>(M0).into_owned()
            } else {
                SVector::zeros()
            };
        }
    }

    /// Largest entry of the tridiagonal blocks and the corner (the constant off-diagonal
    /// entries are ±1).
    pub(super) fn amax(&self) -> f64 {
        self.diag
            .iter()
            .map(|b| b.amax())
            .chain(self.low.iter().map(|b| b.amax()))
            .fold(self.corner.amax().max(1.0), f64::max)
    }
}

/// Block LU factors of [`Lifted`].
///
/// Only the `g` border columns in use are eliminated: the padding columns of `C_c` are zero,
/// so their eliminated columns are zero as well, and every product below skips them. The
/// factors are written in place into buffers kept across Newton steps ([`block_lu`]).
#[derive(Default)]
pub(super) struct Factor {
    /// The LU factors of the pivot blocks `S_c` (unit lower and upper triangle in one block).
    lu: Vec<Blk>,
    /// Their row interchanges ([`block_lu`]).
    perm: Vec<[usize; B]>,
    /// `S_c⁻¹ U_c` (its six nonzero columns, the `δm` columns).
    yu: Vec<B6>,
    /// `S_c⁻¹ C'_c` (border columns after elimination; the padding columns stay zero).
    yc: Vec<BCol>,
    /// Border rows after elimination of the earlier blocks.
    rb: Vec<BRow>,
    corner: Option<nalgebra::LU<f64, Const<G>, Const<G>>>,
}

/// LU factorisation with partial pivoting of a pivot block, in place: the unit lower
/// triangle below the diagonal, the upper triangle on and above it, and in `perm[i]` the
/// row interchanged with row `i` at step `i`. The operations are those of
/// `nalgebra::LU::new` in the same order (same numbers), without its generic views: the
/// blocks are small and their factorisation is the inner loop of every Newton step.
fn block_lu(a: &mut Blk, perm: &mut [usize; B]) {
    let m = a.as_mut_slice();
    for i in 0..B {
        // Pivot: the first entry of largest modulus in column i at or below the diagonal.
        let col = i * B;
        let (mut piv, mut best) = (i, m[col + i].abs());
        for r in i + 1..B {
            let v = m[col + r].abs();
            if v > best {
                best = v;
                piv = r;
            }
        }
        perm[i] = i;
        let diag = m[col + piv];
        if diag == 0.0 {
            continue;
        }
        if piv != i {
            perm[i] = piv;
            for k in 0..B {
                m.swap(k * B + i, k * B + piv);
            }
        }
        let inv = 1.0 / diag;
        for r in i + 1..B {
            m[col + r] *= inv;
        }
        for k in i + 1..B {
            let ck = k * B;
            let f = m[ck + i];
            for r in i + 1..B {
                m[ck + r] += -f * m[col + r];
            }
        }
    }
}

/// Solve `S x = b` in place for the first `ncols` columns of `b` (column-major, `B` rows
/// each) with the factors of [`block_lu`]: the interchanges, then the unit lower and the
/// upper triangle, as `nalgebra::LU::solve_mut`. False where a diagonal entry of the
/// upper triangle is zero.
fn block_solve(a: &Blk, perm: &[usize; B], b: &mut [f64], ncols: usize) -> bool {
    let m = a.as_slice();
    for j in 0..ncols {
        let x = &mut b[j * B..(j + 1) * B];
        for i in 0..B {
            x.swap(i, perm[i]);
        }
        for i in 0..B - 1 {
            let c = x[i];
            // A zero entry adds nothing (the right-hand sides are sparse: the `δm` columns
            // have one nonzero, the border columns a few).
            if c == 0.0 {
                continue;
            }
            let col = &m[i * B..(i + 1) * B];
            for r in i + 1..B {
                x[r] += -c * col[r];
            }
        }
        for i in (0..B).rev() {
            let d = m[i * B + i];
            if d == 0.0 {
                return false;
            }
            let c = x[i] / d;
            x[i] = c;
            if c == 0.0 {
                continue;
            }
            let col = &m[i * B..(i + 1) * B];
            for r in 0..i {
                x[r] += -c * col[r];
            }
        }
    }
    true
}

fn pivot_ok(lu: &Blk) -> bool {
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    for i in 0..B {
        let v = lu[(i, i)].abs();
        lo = lo.min(v);
        hi = hi.max(v);
    }
    hi > 0.0 && lo.is_finite() && lo > PIVOT_RATIO * hi
}

/// `Σ_k a[(i, k)] b[(k, j)]`, summed in the order of nalgebra's matrix product (so that
/// restricting a product to its nonzero rows and columns gives the same numbers).
#[inline(always)]
fn dot_rc<const R: usize, const C: usize>(
    a: &SMatrix<f64, R, B>,
    i: usize,
    b: &SMatrix<f64, B, C>,
    j: usize,
) -> f64 {
    let mut acc = a[(i, 0)] * b[(0, j)];
    for k in 1..B {
        acc += a[(i, k)] * b[(k, j)];
    }
    acc
}

impl Factor {
    /// Factor `sys` into `self`, reusing the allocations.
    pub(super) fn factor(&mut self, sys: &Lifted) -> Result<(), SolverError> {
        let n = sys.n;
        let g = sys.g;
        let singular = || SolverError::SingularJacobian { iteration: 0 };
        self.corner = None;
        self.lu.resize(n, Blk::zeros());
        self.perm.resize(n, [0; B]);
        self.yu.resize(n, B6::zeros());
        self.yc.resize(n, BCol::zeros());
        self.rb.resize(n, BRow::zeros());
        let mut corner = sys.corner;
        self.lu[0].copy_from(&sys.diag[0]);
        self.yc[0].copy_from(&sys.bcol[0]);
        self.rb[0].copy_from(&sys.brow[0]);
        let mut em = B6::zeros();
        for k in 0..6 {
            em[(M0 + k, k)] = -1.0;
        }
        for c in 0..n {
            block_lu(&mut self.lu[c], &mut self.perm[c]);
            let (f, perm) = (&self.lu[c], &self.perm[c]);
            if !pivot_ok(f) {
                return Err(singular());
            }
            // S⁻¹U with U = −E_M: six columns.
            let u = &mut self.yu[c];
            if c + 1 < n {
                *u = em;
                if !block_solve(f, perm, u.as_mut_slice(), 6) {
                    return Err(singular());
                }
            } else {
                *u = B6::zeros();
            }
            let y = &mut self.yc[c];
            if !block_solve(f, perm, y.as_mut_slice(), g) {
                return Err(singular());
            }
            {
                let (y, r) = (&self.yc[c], &self.rb[c]);
                // corner −= R_c y (rows and columns past `g` are zero).
                for j in 0..g {
                    for i in 0..g {
                        corner[(i, j)] -= dot_rc(r, i, y, j);
                    }
                }
            }
            if c + 1 < n {
                let low = &sys.low[c + 1];
                // S_{c+1} = D_{c+1} − L_{c+1} S⁻¹U: only the δm columns change. (Written in
                // place: the next blocks are copied once from the system.)
                let (yc_done, yc_next) = self.yc.split_at_mut(c + 1);
                let (rb_done, rb_next) = self.rb.split_at_mut(c + 1);
                let (y, u, r) = (&yc_done[c], &self.yu[c], &rb_done[c]);
                let (s, cb, rn) = (&mut self.lu[c + 1], &mut yc_next[0], &mut rb_next[0]);
                s.copy_from(&sys.diag[c + 1]);
                cb.copy_from(&sys.bcol[c + 1]);
                rn.copy_from(&sys.brow[c + 1]);
                let ux = u.fixed_rows::<6>(X0);
                let lk = low * ux;
                for j in 0..6 {
                    for i in 0..4 {
                        s[(K0 + i, M0 + j)] -= lk[(i, j)];
                    }
                    for i in 0..6 {
                        s[(X0 + i, M0 + j)] += ux[(i, j)];
                    }
                }
                // C'_{c+1} = C_{c+1} − L_{c+1} y.
                let yx = y.fixed_rows::<6>(X0);
                let ly = low * yx;
                for j in 0..g {
                    for i in 0..4 {
                        cb[(K0 + i, j)] -= ly[(i, j)];
                    }
                    for i in 0..6 {
                        cb[(X0 + i, j)] += yx[(i, j)];
                    }
                }
                // R_{c+1} = B_{c+1} − R_c S⁻¹U: only the δm columns change.
                for j in 0..6 {
                    for i in 0..g {
                        rn[(i, M0 + j)] -= dot_rc(r, i, u, j);
                    }
                }
            }
        }
        let corner = corner.lu();
        if !corner.is_invertible() {
            return Err(singular());
        }
        self.corner = Some(corner);
        Ok(())
    }

    /// Solve `sys x = rhs` into `buf.x` with one step of iterative refinement against the
    /// lifted system; false where a pivot is zero or the refined residual stays above
    /// `1e-9 |rhs| + 1e-13 max|M| |x|` (the second term is the round-off floor near
    /// convergence, where the right-hand side is tiny).
    pub(super) fn solve_refined(&self, sys: &Lifted, rhs: &LVec, buf: &mut SolveBuffers) -> bool {
        if !self.solve(sys, rhs, &mut buf.y, &mut buf.x) {
            return false;
        }
        sys.apply(&buf.x, &mut buf.ax);
        for (a, b) in buf.ax.blocks.iter_mut().zip(&rhs.blocks) {
            *a = b - *a;
        }
        buf.ax.border = rhs.border - buf.ax.border;
        if !self.solve(sys, &buf.ax, &mut buf.y, &mut buf.dx) {
            return false;
        }
        let x = &mut buf.x;
        for (a, b) in x.blocks.iter_mut().zip(&buf.dx.blocks) {
            *a += b;
        }
        x.border += buf.dx.border;
        sys.apply(x, &mut buf.ax);
        let ax = &buf.ax;
        let mut err = (ax.border - rhs.border).norm_squared();
        for (a, b) in ax.blocks.iter().zip(&rhs.blocks) {
            err += (a - b).norm_squared();
        }
        let scale = 1e-9 * rhs.norm() + 1e-13 * sys.amax() * x.norm();
        err.sqrt() <= scale.max(1e-300)
    }

    /// `(sign, ln|det|)` of the factored lifted matrix: the pivot blocks' LU diagonals and
    /// row interchanges, and the border's Schur complement (its padding is the identity).
    /// Eliminating the auxiliary unknowns `ξ`, `δm` (unit block-bidiagonal recursions, whose
    /// determinant is 1) leaves the dense Jacobian, so `ln|det|` is the dense one's and the
    /// sign differs from it by that of a fixed reordering (the same for every state of a
    /// mesh): a sign change along a path is the dense Jacobian's.
    pub(super) fn determinant(&self, n: usize) -> (f64, f64) {
        let (mut sign, mut log) = (1.0f64, 0.0f64);
        for c in 0..n {
            let (lu, perm) = (&self.lu[c], &self.perm[c]);
            for i in 0..B {
                let d = lu[(i, i)];
                sign *= d.signum();
                log += d.abs().ln();
                if perm[i] != i {
                    sign = -sign;
                }
            }
        }
        match &self.corner {
            Some(corner) => {
                let d = corner.determinant();
                (sign * d.signum(), log + d.abs().ln())
            }
            None => (0.0, f64::NEG_INFINITY),
        }
    }

    /// Solve `sys x = rhs` into `x` (`y` a work buffer); false if a pivot is zero.
    pub(super) fn solve(&self, sys: &Lifted, rhs: &LVec, y: &mut Vec<BVec>, x: &mut LVec) -> bool {
        let n = sys.n;
        let g = sys.g;
        let Some(corner) = &self.corner else {
            return false;
        };
        y.clear();
        let mut gb = rhs.border;
        let mut r = rhs.blocks[0];
        for c in 0..n {
            let mut yc = r;
            if !block_solve(&self.lu[c], &self.perm[c], yc.as_mut_slice(), 1) {
                return false;
            }
            // gb −= R_c yc (rows past `g` are zero).
            for i in 0..g {
                let rb = &self.rb[c];
                let mut acc = rb[(i, 0)] * yc[0];
                for k in 1..B {
                    acc += rb[(i, k)] * yc[k];
                }
                gb[i] -= acc;
            }
            if c + 1 < n {
                r = rhs.blocks[c + 1];
                sys.sub_lower(c + 1, &yc, &mut r);
            }
            y.push(yc);
        }
        let Some(xg) = corner.solve(&gb) else {
            return false;
        };
        x.reset(n);
        for c in (0..n).rev() {
            let mut v = y[c] - self.yc[c] * xg;
            if c + 1 < n {
                v -= self.yu[c] * x.blocks[c + 1].fixed_rows::<6>(M0);
            }
            x.blocks[c] = v;
        }
        x.border = xg;
        true
    }
}

/// Buffers of one Newton step, kept across the steps of a thread (a step of a few hundred
/// cells assembles and factors about 2 MB).
#[derive(Default)]
struct Workspace {
    sys: Lifted,
    rhs: LVec,
    fac: Factor,
    buf: SolveBuffers,
}

/// Buffers of [`Factor::solve_refined`]: its solution `x`, and work space.
#[derive(Default)]
pub(super) struct SolveBuffers {
    y: Vec<BVec>,
    pub(super) x: LVec,
    dx: LVec,
    ax: LVec,
}

/// A vector of the model's unknowns (or equations) in the lifted layout, the inverse of
/// [`unlift_layout`] on them, zero in the auxiliary unknowns `ξ`, `δm` (and rows).
pub(super) fn lift_layout(n: usize, np: usize, ng: usize, lo: usize, v: &DVector<f64>) -> LVec {
    let mut x = LVec::default();
    x.reset(n);
    for c in 0..n {
        let b = &mut x.blocks[c];
        for i in 0..4 {
            b[K0 + i] = v[4 * c + i];
        }
        if c + 1 < n {
            b[L0] = v[lo + c + 1];
        }
    }
    for k in 0..3 {
        x.border[k] = v[4 * n + k];
    }
    for k in 0..6 + ng {
        x.border[3 + k] = v[np + k];
    }
    x.border[9 + ng] = v[lo];
    x
}

/// The model's unknowns (or equations) of a lifted vector: the curvature unknowns
/// (stationarity rows) of cell `c` and the wall multiplier (row) of node `c + 1` from block
/// `c`, and `(r0, μ, ν, λ_0)` from the border; the auxiliary `ξ`, `δm` are dropped. `n` cells,
/// `np` primal unknowns, `ng` gauges, `lo` the offset of `λ`.
pub(super) fn unlift_layout(n: usize, np: usize, ng: usize, lo: usize, x: &LVec) -> DVector<f64> {
    let mut dz = DVector::zeros(lo + n);
    for c in 0..n {
        for i in 0..4 {
            dz[4 * c + i] = x.blocks[c][K0 + i];
        }
        if c + 1 < n {
            dz[lo + c + 1] = x.blocks[c][L0];
        }
    }
    for k in 0..3 {
        dz[4 * n + k] = x.border[k];
    }
    for k in 0..6 + ng {
        dz[np + k] = x.border[3 + k];
    }
    dz[lo] = x.border[9 + ng];
    dz
}

thread_local! {
    static WORKSPACE: std::cell::RefCell<Workspace> = std::cell::RefCell::new(Workspace::default());
}

impl EnclosedModel {
    /// The KKT residual `F(z)` and the semismooth Newton step `dz` solving `J dz = −F` with
    /// the Jacobian of [`Self::evaluate`], in `O(N)` (see [`super::lifted`]). Returns
    /// [`SolverError::SingularJacobian`] when the block factorisation cannot be trusted
    /// (then the dense Jacobian is the fallback).
    pub fn newton_step(&self, z: &[f64]) -> Result<(DVector<f64>, DVector<f64>), SolverError> {
        // One second-order chain and one adjoint sweep for the residual and the system.
        let ch = self.checked_chain(z)?;
        let adj = self.adjoints(&ch, z);
        let f = self.residual_with(&ch, &adj, z);
        WORKSPACE.with(|w| {
            let mut w = w.borrow_mut();
            let w = &mut *w;
            self.lifted_system(z, &ch, &adj, &f, &mut w.sys, &mut w.rhs);
            let (sys, rhs) = (&w.sys, &w.rhs);
            w.fac.factor(sys)?;
            if !w.fac.solve_refined(sys, rhs, &mut w.buf) {
                return Err(SolverError::SingularJacobian { iteration: 0 });
            }
            let x = &w.buf.x;
            Ok((f, self.unlift(x)))
        })
    }

    /// The step in the model's unknowns from the lifted solution ([`unlift_layout`]).
    pub(super) fn unlift(&self, x: &LVec) -> DVector<f64> {
        unlift_layout(
            self.cells(),
            self.n_primal(),
            self.n_gauge(),
            self.lambda_offset(),
            x,
        )
    }

    /// Assemble the lifted system and its right-hand side `−F` (see the module docs).
    pub(super) fn lifted_system(
        &self,
        z: &[f64],
        ch: &super::model::Chain,
        adj: &[M4],
        f: &DVector<f64>,
        sys: &mut Lifted,
        rhs: &mut LVec,
    ) {
        let n = self.cells();
        let np = self.n_primal();
        let ng = self.n_gauge();
        let g = 10 + ng;
        debug_assert!(g <= G, "border of {g} > {G}");
        let lo = self.lambda_offset();
        let (gr0, gmu, gnu, gl0) = (0usize, 3usize, 9usize, 9 + ng);
        let basis = se3_basis();
        let r0 = self.start_point(z);
        let p: Vec<V3> = (0..=n).map(|j| translation(&ch.prefix[j])).collect();
        let r: Vec<V3> = p.iter().map(|pj| r0 + pj).collect();
        let lam = &z[lo..lo + n];
        let sigma = self.wall_scale();
        let wall = self.wall();
        // The complementarity row's slopes in `λ_j` and `σ g_j` ([`super::model::Complementarity::eval`]).
        let slopes: Vec<(f64, f64)> = (0..n)
            .map(|j| {
                let (_, da, db) =
                    self.wall_row(j, lam[j] + self.pull_impulse(j), sigma * wall.gap(&r[j]));
                (da, db)
            })
            .collect();
        let mu = self.closure_multipliers(z);
        let kmu = Self::closure_functional(&mu);
        let gauges = self.gauge_rows();

        sys.reset(n, g);
        rhs.reset(n);

        for c in 0..n {
            let (jet_e, jet_d, jet_dd) = (&ch.e[c], &ch.d[c], &ch.dd[c]);
            let pc = &ch.prefix[c];
            let pinv = se3_inverse(pc);
            let einv = se3_inverse(jet_e);
            let mc = ch.prefix[c + 1] * adj[c];
            let h = 0.5 * self.cell_length(c);
            // b_ci and the spatial B_ci.
            let bm: [M4; 4] = std::array::from_fn(|i| pc * jet_d[i] * einv * pinv);
            let b: [[f64; 6]; 4] = std::array::from_fn(|i| vee6(&bm[i]));
            let pd: [M4; 4] = std::array::from_fn(|i| pc * jet_d[i] * einv);
            let d = &mut sys.diag[c];
            // Stationarity rows.
            for i in 0..4 {
                let a = 4 * c + i;
                rhs.blocks[c][K0 + i] = -f[a];
                d[(K0 + i, K0 + i)] += h * self.d_gauss_at(2 * c + i / 2);
                for i2 in 0..4 {
                    d[(K0 + i, K0 + i2)] +=
                        tr_prod(pc, &jet_dd[i][i2], &adj[c]) - tr_prod(&pd[i], &jet_d[i2], &adj[c]);
                }
                for k in 0..6 {
                    d[(K0 + i, M0 + k)] = b[i][k];
                }
                if c >= 1 {
                    for k in 0..6 {
                        let br = bracket(&basis[k], &bm[i]);
                        sys.low[c][(K0 + i, k)] = tr4(&br, &mc);
                    }
                }
                for (kg, (row, idx)) in gauges.iter().enumerate() {
                    if idx.is_none() {
                        sys.bcol[c][(K0 + i, gnu + kg)] = -row[a];
                    }
                }
            }
            // Forward recursion: ξ_{c+1} − ξ_c − Σ b_ci δκ_ci = 0.
            for k in 0..6 {
                d[(X0 + k, X0 + k)] = 1.0;
                for i in 0..4 {
                    d[(X0 + k, K0 + i)] = -b[i][k];
                }
            }
            // Backward recursion.
            for k in 0..6 {
                d[(M0 + k, M0 + k)] = 1.0;
            }
            if c + 1 < n {
                let j = c + 1;
                let lj = lam[j];
                // The wall at node j: `∇g` paired with se(3), `w = −2u` on the sphere, and
                // its derivatives in ξ and r0.
                let wp = wall.node_pairing(&r0, &p[j]);
                let (u, gj) = (wp.w, wp.gradient);
                for k in 0..6 {
                    d[(M0 + k, L0)] = u[k];
                    for l in 0..6 {
                        d[(M0 + k, X0 + l)] = lj * wp.dw_xi[(k, l)];
                    }
                    for l in 0..3 {
                        sys.bcol[c][(M0 + k, gr0 + l)] = lj * wp.dw_r0[(k, l)];
                    }
                }
                // Wall row of node j.
                rhs.blocks[c][L0] = -f[lo + j];
                let (da, db) = slopes[j];
                for k in 0..6 {
                    d[(L0, X0 + k)] = db * sigma * u[k];
                }
                for l in 0..3 {
                    sys.bcol[c][(L0, gr0 + l)] = db * sigma * gj[l];
                }
                d[(L0, L0)] = da;
                // r0 stationarity: −Σ_j δλ_j ∇g_j + λ_j ∇²g_j (δr0 + δp_j), δp_j = −hat(p_j)ω + v.
                for k in 0..3 {
                    sys.brow[c][(gr0 + k, L0)] = -gj[k];
                    for l in 0..3 {
                        sys.brow[c][(gr0 + k, X0 + l)] = -lj * wp.dgrad_xi[(k, l)];
                        sys.brow[c][(gr0 + k, X0 + 3 + l)] += -lj * wp.dgrad_xi[(k, 3 + l)];
                    }
                }
            } else {
                // δm_{N−1} = −hat(ξ_N)P_N K(μ) − P_N K(δμ), paired with se(3).
                let pn = &ch.prefix[n];
                for k in 0..6 {
                    for l in 0..6 {
                        d[(M0 + k, X0 + l)] = tr4(&(basis[k] * basis[l] * pn), &kmu);
                    }
                    for l in (0..6).filter(|&l| l != TWIST_ROW) {
                        let mut e = [0.0; 6];
                        e[l] = 1.0;
                        let kl = Self::closure_functional(&e);
                        sys.bcol[c][(M0 + k, gmu + l)] = tr4(&(basis[k] * pn), &kl);
                    }
                }
                d[(L0, L0)] = 1.0;
                // Closure rows: δF = −(vee skew(hat ω R_N), hat ω p_N + v).
                for l in 0..6 {
                    let m = basis[l] * pn;
                    let (w, t) = (closure_rotation(&m), translation(&m));
                    let v = [w[0], w[1], w[2], t[0], t[1], t[2]];
                    for k in (0..6).filter(|&k| k != TWIST_ROW) {
                        sys.brow[c][(gmu + k, X0 + l)] = -v[k];
                    }
                }
            }
            // Gauge rows.
            for (kg, (row, idx)) in gauges.iter().enumerate() {
                if idx.is_none() {
                    for i in 0..4 {
                        sys.brow[c][(gnu + kg, K0 + i)] = -row[4 * c + i];
                    }
                }
            }
        }
        // Corner: r0 stationarity, closure (none), gauges, wall row of node 0.
        let mut hess_sum = M3::zeros();
        for j in (0..n).filter(|&j| lam[j] != 0.0) {
            hess_sum -= wall.hessian(&r[j]) * lam[j];
        }
        let g0 = wall.gradient(&r0);
        for k in 0..3 {
            for l in 0..3 {
                sys.corner[(gr0 + k, gr0 + l)] += hess_sum[(k, l)];
            }
            sys.corner[(gr0 + k, gl0)] = -g0[k];
            rhs.border[gr0 + k] = -f[4 * n + k];
        }
        for k in 0..6 {
            rhs.border[gmu + k] = -f[np + k];
        }
        // The twist row is `μ_twist = 0` ([`TWIST_ROW`]).
        sys.corner[(gmu + TWIST_ROW, gmu + TWIST_ROW)] = 1.0;
        for (kg, (_, idx)) in gauges.iter().enumerate() {
            rhs.border[gnu + kg] = -f[np + 6 + kg];
            if let Some(i) = idx {
                let k = i - 4 * n;
                sys.corner[(gnu + kg, gr0 + k)] = -1.0;
                sys.corner[(gr0 + k, gnu + kg)] = -1.0;
            }
        }
        rhs.border[gl0] = -f[lo];
        // Padding of the border: identity rows, zero right-hand side.
        for k in g..G {
            sys.corner[(k, k)] = 1.0;
        }
        let (da0, db0) = slopes[0];
        for l in 0..3 {
            sys.corner[(gl0, gr0 + l)] = db0 * sigma * g0[l];
        }
        sys.corner[(gl0, gl0)] = da0;
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// Pseudo-random entries in `[-1, 1)` (a fixed-seed LCG; the wall's tests use it too).
    pub(crate) fn filler(seed: u64) -> impl FnMut() -> f64 {
        let mut s = seed;
        move || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        }
    }

    /// [`block_lu`] and [`block_solve`] give nalgebra's LU factors and solutions to the last
    /// bit (same operations in the same order), on random blocks, on blocks shaped like the
    /// lifted system's (identity rows, a zero first pivot that forces interchanges), and they
    /// report a zero pivot.
    #[test]
    fn block_lu_matches_nalgebra_bitwise() {
        let mut next = filler(7);
        for trial in 0..30 {
            let mut a = Blk::from_fn(|_, _| next());
            if trial % 3 == 1 {
                // Rows like the forward/backward recursions: identity plus a few couplings.
                for i in X0..L0 {
                    for j in 0..B {
                        a[(i, j)] = if i == j { 1.0 } else { 0.0 };
                    }
                    a[(i, K0 + i % 4)] = next();
                }
                a[(0, 0)] = 0.0;
            }
            let mut rhs = BCol::from_fn(|_, _| next());
            let reference = a.lu();
            let mut lu = a;
            let mut perm = [0; B];
            block_lu(&mut lu, &mut perm);
            let (l, u) = (reference.l(), reference.u());
            for i in 0..B {
                for j in 0..B {
                    let want = if i > j { l[(i, j)] } else { u[(i, j)] };
                    assert_eq!(
                        lu[(i, j)].to_bits(),
                        want.to_bits(),
                        "trial {trial} ({i}, {j})"
                    );
                }
            }
            let want = reference.solve(&rhs).expect("invertible");
            assert!(block_solve(&lu, &perm, rhs.as_mut_slice(), G));
            for (x, w) in rhs.iter().zip(want.iter()) {
                assert_eq!(x.to_bits(), w.to_bits(), "trial {trial}");
            }
        }
        // A singular block: a zero column.
        let mut a = Blk::from_fn(|_, _| next());
        for i in 0..B {
            a[(i, 5)] = 0.0;
        }
        let mut perm = [0; B];
        block_lu(&mut a, &mut perm);
        assert!(!pivot_ok(&a));
        let mut b = BVec::from_fn(|_, _| next());
        assert!(!block_solve(&a, &perm, b.as_mut_slice(), 1));
    }
}
