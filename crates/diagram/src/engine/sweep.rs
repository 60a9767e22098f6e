//! The parameter-sweep engine ([`SweepEngine`]): the equilibria at a fixed length traced
//! against a stiffness parameter ([`crate::param_sweep::sweep_param`]), every traced state
//! verified as its file holds it and those that fail left out, and its result in the schema
//! ([`sweep_schema`]).

use rodloop_schema::{Axis, Cell as Value, Diagram, FamilyTrace, Parameter, Point, SpecialPoint};

use super::{schema_err, Engine, RecordStates};
use crate::param_sweep::{sweep_param, verify_sweep, ParamSweep, SweepSettings, SweepState};
use crate::{DiagramError, StateFile};

/// The parameter-sweep engine: the sweep of [`SweepSettings`], its states verified on
/// `threads` threads.
pub struct SweepEngine {
    /// What to compute.
    pub settings: SweepSettings,
    /// Threads of the state verification.
    pub threads: usize,
}

/// A sweep whose states passed their verification (the others left out).
pub struct VerifiedSweep {
    /// The sweep, its families holding the kept states only (`arc` renumbered).
    pub sweep: ParamSweep,
    /// Each kept state's energy estimate and verified file, by family and point.
    pub states: VerifiedStates,
    /// Number of states left out.
    pub unverified: usize,
    /// One warning per state left out.
    pub warnings: Vec<String>,
}

impl Engine for SweepEngine {
    type Output = VerifiedSweep;
    type Progress = ();

    fn model(&self) -> &'static str {
        "numeric"
    }

    fn run(&mut self, _progress: &mut dyn FnMut(())) -> Result<VerifiedSweep, DiagramError> {
        let mut sweep = sweep_param(&self.settings)?;
        let checked = verify_sweep(&self.settings, &sweep, self.threads);
        let (states, unverified, warnings) = keep_verified(&mut sweep, checked);
        Ok(VerifiedSweep {
            sweep,
            states,
            unverified,
            warnings,
        })
    }

    fn schema(&self, out: &VerifiedSweep, scene: &str) -> Result<Diagram, DiagramError> {
        sweep_schema(&out.sweep, scene, &out.states)
    }
}

impl RecordStates for VerifiedSweep {
    /// The state of each point, in the order of the schema's points.
    fn record_states(&self) -> Vec<Vec<&StateFile>> {
        self.states
            .iter()
            .flatten()
            .map(|(_, file)| vec![file])
            .collect()
    }
}

/// The error estimate of each kept state's energy and its verified file
/// ([`crate::param_sweep::SweepState`]), by family and point.
pub type VerifiedStates = Vec<Vec<(f64, StateFile)>>;

/// Keep the states of `sweep` that passed their verification (`checked[f][k]` for
/// `sweep.families[f].points[k]`), drop the others (renumbering `arc`): the kept states'
/// estimates and files, the number left out, and a warning for each.
fn keep_verified(
    sweep: &mut ParamSweep,
    checked: Vec<Vec<SweepState>>,
) -> (VerifiedStates, usize, Vec<String>) {
    let param = sweep.param;
    let mut kept = Vec::new();
    let mut count = 0;
    let mut warnings = Vec::new();
    for (f, results) in sweep.families.iter_mut().zip(checked) {
        let mut files = Vec::new();
        let mut points = Vec::new();
        for (p, r) in std::mem::take(&mut f.points).into_iter().zip(results) {
            match r {
                Ok(v) => {
                    files.push(v);
                    points.push(p);
                }
                Err(why) => {
                    count += 1;
                    warnings.push(format!(
                        "UNVERIFIED STATE LEFT OUT: branch {} family {} at {param} = {}: {why}",
                        f.branch, f.family, p.value
                    ));
                }
            }
        }
        for (i, p) in points.iter_mut().enumerate() {
            p.arc = i;
        }
        f.points = points;
        kept.push(files);
    }
    (kept, count, warnings)
}

/// The sweep in the result schema, for its one writer: one point per traced state, the
/// continued parameter (`param`, `value`) and the fixed length (`lbar`) as the two axes of
/// every point, with the error estimate of its energy (`branches.csv`; the state files are
/// named by their writer);
/// the special points at the fixed length with the parameter's `value` and the
/// `energy_error` beside them (indices only where an index change was located), the
/// sweep's warnings and state folder. The caller adds the run's own keys.
pub fn sweep_schema(
    s: &ParamSweep,
    scene: &str,
    states: &VerifiedStates,
) -> Result<Diagram, DiagramError> {
    let axes = vec![
        Axis {
            name: "value".into(),
            min: s.scene_value.min(s.target),
            max: s.scene_value.max(s.target),
        },
        Axis {
            name: "lbar".into(),
            min: s.lbar,
            max: s.lbar,
        },
    ];
    let mut d = Diagram::new(
        "numeric",
        scene,
        axes,
        "energy E R/(pi D0); lbar = L/(2 pi R)",
    );
    d.columns = [
        "branch",
        "eta",
        "family",
        "param",
        "value",
        "lbar",
        "energy",
        "energy_error",
        "index",
        "stability",
        "arc",
        "state_file",
    ]
    .iter()
    .map(|c| c.to_string())
    .collect();
    for (f, verified) in s.families.iter().zip(states) {
        for (p, (est, _)) in f.points.iter().zip(verified) {
            d.points.push(Point {
                branch: f.branch,
                eta: f.eta,
                family: Some(f.family as u32),
                coords: vec![p.value, s.lbar],
                energy: p.energy,
                energy_error: Some(*est),
                index: Some(p.index),
                label: Some(p.label.as_str().into()),
                extra: [
                    ("param".to_string(), Value::S(s.param.name().into())),
                    ("arc".to_string(), Value::I(p.arc as i64)),
                ]
                .into_iter()
                .collect(),
                ..Point::default()
            });
        }
    }
    for p in &s.special {
        // Checked on their typed form: JSON has no NaN (it would become `null`).
        rodloop_schema::check_finite(&[p.value, p.energy_error])
            .map_err(|m| schema_err("special point", m))?;
    }
    d.special = Some(
        s.special
            .iter()
            .map(|p| SpecialPoint {
                kind: p.kind.clone(),
                lbar: s.lbar,
                energy: p.energy,
                error_estimate: None,
                branch: p.branch,
                family: p.family as u32,
                index_before: p.index.map(|i| i.0),
                index_after: p.index.map(|i| i.1),
                value: Some(p.value),
                energy_error: Some(p.energy_error),
                extra: Default::default(),
            })
            .collect(),
    );
    d.warnings = Some(s.warnings.clone());
    d.states_dir = Some("states".into());
    d.parameter = Some(Parameter {
        name: s.param.name().into(),
        scene_value: s.scene_value,
        target: s.target,
    });
    d.families = Some(
        s.families
            .iter()
            .map(|f| FamilyTrace {
                branch: f.branch,
                eta: f.eta,
                family: f.family,
                cells: f.cells,
                seed_value: f.seed_energy.map(|e| e.0),
                seed_energy: f.seed_energy.map(|e| e.1),
                seed_energy_error: f.seed_energy.map(|e| e.2),
                notes: f.notes.clone(),
                states: f.points.len(),
                end: f.end.clone(),
            })
            .collect(),
    );
    Ok(d)
}
