//! Output helpers: every file is written to a temporary name in the target directory and
//! renamed into place, and no non-finite number is ever written.

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

/// Create the output directory (and parents).
pub fn ensure_dir(dir: &Path) -> Result<()> {
    fs::create_dir_all(dir)
        .with_context(|| format!("cannot create output directory {}", dir.display()))
}

/// Write `bytes` to `dir/name` atomically (temporary file + rename).
pub fn write_atomic(dir: &Path, name: &str, bytes: &[u8]) -> Result<PathBuf> {
    let target = dir.join(name);
    let tmp = dir.join(format!(".{name}.{}.tmp", std::process::id()));
    {
        let mut f =
            fs::File::create(&tmp).with_context(|| format!("cannot create {}", tmp.display()))?;
        f.write_all(bytes)
            .with_context(|| format!("cannot write {}", tmp.display()))?;
        f.sync_all().ok();
    }
    fs::rename(&tmp, &target)
        .with_context(|| format!("cannot move {} to {}", tmp.display(), target.display()))?;
    Ok(target)
}

/// A CSV table held in memory until it is complete and checked.
pub struct Table {
    header: Vec<String>,
    rows: Vec<Vec<String>>,
    name: String,
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
            rows: Vec::new(),
            name: name.to_string(),
        }
    }

    /// Append a row; fails on a non-finite number or a wrong column count.
    pub fn push(&mut self, row: Vec<Cell>) -> Result<()> {
        if row.len() != self.header.len() {
            bail!(
                "internal error: {} row has {} cells, header has {}",
                self.name,
                row.len(),
                self.header.len()
            );
        }
        let mut out = Vec::with_capacity(row.len());
        for (cell, col) in row.into_iter().zip(&self.header) {
            out.push(match cell {
                Cell::F(v) => {
                    if !v.is_finite() {
                        bail!(
                            "{}: column {col} would hold a non-finite value ({v}) in row {}; nothing was written",
                            self.name,
                            self.rows.len() + 1
                        );
                    }
                    format!("{v}")
                }
                Cell::I(v) => v.to_string(),
                Cell::S(s) => s,
            });
        }
        self.rows.push(out);
        Ok(())
    }

    /// Serialise to CSV bytes.
    pub fn to_bytes(&self) -> Result<Vec<u8>> {
        let mut w = csv::Writer::from_writer(Vec::new());
        w.write_record(&self.header)?;
        for r in &self.rows {
            w.write_record(r)?;
        }
        w.into_inner().context("csv buffer")
    }

    /// Write atomically to `dir/name`.
    pub fn write(&self, dir: &Path) -> Result<PathBuf> {
        write_atomic(dir, &self.name, &self.to_bytes()?)
    }
}

/// Serialise a JSON value after checking that it holds no non-finite number (serde_json
/// would write them as `null`), then write it atomically.
pub fn write_json(dir: &Path, name: &str, value: &serde_json::Value) -> Result<PathBuf> {
    let text = serde_json::to_string_pretty(value)?;
    if text.contains("null") {
        bail!("{name}: a value is not finite (would be written as null); nothing was written");
    }
    write_atomic(dir, name, format!("{text}\n").as_bytes())
}

/// Drop the keys whose value is `null` from a JSON summary: they stand for absent optional
/// values (`None`). Note that serde_json also turns a non-finite float into `null`, so a
/// summary must only hold numbers that were checked elsewhere: every command writes its
/// numbers to a CSV table first ([`Table::push`] rejects non-finite values) or derives them
/// from those.
pub fn strip_nulls(v: serde_json::Value) -> serde_json::Value {
    match v {
        serde_json::Value::Object(map) => serde_json::Value::Object(
            map.into_iter()
                .filter(|(_, v)| !v.is_null())
                .map(|(k, v)| (k, strip_nulls(v)))
                .collect(),
        ),
        serde_json::Value::Array(a) => {
            serde_json::Value::Array(a.into_iter().map(strip_nulls).collect())
        }
        other => other,
    }
}

/// One row of `critical.csv`, the same columns for the exact and the numeric model.
pub struct CriticalRow {
    /// Index `i` of `L̄_icr`.
    pub index: usize,
    /// The critical length.
    pub lbar_cr: f64,
    /// Crossing or collapse.
    pub kind: rodloop_exact::diagram::CriticalKind,
    /// Lowest branch below.
    pub from_branch: u32,
    /// Lowest branch above.
    pub to_branch: u32,
    /// Energy at the critical length.
    pub energy: f64,
    /// Estimated error of `lbar_cr`.
    pub error_estimate: f64,
}

/// The `critical.csv` table.
pub fn critical_table(rows: impl IntoIterator<Item = CriticalRow>) -> Result<Table> {
    let mut t = Table::new(
        "critical.csv",
        &[
            "index",
            "lbar_cr",
            "kind",
            "from_branch",
            "to_branch",
            "energy",
            "error_estimate",
        ],
    );
    for c in rows {
        t.push(vec![
            Cell::I(c.index as i64),
            Cell::F(c.lbar_cr),
            Cell::S(c.kind.to_string()),
            Cell::I(c.from_branch.into()),
            Cell::I(c.to_branch.into()),
            Cell::F(c.energy),
            Cell::F(c.error_estimate),
        ])?;
    }
    Ok(t)
}
