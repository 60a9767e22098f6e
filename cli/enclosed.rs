//! `rodloop solve` and `rodloop compare --scene enclosed` for enclosed scenes (`|r| ≤ R`,
//! paper Sec. 3.2).
//!
//! The numerics are [`rodloop_diagram::enclosed_state`] (one state and its certificate) and
//! [`rodloop_diagram::detached`] (the lift-off scan of `compare`); this file reads the
//! arguments and a saved shape, and prints and writes the results.

use std::path::Path;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use rodloop_diagram::detached::{detachments, BranchDetachment};
use rodloop_diagram::enclosed_state::{self, EnclosedResult, TOUCH};
use rodloop_exact::{branch_of_eta, eta_of_branch};
use rodloop_scene::Scene;
use rodloop_solver::enclosed::{SavedShape, Wall};
use rodloop_solver::{Accuracy, Stiffness};

use crate::output::{checked_json, Cell, OutputRun, Table};

const UNITS: &str = "lengths (s, x, y, z, gap = R - |r|) in units of R; kappa in 1/R; energy E R/(pi D0); lambda R^3/D0 (force per unit length); D/D0; eigenvalues mass-normalised in units of D0/R^3";

/// Solve branch `branch` of an enclosed scene at `lbar`
/// ([`rodloop_diagram::enclosed_state::solve_state`] inside the scene's wall, with its
/// stiffness).
pub fn solve_state(
    scene: &Scene,
    stiffness: &Stiffness,
    lbar: f64,
    branch: u32,
    accuracy: Accuracy,
) -> Result<EnclosedResult> {
    Ok(enclosed_state::solve_state(
        crate::engine::wall_of(scene),
        stiffness,
        lbar,
        branch,
        accuracy,
    )?)
}

/// A saved enclosed `config.csv` (columns `s, x, y, z, kappa_1, kappa_2`, in units of `R`)
/// as a [`SavedShape`] in the model's units; the period is the last `s` plus the chord back to
/// the first point.
fn read_shape(path: &Path, radius: f64) -> Result<SavedShape> {
    if path.is_dir() {
        bail!(
            "--from {} is a directory; give a config.csv saved by `rodloop solve` on an enclosed scene",
            path.display()
        );
    }
    let mut rdr = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .from_path(path)
        .with_context(|| format!("reading {}", path.display()))?;
    let headers = rdr.headers()?.clone();
    let col = |name: &str| -> Result<usize> {
        headers.iter().position(|h| h == name).with_context(|| {
            format!(
                "{}: an enclosed start needs the columns s, x, y, z, kappa_1, kappa_2 of a config.csv saved by `rodloop solve` on an enclosed scene; found {:?}",
                path.display(),
                headers.iter().collect::<Vec<_>>()
            )
        })
    };
    let idx = [
        col("s")?,
        col("x")?,
        col("y")?,
        col("z")?,
        col("kappa_1")?,
        col("kappa_2")?,
    ];
    let mut rows: Vec<[f64; 6]> = Vec::new();
    for (k, rec) in rdr.records().enumerate() {
        let rec = rec.with_context(|| format!("{}: row {}", path.display(), k + 2))?;
        let mut row = [0.0; 6];
        for (c, &i) in idx.iter().enumerate() {
            let cell = rec.get(i).unwrap_or("");
            row[c] = cell
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .with_context(|| {
                    format!(
                        "{}: row {}: {:?} is not a finite number",
                        path.display(),
                        k + 2,
                        cell
                    )
                })?;
        }
        rows.push(row);
    }
    if rows.len() < 8 {
        bail!(
            "{}: needs at least 8 rows, found {}",
            path.display(),
            rows.len()
        );
    }
    let (first, last) = (rows[0], rows[rows.len() - 1]);
    let chord = ((first[1] - last[1]).powi(2)
        + (first[2] - last[2]).powi(2)
        + (first[3] - last[3]).powi(2))
    .sqrt();
    let period = last[0] - first[0] + chord;
    if period.is_nan() || period <= 0.0 {
        bail!("{}: the s column does not describe a loop", path.display());
    }
    let shape = SavedShape {
        sigma: rows.iter().map(|r| (r[0] - first[0]) / period).collect(),
        points: rows
            .iter()
            .map(|r| [r[1] * radius, r[2] * radius, r[3] * radius])
            .collect(),
        kappa: rows
            .iter()
            .map(|r| (r[4] / radius, r[5] / radius))
            .collect(),
    };
    shape
        .validate()
        .with_context(|| format!("--from {}", path.display()))?;
    Ok(shape)
}

/// `rodloop solve` for an enclosed scene.
pub fn run_solve(args: &crate::args::SolveArgs, scene: &Scene) -> Result<()> {
    let t0 = Instant::now();
    crate::output::check_lbar(args.lbar)?;
    let branch = match (args.branch, args.eta) {
        (Some(b), _) if b <= 1000 => Some(b as u32),
        (None, Some(e)) if (1..=1000).contains(&e) => Some(branch_of_eta(e as u32)),
        (None, None) if args.from.is_some() => None,
        _ => bail!("give --branch B (0 to 1000; 0 = the planar circle) or --eta N (1 to 1000)"),
    };
    let accuracy = crate::args::accuracy_of(scene, args.accuracy.as_deref())?;
    let stiffness = crate::args::stiffness_of(&scene.stiffness);
    let shape = match &args.from {
        Some(p) => Some(read_shape(p, scene.radius)?),
        None => None,
    };
    let run = OutputRun::begin(&args.out)?;
    let wall = crate::engine::wall_of(scene);
    let res = match (&shape, branch) {
        (Some(sh), _) => enclosed_state::solve_from_shape(
            &wall,
            &stiffness,
            args.lbar,
            sh,
            branch,
            accuracy,
            args.keep_saddle,
        )?,
        (None, Some(b)) => enclosed_state::solve_state_with(
            &wall,
            &stiffness,
            args.lbar,
            b,
            accuracy,
            args.keep_saddle,
        )?,
        (None, None) => unreachable!("a branch or --from is required above"),
    };
    let st = &res.state;
    let contact = st.contact(TOUCH)?;
    let (opt_lmin, opt_gmin, opt_comp, opt_stat) = st.optimality()?;
    let eta = branch.map(|b| if b == 0 { 0 } else { eta_of_branch(b) });
    // The state as its file holds it: at the solve's resolution (the surface loop where it is
    // attached), verified before anything is written.
    let table = crate::states::result_table(&res, scene.radius, scene.stiffness.reference())?;
    let check = enclosed_state::verify_written(&res, eta.filter(|&e| e > 0))
        .context("the state failed its verification; nothing was written")?;
    // Point group and self-intersections, from the table as `rodloop draw` reads it.
    let loop_data = rodloop_figures::data::LoopData::parse("config.csv", &table.to_bytes()?)?;
    let shape = rodloop_figures::loops::shape(&loop_data, Default::default());
    let mut summary = checked_json!({
        "scene": scene.name,
        "confinement": "enclosed",
        "lbar": args.lbar,
        "branch": branch,
        "eta": eta,
        "identified_eta": check.identified_eta,
        "radius": scene.radius,
        "wall": wall_summary(wall.as_ref()),
        "accuracy": format!("{accuracy:?}").to_lowercase(),
        "energy": res.energy.0,
        "error_estimate": res.energy.1,
        "model_energy": res.model_energy.0,
        "model_error_estimate": res.model_energy.1,
        "surface_energy": res.surface.map(|s| s.0),
        "surface_lambda_min": res.surface.map(|s| s.1),
        "energy_below_surface": res.surface.map(|s| s.0 - res.energy.0),
        "attached": contact.intervals == 1 && contact.fraction >= 1.0,
        "contact_fraction": contact.fraction,
        "contact_intervals": contact.intervals,
        "contact_runs": contact.runs,
        "max_gap": contact.max_gap.0,
        "max_gap_at": contact.max_gap.1 * st.model.length() / scene.radius,
        "lambda_contact_min": contact.lambda_range.0,
        "lambda_contact_max": contact.lambda_range.1,
        "index": res.stability.0,
        "stable_local_minimum": res.stability.0 == 0,
        "eigenvalues": res.stability.1,
        "optimality_lambda_min": opt_lmin,
        "optimality_gap_min": opt_gmin,
        "optimality_complementarity_max": opt_comp,
        "optimality_stationarity": opt_stat,
        "cells": st.model.cells(),
        "iterations": st.iterations,
        "residual": st.residual,
        "method": res.method,
        "verification": serde_json::json!({
            "energy_from_file": check.energy_from_file,
            "energy_tolerance": check.energy_tolerance,
        }),
        "units": UNITS,
    })?;
    if let Some(sh) = &shape {
        crate::draw::add_shape(&mut summary, sh);
    }
    // Fields that do not apply (no surface loop) are absent keys, not null.
    let summary = crate::output::strip_nulls(summary);
    run.write_table(&table)?;
    run.write_json("summary.json", &summary)?;
    run.commit()?;
    let pictures = if args.draw {
        // config.csv has x, y, z (and kappa, lambda): `rodloop draw` reads it as it is.
        let set = crate::draw::DrawSettings::beside(&args.out);
        crate::draw::draw_loop(&args.out.join("config.csv"), &set)?
    } else {
        Vec::new()
    };
    let what = match branch {
        Some(b) => format!("enclosed branch {b}"),
        None => "enclosed loop".to_string(),
    };
    outln!(
        "{what} at lbar = {}: E R/(pi D0) = {:.10} ± {:.1e}, index {} ({}), contact fraction {:.4} in {} interval(s), max gap {:.3e} R",
        args.lbar,
        res.energy.0,
        res.energy.1,
        res.stability.0,
        if res.stability.0 == 0 { "local minimum" } else { "unstable" },
        contact.fraction,
        contact.intervals,
        contact.max_gap.0
    );
    if let Some((es, lm)) = res.surface {
        outln!(
            "surface loop: E = {es:.10}, lambda_min R^3/D0 = {lm:.6}; enclosed - surface = {:.3e}",
            res.energy.0 - es
        );
    }
    outln!(
        "{}; {:.0} ms; wrote config.csv, summary.json{} to {}",
        res.method,
        t0.elapsed().as_secs_f64() * 1e3,
        crate::draw::and_pictures(&pictures),
        args.out.display()
    );
    Ok(())
}

/// The wall as `summary.json` names it: its shape and the semi-axes of its outline in units
/// of `R` ([`Wall::outline`]).
fn wall_summary(wall: &dyn Wall) -> serde_json::Value {
    let (shape, axes) = wall.outline();
    let r = wall.radius();
    serde_json::json!({
        "shape": shape,
        "semi_axes": [axes[0] / r, axes[1] / r, axes[2] / r],
    })
}

/// The built-in homogeneous enclosed scene of `rodloop compare --scene enclosed`: the
/// shipped `data/scenes/homogeneous-enclosed.toml`, else the same scene compiled in.
pub fn builtin_enclosed() -> Result<Scene> {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/scenes/homogeneous-enclosed.toml");
    Ok(Scene::from_file(&p)
        .or_else(|_| Scene::from_toml(DEFAULT_ENCLOSED, "built-in enclosed scene"))?)
}

/// `rodloop compare --scene enclosed`: per branch 1–3 over `1 ≤ L̄ ≤ 3` (homogeneous
/// rods), the detached intervals (exact lift-off/landing lengths), the largest gap and
/// energy drop found on a scan, and whether the stable surface loop is detached there.
/// The dispatcher hands it enclosed scenes only.
pub fn run_compare(scene: &Scene, out: &Path) -> Result<()> {
    if !scene.stiffness.is_uniform() {
        bail!("compare --scene supports homogeneous enclosed scenes (the lift-off lengths come from the exact layer); {} is not homogeneous", scene.name);
    }
    let stiffness = crate::args::stiffness_of(&scene.stiffness);
    let run = OutputRun::begin(out)?;
    let (lo, hi) = (1.0, 3.0);
    let mut table = Table::new(
        "compare.csv",
        &[
            "branch",
            "eta",
            "lift_off",
            "landing",
            "max_gap",
            "max_gap_lbar",
            "max_energy_drop",
            "max_energy_drop_lbar",
            "energy_drop_error",
            "stable_detached_from",
            "stable_detached_to",
        ],
    );
    let mut json_rows = Vec::new();
    for BranchDetachment {
        branch,
        eta,
        stretches,
    } in detachments(scene.radius, &stiffness, lo, hi)?
    {
        if stretches.is_empty() {
            outln!("branch {branch} (eta = {eta}): attached (lambda >= 0) for all of its lengths in [{lo}, {hi}]");
        }
        for st in stretches {
            let (a, b, best_gap, best_drop, stable) = (
                st.lift_off,
                st.landing,
                st.max_gap,
                st.max_energy_drop,
                st.stable,
            );
            outln!(
                "branch {branch} (eta = {eta}): detached for {a:.12} < lbar < {b:.12}; largest gap {:.4e} R at lbar ~ {:.3}; largest energy drop below the surface loop {:.4e} ± {:.1e} at lbar ~ {:.3}; {}",
                best_gap.0,
                best_gap.1,
                best_drop.0,
                best_drop.2,
                best_drop.1,
                match stable {
                    Some((s, t)) => format!("stable on the surface (lowest branch) for {s:.6} < lbar < {t:.6} inside this interval: the Sec. 3.2 hypothesis fails there (the enclosed exchange, located by `rodloop diagram`, lies lower still)"),
                    None => "never the lowest surface branch there".into(),
                }
            );
            table.push(vec![
                Cell::I(i64::from(branch)),
                Cell::I(i64::from(eta)),
                Cell::F(a),
                Cell::F(b),
                Cell::F(best_gap.0),
                Cell::F(best_gap.1),
                Cell::F(best_drop.0),
                Cell::F(best_drop.1),
                Cell::F(best_drop.2),
                stable.map_or(Cell::S(String::new()), |s| Cell::F(s.0)),
                stable.map_or(Cell::S(String::new()), |s| Cell::F(s.1)),
            ])?;
            json_rows.push(serde_json::json!({
                "branch": branch, "eta": eta, "lift_off": a, "landing": b,
                "max_gap": best_gap.0, "max_gap_lbar": best_gap.1,
                "max_energy_drop": best_drop.0, "max_energy_drop_lbar": best_drop.1,
                "energy_drop_error": best_drop.2,
                "stable_detached": stable.map(|s| [s.0, s.1]),
            }));
        }
    }
    let summary = checked_json!({
        "scene": scene.name,
        "lbar_range": [lo, hi],
        "detached": json_rows,
        "units": "lbar = L/(2 pi R); gap R - |r| in units of R; energy E R/(pi D0)",
    })?;
    run.write_table(&table)?;
    run.write_json("summary.json", &summary)?;
    run.commit()?;
    outln!("wrote compare.csv and summary.json to {}", out.display());
    Ok(())
}

const DEFAULT_ENCLOSED: &str = "name = \"homogeneous-enclosed\"\nradius = 1.0\nconfinement = \"enclosed\"\nlbar_min = 1.0\nlbar_max = 3.0\n[stiffness]\nkind = \"uniform\"\nd = 1.0\n";
