//! The direct tiny-skia painter against resvg: the same document drawn both ways gives
//! nearly the same pixels (two independent rasterisations of one picture), every figure kind
//! is drawn directly (no fallback), and raw markup falls back to resvg.

use rodloop_exact::{paper_branch_loop, shape::ShapeTolerances};
use rodloop_figures::data::LoopData;
use rodloop_figures::loops::{loop_picture, LoopPictureOptions};
use rodloop_figures::paint::to_png;
use rodloop_figures::profiles::profiles_document;
use rodloop_figures::raster::svg_to_png;
use rodloop_figures::svg::{Anchor, Svg};

/// The figure-eight (branch 2 at L̄ = 1.6) as a CSV table, read as `rodloop draw` reads it.
fn figure_eight() -> LoopData {
    let lp = paper_branch_loop(1, 1.6).unwrap();
    let mut csv = String::from("s,x,y,z,kappa_g,lambda\n");
    for p in lp.sample(400).unwrap() {
        csv += &format!(
            "{},{},{},{},{},{}\n",
            p.s, p.x, p.y, p.z, p.kappa_g, p.lambda
        );
    }
    LoopData::parse("eight", csv.as_bytes()).unwrap()
}

fn pixels(png: &[u8]) -> (u32, u32, Vec<u8>) {
    let p = resvg::tiny_skia::Pixmap::decode_png(png).unwrap();
    (p.width(), p.height(), p.data().to_vec())
}

/// Fraction of pixels whose largest channel difference exceeds `level`.
fn differing(a: &[u8], b: &[u8], level: u8) -> f64 {
    let n = a.len() / 4;
    let bad = a
        .chunks_exact(4)
        .zip(b.chunks_exact(4))
        .filter(|(p, q)| (0..3).any(|c| p[c].abs_diff(q[c]) > level))
        .count();
    bad as f64 / n as f64
}

#[test]
fn direct_painter_matches_resvg() {
    let data = figure_eight();
    let pic = loop_picture(&data, &LoopPictureOptions::default()).unwrap();
    assert!(pic.document.is_direct());
    let prof = profiles_document(&data, None, 480.0, 260.0, "profiles").unwrap();
    assert!(prof.is_direct());
    for doc in [&pic.document, &prof] {
        let (w1, h1, a) = pixels(&to_png(doc, 1.0).unwrap());
        let (w2, h2, b) = pixels(&svg_to_png(&doc.finish(), 1.0).unwrap());
        assert_eq!((w1, h1), (w2, h2));
        // Anti-aliasing and the emboldened titles (resvg has no bold face to use) differ
        // on edge pixels only.
        let f = differing(&a, &b, 64);
        eprintln!(
            "{w1}×{h1}: {:.3} % of pixels differ by more than 64/255",
            100.0 * f
        );
        assert!(f < 0.01, "{f}");
    }
    // The shape found while drawing is the figure-eight's (Sec. 3.1).
    let sh = pic.shape.unwrap();
    assert_eq!(sh.point_group, "C2v");
    assert_eq!(sh.self_intersections, Some(1));
    assert_eq!(sh.tolerances, ShapeTolerances::default());
}

#[test]
fn raw_markup_falls_back_to_resvg_and_scale_is_checked() {
    let mut svg = Svg::new(200.0, 100.0);
    svg.text(10.0, 50.0, 14.0, Anchor::Start, "L̄ = 1.5");
    assert!(svg.is_direct());
    svg.raw("<ellipse cx=\"100\" cy=\"50\" rx=\"40\" ry=\"20\" fill=\"#336699\"/>");
    assert!(!svg.is_direct());
    let (w, h, px) = pixels(&to_png(&svg, 2.0).unwrap());
    assert_eq!((w, h), (400, 200));
    // The ellipse (only resvg knows it) is drawn: its centre pixel is #336699.
    let c = ((100 * w + 200) * 4) as usize;
    assert_eq!(&px[c..c + 3], &[0x33, 0x66, 0x99]);
    assert!(to_png(&svg, 0.0).is_err());
    assert!(to_png(&svg, f32::NAN).is_err());
}
