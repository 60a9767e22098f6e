//! The branch files of a surface diagram ([`BranchFiles`]): each traced branch saved to
//! `DIR/branches/branch-B.json` (B the paper's branch number; a family of a non-uniform rod
//! in `branch-B-family-F-sheet-S.json`, its families in `families-branch-B.json`, written
//! after every sheet file of the branch: its presence means the branch is complete) as soon
//! as it is traced, so that an interrupted run continues from the branches already there
//! (files of older versions, `eta-N.json`, are read too).

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::compute::{BranchHook, Origin};
use crate::families::Families;
use crate::{BoxError, DiagramError, TracedBranch};

/// File name prefix of the per-branch families files of non-uniform rods.
const FAMILIES_PREFIX: &str = "families-";

/// What [`BranchFiles`] reports as it saves and resumes branches (for progress lines).
#[derive(Clone, Debug, PartialEq)]
pub enum BranchFileEvent {
    /// A branch taken from its file with this many states.
    Resumed {
        /// Paper branch.
        branch: u32,
        /// Its states.
        states: usize,
    },
    /// A branch traced and saved (every family and sheet of a non-uniform rod's branch).
    Traced {
        /// Paper branch.
        branch: u32,
        /// Its families.
        families: usize,
        /// Its sheets.
        sheets: usize,
        /// Its states.
        states: usize,
        /// Its wall time (every sheet carries the branch's).
        seconds: f64,
    },
    /// One sheet of a non-uniform rod's branch saved (the branch is reported when all are).
    SheetSaved {
        /// Paper branch.
        branch: u32,
        /// Family.
        family: u32,
        /// Sheet.
        sheet: u32,
    },
}

/// The [`BranchHook`] of a diagram directory: resumes from the branch files under
/// `DIR/branches` and saves each branch as soon as it is ready, reporting each to `event`.
pub struct BranchFiles<'a> {
    dir: PathBuf,
    previous: Vec<TracedBranch>,
    resuming: bool,
    event: Box<dyn Fn(BranchFileEvent) + 'a>,
}

impl<'a> BranchFiles<'a> {
    /// The branch files of the diagram directory `out` (in `out/branches`, which must exist
    /// when the first branch is saved), with the branches of an interrupted run when
    /// `resume` (a fresh run reads none); events go nowhere until [`BranchFiles::on_event`].
    pub fn open(out: &Path, resume: bool) -> Result<Self, DiagramError> {
        Ok(Self {
            dir: out.join("branches"),
            previous: if resume {
                load_resume(out)?
            } else {
                Vec::new()
            },
            resuming: resume,
            event: Box::new(|_| {}),
        })
    }

    /// Report every save and resume to `event`.
    pub fn on_event(&mut self, event: impl Fn(BranchFileEvent) + 'a) {
        self.event = Box::new(event);
    }
}

/// The branches of an interrupted run (`DIR/branches/*.json`, families files aside).
fn load_resume(dir: &Path) -> Result<Vec<TracedBranch>, DiagramError> {
    let context = |what: String| move |e: BoxError| DiagramError::Context { what, source: e };
    let bdir = dir.join("branches");
    let mut out = Vec::new();
    let Ok(entries) = std::fs::read_dir(&bdir) else {
        return Ok(out);
    };
    for e in entries {
        let path = e.map_err(|e| DiagramError::Passed(Box::new(e)))?.path();
        let families_file = path
            .file_name()
            .is_some_and(|n| n.to_string_lossy().starts_with(FAMILIES_PREFIX));
        if path.extension().is_some_and(|x| x == "json") && !families_file {
            let text = std::fs::read_to_string(&path)
                .map_err(|e| context(format!("cannot read {}", path.display()))(Box::new(e)))?;
            let b: TracedBranch = serde_json::from_str(&text).map_err(|e| {
                context(format!(
                    "{} is not a branch file of this rodloop version",
                    path.display()
                ))(Box::new(e))
            })?;
            out.push(b);
        }
    }
    Ok(out)
}

/// Write `bytes` to `dir/name` through a temporary file renamed into place (no partial file
/// on any exit path).
fn write_atomic(dir: &Path, name: &str, bytes: &[u8]) -> Result<(), BoxError> {
    let target = dir.join(name);
    let tmp = dir.join(format!(".{name}.{}.tmp", std::process::id()));
    let result = (|| -> Result<(), BoxError> {
        let mut f = std::fs::File::create(&tmp)
            .map_err(|e| format!("cannot create {}: {e}", tmp.display()))?;
        f.write_all(bytes)
            .map_err(|e| format!("cannot write {}: {e}", tmp.display()))?;
        f.sync_all().ok();
        drop(f);
        std::fs::rename(&tmp, &target)
            .map_err(|e| format!("cannot move {} to {}: {e}", tmp.display(), target.display()))?;
        Ok(())
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

impl BranchHook for BranchFiles<'_> {
    fn resume(&mut self, eta: u32) -> Option<TracedBranch> {
        self.previous.iter().find(|b| b.eta == eta).cloned()
    }

    fn resume_families(&mut self, eta: u32) -> Option<Families> {
        if !self.resuming {
            return None;
        }
        let branch = rodloop_exact::branch_of_eta(eta);
        let path = self
            .dir
            .join(format!("{FAMILIES_PREFIX}branch-{branch}.json"));
        let text = std::fs::read_to_string(path).ok()?;
        serde_json::from_str(&text).ok()
    }

    fn finished_families(&mut self, eta: u32, families: &Families) -> Result<(), BoxError> {
        let branch = rodloop_exact::branch_of_eta(eta);
        let text = serde_json::to_string(families)?;
        write_atomic(
            &self.dir,
            &format!("{FAMILIES_PREFIX}branch-{branch}.json"),
            text.as_bytes(),
        )?;
        // One event per branch: its families and sheets are parts of it.
        (self.event)(traced(branch, &families.sheets));
        Ok(())
    }

    fn finished(&mut self, b: &TracedBranch, origin: Origin) -> Result<(), BoxError> {
        if origin == Origin::Resumed {
            (self.event)(BranchFileEvent::Resumed {
                branch: b.branch,
                states: b.points.len(),
            });
            return Ok(());
        }
        let text = serde_json::to_string(b)?;
        // A non-uniform rod's branch has several families and sheets, one file each.
        let name = if b.family == 0 {
            format!("branch-{}.json", b.branch)
        } else {
            format!(
                "branch-{}-family-{}-sheet-{}.json",
                b.branch, b.family, b.sheet
            )
        };
        write_atomic(&self.dir, &name, text.as_bytes())?;
        // The file name of older versions (by eta) is superseded.
        let _ = std::fs::remove_file(self.dir.join(format!("eta-{}.json", b.eta)));
        if b.family == 0 {
            (self.event)(traced(b.branch, std::slice::from_ref(b)));
        } else {
            // A sheet of a non-uniform rod's branch: the branch's event comes with
            // `finished_families`, once all its sheets are written.
            (self.event)(BranchFileEvent::SheetSaved {
                branch: b.branch,
                family: b.family,
                sheet: b.sheet,
            });
        }
        Ok(())
    }
}

/// The event of a traced branch made of `sheets`.
fn traced(branch: u32, sheets: &[TracedBranch]) -> BranchFileEvent {
    BranchFileEvent::Traced {
        branch,
        families: sheets
            .iter()
            .map(|b| b.family)
            .collect::<std::collections::BTreeSet<_>>()
            .len(),
        sheets: sheets.len(),
        states: sheets.iter().map(|b| b.points.len()).sum(),
        seconds: sheets.iter().map(|b| b.seconds).fold(0.0, f64::max),
    }
}
