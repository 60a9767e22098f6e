//! Seeds of the phase curves: the exchanges of the uniform rod, the lowest placement of
//! the soft segment, and the Maxwell point of two equilibria by the exchange locator.

use rodloop_continuation::exchange::{self, Energies, EnergyPair, ExchangeSettings, Start};
use rodloop_exact::eta_of_branch;
use rodloop_solver::{
    solve_from_state, Equilibrium, Globalization, Param, SolveOptions, SolverError, Stiffness,
    SurfaceSolve,
};

use super::rows::{branch_word, fixed};
use super::{Exchange, PhaseSettings, Tracked};
use crate::maxwell::{join, MaxwellProblem, INDEX_TOL, SEED_OFFSET};
use crate::placements::{classify, shift_of, solve_shifted};
use crate::DiagramError;

/// The crossings of the uniform rod's exact diagram (Sec. 4.3) in `[lbar_min, lbar_max]`.
pub fn uniform_exchanges(lbar_min: f64, lbar_max: f64) -> Result<Vec<Exchange>, DiagramError> {
    let lo = lbar_min.max(0.5);
    if lbar_max.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
        return Err(DiagramError::InvalidOptions(format!(
            "the length range [{lbar_min}, {lbar_max}] holds no exchange of the lowest branch"
        )));
    }
    let settings = rodloop_exact::diagram::DiagramSettings {
        lbar_min: lo,
        lbar_max,
        eta_max: (lbar_max.ceil() as u32 + 1).max(2),
        step: 0.01,
    };
    let d = rodloop_exact::diagram::compute(&settings)
        .map_err(|e| DiagramError::InvalidOptions(format!("exact diagram: {e}")))?;
    Ok(d.critical
        .iter()
        .filter(|c| c.kind == rodloop_exact::diagram::CriticalKind::Crossing)
        .filter(|c| c.from_branch > 0 && c.to_branch > 0)
        .map(|c| Exchange {
            from_branch: c.from_branch,
            to_branch: c.to_branch,
            lbar_uniform: c.lbar_cr,
        })
        .collect())
}

/// Lowest-energy stable state of branch `eta` at `lbar` for a two-segment `stiffness` (the
/// seed of a curve, at a moderate contrast [`SEED_OFFSET`] from the uniform rod).
///
/// Next to the uniform rod the equilibria are the exact loops placed where the energy is
/// stationary with respect to the arclength shift. For the paper's soft segment of half the
/// length the first-order term of that energy is the same for every placement (`κ_g²` has
/// period `1/(2η)`, which divides the segment length), so the placement is selected at second
/// order in `1 − D1/D0`, and for the figure-eight (η = 1) the minimum is *not* one of the
/// mirror-symmetric placements (both have index 1, measured). The state is therefore found
/// by energy minimisation ([`Globalization::Auto`]) from exact loops shifted by eighths of
/// `1/(2η)` (coarse to fine), keeping the lowest one of the right branch with index 0; the
/// search ends once two starts have relaxed to the same state (at `D1/D0 = 0.9` every start
/// that converges reaches the same state, measured for η = 1, 2, 3 near the exchanges).
pub(crate) fn lowest_placement(
    radius: f64,
    lbar: f64,
    eta: u32,
    cells: usize,
    stiffness: &Stiffness,
    opts: &SolveOptions,
) -> Result<Equilibrium, String> {
    let model = crate::surface_model(radius, lbar, cells, stiffness).map_err(|e| e.to_string())?;
    let mut best: Option<(f64, Equilibrium)> = None;
    let mut tried = Vec::new();
    let mut agreed = 0;
    for k in [0, 4, 2, 6, 1, 5, 3, 7] {
        if agreed >= 2 {
            break;
        }
        let shift = shift_of(eta, k);
        match solve_shifted(&model, eta, k, opts) {
            Ok(eq) => {
                let (ok_eta, idx, e) = classify(&eq, eta, INDEX_TOL);
                if ok_eta && idx == 0 {
                    match &best {
                        Some((b, _)) if (e - b).abs() <= 1e-9 * b.abs() => agreed += 1,
                        Some((b, _)) if e > *b => {}
                        _ => {
                            best = Some((e, eq));
                            agreed = 1;
                        }
                    }
                } else {
                    tried.push(format!(
                        "shift {shift:.4}: E = {e:.8}, index {idx}, eta recognised {ok_eta}"
                    ));
                }
            }
            Err(e) => tried.push(format!("shift {shift:.4}: {e}")),
        }
    }
    best.map(|(_, eq)| eq).ok_or_else(|| {
        format!(
            "no stable state of branch eta = {eta} at L̄ = {lbar} ({})",
            tried.join("; ")
        )
    })
}

/// `E_a − E_b` at `lbar`, re-solving both equilibria by Newton from the given states.
pub(super) fn energy_gap(
    a: &Equilibrium,
    b: &Equilibrium,
    lbar: f64,
    opts: &SolveOptions,
) -> Result<(f64, Equilibrium, Equilibrium), SolverError> {
    let newton = SolveOptions {
        globalization: Globalization::Newton,
        ..opts.clone()
    };
    let ea = solve_from_state(a.model().with_lbar(lbar)?, a.state(), &newton)?;
    let eb = solve_from_state(b.model().with_lbar(lbar)?, b.state(), &newton)?;
    Ok((ea.energy().total - eb.energy().total, ea, eb))
}

/// Noise of the energy of a re-solved equilibrium (the KKT tolerance of its Newton
/// solve): the error estimate of each energy in [`maxwell_point`].
const RESOLVE_NOISE: f64 = 1e-11;

/// Two equilibria followed in `L̄` for the exchange locator: each evaluation re-solves both
/// by Newton from the pair solved last.
struct GapPair<'a> {
    start: (&'a Equilibrium, &'a Equilibrium),
    last: Option<(Equilibrium, Equilibrium)>,
    opts: &'a SolveOptions,
}

impl EnergyPair for GapPair<'_> {
    type Error = SolverError;
    fn energies(&mut self, lbar: f64) -> Result<Energies, SolverError> {
        let (_, ea, eb) = match &self.last {
            None => energy_gap(self.start.0, self.start.1, lbar, self.opts)?,
            Some((pa, pb)) => energy_gap(pa, pb, lbar, self.opts)?,
        };
        let out = Energies {
            a: ea.energy().total,
            b: eb.energy().total,
            slope: None,
        };
        self.last = Some((ea, eb));
        Ok(out)
    }
    fn error(&mut self, _lbar: f64) -> Result<f64, SolverError> {
        Ok(2.0 * RESOLVE_NOISE)
    }
}

/// The Maxwell point `E_a(L̄) = E_b(L̄)` of two equilibria (same stiffness) by the exchange
/// locator ([`rodloop_continuation::exchange::locate`]) on re-solved equilibria, hunting
/// from their common length (first step `+10⁻³`, steps clamped to 0.05, within `±0.5`);
/// returns the two equilibria at the critical length and `d(E_a − E_b)/dL̄` there (the
/// chord over `±10⁻⁵`). The energies carry noise of about `RESOLVE_NOISE`, so `L̄` is
/// refined to `10⁻¹¹` only; the augmented Newton polishes.
pub fn maxwell_point(
    a: &Equilibrium,
    b: &Equilibrium,
    opts: &SolveOptions,
) -> Result<(Equilibrium, Equilibrium, f64), SolverError> {
    let mut pair = GapPair {
        start: (a, b),
        last: None,
        opts,
    };
    let settings = ExchangeSettings {
        xtol: 1e-11,
        probe: 1e-3,
        max_step: 0.05,
        baseline: 1e-5,
        max_evaluations: 30,
        misfit: true,
    };
    let x0 = a.lbar();
    let start = Start::Guess {
        x: x0,
        window: (x0 - 0.5, x0 + 0.5),
    };
    let ex = exchange::locate(&mut pair, start, &settings).map_err(|e| match e {
        rodloop_continuation::RootError::Function(e) => e,
        other => SolverError::InvalidInput(format!("E_a = E_b: {other}")),
    })?;
    let (pa, pb) = pair.last.expect("the locator evaluates before it stops");
    let (_, ea, eb) = energy_gap(&pa, &pb, ex.x, opts)?;
    Ok((ea, eb, ex.slope))
}

/// The start of a curve: the Maxwell point of the lowest stable states of the exchange's two
/// branches at `D1/D0 = 1 ∓` [`SEED_OFFSET`] (on the side of the uniform rod where the scene
/// and the target lie), on the problem continued in `d1`.
pub(super) struct Seed<M> {
    /// The augmented system in `d1` (the models of the two branches).
    pub(super) problem: MaxwellProblem<M>,
    /// The polished Maxwell point.
    pub(super) start: Tracked,
    /// `D1/D0` of the seed.
    pub(super) theta: f64,
}

/// Seed exchange `ex` on the side `below` (`D1/D0 < 1`) or above the uniform rod.
pub(super) fn seed_exchange(
    s: &PhaseSettings,
    ex: Exchange,
    below: bool,
) -> Result<Seed<impl SurfaceSolve>, DiagramError> {
    let crit = |reason: String| DiagramError::Critical {
        from_branch: ex.from_branch,
        to_branch: ex.to_branch,
        lbar: ex.lbar_uniform,
        reason,
    };
    let theta = if below {
        1.0 - SEED_OFFSET
    } else {
        1.0 + SEED_OFFSET
    };
    let stiff = s.stiffness.with_param(Param::D1, theta)?;
    let state = |branch: u32| {
        let eta = eta_of_branch(branch);
        let cells = s.accuracy.cells(eta as usize, &stiff);
        lowest_placement(s.radius, ex.lbar_uniform, eta, cells, &stiff, &s.solve).map_err(&crit)
    };
    let (sa, sb) = (state(ex.from_branch)?, state(ex.to_branch)?);
    let (ma, mb, slope) =
        maxwell_point(&sa, &sb, &s.solve).map_err(|e| crit(format!("seed: {e}")))?;
    // E_from − E_to increases through L̄_cr when `from` is the lower one below it.
    if slope.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return Err(crit(format!(
            "seed: at D1/D0 = {theta} the energy difference of {} and {} has slope {slope:.3e} at the crossing: {} is not the lower one below it",
            branch_word(ex.from_branch),
            branch_word(ex.to_branch),
            branch_word(ex.from_branch)
        )));
    }
    let x = join(&ma.state(), &mb.state(), ma.lbar());
    let problem = MaxwellProblem::new(ma.model().clone(), mb.model().clone(), Param::D1)?;
    let p = problem.p_of(theta);
    let x = fixed(&problem, &x, p).map_err(|e| crit(format!("seed polish: {e}")))?;
    let index = problem.indices(&x, p)?;
    Ok(Seed {
        problem,
        start: Tracked {
            x,
            p,
            index,
            arm: 0,
        },
        theta,
    })
}
