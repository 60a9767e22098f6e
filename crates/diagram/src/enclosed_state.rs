//! One enclosed state (`|r| ≤ R`, paper Sec. 3.2) solved as `rodloop solve` reports it, with
//! its certificate: the energy and its error estimate, the surface loop it starts from, the
//! stability index and how the energy was obtained.
//!
//! A branch's enclosed state starts from its surface loop. Where that loop has `λ ≥ 0`
//! everywhere it satisfies every enclosed KKT condition (the wall may push, the loop
//! touches, stationarity is the surface equations), so it is the enclosed equilibrium: the
//! energy reported is the surface one (exact layer for uniform rods) and the 3-D enclosed
//! model re-solves it as a check. Where `λ < 0` somewhere, the 3-D model's semismooth
//! Newton finds the lift-off.
//!
//! The file is over 600 lines because it is one pipeline: the start, the search over the
//! meshes of the accuracy levels, the descent, the check on twice the cells and the report,
//! each step reading what the ones before found (the routes tried, the meshes passed over),
//! which the report names.

use std::sync::Arc;

use rodloop_exact::{eta_of_branch, paper_branch_loop, ExactLoop};
use rodloop_solver::accuracy::enclosed_scene_cells;
use rodloop_solver::enclosed::branch::{solve_levels_from_fine, BranchSolve};
use rodloop_solver::enclosed::descent::{
    descend_branch, enclosed_periods, solve_branch_descended, solve_branch_lowest, DescendedSolve,
};
use rodloop_solver::enclosed::{
    enclosed_cells, finer_check, free_circle, solve_branch, solve_enclosed, solve_levels,
    start_from_shape, EnclosedOptions, EnclosedState, SavedShape, SurfaceSource,
};
use rodloop_solver::enclosed::{IntoWall, Wall};
use rodloop_solver::{Accuracy, Equilibrium, Stiffness};

use crate::DiagramError;

/// Tolerance on the gap (units of `R`) for "touching".
pub const TOUCH: f64 = 1e-9;

/// One enclosed state with everything `solve` reports.
pub struct EnclosedResult {
    /// The 3-D state reported (config.csv).
    pub state: EnclosedState,
    /// Energy `E R/(π D0)` and its error estimate.
    pub energy: (f64, f64),
    /// Surface loop energy and `λ_min` (None for branch 0).
    pub surface: Option<(f64, f64)>,
    /// Stability index of the state reported (its finest level) and the lowest eigenvalues
    /// of the constrained Hessian on the coarsest level of the cascade (`N/8` or `N/4`;
    /// dense, `O(N³)`).
    pub stability: (usize, Vec<f64>),
    /// How the energy was obtained.
    pub method: String,
    /// The 3-D model's own energy (and estimate).
    pub model_energy: (f64, f64),
    /// Where the energy reported is the surface loop's (attached): that loop as its state
    /// file holds it. `None`: the file holds [`EnclosedResult::state`].
    pub attached_loop: Option<AttachedLoop>,
    /// The coarser levels of the 3-D model's estimate (`N/4`, `N/2`; `None` for the planar
    /// circle), with [`EnclosedResult::state`] the ladder the estimate comes from.
    pub levels: Option<[EnclosedState; 2]>,
}

/// The surface loop an attached enclosed state's file holds.
#[derive(Clone, Debug)]
pub enum AttachedLoop {
    /// The exact loop of a uniform rod and the number of points its file samples (uniform in
    /// arclength, at least three per cell of the solve's own resolution).
    Exact(ExactLoop, usize),
    /// A two-segment rod's numerical surface loop as its file holds it, verified against the
    /// reported energy by the routine that verifies every traced surface state
    /// (`verify_refining` (`state_file.rs`)): where the profile of the solve's resolution does
    /// not reproduce the energy within its estimate (`κ_g = 𝓜·n/D` is a second `O(h⁴)`
    /// discretisation of the state), the file samples the state re-solved on `2N`, `4N`, ….
    Numeric(Box<crate::StateFile>),
}

/// [`AttachedLoop::Numeric`] of the surface loop `eq` reported with `energy`: its file
/// verified by `verify_refining` (`state_file.rs`) (the claim kept: `energy` within
/// [`crate::ESTIMATES`] times its estimate), the one check of every surface state's file.
pub fn attached_file(
    eq: &Equilibrium,
    energy: (f64, f64),
) -> Result<AttachedLoop, rodloop_solver::SolverError> {
    crate::states::verify_refining(eq, energy.0, Some(energy.1), crate::states::Ladder::Keep)
        .map(|f| AttachedLoop::Numeric(Box::new(f)))
}

/// What [`verify_written`] measured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WrittenCheck {
    /// `E R/(π D0)` recomputed from the points the file holds, by their quadrature weights.
    pub energy_from_file: f64,
    /// Allowed `|energy_from_file − energy|`.
    pub energy_tolerance: f64,
    /// Periods `η` of the state as its file holds it (the branch identified from the state;
    /// 0 where they are not named and no branch was requested). An exact surface loop is the
    /// loop of the branch requested.
    pub identified_eta: u32,
}

/// The points of the state file of an attached result: `points` samples of the surface loop,
/// uniform in arclength, as `(s, x, y, z, κ_g, λ, D)` in the model's units (ball radius
/// `r`, reference stiffness `d0`); the periodic trapezoid weight of each is `L/points`.
pub fn attached_rows(
    source: &SurfaceSource,
    points: usize,
    r: f64,
    d0: f64,
) -> Result<Vec<[f64; 7]>, DiagramError> {
    match source {
        SurfaceSource::Exact(l) => {
            // The exact loop lives on the unit sphere, in units of `R` and `D`.
            let len = l.length();
            (0..points)
                .map(|i| {
                    let q = l.point(len * i as f64 / points as f64).map_err(passed)?;
                    Ok([
                        q.s * r,
                        q.x * r,
                        q.y * r,
                        q.z * r,
                        q.kappa_g / r,
                        q.lambda * d0 / (r * r * r),
                        d0,
                    ])
                })
                .collect()
        }
        SurfaceSource::Numeric(eq) => Ok(eq
            .profile_uniform(points)
            .map_err(passed)?
            .iter()
            .map(|q| [q.s, q.x, q.y, q.z, q.kappa_g, q.lambda, q.d])
            .collect()),
    }
}

/// Verify `res` as its state file holds it, against its reported energy and `ESTIMATES` times
/// its error estimate (the energy is that of the finest level, or the surface loop's):
/// a 3-D state by [`rodloop_solver::verify_enclosed`] (closed, nodes inside the ball, Gauss
/// points within their cells' reach, energy by the file's quadrature weights, branch `eta`);
/// a numerical surface loop's file ([`AttachedLoop::Numeric`]) by its verification when the
/// result was built (the same claim: the periodic trapezoid on its written samples) and the
/// periods of its moment; an exact surface loop by the periodic trapezoid on its samples, within that rule's own error
/// `|T_h − T_2h|` (the loop is exact, its estimate 0).
pub fn verify_written(
    res: &EnclosedResult,
    eta: Option<u32>,
) -> Result<WrittenCheck, DiagramError> {
    use rodloop_solver::{verify_enclosed, Claim};
    let claim = Claim {
        energy: res.energy.0,
        energy_error: crate::ESTIMATES * res.energy.1,
        profile_error: 0.0,
        eta,
    };
    match &res.attached_loop {
        None => {
            let v = verify_enclosed(&res.state, &claim).map_err(passed)?;
            Ok(WrittenCheck {
                energy_from_file: v.energy_from_profile,
                energy_tolerance: v.energy_tolerance,
                identified_eta: v.eta,
            })
        }
        Some(AttachedLoop::Numeric(file)) => {
            // The file was verified against this claim when the result was built
            // (`attached_file`); the branch requested is checked on its profile.
            let identified_eta =
                rodloop_solver::verify::check_periods(&file.profile, res.state.model.length(), eta)
                    .map_err(passed)?;
            Ok(WrittenCheck {
                energy_from_file: file.verification.energy_from_profile,
                energy_tolerance: file.verification.energy_tolerance,
                identified_eta,
            })
        }
        Some(AttachedLoop::Exact(l, points)) => {
            let m = &res.state.model;
            let (r, d0) = (m.radius(), m.stiffness().kind().reference());
            let rows = attached_rows(&SurfaceSource::Exact(*l), *points, r, d0)?;
            let ds = m.length() / *points as f64;
            let sum = |step: usize| {
                rows.iter()
                    .step_by(step)
                    .map(|q| 0.5 * q[6] * (q[4] * q[4] + 1.0 / (r * r)) * ds * step as f64)
                    .sum::<f64>()
                    * r
                    / (std::f64::consts::PI * d0)
            };
            let (fine, coarse) = (sum(1), sum(2));
            let tolerance = claim.energy_error
                + (fine - coarse).abs()
                + rodloop_solver::verify::ENERGY_RELATIVE_SLACK * claim.energy.abs().max(1.0);
            let gap = (fine - claim.energy).abs();
            if gap.is_nan() || gap > tolerance {
                return Err(DiagramError::Passed(Box::new(
                    rodloop_solver::SolverError::Unverified(format!(
                        "the energy recomputed from the written points of the exact surface \
                         loop, {fine:.10}, differs from the reported {:.10} by more than \
                         {tolerance:.1e}",
                        claim.energy
                    )),
                )));
            }
            Ok(WrittenCheck {
                energy_from_file: fine,
                energy_tolerance: tolerance,
                identified_eta: eta.unwrap_or(0),
            })
        }
    }
}

/// The reported state's stability: the index of the finest level ([`BranchSolve::index`])
/// and the lowest eigenvalues of the constrained Hessian on the coarsest level (a dense
/// eigen-decomposition, `O(N³)`; an approximation of the finest level's, whose count of
/// negative ones can differ from the index next to a zero eigenvalue).
fn stability_of(b: &BranchSolve) -> Result<(usize, Vec<f64>), rodloop_solver::SolverError> {
    let (_, vals) = b.coarsest().stability(1e-6)?;
    Ok((b.index(1e-6)?, vals))
}

/// An error of a lower layer with what was being computed when it happened.
pub(crate) fn context<E>(what: impl Into<String>) -> impl FnOnce(E) -> DiagramError
where
    E: std::error::Error + Send + Sync + 'static,
{
    let what = what.into();
    move |e| DiagramError::Context {
        what,
        source: Box::new(e),
    }
}

/// An error of a lower layer passed on as it is.
pub(crate) fn passed<E>(e: E) -> DiagramError
where
    E: std::error::Error + Send + Sync + 'static,
{
    DiagramError::Passed(Box::new(e))
}

/// Solve branch `branch` of an enclosed scene (ball radius `r`, the rod's `stiffness`, its
/// reference value `D0`) at `lbar`, descending from a saddle to the local minimum of the
/// branch below it ([`solve_state_with`]).
pub fn solve_state(
    wall: impl IntoWall,
    stiffness: &Stiffness,
    lbar: f64,
    branch: u32,
    accuracy: Accuracy,
) -> Result<EnclosedResult, DiagramError> {
    solve_state_with(wall, stiffness, lbar, branch, accuracy, false)
}

/// [`solve_state`]; `keep_saddle`: return the state Newton converges to even where it is a
/// saddle.
pub fn solve_state_with(
    wall: impl IntoWall,
    stiffness: &Stiffness,
    lbar: f64,
    branch: u32,
    accuracy: Accuracy,
    keep_saddle: bool,
) -> Result<EnclosedResult, DiagramError> {
    let wall = wall.into_wall();
    let r = wall.radius();
    let opts = EnclosedOptions::default();
    if branch == 0 {
        if lbar > 1.0 {
            return Err(DiagramError::OutOfRange(format!(
                "branch 0 (the planar circle) fits in the ball only for lbar <= 1; got lbar = {lbar}"
            )));
        }
        // The uniform circle is exact at any resolution: the 3-D check runs at the fast one.
        let cells = enclosed_cells(
            if stiffness.is_uniform() {
                Accuracy::Fast
            } else {
                accuracy
            },
            1,
        );
        let (model, z0) = free_circle(&wall, lbar, cells, stiffness).map_err(passed)?;
        // A non-uniform rod's free loop is not a circle: Newton from the circle, with the
        // start point pinned (the translations of a free loop), answers only where it
        // converges to a loop clear of the wall (one that touches would hang on the pin).
        let nonuniform = |why: String| {
            DiagramError::Unsolved(format!(
                "branch 0 of a non-uniform rod at lbar = {lbar}: {why}; its free loop is not a circle and rodloop has no other start for it (the enclosed diagram of such a rod starts at lbar = 1)"
            ))
        };
        let state = match solve_enclosed(&model, z0, &opts) {
            Ok(s) => s,
            Err(e) if !stiffness.is_uniform() => {
                return Err(nonuniform(format!("Newton from the circle fails ({e})")))
            }
            Err(e) => return Err(context("the free circle")(e)),
        };
        if !stiffness.is_uniform() {
            let c = state.contact(TOUCH).map_err(passed)?;
            if c.fraction > 0.0 {
                return Err(nonuniform(format!(
                    "Newton from the circle reaches a loop touching the wall on {:.1}% of its length, which the pinned start point would hold",
                    100.0 * c.fraction
                )));
            }
        }
        let (cm, cz) = free_circle(&wall, lbar, cells / 2, stiffness).map_err(passed)?;
        let comp = solve_enclosed(&cm, cz, &opts).map_err(passed)?;
        let e = state.energy();
        let est = rodloop_solver::richardson_error(e, comp.energy());
        let stability = comp.stability(1e-6).map_err(passed)?;
        let exact = if stiffness.is_uniform() {
            Some(1.0 / lbar)
        } else {
            None
        };
        return Ok(EnclosedResult {
            energy: (exact.unwrap_or(e), if exact.is_some() { 0.0 } else { est }),
            surface: None,
            stability,
            method: if exact.is_some() {
                "planar circle: E R/(pi D) = 1/lbar exactly; 3-D model solved as a check".into()
            } else {
                "planar circle, 3-D model".into()
            },
            model_energy: (e, est),
            state,
            attached_loop: None,
            levels: None,
        });
    }
    let eta = eta_of_branch(branch);
    let e = f64::from(eta);
    if !(lbar > e - 1.0 && lbar < e + 1.0) {
        return Err(DiagramError::OutOfRange(format!(
            "branch {branch} (eta = {eta}) exists only for {} < lbar < {}; got lbar = {lbar}",
            e - 1.0,
            e + 1.0
        )));
    }
    let d0 = stiffness.reference();
    let (source, surface_error) = if stiffness.is_uniform() {
        let l = paper_branch_loop(eta, lbar).map_err(context(format!(
            "the exact surface loop of branch {branch}"
        )))?;
        (SurfaceSource::Exact(l), 0.0)
    } else {
        SurfaceSource::numeric(r, lbar, stiffness, eta, accuracy)
            .map_err(context(format!("the surface loop of branch {branch}")))?
    };
    let e_surf = source.energy().map_err(passed)?;
    let lam_min = source.lambda_min(r, d0);
    // Only on the sphere is a surface loop with `λ ≥ 0` an enclosed state.
    let attached = wall.sphere().is_some() && lam_min >= 0.0;
    // An attached loop's energy is the surface one; the 3-D re-solve is a check, at the
    // fast resolution.
    let acc = if attached { Accuracy::Fast } else { accuracy };
    let cells = enclosed_scene_cells(stiffness, acc, eta);
    let what = || format!("the enclosed loop of branch {branch} at lbar = {lbar}");
    // Set where the state reported is a lower local minimum than the one reached from the
    // surface loop (continuation in the stiffness from the uniform rod's loop).
    let mut lower_minimum = false;
    let (b, descent, given_up) = if keep_saddle {
        let b =
            solve_branch(&wall, lbar, stiffness, &source, cells, &opts).map_err(context(what()))?;
        (b, None, Vec::new())
    } else {
        // Two-segment rods: every start (this level's surface loop, the stiffness paths,
        // the minima at other lengths, the other levels' surface loops) is tried on the mesh
        // of this accuracy first; only where none of them ends at a local minimum there are
        // the meshes of the finer levels (and twice the finest) tried, with the surface
        // loops.
        let mut ladder = vec![cells];
        if !stiffness.is_uniform() {
            for a in [Accuracy::Default, Accuracy::High] {
                ladder.push(enclosed_cells(a, eta).max(32 * (2 + eta as usize)));
            }
            ladder.push(2 * ladder[ladder.len() - 1]);
            ladder.retain(|&n| n >= cells);
            ladder.dedup();
        }
        // The meshes of the lower accuracies, finest first: the last resort where no mesh of
        // the ladder gives a local minimum (a coarse level of a fine ladder on which the
        // branch's minimum does not converge makes its whole ladder fail: seed 2 of the
        // random enclosed scenes at L̄ = 1.45, whose minimum has no 64-cell state there).
        let mut coarser: Vec<usize> = if stiffness.is_uniform() {
            Vec::new()
        } else {
            [Accuracy::Default, Accuracy::Fast]
                .into_iter()
                .map(|a| enclosed_cells(a, eta).max(32 * (2 + eta as usize)))
                .filter(|&n| n < cells)
                .collect()
        };
        coarser.dedup();
        let search = |ladder: &[usize]| -> Result<(DescendedSolve, bool), DiagramError> {
            let (out, replaced) =
                solve_branch_lowest(&wall, lbar, eta, stiffness, &source, ladder, &opts)
                    .map_err(context(what()))?;
            if stiffness.is_uniform() {
                return Ok((out, replaced));
            }
            let out = lowest_over_surface_starts(
                &wall, lbar, eta, stiffness, accuracy, ladder, &opts, out,
            );
            Ok((out, replaced))
        };
        // The finer meshes without the routes of `solve_branch_lowest` (the stiffness paths
        // and the minima at other lengths, which it follows on one coarse mesh whatever the
        // ladder and carries to the first mesh): this level's surface loop, then the others'.
        let search_finer = |m: usize| -> Result<(DescendedSolve, bool), DiagramError> {
            let out = solve_branch_descended(&wall, lbar, stiffness, &source, &[m], &opts)
                .map_err(context(what()))?;
            let out =
                lowest_over_surface_starts(&wall, lbar, eta, stiffness, accuracy, &[m], &opts, out);
            Ok((out, false))
        };
        // A local minimum of this branch: index 0, and its periods name the branch (a state
        // whose branch cannot be identified is no answer, and is refused when written).
        let minimum = |b: &BranchSolve| {
            b.index(1e-6).is_ok_and(|i| i == 0)
                && enclosed_periods(&b.fine).is_ok_and(|p| p.eta == eta)
        };
        // Mesh by mesh, coarsest first: the first with every start, the finer ones with the
        // surface loops. Where none ends at a local minimum, the finest mesh's result stands
        // (every start's last mesh, as one search over the whole ladder would end), unless a
        // descent reached an index-0 state on a mesh's N/4 level whose finer levels did not
        // converge: then the whole ladder at once, where the next mesh starts from that
        // state.
        let mut by_mesh = None;
        let mut finest = None;
        let mut passed_over = Vec::new();
        let mut minimum_at_quarter = false;
        if ladder.len() > 1 {
            for (k, &m) in ladder.iter().enumerate() {
                let found = if k == 0 {
                    search(&[m])
                } else {
                    search_finer(m)
                };
                match found {
                    Ok(f) if minimum(&f.0 .0) => {
                        by_mesh = Some(f);
                        break;
                    }
                    Ok(f) => {
                        passed_over.push(format!(
                            "at N = {m} cells no start ended at a local minimum of the branch"
                        ));
                        minimum_at_quarter |= f.0 .1.as_ref().is_some_and(|d| d.end().index == 0);
                        finest = Some((f, passed_over.len()));
                    }
                    Err(e) => {
                        passed_over.push(format!("at N = {m} cells no start converged ({e})"))
                    }
                }
            }
        }
        // Then every start on the meshes of the lower accuracies, finest first, and, as the
        // last resort, on the finer accuracy levels' meshes too. The minima of other lengths,
        // carried to a mesh and continued there, can converge on one mesh and not on another
        // (random seed 26 of `tests/random_enclosed.rs`, branch 2 at `L̄ = 1.3679277`: on 128
        // cells, not on 96, while the surface loop leads to a state whose branch cannot be
        // identified on every mesh).
        if by_mesh.is_none() && ladder.len() > 1 {
            let lower = coarser.iter().map(|&m| {
                (
                    m,
                    "the mesh of a lower accuracy (its estimate from N/4, N/2, N there)",
                )
            });
            // The accuracy levels' meshes only: the ladder's last one, twice the finest, checks
            // a state; every start on it costs as much as the rest of the search together.
            let finer = ladder[1..ladder.len() - 1].iter().map(|&m| {
                (
                    m,
                    "by every start (on the meshes before it, by the surface loops)",
                )
            });
            for (m, how) in lower.chain(finer) {
                if let Ok(f) = search(&[m]) {
                    if minimum(&f.0 .0) {
                        passed_over.push(format!(
                            "the state is the lowest local minimum found on N = {m} cells, {how}"
                        ));
                        by_mesh = Some(f);
                        break;
                    }
                }
            }
        }
        let ((b, descent, mut given_up), replaced) = match (by_mesh, finest) {
            (Some(f), _) => f,
            (None, Some((f, before))) if !minimum_at_quarter => {
                // The meshes passed over, without the one reported.
                passed_over.remove(before - 1);
                f
            }
            _ => {
                passed_over.clear();
                search(&ladder)?
            }
        };
        passed_over.append(&mut given_up);
        let given_up = passed_over;
        lower_minimum = replaced;
        (b, descent, given_up)
    };
    let cells = b.fine.model.cells();
    let stability = stability_of(&b).map_err(passed)?;
    let moved = lower_minimum || descent.as_ref().is_some_and(|d| d.moved());
    let (energy, mut method) = if attached && !moved {
        (
            (e_surf, surface_error),
            format!(
                "surface loop (lambda_min = {lam_min:.6} >= 0: it satisfies the enclosed KKT conditions); 3-D model re-solved at N = {cells} as a check"
            ),
        )
    } else {
        let checked = lifted_check(&b, stiffness, &opts);
        (
            (b.energy, checked.map_or(b.energy_error, |c| c.0.max(b.energy_error))),
            format!(
                "3-D enclosed model, N = {cells} cells (semismooth Newton from {}, lambda_min = {lam_min:.6}); {}{}",
                if lower_minimum {
                    "the start of the route named below"
                } else if b.homotopy {
                    "the surface loop by the pull homotopy"
                } else {
                    "the surface loop"
                },
                b.estimate_method(),
                match checked {
                    Some((c, e2)) if c > b.energy_error => format!(
                        ", widened to {c:.1e} by the check on N = {} cells (E R/(pi D0) = {e2:.10}: the distance to it plus its own estimate from N/2, N, 2N)",
                        2 * cells
                    ),
                    Some(_) => format!(
                        "; checked on N = {} cells (the distance to it plus its own estimate is within the estimate)",
                        2 * cells
                    ),
                    None => String::new(),
                }
            ),
        )
    };
    let attached_loop = if attached && !moved {
        let points = crate::STATE_POINTS.max(3 * enclosed_scene_cells(stiffness, accuracy, eta));
        Some(match &source {
            SurfaceSource::Numeric(eq) => attached_file(eq, energy).map_err(context(format!(
                "the surface loop of branch {branch} as its state file holds it"
            )))?,
            SurfaceSource::Exact(l) => AttachedLoop::Exact(*l, points),
        })
    } else {
        None
    };
    for why in &given_up {
        method.push_str(&format!("; {why}"));
    }
    describe_descent(&mut method, descent.as_ref(), &b);
    if stability.0 > 0 && !keep_saddle {
        method.push_str(&format!(
            "; no local minimum of branch {branch} was found ({}, and descents from every saddle reached): the lowest saddle of the branch found is reported",
            if stiffness.is_uniform() {
                "from the surface loop"
            } else {
                "from the surface loops of the three accuracy levels, from the uniform rod's loop continued in the stiffness, from local minima at other lengths continued in lbar"
            }
        ));
    }
    Ok(EnclosedResult {
        model_energy: (b.energy, b.energy_error),
        state: b.fine,
        energy,
        surface: Some((e_surf, lam_min)),
        stability,
        method,
        attached_loop,
        levels: Some([b.quarter, b.coarse]),
    })
}

/// [`finer_check`] of a two-segment rod's lifted-off state `b` that touches the wall, as the
/// diagram checks its rows: `None` for a uniform rod (its ladders are studied in
/// `converge`), an attached state or a free loop.
fn lifted_check(
    b: &BranchSolve,
    stiffness: &Stiffness,
    opts: &EnclosedOptions,
) -> Option<(f64, f64)> {
    let fraction = b.fine.contact(TOUCH).ok()?.fraction;
    if stiffness.is_uniform() || fraction >= 1.0 || fraction == 0.0 {
        return None;
    }
    finer_check(&b.fine, b.coarse.energy(), opts)
}

/// Where the lowest state of a two-segment rod's branch `eta` that a solve finds (`found`,
/// from the surface loop of its accuracy level and the stiffness paths) is a saddle, the
/// surface loops of the other accuracy levels are solved on the same `ladder` and descended
/// as well ([`solve_branch_descended`]), and the lowest state of the branch is kept (an
/// index-0 one first). The pull homotopy ends at different saddles from the surface loops of
/// different levels (they differ by their discretisation); with every level's start each
/// level compares the same saddles, so that where no local minimum of the branch is found
/// the lowest saddle reported is the same state at every accuracy.
#[allow(clippy::too_many_arguments)]
fn lowest_over_surface_starts(
    wall: &Arc<dyn Wall>,
    lbar: f64,
    eta: u32,
    stiffness: &Stiffness,
    accuracy: Accuracy,
    ladder: &[usize],
    opts: &EnclosedOptions,
    found: DescendedSolve,
) -> DescendedSolve {
    let rank = |b: &BranchSolve| -> Option<(bool, f64)> {
        let index = b.index(1e-6).ok()?;
        let same = enclosed_periods(&b.fine).ok().map(|p| p.eta) == Some(eta);
        same.then_some((index > 0, b.energy))
    };
    // Lower by more than round-off: the same state reached from another start stays the
    // state of this level's own start.
    let better = |x: (bool, f64), y: (bool, f64)| {
        (!x.0 && y.0) || (x.0 == y.0 && x.1 < y.1 - 1e-9 * y.1.abs().max(1.0))
    };
    let Some(mine) = rank(&found.0) else {
        return found;
    };
    if !mine.0 {
        return found;
    }
    let mut best = (found, mine);
    for level in [Accuracy::Fast, Accuracy::Default, Accuracy::High] {
        if level == accuracy {
            continue;
        }
        let Ok((source, _)) = SurfaceSource::numeric(wall.radius(), lbar, stiffness, eta, level)
        else {
            continue;
        };
        let Ok((b, d, mut notes)) =
            solve_branch_descended(wall, lbar, stiffness, &source, ladder, opts)
        else {
            continue;
        };
        match rank(&b) {
            Some(other) if better(other, best.1) => {
                notes.insert(
                    0,
                    format!(
                        "started from the surface loop of the {} level (the state reached from this level's surface loop and the stiffness paths, E R/(pi D0) = {:.10}, has index > 0 and lies higher)",
                        format!("{level:?}").to_lowercase(),
                        mine.1
                    ),
                );
                best = ((b, d, notes), other);
            }
            _ => {}
        }
    }
    best.0
}

/// Append a descent from a saddle (started at index > 0) to `method`: what it did, on the
/// ladder's `N/4` mesh with energies at `N`.
fn describe_descent(
    method: &mut String,
    descent: Option<&rodloop_solver::descend::Descent<EnclosedState>>,
    b: &rodloop_solver::enclosed::branch::BranchSolve,
) {
    if let Some(d) = descent.filter(|d| d.start().index > 0) {
        method.push_str(&format!(
            "; {} (descent at N/4 = {} cells, energies at N)",
            d.describe(),
            b.quarter.model.cells()
        ));
    }
}

/// Solve from a saved enclosed shape at `lbar`: the shape's curvature vectors, aligned by
/// [`start_from_shape`], start the cascade at `N/4` (`N = 32(1 + η)` with the branch's `η`
/// when given, else `η = 2`), else, where that cascade does not converge, Newton on `N`
/// cells with its coarser levels re-solved from it ([`solve_levels_from_fine`]).
pub fn solve_from_shape(
    wall: impl IntoWall,
    stiffness: &Stiffness,
    lbar: f64,
    shape: &SavedShape,
    branch: Option<u32>,
    accuracy: Accuracy,
    keep_saddle: bool,
) -> Result<EnclosedResult, DiagramError> {
    let eta = branch.filter(|&b| b > 0).map_or(2, eta_of_branch);
    let cells = enclosed_scene_cells(stiffness, accuracy, eta);
    let wall = wall.into_wall();
    let (model, z0) = start_from_shape(&wall, lbar, cells / 4, stiffness, shape).map_err(passed)?;
    let opts = EnclosedOptions::default();
    // The cascade from `N/4`; where it does not converge (the coarse mesh cannot carry the
    // saved contacts: point contacts of a finer mesh's state fall between its nodes), the
    // shape on `N` cells first, its coarser levels re-solved from it.
    let b = solve_levels(&model, z0, None, &opts)
        .or_else(|first| {
            let watchdog = EnclosedOptions {
                watchdog: 2,
                ..opts.clone()
            };
            start_from_shape(&wall, lbar, cells, stiffness, shape)
                .and_then(|(m, z)| solve_enclosed(&m, z, &watchdog))
                .and_then(|fine| solve_levels_from_fine(fine, &opts))
                .map_err(|_| first)
        })
        .map_err(context("the enclosed loop from the saved shape"))?;
    let (b, descent) = if keep_saddle {
        (b, None)
    } else {
        descend_branch(b, &opts)
            .map_err(context("descending from the saddle Newton converged to"))?
    };
    let stability = stability_of(&b).map_err(passed)?;
    let mut method = format!(
        "3-D enclosed model, N = {cells} cells (semismooth Newton from the saved shape); {}",
        b.estimate_method()
    );
    describe_descent(&mut method, descent.as_ref(), &b);
    Ok(EnclosedResult {
        model_energy: (b.energy, b.energy_error),
        energy: (b.energy, b.energy_error),
        surface: None,
        stability,
        method,
        state: b.fine,
        attached_loop: None,
        levels: Some([b.quarter, b.coarse]),
    })
}
