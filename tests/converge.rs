//! `rodloop converge` end to end: the ladder shows fourth-order convergence to the exact
//! loop, and the printed estimates bound the true errors; on an enclosed scene the ladder
//! starts from the state `solve` reports and its finest rung is written and verified.

mod common;
use common::{bin, read_csv, tmp};

/// `rodloop converge ARGS --out OUT` run to success; the table's header and rows.
fn converge(out: &std::path::Path, args: &[&str]) -> (Vec<String>, Vec<Vec<String>>) {
    let o = bin()
        .arg("converge")
        .args(args)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    read_csv(&out.join("converge.csv"))
}

#[test]
fn converge_ladder_is_fourth_order_against_the_exact_loop() {
    let out = tmp("converge-ladder");
    let (header, rows) = converge(&out, &["--lbar", "1.3", "--branch", "2", "--levels", "4"]);
    let col = |n: &str| common::col(&header, n);
    assert_eq!(rows.len(), 4);
    // The exact energy comes from the exact layer, independently of the numerical model.
    let exact = rodloop_exact::paper_branch_loop(1, 1.3)
        .unwrap()
        .energy()
        .unwrap();
    let energy: Vec<f64> = rows
        .iter()
        .map(|r| r[col("energy")].parse().unwrap())
        .collect();
    let errs: Vec<f64> = energy.iter().map(|e| (e - exact).abs()).collect();
    for w in errs.windows(2) {
        let order = (w[0] / w[1]).log2();
        assert!(
            (3.7..4.3).contains(&order),
            "order {order} from errors {errs:?}"
        );
    }
    for (i, r) in rows.iter().enumerate().skip(1) {
        let est: f64 = r[col("error_estimate")].parse().unwrap();
        assert!(
            est > 0.5 * errs[i] && est < 2.0 * errs[i],
            "rung {i}: estimate {est:e} vs true error {:e}",
            errs[i]
        );
        let printed: f64 = r[col("error_vs_exact")].parse().unwrap();
        assert!((printed - errs[i]).abs() <= 1e-12 + 1e-6 * errs[i]);
    }
}

/// On the uniform enclosed scene, the figure-eight at `L̄ = 1.4` lifted off the wall: the
/// ladder from 64 cells (the solved state resampled) to 512 converges (the energy
/// differences fall at every doubling), its finest energy lies within the estimate `solve`
/// gives at its own mesh, and its finest rung is written (`states/finest.csv`) with the energy
/// recomputed from the file equal to the row's.
#[test]
fn converge_on_an_enclosed_scene_climbs_a_ladder_from_the_solved_state() {
    let out = tmp("converge-enclosed");
    let (header, rows) = converge(
        &out,
        &[
            "--scene",
            "data/scenes/homogeneous-enclosed.toml",
            "--lbar",
            "1.4",
            "--branch",
            "2",
            "--min-cells",
            "64",
            "--levels",
            "4",
        ],
    );
    let col = |n: &str| common::col(&header, n);
    assert_eq!(rows.len(), 4);
    let energy: Vec<f64> = rows
        .iter()
        .map(|r| r[col("energy")].parse().unwrap())
        .collect();
    let d: Vec<f64> = energy.windows(2).map(|w| (w[1] - w[0]).abs()).collect();
    for w in d.windows(2) {
        assert!(w[1] < w[0], "differences {d:?}");
    }
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let solved = summary["solve"]["energy"].as_f64().unwrap();
    let estimate = summary["solve"]["error_estimate"].as_f64().unwrap();
    let finest = energy[3];
    assert!(
        (solved - finest).abs() <= estimate,
        "solve {solved} +- {estimate:e}, finest rung {finest}"
    );
    assert_eq!(rows[3][col("state_file")], "states/finest.csv");
    // The energy of the written file by its own quadrature weights (columns as `solve`
    // writes them: curvature in 1/R, weight in R, D/D0; R = D0 = 1 here).
    let (fh, frows) = read_csv(&out.join("states/finest.csv"));
    let fc = |n: &str| common::col(&fh, n);
    let e_file: f64 = frows
        .iter()
        .map(|r| {
            let k: f64 = r[fc("kappa")].parse().unwrap();
            let w: f64 = r[fc("weight")].parse().unwrap();
            let dd: f64 = r[fc("D")].parse().unwrap();
            0.5 * w * dd * k * k
        })
        .sum::<f64>()
        / std::f64::consts::PI;
    assert!(
        (e_file - finest).abs() < 1e-9 * finest,
        "file {e_file}, row {finest}"
    );
}
