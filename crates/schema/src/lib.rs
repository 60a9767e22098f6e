//! The result schema of every rodloop diagram, with its one writer and its one reader.
//!
//! A diagram of any model (surface uniform or two-segment, enclosed, exact layer) is one
//! [`Diagram`]: the scene and settings it answers, the continued parameters ([`Axis`]), its
//! states as one long table ([`Point`]s, each naming its branch, family and sheet), the
//! pieces of solution curve they lie on ([`Curve`]), the critical lengths where the lowest
//! state changes ([`Critical`]), the special points (folds, branch points, lift-off and
//! landing events: [`SpecialPoint`]), the completeness certificate, warnings and timings.
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
use std::path::Path;

use serde::{Deserialize, Serialize};

mod finite;

pub use finite::check_finite;

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

/// What a column of `branches.csv` holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Field {
    /// [`Point::branch`].
    Branch,
    /// [`Point::eta`].
    Eta,
    /// [`Point::family`].
    Family,
    /// [`Point::sheet`].
    Sheet,
    /// The coordinate of the axis of the same name ([`Point::coords`]).
    Coord,
    /// [`Point::energy`].
    Energy,
    /// [`Point::energy_error`].
    EnergyError,
    /// [`Point::index`].
    Index,
    /// [`Point::label`].
    Label,
    /// [`Point::state_file`].
    StateFile,
    /// A number in [`Point::extra`].
    Number,
    /// An integer in [`Point::extra`].
    Integer,
    /// Text in [`Point::extra`].
    Text,
}

/// One entry of the column dictionary.
#[derive(Clone, Copy, Debug)]
pub struct ColumnSpec {
    /// Column name in `branches.csv`.
    pub name: &'static str,
    /// What it holds.
    pub field: Field,
    /// Meaning and units.
    pub meaning: &'static str,
}

const fn col(name: &'static str, field: Field, meaning: &'static str) -> ColumnSpec {
    ColumnSpec {
        name,
        field,
        meaning,
    }
}

/// Every column a `branches.csv` of rodloop may hold. Energies are `E R/(π D0)`, forces
/// `λ R³/D0`, lengths `L̄ = L/(2πR)`.
pub const COLUMNS: &[ColumnSpec] = &[
    col(
        "branch",
        Field::Branch,
        "paper branch number (0: the free circle)",
    ),
    col("eta", Field::Eta, "periods of the geodesic curvature"),
    col(
        "family",
        Field::Family,
        "family within the branch (0: a uniform rod's one family)",
    ),
    col(
        "sheet",
        Field::Sheet,
        "sheet of the family (monotone in lbar)",
    ),
    col("lbar", Field::Coord, "normalised length L/(2 pi R)"),
    col("energy", Field::Energy, "energy E R/(pi D0)"),
    col(
        "energy_error",
        Field::EnergyError,
        "estimated error of energy (empty: none)",
    ),
    col(
        "index",
        Field::Index,
        "stability index (negative eigenvalues of the constrained Hessian)",
    ),
    col(
        "stability",
        Field::Label,
        "stable, metastable or unstable (surface diagrams)",
    ),
    col(
        "label",
        Field::Label,
        "stable, metastable or unstable (enclosed diagrams)",
    ),
    col(
        "state_file",
        Field::StateFile,
        "the state's loop table, relative to the diagram directory",
    ),
    col("energy_g", Field::Number, "geodesic part E_g R/(pi D0)"),
    col(
        "lambda_min",
        Field::Number,
        "smallest contact force lambda R^3/D0",
    ),
    col(
        "lambda_max",
        Field::Number,
        "largest contact force lambda R^3/D0",
    ),
    col(
        "arc",
        Field::Integer,
        "position along the family: sheet * 10^6 + rank in arclength",
    ),
    col(
        "multiplicity",
        Field::Integer,
        "distinct loops the state stands for (2: a mirror pair)",
    ),
    col("point_group", Field::Text, "point group of the loop"),
    col(
        "self_intersections",
        Field::Text,
        "self-intersections of the loop",
    ),
    col("p", Field::Integer, "paper winding number p, Eq. (50)"),
    col("k", Field::Number, "elliptic modulus k"),
    col("c", Field::Number, "c R"),
    col(
        "closure_residual",
        Field::Number,
        "closure residual in radians",
    ),
    col(
        "lowest",
        Field::Integer,
        "1 where the state is the lowest at its length",
    ),
    col(
        "attached",
        Field::Integer,
        "1 where the loop lies on the wall everywhere",
    ),
    col(
        "contact_fraction",
        Field::Number,
        "length fraction touching the wall",
    ),
    col(
        "contact_intervals",
        Field::Integer,
        "number of contact intervals",
    ),
    col("max_gap", Field::Number, "largest gap (R - |r|)/R"),
    col("gap_min", Field::Number, "smallest gap /R"),
    col("complementarity", Field::Number, "largest |lambda gap|"),
    col(
        "stationarity",
        Field::Number,
        "stationarity residual of the 3-D model",
    ),
    col(
        "cells",
        Field::Integer,
        "cells of the reported state (0: exact)",
    ),
    col("source", Field::Text, "where the state comes from"),
    col(
        "surface_energy",
        Field::Number,
        "energy of the branch's surface loop at this length",
    ),
];

/// The dictionary entry of column `name`.
pub fn column(name: &str) -> Option<&'static ColumnSpec> {
    COLUMNS.iter().find(|c| c.name == name)
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
    /// Stability index on one side.
    pub index_before: usize,
    /// Stability index on the other side.
    pub index_after: usize,
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
    /// The engine's own `summary.json` keys.
    pub extra: BTreeMap<String, serde_json::Value>,
}

/// Keys of `summary.json` the schema writes itself.
const OWN_KEYS: &[&str] = &[
    "schema_version",
    "model",
    "scene",
    "accuracy",
    "critical",
    "special_points",
    "certificate",
    "warnings",
    "timings",
    "units",
    "states_dir",
    "run_id",
];

impl Diagram {
    /// An empty diagram of `model` for `scene` over `axes`.
    pub fn new(model: &str, scene: &str, axes: Vec<Axis>, units: &str) -> Self {
        Self {
            version: VERSION,
            model: model.into(),
            scene: scene.into(),
            accuracy: None,
            axes,
            columns: Vec::new(),
            points: Vec::new(),
            curves: Vec::new(),
            critical: Vec::new(),
            special: None,
            certificate: None,
            warnings: None,
            timings: None,
            units: units.into(),
            states_dir: None,
            run_id: None,
            extra: BTreeMap::new(),
        }
    }

    /// Set an engine's own summary key from a typed value, checking that it holds no
    /// non-finite number (serde_json would turn one into `null`).
    pub fn put<T: Serialize + ?Sized>(&mut self, key: &str, value: &T) -> Result<(), SchemaError> {
        let v = checked_value(key, value)?;
        self.extra.insert(key.into(), v);
        Ok(())
    }

    /// Set the certificate from a typed value (checked like [`Diagram::put`]).
    pub fn set_certificate<T: Serialize + ?Sized>(&mut self, value: &T) -> Result<(), SchemaError> {
        self.certificate = Some(checked_value("certificate", value)?);
        Ok(())
    }

    /// Set the timings from a typed record of seconds (a struct of `f64` fields).
    pub fn set_timings<T: Serialize + ?Sized>(&mut self, value: &T) -> Result<(), SchemaError> {
        let v = checked_value("timings", value)?;
        let map = serde_json::from_value(v).map_err(|e| SchemaError::NotFiniteValue {
            key: "timings".into(),
            message: format!("not a record of seconds: {e}"),
        })?;
        self.timings = Some(map);
        Ok(())
    }

    /// `branches.csv`, checked (every value finite, every point value with a column).
    pub fn branches_csv(&self) -> Result<Vec<u8>, SchemaError> {
        let file = "branches.csv";
        let specs = self
            .columns
            .iter()
            .map(|c| column(c).ok_or_else(|| SchemaError::UnknownColumn(c.clone())))
            .collect::<Result<Vec<_>, _>>()?;
        let has = |f: Field| specs.iter().any(|s| s.field == f);
        let mut w = csv::Writer::from_writer(Vec::new());
        w.write_record(&self.columns).map_err(csv_err(file))?;
        for (r, p) in self.points.iter().enumerate() {
            let row = r + 1;
            for (field, set) in [
                ("family", p.family.is_some() && !has(Field::Family)),
                ("sheet", p.sheet.is_some() && !has(Field::Sheet)),
                (
                    "energy_error",
                    p.energy_error.is_some() && !has(Field::EnergyError),
                ),
                ("index", p.index.is_some() && !has(Field::Index)),
                ("label", p.label.is_some() && !has(Field::Label)),
                (
                    "state_file",
                    p.state_file.is_some() && !has(Field::StateFile),
                ),
            ] {
                if set {
                    return Err(SchemaError::NoColumn { row, field });
                }
            }
            if let Some(k) = p.extra.keys().find(|k| !self.columns.contains(k)) {
                return Err(SchemaError::NoColumn {
                    row,
                    field: column(k).map_or("an unknown column", |c| c.name),
                });
            }
            let mut rec = Vec::with_capacity(specs.len());
            for s in &specs {
                let num = |v: f64| -> Result<String, SchemaError> {
                    if v.is_finite() {
                        Ok(format!("{v}"))
                    } else {
                        Err(SchemaError::NotFinite {
                            file: file.into(),
                            column: s.name.into(),
                            row,
                            value: v,
                        })
                    }
                };
                let opt = |v: Option<f64>| v.map_or(Ok(String::new()), num);
                rec.push(match s.field {
                    Field::Branch => p.branch.to_string(),
                    Field::Eta => p.eta.to_string(),
                    Field::Family => p.family.map_or(String::new(), |v| v.to_string()),
                    Field::Sheet => p.sheet.map_or(String::new(), |v| v.to_string()),
                    Field::Coord => {
                        let i = self.axes.iter().position(|a| a.name == s.name);
                        opt(i.and_then(|i| p.coords.get(i).copied()))?
                    }
                    Field::Energy => num(p.energy)?,
                    Field::EnergyError => opt(p.energy_error)?,
                    Field::Index => p.index.map_or(String::new(), |v| v.to_string()),
                    Field::Label => p.label.clone().unwrap_or_default(),
                    Field::StateFile => p.state_file.clone().unwrap_or_default(),
                    Field::Number | Field::Integer | Field::Text => {
                        match p.extra.get(s.name).unwrap_or(&Cell::Empty) {
                            Cell::F(v) => num(*v)?,
                            Cell::I(v) => v.to_string(),
                            Cell::S(t) => t.clone(),
                            Cell::Empty => String::new(),
                        }
                    }
                });
            }
            w.write_record(&rec).map_err(csv_err(file))?;
        }
        w.into_inner().map_err(|e| SchemaError::Parse {
            path: file.into(),
            message: e.to_string(),
        })
    }

    /// `critical.csv`.
    pub fn critical_csv(&self) -> Result<Vec<u8>, SchemaError> {
        let file = "critical.csv";
        let mut w = csv::Writer::from_writer(Vec::new());
        w.write_record(CRITICAL_COLUMNS).map_err(csv_err(file))?;
        for (r, c) in self.critical.iter().enumerate() {
            let num = finite_in(file, r + 1);
            w.write_record([
                c.index.to_string(),
                num("lbar_cr", c.lbar_cr)?,
                c.kind.clone(),
                c.from_branch.to_string(),
                c.to_branch.to_string(),
                num("energy", c.energy)?,
                num("error_estimate", c.error_estimate)?,
            ])
            .map_err(csv_err(file))?;
        }
        w.into_inner().map_err(|e| SchemaError::Parse {
            path: file.into(),
            message: e.to_string(),
        })
    }

    /// `special_points.csv` (`None` when the model locates no special points).
    pub fn special_csv(&self) -> Result<Option<Vec<u8>>, SchemaError> {
        let Some(special) = &self.special else {
            return Ok(None);
        };
        let file = "special_points.csv";
        let mut w = csv::Writer::from_writer(Vec::new());
        w.write_record(SPECIAL_COLUMNS).map_err(csv_err(file))?;
        for (r, p) in special.iter().enumerate() {
            let num = finite_in(file, r + 1);
            w.write_record([
                p.kind.clone(),
                num("lbar", p.lbar)?,
                num("energy", p.energy)?,
                p.branch.to_string(),
                p.family.to_string(),
                p.index_before.to_string(),
                p.index_after.to_string(),
                p.error_estimate
                    .map_or(Ok(String::new()), |v| num("error_estimate", v))?,
            ])
            .map_err(csv_err(file))?;
        }
        w.into_inner().map(Some).map_err(|e| SchemaError::Parse {
            path: file.into(),
            message: e.to_string(),
        })
    }

    /// `summary.json` as a JSON object without `null` (absent values are left out) and with
    /// every number checked finite.
    pub fn summary(&self) -> Result<serde_json::Value, SchemaError> {
        let mut map = serde_json::Map::new();
        let mut put = |key: &str, v: serde_json::Value| {
            map.insert(key.to_string(), v);
        };
        put("schema_version", self.version.into());
        put("model", self.model.clone().into());
        put("scene", self.scene.clone().into());
        if let Some(a) = &self.accuracy {
            put("accuracy", a.clone().into());
        }
        for a in &self.axes {
            put(&format!("{}_min", a.name), checked_value("axis", &a.min)?);
            put(&format!("{}_max", a.name), checked_value("axis", &a.max)?);
        }
        put("critical", checked_value("critical", &self.critical)?);
        if let Some(s) = &self.special {
            put("special_points", checked_value("special_points", s)?);
        }
        if !self.curves.is_empty() {
            put("branches", checked_value("branches", &self.curves)?);
        }
        if let Some(c) = &self.certificate {
            put("certificate", c.clone());
        }
        if let Some(w) = &self.warnings {
            put("warnings", checked_value("warnings", w)?);
        }
        if let Some(t) = &self.timings {
            put("timings", checked_value("timings", t)?);
        }
        put("units", self.units.clone().into());
        if let Some(s) = &self.states_dir {
            put("states_dir", s.clone().into());
        }
        if let Some(r) = &self.run_id {
            put("run_id", r.clone().into());
        }
        for (k, v) in &self.extra {
            if map.contains_key(k) || OWN_KEYS.contains(&k.as_str()) || self.is_axis_key(k) {
                return Err(SchemaError::KeyClash(k.clone()));
            }
            map.insert(k.clone(), v.clone());
        }
        Ok(strip_nulls(serde_json::Value::Object(map)))
    }

    fn is_axis_key(&self, k: &str) -> bool {
        self.axes
            .iter()
            .any(|a| k == format!("{}_min", a.name) || k == format!("{}_max", a.name))
    }

    /// Every file of the diagram directory, `summary.json` last: `(name, bytes)`.
    pub fn files(&self) -> Result<Vec<(String, Vec<u8>)>, SchemaError> {
        let mut out = vec![
            ("branches.csv".to_string(), self.branches_csv()?),
            ("critical.csv".to_string(), self.critical_csv()?),
        ];
        if let Some(s) = self.special_csv()? {
            out.push(("special_points.csv".into(), s));
        }
        let text =
            serde_json::to_string_pretty(&self.summary()?).map_err(|e| SchemaError::Parse {
                path: "summary.json".into(),
                message: e.to_string(),
            })?;
        out.push(("summary.json".into(), format!("{text}\n").into_bytes()));
        Ok(out)
    }

    /// Write [`Diagram::files`] into `dir` (which must exist).
    pub fn write(&self, dir: &Path) -> Result<(), SchemaError> {
        for (name, bytes) in self.files()? {
            let path = dir.join(&name);
            std::fs::write(&path, bytes).map_err(|source| SchemaError::Io {
                path: path.display().to_string(),
                source,
            })?;
        }
        Ok(())
    }

    /// Read a diagram directory written by [`Diagram::write`] (or by `rodloop diagram`).
    pub fn read(dir: &Path) -> Result<Self, SchemaError> {
        let spath = dir.join("summary.json");
        let text = read_file(&spath)?;
        let src = spath.display().to_string();
        let perr = |m: String| SchemaError::Parse {
            path: src.clone(),
            message: m,
        };
        let serde_json::Value::Object(mut map) =
            serde_json::from_str::<serde_json::Value>(&text).map_err(|e| perr(e.to_string()))?
        else {
            return Err(perr("not a JSON object".into()));
        };
        let mut take = |k: &str| map.remove(k);
        fn typed<T: serde::de::DeserializeOwned>(
            v: Option<serde_json::Value>,
            key: &str,
            src: &str,
        ) -> Result<Option<T>, SchemaError> {
            v.map(|v| {
                serde_json::from_value(v).map_err(|e| SchemaError::Parse {
                    path: src.into(),
                    message: format!("{key}: {e}"),
                })
            })
            .transpose()
        }
        let version = typed(take("schema_version"), "schema_version", &src)?.unwrap_or(VERSION);
        let model: String = typed(take("model"), "model", &src)?.unwrap_or_default();
        let scene: String = typed(take("scene"), "scene", &src)?.unwrap_or_default();
        let accuracy = typed(take("accuracy"), "accuracy", &src)?;
        let critical = typed(take("critical"), "critical", &src)?.unwrap_or_default();
        let special = typed(take("special_points"), "special_points", &src)?;
        let certificate = take("certificate");
        let warnings = typed(take("warnings"), "warnings", &src)?;
        let timings = typed(take("timings"), "timings", &src)?;
        let units = typed(take("units"), "units", &src)?.unwrap_or_default();
        let states_dir = typed(take("states_dir"), "states_dir", &src)?;
        let run_id = typed(take("run_id"), "run_id", &src)?;
        // The sheets of a traced diagram are a list; the exact layer writes a count there.
        let curves = match take("branches") {
            Some(v @ serde_json::Value::Array(_)) => typed(Some(v), "branches", &src)?.unwrap(),
            Some(other) => {
                map.insert("branches".into(), other);
                Vec::new()
            }
            None => Vec::new(),
        };
        // Axes: the `NAME_min`/`NAME_max` pairs (the branch diagram's `lbar`).
        let mut axes = Vec::new();
        let names: Vec<String> = map
            .keys()
            .filter_map(|k| k.strip_suffix("_min").map(str::to_string))
            .filter(|n| map.contains_key(&format!("{n}_max")))
            .collect();
        for n in names {
            let min = typed(map.remove(&format!("{n}_min")), "axis", &src)?.unwrap_or(0.0);
            let max = typed(map.remove(&format!("{n}_max")), "axis", &src)?.unwrap_or(0.0);
            axes.push(Axis { name: n, min, max });
        }
        let (columns, points) = read_points(&dir.join("branches.csv"), &axes)?;
        Ok(Diagram {
            version,
            model,
            scene,
            accuracy,
            axes,
            columns,
            points,
            curves,
            critical,
            special,
            certificate,
            warnings,
            timings,
            units,
            states_dir,
            run_id,
            extra: map.into_iter().collect(),
        })
    }
}

/// Columns of `critical.csv`.
pub const CRITICAL_COLUMNS: &[&str] = &[
    "index",
    "lbar_cr",
    "kind",
    "from_branch",
    "to_branch",
    "energy",
    "error_estimate",
];

/// Columns of `special_points.csv`.
pub const SPECIAL_COLUMNS: &[&str] = &[
    "kind",
    "lbar",
    "energy",
    "branch",
    "family",
    "index_before",
    "index_after",
    "error_estimate",
];

fn csv_err(file: &str) -> impl Fn(csv::Error) -> SchemaError + '_ {
    move |e| SchemaError::Parse {
        path: file.into(),
        message: e.to_string(),
    }
}

fn finite_in(file: &str, row: usize) -> impl Fn(&str, f64) -> Result<String, SchemaError> + '_ {
    move |column, v| {
        if v.is_finite() {
            Ok(format!("{v}"))
        } else {
            Err(SchemaError::NotFinite {
                file: file.into(),
                column: column.into(),
                row,
                value: v,
            })
        }
    }
}

fn checked_value<T: Serialize + ?Sized>(
    key: &str,
    value: &T,
) -> Result<serde_json::Value, SchemaError> {
    check_finite(value).map_err(|message| SchemaError::NotFiniteValue {
        key: key.into(),
        message,
    })?;
    serde_json::to_value(value).map_err(|e| SchemaError::NotFiniteValue {
        key: key.into(),
        message: e.to_string(),
    })
}

/// Drop the keys whose value is `null` from a JSON value: they stand for absent optional
/// values (`None`). serde_json turns a non-finite float into `null` too, so a value must be
/// checked with [`check_finite`] on its typed form before it is turned into JSON.
pub fn strip_nulls(v: serde_json::Value) -> serde_json::Value {
    match v {
        serde_json::Value::Object(map) => serde_json::Value::Object(
            map.into_iter()
                .filter(|(_, v)| !v.is_null())
                .map(|(k, v)| (k, strip_nulls(v)))
                .collect(),
        ),
        serde_json::Value::Array(a) => {
            serde_json::Value::Array(a.into_iter().map(strip_nulls).collect())
        }
        other => other,
    }
}

fn read_file(path: &Path) -> Result<String, SchemaError> {
    std::fs::read_to_string(path).map_err(|source| SchemaError::Io {
        path: path.display().to_string(),
        source,
    })
}

/// `branches.csv` back into points (columns typed by [`COLUMNS`]).
fn read_points(path: &Path, axes: &[Axis]) -> Result<(Vec<String>, Vec<Point>), SchemaError> {
    let src = path.display().to_string();
    let text = read_file(path)?;
    let mut rdr = csv::Reader::from_reader(text.as_bytes());
    let columns: Vec<String> = rdr
        .headers()
        .map_err(|e| SchemaError::Parse {
            path: src.clone(),
            message: e.to_string(),
        })?
        .iter()
        .map(str::to_string)
        .collect();
    let specs = columns
        .iter()
        .map(|c| column(c).ok_or_else(|| SchemaError::UnknownColumn(c.clone())))
        .collect::<Result<Vec<_>, _>>()?;
    let mut points = Vec::new();
    for (r, rec) in rdr.records().enumerate() {
        let rec = rec.map_err(|e| SchemaError::Parse {
            path: src.clone(),
            message: e.to_string(),
        })?;
        let mut p = Point {
            coords: vec![f64::NAN; axes.len()],
            ..Point::default()
        };
        for (s, cell) in specs.iter().zip(rec.iter()) {
            let bad = || SchemaError::Parse {
                path: src.clone(),
                message: format!("row {}: column {}: cannot read {cell:?}", r + 2, s.name),
            };
            let float = || -> Result<Option<f64>, SchemaError> {
                if cell.is_empty() {
                    return Ok(None);
                }
                match cell.parse::<f64>() {
                    Ok(v) if v.is_finite() => Ok(Some(v)),
                    _ => Err(bad()),
                }
            };
            let int = || -> Result<Option<i64>, SchemaError> {
                if cell.is_empty() {
                    Ok(None)
                } else {
                    cell.parse::<i64>().map(Some).map_err(|_| bad())
                }
            };
            let uint = || -> Result<Option<u32>, SchemaError> {
                int()?
                    .map(|v| u32::try_from(v).map_err(|_| bad()))
                    .transpose()
            };
            match s.field {
                Field::Branch => p.branch = uint()?.ok_or_else(bad)?,
                Field::Eta => p.eta = uint()?.ok_or_else(bad)?,
                Field::Family => p.family = uint()?,
                Field::Sheet => p.sheet = uint()?,
                Field::Coord => {
                    if let Some(i) = axes.iter().position(|a| a.name == s.name) {
                        p.coords[i] = float()?.ok_or_else(bad)?;
                    }
                }
                Field::Energy => p.energy = float()?.ok_or_else(bad)?,
                Field::EnergyError => p.energy_error = float()?,
                Field::Index => p.index = uint()?.map(|v| v as usize),
                Field::Label => p.label = Some(cell.to_string()),
                Field::StateFile => p.state_file = Some(cell.to_string()),
                Field::Number => {
                    p.extra
                        .insert(s.name.into(), float()?.map_or(Cell::Empty, Cell::F));
                }
                Field::Integer => {
                    p.extra
                        .insert(s.name.into(), int()?.map_or(Cell::Empty, Cell::I));
                }
                Field::Text => {
                    p.extra.insert(s.name.into(), Cell::S(cell.to_string()));
                }
            }
        }
        points.push(p);
    }
    Ok((columns, points))
}
