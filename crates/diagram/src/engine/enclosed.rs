//! The enclosed engine ([`EnclosedEngine`], `|r| ≤ R`, paper Sec. 3.2) and its result in the
//! schema, with the stretches where the lowest state has lifted off ([`lowest_lifted_off`])
//! and the completeness certificate of a non-uniform rod's diagram
//! ([`EnclosedEngine::certificate`]: `solve`'s search at a few lowest states).

use std::collections::BTreeMap;

use rodloop_schema::{Cell, Diagram, Point, SpecialPoint};
use serde::Serialize;

use super::{columns, critical_of, lbar_axis, Engine, PointState, PointStates, StateSource, UNITS};
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

impl EnclosedEngine {
    /// The engine for the diagram of `stiffness` inside `wall` over `lbar_min ≤ L̄ ≤ lbar_max`
    /// with the default settings of [`EnclosedDiagramOptions::new`] (set the others on
    /// `opts`).
    pub fn new(
        wall: impl rodloop_solver::enclosed::IntoWall,
        stiffness: rodloop_solver::Stiffness,
        lbar_min: f64,
        lbar_max: f64,
    ) -> Self {
        Self {
            opts: EnclosedDiagramOptions::new(wall, stiffness, lbar_min, lbar_max),
        }
    }
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
        out.lowest_lifted_off = opts.branches.is_none().then(|| lowest_lifted_off(d));
        out.put("cells", &d.cells)?;
        out.notes = Some(d.notes.clone());
        Ok(out)
    }
}

/// The states of an enclosed diagram by point (the schema's points): every point, the
/// lifted-off 3-D states as they are and attached ones as their surface loop, in
/// `states/enclosed-branch-B-KKK.csv`, or `states/enclosed-branch-B-family-F-sheet-S-KKK.csv`
/// for a family of a non-uniform rod (`k` counts the points of the branch, family and sheet
/// in increasing `L̄`).
impl PointStates for EnclosedDiagram {
    fn point_states(&self) -> Vec<Option<PointState<'_>>> {
        let points = &self.points;
        let key = |i: usize| (points[i].branch, points[i].family, points[i].sheet);
        let mut order: Vec<usize> = (0..points.len()).collect();
        order.sort_by(|&a, &b| {
            key(a)
                .cmp(&key(b))
                .then(points[a].lbar.total_cmp(&points[b].lbar))
        });
        let mut out: Vec<Option<PointState<'_>>> = points.iter().map(|_| None).collect();
        let mut count = 0;
        for (pos, &i) in order.iter().enumerate() {
            if pos > 0 && key(order[pos - 1]) != key(i) {
                count = 0;
            }
            let p = &points[i];
            out[i] = Some(PointState {
                name: super::state_file_name("enclosed-branch", p.branch, p.family, p.sheet, count),
                source: StateSource::Enclosed(p),
            });
            count += 1;
        }
        out
    }
}

/// One check of the enclosed completeness certificate: `solve`'s state of a branch at the
/// length of a lowest state of the diagram.
#[derive(Clone, Debug, Serialize)]
pub struct CertificateCheck {
    /// `L̄` (that of the diagram's lowest state).
    pub lbar: f64,
    /// The branch `solve` was asked for.
    pub branch: u32,
    /// `solve`'s energy and error estimate (`None` where it found no state).
    pub solve_energy: Option<(f64, f64)>,
    /// The diagram's lowest state there: branch, family, energy, error estimate.
    pub lowest: (u32, u32, f64, f64),
    /// `solve`'s state lies below the lowest state by more than the two estimates.
    pub below: bool,
    /// `solve` was asked for the lowest state's branch and its state (or none) lies above the
    /// lowest state by more than the two estimates: `solve --branch` misses the stable state.
    pub misses: bool,
    /// Why `solve` found no state (empty otherwise).
    pub note: String,
}

impl CertificateCheck {
    /// The check of `solve`'s result `solve_energy` for `branch` at `lbar` against the
    /// diagram's `lowest` state there: below it, or (for its own branch) above it, by more
    /// than the two estimates; `solve` finding no state misses the lowest state of its branch.
    pub fn new(
        lbar: f64,
        branch: u32,
        solve_energy: Option<(f64, f64)>,
        lowest: (u32, u32, f64, f64),
        note: String,
    ) -> Self {
        let (_, _, e0, de0) = lowest;
        let (below, misses) = match solve_energy {
            Some((e, de)) => (e + de < e0 - de0, branch == lowest.0 && e - de > e0 + de0),
            None => (false, branch == lowest.0),
        };
        Self {
            lbar,
            branch,
            solve_energy,
            lowest,
            below,
            misses,
            note,
        }
    }
}

/// Lowest states at which the certificate runs `solve`: three, spread over the range.
const CERTIFICATE_SAMPLES: usize = 3;

impl EnclosedEngine {
    /// The completeness certificate of a non-uniform rod's diagram `d`: at the lengths of
    /// `CERTIFICATE_SAMPLES` lowest states of the diagram spread over its range, `solve`'s
    /// search ([`crate::enclosed_state::solve_state`]: the surface loop of each branch that
    /// exists there, then the enclosed loop from it) for every selected branch, in parallel; a
    /// state of `solve` below the diagram's lowest one by more than the two error estimates is
    /// a state the diagram missed. A uniform rod's diagram and `solve` start from the same
    /// exact surface loops: no check there (empty).
    pub fn certificate(&self, d: &EnclosedDiagram) -> Vec<CertificateCheck> {
        let opts = &self.opts;
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
        let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
        crate::parallel::run_parallel(threads, jobs, &mut |_| {}, &mut |_| {}, |(p, branch), _| {
            let lowest = (p.branch, p.family, p.energy, p.energy_error);
            match crate::enclosed_state::solve_state(
                &opts.wall,
                &opts.stiffness,
                p.lbar,
                branch,
                opts.accuracy,
            ) {
                Ok(res) => {
                    CertificateCheck::new(p.lbar, branch, Some(res.energy), lowest, String::new())
                }
                Err(e) => CertificateCheck::new(p.lbar, branch, None, lowest, error_chain(&e)),
            }
        })
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

/// An error and its sources, `: `-separated (as `anyhow` prints a chain with `{:#}`).
fn error_chain(e: &dyn std::error::Error) -> String {
    let mut out = e.to_string();
    let mut source = e.source();
    while let Some(s) = source {
        out.push_str(": ");
        out.push_str(&s.to_string());
        source = s.source();
    }
    out
}

#[cfg(test)]
mod tests {
    use super::CertificateCheck;

    /// A state of `solve` counts as below or above the lowest state only beyond the sum of
    /// the two estimates, and above only for the lowest state's own branch.
    #[test]
    fn certificate_checks_compare_beyond_both_estimates() {
        let lowest = (2, 1, 1.0, 1e-3);
        let check = |branch, e: f64, de: f64| {
            let c = CertificateCheck::new(1.5, branch, Some((e, de)), lowest, String::new());
            (c.below, c.misses)
        };
        // Within the two estimates either way: the same state.
        assert_eq!(check(2, 1.0 + 1.5e-3, 1e-3), (false, false));
        assert_eq!(check(2, 1.0 - 1.5e-3, 1e-3), (false, false));
        // Beyond them: a state the diagram missed, or the stable state `solve` missed.
        assert_eq!(check(2, 1.0 - 2.5e-3, 1e-3), (true, false));
        assert_eq!(check(2, 1.0 + 2.5e-3, 1e-3), (false, true));
        // Another branch above the lowest state is expected.
        assert_eq!(check(1, 1.5, 1e-3), (false, false));
        assert_eq!(check(1, 0.9, 1e-3), (true, false));
        // No state of the lowest state's branch misses it; of another branch, says nothing.
        let none = |branch| CertificateCheck::new(1.5, branch, None, lowest, "x".into());
        assert!(none(2).misses && !none(2).below);
        assert!(!none(1).misses);
    }
}
