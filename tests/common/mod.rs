//! Helpers shared by the end-to-end tests of `phase` and `diagram --param`.

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

/// The command fails with an error that contains `msg`, without a panic.
pub fn assert_refused(args: &[&str], msg: &str) {
    let r = rodloop(args);
    assert!(!r.status.success(), "{args:?}");
    let e = String::from_utf8_lossy(&r.stderr);
    assert!(e.contains(msg), "{args:?}: {e}");
    assert!(!e.contains("panicked"), "{e}");
}
