//! `diagram --shapes K` and the state files of `diagram`: every traced state is saved in
//! `states/` and re-solves (`solve --from`) to its `branches.csv` energy within the error
//! estimates; the atlas has K cells per branch; no `--shapes` means no atlas.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

mod common;
use common::{bin, run, summary};

fn tmp(name: &str) -> PathBuf {
    common::fresh_dir("rodloop-atlas", name)
}

/// branches.csv as maps from column name to text.
fn rows(dir: &Path) -> Vec<BTreeMap<String, String>> {
    let mut rdr = csv::Reader::from_path(dir.join("branches.csv")).unwrap();
    let header: Vec<String> = rdr.headers().unwrap().iter().map(String::from).collect();
    assert_eq!(header.last().map(String::as_str), Some("state_file"));
    rdr.records()
        .map(|r| {
            let r = r.unwrap();
            header
                .iter()
                .cloned()
                .zip(r.iter().map(String::from))
                .collect()
        })
        .collect()
}

/// Re-solve the state of `row` with `solve --from … --keep-saddle` (the written state as it
/// is, an unstable one included, not the minimum `solve` would descend to) and check the
/// energy against the row's energy: within the sum of the two error estimates.
fn resolve_matches(dir: &Path, row: &BTreeMap<String, String>, scene: Option<&Path>, out: &Path) {
    let file = dir.join(&row["state_file"]);
    let mut cmd = bin();
    cmd.args([
        "solve",
        "--lbar",
        &row["lbar"],
        "--branch",
        &row["branch"],
        "--keep-saddle",
        "--from",
    ])
    .arg(&file)
    .arg("--out")
    .arg(out);
    if let Some(s) = scene {
        cmd.arg("--scene").arg(s);
    }
    let (ok, _, err) = run(&mut cmd);
    assert!(ok, "{}: {err}", file.display());
    let s = summary(out);
    let e_solve = s["energy"].as_f64().unwrap();
    let est_solve = s["error_estimate"].as_f64().unwrap();
    let e_diagram: f64 = row["energy"].parse().unwrap();
    let est_diagram: f64 = row["energy_error"].parse().unwrap();
    assert!(
        (e_solve - e_diagram).abs() <= est_diagram + est_solve,
        "{}: solve {e_solve} ± {est_solve:e}, diagram {e_diagram} ± {est_diagram:e}",
        file.display()
    );
    // The saved state has the columns solve writes.
    let head = |p: &Path| {
        std::fs::read_to_string(p)
            .unwrap()
            .lines()
            .next()
            .unwrap()
            .to_string()
    };
    assert_eq!(head(&file), head(&out.join("config.csv")));
}

/// Atlas thumbnails per (branch, family), from the files in atlas/.
fn thumbnails(dir: &Path) -> BTreeMap<String, usize> {
    let mut m = BTreeMap::new();
    for e in std::fs::read_dir(dir.join("atlas")).unwrap() {
        let name = e.unwrap().file_name().to_string_lossy().to_string();
        if let Some(stem) = name.strip_suffix(".svg") {
            let key = stem.rsplit_once('-').unwrap().0.to_string();
            *m.entry(key).or_insert(0) += 1;
            assert!(dir.join("atlas").join(format!("{stem}.png")).is_file());
        }
    }
    m
}

#[test]
fn homogeneous_states_resolve_and_the_atlas_has_k_cells_per_branch() {
    let d = tmp("homogeneous");
    let (ok, out, err) = run(bin()
        .args(["diagram", "--quiet", "--lbar-min", "1", "--lbar-max", "2.6"])
        .args(["--shapes", "4", "--out"])
        .arg(&d));
    assert!(ok, "{err}");
    assert!(out.contains("atlas:"), "{out}");
    let rs = rows(&d);
    // Every row names its own existing file.
    let mut files: Vec<&str> = rs.iter().map(|r| r["state_file"].as_str()).collect();
    assert!(
        files.iter().all(|f| d.join(f).is_file()),
        "missing state file"
    );
    files.sort_unstable();
    files.dedup();
    assert_eq!(files.len(), rs.len());
    // One state per branch from the middle of its rows re-solves to its energy.
    let branches: Vec<String> = {
        let mut b: Vec<String> = rs.iter().map(|r| r["branch"].clone()).collect();
        b.dedup();
        b.sort();
        b.dedup();
        b
    };
    assert!(branches.len() >= 3, "{branches:?}");
    for b in &branches {
        let of: Vec<_> = rs.iter().filter(|r| &r["branch"] == b).collect();
        resolve_matches(&d, of[of.len() / 2], None, &d.join(format!("solve-{b}")));
    }
    // K thumbnails for every branch, and the composite with K cells per row.
    let t = thumbnails(&d);
    assert_eq!(t.len(), branches.len(), "{t:?}");
    assert!(t.values().all(|&k| k == 4), "{t:?}");
    let svg = std::fs::read_to_string(d.join("atlas.svg")).unwrap();
    roxmltree::Document::parse(&svg).unwrap();
    assert_eq!(svg.matches("L̄ = ").count(), 4 * branches.len());
    let png = std::fs::read(d.join("atlas.png")).unwrap();
    rodloop_figures::raster::png_size(&png).unwrap();
    // summary.json names the state directory and every atlas file, which exist.
    let summary = summary(&d);
    assert_eq!(summary["states_dir"], "states");
    let listed = summary["atlas"]["files"].as_array().unwrap();
    assert_eq!(listed.len(), 2 * 4 * branches.len() + 2);
    assert!(listed.iter().all(|f| d.join(f.as_str().unwrap()).is_file()));

    // Without --shapes: the states stay, the atlas of the previous run goes.
    let (ok, out, err) = run(bin()
        .args([
            "diagram",
            "--quiet",
            "--lbar-min",
            "1",
            "--lbar-max",
            "2.6",
            "--out",
        ])
        .arg(&d));
    assert!(ok, "{err}");
    assert!(!out.contains("atlas:"), "{out}");
    assert!(!d.join("atlas.svg").exists() && !d.join("atlas.png").exists());
    assert!(!d.join("atlas").exists());
    assert!(rows(&d).iter().all(|r| d.join(&r["state_file"]).is_file()));
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn two_segment_family_states_resolve_and_are_drawn() {
    // Eq. (51) with D1/D0 = 0.5 and gamma = 30: a graded mesh, and cells enough for the
    // half-resolution partner, so every traced energy has an error estimate.
    let d = tmp("two-segment");
    let scene = d.join("g30.toml");
    std::fs::write(
        &scene,
        "name = \"two-segment-g30\"\n[stiffness]\nkind = \"tanh\"\nd0 = 1.0\nd1 = 0.5\ns0 = 0.3\ns1 = 0.8\ngamma = 30.0\n",
    )
    .unwrap();
    let out = d.join("diagram");
    let (ok, _, err) = run(bin()
        .args(["diagram", "--quiet", "--branch", "2", "--lbar-min", "1.2"])
        .args(["--lbar-max", "1.8", "--shapes", "3", "--scene"])
        .arg(&scene)
        .arg("--out")
        .arg(&out));
    assert!(ok, "{err}");
    let rs = rows(&out);
    let families: std::collections::BTreeSet<&str> =
        rs.iter().map(|r| r["family"].as_str()).collect();
    assert!(
        families.len() >= 2 && !families.contains("0"),
        "{families:?}"
    );
    for f in &families {
        let of: Vec<_> = rs.iter().filter(|r| r["family"] == *f).collect();
        let row = of[of.len() / 2];
        assert!(row["state_file"].contains(&format!("family-{f}-")));
        resolve_matches(&out, row, Some(&scene), &d.join(format!("solve-{f}")));
        // The state file is uniform in s and carries the stiffness profile.
        let data = rodloop_figures::data::LoopData::read(&out.join(&row["state_file"])).unwrap();
        let s = data.s();
        let h = s[1] - s[0];
        assert!(s.windows(2).all(|w| ((w[1] - w[0]) - h).abs() < 1e-9));
        let dcol = data.column("D").unwrap();
        let (lo, hi) = dcol
            .iter()
            .fold((9.0f64, 0.0f64), |(a, b), &v| (a.min(v), b.max(v)));
        assert!(lo < 0.51 && hi > 0.99, "D in [{lo}, {hi}]");
    }
    let t = thumbnails(&out);
    assert_eq!(t.len(), families.len(), "{t:?}");
    assert!(t.values().all(|&k| k == 3), "{t:?}");
    // The state files draw with `rodloop draw`.
    let first = out.join(&rs[0]["state_file"]);
    let (ok, _, err) = run(bin()
        .arg("draw")
        .arg(&first)
        .args(["--format", "svg", "--out"])
        .arg(&d));
    assert!(ok, "{err}");
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn shapes_bad_input_is_refused() {
    let d = tmp("bad");
    let (ok, _, err) = run(bin().args(["diagram", "--shapes", "21", "--out"]).arg(&d));
    assert!(
        !ok && err.contains("--shapes must be from 0 to 20"),
        "{err}"
    );
    let (ok, _, err) = run(bin().args(["diagram", "--shapes", "-1", "--out"]).arg(&d));
    assert!(!ok && !err.contains("panicked"), "{err}");
    assert!(!d.join("atlas.svg").exists());
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn exact_diagram_writes_fig11_with_eq_b4() {
    let d = tmp("k2");
    let (ok, out, err) = run(bin()
        .args(["diagram", "--model", "exact", "--lbar-max", "3", "--out"])
        .arg(&d));
    assert!(ok, "{err}");
    assert!(out.contains("diagram_k2.svg"), "{out}");
    let svg = std::fs::read_to_string(d.join("diagram_k2.svg")).unwrap();
    let doc = roxmltree::Document::parse(&svg).unwrap();
    // A solid curve per branch (1, 2, 3) and dashed Eq. (B.4) pieces.
    let paths: Vec<_> = doc
        .descendants()
        .filter(|n| n.has_tag_name("path"))
        .collect();
    let dashed = paths
        .iter()
        .filter(|n| n.attribute("stroke-dasharray") == Some("6 4"))
        .count();
    assert!(
        paths.len() - dashed >= 3 && dashed >= 3,
        "{} paths, {dashed} dashed",
        paths.len()
    );
    assert!(svg.contains("Eq. (B.4)"));
    assert!(!d.join("atlas.svg").exists(), "no --shapes, no atlas");
    rodloop_figures::raster::png_size(&std::fs::read(d.join("diagram_k2.png")).unwrap()).unwrap();
    // A numeric run into the same directory removes it.
    let (ok, _, err) = run(bin()
        .args([
            "diagram",
            "--quiet",
            "--accuracy",
            "fast",
            "--lbar-max",
            "1.5",
            "--out",
        ])
        .arg(&d));
    assert!(ok, "{err}");
    assert!(!d.join("diagram_k2.svg").exists() && !d.join("diagram_k2.png").exists());
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn exact_diagram_atlas_has_k_cells_per_branch() {
    let d = tmp("exact-atlas");
    let (ok, out, err) = run(bin()
        .args([
            "diagram",
            "--model",
            "exact",
            "--lbar-max",
            "3",
            "--shapes",
            "3",
            "--out",
        ])
        .arg(&d));
    assert!(ok, "{err}");
    assert!(out.contains("atlas: 3 rows, 9 thumbnails"), "{out}");
    let t = thumbnails(&d);
    assert_eq!(
        t.keys().collect::<Vec<_>>(),
        ["branch-1", "branch-2", "branch-3"]
    );
    assert!(t.values().all(|&k| k == 3), "{t:?}");
    let svg = std::fs::read_to_string(d.join("atlas.svg")).unwrap();
    roxmltree::Document::parse(&svg).unwrap();
    assert_eq!(svg.matches("L̄ = ").count(), 9);
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn enclosed_atlas_states_are_in_the_ball_and_off_the_wall_where_the_diagram_says() {
    let d = tmp("enclosed");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/scenes/homogeneous-enclosed.toml");
    let (ok, out, err) = run(bin()
        .args(["diagram", "--scene"])
        .arg(&scene)
        .args(["--lbar-max", "2", "--shapes", "3", "--out"])
        .arg(&d));
    assert!(ok, "{err}");
    assert!(d.join("atlas.png").is_file(), "{out}");
    // branches.csv of the enclosed diagram: (branch, lbar) -> attached.
    let mut rdr = csv::Reader::from_path(d.join("branches.csv")).unwrap();
    let h: Vec<String> = rdr.headers().unwrap().iter().map(String::from).collect();
    let c = |n: &str| h.iter().position(|x| x == n).unwrap();
    let attached: Vec<(u32, f64, bool)> = rdr
        .records()
        .map(|r| {
            let r = r.unwrap();
            (
                r[c("branch")].parse().unwrap(),
                r[c("lbar")].parse().unwrap(),
                &r[c("attached")] == "1",
            )
        })
        .collect();
    let summary = summary(&d);
    let rows = summary["atlas"]["rows"].as_array().unwrap();
    let mut lifted = 0;
    for row in rows {
        let b = row["branch"].as_u64().unwrap() as u32;
        for (l, f) in row["lbar"]
            .as_array()
            .unwrap()
            .iter()
            .zip(row["state_files"].as_array().unwrap())
        {
            let l = l.as_f64().unwrap();
            let mut st = csv::Reader::from_path(d.join(f.as_str().unwrap())).unwrap();
            let sh: Vec<String> = st.headers().unwrap().iter().map(String::from).collect();
            let k = |n: &str| sh.iter().position(|x| x == n).unwrap();
            let mut max_gap = 0.0f64;
            for r in st.records() {
                let r = r.unwrap();
                let v = |n: &str| r[k(n)].parse::<f64>().unwrap();
                let norm = (v("x").powi(2) + v("y").powi(2) + v("z").powi(2)).sqrt();
                // Nodes lie in the ball; a Gauss point (node 0, weight h/2) at most its
                // cell curve's bulge κ h²/12 beyond the chord between two nodes inside it.
                let h = 2.0 * v("weight");
                let reach = if v("node") == 1.0 {
                    0.0
                } else {
                    1.5 * v("kappa").abs() * h * h / 12.0
                };
                assert!(norm <= 1.0 + 1e-9 + reach, "{f}: |r| = {norm}");
                assert!((norm - (1.0 - v("gap"))).abs() < 1e-9);
                max_gap = max_gap.max(v("gap"));
            }
            // The re-solved state is off the wall exactly where the diagram's sample is.
            let (_, _, on) = attached
                .iter()
                .find(|(bb, ll, _)| *bb == b && (ll - l).abs() < 1e-12)
                .unwrap_or_else(|| panic!("branch {b} at {l} is not a sample"));
            assert_eq!(!on, max_gap > 1e-9, "branch {b} at {l}: max gap {max_gap}");
            lifted += usize::from(max_gap > 1e-9);
        }
    }
    // Branch 2 is lifted off below its landing at 1.506 (and L̄ ≤ 2 here).
    assert!(lifted >= 1, "{rows:?}");
    let svg = std::fs::read_to_string(d.join("atlas.svg")).unwrap();
    roxmltree::Document::parse(&svg).unwrap();
    assert!(svg.contains("amber: lifted off the wall"));
    std::fs::remove_dir_all(&d).ok();
}
