//! What a finished `--param` sweep reports about its states: the stability label of every
//! traced state (the shared labeller over every family's segments) and every state verified
//! as its file holds it ([`verify_sweep`]).

use rodloop_continuation::exchange::{self, Ranked};
use rodloop_solver::{Globalization, SolveOptions, SurfaceSolve};

use super::{ParamSweep, SweepFamily, SweepSettings};

/// Tolerance of the sweep's energy comparisons: each state's energy is given half of it as
/// its error estimate in the labeller's tie rule.
const SWEEP_TIE: f64 = 1e-9;

/// Labels by the labeller ([`rodloop_continuation::exchange::label`]): at each traced
/// state, it and every traced segment (any family, any sheet, linearly interpolated between
/// consecutive points, index 0 where both ends have it) covering its value; the state
/// itself is preferred in ties (within [`SWEEP_TIE`]). Index > 0 unstable; index 0 stable
/// where no index-0 state lies lower, metastable otherwise.
pub(super) fn label(families: &mut [SweepFamily]) {
    // ((value, energy, index 0) at both ends) of every segment.
    type End = (f64, f64, bool);
    let segments: Vec<(End, End)> = families
        .iter()
        .flat_map(|f| {
            f.points
                .windows(2)
                .map(|w| {
                    (
                        (w[0].value, w[0].energy, w[0].index == 0),
                        (w[1].value, w[1].energy, w[1].index == 0),
                    )
                })
                .collect::<Vec<_>>()
        })
        .collect();
    let others = |v: f64| -> Vec<Ranked> {
        segments
            .iter()
            .filter_map(|&((a, ea, ia), (b, eb, ib))| {
                let (lo, hi) = (a.min(b), a.max(b));
                if v < lo || v > hi {
                    return None;
                }
                let energy = if hi > lo {
                    ea + (v - a) / (b - a) * (eb - ea)
                } else {
                    ea.min(eb)
                };
                Some(Ranked {
                    energy,
                    error: 0.5 * SWEEP_TIE,
                    index: usize::from(!(ia && ib)),
                    preferred: false,
                })
            })
            .collect()
    };
    for f in families.iter_mut() {
        for p in &mut f.points {
            let mut states = vec![Ranked {
                energy: p.energy,
                error: 0.5 * SWEEP_TIE,
                index: p.index,
                preferred: true,
            }];
            states.extend(others(p.value));
            p.label = exchange::label(&states)[0].into();
        }
    }
}

/// A traced state of a sweep as its file holds it: the error estimate of its energy
/// (`|E_N − E_{N/2}|/15`, the same state at half the resolution) and the file, verified
/// against its energy within [`crate::ESTIMATES`] times that estimate
/// ([`crate::reported::verify_reported`]).
pub type SweepState = Result<(f64, crate::StateFile), String>;

/// Every traced state of `sweep` verified as its file holds it (see [`SweepState`]), in
/// parallel on `threads` threads: `out[f][k]` for `sweep.families[f].points[k]` (`Err` with
/// why where a state cannot be re-solved or fails a check).
pub fn verify_sweep(s: &SweepSettings, sweep: &ParamSweep, threads: usize) -> Vec<Vec<SweepState>> {
    let jobs: Vec<(usize, usize)> = sweep
        .families
        .iter()
        .enumerate()
        .flat_map(|(i, f)| (0..f.points.len()).map(move |k| (i, k)))
        .collect();
    let newton = SolveOptions {
        globalization: Globalization::Newton,
        ..s.solve.clone()
    };
    let results = crate::parallel::run_parallel(
        threads.max(1),
        jobs.clone(),
        &mut |_| {},
        &mut |_| {},
        |(i, k), _| -> SweepState {
            let f = &sweep.families[i];
            let p = &f.points[k];
            let model = crate::surface_model(s.radius, s.lbar, f.cells, &s.stiffness)
                .and_then(|m| m.with_param(s.param, p.value))
                .map_err(|e| e.to_string())?;
            let eq = model
                .solve_from_state(p.state.clone(), &newton)
                .map_err(|e| format!("the state cannot be re-solved: {e}"))?;
            let est = crate::reported::half_resolution_estimate(&eq).map_err(|e| {
                format!("no state at half the resolution for its error estimate: {e}")
            })?;
            let file = crate::reported::verify_reported(&eq, p.energy, Some(est))
                .map_err(|e| e.to_string())?;
            Ok((est, file))
        },
    );
    let mut out: Vec<Vec<SweepState>> = sweep
        .families
        .iter()
        .map(|f| Vec::with_capacity(f.points.len()))
        .collect();
    for ((i, _), r) in jobs.into_iter().zip(results) {
        out[i].push(r);
    }
    out
}
