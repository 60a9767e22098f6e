//! The equilibria at a fixed length `L̄` traced against a stiffness parameter of the
//! two-segment profile (Eq. (51): `d1` = D1/D0, `gamma`, `s0`, `s1`): `rodloop diagram
//! --param`.
//!
//! At the scene's value every branch that exists at `L̄` (`η − 1 < L̄ < η + 1`) is seeded by
//! energy minimisation from its exact loops shifted along the rod by eighths of `1/(2η)`
//! (the placements of the soft segment); distinct states (energies apart by more than
//! [`SAME_STATE`]) become families. Each family is marched with [`march`] (the generic
//! pseudo-arclength loop, [`ParamProblem`] on the surface model, `O(N)` factorisations) from
//! the scene's value to the target, through folds ([`FoldPolicy::Follow`]), with branch
//! points and index changes located. Every state carries its Hessian index (the same routine
//! and tolerance as the `L̄` diagrams) and a label: `stable` (index 0 and the lowest traced
//! index-0 energy at that parameter value), `metastable` (index 0, not the lowest) or
//! `unstable`.
//! Energies of the seeds and of the special points carry an error estimate from the same
//! state at half the resolution, `|E_N − E_{N/2}|/15`.
//!
//! The file is over 600 lines because it is the whole `--param` diagram of one scene: seeding,
//! marching each family both ways with branch switching, labelling and the log-axis model
//! wrapper; the stepping itself is the continuation crate's (through [`march`]).

use rodloop_continuation::axis::Axis;
use rodloop_continuation::{Direction, SpecialKind};
use rodloop_exact::{branch_of_eta, eta_of_branch};
use rodloop_solver::{
    Accuracy, Confinement, Globalization, Param, ParamProblem, SolveOptions, SolverError,
    Stiffness, SurfaceSolve,
};

use crate::labels::Label;
use crate::march::{march, march_switch, FoldPolicy, March, MarchSettings, MarchStop};
use crate::placements::{classify, shift_of, solve_shifted};
use crate::states::INDEX_TOLERANCE;
use crate::DiagramError;
use rodloop_continuation::exchange::{self, Ranked};

/// Two seeds whose energies differ by less than this are the same state (or mirror
/// images, which have the same energy).
pub const SAME_STATE: f64 = 1e-8;

/// What [`sweep_param`] computes.
#[derive(Clone, Debug)]
pub struct SweepSettings {
    /// Sphere radius `R`.
    pub radius: f64,
    /// The fixed normalised length `L̄`.
    pub lbar: f64,
    /// The scene's stiffness profile (two-segment, Eq. (51)).
    pub stiffness: Stiffness,
    /// The continued parameter.
    pub param: Param,
    /// The end value of the parameter (the start is the scene's value).
    pub target: f64,
    /// Resolution (cells) and error estimates.
    pub accuracy: Accuracy,
    /// Paper branches to trace (empty: every branch that exists at `L̄`).
    pub branches: Vec<u32>,
    /// Solver settings of the seeds.
    pub solve: SolveOptions,
}

/// One traced state.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct SweepPoint {
    /// Parameter value.
    pub value: f64,
    /// Energy `E R/(π D0)`.
    pub energy: f64,
    /// Stability index.
    pub index: usize,
    /// Label (set once every family is traced).
    pub label: Label,
    /// Position along the family (0 = the seed).
    pub arc: usize,
    /// The KKT state (main resolution, at `value`), for [`verify_sweep`].
    #[serde(skip)]
    pub state: Vec<f64>,
}

/// A family: the states of one branch continued from one seed at the scene's value.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct SweepFamily {
    /// Paper branch.
    pub branch: u32,
    /// Periods `η` of `κ_g`.
    pub eta: u32,
    /// Family number within the branch (1, 2, … in increasing seed energy).
    pub family: usize,
    /// Cells of the model.
    pub cells: usize,
    /// Parameter value of the seed, its energy and the energy's error estimate (`None` for
    /// a family switched onto at a branch point).
    pub seed_energy: Option<(f64, f64, f64)>,
    /// The states, seed first, in marching order (through folds).
    pub points: Vec<SweepPoint>,
    /// Why the march ended.
    pub end: String,
    /// Where the family comes from, mirror pairs.
    pub notes: Vec<String>,
}

/// A located special point of a family.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct SweepSpecial {
    /// `fold` (turning point in the parameter), `branch_point` or `index_change`.
    pub kind: String,
    /// Parameter value.
    pub value: f64,
    /// Energy there and its error estimate (half resolution).
    pub energy: f64,
    /// See [`SweepSpecial::energy`].
    pub energy_error: f64,
    /// Paper branch and family.
    pub branch: u32,
    /// Family number (see [`SweepFamily::family`]).
    pub family: usize,
    /// Index below and above `value` (index changes only).
    pub index: Option<(usize, usize)>,
}

/// Result of [`sweep_param`].
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ParamSweep {
    /// The continued parameter.
    pub param: Param,
    /// The scene's value.
    pub scene_value: f64,
    /// The end value.
    pub target: f64,
    /// The fixed length.
    pub lbar: f64,
    /// Every family.
    pub families: Vec<SweepFamily>,
    /// Folds, branch points and index changes.
    pub special: Vec<SweepSpecial>,
    /// Seeds that failed, families that stopped early.
    pub warnings: Vec<String>,
}

/// The paper branches that exist at `lbar` (`η − 1 < L̄ < η + 1`).
pub fn branches_at(lbar: f64) -> Vec<u32> {
    let mut out: Vec<u32> = (1..=(lbar.ceil() as u32 + 1))
        .filter(|&eta| f64::from(eta) - 1.0 < lbar && lbar < f64::from(eta) + 1.0)
        .map(branch_of_eta)
        .collect();
    out.sort_unstable();
    out
}

fn invalid(msg: String) -> DiagramError {
    DiagramError::InvalidOptions(msg)
}

fn check(s: &SweepSettings) -> Result<f64, DiagramError> {
    let Stiffness::Tanh { .. } = &s.stiffness else {
        return Err(invalid(
            "--param needs a two-segment stiffness profile (kind = \"tanh\", Eq. (51)) in the scene"
                .into(),
        ));
    };
    if s.param == Param::Lbar {
        return Err(invalid(
            "--param lbar: the length is fixed by --lbar here; choose d1, gamma, s0 or s1".into(),
        ));
    }
    if !(s.lbar.is_finite() && s.lbar > 0.0 && s.lbar <= 50.0) {
        return Err(invalid(format!(
            "--lbar must lie in (0, 50] (got {})",
            s.lbar
        )));
    }
    if (s.lbar - s.lbar.round()).abs() < 1e-6 {
        return Err(invalid(format!(
            "--lbar {}: at an integer length the loops collapse onto a great circle; choose a length between the integers",
            s.lbar
        )));
    }
    let scene_value = s.stiffness.param(s.param)?;
    if !s.target.is_finite() || s.target == scene_value {
        return Err(invalid(format!(
            "--to {} must be a finite value of {} other than the scene's {scene_value}",
            s.target, s.param
        )));
    }
    s.stiffness
        .with_param(s.param, s.target)?
        .validate()
        .map_err(|e| {
            invalid(format!(
                "--to {}: not a valid value of {}: {e}",
                s.target, s.param
            ))
        })?;
    if s.param == Param::D1 && s.target <= 0.0 {
        return Err(invalid(format!(
            "--to for d1 = D1/D0 must be positive (got {})",
            s.target
        )));
    }
    for &b in &s.branches {
        if !branches_at(s.lbar).contains(&b) {
            return Err(invalid(format!(
                "--branch {b}: branch {b} (eta = {}) does not exist at L̄ = {} (branches there: {:?})",
                eta_of_branch(b),
                s.lbar,
                branches_at(s.lbar)
            )));
        }
    }
    Ok(scene_value)
}

/// The distinct stable states of branch `eta` on `model` from shifted exact loops, lowest
/// first.
fn seeds<M: SurfaceSolve>(
    model: &M,
    eta: u32,
    opts: &SolveOptions,
) -> (Vec<(f64, Vec<f64>)>, Vec<String>) {
    let mut found: Vec<(f64, Vec<f64>)> = Vec::new();
    let mut why = Vec::new();
    for k in 0..8 {
        let shift = shift_of(eta, k);
        match solve_shifted(model, eta, k, opts) {
            Ok(eq) => match classify(&eq, eta, INDEX_TOLERANCE) {
                (true, _, e) => {
                    if !found.iter().any(|(f, _)| (f - e).abs() < SAME_STATE) {
                        found.push((e, eq.state()));
                    }
                }
                (false, _, e) => why.push(format!(
                    "shift {shift:.4}: converged onto another branch (E = {e:.8})"
                )),
            },
            Err(e) => why.push(format!("shift {shift:.4}: {e}")),
        }
    }
    found.sort_by(|a, b| a.0.total_cmp(&b.0));
    (found, why)
}

/// Energy of state `x` of `model` at parameter `value` with the error estimate of the
/// state at half the resolution (Newton from the resampled state).
fn energy_with_estimate<M: SurfaceSolve>(
    model: &M,
    param: Param,
    x: &[f64],
    value: f64,
    opts: &SolveOptions,
) -> Result<(f64, f64), String> {
    let newton = SolveOptions {
        globalization: Globalization::Newton,
        ..opts.clone()
    };
    let m = model.with_param(param, value).map_err(|e| e.to_string())?;
    let eq = m
        .solve_from_state(x.to_vec(), &newton)
        .map_err(|e| e.to_string())?;
    let e = eq.energy().total;
    let nc = (model.cells() / 2).div_ceil(2) * 2;
    let coarse = model
        .with_cells(nc)
        .and_then(|m| m.with_param(param, value))
        .map_err(|e| e.to_string())?;
    let mut z = eq.resample(nc).map_err(|e| e.to_string())?;
    z.extend_from_slice(&eq.multiplier());
    let ec = coarse
        .solve_from_state(z, &newton)
        .map_err(|e| format!("companion at {nc} cells: {e}"))?
        .energy()
        .total;
    Ok((e, rodloop_solver::richardson_error(e, ec)))
}

/// Trace every family (see the module docs).
pub fn sweep_param(s: &SweepSettings) -> Result<ParamSweep, DiagramError> {
    let scene_value = check(s)?;
    let branches = if s.branches.is_empty() {
        branches_at(s.lbar)
    } else {
        s.branches.clone()
    };
    let mut families = Vec::new();
    let mut special = Vec::new();
    let mut warnings = Vec::new();
    for branch in branches {
        let eta = eta_of_branch(branch);
        let cells = s.accuracy.cells(eta as usize, &s.stiffness);
        let model = crate::surface_model(s.radius, s.lbar, cells, &s.stiffness)?;
        let cont = Continued {
            model: model.clone(),
            // The parameter's own axis (Param::axis: d1 and gamma in their logarithm).
            axis: s.param.axis(),
        };
        let problem = ParamProblem::new(cont.clone(), s.param)?;
        let shape = model.n_kappa();
        let toward = |limit: f64, far: f64| MarchSettings {
            limit: cont.p_of(limit),
            ds: 0.05,
            ds_min: 1e-7,
            ds_max: 0.25,
            max_steps: 1500,
            tol: 1e-10,
            locate_tol: 1e-8,
            scaled: shape,
            scale: s.radius / (shape as f64).sqrt(),
            folds: FoldPolicy::Follow,
            detect_branch_points: true,
            index_tolerance: INDEX_TOLERANCE,
            track_index: true,
            hermite_location: false,
            progress_every: usize::MAX,
            far_limit: Some(cont.p_of(far)),
            circles: Vec::new(),
            circle_distance: 0.0,
        };
        let ctx = Ctx {
            s,
            model: &model,
            branch,
            cells,
        };
        let mut mine: Vec<SweepFamily> = Vec::new();
        // Every traced state of this branch `(value, x)`, to recognise seeds on known families.
        let mut known: Vec<Vec<(f64, Vec<f64>)>> = Vec::new();
        let mut family = 0;
        for (vi, &v) in seed_values(s.param, scene_value, s.target)
            .iter()
            .enumerate()
        {
            let at_v = model.with_param(s.param, v)?;
            let (found, why) = seeds(&at_v, eta, &s.solve);
            if found.is_empty() && vi == 0 {
                warnings.push(format!(
                    "branch {branch} (eta = {eta}): no state found at L̄ = {} and {} = {v} ({})",
                    s.lbar,
                    s.param,
                    why.join("; ")
                ));
            }
            for (e0, x0) in &found {
                if vi > 0 && traced(&model, s.param, &known, v, *e0, &s.solve) {
                    continue;
                }
                // A seed whose energy changes by more than 1e-4 (relative) at half the
                // resolution is not a resolved state.
                let seed_energy = match energy_with_estimate(&model, s.param, x0, v, &s.solve) {
                    Ok((e, est)) if est <= 1e-4 * e.abs() => (e, est),
                    Ok((e, est)) => {
                        warnings.push(format!(
                            "branch {branch}: a seed at {} = {v}, E = {e:.8} changes by {:.1e} at half the resolution: not a resolved state, left out",
                            s.param,
                            15.0 * est
                        ));
                        continue;
                    }
                    Err(err) => {
                        warnings.push(format!(
                            "branch {branch}: a seed at {} = {v}, E = {e0:.8} has no companion at half the resolution ({err}): left out",
                            s.param
                        ));
                        continue;
                    }
                };
                family += 1;
                let seed = SweepPoint {
                    value: v,
                    energy: seed_energy.0,
                    index: at_v.index(x0, INDEX_TOLERANCE)?,
                    label: Label::Unstable,
                    arc: 0,
                    state: x0.clone(),
                };
                // Towards the target, and (seeds inside the range) back towards the scene.
                let mut marches = Vec::new();
                for (limit, far) in [(s.target, scene_value), (scene_value, s.target)] {
                    if limit == v {
                        continue;
                    }
                    match march(
                        &problem,
                        x0,
                        cont.p_of(v),
                        &toward(limit, far),
                        &mut |_, _| {},
                    ) {
                        Ok(raw) => {
                            let m = cont.in_theta(&raw);
                            let mut run = vec![(v, x0.clone())];
                            run.extend(m.points.iter().map(|p| (p.value, p.x.clone())));
                            known.push(run);
                            marches.push((raw, m))
                        }
                        Err(e) => warnings.push(format!("branch {branch} family {family}: {e}")),
                    }
                }
                let mut fam: Option<SweepFamily> = None;
                for (k, (_, m)) in marches.iter().enumerate() {
                    let f = ctx.family(
                        family,
                        (k == 0).then(|| seed.clone()),
                        Some((v, seed_energy.0, seed_energy.1)),
                        m,
                        &mut special,
                        &mut warnings,
                    )?;
                    fam = Some(match fam {
                        None => f,
                        // The backward march joins in front, reversed.
                        Some(mut first) => {
                            let mut pts: Vec<SweepPoint> = f.points.into_iter().rev().collect();
                            pts.append(&mut first.points);
                            for (i, p) in pts.iter_mut().enumerate() {
                                p.arc = i;
                            }
                            first.points = pts;
                            first
                        }
                    });
                }
                let Some(mut fam) = fam else { continue };
                if vi > 0 {
                    fam.notes.push(format!(
                        "seeded at {} = {v} (not connected to a state at the scene's value along the traced families)",
                        s.param
                    ));
                }
                for (raw, _) in &marches {
                    for bp in raw.branch_points() {
                        let bp_value = cont.theta(bp.value);
                        let settings = toward(s.target, scene_value);
                        let mut last_energies: Option<Vec<f64>> = None;
                        for dir in [Direction::Forward, Direction::Backward] {
                            let sw_raw = match march_switch(
                                &problem,
                                bp,
                                dir,
                                &settings,
                                &|_, _| false,
                                &mut |_, _| {},
                            ) {
                                Ok(sw) => sw,
                                Err(e) => {
                                    warnings.push(format!(
                                        "branch {branch} family {}: switching at the branch point {} = {bp_value:.8}: {e}",
                                        fam.family, s.param
                                    ));
                                    continue;
                                }
                            };
                            let sw = cont.in_theta(&sw_raw);
                            let energies: Vec<f64> = sw
                                .points
                                .iter()
                                .filter_map(|p| {
                                    model
                                        .with_param(s.param, p.value)
                                        .ok()
                                        .and_then(|m| Confinement::energy(&m, &p.x).ok())
                                })
                                .collect();
                            if let Some(prev) = &last_energies {
                                if prev.len() == energies.len()
                                    && prev
                                        .iter()
                                        .zip(&energies)
                                        .all(|(a, b)| (a - b).abs() < SAME_STATE)
                                {
                                    fam.notes.push(format!(
                                        "the branch point at {} = {bp_value:.8} has a mirror pair of secondary families (multiplicity 2, one traced)",
                                        s.param
                                    ));
                                    continue;
                                }
                            }
                            last_energies = Some(energies);
                            known.push(sw.points.iter().map(|p| (p.value, p.x.clone())).collect());
                            family += 1;
                            let mut f =
                                ctx.family(family, None, None, &sw, &mut special, &mut warnings)?;
                            f.notes.push(format!(
                                "switched from family {} at its branch point {} = {bp_value:.8}",
                                fam.family, s.param
                            ));
                            mine.push(f);
                        }
                    }
                }
                mine.push(fam);
            }
        }
        families.append(&mut mine);
    }
    families.sort_by_key(|f| (f.branch, f.family));
    label(&mut families);
    Ok(ParamSweep {
        param: s.param,
        scene_value,
        target: s.target,
        lbar: s.lbar,
        families,
        special,
        warnings,
    })
}

/// A model continued on an [`Axis`] of its parameter: in `p = ln θ` for `d1` and `gamma` (the
/// decades at even steps, `∂F/∂p = θ ∂F/∂θ`), in the parameter itself otherwise.
#[derive(Clone, Debug)]
struct Continued<M> {
    model: M,
    axis: Axis,
}

impl<M> Continued<M> {
    fn theta(&self, p: f64) -> f64 {
        self.axis.value(p)
    }

    fn p_of(&self, theta: f64) -> f64 {
        self.axis.coordinate(theta)
    }

    /// A march with its parameter values as `θ` (the tangents of its special points are
    /// left in `p`; branch switching uses the march as marched).
    fn in_theta(&self, m: &March) -> March {
        let mut m = m.clone();
        for p in &mut m.points {
            p.value = self.theta(p.value);
        }
        for sp in &mut m.special {
            sp.value = self.theta(sp.value);
        }
        for ic in &mut m.index_changes {
            ic.value = self.theta(ic.value);
        }
        if let MarchStop::StepTooSmall { value, .. } | MarchStop::NearCircle { value, .. } =
            &mut m.stop
        {
            *value = self.theta(*value);
        }
        m
    }
}

impl<M: Confinement> Confinement for Continued<M> {
    type Factor = M::Factor;
    fn dim(&self) -> usize {
        Confinement::dim(&self.model)
    }
    fn n_constraints(&self) -> usize {
        self.model.n_constraints()
    }
    fn residual(&self, z: &[f64]) -> Result<nalgebra::DVector<f64>, SolverError> {
        self.model.residual(z)
    }
    fn jacobian(&self, z: &[f64]) -> Result<nalgebra::DMatrix<f64>, SolverError> {
        self.model.jacobian(z)
    }
    fn factorize(&self, z: &[f64], shift: f64) -> Result<M::Factor, SolverError> {
        Confinement::factorize(&self.model, z, shift)
    }
    fn apply(&self, z: &[f64], dz: &[f64]) -> Result<nalgebra::DVector<f64>, SolverError> {
        Confinement::apply(&self.model, z, dz)
    }
    fn param(&self, p: Param) -> Result<f64, SolverError> {
        Ok(self.p_of(Confinement::param(&self.model, p)?))
    }
    fn with_param(&self, p: Param, value: f64) -> Result<Self, SolverError> {
        Ok(Self {
            model: Confinement::with_param(&self.model, p, self.theta(value))?,
            axis: self.axis,
        })
    }
    fn dparam(&self, z: &[f64], p: Param) -> Result<nalgebra::DVector<f64>, SolverError> {
        let d = self.model.dparam(z, p)?;
        // d/dq = (dθ/dq) d/dθ (θ d/dθ on a log axis).
        let theta = Confinement::param(&self.model, p)?;
        Ok(d * self.axis.derivative(self.p_of(theta)))
    }
    fn index(&self, z: &[f64], tolerance: f64) -> Result<usize, SolverError> {
        self.model.index(z, tolerance)
    }
    fn energy(&self, z: &[f64]) -> Result<f64, SolverError> {
        Confinement::energy(&self.model, z)
    }
    fn residual_norm(&self, f: &nalgebra::DVector<f64>) -> f64 {
        Confinement::residual_norm(&self.model, f)
    }
    fn radius(&self) -> f64 {
        Confinement::radius(&self.model)
    }
    fn lbar(&self) -> f64 {
        Confinement::lbar(&self.model)
    }
    fn cells(&self) -> usize {
        Confinement::cells(&self.model)
    }
    fn stiffness(&self) -> &rodloop_solver::StiffnessProfile {
        Confinement::stiffness(&self.model)
    }
    fn energy_gradient(&self, z: &[f64]) -> Result<nalgebra::DVector<f64>, SolverError> {
        Confinement::energy_gradient(&self.model, z)
    }
    /// `dE/dq = (dθ/dq) ∂E/∂θ`, as [`Confinement::dparam`].
    fn energy_dparam(&self, z: &[f64], p: Param) -> Result<f64, SolverError> {
        let d = self.model.energy_dparam(z, p)?;
        let theta = Confinement::param(&self.model, p)?;
        Ok(d * self.axis.derivative(self.p_of(theta)))
    }
}

/// Parameter values at which states are seeded: the scene's value first, then (for `d1`)
/// every decade strictly between it and the target, and the target.
fn seed_values(param: Param, scene: f64, target: f64) -> Vec<f64> {
    let mut out = vec![scene];
    if param == Param::D1 {
        let (lo, hi) = (scene.min(target), scene.max(target));
        let mut k = hi.log10().ceil() as i32;
        while 10f64.powi(k) > lo {
            let v = 10f64.powi(k);
            if v < hi && v > lo {
                out.push(v);
            }
            k -= 1;
        }
        if target < scene {
            out[1..].sort_by(|a, b| b.total_cmp(a));
        } else {
            out[1..].sort_by(|a, b| a.total_cmp(b));
        }
    } else {
        out.push(0.5 * (scene + target));
    }
    out.push(target);
    out
}

/// Whether the state of energy `e` seeded at `v` lies on a traced family: Newton at `v` from
/// the nearer end of each traced step that spans `v` (the steps of a march are short in
/// arclength, so Newton from its end stays on the family) reaches the same energy (to
/// [`SAME_STATE`]).
fn traced<M: SurfaceSolve>(
    model: &M,
    param: Param,
    known: &[Vec<(f64, Vec<f64>)>],
    v: f64,
    e: f64,
    opts: &SolveOptions,
) -> bool {
    let Ok(at_v) = model.with_param(param, v) else {
        return false;
    };
    let newton = SolveOptions {
        globalization: Globalization::Newton,
        ..opts.clone()
    };
    known.iter().any(|run| {
        run.windows(2).any(|w| {
            let (a, b) = (&w[0], &w[1]);
            // The ends of a march lie on the range's ends up to rounding (e^{ln θ}).
            let slack = 1e-12 * v.abs().max(1e-300);
            if v < a.0.min(b.0) - slack || v > a.0.max(b.0) + slack {
                return false;
            }
            let start = if (a.0 - v).abs() <= (b.0 - v).abs() {
                a
            } else {
                b
            };
            at_v.clone()
                .solve_from_state(start.1.clone(), &newton)
                .map(|eq| (eq.energy().total - e).abs() < SAME_STATE)
                .unwrap_or(false)
        })
    })
}

/// What the families of one branch share.
struct Ctx<'a, M> {
    s: &'a SweepSettings,
    model: &'a M,
    branch: u32,
    cells: usize,
}

impl<M: SurfaceSolve> Ctx<'_, M> {
    /// The family of a march (with its seed first, when it has one); its folds, branch
    /// points and index changes (energies re-solved with their estimates; one that cannot be
    /// re-solved is left out with a warning).
    fn family(
        &self,
        family: usize,
        seed: Option<SweepPoint>,
        seed_energy: Option<(f64, f64, f64)>,
        m: &March,
        special: &mut Vec<SweepSpecial>,
        warnings: &mut Vec<String>,
    ) -> Result<SweepFamily, DiagramError> {
        let (s, model, branch) = (self.s, self.model, self.branch);
        let mut points: Vec<SweepPoint> = seed.into_iter().collect();
        for p in &m.points {
            let mv = model.with_param(s.param, p.value)?;
            let index = match p.index {
                Some(i) => i,
                None => mv.index(&p.x, INDEX_TOLERANCE)?,
            };
            points.push(SweepPoint {
                value: p.value,
                energy: Confinement::energy(&mv, &p.x)?,
                index,
                label: Label::Unstable,
                arc: points.len(),
                state: p.x.clone(),
            });
        }
        let mut add = |kind: &str, x: &[f64], value: f64, index: Option<(usize, usize)>| {
            match energy_with_estimate(model, s.param, x, value, &s.solve) {
                Ok((energy, energy_error)) => special.push(SweepSpecial {
                    kind: kind.into(),
                    value,
                    energy,
                    energy_error,
                    branch,
                    family,
                    index,
                }),
                Err(e) => warnings.push(format!(
                    "branch {branch} family {family}: the {kind} at {} = {value:.8} could not be re-solved ({e}): left out",
                    s.param
                )),
            }
        };
        for sp in &m.special {
            let kind = match sp.kind {
                SpecialKind::Fold => "fold",
                SpecialKind::BranchPoint => "branch_point",
                _ => continue,
            };
            add(kind, &sp.x, sp.value, None);
        }
        for ic in &m.index_changes {
            if let Some(p) = m
                .points
                .iter()
                .find(|p| (p.value - ic.value).abs() <= 1e-12 * ic.value.abs().max(1.0))
            {
                add("index_change", &p.x, p.value, Some((ic.below, ic.above)));
            }
        }
        let end = match &m.stop {
            MarchStop::Reached => "reached the end of the range".to_string(),
            MarchStop::StepTooSmall { value, cause, .. } => format!(
                "the step fell below its minimum at {} = {value}{}",
                s.param,
                cause
                    .as_ref()
                    .map(|c| format!(" ({c})"))
                    .unwrap_or_default()
            ),
            MarchStop::MaxSteps => "the step budget (1500) was used up".into(),
            MarchStop::ClosedLoop => "the family closed a loop".into(),
            other => format!("{other:?}"),
        };
        if !matches!(m.stop, MarchStop::Reached | MarchStop::ClosedLoop) {
            warnings.push(format!("branch {branch} family {family}: {end}"));
        }
        Ok(SweepFamily {
            branch,
            eta: eta_of_branch(branch),
            family,
            cells: self.cells,
            seed_energy,
            points,
            end,
            notes: Vec::new(),
        })
    }
}

/// Tolerance of the sweep's energy comparisons: each state's energy is given half of it as
/// its error estimate in the labeller's tie rule.
const SWEEP_TIE: f64 = 1e-9;

/// Labels by the labeller ([`rodloop_continuation::exchange::label`]): at each traced
/// state, it and every traced segment (any family, any sheet, linearly interpolated between
/// consecutive points, index 0 where both ends have it) covering its value; the state
/// itself is preferred in ties (within [`SWEEP_TIE`]). Index > 0 unstable; index 0 stable
/// where no index-0 state lies lower, metastable otherwise.
fn label(families: &mut [SweepFamily]) {
    // ((value, energy, index 0) at both ends) of every segment.
    type End = (f64, f64, bool);
    let segments: Vec<(End, End)> = families
        .iter()
        .flat_map(|f| {
            f.points
                .windows(2)
                .map(|w| {
                    (
                        (w[0].value, w[0].energy, w[0].index == 0),
                        (w[1].value, w[1].energy, w[1].index == 0),
                    )
                })
                .collect::<Vec<_>>()
        })
        .collect();
    let others = |v: f64| -> Vec<Ranked> {
        segments
            .iter()
            .filter_map(|&((a, ea, ia), (b, eb, ib))| {
                let (lo, hi) = (a.min(b), a.max(b));
                if v < lo || v > hi {
                    return None;
                }
                let energy = if hi > lo {
                    ea + (v - a) / (b - a) * (eb - ea)
                } else {
                    ea.min(eb)
                };
                Some(Ranked {
                    energy,
                    error: 0.5 * SWEEP_TIE,
                    index: usize::from(!(ia && ib)),
                    preferred: false,
                })
            })
            .collect()
    };
    for f in families.iter_mut() {
        for p in &mut f.points {
            let mut states = vec![Ranked {
                energy: p.energy,
                error: 0.5 * SWEEP_TIE,
                index: p.index,
                preferred: true,
            }];
            states.extend(others(p.value));
            p.label = exchange::label(&states)[0].into();
        }
    }
}

/// A traced state of a sweep as its file holds it: the error estimate of its energy
/// (`|E_N − E_{N/2}|/15`, the same state at half the resolution) and the file, verified
/// against its energy within [`crate::ESTIMATES`] times that estimate
/// ([`crate::reported::verify_reported`]).
pub type SweepState = Result<(f64, crate::StateFile), String>;

/// Every traced state of `sweep` verified as its file holds it (see [`SweepState`]), in
/// parallel on `threads` threads: `out[f][k]` for `sweep.families[f].points[k]` (`Err` with
/// why where a state cannot be re-solved or fails a check).
pub fn verify_sweep(s: &SweepSettings, sweep: &ParamSweep, threads: usize) -> Vec<Vec<SweepState>> {
    let jobs: Vec<(usize, usize)> = sweep
        .families
        .iter()
        .enumerate()
        .flat_map(|(i, f)| (0..f.points.len()).map(move |k| (i, k)))
        .collect();
    let newton = SolveOptions {
        globalization: Globalization::Newton,
        ..s.solve.clone()
    };
    let results = crate::parallel::run_parallel(
        threads.max(1),
        jobs.clone(),
        &mut |_| {},
        &mut |_| {},
        |(i, k), _| -> SweepState {
            let f = &sweep.families[i];
            let p = &f.points[k];
            let model = crate::surface_model(s.radius, s.lbar, f.cells, &s.stiffness)
                .and_then(|m| m.with_param(s.param, p.value))
                .map_err(|e| e.to_string())?;
            let eq = model
                .solve_from_state(p.state.clone(), &newton)
                .map_err(|e| format!("the state cannot be re-solved: {e}"))?;
            let est = crate::reported::half_resolution_estimate(&eq).map_err(|e| {
                format!("no state at half the resolution for its error estimate: {e}")
            })?;
            let file = crate::reported::verify_reported(&eq, p.energy, Some(est))
                .map_err(|e| e.to_string())?;
            Ok((est, file))
        },
    );
    let mut out: Vec<Vec<SweepState>> = sweep
        .families
        .iter()
        .map(|f| Vec::with_capacity(f.points.len()))
        .collect();
    for ((i, _), r) in jobs.into_iter().zip(results) {
        out[i].push(r);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DVector;
    use rodloop_continuation::fd_dparam;

    #[test]
    fn log_continued_parameter_derivative_matches_finite_differences() {
        let st = Stiffness::Tanh {
            d0: 1.0,
            d1: 0.3,
            s0: 0.3,
            s1: 0.8,
            gamma: 12.0,
        };
        let model = crate::surface_model(1.0, 1.4, 12, &st).unwrap();
        // A non-equilibrium state: the exact loop of two periods, arbitrary multipliers.
        let mut z = rodloop_solver::StartShape::Exact { eta: 2 }
            .gauss_values(&model)
            .unwrap();
        z.extend_from_slice(&[0.3, -0.2, 0.1]);
        for axis in [Axis::Log, Axis::Linear] {
            let c = Continued {
                model: model.clone(),
                axis,
            };
            let p0 = Confinement::param(&c, Param::D1).unwrap();
            assert!((c.theta(p0) - 0.3).abs() < 1e-15);
            let an = c.dparam(&z, Param::D1).unwrap();
            let fd = fd_dparam(
                |p| -> Result<DVector<f64>, SolverError> {
                    c.with_param(Param::D1, p)?.residual(&z)
                },
                p0,
            )
            .unwrap();
            let err = (&an - &fd).amax() / fd.amax();
            assert!(err < 1e-7, "{axis:?}: {err}");
        }
    }

    #[test]
    fn seed_values_and_branches() {
        assert_eq!(seed_values(Param::D1, 0.5, 0.001).len(), 4);
        let v = seed_values(Param::D1, 0.5, 0.001);
        assert!((v[1] - 0.1).abs() < 1e-15 && (v[2] - 0.01).abs() < 1e-15 && v[3] == 0.001);
        assert_eq!(
            seed_values(Param::Gamma, 200.0, 20.0),
            vec![200.0, 110.0, 20.0]
        );
        // η − 1 < L̄ < η + 1: at 1.4 the figure-eight (η = 1, branch 2) and η = 2 (branch 1).
        assert_eq!(branches_at(1.4), vec![1, 2]);
        assert_eq!(branches_at(2.4), vec![1, 3]);
    }
}
