//! The `point_group` and `self_intersections` of every traced state agree with the exact
//! loop of the same branch at the same length (Sec. 3.1), wherever the exact answer does not
//! depend on the tolerance (away from the lengths where strands start to touch and from the
//! great-circle ends).

use rodloop_exact::paper_branch_loop;
use rodloop_exact::shape::{exact_loop_shape, ShapeTolerances};

use crate::common::{default_diagram, fast_diagram};

#[test]
fn traced_states_have_the_exact_loops_shapes() {
    for d in [fast_diagram(), default_diagram()] {
        let tol = d.shape_tolerance;
        let mut compared = 0;
        for r in d.rows() {
            let Ok(lp) = paper_branch_loop(r.eta, r.lbar) else {
                continue;
            };
            // The exact answer at half and twice the tolerance: compare only where it is the
            // same (a state within the tolerance of touching itself or of the great circle
            // is a matter of the tolerance, not of the model).
            let at = |f: f64| {
                exact_loop_shape(
                    &lp,
                    ShapeTolerances {
                        symmetry: f * tol.symmetry,
                        contact: f * tol.contact,
                    },
                )
                .map(|s| (s.point_group, s.self_intersections))
                .unwrap()
            };
            let (lo, hi) = (at(0.5), at(2.0));
            if lo != hi {
                continue;
            }
            assert_eq!(
                (r.shape.point_group.clone(), r.shape.self_intersections),
                (Some(lo.0.clone()), lo.1),
                "branch {} at L̄ = {}",
                r.branch,
                r.lbar
            );
            compared += 1;
        }
        let total = d.rows().len();
        eprintln!("{compared} of {total} states compared with the exact loops");
        assert!(compared * 10 >= total * 9, "{compared} of {total}");
    }
}
