//! Shared diagrams and exact references.

use std::sync::OnceLock;

use rodloop_diagram::{compute, DiagramOptions, NumericDiagram};
use rodloop_solver::Accuracy;

/// The default scene at the default accuracy (computed once per test binary).
pub fn default_diagram() -> &'static NumericDiagram {
    static D: OnceLock<NumericDiagram> = OnceLock::new();
    D.get_or_init(|| {
        compute(&DiagramOptions::default(), &mut (), &mut |_| {}).expect("default diagram")
    })
}

/// The default scene at the fast accuracy.
pub fn fast_diagram() -> &'static NumericDiagram {
    static D: OnceLock<NumericDiagram> = OnceLock::new();
    D.get_or_init(|| {
        compute(
            &DiagramOptions::with_accuracy(Accuracy::Fast),
            &mut (),
            &mut |_| {},
        )
        .expect("fast diagram")
    })
}

/// The exact diagram of the default scene.
pub fn exact_diagram() -> &'static rodloop_exact::diagram::Diagram {
    static D: OnceLock<rodloop_exact::diagram::Diagram> = OnceLock::new();
    D.get_or_init(|| rodloop_exact::diagram::compute(&Default::default()).expect("exact diagram"))
}

/// Exact energy `E R/(πD)` of branch `eta` at `lbar`.
pub fn exact_energy(eta: u32, lbar: f64) -> f64 {
    rodloop_exact::paper_branch_loop(eta, lbar)
        .and_then(|l| l.energy())
        .expect("exact loop")
}
