//! `rodloop compare --scene FILE` for a two-segment rod on the sphere (Eq. 51): the paper's
//! statements of Sec. 5 next to rodloop's numeric diagram of the scene.
//!
//! The rows ([`rodloop_diagram::compare::segment_rows`]: the energy of an extremely soft
//! segment, the mirror symmetry of branch 1's saddle-like states) come from the diagram
//! crate; this module runs the diagram, prints and writes them.

use std::path::Path;

use anyhow::{bail, Context, Result};
use rodloop_diagram::compare::{segment_rows, ENERGY_TOLERANCE, SOFT_LIMIT};
use rodloop_diagram::DiagramOptions;
use rodloop_diagram::Engine;
use rodloop_scene::{Scene, StiffnessSpec};

use crate::output::{checked_json, Cell, OutputRun, Table};

/// Run the comparison for a two-segment surface scene.
pub fn run(scene: &Scene, out: &Path) -> Result<()> {
    let StiffnessSpec::Tanh { d0, d1, s0, s1, .. } = scene.stiffness else {
        bail!(
            "compare --scene {}: the paper's two-segment statements (Sec. 5) need a two-segment stiffness (kind = \"tanh\")",
            scene.name
        );
    };
    let opts = DiagramOptions {
        radius: scene.radius,
        stiffness: crate::args::stiffness_of(&scene.stiffness),
        lbar_min: scene.lbar_min,
        lbar_max: scene.lbar_max,
        accuracy: crate::args::accuracy_of(scene, None)?,
        ..Default::default()
    };
    opts.validate()?;
    let mut engine = rodloop_diagram::SurfaceEngine {
        opts,
        hook: &mut (),
    };
    let d = engine
        .run(&mut |_| {})
        .with_context(|| format!("numeric diagram of scene {}", scene.name))?;
    let schema = engine.schema(&d, &scene.name)?;
    let ratio = d1 / d0;
    let out_rows = segment_rows(&schema, ratio, (s0, s1), (scene.lbar_min, scene.lbar_max));
    if out_rows.is_empty() {
        bail!(
            "compare --scene {}: the diagram has no stable state to compare (range {} to {})",
            scene.name,
            scene.lbar_min,
            scene.lbar_max
        );
    }
    let mut table = Table::new(
        "compare.csv",
        &[
            "id",
            "lbar",
            "paper",
            "numeric",
            "relative_deviation",
            "tolerance",
            "agrees",
            "source",
        ],
    );
    outln!(
        "scene {} (D1/D0 = {ratio}, s0*/L = {s0}, s1*/L = {s1}): the paper's two-segment statements (Sec. 5) against rodloop's diagram",
        scene.name
    );
    outln!(
        "{:<18} {:>8} {:>14} {:>26} {:>10} {:>6} {:>6}",
        "id",
        "lbar",
        "paper",
        "numeric",
        "deviation",
        "tol",
        "agrees"
    );
    let opt = |v: Option<f64>| v.map(|x| x.to_string()).unwrap_or_default();
    let mut json_rows = Vec::new();
    for r in &out_rows {
        outln!(
            "{:<18} {:>8} {:>14} {:>26} {:>10} {:>6} {:>6}",
            r.id,
            r.lbar.map(|l| format!("{l:.4}")).unwrap_or_default(),
            r.paper,
            r.numeric,
            r.deviation
                .map(|x| format!("{:.2}%", 100.0 * x))
                .unwrap_or_else(|| "-".into()),
            r.tolerance
                .map(|x| format!("{:.0}%", 100.0 * x))
                .unwrap_or_else(|| "-".into()),
            match r.agrees {
                Some(true) => "yes",
                Some(false) => "NO",
                None => "-",
            }
        );
        table.push(vec![
            Cell::S(r.id.clone()),
            Cell::S(opt(r.lbar)),
            Cell::S(r.paper.clone()),
            Cell::S(r.numeric.clone()),
            Cell::S(opt(r.deviation)),
            Cell::S(opt(r.tolerance)),
            Cell::S(r.agrees.map(|a| a.to_string()).unwrap_or_default()),
            Cell::S(r.source.into()),
        ])?;
        json_rows.push(checked_json!({
            "id": r.id, "lbar": r.lbar, "paper": r.paper, "numeric": r.numeric,
            "relative_deviation": r.deviation, "tolerance": r.tolerance, "agrees": r.agrees,
            "source": r.source,
        })?);
    }
    if ratio > SOFT_LIMIT {
        outln!(
            "the energy estimate is judged for D1/D0 <= {SOFT_LIMIT} only (the paper states it for 0.001); here the rows show how far it is off"
        );
    }
    let run = OutputRun::begin(out)?;
    run.write_table(&table)?;
    let summary = checked_json!({
        "scene": scene.name,
        "model": "two-segment statements of Sec. 5 against the numeric diagram",
        "d1_over_d0": ratio,
        "energy_tolerance": ENERGY_TOLERANCE,
        "soft_limit": SOFT_LIMIT,
        "disagreements": out_rows.iter().filter(|r| r.agrees == Some(false)).count(),
        "values": json_rows,
        "units": "lbar = L/(2 pi R); energy E R/(pi D0)",
    })?;
    run.write_json("summary.json", &crate::output::strip_nulls(summary))?;
    run.commit()?;
    outln!("wrote compare.csv and summary.json to {}", out.display());
    Ok(())
}
