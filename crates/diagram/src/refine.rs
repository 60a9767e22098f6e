//! Re-solving a traced branch at the reporting resolution, with Richardson extrapolation.
//!
//! "Trace coarsely and refine only where a number is reported": a critical length is
//! located on equilibria re-solved at two resolutions `(N_f, N_c = N_f/2)` of the accuracy
//! level (below), started from the traced state (resampled), and followed by Newton's method
//! as `L̄` moves. The scheme converges like `h⁴` with an even error expansion, so
//! `X* = X_f + (X_f − X_c)/15` removes the leading term for energies and slopes alike.
//!
//! | level | `N_f` | `N_c` |
//! |---|---|---|
//! | fast | `Accuracy::Fast.cells(η)` = `16 (η + 1)` | `N_f/2` |
//! | default | `Accuracy::Default.cells(η)` = `40 (η + 1)` | `N_f/2` |
//! | high | `2 · Accuracy::Default.cells(η)` | `Accuracy::Default.cells(η)` |
//!
//! (plus what the stiffness profile needs, see [`rodloop_solver::Accuracy::cells`]).

use rodloop_solver::{solve, solve_from_state, Equilibrium, SolverError};

use crate::states::{energy_slope, model_with_phase, newton_options};
use crate::types::TracedBranch;
use crate::DiagramOptions;

/// `(N_f, N_c)`: the two reporting resolutions (cells) of branch `eta` (see the table above):
/// the accuracy policy's rule ([`rodloop_solver::accuracy::reporting_cells`]), which also
/// raises every count by the scene's bending factor.
pub fn reporting_cells(opts: &DiagramOptions, eta: u32) -> (usize, usize) {
    rodloop_solver::accuracy::reporting_cells(opts.accuracy, &opts.stiffness, eta)
}

/// Extrapolated values of a branch at one length.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Refined {
    /// Richardson-extrapolated energy `E R/(π D0)`.
    pub energy: f64,
    /// Richardson-extrapolated `dE/dL̄`.
    pub slope: f64,
}

/// A branch followed at the two reporting resolutions.
pub(crate) struct BranchRefiner {
    fine: Equilibrium,
    coarse: Equilibrium,
}

impl BranchRefiner {
    /// Start at `lbar` from the traced states of `traced`.
    pub fn new(
        opts: &DiagramOptions,
        traced: &TracedBranch,
        lbar: f64,
    ) -> Result<Self, SolverError> {
        let eq_t = traced.solve_at(opts, lbar)?;
        let (nf, nc) = reporting_cells(opts, traced.eta);
        let fine = resolve(opts, &eq_t, nf)?;
        let coarse = resolve(opts, &fine, nc)?;
        Ok(Self { fine, coarse })
    }

    /// Move both resolutions to `lbar` (Newton from the current states).
    pub fn move_to(&mut self, lbar: f64) -> Result<(), SolverError> {
        let opts = newton_options();
        self.fine = solve_from_state(self.fine.model().with_lbar(lbar)?, self.fine.state(), &opts)?;
        self.coarse = solve_from_state(
            self.coarse.model().with_lbar(lbar)?,
            self.coarse.state(),
            &opts,
        )?;
        Ok(())
    }

    /// Extrapolated energy and slope at the current length.
    pub fn values(&self) -> Result<Refined, SolverError> {
        let (ef, ec) = (self.fine.energy().total, self.coarse.energy().total);
        let sf = energy_slope(&self.fine)?;
        let sc = energy_slope(&self.coarse)?;
        let energy = rodloop_solver::richardson(ef, ec);
        let slope = rodloop_solver::richardson(sf, sc);
        Ok(Refined { energy, slope })
    }

    /// The fine equilibrium.
    pub fn fine(&self) -> &Equilibrium {
        &self.fine
    }

    /// Error estimate of the extrapolated energy from a third resolution `N_c/2`:
    /// with `E(h) = E + a h⁴ + b h⁶ + …`, the extrapolations `R_f` (from `N_f`, `N_c`) and
    /// `R_c` (from `N_c`, `N_c/2`) have errors `−3.2 b h⁶` and `−204.8 b h⁶`, so the error
    /// of `R_f` is `|R_f − R_c|/63`; reported with a safety factor of 2, and never below
    /// the rounding level. Falls back to `|E_f − E_c|/15` (the error of `E_f`, a bound for
    /// `R_f`) when `N_c/2` is too coarse (fewer than 4 cells per period of `κ_g`, or not
    /// resolving the stiffness profile) or its solve fails.
    pub fn error_estimate(&self, opts: &DiagramOptions, eta: u32) -> f64 {
        let (ef, ec) = (self.fine.energy().total, self.coarse.energy().total);
        let rounding = 8.0 * f64::EPSILON * ef.abs();
        let fallback = rodloop_solver::richardson_error(ef, ec) + rounding;
        let nq = self.coarse.model().cells() / 2;
        if nq < 4 * (eta.max(1) as usize + 1) || nq < crate::profile_cells(&opts.stiffness) {
            return fallback;
        }
        match resolve(opts, &self.coarse, nq) {
            Ok(q) => {
                let eq = q.energy().total;
                let rf = rodloop_solver::richardson(ef, ec);
                let rc = rodloop_solver::richardson(ec, eq);
                (2.0 * (rf - rc).abs() / 63.0).min(fallback) + rounding
            }
            Err(_) => fallback,
        }
    }
}

/// `eq` re-solved with `cells` cells: resampled profile as start and as phase reference.
pub(crate) fn resolve(
    opts: &DiagramOptions,
    eq: &Equilibrium,
    cells: usize,
) -> Result<Equilibrium, SolverError> {
    let kappa = eq.resample(cells)?;
    let model = model_with_phase(opts, eq.lbar(), cells, &kappa)?;
    solve(&model, &kappa, &newton_options())
}
