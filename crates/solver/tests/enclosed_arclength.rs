//! Pseudo-arclength continuation of an enclosed family at a fixed contact set
//! (`rodloop_solver::enclosed::arclength`): the smooth piece's Jacobian against central
//! differences, the contact set carried to other parameter values, a fold of the two-segment
//! rod's branch 1 on 64 cells (`D1/D0 = 0.5`, Sec. 5) that natural-parameter steps in `L̄`
//! cannot pass, checked by independent semismooth re-solves on both of its sides and by the
//! index changing across it, and the `O(N)` factorisation against the dense one.

mod common;
use nalgebra::DVector;
use rodloop_continuation::{
    fd_jacobian, Continuation, DenseLu, Factorization, Problem, PseudoArclength, SpecialKind,
    StopReason,
};
use rodloop_solver::enclosed::arclength::{
    contact_slack, follow_contacts, node_slacks, ContactRunEnd,
};
use rodloop_solver::enclosed::lifted_factor::LiftedFactor;
use rodloop_solver::enclosed::{
    solve_branch, solve_enclosed, EnclosedOptions, EnclosedState, SurfaceSource,
};
use rodloop_solver::{
    solve_robust, Accuracy, Confinement, Param, ParamProblem, SolveOptions, StartShape, Stiffness,
};

/// The enclosed branch-1 state (`η = 2`) of the paper's two-segment rod at `lbar` on
/// `cells` cells, solved from its surface loop as `rodloop solve` does.
fn branch_one(lbar: f64, cells: usize) -> (Stiffness, EnclosedState) {
    let stiffness = Stiffness::paper_sec5(0.5);
    let (res, _) = solve_robust(
        1.0,
        lbar,
        &stiffness,
        &StartShape::Euler { l: 2 },
        Accuracy::Default,
        Some(2),
        &SolveOptions::default(),
    )
    .expect("surface loop of branch 1");
    let src = SurfaceSource::Numeric(Box::new(res.equilibrium));
    let b = solve_branch(
        1.0,
        lbar,
        &stiffness,
        &src,
        cells,
        &EnclosedOptions::default(),
    )
    .expect("enclosed branch-1 state");
    (stiffness, b.fine)
}

#[test]
fn the_fixed_contact_set_is_a_smooth_system_with_the_state_as_a_root() {
    let (_, state) = branch_one(2.24, 32);
    let set = state.model.wall_active(&state.z).unwrap();
    assert!(set.iter().any(|&on| on) && set.iter().any(|&on| !on));
    let fixed = state.model.clone().with_contact_set(set.clone()).unwrap();
    // The state is a root of its own piece, as of the min-function.
    let f = Confinement::residual(&fixed, &state.z).unwrap();
    assert!(
        fixed.residual_norm(&f) < 1e-9,
        "{}",
        fixed.residual_norm(&f)
    );
    assert!(contact_slack(&fixed, &state.z).unwrap() > 0.0);
    // The contact set is carried to another length.
    let other = Confinement::with_param(&fixed, Param::Lbar, 2.25).unwrap();
    assert_eq!(other.contact_set(), Some(set.as_slice()));
    // Away from the state (where `min` would pick other rows at some nodes), the piece's
    // Jacobian is the derivative of its residual.
    let problem = ParamProblem::new(fixed, Param::Lbar).unwrap();
    let mut x = DVector::from_column_slice(&state.z);
    for (i, v) in x.iter_mut().enumerate() {
        *v += 1e-3 * ((i as f64) * 0.7).sin();
    }
    let jac = problem.jacobian(&x, 2.24).unwrap();
    let fd = fd_jacobian(|v: &DVector<f64>| problem.residual(v, 2.24), &x).unwrap();
    let err = (&jac - &fd).amax();
    assert!(err < 1e-7 * jac.amax(), "{err:e} of {:e}", jac.amax());
}

#[test]
fn branch_one_folds_and_both_sides_are_equilibria_of_the_wall() {
    let cells = 64;
    let lbar = 2.24;
    let (stiffness, state) = branch_one(lbar, cells);
    assert_eq!(state.index(1e-6).unwrap(), 0);
    let set = state.model.wall_active(&state.z).unwrap();
    let fixed = state.model.clone().with_contact_set(set).unwrap();
    let problem = ParamProblem::new(fixed, Param::Lbar).unwrap();
    // Short steps (at most 0.02 in the norm of `(z, L̄)`): longer ones let the corrector
    // land on other parts of the curve where an eigenvalue nearly vanishes.
    let settings = PseudoArclength::new()
        .with_ds(0.01)
        .unwrap()
        .with_ds_bounds(1e-7, 0.02)
        .unwrap()
        .with_tol(1e-9)
        .unwrap()
        .with_range(lbar - 0.2, lbar + 0.2)
        .unwrap()
        .with_max_steps(200)
        .unwrap();
    let slack = |x: &DVector<f64>, p: f64| {
        let m = problem.model_at(p).unwrap();
        contact_slack(&m, x.as_slice()).unwrap()
    };
    let run = Continuation::new(&problem, settings).with_event("contact slack", slack);
    let branch = run
        .run(&DVector::from_column_slice(&state.z), lbar)
        .unwrap();
    let fold = branch
        .special
        .iter()
        .find(|s| s.kind == SpecialKind::Fold)
        .expect("a fold of branch 1");
    assert!(fold.p > lbar && fold.p < lbar + 0.1, "fold at {}", fold.p);
    assert!(slack(&fold.x, fold.p) > 0.0, "the fold lies on the piece");
    // The first contact change after the fold ends the piece's equilibria.
    let end = branch
        .special
        .iter()
        .find(|s| matches!(s.kind, SpecialKind::Event { .. }) && s.s > fold.s)
        .map_or(f64::INFINITY, |s| s.s);
    // Points before and after the fold on the piece, within 1e-2 of it in L̄.
    let near = |after: bool| {
        branch
            .points
            .iter()
            .filter(|q| (q.s > fold.s) == after && q.s < end && fold.p - q.p < 1e-2)
            .min_by(|a, b| (fold.p - a.p).total_cmp(&(fold.p - b.p)))
            .unwrap_or_else(|| {
                panic!(
                    "a point {} the fold",
                    if after { "after" } else { "before" }
                )
            })
            .clone()
    };
    let (below, above) = (near(false), near(true));
    for (q, index) in [(&below, 0), (&above, 1)] {
        assert!(q.p < fold.p);
        // The wall model at this length, no contact set fixed.
        let m = problem.model();
        let model = m
            .rebuilt(q.p, cells, &stiffness, m.gauge().clone())
            .unwrap();
        assert_eq!(model.contact_set(), None);
        let at = EnclosedState {
            model: model.clone(),
            z: q.x.as_slice().to_vec(),
            iterations: 0,
            residual: 0.0,
        };
        // The index changes across the fold (the lowest eigenvalue of the tangent Hessian
        // goes through zero there).
        assert_eq!(at.index(1e-6).unwrap(), index, "L̄ = {}", q.p);
        // An independent semismooth solve of the wall model (min-function, its own contact
        // set) from the continued state stays there: an equilibrium of the wall.
        let again = solve_enclosed(&model, at.z.clone(), &EnclosedOptions::default())
            .expect("semismooth re-solve");
        let (e, e_again) = (at.energy(), again.energy());
        assert!((e - e_again).abs() < 1e-10, "L̄ = {}: {e} vs {e_again}", q.p);
        let dz =
            at.z.iter()
                .zip(&again.z)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
        assert!(dz < 1e-6, "L̄ = {}: the re-solve moved by {dz:e}", q.p);
    }
}

/// The lifted `O(N)` factorisation against the dense LU of the same Jacobian, on states
/// away from equilibrium with mixed contact rows (min-function and a fixed contact set):
/// solves with a dense right-hand side, products `J v`, `ln|det J|`, and the sign of the
/// determinant up to one factor per mesh.
#[test]
fn the_lifted_factorisation_is_the_dense_one() {
    let (_, state) = branch_one(2.24, 32);
    let set = state.model.wall_active(&state.z).unwrap();
    let mut signs = Vec::new();
    for (case, fixed) in [(0, false), (1, false), (2, true)] {
        let mut model = state.model.clone();
        if fixed {
            model = model.with_contact_set(set.clone()).unwrap();
        }
        let mut z = state.z.clone();
        for (i, v) in z.iter_mut().enumerate() {
            *v += 0.01 * ((i as f64 * (1.3 + case as f64)).sin());
        }
        let lo = model.lambda_offset();
        for j in (0..model.cells()).filter(|j| j % 3 == case) {
            z[lo + j] = -0.05;
        }
        let dense = DenseLu::new(Confinement::jacobian(&model, &z).unwrap());
        let lifted = LiftedFactor::new(&model, &z).unwrap();
        let b = DVector::from_fn(model.dim(), |i, _| ((i * 7 + case) as f64 * 0.37).cos());
        let (xd, xl) = (dense.solve(&b).unwrap(), lifted.solve(&b).unwrap());
        let err = (&xd - &xl).amax() / xd.amax();
        assert!(err < 1e-9, "case {case}: solve {err:e}");
        let (yd, yl) = (dense.apply(&b), lifted.apply(&b));
        let err = (&yd - &yl).amax() / yd.amax();
        assert!(err < 1e-12, "case {case}: apply {err:e}");
        let (ld, ll) = (dense.log_abs_det(), lifted.log_abs_det());
        assert!(
            (ld - ll).abs() < 1e-8 * ld.abs().max(1.0),
            "case {case}: {ld} vs {ll}"
        );
        signs.push(dense.det_sign() * lifted.det_sign());
    }
    assert!(signs.iter().all(|&s| s == signs[0]), "{signs:?}");
}

/// Pseudo-arclength across contact changes: the lifted-off figure-eight followed from
/// `L̄ = 1.40` to 1.43, where its contact set changes near `L̄ = 1.4198` (nodes touch down
/// with zero force; the bordered corrector on the min-function stalls there), reaches the
/// state that the enclosed tracer's semismooth Newton steps reach at 1.43 (energy to 1e-9),
/// and every continued point lies inside its piece (impulses on the set and gaps off it
/// nonnegative).
#[test]
fn the_figure_eight_is_followed_across_its_contact_changes() {
    let start = common::enclosed_figure_eight(1.40, 64);
    let settings = PseudoArclength::new()
        .with_ds(0.005)
        .unwrap()
        .with_ds_bounds(1e-7, 0.01)
        .unwrap()
        .with_tol(1e-10)
        .unwrap()
        .with_range(1.39, 1.43)
        .unwrap();
    let (pieces, end) = follow_contacts(&start, Param::Lbar, &settings, 20).unwrap();
    assert_eq!(
        end,
        ContactRunEnd::Stopped(StopReason::LeftRange { boundary: 1.43 })
    );
    assert!(pieces.len() >= 2, "{} piece(s)", pieces.len());
    let first_end = pieces[1].points[0].p;
    assert!(
        (first_end - 1.4198).abs() < 1e-3,
        "first switch at {first_end}"
    );
    for piece in &pieces {
        let model = start
            .model
            .clone()
            .with_contact_set(piece.contact.clone())
            .unwrap();
        for q in &piece.points {
            let m = Confinement::with_param(&model, Param::Lbar, q.p).unwrap();
            let least = node_slacks(&m, q.x.as_slice())
                .unwrap()
                .into_iter()
                .fold(f64::INFINITY, f64::min);
            assert!(least > -1e-9, "L̄ = {}: slack {least:e}", q.p);
        }
    }
    let last = pieces.last().unwrap().points.last().unwrap();
    assert!((last.p - 1.43).abs() < 1e-12, "{}", last.p);
    let opts = EnclosedOptions::default();
    let mut tracer = start.clone();
    for l in [1.41, 1.42, 1.43] {
        tracer = tracer.step_to(l, &opts).unwrap();
    }
    let plain = Confinement::with_param(&start.model, Param::Lbar, 1.43).unwrap();
    let e = Confinement::energy(&plain, last.x.as_slice()).unwrap();
    assert!(
        (e - tracer.energy()).abs() < 1e-9 * e,
        "{e} vs {}",
        tracer.energy()
    );
}
