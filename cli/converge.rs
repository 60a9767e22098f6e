//! `rodloop converge`: one state solved on a ladder of resolutions, to measure the
//! speed/accuracy trade (error against cells and time, observed order of convergence).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use rodloop_exact::eta_of_branch;
use rodloop_scene::{Scene, StiffnessSpec};
use rodloop_solver::{solve_cells, Accuracy, SolveOptions, StartShape};
use serde_json::json;

use crate::args::stiffness_of;
use crate::output::{Cell, OutputRun, Table};

/// Arguments of `rodloop converge`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Normalised length L/(2 pi R).
    #[arg(long, allow_negative_numbers = true)]
    pub lbar: f64,
    /// Paper branch number (1: saddle, eta = 2; 2: figure-eight, eta = 1; B >= 3: eta = B).
    #[arg(long)]
    pub branch: u32,
    /// Scene file (TOML; see data/scenes/). Default: homogeneous loop on the unit sphere.
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Coarsest number of cells of the ladder, at least 8 (default: a quarter of the `default`
    /// accuracy's cells).
    #[arg(long)]
    pub min_cells: Option<usize>,
    /// Number of resolutions (each doubles the cells), 3 to 9.
    #[arg(long, default_value_t = 6)]
    pub levels: usize,
    /// Output directory.
    #[arg(long, default_value = "out/converge")]
    pub out: PathBuf,
}

/// One rung of the ladder.
struct Rung {
    cells: usize,
    energy: f64,
    lambda: (f64, f64),
    seconds: f64,
}

/// The `η` of `--branch`, with `--levels` and `--lbar` checked.
pub(crate) fn checked_eta(args: &Args) -> Result<u32> {
    if args.branch == 0 || args.branch > 1000 {
        bail!("--branch must be from 1 to 1000 (got {})", args.branch);
    }
    if !(3..=9).contains(&args.levels) {
        bail!("--levels must be from 3 to 9 (got {})", args.levels);
    }
    let eta = eta_of_branch(args.branch);
    let e = f64::from(eta);
    if !(args.lbar.is_finite() && args.lbar > e - 1.0 && args.lbar < e + 1.0) {
        bail!(
            "branch {} (eta = {eta}) exists only for {} < lbar < {}; got lbar = {}",
            args.branch,
            e - 1.0,
            e + 1.0,
            args.lbar
        );
    }
    Ok(eta)
}

/// The cells of the coarsest rung (`--min-cells`, else a quarter of the default level's
/// `default_cells`), checked with the finest rung against the cap.
pub(crate) fn ladder_base(args: &Args, default_cells: usize) -> Result<usize> {
    if let Some(m) = args.min_cells.filter(|&m| m < 8) {
        bail!("--min-cells must be at least 8 (got {m})");
    }
    let base = args.min_cells.unwrap_or(default_cells / 4).max(8);
    let finest = base.saturating_mul(1 << (args.levels - 1));
    if finest > 65_536 {
        bail!(
            "the finest rung would have {finest} cells (cap 65536): lower --min-cells or --levels"
        );
    }
    Ok(base)
}

/// The empty `converge.csv` table.
fn converge_table() -> Table {
    Table::new(
        "converge.csv",
        &[
            "nodes",
            "energy",
            "error_estimate",
            "error_vs_finest",
            "error_vs_exact",
            "observed_order",
            "lambda_min",
            "lambda_max",
            "seconds",
            "state_file",
        ],
    )
}

/// The ladder: rung `k` solved at `base · 2^k` cells from `start` (the rung below as the
/// fallback start), with its energy, force range and time; and the finest state.
fn solve_ladder(
    args: &Args,
    scene: &rodloop_scene::Scene,
    stiffness: &rodloop_solver::Stiffness,
    start: &StartShape,
    base: usize,
) -> Result<(Vec<Rung>, Option<rodloop_solver::Equilibrium>)> {
    let opts = SolveOptions::default();
    let mut rungs: Vec<Rung> = Vec::new();
    let mut prev = None;
    for k in 0..args.levels {
        let cells = base << k;
        let t0 = Instant::now();
        // Each rung is solved from the Euler start (so its time is that of a user's solve),
        // the coarse solution only serving as a fallback start.
        let eq = match solve_cells(
            scene.radius,
            args.lbar,
            cells,
            stiffness,
            start,
            None,
            &opts,
        ) {
            Ok(eq) => eq,
            Err(first) => solve_cells(
                scene.radius,
                args.lbar,
                cells,
                stiffness,
                start,
                prev.as_ref(),
                &opts,
            )
            .with_context(|| format!("solving at {cells} cells (from the Euler start: {first})"))?,
        };
        let seconds = t0.elapsed().as_secs_f64();
        rungs.push(Rung {
            cells,
            energy: eq.energy().total,
            lambda: eq.lambda_range(),
            seconds,
        });
        prev = Some(eq);
    }
    Ok((rungs, prev))
}

/// Run the subcommand on a surface scene.
pub fn run(args: &Args, scene: &Scene) -> Result<()> {
    let eta = checked_eta(args)?;
    let stiffness = stiffness_of(&scene.stiffness);
    let start = StartShape::Euler { l: eta };
    let default_cells = Accuracy::Default.cells(eta as usize, &stiffness);
    let base = ladder_base(args, default_cells)?;
    let (rungs, prev) = solve_ladder(args, scene, &stiffness, &start, base)?;
    let exact = match (&scene.stiffness, scene.radius) {
        (StiffnessSpec::Uniform { .. }, _) => rodloop_exact::paper_branch_loop(eta, args.lbar)
            .ok()
            .and_then(|l| l.energy().ok()),
        _ => None,
    };
    let finest_e = rungs.last().map(|r| r.energy).unwrap_or(f64::NAN);
    // The finest state, verified as its file holds it against its row (energy and the
    // estimate from the rung below): states/finest.csv.
    let n = rungs.len();
    let finest_estimate =
        rodloop_solver::richardson_error(rungs[n - 1].energy, rungs[n - 2].energy);
    let finest_file = prev.as_ref().context("no rung was solved").and_then(|eq| {
        rodloop_diagram::reported::verify_reported(eq, finest_e, Some(finest_estimate))
            .map_err(anyhow::Error::from)
    });
    let state_name = "states/finest.csv";
    let (state_file, unverified) = match &finest_file {
        Ok(_) => (state_name.to_string(), 0),
        Err(e) => {
            eprintln!(
                "warning: UNVERIFIED STATE LEFT WITHOUT A FILE: the finest rung ({} cells): {e:#}",
                rungs[n - 1].cells
            );
            (String::new(), 1)
        }
    };
    let reference = exact.unwrap_or(finest_e);
    let mut table = converge_table();
    outln!(
        "branch {} (eta = {eta}) at lbar = {}, scene {}: energy E R/(pi D0) on {} resolutions{}",
        args.branch,
        args.lbar,
        scene.name,
        rungs.len(),
        if exact.is_some() {
            format!(" (exact value {:.15})", reference)
        } else {
            String::new()
        }
    );
    outln!(
        "{:>7} {:>19} {:>10} {:>10} {:>10} {:>6} {:>12} {:>12} {:>9}",
        "nodes",
        "energy",
        "estimate",
        "vs finest",
        "vs exact",
        "order",
        "lambda_min",
        "lambda_max",
        "seconds"
    );
    let mut rows = Vec::new();
    let energies: Vec<f64> = rungs.iter().map(|r| r.energy).collect();
    let errors = rodloop_solver::accuracy::rung_errors(&energies, exact);
    for (i, (r, err)) in rungs.iter().zip(errors).enumerate() {
        let (estimate, vs_finest, vs_exact, order) =
            (err.estimate, err.vs_finest, err.vs_exact, err.order);
        let opt = |v: Option<f64>| v.map(Cell::F).unwrap_or(Cell::S(String::new()));
        table.push(vec![
            Cell::I(r.cells as i64),
            Cell::F(r.energy),
            opt(estimate),
            opt(vs_finest),
            opt(vs_exact),
            opt(order),
            Cell::F(r.lambda.0),
            Cell::F(r.lambda.1),
            Cell::F(r.seconds),
            Cell::S(if i + 1 == n {
                state_file.clone()
            } else {
                String::new()
            }),
        ])?;
        let show = |v: Option<f64>, w: usize| match v {
            Some(x) => format!("{x:>w$.1e}"),
            None => format!("{:>w$}", "-"),
        };
        outln!(
            "{:>7} {:>19.15} {} {} {} {:>6} {:>12.6} {:>12.6} {:>9.4}",
            r.cells,
            r.energy,
            show(estimate, 10),
            show(vs_finest, 10),
            show(vs_exact, 10),
            order
                .map(|o| format!("{o:.2}"))
                .unwrap_or_else(|| "-".into()),
            r.lambda.0,
            r.lambda.1,
            r.seconds
        );
        rows.push(json!({
            "nodes": r.cells, "energy": r.energy, "error_estimate": estimate,
            "error_vs_finest": vs_finest, "error_vs_exact": vs_exact, "observed_order": order,
            "lambda_min": r.lambda.0, "lambda_max": r.lambda.1, "seconds": r.seconds,
        }));
    }
    let fast = Accuracy::Fast.cells(eta as usize, &stiffness);
    outln!(
        "accuracy levels: fast = {fast} cells (estimate from {}), default = {default_cells} cells (estimate from {}), high = {} and {} cells Richardson-extrapolated",
        fast / 2,
        default_cells / 2,
        default_cells,
        2 * default_cells
    );
    let summary = json!({
        "scene": scene.name,
        "lbar": args.lbar,
        "branch": args.branch,
        "eta": eta,
        "exact_energy": exact,
        "rungs": rows,
        "state_file": (!state_file.is_empty()).then_some(&state_file),
        "unverified_states": unverified,
        "accuracy_cells": {"fast": fast, "default": default_cells, "high": [default_cells, 2 * default_cells]},
        "units": "energy E R/(pi D0); lambda in units of D0/R^3; seconds of wall time per solve",
    });
    let summary = crate::output::strip_nulls(summary);
    crate::output::check_finite("summary.json", &summary)?;
    // The figure: error against cells and time, log-log, with the fitted order. The error is
    // against the exact value where there is one, else against the finest rung (which then
    // has none); errors below the rounding level of the energy stay out of the fit.
    let fig_rungs: Vec<rodloop_figures::convergence::Rung> = rungs
        .iter()
        .map(|r| rodloop_figures::convergence::Rung {
            cells: r.cells,
            error: (r.energy - reference).abs(),
            seconds: r.seconds,
        })
        .take(if exact.is_some() {
            rungs.len()
        } else {
            rungs.len() - 1
        })
        .collect();
    let floor = 1e-13 * reference.abs().max(1.0);
    let fig = rodloop_figures::convergence::convergence_figure(
        &fig_rungs,
        if exact.is_some() {
            "|E − E_exact| R/(πD₀)"
        } else {
            "|E − E_finest| R/(πD₀)"
        },
        floor,
        &format!(
            "Convergence of branch {} (η = {eta}) at L̄ = {}, scene {}",
            args.branch, args.lbar, scene.name
        ),
        960.0,
        460.0,
    );
    let run = OutputRun::begin(&args.out)?;
    if let Ok(f) = &finest_file {
        let dir = run.subdir("states")?;
        crate::states::write_state_file(&dir, state_name, f, scene.radius, stiffness.reference())?;
    }
    run.write_table(&table)?;
    let figure_note = match fig {
        Ok(svg) => {
            let png =
                rodloop_figures::raster::svg_to_png(&svg, 1.0).context("rendering converge.png")?;
            run.write_bytes("converge.svg", svg.as_bytes())?;
            run.write_bytes("converge.png", &png)?;
            ", converge.svg/.png".to_string()
        }
        Err(e) => {
            eprintln!("note: no convergence figure: {e}");
            String::new()
        }
    };
    let mut summary = summary;
    if let Some(obj) = summary.as_object_mut() {
        let order = rodloop_figures::convergence::fitted_order(&fig_rungs, floor);
        obj.insert("fitted_order".into(), json!(order));
        obj.insert("fit_error_floor".into(), json!(floor));
        if let Some(p) = order {
            outln!(
                "fitted order of convergence {p:.2} (least squares of log error against log cells, errors above {floor:.0e})"
            );
        }
    }
    let summary = crate::output::strip_nulls(summary);
    run.write_json("summary.json", &summary)?;
    run.commit()?;
    outln!(
        "wrote converge.csv{figure_note} and summary.json to {}",
        args.out.display()
    );
    Ok(())
}
