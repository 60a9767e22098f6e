//! Arguments and their resolution shared by the commands: the accuracy level of
//! `--accuracy`, the stiffness profile of a scene; and the arguments of `solve`, which the
//! surface and the enclosed solve share.

use std::path::PathBuf;

use anyhow::Result;
use rodloop_scene::{Scene, StiffnessSpec};
use rodloop_solver::{Accuracy, Stiffness};

/// Arguments of `rodloop solve`.
#[derive(clap::Args, Debug)]
pub struct SolveArgs {
    /// Normalised length L/(2 pi R).
    #[arg(long)]
    pub lbar: f64,
    /// Paper branch number (1: saddle, eta = 2; 2: figure-eight, eta = 1; B >= 3: eta = B;
    /// enclosed scenes also 0: the planar circle, lbar <= 1).
    #[arg(long, required_unless_present = "eta", conflicts_with = "eta")]
    pub branch: Option<u64>,
    /// Alternative to --branch: the number of periods eta of the geodesic curvature.
    #[arg(long)]
    pub eta: Option<u64>,
    /// Scene file (TOML; see data/scenes/). Default: homogeneous loop on the unit sphere.
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Starting shape: a saved config.csv (its kappa_g column) or any CSV with columns x,y,z
    /// (points of a closed curve, in order). Default: the Euler rotation curve l = eta.
    #[arg(long)]
    pub from: Option<PathBuf>,
    /// Accuracy: fast, default or high (overrides the scene's).
    #[arg(long, value_parser = ACCURACY_CHOICES)]
    pub accuracy: Option<String>,
    /// Keep the state Newton converges to even where it is a saddle (index > 0). By default
    /// a saddle is left along its unstable directions for the local minimum of the same
    /// branch below it, and the output says so.
    #[arg(long)]
    pub keep_saddle: bool,
    /// Also draw the loop (four views, SVG and PNG) next to the CSV (see `rodloop draw`).
    #[arg(long)]
    pub draw: bool,
    /// Output directory.
    #[arg(long, default_value = "out/solve")]
    pub out: PathBuf,
}

/// The solver's stiffness for a scene's profile.
pub fn stiffness_of(spec: &StiffnessSpec) -> Stiffness {
    match spec {
        StiffnessSpec::Uniform { d } => Stiffness::Uniform { d: *d },
        StiffnessSpec::Tanh {
            d0,
            d1,
            s0,
            s1,
            gamma,
        } => Stiffness::Tanh {
            d0: *d0,
            d1: *d1,
            s0: *s0,
            s1: *s1,
            gamma: *gamma,
        },
        StiffnessSpec::Table { s, d } => Stiffness::Table {
            s: s.clone(),
            d: d.clone(),
        },
    }
}

/// The choices of `--accuracy` (clap checks them: an invalid one is a usage error, exit 2).
pub const ACCURACY_CHOICES: [&str; 3] = ["fast", "default", "high"];

/// Map the scene's accuracy (or the command-line override) to the solver's.
pub fn accuracy_of(scene: &Scene, over: Option<&str>) -> Result<Accuracy> {
    Ok(match over {
        Some(s) => s.parse::<Accuracy>()?,
        None => match scene.accuracy {
            rodloop_scene::Accuracy::Fast => Accuracy::Fast,
            rodloop_scene::Accuracy::Default => Accuracy::Default,
            rodloop_scene::Accuracy::High => Accuracy::High,
        },
    })
}
