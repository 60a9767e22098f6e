//! Bad options, narrow ranges, ranges below L̄ = 1 and ends near the great circles.

use rodloop_diagram::{compute, compute_branch, BranchEnd, DiagramError, DiagramOptions};
use rodloop_solver::Accuracy;

fn fast() -> DiagramOptions {
    DiagramOptions::with_accuracy(Accuracy::Fast)
}

#[test]
fn invalid_options_are_rejected() {
    for opts in [
        DiagramOptions {
            lbar_min: 3.0,
            lbar_max: 2.0,
            ..fast()
        },
        DiagramOptions {
            lbar_min: 0.0,
            ..fast()
        },
        DiagramOptions {
            radius: -1.0,
            ..fast()
        },
        DiagramOptions {
            lbar_max: f64::NAN,
            ..fast()
        },
        DiagramOptions {
            end_distance: 0.5,
            ..fast()
        },
        DiagramOptions {
            trace_cells_per_period: Some(1),
            ..fast()
        },
        DiagramOptions {
            stiffness: rodloop_solver::Stiffness::uniform(-1.0),
            ..fast()
        },
    ] {
        let err = compute(&opts, &mut (), &mut |_| {}).unwrap_err();
        println!("{err}");
        assert!(matches!(
            err,
            DiagramError::InvalidOptions(_) | DiagramError::Solver(_)
        ));
    }
    let err = compute_branch(&fast(), 9, &mut |_| {}).unwrap_err();
    assert!(
        matches!(err, DiagramError::BranchOutOfRange { eta: 9, .. }),
        "{err}"
    );
}

#[test]
fn ends_within_the_end_distance_of_every_great_circle() {
    // η = 3 and 4 over their whole ranges, with a tighter end distance.
    let opts = DiagramOptions {
        end_distance: 1e-5,
        ..fast()
    };
    for eta in [3, 4] {
        let b = compute_branch(&opts, eta, &mut |_| {}).unwrap();
        for (end, m) in [(&b.low_end, eta - 1), (&b.high_end, eta + 1)] {
            match end {
                BranchEnd::GreatCircle {
                    m: mm, distance, ..
                } => {
                    assert_eq!(*mm, m);
                    assert!((distance - 1e-5).abs() < 1e-12);
                }
                other => panic!("η = {eta}: {other:?}"),
            }
        }
        // The amplitude vanishes like √|L̄ − m| at the ends.
        let (p0, p1) = (&b.points[0], &b.points[1]);
        let ratio = p1.amplitude / p0.amplitude;
        let expect = ((p1.value - f64::from(eta - 1)) / (p0.value - f64::from(eta - 1))).sqrt();
        assert!((ratio / expect - 1.0).abs() < 0.05, "{ratio} vs {expect}");
        assert!(b.points.iter().all(|p| p.index == 0));
    }
}

#[test]
fn narrow_range_across_a_great_circle_and_a_range_below_one() {
    // A window around L̄ = 3: η = 2 ends, η = 4 starts, η = 3 passes.
    let opts = DiagramOptions {
        lbar_min: 2.9,
        lbar_max: 3.1,
        ..fast()
    };
    assert_eq!(opts.etas(), vec![2, 3, 4]);
    let d = compute(&opts, &mut (), &mut |_| {}).unwrap();
    assert!(d.warnings.is_empty(), "{:#?}", d.warnings);
    assert_eq!(d.critical.len(), 1);
    assert_eq!(
        (
            d.critical[0].lbar_cr,
            d.critical[0].from_branch,
            d.critical[0].to_branch
        ),
        (3.0, 1, 4)
    );
    // Below L̄ = 1 only the figure-eight (η = 1) and the saddle from L̄ = 1 (η = 2) exist.
    let opts = DiagramOptions {
        lbar_min: 0.6,
        lbar_max: 1.5,
        ..fast()
    };
    assert_eq!(opts.etas(), vec![1, 2]);
    let d = compute(&opts, &mut (), &mut |_| {}).unwrap();
    let fig8 = d.branch_by_eta(1).unwrap();
    assert!(matches!(fig8.low_end, BranchEnd::Range { value } if value == 0.6));
    assert!((fig8.points[0].value - 0.6).abs() < 1e-12);
    // The collapse at L̄ = 1 (from the circle, lowest below L̄ = 1, to the saddle that
    // emanates from the great circle) and the crossing.
    let kinds: Vec<_> = d
        .critical
        .iter()
        .map(|c| (c.kind.to_string(), c.from_branch, c.to_branch))
        .collect();
    assert_eq!(
        kinds,
        vec![
            ("collapse".to_string(), 0, 1),
            ("crossing".to_string(), 1, 2)
        ]
    );
    assert_eq!(d.critical[0].lbar_cr, 1.0);
    assert!((d.critical[1].lbar_cr - 1.3799411442868).abs() < 1e-5);
    // Below L̄ = 1 the figure-eight is metastable (the circle is lower).
    let (at, label) = d.label_near(1, 0.8).unwrap();
    assert!((at - 0.8).abs() < 0.1);
    assert_eq!(label, rodloop_diagram::Label::Metastable);
    assert!(d.lowest_at(0.8).is_empty());
}
