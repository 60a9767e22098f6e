//! `rodloop diagram --param P --lbar X [--to V]`: the equilibria at a fixed length traced
//! against a stiffness parameter of a two-segment scene (energy against `log₁₀ D1/D0` for
//! `d1`), with stability labels and special points.

use std::time::Instant;

use anyhow::{bail, Context, Result};
use rodloop_diagram::param_sweep::{ParamSweep, SweepSettings};
use rodloop_diagram::Label;
use rodloop_diagram::{Engine, SweepEngine};
use rodloop_figures::plot::{LegendItem, Mark, Plot, Series, Shape};
use rodloop_figures::raster::svg_to_png;
use rodloop_figures::svg::Svg;
use rodloop_scene::Scene;
use rodloop_solver::{Param, SolveOptions};

use super::args::{Args, Model};
use crate::args::{accuracy_of, stiffness_of};
use crate::output::{Cell, OutputRun, Table};

/// The arguments of `diagram --param`, checked before the scene is read.
pub struct Checked {
    t0: Instant,
    param: Param,
    lbar: f64,
}

/// Check the arguments of `diagram --param` that need no scene.
pub fn check(args: &Args, param: &str) -> Result<Checked> {
    let t0 = Instant::now();
    let param: Param = param.parse()?;
    if args.model == Model::Exact {
        bail!("--param {param} traces numerical equilibria of a two-segment rod; --model exact covers homogeneous loops only");
    }
    let Some(lbar) = args.lbar else {
        bail!("--param {param} needs --lbar X: the fixed length at which the equilibria are traced against {param}");
    };
    if args.lbar_min.is_some() || args.lbar_max.is_some() || args.step.is_some() || args.resume {
        bail!("--lbar-min, --lbar-max, --step and --resume belong to the diagram in L̄; with --param the length is fixed by --lbar");
    }
    if args.max_step.is_some()
        || args.min_step.is_some()
        || args.max_points.is_some()
        || args.newton_tol.is_some()
    {
        bail!("--max-step, --min-step, --max-points and --newton-tol control the tracer of the diagram in L̄; --param uses its own continuation settings");
    }
    if args.shapes > 0 {
        bail!("--shapes draws the atlas of the diagram in L̄; --param writes its states to states/ (draw one with `rodloop draw`)");
    }
    Ok(Checked { t0, param, lbar })
}

/// Run `diagram --param` on a surface scene.
pub fn run(args: &Args, checked: Checked, scene: &Scene) -> Result<()> {
    let Checked { t0, param, lbar } = checked;
    let stiffness = stiffness_of(&scene.stiffness);
    let target = match (args.to, param) {
        (Some(v), _) => v,
        (None, Param::D1) => 1e-3,
        (None, _) => {
            bail!("--param {param} needs --to V (the default end value 1e-3 is for d1 only)")
        }
    };
    let settings = SweepSettings {
        radius: scene.radius,
        lbar,
        stiffness,
        param,
        target,
        accuracy: accuracy_of(scene, args.accuracy.as_deref())?,
        branches: args.branch.iter().map(|&b| b as u32).collect(),
        solve: SolveOptions::default(),
    };
    let run = OutputRun::begin(&args.out)?;
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut engine = SweepEngine { settings, threads };
    let out = engine
        .run(&mut |_| {})
        .with_context(|| format!("diagram of scene {} against {param}", scene.name))?;
    let settings = &engine.settings;
    let (sweep, states) = (&out.sweep, &out.states);
    let (unverified, state_warnings) = (out.unverified, &out.warnings);
    // States whose written κ_g has another dominant harmonic than their branch's η (a very
    // soft segment: the branch is the family's, by continuation from its seed).
    let other_eta: usize = sweep
        .families
        .iter()
        .zip(states)
        .map(|(f, v)| {
            v.iter()
                .filter(|(_, file)| file.counted_other_eta(f.eta))
                .count()
        })
        .sum();
    let state_files = write_sweep_states(
        sweep,
        states,
        scene.radius,
        settings.stiffness.reference(),
        &run,
    )?;
    let seconds = t0.elapsed().as_secs_f64();

    let svg = figure(sweep, &scene.name, args.width as f64, args.height as f64);
    let png = svg_to_png(&svg, 1.0).context("rendering diagram.png")?;
    for f in &sweep.families {
        let seed = match f.seed_energy {
            Some((v, e, est)) => format!("E R/(pi D0) = {e:.10} ± {est:.1e} at {param} = {v}"),
            None => f.notes.first().cloned().unwrap_or_default(),
        };
        let last = f
            .points
            .last()
            .map(|p| p.value)
            .unwrap_or(sweep.scene_value);
        outln!(
            "branch {} (eta = {}) family {}: {seed} ({} cells), traced to {param} = {last:.6} over {} states; {}",
            f.branch, f.eta, f.family, f.cells, f.points.len(), f.end
        );
    }
    for p in &sweep.special {
        outln!(
            "  {} of branch {} family {} at {param} = {:.8}: E R/(pi D0) = {:.10} ± {:.1e}{}",
            p.kind,
            p.branch,
            p.family,
            p.value,
            p.energy,
            p.energy_error,
            p.index
                .map(|(a, b)| format!(" (index {a} -> {b})"))
                .unwrap_or_default()
        );
    }
    for w in sweep.warnings.iter().chain(state_warnings) {
        eprintln!("warning: {w}");
    }
    outln!("time {seconds:.2} s");

    let mut d = engine.schema(&out, &scene.name)?;
    for (p, name) in d.points.iter_mut().zip(state_files.iter().flatten()) {
        p.state_file = Some(name.clone());
    }
    d.put("command", "diagram --param")?;
    d.put("param", &param)?;
    d.put("scene_value", &sweep.scene_value)?;
    d.put("target", &sweep.target)?;
    d.put("lbar", &lbar)?;
    d.put(
        "families",
        &sweep
            .families
            .iter()
            .map(|f| FamilySummary {
                branch: f.branch,
                eta: f.eta,
                family: f.family,
                cells: f.cells,
                seed_value: f.seed_energy.map(|e| e.0),
                seed_energy: f.seed_energy.map(|e| e.1),
                seed_energy_error: f.seed_energy.map(|e| e.2),
                notes: &f.notes,
                states: f.points.len(),
                end: &f.end,
            })
            .collect::<Vec<_>>(),
    )?;
    d.put("unverified_states", &unverified)?;
    d.put("states_counted_other_eta", &other_eta)?;
    d.put("state_warnings", &state_warnings)?;
    d.put("time_seconds", &seconds)?;
    d.put(
        "files",
        &[
            "branches.csv",
            "special_points.csv",
            "diagram.svg",
            "diagram.png",
            "summary.json",
        ],
    )?;
    run.write_bytes("branches.csv", &d.branches_csv()?)?;
    run.write_table(&special_table(sweep)?)?;
    run.write_bytes("diagram.svg", svg.as_bytes())?;
    run.write_bytes("diagram.png", &png)?;
    crate::output::write_summary(&run, &mut d)?;
    run.commit()?;
    outln!("wrote {}", args.out.display());
    Ok(())
}

/// Write every kept state into the run's `states/` directory
/// (`states/branch-B-family-F-KKK.csv`, `KKK` its position along the family): the file of
/// each point, by family (empty where a file could not be written; the error says which).
fn write_sweep_states(
    s: &ParamSweep,
    states: &rodloop_diagram::engine::VerifiedStates,
    r: f64,
    d0: f64,
    run: &OutputRun,
) -> Result<Vec<Vec<String>>> {
    let dir = run.subdir("states")?;
    let mut names = Vec::new();
    for (f, files) in s.families.iter().zip(states) {
        let mut fam = Vec::new();
        for (k, (_, file)) in files.iter().enumerate() {
            let name = format!("states/branch-{}-family-{}-{k:03}.csv", f.branch, f.family);
            crate::states::write_state_file(&dir, &name, file, r, d0)
                .with_context(|| format!("writing {name}"))?;
            fam.push(name);
        }
        names.push(fam);
    }
    Ok(names)
}

/// A family of `summary.json`: how it was seeded, traced and where it ends.
#[derive(serde::Serialize)]
struct FamilySummary<'a> {
    branch: u32,
    eta: u32,
    family: usize,
    cells: usize,
    seed_value: Option<f64>,
    seed_energy: Option<f64>,
    seed_energy_error: Option<f64>,
    notes: &'a [String],
    states: usize,
    end: &'a str,
}

fn special_table(s: &ParamSweep) -> Result<Table> {
    let mut t = Table::new(
        "special_points.csv",
        &[
            "kind",
            "param",
            "value",
            "lbar",
            "energy",
            "energy_error",
            "branch",
            "family",
            "index_before",
            "index_after",
        ],
    );
    for p in &s.special {
        let (a, b) = p
            .index
            .map(|(a, b)| (a as i64, b as i64))
            .unwrap_or((-1, -1));
        t.push(vec![
            Cell::S(p.kind.clone()),
            Cell::S(s.param.name().into()),
            Cell::F(p.value),
            Cell::F(s.lbar),
            Cell::F(p.energy),
            Cell::F(p.energy_error),
            Cell::I(p.branch.into()),
            Cell::I(p.family as i64),
            Cell::I(a),
            Cell::I(b),
        ])?;
    }
    Ok(t)
}

const COLORS: [&str; 5] = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e"];

/// Energy against the parameter (`log₁₀` for `d1`): each family one colour per branch, the
/// line style by its label, special points marked.
fn figure(s: &ParamSweep, scene: &str, w: f64, h: f64) -> String {
    let log = s.param == Param::D1;
    let xv = |v: f64| if log { v.log10() } else { v };
    let style = |l: Label| match l {
        Label::Stable => ("", 2.4),
        Label::Metastable => ("7 4", 1.6),
        Label::Unstable => ("2 3", 1.2),
    };
    let mut plot = Plot {
        title: format!(
            "Equilibria of scene {scene} at L̄ = {} against {}",
            s.lbar, s.param
        ),
        xlabel: if log {
            "log₁₀(D1/D0)".into()
        } else {
            s.param.name().into()
        },
        ylabel: "energy E R/(π D0)".into(),
        // The legend beside the axes, where it cannot cover a curve.
        legend_width: 190.0,
        ..Default::default()
    };
    let mut branches: Vec<u32> = s.families.iter().map(|f| f.branch).collect();
    branches.dedup();
    let color_of = |b: u32| {
        let k = branches.iter().position(|&x| x == b).unwrap_or(0);
        COLORS[k % COLORS.len()]
    };
    for f in &s.families {
        // One series per run of equal labels (the boundary point shared).
        let mut start = 0;
        while start + 1 < f.points.len() {
            let l = f.points[start + 1].label;
            let mut end = start + 1;
            while end + 1 < f.points.len() && f.points[end + 1].label == l {
                end += 1;
            }
            let (dash, width) = style(l);
            plot.series.push(Series {
                color: color_of(f.branch).into(),
                width,
                dash: dash.into(),
                points: f.points[start..=end]
                    .iter()
                    .map(|p| (xv(p.value), p.energy))
                    .collect(),
            });
            start = end;
        }
    }
    for b in &branches {
        plot.legend.push(LegendItem::Line {
            label: format!("branch {b} (η = {})", rodloop_exact::eta_of_branch(*b)),
            color: color_of(*b).into(),
            width: 2.4,
            dash: String::new(),
        });
    }
    for l in [Label::Stable, Label::Metastable, Label::Unstable] {
        let (dash, width) = style(l);
        plot.legend.push(LegendItem::Line {
            label: l.as_str().into(),
            color: "#555".into(),
            width,
            dash: dash.into(),
        });
    }
    for (kind, shape) in [
        ("fold", Shape::Triangle),
        ("branch_point", Shape::Diamond),
        ("index_change", Shape::OpenSquare),
    ] {
        let pts: Vec<_> = s.special.iter().filter(|p| p.kind == kind).collect();
        for p in &pts {
            plot.marks.push(Mark {
                at: (xv(p.value), p.energy),
                shape,
                color: color_of(p.branch).into(),
                size: 4.5,
            });
        }
        if !pts.is_empty() {
            plot.legend.push(LegendItem::Mark {
                label: kind.replace('_', " "),
                shape,
                color: "#777".into(),
            });
        }
    }
    let mut svg = Svg::new(w, h);
    svg.rect(0.0, 0.0, w, h, "white", "none", 0.0);
    plot.render(&mut svg, 0.0, 0.0, w, h, "sweep");
    svg.finish()
}
