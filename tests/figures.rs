//! End-to-end tests of `rodloop draw` and the `--draw` flags, through the built binary.

use std::path::{Path, PathBuf};

use rodloop_figures::raster::png_size;

mod common;
use common::{bin, run};

fn tmp(name: &str) -> PathBuf {
    common::fresh_dir("rodloop-figtest", name)
}

fn svg_size(path: &Path) -> (u32, u32) {
    let text = std::fs::read_to_string(path).unwrap();
    let doc = roxmltree::Document::parse(&text).unwrap();
    let r = doc.root_element();
    let f = |a: &str| r.attribute(a).unwrap().parse::<f64>().unwrap() as u32;
    (f("width"), f("height"))
}

#[test]
fn draw_an_analytic_loop() {
    let d = tmp("analytic");
    let (ok, _, err) = run(bin()
        .args(["analytic", "--lbar", "1.6", "--eta", "1", "--out"])
        .arg(&d));
    assert!(ok, "{err}");
    let (ok, out, err) = run(bin()
        .arg("draw")
        .arg(d.join("loop-01.csv"))
        .args(["--color", "kappa_g"]));
    assert!(ok, "{err}");
    assert!(out.contains("loop-01.png"));
    let png = std::fs::read(d.join("loop-01.png")).unwrap();
    assert_eq!(png_size(&png).unwrap(), svg_size(&d.join("loop-01.svg")));
    let note: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("loop-01-draw.json")).unwrap())
            .unwrap();
    // The figure-eight (branch 2) touches itself once (paper Sec. 3.1).
    assert_eq!(note["self_intersections"], 1);
    assert_eq!(note["color_column"], "kappa_g");
    assert_eq!(note["eta"], 1);
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn draw_flags_write_pictures_next_to_the_csv() {
    let d = tmp("flags");
    let (ok, _, err) = run(bin()
        .args([
            "solve",
            "--lbar",
            "1.2",
            "--branch",
            "1",
            "--accuracy",
            "fast",
            "--draw",
            "--out",
        ])
        .arg(d.join("s")));
    assert!(ok, "{err}");
    for f in ["config.svg", "config.png", "config-draw.json"] {
        assert!(d.join("s").join(f).exists(), "{f}");
    }
    let note: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("s/config-draw.json")).unwrap())
            .unwrap();
    assert_eq!(note["point_group"], "D2d", "the saddle of branch 1");
    assert_eq!(note["self_intersections"], 0);
    let (ok, _, err) = run(bin()
        .args(["euler", "--l", "2", "--lbar", "1.2", "--draw", "--out"])
        .arg(d.join("e")));
    assert!(ok, "{err}");
    assert!(d.join("e/curve.png").exists());
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn diagram_figures_have_the_requested_size() {
    let d = tmp("diagram");
    let (ok, _, err) = run(bin()
        .args([
            "diagram", "--model", "exact", "--width", "800", "--height", "500", "--out",
        ])
        .arg(&d));
    assert!(ok, "{err}");
    for stem in ["diagram", "diagram_split", "diagram_lambda"] {
        let png = std::fs::read(d.join(format!("{stem}.png"))).unwrap();
        assert_eq!(png_size(&png).unwrap(), (800, 500), "{stem}");
        assert_eq!(svg_size(&d.join(format!("{stem}.svg"))), (800, 500));
    }
    let svg = std::fs::read_to_string(d.join("diagram.svg")).unwrap();
    assert!(svg.contains("crossing: E_a = E_b") && svg.contains("collapse onto a great circle"));
    assert!(
        !svg.contains("unstable"),
        "the exact model labels nothing unstable"
    );
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn bad_input_gives_one_line_and_no_picture() {
    let d = tmp("bad");
    let f = d.join("bad.csv");
    std::fs::write(
        &f,
        "s,x,y,z\n0,1,0,0\n1,NaN,1,0\n2,0,0,1\n3,1,1,1\n4,1,0,0\n5,0,1,0\n6,0,0,1\n7,1,1,0\n",
    )
    .unwrap();
    let (ok, _, err) = run(bin().arg("draw").arg(&f));
    assert!(!ok);
    assert!(err.contains("row 3") && err.contains("`x`"), "{err}");
    assert!(!err.contains("panicked"));
    assert!(!d.join("bad.svg").exists());
    std::fs::write(&f, "s,x,y\n0,1,0\n").unwrap();
    let (ok, _, err) = run(bin().arg("draw").arg(&f));
    assert!(!ok && err.contains("no column `z`"), "{err}");
    std::fs::write(&f, "").unwrap();
    let (ok, _, err) = run(bin().arg("draw").arg(&f));
    assert!(!ok && err.starts_with("error:"), "{err}");
    let (ok, _, err) = run(bin().arg("draw").arg(d.join("missing.csv")));
    assert!(!ok && err.contains("missing.csv"), "{err}");
    std::fs::remove_dir_all(&d).ok();
}
