//! `rodloop diagram`: the energy-versus-length diagram and its critical lengths.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Result};
use rodloop_exact::diagram::{compute, Diagram, DiagramSettings};
use serde_json::json;

use crate::output::{
    critical_table, ensure_dir, write_atomic, write_json, Cell, CriticalRow, Table,
};
use crate::svg::{self, branch_color, Curve, Figure, LegendEntry, LineStyle, Marker};

/// Which model computes the diagram.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Model {
    /// Numerical equilibria of the scene (any stiffness profile), traced by continuation.
    Numeric,
    /// Closed-form elliptic-function solutions (homogeneous loops on the surface only).
    Exact,
}

/// Arguments of `rodloop diagram`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Model used to compute the branches.
    #[arg(long, value_enum, default_value_t = Model::Numeric)]
    pub model: Model,
    /// Scene file (TOML; see data/scenes/). Default: homogeneous loops on the unit sphere.
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Accuracy: fast, default or high (overrides the scene's; numeric model).
    #[arg(long)]
    pub accuracy: Option<String>,
    /// Smallest normalised length (default: the scene's, 1).
    #[arg(long)]
    pub lbar_min: Option<f64>,
    /// Largest normalised length (default: the scene's, 5).
    #[arg(long)]
    pub lbar_max: Option<f64>,
    /// Spacing of the sampled lengths in branches.csv (exact model).
    #[arg(long, default_value_t = 0.01)]
    pub step: f64,
    /// Continue an interrupted numeric run from the branch files in OUT/branches.
    #[arg(long)]
    pub resume: bool,
    /// No progress bars (they are also hidden when stderr is not a terminal).
    #[arg(long)]
    pub quiet: bool,
    /// Output directory.
    #[arg(long, default_value = "out/diagram")]
    pub out: PathBuf,
    /// Width of the diagram figures in pixels.
    #[arg(long, default_value_t = 960)]
    pub width: u32,
    /// Height of the diagram figures in pixels.
    #[arg(long, default_value_t = 620)]
    pub height: u32,
}

/// The figures of `draw_diagram` (diagram, diagram_split, diagram_lambda; SVG and PNG).
fn draw_figures(args: &Args) -> Result<()> {
    let mut set = crate::draw::DrawSettings::beside(&args.out);
    set.width = Some(args.width);
    set.height = Some(args.height);
    crate::draw::draw_diagram(&args.out, &set)?;
    Ok(())
}

/// Run the subcommand.
pub fn run(args: &Args) -> Result<()> {
    let scene = crate::solve::load_scene(args.scene.as_deref())?;
    let lbar_min = args.lbar_min.unwrap_or(scene.lbar_min);
    let lbar_max = args.lbar_max.unwrap_or(scene.lbar_max);
    if !(lbar_min > 0.0 && lbar_max > lbar_min && lbar_max <= 50.0) {
        bail!(
            "need 0 < --lbar-min < --lbar-max <= 50 (got {} and {})",
            lbar_min,
            lbar_max
        );
    }
    if args.model == Model::Numeric {
        return run_numeric(args, &scene, lbar_min, lbar_max);
    }
    // Energies and lengths are normalised (E R/(pi D), L/(2 pi R)), so R does not matter.
    if !scene.stiffness.is_uniform() {
        bail!(
            "--model exact covers homogeneous loops only; scene {} has a non-uniform stiffness (use --model numeric)",
            scene.name
        );
    }
    if !(args.step > 0.0 && (lbar_max - lbar_min) / args.step <= 1e6) {
        bail!(
            "--step must be positive and give at most 1e6 samples (got {})",
            args.step
        );
    }
    let t0 = Instant::now();
    let settings = DiagramSettings {
        lbar_min,
        lbar_max,
        eta_max: (lbar_max.floor() as u32).max(1),
        step: args.step,
    };
    let d = compute(&settings)?;
    let elapsed = t0.elapsed();

    let mut branches = Table::new(
        "branches.csv",
        &[
            "branch",
            "eta",
            "p",
            "lbar",
            "energy",
            "energy_g",
            "lambda_min",
            "lambda_max",
            "k",
            "c",
            "closure_residual",
            "lowest",
        ],
    );
    for p in &d.points {
        branches.push(vec![
            Cell::I(p.branch.into()),
            Cell::I(p.eta.into()),
            Cell::I(p.p.into()),
            Cell::F(p.lbar),
            Cell::F(p.energy),
            Cell::F(p.energy_g),
            Cell::F(p.lambda_min),
            Cell::F(p.lambda_max),
            Cell::F(p.k),
            Cell::F(p.c),
            Cell::F(p.closure_residual),
            Cell::I(p.lowest.into()),
        ])?;
    }
    let critical = critical_table(d.critical.iter().map(|c| CriticalRow {
        index: c.index,
        lbar_cr: c.lbar_cr,
        kind: c.kind,
        from_branch: c.from_branch,
        to_branch: c.to_branch,
        energy: c.energy,
        error_estimate: c.error_estimate,
    }))?;
    ensure_dir(&args.out)?;
    branches.write(&args.out)?;
    critical.write(&args.out)?;
    for (name, energy_g) in [("diagram.svg", false), ("diagram_g.svg", true)] {
        let fig = figure(&d, energy_g);
        write_atomic(&args.out, name, svg::render(&fig).as_bytes())?;
    }
    draw_figures(args)?;
    let summary = json!({
        "model": "exact",
        "lbar_min": lbar_min,
        "lbar_max": lbar_max,
        "step": args.step,
        "branches": d.points.len(),
        "continuation_points": d.continuation_steps,
        "critical": d.critical,
        "seconds": elapsed.as_secs_f64(),
    });
    write_json(&args.out, "summary.json", &summary)?;

    outln!("Critical lengths (exact model, homogeneous loops on the sphere):");
    outln!(
        "  {:>2}  {:>18}  {:>9}  {:>6}  {:>18}  {:>9}",
        "i",
        "lbar_cr",
        "kind",
        "from->to",
        "E R/(pi D)",
        "error"
    );
    for c in &d.critical {
        outln!(
            "  {:>2}  {:>18.15}  {:>9}  {:>3}->{:<2}  {:>18.15}  {:>9.1e}",
            c.index,
            c.lbar_cr,
            c.kind,
            c.from_branch,
            c.to_branch,
            c.energy,
            c.error_estimate
        );
    }
    outln!(
        "{} states on {} branches, {} continuation points, computed in {:.3} s; wrote branches.csv, critical.csv, diagram.svg/.png, diagram_g.svg, diagram_split.svg/.png, diagram_lambda.svg/.png, summary.json to {}",
        d.points.len(),
        d.points.iter().map(|p| p.branch).collect::<std::collections::BTreeSet<_>>().len(),
        d.continuation_steps,
        elapsed.as_secs_f64(),
        args.out.display()
    );
    Ok(())
}

/// The numeric model: trace, locate, label, write, print.
fn run_numeric(
    args: &Args,
    scene: &rodloop_scene::Scene,
    lbar_min: f64,
    lbar_max: f64,
) -> Result<()> {
    let accuracy = crate::solve::accuracy_of(scene, args.accuracy.as_deref())?;
    let opts = rodloop_diagram::DiagramOptions {
        radius: scene.radius,
        stiffness: crate::solve::stiffness_of(&scene.stiffness),
        lbar_min,
        lbar_max,
        accuracy,
        ..Default::default()
    };
    opts.validate()?;
    let d = crate::numeric_diagram::run_numeric(&opts, &args.out, args.resume, args.quiet)?;
    crate::numeric_diagram::write_outputs(&d, &opts, &scene.name, &args.out)?;
    draw_figures(args)?;
    // For homogeneous scenes, show the exact layer's critical lengths next to the numeric ones.
    let exact = if scene.stiffness.is_uniform() {
        compute(&DiagramSettings {
            lbar_min,
            lbar_max,
            eta_max: (lbar_max.floor() as u32).max(1),
            step: 0.01,
        })
        .ok()
    } else {
        None
    };
    outln!(
        "Critical lengths (numeric model, scene {}, accuracy {:?}):",
        scene.name,
        accuracy
    );
    outln!(
        "  {:>2}  {:>18}  {:>9}  {:>8}  {:>16}  {:>9}{}",
        "i",
        "lbar_cr",
        "kind",
        "from->to",
        "E R/(pi D0)",
        "error",
        if exact.is_some() {
            "    exact deviation"
        } else {
            ""
        }
    );
    for c in &d.critical {
        let dev = exact.as_ref().and_then(|e| {
            e.critical
                .iter()
                .min_by(|a, b| {
                    (a.lbar_cr - c.lbar_cr)
                        .abs()
                        .total_cmp(&(b.lbar_cr - c.lbar_cr).abs())
                })
                .map(|x| c.lbar_cr - x.lbar_cr)
        });
        outln!(
            "  {:>2}  {:>18.12}  {:>9}  {:>3}->{:<3}  {:>16.10}  {:>9.1e}{}",
            c.index,
            c.lbar_cr,
            c.kind,
            c.from_branch,
            c.to_branch,
            c.energy,
            c.error_estimate,
            dev.map(|x| format!("  {x:>17.1e}")).unwrap_or_default()
        );
    }
    if let Some(gc) = &d.great_circles {
        for l in &gc.loads {
            if let (Some(f), Some(eq)) = (l.lambda_formula, &l.equation) {
                outln!(
                    "  buckling of the {}-fold great circle (mode with {} periods of kappa_g): lambda R^3/D = {:.10} ± {:.1e}, Eq. ({eq}) {:.10}",
                    l.m,
                    l.mode_periods,
                    l.lambda_numeric,
                    l.lambda_error,
                    f
                );
            }
        }
    }
    for w in &d.warnings {
        eprintln!("warning: {w}");
    }
    outln!(
        "{} states on {} branches in {:.2} s (tracing {:.2} s); wrote branches.csv, critical.csv, diagram.svg/.png, diagram_split.svg/.png, diagram_lambda.svg/.png, summary.json to {}",
        d.rows().len(),
        d.branches.len(),
        d.timings.total,
        d.timings.tracing,
        args.out.display()
    );
    Ok(())
}

/// The energy (or its geodesic part) versus length, one colour per branch: solid where the
/// branch has the lowest energy, dashed elsewhere (the exact model does not compute the Hessian
/// index, so higher-energy states are not split into metastable and unstable), critical lengths
/// as vertical markers.
fn figure(d: &Diagram, energy_g: bool) -> Figure {
    let mut curves = Vec::new();
    let mut branches: Vec<u32> = d.points.iter().map(|p| p.branch).collect();
    branches.sort_unstable();
    branches.dedup();
    for &b in &branches {
        let pts: Vec<(f64, f64, bool)> = d
            .points
            .iter()
            .filter(|p| p.branch == b)
            .map(|p| {
                (
                    p.lbar,
                    if energy_g { p.energy_g } else { p.energy },
                    p.lowest,
                )
            })
            .collect();
        curves.extend(svg::runs(&pts, |lowest, points| Curve {
            color: branch_color(b),
            style: if lowest {
                LineStyle::Solid
            } else {
                LineStyle::Dashed
            },
            width: if lowest { 2.2 } else { 1.3 },
            points,
        }));
    }
    let mut legend: Vec<LegendEntry> = branches
        .iter()
        .map(|&b| LegendEntry {
            label: format!("branch {b} (eta = {})", rodloop_exact::eta_of_branch(b)),
            color: branch_color(b),
            style: LineStyle::Solid,
        })
        .collect();
    legend.push(LegendEntry {
        label: "solid: lowest energy".into(),
        color: "black".into(),
        style: LineStyle::Solid,
    });
    legend.push(LegendEntry {
        label: "dashed: higher energy".into(),
        color: "black".into(),
        style: LineStyle::Dashed,
    });
    let markers = d
        .critical
        .iter()
        .map(|c| Marker {
            x: c.lbar_cr,
            label: format!("{:.4}", c.lbar_cr),
        })
        .collect();
    Figure {
        title: if energy_g {
            "Exact branches: geodesic-curvature energy E_g R/(pi D)".into()
        } else {
            "Exact branches: bending energy E R/(pi D) of homogeneous loops on the sphere".into()
        },
        xlabel: "L / (2 pi R)".into(),
        ylabel: if energy_g {
            "E_g R/(pi D)"
        } else {
            "E R/(pi D)"
        }
        .into(),
        curves,
        markers,
        legend,
        range: None,
    }
}
