//! `rodloop solve` and `rodloop compare --scene enclosed` for enclosed scenes (`|r| ≤ R`,
//! paper Sec. 3.2).
//!
//! A branch's enclosed state starts from its surface loop. Where that loop has `λ ≥ 0`
//! everywhere it satisfies every enclosed KKT condition (the wall may push, the loop
//! touches, stationarity is the surface equations), so it is the enclosed equilibrium: the
//! energy reported is the surface one (exact layer for uniform rods) and the 3-D enclosed
//! model re-solves it as a check. Where `λ < 0` somewhere, the 3-D model's semismooth
//! Newton finds the lift-off.

use std::path::Path;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use rodloop_exact::{branch_of_eta, eta_of_branch, paper_branch_loop};
use rodloop_scene::Scene;
use rodloop_solver::enclosed::descent::{descend_branch, solve_branch_lowest};
use rodloop_solver::enclosed::{
    detached_intervals, enclosed_cells, enclosed_solve_cells, free_circle, solve_branch,
    solve_enclosed, solve_levels, start_from_shape, EnclosedOptions, EnclosedState, SavedShape,
    SurfaceSource,
};
use rodloop_solver::{solve_robust, Accuracy, SolveOptions, StartShape, Stiffness};

use crate::output::{checked_json, Cell, OutputRun, Table};

const UNITS: &str = "lengths (s, x, y, z, gap = R - |r|) in units of R; kappa in 1/R; energy E R/(pi D0); lambda R^3/D0 (force per unit length); D/D0; eigenvalues mass-normalised in units of D0/R^3";

/// Tolerance on the gap (units of `R`) for "touching".
const TOUCH: f64 = 1e-9;

/// One enclosed state with everything `solve` reports.
pub struct EnclosedResult {
    /// The 3-D state reported (config.csv).
    pub state: EnclosedState,
    /// Energy `E R/(π D0)` and its error estimate.
    pub energy: (f64, f64),
    /// Surface loop energy and `λ_min` (None for branch 0).
    pub surface: Option<(f64, f64)>,
    /// Stability index and lowest eigenvalues (on the coarsest level of the cascade, `N/8`
    /// or `N/4`; dense, `O(N³)`).
    pub stability: (usize, Vec<f64>),
    /// How the energy was obtained.
    pub method: String,
    /// The 3-D model's own energy (and estimate).
    pub model_energy: (f64, f64),
}

/// Solve branch `branch` of an enclosed scene at `lbar`, descending from a saddle to the
/// local minimum of the branch below it ([`solve_state_with`]).
pub fn solve_state(
    scene: &Scene,
    stiffness: &Stiffness,
    lbar: f64,
    branch: u32,
    accuracy: Accuracy,
) -> Result<EnclosedResult> {
    solve_state_with(scene, stiffness, lbar, branch, accuracy, false)
}

/// [`solve_state`]; `keep_saddle`: return the state Newton converges to even where it is a
/// saddle.
pub fn solve_state_with(
    scene: &Scene,
    stiffness: &Stiffness,
    lbar: f64,
    branch: u32,
    accuracy: Accuracy,
    keep_saddle: bool,
) -> Result<EnclosedResult> {
    let r = scene.radius;
    let opts = EnclosedOptions::default();
    if branch == 0 {
        if lbar > 1.0 {
            bail!("branch 0 (the planar circle) fits in the ball only for lbar <= 1; got lbar = {lbar}");
        }
        // The uniform circle is exact at any resolution: the 3-D check runs at the fast one.
        let cells = enclosed_cells(
            if stiffness.is_uniform() {
                Accuracy::Fast
            } else {
                accuracy
            },
            1,
        );
        let (model, z0) = free_circle(r, lbar, cells, stiffness)?;
        let state = solve_enclosed(&model, z0, &opts).context("the free circle")?;
        let (cm, cz) = free_circle(r, lbar, cells / 2, stiffness)?;
        let comp = solve_enclosed(&cm, cz, &opts)?;
        let e = state.energy();
        let est = rodloop_solver::richardson_error(e, comp.energy());
        let stability = comp.stability(1e-6)?;
        let exact = if stiffness.is_uniform() {
            Some(1.0 / lbar)
        } else {
            None
        };
        return Ok(EnclosedResult {
            energy: (exact.unwrap_or(e), if exact.is_some() { 0.0 } else { est }),
            surface: None,
            stability,
            method: if exact.is_some() {
                "planar circle: E R/(pi D) = 1/lbar exactly; 3-D model solved as a check".into()
            } else {
                "planar circle, 3-D model".into()
            },
            model_energy: (e, est),
            state,
        });
    }
    let eta = eta_of_branch(branch);
    let e = f64::from(eta);
    if !(lbar > e - 1.0 && lbar < e + 1.0) {
        bail!(
            "branch {branch} (eta = {eta}) exists only for {} < lbar < {}; got lbar = {lbar}",
            e - 1.0,
            e + 1.0
        );
    }
    let d0 = scene.stiffness.reference();
    let (source, surface_error) = if stiffness.is_uniform() {
        let l = paper_branch_loop(eta, lbar)
            .with_context(|| format!("the exact surface loop of branch {branch}"))?;
        (SurfaceSource::Exact(l), 0.0)
    } else {
        let (res, _) = solve_robust(
            r,
            lbar,
            stiffness,
            &StartShape::Euler { l: eta },
            accuracy,
            Some(eta),
            &SolveOptions::default(),
        )
        .with_context(|| format!("the surface loop of branch {branch}"))?;
        let err = res.energy_error;
        (SurfaceSource::Numeric(Box::new(res.equilibrium)), err)
    };
    let e_surf = source.energy()?;
    let lam_min = source.lambda_min(r, d0);
    let attached = lam_min >= 0.0;
    // An attached loop's energy is the surface one; the 3-D re-solve is a check, at the
    // fast resolution.
    let acc = if attached { Accuracy::Fast } else { accuracy };
    // Uniform rods: the fine mesh of the O(N) step. Two-segment rods keep the diagram's mesh
    // (observed order 1.0–1.4 there; the cascade started at N/4 = 96 cells from the surface
    // loop of branch 3 at lbar = 2.2 does not converge).
    let mut cells = if stiffness.is_uniform() {
        enclosed_solve_cells(acc, eta)
    } else {
        enclosed_cells(acc, eta)
    };
    if !stiffness.is_uniform() {
        // Sharp profiles (Eq. (51), gamma = 200) need the coarsest level of the cascade
        // (N/4) to resolve the transitions on the graded mesh.
        cells = cells.max(32 * (2 + eta as usize));
    }
    // Set where the state reported is a lower local minimum than the one reached from the
    // surface loop (continuation in the stiffness from the uniform rod's loop).
    let mut lower_minimum = false;
    let (b, descent, given_up) = if keep_saddle {
        let b = solve_branch(r, lbar, stiffness, &source, cells, &opts)
            .with_context(|| format!("the enclosed loop of branch {branch} at lbar = {lbar}"))?;
        (b, None, Vec::new())
    } else {
        // Two-segment rods: where the mesh of this accuracy does not end at a local minimum,
        // the meshes of the finer levels (and twice the finest) are tried.
        let mut ladder = vec![cells];
        if !stiffness.is_uniform() {
            for a in [Accuracy::Default, Accuracy::High] {
                ladder.push(enclosed_cells(a, eta).max(32 * (2 + eta as usize)));
            }
            ladder.push(2 * ladder[ladder.len() - 1]);
            ladder.retain(|&n| n >= cells);
            ladder.dedup();
        }
        let (out, replaced) = solve_branch_lowest(r, lbar, eta, stiffness, &source, &ladder, &opts)
            .with_context(|| format!("the enclosed loop of branch {branch} at lbar = {lbar}"))?;
        lower_minimum = replaced;
        out
    };
    let cells = b.fine.model.cells();
    let stability = b.coarsest().stability(1e-6)?;
    let moved = lower_minimum || descent.as_ref().is_some_and(|d| d.moved());
    let (energy, mut method) = if attached && !moved {
        (
            (e_surf, surface_error),
            format!(
                "surface loop (lambda_min = {lam_min:.6} >= 0: it satisfies the enclosed KKT conditions); 3-D model re-solved at N = {cells} as a check"
            ),
        )
    } else {
        (
            (b.energy, b.energy_error),
            format!(
                "3-D enclosed model, N = {cells} cells (semismooth Newton from {}, lambda_min = {lam_min:.6}); {}",
                if lower_minimum {
                    "the uniform rod's loop continued in the stiffness"
                } else if b.homotopy {
                    "the surface loop by the pull homotopy"
                } else {
                    "the surface loop"
                },
                b.estimate_method()
            ),
        )
    };
    for why in &given_up {
        method.push_str(&format!("; {why}"));
    }
    if let Some(d) = descent.filter(|d| d.start().index > 0) {
        method.push_str(&format!(
            "; {} (descent at N/4 = {} cells, energies at N)",
            d.describe(),
            b.quarter.model.cells()
        ));
    }
    Ok(EnclosedResult {
        model_energy: (b.energy, b.energy_error),
        state: b.fine,
        energy,
        surface: Some((e_surf, lam_min)),
        stability,
        method,
    })
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

/// Solve from a saved enclosed shape at `lbar`: the shape's curvature vectors, aligned by
/// [`start_from_shape`], start the cascade at `N/4` (`N = 32(1 + η)` with the branch's `η`
/// when given, else `η = 2`).
fn solve_from_shape(
    scene: &Scene,
    stiffness: &Stiffness,
    lbar: f64,
    shape: &SavedShape,
    branch: Option<u32>,
    accuracy: Accuracy,
    keep_saddle: bool,
) -> Result<EnclosedResult> {
    let eta = branch.filter(|&b| b > 0).map_or(2, eta_of_branch);
    let mut cells = if stiffness.is_uniform() {
        enclosed_solve_cells(accuracy, eta)
    } else {
        enclosed_cells(accuracy, eta)
    };
    if !stiffness.is_uniform() {
        cells = cells.max(32 * (2 + eta as usize));
    }
    let (model, z0) = start_from_shape(scene.radius, lbar, cells / 4, stiffness, shape)?;
    let opts = EnclosedOptions::default();
    let b =
        solve_levels(&model, z0, None, &opts).context("the enclosed loop from the saved shape")?;
    let (b, descent) = if keep_saddle {
        (b, None)
    } else {
        descend_branch(b, &opts).context("descending from the saddle Newton converged to")?
    };
    let stability = b.coarsest().stability(1e-6)?;
    let mut method = format!(
        "3-D enclosed model, N = {cells} cells (semismooth Newton from the saved shape); {}",
        b.estimate_method()
    );
    if let Some(d) = descent.filter(|d| d.start().index > 0) {
        method.push_str(&format!(
            "; {} (descent at N/4 = {} cells, energies at N)",
            d.describe(),
            b.quarter.model.cells()
        ));
    }
    Ok(EnclosedResult {
        model_energy: (b.energy, b.energy_error),
        energy: (b.energy, b.energy_error),
        surface: None,
        stability,
        method,
        state: b.fine,
    })
}

/// `config.csv` of an enclosed state: one row per node.
pub(crate) fn config_table(st: &EnclosedState, scene: &Scene) -> Result<Table> {
    config_table_in(st, scene.radius, scene.stiffness.reference())
}

/// [`config_table`] for a ball of radius `r` and reference stiffness `d0`.
pub(crate) fn config_table_in(st: &EnclosedState, r: f64, d0: f64) -> Result<Table> {
    let m = &st.model;
    let lam = m.contact_force(&st.z);
    let mut table = Table::new(
        "config.csv",
        &[
            "s", "x", "y", "z", "gap", "kappa", "kappa_1", "kappa_2", "lambda", "D",
        ],
    );
    for (j, (sigma, p)) in st.nodes()?.into_iter().enumerate() {
        let (k1, k2) = st.node_curvature(j);
        let d = m.stiffness().eval(sigma).d;
        table.push(vec![
            Cell::F(sigma * m.length() / r),
            Cell::F(p[0] / r),
            Cell::F(p[1] / r),
            Cell::F(p[2] / r),
            Cell::F((r - p.norm()) / r),
            Cell::F((k1 * k1 + k2 * k2).sqrt() * r),
            Cell::F(k1 * r),
            Cell::F(k2 * r),
            Cell::F(lam[j] * r * r * r / d0),
            Cell::F(d / d0),
        ])?;
    }
    Ok(table)
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
    let res = match (&shape, branch) {
        (Some(sh), _) => solve_from_shape(
            scene,
            &stiffness,
            args.lbar,
            sh,
            branch,
            accuracy,
            args.keep_saddle,
        )?,
        (None, Some(b)) => {
            solve_state_with(scene, &stiffness, args.lbar, b, accuracy, args.keep_saddle)?
        }
        (None, None) => unreachable!("a branch or --from is required above"),
    };
    let st = &res.state;
    let contact = st.contact(TOUCH)?;
    let (opt_lmin, opt_gmin, opt_comp, opt_stat) = st.optimality()?;
    let table = config_table(st, scene)?;
    let eta = branch.map(|b| if b == 0 { 0 } else { eta_of_branch(b) });
    // Point group and self-intersections, from the table as `rodloop draw` reads it.
    let loop_data = rodloop_figures::data::LoopData::parse("config.csv", &table.to_bytes()?)?;
    let shape = rodloop_figures::loops::shape(&loop_data, Default::default());
    let mut summary = checked_json!({
        "scene": scene.name,
        "confinement": "enclosed",
        "lbar": args.lbar,
        "branch": branch,
        "eta": eta,
        "radius": scene.radius,
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

/// `rodloop compare --scene enclosed`: per branch 1–3 over `1 ≤ L̄ ≤ 3` (homogeneous
/// rods), the detached intervals (exact lift-off/landing lengths), the largest gap and
/// energy drop found on a scan, and whether the stable surface loop is detached there.
pub fn run_compare(scene_arg: &str, out: &Path) -> Result<()> {
    let scene = if scene_arg == "enclosed" {
        let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/scenes/homogeneous-enclosed.toml");
        Scene::from_file(&p)
            .or_else(|_| Scene::from_toml(DEFAULT_ENCLOSED, "built-in enclosed scene"))?
    } else {
        Scene::from_file(Path::new(scene_arg))?
    };
    if crate::engine::kind_of(&scene) != crate::engine::EngineKind::Enclosed {
        bail!(
            "compare --scene needs an enclosed scene (confinement = \"enclosed\"); {} is not",
            scene.name
        );
    }
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
    for branch in 1..=3u32 {
        let eta = eta_of_branch(branch);
        let intervals = detached_intervals(eta, lo, hi)?;
        if intervals.is_empty() {
            outln!("branch {branch} (eta = {eta}): attached (lambda >= 0) for all of its lengths in [{lo}, {hi}]");
        }
        for (a, b) in intervals {
            let mut best_gap = (0.0f64, a);
            let mut best_drop = (0.0f64, a, 0.0);
            let n = 12;
            for k in 0..=n {
                let l = a + (b - a) * (0.02 + 0.96 * k as f64 / n as f64);
                let res = solve_state(&scene, &stiffness, l, branch, Accuracy::Fast)?;
                let c = res.state.contact(TOUCH)?;
                if c.max_gap.0 > best_gap.0 {
                    best_gap = (c.max_gap.0, l);
                }
                let drop = res.surface.map(|s| s.0).unwrap_or(0.0) - res.energy.0;
                if drop > best_drop.0 {
                    best_drop = (drop, l, res.energy.1);
                }
            }
            // Where is this branch the lowest surface branch (stable)?
            let stable = stable_stretch(eta, a, b)?;
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

/// The sub-interval of `(a, b)` where branch `eta` is the lowest of the paper's homogeneous
/// surface branches (exact energies; bisection on energy crossings to 1e-12).
fn stable_stretch(eta: u32, a: f64, b: f64) -> Result<Option<(f64, f64)>> {
    let lowest = |l: f64| -> Result<bool> {
        let mine = paper_branch_loop(eta, l)?.energy()?;
        for other in 1..=5u32 {
            if other == eta {
                continue;
            }
            let o = f64::from(other);
            if l > o - 1.0 && l < o + 1.0 && paper_branch_loop(other, l)?.energy()? < mine {
                return Ok(false);
            }
        }
        Ok(true)
    };
    let n = 200;
    let grid: Vec<f64> = (0..=n)
        .map(|i| a + (b - a) * (i as f64 + 0.5) / (n as f64 + 1.0))
        .collect();
    let flags: Vec<bool> = grid.iter().map(|&l| lowest(l)).collect::<Result<_>>()?;
    let first = flags.iter().position(|&f| f);
    let last = flags.iter().rposition(|&f| f);
    let (Some(i), Some(j)) = (first, last) else {
        return Ok(None);
    };
    let refine = |x0: f64, x1: f64, want_true_at_x1: bool| -> Result<f64> {
        let (mut p, mut q) = (x0, x1);
        while q - p > 1e-12 {
            let m = 0.5 * (p + q);
            if lowest(m)? == want_true_at_x1 {
                q = m;
            } else {
                p = m;
            }
        }
        Ok(0.5 * (p + q))
    };
    let s = if i == 0 {
        a
    } else {
        refine(grid[i - 1], grid[i], true)?
    };
    let t = if j == n {
        b
    } else {
        refine(grid[j], grid[j + 1], false)?
    };
    Ok(Some((s, t)))
}

const DEFAULT_ENCLOSED: &str = "name = \"homogeneous-enclosed\"\nradius = 1.0\nconfinement = \"enclosed\"\nlbar_min = 1.0\nlbar_max = 3.0\n[stiffness]\nkind = \"uniform\"\nd = 1.0\n";
