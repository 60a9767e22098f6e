//! A converged enclosed state ([`EnclosedState`]) and what is read off it: energy, wall
//! multipliers and contact summary, contact forces, stability on the tangent space of the
//! active constraints, the two-resolution error estimate, and the steps to a nearby length
//! or parameter that re-solve it. Solving (semismooth Newton, starts) is in
//! [`super::solve`].

#![allow(clippy::needless_range_loop)] // index arithmetic over cells, nodes and unknowns

use nalgebra::{DMatrix, Vector3};

use super::carry::{model_from_curvature, transfer_multipliers};
use super::model::EnclosedModel;
use crate::SolverError;

/// A converged enclosed state.
#[derive(Clone, Debug)]
pub struct EnclosedState {
    /// The model.
    pub model: EnclosedModel,
    /// The KKT vector.
    pub z: Vec<f64>,
    /// Newton iterations used.
    pub iterations: usize,
    /// Final scaled residual norm.
    pub residual: f64,
}

/// Contact summary of a state.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Contact {
    /// Fraction of the nodes (length-weighted) touching the wall (`gap ≤ tol`).
    pub fraction: f64,
    /// Number of maximal runs of touching nodes (periodic; a single free node between
    /// touching neighbours does not split a run).
    pub intervals: usize,
    /// The contact runs as `(σ_start, σ_end)` (periodic; `σ = s/L`).
    pub runs: Vec<(f64, f64)>,
    /// Largest gap `R − |r|` and its `σ`.
    pub max_gap: (f64, f64),
    /// Smallest and largest contact force per unit length on the contact set.
    pub lambda_range: (f64, f64),
}

impl EnclosedState {
    /// Energy `E R/(π D0)`.
    pub fn energy(&self) -> f64 {
        self.model.energy(&self.z).unwrap_or(f64::NAN)
    }

    /// Wall multipliers `λ_j`.
    pub fn multipliers(&self) -> &[f64] {
        let o = self.model.lambda_offset();
        &self.z[o..o + self.model.cells()]
    }

    /// First-order optimality: `(min λ_j, min g_j, max |λ_j g_j|, stationarity norm)` in
    /// units of the scene (`λ_j` as a force density `λ(s) R³/D0`, `g` as a gap `/R`).
    pub fn optimality(&self) -> Result<(f64, f64, f64, f64), SolverError> {
        let m = &self.model;
        let r = m.radius();
        let unit = r.powi(3) / m.stiffness().kind().reference();
        let force = m.contact_force(&self.z);
        let gaps = m.gaps(&self.z)?;
        let lmin = force.iter().fold(f64::INFINITY, |a, &b| a.min(b)) * unit;
        let gmin = gaps.iter().fold(f64::INFINITY, |a, &b| a.min(b)) / r;
        let comp = force
            .iter()
            .zip(&gaps)
            .map(|(l, g)| (l * unit * g / r).abs())
            .fold(0.0, f64::max);
        let f = m.residual(&self.z)?;
        let np = m.n_primal();
        let scales = m.residual_scales();
        let stat = (0..np).map(|i| scales[i] * f[i] * f[i]).sum::<f64>().sqrt();
        Ok((lmin, gmin, comp, stat))
    }

    /// Contact set, gaps and forces (`tol` on the gap in units of `R`).
    pub fn contact(&self, tol: f64) -> Result<Contact, SolverError> {
        let m = &self.model;
        let n = m.cells();
        let r = m.radius();
        let gaps = m.gaps(&self.z)?;
        let force = m.contact_force(&self.z);
        let unit = r.powi(3) / m.stiffness().kind().reference();
        let touch: Vec<bool> = gaps.iter().map(|g| *g / r <= tol).collect();
        let total: f64 = (0..n).map(|j| m.node_weight(j)).sum();
        let fraction = (0..n)
            .filter(|&j| touch[j])
            .map(|j| m.node_weight(j))
            .sum::<f64>()
            / total
            + 0.0;
        let sigma = |j: usize| m.bounds()[j];
        // Runs are counted at the mesh's resolution: a stretch of at most `JOIN_NODES` free
        // nodes between touching neighbours, all within `JOIN_GAP` R of the wall, does not
        // split a run. (On fine meshes the concentrated force at a contact end shows as a
        // touching pair one to three nodes past the arc, the nodes between lifted by
        // 1e-8–5e-8 R: the figure-eight at L̄ = 1.3, N = 384, counted six runs for two arcs.)
        const JOIN_NODES: usize = 3;
        const JOIN_GAP: f64 = 1e-6;
        let mut joined = touch.clone();
        if let Some(s0) = touch.iter().position(|&t| t) {
            // Sweep from a touching node so that free stretches do not wrap.
            let mut k = 1;
            while k < n {
                let j = (s0 + k) % n;
                if touch[j] {
                    k += 1;
                    continue;
                }
                let len = (k..n).take_while(|&q| !touch[(s0 + q) % n]).count();
                let shallow = (k..k + len).all(|q| gaps[(s0 + q) % n] / r <= JOIN_GAP);
                if len <= JOIN_NODES && shallow {
                    for q in k..k + len {
                        joined[(s0 + q) % n] = true;
                    }
                }
                k += len;
            }
        }
        let mut runs = Vec::new();
        if joined.iter().all(|&t| t) {
            runs.push((0.0, 1.0));
        } else if joined.iter().any(|&t| t) {
            // Start the sweep at a free node so that runs do not wrap.
            let s0 = joined.iter().position(|&t| !t).unwrap_or(0);
            let mut start: Option<usize> = None;
            for k in 1..=n {
                let j = (s0 + k) % n;
                match (joined[j], start) {
                    (true, None) => start = Some(j),
                    (false, Some(a)) => {
                        let b = (j + n - 1) % n;
                        runs.push((sigma(a), sigma(b)));
                        start = None;
                    }
                    _ => {}
                }
            }
            if let Some(a) = start {
                runs.push((sigma(a), sigma((s0 + n) % n)));
            }
        }
        let (mut gmax, mut at) = (f64::NEG_INFINITY, 0.0);
        for (j, g) in gaps.iter().enumerate() {
            if *g > gmax {
                gmax = *g;
                at = sigma(j);
            }
        }
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for j in 0..n {
            if touch[j] {
                lo = lo.min(force[j] * unit);
                hi = hi.max(force[j] * unit);
            }
        }
        if lo > hi {
            (lo, hi) = (0.0, 0.0);
        }
        Ok(Contact {
            fraction,
            intervals: runs.len(),
            runs,
            max_gap: (gmax / r, at),
            lambda_range: (lo, hi),
        })
    }

    /// The scaling `s_i = 1/√m_i` of the primal unknowns by their mass (node length share
    /// `h/2` for a curvature unknown, `L/R²` for the start point).
    pub(crate) fn mass_scaling(&self) -> Vec<f64> {
        let m = &self.model;
        let n = m.cells();
        (0..m.n_primal())
            .map(|a| {
                let mass = if a < 4 * n {
                    0.5 * m.cell_length(a / 4)
                } else {
                    m.length() / (m.radius() * m.radius())
                };
                1.0 / mass.sqrt()
            })
            .collect()
    }

    /// The blocks of the mass-scaled KKT matrix on the active set: `W = S ∇²ℒ S` (primal ×
    /// primal, symmetric) and the rows `B = ∇c S` of the closure, the gauges and the
    /// strongly active wall constraints (`λ_j > tol·max λ`), `S = diag(s)` of
    /// [`Self::mass_scaling`].
    pub(crate) fn scaled_kkt_blocks(
        &self,
        tol: f64,
    ) -> Result<(DMatrix<f64>, DMatrix<f64>), SolverError> {
        let m = &self.model;
        let np = m.n_primal();
        let n = m.cells();
        let ev = m.evaluate(&self.z)?;
        let lam = self.multipliers();
        let lmax = lam.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        let s = self.mass_scaling();
        let w = DMatrix::from_fn(np, np, |i, j| ev.jacobian[(i, j)] * s[i] * s[j]);
        let lo = m.lambda_offset();
        let mut rows: Vec<usize> = (np..lo).collect();
        for j in 0..n {
            if lam[j] > tol * lmax.max(1e-300) {
                rows.push(lo + j);
            }
        }
        // Constraint gradients are the (negated) columns ∂F_x/∂y.
        let a = DMatrix::from_fn(rows.len(), np, |r, i| ev.jacobian[(i, rows[r])] * s[i]);
        Ok((w, a))
    }

    /// The mass-scaled Hessian of the Lagrangian on the tangent space of the closure, the
    /// gauges and the strongly active wall constraints (`λ_j > tol·max λ`), as the symmetric
    /// matrix `P W P + β (I − P)` (`β` above every tangent eigenvalue, so the complement's
    /// eigenvalues sit apart), and the scaling `s_i = 1/√m_i` that maps its eigenvectors back
    /// to the primal unknowns. Shared by [`EnclosedState::stability`] and
    /// [`super::unstable_direction`].
    pub(crate) fn tangent_hessian(
        &self,
        tol: f64,
    ) -> Result<(DMatrix<f64>, Vec<f64>), SolverError> {
        let (w, a) = self.scaled_kkt_blocks(tol)?;
        let s = self.mass_scaling();
        let np = w.nrows();
        let svd = a.svd(false, true);
        let vt = svd.v_t.ok_or(SolverError::InvalidInput("svd".into()))?;
        let smax = svd.singular_values.iter().fold(0.0f64, |x, &y| x.max(y));
        // Orthonormal basis V of the constraint gradients' span (rank-revealing SVD); the
        // projector onto the tangent space is P = I − V Vᵀ.
        let keep: Vec<usize> = (0..svd.singular_values.len())
            .filter(|&k| svd.singular_values[k] > 1e-10 * smax)
            .collect();
        let v = DMatrix::from_fn(np, keep.len(), |i, k| vt[(keep[k], i)]);
        let wmax = w.amax();
        let beta = 10.0 * wmax + 1.0;
        // P W P + β (I − P) = W − V(WV)ᵀ − (WV)Vᵀ + V(VᵀWV + β)Vᵀ (W symmetric), in
        // O(N² rank) instead of two dense N³ products; β moves the complement of the
        // tangent space above every tangent eigenvalue.
        let wv = &w * &v;
        let mut t = v.transpose() * &wv;
        for k in 0..keep.len() {
            t[(k, k)] += beta;
        }
        let pw = &w - &v * wv.transpose() - &wv * v.transpose() + &v * (t * v.transpose());
        Ok((pw, s))
    }

    /// Stability: the index ([`Self::index`], from the inertia of the bordered KKT matrix)
    /// and the lowest eigenvalues (ascending, mass-normalised) of the Hessian of the
    /// Lagrangian on the tangent space of the closure, the gauges and the strongly active
    /// wall constraints (`λ_j > tol·max λ`), at most 8. Symmetry modes are removed by the
    /// gauges. The eigenvalues come from a dense symmetric eigen-decomposition, `O(N³)`:
    /// callers that need only the index call [`Self::index`].
    pub fn stability(&self, tol: f64) -> Result<(usize, Vec<f64>), SolverError> {
        let (pw, _) = self.tangent_hessian(tol)?;
        let mut vals: Vec<f64> = pw.symmetric_eigenvalues().iter().copied().collect();
        vals.sort_by(f64::total_cmp);
        vals.truncate(8);
        Ok((self.index(tol)?, vals))
    }

    /// The curvature vector `(κ1, κ2)` at `σ`, interpolated (four-point Lagrange through the
    /// nearest Gauss points, error `O(h⁴)`): a start for another resolution. Across the
    /// closing node the components are continued with the holonomy: the frame comes back
    /// turned by `α` about the tangent ([`super::model::TWIST_ROW`]), so a smooth loop has
    /// `κ(σ + 1) = R(−α) κ(σ)` in components, and values of the other lap are turned into
    /// the frame continued from this one before they enter the stencil.
    pub fn curvature_at(&self, sigma: f64) -> (f64, f64) {
        let m = &self.model;
        let ng = 2 * m.cells();
        let sig: Vec<f64> = (0..ng).map(|g| m.gauss_sigma(g)).collect();
        let s = sigma.rem_euclid(1.0);
        // First Gauss point at or after s (periodically).
        let k = sig.iter().position(|&x| x >= s).unwrap_or(ng);
        let z = &self.z;
        // The end frame's normals in the start frame (the identity): (cos α, sin α) and
        // (−sin α, cos α).
        let (ca, sa) = match m.transforms(z) {
            Ok(p) => {
                let x = &p[m.cells()];
                let a = (x[(2, 1)] - x[(1, 2)]).atan2(x[(1, 1)] + x[(2, 2)]);
                (a.cos(), a.sin())
            }
            Err(_) => (1.0, 0.0),
        };
        let mut out = (0.0, 0.0);
        let idx: Vec<(usize, f64, isize)> = (0..4)
            .map(|q| {
                let raw = k as isize + q as isize - 2;
                let wraps = raw.div_euclid(ng as isize);
                let g = raw.rem_euclid(ng as isize) as usize;
                (g, sig[g] + wraps as f64, wraps)
            })
            .collect();
        for (q, &(g, xq, wraps)) in idx.iter().enumerate() {
            let mut l = 1.0;
            for (p, &(_, xp, _)) in idx.iter().enumerate() {
                if p != q {
                    l *= (s - xp) / (xq - xp);
                }
            }
            let (k1, k2) = (z[2 * g], z[2 * g + 1]);
            // One lap back: end-frame components into the frame continued backwards from
            // the start, R(α) κ; one lap on: R(−α) κ.
            let (k1, k2) = match wraps {
                w if w < 0 => (ca * k1 - sa * k2, sa * k1 + ca * k2),
                w if w > 0 => (ca * k1 + sa * k2, -sa * k1 + ca * k2),
                _ => (k1, k2),
            };
            out.0 += l * k1;
            out.1 += l * k2;
        }
        out
    }

    /// Prolong this state to `2N` cells: curvature by [`Self::curvature_at`], the same start
    /// point and closure multipliers, the contact force density carried over node by node
    /// (coarse nodes are every other fine node; new nodes take the mean of their neighbours).
    pub fn refine(&self) -> Result<(EnclosedModel, Vec<f64>), SolverError> {
        let m = &self.model;
        let n = m.cells();
        let r0 = m.start_point(&self.z);
        let stiff = m.stiffness().kind().clone();
        let (fine, mut z) = model_from_curvature(
            m.wall().clone(),
            m.lbar(),
            2 * n,
            &stiff,
            |s| self.curvature_at(s),
            [r0[0], r0[1], r0[2]],
        )?;
        transfer_multipliers(m, &self.z, &fine, &mut z);
        Ok((fine, z))
    }

    /// [`Self::refine`] with the contact runs kept inside the coarse ones: a new node
    /// between two touching coarse nodes takes the mean of their densities, a new node next
    /// to a free coarse node starts free. For ladders of fine meshes (the enclosed
    /// diagrams' exchanges, up to `8N` cells of the traces' finest level).
    ///
    /// The wall holds at the nodes only, so a mesh's contact runs reach past the loop's
    /// contact arcs by up to a cell at each end and shrink as the mesh is refined (on the
    /// two-segment figure-eight at `L̄ = 1.358` the contact fraction falls from 0.243 to
    /// 0.213 and 0.208 over 128, 256 and 512 cells). Started touching, with the density
    /// interpolated towards the free node, the new node at a run's end pins the finer loop
    /// to the wall past its contact arc: the Newton step of that contact set redistributes
    /// the impulses of the whole run (a step of norm 18 in the impulses from a residual of
    /// 5e-3 at 128 → 256 cells there) and the line search crawls through the set changes
    /// that follow (74 iterations at 256 cells with [`Self::refine`], 20 with this; at 1024
    /// cells the first takes none to convergence in 80 iterations, this 22).
    ///
    /// The diagrams' three-level cascades (`N/4, N/2, N`, 24 to 40 cells on the coarsest
    /// level) keep [`Self::refine`]: there the coarse levels' contact sets are far from the
    /// fine ones', and this start leads their finer levels to other discrete equilibria on
    /// some lengths (on the two-segment scene, other families of branch 2 between
    /// `L̄ = 1.44` and `1.96`), a change of what is traced that is not examined here.
    pub fn refine_in_runs(&self) -> Result<(EnclosedModel, Vec<f64>), SolverError> {
        let (fine, mut z) = self.refine()?;
        let m = &self.model;
        let n = m.cells();
        let (lc, lf) = (m.lambda_offset(), fine.lambda_offset());
        let touching = |j: usize| self.z[lc + j % n] > 0.0;
        for j in 0..n {
            if !(touching(j) && touching(j + 1)) {
                z[lf + 2 * j + 1] = 0.0;
            }
        }
        Ok((fine, z))
    }

    /// Node positions `(σ, r)`.
    pub fn nodes(&self) -> Result<Vec<(f64, Vector3<f64>)>, SolverError> {
        let pos = self.model.positions(&self.z)?;
        Ok(pos
            .into_iter()
            .enumerate()
            .map(|(j, r)| (self.model.bounds()[j], r))
            .collect())
    }

    /// Curvature vector `(κ1, κ2)` at node `j`: the linear extrapolations from the two
    /// adjacent cells' Gauss points, averaged.
    pub fn node_curvature(&self, j: usize) -> (f64, f64) {
        let n = self.model.cells();
        let z = &self.z;
        let g1 = crate::model::GAUSS_OFFSETS[0];
        let g2 = crate::model::GAUSS_OFFSETS[1];
        let ext = |c: usize, at: f64| -> (f64, f64) {
            let t = (at - g1) / (g2 - g1);
            (
                z[4 * c] + t * (z[4 * c + 2] - z[4 * c]),
                z[4 * c + 1] + t * (z[4 * c + 3] - z[4 * c + 1]),
            )
        };
        let (a1, a2) = ext(j % n, 0.0);
        let (mut b1, mut b2) = ext((j + n - 1) % n, 1.0);
        let (mut a1, mut a2) = (a1, a2);
        // At the closing node the two cells' components are in frames that differ by a turn
        // about the tangent (the frame need not return: no twisting moment, `TWIST_ROW`):
        // express both in the frame of the node's own end before averaging.
        if j % n == 0 {
            if let Ok(x) = self.model.transforms(z) {
                let col = |m: &nalgebra::Matrix4<f64>, c: usize| {
                    nalgebra::Vector3::new(m[(0, c)], m[(1, c)], m[(2, c)])
                };
                let (d1s, d2s) = (col(&x[0], 1), col(&x[0], 2));
                let (d1e, d2e) = (col(&x[n], 1), col(&x[n], 2));
                if j == 0 {
                    // The last cell's end components into the start frame.
                    let v = d1e * b1 + d2e * b2;
                    (b1, b2) = (v.dot(&d1s), v.dot(&d2s));
                } else {
                    // The first cell's start components into the end frame.
                    let v = d1s * a1 + d2s * a2;
                    (a1, a2) = (v.dot(&d1e), v.dot(&d2e));
                }
            }
        }
        (0.5 * (a1 + b1), 0.5 * (a2 + b2))
    }
}
