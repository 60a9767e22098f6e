//! Topology of a closed polygon: self-contacts in 3-D (closest approach of non-adjacent
//! segments below a tolerance; for a curve on a sphere these are the true self-intersections,
//! e.g. the single crossing of the figure-eight, branch 2) and crossings of its 2-D
//! projections (which may be only apparent: one strand in front of the other).

use nalgebra::Vector3;

/// Closest points of segments `p0p1` and `q0q1`: `(distance, t, u)` with the points
/// `p0 + t(p1 − p0)` and `q0 + u(q1 − q0)`, `t, u ∈ [0, 1]`.
pub fn segment_distance(
    p0: &Vector3<f64>,
    p1: &Vector3<f64>,
    q0: &Vector3<f64>,
    q1: &Vector3<f64>,
) -> (f64, f64, f64) {
    let d1 = p1 - p0;
    let d2 = q1 - q0;
    let r = p0 - q0;
    let a = d1.dot(&d1);
    let e = d2.dot(&d2);
    let f = d2.dot(&r);
    let eps = 1e-300;
    let (t, u) = if a <= eps && e <= eps {
        (0.0, 0.0)
    } else if a <= eps {
        (0.0, (f / e).clamp(0.0, 1.0))
    } else {
        let c = d1.dot(&r);
        if e <= eps {
            ((-c / a).clamp(0.0, 1.0), 0.0)
        } else {
            let b = d1.dot(&d2);
            let denom = a * e - b * b;
            let mut t = if denom > 1e-14 * a * e {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let mut u = (b * t + f) / e;
            if u < 0.0 {
                u = 0.0;
                t = (-c / a).clamp(0.0, 1.0);
            } else if u > 1.0 {
                u = 1.0;
                t = ((b - c) / a).clamp(0.0, 1.0);
            }
            (t, u)
        }
    };
    let dist = ((p0 + d1 * t) - (q0 + d2 * u)).norm();
    (dist, t, u)
}

/// A self-contact of a closed curve: where two strands come within the tolerance.
#[derive(Clone, Debug, PartialEq)]
pub struct Contact {
    /// Index of the first segment (from point `i` to `i + 1`).
    pub i: usize,
    /// Index of the second segment.
    pub j: usize,
    /// Midpoint of the closest approach.
    pub point: Vector3<f64>,
    /// Closest distance of the two strands.
    pub distance: f64,
}

fn cyclic_gap(a: usize, b: usize, n: usize) -> usize {
    let d = a.abs_diff(b) % n;
    d.min(n - d)
}

/// Self-contacts of the closed polygon through `points` (the last point joins the first):
/// pairs of segments whose closest approach is below `tol`, excluding pairs closer than
/// `2 tol` (plus one segment) along the curve. Hits on neighbouring segment pairs belong to
/// one contact and are merged; the representative is the closest pair.
pub fn self_contacts(points: &[Vector3<f64>], tol: f64) -> Vec<Contact> {
    let n = points.len();
    if n < 4 || tol.is_nan() || tol <= 0.0 {
        return Vec::new();
    }
    let seg = |i: usize| (&points[i], &points[(i + 1) % n]);
    let len: Vec<f64> = (0..n).map(|i| (seg(i).1 - seg(i).0).norm()).collect();
    let mean = len.iter().sum::<f64>() / n as f64;
    let hmax = len.iter().cloned().fold(0.0, f64::max);
    // Cumulative arclength for the "too close along the curve" test.
    let mut cum = vec![0.0; n + 1];
    for i in 0..n {
        cum[i + 1] = cum[i] + len[i];
    }
    let total = cum[n];
    let mids: Vec<Vector3<f64>> = (0..n).map(|i| (seg(i).0 + seg(i).1) * 0.5).collect();
    let mut hits: Vec<Contact> = Vec::new();
    for i in 0..n {
        for j in (i + 2)..n {
            if cyclic_gap(i, j, n) < 2 {
                continue;
            }
            // Arclength between the segments (the shorter way round), segments excluded.
            let along = (cum[j] - cum[i + 1]).min(total - (cum[j + 1] - cum[i]));
            if along < 2.0 * tol {
                continue;
            }
            if (mids[i] - mids[j]).norm() > 0.5 * (len[i] + len[j]) + tol {
                continue;
            }
            let (p0, p1) = seg(i);
            let (q0, q1) = seg(j);
            let (d, t, u) = segment_distance(p0, p1, q0, q1);
            if d < tol {
                let a = p0 + (p1 - p0) * t;
                let b = q0 + (q1 - q0) * u;
                hits.push(Contact {
                    i,
                    j,
                    point: (a + b) * 0.5,
                    distance: d,
                });
            }
        }
    }
    // Merge hits on neighbouring pairs (window: a few segments, wider when tol spans more).
    let window = 3 + (2.0 * tol / mean.max(1e-300)).ceil() as usize + (hmax / mean) as usize;
    let mut clusters: Vec<Vec<Contact>> = Vec::new();
    for h in hits {
        let found = clusters.iter_mut().find(|c| {
            c.iter().any(|g| {
                (cyclic_gap(g.i, h.i, n) <= window && cyclic_gap(g.j, h.j, n) <= window)
                    || (cyclic_gap(g.i, h.j, n) <= window && cyclic_gap(g.j, h.i, n) <= window)
            })
        });
        match found {
            Some(c) => c.push(h),
            None => clusters.push(vec![h]),
        }
    }
    clusters
        .into_iter()
        .filter_map(|c| {
            c.into_iter()
                .min_by(|a, b| a.distance.total_cmp(&b.distance))
        })
        .collect()
}

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

/// Resample a closed curve given at arclengths `s` (increasing, the curve closes after
/// `length`) at `m` points uniform in arclength starting at `s_start`, by 4-point Lagrange
/// interpolation in `s` (error O(h⁴)).
pub fn resample_closed(
    s: &[f64],
    values: &[Vector3<f64>],
    length: f64,
    s_start: f64,
    m: usize,
) -> Vec<Vector3<f64>> {
    let n = s.len();
    let mut out = Vec::with_capacity(m);
    // Periodic extension helpers.
    let s_at = |k: isize| {
        let q = k.div_euclid(n as isize);
        let r = k.rem_euclid(n as isize) as usize;
        s[r] + q as f64 * length
    };
    let v_at = |k: isize| values[k.rem_euclid(n as isize) as usize];
    let mut k = 0isize; // index with s_at(k) <= target < s_at(k+1)
    for idx in 0..m {
        let target = s_start + length * idx as f64 / m as f64;
        while s_at(k + 1) <= target {
            k += 1;
        }
        while s_at(k) > target {
            k -= 1;
        }
        let ks = [k - 1, k, k + 1, k + 2];
        let mut acc = Vector3::zeros();
        for (a, &ka) in ks.iter().enumerate() {
            let mut w = 1.0;
            for (b, &kb) in ks.iter().enumerate() {
                if a != b {
                    w *= (target - s_at(kb)) / (s_at(ka) - s_at(kb));
                }
            }
            acc += v_at(ka) * w;
        }
        out.push(acc);
    }
    out
}
