//! `rodloop draw`: pictures of a loop (`config.csv`, `loop-NN.csv`, `curve.csv`) or of a
//! diagram directory's `branches.csv`, as SVG and/or PNG.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Context, Result};
use rodloop_figures::data::LoopData;
use rodloop_figures::diagram::{
    energy_figure, energy_g_figure, energy_split_figure, lambda_figure, DiagramData,
};
use rodloop_figures::loops::{loop_picture, LoopPictureOptions};
use rodloop_figures::overlay::align;
use rodloop_figures::paint::to_png;
use rodloop_figures::profiles::profiles_document;
use rodloop_figures::raster::svg_to_png;
use rodloop_figures::svg::Svg;
use serde_json::json;

use crate::output::{check_finite, ensure_dir, write_atomic};

/// RMS tolerance (fraction of R) of the point-group detector: a symmetry element is accepted
/// when it maps the resampled loop onto itself to this accuracy (the states of a coarse
/// `--accuracy fast` solve are symmetric to a few 1e-5 R).
pub const POINT_GROUP_TOL: f64 = rodloop_exact::shape::DEFAULT_TOLERANCE;

/// Fields of a `summary.json` for the shape of a loop: `point_group`, `point_group_order`
/// (absent for D∞h, C∞v), `self_intersections` (`"overlap"` for a multiply covered circle),
/// `symmetry_residual` and `shape_tolerance` (fractions of R).
pub fn shape_fields(s: &rodloop_exact::LoopShape) -> serde_json::Value {
    crate::output::strip_nulls(json!({
        "point_group": s.point_group,
        "point_group_order": s.group_order,
        "self_intersections": shape_count(s),
        "symmetry_residual": s.symmetry_residual,
        "shape_tolerance": s.tolerances,
    }))
}

/// Insert [`shape_fields`] into a JSON object.
pub fn add_shape(summary: &mut serde_json::Value, s: &rodloop_exact::LoopShape) {
    if let (Some(obj), serde_json::Value::Object(fields)) =
        (summary.as_object_mut(), shape_fields(s))
    {
        obj.extend(fields);
    }
}

/// The self-intersection count for JSON: the number, or `"overlap"` for a multiply covered
/// circle (which overlaps itself everywhere).
pub fn shape_count(s: &rodloop_exact::LoopShape) -> serde_json::Value {
    match s.self_intersections {
        Some(k) => json!(k),
        None => json!("overlap"),
    }
}

/// Which files to write.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// SVG only.
    Svg,
    /// PNG only.
    Png,
    /// Both.
    Both,
}

/// Arguments of `rodloop draw`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// A loop table (config.csv from solve, loop-NN.csv from analytic, curve.csv from euler, or
    /// any CSV with columns s,x,y,z) or a diagram's branches.csv.
    pub file: PathBuf,
    /// Output directory (default: the file's directory; out/draw for a state file in a
    /// diagram's states/, which holds that diagram's files only).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Column to colour the loop by (D, lambda, kappa_g, gap, kappa, tau, s, …; default:
    /// gap for a loop that has lifted off the wall (enclosed scenes), else lambda when present,
    /// else kappa_g).
    #[arg(long)]
    pub color: Option<String>,
    /// Output format.
    #[arg(long, value_enum, default_value_t = Format::Both)]
    pub format: Format,
    /// Self-contact tolerance as a fraction of the sphere radius: non-adjacent strands closer
    /// than this are marked as touching.
    #[arg(long, default_value_t = 1e-3)]
    pub tol: f64,
    /// Figure width in pixels for diagrams (loop pictures: the side of one view is width/2.5).
    #[arg(long)]
    pub width: Option<u32>,
    /// Figure height in pixels for diagrams.
    #[arg(long)]
    pub height: Option<u32>,
    /// Diagrams: draw the energy relative to the stable state at each length
    /// (E − E_stable(L̄)), for branches that lie close together (a very soft segment).
    #[arg(long)]
    pub relative: bool,
}

/// Resolved settings shared by `draw` and the `--draw` flags of other commands.
#[derive(Clone, Debug)]
pub struct DrawSettings {
    /// Output directory.
    pub out: PathBuf,
    /// Colour column.
    pub color: Option<String>,
    /// Formats.
    pub format: Format,
    /// Contact tolerance (fraction of R).
    pub tol: f64,
    /// Width hint in pixels.
    pub width: Option<u32>,
    /// Height hint in pixels.
    pub height: Option<u32>,
    /// A curve to overlay (dashed, aligned) on the profiles, with its legend label (Fig. 5).
    pub overlay: Option<(LoopData, String)>,
    /// Diagrams: energies relative to the stable state at each length.
    pub relative: bool,
}

/// Samples of an overlay curve.
const OVERLAY_POINTS: usize = 512;

/// The Euler rotation curve `l = η` at `L̄` (Eqs. 4–8) as an overlay, or `None` where it does
/// not exist.
pub fn euler_overlay(eta: u32, lbar: f64) -> Option<(LoopData, String)> {
    let curve = rodloop_exact::euler::EulerCurve::from_lbar(eta, lbar).ok()?;
    let pts = curve.sample(OVERLAY_POINTS);
    overlay_data("Euler curve", &pts, |p| {
        [p.s, p.x, p.y, p.z, p.kappa, p.tau, p.kappa_g]
    })
    .map(|d| {
        (
            d,
            format!("Euler rotation curve l = {eta} (Eqs. 4–8), aligned"),
        )
    })
}

/// The exact loop of the paper's branch with `η` periods at `L̄` (Eq. 35) as an overlay.
pub fn exact_overlay(eta: u32, lbar: f64) -> Option<(LoopData, String)> {
    let lp = rodloop_exact::paper_branch_loop(eta, lbar).ok()?;
    let pts = lp.sample(OVERLAY_POINTS).ok()?;
    overlay_data("exact loop", &pts, |p| {
        [p.s, p.x, p.y, p.z, p.kappa, p.tau, p.kappa_g]
    })
    .map(|d| {
        (
            d,
            format!(
                "exact loop of branch {} (Eq. 35), aligned",
                rodloop_exact::branch_of_eta(eta)
            ),
        )
    })
}

/// The columns `s, x, y, z, kappa, tau, kappa_g` of sampled points as an overlay curve.
fn overlay_data<P>(source: &str, pts: &[P], row: impl Fn(&P) -> [f64; 7]) -> Option<LoopData> {
    let rows: Vec<[f64; 7]> = pts.iter().map(row).collect();
    let cols: Vec<Vec<f64>> = (0..7)
        .map(|j| rows.iter().map(|r| r[j]).collect())
        .collect();
    let names = ["s", "x", "y", "z", "kappa", "tau", "kappa_g"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    LoopData::new(source, names, cols).ok()
}

impl DrawSettings {
    /// Defaults for `--draw`: both formats, next to the CSV.
    pub fn beside(dir: &Path) -> Self {
        Self {
            out: dir.to_path_buf(),
            color: None,
            format: Format::Both,
            tol: 1e-3,
            width: None,
            height: None,
            overlay: None,
            relative: false,
        }
    }
}

/// Write `stem.svg` and/or `stem.png`; returns the names written.
pub fn write_figure(dir: &Path, stem: &str, svg: &str, format: Format) -> Result<Vec<String>> {
    write_pair(
        dir,
        stem,
        format,
        || svg.to_string(),
        || svg_to_png(svg, 1.0),
    )
}

/// Write `stem.svg` and/or `stem.png` of a document (the PNG drawn from its operations).
pub fn write_document(dir: &Path, stem: &str, doc: &Svg, format: Format) -> Result<Vec<String>> {
    write_pair(dir, stem, format, || doc.finish(), || to_png(doc, 1.0))
}

fn write_pair(
    dir: &Path,
    stem: &str,
    format: Format,
    svg: impl FnOnce() -> String,
    png: impl FnOnce() -> Result<Vec<u8>, rodloop_figures::FigureError>,
) -> Result<Vec<String>> {
    let mut names = Vec::new();
    if format != Format::Png {
        write_atomic(dir, &format!("{stem}.svg"), svg().as_bytes())?;
        names.push(format!("{stem}.svg"));
    }
    if format != Format::Svg {
        let png = png().with_context(|| format!("rendering {stem}.png"))?;
        write_atomic(dir, &format!("{stem}.png"), &png)?;
        names.push(format!("{stem}.png"));
    }
    Ok(names)
}

/// What the table next to a loop file says about its state: `summary.json` of `rodloop
/// solve` beside a `config.csv` (branch, L̄, energy, contact-force extremes).
struct StateNote {
    branch: Option<u64>,
    lbar: Option<f64>,
    energy: Option<f64>,
    lambda: Option<(f64, f64)>,
}

fn state_note(path: &Path) -> StateNote {
    let summary = (path.file_name().is_some_and(|n| n == "config.csv"))
        .then(|| path.with_file_name("summary.json"))
        .and_then(|p| std::fs::read_to_string(p).ok())
        .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
        .unwrap_or_default();
    StateNote {
        branch: summary["branch"].as_u64(),
        lbar: summary["lbar"].as_f64(),
        energy: summary["energy"].as_f64(),
        lambda: summary["lambda_min"]
            .as_f64()
            .zip(summary["lambda_max"].as_f64()),
    }
}

/// The bending energy `E R/(πD₀) = (1/2π) ∮ (D/D₀) (κR)² d(s/R)` of a loop table with
/// columns `kappa` (and `D`, else a uniform rod), by the trapezoidal rule on the closed
/// loop; `None` without `kappa`.
fn table_energy(data: &LoopData) -> Option<f64> {
    let kappa = data.column("kappa")?;
    let d = data.column("D");
    let s = data.s();
    let n = s.len();
    if n < 3 || kappa.len() != n {
        return None;
    }
    let length = data.length();
    let f = |i: usize| d.map_or(1.0, |d| d[i]) * kappa[i] * kappa[i];
    let mut sum = 0.0;
    for i in 0..n {
        let h = if i + 1 < n {
            s[i + 1] - s[i]
        } else {
            s[0] + length - s[n - 1]
        };
        sum += 0.5 * h * (f(i) + f((i + 1) % n));
    }
    Some(sum / (2.0 * std::f64::consts::PI * data.radius()))
}

/// The paper branch in a state file's name (`branch-B…` of a diagram's `states/`).
fn branch_in_name(path: &Path) -> Option<u64> {
    let stem = path.file_stem()?.to_str()?;
    stem.strip_prefix("branch-")?
        .split(|c: char| !c.is_ascii_digit())
        .next()?
        .parse()
        .ok()
}

/// The picture's title: the state (branch, η, L̄, energy), not the file's path. Values come
/// from the solve's `summary.json` beside a `config.csv` when there is one, else from the
/// table itself (L̄ from its arclengths, η from the periods of its κ_g, the energy
/// integrated from its κ and D, marked "from the table").
fn state_title(path: &Path, data: &LoopData, note: &StateNote) -> String {
    let mut parts = Vec::new();
    if let Some(b) = note.branch.or_else(|| branch_in_name(path)) {
        parts.push(format!("branch {b}"));
    }
    if let Some(eta) = data.eta() {
        parts.push(format!("η = {eta}"));
    }
    let lbar = note.lbar.unwrap_or_else(|| data.lbar());
    parts.push(format!("L̄ = {}", round_sig(lbar, 6)));
    match note.energy {
        Some(e) => parts.push(format!("E R/(πD₀) = {}", round_sig(e, 8))),
        None => {
            if let Some(e) = table_energy(data) {
                parts.push(format!("E R/(πD₀) ≈ {} (from the table)", round_sig(e, 5)));
            }
        }
    }
    let title = parts.join(", ");
    // "Branch 1, …" (a title that starts with η stays as it is).
    match title.strip_prefix("branch") {
        Some(rest) => format!("Branch{rest}"),
        None => title,
    }
}

/// `v` with `digits` significant digits, trailing zeros dropped (1.2, 1.9164126).
fn round_sig(v: f64, digits: i32) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let dec = (digits - 1 - v.abs().log10().floor() as i32).max(0) as usize;
    let s = format!("{v:.dec$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// Draw one loop file: the four-view picture, and a JSON note of what was found.
pub fn draw_loop(path: &Path, set: &DrawSettings) -> Result<Vec<String>> {
    let t0 = Instant::now();
    let data = LoopData::read(path)?;
    let stem = path
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("loop")
        .to_string();
    if let Some(w) = set.width.filter(|w| !(375..=10_000).contains(w)) {
        bail!("--width {w}: a loop picture is 375 to 10000 pixels wide (each view is width/2.5, 150 to 4000 pixels)");
    }
    if !(set.tol > 0.0 && set.tol < 1.0) {
        bail!(
            "--tol {}: the self-contact tolerance must be in (0, 1), a fraction of R",
            set.tol
        );
    }
    let panel = set.width.map_or(380.0, |w| f64::from(w) / 2.5);
    let note = state_note(path);
    let title = state_title(path, &data, &note);
    let color_column = set
        .color
        .clone()
        .unwrap_or_else(|| data.default_color_column().to_string());
    let opts = LoopPictureOptions {
        color: set.color.clone(),
        tol: set.tol,
        panel,
        title: title.clone(),
        // The solve's contact-force extremes (between the nodes), which it also prints.
        extremes: note.lambda.filter(|_| color_column == "lambda"),
    };
    let pic = loop_picture(&data, &opts)?;
    let t_picture = t0.elapsed().as_secs_f64();
    // Fig. 5: the overlay curve aligned onto the loop (shift, direction, mirror, rotation).
    let aligned = set.overlay.as_ref().map(|(o, label)| {
        align(&data, o)
            .map(|a| (a, label.clone()))
            .map_err(|e| e.to_string())
    });
    let profiles = profiles_document(
        &data,
        match &aligned {
            Some(Ok((a, label))) => Some((&a.data, label.as_str())),
            _ => None,
        },
        480.0,
        260.0,
        &format!("{title}: quantities along the loop (Figs. 5, 6)"),
    )?;
    ensure_dir(&set.out)?;
    // The two figures are rasterised at once (each takes tens of milliseconds with PNG).
    let profiles_stem = format!("{stem}-profiles");
    let (a, b) = std::thread::scope(|scope| {
        let other = scope.spawn(|| write_document(&set.out, &profiles_stem, &profiles, set.format));
        let mine = write_document(&set.out, &stem, &pic.document, set.format);
        (mine, other.join())
    });
    let mut written = a?;
    written.extend(b.map_err(|_| anyhow::anyhow!("drawing {profiles_stem} failed"))??);
    let note = json!({
        "file": path.display().to_string(),
        "points": data.len(),
        "radius": data.radius(),
        "length": data.length(),
        "lbar": data.lbar(),
        "eta": data.eta(),
        "color_column": pic.color_column,
        "color_range": [pic.scale.min, pic.scale.max],
        "self_intersections": pic.shape.as_ref().map_or(json!(pic.contacts.len()), shape_count),
        "self_intersection_tolerance": pic.tol,
        "self_intersection_points": pic.contacts.iter().map(|c| json!({"x": c.point.x, "y": c.point.y, "z": c.point.z, "distance": c.distance})).collect::<Vec<_>>(),
        "apparent_crossings_per_view": pic.apparent_crossings.iter().map(|(v, k)| json!({"view": v, "crossings": k})).collect::<Vec<_>>(),
        "point_group": pic.shape.as_ref().map(|g| g.point_group.clone()),
        "point_group_order": pic.shape.as_ref().and_then(|g| g.group_order),
        "point_group_tolerance": pic.shape.as_ref().map(|g| g.tolerances.symmetry),
        "symmetry_residual": pic.shape.as_ref().map(|g| g.symmetry_residual),
        "overlay": match &aligned {
            Some(Ok((a, label))) => json!({
                "curve": label, "max_distance": a.max_distance, "shift": a.shift,
                "reversed": a.reversed, "mirrored": a.mirrored,
            }),
            Some(Err(e)) => json!({"error": e}),
            None => serde_json::Value::Null,
        },
        "seconds_picture": t_picture,
        "seconds": t0.elapsed().as_secs_f64(),
    });
    let name = format!("{stem}-draw.json");
    let note = crate::output::strip_nulls(note);
    check_finite(&name, &note)?;
    let mut bytes = serde_json::to_vec_pretty(&note)?;
    bytes.push(b'\n');
    write_atomic(&set.out, &name, &bytes)?;
    written.push(name);
    Ok(written)
}

/// `, NAME.svg, …` for a "wrote …" line: the files `draw_loop` wrote (empty without `--draw`).
pub fn and_pictures(names: &[String]) -> String {
    names.iter().map(|n| format!(", {n}")).collect()
}

/// Draw the figures of a diagram directory (`branches.csv`, `critical.csv`) into
/// `set.out`: `diagram` (Fig. 3a), `diagram_split` (Fig. 3b), `diagram_lambda` (Fig. 7); for
/// an enclosed diagram only `diagram` (with its lifted-off parts and lift-off/landing events).
pub fn draw_diagram(dir: &Path, set: &DrawSettings) -> Result<Vec<String>> {
    // Whether the buckling loads of Eqs. (33)–(34) apply follows from the rows (a
    // non-uniform rod's branches are families numbered from 1; see `DiagramData`).
    let mut d = DiagramData::read(dir)?;
    if set.relative {
        d.relative_to_stable()?;
    }
    let w = f64::from(set.width.unwrap_or(960));
    let h = f64::from(set.height.unwrap_or(620));
    ensure_dir(&set.out)?;
    // An enclosed diagram has no energy split and no largest contact force; only the exact
    // model has the energy against `g`.
    let mut figures: Vec<(&str, DiagramFigure)> = vec![("diagram", energy_figure)];
    if d.missing.is_empty() {
        if d.model == "exact" {
            figures.push(("diagram_g", energy_g_figure));
        }
        figures.push(("diagram_split", energy_split_figure));
        figures.push(("diagram_lambda", lambda_figure));
    }
    // Each figure drawn, rendered and written on a thread of its own (the PNG rendering is
    // most of the time); the names in the order of `figures`.
    let written: Vec<Result<Vec<String>>> = std::thread::scope(|scope| {
        let d = &d;
        let handles: Vec<_> = figures
            .iter()
            .map(|&(stem, figure)| {
                scope.spawn(move || write_figure(&set.out, stem, &figure(d, w, h)?, set.format))
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().unwrap_or_else(|p| std::panic::resume_unwind(p)))
            .collect()
    });
    let mut names = Vec::new();
    for w in written {
        names.extend(w?);
    }
    Ok(names)
}

/// A figure of a diagram's tables at a width and height (SVG).
type DiagramFigure = fn(&DiagramData, f64, f64) -> Result<String, rodloop_figures::FigureError>;

/// Whether `dir` is the `states/` folder of a diagram (its parent holds the diagram's
/// `branches.csv`).
pub fn in_diagram_states(dir: &Path) -> bool {
    dir.file_name().is_some_and(|n| n == "states")
        && dir
            .parent()
            .is_some_and(|p| p.join("branches.csv").is_file())
}

/// Run the subcommand.
pub fn run(args: &Args) -> Result<()> {
    let meta = std::fs::metadata(&args.file)
        .with_context(|| format!("cannot read {}", args.file.display()))?;
    if !meta.is_file() {
        bail!("{} is not a file", args.file.display());
    }
    let dir = args
        .file
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("."));
    // A diagram's states/ holds that diagram's state files only: pictures of them go to
    // out/draw unless --out says where.
    let default_out = if in_diagram_states(&dir) {
        PathBuf::from("out/draw")
    } else {
        dir
    };
    let set = DrawSettings {
        out: args.out.clone().unwrap_or(default_out),
        color: args.color.clone(),
        format: args.format,
        tol: args.tol,
        width: args.width,
        height: args.height,
        overlay: None,
        relative: args.relative,
    };
    if args.relative && args.file.file_name().is_none_or(|n| n != "branches.csv") {
        bail!("--relative applies to a diagram's branches.csv (energies relative to the stable state), not to a loop picture");
    }
    let is_diagram = args.file.file_name().is_some_and(|n| n == "branches.csv");
    let written = if is_diagram {
        let dir = args.file.parent().unwrap_or(Path::new("."));
        draw_diagram(dir, &set)?
    } else {
        draw_loop(&args.file, &set)?
    };
    outln!("wrote {} to {}", written.join(", "), set.out.display());
    Ok(())
}
