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
//! The tables are read into [`DiagramData`] by `diagram_data.rs`; this file draws the four
//! figures from that one reading, so that every figure shows the same rows with the same
//! styles.

use std::collections::BTreeSet;

use crate::color::branch_color;
use crate::plot::{LegendItem, Mark, Plot, Series, Shape};
use crate::svg::Svg;
use crate::FigureError;

pub use crate::diagram_data::{CriticalPoint, DiagramData, DiagramPoint, SpecialMark, Stability};

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

impl DiagramData {
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
