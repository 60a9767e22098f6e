//! One interface for every diagram engine, and the one translation of each engine's result
//! into the result schema ([`rodloop_schema::Diagram`]).
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
//! the one result schema that the writer, the figures and the report read; the states of the
//! results against a stiffness parameter reach `states/` through [`RecordStates`], by record
//! of the schema, those of the `L̄` diagrams (surface and enclosed) through [`PointStates`], by
//! point of the schema. Whether a surface
//! rod is uniform or two-segment is a property of its stiffness (the shift symmetry), decided
//! inside [`SurfaceEngine`], not by its caller.
//!
//! | file | holds |
//! |---|---|
//! | `mod.rs` | the [`Engine`] interface and the schema helpers the engines share |
//! | `surface.rs` | [`SurfaceEngine`] and its schema ([`surface_schema`]) |
//! | `branch_files.rs` | [`BranchFiles`]: the surface engine's branches saved to and resumed from their files |
//! | `enclosed.rs` | [`EnclosedEngine`], its schema ([`lowest_lifted_off`]) and its completeness certificate ([`EnclosedEngine::certificate`]) |
//! | `exact.rs` | [`ExactEngine`], its window of the exact diagram ([`exact_window`], in the schema: [`exact_window_schema`]) and the exact counterpart of a critical length ([`exact_counterpart`]) |
//! | `sweep.rs` | [`SweepEngine`] (states at a fixed length against a stiffness parameter) and its schema ([`sweep_schema`]) |
//! | `phase.rs` | [`PhaseEngine`] (critical lengths followed in a stiffness parameter, rows whose states fail left out: [`VerifiedPhase`]) and its schema ([`phase_schema`]) |

mod branch_files;
mod enclosed;
mod exact;
mod phase;
mod surface;
mod sweep;

pub use branch_files::{BranchFileEvent, BranchFiles};
pub use enclosed::{
    lowest_lifted_off, CertificateCheck, EnclosedCertificate, EnclosedEngine, ExchangeCheck,
};
pub use exact::{
    etas_in, exact_counterpart, exact_window, exact_window_schema, ExactEngine, ExactOutput,
};
pub use phase::{phase_schema, PhaseEngine, VerifiedPhase, PHASE_UNITS};
pub use surface::{surface_schema, SurfaceEngine};
pub use sweep::{sweep_schema, SweepEngine, VerifiedStates, VerifiedSweep};

use rodloop_schema::{Axis, Critical, Diagram};
use serde::Serialize;

use crate::DiagramError;

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

/// The verified states an engine's result holds, by record of its schema: what the files of
/// `states/` are written from, each named from its record (the schema holds no states).
pub trait RecordStates {
    /// The states of each record, in the schema's order: of each point of a diagram against a
    /// parameter (one state), of each critical length of a phase diagram (the states of its
    /// curve's `from_branch` and `to_branch`; none for the extrapolated limit row).
    fn record_states(&self) -> Vec<Vec<&crate::StateFile>>;
}

/// The state of one point of a diagram, as `states/` holds it: its file name and where its
/// rows come from ([`PointState::table`]).
pub struct PointState<'a> {
    /// File, relative to the diagram directory (`states/…`).
    pub name: String,
    source: StateSource<'a>,
}

/// Where the rows of a [`PointState`] come from.
enum StateSource<'a> {
    /// A verified surface state.
    Surface(&'a crate::StateFile),
    /// A point of the enclosed diagram (its 3-D state, or its surface loop when attached).
    Enclosed(&'a crate::enclosed::EnclosedPoint),
}

/// The rows of a state file in the columns of `solve`'s `config.csv`.
pub struct StateTable {
    /// The columns ([`crate::state_rows::SURFACE_COLUMNS`] or
    /// [`crate::state_rows::ENCLOSED_COLUMNS`]).
    pub columns: &'static [&'static str; 12],
    /// The column that holds integers (the enclosed `node`), if any.
    pub integer_column: Option<usize>,
    /// The rows.
    pub rows: Vec<[f64; 12]>,
}

/// The name of the `k`-th state file of a sheet, relative to the run's directory:
/// `states/{kind}-{branch}-{k:03}.csv` for a branch's one family (family 0), else
/// `states/{kind}-{branch}-family-{family}-sheet-{sheet}-{k:03}.csv`.
pub(crate) fn state_file_name(
    kind: &str,
    branch: u32,
    family: u32,
    sheet: u32,
    k: usize,
) -> String {
    if family == 0 {
        format!("states/{kind}-{branch}-{k:03}.csv")
    } else {
        format!("states/{kind}-{branch}-family-{family}-sheet-{sheet}-{k:03}.csv")
    }
}

impl PointState<'_> {
    /// The rows in units of the scene's `r` and `d0`.
    pub fn table(&self, r: f64, d0: f64) -> Result<StateTable, DiagramError> {
        use crate::state_rows::{
            point_rows, surface_rows, ENCLOSED_COLUMNS, NODE_COLUMN, SURFACE_COLUMNS,
        };
        Ok(match self.source {
            StateSource::Surface(f) => StateTable {
                columns: &SURFACE_COLUMNS,
                integer_column: None,
                rows: surface_rows(&f.profile, r, d0),
            },
            StateSource::Enclosed(p) => StateTable {
                columns: &ENCLOSED_COLUMNS,
                integer_column: Some(NODE_COLUMN),
                rows: point_rows(p, r, d0)?,
            },
        })
    }
}

/// The states an engine's result keeps, by point of its schema ([`Engine::schema`]'s
/// `points`, in their order): what `states/` is written from, each point naming its file.
pub trait PointStates {
    /// The state of every point (`None`: no verified state, no file).
    fn point_states(&self) -> Vec<Option<PointState<'_>>>;
}

/// The lbar axis of a branch diagram.
pub(super) fn lbar_axis(min: f64, max: f64) -> Vec<Axis> {
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

pub(super) fn schema_err(what: &str, message: String) -> DiagramError {
    DiagramError::Schema(rodloop_schema::SchemaError::NotFiniteValue {
        key: what.into(),
        message,
    })
}

pub(super) fn columns(names: &[&str]) -> Vec<String> {
    names.iter().map(|s| s.to_string()).collect()
}
