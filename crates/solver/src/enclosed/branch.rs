//! A paper branch in an enclosed scene: start from the branch's surface loop (exact for
//! uniform rods, the surface model's equilibrium otherwise), let the semismooth Newton find
//! the contact set, and estimate the discretisation error from two resolutions.

use rodloop_exact::ExactLoop;

use super::solve::{
    solve_by_pull_homotopy, solve_enclosed, solve_prolonged, start_from_curvature,
    start_from_surface, transfer_multipliers, EnclosedOptions, EnclosedState,
};
use super::wall::IntoWall;
pub use crate::accuracy::three_level_estimate;
use crate::solve::Equilibrium;
use crate::stiffness::Stiffness;
use crate::SolverError;

/// The surface loop an enclosed solve starts from.
#[derive(Clone, Debug)]
pub enum SurfaceSource {
    /// An exact homogeneous loop on the unit sphere (scaled to the ball's radius).
    Exact(ExactLoop),
    /// A numerical surface equilibrium.
    Numeric(Box<Equilibrium>),
}

impl SurfaceSource {
    /// The numerical surface loop of branch `eta` at `lbar` ([`crate::solve_robust`] from the
    /// Euler curve `l = η`, at `accuracy`) and its energy estimate: the start of an enclosed
    /// solve of a non-uniform rod.
    pub fn numeric(
        radius: f64,
        lbar: f64,
        stiffness: &Stiffness,
        eta: u32,
        accuracy: crate::Accuracy,
    ) -> Result<(Self, f64), SolverError> {
        let (res, _) = crate::solve_robust(
            radius,
            lbar,
            stiffness,
            &crate::StartShape::Euler { l: eta },
            accuracy,
            Some(eta),
            &crate::SolveOptions::default(),
        )?;
        Ok((
            SurfaceSource::Numeric(Box::new(res.equilibrium)),
            res.energy_error,
        ))
    }

    /// `κ_g` at `σ = s/L` (units of the model).
    pub fn kappa_g(&self, radius: f64, sigma: &[f64]) -> Result<Vec<f64>, SolverError> {
        match self {
            SurfaceSource::Exact(l) => sigma
                .iter()
                .map(|&s| Ok(l.point(s * l.length())?.kappa_g / radius))
                .collect(),
            SurfaceSource::Numeric(eq) => eq.sample_at(sigma),
        }
    }

    /// Energy `E R/(π D0)` of the surface loop.
    pub fn energy(&self) -> Result<f64, SolverError> {
        match self {
            SurfaceSource::Exact(l) => Ok(l.energy()?),
            SurfaceSource::Numeric(eq) => Ok(eq.energy().total),
        }
    }

    /// Smallest contact force `λ_min R³/D0` of the surface loop (Eq. (38) for exact loops).
    pub fn lambda_min(&self, radius: f64, d0: f64) -> f64 {
        match self {
            SurfaceSource::Exact(l) => l.lambda_range().0,
            SurfaceSource::Numeric(eq) => eq.lambda_range().0 * radius.powi(3) / d0,
        }
    }
}

/// An enclosed equilibrium at two resolutions.
#[derive(Clone, Debug)]
pub struct BranchSolve {
    /// The state at `N` cells (reported).
    pub fine: EnclosedState,
    /// The companion at `N/2` cells.
    pub coarse: EnclosedState,
    /// The level at `N/4` cells.
    pub quarter: EnclosedState,
    /// The level at `N/8` cells, where the cascade has it (uniform rods, `N ≥ 256`).
    pub eighth: Option<EnclosedState>,
    /// Energy `E R/(π D0)` at `N` cells.
    pub energy: f64,
    /// The error estimate: [`three_level_estimate`] over `N/4, N/2, N` for an attached
    /// state (fourth order) or where no `N/8` level exists; [`four_level_estimate`] over
    /// `N/8 … N` for a lifted-off one; order 1 for point-like contact
    /// ([`POINT_CONTACT_CELLS`]).
    pub energy_error: f64,
    /// The observed order `p`.
    pub order: f64,
    /// `true` where the finest level touches the wall only at points
    /// ([`point_like_contact`]; the estimate then takes order 1).
    pub point_contact: bool,
    /// For point contacts on a uniform rod: the energy of the same ladder solved with a
    /// node at every contact point ([`super::centre::centre_levels`], fourth order) and its
    /// estimate. The reported estimate is then `|E_N − E_c| + δE_c`.
    pub centred_energy: Option<(f64, f64)>,
    /// `true` when plain Newton failed at `N/4` and the pull homotopy
    /// ([`super::solve::solve_by_pull_homotopy`]) found the state.
    pub homotopy: bool,
}

/// Solve one enclosed state at `cells` and `cells/2` from the surface loop `source`: the
/// semismooth Newton runs first on a coarse mesh from the surface loop, and each finer solve
/// starts from the coarser solution (the contact set is then nearly right, and the
/// active-set iteration needs few steps). The first mesh is `cells/4`; for a uniform rod
/// with `cells ≥ 256` it is `min(cells/8, 64)` (the plain Newton from the surface loop
/// stalled at 128 cells on the figure-eight at `L̄ = 1.4` and needed the pull homotopy),
/// and the `cells/8` level enters the error estimate ([`four_level_estimate`]).
pub fn solve_branch(
    wall: impl IntoWall,
    lbar: f64,
    stiffness: &Stiffness,
    source: &SurfaceSource,
    cells: usize,
    opts: &EnclosedOptions,
) -> Result<BranchSolve, SolverError> {
    let wall = wall.into_wall();
    let radius = wall.radius();
    if cells < 32 || cells % 4 != 0 {
        return Err(SolverError::InvalidInput(format!(
            "enclosed solves need a multiple of 4 cells, at least 32 (got {cells})"
        )));
    }
    let (n0, refinements) = if stiffness.is_uniform() && cells >= 256 && cells % 8 == 0 {
        let mut n0 = cells / 8;
        let mut k = 3;
        while n0 > 64 && n0 % 2 == 0 {
            n0 /= 2;
            k += 1;
        }
        (n0, k)
    } else {
        (cells / 4, 2)
    };
    let (model, z0) = surface_start(&wall, lbar, n0, stiffness, source)?;
    let lmin = source.lambda_min(radius, stiffness.reference());
    solve_ladder(&model, z0, Some(lmin), opts, refinements)
}

/// The start of an enclosed solve on `cells` cells from the surface loop `source`
/// ([`start_from_surface`] with `κ_g` sampled at the model's Gauss points).
fn surface_start(
    wall: &std::sync::Arc<dyn super::wall::Wall>,
    lbar: f64,
    cells: usize,
    stiffness: &Stiffness,
    source: &SurfaceSource,
) -> Result<(super::model::EnclosedModel, Vec<f64>), SolverError> {
    let probe = super::model::EnclosedModel::new(
        wall,
        lbar,
        cells,
        stiffness,
        super::model::Gauge {
            reference: vec![0.0; 4 * cells],
            slope: None,
            pin: None,
        },
    )?;
    let sig: Vec<f64> = (0..2 * cells).map(|g| probe.gauss_sigma(g)).collect();
    let kg = source.kappa_g(wall.radius(), &sig)?;
    let lookup = |s: f64| -> f64 {
        let g = sig.iter().position(|&x| (x - s).abs() < 1e-15).unwrap_or(0);
        kg[g]
    };
    start_from_surface(wall, lbar, cells, stiffness, lookup)
}

/// The enclosed state on `cells` cells (one level) started from the surface loop `source`:
/// semismooth Newton, where it fails the pull homotopy ([`solve_by_pull_homotopy`]).
pub fn solve_from_surface(
    wall: impl IntoWall,
    lbar: f64,
    stiffness: &Stiffness,
    source: &SurfaceSource,
    cells: usize,
    opts: &EnclosedOptions,
) -> Result<EnclosedState, SolverError> {
    let wall = wall.into_wall();
    let (model, z0) = surface_start(&wall, lbar, cells, stiffness, source)?;
    solve_enclosed(&model, z0.clone(), opts).or_else(|plain| {
        let lmin = source.lambda_min(wall.radius(), stiffness.reference());
        solve_by_pull_homotopy(&model, z0, lmin, opts).map_err(|_| plain)
    })
}

/// The cascade of [`solve_branch`] from a start at `N/4` cells (`model`, `z0`): Newton
/// there, then at `N/2` and `N` from the prolonged coarser state, and the three-level error
/// estimate. With `lambda_min` (the start's smallest contact force, `< 0` where it would
/// need a pulling wall), a level where plain Newton fails is retried by the pull homotopy.
pub fn solve_levels(
    model: &super::model::EnclosedModel,
    z0: Vec<f64>,
    lambda_min: Option<f64>,
    opts: &EnclosedOptions,
) -> Result<BranchSolve, SolverError> {
    solve_ladder(model, z0, lambda_min, opts, 2)
}

/// [`solve_levels`] with `refinements ≥ 2` doublings of the start's cells: the last three
/// levels are `N/4, N/2, N`, and with three or more doublings the one before is `N/8`.
fn solve_ladder(
    model: &super::model::EnclosedModel,
    z0: Vec<f64>,
    lambda_min: Option<f64>,
    opts: &EnclosedOptions,
    refinements: usize,
) -> Result<BranchSolve, SolverError> {
    let (first, homotopy) = match solve_enclosed(model, z0.clone(), opts) {
        Ok(s) => (s, false),
        Err(plain) => match lambda_min {
            Some(lmin) => {
                let s = solve_by_pull_homotopy(model, z0, lmin, opts).map_err(|_| plain)?;
                (s, true)
            }
            None => return Err(plain),
        },
    };
    // The prolonged start has its contact ends a node or two off (`solve_prolonged`).
    let refine = |prev: &EnclosedState| -> Result<EnclosedState, SolverError> {
        let (model, z0) = prev.refine()?;
        let first_try = solve_prolonged(&model, z0.clone(), opts);
        match (first_try, lambda_min) {
            (Ok(s), _) => Ok(s),
            // The prolonged state is close to the finer solution; where the active set
            // cycles, the pull homotopy settles it.
            (Err(plain), Some(lmin)) if homotopy => {
                solve_by_pull_homotopy(&model, z0, lmin, opts).map_err(|_| plain)
            }
            (Err(plain), _) => Err(plain),
        }
    };
    let mut ladder = vec![first];
    for _ in 0..refinements.max(2) {
        let next = refine(ladder.last().expect("a level"))?;
        ladder.push(next);
    }
    let fine = ladder.pop().expect("N");
    let coarse = ladder.pop().expect("N/2");
    let quarter = ladder.pop().expect("N/4");
    let eighth = ladder.pop();
    assemble(fine, coarse, quarter, eighth, homotopy)
}

/// The state `state` carried to `cells` cells: its curvature interpolated
/// ([`EnclosedState::curvature_at`]), the same start point, the multipliers carried over
/// ([`transfer_multipliers`]); a start for [`solve_enclosed`].
pub fn resample_state(
    state: &EnclosedState,
    cells: usize,
) -> Result<(super::model::EnclosedModel, Vec<f64>), SolverError> {
    let m = &state.model;
    let r0 = m.start_point(&state.z);
    let stiff = m.stiffness().kind().clone();
    let (model, mut z) = start_from_curvature(
        m.wall(),
        m.lbar(),
        cells,
        &stiff,
        |s| state.curvature_at(s),
        [r0[0], r0[1], r0[2]],
    )?;
    transfer_multipliers(m, &state.z, &model, &mut z);
    Ok((model, z))
}

/// The levels `N/2, N/4` of a state solved at `N` cells (each re-solved from `fine`
/// resampled, [`resample_state`]) and the error estimate of [`solve_levels`]: for a state
/// found at the finest level (a descent from a saddle there).
pub fn solve_levels_from_fine(
    fine: EnclosedState,
    opts: &EnclosedOptions,
) -> Result<BranchSolve, SolverError> {
    let n = fine.model.cells();
    if n < 32 || n % 4 != 0 {
        return Err(SolverError::InvalidInput(format!(
            "enclosed solves need a multiple of 4 cells, at least 32 (got {n})"
        )));
    }
    let (m2, z2) = resample_state(&fine, n / 2)?;
    let coarse = solve_enclosed(&m2, z2, opts)?;
    let (m4, z4) = resample_state(&fine, n / 4)?;
    let quarter = solve_enclosed(&m4, z4, opts)?;
    assemble(fine, coarse, quarter, None, false)
}

/// A [`BranchSolve`] from its three levels `N, N/2, N/4` solved separately (each continued
/// from the levels of a solve at another length, as the enclosed diagram walks its traces'
/// levels): [`solve_levels`]'s estimate.
pub fn branch_from_levels(
    fine: EnclosedState,
    coarse: EnclosedState,
    quarter: EnclosedState,
) -> Result<BranchSolve, SolverError> {
    let n = fine.model.cells();
    if coarse.model.cells() * 2 != n || quarter.model.cells() * 4 != n {
        return Err(SolverError::InvalidInput(format!(
            "levels of {n}, {} and {} cells are not N, N/2, N/4",
            coarse.model.cells(),
            quarter.model.cells()
        )));
    }
    assemble(fine, coarse, quarter, None, false)
}

/// A [`BranchSolve`] from its levels: the contact summary of the finest and the error
/// estimate (see [`BranchSolve::energy_error`]).
fn assemble(
    fine: EnclosedState,
    coarse: EnclosedState,
    quarter: EnclosedState,
    eighth: Option<EnclosedState>,
    homotopy: bool,
) -> Result<BranchSolve, SolverError> {
    let energy = fine.energy();
    let contact = fine.contact(1e-9)?;
    let attached = contact.fraction >= 1.0;
    let point_like = !attached && point_like_contact(&fine, &contact);
    let mut centred_energy = None;
    let (energy_error, order) = if attached {
        three_level_estimate(quarter.energy(), coarse.energy(), energy, 4.0)
    } else {
        let max_order = if point_like {
            1.0
        } else {
            LIFTED_OFF_MAX_ORDER
        };
        let levels: Vec<&EnclosedState> = eighth.iter().chain([&quarter, &coarse, &fine]).collect();
        let centred = if point_like {
            super::centre::centre_levels(&levels, &EnclosedOptions::default())
        } else {
            None
        };
        match centred {
            // Point contacts on nodes converge at fourth order: the estimate is
            // POINT_CONTACT_SAFETY times the distance to that ladder's finest energy, plus
            // its own estimate.
            Some(c) => {
                let e: Vec<f64> = c.iter().map(|s| s.energy()).collect();
                let (est, p) = ladder_estimate(&e, 4.0);
                centred_energy = Some((e[e.len() - 1], est));
                (
                    POINT_CONTACT_SAFETY * (energy - e[e.len() - 1]).abs() + est,
                    p,
                )
            }
            None => {
                let (est, p) = ladder_estimate(
                    &levels.iter().map(|s| s.energy()).collect::<Vec<_>>(),
                    max_order,
                );
                let safety = if point_like {
                    POINT_CONTACT_SAFETY
                } else {
                    1.0
                };
                (safety * est, p)
            }
        }
    };
    Ok(BranchSolve {
        fine,
        coarse,
        quarter,
        eighth,
        energy,
        energy_error,
        order,
        point_contact: point_like,
        centred_energy,
        homotopy,
    })
}

/// [`four_level_estimate`] over four energies (coarsest first), [`three_level_estimate`]
/// over three.
fn ladder_estimate(e: &[f64], max_order: f64) -> (f64, f64) {
    match *e {
        [a, b, c, d] => four_level_estimate([a, b, c, d], max_order),
        [.., a, b, c] => three_level_estimate(a, b, c, max_order),
        _ => (f64::INFINITY, 1.0),
    }
}

impl BranchSolve {
    /// The stability index of the finest level, the state reported: counted on `N/2` and
    /// carried to `N` where the two levels' Newton Jacobians have determinants of one sign,
    /// counted on `N` where they differ ([`EnclosedState::index_via`]).
    pub fn index(&self, tol: f64) -> Result<usize, SolverError> {
        self.fine.index_via(&self.coarse, tol)
    }

    /// The coarsest level kept (`N/8` where the cascade has it, else `N/4`): where callers
    /// compute the lowest eigenvalues of the constrained Hessian (a dense
    /// eigen-decomposition, `O(N³)`) and step along its unstable directions.
    pub fn coarsest(&self) -> &EnclosedState {
        self.eighth.as_ref().unwrap_or(&self.quarter)
    }

    /// How the error estimate was formed, for reports: the levels, the order and whether
    /// the contact is point-like.
    pub fn estimate_method(&self) -> String {
        let levels = if self.eighth.is_some()
            && self.fine.contact(1e-9).is_ok_and(|c| c.fraction < 1.0)
        {
            "N/8, N/4, N/2, N (the smaller of the two observed orders; the larger of the last two differences' estimates)"
        } else {
            "N/4, N/2, N"
        };
        format!(
            "error from {levels}, order {:.2}{}",
            self.order,
            match (self.point_contact, self.centred_energy) {
                (true, Some((e, de))) => format!(
                    " (point-like contact: distance to the ladder with nodes at the contact points, {e:.10} ± {de:.1e}, plus its estimate)"
                ),
                (true, None) => " (point-like contact: order 1)".into(),
                _ => String::new(),
            }
        )
    }
}

/// Safety factor of the point-contact estimates. Where the contact points are on nodes
/// ([`super::centre`]) it covers their location (by the lever rule, to a fraction of a
/// cell): on the figure-eight at `L̄ = 1.2` the node-centred ladders located at `N = 512`
/// and `N = 1024` end 1.1e-9 apart, a third of the distance `|E_512 − E_c|`. Elsewhere
/// (contacts on single nodes or unresolved) the order-1 rule's errors fall irregularly:
/// at `N = 128` there the rule is 1.17× short (against the node-centred `N = 1024` ladder).
pub const POINT_CONTACT_SAFETY: f64 = 2.0;

/// Contact runs at most this many cells long count as point-like ([`point_like_contact`]).
pub const POINT_CONTACT_CELLS: usize = 4;

/// Does a lifted-off state touch the wall only at points: every contact run spans at most
/// [`POINT_CONTACT_CELLS`] cells of its mesh? There the energy converges irregularly and
/// slowly (the figure-eight at `L̄ = 1.2` touches at two points: errors against `N = 1024`
/// of 7.2e-7, 3.9e-7, 3.2e-9 relative at `N = 64, 128, 256`), so the estimate takes order 1.
pub fn point_like_contact(state: &EnclosedState, contact: &super::solve::Contact) -> bool {
    if contact.runs.is_empty() || contact.fraction >= 1.0 {
        return false;
    }
    let n = state.model.cells() as f64;
    contact.runs.iter().all(|&(a, b)| {
        let span = (b - a).rem_euclid(1.0);
        span * n <= POINT_CONTACT_CELLS as f64 + 1e-9
    })
}

/// Energy of the finest of `levels` (coarsest first, each of twice the cells of the one
/// before, at least three) and its error estimate, the rule of a ladder of meshes: a loop
/// touching the wall everywhere converges at the scheme's fourth order
/// ([`three_level_estimate`] over the last three, order at most 4); a lifted-off one by
/// [`four_level_estimate`] over the last four (three where there are three), its order at
/// most [`LIFTED_OFF_MAX_ORDER`], or 1 where its contact is point-like
/// ([`point_like_contact`]): the contact ends fall between nodes and the energies converge
/// irregularly. The enclosed diagrams' exchanges and `rodloop converge` use it.
pub fn finest_energy(levels: &[&EnclosedState]) -> Result<(f64, f64), SolverError> {
    let k = levels.len();
    if k < 3 {
        return Err(SolverError::InvalidInput(format!(
            "a ladder estimate needs three levels (got {k})"
        )));
    }
    let e: Vec<f64> = levels.iter().map(|s| s.energy()).collect();
    let fine = levels[k - 1];
    let c = fine.contact(1e-9)?;
    let max_order = if c.fraction >= 1.0 {
        4.0
    } else if point_like_contact(fine, &c) {
        1.0
    } else {
        LIFTED_OFF_MAX_ORDER
    };
    let (err, _) = if k >= 4 && c.fraction < 1.0 {
        four_level_estimate([e[k - 4], e[k - 3], e[k - 2], e[k - 1]], max_order)
    } else {
        three_level_estimate(e[k - 3], e[k - 2], e[k - 1], max_order)
    };
    Ok((e[k - 1], err))
}

/// Error estimate of the finest of four energies at `N/8, N/4, N/2, N` cells, for sequences
/// that converge irregularly (contact ends between nodes): the order is the smaller of the
/// two observed, `p = min(log2(d0/d1), log2(d1/d2))` with `d_k` the successive differences,
/// clamped to `[1, max_order]`, and the estimate is the larger of `d2/(2^p − 1)` and
/// `d1/((2^p − 1) 2^p)`, so that one small difference (two levels whose errors happen to
/// match) does not make it small. Exact on `E + C N^{−p}` for `p ≤ max_order`. Returns
/// `(estimate, p)`.
///
/// On the figure-eight (`1.2 ≤ L̄ ≤ 1.5`, against `N = 1024`) it bounds the error at
/// `N = 256` at every length but `L̄ = 1.3` (where it is 3.7× short: the error halves
/// only from `N = 128` to 256 after falling 4.5× and 80× before), while the three-level
/// rule was short at `L̄ = 1.3, 1.33, 1.36, 1.38`.
pub fn four_level_estimate(e: [f64; 4], max_order: f64) -> (f64, f64) {
    let d = [
        (e[1] - e[0]).abs(),
        (e[2] - e[1]).abs(),
        (e[3] - e[2]).abs(),
    ];
    let observed = |a: f64, b: f64| {
        if a > 0.0 && b > 0.0 {
            (a / b).log2()
        } else {
            max_order
        }
    };
    let order = observed(d[0], d[1])
        .min(observed(d[1], d[2]))
        .clamp(1.0, max_order);
    let q = 2f64.powf(order);
    ((d[2] / (q - 1.0)).max(d[1] / ((q - 1.0) * q)), order)
}

/// The check of a lifted-off state `fine` (`N` cells; `coarse_energy` its `N/2` level's) on
/// twice its cells: `fine` prolonged with its contact runs ([`EnclosedState::refine_in_runs`])
/// and re-solved, `E_2N`'s own estimate from `N/2, N, 2N` (the three-level rule, order at
/// most [`LIFTED_OFF_MAX_ORDER`]), and the bound `|E_N − E_2N|` plus that estimate. Where the
/// levels `N/4, N/2, N` converge irregularly (a contact run the coarse levels have and the
/// fine one does not) their three-level estimate can be short; the bound is not, on the
/// random two-segment scenes measured (a state at 128 cells with estimate 1.2e-6 and error
/// 2.9e-6 against 4096 cells gets 4.7e-6). Returns `(bound, E_2N)`, `None` where the
/// re-solve fails.
pub fn finer_check(
    fine: &EnclosedState,
    coarse_energy: f64,
    opts: &EnclosedOptions,
) -> Option<(f64, f64)> {
    let (m, z) = fine.refine_in_runs().ok()?;
    let finer = solve_prolonged(&m, z, opts).ok()?;
    let (e, e2) = (fine.energy(), finer.energy());
    let (own, _) = three_level_estimate(coarse_energy, e, e2, LIFTED_OFF_MAX_ORDER);
    Some(((e - e2).abs() + own, e2))
}

/// Largest order trusted by [`three_level_estimate`] on a lifted-off state. The contact
/// ends fall between nodes, so the observed order wanders (2.8–4.0 over `N = 16, 32, 64` on
/// the figure-eight at `1.36 ≤ L̄ ≤ 1.5`) and the fourth-order rule understated the error at
/// `N = 64` by up to 1.9× (`L̄ = 1.38`, `1.4`, against `N = 256`); the third-order rule
/// bounds it there.
///
/// With the `O(N)` Newton step, finer meshes showed the order falling again: over
/// `N = 128, 256, 512` on the figure-eight at `L̄ = 1.4` it is 2.59, and the third-order rule
/// understated the error at `N = 256` by 1.3× (against `N = 512`). The cap is 2.5.
pub const LIFTED_OFF_MAX_ORDER: f64 = 2.5;

/// The `L̄` intervals (within `(lo, hi)`) where the paper's homogeneous branch with `eta`
/// periods needs a pulling wall somewhere, `λ_min < 0`, and so lifts off in the ball. For
/// the wave family Eq. (38) gives `λ_min R³/D = c²(1 − 2k²)`: the loop detaches exactly
/// where `k² > 1/2`. The branch's `k²` at `L̄` is the one root in `m` of the closure
/// condition, where the continuous winding `p_cont(L̄, m)` (Eqs. (48)–(50)) falls through
/// `q = −(η + 1)` ([`rodloop_exact::paper_branch_loop`]); so `k² > 1/2` exactly where
/// `p_cont(L̄, 1/2) > q`, and the ends are the roots in `L̄` of that one closure evaluation
/// (not of `k²(L̄)`, which takes a root search in `m` each), on a grid of 400 steps and by
/// Brent's method to `10⁻¹⁴` relative.
pub fn detached_intervals(eta: u32, lo: f64, hi: f64) -> Result<Vec<(f64, f64)>, SolverError> {
    let e = f64::from(eta);
    let (a, b) = ((e - 1.0).max(lo), (e + 1.0).min(hi));
    if a >= b {
        return Ok(Vec::new());
    }
    let q = -(e + 1.0);
    let f = |l: f64| {
        rodloop_exact::homogeneous::closure(rodloop_exact::Family::Wave, eta, l, 0.5)
            .map(|c| c.p_cont - q)
    };
    let steps = 400;
    let pad = 1e-9;
    let grid: Vec<f64> = (0..=steps)
        .map(|i| a + pad + (b - a - 2.0 * pad) * i as f64 / steps as f64)
        .collect();
    let mut vals = Vec::with_capacity(grid.len());
    for &l in &grid {
        vals.push(f(l)?);
    }
    let mut out = Vec::new();
    let mut start = if vals[0] > 0.0 { Some(a) } else { None };
    for i in 1..grid.len() {
        if (vals[i - 1] > 0.0) != (vals[i] > 0.0) {
            let root = rodloop_exact::roots::brent(f, grid[i - 1], grid[i], 1e-14, 200)?;
            match start.take() {
                Some(s) => out.push((s, root)),
                None => start = Some(root),
            }
        }
    }
    if let Some(s) = start {
        out.push((s, b));
    }
    Ok(out)
}
