//! A diagram directory read for drawing: the result schema's reader
//! ([`rodloop_schema::Diagram::read`]: `summary.json` and the typed columns of `branches.csv`)
//! of any model into [`DiagramData`], with the energy made relative
//! to the stable state on request ([`DiagramData::relative_to_stable`]). The figures drawn
//! from it are in [`crate::diagram`].

use std::path::Path;

use rodloop_schema::{Cell, Diagram, Point, SchemaError};

use crate::FigureError;

/// Stability of a state, as far as the model knows it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Stability {
    /// Lowest energy at its length.
    Stable,
    /// A local minimum with a higher energy.
    Metastable,
    /// Higher energy, index not computed (exact model).
    Higher,
    /// Not a local minimum.
    Unstable,
}

/// One traced state of a branch.
#[derive(Clone, Debug)]
pub struct DiagramPoint {
    /// Paper branch number.
    pub branch: u32,
    /// Periods of κ_g.
    pub eta: u32,
    /// `L̄`.
    pub lbar: f64,
    /// `E R/(πD₀)`.
    pub energy: f64,
    /// Geodesic part `E_g R/(πD₀)`.
    pub energy_g: f64,
    /// Smallest `λR³/D₀`.
    pub lambda_min: f64,
    /// Largest `λR³/D₀`.
    pub lambda_max: f64,
    /// Stability label.
    pub stability: Stability,
    /// Family within the branch (`family` column of non-uniform rods; 0 otherwise).
    pub family: u32,
    /// Position along the family (`arc` column: sheet · 10⁶ + rank in arclength order);
    /// `None` without the column (points are then drawn in increasing `L̄`).
    pub arc: Option<u64>,
    /// Enclosed diagrams (`attached` column): whether the state lies on the wall
    /// everywhere; `None` for surface diagrams.
    pub attached: Option<bool>,
    /// The energy subtracted from `energy` by [`DiagramData::relative_to_stable`] (0
    /// otherwise), so that `energy + shift` is the state's own energy.
    pub shift: f64,
}

/// A special point of the diagram (fold, branch point, lift-off, landing, detachment).
#[derive(Clone, Debug)]
pub struct SpecialMark {
    /// `fold`, `branch_point`, `lift-off`, `landing` or `detachment` (enclosed diagrams).
    pub kind: String,
    /// `L̄`.
    pub lbar: f64,
    /// Energy there.
    pub energy: f64,
}

/// A critical length.
#[derive(Clone, Debug)]
pub struct CriticalPoint {
    /// `L̄_icr`.
    pub lbar_cr: f64,
    /// `crossing` (two branches' energies equal) or `collapse` (onto a great circle).
    pub kind: String,
    /// Energy there.
    pub energy: f64,
    /// Index `i`.
    pub index: usize,
}

/// A diagram read back through the result schema.
#[derive(Clone, Debug)]
pub struct DiagramData {
    /// `model` of `summary.json`: `exact` (labelled by its `lowest` column), `numeric` (a
    /// `stability` column) or `enclosed` (a `label` and an `attached` column).
    pub model: String,
    /// Columns the file lacks that some figures need (`energy_g`, `lambda_max`: the enclosed
    /// diagram has neither); their values are NaN and those figures are refused.
    pub missing: Vec<String>,
    /// States.
    pub points: Vec<DiagramPoint>,
    /// Critical lengths.
    pub critical: Vec<CriticalPoint>,
    /// Folds, branch points and wall events of the diagram (empty when its model locates none).
    pub special: Vec<SpecialMark>,
    /// Whether the great-circle buckling loads of Eqs. (33)–(34) apply (a uniform rod): the
    /// contact-force figure marks them only then. [`DiagramData::read`] sets it for the exact
    /// model and for a numeric diagram whose rows all have family 0 (the `family` column is 0
    /// for a uniform rod; a non-uniform rod's branches are families numbered from 1); a
    /// caller that knows the stiffness may set it itself.
    pub buckling_loads: bool,
    /// Energies are relative to the stable state at each length
    /// ([`DiagramData::relative_to_stable`]).
    pub relative: bool,
}

/// A column of `branches.csv` that a figure needs, absent: the error names the file and the
/// columns that are there.
fn missing(path: &str, column: &str, d: &Diagram) -> FigureError {
    FigureError::MissingColumn {
        path: path.into(),
        column: column.into(),
        found: d.columns.join(", "),
    }
}

/// A number of a point's column (`None`: an empty cell).
fn number(p: &Point, column: &str) -> Option<f64> {
    match p.extra.get(column) {
        Some(Cell::F(v)) => Some(*v),
        Some(Cell::I(v)) => Some(*v as f64),
        _ => None,
    }
}

impl DiagramData {
    /// Read a diagram directory through the result schema ([`Diagram::read`]: `summary.json`
    /// and `branches.csv`, every column typed by [`rodloop_schema::COLUMNS`]); the critical
    /// lengths and special points are those of `summary.json`.
    pub fn read(dir: &Path) -> Result<Self, FigureError> {
        let summary = dir.join("summary.json");
        let d = match Diagram::read(dir) {
            Ok(d) => d,
            Err(SchemaError::Io { source, .. })
                if source.kind() == std::io::ErrorKind::NotFound && !summary.exists() =>
            {
                return Err(FigureError::Diagram(format!(
                    "{} is not a diagram directory: it has no summary.json (rodloop diagram writes it beside branches.csv)",
                    dir.display()
                )))
            }
            Err(e) => return Err(e.into()),
        };
        Self::from_schema(&d, &dir.join("branches.csv").display().to_string())
    }

    /// The figures' view of a diagram in the schema; `path` names its `branches.csv` in
    /// errors.
    pub fn from_schema(d: &Diagram, path: &str) -> Result<Self, FigureError> {
        let model = d.model.as_str();
        if !["exact", "numeric", "enclosed"].contains(&model) {
            return Err(FigureError::Diagram(format!(
                "{path}: a diagram of model `{model}` (summary.json); the diagram figures draw the exact, numeric and enclosed models"
            )));
        }
        // A diagram in L̄: one axis, `lbar` (a diagram against a parameter draws its own figure).
        let lbar = match &d.axes[..] {
            [a] if a.name == "lbar" => 0,
            axes => {
                return Err(FigureError::Diagram(format!(
                    "{path}: a diagram over {} (summary.json); the diagram figures draw diagrams in lbar only",
                    axes.iter().map(|a| a.name.as_str()).collect::<Vec<_>>().join(", ")
                )))
            }
        };
        if d.points.is_empty() {
            return Err(FigureError::TooFewRows {
                path: path.into(),
                needed: 1,
                found: 0,
            });
        }
        let enclosed = model == "enclosed";
        let has = |c: &str| d.columns.iter().any(|n| n == c);
        // The columns every figure needs; the enclosed diagram has no energy split and no
        // largest contact force (those figures are refused).
        let label = match model {
            "numeric" => Some("stability"),
            "enclosed" => Some("label"),
            _ => None,
        };
        let needed = ["branch", "eta", "lbar", "energy", "lambda_min"]
            .into_iter()
            .chain(label)
            .chain(if enclosed { None } else { Some("energy_g") })
            .chain(if enclosed { None } else { Some("lambda_max") })
            .chain(if enclosed { Some("attached") } else { None })
            .chain(if label.is_none() {
                Some("lowest")
            } else {
                None
            });
        for c in needed {
            if !has(c) {
                return Err(missing(path, c, d));
            }
        }
        let missing_cols: Vec<String> = ["energy_g", "lambda_max"]
            .into_iter()
            .filter(|c| !has(c))
            .map(str::to_string)
            .collect();
        let mut points = Vec::with_capacity(d.points.len());
        for (r, p) in d.points.iter().enumerate() {
            let row = r + 2;
            let empty = |column: &str| FigureError::NotFinite {
                path: path.into(),
                row,
                column: column.into(),
                value: String::new(),
            };
            // Columns the reader types as numbers: an empty cell is refused for a column a
            // figure needs, and stands for NaN in one the file lacks.
            let value = |c: &str| -> Result<f64, FigureError> {
                if !has(c) {
                    return Ok(f64::NAN);
                }
                number(p, c).ok_or_else(|| empty(c))
            };
            let stability = match label {
                Some(col) => match p.label.as_deref() {
                    Some("stable") => Stability::Stable,
                    Some("metastable") => Stability::Metastable,
                    Some("unstable") => Stability::Unstable,
                    other => {
                        return Err(FigureError::Diagram(format!(
                            "{path}: row {row}: column `{col}` must be stable, metastable or unstable (got {:?})",
                            other.unwrap_or("")
                        )))
                    }
                },
                None => {
                    if value("lowest")? != 0.0 {
                        Stability::Stable
                    } else {
                        Stability::Higher
                    }
                }
            };
            let arc = match p.extra.get("arc") {
                Some(Cell::I(v)) => {
                    Some(u64::try_from(*v).map_err(|_| FigureError::NotFinite {
                        path: path.into(),
                        row,
                        column: "arc".into(),
                        value: v.to_string(),
                    })?)
                }
                Some(Cell::Empty) => return Err(empty("arc")),
                _ => None,
            };
            points.push(DiagramPoint {
                branch: p.branch,
                eta: p.eta,
                lbar: p.coords[lbar],
                energy: p.energy,
                energy_g: value("energy_g")?,
                lambda_min: value("lambda_min")?,
                lambda_max: value("lambda_max")?,
                stability,
                family: p.family.unwrap_or(0),
                arc,
                attached: if enclosed {
                    Some(value("attached")? != 0.0)
                } else {
                    None
                },
                shift: 0.0,
            });
        }
        let critical = d
            .critical
            .iter()
            .map(|c| CriticalPoint {
                lbar_cr: c.lbar_cr,
                kind: c.kind.clone(),
                energy: c.energy,
                index: c.index,
            })
            .collect();
        let special = d
            .special
            .iter()
            .flatten()
            .filter(|s| {
                ["fold", "branch_point", "lift-off", "landing", "detachment"]
                    .contains(&s.kind.as_str())
            })
            .map(|s| SpecialMark {
                kind: s.kind.clone(),
                lbar: s.lbar,
                energy: s.energy,
            })
            .collect();
        let buckling_loads = model == "exact"
            || (model == "numeric" && points.iter().all(|p: &DiagramPoint| p.family == 0));
        Ok(DiagramData {
            model: model.into(),
            missing: missing_cols,
            points,
            critical,
            special,
            buckling_loads,
            relative: false,
        })
    }

    /// The stable energy at `lbar`: linear interpolation between the states labelled stable
    /// (the lowest energy at their length), held constant beyond the first and last.
    fn stable_energy(stable: &[(f64, f64)], lbar: f64) -> f64 {
        let k = stable.partition_point(|p| p.0 < lbar);
        if k == 0 {
            return stable[0].1;
        }
        if k == stable.len() {
            return stable[k - 1].1;
        }
        let (a, b) = (stable[k - 1], stable[k]);
        if b.0 - a.0 <= 0.0 {
            return a.1.min(b.1);
        }
        a.1 + (lbar - a.0) / (b.0 - a.0) * (b.1 - a.1)
    }

    /// Energies relative to the stable state at the same length: every energy (states,
    /// critical points, special points) minus the lowest energy there, linearly interpolated
    /// between the traced stable states and the critical points. Where every branch lies close to one line (a very
    /// soft segment: `E ≈ L̄ ⟨D⟩/D₀`), this shows how far above the stable state each one is.
    /// The energy split is left as it is.
    pub fn relative_to_stable(&mut self) -> Result<(), FigureError> {
        // The critical points lie on the lowest energy too (a crossing of the two lowest
        // branches, a collapse of the lowest onto a great circle): they anchor the
        // interpolation where the traced stable states are sparse.
        let mut stable: Vec<(f64, f64)> = self
            .points
            .iter()
            .filter(|p| p.stability == Stability::Stable)
            .map(|p| (p.lbar, p.energy))
            .chain(self.critical.iter().map(|c| (c.lbar_cr, c.energy)))
            .collect();
        if stable.is_empty() {
            return Err(FigureError::Invalid(
                "energies relative to the stable state need states labelled stable; this diagram has none".into(),
            ));
        }
        stable.sort_by(|a, b| a.0.total_cmp(&b.0));
        // One value per length: the lowest (two branches at a crossing).
        stable.dedup_by(|b, a| {
            if b.0 == a.0 {
                a.1 = a.1.min(b.1);
                true
            } else {
                false
            }
        });
        for p in &mut self.points {
            p.shift = Self::stable_energy(&stable, p.lbar);
            p.energy -= p.shift;
        }
        for c in &mut self.critical {
            c.energy -= Self::stable_energy(&stable, c.lbar_cr);
        }
        for m in &mut self.special {
            m.energy -= Self::stable_energy(&stable, m.lbar);
        }
        self.relative = true;
        Ok(())
    }
}
