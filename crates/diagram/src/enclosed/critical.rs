//! The critical lengths of the enclosed diagram where a branch has lifted off (the exchange
//! locator [`rodloop_continuation::exchange::locate`] on `E_a = E_b` with re-solved
//! states), and the lowest-branch labels (see the parent module's docs).

use rodloop_continuation::exchange::{self, Energies, EnergyPair, ExchangeSettings, Ranked, Start};
use rodloop_continuation::sampled::{self, Sample};
use rodloop_solver::enclosed::stats;
use rodloop_solver::enclosed::{finest_energy, solve_prolonged, EnclosedOptions, EnclosedState};
use rodloop_solver::{Accuracy, SolverError};

use super::levels::Levels;
use super::trace::exact;
use super::{EnclosedCritical, EnclosedPoint};

/// Is the surface loop of `eta` at `lbar` lifted off (`λ_min < 0`)?
pub(super) fn detached_at(eta: u32, lbar: f64) -> Result<bool, SolverError> {
    Ok(exact(eta, lbar)?.lambda_range().0 < 0.0)
}

/// Energy of branch `eta` at `lbar` with its error: the exact loop where attached,
/// otherwise the 3-D model warm-started from `track` (updated).
pub(super) fn branch_energy(
    eta: u32,
    lbar: f64,
    track: &mut Option<Levels>,
) -> Result<(f64, f64), SolverError> {
    if eta == 0 {
        return Ok((1.0 / lbar, 0.0));
    }
    let l = exact(eta, lbar)?;
    if l.lambda_range().0 >= 0.0 {
        let e = l.energy()?;
        return Ok((e, 1e-14 * e.abs().max(1.0)));
    }
    let t = track.as_ref().ok_or_else(|| {
        SolverError::InvalidInput(format!(
            "no lifted-off state of branch eta = {eta} near lbar = {lbar} to start from"
        ))
    })?;
    let next = t.step_to(lbar, &EnclosedOptions::default())?;
    let out = next.energy();
    *track = Some(next);
    Ok(out)
}

/// Two branches of the enclosed diagram for the exchange locator: `a(x)` and `b(x)` are the
/// two branches' energies at `x` with their error estimates, each side with its own state
/// (its warm start), so the two re-solves at a length run side by side (`b` on a scoped
/// thread in the caller's solve-count scope); the error of `E_a − E_b` at a point is the
/// sum of the two estimates there.
pub(super) struct EnclosedPair<A, B> {
    a: A,
    b: B,
    /// `(x, error of E_a − E_b)` of every evaluation.
    errors: Vec<(f64, f64)>,
}

impl<A, B> EnclosedPair<A, B>
where
    A: FnMut(f64) -> Result<(f64, f64), SolverError> + Send,
    B: FnMut(f64) -> Result<(f64, f64), SolverError> + Send,
{
    pub(super) fn new(a: A, b: B) -> Self {
        Self {
            a,
            b,
            errors: Vec::new(),
        }
    }
}

impl<A, B> EnergyPair for EnclosedPair<A, B>
where
    A: FnMut(f64) -> Result<(f64, f64), SolverError> + Send,
    B: FnMut(f64) -> Result<(f64, f64), SolverError> + Send,
{
    type Error = SolverError;
    fn energies(&mut self, x: f64) -> Result<Energies, SolverError> {
        let (a, b) = (&mut self.a, &mut self.b);
        let scope = stats::current();
        let (ra, rb) = std::thread::scope(|s| {
            let other = s.spawn(|| stats::within(&scope, || b(x)));
            let ra = a(x);
            (
                ra,
                other
                    .join()
                    .unwrap_or_else(|p| std::panic::resume_unwind(p)),
            )
        });
        let ((ea, da), (eb, db)) = (ra?, rb?);
        self.errors.push((x, da + db));
        Ok(Energies {
            a: ea,
            b: eb,
            slope: None,
        })
    }
    fn error(&mut self, x: f64) -> Result<f64, SolverError> {
        match self.errors.iter().rev().find(|(y, _)| *y == x) {
            Some(&(_, e)) => Ok(e),
            None => self
                .energies(x)
                .map(|_| self.errors.last().map_or(0.0, |e| e.1)),
        }
    }
}

/// [`exchange::locate`] from the guess `x0` (first step `probe`, a window of `±0.25`), with
/// the locator's errors as the solver's.
pub(super) fn locate_from<A, B>(
    pair: &mut EnclosedPair<A, B>,
    x0: f64,
    settings: &ExchangeSettings,
) -> Result<exchange::Exchange, SolverError>
where
    A: FnMut(f64) -> Result<(f64, f64), SolverError> + Send,
    B: FnMut(f64) -> Result<(f64, f64), SolverError> + Send,
{
    let window = (x0 - 0.25, x0 + 0.25);
    exchange::locate(pair, Start::Guess { x: x0, window }, settings).map_err(|e| match e {
        rodloop_continuation::RootError::Function(e) => e,
        other => SolverError::InvalidInput(other.to_string()),
    })
}

/// A lifted-off state of one branch at one length on a ladder of meshes `N, 2N, …` (the
/// exchanges' final secant): the trace's three levels stepped to the coarse root, the
/// finest of them prolonged and re-solved up to the ladder's top.
#[derive(Clone, Debug)]
pub(super) struct Ladder {
    states: Vec<EnclosedState>,
}

impl Ladder {
    /// From a trace's levels at `lbar`, with `extra` doublings on top.
    pub(super) fn from_levels(t: &Levels, lbar: f64, extra: usize) -> Result<Self, SolverError> {
        let opts = EnclosedOptions::default();
        let at = t.step_to(lbar, &opts)?;
        let mut states: Vec<EnclosedState> = at.states.to_vec();
        // The prolonged start (its contact runs inside the coarser ones) has its contact
        // ends a node or two off (`solve_prolonged`, as `solve_branch` solves its levels).
        for _ in 0..extra {
            let (m, z) = states.last().expect("a level").refine_in_runs()?;
            let next = solve_prolonged(&m, z, &opts)?;
            states.push(next);
        }
        // Four levels are all the estimate uses.
        let drop = states.len().saturating_sub(4);
        states.drain(..drop);
        Ok(Self { states })
    }

    /// Newton at `lbar` from this ladder, each level from its own state: the finest (which
    /// costs about as much as all the others together, the cells doubling from level to
    /// level) on a thread of its own beside the others.
    pub(super) fn step_to(&self, lbar: f64) -> Result<Self, SolverError> {
        let opts = EnclosedOptions::default();
        let Some((finest, rest)) = self.states.split_last() else {
            return Ok(Self { states: Vec::new() });
        };
        let scope = stats::current();
        let (last, states) = std::thread::scope(|sc| {
            let last = sc.spawn(|| stats::within(&scope, || finest.step_to(lbar, &opts)));
            let states = rest
                .iter()
                .map(|s| s.step_to(lbar, &opts))
                .collect::<Result<Vec<_>, _>>();
            (last.join(), states)
        });
        // The first level that fails names the error, as in order.
        let mut states = states?;
        states.push(last.map_err(|_| {
            SolverError::InvalidInput("the finest level's solve panicked".into())
        })??);
        Ok(Self { states })
    }

    /// Energy of the finest level and its error: the solver's rule for a ladder of meshes
    /// ([`finest_energy`]: the four-level rule over the last four levels of a lifted-off
    /// loop, order capped for its contact; the three-level rule where the ladder has three,
    /// or where the loop touches everywhere).
    pub(super) fn energy(&self) -> Result<(f64, f64), SolverError> {
        let levels: Vec<&EnclosedState> = self.states.iter().collect();
        finest_energy(&levels)
    }

    /// Cells of the levels, coarsest first.
    pub(super) fn cells(&self) -> Vec<usize> {
        self.states.iter().map(|s| s.model.cells()).collect()
    }
}

/// Doublings of the trace's finest mesh `N` for the final secant of an exchange: one at
/// fast accuracy (the ladder `N/4 … 2N`), two at default (`N/2 … 4N`: the figure-eight at
/// 32, 64, 128, 256 cells) and three at high (`N … 8N`: 128, 256, 512, 1024 cells).
pub(super) fn exchange_doublings(accuracy: Accuracy) -> usize {
    match accuracy {
        Accuracy::Fast => 1,
        Accuracy::Default => 2,
        Accuracy::High => 3,
    }
}

/// Energy of branch `eta` at `lbar` with its error: the exact loop where attached,
/// otherwise the ladder `lad` stepped to `lbar` (updated).
fn ladder_energy(eta: u32, lbar: f64, lad: &mut Option<Ladder>) -> Result<(f64, f64), SolverError> {
    if eta == 0 {
        return Ok((1.0 / lbar, 0.0));
    }
    let l = exact(eta, lbar)?;
    if l.lambda_range().0 >= 0.0 {
        let e = l.energy()?;
        return Ok((e, 1e-14 * e.abs().max(1.0)));
    }
    let t = lad.as_ref().ok_or_else(|| {
        SolverError::InvalidInput(format!(
            "no lifted-off state of branch eta = {eta} near lbar = {lbar} to start from"
        ))
    })?;
    let next = t.step_to(lbar)?;
    let out = next.energy()?;
    *lad = Some(next);
    Ok(out)
}

/// Solve `E_a = E_b` near `x0` (see the module docs) with the exchange locator: first with
/// the lifted-off states at the trace's levels `N/4, N/2, N` (hunting from `x0`, first step
/// `−10⁻³`), then, from that root, on the ladder of [`Ladder::from_levels`] with `doublings`
/// more levels (first step `−10⁻⁵`; slope and noise from a chord of half-width `10⁻⁵`; the
/// energies' errors from the ladder's last four levels). Returns `(L̄_cr, error, energy,
/// cells of the final levels)`.
pub(super) fn enclosed_crossing(
    eta_a: u32,
    eta_b: u32,
    x0: f64,
    tracks: &mut [Option<Levels>; 2],
    doublings: usize,
) -> Result<(f64, f64, f64, Vec<usize>), SolverError> {
    let etas = [eta_a, eta_b];
    let coarse = ExchangeSettings {
        baseline: 0.0,
        ..ExchangeSettings::default()
    };
    let xc = {
        let [ta, tb] = &mut *tracks;
        let mut pair = EnclosedPair::new(
            |x| branch_energy(etas[0], x, ta),
            |x| branch_energy(etas[1], x, tb),
        );
        locate_from(&mut pair, x0, &coarse)?.x
    };
    let mut fine: [Option<Ladder>; 2] = [None, None];
    let mut cells = Vec::new();
    for k in 0..2 {
        if let Some(t) = &tracks[k] {
            let lad = Ladder::from_levels(t, xc, doublings)?;
            if lad.cells().last() > cells.last() {
                cells = lad.cells();
            }
            fine[k] = Some(lad);
        }
    }
    let settings = ExchangeSettings {
        probe: -1e-5,
        baseline: 1e-5,
        ..ExchangeSettings::default()
    };
    let [fa, fb] = &mut fine;
    let mut pair = EnclosedPair::new(
        |x| ladder_energy(etas[0], x, fa),
        |x| ladder_energy(etas[1], x, fb),
    );
    let ex = locate_from(&mut pair, xc, &settings)?;
    Ok((ex.x, ex.error, 0.5 * (ex.energies.a + ex.energies.b), cells))
}

/// The lowest branch at `lbar`: the branch the last critical length at or below `lbar`
/// hands over to (the first one's `from` branch below it).
pub(super) fn lowest_branch(critical: &[EnclosedCritical], lbar: f64) -> Option<u32> {
    let k = critical.partition_point(|c| c.critical.lbar_cr <= lbar + 1e-12);
    if k > 0 {
        Some(critical[k - 1].critical.to_branch)
    } else {
        critical.first().map(|c| c.critical.from_branch)
    }
}

/// Energy of `branch` at `lbar` interpolated linearly between its samples
/// ([`interpolated_rows`]).
fn interpolated_state(
    points: &[EnclosedPoint],
    branch: u32,
    lbar: f64,
) -> Option<(f64, f64, bool)> {
    let pts: Vec<&EnclosedPoint> = points.iter().filter(|p| p.branch == branch).collect();
    interpolated_rows(&pts, lbar)
}

/// Energy of the rows `pts` (sorted by `L̄`) at `lbar` interpolated linearly between them,
/// its error estimate ([`sampled::interpolate`]: the rows' own estimates plus the
/// interpolation error from their second differences), and whether it has index 0 there
/// (both neighbouring rows have, or the row at `lbar` has); `None` outside them.
pub(super) fn interpolated_rows(pts: &[&EnclosedPoint], lbar: f64) -> Option<(f64, f64, bool)> {
    let samples: Vec<Sample> = pts
        .iter()
        .map(|p| Sample {
            x: p.lbar,
            f: p.energy,
            error: p.energy_error,
        })
        .collect();
    let (energy, error) = sampled::interpolate(&samples, lbar)?;
    let k = pts.partition_point(|p| p.lbar < lbar);
    let index0 = match pts.iter().find(|p| (p.lbar - lbar).abs() <= 1e-12) {
        Some(p) => p.index == 0,
        None => pts[k - 1].index == 0 && pts[k].index == 0,
    };
    Some((energy, error, index0))
}

/// Lowest flags and labels by the labeller ([`rodloop_continuation::exchange`]): at each
/// sampled state, it and the other branches interpolated to its length, each with its
/// error estimate, the branch the critical lengths name as lowest preferred in ties;
/// `lowest` is the lowest of them at any index (a local minimum before a saddle tied with
/// it, [`exchange::lowest_state`]). A warning where a sampled state lies below the lowest
/// branch by more than the errors (an exchange the list does not have).
pub(super) fn label(
    points: &mut [EnclosedPoint],
    critical: &[EnclosedCritical],
    warnings: &mut Vec<String>,
) {
    let snapshot = points.to_vec();
    let mut branches: Vec<u32> = snapshot.iter().map(|p| p.branch).collect();
    branches.sort_unstable();
    branches.dedup();
    for p in points.iter_mut() {
        let named = lowest_branch(critical, p.lbar);
        let mut states = vec![Ranked {
            energy: p.energy,
            error: p.energy_error,
            index: p.index,
            preferred: named == Some(p.branch),
        }];
        for &b in branches.iter().filter(|&&b| b != p.branch) {
            if let Some((energy, error, index0)) = interpolated_state(&snapshot, b, p.lbar) {
                states.push(Ranked {
                    energy,
                    error,
                    index: usize::from(!index0),
                    preferred: named == Some(b),
                });
            }
        }
        p.lowest = exchange::lowest_state(&states).contains(&0);
        p.label = exchange::label(&states)[0].into();
    }
    for p in points.iter() {
        // Skip the neighbourhood of the located critical lengths, where the lowest branch
        // changes between samples.
        if p.lowest
            || critical
                .iter()
                .any(|c| (c.critical.lbar_cr - p.lbar).abs() < 0.05)
        {
            continue;
        }
        if let Some(b) = lowest_branch(critical, p.lbar) {
            if let Some((e, error, _)) = interpolated_state(&snapshot, b, p.lbar) {
                if p.energy < e - error - p.energy_error {
                    warnings.push(format!(
                        "branch {} at lbar = {:.4} (E = {:.8}) lies below the lowest branch {} (E = {:.8}): an exchange not in the surface list",
                        p.branch, p.lbar, p.energy, b, e
                    ));
                }
            }
        }
    }
}
