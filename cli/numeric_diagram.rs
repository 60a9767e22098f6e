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
    BranchHook, DiagramOptions, Label, NumericDiagram, Origin, Progress, TracedBranch,
};
use rodloop_exact::branch_of_eta;

use crate::output::{
    checked_json, critical_table, ensure_dir, write_atomic, Cell, CriticalRow, OutputRun, Table,
};
use crate::progress::Progress as Bar;
use crate::svg::{self, branch_color, Curve, Figure, LegendEntry, LineStyle, Marker};

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
        self.bar.done(format!(
            "branch {} traced ({} states, {:.2} s)",
            b.branch,
            b.points.len(),
            b.seconds
        ));
        Ok(())
    }
}

/// Trace every branch with [`rodloop_diagram::compute`] (in parallel), writing each branch
/// file when it is done, resuming from the files already there with `resume`; then assemble.
pub fn run_numeric(
    opts: &DiagramOptions,
    out: &Path,
    resume: bool,
    quiet: bool,
    selection: Option<&[u32]>,
) -> Result<NumericDiagram> {
    let dir = out.join("branches");
    ensure_dir(&dir)?;
    let previous = if resume {
        load_resume(out)?
    } else {
        Vec::new()
    };
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
    let result = rodloop_diagram::compute(&opts, &mut hook, &mut |p| match p {
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
    Ok(d)
}

/// Write branches.csv, critical.csv, diagram.svg, summary.json (the summary last).
pub fn write_outputs(
    d: &NumericDiagram,
    opts: &DiagramOptions,
    scene: &str,
    run: &OutputRun,
) -> Result<()> {
    // The common columns first, in the order of the exact model's branches.csv.
    let mut branches = Table::new(
        "branches.csv",
        &[
            "branch",
            "eta",
            "lbar",
            "energy",
            "energy_g",
            "lambda_min",
            "lambda_max",
            "energy_error",
            "stability",
            "index",
            "family",
            "arc",
            "multiplicity",
            "point_group",
            "self_intersections",
            "state_file",
        ],
    );
    // Every traced state's shape in states/ (cli/states.rs), named in the last column.
    let (state_files, state_warnings) = crate::states::write_states(d, opts, run)?;
    // The model works in the scene's R and D; report lambda R^3/D0.
    let lam_unit = opts.radius.powi(3) / opts.stiffness.reference();
    for (r, file) in d.rows().into_iter().zip(state_files) {
        branches.push(vec![
            Cell::I(r.branch.into()),
            Cell::I(r.eta.into()),
            Cell::F(r.lbar),
            Cell::F(r.energy),
            Cell::F(r.energy_g),
            Cell::F(r.lambda_min * lam_unit),
            Cell::F(r.lambda_max * lam_unit),
            match r.energy_error {
                Some(e) => Cell::F(e),
                None => Cell::S(String::new()),
            },
            Cell::S(r.stability.as_str().into()),
            Cell::I(r.index as i64),
            Cell::I(r.family.into()),
            Cell::I(r.arc as i64),
            Cell::I(r.multiplicity.into()),
            Cell::S(r.shape.point_group.clone().unwrap_or_default()),
            Cell::S(r.shape.self_intersections_label()),
            Cell::S(file),
        ])?;
    }
    let special =
        crate::output::special_table(d.special.iter().map(|p| crate::output::SpecialRow {
            kind: p.kind.as_str().into(),
            lbar: p.lbar,
            energy: p.energy,
            branch: p.branch,
            family: p.family,
            index_before: p.index_before,
            index_after: p.index_after,
            error_estimate: p.error_estimate,
        }))?;
    let critical = critical_table(d.critical.iter().map(CriticalRow::from))?;
    run.write_table(&branches)?;
    run.write_table(&critical)?;
    run.write_table(&special)?;
    run.write_bytes("diagram.svg", svg::render(&figure(d, scene)).as_bytes())?;
    let ends = d
        .branches
        .iter()
        .map(|b| {
            checked_json!({
                "branch": b.branch, "eta": b.eta, "family": b.family, "sheet": b.sheet,
                "multiplicity": b.multiplicity, "span": [b.span().0, b.span().1],
                "states": b.points.len(), "cells": b.cells,
                "low_end": b.stop_low, "high_end": b.stop_high, "seed": b.seed, "seconds": b.seconds,
            })
        })
        .collect::<Result<Vec<_>>>()?;
    let summary = checked_json!({
        "model": "numeric",
        "scene": scene,
        "description": d.scene,
        "accuracy": format!("{:?}", opts.accuracy).to_lowercase(),
        "lbar_min": opts.lbar_min,
        "lbar_max": opts.lbar_max,
        "critical": d.critical,
        "special_points": d.special,
        "branches": ends,
        "great_circles": d.great_circles,
        "shape_tolerance": d.shape_tolerance,
        "states_dir": "states",
        "warnings": d.warnings.iter().chain(&state_warnings).collect::<Vec<_>>(),
        "timings": d.timings,
        "certificate": d.certificate,
        "units": crate::diagram::UNITS,
    })?;
    run.write_json("summary.json", &crate::output::strip_nulls(summary))?;
    Ok(())
}

fn style_of(l: Label) -> (LineStyle, f64) {
    match l {
        Label::Stable => (LineStyle::Solid, 2.2),
        Label::Metastable => (LineStyle::Dashed, 1.4),
        Label::Unstable => (LineStyle::Dotted, 1.4),
    }
}

/// Energy versus length: one colour per branch; solid stable, dashed metastable, dotted
/// unstable; critical lengths marked (the paper's Fig. 3a).
fn figure(d: &NumericDiagram, scene: &str) -> Figure {
    let mut curves = Vec::new();
    for (b, labels) in d.branches.iter().zip(&d.labels) {
        // (lbar, energy, label) with a point inserted at every critical length where the label
        // changes between two samples, so that the line style switches there and not at the
        // next traced state.
        let mut pts: Vec<(f64, f64, Label)> = Vec::new();
        for (k, p) in b.points.iter().enumerate() {
            if k > 0 && labels[k] != labels[k - 1] {
                let q = &b.points[k - 1];
                if let Some(c) = d
                    .critical
                    .iter()
                    .find(|c| c.lbar_cr > q.value.min(p.value) && c.lbar_cr < q.value.max(p.value))
                {
                    let t = (c.lbar_cr - q.value) / (p.value - q.value);
                    let e = q.energy + t * (p.energy - q.energy);
                    pts.push((c.lbar_cr, e, labels[k - 1]));
                    pts.push((c.lbar_cr, e, labels[k]));
                }
            }
            pts.push((p.value, p.energy, labels[k]));
        }
        curves.extend(svg::runs(&pts, |label, points| {
            let (style, width) = style_of(label);
            Curve {
                color: branch_color(b.branch),
                style,
                width,
                points,
            }
        }));
    }
    let mut order: Vec<&TracedBranch> = d.branches.iter().collect();
    order.sort_by_key(|b| b.branch);
    let mut legend: Vec<LegendEntry> = order
        .into_iter()
        .map(|b| LegendEntry {
            label: format!("branch {} (eta = {})", b.branch, b.eta),
            color: branch_color(b.branch),
            style: LineStyle::Solid,
        })
        .collect();
    for (label, style) in [
        ("stable", LineStyle::Solid),
        ("metastable", LineStyle::Dashed),
        ("unstable", LineStyle::Dotted),
    ] {
        legend.push(LegendEntry {
            label: label.into(),
            color: "black".into(),
            style,
        });
    }
    Figure {
        title: format!("Numeric branches ({scene}): bending energy E R/(pi D0)"),
        xlabel: "L / (2 pi R)".into(),
        ylabel: "E R/(pi D0)".into(),
        curves,
        markers: d
            .critical
            .iter()
            .map(|c| Marker {
                x: c.lbar_cr,
                label: format!("{:.4}", c.lbar_cr),
            })
            .collect(),
        legend,
        range: None,
    }
}
