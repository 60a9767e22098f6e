//! Branch points of traced enclosed families, located on re-solved states.
//!
//! A branch point of a family of constrained equilibria is where an eigenvalue of the
//! Hessian of the Lagrangian on the tangent space of the closure, the gauges and the strongly
//! active wall constraints crosses zero (second-order optimality, Sec. 3.2; the index is the
//! KKT inertia, [`EnclosedState::index`]). Between two traced states it is bracketed in
//! either of two ways:
//!
//! * the index differs: the eigenvalue at position `min(i_a, i_b)` (ascending) changes sign
//!   along the family;
//! * the point group differs ([`family_symmetry`]): a family keeps its symmetry along a smooth
//!   path, so the trace has passed a symmetry-breaking pitchfork and continued on the
//!   other family that meets there (the family with fewer symmetries exists on one side of
//!   the point only). The eigenvalue that crosses zero is the symmetric family's, at
//!   position `i` (its index) on the side it is traced from: continued in its invariant
//!   subspace (Newton from a symmetric state keeps the symmetry) it changes sign at the point.
//!
//! The root of that eigenvalue is located by Brent's method
//! ([`rodloop_continuation::roots::brent`]) on states re-solved at each trial `L̄`, each by
//! natural-parameter steps from the nearest state already re-solved on the family (a failed
//! step halved; where that walk fails, from the nearest one on the other side of the trial
//! `L̄`, since next to a singular point Newton may converge from one side only), so that
//! every trial state lies on the family the bracket is taken on. This is done on two mesh
//! levels of the trace; the value is the finer level's root and its estimate the final
//! bracket plus the distance between the two levels' roots (the discretisation error of the
//! coarser one, which bounds the finer one's where the location converges at order ≥ 1).
//! Where the coarser level's index does not change next to the bracket, the finer level and
//! its bracket states prolonged to twice their cells take the two levels' places (a jump on
//! the finer level is reported from it alone, [`locate`]).

use rodloop_continuation::roots::brent;
use rodloop_continuation::RootError;
use rodloop_solver::enclosed::{solve_prolonged, EnclosedOptions, EnclosedState};
use rodloop_solver::SolverError;

use super::levels::Levels;

/// Relative threshold of the strongly active wall constraints, as for the traces' index.
const ACTIVE: f64 = 1e-6;

/// Largest `|f|` at the final bracket's states, relative to the larger bracket end's, of a
/// continuous crossing (see [`locate_on_level`]).
const JUMP: f64 = 1e-4;

/// How the error of a root where the eigenvalue jumps begins ([`is_jump`]).
const JUMPS: &str = "the eigenvalue jumps";

/// `true` for the error of [`locate`] where the eigenvalue jumps at the root: a change of
/// the contact set, not a branch point.
pub(super) fn is_jump(e: &SolverError) -> bool {
    matches!(e, SolverError::InvalidInput(m) if m.starts_with(JUMPS))
}

/// Where the eigenvalue jumps ([`is_jump`]): the `L̄` of the jump and the half-width of its
/// bracket (0 where the message gives none), as the message states them.
pub(super) fn jump_at(e: &SolverError) -> Option<(f64, f64)> {
    if !is_jump(e) {
        return None;
    }
    let text = e.to_string();
    let mut words = text.split("at lbar = ").nth(1)?.split_whitespace();
    let x = words.next()?.parse().ok()?;
    let w = match (words.next(), words.next()) {
        (Some("±"), Some(w)) => w.parse().ok()?,
        _ => 0.0,
    };
    Some((x, w))
}

/// Brent's relative bracket tolerance and iteration budget.
const XTOL: f64 = 1e-10;
const MAX_ITER: usize = 40;

/// A located branch point.
#[derive(Clone, Debug)]
pub(super) struct Located {
    /// `L̄` of the point (the finer level's root).
    pub(super) lbar: f64,
    /// Its estimate: final bracket plus the distance between the two levels' roots.
    pub(super) error_estimate: f64,
    /// Energy of the re-solved state next to the root (finer level).
    pub(super) energy: f64,
    /// Index below and above the point (of the bracket's ends on the finer level; the states
    /// at the final bracket, 1e-10 from the root, count the crossing eigenvalue as zero).
    pub(super) index_below: usize,
    /// See `index_below`.
    pub(super) index_above: usize,
}

/// The root on one level.
#[derive(Clone, Debug)]
pub(super) struct LevelRoot {
    pub(super) x: f64,
    pub(super) width: f64,
    pub(super) energy: f64,
    pub(super) index_below: usize,
    pub(super) index_above: usize,
}

/// Newton at `x` from `s` (pinned translations kept for a free loop).
fn step(s: &EnclosedState, x: f64, opts: &EnclosedOptions) -> Result<EnclosedState, SolverError> {
    if s.model.gauge().pin.is_some() {
        s.step_free(x, opts)
    } else {
        s.step_to(x, opts)
    }
}

/// Halvings of a failed re-solve step in [`walk_to`].
const HALVINGS: usize = 5;

/// Newton steps from `s` (at `from`) to `x`: the whole way first, a failed step halved up to
/// [`HALVINGS`] times and the walk resumed from the state reached with the remaining way.
fn walk_to(
    s: &EnclosedState,
    from: f64,
    x: f64,
    opts: &EnclosedOptions,
) -> Result<EnclosedState, SolverError> {
    let (mut cur, mut at, mut h) = (s.clone(), from, x - from);
    let mut halvings = 0;
    loop {
        let to = if (x - at).abs() <= h.abs() { x } else { at + h };
        match step(&cur, to, opts) {
            Ok(t) => {
                (cur, at) = (t, to);
                if to == x {
                    return Ok(cur);
                }
            }
            Err(e) if halvings >= HALVINGS => return Err(e),
            Err(_) => {
                halvings += 1;
                h *= 0.5;
            }
        }
    }
}

/// Eigenvalue `k` (ascending) on the tangent space.
fn eigen(s: &EnclosedState, k: usize) -> Result<f64, SolverError> {
    let (_, vals) = s.stability(ACTIVE)?;
    let v = vals
        .get(k)
        .copied()
        .ok_or_else(|| SolverError::InvalidInput("too few eigenvalues".into()))?;
    Ok(v)
}

/// Width of a sign-changing bracket, relative to the first one, below which a jump is
/// decided ([`jump_found`]).
const JUMP_WIDTH: f64 = 1e-2;

/// Factor by which `|f|` at both ends of a bracket exceeds the local slope times its width
/// where the eigenvalue jumps ([`jump_found`]).
const JUMP_SLOPE: f64 = 100.0;

/// The error of a jump where the re-solved values `solved` (`(L̄, eigenvalue)`, the
/// bracket's ends first) already show one, so that Brent's method stops there instead of
/// bisecting it down to its tolerance. The tightest sign-changing bracket `[lo, hi]` holds a
/// jump when it is narrower than [`JUMP_WIDTH`] of the first bracket `width0` and the
/// eigenvalue at both of its ends exceeds [`JUMP_SLOPE`] times the local slope (the secant
/// to the nearest re-solved value on the same side, the larger of the two sides) times its
/// width, and [`JUMP`] of the first bracket's values: a continuous crossing has
/// `|f(lo)| + |f(hi)| ≈ |f'|·width`.
fn jump_found(solved: &[(f64, f64)], width0: f64) -> Option<SolverError> {
    let neg = |p: &&(f64, f64)| p.1 < 0.0;
    let pos = |p: &&(f64, f64)| p.1 > 0.0;
    // The sign-changing bracket of the latest value with the nearest value of the other sign.
    let last = solved.last()?;
    let other = solved
        .iter()
        .filter(|p| if last.1 > 0.0 { neg(p) } else { pos(p) })
        .min_by(|u, v| (u.0 - last.0).abs().total_cmp(&(v.0 - last.0).abs()))?;
    let width = (last.0 - other.0).abs();
    if width >= JUMP_WIDTH * width0 {
        return None;
    }
    // No value of either sign between them (the tightest bracket).
    if solved
        .iter()
        .any(|p| (p.0 - last.0) * (p.0 - other.0) < 0.0)
    {
        return None;
    }
    let slope = |end: &(f64, f64)| {
        solved
            .iter()
            .filter(|p| p.0 != end.0 && (p.1 > 0.0) == (end.1 > 0.0))
            .filter(|p| (p.0 - end.0) * (end.0 - last.0 - other.0 + end.0) >= 0.0)
            .min_by(|u, v| (u.0 - end.0).abs().total_cmp(&(v.0 - end.0).abs()))
            .map(|p| ((p.1 - end.1) / (p.0 - end.0)).abs())
    };
    let s = slope(last)?.max(slope(other)?);
    let small = last.1.abs().min(other.1.abs());
    let scale = solved[0]
        .1
        .abs()
        .max(solved.get(1).map_or(0.0, |p| p.1.abs()));
    if small > JUMP_SLOPE * s * width && small > JUMP * scale {
        let (lo, hi) = if last.0 < other.0 {
            (last, other)
        } else {
            (other, last)
        };
        return Some(SolverError::InvalidInput(format!(
            "{JUMPS} from {:.3e} to {:.3e} at lbar = {:.6} ± {:.0e} (the active set changes there; no eigenvalue crosses zero)",
            lo.1,
            hi.1,
            0.5 * (lo.0 + hi.0),
            0.5 * width
        )));
    }
    None
}

/// Steps of [`jump_extent`]'s walks across the bracket.
const EXTENT_STEPS: u32 = 8;

/// The error of a jump of the crossing eigenvalue between the bracket's ends `xa` and `xb`,
/// placed by the extent of the two contact sets on either side of it (`solved`: the
/// re-solved states with their eigenvalue; each side's family is the sign of its
/// eigenvalue). A mesh's contact
/// set changes with hysteresis: the state of each side continues past the place where the
/// other one ends, so where Brent's method meets the jump depends on which side it walked
/// from. Each side's state nearest the other end is walked on towards it in
/// [`EXTENT_STEPS`] steps until its index changes or Newton fails; the jump lies
/// between the two places reached (the interval where both sides exist, or the gap between
/// them), and the error gives its middle and half-width plus a step.
fn jump_extent(
    solved: &[(f64, EnclosedState, f64)],
    xa: f64,
    xb: f64,
    opts: &EnclosedOptions,
) -> SolverError {
    let fa = solved[0].2;
    let fb = solved
        .iter()
        .find(|p| (p.2 > 0.0) != (fa > 0.0))
        .map_or(f64::NAN, |p| p.2);
    // Each side's state nearest the other end.
    let nearest = |positive: bool, to: f64| {
        solved
            .iter()
            .filter(|p| (p.2 > 0.0) == positive)
            .min_by(|u, v| (to - u.0).abs().total_cmp(&(to - v.0).abs()))
            .map(|p| (&p.1, p.0))
    };
    match (nearest(fa > 0.0, xb), nearest(fa <= 0.0, xa)) {
        (Some(a), Some(b)) => sides_extent(a, b, xa, xb, opts)
            .map(|(x, w, how)| {
                SolverError::InvalidInput(format!(
                    "{JUMPS} from {fa:.3e} to {fb:.3e} at lbar = {x:.6} ± {w:.1e} ({how}: the active set changes there; no eigenvalue crosses zero)"
                ))
            })
            .unwrap_or_else(|e| e),
        _ => SolverError::InvalidInput(format!(
            "{JUMPS} between lbar = {xa:.6} and {xb:.6} (the active set changes there; no eigenvalue crosses zero)"
        )),
    }
}

/// Where the contact set of a mesh changes between the bracket's ends `xa` and `xb`, from a
/// state of each side (`(state, L̄)`, the `xa` side first; see [`jump_extent`]): each is
/// walked on towards the other end in [`EXTENT_STEPS`] steps of the bracket until its index
/// (the inertia) changes or Newton fails. Returns the middle of the two places reached, the
/// half-distance plus a step, and how they lie.
fn sides_extent(
    a: (&EnclosedState, f64),
    b: (&EnclosedState, f64),
    xa: f64,
    xb: f64,
    opts: &EnclosedOptions,
) -> Result<(f64, f64, &'static str), SolverError> {
    let h = (xb - xa) / f64::from(EXTENT_STEPS);
    let reach = |(start, x0): (&EnclosedState, f64), to: f64| -> Result<f64, SolverError> {
        let dx = h.abs().copysign(to - x0);
        let index = start.index(ACTIVE)?;
        let (mut cur, mut at) = (start.clone(), x0);
        for _ in 0..EXTENT_STEPS {
            let next = at + dx;
            if (next - to) * dx > 0.0 {
                break;
            }
            match step(&cur, next, opts).and_then(|t| Ok((t.index(ACTIVE)?, t))) {
                Ok((i, t)) if i == index => (cur, at) = (t, next),
                _ => break,
            }
        }
        Ok(at)
    };
    let (ra, rb) = (reach(a, xb)?, reach(b, xa)?);
    let (lo, hi) = (ra.min(rb), ra.max(rb));
    let how = if (ra - xa).abs() > (rb - xa).abs() {
        "where the states of either side exist on this mesh"
    } else {
        "between the places the states of either side reach on this mesh"
    };
    Ok((0.5 * (lo + hi), 0.5 * (hi - lo) + h.abs(), how))
}

/// The root on one level between `from` (at `xa`, the family the bracket is taken on) and
/// `to` (at `xb`): `to` is used as the far end where its index differs from `from`'s (the
/// same family on the other side of the point); otherwise (a change of symmetry) the far
/// end is `from` re-solved at `xb`.
pub(super) fn locate_on_level(
    from: &EnclosedState,
    xa: f64,
    to: &EnclosedState,
    xb: f64,
    opts: &EnclosedOptions,
) -> Result<LevelRoot, SolverError> {
    let ia = from.index(ACTIVE)?;
    let ib = to.index(ACTIVE)?;
    let k = if ia != ib { ia.min(ib) } else { ia };
    let mut solved: Vec<(f64, EnclosedState, f64)> = Vec::new();
    let fa = eigen(from, k)?;
    solved.push((xa, from.clone(), fa));
    if ia != ib {
        let fb = eigen(to, k)?;
        solved.push((xb, to.clone(), fb));
    }
    let mut f = |x: f64| -> Result<f64, SolverError> {
        if let Some(p) = solved.iter().find(|p| p.0 == x) {
            return Ok(p.2);
        }
        // From the nearest re-solved state; where that walk fails (Newton does not converge
        // next to the singular point), from the nearest one on the other side of `x`.
        let nearest = |below: Option<bool>| {
            solved
                .iter()
                .filter(|p| below.is_none_or(|b| (p.0 < x) == b))
                .min_by(|u, v| (u.0 - x).abs().total_cmp(&(v.0 - x).abs()))
        };
        let near = nearest(None).expect("the bracket's first end");
        let s = match walk_to(&near.1, near.0, x, opts) {
            Ok(s) => s,
            Err(e) => match nearest(Some(near.0 > x)) {
                Some(other) => walk_to(&other.1, other.0, x, opts)?,
                None => return Err(e),
            },
        };
        let v = eigen(&s, k)?;
        solved.push((x, s, v));
        let values: Vec<(f64, f64)> = solved.iter().map(|p| (p.0, p.2)).collect();
        if let Some(e) = jump_found(&values, (xb - xa).abs()) {
            return Err(e);
        }
        Ok(v)
    };
    let root = match brent(&mut f, xa, xb, XTOL, MAX_ITER) {
        Ok(r) => r,
        Err(RootError::Function(e)) if is_jump(&e) => {
            return Err(jump_extent(&solved, xa, xb, opts))
        }
        Err(RootError::Function(e)) => return Err(e),
        Err(e) => {
            return Err(SolverError::InvalidInput(format!(
                "the crossing eigenvalue was not bracketed: {e}"
            )))
        }
    };
    if !root.converged() {
        return Err(SolverError::InvalidInput(format!(
            "Brent's method did not converge in {MAX_ITER} re-solves (bracket {:.1e})",
            root.width
        )));
    }
    // The re-solved states nearest the root with the eigenvalue of either sign: the two
    // sides of the point.
    let x = root.x;
    let nearest = |positive: bool| {
        solved
            .iter()
            .filter(|p| (p.2 > 0.0) == positive)
            .min_by(|u, v| (u.0 - x).abs().total_cmp(&(v.0 - x).abs()))
    };
    let (Some(p), Some(q)) = (nearest(true), nearest(false)) else {
        return Err(SolverError::InvalidInput(
            "no re-solved state on one side of the root".into(),
        ));
    };
    let (lo, hi) = if p.0 < q.0 { (p, q) } else { (q, p) };
    // A branch point is a zero eigenvalue: across the final bracket the eigenvalue is
    // continuous (`|f| ≈ |f'|·width`, far below the bracket ends' values). Where it jumps
    // instead, the contact set changes there (a contact force reaching 0 takes a constraint
    // off the tangent space) and no eigenvalue crosses zero.
    let scale = solved[0].2.abs().max(solved[1].2.abs());
    if lo.2.abs().max(hi.2.abs()) > JUMP * scale {
        return Err(jump_extent(&solved, xa, xb, opts));
    }
    Ok(LevelRoot {
        x,
        width: (hi.0 - lo.0).abs().max(root.width),
        energy: if (x - lo.0).abs() < (hi.0 - x).abs() {
            lo.1.energy()
        } else {
            hi.1.energy()
        },
        index_below: if xa < xb { ia } else { ib },
        index_above: if xa < xb { ib } else { ia },
    })
}

/// The branch point where the index of a traced family changes between its states `j` and
/// `j + 1` (`tr` in increasing `L̄`), located on the two mesh levels `levels` (coarser
/// first). The index may change between other neighbouring states on another level (the
/// discretisation moves the point): on each level the bracket is the window nearest to
/// `j`, within one state, where that level's index changes. Where the coarser level's index
/// does not change there (its point lies farther, or its mesh does not resolve it), the
/// point is located on the finer level and, where it is a root there, again on the finer
/// level's bracket states prolonged to twice their cells and re-solved; a jump on the finer
/// level is reported from it alone.
pub(super) fn locate(
    tr: &[&Levels],
    j: usize,
    levels: [usize; 2],
    opts: &EnclosedOptions,
) -> Result<Located, SolverError> {
    let window_on = |lvl: usize| -> Result<Option<usize>, SolverError> {
        let lo = j.saturating_sub(1);
        let hi = (j + 2).min(tr.len() - 1);
        let idx: Vec<usize> = (lo..=hi)
            .map(|i| tr[i].states[lvl].index(ACTIVE))
            .collect::<Result<_, _>>()?;
        Ok([j, j.wrapping_sub(1), j + 1]
            .into_iter()
            .find(|&w| w >= lo && w < hi && idx[w - lo] != idx[w + 1 - lo]))
    };
    let bracket = |lvl: usize, w: usize| {
        let (a, b) = (tr[w], tr[w + 1]);
        (a.states[lvl].clone(), a.lbar, b.states[lvl].clone(), b.lbar)
    };
    // The two rungs, coarser first: `(state, L̄)` at either end of the bracket.
    let mut rungs = Vec::with_capacity(2);
    match (window_on(levels[0])?, window_on(levels[1])?) {
        (Some(c), Some(f)) => {
            rungs.push(bracket(levels[0], c));
            rungs.push(bracket(levels[1], f));
        }
        (None, Some(f)) => {
            // The finer level first: a jump there is reported from it alone (where that
            // mesh's contact set changes, not a branch point; the doubled mesh's place would
            // add only cost); a root is located again on twice its cells.
            let (a, xa, b, xb) = bracket(levels[1], f);
            let c = locate_on_level(&a, xa, &b, xb, opts)?;
            let doubled = |s: &EnclosedState| {
                let (m, z) = s.refine()?;
                solve_prolonged(&m, z, opts)
            };
            let (a2, b2) = (doubled(&a)?, doubled(&b)?);
            if a2.index(ACTIVE)? == b2.index(ACTIVE)? {
                return Err(SolverError::InvalidInput(format!(
                    "the index on twice the cells of level {} does not change next to lbar = {:.6}",
                    levels[1], tr[j].lbar
                )));
            }
            let f = locate_on_level(&a2, xa, &b2, xb, opts)?;
            return Ok(located(&c, &f));
        }
        (c, _) => {
            let lvl = if c.is_none() { levels[0] } else { levels[1] };
            return Err(SolverError::InvalidInput(format!(
                "the index on level {lvl} does not change next to lbar = {:.6}",
                tr[j].lbar
            )));
        }
    }
    let mut r = Vec::with_capacity(2);
    // Per rung, coarser first: the root or the jump, `(L̄, estimate)`.
    let mut places: Vec<(f64, f64)> = Vec::with_capacity(2);
    let mut jumped = false;
    for (a, xa, b, xb) in &rungs {
        if jumped {
            // A jump on the coarser rung: on this one, where its contact set changes.
            let (x, w, _) = sides_extent((a, *xa), (b, *xb), *xa, *xb, opts)?;
            places.push((x, w));
            continue;
        }
        match locate_on_level(a, *xa, b, *xb, opts) {
            Ok(root) => {
                places.push((root.x, root.width));
                r.push(root);
            }
            Err(e) => match jump_at(&e) {
                Some(p) => {
                    places.push(p);
                    jumped = true;
                }
                None => return Err(e),
            },
        }
    }
    if jumped {
        // Where the contact set of a mesh changes depends on the mesh: the finer level's
        // place, with the distance to the coarser level's (a jump or a root) as well as both
        // estimates.
        let ((xc, wc), (x, wf)) = (places[0], places[1]);
        let w = wf + wc + (x - xc).abs();
        let (nc, nf) = (rungs[0].0.model.cells(), rungs[1].0.model.cells());
        return Err(SolverError::InvalidInput(format!(
            "{JUMPS} at lbar = {x:.6} ± {w:.1e} (on {nc} and {nf} cells at {xc:.6} and {x:.6}: the active set of the mesh changes there, a place that moves with the mesh; no eigenvalue crosses zero)"
        )));
    }
    Ok(located(&r[0], &r[1]))
}

/// The point from the roots on a coarser and a finer mesh: the finer one, with its bracket
/// plus the distance between the two as its estimate.
fn located(c: &LevelRoot, f: &LevelRoot) -> Located {
    Located {
        lbar: f.x,
        error_estimate: f.width + (f.x - c.x).abs(),
        energy: f.energy,
        index_below: f.index_below,
        index_above: f.index_above,
    }
}

#[cfg(test)]
mod tests {
    //! The symmetry-breaking pitchfork of the uniform rod's planar figure-eight held by the
    //! wall at its two lobe tips (branch 2, near `L̄ = 0.84`): the planar family, continued
    //! past the point in its invariant subspace, gains a negative eigenvalue there.

    use super::*;
    use rodloop_exact::paper_branch_loop;
    use rodloop_solver::enclosed::{solve_branch, SurfaceSource};
    use rodloop_solver::Stiffness;

    /// The planar figure-eight at `xa` on 32, 64 and 128 cells (from the surface loop on 32,
    /// each finer mesh from the coarser state prolonged), and the same family stepped to
    /// `xb`.
    fn brackets(xa: f64, xb: f64) -> Vec<(EnclosedState, EnclosedState)> {
        let opts = EnclosedOptions::default();
        let l = paper_branch_loop(1, xa).unwrap();
        let uniform = Stiffness::uniform(1.0);
        let mut s = solve_branch(1.0, xa, &uniform, &SurfaceSource::Exact(l), 32, &opts)
            .unwrap()
            .fine;
        let mut out = Vec::new();
        for level in 0..3 {
            if level > 0 {
                let (m, z) = s.refine().unwrap();
                s = rodloop_solver::enclosed::solve_enclosed(&m, z, &opts).unwrap();
            }
            // Steps of 2e-3; one that fails next to the singular point (where Newton
            // converges only linearly) is skipped, the next taken from the last state.
            let mut t = s.clone();
            for k in 1..=10 {
                let x = xa + (xb - xa) * f64::from(k) / 10.0;
                match t.step_to(x, &opts) {
                    Ok(u) => t = u,
                    Err(e) => assert!(k < 10, "level {level}: {e}"),
                }
            }
            out.push((s.clone(), t));
        }
        out
    }

    /// Brent's method on the synthetic eigenvalue `g` over `[0, 1]`, each value checked by
    /// [`jump_found`] as [`locate_on_level`] checks its re-solves.
    fn brent_with_jump_check(g: impl Fn(f64) -> f64) -> Result<f64, SolverError> {
        let mut solved: Vec<(f64, f64)> = vec![(0.0, g(0.0)), (1.0, g(1.0))];
        let mut f = |x: f64| -> Result<f64, SolverError> {
            if let Some(p) = solved.iter().find(|p| p.0 == x) {
                return Ok(p.1);
            }
            solved.push((x, g(x)));
            match jump_found(&solved, 1.0) {
                Some(e) => Err(e),
                None => Ok(g(x)),
            }
        };
        match brent(&mut f, 0.0, 1.0, XTOL, MAX_ITER) {
            Ok(r) => Ok(r.x),
            Err(RootError::Function(e)) => Err(e),
            Err(e) => Err(SolverError::InvalidInput(e.to_string())),
        }
    }

    #[test]
    fn the_place_of_a_jump_is_read_from_its_error() {
        let g = |x: f64| if x < 0.618 { -0.05 } else { 0.03 };
        let e = brent_with_jump_check(g).unwrap_err();
        let (x, w) = jump_at(&e).expect("a jump");
        assert!((x - 0.618).abs() <= w + 1e-6, "{x} ± {w}: {e}");
        assert!(w < 1e-2, "{w}");
        assert_eq!(jump_at(&SolverError::InvalidInput("other".into())), None);
    }

    #[test]
    fn a_continuous_crossing_is_not_taken_for_a_jump() {
        // A straight line and a steep but smooth crossing (slope 50 at the root).
        let x = brent_with_jump_check(|x| x - 0.3137).unwrap();
        assert!((x - 0.3137).abs() < 1e-9, "{x}");
        let x = brent_with_jump_check(|x| 0.05 * ((x - 0.4) / 1e-3).tanh()).unwrap();
        assert!((x - 0.4).abs() < 1e-9, "{x}");
    }

    #[test]
    fn an_eigenvalue_that_jumps_is_reported_as_a_change_of_the_contact_set() {
        // Negative below 0.618, positive above, with a gap of 0.08 and a small slope: the
        // contact set changes there, no eigenvalue crosses zero.
        let g = |x: f64| {
            if x < 0.618 {
                -0.049 + 0.002 * x
            } else {
                0.031 + 0.002 * x
            }
        };
        let e = brent_with_jump_check(g).unwrap_err();
        assert!(is_jump(&e), "{e}");
        // The message places the jump at the bracket it found, next to 0.618.
        let text = e.to_string();
        let at: f64 = text
            .split("lbar = ")
            .nth(1)
            .and_then(|t| t.split_whitespace().next())
            .and_then(|t| t.parse().ok())
            .unwrap_or_else(|| panic!("no lbar in {text}"));
        assert!((at - 0.618).abs() < 1e-2, "{text}");
    }

    #[test]
    fn planar_figure_eight_pitchfork_located_on_three_meshes() {
        let (xa, xb) = (0.835, 0.846);
        let opts = EnclosedOptions::default();
        let mut roots = Vec::new();
        for ((a, b), n) in brackets(xa, xb).into_iter().zip([32, 64, 128]) {
            let (ia, ib) = (a.index(ACTIVE).unwrap(), b.index(ACTIVE).unwrap());
            assert_eq!(
                ib,
                ia + 1,
                "N = {n}: the planar family gains a negative eigenvalue"
            );
            let r = locate_on_level(&a, xa, &b, xb, &opts).unwrap();
            assert!(r.width < 1e-8, "N = {n}: bracket {}", r.width);
            assert_eq!((r.index_below, r.index_above), (ia, ib));
            // Independent re-solves 1e-3 on either side, stepped from the far ends.
            let below = walk_to(&a, xa, r.x - 1e-3, &opts).unwrap();
            let above = walk_to(&b, xb, r.x + 1e-3, &opts).unwrap();
            assert_eq!(below.index(ACTIVE).unwrap(), ia, "N = {n}");
            assert_eq!(above.index(ACTIVE).unwrap(), ib, "N = {n}");
            roots.push(r.x);
        }
        // The location converges as the mesh is refined (differences falling at least
        // 2x per doubling), near L̄ = 0.84.
        let (d1, d2) = ((roots[1] - roots[0]).abs(), (roots[2] - roots[1]).abs());
        assert!(d2 < 0.5 * d1, "roots {roots:?}");
        assert!(d2 < 1e-4, "roots {roots:?}");
        assert!((roots[2] - 0.841).abs() < 2e-3, "roots {roots:?}");
    }
}
