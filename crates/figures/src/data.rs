//! Loop tables: `config.csv` (from `solve`), `loop-NN.csv` (from `analytic`), `curve.csv`
//! (from `euler`), or any CSV with columns `s, x, y, z` (a closed curve in order; the last
//! point joins the first).

use std::path::Path;

use nalgebra::Vector3;

use crate::FigureError;

/// Gap (units of `R`) above which a node of an enclosed loop counts as off the wall (the
/// enclosed solver's touching tolerance is 1e-9 R).
pub const GAP_TOUCH: f64 = 1e-9;

/// The wall contact of an enclosed loop ([`LoopData::wall_contact`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WallContact {
    /// Largest gap `(R − |r|)/R`.
    pub max_gap: f64,
    /// Fraction of the points on the wall (gap at most [`GAP_TOUCH`]).
    pub contact_fraction: f64,
    /// Smallest contact force `λR³/D₀`.
    pub lambda_min: f64,
}

/// A closed curve and its per-point columns.
#[derive(Clone, Debug)]
pub struct LoopData {
    /// Where it came from (for messages and titles).
    pub source: String,
    /// Column names, in file order.
    pub names: Vec<String>,
    /// Column values (column-major), all finite.
    pub columns: Vec<Vec<f64>>,
}

/// Label (with units) of a known column, for colour bars and axes.
pub fn column_label(name: &str) -> String {
    match name {
        "s" => "s/R (arclength)".into(),
        "x" => "x/R".into(),
        "y" => "y/R".into(),
        "z" => "z/R".into(),
        "kappa" => "κR (curvature)".into(),
        "tau" => "τR (torsion)".into(),
        "kappa_g" => "κ_g R (geodesic curvature)".into(),
        "lambda" => "λR³/D₀ (contact force)".into(),
        "F_t" => "F_t R²/D₀".into(),
        "F_n" => "F_n R²/D₀".into(),
        "F_b" => "F_b R²/D₀".into(),
        "D" => "D/D₀ (bending stiffness)".into(),
        "gap" => "gap (R − |r|)/R".into(),
        other => other.into(),
    }
}

impl LoopData {
    /// Read a CSV file (`#` starts a comment line).
    pub fn read(path: &Path) -> Result<Self, FigureError> {
        let src = path.display().to_string();
        let bytes = std::fs::read(path).map_err(|source| FigureError::Io {
            path: src.clone(),
            source,
        })?;
        Self::parse(&src, &bytes)
    }

    /// Parse CSV bytes; `source` names them in messages.
    pub fn parse(source: &str, bytes: &[u8]) -> Result<Self, FigureError> {
        let csv_err = |e: csv::Error| FigureError::Csv {
            path: source.into(),
            message: e.to_string(),
        };
        let mut rdr = csv::ReaderBuilder::new()
            .comment(Some(b'#'))
            .trim(csv::Trim::All)
            .from_reader(bytes);
        let names: Vec<String> = rdr
            .headers()
            .map_err(csv_err)?
            .iter()
            .map(str::to_string)
            .collect();
        let mut columns = vec![Vec::new(); names.len()];
        for (r, rec) in rdr.records().enumerate() {
            let rec = rec.map_err(csv_err)?;
            for (c, name) in names.iter().enumerate() {
                let cell = rec.get(c).unwrap_or("");
                let v: f64 = cell.parse().unwrap_or(f64::NAN);
                if !v.is_finite() {
                    return Err(FigureError::NotFinite {
                        path: source.into(),
                        row: r + 2,
                        column: name.clone(),
                        value: cell.into(),
                    });
                }
                columns[c].push(v);
            }
        }
        Self::new(source, names, columns)
    }

    /// Check and wrap columns: `s, x, y, z` present, at least 8 rows, `s` increasing.
    pub fn new(
        source: &str,
        names: Vec<String>,
        columns: Vec<Vec<f64>>,
    ) -> Result<Self, FigureError> {
        let d = LoopData {
            source: source.into(),
            names,
            columns,
        };
        for c in ["s", "x", "y", "z"] {
            if d.column(c).is_none() {
                return Err(FigureError::MissingColumn {
                    path: source.into(),
                    column: c.into(),
                    found: d.names.join(", "),
                });
            }
        }
        let n = d.len();
        if n < 8 {
            return Err(FigureError::TooFewRows {
                path: source.into(),
                needed: 8,
                found: n,
            });
        }
        if let Some(bad) = d.columns.iter().position(|c| c.len() != n) {
            return Err(FigureError::Csv {
                path: source.into(),
                message: format!("column {} has a different length", d.names[bad]),
            });
        }
        let s = d.s();
        if let Some(k) = (1..n).find(|&k| s[k] <= s[k - 1]) {
            return Err(FigureError::Invalid(format!(
                "{source}: column s must increase (row {} has s = {} after {})",
                k + 2,
                s[k],
                s[k - 1]
            )));
        }
        if d.radius() <= 0.0 {
            return Err(FigureError::Invalid(format!(
                "{source}: every point is at the origin"
            )));
        }
        Ok(d)
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.columns.first().map_or(0, Vec::len)
    }

    /// True when there are no points.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// A column by name.
    pub fn column(&self, name: &str) -> Option<&[f64]> {
        self.names
            .iter()
            .position(|n| n == name)
            .map(|i| self.columns[i].as_slice())
    }

    /// Arclength column.
    pub fn s(&self) -> &[f64] {
        self.column("s").unwrap_or(&[])
    }

    /// The points.
    pub fn points(&self) -> Vec<Vector3<f64>> {
        let (x, y, z) = (
            self.column("x").unwrap_or(&[]),
            self.column("y").unwrap_or(&[]),
            self.column("z").unwrap_or(&[]),
        );
        (0..self.len())
            .map(|i| Vector3::new(x[i], y[i], z[i]))
            .collect()
    }

    /// Largest distance from the origin (the sphere's radius for a loop on it).
    pub fn radius(&self) -> f64 {
        self.points().iter().map(|p| p.norm()).fold(0.0, f64::max)
    }

    /// Length of the closed curve. Points equally spaced in `s` (every table rodloop writes
    /// on a uniform mesh) close the loop with one more spacing: `L = n (s_last − s_0)/(n − 1)`,
    /// exact whatever the curvature. Otherwise: the last `s` plus the arc from the last point
    /// back to the first (on the sphere of radius [`LoopData::radius`]), which is short by the
    /// chord's sagitta.
    pub fn length(&self) -> f64 {
        let p = self.points();
        let s = self.s();
        let n = s.len();
        if n >= 3 {
            let h = (s[n - 1] - s[0]) / (n - 1) as f64;
            let uniform = h > 0.0
                && s.windows(2)
                    .all(|w| ((w[1] - w[0]) - h).abs() <= 1e-9 * h.max(1e-300));
            if uniform {
                return h * n as f64;
            }
        }
        let r = self.radius();
        let chord = (p[p.len() - 1] - p[0]).norm();
        let arc = 2.0 * r * (chord / (2.0 * r)).clamp(-1.0, 1.0).asin();
        s[s.len() - 1] - s[0] + arc
    }

    /// `L̄ = L/(2πR)`.
    pub fn lbar(&self) -> f64 {
        self.length() / (2.0 * std::f64::consts::PI * self.radius())
    }

    /// Whether the table has a `gap` column (enclosed scenes) with some gap above
    /// [`GAP_TOUCH`]: the loop has lifted off the wall there.
    pub fn lifted_off(&self) -> bool {
        self.column("gap")
            .is_some_and(|g| g.iter().any(|&v| v > GAP_TOUCH))
    }

    /// The wall contact of an enclosed loop from its `gap` and `lambda` columns: the largest
    /// gap (0 without a `gap` column), the fraction of points within [`GAP_TOUCH`] of the wall
    /// (0 without one) and the smallest contact force (`+∞` without a `lambda` column).
    pub fn wall_contact(&self) -> WallContact {
        let gap = self.column("gap").unwrap_or(&[]);
        let lam = self.column("lambda").unwrap_or(&[]);
        let touching = gap.iter().filter(|&&v| v <= GAP_TOUCH).count();
        WallContact {
            max_gap: gap.iter().fold(0.0f64, |m, &v| m.max(v)),
            contact_fraction: touching as f64 / gap.len().max(1) as f64,
            lambda_min: lam.iter().fold(f64::INFINITY, |m, &v| m.min(v)),
        }
    }

    /// Number of periods η of the geodesic curvature (half its sign changes round the loop),
    /// when the file has a `kappa_g` column.
    pub fn eta(&self) -> Option<u32> {
        let kg = self.column("kappa_g")?;
        let amp = kg.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        if amp < 1e-9 {
            return None;
        }
        let n = kg.len();
        let thr = 1e-9 * amp;
        let signs: Vec<f64> = kg
            .iter()
            .filter(|v| v.abs() > thr)
            .map(|v| v.signum())
            .collect();
        let m = signs.len();
        let changes = (0..m).filter(|&i| signs[i] != signs[(i + 1) % m]).count();
        let _ = n;
        if changes == 0 || changes % 2 != 0 {
            return None;
        }
        Some((changes / 2) as u32)
    }

    /// The column a picture is coloured by when none is chosen: `gap` for a loop that has
    /// lifted off the wall somewhere (an enclosed state with a gap above [`GAP_TOUCH`]), else
    /// `lambda`, else `gap`, else `kappa_g`, else `s`.
    pub fn default_color_column(&self) -> &'static str {
        if self.lifted_off() {
            return "gap";
        }
        for c in ["lambda", "gap", "kappa_g"] {
            if self.column(c).is_some() {
                return c;
            }
        }
        "s"
    }
}
