//! `diagram --shapes K`: the branch atlas, drawn from a diagram directory's `branches.csv`
//! and the state files it names (`state_file`, see [`crate::states`]): K thumbnails per
//! branch (per family for a non-uniform rod) spread along its traced range, in `atlas/`,
//! and the composite `atlas.svg`/`atlas.png` (rows = branches, columns = positions along
//! them, as in the paper's Figs. 2, 9, 10). The layout is `rodloop_figures::atlas`.

use std::collections::BTreeMap;
use std::path::Path;

use anyhow::{bail, Context, Result};
use rodloop_figures::atlas::{atlas_figure, spread, thumbnail, AtlasCell, AtlasRow};
use rodloop_figures::color::branch_color;
use rodloop_figures::data::LoopData;
use rodloop_figures::raster::svg_to_png;

use crate::output::{write_atomic, OutputRun};

/// Width of one cell of the composite atlas, pixels.
pub const CELL: f64 = 170.0;
/// Width of a standalone thumbnail, pixels.
pub const THUMB: f64 = 240.0;

/// Largest `--shapes`.
pub const MAX_SHAPES: usize = 20;

/// One row of branches.csv, as the atlas needs it.
struct Row {
    branch: u32,
    eta: u32,
    family: u32,
    multiplicity: u32,
    arc: u64,
    lbar: f64,
    energy: f64,
    stability: String,
    file: String,
}

fn read_rows(dir: &Path) -> Result<Vec<Row>> {
    let path = dir.join("branches.csv");
    let mut rdr =
        csv::Reader::from_path(&path).with_context(|| format!("cannot read {}", path.display()))?;
    let header = rdr.headers()?.clone();
    let col = |name: &str| {
        header
            .iter()
            .position(|h| h == name)
            .with_context(|| format!("{}: no column {name}", path.display()))
    };
    let (cb, ce, cl, cen, cs, cf) = (
        col("branch")?,
        col("eta")?,
        col("lbar")?,
        col("energy")?,
        col("stability")?,
        col("state_file")?,
    );
    let (cfam, carc, cmul) = (
        col("family").ok(),
        col("arc").ok(),
        col("multiplicity").ok(),
    );
    let mut rows = Vec::new();
    for (i, rec) in rdr.records().enumerate() {
        let rec = rec.with_context(|| format!("{}: row {}", path.display(), i + 2))?;
        let get = |c: usize| rec.get(c).unwrap_or("");
        let num = |c: usize| -> Result<f64> {
            get(c)
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .with_context(|| format!("{}: row {}: not a number", path.display(), i + 2))
        };
        let int = |c: Option<usize>, default: u64| -> u64 {
            c.and_then(|c| get(c).parse().ok()).unwrap_or(default)
        };
        rows.push(Row {
            branch: num(cb)? as u32,
            eta: num(ce)? as u32,
            family: int(cfam, 0) as u32,
            multiplicity: int(cmul, 1) as u32,
            arc: int(carc, i as u64),
            lbar: num(cl)?,
            energy: num(cen)?,
            stability: get(cs).to_string(),
            file: get(cf).to_string(),
        });
    }
    Ok(rows)
}

/// One drawn row: branch, family and the `(lbar, state_file)` of its cells.
pub type NoteRow = (u32, u32, Vec<(f64, String)>);

/// What the atlas drew: per row, its heading and the states of its cells.
pub struct AtlasNote {
    /// The rows.
    pub rows: Vec<NoteRow>,
    /// Files written (relative to the diagram directory).
    pub files: Vec<String>,
}

/// The atlas rows of the diagram in `dir` with `k` cells each (fewer where a branch has fewer
/// states): rows by branch, then family; cells spread evenly in traversed `L̄` along the
/// family's arclength order.
fn atlas_rows(dir: &Path, k: usize) -> Result<(Vec<AtlasRow>, AtlasNote)> {
    let rows = read_rows(dir)?;
    let mut groups: BTreeMap<(u32, u32), Vec<&Row>> = BTreeMap::new();
    for r in &rows {
        groups.entry((r.branch, r.family)).or_default().push(r);
    }
    let mut out = Vec::new();
    let mut note = AtlasNote {
        rows: Vec::new(),
        files: Vec::new(),
    };
    for ((branch, family), mut g) in groups {
        g.sort_by_key(|r| r.arc);
        g.retain(|r| !r.file.is_empty());
        if g.is_empty() {
            continue;
        }
        let mut pos = vec![0.0];
        for w in g.windows(2) {
            pos.push(pos[pos.len() - 1] + (w[1].lbar - w[0].lbar).abs());
        }
        let mut cells = Vec::new();
        let mut picked = Vec::new();
        for i in spread(&pos, k) {
            let r = g[i];
            let data = LoopData::read(&dir.join(&r.file)).with_context(|| {
                format!("reading the state of branch {branch} at L̄ = {}", r.lbar)
            })?;
            cells.push(AtlasCell {
                points: data.points(),
                stiffness: data.column("D").map(<[f64]>::to_vec),
                off_wall: None,
                lbar: r.lbar,
                energy: r.energy,
                stability: r.stability.clone(),
            });
            picked.push((r.lbar, r.file.clone()));
        }
        let eta = g[0].eta;
        let subtitle = if family == 0 {
            format!("η = {eta}")
        } else if g[0].multiplicity > 1 {
            format!("η = {eta}\nfamily {family} (×{})", g[0].multiplicity)
        } else {
            format!("η = {eta}\nfamily {family}")
        };
        out.push(AtlasRow {
            title: format!("branch {branch}"),
            subtitle,
            color: branch_color(branch).to_string(),
            cells,
        });
        note.rows.push((branch, family, picked));
    }
    if out.is_empty() {
        bail!("the diagram has no state files to draw an atlas from");
    }
    Ok((out, note))
}

/// Draw the atlas of the staged diagram of `run` (its `branches.csv` and `states/`): the
/// thumbnails into the run's `atlas/` directory, the composite `atlas.svg`/`atlas.png`.
pub fn write_atlas(run: &OutputRun, k: usize, scene: &str) -> Result<AtlasNote> {
    check_shapes(k)?;
    let (rows, note) = atlas_rows(run.stage_dir(), k)?;
    write_rows(run, &rows, note, scene)
}

fn check_shapes(k: usize) -> Result<()> {
    if !(1..=MAX_SHAPES).contains(&k) {
        bail!("--shapes must be from 0 to {MAX_SHAPES} (got {k})");
    }
    Ok(())
}

/// The atlas of an exact diagram: per branch, `k` lengths spread over its sampled range, each
/// loop computed by the exact layer (Eq. 35, 256 points); labelled `lowest` where the branch
/// has the lowest energy, else `higher` (the exact model computes no Hessian index).
pub fn write_exact_atlas(
    run: &OutputRun,
    k: usize,
    d: &rodloop_schema::Diagram,
) -> Result<AtlasNote> {
    check_shapes(k)?;
    // The sampled points of each branch: (L̄, the point).
    let mut groups: BTreeMap<u32, Vec<(f64, &rodloop_schema::Point)>> = BTreeMap::new();
    for p in &d.points {
        if let Some(&lbar) = p.coords.first() {
            groups.entry(p.branch).or_default().push((lbar, p));
        }
    }
    let mut rows = Vec::new();
    let mut note = AtlasNote {
        rows: Vec::new(),
        files: Vec::new(),
    };
    for (branch, mut g) in groups {
        g.sort_by(|a, b| a.0.total_cmp(&b.0));
        let pos: Vec<f64> = g.iter().map(|p| p.0).collect();
        let mut cells = Vec::new();
        let mut picked = Vec::new();
        for i in spread(&pos, k) {
            let (lbar, p) = g[i];
            let lp = rodloop_exact::paper_branch_loop(p.eta, lbar)
                .with_context(|| format!("exact loop of branch {branch} at L̄ = {lbar}"))?;
            let pts = lp.sample(256)?;
            let lowest =
                matches!(p.extra.get("lowest"), Some(rodloop_schema::Cell::I(v)) if *v != 0);
            cells.push(AtlasCell {
                points: pts
                    .iter()
                    .map(|q| nalgebra::Vector3::new(q.x, q.y, q.z))
                    .collect(),
                stiffness: None,
                off_wall: None,
                lbar,
                energy: p.energy,
                stability: if lowest { "lowest" } else { "higher" }.into(),
            });
            picked.push((lbar, String::new()));
        }
        rows.push(AtlasRow {
            title: format!("branch {branch}"),
            subtitle: format!("η = {}", g[0].1.eta),
            color: branch_color(branch).to_string(),
            cells,
        });
        note.rows.push((branch, 0, picked));
    }
    if rows.is_empty() {
        bail!("the diagram has no states to draw an atlas from");
    }
    write_rows(run, &rows, note, "exact loops")
}

/// Write the thumbnails of `rows` into the run's `atlas/` and the composite.
fn write_rows(
    run: &OutputRun,
    rows: &[AtlasRow],
    mut note: AtlasNote,
    scene: &str,
) -> Result<AtlasNote> {
    let thumbs = run.subdir("atlas")?;
    for (row, (branch, family, _)) in rows.iter().zip(&note.rows) {
        for (j, cell) in row.cells.iter().enumerate() {
            let stem = if *family == 0 {
                format!("branch-{branch}-{:02}", j + 1)
            } else {
                format!("branch-{branch}-family-{family}-{:02}", j + 1)
            };
            let svg = thumbnail(row, cell, THUMB)?;
            write_atomic(&thumbs, &format!("{stem}.svg"), svg.as_bytes())?;
            let png = svg_to_png(&svg, 1.0).with_context(|| format!("rendering {stem}.png"))?;
            write_atomic(&thumbs, &format!("{stem}.png"), &png)?;
            note.files.push(format!("atlas/{stem}.svg"));
            note.files.push(format!("atlas/{stem}.png"));
        }
    }
    let svg = atlas_figure(
        rows,
        CELL,
        &format!("Branch atlas ({scene}): shapes along each branch"),
    )?;
    run.write_bytes("atlas.svg", svg.as_bytes())?;
    run.write_bytes(
        "atlas.png",
        &svg_to_png(&svg, 1.0).context("rendering atlas.png")?,
    )?;
    note.files.push("atlas.svg".into());
    note.files.push("atlas.png".into());
    record_in_summary(run, &note)?;
    Ok(note)
}

/// Add what the atlas drew to the staged `summary.json` (written before the atlas): an
/// `atlas` object with the files written (relative to the output directory) and, per row,
/// the lengths and state files of its cells.
fn record_in_summary(run: &OutputRun, note: &AtlasNote) -> Result<()> {
    let path = run.stage_dir().join("summary.json");
    let Ok(text) = std::fs::read_to_string(&path) else {
        return Ok(());
    };
    let mut summary: serde_json::Value =
        serde_json::from_str(&text).context("reading the staged summary.json")?;
    let rows: Vec<serde_json::Value> = note
        .rows
        .iter()
        .map(|(branch, family, cells)| {
            serde_json::json!({
                "branch": branch,
                "family": family,
                "lbar": cells.iter().map(|c| c.0).collect::<Vec<_>>(),
                "state_files": cells.iter().map(|c| c.1.as_str()).collect::<Vec<_>>(),
            })
        })
        .collect();
    if let serde_json::Value::Object(map) = &mut summary {
        map.insert(
            "atlas".into(),
            serde_json::json!({"files": note.files, "rows": rows}),
        );
    }
    run.write_json("summary.json", &summary)
}

/// The atlas of an enclosed diagram, read from its schema `d` (whose points keep no states
/// fit for the atlas' resolution): per branch, `k` of its sampled lengths spread over its range, each solved again as `rodloop solve` solves it
/// ([`crate::enclosed::solve_state`]; attached: the exact surface loop re-solved by the 3-D
/// model, lifted off: the 3-D model), written to `states/branch-B-NN.csv` in the columns of
/// the enclosed `config.csv` when `states` is given, and drawn with the parts off the wall
/// in amber. Returns the rows, what was drawn and the states that could not be solved.
pub fn enclosed_rows(
    scene: &rodloop_scene::Scene,
    accuracy: rodloop_solver::Accuracy,
    d: &rodloop_schema::Diagram,
    k: usize,
    states: Option<&Path>,
) -> Result<(Vec<AtlasRow>, AtlasNote, Vec<String>)> {
    check_shapes(k)?;
    let stiffness = crate::args::stiffness_of(&scene.stiffness);
    // The sampled points of each branch: (L̄, the point).
    let mut groups: BTreeMap<u32, Vec<(f64, &rodloop_schema::Point)>> = BTreeMap::new();
    for p in &d.points {
        if let Some(&lbar) = p.coords.first() {
            groups.entry(p.branch).or_default().push((lbar, p));
        }
    }
    let mut jobs = Vec::new();
    for (&branch, g) in groups.iter_mut() {
        g.sort_by(|a, b| a.0.total_cmp(&b.0));
        // The free planar circle (branch 0) is free only below L̄ = 1; at L̄ = 1 it is the
        // great circle on the wall, where the free-circle solve is singular: not a state of it.
        if branch == 0 {
            g.retain(|p| p.0 < 1.0 - 1e-9);
        }
        let pos: Vec<f64> = g.iter().map(|p| p.0).collect();
        for (j, i) in spread(&pos, k).into_iter().enumerate() {
            jobs.push((branch, j, g[i]));
        }
    }
    let solved = rodloop_diagram::parallel_map(&jobs, |&(branch, j, (lbar, _))| {
        let one = || -> Result<(LoopData, String)> {
            let res = crate::enclosed::solve_state(scene, &stiffness, lbar, branch, accuracy)?;
            let table =
                crate::states::result_table(&res, scene.radius, scene.stiffness.reference())?;
            let bytes = table.to_bytes()?;
            let name = format!("states/branch-{branch}-{:02}.csv", j + 1);
            if let Some(dir) = states {
                write_atomic(dir, name.trim_start_matches("states/"), &bytes)?;
            }
            let data = LoopData::parse(&name, &bytes)?;
            Ok((
                data,
                if states.is_some() {
                    name
                } else {
                    String::new()
                },
            ))
        };
        one().map_err(|e| format!("branch {branch} at L̄ = {lbar}: {e:#}"))
    });
    let mut rows: Vec<AtlasRow> = Vec::new();
    let mut note = AtlasNote {
        rows: Vec::new(),
        files: Vec::new(),
    };
    let mut failed = Vec::new();
    for ((branch, _, (lbar, p)), res) in jobs.iter().zip(solved) {
        let (data, file) = match res {
            Ok(x) => x,
            Err(e) => {
                failed.push(e);
                continue;
            }
        };
        if rows
            .last()
            .is_none_or(|r| r.title != format!("branch {branch}"))
        {
            rows.push(AtlasRow {
                title: format!("branch {branch}"),
                subtitle: if *branch == 0 {
                    "free circle".into()
                } else {
                    format!("η = {}", p.eta)
                },
                color: if *branch == 0 {
                    "#555555".into()
                } else {
                    branch_color(*branch).to_string()
                },
                cells: Vec::new(),
            });
            note.rows.push((*branch, 0, Vec::new()));
        }
        let off_wall = data.column("gap").map(|g| {
            g.iter()
                .map(|&v| v > rodloop_figures::data::GAP_TOUCH)
                .collect()
        });
        if let (Some(row), Some(n)) = (rows.last_mut(), note.rows.last_mut()) {
            row.cells.push(AtlasCell {
                points: data.points(),
                stiffness: data.column("D").map(<[f64]>::to_vec),
                off_wall,
                lbar: *lbar,
                energy: p.energy,
                stability: p.label.clone().unwrap_or_default(),
            });
            if !file.is_empty() {
                note.files.push(file.clone());
            }
            n.2.push((*lbar, file));
        }
    }
    if rows.is_empty() {
        bail!(
            "no state of the enclosed diagram could be solved for the atlas: {}",
            failed.join("; ")
        );
    }
    Ok((rows, note, failed))
}

/// `diagram --shapes K` on an enclosed scene: [`enclosed_rows`] with the states in the run's
/// `states/`, the thumbnails in `atlas/`, the composite `atlas.svg/.png`; the files and any
/// state that could not be solved are added to `summary.json`.
pub fn write_enclosed_atlas(
    run: &OutputRun,
    k: usize,
    scene: &rodloop_scene::Scene,
    accuracy: rodloop_solver::Accuracy,
    d: &rodloop_schema::Diagram,
) -> Result<AtlasNote> {
    let states = run.subdir("states")?;
    let (rows, note, failed) = enclosed_rows(scene, accuracy, d, k, Some(&states))?;
    for f in &failed {
        eprintln!("warning: atlas: {f}");
    }
    write_rows(run, &rows, note, &scene.name)
}

/// The composite atlas of the diagram in `dir` as SVG (for the report).
pub fn atlas_svg(dir: &Path, k: usize, scene: &str) -> Result<String> {
    let (rows, _) = atlas_rows(dir, k)?;
    Ok(atlas_figure(
        &rows,
        CELL,
        &format!("Branch atlas ({scene}): shapes along each branch"),
    )?)
}
