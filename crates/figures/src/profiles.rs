//! Quantities along the loop against arclength: position `x, y, z`, curvature `κ`, torsion
//! `τ`, geodesic curvature `κ_g` (paper Fig. 5), the contact force `λ(s)` (Fig. 6; Eq. 38
//! for a uniform rod) and the internal force components `F_t, F_n, F_b` (one panel), one
//! panel each, for the columns the table has. A panel whose values have a few sharp peaks
//! (the forces at the stiffness steps of a two-segment rod) is clipped to its bulk by
//! [`crate::plot::robust_range`], and says so under its axis.

use crate::data::{column_label, LoopData};
use crate::plot::{arclength_weights, clipped_note, robust_range, LegendItem, Plot, Series};
use crate::svg::{Anchor, Svg};
use crate::FigureError;

/// Columns drawn, in order, when present.
pub const PROFILE_COLUMNS: [&str; 9] = [
    "x", "y", "z", "kappa", "tau", "kappa_g", "lambda", "D", "gap",
];

/// The profiles figure: a grid of panels, two per row, `panel_w × panel_h` pixels each.
pub fn profiles_figure(
    data: &LoopData,
    panel_w: f64,
    panel_h: f64,
    title: &str,
) -> Result<String, FigureError> {
    Ok(profiles_document(data, None, panel_w, panel_h, title)?.finish())
}

/// [`profiles_figure`] with a second curve drawn dashed in the panels of the columns it has
/// (e.g. the aligned Euler curve of [`crate::overlay::align`], the paper's Fig. 5), named by
/// `overlay.1` in a line under the title.
pub fn profiles_figure_overlay(
    data: &LoopData,
    overlay: Option<(&LoopData, &str)>,
    panel_w: f64,
    panel_h: f64,
    title: &str,
) -> Result<String, FigureError> {
    Ok(profiles_document(data, overlay, panel_w, panel_h, title)?.finish())
}

/// [`profiles_figure_overlay`] as a document (for [`crate::paint::to_png`]).
pub fn profiles_document(
    data: &LoopData,
    overlay: Option<(&LoopData, &str)>,
    panel_w: f64,
    panel_h: f64,
    title: &str,
) -> Result<Svg, FigureError> {
    if !(200.0..=3000.0).contains(&panel_w) || !(150.0..=3000.0).contains(&panel_h) {
        return Err(FigureError::Invalid(format!(
            "profile panels must be 200–3000 × 150–3000 pixels, got {panel_w} × {panel_h}"
        )));
    }
    // A constant stiffness (a uniform rod) says nothing along the loop: no panel, a note.
    let constant_d = data.column("D").and_then(|d| {
        let (lo, hi) = d
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        (hi - lo <= 1e-12 * hi.abs().max(1.0)).then_some(lo)
    });
    let mut cols: Vec<&str> = PROFILE_COLUMNS
        .iter()
        .copied()
        .filter(|c| data.column(c).is_some() && !(*c == "D" && constant_d.is_some()))
        .collect();
    // The internal force (F_t, F_n, F_b) in one panel, when the table has all three.
    let forces = FORCE_COLUMNS.iter().all(|c| data.column(c).is_some());
    if forces {
        cols.push(FORCES);
    }
    let rows = cols.len().div_ceil(2).max(1);
    let top = if overlay.is_some() || constant_d.is_some() {
        60.0
    } else {
        40.0
    };
    let mut svg = Svg::new(2.0 * panel_w, top + rows as f64 * panel_h);
    svg.text_bold(12.0, 26.0, 16.0, Anchor::Start, title);
    if let Some(d) = constant_d {
        svg.text(
            2.0 * panel_w - 12.0,
            48.0,
            13.0,
            Anchor::End,
            &format!(
                "D/D₀ = {} along the whole loop (uniform rod)",
                crate::svg::tick_label(d)
            ),
        );
    }
    if let Some((_, label)) = overlay {
        svg.line(14.0, 44.0, 44.0, 44.0, "#1f4fd1", 1.8, "");
        svg.text(50.0, 48.0, 13.0, Anchor::Start, "this loop");
        svg.line(140.0, 44.0, 170.0, 44.0, "#d8600c", 1.8, "6 4");
        svg.text(176.0, 48.0, 13.0, Anchor::Start, label);
    }
    let s = data.s();
    let length = data.length();
    let weights = arclength_weights(s, length);
    // One closed curve against s/L: the first point repeated at s = L.
    let closed = |v: &[f64]| {
        let mut pts: Vec<(f64, f64)> = s.iter().zip(v).map(|(&a, &b)| (a / length, b)).collect();
        if let (Some(&first), Some(&s0)) = (v.first(), s.first()) {
            pts.push((s0 / length + 1.0, first));
        }
        pts
    };
    for (k, c) in cols.iter().enumerate() {
        if *c == FORCES {
            let (px, py) = ((k % 2) as f64 * panel_w, top + (k / 2) as f64 * panel_h);
            forces_panel(
                data,
                &closed,
                &weights,
                &mut svg,
                (px, py, panel_w, panel_h),
                k,
            );
            continue;
        }
        let v = data.column(c).unwrap_or(&[]);
        let mut series = vec![Series {
            color: "#1f4fd1".into(),
            width: 1.8,
            dash: String::new(),
            points: closed(v),
        }];
        if let Some(o) = overlay.and_then(|(o, _)| o.column(c).map(|v| (o.s(), v))) {
            let (os, ov) = o;
            let mut q: Vec<(f64, f64)> =
                os.iter().zip(ov).map(|(&a, &b)| (a / length, b)).collect();
            if let (Some(&first), Some(&s0)) = (ov.first(), os.first()) {
                q.push((s0 / length + 1.0, first));
            }
            series.push(Series {
                color: "#d8600c".into(),
                width: 1.8,
                dash: "6 4".into(),
                points: q,
            });
        }
        let clip = robust_range(v, Some(&weights));
        let mut plot = Plot {
            title: column_label(c),
            xlabel: "s/L".into(),
            ylabel: column_label(c)
                .split(" (")
                .next()
                .unwrap_or_default()
                .to_string(),
            series,
            hlines: if *c == "lambda" || *c == "kappa_g" || *c == "tau" {
                vec![0.0]
            } else {
                Vec::new()
            },
            range: None,
            ..Default::default()
        };
        if let Some(shown) = clip {
            let (x0, x1) = plot.x_range();
            plot.range = Some((x0, x1, shown.0, shown.1));
            plot.note = clipped_note("y", v, shown);
        }
        let (px, py) = ((k % 2) as f64 * panel_w, top + (k / 2) as f64 * panel_h);
        plot.render(&mut svg, px, py, panel_w, panel_h, &format!("prof{k}"));
    }
    Ok(svg)
}

/// A closed curve against `s/L` from a column's values.
type ClosedCurve<'a> = &'a dyn Fn(&[f64]) -> Vec<(f64, f64)>;

/// The columns of the internal force, drawn together in one panel.
const FORCE_COLUMNS: [&str; 3] = ["F_t", "F_n", "F_b"];

/// The name of the internal-force panel among the profile columns.
const FORCES: &str = "F (internal force)";

/// The internal force `F = F_t t + F_n n + F_b b` along the loop, its three components in
/// one panel with a legend, clipped to their bulk like the other panels.
fn forces_panel(
    data: &LoopData,
    closed: ClosedCurve<'_>,
    weights: &[f64],
    svg: &mut Svg,
    (px, py, w, h): (f64, f64, f64, f64),
    k: usize,
) {
    let colors = ["#1f4fd1", "#d8600c", "#2a8a2a"];
    let mut all = Vec::new();
    let mut series = Vec::new();
    let mut legend = Vec::new();
    for (c, color) in FORCE_COLUMNS.iter().zip(colors) {
        let v = data.column(c).unwrap_or(&[]);
        all.extend_from_slice(v);
        series.push(Series {
            color: color.into(),
            width: 1.6,
            dash: String::new(),
            points: closed(v),
        });
        legend.push(LegendItem::Line {
            label: (*c).into(),
            color: color.into(),
            width: 1.6,
            dash: String::new(),
        });
    }
    let mut plot = Plot {
        title: "internal force F R²/D₀ (tangent, normal, binormal)".into(),
        xlabel: "s/L".into(),
        ylabel: "F R²/D₀".into(),
        series,
        hlines: vec![0.0],
        legend,
        ..Default::default()
    };
    let w3: Vec<f64> = weights.iter().cycle().take(all.len()).copied().collect();
    if let Some(shown) = robust_range(&all, Some(&w3)) {
        let (x0, x1) = plot.x_range();
        plot.range = Some((x0, x1, shown.0, shown.1));
        plot.note = clipped_note("y", &all, shown);
    }
    plot.render(svg, px, py, w, h, &format!("prof{k}"));
}

/// One panel of [`along_loop_figure`]: a column of the loop table against `s/L`.
#[derive(Clone, Copy, Debug)]
pub struct AlongLoop<'a> {
    /// The column (`lambda`, `gap`, …).
    pub column: &'a str,
    /// The panel's title.
    pub title: &'a str,
    /// The label of its value axis.
    pub ylabel: &'a str,
    /// The panel's id in the SVG.
    pub id: &'a str,
    /// When set, a panel whose values have a few sharp peaks (the contact force at the
    /// stiffness steps of a two-segment rod) shows their bulk ([`robust_range`]) and a note
    /// under its axis names the quantity by this symbol.
    pub clip: Option<&'a str>,
}

/// Columns of a loop table against `s/L` (`s = 0` as marked on the loop), closed at
/// `s/L = 1`, one `w × h` panel each side by side, drawn in `color` with a zero line: the
/// contact force `λ(s)` of the paper's Fig. 6 and, for an enclosed loop, its gap to the wall.
pub fn along_loop_figure(
    data: &LoopData,
    panels: &[AlongLoop],
    color: &str,
    (w, h): (f64, f64),
) -> Result<String, FigureError> {
    let length = data.length();
    let s = data.s();
    let mut svg = Svg::new(w * panels.len() as f64, h);
    for (k, p) in panels.iter().enumerate() {
        let v = data
            .column(p.column)
            .ok_or_else(|| FigureError::MissingColumn {
                path: data.source.clone(),
                column: p.column.into(),
                found: data.names.join(", "),
            })?;
        let mut points: Vec<(f64, f64)> = s.iter().zip(v).map(|(&a, &b)| (a / length, b)).collect();
        if let (Some(&s0), Some(&v0)) = (s.first(), v.first()) {
            points.push((s0 / length + 1.0, v0));
        }
        let mut plot = Plot {
            title: p.title.into(),
            xlabel: "s/L (s = 0 as marked on the loop)".into(),
            ylabel: p.ylabel.into(),
            series: vec![Series {
                color: color.into(),
                width: 2.0,
                dash: String::new(),
                points,
            }],
            hlines: vec![0.0],
            ..Default::default()
        };
        if let Some(what) = p.clip {
            if let Some(shown) = robust_range(v, Some(&arclength_weights(s, length))) {
                let (x0, x1) = plot.x_range();
                plot.range = Some((x0, x1, shown.0, shown.1));
                plot.note = clipped_note(what, v, shown);
            }
        }
        plot.render(&mut svg, w * k as f64, 0.0, w, h, p.id);
    }
    Ok(svg.finish())
}
