//! The enclosed engine ([`EnclosedEngine`], `|r| ≤ R`, paper Sec. 3.2) and its result in the
//! schema, with the stretches where the lowest state has lifted off ([`lowest_lifted_off`]).

use std::collections::BTreeMap;

use rodloop_schema::{Cell, Diagram, Point, SpecialPoint};

use super::{columns, critical_of, lbar_axis, Engine, UNITS};
use crate::enclosed::{
    enclosed_diagram_with, EnclosedDiagram, EnclosedDiagramOptions, EnclosedProgress,
};
use crate::DiagramError;

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
                    value: None,
                    energy_error: None,
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
