//! `rodloop solve`: one numerical equilibrium with forces, energy and Hessian stability.

use std::path::Path;

use anyhow::{bail, Context, Result};
use rodloop_exact::ShapeTolerances;
use rodloop_exact::{branch_of_eta, eta_of_branch};
use rodloop_scene::Scene;
use rodloop_solver::identify::identify_equilibrium;
use rodloop_solver::start::from_points;
use rodloop_solver::{solve_robust_verified, verify_accurate, SolveOptions, StartShape, Strategy};

use crate::output::{checked_json, plural, OutputRun, Table};

pub use crate::args::SolveArgs as Args;
use crate::args::{accuracy_of, stiffness_of};

/// Largest branch number (or eta) accepted.
const MAX_BRANCH: u64 = 1000;

/// Units of every `solve` output.
const UNITS: &str = "lengths (s, x, y, z) in units of R; kappa, tau, kappa_g in 1/R; energy E R/(pi D0); lambda R^3/D0; F_t, F_n, F_b R^2/D0; D/D0; eigenvalues in units of D0";

/// A finite number from a CSV cell, or an error naming the file, row and column.
fn number(cell: Option<&str>, path: &Path, row: usize, name: &str) -> Result<f64> {
    let v: f64 = cell.unwrap_or("").parse().with_context(|| {
        format!(
            "{}: row {}: column {name} is not a number",
            path.display(),
            row + 2
        )
    })?;
    if !v.is_finite() {
        bail!(
            "{}: row {}: column {name} is not finite",
            path.display(),
            row + 2
        );
    }
    Ok(v)
}

/// Read a starting shape from a CSV file (see [`Args::from`]).
fn start_from_file(path: &Path) -> Result<StartShape> {
    if path.is_dir() {
        bail!(
            "--from {} is a directory; give a file: a config.csv saved by `rodloop solve` or a CSV of points with columns x,y,z",
            path.display()
        );
    }
    let mut rdr = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .trim(csv::Trim::All)
        .from_path(path)
        .with_context(|| format!("cannot read --from file {}", path.display()))?;
    let header = rdr.headers()?.clone();
    let col = |name: &str| header.iter().position(|h| h == name);
    let mut rows = Vec::new();
    for (i, rec) in rdr.records().enumerate() {
        rows.push(rec.with_context(|| format!("{}: malformed row {}", path.display(), i + 2))?);
    }
    if let Some(k) = col("kappa_g") {
        let mut kg = Vec::with_capacity(rows.len());
        for (i, r) in rows.iter().enumerate() {
            kg.push(number(r.get(k), path, i, "kappa_g")?);
        }
        if kg.len() < 8 {
            bail!(
                "{}: needs at least 8 rows of kappa_g, found {}",
                path.display(),
                kg.len()
            );
        }
        return StartShape::from_kappa_g_samples(&kg).with_context(|| {
            format!(
                "{}: the kappa_g column is not a usable start",
                path.display()
            )
        });
    }
    let (Some(cx), Some(cy), Some(cz)) = (col("x"), col("y"), col("z")) else {
        bail!(
            "{}: needs a kappa_g column (a saved config.csv) or x, y, z columns (points of a closed curve); found columns {:?}",
            path.display(),
            header.iter().collect::<Vec<_>>()
        );
    };
    let mut pts = Vec::with_capacity(rows.len());
    for (i, r) in rows.iter().enumerate() {
        let mut p = [0.0; 3];
        for (j, c) in [cx, cy, cz].into_iter().enumerate() {
            p[j] = number(r.get(c), path, i, ["x", "y", "z"][j])?;
        }
        pts.push(p);
    }
    if pts.len() < 8 {
        bail!(
            "{}: needs at least 8 points, found {}",
            path.display(),
            pts.len()
        );
    }
    let (shape, _lbar, _rho) = from_points(&pts).with_context(|| {
        format!(
            "{}: the points do not describe a usable closed curve",
            path.display()
        )
    })?;
    Ok(shape)
}

/// The `config.csv` table of an equilibrium's profile, normalised by the scene's `R` and
/// `D0`: lengths in units of `R`, curvatures in `1/R`, `λR³/D0`, `F R²/D0`, `D/D0` (the model
/// works in the scene's dimensional `R` and `D`).
pub fn config_table(profile: &[rodloop_solver::ProfilePoint], scene: &Scene) -> Result<Table> {
    crate::states::config_table_in(profile, scene.radius, scene.stiffness.reference())
}

/// The paper branch and `η` of `--branch` / `--eta`, checked to exist at `--lbar`.
fn branch_at_length(args: &Args) -> Result<(u32, u32)> {
    let (branch, eta) = match (args.branch, args.eta) {
        (Some(b), _) => {
            if b == 0 {
                bail!("--branch must be from 1 to {MAX_BRANCH} on the sphere (got 0; branch 0, the planar circle, is a state of enclosed scenes only)");
            }
            if b > MAX_BRANCH {
                bail!("--branch must be from 1 to {MAX_BRANCH} (got {b})");
            }
            (b as u32, eta_of_branch(b as u32))
        }
        (None, Some(e)) => {
            if e == 0 || e > MAX_BRANCH {
                bail!("--eta must be from 1 to {MAX_BRANCH} (got {e})");
            }
            (branch_of_eta(e as u32), e as u32)
        }
        (None, None) => bail!("give --branch B (or --eta N)"),
    };
    crate::output::check_lbar(args.lbar)?;
    let e = f64::from(eta);
    if !(args.lbar > e - 1.0 && args.lbar < e + 1.0) {
        bail!(
            "branch {branch} (eta = {eta}) exists only for {} < lbar < {}; got lbar = {}",
            e - 1.0,
            e + 1.0,
            args.lbar
        );
    }
    Ok((branch, eta))
}

/// `rodloop solve` on a surface scene.
pub(crate) fn run_surface(args: &Args, scene: Scene) -> Result<()> {
    let (branch, eta) = branch_at_length(args)?;
    let accuracy = accuracy_of(&scene, args.accuracy.as_deref())?;
    let stiffness = stiffness_of(&scene.stiffness);
    // Lock the output directory before the work, so that a concurrent run is refused at once.
    let run = OutputRun::begin(&args.out)?;
    let start = match &args.from {
        Some(p) => start_from_file(p)?,
        None => StartShape::Euler { l: eta },
    };
    let (res, strategy, verified) = solve_robust_verified(
        scene.radius,
        args.lbar,
        &stiffness,
        &start,
        accuracy,
        Some(eta),
        &SolveOptions::default(),
    )
    .map_err(|e| {
        let advice = if matches!(e, rodloop_solver::SolverError::NewtonNotConverged { .. }) {
            " (tried: Newton with relaxation from the start; next: --from a state solved at a \
             nearby length, another --accuracy, or for a two-segment rod a milder D1/D0 first)"
        } else if matches!(e, rodloop_solver::SolverError::Unverified(_)) {
            " (nothing was written; start from a state of this branch solved at a nearby \
             length with --from, or from the Euler curve without --from)"
        } else {
            ""
        };
        anyhow::Error::new(e).context(format!(
            "solving branch {branch} at lbar = {}{advice}",
            args.lbar
        ))
    })?;
    // A saddle is not what the loop settles into: descend to the local minimum of its branch.
    let (res, descent) = if args.keep_saddle {
        (res, None)
    } else {
        rodloop_solver::descend::descend_accurate(
            res,
            scene.radius,
            &stiffness,
            &start,
            &SolveOptions::default(),
        )
        .context("descending from the saddle Newton converged to")?
    };
    let eq = &res.equilibrium;
    let report = eq.report();
    if !report.converged {
        bail!(
            "the equilibrium solve did not converge (KKT residual {:.3e}, closure {:.3e} after {} iterations); nothing was written",
            report.residual,
            report.closure,
            report.iterations
        );
    }
    // The start (a --from file above all) carries no branch label: identify the branch of the
    // converged state from its own geodesic curvature and refuse a state of another branch,
    // however it was reached (see rodloop_solver::verify).
    let periods = identify_equilibrium(eq).context(
        "cannot tell which branch the converged state is on; nothing was written (start from a \
         state of the requested branch solved at a nearby length with --from, or from the Euler \
         curve without --from)",
    )?;
    if periods.eta != eta {
        bail!(
            "the converged state has {} of kappa_g, so it is branch {} (eta = {}), not the requested branch {branch} (eta = {eta}); nothing was written. {}",
            plural(periods.eta, "period"),
            branch_of_eta(periods.eta),
            periods.eta,
            if args.from.is_some() {
                "The --from start lies on another branch: start from a state of the requested branch, or drop --from to start from the Euler curve"
            } else {
                "Try another accuracy or start --from a nearby state of the requested branch"
            }
        );
    }
    let profile = eq.profile();
    // Closed, on the sphere, energy reproduced by the written profile (the same profile as
    // `eq.profile()`), branch from the state: the solve verified the state it returned; a
    // state the descent moved to is verified here.
    let moved = descent.as_ref().is_some_and(|d| d.moved());
    let verification = if moved {
        match verify_accurate(&res, Some(eta)) {
            Ok(v) => v,
            Err(e) => bail!(
                "branch {branch} at lbar = {}: {e}; nothing was written",
                args.lbar
            ),
        }
    } else {
        verified
    };
    let stab = eq.stability()?;
    let table = config_table(&profile, &scene)?;
    let r = scene.radius;
    let d0 = scene.stiffness.reference();
    let lam_unit = r * r * r / d0;
    let (lambda_min, lambda_max) = (res.lambda_range.0 * lam_unit, res.lambda_range.1 * lam_unit);
    let lambda_error = res.lambda_error * lam_unit;
    let shape = eq.model().shape(eq.kappa(), ShapeTolerances::default())?;
    let mut summary = checked_json!({
        "scene": scene.name,
        "lbar": args.lbar,
        "branch": branch,
        "eta": eta,
        "identified_eta": periods.eta,
        "radius": scene.radius,
        "accuracy": format!("{accuracy:?}").to_lowercase(),
        "energy": res.energy.total,
        "energy_g": res.energy.geodesic,
        "energy_n": res.energy.normal,
        "error_estimate": res.energy_error,
        "index": stab.index,
        "stable_local_minimum": stab.index == 0,
        "eigenvalues": stab.eigenvalues,
        "symmetry_eigenvalues": stab.symmetry_eigenvalues,
        "lambda_min": lambda_min,
        "lambda_max": lambda_max,
        "lambda_error_estimate": lambda_error,
        "residual": report.residual,
        "closure": report.closure,
        "nodes": profile.len(),
        "iterations": report.iterations,
        "relax_iterations": report.relax_iterations,
        "strategy": strategy.describe(),
        "descent": descent.as_ref().map(|d| serde_json::json!({
            "from_index": d.start().index,
            "from_energy": d.start().energy,
            "to_index": d.end().index,
            "to_energy": d.end().energy,
            "path": d.path,
            "description": d.describe(),
        })),
        "keep_saddle": args.keep_saddle,
        "verification": verification,
        "units": UNITS,
    })?;
    crate::draw::add_shape(&mut summary, &shape);
    // No descent is an absent key, not null (null is how serde_json writes NaN).
    let summary = crate::output::strip_nulls(summary);
    run.write_table(&table)?;
    run.write_json("summary.json", &summary)?;
    run.commit()?;
    let pictures = if args.draw {
        let mut set = crate::draw::DrawSettings::beside(&args.out);
        set.overlay = crate::draw::euler_overlay(eta, args.lbar);
        crate::draw::draw_loop(&args.out.join("config.csv"), &set)?
    } else {
        Vec::new()
    };
    outln!(
        "branch {branch} (eta = {eta}) at lbar = {}: E R/(pi D0) = {:.10} ± {:.1e}, index {} ({}), lambda R^3/D0 in [{:.6}, {:.6}] ± {:.1e}",
        args.lbar,
        res.energy.total,
        res.energy_error,
        stab.index,
        if stab.index == 0 { "local minimum" } else { "unstable" },
        lambda_min,
        lambda_max,
        lambda_error
    );
    if strategy != Strategy::Direct {
        outln!("reached by {}", strategy.describe());
    }
    if let Some(d) = descent.as_ref().filter(|d| d.start().index > 0) {
        outln!("{}", d.describe());
    }
    outln!(
        "{} nodes, {} Newton iterations, KKT residual {:.1e}; wrote config.csv, summary.json{} to {}",
        profile.len(),
        report.iterations,
        report.residual,
        crate::draw::and_pictures(&pictures),
        args.out.display()
    );
    Ok(())
}
