//! The loop picture: the curve on a translucent sphere from four viewpoints (an oblique
//! view and the three axis views, as in the paper's Figs. 2, 9 and 10), shaded for depth,
//! coloured by a column, with its colour bar, self-contacts and `s = 0` marked.

use nalgebra::Vector3;

use crate::color::{colormap, Rgb, Scale, WHITE};
use crate::data::{column_label, LoopData};
use rodloop_exact::shape::{loop_shape, LoopContact, LoopShape, SampledLoop, ShapeTolerances};

use crate::geometry::{crossings_2d, cyclic_gap, self_contacts};
use crate::svg::{tick_label, ticks, Anchor, Svg};
use crate::view::View;
use crate::FigureError;

/// Settings of a loop picture.
#[derive(Clone, Debug)]
pub struct LoopPictureOptions {
    /// Column to colour by (`None`: [`LoopData::default_color_column`]).
    pub color: Option<String>,
    /// Self-contact tolerance, as a fraction of the sphere radius.
    pub tol: f64,
    /// Side of one view panel, pixels.
    pub panel: f64,
    /// Title (first line).
    pub title: String,
    /// The colour column's extremes as the caller knows them more accurately than the table's
    /// samples (e.g. the contact force's extremes between the nodes, which `rodloop solve`
    /// prints): the bar's end labels and the reported range use them, so that the picture
    /// and the console give the same numbers.
    pub extremes: Option<(f64, f64)>,
}

impl Default for LoopPictureOptions {
    fn default() -> Self {
        Self {
            color: None,
            tol: 1e-3,
            panel: 380.0,
            title: String::new(),
            extremes: None,
        }
    }
}

/// A drawn loop picture and what was found while drawing it.
#[derive(Clone, Debug)]
pub struct LoopPicture {
    /// The SVG document.
    pub svg: String,
    /// The same picture as drawing operations (for [`crate::paint::to_png`]).
    pub document: Svg,
    /// Column the loop is coloured by.
    pub color_column: String,
    /// Range of the colour bar: the column's data range, or its central 90 % by arclength
    /// when the rest spans far more (see [`colour_scale`]).
    pub scale: Scale,
    /// The column's full data range when the colour bar is clipped to the central part.
    pub full_range: Option<Scale>,
    /// Self-contacts in 3-D (closest approach of strands apart along the loop below the
    /// tolerance), from [`LoopPicture::shape`] when the table has `kappa_g`, else from the
    /// polygon through the table's points.
    pub contacts: Vec<LoopContact>,
    /// Point group and self-intersections ([`shape`]; `None` without `kappa_g` or `kappa`).
    pub shape: Option<LoopShape>,
    /// Tolerance used for the contacts, in the data's length unit.
    pub tol: f64,
    /// For each view, the crossings of its projection that are not 3-D contacts.
    pub apparent_crossings: Vec<(String, usize)>,
}

/// Shape descriptors of a loop table ([`rodloop_exact::shape::loop_shape`]: point group and
/// self-intersections, `tol` fractions of the sphere radius). The symmetry anchors are the
/// peaks of `|κ_g|`, or of the curvature `κ` for a table without `kappa_g` (an enclosed
/// state off the sphere): every isometry keeps `κ`, and on the sphere `κ² = κ_g² + 1/R²`
/// peaks where `|κ_g|` does. `None` without either column or with too few points.
pub fn shape(data: &LoopData, tol: ShapeTolerances) -> Option<LoopShape> {
    let kg = data.column("kappa_g").or_else(|| data.column("kappa"))?;
    let s = data.s();
    let pts = data.points();
    loop_shape(
        &SampledLoop {
            length: data.length(),
            radius: data.radius(),
            s,
            points: &pts,
            kappa_g_s: s,
            kappa_g: kg,
        },
        tol,
    )
    .ok()
}

/// The point group of a loop table (Schoenflies symbol; number of elements, `None` for the
/// continuous groups D∞h and C∞v) with the RMS tolerance `tol` (a fraction of the radius).
/// `None` without a `kappa_g` or `kappa` column.
pub fn point_group(data: &LoopData, tol: f64) -> Option<(String, Option<usize>)> {
    let sh = shape(
        data,
        ShapeTolerances {
            symmetry: tol,
            ..ShapeTolerances::default()
        },
    )?;
    Some((sh.point_group, sh.group_order))
}

fn map_px(p: (f64, f64), c: (f64, f64), scale: f64) -> (f64, f64) {
    (c.0 + p.0 * scale, c.1 - p.1 * scale)
}

/// Draw the loop picture.
pub fn loop_picture(
    data: &LoopData,
    opts: &LoopPictureOptions,
) -> Result<LoopPicture, FigureError> {
    if !(opts.tol > 0.0 && opts.tol < 1.0) {
        return Err(FigureError::Invalid(format!(
            "the self-contact tolerance must be in (0, 1) (a fraction of R), got {}",
            opts.tol
        )));
    }
    if !(opts.panel >= 150.0 && opts.panel <= 4000.0) {
        return Err(FigureError::Invalid(format!(
            "panel size must be 150 to 4000 pixels, got {}",
            opts.panel
        )));
    }
    let color_column = opts
        .color
        .clone()
        .unwrap_or_else(|| data.default_color_column().to_string());
    let values = data
        .column(&color_column)
        .ok_or_else(|| FigureError::MissingColumn {
            path: data.source.clone(),
            column: color_column.clone(),
            found: data.names.join(", "),
        })?
        .to_vec();
    let (mut scale, mut full_range) = colour_scale(&values, data.s());
    if let Some((lo, hi)) = opts
        .extremes
        .filter(|e| e.0.is_finite() && e.1.is_finite() && e.1 >= e.0)
    {
        let known = Scale { min: lo, max: hi };
        match &mut full_range {
            Some(f) => *f = known,
            None => scale = known,
        }
    }
    let pts = data.points();
    let n = pts.len();
    let r = data.radius();
    let tol = opts.tol * r;
    let s_col = data.s();
    let shape = shape(
        data,
        ShapeTolerances {
            contact: opts.tol,
            ..ShapeTolerances::default()
        },
    );
    let contacts: Vec<LoopContact> = match &shape {
        Some(sh) => sh.contacts.clone(),
        None => self_contacts(&pts, tol)
            .into_iter()
            .map(|c| LoopContact {
                s: [
                    s_col[c.i] + c.t * (s_col[(c.i + 1) % n] - s_col[c.i]),
                    s_col[c.j] + c.u * (s_col[(c.j + 1) % n] - s_col[c.j]),
                ],
                point: c.point,
                distance: c.distance,
            })
            .collect(),
    };
    // The table's segment holding each contact's strands (for the projected crossings).
    let length = data.length();
    let segment_of = |x: f64| {
        let x = s_col[0] + (x - s_col[0]).rem_euclid(length);
        s_col
            .partition_point(|&v| v <= x)
            .saturating_sub(1)
            .min(n - 1)
    };
    let contact_segments: Vec<(usize, usize)> = contacts
        .iter()
        .map(|c| (segment_of(c.s[0]), segment_of(c.s[1])))
        .collect();

    let p = opts.panel;
    let (left, top, gap_x, gap_y) = (20.0, 78.0, 24.0, 40.0);
    let bar_x = left + 2.0 * p + gap_x + 34.0;
    let width = bar_x + 130.0;
    let legend_h = 58.0;
    let height = top + 2.0 * p + gap_y + legend_h;
    let mut svg = Svg::new(width.round(), height.round());
    // Title.
    let lbar = data.lbar();
    let title = if opts.title.is_empty() {
        data.source.clone()
    } else {
        opts.title.clone()
    };
    svg.text_bold(left, 26.0, 17.0, Anchor::Start, &title);
    svg.text(
        left,
        48.0,
        13.0,
        Anchor::Start,
        &format!(
            "L̄ = L/(2πR) = {lbar:.4},  L/R = {:.4},  {n} points;  colour: {}{}",
            data.length() / r,
            column_label(&color_column),
            full_range
                .map(|f| format!(
                    " (from {} to {}; the bar spans 90 % of the loop)",
                    crate::svg::tick_label((f.min * 1e3).round() / 1e3),
                    crate::svg::tick_label((f.max * 1e3).round() / 1e3)
                ))
                .unwrap_or_default()
        ),
    );
    svg.text(
        left,
        66.0,
        13.0,
        Anchor::Start,
        &format!(
            "self-contacts in 3-D (non-adjacent strands closer than {} R): {}",
            tick_label(opts.tol),
            contacts.len()
        ),
    );

    let views = View::paper_set();
    let mut apparent = Vec::new();
    let sc = 0.44 * p / r;
    for (k, view) in views.iter().enumerate() {
        let x0 = left + (k % 2) as f64 * (p + gap_x);
        let y0 = top + (k / 2) as f64 * (p + gap_y) + 18.0;
        let c = (x0 + p / 2.0, y0 + p / 2.0);
        svg.text(x0 + p / 2.0, y0 - 4.0, 13.0, Anchor::Middle, &view.name);
        svg.rect(x0, y0, p, p, "none", "#d0d0d0", 0.8);
        let proj: Vec<_> = pts.iter().map(|q| view.project(q)).collect();
        // Segments sorted back to front (painter's algorithm).
        let mut order: Vec<usize> = (0..n).collect();
        let mid_depth = |i: usize| 0.5 * (proj[i].depth + proj[(i + 1) % n].depth);
        order.sort_by(|&a, &b| mid_depth(a).total_cmp(&mid_depth(b)));
        let draw_seg = |svg: &mut Svg, i: usize| {
            let j = (i + 1) % n;
            let f = ((mid_depth(i) / r + 1.0) / 2.0).clamp(0.0, 1.0);
            let v = 0.5 * (values[i] + values[j]);
            let col = colormap(scale.t(v)).mix(WHITE, 0.5 * (1.0 - f));
            let w = (1.0 + 3.2 * f) * (p / 380.0);
            svg.segment(
                map_px((proj[i].u, proj[i].v), c, sc),
                map_px((proj[j].u, proj[j].v), c, sc),
                &col.css(),
                w,
                1.0,
            );
        };
        let split = order.iter().position(|&i| mid_depth(i) >= 0.0).unwrap_or(n);
        for &i in &order[..split] {
            draw_seg(&mut svg, i);
        }
        // The translucent sphere between the back and the front half.
        svg.sphere(c.0, c.1, r * sc);
        // Equator z = 0 (front half) as an orientation guide, unless seen face-on.
        if view.toward.z.abs() < 0.999 {
            let eq: Vec<(f64, f64)> = (0..=120)
                .map(|t| {
                    let a = std::f64::consts::TAU * t as f64 / 120.0;
                    view.project(&Vector3::new(r * a.cos(), r * a.sin(), 0.0))
                })
                .filter(|q| q.depth >= -1e-9)
                .map(|q| map_px((q.u, q.v), c, sc))
                .collect();
            svg.polyline(&eq, "#8da0b8", 0.8, "4 3");
        }
        for &i in &order[split..] {
            draw_seg(&mut svg, i);
        }
        // Crossings of this projection that are not 3-D contacts.
        let uv: Vec<(f64, f64)> = proj.iter().map(|q| (q.u, q.v)).collect();
        let near_contact = |i: usize, j: usize| {
            contact_segments.iter().any(|&(ci, cj)| {
                let g = |a: usize, b: usize| cyclic_gap(a, b, n);
                (g(ci, i) <= 4 && g(cj, j) <= 4) || (g(ci, j) <= 4 && g(cj, i) <= 4)
            })
        };
        let mut count = 0;
        for x in crossings_2d(&uv) {
            if near_contact(x.i, x.j) {
                continue;
            }
            count += 1;
            let q = map_px(x.at, c, sc);
            svg.line(
                q.0 - 4.0,
                q.1 - 4.0,
                q.0 + 4.0,
                q.1 + 4.0,
                "#404040",
                1.6,
                "",
            );
            svg.line(
                q.0 - 4.0,
                q.1 + 4.0,
                q.0 + 4.0,
                q.1 - 4.0,
                "#404040",
                1.6,
                "",
            );
        }
        apparent.push((view.name.clone(), count));
        // 3-D self-contacts.
        for ct in &contacts {
            let q = view.project(&ct.point);
            let at = map_px((q.u, q.v), c, sc);
            svg.circle_styled(
                (at.0, at.1, 8.0),
                "none",
                1.0,
                "#e00000",
                2.2,
                if q.depth < 0.0 { "3 2" } else { "" },
            );
        }
        // s = 0 and the direction of increasing s.
        let a = map_px((proj[0].u, proj[0].v), c, sc);
        let kk = (n / 30).max(1);
        let b = map_px((proj[kk].u, proj[kk].v), c, sc);
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let len = (dx * dx + dy * dy).sqrt();
        if len > 1.0 {
            let (ux, uy) = (dx / len, dy / len);
            let tip = (a.0 + 16.0 * ux, a.1 + 16.0 * uy);
            svg.line(a.0, a.1, tip.0, tip.1, "black", 1.6, "");
            svg.polygon(
                &[
                    (tip.0 + 6.0 * ux, tip.1 + 6.0 * uy),
                    (tip.0 - 3.5 * uy, tip.1 + 3.5 * ux),
                    (tip.0 + 3.5 * uy, tip.1 - 3.5 * ux),
                ],
                "black",
                "none",
                0.0,
            );
        }
        svg.circle(a.0, a.1, 5.0, "black", "white", 1.5);
        svg.text(a.0 + 8.0, a.1 - 8.0, 12.0, Anchor::Start, "s = 0");
        // Axis triad.
        let o = (x0 + 30.0, y0 + p - 30.0);
        for (axis, name, col) in [
            (Vector3::x(), "x", "#c03030"),
            (Vector3::y(), "y", "#2a8a2a"),
            (Vector3::z(), "z", "#2a50c0"),
        ] {
            let q = view.project(&axis);
            let e = (o.0 + 20.0 * q.u, o.1 - 20.0 * q.v);
            if (q.u * q.u + q.v * q.v).sqrt() > 0.15 {
                svg.line(o.0, o.1, e.0, e.1, col, 1.5, "");
                svg.text(
                    o.0 + 27.0 * q.u,
                    o.1 - 27.0 * q.v + 4.0,
                    11.0,
                    Anchor::Middle,
                    name,
                );
            } else {
                svg.circle(o.0, o.1, 2.5, col, "none", 0.0);
                svg.text(
                    o.0 + 6.0,
                    o.1 + 12.0,
                    11.0,
                    Anchor::Start,
                    &format!("{name}{}", if q.depth > 0.0 { "⊙" } else { "⊗" }),
                );
            }
        }
    }
    colorbar(
        &mut svg,
        bar_x,
        top + 18.0,
        2.0 * p + gap_y,
        scale,
        &column_label(&color_column),
        full_range.is_some(),
    );
    // Legend of the marks.
    let ly = top + 2.0 * p + gap_y + 34.0;
    svg.circle(left + 8.0, ly - 4.0, 7.0, "none", "#e00000", 2.2);
    svg.text(
        left + 22.0,
        ly,
        12.0,
        Anchor::Start,
        "self-contact in 3-D (dashed when behind the sphere)",
    );
    let lx = left + 380.0;
    svg.line(lx + 4.0, ly - 8.0, lx + 12.0, ly, "#404040", 1.6, "");
    svg.line(lx + 4.0, ly, lx + 12.0, ly - 8.0, "#404040", 1.6, "");
    svg.text(
        lx + 20.0,
        ly,
        12.0,
        Anchor::Start,
        "crossing of this projection only (strands apart in 3-D)",
    );
    svg.circle(left + 8.0, ly + 16.0, 5.0, "black", "white", 1.5);
    svg.text(
        left + 22.0,
        ly + 20.0,
        12.0,
        Anchor::Start,
        "s = 0, arrow toward increasing s;  nearer the viewer: darker and thicker; behind the sphere: pale",
    );
    Ok(LoopPicture {
        svg: svg.finish(),
        document: svg,
        color_column,
        scale,
        full_range,
        contacts,
        shape,
        tol,
        apparent_crossings: apparent,
    })
}

/// An end label of a colour bar: enough decimals to resolve the span (at least 4), and no
/// "−0" for a value that rounds to zero.
fn end_label(v: f64, span: f64) -> String {
    let dec = if span > 0.0 && span.is_finite() {
        ((-span.log10()).ceil() as i64 + 2).clamp(4, 9) as usize
    } else {
        4
    };
    let s = format!("{v:.dec$}");
    let unsigned = s.trim_start_matches('-');
    if unsigned.chars().all(|c| c == '0' || c == '.') {
        unsigned.to_string()
    } else {
        s.replace('-', "−")
    }
}

/// The colour range of `values` at arclengths `s`: their full range, unless the central
/// 90 % of the loop's length (5th to 95th percentile weighted by arclength) spans less than
/// a quarter of it. Then a few sharp peaks (the contact force at the stiffness transitions
/// of a two-segment rod) would leave the rest of the loop in one colour, so the bar spans the
/// central part, and the full range is returned beside it for the bar's labels.
pub fn colour_scale(values: &[f64], s: &[f64]) -> (Scale, Option<Scale>) {
    let full = Scale::of(values);
    let n = values.len();
    if n < 8 || s.len() != n || full.max <= full.min {
        return (full, None);
    }
    // Weight of node i: half the arclength to each neighbour (the last closes the loop
    // with the mean spacing).
    let mean = (s[n - 1] - s[0]) / (n - 1) as f64;
    let w: Vec<f64> = (0..n)
        .map(|i| {
            let before = if i == 0 { mean } else { s[i] - s[i - 1] };
            let after = if i + 1 == n { mean } else { s[i + 1] - s[i] };
            0.5 * (before + after).max(0.0)
        })
        .collect();
    let total: f64 = w.iter().sum();
    if total.is_nan() || total <= 0.0 {
        return (full, None);
    }
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| values[a].total_cmp(&values[b]));
    let quantile = |q: f64| {
        let mut acc = 0.0;
        for &i in &order {
            acc += w[i];
            if acc >= q * total {
                return values[i];
            }
        }
        values[order[n - 1]]
    };
    let (lo, hi) = (quantile(0.05), quantile(0.95));
    if hi > lo && hi - lo < 0.25 * (full.max - full.min) {
        (Scale { min: lo, max: hi }, Some(full))
    } else {
        (full, None)
    }
}

/// A vertical colour bar at `(x, y)`, `h` pixels tall, spanning exactly `scale`, with ticks
/// and a rotated label.
pub fn colorbar(svg: &mut Svg, x: f64, y: f64, h: f64, scale: Scale, label: &str, clipped: bool) {
    let w = 18.0;
    let steps = 64;
    for k in 0..steps {
        let t0 = k as f64 / steps as f64;
        let col: Rgb = colormap(t0 + 0.5 / steps as f64);
        let yy = y + h * (1.0 - (k + 1) as f64 / steps as f64);
        svg.rect(x, yy, w, h / steps as f64 + 0.6, &col.css(), "none", 0.0);
    }
    svg.rect(x, y, w, h, "none", "#333", 0.8);
    let pos = |v: f64| y + h * (1.0 - scale.t(v));
    let mut marks: Vec<f64> = if scale.max > scale.min {
        ticks(scale.min, scale.max, 6)
    } else {
        vec![scale.min]
    };
    // Drop inner ticks that would collide with the end labels.
    marks.retain(|&v| {
        (pos(v) - pos(scale.min)).abs() > 14.0 && (pos(v) - pos(scale.max)).abs() > 14.0
    });
    for v in marks {
        svg.line(x + w, pos(v), x + w + 5.0, pos(v), "#333", 1.0, "");
        svg.text(
            x + w + 8.0,
            pos(v) + 4.0,
            12.0,
            Anchor::Start,
            &tick_label(v),
        );
    }
    // The ends carry the exact data range.
    for (k, v) in [scale.min, scale.max].into_iter().enumerate() {
        svg.line(x + w, pos(v), x + w + 5.0, pos(v), "#333", 1.0, "");
        let sign = match (clipped, k) {
            (false, _) => "",
            (true, 0) => "≤ ",
            (true, _) => "≥ ",
        };
        svg.text_bold(
            x + w + 8.0,
            pos(v) + 4.0,
            11.0,
            Anchor::Start,
            &format!("{sign}{}", end_label(v, scale.max - scale.min)),
        );
    }
    if clipped {
        svg.text_vertical(
            x + w + 80.0,
            y + h / 2.0,
            13.0,
            &format!("{label}, central 90 % of the loop"),
        );
    } else {
        svg.text_vertical(x + w + 80.0, y + h / 2.0, 13.0, label);
    }
}
