//! A traced state as its file holds it: the profile sampled uniformly in arclength, checked
//! against its row (closure, on the sphere, energy recomputed from the samples), and the
//! one refinement ladder every written state goes through when that check fails (re-solves
//! at `2N`, `4N`, … by [`crate::resolve`], the row re-estimated where the refined states
//! converge and disagree with it); plus how the branches of the files are identified.
//!
//! The file is over 600 lines with its tests (about 175): the check of a file, its samples and
//! its ladder are one job, the verification of a written state.

use std::f64::consts::PI;

use rodloop_solver::{Claim, Equilibrium, SolverError};

use crate::resolve::resolved_from;
use crate::types::{FinerRun, TracedBranch};
use crate::DiagramOptions;

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
/// arclength (what a state file of `m` points gives, without building its other columns),
/// for `m` doubled from one call to the next: the energy density at the points of `m`
/// (`σ_j = j/m`) is kept, and those of `2m` are its values at the even points (the same `σ`
/// to the bit, `2j/2m = j/m` rounded once) and new ones at the odd points, summed in the
/// order of the points, so every energy is the one of the `m` points evaluated afresh.
struct SampledEnergy<'a> {
    eq: &'a Equilibrium,
    kg: rodloop_solver::periodic::TrigInterpolant,
    d0: f64,
    /// `½ D (κ² + 1/R²)` at `σ_j = j/m`, `j = 0..m` (the last `m` asked for).
    density: Vec<f64>,
}

impl<'a> SampledEnergy<'a> {
    fn new(eq: &'a Equilibrium, d0: f64) -> Result<Self, SolverError> {
        let kg = rodloop_solver::periodic::TrigInterpolant::new(
            &eq.profile().iter().map(|p| p.kappa_g).collect::<Vec<_>>(),
        )?;
        Ok(Self {
            eq,
            kg,
            d0,
            density: Vec::new(),
        })
    }

    /// The densities at `σ_j = j/m` for the given `j`.
    fn densities(&self, m: usize, js: impl Iterator<Item = usize> + Clone) -> Vec<f64> {
        let model = self.eq.model();
        let (r, length) = (model.radius(), model.length());
        let us = model
            .mesh()
            .u_of_sigmas(js.clone().map(|j| j as f64 / m as f64));
        let ks = self.kg.eval_many(&us);
        js.zip(ks)
            .map(|(j, k)| {
                let sigma = j as f64 / m as f64;
                let d = model.stiffness().eval(sigma).per_arclength(length).0;
                0.5 * d * (k * k + 1.0 / (r * r))
            })
            .collect()
    }

    /// The energy of the `m` points.
    fn at(&mut self, m: usize) -> f64 {
        let n = self.density.len();
        self.density = if n > 0 && m == 2 * n {
            let odd = self.densities(m, (1..m).step_by(2));
            self.density
                .iter()
                .zip(&odd)
                .flat_map(|(e, o)| [*e, *o])
                .collect()
        } else {
            self.densities(m, 0..m)
        };
        let model = self.eq.model();
        let (r, length) = (model.radius(), model.length());
        let h = length / m as f64;
        let e: f64 = self.density.iter().map(|p| p * h).sum();
        e * r / (PI * self.d0)
    }
}

/// The samples a state file of `eq` holds, before their profile is built: `m ≥ min_points`
/// points uniform in arclength, `m` doubled (up to [`MAX_STATE_POINTS`]) until the energy of
/// the samples settles (changes by less than a thousandth of `tol` on doubling) or lies
/// within `tol` of `target`: uniform samples of a graded mesh miss narrow features (a very
/// soft segment bent sharply, a steep stiffness step).
struct Samples {
    /// Points of the file.
    points: usize,
    /// Energy `E R/(π D0)` of the samples ([`SampledEnergy`]).
    energy: f64,
    /// Energy of every other sample (the samples of `points/2`), where `points` was doubled.
    every_other: Option<f64>,
}

impl Samples {
    fn settle(
        eq: &Equilibrium,
        min_points: usize,
        target: f64,
        tol: f64,
        d0: f64,
    ) -> Result<Self, SolverError> {
        let mut sampled = SampledEnergy::new(eq, d0)?;
        let mut m = min_points.max(8);
        let mut e_m = sampled.at(m);
        let mut every_other = None;
        while m < MAX_STATE_POINTS && (e_m - target).abs() > tol {
            let e_2m = sampled.at(2 * m);
            m *= 2;
            let settled = (e_2m - e_m).abs() <= 1e-3 * tol;
            every_other = Some(e_m);
            e_m = e_2m;
            if settled {
                break;
            }
        }
        Ok(Self {
            points: m,
            energy: e_m,
            every_other,
        })
    }

    /// Why the file of these samples fails `claim` before its profile is built, if it
    /// does by a wide margin: the state's own closure ([`rodloop_solver::check_holonomy`],
    /// the first check of [`rodloop_solver::verify_state`]) and then the energy of the
    /// samples beyond [`PRECHECK_MARGIN`] times the energy check's tolerance (the profile's
    /// energy is the same sums up to round-off). A state whose cells do not resolve its
    /// bends fails here (its samples' energy settles 20 % away from its row on `D1/D0 =
    /// 0.001`), without building the eleven columns of thousands of points it would not
    /// write.
    fn fails_early(&self, eq: &Equilibrium, claim: &Claim) -> Option<SolverError> {
        if let Err(e) = rodloop_solver::check_holonomy(eq) {
            return Some(e);
        }
        let every_other = self.every_other?;
        rodloop_solver::check_energy(claim, self.energy, every_other, PRECHECK_MARGIN).err()
    }
}

/// Multiple of the energy check's tolerance by which the energy of a file's samples must
/// miss its claim for [`Samples::fails_early`] to reject the file without building it: wide
/// enough that round-off between the samples' sums and the profile's cannot decide.
const PRECHECK_MARGIN: f64 = 2.0;

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
    /// refined resolutions `(E_{2^j N}, E_{2^{j−1} N})` disagrees with the row beyond both
    /// estimates, and the whole ladder from `N` on converges at about the scheme's order
    /// (`ladder_converges`: the refined states are the traced state converging, not a
    /// neighbouring sheet or another state reached by a jump), the row is re-estimated from
    /// that pair ([`StateFile::row`]).
    ///
    /// The branch of a traced state is its family's: the family is traced by continuation
    /// from a seed whose periods were counted. The periods of the state's own `κ_g`
    /// ([`rodloop_solver::Verification::eta`]) are counted too; near the great circles
    /// (`L̄` at an integer, `κ_g` nearly constant) and on soft segments the dominant harmonic
    /// can differ from the family's `η` ([`StateFile::counted_other_eta`]).
    ///
    /// Errors: [`SolverError::Unverified`] naming why no resolution up to the limit passes
    /// (see `verify_refining`); the state's own errors when it cannot be re-evaluated.
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
/// re-solved at `2N`, `4N`, … ([`crate::resolve::resolved`]) up to [`MAX_REFINEMENT`]` N`, the file sampling
/// the finest state needed.
///
/// With [`Ladder::ReEstimate`], from the third resolution on: when the differences of the
/// ladder `(E_{2^{j−2} N}, E_{2^{j−1} N}, E_{2^j N})` decrease by a factor between 4 and 64
/// ([`converges_like_the_scheme`]: the refined states are this state converging, not a
/// neighbouring sheet or another state reached by a jump) and the Richardson value of
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
/// the same model from the same start ([`crate::resolve::resolved_from`]): the same result without repeating
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
            let (e2, e1) = (energies[n - 1], energies[n - 2]);
            // The whole ladder from the state's own resolution: a jump to another state
            // at any rung is not this state converging, even where the rungs above it
            // converge among themselves.
            let converging = ladder_converges(&energies, scale);
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
        let samples = Samples::settle(
            at,
            STATE_POINTS.max(cells),
            claim.energy,
            claim.energy_error,
            d0,
        )?;
        let checked = match samples.fails_early(at, &claim) {
            Some(why) => Err(why),
            None => {
                let profile = at.profile_uniform(samples.points)?;
                rodloop_solver::verify_state(at, &profile, &claim).map(|v| (profile, v))
            }
        };
        match checked {
            Ok((profile, verification)) => {
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

/// Whether two successive differences `d1 = E_{2M} − E_M`, `d2 = E_{4M} − E_{2M}` of a
/// refinement ladder (energies of size `scale`) are those of one state converging at about
/// the scheme's order: `|d2|` at most a quarter of `|d1|` (order 2 at least) and `|d1|` at
/// most [`FASTEST_RATIO`] times `|d2|` plus rounding (order 6 at most). A ladder whose first
/// difference is far larger than the scheme's order allows is not a state converging but a
/// jump to another state that the finer resolutions then resolve: on a very soft segment a
/// state of 116 cells at `E = 0.647` with unresolved bends can re-solve at 232 and 464
/// cells to another family's state at 0.5401 (`|d1/d2|` about 1e4).
fn converges_like_the_scheme(d1: f64, d2: f64, scale: f64) -> bool {
    let rounding = 8.0 * f64::EPSILON * scale;
    d2.abs() <= 0.25 * d1.abs() && d1.abs() <= FASTEST_RATIO * (d2.abs() + rounding)
}

/// Whether the refinement ladder `energies` (`E_N, E_{2N}, …`, at least three, of size
/// `scale`) is one state converging: every two successive differences
/// [`converges_like_the_scheme`].
fn ladder_converges(energies: &[f64], scale: f64) -> bool {
    let diffs: Vec<f64> = energies.windows(2).map(|w| w[1] - w[0]).collect();
    diffs.len() >= 2
        && diffs
            .windows(2)
            .all(|d| converges_like_the_scheme(d[0], d[1], scale))
}

/// Largest ratio `|d1/d2|` of successive differences of a converging refinement ladder
/// ([`converges_like_the_scheme`]): `2⁶`, two orders above the scheme's fourth (the
/// estimates cap the observed ratio at the scheme's `2⁴`, [`crate::estimate`]). The ladders
/// of the `D1/D0 = 0.001` diagram's verification that converge run at ratios 11–16; its
/// jumps at 2.7e4–3.4e4.
const FASTEST_RATIO: f64 = 64.0;

/// Why the finest resolution of the ladder `energies` (`E_N, E_{2N}, …` from `first = N`
/// cells) still fails (`why`): the refined states either converge like `h⁴` (their
/// ladder converges, [`ladder_converges`]) to a value the file's samples miss, or
/// they do not, and then the finer resolutions hold another state than the row's.
fn ladder_reason(first: usize, energies: &[f64], why: &str) -> String {
    let cells: Vec<String> = (0..energies.len())
        .map(|j| format!("{}", first << j))
        .collect();
    let values: Vec<String> = energies.iter().map(|e| format!("{e:.10}")).collect();
    let diffs: Vec<f64> = energies.windows(2).map(|w| (w[1] - w[0]).abs()).collect();
    let scale = energies.iter().fold(1.0f64, |m, e| m.max(e.abs()));
    let converging = ladder_converges(energies, scale);
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

/// Every traced state of `branches` verified as its file holds it
/// ([`TracedBranch::verified_state`], in parallel on `threads` threads): `files[i][k]` for
/// `branches[i].points[k]` (`None` where the state fails, with a warning that says why), the
/// warnings, and how many states fail.
/// Rows re-estimated by the verification get the re-estimated energy and error (and
/// `E_g` moved by the same amount: `E − E_g` depends on the length and stiffness only).
pub(crate) fn verify_all(
    opts: &DiagramOptions,
    branches: &mut [TracedBranch],
    threads: usize,
) -> (Vec<Vec<Option<StateFile>>>, Vec<String>, usize) {
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
    // The failures of each sheet, in the order of its states.
    let mut failed: Vec<Vec<(f64, String)>> = vec![Vec::new(); branches.len()];
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
            Err(e) => failed[i].push((b.points[k].value, e.to_string())),
        }
    }
    let unverified = failed.iter().map(Vec::len).sum();
    let warnings = branches
        .iter()
        .zip(&failed)
        .flat_map(|(b, f)| unverified_warnings((b.branch, b.family, b.sheet), f))
        .collect();
    (files, warnings, unverified)
}

/// The warnings of a sheet's states that fail verification (`(L̄, why)` each): the states
/// whose reasons are the same check failing with numbers of their own (equal with the numbers
/// left out) share one warning, the first one's reason in full and the lengths of the others;
/// a reason of its own gets its own warning.
fn unverified_warnings(b: (u32, u32, u32), failed: &[(f64, String)]) -> Vec<String> {
    let (branch, family, sheet) = b;
    let shape = |why: &str| -> String {
        why.chars()
            .filter(|c| !(c.is_ascii_digit() || matches!(c, '.' | '-' | '+' | 'e')))
            .collect()
    };
    // Groups of equal shape, in the order of their first state.
    let mut groups: Vec<(String, Vec<&(f64, String)>)> = Vec::new();
    for f in failed {
        let sh = shape(&f.1);
        match groups.iter_mut().find(|(s, _)| *s == sh) {
            Some((_, g)) => g.push(f),
            None => groups.push((sh, vec![f])),
        }
    }
    groups
        .into_iter()
        .map(|(_, g)| {
            let (first, why) = g[0];
            if g.len() == 1 {
                return format!(
                    "UNVERIFIED STATE LEFT WITHOUT A FILE: branch {branch} family {family} sheet \
                     {sheet} at L̄ = {first}: {why}"
                );
            }
            let others: Vec<String> = g[1..].iter().map(|(l, _)| format!("{l:.6}")).collect();
            format!(
                "UNVERIFIED STATES LEFT WITHOUT A FILE: {} states of branch {branch} family \
                 {family} sheet {sheet} (their rows leave the table); at L̄ = {first}: {why}; the \
                 same check fails, with numbers of their own, at L̄ = {}",
                g.len(),
                others.join(", ")
            )
        })
        .collect()
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

#[cfg(test)]
mod tests {
    use super::{ladder_converges, unverified_warnings, SampledEnergy};

    /// Energies `E(h)` of a ladder at `h = 1/N, 1/(2N), …` (`rungs` of them).
    fn ladder(e: impl Fn(f64) -> f64, n: f64, rungs: usize) -> Vec<f64> {
        (0..rungs)
            .map(|j| e(1.0 / (n * f64::from(1u32 << j))))
            .collect()
    }

    /// A state converging at the scheme's fourth order (with a sixth-order term), a
    /// pre-asymptotic one at order 2.5 and one at order 6 are ladders that converge; a
    /// ladder whose first rung jumps to another state (its own energy 0.61, the finer
    /// resolutions converging like `h⁴` to 0.5401: the `D1/D0 = 0.001` case of the docs) does
    /// not, however well its upper rungs converge, and neither does one whose rungs do not
    /// settle.
    #[test]
    fn only_a_state_converging_at_about_the_schemes_order_is_a_converging_ladder() {
        let fourth = |h: f64| 0.54 + 3.0 * h.powi(4) - 40.0 * h.powi(6);
        let second = |h: f64| 0.54 + 0.5 * h.powf(2.5);
        let sixth = |h: f64| 0.54 + 1e3 * h.powi(6);
        for (name, e) in [
            ("fourth", &fourth as &dyn Fn(f64) -> f64),
            ("second", &second),
            ("sixth", &sixth),
        ] {
            let l = ladder(e, 116.0, 4);
            assert!(ladder_converges(&l, 1.0), "{name}: {l:?}");
        }
        let other = |h: f64| 0.5401 + 2e5 * h.powi(4);
        let mut jump = vec![0.61];
        jump.extend(ladder(other, 232.0, 3));
        // The upper rungs alone converge, and the first rung's difference falls by far more
        // than fourfold: the test of the last three rungs alone accepts the jump.
        assert!(ladder_converges(&jump[1..], 1.0));
        assert!((jump[3] - jump[2]).abs() <= 0.25 * (jump[2] - jump[1]).abs());
        assert!(!ladder_converges(&jump, 1.0), "{jump:?}");
        let wandering = [0.60, 0.58, 0.575, 0.57];
        assert!(!ladder_converges(&wandering, 1.0));
        assert!(
            !ladder_converges(&jump[..2], 1.0),
            "two rungs are no ladder"
        );
    }

    /// The state of a two-segment rod (`D1/D0 = 0.1`, `γ = 200`) at `L̄ = 1.4` reached from
    /// the Euler curve of two periods, on 80 cells of its graded mesh.
    fn graded_state() -> rodloop_solver::Equilibrium {
        use rodloop_solver::{solve_cells, SolveOptions, StartShape, Stiffness};
        let st = Stiffness::Tanh {
            d0: 1.0,
            d1: 0.1,
            s0: 0.3,
            s1: 0.8,
            gamma: 200.0,
        };
        solve_cells(
            1.0,
            1.4,
            80,
            &st,
            &StartShape::Euler { l: 2 },
            None,
            &SolveOptions::default(),
        )
        .unwrap()
    }

    /// The energies of doubled samples, going on from the kept densities, are those of the
    /// samples evaluated afresh, to the bit (the state files' point counts follow from
    /// them), on a graded mesh (a two-segment rod); they converge to the discrete energy as
    /// the samples resolve the profile.
    #[test]
    fn doubled_samples_reuse_their_points_to_the_bit() {
        let eq = graded_state();
        assert!(!eq.model().mesh().is_uniform());
        let mut going_on = SampledEnergy::new(&eq, 1.0).unwrap();
        let mut last = going_on.at(64);
        for m in [128, 256, 512, 1024] {
            let e = going_on.at(m);
            let fresh = SampledEnergy::new(&eq, 1.0).unwrap().at(m);
            assert_eq!(e.to_bits(), fresh.to_bits(), "m = {m}");
            last = e;
        }
        // Not a doubling: evaluated afresh.
        let e = going_on.at(96);
        assert_eq!(
            e.to_bits(),
            SampledEnergy::new(&eq, 1.0).unwrap().at(96).to_bits()
        );
        let discrete = eq.energy().total;
        assert!(
            (last - discrete).abs() < 1e-4 * discrete,
            "{last} vs {discrete}"
        );
    }

    /// The early rejection of a file ([`super::Samples::fails_early`]) agrees with the full
    /// check of its profile ([`rodloop_solver::verify_state`]): on a two-segment state whose
    /// samples settle at several doublings, claims off by a growing multiple of the check's
    /// tolerance are rejected early only where the full check rejects them too, the right
    /// claim is not, and from 2.5 tolerances on every claim is rejected early.
    #[test]
    fn early_rejection_agrees_with_the_full_check() {
        use rodloop_solver::{verify_state, Claim};
        let eq = graded_state();
        // The energy the samples converge to, claimed with a small error estimate, so that
        // the samples are doubled past the first count.
        let e = super::SampledEnergy::new(&eq, 1.0).unwrap().at(8192);
        let estimate = 1e-9;
        let claim = |energy: f64| Claim {
            energy,
            energy_error: estimate,
            profile_error: 0.0,
            eta: None,
        };
        let truth = super::Samples::settle(&eq, 64, e, estimate, 1.0).unwrap();
        assert!(truth.every_other.is_some(), "the samples were not doubled");
        assert!(truth.fails_early(&eq, &claim(e)).is_none());
        let profile = eq.profile_uniform(truth.points).unwrap();
        let tol =
            rodloop_solver::check_energy(&claim(e), truth.energy, truth.every_other.unwrap(), 1.0)
                .unwrap();
        let mut early = 0;
        for k in 1..=40 {
            let off = 0.1 * f64::from(k) * tol;
            for energy in [e + off, e - off] {
                let c = claim(energy);
                let samples = super::Samples::settle(&eq, 64, energy, estimate, 1.0).unwrap();
                let full = verify_state(&eq, &eq.profile_uniform(samples.points).unwrap(), &c);
                match samples.fails_early(&eq, &c) {
                    Some(_) => {
                        early += 1;
                        assert!(full.is_err(), "rejected early, passes in full: {energy}");
                    }
                    None => assert!(
                        off < 2.5 * tol,
                        "not rejected early at {off:e} (tolerance {tol:e})"
                    ),
                }
            }
        }
        assert!(early > 0);
        assert!(verify_state(&eq, &profile, &claim(e)).is_ok());
    }

    /// States failing the same check with their own numbers share one warning that names
    /// them all; a state failing another check keeps its own.
    #[test]
    fn failures_of_one_check_share_a_warning() {
        let why = |cells: usize, turn: f64| {
            format!(
                "it is not resolved at {cells} cells (its tangent turns by up to {turn:.2} rad)"
            )
        };
        let failed = vec![
            (1.0, why(116, 2.15)),
            (1.01, why(116, 2.1)),
            (
                1.02,
                "its resolutions disagree beyond its own error estimate".to_string(),
            ),
            (1.03, why(232, 1.02)),
        ];
        let w = unverified_warnings((2, 7, 0), &failed);
        assert_eq!(w.len(), 2, "{w:?}");
        assert!(w[0].starts_with(
            "UNVERIFIED STATES LEFT WITHOUT A FILE: 3 states of branch 2 family 7 sheet 0"
        ));
        assert!(w[0].contains("at L̄ = 1: it is not resolved at 116 cells"));
        assert!(w[0].ends_with("at L̄ = 1.010000, 1.030000"), "{}", w[0]);
        assert!(w[1].starts_with("UNVERIFIED STATE LEFT WITHOUT A FILE: branch 2 family 7 sheet 0 at L̄ = 1.02: its resolutions"));
        assert!(unverified_warnings((1, 1, 0), &[]).is_empty());
    }
}
