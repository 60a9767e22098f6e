//! Switching a phase curve onto another pair of states where its own pair stops being the
//! lowest one: past a fold of one of the states in the parameter (the state merges with a
//! saddle and vanishes), past a loss of stability (a lower state branches off), or past a
//! branch point.
//!
//! Just beyond the end of the curve the lowest stable state of each of the two branches is
//! searched at the curve's last length: energy minimisation ([`Globalization::Minimize`])
//! from the last state, from the last state pushed both ways along its softest constrained
//! mode (the direction in which it folds or loses stability), and from the exact loops of the
//! branch shifted by eighths of `1/(2η)` along the rod (as for the seeds,
//! [`super::lowest_placement`]); every start is solved on the curve's own models (mesh and
//! resolution), and the lowest index-0 state with the branch's `η` is kept. The Maxwell
//! point of the new pair is then found by the exchange locator on re-solved equilibria
//! ([`super::maxwell_point`]) and polished by Newton on the augmented system.

use nalgebra::DVector;
use rodloop_exact::eta_of_branch;
use rodloop_solver::{Equilibrium, Globalization, SolveOptions, SurfaceSolve};

use super::rows::fixed;
use super::seed::maxwell_point;
use super::{Exchange, Tracked};
use crate::maxwell::{join, MaxwellProblem, INDEX_TOL};
use crate::placements::{classify, shift_of, solve_shifted};

/// Size of the push along the softest mode relative to the state, in the metric
/// `‖δκ‖_W² = δκᵀWδκ` of the modes (quadrature weights `W`).
const PUSH: f64 = 0.05;

/// Step in the continuation variable (`ln θ` for `d1`) past the end of a curve at which the
/// new pair is searched.
pub(super) const SWITCH_STEP: f64 = 0.01;

/// A state of the new pair: `(energy, equilibrium, how it was found)`.
type Candidate = (f64, Equilibrium, String);

/// Lowest stable state of branch `eta` on `model` (its length and parameter) near the state
/// `z_last` of the curve (see the module docs).
fn lowest_state<M: SurfaceSolve>(
    model: &M,
    z_last: &[f64],
    eta: u32,
    opts: &SolveOptions,
) -> Result<Candidate, String> {
    let minimize = SolveOptions {
        globalization: Globalization::Minimize,
        ..opts.clone()
    };
    let n = model.dim() - model.n_constraints();
    let mut best: Option<Candidate> = None;
    let mut tried = Vec::new();
    let mut consider = |res: Result<Equilibrium, String>, how: String| match res {
        Ok(eq) => {
            let (ok_eta, idx, e) = classify(&eq, eta, INDEX_TOL);
            if ok_eta && idx == 0 {
                if best.as_ref().is_none_or(|b| e < b.0) {
                    best = Some((e, eq, how));
                }
            } else {
                tried.push(format!(
                    "{how}: E = {e:.8}, index {idx}, eta recognised {ok_eta}"
                ));
            }
        }
        Err(e) => tried.push(format!("{how}: {e}")),
    };
    // From the last state, then pushed along its softest mode.
    let relaxed = model
        .solve(&z_last[..n], &minimize)
        .map_err(|e| e.to_string());
    if let Ok(eq) = &relaxed {
        if let Ok((_, modes)) = eq.constrained_modes() {
            if let Some(v) = modes.first() {
                let kappa = eq.kappa();
                // ‖κ‖_W: the push is PUSH of the state in the mode's metric.
                let norm = kappa
                    .iter()
                    .enumerate()
                    .map(|(a, k)| model.cell_weight(a / 2) * k * k)
                    .sum::<f64>()
                    .sqrt();
                for sign in [1.0, -1.0] {
                    let start: Vec<f64> = kappa
                        .iter()
                        .zip(v.iter())
                        .map(|(k, d)| k + sign * PUSH * norm * d)
                        .collect();
                    consider(
                        model.solve(&start, &minimize).map_err(|e| e.to_string()),
                        format!("last state pushed {sign:+} along its softest mode"),
                    );
                }
            }
        }
    }
    consider(relaxed, "last state relaxed".into());
    // Shifted exact loops.
    for k in 0..8 {
        consider(
            solve_shifted(model, eta, k, opts).map_err(|e| e.to_string()),
            format!("exact loop shifted by {:.4}", shift_of(eta, k)),
        );
    }
    best.ok_or_else(|| {
        format!(
            "no stable state of eta = {eta} at L̄ = {:.6} ({})",
            model.lbar(),
            tried.join("; ")
        )
    })
}

/// The Maxwell point of the lowest pair of states at `p` near the last point `last` of a
/// curve (see the module docs), with a description of the two states for people and their
/// energies at the length of `last`.
pub(super) fn switch_pair<M: SurfaceSolve>(
    problem: &MaxwellProblem<M>,
    ex: Exchange,
    last: &Tracked,
    p: f64,
    opts: &SolveOptions,
) -> Result<(Tracked, String, (f64, f64)), String> {
    let (za, zb, lbar) = problem
        .split(last.x.as_slice())
        .map_err(|e| e.to_string())?;
    let (ma, mb) = problem.models_at(lbar, p).map_err(|e| e.to_string())?;
    let (eta_a, eta_b) = (eta_of_branch(ex.from_branch), eta_of_branch(ex.to_branch));
    let (ea, a, how_a) = lowest_state(&ma, za, eta_a, opts)?;
    let (eb, b, how_b) = lowest_state(&mb, zb, eta_b, opts)?;
    let (a, b, _slope) = maxwell_point(&a, &b, opts).map_err(|e| e.to_string())?;
    let x = join(&a.state(), &b.state(), a.lbar());
    let x = fixed(problem, &x, p)?;
    let index = problem.indices(&x, p).map_err(|e| e.to_string())?;
    let why = format!(
        "at L̄ = {lbar:.6}: {} E = {ea:.8} ({how_a}), {} E = {eb:.8} ({how_b})",
        super::rows::branch_word(ex.from_branch),
        super::rows::branch_word(ex.to_branch)
    );
    Ok((
        Tracked {
            x,
            p,
            index,
            arm: last.arm + 1,
        },
        why,
        (ea, eb),
    ))
}

/// `L̄` of a Maxwell point.
fn lbar_of(t: &Tracked) -> f64 {
    t.x[t.x.len() - 1]
}

/// `L̄` of the polyline `curve` (sorted by `p`) at `p`, linearly interpolated; `None` outside.
fn interpolate(curve: &[&Tracked], p: f64) -> Option<(f64, usize)> {
    let k = curve.windows(2).position(|w| w[0].p <= p && p <= w[1].p)?;
    let (a, b) = (curve[k], curve[k + 1]);
    let w = if b.p > a.p {
        (p - a.p) / (b.p - a.p)
    } else {
        0.0
    };
    let near = if w < 0.5 { k } else { k + 1 };
    Some((lbar_of(a) + w * (lbar_of(b) - lbar_of(a)), near))
}

/// The triple point where the Maxwell curve `new` of the new pair (traced back from the
/// switch) crosses the curve `old` of the previous pair in the `(p, L̄)` plane: there the three
/// states (the state common to both pairs and the two that replace each other) have the same
/// energy at the same length, and beyond it the new pair is the lower one. Located by the
/// secant method on `L̄_new(p) − L̄_old(p)`, both Maxwell points solved by Newton on the
/// augmented system at each trial `p`. `None` when the curves do not cross.
pub(super) fn triple_point<M: SurfaceSolve>(
    problem: &MaxwellProblem<M>,
    old: &[Tracked],
    new: &[Tracked],
) -> Option<(Tracked, Tracked)> {
    let mut sorted: Vec<&Tracked> = old.iter().collect();
    sorted.sort_by(|a, b| a.p.total_cmp(&b.p));
    // The first sign change of L̄_new − L̄_old along `new` (from the switch backwards).
    let gaps: Vec<(f64, f64, usize, usize)> = new
        .iter()
        .enumerate()
        .filter_map(|(i, t)| interpolate(&sorted, t.p).map(|(l, k)| (t.p, lbar_of(t) - l, i, k)))
        .collect();
    let w = gaps.windows(2).find(|w| w[0].1 * w[1].1 <= 0.0)?;
    let (mut x_old, mut x_new) = (sorted[w[0].3].x.clone(), new[w[0].2].x.clone());
    let gap_at = |p: f64, xo: &mut DVector<f64>, xn: &mut DVector<f64>| -> Option<f64> {
        *xo = fixed(problem, xo, p).ok()?;
        *xn = fixed(problem, xn, p).ok()?;
        Some(xn[xn.len() - 1] - xo[xo.len() - 1])
    };
    let (mut p0, mut g0) = (w[0].0, w[0].1);
    let (mut p1, mut g1) = (w[1].0, w[1].1);
    for _ in 0..30 {
        if (p1 - p0).abs() < 1e-13 || g1 == 0.0 {
            break;
        }
        let p2 = p1 - g1 * (p1 - p0) / (g1 - g0);
        let g2 = gap_at(p2, &mut x_old, &mut x_new)?;
        (p0, g0, p1, g1) = (p1, g1, p2, g2);
    }
    if g1.abs() > 1e-10 {
        return None;
    }
    let state = |x: DVector<f64>, arm: usize| -> Option<Tracked> {
        Some(Tracked {
            index: problem.indices(&x, p1).ok()?,
            x,
            p: p1,
            arm,
        })
    };
    Some((state(x_old, old[0].arm)?, state(x_new, new[0].arm)?))
}
