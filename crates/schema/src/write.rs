//! The one writer of the schema: `branches.csv`, `critical.csv`, `special_points.csv` and
//! `summary.json`, every number checked finite, no `null`.

use std::collections::BTreeMap;
use std::path::Path;

use serde::Serialize;

use crate::{
    check_finite, column, Axis, Cell, Diagram, Field, SchemaError, CRITICAL_COLUMNS,
    SPECIAL_COLUMNS, VERSION,
};

/// Keys of `summary.json` the schema writes itself.
const OWN_KEYS: &[&str] = &[
    "schema_version",
    "axes",
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
    "param",
    "scene_value",
    "target",
    "curves",
    "families",
    "notes",
    "lowest_lifted_off",
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
            parameter: None,
            exchange_curves: None,
            families: None,
            notes: None,
            lowest_lifted_off: None,
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

    /// An engine's own summary key as a typed value (`None`: absent or not of that type).
    pub fn get<T: serde::de::DeserializeOwned>(&self, key: &str) -> Option<T> {
        self.extra
            .get(key)
            .and_then(|v| serde_json::from_value(v.clone()).ok())
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
                p.index_before.map_or(String::new(), |i| i.to_string()),
                p.index_after.map_or(String::new(), |i| i.to_string()),
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
        // Several axes: their order (that of every point's coordinates) is written too.
        if self.axes.len() > 1 {
            put("axes", checked_value("axes", &self.axes)?);
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
        if let Some(p) = &self.parameter {
            put("param", p.name.clone().into());
            put("scene_value", checked_value("scene_value", &p.scene_value)?);
            put("target", checked_value("target", &p.target)?);
        }
        if let Some(c) = &self.exchange_curves {
            put("curves", checked_value("curves", c)?);
        }
        if let Some(f) = &self.families {
            put("families", checked_value("families", f)?);
        }
        if let Some(n) = &self.notes {
            put("notes", checked_value("notes", n)?);
        }
        if let Some(l) = &self.lowest_lifted_off {
            put("lowest_lifted_off", checked_value("lowest_lifted_off", l)?);
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
        let mut out = Vec::new();
        // A diagram without points or columns (the phase diagram: its critical lengths only)
        // has no branches.csv.
        if !(self.columns.is_empty() && self.points.is_empty()) {
            out.push(("branches.csv".to_string(), self.branches_csv()?));
        }
        out.push(("critical.csv".to_string(), self.critical_csv()?));
        if let Some(s) = self.special_csv()? {
            out.push(("special_points.csv".into(), s));
        }
        out.push(("summary.json".into(), self.summary_json()?));
        Ok(out)
    }

    /// `summary.json` as written ([`Diagram::summary`], pretty-printed, a final newline): for
    /// a run whose tables are its own (`phase.csv`) and whose summary is the schema's.
    pub fn summary_json(&self) -> Result<Vec<u8>, SchemaError> {
        let text =
            serde_json::to_string_pretty(&self.summary()?).map_err(|e| SchemaError::Parse {
                path: "summary.json".into(),
                message: e.to_string(),
            })?;
        Ok(format!("{text}\n").into_bytes())
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
}

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
