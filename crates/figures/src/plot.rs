//! Line plots with axes, ticks, Unicode labels, point markers and a legend that lists only
//! what is drawn.

use crate::svg::{tick_label, ticks, Anchor, Svg};

/// A marker shape.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    /// Filled circle.
    Circle,
    /// Filled square.
    Square,
    /// Filled upward triangle.
    Triangle,
    /// Filled diamond.
    Diamond,
    /// Open square.
    OpenSquare,
}

/// A polyline in data coordinates.
#[derive(Clone, Debug)]
pub struct Series {
    /// Colour.
    pub color: String,
    /// Width, pixels.
    pub width: f64,
    /// SVG dash pattern ("" for solid).
    pub dash: String,
    /// Points.
    pub points: Vec<(f64, f64)>,
}

/// A marker at a data point.
#[derive(Clone, Debug)]
pub struct Mark {
    /// Position.
    pub at: (f64, f64),
    /// Shape.
    pub shape: Shape,
    /// Fill colour.
    pub color: String,
    /// Half-size in pixels.
    pub size: f64,
}

/// A legend entry: a line sample or a marker sample, and its text.
#[derive(Clone, Debug)]
pub enum LegendItem {
    /// A line sample.
    Line {
        /// Text.
        label: String,
        /// Colour.
        color: String,
        /// Width.
        width: f64,
        /// Dash pattern.
        dash: String,
    },
    /// A marker sample.
    Mark {
        /// Text.
        label: String,
        /// Shape.
        shape: Shape,
        /// Colour.
        color: String,
    },
}

/// One plot panel.
#[derive(Clone, Debug, Default)]
pub struct Plot {
    /// Title above the panel.
    pub title: String,
    /// x-axis label.
    pub xlabel: String,
    /// y-axis label.
    pub ylabel: String,
    /// Lines.
    pub series: Vec<Series>,
    /// Markers.
    pub marks: Vec<Mark>,
    /// Vertical guide lines with a label at the top.
    pub vlines: Vec<(f64, String)>,
    /// Horizontal guide lines (drawn thin grey).
    pub hlines: Vec<f64>,
    /// Legend entries (drawn to the right of the axes when `legend_width > 0`, else inside).
    pub legend: Vec<LegendItem>,
    /// Width reserved right of the axes for the legend (0: legend inside, top right).
    pub legend_width: f64,
    /// Data range `(xmin, xmax, ymin, ymax)`; from the data when `None`.
    pub range: Option<(f64, f64, f64, f64)>,
    /// A note under the x-axis label (small text).
    pub note: String,
}

/// Draw a marker at pixel position `(x, y)`.
pub fn draw_mark(svg: &mut Svg, x: f64, y: f64, shape: Shape, color: &str, r: f64) {
    match shape {
        Shape::Circle => svg.circle(x, y, r, color, "black", 0.8),
        Shape::Square => svg.rect(x - r, y - r, 2.0 * r, 2.0 * r, color, "black", 0.8),
        Shape::OpenSquare => svg.rect(x - r, y - r, 2.0 * r, 2.0 * r, "white", color, 1.8),
        Shape::Triangle => svg.polygon(
            &[
                (x, y - 1.2 * r),
                (x - 1.1 * r, y + 0.8 * r),
                (x + 1.1 * r, y + 0.8 * r),
            ],
            color,
            "black",
            0.8,
        ),
        Shape::Diamond => svg.polygon(
            &[(x, y - 1.3 * r), (x + r, y), (x, y + 1.3 * r), (x - r, y)],
            color,
            "black",
            0.8,
        ),
    }
}

/// A y-range that keeps a few sharp outliers from flattening every curve: the 2nd to 98th
/// percentile of `values` (weighted by `weights` when given, e.g. the arclength each sample
/// of a loop stands for, so that a mesh refined at the peaks does not count them many
/// times), widened by 15 % of its span (and to include 0 when it is near). Returns
/// `Some((lo, hi))` only when some values lie more than half that span outside it (e.g. the
/// contact-force spikes at the stiffness steps of a two-segment rod); `None` when the full
/// range shows everything well.
pub fn robust_range(values: &[f64], weights: Option<&[f64]>) -> Option<(f64, f64)> {
    let mut v: Vec<(f64, f64)> = values
        .iter()
        .enumerate()
        .map(|(i, &x)| (x, weights.map_or(1.0, |w| w.get(i).copied().unwrap_or(0.0))))
        .filter(|(x, w)| x.is_finite() && w.is_finite() && *w >= 0.0)
        .collect();
    if v.len() < 20 {
        return None;
    }
    v.sort_by(|a, b| a.0.total_cmp(&b.0));
    let total: f64 = v.iter().map(|p| p.1).sum();
    if total.is_nan() || total <= 0.0 {
        return None;
    }
    let q = |p: f64| {
        let mut acc = 0.0;
        for &(x, w) in &v {
            acc += w;
            if acc >= p * total {
                return x;
            }
        }
        v[v.len() - 1].0
    };
    let (lo, hi) = (q(0.02), q(0.98));
    let span = hi - lo;
    if span <= 0.0 {
        return None;
    }
    let (min, max) = (v[0].0, v[v.len() - 1].0);
    if min >= lo - 0.5 * span && max <= hi + 0.5 * span {
        return None;
    }
    let (mut a, mut b) = (lo - 0.15 * span, hi + 0.15 * span);
    if a > 0.0 && a < 0.5 * span {
        a = 0.0;
    }
    if b < 0.0 && -b < 0.5 * span {
        b = 0.0;
    }
    Some((a, b))
}

/// The arclength each sample of a closed loop stands for: half the spacing to each
/// neighbour (the last closes the loop at `length`), for [`robust_range`].
pub fn arclength_weights(s: &[f64], length: f64) -> Vec<f64> {
    let n = s.len();
    (0..n)
        .map(|i| {
            let before = if i == 0 {
                s[0] + length - s[n - 1]
            } else {
                s[i] - s[i - 1]
            };
            let after = if i + 1 == n {
                s[0] + length - s[n - 1]
            } else {
                s[i + 1] - s[i]
            };
            0.5 * (before + after).max(0.0)
        })
        .collect()
}

/// The note of a panel clipped by [`robust_range`]: how far the values run off it.
pub fn clipped_note(what: &str, values: &[f64], shown: (f64, f64)) -> String {
    let (min, max) = values
        .iter()
        .filter(|x| x.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    format!(
        "{what} axis clipped to {} … {}: values reach {} … {} (sharp peaks, e.g. at stiffness steps)",
        tick_label((shown.0 * 1e3).round() / 1e3),
        tick_label((shown.1 * 1e3).round() / 1e3),
        tick_label((min * 1e3).round() / 1e3),
        tick_label((max * 1e3).round() / 1e3)
    )
}

impl Plot {
    /// The x-range of the data (series and marks), for a caller that sets `range` itself.
    pub fn x_range(&self) -> (f64, f64) {
        let mut r = (f64::INFINITY, f64::NEG_INFINITY);
        for (x, _) in self
            .series
            .iter()
            .flat_map(|s| s.points.iter().copied())
            .chain(self.marks.iter().map(|m| m.at))
        {
            if x.is_finite() {
                r = (r.0.min(x), r.1.max(x));
            }
        }
        if r.0.is_finite() {
            r
        } else {
            (0.0, 1.0)
        }
    }

    /// The data range (with 4 % vertical padding) when none is set.
    pub fn data_range(&self) -> (f64, f64, f64, f64) {
        if let Some(r) = self.range {
            return r;
        }
        let mut r = (
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        );
        let pts = self
            .series
            .iter()
            .flat_map(|s| s.points.iter().copied())
            .chain(self.marks.iter().map(|m| m.at));
        for (x, y) in pts {
            if x.is_finite() && y.is_finite() {
                r = (r.0.min(x), r.1.max(x), r.2.min(y), r.3.max(y));
            }
        }
        if !r.0.is_finite() {
            return (0.0, 1.0, 0.0, 1.0);
        }
        if r.1 - r.0 <= 0.0 {
            r.0 -= 0.5;
            r.1 += 0.5;
        }
        let span = r.3 - r.2;
        if span <= 1e-9 * r.2.abs().max(r.3.abs()).max(1.0) {
            // A constant (to rounding): centre it in a range wide enough for readable ticks.
            let c = 0.5 * (r.2 + r.3);
            let half = 0.5 * c.abs().max(1.0);
            return (r.0, r.1, c - half, c + half);
        }
        let pad = 0.05 * span;
        (r.0, r.1, r.2 - pad, r.3 + pad)
    }

    /// Render into the box `(x, y, w, h)` of `svg`; `id` names the clip path.
    pub fn render(&self, svg: &mut Svg, x: f64, y: f64, w: f64, h: f64, id: &str) {
        let (x0, x1, y0, y1) = self.data_range();
        // Room for the widest y tick label between the axis and the rotated y label.
        let widest = ticks(y0, y1, ((h - 100.0) / 50.0).max(3.0) as usize)
            .iter()
            .map(|&t| tick_label(t).chars().count())
            .max()
            .unwrap_or(1) as f64;
        let (ml, mr, mt, mb) = (
            (36.0 + 7.2 * widest).max(68.0),
            16.0 + self.legend_width,
            match (
                self.title.is_empty(),
                self.vlines.iter().any(|v| !v.1.is_empty()),
            ) {
                (true, false) => 14.0,
                (true, true) | (false, false) => 36.0,
                (false, true) => 62.0,
            },
            if self.note.is_empty() { 50.0 } else { 66.0 },
        );
        let (px, py, pw, ph) = (x + ml, y + mt, w - ml - mr, h - mt - mb);
        let sx = |v: f64| px + (v - x0) / (x1 - x0) * pw;
        let sy = |v: f64| py + ph - (v - y0) / (y1 - y0) * ph;
        if !self.title.is_empty() {
            svg.text_bold(px + pw / 2.0, y + 22.0, 15.0, Anchor::Middle, &self.title);
        }
        for t in ticks(x0, x1, (pw / 80.0).max(3.0) as usize) {
            svg.line(sx(t), py, sx(t), py + ph, "#ececec", 1.0, "");
            svg.line(sx(t), py + ph, sx(t), py + ph + 5.0, "#333", 1.0, "");
            svg.text(sx(t), py + ph + 19.0, 12.5, Anchor::Middle, &tick_label(t));
        }
        for t in ticks(y0, y1, (ph / 50.0).max(3.0) as usize) {
            svg.line(px, sy(t), px + pw, sy(t), "#ececec", 1.0, "");
            svg.line(px - 5.0, sy(t), px, sy(t), "#333", 1.0, "");
            svg.text(px - 8.0, sy(t) + 4.0, 12.5, Anchor::End, &tick_label(t));
        }
        svg.text(
            px + pw / 2.0,
            py + ph + 40.0,
            14.0,
            Anchor::Middle,
            &self.xlabel,
        );
        if !self.note.is_empty() {
            svg.text(
                px + pw / 2.0,
                py + ph + 58.0,
                11.5,
                Anchor::Middle,
                &self.note,
            );
        }
        svg.text_vertical(x + 16.0, py + ph / 2.0, 14.0, &self.ylabel);
        svg.begin_clip(id, px, py, pw, ph);
        for &hy in &self.hlines {
            svg.line(px, sy(hy), px + pw, sy(hy), "#999", 0.8, "");
        }
        for (vx, _) in &self.vlines {
            if *vx >= x0 && *vx <= x1 {
                svg.line(sx(*vx), py, sx(*vx), py + ph, "#9a9a9a", 0.8, "2 3");
            }
        }
        for s in &self.series {
            let pts: Vec<(f64, f64)> = s.points.iter().map(|&(a, b)| (sx(a), sy(b))).collect();
            svg.polyline(&pts, &s.color, s.width, &s.dash);
        }
        svg.end_group();
        for m in &self.marks {
            let (a, b) = m.at;
            if a >= x0 && a <= x1 && b >= y0 && b <= y1 {
                draw_mark(svg, sx(a), sy(b), m.shape, &m.color, m.size);
            }
        }
        svg.rect(px, py, pw, ph, "none", "#222", 1.0);
        // Guide-line labels, nudged apart when they would overlap.
        let mut last = f64::NEG_INFINITY;
        let mut row = 0;
        for (vx, label) in &self.vlines {
            if *vx < x0 || *vx > x1 || label.is_empty() {
                continue;
            }
            let px_ = sx(*vx);
            row = if px_ - last < 44.0 { 1 - row } else { 0 };
            last = px_;
            svg.text(
                px_,
                py - 5.0 - 12.0 * row as f64,
                11.0,
                Anchor::Middle,
                label,
            );
        }
        // Legend.
        if self.legend.is_empty() {
            return;
        }
        let row_h = 21.0;
        let (lx, ly, boxed) = if self.legend_width > 0.0 {
            (px + pw + 18.0, py + 6.0, false)
        } else {
            let lw = self
                .legend
                .iter()
                .map(|l| match l {
                    LegendItem::Line { label, .. } | LegendItem::Mark { label, .. } => {
                        label.chars().count()
                    }
                })
                .max()
                .unwrap_or(0) as f64
                * 6.8
                + 48.0;
            (px + pw - lw - 8.0, py + 8.0, true)
        };
        if boxed {
            let lw = px + pw - 8.0 - lx;
            svg.rect_translucent(
                (
                    lx - 4.0,
                    ly - 4.0,
                    lw + 4.0,
                    row_h * self.legend.len() as f64 + 4.0,
                ),
                "white",
                0.85,
                "#bbb",
                1.0,
            );
        }
        for (k, item) in self.legend.iter().enumerate() {
            let yy = ly + row_h * k as f64 + 10.0;
            let label = match item {
                LegendItem::Line {
                    label,
                    color,
                    width,
                    dash,
                } => {
                    svg.line(lx, yy, lx + 30.0, yy, color, *width, dash);
                    label
                }
                LegendItem::Mark {
                    label,
                    shape,
                    color,
                } => {
                    draw_mark(svg, lx + 15.0, yy, *shape, color, 5.0);
                    label
                }
            };
            svg.text(lx + 38.0, yy + 4.5, 12.5, Anchor::Start, label);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two narrow spikes on a smooth curve are clipped, and only when the samples are
    /// weighted by the arclength they stand for if the mesh crowds at the spikes.
    #[test]
    fn spikes_are_clipped_smooth_data_is_not() {
        let smooth: Vec<f64> = (0..200).map(|i| (i as f64 * 0.05).sin()).collect();
        assert_eq!(robust_range(&smooth, None), None);
        let mut spiky = smooth.clone();
        spiky[50] = 80.0;
        spiky[150] = -80.0;
        let (a, b) = robust_range(&spiky, None).unwrap();
        assert!(a > -2.0 && a < -1.0 && b > 1.0 && b < 2.0, "{a} {b}");
        // Forty samples at each spike (a refined mesh), each standing for a tiny length.
        let mut v = smooth.clone();
        let mut w = vec![1.0; v.len()];
        for _ in 0..40 {
            v.push(80.0);
            v.push(-80.0);
            w.push(1e-3);
            w.push(1e-3);
        }
        assert_eq!(robust_range(&v, None), None);
        assert!(robust_range(&v, Some(&w)).is_some());
    }
}
