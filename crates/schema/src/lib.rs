//! The result schema of every rodloop diagram, with its one writer and its one reader.
//!
//! A diagram of any model (surface uniform or two-segment, enclosed, exact layer) is one
//! [`Diagram`]: the scene and settings it answers, the continued parameters ([`Axis`]), its
//! states as one long table ([`Point`]s, each naming its branch, family and sheet), the
//! pieces of solution curve they lie on ([`Curve`]), the critical lengths where the lowest
//! state changes ([`Critical`]), the special points (folds, branch points, lift-off and
//! landing events: [`SpecialPoint`]), the completeness certificate, warnings and timings.
//!
//! A diagram against a stiffness parameter (the phase diagram, the diagram at a fixed length
//! against the parameter) names its [`Parameter`]; the phase diagram's curves are
//! [`ExchangeCurve`]s whose rows are its critical lengths ([`Critical::curve_row`]), the
//! diagram against the parameter records its families ([`FamilyTrace`]).
//!
//! [`Diagram::critical_table`] is the one printed table of its critical lengths.
//!
//! [`Diagram::files`] turns it into the files a diagram directory holds (`branches.csv`,
//! `critical.csv`, `special_points.csv`, `summary.json`), refusing a non-finite number
//! anywhere and writing no `null`; [`Diagram::read`] reads such a directory back into the same
//! value. Every column of `branches.csv` is named in one dictionary, [`COLUMNS`], with its type
//! and meaning; a diagram chooses which of them it writes and in which order
//! ([`Diagram::columns`]).
//!
//! The crate knows nothing about rods or numerics (it depends on serde, serde_json, csv and
//! thiserror only), so that figures, the report and a Python package can read a diagram
//! without the solvers.
//!
//! # Growth
//!
//! A point carries one coordinate per [`Axis`] (`lbar` for a branch diagram); a fold or
//! pitchfork curve in two parameters is a diagram with two axes. Shards of a sweep over many
//! scenes are diagrams of one scene each, merged by concatenating their points (the scene is
//! in [`Diagram::scene`]). [`VERSION`] is written into `summary.json` (`schema_version`).

#![warn(missing_docs)]

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

mod columns;
mod finite;
mod parameter;
mod print;
mod read;
mod write;

pub use columns::{column, ColumnSpec, Field, COLUMNS, CRITICAL_COLUMNS, SPECIAL_COLUMNS};
pub use finite::check_finite;
pub use parameter::{
    CurveEnd, CurveRow, Exchange, ExchangeCurve, FamilyTrace, Parameter, UniformLimit,
};
pub use print::SideColumn;
pub use write::strip_nulls;

/// Version of the schema (`schema_version` in `summary.json`).
pub const VERSION: u32 = 1;

/// Errors of the writer and the reader.
#[derive(Debug, thiserror::Error)]
pub enum SchemaError {
    /// A number that is not finite (nothing is written).
    #[error(
        "{file}: column {column} would hold a non-finite value ({value}) in row {row}; nothing was written"
    )]
    NotFinite {
        /// File name.
        file: String,
        /// Column.
        column: String,
        /// Row (from 1, after the header).
        row: usize,
        /// The value.
        value: f64,
    },
    /// A summary value holds a non-finite number somewhere.
    #[error("summary value {key}: {message}; nothing was written")]
    NotFiniteValue {
        /// Key of the summary.
        key: String,
        /// Which number.
        message: String,
    },
    /// A column that is not in [`COLUMNS`].
    #[error(
        "unknown column {0} of branches.csv (every column is named in rodloop_schema::COLUMNS)"
    )]
    UnknownColumn(String),
    /// A point holds a value its diagram has no column for (it would be lost).
    #[error("branches.csv row {row}: the point has a value for {field} but the diagram has no column for it")]
    NoColumn {
        /// Row (from 1).
        row: usize,
        /// The field.
        field: &'static str,
    },
    /// An engine's own summary key that the schema writes itself.
    #[error("summary key {0} is written by the schema; an engine's own key may not replace it")]
    KeyClash(String),
    /// A file could not be read.
    #[error("cannot read {path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// A file could not be parsed.
    #[error("{path}: {message}")]
    Parse {
        /// The file.
        path: String,
        /// What is wrong.
        message: String,
    },
}

/// A continued (or fixed) parameter of the diagram and its range.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Axis {
    /// Name (`lbar` for the branch diagram; the column of `branches.csv` holding the
    /// coordinate, and the prefix of `NAME_min`, `NAME_max` in `summary.json`).
    pub name: String,
    /// Smallest value.
    pub min: f64,
    /// Largest value.
    pub max: f64,
}

/// One value of [`Point::extra`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Cell {
    /// An integer.
    I(i64),
    /// A number (finite).
    F(f64),
    /// Text.
    S(String),
    /// No value (an empty cell).
    Empty,
}

/// One state of a diagram (one row of `branches.csv`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Point {
    /// Paper branch number.
    pub branch: u32,
    /// Periods of the geodesic curvature.
    pub eta: u32,
    /// Family within the branch (`None`: the diagram does not split branches).
    pub family: Option<u32>,
    /// Sheet of the family (`None`: not recorded).
    pub sheet: Option<u32>,
    /// One coordinate per [`Diagram::axes`].
    pub coords: Vec<f64>,
    /// Energy `E R/(π D0)`.
    pub energy: f64,
    /// Its estimated error.
    pub energy_error: Option<f64>,
    /// Stability index.
    pub index: Option<usize>,
    /// Stability label.
    pub label: Option<String>,
    /// Loop table of the state, relative to the diagram directory.
    pub state_file: Option<String>,
    /// The other columns, by name ([`COLUMNS`]).
    pub extra: BTreeMap<String, Cell>,
}

/// A piece of solution curve: one sheet of a family of a branch, with how it was traced.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Curve {
    /// Paper branch number.
    pub branch: u32,
    /// Periods of the geodesic curvature.
    pub eta: u32,
    /// Family within the branch.
    pub family: u32,
    /// Sheet of the family.
    pub sheet: u32,
    /// Distinct loops each state stands for.
    pub multiplicity: u32,
    /// Range of the continued parameter.
    pub span: (f64, f64),
    /// Number of states.
    pub states: usize,
    /// Tracing resolution (cells).
    pub cells: usize,
    /// How the lower end came about.
    pub low_end: String,
    /// How the upper end came about.
    pub high_end: String,
    /// How it was seeded.
    pub seed: String,
    /// Wall time of its tracing (seconds).
    pub seconds: f64,
}

/// A critical length `L̄_icr`: the lowest state changes branch (a crossing, `E_a = E_b`) or
/// collapses onto a great circle (`L̄ = m`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Critical {
    /// Index `i` of `L̄_icr` (from 1, counted from `L̄_1cr = 1`).
    pub index: usize,
    /// The critical length.
    pub lbar_cr: f64,
    /// `crossing` or `collapse`.
    pub kind: String,
    /// Lowest branch just below.
    pub from_branch: u32,
    /// Lowest branch just above.
    pub to_branch: u32,
    /// Energy there.
    pub energy: f64,
    /// Estimated error of `lbar_cr`.
    pub error_estimate: f64,
    /// What the engine adds (method, slopes, the surface value …), kept in `summary.json`.
    #[serde(flatten)]
    pub extra: BTreeMap<String, serde_json::Value>,
}

impl Critical {
    /// The surface model's value of this critical length (`surface_lbar_cr`, which an enclosed
    /// diagram records beside its own; `None` for the other models).
    pub fn surface_lbar_cr(&self) -> Option<f64> {
        self.extra
            .get("surface_lbar_cr")
            .and_then(serde_json::Value::as_f64)
    }
}

/// A special point of a branch: fold, branch point, crossing, collapse, lift-off, landing,
/// detachment.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SpecialPoint {
    /// What it is (`fold`, `branch_point`, `crossing`, `collapse`, `lift-off`, `landing`,
    /// `detachment`).
    pub kind: String,
    /// Where.
    pub lbar: f64,
    /// Energy there.
    pub energy: f64,
    /// Estimated error of `lbar` (`None`: known only to the tracing's width).
    pub error_estimate: Option<f64>,
    /// Paper branch.
    pub branch: u32,
    /// Family within the branch.
    pub family: u32,
    /// Stability index on one side (`None`: not located, a fold or branch point of a
    /// diagram against a parameter).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub index_before: Option<usize>,
    /// Stability index on the other side.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub index_after: Option<usize>,
    /// The parameter's value there (a diagram against a parameter, whose special points lie
    /// at its fixed length).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub value: Option<f64>,
    /// Estimated error of `energy` (a diagram against a parameter).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub energy_error: Option<f64>,
    /// What the engine adds, kept in `summary.json`.
    #[serde(flatten)]
    pub extra: BTreeMap<String, serde_json::Value>,
}

/// A diagram of any model.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Diagram {
    /// [`VERSION`] of the schema.
    pub version: u32,
    /// The model that computed it (`numeric`, `enclosed`, `exact`).
    pub model: String,
    /// Scene name.
    pub scene: String,
    /// Accuracy level (`fast`, `default`, `high`; `None` for the exact layer).
    pub accuracy: Option<String>,
    /// The parameters of the coordinates of every point (`lbar` for a branch diagram).
    pub axes: Vec<Axis>,
    /// Columns of `branches.csv`, in order (names of [`COLUMNS`]).
    pub columns: Vec<String>,
    /// States, in the order of `branches.csv`.
    pub points: Vec<Point>,
    /// Traced curves (sheets), `branches` in `summary.json` (empty: not recorded).
    pub curves: Vec<Curve>,
    /// Critical lengths.
    pub critical: Vec<Critical>,
    /// Special points (`None`: the model locates none, and no `special_points.csv`).
    pub special: Option<Vec<SpecialPoint>>,
    /// Completeness certificate (engine-specific record).
    pub certificate: Option<serde_json::Value>,
    /// Warnings (`None`: the model reports none).
    pub warnings: Option<Vec<String>>,
    /// Wall times of the stages (seconds).
    pub timings: Option<BTreeMap<String, f64>>,
    /// Units of the numbers.
    pub units: String,
    /// Folder of the state files (relative to the diagram directory).
    pub states_dir: Option<String>,
    /// Identifier of the run that wrote the files.
    pub run_id: Option<String>,
    /// The stiffness parameter of a diagram against a parameter (`param`, `scene_value`,
    /// `target` in `summary.json`).
    pub parameter: Option<Parameter>,
    /// The curves of a phase diagram (`curves` in `summary.json`).
    pub exchange_curves: Option<Vec<ExchangeCurve>>,
    /// The families of a diagram against a parameter (`families` in `summary.json`).
    pub families: Option<Vec<FamilyTrace>>,
    /// Notes of the run: what the model did besides the plan, not a fault (`notes` in
    /// `summary.json`; `None`: the model writes none).
    pub notes: Option<Vec<String>>,
    /// The `L̄` intervals `(a, b)` where the lowest state has lifted off the wall (an enclosed
    /// diagram over every branch; `lowest_lifted_off` in `summary.json`; `None`: no verdict,
    /// as for a diagram of selected branches or on the surface).
    pub lowest_lifted_off: Option<Vec<(f64, f64)>>,
    /// The engine's own `summary.json` keys.
    pub extra: BTreeMap<String, serde_json::Value>,
}
