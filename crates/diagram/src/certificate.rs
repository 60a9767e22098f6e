//! Completeness certificate of a branch diagram: at sample lengths spread over the range,
//! the search `rodloop solve` runs (plus starts placed by the stiffness profile's own
//! features) looks for equilibria, and every one found below the lowest traced state is
//! reported (GUIDE §2, "Completeness is systematic"). The diagram seeds a family from each
//! such state and traces it; what is still below the traced set afterwards is *unexplained*:
//! a loud warning and a field of `summary.json`.
//!
//! The search is a [`StateSearch`] ("the equilibria found at `L̄`"), so that any model (the
//! surface model here, the enclosed model too) can be certified the same way; the surface
//! model's search is [`SurfaceSearch`]. It runs in two stages: every start is solved without
//! knowing the traced set (so `crate::compute` runs that stage on the threads the tracing
//! leaves idle), then only the states that may lie below the traced set get their error
//! estimate, verification, index and seed.

use rodloop_exact::branch_of_eta;
use rodloop_solver::{
    finish_with_accuracy, richardson, solve, verify_accurate, Accuracy, Confinement, Equilibrium,
    SolveOptions, SolverError, StartShape, Stiffness, Strategy, SurfaceModel,
};
use serde::Serialize;

pub use crate::sampling::{closes, feature_shifts, sample_lengths, SAMPLE_SPACING};

use crate::parallel::run_parallel;
use crate::types::TracedBranch;
use crate::DiagramOptions;

/// An equilibrium a [`StateSearch`] found at one length.
#[derive(Clone, Debug)]
pub struct Found {
    /// Normalised length.
    pub lbar: f64,
    /// Periods of `κ_g` of the state (its branch).
    pub eta: u32,
    /// `E R/(π D0)`.
    pub energy: f64,
    /// Estimated absolute error of `energy`.
    pub error: f64,
    /// Stability index (if computed).
    pub index: Option<usize>,
    /// How it was found (human-readable).
    pub how: String,
    /// A start for tracing the state's family: its unknowns at the model's tracing resolution.
    pub seed: Option<Vec<f64>>,
}

/// Finds equilibria at a given length: what the certificate runs at every sample length, in
/// two stages. The first ([`StateSearch::candidates_at`]) solves every start and needs
/// nothing of the traced set, so it can run beside the tracing; the second
/// ([`StateSearch::complete`]) is given the lowest traced energy at the candidate's length
/// and estimates the error (and the index, and a seed) of only the candidates that may lie
/// below it.
pub trait StateSearch: Sync {
    /// A state a start converged to, before its error estimate.
    type Candidate: Send;
    /// The distinct states the starts at `lbar` converge to.
    fn candidates_at(&self, lbar: f64) -> Vec<Self::Candidate>;
    /// The length of a candidate.
    fn length_of(&self, candidate: &Self::Candidate) -> f64;
    /// The equilibrium found, given the lowest traced energy at its length (`lowest`); `None`
    /// if it fails the checks of a reported state.
    fn complete(&self, candidate: Self::Candidate, lowest: Option<f64>) -> Option<Found>;
}

/// A state found below the lowest traced one.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Finding {
    /// Normalised length.
    pub lbar: f64,
    /// Paper branch of the state.
    pub branch: u32,
    /// Periods of `κ_g`.
    pub eta: u32,
    /// `E R/(π D0)` of the state found.
    pub energy: f64,
    /// Its estimated error.
    pub error: f64,
    /// Its stability index (if computed).
    pub index: Option<usize>,
    /// The lowest traced energy at `lbar` when it was found (`None`: no traced state there).
    pub lowest_traced: Option<f64>,
    /// How it was found.
    pub how: String,
}

/// The certificate of a diagram (`summary.json`, field `certificate`).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Certificate {
    /// Sample lengths searched.
    pub lengths_checked: usize,
    /// Their spacing in `L̄`.
    pub spacing: f64,
    /// Equilibria the search found in all (on traced families or not).
    pub states_found: usize,
    /// Those found below the lowest traced state (by more than [`margin`]).
    pub found_below: Vec<Finding>,
    /// Families traced from them.
    pub families_seeded: usize,
    /// Those still below the traced set after seeding: the diagram may be incomplete there.
    pub unexplained: Vec<Finding>,
    /// Time of the search, in seconds, summed over the threads that ran it (its first stage
    /// runs beside the tracing).
    pub search_seconds: f64,
    /// That and the wall time of the seeded tracing, in seconds.
    pub seconds: f64,
}

impl Certificate {
    /// One warning per unexplained state.
    pub fn warnings(&self) -> Vec<String> {
        self.unexplained
            .iter()
            .map(|f| {
                format!(
                    "CERTIFICATE: at L̄ = {:.4} the search of `rodloop solve` finds a state of \
                     branch {} (η = {}) with E R/(π D0) = {:.8} ± {:.1e}, below the lowest \
                     traced state ({}); its family could not be traced: the diagram may miss \
                     the stable state there",
                    f.lbar,
                    f.branch,
                    f.eta,
                    f.energy,
                    f.error,
                    f.lowest_traced
                        .map_or("none traced there".to_string(), |e| format!("{e:.8}"))
                )
            })
            .collect()
    }
}

/// How far below the lowest traced energy a found state must lie to count as missed:
/// three times its error estimate plus `10⁻⁶` relative (the traced energies' own errors are
/// far smaller).
pub fn margin(found: &Found) -> f64 {
    3.0 * found.error + 1e-6 * found.energy.abs().max(1.0)
}

/// The lowest traced energy at `lbar` (cubic Hermite interpolation of each sheet).
pub fn lowest_traced(branches: &[TracedBranch], lbar: f64) -> Option<f64> {
    branches
        .iter()
        .filter_map(|b| b.energy_at(lbar))
        .min_by(f64::total_cmp)
}

/// Whether `found` lies below the traced set (`lowest` at its length) by more than its
/// [`margin`].
pub fn is_below(found: &Found, lowest: Option<f64>) -> bool {
    lowest.is_none_or(|e| found.energy < e - margin(found))
}

/// Run the first stage of `search` ([`StateSearch::candidates_at`]) at every one of
/// `lengths` on `threads` threads: the candidates, in the order of `lengths`.
pub fn search_all<S: StateSearch>(
    search: &S,
    lengths: &[f64],
    threads: usize,
) -> Vec<S::Candidate> {
    run_parallel(
        threads,
        lengths.to_vec(),
        &mut |_| {},
        &mut |_| {},
        |l, _| search.candidates_at(l),
    )
    .into_iter()
    .flatten()
    .collect()
}

/// The finding of a state found below the traced set.
pub fn finding(found: &Found, lowest: Option<f64>) -> Finding {
    Finding {
        lbar: found.lbar,
        branch: branch_of_eta(found.eta),
        eta: found.eta,
        energy: found.energy,
        error: found.error,
        index: found.index,
        lowest_traced: lowest,
        how: found.how.clone(),
    }
}

/// The traced set a certificate checks and extends.
pub trait TracedSet {
    /// The lowest traced energy at `lbar` (`None`: nothing traced there).
    fn lowest(&self, lbar: f64) -> Option<f64>;
    /// Trace families from `found` (states below the traced set, in increasing `L̄`):
    /// the number of families added and, for each state, whether it now lies on a traced
    /// family.
    fn extend(&mut self, found: &[Found]) -> (usize, Vec<bool>);
}

/// The certificate of `traced` at `lengths` (spacing `spacing`) from the `candidates` of
/// `search` there ([`search_all`], or the same jobs run beside the tracing; `search_seconds`:
/// their time): the candidates that may lie below the traced set completed by
/// [`StateSearch::complete`] (on `threads` threads), the states below it handed to
/// [`TracedSet::extend`], and those still below afterwards reported as unexplained.
pub fn certify<S: StateSearch>(
    search: &S,
    candidates: Vec<S::Candidate>,
    search_seconds: f64,
    traced: &mut dyn TracedSet,
    lengths: &[f64],
    spacing: f64,
    threads: usize,
) -> Certificate {
    let jobs: Vec<(S::Candidate, Option<f64>)> = candidates
        .into_iter()
        .map(|c| {
            let low = traced.lowest(search.length_of(&c));
            (c, low)
        })
        .collect();
    let completed = run_parallel(threads, jobs, &mut |_| {}, &mut |_| {}, |(c, low), _| {
        let t = std::time::Instant::now();
        (search.complete(c, low), t.elapsed().as_secs_f64())
    });
    let search_seconds = search_seconds + completed.iter().map(|(_, t)| t).sum::<f64>();
    let found: Vec<Found> = completed.into_iter().filter_map(|(f, _)| f).collect();
    let seeding = std::time::Instant::now();
    let mut below: Vec<Found> = found
        .iter()
        .filter(|f| is_below(f, traced.lowest(f.lbar)))
        .cloned()
        .collect();
    below.sort_by(|a, b| {
        a.lbar
            .total_cmp(&b.lbar)
            .then(a.energy.total_cmp(&b.energy))
    });
    let found_below: Vec<Finding> = below
        .iter()
        .map(|f| finding(f, traced.lowest(f.lbar)))
        .collect();
    let (families_seeded, on_traced) = if below.is_empty() {
        (0, Vec::new())
    } else {
        traced.extend(&below)
    };
    let unexplained = below
        .iter()
        .enumerate()
        .filter(|&(k, f)| {
            !on_traced.get(k).copied().unwrap_or(false) && is_below(f, traced.lowest(f.lbar))
        })
        .map(|(_, f)| finding(f, traced.lowest(f.lbar)))
        .collect();
    Certificate {
        lengths_checked: lengths.len(),
        spacing,
        states_found: found.len(),
        found_below,
        families_seeded,
        unexplained,
        search_seconds,
        seconds: search_seconds + seeding.elapsed().as_secs_f64(),
    }
}

/// The traced sheets of a two-segment surface diagram as a [`TracedSet`]: new families are
/// traced by [`crate::families::extend_families`]; its notes join `notes`.
pub struct SurfaceTraced<'a> {
    /// The diagram's options.
    pub opts: &'a DiagramOptions,
    /// The traced sheets (new ones are appended).
    pub sheets: &'a mut Vec<TracedBranch>,
    /// Notes for the diagram's warnings.
    pub notes: &'a mut Vec<String>,
}

impl TracedSet for SurfaceTraced<'_> {
    fn lowest(&self, lbar: f64) -> Option<f64> {
        lowest_traced(self.sheets, lbar)
    }

    fn extend(&mut self, found: &[Found]) -> (usize, Vec<bool>) {
        use crate::families::{extend_families, SeedOutcome};
        let mut on = vec![false; found.len()];
        let mut families = 0;
        let mut etas: Vec<u32> = found.iter().map(|f| f.eta).collect();
        etas.sort_unstable();
        etas.dedup();
        for eta in etas {
            let picks: Vec<usize> = (0..found.len())
                .filter(|&k| found[k].eta == eta && found[k].seed.is_some())
                .collect();
            let seeds: Vec<(f64, Vec<f64>)> = picks
                .iter()
                .filter_map(|&k| found[k].seed.clone().map(|s| (found[k].lbar, s)))
                .collect();
            match extend_families(self.opts, eta, self.sheets, &seeds) {
                Ok((f, outcomes)) => {
                    let mut fams: Vec<u32> = f.sheets.iter().map(|s| s.family).collect();
                    fams.dedup();
                    families += fams.len();
                    self.sheets.extend(f.sheets);
                    self.notes.extend(f.notes);
                    for (&k, o) in picks.iter().zip(outcomes) {
                        on[k] = matches!(o, SeedOutcome::Known | SeedOutcome::Traced);
                    }
                }
                Err(e) => self.notes.push(format!(
                    "branch {} (η = {eta}): the families of the states the completeness \
                     certificate found could not be traced: {e}",
                    branch_of_eta(eta)
                )),
            }
        }
        self.sheets.sort_by_key(|b| (b.eta, b.family, b.sheet));
        (families, on)
    }
}

/// The search of the surface model of a two-segment rod at one length: for every branch of
/// the diagram that exists there, what `rodloop solve --branch` runs first (relaxation, then
/// Newton from the Euler curve at the fast resolution; its shifted starts and its
/// continuations in `D1/D0` and `L̄` are left out: the tracer follows families in `L̄`
/// itself, and the shifted starts cost three times the rest at strong contrast), plus, at
/// every other sample length (`feature_lengths`), the same solve from the Euler curve placed
/// by the profile's own features: each end of the soft segment (`s0*`, `s1*`) at the phases
/// `0` and `1/2` of a half period of `κ_g` (`1/(2η)` of the length: an extremum of `κ_g²`
/// and a point between two; a shift by half a period is the reflection `κ_g → −κ_g`). The
/// feature starts cost three quarters of the search at every length; at every other length
/// they keep the certificate's time within that of the tracing.
///
/// Every state a start converges to on its branch and that closes is a candidate; starts
/// that converge to the same state (same energy to `10⁻¹⁰` relative, the same branch and
/// length) give one. A candidate's error estimate (its companion solve at half the cells, as
/// `solve` makes it), the verification `solve` applies, its index and its seed are computed
/// only if its energy lies less than [`MAYBE_BELOW`] (relative) above the lowest traced
/// energy at its length; the others are counted, with no estimate.
pub struct SurfaceSearch<'a> {
    opts: &'a DiagramOptions,
    etas: Vec<u32>,
    feature_lengths: Vec<f64>,
}

/// A state a start of [`SurfaceSearch`] converged to.
pub struct SurfaceCandidate {
    lbar: f64,
    eta: u32,
    start: StartShape,
    equilibrium: Equilibrium,
    how: String,
}

/// How far above the lowest traced energy (relative, at least `1` absolute in units of
/// `π D0/R`) a candidate of [`SurfaceSearch`] is still estimated: more than ten times the
/// largest relative error estimate of the fast resolution's energies measured (`2·10⁻⁶` on
/// the paper's scenes, `7·10⁻⁵` on random two-segment scenes, the largest at `D1/D0 = 0.013`,
/// `γ = 250`), so that no state whose estimate could put it below the traced set goes
/// without one.
pub const MAYBE_BELOW: f64 = 1e-3;

impl<'a> SurfaceSearch<'a> {
    /// The search over the branches `opts` traces, with feature-placed starts at every other
    /// one of the sample `lengths`.
    pub fn new(opts: &'a DiagramOptions, lengths: &[f64]) -> Self {
        Self {
            opts,
            etas: opts.etas(),
            feature_lengths: lengths.iter().step_by(2).copied().collect(),
        }
    }

    /// The origin shifts of the feature-placed starts of `eta` (fractions of the length):
    /// [`feature_shifts`] at the phases `j = 0, 2`.
    pub fn feature_shifts(stiffness: &Stiffness, eta: u32) -> Vec<f64> {
        feature_shifts(stiffness, eta, &[0, 2], true)
    }

    /// The starts of branch `eta` at `lbar`: the Euler curve as `solve` places it, then (at
    /// the feature lengths) the feature-placed ones, each with its curvature at the Gauss
    /// points of `model` (the model at `lbar`) and how it is described. The Euler curve is
    /// sampled once for all of them (the shifted starts are its samples at shifted points).
    fn starts(
        &self,
        lbar: f64,
        eta: u32,
        model: &SurfaceModel,
    ) -> Vec<(StartShape, Result<Vec<f64>, SolverError>, String)> {
        let euler = StartShape::Euler { l: eta };
        let Ok(sampled) = euler.interpolant(lbar).map(StartShape::Profile) else {
            return Vec::new();
        };
        let kappa = if model.lbar() == lbar {
            sampled.gauss_values(model)
        } else {
            euler.gauss_values(model)
        };
        let mut out = vec![(
            euler.clone(),
            kappa,
            format!(
                "rodloop solve --branch {}: {}",
                branch_of_eta(eta),
                Strategy::Direct.describe()
            ),
        )];
        if self
            .feature_lengths
            .iter()
            .any(|&l| (l - lbar).abs() < 1e-12)
        {
            for shift in Self::feature_shifts(&self.opts.stiffness, eta) {
                let start = if shift == 0.0 {
                    Ok(euler.clone())
                } else {
                    sampled.shifted(lbar, shift)
                };
                if let Ok(start) = start {
                    let kappa = start.gauss_values(model);
                    out.push((
                        start,
                        kappa,
                        format!(
                            "Newton from the Euler curve l = {eta} with its origin moved by \
                             {shift:.4} (a stiffness change at a phase of κ_g)"
                        ),
                    ));
                }
            }
        }
        out
    }
}

impl StateSearch for SurfaceSearch<'_> {
    type Candidate = SurfaceCandidate;

    fn candidates_at(&self, lbar: f64) -> Vec<SurfaceCandidate> {
        let opts = self.opts;
        let mut out: Vec<SurfaceCandidate> = Vec::new();
        for &eta in &self.etas {
            let e = f64::from(eta);
            if !(lbar > (e - 1.0).max(0.0) && lbar < e + 1.0) {
                continue;
            }
            let cells = Accuracy::Fast.cells(eta as usize, &opts.stiffness);
            let Ok(model) = opts.model(lbar, cells) else {
                continue;
            };
            let first = out.len();
            for (start, kappa, how) in self.starts(lbar, eta, &model) {
                let Some(eq) = kappa
                    .and_then(|k| solve(&model, &k, &SolveOptions::default()))
                    .ok()
                else {
                    continue;
                };
                let on_branch =
                    rodloop_solver::identify::identify_equilibrium(&eq).is_ok_and(|p| p.eta == eta);
                if !on_branch || !closes(&eq) {
                    continue;
                }
                let en = eq.energy().total;
                let same = |c: &SurfaceCandidate| {
                    let ec = c.equilibrium.energy().total;
                    (ec - en).abs() <= 1e-10 * en.abs().max(1.0)
                };
                if out[first..].iter().any(same) {
                    continue;
                }
                out.push(SurfaceCandidate {
                    lbar,
                    eta,
                    start,
                    equilibrium: eq,
                    how,
                });
            }
        }
        out
    }

    fn length_of(&self, candidate: &SurfaceCandidate) -> f64 {
        candidate.lbar
    }

    fn complete(&self, c: SurfaceCandidate, lowest: Option<f64>) -> Option<Found> {
        let opts = self.opts;
        let en = c.equilibrium.energy().total;
        let maybe_below = lowest.is_none_or(|l| en < l + MAYBE_BELOW * l.abs().max(1.0));
        if !maybe_below {
            return Some(Found {
                lbar: c.lbar,
                eta: c.eta,
                energy: en,
                error: 0.0,
                index: None,
                how: c.how,
                seed: None,
            });
        }
        // Completed as `solve` completes its state: the companion solve for the error
        // estimate, and the checks of every reported state.
        let acc = finish_with_accuracy(
            c.equilibrium,
            opts.radius,
            &opts.stiffness,
            &c.start,
            Accuracy::Fast,
            &SolveOptions::default(),
        )
        .ok()?;
        verify_accurate(&acc, Some(c.eta)).ok()?;
        let eq = &acc.equilibrium;
        // The energy extrapolated from the state and its companion (Richardson; the error
        // estimate bounds its error too).
        let energy = richardson(eq.energy().total, acc.companion.energy().total);
        let index = eq
            .model()
            .index(&eq.state(), crate::states::INDEX_TOLERANCE)
            .ok();
        let seed = eq.resample(opts.trace_cells(c.eta)).ok();
        Some(Found {
            lbar: c.lbar,
            eta: c.eta,
            energy,
            error: acc.energy_error,
            index,
            how: c.how,
            seed,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Sample lengths: midpoints of equal parts no longer than the spacing.
    #[test]
    fn sample_lengths_cover_the_range() {
        let (l, h) = sample_lengths(1.0, 3.0);
        assert_eq!(l.len(), 40);
        assert!((h - 0.05).abs() < 1e-15);
        assert!((l[0] - 1.025).abs() < 1e-12 && (l[39] - 2.975).abs() < 1e-12);
        assert!(l.iter().all(|x| (x - x.round()).abs() > 0.02));
        let (l, h) = sample_lengths(1.0, 1.12);
        assert_eq!(l.len(), 3);
        assert!((h - 0.04).abs() < 1e-12);
    }

    /// Feature-placed starts: each stiffness change at two phases of the half period.
    #[test]
    fn feature_shifts_place_each_change_at_two_phases() {
        let st = Stiffness::Tanh {
            d0: 1.0,
            d1: 0.3,
            s0: 0.2,
            s1: 0.4,
            gamma: 100.0,
        };
        let s = SurfaceSearch::feature_shifts(&st, 2);
        // Half period 1/4: phase 0 at s0 = 0.2 is the shift −0.2 ≡ 0.05, phase 2/16 at s0 is
        // 0.125 − 0.2 ≡ 0.175; at s1 = 0.4: 0.1 and 0.225.
        assert_eq!(s.len(), 4);
        for want in [0.05, 0.175, 0.1, 0.225] {
            assert!(s.iter().any(|&x| (x - want).abs() < 1e-12), "{s:?}");
        }
        // The start sampled at σ + shift puts its point of phase 0 at σ = −shift = 0.95, and
        // half a period on (σ = 0.2 = s0) the reflected point: κ_g there is ∓ κ_g(0).
        let start = StartShape::Euler { l: 2 };
        let shifted = start.shifted(1.5, s[0]).unwrap();
        let t = |sh: &StartShape, sigma: f64| sh.interpolant(1.5).unwrap().eval(sigma);
        let k0 = t(&start, 0.0);
        assert!(k0.abs() > 0.1);
        assert!((t(&shifted, 0.95) - k0).abs() < 1e-9 * k0.abs());
        assert!((t(&shifted, 0.2).abs() - k0.abs()).abs() < 1e-9 * k0.abs());
    }

    /// A found state counts as missed only beyond its margin, and anywhere nothing is traced.
    #[test]
    fn below_means_beyond_the_margin() {
        let f = |energy: f64, error: f64| Found {
            lbar: 1.5,
            eta: 2,
            energy,
            error,
            index: Some(0),
            how: String::new(),
            seed: None,
        };
        assert!(is_below(&f(1.0, 1e-4), Some(1.001)));
        assert!(!is_below(&f(1.0, 1e-3), Some(1.001)));
        assert!(!is_below(&f(1.0, 0.0), Some(1.0000005)));
        assert!(is_below(&f(1.0, 0.0), None));
    }
}
