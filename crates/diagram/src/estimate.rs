//! Error estimates of a traced state's energy from a ladder of three resolutions.
//!
//! The scheme converges like `h⁴` with an even expansion, `E(h) = E + a h⁴ + b h⁶ + …`
//! (`rodloop_solver::accuracy`). A traced row holds `R_N = E_N + (E_N − E_{N/2})/15`, the
//! Richardson value of its tracing resolution `N` and of `N/2`. The two-level estimate
//! `|E_N − E_{N/2}|/15` is the error of `E_N` only once the order has settled at `N/2`; on a
//! soft segment (`D1 ≪ D0`, a profile whose transitions take several cells) the pair is
//! often still pre-asymptotic, and the two energies can agree by accident while both are
//! off (branch 1 of the paper's `D1/D0 = 0.1` rod at `L̄ = 1.3`, 80 cells: the differences
//! of the energies at `N/4, N/2, N, 2N, 4N` shrink by 7, then 14; the row lies 3.9e-7 from a
//! re-solve at 16 `N`, its two-level estimate is 3.7e-7).
//!
//! [`ladder_error`] adds the state at `2N`. With the differences `d₁ = E_N − E_{N/2}`,
//! `d₂ = E_{2N} − E_N` and the observed ratio `ρ = |d₁/d₂|` (16 for the scheme's fourth
//! order; the observed order is `log₂ ρ`), a geometric error sequence has the error
//! `|d₂|/(ρ − 1)` at `2N` (the solver's [`rodloop_solver::accuracy::ladder_estimate`], the
//! same routine as the enclosed model's three-level estimate). The ratio is taken as at most 16 (a ladder never converges
//! faster than the scheme's order; a faster observed ratio is a cancellation, not
//! convergence) and, where it is below 2 (no sign of convergence), the error of `E_{2N}` is
//! taken as `|d₁| + |d₂|`; it enters with a safety factor of 2 (an error sequence is
//! geometric only asymptotically). Then, by the triangle inequality,
//!
//! ```text
//! |R_N − E| ≤ |R_N − E_{2N}| + |E_{2N} − E|,
//! ```
//!
//! and the estimate is the larger of that bound and the two-level `|d₁|/15` (which remains
//! the tolerance a state file at `N` cells is held to). The test below checks the estimate
//! against independent re-solves at 16 `N` on rows of a paper scene and of a random one.

use rodloop_solver::accuracy::{ladder_estimate, LadderRule, SlowLadder, ORDER};

/// Error estimate of the Richardson value `R_N` of `fine` (`E_N`) and `coarse` (`E_{N/2}`),
/// from the ladder with `finer` (`E_{2N}`, when its solve succeeded; see the module docs).
/// Without `finer` it is the two-level `|E_N − E_{N/2}|/15`.
pub(crate) fn ladder_error(fine: f64, coarse: f64, finer: Option<f64>) -> f64 {
    let two_level = rodloop_solver::richardson_error(fine, coarse);
    let Some(finer) = finer else {
        return two_level;
    };
    let rounding = 8.0 * f64::EPSILON * fine.abs().max(1.0);
    // The error of `E_{2N}` from the observed ratio of the ladder `N/2, N, 2N`.
    let (finer_error, _) = ladder_estimate(
        [coarse, fine, finer],
        LadderRule {
            max_order: f64::from(ORDER),
            negligible: rounding,
            slow: SlowLadder::SumOfDifferences,
        },
    );
    let rich = rodloop_solver::richardson(fine, coarse);
    two_level.max((rich - finer).abs() + 2.0 * finer_error) + rounding
}

#[cfg(test)]
mod tests {
    use super::ladder_error;

    /// `R_N` of the ladder `E(h)` at `h = 1/N` for `N/2, N, 2N`, its true error and the
    /// estimate.
    fn case(e: impl Fn(f64) -> f64, n: f64) -> (f64, f64, f64) {
        let (ec, ef, eff) = (e(2.0 / n), e(1.0 / n), e(0.5 / n));
        let rich = rodloop_solver::richardson(ef, ec);
        (rich, (rich - e(0.0)).abs(), ladder_error(ef, ec, Some(eff)))
    }

    /// Synthetic ladders with known limits: the asymptotic `h⁴ + h⁶` expansion, a
    /// pre-asymptotic second-order one, and one whose `N/2` and `N` values agree by accident
    /// (an error that changes sign between them). The estimate bounds the true error of the
    /// Richardson value in each, where the two-level estimate fails the last two.
    #[test]
    fn ladder_bounds_the_error_of_synthetic_sequences() {
        let asymptotic = |h: f64| 1.0 + 3.0 * h.powi(4) - 40.0 * h.powi(6);
        let second = |h: f64| 1.0 + 0.5 * h.powi(2);
        // Equal values at h = 1/40 and 2/40: 16 h⁴ − 32 k h⁵ = h⁴ − k h⁵ for k = 15/(31 h).
        let crossing = |h: f64| 1.0 + 1e3 * (h.powi(4) - 15.0 / 31.0 * 40.0 * h.powi(5));
        for n in [40.0, 80.0] {
            for (name, f) in [
                ("asymptotic", &asymptotic as &dyn Fn(f64) -> f64),
                ("second order", &second),
                ("crossing", &crossing),
            ] {
                let (_, err, est) = case(f, n);
                assert!(
                    err <= est,
                    "{name}, N = {n}: error {err:e} above estimate {est:e}"
                );
            }
        }
        // The two-level estimate is short on the last two (so the ladder is what bounds them).
        for f in [&second as &dyn Fn(f64) -> f64, &crossing] {
            let n = 40.0;
            let (_, err, _) = case(f, n);
            let two = rodloop_solver::richardson_error(f(1.0 / n), f(2.0 / n));
            assert!(two < err, "two-level {two:e} vs error {err:e}");
        }
        // Without the third level the estimate is the two-level one.
        assert_eq!(
            ladder_error(1.1, 1.4, None),
            rodloop_solver::richardson_error(1.1, 1.4)
        );
    }

    use crate::families::compute_families;
    use crate::refine::resolve;
    use crate::DiagramOptions;
    use rodloop_solver::Stiffness;

    /// Every `k`-th row of each sheet of branch `eta` of the scene `stiffness` on
    /// `[lo, hi]`, and the rows' distance to an independent re-solve at 16 times the tracing
    /// resolution (Newton from the row's state resampled), against the row's estimate:
    /// `(L̄, |E_row − E_16N|, estimate)`.
    fn rows_against_accurate(
        stiffness: Stiffness,
        (lo, hi): (f64, f64),
        eta: u32,
        every: usize,
    ) -> Vec<(f64, f64, f64)> {
        let opts = DiagramOptions {
            stiffness,
            lbar_min: lo,
            lbar_max: hi,
            great_circles: false,
            ..DiagramOptions::default()
        };
        let fam = compute_families(&opts, eta, &mut |_| {}).unwrap();
        let mut out = Vec::new();
        for b in &fam.sheets {
            for k in (0..b.points.len()).step_by(every) {
                let Some(estimate) = crate::states::sheet_estimate(&b.points, k) else {
                    continue;
                };
                let eq = b.equilibrium_of(&opts, k).unwrap();
                let accurate = resolve(&opts, &eq, 16 * eq.model().cells())
                    .unwrap()
                    .energy()
                    .total;
                out.push((
                    b.points[k].value,
                    (b.points[k].energy - accurate).abs(),
                    estimate,
                ));
            }
        }
        out
    }

    /// Rows of the paper's `D1/D0 = 0.1` scene (branch 1 on `1.3 ≤ L̄ ≤ 1.5`, where the pair
    /// `N/2, N` is pre-asymptotic) and of a random profile lie within their estimates of a
    /// re-solve at 16 `N` (whose own error is below 1e-9 there).
    #[test]
    fn traced_rows_lie_within_their_estimates_of_accurate_resolves() {
        let paper = Stiffness::Tanh {
            d0: 1.0,
            d1: 0.1,
            s0: 0.3,
            s1: 0.8,
            gamma: 200.0,
        };
        // Drawn like the scenes of tests/random_scenes.rs.
        let random = Stiffness::Tanh {
            d0: 1.0,
            d1: 0.054,
            s0: 0.001,
            s1: 0.502,
            gamma: 297.0,
        };
        let mut bad = Vec::new();
        let mut checked = 0;
        for (name, st, range, eta) in [
            ("D1/D0 = 0.1", paper, (1.3, 1.5), 2),
            ("random profile", random, (1.6, 1.75), 2),
        ] {
            for (l, err, est) in rows_against_accurate(st, range, eta, 2) {
                checked += 1;
                if err > est {
                    bad.push(format!(
                        "{name} at L̄ = {l:.5}: |E_row − E_16N| = {err:.2e} > {est:.2e}"
                    ));
                }
            }
        }
        assert!(checked >= 8, "only {checked} rows checked");
        assert!(bad.is_empty(), "{}", bad.join("\n"));
    }
}
