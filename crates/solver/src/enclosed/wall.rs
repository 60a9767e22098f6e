//! The confining wall of the enclosed model: one constraint function `g(r) ≥ 0` with its
//! gradient and Hessian ([`Wall`]), and the paper's sphere ([`SphereWall`]).
//!
//! The paper confines the loop to the ball, `0 < ρ(s) ≤ R` (Sec. 2, the inequality stated
//! with the closure conditions Eq. (3); Sec. 3.2, `|r(s)| ≤ R`). The model writes it as
//! `g(r) = R² − |r|² ≥ 0` at the nodes (smooth at the centre, unlike `R − |r|`), with the
//! multiplier `λ_j ≥ 0` the nodal contact impulse: the line load `q` of Eq. (9) at node `j`
//! is `λ_j ∇g(r_j)/w_j` (`w_j` the node's share of the length), along the inward normal for
//! `λ > 0` (Eq. (38)'s sign).
//! Everything the model needs from the wall — the gap in the complementarity row, `∇g` in
//! the stationarity rows, `∇²g` in the Jacobian, the clearance in reports and the
//! inside-the-wall test of the verification — comes from this trait, so another confinement
//! is one more implementation.

use std::fmt::Debug;
use std::sync::Arc;

use nalgebra::{Matrix3, SMatrix, Vector3};

type V3 = Vector3<f64>;
type M3 = Matrix3<f64>;

/// The constraint of node `j` in the spatial-frame variables of the lifted Newton step
/// ([`super::lifted`]): node perturbation `δr_j = δr0 − hat(p_j)ω + v` for `ξ = (ω, v)`.
#[derive(Clone, Debug, PartialEq)]
pub struct NodePairing {
    /// `∇g(r_j)`.
    pub gradient: V3,
    /// `w_j = (p_j × ∇g, ∇g)`: `∇g` paired with `se(3)`, so `δg_j = w_j·ξ_j + ∇g·δr0`.
    pub w: [f64; 6],
    /// `∂w_j/∂ξ_j` (6×6).
    pub dw_xi: SMatrix<f64, 6, 6>,
    /// `∂w_j/∂r0` (6×3).
    pub dw_r0: SMatrix<f64, 6, 3>,
    /// `∂(∇g)/∂ξ_j = ∇²g [−hat(p_j) | I]` (3×6).
    pub dgrad_xi: SMatrix<f64, 3, 6>,
}

/// `hat(a) b = a × b`.
fn hat(a: &V3) -> M3 {
    M3::new(0.0, -a[2], a[1], a[2], 0.0, -a[0], -a[1], a[0], 0.0)
}

/// A confining wall `g(r) ≥ 0` (inside where `g > 0`, see the module docs).
pub trait Wall: Debug + Send + Sync {
    /// The length scale `R` of the scene (the unit of lengths, forces and energies).
    fn radius(&self) -> f64;

    /// The constraint function `g(r)`, `≥ 0` inside.
    fn gap(&self, r: &V3) -> f64;

    /// `∇g(r)`.
    fn gradient(&self, r: &V3) -> V3;

    /// `∇²g(r)`.
    fn hessian(&self, r: &V3) -> M3;

    /// The clearance of `r` in units of length, positive inside and zero on the wall (the
    /// distance to the wall along the normal to first order): the gaps a state reports and
    /// the touch tests read.
    fn clearance(&self, r: &V3) -> f64;

    /// The wall as state files name it and pictures draw it: its shape and the semi-axes
    /// along `x, y, z` of the ellipsoid about the origin drawn as its outline (the sphere:
    /// `("sphere", [R, R, R])`).
    fn outline(&self) -> (&'static str, [f64; 3]);

    /// `Some(R)` when the wall is the sphere of radius `R` about the origin, where the
    /// paper's surface loops with `λ ≥ 0` are enclosed states (Sec. 3.2); `None` for any
    /// other wall.
    fn sphere(&self) -> Option<f64> {
        None
    }

    /// `|∇g|` at the point of the wall nearest `r`: what turns a wall impulse at a node into
    /// the contact force density it stands for (`λ_j |∇g| / w_j`) when the node lies off the
    /// wall by an interpolation error, as a prolonged node does. The default is the node's own
    /// `|∇g(r)|`, exact on the wall.
    fn gradient_norm_on_wall(&self, r: &V3) -> f64 {
        self.gradient(r).norm()
    }

    /// `true` when `r` lies inside the wall up to `slack` (a fraction of [`Self::radius`]).
    fn contains(&self, r: &V3, slack: f64) -> bool {
        self.clearance(r) >= -slack * self.radius()
    }

    /// The pairing of node `j` at `r = r0 + p` for the lifted step ([`NodePairing`]), from
    /// [`Self::gradient`] and [`Self::hessian`]: with `G = ∇g`, `H = ∇²g`,
    /// `δ(p × G) = −hat(G)δp + hat(p)Hδr`, `δG = Hδr`.
    fn node_pairing(&self, r0: &V3, p: &V3) -> NodePairing {
        let r = r0 + p;
        let g = self.gradient(&r);
        let h = self.hessian(&r);
        let (hg, hp) = (hat(&g), hat(p));
        let pc = p.cross(&g);
        let mut dw_xi = SMatrix::<f64, 6, 6>::zeros();
        let mut dw_r0 = SMatrix::<f64, 6, 3>::zeros();
        let mut dgrad_xi = SMatrix::<f64, 3, 6>::zeros();
        let hhp = h * hp;
        dw_xi
            .fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&(hg * hp - hp * hhp));
        dw_xi.fixed_view_mut::<3, 3>(0, 3).copy_from(&(hp * h - hg));
        dw_xi.fixed_view_mut::<3, 3>(3, 0).copy_from(&(-hhp));
        dw_xi.fixed_view_mut::<3, 3>(3, 3).copy_from(&h);
        dw_r0.fixed_view_mut::<3, 3>(0, 0).copy_from(&(hp * h));
        dw_r0.fixed_view_mut::<3, 3>(3, 0).copy_from(&h);
        dgrad_xi.fixed_view_mut::<3, 3>(0, 0).copy_from(&(-hhp));
        dgrad_xi.fixed_view_mut::<3, 3>(0, 3).copy_from(&h);
        NodePairing {
            gradient: g,
            w: [pc[0], pc[1], pc[2], g[0], g[1], g[2]],
            dw_xi,
            dw_r0,
            dgrad_xi,
        }
    }
}

/// What the enclosed model and its starts are built from: a wall, or a radius for the paper's
/// sphere of that radius ([`SphereWall`]), so that a caller with a wall hands it on and a
/// caller in the ball writes its radius.
pub trait IntoWall {
    /// The wall.
    fn into_wall(self) -> Arc<dyn Wall>;
}

impl IntoWall for Arc<dyn Wall> {
    fn into_wall(self) -> Arc<dyn Wall> {
        self
    }
}

impl IntoWall for &Arc<dyn Wall> {
    fn into_wall(self) -> Arc<dyn Wall> {
        self.clone()
    }
}

impl IntoWall for SphereWall {
    fn into_wall(self) -> Arc<dyn Wall> {
        Arc::new(self)
    }
}

/// The sphere of radius `self`.
impl IntoWall for f64 {
    fn into_wall(self) -> Arc<dyn Wall> {
        Arc::new(SphereWall { radius: self })
    }
}

/// The paper's wall: the sphere of radius `R` about the origin, `g = R² − |r|²`,
/// `∇g = −2r`, `∇²g = −2I`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SphereWall {
    /// `R`.
    pub radius: f64,
}

impl Wall for SphereWall {
    fn radius(&self) -> f64 {
        self.radius
    }

    #[inline]
    fn gap(&self, r: &V3) -> f64 {
        self.radius * self.radius - r.norm_squared()
    }

    #[inline]
    fn gradient(&self, r: &V3) -> V3 {
        r * -2.0
    }

    #[inline]
    fn hessian(&self, _r: &V3) -> M3 {
        M3::identity() * -2.0
    }

    /// `R − |r|`.
    fn clearance(&self, r: &V3) -> f64 {
        self.radius - r.norm()
    }

    fn outline(&self) -> (&'static str, [f64; 3]) {
        ("sphere", [self.radius; 3])
    }

    fn sphere(&self) -> Option<f64> {
        Some(self.radius)
    }

    /// `2R`: `|∇g| = 2|r|` is `2R` everywhere on the sphere.
    fn gradient_norm_on_wall(&self, _r: &V3) -> f64 {
        2.0 * self.radius
    }

    /// The closed form of [`Wall::node_pairing`] for `∇²g = −2I`: with `r − p = r0`,
    /// `δ(p × r) = −hat(r0)δp`; `w = −2(p × r, r)`.
    fn node_pairing(&self, r0: &V3, p: &V3) -> NodePairing {
        let r = r0 + p;
        let u = p.cross(&r);
        let hr0 = hat(r0);
        let hp = hat(p);
        let mut du_xi = SMatrix::<f64, 6, 6>::zeros();
        let mut du_r0 = SMatrix::<f64, 6, 3>::zeros();
        du_xi.fixed_view_mut::<3, 3>(0, 0).copy_from(&(hr0 * hp));
        du_xi.fixed_view_mut::<3, 3>(0, 3).copy_from(&(-hr0));
        du_xi.fixed_view_mut::<3, 3>(3, 0).copy_from(&(-hp));
        du_xi
            .fixed_view_mut::<3, 3>(3, 3)
            .copy_from(&M3::identity());
        du_r0.fixed_view_mut::<3, 3>(0, 0).copy_from(&hp);
        du_r0
            .fixed_view_mut::<3, 3>(3, 0)
            .copy_from(&M3::identity());
        let mut dgrad_xi = SMatrix::<f64, 3, 6>::zeros();
        dgrad_xi.fixed_view_mut::<3, 3>(0, 0).copy_from(&(hp * 2.0));
        dgrad_xi
            .fixed_view_mut::<3, 3>(0, 3)
            .copy_from(&(M3::identity() * -2.0));
        NodePairing {
            gradient: r * -2.0,
            w: [
                -2.0 * u[0],
                -2.0 * u[1],
                -2.0 * u[2],
                -2.0 * r[0],
                -2.0 * r[1],
                -2.0 * r[2],
            ],
            dw_xi: du_xi * -2.0,
            dw_r0: du_r0 * -2.0,
            dgrad_xi,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::enclosed::lifted::tests::filler;

    /// A wall with only the three required derivatives: it takes the default
    /// [`Wall::node_pairing`] (the general formula an ellipsoid would use).
    #[derive(Debug)]
    struct Generic(SphereWall);

    impl Wall for Generic {
        fn radius(&self) -> f64 {
            self.0.radius
        }
        fn gap(&self, r: &V3) -> f64 {
            self.0.gap(r)
        }
        fn gradient(&self, r: &V3) -> V3 {
            self.0.gradient(r)
        }
        fn hessian(&self, r: &V3) -> M3 {
            self.0.hessian(r)
        }
        fn clearance(&self, r: &V3) -> f64 {
            self.0.clearance(r)
        }
        fn outline(&self) -> (&'static str, [f64; 3]) {
            self.0.outline()
        }
    }

    fn random_point(rnd: &mut impl FnMut() -> f64, scale: f64) -> V3 {
        V3::new(rnd(), rnd(), rnd()) * scale
    }

    #[test]
    fn sphere_gap_is_r_squared_minus_norm_squared() {
        let mut rnd = filler(11);
        for _ in 0..50 {
            let radius = 0.5 + 2.0 * rnd().abs();
            let w = SphereWall { radius };
            let r = random_point(&mut rnd, 2.0 * radius);
            let want = radius * radius - (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
            assert!((w.gap(&r) - want).abs() <= 1e-14 * radius * radius);
            // The clearance has the gap's sign and vanishes with it: g = (R − |r|)(R + |r|).
            let c = w.clearance(&r);
            assert!((c * (radius + r.norm()) - w.gap(&r)).abs() <= 1e-13 * radius * radius);
            assert_eq!(w.contains(&r, 0.0), want >= 0.0);
        }
        let w = SphereWall { radius: 1.5 };
        assert_eq!(w.gap(&V3::new(0.0, 1.5, 0.0)), 0.0);
        assert_eq!(w.gap(&V3::zeros()), 2.25);
    }

    /// Gradient and Hessian against central differences of `gap` and `gradient`.
    #[test]
    fn sphere_derivatives_match_central_differences() {
        let mut rnd = filler(7);
        for _ in 0..40 {
            let radius = 0.5 + 2.0 * rnd().abs();
            let w = SphereWall { radius };
            let r = random_point(&mut rnd, 1.5 * radius);
            let h = 1e-5 * radius;
            let g = w.gradient(&r);
            let hess = w.hessian(&r);
            for k in 0..3 {
                let mut e = V3::zeros();
                e[k] = h;
                let fd = (w.gap(&(r + e)) - w.gap(&(r - e))) / (2.0 * h);
                assert!(
                    (fd - g[k]).abs() <= 1e-8 * radius,
                    "∂g/∂r{k}: {fd} vs {}",
                    g[k]
                );
                let fd2 = (w.gradient(&(r + e)) - w.gradient(&(r - e))) / (2.0 * h);
                for l in 0..3 {
                    assert!((fd2[l] - hess[(l, k)]).abs() <= 1e-8, "∂²g/∂r{l}∂r{k}");
                }
            }
        }
    }

    /// The sphere's closed-form pairing equals the general one, and the general one is the
    /// derivative of `w` (central differences in `ξ` and `r0`).
    #[test]
    fn node_pairing_is_consistent_and_differentiates_w() {
        let mut rnd = filler(3);
        for _ in 0..30 {
            let radius = 0.5 + rnd().abs();
            let sphere = SphereWall { radius };
            let general = Generic(sphere);
            let r0 = random_point(&mut rnd, radius);
            let p = random_point(&mut rnd, radius);
            let a = sphere.node_pairing(&r0, &p);
            let b = general.node_pairing(&r0, &p);
            let close = |x: f64, y: f64| (x - y).abs() <= 1e-13 * (1.0 + x.abs());
            assert!((a.gradient - b.gradient).norm() <= 1e-14 * radius);
            assert!(a.w.iter().zip(&b.w).all(|(x, y)| close(*x, *y)));
            assert!(a
                .dw_xi
                .iter()
                .zip(b.dw_xi.iter())
                .all(|(x, y)| close(*x, *y)));
            assert!(a
                .dw_r0
                .iter()
                .zip(b.dw_r0.iter())
                .all(|(x, y)| close(*x, *y)));
            assert!(a
                .dgrad_xi
                .iter()
                .zip(b.dgrad_xi.iter())
                .all(|(x, y)| close(*x, *y)));
            // δp = −hat(p)ω + v moves p; δr0 moves r0. Central differences of (w, ∇g).
            let eps = 1e-6;
            for l in 0..9 {
                let shift = |s: f64| {
                    let (mut q0, mut q) = (r0, p);
                    if l < 3 {
                        let mut om = V3::zeros();
                        om[l] = s;
                        q += om.cross(&p);
                    } else if l < 6 {
                        q[l - 3] += s;
                    } else {
                        q0[l - 6] += s;
                    }
                    let np = general.node_pairing(&q0, &q);
                    (np.w, np.gradient)
                };
                let (wp, gp) = shift(eps);
                let (wm, gm) = shift(-eps);
                for k in 0..6 {
                    let fd = (wp[k] - wm[k]) / (2.0 * eps);
                    let an = if l < 6 {
                        b.dw_xi[(k, l)]
                    } else {
                        b.dw_r0[(k, l - 6)]
                    };
                    assert!((fd - an).abs() <= 1e-7 * (1.0 + an.abs()), "∂w{k}/∂{l}");
                }
                if l < 6 {
                    for k in 0..3 {
                        let fd = (gp[k] - gm[k]) / (2.0 * eps);
                        let an = b.dgrad_xi[(k, l)];
                        assert!((fd - an).abs() <= 1e-7 * (1.0 + an.abs()), "∂G{k}/∂ξ{l}");
                    }
                }
            }
        }
    }
}
