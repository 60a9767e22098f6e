//! What a diagram computes: [`DiagramOptions`] (scene, range of lengths, accuracy level) and
//! [`TraceControls`] (continuation controls a user may set), their validation and the
//! quantities they imply (branches, tracing cells, worker threads, the fingerprint a resumed
//! branch must match), and the scene's surface model built from them ([`surface_model`], the
//! one place the surface diagram chooses its confinement model).

use crate::DiagramError;
use rodloop_solver::{Accuracy, Param, SolverError, Stiffness};

/// What to compute: the scene, the range of lengths and the accuracy level.
///
/// [`DiagramOptions::default`] is the default scene of the CLI: homogeneous rod (`D = 1`) on
/// the unit sphere, `1 ≤ L̄ ≤ 5`, [`Accuracy::Default`].
#[derive(Clone, Debug, PartialEq)]
pub struct DiagramOptions {
    /// Sphere radius `R`.
    pub radius: f64,
    /// Bending stiffness profile.
    pub stiffness: Stiffness,
    /// Smallest length of the diagram.
    pub lbar_min: f64,
    /// Largest length of the diagram.
    pub lbar_max: f64,
    /// Accuracy level: tracing resolution, reporting resolution of the critical lengths.
    pub accuracy: Accuracy,
    /// Largest `η` traced. `None`: every branch whose range `(η − 1, η + 1)` meets
    /// `[lbar_min, lbar_max]`.
    pub eta_max: Option<u32>,
    /// Cells per period of `κ_g` (times `η + 1`) of the tracing resolution; `None`: from the
    /// accuracy level (8, 12, 16 for fast, default, high).
    pub trace_cells_per_period: Option<usize>,
    /// Distance from the great circle at which a branch end stops (must be in `(0, 1e-2)`).
    pub end_distance: f64,
    /// Whether [`assemble`](crate::assemble) analyses the great circles (buckling loads and branch
    /// switching).
    pub great_circles: bool,
    /// Worker threads for tracing and refinement (0: the available parallelism).
    pub threads: usize,
    /// The continued parameter of the branches. Only [`Param::Lbar`] makes a branch diagram
    /// (critical lengths, great circles); [`DiagramOptions::validate`] rejects the others.
    /// Continuing a branch in another parameter (e.g. `d1` at fixed `L̄`) is done with
    /// [`march()`](crate::march()) on a [`rodloop_solver::ParamProblem`].
    pub param: Param,
    /// Only these paper branch numbers ([`rodloop_exact::branch_of_eta`]); `None`: all of
    /// [`DiagramOptions::etas`]. Not part of the fingerprint.
    pub only_branches: Option<Vec<u32>>,
    /// Continuation controls of the tracing (`None` fields: the accuracy level's values).
    pub controls: TraceControls,
}

/// Continuation controls a user may set (`None`: the accuracy level's value). Steps are in
/// the tracer's scaled pseudo-arclength (unknowns scaled by `R/√n`, plus `L̄`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TraceControls {
    /// Largest step (default 0.6 / 0.25 / 0.2 for fast / default / high).
    pub max_step: Option<f64>,
    /// Smallest step before a branch end is declared (default 1e-6).
    pub min_step: Option<f64>,
    /// Most continuation points per direction of a branch (default 1000).
    pub max_points: Option<usize>,
    /// Newton tolerance of the corrector, max-norm of the scaled residual (default 1e-10).
    pub newton_tol: Option<f64>,
}

impl TraceControls {
    /// Whether every control is at its default.
    pub fn is_default(&self) -> bool {
        *self == Self::default()
    }

    fn validate(&self) -> Result<(), String> {
        if let Some(v) = self.max_step {
            if !(v.is_finite() && v > 0.0 && v <= 10.0) {
                return Err(format!("max_step must lie in (0, 10] (got {v})"));
            }
        }
        if let Some(v) = self.min_step {
            let hi = self.max_step.unwrap_or(0.2);
            if !(v.is_finite() && v > 0.0 && v < hi) {
                return Err(format!(
                    "min_step must be positive and below max_step = {hi} (got {v})"
                ));
            }
        }
        if let Some(v) = self.max_points {
            if !(10..=100_000).contains(&v) {
                return Err(format!("max_points must lie in [10, 100000] (got {v})"));
            }
        }
        if let Some(v) = self.newton_tol {
            if !(v.is_finite() && (1e-14..=1e-4).contains(&v)) {
                return Err(format!("newton_tol must lie in [1e-14, 1e-4] (got {v})"));
            }
        }
        Ok(())
    }
}

impl Default for DiagramOptions {
    fn default() -> Self {
        Self {
            radius: 1.0,
            stiffness: Stiffness::uniform(1.0),
            lbar_min: 1.0,
            lbar_max: 5.0,
            accuracy: Accuracy::Default,
            eta_max: None,
            trace_cells_per_period: None,
            end_distance: 5e-5,
            great_circles: true,
            threads: 0,
            param: Param::Lbar,
            only_branches: None,
            controls: TraceControls::default(),
        }
    }
}

/// The confinement model of the surface diagram: the one name of the concrete model in the
/// diagram's options, its data types and its state verification. Everything else works
/// through the model seam ([`rodloop_solver::Confinement`], with the surface solvers of
/// [`rodloop_solver::SurfaceSolve`]) or takes the model from [`DiagramOptions::model`] and
/// the equilibria it returns.
pub(crate) type Model = rodloop_solver::SurfaceModel;

/// A model at `lbar` with `cells` cells and, for uniform stiffness, the phase condition of
/// the reference `kappa` (Gauss values).
pub(crate) fn model_with_phase(
    opts: &DiagramOptions,
    lbar: f64,
    cells: usize,
    kappa: &[f64],
) -> Result<Model, SolverError> {
    let model = opts.model(lbar, cells)?;
    if opts.stiffness.is_uniform() {
        model.with_phase(rodloop_solver::Phase::from_gauss_values(kappa, cells)?)
    } else {
        Ok(model)
    }
}

/// The scene's surface model (sphere radius, length `L̄`, cells, stiffness): the one
/// place the surface diagram chooses its confinement model. Everything downstream works
/// through the model seam ([`rodloop_solver::Confinement`], with the surface solvers of
/// [`rodloop_solver::SurfaceSolve`]).
pub(crate) fn surface_model(
    radius: f64,
    lbar: f64,
    cells: usize,
    stiffness: &Stiffness,
) -> Result<Model, SolverError> {
    Model::new(radius, lbar, cells, stiffness)
}

impl DiagramOptions {
    /// The scene's model at length `lbar` with `cells` cells (`surface_model`).
    pub fn model(&self, lbar: f64, cells: usize) -> Result<Model, SolverError> {
        surface_model(self.radius, lbar, cells, &self.stiffness)
    }

    /// The default scene at another accuracy level.
    pub fn with_accuracy(accuracy: Accuracy) -> Self {
        Self {
            accuracy,
            ..Self::default()
        }
    }

    /// Check the options (finite positive radius, `0 < lbar_min < lbar_max`, a valid
    /// stiffness profile, a sensible end distance).
    pub fn validate(&self) -> Result<(), DiagramError> {
        let bad = |m: String| Err(DiagramError::InvalidOptions(m));
        if !(self.radius.is_finite() && self.radius > 0.0) {
            return bad(format!("radius must be positive (got {})", self.radius));
        }
        if !(self.lbar_min.is_finite() && self.lbar_max.is_finite()) {
            return bad("the length range must be finite".into());
        }
        if !(self.lbar_min > 0.0 && self.lbar_max > self.lbar_min) {
            return bad(format!(
                "need 0 < lbar_min < lbar_max (got {}, {})",
                self.lbar_min, self.lbar_max
            ));
        }
        if self.lbar_max > 1000.0 {
            return bad(format!("lbar_max = {} is beyond 1000", self.lbar_max));
        }
        if !(self.end_distance > 0.0 && self.end_distance < 1e-2) {
            return bad(format!(
                "end_distance must lie in (0, 0.01) (got {})",
                self.end_distance
            ));
        }
        if let Err(m) = self.controls.validate() {
            return bad(m);
        }
        if let Some(c) = self.trace_cells_per_period {
            if !(4..=400).contains(&c) {
                return bad(format!(
                    "trace_cells_per_period must lie in [4, 400] (got {c})"
                ));
            }
        }
        if self.param != Param::Lbar {
            return bad(format!(
                "a branch diagram is continued in lbar (got {}); use march() for other parameters",
                self.param
            ));
        }
        self.stiffness.validate()?;
        Ok(())
    }

    /// The branches `η` of the diagram, ascending (those of
    /// [`DiagramOptions::only_branches`] if given).
    pub fn etas(&self) -> Vec<u32> {
        let top = self.lbar_max.ceil() as u32 + 1;
        let max = self.eta_max.unwrap_or(top);
        (1..=max.min(top))
            .filter(|&eta| {
                let e = f64::from(eta);
                e - 1.0 < self.lbar_max && e + 1.0 > self.lbar_min
            })
            .filter(|&eta| {
                self.only_branches
                    .as_ref()
                    .is_none_or(|b| b.contains(&rodloop_exact::branch_of_eta(eta)))
            })
            .collect()
    }

    /// Cells per period of the tracing resolution.
    pub fn trace_cells_per_period(&self) -> usize {
        self.trace_cells_per_period
            .unwrap_or(self.accuracy.pick(rodloop_solver::accuracy::TRACE_CELLS))
    }

    /// Number of cells of the tracing resolution of branch `eta`: the accuracy policy's
    /// rule ([`rodloop_solver::accuracy::trace_cells`]) with [`Self::trace_cells_per_period`].
    pub fn trace_cells(&self, eta: u32) -> usize {
        rodloop_solver::accuracy::trace_cells(
            self.accuracy,
            self.trace_cells_per_period(),
            &self.stiffness,
            eta,
        )
    }

    /// Worker threads actually used.
    pub fn worker_threads(&self) -> usize {
        if self.threads > 0 {
            self.threads
        } else {
            std::thread::available_parallelism()
                .map(|n| n.get())
                .unwrap_or(1)
        }
    }

    /// A string identifying everything that determines a traced branch (scene, range,
    /// accuracy, tracing resolution, end distance): [`compute`](crate::compute) reuses a resumed
    /// branch only if its fingerprint matches.
    pub fn fingerprint(&self) -> String {
        format!(
            "R={:e};D={:?};range=[{:e},{:e}];accuracy={:?};cpp={};end={:e};v=1",
            self.radius,
            self.stiffness,
            self.lbar_min,
            self.lbar_max,
            self.accuracy,
            self.trace_cells_per_period(),
            self.end_distance
        ) + &if self.controls.is_default() {
            String::new()
        } else {
            format!(";controls={:?}", self.controls)
        }
    }
}
