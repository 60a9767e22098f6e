//! Sampling of the enclosed diagram's branches: attached samples from the exact layer (index
//! from the surface model, the wall being strictly active), lift-off/landing events, lifted-off parts traced by natural-parameter
//! steps at three resolutions (see the parent module's docs).
//!
//! It is one file because the attached samples, the events and the lifted-off traces share the
//! resolution levels and step options defined here.

#![allow(clippy::needless_range_loop)]

use std::time::Instant;

use rodloop_continuation::natural::{walk, NaturalSettings};
use rodloop_exact::{branch_of_eta, paper_branch_loop, ExactLoop};
use rodloop_solver::enclosed::stats::{self, Stage};
use rodloop_solver::enclosed::{
    detached_intervals, enclosed_cells, solve_branch, three_level_estimate, EnclosedOptions,
    SurfaceSource, STEP_ITERATIONS,
};
use rodloop_solver::{
    solve_cells, Accuracy, Confinement, Globalization, SolveOptions, SolverError, StartShape,
    Stiffness,
};

use super::levels::Levels;
use super::locate::{is_jump, locate};
use super::{
    BranchFrom, EnclosedDiagramOptions, EnclosedEvent, EnclosedPoint, EventKind, PointShape,
    PointSource, TOUCH,
};
use crate::labels::Label;
use crate::DiagramError;

/// Where a free loop traced at `lv` (every level off the wall, uniform rod) would touch the
/// wall: the discrete equations of a uniform rod on a uniform mesh are invariant under
/// `L → cL`, `κ → κ/c`, `r → c r`, so the free state at `L̄` stands for the free states at
/// every length, and the smallest ball holding the nodes has radius `ρ` and centre `c`; it is
/// the wall at `L̄ R/ρ`. Per level, `ρ` is half the largest node distance (the state is
/// refused when some node lies outside the ball on that diameter, i.e. when the smallest
/// ball is not set by two antipodal contacts). Returns `(L̄_d, estimate, E R/(πD) at
/// L̄_d)`: the finest level's value with the three-level estimate (fourth order, as for
/// attached states: the contacts are nodes, no contact end moves between them).
pub(super) fn detachment(lv: &Levels) -> Result<(f64, f64, f64), SolverError> {
    let mut x = [0.0; 3];
    for (k, st) in lv.states.iter().enumerate() {
        let pos = st.model.positions(&st.z)?;
        let (mut best, mut pair) = (0.0, (0, 0));
        for i in 0..pos.len() {
            for j in i + 1..pos.len() {
                let d = (pos[i] - pos[j]).norm();
                if d > best {
                    best = d;
                    pair = (i, j);
                }
            }
        }
        let mid = 0.5 * (pos[pair.0] + pos[pair.1]);
        let rho = 0.5 * best;
        if pos.iter().any(|r| (r - mid).norm() > rho * (1.0 + 1e-9)) {
            return Err(SolverError::InvalidInput(format!(
                "the free loop at lbar = {} is not held by two antipodal points of its smallest ball",
                lv.lbar
            )));
        }
        x[k] = lv.lbar * st.model.radius() / rho;
    }
    let (err, _) = three_level_estimate(x[0], x[1], x[2], 4.0);
    let energy = lv.states[2].energy() * lv.lbar / x[2];
    Ok((x[2], err, energy))
}

pub(super) fn exact(eta: u32, lbar: f64) -> Result<ExactLoop, SolverError> {
    Ok(paper_branch_loop(eta, lbar)?)
}

/// Index of an attached loop. Where the loop presses on the wall everywhere (`λ > 0`, which
/// is what makes it attached), the wall constraint is strictly active at every node, so the
/// second-order conditions of the 3-D model live on the tangent space of the sphere: its
/// index is that of the surface model, the constrained Hessian's inertia read from the KKT
/// factorisation at the fast surface resolution ([`Accuracy::cells`]), Newton from the exact
/// loop.
pub(super) fn attached_index(
    radius: f64,
    stiffness: &Stiffness,
    l: &ExactLoop,
) -> Result<usize, SolverError> {
    let start = StartShape::Exact { eta: l.eta };
    let n = Accuracy::Fast.cells(l.eta as usize, stiffness);
    let newton = SolveOptions {
        globalization: Globalization::Newton,
        ..SolveOptions::default()
    };
    let eq = solve_cells(radius, l.lbar, n, stiffness, &start, None, &newton)?;
    eq.model().index(&eq.state(), 1e-6)
}

pub(super) fn exact_point(
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
        family: 0,
        sheet: 0,
        multiplicity: 1,
        branch_from: BranchFrom::Exact,
        surface_energy: Some(l.energy()?),
        shape: PointShape::Exact(*l),
    })
}

pub(super) fn circle_point(lbar: f64) -> EnclosedPoint {
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
        family: 0,
        sheet: 0,
        multiplicity: 1,
        branch_from: BranchFrom::Exact,
        surface_energy: None,
        shape: PointShape::Circle,
    }
}

/// Sample lengths in `(a, b)` on the grid `lbar_min + k·step`, plus the ends when they lie
/// in the window (`incl_a`, `incl_b`).
pub(super) fn grid(opts: &EnclosedDiagramOptions, a: f64, b: f64) -> Vec<f64> {
    let (lo, h) = (opts.lbar_min, opts.step);
    let k0 = ((a - lo) / h).floor().max(0.0) as i64;
    let k1 = ((b - lo) / h).ceil() as i64;
    (k0..=k1)
        .map(|k| lo + k as f64 * h)
        .filter(|&x| x > a + 1e-9 && x < b - 1e-9 && x <= opts.lbar_max + 1e-12)
        .collect()
}

/// Trace a lifted-off interval `(a, b)` of branch `eta` at the sample lengths `xs`: seed in
/// the middle from the surface loop (or, where that fails, at the sample nearest the middle
/// where it converges), then natural-parameter steps both ways (halving a failed step up to
/// 6 times).
pub(super) fn trace_detached(
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
    // Seeded in the middle; where Newton from the surface loop fails there (a loop far off
    // the wall: with `--lbar-max 1.2` the figure-eight at `L̄ = 1.1` reaches 0.25 R inside),
    // at the next sample outwards, the nearer samples first.
    let mut order: Vec<usize> = (0..xs.len()).collect();
    let centre = xs.len() / 2;
    order.sort_by_key(|&k| (k.abs_diff(centre), k < centre));
    let mut first_error = None;
    let mut seeded = None;
    for k in order {
        let at = xs[k];
        let l = exact(eta, at)?;
        let tried = stats::stage(Stage::Seed, || {
            solve_branch(
                opts.radius,
                at,
                &opts.stiffness,
                &SurfaceSource::Exact(l),
                n,
                &sopts,
            )
        });
        match tried {
            Ok(s) => {
                seeded = Some((k, s));
                break;
            }
            Err(e) => {
                first_error.get_or_insert((at, e));
            }
        }
    }
    let Some((mid, seed)) = seeded else {
        let (lbar, source) = first_error.expect("xs is not empty");
        return Err(DiagramError::Seed { eta, lbar, source });
    };
    let seed_at = xs[mid];
    let first = Levels {
        lbar: seed_at,
        states: [seed.quarter, seed.coarse, seed.fine],
    };
    let what = format!("branch {} (eta = {eta})", branch_of_eta(eta));
    let mut stops = Vec::new();
    // The steps with the tracer's Newton budget (a step that stalls is halved early).
    let traced = follow(first, xs, mid, &what, &step_options(), false, &mut stops);
    warnings.extend(stops.into_iter().map(|s| s.text));
    Ok(traced)
}

/// Where a trace stopped because Newton failed under step halving.
#[derive(Clone, Debug)]
pub(super) struct TraceStop {
    /// `L̄` of the last state reached.
    pub(super) lbar: f64,
    /// The warning text (what stopped, why, the last state's contact).
    pub(super) text: String,
    /// The last state reached (its levels), from which a fold is looked for (`fold.rs`).
    pub(super) last: Box<Levels>,
    /// The sample length the trace was walking to and could not reach.
    pub(super) toward: f64,
}

/// Follow a lifted-off state `first` (at `xs[mid]`) through the sample lengths `xs` both
/// ways, one natural-parameter [`walk`] per sample length ([`step`] corrects each step),
/// halving a failed step up to 6 times (5 with `extend`); a walk that gets stuck is retried
/// once as a plain step of every level straight to the target; a trace that still fails
/// stops there with a warning naming `what`. With `extend`, a walk that gets stuck is also
/// retried as a jump past the target and back (over a singular point such as a pitchfork of
/// the lifted-off branch), and a trace that stops keeps the last state it reached. A stop
/// is recorded in `stops`. Returns the states in increasing `L̄`.
pub(super) fn follow(
    first: Levels,
    xs: &[f64],
    mid: usize,
    what: &str,
    sopts: &EnclosedOptions,
    extend: bool,
    stops: &mut Vec<TraceStop>,
) -> Vec<Levels> {
    let settings = NaturalSettings {
        max_step: f64::INFINITY,
        max_halvings: if extend { 5 } else { 6 },
        arrive: 1e-14,
        snap: 1e-9,
    };
    let mut up = vec![first.clone()];
    let mut down = vec![first];
    for (dir, out) in [(1i64, &mut up), (-1i64, &mut down)] {
        let targets: Vec<f64> = if dir > 0 {
            xs[mid + 1..].to_vec()
        } else {
            xs[..mid].iter().rev().copied().collect()
        };
        for &x in &targets {
            let start = out.last().expect("seed").clone();
            let prev = out.len().checked_sub(2).map(|k| out[k].clone());
            let walked = {
                let _stage = stats::enter(Stage::Trace);
                walk(
                    start,
                    prev,
                    x,
                    |l: &Levels| l.lbar,
                    &settings,
                    |cur, prev, to, halvings| step(cur, prev, to, halvings, sopts),
                )
            };
            let stuck = match walked {
                Ok(w) => {
                    out.push(w.last);
                    continue;
                }
                Err(stuck) => stuck,
            };
            let mut cur = stuck.last;
            // A level that left the traced state for a nearby one (on the uniform
            // figure-eight below L̄ ≈ 1.2, the finest level slips from the planar saddle to a
            // non-planar state of its mesh, holonomy ~0.1 rad at N = 64, whose discrete
            // branch ends in a fold a little further on) stalls the halved steps; a plain
            // step of every level straight to the target lands back on the traced state.
            if let Ok(at) = stats::stage(Stage::Retry, || cur.step_to(x, sopts)) {
                out.push(at);
                continue;
            }
            if extend {
                let over = x + (x - cur.lbar);
                let jumped = stats::stage(Stage::Retry, || {
                    cur.step_to(over, sopts).and_then(|j| j.step_to(x, sopts))
                });
                if let Ok(at) = jumped {
                    out.push(at);
                    continue;
                }
                let crept =
                    stats::stage(Stage::Creep, || creep(cur, stuck.prev, x, &settings, sopts));
                match crept {
                    Ok(at) => {
                        out.push(at);
                        continue;
                    }
                    Err(last) => cur = *last,
                }
                if (cur.lbar - out.last().expect("seed").lbar).abs() > 1e-12 {
                    out.push(cur.clone());
                }
            }
            let c = cur.states[2].contact(TOUCH).ok();
            stops.push(TraceStop {
                last: Box::new(cur.clone()),
                toward: x,
                lbar: cur.lbar,
                text: format!(
                    "{what}: the lifted-off trace stops at lbar = {:.6} ({}); the last state touches the wall on {:.1}% of its length with contact forces in [{:.3e}, {:.3e}]; Newton failed under {} step halvings (perhaps a fold or a bifurcation of the lifted-off branch; not traced further)",
                    cur.lbar,
                    stuck.error,
                    100.0 * c.as_ref().map_or(f64::NAN, |c| c.fraction),
                    c.as_ref().map_or(f64::NAN, |c| c.lambda_range.0),
                    c.as_ref().map_or(f64::NAN, |c| c.lambda_range.1),
                    settings.max_halvings,
                ),
            });
            break;
        }
    }
    down.remove(0);
    down.reverse();
    down.extend(up);
    down
}

/// Restarts of a stuck walk in [`creep`].
const CREEPS: usize = 3;

/// Halvings beyond the walk's that [`creep`] tries for its short step.
const CREEP_HALVINGS: i32 = 7;

/// A stuck walk of [`follow`] resumed: a step of `2^-(k+1)` of the remaining way to `x`
/// (`k` the walk's halvings, up to [`CREEP_HALVINGS`] more), then the walk again from the
/// state reached, with the secant predictor through the last two states and the full step
/// and halving budget, at most [`CREEPS`] times. A natural-parameter walk keeps the step it
/// halved to, and its first step from a seed has no predictor: on the two-segment
/// figure-eight lifted `0.55 R` off the wall at `L̄ = 1.42`, the plain step fails down to
/// `ΔL̄ = 2.5·10⁻³` and succeeds at `1.25·10⁻³`, after which the predicted steps reach
/// `L̄ = 1.34` in one walk. Returns the state at `x`, or the last state reached.
fn creep(
    mut cur: Levels,
    mut prev: Option<Levels>,
    x: f64,
    settings: &NaturalSettings,
    sopts: &EnclosedOptions,
) -> Result<Levels, Box<Levels>> {
    for _ in 0..CREEPS {
        let first = settings.max_halvings as i32 + 1;
        let short = (first..first + CREEP_HALVINGS).find_map(|k| {
            let to = cur.lbar + (x - cur.lbar) * 0.5f64.powi(k);
            step(&cur, prev.as_ref(), to, settings.max_halvings, sopts).ok()
        });
        let Some(next) = short else {
            return Err(Box::new(cur));
        };
        let resumed = walk(
            next.clone(),
            Some(cur),
            x,
            |l: &Levels| l.lbar,
            settings,
            |c, p, to, h| step(c, p, to, h, sopts),
        );
        match resumed {
            Ok(w) => return Ok(w.last),
            Err(stuck) => {
                cur = stuck.last;
                prev = stuck.prev;
            }
        }
    }
    Err(Box::new(cur))
}

/// One step of [`follow`] from `cur` to `to`: from the secant predictor through `prev`
/// (not for a free loop); the plain warm start where there is no predictor, for a free
/// loop, or once the step has been halved twice (trying it on every failed predicted step
/// doubled the cost of failures); leaving the wall where the contact has shrunk to points
/// whose force is vanishing ([`Levels::leave_wall`]).
fn step(
    cur: &Levels,
    prev: Option<&Levels>,
    to: f64,
    halvings: usize,
    sopts: &EnclosedOptions,
) -> Result<Levels, SolverError> {
    let predicted = match prev {
        Some(p) if !cur.free() => cur.step_predicted(p, to, sopts),
        _ => Err(SolverError::InvalidInput("no predictor".into())),
    };
    let try_plain = prev.is_none() || cur.free() || halvings >= 2;
    predicted
        .or_else(|e| {
            if try_plain {
                cur.step_to(to, sopts)
            } else {
                Err(e)
            }
        })
        .or_else(|e| {
            let point_like = !cur.free()
                && cur.states[2]
                    .contact(TOUCH)
                    .is_ok_and(|c| c.fraction > 0.0 && c.fraction < 0.1);
            if point_like {
                cur.leave_wall(to, sopts).map_err(|_| e)
            } else {
                Err(e)
            }
        })
}

/// One branch's share of the diagram.
#[derive(Default)]
pub(super) struct BranchOut {
    pub(super) points: Vec<EnclosedPoint>,
    pub(super) events: Vec<EnclosedEvent>,
    pub(super) levels: Vec<Levels>,
    pub(super) warnings: Vec<String>,
    /// Index changes explained as changes of the contact set (`locate.rs`).
    pub(super) notes: Vec<String>,
    pub(super) attached_s: f64,
    pub(super) lifted_s: f64,
}

/// Sample branch `eta` on the window: attached samples from the exact layer, events at the
/// ends of its lifted-off intervals, the lifted-off parts traced with the 3-D model.
pub(super) fn trace_branch(
    opts: &EnclosedDiagramOptions,
    eta: u32,
) -> Result<BranchOut, DiagramError> {
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
                    family: 0,
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
        // Detachments: a free state next to a touching one.
        for w in tr.windows(2) {
            if !w[0].free() || w[1].free() {
                continue;
            }
            match detachment(&w[0]) {
                Ok((x, err, energy)) if x > w[0].lbar && x < w[1].lbar => {
                    out.events.push(EnclosedEvent {
                        kind: EventKind::Detachment,
                        branch,
                        family: 0,
                        lbar: x,
                        error_estimate: err,
                        energy,
                        index_before: 0,
                        index_after: 0,
                    });
                }
                Ok((x, _, _)) => out.warnings.push(format!(
                    "branch {branch}: the loop leaves the wall between lbar = {:.6} and {:.6}, but its free state would touch at {x:.6}, outside that interval",
                    w[0].lbar, w[1].lbar
                )),
                Err(e) => out.warnings.push(format!(
                    "branch {branch}: the loop leaves the wall between lbar = {:.6} and {:.6}; not located ({e})",
                    w[0].lbar, w[1].lbar
                )),
            }
        }
        let (bps, bp_notes, bp_warnings) = locate_branch_points(&tr, branch, &sopts_locate());
        out.events.extend(bps);
        out.notes.extend(bp_notes);
        out.warnings.extend(bp_warnings);
        for lv in &tr {
            let mut pt = lv.point(branch, eta)?;
            pt.surface_energy = Some(exact(eta, lv.lbar)?.energy().map_err(SolverError::from)?);
            branch_points.push(pt);
        }
        out.levels.extend(tr);
    }
    branch_points.sort_by(|u, v| u.lbar.total_cmp(&v.lbar));
    // Index before/after each event from the neighbouring samples.
    for ev in out
        .events
        .iter_mut()
        .filter(|e| e.kind != EventKind::BranchPoint)
    {
        let before = branch_points.iter().rev().find(|p| p.lbar < ev.lbar - 1e-9);
        let after = branch_points.iter().find(|p| p.lbar > ev.lbar + 1e-9);
        ev.index_before = before.map_or(0, |p| p.index);
        ev.index_after = after.map_or(0, |p| p.index);
    }
    out.points = branch_points;
    Ok(out)
}

/// Newton options of the re-solves that locate a branch point (the default budget: next to
/// the singular point Newton converges linearly).
fn sopts_locate() -> EnclosedOptions {
    EnclosedOptions::default()
}

/// Branch points between consecutive states of a trace `tr` of a uniform rod's branch
/// (both on the wall, or both free) where the index (of the finest level, as the traces
/// report it, [`Levels::index`]) changes ([`super::locate`]; located on the levels `N/2` and `N`). Returns the
/// events, notes for changes at a change of the contact set (the eigenvalue jumps) and
/// warnings for changes that were not located.
fn locate_branch_points(
    tr: &[Levels],
    branch: u32,
    sopts: &EnclosedOptions,
) -> (Vec<EnclosedEvent>, Vec<String>, Vec<String>) {
    let (mut events, mut notes, mut warnings) = (Vec::new(), Vec::new(), Vec::new());
    let refs: Vec<&Levels> = tr.iter().collect();
    for (j, w) in tr.windows(2).enumerate() {
        let (a, b) = (&w[0], &w[1]);
        if a.free() != b.free() {
            continue;
        }
        let (Ok(ia), Ok(ib)) = (a.index(), b.index()) else {
            continue;
        };
        if ia == ib {
            continue;
        }
        match locate(&refs, j, [1, 2], sopts) {
            Ok(p) => events.push(EnclosedEvent {
                kind: EventKind::BranchPoint,
                branch,
                family: 0,
                lbar: p.lbar,
                error_estimate: p.error_estimate,
                energy: p.energy,
                index_before: p.index_below,
                index_after: p.index_above,
            }),
            Err(e) if is_jump(&e) => notes.push(format!(
                "branch {branch}: the index changes from {ia} to {ib} between lbar = {:.6} and {:.6} at a change of the contact set, not at a branch point ({e})",
                a.lbar, b.lbar
            )),
            Err(e) => warnings.push(format!(
                "branch {branch}: the index changes from {ia} to {ib} between lbar = {:.6} and {:.6}, but the branch point was not located ({e})",
                a.lbar, b.lbar
            )),
        }
    }
    (events, notes, warnings)
}

/// Newton options of the continuation steps: a step that needs more than
/// [`STEP_ITERATIONS`] iterations is halved instead, and one that has not halved its
/// residual in 6 iterations is given up (it is shedding the old contact set node by node; a
/// shorter step does better).
pub(super) fn step_options() -> EnclosedOptions {
    EnclosedOptions {
        max_iterations: STEP_ITERATIONS,
        stall_window: 6,
        ..EnclosedOptions::default()
    }
}
