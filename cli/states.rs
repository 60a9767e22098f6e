//! Every traced state of a numeric diagram as a loop table, `OUT/states/*.csv`, in the
//! columns of `solve`'s `config.csv`: any point of a diagram can be re-solved
//! (`solve --from OUT/states/FILE`) or drawn (`draw OUT/states/FILE`). The row of
//! `branches.csv` names its file in the column `state_file`.

use anyhow::Result;
use rodloop_diagram::{DiagramOptions, NumericDiagram, TracedBranch};

use crate::output::{Cell, OutputRun, Table};

/// Points per state file of an enclosed diagram's attached and exact states.
pub use rodloop_diagram::STATE_POINTS;

/// The file of traced state `k` of `b`, relative to the diagram directory:
/// `states/branch-B-KKK.csv`, or `states/branch-B-family-F-sheet-S-KKK.csv` for a family of
/// a non-uniform rod (`k` counts the sheet's states in increasing `L̄`).
pub fn file_name(b: &TracedBranch, k: usize) -> String {
    if b.family == 0 {
        format!("states/branch-{}-{k:03}.csv", b.branch)
    } else {
        format!(
            "states/branch-{}-family-{}-sheet-{}-{k:03}.csv",
            b.branch, b.family, b.sheet
        )
    }
}

/// Write the state files into the run's `states/` directory: the states as the diagram
/// verified them ([`NumericDiagram::state_files`]). Returns the file of every row of
/// [`NumericDiagram::rows`], in that order (empty where a state failed the verification,
/// which the diagram's warnings name), and the warnings of files that could not be written.
pub fn write_states(
    d: &NumericDiagram,
    opts: &DiagramOptions,
    run: &OutputRun,
) -> Result<(Vec<String>, Vec<String>)> {
    let dir = run.subdir("states")?;
    let (r, d0) = (opts.radius, opts.stiffness.reference());
    let mut names = Vec::new();
    let mut warnings = Vec::new();
    for (b, files) in d.branches.iter().zip(&d.state_files) {
        for (k, f) in files.iter().enumerate() {
            let Some(f) = f else {
                names.push(String::new());
                continue;
            };
            let name = file_name(b, k);
            match write_state_file(&dir, &name, f, r, d0) {
                Ok(_) => names.push(name),
                Err(e) => {
                    names.push(String::new());
                    warnings.push(format!("{name} could not be written: {e:#}"));
                }
            }
        }
    }
    Ok((names, warnings))
}

/// Write the verified state `f` as `name` (relative to the run's directory, `states/…`) into
/// `dir` (the run's `states/` directory), in the columns of `solve`'s `config.csv` (units of
/// the scene's `r` and `d0`): the one writer of every state file of a surface scene.
pub fn write_state_file(
    dir: &std::path::Path,
    name: &str,
    f: &rodloop_diagram::StateFile,
    r: f64,
    d0: f64,
) -> Result<()> {
    let file = name.trim_start_matches("states/");
    let bytes = config_table_in(&f.profile, r, d0)?.to_bytes()?;
    crate::output::write_atomic(dir, file, &bytes)?;
    Ok(())
}

/// [`crate::solve::config_table`] for a sphere of radius `r` and reference stiffness `d0`.
pub fn config_table_in(profile: &[rodloop_solver::ProfilePoint], r: f64, d0: f64) -> Result<Table> {
    let (lam_unit, f_unit) = (r * r * r / d0, r * r / d0);
    let mut table = Table::new(
        "config.csv",
        &[
            "s", "x", "y", "z", "kappa", "tau", "kappa_g", "lambda", "F_t", "F_n", "F_b", "D",
        ],
    );
    for p in profile {
        table.push(vec![
            Cell::F(p.s / r),
            Cell::F(p.x / r),
            Cell::F(p.y / r),
            Cell::F(p.z / r),
            Cell::F(p.kappa * r),
            Cell::F(p.tau * r),
            Cell::F(p.kappa_g * r),
            Cell::F(p.lambda * lam_unit),
            Cell::F(p.f_t * f_unit),
            Cell::F(p.f_n * f_unit),
            Cell::F(p.f_b * f_unit),
            Cell::F(p.d / d0),
        ])?;
    }
    Ok(table)
}

/// `f` over `items` on the available cores, results in the order of `items`.
pub fn parallel_map<T: Sync, R: Send>(items: &[T], f: impl Fn(&T) -> R + Sync) -> Vec<R> {
    let threads = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .min(items.len().max(1));
    let next = std::sync::atomic::AtomicUsize::new(0);
    let slots: Vec<std::sync::Mutex<Option<R>>> =
        items.iter().map(|_| std::sync::Mutex::new(None)).collect();
    std::thread::scope(|scope| {
        for _ in 0..threads {
            scope.spawn(|| loop {
                let k = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                let Some(item) = items.get(k) else {
                    break;
                };
                let r = f(item);
                if let Ok(mut slot) = slots[k].lock() {
                    *slot = Some(r);
                }
            });
        }
    });
    slots
        .into_iter()
        .map(|m| {
            m.into_inner()
                .ok()
                .flatten()
                .expect("every item was mapped by a worker")
        })
        .collect()
}

/// Every file under `dir` (recursively), as sorted paths relative to it with `/` separators:
/// what a command wrote into its output directory, for its `summary.json`.
pub fn files_in(dir: &std::path::Path) -> Result<Vec<String>> {
    fn walk(base: &std::path::Path, d: &std::path::Path, out: &mut Vec<String>) -> Result<()> {
        for e in std::fs::read_dir(d)? {
            let p = e?.path();
            if p.is_dir() {
                walk(base, &p, out)?;
            } else if let Ok(rel) = p.strip_prefix(base) {
                let parts: Vec<String> = rel
                    .components()
                    .map(|c| c.as_os_str().to_string_lossy().into_owned())
                    .collect();
                out.push(parts.join("/"));
            }
        }
        Ok(())
    }
    let mut out = Vec::new();
    walk(dir, dir, &mut out)?;
    out.sort();
    Ok(out)
}

/// The file of point `k` of an enclosed diagram (`k` counts the points of its branch, family
/// and sheet in increasing `L̄`): `states/enclosed-branch-B-KKK.csv`, or
/// `states/enclosed-branch-B-family-F-sheet-S-KKK.csv` for a family of a non-uniform rod.
pub fn enclosed_file_name(p: &rodloop_diagram::enclosed::EnclosedPoint, k: usize) -> String {
    if p.family == 0 {
        format!("states/enclosed-branch-{}-{k:03}.csv", p.branch)
    } else {
        format!(
            "states/enclosed-branch-{}-family-{}-sheet-{}-{k:03}.csv",
            p.branch, p.family, p.sheet
        )
    }
}

/// The columns of an enclosed state file: every row a point of the loop in increasing `s`;
/// `node` is 1 at a node of the 3-D model (or at every sample of a surface loop) and 0 at a
/// Gauss point; `weight` is the point's quadrature weight in units of `R`, so that
/// `E R/(π D0) = (1/π) Σ weight · ½ D κ²` is the reported state's energy by the rule that
/// computed it (two-point Gauss per cell for the 3-D model, the periodic trapezoid for the
/// uniform samples of a surface loop).
pub const ENCLOSED_COLUMNS: [&str; 12] = [
    "s", "x", "y", "z", "gap", "kappa", "kappa_1", "kappa_2", "lambda", "D", "node", "weight",
];

/// The enclosed `config.csv` table ([`ENCLOSED_COLUMNS`], units of `R` and `D0`) of a loop
/// on the sphere of radius `r` given as `(s, x, y, z, κ_g, λ, D)` rows in the model's units,
/// uniform in arclength over the length `length`: the surface loop is the enclosed state
/// where it is attached, with curvature vector `(κ1, κ2) = (κ_g, −1/R)` in the Darboux frame
/// (rotation-minimising on the sphere, as in the 3-D model's start from a surface loop).
fn sphere_table(rows: &[[f64; 7]], length: f64, r: f64, d0: f64) -> Result<Table> {
    let mut table = Table::new("config.csv", &ENCLOSED_COLUMNS);
    let weight = length / rows.len() as f64;
    for &[s, x, y, z, kg, lam, d] in rows {
        let rad = (x * x + y * y + z * z).sqrt();
        table.push(vec![
            Cell::F(s / r),
            Cell::F(x / r),
            Cell::F(y / r),
            Cell::F(z / r),
            Cell::F((r - rad) / r),
            Cell::F((kg * kg + 1.0 / (r * r)).sqrt() * r),
            Cell::F(kg * r),
            Cell::F(-1.0),
            Cell::F(lam * r * r * r / d0),
            Cell::F(d / d0),
            Cell::I(1),
            Cell::F(weight / r),
        ])?;
    }
    Ok(table)
}

/// The enclosed `config.csv` table of a 3-D state ([`ENCLOSED_COLUMNS`], units of `R` and
/// `D0`, ball radius `r`): every node and the two Gauss points of each cell
/// ([`rodloop_solver::enclosed_profile`]). The contact force `λ` is nodal (the wall is
/// imposed at the nodes); a Gauss row holds it interpolated linearly between its cell's
/// nodes.
pub fn model_table(st: &rodloop_solver::enclosed::EnclosedState, r: f64, d0: f64) -> Result<Table> {
    let m = &st.model;
    let lam = m.contact_force(&st.z);
    let n = m.cells();
    let bounds = m.bounds();
    let mut table = Table::new("config.csv", &ENCLOSED_COLUMNS);
    for (k, p) in rodloop_solver::enclosed_profile(st)?.iter().enumerate() {
        let c = k / 3;
        let lambda = if p.node {
            lam[c]
        } else {
            let t = (p.s / m.length() - bounds[c]) / (bounds[c + 1] - bounds[c]);
            lam[c] + t * (lam[(c + 1) % n] - lam[c])
        };
        let (k1, k2) = p.kappa;
        let rad = (p.r[0] * p.r[0] + p.r[1] * p.r[1] + p.r[2] * p.r[2]).sqrt();
        table.push(vec![
            Cell::F(p.s / r),
            Cell::F(p.r[0] / r),
            Cell::F(p.r[1] / r),
            Cell::F(p.r[2] / r),
            Cell::F((r - rad) / r),
            Cell::F((k1 * k1 + k2 * k2).sqrt() * r),
            Cell::F(k1 * r),
            Cell::F(k2 * r),
            Cell::F(lambda * r * r * r / d0),
            Cell::F(p.d / d0),
            Cell::I(i64::from(p.node)),
            Cell::F(p.weight / r),
        ])?;
    }
    Ok(table)
}

/// The enclosed `config.csv` table of a solve's result: the surface loop where the energy
/// reported is its (attached), else the 3-D state.
pub fn result_table(
    res: &rodloop_diagram::enclosed_state::EnclosedResult,
    r: f64,
    d0: f64,
) -> Result<Table> {
    match &res.attached_loop {
        Some((source, points)) => {
            let rows = rodloop_diagram::enclosed_state::attached_rows(source, *points, r, d0)?;
            sphere_table(&rows, res.state.model.length(), r, d0)
        }
        None => model_table(&res.state, r, d0),
    }
}

/// The table of one enclosed diagram point's loop (see [`sphere_table`] for attached ones).
fn enclosed_table(p: &rodloop_diagram::enclosed::EnclosedPoint, r: f64, d0: f64) -> Result<Table> {
    use rodloop_diagram::enclosed::PointShape;
    use std::f64::consts::PI;
    match &p.shape {
        PointShape::Model(st) => model_table(st, r, d0),
        PointShape::Surface(eq) => {
            let m = STATE_POINTS.max(eq.model().cells());
            let rows: Vec<[f64; 7]> = eq
                .profile_uniform(m)?
                .iter()
                .map(|q| [q.s, q.x, q.y, q.z, q.kappa_g, q.lambda, q.d])
                .collect();
            sphere_table(&rows, eq.model().length(), r, d0)
        }
        PointShape::Exact(l) => {
            let source = rodloop_solver::enclosed::SurfaceSource::Exact(*l);
            let rows =
                rodloop_diagram::enclosed_state::attached_rows(&source, STATE_POINTS, r, d0)?;
            sphere_table(&rows, l.length() * r, r, d0)
        }
        PointShape::Circle => {
            // Radius `ρ = R L̄` about the centre, in the plane y = 0; curvature vector
            // (0, −1/ρ) in the frame whose tangent starts along x (the model's start).
            let rho = p.lbar;
            let mut table = Table::new("config.csv", &ENCLOSED_COLUMNS);
            for i in 0..STATE_POINTS {
                let a = 2.0 * PI * i as f64 / STATE_POINTS as f64;
                table.push(vec![
                    Cell::F(rho * a),
                    Cell::F(rho * a.sin()),
                    Cell::F(0.0),
                    Cell::F(rho * a.cos()),
                    Cell::F(1.0 - rho),
                    Cell::F(1.0 / rho),
                    Cell::F(0.0),
                    Cell::F(-1.0 / rho),
                    Cell::F(0.0),
                    Cell::F(1.0),
                    Cell::I(1),
                    Cell::F(2.0 * PI * rho / STATE_POINTS as f64),
                ])?;
            }
            Ok(table)
        }
        PointShape::Missing => anyhow::bail!("no verified shape (the diagram's warnings say why)"),
    }
}

/// Write every point of an enclosed diagram into the run's `states/` directory (in
/// parallel): the lifted-off 3-D states as they are, attached ones as their surface loop.
/// Returns the file of every point of `d.points`, in that order (empty where none was
/// written), and the warnings for those.
pub fn write_enclosed_states(
    d: &rodloop_diagram::enclosed::EnclosedDiagram,
    radius: f64,
    d0: f64,
    run: &OutputRun,
) -> Result<(Vec<String>, Vec<String>)> {
    let dir = run.subdir("states")?;
    // Number the points of each (branch, family, sheet) in increasing L̄.
    let mut order: Vec<usize> = (0..d.points.len()).collect();
    let key = |i: usize| {
        let p = &d.points[i];
        (p.branch, p.family, p.sheet)
    };
    order.sort_by(|&a, &b| {
        key(a)
            .cmp(&key(b))
            .then(d.points[a].lbar.total_cmp(&d.points[b].lbar))
    });
    let mut names = vec![String::new(); d.points.len()];
    let mut count = 0;
    for (pos, &i) in order.iter().enumerate() {
        if pos > 0 && key(order[pos - 1]) != key(i) {
            count = 0;
        }
        names[i] = enclosed_file_name(&d.points[i], count);
        count += 1;
    }
    let jobs: Vec<usize> = (0..d.points.len()).collect();
    let results = parallel_map(&jobs, |&i| {
        let table = enclosed_table(&d.points[i], radius, d0).map_err(|e| format!("{e:#}"))?;
        let bytes = table.to_bytes().map_err(|e| format!("{e:#}"))?;
        let file = names[i].trim_start_matches("states/");
        crate::output::write_atomic(&dir, file, &bytes).map_err(|e| format!("{e:#}"))?;
        Ok::<(), String>(())
    });
    let mut warnings = Vec::new();
    for (i, res) in results.into_iter().enumerate() {
        if let Err(e) = res {
            let p = &d.points[i];
            warnings.push(format!(
                "the state of branch {} family {} at L̄ = {} has no state file: {e}",
                p.branch, p.family, p.lbar
            ));
            names[i].clear();
        }
    }
    Ok((names, warnings))
}
