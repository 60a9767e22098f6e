//! `rodloop euler`: the Euler rotation curve approximation (Eqs. 4-6).

use std::path::PathBuf;

use anyhow::{Context, Result};
use rodloop_exact::euler::EulerCurve;
use serde_json::json;

use crate::output::{ensure_dir, write_json, Cell, Table};

/// Arguments of `rodloop euler`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Integer periodicity l of Eq. (4) (l = 1 hippopede, l = 2 tennis-ball seam).
    #[arg(long)]
    pub l: u32,
    /// Normalised length L/(2 pi R), in (l - 1, l + 1).
    #[arg(long)]
    pub lbar: f64,
    /// Number of points, uniform in arclength.
    #[arg(long, default_value_t = 512)]
    pub points: usize,
    /// Also draw the loop (four views, SVG and PNG) next to the CSV (see `rodloop draw`).
    #[arg(long)]
    pub draw: bool,
    /// Output directory.
    #[arg(long, default_value = "out/euler")]
    pub out: PathBuf,
}

/// Run the subcommand.
pub fn run(args: &Args) -> Result<()> {
    if args.points < 8 {
        anyhow::bail!("--points must be at least 8 (got {})", args.points);
    }
    let curve = EulerCurve::from_lbar(args.l, args.lbar).with_context(|| {
        format!(
            "no Euler rotation curve with l = {} at lbar = {}",
            args.l, args.lbar
        )
    })?;
    let energy = curve.bending_energy();
    let energy_g = curve.energy_g();
    if !energy.converged || !energy_g.converged {
        anyhow::bail!(
            "the Euler curve with l = {} at lbar = {} is too close to degenerate for the energy quadrature to converge ({} points); choose lbar further from {}",
            args.l,
            args.lbar,
            energy.points,
            args.l.saturating_sub(1)
        );
    }
    let mut table = Table::new(
        "curve.csv",
        &["s", "x", "y", "z", "kappa", "tau", "kappa_g"],
    );
    for p in curve.sample(args.points) {
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
    ensure_dir(&args.out)?;
    table.write(&args.out)?;
    let summary = json!({
        "l": args.l,
        "lbar": args.lbar,
        "alpha": curve.alpha,
        "length": curve.length(),
        "energy": energy.value,
        "energy_error_estimate": energy.error_estimate,
        "energy_n": curve.energy_n(),
        "energy_g": energy_g.value,
        "total_torsion": curve.total_torsion().value,
        "quadrature_points": energy.points,
        "units": "R = 1; energy is E R/(pi D)",
    });
    write_json(&args.out, "summary.json", &summary)?;
    if args.draw {
        let set = crate::draw::DrawSettings::beside(&args.out);
        crate::draw::draw_loop(&args.out.join("curve.csv"), &set)?;
    }
    outln!(
        "Euler rotation curve l = {}, lbar = {}: alpha = {:.15}, energy E R/(pi D) = {:.12} (quadrature error <= {:.1e})",
        args.l, args.lbar, curve.alpha, energy.value, energy.error_estimate
    );
    outln!("wrote {}/curve.csv and summary.json", args.out.display());
    Ok(())
}
