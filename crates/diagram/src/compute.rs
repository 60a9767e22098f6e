//! [`compute`]: every branch (traced in parallel, or supplied by a [`BranchHook`] to
//! resume), then the assembly.

use std::time::Instant;

use rodloop_continuation::BoxError;

use crate::certificate::StateSearch;
use crate::diagram::{assemble, NumericDiagram};
use crate::families::{compute_families, Families};
use crate::parallel::run_parallel;
use crate::trace::compute_branch;
use crate::types::TracedBranch;
use crate::{DiagramError, DiagramOptions, Progress};

/// How a branch handed to [`BranchHook::finished`] came about.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Origin {
    /// Traced by this call of [`compute`].
    Traced,
    /// Supplied by [`BranchHook::resume`] (and accepted: same fingerprint).
    Resumed,
}

/// Per-branch hook of [`compute`]: supplies branches traced earlier and is told about every
/// branch of the diagram when it is ready. Both methods are called on the thread that called
/// [`compute`].
pub trait BranchHook {
    /// A branch traced earlier for `eta` (e.g. read from a file), to use instead of tracing
    /// it. [`compute`] accepts it only if its [`TracedBranch::fingerprint`] matches
    /// [`DiagramOptions::fingerprint`] and it has states; otherwise it reports
    /// [`Progress::BranchResumeRejected`] and traces the branch. Default: none.
    fn resume(&mut self, eta: u32) -> Option<TracedBranch> {
        let _ = eta;
        None
    }

    /// Called once for every branch of the diagram as soon as it is ready: traced
    /// ([`Origin::Traced`], in the order the threads finish) or resumed
    /// ([`Origin::Resumed`], before tracing starts). Not called for a branch that could
    /// not be traced. An error makes [`compute`] fail with [`DiagramError::Hook`] (the
    /// branches already being traced finish first; the hook is not called again).
    /// Default: nothing.
    fn finished(&mut self, branch: &TracedBranch, origin: Origin) -> Result<(), BoxError> {
        let _ = (branch, origin);
        Ok(())
    }

    /// Non-uniform rods: every family of `eta` traced earlier (sheets and notes), to use
    /// instead of tracing them. Accepted only if it has sheets, all of `eta` and with the
    /// matching fingerprint. Default: none.
    fn resume_families(&mut self, eta: u32) -> Option<Families> {
        let _ = eta;
        None
    }

    /// Non-uniform rods: called once for every branch `eta` whose families were traced,
    /// after [`BranchHook::finished`] for each of its sheets (so a hook that saves the
    /// families last knows the branch is complete). Default: nothing.
    fn finished_families(&mut self, eta: u32, families: &Families) -> Result<(), BoxError> {
        let _ = (eta, families);
        Ok(())
    }
}

/// No hook: trace every branch.
impl BranchHook for () {}

/// Resume from branches in memory (e.g. deserialised from files); nothing is saved.
#[derive(Clone, Copy, Debug)]
pub struct Resume<'a>(pub &'a [TracedBranch]);

impl BranchHook for Resume<'_> {
    fn resume(&mut self, eta: u32) -> Option<TracedBranch> {
        self.0.iter().find(|b| b.eta == eta).cloned()
    }

    fn resume_families(&mut self, eta: u32) -> Option<Families> {
        let sheets: Vec<TracedBranch> = self.0.iter().filter(|b| b.eta == eta).cloned().collect();
        (!sheets.is_empty()).then_some(Families {
            sheets,
            notes: Vec::new(),
        })
    }
}

/// A job of [`compute`]'s thread pool.
enum Job {
    /// Trace branch `η`.
    Trace(u32),
    /// The first stage of the certificate's search at a sample length.
    Search(f64),
}

/// The result of a [`Job`]: the traced families, or the certificate's candidates and the
/// seconds they took.
enum Done {
    Traced(Result<Families, DiagramError>),
    Searched(Vec<crate::certificate::SurfaceCandidate>, f64),
}

/// Compute the whole numeric diagram: for every branch of [`DiagramOptions::etas`], the
/// branch the hook supplies ([`BranchHook::resume`], if its fingerprint matches) or
/// [`compute_branch`], then [`assemble`]. Branches are traced on
/// [`DiagramOptions::worker_threads`] threads, largest `η` first; the progress callback and
/// the hook are always called from the calling thread.
///
/// A branch that cannot be traced is left out with a warning; the call fails if none is
/// left, on invalid options, or if the hook fails.
pub fn compute(
    opts: &DiagramOptions,
    hook: &mut dyn BranchHook,
    progress: &mut dyn FnMut(Progress),
) -> Result<NumericDiagram, DiagramError> {
    opts.validate()?;
    let start = Instant::now();
    let etas = opts.etas();
    if etas.is_empty() {
        return Err(DiagramError::InvalidOptions(
            "no branch meets the length range".into(),
        ));
    }
    let fingerprint = opts.fingerprint();
    let mut have: Vec<TracedBranch> = Vec::new();
    let mut todo: Vec<u32> = Vec::new();
    let mut rejected = Vec::new();
    // Notes and failures by branch, reported in decreasing η (the tracing order).
    let mut notes: Vec<(u32, Vec<String>)> = Vec::new();
    for &eta in &etas {
        if !opts.stiffness.is_uniform() {
            // Non-uniform rods: all the families of a branch, or none.
            match hook.resume_families(eta) {
                Some(f)
                    if !f.sheets.is_empty()
                        && f.sheets.iter().all(|b| {
                            b.fingerprint == fingerprint && b.eta == eta && !b.points.is_empty()
                        }) =>
                {
                    have.extend(f.sheets);
                    notes.push((eta, f.notes));
                }
                Some(f) => {
                    rejected.push(Progress::BranchResumeRejected {
                        eta,
                        reason: format!(
                            "the saved families ({} sheets) were traced with other options or \
                             are incomplete",
                            f.sheets.len()
                        ),
                    });
                    todo.push(eta);
                }
                None => todo.push(eta),
            }
            continue;
        }
        match hook.resume(eta) {
            Some(b) if b.fingerprint == fingerprint && b.eta == eta && !b.points.is_empty() => {
                have.push(b)
            }
            Some(b) => {
                rejected.push(Progress::BranchResumeRejected {
                    eta,
                    reason: if b.points.is_empty() {
                        "no traced points".into()
                    } else if b.eta != eta {
                        format!("the hook supplied branch eta = {} for eta = {eta}", b.eta)
                    } else {
                        format!(
                            "traced with other options ({} ≠ {})",
                            b.fingerprint, fingerprint
                        )
                    },
                });
                todo.push(eta);
            }
            None => todo.push(eta),
        }
    }
    progress(Progress::Planned {
        etas: etas.clone(),
        resumed: have.len(),
    });
    for r in rejected {
        progress(r);
    }
    for b in &have {
        progress(Progress::BranchResumed {
            branch: b.branch,
            eta: b.eta,
            points: b.points.len(),
        });
        hook.finished(b, Origin::Resumed)
            .map_err(DiagramError::Hook)?;
    }
    // Largest branches first, for the balance of the threads; then, for a two-segment rod,
    // the first stage of the completeness certificate's search at its sample lengths (it
    // needs nothing of the traced set, so it fills the threads the tracing leaves idle).
    let uniform = opts.stiffness.is_uniform();
    todo.sort_by_key(|&eta| std::cmp::Reverse(eta));
    let (lengths, spacing) = crate::certificate::sample_lengths(opts.lbar_min, opts.lbar_max);
    let search = crate::certificate::SurfaceSearch::new(opts, &lengths);
    let jobs: Vec<Job> = todo
        .iter()
        .map(|&eta| Job::Trace(eta))
        .chain(lengths.iter().filter(|_| !uniform).map(|&l| Job::Search(l)))
        .collect();
    let mut hook_error = None;
    let results = run_parallel(
        opts.worker_threads(),
        jobs,
        progress,
        &mut |r: &Done| {
            if let Done::Traced(Ok(f)) = r {
                for b in &f.sheets {
                    if hook_error.is_none() {
                        hook_error = hook.finished(b, Origin::Traced).err();
                    }
                }
                if !uniform && hook_error.is_none() {
                    if let Some(eta) = f.sheets.first().map(|b| b.eta) {
                        hook_error = hook.finished_families(eta, f).err();
                    }
                }
            }
        },
        |job, tx| match job {
            Job::Search(l) => {
                let t = Instant::now();
                let c = search.candidates_at(l);
                Done::Searched(c, t.elapsed().as_secs_f64())
            }
            Job::Trace(eta) => {
                let r = if uniform {
                    compute_branch(opts, eta, &mut |p| tx(p)).map(|b| Families {
                        sheets: vec![b],
                        notes: Vec::new(),
                    })
                } else {
                    compute_families(opts, eta, &mut |p| tx(p))
                };
                if let Err(e) = &r {
                    tx(Progress::BranchFailed {
                        eta,
                        reason: e.to_string(),
                    });
                }
                Done::Traced(r)
            }
        },
    );
    let mut traced = Vec::new();
    let mut candidates = Vec::new();
    let mut search_seconds = 0.0;
    for r in results {
        match r {
            Done::Traced(t) => traced.push(t),
            Done::Searched(c, secs) => {
                candidates.extend(c);
                search_seconds += secs;
            }
        }
    }
    if let Some(e) = hook_error {
        return Err(DiagramError::Hook(e));
    }
    // A branch that cannot be traced at all is left out with a warning (the others still make
    // a diagram); invalid options fail everything.
    for (t, &eta) in traced.into_iter().zip(&todo) {
        match t {
            Ok(f) => {
                have.extend(f.sheets);
                notes.push((eta, f.notes));
            }
            Err(e @ DiagramError::InvalidOptions(_)) => return Err(e),
            Err(e) => notes.push((eta, vec![format!("branch left out of the diagram: {e}")])),
        }
    }
    notes.sort_by_key(|(eta, _)| std::cmp::Reverse(*eta));
    let failures: Vec<String> = notes.into_iter().flat_map(|(_, n)| n).collect();
    if have.is_empty() {
        return Err(DiagramError::InvalidOptions(format!(
            "no branch could be traced: {}",
            failures.join("; ")
        )));
    }
    have.sort_by_key(|b| (b.eta, b.family, b.sheet));
    // Completeness certificate of a two-segment rod: the search of `rodloop solve` at
    // sample lengths; families of states found below the traced ones are traced too.
    let mut failures = failures;
    let certificate = (!uniform).then(|| {
        let mut set = crate::certificate::SurfaceTraced {
            opts,
            sheets: &mut have,
            notes: &mut failures,
        };
        crate::certificate::certify(
            &search,
            candidates,
            search_seconds,
            &mut set,
            &lengths,
            spacing,
            opts.worker_threads(),
        )
    });
    let tracing_seconds = start.elapsed().as_secs_f64();
    let mut d = assemble(opts, have, progress)?;
    if let Some(c) = &certificate {
        failures.extend(c.warnings());
    }
    d.certificate = certificate;
    d.warnings.splice(0..0, failures);
    d.timings.tracing = tracing_seconds;
    d.timings.total = start.elapsed().as_secs_f64();
    Ok(d)
}
