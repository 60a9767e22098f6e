//! Critical lengths: where the lowest-energy branch changes.
//!
//! * **Detection** on the traced samples: on the union of all traced lengths, the branch of
//!   lowest energy (cubic Hermite interpolation of each branch's energies and slopes) is
//!   found; where it changes between two neighbouring lengths and both branches exist on
//!   the whole interval, the two branches cross there.
//! * **Crossings** are then located on re-solved equilibria ([`crate::refine`]) by the
//!   exchange locator ([`rodloop_continuation::exchange::locate`]) on
//!   `f(L̄) = E_a(L̄) − E_b(L̄)`: Newton steps with `f' = dE_a/dL̄ − dE_b/dL̄` (both analytic,
//!   Richardson-extrapolated) from the root of the interpolated difference until the sign
//!   changes, then Brent's method on that bracket, every evaluation re-solving both
//!   branches at the two reporting resolutions. The error estimate is
//!   `(δE_a + δE_b)/|f'| + final bracket`, with `δE` the discretisation error estimate of
//!   each extrapolated energy.
//! * **Collapses**: at an integer `m` in the range where the lowest branch just below ends on
//!   the m-fold great circle, or the lowest branch just above starts from it. The m-fold great
//!   circle `κ ≡ 0` closes exactly at `L̄ = m` in the discrete model too (its holonomy is the
//!   rotation by `L/R`), so `L̄_cr = m` with no error; its energy is computed from the model
//!   (`= m` for a uniform rod) and checked against the traced branches, whose energies
//!   extrapolate (linearly in `L̄`, from the last traced state and its slope) to it.

use serde::{Deserialize, Serialize};

use rodloop_continuation::exchange::{self, Energies, EnergyPair, ExchangeSettings, Start};

use crate::refine::BranchRefiner;
use crate::types::TracedBranch;
use crate::{DiagramError, DiagramOptions};

/// Kind of a critical length: the exact layer's, shared so both models use one vocabulary.
pub use rodloop_exact::diagram::CriticalKind;

/// A critical length `L̄_icr`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CriticalLength {
    /// Index `i` of `L̄_icr` in increasing order (from 1).
    pub index: usize,
    /// The critical length.
    pub lbar_cr: f64,
    /// Crossing or collapse.
    pub kind: CriticalKind,
    /// Paper branch lowest just below (0: none computed there, e.g. the circle below
    /// `L̄ = 1`).
    pub from_branch: u32,
    /// Paper branch lowest just above (0: none computed there).
    pub to_branch: u32,
    /// `η` of `from_branch` (0: none).
    pub from_eta: u32,
    /// `η` of `to_branch` (0: none).
    pub to_eta: u32,
    /// Energy `E R/(π D0)` at the critical length.
    pub energy: f64,
    /// Estimated absolute error of `lbar_cr` (0 for collapses, exact in the model).
    pub error_estimate: f64,
    /// Crossings: `|dE_a/dL̄ − dE_b/dL̄|` at the root; collapses: 0.
    pub slope_difference: f64,
    /// Crossings: evaluations of both energies by the exchange locator; collapses: 0.
    pub iterations: usize,
    /// How the number was obtained and checked (human-readable).
    pub note: String,
    /// Position in [`crate::NumericDiagram::branches`] of the sheet lowest just below (not
    /// serialised).
    #[serde(skip)]
    pub from_sheet: Option<usize>,
    /// Position in [`crate::NumericDiagram::branches`] of the sheet lowest just above (not
    /// serialised).
    #[serde(skip)]
    pub to_sheet: Option<usize>,
}

/// A crossing found on the samples, before location.
#[derive(Clone, Debug)]
pub(crate) struct Candidate {
    /// Index of the branch lowest below.
    pub a: usize,
    /// Index of the branch lowest above.
    pub b: usize,
    /// Bracket from the samples.
    pub lo: f64,
    /// Bracket from the samples.
    pub hi: f64,
    /// Root of the interpolated energy difference.
    pub guess: f64,
}

/// The branch of lowest interpolated energy at `lbar` among those covering it.
pub(crate) fn lowest_interpolated(branches: &[TracedBranch], lbar: f64) -> Option<(usize, f64)> {
    let mut best: Option<(usize, f64)> = None;
    for (i, b) in branches.iter().enumerate() {
        if let Some(e) = b.energy_at(lbar) {
            if best.is_none_or(|(_, eb)| e < eb) {
                best = Some((i, e));
            }
        }
    }
    best
}

/// Distance in `L̄` within which two sheet ends count as the same state in [`touch`]: a branch
/// point located from its two branches lands `10⁻⁷` apart at the tracing's locate width.
const TOUCH_LBAR: f64 = 1e-6;

/// Crossings of the lowest energy seen on the traced samples, plus warnings for changes of
/// the lowest branch that are neither crossings nor at integer lengths.
pub(crate) fn detect_crossings(
    opts: &DiagramOptions,
    branches: &[TracedBranch],
) -> (Vec<Candidate>, Vec<String>) {
    let mut grid: Vec<f64> = branches
        .iter()
        .flat_map(|b| b.points.iter().map(|p| p.value))
        .filter(|&l| l >= opts.lbar_min && l <= opts.lbar_max)
        .collect();
    grid.sort_by(f64::total_cmp);
    grid.dedup_by(|a, b| (*a - *b).abs() <= 1e-13);
    let lowest: Vec<Option<usize>> = grid
        .iter()
        .map(|&l| lowest_interpolated(branches, l).map(|x| x.0))
        .collect();
    let mut out = Vec::new();
    let mut warnings = Vec::new();
    for k in 1..grid.len() {
        let (Some(a), Some(b)) = (lowest[k - 1], lowest[k]) else {
            continue;
        };
        if a == b {
            continue;
        }
        let (l0, l1) = (grid[k - 1], grid[k]);
        let (ba, bb) = (&branches[a], &branches[b]);
        // Two sheets that meet at a fold or a branch point in the interval (the lowest
        // state changes continuously there): no crossing.
        if touch(ba, bb, l0, l1) {
            continue;
        }
        // Two sheets of one branch whose energies differ by less than 10⁻⁵ (relative) on
        // both sides: near-degenerate states of one family cluster (several pitchforks
        // within 10⁻³ in L̄ at D1/D0 = 0.001), not an exchange of the lowest branch.
        if ba.eta == bb.eta {
            let gap = |l: f64| match (ba.energy_at(l), bb.energy_at(l)) {
                (Some(x), Some(y)) => (x - y).abs() <= DEGENERATE * x.abs().max(1.0),
                _ => true,
            };
            if gap(l0) && gap(l1) {
                continue;
            }
        }
        if ba.covers(l0) && ba.covers(l1) && bb.covers(l0) && bb.covers(l1) {
            let diff =
                |l: f64| ba.energy_at(l).unwrap_or(f64::NAN) - bb.energy_at(l).unwrap_or(f64::NAN);
            let (mut lo, mut hi) = (l0, l1);
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                if diff(mid) < 0.0 {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            let guess = 0.5 * (lo + hi);
            // Two sheets that meet at a pitchfork are tangent there (their energies differ
            // like a power of the distance): a root of the interpolated difference within
            // two sample spacings of the meeting point is that tangency.
            let near = (2.0 * (l1 - l0)).max(NEAR_MEETING);
            if meeting_points(ba, bb)
                .iter()
                .any(|m| (m - guess).abs() <= near)
            {
                continue;
            }
            out.push(Candidate {
                a,
                b,
                lo: l0,
                hi: l1,
                guess,
            });
        } else {
            // An end of a branch between the two samples: fine at an integer (collapse),
            // suspicious elsewhere.
            let int_between = (l0.ceil() <= l1.floor())
                || (l1 - l1.round()).abs() < 1e-3
                || (l0 - l0.round()).abs() < 1e-3;
            if !int_between {
                warnings.push(format!(
                    "the lowest branch changes from {} to {} between L̄ = {l0:.6} and {l1:.6} \
                     where one of them is not traced (stop reasons: {} / {}; {} / {})",
                    ba.branch, bb.branch, ba.stop_low, ba.stop_high, bb.stop_low, bb.stop_high
                ));
            }
        }
    }
    (out, warnings)
}

/// Relative energy gap below which two sheets of one branch count as degenerate in
/// [`detect_crossings`].
const DEGENERATE: f64 = 1e-5;

/// Distance in `L̄` from a meeting point of two sheets within which a root of their
/// interpolated energy difference is taken for their tangency there (near a pitchfork the
/// symmetric and asymmetric sheets differ by less than the interpolation error).
const NEAR_MEETING: f64 = 1e-3;

/// The lengths where the two sheets meet: an end state of one that is a state of the other
/// (within [`TOUCH_LBAR`] and `10⁻⁶` relative in energy) — a shared fold or branch point, or
/// a branch point in the middle of the other sheet.
fn meeting_points(a: &TracedBranch, b: &TracedBranch) -> Vec<f64> {
    let ends = |t: &TracedBranch| [t.points.first().cloned(), t.points.last().cloned()];
    let mut out = Vec::new();
    for (x, y) in [(a, b), (b, a)] {
        for pe in ends(x).into_iter().flatten() {
            let hit = y.points.iter().any(|q| {
                (q.value - pe.value).abs() <= TOUCH_LBAR
                    && (q.energy - pe.energy).abs() <= 1e-6 * pe.energy.abs().max(1.0)
            });
            if hit {
                out.push(pe.value);
            }
        }
    }
    out
}

/// Whether two sheets share an end state (same length and energy, within [`TOUCH_LBAR`] and
/// `10⁻⁶` relative) within `[l0, l1]`: a fold joining two sheets of one family, or a branch
/// point where a family meets another (located from either side to the tracing's width).
pub(crate) fn touch(a: &TracedBranch, b: &TracedBranch, l0: f64, l1: f64) -> bool {
    let ends = |t: &TracedBranch| [t.points.first().cloned(), t.points.last().cloned()];
    let mut found = false;
    for pa in ends(a).into_iter().flatten() {
        for pb in ends(b).into_iter().flatten() {
            if pa.value.max(pb.value) >= l0 - 1e-9
                && pa.value.min(pb.value) <= l1 + 1e-9
                && (pa.value - pb.value).abs() <= TOUCH_LBAR
                && (pa.energy - pb.energy).abs() <= 1e-6 * pa.energy.abs().max(1.0)
            {
                found = true;
            }
        }
    }
    // A branch point in the middle of the other sheet (the symmetric family passes through
    // the pitchfork where the asymmetric pair ends).
    for (x, y) in [(a, b), (b, a)] {
        for pe in ends(x).into_iter().flatten() {
            if pe.value >= l0 - TOUCH_LBAR && pe.value <= l1 + TOUCH_LBAR {
                if let Some(e) = y
                    .points
                    .iter()
                    .find(|q| (q.value - pe.value).abs() <= TOUCH_LBAR)
                {
                    if (e.energy - pe.energy).abs() <= 1e-6 * pe.energy.abs().max(1.0) {
                        found = true;
                    }
                }
            }
        }
    }
    found
}

/// Two traced branches followed at the reporting resolutions, for the exchange locator.
struct RefinedPair<'a> {
    opts: &'a DiagramOptions,
    eta: [u32; 2],
    refiners: [BranchRefiner; 2],
    /// The length both refiners are at.
    at: f64,
    /// The energies' error estimates at the root.
    errors: [f64; 2],
}

impl RefinedPair<'_> {
    fn move_to(&mut self, x: f64) -> Result<(), rodloop_solver::SolverError> {
        if x != self.at {
            for r in &mut self.refiners {
                r.move_to(x)?;
            }
            self.at = x;
        }
        Ok(())
    }
}

impl EnergyPair for RefinedPair<'_> {
    type Error = rodloop_solver::SolverError;
    fn energies(&mut self, x: f64) -> Result<Energies, Self::Error> {
        self.move_to(x)?;
        let va = self.refiners[0].values()?;
        let vb = self.refiners[1].values()?;
        Ok(Energies {
            a: va.energy,
            b: vb.energy,
            slope: Some(va.slope - vb.slope),
        })
    }
    fn error(&mut self, x: f64) -> Result<f64, Self::Error> {
        self.move_to(x)?;
        for k in 0..2 {
            self.errors[k] = self.refiners[k].error_estimate(self.opts, self.eta[k]);
        }
        Ok(self.errors[0] + self.errors[1])
    }
}

/// Locate a crossing on re-solved equilibria (see the module docs).
pub(crate) fn locate_crossing(
    opts: &DiagramOptions,
    branches: &[TracedBranch],
    cand: &Candidate,
) -> Result<CriticalLength, DiagramError> {
    let (ba, bb) = (&branches[cand.a], &branches[cand.b]);
    let fail = |lbar: f64, reason: String| DiagramError::Critical {
        from_branch: ba.branch,
        to_branch: bb.branch,
        lbar,
        reason,
    };
    let width = cand.hi - cand.lo;
    let x0 = cand.guess;
    let ra = BranchRefiner::new(opts, ba, x0).map_err(|e| fail(x0, e.to_string()))?;
    let rb = BranchRefiner::new(opts, bb, x0).map_err(|e| fail(x0, e.to_string()))?;
    let mut pair = RefinedPair {
        opts,
        eta: [ba.eta, bb.eta],
        refiners: [ra, rb],
        at: x0,
        errors: [0.0; 2],
    };
    let settings = ExchangeSettings {
        xtol: 1e-13 * x0.abs().max(1.0),
        max_step: width,
        max_evaluations: 30,
        ..ExchangeSettings::default()
    };
    let window = (cand.lo - 2.0 * width, cand.hi + 2.0 * width);
    let ex = exchange::locate(&mut pair, Start::Guess { x: x0, window }, &settings)
        .map_err(|e| fail(x0, e.to_string()))?;
    let [err_a, err_b] = pair.errors;
    let [ra, rb] = &pair.refiners;
    Ok(CriticalLength {
        index: 0,
        lbar_cr: ex.x,
        kind: CriticalKind::Crossing,
        from_branch: ba.branch,
        to_branch: bb.branch,
        from_eta: ba.eta,
        to_eta: bb.eta,
        energy: 0.5 * (ex.energies.a + ex.energies.b),
        error_estimate: ex.error,
        slope_difference: ex.slope.abs(),
        iterations: ex.evaluations,
        from_sheet: Some(cand.a),
        to_sheet: Some(cand.b),
        note: format!(
            "E_{} = E_{} located by Newton steps to a bracket and Brent's method in L̄ on \
             equilibria re-solved with {} and {} / {} and {} cells, Richardson-extrapolated; \
             energy error estimates {:.1e}, {:.1e}",
            ba.branch,
            bb.branch,
            ra.fine().model().cells(),
            crate::refine::reporting_cells(opts, ba.eta).1,
            rb.fine().model().cells(),
            crate::refine::reporting_cells(opts, bb.eta).1,
            err_a,
            err_b
        ),
    })
}

/// Collapses at the integers of the range (see the module docs). `beyond(m)` names the
/// branch (`η` and how it was found) emanating upwards from the m-fold great circle when
/// no traced branch is above `m` (the top of the range).
pub(crate) fn collapses(
    opts: &DiagramOptions,
    branches: &[TracedBranch],
    beyond: &dyn Fn(u32) -> Option<(u32, String)>,
) -> Vec<CriticalLength> {
    let mut out = Vec::new();
    let d = opts.end_distance;
    let first = opts.lbar_min.ceil().max(1.0) as u32;
    let last = opts.lbar_max.floor() as u32;
    for m in first..=last {
        let mf = f64::from(m);
        let mut below = lowest_interpolated(branches, mf - d).filter(|_| mf - d >= opts.lbar_min);
        // Below L̄ = 1 a uniform rod also has the circle, `E R/(πD) = 1/L̄` (the small
        // circles of the sphere, which end on the great circle at L̄ = 1): not traced, but
        // lower than every traced loop there.
        let circle_below =
            m == 1 && opts.stiffness.is_uniform() && below.is_none_or(|(_, e)| 1.0 / (1.0 - d) < e);
        if circle_below {
            below = None;
        }
        let above = lowest_interpolated(branches, mf + d).filter(|_| mf + d <= opts.lbar_max);
        let ends_here = |i: usize| branches[i].high_end.great_circle() == Some(m);
        let starts_here = |i: usize| branches[i].low_end.great_circle() == Some(m);
        let below_ends = below.is_some_and(|(i, _)| ends_here(i)) || circle_below;
        let above_starts = above.is_some_and(|(i, _)| starts_here(i));
        if !(below_ends || above_starts) {
            continue;
        }
        let (from_eta, from_branch) =
            below.map_or((0, 0), |(i, _)| (branches[i].eta, branches[i].branch));
        let (to_eta, to_branch, named) = match above {
            Some((i, _)) => (branches[i].eta, branches[i].branch, None),
            None => match beyond(m) {
                Some((eta, how)) => (eta, rodloop_exact::branch_of_eta(eta), Some((eta, how))),
                None => (0, 0, None),
            },
        };
        if from_eta == to_eta && from_eta != 0 {
            continue;
        }
        // Energy of the great circle in the model, and the checks of the branch ends.
        let circle = great_circle_energy(opts, mf);
        let mut checks = Vec::new();
        for b in branches {
            let (end, p) = if b.high_end.great_circle() == Some(m) {
                ("upper", b.points.last())
            } else if b.low_end.great_circle() == Some(m) {
                ("lower", b.points.first())
            } else {
                continue;
            };
            if let Some(p) = p {
                let extrap = p.energy + p.slope * (mf - p.value);
                checks.push(format!(
                    "branch {} ({end} end at L̄ = {:.6}, E = {:.9}) extrapolates to E = {:.9} \
                     at L̄ = {m} (difference {:.1e})",
                    b.branch,
                    p.value,
                    p.energy,
                    extrap,
                    (extrap - circle).abs()
                ));
            }
        }
        let mut note = format!(
            "the {m}-fold great circle closes exactly at L̄ = {m} (E = {circle:.12}); {}",
            if checks.is_empty() {
                "no traced branch end to check".to_string()
            } else {
                checks.join("; ")
            }
        );
        if circle_below {
            note.push_str(
                "; below L̄ = 1 the lowest state is the circle (E R/(πD) = 1/L̄, branch 0, not \
                 traced), which becomes the great circle at L̄ = 1",
            );
        }
        if let Some((eta, how)) = named {
            note.push_str(&format!(
                "; above L̄ = {m} (outside the range) the branch with η = {eta} emanates from \
                 the great circle ({how})"
            ));
        }
        out.push(CriticalLength {
            index: 0,
            lbar_cr: mf,
            kind: CriticalKind::Collapse,
            from_branch,
            to_branch,
            from_eta,
            to_eta,
            energy: circle,
            error_estimate: 0.0,
            slope_difference: 0.0,
            iterations: 0,
            note,
            from_sheet: below.map(|(i, _)| i),
            to_sheet: above.map(|(i, _)| i),
        });
    }
    out
}

/// Energy `E R/(π D0)` of the m-fold great circle (`κ ≡ 0`) at `L̄ = m`: the normal part
/// `½∫D/R² ds` (`= m` for a uniform rod), evaluated by the model's quadrature.
pub(crate) fn great_circle_energy(opts: &DiagramOptions, m: f64) -> f64 {
    let cells = 2048;
    opts.model(m, cells)
        .and_then(|model| model.energy_normalized(&vec![0.0; 2 * cells]))
        .map(|e| e.0)
        .unwrap_or(m)
}
