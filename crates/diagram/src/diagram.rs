//! The assembled diagram: critical lengths, labels, great circles.
//!
//! The file is over 600 lines because it is the one result of the `L̄` diagram: its types
//! (the diagram, its rows, its summary), [`assemble`] that fills them from the traced
//! branches, and the end points and special points read from those branches.

use std::time::Instant;

use rodloop_solver::Accuracy;
use serde::Serialize;

use crate::buckling::{self, BucklingReport};
use crate::critical::{self, CriticalKind, CriticalLength};
use crate::labels::{self, Label};
use crate::parallel::run_parallel;
use crate::shapes::{state_shapes, StateShape};
use crate::types::TracedBranch;
use crate::{DiagramError, DiagramOptions, Progress};
use rodloop_exact::shape::ShapeTolerances;

/// Work of the assembly phase.
enum Task {
    Circle(u32),
    Crossing(critical::Candidate),
    /// A fold or branch point (index into the end points) at a sheet's end.
    End(usize, usize, bool),
}

/// Result of a [`Task`] with its duration.
enum Done {
    Circle(u32, buckling::CircleResult, f64),
    Crossing(Box<Result<CriticalLength, DiagramError>>, f64),
    End(usize, Option<crate::special::Located>, f64),
}

/// Wall times of the phases, in seconds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Timings {
    /// Tracing all branches (wall time; 0 when [`assemble`] is called directly).
    pub tracing: f64,
    /// Locating the crossings and the folds and branch points (sum over the tasks, which
    /// run in parallel with the great circles).
    pub critical: f64,
    /// Great circles: buckling loads and branch switching (sum over the circles).
    pub great_circles: f64,
    /// Wall time of the parallel phase (crossings and great circles).
    pub parallel_wall: f64,
    /// Labels.
    pub labels: f64,
    /// Shape descriptors of the states (point group, self-intersections).
    pub shapes: f64,
    /// Everything ([`crate::compute`]) or the assembly alone ([`assemble`]).
    pub total: f64,
}

/// The numeric branch diagram.
#[derive(Clone, Debug, Serialize)]
pub struct NumericDiagram {
    /// Accuracy level.
    pub accuracy: Accuracy,
    /// Scene and resolution summary (human-readable).
    pub scene: String,
    /// Diagram range `(lbar_min, lbar_max)`.
    pub range: (f64, f64),
    /// Traced branches, by `η`.
    pub branches: Vec<TracedBranch>,
    /// Labels of the traced states, `labels[i][k]` for `branches[i].points[k]`.
    pub labels: Vec<Vec<Label>>,
    /// Point group and self-intersections of the traced states, `shapes[i][k]` for
    /// `branches[i].points[k]`.
    pub shapes: Vec<Vec<StateShape>>,
    /// Tolerances of [`NumericDiagram::shapes`].
    pub shape_tolerance: ShapeTolerances,
    /// Critical lengths in increasing order.
    pub critical: Vec<CriticalLength>,
    /// Folds, branch points, crossings and collapses, in increasing `L̄`.
    pub special: Vec<SpecialPoint>,
    /// Great-circle analysis (`None` if disabled).
    pub great_circles: Option<BucklingReport>,
    /// Anything suspicious met on the way.
    pub warnings: Vec<String>,
    /// Wall times.
    pub timings: Timings,
    /// Completeness certificate (two-segment surface diagrams; `None` where not run).
    pub certificate: Option<crate::certificate::Certificate>,
    /// Every traced state as its file holds it, verified against its row:
    /// `state_files[i][k]` for `branches[i].points[k]` (`None`: the state failed the
    /// verification and has no file; a warning says why).
    #[serde(skip)]
    pub state_files: Vec<Vec<Option<crate::StateFile>>>,
    /// How many traced states failed the verification.
    pub unverified_states: usize,
}

/// One row of the branch table (`branches.csv`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DiagramRow {
    /// Paper branch number.
    pub branch: u32,
    /// Periods of `κ_g`.
    pub eta: u32,
    /// Family within the branch ([`TracedBranch::family`]).
    pub family: u32,
    /// Position along the family: sheet number times 10⁶ plus the point's rank in the
    /// family's arclength order, so that sorting a family's rows by it draws the family
    /// as one path through its folds.
    pub arc: u64,
    /// Mirror multiplicity ([`TracedBranch::multiplicity`]).
    pub multiplicity: u32,
    /// Normalised length.
    pub lbar: f64,
    /// `E R/(π D0)`.
    pub energy: f64,
    /// `E_g R/(π D0)`.
    pub energy_g: f64,
    /// Estimated error of `energy` (`None` if unknown).
    pub energy_error: Option<f64>,
    /// Stability label.
    pub stability: Label,
    /// Stability index.
    pub index: usize,
    /// Minimum of `λR³/D0`.
    pub lambda_min: f64,
    /// Maximum of `λR³/D0`.
    pub lambda_max: f64,
    /// Point group and self-intersections ([`NumericDiagram::shapes`]).
    pub shape: StateShape,
}

/// A compact summary of a diagram (no states): what `summary.json` needs.
#[derive(Clone, Debug, Serialize)]
pub struct DiagramSummary<'a> {
    /// Accuracy level.
    pub accuracy: Accuracy,
    /// Scene and resolution summary.
    pub scene: &'a str,
    /// Diagram range.
    pub range: (f64, f64),
    /// One entry per branch.
    pub branches: Vec<BranchSummary<'a>>,
    /// Critical lengths.
    pub critical: &'a [CriticalLength],
    /// Special points.
    pub special: &'a [SpecialPoint],
    /// Great-circle analysis.
    pub great_circles: Option<&'a BucklingReport>,
    /// Warnings.
    pub warnings: &'a [String],
    /// Wall times.
    pub timings: Timings,
    /// Completeness certificate (`None` where not run).
    pub certificate: Option<&'a crate::certificate::Certificate>,
}

/// Summary of one traced branch.
#[derive(Clone, Debug, Serialize)]
pub struct BranchSummary<'a> {
    /// Paper branch number.
    pub branch: u32,
    /// Periods of `κ_g`.
    pub eta: u32,
    /// Number of traced states.
    pub points: usize,
    /// Traced span `(first, last)` of `L̄`.
    pub span: (f64, f64),
    /// Tracing resolution (cells).
    pub cells: usize,
    /// Reporting resolutions `(N_f, N_c)` of the critical lengths.
    pub reporting_cells: (usize, usize),
    /// How the lower end came about.
    pub low_end: &'a crate::BranchEnd,
    /// How the upper end came about.
    pub high_end: &'a crate::BranchEnd,
    /// Why the lower end stopped.
    pub stop_low: &'a str,
    /// Why the upper end stopped.
    pub stop_high: &'a str,
    /// Seed.
    pub seed: &'a str,
    /// Changes of the stability index.
    pub index_changes: &'a [crate::IndexChange],
    /// Continuation steps.
    pub steps: usize,
    /// Wall time of the tracing.
    pub seconds: f64,
}

impl NumericDiagram {
    /// A compact, serialisable summary (everything but the states).
    pub fn summary(&self, opts: &DiagramOptions) -> DiagramSummary<'_> {
        DiagramSummary {
            accuracy: self.accuracy,
            scene: &self.scene,
            range: self.range,
            branches: self
                .branches
                .iter()
                .map(|b| BranchSummary {
                    branch: b.branch,
                    eta: b.eta,
                    points: b.points.len(),
                    span: b.span(),
                    cells: b.cells,
                    reporting_cells: crate::refine::reporting_cells(opts, b.eta),
                    low_end: &b.low_end,
                    high_end: &b.high_end,
                    stop_low: &b.stop_low,
                    stop_high: &b.stop_high,
                    seed: &b.seed,
                    index_changes: &b.index_changes,
                    steps: b.steps,
                    seconds: b.seconds,
                })
                .collect(),
            critical: &self.critical,
            special: &self.special,
            great_circles: self.great_circles.as_ref(),
            warnings: &self.warnings,
            timings: self.timings,
            certificate: self.certificate.as_ref(),
        }
    }

    /// All traced states as flat rows, by branch then length.
    pub fn rows(&self) -> Vec<DiagramRow> {
        self.branches
            .iter()
            .zip(&self.labels)
            .zip(&self.shapes)
            .flat_map(|((b, ls), shapes)| {
                let n = b.points.len() as u64;
                b.points
                    .iter()
                    .zip(ls)
                    .zip(shapes)
                    .enumerate()
                    .map(move |(k, ((p, &l), shape))| DiagramRow {
                        branch: b.branch,
                        eta: b.eta,
                        family: b.family,
                        arc: u64::from(b.sheet) * 1_000_000
                            + if b.reversed {
                                n - 1 - k as u64
                            } else {
                                k as u64
                            },
                        multiplicity: b.multiplicity,
                        lbar: p.value,
                        energy: p.energy,
                        energy_g: p.energy_g,
                        energy_error: crate::states::sheet_estimate(&b.points, k),
                        stability: l,
                        index: p.index,
                        lambda_min: p.lambda_min,
                        lambda_max: p.lambda_max,
                        shape: shape.clone(),
                    })
            })
            .collect()
    }

    /// The branch with `eta`, if traced.
    pub fn branch_by_eta(&self, eta: u32) -> Option<&TracedBranch> {
        self.branches.iter().find(|b| b.eta == eta)
    }

    /// Label of the state of branch `eta` nearest to `lbar` (with its length).
    pub fn label_near(&self, eta: u32, lbar: f64) -> Option<(f64, Label)> {
        let i = self.branches.iter().position(|b| b.eta == eta)?;
        let b = &self.branches[i];
        let k = (0..b.points.len()).min_by(|&x, &y| {
            (b.points[x].value - lbar)
                .abs()
                .total_cmp(&(b.points[y].value - lbar).abs())
        })?;
        Some((b.points[k].value, self.labels[i][k]))
    }

    /// Positions in [`NumericDiagram::branches`] of the sheets lowest at `lbar` (two exactly
    /// at a critical length, none at a collapse).
    pub fn lowest_sheets_at(&self, lbar: f64) -> Vec<usize> {
        labels::lowest_sheets(&self.branches, &self.critical, lbar)
    }

    /// Paper branch numbers lowest at `lbar` (two exactly at a critical length).
    pub fn lowest_at(&self, lbar: f64) -> Vec<u32> {
        labels::lowest_etas(&self.branches, &self.critical, lbar)
            .into_iter()
            .map(rodloop_exact::branch_of_eta)
            .collect()
    }
}

/// Everything after tracing: critical lengths (located on re-solved equilibria), labels,
/// great circles. `branches` are the traced branches (any order; sorted by `η` here).
pub fn assemble(
    opts: &DiagramOptions,
    mut branches: Vec<TracedBranch>,
    progress: &mut dyn FnMut(Progress),
) -> Result<NumericDiagram, DiagramError> {
    opts.validate()?;
    let start = Instant::now();
    branches.sort_by_key(|b| (b.eta, b.family, b.sheet));
    for b in &branches {
        check_branch(b)?;
    }
    let mut timings = Timings::default();

    // Crossings (located on re-solved equilibria) and great circles, in parallel.
    let t = Instant::now();
    let (candidates, mut warnings) = critical::detect_crossings(opts, &branches);
    let circles = if opts.great_circles {
        buckling::circles(opts)
    } else {
        Vec::new()
    };
    progress(Progress::AssemblyPlanned {
        crossings: candidates.len(),
        great_circles: circles.len(),
    });
    let total_circles = circles.len();
    let (mut ends, end_sources) = end_points(&branches);
    let mut tasks: Vec<Task> = circles.into_iter().map(Task::Circle).collect();
    tasks.extend(candidates.into_iter().map(Task::Crossing));
    tasks.extend(
        end_sources
            .iter()
            .enumerate()
            .map(|(k, &(sheet, at_low))| Task::End(k, sheet, at_low)),
    );
    let results = run_parallel(
        opts.worker_threads(),
        tasks,
        progress,
        &mut |_| {},
        |task, tx| {
            let t = Instant::now();
            match task {
                Task::Circle(m) => {
                    let r = buckling::analyse_circle(opts, m, &branches);
                    tx(Progress::GreatCircleDone {
                        m,
                        total: total_circles,
                    });
                    Done::Circle(m, r, t.elapsed().as_secs_f64())
                }
                Task::Crossing(cand) => {
                    let r = critical::locate_crossing(opts, &branches, &cand);
                    if let Ok(c) = &r {
                        tx(Progress::CriticalLocated {
                            kind: c.kind,
                            lbar_cr: c.lbar_cr,
                            from_branch: c.from_branch,
                            to_branch: c.to_branch,
                        });
                    }
                    Done::Crossing(Box::new(r), t.elapsed().as_secs_f64())
                }
                Task::End(k, sheet, at_low) => Done::End(
                    k,
                    crate::special::locate_end(opts, &branches[sheet], at_low),
                    t.elapsed().as_secs_f64(),
                ),
            }
        },
    );
    let mut critical = Vec::new();
    let mut circle_results = Vec::new();
    for r in results {
        match r {
            Done::Circle(m, r, secs) => {
                timings.great_circles += secs;
                circle_results.push((m, r));
            }
            Done::End(k, located, secs) => {
                timings.critical += secs;
                if let Some(l) = located {
                    ends[k].lbar = l.lbar;
                    ends[k].energy = l.energy;
                    ends[k].error_estimate = Some(l.error);
                }
            }
            Done::Crossing(r, secs) => {
                timings.critical += secs;
                match *r {
                    Ok(c) => critical.push(c),
                    // A uniform rod's crossings are all regular: a failure is an error.
                    Err(e) if opts.stiffness.is_uniform() => return Err(e),
                    Err(e) => warnings.push(format!("a crossing was not located: {e}")),
                }
            }
        }
    }
    let great = opts
        .great_circles
        .then(|| buckling::collect_report(opts, circle_results));
    let beyond = |m: u32| -> Option<(u32, String)> {
        match great.as_ref().and_then(|g| g.branch_above(m)) {
            Some(eta) => Some((
                eta,
                format!("found by branch switching from its buckling mode with {eta} periods"),
            )),
            None => Some((
                m + 1,
                "named after the buckling mode with m + 1 periods of Eq. (33); not computed"
                    .to_string(),
            )),
        }
    };
    for c in critical::collapses(opts, &branches, &beyond) {
        progress(Progress::CriticalLocated {
            kind: CriticalKind::Collapse,
            lbar_cr: c.lbar_cr,
            from_branch: c.from_branch,
            to_branch: c.to_branch,
        });
        critical.push(c);
    }
    timings.parallel_wall = t.elapsed().as_secs_f64();
    critical.sort_by(|a, b| a.lbar_cr.total_cmp(&b.lbar_cr));
    for (i, c) in critical.iter_mut().enumerate() {
        c.index = i + 1;
    }
    for w in critical.windows(2) {
        // The same sheet, or sheets that meet at a fold or branch point in between (the
        // lowest state passes continuously from one to the other there), or sheets of one
        // branch (changes of the lowest family within a branch are not exchanges; see
        // `critical::detect_crossings`).
        let connected = match (w[0].to_sheet, w[1].from_sheet) {
            (Some(a), Some(b)) => {
                a == b
                    || branches[a].eta == branches[b].eta
                    || critical::touch(&branches[a], &branches[b], w[0].lbar_cr, w[1].lbar_cr)
            }
            _ => w[0].to_eta == w[1].from_eta,
        };
        if !connected {
            warnings.push(format!(
                "critical lengths {} (L̄ = {:.6}, to branch {}) and {} (L̄ = {:.6}, from branch \
                 {}) do not connect",
                w[0].index,
                w[0].lbar_cr,
                w[0].to_branch,
                w[1].index,
                w[1].lbar_cr,
                w[1].from_branch
            ));
        }
    }

    // Every state verified as its file holds it (rows re-estimated where refined
    // resolutions contradict them), before the labels that compare the energies.
    let threads = opts.worker_threads();
    // A state that fails is not reported: its row leaves the table (the warning says why),
    // so every row of `branches.csv` has a verified file.
    let (mut state_files, state_warnings) = crate::states::verify_all(opts, &mut branches, threads);
    let unverified_states = state_warnings.len();
    warnings.extend(state_warnings);
    for (b, files) in branches.iter_mut().zip(state_files.iter_mut()) {
        let mut keep = files.iter().map(Option::is_some);
        b.points.retain(|_| keep.next().unwrap_or(false));
        files.retain(Option::is_some);
    }
    // Sheets left empty go, and the critical lengths' sheet indices follow the renumbering.
    let mut next = 0;
    let renumber: Vec<Option<usize>> = branches
        .iter()
        .map(|b| {
            (!b.points.is_empty()).then(|| {
                next += 1;
                next - 1
            })
        })
        .collect();
    for c in &mut critical {
        c.from_sheet = c.from_sheet.and_then(|i| renumber[i]);
        c.to_sheet = c.to_sheet.and_then(|i| renumber[i]);
    }
    branches.retain(|b| !b.points.is_empty());
    state_files.retain(|f| !f.is_empty());
    // Labels.
    let t = Instant::now();
    let labels = labels::label_all(&branches, &critical);
    timings.labels = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let shape_tolerance = ShapeTolerances::default();
    let (shapes, shape_warnings) = state_shapes(opts, &branches, shape_tolerance);
    timings.shapes = t.elapsed().as_secs_f64();
    warnings.extend(shape_warnings);
    warnings.extend(no_minimum_warnings(opts, &branches));
    let special = special_points(ends, &branches, &critical);

    for b in &branches {
        for (end, stop) in [(&b.low_end, &b.stop_low), (&b.high_end, &b.stop_high)] {
            if matches!(end, crate::BranchEnd::Failed { .. }) {
                warnings.push(format!("branch {} (η = {}): {stop}", b.branch, b.eta));
            }
        }
    }
    if let Some(g) = &great {
        warnings.extend(g.notes.iter().cloned());
    }
    timings.total = start.elapsed().as_secs_f64();
    let scene = format!(
        "R = {}, {}, {} ≤ L̄ ≤ {}, accuracy {}, tracing with {} cells per period",
        opts.radius,
        opts.stiffness,
        opts.lbar_min,
        opts.lbar_max,
        format!("{:?}", opts.accuracy).to_lowercase(),
        opts.trace_cells_per_period()
    );
    Ok(NumericDiagram {
        accuracy: opts.accuracy,
        scene,
        range: (opts.lbar_min, opts.lbar_max),
        branches,
        labels,
        shapes,
        shape_tolerance,
        critical,
        special,
        great_circles: great,
        warnings,
        timings,
        certificate: None,
        state_files,
        unverified_states,
    })
}

/// The stretches of the range where no traced state has stability index 0 (checked on a
/// grid of step 0.005 and at every traced length; the great-circle lengths themselves and,
/// for a uniform rod, `L̄ < 1` (the circle) are left out), one warning per stretch.
fn no_minimum_warnings(opts: &DiagramOptions, branches: &[TracedBranch]) -> Vec<String> {
    let mut grid: Vec<f64> = Vec::new();
    let n = ((opts.lbar_max - opts.lbar_min) / 0.005).ceil() as usize;
    for k in 0..=n {
        grid.push(opts.lbar_min + (opts.lbar_max - opts.lbar_min) * k as f64 / n.max(1) as f64);
    }
    grid.sort_by(f64::total_cmp);
    let has_minimum = |l: f64| {
        branches.iter().any(|b| {
            b.covers(l) && {
                let k = b.points.partition_point(|p| p.value < l);
                let near = |i: usize| b.points.get(i).map(|p| p.index == 0);
                // Index 0 on both neighbouring states (or the state itself).
                match (k.checked_sub(1).and_then(near), near(k)) {
                    (Some(a), Some(c)) => a && c,
                    (None, Some(c)) => c,
                    (Some(a), None) => a,
                    _ => false,
                }
            }
        })
    };
    let skip = |l: f64| (l - l.round()).abs() < 2e-3 || (opts.stiffness.is_uniform() && l < 1.0);
    let mut out = Vec::new();
    let mut run: Option<(f64, f64)> = None;
    for &l in &grid {
        let bad = !skip(l) && !has_minimum(l);
        match (bad, run) {
            (true, None) => run = Some((l, l)),
            (true, Some((a, _))) => run = Some((a, l)),
            (false, Some((a, b))) => {
                out.push((a, b));
                run = None;
            }
            (false, None) => {}
        }
    }
    if let Some(r) = run {
        out.push(r);
    }
    // With --branch the lowest state may lie on a branch that was not traced.
    let why = match &opts.only_branches {
        Some(only) => format!(
            "only branch(es) {} were traced, so the lowest state there may lie on another branch",
            only.iter()
                .map(|b| b.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
        None => "the lowest state there was not found".to_string(),
    };
    out.into_iter()
        .map(|(a, b)| {
            format!(
                "NO STABLE STATE FOUND: on {a:.4} ≤ L̄ ≤ {b:.4} no traced state has stability index 0 ({why}; labels there are incomplete)"
            )
        })
        .collect()
}

/// Folds and branch points (the ends of sheets), one record per point, with the sheet and
/// end (`true`: low) each was first seen at. Their lengths and energies are the traced ones
/// until [`crate::special::locate_end`] refines them.
fn end_points(branches: &[TracedBranch]) -> (Vec<SpecialPoint>, Vec<(usize, bool)>) {
    let mut out: Vec<SpecialPoint> = Vec::new();
    let mut sources = Vec::new();
    for (bi, b) in branches.iter().enumerate() {
        for (end, at_low) in [(&b.low_end, true), (&b.high_end, false)] {
            let kind = match end {
                crate::BranchEnd::Fold { .. } => SpecialKind::Fold,
                crate::BranchEnd::BranchPoint { .. } => SpecialKind::BranchPoint,
                _ => continue,
            };
            let (p, q) = if at_low {
                (b.points.first(), b.points.get(1))
            } else {
                (
                    b.points.last(),
                    b.points.len().checked_sub(2).and_then(|k| b.points.get(k)),
                )
            };
            let (Some(p), Some(q)) = (p, q) else { continue };
            let value = p.value;
            // One record per point: a fold is the end of two sheets, a branch point of
            // several (located from each within the tracing's width, up to ~1e-5 apart at
            // D1/D0 = 0.5; a pitchfork is a turning point of the asymmetric sheets that end
            // there).
            if let Some(s) = out.iter_mut().find(|s| {
                (s.lbar - value).abs() < 1e-4
                    && (s.energy - p.energy).abs() < 1e-4 * p.energy.abs().max(1.0)
            }) {
                s.index_after = s.index_after.max(q.index);
                s.index_before = s.index_before.min(q.index);
                if kind == SpecialKind::BranchPoint {
                    s.kind = kind;
                }
                continue;
            }
            out.push(SpecialPoint {
                kind,
                lbar: value,
                energy: p.energy,
                error_estimate: None,
                branch: b.branch,
                family: b.family,
                index_before: q.index,
                index_after: q.index,
            });
            sources.push((bi, at_low));
        }
    }
    (out, sources)
}

/// Special points of the diagram: folds and branch points (`ends`, see [`end_points`]),
/// crossings and collapses (the critical lengths), in increasing `L̄`.
fn special_points(
    ends: Vec<SpecialPoint>,
    branches: &[TracedBranch],
    critical: &[CriticalLength],
) -> Vec<SpecialPoint> {
    let mut out = ends;
    // Before/after: the two sides of a fold are its two sheets, the lower index first.
    for c in critical {
        out.push(SpecialPoint {
            kind: match c.kind {
                CriticalKind::Crossing => SpecialKind::Crossing,
                CriticalKind::Collapse => SpecialKind::Collapse,
            },
            lbar: c.lbar_cr,
            energy: c.energy,
            error_estimate: Some(c.error_estimate),
            branch: c.to_branch,
            family: c.to_sheet.map_or(0, |i| branches[i].family),
            index_before: 0,
            index_after: 0,
        });
    }
    out.sort_by(|a, b| a.lbar.total_cmp(&b.lbar));
    out
}

/// Kind of a [`SpecialPoint`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SpecialKind {
    /// A turning point in `L̄` of a followed family (two sheets meet).
    Fold,
    /// A simple branch point: a mirror-symmetric family meets a pair of mirror-image
    /// asymmetric ones (pitchfork).
    BranchPoint,
    /// An exchange of the lowest state between two sheets (`E_a = E_b`).
    Crossing,
    /// The lowest state collapses onto a great circle (`L̄ = m`).
    Collapse,
}

impl SpecialKind {
    /// `fold`, `branch_point`, `crossing` or `collapse`.
    pub fn as_str(self) -> &'static str {
        match self {
            SpecialKind::Fold => "fold",
            SpecialKind::BranchPoint => "branch_point",
            SpecialKind::Crossing => "crossing",
            SpecialKind::Collapse => "collapse",
        }
    }
}

/// A special point of the diagram (`special_points.csv`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SpecialPoint {
    /// What it is.
    pub kind: SpecialKind,
    /// Where.
    pub lbar: f64,
    /// Energy `E R/(π D0)` there.
    pub energy: f64,
    /// Error estimate of `lbar`: folds and branch points located at the reporting
    /// resolutions (`crate::special`), crossings and collapses as in `critical.csv`; `None`
    /// where a fold or branch point is known only to the tracing's width (its re-location
    /// failed).
    pub error_estimate: Option<f64>,
    /// Paper branch (crossings and collapses: the branch lowest above).
    pub branch: u32,
    /// Family within the branch (0: uniform rod, or none).
    pub family: u32,
    /// Stability index on one side (folds and branch points: the smaller of the indices of
    /// the sheets that meet there; crossings and collapses: of the lowest state, 0).
    pub index_before: usize,
    /// Stability index on the other side (the larger).
    pub index_after: usize,
}

fn check_branch(b: &TracedBranch) -> Result<(), DiagramError> {
    let bad = |reason: String| Err(DiagramError::InvalidBranch { eta: b.eta, reason });
    if b.param != rodloop_solver::Param::Lbar {
        return bad(format!("traced in {}, not in lbar", b.param));
    }
    if b.points.is_empty() {
        return bad("no traced states".into());
    }
    let dim = 2 * b.cells + 3 + usize::from(b.phase);
    for (k, p) in b.points.iter().enumerate() {
        if p.state.len() != dim {
            return bad(format!(
                "state {k} has length {} instead of {dim}",
                p.state.len()
            ));
        }
        if !(p.value.is_finite() && p.energy.is_finite() && p.slope.is_finite()) {
            return bad(format!("state {k} has non-finite values"));
        }
        if k > 0 && p.value < b.points[k - 1].value {
            return bad("states are not in increasing L̄".into());
        }
    }
    Ok(())
}
