//! Output helpers: every file is written to a temporary name in the target directory and
//! renamed into place (or, in a run's staging directory, written there and synced before the
//! run moves it into place), and no non-finite number is ever written.

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

use crate::staging::{Stager, Syncer};

/// Create the output directory (and parents).
pub fn ensure_dir(dir: &Path) -> Result<()> {
    fs::create_dir_all(dir)
        .with_context(|| format!("cannot create output directory {}", dir.display()))
}

/// Write `bytes` to `dir/name` atomically (temporary file + rename).
pub fn write_atomic(dir: &Path, name: &str, bytes: &[u8]) -> Result<PathBuf> {
    let target = dir.join(name);
    let tmp = dir.join(format!(".{name}.{}.tmp", std::process::id()));
    let result = (|| -> Result<()> {
        let mut f =
            fs::File::create(&tmp).with_context(|| format!("cannot create {}", tmp.display()))?;
        f.write_all(bytes)
            .with_context(|| format!("cannot write {}", tmp.display()))?;
        f.sync_all().ok();
        drop(f);
        fs::rename(&tmp, &target)
            .with_context(|| format!("cannot move {} to {}", tmp.display(), target.display()))
    })();
    if result.is_err() {
        // No temporary file is left behind on any exit path.
        let _ = fs::remove_file(&tmp);
    }
    result.map(|()| target)
}

/// A CSV table held in memory until it is complete and checked: its rows are encoded as
/// they are pushed (each cell written once, no per-cell allocation), the header is put in
/// front when the bytes are taken.
pub struct Table {
    header: Vec<String>,
    /// The CSV encoding of the rows pushed so far.
    rows: csv::Writer<Vec<u8>>,
    /// Rows pushed so far.
    count: usize,
    name: String,
    /// Buffer of the cell being written.
    cell: String,
}

/// One cell of a CSV row.
pub enum Cell {
    /// A floating-point value (must be finite).
    F(f64),
    /// An integer.
    I(i64),
    /// Text.
    S(String),
}

impl Table {
    /// New table called `name` (used in error messages) with the given columns.
    pub fn new(name: &str, header: &[&str]) -> Self {
        Self {
            header: header.iter().map(|s| s.to_string()).collect(),
            rows: csv::Writer::from_writer(Vec::new()),
            count: 0,
            name: name.to_string(),
            cell: String::with_capacity(32),
        }
    }

    /// Append a row; fails on a non-finite number or a wrong column count (and then leaves
    /// the table as it was).
    pub fn push(&mut self, row: Vec<Cell>) -> Result<()> {
        use std::fmt::Write as _;
        if row.len() != self.header.len() {
            bail!(
                "internal error: {} row has {} cells, header has {}",
                self.name,
                row.len(),
                self.header.len()
            );
        }
        for (cell, col) in row.iter().zip(&self.header) {
            if let Cell::F(v) = cell {
                if !v.is_finite() {
                    bail!(
                        "{}: column {col} would hold a non-finite value ({v}) in row {}; nothing was written",
                        self.name,
                        self.count + 1
                    );
                }
            }
        }
        for cell in &row {
            // Numbers in their shortest round-trip form (as `{}` writes them), text as given.
            let field: &str = match cell {
                Cell::F(v) => {
                    self.cell.clear();
                    crate::decimal::push_f64(&mut self.cell, *v);
                    &self.cell
                }
                Cell::I(v) => {
                    self.cell.clear();
                    write!(self.cell, "{v}")?;
                    &self.cell
                }
                Cell::S(s) => s,
            };
            self.rows.write_field(field)?;
        }
        self.rows.write_record(None::<&[u8]>)?;
        // Into the vector, so that `to_bytes` reads every row pushed.
        self.rows.flush()?;
        self.count += 1;
        Ok(())
    }

    /// Serialise to CSV bytes.
    pub fn to_bytes(&self) -> Result<Vec<u8>> {
        let mut w = csv::Writer::from_writer(Vec::new());
        w.write_record(&self.header)?;
        let mut out = w.into_inner().context("csv buffer")?;
        out.extend_from_slice(self.rows.get_ref());
        Ok(out)
    }
}

/// Drop the keys whose value is `null` from a JSON summary ([`rodloop_schema::strip_nulls`]):
/// a summary must only hold numbers checked with [`check_finite`] first.
pub fn strip_nulls(v: serde_json::Value) -> serde_json::Value {
    rodloop_schema::strip_nulls(v)
}

/// Stage the files of a diagram in the result schema (`branches.csv`, `critical.csv`,
/// `special_points.csv`, `summary.json` with this run's id): the one writer of every diagram
/// ([`rodloop_schema::Diagram::files`]; nothing is staged if any number is not finite).
pub fn write_diagram(run: &OutputRun, d: &mut rodloop_schema::Diagram) -> Result<()> {
    d.run_id = Some(run.run_id().to_string());
    for (name, bytes) in d.files()? {
        run.write_bytes(&name, &bytes)?;
    }
    Ok(())
}

/// Stage the `summary.json` of a run in the result schema whose tables are its own (`phase`,
/// `diagram --param`): [`rodloop_schema::Diagram::summary_json`] with this run's id.
pub fn write_summary(run: &OutputRun, d: &mut rodloop_schema::Diagram) -> Result<()> {
    d.run_id = Some(run.run_id().to_string());
    run.write_bytes("summary.json", &d.summary_json()?)
}

/// Check that a typed value holds no non-finite float anywhere (fields, vectors, options),
/// before it is turned into JSON; `what` names it in the error.
pub fn check_finite<T: serde::Serialize + ?Sized>(what: &str, value: &T) -> Result<()> {
    rodloop_schema::check_finite(value)
        .map_err(|e| anyhow::anyhow!("{what}: {e}; nothing was written"))
}

/// A JSON object like `serde_json::json!({"key": value, …})` (flat, string-literal keys),
/// except that each value is first checked with [`check_finite`] on its typed form.
/// Evaluates to `anyhow::Result<serde_json::Value>`.
macro_rules! checked_json {
    ({ $($key:literal : $val:expr),* $(,)? }) => {
        (|| -> anyhow::Result<serde_json::Value> {
            #[allow(unused_mut)]
            let mut map = serde_json::Map::new();
            $(
                {
                    let v = &$val;
                    $crate::output::check_finite(concat!("summary value ", $key), v)?;
                    map.insert($key.to_string(), serde_json::to_value(v)?);
                }
            )*
            Ok(serde_json::Value::Object(map))
        })()
    };
}
pub(crate) use checked_json;

/// Singular or plural: `1 period`, `2 periods`, `3 branches`.
pub fn plural(n: impl Into<u64>, word: &str) -> String {
    let n = n.into();
    if n == 1 {
        format!("1 {word}")
    } else if let Some(stem) = word
        .strip_suffix('y')
        .filter(|s| !s.ends_with(['a', 'e', 'o', 'u']))
    {
        format!("{n} {stem}ies")
    } else if word.ends_with("ch") || word.ends_with('s') {
        format!("{n} {word}es")
    } else {
        format!("{n} {word}s")
    }
}

/// Check a normalised length given on the command line.
pub fn check_lbar(lbar: f64) -> Result<()> {
    if !lbar.is_finite() {
        bail!("lbar must be a finite number (got {lbar})");
    }
    if lbar <= 0.0 {
        bail!("lbar must be positive (got {lbar})");
    }
    Ok(())
}

/// Names of every file a rodloop command writes into its output directory (and `loop-NN.csv`,
/// and the pictures `--draw` writes beside `config.csv`, `curve.csv`, `loop-NN.csv`):
/// a run removes those of a previous run that it does not write itself, so that a directory
/// never mixes the outputs of two runs (e.g. a stale `diagram_g.svg` after switching model).
const KNOWN_OUTPUTS: &[&str] = &[
    "config.csv",
    "summary.json",
    "branches.csv",
    "critical.csv",
    "special_points.csv",
    "diagram.svg",
    "diagram_g.svg",
    "diagram_g.png",
    "curve.csv",
    "compare.csv",
    "report.html",
    "atlas.svg",
    "atlas.png",
    "diagram_k2.svg",
    "diagram_k2.png",
    "diagram.png",
    "diagram_split.svg",
    "diagram_split.png",
    "diagram_lambda.svg",
    "diagram_lambda.png",
    "converge.csv",
    "converge.svg",
    "converge.png",
    "phase.csv",
    "phase.svg",
    "phase.png",
];

/// Subdirectories a rodloop command writes whole ([`OutputRun::subdir`]): a run that does not
/// write one removes that of a previous run.
const KNOWN_OUTPUT_DIRS: &[&str] = &["states", "atlas"];

fn is_known_output(name: &str) -> bool {
    let is_loop_stem = |stem: &str| {
        stem.strip_prefix("loop-")
            .is_some_and(|n| !n.is_empty() && n.chars().all(|c| c.is_ascii_digit()))
    };
    // The pictures `--draw` writes beside a loop table (`rodloop draw`: NAME.svg/.png,
    // NAME-profiles.svg/.png, NAME-draw.json), for the tables rodloop writes.
    let picture_of_table = [".svg", ".png", "-draw.json"]
        .iter()
        .find_map(|ext| name.strip_suffix(ext))
        .map(|stem| stem.strip_suffix("-profiles").unwrap_or(stem))
        .is_some_and(|stem| stem == "config" || stem == "curve" || is_loop_stem(stem));
    KNOWN_OUTPUTS.contains(&name)
        || name.strip_suffix(".csv").is_some_and(is_loop_stem)
        || picture_of_table
}

/// Whether `name` is a branch file the numeric diagram writes into `branches/` for
/// `--resume` (`branch-….json`, `families-branch-….json`, or `eta-N.json` of older versions).
pub fn is_branch_file(name: &str) -> bool {
    name.ends_with(".json")
        && (name.starts_with("branch-")
            || name.starts_with("families-branch-")
            || name.starts_with("eta-"))
}

/// Remove the branch files of `dir/branches` (only rodloop's own, [`is_branch_file`]) and the
/// folder itself when that leaves it empty.
pub fn remove_branch_files(dir: &Path) -> Result<()> {
    let bdir = dir.join("branches");
    let Ok(entries) = fs::read_dir(&bdir) else {
        return Ok(());
    };
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().to_string();
        if is_branch_file(&name) && e.path().is_file() {
            fs::remove_file(e.path())
                .with_context(|| format!("cannot remove stale output {}", e.path().display()))?;
        }
    }
    let _ = fs::remove_dir(&bdir);
    Ok(())
}

/// Name of the lock file that marks an output directory as in use.
pub const LOCK_NAME: &str = ".rodloop.lock";

/// Whether process `pid` is running (Linux: `/proc/PID`; elsewhere assumed running).
fn pid_alive(pid: u32) -> bool {
    if pid == std::process::id() {
        return true;
    }
    let proc_root = Path::new("/proc");
    if proc_root.join("self").exists() {
        proc_root.join(pid.to_string()).exists()
    } else {
        true
    }
}

/// One run's output set: the directory is locked (a lock file holding the pid), files are
/// written into a staging directory inside it and moved into place by [`OutputRun::commit`],
/// `summary.json` last and with the run id. Dropping a run that was not committed removes the
/// staging directory and the lock (and the directory itself if the run created it and it is
/// empty), so that an error leaves no temporary file and no partial set that looks complete.
pub struct OutputRun {
    dir: PathBuf,
    stage: PathBuf,
    lock: PathBuf,
    run_id: String,
    written: std::cell::RefCell<Vec<String>>,
    dirs: std::cell::RefCell<Vec<String>>,
    /// The run wrote `branches/` itself (the numeric diagram's files for `--resume`); any
    /// other run removes the branch files a previous run left there.
    keeps_branches: std::cell::Cell<bool>,
    committed: bool,
    /// Whether this run created `dir` (an uncommitted run then removes it if it is empty).
    created: bool,
    /// Syncs the files staged through [`OutputRun::stager`].
    syncer: Syncer,
}

impl OutputRun {
    /// Create and lock `dir`, clean what dead runs left behind (temporary files, staging
    /// directories, stale locks), and open a staging directory.
    pub fn begin(dir: &Path) -> Result<Self> {
        let created = !dir.exists();
        ensure_dir(dir)?;
        let lock = dir.join(LOCK_NAME);
        let me = std::process::id();
        let mut attempts = 0;
        loop {
            attempts += 1;
            match fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(&lock)
            {
                Ok(mut f) => {
                    f.write_all(format!("{me}\n").as_bytes())
                        .with_context(|| format!("cannot write {}", lock.display()))?;
                    break;
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists && attempts < 5 => {
                    let text = fs::read_to_string(&lock).unwrap_or_default();
                    match text.trim().parse::<u32>() {
                        Ok(pid) if pid_alive(pid) => bail!(
                            "output directory {} is in use by another rodloop run (process {pid}, lock file {}); wait for it to finish or choose another --out",
                            dir.display(),
                            lock.display()
                        ),
                        // A lock of a dead process (or an unreadable one being written right
                        // now: retry once it is complete).
                        Ok(_) => {
                            let _ = fs::remove_file(&lock);
                        }
                        Err(_) => std::thread::sleep(std::time::Duration::from_millis(50)),
                    }
                }
                Err(e) => {
                    return Err(e).with_context(|| {
                        format!(
                            "cannot lock output directory {} (lock file {}); if no rodloop run uses it, remove the lock file",
                            dir.display(),
                            lock.display()
                        )
                    })
                }
            }
        }
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.as_nanos())
            .unwrap_or(0);
        let run_id = format!("{nanos:x}-{me}");
        let stage = dir.join(format!(".staging-{run_id}"));
        let run = OutputRun {
            dir: dir.to_path_buf(),
            stage,
            lock,
            run_id,
            written: std::cell::RefCell::new(Vec::new()),
            dirs: std::cell::RefCell::new(Vec::new()),
            keeps_branches: std::cell::Cell::new(false),
            committed: false,
            created,
            syncer: Syncer::start(),
        };
        run.clean_leftovers();
        fs::create_dir(&run.stage)
            .with_context(|| format!("cannot create {}", run.stage.display()))?;
        Ok(run)
    }

    /// Remove temporaries and staging directories of dead runs (we hold the lock, so no live
    /// run owns them), here and in `branches/`.
    fn clean_leftovers(&self) {
        for d in [self.dir.clone(), self.dir.join("branches")] {
            let Ok(entries) = fs::read_dir(&d) else {
                continue;
            };
            for e in entries.flatten() {
                let name = e.file_name().to_string_lossy().to_string();
                let path = e.path();
                if name.starts_with(".staging-") && path.is_dir() {
                    let _ = fs::remove_dir_all(&path);
                } else if name.starts_with('.') && name.ends_with(".tmp") {
                    let _ = fs::remove_file(&path);
                }
            }
        }
    }

    /// A writer of files into the staging directory (e.g. into a [`OutputRun::subdir`]) that
    /// does not wait for the disk: [`OutputRun::commit`] waits for the files' syncs.
    pub fn stager(&self) -> Stager<'_> {
        self.syncer.stager()
    }

    /// Stage a file (staging the same name again replaces it).
    pub fn write_bytes(&self, name: &str, bytes: &[u8]) -> Result<()> {
        write_atomic(&self.stage, name, bytes)?;
        let mut written = self.written.borrow_mut();
        if !written.iter().any(|n| n == name) {
            written.push(name.to_string());
        }
        Ok(())
    }

    /// Stage a whole subdirectory `name` (one of `KNOWN_OUTPUT_DIRS`) and return its staging
    /// path; [`OutputRun::commit`] replaces the directory of that name with it.
    pub fn subdir(&self, name: &str) -> Result<PathBuf> {
        if !KNOWN_OUTPUT_DIRS.contains(&name) {
            bail!("internal error: {name} is not a known output directory");
        }
        let path = self.stage.join(name);
        ensure_dir(&path)?;
        let mut dirs = self.dirs.borrow_mut();
        if !dirs.iter().any(|n| n == name) {
            dirs.push(name.to_string());
        }
        Ok(path)
    }

    /// This run's outputs include `branches/` (written in place, for `--resume`).
    pub fn keep_branch_files(&self) {
        self.keeps_branches.set(true);
    }

    /// Record files that were written straight into the staging directory (e.g. figures
    /// drawn from the staged tables), so that [`OutputRun::commit`] moves them into place.
    pub fn record_staged(&self, names: &[String]) {
        let mut written = self.written.borrow_mut();
        for name in names {
            if !written.iter().any(|n| n == name) {
                written.push(name.clone());
            }
        }
    }

    /// The run id (`summary.json` carries it).
    pub fn run_id(&self) -> &str {
        &self.run_id
    }

    /// The staging directory: files staged so far can be read back from it before
    /// [`OutputRun::commit`], and scratch files written into it vanish with the run.
    pub fn stage_dir(&self) -> &Path {
        &self.stage
    }

    /// Stage a table.
    pub fn write_table(&self, table: &Table) -> Result<()> {
        self.write_bytes(&table.name, &table.to_bytes()?)
    }

    /// Stage a JSON summary (an object gets the key `run_id`).
    pub fn write_json(&self, name: &str, value: &serde_json::Value) -> Result<()> {
        let mut value = value.clone();
        if let serde_json::Value::Object(map) = &mut value {
            map.insert("run_id".into(), self.run_id.clone().into());
        }
        let text = serde_json::to_string_pretty(&value)?;
        self.write_bytes(name, format!("{text}\n").as_bytes())
    }

    /// Move the staged files into place: first the old `summary.json` and every output of a
    /// previous run that this run does not write are removed (and its subdirectories such as
    /// `states/`), then the new subdirectories and files are renamed in, `summary.json` last,
    /// so that a complete-looking set is always one run's.
    pub fn commit(mut self) -> Result<()> {
        self.syncer.finish();
        let mut names = self.written.borrow().clone();
        names.sort_by_key(|n| n == "summary.json");
        let _ = fs::remove_file(self.dir.join("summary.json"));
        if let Ok(entries) = fs::read_dir(&self.dir) {
            for e in entries.flatten() {
                let name = e.file_name().to_string_lossy().to_string();
                if is_known_output(&name) && !names.contains(&name) && e.path().is_file() {
                    fs::remove_file(e.path()).with_context(|| {
                        format!("cannot remove stale output {}", e.path().display())
                    })?;
                }
            }
        }
        if !self.keeps_branches.get() {
            remove_branch_files(&self.dir)?;
        }
        let dirs = self.dirs.borrow().clone();
        for name in KNOWN_OUTPUT_DIRS {
            let old = self.dir.join(name);
            if old.is_dir() {
                fs::remove_dir_all(&old)
                    .with_context(|| format!("cannot remove stale output {}", old.display()))?;
            }
        }
        for name in dirs.iter().chain(&names) {
            let (from, to) = (self.stage.join(name), self.dir.join(name));
            fs::rename(&from, &to)
                .with_context(|| format!("cannot move {} to {}", from.display(), to.display()))?;
        }
        self.committed = true;
        Ok(())
    }
}

impl Drop for OutputRun {
    fn drop(&mut self) {
        self.syncer.finish();
        let _ = fs::remove_dir_all(&self.stage);
        let ours = fs::read_to_string(&self.lock)
            .ok()
            .and_then(|t| t.trim().parse::<u32>().ok())
            == Some(std::process::id());
        if ours {
            let _ = fs::remove_file(&self.lock);
        }
        // A failed run into a directory it created leaves no empty directory behind
        // (`remove_dir` keeps a directory that holds anything, e.g. `branches/` for --resume).
        if !self.committed && self.created {
            let _ = fs::remove_dir(&self.dir);
        }
    }
}

/// Default cap on `--points` (sampled points per curve); the environment variable
/// `RODLOOP_MAX_POINTS` raises or lowers it.
pub const MAX_POINTS: u64 = 1_000_000;

/// Check `--points`: at least 8, at most the cap (so that a huge value is a clear error, not an
/// allocation failure).
pub fn check_points(points: u64) -> Result<usize> {
    let cap = std::env::var("RODLOOP_MAX_POINTS")
        .ok()
        .and_then(|v| v.trim().parse::<u64>().ok())
        .unwrap_or(MAX_POINTS);
    if points < 8 {
        bail!("--points must be at least 8 (got {points})");
    }
    if points > cap {
        bail!(
            "--points {points} is above the cap of {cap} points (each point is a CSV row of about 200 bytes); set the environment variable RODLOOP_MAX_POINTS to raise the cap"
        );
    }
    usize::try_from(points)
        .map_err(|_| anyhow::anyhow!("--points {points} does not fit this machine"))
}

#[cfg(test)]
mod tests {
    use super::{Cell, Table};

    /// A table's bytes are those of the `csv` crate writing its header and rows as the
    /// strings `{}` makes of the cells (text quoted where CSV needs it); a row with a
    /// non-finite number is refused and leaves the table as it was.
    #[test]
    fn table_bytes_are_the_csv_of_the_formatted_cells() {
        let rows: Vec<(f64, i64, &str)> = vec![
            (0.1 + 0.2, -3, "plain"),
            (1.370818474960669e-8, 0, "a, b"),
            (-2.5e300, i64::MAX, "say \"x\""),
            (5e-324, 7, ""),
        ];
        let mut t = Table::new("t.csv", &["v", "k", "text"]);
        for &(v, k, s) in &rows {
            t.push(vec![Cell::F(v), Cell::I(k), Cell::S(s.into())])
                .unwrap();
        }
        let err = t
            .push(vec![Cell::F(f64::NAN), Cell::I(1), Cell::S("x".into())])
            .unwrap_err();
        assert!(err.to_string().contains("row 5"), "{err}");
        assert!(t.push(vec![Cell::I(1)]).is_err());
        let mut w = csv::Writer::from_writer(Vec::new());
        w.write_record(["v", "k", "text"]).unwrap();
        for &(v, k, s) in &rows {
            w.write_record([v.to_string(), k.to_string(), s.to_string()])
                .unwrap();
        }
        let want = w.into_inner().unwrap();
        assert_eq!(t.to_bytes().unwrap(), want);
        assert!(String::from_utf8(want).unwrap().contains("\"a, b\""));
    }
}
