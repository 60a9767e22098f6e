//! `rodloop diagram --model numeric`: numerical branches traced by pseudo-arclength
//! continuation, critical lengths on re-solved equilibria, stable / metastable / unstable
//! labels from the Hessian index, great-circle buckling loads.
//!
//! Each branch is written to `DIR/branches/branch-B.json` (B the paper's branch number) as
//! soon as it is traced, so that an interrupted run continues with `--resume` from the
//! branches already there (files of older versions, `eta-N.json`, are read too).

use std::path::Path;

use anyhow::{bail, Context, Result};
use rodloop_diagram::{
    BranchHook, DiagramOptions, Engine, NumericDiagram, Origin, PointStates, Progress,
    SurfaceEngine, TracedBranch,
};
use rodloop_exact::branch_of_eta;

use crate::output::{ensure_dir, write_atomic, OutputRun};
use crate::progress::Progress as Bar;

/// File name prefix of the per-branch families files of non-uniform rods
/// (`families-branch-B.json`, written after every sheet file of the branch: its presence
/// means the branch is complete).
const FAMILIES_PREFIX: &str = "families-";

/// Load the branches of an interrupted run (`DIR/branches/*.json`).
fn load_resume(dir: &Path) -> Result<Vec<TracedBranch>> {
    let bdir = dir.join("branches");
    let mut out = Vec::new();
    let Ok(entries) = std::fs::read_dir(&bdir) else {
        return Ok(out);
    };
    for e in entries {
        let path = e?.path();
        let families_file = path
            .file_name()
            .is_some_and(|n| n.to_string_lossy().starts_with(FAMILIES_PREFIX));
        if path.extension().is_some_and(|x| x == "json") && !families_file {
            let text = std::fs::read_to_string(&path)
                .with_context(|| format!("cannot read {}", path.display()))?;
            let b: TracedBranch = serde_json::from_str(&text).with_context(|| {
                format!(
                    "{} is not a branch file of this rodloop version",
                    path.display()
                )
            })?;
            out.push(b);
        }
    }
    Ok(out)
}

/// The CLI's per-branch hook: resume from the branch files of an interrupted run, and write
/// each branch file as soon as its branch is traced.
struct BranchFiles<'a> {
    dir: std::path::PathBuf,
    previous: Vec<TracedBranch>,
    /// `--resume` given.
    resuming: bool,
    bar: &'a Bar,
}

impl BranchHook for BranchFiles<'_> {
    fn resume(&mut self, eta: u32) -> Option<TracedBranch> {
        self.previous.iter().find(|b| b.eta == eta).cloned()
    }

    fn resume_families(&mut self, eta: u32) -> Option<rodloop_diagram::families::Families> {
        if !self.resuming {
            return None;
        }
        let branch = rodloop_exact::branch_of_eta(eta);
        let path = self
            .dir
            .join(format!("{FAMILIES_PREFIX}branch-{branch}.json"));
        let text = std::fs::read_to_string(path).ok()?;
        serde_json::from_str(&text).ok()
    }

    fn finished_families(
        &mut self,
        eta: u32,
        families: &rodloop_diagram::families::Families,
    ) -> std::result::Result<(), rodloop_diagram::BoxError> {
        let branch = rodloop_exact::branch_of_eta(eta);
        let text = serde_json::to_string(families)?;
        write_atomic(
            &self.dir,
            &format!("{FAMILIES_PREFIX}branch-{branch}.json"),
            text.as_bytes(),
        )?;
        // One line (and one bar step) per branch: its families and sheets are parts of it.
        self.bar.done(branch_line(branch, &families.sheets));
        Ok(())
    }

    fn finished(
        &mut self,
        b: &TracedBranch,
        origin: Origin,
    ) -> std::result::Result<(), rodloop_diagram::BoxError> {
        if origin == Origin::Resumed {
            self.bar.done(format!(
                "branch {} resumed ({} states)",
                b.branch,
                b.points.len()
            ));
            return Ok(());
        }
        let text = serde_json::to_string(b)?;
        // A non-uniform rod's branch has several families and sheets, one file each.
        let name = if b.family == 0 {
            format!("branch-{}.json", b.branch)
        } else {
            format!(
                "branch-{}-family-{}-sheet-{}.json",
                b.branch, b.family, b.sheet
            )
        };
        write_atomic(&self.dir, &name, text.as_bytes())?;
        // The file name of older versions (by eta) is superseded.
        let _ = std::fs::remove_file(self.dir.join(format!("eta-{}.json", b.eta)));
        if b.family == 0 {
            self.bar
                .done(branch_line(b.branch, std::slice::from_ref(b)));
        } else {
            // A sheet of a non-uniform rod's branch: the branch's line comes with
            // `finished_families`, once all its sheets are written.
            self.bar.message(format!(
                "branch {} family {} sheet {} written",
                b.branch, b.family, b.sheet
            ));
        }
        Ok(())
    }
}

/// "3 branches" — or "3 branches (7 families, 15 sheets)" for a non-uniform rod, whose
/// branches consist of several traced families and sheets.
pub fn branch_count(traced: &[TracedBranch]) -> String {
    let branches: std::collections::BTreeSet<u32> = traced.iter().map(|b| b.branch).collect();
    let families: std::collections::BTreeSet<(u32, u32)> =
        traced.iter().map(|b| (b.branch, b.family)).collect();
    let words = crate::output::plural(branches.len() as u64, "branch");
    if traced.len() > branches.len() {
        format!(
            "{words} ({}, {})",
            crate::output::plural(families.len() as u64, "family"),
            crate::output::plural(traced.len() as u64, "sheet")
        )
    } else {
        words
    }
}

/// The progress line of one traced branch: its states, and its families and sheets when it
/// has several (a non-uniform rod); the wall time is the branch's (every sheet carries it).
fn branch_line(branch: u32, sheets: &[TracedBranch]) -> String {
    let states: usize = sheets.iter().map(|b| b.points.len()).sum();
    let seconds = sheets.iter().map(|b| b.seconds).fold(0.0, f64::max);
    let families = sheets
        .iter()
        .map(|b| b.family)
        .collect::<std::collections::BTreeSet<_>>()
        .len();
    let parts = if sheets.len() > 1 {
        format!(
            "{}, {}: ",
            crate::output::plural(families as u64, "family"),
            crate::output::plural(sheets.len() as u64, "sheet")
        )
    } else {
        String::new()
    };
    format!(
        "branch {branch} traced ({parts}{}, {seconds:.2} s)",
        crate::output::plural(states as u64, "state")
    )
}

/// Trace every branch with [`rodloop_diagram::compute`] (in parallel), writing each branch
/// file when it is done, resuming from the files already there with `resume`; then assemble.
/// Returns the engine's result (its states, [`PointStates`]) and its schema for `scene`.
pub fn run_numeric(
    opts: &DiagramOptions,
    out: &Path,
    resume: bool,
    quiet: bool,
    selection: Option<&[u32]>,
    scene: &str,
) -> Result<(NumericDiagram, rodloop_schema::Diagram)> {
    let dir = out.join("branches");
    let previous = if resume {
        load_resume(out)?
    } else {
        // A fresh run: the branch files of a previous run (other branches, other settings)
        // are not this run's outputs.
        crate::output::remove_branch_files(out)?;
        Vec::new()
    };
    ensure_dir(&dir)?;
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
    let bar = Bar::new(etas.len() as u64, "branches", quiet);
    bar.set_length(etas.len() as u64);
    let mut hook = BranchFiles {
        dir,
        previous,
        resuming: resume,
        bar: &bar,
    };
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
/// [`crate::draw::draw_diagram`]. Returns the schema written.
pub fn write_outputs(
    d: &(impl PointStates + ?Sized),
    mut schema: rodloop_schema::Diagram,
    opts: &DiagramOptions,
    run: &OutputRun,
) -> Result<rodloop_schema::Diagram> {
    // Every traced state's shape in states/ (cli/states.rs), named in the last column.
    let state_warnings = crate::states::write_point_states(
        d,
        &mut schema,
        opts.radius,
        opts.stiffness.reference(),
        run,
    )?;
    schema
        .warnings
        .get_or_insert_with(Vec::new)
        .extend(state_warnings);
    crate::output::write_diagram(run, &mut schema)?;
    Ok(schema)
}
