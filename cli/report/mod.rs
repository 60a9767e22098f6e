//! `rodloop report`: one self-contained HTML page with everything a run of the numeric
//! diagram produces: the energy diagram and its companions (Figs. 3a, 3b, 7), the critical
//! lengths with their error estimates (and, for homogeneous scenes, the exact values), the
//! comparison with the paper's printed values, `k²` against `L̄` with Eq. (B.4) (Fig. 11,
//! homogeneous scenes), the branch atlas (Figs. 2, 9, 10; [`crate::atlas`]), a picture and the
//! contact force `λ(s)` of the stable state of every branch at one length, the shape of the
//! first against its Euler curve (Fig. 5), the run's settings and its timings. The page builder
//! both kinds of scene share is `page.rs`, the representative states of this page `states.rs`
//! (where each branch is shown: [`rodloop_diagram::representative`]), the tables (the one
//! table markup, the critical lengths and special points of the diagram directory as
//! [`rodloop_schema::Diagram::read`] reads it back) and the style sheet `tables.rs`, the
//! arguments and page sizes `args.rs`, the page of an enclosed scene `enclosed.rs`.
//!
//! The page needs no network and no file beside it: every figure is an inline `<svg>`, the
//! style sheet is inline, there is no script and no external font (the figures name
//! DejaVu Sans with a generic sans-serif fallback). Nothing here recomputes what other
//! commands compute: the diagram comes from [`crate::diagram::surface::run_numeric`] and
//! [`crate::diagram::surface::write_outputs`], the figures from [`rodloop_figures`] (read back
//! from the staged `branches.csv`/`critical.csv`, as `rodloop draw` reads them), the paper
//! comparison from [`crate::compare::compare_rows`], the states from
//! [`rodloop_solver::solve_with_accuracy`] as `rodloop solve` calls it.

use std::time::Instant;

use anyhow::{Context, Result};
use rodloop_diagram::DiagramOptions;
use rodloop_figures::diagram::{energy_figure, energy_split_figure, lambda_figure, DiagramData};
use rodloop_figures::svg::esc;

use crate::diagram::surface::seconds;
use crate::output::{checked_json, OutputRun};
mod args;
mod enclosed;
mod page;
mod sections;
mod states;
mod tables;

pub use args::Args;
use args::{ATLAS_SHAPES, FIG_H, FIG_W};
use page::Page;

/// The report of an enclosed scene.
pub(crate) fn run_enclosed(args: &Args, scene: &rodloop_scene::Scene) -> Result<()> {
    enclosed::run(args, scene)
}

/// The report of a surface scene (`t_start`: when the command started).
pub(crate) fn run_surface(
    args: &Args,
    scene: &rodloop_scene::Scene,
    t_start: Instant,
) -> Result<()> {
    let scene_text = match &args.scene {
        Some(p) => Some(
            std::fs::read_to_string(p).with_context(|| format!("cannot read {}", p.display()))?,
        ),
        None => None,
    };
    let accuracy = crate::args::accuracy_of(scene, args.accuracy.as_deref())?;
    let opts = DiagramOptions {
        radius: scene.radius,
        stiffness: crate::args::stiffness_of(&scene.stiffness),
        lbar_min: scene.lbar_min,
        lbar_max: scene.lbar_max,
        accuracy,
        ..Default::default()
    };
    opts.validate()?;
    let run = OutputRun::begin(&args.out)?;

    // 1. The numeric diagram (branch files go to the staging directory and vanish with it).
    let t = Instant::now();
    let (d, schema) = crate::diagram::surface::run_numeric(
        &opts,
        run.stage_dir(),
        false,
        args.quiet,
        None,
        &scene.name,
    )?;
    let (schema, state_warnings) = crate::diagram::surface::write_outputs(&d, schema, &opts, &run)?;
    let description = schema.get::<String>("description").unwrap_or_default();
    // The page's tables from the diagram directory as the schema reads it back.
    let dir = rodloop_schema::Diagram::read(run.stage_dir())?;
    let t_diagram = t.elapsed().as_secs_f64();

    // 2. The diagram figures, from the staged CSV files as `rodloop draw` reads them.
    let t = Instant::now();
    let mut dd = DiagramData::read(run.stage_dir())?;
    dd.buckling_loads = scene.stiffness.is_uniform();
    let fig_energy = energy_figure(&dd, FIG_W, FIG_H)?;
    let fig_split = energy_split_figure(&dd, FIG_W, 480.0)?;
    let fig_lambda = lambda_figure(&dd, FIG_W, FIG_H)?;
    // The energy figure beside the tables, as `rodloop diagram` writes it.
    run.write_bytes("diagram.svg", fig_energy.as_bytes())?;
    let t_diagram_figures = t.elapsed().as_secs_f64();
    // The branch atlas from the staged state files (as `diagram --shapes` draws it).
    let t = Instant::now();
    let fig_atlas = crate::atlas::atlas_svg(run.stage_dir(), ATLAS_SHAPES, &scene.name)
        .map_err(|e| format!("{e:#}"));
    let t_atlas = t.elapsed().as_secs_f64();

    // 3. Exact critical lengths (homogeneous scenes) and the paper's values.
    let t = Instant::now();
    let exact = crate::engine::exact_layer(scene, opts.lbar_min, opts.lbar_max)?;
    let uniform = exact.is_some();
    let compare = crate::compare::compare_rows(uniform.then_some(&schema))?;
    // Fig. 11 from the exact layer (homogeneous scenes).
    let fig_k2 = match &exact {
        Some(e) => Some(crate::diagram::k2_figure(e, FIG_W, 480.0)?),
        None => None,
    };
    let t_exact = t.elapsed().as_secs_f64();

    // 4. One state per branch, its picture and its contact force.
    let t = Instant::now();
    let states = states::representative_states(scene, accuracy, &opts, &d);
    let t_states = t.elapsed().as_secs_f64();

    // 5. The page.
    let t = Instant::now();
    let mut page = Page::begin(
        &scene.name,
        &format!(
            "{desc}. Numeric branch diagram for {lo} ≤ L̄ ≤ {hi} at accuracy <b>{acc}</b>: {nstates} traced states on {nbranches}, {ncrit} critical lengths.",
            desc = esc(&description),
            lo = opts.lbar_min,
            hi = opts.lbar_max,
            acc = format!("{accuracy:?}").to_lowercase(),
            nstates = dir.points.len(),
            nbranches = crate::diagram::surface::branch_count(&schema.curves),
            ncrit = dir.critical.len(),
        ),
        &[
            ("diagram", "Diagram"),
            ("critical", "Critical lengths"),
            ("atlas", "Atlas"),
            ("states", "States"),
            ("paper", "Paper values"),
            ("settings", "Settings"),
            ("timings", "Timings"),
        ],
    );
    page.notes(
        "warning",
        crate::diagram::surface::engine_warnings(&schema, state_warnings),
    );

    sections::energy(
        &mut page,
        [&fig_energy, &fig_split, &fig_lambda],
        fig_k2.as_deref(),
        uniform,
    );
    let great_circles = schema.get::<rodloop_diagram::BucklingReport>("great_circles");
    sections::critical(&mut page, &dir, exact.as_ref(), great_circles.as_ref());
    sections::atlas(&mut page, &fig_atlas);
    sections::states(&mut page, &states);
    sections::paper(&mut page, &compare, uniform);

    let t_page = t.elapsed().as_secs_f64();
    let total = t_start.elapsed().as_secs_f64();
    let settings = tables::Settings {
        number: 6,
        scene_name: &scene.name,
        scene_file: args.scene.as_deref(),
        extra: vec![
            ("description", esc(&description)),
            ("sphere radius R", scene.radius.to_string()),
            (
                "length range",
                format!("{} ≤ L̄ ≤ {}", opts.lbar_min, opts.lbar_max),
            ),
        ],
        accuracy: (accuracy, args.accuracy.is_some()),
        units: "lengths in R, L̄ = L/(2πR), energies E R/(πD₀), contact force λR³/D₀ (D₀ = D for a uniform rod)",
        scene_text: scene_text.as_deref(),
    };
    let stages = [
        ("diagram: tracing the branches", seconds(&schema, "tracing")),
        ("diagram: critical lengths", seconds(&schema, "critical")),
        ("diagram: great circles", seconds(&schema, "great_circles")),
        ("diagram total (with writing the CSV files)", t_diagram),
        ("diagram figures", t_diagram_figures),
        ("branch atlas", t_atlas),
        ("exact layer and paper comparison", t_exact),
    ];
    let times = [
        ("diagram", t_diagram),
        ("diagram_figures", t_diagram_figures),
        ("atlas", t_atlas),
        ("exact_and_paper", t_exact),
    ];
    let fields = checked_json!({
        "paper_disagreements_exact": compare.iter().filter(|r| r.agrees_exact == Some(false)).count(),
        "paper_disagreements_numeric": compare.iter().filter(|r| r.agrees_numeric == Some(false)).count(),
    })?;
    let (bytes, figures, failed) = page.finish(
        run, &settings, &stages, &times, &states, t_states, t_page, total, fields,
    )?;
    outln!(
        "wrote report.html ({} KB, {} figures: diagram, energy split, lambda extremes, {}branch atlas, shape against the Euler curve, {} with their force plots), branches.csv, critical.csv, special_points.csv, diagram.svg, summary.json, states/ to {} in {:.2} s",
        bytes.div_ceil(1024),
        figures,
        if fig_k2.is_some() { "k² (Fig. 11), " } else { "" },
        crate::output::plural((states.len() - failed) as u64, "loop picture"),
        args.out.display(),
        t_start.elapsed().as_secs_f64()
    );
    Ok(())
}
