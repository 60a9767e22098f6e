//! `phase.svg`: the critical lengths `L̄_cr` of a two-segment rod against the continued
//! parameter (log axis for `d1`), every region between the curves and the collapses at the
//! integers labelled by its lowest (stable) branch (once per band), switches onto other
//! pairs of states, the exact rows (`--at` and the scene's value) and the ends of curves
//! that stop short of the requested range marked with their reason. The horizontal axis
//! covers the whole requested range, from the scene's value to `--to`.

use rodloop_figures::plot::{LegendItem, Mark, Plot, Series, Shape};
use rodloop_figures::svg::{Anchor, Svg};

use crate::phase_rows::{CurveRows, PhaseRows};

const COLORS: [&str; 4] = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd"];

/// Width reserved right of the axes for the legend, pixels.
const LEGEND_W: f64 = 330.0;

/// `L̄_cr` and the lowest branches `(below, above)` of `curve` at `x` (plot coordinate),
/// linearly interpolated between its rows of one arm; `None` outside the curve.
fn curve_at(c: &CurveRows, x: f64, xv: &dyn Fn(f64) -> f64) -> Option<(f64, u32, u32)> {
    let mut rows: Vec<_> = c.rows.iter().map(|(r, at)| (xv(at.value), *r)).collect();
    rows.sort_by(|a, b| a.0.total_cmp(&b.0));
    rows.windows(2).find_map(|w| {
        let ((xa, a), (xb, b)) = (w[0], w[1]);
        if !(xa <= x && x <= xb) || xb <= xa {
            return None;
        }
        let t = (x - xa) / (xb - xa);
        let near = if t < 0.5 { a } else { b };
        Some((
            a.lbar_cr + t * (b.lbar_cr - a.lbar_cr),
            near.from_branch,
            near.to_branch,
        ))
    })
}

/// The figure; `lbar_range` is the scene's length range (the vertical axis).
pub fn phase_svg(d: &PhaseRows, scene: &str, lbar_range: (f64, f64)) -> String {
    let param = &d.parameter;
    let log = param.is_log();
    let xv = |v: f64| if log { v.log10() } else { v };
    let mut plot = Plot {
        title: format!("Critical lengths of scene {scene} against {}", param.name),
        xlabel: if log {
            "log₁₀(D1/D0)".into()
        } else {
            param.name.clone()
        },
        ylabel: "critical length L̄_cr = L/(2πR)".into(),
        // The legend beside the axes, where it cannot cover a curve.
        legend_width: LEGEND_W,
        ..Default::default()
    };
    // The requested range, from the scene's value to --to, whatever the curves reach.
    let (mut x0, mut x1) = (
        xv(param.scene_value).min(xv(param.target)),
        xv(param.scene_value).max(xv(param.target)),
    );
    let mut ends: Vec<(f64, f64, String)> = Vec::new();
    let (mut y0, mut y1) = lbar_range;
    for (k, c) in d.curves.iter().enumerate() {
        let color = COLORS[k % COLORS.len()];
        let arms = c.rows.iter().map(|(_, at)| at.arm).max().unwrap_or(0);
        for arm in 0..=arms {
            let pts: Vec<(f64, f64)> = c
                .rows
                .iter()
                .filter(|(_, at)| at.arm == arm)
                .map(|(r, at)| (xv(at.value), r.lbar_cr))
                .collect();
            for p in &pts {
                (x0, x1, y0, y1) = (x0.min(p.0), x1.max(p.0), y0.min(p.1), y1.max(p.1));
            }
            plot.series.push(Series {
                color: color.into(),
                width: 2.0,
                dash: String::new(),
                points: pts,
            });
        }
        for (r, at) in &c.rows {
            let shape = match at.source.as_str() {
                "switch" => Shape::Diamond,
                "limit" => Shape::Circle,
                "fixed" if !(log && (at.value - 1.0).abs() < 0.01) => Shape::Square,
                _ => continue,
            };
            plot.marks.push(Mark {
                at: (xv(at.value), r.lbar_cr),
                shape,
                color: color.into(),
                size: 4.5,
            });
        }
        // Ends short of the requested range: an open square with the reason's kind.
        for e in c.curve.stopped_short(param.range()) {
            if let Some((r, at)) = c.rows.iter().min_by(|(_, a), (_, b)| {
                (a.value - e.value)
                    .abs()
                    .total_cmp(&(b.value - e.value).abs())
            }) {
                plot.marks.push(Mark {
                    at: (xv(at.value), r.lbar_cr),
                    shape: Shape::OpenSquare,
                    color: color.into(),
                    size: 6.0,
                });
                ends.push((xv(at.value), r.lbar_cr, e.kind.replace('_', " ")));
            }
        }
        let ex = c.curve.exchange;
        plot.legend.push(LegendItem::Line {
            label: format!(
                "exchange {} → {} (uniform rod: {:.4})",
                ex.from_branch, ex.to_branch, ex.lbar_uniform
            ),
            color: color.into(),
            width: 2.0,
            dash: String::new(),
        });
    }
    for (shape, label) in [
        (Shape::Diamond, "switch onto another pair of states"),
        (Shape::Square, "exact row (--at values, the scene's value)"),
        (Shape::Circle, "limit D1/D0 → 1"),
        (
            Shape::OpenSquare,
            "curve stops short of --to (reason beside)",
        ),
    ] {
        if plot.marks.iter().any(|m| m.shape == shape) {
            plot.legend.push(LegendItem::Mark {
                label: label.into(),
                shape,
                color: "#777".into(),
            });
        }
    }
    if !x0.is_finite() {
        (x0, x1) = (0.0, 1.0);
    }
    let range = (x0, x1.max(x0 + 1e-9), y0, y1);
    plot.range = Some(range);
    let (w, h) = (820.0 + LEGEND_W, 560.0);
    let mut svg = Svg::new(w, h);
    svg.rect(0.0, 0.0, w, h, "white", "none", 0.0);
    plot.render(&mut svg, 0.0, 0.0, w, h, "phase");
    // Margins of `Plot::render` with a title, no vline labels and no note: 68, 16 + the
    // legend, 36, 50.
    let (px, py, pw, ph) = (68.0, 36.0, w - 68.0 - 16.0 - LEGEND_W, h - 36.0 - 50.0);
    let sy = |v: f64| py + ph - (v - range.2) / (range.3 - range.2) * ph;
    let sx = |v: f64| px + (v - range.0) / (range.1 - range.0) * pw;
    for (x, y, why) in &ends {
        svg.text(
            sx(*x) + 8.0,
            sy(*y) - 8.0,
            11.0,
            Anchor::Start,
            &format!("stops: {why}"),
        );
    }
    // The scene's value.
    let xs = xv(param.scene_value);
    if xs >= range.0 && xs <= range.1 {
        svg.line(sx(xs), py, sx(xs), py + ph, "#555", 1.0, "2 3");
        svg.text(sx(xs) - 4.0, py + ph - 6.0, 11.0, Anchor::End, "scene");
    }
    // Integer lengths: collapses onto m-fold great circles.
    let mut m = range.2.ceil();
    while m <= range.3 {
        svg.line(px, sy(m), px + pw, sy(m), "#999", 0.8, "4 3");
        svg.text(
            px + 6.0,
            sy(m) - 5.0,
            11.0,
            Anchor::Start,
            &format!("L̄ = {m}: {m}-fold great circle"),
        );
        m += 1.0;
    }
    // Region labels at two places along the axis: each band between neighbouring
    // boundaries (curves, integers) named by the lowest branch the curve below or above
    // it gives.
    // A band already labelled at the first place is not labelled again at the second.
    let mut placed: Vec<(u32, f64, f64)> = Vec::new();
    for frac in [0.18, 0.45] {
        let x = range.0 + frac * (range.1 - range.0);
        // (L̄, lowest below, lowest above) of each curve at x; integers carry none.
        let mut bounds: Vec<(f64, Option<(u32, u32)>)> = d
            .curves
            .iter()
            .filter_map(|c| curve_at(c, x, &xv))
            .map(|(l, a, b)| (l, Some((a, b))))
            .collect();
        let mut m = range.2.ceil();
        while m <= range.3 {
            bounds.push((m, None));
            m += 1.0;
        }
        bounds.push((range.2, None));
        bounds.push((range.3, None));
        bounds.sort_by(|a, b| a.0.total_cmp(&b.0));
        for w in bounds.windows(2) {
            let (lo, hi) = (&w[0], &w[1]);
            let branch = match (lo.1, hi.1) {
                (Some((_, above)), _) => above,
                (None, Some((below, _))) => below,
                _ => continue,
            };
            if sy(lo.0) - sy(hi.0) < 22.0 {
                continue;
            }
            if placed
                .iter()
                .any(|&(b, a, c)| b == branch && lo.0 < c && hi.0 > a)
            {
                continue;
            }
            placed.push((branch, lo.0, hi.0));
            svg.text(
                sx(x),
                0.5 * (sy(lo.0) + sy(hi.0)) + 4.0,
                12.5,
                Anchor::Middle,
                &format!("branch {branch} lowest"),
            );
        }
    }
    svg.finish()
}

/// A curve end short of the requested range.
pub(crate) struct Short {
    pub from: u32,
    pub to: u32,
    pub value: f64,
    pub kind: String,
}

/// The curve ends that stop between the scene's value and `--to` (not `reached`, not the
/// uniform-rod `limit`).
pub(crate) fn stopped_short(d: &PhaseRows) -> Vec<Short> {
    d.curves
        .iter()
        .flat_map(|c| {
            let ex = c.curve.exchange;
            c.curve
                .stopped_short(d.parameter.range())
                .map(move |e| Short {
                    from: ex.from_branch,
                    to: ex.to_branch,
                    value: e.value,
                    kind: e.kind.clone(),
                })
        })
        .collect()
}
