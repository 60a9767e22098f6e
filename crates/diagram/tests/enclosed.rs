//! The enclosed diagram (`|r| ≤ R`, paper Sec. 3.2) on `[1, 3]`: first-order optimality of every
//! state, the exchanges against the surface ones where both states are attached and
//! against independent 3-D solves where one has lifted off, the lift-off/landing events
//! against independent 3-D solves on both sides, and the labels.

use std::sync::OnceLock;

use rodloop_diagram::enclosed::{
    enclosed_diagram, EnclosedDiagram, EnclosedDiagramOptions, EventKind, PointSource,
};
use rodloop_diagram::Label;
use rodloop_exact::diagram::{compute, CriticalKind, DiagramSettings};
use rodloop_exact::{eta_of_branch, paper_branch_loop};
use rodloop_solver::enclosed::{
    solve_branch, solve_enclosed, start_from_surface, EnclosedOptions, SurfaceSource,
};
use rodloop_solver::Stiffness;

fn uniform() -> Stiffness {
    Stiffness::Uniform { d: 1.0 }
}

fn diagram() -> &'static EnclosedDiagram {
    static D: OnceLock<EnclosedDiagram> = OnceLock::new();
    D.get_or_init(|| {
        enclosed_diagram(&EnclosedDiagramOptions::new(1.0, uniform(), 1.0, 3.0))
            .expect("enclosed diagram on [1, 3]")
    })
}

/// The enclosed energy of branch `eta` at `lbar`, solved independently of the diagram
/// (semismooth Newton from the surface loop at N/4, N/2, N), with its error estimate.
fn enclosed_energy(eta: u32, lbar: f64, cells: usize) -> (f64, f64, f64) {
    let l = paper_branch_loop(eta, lbar).unwrap();
    let b = solve_branch(
        1.0,
        lbar,
        &uniform(),
        &SurfaceSource::Exact(l),
        cells,
        &EnclosedOptions::default(),
    )
    .unwrap();
    let c = b.fine.contact(1e-9).unwrap();
    (b.energy, b.energy_error, c.max_gap.0)
}

#[test]
fn every_state_is_first_order_optimal() {
    let d = diagram();
    assert!(d.points.len() > 50);
    for p in &d.points {
        assert!(p.energy.is_finite() && p.energy_error.is_finite());
        assert!(p.lambda_min >= -1e-8, "{p:?}");
        assert!(p.gap_min >= -1e-10, "{p:?}");
        assert!(p.complementarity <= 1e-9, "{p:?}");
        assert!(p.stationarity <= 1e-8, "{p:?}");
        if p.source == PointSource::Model {
            // A lifted-off state lies below its branch's surface loop (which needs a
            // pulling wall there).
            let s = paper_branch_loop(p.eta, p.lbar).unwrap();
            assert!(s.lambda_range().0 < 0.0, "{p:?}");
            assert!(p.energy < s.energy().unwrap(), "{p:?}");
            assert!(p.max_gap > 1e-12, "{p:?}");
        }
    }
}

/// The index of every attached sample (read from the surface model, the wall being strictly
/// active there) is the index of the 3-D model itself: the exact loop re-solved by the
/// semismooth Newton method at two resolutions, its inertia counted on the tangent space of
/// the closure, the gauges and the active wall. (On `[1, 3]` every attached sample of the
/// uniform rod is a minimum in both models: the check is that the 3-D model, which may also
/// lift the loop off, finds no descent direction the surface model misses, up to the
/// samples next to a lift-off.)
#[test]
fn attached_indices_are_those_of_the_3d_model() {
    let d = diagram();
    let attached: Vec<_> = d
        .points
        .iter()
        .filter(|p| p.source == PointSource::Exact && p.eta > 0)
        .collect();
    assert!(attached.len() > 20, "{} attached samples", attached.len());
    let mut checked = 0;
    for p in attached {
        let l = paper_branch_loop(p.eta, p.lbar).unwrap();
        if l.lambda_range().0 <= 0.0 {
            continue;
        }
        let len = l.length();
        for cells in [24 * (1 + p.eta as usize), 48 * (1 + p.eta as usize)] {
            let (model, z0) = start_from_surface(1.0, p.lbar, cells, &uniform(), |s| {
                l.point(s * len).map(|q| q.kappa_g).unwrap_or(f64::NAN)
            })
            .unwrap();
            let st = solve_enclosed(&model, z0, &EnclosedOptions::default()).unwrap();
            assert_eq!(
                st.index(1e-6).unwrap(),
                p.index,
                "branch {} at lbar = {}, N = {cells}",
                p.branch,
                p.lbar
            );
        }
        checked += 1;
    }
    assert!(checked > 20, "{checked} samples checked");
}

#[test]
fn the_uniform_diagram_runs_without_warnings() {
    let d = diagram();
    assert!(d.warnings.is_empty(), "{:?}", d.warnings);
}

#[test]
fn exchanges_between_attached_states_are_the_surface_ones() {
    let d = diagram();
    let surface = compute(&DiagramSettings {
        lbar_min: 1.0,
        lbar_max: 3.0,
        eta_max: 3,
        step: 0.01,
    })
    .unwrap();
    assert_eq!(d.critical.len(), surface.critical.len());
    for (e, s) in d.critical.iter().zip(&surface.critical) {
        let c = &e.critical;
        assert_eq!(
            (c.from_branch, c.to_branch, c.kind),
            (s.from_branch, s.to_branch, s.kind)
        );
        // Is either branch lifted off at the surface value?
        let lifted = [c.from_branch, c.to_branch].iter().any(|&b| {
            b > 0
                && paper_branch_loop(eta_of_branch(b), s.lbar_cr)
                    .map(|l| l.lambda_range().0 < 0.0)
                    .unwrap_or(false)
        });
        if lifted {
            assert!(c.error_estimate <= 1e-7, "{c:?}");
            // The lifted-off branch has the lower energy, so the exchange moves.
            assert!((c.lbar_cr - s.lbar_cr).abs() > 1e-6, "{c:?}");
        } else {
            assert_eq!(c.lbar_cr, s.lbar_cr);
        }
    }
    // The paper's exchange L̄ = 2.425697732215 (branches 3 -> 1, both attached) is kept.
    assert!(d
        .critical
        .iter()
        .any(|c| c.critical.kind == CriticalKind::Crossing
            && (c.critical.lbar_cr - 2.425697732215).abs() < 1e-11));
}

#[test]
fn lifted_off_exchange_brackets_independent_solves() {
    // Branch 1 (eta = 2) is attached, branch 2 (eta = 1) lifted off near L̄ = 1.3799: the
    // enclosed energy difference, solved independently at N = 128 from the surface loops,
    // changes sign across L̄_cr ± (estimate + δ).
    let d = diagram();
    let c = d
        .critical
        .iter()
        .find(|c| c.critical.from_branch == 1 && c.critical.to_branch == 2)
        .expect("the 1 -> 2 exchange");
    assert!(c.critical.lbar_cr < c.surface_lbar_cr.expect("the surface value"));
    let c = &c.critical;
    let delta = 10.0 * c.error_estimate + 2e-7;
    let f = |x: f64| {
        let e1 = paper_branch_loop(2, x).unwrap().energy().unwrap();
        let (e2, err, gap) = enclosed_energy(1, x, 128);
        assert!(gap > 1e-4);
        // The energy error is below the energy change over the bracket (slope difference ~3).
        assert!(err < delta);
        e1 - e2
    };
    assert!(f(c.lbar_cr - delta) < 0.0);
    assert!(f(c.lbar_cr + delta) > 0.0);
}

#[test]
fn events_separate_attached_and_lifted_off_solves() {
    let d = diagram();
    assert_eq!(d.events.len(), 1, "{:?}", d.events);
    for e in &d.events {
        let eta = eta_of_branch(e.branch);
        // Eq. (38): λ_min = 0 at the event.
        let l = paper_branch_loop(eta, e.lbar).unwrap();
        assert!(l.lambda_range().0.abs() < 1e-9);
        let (below, above) = (e.lbar - 1e-4, e.lbar + 1e-4);
        let (lifted, attached) = match e.kind {
            EventKind::Landing => (below, above),
            EventKind::LiftOff => (above, below),
            // Below L̄ = 1 only (tests/enclosed_detachment.rs); two-segment rods only.
            EventKind::Detachment | EventKind::BranchPoint | EventKind::Fold => {
                panic!("no detachment, branch point or fold in [1, 3]: {e:?}")
            }
        };
        let (_, _, gap_l) = enclosed_energy(eta, lifted, 64);
        let (_, _, gap_a) = enclosed_energy(eta, attached, 64);
        assert!(gap_l > 1e-12, "gap {gap_l} at {lifted}");
        assert!(gap_a < 1e-13, "gap {gap_a} at {attached}");
    }
}

#[test]
fn lowest_states_are_stable_and_lifted_off_only_between_exchange_and_landing() {
    let d = diagram();
    let c = d
        .critical
        .iter()
        .find(|c| c.critical.from_branch == 1 && c.critical.to_branch == 2)
        .unwrap()
        .critical;
    let landing = d.events[0].lbar;
    for p in d.points.iter().filter(|p| p.lowest) {
        assert_eq!(p.index, 0, "{p:?}");
        assert_eq!(p.label, Label::Stable);
        let inside = p.lbar > c.lbar_cr && p.lbar < landing;
        assert_eq!(!p.attached, inside && p.branch == 2, "{p:?}");
    }
    for p in d.points.iter().filter(|p| !p.lowest && p.index == 0) {
        assert_eq!(p.label, Label::Metastable);
    }
}

#[test]
fn bad_options_are_refused() {
    let mut o = EnclosedDiagramOptions::new(1.0, uniform(), 3.0, 1.0);
    assert!(enclosed_diagram(&o).is_err());
    o = EnclosedDiagramOptions::new(1.0, uniform(), 1.0, 3.0);
    o.step = 0.0;
    assert!(enclosed_diagram(&o).is_err());
    let tanh = Stiffness::Tanh {
        d0: 1.0,
        d1: 0.5,
        s0: 0.25,
        s1: 0.75,
        gamma: 200.0,
    };
    // A non-uniform rod's free loop below L̄ = 1 is not a circle and is not modelled.
    let err = enclosed_diagram(&EnclosedDiagramOptions::new(1.0, tanh, 0.5, 3.0)).unwrap_err();
    assert!(err.to_string().contains("starts at lbar = 1"), "{err}");
}

/// A wall that is not the sphere: the unit ball's gap, named otherwise.
#[derive(Debug)]
struct NotASphere;

impl rodloop_solver::enclosed::Wall for NotASphere {
    fn radius(&self) -> f64 {
        1.0
    }
    fn gap(&self, r: &nalgebra::Vector3<f64>) -> f64 {
        1.0 - r.norm_squared()
    }
    fn gradient(&self, r: &nalgebra::Vector3<f64>) -> nalgebra::Vector3<f64> {
        r * -2.0
    }
    fn hessian(&self, _r: &nalgebra::Vector3<f64>) -> nalgebra::Matrix3<f64> {
        nalgebra::Matrix3::identity() * -2.0
    }
    fn clearance(&self, r: &nalgebra::Vector3<f64>) -> f64 {
        1.0 - r.norm()
    }
    fn outline(&self) -> (&'static str, [f64; 3]) {
        ("test wall", [1.0; 3])
    }
}

/// The diagram's tracers start from the sphere's surface loops: another wall is refused with
/// its name, not traced as the sphere.
#[test]
fn a_wall_other_than_the_sphere_is_refused() {
    let wall: std::sync::Arc<dyn rodloop_solver::enclosed::Wall> = std::sync::Arc::new(NotASphere);
    let err =
        enclosed_diagram(&EnclosedDiagramOptions::new(wall, uniform(), 1.0, 3.0)).unwrap_err();
    assert!(err.to_string().contains("test wall"), "{err}");
}
