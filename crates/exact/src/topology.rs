//! Topology of a closed polygon in 3-D: self-contacts (closest approach of non-adjacent
//! segments below a tolerance). For a curve on a sphere these are its true
//! self-intersections, e.g. the single crossing of the figure-eight (branch 2, Sec. 3.1).
//! Also the periodic interpolation in arclength that [`crate::shape`] resamples loops with.

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

/// A self-contact of a closed polygon: where two strands come within the tolerance.
#[derive(Clone, Debug, PartialEq)]
pub struct Contact {
    /// Index of the first segment (from point `i` to `i + 1`).
    pub i: usize,
    /// Index of the second segment.
    pub j: usize,
    /// Where along segment `i` the strands are closest (`0..=1`).
    pub t: f64,
    /// Where along segment `j` (`0..=1`).
    pub u: f64,
    /// Midpoint of the closest approach.
    pub point: Vector3<f64>,
    /// Closest distance of the two strands.
    pub distance: f64,
}

/// Distance of indices `a`, `b` around a cycle of `n`.
pub fn cyclic_gap(a: usize, b: usize, n: usize) -> usize {
    let d = a.abs_diff(b) % n;
    d.min(n - d)
}

/// Self-contacts of the closed polygon through `points` (the last point joins the first):
/// pairs of segments whose closest approach is below `tol`, excluding pairs closer than
/// `2 tol` (plus one segment) along the curve. Hits on neighbouring segment pairs belong to
/// one contact and are merged (transitively); the representative is the closest pair.
///
/// Candidate pairs come from a sweep over the segments sorted by the `x` of their
/// midpoints, so the cost is `O(n log n)` plus the pairs within one segment length and
/// `tol` in `x`, rather than `O(n²)`.
pub fn self_contacts(points: &[Vector3<f64>], tol: f64) -> Vec<Contact> {
    let n = points.len();
    if n < 4 || tol.is_nan() || tol <= 0.0 {
        return Vec::new();
    }
    let seg = |i: usize| (&points[i], &points[(i + 1) % n]);
    let len: Vec<f64> = (0..n).map(|i| (seg(i).1 - seg(i).0).norm()).collect();
    let mean = len.iter().sum::<f64>() / n as f64;
    let hmax = len.iter().cloned().fold(0.0, f64::max);
    let mut cum = vec![0.0; n + 1];
    for i in 0..n {
        cum[i + 1] = cum[i] + len[i];
    }
    let total = cum[n];
    let mids: Vec<Vector3<f64>> = (0..n).map(|i| (seg(i).0 + seg(i).1) * 0.5).collect();
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| mids[a].x.total_cmp(&mids[b].x));
    let reach = hmax + tol;
    let mut hits: Vec<Contact> = Vec::new();
    for (k, &a) in order.iter().enumerate() {
        for &b in &order[k + 1..] {
            if mids[b].x - mids[a].x > reach {
                break;
            }
            let (i, j) = (a.min(b), a.max(b));
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
                let pa = p0 + (p1 - p0) * t;
                let pb = q0 + (q1 - q0) * u;
                hits.push(Contact {
                    i,
                    j,
                    t,
                    u,
                    point: (pa + pb) * 0.5,
                    distance: d,
                });
            }
        }
    }
    // Merge hits on neighbouring pairs (window: a few segments, wider when tol spans more),
    // transitively (union-find).
    let window = 3 + (2.0 * tol / mean.max(1e-300)).ceil() as usize + (hmax / mean) as usize;
    hits.sort_by_key(|a| (a.i, a.j));
    let mut parent: Vec<usize> = (0..hits.len()).collect();
    fn root(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    for a in 0..hits.len() {
        for b in a + 1..hits.len() {
            let (g, h) = (&hits[a], &hits[b]);
            let near = (cyclic_gap(g.i, h.i, n) <= window && cyclic_gap(g.j, h.j, n) <= window)
                || (cyclic_gap(g.i, h.j, n) <= window && cyclic_gap(g.j, h.i, n) <= window);
            if near {
                let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
                parent[ra] = rb;
            }
        }
    }
    let mut best: Vec<Option<usize>> = vec![None; hits.len()];
    for a in 0..hits.len() {
        let r = root(&mut parent, a);
        if best[r].is_none_or(|b| hits[a].distance < hits[b].distance) {
            best[r] = Some(a);
        }
    }
    let mut keep: Vec<usize> = best.into_iter().flatten().collect();
    keep.sort_unstable();
    keep.into_iter().map(|a| hits[a].clone()).collect()
}

/// Value at `target` of the periodic 4-point Lagrange interpolant through `(s_k, values_k)`
/// (`s` increasing, the data repeat after `length`): error `O(h⁴)`. `k` is a hint: an index
/// with `s_k ≤ target` near the answer (updated, so that monotone targets cost `O(1)`).
pub fn periodic_lagrange<T>(s: &[f64], values: &[T], length: f64, target: f64, k: &mut isize) -> T
where
    T: Copy + std::ops::Mul<f64, Output = T> + std::ops::Add<Output = T>,
{
    let n = s.len() as isize;
    let s_at = |k: isize| s[k.rem_euclid(n) as usize] + k.div_euclid(n) as f64 * length;
    let v_at = |k: isize| values[k.rem_euclid(n) as usize];
    while s_at(*k + 1) <= target {
        *k += 1;
    }
    while s_at(*k) > target {
        *k -= 1;
    }
    let ss = [s_at(*k - 1), s_at(*k), s_at(*k + 1), s_at(*k + 2)];
    let mut acc = v_at(*k - 1) * 0.0;
    for a in 0..4 {
        let mut w = 1.0;
        for b in 0..4 {
            if a != b {
                w *= (target - ss[b]) / (ss[a] - ss[b]);
            }
        }
        acc = acc + v_at(*k - 1 + a as isize) * w;
    }
    acc
}

/// Resample a closed curve given at arclengths `s` (increasing, the curve closes after
/// `length`) at `m` points uniform in arclength starting at `s_start`, by 4-point Lagrange
/// interpolation in `s` (error `O(h⁴)`).
pub fn resample_closed(
    s: &[f64],
    values: &[Vector3<f64>],
    length: f64,
    s_start: f64,
    m: usize,
) -> Vec<Vector3<f64>> {
    if s.len() < 4 || s.len() != values.len() {
        return Vec::new();
    }
    let mut k = 0isize;
    (0..m)
        .map(|idx| {
            let target = s_start + length * idx as f64 / m as f64;
            periodic_lagrange(s, values, length, target, &mut k)
        })
        .collect()
}
