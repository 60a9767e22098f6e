//! The branch diagram of homogeneous loops enclosed in the ball, `|r| ≤ R` (paper Sec. 3.2;
//! issue 9): every paper branch traced through its attached and lifted-off parts, branch 0
//! (the free planar circle) below `L̄ = 1`, the lift-off and landing events, the exchanges
//! of the lowest branch with error estimates, and the Hessian index on the tangent space of
//! the active constraints.
//!
//! # Route: a natural-parameter tracer with re-solves, not the `Confinement` seam
//!
//! * **Attached parts need no continuation.** While the surface loop of a uniform rod has
//!   `λ ≥ 0` everywhere, it meets every enclosed KKT condition (stationarity is the surface
//!   equations, the wall pushes, the gap is zero), so it *is* the enclosed equilibrium, and
//!   the exact layer gives it in closed form with its contact force (Eq. (38),
//!   `λ_min R³/D = c²(1 − 2k²)`). Its energy carries no discretisation error.
//! * **Events are roots of the exact layer.** A branch lifts off or lands where `λ_min`
//!   crosses zero, i.e. where `k²(L̄) = 1/2` ([`detached_intervals`], bisection to `1e-13`).
//!   That is the event "λ crosses 0 on the contact set" without a discrete event function,
//!   and more accurate than locating it on a discrete trace. The tests check it
//!   independently with the 3-D model on both sides of each event.
//! * **Only lifted-off parts use the 3-D model**, traced in `L̄` by natural-parameter steps
//!   with warm starts ([`EnclosedState::step_to`]) at three resolutions `N/4, N/2, N` (for
//!   the energy and its error estimate). The semismooth Newton picks the contact set anew
//!   at every step, so contact ends that move between nodes need no bookkeeping; with a
//!   fixed active set behind the `Confinement` seam, every node a contact end passes would be
//!   an event and a restart. `L̄` is a good parameter on the lifted-off parts of the paper's
//!   branches (no folds: a fold would show as Newton failing under step halving, which is
//!   reported as a warning and ends the trace there).
//! * **Exchanges** come from the exact layer's list (the surface diagram): an exchange
//!   between two attached states is the surface one, exactly. Where a branch of an exchange
//!   has lifted off, `E_a(L̄) = E_b(L̄)` is solved again by the secant method on re-solved
//!   states (3-D model at `N/4, N/2, N` to locate it, then at `N/2, N, 2N` from there;
//!   warm-started from the trace), with the error
//!   estimate `(δE_a + δE_b)/|d(E_a − E_b)/dL̄| +` the last secant step. The enclosed
//!   energy never exceeds the surface one, and below `L̄ = 1` the circle is the lowest
//!   closed curve of its length, so no exchange outside that list appears; the sampled
//!   energies are checked for one anyway (a warning if found).
//!
//! Non-uniform rods are refused: there is no exact layer (every part would need the 3-D
//! model, and the two-segment scene's loops lift off everywhere checked), the 3-D Newton
//! reaches their lifted-off states only through the pull homotopy and not at every length,
//! and their branches come as families (shifted seeds, mirror pairs) that this tracer does
//! not follow.

#![allow(clippy::needless_range_loop)]

use std::time::Instant;

use rodloop_exact::diagram::{compute, Critical, CriticalKind, DiagramSettings};
use rodloop_exact::{branch_of_eta, eta_of_branch, paper_branch_loop, ExactLoop};
use rodloop_solver::enclosed::{
    detached_intervals, enclosed_cells, solve_branch, solve_enclosed, start_from_surface,
    three_level_estimate, EnclosedOptions, EnclosedState, SurfaceSource, LIFTED_OFF_MAX_ORDER,
};
use rodloop_solver::{Accuracy, SolverError, Stiffness};
use serde::Serialize;

use crate::labels::Label;
use crate::parallel::run_parallel;
use crate::DiagramError;

/// Gap (units of `R`) below which a node touches the wall.
pub const TOUCH: f64 = 1e-9;

/// What to compute.
#[derive(Clone, Debug)]
pub struct EnclosedDiagramOptions {
    /// Ball radius.
    pub radius: f64,
    /// Stiffness (uniform only).
    pub stiffness: Stiffness,
    /// Smallest `L̄`.
    pub lbar_min: f64,
    /// Largest `L̄`.
    pub lbar_max: f64,
    /// Accuracy level: cells of the lifted-off parts `32(1+η)` at default (`16`, `64` per
    /// period for fast, high) and twice that for the finest level and the exchanges.
    pub accuracy: Accuracy,
    /// Spacing of the sampled lengths (default 0.05).
    pub step: f64,
    /// Only these branches (`None`: all that meet the range).
    pub branches: Option<Vec<u32>>,
}

impl EnclosedDiagramOptions {
    /// Defaults for the range `[lbar_min, lbar_max]` of a uniform rod of stiffness `d`.
    pub fn new(radius: f64, stiffness: Stiffness, lbar_min: f64, lbar_max: f64) -> Self {
        Self {
            radius,
            stiffness,
            lbar_min,
            lbar_max,
            accuracy: Accuracy::Default,
            step: 0.05,
            branches: None,
        }
    }

    fn validate(&self) -> Result<(), DiagramError> {
        let bad = |m: String| Err(DiagramError::InvalidOptions(m));
        if !(self.radius.is_finite() && self.radius > 0.0) {
            return bad(format!("radius must be positive (got {})", self.radius));
        }
        if !(self.lbar_min.is_finite()
            && self.lbar_max.is_finite()
            && self.lbar_min > 0.0
            && self.lbar_max > self.lbar_min
            && self.lbar_max <= 20.0)
        {
            return bad(format!(
                "need 0 < lbar_min < lbar_max <= 20 (got {} and {})",
                self.lbar_min, self.lbar_max
            ));
        }
        if !(self.step.is_finite() && self.step >= 1e-3 && self.step <= 0.5) {
            return bad(format!(
                "the sample spacing must lie in [0.001, 0.5] (got {})",
                self.step
            ));
        }
        if !self.stiffness.is_uniform() {
            return bad("the enclosed diagram covers uniform rods only: a non-uniform rod has no exact layer, its branches come as families that this tracer does not follow, and the 3-D Newton reaches its lifted-off states only through the pull homotopy and not at every length (use `rodloop solve` for single states)".into());
        }
        Ok(())
    }
}

/// How a point of the diagram was obtained.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum PointSource {
    /// The free planar circle, `E R/(πD) = 1/L̄` (branch 0).
    Circle,
    /// The exact surface loop, attached (`λ_min ≥ 0`).
    Exact,
    /// The 3-D enclosed model (lifted off).
    Model,
}

/// One state of the enclosed diagram.
#[derive(Clone, Debug, Serialize)]
pub struct EnclosedPoint {
    /// Paper branch (0: the circle).
    pub branch: u32,
    /// Periods `η` of `κ_g` (0 for the circle).
    pub eta: u32,
    /// `L̄`.
    pub lbar: f64,
    /// Energy `E R/(π D)`.
    pub energy: f64,
    /// Its error estimate.
    pub energy_error: f64,
    /// Fully on the wall.
    pub attached: bool,
    /// Length fraction touching the wall.
    pub contact_fraction: f64,
    /// Number of contact intervals.
    pub contact_intervals: usize,
    /// Largest gap `(R − |r|)/R`.
    pub max_gap: f64,
    /// Smallest contact force `λ R³/D` over all nodes (≥ 0 at an equilibrium).
    pub lambda_min: f64,
    /// Smallest gap `/R` (≥ 0).
    pub gap_min: f64,
    /// Largest `|λ · gap|` (0).
    pub complementarity: f64,
    /// Stationarity residual of the 3-D model (0 for exact states).
    pub stationarity: f64,
    /// Hessian index on the tangent space of the active constraints.
    pub index: usize,
    /// Stability label.
    pub label: Label,
    /// The lowest state at this length.
    pub lowest: bool,
    /// Cells of the reported 3-D state (0 for exact states).
    pub cells: usize,
    /// Where the state comes from.
    pub source: PointSource,
}

/// Kind of an event on a branch.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum EventKind {
    /// Attached below, lifted off above (increasing `L̄`).
    LiftOff,
    /// Lifted off below, attached above.
    Landing,
}

impl EventKind {
    /// `"lift-off"` or `"landing"`.
    pub fn as_str(self) -> &'static str {
        match self {
            EventKind::LiftOff => "lift-off",
            EventKind::Landing => "landing",
        }
    }
}

/// A lift-off or landing event (a special point).
#[derive(Clone, Debug, Serialize)]
pub struct EnclosedEvent {
    /// Kind.
    pub kind: EventKind,
    /// Branch.
    pub branch: u32,
    /// `L̄` of the event (`k² = 1/2`, `λ_min = 0`).
    pub lbar: f64,
    /// Its error estimate.
    pub error_estimate: f64,
    /// Energy at the event (exact layer).
    pub energy: f64,
    /// Index just below and just above.
    pub index_before: usize,
    /// Index just above.
    pub index_after: usize,
}

/// An exchange (or collapse) of the lowest branch: the surface diagram's record with the
/// enclosed value (index `i` of `L̄_icr` as in the surface diagram, counted from
/// `L̄_1cr = 1`).
#[derive(Clone, Debug, Serialize)]
pub struct EnclosedCritical {
    /// The critical length, its kind, branches, energy and error estimate.
    #[serde(flatten)]
    pub critical: Critical,
    /// The surface diagram's value (exact layer).
    pub surface_lbar_cr: f64,
    /// How it was obtained.
    pub method: String,
}

/// The enclosed diagram.
#[derive(Clone, Debug, Serialize)]
pub struct EnclosedDiagram {
    /// States, by branch then `L̄`.
    pub points: Vec<EnclosedPoint>,
    /// Lift-off and landing events.
    pub events: Vec<EnclosedEvent>,
    /// Critical lengths of the lowest branch.
    pub critical: Vec<EnclosedCritical>,
    /// Things the caller should print.
    pub warnings: Vec<String>,
    /// Cells of the lifted-off trace (`N` of `N/4, N/2, N`) per branch.
    pub cells: Vec<(u32, usize)>,
    /// Wall-clock seconds: total, attached samples (index checks), lifted-off traces,
    /// critical lengths.
    pub seconds: EnclosedTimings,
}

/// Wall-clock seconds of the parts of [`enclosed_diagram`].
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct EnclosedTimings {
    /// Everything.
    pub total: f64,
    /// Attached samples (exact layer, index from the 3-D model), summed over the branch
    /// threads.
    pub attached: f64,
    /// Lifted-off traces, summed over the branch threads.
    pub lifted_off: f64,
    /// Critical lengths.
    pub critical: f64,
}

/// A traced lifted-off state at three resolutions `N/4, N/2, N`.
#[derive(Clone, Debug)]
struct Levels {
    lbar: f64,
    states: [EnclosedState; 3],
}

impl Levels {
    fn energy(&self) -> (f64, f64) {
        let e = [
            self.states[0].energy(),
            self.states[1].energy(),
            self.states[2].energy(),
        ];
        let max_order = match self.states[2].contact(TOUCH) {
            Ok(c) if c.fraction >= 1.0 => 4.0,
            _ => LIFTED_OFF_MAX_ORDER,
        };
        let (err, _) = three_level_estimate(e[0], e[1], e[2], max_order);
        (e[2], err)
    }

    fn step_to(&self, lbar: f64, opts: &EnclosedOptions) -> Result<Levels, SolverError> {
        let mut out = Vec::with_capacity(3);
        for s in &self.states {
            out.push(s.step_to(lbar, opts)?);
        }
        let [a, b, c]: [EnclosedState; 3] = out.try_into().expect("three levels");
        Ok(Levels {
            lbar,
            states: [a, b, c],
        })
    }

    /// The same length at twice the cells (each level prolonged and re-solved).
    fn refine(&self, opts: &EnclosedOptions) -> Result<Levels, SolverError> {
        let mut out = Vec::with_capacity(3);
        for s in &self.states {
            let (m, z) = s.refine()?;
            out.push(solve_enclosed(&m, z, opts)?);
        }
        let [a, b, c]: [EnclosedState; 3] = out.try_into().expect("three levels");
        Ok(Levels {
            lbar: self.lbar,
            states: [a, b, c],
        })
    }

    fn point(&self, branch: u32, eta: u32) -> Result<EnclosedPoint, SolverError> {
        let fine = &self.states[2];
        let (energy, energy_error) = self.energy();
        let c = fine.contact(TOUCH)?;
        let (lmin, gmin, comp, stat) = fine.optimality()?;
        let (index, _) = self.states[1].stability(1e-6)?;
        Ok(EnclosedPoint {
            branch,
            eta,
            lbar: self.lbar,
            energy,
            energy_error,
            attached: c.fraction >= 1.0,
            contact_fraction: c.fraction,
            contact_intervals: c.intervals,
            max_gap: c.max_gap.0,
            lambda_min: lmin,
            gap_min: gmin,
            complementarity: comp,
            stationarity: stat,
            index,
            label: Label::Unstable,
            lowest: false,
            cells: fine.model.cells(),
            source: PointSource::Model,
        })
    }
}

fn exact(eta: u32, lbar: f64) -> Result<ExactLoop, SolverError> {
    Ok(paper_branch_loop(eta, lbar)?)
}

/// Index of an attached loop: the 3-D model re-solved from the exact loop at half the
/// fast resolution (`8(1+η)` cells, at least 16), stability on the tangent space of the
/// closure, gauges and the (strictly active) wall. (On `[1, 3]` the indices at 48 and 24
/// cells for `η = 2` agree at every sample; the coarser one costs a fifth.)
fn attached_index(radius: f64, stiffness: &Stiffness, l: &ExactLoop) -> Result<usize, SolverError> {
    let n = (enclosed_cells(Accuracy::Fast, l.eta) / 2).max(16);
    let len = l.length();
    let (model, z0) = start_from_surface(radius, l.lbar, n, stiffness, |s| {
        l.point(s * len)
            .map(|p| p.kappa_g / radius)
            .unwrap_or(f64::NAN)
    })?;
    let st = solve_enclosed(&model, z0, &EnclosedOptions::default())?;
    Ok(st.stability(1e-6)?.0)
}

fn exact_point(
    radius: f64,
    stiffness: &Stiffness,
    l: &ExactLoop,
    branch: u32,
) -> Result<EnclosedPoint, SolverError> {
    let lmin = l.lambda_range().0;
    Ok(EnclosedPoint {
        branch,
        eta: l.eta,
        lbar: l.lbar,
        energy: l.energy()?,
        energy_error: 1e-14 * l.energy()?.abs().max(1.0),
        attached: true,
        contact_fraction: 1.0,
        contact_intervals: 1,
        max_gap: 0.0,
        lambda_min: lmin,
        gap_min: 0.0,
        complementarity: 0.0,
        stationarity: 0.0,
        index: attached_index(radius, stiffness, l)?,
        label: Label::Unstable,
        lowest: false,
        cells: 0,
        source: PointSource::Exact,
    })
}

fn circle_point(lbar: f64) -> EnclosedPoint {
    let touch = (lbar - 1.0).abs() < 1e-12;
    EnclosedPoint {
        branch: 0,
        eta: 0,
        lbar,
        energy: 1.0 / lbar,
        energy_error: 0.0,
        attached: touch,
        contact_fraction: if touch { 1.0 } else { 0.0 },
        contact_intervals: usize::from(touch),
        max_gap: (1.0 - lbar).max(0.0),
        lambda_min: 0.0,
        gap_min: (1.0 - lbar).max(0.0),
        complementarity: 0.0,
        stationarity: 0.0,
        // The circle is the global minimum of ∫κ² among closed curves of its length.
        index: 0,
        label: Label::Unstable,
        lowest: false,
        cells: 0,
        source: PointSource::Circle,
    }
}

/// Sample lengths in `(a, b)` on the grid `lbar_min + k·step`, plus the ends when they lie
/// in the window (`incl_a`, `incl_b`).
fn grid(opts: &EnclosedDiagramOptions, a: f64, b: f64) -> Vec<f64> {
    let (lo, h) = (opts.lbar_min, opts.step);
    let k0 = ((a - lo) / h).floor().max(0.0) as i64;
    let k1 = ((b - lo) / h).ceil() as i64;
    (k0..=k1)
        .map(|k| lo + k as f64 * h)
        .filter(|&x| x > a + 1e-9 && x < b - 1e-9 && x <= opts.lbar_max + 1e-12)
        .collect()
}

/// Trace a lifted-off interval `(a, b)` of branch `eta` at the sample lengths `xs`: seed in
/// the middle from the surface loop, then natural-parameter steps both ways (halving a
/// failed step up to 6 times).
fn trace_detached(
    opts: &EnclosedDiagramOptions,
    eta: u32,
    xs: &[f64],
    warnings: &mut Vec<String>,
) -> Result<Vec<Levels>, DiagramError> {
    if xs.is_empty() {
        return Ok(Vec::new());
    }
    let n = enclosed_cells(opts.accuracy, eta);
    let sopts = EnclosedOptions::default();
    let mid = xs.len() / 2;
    let seed_at = xs[mid];
    let l = exact(eta, seed_at)?;
    let seed = solve_branch(
        opts.radius,
        seed_at,
        &opts.stiffness,
        &SurfaceSource::Exact(l),
        n,
        &sopts,
    )
    .map_err(|source| DiagramError::Seed {
        eta,
        lbar: seed_at,
        source,
    })?;
    let first = Levels {
        lbar: seed_at,
        states: [seed.quarter, seed.coarse, seed.fine],
    };
    let mut up = vec![first.clone()];
    let mut down = vec![first];
    for (dir, out) in [(1i64, &mut up), (-1i64, &mut down)] {
        let targets: Vec<f64> = if dir > 0 {
            xs[mid + 1..].to_vec()
        } else {
            xs[..mid].iter().rev().copied().collect()
        };
        'targets: for &x in &targets {
            let mut cur = out.last().expect("seed").clone();
            let mut h = x - cur.lbar;
            let mut halvings = 0;
            while (x - cur.lbar).abs() > 1e-14 {
                let to = if (x - cur.lbar).abs() <= h.abs() * (1.0 + 1e-9) {
                    x
                } else {
                    cur.lbar + h
                };
                match cur.step_to(to, &sopts) {
                    Ok(next) => cur = next,
                    Err(e) => {
                        halvings += 1;
                        if halvings > 6 {
                            let c = cur.states[2].contact(TOUCH).ok();
                            warnings.push(format!(
                                "branch {} (eta = {eta}): the lifted-off trace stops at lbar = {:.6} ({e}); the last state touches the wall on {:.1}% of its length with contact forces in [{:.3e}, {:.3e}]; Newton failed under 6 step halvings (perhaps a fold or a bifurcation of the lifted-off branch; not traced further)",
                                branch_of_eta(eta),
                                cur.lbar,
                                100.0 * c.as_ref().map_or(f64::NAN, |c| c.fraction),
                                c.as_ref().map_or(f64::NAN, |c| c.lambda_range.0),
                                c.as_ref().map_or(f64::NAN, |c| c.lambda_range.1),
                            ));
                            break 'targets;
                        }
                        h *= 0.5;
                    }
                }
            }
            out.push(cur);
        }
    }
    down.remove(0);
    down.reverse();
    down.extend(up);
    Ok(down)
}

/// Is the surface loop of `eta` at `lbar` lifted off (`λ_min < 0`)?
fn detached_at(eta: u32, lbar: f64) -> Result<bool, SolverError> {
    Ok(exact(eta, lbar)?.lambda_range().0 < 0.0)
}

/// Energy of branch `eta` at `lbar` with its error: the exact loop where attached,
/// otherwise the 3-D model warm-started from `track` (updated).
fn branch_energy(
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

/// Secant iteration on `f(x) = 0` from `xa` and `xb` until the step is below `1e-12`;
/// returns `(x, f', last step, f's error, mean energy)`.
fn secant<F>(mut f: F, mut xa: f64, mut xb: f64) -> Result<(f64, f64, f64, f64, f64), SolverError>
where
    F: FnMut(f64) -> Result<(f64, f64, f64), SolverError>,
{
    let (mut fa, _, _) = f(xa)?;
    let (mut fb, mut err, mut e) = f(xb)?;
    for _ in 0..30 {
        let slope = (fb - fa) / (xb - xa);
        if fb == 0.0 || !slope.is_finite() || slope == 0.0 {
            return Ok((xb, slope, (xb - xa).abs(), err, e));
        }
        let xn = xb - fb / slope;
        let (fnew, errn, en) = f(xn)?;
        let step = (xn - xb).abs();
        (xa, fa, xb, fb, err, e) = (xb, fb, xn, fnew, errn, en);
        if step < 1e-12 {
            return Ok((xn, slope, step, err, e));
        }
    }
    Err(SolverError::InvalidInput(
        "the secant iteration did not converge in 30 steps".into(),
    ))
}

/// Solve `E_a = E_b` near `x0` (see the module docs): a secant iteration with the
/// lifted-off states at the trace's levels `N/4, N/2, N`, then, from its root, the same at
/// `N/2, N, 2N` (first step with the coarse slope). Returns `(L̄_cr, error, energy)`.
fn enclosed_crossing(
    eta_a: u32,
    eta_b: u32,
    x0: f64,
    tracks: &mut [Option<Levels>; 2],
) -> Result<(f64, f64, f64), SolverError> {
    let f = |x: f64, tr: &mut [Option<Levels>; 2]| -> Result<(f64, f64, f64), SolverError> {
        let (ea, da) = branch_energy(eta_a, x, &mut tr[0])?;
        let (eb, db) = branch_energy(eta_b, x, &mut tr[1])?;
        Ok((ea - eb, da + db, 0.5 * (ea + eb)))
    };
    let (xc, slope, _, _, _) = secant(|x| f(x, tracks), x0, x0 - 1e-3)?;
    let sopts = EnclosedOptions::default();
    let mut fine: [Option<Levels>; 2] = [None, None];
    for k in 0..2 {
        if let Some(t) = &tracks[k] {
            // Bring the track to the coarse root first, then double its cells.
            let at = t.step_to(xc, &sopts)?;
            fine[k] = Some(at.refine(&sopts)?);
        }
    }
    let (fc, _, _) = f(xc, &mut fine)?;
    let x1 = if fc == 0.0 {
        xc - 1e-9
    } else {
        xc - fc / slope
    };
    let (x, slope, step, err, e) = secant(|x| f(x, &mut fine), xc, x1)?;
    Ok((x, err / slope.abs().max(1e-300) + step, e))
}

/// One branch's share of the diagram.
#[derive(Default)]
struct BranchOut {
    points: Vec<EnclosedPoint>,
    events: Vec<EnclosedEvent>,
    levels: Vec<Levels>,
    warnings: Vec<String>,
    attached_s: f64,
    lifted_s: f64,
}

/// Sample branch `eta` on the window: attached samples from the exact layer, events at the
/// ends of its lifted-off intervals, the lifted-off parts traced with the 3-D model.
fn trace_branch(opts: &EnclosedDiagramOptions, eta: u32) -> Result<BranchOut, DiagramError> {
    let (lo, hi) = (opts.lbar_min, opts.lbar_max);
    let r = opts.radius;
    let mut out = BranchOut::default();
    let branch = branch_of_eta(eta);
    let e = f64::from(eta);
    let pad = 1e-4;
    let (a, b) = ((e - 1.0 + pad).max(lo), (e + 1.0 - pad).min(hi));
    let det = detached_intervals(eta, a, b)?;
    let mut branch_points = Vec::new();
    // Attached samples.
    // The grid, plus the ends (the window's, or `1e-4` inside the branch's range).
    let mut xs = grid(opts, a - 1e-9, b + 1e-9);
    if xs.first().is_none_or(|&x| x > a + 1e-9) {
        xs.insert(0, a);
    }
    if xs.last().is_none_or(|&x| x < b - 1e-9) {
        xs.push(b);
    }
    let inside = |x: f64| det.iter().any(|&(p, q)| x > p - 1e-12 && x < q + 1e-12);
    let ta = Instant::now();
    for &x in xs.iter().filter(|&&x| !inside(x)) {
        branch_points.push(exact_point(r, &opts.stiffness, &exact(eta, x)?, branch)?);
    }
    out.attached_s += ta.elapsed().as_secs_f64();
    // Events and lifted-off parts.
    for &(p, q) in &det {
        for (x, kind) in [(p, EventKind::LiftOff), (q, EventKind::Landing)] {
            let interior = x > a + 1e-9 && x < b - 1e-9;
            if interior {
                let l = exact(eta, x)?;
                let mut pt = exact_point(r, &opts.stiffness, &l, branch)?;
                pt.lambda_min = pt.lambda_min.max(0.0);
                out.events.push(EnclosedEvent {
                    kind,
                    branch,
                    lbar: x,
                    // Bisection width of `detached_intervals` plus the exact layer's
                    // round-off in `k²(L̄)`.
                    error_estimate: 1e-12,
                    energy: pt.energy,
                    index_before: 0,
                    index_after: 0,
                });
                branch_points.push(pt);
            }
        }
        let mut ys: Vec<f64> = xs.iter().copied().filter(|&x| x > p && x < q).collect();
        if ys.is_empty() {
            ys.push(0.5 * (p + q));
        }
        let td = Instant::now();
        let tr = trace_detached(opts, eta, &ys, &mut out.warnings)?;
        out.lifted_s += td.elapsed().as_secs_f64();
        for lv in &tr {
            branch_points.push(lv.point(branch, eta)?);
        }
        out.levels.extend(tr);
    }
    branch_points.sort_by(|u, v| u.lbar.total_cmp(&v.lbar));
    // Index before/after each event from the neighbouring samples.
    for ev in out.events.iter_mut() {
        let before = branch_points.iter().rev().find(|p| p.lbar < ev.lbar - 1e-9);
        let after = branch_points.iter().find(|p| p.lbar > ev.lbar + 1e-9);
        ev.index_before = before.map_or(0, |p| p.index);
        ev.index_after = after.map_or(0, |p| p.index);
    }
    out.points = branch_points;
    Ok(out)
}

/// Compute the enclosed diagram (see the module docs).
pub fn enclosed_diagram(opts: &EnclosedDiagramOptions) -> Result<EnclosedDiagram, DiagramError> {
    opts.validate()?;
    let t0 = Instant::now();
    let (lo, hi) = (opts.lbar_min, opts.lbar_max);
    let mut warnings = Vec::new();
    let mut points: Vec<EnclosedPoint> = Vec::new();
    let mut events: Vec<EnclosedEvent> = Vec::new();
    let mut cells = Vec::new();
    let mut timings = EnclosedTimings::default();
    let top = hi.ceil() as u32 + 1;
    let mut etas: Vec<u32> = (1..=top)
        .filter(|&e| f64::from(e) - 1.0 < hi && f64::from(e) + 1.0 > lo)
        .collect();
    let wanted = |b: u32| opts.branches.as_ref().is_none_or(|s| s.contains(&b));
    etas.retain(|&e| wanted(branch_of_eta(e)));
    if lo <= 1.0 && wanted(0) {
        let mut xs = grid(opts, lo - opts.step, 1.0 + 1e-12);
        xs.retain(|&x| x >= lo - 1e-12);
        if !xs.iter().any(|&x| (x - 1.0).abs() < 1e-12) {
            xs.push(1.0);
        }
        points.extend(xs.into_iter().map(circle_point));
    }
    // Branches in parallel on the crate's pool (the lifted-off traces dominate: branch 2
    // first).
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut order: Vec<u32> = etas.clone();
    order.sort_by_key(|&e| u32::from(e != 1));
    let outs = run_parallel(
        threads,
        order.clone(),
        &mut |_| {},
        &mut |_: &Result<BranchOut, DiagramError>| {},
        |eta, _| trace_branch(opts, eta),
    );
    let mut outs: Vec<(u32, Result<BranchOut, DiagramError>)> =
        order.into_iter().zip(outs).collect();
    outs.sort_by_key(|(e, _)| *e);
    let mut traced: Vec<(u32, Vec<Levels>)> = Vec::new();
    for (eta, o) in outs {
        let o = o?;
        points.extend(o.points);
        events.extend(o.events);
        warnings.extend(o.warnings);
        timings.attached += o.attached_s;
        timings.lifted_off += o.lifted_s;
        cells.push((branch_of_eta(eta), enclosed_cells(opts.accuracy, eta)));
        traced.push((eta, o.levels));
    }
    events.sort_by(|u, v| u.lbar.total_cmp(&v.lbar));

    // Critical lengths: the surface list, re-solved where a branch has lifted off.
    let tc = Instant::now();
    let eta_max = etas.iter().copied().max().unwrap_or(1).max(1);
    let surface = compute(&DiagramSettings {
        lbar_min: lo.min(1.0),
        lbar_max: hi,
        eta_max,
        step: 0.01,
    })
    .map_err(SolverError::from)?;
    let mut critical = Vec::new();
    for c in surface.critical.iter().filter(|c| {
        c.lbar_cr >= lo - 1e-12
            && c.lbar_cr <= hi + 1e-12
            && wanted(c.from_branch)
            && wanted(c.to_branch)
    }) {
        let involved = [c.from_branch, c.to_branch];
        let mut lifted = false;
        for &bch in &involved {
            if bch == 0 {
                continue;
            }
            let eta = eta_of_branch(bch);
            let e = f64::from(eta);
            let x = c.lbar_cr.clamp(e - 1.0 + 1e-6, e + 1.0 - 1e-6);
            lifted |= detached_at(eta, x)?;
        }
        if !lifted {
            critical.push(EnclosedCritical {
                critical: *c,
                surface_lbar_cr: c.lbar_cr,
                method: "exact layer: both states attached, so the surface value holds".into(),
            });
            continue;
        }
        if c.kind != CriticalKind::Crossing {
            warnings.push(format!(
                "the {} of branches {} -> {} at lbar = {} involves a lifted-off state; not re-solved",
                c.kind, c.from_branch, c.to_branch, c.lbar_cr
            ));
            continue;
        }
        let etas2 = [eta_of_branch(c.from_branch), eta_of_branch(c.to_branch)];
        let nearest = |eta: u32| -> Option<Levels> {
            traced.iter().find(|(e, _)| *e == eta).and_then(|(_, lv)| {
                lv.iter()
                    .min_by(|u, v| {
                        (u.lbar - c.lbar_cr)
                            .abs()
                            .total_cmp(&(v.lbar - c.lbar_cr).abs())
                    })
                    .cloned()
            })
        };
        let mut tracks = [nearest(etas2[0]), nearest(etas2[1])];
        let (x, err, energy) = enclosed_crossing(etas2[0], etas2[1], c.lbar_cr, &mut tracks)
            .map_err(|e| DiagramError::Critical {
                from_branch: c.from_branch,
                to_branch: c.to_branch,
                lbar: c.lbar_cr,
                reason: e.to_string(),
            })?;
        let n = etas2
            .iter()
            .zip(&tracks)
            .filter(|(_, t)| t.is_some())
            .map(|(&e, _)| 2 * enclosed_cells(opts.accuracy, e))
            .max()
            .unwrap_or(0);
        critical.push(EnclosedCritical {
            critical: Critical {
                lbar_cr: x,
                energy,
                error_estimate: err,
                ..*c
            },
            surface_lbar_cr: c.lbar_cr,
            method: format!(
                "secant on E_a = E_b with the lifted-off state re-solved (3-D model at N = {}, {}, {}; error from the three levels and the last secant step)",
                n / 4,
                n / 2,
                n
            ),
        });
    }

    timings.critical = tc.elapsed().as_secs_f64();
    label(&mut points, &critical, &mut warnings);
    timings.total = t0.elapsed().as_secs_f64();
    Ok(EnclosedDiagram {
        points,
        events,
        critical,
        warnings,
        cells,
        seconds: timings,
    })
}

/// The lowest branch at `lbar`: the branch the last critical length at or below `lbar`
/// hands over to (the first one's `from` branch below it).
fn lowest_branch(critical: &[EnclosedCritical], lbar: f64) -> Option<u32> {
    let k = critical.partition_point(|c| c.critical.lbar_cr <= lbar + 1e-12);
    if k > 0 {
        Some(critical[k - 1].critical.to_branch)
    } else {
        critical.first().map(|c| c.critical.from_branch)
    }
}

/// Energy of `branch` at `lbar` interpolated linearly between its samples.
fn interpolated(points: &[EnclosedPoint], branch: u32, lbar: f64) -> Option<f64> {
    let pts: Vec<&EnclosedPoint> = points.iter().filter(|p| p.branch == branch).collect();
    let k = pts.partition_point(|p| p.lbar < lbar);
    if k == 0 || k == pts.len() {
        return pts
            .iter()
            .find(|p| (p.lbar - lbar).abs() < 1e-12)
            .map(|p| p.energy);
    }
    let (a, b) = (pts[k - 1], pts[k]);
    let t = (lbar - a.lbar) / (b.lbar - a.lbar);
    Some(a.energy + t * (b.energy - a.energy))
}

/// Lowest flags and labels; a warning where a sampled state lies below the lowest branch
/// by more than the errors (an exchange the list does not have).
fn label(points: &mut [EnclosedPoint], critical: &[EnclosedCritical], warnings: &mut Vec<String>) {
    let snapshot = points.to_vec();
    for p in points.iter_mut() {
        let lowest = match lowest_branch(critical, p.lbar) {
            Some(b) => b == p.branch,
            None => snapshot
                .iter()
                .filter(|q| q.branch != p.branch)
                .all(|q| interpolated(&snapshot, q.branch, p.lbar).is_none_or(|e| p.energy <= e)),
        };
        p.lowest = lowest;
        p.label = match (p.index, lowest) {
            (0, true) => Label::Stable,
            (0, false) => Label::Metastable,
            _ => Label::Unstable,
        };
    }
    for p in points.iter() {
        // Linear interpolation between samples errs by ~E''h²/8; skip the neighbourhood
        // of the located critical lengths and allow 1e-3.
        if p.lowest
            || critical
                .iter()
                .any(|c| (c.critical.lbar_cr - p.lbar).abs() < 0.05)
        {
            continue;
        }
        if let Some(b) = lowest_branch(critical, p.lbar) {
            if let Some(e) = interpolated(&snapshot, b, p.lbar) {
                if p.energy < e - 1e-3 {
                    warnings.push(format!(
                        "branch {} at lbar = {:.4} (E = {:.8}) lies below the lowest branch {} (E = {:.8}): an exchange not in the surface list",
                        p.branch, p.lbar, p.energy, b, e
                    ));
                }
            }
        }
    }
}
