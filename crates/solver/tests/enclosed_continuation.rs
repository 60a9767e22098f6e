//! Continuation helpers of the enclosed model: the secant predictor reaches the
//! same state as the plain warm start from a start much closer to it, and the pinned free
//! step re-bases a loop whose node 0 touches the wall without changing the equilibrium.

mod common;

use rodloop_solver::enclosed::{EnclosedOptions, EnclosedState};

/// The lifted-off figure-eight (branch 2) at `lbar`, `N = 64`.
fn figure_eight(lbar: f64) -> EnclosedState {
    common::enclosed_figure_eight(lbar, 64)
}

#[test]
fn the_secant_predictor_starts_closer_and_reaches_the_same_state() {
    let opts = EnclosedOptions::default();
    let a = figure_eight(1.40);
    let b = a.step_to(1.41, &opts).unwrap();
    let target = 1.42;
    // The plain warm start and the predicted one, as Newton starts at 1.42.
    let (m_plain, z_plain) = b.continue_to(target).unwrap();
    let (m_pred, z_pred) = b.predict_to(&a, target).unwrap().expect("a predictor");
    let r_plain = m_plain.residual_norm(&m_plain.residual(&z_plain).unwrap());
    let r_pred = m_pred.residual_norm(&m_pred.residual(&z_pred).unwrap());
    // O(ΔL̄²) against O(ΔL̄): at least ten times closer here.
    assert!(
        r_pred < 0.1 * r_plain,
        "predicted {r_pred:.3e}, plain {r_plain:.3e}"
    );
    let plain = rodloop_solver::enclosed::solve_enclosed(&m_plain, z_plain, &opts).unwrap();
    let pred = rodloop_solver::enclosed::solve_enclosed(&m_pred, z_pred, &opts).unwrap();
    assert!(
        pred.iterations <= plain.iterations,
        "{} {}",
        pred.iterations,
        plain.iterations
    );
    assert!(
        (pred.energy() - plain.energy()).abs() < 1e-11,
        "{} {}",
        pred.energy(),
        plain.energy()
    );
    // No predictor across meshes or from the same length.
    assert!(b.predict_to(&b, target).unwrap().is_none());
}

#[test]
fn the_pinned_step_keeps_a_balanced_state_and_rebases_a_touching_node_zero() {
    // Below L̄ ≈ 1.3 the figure-eight touches the wall at its lobe tips, nodes 0 and N/2.
    let a = figure_eight(1.2);
    let lam = a.multipliers();
    assert!(lam[0] > 0.0 && lam[32] > 0.0);
    // The wall forces balance (no other external force acts on a closed rod).
    assert!(a.net_wall_force().unwrap() < 1e-9);
    // Pinned at the same length: node 0 touches, so the loop is re-based by N/4 cells and
    // turned (and, touching, not moved); the equilibrium (energy, contact forces) is the
    // same and the pin carries no force.
    let (model, z) = a.continue_free(1.2).unwrap();
    assert!(model.gauge().pin.is_some());
    let st =
        rodloop_solver::enclosed::solve_enclosed(&model, z, &EnclosedOptions::default()).unwrap();
    assert!(
        (st.energy() - a.energy()).abs() < 1e-10,
        "{} {}",
        st.energy(),
        a.energy()
    );
    let (c0, c1) = (a.contact(1e-9).unwrap(), st.contact(1e-9).unwrap());
    assert_eq!(c0.intervals, c1.intervals);
    assert!((c0.lambda_range.1 - c1.lambda_range.1).abs() < 1e-6 * c0.lambda_range.1);
    assert!(st.net_wall_force().unwrap() < 1e-8);
    // The re-based loop's node 0 is off the wall.
    assert!(st.model.gaps(&st.z).unwrap()[0] > 1e-3);
}
