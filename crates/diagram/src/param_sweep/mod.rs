//! The equilibria at a fixed length `L̄` traced against a stiffness parameter of the
//! two-segment profile (Eq. (51): `d1` = D1/D0, `gamma`, `s0`, `s1`): `rodloop diagram
//! --param`.
//!
//! At the scene's value every branch that exists at `L̄` (`η − 1 < L̄ < η + 1`) is seeded by
//! energy minimisation from its exact loops shifted along the rod by eighths of `1/(2η)`
//! (the placements of the soft segment); distinct states (energies apart by more than
//! [`SAME_STATE`]) become families. Each family is marched with
//! [`march`](crate::march::march) (the generic pseudo-arclength loop,
//! [`ParamProblem`](rodloop_solver::ParamProblem) on the surface model, `O(N)`
//! factorisations) from the scene's value to the target, through folds
//! ([`FoldPolicy::Follow`](crate::march::FoldPolicy::Follow)), with branch
//! points and index changes located. Every state carries its Hessian index (the same routine
//! and tolerance as the `L̄` diagrams) and a label: `stable` (index 0 and the lowest traced
//! index-0 energy at that parameter value), `metastable` (index 0, not the lowest) or
//! `unstable`.
//! Energies of the seeds and of the special points carry an error estimate from the same
//! state at half the resolution, `|E_N − E_{N/2}|/15`.
//!
//! | file | holds |
//! |---|---|
//! | `mod.rs` | the settings and result types, their validation and [`sweep_param`] |
//! | `seeds.rs` | the seed values, the seeds of a branch and their energy estimates |
//! | `family.rs` | the families of one branch: marches, special points, branch switching |
//! | `continued.rs` | the model on the parameter's axis (log for `d1` and `gamma`) |
//! | `rows.rs` | the labels of the traced states and their verification against their files |
//!
//! The stepping itself is the continuation crate's (through [`march`](crate::march::march)).

mod continued;
mod family;
mod rows;
mod seeds;

pub use rows::{verify_sweep, SweepState};

use rodloop_exact::{branch_of_eta, eta_of_branch};
use rodloop_solver::{Accuracy, Param, SolveOptions, Stiffness};

use crate::labels::Label;
use crate::DiagramError;
use family::BranchTrace;

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
        let shape = model.n_kappa();
        let mut traced = BranchTrace::new(s, scene_value, branch, &model, cells, shape)?.trace()?;
        families.append(&mut traced.families);
        special.append(&mut traced.special);
        warnings.append(&mut traced.warnings);
    }
    families.sort_by_key(|f| (f.branch, f.family));
    rows::label(&mut families);
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
