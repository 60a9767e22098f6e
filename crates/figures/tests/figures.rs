//! Known-answer tests of the figures crate: projections, self-contacts, colour bar, PNG and
//! SVG validity, bad input.

use std::collections::BTreeMap;
use std::f64::consts::{PI, TAU};
use std::path::{Path, PathBuf};

use nalgebra::Vector3;
use rodloop_exact::{all_loops, Family};
use rodloop_figures::color::Scale;
use rodloop_figures::data::LoopData;
use rodloop_figures::diagram::{energy_figure, lambda_figure, DiagramData};
use rodloop_figures::geometry::{crossings_2d, resample_closed, self_contacts};
use rodloop_figures::loops::{loop_picture, point_group, LoopPictureOptions};
use rodloop_figures::raster::{png_size, svg_to_png};
use rodloop_figures::view::View;
use rodloop_figures::FigureError;
use rodloop_schema::{Axis, Cell, Critical, Diagram, Point};

/// The paper's branch loop (wave family, q = −(η + 1)) with `eta` periods at `lbar`, as a table.
fn exact_loop(eta: u32, lbar: f64, n: usize) -> LoopData {
    let lp = all_loops(eta, lbar)
        .unwrap()
        .into_iter()
        .find(|l| l.family == Family::Wave && l.q == -(eta as i32 + 1))
        .expect("paper branch");
    let pts = lp.sample(n).unwrap();
    let names = ["s", "x", "y", "z", "kappa_g", "lambda"];
    let cols: Vec<Vec<f64>> = vec![
        pts.iter().map(|p| p.s).collect(),
        pts.iter().map(|p| p.x).collect(),
        pts.iter().map(|p| p.y).collect(),
        pts.iter().map(|p| p.z).collect(),
        pts.iter().map(|p| p.kappa_g).collect(),
        pts.iter().map(|p| p.lambda).collect(),
    ];
    LoopData::new("exact", names.iter().map(|s| s.to_string()).collect(), cols).unwrap()
}

fn circle(n: usize) -> Vec<Vector3<f64>> {
    (0..n)
        .map(|i| {
            let t = TAU * i as f64 / n as f64;
            Vector3::new(t.cos(), t.sin(), 0.0)
        })
        .collect()
}

#[test]
fn axis_views_map_known_points() {
    let px = Vector3::x();
    let p = View::from_x().project(&px);
    assert!(p.u.abs() < 1e-15 && p.v.abs() < 1e-15 && (p.depth - 1.0).abs() < 1e-15);
    let p = View::from_z().project(&px);
    assert!((p.u - 1.0).abs() < 1e-15 && p.v.abs() < 1e-15 && p.depth.abs() < 1e-15);
    let p = View::from_y().project(&px);
    assert!((p.u + 1.0).abs() < 1e-15, "from +y, +x is on the left");
    let p = View::from_x().project(&Vector3::z());
    assert!((p.v - 1.0).abs() < 1e-15, "z is up");
    for v in View::paper_set() {
        assert!(
            (v.right.cross(&v.up) - v.toward).norm() < 1e-12,
            "{}",
            v.name
        );
        assert!((v.right.norm() - 1.0).abs() < 1e-12 && v.right.dot(&v.up).abs() < 1e-12);
    }
}

#[test]
fn great_circle_seen_edge_on_is_a_line() {
    // The equator seen from +x: every point has v = 0 and |u| <= 1.
    for p in circle(100) {
        let q = View::from_x().project(&p);
        assert!(q.v.abs() < 1e-15 && q.u.abs() <= 1.0 + 1e-15);
    }
    // Seen face-on from +z it is the unit circle.
    for p in circle(100) {
        let q = View::from_z().project(&p);
        assert!(((q.u * q.u + q.v * q.v).sqrt() - 1.0).abs() < 1e-14);
    }
}

#[test]
fn contacts_of_curves_with_known_crossings() {
    // A circle: none.
    assert_eq!(self_contacts(&circle(400), 1e-3).len(), 0);
    // A planar figure-eight (lemniscate of Gerono): one crossing, at the origin.
    let eight: Vec<Vector3<f64>> = (0..400)
        .map(|i| {
            let t = TAU * i as f64 / 400.0 + 0.1;
            Vector3::new(t.sin(), t.sin() * t.cos(), 0.0)
        })
        .collect();
    let c = self_contacts(&eight, 1e-3);
    assert_eq!(c.len(), 1);
    assert!(c[0].point.norm() < 1e-3);
    // Its 2-D projection from +z crosses once too; from +x it is a line (degenerate, no
    // proper crossing).
    let uv: Vec<(f64, f64)> = eight.iter().map(|p| (p.x, p.y)).collect();
    assert_eq!(crossings_2d(&uv).len(), 1);
    // A trefoil knot: no 3-D contact, three crossings in the xy projection.
    let knot: Vec<Vector3<f64>> = (0..600)
        .map(|i| {
            let t = TAU * i as f64 / 600.0;
            Vector3::new(
                t.sin() + 2.0 * (2.0 * t).sin(),
                t.cos() - 2.0 * (2.0 * t).cos(),
                -(3.0 * t).sin(),
            )
        })
        .collect();
    assert_eq!(self_contacts(&knot, 1e-3).len(), 0);
    let uv: Vec<(f64, f64)> = knot.iter().map(|p| (p.x, p.y)).collect();
    assert_eq!(crossings_2d(&uv).len(), 3);
}

#[test]
fn exact_loops_have_the_papers_self_intersections() {
    // Paper Sec. 3.1: saddle (branch 1) none; figure-eight (branch 2) one; branch 3 three;
    // branch 1 beyond L̄_4cr four.
    for (eta, lbar, want) in [(2, 1.2, 0), (1, 1.6, 1), (3, 2.2, 3), (2, 2.6, 4)] {
        let d = exact_loop(eta, lbar, 512);
        let got = self_contacts(&d.points(), 1e-3).len();
        assert_eq!(got, want, "eta = {eta}, lbar = {lbar}");
    }
}

#[test]
fn saddle_is_d2d() {
    // Paper Sec. 3.1: the saddle loops of branch 1 have D2d symmetry.
    let d = exact_loop(2, 1.2, 500);
    let (sym, order) = point_group(&d, 1e-4).unwrap();
    assert_eq!(sym, "D2d");
    assert_eq!(order, Some(8));
}

#[test]
fn resampling_a_circle_converges_at_fourth_order() {
    let err = |n: usize| {
        let pts = circle(n);
        let s: Vec<f64> = (0..n).map(|i| TAU * i as f64 / n as f64).collect();
        let out = resample_closed(&s, &pts, TAU, 0.3, 100);
        out.iter()
            .enumerate()
            .map(|(k, p)| {
                let t = 0.3 + TAU * k as f64 / 100.0;
                (p - Vector3::new(t.cos(), t.sin(), 0.0)).norm()
            })
            .fold(0.0, f64::max)
    };
    let (e1, e2) = (err(64), err(128));
    assert!(e1 < 1e-5, "{e1}");
    let order = (e1 / e2).log2();
    assert!((order - 4.0).abs() < 0.3, "order {order}");
}

#[test]
fn colour_bar_spans_the_data_and_figures_are_valid() {
    let d = exact_loop(2, 1.2, 256);
    let lam = d.column("lambda").unwrap();
    let (lo, hi) = lam
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let pic = loop_picture(&d, &LoopPictureOptions::default()).unwrap();
    assert_eq!(pic.color_column, "lambda");
    assert_eq!(pic.scale, Scale { min: lo, max: hi });
    // Both ends of the bar are labelled with the data range.
    assert!(pic.svg.contains(&format!("{lo:.4}")) && pic.svg.contains(&format!("{hi:.4}")));
    // Valid XML with a width and height.
    let doc = roxmltree::Document::parse(&pic.svg).unwrap();
    let w: f64 = doc
        .root_element()
        .attribute("width")
        .unwrap()
        .parse()
        .unwrap();
    let h: f64 = doc
        .root_element()
        .attribute("height")
        .unwrap()
        .parse()
        .unwrap();
    let png = svg_to_png(&pic.svg, 1.0).unwrap();
    assert_eq!(png_size(&png).unwrap(), (w as u32, h as u32));
    let png2 = svg_to_png(&pic.svg, 0.5).unwrap();
    assert_eq!(
        png_size(&png2).unwrap(),
        ((w * 0.5).round() as u32, (h * 0.5).round() as u32)
    );
    // Colouring by a column that is not there names it.
    let e = loop_picture(
        &d,
        &LoopPictureOptions {
            color: Some("gap".into()),
            ..Default::default()
        },
    )
    .unwrap_err();
    assert!(matches!(e, FigureError::MissingColumn { ref column, .. } if column == "gap"));
}

#[test]
fn bad_tables_give_precise_errors() {
    let e = LoopData::parse("f.csv", b"").unwrap_err();
    assert!(matches!(e, FigureError::MissingColumn { .. }), "{e}");
    let e = LoopData::parse("f.csv", b"s,x,y\n0,1,0\n").unwrap_err();
    assert!(e.to_string().contains("`z`"), "{e}");
    let mut text = String::from("s,x,y,z\n");
    for i in 0..10 {
        let t = i as f64 * PI / 5.0;
        text += &format!(
            "{t},{},{},0\n",
            t.cos(),
            if i == 4 {
                "NaN".into()
            } else {
                t.sin().to_string()
            }
        );
    }
    let e = LoopData::parse("f.csv", text.as_bytes()).unwrap_err();
    assert!(
        e.to_string().contains("row 6") && e.to_string().contains("`y`"),
        "{e}"
    );
    let e = LoopData::parse("f.csv", b"s,x,y,z\n0,1,0,0\n1,0,1,0\n").unwrap_err();
    assert!(matches!(e, FigureError::TooFewRows { found: 2, .. }), "{e}");
}

/// A numeric diagram of one branch in the result schema: stable below `L̄ = 1.35`,
/// metastable above, one collapse at `L̄ = 1`.
fn numeric_diagram() -> Diagram {
    let mut d = Diagram::new(
        "numeric",
        "test",
        vec![Axis {
            name: "lbar".into(),
            min: 1.0,
            max: 1.9,
        }],
        "u",
    );
    d.columns = [
        "branch",
        "eta",
        "lbar",
        "energy",
        "energy_g",
        "energy_error",
        "stability",
        "index",
        "lambda_min",
        "lambda_max",
    ]
    .iter()
    .map(|c| c.to_string())
    .collect();
    for k in 0..=9 {
        let l = 1.0 + 0.1 * k as f64;
        d.points.push(Point {
            branch: 1,
            eta: 2,
            coords: vec![l],
            energy: 1.0 + l,
            energy_error: Some(1e-9),
            index: Some(0),
            label: Some(if k < 4 { "stable" } else { "metastable" }.into()),
            extra: BTreeMap::from([
                ("energy_g".into(), Cell::F(l - 1.0)),
                ("lambda_min".into(), Cell::F(4.0 - l)),
                ("lambda_max".into(), Cell::F(4.0 + l)),
            ]),
            ..Point::default()
        });
    }
    d.critical.push(Critical {
        index: 1,
        lbar_cr: 1.0,
        kind: "collapse".into(),
        from_branch: 0,
        to_branch: 1,
        energy: 1.0,
        error_estimate: 0.0,
        extra: BTreeMap::new(),
    });
    d
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("rodloop-fig-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn diagram_legend_lists_only_what_is_drawn() {
    let dir = scratch("legend");
    numeric_diagram().write(&dir).unwrap();
    let d = DiagramData::read(&dir).unwrap();
    assert_eq!(d.model, "numeric");
    let svg = energy_figure(&d, 900.0, 600.0).unwrap();
    roxmltree::Document::parse(&svg).unwrap();
    assert!(svg.contains("stable (lowest energy)") && svg.contains("metastable"));
    assert!(!svg.contains("unstable"), "nothing unstable is drawn");
    assert!(svg.contains("collapse onto a great circle") && !svg.contains("crossing: "));
    assert!(svg.contains("L̄ = L/(2πR)") && svg.contains("E R/(πD₀)") && svg.contains("η = 2"));
    // L̄ spans [1, 1.9]: Eq. (33) at m = 1 is (1+1)²/1² = 4; Eq. (34) needs m ≥ 2: none here.
    let lam = lambda_figure(&d, 900.0, 600.0).unwrap();
    assert!(lam.contains("Eq. (33)") && !lam.contains("Eq. (34)"));
    assert!(energy_figure(&d, 10.0, 600.0).is_err());
    std::fs::remove_dir_all(&dir).ok();
}

/// A diagram directory is read through the schema: without `summary.json`, with a column
/// the schema does not know, with a cell that is not a number, without a column a figure
/// needs, or a diagram against a parameter, the error is one line naming the file and the
/// column or row at fault.
#[test]
fn diagram_directories_that_cannot_be_drawn_say_why() {
    let err = |dir: &Path| {
        let e = DiagramData::read(dir).unwrap_err().to_string();
        assert_eq!(e.lines().count(), 1, "{e}");
        e
    };
    // Only the tables: not a diagram directory.
    let dir = scratch("no-summary");
    numeric_diagram().write(&dir).unwrap();
    std::fs::remove_file(dir.join("summary.json")).unwrap();
    let e = err(&dir);
    assert!(
        e.contains("not a diagram directory") && e.contains("summary.json"),
        "{e}"
    );
    // A column the schema does not know.
    numeric_diagram().write(&dir).unwrap();
    let csv = std::fs::read_to_string(dir.join("branches.csv")).unwrap();
    std::fs::write(
        dir.join("branches.csv"),
        csv.replacen("energy_g", "energy_x", 1),
    )
    .unwrap();
    let e = err(&dir);
    assert!(e.contains("branches.csv") && e.contains("energy_x"), "{e}");
    // A cell that is not a number (row 4 of the file: the third state).
    let mut lines: Vec<String> = csv.lines().map(str::to_string).collect();
    let mut cells: Vec<&str> = lines[3].split(',').collect();
    cells[5] = "NaN";
    lines[3] = cells.join(",");
    std::fs::write(dir.join("branches.csv"), lines.join("\n") + "\n").unwrap();
    let e = err(&dir);
    assert!(
        e.contains("branches.csv") && e.contains("row 4") && e.contains("energy_error"),
        "{e}"
    );
    // Without the largest contact force a numeric diagram's figures cannot be drawn.
    let mut d = numeric_diagram();
    d.columns.retain(|c| c != "lambda_max");
    for p in &mut d.points {
        p.extra.remove("lambda_max");
    }
    d.write(&dir).unwrap();
    let e = err(&dir);
    assert!(
        e.contains("branches.csv") && e.contains("no column `lambda_max`"),
        "{e}"
    );
    // A diagram against a parameter (two axes) is not drawn as a diagram in L̄.
    let mut d = numeric_diagram();
    d.axes.insert(
        0,
        Axis {
            name: "value".into(),
            min: 0.1,
            max: 0.5,
        },
    );
    d.columns.push("value".into());
    for p in &mut d.points {
        p.coords.insert(0, 0.3);
    }
    d.write(&dir).unwrap();
    let e = err(&dir);
    assert!(e.contains("value, lbar") && e.contains("lbar only"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn colour_scale_clips_only_isolated_peaks() {
    use rodloop_figures::loops::colour_scale;
    let n = 200;
    let s: Vec<f64> = (0..n).map(|i| i as f64 / n as f64).collect();
    let smooth: Vec<f64> = s
        .iter()
        .map(|x| (std::f64::consts::TAU * x).sin())
        .collect();
    // A smooth column: the bar spans the data.
    let (sc, full) = colour_scale(&smooth, &s);
    assert!(full.is_none());
    let (lo, hi) = smooth
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    assert_eq!((sc.min, sc.max), (lo, hi));
    // Four nodes (2 % of the length) at ±100: the bar spans the sine, the full range is kept.
    let mut peaks = smooth.clone();
    for (i, v) in [(50, 100.0), (51, -100.0), (150, 100.0), (151, -100.0)] {
        peaks[i] = v;
    }
    let (sc, full) = colour_scale(&peaks, &s);
    let full = full.expect("clipped");
    assert_eq!((full.min, full.max), (-100.0, 100.0));
    assert!(
        sc.min >= -1.0 && sc.max <= 1.0 && sc.max - sc.min > 1.5,
        "{sc:?}"
    );
}
