//! Known-answer tests of the figures crate: projections, self-contacts, colour bar, PNG and
//! SVG validity, bad input.

use std::f64::consts::{PI, TAU};

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

#[test]
fn diagram_legend_lists_only_what_is_drawn() {
    let dir = std::env::temp_dir().join(format!("rodloop-fig-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut b = String::from(
        "branch,eta,lbar,energy,energy_g,energy_error,stability,index,lambda_min,lambda_max\n",
    );
    for k in 0..=9 {
        let l = 1.0 + 0.1 * k as f64;
        let st = if k < 4 { "stable" } else { "metastable" };
        b += &format!(
            "1,2,{l},{},{},1e-9,{st},0,{},{}\n",
            1.0 + l,
            l - 1.0,
            4.0 - l,
            4.0 + l
        );
    }
    std::fs::write(dir.join("branches.csv"), b).unwrap();
    std::fs::write(
        dir.join("critical.csv"),
        "index,lbar_cr,kind,from_branch,to_branch,energy,error_estimate\n1,1,collapse,0,1,1,0\n",
    )
    .unwrap();
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
