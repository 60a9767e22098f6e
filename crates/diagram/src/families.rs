//! Tracing every family of branch `η` of a non-uniform rod (paper Sec. 5, Figs. 9, 10, S7).
//!
//! A two-segment rod (Eq. (51)) keeps only the mirror symmetry `σ ↦ s0* + s1* − σ` of its
//! stiffness profile, so branch `η` of the uniform rod (a circle of loops related by moving
//! the arclength origin) splits into *families* by where the soft segment sits on the shape:
//! mirror-symmetric families, and pairs of mirror-image asymmetric ones that meet the
//! symmetric families at pitchforks. In `L̄` a pitchfork seen from the asymmetric side is a
//! turning point.
//!
//! [`compute_families`]:
//!
//! 1. **Seeds**: the Euler rotation curve `l = η` (Eqs. 4–8) with its arclength origin moved
//!    by `j/(8η)` of the length (`j = 0…3`, half a period: a shift by half a period is the
//!    loop's reflection `κ_g → −κ_g`), relaxed and solved at three lengths inside the
//!    branch's range; a seed that lies on a family already traced (itself, its reflection,
//!    its mirror image or both) is dropped.
//! 2. **Following**: each new seed is followed in `L̄` in both directions *through* its
//!    folds ([`FoldPolicy::Follow`]) with simple branch points detected, until the range
//!    ends, the approach to a great-circle end (then `ends.rs` takes over down to
//!    [`DiagramOptions::end_distance`]), a closed loop or the step budget.
//! 3. **Switching**: at every branch point not met before, the second branch is followed in
//!    both directions ([`march_switch`]) unless its first point lies on a known family.
//! 4. **Sheets**: every followed curve is cut at its turning points into sheets monotone in
//!    `L̄` (one [`TracedBranch`] each, with its family, position along the family and
//!    direction); sheets that repeat a kept one (the mirror half of an asymmetric curve
//!    traced through its pitchfork) are dropped, and every asymmetric sheet gets
//!    multiplicity 2.
//!
//! Caps ([`MAX_FAMILIES`], [`MAX_SWITCHES`], the step budget) bound the work; reaching one is
//! reported as a note.

use std::time::Instant;

use rodloop_continuation::{Direction, SpecialKind};
use rodloop_exact::branch_of_eta;
use rodloop_solver::{
    solve, Confinement, Param, ParamProblem, SolveOptions, StartShape, Stiffness, SurfaceModel,
};

use crate::ends::{approach_end, SWITCH_DISTANCE};
use crate::march::{march, march_switch, FoldPolicy, MarchPoint, MarchSpecial, MarchStop};
use crate::parallel::run_parallel;
use crate::seed::periods_of;
use crate::states::finish_point;
use crate::trace::march_settings;
use crate::types::{BranchEnd, BranchTimings, IndexChange, PointSource, TracedBranch};
use crate::{DiagramError, DiagramOptions, Progress};

/// Most families (followed curves) per branch `η`.
pub const MAX_FAMILIES: usize = 16;
/// Most branch points switched at per branch `η`.
pub const MAX_SWITCHES: usize = 16;
/// Budget of continuation steps per followed direction.
const MAX_STEPS: usize = 600;
/// Width (arclength) to which the tracer locates folds, branch points and index changes.
const TRACE_LOCATE_TOL: f64 = 1e-6;
/// Distance (root-mean-square of `κ_g R`) below which two states count as the same.
const SAME_STATE: f64 = 0.03;

/// The traced sheets of branch `eta` and notes (caps reached, failed switches).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Families {
    /// The sheets, by family and position along it.
    pub sheets: Vec<TracedBranch>,
    /// Notes for the diagram's warnings.
    pub notes: Vec<String>,
}

/// A followed curve: its states in arclength order and how its two ends came about.
struct Curve {
    points: Vec<MarchPoint>,
    start_end: (BranchEnd, String),
    finish_end: (BranchEnd, String),
}

/// The symmetry images of a state's curvatures: the mirror axis of the profile.
struct Images {
    /// `σ` of the Gauss points (fraction of the length).
    sigma: Vec<f64>,
    /// `s0* + s1*` (mirror `σ ↦ axis − σ`), if the profile has a mirror axis.
    axis: Option<f64>,
    /// Shape unknowns.
    shape: usize,
    /// `R/√shape`: scaling to the root-mean-square of `κ_g R`.
    scale: f64,
}

impl Images {
    fn new(model: &SurfaceModel, stiffness: &Stiffness) -> Self {
        let shape = model.n_kappa();
        Self {
            sigma: model.gauss_sigma(),
            axis: match stiffness {
                Stiffness::Tanh { s0, s1, .. } => Some(s0 + s1),
                _ => None,
            },
            shape,
            scale: model.radius() / (shape as f64).sqrt(),
        }
    }

    /// `κ(axis − σ)` at the Gauss points (periodic linear interpolation).
    fn mirror(&self, kappa: &[f64]) -> Option<Vec<f64>> {
        let axis = self.axis?;
        let n = self.sigma.len();
        Some(
            self.sigma
                .iter()
                .map(|&s| {
                    let t = (axis - s).rem_euclid(1.0);
                    let k = self.sigma.partition_point(|&x| x <= t);
                    let (i0, i1) = ((k + n - 1) % n, k % n);
                    let (a, mut b) = (self.sigma[i0], self.sigma[i1]);
                    if b <= a {
                        b += 1.0;
                    }
                    let tt = if t < a { t + 1.0 } else { t };
                    let w = ((tt - a) / (b - a)).clamp(0.0, 1.0);
                    kappa[i0] + w * (kappa[i1] - kappa[i0])
                })
                .collect(),
        )
    }

    /// Root-mean-square of `(a − b) R` over the shape unknowns.
    fn dist(&self, a: &[f64], b: &[f64]) -> f64 {
        a[..self.shape]
            .iter()
            .zip(&b[..self.shape])
            .map(|(x, y)| (x - y) * (x - y))
            .sum::<f64>()
            .sqrt()
            * self.scale
    }

    /// Smallest distance of `b` to `a`, `−a`, `M a`, `−M a`.
    fn dist_images(&self, a: &[f64], b: &[f64]) -> f64 {
        let neg: Vec<f64> = a[..self.shape].iter().map(|v| -v).collect();
        let mut d = self.dist(a, b).min(self.dist(&neg, b));
        if let Some(m) = self.mirror(&a[..self.shape]) {
            let mneg: Vec<f64> = m.iter().map(|v| -v).collect();
            d = d.min(self.dist(&m, b)).min(self.dist(&mneg, b));
        }
        d
    }

    /// Whether the state equals its mirror image (up to the reflection `κ → −κ`); `true`
    /// for profiles without a mirror axis.
    fn symmetric(&self, a: &[f64]) -> bool {
        let Some(m) = self.mirror(&a[..self.shape]) else {
            return true;
        };
        let mneg: Vec<f64> = m.iter().map(|v| -v).collect();
        let tol = SAME_STATE * 0.5;
        self.dist(&m, a) < tol || self.dist(&mneg, a) < tol
    }
}

/// Whether `(x, p)` lies on one of `curves` (or on an image of one), within [`SAME_STATE`].
fn on_known(images: &Images, curves: &[Curve], x: &[f64], p: f64) -> bool {
    on_known_within(images, curves, x, p, SAME_STATE)
}

/// [`on_known`] with the distance `tol` instead of [`SAME_STATE`].
fn on_known_within(images: &Images, curves: &[Curve], x: &[f64], p: f64, tol: f64) -> bool {
    curves.iter().any(|c| {
        c.points.windows(2).any(|w| {
            let (a, b) = (&w[0], &w[1]);
            let (lo, hi) = (a.value.min(b.value), a.value.max(b.value));
            if p < lo - 1e-9 || p > hi + 1e-9 {
                return false;
            }
            let t = if hi > lo {
                (p - a.value) / (b.value - a.value)
            } else {
                0.0
            };
            let xi: Vec<f64> = a.x.iter().zip(&b.x).map(|(u, v)| u + t * (v - u)).collect();
            images.dist_images(&xi, x) < tol
        })
    })
}

/// Trace every family of branch `eta` of a non-uniform rod (see the module docs).
pub fn compute_families(
    opts: &DiagramOptions,
    eta: u32,
    progress: &mut dyn FnMut(Progress),
) -> Result<Families, DiagramError> {
    opts.validate()?;
    let t0 = Instant::now();
    let branch = branch_of_eta(eta);
    let e = f64::from(eta);
    let (exist_lo, exist_hi) = (if eta == 1 { 0.0 } else { e - 1.0 }, e + 1.0);
    if eta == 0 || !(exist_hi > opts.lbar_min && exist_lo < opts.lbar_max) {
        return Err(DiagramError::BranchOutOfRange {
            eta,
            lo: exist_lo,
            hi: exist_hi,
            lbar_min: opts.lbar_min,
            lbar_max: opts.lbar_max,
        });
    }
    progress(Progress::BranchStarted { branch, eta });
    let lo = opts.lbar_min.max(exist_lo);
    let hi = opts.lbar_max.min(exist_hi);
    let circles: Vec<f64> = [e - 1.0, e + 1.0]
        .into_iter()
        .filter(|&m| m >= 1.0 && m >= opts.lbar_min - 1e-12 && m <= opts.lbar_max + 1e-12)
        .collect();
    let cells = opts.trace_cells(eta);
    let mid = 0.5 * (lo + hi);
    let model = SurfaceModel::new(opts.radius, mid, cells, &opts.stiffness)?;
    let problem = ParamProblem::new(model.clone(), Param::Lbar)?;
    let images = Images::new(&model, &opts.stiffness);
    let shape = model.dim() - model.n_constraints();
    let mut settings = march_settings(opts, hi, shape);
    settings.folds = FoldPolicy::Follow;
    settings.detect_branch_points = true;
    settings.far_limit = Some(lo);
    settings.max_steps = MAX_STEPS;
    settings.ds_min = 1e-5;
    settings.circles = circles.clone();
    settings.circle_distance = SWITCH_DISTANCE;
    // Folds and branch points are located again at the reporting resolution
    // (`crate::special`): the tracer needs them only to its own width.
    settings.locate_tol = TRACE_LOCATE_TOL;

    let span = hi - lo;
    let seed_lengths: Vec<f64> = [0.5, 0.25, 0.75]
        .iter()
        .map(|f| lo + f * span)
        .filter(|l| {
            circles
                .iter()
                .all(|m| (l - m).abs() > 2.0 * SWITCH_DISTANCE)
        })
        .collect();
    let end_ctx = EndContext {
        opts,
        problem: &problem,
        lo,
        hi,
    };
    let mut tr = Tracing {
        ctx: &end_ctx,
        settings: &settings,
        images: &images,
        branch,
        eta,
        curves: Vec::new(),
        notes: Vec::new(),
        pending: Vec::new(),
        switched: Vec::new(),
        steps: 0,
        seed_note: Vec::new(),
    };
    let strong = matches!(&opts.stiffness, Stiffness::Tanh { d0, d1, .. }
        if d1 / d0 < HOMOTOPY_BELOW);
    let jobs = seed_jobs(
        &seed_lengths,
        eta,
        (exist_lo, exist_hi),
        (lo, hi),
        &circles,
        strong,
    );
    let seeds_tried = jobs.len();
    // Every seed is solved before any is followed, on the crate's thread pool: the seeds are
    // independent of each other and of the curves (which only decide whether a seed is
    // new).
    let solve_seed = |lbar: f64, seed: Seed| {
        let ts = Instant::now();
        let x = problem.model_at(lbar).ok().and_then(|m| match seed {
            Seed::Solve { starts } => robust_seed(opts, &m, eta, lbar, starts),
            Seed::Shifted(shift) => seed_state(opts, &m, eta, lbar, shift, strong),
            Seed::Direct(shift) => seed_state(opts, &m, eta, lbar, shift, false),
        });
        (x, ts.elapsed().as_secs_f64())
    };
    let solved = run_parallel(
        opts.worker_threads(),
        jobs.clone(),
        &mut |_| {},
        &mut |_| {},
        |(lbar, seed), _| solve_seed(lbar, seed),
    );
    let mut unsolved = Vec::new();
    for (&(lbar, seed), (seeded, secs)) in jobs.iter().zip(solved) {
        if seeded.is_none() && matches!(seed, Seed::Solve { .. }) {
            unsolved.push(lbar);
        }
        if !tr.take(lbar, seed, seeded, secs, progress)? {
            break;
        }
    }
    // At strong contrast, `solve`'s homotopies in D1/D0 where its starts failed, one length
    // at a time, and only where no traced family of the branch is stable yet: they cost
    // 0.3–1 s each and serve to find a state of the branch where none is known.
    for lbar in unsolved {
        if tr.stable_at(lbar) {
            debug(|| format!("eta {eta} at {lbar:.3}: a stable state is traced, no homotopy"));
            continue;
        }
        let seed = Seed::Solve { starts: false };
        let (seeded, secs) = solve_seed(lbar, seed);
        if !tr.take(lbar, seed, seeded, secs, progress)? {
            break;
        }
    }
    let Tracing {
        curves,
        notes,
        steps,
        seed_note,
        ..
    } = tr;
    if curves.is_empty() {
        return Err(DiagramError::Seed {
            eta,
            lbar: mid,
            source: rodloop_solver::SolverError::InvalidInput(format!(
                "none of the {seeds_tried} seeds (Euler starts, shifted, solved directly or by                  homotopy) converged to a loop with {eta} period(s) of κ_g"
            )),
        });
    }
    let t_trace = t0.elapsed().as_secs_f64();
    debug(|| format!("eta {eta}: traced in {t_trace:.3} s"));

    // Sheets.
    let mut sheets: Vec<TracedBranch> = Vec::new();
    let mut kept_states: Vec<(usize, Vec<f64>, f64)> = Vec::new();
    for (ci, curve) in curves.iter().enumerate() {
        let finished: Vec<_> = thinned(&images, &curve.points)
            .into_iter()
            .filter_map(|r| finish_point(opts, &problem, r).map(|p| (p, r.source)))
            .collect();
        let mut pieces = split_monotone(&finished);
        let count = pieces.len();
        for (k, piece) in pieces.drain(..).enumerate() {
            if piece.len() < 2 {
                continue;
            }
            let reversed = piece[0].0.value > piece[piece.len() - 1].0.value;
            let mut pts: Vec<_> = piece;
            if reversed {
                pts.reverse();
            }
            // Ends: the curve's own ends, or the turning point / branch point between sheets
            // (in arclength order first, then by L̄).
            let inner = |src: PointSource, value: f64| match src {
                PointSource::BranchPoint => (
                    BranchEnd::BranchPoint { value },
                    format!("branch point at L̄ = {value:.6}"),
                ),
                _ => (
                    BranchEnd::Fold { value },
                    format!("fold (turning point in L̄) at L̄ = {value:.6}"),
                ),
            };
            let (lo_v, hi_v) = (pts[0].0.value, pts[pts.len() - 1].0.value);
            let (arc_first, arc_last) = if reversed {
                ((pts[pts.len() - 1].1, hi_v), (pts[0].1, lo_v))
            } else {
                ((pts[0].1, lo_v), (pts[pts.len() - 1].1, hi_v))
            };
            let first_end = if k == 0 {
                curve.start_end.clone()
            } else {
                inner(arc_first.0, arc_first.1)
            };
            let last_end = if k + 1 == count {
                curve.finish_end.clone()
            } else {
                inner(arc_last.0, arc_last.1)
            };
            let ((low_end, stop_low), (high_end, stop_high)) = if reversed {
                (last_end, first_end)
            } else {
                (first_end, last_end)
            };
            fill_corrections(&mut pts);
            let index_changes = index_changes_of(&pts);
            let midk = pts.len() / 2;
            let mid_state = pts[midk].0.state.clone();
            let mid_value = pts[midk].0.value;
            // A repetition of a kept sheet (its mirror image, its reflection)?
            let duplicate = kept_states.iter().any(|(si, _, _)| {
                let s: &TracedBranch = &sheets[*si];
                let (a, b) = s.span();
                if !(a <= lo_v + 1e-6 && b >= hi_v - 1e-6) {
                    return false;
                }
                let z = s.state_near(mid_value);
                images.dist_images(&z, &mid_state) < SAME_STATE
            });
            if duplicate {
                continue;
            }
            let multiplicity = if images.symmetric(&mid_state) { 1 } else { 2 };
            let tb = TracedBranch {
                branch,
                eta,
                param: Param::Lbar,
                family: ci as u32 + 1,
                sheet: k as u32,
                reversed,
                multiplicity,
                fingerprint: opts.fingerprint(),
                cells,
                phase: false,
                points: pts.into_iter().map(|(p, _)| p).collect(),
                low_end,
                high_end,
                stop_low,
                stop_high,
                seed: format!(
                    "family {} of branch {branch}: {}",
                    ci + 1,
                    seed_note
                        .get(ci)
                        .cloned()
                        .flatten()
                        .unwrap_or_else(|| "found by branch switching".into())
                ),
                index_changes,
                steps: 0,
                seconds: 0.0,
                timings: BranchTimings::default(),
            };
            kept_states.push((sheets.len(), mid_state, mid_value));
            sheets.push(tb);
        }
    }
    // Families numbered 1, 2, … in the order kept.
    let mut map: Vec<u32> = Vec::new();
    for s in &mut sheets {
        let pos = match map.iter().position(|&f| f == s.family) {
            Some(p) => p,
            None => {
                map.push(s.family);
                map.len() - 1
            }
        };
        s.family = pos as u32 + 1;
    }
    let seconds = t0.elapsed().as_secs_f64();
    debug(|| {
        format!(
            "eta {eta}: {} sheets of {} states in {:.3} s",
            sheets.len(),
            sheets.iter().map(|s| s.points.len()).sum::<usize>(),
            seconds - t_trace
        )
    });
    let count = sheets.len().max(1);
    for s in &mut sheets {
        s.steps = steps / count;
        s.seconds = seconds / count as f64;
        s.timings = BranchTimings {
            seed: 0.0,
            continuation: t_trace / count as f64,
            end_approach: 0.0,
            states: (seconds - t_trace) / count as f64,
        };
    }
    progress(Progress::BranchFinished {
        branch,
        eta,
        points: sheets.iter().map(|s| s.points.len()).sum(),
        seconds,
    });
    Ok(Families { sheets, notes })
}

/// States of a sheet whose half-resolution partner failed (no `energy_error`; typically
/// right next to a branch point) get the Richardson correction `energy − energy_trace` of
/// the nearest state of the sheet that has one, so that the sheet's energies are of one
/// kind (a jump of the correction, ~10⁻⁴, would read as a kink). `energy_error` stays
/// `None`: these energies have no estimate of their own.
fn fill_corrections(pts: &mut [(crate::TracedPoint, PointSource)]) {
    let with: Vec<(f64, f64)> = pts
        .iter()
        .filter(|p| p.0.energy_error.is_some())
        .map(|p| (p.0.value, p.0.energy - p.0.energy_trace))
        .collect();
    if with.is_empty() {
        return;
    }
    for p in pts.iter_mut().filter(|p| p.0.energy_error.is_none()) {
        let v = p.0.value;
        let corr = with
            .iter()
            .min_by(|a, b| (a.0 - v).abs().total_cmp(&(b.0 - v).abs()))
            .map_or(0.0, |c| c.1);
        p.0.energy = p.0.energy_trace + corr;
    }
}

/// Index changes between consecutive states of a sheet (increasing `L̄`), placed midway.
fn index_changes_of(pts: &[(crate::TracedPoint, PointSource)]) -> Vec<IndexChange> {
    pts.windows(2)
        .filter(|w| w[0].0.index != w[1].0.index)
        .map(|w| IndexChange {
            value: if w[1].1 == PointSource::IndexChange {
                w[1].0.value
            } else {
                w[0].0.value
            },
            below: w[0].0.index,
            above: w[1].0.index,
        })
        .collect()
}

/// Least spacing in `L̄` of the continuation states a sheet keeps ([`thinned`]).
const MIN_SPACING: f64 = 5e-4;

/// The states of a curve that become sheet states: all but the continuation states closer
/// than [`MIN_SPACING`] in `L̄` and than `SAME_STATE` in shape to the previous one kept
/// (where a family creeps through a nearly singular stretch, e.g. branch 2 at
/// `D1/D0 = 0.001` near `L̄ = 1.1` with 400 steps in 0.025, those would be most of the
/// diagram's states); located points, the ends and the turning states in `L̄` are always
/// kept.
fn thinned<'p>(images: &Images, points: &'p [MarchPoint]) -> Vec<&'p MarchPoint> {
    let n = points.len();
    let mut out: Vec<&MarchPoint> = Vec::with_capacity(n);
    for (i, p) in points.iter().enumerate() {
        let keep = match out.last() {
            None => true,
            Some(last) => {
                let turning = i + 1 < n
                    && i > 0
                    && (points[i + 1].value - p.value) * (p.value - points[i - 1].value) <= 0.0;
                p.source != PointSource::Continuation
                    || i + 1 == n
                    || turning
                    || (p.value - last.value).abs() >= MIN_SPACING
                    || images.dist(&p.x, &last.x) >= SAME_STATE
            }
        };
        if keep {
            out.push(p);
        }
    }
    out
}

/// Cut a curve (arclength order) into pieces monotone in `L̄`; the turning state belongs
/// to both pieces.
fn split_monotone(
    pts: &[(crate::TracedPoint, PointSource)],
) -> Vec<Vec<(crate::TracedPoint, PointSource)>> {
    let mut out: Vec<Vec<_>> = Vec::new();
    let mut cur: Vec<(crate::TracedPoint, PointSource)> = Vec::new();
    let mut dir = 0.0f64;
    for p in pts {
        if let Some(last) = cur.last() {
            let d = p.0.value - last.0.value;
            if d.abs() <= 1e-13 * p.0.value.abs().max(1.0) {
                // Same length (a located point repeated): keep the located one.
                if p.1 != PointSource::Continuation {
                    cur.pop();
                    cur.push(p.clone());
                }
                continue;
            }
            let s = d.signum();
            if dir != 0.0 && s != dir {
                let turn = cur.last().cloned().expect("non-empty");
                out.push(std::mem::take(&mut cur));
                cur.push(turn);
            }
            dir = s;
        }
        cur.push(p.clone());
    }
    if !cur.is_empty() {
        out.push(cur);
    }
    out
}

/// How a seed state is found.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Seed {
    /// The state `rodloop solve --branch` finds ([`robust_seed`]); without `starts`, only
    /// by its homotopies in `D1/D0` (its direct and shifted starts failed before).
    Solve { starts: bool },
    /// The Euler start with its origin moved by the fraction given, solved directly or at
    /// strong contrast through a homotopy in `D1/D0` ([`seed_state`]).
    Shifted(f64),
    /// The same start solved directly at any contrast.
    Direct(f64),
}

/// The seeds of branch `eta` (existence interval `exist`, traced on `range`), in the order
/// they are followed.
///
/// At mild contrast, the Euler start `l = η` with its origin moved by `j/(8η)` (`j = 0…3`)
/// at each of `lengths`. At strong contrast (`strong`) the state `rodloop solve --branch`
/// finds at each of `lengths` (its direct and shifted starts and its homotopies in `D1/D0`)
/// and, where `solve` would follow a family in `L̄` from another length of the branch's
/// existence interval (its last fallback; [`rodloop_solver::Fallbacks::lbar_path`]), the
/// direct solves from the eight shifted starts it uses there, if that length lies in the
/// range: the tracer follows those families in `L̄` itself. (The range end `L̄ = 1` of
/// branch 2 is such a length: the family of `η = 1` that exists only on `1 ≤ L̄ < 1.045` at
/// `D1/D0 = 0.001` is found there.)
fn seed_jobs(
    lengths: &[f64],
    eta: u32,
    exist: (f64, f64),
    range: (f64, f64),
    circles: &[f64],
    strong: bool,
) -> Vec<(f64, Seed)> {
    let e = f64::from(eta);
    if !strong {
        return lengths
            .iter()
            .flat_map(|&l| (0..4).map(move |j| (l, Seed::Shifted(j as f64 / (8.0 * e)))))
            .collect();
    }
    let mut jobs: Vec<(f64, Seed)> = lengths
        .iter()
        .map(|&l| (l, Seed::Solve { starts: true }))
        .collect();
    let per = 1.0 / e;
    for f in [0.5, 0.25, 0.75] {
        let l = exist.0 + f * (exist.1 - exist.0);
        let inside = l >= range.0 - 1e-12 && l <= range.1 + 1e-12;
        let seeded = lengths.iter().any(|&s| (s - l).abs() < 1e-9);
        let near_circle = circles
            .iter()
            .any(|m| (l - m).abs() <= 2.0 * SWITCH_DISTANCE);
        if inside && !seeded && !near_circle {
            jobs.extend((0..8).map(|j| (l, Seed::Direct(j as f64 / 8.0 * per))));
        }
    }
    jobs
}

/// The followed curves of a branch and what following them needs.
struct Tracing<'a> {
    ctx: &'a EndContext<'a>,
    settings: &'a crate::MarchSettings,
    images: &'a Images,
    branch: u32,
    eta: u32,
    curves: Vec<Curve>,
    notes: Vec<String>,
    /// Branch points met and not yet switched at.
    pending: Vec<MarchSpecial>,
    /// Branch points switched at.
    switched: Vec<MarchSpecial>,
    steps: usize,
    /// The seed of each followed curve (`None`: found by branch switching).
    seed_note: Vec<Option<String>>,
}

impl Tracing<'_> {
    /// Follow the state `seeded` (solved at `lbar` as `seed` in `secs` seconds) unless it
    /// is missing or on a known curve, then switch at every new branch point (a later seed
    /// may lie on a family found by switching). `false` once the cap of followed curves is
    /// reached.
    fn take(
        &mut self,
        lbar: f64,
        seed: Seed,
        seeded: Option<Vec<f64>>,
        secs: f64,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<bool, DiagramError> {
        let (branch, eta) = (self.branch, self.eta);
        let what = match seed {
            Seed::Shifted(shift) | Seed::Direct(shift) => format!("origin moved by {shift:.4}"),
            Seed::Solve { .. } => "as `rodloop solve` finds it".to_string(),
        };
        debug(|| {
            format!(
                "eta {eta} seed at {lbar:.3} ({what}): {} in {secs:.3} s",
                seeded.is_some(),
            )
        });
        let Some(x0) = seeded else {
            return Ok(true);
        };
        if on_known(self.images, &self.curves, &x0, lbar) {
            return Ok(true);
        }
        if self.curves.len() >= MAX_FAMILIES {
            self.notes.push(format!(
                "branch {branch} (η = {eta}): the cap of {MAX_FAMILIES} followed curves was \
                 reached; further seeds were not followed"
            ));
            return Ok(false);
        }
        let ts = Instant::now();
        let curve = follow_seed(
            self.ctx,
            self.settings,
            &x0,
            lbar,
            &mut self.pending,
            &mut self.steps,
        )?;
        let (cmin, cmax) = curve
            .points
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
                (a.min(p.value), b.max(p.value))
            });
        if cmax - cmin < 1e-3 {
            self.notes.push(format!(
                "branch {branch} (η = {eta}): a seed at L̄ = {lbar:.4} ({what}) could not be \
                 followed ({}; {}): left out",
                curve.start_end.1, curve.finish_end.1
            ));
            return Ok(true);
        }
        debug(|| {
            format!(
                "eta {eta} followed seed: {} points on {cmin:.4}–{cmax:.4} in {:.3} s",
                curve.points.len(),
                ts.elapsed().as_secs_f64()
            )
        });
        self.seed_note.resize(self.curves.len(), None);
        self.seed_note.push(Some(format!("L̄ = {lbar:.4}, {what}")));
        self.curves.push(curve);
        progress(Progress::BranchStep {
            eta,
            lbar,
            steps: self.steps,
        });
        switch_all(
            self.ctx,
            self.settings,
            self.images,
            &mut self.curves,
            &mut self.pending,
            &mut self.switched,
            &mut self.notes,
            &mut self.steps,
        );
        Ok(true)
    }

    /// Whether a followed curve has a stable (index 0) state at `lbar`: the states on
    /// either side of it on some curve both have index 0.
    fn stable_at(&self, lbar: f64) -> bool {
        self.curves.iter().any(|c| {
            c.points.windows(2).any(|w| {
                let (lo, hi) = (w[0].value.min(w[1].value), w[0].value.max(w[1].value));
                lo <= lbar && lbar <= hi && w[0].index == Some(0) && w[1].index == Some(0)
            })
        })
    }
}

/// What the ends of followed curves need.
struct EndContext<'a> {
    opts: &'a DiagramOptions,
    problem: &'a ParamProblem<SurfaceModel>,
    lo: f64,
    hi: f64,
}

/// The state `rodloop solve --branch` finds for `eta` at `lbar` (`solve_robust` from the
/// Euler curve, fast accuracy), re-solved on `model` (the tracing resolution). Without
/// `rodloop solve`'s continuation in `L̄` (the tracer follows those families itself,
/// [`seed_jobs`]); with `starts`, its direct and shifted starts only, without, its
/// homotopies in `D1/D0` only.
fn robust_seed(
    opts: &DiagramOptions,
    model: &SurfaceModel,
    eta: u32,
    lbar: f64,
    starts: bool,
) -> Option<Vec<f64>> {
    let (acc, strategy) = rodloop_solver::solve_robust_with(
        opts.radius,
        lbar,
        &opts.stiffness,
        &StartShape::Euler { l: eta },
        rodloop_solver::Accuracy::Fast,
        Some(eta),
        &SolveOptions::default(),
        rodloop_solver::Fallbacks {
            starts,
            homotopy: !starts,
            lbar_path: false,
            ..rodloop_solver::Fallbacks::default()
        },
    )
    .map_err(|e| debug(|| format!("robust seed {eta} at {lbar}: {e}")))
    .ok()?;
    debug(|| format!("robust seed {eta} at {lbar}: {}", strategy.describe()));
    let kappa = acc.equilibrium.resample(model.cells()).ok()?;
    solve(model, &kappa, &crate::states::newton_options())
        .ok()
        .map(|eq| eq.state())
}

/// Contrast `D1/D0` below which seeds come from a mild contrast by continuation in `D1/D0`
/// (direct solves from Euler starts rarely converge there).
const HOMOTOPY_BELOW: f64 = crate::STRONG_CONTRAST;
/// The mild contrast of those continuations.
const MILD_CONTRAST: f64 = 0.5;

/// The state of an Euler start of `eta` periods with its origin moved by `shift`, relaxed
/// and solved on `model` (the tracing resolution), if it has `eta` periods of `κ_g`. With
/// `homotopy` (used at strong contrast, `D1/D0 <` [`HOMOTOPY_BELOW`]) the start is solved
/// at [`MILD_CONTRAST`] and followed in `D1/D0` to the scene's value (the state is dropped
/// if the family folds back in `D1/D0` before it).
fn seed_state(
    opts: &DiagramOptions,
    model: &SurfaceModel,
    eta: u32,
    lbar: f64,
    shift: f64,
    homotopy: bool,
) -> Option<Vec<f64>> {
    let start = StartShape::Euler { l: eta }.shifted(lbar, shift).ok()?;
    let contrast = match &opts.stiffness {
        Stiffness::Tanh { d0, d1, .. } => d1 / d0,
        _ => 1.0,
    };
    if !homotopy || contrast >= MILD_CONTRAST {
        let kappa = start.gauss_values(model).ok()?;
        let eq = solve(model, &kappa, &SolveOptions::default())
            .map_err(|e| debug(|| format!("seed solve failed: {e}")))
            .ok()?;
        return (periods_of(&eq).ok()? == eta as usize).then(|| eq.state());
    }
    let mild = opts.stiffness.with_param(Param::D1, MILD_CONTRAST).ok()?;
    let mild_model = SurfaceModel::new(opts.radius, lbar, model.cells(), &mild).ok()?;
    let kappa = start.gauss_values(&mild_model).ok()?;
    let eq = solve(&mild_model, &kappa, &SolveOptions::default())
        .map_err(|e| debug(|| format!("mild seed solve failed: {e}")))
        .ok()?;
    if periods_of(&eq).ok()? != eta as usize {
        return None;
    }
    let problem = ParamProblem::new(mild_model, Param::D1).ok()?;
    let shape = model.dim() - model.n_constraints();
    let mut settings = march_settings(opts, contrast, shape);
    settings.ds_min = 1e-6;
    settings.max_steps = MAX_STEPS;
    let run = march(
        &problem,
        &eq.state(),
        MILD_CONTRAST,
        &settings,
        &mut |_, _| {},
    )
    .ok()?;
    debug(|| {
        format!(
            "homotopy in D1/D0: {} steps, {:?}",
            run.steps,
            run.stop.clone()
        )
    });
    let last = run.points.last()?;
    if run.stop != MarchStop::Reached || (last.value - contrast).abs() > 1e-12 {
        return None;
    }
    let eq = rodloop_solver::solve_from_state(
        model.clone(),
        last.x.clone(),
        &crate::states::newton_options(),
    )
    .map_err(|e| debug(|| format!("after the homotopy: {e}")))
    .ok()?;
    let periods = periods_of(&eq);
    debug(|| format!("after the homotopy: periods {periods:?}"));
    (periods.ok()? == eta as usize).then(|| eq.state())
}

/// Follow a seed both ways; branch points go to `pending`.
fn follow_seed(
    ctx: &EndContext<'_>,
    settings: &crate::MarchSettings,
    x0: &[f64],
    p0: f64,
    pending: &mut Vec<MarchSpecial>,
    steps: &mut usize,
) -> Result<Curve, DiagramError> {
    let cont = |e: rodloop_solver::SolverError| DiagramError::Continuation {
        eta: 0,
        reason: e.to_string(),
    };
    let mut up_s = settings.clone();
    up_s.limit = ctx.hi;
    up_s.far_limit = Some(ctx.lo);
    let up = march(ctx.problem, x0, p0, &up_s, &mut |_, _| {}).map_err(cont)?;
    *steps += up.steps;
    pending.extend(up.branch_points().cloned());
    let start = MarchPoint {
        x: x0.to_vec(),
        value: p0,
        index: None,
        source: PointSource::Seed,
    };
    if up.stop == MarchStop::ClosedLoop {
        let mut points = vec![start];
        points.extend(up.points);
        let e = (
            BranchEnd::Range { value: p0 },
            "the family closes on itself (a loop in the diagram)".to_string(),
        );
        return Ok(Curve {
            points,
            start_end: e.clone(),
            finish_end: e,
        });
    }
    let mut down_s = settings.clone();
    down_s.limit = ctx.lo;
    down_s.far_limit = Some(ctx.hi);
    let down = march(ctx.problem, x0, p0, &down_s, &mut |_, _| {}).map_err(cont)?;
    *steps += down.steps;
    pending.extend(down.branch_points().cloned());
    let mut down_pts = down.points;
    let start_end = finish_end(ctx, &down.stop, &mut down_pts, (x0, p0));
    let mut up_pts = up.points;
    let finish = finish_end(ctx, &up.stop, &mut up_pts, (x0, p0));
    let mut points: Vec<MarchPoint> = down_pts.into_iter().rev().collect();
    points.push(start);
    points.extend(up_pts);
    Ok(Curve {
        points,
        start_end,
        finish_end: finish,
    })
}

/// The end of a followed direction: the approach to a great circle where the march stopped
/// near one, else the record of why it stopped.
fn finish_end(
    ctx: &EndContext<'_>,
    stop: &MarchStop,
    points: &mut Vec<MarchPoint>,
    start: (&[f64], f64),
) -> (BranchEnd, String) {
    let last = points.last().map_or(start.1, |p| p.value);
    match stop {
        MarchStop::Reached => {
            let at = if (last - ctx.lo).abs() < (last - ctx.hi).abs() {
                ctx.lo
            } else {
                ctx.hi
            };
            (
                BranchEnd::Range { value: last },
                format!("stopped at L̄ = {at}, an end of the diagram's range"),
            )
        }
        MarchStop::NearCircle { circle, .. } => {
            let m = *circle;
            let d = ctx.opts.end_distance;
            let side = if last > m { 1.0 } else { -1.0 };
            let target = m + side * d;
            let mut chain: Vec<(Vec<f64>, f64)> = Vec::new();
            if points.len() < 2 {
                chain.push((start.0.to_vec(), start.1));
            }
            chain.extend(
                points
                    .iter()
                    .rev()
                    .take(3)
                    .rev()
                    .map(|r| (r.x.clone(), r.value)),
            );
            let found = approach_end(ctx.problem, &chain, m, target);
            for (x, p) in found.points {
                let index = ctx
                    .problem
                    .model_at(p)
                    .and_then(|model| model.index(&x, crate::states::INDEX_TOLERANCE))
                    .ok();
                points.push(MarchPoint {
                    x,
                    value: p,
                    index,
                    source: PointSource::EndApproach,
                });
            }
            let last = points.last().map_or(start.1, |p| p.value);
            match found.failure {
                None => (
                    BranchEnd::GreatCircle {
                        m: m.round() as u32,
                        value: last,
                        distance: (last - m).abs(),
                    },
                    format!(
                        "stopped at L̄ = {last:.6}, {:.1e} from the {}-fold great circle, where \
                         the family ends (the loop collapses onto it)",
                        (last - m).abs(),
                        m
                    ),
                ),
                Some(reason) => (
                    BranchEnd::Failed {
                        value: last,
                        target,
                        reason: reason.clone(),
                    },
                    format!("stopped at L̄ = {last:.6} approaching L̄ = {m}: {reason}"),
                ),
            }
        }
        other => {
            let reason = match other {
                MarchStop::StepTooSmall { ds, value, cause } => format!(
                    "the continuation step fell below its minimum ({ds:.1e}) at L̄ = {value:.6}{}",
                    cause
                        .as_ref()
                        .map(|c| format!(" ({c})"))
                        .unwrap_or_default()
                ),
                MarchStop::MaxSteps => {
                    format!("the continuation used up its budget of {MAX_STEPS} steps")
                }
                MarchStop::ClosedLoop => "the family closes on itself".into(),
                _ => "stopped".into(),
            };
            let failed = !matches!(other, MarchStop::ClosedLoop);
            (
                if failed {
                    BranchEnd::Failed {
                        value: last,
                        target: f64::NAN,
                        reason: reason.clone(),
                    }
                } else {
                    BranchEnd::Range { value: last }
                },
                format!("stopped at L̄ = {last:.6}: {reason}"),
            )
        }
    }
}

/// Switch at every pending branch point not met before, following the new curves (whose
/// branch points join the queue).
#[allow(clippy::too_many_arguments)]
fn switch_all(
    ctx: &EndContext<'_>,
    settings: &crate::MarchSettings,
    images: &Images,
    curves: &mut Vec<Curve>,
    pending: &mut Vec<MarchSpecial>,
    switched: &mut Vec<MarchSpecial>,
    notes: &mut Vec<String>,
    steps: &mut usize,
) {
    while let Some(bp) = pending.pop() {
        if bp.kind != SpecialKind::BranchPoint {
            continue;
        }
        let seen = switched.iter().any(|s| {
            (s.value - bp.value).abs() < 1e-5 && images.dist_images(&s.x, &bp.x) < SAME_STATE
        });
        if seen {
            continue;
        }
        if switched.len() >= MAX_SWITCHES {
            notes.push(format!(
                "the cap of {MAX_SWITCHES} branch points switched at was reached (branch point \
                 at L̄ = {:.6} not followed)",
                bp.value
            ));
            pending.clear();
            break;
        }
        switched.push(bp.clone());
        // Both branches through it already known (two followed curves pass through it).
        let through = curves
            .iter()
            .filter(|c| on_known(images, std::slice::from_ref(*c), &bp.x, bp.value))
            .count();
        if through >= 2 {
            continue;
        }
        let bp_symmetric = images.symmetric(&bp.x);
        for dir in [Direction::Forward, Direction::Backward] {
            if curves.len() >= MAX_FAMILIES {
                notes.push(format!(
                    "the cap of {MAX_FAMILIES} followed curves was reached at the branch point \
                     at L̄ = {:.6}",
                    bp.value
                ));
                break;
            }
            // The first point off the branch point is one step (or less) away from it: it
            // lies on a known curve only if much closer to that curve than to the branch
            // point (near a great circle, or after a shortened first step, distinct
            // branches are closer than SAME_STATE).
            let known = |x: &[f64], p: f64| {
                let tol = SAME_STATE.min(0.3 * images.dist(x, &bp.x));
                on_known_within(images, curves, x, p, tol)
            };
            let mut s = settings.clone();
            s.limit = ctx.hi;
            s.far_limit = Some(ctx.lo);
            let ts = Instant::now();
            let run = march_switch(ctx.problem, &bp, dir, &s, &known, &mut |_, _| {});
            debug(|| {
                format!(
                    "switch at {:.5} {dir:?}: {:?} in {:.3} s",
                    bp.value,
                    run.as_ref()
                        .map(|r| (
                            r.points.len(),
                            r.stop.clone(),
                            r.points
                                .iter()
                                .map(|p| p.value)
                                .fold(f64::INFINITY, f64::min),
                            r.points
                                .iter()
                                .map(|p| p.value)
                                .fold(f64::NEG_INFINITY, f64::max),
                            r.special.len(),
                            r.points.iter().filter_map(|p| p.index).max(),
                        ))
                        .map_err(|e| e.to_string()),
                    ts.elapsed().as_secs_f64()
                )
            });
            let run = match run {
                Ok(r) => r,
                Err(e) => {
                    notes.push(format!(
                        "branch switching at the branch point at L̄ = {:.6} failed: {e}",
                        bp.value
                    ));
                    continue;
                }
            };
            if run.stop == MarchStop::Known {
                continue;
            }
            // From a symmetric branch point onto an asymmetric branch: the other direction
            // is its mirror image.
            let mirror_pair =
                bp_symmetric && run.points.get(1).is_some_and(|p| !images.symmetric(&p.x));
            *steps += run.steps;
            for b in run.branch_points() {
                if (b.value - bp.value).abs() > 1e-6 {
                    pending.push(b.clone());
                }
            }
            let mut pts = run.points;
            let bp_end = (
                BranchEnd::BranchPoint { value: bp.value },
                format!("branch point at L̄ = {:.6}", bp.value),
            );
            let end = finish_end(ctx, &run.stop, &mut pts, (&bp.x, bp.value));
            curves.push(Curve {
                points: pts,
                start_end: bp_end,
                finish_end: end,
            });
            if mirror_pair {
                break;
            }
        }
    }
}

/// Diagnostics on stderr when `RODLOOP_DEBUG_FAMILIES` is set.
fn debug(msg: impl FnOnce() -> String) {
    if std::env::var_os("RODLOOP_DEBUG_FAMILIES").is_some() {
        eprintln!("[families] {}", msg());
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::TracedPoint;

    fn pt(value: f64, src: PointSource) -> (TracedPoint, PointSource) {
        (
            TracedPoint {
                value,
                energy: value,
                energy_g: 0.0,
                energy_error: None,
                energy_trace: value,
                slope: 1.0,
                index: 0,
                lambda_min: 0.0,
                lambda_max: 0.0,
                amplitude: 0.0,
                source: src,
                state: vec![],
            },
            src,
        )
    }

    /// A curve up to a fold, back down past the start, and up again is three monotone
    /// pieces sharing their turning states.
    #[test]
    fn split_at_turning_points() {
        let c = PointSource::Continuation;
        let pts: Vec<_> = [1.0, 1.2, 1.4, 1.3, 1.1, 0.9, 1.0, 1.5]
            .iter()
            .map(|&v| pt(v, c))
            .collect();
        let pieces = split_monotone(&pts);
        let values: Vec<Vec<f64>> = pieces
            .iter()
            .map(|p| p.iter().map(|q| q.0.value).collect())
            .collect();
        assert_eq!(
            values,
            vec![
                vec![1.0, 1.2, 1.4],
                vec![1.4, 1.3, 1.1, 0.9],
                vec![0.9, 1.0, 1.5]
            ]
        );
    }
}
