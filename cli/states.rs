//! Every traced state of a numeric diagram as a loop table, `OUT/states/*.csv`, in the
//! columns of `solve`'s `config.csv`: any point of a diagram can be re-solved
//! (`solve --from OUT/states/FILE`) or drawn (`draw OUT/states/FILE`). The row of
//! `branches.csv` names its file in the column `state_file`. The rows come from
//! [`rodloop_diagram::state_rows`], the files are named by the engine's result
//! ([`rodloop_diagram::PointStates`]); this module writes them.

use anyhow::Result;
use rodloop_diagram::state_rows::{
    model_rows, result_rows, surface_rows, ENCLOSED_COLUMNS, NODE_COLUMN, SURFACE_COLUMNS,
};
use rodloop_diagram::{PointStates, StateTable};

use crate::output::{Cell, OutputRun, Table};

/// Write the state of every point of `schema` that `states` keeps into the run's `states/`
/// directory (in parallel), in the columns of `solve`'s `config.csv` (units of the scene's `r`
/// and `d0`), and name each file in its point's `state_file` (empty where the point has no
/// verified state or its file could not be written). Returns the warnings for those that
/// could not be written.
pub fn write_point_states(
    states: &(impl PointStates + ?Sized),
    schema: &mut rodloop_schema::Diagram,
    r: f64,
    d0: f64,
    run: &OutputRun,
) -> Result<Vec<String>> {
    let dir = run.subdir("states")?;
    let points = states.point_states();
    let stager = run.stager();
    let results = rodloop_diagram::parallel_map(&points, |state| {
        let Some(state) = state else {
            return Ok(String::new());
        };
        let table = state
            .table(r, d0)
            .map_err(|e| StateError::Rows(format!("{e:#}")))?;
        let write = || -> Result<()> {
            let bytes = state_table(&table)?.to_bytes()?;
            stager.write(&dir, state.name.trim_start_matches("states/"), &bytes)?;
            Ok(())
        };
        write().map_err(|e| {
            StateError::Write(format!("{} could not be written: {e:#}", state.name))
        })?;
        Ok(state.name.clone())
    });
    let mut warnings = Vec::new();
    for (p, res) in schema.points.iter_mut().zip(results) {
        p.state_file = Some(match res {
            Ok(name) => name,
            Err(StateError::Rows(e)) => {
                warnings.push(format!(
                    "the state of branch {} family {} at L̄ = {} has no state file: {e}",
                    p.branch,
                    p.family.unwrap_or(0),
                    p.coords.first().map_or(String::new(), f64::to_string)
                ));
                String::new()
            }
            Err(StateError::Write(w)) => {
                warnings.push(w);
                String::new()
            }
        });
    }
    Ok(warnings)
}

/// Why a state has no file.
enum StateError {
    /// Its rows could not be made.
    Rows(String),
    /// Its file could not be written.
    Write(String),
}

/// The `config.csv` table of a state ([`StateTable`]; its integer column as integers).
fn state_table(t: &StateTable) -> Result<Table> {
    rows_table(t.columns, &t.rows, t.integer_column)
}

/// A `config.csv` table of `rows` in `columns`, the column `integer` (if any) as integers:
/// the one builder of every state table.
fn rows_table(columns: &[&str], rows: &[[f64; 12]], integer: Option<usize>) -> Result<Table> {
    let mut table = Table::new("config.csv", columns);
    for row in rows {
        table.push(
            row.iter()
                .enumerate()
                .map(|(i, &x)| {
                    if Some(i) == integer {
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
    rows_table(&SURFACE_COLUMNS, &surface_rows(profile, r, d0), None)
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

/// The enclosed `config.csv` table of a 3-D state ([`model_rows`]).
pub fn model_table(st: &rodloop_solver::enclosed::EnclosedState, r: f64, d0: f64) -> Result<Table> {
    rows_table(
        &ENCLOSED_COLUMNS,
        &model_rows(st, r, d0)?,
        Some(NODE_COLUMN),
    )
}

/// The enclosed `config.csv` table of a solve's result ([`result_rows`]).
pub fn result_table(
    res: &rodloop_diagram::enclosed_state::EnclosedResult,
    r: f64,
    d0: f64,
) -> Result<Table> {
    rows_table(
        &ENCLOSED_COLUMNS,
        &result_rows(res, r, d0)?,
        Some(NODE_COLUMN),
    )
}
