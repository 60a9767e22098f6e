//! `rodloop diagram` for enclosed scenes (`|r| ≤ R`, paper Sec. 3.2): the
//! engine is `rodloop_diagram::enclosed` (attached parts from the exact layer, lifted-off
//! parts from the 3-D model, events where `λ_min` crosses zero, exchanges re-solved where a
//! branch has lifted off); non-uniform rods from their surface families.

use std::path::Path;

use anyhow::{bail, Context, Result};
use rodloop_diagram::enclosed::EnclosedProgress;
use rodloop_diagram::engine::{CertificateCheck, ExchangeCheck};
use rodloop_diagram::{EnclosedEngine, Engine, PointStates};
use rodloop_figures::raster::svg_to_png;
use rodloop_scene::Scene;

use super::args::{Args, Model};
use crate::output::OutputRun;

/// Run `rodloop diagram` on an enclosed scene.
pub fn run(args: &Args, scene: &Scene) -> Result<()> {
    if args.model == Model::Exact {
        bail!(
            "--model exact does not apply to enclosed scenes: the enclosed diagram uses the exact layer where a branch is attached and the 3-D enclosed model where it has lifted off (omit --model)"
        );
    }
    if args.resume
        || args.max_step.is_some()
        || args.min_step.is_some()
        || args.max_points.is_some()
        || args.newton_tol.is_some()
    {
        bail!(
            "--resume, --max-step, --min-step, --max-points and --newton-tol control the surface tracer; the enclosed diagram samples every --step in lbar (default 0.05) and traces lifted-off parts by natural-parameter steps"
        );
    }
    let lbar_min = args.lbar_min.unwrap_or(scene.lbar_min);
    let lbar_max = args.lbar_max.unwrap_or(scene.lbar_max);
    if !(lbar_min > 0.0 && lbar_max > lbar_min && lbar_max <= 20.0) {
        bail!("need 0 < --lbar-min < --lbar-max <= 20 for an enclosed diagram (got {lbar_min} and {lbar_max})");
    }
    let accuracy = crate::args::accuracy_of(scene, args.accuracy.as_deref())?;
    let mut engine = EnclosedEngine::new(
        crate::engine::wall_of(scene),
        crate::args::stiffness_of(&scene.stiffness),
        lbar_min,
        lbar_max,
    );
    let opts = &mut engine.opts;
    opts.accuracy = accuracy;
    if let Some(step) = args.step {
        opts.step = step;
    }
    if !args.branch.is_empty() {
        let mut sel = Vec::new();
        for &b in &args.branch {
            let b = u32::try_from(b).with_context(|| format!("--branch {b}"))?;
            let ok = if b == 0 {
                lbar_min <= 1.0
            } else {
                let e = f64::from(rodloop_exact::eta_of_branch(b));
                e - 1.0 < lbar_max && e + 1.0 > lbar_min
            };
            if !ok {
                bail!("--branch {b}: no such branch in the length range [{lbar_min}, {lbar_max}] (branch 0 is the circle, lbar <= 1)");
            }
            sel.push(b);
        }
        opts.branches = Some(sel);
    }
    let run = OutputRun::begin(&args.out)?;
    // Progress on stderr (cli/progress.rs): a bar on a terminal, one line per task otherwise.
    let bar = crate::progress::Progress::new(0, "enclosed", args.quiet);
    let mut planned = 0u64;
    let d = engine
        .run(&mut |p| match p {
            EnclosedProgress::Planned(n) => {
                planned += n as u64;
                bar.set_length(planned);
            }
            EnclosedProgress::Done(msg) => bar.done(msg),
        })
        .context("the enclosed diagram")?;
    bar.finish();
    // The completeness certificate (the same search `solve` runs) goes into summary.json.
    let cert = engine.certificate(&d);
    let mut schema = engine.schema(&d, &scene.name)?;
    schema.set_certificate(&cert.at_lowest)?;
    schema.put("exchange_certificate", &cert.at_exchanges)?;
    let state_warnings = write_outputs(&mut schema, &d, &engine, &run, args.width, args.height)?;
    if args.shapes > 0 {
        // The branch atlas (cli/atlas.rs): states re-solved along each branch, in states/.
        crate::atlas::write_enclosed_atlas(&run, args.shapes, scene, accuracy, &schema)?;
    }
    run.commit()?;
    print(&schema, state_warnings, scene, &engine, &args.out);
    print_certificate(&cert.at_lowest);
    print_exchange_certificate(&cert.at_exchanges);
    Ok(())
}

/// One line per located exchange of the certificate, a warning where `solve` finds a state
/// below the exchange's energy (the diagram missed it) and where it does not reach a traced
/// state there.
fn print_exchange_certificate(checks: &[ExchangeCheck]) {
    for c in checks {
        let [a, b] = c.branches;
        let (e, de) = c.energy;
        let show = |f: Option<(f64, f64)>, branch: u32| match f {
            Some((v, dv)) => format!("branch {branch} {v:.10} ± {dv:.1e}"),
            None => format!("branch {branch} no local minimum"),
        };
        outln!(
            "  certificate at the exchange {a} -> {b}, lbar = {:.10} ± {:.1e}, E R/(pi D) = {e:.10} ± {de:.1e}: solve finds {}, {}",
            c.lbar,
            c.error_estimate,
            show(c.solve_energies[0], a),
            show(c.solve_energies[1], b)
        );
        if c.below {
            eprintln!(
                "warning: solve finds a state below the exchange {a} -> {b} at lbar = {:.10} (E R/(pi D) = {e:.10} ± {de:.1e}) beyond the estimates: the diagram missed it, and the exchange lies elsewhere",
                c.lbar
            );
        }
        if c.misses {
            let why = if c.note.is_empty() {
                "a state above the exchange's energy beyond the estimates".to_string()
            } else {
                c.note.clone()
            };
            eprintln!(
                "warning: solve does not reach the traced states of the exchange {a} -> {b} at lbar = {:.10}: {why}",
                c.lbar
            );
        }
    }
}

/// One line per length of the certificate, a warning per state below the diagram's and per
/// lowest state that `solve` for its branch does not reach.
fn print_certificate(cert: &[CertificateCheck]) {
    let mut xs: Vec<f64> = cert.iter().map(|c| c.lbar).collect();
    xs.dedup();
    for x in xs {
        let here: Vec<_> = cert.iter().filter(|c| c.lbar == x).collect();
        let (b, f, e, de) = here[0].lowest;
        let found: Vec<String> = here
            .iter()
            .map(|c| match c.solve_energy {
                Some((v, err)) => format!("branch {} {v:.10} ± {err:.1e}", c.branch),
                None => format!("branch {} none", c.branch),
            })
            .collect();
        outln!(
            "  certificate at lbar = {x:.6}: lowest branch {b} family {f}, E R/(pi D) = {e:.10} ± {de:.1e}; solve finds {}",
            found.join(", ")
        );
        for c in here.iter().filter(|c| c.below) {
            if let Some((v, err)) = c.solve_energy {
                eprintln!(
                    "warning: solve finds branch {} at lbar = {x:.6} with E R/(pi D) = {v:.10} ± {err:.1e}, below the diagram's lowest state ({e:.10} ± {de:.1e}): the diagram missed it",
                    c.branch
                );
            }
        }
        for c in here.iter().filter(|c| c.misses) {
            let found = match c.solve_energy {
                Some((v, err)) => format!("E R/(pi D) = {v:.10} ± {err:.1e}, above it"),
                None => format!("no state ({})", c.note),
            };
            eprintln!(
                "warning: solve --branch {} at lbar = {x:.6} does not reach the diagram's lowest state ({e:.10} ± {de:.1e}): {found}",
                c.branch
            );
        }
    }
}

/// Write states/, the diagram's files in the result schema (branches.csv, critical.csv,
/// special_points.csv, summary.json) and diagram.svg/.png drawn from the staged tables; the
/// warnings of states without a file are printed and added to the schema's (their number is
/// returned).
pub(crate) fn write_outputs(
    schema: &mut rodloop_schema::Diagram,
    d: &(impl PointStates + ?Sized),
    engine: &EnclosedEngine,
    run: &OutputRun,
    width: u32,
    height: u32,
) -> Result<usize> {
    // Every point's loop in states/ (cli/states.rs), named in the last column.
    let state_warnings = crate::states::write_point_states(
        d,
        schema,
        engine.opts.radius,
        engine.opts.stiffness.reference(),
        run,
    )?;
    for w in &state_warnings {
        eprintln!("warning: {w}");
    }
    let written = state_warnings.len();
    let unverified = schema
        .points
        .iter()
        .filter(|p| p.state_file.as_deref().is_none_or(str::is_empty))
        .count();
    schema.put("unverified_states", &unverified)?;
    schema
        .warnings
        .get_or_insert_with(Vec::new)
        .extend(state_warnings);
    crate::output::write_diagram(run, schema)?;
    // The figure from the staged CSV files, as `rodloop draw` and `report` draw it (real
    // symbols, the lifted-off band, lift-off/landing and critical markers).
    let data = rodloop_figures::diagram::DiagramData::read(run.stage_dir())?;
    let text = rodloop_figures::diagram::energy_figure(&data, f64::from(width), f64::from(height))?;
    run.write_bytes("diagram.svg", text.as_bytes())?;
    let png = svg_to_png(&text, 1.0).context("rendering diagram.png")?;
    run.write_bytes("diagram.png", &png)?;
    Ok(written)
}

/// The printed result, every number from the schema `d` as written (whose last
/// `state_warnings` warnings, those of states without a file, were printed when the states
/// were written).
fn print(
    d: &rodloop_schema::Diagram,
    state_warnings: usize,
    scene: &Scene,
    engine: &EnclosedEngine,
    out: &Path,
) {
    outln!(
        "Critical lengths (enclosed scene {}, accuracy {:?}):",
        scene.name,
        engine.opts.accuracy
    );
    let side = rodloop_schema::SideColumn {
        header: "surface lbar_cr".into(),
        width: 18,
        cells: d
            .critical
            .iter()
            .map(|c| {
                c.surface_lbar_cr()
                    .map_or(String::new(), |x| format!("{x:.12}"))
            })
            .collect(),
    };
    for line in d.critical_table(Some(&side)) {
        outln!("{line}");
    }
    for e in d.special.iter().flatten() {
        let what = match e.kind.as_str() {
            "detachment" => "the last contact force is 0; below it the loop is free".to_string(),
            "branch_point" => format!(
                "family {}: the index changes {} -> {}",
                e.family,
                e.index_before.unwrap_or_default(),
                e.index_after.unwrap_or_default()
            ),
            _ => "lambda_min = 0".to_string(),
        };
        outln!(
            "  {} of branch {} at lbar = {:.12} ± {:.0e} ({what}; E R/(pi D) = {:.10})",
            e.kind,
            e.branch,
            e.lbar,
            e.error_estimate.unwrap_or_default(),
            e.energy
        );
    }
    for &(a, b) in d.lowest_lifted_off.iter().flatten() {
        outln!(
            "  the lowest state has lifted off the wall for {a:.9} < lbar < {b:.9} (the Sec. 3.2 hypothesis fails there)"
        );
    }
    for n in d.notes.iter().flatten() {
        eprintln!("note: {n}");
    }
    let warnings = d.warnings.as_deref().unwrap_or_default();
    for w in &warnings[..warnings.len().saturating_sub(state_warnings)] {
        eprintln!("warning: {w}");
    }
    outln!(
        "{} in {:.2} s; wrote branches.csv, critical.csv, special_points.csv, diagram.svg/.png, summary.json to {}",
        crate::output::plural(d.points.len() as u64, "state"),
        d.timings.as_ref().and_then(|t| t.get("total")).copied().unwrap_or_default(),
        out.display()
    );
}
