//! Point contacts on nodes: a uniform lifted-off loop whose contact with the wall shrinks
//! to points (the figure-eight below `L̄ ≈ 1.3`, its lobe tips) re-solved with its arclength
//! origin moved onto a contact point.
//!
//! The wall holds at the nodes only (Sec. 3.2 discretised, [`super::model`]). A point
//! contact between two nodes is carried by both: the loop touches at the two flanking
//! nodes and passes slightly outside the ball between them, and how far depends on where
//! the contact point falls in its cell, which changes erratically as `N` doubles. The
//! energy then converges at about order 1 and irregularly (figure-eight at `L̄ = 1.2`).
//! The point force also puts a jump of `κ'` inside a cell, where the Gauss quadrature loses
//! its order.
//!
//! For a uniform rod the arclength origin is a gauge (the phase condition,
//! [`super::model::Gauge::slope`]), so it may sit on a contact point, and the mesh may have
//! a node at every other one: the contact points come from the nodal impulses of each
//! two-node contact (the lever rule, `σ* = Σλ_j σ_j/Σλ_j`), the state is rebuilt from its
//! curvature continued from the first contact point ([`shifted_start`]: the frame there, by
//! the partial Magnus step of its cell, becomes the identity and the loop turns with it
//! about the ball's centre) on a mesh that is uniform between consecutive contact points
//! ([`EnclosedModel::with_bounds`]), and solved again. Each point force then acts at a
//! node, the jump of `κ'` falls on a cell boundary, and the ladder of such meshes (the same
//! pieces, the cells doubled) converges at fourth order: on the figure-eight at `L̄ = 1.2`,
//! `N = 64 … 512`, the differences fall 16.2× and 16.1× (orders 4.02, 4.01), where on the
//! uniform mesh their ratios run from 0.86 to 190.
//!
//! A contact carried by a single node of the uniform mesh may be two contact points closer
//! than a cell (the figure-eight at `L̄ = 1.2` for `N ≤ 256`); [`centre_levels`] declines
//! those, and the caller keeps the order-1 rule.

use nalgebra::{Matrix3, Vector3};

use super::jet::cell_exp;
use super::model::{rotation, translation, EnclosedModel, Gauge};
use super::solve::{
    least_squares_multipliers, solve_enclosed, start_from_curvature, transfer_multipliers,
    EnclosedOptions, EnclosedState, LEAST_SQUARES_MAX_CELLS,
};
use crate::model::GAUSS_OFFSETS;
use crate::SolverError;

/// Moves of the origin tried per level before the level counts as not centred.
pub const CENTRE_MOVES: usize = 4;

/// The contacts of a state, as groups of consecutive nodes (periodic) with a positive wall
/// impulse: for each, the nodes and the lever-rule contact point `σ* = Σλ_j σ_j/Σλ_j`
/// (unwrapped from the group's first node, so it may exceed 1).
pub fn contact_groups(state: &EnclosedState) -> Vec<(Vec<usize>, f64)> {
    let m = &state.model;
    let n = m.cells();
    let lam = &state.z[m.lambda_offset()..m.lambda_offset() + n];
    let on: Vec<bool> = lam.iter().map(|&l| l > 0.0).collect();
    let Some(start) = (0..n).find(|&j| on[j] && !on[(j + n - 1) % n]) else {
        return Vec::new();
    };
    let mut groups = Vec::new();
    let mut k = 0;
    while k < n {
        let j = (start + k) % n;
        if !on[j] {
            k += 1;
            continue;
        }
        let mut nodes = Vec::new();
        while k < n && on[(start + k) % n] {
            nodes.push((start + k) % n);
            k += 1;
        }
        let s0 = m.bounds()[nodes[0]];
        let (mut w, mut ws) = (0.0, 0.0);
        for &q in &nodes {
            let ds = (m.bounds()[q] - s0).rem_euclid(1.0);
            w += lam[q];
            ws += lam[q] * (s0 + ds);
        }
        groups.push((nodes, ws / w));
    }
    groups
}

/// `true` when `state` touches the wall and only at the nodes `placed`.
fn on_nodes(state: &EnclosedState, placed: &[usize]) -> bool {
    let g = contact_groups(state);
    !g.is_empty() && g.iter().flat_map(|(n, _)| n).all(|j| placed.contains(j))
}

/// Pieces shorter than this (in `σ`) merge with their neighbour: two contact points that
/// close are one.
const MIN_PIECE: f64 = 1e-6;

/// Cell boundaries with a node at each of `breaks` (sorted, in `[0, 1)`, the first 0):
/// `counts[i]` equal cells on piece `i`.
fn piece_bounds(breaks: &[f64], counts: &[usize]) -> Vec<f64> {
    let mut b = Vec::with_capacity(counts.iter().sum::<usize>() + 1);
    for (i, &c) in counts.iter().enumerate() {
        let (lo, hi) = (breaks[i], breaks.get(i + 1).copied().unwrap_or(1.0));
        b.extend((0..c).map(|k| lo + (hi - lo) * k as f64 / c as f64));
    }
    b.push(1.0);
    b
}

/// Cells per piece for `n` cells in all: proportional to the piece lengths, at least one
/// each (largest remainders). `None` when there are more pieces than cells.
fn apportion(breaks: &[f64], n: usize) -> Option<Vec<usize>> {
    let len: Vec<f64> = (0..breaks.len())
        .map(|i| breaks.get(i + 1).copied().unwrap_or(1.0) - breaks[i])
        .collect();
    if len.len() > n {
        return None;
    }
    let mut c: Vec<usize> = len
        .iter()
        .map(|l| ((l * n as f64).floor() as usize).max(1))
        .collect();
    while c.iter().sum::<usize>() < n {
        let i = (0..c.len())
            .max_by(|&a, &b| {
                (len[a] * n as f64 - c[a] as f64).total_cmp(&(len[b] * n as f64 - c[b] as f64))
            })
            .expect("a piece");
        c[i] += 1;
    }
    while c.iter().sum::<usize>() > n {
        let i = (0..c.len())
            .filter(|&i| c[i] > 1)
            .max_by(|&a, &b| (c[a] as f64 / len[a]).total_cmp(&(c[b] as f64 / len[b])))?;
        c[i] -= 1;
    }
    Some(c)
}

/// The frame (rotation) and position of the loop `state` at `σ = shift`: the node
/// transform of its cell times the partial Magnus step over the rest.
fn frame_at(
    state: &EnclosedState,
    shift: f64,
) -> Result<(Matrix3<f64>, Vector3<f64>), SolverError> {
    let m = &state.model;
    let b = m.bounds();
    let n = m.cells();
    let c = b[..n].partition_point(|&x| x <= shift).saturating_sub(1);
    let p = m.transforms(&state.z)?;
    let part = shift - b[c];
    let at = |o: f64| state.curvature_at(b[c] + o * part);
    let (ka, kb) = (at(GAUSS_OFFSETS[0]), at(GAUSS_OFFSETS[1]));
    let frame = p[c] * cell_exp(part * m.length(), [ka.0, ka.1, kb.0, kb.1]);
    Ok((
        rotation(&frame),
        m.start_point(&state.z) + translation(&frame),
    ))
}

/// The start of `state` with its arclength origin moved to `σ = shift`, on the cell
/// boundaries `bounds` (see the module docs): curvature `κ(σ + shift)` (interpolated and
/// continued across the closing node with the holonomy, [`EnclosedState::curvature_at`]),
/// the loop turned so that its frame at `shift` is the identity, start point the turned
/// `r(shift)`. The gauge takes the moved curvature as reference, with the phase condition
/// along its `σ`-derivative (central differences); multipliers by least squares (through
/// a uniform start of [`LEAST_SQUARES_MAX_CELLS`] cells on finer meshes).
pub fn shifted_start(
    state: &EnclosedState,
    shift: f64,
    bounds: Vec<f64>,
) -> Result<(EnclosedModel, Vec<f64>), SolverError> {
    let m = &state.model;
    let shift = shift.rem_euclid(1.0);
    let (q, r_at) = frame_at(state, shift)?;
    let r0 = q.transpose() * r_at;
    let kappa = |s: f64| state.curvature_at(s + shift);
    let stiff = m.stiffness().kind().clone();
    let cells = bounds.len() - 1;
    let zero = Gauge {
        reference: vec![0.0; 4 * cells],
        slope: None,
        pin: None,
    };
    let probe = EnclosedModel::with_bounds(m.wall(), m.lbar(), bounds.clone(), &stiff, zero)?;
    let reference = probe.sample_gauss(kappa);
    let d = 1e-5;
    let mut slope = probe.sample_gauss(|s| {
        let (a, b) = (kappa(s + d), kappa(s - d));
        ((a.0 - b.0) / (2.0 * d), (a.1 - b.1) / (2.0 * d))
    });
    let rms = (slope.iter().map(|v| v * v).sum::<f64>() / slope.len() as f64).sqrt();
    if !(rms.is_finite() && rms > 0.0) {
        return Err(SolverError::InvalidInput(
            "a loop of constant curvature has no contact point to move to".into(),
        ));
    }
    slope.iter_mut().for_each(|v| *v /= rms);
    let gauge = Gauge {
        reference: reference.clone(),
        slope: Some(slope),
        pin: None,
    };
    let model = EnclosedModel::with_bounds(m.wall(), m.lbar(), bounds, &stiff, gauge)?;
    let mut z = vec![0.0; model.dim()];
    z[..4 * cells].copy_from_slice(&reference);
    z[4 * cells..4 * cells + 3].copy_from_slice(&[r0[0], r0[1], r0[2]]);
    if cells <= LEAST_SQUARES_MAX_CELLS {
        least_squares_multipliers(&model, &mut z)?;
    } else {
        let (cm, cz) = start_from_curvature(
            m.wall(),
            m.lbar(),
            LEAST_SQUARES_MAX_CELLS,
            &stiff,
            kappa,
            [r0[0], r0[1], r0[2]],
        )?;
        transfer_multipliers(&cm, &cz, &model, &mut z);
    }
    Ok((model, z))
}

/// A level with its nodes on the contact points: the state, the breakpoints (`σ` of the
/// contact points, the first 0) and the cells per piece between them.
#[derive(Clone, Debug)]
pub struct CentredLevel {
    /// The solution.
    pub state: EnclosedState,
    /// The contact points (`σ`, sorted, the first 0).
    pub breaks: Vec<f64>,
    /// Cells on each piece between consecutive breakpoints.
    pub counts: Vec<usize>,
}

/// Node indices of the breakpoints of a piecewise mesh with `counts` cells per piece.
fn break_nodes(counts: &[usize]) -> Vec<usize> {
    counts
        .iter()
        .scan(0, |acc, &c| {
            let j = *acc;
            *acc += c;
            Some(j)
        })
        .collect()
}

/// Breakpoints from contact points `pts` with the origin moved to `shift`: sorted, the
/// first 0, points closer than [`MIN_PIECE`] merged.
fn breaks_from(pts: &[f64], shift: f64) -> Vec<f64> {
    let mut moved: Vec<f64> = pts.iter().map(|p| (p - shift).rem_euclid(1.0)).collect();
    moved.sort_by(f64::total_cmp);
    let mut breaks = vec![0.0];
    for b in moved {
        if b - breaks.last().expect("0") > MIN_PIECE && 1.0 - b > MIN_PIECE {
            breaks.push(b);
        }
    }
    breaks
}

/// The contact points of a state whose contacts are resolved: one per contact group of one
/// or two nodes (its node, or the lever-rule point `Σλ_jσ_j/Σλ_j` of the two). `None` where
/// a group spans three or more nodes (two contact points closer than the mesh resolves,
/// or an arc).
pub fn contact_points(state: &EnclosedState) -> Option<Vec<f64>> {
    let g = contact_groups(state);
    if g.is_empty() || g.iter().any(|(nodes, _)| nodes.len() > 2) {
        return None;
    }
    Some(g.into_iter().map(|(_, t)| t.rem_euclid(1.0)).collect())
}

/// `state` solved again on the pieces `breaks` with `counts` cells each, its origin moved
/// to `shift` ([`shifted_start`]); its wall impulses moved with their nodes onto the
/// nearest breakpoint node (a point force stays concentrated).
fn solve_on_pieces(
    state: &EnclosedState,
    shift: f64,
    breaks: &[f64],
    counts: &[usize],
    opts: &EnclosedOptions,
) -> Option<EnclosedState> {
    let (model, mut z) = shifted_start(state, shift, piece_bounds(breaks, counts)).ok()?;
    let nodes = break_nodes(counts);
    let (fm, lo) = (&state.model, state.model.lambda_offset());
    let to = model.lambda_offset();
    z[to..to + model.cells()].iter_mut().for_each(|v| *v = 0.0);
    for j in 0..fm.cells() {
        let lam = state.z[lo + j];
        if lam > 0.0 {
            let sigma = (fm.bounds()[j] - shift).rem_euclid(1.0);
            let dist = |k: usize| {
                let d = (breaks[k] - sigma).rem_euclid(1.0);
                d.min(1.0 - d)
            };
            let k = (0..breaks.len()).min_by(|&a, &b| dist(a).total_cmp(&dist(b)))?;
            z[to + nodes[k]] += lam;
        }
    }
    solve_enclosed(&model, z, opts).ok()
}

/// The point-contact state `from` solved again at `cells` cells with its arclength origin
/// on a contact point and a node at every contact point ([`contact_points`]; the pieces
/// between them meshed uniformly, their cells in the proportion of a `coarsest`-cell mesh,
/// at least one each, times `cells/coarsest`); where the solution still carries a contact
/// on two nodes, its contact points are taken again (at most [`CENTRE_MOVES`] times).
/// `None` unless the loop ends touching the wall at breakpoint nodes only, or where a
/// contact of `from` spans three or more nodes or a solve fails.
pub fn centred_level(
    from: &EnclosedState,
    coarsest: usize,
    cells: usize,
    opts: &EnclosedOptions,
) -> Option<CentredLevel> {
    if cells % coarsest != 0 {
        return None;
    }
    let mut source = from.clone();
    for _ in 0..CENTRE_MOVES {
        let pts = contact_points(&source)?;
        // The contact point nearest the origin goes to the origin.
        let shift = pts
            .iter()
            .copied()
            .min_by(|a, b| a.min(1.0 - a).total_cmp(&b.min(1.0 - b)))?;
        let breaks = breaks_from(&pts, shift);
        let counts: Vec<usize> = apportion(&breaks, coarsest)?
            .into_iter()
            .map(|c| c * (cells / coarsest))
            .collect();
        source = solve_on_pieces(&source, shift, &breaks, &counts, opts)?;
        if on_nodes(&source, &break_nodes(&counts)) {
            return Some(CentredLevel {
                state: source,
                breaks,
                counts,
            });
        }
    }
    None
}

/// The levels of a point-contact ladder (`states`, coarsest first, each of twice the cells
/// of the one before) solved again with a node at every contact point: the finest by
/// [`centred_level`], the others on the same pieces with their cells halved, each started
/// from the finest. `None` unless the rod is uniform, every contact of the finest level is
/// carried by two nodes (a contact point between them) and every level touches the wall at
/// its breakpoint nodes only.
pub fn centre_levels(
    states: &[&EnclosedState],
    opts: &EnclosedOptions,
) -> Option<Vec<EnclosedState>> {
    let fine = states.last()?;
    if !fine.model.stiffness().kind().is_uniform() {
        return None;
    }
    // A contact on one node may be two contact points the mesh does not resolve (the
    // figure-eight at L̄ = 1.2 at N = 64): only contacts between two nodes are located.
    let groups = contact_groups(fine);
    if groups.is_empty() || groups.iter().any(|(nodes, _)| nodes.len() != 2) {
        return None;
    }
    let coarsest = states.first()?.model.cells();
    let top = centred_level(fine, coarsest, fine.model.cells(), opts)?;
    let mut out = Vec::with_capacity(states.len());
    for s in &states[..states.len() - 1] {
        let f = s.model.cells() / coarsest;
        let counts: Vec<usize> = top
            .counts
            .iter()
            .map(|c| c / (fine.model.cells() / coarsest) * f)
            .collect();
        let level = solve_on_pieces(&top.state, 0.0, &top.breaks, &counts, opts)?;
        if !on_nodes(&level, &break_nodes(&counts)) {
            return None;
        }
        out.push(level);
    }
    out.push(top.state);
    Some(out)
}
