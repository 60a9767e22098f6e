//! `rodloop diagram` for enclosed scenes (`|r| ≤ R`, paper Sec. 3.2): the
//! engine is `rodloop_diagram::enclosed` (attached parts from the exact layer, lifted-off
//! parts from the 3-D model, events where `λ_min` crosses zero, exchanges re-solved where a
//! branch has lifted off); non-uniform rods from their surface families.

use std::path::Path;

use anyhow::{bail, Context, Result};
use rodloop_diagram::enclosed::{EnclosedDiagram, EnclosedDiagramOptions, EnclosedProgress};
use rodloop_diagram::engine::lowest_lifted_off;
use rodloop_diagram::{EnclosedEngine, Engine};
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
    let mut opts = EnclosedDiagramOptions::new(
        crate::engine::wall_of(scene),
        crate::args::stiffness_of(&scene.stiffness),
        lbar_min,
        lbar_max,
    );
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
    let mut engine = EnclosedEngine { opts };
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
    let opts = &engine.opts;
    // The completeness certificate (the same search `solve` runs) goes into summary.json.
    let cert = certificate(&d, scene, opts);
    let mut schema = engine.schema(&d, &scene.name)?;
    schema.set_certificate(&cert)?;
    write_outputs(&mut schema, &d, opts, &run, args.width, args.height)?;
    if args.shapes > 0 {
        // The branch atlas (cli/atlas.rs): states re-solved along each branch, in states/.
        crate::atlas::write_enclosed_atlas(&run, args.shapes, scene, accuracy, &d)?;
    }
    run.commit()?;
    print(&schema, &d, scene, opts, &args.out);
    print_certificate(&cert);
    Ok(())
}

/// One check of the completeness certificate: `solve`'s state of a branch at the length
/// of a lowest state of the diagram.
#[derive(Clone, Debug, serde::Serialize)]
pub(crate) struct CertificateCheck {
    /// `L̄` (that of the diagram's lowest state).
    lbar: f64,
    /// The branch `solve` was asked for.
    branch: u32,
    /// `solve`'s energy and error estimate (`None` where it found no state).
    solve_energy: Option<(f64, f64)>,
    /// The diagram's lowest state there: branch, family, energy, error estimate.
    lowest: (u32, u32, f64, f64),
    /// `solve`'s state lies below the lowest state by more than the two estimates.
    below: bool,
    /// Why `solve` found no state (empty otherwise).
    note: String,
}

/// Lowest states at which the certificate runs `solve`: three, spread over the range.
const CERTIFICATE_SAMPLES: usize = 3;

/// The completeness certificate of a non-uniform rod's diagram: at the lengths of
/// [`CERTIFICATE_SAMPLES`] lowest states of the diagram spread over its range, `solve`'s
/// search (surface loop of each branch that exists there, then the enclosed loop from it,
/// cli/enclosed.rs) for every selected branch; a state of `solve` below the diagram's lowest
/// one by more than the two error estimates is a state the diagram missed. (A uniform rod's
/// diagram and `solve` start from the same exact surface loops: no check there.)
fn certificate(
    d: &EnclosedDiagram,
    scene: &Scene,
    opts: &EnclosedDiagramOptions,
) -> Vec<CertificateCheck> {
    if opts.stiffness.is_uniform() {
        return Vec::new();
    }
    let mut lowest: Vec<_> = d
        .points
        .iter()
        .filter(|p| p.lowest && p.branch > 0)
        .collect();
    lowest.sort_by(|a, b| a.lbar.total_cmp(&b.lbar));
    if lowest.is_empty() {
        return Vec::new();
    }
    let n = lowest.len();
    let mut picks: Vec<usize> = (0..CERTIFICATE_SAMPLES)
        .map(|i| ((2 * i + 1) * n / (2 * CERTIFICATE_SAMPLES)).min(n - 1))
        .collect();
    picks.dedup();
    let wanted = |b: u32| opts.branches.as_ref().is_none_or(|s| s.contains(&b));
    let mut jobs = Vec::new();
    for &i in &picks {
        let p = lowest[i];
        let top = p.lbar.floor() as u32 + 1;
        for eta in 1..=top {
            let e = f64::from(eta);
            let branch = rodloop_exact::branch_of_eta(eta);
            if p.lbar > e - 1.0 && p.lbar < e + 1.0 && wanted(branch) {
                jobs.push((p, branch));
            }
        }
    }
    let stiffness = opts.stiffness.clone();
    crate::states::parallel_map(&jobs, |&(p, branch)| {
        let lowest = (p.branch, p.family, p.energy, p.energy_error);
        match crate::enclosed::solve_state(scene, &stiffness, p.lbar, branch, opts.accuracy) {
            Ok(res) => {
                let (e, err) = res.energy;
                CertificateCheck {
                    lbar: p.lbar,
                    branch,
                    solve_energy: Some((e, err)),
                    lowest,
                    below: e + err < p.energy - p.energy_error,
                    note: String::new(),
                }
            }
            Err(e) => CertificateCheck {
                lbar: p.lbar,
                branch,
                solve_energy: None,
                lowest,
                below: false,
                note: format!("{e:#}"),
            },
        }
    })
}

/// One line per length of the certificate, a warning per state below the diagram's.
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
    }
}

/// Write states/, the diagram's files in the result schema (branches.csv, critical.csv,
/// special_points.csv, summary.json) and diagram.svg/.png drawn from the staged tables.
pub(crate) fn write_outputs(
    schema: &mut rodloop_schema::Diagram,
    d: &EnclosedDiagram,
    opts: &EnclosedDiagramOptions,
    run: &OutputRun,
    width: u32,
    height: u32,
) -> Result<()> {
    // Every point's loop in states/ (cli/states.rs), named in the last column.
    let (state_files, state_warnings) =
        crate::states::write_enclosed_states(d, opts.radius, opts.stiffness.reference(), run)?;
    for w in &state_warnings {
        eprintln!("warning: {w}");
    }
    let unverified = state_files.iter().filter(|f| f.is_empty()).count();
    schema.put("unverified_states", &unverified)?;
    for (p, file) in schema.points.iter_mut().zip(state_files) {
        p.state_file = Some(file);
    }
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
    Ok(())
}

fn print(
    schema: &rodloop_schema::Diagram,
    d: &EnclosedDiagram,
    scene: &Scene,
    opts: &EnclosedDiagramOptions,
    out: &Path,
) {
    outln!(
        "Critical lengths (enclosed scene {}, accuracy {:?}):",
        scene.name,
        opts.accuracy
    );
    let surface: Vec<f64> = d.critical.iter().map(|e| e.surface_lbar_cr).collect();
    let side = rodloop_schema::SideColumn::fixed("surface lbar_cr", 18, 12, &surface);
    for line in schema.critical_table(Some(&side)) {
        outln!("{line}");
    }
    for e in &d.events {
        use rodloop_diagram::enclosed::EventKind;
        let what = match e.kind {
            EventKind::Detachment => {
                "the last contact force is 0; below it the loop is free".to_string()
            }
            EventKind::BranchPoint => format!(
                "family {}: the index changes {} -> {}",
                e.family, e.index_before, e.index_after
            ),
            _ => "lambda_min = 0".to_string(),
        };
        outln!(
            "  {} of branch {} at lbar = {:.12} ± {:.0e} ({what}; E R/(pi D) = {:.10})",
            e.kind.as_str(),
            e.branch,
            e.lbar,
            e.error_estimate,
            e.energy
        );
    }
    let verdict = if opts.branches.is_none() {
        lowest_lifted_off(d)
    } else {
        Vec::new()
    };
    for (a, b) in verdict {
        outln!(
            "  the lowest state has lifted off the wall for {a:.9} < lbar < {b:.9} (the Sec. 3.2 hypothesis fails there)"
        );
    }
    for n in &d.notes {
        eprintln!("note: {n}");
    }
    for w in &d.warnings {
        eprintln!("warning: {w}");
    }
    outln!(
        "{} in {:.2} s; wrote branches.csv, critical.csv, special_points.csv, diagram.svg/.png, summary.json to {}",
        crate::output::plural(d.points.len() as u64, "state"),
        d.seconds.total,
        out.display()
    );
}
