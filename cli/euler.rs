//! `rodloop euler`: the Euler rotation curve approximation (Eqs. 4-6).

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use rodloop_exact::eta_of_branch;
use rodloop_exact::euler::EulerCurve;
use rodloop_exact::shape::{unit_sphere_shape, ShapeTolerances};

use crate::output::{checked_json, Cell, OutputRun, Table};

/// Largest `--l` accepted (as for `analytic --eta`).
const MAX_L: u64 = 1000;

/// Arguments of `rodloop euler`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Integer periodicity l of Eq. (4) (l = 1 hippopede, l = 2 tennis-ball seam); l = eta.
    #[arg(long, required_unless_present = "branch", conflicts_with = "branch")]
    pub l: Option<u64>,
    /// Alternative to --l: the paper's branch number (its curve has l = eta(B)).
    #[arg(long)]
    pub branch: Option<u64>,
    /// Normalised length L/(2 pi R), in (l - 1, l + 1).
    #[arg(long)]
    pub lbar: f64,
    /// Number of points, uniform in arclength (at most 1,000,000; the environment variable
    /// RODLOOP_MAX_POINTS raises the cap).
    #[arg(long, default_value_t = 512)]
    pub points: u64,
    /// Also draw the loop (four views, SVG and PNG) next to the CSV (see `rodloop draw`).
    #[arg(long)]
    pub draw: bool,
    /// Output directory.
    #[arg(long, default_value = "out/euler")]
    pub out: PathBuf,
}

/// Run the subcommand.
pub fn run(args: &Args) -> Result<()> {
    let l = match (args.l, args.branch) {
        (Some(l), _) => {
            if l == 0 || l > MAX_L {
                bail!("--l must be an integer from 1 to {MAX_L} (got {l})");
            }
            l as u32
        }
        (None, Some(b)) => {
            if b == 0 || b > MAX_L {
                bail!("--branch must be an integer from 1 to {MAX_L} (got {b})");
            }
            eta_of_branch(b as u32)
        }
        (None, None) => bail!("give --l N (or --branch B)"),
    };
    crate::output::check_lbar(args.lbar)?;
    let points = crate::output::check_points(args.points)?;
    let lf = f64::from(l);
    if !(args.lbar > lf - 1.0 && args.lbar < lf + 1.0) {
        bail!(
            "the Euler curve with l = {l} exists only for {} < lbar < {}; got lbar = {}",
            lf - 1.0,
            lf + 1.0,
            args.lbar
        );
    }
    let curve = EulerCurve::from_lbar(l, args.lbar).with_context(|| {
        format!(
            "no Euler rotation curve with l = {l} at lbar = {}",
            args.lbar
        )
    })?;
    let energy = curve.bending_energy();
    let energy_g = curve.energy_g();
    if !energy.converged || !energy_g.converged {
        bail!(
            "the Euler curve with l = {l} at lbar = {} is too close to degenerate for the energy quadrature to converge ({} points); choose lbar further from {}",
            args.lbar,
            energy.points,
            l.saturating_sub(1)
        );
    }
    let run = OutputRun::begin(&args.out)?;
    let mut table = Table::new(
        "curve.csv",
        &["s", "x", "y", "z", "kappa", "tau", "kappa_g"],
    );
    let samples = curve.sample(points);
    for p in &samples {
        table.push(vec![
            Cell::F(p.s),
            Cell::F(p.x),
            Cell::F(p.y),
            Cell::F(p.z),
            Cell::F(p.kappa),
            Cell::F(p.tau),
            Cell::F(p.kappa_g),
        ])?;
    }
    run.write_table(&table)?;
    // The quadrature's own estimate can be 0 when successive refinements agree to the last
    // bit; the rounding of the sum (a few ulps of the value) is then the bound.
    let bound = energy
        .error_estimate
        .max(4.0 * f64::EPSILON * energy.value.abs());
    let shape = unit_sphere_shape(
        curve.length(),
        samples
            .iter()
            .map(|p| (p.s, nalgebra::Vector3::new(p.x, p.y, p.z), p.kappa_g)),
        ShapeTolerances::default(),
    )?;
    let mut summary = checked_json!({
        "l": l,
        "lbar": args.lbar,
        "alpha": curve.alpha,
        "length": curve.length(),
        "energy": energy.value,
        "energy_error_estimate": bound,
        "energy_n": curve.energy_n(),
        "energy_g": energy_g.value,
        "total_torsion": curve.total_torsion().value,
        "quadrature_points": energy.points,
        "units": "lengths in units of R; kappa, tau, kappa_g in 1/R; energy E R/(pi D)",
    })?;
    crate::draw::add_shape(&mut summary, &shape);
    run.write_json("summary.json", &summary)?;
    run.commit()?;
    let pictures = if args.draw {
        let mut set = crate::draw::DrawSettings::beside(&args.out);
        set.overlay = crate::draw::exact_overlay(l, args.lbar);
        crate::draw::draw_loop(&args.out.join("curve.csv"), &set)?
    } else {
        Vec::new()
    };
    outln!(
        "Euler rotation curve l = {l}, lbar = {}: alpha = {:.15}, energy E R/(pi D) = {:.12} (quadrature error <= {:.1e}{})",
        args.lbar,
        curve.alpha,
        energy.value,
        bound,
        if energy.error_estimate < bound { ", the rounding of the sum" } else { "" }
    );
    outln!(
        "wrote curve.csv, summary.json{} to {}",
        crate::draw::and_pictures(&pictures),
        args.out.display()
    );
    Ok(())
}
