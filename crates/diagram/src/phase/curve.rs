//! One phase curve: seed an exchange of the uniform rod, follow it in the parameter (switching
//! onto the lowest pair of states wherever the followed pair ends), and extrapolate its limit
//! at the uniform rod.

use rodloop_solver::{Confinement, Param, SurfaceSolve};

use super::follow::follow;
use super::rows::{add_at_rows, fixed, RowMaker};
use super::seed::seed_exchange;
use super::switch::{switch_pair, triple_point, SWITCH_STEP};
use super::{
    CurveEnd, Exchange, PhaseCurve, PhaseRow, PhaseSettings, RowSource, Tracked, UniformCheck,
};
use crate::maxwell::{join, MaxwellProblem, LIMIT_OFFSETS};
use crate::DiagramError;

/// Most switches onto another pair of states along one curve.
const MAX_SWITCHES: usize = 8;

/// How far (in the continuation variable) the curve of a new pair is traced back from a
/// switch to look for its crossing with the previous curve.
const BACK_RANGE: f64 = 0.5;

/// A state of the search at a checkpoint counts as lower than the followed one when its
/// energy is below by more than this (relative; the energies of re-solved states carry noise
/// of about 1e-11).
const LOWER: f64 = 1e-8;

/// The decades `10^k` strictly between `p0` and `p_end` for `d1` (continued in `ln d1`), in
/// the order the curve meets them; none for the other parameters.
fn checkpoints<M: SurfaceSolve>(problem: &MaxwellProblem<M>, p0: f64, p_end: f64) -> Vec<f64> {
    if problem.param() != Param::D1 {
        return Vec::new();
    }
    let (lo, hi) = (p0.min(p_end), p0.max(p_end));
    let ln10 = std::f64::consts::LN_10;
    let mut out: Vec<f64> = ((lo / ln10).floor() as i32..=(hi / ln10).ceil() as i32)
        .map(|k| f64::from(k) * ln10)
        .filter(|&p| p > lo + SWITCH_STEP && p < hi - SWITCH_STEP)
        .collect();
    if p_end < p0 {
        out.reverse();
    }
    out
}

/// What a curve accumulates while it is traced.
#[derive(Default)]
struct Parts {
    rows: Vec<PhaseRow>,
    /// Every main-resolution Maxwell point computed (for the `--at` rows).
    states: Vec<Tracked>,
    ends: Vec<CurveEnd>,
    turns: Vec<String>,
    switches: Vec<String>,
    /// Parameter values at which no lower pair of states was found.
    checks: Vec<f64>,
    notes: Vec<String>,
    steps: usize,
}

impl Parts {
    /// A row of `t` (and `t` kept for the `--at` rows).
    fn push<M: SurfaceSolve>(
        &mut self,
        maker: &mut RowMaker<M>,
        t: &Tracked,
        source: RowSource,
        ex: Exchange,
    ) -> Result<(), DiagramError> {
        let row = maker.row(t, source).map_err(|e| crit(ex, e))?;
        self.rows.push(row);
        self.states.push(t.clone());
        Ok(())
    }

    /// Follow the curve from `start` towards `p_end` inside `range`; where it ends at a fold,
    /// a loss of stability or a branch point before `p_end`, switch onto the lowest pair of
    /// states just beyond ([`switch_pair`]) and go on. For `d1` the curve also stops at every
    /// decade on the way ([`checkpoints`]) to search for a lower pair of states at its length
    /// (a state of another family can become the lowest without any event on the followed
    /// pair); if one is found, the curve switches there.
    fn sweep<M: SurfaceSolve>(
        &mut self,
        s: &PhaseSettings,
        maker: &mut RowMaker<M>,
        start: &Tracked,
        p_end: f64,
        range: (f64, f64),
        ex: Exchange,
    ) -> Result<(), DiagramError> {
        let problem = maker.main;
        let name = problem.param();
        let mut start = start.clone();
        let mut stops = checkpoints(problem, start.p, p_end);
        stops.push(p_end);
        let mut next = 0;
        let mut switches = 0;
        while switches <= MAX_SWITCHES {
            let target = stops[next];
            // The leg's range ends at its target.
            let leg_range = if target < start.p {
                (range.0.max(target), range.1)
            } else {
                (range.0, range.1.min(target))
            };
            let mut leg = follow(problem, &start, target, leg_range, ex, &mut self.turns)?;
            self.steps += leg.points.len();
            for t in &leg.points {
                self.push(maker, t, RowSource::Continuation, ex)?;
            }
            let last = leg.points.last().cloned().unwrap_or(start.clone());
            let p_stop = problem.p_of(leg.end.value);
            let old = |start: &Tracked| -> Vec<Tracked> {
                std::iter::once(start)
                    .chain(&leg.points)
                    .filter(|o| o.arm == last.arm)
                    .cloned()
                    .collect()
            };
            if leg.end.kind == "reached" && target != p_end && (last.p - target).abs() < 1e-9 {
                // A checkpoint: is there a lower pair at this length?
                next += 1;
                let lower = switch_pair(problem, ex, &last, last.p, &s.solve)
                    .ok()
                    .filter(|(_, _, (ea, eb))| {
                        problem.energies(&last.x, last.p).is_ok_and(|(ca, cb)| {
                            *ea < ca - LOWER * ca.abs() || *eb < cb - LOWER * cb.abs()
                        })
                    });
                match lower {
                    None => {
                        self.checks.push(problem.theta(last.p));
                        start = last;
                    }
                    Some((t, why, _)) => {
                        maker.reset();
                        let triple = self.connect(maker, &t, &old(&start), start.p, p_stop, ex)?;
                        self.switches.push(format!(
                            "at the check {name} = {:.6} a lower pair of states was found, {why}; L̄_cr = {:.8}; {triple}",
                            problem.theta(last.p),
                            t.x[t.x.len() - 1],
                        ));
                        self.push(maker, &t, RowSource::Switch, ex)?;
                        switches += 1;
                        start = t;
                    }
                }
                continue;
            }
            let left = p_end - p_stop;
            if !matches!(leg.end.kind.as_str(), "fold" | "unstable" | "branch_point")
                || left.abs() <= SWITCH_STEP
            {
                self.ends.push(leg.end);
                return Ok(());
            }
            let p = p_stop + SWITCH_STEP * left.signum();
            match switch_pair(problem, ex, &last, p, &s.solve) {
                Ok((t, why, _)) => {
                    // The companion follows the new pair.
                    maker.reset();
                    let triple = self.connect(maker, &t, &old(&start), start.p, p_stop, ex)?;
                    self.switches.push(format!(
                        "past {name} = {:.6} ({}): switched at {name} = {:.6} onto the lowest pair of states, {why}; L̄_cr = {:.8}; {triple}",
                        leg.end.value,
                        leg.end.kind,
                        problem.theta(p),
                        t.x[t.x.len() - 1],
                    ));
                    self.push(maker, &t, RowSource::Switch, ex)?;
                    switches += 1;
                    // Checkpoints passed by the switch step are skipped.
                    while next + 1 < stops.len() && (stops[next] - t.p) * left.signum() <= 0.0 {
                        next += 1;
                    }
                    start = t;
                }
                Err(e) => {
                    leg.end.reason.push_str(&format!(
                        "; no stable pair of states was found beyond it ({e})"
                    ));
                    self.ends.push(leg.end);
                    return Ok(());
                }
            }
        }
        let v = problem.theta(start.p);
        self.ends.push(CurveEnd {
            value: v,
            kind: "failed".into(),
            reason: format!(
                "{MAX_SWITCHES} switches onto other pairs of states used up at {name} = {v}"
            ),
        });
        Ok(())
    }

    /// Join the curve of the new pair (starting at `t`, just past `p_stop`) to the curve
    /// `old` of the previous pair: trace it back towards `leg_start` (at most
    /// [`BACK_RANGE`]); where the two cross (a triple point, [`triple_point`]) the previous
    /// pair stops being the lowest, and its rows beyond are dropped; otherwise the back-traced
    /// rows fill the gap between `p_stop` and the switch. Returns a description.
    fn connect<M: SurfaceSolve>(
        &mut self,
        maker: &mut RowMaker<M>,
        t: &Tracked,
        old: &[Tracked],
        leg_start: f64,
        p_stop: f64,
        ex: Exchange,
    ) -> Result<String, DiagramError> {
        let problem = maker.main;
        let name = problem.param();
        // The direction of travel.
        let dir = (p_stop - leg_start).signum();
        let back_end = if (p_stop - leg_start).abs() > BACK_RANGE {
            p_stop - dir * BACK_RANGE
        } else {
            leg_start
        };
        let range = (back_end.min(t.p), back_end.max(t.p));
        let back = follow(problem, t, back_end, range, ex, &mut Vec::new())?;
        let (back_end_kind, back_end_reason) = (back.end.kind.clone(), back.end.reason.clone());
        let back_stop = back.end;
        let new: Vec<Tracked> = std::iter::once(t.clone()).chain(back.points).collect();
        let beyond = |p: f64, q: f64| (p - q) * dir > 0.0;
        match triple_point(problem, old, &new) {
            Some((o, n)) => {
                let arm = o.arm;
                let pt = o.p;
                self.rows
                    .retain(|r| !(r.arm == arm && beyond(problem.p_of(r.value), pt)));
                self.states.retain(|r| !(r.arm == arm && beyond(r.p, pt)));
                self.push(maker, &o, RowSource::Switch, ex)?;
                self.push(maker, &n, RowSource::Switch, ex)?;
                for b in new[1..].iter().filter(|b| beyond(b.p, pt)) {
                    self.push(maker, b, RowSource::Continuation, ex)?;
                }
                Ok(format!(
                    "the two curves cross at the triple point {name} = {:.8}, L̄ = {:.8} (three states of equal energy): the previous pair is the lowest only on its side of it",
                    problem.theta(pt),
                    o.x[o.x.len() - 1]
                ))
            }
            None => {
                for b in new[1..].iter().filter(|b| beyond(b.p, p_stop)) {
                    self.push(maker, b, RowSource::Continuation, ex)?;
                }
                let v = back_stop.value;
                if back_stop.kind == "branch_point"
                    && (problem.p_of(v) - p_stop).abs() <= 0.1 * SWITCH_STEP
                {
                    return Ok(format!(
                        "traced back, the new pair's curve meets the previous one at the branch point {name} = {v:.6}: the previous state becomes a saddle there and the new one branches off it (a pitchfork), so the curve is continuous with a kink"
                    ));
                }
                Ok(format!(
                    "traced back to {name} = {:.6} ({}: {}), the new pair's curve does not cross the previous one",
                    problem.theta(new.last().map(|b| b.p).unwrap_or(t.p)),
                    back_end_kind,
                    back_end_reason
                ))
            }
        }
    }

    /// Sort the rows by the parameter, drop a continuation row that is also a fixed row (the
    /// top of the ladder), and assemble the curve.
    fn finish(
        mut self,
        ex: Exchange,
        uniform: Option<UniformCheck>,
        cells: (usize, usize),
    ) -> PhaseCurve {
        self.rows.sort_by(|a, b| a.value.total_cmp(&b.value));
        let fixed_at: Vec<(f64, usize)> = self
            .rows
            .iter()
            .filter(|r| r.source == RowSource::Fixed)
            .map(|r| (r.value, r.arm))
            .collect();
        self.rows.retain(|r| {
            r.source != RowSource::Continuation
                || !fixed_at
                    .iter()
                    .any(|(v, arm)| *arm == r.arm && (v - r.value).abs() <= 1e-12 * v.abs())
        });
        PhaseCurve {
            exchange: ex,
            rows: self.rows,
            ends: self.ends,
            uniform,
            steps: self.steps,
            cells,
            turns: self.turns,
            switches: self.switches,
            checks: self.checks,
            notes: self.notes,
        }
    }
}

fn crit(ex: Exchange, reason: String) -> DiagramError {
    DiagramError::Critical {
        from_branch: ex.from_branch,
        to_branch: ex.to_branch,
        lbar: ex.lbar_uniform,
        reason,
    }
}

/// Seed, continue and extrapolate one exchange.
pub(super) fn trace_exchange(
    s: &PhaseSettings,
    scene_value: f64,
    ex: Exchange,
) -> Result<PhaseCurve, DiagramError> {
    // Side of the uniform rod on which the scene's d1 lies.
    let d1_scene = s.stiffness.param(Param::D1)?;
    let below = if s.param == Param::D1 {
        scene_value.min(s.target) < 1.0
    } else {
        d1_scene < 1.0
    };
    let seed = seed_exchange(s, ex, below)?;
    let d1_problem = &seed.problem;
    let cells = (d1_problem.models().0.cells(), d1_problem.models().1.cells());
    let mut parts = Parts::default();
    if s.param != Param::D1 {
        return trace_other(s, scene_value, ex, &seed, d1_scene, parts);
    }
    let mut maker = RowMaker::new(d1_problem, ex, s);
    parts.push(&mut maker, &seed.start, RowSource::Seed, ex)?;
    // Towards the far end of the range.
    let far = if below {
        scene_value.min(s.target)
    } else {
        scene_value.max(s.target)
    };
    let mut offsets = LIMIT_OFFSETS;
    offsets.sort_by(|a, b| b.total_cmp(a));
    let towards = |off: f64| if below { 1.0 - off } else { 1.0 + off };
    // The whole traced range: from the far end to the top of the ladder.
    let p_top = d1_problem.p_of(towards(offsets[0]));
    let p_far = d1_problem.p_of(far);
    let range = (p_far.min(p_top), p_far.max(p_top));
    parts.sweep(s, &mut maker, &seed.start, p_far, range, ex)?;
    // Towards the uniform rod: continuation to the largest offset of the ladder, then
    // Newton at the ladder's values, extrapolated to D1/D0 = 1.
    let mut maker = RowMaker::new(d1_problem, ex, s);
    let leg = follow(d1_problem, &seed.start, p_top, range, ex, &mut parts.turns)?;
    parts.steps += leg.points.len();
    for t in &leg.points {
        parts.push(&mut maker, t, RowSource::Continuation, ex)?;
    }
    let reached = leg
        .points
        .last()
        .is_some_and(|t| (t.p - p_top).abs() < 1e-9 && t.arm == 0);
    let mut x = leg
        .points
        .last()
        .map(|t| t.x.clone())
        .unwrap_or(seed.start.x.clone());
    let mut ladder = Vec::new();
    if reached {
        for off in offsets {
            let theta = towards(off);
            let p = d1_problem.p_of(theta);
            match fixed(d1_problem, &x, p) {
                Ok(y) => {
                    let t = Tracked {
                        index: d1_problem.indices(&y, p)?,
                        x: y,
                        p,
                        arm: 0,
                    };
                    parts.push(&mut maker, &t, RowSource::Fixed, ex)?;
                    ladder.push((off, parts.rows[parts.rows.len() - 1].clone()));
                    x = t.x;
                }
                Err(e) => {
                    parts.notes.push(format!(
                        "towards the uniform rod: Newton at D1/D0 = {theta} failed ({e})"
                    ));
                    break;
                }
            }
        }
    }
    let mut uniform = None;
    if ladder.len() == offsets.len() {
        let (row, check) = limit_row(&ladder, ex);
        parts.rows.push(row);
        uniform = Some(check);
        parts.ends.push(CurveEnd {
            value: 1.0,
            kind: "limit".into(),
            reason: format!(
                "the uniform rod D1/D0 = 1 (arclength-shift symmetry); the limit is extrapolated from |1 - D1/D0| = {}",
                offsets
                    .iter()
                    .map(|o| format!("{o}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        });
    } else {
        parts.ends.push(leg.end);
    }
    let mut notes = std::mem::take(&mut parts.notes);
    add_at_rows(
        s,
        d1_problem,
        ex,
        &parts.states,
        &mut parts.rows,
        &mut notes,
    )?;
    parts.notes = notes;
    Ok(parts.finish(ex, uniform, cells))
}

/// The limit `D1/D0 → 1` from the ladder of fixed rows `(t, row)` in decreasing offset
/// `t = |1 − D1/D0|`: `L̄_cr(t)` is smooth in `t` (the placement of the segment is selected by
/// a nondegenerate minimum); quadratic through the three smallest offsets, the estimate
/// compares it with the quadratic through the three largest.
fn limit_row(ladder: &[(f64, PhaseRow)], ex: Exchange) -> (PhaseRow, UniformCheck) {
    let pts: Vec<(f64, f64, f64)> = ladder
        .iter()
        .map(|(t, r)| (*t, r.lbar_cr, r.energy))
        .collect();
    let quad = |q: &[(f64, f64, f64)], pick: fn(&(f64, f64, f64)) -> f64| -> f64 {
        let mut acc = 0.0;
        for i in 0..3 {
            let mut w = 1.0;
            for j in 0..3 {
                if i != j {
                    w *= (0.0 - q[j].0) / (q[i].0 - q[j].0);
                }
            }
            acc += w * pick(&q[i]);
        }
        acc
    };
    let n = pts.len();
    let small = &pts[n - 3..];
    let large = &pts[..3];
    let lim = quad(small, |q| q.1);
    let lim_large = quad(large, |q| q.1);
    let energy_lim = quad(small, |q| q.2);
    let disc = ladder
        .iter()
        .map(|(_, r)| r.error_estimate)
        .fold(0.0, f64::max);
    let est = disc + (lim - lim_large).abs();
    let energy_disc = ladder
        .iter()
        .map(|(_, r)| r.energy_error)
        .fold(0.0, f64::max);
    let energy_error = energy_disc + (energy_lim - quad(large, |q| q.2)).abs();
    let last = &ladder[n - 1].1;
    let row = PhaseRow {
        value: 1.0,
        lbar_cr: lim,
        error_estimate: est,
        energy: energy_lim,
        from_branch: last.from_branch,
        to_branch: last.to_branch,
        index: last.index,
        arm: 0,
        slope: last.slope,
        source: RowSource::Limit,
        energy_error,
        states: super::RowStates::None,
    };
    let check = UniformCheck {
        lbar_cr: lim,
        error_estimate: est,
        exact: ex.lbar_uniform,
        deviation: lim - ex.lbar_uniform,
    };
    (row, check)
}

/// A curve in `gamma`, `s0` or `s1`: first bring the seed's Maxwell point to the scene's
/// `d1`, then continue in the parameter.
fn trace_other<M: SurfaceSolve>(
    s: &PhaseSettings,
    scene_value: f64,
    ex: Exchange,
    seed: &super::seed::Seed<M>,
    d1_scene: f64,
    mut parts: Parts,
) -> Result<PhaseCurve, DiagramError> {
    let d1_problem = &seed.problem;
    let p_seed = seed.start.p;
    let p_scene = d1_problem.p_of(d1_scene);
    let leg = follow(
        d1_problem,
        &seed.start,
        p_scene,
        (p_scene.min(p_seed), p_scene.max(p_seed)),
        ex,
        &mut parts.turns,
    )?;
    if leg.end.kind != "reached" {
        return Err(crit(
            ex,
            format!(
                "continuation in D1/D0 from {} to the scene's {d1_scene} ended at D1/D0 = {}: {}",
                seed.theta, leg.end.value, leg.end.reason
            ),
        ));
    }
    let last = leg
        .points
        .last()
        .map(|t| t.x.clone())
        .unwrap_or(seed.start.x.clone());
    let (za, zb, lbar) = d1_problem.split(last.as_slice())?;
    let (ma0, mb0) = d1_problem.models_at(1.0, p_scene)?;
    let problem = MaxwellProblem::new(ma0, mb0, s.param)?;
    let p0 = problem.p_of(scene_value);
    let x0 = join(za, zb, lbar);
    let x0 = fixed(&problem, &x0, p0).map_err(|e| crit(ex, e))?;
    let t0 = Tracked {
        index: problem.indices(&x0, p0)?,
        x: x0,
        p: p0,
        arm: 0,
    };
    let mut maker = RowMaker::new(&problem, ex, s);
    parts.push(&mut maker, &t0, RowSource::Seed, ex)?;
    let pt = problem.p_of(s.target);
    parts.sweep(s, &mut maker, &t0, pt, (pt.min(p0), pt.max(p0)), ex)?;
    let mut notes = std::mem::take(&mut parts.notes);
    add_at_rows(s, &problem, ex, &parts.states, &mut parts.rows, &mut notes)?;
    notes.push(format!(
        "the mesh is graded for the scene's {} = {scene_value} and kept along the curve; \
         the error estimates measure what that costs",
        s.param
    ));
    parts.notes = notes;
    let cells = (problem.models().0.cells(), problem.models().1.cells());
    Ok(parts.finish(ex, None, cells))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rodloop_solver::Stiffness;

    #[test]
    fn checkpoints_are_the_decades_strictly_inside_in_travel_order() {
        let st = Stiffness::Tanh {
            d0: 1.0,
            d1: 0.5,
            s0: 0.3,
            s1: 0.8,
            gamma: 12.0,
        };
        let m = crate::surface_model(1.0, 1.4, 12, &st).unwrap();
        let pb = MaxwellProblem::new(m.clone(), m.clone(), Param::D1).unwrap();
        let down = checkpoints(&pb, 0.9f64.ln(), 0.001f64.ln());
        let want = [0.1f64.ln(), 0.01f64.ln()];
        assert_eq!(down.len(), 2);
        for (a, b) in down.iter().zip(want) {
            assert!((a - b).abs() < 1e-12);
        }
        let up = checkpoints(&pb, 0.001f64.ln(), 0.9f64.ln());
        assert!((up[0] - 0.01f64.ln()).abs() < 1e-12 && up.len() == 2);
        // A decade within SWITCH_STEP of an end is not a checkpoint; nor is the end itself.
        assert!(checkpoints(&pb, 0.5f64.ln(), 0.1f64.ln()).is_empty());
        let g = MaxwellProblem::new(m.clone(), m, Param::Gamma).unwrap();
        assert!(checkpoints(&g, 12.0, 100.0).is_empty());
    }
}
