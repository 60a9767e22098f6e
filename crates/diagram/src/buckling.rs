//! Buckling of the m-fold great circles (paper Sec. 4.2) and branch switching from them.
//!
//! # Buckling loads
//!
//! At `L̄ = m` the m-fold great circle `κ ≡ 0` closes exactly, and it is an equilibrium for
//! every closure multiplier along its axis: stationarity `∇E = ∇cᵀμ` holds with `∇E = 0` and
//! `μ ⊥ n(s)` for all `s`, i.e. `μ = μ_g g` (in the solver's frame `g ≡ e_y`). The uniform
//! contact load follows from the solver's force formula `λ = −F_t/R + D''/R` with
//! `F_t = (𝓜·g − D/R)/R` and `𝓜 = −μ`: `λR³/D = 1 + μ_g R/D`. So the load is the natural
//! parameter of this trivial family, and the circle buckles where the constrained Hessian
//! `Zᵀ(∇²E − μ_g ∇²c_g)Z` (tangent space `Z` of the two independent closure rows; the third
//! row vanishes on the great circle) becomes singular. The Hessian is affine in `μ_g`, so the
//! singular loads are found at once from a symmetric eigenvalue problem: with `u = W^{1/2}δκ`
//! (quadrature weights `W = h/2`) the reduced `∇²E` is `D·I`, and
//! `D + μ_g β = 0` for every eigenvalue `β` of `Zᵀ W^{−1/2}(−∇²c_g)W^{−1/2} Z`. The number of
//! periods of each null vector (dominant Fourier mode of `δκ`) identifies the mode; the
//! continuum answer (Eqs. 30–34) is `λR³/D = n²/m²` for `n ≠ m` periods (the `n = m` modes
//! are excluded by the linearised closure), the extreme eigenvalues being `n = m ± 1`:
//! Eq. (33) `(m + 1)²/m²` and Eq. (34) `(m − 1)²/m²`. Only those extremes (and whether each
//! is a sine/cosine pair) are wanted, and they stand apart from a bulk of high harmonics near
//! `β = 0`: block Lanczos finds them ([`rodloop_solver::extreme_eigenpairs`], 24–32 basis
//! vectors for pencils of 62–446 rows). Each load is computed at three
//! resolutions `N, 2N, 4N` (`N = 4, 8, 16 × (m + 2)` cells for fast, default, high) and
//! Richardson-extrapolated twice (`h⁴` and `h⁶` terms); the report gives the deviation from
//! the formula next to the estimated error.
//!
//! # Branch switching
//!
//! From a null vector `v` (mode with `n` periods, at the critical multiplier), the bifurcating
//! branch is, to leading order (Lyapunov–Schmidt), `κ = εv` at `L̄ = m + Δ` with
//! `∂c_g/∂L̄ Δ + ½ε² vᵀ∇²c_g v = 0`: the sign of `Δ` (which side of `m` the branch lives on)
//! and the amplitude `ε` are both computed from the model. Newton's method from that guess
//! at `|Δ| = 0.01` gives a point of the buckled branch; its periods, energy and contact-force
//! range at equal `L̄` and resolution are compared with the traced branches: a match (same
//! `η`, same energy and force range — the same loop up to rotation, mirror image and shift)
//! is merged with the traced branch; anything else is reported as a new branch.
//!
//! Only uniform rods are analysed (for a non-uniform rod the contact load of the great
//! circle is not uniform and Eqs. 33–34 do not apply).

use nalgebra::DVector;
use rodloop_solver::stability::TangentReduction;
use rodloop_solver::{solve, Equilibrium, Globalization, SolveOptions, SolverError};
use serde::{Deserialize, Serialize};

use crate::refine::resolve;
use crate::seed::periods_of;
use crate::states::newton_options;
use crate::types::TracedBranch;
use crate::DiagramOptions;

/// Distance `|Δ|` from the great circle at which the switched branch is solved.
pub const SWITCH_OFFSET: f64 = 0.01;

/// A buckling load of the m-fold great circle.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Buckling {
    /// Turns of the great circle (`L̄ = m`).
    pub m: u32,
    /// Periods of `κ_g` of the null vector (`m ± 1` for Eqs. 33–34).
    pub mode_periods: u32,
    /// Multiplicity (2: the `sin`/`cos` pair of a mode with `n ≥ 1` periods).
    pub multiplicity: usize,
    /// Critical closure multiplier along the circle's axis, `μ_g R/D = λR³/D − 1`.
    pub multiplier: f64,
    /// Critical load `λR³/D = 1 + μ_g R/D`, Richardson-extrapolated from three resolutions
    /// `N, 2N, 4N` (removing the `h⁴` and `h⁶` terms).
    pub lambda_numeric: f64,
    /// Estimated discretisation error of `lambda_numeric` (`2|R₂ − R₁|/63`, the error
    /// estimate of the two-level extrapolation `R₂` from `2N, 4N`).
    pub lambda_error: f64,
    /// Eq. (33) `(m + 1)²/m²` or Eq. (34) `(m − 1)²/m²` for modes with `m ± 1` periods
    /// (`None` otherwise, and for Eq. (34) at `m = 1`, which the paper states for `m ≥ 2`).
    pub lambda_formula: Option<f64>,
    /// `"33"` or `"34"`.
    pub equation: Option<String>,
    /// `|lambda_numeric − lambda_formula|`.
    pub deviation: Option<f64>,
    /// Coarsest and finest of the three resolutions `(N, 2N, 4N)` (cells).
    pub cells: (usize, usize),
}

/// Branch switching from a great-circle buckling mode.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Switching {
    /// Turns of the great circle.
    pub m: u32,
    /// Periods of the buckling mode.
    pub mode_periods: u32,
    /// Side of `L̄ = m` on which the buckled branch lives (`+1`: longer loops), from the
    /// second-order closure condition.
    pub side: i32,
    /// Where the switched state was solved, `m + side·0.01`.
    pub lbar: f64,
    /// Leading-order amplitude `ε` of the mode (`max|κ_g R|` of `εv`).
    pub amplitude: f64,
    /// Periods of `κ_g` of the solved state (0 if the solve failed).
    pub periods: u32,
    /// Energy `E R/(π D0)` of the solved state (tracing resolution of the joined branch).
    pub energy: Option<f64>,
    /// `(λ_min, λ_max)` of the solved state.
    pub lambda_range: Option<(f64, f64)>,
    /// The traced branch it coincides with (paper number), if any.
    pub joined_branch: Option<u32>,
    /// `|E_switched − E_traced|` at `lbar` (same resolution).
    pub energy_difference: Option<f64>,
    /// Whether it was merged with a traced branch.
    pub merged: bool,
    /// What happened (human-readable).
    pub note: String,
}

/// Great-circle analysis of a diagram.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BucklingReport {
    /// Buckling loads, by `m` then mode.
    pub loads: Vec<Buckling>,
    /// Branch switching results.
    pub switching: Vec<Switching>,
    /// Remarks (skipped analyses and why).
    pub notes: Vec<String>,
}

impl BucklingReport {
    /// `η` of the branch emanating upwards (`L̄ > m`) from the m-fold great circle, found by
    /// switching.
    pub fn branch_above(&self, m: u32) -> Option<u32> {
        self.switching
            .iter()
            .find(|s| s.m == m && s.side > 0 && s.periods > 0)
            .map(|s| s.periods)
    }
}

/// One critical load at one resolution, with its null vector (Gauss values).
struct Mode {
    /// `−1`: the most negative eigenvalue (`n = m + 1`), `+1`: the most positive (`n = m − 1`).
    end: i8,
    multiplier: f64,
    periods: u32,
    multiplicity: usize,
    vector: DVector<f64>,
}

/// The reduced pencil of the m-fold great circle at `cells` cells: extreme eigenpairs
/// (`n = m ± 1`) as [`Mode`]s.
fn circle_modes(
    opts: &DiagramOptions,
    m: u32,
    cells: usize,
    vectors: bool,
) -> Result<Vec<Mode>, SolverError> {
    let mf = f64::from(m);
    let model = opts.model(mf, cells)?;
    let n = model.n_kappa();
    let zero = vec![0.0; n];
    let d = opts.stiffness.reference();
    let h0 = model.lagrangian_hessian(&zero, &[0.0; 3])?;
    let h1 = model.lagrangian_hessian(&zero, &[0.0, 1.0, 0.0])? - &h0;
    // B = W^{-1/2} (−∇²c_g) W^{-1/2} on the closure tangent space (h1 = −∇²c_g); a great
    // circle's closure has rank 2, so rows below 1e-8 of the largest are dropped.
    let weights = DVector::from_fn(n, |a, _| model.cell_weight(a / 2));
    let red = TangentReduction::new(&model.closure_jacobian(&zero)?, &weights, 1e-8)?;
    let block = red.reduce(&h1);
    if block.nrows() < 2 {
        return Ok(Vec::new());
    }
    // Extremes: the most negative (n = m + 1) and the most positive (n = m − 1) eigenvalues,
    // each with its partner when they form a degenerate pair (sin/cos).
    let ends = rodloop_solver::extreme_eigenpairs(&block, 2);
    let close = |a: f64, c: f64| (a - c).abs() <= 1e-6 * a.abs().max(c.abs());
    let mut out = Vec::new();
    for (end, pairs) in [(-1i8, &ends.low), (1i8, &ends.high)] {
        let beta = pairs[0].0;
        if beta.abs() <= 1e-12 {
            continue;
        }
        let (periods, vector) = if vectors {
            let vector = red.lift(&pairs[0].1);
            (dominant_frequency(&vector, cells), vector)
        } else {
            (0, DVector::zeros(0))
        };
        out.push(Mode {
            end,
            multiplier: -d / beta,
            periods,
            multiplicity: if close(pairs[0].0, pairs[1].0) { 2 } else { 1 },
            vector,
        });
    }
    Ok(out)
}

/// Dominant Fourier mode of the Gauss values `v` on the first sub-grid.
fn dominant_frequency(v: &DVector<f64>, cells: usize) -> u32 {
    let sub: Vec<f64> = (0..cells).map(|c| v[2 * c]).collect();
    let mut best = (0usize, -1.0f64);
    for k in 0..=cells / 2 {
        let (mut re, mut im) = (0.0, 0.0);
        for (j, x) in sub.iter().enumerate() {
            let t = 2.0 * std::f64::consts::PI * (k * j % cells) as f64 / cells as f64;
            re += x * t.cos();
            im += x * t.sin();
        }
        let a = re.hypot(im);
        if a > best.1 {
            best = (k, a);
        }
    }
    best.0 as u32
}

/// The great circles analysed for the options: `m = ⌈lbar_min⌉ … ⌊lbar_max⌋` for a uniform
/// rod, none otherwise.
pub fn circles(opts: &DiagramOptions) -> Vec<u32> {
    if !opts.stiffness.is_uniform() {
        return Vec::new();
    }
    let first = opts.lbar_min.ceil().max(1.0) as u32;
    let last = opts.lbar_max.floor() as u32;
    (first..=last).collect()
}

/// Analyse the great circles of [`circles`]: buckling loads, then branch switching onto
/// `branches` (serially; [`crate::assemble`] runs the circles in parallel).
pub fn analyse(opts: &DiagramOptions, branches: &[TracedBranch]) -> BucklingReport {
    let results = circles(opts)
        .into_iter()
        .map(|m| (m, analyse_circle(opts, m, branches)))
        .collect();
    collect_report(opts, results)
}

/// Result of one great circle.
pub(crate) type CircleResult = Result<(Vec<Buckling>, Vec<Switching>), SolverError>;

/// Gather the per-circle results into a report.
pub(crate) fn collect_report(
    opts: &DiagramOptions,
    results: Vec<(u32, CircleResult)>,
) -> BucklingReport {
    let mut report = BucklingReport::default();
    if !opts.stiffness.is_uniform() {
        report.notes.push(
            "great-circle buckling is analysed for uniform rods only (the contact load of a \
             great circle of a non-uniform rod is not uniform, Eqs. 33–34 do not apply)"
                .into(),
        );
    }
    for (m, r) in results {
        match r {
            Ok((loads, sw)) => {
                report.loads.extend(loads);
                report.switching.extend(sw);
            }
            Err(e) => report
                .notes
                .push(format!("great circle m = {m}: analysis failed ({e})")),
        }
    }
    report
}

/// Buckling loads and switching of the m-fold great circle.
pub(crate) fn analyse_circle(
    opts: &DiagramOptions,
    m: u32,
    branches: &[TracedBranch],
) -> Result<(Vec<Buckling>, Vec<Switching>), SolverError> {
    let n1 = rodloop_solver::accuracy::load_cells(opts.accuracy, m);
    let coarse = circle_modes(opts, m, n1, true)?;
    let fine = circle_modes(opts, m, 2 * n1, true)?;
    let finest = circle_modes(opts, m, 4 * n1, false)?;
    let d = opts.stiffness.reference();
    let r = opts.radius;
    let mf = f64::from(m);
    let mut loads = Vec::new();
    let mut switches = Vec::new();
    for mode in &fine {
        let lam = |mu: f64| 1.0 + mu * r / d;
        let at = |set: &[Mode]| {
            set.iter()
                .find(|c| c.end == mode.end)
                .map(|c| lam(c.multiplier))
        };
        let l1 = lam(mode.multiplier);
        // Three-level Richardson (errors ∝ h⁴, h⁶): see the module docs.
        let (lambda, err) = match (at(&coarse), at(&finest)) {
            (Some(l0), Some(l2)) => {
                let r1 = rodloop_solver::richardson(l1, l0);
                let r2 = rodloop_solver::richardson(l2, l1);
                (r2 + (r2 - r1) / 63.0, 2.0 * (r2 - r1).abs() / 63.0)
            }
            (Some(l0), None) => (
                rodloop_solver::richardson(l1, l0),
                rodloop_solver::richardson_error(l1, l0),
            ),
            _ => (l1, 0.0),
        };
        let n = mode.periods;
        let (formula, equation) = if n == m + 1 {
            (Some((mf + 1.0).powi(2) / (mf * mf)), Some("33".to_string()))
        } else if n + 1 == m && m >= 2 {
            (Some((mf - 1.0).powi(2) / (mf * mf)), Some("34".to_string()))
        } else {
            (None, None)
        };
        loads.push(Buckling {
            m,
            mode_periods: n,
            multiplicity: mode.multiplicity,
            multiplier: lambda - 1.0,
            lambda_numeric: lambda,
            lambda_error: err + 8.0 * f64::EPSILON * lambda.abs(),
            lambda_formula: formula,
            equation,
            deviation: formula.map(|f| (lambda - f).abs()),
            cells: (n1, 4 * n1),
        });
        if n >= 1 {
            switches.push(switch(opts, m, mode, 2 * n1, branches));
        }
    }
    loads.sort_by_key(|b| std::cmp::Reverse(b.mode_periods));
    switches.sort_by_key(|s| std::cmp::Reverse(s.mode_periods));
    Ok((loads, switches))
}

/// Branch switching from one mode (see the module docs).
fn switch(
    opts: &DiagramOptions,
    m: u32,
    mode: &Mode,
    cells: usize,
    branches: &[TracedBranch],
) -> Switching {
    let mf = f64::from(m);
    let mut out = Switching {
        m,
        mode_periods: mode.periods,
        side: 0,
        lbar: mf,
        amplitude: 0.0,
        periods: 0,
        energy: None,
        lambda_range: None,
        joined_branch: None,
        energy_difference: None,
        merged: false,
        note: String::new(),
    };
    let result = (|| -> Result<Equilibrium, SolverError> {
        let model = opts.model(mf, cells)?;
        let nk = model.n_kappa();
        let scale = mode.vector.amax() * opts.radius;
        let v = &mode.vector / scale;
        let zero = vec![0.0; nk];
        let h1 = model.lagrangian_hessian(&zero, &[0.0, 1.0, 0.0])?
            - model.lagrangian_hessian(&zero, &[0.0; 3])?;
        // vᵀ∇²c_g v = −vᵀ h1 v.
        let q = -v.dot(&(&h1 * &v));
        let mut z0 = vec![0.0; nk + 3];
        z0[nk + 1] = mode.multiplier;
        let dl = model.kkt_dlbar(&z0)?;
        let dc = -dl[nk + 1];
        let side = if dc * q > 0.0 { -1.0 } else { 1.0 };
        let delta = side * SWITCH_OFFSET;
        let eps2 = -2.0 * dc * delta / q;
        if !(eps2.is_finite() && eps2 > 0.0) {
            return Err(SolverError::InvalidInput(format!(
                "degenerate second-order closure (∂c/∂L̄ = {dc:.3e}, vᵀ∇²c v = {q:.3e})"
            )));
        }
        let eps = eps2.sqrt();
        out.side = side as i32;
        out.lbar = mf + delta;
        out.amplitude = eps * opts.radius;
        let model = model.with_lbar(mf + delta)?;
        let start: Vec<f64> = v.iter().map(|x| eps * x).collect();
        let newton = SolveOptions {
            max_iterations: 60,
            ..newton_options()
        };
        solve(&model, &start, &newton).or_else(|_| {
            solve(
                &model,
                &start,
                &SolveOptions {
                    globalization: Globalization::Auto,
                    ..SolveOptions::default()
                },
            )
        })
    })();
    let eq = match result {
        Ok(eq) => eq,
        Err(e) => {
            out.note = format!("switching failed: {e}");
            return out;
        }
    };
    out.periods = periods_of(&eq).unwrap_or(0) as u32;
    let in_range = out.lbar >= opts.lbar_min && out.lbar <= opts.lbar_max;
    let candidate = branches
        .iter()
        .find(|b| b.eta == out.periods && b.covers(out.lbar));
    match candidate {
        Some(b) => {
            let cmp = (|| -> Result<(Equilibrium, Equilibrium), SolverError> {
                let traced = b.solve_at(opts, out.lbar)?;
                let sw = resolve(opts, &eq, b.cells)?;
                Ok((traced, sw))
            })();
            match cmp {
                Ok((traced, sw)) => {
                    let (et, es) = (traced.energy().total, sw.energy().total);
                    let (lt, ls) = (traced.lambda_range(), sw.lambda_range());
                    let de = (et - es).abs();
                    let dl = (lt.0 - ls.0).abs().max((lt.1 - ls.1).abs());
                    out.energy = Some(es);
                    out.lambda_range = Some(ls);
                    out.energy_difference = Some(de);
                    let lam_scale = lt.0.abs().max(lt.1.abs()).max(1.0);
                    if de <= 1e-9 * et.abs().max(1.0) && dl <= 1e-6 * lam_scale {
                        out.joined_branch = Some(b.branch);
                        out.merged = true;
                        out.note = format!(
                            "joins branch {} (η = {}): at L̄ = {:.4} the same energy \
                             ({es:.10}, difference {de:.1e}) and contact-force range \
                             (difference {dl:.1e}) at {} cells; merged",
                            b.branch, b.eta, out.lbar, b.cells
                        );
                    } else {
                        out.note = format!(
                            "η = {} like branch {} but a different state at L̄ = {:.4} \
                             (energy difference {de:.1e}, force-range difference {dl:.1e}): \
                             a new branch, not traced",
                            out.periods, b.branch, out.lbar
                        );
                    }
                }
                Err(e) => {
                    out.energy = Some(eq.energy().total);
                    out.lambda_range = Some(eq.lambda_range());
                    out.note = format!(
                        "η = {} but the comparison with branch {} failed: {e}",
                        out.periods, b.branch
                    );
                }
            }
        }
        None => {
            out.energy = Some(eq.energy().total);
            out.lambda_range = Some(eq.lambda_range());
            out.note = if in_range {
                format!(
                    "a branch with η = {} at L̄ = {:.4} that was not traced from an Euler seed",
                    out.periods, out.lbar
                )
            } else {
                format!(
                    "the branch with η = {} (paper branch {}) emanates from the {m}-fold great \
                     circle towards L̄ = {:.4}, outside the range",
                    out.periods,
                    rodloop_exact::branch_of_eta(out.periods),
                    out.lbar
                )
            };
        }
    }
    out
}
