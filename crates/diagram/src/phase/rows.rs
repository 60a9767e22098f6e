//! Rows of a phase curve: Maxwell points with their companion at another resolution (the
//! error estimate), and the rows at the requested `--at` values.

use nalgebra::DVector;
use rodloop_continuation::newton;
use rodloop_exact::eta_of_branch;
use rodloop_solver::{
    solve_from_state, Accuracy, Globalization, Param, SolveOptions, SurfaceSolve,
};

use super::{Exchange, PhaseRow, PhaseSettings, RowSource, RowStates, Tracked};
use crate::maxwell::MaxwellProblem;
use crate::reported::{half_resolution_estimate, verify_reported};
use crate::DiagramError;

/// Newton on the augmented system at fixed `p` from `x`.
pub(super) fn fixed<M: SurfaceSolve>(
    problem: &MaxwellProblem<M>,
    x: &DVector<f64>,
    p: f64,
) -> Result<DVector<f64>, String> {
    newton(problem, x, p, 1e-11, 30)
        .map(|(x, _)| x)
        .map_err(|e| e.to_string())
}

/// A Maxwell point at `p` with its companion, as a row.
pub(super) struct RowMaker<'a, M> {
    /// The Maxwell problem of the rows.
    pub(super) main: &'a MaxwellProblem<M>,
    ex: Exchange,
    accuracy: Accuracy,
    opts: &'a SolveOptions,
    /// The companion problem and its last state (warm start).
    companion: Option<(MaxwellProblem<M>, DVector<f64>)>,
}

impl<'a, M: SurfaceSolve> RowMaker<'a, M> {
    /// Rows of the Maxwell points of `main` for exchange `ex`, at the accuracy and with the
    /// solver settings of `s`.
    pub(super) fn new(main: &'a MaxwellProblem<M>, ex: Exchange, s: &'a PhaseSettings) -> Self {
        Self {
            main,
            ex,
            accuracy: s.accuracy,
            opts: &s.solve,
            companion: None,
        }
    }

    /// Forget the companion's warm start (after a switch onto another pair of states).
    pub(super) fn reset(&mut self) {
        self.companion = None;
    }

    pub(super) fn row(&mut self, t: &Tracked, source: RowSource) -> Result<PhaseRow, String> {
        let (x, p, index) = (&t.x, t.p, t.index);
        let pb = self.main;
        let (slope, _, _) = pb.crossing_slope(x, p).map_err(|e| e.to_string())?;
        let (from_branch, to_branch) = if slope > 0.0 {
            (self.ex.from_branch, self.ex.to_branch)
        } else {
            (self.ex.to_branch, self.ex.from_branch)
        };
        let (ea, _) = pb.energies(x, p).map_err(|e| e.to_string())?;
        let lbar = x[x.len() - 1];
        // The companion from its last state, or resampled from x when that fails.
        let mut comp = None;
        if let Some((cp, cx)) = &self.companion {
            if let Ok(y) = fixed(cp, cx, p) {
                comp = Some((cp.clone(), y));
            }
        }
        let mut finer = false;
        if comp.is_none() {
            let (ma, mb) = pb.models();
            let mut why = Vec::new();
            // The companion of the accuracy level; if it does not converge (a sharp profile
            // at few cells), twice the main resolution, as `finish_with_accuracy` does.
            let mut pairs = vec![(
                rodloop_solver::accuracy::companion_cells(self.accuracy, ma.cells()),
                rodloop_solver::accuracy::companion_cells(self.accuracy, mb.cells()),
            )];
            if self.accuracy != Accuracy::High {
                pairs.push((2 * ma.cells(), 2 * mb.cells()));
            }
            for (k, (ca, cb)) in pairs.into_iter().enumerate() {
                let attempt = pb
                    .resampled(x, p, ca, cb, self.opts)
                    .map_err(|e| e.to_string())
                    .and_then(|(cp, cx)| fixed(&cp, &cx, p).map(|y| (cp, y)));
                match attempt {
                    Ok(c) => {
                        finer = k == 1;
                        comp = Some(c);
                        break;
                    }
                    Err(e) => why.push(format!("{ca}+{cb} cells: {e}")),
                }
            }
            if comp.is_none() {
                return Err(format!("companion resolution: {}", why.join("; ")));
            }
        } else if let Some((cp, _)) = &comp {
            finer = cp.models().0.cells() > pb.models().0.cells();
        }
        let (cp, y) = comp.expect("set above");
        let lc = y[y.len() - 1];
        let (ec, _) = cp.energies(&y, p).map_err(|e| e.to_string())?;
        self.companion = Some((cp, y));
        let (lbar_cr, energy, est) = match self.accuracy {
            _ if finer && self.accuracy != Accuracy::High => {
                (lbar, ea, rodloop_solver::richardson_error(lc, lbar))
            }
            Accuracy::High => (
                rodloop_solver::richardson(lc, lbar),
                rodloop_solver::richardson(ec, ea),
                rodloop_solver::richardson_error(lc, lbar),
            ),
            _ => (lbar, ea, rodloop_solver::richardson_error(lbar, lc)),
        };
        // The written states: those of the finer resolution of the pair.
        let (cp, y) = self.companion.as_ref().expect("set above");
        let (energy_error, states) = if finer || self.accuracy == Accuracy::High {
            verified_pair((cp, y), (pb, x), p, energy, self.opts)
        } else {
            verified_pair((pb, x), (cp, y), p, energy, self.opts)
        };
        Ok(PhaseRow {
            value: pb.theta(p),
            lbar_cr,
            error_estimate: est,
            energy,
            from_branch,
            to_branch,
            index,
            arm: t.arm,
            slope,
            source,
            energy_error,
            states,
        })
    }
}

/// The two states of the Maxwell point `written` at `p` (those of the exchange's
/// `from_branch` and `to_branch`, at the finer resolution of the row's pair), each verified
/// as its file holds it against the row's `energy` ([`verify_reported`]), and the error
/// estimate of that energy as the energy of each state at its length: the largest over the
/// two of `|energy − E_N| + |E_N − E_M|/15`, `E_N` the state's energy and `E_M` that of the
/// same state at the pair's other, coarser resolution `M = N/2` (the Maxwell point `other`,
/// re-solved by Newton at the written state's `L̄`, which differs from its own by about the
/// estimate of `L̄_cr`; where that fails, the state resampled at half its resolution,
/// [`half_resolution_estimate`]). For the Richardson-extrapolated rows of `high` the first
/// term is the extrapolation's step. `(0, Unverified)` where a state cannot be re-solved or
/// fails a check.
fn verified_pair<M: SurfaceSolve>(
    written: (&MaxwellProblem<M>, &DVector<f64>),
    other: (&MaxwellProblem<M>, &DVector<f64>),
    p: f64,
    energy: f64,
    opts: &SolveOptions,
) -> (f64, RowStates) {
    let newton = SolveOptions {
        globalization: Globalization::Newton,
        ..opts.clone()
    };
    let pair = written
        .0
        .equilibria(written.1, p, opts)
        .map_err(|e| format!("the states cannot be re-solved: {e}"))
        .and_then(|(a, b)| {
            let coarse = other.0.equilibria(other.1, p, opts).ok();
            let mut estimates = Vec::new();
            for (k, eq) in [&a, &b].into_iter().enumerate() {
                let here = coarse.as_ref().and_then(|c| {
                    let o = if k == 0 { &c.0 } else { &c.1 };
                    o.model()
                        .with_lbar(eq.lbar())
                        .and_then(|m| solve_from_state(m, o.state(), &newton))
                        .ok()
                });
                let half = match here {
                    Some(o) => {
                        rodloop_solver::richardson_error(eq.energy().total, o.energy().total)
                    }
                    None => half_resolution_estimate(eq).map_err(|e| {
                        format!("no state at another resolution for its error estimate: {e}")
                    })?,
                };
                estimates.push((energy - eq.energy().total).abs() + half);
            }
            let error = estimates.iter().copied().fold(0.0, f64::max);
            let mut files = Vec::new();
            for (eq, est) in [&a, &b].into_iter().zip(estimates) {
                files.push(verify_reported(eq, energy, Some(est)).map_err(|e| e.to_string())?);
            }
            Ok((error, files))
        });
    match pair {
        Ok((error, files)) => (error, RowStates::Verified(files)),
        Err(why) => (0.0, RowStates::Unverified(why)),
    }
}

pub(super) fn branch_word(b: u32) -> String {
    format!("branch {b} (eta = {})", eta_of_branch(b))
}

/// Rows at the `--at` values inside the traced range of each arm of a curve (Newton on the
/// augmented system at exactly that `θ`, from the nearest traced state of the arm); notes
/// for the others.
pub(super) fn add_at_rows<M: SurfaceSolve>(
    s: &PhaseSettings,
    problem: &MaxwellProblem<M>,
    ex: Exchange,
    states: &[Tracked],
    rows: &mut Vec<PhaseRow>,
    notes: &mut Vec<String>,
) -> Result<(), DiagramError> {
    if s.at.is_empty() || states.is_empty() {
        return Ok(());
    }
    let arms = states.iter().map(|t| t.arm).max().unwrap_or(0);
    for &v in &s.at {
        if s.param == Param::D1 && v == 1.0 {
            notes.push("--at 1: d1 = 1 is the uniform rod; see the limit row".into());
            continue;
        }
        let p = problem.p_of(v);
        let mut found = false;
        for arm in 0..=arms {
            let on: Vec<&Tracked> = states.iter().filter(|t| t.arm == arm).collect();
            let (lo, hi) = on
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), t| {
                    (a.min(t.p), b.max(t.p))
                });
            if p < lo - 1e-12 || p > hi + 1e-12 {
                continue;
            }
            found = true;
            let near = on
                .iter()
                .min_by(|a, b| (a.p - p).abs().total_cmp(&(b.p - p).abs()))
                .expect("non-empty");
            let mut maker = RowMaker::new(problem, ex, s);
            let row = fixed(problem, &near.x, p).and_then(|y| {
                let idx = problem.indices(&y, p).map_err(|e| e.to_string())?;
                maker.row(
                    &Tracked {
                        x: y,
                        p,
                        index: idx,
                        arm,
                    },
                    RowSource::Fixed,
                )
            });
            match row {
                Ok(r) => rows.push(PhaseRow { value: v, ..r }),
                Err(e) => notes.push(format!(
                    "--at {v}: Newton at fixed {} failed ({e})",
                    s.param
                )),
            }
        }
        if !found {
            let (lo, hi) = states
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), t| {
                    (a.min(t.p), b.max(t.p))
                });
            notes.push(format!(
                "--at {v}: outside the traced range {} = {:.6}..{:.6} of this curve",
                s.param,
                problem.theta(lo),
                problem.theta(hi)
            ));
        }
    }
    Ok(())
}
