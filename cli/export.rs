//! `rodloop export`: loop tables (`config.csv` of `solve`, the `states/` files of a diagram,
//! `loop-NN.csv` of `analytic`) as VTK PolyData (`.vtp`) for ParaView: the points, one closed
//! polyline, and every column of the table (`s, kappa, tau, kappa_g, lambda, F_t, F_n, F_b,
//! D, …`) as point data (see `rodloop_figures::vtk`).

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use rodloop_figures::data::LoopData;
use rodloop_figures::vtk::loop_vtp;

use crate::output::{ensure_dir, write_atomic};

/// Arguments of `rodloop export`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Loop tables to export (config.csv, states/*.csv, loop-NN.csv, curve.csv).
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
    /// Output directory (default: each file's directory; out/export for the state files of a
    /// diagram's states/, which holds that diagram's files only).
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// The loop's scalars for the file's field data: `lbar` (from the solve's `summary.json`
/// beside a `config.csv`, else from the table) and the solve's `energy` when known.
fn fields(path: &Path, data: &LoopData) -> Vec<(&'static str, f64)> {
    let summary = (path.file_name().is_some_and(|n| n == "config.csv"))
        .then(|| path.with_file_name("summary.json"))
        .and_then(|p| std::fs::read_to_string(p).ok())
        .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
        .unwrap_or_default();
    let mut out = vec![(
        "lbar",
        summary["lbar"].as_f64().unwrap_or_else(|| data.lbar()),
    )];
    if let Some(e) = summary["energy"].as_f64() {
        out.push(("energy", e));
    }
    out
}

/// Run the subcommand.
pub fn run(args: &Args) -> Result<()> {
    let mut written = Vec::new();
    for file in &args.files {
        if !std::fs::metadata(file)
            .with_context(|| format!("cannot read {}", file.display()))?
            .is_file()
        {
            bail!("{} is not a file", file.display());
        }
        let data = LoopData::read(file)?;
        let text = loop_vtp(&data, &fields(file, &data))?;
        let dir = file
            .parent()
            .map(Path::to_path_buf)
            .unwrap_or_else(|| PathBuf::from("."));
        let out = match &args.out {
            Some(o) => o.clone(),
            None if crate::draw::in_diagram_states(&dir) => PathBuf::from("out/export"),
            None => dir,
        };
        let stem = file
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or("loop")
            .to_string();
        ensure_dir(&out)?;
        let path = write_atomic(&out, &format!("{stem}.vtp"), text.as_bytes())?;
        written.push(path);
    }
    for p in &written {
        outln!("wrote {}", p.display());
    }
    Ok(())
}
