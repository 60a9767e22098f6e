//! `rodloop compare`: the paper's printed values next to rodloop's results, with deviations.
//!
//! The paper's values live in `data/reference/paper_values.csv` (with page/equation sources)
//! and are compiled into the binary.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use rodloop_exact::diagram::{compute, CriticalKind, DiagramSettings};
use rodloop_exact::{eta_of_branch, paper_branch_loop};

use crate::output::{checked_json, Cell, OutputRun, Table};

const PAPER_VALUES: &str = include_str!("../data/reference/paper_values.csv");

/// Arguments of `rodloop compare`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Output directory.
    #[arg(long, default_value = "out/compare")]
    pub out: PathBuf,
    /// Compare a scene: `enclosed` (the built-in homogeneous enclosed scene) or a scene file
    /// with `confinement = "enclosed"` (against the surface), or a two-segment scene on the
    /// surface (against the paper's statements of Sec. 5).
    #[arg(long)]
    pub scene: Option<String>,
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

fn paper_values() -> Result<Vec<PaperValue>> {
    let mut rdr = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .from_reader(PAPER_VALUES.as_bytes());
    let mut out = Vec::new();
    for rec in rdr.records() {
        let r = rec.context("data/reference/paper_values.csv is malformed")?;
        let num = |i: usize| -> Option<f64> { r.get(i).and_then(|s| s.parse().ok()) };
        out.push(PaperValue {
            id: r[0].to_string(),
            kind: r[1].to_string(),
            branch: r[2].parse().context("branch column")?,
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
fn exact_value(pv: &PaperValue, crit: &[rodloop_exact::diagram::Critical]) -> Result<Option<f64>> {
    let eta = eta_of_branch(pv.branch);
    Ok(match pv.kind.as_str() {
        "critical_length" => nearest_critical(
            pv,
            pv.value.parse()?,
            crit.iter().map(|c| (c.kind, c.lbar_cr)),
        ),
        "buckling_load" => {
            // The great circle's buckling load, exact: Eq. (33) (m + 1)²/m² where the branch
            // starts at L̄ = m, Eq. (34) (m − 1)²/m² where it ends there (Sec. 4).
            let m = pv.lbar.context("buckling_load needs lbar")?;
            let k = if pv.side == "above" { m + 1.0 } else { m - 1.0 };
            Some(k * k / (m * m))
        }
        "winding" => {
            let l = pv.lbar.context("winding needs lbar")?;
            Some(f64::from(paper_branch_loop(eta, l)?.p))
        }
        _ => None,
    })
}

/// Point group (Schoenflies) of the exact loop of a branch at the row's length, sampled from
/// the maximum of κ_g with 48η points (a multiple of 4η, as the detector requires).
fn exact_symmetry(pv: &PaperValue) -> Result<String> {
    let eta = eta_of_branch(pv.branch);
    let l = pv.lbar.context("symmetry rows need lbar")?;
    let lp = paper_branch_loop(eta, l)?;
    let pts: Vec<nalgebra::Vector3<f64>> = lp
        .sample(48 * eta as usize)?
        .iter()
        .map(|p| nalgebra::Vector3::new(p.x, p.y, p.z))
        .collect();
    Ok(rodloop_exact::symmetry::point_group(&pts, 1e-9).symbol)
}

/// The numeric model's value for a paper row: critical lengths from the numeric diagram,
/// buckling loads from its great-circle analysis (Eq. 33 rows: the mode with m + 1 periods,
/// Eq. 34 rows: m − 1). Winding numbers and symmetries are compared on the exact layer only.
/// Critical lengths outside the diagram's length range have no numeric value.
fn numeric_value(pv: &PaperValue, nd: &rodloop_diagram::NumericDiagram) -> Option<f64> {
    match pv.kind.as_str() {
        "critical_length" => {
            // Only a printed length inside the diagram's range has a numeric counterpart
            // (a diagram of a sub-range must not be matched to a neighbour outside it).
            let target: f64 = pv.value.parse().ok()?;
            let (lo, hi) = nd.range;
            if target < lo - 1e-9 || target > hi + 1e-9 {
                return None;
            }
            nearest_critical(pv, target, nd.critical.iter().map(|c| (c.kind, c.lbar_cr)))
        }
        "buckling_load" => {
            let m = pv.lbar? as u32;
            let eq = if pv.side == "above" { "33" } else { "34" };
            nd.great_circles.as_ref()?.loads.iter().find_map(|l| {
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
/// and, when `nd` is given, the numeric diagram's (critical lengths inside the diagram's
/// length range, buckling loads of its great-circle analysis), with deviations and
/// agreement within the printed resolution.
pub fn compare_rows(nd: Option<&rodloop_diagram::NumericDiagram>) -> Result<Vec<CompareRow>> {
    let values = paper_values()?;
    if values.is_empty() {
        bail!("no paper values compiled in");
    }
    let d = compute(&DiagramSettings::default())?;
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

/// Run the subcommand.
pub fn run(args: &Args) -> Result<()> {
    if let Some(s) = &args.scene {
        // A two-segment rod on the sphere: the paper's statements of Sec. 5.
        if s != "enclosed" {
            let scene = rodloop_scene::Scene::from_file(std::path::Path::new(s))?;
            if crate::engine::kind_of(&scene) == crate::engine::EngineKind::Surface
                && !scene.stiffness.is_uniform()
            {
                return crate::compare_segments::run(&scene, &args.out);
            }
        }
        return crate::enclosed::run_compare(s, &args.out);
    }
    let nd = rodloop_diagram::compute(
        &rodloop_diagram::DiagramOptions::default(),
        &mut (),
        &mut |_| {},
    )
    .context("numeric diagram of the default scene")?;
    let values = compare_rows(Some(&nd))?;
    let mut table = Table::new(
        "compare.csv",
        &[
            "id",
            "kind",
            "branch",
            "lbar",
            "paper",
            "resolution",
            "exact",
            "exact_deviation",
            "within_resolution",
            "tolerance",
            "numeric",
            "numeric_deviation",
            "numeric_within_resolution",
            "numeric_minus_exact",
            "source",
        ],
    );
    let mut rows = Vec::new();
    outln!(
        "{:<11} {:<15} {:>6} {:>5} {:>9} {:>8} {:>17} {:>9} {:>6} {:>17} {:>9} {:>6}",
        "id",
        "kind",
        "branch",
        "lbar",
        "paper",
        "tol",
        "exact",
        "deviation",
        "agrees",
        "numeric",
        "deviation",
        "agrees"
    );
    let mut disagreements = 0;
    let mut numeric_disagreements = 0;
    for r in &values {
        disagreements += usize::from(r.agrees_exact == Some(false));
        numeric_disagreements += usize::from(r.agrees_numeric == Some(false));
        let yes = |a: Option<bool>| match a {
            Some(true) => "yes",
            Some(false) => "NO",
            None => "-",
        };
        let sci = |v: Option<f64>| v.map(|x| format!("{x:.1e}")).unwrap_or_else(|| "-".into());
        outln!(
            "{:<11} {:<15} {:>6} {:>5} {:>9} {:>8} {:>17} {:>9} {:>6} {:>17} {:>9} {:>6}",
            r.id,
            r.kind,
            r.branch,
            r.lbar.map(|l| l.to_string()).unwrap_or_default(),
            if r.paper.len() > 9 {
                &r.paper[..9]
            } else {
                &r.paper
            },
            match (r.kind.as_str(), r.tolerance) {
                ("winding", _) | (_, None) => "exact".to_string(),
                (_, Some(t)) => format!("±{t:.0e}"),
            },
            r.exact_text(),
            sci(r.exact_deviation),
            yes(r.agrees_exact),
            r.numeric_text(),
            sci(r.numeric_deviation),
            yes(r.agrees_numeric),
        );
        let opt = |v: Option<f64>| v.map(|x| x.to_string()).unwrap_or_default();
        table.push(vec![
            Cell::S(r.id.clone()),
            Cell::S(r.kind.clone()),
            Cell::I(r.branch.into()),
            Cell::S(opt(r.lbar)),
            Cell::S(r.paper.clone()),
            Cell::S(opt(r.resolution)),
            Cell::S(r.symmetry.clone().unwrap_or_else(|| opt(r.exact))),
            Cell::S(opt(r.exact_deviation)),
            Cell::S(r.agrees_exact.map(|a| a.to_string()).unwrap_or_default()),
            Cell::S(opt(r.tolerance)),
            Cell::S(opt(r.numeric)),
            Cell::S(opt(r.numeric_deviation)),
            Cell::S(r.agrees_numeric.map(|a| a.to_string()).unwrap_or_default()),
            Cell::S(opt(r.numeric_minus_exact)),
            Cell::S(r.source.clone()),
        ])?;
        rows.push(checked_json!({
            "id": r.id,
            "paper": r.paper,
            "exact": r.symmetry.clone().map(serde_json::Value::from).unwrap_or_else(|| r.exact.into()),
            "numeric": r.numeric,
            "agrees_exact": r.agrees_exact,
            "agrees_numeric": r.agrees_numeric,
            "numeric_minus_exact": r.numeric_minus_exact,
        })?);
    }
    let run = OutputRun::begin(&args.out)?;
    run.write_table(&table)?;
    let summary = checked_json!({
        "rows": values.len(),
        "disagreements_exact": disagreements,
        "disagreements_numeric": numeric_disagreements,
        "numeric_model": "rodloop diagram --model numeric, default scene, default accuracy",
        "values": rows,
        "units": "lengths lbar = L/(2 pi R); energy E R/(pi D); lambda R^3/D",
    })?;
    run.write_json("summary.json", &crate::output::strip_nulls(summary))?;
    run.commit()?;
    outln!(
        "{} paper values; beyond the printed resolution {} disagree with the exact layer and {} with the numeric model (winding numbers and symmetries: exact layer only). Wrote compare.csv and summary.json to {}",
        values.len(),
        disagreements,
        numeric_disagreements,
        args.out.display()
    );
    Ok(())
}
