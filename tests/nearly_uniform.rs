//! A nearly uniform two-segment rod (`D1/D0 = 0.99`): `diagram` traces both branches around
//! the 1 → 2 exchange (its seeds left both out before: Newton from Euler starts drifts along
//! the nearly neutral placement of the soft segment) and the exchange it prints is bracketed
//! by independent `solve` runs.

use std::path::Path;

mod common;
use common::{rodloop, tmp};

fn scene(dir: &Path) -> String {
    std::fs::create_dir_all(dir).unwrap();
    let p = dir.join("nearly-uniform.toml");
    std::fs::write(
        &p,
        "name = \"nearly-uniform\"\nradius = 1.0\nlbar_min = 1.3\nlbar_max = 1.5\n\
         [stiffness]\nkind = \"tanh\"\nd0 = 1.0\nd1 = 0.99\ngamma = 200.0\ns0 = 0.3\ns1 = 0.8\n",
    )
    .unwrap();
    p.to_str().unwrap().to_string()
}

fn energy(scene: &str, lbar: f64, branch: u32, out: &Path) -> f64 {
    let o = rodloop(&[
        "solve",
        "--scene",
        scene,
        "--lbar",
        &lbar.to_string(),
        "--branch",
        &branch.to_string(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    s["energy"].as_f64().unwrap()
}

#[test]
fn nearly_uniform_rod_has_its_exchange_bracketed_by_independent_solves() {
    let dir = tmp("nearly-uniform");
    let scene = scene(&dir);
    let out = dir.join("diagram");
    let o = rodloop(&[
        "diagram",
        "--scene",
        &scene,
        "--branch",
        "1,2",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !err.contains("left out") && !err.contains("NO STABLE"),
        "{err}"
    );
    let mut rdr = csv::Reader::from_path(out.join("critical.csv")).unwrap();
    let rows: Vec<csv::StringRecord> = rdr.records().map(|r| r.unwrap()).collect();
    let x = rows
        .iter()
        .find(|r| &r[2] == "crossing" && &r[3] == "1" && &r[4] == "2")
        .unwrap_or_else(|| panic!("no 1 → 2 exchange: {rows:?}"));
    let (lbar, est): (f64, f64) = (x[1].parse().unwrap(), x[6].parse().unwrap());
    assert!(est < 1e-6, "estimate {est}");
    // Independent solves on either side: branch 1 lowest below, branch 2 above.
    let h = 1e-4;
    let below =
        energy(&scene, lbar - h, 1, &dir.join("b1")) - energy(&scene, lbar - h, 2, &dir.join("b2"));
    let above =
        energy(&scene, lbar + h, 1, &dir.join("a1")) - energy(&scene, lbar + h, 2, &dir.join("a2"));
    assert!(
        below < 0.0 && above > 0.0,
        "E1 − E2: {below} at −h, {above} at +h"
    );
}
