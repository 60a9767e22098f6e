//! The enclosed model inside a wall other than the sphere: the KKT Jacobian and the lifted
//! Newton step read `g`, `∇g` and `∇²g` from the model's [`Wall`] only. A quadric wall
//! `g = R² − rᵀAr` with a full symmetric `A` (`∇g = −2Ar`, `∇²g = −2A`, off-diagonal
//! Hessian entries) checks the general terms the sphere's `−2I` leaves out.

mod common;

use std::sync::Arc;

use nalgebra::{Matrix3, Vector3};
use rodloop_exact::paper_branch_loop;
use rodloop_solver::enclosed::{
    solve_branch, start_from_surface, EnclosedModel, EnclosedOptions, SphereWall, SurfaceSource,
    Wall,
};
use rodloop_solver::Stiffness;

/// `g = R² − rᵀAr` (`A` symmetric positive definite).
#[derive(Debug)]
struct Quadric {
    radius: f64,
    a: Matrix3<f64>,
}

impl Wall for Quadric {
    fn radius(&self) -> f64 {
        self.radius
    }
    fn gap(&self, r: &Vector3<f64>) -> f64 {
        self.radius * self.radius - r.dot(&(self.a * r))
    }
    fn gradient(&self, r: &Vector3<f64>) -> Vector3<f64> {
        self.a * r * -2.0
    }
    fn hessian(&self, _r: &Vector3<f64>) -> Matrix3<f64> {
        self.a * -2.0
    }
    fn clearance(&self, r: &Vector3<f64>) -> f64 {
        self.gap(r) / self.gradient(r).norm().max(self.radius)
    }
    fn outline(&self) -> (&'static str, [f64; 3]) {
        ("quadric", [self.radius; 3])
    }
}

fn quadric() -> Arc<dyn Wall> {
    Arc::new(Quadric {
        radius: 1.0,
        a: Matrix3::new(1.10, 0.07, -0.04, 0.07, 0.92, 0.05, -0.04, 0.05, 1.01),
    })
}

/// A perturbed state of branch 1 at `L̄ = 1.5` inside the quadric, with mixed contact rows.
fn state(cells: usize, stiff: &Stiffness) -> (EnclosedModel, Vec<f64>) {
    let l = paper_branch_loop(1, 1.5).unwrap();
    let (m, mut z) = start_from_surface(1.0, 1.5, cells, stiff, |s| {
        l.point(s * l.length()).unwrap().kappa_g
    })
    .unwrap();
    let m = m.with_wall(quadric()).unwrap();
    for (i, v) in z.iter_mut().enumerate() {
        *v += 0.01 * ((i as f64 * 1.7).sin());
    }
    let lo = m.lambda_offset();
    for j in 0..m.cells() {
        z[lo + j] = if j % 3 == 0 {
            -0.05
        } else {
            0.3 + 0.01 * j as f64
        };
    }
    (m, z)
}

fn stiffnesses() -> [Stiffness; 2] {
    [Stiffness::uniform(1.0), common::mild_two_segment()]
}

/// The semismooth Jacobian inside the quadric against central differences of the residual.
#[test]
fn jacobian_inside_a_quadric_matches_finite_differences() {
    for stiff in stiffnesses() {
        let (m, z) = state(10, &stiff);
        let active = m.wall_active(&z).unwrap();
        assert!(active.iter().any(|&a| a) && active.iter().any(|&a| !a));
        let ev = m.evaluate(&z).unwrap();
        let eps = 1e-6;
        let mut worst: f64 = 0.0;
        for k in 0..m.dim() {
            let mut zp = z.clone();
            let mut zm = z.clone();
            zp[k] += eps;
            zm[k] -= eps;
            let fd = (m.residual(&zp).unwrap() - m.residual(&zm).unwrap()) / (2.0 * eps);
            for i in 0..m.dim() {
                let scale = 1.0 + ev.jacobian[(i, k)].abs();
                worst = worst.max((fd[i] - ev.jacobian[(i, k)]).abs() / scale);
            }
        }
        assert!(worst < 1e-6, "{stiff:?}: worst FD mismatch {worst:e}");
    }
}

/// The lifted `O(N)` step inside the quadric (the general node pairing of
/// `Wall::node_pairing`) is the dense semismooth Newton step.
#[test]
fn lifted_step_inside_a_quadric_equals_dense_step() {
    for (stiff, cells) in stiffnesses().into_iter().zip([12, 20]) {
        let (m, z) = state(cells, &stiff);
        let ev = m.evaluate(&z).unwrap();
        let dense = ev.jacobian.clone().lu().solve(&(-&ev.residual)).unwrap();
        let (f, step) = m.newton_step(&z).unwrap();
        assert!((&f - &ev.residual).amax() < 1e-13 * (1.0 + f.amax()));
        let err = (&step - &dense).amax() / dense.amax();
        assert!(err < 1e-9, "cells {cells}: lifted vs dense step {err:e}");
    }
}

/// The quadric changes the residual (the wall rows and the wall force read it), and a model
/// rebuilt at another length keeps the wall.
#[test]
fn the_wall_enters_the_residual_and_survives_a_rebuild() {
    let stiff = Stiffness::uniform(1.0);
    let (m, z) = state(12, &stiff);
    let sphere = EnclosedModel::new(1.0, 1.5, 12, &stiff, m.gauge().clone()).unwrap();
    let diff = (m.residual(&z).unwrap() - sphere.residual(&z).unwrap()).amax();
    assert!(
        diff > 1e-3,
        "the quadric's residual equals the sphere's ({diff:e})"
    );
    let again = m.rebuilt(1.6, 12, &stiff, m.gauge().clone()).unwrap();
    let r = Vector3::new(0.3, -0.2, 0.9);
    assert_eq!(again.wall().gap(&r), m.wall().gap(&r));
    assert_ne!(again.wall().gap(&r), sphere.wall().gap(&r));
}

/// The contact force `λ_j |∇g(r_j)|/w_j` is the sphere's `2Rλ_j/w_j` on states solved in the
/// sphere (the figure-eight at `L̄ = 1.4`, lifted off in places: touching nodes lie on the
/// wall to the solve's tolerance, free ones carry `λ_j = 0`), given as a radius or as the
/// wall, in two radii.
#[test]
fn contact_force_on_the_sphere_is_two_r_lambda_over_w() {
    let stiff = Stiffness::uniform(1.0);
    for radius in [1.0, 2.5] {
        let l = paper_branch_loop(1, 1.4).unwrap();
        let src = SurfaceSource::Exact(l);
        let opts = EnclosedOptions::default();
        let by_radius = solve_branch(radius, 1.4, &stiff, &src, 64, &opts).unwrap();
        let wall: Arc<dyn Wall> = Arc::new(SphereWall { radius });
        let by_wall = solve_branch(&wall, 1.4, &stiff, &src, 64, &opts).unwrap();
        assert_eq!(by_radius.energy, by_wall.energy);
        let (m, z) = (&by_wall.fine.model, &by_wall.fine.z);
        let force = m.contact_force(z);
        let lo = m.lambda_offset();
        let gaps = m.gaps(z).unwrap();
        let peak = force.iter().fold(0.0f64, |a, f| a.max(f.abs()));
        let (mut touching, mut free) = (0, 0);
        for (j, f) in force.iter().enumerate() {
            // `|∇g| = 2|r_j| = 2(R − gap_j)`: the two differ by the node's gap, which the
            // semismooth Newton closes to its tolerance where the loop touches.
            let sphere = 2.0 * radius * z[lo + j] / m.node_weight(j);
            assert!(
                (f - sphere * (1.0 - gaps[j] / radius)).abs() <= 1e-14 * peak,
                "R = {radius}, node {j}: {f} vs 2(R - gap) lambda/w"
            );
            assert!(
                (f - sphere).abs() <= 1e-10 * peak,
                "R = {radius}, node {j}: {f} vs 2R lambda/w = {sphere}"
            );
            if gaps[j] <= 1e-9 * radius {
                touching += 1;
            } else {
                free += 1;
            }
        }
        assert!(
            touching > 0 && free > 0,
            "R = {radius}: {touching} touching, {free} free"
        );
    }
}

/// `|∇g|` at the nearest wall point: the sphere's `2R` is the norm of its gradient at the
/// radial projection of any point; a wall without its own rule (the quadric) gives the
/// point's own `|∇g|`.
#[test]
fn gradient_norm_on_the_wall() {
    let sphere = SphereWall { radius: 1.3 };
    let q = quadric();
    for r in [
        Vector3::new(0.2, -0.9, 0.4),
        Vector3::new(1.1, 0.3, -0.5),
        Vector3::new(-0.05, 0.02, 1.2),
    ] {
        let on = r * (sphere.radius / r.norm());
        let want = sphere.gradient(&on).norm();
        assert!((sphere.gradient_norm_on_wall(&r) - want).abs() <= 1e-14 * want);
        assert_eq!(q.gradient_norm_on_wall(&r), q.gradient(&r).norm());
    }
}
