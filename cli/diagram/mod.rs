//! `rodloop diagram`: the energy-versus-length diagram and its critical lengths. The engine
//! is chosen once from the scene ([`crate::engine`]); `surface.rs`, `enclosed.rs` and
//! `param.rs` run and print the surface, enclosed and parameter diagrams, `args.rs` holds the
//! arguments they share; the exact layer runs here.

use anyhow::{bail, Result};
use rodloop_diagram::{Engine, ExactEngine};
use rodloop_schema::{Cell, Diagram, SideColumn};

use crate::output::OutputRun;

mod args;
pub mod enclosed;
pub mod param;
pub mod surface;

pub use args::{Args, Model, FIGURE_SIZE};

pub use rodloop_diagram::engine::{etas_in, exact_counterpart};

/// The figures of `draw_diagram` (diagram, diagram_split, diagram_lambda, and diagram_g for
/// the exact model; SVG and PNG), drawn from the staged tables into the run's staging
/// directory, so that they are committed with the tables as one set.
fn draw_figures(args: &Args, run: &OutputRun) -> Result<()> {
    let mut set = crate::draw::DrawSettings::beside(run.stage_dir());
    set.width = Some(args.width);
    set.height = Some(args.height);
    set.relative = args.relative;
    let names = crate::draw::draw_diagram(run.stage_dir(), &set)?;
    run.record_staged(&names);
    Ok(())
}

/// `k²` of every loop of the exact diagram `d` (its columns `p` and `k`) against `L̄`, with
/// Eq. (B.4) (paper Fig. 11; SVG).
pub fn k2_figure(d: &Diagram, width: f64, height: f64) -> Result<String> {
    let k2 = d
        .points
        .iter()
        .map(
            |p| match (p.extra.get("p"), p.extra.get("k"), p.coords.first()) {
                (Some(Cell::I(period)), Some(Cell::F(k)), Some(&lbar)) => {
                    Ok(rodloop_figures::k2::K2Point {
                        branch: p.branch,
                        eta: p.eta,
                        p: i32::try_from(*period)?,
                        lbar,
                        k2: k * k,
                    })
                }
                _ => bail!(
                    "the k² figure needs the exact diagram's columns p and k (branch {} has none)",
                    p.branch
                ),
            },
        )
        .collect::<Result<Vec<_>>>()?;
    Ok(rodloop_figures::k2::k2_figure(&k2, width, height)?)
}

/// The selected branch numbers, checked against the window.
fn selected_branches(args: &Args, lbar_min: f64, lbar_max: f64) -> Result<Option<Vec<u32>>> {
    if args.branch.is_empty() {
        return Ok(None);
    }
    let available: Vec<u32> = etas_in(lbar_min, lbar_max)
        .into_iter()
        .map(rodloop_exact::branch_of_eta)
        .collect();
    let mut out = Vec::new();
    for &b in &args.branch {
        let ok = u32::try_from(b).ok().filter(|b| available.contains(b));
        match ok {
            Some(b) => out.push(b),
            None => bail!(
                "--branch {b}: no such branch in the length range [{lbar_min}, {lbar_max}] (branches there: {})",
                available
                    .iter()
                    .map(|b| b.to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        }
    }
    out.sort_unstable();
    out.dedup();
    Ok(Some(out))
}

/// The part of the subcommand that needs no scene: the checks of the arguments of `--param`
/// (`Some`: the scene's engine sweeps it) or of a diagram in `L̄` (`None`: the scene's engine
/// draws it).
pub fn param_or_checked(args: &Args) -> Result<Option<param::Checked>> {
    if args.relative && args.param.is_some() {
        bail!("--relative draws the diagram in L̄ relative to its stable states; it does not apply to --param");
    }
    if let Some(p) = &args.param {
        return param::check(args, p).map(Some);
    }
    if args.lbar.is_some() || args.to.is_some() {
        bail!("--lbar and --to belong to --param (the equilibria at a fixed length against a parameter); the diagram in L̄ takes --lbar-min and --lbar-max");
    }
    Ok(None)
}

/// The diagram in `L̄` of a surface scene (numeric or exact model).
pub(crate) fn run_surface(args: &Args, scene: &rodloop_scene::Scene) -> Result<()> {
    let lbar_min = args.lbar_min.unwrap_or(scene.lbar_min);
    let lbar_max = args.lbar_max.unwrap_or(scene.lbar_max);
    if !(lbar_min > 0.0 && lbar_max > lbar_min && lbar_max <= 50.0) {
        bail!(
            "need 0 < --lbar-min < --lbar-max <= 50 (got {} and {})",
            lbar_min,
            lbar_max
        );
    }
    let selection = selected_branches(args, lbar_min, lbar_max)?;
    if args.shapes > crate::atlas::MAX_SHAPES {
        bail!(
            "--shapes must be from 0 to {} (got {})",
            crate::atlas::MAX_SHAPES,
            args.shapes
        );
    }
    if args.model == Model::Numeric {
        if let Some(step) = args.step {
            bail!(
                "--step {step} applies to --model exact only: the numeric model reports the states its continuation lands on (their spacing adapts to the branch)"
            );
        }
        return run_numeric(args, scene, lbar_min, lbar_max, selection.as_deref());
    }
    if let Some(a) = &args.accuracy {
        bail!(
            "--accuracy {a} applies to --model numeric only: the exact model solves the closed-form closure to machine precision"
        );
    }
    if args.resume {
        bail!(
            "--resume applies to --model numeric only: the exact diagram takes milliseconds and is always computed afresh"
        );
    }
    if args.max_step.is_some()
        || args.min_step.is_some()
        || args.max_points.is_some()
        || args.newton_tol.is_some()
    {
        bail!(
            "--max-step, --min-step, --max-points and --newton-tol control the numeric model's continuation; the exact model samples closed-form loops (use --step)"
        );
    }
    // Energies and lengths are normalised (E R/(pi D), L/(2 pi R)), so R does not matter.
    if !scene.stiffness.is_uniform() {
        bail!(
            "--model exact covers homogeneous loops only; scene {} has a non-uniform stiffness (use --model numeric)",
            scene.name
        );
    }
    let step = args.step.unwrap_or(0.01);
    if !(step.is_finite() && step > 0.0 && (lbar_max - lbar_min) / step <= 1e6) {
        bail!("--step must be a positive number giving at most 1e6 samples (got {step})");
    }
    if step > lbar_max - lbar_min {
        bail!(
            "--step {step:e} is longer than the range [{lbar_min}, {lbar_max}]: the exact diagram needs at least two sampled lengths"
        );
    }
    let run = OutputRun::begin(&args.out)?;
    let mut engine = ExactEngine {
        lbar_min,
        lbar_max,
        step,
        branches: selection,
        threads: std::thread::available_parallelism().map_or(1, |n| n.get()),
    };
    let out = engine.run(&mut |()| {})?;
    let mut schema = engine.schema(&out, &scene.name)?;
    crate::output::write_diagram(&run, &mut schema)?;
    // Fig. 11: k² against L̄ with Eq. (B.4).
    let k2_svg = k2_figure(&schema, f64::from(args.width), f64::from(args.height))?;
    run.write_bytes("diagram_k2.svg", k2_svg.as_bytes())?;
    run.write_bytes(
        "diagram_k2.png",
        &rodloop_figures::raster::svg_to_png(&k2_svg, 1.0)?,
    )?;
    let atlas = match args.shapes {
        0 => None,
        k => Some(crate::atlas::write_exact_atlas(&run, k, &schema)?),
    };
    draw_figures(args, &run)?;
    run.commit()?;

    outln!("Critical lengths (exact model, homogeneous loops on the sphere):");
    for line in schema.critical_table(None) {
        outln!("{line}");
    }
    outln!(
        "{} on {}, {} continuation points, computed in {:.3} s; wrote branches.csv, critical.csv, diagram.svg/.png, diagram_g.svg/.png, diagram_split.svg/.png, diagram_lambda.svg/.png, diagram_k2.svg/.png (Fig. 11), summary.json to {}",
        crate::output::plural(schema.points.len() as u64, "state"),
        crate::output::plural(
            schema.get::<u64>("branches").unwrap_or_default(),
            "branch"
        ),
        schema
            .get::<usize>("continuation_points")
            .unwrap_or_default(),
        schema.get::<f64>("seconds").unwrap_or_default(),
        args.out.display()
    );
    if let Some(a) = atlas {
        outln!(
            "atlas: {} rows, {} thumbnails in atlas/, atlas.svg/.png",
            a.rows.len(),
            a.rows.iter().map(|r| r.2.len()).sum::<usize>()
        );
    }
    Ok(())
}

/// The numeric model: trace, locate, label, write, print.
fn run_numeric(
    args: &Args,
    scene: &rodloop_scene::Scene,
    lbar_min: f64,
    lbar_max: f64,
    selection: Option<&[u32]>,
) -> Result<()> {
    let accuracy = crate::args::accuracy_of(scene, args.accuracy.as_deref())?;
    let opts = rodloop_diagram::DiagramOptions {
        radius: scene.radius,
        stiffness: crate::args::stiffness_of(&scene.stiffness),
        lbar_min,
        lbar_max,
        accuracy,
        controls: rodloop_diagram::TraceControls {
            max_step: args.max_step,
            min_step: args.min_step,
            max_points: args.max_points,
            newton_tol: args.newton_tol,
        },
        ..Default::default()
    };
    opts.validate()?;
    let run = OutputRun::begin(&args.out)?;
    run.keep_branch_files();
    let (d, schema) = surface::run_numeric(
        &opts,
        &args.out,
        args.resume,
        args.quiet,
        selection,
        &scene.name,
    )?;
    let (schema, state_warnings) = surface::write_outputs(&d, schema, &opts, &run)?;
    let atlas = match args.shapes {
        0 => None,
        k => Some(crate::atlas::write_atlas(&run, k, &scene.name)?),
    };
    draw_figures(args, &run)?;
    run.commit()?;
    // For homogeneous scenes, show the exact layer's critical lengths next to the numeric ones:
    // the same critical length (same kind, same branches) of the exact diagram of this window.
    let exact = crate::engine::exact_layer(scene, lbar_min, lbar_max)
        .ok()
        .flatten();
    outln!(
        "Critical lengths (numeric model, scene {}, accuracy {:?}):",
        scene.name,
        accuracy
    );
    let side = exact.as_ref().map(|e| SideColumn {
        header: "exact deviation".into(),
        width: 17,
        cells: schema
            .critical
            .iter()
            .map(|c| {
                exact_counterpart(c, e).map_or("no exact match".into(), |x| {
                    format!("{:.1e}", c.lbar_cr - x.lbar_cr)
                })
            })
            .collect(),
    });
    for line in schema.critical_table(side.as_ref()) {
        outln!("{line}");
    }
    if let Some(gc) = schema.get::<rodloop_diagram::BucklingReport>("great_circles") {
        for l in &gc.loads {
            if let (Some(f), Some(eq)) = (l.lambda_formula, &l.equation) {
                outln!(
                    "  buckling of the {}-fold great circle (mode with {} of kappa_g): lambda R^3/D = {:.10} ± {:.1e}, Eq. ({eq}) {:.10}",
                    l.m,
                    crate::output::plural(l.mode_periods as u64, "period"),
                    l.lambda_numeric,
                    l.lambda_error,
                    f
                );
            }
        }
    }
    for w in surface::engine_warnings(&schema, state_warnings) {
        eprintln!("warning: {w}");
    }
    outln!(
        "{} on {} in {:.2} s (tracing {:.2} s); wrote branches.csv, critical.csv, diagram.svg/.png, diagram_split.svg/.png, diagram_lambda.svg/.png, summary.json to {}",
        crate::output::plural(schema.points.len() as u64, "state"),
        surface::branch_count(&schema.curves),
        surface::seconds(&schema, "total"),
        surface::seconds(&schema, "tracing"),
        args.out.display()
    );
    outln!(
        "every traced state's shape is in states/ (the state_file column of branches.csv; re-solve with solve --from, draw with draw)"
    );
    if let Some(a) = atlas {
        outln!(
            "atlas: {} rows, {} thumbnails in atlas/, atlas.svg/.png",
            a.rows.len(),
            a.rows.iter().map(|r| r.2.len()).sum::<usize>()
        );
    }
    Ok(())
}
