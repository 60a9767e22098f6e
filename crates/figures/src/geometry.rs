//! Topology of a closed polygon: self-contacts in 3-D live in
//! [`rodloop_exact::topology`] (shared with the diagram's shape columns) and are re-exported
//! here; this module adds the crossings of 2-D projections (which may be only apparent: one
//! strand in front of the other).

pub use rodloop_exact::topology::{
    cyclic_gap, resample_closed, segment_distance, self_contacts, Contact,
};

/// A crossing of two segments of a closed polygon in the plane.
#[derive(Clone, Debug, PartialEq)]
pub struct Crossing2d {
    /// First segment.
    pub i: usize,
    /// Second segment.
    pub j: usize,
    /// Where they cross.
    pub at: (f64, f64),
}

/// Proper crossings of non-adjacent segments of the closed planar polygon `pts`.
pub fn crossings_2d(pts: &[(f64, f64)]) -> Vec<Crossing2d> {
    let n = pts.len();
    let mut out = Vec::new();
    if n < 4 {
        return out;
    }
    let cross = |a: (f64, f64), b: (f64, f64)| a.0 * b.1 - a.1 * b.0;
    let sub = |a: (f64, f64), b: (f64, f64)| (a.0 - b.0, a.1 - b.1);
    let bbox: Vec<(f64, f64, f64, f64)> = (0..n)
        .map(|i| {
            let (a, b) = (pts[i], pts[(i + 1) % n]);
            (a.0.min(b.0), a.0.max(b.0), a.1.min(b.1), a.1.max(b.1))
        })
        .collect();
    for i in 0..n {
        for j in (i + 2)..n {
            if cyclic_gap(i, j, n) < 2 {
                continue;
            }
            let (bi, bj) = (bbox[i], bbox[j]);
            if bi.1 < bj.0 || bj.1 < bi.0 || bi.3 < bj.2 || bj.3 < bi.2 {
                continue;
            }
            let (p, p1) = (pts[i], pts[(i + 1) % n]);
            let (q, q1) = (pts[j], pts[(j + 1) % n]);
            let r = sub(p1, p);
            let s = sub(q1, q);
            let den = cross(r, s);
            if den.abs() < 1e-300 {
                continue;
            }
            let qp = sub(q, p);
            let t = cross(qp, s) / den;
            let u = cross(qp, r) / den;
            // Strands that run (anti)parallel on top of each other (a symmetric loop seen
            // along its axis) overlap rather than cross: skip angles below ~3°.
            let sin = den.abs() / ((r.0 * r.0 + r.1 * r.1) * (s.0 * s.0 + s.1 * s.1)).sqrt();
            if sin < 0.05 {
                continue;
            }
            // Half-open in t and u so a crossing exactly at a vertex is counted once.
            if (0.0..1.0).contains(&t) && (0.0..1.0).contains(&u) {
                out.push(Crossing2d {
                    i,
                    j,
                    at: (p.0 + t * r.0, p.1 + t * r.1),
                });
            }
        }
    }
    // One crossing may be found on two neighbouring segment pairs when it falls on a vertex
    // up to rounding; keep one per neighbourhood.
    let mut kept: Vec<Crossing2d> = Vec::new();
    for c in out {
        if !kept
            .iter()
            .any(|k| cyclic_gap(k.i, c.i, n) <= 2 && cyclic_gap(k.j, c.j, n) <= 2)
        {
            kept.push(c);
        }
    }
    kept
}
