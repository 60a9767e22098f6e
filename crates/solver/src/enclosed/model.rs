//! The discretised enclosed loop ([`EnclosedModel`]): energy, closure, wall constraints and
//! the semismooth KKT system with its exact Jacobian.
//!
//! It is one file because the energy, the closure, the wall constraints and the exact Jacobian
//! all index the one layout of unknowns described below; split, that layout would be spread
//! over several files.
//!
//! # Unknowns
//!
//! `N` cells (the mesh of [`crate::MeshMap::for_profile`]); in every cell the curvature
//! vector `(κ1, κ2)` in the rotation-minimising frame at the two Gauss points (`4N`
//! values, stored `κ1a, κ2a, κ1b, κ2b` per cell), and the start point `r0` (3 values). The
//! frame at `s = 0` is the identity (`t = e1, d1 = e2, d2 = e3`): that fixes two of the
//! three rigid rotations and, with them, the direction of the tangent at `s = 0`. The
//! rotation about `t(0)` (which turns `r0` about `e1` and the curvature vectors about `t`)
//! is fixed by the linear gauge `φ_B = Σ_g (κ1ref κ2 − κ2ref κ1)/(2N |κref|_rms) = 0`.
//! For a uniform rod the shift of the arclength origin is fixed by a phase condition
//! `φ_S = Σ_g κ̇ref · (κ − κref)/(2N) = 0` as in [`crate::Phase`]; for a loop not touching
//! the wall (the free circle, `L̄ < 1`) the three translations are fixed by pinning `r0`.
//!
//! # Equations
//!
//! Positions and frames at the nodes `s_j` (cell boundaries) follow from the SE(3) Magnus
//! chain `P_{c+1} = P_c exp(Θ_c)` ([`super::jet`]), `r_j = r0 + p_j`. Closure of position
//! and tangent, `C = (c_rot(X_N), p_N) = 0` with the rows of `closure_rotation` (the tangent
//! back on `t(0) = e1`, full rank at every turn of the frame about it); the
//! rotation about the tangent (row [`TWIST_ROW`]) is free: its row reads `μ_twist = 0` (no
//! twisting moment). The wall
//! `g_j = R² − |r_j|² ≥ 0` (the sphere's gap; the model reads `g`, `∇g` and `∇²g` from its
//! [`Wall`]) is imposed at the `N` nodes; its multipliers `λ_j ≥ 0` are the
//! nodal contact impulses (the force per unit length is `λ(s_j) ≈ 2Rλ_j/w_j`, `w_j` the
//! node's share of the length; Sec. 3.2 with Eq. (38)'s sign: `λ > 0` pushes inward).
//! Energy, Eq. (2) with two-point Gauss quadrature, `E = Σ_c (h_c/2) Σ_g ½ D_g |κ_g|²`.
//! Lagrangian `ℒ = E − μ·C − ν·φ − λ·g`; the KKT conditions are
//! `∇ℒ = 0, C = 0, φ = 0` and the complementarity `λ ≥ 0, g ≥ 0, λ g = 0`, written with
//! the min-function `min(λ_j, σ g_j) = 0` (`σ = D0 h/R⁵` balances the units).
//!
//! # Derivatives
//!
//! `∂P_j/∂κ_a = P_c ∂E_c E_{c+1}⋯E_{j−1}` for an unknown of cell `c < j`. The gradient of
//! `Ψ = Σ_j λ_j |r_j|² − μ·C` uses the adjoint `A_c = 2λ_{c+1} e4 ρ_{c+1}ᵀ + E_{c+1}A_{c+1}`,
//! `A_{N−1} = −K` (`μ·C = tr(P_N K)`, `ρ = (r, 0)`): `∂Ψ/∂κ_a = tr(P_c ∂_aE_c A_c)`; its
//! Hessian is `tr(P_c ∂_aE_c E_{c+1}⋯E_{c'−1} ∂_bE_{c'} A_{c'})` (cells `c < c'`),
//! `tr(P_c ∂²_{ab}E_c A_c)` (one cell) plus `Σ_j 2λ_j ∂_a p_j·∂_b p_j`. All exact (the cell
//! jets come from [`super::jet::cell_jet`]); checked against finite differences in tests.
//! Assembly costs `O(N²)` 4×4 products plus one `O(N³)` product for the last term.

#![allow(clippy::needless_range_loop)] // index arithmetic over cells, nodes and unknowns

use std::f64::consts::PI;
use std::sync::Arc;

use nalgebra::{DMatrix, DVector, Matrix3, Matrix4, Vector3};

use super::jet::{cell_exp, cell_grad, cell_jet};
use super::wall::{IntoWall, Wall};
use crate::mesh::MeshMap;
use crate::model::GAUSS_OFFSETS;
use crate::periodic::TrigInterpolant;
use crate::stiffness::{Stiffness, StiffnessProfile};
use crate::SolverError;

type M4 = Matrix4<f64>;
type V3 = Vector3<f64>;

/// The closure row of the rotation about the tangent `t(0)` (the first component of
/// `closure_rotation`). The rod has no twist energy (paper Sec. 2: pure bending, `M·t = 0`), so
/// the rotation-minimising frame need not return about the tangent: a space curve's frame
/// comes back turned by its holonomy (`−∮τ ds` mod 2π; zero on the sphere, Geppert's
/// theorem, but not for a loop off the wall). Requiring it to return would be a constraint
/// that carries a twisting moment. So this row of the KKT system is `μ_twist = 0` and the
/// multiplier does not enter stationarity; closure is position (3) and tangent (2).
pub const TWIST_ROW: usize = 0;

/// The gauge conditions of an enclosed model (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct Gauge {
    /// Reference curvature vectors at the Gauss points (`4N`, per cell `κ1a, κ2a, κ1b, κ2b`).
    pub reference: Vec<f64>,
    /// Normalised `dκref/dσ` (`4N`), for the arclength phase condition (uniform rods).
    pub slope: Option<Vec<f64>>,
    /// Pinned start point (loops that do not touch the wall).
    pub pin: Option<[f64; 3]>,
}

/// The discretised enclosed loop (see the module docs).
#[derive(Clone, Debug)]
pub struct EnclosedModel {
    radius: f64,
    wall: Arc<dyn Wall>,
    lbar: f64,
    cells: usize,
    stiffness: StiffnessProfile,
    d_gauss: Vec<f64>,
    bounds: Vec<f64>,
    uniform_mesh: bool,
    gauge: Gauge,
    pull: f64,
    complementarity: Complementarity,
    contact_set: Option<Arc<[bool]>>,
}

/// The function `φ(a, b)` with `φ = 0 ⇔ a ≥ 0, b ≥ 0, ab = 0` that writes the wall's
/// complementarity (`a = λ_j + π_j`, `b = σ g_j`) as an equation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Complementarity {
    /// `min(a, b)`: each Newton step is the equality-constrained step of one contact set
    /// (the primal–dual active-set method).
    Min,
    /// Fischer–Burmeister, `a + b − √(a² + b²)` (Fischer, Optimization 24, 1992): smooth
    /// except at `a = b = 0`, so the squared residual norm is continuously differentiable
    /// and the Newton direction is a descent direction for it wherever the Jacobian is
    /// regular (De Luca, Facchinei & Kanzow, Math. Program. 75, 1996). The contact set is
    /// not chosen step by step but follows from the iterate continuously, so a contact
    /// point that lies between two nodes cannot make the set cycle.
    FischerBurmeister,
}

impl Complementarity {
    /// `(φ(a, b), ∂φ/∂a, ∂φ/∂b)`, with the element `(1 − 1/√2, 1 − 1/√2)` of the generalized
    /// Jacobian at the kink of Fischer–Burmeister and the branch `b ≤ a` (wall row) of `min`.
    pub fn eval(self, a: f64, b: f64) -> (f64, f64, f64) {
        match self {
            Complementarity::Min => {
                if b <= a {
                    (b, 0.0, 1.0)
                } else {
                    (a, 1.0, 0.0)
                }
            }
            Complementarity::FischerBurmeister => {
                let r = a.hypot(b);
                if r == 0.0 {
                    let c = 1.0 - std::f64::consts::FRAC_1_SQRT_2;
                    return (0.0, c, c);
                }
                // a + b − r without cancellation where both are positive.
                let v = if a > 0.0 && b > 0.0 {
                    2.0 * a * b / (a + b + r)
                } else {
                    a + b - r
                };
                (v, 1.0 - a / r, 1.0 - b / r)
            }
        }
    }
}

/// The chain of cell propagators with their derivatives and prefix products.
pub(super) struct Chain {
    /// Cell propagators `E_c`.
    pub(super) e: Vec<M4>,
    /// Their first derivatives in the four cell unknowns.
    pub(super) d: Vec<[M4; 4]>,
    /// Their second derivatives (empty for a first-order chain, [`EnclosedModel::chain_first`]).
    pub(super) dd: Vec<[[M4; 4]; 4]>,
    /// `P_c`, `c = 0..=N`.
    pub(super) prefix: Vec<M4>,
}

/// Everything the Jacobian needs, from one evaluation.
pub struct Evaluation {
    /// The KKT residual.
    pub residual: DVector<f64>,
    /// The semismooth KKT Jacobian.
    pub jacobian: DMatrix<f64>,
    /// Indices (into `0..N`) of the nodes whose complementarity row is the wall (`σg ≤ λ`).
    pub wall_rows: Vec<usize>,
}

pub(super) fn vee_skew3(m: &M4) -> V3 {
    V3::new(
        0.5 * (m[(2, 1)] - m[(1, 2)]),
        0.5 * (m[(0, 2)] - m[(2, 0)]),
        0.5 * (m[(1, 0)] - m[(0, 1)]),
    )
}

/// The rotation rows of the closure of the frame `X = P_N` (linear in `X`): the twist row
/// [`TWIST_ROW`] `½(X₃₂ − X₂₃)` (unused: its row of the KKT system is `μ_twist = 0`) and the
/// tangent rows `(X₁₃, −X₁₂)`, two components of `Xᵀe1` (the tangent `t(0)` in the returning
/// frame; `Xᵀe1 = ±e1` exactly where `t(L) = X e1 = ±t(0)`). They vanish only there, and
/// their Jacobian in a rotation `X hat(ω)` is `(ω_y, ω_z)` turned by the holonomy: rank 2
/// whatever the frame's turn about the tangent. (The rows `(−X₃₁, X₂₁)` of `X e1` have the
/// same zeros and rank; they differ at second order, `(ω_y, ω_z)` turned by `±ω_x/2`, and
/// with them the trace of the uniform rod's figure-eight stalls at `L̄ = 1.132`, where
/// non-planar states branch off.)
/// The rows `vee(skew X)` restricted to the same components vanish at every half-turn (the
/// tangent then comes back anywhere: `t(L) = 2(a·e1)a − e1` for a half-turn about `a`) and
/// their Jacobian vanishes at the half-turn about the tangent (holonomy `π`, a closed
/// loop), where Newton stalls. Near `X = I` both agree to first order, so the multipliers
/// keep their meaning (the moment at the cut).
pub(super) fn closure_rotation(m: &M4) -> V3 {
    V3::new(0.5 * (m[(2, 1)] - m[(1, 2)]), m[(0, 2)], -m[(0, 1)])
}

pub(super) fn tr4(a: &M4, b: &M4) -> f64 {
    let mut s = 0.0;
    for i in 0..4 {
        for j in 0..4 {
            s += a[(i, j)] * b[(j, i)];
        }
    }
    s
}

pub(super) fn translation(m: &M4) -> V3 {
    V3::new(m[(0, 3)], m[(1, 3)], m[(2, 3)])
}

impl EnclosedModel {
    /// A loop of normalised length `lbar` inside `wall` (a radius: the ball of that radius,
    /// [`IntoWall`]), `cells` cells, stiffness `stiffness`, with the gauge `gauge`
    /// (reference of length `4·cells`).
    pub fn new(
        wall: impl IntoWall,
        lbar: f64,
        cells: usize,
        stiffness: &Stiffness,
        gauge: Gauge,
    ) -> Result<Self, SolverError> {
        let wall = wall.into_wall();
        let radius = wall.radius();
        crate::model::check_loop_inputs(radius, lbar, cells, 8)?;
        if gauge.reference.len() != 4 * cells {
            return Err(SolverError::WrongLength {
                expected: 4 * cells,
                found: gauge.reference.len(),
            });
        }
        if let Some(s) = &gauge.slope {
            if s.len() != 4 * cells {
                return Err(SolverError::WrongLength {
                    expected: 4 * cells,
                    found: s.len(),
                });
            }
        }
        let profile = stiffness.validate()?;
        let map = MeshMap::for_profile(stiffness);
        let uniform_mesh = map.is_uniform();
        let bounds = map.bounds(cells)?;
        let mut m = Self {
            radius,
            wall,
            lbar,
            cells,
            stiffness: profile,
            d_gauss: Vec::new(),
            bounds,
            uniform_mesh,
            gauge,
            pull: 0.0,
            complementarity: Complementarity::Min,
            contact_set: None,
        };
        m.d_gauss = (0..2 * cells)
            .map(|g| m.stiffness.eval(m.gauss_sigma(g)).d)
            .collect();
        Ok(m)
    }

    /// A model of the same wall with another length, mesh, stiffness or gauge.
    pub fn rebuilt(
        &self,
        lbar: f64,
        cells: usize,
        stiffness: &Stiffness,
        gauge: Gauge,
    ) -> Result<Self, SolverError> {
        Self::new(&self.wall, lbar, cells, stiffness, gauge)
    }

    /// [`Self::new`] on given cell boundaries `bounds` in `σ` (`0 = σ_0 < … < σ_N = 1`)
    /// instead of the stiffness profile's mesh map: nodes placed at the ends of point
    /// contacts ([`super::centre`]).
    pub fn with_bounds(
        wall: impl IntoWall,
        lbar: f64,
        bounds: Vec<f64>,
        stiffness: &Stiffness,
        gauge: Gauge,
    ) -> Result<Self, SolverError> {
        let cells = bounds.len().saturating_sub(1);
        let ordered = bounds.first() == Some(&0.0)
            && bounds.last() == Some(&1.0)
            && bounds.windows(2).all(|w| w[1] > w[0]);
        if !ordered {
            return Err(SolverError::InvalidInput(
                "cell boundaries must increase from 0 to 1".into(),
            ));
        }
        let mut m = Self::new(wall, lbar, cells, stiffness, gauge)?;
        m.uniform_mesh = false;
        m.bounds = bounds;
        m.d_gauss = (0..2 * cells)
            .map(|g| m.stiffness.eval(m.gauss_sigma(g)).d)
            .collect();
        Ok(m)
    }

    /// Normalised arclength `σ = s/L` of Gauss point `g` (`0..2N`).
    pub fn gauss_sigma(&self, g: usize) -> f64 {
        let c = g / 2;
        self.bounds[c] + GAUSS_OFFSETS[g % 2] * (self.bounds[c + 1] - self.bounds[c])
    }

    /// Cell boundaries in `σ`.
    pub fn bounds(&self) -> &[f64] {
        &self.bounds
    }

    /// `true` when the cells are of equal length.
    pub fn uniform_mesh(&self) -> bool {
        self.uniform_mesh
    }

    /// Number of cells `N`.
    pub fn cells(&self) -> usize {
        self.cells
    }

    /// Sphere radius (the wall's length scale, [`Wall::radius`]).
    pub fn radius(&self) -> f64 {
        self.radius
    }

    /// The confining wall.
    pub fn wall(&self) -> &Arc<dyn Wall> {
        &self.wall
    }

    /// The same model inside `wall` (its length scale becomes [`Self::radius`]).
    pub fn with_wall(mut self, wall: Arc<dyn Wall>) -> Result<Self, SolverError> {
        crate::model::check_loop_inputs(wall.radius(), self.lbar, self.cells, 8)?;
        self.radius = wall.radius();
        self.wall = wall;
        Ok(self)
    }

    /// `L̄`.
    pub fn lbar(&self) -> f64 {
        self.lbar
    }

    /// Loop length `L = 2πR L̄`.
    pub fn length(&self) -> f64 {
        2.0 * PI * self.radius * self.lbar
    }

    /// `D` at Gauss point `g` (`0..2N`).
    pub(super) fn d_gauss_at(&self, g: usize) -> f64 {
        self.d_gauss[g]
    }

    /// The stiffness profile.
    pub fn stiffness(&self) -> &StiffnessProfile {
        &self.stiffness
    }

    /// The gauge.
    pub fn gauge(&self) -> &Gauge {
        &self.gauge
    }

    /// Length of cell `c`.
    pub fn cell_length(&self, c: usize) -> f64 {
        self.length() * (self.bounds[c + 1] - self.bounds[c])
    }

    /// Length share `w_j = (h_{j−1} + h_j)/2` of node `j`.
    pub fn node_weight(&self, j: usize) -> f64 {
        let n = self.cells;
        0.5 * (self.cell_length((j + n - 1) % n) + self.cell_length(j % n))
    }

    /// Number of primal unknowns `4N + 3`.
    pub fn n_primal(&self) -> usize {
        4 * self.cells + 3
    }

    /// Number of gauge conditions.
    pub fn n_gauge(&self) -> usize {
        1 + usize::from(self.gauge.slope.is_some()) + 3 * usize::from(self.gauge.pin.is_some())
    }

    /// Number of equality constraints (closure 6 plus gauges).
    pub fn n_equalities(&self) -> usize {
        6 + self.n_gauge()
    }

    /// Size of the KKT system, `5N + 9 + gauges`.
    pub fn dim(&self) -> usize {
        self.n_primal() + self.n_equalities() + self.cells
    }

    /// Offset of the wall multipliers `λ` in the KKT vector.
    pub fn lambda_offset(&self) -> usize {
        self.n_primal() + self.n_equalities()
    }

    /// The same model with a wall that may pull up to `pull` (force per unit length, units
    /// `D0/R³`): the complementarity becomes `min(λ_j + π_j, σ g_j) = 0` with `π_j` the
    /// impulse of `pull` at node `j`. A homotopy device only (`pull = 0` is the physical
    /// wall): at `pull ≥ −λ_min` of a surface loop, that loop satisfies it
    /// ([`super::solve::solve_by_pull_homotopy`]).
    pub fn with_pull(mut self, pull: f64) -> Result<Self, SolverError> {
        if !(pull.is_finite() && pull >= 0.0) {
            return Err(SolverError::InvalidInput(format!(
                "the homotopy's pulling force must be finite and >= 0 (got {pull})"
            )));
        }
        self.pull = pull;
        Ok(self)
    }

    /// The same model with the complementarity written by `c` ([`Complementarity`]; the
    /// solutions are the same, only the Newton iteration differs).
    pub fn with_complementarity(mut self, c: Complementarity) -> Self {
        self.complementarity = c;
        self
    }

    /// The same model on one smooth piece of the complementarity: the wall row `σ g_j = 0`
    /// at the nodes `j` with `contact[j]` and `λ_j = 0` at the others, the contact set held
    /// fixed instead of chosen by `min(λ_j, σ g_j)` ([`super::arclength`]: pseudo-arclength
    /// continuation through folds, which needs a smooth system). A state of this model is
    /// an equilibrium of the wall where its contact impulses and free gaps are nonnegative
    /// ([`super::arclength::contact_slack`]).
    pub fn with_contact_set(mut self, contact: Vec<bool>) -> Result<Self, SolverError> {
        if contact.len() != self.cells {
            return Err(SolverError::WrongLength {
                expected: self.cells,
                found: contact.len(),
            });
        }
        self.contact_set = Some(contact.into());
        Ok(self)
    }

    /// The contact set held fixed ([`Self::with_contact_set`]), if any.
    pub fn contact_set(&self) -> Option<&[bool]> {
        self.contact_set.as_deref()
    }

    /// Whether node `j`'s row is the wall at `a = λ_j + π_j`, `b = σ g_j`: in the fixed
    /// contact set where one is held, else `b ≤ a` (the branch of `min` that is active).
    fn on_wall(&self, j: usize, a: f64, b: f64) -> bool {
        match &self.contact_set {
            Some(set) => set[j],
            None => b <= a,
        }
    }

    /// Node `j`'s wall row `(φ, ∂φ/∂a, ∂φ/∂b)` at `a = λ_j + π_j`, `b = σ g_j`: the
    /// complementarity function, or the fixed contact set's piece of `min`.
    pub(super) fn wall_row(&self, j: usize, a: f64, b: f64) -> (f64, f64, f64) {
        match &self.contact_set {
            Some(_) if self.on_wall(j, a, b) => (b, 0.0, 1.0),
            Some(_) => (a, 1.0, 0.0),
            None => self.complementarity.eval(a, b),
        }
    }

    /// How the wall's complementarity is written ([`Complementarity`]).
    pub fn complementarity(&self) -> Complementarity {
        self.complementarity
    }

    /// The allowed pulling force (0: the physical wall).
    pub fn pull(&self) -> f64 {
        self.pull
    }

    /// Impulse `π_j` of the allowed pull at node `j`.
    pub(super) fn pull_impulse(&self, j: usize) -> f64 {
        if self.pull == 0.0 {
            return 0.0;
        }
        let r = self.radius;
        self.pull * self.stiffness.kind().reference() / r.powi(3) * self.node_weight(j) / (2.0 * r)
    }

    /// Scale `σ` of the min-function.
    pub fn wall_scale(&self) -> f64 {
        let r = self.radius;
        self.stiffness.kind().reference() * (self.length() / self.cells as f64) / r.powi(5)
    }

    fn check(&self, z: &[f64]) -> Result<(), SolverError> {
        if z.len() != self.dim() {
            return Err(SolverError::WrongLength {
                expected: self.dim(),
                found: z.len(),
            });
        }
        if let Some(i) = z.iter().position(|v| !v.is_finite()) {
            return Err(SolverError::InvalidInput(format!(
                "unknown {i} of the enclosed state is not finite"
            )));
        }
        Ok(())
    }

    fn cell_x(z: &[f64], c: usize) -> [f64; 4] {
        [z[4 * c], z[4 * c + 1], z[4 * c + 2], z[4 * c + 3]]
    }

    /// Node transforms `P_j`, `j = 0..=N` (rotation block: columns `t, d1, d2`; last
    /// column: `p_j = r_j − r0`).
    pub fn transforms(&self, z: &[f64]) -> Result<Vec<M4>, SolverError> {
        if z.len() < 4 * self.cells {
            return Err(SolverError::WrongLength {
                expected: self.dim(),
                found: z.len(),
            });
        }
        let mut p = Vec::with_capacity(self.cells + 1);
        let mut acc = M4::identity();
        p.push(acc);
        for c in 0..self.cells {
            acc *= cell_exp(self.cell_length(c), Self::cell_x(z, c));
            p.push(acc);
        }
        Ok(p)
    }

    /// Start point `r0`.
    pub fn start_point(&self, z: &[f64]) -> V3 {
        let o = 4 * self.cells;
        V3::new(z[o], z[o + 1], z[o + 2])
    }

    /// Node positions `r_j`, `j = 0..N` (`r_N` omitted: it equals `r_0` at closure).
    pub fn positions(&self, z: &[f64]) -> Result<Vec<V3>, SolverError> {
        let p = self.transforms(z)?;
        let r0 = self.start_point(z);
        Ok(p[..self.cells]
            .iter()
            .map(|m| r0 + translation(m))
            .collect())
    }

    /// Gaps `R − |r_j|` at the nodes (the wall's clearance, [`Wall::clearance`]).
    pub fn gaps(&self, z: &[f64]) -> Result<Vec<f64>, SolverError> {
        Ok(self
            .positions(z)?
            .iter()
            .map(|r| self.wall.clearance(r))
            .collect())
    }

    /// The contact set of the semismooth Newton step at `z`: node `j` takes the wall row
    /// where `σ g_j ≤ λ_j + π_j` (the branch of the min-function that is active), or where
    /// the contact set held fixed ([`Self::with_contact_set`]) says so.
    pub fn wall_active(&self, z: &[f64]) -> Result<Vec<bool>, SolverError> {
        self.check(z)?;
        let lo = self.lambda_offset();
        let sigma = self.wall_scale();
        Ok(self
            .positions(z)?
            .iter()
            .enumerate()
            .map(|(j, r)| {
                self.on_wall(
                    j,
                    z[lo + j] + self.pull_impulse(j),
                    sigma * self.wall.gap(r),
                )
            })
            .collect())
    }

    /// Closure residual `(c_rot(X_N), p_N)` (`closure_rotation`) with its twist component
    /// (about `t(0)`, the first) reported as 0: the loop closes when position and tangent return; the
    /// rotation-minimising frame may come back turned about the tangent (see
    /// [`TWIST_ROW`]).
    pub fn closure(&self, z: &[f64]) -> Result<[f64; 6], SolverError> {
        let p = self.transforms(z)?;
        let pn = &p[self.cells];
        let v = closure_rotation(pn);
        let t = translation(pn);
        Ok([0.0, v[1], v[2], t[0], t[1], t[2]])
    }

    /// The closure multipliers `μ` of `z` as they enter stationarity: the twist component
    /// ([`TWIST_ROW`]) is 0.
    pub(super) fn closure_multipliers(&self, z: &[f64]) -> [f64; 6] {
        let np = self.n_primal();
        let mut mu = [0.0; 6];
        mu.copy_from_slice(&z[np..np + 6]);
        mu[TWIST_ROW] = 0.0;
        mu
    }

    /// Dimensional energy, two-point Gauss quadrature of Eq. (2).
    pub fn energy_raw(&self, z: &[f64]) -> f64 {
        let mut e = 0.0;
        for c in 0..self.cells {
            let w = 0.5 * self.cell_length(c);
            for j in 0..2 {
                let g = 2 * c + j;
                let (k1, k2) = (z[2 * g], z[2 * g + 1]);
                e += 0.5 * w * self.d_gauss[g] * (k1 * k1 + k2 * k2);
            }
        }
        e
    }

    /// Energy `E R/(π D0)`.
    pub fn energy(&self, z: &[f64]) -> Result<f64, SolverError> {
        self.check(z)?;
        Ok(self.energy_raw(z) * self.radius / (PI * self.stiffness.kind().reference()))
    }

    /// Contact force per unit length at the nodes, `λ(s_j) = λ_j |∇g(r_j)|/w_j` (the line
    /// load `q = λ_j ∇g/w_j` of the module docs; `2Rλ_j/w_j` on the sphere's wall). Empty
    /// for a `z` too short to hold the nodes.
    pub fn contact_force(&self, z: &[f64]) -> Vec<f64> {
        let o = self.lambda_offset();
        self.wall_gradient_norms(z)
            .iter()
            .enumerate()
            .map(|(j, g)| z[o + j] * g / self.node_weight(j))
            .collect()
    }

    /// `|∇g(r_j)|` at the nodes: what turns a wall impulse `λ_j` into the force density
    /// `λ_j |∇g|/w_j` ([`Self::contact_force`]). Empty for a `z` too short to hold the nodes.
    pub fn wall_gradient_norms(&self, z: &[f64]) -> Vec<f64> {
        self.positions(z).map_or_else(
            |_| Vec::new(),
            |pos| pos.iter().map(|r| self.wall.gradient(r).norm()).collect(),
        )
    }

    pub(super) fn gauge_rows(&self) -> Vec<(Vec<f64>, Option<usize>)> {
        // Dense gradients over the primal unknowns for the κ gauges, or a pinned index.
        let n = self.cells;
        let reference = &self.gauge.reference;
        let rms = (reference.iter().map(|v| v * v).sum::<f64>() / (2 * n) as f64)
            .sqrt()
            .max(1e-300);
        let mut rows = Vec::new();
        let mut gb = vec![0.0; self.n_primal()];
        for g in 0..2 * n {
            gb[2 * g] = -reference[2 * g + 1] / (2 * n) as f64 / rms;
            gb[2 * g + 1] = reference[2 * g] / (2 * n) as f64 / rms;
        }
        rows.push((gb, None));
        if let Some(sl) = &self.gauge.slope {
            let mut gs = vec![0.0; self.n_primal()];
            for a in 0..4 * n {
                gs[a] = sl[a] / (2 * n) as f64;
            }
            rows.push((gs, None));
        }
        if self.gauge.pin.is_some() {
            for k in 0..3 {
                rows.push((Vec::new(), Some(4 * n + k)));
            }
        }
        rows
    }

    /// Gauge values `φ(z)`.
    fn gauge_values(&self, z: &[f64]) -> Vec<f64> {
        let n = self.cells;
        let mut out = Vec::new();
        for (k, (row, idx)) in self.gauge_rows().into_iter().enumerate() {
            match idx {
                None => {
                    let mut v = 0.0;
                    for a in 0..4 * n {
                        let zr = if k == 0 {
                            z[a]
                        } else {
                            z[a] - self.gauge.reference[a]
                        };
                        v += row[a] * zr;
                    }
                    out.push(v);
                }
                Some(i) => {
                    let pin = self.gauge.pin.unwrap_or([0.0; 3]);
                    out.push(z[i] - pin[i - 4 * n]);
                }
            }
        }
        out
    }

    pub(super) fn chain(&self, z: &[f64]) -> Chain {
        let n = self.cells;
        let mut ch = Chain {
            e: Vec::with_capacity(n),
            d: Vec::with_capacity(n),
            dd: Vec::with_capacity(n),
            prefix: Vec::with_capacity(n + 1),
        };
        let mut acc = M4::identity();
        ch.prefix.push(acc);
        for c in 0..n {
            let j = cell_jet(self.cell_length(c), Self::cell_x(z, c));
            acc *= j.e;
            ch.prefix.push(acc);
            ch.e.push(j.e);
            ch.d.push(j.d);
            ch.dd.push(j.dd);
        }
        ch
    }

    /// The chain with first derivatives only (all the residual needs).
    pub(super) fn chain_first(&self, z: &[f64]) -> Chain {
        let n = self.cells;
        let mut ch = Chain {
            e: Vec::with_capacity(n),
            d: Vec::with_capacity(n),
            dd: Vec::new(),
            prefix: Vec::with_capacity(n + 1),
        };
        let mut acc = M4::identity();
        ch.prefix.push(acc);
        for c in 0..n {
            let (e, d) = cell_grad(self.cell_length(c), Self::cell_x(z, c));
            acc *= e;
            ch.prefix.push(acc);
            ch.e.push(e);
            ch.d.push(d);
        }
        ch
    }

    /// `K` with `μ·C = tr(P_N K)`.
    pub(super) fn closure_functional(mu: &[f64]) -> M4 {
        let mut k = M4::zeros();
        // Rotation ([`closure_rotation`]): `tr(X K) = Σ X_ij K_ji`.
        k[(1, 2)] = 0.5 * mu[0];
        k[(2, 1)] = -0.5 * mu[0];
        k[(2, 0)] = mu[1];
        k[(1, 0)] = -mu[2];
        for i in 0..3 {
            k[(3, i)] = mu[3 + i];
        }
        k
    }

    /// KKT residual (see the module docs).
    pub fn residual(&self, z: &[f64]) -> Result<DVector<f64>, SolverError> {
        self.check(z)?;
        let ch = self.chain_first(z);
        Ok(self.residual_from(&ch, z))
    }

    pub(super) fn adjoints(&self, ch: &Chain, z: &[f64]) -> Vec<M4> {
        let n = self.cells;
        let r0 = self.start_point(z);
        let lo = self.lambda_offset();
        let mu = self.closure_multipliers(z);
        let mut a = vec![M4::zeros(); n];
        a[n - 1] = -Self::closure_functional(&mu);
        for c in (0..n - 1).rev() {
            let j = c + 1;
            let r = r0 + translation(&ch.prefix[j]);
            let lam = z[lo + j];
            let mut t = ch.e[j] * a[j];
            let grad = self.wall.gradient(&r);
            for k in 0..3 {
                t[(3, k)] -= lam * grad[k];
            }
            a[c] = t;
        }
        a
    }

    pub(super) fn residual_from(&self, ch: &Chain, z: &[f64]) -> DVector<f64> {
        let adj = self.adjoints(ch, z);
        self.residual_with(ch, &adj, z)
    }

    /// The second-order chain of `z` after checking `z`.
    pub(super) fn checked_chain(&self, z: &[f64]) -> Result<Chain, SolverError> {
        self.check(z)?;
        Ok(self.chain(z))
    }

    /// The residual from a chain and its adjoints ([`Self::adjoints`]).
    pub(super) fn residual_with(&self, ch: &Chain, adj: &[M4], z: &[f64]) -> DVector<f64> {
        let n = self.cells;
        let np = self.n_primal();
        let lo = self.lambda_offset();
        let mut f = DVector::zeros(self.dim());
        for c in 0..n {
            let w = 0.5 * self.cell_length(c);
            for i in 0..4 {
                let a = 4 * c + i;
                let g = 2 * c + i / 2;
                f[a] = w * self.d_gauss[g] * z[a] + tr4(&(ch.prefix[c] * ch.d[c][i]), &adj[c]);
            }
        }
        let r0 = self.start_point(z);
        let sigma = self.wall_scale();
        let mut fr = V3::zeros();
        for j in 0..n {
            let r = r0 + translation(&ch.prefix[j]);
            let lam = z[lo + j];
            fr -= self.wall.gradient(&r) * lam;
            let g = self.wall.gap(&r);
            f[lo + j] = self.wall_row(j, lam + self.pull_impulse(j), sigma * g).0;
        }
        for k in 0..3 {
            f[4 * n + k] = fr[k];
        }
        // Closure.
        let pn = &ch.prefix[n];
        let v = closure_rotation(pn);
        let t = translation(pn);
        for k in 0..3 {
            f[np + k] = -v[k];
            f[np + 3 + k] = -t[k];
        }
        // The twist row: its multiplier is 0 (no twisting moment), see [`TWIST_ROW`].
        f[np + TWIST_ROW] = z[np + TWIST_ROW];
        // Gauges.
        let nu0 = np + 6;
        let gv = self.gauge_values(z);
        for (k, (row, idx)) in self.gauge_rows().into_iter().enumerate() {
            let nu = z[nu0 + k];
            match idx {
                None => {
                    for a in 0..4 * n {
                        f[a] -= nu * row[a];
                    }
                }
                Some(i) => f[i] -= nu,
            }
            f[nu0 + k] = -gv[k];
        }
        f
    }

    /// Residual and semismooth Jacobian (see the module docs).
    pub fn evaluate(&self, z: &[f64]) -> Result<Evaluation, SolverError> {
        self.check(z)?;
        let n = self.cells;
        let nk = 4 * n;
        let np = self.n_primal();
        let lo = self.lambda_offset();
        let dim = self.dim();
        let ch = self.chain(z);
        let residual = self.residual_from(&ch, z);
        let adj = self.adjoints(&ch, z);
        let r0 = self.start_point(z);
        let pos: Vec<V3> = (0..=n).map(|j| r0 + translation(&ch.prefix[j])).collect();
        // dp[j] (3 × 4N) for nodes j = 1..=N, and the rotation closure Jacobian.
        let mut jp = DMatrix::<f64>::zeros(3 * n, nk); // rows 3(j−1)+k, j = 1..=N
        let mut jrot = DMatrix::<f64>::zeros(3, nk);
        for c in 0..n {
            for i in 0..4 {
                let a = 4 * c + i;
                let mut m = ch.prefix[c] * ch.d[c][i];
                for j in c + 1..=n {
                    let t = translation(&m);
                    for k in 0..3 {
                        jp[(3 * (j - 1) + k, a)] = t[k];
                    }
                    if j == n {
                        let v = closure_rotation(&m);
                        for k in 0..3 {
                            jrot[(k, a)] = v[k];
                        }
                    } else {
                        m *= ch.e[j];
                    }
                }
            }
        }
        let mut jac = DMatrix::<f64>::zeros(dim, dim);
        // Hessian of the Lagrangian, κκ block: energy + curvature (adjoint) terms.
        for c in 0..n {
            let w = 0.5 * self.cell_length(c);
            for i in 0..4 {
                let a = 4 * c + i;
                jac[(a, a)] += w * self.d_gauss[2 * c + i / 2];
                let pd = ch.prefix[c] * ch.d[c][i];
                for i2 in i..4 {
                    let v = tr4(&(ch.prefix[c] * ch.dd[c][i][i2]), &adj[c]);
                    jac[(a, 4 * c + i2)] += v;
                    if i2 != i {
                        jac[(4 * c + i2, a)] += v;
                    }
                }
                let mut rm = pd;
                for cp in c + 1..n {
                    for i2 in 0..4 {
                        let g = ch.d[cp][i2] * adj[cp];
                        let v = tr4(&rm, &g);
                        let b = 4 * cp + i2;
                        jac[(a, b)] += v;
                        jac[(b, a)] += v;
                    }
                    rm *= ch.e[cp];
                }
            }
        }
        // The wall's curvature term −Σ_j λ_j ∂p_jᵀ ∇²g_j ∂p_j (nodes 1..N−1; the sphere's
        // `2λ_j ∂p_j·∂p_j`), the κ–r0 block and the r0–r0 block `−Σ_j λ_j ∇²g_j`. Vanishing
        // Hessian entries are skipped (the sphere's is diagonal).
        let mut scaled = DMatrix::<f64>::zeros(3 * (n - 1), nk);
        let mut kr = DMatrix::<f64>::zeros(nk, 3);
        let mut hess_sum = Matrix3::<f64>::zeros();
        for j in 0..n {
            let lam = z[lo + j];
            if lam == 0.0 {
                continue;
            }
            let h = self.wall.hessian(&pos[j]);
            hess_sum -= h * lam;
            if j == 0 {
                continue;
            }
            for k in 0..3 {
                let out = 3 * (j - 1) + k;
                let mut first = true;
                for l in (0..3).filter(|&l| h[(k, l)] != 0.0) {
                    let row = jp.row(3 * (j - 1) + l) * (-lam * h[(k, l)]);
                    if first {
                        scaled.row_mut(out).copy_from(&row);
                    } else {
                        let mut dst = scaled.row_mut(out);
                        dst += &row;
                    }
                    first = false;
                }
                for a in 0..nk {
                    kr[(a, k)] += scaled[(out, a)];
                }
            }
        }
        let jp_wall = jp.rows(0, 3 * (n - 1));
        let gn = jp_wall.transpose() * &scaled;
        {
            let mut blk = jac.view_mut((0, 0), (nk, nk));
            blk += gn;
        }
        for a in 0..nk {
            for k in 0..3 {
                jac[(a, nk + k)] += kr[(a, k)];
                jac[(nk + k, a)] += kr[(a, k)];
            }
        }
        for k in 0..3 {
            for l in 0..3 {
                jac[(nk + k, nk + l)] += hess_sum[(k, l)];
            }
        }
        // Closure columns/rows: ∂F_x/∂μ = −∇Cᵀ, F_μ = −C.
        for a in 0..nk {
            for k in 0..3 {
                if k != TWIST_ROW {
                    jac[(a, np + k)] = -jrot[(k, a)];
                    jac[(np + k, a)] = -jrot[(k, a)];
                }
                let t = jp[(3 * (n - 1) + k, a)];
                jac[(a, np + 3 + k)] = -t;
                jac[(np + 3 + k, a)] = -t;
            }
        }
        jac[(np + TWIST_ROW, np + TWIST_ROW)] = 1.0;
        // Gauges.
        let nu0 = np + 6;
        for (k, (row, idx)) in self.gauge_rows().into_iter().enumerate() {
            match idx {
                None => {
                    for a in 0..nk {
                        jac[(a, nu0 + k)] = -row[a];
                        jac[(nu0 + k, a)] = -row[a];
                    }
                }
                Some(i) => {
                    jac[(i, nu0 + k)] = -1.0;
                    jac[(nu0 + k, i)] = -1.0;
                }
            }
        }
        // Wall: ∂F_x/∂λ_j = −∇g_j; complementarity rows.
        let sigma = self.wall_scale();
        let mut wall_rows = Vec::new();
        for j in 0..n {
            let r = pos[j];
            let lam = z[lo + j];
            let g = self.wall.gap(&r);
            // ∇g_j: κ part ∇g·∂p_j (j ≥ 1), r0 part ∇g (the sphere's −2r).
            let gr = self.wall.gradient(&r);
            let mut grad = vec![0.0; np];
            if j >= 1 {
                for a in 0..nk {
                    let mut s = 0.0;
                    for k in 0..3 {
                        s += gr[k] * jp[(3 * (j - 1) + k, a)];
                    }
                    grad[a] = s;
                }
            }
            for k in 0..3 {
                grad[nk + k] = gr[k];
            }
            for a in 0..np {
                jac[(a, lo + j)] = -grad[a];
            }
            let (a, b) = (lam + self.pull_impulse(j), sigma * g);
            if self.on_wall(j, a, b) {
                wall_rows.push(j);
            }
            let (_, da, db) = self.wall_row(j, a, b);
            if db != 0.0 {
                for a in 0..np {
                    jac[(lo + j, a)] = db * sigma * grad[a];
                }
            }
            jac[(lo + j, lo + j)] = da;
        }
        Ok(Evaluation {
            residual,
            jacobian: jac,
            wall_rows,
        })
    }

    /// Weights `s_i` of the squared residual norm `Σ s_i F_i²`: stationarity rows as a
    /// density (`F/(h/2)`, root mean square over the loop, units of `D0/R`), closure and
    /// gauges as they are, complementarity rows in units of the contact impulse.
    pub fn residual_scales(&self) -> Vec<f64> {
        let n = self.cells;
        let unit = self.radius / self.stiffness.kind().reference();
        let mut s = Vec::with_capacity(self.dim());
        for a in 0..4 * n {
            let w = 0.5 * self.cell_length(a / 4);
            s.push(unit * unit / (w * w) / (4 * n) as f64);
        }
        for _ in 0..3 {
            s.push(unit * unit / (self.radius * self.radius));
        }
        s.extend(std::iter::repeat_n(1.0, self.n_equalities()));
        let lam_unit = self.radius.powi(3) / self.stiffness.kind().reference();
        for j in 0..n {
            let w = self.node_weight(j);
            let u = 2.0 * self.radius * lam_unit / w;
            s.push(u * u / n as f64);
        }
        s
    }

    /// Resolution-independent residual norm (see [`Self::residual_scales`]).
    pub fn residual_norm(&self, f: &DVector<f64>) -> f64 {
        self.residual_scales()
            .iter()
            .zip(f.iter())
            .map(|(s, v)| s * v * v)
            .sum::<f64>()
            .sqrt()
    }

    /// Curvature unknowns at the Gauss points of `cells` cells on this model's mesh map,
    /// sampled from periodic functions `κ1(σ), κ2(σ)`.
    pub fn sample_gauss<F: Fn(f64) -> (f64, f64)>(&self, f: F) -> Vec<f64> {
        let mut out = Vec::with_capacity(4 * self.cells);
        for g in 0..2 * self.cells {
            let (a, b) = f(self.gauss_sigma(g));
            out.push(a);
            out.push(b);
        }
        out
    }
}

/// Normalised slope `dκ/dσ` of Gauss-point curvature vectors on a uniform mesh of `cells`
/// cells (spectral differentiation on each Gauss sub-grid), unit root-mean-square; `None`
/// when the curvature is (nearly) constant (a circle has no shift mode).
pub fn phase_slope(reference: &[f64], cells: usize) -> Result<Option<Vec<f64>>, SolverError> {
    let mut slope = vec![0.0; 4 * cells];
    for (j, off) in GAUSS_OFFSETS.iter().enumerate() {
        for comp in 0..2 {
            let sub: Vec<f64> = (0..cells)
                .map(|c| reference[4 * c + 2 * j + comp])
                .collect();
            let t = TrigInterpolant::with_offset(&sub, off / cells as f64)?;
            for c in 0..cells {
                slope[4 * c + 2 * j + comp] = t.derivative((c as f64 + off) / cells as f64);
            }
        }
    }
    let rms = (slope.iter().map(|v| v * v).sum::<f64>() / slope.len() as f64).sqrt();
    let scale = reference.iter().map(|v| v.abs()).fold(0.0, f64::max);
    if !(rms.is_finite() && rms > 1e-9 * (1.0 + scale)) {
        return Ok(None);
    }
    Ok(Some(slope.into_iter().map(|v| v / rms).collect()))
}

/// The frame at node transforms: the rotation block of `P`.
pub fn rotation(p: &M4) -> Matrix3<f64> {
    p.fixed_view::<3, 3>(0, 0).into_owned()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Fischer–Burmeister form: zero exactly on the complementarity set, its slopes equal
    /// to central differences of its value, and the KKT Jacobian of the model in that form
    /// equal to central differences of its residual, with the `O(N)` lifted step equal to
    /// the dense LU step.
    #[test]
    fn fischer_burmeister_rows_match_finite_differences() {
        let fb = Complementarity::FischerBurmeister;
        for (a, b) in [(0.0, 2.0), (3.0, 0.0), (0.0, 0.0)] {
            assert_eq!(fb.eval(a, b).0, 0.0);
        }
        for (a, b) in [
            (0.5, 1e-3),
            (-0.2, 0.7),
            (1e-4, -3.0),
            (2.0, 2.5),
            (-1.0, -0.5),
        ] {
            let (v, da, db) = fb.eval(a, b);
            assert!(v != 0.0);
            let h = 1e-6;
            let na = (fb.eval(a + h, b).0 - fb.eval(a - h, b).0) / (2.0 * h);
            let nb = (fb.eval(a, b + h).0 - fb.eval(a, b - h).0) / (2.0 * h);
            assert!((na - da).abs() < 1e-7 && (nb - db).abs() < 1e-7, "{a} {b}");
        }
        // The circle of L̄ = 1 on the wall, perturbed, with multipliers of either sign.
        let (m, mut z) =
            crate::enclosed::free_circle(1.0, 1.0, 12, &Stiffness::uniform(1.0)).expect("circle");
        let m = m.with_complementarity(fb);
        let mut s = 12345u64;
        let mut next = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        };
        for v in z.iter_mut() {
            *v += 1e-3 * next();
        }
        let lo = m.lambda_offset();
        for j in 0..m.cells() {
            // Away from the kink, where `φ`'s third derivative (`~1/r²`) keeps the
            // differences' error small.
            let v = next();
            z[lo + j] = (0.05 + 0.05 * v.abs()).copysign(v);
        }
        let ev = m.evaluate(&z).expect("evaluate");
        let h = 1e-6;
        let mut worst = 0.0f64;
        for k in 0..m.dim() {
            let (mut zp, mut zm) = (z.clone(), z.clone());
            zp[k] += h;
            zm[k] -= h;
            let col = (m.residual(&zp).unwrap() - m.residual(&zm).unwrap()) / (2.0 * h);
            for i in 0..m.dim() {
                worst = worst.max((col[i] - ev.jacobian[(i, k)]).abs());
            }
        }
        let worst = worst / ev.jacobian.amax();
        assert!(
            worst < 1e-7,
            "Jacobian against differences (relative): {worst:.2e}"
        );
        let (_, step) = m.newton_step(&z).expect("lifted step");
        let dense = ev
            .jacobian
            .lu()
            .solve(&(-&ev.residual))
            .expect("dense step");
        let rel = (&step - &dense).norm() / dense.norm();
        assert!(rel < 1e-8, "lifted against dense step: {rel:.2e}");
    }

    fn frame(r: Matrix3<f64>) -> M4 {
        let mut m = M4::identity();
        m.fixed_view_mut::<3, 3>(0, 0).copy_from(&r);
        m
    }

    fn rot(axis: V3, angle: f64) -> Matrix3<f64> {
        crate::frame::expm_skew(&crate::frame::hat(&(axis.normalize() * angle)))
    }

    /// The tangent rows of the closure vanish where the tangent returns, whatever the turn
    /// of the frame about it (a half-turn included), and among the other half-turns only
    /// where the tangent comes back reversed; their Jacobian has rank 2 at every such turn. `vee(skew X)` vanishes at every
    /// half-turn (the tangent then comes back at `2β` from `e1` for an axis at `β`) and its
    /// Jacobian vanishes at the half-turn about the tangent.
    #[test]
    fn tangent_closure_is_zero_only_where_the_tangent_returns_and_has_full_rank() {
        let rows = |x: &M4| {
            let v = closure_rotation(x);
            [v[1], v[2]]
        };
        for alpha in [0.0, 0.3, -2.0, PI - 1e-3, PI] {
            let x = frame(rot(V3::x(), alpha));
            let [a, b] = rows(&x);
            assert!(a.abs() < 1e-15 && b.abs() < 1e-15, "{alpha}");
            // Jacobian in a body rotation ω = (0, ω_y, ω_z), central differences.
            let h = 1e-6;
            let mut jac = [[0.0; 2]; 2];
            for (k, col) in [V3::y(), V3::z()].iter().enumerate() {
                let p = rows(&(x * frame(rot(*col, h))));
                let m = rows(&(x * frame(rot(*col, -h))));
                for i in 0..2 {
                    jac[i][k] = (p[i] - m[i]) / (2.0 * h);
                }
            }
            let det = jac[0][0] * jac[1][1] - jac[0][1] * jac[1][0];
            assert!((det - 1.0).abs() < 1e-8, "alpha {alpha}: det {det}");
        }
        for beta in [0.05f64, 0.3, 1.0, PI / 2.0] {
            let axis = V3::new(beta.cos(), beta.sin(), 0.0);
            let x = frame(rot(axis, PI));
            let [a, b] = rows(&x);
            // Xᵀe1 = t(L) = (cos 2β, sin 2β, 0) (X symmetric): the rows are (0, −sin 2β),
            // zero only for the reversed tangent (β = π/2, a cusp that verification refuses).
            assert!(
                a.abs() < 1e-15 && (b + (2.0 * beta).sin()).abs() < 1e-12,
                "{beta}"
            );
            if beta < PI / 2.0 {
                assert!(b < -0.09, "beta {beta}: {b}");
            }
            let old = vee_skew3(&x);
            assert!(old[1].abs() < 1e-15 && old[2].abs() < 1e-15);
        }
    }
}
