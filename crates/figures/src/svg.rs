//! A minimal SVG document writer: the figures are built from a handful of primitives
//! (lines, polylines, circles, rectangles, text), so a string builder is all we need, and
//! every coordinate is ours to check.

use std::fmt::Write as _;

/// Escape text for an SVG text node or attribute.
pub fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Horizontal text anchor.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Anchor {
    /// Text starts at x.
    Start,
    /// Text is centred on x.
    Middle,
    /// Text ends at x.
    End,
}

impl Anchor {
    fn as_str(self) -> &'static str {
        match self {
            Anchor::Start => "start",
            Anchor::Middle => "middle",
            Anchor::End => "end",
        }
    }
}

/// An SVG document under construction.
#[derive(Clone, Debug)]
pub struct Svg {
    width: f64,
    height: f64,
    body: String,
    defs: String,
}

impl Svg {
    /// A blank white document of `width × height` pixels.
    pub fn new(width: f64, height: f64) -> Self {
        let mut s = Self {
            width,
            height,
            body: String::new(),
            defs: String::new(),
        };
        s.rect(0.0, 0.0, width, height, "white", "none", 0.0);
        s
    }

    /// Width in pixels.
    pub fn width(&self) -> f64 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> f64 {
        self.height
    }

    /// Append raw markup to the `<defs>` section (gradients, clip paths).
    pub fn def(&mut self, markup: &str) {
        self.defs.push_str(markup);
        self.defs.push('\n');
    }

    /// Append raw markup to the body.
    pub fn raw(&mut self, markup: &str) {
        self.body.push_str(markup);
        self.body.push('\n');
    }

    /// A straight line.
    #[allow(clippy::too_many_arguments)]
    pub fn line(
        &mut self,
        x1: f64,
        y1: f64,
        x2: f64,
        y2: f64,
        color: &str,
        width: f64,
        dash: &str,
    ) {
        let dash = if dash.is_empty() {
            String::new()
        } else {
            format!(" stroke-dasharray=\"{dash}\"")
        };
        let _ = writeln!(
            self.body,
            "<line x1=\"{x1:.2}\" y1=\"{y1:.2}\" x2=\"{x2:.2}\" y2=\"{y2:.2}\" stroke=\"{color}\" stroke-width=\"{width:.2}\"{dash}/>"
        );
    }

    /// A line segment with round caps and an opacity (used for the depth-sorted loop).
    #[allow(clippy::too_many_arguments)]
    pub fn segment(&mut self, a: (f64, f64), b: (f64, f64), color: &str, width: f64, opacity: f64) {
        let _ = writeln!(
            self.body,
            "<line x1=\"{:.2}\" y1=\"{:.2}\" x2=\"{:.2}\" y2=\"{:.2}\" stroke=\"{color}\" stroke-width=\"{width:.2}\" stroke-linecap=\"round\" stroke-opacity=\"{opacity:.3}\"/>",
            a.0, a.1, b.0, b.1
        );
    }

    /// An open polyline.
    pub fn polyline(&mut self, pts: &[(f64, f64)], color: &str, width: f64, dash: &str) {
        if pts.len() < 2 {
            return;
        }
        let mut d = String::with_capacity(pts.len() * 16);
        for (i, p) in pts.iter().enumerate() {
            let _ = write!(
                d,
                "{}{:.2},{:.2}",
                if i == 0 { "M" } else { " L" },
                p.0,
                p.1
            );
        }
        let dash = if dash.is_empty() {
            String::new()
        } else {
            format!(" stroke-dasharray=\"{dash}\"")
        };
        let _ = writeln!(
            self.body,
            "<path d=\"{d}\" fill=\"none\" stroke=\"{color}\" stroke-width=\"{width:.2}\" stroke-linejoin=\"round\"{dash}/>"
        );
    }

    /// A rectangle.
    #[allow(clippy::too_many_arguments)]
    pub fn rect(&mut self, x: f64, y: f64, w: f64, h: f64, fill: &str, stroke: &str, sw: f64) {
        let _ = writeln!(
            self.body,
            "<rect x=\"{x:.2}\" y=\"{y:.2}\" width=\"{w:.2}\" height=\"{h:.2}\" fill=\"{fill}\" stroke=\"{stroke}\" stroke-width=\"{sw:.2}\"/>"
        );
    }

    /// A circle.
    pub fn circle(&mut self, cx: f64, cy: f64, r: f64, fill: &str, stroke: &str, sw: f64) {
        let _ = writeln!(
            self.body,
            "<circle cx=\"{cx:.2}\" cy=\"{cy:.2}\" r=\"{r:.2}\" fill=\"{fill}\" stroke=\"{stroke}\" stroke-width=\"{sw:.2}\"/>"
        );
    }

    /// A closed polygon.
    pub fn polygon(&mut self, pts: &[(f64, f64)], fill: &str, stroke: &str, sw: f64) {
        let mut d = String::new();
        for p in pts {
            let _ = write!(d, "{:.2},{:.2} ", p.0, p.1);
        }
        let _ = writeln!(
            self.body,
            "<polygon points=\"{}\" fill=\"{fill}\" stroke=\"{stroke}\" stroke-width=\"{sw:.2}\"/>",
            d.trim_end()
        );
    }

    /// Text at `(x, y)` (baseline), `size` pixels.
    pub fn text(&mut self, x: f64, y: f64, size: f64, anchor: Anchor, s: &str) {
        let _ = writeln!(
            self.body,
            "<text x=\"{x:.2}\" y=\"{y:.2}\" font-size=\"{size:.1}\" text-anchor=\"{}\">{}</text>",
            anchor.as_str(),
            esc(s)
        );
    }

    /// Text rotated by −90° about `(x, y)` (a y-axis label).
    pub fn text_vertical(&mut self, x: f64, y: f64, size: f64, s: &str) {
        let _ = writeln!(
            self.body,
            "<text x=\"{x:.2}\" y=\"{y:.2}\" font-size=\"{size:.1}\" text-anchor=\"middle\" transform=\"rotate(-90 {x:.2} {y:.2})\">{}</text>",
            esc(s)
        );
    }

    /// Bold text.
    pub fn text_bold(&mut self, x: f64, y: f64, size: f64, anchor: Anchor, s: &str) {
        let _ = writeln!(
            self.body,
            "<text x=\"{x:.2}\" y=\"{y:.2}\" font-size=\"{size:.1}\" font-weight=\"bold\" text-anchor=\"{}\">{}</text>",
            anchor.as_str(),
            esc(s)
        );
    }

    /// Open a group clipped to a rectangle; close it with [`Svg::end_group`].
    pub fn begin_clip(&mut self, id: &str, x: f64, y: f64, w: f64, h: f64) {
        self.def(&format!(
            "<clipPath id=\"{id}\"><rect x=\"{x:.2}\" y=\"{y:.2}\" width=\"{w:.2}\" height=\"{h:.2}\"/></clipPath>"
        ));
        let _ = writeln!(self.body, "<g clip-path=\"url(#{id})\">");
    }

    /// Close a group.
    pub fn end_group(&mut self) {
        self.body.push_str("</g>\n");
    }

    /// The finished document.
    pub fn finish(&self) -> String {
        format!(
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\" font-family=\"DejaVu Sans, sans-serif\">\n<defs>\n{}</defs>\n{}</svg>\n",
            self.defs,
            self.body,
            w = self.width,
            h = self.height
        )
    }
}

/// A number for a tick label: at most 6 decimals, trailing zeros dropped, no "-0".
pub fn tick_label(v: f64) -> String {
    let s = format!("{v:.6}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".into()
    } else {
        s.replace('-', "−")
    }
}

/// "Nice" tick positions covering `[lo, hi]` (about `target` of them).
pub fn ticks(lo: f64, hi: f64, target: usize) -> Vec<f64> {
    let span = (hi - lo).abs();
    if !(span.is_finite() && span > 0.0) {
        return vec![lo];
    }
    let raw = span / target.max(1) as f64;
    let mag = 10f64.powf(raw.log10().floor());
    let norm = raw / mag;
    let step = mag
        * if norm < 1.5 {
            1.0
        } else if norm < 3.5 {
            2.0
        } else if norm < 7.5 {
            5.0
        } else {
            10.0
        };
    let mut out = Vec::new();
    let mut k = (lo / step).ceil();
    while k * step <= hi + 1e-9 * step {
        out.push(k * step);
        k += 1.0;
    }
    out
}
