//! The branch atlas: shape thumbnails along each branch of a diagram, and the composite
//! figure with one row per branch and one column per position along it (the layout of the
//! paper's Figs. 2, 9 and 10). Each thumbnail is the loop on a translucent sphere seen
//! obliquely, turned to its principal axes so that the shapes of a row are seen alike,
//! shaded for depth, labelled with `L̄` and its stability.

use nalgebra::{Matrix3, SymmetricEigen, Vector3};

use crate::color::{Rgb, WHITE};
use crate::svg::{Anchor, Svg};
use crate::view::View;
use crate::FigureError;

/// Colour of the soft segment of a non-uniform rod.
pub const SOFT_COLOR: &str = "#e8590c";

/// Colour of the parts of an enclosed loop that have lifted off the wall.
pub const OFF_WALL_COLOR: &str = "#d9a400";

/// One loop of the atlas.
#[derive(Clone, Debug)]
pub struct AtlasCell {
    /// Points of the closed curve in arclength order (any radius; the sphere is the largest
    /// `|r|`).
    pub points: Vec<Vector3<f64>>,
    /// Bending stiffness at the points (`None` or constant: a uniform rod). Where it lies
    /// below the middle of its range the loop is drawn in [`SOFT_COLOR`].
    pub stiffness: Option<Vec<f64>>,
    /// Points off the wall (an enclosed loop's gap above [`crate::data::GAP_TOUCH`]),
    /// drawn in [`OFF_WALL_COLOR`]; `None` on the surface.
    pub off_wall: Option<Vec<bool>>,
    /// `L̄` of the state.
    pub lbar: f64,
    /// Energy `E R/(πD₀)`.
    pub energy: f64,
    /// Stability label (`stable`, `metastable`, `unstable`, or for the exact model `lowest`,
    /// `higher`).
    pub stability: String,
}

/// One row: a branch (or one family of a non-uniform rod's branch).
#[derive(Clone, Debug)]
pub struct AtlasRow {
    /// Heading, e.g. `branch 1`.
    pub title: String,
    /// Further heading lines (separated by `\n`), e.g. `η = 2` or `η = 2\nfamily 2 (×2)`.
    pub subtitle: String,
    /// Line colour of the loops (the branch's colour in the diagram).
    pub color: String,
    /// The loops, in order along the branch.
    pub cells: Vec<AtlasCell>,
}

/// `k` indices into a path of states spread evenly along it: `position` is the states'
/// position along the path, nondecreasing (e.g. the cumulative `|ΔL̄|` in the order of the
/// family's arclength); the targets are the midpoints of `k` equal parts of the whole range,
/// and each gets the nearest state, kept distinct and in order. Fewer than `k` states: all.
pub fn spread(position: &[f64], k: usize) -> Vec<usize> {
    let n = position.len();
    if n <= k {
        return (0..n).collect();
    }
    if k == 0 {
        return Vec::new();
    }
    let (a, b) = (position[0], position[n - 1]);
    let mut idx: Vec<usize> = (0..k)
        .map(|i| {
            let t = a + (b - a) * (i as f64 + 0.5) / k as f64;
            (0..n)
                .min_by(|&x, &y| (position[x] - t).abs().total_cmp(&(position[y] - t).abs()))
                .unwrap_or(0)
        })
        .collect();
    // Distinct and increasing: push forward, then pull back from the end.
    for i in 1..k {
        idx[i] = idx[i].max(idx[i - 1] + 1);
    }
    for i in (0..k).rev() {
        let cap = n - (k - i);
        idx[i] = idx[i].min(cap);
        if i + 1 < k {
            idx[i] = idx[i].min(idx[i + 1] - 1);
        }
    }
    idx
}

/// The rotation taking the curve's principal axes (eigenvectors of `Σ r rᵀ`, largest spread
/// first) to `x, y, z`, right-handed, with signs fixed by the first point and the curve's
/// sense of rotation, so that the states of a branch are seen alike.
pub fn principal_frame(points: &[Vector3<f64>]) -> Matrix3<f64> {
    let mut m = Matrix3::zeros();
    for p in points {
        m += p * p.transpose();
    }
    let eig = SymmetricEigen::new(m);
    let mut order = [0usize, 1, 2];
    order.sort_by(|&i, &j| eig.eigenvalues[j].total_cmp(&eig.eigenvalues[i]));
    let mut e: Vec<Vector3<f64>> = order
        .iter()
        .map(|&i| eig.eigenvectors.column(i).into_owned())
        .collect();
    // Orient the smallest axis along the curve's mean angular momentum (its sense of
    // rotation), the largest toward the first point, and complete right-handed.
    let n = points.len();
    let mut ang = Vector3::zeros();
    for i in 0..n {
        ang += points[i].cross(&points[(i + 1) % n]);
    }
    if ang.dot(&e[2]) < 0.0 {
        e[2] = -e[2];
    }
    if points.first().is_some_and(|p| p.dot(&e[0]) < 0.0) {
        e[0] = -e[0];
    }
    e[1] = e[2].cross(&e[0]);
    Matrix3::from_rows(&[e[0].transpose(), e[1].transpose(), e[2].transpose()])
}

/// Draw one loop in a `side × side` box at `(x0, y0)`: the sphere, the loop (turned to its
/// principal axes, seen from azimuth 35°, elevation 25°), `s = 0`, and two label lines.
pub fn draw_cell(svg: &mut Svg, x0: f64, y0: f64, side: f64, cell: &AtlasCell, color: &str) {
    let pts = &cell.points;
    let n = pts.len();
    let r = pts.iter().map(|p| p.norm()).fold(0.0, f64::max);
    if n < 3 || r <= 0.0 {
        return;
    }
    let rot = principal_frame(pts);
    let view = View::oblique("oblique", 35f64.to_radians(), 25f64.to_radians());
    let proj: Vec<_> = pts.iter().map(|p| view.project(&(rot * p))).collect();
    let c = (x0 + side / 2.0, y0 + 0.43 * side);
    let sc = 0.39 * side / r;
    let px = |u: f64, v: f64| (c.0 + u * sc, c.1 - v * sc);
    let soft: Vec<bool> = match &cell.stiffness {
        Some(d) if d.len() == n => {
            let (lo, hi) = d
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                    (a.min(v), b.max(v))
                });
            if hi - lo > 1e-9 * hi.abs() {
                d.iter().map(|&v| v < 0.5 * (lo + hi)).collect()
            } else {
                vec![false; n]
            }
        }
        _ => vec![false; n],
    };
    let off: Vec<bool> = match &cell.off_wall {
        Some(o) if o.len() == n => o.clone(),
        _ => vec![false; n],
    };
    let base = Rgb::hex(u32::from_str_radix(color.trim_start_matches('#'), 16).unwrap_or(0x1f4fd1));
    let soft_rgb = Rgb::hex(0xe8590c);
    let off_rgb = Rgb::hex(0xd9a400);
    let mid = |i: usize| 0.5 * (proj[i].depth + proj[(i + 1) % n].depth);
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| mid(a).total_cmp(&mid(b)));
    let split = order.iter().position(|&i| mid(i) >= 0.0).unwrap_or(n);
    let w0 = side / 170.0;
    let seg = |svg: &mut Svg, i: usize| {
        let j = (i + 1) % n;
        let f = ((mid(i) / r + 1.0) / 2.0).clamp(0.0, 1.0);
        let col = if off[i] && off[j] {
            off_rgb
        } else if soft[i] && soft[j] {
            soft_rgb
        } else {
            base
        };
        svg.segment(
            px(proj[i].u, proj[i].v),
            px(proj[j].u, proj[j].v),
            &col.mix(WHITE, 0.55 * (1.0 - f)).css(),
            (0.8 + 2.2 * f) * w0,
            1.0,
        );
    };
    for &i in &order[..split] {
        seg(svg, i);
    }
    svg.raw(&format!(
        "<circle cx=\"{:.2}\" cy=\"{:.2}\" r=\"{:.2}\" fill=\"url(#atlas-sphere)\" fill-opacity=\"0.35\" stroke=\"#7a8ca5\" stroke-width=\"0.8\"/>",
        c.0,
        c.1,
        r * sc
    ));
    // The principal plane's equator (front half), as an orientation guide.
    let eq: Vec<(f64, f64)> = (0..=96)
        .map(|t| {
            let a = std::f64::consts::TAU * t as f64 / 96.0;
            view.project(&Vector3::new(r * a.cos(), r * a.sin(), 0.0))
        })
        .filter(|q| q.depth >= -1e-9)
        .map(|q| px(q.u, q.v))
        .collect();
    svg.polyline(&eq, "#8da0b8", 0.7, "3 3");
    for &i in &order[split..] {
        seg(svg, i);
    }
    let s0 = px(proj[0].u, proj[0].v);
    svg.circle(s0.0, s0.1, 2.6 * w0, "black", "white", 0.8 * w0);
    let fs = (11.5 * side / 170.0).clamp(9.0, 16.0);
    svg.text(
        c.0,
        y0 + 0.89 * side,
        fs,
        Anchor::Middle,
        &format!("L̄ = {:.4}", cell.lbar),
    );
    svg.text(
        c.0,
        y0 + 0.89 * side + 1.25 * fs,
        fs * 0.92,
        Anchor::Middle,
        &format!("{}, E = {:.4}", cell.stability, cell.energy),
    );
}

const GRADIENT: &str = "<radialGradient id=\"atlas-sphere\" cx=\"0.42\" cy=\"0.38\" r=\"0.62\"><stop offset=\"0\" stop-color=\"#eef4fb\"/><stop offset=\"0.75\" stop-color=\"#c9d8ea\"/><stop offset=\"1\" stop-color=\"#9fb4cf\"/></radialGradient>";

/// Height of a cell with its two label lines, for a cell of width `side`.
fn cell_height(side: f64) -> f64 {
    side * 1.08
}

/// One thumbnail as a standalone SVG: the row's heading above one cell.
pub fn thumbnail(row: &AtlasRow, cell: &AtlasCell, side: f64) -> Result<String, FigureError> {
    check_side(side)?;
    let top = 24.0;
    let mut svg = Svg::new(side.round(), (top + cell_height(side)).round());
    svg.def(GRADIENT);
    svg.text_bold(
        side / 2.0,
        17.0,
        13.0,
        Anchor::Middle,
        &format!("{} ({})", row.title, row.subtitle.replace('\n', ", ")),
    );
    draw_cell(&mut svg, 0.0, top, side, cell, &row.color);
    Ok(svg.finish())
}

fn check_side(side: f64) -> Result<(), FigureError> {
    if (100.0..=1000.0).contains(&side) {
        Ok(())
    } else {
        Err(FigureError::Invalid(format!(
            "atlas cells must be 100 to 1000 pixels wide, got {side}"
        )))
    }
}

/// The composite atlas: a title, one row per [`AtlasRow`] (heading on the left, its cells
/// to the right), and a legend line.
pub fn atlas_figure(rows: &[AtlasRow], side: f64, title: &str) -> Result<String, FigureError> {
    check_side(side)?;
    if rows.is_empty() {
        return Err(FigureError::Invalid(
            "an atlas needs at least one branch".into(),
        ));
    }
    let cols = rows.iter().map(|r| r.cells.len()).max().unwrap_or(0).max(1);
    let (left, top, legend) = (118.0, 46.0, 52.0);
    let ch = cell_height(side);
    let width = (left + cols as f64 * side + 10.0).max(640.0);
    let height = top + rows.len() as f64 * ch + legend;
    let mut svg = Svg::new(width.round(), height.round());
    svg.def(GRADIENT);
    svg.text_bold(12.0, 26.0, 16.0, Anchor::Start, title);
    let any_soft = rows.iter().any(|r| {
        r.cells.iter().any(|c| {
            c.stiffness.as_ref().is_some_and(|d| {
                let (lo, hi) = d
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                        (a.min(v), b.max(v))
                    });
                hi - lo > 1e-9 * hi.abs()
            })
        })
    });
    let any_off = rows.iter().any(|r| {
        r.cells
            .iter()
            .any(|c| c.off_wall.as_ref().is_some_and(|o| o.iter().any(|&b| b)))
    });
    for (i, row) in rows.iter().enumerate() {
        let y = top + i as f64 * ch;
        if i > 0 {
            svg.line(8.0, y, width - 8.0, y, "#e3e7ee", 1.0, "");
        }
        svg.rect(
            10.0,
            y + 0.36 * side,
            5.0,
            0.16 * side,
            &row.color,
            "none",
            0.0,
        );
        svg.text_bold(22.0, y + 0.42 * side, 14.0, Anchor::Start, &row.title);
        for (l, line) in row.subtitle.lines().enumerate() {
            let dy = 18.0 * (l + 1) as f64;
            svg.text(22.0, y + 0.42 * side + dy, 12.5, Anchor::Start, line);
        }
        for (j, cell) in row.cells.iter().enumerate() {
            draw_cell(&mut svg, left + j as f64 * side, y, side, cell, &row.color);
        }
    }
    let ly = height - legend + 20.0;
    svg.text(
        12.0,
        ly,
        12.0,
        Anchor::Start,
        "Oblique view (az. 35°, el. 25°) of each loop turned to its principal axes (dashed: plane of the two largest).",
    );
    svg.text(
        12.0,
        ly + 16.0,
        12.0,
        Anchor::Start,
        match (any_soft, any_off) {
            (true, true) => "Nearer strands darker and thicker; ● s = 0; orange: the soft segment; amber: off the wall.",
            (true, false) => "Nearer strands darker and thicker; ● s = 0; orange: the soft segment.",
            (false, true) => "Nearer strands darker and thicker; ● s = 0; amber: lifted off the wall (gap > 1e-9 R).",
            (false, false) => "Nearer strands darker and thicker; ● s = 0.",
        },
    );
    Ok(svg.finish())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread_picks_distinct_ordered_states_near_the_targets() {
        let pos: Vec<f64> = (0..11).map(|i| i as f64 / 10.0).collect();
        assert_eq!(spread(&pos, 5), vec![1, 3, 5, 7, 9]);
        assert_eq!(spread(&pos, 20), (0..11).collect::<Vec<_>>());
        assert!(spread(&pos, 0).is_empty());
        // Clustered states: still distinct and increasing.
        let pos = [0.0, 0.001, 0.002, 0.003, 0.004, 1.0];
        let idx = spread(&pos, 4);
        assert_eq!(idx.len(), 4);
        assert!(idx.windows(2).all(|w| w[0] < w[1]));
        assert!(*idx.last().unwrap() <= 5);
    }

    #[test]
    fn principal_frame_is_a_rotation_to_the_axes_of_spread() {
        // An ellipse-like loop with spreads 3 > 2 > 0.5 along a tilted frame.
        let q = nalgebra::Rotation3::from_euler_angles(0.3, -0.7, 1.1);
        let pts: Vec<Vector3<f64>> = (0..64)
            .map(|i| {
                let t = std::f64::consts::TAU * i as f64 / 64.0;
                q * Vector3::new(3.0 * t.cos(), 2.0 * t.sin(), 0.5 * (2.0 * t).sin())
            })
            .collect();
        let m = principal_frame(&pts);
        assert!((m.determinant() - 1.0).abs() < 1e-12);
        assert!((m * m.transpose() - Matrix3::identity()).norm() < 1e-12);
        let back: Vec<Vector3<f64>> = pts.iter().map(|p| m * p).collect();
        let spread = |k: usize| back.iter().map(|p| p[k] * p[k]).sum::<f64>();
        assert!(spread(0) > spread(1) && spread(1) > spread(2));
        // The first point lies on +x.
        assert!((back[0] - Vector3::new(3.0, 0.0, 0.0)).norm() < 1e-9);
    }
}
