//! Point group and self-intersections of one sampled closed loop, the two shape descriptors
//! of Sec. 3.1 (the paper names each branch by its Schoenflies group, Fig. 2, and counts its
//! crossings: none for the saddle, one for the figure-eight, …). Used for exact loops, for
//! the numeric model's states and for any loop table that `rodloop draw` reads.
//!
//! # Point group
//!
//! A symmetry `Q ∈ O(3)` of a loop on a sphere centred on the origin maps the loop onto
//! itself and so induces an arclength map `s ↦ ±s + σ`, under which the geodesic curvature
//! goes to `±κ_g` (a reversal or a reflection flips its sign). So it maps the points where
//! `|κ_g|` attains its maximum onto one another. These *anchors* are located to `O(h³)` on
//! the 4-point interpolant of the `κ_g` samples; every symmetry then sends the first anchor
//! to some anchor, forwards or backwards, and each of those `2 × anchors` candidate maps is
//! tested by the orthogonal Procrustes fit of [`crate::symmetry`] on the loop resampled
//! uniformly from the two anchors. No sampling compatible with the symmetry is needed (the
//! grid-based [`crate::symmetry::point_group`] needs a multiple of `4η` points from an
//! extremum or zero of `κ_g`), nor is `η`, so non-uniform rods (whose symmetries need not
//! shift `s` by a multiple of `L/(4η)`) are covered too.
//!
//! A loop within the tolerance of a circle has a continuous group: `D∞h` for a great circle
//! (Sec. 3.1, the loops at `L̄ = m`), `C∞v` for a small circle.
//!
//! # Self-intersections
//!
//! The loop is resampled uniformly (spacing at most `R/40`, so the chords sag by less than
//! `h²/(8R) < 1e-4 R`) and its self-contacts counted by
//! [`crate::topology::self_contacts`]: strands closer than the contact tolerance, away from
//! each other along the loop. A loop within the symmetry tolerance of a circle covered `m ≥ 2`
//! times overlaps itself everywhere: its count is `None`.

use std::f64::consts::PI;

use nalgebra::{Matrix3, Vector3};

use crate::symmetry::{procrustes, Elements};
use crate::topology::{periodic_lagrange, resample_closed, self_contacts};
use crate::ExactError;

/// A closed loop sampled along its arclength, with its geodesic curvature (possibly at other
/// arclengths, e.g. the numeric model's Gauss points). Positions are relative to the sphere's
/// centre.
#[derive(Clone, Copy, Debug)]
pub struct SampledLoop<'a> {
    /// Length `L` of the loop.
    pub length: f64,
    /// Radius `R` of the sphere (the unit of the tolerances).
    pub radius: f64,
    /// Arclengths of `points`, increasing, within one length `L`.
    pub s: &'a [f64],
    /// Positions at `s`.
    pub points: &'a [Vector3<f64>],
    /// Arclengths of `kappa_g`, increasing, within one length `L`.
    pub kappa_g_s: &'a [f64],
    /// Geodesic curvature at `kappa_g_s` (any unit: only where `|κ_g|` peaks matters).
    pub kappa_g: &'a [f64],
}

/// Tolerances of the shape descriptors, as fractions of the sphere radius `R`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ShapeTolerances {
    /// RMS residual below which a symmetry operation is accepted (also: the RMS distance
    /// from a circle below which a loop counts as a circle).
    pub symmetry: f64,
    /// Distance below which two strands, apart along the loop, are in contact.
    pub contact: f64,
}

/// The default of both tolerances, `1e-3 R`: far above the symmetry residual of the numeric
/// model's coarsest states (a few 1e-5 R at 8 cells per period, `crates/solver/tests/shape.rs`)
/// and far below the strand distances of the paper's loops away from their great-circle ends.
pub const DEFAULT_TOLERANCE: f64 = 1e-3;

impl Default for ShapeTolerances {
    /// [`DEFAULT_TOLERANCE`] for both.
    fn default() -> Self {
        Self {
            symmetry: DEFAULT_TOLERANCE,
            contact: DEFAULT_TOLERANCE,
        }
    }
}

/// A self-contact found on the resampled loop.
#[derive(Clone, Debug, PartialEq)]
pub struct LoopContact {
    /// Arclengths of the two strands at their closest approach.
    pub s: [f64; 2],
    /// Midpoint of the closest approach.
    pub point: Vector3<f64>,
    /// Distance of the strands there.
    pub distance: f64,
}

/// The shape descriptors of one loop.
#[derive(Clone, Debug, PartialEq)]
pub struct LoopShape {
    /// Schoenflies symbol of the point group, e.g. `D2d`, `C2v`, `D3h`, `D∞h`.
    pub point_group: String,
    /// Number of elements; `None` for the continuous groups `D∞h`, `C∞v`.
    pub group_order: Option<usize>,
    /// Largest RMS residual (units of `R`) among the accepted symmetry operations, or the RMS
    /// distance from the circle for a circle.
    pub symmetry_residual: f64,
    /// Number of self-intersections; `None` for a multiply covered circle.
    pub self_intersections: Option<usize>,
    /// The self-contacts (empty for a circle).
    pub contacts: Vec<LoopContact>,
    /// The tolerances used.
    pub tolerances: ShapeTolerances,
}

impl LoopShape {
    /// The count as a table cell: the number, or `overlap` for a multiply covered circle.
    pub fn self_intersections_label(&self) -> String {
        self.self_intersections
            .map_or_else(|| "overlap".to_string(), |k| k.to_string())
    }
}

fn invalid(msg: String) -> ExactError {
    ExactError::InvalidParameter(msg)
}

fn check(l: &SampledLoop, tol: &ShapeTolerances) -> Result<(), ExactError> {
    if !(l.length.is_finite() && l.length > 0.0 && l.radius.is_finite() && l.radius > 0.0) {
        return Err(invalid(format!(
            "a loop needs a positive length and radius (got L = {}, R = {})",
            l.length, l.radius
        )));
    }
    for (name, t) in [("symmetry", tol.symmetry), ("contact", tol.contact)] {
        if !(t > 0.0 && t < 1.0) {
            return Err(invalid(format!(
                "the {name} tolerance must lie in (0, 1) (a fraction of R), got {t}"
            )));
        }
    }
    if l.s.len() != l.points.len() || l.s.len() < 8 {
        return Err(invalid(format!(
            "a loop needs at least 8 points with one arclength each (got {} points, {} arclengths)",
            l.points.len(),
            l.s.len()
        )));
    }
    if l.kappa_g_s.len() != l.kappa_g.len() || l.kappa_g.len() < 8 {
        return Err(invalid(format!(
            "a loop needs at least 8 values of kappa_g with one arclength each (got {}, {})",
            l.kappa_g.len(),
            l.kappa_g_s.len()
        )));
    }
    for s in [l.s, l.kappa_g_s] {
        let span = s[s.len() - 1] - s[0];
        if s.windows(2)
            .any(|w| w[1].partial_cmp(&w[0]) != Some(std::cmp::Ordering::Greater))
            || span.partial_cmp(&l.length) != Some(std::cmp::Ordering::Less)
        {
            return Err(invalid(
                "arclengths must increase and span less than one loop length".into(),
            ));
        }
    }
    let finite = l.points.iter().all(|p| p.iter().all(|v| v.is_finite()))
        && l.kappa_g.iter().all(|v| v.is_finite());
    if !finite {
        return Err(invalid("the loop has non-finite values".into()));
    }
    Ok(())
}

/// Number of points of the uniform resampling: spacing at most `R/40`, so that chords sag
/// by at most `h²/(8R) < 1e-4 R` (a tenth of the default contact tolerance), and no fewer
/// points than the data have.
fn resolution(l: &SampledLoop) -> usize {
    ((40.0 * l.length / l.radius).ceil() as usize)
        .max(l.points.len())
        .clamp(256, 16384)
}

/// Point group and self-intersections of `l`.
pub fn loop_shape(l: &SampledLoop, tol: ShapeTolerances) -> Result<LoopShape, ExactError> {
    check(l, &tol)?;
    let m = resolution(l);
    let uniform = resample_closed(l.s, l.points, l.length, l.s[0], m);
    let r = l.radius;
    if let Some((centre, rho, dev)) = circle_fit(&uniform).filter(|c| c.2 < tol.symmetry * r) {
        let cover = (l.length / (2.0 * PI * rho)).round().max(1.0) as usize;
        let great = centre.norm() < tol.symmetry * r;
        return Ok(LoopShape {
            point_group: if great { "D∞h" } else { "C∞v" }.into(),
            group_order: None,
            symmetry_residual: dev,
            self_intersections: if cover >= 2 { None } else { Some(0) },
            contacts: Vec::new(),
            tolerances: tol,
        });
    }
    let (group, order, residual) = point_group_of(l, tol.symmetry * r);
    let h = l.length / m as f64;
    let contacts = self_contacts(&uniform, tol.contact * r)
        .into_iter()
        .map(|c| LoopContact {
            s: [
                l.s[0] + h * (c.i as f64 + c.t),
                l.s[0] + h * (c.j as f64 + c.u),
            ],
            point: c.point,
            distance: c.distance,
        })
        .collect::<Vec<_>>();
    Ok(LoopShape {
        point_group: group,
        group_order: Some(order),
        symmetry_residual: residual,
        self_intersections: Some(contacts.len()),
        contacts,
        tolerances: tol,
    })
}

/// Best-fit circle of the points: `(centre, radius, RMS distance from the circle)`.
fn circle_fit(p: &[Vector3<f64>]) -> Option<(Vector3<f64>, f64, f64)> {
    let n = p.len() as f64;
    let c = p.iter().fold(Vector3::zeros(), |a, q| a + q) / n;
    let mut cov = Matrix3::zeros();
    for q in p {
        let d = q - c;
        cov += d * d.transpose();
    }
    cov /= n;
    let eig = cov.symmetric_eigen();
    let k = eig.eigenvalues.imin();
    let normal = eig.eigenvectors.column(k).into_owned();
    let radial: Vec<f64> = p
        .iter()
        .map(|q| {
            let d = q - c;
            (d - normal * d.dot(&normal)).norm()
        })
        .collect();
    let rho = radial.iter().sum::<f64>() / n;
    if rho.is_nan() || rho <= 0.0 {
        return None;
    }
    let in_plane = radial.iter().map(|x| (x - rho) * (x - rho)).sum::<f64>() / n;
    let off_plane = eig.eigenvalues[k].max(0.0);
    Some((c, rho, (in_plane + off_plane).sqrt()))
}

/// Arclengths where `|κ_g|` peaks within 5 % of its maximum (refined on the interpolant),
/// merged when closer than 1 % of the length.
fn anchors(l: &SampledLoop) -> Vec<f64> {
    let (s, kg, len) = (l.kappa_g_s, l.kappa_g, l.length);
    let n = kg.len();
    let top = kg.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let mut out: Vec<(f64, f64)> = Vec::new();
    for i in 0..n {
        let (a, b, c) = (
            kg[(i + n - 1) % n].abs(),
            kg[i].abs(),
            kg[(i + 1) % n].abs(),
        );
        if !(b >= a && b > c && b >= 0.95 * top) {
            continue;
        }
        // Golden-section search for the peak of |κ_g| between the neighbours.
        let lo = if i == 0 { s[n - 1] - len } else { s[i - 1] };
        let hi = if i + 1 == n { s[0] + len } else { s[i + 1] };
        let mut hint = i as isize;
        let mut f = |x: f64| periodic_lagrange(s, kg, len, x, &mut hint).abs();
        let x = brent_min(|x| -f(x), lo, hi, PEAK_XTOL * len, 60);
        out.push((x, f(x)));
    }
    // Merge near-duplicates (a flat peak sampled twice), keeping the higher.
    let mut merged: Vec<(f64, f64)> = Vec::new();
    for (x, v) in out {
        let near = merged.iter_mut().find(|(y, _)| {
            let d = (x - y).rem_euclid(len);
            d.min(len - d) < 0.01 * len
        });
        match near {
            Some(e) if v > e.1 => *e = (x, v),
            Some(_) => {}
            None => merged.push((x, v)),
        }
    }
    merged.into_iter().map(|(x, _)| x).collect()
}

/// Point group from the anchor maps: `(symbol, order, worst residual in units of R)`.
///
/// Residuals are RMS over 128 points uniform in arclength (the RMS of a smooth periodic
/// function converges exponentially in the number of uniform samples). The anchors are
/// located only to the accuracy of the `κ_g` interpolant (`O(h³)`, about 1e-3 R for the
/// diagram's coarsest states), so a candidate map that comes within 30 times the tolerance
/// but not within a tenth of it is refined: the start of its image is moved by a
/// golden-section search (within two `κ_g` spacings, residuals on 64 points) to the least
/// residual. Maps that are not symmetries miss by `O(R)`.
fn point_group_of(l: &SampledLoop, tol: f64) -> (String, usize, f64) {
    let marks = anchors(l);
    let len = l.length;
    let sample = |start: f64, dir: f64, count: usize| -> Vec<Vector3<f64>> {
        let h = len / count as f64;
        let mut hint = 0isize;
        (0..count)
            .map(|i| periodic_lagrange(l.s, l.points, len, start + dir * h * i as f64, &mut hint))
            .collect()
    };
    let Some(&first) = marks.first() else {
        return ("C1".into(), 1, 0.0);
    };
    let coarse = 128;
    let base_coarse = sample(first, 1.0, coarse);
    // The search needs only where the residual is least: 64 points do.
    const SEARCH: usize = 64;
    let base_search = sample(first, 1.0, SEARCH);
    let best = |img: &[Vector3<f64>], b: &[Vector3<f64>]| {
        procrustes(b, img)
            .into_iter()
            .map(|(_, r)| r)
            .fold(f64::INFINITY, f64::min)
    };
    let spacing = l
        .kappa_g_s
        .windows(2)
        .map(|w| w[1] - w[0])
        .fold(0.0f64, f64::max)
        .max(len - (l.kappa_g_s[l.kappa_g_s.len() - 1] - l.kappa_g_s[0]));
    let mut found = Elements::default();
    for &a in &marks {
        for dir in [1.0, -1.0] {
            let r0 = best(&sample(a, dir, coarse), &base_coarse);
            if r0 > 30.0 * tol {
                continue;
            }
            let start = if r0 < 0.1 * tol {
                a
            } else {
                let f = |x: f64| best(&sample(x, dir, SEARCH), &base_search);
                brent_min(
                    f,
                    a - 2.0 * spacing,
                    a + 2.0 * spacing,
                    MAP_XTOL * spacing,
                    30,
                )
            };
            found.test(&base_coarse, &sample(start, dir, coarse), tol);
        }
    }
    let g = found.finish(&base_coarse);
    (g.symbol, g.order, g.worst_residual / l.radius)
}

/// Bracket (fraction of the loop's length) to which [`brent_min`] locates a peak of `|κ_g|`
/// for the anchors: far below the interpolant's own accuracy (`O(h³)`), so the anchor is
/// the interpolant's peak.
const PEAK_XTOL: f64 = 1e-9;

/// Bracket (fraction of the `κ_g` sample spacing) to which [`brent_min`] locates the start
/// of a symmetry map's image of least residual: the least residual is flat to second order
/// there, so the residual at the bracket's ends differs from the least by far less than the
/// symmetry tolerance.
const MAP_XTOL: f64 = 1e-6;

/// Minimiser of `f` on `[lo, hi]` by Brent's method: parabolic interpolation through the
/// three best points so far, a golden-section step wherever the parabola is not trusted
/// (R. P. Brent, *Algorithms for Minimization without Derivatives*, 1973, ch. 5), until the
/// minimiser is bracketed to `xtol` (plus `√ε` relative) or after `max_evals` evaluations.
/// On a smooth minimum it needs fewer evaluations than golden sections for the same bracket
/// (at most 30 against 45 on the smooth minima of the test below).
fn brent_min(mut f: impl FnMut(f64) -> f64, lo: f64, hi: f64, xtol: f64, max_evals: usize) -> f64 {
    let golden = 0.5 * (3.0 - 5f64.sqrt());
    let root_eps = f64::EPSILON.sqrt();
    let (mut a, mut b) = (lo.min(hi), lo.max(hi));
    let mut x = a + golden * (b - a);
    let (mut w, mut v) = (x, x);
    let mut fx = f(x);
    let (mut fw, mut fv) = (fx, fx);
    // The step taken and the one before it.
    let (mut d, mut e) = (0.0f64, 0.0f64);
    for _ in 1..max_evals {
        let m = 0.5 * (a + b);
        let tol = root_eps * x.abs() + xtol / 3.0;
        let t2 = 2.0 * tol;
        if (x - m).abs() <= t2 - 0.5 * (b - a) {
            break;
        }
        let mut parabolic = false;
        if e.abs() > tol {
            let r = (x - w) * (fx - fv);
            let mut q = (x - v) * (fx - fw);
            let mut p = (x - v) * q - (x - w) * r;
            q = 2.0 * (q - r);
            if q > 0.0 {
                p = -p;
            } else {
                q = -q;
            }
            let before = e;
            e = d;
            // Accept the parabola's vertex only inside the bracket and for a step shorter
            // than half the one before last.
            if p.abs() < (0.5 * q * before).abs() && p > q * (a - x) && p < q * (b - x) {
                d = p / q;
                let u = x + d;
                if u - a < t2 || b - u < t2 {
                    d = if x < m { tol } else { -tol };
                }
                parabolic = true;
            }
        }
        if !parabolic {
            e = if x < m { b - x } else { a - x };
            d = golden * e;
        }
        let u = if d.abs() >= tol {
            x + d
        } else if d > 0.0 {
            x + tol
        } else {
            x - tol
        };
        let fu = f(u);
        if fu <= fx {
            if u < x {
                b = x;
            } else {
                a = x;
            }
            (v, fv, w, fw, x, fx) = (w, fw, x, fx, u, fu);
        } else {
            if u < x {
                a = u;
            } else {
                b = u;
            }
            if fu <= fw || w == x {
                (v, fv, w, fw) = (w, fw, u, fu);
            } else if fu <= fv || v == x || v == w {
                (v, fv) = (u, fu);
            }
        }
    }
    x
}

/// [`loop_shape`] of samples `(s, r, κ_g)` of a loop of length `length` on the unit sphere.
pub fn unit_sphere_shape(
    length: f64,
    samples: impl Iterator<Item = (f64, Vector3<f64>, f64)>,
    tol: ShapeTolerances,
) -> Result<LoopShape, ExactError> {
    let (mut s, mut points, mut kg) = (Vec::new(), Vec::new(), Vec::new());
    for (a, r, k) in samples {
        s.push(a);
        points.push(r);
        kg.push(k);
    }
    loop_shape(
        &SampledLoop {
            length,
            radius: 1.0,
            s: &s,
            points: &points,
            kappa_g_s: &s,
            kappa_g: &kg,
        },
        tol,
    )
}

/// Shape descriptors of an exact loop (unit sphere), sampled at `48 (η + 1)` points of
/// Eq. (45) (the interpolation error, `O(h⁴)`, stays below 1e-4 R).
pub fn exact_loop_shape(
    lp: &crate::ExactLoop,
    tol: ShapeTolerances,
) -> Result<LoopShape, ExactError> {
    let pts = lp.sample(48 * (lp.eta as usize + 1))?;
    unit_sphere_shape(
        lp.length(),
        pts.iter()
            .map(|p| (p.s, Vector3::new(p.x, p.y, p.z), p.kappa_g)),
        tol,
    )
}

/// Shape descriptors of the paper's branch `η` loop at `lbar` with modulus `k` (a point of
/// the exact diagram, wave family, `m = k²`); `k = 0` is the branch's end, the great circle
/// covered `L̄` times.
pub fn branch_point_shape(
    eta: u32,
    lbar: f64,
    k: f64,
    tol: ShapeTolerances,
) -> Result<LoopShape, ExactError> {
    if k == 0.0 {
        let len = 2.0 * PI * lbar;
        let n = (256.0 * lbar).ceil() as usize;
        return unit_sphere_shape(
            len,
            (0..n).map(|i| {
                let t = len * i as f64 / n as f64;
                (t, Vector3::new(t.cos(), t.sin(), 0.0), 0.0)
            }),
            tol,
        );
    }
    let lp = crate::ExactLoop::from_parameter(crate::Family::Wave, eta, lbar, k * k)?;
    exact_loop_shape(&lp, tol)
}

/// [`branch_point_shape`] of every point of an exact diagram, in order, on up to
/// `threads` threads.
pub fn diagram_shapes(
    points: &[crate::diagram::BranchPoint],
    tol: ShapeTolerances,
    threads: usize,
) -> Result<Vec<LoopShape>, ExactError> {
    let one = |p: &crate::diagram::BranchPoint| branch_point_shape(p.eta, p.lbar, p.k, tol);
    let threads = threads.clamp(1, 64);
    if threads == 1 || points.len() < 2 * threads {
        return points.iter().map(one).collect();
    }
    let chunk = points.len().div_ceil(threads);
    std::thread::scope(|scope| {
        let handles: Vec<_> = points
            .chunks(chunk)
            .map(|c| scope.spawn(move || c.iter().map(one).collect::<Result<Vec<_>, _>>()))
            .collect();
        let mut out = Vec::with_capacity(points.len());
        for h in handles {
            match h.join() {
                Ok(r) => out.extend(r?),
                Err(_) => {
                    return Err(ExactError::InvalidParameter(
                        "a shape worker panicked".into(),
                    ))
                }
            }
        }
        Ok(out)
    })
}

#[cfg(test)]
mod tests {
    use super::brent_min;

    /// Brent's minimiser finds known minima to its bracket plus `√ε` relative (where a
    /// smooth minimum is defined in floating point): a parabola, a cosine, a peak of a
    /// trigonometric sum like `|κ_g|` (where the derivative vanishes), a minimum at an end of
    /// the bracket, and a flat quartic (minimiser defined only to `ε^{1/4}`); the smooth
    /// interior ones in at most 30 evaluations, where golden sections need 45 to shrink the
    /// bracket to 1e-9.
    #[test]
    fn brent_min_finds_known_minima() {
        // (function, bracket, minimiser (NaN: where the derivative vanishes), tolerance)
        type Case<'a> = (&'a dyn Fn(f64) -> f64, f64, f64, f64, f64);
        let cases: [Case; 5] = [
            (&|x: f64| (x - 0.3).powi(2) + 1.0, -1.0, 2.0, 0.3, 3e-8),
            (&|x: f64| x.cos(), 2.0, 4.5, std::f64::consts::PI, 1e-7),
            (
                &|x: f64| -(x.sin() + 0.3 * (2.0 * x).sin() + 0.1 * (5.0 * x).cos()).abs(),
                0.5,
                1.6,
                f64::NAN,
                0.0,
            ),
            (&|x: f64| (x - 2.0).powi(2), 0.0, 1.0, 1.0, 3e-8),
            (&|x: f64| (x - 0.7).powi(4), 0.0, 1.0, 0.7, 1e-3),
        ];
        for (k, (f, lo, hi, want, tol)) in cases.iter().enumerate() {
            let mut evals = 0;
            let x = brent_min(
                |x| {
                    evals += 1;
                    f(x)
                },
                *lo,
                *hi,
                1e-9,
                200,
            );
            // The interior peak: no closed form; the derivative vanishes there.
            let want = if want.is_nan() {
                let h = 1e-6;
                assert!(
                    ((f(x + h) - f(x - h)) / (2.0 * h)).abs() < 1e-6,
                    "case {k}: {x}"
                );
                x
            } else {
                *want
            };
            assert!((x - want).abs() <= *tol, "case {k}: {x} vs {want}");
            if k < 3 {
                assert!(evals <= 30, "case {k}: {evals} evaluations");
            }
        }
    }
}
