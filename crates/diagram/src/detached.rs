//! Where the enclosed loops of a homogeneous rod leave the wall (`rodloop compare --scene
//! enclosed`, paper Sec. 3.2): per branch, the intervals of `L̄` where its surface loop has
//! `λ < 0` somewhere (exact lift-off and landing lengths), and on a scan of each interval the
//! largest gap to the wall and the largest energy drop of the enclosed state below the
//! surface loop, with the stretch where the branch is the lowest surface branch.

use rodloop_exact::{eta_of_branch, paper_branch_loop};
use rodloop_solver::enclosed::detached_intervals;
use rodloop_solver::{Accuracy, Stiffness};

use crate::enclosed_state::{passed, solve_state, TOUCH};
use crate::DiagramError;

/// One interval of lengths where a branch has lifted off, and what a scan of it found.
#[derive(Clone, Debug, PartialEq)]
pub struct DetachedStretch {
    /// Lift-off length (exact layer).
    pub lift_off: f64,
    /// Landing length (exact layer).
    pub landing: f64,
    /// Largest gap `(R − |r|)/R` on the scan and the length where it is.
    pub max_gap: (f64, f64),
    /// Largest energy drop below the surface loop, the length where it is and the error
    /// estimate of the enclosed energy there.
    pub max_energy_drop: (f64, f64, f64),
    /// The sub-interval where the branch is the lowest surface branch ([`stable_stretch`]).
    pub stable: Option<(f64, f64)>,
}

/// One branch and its detached intervals in the scanned range (none: attached throughout).
#[derive(Clone, Debug, PartialEq)]
pub struct BranchDetachment {
    /// Paper branch number.
    pub branch: u32,
    /// Periods of `κ_g`.
    pub eta: u32,
    /// The intervals where it has lifted off.
    pub stretches: Vec<DetachedStretch>,
}

/// Branches 1–3 of a homogeneous enclosed scene (ball radius `r`) over `lo ≤ L̄ ≤ hi`: each
/// detached interval scanned at 13 lengths (at 2 % … 98 % of it) by [`solve_state`] at the
/// fast accuracy.
pub fn detachments(
    r: f64,
    stiffness: &Stiffness,
    lo: f64,
    hi: f64,
) -> Result<Vec<BranchDetachment>, DiagramError> {
    let mut out = Vec::new();
    for branch in 1..=3u32 {
        let eta = eta_of_branch(branch);
        let intervals = detached_intervals(eta, lo, hi).map_err(passed)?;
        let mut stretches = Vec::new();
        for (a, b) in intervals {
            let mut best_gap = (0.0f64, a);
            let mut best_drop = (0.0f64, a, 0.0);
            let n = 12;
            for k in 0..=n {
                let l = a + (b - a) * (0.02 + 0.96 * k as f64 / n as f64);
                let res = solve_state(r, stiffness, l, branch, Accuracy::Fast)?;
                let c = res.state.contact(TOUCH).map_err(passed)?;
                if c.max_gap.0 > best_gap.0 {
                    best_gap = (c.max_gap.0, l);
                }
                let drop = res.surface.map(|s| s.0).unwrap_or(0.0) - res.energy.0;
                if drop > best_drop.0 {
                    best_drop = (drop, l, res.energy.1);
                }
            }
            stretches.push(DetachedStretch {
                lift_off: a,
                landing: b,
                max_gap: best_gap,
                max_energy_drop: best_drop,
                stable: stable_stretch(eta, a, b)?,
            });
        }
        out.push(BranchDetachment {
            branch,
            eta,
            stretches,
        });
    }
    Ok(out)
}

/// The sub-interval of `(a, b)` where branch `eta` is the lowest of the paper's homogeneous
/// surface branches (exact energies; bisection on energy crossings to 1e-12).
pub fn stable_stretch(eta: u32, a: f64, b: f64) -> Result<Option<(f64, f64)>, DiagramError> {
    let energy = |eta: u32, l: f64| -> Result<f64, DiagramError> {
        paper_branch_loop(eta, l)
            .and_then(|lp| lp.energy())
            .map_err(passed)
    };
    let lowest = |l: f64| -> Result<bool, DiagramError> {
        let mine = energy(eta, l)?;
        for other in 1..=5u32 {
            if other == eta {
                continue;
            }
            let o = f64::from(other);
            if l > o - 1.0 && l < o + 1.0 && energy(other, l)? < mine {
                return Ok(false);
            }
        }
        Ok(true)
    };
    let n = 200;
    let grid: Vec<f64> = (0..=n)
        .map(|i| a + (b - a) * (i as f64 + 0.5) / (n as f64 + 1.0))
        .collect();
    let flags: Vec<bool> = grid.iter().map(|&l| lowest(l)).collect::<Result<_, _>>()?;
    let first = flags.iter().position(|&f| f);
    let last = flags.iter().rposition(|&f| f);
    let (Some(i), Some(j)) = (first, last) else {
        return Ok(None);
    };
    let refine = |x0: f64, x1: f64, want_true_at_x1: bool| -> Result<f64, DiagramError> {
        let (mut p, mut q) = (x0, x1);
        while q - p > 1e-12 {
            let m = 0.5 * (p + q);
            if lowest(m)? == want_true_at_x1 {
                q = m;
            } else {
                p = m;
            }
        }
        Ok(0.5 * (p + q))
    };
    let s = if i == 0 {
        a
    } else {
        refine(grid[i - 1], grid[i], true)?
    };
    let t = if j == n {
        b
    } else {
        refine(grid[j], grid[j + 1], false)?
    };
    Ok(Some((s, t)))
}
