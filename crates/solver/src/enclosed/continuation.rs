//! Natural-parameter steps in `L̄` for enclosed states (the enclosed diagram's tracer,
//! `rodloop_diagram::enclosed`).
//!
//! A converged state at `L̄` starts Newton at a nearby `L̄'` unchanged: the same curvature
//! vectors, start point and multipliers (closure, gauges, wall), so only the cell lengths
//! change and the start misses closure by `O(L̄' − L̄)`. (A similarity rescaling, curvature
//! times `L/L'` and start point times `L'/L`, closes exactly but pushes every contact node
//! through the wall; the semismooth Newton then stalled at `N = 64` on the lifted-off
//! figure-eight near `L̄ = 1.38`, while the unscaled start converges in 3 iterations.) The
//! gauge takes the start as its reference, as in [`super::start_from_surface`].
//!
//! Continuation in the stiffness at fixed `L̄` ([`continue_in_stiffness`]): from the uniform
//! rod's states to a non-uniform rod's, along [`blended_stiffness`].

use super::model::{phase_slope, rotation, translation, EnclosedModel, Gauge};
use nalgebra::{DMatrix, DVector};
use rodloop_continuation::natural::{walk_adaptive, AdaptiveSettings};

use super::solve::{
    solve_enclosed, start_from_curvature, transfer_multipliers, EnclosedOptions, EnclosedState,
    STEP_ITERATIONS,
};
use crate::stiffness::Stiffness;
use crate::SolverError;

impl EnclosedState {
    /// The model and start vector at `lbar` built from this state (see the module docs).
    pub fn continue_to(&self, lbar: f64) -> Result<(EnclosedModel, Vec<f64>), SolverError> {
        let m = &self.model;
        let n = m.cells();
        crate::model::check_lbar(lbar)?;
        let reference: Vec<f64> = self.z[..4 * n].to_vec();
        let stiffness = m.stiffness().kind().clone();
        let slope = if m.gauge().slope.is_some() {
            phase_slope(&reference, n)?
        } else {
            None
        };
        if slope.is_some() != m.gauge().slope.is_some() {
            return Err(SolverError::InvalidInput(
                "the phase condition of the enclosed state is degenerate at the new length".into(),
            ));
        }
        let pin = m.gauge().pin;
        let model = m.rebuilt(
            lbar,
            n,
            &stiffness,
            Gauge {
                reference: reference.clone(),
                slope,
                pin,
            },
        )?;
        Ok((model, self.z.clone()))
    }

    /// Newton at `lbar` from this state ([`Self::continue_to`], then [`solve_enclosed`]).
    pub fn step_to(&self, lbar: f64, opts: &EnclosedOptions) -> Result<EnclosedState, SolverError> {
        let (model, z) = self.continue_to(lbar)?;
        solve_enclosed(&model, z, opts)
    }
}

impl EnclosedState {
    /// Length-weighted centroid of the nodes (the trapezoid rule of `∫r ds/L`, spectrally
    /// accurate on a uniform periodic mesh).
    pub fn centroid(&self) -> Result<[f64; 3], SolverError> {
        let m = &self.model;
        let pos = m.positions(&self.z)?;
        let mut c = [0.0; 3];
        let mut w_sum = 0.0;
        for (j, r) in pos.iter().enumerate() {
            let w = m.node_weight(j);
            w_sum += w;
            for k in 0..3 {
                c[k] += w * r[k];
            }
        }
        Ok(c.map(|v| v / w_sum))
    }

    /// The model and start vector at `lbar` for a loop that does not touch the wall: as
    /// [`Self::continue_to`], but with the three translations pinned (they are symmetry
    /// modes of a free loop, and the KKT matrix is singular without a pin) and, when it is
    /// off the wall, the loop moved so that its centroid is the ball's centre (the pin is the
    /// start point of the moved loop). A pinned state is physical only where its wall forces
    /// balance
    /// (`Σ λ_j r_j = 0`, which the pin's multiplier measures): always for a loop off the
    /// wall.
    ///
    /// The pin fixes node 0. Where node 0 touches the wall (its wall constraint would
    /// depend only on the pinned start point, a rank-deficient KKT matrix), the loop is
    /// first re-based on a uniform mesh: arclength origin moved by `N/4` cells, the loop
    /// turned about the centre so that the frame there is the identity (the curvature
    /// vectors in the rotation-minimising frame are unchanged), the wall impulses moved with
    /// their nodes, and the closure and gauge multipliers taken afresh by least squares.
    pub fn continue_free(&self, lbar: f64) -> Result<(EnclosedModel, Vec<f64>), SolverError> {
        let m = &self.model;
        let n = m.cells();
        crate::model::check_lbar(lbar)?;
        let gap0 = m.gaps(&self.z)?[0];
        let touches0 = gap0 <= 1e-6 * m.radius() || self.multipliers()[0] != 0.0;
        let rebase = touches0 && m.uniform_mesh() && m.stiffness().kind().is_uniform();
        let shift = if rebase { n / 4 } else { 0 };
        let p = m.transforms(&self.z)?;
        let q = if rebase {
            rotation(&p[shift]).transpose()
        } else {
            nalgebra::Matrix3::identity()
        };
        let r0 = m.start_point(&self.z);
        let start = q * (r0 + translation(&p[shift]));
        // A loop off the wall is moved to the centre; a touching one stays where the wall
        // holds it (its centroid need not be the centre: the lifted-off figure-eight at
        // L̄ = 1.2 has it 0.48 R away).
        let touching = self.multipliers().iter().any(|&l| l != 0.0);
        let c = if touching {
            nalgebra::Vector3::zeros()
        } else {
            q * nalgebra::Vector3::from(self.centroid()?)
        };
        let pin = start - c;
        let mut kappa = vec![0.0; 4 * n];
        for cell in 0..n {
            let from = (cell + shift) % n;
            kappa[4 * cell..4 * cell + 4].copy_from_slice(&self.z[4 * from..4 * from + 4]);
        }
        let slope = if m.gauge().slope.is_some() {
            phase_slope(&kappa, n)?
        } else {
            None
        };
        let model = m.rebuilt(
            lbar,
            n,
            &m.stiffness().kind().clone(),
            Gauge {
                reference: kappa.clone(),
                slope,
                pin: Some([pin[0], pin[1], pin[2]]),
            },
        )?;
        let mut z = vec![0.0; model.dim()];
        z[..4 * n].copy_from_slice(&kappa);
        z[4 * n..4 * n + 3].copy_from_slice(&[pin[0], pin[1], pin[2]]);
        if rebase {
            // The wall impulses move with their nodes; the closure and gauge multipliers
            // (whose frame changed) by least squares with those impulses held.
            let lam_old = self.multipliers();
            equality_multipliers(&model, &mut z, |j| lam_old[(j + shift) % n])?;
        } else {
            // The same multipliers (closure, gauges, wall); the pin's start at 0.
            let (np_old, lo_old) = (m.n_primal(), m.lambda_offset());
            let np = model.n_primal();
            let k = (lo_old - np_old).min(model.lambda_offset() - np);
            z[np..np + k].copy_from_slice(&self.z[np_old..np_old + k]);
            let lo = model.lambda_offset();
            z[lo..lo + n].copy_from_slice(&self.z[lo_old..lo_old + n]);
        }
        Ok((model, z))
    }

    /// Newton at `lbar` from this state with the translations pinned
    /// ([`Self::continue_free`], then [`solve_enclosed`]).
    pub fn step_free(
        &self,
        lbar: f64,
        opts: &EnclosedOptions,
    ) -> Result<EnclosedState, SolverError> {
        let (model, z) = self.continue_free(lbar)?;
        solve_enclosed(&model, z, opts)
    }

    /// Net wall force `Σ_j 2λ_j r_j` (the stationarity row of the start point without a pin;
    /// the pin's reaction with one), in units of `D0/R²`: zero at a physical equilibrium.
    pub fn net_wall_force(&self) -> Result<f64, SolverError> {
        let m = &self.model;
        let pos = m.positions(&self.z)?;
        let lam = self.multipliers();
        let mut f = [0.0; 3];
        for (j, r) in pos.iter().enumerate() {
            let grad = m.wall().gradient(r);
            for k in 0..3 {
                f[k] -= lam[j] * grad[k];
            }
        }
        let r = m.radius();
        let unit = r * r / m.stiffness().kind().reference();
        Ok((f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt() * unit)
    }
}

impl EnclosedState {
    /// Newton at `lbar` from the secant predictor through `prev` and this state
    /// (`z + t(z − z_prev)`, `t = (L̄' − L̄)/(L̄ − L̄_prev)`; the model of
    /// [`Self::continue_to`]). Where the contact set changes smoothly along the trace, the predicted start
    /// misses the new state by `O(ΔL̄²)` instead of `O(ΔL̄)` (the plain warm start leaves
    /// closure open by `O(ΔL̄)` and the contact set of the old length, which the semismooth
    /// Newton then sheds node by node under backtracking). `None` when `prev` does not fit
    /// (other mesh, a pinned loop, or no length step between the two).
    pub fn predict_to(
        &self,
        prev: &EnclosedState,
        lbar: f64,
    ) -> Result<Option<(EnclosedModel, Vec<f64>)>, SolverError> {
        let (m, mp) = (&self.model, &prev.model);
        let dl = m.lbar() - mp.lbar();
        if mp.cells() != m.cells()
            || prev.z.len() != self.z.len()
            || mp.gauge().pin.is_some()
            || m.gauge().pin.is_some()
            || dl.abs() < 1e-12
        {
            return Ok(None);
        }
        let (model, _) = self.continue_to(lbar)?;
        let t = (lbar - m.lbar()) / dl;
        let z: Vec<f64> = self
            .z
            .iter()
            .zip(&prev.z)
            .map(|(a, b)| a + t * (a - b))
            .collect();
        Ok(Some((model, z)))
    }
}

/// Closure and gauge multipliers of `z` by least squares on the stationarity rows, with the
/// wall impulses set to `lambda(j)` and held (stationarity is linear in all multipliers).
fn equality_multipliers<F: Fn(usize) -> f64>(
    model: &EnclosedModel,
    z: &mut [f64],
    lambda: F,
) -> Result<(), SolverError> {
    let np = model.n_primal();
    let lo = model.lambda_offset();
    for v in z[np..lo].iter_mut() {
        *v = 0.0;
    }
    for j in 0..model.cells() {
        z[lo + j] = lambda(j);
    }
    let ev = model.evaluate(z)?;
    let f0 = ev.residual.rows(0, np).into_owned();
    let a = ev.jacobian.view((0, np), (np, lo - np)).into_owned();
    let scales = model.residual_scales();
    let w: Vec<f64> = scales[..np].iter().map(|s| s.sqrt()).collect();
    let aw = DMatrix::from_fn(np, lo - np, |i, j| a[(i, j)] * w[i]);
    let fw = DVector::from_fn(np, |i, _| f0[i] * w[i]);
    let mut nrm = aw.transpose() * &aw;
    let tr = nrm.trace() / nrm.nrows() as f64;
    for i in 0..nrm.nrows() {
        nrm[(i, i)] += 1e-14 * tr;
    }
    let rhs = -(aw.transpose() * fw);
    let y = nrm
        .clone()
        .cholesky()
        .map(|c| c.solve(&rhs))
        .or_else(|| nrm.lu().solve(&rhs))
        .ok_or(SolverError::SingularJacobian { iteration: 0 })?;
    for (k, v) in y.iter().enumerate() {
        z[np + k] = *v;
    }
    Ok(())
}

/// The stiffness `D_t(σ) = D_ref + t (D(σ) − D_ref)` between the uniform rod of the
/// profile's reference stiffness `D_ref` ([`Stiffness::reference`], `t = 0`) and `target`
/// (`t = 1`): the path of [`continue_in_stiffness`]. Eq. (51) keeps its form (`D1` moves
/// from `D0` to its value); a table moves every value.
pub fn blended_stiffness(target: &Stiffness, t: f64) -> Stiffness {
    let r = target.reference();
    match target {
        Stiffness::Uniform { .. } => target.clone(),
        Stiffness::Tanh {
            d0,
            d1,
            s0,
            s1,
            gamma,
        } => Stiffness::Tanh {
            d0: *d0,
            d1: d0 + t * (d1 - d0),
            s0: *s0,
            s1: *s1,
            gamma: *gamma,
        },
        Stiffness::Table { s, d } => Stiffness::Table {
            s: s.clone(),
            d: d.iter().map(|v| r + t * (v - r)).collect(),
        },
    }
}

/// `state` carried to the stiffness `stiffness` on the same number of cells (the mesh may
/// be graded differently): curvature interpolated ([`EnclosedState::curvature_at`]), the
/// same start point, the multipliers carried over ([`transfer_multipliers`]).
pub fn with_stiffness(
    state: &EnclosedState,
    stiffness: &Stiffness,
) -> Result<(EnclosedModel, Vec<f64>), SolverError> {
    let m = &state.model;
    let r0 = m.start_point(&state.z);
    let (model, mut z) = start_from_curvature(
        m.wall(),
        m.lbar(),
        m.cells(),
        stiffness,
        |s| state.curvature_at(s),
        [r0[0], r0[1], r0[2]],
    )?;
    transfer_multipliers(m, &state.z, &model, &mut z);
    Ok((model, z))
}

/// The eigenvector of the lowest eigenvalue (of any sign) of the tangent Hessian of
/// `state` (`EnclosedState::tangent_hessian`, active wall multipliers above `1e-6` of the
/// largest), in the primal unknowns, scaled to the state's `(∫|κ|² ds)^½` in the mass norm;
/// with the eigenvalue. At a fold of a one-parameter family of equilibria that eigenvalue
/// goes through zero and its eigenvector is the direction in which the state leaves.
pub fn softest_direction(state: &EnclosedState) -> Result<(f64, Vec<f64>), SolverError> {
    let m = &state.model;
    let np = m.n_primal();
    let (pw, s) = state.tangent_hessian(1e-6)?;
    let eig = nalgebra::SymmetricEigen::new(pw);
    let k = (0..eig.eigenvalues.len())
        .min_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]))
        .ok_or_else(|| SolverError::InvalidInput("empty Hessian".into()))?;
    let norm = (0..4 * m.cells())
        .map(|a| 0.5 * m.cell_length(a / 4) * state.z[a] * state.z[a])
        .sum::<f64>()
        .sqrt();
    let u = eig.eigenvectors.column(k);
    Ok((
        eig.eigenvalues[k],
        (0..np).map(|i| u[i] * s[i] * norm).collect(),
    ))
}

/// Relative amplitudes of the steps along [`softest_direction`] that leave a fold of the
/// stiffness path ([`continue_in_stiffness`]), tried in turn, both signs.
const SNAP_AMPLITUDES: [f64; 4] = [0.05, 0.15, 0.3, 0.5];

/// Natural-parameter continuation of an enclosed state of the uniform rod (or of any
/// stiffness) to the stiffness `target` along [`blended_stiffness`], `t` from 0 to 1, at
/// fixed `L̄` and mesh size, walked by the continuation crate's
/// [`walk_adaptive`]: steps of `t` of at most `1/4`, halved on a failed Newton solve
/// ([`STEP_ITERATIONS`] iterations) down to `1/512`, grown by half after a success. Where
/// the steps fail at a fold of the
/// path (the state ceases to exist as `t` grows), the loop snaps through as a quasi-static
/// loading would: just past the fold, Newton from the last state displaced along its
/// [`softest_direction`] (amplitudes `SNAP_AMPLITUDES`, both signs), and the lowest
/// state reached below the last one's energy carries the path on. The enclosed problem of
/// a two-segment rod has lifted-off equilibria that no surface family of that rod leads to
/// but that the uniform rod's loops lead to along this path.
pub fn continue_in_stiffness(
    start: &EnclosedState,
    target: &Stiffness,
    opts: &EnclosedOptions,
) -> Result<EnclosedState, SolverError> {
    const MIN_STEP: f64 = 1.0 / 512.0;
    let settings = AdaptiveSettings {
        max_step: 0.25,
        min_step: MIN_STEP,
        growth: 1.5,
        // Folds snapped through at most (each one lowers the energy).
        max_rescues: 4,
        restart_step: 4.0 * MIN_STEP,
    };
    // Steps and snaps: Newton with the continuation steps' budget.
    let opts = &EnclosedOptions {
        max_iterations: STEP_ITERATIONS,
        ..opts.clone()
    };
    let step = |cur: &EnclosedState, tn: f64| {
        let st = blended_stiffness(target, tn);
        with_stiffness(cur, &st).and_then(|(m, z)| solve_enclosed(&m, z, opts))
    };
    // Past a fold: the lowest state reached along the softest direction, a little further
    // along the blend.
    let snap = |cur: &EnclosedState, t: f64, e: SolverError| {
        let tn = (t + 4.0 * MIN_STEP).min(1.0);
        let st = blended_stiffness(target, tn);
        let (_, v) = softest_direction(cur)?;
        let e0 = cur.energy();
        let mut best: Option<EnclosedState> = None;
        for amp in SNAP_AMPLITUDES {
            for sign in [1.0, -1.0] {
                let mut z = cur.z.clone();
                for (zi, vi) in z.iter_mut().zip(&v) {
                    *zi += sign * amp * vi;
                }
                let moved = EnclosedState { z, ..cur.clone() };
                let Ok(s) =
                    with_stiffness(&moved, &st).and_then(|(m, z)| solve_enclosed(&m, z, opts))
                else {
                    continue;
                };
                let es = s.energy();
                if es < e0 - 1e-6 * e0.abs() && best.as_ref().is_none_or(|b| es < b.energy()) {
                    best = Some(s);
                }
            }
            if best.is_some() {
                break;
            }
        }
        best.map(|b| (b, tn)).ok_or(e)
    };
    walk_adaptive(start.clone(), 0.0, 1.0, &settings, step, snap)
}
