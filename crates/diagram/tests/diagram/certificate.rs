//! The completeness certificate finds what the traced set lacks: a diagram of a two-segment
//! rod is traced, the family holding its lowest state at a sample length is withheld, and the
//! certificate run on the rest must find a state of that family below the traced set, trace
//! its family again and leave nothing unexplained.

use rodloop_diagram::certificate::{
    certify, lowest_traced, sample_lengths, search_all, SurfaceSearch, SurfaceTraced,
};
use rodloop_diagram::{compute, DiagramOptions};
use rodloop_solver::Stiffness;

#[test]
fn certificate_finds_and_retraces_a_withheld_family() {
    // A profile of a user's own (not one of the paper's): soft segment 0.2–0.4 of the loop.
    let opts = DiagramOptions {
        stiffness: Stiffness::Tanh {
            d0: 1.0,
            d1: 0.3,
            s0: 0.2,
            s1: 0.4,
            gamma: 100.0,
        },
        lbar_min: 1.3,
        lbar_max: 1.5,
        ..DiagramOptions::default()
    };
    let full = compute(&opts, &mut (), &mut |_| {}).expect("diagram");
    let (lengths, spacing) = sample_lengths(opts.lbar_min, opts.lbar_max);
    let l = lengths[lengths.len() / 2];
    let lowest = lowest_traced(&full.branches, l).expect("a traced state at the middle length");
    let holder = full
        .branches
        .iter()
        .find(|b| b.energy_at(l) == Some(lowest))
        .expect("the sheet of the lowest state");
    let (eta, family) = (holder.eta, holder.family);
    let mut sheets: Vec<_> = full
        .branches
        .iter()
        .filter(|b| !(b.eta == eta && b.family == family))
        .cloned()
        .collect();
    let without = lowest_traced(&sheets, l);
    // Withholding the family must leave the traced set higher there (or empty), by far more
    // than the tolerance of the comparison below.
    let tol = 1e-4 * lowest.abs().max(1.0);
    assert!(
        without.is_none_or(|e| e > lowest + 10.0 * tol),
        "withholding η = {eta} family {family} leaves {without:?} at L̄ = {l} (lowest {lowest})"
    );
    let search = SurfaceSearch::new(&opts, &lengths);
    let candidates = search_all(&search, &lengths, 2);
    let mut notes = Vec::new();
    let cert = {
        let mut set = SurfaceTraced {
            opts: &opts,
            sheets: &mut sheets,
            notes: &mut notes,
        };
        certify(&search, candidates, 0.0, &mut set, &lengths, spacing, 2)
    };
    // The search finds the withheld state at `l`, below the rest of the traced set.
    let found = cert
        .found_below
        .iter()
        .find(|f| (f.lbar - l).abs() < 1e-12 && f.eta == eta)
        .unwrap_or_else(|| panic!("nothing found below at L̄ = {l}: {cert:?}"));
    assert!(
        (found.energy - lowest).abs() <= tol + 3.0 * found.error,
        "found {} ± {:.1e} at L̄ = {l}, the withheld family has {lowest}",
        found.energy,
        found.error
    );
    // Its family is traced again, and the traced set's lowest state there is restored.
    assert!(cert.families_seeded >= 1, "{cert:?}; notes {notes:?}");
    assert!(cert.unexplained.is_empty(), "{cert:?}; notes {notes:?}");
    let again = lowest_traced(&sheets, l).expect("a traced state after seeding");
    assert!(
        (again - lowest).abs() <= tol,
        "after seeding the lowest traced state at L̄ = {l} is {again}, before withholding {lowest}"
    );
}
