//! The phase diagram of a two-segment rod: every exchange of the lowest branch of the
//! uniform rod followed as a curve `L̄_cr(θ)` in a stiffness parameter `θ` (see
//! [`crate::maxwell`] for the augmented system and its continuation).

use nalgebra::DVector;
use rodloop_continuation::{
    newton, Continuation, Direction, PseudoArclength, SpecialKind, StopReason,
};
use rodloop_exact::eta_of_branch;
use rodloop_solver::identify::identify_equilibrium;
use rodloop_solver::{
    solve_cells, solve_from_state, Accuracy, Confinement, Equilibrium, Globalization, Param,
    SolveOptions, SolverError, StartShape, Stiffness,
};

use crate::maxwell::{MaxwellProblem, INDEX_TOL, LIMIT_OFFSETS, SEED_OFFSET};
use crate::DiagramError;

/// An exchange of the lowest branch of the uniform rod (a crossing `E_a = E_b`, from the
/// exact layer), the start of a curve.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Exchange {
    /// Lowest paper branch just below `L̄_cr`.
    pub from_branch: u32,
    /// Lowest paper branch just above.
    pub to_branch: u32,
    /// The exact critical length of the uniform rod.
    pub lbar_uniform: f64,
}

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

/// What [`trace_phase`] computes.
#[derive(Clone, Debug)]
pub struct PhaseSettings {
    /// Sphere radius `R`.
    pub radius: f64,
    /// The scene's stiffness profile (two-segment, Eq. (51)).
    pub stiffness: Stiffness,
    /// The continued parameter (`d1`, `gamma`, `s0`, `s1`).
    pub param: Param,
    /// The end value of the parameter (the start is the scene's value).
    pub target: f64,
    /// Length range of the scene: the exchanges of the uniform rod inside it are followed.
    pub lbar_min: f64,
    /// Upper end of the length range.
    pub lbar_max: f64,
    /// Resolution and error estimate ([`Accuracy`]).
    pub accuracy: Accuracy,
    /// Parameter values at which rows are solved exactly (Newton at fixed `θ`).
    pub at: Vec<f64>,
    /// Solver settings of the seeds and re-solves.
    pub solve: SolveOptions,
}

/// How a row of a curve was obtained.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RowSource {
    /// The Maxwell point by the secant method on re-solved equilibria (the curve's start).
    Seed,
    /// An accepted point of the pseudo-arclength continuation.
    Continuation,
    /// Newton's method on the augmented system at an exact parameter value (`--at`, and the
    /// ladder towards `D1/D0 = 1`).
    Fixed,
    /// The limit `D1/D0 → 1`, extrapolated from the ladder of fixed rows.
    Limit,
}

impl RowSource {
    /// Name in output files.
    pub fn name(self) -> &'static str {
        match self {
            RowSource::Seed => "seed",
            RowSource::Continuation => "continuation",
            RowSource::Fixed => "fixed",
            RowSource::Limit => "limit",
        }
    }
}

/// One Maxwell point of a curve.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PhaseRow {
    /// Parameter value `θ`.
    pub value: f64,
    /// Critical length `L̄_cr` (Richardson-extrapolated for `High`).
    pub lbar_cr: f64,
    /// Estimated absolute error of `lbar_cr`.
    pub error_estimate: f64,
    /// Common energy `E R/(π D0)` of the two states.
    pub energy: f64,
    /// Lowest branch just below `lbar_cr` (from the sign of the slope).
    pub from_branch: u32,
    /// Lowest branch just above.
    pub to_branch: u32,
    /// Stability indices of the states of the exchange's `from_branch` and `to_branch` (those
    /// of [`PhaseCurve::exchange`]).
    pub index: (usize, usize),
    /// Arm of the curve: 0 from the start, +1 after each fold where the energy curves touch.
    pub arm: usize,
    /// `d(E_from − E_to)/dL̄` of the exchange's branches at the crossing (re-solved states).
    pub slope: f64,
    /// How the row was obtained.
    pub source: RowSource,
}

/// Why (and where) a curve ends in one direction.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct CurveEnd {
    /// Parameter value of the last Maxwell point of the curve in this direction.
    pub value: f64,
    /// `reached` (the end of the requested range), `unstable` (a state lost stability),
    /// `fold` (the Maxwell point turns back in the parameter), `branch_point`, `failed`, or
    /// `limit` (the uniform rod, `D1/D0 → 1`).
    pub kind: String,
    /// Explanation for people.
    pub reason: String,
}

/// The limit `D1/D0 → 1` of a curve compared with the uniform rod's exact critical length.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct UniformCheck {
    /// Extrapolated `L̄_cr` at `D1/D0 = 1`.
    pub lbar_cr: f64,
    /// Its estimated error (discretisation + extrapolation).
    pub error_estimate: f64,
    /// The exact critical length of the uniform rod.
    pub exact: f64,
    /// `lbar_cr − exact`.
    pub deviation: f64,
}

/// One followed exchange.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PhaseCurve {
    /// The exchange of the uniform rod it starts from.
    pub exchange: Exchange,
    /// Rows in increasing parameter value.
    pub rows: Vec<PhaseRow>,
    /// How the curve ends towards lower and higher parameter values.
    pub ends: Vec<CurveEnd>,
    /// The limit at the uniform rod (`d1` only).
    pub uniform: Option<UniformCheck>,
    /// Accepted continuation steps.
    pub steps: usize,
    /// Cells of the two models `(from_branch, to_branch)` at the main resolution.
    pub cells: (usize, usize),
    /// Folds of the curve where the two energy curves touch (the curve goes on, on its next
    /// arm).
    pub turns: Vec<String>,
    /// Notes (requested `--at` values outside the traced range, …).
    pub notes: Vec<String>,
}

/// Result of [`trace_phase`].
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PhaseDiagram {
    /// The continued parameter.
    pub param: Param,
    /// The scene's value.
    pub scene_value: f64,
    /// The requested end value.
    pub target: f64,
    /// One curve per exchange of the uniform rod in the length range.
    pub curves: Vec<PhaseCurve>,
}

/// A state of the continuation with its companion (other resolution) for the error estimate.
#[derive(Clone)]
struct Tracked {
    x: DVector<f64>,
    p: f64,
    index: (usize, usize),
    /// Arm of the curve (the count of tangency folds passed before it).
    arm: usize,
}

/// The resolution pair of an accuracy level: `Some(cells factor)` of the companion.
fn companion_cells(accuracy: Accuracy, n: usize) -> usize {
    match accuracy {
        Accuracy::High => 2 * n,
        _ => (n / 2).div_ceil(2) * 2,
    }
}

/// Follow every exchange of the uniform rod in the scene's length range (see the module
/// docs of [`crate::maxwell`]).
pub fn trace_phase(settings: &PhaseSettings) -> Result<PhaseDiagram, DiagramError> {
    let s = settings;
    let Stiffness::Tanh { .. } = &s.stiffness else {
        return Err(DiagramError::InvalidOptions(
            "phase needs a two-segment stiffness profile (kind = \"tanh\", Eq. (51)) in the scene"
                .into(),
        ));
    };
    if s.param == Param::Lbar {
        return Err(DiagramError::InvalidOptions(
            "the parameter of a phase diagram is d1, gamma, s0 or s1 (lbar is the unknown critical length)"
                .into(),
        ));
    }
    let scene_value = s.stiffness.param(s.param)?;
    if !s.target.is_finite() {
        return Err(DiagramError::InvalidOptions(format!(
            "--to must be finite (got {})",
            s.target
        )));
    }
    // The target profile must be valid.
    s.stiffness.with_param(s.param, s.target)?.validate()?;
    if s.param == Param::D1 {
        if s.target.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            return Err(DiagramError::InvalidOptions(format!(
                "--to for d1 = D1/D0 must be positive (got {})",
                s.target
            )));
        }
        let (lo, hi) = (scene_value.min(s.target), scene_value.max(s.target));
        if lo < 1.0 && hi > 1.0 {
            return Err(DiagramError::InvalidOptions(format!(
                "the range of d1 from {scene_value} to {} crosses the uniform rod d1 = 1, where the \
                 lowest placement of the segment changes; trace each side separately",
                s.target
            )));
        }
    } else if (s.target - scene_value).abs() == 0.0 {
        return Err(DiagramError::InvalidOptions(format!(
            "--to {} is the scene's value of {}: nothing to follow",
            s.target, s.param
        )));
    }
    for &v in &s.at {
        s.stiffness
            .with_param(s.param, v)?
            .validate()
            .map_err(|e| {
                DiagramError::InvalidOptions(format!(
                    "--at {v}: not a valid value of {}: {e}",
                    s.param
                ))
            })?;
        if s.param == Param::D1 && v.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            return Err(DiagramError::InvalidOptions(format!(
                "--at {v}: d1 = D1/D0 must be positive"
            )));
        }
    }
    let exchanges = uniform_exchanges(s.lbar_min, s.lbar_max)?;
    // One thread per exchange (the curves are independent).
    let results: Vec<Result<PhaseCurve, DiagramError>> = std::thread::scope(|scope| {
        let handles: Vec<_> = exchanges
            .iter()
            .map(|&ex| scope.spawn(move || trace_exchange(s, scene_value, ex)))
            .collect();
        handles
            .into_iter()
            .map(|h| {
                h.join().unwrap_or_else(|_| {
                    Err(DiagramError::InvalidOptions(
                        "internal error: a phase curve's thread panicked".into(),
                    ))
                })
            })
            .collect()
    });
    let curves = results.into_iter().collect::<Result<Vec<_>, _>>()?;
    Ok(PhaseDiagram {
        param: s.param,
        scene_value,
        target: s.target,
        curves,
    })
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
    let start = StartShape::Exact { eta };
    let period = 0.5 / f64::from(eta);
    let mut best: Option<(f64, Equilibrium)> = None;
    let mut tried = Vec::new();
    let mut agreed = 0;
    for k in [0, 4, 2, 6, 1, 5, 3, 7] {
        if agreed >= 2 {
            break;
        }
        let shift = period * f64::from(k) / 8.0;
        let st = start.shifted(lbar, shift).map_err(|e| e.to_string())?;
        match solve_cells(radius, lbar, cells, stiffness, &st, None, opts) {
            Ok(eq) => {
                let ok_eta = identify_equilibrium(&eq)
                    .map(|p| p.eta == eta)
                    .unwrap_or(false);
                let idx = eq
                    .model()
                    .index(&eq.state(), INDEX_TOL)
                    .unwrap_or(usize::MAX);
                let e = eq.energy().total;
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
fn energy_gap(
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

/// The Maxwell point `E_a(L̄) = E_b(L̄)` of two equilibria (same stiffness) by the secant
/// method on re-solved equilibria, starting at their common length and `lbar + 1e-3`;
/// returns the two equilibria at the critical length and `d(E_a − E_b)/dL̄` there.
pub fn maxwell_by_secant(
    a: &Equilibrium,
    b: &Equilibrium,
    opts: &SolveOptions,
) -> Result<(Equilibrium, Equilibrium, f64), SolverError> {
    let mut l0 = a.lbar();
    let (mut f0, mut a0, mut b0) = energy_gap(a, b, l0, opts)?;
    let mut l1 = l0 + 1e-3;
    let (mut f1, mut a1, mut b1) = energy_gap(&a0, &b0, l1, opts)?;
    for _ in 0..30 {
        let slope = (f1 - f0) / (l1 - l0);
        // The energies of re-solved states carry noise of about 1e-11 (the KKT tolerance):
        // stop at 1e-10 (L̄ to ~1e-11 for slopes of order 1); the augmented Newton polishes.
        if f1.abs() < 1e-10 {
            return Ok((a1, b1, slope));
        }
        if !(slope.is_finite() && slope != 0.0) {
            break;
        }
        let step = (-f1 / slope).clamp(-0.05, 0.05);
        let l2 = l1 + step;
        let (f2, a2, b2) = energy_gap(&a1, &b1, l2, opts)?;
        (l0, f0, a0, b0) = (l1, f1, a1, b1);
        (l1, f1, a1, b1) = (l2, f2, a2, b2);
        if (l1 - l0).abs() < 1e-13 {
            return Ok((a1, b1, slope));
        }
    }
    let _ = (a0, b0);
    Err(SolverError::InvalidInput(format!(
        "the secant method for E_a = E_b did not converge (last L̄ = {l1}, gap {f1:.3e})"
    )))
}

/// Newton on the augmented system at fixed `p` from `x`.
fn fixed(problem: &MaxwellProblem, x: &DVector<f64>, p: f64) -> Result<DVector<f64>, String> {
    newton(problem, x, p, 1e-11, 30)
        .map(|(x, _)| x)
        .map_err(|e| e.to_string())
}

/// A Maxwell point at `p` with its companion, as a row.
struct RowMaker<'a> {
    main: &'a MaxwellProblem,
    ex: Exchange,
    accuracy: Accuracy,
    opts: &'a SolveOptions,
    /// The companion problem and its last state (warm start).
    companion: Option<(MaxwellProblem, DVector<f64>)>,
}

impl RowMaker<'_> {
    fn row(&mut self, t: &Tracked, source: RowSource) -> Result<PhaseRow, String> {
        let (x, p, index) = (&t.x, t.p, t.index);
        let pb = self.main;
        let (slope, _, _) = pb.crossing_slope(x, p).map_err(|e| e.to_string())?;
        let (from_branch, to_branch) = if slope > 0.0 {
            (self.ex.from_branch, self.ex.to_branch)
        } else {
            (self.ex.to_branch, self.ex.from_branch)
        };
        let (ea, _) = pb.energies(x, p).map_err(|e| e.to_string())?;
        let lbar = x[x.len() - 1];
        // The companion from its last state, or resampled from x when that fails.
        let mut comp = None;
        if let Some((cp, cx)) = &self.companion {
            if let Ok(y) = fixed(cp, cx, p) {
                comp = Some((cp.clone(), y));
            }
        }
        let mut finer = false;
        if comp.is_none() {
            let (ma, mb) = pb.models();
            let mut why = Vec::new();
            // The companion of the accuracy level; if it does not converge (a sharp profile
            // at few cells), twice the main resolution, as `finish_with_accuracy` does.
            let mut pairs = vec![(
                companion_cells(self.accuracy, ma.cells()),
                companion_cells(self.accuracy, mb.cells()),
            )];
            if self.accuracy != Accuracy::High {
                pairs.push((2 * ma.cells(), 2 * mb.cells()));
            }
            for (k, (ca, cb)) in pairs.into_iter().enumerate() {
                let attempt = pb
                    .resampled(x, p, ca, cb, self.opts)
                    .map_err(|e| e.to_string())
                    .and_then(|(cp, cx)| fixed(&cp, &cx, p).map(|y| (cp, y)));
                match attempt {
                    Ok(c) => {
                        finer = k == 1;
                        comp = Some(c);
                        break;
                    }
                    Err(e) => why.push(format!("{ca}+{cb} cells: {e}")),
                }
            }
            if comp.is_none() {
                return Err(format!("companion resolution: {}", why.join("; ")));
            }
        } else if let Some((cp, _)) = &comp {
            finer = cp.models().0.cells() > pb.models().0.cells();
        }
        let (cp, y) = comp.expect("set above");
        let lc = y[y.len() - 1];
        let (ec, _) = cp.energies(&y, p).map_err(|e| e.to_string())?;
        self.companion = Some((cp, y));
        let (lbar_cr, energy, est) = match self.accuracy {
            _ if finer && self.accuracy != Accuracy::High => (lbar, ea, (lc - lbar).abs() / 15.0),
            Accuracy::High => (
                lc + (lc - lbar) / 15.0,
                ec + (ec - ea) / 15.0,
                (lc - lbar).abs() / 15.0,
            ),
            _ => (lbar, ea, (lbar - lc).abs() / 15.0),
        };
        Ok(PhaseRow {
            value: pb.theta(p),
            lbar_cr,
            error_estimate: est,
            energy,
            from_branch,
            to_branch,
            index,
            arm: t.arm,
            slope,
            source,
        })
    }
}

fn branch_word(b: u32) -> String {
    format!("branch {b} (eta = {})", eta_of_branch(b))
}

/// Seed, continue and extrapolate one exchange.
fn trace_exchange(
    s: &PhaseSettings,
    scene_value: f64,
    ex: Exchange,
) -> Result<PhaseCurve, DiagramError> {
    let crit = |reason: String| DiagramError::Critical {
        from_branch: ex.from_branch,
        to_branch: ex.to_branch,
        lbar: ex.lbar_uniform,
        reason,
    };
    // Side of the uniform rod on which the scene's d1 lies.
    let d1_scene = s.stiffness.param(Param::D1)?;
    let below = if s.param == Param::D1 {
        scene_value.min(s.target) < 1.0
    } else {
        d1_scene < 1.0
    };
    let theta_seed = if below {
        1.0 - SEED_OFFSET
    } else {
        1.0 + SEED_OFFSET
    };
    let seed_stiff = s.stiffness.with_param(Param::D1, theta_seed)?;
    let (eta_a, eta_b) = (eta_of_branch(ex.from_branch), eta_of_branch(ex.to_branch));
    let cells_a = s.accuracy.cells(eta_a as usize, &seed_stiff);
    let cells_b = s.accuracy.cells(eta_b as usize, &seed_stiff);
    let sa = lowest_placement(
        s.radius,
        ex.lbar_uniform,
        eta_a,
        cells_a,
        &seed_stiff,
        &s.solve,
    )
    .map_err(&crit)?;
    let sb = lowest_placement(
        s.radius,
        ex.lbar_uniform,
        eta_b,
        cells_b,
        &seed_stiff,
        &s.solve,
    )
    .map_err(&crit)?;
    let (ma, mb, slope) =
        maxwell_by_secant(&sa, &sb, &s.solve).map_err(|e| crit(format!("seed: {e}")))?;
    // E_from − E_to increases through L̄_cr when `from` is the lower one below it.
    if slope.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return Err(crit(format!(
            "seed: at D1/D0 = {theta_seed} the energy difference of {} and {} has slope {slope:.3e} at the crossing: {} is not the lower one below it",
            branch_word(ex.from_branch),
            branch_word(ex.to_branch),
            branch_word(ex.from_branch)
        )));
    }
    let x_seed = MaxwellProblem::join(&ma.state(), &mb.state(), ma.lbar());
    let d1_problem = MaxwellProblem::new(ma.model().clone(), mb.model().clone(), Param::D1)?;
    let p_seed = d1_problem.p_of(theta_seed);
    let x_seed =
        fixed(&d1_problem, &x_seed, p_seed).map_err(|e| crit(format!("seed polish: {e}")))?;
    let seed_index = d1_problem.indices(&x_seed, p_seed)?;

    let mut notes = Vec::new();
    let mut turns = Vec::new();
    let mut ends = Vec::new();
    let mut steps = 0;
    let mut rows = Vec::new();
    let mut uniform = None;
    // Every main-resolution Maxwell point computed (for the `--at` rows).
    let mut states: Vec<Tracked> = Vec::new();

    if s.param == Param::D1 {
        let mut maker = RowMaker {
            main: &d1_problem,
            ex,
            accuracy: s.accuracy,
            opts: &s.solve,
            companion: None,
        };
        let seed_t = Tracked {
            x: x_seed.clone(),
            p: p_seed,
            index: seed_index,
            arm: 0,
        };
        rows.push(maker.row(&seed_t, RowSource::Seed).map_err(&crit)?);
        states.push(seed_t.clone());
        // Towards the far end of the range.
        let far = if below {
            scene_value.min(s.target)
        } else {
            scene_value.max(s.target)
        };
        let mut offsets = LIMIT_OFFSETS;
        offsets.sort_by(|a, b| b.total_cmp(a));
        let towards = |off: f64| if below { 1.0 - off } else { 1.0 + off };
        // The whole traced range: from the far end to the top of the ladder.
        let (pa, pb) = (d1_problem.p_of(far), d1_problem.p_of(towards(offsets[0])));
        let range = (pa.min(pb), pa.max(pb));
        let leg = follow(
            &d1_problem,
            &x_seed,
            p_seed,
            d1_problem.p_of(far),
            range,
            seed_index,
            ex,
            &mut turns,
        )?;
        steps += leg.points.len();
        for t in &leg.points {
            rows.push(maker.row(t, RowSource::Continuation).map_err(&crit)?);
        }
        ends.push(leg.end);
        states.extend(leg.points);
        // Towards the uniform rod: continuation to the largest offset of the ladder, then
        // Newton at the ladder's values, extrapolated to D1/D0 = 1.
        let mut maker = RowMaker {
            main: &d1_problem,
            ex,
            accuracy: s.accuracy,
            opts: &s.solve,
            companion: None,
        };
        let p_top = d1_problem.p_of(towards(offsets[0]));
        let leg = follow(
            &d1_problem,
            &x_seed,
            p_seed,
            p_top,
            range,
            seed_index,
            ex,
            &mut turns,
        )?;
        steps += leg.points.len();
        let leg_reached = leg
            .points
            .last()
            .is_some_and(|t| (t.p - p_top).abs() < 1e-9 && t.arm == 0);
        let mut x = leg
            .points
            .last()
            .map(|t| t.x.clone())
            .unwrap_or(x_seed.clone());
        for t in &leg.points {
            rows.push(maker.row(t, RowSource::Continuation).map_err(&crit)?);
        }
        states.extend(leg.points);
        let mut ladder = Vec::new();
        if leg_reached {
            for off in offsets {
                let theta = towards(off);
                let p = d1_problem.p_of(theta);
                match fixed(&d1_problem, &x, p) {
                    Ok(y) => {
                        let idx = d1_problem.indices(&y, p)?;
                        let t = Tracked {
                            x: y.clone(),
                            p,
                            index: idx,
                            arm: 0,
                        };
                        let row = maker.row(&t, RowSource::Fixed).map_err(&crit)?;
                        ladder.push((off, row.clone()));
                        rows.push(row);
                        states.push(t);
                        x = y;
                    }
                    Err(e) => {
                        notes.push(format!(
                            "towards the uniform rod: Newton at D1/D0 = {theta} failed ({e})"
                        ));
                        break;
                    }
                }
            }
        }
        if ladder.len() == offsets.len() {
            // Ladder in decreasing offset t; L̄_cr(t) is smooth in t = |1 − D1/D0| (the
            // placement of the segment is selected by a nondegenerate minimum). Quadratic
            // through the three smallest offsets; the estimate compares it with the quadratic
            // through the three largest.
            let pts: Vec<(f64, f64, f64)> = ladder
                .iter()
                .map(|(t, r)| (*t, r.lbar_cr, r.energy))
                .collect();
            let quad = |q: &[(f64, f64, f64)], pick: fn(&(f64, f64, f64)) -> f64| -> f64 {
                let mut acc = 0.0;
                for i in 0..3 {
                    let mut w = 1.0;
                    for j in 0..3 {
                        if i != j {
                            w *= (0.0 - q[j].0) / (q[i].0 - q[j].0);
                        }
                    }
                    acc += w * pick(&q[i]);
                }
                acc
            };
            let n = pts.len();
            let small = &pts[n - 3..];
            let large = &pts[..3];
            let lim = quad(small, |q| q.1);
            let lim_large = quad(large, |q| q.1);
            let energy_lim = quad(small, |q| q.2);
            let disc = ladder
                .iter()
                .map(|(_, r)| r.error_estimate)
                .fold(0.0, f64::max);
            let est = disc + (lim - lim_large).abs();
            rows.push(PhaseRow {
                value: 1.0,
                lbar_cr: lim,
                error_estimate: est,
                energy: energy_lim,
                from_branch: ladder[n - 1].1.from_branch,
                to_branch: ladder[n - 1].1.to_branch,
                index: ladder[n - 1].1.index,
                arm: 0,
                slope: ladder[n - 1].1.slope,
                source: RowSource::Limit,
            });
            uniform = Some(UniformCheck {
                lbar_cr: lim,
                error_estimate: est,
                exact: ex.lbar_uniform,
                deviation: lim - ex.lbar_uniform,
            });
            ends.push(CurveEnd {
                value: 1.0,
                kind: "limit".into(),
                reason: format!(
                    "the uniform rod D1/D0 = 1 (arclength-shift symmetry); the limit is extrapolated from |1 - D1/D0| = {}",
                    offsets
                        .iter()
                        .map(|o| format!("{o}"))
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            });
        } else {
            ends.push(leg.end);
        }
        add_at_rows(s, &d1_problem, ex, &states, &mut rows, &mut notes)?;
    } else {
        // First bring the Maxwell point to the scene's d1, then continue in the parameter.
        let p_scene = d1_problem.p_of(d1_scene);
        let leg = follow(
            &d1_problem,
            &x_seed,
            p_seed,
            p_scene,
            (p_scene.min(p_seed), p_scene.max(p_seed)),
            seed_index,
            ex,
            &mut turns,
        )?;
        if leg.end.kind != "reached" {
            return Err(crit(format!(
                "continuation in D1/D0 from {theta_seed} to the scene's {d1_scene} ended at D1/D0 = {}: {}",
                leg.end.value, leg.end.reason
            )));
        }
        let last = leg.points.last().map(|t| t.x.clone()).unwrap_or(x_seed);
        let (za, zb, _) = d1_problem.split(last.as_slice())?;
        let (ma0, mb0) = d1_problem.models_at(1.0, d1_problem.p_of(d1_scene))?;
        let problem = MaxwellProblem::new(ma0, mb0, s.param)?;
        let p0 = problem.p_of(scene_value);
        let x0 = MaxwellProblem::join(za, zb, last[last.len() - 1]);
        let x0 = fixed(&problem, &x0, p0).map_err(&crit)?;
        let idx0 = problem.indices(&x0, p0)?;
        let mut maker = RowMaker {
            main: &problem,
            ex,
            accuracy: s.accuracy,
            opts: &s.solve,
            companion: None,
        };
        let t0 = Tracked {
            x: x0.clone(),
            p: p0,
            index: idx0,
            arm: 0,
        };
        rows.push(maker.row(&t0, RowSource::Seed).map_err(&crit)?);
        states.push(t0);
        let pt = problem.p_of(s.target);
        let leg = follow(
            &problem,
            &x0,
            p0,
            pt,
            (pt.min(p0), pt.max(p0)),
            idx0,
            ex,
            &mut turns,
        )?;
        steps += leg.points.len();
        for t in &leg.points {
            rows.push(maker.row(t, RowSource::Continuation).map_err(&crit)?);
        }
        ends.push(leg.end);
        states.extend(leg.points);
        add_at_rows(s, &problem, ex, &states, &mut rows, &mut notes)?;
        notes.push(format!(
            "the mesh is graded for the scene's {} = {scene_value} and kept along the curve; \
             the error estimates measure what that costs",
            s.param
        ));
    }
    rows.sort_by(|a, b| a.value.total_cmp(&b.value));
    // A continuation point that is also a fixed row (the top of the ladder): keep one.
    let fixed_at: Vec<(f64, usize)> = rows
        .iter()
        .filter(|r| r.source == RowSource::Fixed)
        .map(|r| (r.value, r.arm))
        .collect();
    rows.retain(|r| {
        r.source != RowSource::Continuation
            || !fixed_at
                .iter()
                .any(|(v, arm)| *arm == r.arm && (v - r.value).abs() <= 1e-12 * v.abs())
    });
    Ok(PhaseCurve {
        exchange: ex,
        rows,
        ends,
        uniform,
        steps,
        cells: (cells_a, cells_b),
        turns,
        notes,
    })
}

/// A leg of continuation: its accepted points and how it ended.
struct Leg {
    points: Vec<Tracked>,
    end: CurveEnd,
}

/// Continue the Maxwell point from `(x0, p0)` towards `p_end` inside `[p_lo, p_hi]`. The
/// curve goes on through a fold where the two energy curves touch (two crossings merge: the
/// next arm is the other crossing, with the roles of the branches swapped) and stops where a
/// state loses stability, at a fold or branch point of one of the states, or where it leaves
/// the range.
#[allow(clippy::too_many_arguments)]
fn follow(
    problem: &MaxwellProblem,
    x0: &DVector<f64>,
    p0: f64,
    p_end: f64,
    (p_lo, p_hi): (f64, f64),
    index0: (usize, usize),
    ex: Exchange,
    turns: &mut Vec<String>,
) -> Result<Leg, DiagramError> {
    let theta = |p: f64| problem.theta(p);
    let name = problem.param();
    if index0 != (0, 0) {
        return Ok(Leg {
            points: Vec::new(),
            end: CurveEnd {
                value: theta(p0),
                kind: "unstable".into(),
                reason: unstable_reason(ex, index0, theta(p0)),
            },
        });
    }
    if (p_end - p0).abs() < 1e-14 {
        return Ok(Leg {
            points: Vec::new(),
            end: CurveEnd {
                value: theta(p0),
                kind: "reached".into(),
                reason: "the start is the end of the range".into(),
            },
        });
    }
    let dir = if p_end < p0 {
        Direction::Backward
    } else {
        Direction::Forward
    };
    let settings = PseudoArclength::new()
        .with_ds(0.05)
        .and_then(|st| st.with_ds_bounds(1e-6, 2.0))
        .and_then(|st| st.with_range(p_lo.min(p0) - 1e-12, p_hi.max(p0) + 1e-12))
        .and_then(|st| st.with_direction(dir))
        .and_then(|st| st.with_max_steps(400))
        .and_then(|st| st.with_tol(1e-10))
        .and_then(|st| st.with_locate_tol(1e-6))
        .and_then(|st| st.with_detect_loops(false))
        .map_err(|e| DiagramError::InvalidOptions(e.to_string()))?;
    let cont = Continuation::new(problem, settings).with_stability_fn(|x, p| {
        match problem.indices(x, p) {
            Ok((a, b)) => a + 1000 * b,
            Err(_) => usize::MAX / 2,
        }
    });
    let mut stepper = cont.start(x0, p0).map_err(|e| DiagramError::Critical {
        from_branch: ex.from_branch,
        to_branch: ex.to_branch,
        lbar: x0[x0.len() - 1],
        reason: format!("continuation could not start: {e}"),
    })?;
    let mut points: Vec<Tracked> = Vec::new();
    let mut arm = 0;
    let mut prev = (x0.clone(), p0);
    let last_p = |pts: &Vec<Tracked>| pts.last().map(|t| t.p).unwrap_or(p0);
    loop {
        let step = match stepper.step() {
            Ok(st) => st,
            Err(e) => {
                let v = theta(last_p(&points));
                return Ok(Leg {
                    points,
                    end: CurveEnd {
                        value: v,
                        kind: "failed".into(),
                        reason: format!("the continuation failed after {name} = {v}: {e}"),
                    },
                });
            }
        };
        // The first special point that ends the curve.
        for sp in &step.special {
            let lbar = sp.x[sp.x.len() - 1];
            let end = match &sp.kind {
                SpecialKind::IndexChange { old, new } if new > old => {
                    let idx = (new % 1000, new / 1000);
                    Some(CurveEnd {
                        value: theta(sp.p),
                        kind: "unstable".into(),
                        reason: unstable_reason(ex, idx, theta(sp.p)),
                    })
                }
                SpecialKind::Fold => {
                    // Which determinant changed sign across the step: a state's (it folds
                    // or branches in L̄) or only the slope of the energy difference
                    // (tangency of the two energy curves).
                    let before = problem.crossing_slope(&prev.0, prev.1).ok();
                    let after = step
                        .point
                        .as_ref()
                        .and_then(|pt| problem.crossing_slope(&pt.x, pt.p).ok());
                    match (before, after) {
                        (Some(b), Some(a)) if b.1 == a.1 && b.2 == a.2 && b.0 * a.0 < 0.0 => {
                            turns.push(format!(
                                "the crossing turns back in {name} at {:.6} (L̄ = {lbar:.6}): there the energy curves of {} and {} touch, and below it (in {name}) the two crossings merge and vanish",
                                theta(sp.p),
                                branch_word(ex.from_branch),
                                branch_word(ex.to_branch),
                            ));
                            arm += 1;
                            None
                        }
                        (b, a) => {
                            let who = match (b, a) {
                                (Some(b), Some(a)) if b.1 != a.1 && b.2 == a.2 => {
                                    format!("the state of {}", branch_word(ex.from_branch))
                                }
                                (Some(b), Some(a)) if b.1 == a.1 && b.2 != a.2 => {
                                    format!("the state of {}", branch_word(ex.to_branch))
                                }
                                _ => "one of the two states".to_string(),
                            };
                            Some(CurveEnd {
                                value: theta(sp.p),
                                kind: "fold".into(),
                                reason: format!(
                                    "the Maxwell point of {} and {} turns back in {name} at {:.6} (L̄ = {lbar:.6}) because {who} folds there: it merges with another state of its family and does not exist beyond",
                                    branch_word(ex.from_branch),
                                    branch_word(ex.to_branch),
                                    theta(sp.p),
                                ),
                            })
                        }
                    }
                }
                SpecialKind::BranchPoint => Some(CurveEnd {
                    value: theta(sp.p),
                    kind: "branch_point".into(),
                    reason: format!(
                        "a branch point of the Maxwell curve at {name} = {:.6} (L̄ = {lbar:.6}): a state meets another family (symmetry-breaking pitchfork)",
                        theta(sp.p),
                    ),
                }),
                _ => None,
            };
            if let Some(end) = end {
                return Ok(Leg { points, end });
            }
        }
        if let Some(pt) = &step.point {
            points.push(Tracked {
                x: pt.x.clone(),
                p: pt.p,
                index: pt
                    .index
                    .map(|i| (i % 1000, i / 1000))
                    .unwrap_or((usize::MAX, usize::MAX)),
                arm,
            });
            prev = (pt.x.clone(), pt.p);
        }
        if let Some(stop) = step.stop {
            let v = theta(last_p(&points));
            let (kind, reason) = match stop {
                StopReason::LeftRange { boundary } => {
                    if (boundary - p_end).abs() <= 1e-9 * p_end.abs().max(1.0) {
                        ("reached", "the end of the requested range".to_string())
                    } else {
                        (
                            "reached",
                            format!(
                                "the curve came back to {name} = {:.6} after turning (the other end of the traced range)",
                                theta(boundary)
                            ),
                        )
                    }
                }
                StopReason::StepTooSmall { ds, .. } => (
                    "failed",
                    format!("the continuation step fell below its minimum ({ds:.1e})"),
                ),
                StopReason::MaxSteps => ("failed", "the step budget (400) was used up".into()),
                other => ("failed", format!("{other:?}")),
            };
            return Ok(Leg {
                points,
                end: CurveEnd {
                    value: v,
                    kind: kind.into(),
                    reason,
                },
            });
        }
    }
}

fn unstable_reason(ex: Exchange, idx: (usize, usize), theta: f64) -> String {
    let who = match (idx.0 > 0, idx.1 > 0) {
        (true, true) => format!(
            "both states ({} and {})",
            branch_word(ex.from_branch),
            branch_word(ex.to_branch)
        ),
        (true, false) => format!("the state of {}", branch_word(ex.from_branch)),
        _ => format!("the state of {}", branch_word(ex.to_branch)),
    };
    format!(
        "{who} stops being a local minimum at {theta:.6} (indices {} and {}): a lower state of that branch family exists beyond, so this Maxwell point no longer separates the lowest branches",
        idx.0, idx.1
    )
}

/// Rows at the `--at` values inside the traced range of each arm of a curve (Newton on the
/// augmented system at exactly that `θ`, from the nearest traced state of the arm); notes
/// for the others.
fn add_at_rows(
    s: &PhaseSettings,
    problem: &MaxwellProblem,
    ex: Exchange,
    states: &[Tracked],
    rows: &mut Vec<PhaseRow>,
    notes: &mut Vec<String>,
) -> Result<(), DiagramError> {
    if s.at.is_empty() || states.is_empty() {
        return Ok(());
    }
    let arms = states.iter().map(|t| t.arm).max().unwrap_or(0);
    for &v in &s.at {
        if s.param == Param::D1 && v == 1.0 {
            notes.push("--at 1: d1 = 1 is the uniform rod; see the limit row".into());
            continue;
        }
        let p = problem.p_of(v);
        let mut found = false;
        for arm in 0..=arms {
            let on: Vec<&Tracked> = states.iter().filter(|t| t.arm == arm).collect();
            let (lo, hi) = on
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), t| {
                    (a.min(t.p), b.max(t.p))
                });
            if p < lo - 1e-12 || p > hi + 1e-12 {
                continue;
            }
            found = true;
            let near = on
                .iter()
                .min_by(|a, b| (a.p - p).abs().total_cmp(&(b.p - p).abs()))
                .expect("non-empty");
            let mut maker = RowMaker {
                main: problem,
                ex,
                accuracy: s.accuracy,
                opts: &s.solve,
                companion: None,
            };
            let row = fixed(problem, &near.x, p).and_then(|y| {
                let idx = problem.indices(&y, p).map_err(|e| e.to_string())?;
                maker.row(
                    &Tracked {
                        x: y,
                        p,
                        index: idx,
                        arm,
                    },
                    RowSource::Fixed,
                )
            });
            match row {
                Ok(r) => rows.push(r),
                Err(e) => notes.push(format!(
                    "--at {v}: Newton at fixed {} failed ({e})",
                    s.param
                )),
            }
        }
        if !found {
            let (lo, hi) = states
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), t| {
                    (a.min(t.p), b.max(t.p))
                });
            notes.push(format!(
                "--at {v}: outside the traced range {} = {:.6}..{:.6} of this curve",
                s.param,
                problem.theta(lo),
                problem.theta(hi)
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene(d1: f64) -> Stiffness {
        Stiffness::Tanh {
            d0: 1.0,
            d1,
            s0: 0.3,
            s1: 0.8,
            gamma: 200.0,
        }
    }

    fn settings(d1: f64, target: f64, at: Vec<f64>) -> PhaseSettings {
        PhaseSettings {
            radius: 1.0,
            stiffness: scene(d1),
            param: Param::D1,
            target,
            lbar_min: 1.0,
            lbar_max: 3.0,
            accuracy: Accuracy::Default,
            at,
            solve: SolveOptions::default(),
        }
    }

    /// The exact critical lengths of the uniform rod (the exact layer, Sec. 4.3).
    fn exact_crossings() -> Vec<f64> {
        let d = rodloop_exact::diagram::compute(&rodloop_exact::diagram::DiagramSettings {
            lbar_min: 1.0,
            lbar_max: 3.0,
            eta_max: 4,
            step: 0.01,
        })
        .unwrap();
        d.critical
            .iter()
            .filter(|c| c.kind == rodloop_exact::diagram::CriticalKind::Crossing)
            .map(|c| c.lbar_cr)
            .collect()
    }

    #[test]
    fn maxwell_points_approach_the_uniform_critical_lengths() {
        let d = trace_phase(&settings(0.9, 0.9, vec![])).unwrap();
        let exact = exact_crossings();
        assert_eq!(d.curves.len(), 2);
        for (c, ex) in d.curves.iter().zip(&exact) {
            let u = c.uniform.expect("limit row");
            assert!((u.exact - ex).abs() < 1e-12);
            assert!(
                u.deviation.abs() <= 2.0 * u.error_estimate,
                "limit {} vs exact {ex}: deviation {:.2e}, estimate {:.2e}",
                u.lbar_cr,
                u.deviation,
                u.error_estimate
            );
            // The ladder 1 − t, t = 8e-3 … 1e-3: each within its estimate plus a term that
            // vanishes with t, and closer to the limit as t decreases.
            let ladder: Vec<&PhaseRow> = c
                .rows
                .iter()
                .filter(|r| r.source == RowSource::Fixed && r.value > 0.99)
                .collect();
            assert_eq!(ladder.len(), 4);
            let mut last = f64::INFINITY;
            for r in ladder {
                let t = 1.0 - r.value;
                assert!((r.lbar_cr - ex).abs() <= 2.0 * r.error_estimate + 0.05 * t);
                let to_limit = (r.lbar_cr - u.lbar_cr).abs();
                assert!(to_limit < last, "not approaching at t = {t}");
                last = to_limit;
            }
        }
    }

    #[test]
    fn at_rows_agree_with_an_independent_secant_solve() {
        let theta = 0.7;
        let d = trace_phase(&settings(0.9, 0.65, vec![theta])).unwrap();
        for c in &d.curves {
            let row = c
                .rows
                .iter()
                .find(|r| r.source == RowSource::Fixed && r.value == theta)
                .expect("an --at row");
            // Independent: the lowest stable states at θ from shifted exact loops, then the
            // secant method on re-solved equilibria.
            let st = scene(theta);
            let (ea, eb) = (
                eta_of_branch(c.exchange.from_branch),
                eta_of_branch(c.exchange.to_branch),
            );
            let opts = SolveOptions::default();
            let a = lowest_placement(1.0, row.lbar_cr, ea, c.cells.0, &st, &opts).unwrap();
            let b = lowest_placement(1.0, row.lbar_cr, eb, c.cells.1, &st, &opts).unwrap();
            let (ma, _, slope) = maxwell_by_secant(&a, &b, &opts).unwrap();
            assert!(slope > 0.0);
            assert!(
                (ma.lbar() - row.lbar_cr).abs() < 1e-9,
                "--at row {} vs secant {}",
                row.lbar_cr,
                ma.lbar()
            );
            assert!((ma.energy().total - row.energy).abs() < 1e-9);
        }
    }

    #[test]
    fn bad_input_gives_clear_errors() {
        let msg = |s: PhaseSettings| trace_phase(&s).unwrap_err().to_string();
        assert!(msg(settings(0.5, 2.0, vec![])).contains("crosses the uniform rod"));
        assert!(msg(settings(0.5, -1.0, vec![])).contains("invalid"));
        assert!(msg(settings(0.5, 0.1, vec![-0.3])).contains("--at"));
        let mut s = settings(0.5, 0.1, vec![]);
        s.stiffness = Stiffness::uniform(1.0);
        assert!(msg(s).contains("two-segment"));
        let mut s = settings(0.5, 0.1, vec![]);
        s.param = Param::Lbar;
        assert!(msg(s).contains("lbar"));
    }
}
