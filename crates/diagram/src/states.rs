//! Quantities of a traced state: the equilibrium re-solved at the tracing resolution, its
//! Richardson partner at half the resolution (energy, geodesic energy and contact-force
//! extremes extrapolated like `h⁴`), the slope `dE/dL̄` from the multipliers, and the
//! stability index; plus the small model helpers the assembly shares (a model with the
//! phase condition of a reference state, Newton options for re-solving known states).

use std::f64::consts::PI;

use rodloop_solver::{
    solve, solve_newton_keeping, Claim, Confinement, Equilibrium, Globalization, Param,
    ParamProblem, Phase, SolveOptions, SolverError, SurfaceSolve,
};

use crate::march::MarchPoint;
use crate::types::{FinerRun, TracedBranch, TracedPoint};
use crate::DiagramOptions;

/// Threshold below which an eigenvalue (units of `D0`) counts as negative (the solver's
/// default, [`rodloop_solver::StabilityOptions`]).
pub(crate) const INDEX_TOLERANCE: f64 = 1e-6;

pub(crate) use crate::model_with_phase;

/// Newton options for re-solving known states.
pub(crate) fn newton_options() -> SolveOptions {
    SolveOptions {
        globalization: Globalization::Newton,
        max_iterations: 30,
        ..SolveOptions::default()
    }
}

/// `dE/dL̄` along the branch at the KKT state `z` (normalised as `E R/(π D0)`):
/// `dE/dL̄ = ∂E/∂L̄ + ∇E·κ̇ = E/L̄ + μ·(∂(−c)/∂L̄)`, because `∇E = ∇cᵀμ + ν∇φ`,
/// `∇c κ̇ = −∂c/∂L̄` and `∇φ κ̇ = 0` (the phase condition does not depend on `L̄`).
pub(crate) fn energy_slope(eq: &Equilibrium) -> Result<f64, SolverError> {
    let (model, z) = (eq.model(), &eq.state());
    let (kappa, mu, _) = model.split(z)?;
    let e = model.energy(kappa)?;
    let d = model.kkt_dlbar(z)?;
    let nk = model.n_kappa();
    let de = e / model.lbar() + mu[0] * d[nk] + mu[1] * d[nk + 1] + mu[2] * d[nk + 2];
    Ok(de * model.radius() / (PI * model.stiffness().kind().reference()))
}

/// Quantities of a traced state: equilibrium at the tracing resolution (Newton check),
/// Richardson partner at half the resolution, the error estimate from the ladder with twice
/// the resolution ([`crate::estimate::ladder_error`]), slope, forces, index.
pub(crate) fn finish_point<M: SurfaceSolve>(
    opts: &DiagramOptions,
    problem: &ParamProblem<M>,
    raw: &MarchPoint,
) -> Option<TracedPoint> {
    let eq = match problem
        .model_at(raw.value)
        .and_then(|m| m.solve_from_state(raw.x.clone(), &newton_options()))
    {
        Ok(eq) => eq,
        Err(_) => return None,
    };
    let z = eq.state();
    let en = eq.energy();
    let (lmin, lmax) = eq.lambda_range();
    let slope = energy_slope(&eq).unwrap_or(f64::NAN);
    let amplitude = eq
        .kappa()
        .iter()
        .fold(0.0f64, |a, v| a.max(v.abs() * opts.radius));
    let index = match raw.index {
        Some(i) => i,
        None => eq.model().index(&z, INDEX_TOLERANCE).ok()?,
    };
    let cells = eq.model().cells();
    let partner = if cells / 2 >= crate::profile_cells(&opts.stiffness) {
        half_resolution(opts, &eq, cells / 2)
    } else {
        None
    };
    let mut kept = FinerRun::default();
    let (energy, energy_g, energy_error, lambda_min, lambda_max) = match partner {
        Some(h) => {
            let eh = h.energy();
            let (hmin, hmax) = h.lambda_range();
            let rich = rodloop_solver::richardson;
            // The third rung of the estimate's ladder (`crate::estimate`), its run kept for
            // the verification's re-solve at the same resolution (`resolved`).
            let (finer, run) = finer_resolution(opts, &eq, 2 * cells);
            kept = run;
            let finer = finer.map(|d| d.energy().total);
            (
                rich(en.total, eh.total),
                rich(en.geodesic, eh.geodesic),
                Some(crate::estimate::ladder_error(en.total, eh.total, finer)),
                rich(lmin, hmin),
                rich(lmax, hmax),
            )
        }
        None => (en.total, en.geodesic, None, lmin, lmax),
    };
    let values = [energy, energy_g, en.total, slope, lambda_min, lambda_max];
    if values.iter().any(|v| !v.is_finite()) {
        return None;
    }
    Some(TracedPoint {
        value: raw.value,
        energy,
        energy_g,
        energy_error,
        energy_trace: en.total,
        slope,
        index,
        lambda_min,
        lambda_max,
        amplitude,
        source: raw.source,
        state: z,
        finer: kept,
    })
}

/// The equilibrium `eq` re-solved with `cells` cells (resampled start, phase condition from
/// the resampled profile so that the arclength origin is the same).
pub(crate) fn half_resolution(
    opts: &DiagramOptions,
    eq: &Equilibrium,
    cells: usize,
) -> Option<Equilibrium> {
    if cells < 4 {
        return None;
    }
    let kappa = eq.resample(cells).ok()?;
    let model = model_with_phase(opts, eq.lbar(), cells, &kappa).ok()?;
    solve(&model, &kappa, &newton_options()).ok()
}

/// [`half_resolution`] at `cells` cells by [`rodloop_solver::solve_newton_keeping`]: the
/// equilibrium, and the run kept for [`resolved`] (its tolerance, [`RESOLVED_TOLERANCE`]).
fn finer_resolution(
    opts: &DiagramOptions,
    eq: &Equilibrium,
    cells: usize,
) -> (Option<Equilibrium>, FinerRun) {
    let none = || (None, FinerRun::default());
    if cells < 4 {
        return none();
    }
    let Ok(kappa) = eq.resample(cells) else {
        return none();
    };
    let Ok(model) = model_with_phase(opts, eq.lbar(), cells, &kappa) else {
        return none();
    };
    let (r, run) = solve_newton_keeping(&model, &kappa, &newton_options(), RESOLVED_TOLERANCE);
    (r.ok(), FinerRun::new(kappa, run))
}

/// Re-solving a traced branch's states (here, beside the solver helpers they use, so that
/// the data type [`TracedBranch`] does not depend on this module).
impl TracedBranch {
    /// The model of the tracing resolution at `lbar`, with a phase condition taken from
    /// `state` (uniform stiffness) so that `state` satisfies it exactly.
    pub(crate) fn model_for(
        &self,
        opts: &DiagramOptions,
        lbar: f64,
        state: &[f64],
    ) -> Result<impl SurfaceSolve, SolverError> {
        model_with_phase(opts, lbar, self.cells, &state[..2 * self.cells])
    }

    /// The equilibrium of traced state `k` itself, at the tracing resolution: Newton from its
    /// own KKT state (already converged, so normally no step), giving its profile
    /// (positions, forces). Only for branches traced in `lbar`.
    pub fn equilibrium_of(
        &self,
        opts: &DiagramOptions,
        k: usize,
    ) -> Result<Equilibrium, SolverError> {
        let p = self.points.get(k).ok_or_else(|| {
            SolverError::InvalidInput(format!(
                "branch eta = {} has {} states, no state {k}",
                self.eta,
                self.points.len()
            ))
        })?;
        if self.param != Param::Lbar {
            return Err(SolverError::InvalidInput(format!(
                "branch eta = {} was traced in {}, not in lbar",
                self.eta, self.param
            )));
        }
        let dim = 2 * self.cells + 3 + usize::from(self.phase);
        if p.state.len() != dim {
            return Err(SolverError::WrongLength {
                expected: dim,
                found: p.state.len(),
            });
        }
        let model = self.model_for(opts, p.value, &p.state)?;
        // The traced state met the corrector's tolerance: accept it as it is unless its
        // residual has grown above 1e-8 (a state read from an older file).
        let accept = rodloop_solver::SolveOptions {
            tolerance: 1e-8,
            ..newton_options()
        };
        model.solve_from_state(p.state.clone(), &accept)
    }

    /// The equilibrium of this branch at `lbar` at the tracing resolution (Newton from the
    /// interpolated traced states). Only for branches traced in `lbar`.
    pub fn solve_at(&self, opts: &DiagramOptions, lbar: f64) -> Result<Equilibrium, SolverError> {
        if self.param != Param::Lbar {
            return Err(SolverError::InvalidInput(format!(
                "branch eta = {} was traced in {}, not in lbar",
                self.eta, self.param
            )));
        }
        let z = self.state_near(lbar);
        let dim = 2 * self.cells + 3 + usize::from(self.phase);
        if z.len() != dim {
            return Err(SolverError::WrongLength {
                expected: dim,
                found: z.len(),
            });
        }
        let model = self.model_for(opts, lbar, &z)?;
        model.solve_from_state(z, &newton_options())
    }
}

/// Points per state file (uniform in arclength), at least; more when the state's resolution
/// has more cells, and doubled until the samples hold the state (see
/// [`TracedBranch::verified_state`]).
pub const STATE_POINTS: usize = 128;

/// Most points per state file.
pub const MAX_STATE_POINTS: usize = 16_384;

/// Multiple of a row's error estimate within which the energy recomputed from its file must
/// lie (the estimate is that of the Richardson-extrapolated energy, which the file's single
/// resolution approaches like `h⁴`; see [`TracedBranch::verified_state`]).
pub const ESTIMATES: f64 = 5.0;

/// Relative tolerance of the file's energy for a row without an error estimate (its
/// half-resolution partner failed, so its discretisation error is not known; measured up to
/// 3e-5 relative on random two-segment scenes, `cargo test --release --test random_scenes`).
pub const NO_ESTIMATE_TOLERANCE: f64 = 1e-4;

/// Largest refinement of a state file's resolution over the tracing resolution
/// ([`TracedBranch::verified_state`]): three doublings reduce an `O(h⁴)` error 4096-fold.
pub const MAX_REFINEMENT: usize = 8;

/// A traced state as its file holds it, verified against its row.
#[derive(Clone, Debug, PartialEq)]
pub struct StateFile {
    /// The profile at points uniform in arclength (dimensional, the model's `R` and `D`).
    pub profile: Vec<rodloop_solver::ProfilePoint>,
    /// What was measured on it ([`rodloop_solver::verify_state`]).
    pub verification: rodloop_solver::Verification,
    /// Cells of the equilibrium the file samples (the tracing resolution, or a multiple of it
    /// where that resolution's profile does not reproduce the row's energy).
    pub cells: usize,
    /// The row's energy and error estimate re-estimated from refined resolutions, where the
    /// row's own disagreed with them beyond both estimates (see
    /// [`TracedBranch::verified_state`]).
    pub row: Option<(f64, f64)>,
}

impl StateFile {
    /// Whether the dominant harmonic of the written `κ_g` differs from the branch's `η`
    /// (the state is of its branch by continuation, see [`TracedBranch::verified_state`]).
    pub fn counted_other_eta(&self, eta: u32) -> bool {
        self.verification.eta != eta
    }
}

/// `E R/(π D0)` of the trigonometric interpolant of `κ_g` of `eq` at `m` points uniform in
/// arclength (what a state file of `m` points gives, without building its other columns).
fn sampled_energy(
    eq: &Equilibrium,
    kg: &rodloop_solver::periodic::TrigInterpolant,
    m: usize,
    d0: f64,
) -> f64 {
    let model = eq.model();
    let (r, length) = (model.radius(), model.length());
    let map = model.mesh();
    let h = length / m as f64;
    let us = map.u_of_sigmas((0..m).map(|j| j as f64 / m as f64));
    let e: f64 = (0..m)
        .map(|j| {
            let sigma = j as f64 / m as f64;
            let k = kg.eval(us[j]);
            let d = model.stiffness().eval(sigma).per_arclength(length).0;
            0.5 * d * (k * k + 1.0 / (r * r)) * h
        })
        .sum();
    e * r / (PI * d0)
}

/// The profile of `eq` at `m ≥ min_points` points uniform in arclength, `m` doubled (up to
/// [`MAX_STATE_POINTS`]) until the energy of the samples settles (changes by less than a
/// thousandth of `tol` on doubling) or lies within `tol` of `target`: uniform samples of a
/// graded mesh miss narrow features (a very soft segment bent sharply, a steep stiffness
/// step).
pub(crate) fn uniform_profile(
    eq: &Equilibrium,
    min_points: usize,
    target: f64,
    tol: f64,
    d0: f64,
) -> Result<Vec<rodloop_solver::ProfilePoint>, SolverError> {
    let kg = rodloop_solver::periodic::TrigInterpolant::new(
        &eq.profile().iter().map(|p| p.kappa_g).collect::<Vec<_>>(),
    )?;
    let mut m = min_points.max(8);
    let mut e_m = sampled_energy(eq, &kg, m, d0);
    while m < MAX_STATE_POINTS && (e_m - target).abs() > tol {
        let e_2m = sampled_energy(eq, &kg, 2 * m, d0);
        m *= 2;
        let settled = (e_2m - e_m).abs() <= 1e-3 * tol;
        e_m = e_2m;
        if settled {
            break;
        }
    }
    eq.profile_uniform(m)
}

impl TracedBranch {
    /// Traced state `k` as its state file holds it, verified against its row
    /// ([`rodloop_solver::verify_state`]): the loop closes (holonomy and written points),
    /// lies on the sphere, and the energy
    /// recomputed from the written samples (`½ ∮ D κ² ds`, Eq. (2)) equals the row's within
    /// [`ESTIMATES`] times the row's error estimate (or [`NO_ESTIMATE_TOLERANCE`] without
    /// one) plus the quadrature's own error.
    ///
    /// The row's energy is Richardson-extrapolated from the tracing resolution `N` and
    /// `N/2`; a file samples one resolution, whose profile (`κ_g = 𝓜·n/D`, Eq. (41), at the
    /// cell boundaries) carries that resolution's `O(h⁴)` discretisation error. Where that
    /// error exceeds the row's estimate (a very soft segment: on `D1/D0 = 0.001`, branch 2
    /// near `L̄ = 1`, the profile at the tracing resolution is 1e-3 relative off while the
    /// estimate is 6e-6), the state is re-solved at `2N`, `4N`, … (Newton from its resampled
    /// profile at the same `L̄`), up to [`MAX_REFINEMENT`]` N`, and the file samples the
    /// finest state needed.
    ///
    /// The refined states also test the row: where the pair `(N, N/2)` is not yet in the
    /// asymptotic range its estimate is too small (the same states: row 4.7e-5 above the
    /// converged energy with an estimate of 5.9e-6). When the Richardson value of two
    /// refined resolutions `(E_{2^j N}, E_{2^{j−1} N})`, whose differences decrease at least
    /// fourfold per doubling (so that the refined states are the traced state converging,
    /// not a neighbouring sheet), disagrees with the row beyond both estimates, the row is
    /// re-estimated from that pair ([`StateFile::row`]).
    ///
    /// The branch of a traced state is its family's: the family is traced by continuation
    /// from a seed whose periods were counted. The periods of the state's own `κ_g`
    /// ([`rodloop_solver::Verification::eta`]) are counted too; near the great circles
    /// (`L̄` at an integer, `κ_g` nearly constant) and on soft segments the dominant harmonic
    /// can differ from the family's `η` ([`StateFile::counted_other_eta`]).
    ///
    /// Errors: [`SolverError::Unverified`] naming why no resolution up to the limit passes
    /// (see [`verify_refining`]); the state's own errors when it cannot be re-evaluated.
    pub fn verified_state(
        &self,
        opts: &DiagramOptions,
        k: usize,
    ) -> Result<StateFile, SolverError> {
        let eq = self.equilibrium_of(opts, k)?;
        let p = &self.points[k];
        verify_refining_from(
            &eq,
            p.energy,
            sheet_estimate(&self.points, k),
            Ladder::ReEstimate,
            &p.finer,
        )
    }
}

/// What the refinement ladder of [`verify_refining`] may do with the reported energy.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Ladder {
    /// The claim stays the reported energy and estimate (`phase`, `--param`, `converge`).
    Keep,
    /// The claim is re-estimated from two refined resolutions when they converge and
    /// disagree with it (the traced states of the `L̄` diagrams: [`StateFile::row`]).
    ReEstimate,
}

/// The one verification loop of every state written to a file (the diagrams' traced states
/// through [`TracedBranch::verified_state`], and the states `phase`, `--param` and `converge`
/// report): `eq` (`N` cells) checked as its file holds it against `energy` within [`ESTIMATES`] times `energy_error` (or
/// [`NO_ESTIMATE_TOLERANCE`] times `max(|energy|, 1)` without one); where the check fails,
/// re-solved at `2N`, `4N`, … ([`resolved`]) up to [`MAX_REFINEMENT`]` N`, the file sampling
/// the finest state needed.
///
/// With [`Ladder::ReEstimate`], from the third resolution on: when the differences of the
/// ladder `(E_{2^{j−2} N}, E_{2^{j−1} N}, E_{2^j N})` decrease at least fourfold (the refined
/// states are this state converging, not a neighbouring sheet) and the Richardson value of
/// the last two disagrees with the claim beyond both estimates, the claim becomes that
/// value with its estimate ([`StateFile::row`]).
///
/// A state that still fails is left out with the cause named: where Newton finds no
/// equilibrium at the next resolution, the check that fails at its own, whether its cells
/// resolve its bends (the largest turning of its tangent in one cell against
/// [`UNRESOLVED_TURNING`]), its own error estimate, and how Newton ended; where the refined
/// states do not converge like `h⁴`, that the finer resolutions hold another state than the
/// row's, with the ladder's energies.
pub(crate) fn verify_refining(
    eq: &Equilibrium,
    energy: f64,
    energy_error: Option<f64>,
    ladder: Ladder,
) -> Result<StateFile, SolverError> {
    verify_refining_from(eq, energy, energy_error, ladder, &FinerRun::default())
}

/// [`verify_refining`] whose re-solve at `2N` goes on from `finer` where that is a run of
/// the same model from the same start ([`resolved_from`]): the same result without repeating
/// the run.
fn verify_refining_from(
    eq: &Equilibrium,
    energy: f64,
    energy_error: Option<f64>,
    ladder: Ladder,
    finer: &FinerRun,
) -> Result<StateFile, SolverError> {
    let d0 = eq.model().stiffness().kind().reference();
    let scale = energy.abs().max(1.0);
    let mut claim = Claim {
        energy,
        energy_error: match energy_error {
            Some(e) => ESTIMATES * e,
            None => NO_ESTIMATE_TOLERANCE * scale,
        },
        profile_error: 0.0,
        eta: None,
    };
    let mut row: Option<(f64, f64)> = None;
    let first = eq.model().cells();
    let mut refined: Option<Equilibrium> = None;
    // Discrete energies of the resolutions so far (the state's own first).
    let mut energies = vec![eq.energy().total];
    // The check that fails at the state's own resolution.
    let mut first_why: Option<String> = None;
    loop {
        let at = refined.as_ref().unwrap_or(eq);
        let cells = at.model().cells();
        if ladder == Ladder::ReEstimate && energies.len() >= 3 {
            let n = energies.len();
            let (e2, e1, e0) = (energies[n - 1], energies[n - 2], energies[n - 3]);
            let converging = (e2 - e1).abs() <= 0.25 * (e1 - e0).abs();
            let (rich, est) = (
                rodloop_solver::richardson(e2, e1),
                rodloop_solver::richardson_error(e2, e1) + 8.0 * f64::EPSILON * scale,
            );
            if converging && (rich - claim.energy).abs() > claim.energy_error + ESTIMATES * est {
                row = Some((rich, est));
                claim.energy = rich;
                claim.energy_error = ESTIMATES * est;
            }
        }
        let profile = uniform_profile(
            at,
            STATE_POINTS.max(cells),
            claim.energy,
            claim.energy_error,
            d0,
        )?;
        match rodloop_solver::verify_state(at, &profile, &claim) {
            Ok(verification) => {
                return Ok(StateFile {
                    profile,
                    verification,
                    cells,
                    row,
                })
            }
            Err(why) => {
                let why = match why {
                    SolverError::Unverified(m) => m,
                    e => e.to_string(),
                };
                if first_why.is_none() {
                    first_why = Some(why.clone());
                }
                let own = || {
                    format!(
                        "at the {first} cells of its file {}",
                        first_why.as_deref().unwrap_or_default()
                    )
                };
                if 2 * cells > MAX_REFINEMENT * first {
                    return Err(SolverError::Unverified(format!(
                        "{}; {}",
                        own(),
                        ladder_reason(first, &energies, &why)
                    )));
                }
                let next = resolved_from(at, 2 * cells, finer).map_err(|e| {
                    let turning = turning_per_cell(at);
                    let estimate = energy_error.map_or("none".into(), |e| format!("{e:.1e}"));
                    let cause = if turning > UNRESOLVED_TURNING {
                        format!(
                            "it is not resolved at {cells} cells (its tangent turns by up to \
                             {turning:.2} rad in one cell; its own error estimate is {estimate})"
                        )
                    } else {
                        format!(
                            "its resolutions disagree beyond its own error estimate, \
                             {estimate}, although its tangent turns by at most {turning:.2} \
                             rad in one of its {cells} cells"
                        )
                    };
                    SolverError::Unverified(format!(
                        "{}: {cause}, and at {} cells Newton from its resampled profile finds \
                         no equilibrium within reach ({e})",
                        own(),
                        2 * cells
                    ))
                })?;
                energies.push(next.energy().total);
                refined = Some(next);
            }
        }
    }
}

/// Turning of the tangent within one cell (radians) above which a state's cells do not
/// resolve its bends: the scheme's error terms, powers of `κ h` from `(κ h)⁴` on, are no
/// longer small (`0.5⁴ ≈ 0.06`).
const UNRESOLVED_TURNING: f64 = 0.5;

/// The largest turning of the tangent within one cell of `eq`, `max |κ_g| h` over its cell
/// boundaries (radians): the state's own scale of resolution (of order 1 where the cells do
/// not resolve its bends).
fn turning_per_cell(eq: &Equilibrium) -> f64 {
    let p = eq.profile();
    let length = eq.model().length();
    let n = p.len();
    (0..n)
        .map(|j| {
            let ds = if j + 1 < n {
                p[j + 1].s - p[j].s
            } else {
                length + p[0].s - p[j].s
            };
            let k = p[j].kappa_g.abs().max(p[(j + 1) % n].kappa_g.abs());
            k * ds
        })
        .fold(0.0, f64::max)
}

/// Why the finest resolution of the ladder `energies` (`E_N, E_{2N}, …` from `first = N`
/// cells) still fails (`why`): the refined states either converge like `h⁴` (their
/// differences fall at least fourfold per doubling) to a value the file's samples miss, or
/// they do not, and then the finer resolutions hold another state than the row's.
fn ladder_reason(first: usize, energies: &[f64], why: &str) -> String {
    let cells: Vec<String> = (0..energies.len())
        .map(|j| format!("{}", first << j))
        .collect();
    let values: Vec<String> = energies.iter().map(|e| format!("{e:.10}")).collect();
    let diffs: Vec<f64> = energies.windows(2).map(|w| (w[1] - w[0]).abs()).collect();
    let converging = diffs.len() >= 2 && diffs.windows(2).all(|d| d[1] <= 0.25 * d[0]);
    let finest = first << (energies.len() - 1);
    if converging {
        format!(
            "re-solved at {} cells its energies {} converge like h⁴, and at {finest} cells {why}",
            cells.join(", "),
            values.join(", ")
        )
    } else {
        format!(
            "re-solved from its own profile at {} cells its energies are {}, which do not \
             converge like h⁴ (differences {}): the finer resolutions hold another state \
             than its row's, so no file holds the row's state (at {finest} cells {why})",
            cells.join(", "),
            values.join(", "),
            diffs
                .iter()
                .map(|d| format!("{d:.1e}"))
                .collect::<Vec<_>>()
                .join(", ")
        )
    }
}

/// `eq` re-solved with `cells` cells at its own length and stiffness for a state file, by the
/// diagrams ([`TracedBranch::verified_state`]) and by `phase`, `converge` and
/// `--param` alike: the resampled profile as start (and, for uniform stiffness, as phase
/// reference), Newton to the tolerance a traced state is accepted with (`1e-8`, as in
/// [`crate::TracedBranch::equilibrium_of`]; on a very soft segment, `D1/D0 = 0.001`, the
/// residual of the finer resolutions stalls at a few 1e-9 in round-off), for as long as the
/// run converges ([`newton_until_stall`]).
pub(crate) fn resolved(eq: &Equilibrium, cells: usize) -> Result<Equilibrium, SolverError> {
    resolved_from(eq, cells, &FinerRun::default())
}

/// The tolerance of [`resolved`]'s Newton run.
const RESOLVED_TOLERANCE: f64 = 1e-8;

/// Newton passes of [`resolved`] between two looks at its progress.
const NEWTON_STRETCH: usize = 20;

/// Least factor by which the KKT residual falls over [`NEWTON_STRETCH`] passes for
/// [`newton_until_stall`] to go on: a steady linear rate of at least 3.5 % per pass (a
/// Newton-like run falls far faster; damped steps from a start that its resolution moves,
/// a very soft segment bent sharply, creep at such rates); a run that falls slower has
/// stalled.
const STEADY_FALL: f64 = 2.0;

/// [`resolved`], going on from the kept run `finer` where it is a run of the same model
/// from the same start ([`FinerRun::resume_keeping`]; the same iterates, so the same result).
fn resolved_from(
    eq: &Equilibrium,
    cells: usize,
    finer: &FinerRun,
) -> Result<Equilibrium, SolverError> {
    let m = eq.model();
    let kappa = eq.resample(cells)?;
    let kind = m.stiffness().kind();
    let mut model = m.with_cells(cells)?;
    if kind.is_uniform() {
        model = model.with_phase(Phase::from_gauss_values(&kappa, cells)?)?;
    }
    newton_until_stall(&model, &kappa, finer)
}

/// Newton's method for `model` from `start` (curvature at the Gauss points) to
/// [`RESOLVED_TOLERANCE`], its iteration limit following the run's own convergence: the run
/// goes on by [`NEWTON_STRETCH`] passes at a time while its residual keeps falling at least
/// [`STEADY_FALL`]-fold per stretch, and stops where it stalls (then the error of the last
/// pass). The residual falls that much per stretch from a finite start to the tolerance, so
/// the run ends. Goes on from the kept run `finer` where that is a run of this model and
/// start.
fn newton_until_stall(
    model: &rodloop_solver::SurfaceModel,
    start: &[f64],
    finer: &FinerRun,
) -> Result<Equilibrium, SolverError> {
    let mut newton = SolveOptions {
        tolerance: RESOLVED_TOLERANCE,
        max_iterations: 3 * NEWTON_STRETCH,
        ..newton_options()
    };
    let (mut result, mut run) = match finer.resume_keeping(model, start, &newton) {
        Some(r) => r,
        None => {
            let (r, run) = solve_newton_keeping(model, start, &newton, RESOLVED_TOLERANCE);
            (r, run)
        }
    };
    loop {
        let Err(SolverError::NewtonNotConverged { iterations, .. }) = result else {
            return result;
        };
        let Some(kept) = run.take() else {
            return result;
        };
        let residuals = kept.residuals();
        let n = residuals.len();
        let steady = iterations == newton.max_iterations
            && n > NEWTON_STRETCH
            && residuals[n - 1] * STEADY_FALL <= residuals[n - 1 - NEWTON_STRETCH];
        if !steady {
            return result;
        }
        newton.max_iterations += NEWTON_STRETCH;
        match kept.resume_keeping(&newton) {
            Some((r, k)) => (result, run) = (r, k),
            None => return result,
        }
    }
}

/// Every traced state of `branches` verified as its file holds it
/// ([`TracedBranch::verified_state`], in parallel on `threads` threads): `files[i][k]` for
/// `branches[i].points[k]` (`None` where the state fails, with a warning that says why).
/// Rows re-estimated by the verification get the re-estimated energy and error (and
/// `E_g` moved by the same amount: `E − E_g` depends on the length and stiffness only).
pub(crate) fn verify_all(
    opts: &DiagramOptions,
    branches: &mut [TracedBranch],
    threads: usize,
) -> (Vec<Vec<Option<StateFile>>>, Vec<String>) {
    let jobs: Vec<(usize, usize)> = branches
        .iter()
        .enumerate()
        .flat_map(|(i, b)| (0..b.points.len()).map(move |k| (i, k)))
        .collect();
    let shared: &[TracedBranch] = branches;
    let results = crate::parallel::run_parallel(
        threads,
        jobs.clone(),
        &mut |_| {},
        &mut |_| {},
        |(i, k), _| shared[i].verified_state(opts, k),
    );
    let mut files: Vec<Vec<Option<StateFile>>> = branches
        .iter()
        .map(|b| vec![None; b.points.len()])
        .collect();
    let mut warnings = Vec::new();
    for ((i, k), r) in jobs.into_iter().zip(results) {
        let b = &mut branches[i];
        match r {
            Ok(f) => {
                if let Some((e, err)) = f.row {
                    let p = &mut b.points[k];
                    p.energy_g += e - p.energy;
                    p.energy = e;
                    p.energy_error = Some(err);
                }
                files[i][k] = Some(f);
            }
            Err(e) => warnings.push(format!(
                "UNVERIFIED STATE LEFT WITHOUT A FILE: branch {} family {} sheet {} at L̄ = {}: {e}",
                b.branch, b.family, b.sheet, b.points[k].value
            )),
        }
    }
    (files, warnings)
}

/// The energy estimate of row `k` of a sheet: the largest of its own and its neighbours'. A
/// two-level estimate `|E_N − E_{N/2}|/15` passes through zero where the discretisation
/// error changes sign along a sheet, although the error of the row does not vanish there.
pub(crate) fn sheet_estimate(points: &[crate::TracedPoint], k: usize) -> Option<f64> {
    let own = points[k].energy_error?;
    Some(
        points[k.saturating_sub(1)..(k + 2).min(points.len())]
            .iter()
            .filter_map(|p| p.energy_error)
            .fold(own, f64::max),
    )
}

/// How the branches of a diagram's state files are identified (`branch_identification` in
/// `summary.json`; docs/src/methods.md, "How the branch of a state is identified"): every
/// row carries the branch of the family it is traced on, continued from a seed whose periods
/// were counted; the periods of each file's own bending moment are counted too.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct BranchIdentification {
    /// Files whose bending moment has the periods of their row's branch: named by the state
    /// itself.
    pub by_own_periods: usize,
    /// Files whose bending moment has no resolved periods (a very soft segment leaves the
    /// stiff one a geodesic arc to within the noise): named by their family's continuation
    /// from its seed only.
    pub by_continuation_no_periods: usize,
    /// Files whose bending moment counts another number of periods than their row's branch:
    /// named by their family's continuation from its seed, which their own count contradicts.
    pub by_continuation_other_periods: usize,
}

/// [`BranchIdentification`] of the files `files[i][k]` of `branches[i].points[k]`.
pub fn branch_identification(
    branches: &[TracedBranch],
    files: &[Vec<Option<StateFile>>],
) -> BranchIdentification {
    let mut out = BranchIdentification::default();
    for (b, fs) in branches.iter().zip(files) {
        for f in fs.iter().flatten() {
            match f.verification.eta {
                0 => out.by_continuation_no_periods += 1,
                e if e == b.eta => out.by_own_periods += 1,
                _ => out.by_continuation_other_periods += 1,
            }
        }
    }
    out
}
