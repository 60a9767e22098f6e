//! `rodloop analytic`: every exact closed loop with `eta` periods of geodesic curvature.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use rodloop_exact::ShapeTolerances;
use rodloop_exact::{all_loops, branch_of_eta, eta_of_branch, Family};

use crate::output::{checked_json, Cell, OutputRun, Table};

/// Largest `--eta` accepted: beyond it `p` reaches ~1e3 and the closure loses the digits
/// needed for a 1e-10 residual.
const MAX_ETA: u32 = 1000;
/// Largest `--lbar` accepted, for the same reason.
const MAX_LBAR: f64 = 1000.0;

/// Arguments of `rodloop analytic`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Normalised length L/(2 pi R).
    #[arg(long)]
    pub lbar: f64,
    /// Number of periods of the geodesic curvature (eta = 2 is branch 1, eta = 1 branch 2).
    #[arg(long, required_unless_present = "branch", conflicts_with = "branch")]
    pub eta: Option<u64>,
    /// Alternative to --eta: the paper's branch number (1: eta = 2, 2: eta = 1, B >= 3: eta = B).
    #[arg(long)]
    pub branch: Option<u64>,
    /// Number of points per loop, uniform in arclength (at most 1,000,000; the environment
    /// variable RODLOOP_MAX_POINTS raises the cap).
    #[arg(long, default_value_t = 512)]
    pub points: u64,
    /// Also draw every loop (four views, SVG and PNG) next to its CSV (see `rodloop draw`).
    #[arg(long)]
    pub draw: bool,
    /// Output directory.
    #[arg(long, default_value = "out/analytic")]
    pub out: PathBuf,
}

/// Run the subcommand.
pub fn run(args: &Args) -> Result<()> {
    let eta = match (args.eta, args.branch) {
        (Some(e), _) => {
            if e == 0 || e > u64::from(MAX_ETA) {
                bail!("--eta must be an integer from 1 to {MAX_ETA} (got {e})");
            }
            e as u32
        }
        (None, Some(b)) => {
            if b == 0 || b > u64::from(MAX_ETA) {
                bail!("--branch must be an integer from 1 to {MAX_ETA} (got {b})");
            }
            eta_of_branch(b as u32)
        }
        (None, None) => bail!("give --eta N (or --branch B)"),
    };
    crate::output::check_lbar(args.lbar)?;
    if args.lbar > MAX_LBAR {
        bail!(
            "lbar must be at most {MAX_LBAR} (got {}): beyond it the closure loses the digits needed for a 1e-10 residual",
            args.lbar
        );
    }
    let points = crate::output::check_points(args.points)?;
    let loops = all_loops(eta, args.lbar).with_context(|| {
        format!(
            "solving the closure for eta = {} at lbar = {}",
            eta, args.lbar
        )
    })?;
    if loops.is_empty() {
        bail!(
            "no closed loop with eta = {} at lbar = {} (the paper's branch for this eta exists for {} < lbar < {})",
            eta,
            args.lbar,
            eta - 1,
            eta + 1
        );
    }
    let run = OutputRun::begin(&args.out)?;
    let mut summaries = Vec::new();
    outln!(
        "{} closed loop(s) with eta = {} at lbar = {} (branch {} is q = {}):",
        loops.len(),
        eta,
        args.lbar,
        branch_of_eta(eta),
        -(eta as i32 + 1)
    );
    outln!(
        "  {:>3} {:>6} {:>4} {:>4} {:>20} {:>20} {:>20} {:>10}",
        "#",
        "family",
        "p",
        "q",
        "k",
        "cR",
        "E R/(pi D)",
        "closure"
    );
    for (i, lp) in loops.iter().enumerate() {
        let name = format!("loop-{:02}.csv", i + 1);
        let mut table = Table::new(
            &name,
            &[
                "s", "x", "y", "z", "kappa", "tau", "kappa_g", "lambda", "F_t", "F_n", "F_b",
            ],
        );
        for p in lp.sample(points)? {
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
            ])?;
        }
        run.write_table(&table)?;
        let energy = lp.energy()?;
        let (lambda_min, lambda_max) = lp.lambda_range();
        let family = match lp.family {
            Family::Wave => "wave",
            Family::Orbit => "orbit",
        };
        let paper_branch = lp.family == Family::Wave && lp.q == -(eta as i32 + 1);
        let k2_small = lp.k2_small();
        outln!(
            "  {:>3} {:>6} {:>4} {:>4} {:>20.15} {:>20.15} {:>20.15} {:>10.1e}{}",
            i + 1,
            family,
            lp.p,
            lp.q,
            lp.k,
            lp.c,
            energy,
            lp.closure_residual,
            if paper_branch {
                "  <- paper branch"
            } else {
                ""
            }
        );
        let shape = rodloop_exact::shape::exact_loop_shape(lp, ShapeTolerances::default())?;
        let mut entry = checked_json!({
            "file": name,
            "family": family,
            "paper_branch": paper_branch,
            "branch": if paper_branch { Some(branch_of_eta(eta)) } else { None },
            "lbar": lp.lbar,
            "eta": lp.eta,
            "p": lp.p,
            "q": lp.q,
            "k": lp.k,
            "c": lp.c,
            "energy": energy,
            "energy_n": lp.energy_n(),
            "energy_g": lp.energy_g()?,
            "lambda_min": lambda_min,
            "lambda_max": lambda_max,
            "conserved_moment": lp.conserved_moment(),
            "closure_residual": lp.closure_residual,
            "k2_small_b4": if lp.family == Family::Wave { Some(k2_small) } else { None },
            "k2_small_b4_error": if lp.family == Family::Wave { Some(k2_small - lp.k * lp.k) } else { None },
        })?;
        crate::draw::add_shape(&mut entry, &shape);
        summaries.push(entry);
    }
    let summary = checked_json!({
        "lbar": args.lbar,
        "eta": eta,
        "units": "R = 1, D = 1: energy E R/(pi D), lambda R^3/D, forces F R^2/D",
        "search": "all integers q crossed by the continuous closure p_cont(m), 0 < m <= 1 - 1e-6, both families",
        "loops": summaries,
    })?;
    // serde_json writes None as null; our NaN guard would reject that, so drop the nulls.
    let summary = crate::output::strip_nulls(summary);
    run.write_json("summary.json", &summary)?;
    run.commit()?;
    let mut pictures = 0;
    if args.draw {
        let set = crate::draw::DrawSettings::beside(&args.out);
        for i in 0..loops.len() {
            let path = args.out.join(format!("loop-{:02}.csv", i + 1));
            pictures += crate::draw::draw_loop(&path, &set)?.len();
        }
    }
    outln!(
        "wrote {} loop file(s){}, summary.json to {}",
        loops.len(),
        if pictures > 0 {
            format!(", {pictures} picture files (SVG, PNG, -draw.json)")
        } else {
            String::new()
        },
        args.out.display()
    );
    Ok(())
}
