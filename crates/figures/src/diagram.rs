//! The branch diagram drawn from a diagram directory's `branches.csv` and `critical.csv`
//! (either model): energy against length (Fig. 3a), the geodesic / normal energy split
//! (Fig. 3b), the geodesic energy alone, and the contact-force extremes with the
//! great-circle buckling loads of Eqs. (33)–(34) for a uniform rod (Fig. 7).
//!
//! Line styles mean the same in both models: solid = stable (lowest energy at that length),
//! dashed = higher energy and not known to be unstable (metastable in the numeric model,
//! where the Hessian index is 0; the exact model computes no index), dotted = unstable
//! (Hessian index > 0, numeric model only).
//!
//! The file is longer than most because it is one job end to end: the tables of a diagram
//! directory read into [`DiagramData`] (with the energy made relative to the stable state on
//! request), and the four figures drawn from that one reading, so that every figure shows the
//! same rows with the same styles.

use std::collections::BTreeSet;
use std::path::Path;

use crate::color::branch_color;
use crate::plot::{LegendItem, Mark, Plot, Series, Shape};
use crate::svg::Svg;
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

impl Stability {
    fn style(self) -> (f64, &'static str) {
        match self {
            Stability::Stable => (2.6, ""),
            Stability::Metastable | Stability::Higher => (1.4, "7 4"),
            Stability::Unstable => (1.4, "1.5 3"),
        }
    }

    fn legend(self) -> &'static str {
        match self {
            Stability::Stable => "stable (lowest energy)",
            Stability::Metastable => "metastable (local min., higher E)",
            Stability::Higher => "higher E (index not computed)",
            Stability::Unstable => "unstable (Hessian index > 0)",
        }
    }
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

    fn branches(&self) -> Vec<(u32, u32)> {
        let set: BTreeSet<(u32, u32)> = self.points.iter().map(|p| (p.branch, p.eta)).collect();
        set.into_iter().collect()
    }

    /// Series of one quantity per branch, split where the stability changes; also returns
    /// the stabilities drawn.
    fn lines(
        &self,
        f: impl Fn(&DiagramPoint) -> f64,
        used: &mut BTreeSet<Stability>,
    ) -> Vec<Series> {
        let mut out = Vec::new();
        for (b, _) in self.branches() {
            let mut families: Vec<u32> = self
                .points
                .iter()
                .filter(|p| p.branch == b)
                .map(|p| p.family)
                .collect();
            families.sort_unstable();
            families.dedup();
            for fam in families {
                let mut pts: Vec<&DiagramPoint> = self
                    .points
                    .iter()
                    .filter(|p| p.branch == b && p.family == fam)
                    .collect();
                // A family in arclength order (one path through its folds), else by L̄.
                if pts.iter().all(|p| p.arc.is_some()) {
                    pts.sort_by_key(|p| p.arc);
                } else {
                    pts.sort_by(|a, c| a.lbar.total_cmp(&c.lbar));
                }
                // Pieces: split where the stability changes and where the family has a gap
                // (a sheet left out between two sheets: not adjacent in arclength).
                let gap = |a: &DiagramPoint, c: &DiagramPoint| match (a.arc, c.arc) {
                    (Some(x), Some(y)) => y / 1_000_000 > x / 1_000_000 + 1,
                    _ => false,
                };
                let mut start = 0;
                for i in 1..=pts.len() {
                    let broken = i < pts.len() && gap(pts[i - 1], pts[i]);
                    if i == pts.len() || broken || pts[i].stability != pts[start].stability {
                        let end = if broken { i } else { (i + 1).min(pts.len()) };
                        let st = pts[start].stability;
                        used.insert(st);
                        let (w, dash) = st.style();
                        if end > start {
                            out.push(Series {
                                color: branch_color(b).into(),
                                width: w,
                                dash: dash.into(),
                                points: pts[start..end].iter().map(|p| (p.lbar, f(p))).collect(),
                            });
                        }
                        start = i;
                    }
                }
            }
        }
        out
    }

    /// Wide light bands under the runs of lifted-off states (enclosed diagrams), drawn
    /// before the branch lines.
    ///
    /// Each family is followed in its own order (arclength when the file has it), as its line
    /// is: sorting a whole branch by `L̄` would zigzag between its families and smear the band
    /// over every curve.
    fn lifted_off(&self, f: impl Fn(&DiagramPoint) -> f64) -> Vec<Series> {
        let mut out = Vec::new();
        for (b, _) in self.branches() {
            let families: BTreeSet<u32> = self
                .points
                .iter()
                .filter(|p| p.branch == b)
                .map(|p| p.family)
                .collect();
            for fam in families {
                let mut pts: Vec<&DiagramPoint> = self
                    .points
                    .iter()
                    .filter(|p| p.branch == b && p.family == fam)
                    .collect();
                if pts.iter().all(|p| p.arc.is_some()) {
                    pts.sort_by_key(|p| p.arc);
                } else {
                    pts.sort_by(|a, c| a.lbar.total_cmp(&c.lbar));
                }
                for run in pts.split(|p| p.attached != Some(false)) {
                    if run.len() >= 2 {
                        out.push(Series {
                            color: LIFTED.into(),
                            width: LIFTED_WIDTH,
                            dash: String::new(),
                            points: run.iter().map(|p| (p.lbar, f(p))).collect(),
                        });
                    }
                }
            }
        }
        out
    }

    fn legend(&self, used: &BTreeSet<Stability>) -> Vec<LegendItem> {
        // Only branches drawn as a line (a branch with one state, such as the planar circle
        // touching the wall at L̄ = 1 of an enclosed diagram, draws nothing).
        let mut legend: Vec<LegendItem> = self
            .branches()
            .into_iter()
            .filter(|&(b, _)| self.points.iter().filter(|p| p.branch == b).count() >= 2)
            .map(|(b, eta)| LegendItem::Line {
                label: if b == 0 {
                    "branch 0 (planar circle)".into()
                } else {
                    format!("branch {b} (η = {eta})")
                },
                color: branch_color(b).into(),
                width: 2.6,
                dash: String::new(),
            })
            .collect();
        for &st in used {
            let (w, dash) = st.style();
            legend.push(LegendItem::Line {
                label: st.legend().into(),
                color: "#222".into(),
                width: w,
                dash: dash.into(),
            });
        }
        legend
    }
}

/// Colour of the band under the lifted-off parts of an enclosed diagram.
const LIFTED: &str = "#f7e3a1";

/// Width of that band, pixels: wider than the lines it underlies, narrow enough not to hide
/// the curves near them.
const LIFTED_WIDTH: f64 = 6.0;

/// Marker of a special point: shape, colour, half-size, legend text.
fn special_style(kind: &str) -> (Shape, &'static str, f64, &'static str) {
    match kind {
        "fold" => (Shape::Triangle, "#555", 3.5, "fold (turning point in L̄)"),
        "lift-off" => (Shape::Circle, "#e08a00", 4.5, "lift-off (λ_min = 0)"),
        "landing" => (Shape::Circle, "#2a8a2a", 4.5, "landing (λ_min = 0)"),
        "detachment" => (
            Shape::Circle,
            "#6a3d9a",
            4.5,
            "detachment (last contact force 0)",
        ),
        _ => (Shape::Circle, "#b00", 3.5, "branch point (pitchfork)"),
    }
}

/// Refuse a figure that needs columns the diagram lacks.
fn require(d: &DiagramData, what: &str) -> Result<(), FigureError> {
    if d.missing.is_empty() {
        Ok(())
    } else {
        Err(FigureError::Invalid(format!(
            "the {} diagram has no {} columns, which {what} needs",
            d.model,
            d.missing.join(", ")
        )))
    }
}

/// Figure size check shared by the diagram figures.
pub fn check_size(w: f64, h: f64) -> Result<(), FigureError> {
    if !(300.0..=6000.0).contains(&w) || !(200.0..=6000.0).contains(&h) {
        return Err(FigureError::Invalid(format!(
            "figure size must be 300–6000 × 200–6000 pixels, got {w} × {h}"
        )));
    }
    Ok(())
}

/// Fig. 3a: `E R/(πD₀)` against `L̄`, critical points marked (◆ crossing of two branches,
/// □ collapse onto an m-fold great circle); relative to the stable state when
/// [`DiagramData::relative`].
pub fn energy_figure(d: &DiagramData, w: f64, h: f64) -> Result<String, FigureError> {
    energy_like_figure(d, w, h, false)
}

/// The geodesic-curvature energy `E_g R/(πD₀)` against `L̄`, one panel (the left panel of
/// [`energy_split_figure`] at full size), critical lengths as dotted lines.
pub fn energy_g_figure(d: &DiagramData, w: f64, h: f64) -> Result<String, FigureError> {
    require(d, "the geodesic energy")?;
    energy_like_figure(d, w, h, true)
}

fn energy_like_figure(
    d: &DiagramData,
    w: f64,
    h: f64,
    geodesic: bool,
) -> Result<String, FigureError> {
    check_size(w, h)?;
    let f = |p: &DiagramPoint| if geodesic { p.energy_g } else { p.energy };
    let mut used = BTreeSet::new();
    let mut series = d.lifted_off(f);
    let lifted = !series.is_empty();
    series.extend(d.lines(f, &mut used));
    let mut legend = d.legend(&used);
    if lifted {
        legend.push(LegendItem::Line {
            label: "lifted off the wall (gap > 0)".into(),
            color: LIFTED.into(),
            width: LIFTED_WIDTH,
            dash: String::new(),
        });
    }
    let mut marks = Vec::new();
    let mut kinds = BTreeSet::new();
    // Critical and special points carry the total energy: drawn on the energy figure only.
    for c in d.critical.iter().filter(|_| !geodesic) {
        let shape = if c.kind == "crossing" {
            Shape::Diamond
        } else {
            Shape::OpenSquare
        };
        kinds.insert(c.kind == "crossing");
        marks.push(Mark {
            at: (c.lbar_cr, c.energy),
            shape,
            color: "#111".into(),
            size: 5.5,
        });
    }
    let mut special_kinds = BTreeSet::new();
    for p in d.special.iter().filter(|_| !geodesic) {
        let (shape, color, size, _) = special_style(&p.kind);
        special_kinds.insert(p.kind.as_str());
        marks.push(Mark {
            at: (p.lbar, p.energy),
            shape,
            color: color.into(),
            size,
        });
    }
    for kind in ["fold", "branch_point", "lift-off", "landing", "detachment"] {
        if special_kinds.contains(kind) {
            let (shape, color, _, label) = special_style(kind);
            legend.push(LegendItem::Mark {
                label: label.into(),
                shape,
                color: color.into(),
            });
        }
    }
    if kinds.contains(&true) {
        legend.push(LegendItem::Mark {
            label: "crossing: E_a = E_b".into(),
            shape: Shape::Diamond,
            color: "#111".into(),
        });
    }
    if kinds.contains(&false) {
        legend.push(LegendItem::Mark {
            label: "collapse onto a great circle".into(),
            shape: Shape::OpenSquare,
            color: "#111".into(),
        });
    }
    let (title, ylabel) = match (geodesic, d.relative) {
        (true, _) => (
            format!(
                "Geodesic-curvature energy of the branches ({} model)",
                d.model
            ),
            "E_g R/(πD₀)".to_string(),
        ),
        (false, false) => (
            format!("Bending energy of the branches ({} model)", d.model),
            "E R/(πD₀)".to_string(),
        ),
        (false, true) => (
            format!("Bending energy above the stable state ({} model)", d.model),
            "(E − E_stable(L̄)) R/(πD₀)".to_string(),
        ),
    };
    let mut plot = Plot {
        title,
        xlabel: "L̄ = L/(2πR)".into(),
        ylabel,
        series,
        marks,
        vlines: d
            .critical
            .iter()
            .map(|c| (c.lbar_cr, format!("{:.4}", c.lbar_cr)))
            .collect(),
        legend,
        legend_width: 270.0,
        note: if d.relative && !geodesic {
            "critical lengths L̄_icr at the top (dotted lines); E_stable interpolated linearly between the stable states and critical points".into()
        } else {
            "critical lengths L̄_icr at the top (dotted lines)".into()
        },
        ..Default::default()
    };
    // Relative energies span little except near a branch's end: clip a few outliers so that
    // the differences between the branches stay visible, and say so.
    if d.relative && !geodesic {
        let values: Vec<f64> = d.points.iter().map(|p| p.energy).collect();
        if let Some(shown) = crate::plot::robust_range(&values, None) {
            let (x0, x1, _, _) = plot.data_range();
            plot.range = Some((x0, x1, shown.0, shown.1));
            plot.note = crate::plot::clipped_note("energy", &values, shown);
        }
    }
    let mut svg = Svg::new(w, h);
    plot.render(&mut svg, 0.0, 0.0, w, h, "energy");
    Ok(svg.finish())
}

/// Fig. 3b: the split `E = E_g + E_n` (`E_n = L̄` for a uniform rod on the unit sphere), two
/// panels.
pub fn energy_split_figure(d: &DiagramData, w: f64, h: f64) -> Result<String, FigureError> {
    check_size(w, h)?;
    require(d, "the energy split")?;
    let mut svg = Svg::new(w, h);
    for (k, (title, ylabel, f)) in [
        (
            "Geodesic-curvature energy",
            "E_g R/(πD₀)",
            (|p: &DiagramPoint| p.energy_g) as fn(&DiagramPoint) -> f64,
        ),
        (
            "Normal-curvature energy",
            "E_n R/(πD₀)",
            (|p: &DiagramPoint| p.energy + p.shift - p.energy_g) as fn(&DiagramPoint) -> f64,
        ),
    ]
    .into_iter()
    .enumerate()
    {
        let mut used = BTreeSet::new();
        let series = d.lines(f, &mut used);
        let plot = Plot {
            title: title.into(),
            xlabel: "L̄ = L/(2πR)".into(),
            ylabel: ylabel.into(),
            series,
            legend: if k == 0 { d.legend(&used) } else { Vec::new() },
            vlines: d
                .critical
                .iter()
                .map(|c| (c.lbar_cr, String::new()))
                .collect(),
            ..Default::default()
        };
        plot.render(
            &mut svg,
            k as f64 * w / 2.0,
            0.0,
            w / 2.0,
            h,
            &format!("split{k}"),
        );
    }
    Ok(svg.finish())
}

/// Fig. 7: the largest and smallest contact force `λR³/D₀` of each state against `L̄`, with
/// the great-circle buckling loads at `L̄ = m` of a uniform rod
/// ([`DiagramData::buckling_loads`]): Eq. (33) `(m + 1)²/m²` (■) and Eq. (34)
/// `(m − 1)²/m²`, `m ≥ 2` (▲). The axis is clipped to the bulk of the values when a few
/// states have sharp peaks ([`crate::plot::robust_range`]), and says so.
pub fn lambda_figure(d: &DiagramData, w: f64, h: f64) -> Result<String, FigureError> {
    check_size(w, h)?;
    require(d, "the contact-force figure")?;
    let mut used = BTreeSet::new();
    let mut series = d.lines(|p| p.lambda_max, &mut used);
    series.extend(d.lines(|p| p.lambda_min, &mut used));
    let mut legend = d.legend(&used);
    let (lo, hi) = d
        .points
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(p.lbar), b.max(p.lbar))
        });
    let mut marks = Vec::new();
    let mut m = lo.ceil().max(1.0) as u32;
    // Eqs. (33)–(34) hold for a uniform rod only (a non-uniform rod's great circle carries a
    // non-uniform load): no markers otherwise.
    while d.buckling_loads && f64::from(m) <= hi + 1e-9 {
        let mf = f64::from(m);
        marks.push(Mark {
            at: (mf, (mf + 1.0).powi(2) / (mf * mf)),
            shape: Shape::Square,
            color: "#111".into(),
            size: 5.0,
        });
        if m >= 2 {
            marks.push(Mark {
                at: (mf, (mf - 1.0).powi(2) / (mf * mf)),
                shape: Shape::Triangle,
                color: "#111".into(),
                size: 5.5,
            });
        }
        m += 1;
    }
    if !marks.is_empty() {
        legend.push(LegendItem::Mark {
            label: "Eq. (33): (m+1)²/m² at L̄ = m".into(),
            shape: Shape::Square,
            color: "#111".into(),
        });
    }
    if marks.iter().any(|k| k.shape == Shape::Triangle) {
        legend.push(LegendItem::Mark {
            label: "Eq. (34): (m−1)²/m² at L̄ = m".into(),
            shape: Shape::Triangle,
            color: "#111".into(),
        });
    }
    let mut plot = Plot {
        title: "Extreme contact forces along the branches".into(),
        xlabel: "L̄ = L/(2πR)".into(),
        ylabel: "λ_max and λ_min, λR³/D₀".into(),
        series,
        marks,
        hlines: vec![0.0],
        legend,
        legend_width: 270.0,
        note: "upper curves: max λ; lower curves: min λ (λ < 0 would pull the loop off the wall)"
            .into(),
        ..Default::default()
    };
    // A few states with sharp peaks (at the stiffness steps) must not flatten every curve.
    let values: Vec<f64> = d
        .points
        .iter()
        .flat_map(|p| [p.lambda_min, p.lambda_max])
        .collect();
    if let Some(shown) = crate::plot::robust_range(&values, None) {
        let (x0, x1, _, _) = plot.data_range();
        plot.range = Some((x0, x1, shown.0, shown.1));
        plot.note = crate::plot::clipped_note("λ", &values, shown);
    }
    let mut svg = Svg::new(w, h);
    plot.render(&mut svg, 0.0, 0.0, w, h, "lambda");
    Ok(svg.finish())
}
