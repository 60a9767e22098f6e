//! Point-group symmetry of a closed curve centred on the sphere's centre.
//!
//! A symmetry operation `Q ∈ O(3)` of a closed curve maps it onto itself and so induces an
//! arclength map `s ↦ ±s + σ`. For a curve sampled at `n` points uniform in arclength, every
//! candidate (orientation, grid shift) pair is tested by solving the orthogonal Procrustes
//! problem `min_Q Σ |Q r_i − r'_i|²` (SVD of the 3×3 correlation matrix; Kabsch 1976 without
//! the determinant fix, since reflections are wanted). The candidates whose residual is below
//! the tolerance form the symmetry group, which is then named in Schoenflies notation (the
//! notation the paper uses in Sec. 3.1).
//!
//! Shifts that are not a multiple of the grid spacing are not tested, so the sampling must be
//! compatible with the symmetry: `n` should be a multiple of `4η` for a loop with `η` periods of
//! geodesic curvature (every symmetry of such a loop shifts the arclength by a multiple of
//! `L/(4η)`, half a half-period, as `κ_g` is even about its extrema and odd about its zeros),
//! and the sample must start at an extremum or a zero of `κ_g`.

use nalgebra::{Matrix3, Vector3};

/// A detected symmetry group.
#[derive(Clone, Debug)]
pub struct PointGroup {
    /// Schoenflies symbol, e.g. `D2d`, `C2v`, `D3h`.
    pub symbol: String,
    /// Number of elements.
    pub order: usize,
    /// The elements.
    pub elements: Vec<Matrix3<f64>>,
    /// Largest RMS residual among the accepted elements (how exact the symmetry is).
    pub worst_residual: f64,
}

/// Detect the point group of a closed curve given by `points` (uniform in arclength, curve
/// centred on the origin). `tol` is the RMS residual (in the units of the points) below which a
/// candidate is accepted.
pub fn point_group(points: &[Vector3<f64>], tol: f64) -> PointGroup {
    let n = points.len();
    let mut found = Elements::default();
    for reversed in [false, true] {
        for shift in 0..n {
            let image: Vec<Vector3<f64>> = (0..n)
                .map(|i| {
                    let j = if reversed {
                        (shift + n - i % n) % n
                    } else {
                        (i + shift) % n
                    };
                    points[j]
                })
                .collect();
            found.test(points, &image, tol);
        }
    }
    found.finish(points)
}

/// Symmetry elements collected from candidate arclength maps.
#[derive(Default)]
pub(crate) struct Elements {
    elements: Vec<Matrix3<f64>>,
    worst: f64,
}

impl Elements {
    /// Test the candidate map `points[i] ↦ image[i]` ([`procrustes`]): its operations are
    /// kept when their RMS residual is below `tol`.
    pub(crate) fn test(&mut self, points: &[Vector3<f64>], image: &[Vector3<f64>], tol: f64) {
        for (q, rms) in procrustes(points, image) {
            if rms < tol && !self.elements.iter().any(|e| (e - q).norm() < 1e-6) {
                self.worst = self.worst.max(rms);
                self.elements.push(q);
            }
        }
    }

    /// The group of the collected elements, named with a matching tolerance that grows with
    /// the worst residual (relative to the curve's RMS radius): elements found on sampled
    /// data are orthogonal matrices accurate to about that residual.
    pub(crate) fn finish(self, points: &[Vector3<f64>]) -> PointGroup {
        let scale = (points.iter().map(|p| p.norm_squared()).sum::<f64>()
            / points.len().max(1) as f64)
            .sqrt();
        let eps = if scale > 0.0 {
            (20.0 * self.worst / scale).clamp(1e-6, 2e-2)
        } else {
            1e-6
        };
        let elements = dedupe(self.elements, eps);
        let symbol = classify_with(&elements, eps);
        PointGroup {
            symbol,
            order: elements.len(),
            elements,
            worst_residual: self.worst,
        }
    }
}

/// The orthogonal `Q` minimising `Σ |Q points_i − image_i|²` (orthogonal Procrustes: SVD of
/// the 3×3 correlation matrix, Kabsch 1976 without the determinant fix, since reflections
/// are wanted) with its RMS residual; for a planar curve both solutions (`Q` and `Q`
/// followed by the mirror in the plane).
pub(crate) fn procrustes(
    points: &[Vector3<f64>],
    image: &[Vector3<f64>],
) -> Vec<(Matrix3<f64>, f64)> {
    let n = points.len().max(1);
    // Correlation matrix C = Σ r'_i r_iᵀ; the best orthogonal Q is U Vᵀ.
    let mut c = Matrix3::zeros();
    for (p, q) in points.iter().zip(image) {
        c += q * p.transpose();
    }
    let svd = c.svd(true, true);
    let (Some(u), Some(vt)) = (svd.u, svd.v_t) else {
        return Vec::new();
    };
    // For a planar curve C has rank 2 and the sign of the third singular direction is free.
    let sv = svd.singular_values;
    let (imax, imin) = (sv.imax(), sv.imin());
    let mut choices = vec![u * vt];
    if sv[imin] <= 1e-9 * sv[imax] {
        let mut flip = Matrix3::identity();
        flip[(imin, imin)] = -1.0;
        choices.push(u * flip * vt);
    }
    choices
        .into_iter()
        .map(|q| {
            let rms = (points
                .iter()
                .zip(image)
                .map(|(p, r)| (q * p - r).norm_squared())
                .sum::<f64>()
                / n as f64)
                .sqrt();
            (q, rms)
        })
        .collect()
}

/// Drop elements equal to an earlier one within `eps`.
fn dedupe(elements: Vec<Matrix3<f64>>, eps: f64) -> Vec<Matrix3<f64>> {
    let mut out: Vec<Matrix3<f64>> = Vec::with_capacity(elements.len());
    for q in elements {
        if !out.iter().any(|e| (e - q).norm() < eps) {
            out.push(q);
        }
    }
    out
}

/// Axis (unit vector, sign fixed) and rotation order of a proper rotation; `None` for identity
/// (within `eps`).
fn rotation_axis_order(q: &Matrix3<f64>, eps: f64) -> Option<(Vector3<f64>, usize)> {
    let c = ((q.trace() - 1.0) / 2.0).clamp(-1.0, 1.0);
    let angle = c.acos();
    if angle < eps {
        return None;
    }
    let order = (2.0 * std::f64::consts::PI / angle).round() as usize;
    let axis = if angle > std::f64::consts::FRAC_PI_2 {
        // Near a half turn the skew part vanishes; the symmetric part is
        // cos θ I + (1 − cos θ) a aᵀ, so its largest column (less cos θ I) is along the axis.
        let m = ((q + q.transpose()) * 0.5 - Matrix3::identity() * c) / (1.0 - c);
        let col = (0..3)
            .map(|j| m.column(j).into_owned())
            .max_by(|a, b| a.norm().total_cmp(&b.norm()))
            .unwrap_or(Vector3::z());
        col.normalize()
    } else {
        Vector3::new(
            q[(2, 1)] - q[(1, 2)],
            q[(0, 2)] - q[(2, 0)],
            q[(1, 0)] - q[(0, 1)],
        )
        .normalize()
    };
    Some((canonical(axis), order))
}

/// Fix the sign of an axis so that equal axes compare equal.
fn canonical(v: Vector3<f64>) -> Vector3<f64> {
    let first = if v.x.abs() > 1e-8 {
        v.x
    } else if v.y.abs() > 1e-8 {
        v.y
    } else {
        v.z
    };
    if first < 0.0 {
        -v
    } else {
        v
    }
}

fn same_axis(a: &Vector3<f64>, b: &Vector3<f64>, eps: f64) -> bool {
    a.cross(b).norm() < 10.0 * eps
}

/// Name a finite subgroup of O(3) in Schoenflies notation (elements exact to about 1e-6).
pub fn classify(elements: &[Matrix3<f64>]) -> String {
    classify_with(elements, 1e-6)
}

/// Name a finite subgroup of O(3) in Schoenflies notation; `eps` is the accuracy of the
/// elements (angles, traces and axes are matched within it).
pub fn classify_with(elements: &[Matrix3<f64>], eps: f64) -> String {
    let order = elements.len();
    let proper: Vec<&Matrix3<f64>> = elements.iter().filter(|q| q.determinant() > 0.0).collect();
    let improper: Vec<&Matrix3<f64>> = elements.iter().filter(|q| q.determinant() < 0.0).collect();
    let has_inversion = improper
        .iter()
        .any(|q| (*q + Matrix3::identity()).norm() < eps);
    // Rotation axes with their largest order.
    let mut axes: Vec<(Vector3<f64>, usize)> = Vec::new();
    for q in &proper {
        if let Some((a, k)) = rotation_axis_order(q, eps) {
            if let Some(e) = axes.iter_mut().find(|(b, _)| same_axis(&a, b, eps)) {
                e.1 = e.1.max(k);
            } else {
                axes.push((a, k));
            }
        }
    }
    // Reflections: improper elements with trace 1 (eigenvalues 1, 1, −1); normal = −1 eigvector.
    let mirror_normals: Vec<Vector3<f64>> = improper
        .iter()
        .filter(|q| (q.trace() - 1.0).abs() < eps)
        .map(|q| {
            let m = (Matrix3::identity() - **q) * 0.5;
            let col = (0..3)
                .map(|j| m.column(j).into_owned())
                .max_by(|a, b| a.norm().total_cmp(&b.norm()))
                .unwrap_or(Vector3::z());
            canonical(col.normalize())
        })
        .collect();
    // Improper rotations S_k about an axis: −Q is a proper rotation; S_k with k from its angle.
    let improper_axes: Vec<(Vector3<f64>, usize)> = improper
        .iter()
        .filter(|q| (q.trace() - 1.0).abs() >= eps && (**q + Matrix3::identity()).norm() >= eps)
        .filter_map(|q| {
            // q = −R with R a rotation by θ + π about the same axis; S_k rotates by 2π/k.
            let r = -**q;
            let c = ((r.trace() - 1.0) / 2.0).clamp(-1.0, 1.0);
            let theta_r = c.acos();
            let theta_s = std::f64::consts::PI - theta_r;
            let k = (2.0 * std::f64::consts::PI / theta_s).round() as usize;
            rotation_axis_order(&r, eps).map(|(a, _)| (a, k))
        })
        .collect();

    let high: Vec<&(Vector3<f64>, usize)> = axes.iter().filter(|(_, k)| *k >= 3).collect();
    if high.len() >= 2 {
        // Cubic groups.
        let has_c4 = axes.iter().any(|(_, k)| *k == 4);
        let has_c5 = axes.iter().any(|(_, k)| *k == 5);
        let base = if has_c5 {
            "I"
        } else if has_c4 {
            "O"
        } else {
            "T"
        };
        return match (improper.is_empty(), has_inversion) {
            (true, _) => base.to_string(),
            (false, true) => format!("{base}h"),
            (false, false) => format!("{base}d"),
        };
    }
    if axes.is_empty() {
        return if improper.is_empty() {
            "C1".into()
        } else if has_inversion {
            "Ci".into()
        } else {
            "Cs".into()
        };
    }
    // Principal axis: the highest order; among several C2 axes prefer one that is also an S4
    // axis (D2d), then one perpendicular to a mirror (σh).
    let n = axes.iter().map(|(_, k)| *k).max().unwrap_or(1);
    let candidates: Vec<&(Vector3<f64>, usize)> = axes.iter().filter(|(_, k)| *k == n).collect();
    let principal = candidates
        .iter()
        .find(|(a, _)| {
            improper_axes
                .iter()
                .any(|(b, k)| same_axis(a, b, eps) && *k == 2 * n)
        })
        .or_else(|| {
            candidates
                .iter()
                .find(|(a, _)| mirror_normals.iter().any(|m| same_axis(a, m, eps)))
        })
        .unwrap_or(&candidates[0])
        .0;
    let perp_c2 = axes
        .iter()
        .filter(|(a, k)| *k >= 2 && a.dot(&principal).abs() < 10.0 * eps)
        .count();
    let sigma_h = mirror_normals.iter().any(|m| same_axis(m, &principal, eps));
    let sigma_v = mirror_normals
        .iter()
        .any(|m| m.dot(&principal).abs() < 10.0 * eps);
    let s2n = improper_axes
        .iter()
        .any(|(a, k)| same_axis(a, &principal, eps) && *k == 2 * n);
    let sym = if perp_c2 >= n && n >= 2 {
        if sigma_h {
            format!("D{n}h")
        } else if sigma_v {
            format!("D{n}d")
        } else {
            format!("D{n}")
        }
    } else if sigma_h {
        format!("C{n}h")
    } else if sigma_v {
        format!("C{n}v")
    } else if s2n {
        format!("S{}", 2 * n)
    } else {
        format!("C{n}")
    };
    debug_assert!(order >= 1);
    sym
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn curve(f: impl Fn(f64) -> Vector3<f64>, n: usize) -> Vec<Vector3<f64>> {
        (0..n).map(|i| f(2.0 * PI * i as f64 / n as f64)).collect()
    }

    #[test]
    fn known_curves_have_known_groups() {
        // Planar circle in the xy-plane: D∞h, sampled at n points it shows Dnh.
        let g = point_group(&curve(|t| Vector3::new(t.cos(), t.sin(), 0.0), 12), 1e-9);
        assert_eq!(g.symbol, "D12h");
        // Tennis-ball seam (Eq. 7, a = 0.3, b = 0.7): D2d.
        let (a, b) = (0.3f64, 0.7f64);
        let seam = |t: f64| {
            Vector3::new(
                a * t.cos() - b * (3.0 * t).cos(),
                a * t.sin() + b * (3.0 * t).sin(),
                2.0 * (a * b).sqrt() * (2.0 * t).cos(),
            )
        };
        let g = point_group(&curve(seam, 64), 1e-9);
        assert_eq!((g.symbol.as_str(), g.order), ("D2d", 8));
        // A generic curve has only the identity.
        let generic = |t: f64| {
            Vector3::new(
                t.cos() + 0.3 * (2.0 * t).sin(),
                t.sin() + 0.2 * (3.0 * t).cos(),
                0.4 * (t + 0.3).sin() + 0.1 * (2.0 * t).cos(),
            )
        };
        assert_eq!(point_group(&curve(generic, 64), 1e-9).symbol, "C1");
    }
}
