//! `rodloop converge` on an enclosed scene (`|r| ≤ R`, paper Sec. 3.2): the state `rodloop
//! solve` reports, carried up a ladder of meshes, to measure what the wall's nodewise
//! contact does to the convergence. Each rung is solved from the one below with its contact
//! runs kept inside the coarser ones (`EnclosedState::refine_in_runs`, the start of the
//! enclosed diagrams' exchange ladders); the first from the solved state resampled. Per
//! rung: the energy, the error estimate the exchanges use (`finest_energy`: the four-level
//! rule of a lifted-off loop, its order capped for its contact), the distance to the finest
//! rung, the observed order, the contact and the time.

use std::time::Instant;

use anyhow::{bail, Context, Result};
use rodloop_diagram::enclosed_state::TOUCH;
use rodloop_scene::Scene;
use rodloop_solver::enclosed::{
    branch::resample_state, finest_energy, solve_prolonged, EnclosedOptions, EnclosedState,
};
use rodloop_solver::{Accuracy, Claim};
use serde_json::json;

use crate::args::stiffness_of;
use crate::converge::{checked_eta, ladder_base, Args};
use crate::output::{Cell, OutputRun, Table};

/// Cells of the finest rung at most (a rung of 8192 cells takes about half a minute).
const MAX_CELLS: usize = 8192;

/// One rung: the state, its contact and the wall time of its solve (for the first rung at
/// the solve's own mesh, that of the whole `solve`).
struct Rung {
    state: EnclosedState,
    fraction: f64,
    runs: usize,
    seconds: f64,
}

/// Run the subcommand on an enclosed scene.
pub fn run(args: &Args, scene: &Scene) -> Result<()> {
    let eta = checked_eta(args)?;
    let stiffness = stiffness_of(&scene.stiffness);
    let t0 = Instant::now();
    let solved =
        crate::enclosed::solve_state(scene, &stiffness, args.lbar, args.branch, Accuracy::Default)?;
    let solve_seconds = t0.elapsed().as_secs_f64();
    // The ladder starts at the solve's own mesh unless --min-cells asks for another (the
    // solved state resampled), and stops at MAX_CELLS.
    let own = solved.state.model.cells();
    let base = match args.min_cells {
        Some(_) => ladder_base(args, own)?,
        None => own,
    };
    let levels = (0..args.levels)
        .take_while(|&k| base << k <= MAX_CELLS)
        .count();
    if levels < 3 {
        bail!(
            "the ladder from {base} cells has {levels} rung(s) up to {MAX_CELLS} cells; at least three are needed: lower --min-cells"
        );
    }
    let mut rungs: Vec<Rung> = Vec::new();
    // Why the ladder stopped before its last rung (a rung whose Newton run failed), if it did.
    let mut stopped: Option<String> = None;
    for k in 0..levels {
        let cells = base << k;
        let t = Instant::now();
        let state = match rungs.last() {
            None if cells == own => solved.state.clone(),
            None => {
                let (model, z) = resample_state(&solved.state, cells)
                    .with_context(|| format!("starting the rung of {cells} cells"))?;
                solve_prolonged(&model, z, &EnclosedOptions::default())
                    .with_context(|| format!("solving the rung of {cells} cells"))?
            }
            Some(r) => {
                let solved = r
                    .state
                    .refine_in_runs()
                    .and_then(|(model, z)| solve_prolonged(&model, z, &EnclosedOptions::default()));
                match solved {
                    Ok(st) => st,
                    Err(e) if rungs.len() >= 3 => {
                        stopped = Some(format!("the rung of {cells} cells did not solve: {e}"));
                        break;
                    }
                    Err(e) => bail!("solving the rung of {cells} cells: {e}"),
                }
            }
        };
        let seconds = if k == 0 && cells == own {
            solve_seconds
        } else {
            t.elapsed().as_secs_f64()
        };
        let c = state.contact(TOUCH)?;
        rungs.push(Rung {
            fraction: c.fraction,
            runs: c.intervals,
            state,
            seconds,
        });
    }
    let energies: Vec<f64> = rungs.iter().map(|r| r.state.energy()).collect();
    let n = rungs.len();
    let finest = energies[n - 1];
    // The estimate of each rung from the rungs up to it (three at least).
    let estimates: Vec<Option<f64>> = (0..n)
        .map(|k| {
            (k >= 2)
                .then(|| {
                    let levels: Vec<&EnclosedState> =
                        rungs[..=k].iter().map(|r| &r.state).collect();
                    finest_energy(&levels).ok().map(|(_, e)| e)
                })
                .flatten()
        })
        .collect();
    // The distance to the finest rung and the observed order, as the surface ladder gives them.
    let errors = rodloop_solver::accuracy::rung_errors(&energies, None);
    // The finest rung as its file holds it, verified against its energy and estimate.
    let claim = Claim {
        energy: finest,
        energy_error: rodloop_diagram::ESTIMATES * estimates[n - 1].unwrap_or(0.0),
        profile_error: 0.0,
        eta: Some(eta),
    };
    let fine = &rungs[n - 1].state;
    let verified = rodloop_solver::verify_enclosed(fine, &claim);
    let state_name = "states/finest.csv";
    let state_file = match &verified {
        Ok(_) => state_name.to_string(),
        Err(e) => {
            eprintln!(
                "warning: UNVERIFIED STATE LEFT WITHOUT A FILE: the finest rung ({} cells): {e}",
                fine.model.cells()
            );
            String::new()
        }
    };
    let mut table = Table::new(
        "converge.csv",
        &[
            "cells",
            "energy",
            "error_estimate",
            "error_vs_finest",
            "observed_order",
            "contact_fraction",
            "contact_runs",
            "iterations",
            "seconds",
            "state_file",
        ],
    );
    outln!(
        "branch {} (eta = {eta}) at lbar = {} inside the ball, scene {}: the state solve reports (E R/(pi D0) = {:.10} +- {:.1e} on {} cells, {:.1} s) on {} meshes",
        args.branch,
        args.lbar,
        scene.name,
        solved.model_energy.0,
        solved.model_energy.1,
        solved.state.model.cells(),
        solve_seconds,
        n
    );
    outln!(
        "{:>7} {:>19} {:>10} {:>10} {:>6} {:>8} {:>5} {:>5} {:>9}",
        "cells",
        "energy",
        "estimate",
        "vs finest",
        "order",
        "contact",
        "runs",
        "iter",
        "seconds"
    );
    let opt = |v: Option<f64>| v.map(Cell::F).unwrap_or(Cell::S(String::new()));
    let show = |v: Option<f64>, w: usize| match v {
        Some(x) => format!("{x:>w$.1e}"),
        None => format!("{:>w$}", "-"),
    };
    let mut rows = Vec::new();
    for (k, r) in rungs.iter().enumerate() {
        let (vs_finest, order) = (errors[k].vs_finest, errors[k].order);
        table.push(vec![
            Cell::I(r.state.model.cells() as i64),
            Cell::F(energies[k]),
            opt(estimates[k]),
            opt(vs_finest),
            opt(order),
            Cell::F(r.fraction),
            Cell::I(r.runs as i64),
            Cell::I(r.state.iterations as i64),
            Cell::F(r.seconds),
            Cell::S(if k + 1 == n {
                state_file.clone()
            } else {
                String::new()
            }),
        ])?;
        outln!(
            "{:>7} {:>19.15} {} {} {:>6} {:>8.4} {:>5} {:>5} {:>9.3}",
            r.state.model.cells(),
            energies[k],
            show(estimates[k], 10),
            show(vs_finest, 10),
            order
                .map(|o| format!("{o:.2}"))
                .unwrap_or_else(|| "-".into()),
            r.fraction,
            r.runs,
            r.state.iterations,
            r.seconds
        );
        rows.push(json!({
            "cells": r.state.model.cells(), "energy": energies[k],
            "error_estimate": estimates[k], "error_vs_finest": vs_finest,
            "observed_order": order, "contact_fraction": r.fraction,
            "contact_runs": r.runs, "iterations": r.state.iterations, "seconds": r.seconds,
        }));
    }
    if let Some(why) = &stopped {
        eprintln!(
            "warning: the ladder stops at {} cells: {why}",
            rungs[n - 1].state.model.cells()
        );
    }
    let summary = json!({
        "scene": scene.name,
        "confinement": "enclosed",
        "stopped": stopped,
        "lbar": args.lbar,
        "branch": args.branch,
        "eta": eta,
        "solve": {
            "energy": solved.model_energy.0,
            "error_estimate": solved.model_energy.1,
            "cells": solved.state.model.cells(),
            "seconds": solve_seconds,
        },
        "rungs": rows,
        "state_file": (!state_file.is_empty()).then_some(&state_file),
        "unverified_states": usize::from(state_file.is_empty()),
        "units": "energy E R/(pi D0) of the 3-D model; seconds of wall time per rung",
    });
    let summary = crate::output::strip_nulls(summary);
    crate::output::check_finite("summary.json", &summary)?;
    let run = OutputRun::begin(&args.out)?;
    if verified.is_ok() {
        let dir = run.subdir("states")?;
        let t = crate::states::model_table(fine, scene.radius, stiffness.reference())?;
        crate::output::write_atomic(&dir, "finest.csv", &t.to_bytes()?)?;
    }
    run.write_table(&table)?;
    run.write_json("summary.json", &summary)?;
    run.commit()?;
    outln!(
        "wrote converge.csv and summary.json to {}",
        args.out.display()
    );
    Ok(())
}
