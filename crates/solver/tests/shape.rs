//! Shape descriptors of numeric states (point group, self-intersections) against the exact
//! loops at the same `(η, L̄)` (Sec. 3.1), at the coarsest resolutions the diagram traces
//! with, and the sub-cell positions they are computed from.

mod common;

use common::solve_uniform;
use rodloop_exact::shape::{exact_loop_shape, ShapeTolerances};
use rodloop_solver::{Accuracy, StartShape, Stiffness};

#[test]
fn numeric_states_have_the_exact_loops_groups_and_crossings() {
    let tol = ShapeTolerances::default();
    for (eta, lbar) in [(2, 1.2), (1, 1.7), (3, 2.2), (2, 2.6), (2, 2.8), (4, 3.5)] {
        let exact =
            exact_loop_shape(&rodloop_exact::paper_branch_loop(eta, lbar).unwrap(), tol).unwrap();
        // The diagram's coarsest tracing resolution, 8 (η + 1) cells, and the fast accuracy.
        let fast = Accuracy::Fast.cells(eta as usize, &Stiffness::uniform(1.0));
        for cells in [8 * (eta as usize + 1), fast] {
            let eq = solve_uniform(eta, lbar, cells, &StartShape::Euler { l: eta });
            let sh = eq.model().shape(eq.kappa(), tol).unwrap();
            eprintln!(
                "eta {eta} lbar {lbar} cells {cells}: {} residual {:.1e}, {:?} crossings",
                sh.point_group, sh.symmetry_residual, sh.self_intersections
            );
            assert_eq!(sh.point_group, exact.point_group, "eta {eta} lbar {lbar}");
            assert_eq!(sh.group_order, exact.group_order);
            assert_eq!(sh.self_intersections, exact.self_intersections);
            // The symmetry holds to the discretisation error, far inside the tolerance.
            assert!(sh.symmetry_residual < 0.1 * tol.symmetry);
        }
    }
}

/// The sub-cell positions lie on the sphere, start at the model's cell-boundary frames, and
/// every chord between neighbours is at most its arclength and falls short of it by no more
/// than the chord deficit `κ² h³/24` (unit speed, no kinks), up to 1e-4 R: a tenth of the
/// shape tolerance, which bounds the mismatch where a cell's sub-steps meet the next
/// cell's boundary frame.
#[test]
fn sub_cell_positions_follow_the_curve() {
    let (eta, lbar) = (2, 1.2);
    let cells = 24;
    let eq = solve_uniform(eta, lbar, cells, &StartShape::Euler { l: eta });
    let model = eq.model();
    let frames = model.frames(eq.kappa()).unwrap();
    let kmax = eq.kappa().iter().fold(0.0f64, |a, v| a.max(v.abs()));
    for per in [1usize, 4, 16] {
        let (s, r) = model.positions(eq.kappa(), per).unwrap();
        assert_eq!(s.len(), cells * per);
        for (k, p) in r.iter().enumerate() {
            assert!((p.norm() - 1.0).abs() < 1e-13);
            if k % per == 0 {
                let f = frames[k / per];
                let q = nalgebra::Vector3::new(f[(2, 0)], f[(2, 1)], f[(2, 2)]);
                assert!((p - q).norm() < 1e-14);
            }
        }
        let n = r.len();
        let len = model.length();
        let mut worst: f64 = 0.0;
        for i in 0..n {
            let h = if i + 1 < n {
                s[i + 1] - s[i]
            } else {
                len - s[i]
            };
            let chord = (r[(i + 1) % n] - r[i]).norm();
            let deficit = (1.0 + kmax * kmax) * h * h * h / 24.0;
            worst = worst.max((chord - h).max(h - deficit - chord));
        }
        eprintln!("per cell {per}: worst chord excess {worst:.2e}");
        assert!(worst < 1e-4, "{worst}");
    }
}
