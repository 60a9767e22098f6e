//! A second closed curve aligned onto a loop, for overlaying their profiles (the paper's
//! Fig. 5: a loop's `x, y, z, κ, τ` against `s` with the Euler rotation curve of Eqs. (4)–(8)
//! that approximates it).
//!
//! Two curves of the same shape can differ by where `s = 0` is, by the direction of travel,
//! by a mirror image and by a rotation. The alignment picks the arclength shift, direction
//! and mirror that best match the invariants `κ_g(s)` (else `κ`) and `τ(s)` (least squares
//! over the loop's samples), then the rotation that best matches the positions (Kabsch: SVD
//! of the 3 × 3 correlation matrix).

use nalgebra::{Matrix3, Vector3};

use crate::data::LoopData;
use crate::FigureError;

/// The other curve resampled at the loop's arclengths and moved onto it.
#[derive(Clone, Debug)]
pub struct Aligned {
    /// Columns `s, x, y, z` and those of `kappa, tau, kappa_g` the other curve has, at the
    /// loop's `s`.
    pub data: LoopData,
    /// Arclength shift (fraction of the length) of the other curve's origin.
    pub shift: f64,
    /// Whether the other curve runs the other way.
    pub reversed: bool,
    /// Whether the other curve is the mirror image.
    pub mirrored: bool,
    /// Largest distance between corresponding points after alignment (the loop's length
    /// unit).
    pub max_distance: f64,
}

/// Periodic linear interpolation of `v` (samples at `sigma`, increasing in `[0, 1)`) at `t`.
fn periodic(sigma: &[f64], v: &[f64], t: f64) -> f64 {
    let n = sigma.len();
    let t = t - t.floor();
    let k = sigma.partition_point(|&x| x <= t);
    let (i0, i1) = if k == 0 { (n - 1, 0) } else { (k - 1, k % n) };
    let (a, mut b) = (sigma[i0], sigma[i1]);
    let mut tt = t;
    if b <= a {
        b += 1.0;
        if tt < a {
            tt += 1.0;
        }
    }
    let w = if b > a { (tt - a) / (b - a) } else { 0.0 };
    v[i0] + w * (v[i1] - v[i0])
}

fn fractions(d: &LoopData) -> Vec<f64> {
    let s = d.s();
    let len = d.length();
    s.iter().map(|&x| (x - s[0]) / len).collect()
}

/// Align `other` onto `reference` (see the module docs). Both must have `kappa_g` or
/// `kappa` columns; `tau` is used when both have it.
pub fn align(reference: &LoopData, other: &LoopData) -> Result<Aligned, FigureError> {
    let key = ["kappa_g", "kappa"]
        .into_iter()
        .find(|c| reference.column(c).is_some() && other.column(c).is_some())
        .ok_or_else(|| {
            FigureError::Invalid(format!(
                "cannot align {} onto {}: neither has a kappa_g or kappa column in both",
                other.source, reference.source
            ))
        })?;
    let (sr, so) = (fractions(reference), fractions(other));
    let kr = reference.column(key).unwrap_or(&[]);
    let ko = other.column(key).unwrap_or(&[]);
    let tau = match (reference.column("tau"), other.column("tau")) {
        (Some(a), Some(b)) => Some((a, b)),
        _ => None,
    };
    // κ_g changes sign under reversal and under a mirror; τ under a mirror only; κ never.
    let signs = |rev: bool, mir: bool| -> (f64, f64) {
        let flip = |b: bool| if b { -1.0 } else { 1.0 };
        if key == "kappa_g" {
            (flip(rev) * flip(mir), flip(mir))
        } else {
            (1.0, flip(mir))
        }
    };
    let at = |i: usize, shift: f64, rev: bool| {
        if rev {
            shift - sr[i]
        } else {
            shift + sr[i]
        }
    };
    // The grid search uses every `stride`-th sample of the loop, the refinement all of them.
    let stride = sr.len().div_ceil(128);
    let score_every = |shift: f64, rev: bool, mir: bool, stride: usize| -> f64 {
        let (sk, st) = signs(rev, mir);
        (0..sr.len())
            .step_by(stride)
            .map(|i| {
                let t = at(i, shift, rev);
                let dk = kr[i] - sk * periodic(&so, ko, t);
                let dt = tau.map_or(0.0, |(a, b)| a[i] - st * periodic(&so, b, t));
                dk * dk + dt * dt
            })
            .sum()
    };
    let score = |shift: f64, rev: bool, mir: bool| score_every(shift, rev, mir, 1);
    let grid = 512;
    let (ox, oy, oz) = (
        other.column("x").unwrap_or(&[]),
        other.column("y").unwrap_or(&[]),
        other.column("z").unwrap_or(&[]),
    );
    let target = reference.points();
    let n = sr.len();
    // Positions at the matched arclengths (mirrored in x if needed), turned by the best
    // rotation; with the largest distance to the loop.
    let place = |shift: f64, rev: bool, mir: bool| -> (Vec<Vector3<f64>>, f64) {
        let flip = if mir { -1.0 } else { 1.0 };
        let moved: Vec<Vector3<f64>> = (0..n)
            .map(|i| {
                let t = at(i, shift, rev);
                Vector3::new(
                    flip * periodic(&so, ox, t),
                    periodic(&so, oy, t),
                    periodic(&so, oz, t),
                )
            })
            .collect();
        let mut h = Matrix3::zeros();
        for (p, q) in moved.iter().zip(&target) {
            h += p * q.transpose();
        }
        let svd = h.svd(true, true);
        let (u, vt) = (
            svd.u.unwrap_or_else(Matrix3::identity),
            svd.v_t.unwrap_or_else(Matrix3::identity),
        );
        let v = vt.transpose();
        let det = (v * u.transpose()).determinant();
        let rot = v * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, det.signum())) * u.transpose();
        let pts: Vec<Vector3<f64>> = moved.iter().map(|p| rot * p).collect();
        let worst = pts
            .iter()
            .zip(&target)
            .map(|(p, q)| (p - q).norm())
            .fold(0.0, f64::max);
        (pts, worst)
    };
    // For each direction and mirror: the best shift on a grid, refined by golden-section
    // search within one grid step; then the candidate whose positions match best (the
    // invariants of a symmetric loop do not tell its symmetric alignments apart).
    let phi = 0.5 * (5f64.sqrt() - 1.0);
    // (largest distance, shift, reversed, mirrored, placed points)
    type Candidate = (f64, f64, bool, bool, Vec<Vector3<f64>>);
    let mut best: Option<Candidate> = None;
    for rev in [false, true] {
        for mir in [false, true] {
            let (mut v0, mut shift) = (f64::INFINITY, 0.0);
            for g in 0..grid {
                let sh = g as f64 / grid as f64;
                let v = score_every(sh, rev, mir, stride);
                if v < v0 {
                    (v0, shift) = (v, sh);
                }
            }
            v0 = score(shift, rev, mir);
            let (mut a, mut b) = (shift - 1.0 / grid as f64, shift + 1.0 / grid as f64);
            for _ in 0..40 {
                let (c, d) = (b - phi * (b - a), a + phi * (b - a));
                if score(c, rev, mir) < score(d, rev, mir) {
                    b = d;
                } else {
                    a = c;
                }
            }
            if score(0.5 * (a + b), rev, mir) <= v0 {
                shift = 0.5 * (a + b);
            }
            let (pts, worst) = place(shift, rev, mir);
            if best.as_ref().is_none_or(|b| worst < b.0) {
                best = Some((worst, shift, rev, mir, pts));
            }
        }
    }
    let Some((max_distance, shift, rev, mir, pts)) = best else {
        return Err(FigureError::Invalid("no alignment".into()));
    };
    let mut names = vec!["s".to_string(), "x".into(), "y".into(), "z".into()];
    let mut columns = vec![
        reference.s().to_vec(),
        pts.iter().map(|p| p.x).collect(),
        pts.iter().map(|p| p.y).collect(),
        pts.iter().map(|p| p.z).collect(),
    ];
    let (sk, st) = signs(rev, mir);
    for (c, sign) in [("kappa", 1.0), ("tau", st), ("kappa_g", sk)] {
        if let Some(v) = other.column(c) {
            let sign = if c == "kappa_g" && key != "kappa_g" {
                1.0
            } else {
                sign
            };
            names.push(c.into());
            columns.push(
                (0..n)
                    .map(|i| sign * periodic(&so, v, at(i, shift, rev)))
                    .collect(),
            );
        }
    }
    Ok(Aligned {
        data: LoopData::new(&other.source, names, columns)?,
        shift: shift - shift.floor(),
        reversed: rev,
        mirrored: mir,
        max_distance,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A tilted wavy loop on the unit sphere without symmetries, with κ_g-like and τ-like
    /// columns (any smooth periodic invariants serve the test).
    fn wavy(
        n: usize,
        shift: f64,
        rev: bool,
        mir: bool,
        rot: &nalgebra::Rotation3<f64>,
    ) -> LoopData {
        let mut cols = vec![Vec::new(); 6];
        for j in 0..n {
            let s = j as f64 / n as f64;
            let u = if rev { shift - s } else { s - shift };
            let a = std::f64::consts::TAU * u;
            let p = Vector3::new(
                a.cos() + 0.2 * (2.0 * a).cos(),
                a.sin(),
                0.4 * (2.0 * a).sin() + 0.3 * (3.0 * a).cos(),
            )
            .normalize();
            let p = rot * Vector3::new(if mir { -p.x } else { p.x }, p.y, p.z);
            let kg = (2.0 * a).sin() + 0.3 * a.cos();
            let tau = (2.0 * a).cos() + 0.2 * a.sin();
            let sk = if rev { -1.0 } else { 1.0 } * if mir { -1.0 } else { 1.0 };
            let st = if mir { -1.0 } else { 1.0 };
            for (c, v) in [std::f64::consts::TAU * s, p.x, p.y, p.z, sk * kg, st * tau]
                .into_iter()
                .enumerate()
            {
                cols[c].push(v);
            }
        }
        let names = ["s", "x", "y", "z", "kappa_g", "tau"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        LoopData::new("wavy", names, cols).unwrap()
    }

    #[test]
    fn recovers_shift_direction_mirror_and_rotation() {
        let id = nalgebra::Rotation3::identity();
        let reference = wavy(400, 0.0, false, false, &id);
        let q = nalgebra::Rotation3::from_euler_angles(0.4, 1.0, -0.6);
        for (shift, rev, mir) in [(0.13, false, false), (0.61, true, false), (0.3, true, true)] {
            let other = wavy(1000, shift, rev, mir, &q);
            let a = align(&reference, &other).unwrap();
            assert_eq!((a.reversed, a.mirrored), (rev, mir));
            assert!((a.shift - shift).abs() < 1e-4, "{} vs {shift}", a.shift);
            // The fixture's s is its parameter, not its arclength (a mismatch of about 1e-3
            // in the length fractions), so positions agree to that level only.
            assert!(a.max_distance < 3e-3, "{}", a.max_distance);
        }
    }

    fn exact(
        n: usize,
        shift: f64,
        rev: bool,
        mir: bool,
        rot: &nalgebra::Rotation3<f64>,
    ) -> LoopData {
        let lp = rodloop_exact::paper_branch_loop(1, 1.6).unwrap();
        let len = lp.length();
        let mut cols = vec![Vec::new(); 7];
        for j in 0..n {
            let s = len * j as f64 / n as f64;
            let u = if rev {
                shift * len - s
            } else {
                s - shift * len
            };
            let p = lp.point(u.rem_euclid(len)).unwrap();
            let q = rot * Vector3::new(if mir { -p.x } else { p.x }, p.y, p.z);
            let sk = if rev != mir { -1.0 } else { 1.0 };
            let st = if mir { -1.0 } else { 1.0 };
            for (c, v) in [s, q.x, q.y, q.z, p.kappa, st * p.tau, sk * p.kappa_g]
                .into_iter()
                .enumerate()
            {
                cols[c].push(v);
            }
        }
        let names = ["s", "x", "y", "z", "kappa", "tau", "kappa_g"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        LoopData::new("figure-eight", names, cols).unwrap()
    }

    #[test]
    fn an_exact_loop_moved_about_is_put_back() {
        // The figure-eight (C2v) moved by shifts, reversals, mirrors and a rotation: aligned
        // back onto itself (any of its symmetric alignments will do) to the interpolation
        // error of 2000 samples.
        let id = nalgebra::Rotation3::identity();
        let reference = exact(300, 0.0, false, false, &id);
        let q = nalgebra::Rotation3::from_euler_angles(-0.9, 0.5, 2.0);
        for (shift, rev, mir) in [
            (0.37, false, false),
            (0.8, true, false),
            (0.05, false, true),
        ] {
            let a = align(&reference, &exact(2000, shift, rev, mir, &q)).unwrap();
            assert!(a.max_distance < 1e-4, "{}", a.max_distance);
            for c in ["kappa_g", "tau", "kappa"] {
                let (x, y) = (reference.column(c).unwrap(), a.data.column(c).unwrap());
                let d = x
                    .iter()
                    .zip(y)
                    .map(|(u, v)| (u - v).abs())
                    .fold(0.0, f64::max);
                assert!(d < 1e-3, "{c}: {d}");
            }
        }
    }
}
