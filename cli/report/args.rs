//! The arguments of `rodloop report` and the sizes of its page, shared by the surface and the
//! enclosed page.

use std::path::PathBuf;

/// Width of the diagram figures in the page, pixels.
pub const FIG_W: f64 = 960.0;
/// Height of the diagram figures in the page, pixels.
pub const FIG_H: f64 = 560.0;
/// Side of one view of a loop picture, pixels (four views per picture): the smallest at which
/// the view titles and the legend of `loop_picture` fit, so that its text is drawn at its
/// own size (the picture is 2·PANEL + 208 pixels wide).
pub const PANEL: f64 = 300.0;
/// Columns of the branch atlas in the page.
pub const ATLAS_SHAPES: usize = 5;
/// Arguments of `rodloop report`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Scene file (TOML; see data/scenes/). Default: homogeneous loops on the unit sphere.
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Accuracy: fast, default or high (overrides the scene's).
    #[arg(long, value_parser = crate::args::ACCURACY_CHOICES)]
    pub accuracy: Option<String>,
    /// No progress output on stderr.
    #[arg(long)]
    pub quiet: bool,
    /// Output directory: report.html, with the diagram's branches.csv, critical.csv,
    /// diagram.svg and summary.json.
    #[arg(long, default_value = "out/report")]
    pub out: PathBuf,
}
