//! The elliptic modulus against length (the paper's Fig. 11): `k²` of the exact loops of each
//! branch against `L̄`, with the first-order small-`k²` formula of Eq. (B.4) dashed.

use crate::color::branch_color;
use crate::plot::{LegendItem, Plot, Series};
use crate::svg::Svg;
use crate::FigureError;

/// One exact state: branch, `η`, winding `p`, `L̄` and `k²`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct K2Point {
    /// Paper branch number.
    pub branch: u32,
    /// Periods of `κ_g`.
    pub eta: u32,
    /// Winding number `p` (Eq. B.4 depends on it).
    pub p: i32,
    /// `L̄`.
    pub lbar: f64,
    /// `k²`.
    pub k2: f64,
}

/// The figure, `w × h` pixels: one colour per branch, solid the exact `k²`, dashed
/// Eq. (B.4) evaluated with the same `(η, p)` (split where `sgn(L̄ − η)` changes), clipped to
/// `0 ≤ k² ≤ 1`.
pub fn k2_figure(points: &[K2Point], w: f64, h: f64) -> Result<String, FigureError> {
    if !(300.0..=4000.0).contains(&w) || !(200.0..=4000.0).contains(&h) {
        return Err(FigureError::Invalid(format!(
            "figure size must be 300–4000 × 200–4000 pixels, got {w} × {h}"
        )));
    }
    let mut branches: Vec<u32> = points.iter().map(|p| p.branch).collect();
    branches.sort_unstable();
    branches.dedup();
    if branches.is_empty() {
        return Err(FigureError::Invalid("no states to plot".into()));
    }
    let mut series = Vec::new();
    let mut legend = Vec::new();
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for &b in &branches {
        let mut pts: Vec<&K2Point> = points.iter().filter(|p| p.branch == b).collect();
        pts.sort_by(|a, c| a.lbar.total_cmp(&c.lbar));
        let color = branch_color(b).to_string();
        let eta = pts[0].eta;
        series.push(Series {
            color: color.clone(),
            width: 2.2,
            dash: String::new(),
            points: pts.iter().map(|p| (p.lbar, p.k2)).collect(),
        });
        // Eq. (B.4) in runs of constant sgn(L̄ − η) and p.
        let mut run: Vec<(f64, f64)> = Vec::new();
        let mut key = None;
        for p in &pts {
            lo = lo.min(p.lbar);
            hi = hi.max(p.lbar);
            let k = (p.lbar > f64::from(p.eta), p.p);
            if key.is_some_and(|x| x != k) && run.len() > 1 {
                series.push(Series {
                    color: color.clone(),
                    width: 1.5,
                    dash: "6 4".into(),
                    points: std::mem::take(&mut run),
                });
            } else if key.is_some_and(|x| x != k) {
                run.clear();
            }
            key = Some(k);
            let v = rodloop_exact::homogeneous::k2_small(p.lbar, p.eta, p.p);
            if v.is_finite() {
                run.push((p.lbar, v));
            }
        }
        if run.len() > 1 {
            series.push(Series {
                color: color.clone(),
                width: 1.5,
                dash: "6 4".into(),
                points: run,
            });
        }
        legend.push(LegendItem::Line {
            label: format!("branch {b} (η = {eta})"),
            color,
            width: 2.2,
            dash: String::new(),
        });
    }
    legend.push(LegendItem::Line {
        label: "exact loops".into(),
        color: "black".into(),
        width: 2.2,
        dash: String::new(),
    });
    legend.push(LegendItem::Line {
        label: "small-k² formula, Eq. (B.4)".into(),
        color: "black".into(),
        width: 1.5,
        dash: "6 4".into(),
    });
    let plot = Plot {
        title: "Elliptic modulus of the exact loops (Fig. 11)".into(),
        xlabel: "L̄ = L/(2πR)".into(),
        ylabel: "k²".into(),
        series,
        legend,
        legend_width: 230.0,
        range: Some((lo, hi, 0.0, 1.0)),
        note: "k² → 0 where a branch ends on a great circle; Eq. (B.4) is first order in k²".into(),
        ..Default::default()
    };
    let mut svg = Svg::new(w, h);
    plot.render(&mut svg, 0.0, 0.0, w, h, "k2");
    Ok(svg.finish())
}
