//! A surface state's curvature carried to another mesh of the same map cell by cell: the
//! start of a re-solve at a finer resolution.
//!
//! [`Equilibrium::resample`] interpolates `κ_g` trigonometrically over the whole loop, which
//! is spectrally accurate for a smooth state. A state whose bends its cells do not resolve
//! (on a very soft segment the tangent can turn by 2 rad within one cell) has a `κ_g` that
//! jumps between neighbouring cells; its trigonometric interpolant rings over the whole loop,
//! and Newton at the finer resolution starts far from every equilibrium there.
//! [`Equilibrium::prolong`] interpolates locally instead: the cubic through the four Gauss
//! values nearest the new point (the two of its cell and one on each side), exact for cubics
//! in `σ` and `O(h⁴)` for a smooth `κ_g`, whose error stays within two cells of a jump.

use crate::solve::Equilibrium;
use crate::surface::model::GAUSS_OFFSETS;
use crate::SolverError;

/// The values at the Gauss points of the cells `to` (boundaries `σ_0 = 0 < … < σ_M = 1`,
/// periodic) of the function whose values at the Gauss points of the cells `from` are
/// `values` (two per cell, [`GAUSS_OFFSETS`]): at each new point, the cubic through the
/// four old Gauss values nearest it (those of the old cell holding it and the next one on
/// each side, across `σ = 1` periodically).
///
/// Errors: [`SolverError::WrongLength`] unless `values` has two entries per cell of `from`;
/// [`SolverError::InvalidInput`] for fewer than two cells.
pub fn prolong_gauss_values(
    from: &[f64],
    values: &[f64],
    to: &[f64],
) -> Result<Vec<f64>, SolverError> {
    let n = from.len().saturating_sub(1);
    if n < 2 || to.len() < 3 {
        return Err(SolverError::InvalidInput(format!(
            "a prolongation needs at least two cells on each mesh (got {} and {})",
            n,
            to.len().saturating_sub(1)
        )));
    }
    if values.len() != 2 * n {
        return Err(SolverError::WrongLength {
            expected: 2 * n,
            found: values.len(),
        });
    }
    let m = (2 * n) as isize;
    // Old Gauss point `a` (any integer, periodic) as `(σ, value)`, `σ` unwrapped.
    let node = |a: isize| -> (f64, f64) {
        let turns = a.div_euclid(m);
        let a = a.rem_euclid(m) as usize;
        let c = a / 2;
        let s = from[c] + GAUSS_OFFSETS[a % 2] * (from[c + 1] - from[c]) + turns as f64;
        (s, values[a])
    };
    let cells = to.len() - 1;
    Ok((0..2 * cells)
        .map(|a| {
            let c = a / 2;
            let s = to[c] + GAUSS_OFFSETS[a % 2] * (to[c + 1] - to[c]);
            let k = from.partition_point(|&x| x <= s).clamp(1, n) - 1;
            let pts = [-1isize, 0, 1, 2].map(|j| node(2 * k as isize + j));
            pts.iter()
                .enumerate()
                .map(|(i, &(si, vi))| {
                    let w: f64 = pts
                        .iter()
                        .enumerate()
                        .filter(|&(j, _)| j != i)
                        .map(|(_, &(sj, _))| (s - sj) / (si - sj))
                        .product();
                    w * vi
                })
                .sum()
        })
        .collect())
}

impl Equilibrium {
    /// Geodesic curvature at the Gauss points of a grid of `cells` cells on the same mesh
    /// map, interpolated locally from the state's own Gauss values
    /// ([`prolong_gauss_values`]; see the module docs for why not [`Equilibrium::resample`]).
    pub fn prolong(&self, cells: usize) -> Result<Vec<f64>, SolverError> {
        let model = self.model();
        let to = model.mesh().bounds(cells)?;
        prolong_gauss_values(model.bounds(), self.kappa(), &to)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gauss_points(bounds: &[f64]) -> Vec<f64> {
        (0..2 * (bounds.len() - 1))
            .map(|a| {
                let c = a / 2;
                bounds[c] + GAUSS_OFFSETS[a % 2] * (bounds[c + 1] - bounds[c])
            })
            .collect()
    }

    /// Graded boundaries: `σ_i = u_i + a sin(2π u_i)/(2π)`, `u_i = i/n`.
    fn graded(n: usize, a: f64) -> Vec<f64> {
        (0..=n)
            .map(|i| {
                let u = i as f64 / n as f64;
                u + a * (2.0 * std::f64::consts::PI * u).sin() / (2.0 * std::f64::consts::PI)
            })
            .collect()
    }

    #[test]
    fn cubics_away_from_the_seam_are_reproduced_exactly() {
        let from = graded(40, 0.5);
        let to = graded(80, 0.5);
        let f = |s: f64| 0.3 - 1.7 * s + 2.2 * s * s - 0.9 * s * s * s;
        let values: Vec<f64> = gauss_points(&from).iter().map(|&s| f(s)).collect();
        let out = prolong_gauss_values(&from, &values, &to).unwrap();
        // A cubic in σ is not periodic: only points whose four nodes do not cross σ = 0.
        for (s, v) in gauss_points(&to).iter().zip(&out) {
            if *s > 0.1 && *s < 0.9 {
                assert!(
                    (v - f(*s)).abs() < 1e-12,
                    "at σ = {s}: {v} against {}",
                    f(*s)
                );
            }
        }
    }

    #[test]
    fn smooth_periodic_values_converge_at_fourth_order() {
        let errs: Vec<f64> = [20, 40, 80]
            .iter()
            .map(|&n| {
                let from = graded(n, 0.4);
                let to = graded(2 * n, 0.4);
                let values: Vec<f64> = gauss_points(&from).iter().map(|&s| p(s)).collect();
                let out = prolong_gauss_values(&from, &values, &to).unwrap();
                gauss_points(&to)
                    .iter()
                    .zip(&out)
                    .map(|(s, v)| (v - p(*s)).abs())
                    .fold(0.0, f64::max)
            })
            .collect();
        for w in errs.windows(2) {
            let order = (w[0] / w[1]).log2();
            assert!(order > 3.7, "errors {errs:?}: order {order}");
        }
    }

    /// A smooth 1-periodic function.
    fn p(s: f64) -> f64 {
        let t = 2.0 * std::f64::consts::PI * s;
        3.0 * t.sin() + (2.0 * t).cos() - 0.5 * (3.0 * t).sin()
    }

    #[test]
    fn a_jump_disturbs_only_the_cells_next_to_it() {
        let from = graded(64, 0.0);
        let to = graded(128, 0.0);
        let step = |s: f64| if (0.40..0.6).contains(&s) { 5.0 } else { 0.0 };
        let values: Vec<f64> = gauss_points(&from).iter().map(|&s| step(s)).collect();
        let out = prolong_gauss_values(&from, &values, &to).unwrap();
        for (s, v) in gauss_points(&to).iter().zip(&out) {
            let far = (s - 0.4).abs() > 2.0 / 64.0 && (s - 0.6).abs() > 2.0 / 64.0;
            if far {
                assert!((v - step(*s)).abs() < 1e-12, "at σ = {s}: {v}");
            }
        }
    }

    #[test]
    fn wrong_sizes_are_refused() {
        let from = graded(8, 0.0);
        assert!(prolong_gauss_values(&from, &[0.0; 15], &graded(16, 0.0)).is_err());
        assert!(prolong_gauss_values(&[0.0, 1.0], &[0.0; 2], &graded(16, 0.0)).is_err());
    }
}
