//! A diagram directory's tables read for drawing: `branches.csv`, `critical.csv` and
//! `special_points.csv` of either model into [`DiagramData`], with the energy made relative
//! to the stable state on request ([`DiagramData::relative_to_stable`]). The figures drawn
//! from it are in [`crate::diagram`].

use std::path::Path;

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

/// A special point of `special_points.csv` (fold, branch point, crossing, collapse).
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

/// A diagram read back from its CSV files.
#[derive(Clone, Debug)]
pub struct DiagramData {
    /// `exact` (a `lowest` column), `numeric` (a `stability` column) or `enclosed` (a
    /// `label` and an `attached` column).
    pub model: String,
    /// Columns the file lacks that some figures need (`energy_g`, `lambda_max`: the enclosed
    /// diagram has neither); their values are NaN and those figures are refused.
    pub missing: Vec<String>,
    /// States.
    pub points: Vec<DiagramPoint>,
    /// Critical lengths.
    pub critical: Vec<CriticalPoint>,
    /// Folds and branch points of `special_points.csv` (empty without the file).
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

/// Read a CSV as named text columns.
fn read_text(path: &Path) -> Result<(Vec<String>, Vec<Vec<String>>), FigureError> {
    let src = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|source| FigureError::Io {
        path: src.clone(),
        source,
    })?;
    let mut rdr = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .from_reader(&bytes[..]);
    let e = |e: csv::Error| FigureError::Csv {
        path: src.clone(),
        message: e.to_string(),
    };
    let names: Vec<String> = rdr
        .headers()
        .map_err(e)?
        .iter()
        .map(str::to_string)
        .collect();
    let mut rows = Vec::new();
    for r in rdr.records() {
        rows.push(r.map_err(e)?.iter().map(str::to_string).collect());
    }
    Ok((names, rows))
}

fn num_col(
    names: &[String],
    rows: &[Vec<String>],
    col: &str,
    src: &str,
) -> Result<Vec<f64>, FigureError> {
    let i = names
        .iter()
        .position(|n| n == col)
        .ok_or_else(|| FigureError::MissingColumn {
            path: src.into(),
            column: col.into(),
            found: names.join(", "),
        })?;
    rows.iter()
        .enumerate()
        .map(|(r, row)| {
            let cell = row.get(i).map(String::as_str).unwrap_or("");
            match cell.parse::<f64>() {
                Ok(v) if v.is_finite() => Ok(v),
                _ => Err(FigureError::NotFinite {
                    path: src.into(),
                    row: r + 2,
                    column: col.into(),
                    value: cell.into(),
                }),
            }
        })
        .collect()
}

impl DiagramData {
    /// Read `branches.csv` and `critical.csv` from a diagram directory.
    pub fn read(dir: &Path) -> Result<Self, FigureError> {
        let bpath = dir.join("branches.csv");
        let src = bpath.display().to_string();
        let (names, rows) = read_text(&bpath)?;
        if rows.is_empty() {
            return Err(FigureError::TooFewRows {
                path: src,
                needed: 1,
                found: 0,
            });
        }
        let col = |c: &str| num_col(&names, &rows, c, &src);
        let enclosed = names.iter().any(|n| n == "attached") && names.iter().any(|n| n == "label");
        let mut missing = Vec::new();
        // The enclosed diagram has no energy split and no largest contact force.
        let mut col_or_nan = |c: &str| -> Result<Vec<f64>, FigureError> {
            if enclosed && !names.iter().any(|n| n == c) {
                missing.push(c.to_string());
                Ok(vec![f64::NAN; rows.len()])
            } else {
                col(c)
            }
        };
        let (energy_g, lmax) = (col_or_nan("energy_g")?, col_or_nan("lambda_max")?);
        let (branch, eta, lbar, energy, lmin) = (
            col("branch")?,
            col("eta")?,
            col("lbar")?,
            col("energy")?,
            col("lambda_min")?,
        );
        let attached = if enclosed {
            Some(col("attached")?)
        } else {
            None
        };
        let (model, stability): (String, Vec<Stability>) = if let Some(i) = names
            .iter()
            .position(|n| n == "stability" || (enclosed && n == "label"))
        {
            let mut v = Vec::new();
            for (r, row) in rows.iter().enumerate() {
                v.push(match row.get(i).map(String::as_str) {
                        Some("stable") => Stability::Stable,
                        Some("metastable") => Stability::Metastable,
                        Some("unstable") => Stability::Unstable,
                        other => {
                            return Err(FigureError::Invalid(format!(
                                "{src}: row {}: stability (label) must be stable, metastable or unstable (got {:?})",
                                r + 2,
                                other.unwrap_or("")
                            )))
                        }
                    });
            }
            (if enclosed { "enclosed" } else { "numeric" }.into(), v)
        } else {
            let lowest = col("lowest")?;
            (
                "exact".into(),
                lowest
                    .iter()
                    .map(|&l| {
                        if l != 0.0 {
                            Stability::Stable
                        } else {
                            Stability::Higher
                        }
                    })
                    .collect(),
            )
        };
        let opt_col = |c: &str| -> Result<Option<Vec<f64>>, FigureError> {
            if names.iter().any(|n| n == c) {
                col(c).map(Some)
            } else {
                Ok(None)
            }
        };
        let family = opt_col("family")?;
        let arc = opt_col("arc")?;
        let points = (0..rows.len())
            .map(|k| DiagramPoint {
                family: family.as_ref().map_or(0, |f| f[k] as u32),
                arc: arc.as_ref().map(|a| a[k] as u64),
                attached: attached.as_ref().map(|a| a[k] != 0.0),
                shift: 0.0,
                branch: branch[k] as u32,
                eta: eta[k] as u32,
                lbar: lbar[k],
                energy: energy[k],
                energy_g: energy_g[k],
                lambda_min: lmin[k],
                lambda_max: lmax[k],
                stability: stability[k],
            })
            .collect();
        let cpath = dir.join("critical.csv");
        let mut critical = Vec::new();
        if cpath.exists() {
            let csrc = cpath.display().to_string();
            let (cn, cr) = read_text(&cpath)?;
            let lb = num_col(&cn, &cr, "lbar_cr", &csrc)?;
            let en = num_col(&cn, &cr, "energy", &csrc)?;
            let ix = num_col(&cn, &cr, "index", &csrc)?;
            let ki =
                cn.iter()
                    .position(|n| n == "kind")
                    .ok_or_else(|| FigureError::MissingColumn {
                        path: csrc.clone(),
                        column: "kind".into(),
                        found: cn.join(", "),
                    })?;
            for (k, row) in cr.iter().enumerate() {
                critical.push(CriticalPoint {
                    lbar_cr: lb[k],
                    energy: en[k],
                    index: ix[k] as usize,
                    kind: row.get(ki).cloned().unwrap_or_default(),
                });
            }
        }
        let spath = dir.join("special_points.csv");
        let mut special = Vec::new();
        if spath.exists() {
            let ssrc = spath.display().to_string();
            let (sn, sr) = read_text(&spath)?;
            let lb = num_col(&sn, &sr, "lbar", &ssrc)?;
            let en = num_col(&sn, &sr, "energy", &ssrc)?;
            let ki =
                sn.iter()
                    .position(|n| n == "kind")
                    .ok_or_else(|| FigureError::MissingColumn {
                        path: ssrc.clone(),
                        column: "kind".into(),
                        found: sn.join(", "),
                    })?;
            for (k, row) in sr.iter().enumerate() {
                let kind = row.get(ki).cloned().unwrap_or_default();
                if ["fold", "branch_point", "lift-off", "landing", "detachment"]
                    .contains(&kind.as_str())
                {
                    special.push(SpecialMark {
                        kind,
                        lbar: lb[k],
                        energy: en[k],
                    });
                }
            }
        }
        let buckling_loads = model == "exact"
            || (model == "numeric" && family.as_ref().is_none_or(|f| f.iter().all(|&x| x == 0.0)));
        Ok(DiagramData {
            model,
            missing,
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
