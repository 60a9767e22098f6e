//! PNG of an [`Svg`] document drawn with tiny-skia straight from its drawing operations
//! ([`Svg::ops`]), so the SVG text is never parsed back (resvg's parse and text layout took
//! about half the time of a loop picture's PNG). Text is shaped with rustybuzz and drawn from
//! the glyph outlines of the bundled font ([`crate::raster::FONT`]), as resvg does, with the
//! shaping face built once per process. Documents with raw markup go through resvg
//! ([`crate::raster::svg_to_png`]).

use std::collections::HashMap;
use std::sync::OnceLock;

use resvg::tiny_skia::{
    Color, FillRule, GradientStop, LineCap, LineJoin, Mask, Paint, PathBuilder, Pixmap, Point,
    RadialGradient, Rect, SpreadMode, Stroke, StrokeDash, Transform,
};
use rustybuzz::ttf_parser;

use crate::raster::{encode_opaque, svg_to_png, FONT};
use crate::svg::{Anchor, Op, Svg};
use crate::FigureError;

/// The shaping face of the bundled font, parsed once.
fn face() -> Option<&'static rustybuzz::Face<'static>> {
    static FACE: OnceLock<Option<rustybuzz::Face<'static>>> = OnceLock::new();
    FACE.get_or_init(|| rustybuzz::Face::from_slice(FONT, 0))
        .as_ref()
}

/// Parse the colours the figures use: `#rgb`, `#rrggbb`, `white`, `black` (`none`: `None`).
fn color(s: &str, alpha: f64) -> Result<Option<Color>, ()> {
    let a = alpha.clamp(0.0, 1.0) as f32;
    let hex = |h: &str| u8::from_str_radix(h, 16).map_err(|_| ());
    let rgb = match s {
        "none" => return Ok(None),
        "white" => (255, 255, 255),
        "black" => (0, 0, 0),
        _ if s.len() == 7 && s.starts_with('#') => (hex(&s[1..3])?, hex(&s[3..5])?, hex(&s[5..7])?),
        _ if s.len() == 4 && s.starts_with('#') => {
            let d = |i: usize| hex(&s[i..i + 1]).map(|v| v * 17);
            (d(1)?, d(2)?, d(3)?)
        }
        _ => return Err(()),
    };
    let mut c = Color::from_rgba8(rgb.0, rgb.1, rgb.2, 255);
    c.set_alpha(a);
    Ok(Some(c))
}

fn dash(pattern: &str) -> Result<Option<StrokeDash>, ()> {
    if pattern.is_empty() {
        return Ok(None);
    }
    let v: Vec<f32> = pattern
        .split([' ', ','])
        .filter(|t| !t.is_empty())
        .map(|t| t.parse::<f32>().map_err(|_| ()))
        .collect::<Result<_, _>>()?;
    Ok(StrokeDash::new(v, 0.0))
}

fn paint_of(c: Color) -> Paint<'static> {
    let mut p = Paint::default();
    p.set_color(c);
    p.anti_alias = true;
    p
}

/// The path through `pts`, closed if `close`.
fn path_through(pts: &[(f64, f64)], close: bool) -> Option<resvg::tiny_skia::Path> {
    let mut pb = PathBuilder::new();
    for (i, p) in pts.iter().enumerate() {
        if i == 0 {
            pb.move_to(p.0 as f32, p.1 as f32);
        } else {
            pb.line_to(p.0 as f32, p.1 as f32);
        }
    }
    if close {
        pb.close();
    }
    pb.finish()
}

/// Glyph outline in font units, as a tiny-skia path.
struct Outline(PathBuilder);

impl ttf_parser::OutlineBuilder for Outline {
    fn move_to(&mut self, x: f32, y: f32) {
        self.0.move_to(x, y);
    }
    fn line_to(&mut self, x: f32, y: f32) {
        self.0.line_to(x, y);
    }
    fn quad_to(&mut self, x1: f32, y1: f32, x: f32, y: f32) {
        self.0.quad_to(x1, y1, x, y);
    }
    fn curve_to(&mut self, x1: f32, y1: f32, x2: f32, y2: f32, x: f32, y: f32) {
        self.0.cubic_to(x1, y1, x2, y2, x, y);
    }
    fn close(&mut self) {
        self.0.close();
    }
}

/// The canvas and its state while drawing.
struct Canvas {
    pixmap: Pixmap,
    base: Transform,
    clips: Vec<Mask>,
    glyphs: HashMap<u16, Option<resvg::tiny_skia::Path>>,
}

impl Canvas {
    fn mask(&self) -> Option<&Mask> {
        self.clips.last()
    }

    fn stroke(
        &mut self,
        path: &resvg::tiny_skia::Path,
        c: Color,
        width: f64,
        pattern: &str,
        cap: LineCap,
    ) -> Result<(), ()> {
        let stroke = Stroke {
            width: width as f32,
            line_cap: cap,
            line_join: LineJoin::Round,
            dash: dash(pattern)?,
            ..Stroke::default()
        };
        let (base, mask) = (self.base, self.clips.last());
        self.pixmap
            .stroke_path(path, &paint_of(c), &stroke, base, mask);
        Ok(())
    }

    fn text(&mut self, op: &Op) -> Result<(), ()> {
        let Op::Text {
            x,
            y,
            size,
            anchor,
            bold,
            vertical,
            text,
        } = op
        else {
            return Ok(());
        };
        let face = face().ok_or(())?;
        let mut buf = rustybuzz::UnicodeBuffer::new();
        buf.push_str(text);
        let glyphs = rustybuzz::shape(face, &[], buf);
        let upem = f64::from(face.units_per_em());
        let k = size / upem;
        let advance: f64 = glyphs
            .glyph_positions()
            .iter()
            .map(|p| f64::from(p.x_advance))
            .sum::<f64>()
            * k;
        let start = match anchor {
            Anchor::Start => 0.0,
            Anchor::Middle => -advance / 2.0,
            Anchor::End => -advance,
        };
        // Local frame: origin at the anchor point, x along the baseline, y down.
        let mut frame = Transform::from_translate(*x as f32, *y as f32);
        if *vertical {
            frame = frame.pre_rotate(-90.0);
        }
        let black = paint_of(Color::BLACK);
        let mut pen = start;
        for (info, pos) in glyphs.glyph_infos().iter().zip(glyphs.glyph_positions()) {
            let id = info.glyph_id as u16;
            let path = self
                .glyphs
                .entry(id)
                .or_insert_with(|| {
                    let mut o = Outline(PathBuilder::new());
                    face.outline_glyph(ttf_parser::GlyphId(id), &mut o)?;
                    o.0.finish()
                })
                .clone();
            if let Some(path) = path {
                let gx = pen + f64::from(pos.x_offset) * k;
                let gy = -f64::from(pos.y_offset) * k;
                let ts = self.base.pre_concat(frame).pre_concat(Transform::from_row(
                    k as f32, 0.0, 0.0, -k as f32, gx as f32, gy as f32,
                ));
                let mask = self.clips.last();
                self.pixmap
                    .fill_path(&path, &black, FillRule::Winding, ts, mask);
                if *bold {
                    // The bundled font has no bold face: embolden by stroking the outline.
                    let stroke = Stroke {
                        width: (0.045 * upem) as f32,
                        line_join: LineJoin::Round,
                        ..Stroke::default()
                    };
                    self.pixmap.stroke_path(&path, &black, &stroke, ts, mask);
                }
            }
            pen += f64::from(pos.x_advance) * k;
        }
        Ok(())
    }

    fn draw(&mut self, op: &Op) -> Result<(), ()> {
        match op {
            Op::Line {
                a,
                b,
                color: c,
                width,
                dash: d,
                round,
                opacity,
            } => {
                let Some(c) = color(c, *opacity)? else {
                    return Ok(());
                };
                let mut pb = PathBuilder::new();
                pb.move_to(a.0 as f32, a.1 as f32);
                pb.line_to(b.0 as f32, b.1 as f32);
                if let Some(path) = pb.finish() {
                    let cap = if *round {
                        LineCap::Round
                    } else {
                        LineCap::Butt
                    };
                    self.stroke(&path, c, *width, d, cap)?;
                }
            }
            Op::Polyline {
                pts,
                color: c,
                width,
                dash: d,
            } => {
                let Some(c) = color(c, 1.0)? else {
                    return Ok(());
                };
                if let Some(path) = path_through(pts, false) {
                    self.stroke(&path, c, *width, d, LineCap::Butt)?;
                }
            }
            Op::Shape {
                pts,
                circle,
                fill,
                fill_opacity,
                stroke,
                width,
                dash: d,
            } => {
                let path = match circle {
                    Some((cx, cy, r)) => {
                        PathBuilder::from_circle(*cx as f32, *cy as f32, *r as f32)
                    }
                    None => path_through(pts, true),
                };
                let Some(path) = path else {
                    return Ok(());
                };
                if let Some(c) = color(fill, *fill_opacity)? {
                    let mask = self.clips.last();
                    self.pixmap
                        .fill_path(&path, &paint_of(c), FillRule::Winding, self.base, mask);
                }
                if *width > 0.0 {
                    if let Some(c) = color(stroke, 1.0)? {
                        self.stroke(&path, c, *width, d, LineCap::Butt)?;
                    }
                }
            }
            Op::Sphere { cx, cy, r } => {
                // The gradient of SPHERE_GRADIENT in the circle's bounding box, 35 % opaque.
                let (x0, y0, d) = (cx - r, cy - r, 2.0 * r);
                let centre = Point::from_xy((x0 + 0.42 * d) as f32, (y0 + 0.38 * d) as f32);
                let stop = |t: f32, hex: &str| -> Result<GradientStop, ()> {
                    Ok(GradientStop::new(t, color(hex, 0.35)?.ok_or(())?))
                };
                let shader = RadialGradient::new(
                    centre,
                    centre,
                    (0.62 * d) as f32,
                    vec![
                        stop(0.0, "#eef4fb")?,
                        stop(0.75, "#c9d8ea")?,
                        stop(1.0, "#9fb4cf")?,
                    ],
                    SpreadMode::Pad,
                    Transform::identity(),
                )
                .ok_or(())?;
                let Some(path) = PathBuilder::from_circle(*cx as f32, *cy as f32, *r as f32) else {
                    return Ok(());
                };
                let mut paint = Paint {
                    shader,
                    ..Paint::default()
                };
                paint.anti_alias = true;
                let mask = self.clips.last();
                self.pixmap
                    .fill_path(&path, &paint, FillRule::Winding, self.base, mask);
                let c = color("#7a8ca5", 1.0)?.ok_or(())?;
                self.stroke(&path, c, 1.0, "", LineCap::Butt)?;
            }
            Op::Text { .. } => self.text(op)?,
            Op::BeginClip(x, y, w, h) => {
                let mut m = Mask::new(self.pixmap.width(), self.pixmap.height()).ok_or(())?;
                let rect = Rect::from_xywh(*x as f32, *y as f32, *w as f32, *h as f32).ok_or(())?;
                let path = PathBuilder::from_rect(rect);
                m.fill_path(&path, FillRule::Winding, true, self.base);
                if let Some(outer) = self.mask() {
                    // Nested clips intersect.
                    let mut data = m.data().to_vec();
                    for (a, b) in data.iter_mut().zip(outer.data()) {
                        *a = ((u16::from(*a) * u16::from(*b)) / 255) as u8;
                    }
                    let size =
                        resvg::tiny_skia::IntSize::from_wh(m.width(), m.height()).ok_or(())?;
                    m = Mask::from_vec(data, size).ok_or(())?;
                }
                self.clips.push(m);
            }
            Op::EndClip => {
                self.clips.pop();
            }
        }
        Ok(())
    }
}

/// PNG bytes of `svg` at `scale` times its pixel size: drawn directly from its operations
/// when it has no raw markup ([`Svg::is_direct`]) and every colour is one this painter knows,
/// otherwise by resvg from its text.
pub fn to_png(svg: &Svg, scale: f32) -> Result<Vec<u8>, FigureError> {
    if !(scale.is_finite() && scale > 0.0 && scale <= 8.0) {
        return Err(FigureError::Invalid(format!(
            "PNG scale must be in (0, 8], got {scale}"
        )));
    }
    if svg.is_direct() {
        if let Some(pixmap) = paint(svg, scale) {
            return encode_opaque(&pixmap);
        }
    }
    svg_to_png(&svg.finish(), scale)
}

/// Draw the operations; `None` if one of them cannot be drawn here.
fn paint(svg: &Svg, scale: f32) -> Option<Pixmap> {
    let w = (svg.width() * f64::from(scale)).round() as u32;
    let h = (svg.height() * f64::from(scale)).round() as u32;
    let mut pixmap = Pixmap::new(w, h)?;
    pixmap.fill(Color::WHITE);
    let mut canvas = Canvas {
        pixmap,
        base: Transform::from_scale(scale, scale),
        clips: Vec::new(),
        glyphs: HashMap::new(),
    };
    for op in svg.ops() {
        canvas.draw(op).ok()?;
    }
    Some(canvas.pixmap)
}
