//! Every traced state of a numeric diagram as a loop table, `OUT/states/*.csv`, in the
//! columns of `solve`'s `config.csv`: any point of a diagram can be re-solved
//! (`solve --from OUT/states/FILE`) or drawn (`draw OUT/states/FILE`). The row of
//! `branches.csv` names its file in the column `state_file`. The rows come from
//! [`rodloop_diagram::state_rows`]; this module names and writes the files.

use anyhow::Result;
use rodloop_diagram::state_rows::{
    point_rows, result_rows, surface_rows, ENCLOSED_COLUMNS, NODE_COLUMN, SURFACE_COLUMNS,
};
use rodloop_diagram::{DiagramOptions, NumericDiagram, TracedBranch};

use crate::output::{Cell, OutputRun, Table};

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
    let mut table = Table::new("config.csv", &SURFACE_COLUMNS);
    for row in surface_rows(profile, r, d0) {
        table.push(row.iter().map(|&x| Cell::F(x)).collect())?;
    }
    Ok(table)
}

/// The enclosed `config.csv` table of `rows` ([`ENCLOSED_COLUMNS`]; `node` as an integer).
fn enclosed_rows_table(rows: &[[f64; 12]]) -> Result<Table> {
    let mut table = Table::new("config.csv", &ENCLOSED_COLUMNS);
    for row in rows {
        table.push(
            row.iter()
                .enumerate()
                .map(|(i, &x)| {
                    if i == NODE_COLUMN {
                        Cell::I(x as i64)
                    } else {
                        Cell::F(x)
                    }
                })
                .collect(),
        )?;
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

/// The enclosed `config.csv` table of a solve's result ([`result_rows`]).
pub fn result_table(
    res: &rodloop_diagram::enclosed_state::EnclosedResult,
    r: f64,
    d0: f64,
) -> Result<Table> {
    enclosed_rows_table(&result_rows(res, r, d0)?)
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
        let rows = point_rows(&d.points[i], radius, d0).map_err(|e| format!("{e:#}"))?;
        let table = enclosed_rows_table(&rows).map_err(|e| format!("{e:#}"))?;
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
