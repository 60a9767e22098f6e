//! `rodloop diagram` for enclosed scenes (`|r| ≤ R`, paper Sec. 3.2): the
//! engine is `rodloop_diagram::enclosed` (attached parts from the exact layer, lifted-off
//! parts from the 3-D model, events where `λ_min` crosses zero, exchanges re-solved where a
//! branch has lifted off); non-uniform rods from their surface families.

use std::path::Path;

use anyhow::{bail, Context, Result};
use rodloop_diagram::enclosed::{
    enclosed_diagram_with, EnclosedDiagram, EnclosedDiagramOptions, EnclosedProgress,
};
use rodloop_figures::raster::svg_to_png;
use rodloop_scene::{Confinement, Scene};

use crate::diagram::{Args, Model};
use crate::output::{checked_json, critical_table, Cell, CriticalRow, OutputRun, Table};

/// The scene of `path` when it is an enclosed scene (the default scene is a surface one).
pub fn enclosed_scene(path: Option<&Path>) -> Result<Option<Scene>> {
    let Some(p) = path else { return Ok(None) };
    let scene = Scene::from_file(p)?;
    Ok((scene.confinement == Confinement::Enclosed).then_some(scene))
}

/// Run `rodloop diagram` on an enclosed scene.
pub fn run(args: &Args, scene: &Scene) -> Result<()> {
    if args.model == Model::Exact {
        bail!(
            "--model exact does not apply to enclosed scenes: the enclosed diagram uses the exact layer where a branch is attached and the 3-D enclosed model where it has lifted off (omit --model)"
        );
    }
    if args.resume
        || args.max_step.is_some()
        || args.min_step.is_some()
        || args.max_points.is_some()
        || args.newton_tol.is_some()
    {
        bail!(
            "--resume, --max-step, --min-step, --max-points and --newton-tol control the surface tracer; the enclosed diagram samples every --step in lbar (default 0.05) and traces lifted-off parts by natural-parameter steps"
        );
    }
    let lbar_min = args.lbar_min.unwrap_or(scene.lbar_min);
    let lbar_max = args.lbar_max.unwrap_or(scene.lbar_max);
    if !(lbar_min > 0.0 && lbar_max > lbar_min && lbar_max <= 20.0) {
        bail!("need 0 < --lbar-min < --lbar-max <= 20 for an enclosed diagram (got {lbar_min} and {lbar_max})");
    }
    let accuracy = crate::solve::accuracy_of(scene, args.accuracy.as_deref())?;
    let mut opts = EnclosedDiagramOptions::new(
        scene.radius,
        crate::solve::stiffness_of(&scene.stiffness),
        lbar_min,
        lbar_max,
    );
    opts.accuracy = accuracy;
    if let Some(step) = args.step {
        opts.step = step;
    }
    if !args.branch.is_empty() {
        let mut sel = Vec::new();
        for &b in &args.branch {
            let b = u32::try_from(b).with_context(|| format!("--branch {b}"))?;
            let ok = if b == 0 {
                lbar_min <= 1.0
            } else {
                let e = f64::from(rodloop_exact::eta_of_branch(b));
                e - 1.0 < lbar_max && e + 1.0 > lbar_min
            };
            if !ok {
                bail!("--branch {b}: no such branch in the length range [{lbar_min}, {lbar_max}] (branch 0 is the circle, lbar <= 1)");
            }
            sel.push(b);
        }
        opts.branches = Some(sel);
    }
    let run = OutputRun::begin(&args.out)?;
    // Progress on stderr (cli/progress.rs): a bar on a terminal, one line per task otherwise.
    let bar = crate::progress::Progress::new(0, "enclosed", args.quiet);
    let mut planned = 0u64;
    let d = enclosed_diagram_with(&opts, &mut |p| match p {
        EnclosedProgress::Planned(n) => {
            planned += n as u64;
            bar.set_length(planned);
        }
        EnclosedProgress::Done(msg) => bar.done(msg),
    })
    .context("the enclosed diagram")?;
    bar.finish();
    // The completeness certificate (the same search `solve` runs) goes into summary.json.
    let cert = certificate(&d, scene, &opts);
    write_outputs(&d, &opts, &scene.name, &run, args)?;
    let mut summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(run.stage_dir().join("summary.json"))?)?;
    summary["certificate"] = serde_json::to_value(&cert)?;
    run.write_json("summary.json", &summary)?;
    if args.shapes > 0 {
        // The branch atlas (cli/atlas.rs): states re-solved along each branch, in states/.
        crate::atlas::write_enclosed_atlas(&run, args.shapes, scene, accuracy, &d)?;
    }
    run.commit()?;
    print(&d, scene, &opts, &args.out);
    print_certificate(&cert);
    Ok(())
}

/// One check of the completeness certificate: `solve`'s state of a branch at the length
/// of a lowest state of the diagram.
#[derive(Clone, Debug, serde::Serialize)]
pub(crate) struct CertificateCheck {
    /// `L̄` (that of the diagram's lowest state).
    lbar: f64,
    /// The branch `solve` was asked for.
    branch: u32,
    /// `solve`'s energy and error estimate (`None` where it found no state).
    solve_energy: Option<(f64, f64)>,
    /// The diagram's lowest state there: branch, family, energy, error estimate.
    lowest: (u32, u32, f64, f64),
    /// `solve`'s state lies below the lowest state by more than the two estimates.
    below: bool,
    /// Why `solve` found no state (empty otherwise).
    note: String,
}

/// Lowest states at which the certificate runs `solve`: three, spread over the range.
const CERTIFICATE_SAMPLES: usize = 3;

/// The completeness certificate of a non-uniform rod's diagram: at the lengths of
/// [`CERTIFICATE_SAMPLES`] lowest states of the diagram spread over its range, `solve`'s
/// search (surface loop of each branch that exists there, then the enclosed loop from it,
/// cli/enclosed.rs) for every selected branch; a state of `solve` below the diagram's lowest
/// one by more than the two error estimates is a state the diagram missed. (A uniform rod's
/// diagram and `solve` start from the same exact surface loops: no check there.)
fn certificate(
    d: &EnclosedDiagram,
    scene: &Scene,
    opts: &EnclosedDiagramOptions,
) -> Vec<CertificateCheck> {
    if opts.stiffness.is_uniform() {
        return Vec::new();
    }
    let mut lowest: Vec<_> = d
        .points
        .iter()
        .filter(|p| p.lowest && p.branch > 0)
        .collect();
    lowest.sort_by(|a, b| a.lbar.total_cmp(&b.lbar));
    if lowest.is_empty() {
        return Vec::new();
    }
    let n = lowest.len();
    let mut picks: Vec<usize> = (0..CERTIFICATE_SAMPLES)
        .map(|i| ((2 * i + 1) * n / (2 * CERTIFICATE_SAMPLES)).min(n - 1))
        .collect();
    picks.dedup();
    let wanted = |b: u32| opts.branches.as_ref().is_none_or(|s| s.contains(&b));
    let mut jobs = Vec::new();
    for &i in &picks {
        let p = lowest[i];
        let top = p.lbar.floor() as u32 + 1;
        for eta in 1..=top {
            let e = f64::from(eta);
            let branch = rodloop_exact::branch_of_eta(eta);
            if p.lbar > e - 1.0 && p.lbar < e + 1.0 && wanted(branch) {
                jobs.push((p, branch));
            }
        }
    }
    let stiffness = opts.stiffness.clone();
    crate::states::parallel_map(&jobs, |&(p, branch)| {
        let lowest = (p.branch, p.family, p.energy, p.energy_error);
        match crate::enclosed::solve_state(scene, &stiffness, p.lbar, branch, opts.accuracy) {
            Ok(res) => {
                let (e, err) = res.energy;
                CertificateCheck {
                    lbar: p.lbar,
                    branch,
                    solve_energy: Some((e, err)),
                    lowest,
                    below: e + err < p.energy - p.energy_error,
                    note: String::new(),
                }
            }
            Err(e) => CertificateCheck {
                lbar: p.lbar,
                branch,
                solve_energy: None,
                lowest,
                below: false,
                note: format!("{e:#}"),
            },
        }
    })
}

/// One line per length of the certificate, a warning per state below the diagram's.
fn print_certificate(cert: &[CertificateCheck]) {
    let mut xs: Vec<f64> = cert.iter().map(|c| c.lbar).collect();
    xs.dedup();
    for x in xs {
        let here: Vec<_> = cert.iter().filter(|c| c.lbar == x).collect();
        let (b, f, e, de) = here[0].lowest;
        let found: Vec<String> = here
            .iter()
            .map(|c| match c.solve_energy {
                Some((v, err)) => format!("branch {} {v:.10} ± {err:.1e}", c.branch),
                None => format!("branch {} none", c.branch),
            })
            .collect();
        outln!(
            "  certificate at lbar = {x:.6}: lowest branch {b} family {f}, E R/(pi D) = {e:.10} ± {de:.1e}; solve finds {}",
            found.join(", ")
        );
        for c in here.iter().filter(|c| c.below) {
            if let Some((v, err)) = c.solve_energy {
                eprintln!(
                    "warning: solve finds branch {} at lbar = {x:.6} with E R/(pi D) = {v:.10} ± {err:.1e}, below the diagram's lowest state ({e:.10} ± {de:.1e}): the diagram missed it",
                    c.branch
                );
            }
        }
    }
}

pub(crate) fn write_outputs(
    d: &EnclosedDiagram,
    opts: &EnclosedDiagramOptions,
    scene: &str,
    run: &OutputRun,
    args: &Args,
) -> Result<()> {
    let mut branches = Table::new(
        "branches.csv",
        &[
            "branch",
            "eta",
            "lbar",
            "energy",
            "energy_error",
            "attached",
            "contact_fraction",
            "contact_intervals",
            "max_gap",
            "lambda_min",
            "gap_min",
            "complementarity",
            "stationarity",
            "index",
            "label",
            "lowest",
            "cells",
            "source",
            "family",
            "sheet",
            "multiplicity",
            "surface_energy",
            "state_file",
        ],
    );
    // Every point's loop in states/ (cli/states.rs), named in the last column.
    let (state_files, state_warnings) =
        crate::states::write_enclosed_states(d, opts.radius, opts.stiffness.reference(), run)?;
    for w in &state_warnings {
        eprintln!("warning: {w}");
    }
    for (p, file) in d.points.iter().zip(&state_files) {
        branches.push(vec![
            Cell::I(p.branch.into()),
            Cell::I(p.eta.into()),
            Cell::F(p.lbar),
            Cell::F(p.energy),
            Cell::F(p.energy_error),
            Cell::I(p.attached.into()),
            Cell::F(p.contact_fraction),
            Cell::I(p.contact_intervals as i64),
            Cell::F(p.max_gap),
            Cell::F(p.lambda_min),
            Cell::F(p.gap_min),
            Cell::F(p.complementarity),
            Cell::F(p.stationarity),
            Cell::I(p.index as i64),
            Cell::S(p.label.as_str().into()),
            Cell::I(p.lowest.into()),
            Cell::I(p.cells as i64),
            Cell::S(
                serde_json::to_value(p.source)?
                    .as_str()
                    .unwrap_or("")
                    .to_string(),
            ),
            Cell::I(p.family.into()),
            Cell::I(p.sheet.into()),
            Cell::I(p.multiplicity.into()),
            p.surface_energy.map_or(Cell::S(String::new()), Cell::F),
            Cell::S(file.clone()),
        ])?;
    }
    // critical.csv has the surface diagram's columns; the surface values and the methods
    // are in summary.json.
    let critical = critical_table(d.critical.iter().map(|c| CriticalRow::from(&c.critical)))?;
    let special =
        crate::output::special_table(d.events.iter().map(|e| crate::output::SpecialRow {
            kind: e.kind.as_str().into(),
            lbar: e.lbar,
            energy: e.energy,
            branch: e.branch,
            family: e.family,
            index_before: e.index_before,
            index_after: e.index_after,
            error_estimate: Some(e.error_estimate),
        }))?;
    run.write_table(&branches)?;
    run.write_table(&critical)?;
    run.write_table(&special)?;
    // The figure from the staged CSV files, as `rodloop draw` and `report` draw it (real
    // symbols, the lifted-off band, lift-off/landing and critical markers).
    let data = rodloop_figures::diagram::DiagramData::read(run.stage_dir())?;
    let text = rodloop_figures::diagram::energy_figure(
        &data,
        f64::from(args.width),
        f64::from(args.height),
    )?;
    run.write_bytes("diagram.svg", text.as_bytes())?;
    let png = svg_to_png(&text, 1.0).context("rendering diagram.png")?;
    run.write_bytes("diagram.png", &png)?;
    // With --branch, "lowest" is among the selected branches only: no hypothesis verdict.
    let lowest_lifted = opts.branches.is_none().then(|| lowest_lifted_off(d));
    let summary = checked_json!({
        "model": "enclosed",
        "scene": scene,
        "lbar_min": opts.lbar_min,
        "lbar_max": opts.lbar_max,
        "accuracy": format!("{:?}", opts.accuracy).to_lowercase(),
        "step": opts.step,
        "states": d.points.len(),
        "critical": d.critical,
        "special_points": d.events,
        "lowest_lifted_off": lowest_lifted,
        "cells": d.cells,
        "warnings": d.warnings.iter().chain(&state_warnings).collect::<Vec<_>>(),
        "states_dir": "states",
        "unverified_states": state_files.iter().filter(|f| f.is_empty()).count(),
        "notes": d.notes,
        "timings": d.seconds,
        "units": crate::diagram::UNITS,
    })?;
    run.write_json("summary.json", &summary)?;
    Ok(())
}

/// The `L̄` intervals where the lowest state is a paper branch that has lifted off (branch
/// 0, the free circle below `L̄ = 1`, is not counted): from each critical length or event to
/// the next, when the lowest branch there is lifted off at the samples between.
pub(crate) fn lowest_lifted_off(d: &EnclosedDiagram) -> Vec<(f64, f64)> {
    let mut cuts: Vec<f64> = d
        .critical
        .iter()
        .map(|c| c.critical.lbar_cr)
        .chain(
            d.events
                .iter()
                .filter(|e| {
                    matches!(
                        e.kind,
                        rodloop_diagram::enclosed::EventKind::LiftOff
                            | rodloop_diagram::enclosed::EventKind::Landing
                    )
                })
                .map(|e| e.lbar),
        )
        .collect();
    cuts.push(
        d.points
            .iter()
            .map(|p| p.lbar)
            .fold(f64::INFINITY, f64::min),
    );
    cuts.push(
        d.points
            .iter()
            .map(|p| p.lbar)
            .fold(f64::NEG_INFINITY, f64::max),
    );
    cuts.sort_by(f64::total_cmp);
    cuts.dedup_by(|a, b| (*a - *b).abs() < 1e-12);
    let mut out: Vec<(f64, f64)> = Vec::new();
    for w in cuts.windows(2) {
        let inside: Vec<_> = d
            .points
            .iter()
            .filter(|p| p.lowest && p.branch > 0 && p.lbar > w[0] + 1e-9 && p.lbar < w[1] - 1e-9)
            .collect();
        if !inside.is_empty() && inside.iter().all(|p| !p.attached) {
            match out.last_mut() {
                Some(last) if (last.1 - w[0]).abs() < 1e-12 => last.1 = w[1],
                _ => out.push((w[0], w[1])),
            }
        }
    }
    out
}

fn print(d: &EnclosedDiagram, scene: &Scene, opts: &EnclosedDiagramOptions, out: &Path) {
    outln!(
        "Critical lengths (enclosed scene {}, accuracy {:?}):",
        scene.name,
        opts.accuracy
    );
    outln!(
        "  {:>2}  {:>18}  {:>9}  {:>8}  {:>16}  {:>9}  {:>18}",
        "i",
        "lbar_cr",
        "kind",
        "from->to",
        "E R/(pi D)",
        "error",
        "surface lbar_cr"
    );
    for e in &d.critical {
        let c = &e.critical;
        outln!(
            "  {:>2}  {:>18.12}  {:>9}  {:>3}->{:<3}  {:>16.10}  {:>9.1e}  {:>18.12}",
            c.index,
            c.lbar_cr,
            c.kind,
            c.from_branch,
            c.to_branch,
            c.energy,
            c.error_estimate,
            e.surface_lbar_cr
        );
    }
    for e in &d.events {
        use rodloop_diagram::enclosed::EventKind;
        let what = match e.kind {
            EventKind::Detachment => {
                "the last contact force is 0; below it the loop is free".to_string()
            }
            EventKind::BranchPoint => format!(
                "family {}: the index changes {} -> {}",
                e.family, e.index_before, e.index_after
            ),
            _ => "lambda_min = 0".to_string(),
        };
        outln!(
            "  {} of branch {} at lbar = {:.12} ± {:.0e} ({what}; E R/(pi D) = {:.10})",
            e.kind.as_str(),
            e.branch,
            e.lbar,
            e.error_estimate,
            e.energy
        );
    }
    let verdict = if opts.branches.is_none() {
        lowest_lifted_off(d)
    } else {
        Vec::new()
    };
    for (a, b) in verdict {
        outln!(
            "  the lowest state has lifted off the wall for {a:.9} < lbar < {b:.9} (the Sec. 3.2 hypothesis fails there)"
        );
    }
    for n in &d.notes {
        eprintln!("note: {n}");
    }
    for w in &d.warnings {
        eprintln!("warning: {w}");
    }
    outln!(
        "{} in {:.2} s; wrote branches.csv, critical.csv, special_points.csv, diagram.svg/.png, summary.json to {}",
        crate::output::plural(d.points.len() as u64, "state"),
        d.seconds.total,
        out.display()
    );
}
