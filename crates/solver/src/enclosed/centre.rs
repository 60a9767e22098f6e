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
use crate::mesh::MeshMap;
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
    let probe = EnclosedModel::with_bounds(m.radius(), m.lbar(), bounds.clone(), &stiff, zero)?;
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
    let model = EnclosedModel::with_bounds(m.radius(), m.lbar(), bounds, &stiff, gauge)?;
    let mut z = vec![0.0; model.dim()];
    z[..4 * cells].copy_from_slice(&reference);
    z[4 * cells..4 * cells + 3].copy_from_slice(&[r0[0], r0[1], r0[2]]);
    if cells <= LEAST_SQUARES_MAX_CELLS {
        least_squares_multipliers(&model, &mut z)?;
    } else {
        let (cm, cz) = start_from_curvature(
            m.radius(),
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

/// Cell boundaries on the mesh map `map` with a node at each of `breaks` (sorted, in
/// `[0, 1)`, the first 0): piece `i` has `counts[i]` cells of equal length in the map's
/// uniform coordinate `u` ([`MeshMap::u_of_sigma`]), so the cells keep the map's grading
/// (finer at a stiffness transition) and halving every piece's cells halves every cell.
pub fn mapped_bounds(map: &MeshMap, breaks: &[f64], counts: &[usize]) -> Vec<f64> {
    let mut u = map.u_of_sigmas(breaks.iter().copied());
    u.push(1.0);
    let mut b = Vec::with_capacity(counts.iter().sum::<usize>() + 1);
    for (i, &c) in counts.iter().enumerate() {
        b.push(breaks[i]);
        b.extend((1..c).map(|k| map.sigma_of_u(u[i] + (u[i + 1] - u[i]) * k as f64 / c as f64)));
    }
    b.push(1.0);
    b
}

/// The start of `state` on the cell boundaries `bounds` with the same arclength origin:
/// curvature interpolated ([`EnclosedState::curvature_at`]), the same start point, gauge and
/// closure multipliers, wall impulses through the contact force density
/// ([`transfer_multipliers`]).
pub fn placed_start(
    state: &EnclosedState,
    bounds: Vec<f64>,
) -> Result<(EnclosedModel, Vec<f64>), SolverError> {
    let m = &state.model;
    let stiff = m.stiffness().kind().clone();
    let cells = bounds.len() - 1;
    let zero = Gauge {
        reference: vec![0.0; 4 * cells],
        slope: None,
        pin: m.gauge().pin,
    };
    let probe = EnclosedModel::with_bounds(m.radius(), m.lbar(), bounds.clone(), &stiff, zero)?;
    let reference = probe.sample_gauss(|s| state.curvature_at(s));
    let gauge = Gauge {
        reference: reference.clone(),
        slope: None,
        pin: m.gauge().pin,
    };
    let model = EnclosedModel::with_bounds(m.radius(), m.lbar(), bounds, &stiff, gauge)?
        .with_wall(m.wall().clone())?;
    let mut z = vec![0.0; model.dim()];
    z[..4 * cells].copy_from_slice(&reference);
    let r0 = m.start_point(&state.z);
    z[4 * cells..4 * cells + 3].copy_from_slice(&[r0[0], r0[1], r0[2]]);
    transfer_multipliers(m, &state.z, &model, &mut z);
    Ok((model, z))
}

/// Where the contacts of `state` begin and end (`σ`, sorted, the first 0, for
/// [`mapped_bounds`]): a contact on one or two nodes is a point (its node, or the lever
/// rule on the two, [`contact_points`]); a contact on three or more nodes is an arc, whose
/// ends are extrapolated from the gaps at the two nodes outside each end, `g ∝ (σ − σ_e)³`
/// (curvature continuous across the end, a point force at it: `g`, `g'`, `g''` vanish
/// there), and taken no farther out than the end node.
pub fn contact_breaks(state: &EnclosedState) -> Result<Vec<f64>, SolverError> {
    let m = &state.model;
    let n = m.cells() as isize;
    let gaps = m.gaps(&state.z)?;
    let b = m.bounds();
    // (σ unwrapped, cube root of the gap) at node j (any integer).
    let at = |j: isize| {
        let k = j.rem_euclid(n) as usize;
        (b[k] + j.div_euclid(n) as f64, gaps[k].max(0.0).cbrt())
    };
    let mut pts = Vec::new();
    for (nodes, lever) in contact_groups(state) {
        if nodes.len() <= 2 {
            pts.push(lever);
            continue;
        }
        let first = nodes[0] as isize;
        let mut last = nodes[nodes.len() - 1] as isize;
        if last < first {
            last += n;
        }
        let ((s1, t1), (s2, t2), (sf, _)) = (at(first - 1), at(first - 2), at(first));
        let start = if t2 > t1 {
            (s1 + t1 * (s1 - s2) / (t2 - t1)).min(sf)
        } else {
            sf
        };
        let ((s1, t1), (s2, t2), (sl, _)) = (at(last + 1), at(last + 2), at(last));
        let end = if t2 > t1 {
            (s1 - t1 * (s2 - s1) / (t2 - t1)).max(sl)
        } else {
            sl
        };
        pts.push(start);
        pts.push(end);
    }
    let mut breaks = vec![0.0];
    let mut moved: Vec<f64> = pts.into_iter().map(|p| p.rem_euclid(1.0)).collect();
    moved.sort_by(f64::total_cmp);
    for p in moved {
        if p - breaks.last().expect("0") > MIN_PIECE && 1.0 - p > MIN_PIECE {
            breaks.push(p);
        }
    }
    Ok(breaks)
}

/// Cells per piece between `breaks` for `cells` cells in all on the mesh map `map`: in
/// proportion to the pieces' lengths in `u`, at least one each.
fn mapped_counts(map: &MeshMap, breaks: &[f64], cells: usize) -> Option<Vec<usize>> {
    apportion(&map.u_of_sigmas(breaks.iter().copied()), cells)
}

/// `state` solved again on the mesh map of its stiffness profile with nodes at `breaks`,
/// `counts` cells per piece; the watchdog first, plain backtracking where it fails.
fn solve_placed(
    state: &EnclosedState,
    breaks: &[f64],
    counts: &[usize],
    opts: &EnclosedOptions,
) -> Option<EnclosedState> {
    let map = MeshMap::for_profile(state.model.stiffness().kind());
    let (model, z) = placed_start(state, mapped_bounds(&map, breaks, counts)).ok()?;
    let watchdog = EnclosedOptions {
        watchdog: opts.watchdog.max(2),
        ..opts.clone()
    };
    solve_enclosed(&model, z.clone(), &watchdog)
        .or_else(|_| solve_enclosed(&model, z, opts))
        .ok()
}

/// A ladder of meshes with a node at every contact point and contact end of `from`, for a
/// rod whose arclength origin is not a gauge (a non-uniform rod): the profile's mesh map
/// ([`mapped_bounds`]) with breakpoints from [`contact_breaks`], the cells of the pieces in
/// the proportion of a `coarsest`-cell mesh. The breakpoints are taken again from the
/// solution at each doubling from `2·coarsest` up to twice the finest level (each started
/// from the one before: a contact that the coarse mesh merges with an arc, a point contact
/// next to an arc's end, separates on the finer meshes), and the `levels` levels
/// `coarsest·2^k`, `k < levels`, are then solved on the last ones, each from the finest.
/// `None` where a solve fails.
pub fn placed_levels(
    from: &EnclosedState,
    coarsest: usize,
    levels: usize,
    opts: &EnclosedOptions,
) -> Option<Vec<EnclosedState>> {
    let map = MeshMap::for_profile(from.model.stiffness().kind());
    let top = coarsest << levels.checked_sub(1)?;
    let mut source = from.clone();
    let mut breaks = contact_breaks(&source).ok()?;
    let mut cells = 2 * coarsest;
    let mut moves = 0;
    while cells <= 2 * top {
        let counts: Vec<usize> = mapped_counts(&map, &breaks, coarsest)?
            .into_iter()
            .map(|c| c * (cells / coarsest))
            .collect();
        source = solve_placed(&source, &breaks, &counts, opts)?;
        breaks = contact_breaks(&source).ok()?;
        if cells < 2 * top || moves >= CENTRE_MOVES {
            cells *= 2;
        } else {
            moves += 1;
        }
    }
    let base = mapped_counts(&map, &breaks, coarsest)?;
    let mut out: Vec<EnclosedState> = Vec::with_capacity(levels);
    for k in (0..levels).rev() {
        let counts: Vec<usize> = base.iter().map(|c| c << k).collect();
        let level = solve_placed(&source, &breaks, &counts, opts)
            .or_else(|| solve_placed(out.last()?, &breaks, &counts, opts))?;
        if k == levels - 1 {
            source = level.clone();
        }
        out.push(level);
    }
    out.reverse();
    Some(out)
}
