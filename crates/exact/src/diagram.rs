//! The exact energy-versus-length diagram of homogeneous loops on the sphere (Fig. 3a).
//!
//! Each paper branch `η` (wave family, `q = −(η+1)`) is traced over `η − 1 < L̄ < η + 1` by
//! pseudo-arclength continuation of the closure equation in the plane `(m = k², L̄)`
//! ([`trace_branch`]); its ends are the `(η∓1)`-fold great circles (`k = 0`). The diagram
//! samples each branch on a common grid by re-solving the closure there, finds where the
//! lowest-energy branch changes, and locates every such exchange exactly:
//!
//! * a **crossing** `E_a(L̄) = E_b(L̄)` of two branches that both exist around it is located
//!   by the exchange locator ([`rodloop_continuation::exchange::locate`]: Brent's method in
//!   `L̄` on the grid bracket, every evaluation re-solving both closures to full precision;
//!   error from the final bracket and the energies' uncertainties over the slope of a chord
//!   of half-width `10⁻⁶`);
//! * a **collapse** is an integer `L̄ = m`, where the lowest branch ends on the `m`-fold great
//!   circle (energy `E R/(πD) = m`) and another one begins.

use rodloop_continuation::exchange::{self, Energies, EnergyPair, ExchangeSettings, Ranked, Start};
use rodloop_continuation::{Continuation, Direction, PseudoArclength, StopReason};

use crate::homogeneous::{closure, paper_branch_loop, ExactLoop, Family};
use crate::{branch_of_eta, roots, ExactError};

/// One sampled state of a branch.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct BranchPoint {
    /// Paper branch number.
    pub branch: u32,
    /// Periods of `κ_g`.
    pub eta: u32,
    /// Paper winding number `p`, Eq. (50) (`0` at a great-circle end point).
    pub p: i32,
    /// Normalised length.
    pub lbar: f64,
    /// Modulus `k`.
    pub k: f64,
    /// `cR`.
    pub c: f64,
    /// `E R/(πD)`.
    pub energy: f64,
    /// Geodesic part `E_g R/(πD)`.
    pub energy_g: f64,
    /// Minimum of `λR³/D` over the loop.
    pub lambda_min: f64,
    /// Maximum of `λR³/D` over the loop.
    pub lambda_max: f64,
    /// Closure residual in radians (0 at great-circle ends, which are exact).
    pub closure_residual: f64,
    /// Whether this branch has the lowest energy of all branches at this length.
    pub lowest: bool,
}

/// Kind of a critical length (used by the exact and the numeric diagram alike).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum CriticalKind {
    /// Two branches exchange the lowest energy (`E_a = E_b`).
    Crossing,
    /// The lowest branch collapses onto (or emanates from) an `m`-fold great circle at
    /// `L̄ = m`.
    Collapse,
}

impl std::fmt::Display for CriticalKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            CriticalKind::Crossing => "crossing",
            CriticalKind::Collapse => "collapse",
        })
    }
}

/// A critical length `L̄_icr`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Critical {
    /// Index `i` of `L̄_icr` in increasing order.
    pub index: usize,
    /// The critical length.
    pub lbar_cr: f64,
    /// Crossing or collapse.
    pub kind: CriticalKind,
    /// Lowest branch just below (0 = the circle, below `L̄ = 1`).
    pub from_branch: u32,
    /// Lowest branch just above.
    pub to_branch: u32,
    /// Energy `E R/(πD)` at the critical length.
    pub energy: f64,
    /// Estimated absolute error of `lbar_cr` (0 for collapses, which are exact integers).
    pub error_estimate: f64,
}

/// Settings of the exact diagram.
#[derive(Clone, Debug)]
pub struct DiagramSettings {
    /// Smallest length.
    pub lbar_min: f64,
    /// Largest length.
    pub lbar_max: f64,
    /// Largest `η` included.
    pub eta_max: u32,
    /// Grid spacing of the sampled branches.
    pub step: f64,
}

impl Default for DiagramSettings {
    fn default() -> Self {
        Self {
            lbar_min: 1.0,
            lbar_max: 5.0,
            eta_max: 5,
            step: 0.01,
        }
    }
}

/// The exact diagram: sampled branches and critical lengths.
#[derive(Clone, Debug)]
pub struct Diagram {
    /// Sampled states, ordered by branch then length.
    pub points: Vec<BranchPoint>,
    /// Critical lengths in increasing order.
    pub critical: Vec<Critical>,
    /// Number of continuation steps used to trace all branches.
    pub continuation_steps: usize,
}

/// Continuation problem: closure of the paper branch `η` as `F(m, L̄) = p_cont − q`.
struct ClosureProblem {
    eta: u32,
    q: i32,
}

impl ClosureProblem {
    /// Closure residual; for `m < 0` (outside the physical range, reached only by Newton
    /// iterates next to a great-circle end) the odd reflection `2F(0) − F(−m)`, which keeps the
    /// function C¹ so that the corrector can converge onto `m = 0`.
    fn f(&self, m: f64, lbar: f64) -> Result<f64, ExactError> {
        let g = |m: f64| -> Result<f64, ExactError> {
            Ok(closure(Family::Wave, self.eta, lbar, m)?.p_cont - f64::from(self.q))
        };
        if m >= 0.0 {
            g(m)
        } else {
            Ok(2.0 * g(0.0)? - g(-m)?)
        }
    }
}

/// Relative step of the central differences used for the 1×2 Jacobian of the closure.
const FD_STEP: f64 = 1e-7;

impl rodloop_continuation::Problem for ClosureProblem {
    type Error = ExactError;

    fn dim(&self) -> usize {
        1
    }

    fn residual(
        &self,
        x: &nalgebra::DVector<f64>,
        p: f64,
    ) -> Result<nalgebra::DVector<f64>, ExactError> {
        Ok(nalgebra::DVector::from_element(1, self.f(x[0], p)?))
    }

    fn jacobian(
        &self,
        x: &nalgebra::DVector<f64>,
        p: f64,
    ) -> Result<nalgebra::DMatrix<f64>, ExactError> {
        let m = x[0];
        let h = FD_STEP * m.abs().max(1e-4);
        let d = (self.f(m + h, p)? - self.f(m - h, p)?) / (2.0 * h);
        Ok(nalgebra::DMatrix::from_element(1, 1, d))
    }

    fn dparam(
        &self,
        x: &nalgebra::DVector<f64>,
        p: f64,
    ) -> Result<nalgebra::DVector<f64>, ExactError> {
        let h = FD_STEP;
        let d = (self.f(x[0], p + h)? - self.f(x[0], p - h)?) / (2.0 * h);
        Ok(nalgebra::DVector::from_element(1, d))
    }
}

/// A traced branch: the `(L̄, m)` points of the continuation.
#[derive(Clone, Debug)]
pub struct TracedBranch {
    /// Periods of `κ_g`.
    pub eta: u32,
    /// `(L̄, m = k²)` along the branch, in the order traced.
    pub points: Vec<(f64, f64)>,
    /// Why the continuation stopped.
    pub stop: String,
}

/// Distance from the lower end `η − 1` at which tracing starts (from a root-bracketed solve).
pub const TRACE_START_OFFSET: f64 = 1e-6;

/// Where the `η = 1` branch (figure-eight) is started. It has no great-circle lower end: as
/// `L̄ → 0` the loop shrinks towards the planar figure-eight elastica (`cR → ∞`) and the closure
/// becomes degenerate (`p_cont → −2` for every `k`), so tracing starts at a moderate length.
pub const ETA1_START: f64 = 0.25;

/// Trace the paper branch `η` over `η − 1 < L̄ ≤ η + 1` by pseudo-arclength continuation of
/// the closure equation in `(m = k², L̄)`, starting `1e-6` above the `(η−1)`-fold great circle
/// (for `η = 1` at [`ETA1_START`]) and stopping at `L̄ = η + 1`, where `k²`
/// returns to 0 on the `(η+1)`-fold great circle.
pub fn trace_branch(eta: u32) -> Result<TracedBranch, ExactError> {
    let e = f64::from(eta);
    let start = if eta == 1 {
        ETA1_START
    } else {
        e - 1.0 + TRACE_START_OFFSET
    };
    let first = paper_branch_loop(eta, start)?;
    let problem = ClosureProblem {
        eta,
        q: -(eta as i32 + 1),
    };
    let cont_err =
        |e: rodloop_continuation::ContinuationError| ExactError::Continuation(e.to_string());
    let settings = PseudoArclength::new()
        .with_ds(0.01)
        .and_then(|s| s.with_ds_bounds(1e-10, 0.05))
        .and_then(|s| s.with_range(start, e + 1.0))
        .and_then(|s| s.with_max_steps(10_000))
        .and_then(|s| s.with_tol(1e-11))
        .and_then(|s| s.with_direction(Direction::Forward))
        .map_err(cont_err)?;
    let branch = Continuation::new(&problem, settings)
        .run(&nalgebra::DVector::from_element(1, first.m), start)
        .map_err(cont_err)?;
    let stop = match &branch.stop {
        StopReason::LeftRange { boundary } => format!("reached lbar = {boundary}"),
        other => format!("{other:?}"),
    };
    let points = branch
        .points
        .iter()
        .map(|pt| (pt.p, pt.x[0].max(0.0)))
        .collect();
    Ok(TracedBranch { eta, points, stop })
}

/// Re-solve the closure of branch `eta` at `lbar` starting from a nearby parameter `m_guess`:
/// expand a bracket around the guess, then Brent to full precision.
pub fn resolve_near(eta: u32, lbar: f64, m_guess: f64) -> Result<ExactLoop, ExactError> {
    let q = f64::from(-(eta as i32 + 1));
    let f = |m: f64| closure(Family::Wave, eta, lbar, m).map(|c| c.p_cont - q);
    let m0 = m_guess.clamp(1e-15, crate::homogeneous::M_MAX);
    let f0 = f(m0)?;
    if f0 == 0.0 {
        return ExactLoop::from_parameter(Family::Wave, eta, lbar, m0);
    }
    let mut width = 1e-3 * m0.max(1e-8);
    for _ in 0..80 {
        let lo = (m0 - width).max(1e-16);
        let hi = (m0 + width).min(crate::homogeneous::M_MAX);
        let (flo, fhi) = (f(lo)?, f(hi)?);
        if (flo > 0.0) != (f0 > 0.0) {
            let m = roots::brent(f, lo, m0, 1e-16, 200)?;
            return ExactLoop::from_parameter(Family::Wave, eta, lbar, m);
        }
        if (fhi > 0.0) != (f0 > 0.0) {
            let m = roots::brent(f, m0, hi, 1e-16, 200)?;
            return ExactLoop::from_parameter(Family::Wave, eta, lbar, m);
        }
        width *= 2.0;
    }
    paper_branch_loop(eta, lbar)
}

/// Energy of branch `eta` at `lbar`, with the loop re-solved from `m_guess`.
fn energy_at(eta: u32, lbar: f64, m_guess: f64) -> Result<(f64, ExactLoop), ExactError> {
    let lp = resolve_near(eta, lbar, m_guess)?;
    Ok((lp.energy()?, lp))
}

/// Uncertainty of the energy of a re-solved loop: rounding in the closed form (a few ulps) plus
/// the closure residual propagated through the branch, `|dE/dm| / |dp_cont/dm| · δp`.
fn energy_uncertainty(lp: &ExactLoop, energy: f64) -> Result<f64, ExactError> {
    let h = 1e-6 * lp.m;
    let e = |m: f64| ExactLoop::from_parameter(Family::Wave, lp.eta, lp.lbar, m)?.energy();
    let p = |m: f64| closure(Family::Wave, lp.eta, lp.lbar, m).map(|c| c.p_cont);
    let de = (e(lp.m + h)? - e(lp.m - h)?) / (2.0 * h);
    let dp = (p(lp.m + h)? - p(lp.m - h)?) / (2.0 * h);
    let dp_residual = lp.closure_residual / (2.0 * std::f64::consts::PI) + 4.0 * f64::EPSILON;
    Ok(8.0 * f64::EPSILON * energy + (de / dp).abs() * dp_residual)
}

/// A great-circle end point of branch `eta` at integer `lbar` (`k = 0`): Eqs. (33)–(34) give
/// the contact force `λR³/D = c² = (η/L̄)²`.
fn end_point(eta: u32, lbar: f64) -> BranchPoint {
    let c = f64::from(eta) / lbar;
    BranchPoint {
        branch: branch_of_eta(eta),
        eta,
        p: 0,
        lbar,
        k: 0.0,
        c,
        energy: lbar,
        energy_g: 0.0,
        lambda_min: c * c,
        lambda_max: c * c,
        closure_residual: 0.0,
        lowest: false,
    }
}

fn to_point(eta: u32, lp: &ExactLoop, energy: f64) -> Result<BranchPoint, ExactError> {
    let (lambda_min, lambda_max) = lp.lambda_range();
    Ok(BranchPoint {
        branch: branch_of_eta(eta),
        eta,
        p: lp.p,
        lbar: lp.lbar,
        k: lp.k,
        c: lp.c,
        energy,
        energy_g: lp.energy_g()?,
        lambda_min,
        lambda_max,
        closure_residual: lp.closure_residual,
        lowest: false,
    })
}

/// Interpolate the traced `(L̄, m)` points to a starting guess of `m` at `lbar`.
fn guess_m(tr: &TracedBranch, lbar: f64) -> f64 {
    let pts = &tr.points;
    let mut best = pts[0];
    for w in pts.windows(2) {
        let ((l0, m0), (l1, m1)) = (w[0], w[1]);
        if (l0 - lbar) * (l1 - lbar) <= 0.0 && l1 != l0 {
            return m0 + (m1 - m0) * (lbar - l0) / (l1 - l0);
        }
        if (w[1].0 - lbar).abs() < (best.0 - lbar).abs() {
            best = w[1];
        }
    }
    best.1
}

/// Two branches of the exact diagram for the exchange locator: each energy re-solved from the
/// traced `(L̄, m)` points; the error of `E_a − E_b` is the sum of [`energy_uncertainty`].
struct ExactPair<'a> {
    a: u32,
    b: u32,
    tra: &'a TracedBranch,
    trb: &'a TracedBranch,
}

impl ExactPair<'_> {
    fn loops(&self, x: f64) -> Result<[(f64, ExactLoop); 2], ExactError> {
        Ok([
            energy_at(self.a, x, guess_m(self.tra, x))?,
            energy_at(self.b, x, guess_m(self.trb, x))?,
        ])
    }
}

impl EnergyPair for ExactPair<'_> {
    type Error = ExactError;
    fn energies(&mut self, x: f64) -> Result<Energies, ExactError> {
        let [(ea, _), (eb, _)] = self.loops(x)?;
        Ok(Energies {
            a: ea,
            b: eb,
            slope: None,
        })
    }
    fn error(&mut self, x: f64) -> Result<f64, ExactError> {
        let [(ea, la), (eb, lb)] = self.loops(x)?;
        Ok(energy_uncertainty(&la, ea)? + energy_uncertainty(&lb, eb)?)
    }
}

/// Compute the exact diagram.
pub fn compute(settings: &DiagramSettings) -> Result<Diagram, ExactError> {
    let DiagramSettings {
        lbar_min,
        lbar_max,
        eta_max,
        step,
    } = settings.clone();
    if !(lbar_min > 0.0 && lbar_max > lbar_min && step > 0.0 && eta_max >= 1) {
        return Err(ExactError::InvalidParameter(format!(
            "diagram needs 0 < lbar_min < lbar_max and step > 0 (got {lbar_min}, {lbar_max}, {step})"
        )));
    }
    // Trace every branch that meets the range (and one more, for the collapse at the top end).
    let mut traced = Vec::new();
    let mut steps = 0;
    for eta in 1..=eta_max + 1 {
        let e = f64::from(eta);
        if e + 1.0 <= lbar_min || e - 1.0 > lbar_max {
            continue;
        }
        let tr = trace_branch(eta)?;
        steps += tr.points.len();
        traced.push(tr);
    }
    let n = ((lbar_max - lbar_min) / step).round() as usize;
    let grid: Vec<f64> = (0..=n)
        .map(|i| lbar_min + (lbar_max - lbar_min) * i as f64 / n as f64)
        .collect();

    // Sample each branch (η ≤ eta_max) on the grid: open interior re-solved, ends exact.
    let mut points = Vec::new();
    for tr in traced.iter().filter(|t| t.eta <= eta_max) {
        let e = f64::from(tr.eta);
        for &l in &grid {
            if (l - (e - 1.0)).abs() < 1e-12 || (l - (e + 1.0)).abs() < 1e-12 {
                points.push(end_point(tr.eta, l));
            } else if l > e - 1.0 && l < e + 1.0 {
                let (en, lp) = energy_at(tr.eta, l, guess_m(tr, l))?;
                points.push(to_point(tr.eta, &lp, en)?);
            }
        }
    }
    // Lowest branch at each grid length ([`exchange::lowest`]: the energies are exact to
    // rounding, so no estimate and no preference; the least energy).
    for &l in &grid {
        let at: Vec<usize> = (0..points.len()).filter(|&i| points[i].lbar == l).collect();
        let ranked: Vec<Ranked> = at
            .iter()
            .map(|&i| Ranked {
                energy: points[i].energy,
                error: 0.0,
                index: 0,
                preferred: false,
            })
            .collect();
        for k in exchange::lowest(&ranked) {
            points[at[k]].lowest = true;
        }
    }

    let lowest_at = |l: f64| -> Result<Option<(u32, f64)>, ExactError> {
        let mut best: Option<(u32, f64)> = None;
        for tr in &traced {
            let e = f64::from(tr.eta);
            if l > e - 1.0 && l < e + 1.0 {
                let (en, _) = energy_at(tr.eta, l, guess_m(tr, l))?;
                if best.is_none_or(|(_, b)| en < b) {
                    best = Some((tr.eta, en));
                }
            }
        }
        Ok(best)
    };

    let mut critical = Vec::new();
    // Collapses at integers: the lowest branch just below ends at m, another is lowest above.
    let first_int = lbar_min.ceil() as i64;
    let last_int = lbar_max.floor() as i64;
    let delta = 1e-7;
    for mi in first_int..=last_int {
        let m = mi as f64;
        let below = if m - delta > 0.0 {
            lowest_at(m - delta)?
        } else {
            None
        };
        let above = lowest_at(m + delta)?;
        let from = match below {
            Some((eta, _)) if eta + 1 == mi as u32 => branch_of_eta(eta),
            None => 0,
            Some(_) if mi == 1 => 0,
            Some(_) => continue,
        };
        if mi == 1 && below.is_some() {
            // Below L̄ = 1 the circle (E = 1/L̄) is lower than the figure-eight.
            let (_, eb) = below.unwrap_or((0, f64::INFINITY));
            if eb < 1.0 / (1.0 - delta) {
                continue;
            }
        }
        if let Some((eta_above, _)) = above {
            if eta_above != mi as u32 + 1 {
                continue;
            }
            critical.push(Critical {
                index: 0,
                lbar_cr: m,
                kind: CriticalKind::Collapse,
                from_branch: from,
                to_branch: branch_of_eta(eta_above),
                energy: m,
                error_estimate: 0.0,
            });
        }
    }
    // Crossings between grid points where the lowest branch changes and both exist throughout.
    let lowest_on_grid: Vec<(f64, Option<u32>)> = grid
        .iter()
        .map(|&l| {
            let b = points
                .iter()
                .find(|p| p.lbar == l && p.lowest && p.k > 0.0)
                .map(|p| p.eta);
            (l, b)
        })
        .collect();
    for w in lowest_on_grid.windows(2) {
        let ((l0, a), (l1, b)) = (w[0], w[1]);
        let (Some(a), Some(b)) = (a, b) else { continue };
        if a == b {
            continue;
        }
        let exists = |eta: u32, l: f64| l > f64::from(eta) - 1.0 && l < f64::from(eta) + 1.0;
        if !(exists(a, l0) && exists(a, l1) && exists(b, l0) && exists(b, l1)) {
            continue;
        }
        let tra = traced.iter().find(|t| t.eta == a).expect("traced");
        let trb = traced.iter().find(|t| t.eta == b).expect("traced");
        let mut pair = ExactPair { a, b, tra, trb };
        let settings = ExchangeSettings {
            xtol: 1e-16 * l1.abs(),
            baseline: 1e-6,
            max_evaluations: 200,
            // The energies carry rounding only, which `energy_uncertainty` covers.
            misfit: false,
            ..ExchangeSettings::default()
        };
        let ex = exchange::locate(&mut pair, Start::Bracket(l0, l1), &settings)
            .map_err(roots::root_error)?;
        let (x, error_estimate, ea) = (ex.x, ex.error, ex.energies.a);
        critical.push(Critical {
            index: 0,
            lbar_cr: x,
            kind: CriticalKind::Crossing,
            from_branch: branch_of_eta(a),
            to_branch: branch_of_eta(b),
            energy: ea,
            error_estimate,
        });
    }
    critical.sort_by(|a, b| a.lbar_cr.total_cmp(&b.lbar_cr));
    for (i, c) in critical.iter_mut().enumerate() {
        c.index = i + 1;
    }
    Ok(Diagram {
        points,
        critical,
        continuation_steps: steps,
    })
}
