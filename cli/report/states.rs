//! The representative states of a surface report: one state per branch, where the diagram
//! finds it the lowest branch, solved as `rodloop solve` solves it, drawn, with its contact
//! force along the loop and its shape against the Euler curve.

use std::time::Instant;

use anyhow::{Context, Result};
use rodloop_diagram::{DiagramOptions, DiagramRow, Label, NumericDiagram};
use rodloop_figures::color::branch_color;
use rodloop_figures::data::LoopData;
use rodloop_figures::loops::{loop_picture, point_group, LoopPictureOptions};
use rodloop_figures::plot::{Plot, Series};
use rodloop_figures::svg::Svg;
use rodloop_scene::Scene;
use rodloop_solver::Accuracy;

use super::args::{middle, PANEL};
use super::page::{Entry, Solved};
use crate::output::checked_json;

/// Size of the force plot beside each loop picture, pixels.
const FORCE_W: f64 = 360.0;
/// Height of the force plot beside each loop picture, pixels.
const FORCE_H: f64 = 300.0;

/// A solved representative state with its picture.
pub(super) struct SolvedState {
    pub(super) energy: f64,
    pub(super) energy_error: f64,
    pub(super) index: usize,
    pub(super) label: &'static str,
    pub(super) lambda_range: (f64, f64),
    pub(super) lambda_error: f64,
    pub(super) cells: usize,
    /// Where the solve started.
    pub(super) start: String,
    pub(super) point_group: Option<String>,
    pub(super) self_contacts: usize,
    /// The loop picture (SVG).
    pub(super) picture: String,
    /// `λ(s)` along the loop (SVG).
    pub(super) force: String,
    /// `x, y, z, κ, τ, κ_g` along the loop with the aligned Euler curve (Fig. 5; SVG) and the
    /// largest distance between the two curves.
    pub(super) shape: Option<(String, f64)>,
    pub(super) seconds: f64,
}

impl Solved for SolvedState {
    fn seconds(&self) -> f64 {
        self.seconds
    }

    fn note(&self) -> Result<serde_json::Value> {
        checked_json!({
            "energy": self.energy, "energy_error": self.energy_error, "index": self.index,
            "state": self.label, "lambda_min": self.lambda_range.0,
            "lambda_max": self.lambda_range.1, "point_group": self.point_group,
            "self_contacts": self.self_contacts, "start": self.start, "seconds": self.seconds,
        })
    }
}

/// The widest stretch of lengths over which the diagram labels branch `branch` stable: the
/// stable rows of every branch in increasing `L̄`, split where another branch's stable row
/// comes between (a non-uniform rod's branch has several families, so the rows of the branch
/// alone interleave); the lengths of the first and last row of the widest run.
fn widest_stable_stretch(rows: &[DiagramRow], branch: u32) -> Option<(f64, f64)> {
    let mut stable: Vec<&DiagramRow> = rows
        .iter()
        .filter(|r| r.stability == Label::Stable)
        .collect();
    stable.sort_by(|a, b| a.lbar.total_cmp(&b.lbar));
    stable
        .chunk_by(|a, b| (a.branch == branch) == (b.branch == branch))
        .filter(|run| run[0].branch == branch)
        .map(|run| (run[0].lbar, run[run.len() - 1].lbar))
        .max_by(|a, b| (a.1 - a.0).total_cmp(&(b.1 - b.0)))
}

/// Solve branch `eta` at `lbar` from the Euler curve `l = η` (as `rodloop solve` does) or,
/// when that fails, from the diagram's own state of the branch there (re-solved at the tracing
/// resolution and passed on as points, as `solve --from` takes them); then draw it.
fn solve_state(
    scene: &Scene,
    accuracy: Accuracy,
    opts: &DiagramOptions,
    d: &NumericDiagram,
    branch: u32,
    eta: u32,
    lbar: f64,
) -> Result<SolvedState> {
    let t0 = Instant::now();
    let (res, start) =
        rodloop_diagram::representative::solve_on_branch(d, opts, accuracy, eta, lbar)?;
    let eq = &res.equilibrium;
    let index = eq.stability()?.index;
    let label = if index > 0 {
        "unstable"
    } else if d.lowest_at(lbar).contains(&branch) {
        "stable"
    } else {
        "metastable"
    };
    let profile = eq.profile();
    let table = crate::solve::config_table(&profile, scene)?;
    let source = format!("branch {branch} at L̄ = {lbar}");
    let data = LoopData::parse(&source, &table.to_bytes()?)?;
    let pic = loop_picture(
        &data,
        &LoopPictureOptions {
            // Uniform rods: the contact force; otherwise the stiffness (where the soft segment is).
            color: Some(
                if scene.stiffness.is_uniform() {
                    "lambda"
                } else {
                    "D"
                }
                .into(),
            ),
            tol: 1e-3,
            panel: PANEL,
            title: format!("Branch {branch} (η = {eta}) at L̄ = {lbar}: {label}"),
            // The contact force's extremes between the nodes, as the states table gives them.
            extremes: scene.stiffness.is_uniform().then(|| {
                let unit = scene.radius.powi(3) / scene.stiffness.reference();
                (res.lambda_range.0 * unit, res.lambda_range.1 * unit)
            }),
        },
    )?;
    let force = force_figure(&data, branch)?;
    let shape = crate::draw::euler_overlay(eta, lbar).and_then(|(o, label)| {
        let a = rodloop_figures::overlay::align(&data, &o).ok()?;
        let svg = rodloop_figures::profiles::profiles_figure_overlay(
            &data,
            Some((&a.data, &label)),
            480.0,
            240.0,
            &format!("Branch {branch} (η = {eta}) at L̄ = {lbar}: shape along the loop (Fig. 5)"),
        )
        .ok()?;
        Some((svg, a.max_distance))
    });
    let lam_unit = scene.radius.powi(3) / scene.stiffness.reference();
    Ok(SolvedState {
        energy: res.energy.total,
        energy_error: res.energy_error,
        index,
        label,
        lambda_range: (res.lambda_range.0 * lam_unit, res.lambda_range.1 * lam_unit),
        lambda_error: res.lambda_error * lam_unit,
        cells: profile.len(),
        start,
        point_group: point_group(&data, crate::draw::POINT_GROUP_TOL).map(|g| g.0),
        self_contacts: pic.contacts.len(),
        picture: pic.svg,
        force,
        shape,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

/// One representative state per traced branch: the middle of its first stable range in the
/// diagram, or of its traced range when it is never the lowest. The solves run in parallel.
pub(super) fn representative_states(
    scene: &Scene,
    accuracy: Accuracy,
    opts: &DiagramOptions,
    d: &NumericDiagram,
) -> Vec<Entry<SolvedState>> {
    let rows = d.rows();
    // One entry per branch (a non-uniform rod's branch is traced as several families and
    // sheets): its traced range is the union of theirs.
    let mut spans: std::collections::BTreeMap<u32, (u32, f64, f64)> = Default::default();
    for b in &d.branches {
        let (a, c) = b.span();
        let e = spans
            .entry(b.branch)
            .or_insert((b.eta, f64::INFINITY, f64::NEG_INFINITY));
        e.1 = e.1.min(a);
        e.2 = e.2.max(c);
    }
    let mut plan: Vec<(u32, u32, f64, String)> = spans
        .into_iter()
        .map(|(branch, (eta, lo, hi))| match widest_stable_stretch(&rows, branch) {
            Some((a, c)) if c > a => (
                branch,
                eta,
                middle(a, c),
                format!("middle of its widest stable stretch (traced states at {a:.4} ≤ L̄ ≤ {c:.4})"),
            ),
            Some((a, _)) => (
                branch,
                eta,
                a,
                format!("the one length where the diagram finds it the lowest branch (L̄ = {a:.4})"),
            ),
            None => (
                branch,
                eta,
                middle(lo, hi),
                format!("middle of its traced range {lo:.4} ≤ L̄ ≤ {hi:.4} (never the lowest branch there)"),
            ),
        })
        .collect();
    plan.sort_by_key(|p| p.0);
    let threads = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .min(plan.len().max(1));
    let next = std::sync::atomic::AtomicUsize::new(0);
    let mut results: Vec<Option<Result<SolvedState, String>>> =
        (0..plan.len()).map(|_| None).collect();
    let slots = std::sync::Mutex::new(&mut results);
    std::thread::scope(|scope| {
        for _ in 0..threads {
            scope.spawn(|| loop {
                let k = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                let Some((branch, eta, lbar, _)) = plan.get(k) else {
                    break;
                };
                let r = solve_state(scene, accuracy, opts, d, *branch, *eta, *lbar)
                    .map_err(|e| format!("{e:#}"));
                if let Ok(mut s) = slots.lock() {
                    s[k] = Some(r);
                }
            });
        }
    });
    plan.into_iter()
        .zip(results)
        .map(|((branch, eta, lbar, why), r)| Entry {
            branch,
            eta,
            lbar,
            why,
            outcome: r.unwrap_or_else(|| Err("the solve thread did not report".into())),
        })
        .collect()
}

/// The contact force `λR³/D0` against `s/L` along one state (the paper's Fig. 6), from the
/// `lambda` column of its loop table, closed at `s/L = 1`.
fn force_figure(data: &LoopData, branch: u32) -> Result<String> {
    let length = data.length();
    let s = data.s();
    let lam = data
        .column("lambda")
        .context("the loop table has no lambda column")?;
    let mut points: Vec<(f64, f64)> = s.iter().zip(lam).map(|(&a, &b)| (a / length, b)).collect();
    if let (Some(&s0), Some(&l0)) = (s.first(), lam.first()) {
        points.push((s0 / length + 1.0, l0));
    }
    let clip = rodloop_figures::plot::robust_range(
        lam,
        Some(&rodloop_figures::plot::arclength_weights(s, length)),
    );
    let mut plot = Plot {
        title: "Contact force along the loop".into(),
        xlabel: "s/L (s = 0 as marked on the loop)".into(),
        ylabel: "λR³/D₀".into(),
        series: vec![Series {
            color: branch_color(branch).to_string(),
            width: 2.0,
            dash: String::new(),
            points,
        }],
        hlines: vec![0.0],
        ..Default::default()
    };
    if let Some(shown) = clip {
        let (x0, x1) = plot.x_range();
        plot.range = Some((x0, x1, shown.0, shown.1));
        plot.note = rodloop_figures::plot::clipped_note("λ", lam, shown);
    }
    let mut svg = Svg::new(FORCE_W, FORCE_H);
    plot.render(&mut svg, 0.0, 0.0, FORCE_W, FORCE_H, "force");
    Ok(svg.finish())
}
