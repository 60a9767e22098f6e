//! The paper's printed values next to rodloop's results (`rodloop compare`, the report's
//! comparison section): the exact layer's value and the numeric diagram's for every row of
//! `data/reference/paper_values.csv` (compiled in, with page and equation sources), with
//! deviations and agreement within the printed resolution; and, for a two-segment rod on the
//! sphere, the paper's two statements of Sec. 5 ([`segment_rows`]).

use rodloop_exact::diagram::{compute, CriticalKind, DiagramSettings};
use rodloop_exact::{eta_of_branch, paper_branch_loop};

use crate::representative::{middle_of_first_stable, stable_near_half_integers, StableRow};
use crate::DiagramError;
use crate::Label;

const PAPER_VALUES: &str = include_str!("../../../data/reference/paper_values.csv");

fn context(what: &str, e: impl std::error::Error + Send + Sync + 'static) -> DiagramError {
    DiagramError::Context {
        what: what.into(),
        source: Box::new(e),
    }
}

fn passed(e: impl std::error::Error + Send + Sync + 'static) -> DiagramError {
    DiagramError::Passed(Box::new(e))
}

fn needs_lbar(pv: &PaperValue) -> Result<f64, DiagramError> {
    pv.lbar.ok_or_else(|| {
        DiagramError::InvalidOptions(format!(
            "data/reference/paper_values.csv: row {} ({}) needs lbar",
            pv.id, pv.kind
        ))
    })
}

/// One row of the paper's table.
#[derive(Debug, Clone)]
struct PaperValue {
    id: String,
    kind: String,
    branch: u32,
    lbar: Option<f64>,
    side: String,
    value: String,
    resolution: Option<f64>,
    source: String,
}

fn paper_values() -> Result<Vec<PaperValue>, DiagramError> {
    let mut rdr = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .from_reader(PAPER_VALUES.as_bytes());
    let mut out = Vec::new();
    for rec in rdr.records() {
        let r = rec.map_err(|e| context("data/reference/paper_values.csv is malformed", e))?;
        let num = |i: usize| -> Option<f64> { r.get(i).and_then(|s| s.parse().ok()) };
        out.push(PaperValue {
            id: r[0].to_string(),
            kind: r[1].to_string(),
            branch: r[2]
                .parse()
                .map_err(|e| context("data/reference/paper_values.csv: branch column", e))?,
            lbar: num(3),
            side: r[4].to_string(),
            value: r[5].to_string(),
            resolution: num(6),
            source: r[7].to_string(),
        });
    }
    Ok(out)
}

/// The computed critical length closest to a printed one, of the kind the row implies (an
/// exact printed value is a collapse onto a great circle, a rounded one a crossing).
fn nearest_critical(
    pv: &PaperValue,
    target: f64,
    crit: impl Iterator<Item = (CriticalKind, f64)>,
) -> Option<f64> {
    let want = if pv.resolution == Some(0.0) {
        CriticalKind::Collapse
    } else {
        CriticalKind::Crossing
    };
    crit.filter(|(k, _)| *k == want)
        .map(|(_, x)| x)
        .min_by(|a, b| (a - target).abs().total_cmp(&(b - target).abs()))
}

/// The exact layer's value for a paper row, as text, with the numeric value when there is one.
fn exact_value(
    pv: &PaperValue,
    crit: &[rodloop_exact::diagram::Critical],
) -> Result<Option<f64>, DiagramError> {
    let eta = eta_of_branch(pv.branch);
    Ok(match pv.kind.as_str() {
        "critical_length" => nearest_critical(
            pv,
            pv.value
                .parse()
                .map_err(|e| context(&format!("paper value {}", pv.id), e))?,
            crit.iter().map(|c| (c.kind, c.lbar_cr)),
        ),
        "buckling_load" => {
            // The great circle's buckling load, exact: Eq. (33) (m + 1)²/m² where the branch
            // starts at L̄ = m, Eq. (34) (m − 1)²/m² where it ends there (Sec. 4).
            let m = needs_lbar(pv)?;
            let k = if pv.side == "above" { m + 1.0 } else { m - 1.0 };
            Some(k * k / (m * m))
        }
        "winding" => {
            let l = needs_lbar(pv)?;
            Some(f64::from(paper_branch_loop(eta, l).map_err(passed)?.p))
        }
        _ => None,
    })
}

/// Point group (Schoenflies) of the exact loop of a branch at the row's length, sampled from
/// the maximum of κ_g with 48η points (a multiple of 4η, as the detector requires).
fn exact_symmetry(pv: &PaperValue) -> Result<String, DiagramError> {
    let eta = eta_of_branch(pv.branch);
    let l = needs_lbar(pv)?;
    let lp = paper_branch_loop(eta, l).map_err(passed)?;
    let pts: Vec<nalgebra::Vector3<f64>> = lp
        .sample(48 * eta as usize)
        .map_err(passed)?
        .iter()
        .map(|p| nalgebra::Vector3::new(p.x, p.y, p.z))
        .collect();
    Ok(rodloop_exact::symmetry::point_group(&pts, 1e-9).symbol)
}

/// The numeric model's value for a paper row: critical lengths from the numeric diagram,
/// buckling loads from its great-circle analysis (Eq. 33 rows: the mode with m + 1 periods,
/// Eq. 34 rows: m − 1). Winding numbers and symmetries are compared on the exact layer only.
/// Critical lengths outside the diagram's length range have no numeric value.
fn numeric_value(pv: &PaperValue, nd: &rodloop_schema::Diagram) -> Option<f64> {
    match pv.kind.as_str() {
        "critical_length" => {
            // Only a printed length inside the diagram's range has a numeric counterpart
            // (a diagram of a sub-range must not be matched to a neighbour outside it).
            let target: f64 = pv.value.parse().ok()?;
            let axis = nd.axes.first()?;
            if target < axis.min - 1e-9 || target > axis.max + 1e-9 {
                return None;
            }
            let kinds = nd.critical.iter().filter_map(|c| {
                serde_json::from_value::<CriticalKind>(serde_json::Value::String(c.kind.clone()))
                    .ok()
                    .map(|k| (k, c.lbar_cr))
            });
            nearest_critical(pv, target, kinds)
        }
        "buckling_load" => {
            let m = pv.lbar? as u32;
            let eq = if pv.side == "above" { "33" } else { "34" };
            nd.get::<crate::BucklingReport>("great_circles")?
                .loads
                .iter()
                .find_map(|l| {
                    (l.m == m && l.equation.as_deref() == Some(eq)).then_some(l.lambda_numeric)
                })
        }
        _ => None,
    }
}

/// One of the paper's printed values next to the exact layer's and the numeric model's.
#[derive(Debug, Clone)]
pub struct CompareRow {
    /// Row id of `paper_values.csv` (`L2cr`, `eq33_m2`, …).
    pub id: String,
    /// `critical_length`, `buckling_load`, `winding` or `symmetry`.
    pub kind: String,
    /// Paper branch number.
    pub branch: u32,
    /// Length of the row, when it has one.
    pub lbar: Option<f64>,
    /// The value as printed.
    pub paper: String,
    /// Half a unit of the last printed digit (0 for exact statements).
    pub resolution: Option<f64>,
    /// Where the paper prints it.
    pub source: String,
    /// The exact layer's value (numeric kinds).
    pub exact: Option<f64>,
    /// The exact layer's point group (symmetry rows).
    pub symmetry: Option<String>,
    /// `exact − paper`.
    pub exact_deviation: Option<f64>,
    /// Whether the exact value agrees within the printed resolution.
    pub agrees_exact: Option<bool>,
    /// The tolerance of the agreement: half a unit of the last printed digit, at least
    /// 1e-6 relative (numeric kinds).
    pub tolerance: Option<f64>,
    /// The numeric model's value (critical lengths and buckling loads).
    pub numeric: Option<f64>,
    /// `numeric − paper`.
    pub numeric_deviation: Option<f64>,
    /// Whether the numeric value agrees within the printed resolution.
    pub agrees_numeric: Option<bool>,
    /// `numeric − exact`.
    pub numeric_minus_exact: Option<f64>,
}

impl CompareRow {
    /// The exact layer's value as text (`-` when there is none).
    pub fn exact_text(&self) -> String {
        self.symmetry
            .clone()
            .unwrap_or_else(|| self.shown(self.exact))
    }

    /// The numeric model's value as text (`-` when there is none).
    pub fn numeric_text(&self) -> String {
        self.shown(self.numeric)
    }

    fn shown(&self, v: Option<f64>) -> String {
        match (self.kind.as_str(), v) {
            ("winding", Some(x)) => format!("{x}"),
            (_, Some(x)) => format!("{x:.12}"),
            (_, None) => "-".into(),
        }
    }
}

/// Every paper value of `data/reference/paper_values.csv` next to the exact layer's value
/// and, when `nd` is given, the numeric diagram's in the schema (critical lengths inside its
/// length range, buckling loads of its great-circle analysis), with deviations and
/// agreement within the printed resolution.
pub fn compare_rows(nd: Option<&rodloop_schema::Diagram>) -> Result<Vec<CompareRow>, DiagramError> {
    let values = paper_values()?;
    if values.is_empty() {
        return Err(DiagramError::InvalidOptions(
            "no paper values compiled in".into(),
        ));
    }
    let d = compute(&DiagramSettings::default()).map_err(passed)?;
    let mut rows = Vec::with_capacity(values.len());
    for pv in values {
        let exact = exact_value(&pv, &d.critical)?;
        let numeric = nd.and_then(|nd| numeric_value(&pv, nd));
        let paper_num: Option<f64> = pv.value.parse().ok();
        let symmetry = if pv.kind == "symmetry" {
            Some(exact_symmetry(&pv)?)
        } else {
            None
        };
        // Deviation from the paper and agreement within its printed resolution.
        let judge = |v: Option<f64>| match (v, paper_num) {
            (Some(x), Some(p)) => {
                let dev = x - p;
                let tol = pv.resolution.unwrap_or(0.0).max(1e-6 * p.abs().max(1.0));
                (Some(dev), Some(dev.abs() <= tol))
            }
            _ => (None, None),
        };
        let (dev, agrees) = match &symmetry {
            Some(sym) => (None, Some(*sym == pv.value)),
            None => judge(exact),
        };
        let (ndev, nagrees) = judge(numeric);
        let tolerance = paper_num
            .filter(|_| symmetry.is_none())
            .map(|p| pv.resolution.unwrap_or(0.0).max(1e-6 * p.abs().max(1.0)));
        let numeric_minus_exact = match (numeric, exact) {
            (Some(n), Some(e)) => Some(n - e),
            _ => None,
        };
        rows.push(CompareRow {
            id: pv.id,
            kind: pv.kind,
            branch: pv.branch,
            lbar: pv.lbar,
            paper: pv.value,
            resolution: pv.resolution,
            source: pv.source,
            exact,
            symmetry,
            exact_deviation: dev,
            agrees_exact: agrees,
            tolerance,
            numeric,
            numeric_deviation: ndev,
            agrees_numeric: nagrees,
            numeric_minus_exact,
        });
    }
    Ok(rows)
}

/// Relative tolerance rodloop reads into the paper's "well approximated" (Sec. 5).
pub const ENERGY_TOLERANCE: f64 = 0.01;

/// Softest segment the paper's energy statement is judged for (a decade above its 0.001).
pub const SOFT_LIMIT: f64 = 0.01;

/// One statement of the paper's Sec. 5 next to rodloop's value.
#[derive(Clone, Debug)]
pub struct SegmentRow {
    /// Row id (`soft_energy_2.50`, `sym_branch1`).
    pub id: String,
    /// Length of the state compared.
    pub lbar: Option<f64>,
    /// The paper's value (the energy estimate, or the point group).
    pub paper: String,
    /// rodloop's value as text (energy with its error estimate, or the point group).
    pub numeric: String,
    /// `(numeric − paper)/paper` (energy rows).
    pub deviation: Option<f64>,
    /// Tolerance of the agreement (judged rows).
    pub tolerance: Option<f64>,
    /// Whether rodloop's value agrees (judged rows).
    pub agrees: Option<bool>,
    /// Where the paper states it.
    pub source: &'static str,
}

/// The paper's statements of Sec. 5 for a two-segment rod of stiffness ratio `ratio =
/// D1/D0` whose soft segment spans `s0*/L … s1*/L`, against its diagram `d` over
/// `[lbar_min, lbar_max]`:
/// - for an extremely soft segment (Fig. 9, `D1/D0 = 0.001`) the elastic energy is that of the
///   stiff segment on a great circle, `E ≈ D0 ℓ_stiff/(2R²)`, i.e. `E R/(πD0) ≈ (ℓ_stiff/L) L̄`
///   with `ℓ_stiff/L = 1 − (s1* − s0*)`, at the stable state nearest each half-integer length;
///   judged within [`ENERGY_TOLERANCE`] for `D1/D0 ≤` [`SOFT_LIMIT`] only;
/// - the saddle-like states of branch 1 keep only a mirror plane (`Cs`; Fig. 10), in the
///   middle of its first stable stretch.
pub fn segment_rows(
    d: &rodloop_schema::Diagram,
    ratio: f64,
    (s0, s1): (f64, f64),
    (lbar_min, lbar_max): (f64, f64),
) -> Vec<SegmentRow> {
    let rows: Vec<SchemaRow> = d
        .points
        .iter()
        .filter_map(|p| {
            Some(SchemaRow {
                lbar: *p.coords.first()?,
                point: p,
            })
        })
        .collect();
    let stiff = 1.0 - (s1 - s0);
    let mut out = Vec::new();
    for row in stable_near_half_integers(&rows, lbar_min, lbar_max) {
        let r = Row::of(row);
        let estimate = stiff * r.lbar;
        let dev = (r.energy - estimate) / estimate;
        let judged = ratio <= SOFT_LIMIT;
        out.push(SegmentRow {
            id: format!("soft_energy_{:.2}", r.lbar),
            lbar: Some(r.lbar),
            paper: format!("{estimate:.10}"),
            numeric: format!(
                "{:.10}{}",
                r.energy,
                r.energy_error
                    .map(|e| format!(" ± {e:.1e}"))
                    .unwrap_or_default()
            ),
            deviation: Some(dev),
            tolerance: judged.then_some(ENERGY_TOLERANCE),
            agrees: judged.then_some(dev.abs() <= ENERGY_TOLERANCE),
            source: "Sec. 5 (Fig. 9): E ≈ D0 ℓ_stiff/(2R²) for an extremely soft segment; stable state of the diagram",
        });
    }
    if let Some(row) = middle_of_first_stable(&rows, 1) {
        let r = Row::of(row);
        let group = match row.point.extra.get("point_group") {
            Some(rodloop_schema::Cell::S(g)) if !g.is_empty() => g.clone(),
            _ => "?".into(),
        };
        out.push(SegmentRow {
            id: "sym_branch1".into(),
            lbar: Some(r.lbar),
            paper: "Cs".into(),
            agrees: Some(group == "Cs"),
            numeric: group,
            deviation: None,
            tolerance: None,
            source: "Sec. 5 (Fig. 10): saddle-like states keep only a mirror plane",
        });
    }
    out
}

/// A point of a surface diagram's schema with its length, as the stable-stretch helpers read
/// it.
struct SchemaRow<'a> {
    lbar: f64,
    point: &'a rodloop_schema::Point,
}

impl StableRow for SchemaRow<'_> {
    fn branch(&self) -> u32 {
        self.point.branch
    }
    fn lbar(&self) -> f64 {
        self.lbar
    }
    fn stable(&self) -> bool {
        self.point.label.as_deref() == Some(Label::Stable.as_str())
    }
}

/// The numbers [`segment_rows`] prints of a row.
struct Row {
    lbar: f64,
    energy: f64,
    energy_error: Option<f64>,
}

impl Row {
    fn of(r: &SchemaRow<'_>) -> Self {
        Self {
            lbar: r.lbar,
            energy: r.point.energy,
            energy_error: r.point.energy_error,
        }
    }
}
