//! One interface for every diagram engine, and the one translation of each engine's result
//! into the result schema ([`rodloop_schema::Diagram`]).
//!
//! The file is one job, the translation of each engine's result into the schema: the three
//! engines and their `schema` methods share `columns`, `critical_of` and the axis of `L̄`,
//! and are read side by side, so they stay together.
//!
//! Every engine runs the same pipeline, in these steps:
//!
//! 1. **seed**: starting states of every branch from the scene's own features (surface: the
//!    Euler rotation curve and, for a rod without the shift symmetry, its placements and
//!    families; enclosed: the exact or surface loops; exact: the closed-form closure);
//! 2. **trace**: continuation in the parameter (pseudo-arclength through folds on the surface,
//!    natural-parameter steps of the lifted-off parts in the ball, the closure curve of the
//!    exact layer);
//! 3. **locate** the special points (folds, branch points, index changes; lift-off, landing
//!    and detachment events);
//! 4. **exchanges**: the critical lengths where the lowest state changes, on re-solved
//!    equilibria;
//! 5. **label** every state (stable / metastable / unstable from the Hessian index).
//!
//! [`Engine::run`] performs them and returns the engine's own result (which keeps the states
//! themselves, for `states/`, the atlas and the report); [`Engine::schema`] turns that into
//! the one result schema that the writer, the figures and the report read. Whether a surface
//! rod is uniform or two-segment is a property of its stiffness (the shift symmetry), decided
//! inside [`SurfaceEngine`], not by its caller.

use std::collections::BTreeMap;

use rodloop_schema::{Axis, Cell, Critical, Diagram, Point, SpecialPoint};
use serde::Serialize;

use crate::enclosed::{
    enclosed_diagram_with, EnclosedDiagram, EnclosedDiagramOptions, EnclosedProgress,
};
use crate::{BranchHook, DiagramError, DiagramOptions, NumericDiagram, Progress};

/// Units of the diagram outputs.
pub const UNITS: &str =
    "lengths lbar = L/(2 pi R); energy E R/(pi D0) (D0 = D for a uniform rod); lambda R^3/D0";

/// A diagram engine: one model's pipeline (seed → trace → locate → exchanges → label).
pub trait Engine {
    /// The engine's own result (the schema names its states by file; the states live here).
    type Output;
    /// Progress events of [`Engine::run`].
    type Progress;
    /// `model` in `summary.json`.
    fn model(&self) -> &'static str;
    /// Run the pipeline.
    fn run(
        &mut self,
        progress: &mut dyn FnMut(Self::Progress),
    ) -> Result<Self::Output, DiagramError>;
    /// The result in the schema, for scene `scene` (state files not yet named).
    fn schema(&self, out: &Self::Output, scene: &str) -> Result<Diagram, DiagramError>;
}

/// The lbar axis of a branch diagram.
fn lbar_axis(min: f64, max: f64) -> Vec<Axis> {
    vec![Axis {
        name: "lbar".into(),
        min,
        max,
    }]
}

/// An engine's record of a critical length in the schema: the common fields, the rest kept as
/// the engine wrote them.
pub fn critical_of<T: Serialize>(c: &T) -> Result<Critical, DiagramError> {
    rodloop_schema::check_finite(c).map_err(|m| schema_err("critical", m))?;
    let v = serde_json::to_value(c).map_err(|e| schema_err("critical", e.to_string()))?;
    serde_json::from_value(v).map_err(|e| schema_err("critical", e.to_string()))
}

fn schema_err(what: &str, message: String) -> DiagramError {
    DiagramError::Schema(rodloop_schema::SchemaError::NotFiniteValue {
        key: what.into(),
        message,
    })
}

fn columns(names: &[&str]) -> Vec<String> {
    names.iter().map(|s| s.to_string()).collect()
}

/// The surface engine: any stiffness profile on the sphere (uniform rods by one family per
/// branch, two-segment rods by their families and sheets), every branch traced by
/// pseudo-arclength continuation ([`crate::compute`]), with a [`BranchHook`] that saves and
/// resumes branches.
pub struct SurfaceEngine<'a> {
    /// What to compute.
    pub opts: DiagramOptions,
    /// Saves each traced branch and hands back those of an interrupted run.
    pub hook: &'a mut dyn BranchHook,
}

impl Engine for SurfaceEngine<'_> {
    type Output = NumericDiagram;
    type Progress = Progress;

    fn model(&self) -> &'static str {
        "numeric"
    }

    fn run(&mut self, progress: &mut dyn FnMut(Progress)) -> Result<NumericDiagram, DiagramError> {
        crate::compute(&self.opts, self.hook, progress)
    }

    fn schema(&self, d: &NumericDiagram, scene: &str) -> Result<Diagram, DiagramError> {
        surface_schema(d, &self.opts, scene)
    }
}

/// The schema of a surface diagram traced with `opts`.
pub fn surface_schema(
    d: &NumericDiagram,
    opts: &DiagramOptions,
    scene: &str,
) -> Result<Diagram, DiagramError> {
    let mut out = Diagram::new(
        "numeric",
        scene,
        lbar_axis(opts.lbar_min, opts.lbar_max),
        UNITS,
    );
    out.accuracy = Some(format!("{:?}", opts.accuracy).to_lowercase());
    // The common columns first, in the order of the exact model's branches.csv.
    out.columns = columns(&[
        "branch",
        "eta",
        "lbar",
        "energy",
        "energy_g",
        "lambda_min",
        "lambda_max",
        "energy_error",
        "stability",
        "index",
        "family",
        "arc",
        "multiplicity",
        "point_group",
        "self_intersections",
        "state_file",
    ]);
    // The model works in the scene's R and D; report lambda R^3/D0.
    let lam_unit = opts.radius.powi(3) / opts.stiffness.reference();
    out.points = d
        .rows()
        .into_iter()
        .map(|r| Point {
            branch: r.branch,
            eta: r.eta,
            family: Some(r.family),
            sheet: None,
            coords: vec![r.lbar],
            energy: r.energy,
            energy_error: r.energy_error,
            index: Some(r.index),
            label: Some(r.stability.as_str().into()),
            state_file: Some(String::new()),
            extra: BTreeMap::from([
                ("energy_g".into(), Cell::F(r.energy_g)),
                ("lambda_min".into(), Cell::F(r.lambda_min * lam_unit)),
                ("lambda_max".into(), Cell::F(r.lambda_max * lam_unit)),
                ("arc".into(), Cell::I(r.arc as i64)),
                ("multiplicity".into(), Cell::I(r.multiplicity.into())),
                (
                    "point_group".into(),
                    Cell::S(r.shape.point_group.clone().unwrap_or_default()),
                ),
                (
                    "self_intersections".into(),
                    Cell::S(r.shape.self_intersections_label()),
                ),
            ]),
        })
        .collect();
    out.curves = d
        .branches
        .iter()
        .map(|b| rodloop_schema::Curve {
            branch: b.branch,
            eta: b.eta,
            family: b.family,
            sheet: b.sheet,
            multiplicity: b.multiplicity,
            span: b.span(),
            states: b.points.len(),
            cells: b.cells,
            low_end: b.stop_low.clone(),
            high_end: b.stop_high.clone(),
            seed: b.seed.clone(),
            seconds: b.seconds,
        })
        .collect();
    out.critical = d
        .critical
        .iter()
        .map(critical_of)
        .collect::<Result<_, _>>()?;
    out.special = Some(
        d.special
            .iter()
            .map(|p| SpecialPoint {
                kind: p.kind.as_str().into(),
                lbar: p.lbar,
                energy: p.energy,
                error_estimate: p.error_estimate,
                branch: p.branch,
                family: p.family,
                index_before: Some(p.index_before),
                index_after: Some(p.index_after),
                extra: BTreeMap::new(),
            })
            .collect(),
    );
    out.warnings = Some(d.warnings.clone());
    out.set_timings(&d.timings)?;
    if let Some(c) = &d.certificate {
        out.set_certificate(c)?;
    }
    out.states_dir = Some("states".into());
    out.put("unverified_states", &d.unverified_states)?;
    let named = crate::branch_identification(&d.branches, &d.state_files);
    out.put("branch_identification", &named)?;
    out.put("description", &d.scene)?;
    out.put("great_circles", &d.great_circles)?;
    out.put("shape_tolerance", &d.shape_tolerance)?;
    Ok(out)
}

/// The enclosed engine (`|r| ≤ R`, paper Sec. 3.2): attached parts from the exact layer (or
/// the surface families of a non-uniform rod), lifted-off parts from the 3-D model, events
/// where `λ_min` crosses zero, exchanges re-solved where a branch has lifted off.
pub struct EnclosedEngine {
    /// What to compute.
    pub opts: EnclosedDiagramOptions,
}

impl Engine for EnclosedEngine {
    type Output = EnclosedDiagram;
    type Progress = EnclosedProgress;

    fn model(&self) -> &'static str {
        "enclosed"
    }

    fn run(
        &mut self,
        progress: &mut dyn FnMut(EnclosedProgress),
    ) -> Result<EnclosedDiagram, DiagramError> {
        enclosed_diagram_with(&self.opts, progress)
    }

    fn schema(&self, d: &EnclosedDiagram, scene: &str) -> Result<Diagram, DiagramError> {
        let opts = &self.opts;
        let mut out = Diagram::new(
            "enclosed",
            scene,
            lbar_axis(opts.lbar_min, opts.lbar_max),
            UNITS,
        );
        out.accuracy = Some(format!("{:?}", opts.accuracy).to_lowercase());
        out.columns = columns(&[
            "branch",
            "eta",
            "lbar",
            "energy",
            "energy_error",
            "attached",
            "contact_fraction",
            "contact_intervals",
            "max_gap",
            "lambda_min",
            "gap_min",
            "complementarity",
            "stationarity",
            "index",
            "label",
            "lowest",
            "cells",
            "source",
            "family",
            "sheet",
            "multiplicity",
            "surface_energy",
            "branch_from",
            "state_file",
        ]);
        let mut points = Vec::with_capacity(d.points.len());
        for p in &d.points {
            let source = serde_json::to_value(p.source)
                .ok()
                .and_then(|v| v.as_str().map(str::to_string))
                .unwrap_or_default();
            points.push(Point {
                branch: p.branch,
                eta: p.eta,
                family: Some(p.family),
                sheet: Some(p.sheet),
                coords: vec![p.lbar],
                energy: p.energy,
                energy_error: Some(p.energy_error),
                index: Some(p.index),
                label: Some(p.label.as_str().into()),
                state_file: Some(String::new()),
                extra: BTreeMap::from([
                    ("attached".into(), Cell::I(p.attached.into())),
                    ("contact_fraction".into(), Cell::F(p.contact_fraction)),
                    (
                        "contact_intervals".into(),
                        Cell::I(p.contact_intervals as i64),
                    ),
                    ("max_gap".into(), Cell::F(p.max_gap)),
                    ("lambda_min".into(), Cell::F(p.lambda_min)),
                    ("gap_min".into(), Cell::F(p.gap_min)),
                    ("complementarity".into(), Cell::F(p.complementarity)),
                    ("stationarity".into(), Cell::F(p.stationarity)),
                    ("lowest".into(), Cell::I(p.lowest.into())),
                    ("cells".into(), Cell::I(p.cells as i64)),
                    ("source".into(), Cell::S(source)),
                    ("multiplicity".into(), Cell::I(p.multiplicity.into())),
                    (
                        "surface_energy".into(),
                        p.surface_energy.map_or(Cell::Empty, Cell::F),
                    ),
                    ("branch_from".into(), Cell::S(p.branch_from.as_str().into())),
                ]),
            });
        }
        out.points = points;
        out.critical = d
            .critical
            .iter()
            .map(critical_of)
            .collect::<Result<_, _>>()?;
        out.special = Some(
            d.events
                .iter()
                .map(|e| SpecialPoint {
                    kind: e.kind.as_str().into(),
                    lbar: e.lbar,
                    energy: e.energy,
                    error_estimate: Some(e.error_estimate),
                    branch: e.branch,
                    family: e.family,
                    index_before: Some(e.index_before),
                    index_after: Some(e.index_after),
                    extra: BTreeMap::new(),
                })
                .collect(),
        );
        out.warnings = Some(d.warnings.clone());
        out.set_timings(&d.seconds)?;
        let solves: std::collections::BTreeMap<&str, _> =
            d.solves.iter().map(|(s, c)| (s.name(), *c)).collect();
        out.put("solves", &solves)?;
        out.states_dir = Some("states".into());
        out.put("step", &opts.step)?;
        out.put("states", &d.points.len())?;
        // With a branch selection, "lowest" is among the selected branches only: no
        // hypothesis verdict.
        out.put(
            "lowest_lifted_off",
            &opts.branches.is_none().then(|| lowest_lifted_off(d)),
        )?;
        out.put("cells", &d.cells)?;
        out.put("notes", &d.notes)?;
        Ok(out)
    }
}

/// The `L̄` intervals where the lowest state of an enclosed diagram is a paper branch that has
/// lifted off (branch 0, the free circle below `L̄ = 1`, is not counted): from each critical
/// length or event to the next, when the lowest branch there is lifted off at the samples
/// between.
pub fn lowest_lifted_off(d: &EnclosedDiagram) -> Vec<(f64, f64)> {
    use crate::enclosed::EventKind;
    let mut cuts: Vec<f64> = d
        .critical
        .iter()
        .map(|c| c.critical.lbar_cr)
        .chain(
            d.events
                .iter()
                .filter(|e| matches!(e.kind, EventKind::LiftOff | EventKind::Landing))
                .map(|e| e.lbar),
        )
        .collect();
    cuts.push(
        d.points
            .iter()
            .map(|p| p.lbar)
            .fold(f64::INFINITY, f64::min),
    );
    cuts.push(
        d.points
            .iter()
            .map(|p| p.lbar)
            .fold(f64::NEG_INFINITY, f64::max),
    );
    cuts.sort_by(f64::total_cmp);
    cuts.dedup_by(|a, b| (*a - *b).abs() < 1e-12);
    let mut out: Vec<(f64, f64)> = Vec::new();
    for w in cuts.windows(2) {
        let inside: Vec<_> = d
            .points
            .iter()
            .filter(|p| p.lowest && p.branch > 0 && p.lbar > w[0] + 1e-9 && p.lbar < w[1] - 1e-9)
            .collect();
        if !inside.is_empty() && inside.iter().all(|p| !p.attached) {
            match out.last_mut() {
                Some(last) if (last.1 - w[0]).abs() < 1e-12 => last.1 = w[1],
                _ => out.push((w[0], w[1])),
            }
        }
    }
    out
}

/// The exact engine: closed-form elliptic-function loops of a homogeneous rod on the sphere,
/// sampled every `step` in `L̄`, with the critical lengths solved to machine precision.
pub struct ExactEngine {
    /// Smallest length.
    pub lbar_min: f64,
    /// Largest length.
    pub lbar_max: f64,
    /// Sample spacing.
    pub step: f64,
    /// Only these paper branches (`None`: all).
    pub branches: Option<Vec<u32>>,
    /// Threads for the shape descriptors.
    pub threads: usize,
}

/// The exact engine's result.
#[derive(Clone, Debug)]
pub struct ExactOutput {
    /// The exact diagram of the window.
    pub diagram: rodloop_exact::diagram::Diagram,
    /// Shape descriptors of its points, in order.
    pub shapes: Vec<rodloop_exact::shape::LoopShape>,
    /// Seconds of the diagram.
    pub seconds: f64,
    /// Seconds of the shape descriptors.
    pub seconds_shapes: f64,
}

/// The branches `η` that meet the open length window `(lbar_min, lbar_max)`: branch `η`
/// lives for `η − 1 < L̄ < η + 1`.
pub fn etas_in(lbar_min: f64, lbar_max: f64) -> Vec<u32> {
    let top = lbar_max.ceil() as u32 + 1;
    (1..=top)
        .filter(|&e| {
            let e = f64::from(e);
            e - 1.0 < lbar_max && e + 1.0 > lbar_min
        })
        .collect()
}

/// The exact diagram restricted to `[lbar_min, lbar_max]`, equal to the full diagram there:
/// every branch that meets the window is sampled on it; the critical lengths are those of the
/// diagram from `min(lbar_min, 1)` to `lbar_max` with the same branches (so that the indices
/// are the paper's `L̄_icr`, counted from `L̄_1cr = 1`) that fall in the window; and below
/// `L̄ = 1` a state is the lowest only if it lies below the circle (branch 0,
/// `E R/(πD) = 1/L̄`).
pub fn exact_window(
    lbar_min: f64,
    lbar_max: f64,
    step: f64,
) -> Result<rodloop_exact::diagram::Diagram, rodloop_exact::ExactError> {
    use rodloop_exact::diagram::{compute, DiagramSettings};
    let etas = etas_in(lbar_min, lbar_max);
    let eta_max = etas.iter().copied().max().unwrap_or(1);
    let mut d = compute(&DiagramSettings {
        lbar_min,
        lbar_max,
        eta_max,
        step,
    })?;
    if lbar_min > 1.0 {
        let from_one = compute(&DiagramSettings {
            lbar_min: 1.0,
            lbar_max,
            eta_max,
            step: step.max(0.01),
        })?;
        let tol = 1e-12;
        d.critical = from_one
            .critical
            .into_iter()
            .filter(|c| c.lbar_cr >= lbar_min - tol && c.lbar_cr <= lbar_max + tol)
            .collect();
    }
    for p in &mut d.points {
        if p.lbar < 1.0 && 1.0 / p.lbar < p.energy {
            p.lowest = false;
        }
    }
    Ok(d)
}

impl Engine for ExactEngine {
    type Output = ExactOutput;
    type Progress = ();

    fn model(&self) -> &'static str {
        "exact"
    }

    fn run(&mut self, _progress: &mut dyn FnMut(())) -> Result<ExactOutput, DiagramError> {
        let t0 = std::time::Instant::now();
        let exact = |e: rodloop_exact::ExactError| DiagramError::InvalidOptions(e.to_string());
        let mut d = exact_window(self.lbar_min, self.lbar_max, self.step).map_err(exact)?;
        if let Some(sel) = &self.branches {
            d.points.retain(|p| sel.contains(&p.branch));
            d.critical
                .retain(|c| sel.contains(&c.from_branch) || sel.contains(&c.to_branch));
        }
        let seconds = t0.elapsed().as_secs_f64();
        let t1 = std::time::Instant::now();
        let shapes = rodloop_exact::shape::diagram_shapes(
            &d.points,
            rodloop_exact::shape::ShapeTolerances::default(),
            self.threads,
        )
        .map_err(exact)?;
        Ok(ExactOutput {
            diagram: d,
            shapes,
            seconds,
            seconds_shapes: t1.elapsed().as_secs_f64(),
        })
    }

    fn schema(&self, out: &ExactOutput, scene: &str) -> Result<Diagram, DiagramError> {
        let d = &out.diagram;
        let mut s = Diagram::new(
            "exact",
            scene,
            lbar_axis(self.lbar_min, self.lbar_max),
            UNITS,
        );
        s.columns = columns(&[
            "branch",
            "eta",
            "lbar",
            "energy",
            "energy_g",
            "lambda_min",
            "lambda_max",
            "p",
            "k",
            "c",
            "closure_residual",
            "lowest",
            "point_group",
            "self_intersections",
        ]);
        s.points = d
            .points
            .iter()
            .zip(&out.shapes)
            .map(|(p, sh)| Point {
                branch: p.branch,
                eta: p.eta,
                coords: vec![p.lbar],
                energy: p.energy,
                extra: BTreeMap::from([
                    ("energy_g".into(), Cell::F(p.energy_g)),
                    ("lambda_min".into(), Cell::F(p.lambda_min)),
                    ("lambda_max".into(), Cell::F(p.lambda_max)),
                    ("p".into(), Cell::I(p.p.into())),
                    ("k".into(), Cell::F(p.k)),
                    ("c".into(), Cell::F(p.c)),
                    ("closure_residual".into(), Cell::F(p.closure_residual)),
                    ("lowest".into(), Cell::I(p.lowest.into())),
                    ("point_group".into(), Cell::S(sh.point_group.clone())),
                    (
                        "self_intersections".into(),
                        Cell::S(sh.self_intersections_label()),
                    ),
                ]),
                ..Point::default()
            })
            .collect();
        s.critical = d
            .critical
            .iter()
            .map(critical_of)
            .collect::<Result<_, _>>()?;
        let branch_count = d
            .points
            .iter()
            .map(|p| p.branch)
            .collect::<std::collections::BTreeSet<_>>()
            .len();
        s.put("step", &self.step)?;
        s.put("branches", &branch_count)?;
        s.put("states", &d.points.len())?;
        s.put("continuation_points", &d.continuation_steps)?;
        s.put("seconds", &out.seconds)?;
        s.put("seconds_shapes", &out.seconds_shapes)?;
        s.put(
            "shape_tolerance",
            &rodloop_exact::shape::ShapeTolerances::default(),
        )?;
        Ok(s)
    }
}
