//! Resolution choice and error estimates.
//!
//! The scheme (Gauss collocation + fourth-order Magnus + two-point Gauss quadrature) converges
//! like `h⁴` in the energy and in `λ` (measured in `tests/convergence.rs`). Every
//! [`solve_with_accuracy`] solves at two resolutions and reports an error estimate from
//! their difference (`|X_fine − X_coarse|/(2⁴ − 1)` for a halving of `h`):
//!
//! * [`Accuracy::Fast`] and [`Accuracy::Default`]: `N` cells and `N/2` cells; the values are
//!   those at `N`, the estimate is that of their error.
//! * [`Accuracy::High`]: `N` and `2N` cells (`N` of `Default`), Richardson extrapolation
//!   `X* = X_2N + (X_2N − X_N)/15` of the energies and of `λ_min, λ_max`; the estimate is
//!   `|X_2N − X_N|/15` (the error of `X_2N`, a conservative bound for `X*`). Profiles are
//!   those of the `2N` solution.
//!
//! Every rule that turns a level and a scene into a number of cells, whatever it is used
//! for (solve, tracing, reporting pair, buckling loads, enclosed levels), is in `cells`
//! with the resolution table it reads.

mod cells;

use crate::model::{Phase, SurfaceModel};
use crate::solve::{solve, EnergyReport, Equilibrium, SolveOptions};
use crate::start::StartShape;
use crate::stiffness::Stiffness;
use crate::SolverError;

/// Accuracy level (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Accuracy {
    /// Coarse and quick.
    Fast,
    /// Meets energy relative error ≤ 1e-6 and `max|λ − λ_exact| ≤ 1e-4 max|λ_exact|` for
    /// the homogeneous branches η = 1..4 (measured in `tests/convergence.rs`).
    Default,
    /// `Default` and twice its resolution, Richardson-extrapolated.
    High,
}

impl std::str::FromStr for Accuracy {
    type Err = SolverError;
    fn from_str(s: &str) -> Result<Self, SolverError> {
        match s.to_ascii_lowercase().as_str() {
            "fast" => Ok(Accuracy::Fast),
            "default" => Ok(Accuracy::Default),
            "high" => Ok(Accuracy::High),
            _ => Err(SolverError::InvalidInput(format!(
                "unknown accuracy level '{s}' (expected fast, default or high)"
            ))),
        }
    }
}

pub use cells::*;

/// Order `p` of the scheme's discretisation error in the cell length `h` (energies and
/// `λ`; see the module docs): halving `h` divides the error by `2^p = 16`.
pub const ORDER: i32 = 4;

/// Richardson extrapolation of a quantity computed with cells of length `h` (`fine`) and
/// `2h` (`coarse`) by a scheme of order [`ORDER`]: `X* = X_h + (X_h − X_2h)/(2⁴ − 1)`.
pub fn richardson(fine: f64, coarse: f64) -> f64 {
    fine + (fine - coarse) / 15.0
}

/// Error estimate of the finer of two values at `h` and `2h` (order [`ORDER`]):
/// `|X_h − X_2h|/(2⁴ − 1)` (also a conservative bound for [`richardson`]'s value).
pub fn richardson_error(fine: f64, coarse: f64) -> f64 {
    (fine - coarse).abs() / 15.0
}

/// What a ladder of resolutions says of each of its rungs (cells doubling from one to the
/// next): the Richardson error estimate against the rung below, the distance to the finest
/// rung's value, the distance to an exact value when there is one, and the observed order
/// from three consecutive rungs, `log2(|X_{N/2} − X_N| / |X_N − X_{2N}|)` (finite values only).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RungErrors {
    /// [`richardson_error`] against the rung below (none for the coarsest).
    pub estimate: Option<f64>,
    /// `|X − X_finest|` (none for the finest).
    pub vs_finest: Option<f64>,
    /// `|X − X_exact|`.
    pub vs_exact: Option<f64>,
    /// Observed order (none for the coarsest and the finest rung).
    pub order: Option<f64>,
}

/// [`RungErrors`] of every rung of `values` (coarsest first, the cells doubling each time).
pub fn rung_errors(values: &[f64], exact: Option<f64>) -> Vec<RungErrors> {
    let n = values.len();
    let finest = values.last().copied().unwrap_or(f64::NAN);
    (0..n)
        .map(|i| {
            let x = values[i];
            RungErrors {
                estimate: (i > 0).then(|| richardson_error(x, values[i - 1])),
                vs_finest: (i + 1 < n).then(|| (x - finest).abs()),
                vs_exact: exact.map(|e| (x - e).abs()),
                order: (i > 0 && i + 1 < n)
                    .then(|| ((values[i - 1] - x).abs() / (x - values[i + 1]).abs()).log2())
                    .filter(|o| o.is_finite()),
            }
        })
        .collect()
}

/// How [`ladder_estimate`] treats a ladder that shows no convergence (an observed order
/// below 1: the last difference is more than half the one before).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SlowLadder {
    /// The order is taken as 1: the error of the finest level is its last difference.
    FirstOrder,
    /// The error of the finest level is the sum of both differences (the surface diagram's
    /// ladder, `rodloop_diagram`'s `estimate` module).
    SumOfDifferences,
}

/// The rule of [`ladder_estimate`]: the largest order trusted, the size below which the
/// last difference counts as converged, and what a ladder without convergence gets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LadderRule {
    /// Cap of the observed order (the scheme's [`ORDER`], or less where the convergence is
    /// irregular: the enclosed model's lifted-off states).
    pub max_order: f64,
    /// A last difference at most this large is converged: the order is taken as
    /// `max_order` (0: only an exact tie; the surface ladder passes its round-off level).
    pub negligible: f64,
    /// An observed order below 1.
    pub slow: SlowLadder,
}

/// Error estimate of the finest of three levels `E_{4h}, E_{2h}, E_h` (e.g. `N/4, N/2, N`
/// cells, or `N/2, N, 2N`) from their observed order: with the differences
/// `d₁ = |E_{2h} − E_{4h}|`, `d₂ = |E_h − E_{2h}|`, the order `p = log₂(d₁/d₂)` capped at
/// `rule.max_order` (and `max_order` where `d₂ ≤ rule.negligible`), the error of `E_h` is
/// `d₂/(2^p − 1)`, the tail of a geometric sequence (exact on `E + C h^p`). An order below 1
/// (no sign of convergence) follows `rule.slow`. Returns `(estimate, p)` (`p = 0` for
/// [`SlowLadder::SumOfDifferences`]).
///
/// The enclosed model's levels ([`three_level_estimate`]) and the surface diagram's ladder
/// around a traced row both use it.
pub fn ladder_estimate(levels: [f64; 3], rule: LadderRule) -> (f64, f64) {
    let (d1, d2) = ((levels[1] - levels[0]).abs(), (levels[2] - levels[1]).abs());
    let order = if d2 > rule.negligible {
        (d1 / d2).log2().min(rule.max_order)
    } else {
        rule.max_order
    };
    let order = if order >= 1.0 {
        order
    } else {
        match rule.slow {
            SlowLadder::FirstOrder => 1.0,
            SlowLadder::SumOfDifferences => return (d1 + d2, 0.0),
        }
    };
    (d2 / (2f64.powf(order) - 1.0), order)
}

/// Error estimate of the finest of three energies at `N/4, N/2, N` cells:
/// [`ladder_estimate`] with the order clamped to `[1, max_order]`. Use `max_order = 4` for a
/// fully attached enclosed state (fourth order, measured against the exact layer) and
/// [`crate::enclosed::LIFTED_OFF_MAX_ORDER`] for a lifted-off one. Returns `(estimate, p)`.
pub fn three_level_estimate(
    e_quarter: f64,
    e_half: f64,
    e_full: f64,
    max_order: f64,
) -> (f64, f64) {
    ladder_estimate(
        [e_quarter, e_half, e_full],
        LadderRule {
            max_order,
            negligible: 0.0,
            slow: SlowLadder::FirstOrder,
        },
    )
}

/// Result of [`solve_with_accuracy`].
#[derive(Clone, Debug)]
pub struct AccurateEquilibrium {
    /// The finest solution (profiles, forces, stability come from it).
    pub equilibrium: Equilibrium,
    /// The companion solution used for the error estimate.
    pub companion: Equilibrium,
    /// Energies (extrapolated for `High`), `E R/(π D0)`.
    pub energy: EnergyReport,
    /// Estimated absolute error of `energy.total`.
    pub energy_error: f64,
    /// `(λ_min, λ_max)` (extrapolated for `High`).
    pub lambda_range: (f64, f64),
    /// Estimated absolute error of `λ_min, λ_max` (the larger of the two).
    pub lambda_error: f64,
    /// Accuracy level used.
    pub accuracy: Accuracy,
}

/// Solve at exactly `cells` cells (on the mesh [`crate::MeshMap::for_profile`] chooses) from
/// `start`, or from `initial` resampled when given. For a uniform rod the phase condition
/// comes from `start`, so that solutions at different resolutions share their arclength
/// origin.
pub fn solve_cells(
    radius: f64,
    lbar: f64,
    cells: usize,
    stiffness: &Stiffness,
    start: &StartShape,
    initial: Option<&Equilibrium>,
    opts: &SolveOptions,
) -> Result<Equilibrium, SolverError> {
    let mut model = SurfaceModel::new(radius, lbar, cells, stiffness)?;
    let reference = start.gauss_values(&model)?;
    if stiffness.is_uniform() {
        // The same continuous phase condition at every resolution keeps the arclength origin
        // of the two solutions consistent.
        model = model.with_phase(Phase::from_gauss_values(&reference, cells)?)?;
    }
    let guess = match initial {
        Some(eq) => eq.resample(cells)?,
        None => reference,
    };
    solve(&model, &guess, opts)
}

/// Solve at the resolution of `accuracy` from `start` and estimate the discretisation error
/// (see the module docs).
pub fn solve_with_accuracy(
    radius: f64,
    lbar: f64,
    stiffness: &Stiffness,
    start: &StartShape,
    accuracy: Accuracy,
    opts: &SolveOptions,
) -> Result<AccurateEquilibrium, SolverError> {
    let periods = start.periods(lbar)?;
    let n = accuracy.cells(periods, stiffness);
    let main = solve_cells(radius, lbar, n, stiffness, start, None, opts)?;
    finish_with_accuracy(main, radius, stiffness, start, accuracy, opts)
}

/// Complete a solve at the main resolution of `accuracy` (`main`, at
/// [`Accuracy::cells`] cells) with its companion solve and the error estimate (see the
/// module docs); the companion starts from `main` resampled.
pub fn finish_with_accuracy(
    main: Equilibrium,
    radius: f64,
    stiffness: &Stiffness,
    start: &StartShape,
    accuracy: Accuracy,
    opts: &SolveOptions,
) -> Result<AccurateEquilibrium, SolverError> {
    let n = main.model().cells();
    let lbar = main.lbar();
    // The companion at half the cells (or twice, for High). If the coarse companion does not
    // converge (a sharp profile at few cells), a fine one at 2N is solved instead: the values
    // are then those at 2N, with the estimate |X_2N − X_N|/15 of their error.
    let (fine, coarse) = match accuracy {
        Accuracy::High => {
            let fine = solve_cells(radius, lbar, 2 * n, stiffness, start, Some(&main), opts)?;
            (fine, main)
        }
        _ => match solve_cells(radius, lbar, n / 2, stiffness, start, Some(&main), opts) {
            Ok(coarse) => (main, coarse),
            Err(_) => {
                let fine = solve_cells(radius, lbar, 2 * n, stiffness, start, Some(&main), opts)?;
                (fine, main)
            }
        },
    };
    let (ef, ec) = (fine.energy(), coarse.energy());
    let (lf, lc) = (fine.lambda_range(), coarse.lambda_range());
    let energy_error = richardson_error(ef.total, ec.total);
    let lambda_error = richardson_error(lf.0, lc.0).max(richardson_error(lf.1, lc.1));
    let (energy, lambda_range) = if accuracy == Accuracy::High {
        let rich = richardson;
        (
            EnergyReport {
                total: rich(ef.total, ec.total),
                geodesic: rich(ef.geodesic, ec.geodesic),
                normal: rich(ef.normal, ec.normal),
            },
            (rich(lf.0, lc.0), rich(lf.1, lc.1)),
        )
    } else {
        (ef, lf)
    };
    Ok(AccurateEquilibrium {
        equilibrium: fine,
        companion: coarse,
        energy,
        energy_error,
        lambda_range,
        lambda_error,
        accuracy,
    })
}
