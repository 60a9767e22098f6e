//! One sheet of the non-uniform enclosed diagram ([`super::nonuniform`]): its share of the
//! output ([`SheetOut`]), its surface states re-solved at a length ([`surface_at`],
//! [`surface_energy`]), and its lifted-off states walked to a length ([`walk`]). The
//! diagram's route, its exchanges, special points and descents all build on these.

use rodloop_continuation::natural::{self, Halted, StepSettings};
use rodloop_solver::enclosed::{finer_check, EnclosedOptions};
use rodloop_solver::{solve_from_state, Equilibrium, SolverError};

use super::levels::Levels;
use super::trace::{step_options, TraceStop};
use super::{EnclosedEvent, EnclosedPoint, PointSource};
use crate::parallel::run_parallel;
use crate::states::{half_resolution, newton_options};
use crate::types::TracedBranch;
use crate::DiagramOptions;

/// One sheet's share of the diagram.
pub(super) struct SheetOut {
    pub(super) branch: u32,
    pub(super) eta: u32,
    pub(super) family: u32,
    pub(super) points: Vec<EnclosedPoint>,
    pub(super) levels: Vec<Levels>,
    pub(super) events: Vec<EnclosedEvent>,
    pub(super) warnings: Vec<String>,
    /// Where its lifted-off traces stopped (classified in `nonuniform_special.rs`).
    pub(super) stops: Vec<TraceStop>,
    pub(super) attached_s: f64,
    pub(super) lifted_s: f64,
}

impl SheetOut {
    /// A sheet of branch `branch` (`eta`), family `family`, with no states yet.
    pub(super) fn empty(branch: u32, eta: u32, family: u32) -> Self {
        Self {
            branch,
            eta,
            family,
            points: Vec::new(),
            levels: Vec::new(),
            events: Vec::new(),
            warnings: Vec::new(),
            stops: Vec::new(),
            attached_s: 0.0,
            lifted_s: 0.0,
        }
    }
}

/// The surface equilibrium of `sheet` at `x` with `cells` cells: Newton at the tracing
/// resolution from the traced state nearest in `L̄`, then (for other `cells`) re-solved
/// there.
pub(super) fn surface_at(
    dopts: &DiagramOptions,
    sheet: &TracedBranch,
    x: f64,
    cells: usize,
) -> Result<Equilibrium, SolverError> {
    let p = sheet
        .points
        .iter()
        .min_by(|a, b| (a.value - x).abs().total_cmp(&(b.value - x).abs()))
        .ok_or_else(|| SolverError::InvalidInput("an empty sheet".into()))?;
    let model = dopts.model(x, sheet.cells)?;
    let eq = solve_from_state(model, p.state.clone(), &newton_options())?;
    if cells == sheet.cells {
        return Ok(eq);
    }
    half_resolution(dopts, &eq, cells).ok_or_else(|| {
        SolverError::InvalidInput(format!(
            "the surface state at lbar = {x} did not re-solve at {cells} cells"
        ))
    })
}

/// Surface energy of `sheet` at `x` with its error: `N` and `2N` cells,
/// `E_2N` and `|E_2N − E_N|/15` (fourth order on the graded mesh).
pub(super) fn surface_energy(
    dopts: &DiagramOptions,
    sheet: &TracedBranch,
    x: f64,
) -> Result<(f64, f64), SolverError> {
    surface_energy_doubled(dopts, sheet, x, 0)
}

/// [`surface_energy`] on `2^k N` and `2^(k+1) N` cells (`N` the tracing resolution): the
/// attached side of an exchange located on a ladder of meshes `k` doublings above the
/// trace (`exchange_doublings`), so that its energy is resolved as finely as the lifted-off
/// side's. The state is solved at `N` from the traced state nearest in `L̄`, then re-solved
/// at each doubling from the one below.
pub(super) fn surface_energy_doubled(
    dopts: &DiagramOptions,
    sheet: &TracedBranch,
    x: f64,
    k: usize,
) -> Result<(f64, f64), SolverError> {
    let mut fine = surface_at(dopts, sheet, x, sheet.cells)?;
    let mut coarse = None;
    for _ in 0..=k {
        let n = 2 * fine.model().cells();
        let next = half_resolution(dopts, &fine, n).ok_or_else(|| {
            SolverError::InvalidInput(format!(
                "the surface state at lbar = {x} did not re-solve at {n} cells"
            ))
        })?;
        coarse = Some(std::mem::replace(&mut fine, next));
    }
    let coarse = coarse.expect("at least one doubling");
    let (a, b) = (coarse.energy().total, fine.energy().total);
    Ok((b, rodloop_solver::richardson_error(b, a)))
}

/// Step `t` to `x` in steps of `0.01`, halving a failed step up to 6 times; after the first
/// step, each step starts from the secant predictor through the last two states (the plain
/// warm start where that fails).
pub(super) fn walk(t: &Levels, x: f64) -> Result<Levels, SolverError> {
    walk_with(t, x, &step_options())
}

/// Length of the steps of [`walk`] in `L̄`.
const WALK_STEP: f64 = 0.01;

/// [`walk`] with the Newton options `opts`: a natural-parameter [`natural::walk_steps`] in
/// steps of [`WALK_STEP`], each step halved up to 6 times where it fails and the next step
/// tried at full length again (a step that had to be halved once does not shrink every later
/// one: with the step kept at its halved length, a walk of `0.6` in `L̄` took about 1200
/// steps instead of 60), arrival to `1e-15`.
pub(super) fn walk_with(t: &Levels, x: f64, opts: &EnclosedOptions) -> Result<Levels, SolverError> {
    const HALVINGS: usize = 6;
    // Every step is at least `WALK_STEP / 2^HALVINGS` long, so this bounds a walk that
    // reaches its target.
    let max_steps = ((x - t.lbar).abs() / WALK_STEP).ceil() as usize * (1 << HALVINGS) + 1;
    let settings = StepSettings {
        step: WALK_STEP,
        max_halvings: HALVINGS,
        max_steps,
        arrive: 1e-15,
    };
    natural::walk_steps(
        t.clone(),
        None,
        x,
        |l: &Levels| l.lbar,
        &settings,
        |cur, prev, to, _| {
            let predicted = match prev {
                Some(p) => cur.step_predicted(p, to, opts),
                None => Err(SolverError::InvalidInput("no predictor".into())),
            };
            predicted.or_else(|_| cur.step_to(to, opts))
        },
    )
    .map(|w| w.last)
    .map_err(|h| match h {
        Halted::Stuck(s) => s.error,
        Halted::OutOfSteps { last } => SolverError::InvalidInput(format!(
            "the walk to lbar = {x} ran out of steps at lbar = {}",
            last.lbar
        )),
    })
}

impl SheetOut {
    /// Leave out the lifted-off states whose own periods name another branch than the
    /// sheet's (the moment of the central projection,
    /// [`rodloop_solver::identify::identify_enclosed`]): near a great circle the sheets of
    /// `η` and of another branch through it come close, and a trace or a descent there can
    /// land on the other one. Such a state is not a state of this row's branch, so neither
    /// its row nor its file is kept. States whose periods cannot be counted (a loop in a
    /// plane through the centre) keep the family's branch (continuation history).
    /// Returns one message per sheet with states left out.
    pub(super) fn drop_other_branches(&mut self) -> Option<String> {
        let mut gone: Vec<(f64, u32)> = Vec::new();
        self.points.retain(|p| {
            let super::PointShape::Model(st) = &p.shape else {
                return true;
            };
            match rodloop_solver::identify::identify_enclosed(st) {
                Ok(per) if per.eta != self.eta => {
                    gone.push((p.lbar, per.eta));
                    false
                }
                _ => true,
            }
        });
        if gone.is_empty() {
            return None;
        }
        self.levels
            .retain(|l| !gone.iter().any(|&(x, _)| (l.lbar - x).abs() < 1e-12));
        let list: Vec<String> = gone
            .iter()
            .map(|(x, e)| format!("lbar = {x:.6} (eta = {e})"))
            .collect();
        Some(format!(
            "branch {} (eta = {}) family {}: {} lifted-off state(s) whose moment names another branch left out ({}): the trace reached another branch's states, which are not rows of this family",
            self.branch,
            self.eta,
            self.family,
            gone.len(),
            list.join(", ")
        ))
    }
}

/// The rows of the sheets `outs` that have lifted off and touch the wall, each checked on
/// twice its cells ([`finer_check`]: the state prolonged and re-solved, the distance to it
/// plus its own estimate), on `threads` threads: a row's estimate is widened to that bound
/// where it is larger (the three-level estimate of `N/4, N/2, N` is short where those levels
/// converge irregularly). Returns how many rows were widened and how many checks failed.
pub(super) fn check_rows_on_finer(outs: &mut [SheetOut], threads: usize) -> (usize, usize) {
    let mut items = Vec::new();
    for (i, s) in outs.iter().enumerate() {
        for (j, p) in s.points.iter().enumerate() {
            let touches = p.contact_fraction > 0.0 && !p.attached;
            if p.source == PointSource::Model && touches {
                items.push((i, j));
            }
        }
    }
    let opts = EnclosedOptions::default();
    let found = {
        let outs = &*outs;
        run_parallel(threads, items, &mut |_| {}, &mut |_| {}, |(i, j), _| {
            let p = &outs[i].points[j];
            let bound = outs[i]
                .levels
                .iter()
                .find(|l| (l.lbar - p.lbar).abs() < 1e-12)
                .and_then(|l| finer_check(&l.states[2], l.states[1].energy(), &opts))
                .map(|c| c.0);
            (i, j, bound)
        })
    };
    let (mut widened, mut failed) = (0, 0);
    for (i, j, bound) in found {
        let p = &mut outs[i].points[j];
        match bound {
            Some(b) if b > p.energy_error => {
                p.energy_error = b;
                widened += 1;
            }
            Some(_) => {}
            None => failed += 1,
        }
    }
    (widened, failed)
}
