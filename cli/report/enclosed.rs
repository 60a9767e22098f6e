//! `rodloop report` for enclosed scenes (`|r| ≤ R`, paper Sec. 3.2): the same one-page HTML
//! report as [`crate::report`], built on the enclosed diagram
//! ([`rodloop_diagram::enclosed`], written as `rodloop diagram` writes it by
//! [`crate::diagram::enclosed::write_outputs`]): the energy diagram with its lifted-off parts
//! and the lift-off / landing events, the critical lengths with their error estimates next to
//! the surface values, the lengths where the lowest state has lifted off the wall (where the
//! Sec. 3.2 hypothesis fails), the branch atlas (states re-solved along each branch,
//! [`crate::atlas::enclosed_rows`]), one state per branch solved as `rodloop solve` solves it
//! ([`crate::enclosed::solve_state`]) and drawn coloured by its gap to the wall (by `λ` where it
//! is attached), the settings and the timings.

use std::fmt::Write as _;
use std::time::Instant;

use anyhow::{Context, Result};
use rodloop_diagram::representative::{enclosed_choices, Choice};
use rodloop_diagram::{EnclosedEngine, Engine};
use rodloop_figures::atlas::atlas_figure;
use rodloop_figures::color::branch_color;
use rodloop_figures::data::LoopData;
use rodloop_figures::diagram::{energy_figure, DiagramData};
use rodloop_figures::loops::{loop_picture, point_group, LoopPictureOptions};
use rodloop_figures::profiles::{along_loop_figure, AlongLoop};
use rodloop_figures::svg::esc;
use rodloop_scene::Scene;
use rodloop_solver::Accuracy;

use super::args::{Args, ATLAS_SHAPES, FIG_H, FIG_W, PANEL};
use super::page::{Entry, Page};
use super::tables::{critical_html, num, sci, special_html, td};
use crate::output::{checked_json, OutputRun};

/// A solved state with its pictures.
struct Solved {
    energy: (f64, f64),
    surface: Option<(f64, f64)>,
    index: usize,
    label: &'static str,
    max_gap: f64,
    contact_fraction: f64,
    lambda_min: f64,
    method: String,
    point_group: Option<String>,
    picture: String,
    color: &'static str,
    profile: String,
    seconds: f64,
}

/// `λ(s)` and, for a loop off the wall somewhere, the gap `(R − |r|)/R` along the loop.
fn profile_figure(data: &LoopData, branch: u32, lifted: bool) -> Result<String> {
    let force = AlongLoop {
        column: "lambda",
        title: "Contact force along the loop",
        ylabel: "λR³/D₀",
        id: "force",
        clip: None,
    };
    let gap = AlongLoop {
        column: "gap",
        title: "Gap to the wall along the loop",
        ylabel: "gap (R − |r|)/R",
        id: "gap",
        clip: None,
    };
    let panels = if lifted {
        vec![force, gap]
    } else {
        vec![force]
    };
    Ok(along_loop_figure(
        data,
        &panels,
        branch_color(branch),
        (380.0, 300.0),
    )?)
}

impl super::page::Solved for Solved {
    fn seconds(&self) -> f64 {
        self.seconds
    }

    fn pictures(&self) -> (&str, &str) {
        (&self.picture, &self.profile)
    }

    fn note(&self) -> Result<serde_json::Value> {
        checked_json!({
            "energy": self.energy.0, "energy_error": self.energy.1,
            "surface_energy": self.surface.map(|x| x.0),
            "surface_lambda_min": self.surface.map(|x| x.1), "index": self.index,
            "state": self.label, "contact_fraction": self.contact_fraction,
            "max_gap": self.max_gap, "lambda_min": self.lambda_min,
            "point_group": self.point_group, "colour": self.color, "method": self.method,
            "seconds": self.seconds,
        })
    }
}

/// Branch `choice.branch` solved at `choice.lbar` as `rodloop solve` solves it, and drawn.
fn solve_one(scene: &Scene, accuracy: Accuracy, choice: &Choice) -> Result<Solved> {
    let t0 = Instant::now();
    let (branch, eta, lbar) = (choice.branch, choice.eta, choice.lbar);
    let stiffness = crate::args::stiffness_of(&scene.stiffness);
    let res = crate::enclosed::solve_state(scene, &stiffness, lbar, branch, accuracy)?;
    let table = crate::states::result_table(&res, scene.radius, scene.stiffness.reference())?;
    let data = LoopData::parse(
        &format!("branch {branch} at L̄ = {lbar}"),
        &table.to_bytes()?,
    )?;
    let index = res.stability.0;
    let label = choice.label(index);
    let lifted = data.lifted_off();
    let color = if lifted { "gap" } else { "lambda" };
    let wall = data.wall_contact();
    let pic = loop_picture(
        &data,
        &LoopPictureOptions {
            color: Some(color.into()),
            tol: 1e-3,
            panel: PANEL,
            title: format!(
                "Branch {branch} (η = {eta}) at L̄ = {lbar}: {label}, {}",
                if lifted {
                    "lifted off the wall"
                } else {
                    "on the wall"
                }
            ),
            extremes: None,
        },
    )?;
    Ok(Solved {
        energy: res.energy,
        surface: res.surface,
        index,
        label,
        max_gap: wall.max_gap,
        contact_fraction: wall.contact_fraction,
        lambda_min: wall.lambda_min,
        method: res.method,
        point_group: point_group(&data, crate::draw::POINT_GROUP_TOL).map(|g| g.0),
        picture: pic.svg,
        color,
        profile: profile_figure(&data, branch, lifted)?,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

/// Run `rodloop report` on an enclosed scene.
pub fn run(args: &Args, scene: &Scene) -> Result<()> {
    let t_start = Instant::now();
    let scene_text = match &args.scene {
        Some(p) => Some(
            std::fs::read_to_string(p).with_context(|| format!("cannot read {}", p.display()))?,
        ),
        None => None,
    };
    let accuracy = crate::args::accuracy_of(scene, args.accuracy.as_deref())?;
    let mut engine = EnclosedEngine::new(
        crate::engine::wall_of(scene),
        crate::args::stiffness_of(&scene.stiffness),
        scene.lbar_min,
        scene.lbar_max,
    );
    engine.opts.accuracy = accuracy;
    let opts = engine.opts.clone();
    let run = OutputRun::begin(&args.out)?;

    // 1. The enclosed diagram, written as `rodloop diagram` writes it.
    let t = Instant::now();
    if !args.quiet {
        eprintln!(
            "tracing the enclosed diagram ({} ≤ L̄ ≤ {})",
            opts.lbar_min, opts.lbar_max
        );
    }
    let d = engine.run(&mut |_| {}).context("the enclosed diagram")?;
    let mut schema = engine.schema(&d, &scene.name)?;
    let (w, h) = crate::diagram::FIGURE_SIZE;
    let state_warnings =
        crate::diagram::enclosed::write_outputs(&mut schema, &d, &engine, &run, w, h)?;
    // The page's tables from the diagram directory as the schema reads it back.
    let dir = rodloop_schema::Diagram::read(run.stage_dir())?;
    let lifted = schema.lowest_lifted_off.clone().unwrap_or_default();
    let t_diagram = t.elapsed().as_secs_f64();

    // 2. The diagram figure, from the staged CSV files as `rodloop draw` reads them.
    let t = Instant::now();
    let dd = DiagramData::read(run.stage_dir())?;
    let fig_energy = energy_figure(&dd, FIG_W, FIG_H)?;
    let t_figures = t.elapsed().as_secs_f64();

    // 3. The atlas: states re-solved along each branch (into states/).
    let t = Instant::now();
    let states_dir = run.subdir("states")?;
    let atlas =
        crate::atlas::enclosed_rows(scene, accuracy, &schema, ATLAS_SHAPES, Some(&states_dir))
            .and_then(|(rows, note, failed)| {
                let svg = atlas_figure(
                    &rows,
                    crate::atlas::CELL,
                    &format!("Branch atlas ({}): shapes along each branch", scene.name),
                )?;
                Ok((svg, note, failed))
            })
            .map_err(|e| format!("{e:#}"));
    let t_atlas = t.elapsed().as_secs_f64();

    // 4. One state per branch.
    let t = Instant::now();
    let states = Entry::solve_all(enclosed_choices(&schema), |c| solve_one(scene, accuracy, c));
    let t_states = t.elapsed().as_secs_f64();

    // 5. The page.
    let t = Instant::now();
    let mut page = Page::begin(
        &scene.name,
        &format!(
            "Homogeneous loops enclosed in the ball |r| ≤ R (paper Sec. 3.2): a loop may leave the wall where the wall would have to pull. Enclosed branch diagram for {lo} ≤ L̄ ≤ {hi} at accuracy <b>{acc}</b>: {nstates} states on {nbranches} branches, {ncrit} critical lengths, {nev}.",
            lo = opts.lbar_min,
            hi = opts.lbar_max,
            acc = format!("{accuracy:?}").to_lowercase(),
            nstates = dir.points.len(),
            nbranches = dir.points.iter().map(|p| p.branch).collect::<std::collections::BTreeSet<_>>().len(),
            ncrit = dir.critical.len(),
            nev = crate::output::plural(schema.special.as_ref().map_or(0, Vec::len) as u64, "special point"),
        ),
        &[
            ("diagram", "Diagram"),
            ("critical", "Critical lengths"),
            ("atlas", "Atlas"),
            ("states", "States"),
            ("settings", "Settings"),
            ("timings", "Timings"),
        ],
    );
    // The engine's warnings (those of states without a file were printed as they were
    // written).
    let warnings = schema.warnings.as_deref().unwrap_or_default();
    page.notes(
        "warning",
        &warnings[..warnings.len().saturating_sub(state_warnings)],
    );
    page.notes("note", schema.notes.as_deref().unwrap_or_default());
    page.h
        .push_str("<section id=\"diagram\">\n<h2>1. Energy against length</h2>\n");
    page.fig(
        &fig_energy,
        "bending energy of the enclosed loops against normalised length",
        "Bending energy E R/(πD₀) of every sampled state against L̄ = L/(2πR) (the enclosed counterpart of Fig. 3a). One colour per branch; solid: stable (lowest energy, Hessian index 0 on the tangent space of the active constraints), dashed: metastable, dotted: unstable. The light band marks states that have lifted off the wall (somewhere R − |r| &gt; 0); elsewhere the loop is the surface loop of the exact layer. Diamonds: exchanges E<sub>a</sub> = E<sub>b</sub>; open squares: collapses onto an m-fold great circle; circles: lift-off and landing (λ<sub>min</sub> = 0, Eq. (38)), detachment (the last contact force vanishes) and branch points (the index of a lifted-off sheet changes).",
        "fig-energy",
    );
    page.h.push_str("</section>\n");

    critical_section(&mut page, &dir, &lifted);

    page.h
        .push_str("<section id=\"atlas\">\n<h2>3. Branch atlas</h2>\n");
    match &atlas {
        Ok((svg, _, failed)) => {
            page.fig(
                svg,
                "branch atlas: shapes along every branch",
                &format!("{ATLAS_SHAPES} states per branch spread over its sampled range, each solved again as <code>rodloop solve</code> solves it and saved in <code>states/</code> (enclosed <code>config.csv</code> columns, with <code>gap</code>); parts off the wall in amber. Labels: L̄, the diagram's stability label and E R/(πD₀). <code>rodloop diagram --shapes K</code> draws this atlas with K columns."),
                "fig-atlas",
            );
            for f in failed {
                let _ = writeln!(
                    page.h,
                    "<p class=\"note\">atlas: not solved: {}</p>",
                    esc(f)
                );
            }
        }
        Err(e) => {
            let _ = writeln!(page.h, "<p class=\"note\">no atlas: {}</p>", esc(e));
        }
    }
    page.h.push_str("</section>\n");

    states_section(&mut page, &states);

    let t_page = t.elapsed().as_secs_f64();
    let total = t_start.elapsed().as_secs_f64();
    let settings = super::tables::Settings {
        number: 5,
        scene_name: &scene.name,
        scene_file: args.scene.as_deref(),
        extra: vec![
            ("confinement", "enclosed, |r| ≤ R".into()),
            ("sphere radius R", scene.radius.to_string()),
            (
                "length range",
                format!(
                    "{} ≤ L̄ ≤ {}, sampled every {}",
                    opts.lbar_min, opts.lbar_max, opts.step
                ),
            ),
            (
                "cells of the lifted-off traces",
                schema
                    .get::<Vec<(u32, usize)>>("cells")
                    .unwrap_or_default()
                    .iter()
                    .map(|(b, n)| format!("branch {b}: N = {n}"))
                    .collect::<Vec<_>>()
                    .join(", "),
            ),
        ],
        accuracy: (accuracy, args.accuracy.is_some()),
        units: "lengths and gaps in R, L̄ = L/(2πR), energies E R/(πD₀), contact force λR³/D₀",
        scene_text: scene_text.as_deref(),
    };
    let stages = [
        ("enclosed diagram (with writing the CSV files)", t_diagram),
        ("diagram figure", t_figures),
        ("branch atlas (states re-solved)", t_atlas),
    ];
    let times = [
        ("diagram", t_diagram),
        ("diagram_figures", t_figures),
        ("atlas", t_atlas),
    ];
    let fields = checked_json!({
        "lowest_lifted_off": lifted,
        "atlas_rows": atlas.as_ref().ok().map(|(_, note, _)| note.rows.iter().map(|(b, _, c)| serde_json::json!({"branch": b, "lbar": c.iter().map(|x| x.0).collect::<Vec<_>>(), "state_files": c.iter().map(|x| x.1.clone()).collect::<Vec<_>>()})).collect::<Vec<_>>()),
    })?;
    let (bytes, figures, failed) = page.finish(
        run, &settings, &stages, &times, &states, t_states, t_page, total, fields,
    )?;
    outln!(
        "wrote report.html ({} KB, {} figures: enclosed diagram, branch atlas, {} with their force and gap plots), branches.csv, critical.csv, special_points.csv, diagram.svg/.png, summary.json, states/ to {} in {:.2} s",
        bytes.div_ceil(1024),
        figures,
        crate::output::plural((states.len() - failed) as u64, "loop picture"),
        args.out.display(),
        t_start.elapsed().as_secs_f64()
    );
    Ok(())
}

/// Section 2 of the enclosed page: the critical lengths of the diagram directory `dir`, its
/// special points and the stretches where the lowest state has lifted off (`lifted`).
fn critical_section(page: &mut Page, dir: &rodloop_schema::Diagram, lifted: &[(f64, f64)]) {
    page.h.push_str("<section id=\"critical\">\n<h2>2. Critical lengths and lift-off</h2>\n<p>Where the lowest branch changes. An exchange between two attached states is the surface one (exact layer); where one of the two has lifted off, E<sub>a</sub> = E<sub>b</sub> is solved again on re-solved 3-D states, with the error estimate of L̄<sub>cr</sub> itself. The same numbers are in <code>critical.csv</code>; the surface value is the surface diagram's.</p>\n");
    page.h.push_str(&critical_html(
        &dir.critical,
        &["surface L̄<sub>cr</sub>", "enclosed − surface", "method"],
        |c| {
            let surface = c.extra.get("surface_lbar_cr").and_then(|v| v.as_f64());
            vec![
                num(surface.map_or("–".into(), |x| format!("{x:.12}"))),
                num(surface.map_or("–".into(), |x| sci(c.lbar_cr - x))),
                td(esc(c
                    .extra
                    .get("method")
                    .and_then(|v| v.as_str())
                    .unwrap_or("–"))),
            ]
        },
    ));
    let special = dir.special.as_deref().unwrap_or_default();
    if special.is_empty() {
        page.h
            .push_str("<p>No branch lifts off or lands inside the range.</p>\n");
    } else {
        page.h.push_str("<p>Special points (<code>special_points.csv</code>). Lift-off and landing: where λ<sub>min</sub> of a branch's surface loop crosses zero, i.e. k²(L̄) = 1/2 (Eq. (38)) for a uniform rod, bisected on the exact layer (located on re-solved surface states for a two-segment rod). Detachment: where the last contact force of a lifted-off branch vanishes and the loop leaves the wall (below it the loop is free). Branch point: where the Hessian index of a lifted-off sheet changes, at the interpolated root of the crossing eigenvalue.</p>\n");
        page.h.push_str(&special_html(special));
    }
    if lifted.is_empty() {
        page.h.push_str("<p id=\"lifted-off\">The lowest state of a paper branch lies on the wall at every sampled length: the Sec. 3.2 hypothesis (stable loops with L̄ ≥ 1 stay on the surface) holds in this range.</p>\n");
    } else {
        page.h
            .push_str("<p id=\"lifted-off\">The lowest state has <b>lifted off the wall</b> for ");
        let parts: Vec<String> = lifted
            .iter()
            .map(|(a, b)| format!("<span class=\"num\">{a:.9} &lt; L̄ &lt; {b:.9}</span>"))
            .collect();
        page.h.push_str(&parts.join(", "));
        page.h.push_str(" (ends: the critical lengths and events above, with their error estimates): the Sec. 3.2 hypothesis fails there.</p>\n");
    }
    page.h.push_str("</section>\n");
}

/// Section 4 of the enclosed page: the representative state of each branch and its pictures.
fn states_section(page: &mut Page, states: &[Entry<Solved>]) {
    page.h.push_str("<section id=\"states\">\n<h2>4. One state of each branch</h2>\n<p>Each branch solved at one length as <code>rodloop solve</code> solves it: the exact surface loop where its λ ≥ 0 (then it is the enclosed equilibrium; the 3-D model re-solves it as a check), else the 3-D enclosed model from it (energy error from the cascade's last three or four levels, as its method says). A loop that has lifted off is coloured by its gap (R − |r|)/R, one on the wall by its contact force λR³/D₀; nearer strands are darker and thicker; red circles: self-contacts in 3-D.</p>\n");
    page.states_table(
        &[
            "branch",
            "η",
            "L̄",
            "chosen as",
            "E R/(πD₀)",
            "error",
            "surface E",
            "surface λ<sub>min</sub>R³/D₀",
            "index",
            "state",
            "on the wall",
            "max gap / R",
            "point group",
            "method",
        ],
        states,
        |st, s| {
            let (se, sl) = s
                .surface
                .map(|(e, l)| (format!("{e:.10}"), format!("{l:.6}")))
                .unwrap_or_else(|| ("–".into(), "–".into()));
            vec![
                td(st.branch),
                td(st.eta),
                td(st.lbar),
                td(esc(&st.why)),
                num(format!("{:.10}", s.energy.0)),
                num(sci(s.energy.1)),
                num(se),
                num(sl),
                td(s.index),
                td(s.label),
                num(format!("{:.1} %", 100.0 * s.contact_fraction)),
                num(sci(s.max_gap)),
                td(s.point_group
                    .as_deref()
                    .map(esc)
                    .unwrap_or_else(|| "–".into())),
                td(esc(&s.method)),
            ]
        },
    );
    page.state_pictures(states, |st, s| {
        [
            (
                format!("loop of branch {} at length {}", st.branch, st.lbar),
                format!(
                    "Branch {} (η = {}) at L̄ = {}: {}, E R/(πD₀) = {:.8} ± {}, coloured by {}; {:.1} % of the nodes on the wall, largest gap {} R.",
                    st.branch,
                    st.eta,
                    st.lbar,
                    s.label,
                    s.energy.0,
                    sci(s.energy.1),
                    if s.color == "gap" {
                        "the gap (R − |r|)/R"
                    } else {
                        "the contact force λR³/D₀"
                    },
                    100.0 * s.contact_fraction,
                    sci(s.max_gap)
                ),
            ),
            (
                format!("contact force and gap along the loop of branch {}", st.branch),
                format!(
                    "Contact force λR³/D₀{} along the loop of branch {} at L̄ = {} (smallest λ {:.6}; the wall only pushes, λ ≥ 0, and λ = 0 wherever the loop is off the wall).",
                    if s.color == "gap" { " and gap (R − |r|)/R" } else { "" },
                    st.branch,
                    st.lbar,
                    s.lambda_min
                ),
            ),
        ]
    });
    page.h.push_str("</section>\n");
}
