//! The reader of the schema: a diagram directory back into a [`Diagram`].

use std::path::Path;

use crate::{column, Axis, Cell, Diagram, Field, Parameter, Point, SchemaError, VERSION};

impl Diagram {
    /// Read a diagram directory written by [`Diagram::write`] (or by `rodloop diagram`,
    /// `rodloop diagram --param`, `rodloop phase`: its `summary.json`).
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
        let parameter = match (take("param"), take("scene_value"), take("target")) {
            (Some(name), Some(scene_value), Some(target)) => Some(Parameter {
                name: typed(Some(name), "param", &src)?.unwrap_or_default(),
                scene_value: typed(Some(scene_value), "scene_value", &src)?.unwrap_or(0.0),
                target: typed(Some(target), "target", &src)?.unwrap_or(0.0),
            }),
            (None, None, None) => None,
            _ => {
                return Err(SchemaError::Parse {
                    path: src.clone(),
                    message: "param, scene_value and target come together (the parameter of a diagram against a parameter)".into(),
                })
            }
        };
        let exchange_curves = typed(take("curves"), "curves", &src)?;
        let families = typed(take("families"), "families", &src)?;
        let notes = typed(take("notes"), "notes", &src)?;
        let lowest_lifted_off = typed(take("lowest_lifted_off"), "lowest_lifted_off", &src)?;
        // The sheets of a traced diagram are a list; the exact layer writes a count there.
        let curves = match take("branches") {
            Some(v @ serde_json::Value::Array(_)) => typed(Some(v), "branches", &src)?.unwrap(),
            Some(other) => {
                map.insert("branches".into(), other);
                Vec::new()
            }
            None => Vec::new(),
        };
        // Axes: in their written order, or the `NAME_min`/`NAME_max` pairs of a diagram with
        // one axis (the branch diagram's `lbar`).
        let mut axes: Vec<Axis> = typed(map.remove("axes"), "axes", &src)?.unwrap_or_default();
        for a in &axes {
            map.remove(&format!("{}_min", a.name));
            map.remove(&format!("{}_max", a.name));
        }
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
        // A diagram over no axes (the phase diagram) may have no branches.csv.
        let branches = dir.join("branches.csv");
        let (columns, points) = if axes.is_empty() && !branches.exists() {
            (Vec::new(), Vec::new())
        } else {
            read_points(&branches, &axes)?
        };
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
            parameter,
            exchange_curves,
            families,
            notes,
            lowest_lifted_off,
            extra: map.into_iter().collect(),
        })
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
        .map(|c| {
            column(c).ok_or_else(|| SchemaError::Parse {
                path: src.clone(),
                message: format!(
                    "unknown column `{c}` (every column of branches.csv is named in rodloop_schema::COLUMNS)"
                ),
            })
        })
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
                message: format!(
                    "row {}: column `{}` holds {cell:?}, not {}",
                    r + 2,
                    s.name,
                    match s.field {
                        Field::Coord | Field::Energy | Field::EnergyError | Field::Number =>
                            "a finite number",
                        _ => "an integer in the column's range",
                    }
                ),
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
