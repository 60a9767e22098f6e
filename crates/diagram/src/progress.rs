//! The progress events of [`crate::compute`], [`crate::compute_branch`] and
//! [`crate::assemble`] ([`Progress`], for progress bars).

use crate::CriticalKind;

/// Progress events of [`compute`](crate::compute), [`compute_branch`](crate::compute_branch) and
/// [`assemble`](crate::assemble) (for progress bars).
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum Progress {
    /// [`compute`](crate::compute) will produce these branches (`η` values), `resumed` of them from
    /// the resume list.
    Planned {
        /// Branches (`η`) of the diagram.
        etas: Vec<u32>,
        /// How many come from the resume list.
        resumed: usize,
    },
    /// Tracing of a branch started.
    BranchStarted {
        /// Paper branch number.
        branch: u32,
        /// Periods of `κ_g`.
        eta: u32,
    },
    /// Tracing of a branch progressed (every 25 continuation steps, and at the end of each
    /// direction).
    BranchStep {
        /// Periods of `κ_g`.
        eta: u32,
        /// Length reached.
        lbar: f64,
        /// Continuation steps so far in this direction.
        steps: usize,
    },
    /// A branch was traced.
    BranchFinished {
        /// Paper branch number.
        branch: u32,
        /// Periods of `κ_g`.
        eta: u32,
        /// Number of traced states.
        points: usize,
        /// Wall time of the branch in seconds.
        seconds: f64,
    },
    /// A branch was taken from the resume list.
    BranchResumed {
        /// Paper branch number.
        branch: u32,
        /// Periods of `κ_g`.
        eta: u32,
        /// Number of traced states.
        points: usize,
    },
    /// A branch could not be traced (it is left out of the diagram, with a warning).
    BranchFailed {
        /// Periods of `κ_g`.
        eta: u32,
        /// Why.
        reason: String,
    },
    /// A resumed branch did not match the options and is traced again.
    BranchResumeRejected {
        /// Periods of `κ_g`.
        eta: u32,
        /// Why it was rejected.
        reason: String,
    },
    /// [`assemble`](crate::assemble) will locate this many crossings and analyse this many great
    /// circles (one [`Progress::CriticalLocated`] per crossing, one [`Progress::GreatCircleDone`]
    /// per circle follow, in any order).
    AssemblyPlanned {
        /// Number of crossings found on the samples.
        crossings: usize,
        /// Number of great circles to analyse.
        great_circles: usize,
    },
    /// A critical length was located.
    CriticalLocated {
        /// Crossing or collapse.
        kind: CriticalKind,
        /// The critical length.
        lbar_cr: f64,
        /// Lowest branch below.
        from_branch: u32,
        /// Lowest branch above.
        to_branch: u32,
    },
    /// The great circle with `m` turns was analysed (buckling loads and switching).
    GreatCircleDone {
        /// Number of turns.
        m: u32,
        /// Of this many.
        total: usize,
    },
}
