//! The phase engine ([`PhaseEngine`]): the exchanges of the lowest state followed in a
//! stiffness parameter ([`crate::phase::trace_phase`]), and its result in the schema
//! ([`phase_schema`]): one critical record per row of a curve, the curves' summaries as the
//! engine's own keys.

use rodloop_schema::{Critical, Diagram};

use super::{schema_err, Engine};
use crate::phase::{trace_phase, CurveEnd, Exchange, PhaseDiagram, PhaseSettings, UniformCheck};
use crate::DiagramError;

/// `units` of the phase schema.
pub const PHASE_UNITS: &str =
    "lbar = L/(2 pi R); energy E R/(pi D0); value: d1 = D1/D0, gamma, or s0, s1 as fractions of L";

/// The phase engine: the critical lengths of the exchanges of the lowest state of a
/// two-segment rod followed in a stiffness parameter (`d1`, `gamma`, `s0`, `s1`) towards
/// [`PhaseSettings::target`].
pub struct PhaseEngine {
    /// What to compute.
    pub settings: PhaseSettings,
}

impl Engine for PhaseEngine {
    type Output = PhaseDiagram;
    type Progress = ();

    fn model(&self) -> &'static str {
        "numeric"
    }

    fn run(&mut self, _progress: &mut dyn FnMut(())) -> Result<PhaseDiagram, DiagramError> {
        trace_phase(&self.settings)
    }

    fn schema(&self, d: &PhaseDiagram, scene: &str) -> Result<Diagram, DiagramError> {
        phase_schema(d, scene, &format!("{:?}", self.settings.accuracy))
    }
}

/// A curve of `summary.json`: its exchange, how it was traced and why it ends.
#[derive(serde::Serialize)]
struct CurveSummary<'a> {
    exchange: &'a Exchange,
    rows: usize,
    steps: usize,
    cells: (usize, usize),
    ends: &'a [CurveEnd],
    uniform: &'a Option<UniformCheck>,
    turns: &'a [String],
    switches: &'a [String],
    checks: &'a [f64],
    notes: &'a [String],
}

/// The phase diagram `d` of scene `scene` at accuracy `accuracy` (the level's name) in the
/// result schema: every row of `phase.csv` is a critical length of the schema (`index` its
/// row, from 1; the parameter value, the row's source, curve, arm, indices, slope and
/// energy error beside it), the curves and the parameter's range are the engine's own keys;
/// the caller adds the run's.
pub fn phase_schema(
    d: &PhaseDiagram,
    scene: &str,
    accuracy: &str,
) -> Result<Diagram, DiagramError> {
    let mut s = Diagram::new("numeric", scene, Vec::new(), PHASE_UNITS);
    s.accuracy = Some(accuracy.to_lowercase());
    for (k, c) in d.curves.iter().enumerate() {
        for r in &c.rows {
            let extra = serde_json::json!({
                "param": d.param.name(),
                "value": r.value,
                "source": r.source.name(),
                "curve": k + 1,
                "arm": r.arm,
                "index_from": r.index.0,
                "index_to": r.index.1,
                "slope": r.slope,
                "energy_error": r.energy_error,
            });
            rodloop_schema::check_finite(&[r.value, r.slope, r.energy_error])
                .map_err(|m| schema_err("phase row", m))?;
            s.critical.push(Critical {
                index: s.critical.len() + 1,
                lbar_cr: r.lbar_cr,
                kind: "crossing".into(),
                from_branch: r.from_branch,
                to_branch: r.to_branch,
                energy: r.energy,
                error_estimate: r.error_estimate,
                extra: serde_json::from_value(extra)
                    .map_err(|e| schema_err("phase row", e.to_string()))?,
            });
        }
    }
    s.put("param", &d.param)?;
    s.put("scene_value", &d.scene_value)?;
    s.put("target", &d.target)?;
    s.put(
        "curves",
        &d.curves
            .iter()
            .map(|c| CurveSummary {
                exchange: &c.exchange,
                rows: c.rows.len(),
                steps: c.steps,
                cells: c.cells,
                ends: &c.ends,
                uniform: &c.uniform,
                turns: &c.turns,
                switches: &c.switches,
                checks: &c.checks,
                notes: &c.notes,
            })
            .collect::<Vec<_>>(),
    )?;
    Ok(s)
}
