//! `accuracy::rung_errors` on a ladder with a known fourth-order error `X_N = X* + C/N⁴`:
//! the observed order is 4, the Richardson estimate equals the true error, and the distances
//! to the finest rung and to `X*` are the differences of the closed form.

use rodloop_solver::accuracy::rung_errors;

#[test]
fn fourth_order_ladder_gives_order_four_and_exact_estimates() {
    let (x_star, c) = (2.5, 3.0e3);
    let cells = [8.0_f64, 16.0, 32.0, 64.0, 128.0];
    let values: Vec<f64> = cells.iter().map(|n| x_star + c / n.powi(4)).collect();
    let errs = rung_errors(&values, Some(x_star));
    assert_eq!(errs.len(), cells.len());
    assert!(errs[0].estimate.is_none() && errs[0].order.is_none());
    assert!(errs[4].vs_finest.is_none() && errs[4].order.is_none());
    for (i, e) in errs.iter().enumerate() {
        let true_err = c / cells[i].powi(4);
        let vs_exact = e.vs_exact.expect("an exact value was given");
        assert!((vs_exact - true_err).abs() <= 1e-12 * true_err.max(1.0));
        if i > 0 {
            let est = e
                .estimate
                .expect("every rung above the coarsest has an estimate");
            assert!(
                (est - true_err).abs() <= 1e-9 * true_err,
                "rung {i}: {est} vs {true_err}"
            );
        }
        if i > 0 && i + 1 < cells.len() {
            let p = e.order.expect("inner rungs have an order");
            assert!((p - 4.0).abs() < 1e-6, "rung {i}: order {p}");
        }
        if i + 1 < cells.len() {
            let want = true_err - c / cells[4].powi(4);
            assert!((e.vs_finest.unwrap() - want).abs() <= 1e-12 * want.max(1.0));
        }
    }
}

#[test]
fn a_ladder_without_exact_value_or_with_equal_rungs_reports_no_such_numbers() {
    let errs = rung_errors(&[1.0, 1.0, 1.0], None);
    assert!(errs.iter().all(|e| e.vs_exact.is_none()));
    // 0/0: no finite order is reported.
    assert!(errs[1].order.is_none());
    assert_eq!(errs[1].estimate, Some(0.0));
}
