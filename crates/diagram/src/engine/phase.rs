//! The phase engine ([`PhaseEngine`]): the exchanges of the lowest state followed in a
//! stiffness parameter ([`crate::phase::trace_phase`]), the rows whose states fail their
//! verification left out ([`VerifiedPhase`]), and its result in the schema
//! ([`phase_schema`]): one critical record per row of a curve, with its place on the curve,
//! and the curves themselves.

use rodloop_schema::{
    Critical, CurveEnd, CurveRow, Diagram, Exchange, ExchangeCurve, Parameter, UniformLimit,
};

use super::{Engine, RecordStates};
use crate::phase::{trace_phase, PhaseCurve, PhaseDiagram, PhaseSettings, RowStates};
use crate::{DiagramError, StateFile};

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

/// A phase diagram whose rows' states passed their verification (the other rows left out).
pub struct VerifiedPhase {
    /// The diagram, its curves holding the kept rows only.
    pub diagram: PhaseDiagram,
    /// Number of states left out (both of each row left out).
    pub unverified: usize,
    /// One warning per row left out.
    pub warnings: Vec<String>,
}

impl Engine for PhaseEngine {
    type Output = VerifiedPhase;
    type Progress = ();

    fn model(&self) -> &'static str {
        "numeric"
    }

    fn run(&mut self, _progress: &mut dyn FnMut(())) -> Result<VerifiedPhase, DiagramError> {
        let mut diagram = trace_phase(&self.settings)?;
        let (unverified, warnings) = drop_unverified(&mut diagram);
        Ok(VerifiedPhase {
            diagram,
            unverified,
            warnings,
        })
    }

    fn schema(&self, out: &VerifiedPhase, scene: &str) -> Result<Diagram, DiagramError> {
        phase_schema(
            &out.diagram,
            scene,
            &format!("{:?}", self.settings.accuracy),
        )
    }
}

impl RecordStates for VerifiedPhase {
    /// The two states of each row (those of its curve's `from_branch` and `to_branch`; none
    /// for the limit row), in the order of the schema's critical lengths.
    fn record_states(&self) -> Vec<Vec<&StateFile>> {
        self.diagram
            .curves
            .iter()
            .flat_map(|c| &c.rows)
            .map(|r| match &r.states {
                RowStates::Verified(files) => files.iter().collect(),
                _ => Vec::new(),
            })
            .collect()
    }
}

/// Leave out the rows of `d` whose states failed their verification ([`RowStates`]):
/// returns the number of states left out (both of each such row) and a warning for each row.
fn drop_unverified(d: &mut PhaseDiagram) -> (usize, Vec<String>) {
    let param = d.param;
    let mut count = 0;
    let mut warnings = Vec::new();
    for c in &mut d.curves {
        let ex = c.exchange;
        c.rows.retain(|r| match &r.states {
            RowStates::Unverified(why) => {
                count += 2;
                warnings.push(format!(
                    "UNVERIFIED STATES LEFT OUT: exchange {} -> {} at {param} = {} (L̄_cr = {}): {why}",
                    ex.from_branch, ex.to_branch, r.value, r.lbar_cr
                ));
                false
            }
            _ => true,
        });
    }
    (count, warnings)
}

/// The phase diagram `d` of scene `scene` at accuracy `accuracy` (the level's name) in the
/// result schema: every row of `phase.csv` is a critical length of the schema (`index` its
/// row, from 1) with its place on its curve ([`CurveRow`]: the parameter value, the row's
/// source, curve, arm, indices, slope and energy error), the curves are the schema's
/// [`ExchangeCurve`]s, the parameter its [`Parameter`]; the caller adds the run's keys.
pub fn phase_schema(
    d: &PhaseDiagram,
    scene: &str,
    accuracy: &str,
) -> Result<Diagram, DiagramError> {
    let mut s = Diagram::new("numeric", scene, Vec::new(), PHASE_UNITS);
    s.accuracy = Some(accuracy.to_lowercase());
    for (k, c) in d.curves.iter().enumerate() {
        for r in &c.rows {
            let mut critical = Critical {
                index: s.critical.len() + 1,
                lbar_cr: r.lbar_cr,
                kind: "crossing".into(),
                from_branch: r.from_branch,
                to_branch: r.to_branch,
                energy: r.energy,
                error_estimate: r.error_estimate,
                extra: Default::default(),
            };
            critical.set_curve_row(&CurveRow {
                param: d.param.name().into(),
                value: r.value,
                source: r.source.name().into(),
                curve: k + 1,
                arm: r.arm,
                index_from: r.index.0,
                index_to: r.index.1,
                slope: r.slope,
                energy_error: r.energy_error,
            })?;
            s.critical.push(critical);
        }
    }
    s.parameter = Some(Parameter {
        name: d.param.name().into(),
        scene_value: d.scene_value,
        target: d.target,
    });
    s.exchange_curves = Some(d.curves.iter().map(exchange_curve).collect());
    Ok(s)
}

/// A curve of the phase diagram in the schema: its exchange, how it was traced and why it
/// ends (its rows are the critical lengths that name it).
fn exchange_curve(c: &PhaseCurve) -> ExchangeCurve {
    ExchangeCurve {
        exchange: Exchange {
            from_branch: c.exchange.from_branch,
            to_branch: c.exchange.to_branch,
            lbar_uniform: c.exchange.lbar_uniform,
        },
        rows: c.rows.len(),
        steps: c.steps,
        cells: c.cells,
        ends: c
            .ends
            .iter()
            .map(|e| CurveEnd {
                value: e.value,
                kind: e.kind.clone(),
                reason: e.reason.clone(),
            })
            .collect(),
        uniform: c.uniform.map(|u| UniformLimit {
            lbar_cr: u.lbar_cr,
            error_estimate: u.error_estimate,
            exact: u.exact,
            deviation: u.deviation,
        }),
        turns: c.turns.clone(),
        switches: c.switches.clone(),
        checks: c.checks.clone(),
        notes: c.notes.clone(),
    }
}
