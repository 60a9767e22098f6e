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

/// The gradient of [`Svg::sphere`] (object-bounding-box units): centre and focus at
/// (0.42, 0.38), radius 0.62, from near-white to a light steel blue.
pub const SPHERE_GRADIENT: &str = "<radialGradient id=\"sphere\" cx=\"0.42\" cy=\"0.38\" r=\"0.62\"><stop offset=\"0\" stop-color=\"#eef4fb\"/><stop offset=\"0.75\" stop-color=\"#c9d8ea\"/><stop offset=\"1\" stop-color=\"#9fb4cf\"/></radialGradient>";

/// ` stroke-dasharray="…"`, or nothing for a solid stroke.
fn dash_attr(dash: &str) -> String {
    if dash.is_empty() {
        String::new()
    } else {
        format!(" stroke-dasharray=\"{dash}\"")
    }
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

/// One drawing operation, kept alongside the markup so that [`crate::paint`] can draw the
/// PNG with tiny-skia directly instead of parsing the SVG text back.
#[derive(Clone, Debug, PartialEq)]
pub enum Op {
    /// A line, optionally dashed (`dash` as in `stroke-dasharray`), with round caps if
    /// `round`, and a stroke opacity.
    Line {
        /// Start.
        a: (f64, f64),
        /// End.
        b: (f64, f64),
        /// Colour.
        color: String,
        /// Stroke width.
        width: f64,
        /// Dash pattern (empty: solid).
        dash: String,
        /// Round caps.
        round: bool,
        /// Opacity.
        opacity: f64,
    },
    /// An open polyline with round joins.
    Polyline {
        /// Vertices.
        pts: Vec<(f64, f64)>,
        /// Colour.
        color: String,
        /// Stroke width.
        width: f64,
        /// Dash pattern (empty: solid).
        dash: String,
    },
    /// A closed polygon, rectangle (4 corners) or circle (`circle: Some((cx, cy, r))`).
    Shape {
        /// Vertices (ignored for a circle).
        pts: Vec<(f64, f64)>,
        /// Circle centre and radius.
        circle: Option<(f64, f64, f64)>,
        /// Fill colour (`none`: no fill).
        fill: String,
        /// Fill opacity.
        fill_opacity: f64,
        /// Stroke colour (`none`: no stroke).
        stroke: String,
        /// Stroke width.
        width: f64,
        /// Dash pattern of the stroke (empty: solid).
        dash: String,
    },
    /// The translucent shaded sphere of the loop pictures.
    Sphere {
        /// Centre x.
        cx: f64,
        /// Centre y.
        cy: f64,
        /// Radius.
        r: f64,
    },
    /// Text with its baseline at `(x, y)`.
    Text {
        /// Anchor point x.
        x: f64,
        /// Baseline y.
        y: f64,
        /// Font size in pixels.
        size: f64,
        /// Horizontal anchor.
        anchor: Anchor,
        /// Bold.
        bold: bool,
        /// Rotated by −90° about `(x, y)`.
        vertical: bool,
        /// The text.
        text: String,
    },
    /// Start clipping to a rectangle `(x, y, w, h)`.
    BeginClip(f64, f64, f64, f64),
    /// End the innermost clip.
    EndClip,
}

/// An SVG document under construction.
#[derive(Clone, Debug)]
pub struct Svg {
    width: f64,
    height: f64,
    body: String,
    defs: String,
    ops: Vec<Op>,
    /// False once raw markup was added: the PNG then goes through resvg.
    direct: bool,
    sphere_def: bool,
}

impl Svg {
    /// A blank white document of `width × height` pixels.
    pub fn new(width: f64, height: f64) -> Self {
        let mut s = Self {
            width,
            height,
            body: String::new(),
            defs: String::new(),
            ops: Vec::new(),
            direct: true,
            sphere_def: false,
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

    /// The drawing operations (meaningful when [`Svg::is_direct`]).
    pub fn ops(&self) -> &[Op] {
        &self.ops
    }

    /// Whether every element was added through a typed method (so [`Svg::ops`] describes the
    /// whole picture).
    pub fn is_direct(&self) -> bool {
        self.direct
    }

    /// Append raw markup to the `<defs>` section (gradients, clip paths). The PNG of a
    /// document with raw markup is drawn by resvg from the SVG text.
    pub fn def(&mut self, markup: &str) {
        self.direct = false;
        self.defs.push_str(markup);
        self.defs.push('\n');
    }

    /// Append raw markup to the body (the PNG is then drawn by resvg from the SVG text).
    pub fn raw(&mut self, markup: &str) {
        self.direct = false;
        self.body.push_str(markup);
        self.body.push('\n');
    }

    /// The translucent sphere of radius `r` at `(cx, cy)`: a radial gradient lit from the
    /// upper left, 35 % opaque, with a thin outline.
    pub fn sphere(&mut self, cx: f64, cy: f64, r: f64) {
        if !self.sphere_def {
            self.sphere_def = true;
            self.defs.push_str(SPHERE_GRADIENT);
            self.defs.push('\n');
        }
        let _ = writeln!(
            self.body,
            "<circle cx=\"{cx:.2}\" cy=\"{cy:.2}\" r=\"{r:.2}\" fill=\"url(#sphere)\" fill-opacity=\"0.35\" stroke=\"#7a8ca5\" stroke-width=\"1\"/>"
        );
        self.ops.push(Op::Sphere { cx, cy, r });
    }

    /// A circle with an optional dashed outline and a fill opacity.
    #[allow(clippy::too_many_arguments)]
    pub fn circle_styled(
        &mut self,
        (cx, cy, r): (f64, f64, f64),
        fill: &str,
        fill_opacity: f64,
        stroke: &str,
        sw: f64,
        dash: &str,
    ) {
        let dash_attr = dash_attr(dash);
        let _ = writeln!(
            self.body,
            "<circle cx=\"{cx:.2}\" cy=\"{cy:.2}\" r=\"{r:.2}\" fill=\"{fill}\" fill-opacity=\"{fill_opacity}\" stroke=\"{stroke}\" stroke-width=\"{sw:.2}\"{dash_attr}/>"
        );
        self.push_shape(
            Vec::new(),
            Some((cx, cy, r)),
            (fill, fill_opacity),
            (stroke, sw),
            dash,
        );
    }

    /// A rectangle with a fill opacity.
    #[allow(clippy::too_many_arguments)]
    pub fn rect_translucent(
        &mut self,
        (x, y, w, h): (f64, f64, f64, f64),
        fill: &str,
        fill_opacity: f64,
        stroke: &str,
        sw: f64,
    ) {
        let _ = writeln!(
            self.body,
            "<rect x=\"{x:.2}\" y=\"{y:.2}\" width=\"{w:.2}\" height=\"{h:.2}\" fill=\"{fill}\" fill-opacity=\"{fill_opacity}\" stroke=\"{stroke}\" stroke-width=\"{sw:.2}\"/>"
        );
        self.push_shape(
            vec![(x, y), (x + w, y), (x + w, y + h), (x, y + h)],
            None,
            (fill, fill_opacity),
            (stroke, sw),
            "",
        );
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
        let dash_attr = dash_attr(dash);
        let _ = writeln!(
            self.body,
            "<line x1=\"{x1:.2}\" y1=\"{y1:.2}\" x2=\"{x2:.2}\" y2=\"{y2:.2}\" stroke=\"{color}\" stroke-width=\"{width:.2}\"{dash_attr}/>"
        );
        self.ops.push(Op::Line {
            a: (x1, y1),
            b: (x2, y2),
            color: color.into(),
            width,
            dash: dash.into(),
            round: false,
            opacity: 1.0,
        });
    }

    /// A line segment with round caps and an opacity (used for the depth-sorted loop).
    #[allow(clippy::too_many_arguments)]
    pub fn segment(&mut self, a: (f64, f64), b: (f64, f64), color: &str, width: f64, opacity: f64) {
        let _ = writeln!(
            self.body,
            "<line x1=\"{:.2}\" y1=\"{:.2}\" x2=\"{:.2}\" y2=\"{:.2}\" stroke=\"{color}\" stroke-width=\"{width:.2}\" stroke-linecap=\"round\" stroke-opacity=\"{opacity:.3}\"/>",
            a.0, a.1, b.0, b.1
        );
        self.ops.push(Op::Line {
            a,
            b,
            color: color.into(),
            width,
            dash: String::new(),
            round: true,
            opacity,
        });
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
        let dash_attr = dash_attr(dash);
        let _ = writeln!(
            self.body,
            "<path d=\"{d}\" fill=\"none\" stroke=\"{color}\" stroke-width=\"{width:.2}\" stroke-linejoin=\"round\"{dash_attr}/>"
        );
        self.ops.push(Op::Polyline {
            pts: pts.to_vec(),
            color: color.into(),
            width,
            dash: dash.into(),
        });
    }

    /// A rectangle.
    #[allow(clippy::too_many_arguments)]
    pub fn rect(&mut self, x: f64, y: f64, w: f64, h: f64, fill: &str, stroke: &str, sw: f64) {
        let _ = writeln!(
            self.body,
            "<rect x=\"{x:.2}\" y=\"{y:.2}\" width=\"{w:.2}\" height=\"{h:.2}\" fill=\"{fill}\" stroke=\"{stroke}\" stroke-width=\"{sw:.2}\"/>"
        );
        self.push_shape(
            vec![(x, y), (x + w, y), (x + w, y + h), (x, y + h)],
            None,
            (fill, 1.0),
            (stroke, sw),
            "",
        );
    }

    /// A circle.
    pub fn circle(&mut self, cx: f64, cy: f64, r: f64, fill: &str, stroke: &str, sw: f64) {
        let _ = writeln!(
            self.body,
            "<circle cx=\"{cx:.2}\" cy=\"{cy:.2}\" r=\"{r:.2}\" fill=\"{fill}\" stroke=\"{stroke}\" stroke-width=\"{sw:.2}\"/>"
        );
        self.push_shape(Vec::new(), Some((cx, cy, r)), (fill, 1.0), (stroke, sw), "");
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
        self.push_shape(pts.to_vec(), None, (fill, 1.0), (stroke, sw), "");
    }

    /// Text at `(x, y)` (baseline), `size` pixels.
    pub fn text(&mut self, x: f64, y: f64, size: f64, anchor: Anchor, s: &str) {
        let _ = writeln!(
            self.body,
            "<text x=\"{x:.2}\" y=\"{y:.2}\" font-size=\"{size:.1}\" text-anchor=\"{}\">{}</text>",
            anchor.as_str(),
            esc(s)
        );
        self.push_text(x, y, size, anchor, false, false, s);
    }

    fn push_shape(
        &mut self,
        pts: Vec<(f64, f64)>,
        circle: Option<(f64, f64, f64)>,
        (fill, fill_opacity): (&str, f64),
        (stroke, width): (&str, f64),
        dash: &str,
    ) {
        self.ops.push(Op::Shape {
            pts,
            circle,
            fill: fill.into(),
            fill_opacity,
            stroke: stroke.into(),
            width,
            dash: dash.into(),
        });
    }

    #[allow(clippy::too_many_arguments)]
    fn push_text(
        &mut self,
        x: f64,
        y: f64,
        size: f64,
        anchor: Anchor,
        bold: bool,
        vertical: bool,
        s: &str,
    ) {
        self.ops.push(Op::Text {
            x,
            y,
            size,
            anchor,
            bold,
            vertical,
            text: s.into(),
        });
    }

    /// Text rotated by −90° about `(x, y)` (a y-axis label).
    pub fn text_vertical(&mut self, x: f64, y: f64, size: f64, s: &str) {
        let _ = writeln!(
            self.body,
            "<text x=\"{x:.2}\" y=\"{y:.2}\" font-size=\"{size:.1}\" text-anchor=\"middle\" transform=\"rotate(-90 {x:.2} {y:.2})\">{}</text>",
            esc(s)
        );
        self.push_text(x, y, size, Anchor::Middle, false, true, s);
    }

    /// Bold text.
    pub fn text_bold(&mut self, x: f64, y: f64, size: f64, anchor: Anchor, s: &str) {
        let _ = writeln!(
            self.body,
            "<text x=\"{x:.2}\" y=\"{y:.2}\" font-size=\"{size:.1}\" font-weight=\"bold\" text-anchor=\"{}\">{}</text>",
            anchor.as_str(),
            esc(s)
        );
        self.push_text(x, y, size, anchor, true, false, s);
    }

    /// Open a group clipped to a rectangle; close it with [`Svg::end_group`].
    pub fn begin_clip(&mut self, id: &str, x: f64, y: f64, w: f64, h: f64) {
        let _ = writeln!(
            self.defs,
            "<clipPath id=\"{id}\"><rect x=\"{x:.2}\" y=\"{y:.2}\" width=\"{w:.2}\" height=\"{h:.2}\"/></clipPath>"
        );
        let _ = writeln!(self.body, "<g clip-path=\"url(#{id})\">");
        self.ops.push(Op::BeginClip(x, y, w, h));
    }

    /// Close a group.
    pub fn end_group(&mut self) {
        self.body.push_str("</g>\n");
        self.ops.push(Op::EndClip);
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
