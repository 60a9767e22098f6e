//! `rodloop phase`: the critical lengths of a two-segment rod as curves in a stiffness
//! parameter (two-parameter continuation of the Maxwell points, paper Sec. 5).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use rodloop_diagram::phase::{trace_phase, PhaseDiagram, PhaseSettings, RowSource};
use rodloop_figures::plot::{LegendItem, Plot, Series};
use rodloop_figures::raster::svg_to_png;
use rodloop_figures::svg::{Anchor, Svg};
use rodloop_solver::{Param, SolveOptions};

use crate::output::{check_finite, strip_nulls, Cell, OutputRun, Table};
use crate::solve::{accuracy_of, load_scene, stiffness_of};

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
    #[arg(long)]
    pub accuracy: Option<String>,
    /// Output directory.
    #[arg(long, default_value = "out/phase")]
    pub out: PathBuf,
}

/// Run `rodloop phase`.
pub fn run(args: &Args) -> Result<()> {
    let t0 = Instant::now();
    let scene = load_scene(Some(&args.scene))?;
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
    let accuracy = accuracy_of(&scene, args.accuracy.as_deref())?;
    let settings = PhaseSettings {
        radius: scene.radius,
        stiffness: stiffness_of(&scene.stiffness),
        param,
        target: args.to,
        lbar_min: scene.lbar_min,
        lbar_max: scene.lbar_max,
        accuracy,
        at: args.at.clone(),
        solve: SolveOptions::default(),
    };
    let run = OutputRun::begin(&args.out)?;
    let diagram =
        trace_phase(&settings).with_context(|| format!("phase diagram of scene {}", scene.name))?;
    let seconds = t0.elapsed().as_secs_f64();

    let table = phase_table(&diagram)?;
    let svg = phase_svg(&diagram, &scene.name);
    let png = svg_to_png(&svg, 1.0).context("rendering phase.png")?;

    // People: the limit check, the ends and notes of each curve.
    for c in &diagram.curves {
        let ex = c.exchange;
        outln!(
            "exchange {} -> {} (uniform rod: L̄_cr = {:.10}): {} rows, {} continuation steps",
            ex.from_branch,
            ex.to_branch,
            ex.lbar_uniform,
            c.rows.len(),
            c.steps
        );
        for r in c
            .rows
            .iter()
            .filter(|r| r.source != RowSource::Continuation)
        {
            outln!(
                "  {} = {:<10.6} L̄_cr = {:.10} ± {:.1e}  E R/(pi D0) = {:.8}  ({}, lowest {} -> {})",
                diagram.param,
                r.value,
                r.lbar_cr,
                r.error_estimate,
                r.energy,
                r.source.name(),
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
                "phase: exchange {} -> {}: the curve ends at {} = {} ({}): {}",
                ex.from_branch, ex.to_branch, diagram.param, e.value, e.kind, e.reason
            );
        }
        for t in c.turns.iter().chain(&c.switches) {
            eprintln!(
                "phase: exchange {} -> {}: {t}",
                ex.from_branch, ex.to_branch
            );
        }
        for n in &c.notes {
            eprintln!(
                "phase: exchange {} -> {}: note: {n}",
                ex.from_branch, ex.to_branch
            );
        }
    }
    outln!("time {seconds:.2} s");

    let summary = serde_json::json!({
        "command": "phase",
        "scene": scene.name,
        "param": diagram.param,
        "scene_value": diagram.scene_value,
        "target": diagram.target,
        "accuracy": accuracy,
        "at": args.at,
        "curves": diagram.curves.iter().map(|c| serde_json::json!({
            "exchange": c.exchange,
            "rows": c.rows.len(),
            "steps": c.steps,
            "cells": c.cells,
            "ends": c.ends,
            "uniform": c.uniform,
            "turns": c.turns,
            "switches": c.switches,
            "notes": c.notes,
        })).collect::<Vec<_>>(),
        "time_seconds": seconds,
        "files": ["phase.csv", "phase.svg", "phase.png"],
    });
    check_finite("summary.json", &summary)?;
    run.write_table(&table)?;
    run.write_bytes("phase.svg", svg.as_bytes())?;
    run.write_bytes("phase.png", &png)?;
    run.write_json("summary.json", &strip_nulls(summary))?;
    run.commit()?;
    outln!("wrote {}", args.out.display());
    Ok(())
}

/// `phase.csv`: one row per Maxwell point.
fn phase_table(d: &PhaseDiagram) -> Result<Table> {
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
        ],
    );
    for (k, c) in d.curves.iter().enumerate() {
        for r in &c.rows {
            t.push(vec![
                Cell::S(d.param.name().into()),
                Cell::F(r.value),
                Cell::F(r.lbar_cr),
                Cell::S("crossing".into()),
                Cell::I(r.from_branch.into()),
                Cell::I(r.to_branch.into()),
                Cell::F(r.energy),
                Cell::F(r.error_estimate),
                Cell::S(r.source.name().into()),
                Cell::I(k as i64 + 1),
                Cell::I(r.arm as i64),
                Cell::I(r.index.0 as i64),
                Cell::I(r.index.1 as i64),
                Cell::F(r.slope),
            ])?;
        }
    }
    Ok(t)
}

/// `phase.svg`: `L̄_cr` against the parameter (log axis for `d1`), the regions between the
/// curves labelled by their lowest branch.
fn phase_svg(d: &PhaseDiagram, scene: &str) -> String {
    let log = d.param == Param::D1;
    let xv = |v: f64| if log { v.log10() } else { v };
    let colors = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd"];
    let mut plot = Plot {
        title: format!("Critical lengths of scene {scene} against {}", d.param),
        xlabel: if log {
            "log₁₀(D1/D0)".into()
        } else {
            d.param.name().into()
        },
        ylabel: "critical length L̄_cr = L/(2πR)".into(),
        legend_width: 0.0,
        ..Default::default()
    };
    let mut all: Vec<(f64, f64)> = Vec::new();
    for (k, c) in d.curves.iter().enumerate() {
        let arms = c.rows.iter().map(|r| r.arm).max().unwrap_or(0);
        for arm in 0..=arms {
            let pts: Vec<(f64, f64)> = c
                .rows
                .iter()
                .filter(|r| r.arm == arm)
                .map(|r| (xv(r.value), r.lbar_cr))
                .collect();
            all.extend(&pts);
            plot.series.push(Series {
                color: colors[k % colors.len()].into(),
                width: 2.0,
                dash: if arm == 0 {
                    String::new()
                } else {
                    "6 4".into()
                },
                points: pts,
            });
        }
        plot.legend.push(LegendItem::Line {
            label: format!(
                "exchange {} → {} (uniform: {:.4})",
                c.exchange.from_branch, c.exchange.to_branch, c.exchange.lbar_uniform
            ),
            color: colors[k % colors.len()].into(),
            width: 2.0,
            dash: String::new(),
        });
    }
    let (mut x0, mut x1, mut y0, mut y1) = all.iter().fold(
        (
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ),
        |r, p| (r.0.min(p.0), r.1.max(p.0), r.2.min(p.1), r.3.max(p.1)),
    );
    if !x0.is_finite() {
        (x0, x1, y0, y1) = (0.0, 1.0, 1.0, 3.0);
    }
    let ypad = 0.15 * (y1 - y0).max(0.1);
    let range = (x0, x1.max(x0 + 1e-9), y0 - ypad, y1 + ypad);
    plot.range = Some(range);
    let (w, h) = (820.0, 520.0);
    let mut svg = Svg::new(w, h);
    svg.rect(0.0, 0.0, w, h, "white", "none", 0.0);
    plot.render(&mut svg, 0.0, 0.0, w, h, "phase");
    // Region labels at the middle of the x range: the lowest branch between the curves
    // (margins of `Plot::render` with a title and no vline labels: 68, 16, 36, 50).
    let (px, py, pw, ph) = (68.0, 36.0, w - 68.0 - 16.0, h - 36.0 - 50.0);
    let sy = |v: f64| py + ph - (v - range.2) / (range.3 - range.2) * ph;
    let sx = |v: f64| px + (v - range.0) / (range.1 - range.0) * pw;
    // Each curve separates its lower branch (below) from its upper one (above): labels at
    // the middle of the curve's own range.
    for c in &d.curves {
        let xs: Vec<f64> = c
            .rows
            .iter()
            .filter(|r| r.arm == 0)
            .map(|r| xv(r.value))
            .collect();
        let (lo, hi) = xs.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |r, &x| {
            (r.0.min(x), r.1.max(x))
        });
        let xm = 0.5 * (lo + hi);
        let near = c.rows.iter().filter(|r| r.arm == 0).min_by(|a, b| {
            (xv(a.value) - xm)
                .abs()
                .total_cmp(&(xv(b.value) - xm).abs())
        });
        if let Some(r) = near {
            let (x, y) = (sx(xm), sy(r.lbar_cr));
            svg.text(
                x,
                y + 18.0,
                12.5,
                Anchor::Middle,
                &format!("branch {} lowest ↓", r.from_branch),
            );
            svg.text(
                x,
                y - 9.0,
                12.5,
                Anchor::Middle,
                &format!("branch {} lowest ↑", r.to_branch),
            );
        }
    }
    // Integer lengths inside the range: collapses onto m-fold great circles.
    let mut m = range.2.ceil();
    while m <= range.3 {
        svg.line(px, sy(m), px + pw, sy(m), "#999", 0.8, "4 3");
        svg.text(
            px + pw - 6.0,
            sy(m) - 5.0,
            11.0,
            Anchor::End,
            &format!("L̄ = {m}: {m}-fold great circle"),
        );
        m += 1.0;
    }
    svg.finish()
}
