//! The representative states of a surface report: one state per branch, where the diagram
//! finds it the lowest branch, solved as `rodloop solve` solves it, drawn, with its contact
//! force along the loop and its shape against the Euler curve.

use std::time::Instant;

use anyhow::Result;
use rodloop_diagram::representative::{Choice, Representatives};
use rodloop_diagram::DiagramOptions;
use rodloop_figures::color::branch_color;
use rodloop_figures::data::LoopData;
use rodloop_figures::loops::{loop_picture, point_group, LoopPictureOptions};
use rodloop_figures::profiles::{along_loop_figure, AlongLoop};
use rodloop_scene::Scene;
use rodloop_solver::Accuracy;

use super::args::PANEL;
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

    fn pictures(&self) -> (&str, &str) {
        (&self.picture, &self.force)
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

/// Solve branch `eta` at `lbar` from the Euler curve `l = η` (as `rodloop solve` does) or,
/// when that fails, from the diagram's own state of the branch there (re-solved at the tracing
/// resolution and passed on as points, as `solve --from` takes them); then draw it.
fn solve_state(
    scene: &Scene,
    accuracy: Accuracy,
    opts: &DiagramOptions,
    d: &(impl Representatives + ?Sized),
    choice: &Choice,
) -> Result<SolvedState> {
    let t0 = Instant::now();
    let (branch, eta, lbar) = (choice.branch, choice.eta, choice.lbar);
    let (res, start) = d.solve_on_branch(opts, accuracy, eta, lbar)?;
    let eq = &res.equilibrium;
    let index = eq.stability()?.index;
    let label = choice.label(index);
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

/// One representative state per traced branch, where
/// [`Representatives::choices`] shows it; the solves run in parallel.
pub(super) fn representative_states(
    scene: &Scene,
    accuracy: Accuracy,
    opts: &DiagramOptions,
    d: &(impl Representatives + ?Sized),
) -> Vec<Entry<SolvedState>> {
    Entry::solve_all(d.choices(), |c| solve_state(scene, accuracy, opts, d, c))
}

/// The contact force `λR³/D0` against `s/L` along one state (the paper's Fig. 6), closed at
/// `s/L = 1`, its bulk shown where a few sharp peaks stand out.
fn force_figure(data: &LoopData, branch: u32) -> Result<String> {
    Ok(along_loop_figure(
        data,
        &[AlongLoop {
            column: "lambda",
            title: "Contact force along the loop",
            ylabel: "λR³/D₀",
            id: "force",
            clip: Some("λ"),
        }],
        branch_color(branch),
        (FORCE_W, FORCE_H),
    )?)
}
