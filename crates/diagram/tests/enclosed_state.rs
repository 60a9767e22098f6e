//! One enclosed state as `rodloop solve` reports it ([`rodloop_diagram::enclosed_state`]),
//! against the exact layer: the planar circle below `L̄ = 1`, an attached surface loop, a
//! loop that has lifted off, and lengths outside a branch's range.

use rodloop_diagram::enclosed_state::{solve_state, TOUCH};
use rodloop_diagram::DiagramError;
use rodloop_exact::{eta_of_branch, paper_branch_loop};
use rodloop_solver::{Accuracy, Stiffness};

#[test]
fn planar_circle_is_exact_and_the_model_agrees() {
    let lbar = 0.8;
    let r = solve_state(1.0, &Stiffness::uniform(1.0), lbar, 0, Accuracy::Default).unwrap();
    // A circle of radius ρ = R L̄: E = (D/2)(1/ρ²)(2πρ) = πD/ρ, so E R/(πD) = 1/L̄.
    assert_eq!(r.energy, (1.0 / lbar, 0.0));
    assert!(
        (r.model_energy.0 - 1.0 / lbar).abs() < 1e-6,
        "{:?}",
        r.model_energy
    );
    assert_eq!(r.stability.0, 0);
    assert!(r.surface.is_none());
}

#[test]
fn attached_loop_is_the_surface_loop_and_the_model_re_solves_it() {
    // Branch 3 at L̄ = 2.2: λ_min > 0, the surface loop is the enclosed equilibrium.
    let (branch, lbar) = (3, 2.2);
    let r = solve_state(
        1.0,
        &Stiffness::uniform(1.0),
        lbar,
        branch,
        Accuracy::Default,
    )
    .unwrap();
    let exact = paper_branch_loop(eta_of_branch(branch), lbar)
        .unwrap()
        .energy()
        .unwrap();
    let (e_surf, lam_min) = r.surface.unwrap();
    assert!(lam_min > 0.0);
    assert!((e_surf - exact).abs() < 1e-12);
    // The 3-D model, an independent discretisation, lands on the same energy.
    assert!(
        (r.model_energy.0 - exact).abs() < 1e-4,
        "{} vs {exact}",
        r.model_energy.0
    );
    let c = r.state.contact(TOUCH).unwrap();
    assert_eq!((c.intervals, c.fraction), (1, 1.0));
}

#[test]
fn lifted_off_loop_lies_below_its_surface_loop() {
    // Branch 2 (η = 1) at L̄ = 1.2: λ < 0 on its surface loop, the enclosed state leaves the
    // wall and has the lower energy (the enclosed problem relaxes the surface constraint).
    let r = solve_state(1.0, &Stiffness::uniform(1.0), 1.2, 2, Accuracy::Default).unwrap();
    let (e_surf, lam_min) = r.surface.unwrap();
    assert!(lam_min < 0.0);
    assert!(
        r.energy.0 < e_surf - 10.0 * r.energy.1,
        "{:?} vs {e_surf}",
        r.energy
    );
    let c = r.state.contact(TOUCH).unwrap();
    assert!(c.max_gap.0 > 1e-3, "max gap {:?}", c.max_gap);
    assert_eq!(r.stability.0, 0);
}

#[test]
fn lengths_outside_a_branch_are_refused() {
    let s = Stiffness::uniform(1.0);
    for (branch, lbar) in [(0, 1.5), (1, 3.5)] {
        match solve_state(1.0, &s, lbar, branch, Accuracy::Fast) {
            Err(DiagramError::OutOfRange(m)) => assert!(m.contains("got lbar"), "{m}"),
            other => panic!("branch {branch} at {lbar}: {:?}", other.map(|r| r.energy)),
        }
    }
}
