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
//! 1. **Seeds** (`seeding.rs`): the uniform rod's exact loop of `η` periods at every
//!    placement where a family leaves the uniform circle of loops as `D1/D0` departs from 1
//!    (the critical points of the placed loop's energy on the scene's profile,
//!    `crate::placements::PlacedProfile::placements`), continued in `ln(D1/D0)` from 0 to the
//!    scene's contrast by pseudo-arclength; and the Euler rotation curve `l = η`
//!    (Eqs. 4–8) with the stiffness change `s0*` at the phases `j/(8η)` (`j = 0…3`) of its
//!    `κ_g`, solved directly. The range is cut into stretches over which the number of
//!    these placements is the same; each placement is seeded at the length nearest its
//!    stretch's middle where its continuation converges, the Euler starts at the middle,
//!    at the stretch's two ends (where families are born in pairs or cut by the range) and
//!    at any length where no open placement converges. Where no seed converges anywhere, the states
//!    `rodloop solve --branch` finds at the stretches' middles. A seed that lies on
//!    a family already traced (itself, its reflection, its mirror image or both;
//!    `images.rs`) is dropped.
//! 2. **Following** (`following.rs`): each new seed is followed in `L̄` in both directions
//!    *through* its folds ([`FoldPolicy::Follow`]) with simple branch points detected, until
//!    the range ends, the approach to a great-circle end (then `ends.rs` takes over down to
//!    [`DiagramOptions::end_distance`]), a closed loop, the step budget, or the point where
//!    it goes on as a symmetry image of a traced curve or of its own earlier part
//!    (`images.rs`, `image_match`): an asymmetric family that passes
//!    through a pitchfork into its own mirror image is cut back to the pitchfork, so that a
//!    closed loop made of images of one sheet is traced once.
//! 3. **Switching** (`following.rs`): at every branch point not met before, the second
//!    branch is followed in both directions ([`march_switch`](crate::march::march_switch))
//!    unless its first point lies on a known family; a switch that runs onto an image of a
//!    known family is dropped. The two halves followed from one branch point are one
//!    family, joined in arclength order through the branch point (a mirror-symmetric family
//!    crossing an asymmetric one at its pitchfork is reached there and runs on both sides).
//! 4. **Sheets** (`sheets.rs`): every followed curve is cut at its turning points into sheets
//!    monotone in `L̄` (one [`TracedBranch`] each, with its family, position along the family
//!    and direction); sheets that repeat a kept one (the mirror half of an asymmetric curve
//!    traced through its pitchfork) are dropped, and every asymmetric sheet gets
//!    multiplicity 2.
//!
//! Caps ([`MAX_FAMILIES`], [`MAX_SWITCHES`], the step budget) bound the work; reaching one is
//! reported as a note.
//!
//! [`extend_families`] follows further seeds the same way, given the sheets traced so far:
//! the diagram's completeness certificate (`crate::certificate`) hands it the states its
//! search finds below the traced ones.

mod following;
mod images;
mod seeding;
mod sheets;

use std::time::Instant;

use rodloop_exact::branch_of_eta;
use rodloop_solver::{Confinement, Param, ParamProblem, SurfaceSolve};

use crate::ends::SWITCH_DISTANCE;
use crate::march::{FoldPolicy, MarchPoint};
use crate::parallel::run_parallel;
use crate::trace::march_settings;
use crate::types::{BranchEnd, BranchTimings, TracedBranch};
use crate::{DiagramError, DiagramOptions, Progress};
use following::{EndContext, Tracing};
use images::Images;
use seeding::{
    euler_jobs, robust_seed, seed_lengths, seed_state, uniform_jobs, uniform_seed, Seed,
};

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

/// Trace every family of branch `eta` of a non-uniform rod (see the module docs).
pub fn compute_families(
    opts: &DiagramOptions,
    eta: u32,
    progress: &mut dyn FnMut(Progress),
) -> Result<Families, DiagramError> {
    opts.validate()?;
    let t0 = Instant::now();
    let su = setup(opts, eta)?;
    let branch = su.branch;
    progress(Progress::BranchStarted { branch, eta });
    let (lo, hi, mid, cells) = (su.lo, su.hi, su.mid, su.cells);
    let circles = su.settings.circles.clone();
    let (problem, images, settings) = (&su.problem, &su.images, &su.settings);

    let end_ctx = su.end_context(opts);
    let mut tr = Tracing {
        ctx: &end_ctx,
        settings,
        images,
        branch,
        eta,
        curves: Vec::new(),
        notes: Vec::new(),
        pending: Vec::new(),
        switched: Vec::new(),
        steps: 0,
        seed_note: Vec::new(),
    };
    let stretches = seed_lengths(&opts.stiffness, eta, (lo, hi), &circles);
    let mut seeds_tried = 0;
    // Every seed of a length is solved before any is followed, on the crate's thread pool:
    // the seeds are independent of each other and of the curves (which only decide whether
    // a seed is new).
    let solve_seed = |lbar: f64, seed: Seed| {
        let ts = Instant::now();
        let x = problem.model_at(lbar).ok().and_then(|m| match seed {
            Seed::Solve { starts } => robust_seed(opts, &m, eta, lbar, starts),
            Seed::Uniform(shift) => uniform_seed(&m, &opts.stiffness, eta, lbar, shift),
            Seed::Shifted(shift) => seed_state(&m, eta, lbar, shift),
            Seed::Found => None,
        });
        (x, ts.elapsed().as_secs_f64())
    };
    // Each placement of a stretch is seeded at the length nearest the stretch's middle where
    // its continuation from the uniform rod reaches the scene's contrast with `η` periods;
    // the Euler starts at the middle, and at a length where none of the placements still
    // open converges (until one converges).
    'stretches: for stretch in &stretches {
        let mut open: Option<Vec<usize>> = None;
        let mut euler_found = false;
        for (li, (l, placements)) in stretch.iter().enumerate() {
            let l = *l;
            let uniform = uniform_jobs(l, placements);
            let euler = euler_jobs(&opts.stiffness, eta, l);
            let idx: Vec<usize> = open
                .clone()
                .unwrap_or_else(|| (0..uniform.len()).collect())
                .into_iter()
                .filter(|&k| k < uniform.len())
                .collect();
            let jobs: Vec<(f64, Seed)> = idx.iter().map(|&k| uniform[k]).collect();
            let mut converged = Vec::new();
            let mut groups = vec![(idx, jobs)];
            if !euler_found {
                groups.push((Vec::new(), euler));
            }
            for (gi, (idx, jobs)) in groups.into_iter().enumerate() {
                if gi == 1 && li > 0 && !converged.is_empty() {
                    break;
                }
                seeds_tried += jobs.len();
                let solved = run_parallel(
                    opts.worker_threads(),
                    jobs.clone(),
                    &mut |_| {},
                    &mut |_| {},
                    |(lbar, seed), _| solve_seed(lbar, seed),
                );
                for (j, (&(lbar, seed), (seeded, secs))) in jobs.iter().zip(solved).enumerate() {
                    if seeded.is_some() {
                        if gi == 0 {
                            converged.push(idx[j]);
                        } else {
                            euler_found = true;
                        }
                    }
                    if !tr.take(lbar, seed, seeded, secs, progress)? {
                        break 'stretches;
                    }
                }
            }
            let left: Vec<usize> = open
                .take()
                .unwrap_or_else(|| (0..uniform.len()).collect())
                .into_iter()
                .filter(|k| !converged.contains(k))
                .collect();
            if left.is_empty() {
                break;
            }
            open = Some(left);
        }
        // The stretch's ends (where families are born in pairs, or cut by the range): the
        // Euler starts there.
        let ends = [
            stretch.iter().map(|s| s.0).reduce(f64::min),
            stretch.iter().map(|s| s.0).reduce(f64::max),
        ];
        for l in ends.into_iter().flatten() {
            let euler = euler_jobs(&opts.stiffness, eta, l);
            seeds_tried += euler.len();
            let solved = run_parallel(
                opts.worker_threads(),
                euler.clone(),
                &mut |_| {},
                &mut |_| {},
                |(lbar, seed), _| solve_seed(lbar, seed),
            );
            for (&(lbar, seed), (seeded, secs)) in euler.iter().zip(solved) {
                if !tr.take(lbar, seed, seeded, secs, progress)? {
                    break 'stretches;
                }
            }
        }
    }
    let seed_lengths: Vec<f64> = stretches
        .iter()
        .filter_map(|s| s.first().map(|s| s.0))
        .collect();
    // Where no family of the uniform rod reaches the scene's contrast at the seed lengths,
    // the states `rodloop solve --branch` finds there: its direct and shifted starts, then
    // its homotopies in D1/D0 where those fail.
    if tr.curves.is_empty() {
        for lbar in seed_lengths {
            for starts in [true, false] {
                let seed = Seed::Solve { starts };
                seeds_tried += 1;
                let (seeded, secs) = solve_seed(lbar, seed);
                let found = seeded.is_some();
                if !tr.take(lbar, seed, seeded, secs, progress)? {
                    break;
                }
                if found {
                    break;
                }
            }
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
                "none of the {seeds_tried} seeds (the uniform rod's loop continued in D1/D0 \
                 at each placement, then `rodloop solve --branch`) converged to a loop with \
                 {eta} period(s) of κ_g"
            )),
        });
    }
    let t_trace = t0.elapsed().as_secs_f64();
    debug(|| format!("eta {eta}: traced in {t_trace:.3} s"));

    // Sheets.
    let mut sheets = sheets::make_sheets(
        opts,
        problem,
        images,
        &curves,
        &seed_note,
        (branch, eta, cells),
    );
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

/// What tracing the families of one branch needs: its range, the model and its symmetry
/// images, the march settings.
struct Setup<M> {
    branch: u32,
    lo: f64,
    hi: f64,
    mid: f64,
    cells: usize,
    problem: ParamProblem<M>,
    images: Images,
    settings: crate::MarchSettings,
}

/// The [`Setup`] of branch `eta` on the scene's model ([`DiagramOptions::model`]).
fn setup(opts: &DiagramOptions, eta: u32) -> Result<Setup<impl SurfaceSolve>, DiagramError> {
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
    let lo = opts.lbar_min.max(exist_lo);
    let hi = opts.lbar_max.min(exist_hi);
    let circles: Vec<f64> = [e - 1.0, e + 1.0]
        .into_iter()
        .filter(|&m| m >= 1.0 && m >= opts.lbar_min - 1e-12 && m <= opts.lbar_max + 1e-12)
        .collect();
    let cells = opts.trace_cells(eta);
    let mid = 0.5 * (lo + hi);
    let model = opts.model(mid, cells)?;
    let problem = ParamProblem::new(model.clone(), Param::Lbar)?;
    let images = Images::new(&model, &opts.stiffness);
    let shape = model.dim() - model.n_constraints();
    let mut settings = march_settings(opts, hi, shape);
    settings.folds = FoldPolicy::Follow;
    settings.detect_branch_points = true;
    settings.far_limit = Some(lo);
    settings.max_steps = MAX_STEPS;
    settings.circles = circles;
    settings.circle_distance = SWITCH_DISTANCE;
    // Folds and branch points are located again at the reporting resolution
    // (`crate::special`): the tracer needs them only to its own width.
    settings.locate_tol = TRACE_LOCATE_TOL;
    Ok(Setup {
        branch,
        lo,
        hi,
        mid,
        cells,
        problem,
        images,
        settings,
    })
}

impl<M: SurfaceSolve> Setup<M> {
    fn end_context<'a>(&'a self, opts: &'a DiagramOptions) -> EndContext<'a, M> {
        EndContext {
            opts,
            problem: &self.problem,
            lo: self.lo,
            hi: self.hi,
            ds_min: self.settings.ds_min,
        }
    }
}

/// What became of a seed given to [`extend_families`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SeedOutcome {
    /// Newton did not converge from it at the tracing resolution.
    Unsolved,
    /// It lies on a family traced before (or on a symmetry image of one).
    Known,
    /// A new family was followed from it.
    Traced,
    /// It could not be followed (or a cap was reached).
    NotFollowed,
}

/// Trace the families of branch `eta` through further seeds, given the sheets of the branch
/// traced so far (`known`): each seed `(L̄, κ)` (Gauss values at the tracing resolution) is
/// solved, and followed like the seeds of [`compute_families`] (both ways through its folds,
/// switching at its branch points) unless it lies on a known family or on one traced from an
/// earlier seed. Returns the new sheets (families numbered after those of `known`), notes,
/// and what became of each seed.
pub fn extend_families(
    opts: &DiagramOptions,
    eta: u32,
    known: &[TracedBranch],
    seeds: &[(f64, Vec<f64>)],
) -> Result<(Families, Vec<SeedOutcome>), DiagramError> {
    opts.validate()?;
    let t0 = Instant::now();
    let su = setup(opts, eta)?;
    let end_ctx = su.end_context(opts);
    let known_curves: Vec<Curve> = known
        .iter()
        .filter(|b| b.eta == eta && b.cells == su.cells)
        .map(|b| Curve {
            points: b
                .points
                .iter()
                .map(|p| MarchPoint {
                    x: p.state.clone(),
                    value: p.value,
                    index: Some(p.index),
                    source: p.source,
                })
                .collect(),
            start_end: (b.low_end.clone(), b.stop_low.clone()),
            finish_end: (b.high_end.clone(), b.stop_high.clone()),
        })
        .collect();
    let n_known = known_curves.len();
    let mut tr = Tracing {
        ctx: &end_ctx,
        settings: &su.settings,
        images: &su.images,
        branch: su.branch,
        eta,
        curves: known_curves,
        notes: Vec::new(),
        pending: Vec::new(),
        switched: Vec::new(),
        steps: 0,
        seed_note: vec![None; n_known],
    };
    let mut outcomes = Vec::with_capacity(seeds.len());
    for (lbar, kappa) in seeds {
        let lbar = *lbar;
        let Some(x0) = su
            .problem
            .model_at(lbar)
            .ok()
            .and_then(|m| m.solve(kappa, &crate::states::newton_options()).ok())
            .map(|eq| eq.state())
        else {
            outcomes.push(SeedOutcome::Unsolved);
            continue;
        };
        if images::on_known(&su.images, &tr.curves, &x0, lbar) {
            outcomes.push(SeedOutcome::Known);
            continue;
        }
        let before = tr.curves.len();
        let seed = Seed::Found;
        if !tr.take(lbar, seed, Some(x0), 0.0, &mut |_| {})? {
            outcomes.push(SeedOutcome::NotFollowed);
            break;
        }
        outcomes.push(if tr.curves.len() > before {
            SeedOutcome::Traced
        } else {
            SeedOutcome::NotFollowed
        });
    }
    outcomes.resize(seeds.len(), SeedOutcome::NotFollowed);
    let Tracing {
        curves,
        notes,
        steps,
        mut seed_note,
        ..
    } = tr;
    let new_curves = &curves[n_known..];
    seed_note.resize(curves.len(), None);
    let family0 = known
        .iter()
        .filter(|b| b.eta == eta)
        .map(|b| b.family)
        .max()
        .unwrap_or(0);
    let mut sheets = sheets::make_sheets(
        opts,
        &su.problem,
        &su.images,
        new_curves,
        &seed_note[n_known..],
        (su.branch, eta, su.cells),
    );
    let seconds = t0.elapsed().as_secs_f64();
    let count = sheets.len().max(1);
    for s in &mut sheets {
        s.family += family0;
        s.steps = steps / count;
        s.seconds = seconds / count as f64;
        s.timings = BranchTimings {
            continuation: seconds / count as f64,
            ..BranchTimings::default()
        };
    }
    Ok((Families { sheets, notes }, outcomes))
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
    use rodloop_solver::{StartShape, Stiffness};

    /// The Euler placements left out as mirror images of kept ones seed the mirror images of
    /// the kept ones' states: one placement of the four is left out, the kept placement the
    /// mirror formula names is among the kept ones, and the two seeds, solved independently
    /// at the tracing resolution (soft segment `D1/D0 = 0.3`, whose bends the cells
    /// resolve), lie within [`SAME_STATE`] of each other's symmetry images with the same
    /// energy to 1e-6. Two profiles: the soft segment half the loop long (the seeds are two
    /// distinct mirror images) and a quarter of it (both reach one mirror-symmetric state).
    #[test]
    fn mirror_placements_left_out_seed_the_images_of_kept_ones() {
        for (s0, s1) in [(0.3, 0.8), (0.2, 0.45)] {
            let st = Stiffness::Tanh {
                d0: 1.0,
                d1: 0.3,
                s0,
                s1,
                gamma: 60.0,
            };
            let opts = DiagramOptions {
                stiffness: st.clone(),
                lbar_min: 1.0,
                lbar_max: 2.0,
                ..DiagramOptions::default()
            };
            let (eta, l) = (1, 1.3);
            let all = crate::sampling::feature_shifts(&st, eta, &[0, 1, 2, 3], false);
            let kept: Vec<f64> = euler_jobs(&st, eta, l)
                .into_iter()
                .map(|(_, seed)| match seed {
                    Seed::Shifted(sh) => sh,
                    other => panic!("{other:?}"),
                })
                .collect();
            let left: Vec<f64> = all
                .iter()
                .copied()
                .filter(|a| !kept.iter().any(|k| (k - a).abs() < 1e-12))
                .collect();
            assert_eq!(left.len(), 1, "({s0}, {s1}): all {all:?}, kept {kept:?}");
            let model = opts.model(l, opts.trace_cells(eta)).unwrap();
            let images = Images::new(&model, &st);
            let energy = |x: &[f64]| {
                let eq = model
                    .clone()
                    .solve_from_state(x.to_vec(), &crate::states::newton_options())
                    .unwrap();
                eq.energy().total
            };
            let seed = |sh: f64| seeding::seed_state(&model, eta, l, sh).unwrap();
            let dropped = seed(left[0]);
            // The start `κ(σ) = f(σ + sh)` mirrored, `f(a − σ + sh)`, is `±f(σ − a − sh)` for
            // the Euler curve (even about its origin): the placement `−a − sh`, modulo the
            // half period `1/(2η)` (a reflection `κ_g → −κ_g`).
            let half = 0.5 / f64::from(eta);
            let partner = (-(s0 + s1) - left[0]).rem_euclid(half);
            let k = kept
                .iter()
                .copied()
                .find(|k| {
                    let d = (k - partner).rem_euclid(half);
                    d.min(half - d) < 1e-9
                })
                .unwrap_or_else(|| panic!("({s0}, {s1}): {partner} not among {kept:?}"));
            let (x, e) = (seed(k), energy(&seed(k)));
            assert!(
                images.dist_images(&x, &dropped) < SAME_STATE
                    && (e - energy(&dropped)).abs() < 1e-6 * e,
                "({s0}, {s1}): the seeds at {} and {k} are not images of each other",
                left[0]
            );
        }
    }

    /// A nearly uniform rod (`D1/D0 = 0.95`): every placement where a family leaves the
    /// uniform circle is traced, with the energy first-order perturbation theory gives it:
    /// `E R/(π D0) = L̄ ∫ D(σ) κ(σ + φ)² dσ` of the uniform rod's exact loop placed at `φ`
    /// (`R = D0 = 1`, `κ² = κ_g² + 1`), computed here by the trapezoidal rule on the exact
    /// loop, independently of the traced states. The error of first order is `O(ε²)`,
    /// `ε = 0.05`: each traced energy lies within a tenth of the placements' energy spread.
    #[test]
    fn nearly_uniform_rod_traces_every_placement_at_its_first_order_energy() {
        let st = Stiffness::Tanh {
            d0: 1.0,
            d1: 0.95,
            s0: 0.15,
            s1: 0.52,
            gamma: 80.0,
        };
        let opts = DiagramOptions {
            stiffness: st.clone(),
            lbar_min: 1.4,
            lbar_max: 1.7,
            great_circles: false,
            ..DiagramOptions::default()
        };
        let eta = 2;
        let fam = compute_families(&opts, eta, &mut |_| {}).unwrap();
        let profile = st.validate().unwrap();
        for l in [1.45, 1.55, 1.65] {
            let kg = StartShape::Exact { eta }.interpolant(l).unwrap();
            let first_order = |phi: f64| {
                let n = 20_000;
                l * (0..n)
                    .map(|j| {
                        let s = j as f64 / n as f64;
                        profile.eval(s).d * (kg.eval(s + phi).powi(2) + 1.0)
                    })
                    .sum::<f64>()
                    / n as f64
            };
            let ps = crate::placements::PlacedProfile::new(&st, eta)
                .and_then(|p| p.placements(l))
                .unwrap();
            let predicted: Vec<f64> = ps.iter().map(|&p| first_order(p)).collect();
            let spread = predicted.iter().copied().fold(f64::NEG_INFINITY, f64::max)
                - predicted.iter().copied().fold(f64::INFINITY, f64::min);
            assert!(ps.len() >= 2 && spread > 1e-4, "{ps:?} {predicted:?}");
            let traced: Vec<f64> = fam.sheets.iter().filter_map(|b| b.energy_at(l)).collect();
            for (p, e) in ps.iter().zip(&predicted) {
                let near = traced
                    .iter()
                    .map(|t| (t - e).abs())
                    .fold(f64::INFINITY, f64::min);
                assert!(
                    near < 0.1 * spread,
                    "L̄ = {l}, placement {p}: first order {e}, traced {traced:?} (spread {spread})"
                );
            }
        }
    }
}
