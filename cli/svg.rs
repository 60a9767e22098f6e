//! A small, dependency-free SVG line-plot writer for the energy-versus-length diagram.
//!
//! (plotters' text layout needs a system font through font-kit, which a fresh machine may
//! not have; SVG `<text>` elements need none.)

use std::fmt::Write as _;

/// Line style of a curve segment.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LineStyle {
    /// Solid line.
    Solid,
    /// Dashed line.
    Dashed,
    /// Dotted line.
    Dotted,
}

impl LineStyle {
    fn dasharray(self) -> &'static str {
        match self {
            LineStyle::Solid => "",
            LineStyle::Dashed => " stroke-dasharray=\"7 4\"",
            LineStyle::Dotted => " stroke-dasharray=\"1.5 3\"",
        }
    }
}

/// One polyline of the plot.
#[derive(Clone, Debug)]
pub struct Curve {
    /// Colour (SVG colour string).
    pub color: String,
    /// Line style.
    pub style: LineStyle,
    /// Line width in pixels.
    pub width: f64,
    /// Points in data coordinates.
    pub points: Vec<(f64, f64)>,
}

/// A vertical marker line with a label (critical lengths).
#[derive(Clone, Debug)]
pub struct Marker {
    /// Data x position.
    pub x: f64,
    /// Label drawn at the top.
    pub label: String,
}

/// A legend entry.
#[derive(Clone, Debug)]
pub struct LegendEntry {
    /// Text.
    pub label: String,
    /// Colour.
    pub color: String,
    /// Style.
    pub style: LineStyle,
}

/// Everything drawn in one figure.
#[derive(Clone, Debug, Default)]
pub struct Figure {
    /// Title above the plot.
    pub title: String,
    /// x-axis label.
    pub xlabel: String,
    /// y-axis label.
    pub ylabel: String,
    /// Curves.
    pub curves: Vec<Curve>,
    /// Vertical markers.
    pub markers: Vec<Marker>,
    /// Legend entries.
    pub legend: Vec<LegendEntry>,
    /// Data range `(xmin, xmax, ymin, ymax)`; computed from the curves when `None`.
    pub range: Option<(f64, f64, f64, f64)>,
}

/// Split a branch's points `(x, y, key)` into runs of equal key, one curve per run made by
/// `curve(key, points)`; each run also takes the first point of the next so the runs join up.
pub fn runs<K: PartialEq + Copy>(
    pts: &[(f64, f64, K)],
    mut curve: impl FnMut(K, Vec<(f64, f64)>) -> Curve,
) -> Vec<Curve> {
    let mut out = Vec::new();
    let mut start = 0;
    for i in 1..=pts.len() {
        if i == pts.len() || pts[i].2 != pts[start].2 {
            let end = (i + 1).min(pts.len());
            out.push(curve(
                pts[start].2,
                pts[start..end].iter().map(|p| (p.0, p.1)).collect(),
            ));
            start = i;
        }
    }
    out
}

/// Colours for branches 1, 2, 3, …: blue, red, green, pink (as in the paper's Fig. 3), then more.
pub fn branch_color(branch: u32) -> String {
    const C: [&str; 8] = [
        "#1f4fd1", "#d62728", "#2ca02c", "#e377c2", "#ff7f0e", "#8c564b", "#17becf", "#7f7f7f",
    ];
    C[(branch.max(1) as usize - 1) % C.len()].to_string()
}

/// "Nice" tick spacing for a range.
fn tick_step(span: f64) -> f64 {
    let raw = span / 8.0;
    let mag = 10f64.powf(raw.log10().floor());
    let norm = raw / mag;
    let nice = if norm < 1.5 {
        1.0
    } else if norm < 3.5 {
        2.0
    } else if norm < 7.5 {
        5.0
    } else {
        10.0
    };
    nice * mag
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// Render the figure as an SVG document.
pub fn render(fig: &Figure) -> String {
    let (w, h) = (900.0, 620.0);
    let (ml, mr, mt, mb) = (80.0, 220.0, 60.0, 60.0);
    let (pw, ph) = (w - ml - mr, h - mt - mb);
    let (x0, x1, y0, y1) = fig.range.unwrap_or_else(|| {
        let mut r = (
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        );
        for c in &fig.curves {
            for &(x, y) in &c.points {
                r = (r.0.min(x), r.1.max(x), r.2.min(y), r.3.max(y));
            }
        }
        if !r.0.is_finite() {
            r = (0.0, 1.0, 0.0, 1.0);
        }
        let pad = 0.04 * (r.3 - r.2).max(1e-12);
        (r.0, r.1, r.2 - pad, r.3 + pad)
    });
    let sx = |x: f64| ml + (x - x0) / (x1 - x0) * pw;
    let sy = |y: f64| mt + ph - (y - y0) / (y1 - y0) * ph;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\" font-family=\"sans-serif\" font-size=\"13\">"
    );
    let _ = writeln!(s, "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>");
    let _ = writeln!(
        s,
        "<text x=\"{}\" y=\"30\" text-anchor=\"middle\" font-size=\"16\">{}</text>",
        ml + pw / 2.0,
        esc(&fig.title)
    );
    // Clip region for data.
    let _ = writeln!(
        s,
        "<defs><clipPath id=\"plot\"><rect x=\"{ml}\" y=\"{mt}\" width=\"{pw}\" height=\"{ph}\"/></clipPath></defs>"
    );
    // Ticks and grid.
    let xs = tick_step(x1 - x0);
    let mut t = (x0 / xs).ceil() * xs;
    while t <= x1 + 1e-9 * xs {
        let _ = writeln!(
            s,
            "<line x1=\"{0:.2}\" y1=\"{1}\" x2=\"{0:.2}\" y2=\"{2}\" stroke=\"#e6e6e6\"/><text x=\"{0:.2}\" y=\"{3}\" text-anchor=\"middle\">{4}</text>",
            sx(t),
            mt,
            mt + ph,
            mt + ph + 18.0,
            trim(t)
        );
        t += xs;
    }
    let ys = tick_step(y1 - y0);
    let mut t = (y0 / ys).ceil() * ys;
    while t <= y1 + 1e-9 * ys {
        let _ = writeln!(
            s,
            "<line x1=\"{0}\" y1=\"{1:.2}\" x2=\"{2}\" y2=\"{1:.2}\" stroke=\"#e6e6e6\"/><text x=\"{3}\" y=\"{4:.2}\" text-anchor=\"end\">{5}</text>",
            ml,
            sy(t),
            ml + pw,
            ml - 6.0,
            sy(t) + 4.0,
            trim(t)
        );
        t += ys;
    }
    let _ = writeln!(
        s,
        "<rect x=\"{ml}\" y=\"{mt}\" width=\"{pw}\" height=\"{ph}\" fill=\"none\" stroke=\"black\"/>"
    );
    let _ = writeln!(
        s,
        "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">{}</text>",
        ml + pw / 2.0,
        h - 15.0,
        esc(&fig.xlabel)
    );
    let _ = writeln!(
        s,
        "<text x=\"20\" y=\"{}\" text-anchor=\"middle\" transform=\"rotate(-90 20 {})\">{}</text>",
        mt + ph / 2.0,
        mt + ph / 2.0,
        esc(&fig.ylabel)
    );
    // Markers.
    for m in &fig.markers {
        if m.x < x0 || m.x > x1 {
            continue;
        }
        let _ = writeln!(
            s,
            "<line x1=\"{0:.2}\" y1=\"{1}\" x2=\"{0:.2}\" y2=\"{2}\" stroke=\"#555\" stroke-width=\"0.8\" stroke-dasharray=\"2 3\"/><text x=\"{0:.2}\" y=\"{3}\" text-anchor=\"middle\" font-size=\"11\">{4}</text>",
            sx(m.x),
            mt,
            mt + ph,
            mt - 6.0,
            esc(&m.label)
        );
    }
    // Curves.
    let _ = writeln!(s, "<g clip-path=\"url(#plot)\" fill=\"none\">");
    for c in &fig.curves {
        if c.points.len() < 2 {
            continue;
        }
        let mut d = String::new();
        for (i, &(x, y)) in c.points.iter().enumerate() {
            let _ = write!(
                d,
                "{}{:.2},{:.2}",
                if i == 0 { "M" } else { " L" },
                sx(x),
                sy(y)
            );
        }
        let _ = writeln!(
            s,
            "<path d=\"{d}\" stroke=\"{}\" stroke-width=\"{}\"{}/>",
            c.color,
            c.width,
            c.style.dasharray()
        );
    }
    let _ = writeln!(s, "</g>");
    // Legend.
    let lx = ml + pw + 20.0;
    for (i, e) in fig.legend.iter().enumerate() {
        let y = mt + 10.0 + 22.0 * i as f64;
        let _ = writeln!(
            s,
            "<line x1=\"{lx}\" y1=\"{y}\" x2=\"{}\" y2=\"{y}\" stroke=\"{}\" stroke-width=\"2\"{}/><text x=\"{}\" y=\"{}\">{}</text>",
            lx + 30.0,
            e.color,
            e.style.dasharray(),
            lx + 38.0,
            y + 4.0,
            esc(&e.label)
        );
    }
    s.push_str("</svg>\n");
    s
}

fn trim(v: f64) -> String {
    let s = format!("{v:.6}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".into()
    } else {
        s.into()
    }
}
