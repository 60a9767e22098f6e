//! The discretised surface model: a closed loop on a sphere described by its geodesic
//! curvature at Gauss points, its energy, its closure (holonomy) condition and the KKT system
//! of constrained equilibrium with analytic first and second derivatives.
//!
//! # Formulation
//!
//! A closed curve on the sphere of radius `R` is determined up to a rotation by its geodesic
//! curvature `κ_g(s)`: the Darboux frame `X(s)` (rows `t, g, n`, `n = r/R`) obeys
//! `X' = Ω(κ_g) X` (App. A with `κ_n = −1/R`, `τ_g = 0`; see [`crate::frame`]) and
//! `r = R n`. Every iterate therefore lies exactly on the sphere with `|r'| = 1`: both
//! constraints of Sec. 2 hold by construction, and closure of the loop with a continuous
//! tangent is the holonomy condition `X(L) = X(0)` (three equations).
//!
//! Rigid rotations of the loop do not appear: `κ_g` is invariant under them, and the frame
//! starts from `X(0) = I` (the loop is reported in that orientation).
//!
//! # Discretisation ("Gauss collocation")
//!
//! `N` equal cells of length `h = L/N`; the unknowns are `κ_g` at the two Gauss points of
//! every cell, `s_{c,1,2} = (c + 1/2 ∓ √3/6) h`, stored as `κ[2c + j]`.
//!
//! * Energy, Eq. (2) with `κ² = κ_g² + 1/R²` (Sec. 3.1) and two-point Gauss quadrature:
//!   `E = Σ_c (h/2) Σ_j ½ D(s_cj)(κ_cj² + 1/R²)`.
//! * Cell propagator (fourth-order Magnus): `E_c = exp(Θ_c)`,
//!   `Θ_c = (h/2)(Ω(κ_c1) + Ω(κ_c2)) + (√3/12)h² [Ω(κ_c2), Ω(κ_c1)]`. As `Ω = κA + B` is
//!   affine in `κ`, the commutator is `(κ_c2 − κ_c1)[A, B]` and `Θ_c` is affine in the two
//!   cell unknowns. Holonomy `H = E_{N−1} ⋯ E_0`.
//! * Closure `c(κ) = 2 vee(skew H)/√(1 + tr H)` (`vee(skew H) = ((H₃₂ − H₂₃), (H₁₃ − H₃₁),
//!   (H₂₁ − H₁₂))/2`): twice the vector part of the holonomy's unit quaternion with its
//!   scalar part non-negative, `2 sin(θ/2) u` for a rotation by `θ` about `u`. It is zero
//!   only at `H = I`; `vee(skew H)` alone also vanishes at every half-turn, which would let
//!   Newton converge to an open loop. Near `H = I`, `μ·c = −½ tr(hat(μ) H) + O(|H − I|²)`;
//!   the exact first and second derivatives are given with the internal `Closure` map.
//! * Lagrangian `ℒ = E − μ·c − ν φ`, with the phase condition `φ` (uniform `D` only, see
//!   [`Phase`]). KKT residual `F(z) = (∇E − ∇cᵀμ − ν∇φ, −c, −φ)`, `z = (κ, μ, ν)`, whose
//!   Jacobian `[[∇²ℒ, −∇cᵀ, −∇φ], [−∇c, 0, 0], [−∇φᵀ, 0, 0]]` is symmetric.
//!
//! Derivatives of `H`: each unknown lives in one cell, `∂H/∂κ_a = S_c ∂E_c P_c` with the
//! prefix `P_c = E_{c−1}⋯E_0` and suffix `S_c = E_{N−1}⋯E_{c+1}`; second derivatives for
//! unknowns in cells `c < c'` are `S_{c'} ∂E_{c'} (E_{c'−1}⋯E_{c+1}) ∂E_c P_c`, in one cell
//! `S_c ∂²E_c P_c`. The cell derivatives come exactly from a second-order jet through
//! Rodrigues' formula ([`crate::frame::exp_jet`]); the full Hessian costs `O(N²)` 3×3
//! products.
//!
//! # Multiplier and conserved moment
//!
//! In the continuum, `δH = H ∫ δκ_g X(s)ᵀ A X(s) ds = −H ∫ δκ_g hat(n(s)) ds`, so at a closed
//! loop `∇c = −n(s)` (per unit length) and stationarity reads `D κ_g = −μ·n`. Comparing with
//! `𝓜·n = Dκ_g` (Eq. 41) identifies the conserved moment about the sphere centre (Sec. 4.3)
//! with `𝓜 = −μ` (in the frame where `X(0) = I`); see [`crate::Equilibrium::moment`].
//!
//! # Size
//!
//! This file is longer than most because the energy, the holonomy, the closure and their
//! first and second derivatives share one private cell chain (the propagators `E_c` and their
//! prefix/suffix products) and the formulation above: split apart they would need that chain
//! made public. The KKT system assembled from them (residual, Jacobian, parameter derivatives,
//! norms) is the child module `kkt_system`.

use std::f64::consts::PI;

use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

use crate::frame::{
    exp_jet1_into, exp_jet2_affine_into, exp_jet_last_into, exp_value, expm_skew, hat,
};
use crate::mesh::MeshMap;
use crate::periodic::TrigInterpolant;
use crate::stiffness::{Stiffness, StiffnessProfile};
use crate::SolverError;

type M3 = Matrix3<f64>;
type V3 = Vector3<f64>;

mod kkt_system;

/// `√3/6`, offset of the Gauss points from the cell centre in units of `h`.
pub const GAUSS_HALF_GAP: f64 = 0.288_675_134_594_812_9;

/// Positions of the two Gauss points inside a cell, in units of `h`.
pub const GAUSS_OFFSETS: [f64; 2] = [0.5 - GAUSS_HALF_GAP, 0.5 + GAUSS_HALF_GAP];

/// `√3/12`, coefficient of the Magnus commutator term.
const MAGNUS_C: f64 = 0.144_337_567_297_406_43;

/// Phase condition fixing the arclength-shift symmetry of a uniform rod.
///
/// `φ(κ) = (1/2N) Σ_a κ̇_ref,a (κ_a − κ_ref,a)`, with `κ_ref` a reference profile at the
/// Gauss points and `κ̇_ref = dκ_ref/dσ` (`σ = s/L`) normalised to unit root-mean-square.
/// `φ = 0` says that `κ` has no component along the shift mode of the reference. Both
/// arrays are functions of `σ`, so the condition does not depend on `L̄` (it is held fixed
/// during continuation in `L̄`).
#[derive(Clone, Debug, PartialEq)]
pub struct Phase {
    reference: Vec<f64>,
    slope: Vec<f64>,
}

impl Phase {
    /// Phase condition from reference values at the Gauss points of `cells` cells; the
    /// slope is obtained by spectral differentiation on each of the two interleaved uniform
    /// sub-grids (`σ = (c + offset_j)/N`).
    pub fn from_gauss_values(reference: &[f64], cells: usize) -> Result<Self, SolverError> {
        check_len(reference.len(), 2 * cells)?;
        let mut slope = vec![0.0; 2 * cells];
        for (j, off) in GAUSS_OFFSETS.iter().enumerate() {
            let sub: Vec<f64> = (0..cells).map(|c| reference[2 * c + j]).collect();
            let t = TrigInterpolant::with_offset(&sub, off / cells as f64)?;
            for c in 0..cells {
                slope[2 * c + j] = t.derivative((c as f64 + off) / cells as f64);
            }
        }
        Self::from_parts(reference.to_vec(), slope)
    }

    /// Phase condition from reference values and their σ-derivatives at the Gauss points.
    pub fn from_parts(reference: Vec<f64>, mut slope: Vec<f64>) -> Result<Self, SolverError> {
        check_len(slope.len(), reference.len())?;
        let n = slope.len().max(1) as f64;
        let rms = (slope.iter().map(|v| v * v).sum::<f64>() / n).sqrt();
        let scale = reference.iter().map(|v| v.abs()).fold(0.0, f64::max);
        if !(rms.is_finite() && rms > 1e-9 * (1.0 + scale)) {
            return Err(SolverError::InvalidInput(
                "the phase reference is (nearly) constant: it has no arclength-shift mode \
                 (a circle needs no phase condition)"
                    .into(),
            ));
        }
        for v in &mut slope {
            *v /= rms;
        }
        Ok(Self { reference, slope })
    }

    /// `φ(κ)`.
    pub fn value(&self, kappa: &[f64]) -> f64 {
        let n = self.slope.len() as f64;
        self.slope
            .iter()
            .zip(kappa.iter().zip(&self.reference))
            .map(|(s, (k, r))| s * (k - r))
            .sum::<f64>()
            / n
    }

    /// `∂φ/∂κ_a` (constant: φ is linear).
    pub fn gradient(&self) -> Vec<f64> {
        let n = self.slope.len() as f64;
        self.slope.iter().map(|s| s / n).collect()
    }

    /// Reference profile at the Gauss points.
    pub fn reference(&self) -> &[f64] {
        &self.reference
    }

    /// Normalised reference slope `dκ_ref/dσ` at the Gauss points (unit RMS).
    pub fn slope(&self) -> &[f64] {
        &self.slope
    }
}

fn check_len(found: usize, expected: usize) -> Result<(), SolverError> {
    if found != expected {
        return Err(SolverError::WrongLength { expected, found });
    }
    Ok(())
}

/// The discretised loop on a sphere (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct SurfaceModel {
    radius: f64,
    lbar: f64,
    cells: usize,
    stiffness: StiffnessProfile,
    phase: Option<Phase>,
    /// `D` at the Gauss points (functions of `σ` only, hence independent of `L̄`).
    d_gauss: Vec<f64>,
    /// The mesh map and the cell boundaries `σ_0 = 0 < … < σ_N = 1`.
    map: MeshMap,
    bounds: Vec<f64>,
}

/// Cell propagators with their derivatives and the prefix/suffix products.
pub(crate) struct Chain {
    pub(crate) e: Vec<M3>,
    pub(crate) de: Vec<[M3; 2]>,
    /// `[∂₁₁, ∂₁₂, ∂₂₂]` (empty for [`SurfaceModel::chain1`]).
    pub(crate) dde: Vec<[M3; 3]>,
    /// `P_c = E_{c−1}⋯E_0`, `c = 0..=N` (`P_N = H`).
    pub(crate) prefix: Vec<M3>,
    /// `S_c = E_{N−1}⋯E_{c+1}`, `c = 0..N`.
    pub(crate) suffix: Vec<M3>,
}

/// `vee(skew(X))`.
pub(crate) fn vee_skew(x: &M3) -> V3 {
    V3::new(
        0.5 * (x[(2, 1)] - x[(1, 2)]),
        0.5 * (x[(0, 2)] - x[(2, 0)]),
        0.5 * (x[(1, 0)] - x[(0, 1)]),
    )
}

/// The closure residual as a function of the holonomy `H` (a rotation by `θ` about `u`):
/// `c(H) = 2 vee(skew H)/√(1 + tr H)`, twice the vector part of the unit quaternion of `H`
/// with its scalar part taken non-negative, `c = 2 sin(θ/2) u` for `θ ∈ [0, π)`.
///
/// `vee(skew H) = sin θ u` alone vanishes at half-turns (`θ = π`) as well as at the
/// identity, so Newton could converge to an open loop; `|c| = 2 sin(θ/2)` vanishes only at
/// `H = I` (and tends to 2 at a half-turn). Near the identity `c = θu + O(θ³)`, as
/// `vee(skew H)` is, and at `H = I` both have the same Jacobian, so the multiplier keeps its
/// meaning (`𝓜 = −μ`) and the constrained Hessian at an equilibrium is unchanged (the extra
/// terms below vanish there). No smooth map `SO(3) → ℝ³` with an invertible Jacobian at `I`
/// vanishes only at `I` (the sphere around `I` would have degree ±1 and bound `ℝP²`), so
/// some singularity is unavoidable: here it is at the half-turns (`1 + tr H → 0`), where
/// `|c| → 2`, far from a root. There the value comes from Shepperd's stable quaternion
/// extraction and the derivatives from the formula with `1 + tr H` floored at
/// [`HALF_TURN_FLOOR`] (no Newton iterate converges there).
///
/// With `v = vee(skew H)`, `t = tr H`, `s(t) = 2/√(1 + t)` and a variation `δH = hat(ξ) H`:
/// `δv = B ξ` (`B e_k = vee(skew(hat(e_k) H))`), `δt = −2 v·ξ`, so
/// `δc = J ξ` with `J = s B − 2 s' v vᵀ`; for `φ = μ·c`,
/// `Dφ[X] = s μ·vee(skew X) + s'(μ·v) tr X = −½ tr(M X)` with `M = s hat(μ) − 2s'(μ·v) I`,
/// and `D²φ[hat(ξ)H, hat(ζ)H] = ξᵀ K ζ` with
/// `K = −2s'(Bᵀμ vᵀ + v μᵀB) + 4 s''(μ·v) v vᵀ`.
#[derive(Clone, Debug)]
pub(crate) struct Closure {
    /// `c(H)`.
    pub(crate) value: V3,
    /// `J`, the derivative of `c` along `δH = hat(ξ)H`.
    pub(crate) jac: M3,
    v: V3,
    b: M3,
    s: f64,
    s1: f64,
    s2: f64,
}

/// Floor of `1 + tr H` (`= 4 cos²(θ/2)`) in the closure derivatives; below it (`θ` within
/// about `1e-4` of a half-turn) the value of the residual comes from Shepperd's method.
pub const HALF_TURN_FLOOR: f64 = 1e-8;

impl Closure {
    pub(crate) fn of(h: &M3) -> Self {
        let v = vee_skew(h);
        let t = h.trace();
        let p = (1.0 + t).max(HALF_TURN_FLOOR);
        let s = 2.0 / p.sqrt();
        let s1 = -1.0 / (p * p.sqrt());
        let s2 = 1.5 / (p * p * p.sqrt());
        let mut b = M3::zeros();
        for k in 0..3 {
            b.set_column(k, &vee_skew(&(hat(&V3::ith(k, 1.0)) * h)));
        }
        let jac = b * s - v * v.transpose() * (2.0 * s1);
        let value = if 1.0 + t >= HALF_TURN_FLOOR {
            v * s
        } else {
            half_turn_residual(h)
        };
        Self {
            value,
            jac,
            v,
            b,
            s,
            s1,
            s2,
        }
    }

    /// `M` with `D(μ·c)[X] = −½ tr(M X)`.
    pub(crate) fn first(&self, mu: &V3) -> M3 {
        hat(mu) * self.s - M3::identity() * (2.0 * self.s1 * mu.dot(&self.v))
    }

    /// `K` with `D²(μ·c)[hat(ξ)H, hat(ζ)H] = ξᵀ K ζ` (symmetric).
    pub(crate) fn second(&self, mu: &V3) -> M3 {
        let btm = self.b.transpose() * mu;
        let cross = btm * self.v.transpose();
        (cross + cross.transpose()) * (-2.0 * self.s1)
            + self.v * self.v.transpose() * (4.0 * self.s2 * mu.dot(&self.v))
    }
}

/// `2 q_v` of the unit quaternion `(q_w, q_v)` of the rotation `h`, `q_w ≥ 0`, by Shepperd's
/// method from the largest diagonal entry (stable at a half-turn, where `q_w → 0`).
fn half_turn_residual(h: &M3) -> V3 {
    let t = h.trace();
    let i = (0..3)
        .max_by(|&a, &b| h[(a, a)].total_cmp(&h[(b, b)]))
        .unwrap_or(0);
    let (j, k) = ((i + 1) % 3, (i + 2) % 3);
    let xi = 0.5 * (1.0 + 2.0 * h[(i, i)] - t).max(0.0).sqrt();
    let mut x = V3::zeros();
    x[i] = xi;
    if xi > 0.0 {
        x[j] = (h[(i, j)] + h[(j, i)]) / (4.0 * xi);
        x[k] = (h[(i, k)] + h[(k, i)]) / (4.0 * xi);
        let w = vee_skew(h)[i] / (2.0 * xi);
        if w < 0.0 {
            x = -x;
        }
    }
    x * 2.0
}

/// `tr(A B)`.
pub(crate) fn tr_prod(a: &M3, b: &M3) -> f64 {
    let mut s = 0.0;
    for i in 0..3 {
        for j in 0..3 {
            s += a[(i, j)] * b[(j, i)];
        }
    }
    s
}

/// `L̄` must be positive and finite (every model and continuation step checks it).
pub(crate) fn check_lbar(lbar: f64) -> Result<(), SolverError> {
    if !(lbar.is_finite() && lbar > 0.0) {
        return Err(SolverError::InvalidInput(format!(
            "normalised length L̄ must be positive and finite (got {lbar})"
        )));
    }
    Ok(())
}

/// The inputs every discretised loop shares (the surface model and the enclosed one): a
/// positive finite sphere radius and `L̄`, and at least `min_cells` cells.
pub(crate) fn check_loop_inputs(
    radius: f64,
    lbar: f64,
    cells: usize,
    min_cells: usize,
) -> Result<(), SolverError> {
    if !(radius.is_finite() && radius > 0.0) {
        return Err(SolverError::InvalidInput(format!(
            "sphere radius must be positive and finite (got {radius})"
        )));
    }
    check_lbar(lbar)?;
    if cells < min_cells {
        return Err(SolverError::InvalidInput(format!(
            "at least {min_cells} cells are needed (got {cells})"
        )));
    }
    Ok(())
}

impl SurfaceModel {
    /// Loop of normalised length `lbar = L/(2πR)` on a sphere of radius `radius`, discretised
    /// with `cells` cells, with bending stiffness `stiffness` (validated here). No phase
    /// condition: add one with [`SurfaceModel::with_phase`] for uniform rods (the solver does
    /// so automatically from the starting shape).
    pub fn new(
        radius: f64,
        lbar: f64,
        cells: usize,
        stiffness: &Stiffness,
    ) -> Result<Self, SolverError> {
        check_loop_inputs(radius, lbar, cells, 4)?;
        let profile = stiffness.validate()?;
        let mut m = Self {
            radius,
            lbar,
            cells,
            stiffness: profile,
            phase: None,
            d_gauss: Vec::new(),
            map: MeshMap::Uniform,
            bounds: Vec::new(),
        };
        m.set_mesh(MeshMap::for_profile(stiffness))?;
        Ok(m)
    }

    fn set_mesh(&mut self, map: MeshMap) -> Result<(), SolverError> {
        self.bounds = map.bounds(self.cells)?;
        self.map = map;
        self.d_gauss = (0..2 * self.cells)
            .map(|a| self.stiffness.eval(self.sigma_of(a)).d)
            .collect();
        Ok(())
    }

    /// The same model on another mesh map (the default is [`MeshMap::for_profile`]).
    /// Drops a phase condition unless the new mesh is uniform.
    pub fn with_mesh(mut self, map: MeshMap) -> Result<Self, SolverError> {
        if !map.is_uniform() {
            self.phase = None;
        }
        self.set_mesh(map)?;
        Ok(self)
    }

    /// The mesh map.
    pub fn mesh(&self) -> &MeshMap {
        &self.map
    }

    /// Cell boundaries `σ_i = s_i/L`, `i = 0..=N`.
    pub fn bounds(&self) -> &[f64] {
        &self.bounds
    }

    /// The same model with a phase condition (uniform meshes only: the phase condition is
    /// for uniform rods, whose mesh is uniform).
    pub fn with_phase(mut self, phase: Phase) -> Result<Self, SolverError> {
        check_len(phase.reference.len(), 2 * self.cells)?;
        if !self.map.is_uniform() {
            return Err(SolverError::InvalidInput(
                "a phase condition needs a uniform mesh".into(),
            ));
        }
        self.phase = Some(phase);
        Ok(self)
    }

    /// The same model without phase condition.
    pub fn without_phase(mut self) -> Self {
        self.phase = None;
        self
    }

    /// The same model at another normalised length (same cells, profile and phase).
    pub fn with_lbar(&self, lbar: f64) -> Result<Self, SolverError> {
        check_lbar(lbar)?;
        let mut m = self.clone();
        m.lbar = lbar;
        Ok(m)
    }

    fn sigma_of(&self, a: usize) -> f64 {
        let c = a / 2;
        self.bounds[c] + GAUSS_OFFSETS[a % 2] * (self.bounds[c + 1] - self.bounds[c])
    }

    /// Sphere radius `R`.
    pub fn radius(&self) -> f64 {
        self.radius
    }

    /// Normalised length `L̄ = L/(2πR)`.
    pub fn lbar(&self) -> f64 {
        self.lbar
    }

    /// Number of cells `N`.
    pub fn cells(&self) -> usize {
        self.cells
    }

    /// Number of curvature unknowns `2N`.
    pub fn n_kappa(&self) -> usize {
        2 * self.cells
    }

    /// Number of multipliers: 3 (closure) plus 1 with a phase condition.
    pub fn n_multipliers(&self) -> usize {
        3 + usize::from(self.phase.is_some())
    }

    /// Size of the KKT system, `2N + 3 (+1)`.
    pub fn dim(&self) -> usize {
        self.n_kappa() + self.n_multipliers()
    }

    /// Loop length `L = 2πR L̄`.
    pub fn length(&self) -> f64 {
        2.0 * PI * self.radius * self.lbar
    }

    /// Mean cell length `L/N` (the cell length of a uniform mesh).
    pub fn h(&self) -> f64 {
        self.length() / self.cells as f64
    }

    /// Length `h_c` of cell `c`.
    pub fn cell_length(&self, c: usize) -> f64 {
        self.length() * (self.bounds[c + 1] - self.bounds[c])
    }

    /// Quadrature weight `h_c/2` of the two unknowns of cell `c`.
    pub fn cell_weight(&self, c: usize) -> f64 {
        0.5 * self.cell_length(c)
    }

    /// The validated stiffness profile.
    pub fn stiffness(&self) -> &StiffnessProfile {
        &self.stiffness
    }

    /// The phase condition, if any.
    pub fn phase(&self) -> Option<&Phase> {
        self.phase.as_ref()
    }

    /// Normalised arclength `σ = s/L` of every unknown (the Gauss points).
    pub fn gauss_sigma(&self) -> Vec<f64> {
        (0..self.n_kappa()).map(|a| self.sigma_of(a)).collect()
    }

    /// Mean quadrature weight `L/(2N)` (the weight of every unknown on a uniform mesh; see
    /// [`SurfaceModel::cell_weight`]).
    pub fn weight(&self) -> f64 {
        0.5 * self.h()
    }

    /// `D` at the Gauss points.
    pub fn d_gauss(&self) -> &[f64] {
        &self.d_gauss
    }

    pub(crate) fn check_kappa(&self, kappa: &[f64]) -> Result<(), SolverError> {
        check_len(kappa.len(), self.n_kappa())?;
        if let Some(i) = kappa.iter().position(|v| !v.is_finite()) {
            return Err(SolverError::InvalidInput(format!(
                "curvature unknown {i} is not finite ({})",
                kappa[i]
            )));
        }
        Ok(())
    }

    /// `(ω0, v1, v2)` with `Θ_c = hat(ω0 + κ_c1 v1 + κ_c2 v2)` for cell length `h`.
    fn cell_vectors(&self, h: f64) -> (V3, V3, V3) {
        let r = self.radius;
        let w0 = V3::new(0.0, -h / r, 0.0);
        let v1 = V3::new(MAGNUS_C * h * h / r, 0.0, -0.5 * h);
        let v2 = V3::new(-MAGNUS_C * h * h / r, 0.0, -0.5 * h);
        (w0, v1, v2)
    }

    /// Cell propagators `E_c` only.
    fn propagators(&self, kappa: &[f64]) -> Vec<M3> {
        (0..self.cells)
            .map(|c| {
                let (w0, v1, v2) = self.cell_vectors(self.cell_length(c));
                expm_skew(&hat(&(w0 + v1 * kappa[2 * c] + v2 * kappa[2 * c + 1])))
            })
            .collect()
    }

    /// The chain with second derivatives (what the Hessian and the Newton matrix need).
    pub(crate) fn chain(&self, kappa: &[f64]) -> Chain {
        self.chain_with(kappa, true)
    }

    /// The chain without second derivatives (`dde` empty): enough for the KKT residual and
    /// the closure Jacobian.
    pub(crate) fn chain1(&self, kappa: &[f64]) -> Chain {
        self.chain_with(kappa, false)
    }

    fn chain_with(&self, kappa: &[f64], second: bool) -> Chain {
        let n = self.cells;
        // The jets are written in place into arrays of their final size.
        let mut e = vec![M3::zeros(); n];
        let mut de = vec![[M3::zeros(); 2]; n];
        let mut dde = vec![[M3::zeros(); 3]; if second { n } else { 0 }];
        for (c, (ec, d)) in e.iter_mut().zip(de.iter_mut()).enumerate() {
            let (w0, v1, v2) = self.cell_vectors(self.cell_length(c));
            let w = w0 + v1 * kappa[2 * c] + v2 * kappa[2 * c + 1];
            if second {
                exp_jet2_affine_into(&w, &[v1, v2], ec, d, &mut dde[c]);
            } else {
                exp_jet1_into(&w, &[v1, v2], ec, d);
            }
        }
        let (prefix, suffix) = prefix_suffix(&e);
        Chain {
            e,
            de,
            dde,
            prefix,
            suffix,
        }
    }

    /// Holonomy `H = E_{N−1} ⋯ E_0` (the frame at `s = L` when `X(0) = I`).
    pub fn holonomy(&self, kappa: &[f64]) -> Result<M3, SolverError> {
        self.check_kappa(kappa)?;
        Ok(self
            .propagators(kappa)
            .iter()
            .fold(M3::identity(), |acc, e| e * acc))
    }

    /// Frames `X(s_i)` (rows `t, g, n`) at the cell boundaries `s_i = i h`, `i = 0..=N`.
    pub fn frames(&self, kappa: &[f64]) -> Result<Vec<M3>, SolverError> {
        self.check_kappa(kappa)?;
        let e = self.propagators(kappa);
        let mut out = Vec::with_capacity(self.cells + 1);
        let mut x = M3::identity();
        out.push(x);
        for ec in &e {
            x = ec * x;
            out.push(x);
        }
        Ok(out)
    }

    /// Closure residual and its Jacobian from one pass over the cells.
    pub fn closure_with_jacobian(
        &self,
        kappa: &[f64],
    ) -> Result<([f64; 3], DMatrix<f64>), SolverError> {
        self.check_kappa(kappa)?;
        let ch = self.chain1(kappa);
        let v = Closure::of(&ch.prefix[self.cells]).value;
        Ok(([v[0], v[1], v[2]], self.closure_jacobian_from(&ch)))
    }

    /// Closure residual `c(κ) = 2 vee(skew H)/√(1 + tr H)`, zero only when the holonomy `H`
    /// is the identity (see the module docs).
    pub fn closure(&self, kappa: &[f64]) -> Result<[f64; 3], SolverError> {
        let h = self.holonomy(kappa)?;
        let v = Closure::of(&h).value;
        Ok([v[0], v[1], v[2]])
    }

    /// Discrete energy `E` (dimensional), two-point Gauss quadrature of Eq. (2).
    pub fn energy(&self, kappa: &[f64]) -> Result<f64, SolverError> {
        self.check_kappa(kappa)?;
        let (g, n) = self.energy_parts_raw(kappa);
        Ok(g + n)
    }

    /// `(E_g, E_n)`: geodesic and normal parts of the discrete energy (dimensional).
    fn energy_parts_raw(&self, kappa: &[f64]) -> (f64, f64) {
        let r2 = 1.0 / (self.radius * self.radius);
        let mut eg = 0.0;
        let mut en = 0.0;
        for (a, (k, d)) in kappa.iter().zip(&self.d_gauss).enumerate() {
            let w = self.cell_weight(a / 2);
            eg += 0.5 * w * d * k * k;
            en += 0.5 * w * d * r2;
        }
        (eg, en)
    }

    /// Energy parts normalised as `E R/(π D0)` (`D0` = [`Stiffness::reference`]):
    /// `(total, geodesic, normal)`. For uniform `D` the normal part is `L̄` (Sec. 3.1).
    pub fn energy_normalized(&self, kappa: &[f64]) -> Result<(f64, f64, f64), SolverError> {
        self.check_kappa(kappa)?;
        let (g, n) = self.energy_parts_raw(kappa);
        let scale = self.radius / (PI * self.stiffness.kind().reference());
        Ok(((g + n) * scale, g * scale, n * scale))
    }

    /// Gradient of the energy, `∂E/∂κ_a = (h_c/2) D_a κ_a`.
    pub fn energy_gradient(&self, kappa: &[f64]) -> Result<Vec<f64>, SolverError> {
        self.check_kappa(kappa)?;
        Ok(kappa
            .iter()
            .zip(&self.d_gauss)
            .enumerate()
            .map(|(a, (k, d))| self.cell_weight(a / 2) * d * k)
            .collect())
    }

    /// Constraint Jacobian `∇c` (3 × 2N).
    pub fn closure_jacobian(&self, kappa: &[f64]) -> Result<DMatrix<f64>, SolverError> {
        self.check_kappa(kappa)?;
        let ch = self.chain1(kappa);
        Ok(self.closure_jacobian_from(&ch))
    }

    pub(crate) fn closure_jacobian_from(&self, ch: &Chain) -> DMatrix<f64> {
        let cl = Closure::of(&ch.prefix[self.cells]);
        let mut j = DMatrix::zeros(3, self.n_kappa());
        for c in 0..self.cells {
            for i in 0..2 {
                // δc = s δv + s' v δt for the variation X = ∂H/∂κ_a.
                let x = ch.suffix[c] * ch.de[c][i] * ch.prefix[c];
                let v = vee_skew(&x) * cl.s + cl.v * (cl.s1 * x.trace());
                for k in 0..3 {
                    j[(k, 2 * c + i)] = v[k];
                }
            }
        }
        j
    }

    /// Hessian of `μ·c(κ)` (2N × 2N): `−½ tr(M ∂²H)` with `M` from `Closure::first`, plus
    /// `Ξᵀ K Ξ` (`Closure::second`) with the columns `Ξ_a = vee(∂_aH Hᵀ)`.
    fn closure_hessian_from(&self, ch: &Chain, mu: &V3) -> DMatrix<f64> {
        let n = self.cells;
        let hol = ch.prefix[n];
        let cl = Closure::of(&hol);
        let m = cl.first(mu);
        // K_c = M S_c and G_{c,i} = K_c ∂_i E_c, so that tr(∂_i E_c R M S_c) = tr(R G_{c,i}).
        let k: Vec<M3> = ch.suffix.iter().map(|s| m * s).collect();
        let g: Vec<[M3; 2]> = (0..n)
            .map(|c| [k[c] * ch.de[c][0], k[c] * ch.de[c][1]])
            .collect();
        let mut hess = DMatrix::zeros(2 * n, 2 * n);
        for c in 0..n {
            // Same cell: −½ tr(∂²E_c P_c K_c).
            let pk = ch.prefix[c] * k[c];
            let h11 = -0.5 * tr_prod(&ch.dde[c][0], &pk);
            let h12 = -0.5 * tr_prod(&ch.dde[c][1], &pk);
            let h22 = -0.5 * tr_prod(&ch.dde[c][2], &pk);
            hess[(2 * c, 2 * c)] = h11;
            hess[(2 * c, 2 * c + 1)] = h12;
            hess[(2 * c + 1, 2 * c)] = h12;
            hess[(2 * c + 1, 2 * c + 1)] = h22;
            // Cells c < c': −½ tr(M S_{c'} ∂_i E_{c'} Q ∂_j E_c P_c), Q = E_{c'−1}⋯E_{c+1}.
            for j in 0..2 {
                let mut r = ch.de[c][j] * ch.prefix[c];
                for cp in c + 1..n {
                    for i in 0..2 {
                        let v = -0.5 * tr_prod(&r, &g[cp][i]);
                        hess[(2 * cp + i, 2 * c + j)] = v;
                        hess[(2 * c + j, 2 * cp + i)] = v;
                    }
                    r = ch.e[cp] * r;
                }
            }
        }
        let kmat = cl.second(mu);
        if kmat.amax() > 0.0 {
            let ht = hol.transpose();
            let xi: Vec<V3> = (0..2 * n)
                .map(|a| {
                    vee_skew(&(ch.suffix[a / 2] * ch.de[a / 2][a % 2] * ch.prefix[a / 2] * ht))
                })
                .collect();
            let kxi: Vec<V3> = xi.iter().map(|x| kmat * x).collect();
            for a in 0..2 * n {
                for b in 0..2 * n {
                    hess[(a, b)] += xi[a].dot(&kxi[b]);
                }
            }
        }
        hess
    }

    /// Hessian of the Lagrangian `∇²ℒ = ∇²E − ∇²(μ·c)` (2N × 2N) at `(κ, μ)`; `φ` is linear
    /// and does not contribute.
    pub fn lagrangian_hessian(
        &self,
        kappa: &[f64],
        mu: &[f64; 3],
    ) -> Result<DMatrix<f64>, SolverError> {
        self.check_kappa(kappa)?;
        let ch = self.chain(kappa);
        Ok(self.lagrangian_hessian_from(&ch, &V3::from(*mu)))
    }

    fn lagrangian_hessian_from(&self, ch: &Chain, mu: &V3) -> DMatrix<f64> {
        let mut h = -self.closure_hessian_from(ch, mu);
        for (a, d) in self.d_gauss.iter().enumerate() {
            h[(a, a)] += self.cell_weight(a / 2) * d;
        }
        h
    }
}

fn prefix_suffix(e: &[M3]) -> (Vec<M3>, Vec<M3>) {
    let n = e.len();
    let mut prefix = Vec::with_capacity(n + 1);
    let mut acc = M3::identity();
    prefix.push(acc);
    for ec in e {
        acc = ec * acc;
        prefix.push(acc);
    }
    let mut suffix = vec![M3::identity(); n];
    for c in (1..n).rev() {
        suffix[c - 1] = suffix[c] * e[c];
    }
    (prefix, suffix)
}
