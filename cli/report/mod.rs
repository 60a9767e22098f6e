//! `rodloop report`: one self-contained HTML page with everything a run of the numeric
//! diagram produces: the energy diagram and its companions (Figs. 3a, 3b, 7), the critical
//! lengths with their error estimates (and, for homogeneous scenes, the exact values), the
//! comparison with the paper's printed values, `k²` against `L̄` with Eq. (B.4) (Fig. 11,
//! homogeneous scenes), the branch atlas (Figs. 2, 9, 10; [`crate::atlas`]), a picture and the
//! contact force `λ(s)` of the stable state of every branch at one length, the shape of the
//! first against its Euler curve (Fig. 5), the run's settings and its timings. The page builder
//! both kinds of scene share is `page.rs`, the representative states of this page `states.rs`
//! (where each branch is shown: [`rodloop_diagram::representative`]), the tables (the one
//! table markup, the critical lengths and special points of the diagram directory as
//! [`rodloop_schema::Diagram::read`] reads it back) and the style sheet `tables.rs`, the
//! arguments and page sizes `args.rs`, the page of an enclosed scene `enclosed.rs`.
//!
//! The page needs no network and no file beside it: every figure is an inline `<svg>`, the
//! style sheet is inline, there is no script and no external font (the figures name
//! DejaVu Sans with a generic sans-serif fallback). Nothing here recomputes what other
//! commands compute: the diagram comes from [`crate::diagram::surface::run_numeric`] and
//! [`crate::diagram::surface::write_outputs`], the figures from [`rodloop_figures`] (read back
//! from the staged `branches.csv`/`critical.csv`, as `rodloop draw` reads them), the paper
//! comparison from [`crate::compare::compare_rows`], the states from
//! [`rodloop_solver::solve_with_accuracy`] as `rodloop solve` calls it.

use std::fmt::Write as _;
use std::time::Instant;

use anyhow::{Context, Result};
use rodloop_diagram::DiagramOptions;
use rodloop_figures::diagram::{energy_figure, energy_split_figure, lambda_figure, DiagramData};
use rodloop_figures::svg::esc;

use crate::output::{checked_json, OutputRun};
mod args;
mod enclosed;
mod page;
mod states;
mod tables;

pub use args::Args;
use args::{ATLAS_SHAPES, FIG_H, FIG_W};
use page::Page;
use tables::{compare_html, critical_html, exact_cells, num, sci, td, HtmlTable};

/// Run the subcommand.
pub fn run(args: &Args) -> Result<()> {
    let t_start = Instant::now();
    let (scene, engine) = crate::engine::load(args.scene.as_deref())?;
    if engine == crate::engine::EngineKind::Enclosed {
        return enclosed::run(args, &scene);
    }
    let scene_text = match &args.scene {
        Some(p) => Some(
            std::fs::read_to_string(p).with_context(|| format!("cannot read {}", p.display()))?,
        ),
        None => None,
    };
    let accuracy = crate::args::accuracy_of(&scene, args.accuracy.as_deref())?;
    let opts = DiagramOptions {
        radius: scene.radius,
        stiffness: crate::args::stiffness_of(&scene.stiffness),
        lbar_min: scene.lbar_min,
        lbar_max: scene.lbar_max,
        accuracy,
        ..Default::default()
    };
    opts.validate()?;
    let run = OutputRun::begin(&args.out)?;

    // 1. The numeric diagram (branch files go to the staging directory and vanish with it).
    let t = Instant::now();
    let d = crate::diagram::surface::run_numeric(&opts, run.stage_dir(), false, args.quiet, None)?;
    crate::diagram::surface::write_outputs(&d, &opts, &scene.name, &run)?;
    // The page's tables from the diagram directory as the schema reads it back.
    let dir = rodloop_schema::Diagram::read(run.stage_dir())?;
    let t_diagram = t.elapsed().as_secs_f64();

    // 2. The diagram figures, from the staged CSV files as `rodloop draw` reads them.
    let t = Instant::now();
    let mut dd = DiagramData::read(run.stage_dir())?;
    dd.buckling_loads = scene.stiffness.is_uniform();
    let fig_energy = energy_figure(&dd, FIG_W, FIG_H)?;
    let fig_split = energy_split_figure(&dd, FIG_W, 480.0)?;
    let fig_lambda = lambda_figure(&dd, FIG_W, FIG_H)?;
    // The energy figure beside the tables, as `rodloop diagram` writes it.
    run.write_bytes("diagram.svg", fig_energy.as_bytes())?;
    let t_diagram_figures = t.elapsed().as_secs_f64();
    // The branch atlas from the staged state files (as `diagram --shapes` draws it).
    let t = Instant::now();
    let fig_atlas = crate::atlas::atlas_svg(run.stage_dir(), ATLAS_SHAPES, &scene.name)
        .map_err(|e| format!("{e:#}"));
    let t_atlas = t.elapsed().as_secs_f64();

    // 3. Exact critical lengths (homogeneous scenes) and the paper's values.
    let t = Instant::now();
    let uniform = scene.stiffness.is_uniform();
    let exact = if uniform {
        Some(crate::diagram::exact_window(
            opts.lbar_min,
            opts.lbar_max,
            0.01,
        )?)
    } else {
        None
    };
    let compare = crate::compare::compare_rows(uniform.then_some(&d))?;
    // Fig. 11 from the exact layer (homogeneous scenes).
    let fig_k2 = match &exact {
        Some(e) => Some(crate::diagram::k2_figure(e, FIG_W, 480.0)?),
        None => None,
    };
    let t_exact = t.elapsed().as_secs_f64();

    // 4. One state per branch, its picture and its contact force.
    let t = Instant::now();
    let states = states::representative_states(&scene, accuracy, &opts, &d);
    let t_states = t.elapsed().as_secs_f64();

    // 5. The page.
    let t = Instant::now();
    let mut page = Page::begin(
        &scene.name,
        &format!(
            "{desc}. Numeric branch diagram for {lo} ≤ L̄ ≤ {hi} at accuracy <b>{acc}</b>: {nstates} traced states on {nbranches}, {ncrit} critical lengths.",
            desc = esc(&d.scene),
            lo = opts.lbar_min,
            hi = opts.lbar_max,
            acc = format!("{accuracy:?}").to_lowercase(),
            nstates = dir.points.len(),
            nbranches = crate::diagram::surface::branch_count(&d.branches),
            ncrit = dir.critical.len(),
        ),
        &[
            ("diagram", "Diagram"),
            ("critical", "Critical lengths"),
            ("atlas", "Atlas"),
            ("states", "States"),
            ("paper", "Paper values"),
            ("settings", "Settings"),
            ("timings", "Timings"),
        ],
    );
    page.notes("warning", &d.warnings);

    page.h
        .push_str("<section id=\"diagram\">\n<h2>1. Energy against length</h2>\n");
    page.fig(
        &fig_energy,
        "bending energy against normalised length",
        "Bending energy E R/(πD₀) of every traced state against L̄ = L/(2πR) (paper Fig. 3a). One colour per branch; solid: stable (lowest energy), dashed: metastable (a local minimum with higher energy), dotted: unstable (Hessian index &gt; 0). Diamonds: crossings E<sub>a</sub> = E<sub>b</sub>; open squares: collapses onto an m-fold great circle.",
        "fig-energy",
    );
    page.fig(
        &fig_split,
        "geodesic and normal energy split",
        "The energy split E = E<sub>g</sub> + E<sub>n</sub> into its geodesic-curvature and normal-curvature parts (paper Fig. 3b).",
        "fig-split",
    );
    page.fig(
        &fig_lambda,
        "contact force extremes against length",
        &if uniform {
            "Largest and smallest contact force λR³/D₀ of every state (paper Fig. 7), with the great-circle buckling loads of Eqs. (33)–(34) at L̄ = m.".to_string()
        } else {
            "Largest and smallest contact force λR³/D₀ of every state (paper Fig. 7). The great-circle buckling loads of Eqs. (33)–(34) hold for a uniform rod only and are not marked. Where a few states have sharp force peaks at the stiffness steps, the axis shows the bulk of the values and the note under it gives the full range.".to_string()
        },
        "fig-lambda",
    );
    if let Some(k2) = &fig_k2 {
        page.fig(
            k2,
            "elliptic modulus against length",
            "k² of the exact loops of every branch against L̄ (paper Fig. 11), with the small-k² formula Eq. (B.4) dashed, evaluated with each branch's (η, p). The numeric model has no k; this figure is the exact layer's.",
            "fig-k2",
        );
    } else {
        page.h.push_str("<p class=\"note\" id=\"no-k2\">No k² figure (paper Fig. 11): the elliptic modulus k belongs to the closed-form loops of a uniform rod (Eq. (35)); this scene's stiffness is not uniform, so its loops have no k and Eq. (B.4) does not apply.</p>\n");
    }
    page.h.push_str("</section>\n");

    page.h.push_str("<section id=\"critical\">\n<h2>2. Critical lengths</h2>\n<p>Where the globally stable branch changes: crossings solve E<sub>a</sub>(L̄) = E<sub>b</sub>(L̄) on re-solved, Richardson-extrapolated equilibria; collapses are the lengths L̄ = m where the lowest branch ends on the m-fold great circle. Branch 0 is the planar circle below L̄ = 1. The error estimate is that of L̄<sub>cr</sub> itself.");
    if exact.is_some() {
        page.h.push_str(" For this homogeneous scene the exact layer (closed-form elliptic-function loops, error ≈ 1e−14) gives the exact values.");
    }
    page.h
        .push_str(" The same numbers are in <code>critical.csv</code>.</p>\n");
    let exact_heads: &[&str] = if exact.is_some() {
        &["exact L̄<sub>cr</sub>", "numeric − exact"]
    } else {
        &[]
    };
    page.h
        .push_str(&critical_html(&dir.critical, exact_heads, |c| {
            exact.as_ref().map_or(Vec::new(), |e| exact_cells(c, e))
        }));
    if let Some(gc) = &d.great_circles {
        let loads: Vec<_> = gc
            .loads
            .iter()
            .filter_map(|l| Some((l, l.lambda_formula?, l.equation.as_ref()?)))
            .collect();
        if !loads.is_empty() {
            page.h.push_str("<p>Buckling loads of the m-fold great circles, found numerically where the constrained Hessian becomes singular, against Eqs. (33)–(34):</p>\n");
            let mut t = HtmlTable::new(
                "buckling-table",
                &[
                    "m",
                    "mode (periods of κ<sub>g</sub>)",
                    "numeric λR³/D₀",
                    "error estimate",
                    "formula",
                    "value",
                ],
            );
            for (l, f, eq) in loads {
                t.row([
                    td(l.m),
                    td(l.mode_periods),
                    num(format!("{:.10}", l.lambda_numeric)),
                    num(sci(l.lambda_error)),
                    td(format!("Eq. ({})", esc(eq))),
                    num(format!("{f:.10}")),
                ]);
            }
            page.h.push_str(&t.finish());
        }
    }
    page.h.push_str("</section>\n");

    page.h
        .push_str("<section id=\"atlas\">\n<h2>3. Branch atlas</h2>\n");
    match &fig_atlas {
        Ok(svg) => page.fig(
            svg,
            "branch atlas: shapes along every branch",
            &format!("The traced states along every branch (one row per branch, or per family of a non-uniform rod), {ATLAS_SHAPES} per row spread evenly over its traced range (paper Figs. 2, 9, 10), each labelled with L̄, its stability and E R/(πD₀). Every traced state is in <code>states/</code> (column <code>state_file</code> of <code>branches.csv</code>); <code>rodloop diagram --shapes K</code> draws this atlas with K columns."),
            "fig-atlas",
        ),
        Err(e) => {
            let _ = writeln!(page.h, "<p class=\"note\">no atlas: {}</p>", esc(e));
        }
    }
    page.h.push_str("</section>\n");

    page.h.push_str("<section id=\"states\">\n<h2>4. The stable state of each branch</h2>\n<p>Each branch solved at one length (the middle of the widest stretch where the diagram finds it the lowest branch), from the Euler rotation curve with l = η at the report's accuracy, as <code>rodloop solve</code> does; the converged state's branch is checked from the periods of its κ<sub>g</sub>. Each picture shows the loop on the sphere from an oblique view and along the three axes, coloured by the contact force λR³/D₀ (uniform rods) or by the stiffness D/D₀ (other profiles); nearer strands are darker and thicker. Red circles: self-contacts in 3-D.</p>\n");
    page.states_table(
        &[
            "branch",
            "η",
            "L̄",
            "chosen as",
            "solved from",
            "E R/(πD₀)",
            "error",
            "index",
            "state",
            "λR³/D₀ range",
            "point group",
            "self-contacts",
            "cells",
        ],
        &states,
        |st, s| {
            vec![
                td(st.branch),
                td(st.eta),
                td(st.lbar),
                td(esc(&st.why)),
                td(esc(&s.start)),
                num(format!("{:.10}", s.energy)),
                num(sci(s.energy_error)),
                td(s.index),
                td(s.label),
                num(format!(
                    "[{:.6}, {:.6}] ± {}",
                    s.lambda_range.0,
                    s.lambda_range.1,
                    sci(s.lambda_error)
                )),
                td(s.point_group
                    .as_deref()
                    .map(esc)
                    .unwrap_or_else(|| "–".into())),
                td(s.self_contacts),
                td(s.cells),
            ]
        },
    );
    // Fig. 5 for the first solved state: its shape against the Euler curve.
    if let Some((st, (svg, dist))) = states.iter().find_map(|st| {
        st.outcome
            .as_ref()
            .ok()
            .and_then(|s| s.shape.as_ref())
            .map(|x| (st, x))
    }) {
        page.fig(
            svg,
            &format!("shape of branch {} against its Euler curve", st.branch),
            &format!(
                "Position, curvature, torsion and geodesic curvature along the loop of branch {} at L̄ = {} (solid) and the Euler rotation curve l = η of Eqs. (4)–(8) at the same length (dashed; paper Fig. 5), aligned by arclength shift, direction, mirror and rotation. The two curves are at most {:.3} R apart.",
                st.branch, st.lbar, dist
            ),
            "fig-shape",
        );
    }
    page.state_pictures(&states, |st, s| {
        [
            (
                format!("loop of branch {} at length {}", st.branch, st.lbar),
                format!(
                    "Branch {} (η = {}) at L̄ = {}: {}, E R/(πD₀) = {:.8} ± {}{}, {}.",
                    st.branch,
                    st.eta,
                    st.lbar,
                    s.label,
                    s.energy,
                    sci(s.energy_error),
                    s.point_group
                        .as_deref()
                        .map(|g| format!(", point group {}", esc(g)))
                        .unwrap_or_default(),
                    crate::output::plural(s.self_contacts as u64, "self-contact"),
                ),
            ),
            (
                format!("contact force along the loop of branch {}", st.branch),
                format!(
                    "Contact force λR³/D₀ along the loop of branch {} at L̄ = {} (paper Fig. 6): from {:.6} to {:.6} ± {}.",
                    st.branch,
                    st.lbar,
                    s.lambda_range.0,
                    s.lambda_range.1,
                    sci(s.lambda_error)
                ),
            ),
        ]
    });
    page.h.push_str("</section>\n");

    page.h.push_str("<section id=\"paper\">\n<h2>5. Comparison with the paper's printed values</h2>\n<p>Values printed in the paper (<code>data/reference/paper_values.csv</code>, with their sources), next to rodloop's. “Agrees” means within half a unit of the last printed digit (exact statements: within 1e−6).");
    if !uniform {
        page.h.push_str(" The paper's values are for homogeneous loops; this scene's stiffness is not uniform, so only the exact (homogeneous) layer is compared.");
    }
    page.h
        .push_str(" Winding numbers and symmetries are compared on the exact layer only.</p>\n");
    page.h.push_str(&compare_html(&compare, uniform));
    page.h.push_str("</section>\n");

    let t_page = t.elapsed().as_secs_f64();
    let total = t_start.elapsed().as_secs_f64();
    let settings = tables::Settings {
        number: 6,
        scene_name: &scene.name,
        scene_file: args.scene.as_deref(),
        extra: vec![
            ("description", esc(&d.scene)),
            ("sphere radius R", scene.radius.to_string()),
            (
                "length range",
                format!("{} ≤ L̄ ≤ {}", opts.lbar_min, opts.lbar_max),
            ),
        ],
        accuracy: (accuracy, args.accuracy.is_some()),
        units: "lengths in R, L̄ = L/(2πR), energies E R/(πD₀), contact force λR³/D₀ (D₀ = D for a uniform rod)",
        scene_text: scene_text.as_deref(),
    };
    let stages = [
        ("diagram: tracing the branches", d.timings.tracing),
        ("diagram: critical lengths", d.timings.critical),
        ("diagram: great circles", d.timings.great_circles),
        ("diagram total (with writing the CSV files)", t_diagram),
        ("diagram figures", t_diagram_figures),
        ("branch atlas", t_atlas),
        ("exact layer and paper comparison", t_exact),
    ];
    let times = [
        ("diagram", t_diagram),
        ("diagram_figures", t_diagram_figures),
        ("atlas", t_atlas),
        ("exact_and_paper", t_exact),
    ];
    let fields = checked_json!({
        "paper_disagreements_exact": compare.iter().filter(|r| r.agrees_exact == Some(false)).count(),
        "paper_disagreements_numeric": compare.iter().filter(|r| r.agrees_numeric == Some(false)).count(),
    })?;
    let (bytes, figures, failed) = page.finish(
        run, &settings, &stages, &times, &states, t_states, t_page, total, fields,
    )?;
    outln!(
        "wrote report.html ({} KB, {} figures: diagram, energy split, lambda extremes, {}branch atlas, shape against the Euler curve, {} with their force plots), branches.csv, critical.csv, special_points.csv, diagram.svg, summary.json, states/ to {} in {:.2} s",
        bytes.div_ceil(1024),
        figures,
        if fig_k2.is_some() { "k² (Fig. 11), " } else { "" },
        crate::output::plural((states.len() - failed) as u64, "loop picture"),
        args.out.display(),
        t_start.elapsed().as_secs_f64()
    );
    Ok(())
}
