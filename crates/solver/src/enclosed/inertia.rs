//! The stability index of an enclosed state from the inertia of its bordered KKT matrix,
//! without an eigen-decomposition.
//!
//! The index is the number of eigenvalues below a threshold of the mass-scaled Hessian of
//! the Lagrangian `W` restricted to the tangent space `{y : B y = 0}` of the closure, the
//! gauges and the strongly active wall constraints (second-order optimality, Sec. 3.2; the
//! same operator as `EnclosedState::tangent_hessian`). With `r` independent rows `B`, the
//! bordered matrix `K(σ) = [[W − σI, Bᵀ], [B, 0]]` has inertia
//! `(n_−, n_+, n_0) = inertia(Zᵀ(W − σI)Z) + (r, r, 0)` (Sylvester's law of inertia with
//! Haynsworth's additivity, `Z` an orthonormal basis of the tangent space), so the number of
//! tangent eigenvalues below `σ` is `n_−(K(σ)) − r`. `n_−` comes from a symmetric indefinite
//! `LDLᵀ` factorisation with Bunch–Kaufman pivoting (J. R. Bunch, L. Kaufman, Math. Comp. 31,
//! 1977): `D` has 1×1 and 2×2 blocks whose signs are read off directly. Dependent constraint
//! rows are dropped first (Gram–Schmidt with a relative threshold `1e-10`, the rank decision
//! of the dense reduction), so that `K` is nonsingular whenever `σ` is not an eigenvalue.
//!
//! Cost: `(n + r)³/3` flops for the factorisation (`n = 4N + 3`), against the dense
//! reduction's projector products and a full symmetric eigen-decomposition of size `n`.
//!
//! # The index carried to a finer level
//!
//! The sign of the determinant of the semismooth Newton Jacobian `J` at a converged state
//! ([`LiftedFactor`], `O(N)`) gives the parity of the index: `sign det J = c (−1)^index`.
//! The rows of a free node (`λ_j = 0`, slope `1`) factor out. A wall node's row is
//! `σ ∇g_j` (`σ > 0`) and its column `∂F/∂λ_j = −∇g_jᵀ`: turning the column and scaling
//! the row by `1/σ` makes it a symmetric border row of `K(0)` above at the cost of a factor
//! `−σ`, and `sign det K(0) = (−1)^{index + r}` counts that row once more, so the wall rows
//! leave the sign alone. The closure and gauge rows enter the same way up to a sign of their
//! own, `c`, fixed by which rows the model has: on every level of one loop the same
//! (`c = −1` for a uniform rod with the phase condition, `+1` for a two-segment rod; the test
//! below checks it on every level of uniform and two-segment loops of both parities). It
//! holds where the wall rows of `J` are the strongly active ones of the index; a node on
//! the wall with a vanishing impulse, a dependent row or a zero eigenvalue can break it.
//! [`EnclosedState::index_beside`] therefore only uses it to carry a count from a coarser
//! level of the same loop, comparing the two levels' signs (so `c` cancels), and counts
//! again where they differ: a level whose contact sits differently on its nodes may have
//! another index than the coarser one, and the state reported is the finer one.

use nalgebra::DMatrix;
use rodloop_continuation::Factorization;

use super::lifted_factor::LiftedFactor;
use super::solve::EnclosedState;
use crate::SolverError;

/// Inertia `(negative, zero, positive)` of the symmetric matrix `a` (its lower triangle is
/// read) by `LDLᵀ` with Bunch–Kaufman partial pivoting. A pivot of absolute value at most
/// `zero_tol` counts as zero.
pub fn symmetric_inertia(mut a: DMatrix<f64>, zero_tol: f64) -> (usize, usize, usize) {
    let n = a.nrows();
    // Symmetrise from the lower triangle: the updates below keep the full matrix.
    for j in 0..n {
        for i in j + 1..n {
            a[(j, i)] = a[(i, j)];
        }
    }
    let alpha = (1.0 + 17f64.sqrt()) / 8.0;
    let (mut neg, mut zero, mut pos) = (0, 0, 0);
    let swap = |a: &mut DMatrix<f64>, p: usize, q: usize| {
        if p != q {
            a.swap_rows(p, q);
            a.swap_columns(p, q);
        }
    };
    let mut k = 0;
    while k < n {
        let akk = a[(k, k)].abs();
        let (mut lam, mut r) = (0.0f64, k);
        for i in k + 1..n {
            if a[(i, k)].abs() > lam {
                lam = a[(i, k)].abs();
                r = i;
            }
        }
        if akk.max(lam) <= zero_tol {
            zero += 1;
            k += 1;
            continue;
        }
        let two = if akk >= alpha * lam {
            false
        } else {
            let mut sig = 0.0f64;
            for j in k..n {
                if j != r {
                    sig = sig.max(a[(r, j)].abs());
                }
            }
            if akk * sig >= alpha * lam * lam {
                false
            } else if a[(r, r)].abs() >= alpha * sig {
                swap(&mut a, k, r);
                false
            } else {
                swap(&mut a, k + 1, r);
                true
            }
        };
        if !two {
            let d = a[(k, k)];
            if d.abs() <= zero_tol {
                zero += 1;
            } else if d < 0.0 {
                neg += 1;
            } else {
                pos += 1;
            }
            if d != 0.0 {
                for j in k + 1..n {
                    let f = a[(j, k)] / d;
                    if f == 0.0 {
                        continue;
                    }
                    for i in k + 1..n {
                        a[(i, j)] -= f * a[(i, k)];
                    }
                }
            }
            k += 1;
        } else {
            let (p, q, s) = (a[(k, k)], a[(k + 1, k)], a[(k + 1, k + 1)]);
            let det = p * s - q * q;
            // Bunch–Kaufman 2×2 pivots have det < 0 (one eigenvalue of each sign).
            if det < 0.0 {
                neg += 1;
                pos += 1;
            } else if p + s < 0.0 {
                neg += 2;
            } else {
                pos += 2;
            }
            // A ← A − C D⁻¹ Cᵀ with C the two pivot columns below the block.
            let (ip, iq, is) = (s / det, -q / det, p / det);
            for j in k + 2..n {
                let (cj0, cj1) = (a[(j, k)], a[(j, k + 1)]);
                let w0 = ip * cj0 + iq * cj1;
                let w1 = iq * cj0 + is * cj1;
                for i in k + 2..n {
                    a[(i, j)] -= a[(i, k)] * w0 + a[(i, k + 1)] * w1;
                }
            }
            k += 2;
        }
    }
    (neg, zero, pos)
}

/// Indices of a maximal set of linearly independent rows of `a` (greedy modified
/// Gram–Schmidt in row order: a row is kept when its component orthogonal to the rows kept
/// before it exceeds `rel` times the largest row norm).
fn independent_rows(a: &DMatrix<f64>, rel: f64) -> Vec<usize> {
    let big = (0..a.nrows())
        .map(|i| a.row(i).norm())
        .fold(0.0f64, f64::max);
    let mut basis: Vec<nalgebra::RowDVector<f64>> = Vec::new();
    let mut kept = Vec::new();
    for i in 0..a.nrows() {
        let mut v = a.row(i).into_owned();
        for _ in 0..2 {
            for b in &basis {
                let c = v.dot(b);
                v -= b * c;
            }
        }
        let nv = v.norm();
        if nv > rel * big && nv > 0.0 {
            basis.push(v / nv);
            kept.push(i);
        }
    }
    kept
}

impl EnclosedState {
    /// Number of eigenvalues below `shift` of the mass-scaled Hessian of the Lagrangian on
    /// the tangent space of the closure, the gauges and the strongly active wall constraints
    /// (`λ_j > tol·max λ`), from the inertia of the bordered KKT matrix (module docs). The
    /// threshold is moved down by `1e-9·(10 max|W| + 1)` (the scale of the dense reduction),
    /// so that symmetry modes removed to round-off do not count.
    pub fn count_below(&self, tol: f64, shift: f64) -> Result<usize, SolverError> {
        let (w, b) = self.scaled_kkt_blocks(tol)?;
        let np = w.nrows();
        let rows = independent_rows(&b, 1e-10);
        let r = rows.len();
        let wmax = w.amax();
        let sigma = shift - 1e-9 * (10.0 * wmax + 1.0);
        let mut k = DMatrix::<f64>::zeros(np + r, np + r);
        k.view_mut((0, 0), (np, np)).copy_from(&w);
        for i in 0..np {
            k[(i, i)] -= sigma;
        }
        for (q, &row) in rows.iter().enumerate() {
            for i in 0..np {
                k[(np + q, i)] = b[(row, i)];
                k[(i, np + q)] = b[(row, i)];
            }
        }
        let (neg, _, _) = symmetric_inertia(k, 0.0);
        Ok(neg.saturating_sub(r))
    }

    /// The stability index: eigenvalues below `−1e-9·(10 max|W| + 1)` of the constrained,
    /// mass-scaled Hessian ([`Self::count_below`] at shift 0), in `O((5N)³/3)` without an
    /// eigen-decomposition.
    pub fn index(&self, tol: f64) -> Result<usize, SolverError> {
        self.count_below(tol, 0.0)
    }

    /// The sign of the determinant of the Newton Jacobian at this state (the lifted block
    /// factorisation, `O(N)`; module docs): `None` where a pivot block is nearly singular.
    pub fn jacobian_sign(&self) -> Option<f64> {
        LiftedFactor::new(&self.model, &self.z)
            .ok()
            .map(|f| f.det_sign())
            .filter(|s| *s != 0.0)
    }

    /// The index of this state ([`Self::index`]) given `coarse_index`, the index of
    /// `coarse`, the same loop on a coarser mesh: `coarse_index` where the two Newton
    /// Jacobians' determinants have the same sign (the same index parity, module docs),
    /// else (or where a sign is not available) counted here. The cost is `O(N)` where the
    /// levels agree and the dense count `O((5N)³/3)` where they do not. A change of the
    /// index by an even number between the levels is not seen.
    pub fn index_beside(
        &self,
        coarse: &EnclosedState,
        coarse_index: usize,
        tol: f64,
    ) -> Result<usize, SolverError> {
        match (self.jacobian_sign(), coarse.jacobian_sign()) {
            (Some(a), Some(b)) if a == b => Ok(coarse_index),
            _ => self.index(tol),
        }
    }

    /// The index of this state counted on `coarse`, the same loop on the mesh of half its
    /// cells, and carried here ([`Self::index_beside`]): the index of a cascade's or a
    /// trace's finest level, the state reported, at an eighth of the cost of counting it
    /// here where the two levels agree.
    pub fn index_via(&self, coarse: &EnclosedState, tol: f64) -> Result<usize, SolverError> {
        self.index_beside(coarse, coarse.index(tol)?, tol)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::enclosed::{solve_branch, EnclosedOptions, SurfaceSource};
    use crate::Stiffness;

    /// Negative eigenvalues of a symmetric matrix by the dense eigen-decomposition.
    fn dense_negatives(a: &DMatrix<f64>) -> usize {
        a.clone()
            .symmetric_eigenvalues()
            .iter()
            .filter(|&&v| v < 0.0)
            .count()
    }

    /// The two-segment stiffness of the cases below (Eq. (51), mild transitions).
    fn tanh() -> Stiffness {
        Stiffness::Tanh {
            d0: 1.0,
            d1: 0.5,
            s0: 0.3,
            s1: 0.8,
            gamma: 10.0,
        }
    }

    /// Uniform and two-segment loops, attached and lifted off, stable and unstable:
    /// `(η, L̄, stiffness)`.
    fn cases() -> Vec<(u32, f64, Stiffness)> {
        vec![
            (1, 1.4, Stiffness::uniform(1.0)),
            (2, 2.3, Stiffness::uniform(1.0)),
            (3, 3.2, Stiffness::uniform(1.0)),
            (2, 1.8, tanh()),
            (2, 1.6, tanh()),
            (2, 2.0, tanh()),
            (3, 2.6, tanh()),
        ]
    }

    /// The cascade of a case from the exact surface loop on `16(1 + η)` cells; `None` where
    /// Newton does not bring the start to an equilibrium (no case for the count).
    fn solved(eta: u32, lbar: f64, stiff: &Stiffness) -> Option<crate::enclosed::BranchSolve> {
        let l = rodloop_exact::paper_branch_loop(eta, lbar).unwrap();
        solve_branch(
            1.0,
            lbar,
            stiff,
            &SurfaceSource::Exact(l),
            16 * (1 + eta as usize),
            &EnclosedOptions::default(),
        )
        .ok()
    }

    #[test]
    fn bunch_kaufman_inertia_matches_the_eigenvalue_count() {
        // Pseudo-random symmetric matrices, among them saddle-point matrices with a zero
        // block (every diagonal pivot tiny: 2×2 pivots are needed).
        let mut seed = 12345u64;
        let mut next = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        };
        for trial in 0..40 {
            let n = 3 + trial % 17;
            let m = trial % 4;
            let mut a = DMatrix::<f64>::zeros(n + m, n + m);
            for i in 0..n {
                for j in 0..=i {
                    let v = next();
                    a[(i, j)] = v;
                    a[(j, i)] = v;
                }
            }
            for q in 0..m {
                for i in 0..n {
                    let v = next();
                    a[(n + q, i)] = v;
                    a[(i, n + q)] = v;
                }
            }
            if trial % 5 == 0 {
                // A zero diagonal: 1×1 pivots are all zero.
                for i in 0..n {
                    a[(i, i)] = 0.0;
                }
            }
            let (neg, zero, pos) = symmetric_inertia(a.clone(), 0.0);
            assert_eq!(zero, 0, "trial {trial}");
            assert_eq!(neg + pos, n + m);
            assert_eq!(neg, dense_negatives(&a), "trial {trial}");
        }
    }

    /// `sign det J = c (−1)^index` (module docs) on every level of uniform and two-segment
    /// loops, attached and lifted off, stable and unstable, with one `c` per kind of gauge
    /// (the phase condition of a uniform rod or not) on every level; and
    /// [`EnclosedState::index_beside`] carries a coarser level's count where the signs
    /// agree and counts again where they do not (a state of the other parity handed to it as
    /// the coarse level); a cascade's index ([`BranchSolve::index`]) is its finest level's.
    #[test]
    fn the_jacobian_sign_is_the_index_parity() {
        let mut cases = cases();
        cases.extend([
            (1, 1.3, tanh()),
            (3, 2.3, tanh()),
            (2, 1.6, Stiffness::uniform(1.0)),
            (2, 1.8, Stiffness::uniform(1.0)),
            (3, 2.6, Stiffness::uniform(1.0)),
        ]);
        // (gauge rows, fine state, its index, c) of every case.
        let mut fines = Vec::new();
        let mut constants: Vec<(usize, f64)> = Vec::new();
        for (eta, lbar, stiff) in cases {
            let Some(solved) = solved(eta, lbar, &stiff) else {
                continue;
            };
            for st in [&solved.quarter, &solved.coarse, &solved.fine] {
                let index = st.index(1e-6).unwrap();
                let sign = st.jacobian_sign().expect("a regular Jacobian");
                let c = if index % 2 == 0 { sign } else { -sign };
                let gauge = st.model.n_gauge();
                match constants.iter().find(|(g, _)| *g == gauge) {
                    Some(&(_, c0)) => {
                        assert_eq!(c, c0, "eta {eta}, lbar {lbar}, N {}", st.model.cells())
                    }
                    None => constants.push((gauge, c)),
                }
            }
            let (coarse, fine) = (&solved.coarse, &solved.fine);
            let (ic, ifine) = (coarse.index(1e-6).unwrap(), fine.index(1e-6).unwrap());
            assert_eq!(fine.index_beside(coarse, ic, 1e-6).unwrap(), ifine);
            assert_eq!(solved.index(1e-6).unwrap(), ifine);
            fines.push((fine.model.n_gauge(), solved.fine.clone(), ifine));
        }
        // Both kinds of gauge, and states of both parities of one kind.
        assert_eq!(constants.len(), 2, "{constants:?}");
        let mut crossed = 0;
        for (ga, a, ia) in &fines {
            for (gb, b, ib) in &fines {
                if ga == gb && (ia + ib) % 2 == 1 {
                    assert_eq!(a.index_beside(b, *ib, 1e-6).unwrap(), *ia);
                    crossed += 1;
                }
            }
        }
        let kinds: Vec<(usize, usize)> = fines.iter().map(|(g, _, i)| (*g, *i)).collect();
        assert!(crossed > 0, "(gauge rows, index): {kinds:?}");
    }

    /// The inertia counts against the dense reduction's eigenvalues
    /// ([`EnclosedState::stability`]): the index, and the count below shifts placed between
    /// consecutive eigenvalues (counts 1 to 7), on a lifted-off figure-eight, attached loops of
    /// branches 1 and 3, and a saddle (index 1) of branch 1 with Eq. (51) stiffness.
    #[test]
    fn inertia_counts_match_the_dense_eigenvalues() {
        let mut indices = Vec::new();
        for (eta, lbar, stiff) in cases() {
            let Some(solved) = solved(eta, lbar, &stiff) else {
                continue;
            };
            let st = solved.coarse;
            let (pw, _) = st.tangent_hessian(1e-6).unwrap();
            let mut vals: Vec<f64> = pw.symmetric_eigenvalues().iter().copied().collect();
            vals.sort_by(f64::total_cmp);
            let dense_index = vals.iter().filter(|&&v| v < 0.0).count();
            // The comparison means something only away from a zero eigenvalue.
            let gap = vals.iter().fold(f64::INFINITY, |a, v| a.min(v.abs()));
            assert!(gap > 1e-6, "eta {eta}, lbar {lbar}: eigenvalue {gap:e}");
            let index = st.index(1e-6).unwrap();
            assert_eq!(index, dense_index, "eta {eta}, lbar {lbar}: {vals:?}");
            assert_eq!(st.stability(1e-6).unwrap().0, index);
            indices.push(index);
            for k in 0..7 {
                let shift = 0.5 * (vals[k] + vals[k + 1]);
                if vals[k + 1] - vals[k] < 1e-6 * vals[k + 1].abs().max(1.0) {
                    continue;
                }
                assert_eq!(
                    st.count_below(1e-6, shift).unwrap(),
                    k + 1,
                    "eta {eta}, lbar {lbar}, shift {shift}: {vals:?}"
                );
            }
        }
        // Both stable and unstable states are among the cases.
        assert!(indices.len() >= 4, "{indices:?}");
        assert!(indices.contains(&0), "{indices:?}");
        assert!(indices.iter().any(|&i| i > 0), "{indices:?}");
    }
}
