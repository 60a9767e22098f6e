//! The arguments of `rodloop diagram`, shared by its surface, enclosed, exact and parameter
//! runs.

use std::path::PathBuf;

/// Default size of the diagram figures in pixels (width, height).
pub const FIGURE_SIZE: (u32, u32) = (960, 620);

/// Which model computes the diagram.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Model {
    /// Numerical equilibria of the scene (any stiffness profile), traced by continuation.
    Numeric,
    /// Closed-form elliptic-function solutions (homogeneous loops on the surface only).
    Exact,
}

/// Arguments of `rodloop diagram`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Model used to compute the branches.
    #[arg(long, value_enum, default_value_t = Model::Numeric)]
    pub model: Model,
    /// Scene file (TOML; see data/scenes/). Default: homogeneous loops on the unit sphere.
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Accuracy: fast, default or high (overrides the scene's; numeric model only).
    #[arg(long, value_parser = crate::args::ACCURACY_CHOICES)]
    pub accuracy: Option<String>,
    /// Smallest normalised length (default: the scene's, 1).
    #[arg(long)]
    pub lbar_min: Option<f64>,
    /// Largest normalised length (default: the scene's, 5).
    #[arg(long)]
    pub lbar_max: Option<f64>,
    /// Only these paper branches (comma-separated, e.g. 1,2); default: every branch that meets
    /// the length range.
    #[arg(long, value_delimiter = ',')]
    pub branch: Vec<u64>,
    /// Spacing of the sampled lengths in branches.csv (exact model, default 0.01; enclosed
    /// scenes, default 0.05; the numeric surface model reports the states it lands on).
    #[arg(long)]
    pub step: Option<f64>,
    /// Continue an interrupted numeric run from the branch files in OUT/branches (numeric
    /// model only).
    #[arg(long)]
    pub resume: bool,
    /// Largest continuation step, in the tracer's scaled arclength (numeric model; default
    /// 0.6 / 0.25 / 0.2 for fast / default / high).
    #[arg(long)]
    pub max_step: Option<f64>,
    /// Smallest continuation step before a branch end is declared (numeric model; default
    /// 1e-6).
    #[arg(long)]
    pub min_step: Option<f64>,
    /// Most continuation points per direction of a branch (numeric model; default 1000).
    #[arg(long)]
    pub max_points: Option<usize>,
    /// Newton tolerance of the continuation corrector, max-norm of the scaled residual
    /// (numeric model; default 1e-10).
    #[arg(long)]
    pub newton_tol: Option<f64>,
    /// No progress output on stderr (bars on a terminal, one line per branch otherwise).
    #[arg(long)]
    pub quiet: bool,
    /// Output directory.
    #[arg(long, default_value = "out/diagram")]
    pub out: PathBuf,
    /// Width of the diagram figures in pixels.
    #[arg(long, default_value_t = FIGURE_SIZE.0)]
    pub width: u32,
    /// Height of the diagram figures in pixels.
    #[arg(long, default_value_t = FIGURE_SIZE.1)]
    pub height: u32,
    /// Trace the equilibria at the fixed length --lbar against this parameter of a
    /// two-segment scene (d1 = D1/D0 on a log axis, gamma, s0, s1) instead of against L̄.
    #[arg(long)]
    pub param: Option<String>,
    /// The fixed normalised length of --param.
    #[arg(long)]
    pub lbar: Option<f64>,
    /// End value of --param (default 1e-3 for d1; the start is the scene's value).
    #[arg(long)]
    pub to: Option<f64>,
    /// Draw the energy figure relative to the stable state at each length (E − E_stable(L̄)),
    /// for diagrams whose branches lie close together (a very soft segment).
    #[arg(long)]
    pub relative: bool,
    /// Branch atlas: K shape thumbnails per branch spread along its range (in OUT/atlas/) and
    /// the composite atlas.svg/.png (rows = branches, columns = lengths); 0: none.
    #[arg(long, default_value_t = 0)]
    pub shapes: usize,
}
