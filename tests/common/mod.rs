//! Helpers shared by the end-to-end tests: running the built binary, fresh output
//! directories, reading what a run wrote (CSV tables, `summary.json`), and the generator
//! of the random scenes.
//! Each test file uses some of them.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Run the built binary.
pub fn rodloop(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_rodloop"))
        .args(args)
        .output()
        .expect("run rodloop")
}

/// A fresh directory under the target's temporary directory.
pub fn tmp(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// Run the built binary and require success (the arguments and stderr in the message).
pub fn rodloop_ok(args: &[&str]) -> Output {
    let o = rodloop(args);
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

/// The command fails with an error that contains `msg`, without a panic.
pub fn assert_refused(args: &[&str], msg: &str) {
    let r = rodloop(args);
    assert!(!r.status.success(), "{args:?}");
    let e = String::from_utf8_lossy(&r.stderr);
    assert!(e.contains(msg), "{args:?}: {e}");
    assert!(!e.contains("panicked"), "{e}");
}

/// The built binary as a command, for tests that add arguments, directories or inputs.
pub fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_rodloop"))
}

/// Run `cmd`: whether it succeeded, its stdout and its stderr.
pub fn run(cmd: &mut Command) -> (bool, String, String) {
    let o = cmd.output().expect("run rodloop");
    (
        o.status.success(),
        String::from_utf8_lossy(&o.stdout).into(),
        String::from_utf8_lossy(&o.stderr).into(),
    )
}

/// A fresh, existing directory `prefix-PID-name` under the system's temporary directory.
pub fn fresh_dir(prefix: &str, name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("{prefix}-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A CSV file without quoted fields as its header and rows of text (`#` lines are comments).
pub fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| l.split(',').map(String::from).collect())
        .collect();
    (header, rows)
}

/// The position of column `name` in `header`.
pub fn col(header: &[String], name: &str) -> usize {
    header
        .iter()
        .position(|h| h == name)
        .unwrap_or_else(|| panic!("no column {name} in {header:?}"))
}

/// A JSON file.
pub fn read_json(path: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The `summary.json` of an output directory.
pub fn summary(dir: &Path) -> serde_json::Value {
    read_json(&dir.join("summary.json"))
}

/// A small linear congruential generator (Knuth's MMIX constants): random scenes that are
/// the same on every machine.
pub struct Lcg(pub u64);

impl Lcg {
    /// The next number, uniform in `[0, 1)`.
    pub fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    /// The next number, uniform in `[lo, hi)`.
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
}
