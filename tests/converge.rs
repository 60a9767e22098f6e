//! `rodloop converge` end to end: the ladder shows fourth-order convergence to the exact
//! loop, and the printed estimates bound the true errors.

mod common;
use common::{bin, read_csv, tmp};

#[test]
fn converge_ladder_is_fourth_order_against_the_exact_loop() {
    let out = tmp("converge-ladder");
    let o = bin()
        .args([
            "converge", "--lbar", "1.3", "--branch", "2", "--levels", "4",
        ])
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (header, rows) = read_csv(&out.join("converge.csv"));
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
