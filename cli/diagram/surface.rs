//! `rodloop diagram --model numeric`: numerical branches traced by pseudo-arclength
//! continuation, critical lengths on re-solved equilibria, stable / metastable / unstable
//! labels from the Hessian index, great-circle buckling loads.
//!
//! Each branch is written to `DIR/branches/branch-B.json` (B the paper's branch number) as
//! soon as it is traced ([`rodloop_diagram::BranchFiles`]), so that an interrupted run
//! continues with `--resume` from the branches already there; this module prints its events
//! as progress lines.

use std::path::Path;

use anyhow::{bail, Result};
use rodloop_diagram::representative::Representatives;
use rodloop_diagram::{
    BranchFileEvent, BranchFiles, DiagramOptions, Engine, PointStates, Progress, SurfaceEngine,
};
use rodloop_exact::branch_of_eta;

use crate::output::{ensure_dir, OutputRun};
use crate::progress::Progress as Bar;

/// "3 branches" — or "3 branches (7 families, 15 sheets)" for a non-uniform rod, whose
/// branches consist of several traced families and sheets (the schema's `curves`).
pub fn branch_count(curves: &[rodloop_schema::Curve]) -> String {
    let branches: std::collections::BTreeSet<u32> = curves.iter().map(|b| b.branch).collect();
    let families: std::collections::BTreeSet<(u32, u32)> =
        curves.iter().map(|b| (b.branch, b.family)).collect();
    let words = crate::output::plural(branches.len() as u64, "branch");
    if curves.len() > branches.len() {
        format!(
            "{words} ({}, {})",
            crate::output::plural(families.len() as u64, "family"),
            crate::output::plural(curves.len() as u64, "sheet")
        )
    } else {
        words
    }
}

/// The wall time of stage `key` of a diagram's schema (`timings`; 0 where absent).
pub fn seconds(d: &rodloop_schema::Diagram, key: &str) -> f64 {
    d.timings
        .as_ref()
        .and_then(|t| t.get(key))
        .copied()
        .unwrap_or_default()
}

/// The engine's warnings of a written diagram: all but its last `state_warnings` (those of
/// states without a file, added when the states were written).
pub fn engine_warnings(d: &rodloop_schema::Diagram, state_warnings: usize) -> &[String] {
    let w = d.warnings.as_deref().unwrap_or_default();
    &w[..w.len().saturating_sub(state_warnings)]
}

/// The progress line of a saved or resumed branch: its states, and its families and sheets
/// when it has several (a non-uniform rod), with its wall time.
fn branch_line(e: &BranchFileEvent) -> String {
    match *e {
        BranchFileEvent::Resumed { branch, states } => {
            format!("branch {branch} resumed ({states} states)")
        }
        BranchFileEvent::Traced {
            branch,
            families,
            sheets,
            states,
            seconds,
        } => {
            let parts = if sheets > 1 {
                format!(
                    "{}, {}: ",
                    crate::output::plural(families as u64, "family"),
                    crate::output::plural(sheets as u64, "sheet")
                )
            } else {
                String::new()
            };
            format!(
                "branch {branch} traced ({parts}{}, {seconds:.2} s)",
                crate::output::plural(states as u64, "state")
            )
        }
        BranchFileEvent::SheetSaved {
            branch,
            family,
            sheet,
        } => format!("branch {branch} family {family} sheet {sheet} written"),
    }
}

/// Trace every branch with [`rodloop_diagram::compute`] (in parallel), writing each branch
/// file when it is done, resuming from the files already there with `resume`; then assemble.
/// Returns the engine's result (its states for `states/`, [`PointStates`], and for the
/// report's representative solves, [`Representatives`]) and its schema for `scene`.
pub fn run_numeric(
    opts: &DiagramOptions,
    out: &Path,
    resume: bool,
    quiet: bool,
    selection: Option<&[u32]>,
    scene: &str,
) -> Result<(impl PointStates + Representatives, rodloop_schema::Diagram)> {
    // The progress bar outlives the hook that reports to it.
    let bar: Bar;
    let mut hook = BranchFiles::open(out, resume)?;
    if !resume {
        // A fresh run: the branch files of a previous run (other branches, other settings)
        // are not this run's outputs.
        crate::output::remove_branch_files(out)?;
    }
    ensure_dir(&out.join("branches"))?;
    let opts = DiagramOptions {
        only_branches: selection.map(<[u32]>::to_vec),
        ..opts.clone()
    };
    let etas = opts.etas();
    if etas.is_empty() {
        bail!(
            "no branch meets the length range [{}, {}]",
            opts.lbar_min,
            opts.lbar_max
        );
    }
    bar = Bar::new(etas.len() as u64, "branches", quiet);
    bar.set_length(etas.len() as u64);
    // One line (and one bar step) per branch; a sheet of a non-uniform rod's branch is a
    // message until all its sheets are written.
    hook.on_event(|e| match e {
        BranchFileEvent::SheetSaved { .. } => bar.message(branch_line(&e)),
        _ => bar.done(branch_line(&e)),
    });
    // Progress: branches re-traced because their files do not match are named in one note;
    // the critical lengths get a bar of their own once the tracing is done.
    let mut retrace: Vec<u32> = Vec::new();
    let mut critical_bar: Option<Bar> = None;
    let note = |retrace: &mut Vec<u32>| {
        if !retrace.is_empty() {
            eprintln!(
                "note: --resume: the saved branch files of {} were traced with other settings (scene, range or accuracy); re-tracing them",
                retrace
                    .iter()
                    .map(|b| format!("branch {b}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            );
            retrace.clear();
        }
    };
    let mut engine = SurfaceEngine {
        opts,
        hook: &mut hook,
    };
    let result = engine.run(&mut |p| match p {
        Progress::BranchResumeRejected { eta, .. } => retrace.push(branch_of_eta(eta)),
        Progress::BranchStarted { branch, .. } => {
            note(&mut retrace);
            bar.message(format!("tracing branch {branch}"))
        }
        Progress::BranchFailed { eta, .. } => {
            bar.done(format!("branch {} failed", branch_of_eta(eta)))
        }
        Progress::AssemblyPlanned { .. } => {
            note(&mut retrace);
            bar.finish();
            critical_bar = Some(Bar::new(1, "critical", quiet));
        }
        Progress::CriticalLocated { lbar_cr, kind, .. } => {
            if let Some(b) = &critical_bar {
                b.message(format!("{kind} at {lbar_cr:.9}"));
            }
        }
        Progress::Planned { .. } | Progress::BranchResumed { .. } => {}
        _ => note(&mut retrace),
    });
    note(&mut retrace);
    bar.finish();
    let d = result.map_err(|e| match e {
        rodloop_diagram::DiagramError::InvalidOptions(m) if m.starts_with("no branch could") => {
            anyhow::anyhow!(m)
        }
        e => e.into(),
    })?;
    if let Some(b) = critical_bar {
        b.done(format!(
            "critical lengths located ({} found)",
            d.critical.len()
        ));
        b.finish();
    }
    let schema = engine.schema(&d, scene)?;
    Ok((d, schema))
}

/// Write states/ and the diagram's files in the result schema (branches.csv, critical.csv,
/// special_points.csv, summary.json); the figures are drawn from these files by
/// [`crate::draw::draw_diagram`]. Returns the schema written and the number of its warnings
/// that are those of states without a file (its last ones).
pub fn write_outputs(
    d: &(impl PointStates + ?Sized),
    mut schema: rodloop_schema::Diagram,
    opts: &DiagramOptions,
    run: &OutputRun,
) -> Result<(rodloop_schema::Diagram, usize)> {
    // Every traced state's shape in states/ (cli/states.rs), named in the last column.
    let state_warnings = crate::states::write_point_states(
        d,
        &mut schema,
        opts.radius,
        opts.stiffness.reference(),
        run,
    )?;
    let written = state_warnings.len();
    schema
        .warnings
        .get_or_insert_with(Vec::new)
        .extend(state_warnings);
    crate::output::write_diagram(run, &mut schema)?;
    Ok((schema, written))
}
