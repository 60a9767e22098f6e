//! Where a `--param` sweep starts its families: the parameter values it seeds at, the
//! distinct states of a branch there (energy minimisation from shifted exact loops), a seed's
//! energy with its half-resolution error estimate, and whether a seed lies on a family
//! already traced.

use rodloop_solver::{Globalization, Param, SolveOptions, SurfaceSolve};

use super::SAME_STATE;
use crate::placements::{classify, shift_of, solve_shifted};
use crate::states::INDEX_TOLERANCE;

/// The distinct stable states of branch `eta` on `model` from shifted exact loops, lowest
/// first.
pub(super) fn seeds<M: SurfaceSolve>(
    model: &M,
    eta: u32,
    opts: &SolveOptions,
) -> (Vec<(f64, Vec<f64>)>, Vec<String>) {
    let mut found: Vec<(f64, Vec<f64>)> = Vec::new();
    let mut why = Vec::new();
    for k in 0..8 {
        let shift = shift_of(eta, k);
        match solve_shifted(model, eta, k, opts) {
            Ok(eq) => match classify(&eq, eta, INDEX_TOLERANCE) {
                (true, _, e) => {
                    if !found.iter().any(|(f, _)| (f - e).abs() < SAME_STATE) {
                        found.push((e, eq.state()));
                    }
                }
                (false, _, e) => why.push(format!(
                    "shift {shift:.4}: converged onto another branch (E = {e:.8})"
                )),
            },
            Err(e) => why.push(format!("shift {shift:.4}: {e}")),
        }
    }
    found.sort_by(|a, b| a.0.total_cmp(&b.0));
    (found, why)
}

/// Energy of state `x` of `model` at parameter `value` with the error estimate of the
/// state at half the resolution (Newton from the resampled state).
pub(super) fn energy_with_estimate<M: SurfaceSolve>(
    model: &M,
    param: Param,
    x: &[f64],
    value: f64,
    opts: &SolveOptions,
) -> Result<(f64, f64), String> {
    let newton = SolveOptions {
        globalization: Globalization::Newton,
        ..opts.clone()
    };
    let m = model.with_param(param, value).map_err(|e| e.to_string())?;
    let eq = m
        .solve_from_state(x.to_vec(), &newton)
        .map_err(|e| e.to_string())?;
    let e = eq.energy().total;
    let nc = (model.cells() / 2).div_ceil(2) * 2;
    let coarse = model
        .with_cells(nc)
        .and_then(|m| m.with_param(param, value))
        .map_err(|e| e.to_string())?;
    let mut z = eq.resample(nc).map_err(|e| e.to_string())?;
    z.extend_from_slice(&eq.multiplier());
    let ec = coarse
        .solve_from_state(z, &newton)
        .map_err(|e| format!("companion at {nc} cells: {e}"))?
        .energy()
        .total;
    Ok((e, rodloop_solver::richardson_error(e, ec)))
}

/// Parameter values at which states are seeded: the scene's value first, then (for `d1`)
/// every decade strictly between it and the target, and the target.
pub(super) fn seed_values(param: Param, scene: f64, target: f64) -> Vec<f64> {
    let mut out = vec![scene];
    if param == Param::D1 {
        let (lo, hi) = (scene.min(target), scene.max(target));
        let mut k = hi.log10().ceil() as i32;
        while 10f64.powi(k) > lo {
            let v = 10f64.powi(k);
            if v < hi && v > lo {
                out.push(v);
            }
            k -= 1;
        }
        if target < scene {
            out[1..].sort_by(|a, b| b.total_cmp(a));
        } else {
            out[1..].sort_by(|a, b| a.total_cmp(b));
        }
    } else {
        out.push(0.5 * (scene + target));
    }
    out.push(target);
    out
}

/// Whether the state of energy `e` seeded at `v` lies on a traced family: Newton at `v` from
/// the nearer end of each traced step that spans `v` (the steps of a march are short in
/// arclength, so Newton from its end stays on the family) reaches the same energy (to
/// [`SAME_STATE`]).
pub(super) fn traced<M: SurfaceSolve>(
    model: &M,
    param: Param,
    known: &[Vec<(f64, Vec<f64>)>],
    v: f64,
    e: f64,
    opts: &SolveOptions,
) -> bool {
    let Ok(at_v) = model.with_param(param, v) else {
        return false;
    };
    let newton = SolveOptions {
        globalization: Globalization::Newton,
        ..opts.clone()
    };
    known.iter().any(|run| {
        run.windows(2).any(|w| {
            let (a, b) = (&w[0], &w[1]);
            // The ends of a march lie on the range's ends up to rounding (e^{ln θ}).
            let slack = 1e-12 * v.abs().max(1e-300);
            if v < a.0.min(b.0) - slack || v > a.0.max(b.0) + slack {
                return false;
            }
            let start = if (a.0 - v).abs() <= (b.0 - v).abs() {
                a
            } else {
                b
            };
            at_v.clone()
                .solve_from_state(start.1.clone(), &newton)
                .map(|eq| (eq.energy().total - e).abs() < SAME_STATE)
                .unwrap_or(false)
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::param_sweep::branches_at;

    #[test]
    fn seed_values_and_branches() {
        assert_eq!(seed_values(Param::D1, 0.5, 0.001).len(), 4);
        let v = seed_values(Param::D1, 0.5, 0.001);
        assert!((v[1] - 0.1).abs() < 1e-15 && (v[2] - 0.01).abs() < 1e-15 && v[3] == 0.001);
        assert_eq!(
            seed_values(Param::Gamma, 200.0, 20.0),
            vec![200.0, 110.0, 20.0]
        );
        // η − 1 < L̄ < η + 1: at 1.4 the figure-eight (η = 1, branch 2) and η = 2 (branch 1).
        assert_eq!(branches_at(1.4), vec![1, 2]);
        assert_eq!(branches_at(2.4), vec![1, 3]);
    }
}
