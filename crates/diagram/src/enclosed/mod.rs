//! The branch diagram of loops enclosed in the ball, `|r| ≤ R` (paper Sec. 3.2): every
//! paper branch traced through its attached and lifted-off parts, branch 0
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
//!   crosses zero, i.e. where `k²(L̄) = 1/2`
//!   ([`detached_intervals`](rodloop_solver::enclosed::detached_intervals), bisection to
//!   `1e-13`). That is the event "λ crosses 0 on the contact set" without a discrete
//!   event function, and more accurate than locating it on a discrete trace. The tests
//!   check it independently with the 3-D model on both sides of each event.
//! * **Only lifted-off parts use the 3-D model**, traced in `L̄` by natural-parameter steps
//!   with warm starts ([`step_to`](rodloop_solver::enclosed::EnclosedState::step_to)) at
//!   three resolutions `N/4, N/2, N` (for the energy and its error estimate). The
//!   semismooth Newton picks the contact set anew at every step, so contact ends that move
//!   between nodes need no bookkeeping; with a fixed active set behind the `Confinement`
//!   seam, every node a contact end passes would be an event and a restart. `L̄` is a good
//!   parameter on the lifted-off parts of the paper's branches in `[1, 3]` (no folds: a fold
//!   would show as Newton failing under step halving, which is reported as a warning and
//!   ends the trace there). Below `L̄ = 1` branch 2 (the figure-eight, held at two points)
//!   leaves the wall at `L̄* = K(k)/(πk) = 0.81286` (`2E(k) = K(k)`) where Euler's free
//!   figure-eight just fits; its translations lose their stiffness there, so the step is
//!   retried with them pinned ([`EnclosedState::continue_free`](rodloop_solver::enclosed::EnclosedState::continue_free))
//!   and the free loop traced on; the point is a special point (`detachment`), located
//!   by the scale invariance of the free discrete loop.
//! * **Exchanges** come from the exact layer's list (the surface diagram): an exchange
//!   between two attached states is the surface one, exactly. Where a branch of an exchange
//!   has lifted off, `E_a(L̄) = E_b(L̄)` is located again by the exchange locator
//!   ([`rodloop_continuation::exchange::locate`]: a hunt for the sign change from the
//!   surface value, then Brent's method) on re-solved states (3-D model at `N/4, N/2, N`
//!   to locate it, then on a ladder of finer meshes from there; warm-started from the
//!   trace), with the error estimate `(δE_a + δE_b + m)/|d(E_a − E_b)/dL̄| +` the final
//!   bracket (`m` the noise misfit of the chord over `±10⁻⁵` that gives the slope). The enclosed
//!   energy never exceeds the surface one, and below `L̄ = 1` the circle is the lowest
//!   closed curve of its length, so no exchange outside that list appears; the sampled
//!   energies are checked for one anyway (a warning if found).
//!
//! Non-uniform rods (two-segment stiffness, Eq. (51)) have no exact layer and their
//! branches come as families: `nonuniform.rs` takes the attached parts, events and
//! lifted-off starts from the surface families instead (see its docs);
//! `nonuniform_descent.rs` adds the families below unstable lowest states and
//! `nonuniform_special.rs` the branch points and the sorting of the traces' stops.

#![allow(clippy::needless_range_loop)]

use std::sync::Arc;
use std::time::Instant;

use rodloop_exact::diagram::{compute, Critical, CriticalKind, DiagramSettings};
use rodloop_exact::ExactLoop;
use rodloop_exact::{branch_of_eta, eta_of_branch};
use rodloop_solver::enclosed::stats::{self, SolveStats, Stage, StageCounts};
use rodloop_solver::enclosed::{enclosed_cells, EnclosedState, IntoWall, Wall};
use rodloop_solver::{Accuracy, Equilibrium, SolverError, Stiffness};
use serde::Serialize;

use crate::labels::Label;
use crate::parallel::run_parallel;
use crate::DiagramError;

mod critical;
mod fold;
mod levels;
mod locate;
mod nonuniform;
mod nonuniform_descent;
mod nonuniform_exchange;
mod nonuniform_seeds;
mod nonuniform_sheet;
mod nonuniform_special;
mod trace;
mod verify;

pub use rodloop_solver::enclosed::nonuniform_cells;

use critical::{detached_at, enclosed_crossing, exchange_doublings, label};
use levels::Levels;
use trace::{circle_point, grid, trace_branch, BranchOut};

/// Gap (units of `R`) below which a node touches the wall: the one tolerance of `solve`'s
/// enclosed states and the diagrams' rows.
pub use crate::enclosed_state::TOUCH;

/// What to compute.
#[derive(Clone, Debug)]
pub struct EnclosedDiagramOptions {
    /// The wall's length scale `R` ([`Wall::radius`]).
    pub radius: f64,
    /// The wall (the diagram traces inside the sphere: [`Wall::sphere`]).
    pub wall: Arc<dyn Wall>,
    /// Stiffness (uniform or non-uniform).
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
    pub fn new(wall: impl IntoWall, stiffness: Stiffness, lbar_min: f64, lbar_max: f64) -> Self {
        let wall = wall.into_wall();
        Self {
            radius: wall.radius(),
            wall,
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
        if self.wall.sphere().is_none() {
            return bad(format!(
                "the enclosed diagram traces inside the sphere; the wall is a {}",
                self.wall.outline().0
            ));
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
    /// The surface model's equilibrium, attached (`λ_min > 0`; non-uniform rods).
    Surface,
}

/// How the branch of a point of the enclosed diagram is known
/// (docs/src/methods.md, "How the branch of a state is identified").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum BranchFrom {
    /// Closed form: the exact loop of the branch, or the free circle (branch 0).
    #[default]
    Exact,
    /// The periods of the state's own bending moment (of its central projection onto the
    /// sphere for a 3-D state) equal the branch's `η`.
    Periods,
    /// The state's moment has no periods to count (a loop in a plane through the centre of
    /// the ball projects onto a great circle; a pattern within the noise): the branch is the
    /// one of the family it was continued on from a named seed.
    Continuation,
}

impl BranchFrom {
    /// `"exact"`, `"periods"` or `"continuation"`.
    pub fn as_str(self) -> &'static str {
        match self {
            BranchFrom::Exact => "exact",
            BranchFrom::Periods => "periods",
            BranchFrom::Continuation => "continuation",
        }
    }
}

/// The loop behind a point of the enclosed diagram (what `diagram` writes to `states/`).
#[derive(Clone, Debug, Default)]
pub enum PointShape {
    /// The reported 3-D state (lifted off: the finest of the levels `N/4, N/2, N`).
    Model(Box<EnclosedState>),
    /// The surface equilibrium of an attached state (non-uniform rods, `λ_min > 0`), before
    /// its file is verified (`verify.rs` replaces it by [`PointShape::SurfaceFile`]).
    Surface(Box<Equilibrium>),
    /// An attached state's surface loop as its file holds it, verified against the row by
    /// the routine that verifies every traced surface state
    /// (`verify_refining` (`state_file.rs`); the file may sample the state re-solved on
    /// `2N`, `4N`, … where the tracing resolution's profile does not reproduce the row's
    /// energy), and the loop's length.
    SurfaceFile(Box<crate::StateFile>, f64),
    /// The exact surface loop of an attached state (uniform rods).
    Exact(ExactLoop),
    /// The free planar circle of radius `R L̄` through the centre's plane (branch 0).
    Circle,
    /// No shape kept (the surface state could not be re-evaluated).
    #[default]
    Missing,
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
    /// Family within the branch (non-uniform rods; 0 for a uniform rod, whose branch is one
    /// family).
    pub family: u32,
    /// Sheet of the family (monotone in `L̄`; 0 for a uniform rod).
    pub sheet: u32,
    /// Distinct loops the state stands for (2 for a mirror-asymmetric state of a
    /// non-uniform rod, reported once).
    pub multiplicity: u32,
    /// Energy of the branch's surface loop at this length (`None` for the free circle).
    pub surface_energy: Option<f64>,
    /// How the state's branch is known (set by the verification of its file).
    pub branch_from: BranchFrom,
    /// The loop itself (for `states/`; not serialised).
    #[serde(skip)]
    pub shape: PointShape,
}

/// Kind of an event on a branch.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum EventKind {
    /// Attached below, lifted off above (increasing `L̄`).
    LiftOff,
    /// Lifted off below, attached above.
    Landing,
    /// The loop leaves the wall altogether (decreasing `L̄`): the forces at its last,
    /// point-like contacts vanish, and below it the branch is a free elastica inside the
    /// ball (branch 2: Euler's figure-eight, whose tips touch the wall at
    /// `L̄ = K(k)/(πk)`, `2E(k) = K(k)`).
    Detachment,
    /// An eigenvalue on the tangent space of the active constraints crosses zero on a
    /// lifted-off sheet (the Hessian index changes): another family meets the sheet there.
    BranchPoint,
    /// A lifted-off family turns back in `L̄` (a fold: the family and one whose index differs
    /// by one meet and end there), located from a trace's stop (`fold.rs`).
    Fold,
}

impl EventKind {
    /// `"lift-off"` or `"landing"`.
    pub fn as_str(self) -> &'static str {
        match self {
            EventKind::LiftOff => "lift-off",
            EventKind::Landing => "landing",
            EventKind::Detachment => "detachment",
            EventKind::BranchPoint => "branch_point",
            EventKind::Fold => "fold",
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
    /// Family within the branch (0 for a uniform rod).
    pub family: u32,
    /// `L̄` of the event (`λ_min = 0`, `k² = 1/2` for a uniform rod; for a detachment, the
    /// last contact force 0).
    pub lbar: f64,
    /// Its error estimate.
    pub error_estimate: f64,
    /// Energy at the event (exact layer; for a detachment, the free loop's).
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
    /// The surface diagram's value (exact layer; for a non-uniform rod the same two sheets'
    /// surface states), where it was located.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub surface_lbar_cr: Option<f64>,
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
    /// Explained ends of traces (printed as notes).
    pub notes: Vec<String>,
    /// Cells of the lifted-off trace (`N` of `N/4, N/2, N`) per branch.
    pub cells: Vec<(u32, usize)>,
    /// Wall-clock seconds: total, attached samples (index checks), lifted-off traces,
    /// critical lengths.
    pub seconds: EnclosedTimings,
    /// The enclosed Newton solves by stage: attempted, converged, failed, iterations and
    /// their time ([`rodloop_solver::enclosed::stats`]).
    pub solves: Vec<(Stage, StageCounts)>,
}

/// Wall-clock seconds of the parts of [`enclosed_diagram`].
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct EnclosedTimings {
    /// Everything.
    pub total: f64,
    /// Attached samples (exact layer, index from the surface model), summed over the branch
    /// threads.
    pub attached: f64,
    /// Lifted-off traces, summed over the branch threads.
    pub lifted_off: f64,
    /// Critical lengths.
    pub critical: f64,
    /// Surface families traced first (non-uniform rods; 0 for uniform ones).
    pub surface: f64,
    /// Non-uniform rods (0 for uniform ones), wall-clock seconds of each stage after the
    /// surface families: the sheets (attached samples, events, lifted-off traces)...
    pub sheets: f64,
    /// ... the search for lifted-off families from the stiffness path ...
    pub stiffness_path: f64,
    /// ... the descent from unstable lowest states ...
    pub descent: f64,
    /// ... the branch points of the lifted-off sheets ...
    pub branch_points: f64,
    /// ... the folds at the traces' stops ...
    pub folds: f64,
    /// ... and the check of the lifted-off rows' estimates on twice their cells.
    pub row_checks: f64,
}

/// A stage of [`enclosed_diagram_with`] for progress reports (sent on the calling thread).
#[derive(Clone, Debug, PartialEq)]
pub enum EnclosedProgress {
    /// This many more tasks (branches, surface families, sheets, stages) are planned.
    Planned(usize),
    /// One task finished (what it was, for a status line).
    Done(String),
}

/// Compute the enclosed diagram (see the module docs).
pub fn enclosed_diagram(opts: &EnclosedDiagramOptions) -> Result<EnclosedDiagram, DiagramError> {
    enclosed_diagram_with(opts, &mut |_| {})
}

/// [`enclosed_diagram`], reporting its tasks to `progress` as they are planned and done.
pub fn enclosed_diagram_with(
    opts: &EnclosedDiagramOptions,
    progress: &mut dyn FnMut(EnclosedProgress),
) -> Result<EnclosedDiagram, DiagramError> {
    opts.validate()?;
    // Every enclosed Newton solve of the diagram counted by stage (`solves`).
    let counters = SolveStats::new();
    let mut d = stats::scope(&counters, Stage::Other, || {
        if opts.stiffness.is_uniform() {
            uniform_diagram(opts, progress)
        } else {
            nonuniform::nonuniform_diagram(opts, progress)
        }
    })?;
    d = verify::verified(d);
    d.solves = counters.snapshot();
    Ok(d)
}

/// The enclosed diagram of a uniform rod (see the module docs), before verification.
fn uniform_diagram(
    opts: &EnclosedDiagramOptions,
    progress: &mut dyn FnMut(EnclosedProgress),
) -> Result<EnclosedDiagram, DiagramError> {
    let t0 = Instant::now();
    let (lo, hi) = (opts.lbar_min, opts.lbar_max);
    let mut warnings = Vec::new();
    let mut notes = Vec::new();
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
    // Tasks: the branches, then the critical lengths.
    progress(EnclosedProgress::Planned(order.len() + 1));
    let scope = stats::current();
    let outs = run_parallel(
        threads,
        order.clone(),
        &mut |_| {},
        &mut |o: &Result<BranchOut, DiagramError>| {
            if let Ok(o) = o {
                progress(EnclosedProgress::Done(format!(
                    "branch {} traced ({} states)",
                    o.points.first().map_or(0, |p| p.branch),
                    o.points.len()
                )));
            }
        },
        |eta, _| stats::within(&scope, || trace_branch(opts, eta)),
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
        notes.extend(o.notes);
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
                surface_lbar_cr: Some(c.lbar_cr),
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
        let (x, err, energy, cells) = stats::stage(Stage::Exchange, || {
            enclosed_crossing(
                etas2[0],
                etas2[1],
                c.lbar_cr,
                &mut tracks,
                exchange_doublings(opts.accuracy),
            )
        })
        .map_err(|e| DiagramError::Critical {
            from_branch: c.from_branch,
            to_branch: c.to_branch,
            lbar: c.lbar_cr,
            reason: e.to_string(),
        })?;
        let cells: Vec<String> = cells.iter().map(usize::to_string).collect();
        critical.push(EnclosedCritical {
            critical: Critical {
                lbar_cr: x,
                energy,
                error_estimate: err,
                ..*c
            },
            surface_lbar_cr: Some(c.lbar_cr),
            method: format!(
                "the exchange locator on E_a = E_b with the lifted-off state re-solved (3-D model at N = {}; error from these levels (the smaller observed order, the larger of the last two differences' estimates), the noise of the slope's chord over +-1e-5 and the final bracket)",
                cells.join(", ")
            ),
        });
    }

    timings.critical = tc.elapsed().as_secs_f64();
    progress(EnclosedProgress::Done(format!(
        "{} critical lengths located",
        critical.len()
    )));
    label(&mut points, &critical, &mut warnings);
    timings.total = t0.elapsed().as_secs_f64();
    Ok(EnclosedDiagram {
        points,
        events,
        critical,
        warnings,
        notes,
        cells,
        seconds: timings,
        solves: Vec::new(),
    })
}
