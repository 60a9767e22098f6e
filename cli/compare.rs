//! `rodloop compare`: the paper's printed values next to rodloop's results, with deviations.
//!
//! The rows (the paper's values of `data/reference/paper_values.csv`, the exact layer's and
//! the numeric diagram's) come from [`rodloop_diagram::compare`]; this module prints and
//! writes them.

use std::path::PathBuf;

use anyhow::{Context, Result};
pub use rodloop_diagram::compare::{compare_rows, CompareRow};
use rodloop_diagram::Engine;

use crate::output::{checked_json, Cell, OutputRun, Table};

/// Arguments of `rodloop compare`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Output directory.
    #[arg(long, default_value = "out/compare")]
    pub out: PathBuf,
    /// Compare a scene: `enclosed` (the built-in homogeneous enclosed scene) or a scene file
    /// with `confinement = "enclosed"` (against the surface), or a two-segment scene on the
    /// surface (against the paper's statements of Sec. 5).
    #[arg(long)]
    pub scene: Option<String>,
}

/// Run the subcommand without `--scene`: the default scene's numeric diagram against the
/// exact layer and the paper's printed values.
pub fn run(args: &Args) -> Result<()> {
    let mut engine = rodloop_diagram::SurfaceEngine {
        opts: rodloop_diagram::DiagramOptions::default(),
        hook: &mut (),
    };
    let nd = engine
        .run(&mut |_| {})
        .context("numeric diagram of the default scene")?;
    let values = compare_rows(Some(&engine.schema(&nd, "")?))?;
    let mut table = Table::new(
        "compare.csv",
        &[
            "id",
            "kind",
            "branch",
            "lbar",
            "paper",
            "resolution",
            "exact",
            "exact_deviation",
            "within_resolution",
            "tolerance",
            "numeric",
            "numeric_deviation",
            "numeric_within_resolution",
            "numeric_minus_exact",
            "source",
        ],
    );
    let mut rows = Vec::new();
    outln!(
        "{:<11} {:<15} {:>6} {:>5} {:>9} {:>8} {:>17} {:>9} {:>6} {:>17} {:>9} {:>6}",
        "id",
        "kind",
        "branch",
        "lbar",
        "paper",
        "tol",
        "exact",
        "deviation",
        "agrees",
        "numeric",
        "deviation",
        "agrees"
    );
    let mut disagreements = 0;
    let mut numeric_disagreements = 0;
    for r in &values {
        disagreements += usize::from(r.agrees_exact == Some(false));
        numeric_disagreements += usize::from(r.agrees_numeric == Some(false));
        let yes = |a: Option<bool>| match a {
            Some(true) => "yes",
            Some(false) => "NO",
            None => "-",
        };
        let sci = |v: Option<f64>| v.map(|x| format!("{x:.1e}")).unwrap_or_else(|| "-".into());
        outln!(
            "{:<11} {:<15} {:>6} {:>5} {:>9} {:>8} {:>17} {:>9} {:>6} {:>17} {:>9} {:>6}",
            r.id,
            r.kind,
            r.branch,
            r.lbar.map(|l| l.to_string()).unwrap_or_default(),
            if r.paper.len() > 9 {
                &r.paper[..9]
            } else {
                &r.paper
            },
            match (r.kind.as_str(), r.tolerance) {
                ("winding", _) | (_, None) => "exact".to_string(),
                (_, Some(t)) => format!("±{t:.0e}"),
            },
            r.exact_text(),
            sci(r.exact_deviation),
            yes(r.agrees_exact),
            r.numeric_text(),
            sci(r.numeric_deviation),
            yes(r.agrees_numeric),
        );
        let opt = |v: Option<f64>| v.map(|x| x.to_string()).unwrap_or_default();
        table.push(vec![
            Cell::S(r.id.clone()),
            Cell::S(r.kind.clone()),
            Cell::I(r.branch.into()),
            Cell::S(opt(r.lbar)),
            Cell::S(r.paper.clone()),
            Cell::S(opt(r.resolution)),
            Cell::S(r.symmetry.clone().unwrap_or_else(|| opt(r.exact))),
            Cell::S(opt(r.exact_deviation)),
            Cell::S(r.agrees_exact.map(|a| a.to_string()).unwrap_or_default()),
            Cell::S(opt(r.tolerance)),
            Cell::S(opt(r.numeric)),
            Cell::S(opt(r.numeric_deviation)),
            Cell::S(r.agrees_numeric.map(|a| a.to_string()).unwrap_or_default()),
            Cell::S(opt(r.numeric_minus_exact)),
            Cell::S(r.source.clone()),
        ])?;
        rows.push(checked_json!({
            "id": r.id,
            "paper": r.paper,
            "exact": r.symmetry.clone().map(serde_json::Value::from).unwrap_or_else(|| r.exact.into()),
            "numeric": r.numeric,
            "agrees_exact": r.agrees_exact,
            "agrees_numeric": r.agrees_numeric,
            "numeric_minus_exact": r.numeric_minus_exact,
        })?);
    }
    let run = OutputRun::begin(&args.out)?;
    run.write_table(&table)?;
    let summary = checked_json!({
        "rows": values.len(),
        "disagreements_exact": disagreements,
        "disagreements_numeric": numeric_disagreements,
        "numeric_model": "rodloop diagram --model numeric, default scene, default accuracy",
        "values": rows,
        "units": "lengths lbar = L/(2 pi R); energy E R/(pi D); lambda R^3/D",
    })?;
    run.write_json("summary.json", &crate::output::strip_nulls(summary))?;
    run.commit()?;
    outln!(
        "{} paper values; beyond the printed resolution {} disagree with the exact layer and {} with the numeric model (winding numbers and symmetries: exact layer only). Wrote compare.csv and summary.json to {}",
        values.len(),
        disagreements,
        numeric_disagreements,
        args.out.display()
    );
    Ok(())
}
