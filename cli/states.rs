//! Every traced state of a numeric diagram as a loop table, `OUT/states/*.csv`, in the
//! columns of `solve`'s `config.csv`: any point of a diagram can be re-solved
//! (`solve --from OUT/states/FILE`) or drawn (`draw OUT/states/FILE`). The row of
//! `branches.csv` names its file in the column `state_file`.

use anyhow::Result;
use rodloop_diagram::{DiagramOptions, NumericDiagram, TracedBranch};

use crate::output::OutputRun;

/// Points per state file (uniform in arclength); more when the tracing resolution has more
/// cells.
pub const STATE_POINTS: usize = 128;

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

/// Write the state files into the run's `states/` directory (the traced states in parallel).
/// Returns the file of every row of [`NumericDiagram::rows`], in that order (empty where a
/// state could not be re-evaluated), and the warnings for those.
pub fn write_states(
    d: &NumericDiagram,
    opts: &DiagramOptions,
    run: &OutputRun,
) -> Result<(Vec<String>, Vec<String>)> {
    let dir = run.subdir("states")?;
    let jobs: Vec<(&TracedBranch, usize)> = d
        .branches
        .iter()
        .flat_map(|b| (0..b.points.len()).map(move |k| (b, k)))
        .collect();
    let (r, d0) = (opts.radius, opts.stiffness.reference());
    let one = |b: &TracedBranch, k: usize| -> Result<String> {
        let eq = b.equilibrium_of(opts, k)?;
        let m = STATE_POINTS.max(eq.model().cells());
        let table = crate::solve::config_table_in(&eq.profile_uniform(m)?, r, d0)?;
        let name = file_name(b, k);
        let file = name.trim_start_matches("states/");
        crate::output::write_atomic(&dir, file, &table.to_bytes()?)?;
        Ok(name)
    };
    let results = parallel_map(&jobs, |&(b, k)| one(b, k).map_err(|e| format!("{e:#}")));
    let mut names = Vec::with_capacity(jobs.len());
    let mut warnings = Vec::new();
    for ((b, k), res) in jobs.iter().zip(results) {
        match res {
            Ok(n) => names.push(n),
            Err(e) => {
                names.push(String::new());
                warnings.push(format!(
                    "state {k} of branch {} (L̄ = {}) has no state file: {e}",
                    b.branch, b.points[*k].value
                ));
            }
        }
    }
    Ok((names, warnings))
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
