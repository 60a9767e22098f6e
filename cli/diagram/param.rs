//! `rodloop diagram --param P --lbar X [--to V]`: the equilibria at a fixed length traced
//! against a stiffness parameter of a two-segment scene (energy against `log₁₀ D1/D0` for
//! `d1`), with stability labels and special points.

use std::time::Instant;

use std::collections::BTreeMap;

use anyhow::{bail, Context, Result};
use rodloop_diagram::param_sweep::SweepSettings;
use rodloop_diagram::{Engine, RecordStates, StateFile, SweepEngine};
use rodloop_figures::plot::{LegendItem, Mark, Plot, Series, Shape};
use rodloop_figures::raster::svg_to_png;
use rodloop_figures::svg::Svg;
use rodloop_scene::Scene;
use rodloop_schema::{Diagram, FamilyTrace, Point};
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
    let mut d = engine.schema(&out, &scene.name)?;
    let settings = &engine.settings;
    let states = out.record_states();
    let (unverified, state_warnings) = (out.unverified, &out.warnings);
    // States whose written κ_g has another dominant harmonic than their branch's η (a very
    // soft segment: the branch is the family's, by continuation from its seed).
    let other_eta: usize = d
        .points
        .iter()
        .zip(&states)
        .filter(|(p, files)| files.iter().any(|f| f.counted_other_eta(p.eta)))
        .count();
    let state_files = write_sweep_states(
        &d,
        &states,
        scene.radius,
        settings.stiffness.reference(),
        &run,
    )?;
    let seconds = t0.elapsed().as_secs_f64();

    let (Some(parameter), Some(families), Some(special)) = (&d.parameter, &d.families, &d.special)
    else {
        bail!("internal error: the schema of a diagram against {param} has no parameter, families or special points");
    };
    let svg = figure(&d, &scene.name, args.width as f64, args.height as f64);
    let png = svg_to_png(&svg, 1.0).context("rendering diagram.png")?;
    for f in families {
        let seed = match (f.seed_value, f.seed_energy, f.seed_energy_error) {
            (Some(v), Some(e), Some(est)) => {
                format!("E R/(pi D0) = {e:.10} ± {est:.1e} at {param} = {v}")
            }
            _ => f.notes.first().cloned().unwrap_or_default(),
        };
        let last = family_points(&d, f)
            .last()
            .map(|p| p.coords[0])
            .unwrap_or(parameter.scene_value);
        outln!(
            "branch {} (eta = {}) family {}: {seed} ({} cells), traced to {param} = {last:.6} over {} states; {}",
            f.branch, f.eta, f.family, f.cells, f.states, f.end
        );
    }
    for p in special {
        outln!(
            "  {} of branch {} family {} at {param} = {:.8}: E R/(pi D0) = {:.10} ± {:.1e}{}",
            p.kind,
            p.branch,
            p.family,
            p.value.unwrap_or(f64::NAN),
            p.energy,
            p.energy_error.unwrap_or(f64::NAN),
            p.index_before
                .zip(p.index_after)
                .map(|(a, b)| format!(" (index {a} -> {b})"))
                .unwrap_or_default()
        );
    }
    for w in d.warnings.iter().flatten().chain(state_warnings) {
        eprintln!("warning: {w}");
    }
    outln!("time {seconds:.2} s");
    let special = special_table(&d)?;

    for (p, name) in d.points.iter_mut().zip(state_files) {
        p.state_file = Some(name);
    }
    d.put("command", "diagram --param")?;
    d.put("lbar", &lbar)?;
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
    run.write_table(&special)?;
    run.write_bytes("diagram.svg", svg.as_bytes())?;
    run.write_bytes("diagram.png", &png)?;
    crate::output::write_summary(&run, &mut d)?;
    run.commit()?;
    outln!("wrote {}", args.out.display());
    Ok(())
}

/// The points of family `f` of the diagram `d` against a parameter, in tracing order.
fn family_points<'a>(d: &'a Diagram, f: &FamilyTrace) -> Vec<&'a Point> {
    d.points
        .iter()
        .filter(|p| p.branch == f.branch && p.family == Some(f.family as u32))
        .collect()
}

/// Write the state of every point (`states[i]` that of the schema's point `i`,
/// [`rodloop_diagram::RecordStates`]) into the run's `states/` directory
/// (`states/branch-B-family-F-KKK.csv`, `KKK` its position along the family): the file of
/// each point, in the schema's order.
fn write_sweep_states(
    d: &Diagram,
    states: &[Vec<&StateFile>],
    r: f64,
    d0: f64,
    run: &OutputRun,
) -> Result<Vec<String>> {
    let dir = run.subdir("states")?;
    let mut names = Vec::new();
    let mut along: BTreeMap<(u32, Option<u32>), usize> = BTreeMap::new();
    for (p, files) in d.points.iter().zip(states) {
        let k = along.entry((p.branch, p.family)).or_default();
        let name = format!(
            "states/branch-{}-family-{}-{k:03}.csv",
            p.branch,
            p.family.unwrap_or_default()
        );
        *k += 1;
        let [file] = files[..] else {
            bail!(
                "internal error: {name}: a point of the diagram holds {} states, not one",
                files.len()
            );
        };
        crate::states::write_state_file(&dir, &name, file, r, d0)
            .with_context(|| format!("writing {name}"))?;
        names.push(name);
    }
    Ok(names)
}

/// `special_points.csv` of the diagram against a parameter: its special points at the fixed
/// length, with the parameter's value.
fn special_table(d: &Diagram) -> Result<Table> {
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
    let param = d.parameter.as_ref().map_or("", |p| p.name.as_str());
    for p in d.special.iter().flatten() {
        let (a, b) = p
            .index_before
            .zip(p.index_after)
            .map(|(a, b)| (a as i64, b as i64))
            .unwrap_or((-1, -1));
        t.push(vec![
            Cell::S(p.kind.clone()),
            Cell::S(param.into()),
            Cell::F(p.value.unwrap_or(f64::NAN)),
            Cell::F(p.lbar),
            Cell::F(p.energy),
            Cell::F(p.energy_error.unwrap_or(f64::NAN)),
            Cell::I(p.branch.into()),
            Cell::I(p.family.into()),
            Cell::I(a),
            Cell::I(b),
        ])?;
    }
    Ok(t)
}

const COLORS: [&str; 5] = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e"];

/// Line style of a stability label: dash pattern and width.
fn style(label: &str) -> (&'static str, f64) {
    match label {
        "stable" => ("", 2.4),
        "metastable" => ("7 4", 1.6),
        _ => ("2 3", 1.2),
    }
}

/// Energy against the parameter (`log₁₀` for `d1`): each family one colour per branch, the
/// line style by its label, special points marked.
fn figure(d: &Diagram, scene: &str, w: f64, h: f64) -> String {
    let param = d.parameter.as_ref();
    let name = param.map_or("", |p| p.name.as_str());
    let log = param.is_some_and(|p| p.is_log());
    let xv = |v: f64| if log { v.log10() } else { v };
    let lbar = d
        .axes
        .iter()
        .find(|a| a.name == "lbar")
        .map_or(0.0, |a| a.min);
    let mut plot = Plot {
        title: format!("Equilibria of scene {scene} at L̄ = {lbar} against {name}"),
        xlabel: if log {
            "log₁₀(D1/D0)".into()
        } else {
            name.into()
        },
        ylabel: "energy E R/(π D0)".into(),
        // The legend beside the axes, where it cannot cover a curve.
        legend_width: 190.0,
        ..Default::default()
    };
    let families = d.families.as_deref().unwrap_or_default();
    let mut branches: Vec<u32> = families.iter().map(|f| f.branch).collect();
    branches.dedup();
    let color_of = |b: u32| {
        let k = branches.iter().position(|&x| x == b).unwrap_or(0);
        COLORS[k % COLORS.len()]
    };
    let label = |p: &Point| p.label.clone().unwrap_or_default();
    for f in families {
        let points = family_points(d, f);
        // One series per run of equal labels (the boundary point shared).
        let mut start = 0;
        while start + 1 < points.len() {
            let l = label(points[start + 1]);
            let mut end = start + 1;
            while end + 1 < points.len() && label(points[end + 1]) == l {
                end += 1;
            }
            let (dash, width) = style(&l);
            plot.series.push(Series {
                color: color_of(f.branch).into(),
                width,
                dash: dash.into(),
                points: points[start..=end]
                    .iter()
                    .map(|p| (xv(p.coords[0]), p.energy))
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
    for l in ["stable", "metastable", "unstable"] {
        let (dash, width) = style(l);
        plot.legend.push(LegendItem::Line {
            label: l.into(),
            color: "#555".into(),
            width,
            dash: dash.into(),
        });
    }
    let special = d.special.as_deref().unwrap_or_default();
    for (kind, shape) in [
        ("fold", Shape::Triangle),
        ("branch_point", Shape::Diamond),
        ("index_change", Shape::OpenSquare),
    ] {
        let pts: Vec<_> = special.iter().filter(|p| p.kind == kind).collect();
        for p in &pts {
            plot.marks.push(Mark {
                at: (xv(p.value.unwrap_or(f64::NAN)), p.energy),
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
