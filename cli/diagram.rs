//! `rodloop diagram`: the energy-versus-length diagram and its critical lengths.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Result};
use rodloop_exact::diagram::{compute, DiagramSettings};
use serde_json::json;

use crate::output::{ensure_dir, write_json, Cell, Table};

/// Which model computes the diagram.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Model {
    /// Closed-form elliptic-function solutions (homogeneous loops on the surface only).
    Exact,
    /// Discretised equilibria (any stiffness profile); not available yet.
    Numeric,
}

/// Arguments of `rodloop diagram`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Model used to compute the branches.
    #[arg(long, value_enum, default_value_t = Model::Exact)]
    pub model: Model,
    /// Smallest normalised length.
    #[arg(long, default_value_t = 1.0)]
    pub lbar_min: f64,
    /// Largest normalised length.
    #[arg(long, default_value_t = 5.0)]
    pub lbar_max: f64,
    /// Spacing of the sampled lengths in branches.csv.
    #[arg(long, default_value_t = 0.01)]
    pub step: f64,
    /// Output directory.
    #[arg(long, default_value = "out/diagram")]
    pub out: PathBuf,
}

/// Run the subcommand.
pub fn run(args: &Args) -> Result<()> {
    if args.model == Model::Numeric {
        bail!("--model numeric is not implemented yet; use --model exact (homogeneous loops on the sphere)");
    }
    if !(args.lbar_min > 0.0 && args.lbar_max > args.lbar_min && args.lbar_max <= 50.0) {
        bail!(
            "need 0 < --lbar-min < --lbar-max <= 50 (got {} and {})",
            args.lbar_min,
            args.lbar_max
        );
    }
    if !(args.step > 0.0 && (args.lbar_max - args.lbar_min) / args.step <= 1e6) {
        bail!(
            "--step must be positive and give at most 1e6 samples (got {})",
            args.step
        );
    }
    let t0 = Instant::now();
    let settings = DiagramSettings {
        lbar_min: args.lbar_min,
        lbar_max: args.lbar_max,
        eta_max: (args.lbar_max.floor() as u32).max(1),
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
    let mut critical = Table::new(
        "critical.csv",
        &[
            "index",
            "lbar_cr",
            "kind",
            "from_branch",
            "to_branch",
            "energy",
            "error_estimate",
        ],
    );
    for c in &d.critical {
        critical.push(vec![
            Cell::I(c.index as i64),
            Cell::F(c.lbar_cr),
            Cell::S(c.kind.to_string()),
            Cell::I(c.from_branch.into()),
            Cell::I(c.to_branch.into()),
            Cell::F(c.energy),
            Cell::F(c.error_estimate),
        ])?;
    }
    ensure_dir(&args.out)?;
    branches.write(&args.out)?;
    critical.write(&args.out)?;
    let summary = json!({
        "model": "exact",
        "lbar_min": args.lbar_min,
        "lbar_max": args.lbar_max,
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
        "{} states on {} branches, {} continuation points, computed in {:.3} s; wrote branches.csv, critical.csv, summary.json to {}",
        d.points.len(),
        d.points.iter().map(|p| p.branch).collect::<std::collections::BTreeSet<_>>().len(),
        d.continuation_steps,
        elapsed.as_secs_f64(),
        args.out.display()
    );
    Ok(())
}
