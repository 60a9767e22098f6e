//! Counters of the enclosed Newton solves ([`super::solve_enclosed`]) by stage of a caller:
//! solves attempted, converged and failed (by why they stopped), Newton iterations and the
//! time spent in them. A caller opens a [`scope`] with its own [`SolveStats`] on each thread
//! that works for it and names the stage it is in with [`stage`]; every solve on that thread
//! adds to the stage's counts. Outside a scope nothing is recorded.
//!
//! The counts say where a computation spends its solves, in particular how many of them fail
//! and how many iterations the failures cost (a failing solve ends at the iteration cap, a
//! stall window or a failed line search).

use std::cell::RefCell;
use std::sync::{Arc, Mutex};
use std::time::Instant;

use serde::Serialize;

/// A stage of an enclosed computation, for [`SolveStats`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Stage {
    /// Anything not named below.
    Other,
    /// Lifted-off states solved from a surface loop (the seeds of traces).
    Seed,
    /// Natural-parameter steps of a trace.
    Trace,
    /// A stuck trace's retries: the plain step straight to the target and the jump past it.
    Retry,
    /// A stuck trace resumed with shorter steps (creep).
    Creep,
    /// States found by continuation in the stiffness (non-uniform rods).
    StiffnessPath,
    /// Lower states below unstable ones (descent along the unstable direction).
    Descent,
    /// Exchanges located on re-solved states.
    Exchange,
    /// Lift-off and landing events.
    Event,
    /// States solved after the diagram (certificate, atlas).
    After,
}

impl Stage {
    /// The stage's name (`snake_case`, as serialised).
    pub fn name(self) -> &'static str {
        match self {
            Stage::Other => "other",
            Stage::Seed => "seed",
            Stage::Trace => "trace",
            Stage::Retry => "retry",
            Stage::Creep => "creep",
            Stage::StiffnessPath => "stiffness_path",
            Stage::Descent => "descent",
            Stage::Exchange => "exchange",
            Stage::Event => "event",
            Stage::After => "after",
        }
    }
}

/// The counts of one stage.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct StageCounts {
    /// Solves started.
    pub attempted: u64,
    /// Solves that converged.
    pub converged: u64,
    /// Solves that failed: at the iteration cap.
    pub failed_cap: u64,
    /// Solves that failed: the stall window ([`super::EnclosedOptions::stall_window`]).
    pub failed_stall: u64,
    /// Solves that failed: the line search found no decrease, or the residual became
    /// non-finite, or the model refused the iterate.
    pub failed_other: u64,
    /// Newton iterations of the converged solves.
    pub iterations: u64,
    /// Newton iterations of the failed solves.
    pub failed_iterations: u64,
    /// Newton steps that fell back to the dense LU (the block factorisation refused).
    pub dense_steps: u64,
    /// Seconds in the converged solves (summed over threads).
    pub seconds: f64,
    /// Seconds in the failed solves (summed over threads).
    pub failed_seconds: f64,
}

impl StageCounts {
    /// Solves that failed.
    pub fn failed(&self) -> u64 {
        self.failed_cap + self.failed_stall + self.failed_other
    }

    fn add(&mut self, o: &StageCounts) {
        self.attempted += o.attempted;
        self.converged += o.converged;
        self.failed_cap += o.failed_cap;
        self.failed_stall += o.failed_stall;
        self.failed_other += o.failed_other;
        self.iterations += o.iterations;
        self.failed_iterations += o.failed_iterations;
        self.dense_steps += o.dense_steps;
        self.seconds += o.seconds;
        self.failed_seconds += o.failed_seconds;
    }
}

/// Why a solve ended (for [`record`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Outcome {
    Converged,
    Cap,
    Stall,
    Other,
}

/// Counters shared by the threads of one computation.
#[derive(Debug, Default)]
pub struct SolveStats {
    counts: Mutex<Vec<(Stage, StageCounts)>>,
}

impl SolveStats {
    /// An empty set of counters.
    pub fn new() -> Arc<Self> {
        Arc::new(Self::default())
    }

    fn add(&self, stage: Stage, c: &StageCounts) {
        let mut v = self.counts.lock().unwrap_or_else(|e| e.into_inner());
        match v.iter_mut().find(|(s, _)| *s == stage) {
            Some((_, t)) => t.add(c),
            None => v.push((stage, *c)),
        }
    }

    /// The counts by stage (stages without a solve left out), in the order of [`Stage`].
    pub fn snapshot(&self) -> Vec<(Stage, StageCounts)> {
        let mut v = self
            .counts
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .clone();
        v.sort_by_key(|(s, _)| *s);
        v
    }
}

thread_local! {
    static CURRENT: RefCell<Option<(Arc<SolveStats>, Stage)>> = const { RefCell::new(None) };
}

/// Run `f` with the solves of this thread counted in `stats` under `stage` (the previous
/// scope, if any, is restored afterwards).
pub fn scope<R>(stats: &Arc<SolveStats>, stage: Stage, f: impl FnOnce() -> R) -> R {
    let prev = CURRENT.with(|c| c.borrow_mut().replace((stats.clone(), stage)));
    let out = f();
    CURRENT.with(|c| *c.borrow_mut() = prev);
    out
}

/// The current thread's scope (counters and stage), to be reopened on worker threads with
/// [`within`].
pub type Handle = Option<(Arc<SolveStats>, Stage)>;

/// The current thread's scope ([`Handle`]; `None` outside a scope).
pub fn current() -> Handle {
    CURRENT.with(|c| c.borrow().clone())
}

/// Run `f` in the scope `h` (taken by [`current`] on another thread); without one, `f` runs
/// uncounted.
pub fn within<R>(h: &Handle, f: impl FnOnce() -> R) -> R {
    match h {
        Some((stats, stage)) => scope(stats, *stage, f),
        None => f(),
    }
}

/// Open the scope `h` (taken by [`current`] on another thread) on this thread until the
/// guard is dropped, then the thread's previous scope again; without one, nothing changes.
pub fn reopen(h: &Handle) -> ScopeGuard {
    let prev = h
        .as_ref()
        .map(|open| CURRENT.with(|c| c.borrow_mut().replace(open.clone())));
    ScopeGuard { prev }
}

/// The guard of [`reopen`].
#[must_use = "the scope ends when the guard is dropped"]
pub struct ScopeGuard {
    /// `Some(previous scope)` where a scope was opened.
    prev: Option<Handle>,
}

impl Drop for ScopeGuard {
    fn drop(&mut self) {
        if let Some(p) = self.prev.take() {
            CURRENT.with(|c| *c.borrow_mut() = p);
        }
    }
}

/// Count the solves of this thread under `stage` in the current scope's counters until the
/// guard is dropped (then the previous stage again; nothing is counted outside a scope).
pub fn enter(stage: Stage) -> StageGuard {
    let prev = CURRENT.with(|c| {
        let mut c = c.borrow_mut();
        let prev = c.as_ref().map(|(_, s)| *s);
        if let Some((_, s)) = c.as_mut() {
            *s = stage;
        }
        prev
    });
    StageGuard { prev }
}

/// The guard of [`enter`].
#[must_use = "the stage ends when the guard is dropped"]
pub struct StageGuard {
    prev: Option<Stage>,
}

impl Drop for StageGuard {
    fn drop(&mut self) {
        if let Some(p) = self.prev {
            CURRENT.with(|c| {
                if let Some((_, s)) = c.borrow_mut().as_mut() {
                    *s = p;
                }
            });
        }
    }
}

/// Run `f` with the solves of this thread counted under `stage` in the current scope's
/// counters (nothing is counted outside a scope).
pub fn stage<R>(stage: Stage, f: impl FnOnce() -> R) -> R {
    let _guard = enter(stage);
    f()
}

/// Whether this thread counts its solves (a [`scope`] is open).
pub(crate) fn active() -> bool {
    CURRENT.with(|c| c.borrow().is_some())
}

/// Add one solve that started at `start`, took `iterations` and `dense` dense steps to the
/// current stage.
pub(crate) fn record(outcome: Outcome, iterations: usize, dense: usize, start: Instant) {
    CURRENT.with(|c| {
        let c = c.borrow();
        let Some((stats, stage)) = c.as_ref() else {
            return;
        };
        let secs = start.elapsed().as_secs_f64();
        let it = iterations as u64;
        let mut k = StageCounts {
            attempted: 1,
            dense_steps: dense as u64,
            ..StageCounts::default()
        };
        match outcome {
            Outcome::Converged => {
                k.converged = 1;
                k.iterations = it;
                k.seconds = secs;
            }
            failed => {
                match failed {
                    Outcome::Cap => k.failed_cap = 1,
                    Outcome::Stall => k.failed_stall = 1,
                    _ => k.failed_other = 1,
                }
                k.failed_iterations = it;
                k.failed_seconds = secs;
            }
        }
        stats.add(*stage, &k);
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Solves are counted under the stage named innermost, only inside a scope, and the
    /// scope and stage are restored on the way out.
    #[test]
    fn counts_follow_scope_and_stage() {
        let stats = SolveStats::new();
        let t = Instant::now();
        record(Outcome::Converged, 3, 0, t);
        assert!(!active());
        scope(&stats, Stage::Trace, || {
            record(Outcome::Converged, 3, 0, t);
            stage(Stage::Creep, || {
                record(Outcome::Stall, 6, 1, t);
                record(Outcome::Cap, 30, 0, t);
            });
            record(Outcome::Other, 2, 0, t);
        });
        assert!(!active());
        record(Outcome::Converged, 5, 0, t);
        // A worker thread reopens the scope it is handed.
        let h = scope(&stats, Stage::Seed, current);
        let h2 = h.clone();
        std::thread::spawn(move || within(&h, || record(Outcome::Converged, 4, 0, t)))
            .join()
            .expect("worker");
        std::thread::spawn(move || {
            {
                let _counted = reopen(&h2);
                record(Outcome::Converged, 1, 0, t);
            }
            assert!(!active());
        })
        .join()
        .expect("worker");
        let snap = stats.snapshot();
        assert_eq!(snap.len(), 3);
        let (s0, seed) = snap[0];
        let (s1, trace) = snap[1];
        let (s2, creep) = snap[2];
        assert_eq!((s0, s1, s2), (Stage::Seed, Stage::Trace, Stage::Creep));
        assert_eq!((seed.attempted, seed.iterations), (2, 5));
        assert_eq!(
            (trace.attempted, trace.converged, trace.failed()),
            (2, 1, 1)
        );
        assert_eq!((trace.iterations, trace.failed_iterations), (3, 2));
        assert_eq!(trace.failed_other, 1);
        assert_eq!(
            (creep.attempted, creep.failed_stall, creep.failed_cap),
            (2, 1, 1)
        );
        assert_eq!((creep.failed_iterations, creep.dense_steps), (36, 1));
    }
}
