//! [`assemble`]: everything after tracing, in steps: the crossings, great circles and
//! sheets' ends located in parallel, the collapses added, the critical lengths numbered and
//! checked for connection, every state verified against its file, then labels, shapes,
//! special points and warnings.

use std::time::Instant;

use super::points::{end_points, special_points, SpecialPoint};
use super::{NumericDiagram, Timings};
use crate::buckling::{self, BucklingReport};
use crate::critical::{self, CriticalKind, CriticalLength};
use crate::labels;
use crate::parallel::run_parallel;
use crate::shapes::state_shapes;
use crate::types::TracedBranch;
use crate::{DiagramError, DiagramOptions, Progress};
use rodloop_exact::shape::ShapeTolerances;

/// Work of the assembly phase.
enum Task {
    Circle(u32),
    Crossing(critical::Candidate),
    /// A fold or branch point (index into the end points) at a sheet's end (sheet, whether
    /// the low end), located at the fine (`true`) or coarse reporting resolution.
    End(usize, usize, bool, bool),
}

/// Result of a [`Task`] with its duration.
enum Done {
    Circle(u32, buckling::CircleResult, f64),
    Crossing(Box<Result<CriticalLength, DiagramError>>, f64),
    /// The location `(L̄, E)` of end `k` at the fine (`true`) or coarse resolution.
    End(usize, bool, Option<(f64, f64)>, f64),
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
    let Located {
        mut critical,
        circle_results,
        ends,
        mut warnings,
    } = locate_in_parallel(opts, &branches, &mut timings, progress)?;
    let great = opts
        .great_circles
        .then(|| buckling::collect_report(opts, circle_results));
    add_collapses(opts, &branches, great.as_ref(), &mut critical, progress);
    timings.parallel_wall = t.elapsed().as_secs_f64();
    number_and_connect(&branches, &mut critical, &mut warnings);

    let (state_files, unverified_states) =
        keep_verified(opts, &mut branches, &mut critical, &mut warnings);
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

    warnings.extend(failed_end_warnings(&branches));
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

/// What the parallel phase of [`assemble`] finds: the located crossings, the great circles'
/// analyses, the sheets' ends (re-located where possible) and the warnings so far.
struct Located {
    critical: Vec<CriticalLength>,
    circle_results: Vec<(u32, buckling::CircleResult)>,
    ends: Vec<SpecialPoint>,
    warnings: Vec<String>,
}

/// The crossings between traced samples located on re-solved equilibria, the great circles
/// analysed and the sheets' ends re-located, as one parallel task list (times added to
/// `timings`). A crossing of a uniform rod that cannot be located is an error; of a
/// two-segment rod a warning.
fn locate_in_parallel(
    opts: &DiagramOptions,
    branches: &[TracedBranch],
    timings: &mut Timings,
    progress: &mut dyn FnMut(Progress),
) -> Result<Located, DiagramError> {
    let (candidates, mut warnings) = critical::detect_crossings(opts, branches);
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
    let (mut ends, end_sources) = end_points(branches);
    let mut tasks: Vec<Task> = circles.into_iter().map(Task::Circle).collect();
    tasks.extend(candidates.into_iter().map(Task::Crossing));
    // Each end at its two reporting resolutions as two tasks (the finer first: the threads
    // share out the marches more evenly than whole ends).
    let end_cells: Vec<(usize, usize)> = end_sources
        .iter()
        .map(|&(sheet, _)| crate::special::end_cells(opts, &branches[sheet]))
        .collect();
    for fine in [true, false] {
        tasks.extend(
            end_sources
                .iter()
                .enumerate()
                .map(|(k, &(sheet, at_low))| Task::End(k, sheet, at_low, fine)),
        );
    }
    let mut at_cells: Vec<[Option<(f64, f64)>; 2]> = vec![[None, None]; end_sources.len()];
    let results = run_parallel(
        opts.worker_threads(),
        tasks,
        progress,
        &mut |_| {},
        |task, tx| {
            let t = Instant::now();
            match task {
                Task::Circle(m) => {
                    let r = buckling::analyse_circle(opts, m, branches);
                    tx(Progress::GreatCircleDone {
                        m,
                        total: total_circles,
                    });
                    Done::Circle(m, r, t.elapsed().as_secs_f64())
                }
                Task::Crossing(cand) => {
                    let r = critical::locate_crossing(opts, branches, &cand);
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
                Task::End(k, sheet, at_low, fine) => {
                    let (nf, nc) = end_cells[k];
                    let cells = if fine { nf } else { nc };
                    let r = crate::special::locate_end_at(opts, &branches[sheet], at_low, cells);
                    Done::End(k, fine, r, t.elapsed().as_secs_f64())
                }
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
            Done::End(k, fine, located, secs) => {
                timings.critical += secs;
                at_cells[k][usize::from(!fine)] = located;
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
    for (k, at) in at_cells.into_iter().enumerate() {
        if let [Some(f), Some(c)] = at {
            let l = crate::special::extrapolate_end(end_cells[k], f, c);
            ends[k].lbar = l.lbar;
            ends[k].energy = l.energy;
            ends[k].error_estimate = Some(l.error);
        }
    }
    Ok(Located {
        critical,
        circle_results,
        ends,
        warnings,
    })
}

/// The collapses onto the great circles (named after the branch found by switching from the
/// buckling mode above, where the great circles were analysed) added to `critical`.
fn add_collapses(
    opts: &DiagramOptions,
    branches: &[TracedBranch],
    great: Option<&BucklingReport>,
    critical: &mut Vec<CriticalLength>,
    progress: &mut dyn FnMut(Progress),
) {
    let beyond = |m: u32| -> Option<(u32, String)> {
        match great.and_then(|g| g.branch_above(m)) {
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
    for c in critical::collapses(opts, branches, &beyond) {
        progress(Progress::CriticalLocated {
            kind: CriticalKind::Collapse,
            lbar_cr: c.lbar_cr,
            from_branch: c.from_branch,
            to_branch: c.to_branch,
        });
        critical.push(c);
    }
}

/// The critical lengths sorted and numbered, with a warning for each consecutive pair that
/// does not connect.
fn number_and_connect(
    branches: &[TracedBranch],
    critical: &mut [CriticalLength],
    warnings: &mut Vec<String>,
) {
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
}

/// Every state verified as its file holds it (rows re-estimated where refined resolutions
/// contradict them), before the labels that compare the energies; the files of the kept
/// states and the number left out.
fn keep_verified(
    opts: &DiagramOptions,
    branches: &mut Vec<TracedBranch>,
    critical: &mut [CriticalLength],
    warnings: &mut Vec<String>,
) -> (Vec<Vec<Option<crate::StateFile>>>, usize) {
    let threads = opts.worker_threads();
    // A state that fails is not reported: its row leaves the table (the warning says why),
    // so every row of `branches.csv` has a verified file.
    let (mut state_files, state_warnings, unverified_states) =
        crate::states::verify_all(opts, branches, threads);
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
    for c in critical.iter_mut() {
        c.from_sheet = c.from_sheet.and_then(|i| renumber[i]);
        c.to_sheet = c.to_sheet.and_then(|i| renumber[i]);
    }
    branches.retain(|b| !b.points.is_empty());
    state_files.retain(|f| !f.is_empty());
    (state_files, unverified_states)
}

/// A warning for every branch end where the tracing failed.
fn failed_end_warnings(branches: &[TracedBranch]) -> Vec<String> {
    let mut warnings = Vec::new();
    for b in branches {
        for (end, stop) in [(&b.low_end, &b.stop_low), (&b.high_end, &b.stop_high)] {
            if matches!(end, crate::BranchEnd::Failed { .. }) {
                warnings.push(format!("branch {} (η = {}): {stop}", b.branch, b.eta));
            }
        }
    }
    warnings
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
