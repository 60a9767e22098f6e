//! Where a two-segment diagram looks for states: the sample lengths of a range (the
//! completeness certificate's and the seeding's), the origin shifts that put a stiffness
//! change at a phase of the curvature pattern, and whether a solved loop closes. Shared by
//! the certificate and the family seeding, which depend on it and not on each other.

use rodloop_solver::Stiffness;

/// Spacing in `L̄` of the certificate's sample lengths (at most; the range is cut into equal
/// parts no longer than this).
pub const SAMPLE_SPACING: f64 = 0.05;

/// Sample lengths of the range `[lo, hi]`: the midpoints of `n = ⌈(hi − lo)/`
/// [`SAMPLE_SPACING`]`⌉` equal parts (so never an end of the range, where a family may end,
/// and never an integer length inside it, where the great circles are, unless a part's
/// midpoint falls there), and the spacing.
pub fn sample_lengths(lo: f64, hi: f64) -> (Vec<f64>, f64) {
    let span = (hi - lo).max(0.0);
    let n = ((span / SAMPLE_SPACING).ceil() as usize).max(1);
    let h = span / n as f64;
    ((0..n).map(|k| lo + (k as f64 + 0.5) * h).collect(), h)
}

/// Origin shifts (fractions of the length, in `[0, 1/(2η))`) that put the point of phase
/// `j/(8η)` of the Euler curve of `eta` periods (`j` in `phases`) at each stiffness change:
/// `s0*`, and `s1*` too if `both`. [`StartShape::shifted`](rodloop_solver::StartShape::shifted)
/// samples the start at `σ + shift`, so the start's point `σ₀` lands at `σ₀ − shift`; the shift
/// that puts phase `φ` at `s` is `φ − s` (modulo the half period `1/(2η)`, a shift by which is the
/// reflection `κ_g → −κ_g`). Empty for a profile without stiffness changes.
pub fn feature_shifts(stiffness: &Stiffness, eta: u32, phases: &[u32], both: bool) -> Vec<f64> {
    let features: Vec<f64> = match stiffness {
        Stiffness::Tanh { s0, s1, .. } if both => vec![*s0, *s1],
        Stiffness::Tanh { s0, .. } => vec![*s0],
        _ => Vec::new(),
    };
    let e = f64::from(eta.max(1));
    let mut out: Vec<f64> = Vec::new();
    for s in features {
        for &j in phases {
            let shift = (f64::from(j) / (8.0 * e) - s).rem_euclid(1.0 / (2.0 * e));
            if !out.iter().any(|&o| (o - shift).abs() < 1e-9) {
                out.push(shift);
            }
        }
    }
    out
}

/// Whether the loop of `eq` closes: the gap between its last and first node is at most
/// twice the largest distance between consecutive nodes. A KKT point whose holonomy is a
/// half-turn satisfies the closure residual without closing (gaps of 0.5–2 R); it is not
/// an equilibrium of the loop and is not counted.
pub fn closes(eq: &rodloop_solver::Equilibrium) -> bool {
    let p = eq.profile();
    let d = |a: &rodloop_solver::ProfilePoint, b: &rodloop_solver::ProfilePoint| {
        ((a.x - b.x).powi(2) + (a.y - b.y).powi(2) + (a.z - b.z).powi(2)).sqrt()
    };
    let step = p.windows(2).map(|w| d(&w[0], &w[1])).fold(0.0, f64::max);
    match (p.first(), p.last()) {
        (Some(a), Some(b)) => d(b, a) <= 2.0 * step,
        _ => false,
    }
}
