//! `rodloop solve`: one numerical equilibrium with forces, energy and Hessian stability.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use rodloop_exact::{branch_of_eta, eta_of_branch};
use rodloop_scene::{Confinement, Scene, StiffnessSpec};
use rodloop_solver::start::from_points;
use rodloop_solver::{solve_with_accuracy, Accuracy, SolveOptions, StartShape, Stiffness};
use serde_json::json;

use crate::output::{ensure_dir, write_json, Cell, Table};

/// Arguments of `rodloop solve`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Normalised length L/(2 pi R).
    #[arg(long)]
    pub lbar: f64,
    /// Paper branch number (1: saddle, eta = 2; 2: figure-eight, eta = 1; B >= 3: eta = B).
    #[arg(long)]
    pub branch: u32,
    /// Scene file (TOML; see data/scenes/). Default: homogeneous loop on the unit sphere.
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Starting shape: a saved config.csv (its kappa_g column) or any CSV with columns x,y,z
    /// (points of a closed curve, in order). Default: the Euler rotation curve l = eta.
    #[arg(long)]
    pub from: Option<PathBuf>,
    /// Accuracy: fast, default or high (overrides the scene's).
    #[arg(long)]
    pub accuracy: Option<String>,
    /// Also draw the loop (four views, SVG and PNG) next to the CSV (see `rodloop draw`).
    #[arg(long)]
    pub draw: bool,
    /// Output directory.
    #[arg(long, default_value = "out/solve")]
    pub out: PathBuf,
}

/// The solver's stiffness for a scene's profile.
pub fn stiffness_of(spec: &StiffnessSpec) -> Stiffness {
    match spec {
        StiffnessSpec::Uniform { d } => Stiffness::Uniform { d: *d },
        StiffnessSpec::Tanh {
            d0,
            d1,
            s0,
            s1,
            gamma,
        } => Stiffness::Tanh {
            d0: *d0,
            d1: *d1,
            s0: *s0,
            s1: *s1,
            gamma: *gamma,
        },
        StiffnessSpec::Table { s, d } => Stiffness::Table {
            s: s.clone(),
            d: d.clone(),
        },
    }
}

/// Load the scene (or the default) and check that the model covers it.
pub fn load_scene(path: Option<&Path>) -> Result<Scene> {
    let scene = match path {
        Some(p) => Scene::from_file(p)?,
        None => Scene::default(),
    };
    if scene.confinement == Confinement::Enclosed {
        bail!(
            "scene {}: confinement = \"enclosed\" is not modelled yet (the paper finds that stable homogeneous loops stay on the surface for 1 <= lbar <= 3, Sec. 3.2); use confinement = \"surface\"",
            scene.name
        );
    }
    Ok(scene)
}

/// Map the scene's accuracy (or the command-line override) to the solver's.
pub fn accuracy_of(scene: &Scene, over: Option<&str>) -> Result<Accuracy> {
    Ok(match over {
        Some(s) => s.parse::<Accuracy>()?,
        None => match scene.accuracy {
            rodloop_scene::Accuracy::Fast => Accuracy::Fast,
            rodloop_scene::Accuracy::Default => Accuracy::Default,
            rodloop_scene::Accuracy::High => Accuracy::High,
        },
    })
}

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
fn start_from_file(path: &Path, radius: f64) -> Result<StartShape> {
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
            kg.push(number(r.get(k), path, i, "kappa_g")? * radius);
        }
        if kg.len() < 8 {
            bail!(
                "{}: needs at least 8 rows of kappa_g, found {}",
                path.display(),
                kg.len()
            );
        }
        return Ok(StartShape::from_kappa_g_samples(&kg)?);
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
    let (shape, _lbar, _rho) = from_points(&pts)?;
    Ok(shape)
}

/// Run the subcommand.
pub fn run(args: &Args) -> Result<()> {
    let scene = load_scene(args.scene.as_deref())?;
    let accuracy = accuracy_of(&scene, args.accuracy.as_deref())?;
    if args.branch == 0 || args.branch > 1000 {
        bail!("--branch must be from 1 to 1000 (got {})", args.branch);
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
    let stiffness = stiffness_of(&scene.stiffness);
    let start = match &args.from {
        Some(p) => start_from_file(p, scene.radius)?,
        None => StartShape::Euler { l: eta },
    };
    let res = solve_with_accuracy(
        scene.radius,
        args.lbar,
        &stiffness,
        &start,
        accuracy,
        &SolveOptions::default(),
    )
    .with_context(|| format!("solving branch {} at lbar = {}", args.branch, args.lbar))?;
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
    let stab = eq.stability()?;
    let profile = eq.profile();
    let mut table = Table::new(
        "config.csv",
        &[
            "s", "x", "y", "z", "kappa", "tau", "kappa_g", "lambda", "F_t", "F_n", "F_b", "D",
        ],
    );
    for p in &profile {
        table.push(vec![
            Cell::F(p.s),
            Cell::F(p.x),
            Cell::F(p.y),
            Cell::F(p.z),
            Cell::F(p.kappa),
            Cell::F(p.tau),
            Cell::F(p.kappa_g),
            Cell::F(p.lambda),
            Cell::F(p.f_t),
            Cell::F(p.f_n),
            Cell::F(p.f_b),
            Cell::F(p.d),
        ])?;
    }
    let (lambda_min, lambda_max) = res.lambda_range;
    let summary = json!({
        "scene": scene.name,
        "lbar": args.lbar,
        "branch": branch_of_eta(eta),
        "eta": eta,
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
        "lambda_error_estimate": res.lambda_error,
        "residual": report.residual,
        "closure": report.closure,
        "nodes": profile.len(),
        "iterations": report.iterations,
        "relax_iterations": report.relax_iterations,
        "units": "energy E R/(pi D0); lambda, F in units of D0/R^3, D0/R^2; eigenvalues in units of D0",
    });
    ensure_dir(&args.out)?;
    table.write(&args.out)?;
    write_json(&args.out, "summary.json", &summary)?;
    if args.draw {
        let set = crate::draw::DrawSettings::beside(&args.out);
        crate::draw::draw_loop(&args.out.join("config.csv"), &set)?;
    }
    outln!(
        "branch {} (eta = {eta}) at lbar = {}: E R/(pi D0) = {:.10} ± {:.1e}, index {} ({}), lambda in [{:.6}, {:.6}] ± {:.1e}",
        args.branch,
        args.lbar,
        res.energy.total,
        res.energy_error,
        stab.index,
        if stab.index == 0 { "local minimum" } else { "unstable" },
        lambda_min,
        lambda_max,
        res.lambda_error
    );
    outln!(
        "{} nodes, {} Newton iterations, KKT residual {:.1e}; wrote config.csv and summary.json to {}",
        profile.len(),
        report.iterations,
        report.residual,
        args.out.display()
    );
    Ok(())
}
