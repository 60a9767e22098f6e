//! Diagrams against a stiffness parameter: the phase diagram (critical lengths followed as
//! curves in the parameter) and the diagram at a fixed length against the parameter.
//!
//! Both name their [`Parameter`] (`param`, `scene_value`, `target` in `summary.json`). A phase
//! diagram's critical lengths are the rows of its curves: each record carries its place on
//! its curve ([`CurveRow`], read with [`Critical::curve_row`]), and the curves themselves are
//! [`ExchangeCurve`]s (`curves`). A diagram against the parameter records how each of its
//! families was seeded and traced ([`FamilyTrace`], `families`); its points have the axes
//! `value` and `lbar`, its special points the parameter's value
//! ([`crate::SpecialPoint::value`]).

use serde::{Deserialize, Serialize};

use crate::{Critical, SchemaError};

/// The stiffness parameter a diagram is traced against.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Parameter {
    /// Its name: `d1` (= `D1/D0`), `gamma`, `s0` or `s1` (fractions of the length).
    #[serde(rename = "param")]
    pub name: String,
    /// The scene's value (where the tracing starts).
    pub scene_value: f64,
    /// The requested end value.
    pub target: f64,
}

impl Parameter {
    /// Whether the parameter is drawn on a logarithmic axis (`d1`, a ratio of stiffnesses).
    pub fn is_log(&self) -> bool {
        self.name == "d1"
    }

    /// The requested range, from the scene's value to the target, as `(low, high)`.
    pub fn range(&self) -> (f64, f64) {
        (
            self.scene_value.min(self.target),
            self.scene_value.max(self.target),
        )
    }
}

/// Where a critical length of a phase diagram lies on its curve: the keys its record in
/// `critical` carries beside the common ones.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CurveRow {
    /// The parameter's name.
    pub param: String,
    /// The parameter's value.
    pub value: f64,
    /// How the row was obtained: `seed` (the Maxwell point located on re-solved equilibria),
    /// `continuation`, `switch` (onto another pair of states), `fixed` (an exact solve at a
    /// requested value), `limit` (extrapolated to the uniform rod).
    pub source: String,
    /// The curve (from 1, in the order of [`crate::Diagram::exchange_curves`]).
    pub curve: usize,
    /// Arm of the curve: 0 from its start, one more after each fold where the two energy
    /// curves touch or each switch.
    pub arm: usize,
    /// Stability index of the state of the curve's `from_branch`.
    pub index_from: usize,
    /// Stability index of the state of the curve's `to_branch`.
    pub index_to: usize,
    /// `d(E_from − E_to)/dL̄` of the curve's two branches at the crossing.
    pub slope: f64,
    /// Estimated error of the energy.
    pub energy_error: f64,
}

impl Critical {
    /// The record's place on a curve of a phase diagram (`None`: a critical length of a
    /// diagram in `L̄`).
    pub fn curve_row(&self) -> Option<CurveRow> {
        let map: serde_json::Map<_, _> = self
            .extra
            .iter()
            .map(|(k, v)| (k.clone(), v.clone()))
            .collect();
        serde_json::from_value(serde_json::Value::Object(map)).ok()
    }

    /// Record the place on a curve ([`Critical::curve_row`]), every number checked finite.
    pub fn set_curve_row(&mut self, row: &CurveRow) -> Result<(), SchemaError> {
        crate::check_finite(row).map_err(|message| SchemaError::NotFiniteValue {
            key: "critical".into(),
            message,
        })?;
        let serde_json::Value::Object(map) =
            serde_json::to_value(row).map_err(|e| SchemaError::NotFiniteValue {
                key: "critical".into(),
                message: e.to_string(),
            })?
        else {
            unreachable!("a struct serialises to an object")
        };
        self.extra.extend(map);
        Ok(())
    }
}

/// An exchange of the lowest branch of the uniform rod: the start of a curve of a phase
/// diagram.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Exchange {
    /// Lowest branch just below the critical length.
    pub from_branch: u32,
    /// Lowest branch just above.
    pub to_branch: u32,
    /// The exact critical length of the uniform rod.
    pub lbar_uniform: f64,
}

/// Why (and where) a curve of a phase diagram ends in one direction.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CurveEnd {
    /// The parameter's value at the last row in this direction.
    pub value: f64,
    /// `reached` (the end of the requested range), `unstable`, `fold`, `branch_point`,
    /// `failed`, or `limit` (the uniform rod).
    pub kind: String,
    /// Explanation for people.
    pub reason: String,
}

/// The limit of a curve at the uniform rod (`D1/D0 → 1`) against its exact critical length.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct UniformLimit {
    /// Extrapolated critical length at `D1/D0 = 1`.
    pub lbar_cr: f64,
    /// Its estimated error.
    pub error_estimate: f64,
    /// The exact critical length of the uniform rod.
    pub exact: f64,
    /// `lbar_cr − exact`.
    pub deviation: f64,
}

/// A curve of a phase diagram: one exchange followed in the parameter (its rows are the
/// critical lengths whose [`CurveRow::curve`] names it).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ExchangeCurve {
    /// The exchange of the uniform rod it starts from.
    pub exchange: Exchange,
    /// Number of rows.
    pub rows: usize,
    /// Accepted continuation steps.
    pub steps: usize,
    /// Cells of the two branches' models at the main resolution.
    pub cells: (usize, usize),
    /// How the curve ends towards lower and higher values.
    pub ends: Vec<CurveEnd>,
    /// The limit at the uniform rod (`d1` only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub uniform: Option<UniformLimit>,
    /// Folds where the two energy curves touch (the curve goes on, on its next arm).
    pub turns: Vec<String>,
    /// Switches onto another pair of states.
    pub switches: Vec<String>,
    /// Values at which a search for lower states of both branches found none.
    pub checks: Vec<f64>,
    /// Notes.
    pub notes: Vec<String>,
}

impl ExchangeCurve {
    /// The ends that stop inside the requested range `(low, high)` (not `reached`, not the
    /// uniform rod's `limit`).
    pub fn stopped_short(&self, (low, high): (f64, f64)) -> impl Iterator<Item = &CurveEnd> {
        self.ends
            .iter()
            .filter(|e| e.kind != "reached" && e.kind != "limit")
            .filter(move |e| e.value > low && e.value < high)
    }
}

/// A family of a diagram against the parameter: how it was seeded and traced.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FamilyTrace {
    /// Paper branch.
    pub branch: u32,
    /// Periods of the geodesic curvature.
    pub eta: u32,
    /// Family within the branch.
    pub family: usize,
    /// Cells of its model.
    pub cells: usize,
    /// The parameter's value of its seed (`None`: not seeded).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seed_value: Option<f64>,
    /// The seed's energy.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seed_energy: Option<f64>,
    /// Its estimated error.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seed_energy_error: Option<f64>,
    /// Notes (why it was not seeded, …).
    pub notes: Vec<String>,
    /// Number of states.
    pub states: usize,
    /// How its tracing ended.
    pub end: String,
}
