//! Unit tests of the labeller's view of `nonuniform_exchange.rs` ([`ranked_at`]) on
//! hand-made sheets: the interpolation estimate, the named branch of a located crossing and
//! the ends of a collapse.

use super::*;
use crate::labels::Label;
use rodloop_continuation::exchange::lowest_state;
use rodloop_exact::diagram::{Critical, CriticalKind};

fn point(branch: u32, family: u32, lbar: f64, energy: f64, index: usize) -> EnclosedPoint {
    EnclosedPoint {
        branch,
        eta: branch,
        lbar,
        energy,
        energy_error: 1e-6,
        attached: false,
        contact_fraction: 0.0,
        contact_intervals: 0,
        max_gap: 0.0,
        lambda_min: 0.0,
        gap_min: 0.0,
        complementarity: 0.0,
        stationarity: 0.0,
        index,
        label: Label::Unstable,
        lowest: false,
        cells: 0,
        source: PointSource::Model,
        family,
        sheet: 0,
        multiplicity: 1,
        surface_energy: None,
        branch_from: Default::default(),
        shape: Default::default(),
    }
}

fn sheet(branch: u32, family: u32, samples: &[(f64, f64)]) -> SheetOut {
    let mut s = SheetOut::empty(branch, branch, family);
    s.points = samples
        .iter()
        .map(|&(x, e)| point(branch, family, x, e, 0))
        .collect();
    s
}

fn crossing(x: f64, from: u32, to: u32) -> EnclosedCritical {
    EnclosedCritical {
        critical: Critical {
            index: 1,
            kind: CriticalKind::Crossing,
            lbar_cr: x,
            from_branch: from,
            to_branch: to,
            energy: 0.0,
            error_estimate: 1e-7,
        },
        surface_lbar_cr: None,
        method: String::new(),
    }
}

/// A curved sheet sampled sparsely: its interpolated energy at a length between samples
/// carries the curvature estimate, which covers its true value there.
#[test]
fn an_interpolated_energy_carries_its_curvature() {
    // E = (x − 1.3)² + 1 sampled at 1.2, 1.3, 1.5, 1.7.
    let f = |x: f64| (x - 1.3) * (x - 1.3) + 1.0;
    let s = sheet(2, 1, &[1.2, 1.3, 1.5, 1.7].map(|x| (x, f(x))));
    let p = point(1, 1, 1.4, 5.0, 0);
    let other = sheet(1, 1, &[(1.4, 5.0)]);
    let states = ranked_at(&[other, s], &[], &[], 0, &p, 0.75);
    let r = states[1];
    // Linear interpolation gives 1.02 + 0.02 (the chord), the truth 1.01: the estimate
    // (f'' = 2, (0.1)(0.1)/2 · 2 = 0.01, plus the samples' 1e-6) covers the difference.
    assert!((r.energy - 1.02).abs() < 1e-12, "{r:?}");
    assert!((r.energy - f(1.4)).abs() <= r.error, "{r:?}");
    assert!(r.error < 0.0101, "{r:?}");
}

/// Inside the closed bracket of a crossing `1 → 2` located at 1.349, a sample of branch 1
/// at the bracket's end (1.3495, past the crossing) ties with branch 2 interpolated there,
/// and branch 2 (any family of it) is preferred, so branch 1 is not the lowest.
#[test]
fn a_located_crossing_names_its_branch_at_the_bracket_end() {
    let b1 = sheet(
        1,
        1,
        &[(1.2914, 1.74916), (1.3495, 1.852118), (1.4166, 1.950657)],
    );
    let b2 = sheet(
        2,
        3,
        &[(1.3201, 1.873888), (1.4026, 1.812540), (1.4384, 1.789279)],
    );
    let outs = [b1, b2];
    let p = outs[0].points[1].clone();
    let brackets = [(1.3201, 1.3495, 0, 1)];
    let states = ranked_at(&outs, &brackets, &[crossing(1.349, 1, 2)], 0, &p, 0.75);
    assert!(!states[0].preferred && states[1].preferred, "{states:?}");
    assert!(!lowest_state(&states).contains(&0), "{states:?}");
    // Without the crossing, the sampled energies tie and nothing is preferred: both lowest.
    let states = ranked_at(&outs, &[], &[], 0, &p, 0.75);
    assert!(lowest_state(&states).contains(&0), "{states:?}");
}

/// A saddle at the end of a sheet `5·10⁻⁵` below a great circle and a minimum at the start
/// of another `5·10⁻⁵` above it are the two ends of the collapse there: tied, so the
/// minimum is the lowest; a one-sample sheet on the same side as `p` takes the slope of its
/// chord to the circle's energy.
#[test]
fn the_ends_of_a_collapse_are_tied() {
    let below = || {
        let mut s = sheet(2, 1, &[(1.93, 1.7763), (1.99995, 1.7594635)]);
        s.points[1].index = 2;
        s
    };
    let above = sheet(3, 1, &[(2.00005, 1.7597553), (2.05, 1.80)]);
    let outs = [below(), above];
    let p = outs[0].points[1].clone();
    let states = ranked_at(&outs, &[], &[], 0, &p, 0.879863);
    assert!((states[1].energy - 1.7597553).abs() < 1e-12, "{states:?}");
    assert!(
        states[1].error >= (states[1].energy - p.energy).abs(),
        "{states:?}"
    );
    assert!(!lowest_state(&states).contains(&0), "{states:?}");
    // On the same side: a one-sample sheet at 1.9990 (E = 1.7590) next to p at 1.99995; its
    // chord to the circle's energy 2 · 0.879863 has slope 0.7697, so the shift is 7.3e-4.
    let one = sheet(1, 5, &[(1.999, 1.759)]);
    let outs = [below(), one];
    let states = ranked_at(&outs, &[], &[], 0, &p, 0.879863);
    let slope = (2.0 * 0.879863 - 1.759) / (2.0 - 1.999);
    assert!(
        (states[1].error - (1e-6 + slope * 0.00095)).abs() < 1e-12,
        "{states:?}"
    );
}
