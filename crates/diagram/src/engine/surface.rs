//! The surface engine ([`SurfaceEngine`]): any stiffness profile on the sphere, traced by
//! [`crate::compute`], and its result in the schema ([`surface_schema`]).

use std::collections::BTreeMap;

use rodloop_schema::{Cell, Diagram, Point, SpecialPoint};

use super::{columns, critical_of, lbar_axis, Engine, PointState, PointStates, StateSource, UNITS};
use crate::{BranchHook, DiagramError, DiagramOptions, NumericDiagram, Progress};

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
                value: None,
                energy_error: None,
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

/// The states of a surface diagram by row ([`NumericDiagram::rows`], the schema's points): the
/// verified state of each, `states/branch-B-KKK.csv`, or
/// `states/branch-B-family-F-sheet-S-KKK.csv` for a family of a non-uniform rod (`k` counts
/// the sheet's states in increasing `L̄`).
impl PointStates for NumericDiagram {
    fn point_states(&self) -> Vec<Option<PointState<'_>>> {
        let mut out = Vec::new();
        for (b, files) in self.branches.iter().zip(&self.state_files) {
            for (k, f) in files.iter().enumerate() {
                out.push(f.as_ref().map(|f| PointState {
                    name: super::state_file_name("branch", b.branch, b.family, b.sheet, k),
                    source: StateSource::Surface(f),
                }));
            }
        }
        out
    }
}
