//! `rodloop phase`: the critical lengths of a two-segment rod as curves in a stiffness
//! parameter (two-parameter continuation of the Maxwell points, paper Sec. 5).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use rodloop_diagram::phase::PhaseSettings;
use rodloop_diagram::{Engine, PhaseEngine, RecordStates, StateFile};
use rodloop_figures::raster::svg_to_png;
use rodloop_scene::Scene;
use rodloop_schema::{Diagram, Parameter};
use rodloop_solver::{Param, SolveOptions};

use crate::args::{accuracy_of, stiffness_of};
use crate::output::{Cell, OutputRun, Table};
use crate::phase_figure::{phase_svg, stopped_short};
use crate::phase_rows::curves_of;

/// Arguments of `rodloop phase`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Scene file (TOML) with a two-segment stiffness profile (kind = "tanh").
    #[arg(long)]
    pub scene: PathBuf,
    /// The parameter to move: d1 (= D1/D0, continued in ln d1), gamma, s0 or s1.
    #[arg(long, default_value = "d1")]
    pub param: String,
    /// The end value of the parameter (the start is the scene's value).
    #[arg(long)]
    pub to: f64,
    /// Extra rows at exactly these parameter values (comma-separated).
    #[arg(long, value_delimiter = ',')]
    pub at: Vec<f64>,
    /// Accuracy: fast, default or high (overrides the scene's).
    #[arg(long, value_parser = crate::args::ACCURACY_CHOICES)]
    pub accuracy: Option<String>,
    /// Output directory.
    #[arg(long, default_value = "out/phase")]
    pub out: PathBuf,
}

/// Run `rodloop phase` on a surface scene (`t0`: when the command started).
pub fn run(args: &Args, scene: &Scene, t0: Instant) -> Result<()> {
    let param: Param = args.param.parse()?;
    if param == Param::Lbar {
        bail!("--param lbar: the critical length is the unknown; choose d1, gamma, s0 or s1");
    }
    if !args.to.is_finite() {
        bail!("--to must be a finite number (got {})", args.to);
    }
    if let Some(v) = args.at.iter().find(|v| !v.is_finite()) {
        bail!("--at values must be finite numbers (got {v})");
    }
    let accuracy = accuracy_of(scene, args.accuracy.as_deref())?;
    let stiffness = stiffness_of(&scene.stiffness);
    // The scene's own value always gets a row (an exact Newton solve there), as --at values do.
    let mut at = args.at.clone();
    if let Ok(v) = stiffness.param(param) {
        if !at.iter().any(|a| (a - v).abs() <= 1e-12 * v.abs().max(1.0)) {
            at.push(v);
        }
    }
    let settings = PhaseSettings {
        radius: scene.radius,
        stiffness,
        param,
        target: args.to,
        lbar_min: scene.lbar_min,
        lbar_max: scene.lbar_max,
        accuracy,
        at,
        solve: SolveOptions::default(),
    };
    let run = OutputRun::begin(&args.out)?;
    let mut engine = PhaseEngine { settings };
    // Rows whose states fail their verification are left out by the engine.
    let out = engine
        .run(&mut |_| {})
        .with_context(|| format!("phase diagram of scene {}", scene.name))?;
    let mut summary = engine.schema(&out, &scene.name)?;
    let settings = &engine.settings;
    let (unverified, mut state_warnings) = (out.unverified, out.warnings.clone());
    let curves = curves_of(&summary)?;
    let (state_files, write_warnings) = write_row_states(
        &summary,
        &out.record_states(),
        scene.radius,
        settings.stiffness.reference(),
        &run,
    )?;
    state_warnings.extend(write_warnings);
    for w in &state_warnings {
        eprintln!("warning: {w}");
    }
    let seconds = t0.elapsed().as_secs_f64();

    let param = &curves.parameter;
    let table = phase_table(&summary, param, &state_files)?;
    let svg = phase_svg(&curves, &scene.name, (scene.lbar_min, scene.lbar_max));
    let png = svg_to_png(&svg, 1.0).context("rendering phase.png")?;

    // People: the limit check, the ends and notes of each curve.
    for v in &curves.curves {
        let (c, ex) = (v.curve, v.curve.exchange);
        outln!(
            "exchange {} -> {} (uniform rod: L̄_cr = {:.10}): {} rows, {} continuation steps",
            ex.from_branch,
            ex.to_branch,
            ex.lbar_uniform,
            c.rows,
            c.steps
        );
        for (r, at) in v.rows.iter().filter(|(_, at)| at.source != "continuation") {
            outln!(
                "  {} = {:<10.6} L̄_cr = {:.10} ± {:.1e}  E R/(pi D0) = {:.8}  ({}, lowest {} -> {})",
                param.name,
                at.value,
                r.lbar_cr,
                r.error_estimate,
                r.energy,
                at.source,
                r.from_branch,
                r.to_branch
            );
        }
        if let Some(u) = &c.uniform {
            outln!(
                "  limit at the uniform rod: {:.10} ± {:.1e}, exact {:.10}, deviation {:.1e}",
                u.lbar_cr,
                u.error_estimate,
                u.exact,
                u.deviation
            );
        }
        for e in &c.ends {
            eprintln!(
                "phase: exchange {} -> {}: the curve ends at {} = {:.6} ({}): {}",
                ex.from_branch,
                ex.to_branch,
                param.name,
                e.value,
                e.kind,
                brief(&e.reason)
            );
        }
        for t in c.turns.iter().chain(&c.switches) {
            eprintln!(
                "phase: exchange {} -> {}: {}",
                ex.from_branch,
                ex.to_branch,
                brief(t)
            );
        }
        if !c.checks.is_empty() {
            eprintln!(
                "phase: exchange {} -> {}: no lower state of either branch at its length at {} = {} (searched by minimisation from shifted exact loops and the followed states)",
                ex.from_branch,
                ex.to_branch,
                param.name,
                c.checks
                    .iter()
                    .map(|v| format!("{v:.6}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            );
        }
        for n in &c.notes {
            eprintln!(
                "phase: exchange {} -> {}: note: {}",
                ex.from_branch,
                ex.to_branch,
                brief(n)
            );
        }
    }
    outln!("time {seconds:.2} s");
    let short = stopped_short(&curves);
    let param_name = param.name.clone();
    drop(curves);

    summary.put("command", "phase")?;
    summary.put("at", &args.at)?;
    summary.put("time_seconds", &seconds)?;
    summary.put("complete", &short.is_empty())?;
    summary.put(
        "stopped_short",
        &short
            .iter()
            .map(|s| StoppedShort {
                exchange: [s.from, s.to],
                value: s.value,
                kind: &s.kind,
            })
            .collect::<Vec<_>>(),
    )?;
    summary.put("files", &["phase.csv", "phase.svg", "phase.png"])?;
    summary.states_dir = Some("states".into());
    summary.put("unverified_states", &unverified)?;
    summary.put("state_warnings", &state_warnings)?;
    run.write_table(&table)?;
    run.write_bytes("phase.svg", svg.as_bytes())?;
    run.write_bytes("phase.png", &png)?;
    crate::output::write_summary(&run, &mut summary)?;
    run.commit()?;
    outln!("wrote {}", args.out.display());
    if !short.is_empty() {
        bail!(
            "phase: {} short of --to {}: {}; the traced part is in {} (summary.json: \"complete\": false)",
            if short.len() == 1 {
                "one curve stopped"
            } else {
                "curves stopped"
            },
            args.to,
            short
                .iter()
                .map(|s| format!(
                    "exchange {} -> {} at {} = {:.6} ({})",
                    s.from, s.to, param_name, s.value, s.kind
                ))
                .collect::<Vec<_>>()
                .join(", "),
            args.out.display()
        );
    }
    Ok(())
}

/// A curve that stopped short of `--to`, in `summary.json`.
#[derive(serde::Serialize)]
struct StoppedShort<'a> {
    exchange: [u32; 2],
    value: f64,
    kind: &'a str,
}

/// Longest message line: a longer explanation is cut at its first clause (the whole text is in
/// `summary.json`).
const BRIEF: usize = 200;

/// `text` on one line of at most [`BRIEF`] characters: cut at the first `(` or `;` past 60
/// characters, or hard at the limit, with a pointer to the full text.
pub(crate) fn brief(text: &str) -> String {
    let one: String = text.split_whitespace().collect::<Vec<_>>().join(" ");
    if one.chars().count() <= BRIEF {
        return one;
    }
    let limit: String = one.chars().take(BRIEF).collect();
    let cut = limit
        .char_indices()
        .filter(|&(i, c)| i >= 60 && (c == '(' || c == ';'))
        .map(|(i, _)| i)
        .next()
        .unwrap_or(limit.len());
    format!("{} … (full text in summary.json)", limit[..cut].trim_end())
}

/// The state files of each row, in the order of the schema's critical lengths (see
/// [`write_row_states`]).
type RowFiles = Vec<[String; 2]>;

/// Write the two states of every row (`states[i]` those of the schema's critical length `i`,
/// [`rodloop_diagram::RecordStates`]) into the run's `states/` directory
/// (`states/curve-C-row-RRR-branch-B.csv`, `RRR` counting the curve's rows of `phase.csv`,
/// `B` the state's branch): the file names of each row in the order of its `from_branch` and
/// `to_branch` (empty for the limit row, or where a file could not be written: warnings).
fn write_row_states(
    d: &Diagram,
    states: &[Vec<&StateFile>],
    r: f64,
    d0: f64,
    run: &OutputRun,
) -> Result<(RowFiles, Vec<String>)> {
    let dir = run.subdir("states")?;
    let curves = d.exchange_curves.as_deref().unwrap_or_default();
    let mut names = Vec::new();
    let mut warnings = Vec::new();
    // Rows of each curve so far.
    let mut count = vec![0usize; curves.len()];
    for (i, row) in d.critical.iter().enumerate() {
        let k = row.curve_row().map_or(0, |at| at.curve);
        let (Some(curve), Some(j)) = (
            k.checked_sub(1).and_then(|k| curves.get(k)),
            k.checked_sub(1).and_then(|k| count.get_mut(k)),
        ) else {
            bail!(
                "internal error: critical length {} of the phase diagram is on no curve",
                row.index
            );
        };
        let ex = curve.exchange;
        let mut pair = [String::new(), String::new()];
        let files = states.get(i).map_or(&[][..], |v| &v[..]);
        if !files.is_empty() {
            let branches = [ex.from_branch, ex.to_branch];
            for ((slot, f), b) in pair.iter_mut().zip(files).zip(branches) {
                let name = format!("states/curve-{k}-row-{j:03}-branch-{b}.csv");
                match crate::states::write_state_file(&dir, &name, f, r, d0) {
                    Ok(()) => *slot = name,
                    Err(e) => warnings.push(format!("{name} could not be written: {e:#}")),
                }
            }
            // In the order of the row's own from_branch and to_branch.
            if row.from_branch != ex.from_branch {
                pair.swap(0, 1);
            }
        }
        *j += 1;
        names.push(pair);
    }
    Ok((names, warnings))
}

/// `phase.csv`: one row per Maxwell point (the schema's critical lengths), with the files of
/// its two states (`files[i]`, [`write_row_states`]).
fn phase_table(d: &Diagram, param: &Parameter, files: &[[String; 2]]) -> Result<Table> {
    let mut t = Table::new(
        "phase.csv",
        &[
            "param",
            "value",
            "lbar_cr",
            "kind",
            "from_branch",
            "to_branch",
            "energy",
            "error_estimate",
            "source",
            "curve",
            "arm",
            "index_from",
            "index_to",
            "slope",
            "energy_error",
            "state_file_from",
            "state_file_to",
        ],
    );
    for (r, [from, to]) in d.critical.iter().zip(files) {
        let Some(at) = r.curve_row() else {
            bail!(
                "internal error: critical length {} of the phase diagram is on no curve",
                r.index
            );
        };
        t.push(vec![
            Cell::S(param.name.clone()),
            Cell::F(at.value),
            Cell::F(r.lbar_cr),
            Cell::S(r.kind.clone()),
            Cell::I(r.from_branch.into()),
            Cell::I(r.to_branch.into()),
            Cell::F(r.energy),
            Cell::F(r.error_estimate),
            Cell::S(at.source),
            Cell::I(at.curve as i64),
            Cell::I(at.arm as i64),
            Cell::I(at.index_from as i64),
            Cell::I(at.index_to as i64),
            Cell::F(at.slope),
            Cell::F(at.energy_error),
            Cell::S(from.clone()),
            Cell::S(to.clone()),
        ])?;
    }
    Ok(t)
}
