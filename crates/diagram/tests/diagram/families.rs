//! The paper's two-segment rod (Eq. 51, D1/D0 = 0.5, s0*/L = 0.3, s1*/L = 0.8, γ = 200;
//! Sec. 5, Fig. 10): families followed through folds and branch points, checked against
//! independent solves.

use std::sync::OnceLock;

use rodloop_diagram::{compute, BranchEnd, CriticalKind, DiagramOptions, Label, NumericDiagram};
use rodloop_solver::{solve_robust, Accuracy, SolveOptions, StartShape, Stiffness};

fn paper_rod() -> Stiffness {
    Stiffness::paper_sec5(0.5)
}

fn diagram() -> &'static NumericDiagram {
    static D: OnceLock<NumericDiagram> = OnceLock::new();
    D.get_or_init(|| {
        let opts = DiagramOptions {
            stiffness: paper_rod(),
            lbar_min: 1.0,
            lbar_max: 3.0,
            ..DiagramOptions::default()
        };
        compute(&opts, &mut (), &mut |_| {}).expect("diagram of the paper's rod")
    })
}

/// The located crossings of a diagram.
fn crossings_of(d: &NumericDiagram) -> Vec<&rodloop_diagram::CriticalLength> {
    d.critical
        .iter()
        .filter(|c| c.kind == CriticalKind::Crossing)
        .collect()
}

/// `e_diagram` (the diagram's lowest energy at `lbar`) is no higher than the energy of any
/// state `solve_robust` finds there for branches η = 1–3 (the diagram's energies are at the
/// tracing resolution, error ≲ 1e-5 here: tolerance 1e-4 plus solve's estimate).
fn assert_no_higher_than_solve(rod: &Stiffness, lbar: f64, e_diagram: f64) {
    for eta in [1u32, 2, 3] {
        if !(f64::from(eta) - 1.0 < lbar && lbar < f64::from(eta) + 1.0) {
            continue;
        }
        let Ok((acc, _)) = solve_robust(
            1.0,
            lbar,
            rod,
            &StartShape::Euler { l: eta },
            Accuracy::Default,
            Some(eta),
            &SolveOptions::default(),
        ) else {
            continue;
        };
        let tol = 1e-4 + acc.energy_error;
        assert!(
            e_diagram <= acc.energy.total + tol,
            "L̄ = {lbar}: diagram's lowest {e_diagram} above solve's {} for η = {eta}",
            acc.energy.total
        );
    }
}

/// At several lengths the diagram's lowest state is stable with index 0, and its energy is
/// no higher than that of every state `solve_robust` (shifted Euler starts, continuation in
/// D1/D0; an independent route at another resolution) finds for branches 1–3.
#[test]
fn lowest_state_is_no_higher_than_solve() {
    let d = diagram();
    for lbar in [1.2, 1.5, 1.7, 1.9, 2.2, 2.5, 2.8] {
        let sheets = d.lowest_sheets_at(lbar);
        assert_eq!(sheets.len(), 1, "L̄ = {lbar}: {sheets:?}");
        let b = &d.branches[sheets[0]];
        let e_diagram = b.energy_at(lbar).expect("covers");
        // The label and index of the traced state nearest to lbar on that sheet.
        let k = (0..b.points.len())
            .min_by(|&x, &y| {
                (b.points[x].value - lbar)
                    .abs()
                    .total_cmp(&(b.points[y].value - lbar).abs())
            })
            .unwrap();
        assert_eq!(b.points[k].index, 0, "L̄ = {lbar}");
        assert_eq!(d.labels[sheets[0]][k], Label::Stable, "L̄ = {lbar}");
        assert_no_higher_than_solve(&paper_rod(), lbar, e_diagram);
    }
}

/// The structure of the diagram: the paper's exchanges (Fig. 10: saddle → figure-eight
/// near 1.38, orbit-like η = 3 → η = 2 near 2.43) and collapses; every followed family has
/// sheets monotone in L̄; mirror-asymmetric sheets carry multiplicity 2; folds and branch
/// points are recorded as special points; no failed ends and no warning that a stable
/// state is missing.
#[test]
fn families_and_special_points() {
    let d = diagram();
    let crossings = crossings_of(d);
    assert_eq!(crossings.len(), 2, "{crossings:#?}");
    assert!((crossings[0].lbar_cr - 1.38).abs() < 0.03);
    assert_eq!((crossings[0].from_eta, crossings[0].to_eta), (2, 1));
    assert!((crossings[1].lbar_cr - 2.42).abs() < 0.03);
    assert_eq!((crossings[1].from_eta, crossings[1].to_eta), (3, 2));
    for c in &crossings {
        assert!(c.error_estimate <= 1e-7, "{c:?}");
    }
    // Great circles of the mean stiffness 0.75 D0: E R/(π D0) = 0.75 m at L̄ = m.
    let collapses: Vec<_> = d
        .critical
        .iter()
        .filter(|c| c.kind == CriticalKind::Collapse)
        .collect();
    assert_eq!(collapses.len(), 3);
    for c in &collapses {
        assert!((c.energy - 0.75 * c.lbar_cr).abs() < 1e-9, "{c:?}");
    }
    for b in &d.branches {
        assert!(b.points.windows(2).all(|w| w[0].value <= w[1].value));
        assert!(b.multiplicity == 1 || b.multiplicity == 2);
        for end in [&b.low_end, &b.high_end] {
            assert!(!matches!(end, BranchEnd::Failed { .. }), "{end:?}");
        }
    }
    assert!(d.branches.iter().any(|b| b.multiplicity == 2));
    assert!(d
        .special
        .iter()
        .any(|s| s.kind == rodloop_diagram::SpecialKind::BranchPoint));
    assert!(
        !d.warnings.iter().any(|w| w.contains("NO STABLE STATE")),
        "{:#?}",
        d.warnings
    );
    // A fold is the end of a kept sheet (the sheet beyond it may be the mirror half of an
    // asymmetric family, reported once).
    for s in d
        .special
        .iter()
        .filter(|s| s.kind == rodloop_diagram::SpecialKind::Fold)
    {
        let ends: Vec<_> = d
            .branches
            .iter()
            .filter(|b| {
                // Located again at the reporting resolution: within the tracing's width.
                [&b.low_end, &b.high_end].iter().any(|e| {
                    matches!(e, BranchEnd::Fold { value } | BranchEnd::BranchPoint { value }
                        if (value - s.lbar).abs() < 1e-4)
                })
            })
            .collect();
        assert!(!ends.is_empty(), "fold at {}", s.lbar);
    }
}

/// Folds and branch points located at the reporting resolutions: most are located (an
/// error estimate), and at `--accuracy high` (twice the cells) each lies within the sum of
/// the two estimates of the default location (an independent finer computation).
#[test]
fn special_points_agree_with_the_high_accuracy_ones() {
    let d = diagram();
    let high = compute(
        &DiagramOptions {
            stiffness: paper_rod(),
            lbar_min: 1.0,
            lbar_max: 3.0,
            ..DiagramOptions::with_accuracy(Accuracy::High)
        },
        &mut (),
        &mut |_| {},
    )
    .expect("high-accuracy diagram");
    let ends = |d: &NumericDiagram| -> Vec<(f64, f64)> {
        d.special
            .iter()
            .filter(|s| {
                matches!(
                    s.kind,
                    rodloop_diagram::SpecialKind::Fold | rodloop_diagram::SpecialKind::BranchPoint
                )
            })
            .filter_map(|s| s.error_estimate.map(|e| (s.lbar, e)))
            .collect()
    };
    let (a, b) = (ends(d), ends(&high));
    // The fold of branch 2 and the two pitchforks of branch 1 (each reported once: the
    // asymmetric family of branch 1 turns at them, traced once, not once per image).
    assert!(a.len() >= 3, "{a:?}");
    let mut compared = 0;
    for &(l, e) in &a {
        assert!(e < 1e-5, "fold or branch point at {l}: estimate {e}");
        let Some(&(lh, eh)) = b
            .iter()
            .min_by(|x, y| (x.0 - l).abs().total_cmp(&(y.0 - l).abs()))
        else {
            continue;
        };
        if (lh - l).abs() > 1e-4 {
            continue;
        }
        compared += 1;
        assert!(
            (lh - l).abs() <= e + eh,
            "default {l} ± {e:.1e}, high {lh} ± {eh:.1e}"
        );
    }
    assert!(compared >= 3, "{a:?} / {b:?}");
}

/// The very soft rod (D1/D0 = 0.001): at lengths that are not seed lengths of the diagram
/// (its seeds lie at 1.25, 1.5, 1.75 for η = 1, 1.5, 2, 2.5 for η = 2 and 2.25, 2.5, 2.75
/// for η = 3), the lowest traced state is no higher than what `solve_robust` finds for any
/// branch there (independent route: its own starts, resolution and homotopy), and the
/// lowest state passes from branch 1 (η = 2) to branch 2 (η = 1) and back to branch 1 only
/// through located crossings.
#[test]
fn very_soft_rod_lowest_state_is_no_higher_than_solve() {
    let rod = Stiffness::paper_sec5(0.001);
    let opts = DiagramOptions {
        stiffness: rod.clone(),
        lbar_min: 1.0,
        lbar_max: 3.0,
        ..DiagramOptions::default()
    };
    let d = compute(&opts, &mut (), &mut |_| {}).expect("diagram of the very soft rod");
    let crossings = crossings_of(&d);
    assert_eq!(crossings.len(), 2, "{crossings:#?}");
    for lbar in [1.28, 1.62, 2.2, 2.62] {
        let sheets = d.lowest_sheets_at(lbar);
        assert!(!sheets.is_empty(), "L̄ = {lbar}");
        let e_diagram = d.branches[sheets[0]].energy_at(lbar).expect("covers");
        assert_no_higher_than_solve(&rod, lbar, e_diagram);
    }
}

/// The very soft rod of the paper (D1/D0 = 0.001).
fn very_soft_rod() -> Stiffness {
    Stiffness::paper_sec5(0.001)
}

/// The state of a sheet at `lbar`: linear interpolation of its traced states.
fn sheet_state(b: &rodloop_diagram::TracedBranch, lbar: f64) -> Vec<f64> {
    let k = b
        .points
        .partition_point(|p| p.value <= lbar)
        .clamp(1, b.points.len() - 1);
    let (p, q) = (&b.points[k - 1], &b.points[k]);
    let t = if q.value > p.value {
        (lbar - p.value) / (q.value - p.value)
    } else {
        0.0
    };
    p.state
        .iter()
        .zip(&q.state)
        .map(|(a, c)| a + t * (c - a))
        .collect()
}

/// No family of branch 2 (η = 1) of the very soft rod is lost: at lengths that are not seed
/// lengths of the tracer (its seeds for η = 1 lie at 1.25, 1.5, 1.75 and 1.0), every
/// equilibrium with one period of κ_g that Newton (with relaxation) reaches from the Euler
/// curve with its origin moved by k/8 of the length (k = 0…7: the soft segment at eight
/// offsets along the loop) lies on a traced sheet: re-solved at that length from the sheet's
/// interpolated state (same resolution), one sheet gives the same equilibrium: energy within
/// 1e-5 relative, the threshold below which the diagram treats families as near-degenerate.
/// (Along the nearly neutral directions of this rod, Newton from two guesses stops at
/// points of one valley whose energies differ by up to ~1e-6; distinct families of η = 1
/// differ by 1e-3 or more at these lengths.) Among these lengths are
/// 1.02–1.06, where the family of η = 1 that exists only on 1 ≤ L̄ < 1.052 lies and where
/// the symmetric family, stepped through a nearly singular stretch near 1.1, could be cut
/// short.
#[test]
fn very_soft_rod_states_lie_on_traced_sheets() {
    use rodloop_solver::identify::identify_equilibrium;
    use rodloop_solver::{solve, solve_from_state, Globalization, SurfaceModel};
    let rod = very_soft_rod();
    let opts = DiagramOptions {
        stiffness: rod.clone(),
        lbar_min: 1.0,
        lbar_max: 3.0,
        ..DiagramOptions::default()
    };
    let fam = rodloop_diagram::families::compute_families(&opts, 1, &mut |_| {}).expect("branch 2");
    let cells = opts.trace_cells(1);
    let newton = SolveOptions {
        globalization: Globalization::Newton,
        ..SolveOptions::default()
    };
    // Energies of the traced sheets over `lbar`, each re-solved there from its own state.
    let sheet_energies = |model: &SurfaceModel, lbar: f64| -> Vec<f64> {
        fam.sheets
            .iter()
            .filter(|b| b.covers(lbar))
            .filter_map(|b| {
                solve_from_state(model.clone(), sheet_state(b, lbar), &newton)
                    .ok()
                    .map(|q| q.energy().total)
            })
            .collect()
    };
    let (mut checked, mut below) = (0, 0);
    for lbar in [1.02, 1.035, 1.06, 1.2, 1.4, 1.65, 1.9] {
        let model = SurfaceModel::new(1.0, lbar, cells, &rod).expect("model");
        let mut seen: Vec<f64> = Vec::new();
        for k in 0..8 {
            let start = StartShape::Euler { l: 1 }
                .shifted(lbar, f64::from(k) / 8.0)
                .expect("start");
            let kappa = start.gauss_values(&model).expect("start values");
            let Ok(eq) = solve(&model, &kappa, &SolveOptions::default()) else {
                continue;
            };
            if identify_equilibrium(&eq).map(|p| p.eta).ok() != Some(1) {
                continue;
            }
            let e = eq.energy().total;
            if seen.iter().any(|s| (s - e).abs() <= 1e-9 * e) {
                continue;
            }
            seen.push(e);
            let on = sheet_energies(&model, lbar);
            assert!(
                on.iter().any(|s| (s - e).abs() <= 1e-5 * e),
                "L̄ = {lbar}, start moved by {k}/8: E = {e} is on no traced sheet ({on:?})"
            );
            checked += 1;
            if lbar < 1.1 {
                below += 1;
            }
        }
    }
    // The symmetric family, which no start above reaches below L̄ = 1.6: followed down from
    // its independent state at 1.65 to 1.06 by Newton at fixed length from the secant of
    // the last two states (natural continuation in steps of 0.01: no pseudo-arclength, no
    // tangents). Below 1.125, where the Jacobian is nearly singular (its smallest singular
    // value falls to ~1e-12 of its largest near 1.107 and is still ~1e-9 at 1.08), Newton
    // stalls at residuals of 1e-9 to 1e-8 and is accepted at 1e-7 (the energy is stationary:
    // far below the 1e-5 of the comparison).
    let model_at = |lbar: f64| SurfaceModel::new(1.0, lbar, cells, &rod).expect("model");
    let loose = SolveOptions {
        tolerance: 1e-7,
        ..newton.clone()
    };
    let mut prev: Option<(Vec<f64>, f64)> = None;
    let mut cur = {
        let model = model_at(1.65);
        let start = StartShape::Euler { l: 1 }
            .gauss_values(&model)
            .expect("start");
        let eq = solve(&model, &start, &SolveOptions::default()).expect("the state at 1.65");
        (eq.state(), 1.65)
    };
    let mut swept: Vec<(f64, f64)> = Vec::new();
    for i in 1..=59 {
        let lbar = 1.65 - 0.01 * f64::from(i);
        let guess: Vec<f64> = match &prev {
            Some((zp, lp)) => {
                let r = (lbar - cur.1) / (cur.1 - lp);
                cur.0.iter().zip(zp).map(|(a, b)| a + (a - b) * r).collect()
            }
            None => cur.0.clone(),
        };
        let check = [1.4, 1.2, 1.08, 1.06]
            .iter()
            .any(|l| (l - lbar).abs() < 1e-9);
        let eq = solve_from_state(model_at(lbar), guess.clone(), &newton)
            .or_else(|e| {
                if lbar > 1.125 {
                    Err(e)
                } else {
                    solve_from_state(model_at(lbar), guess, &loose)
                }
            })
            .unwrap_or_else(|e| panic!("natural continuation at L̄ = {lbar}: {e}"));
        if check {
            swept.push((lbar, eq.energy().total));
        }
        prev = Some(std::mem::replace(&mut cur, (eq.state(), lbar)));
    }
    for (lbar, e) in swept {
        let model = model_at(lbar);
        let on = sheet_energies(&model, lbar);
        assert!(
            on.iter().any(|s| (s - e).abs() <= 1e-5 * e),
            "L̄ = {lbar}, followed down from 1.65: E = {e} is on no traced sheet ({on:?})"
        );
        checked += 1;
        if lbar < 1.1 {
            below += 1;
        }
    }
    // (Below the branch point of this family at 1.0412 the same route reaches, at 1.03, a
    // state of the other branch through it, E = 0.54269, which is not traced: there the
    // Jacobian has a second nearly singular direction and the computed secondary tangent
    // leads back onto the traced family. Not checked; see docs/src/two-segment.md, Limitations.)
    assert!(
        checked >= 8 && below >= 5,
        "{checked} states, {below} below 1.1"
    );
}

/// `κ(s0* + s1* − σ)` at the Gauss points `sigma` (periodic linear interpolation of
/// `kappa` given there): the curvatures of the mirror image of a state of the paper's rod.
fn mirrored(sigma: &[f64], kappa: &[f64], axis: f64) -> Vec<f64> {
    let n = sigma.len();
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| sigma[a].total_cmp(&sigma[b]));
    let at = |t: f64| -> f64 {
        let t = t.rem_euclid(1.0);
        let k = order.partition_point(|&i| sigma[i] <= t);
        let (i0, i1) = (order[(k + n - 1) % n], order[k % n]);
        let (a, mut b) = (sigma[i0], sigma[i1]);
        if b <= a {
            b += 1.0;
        }
        let tt = if t < a { t + 1.0 } else { t };
        kappa[i0] + (tt - a) / (b - a) * (kappa[i1] - kappa[i0])
    };
    sigma.iter().map(|&s| at(axis - s)).collect()
}

/// Each curve of the paper's rod is reported once: no two sheets of branch 1 (η = 2, whose
/// asymmetric family is a closed loop through two pitchforks, traced once per symmetry
/// image before) are the same curve. For every two sheets whose spans overlap by 0.01 or
/// more, both states are re-solved by Newton at three lengths inside the overlap and
/// compared: the same curve would have equal energies (1e-5 relative: mirror images differ
/// by the discretization error of the graded mesh) and one state within
/// 0.05 (root-mean-square of `κ_g R`) of the other, of its reflection `−κ_g`, or of the
/// mirror images `±κ_g(s0* + s1* − σ)`, at all three.
#[test]
fn paper_rod_sheets_are_not_images_of_each_other() {
    use rodloop_solver::{solve_from_state, Globalization, SurfaceModel};
    let rod = paper_rod();
    let opts = DiagramOptions {
        stiffness: rod.clone(),
        lbar_min: 1.0,
        lbar_max: 3.0,
        ..DiagramOptions::default()
    };
    let fam = branch1_families();
    let cells = opts.trace_cells(2);
    let newton = SolveOptions {
        globalization: Globalization::Newton,
        ..SolveOptions::default()
    };
    let sheets = &fam.sheets;
    assert!(sheets.len() >= 2, "{} sheets", sheets.len());
    let mut compared = 0;
    for (i, a) in sheets.iter().enumerate() {
        for b in &sheets[i + 1..] {
            let (lo, hi) = (a.span().0.max(b.span().0), a.span().1.min(b.span().1));
            if hi - lo < 0.01 {
                continue;
            }
            let same_everywhere = [0.25, 0.5, 0.75].iter().all(|f| {
                let lbar = lo + f * (hi - lo);
                let model = SurfaceModel::new(1.0, lbar, cells, &rod).expect("model");
                let nk = model.n_kappa();
                let sigma = model.gauss_sigma();
                let (Ok(za), Ok(zb)) = (
                    solve_from_state(model.clone(), sheet_state(a, lbar), &newton),
                    solve_from_state(model.clone(), sheet_state(b, lbar), &newton),
                ) else {
                    return false;
                };
                let (ea, eb) = (za.energy().total, zb.energy().total);
                let (ka, kb) = (&za.state()[..nk], &zb.state()[..nk]);
                let m = mirrored(&sigma, kb, 0.3 + 0.8);
                let rms = |u: &[f64], sign: f64| {
                    (ka.iter()
                        .zip(u)
                        .map(|(x, y)| (x - sign * y).powi(2))
                        .sum::<f64>()
                        / nk as f64)
                        .sqrt()
                };
                let d = rms(kb, 1.0)
                    .min(rms(kb, -1.0))
                    .min(rms(&m, 1.0))
                    .min(rms(&m, -1.0));
                (ea - eb).abs() <= 1e-5 * ea.abs() && d < 0.05
            });
            compared += 1;
            assert!(
                !same_everywhere,
                "family {} sheet {} ({:?}) and family {} sheet {} ({:?}) are one curve",
                a.family,
                a.sheet,
                a.span(),
                b.family,
                b.sheet,
                b.span()
            );
        }
    }
    assert!(compared >= 1, "no overlapping sheets compared");
}

/// The families of branch 1 (`η = 2`) of the paper's rod on `1 ≤ L̄ ≤ 3`.
fn branch1_families() -> &'static rodloop_diagram::families::Families {
    static F: OnceLock<rodloop_diagram::families::Families> = OnceLock::new();
    F.get_or_init(|| {
        let opts = DiagramOptions {
            stiffness: paper_rod(),
            lbar_min: 1.0,
            lbar_max: 3.0,
            ..DiagramOptions::default()
        };
        rodloop_diagram::families::compute_families(&opts, 2, &mut |_| {}).expect("branch 1")
    })
}

/// A family that passes through a branch point is one family. On the paper's rod the
/// mirror-symmetric family of branch 1 that runs from the 1-fold to the 3-fold great circle
/// crosses the asymmetric one at a pitchfork near `L̄ = 1.81` and is reached there by
/// branch switching, which follows it both ways from the branch point. No two families may
/// then meet end to end: no mirror-symmetric sheet ends (in `L̄`) at a branch point whose
/// state is the start of a mirror-symmetric sheet of another family on the other side of
/// it; and some mirror-symmetric sheet passes through a located branch point.
#[test]
fn a_family_through_a_branch_point_is_one_family() {
    use rodloop_diagram::{PointSource, TracedBranch};
    let fam = branch1_families();
    let symmetric: Vec<&TracedBranch> = fam.sheets.iter().filter(|b| b.multiplicity == 1).collect();
    let rms = |a: &[f64], b: &[f64]| {
        (a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>() / a.len() as f64).sqrt()
    };
    for a in &symmetric {
        let BranchEnd::BranchPoint { value } = a.high_end else {
            continue;
        };
        let end = a.points.last().expect("states");
        for b in &symmetric {
            if b.family == a.family {
                continue;
            }
            let BranchEnd::BranchPoint { value: v } = b.low_end else {
                continue;
            };
            let start = b.points.first().expect("states");
            assert!(
                (v - value).abs() > 1e-9 || rms(&end.state, &start.state) > 1e-8,
                "family {} (up to L̄ = {value}) and family {} (from L̄ = {v}) are the two \
                 halves of one family through the branch point",
                a.family,
                b.family
            );
        }
    }
    let through = symmetric.iter().any(|b| {
        let n = b.points.len();
        b.points[1..n - 1]
            .iter()
            .any(|p| p.source == PointSource::BranchPoint)
    });
    assert!(
        through,
        "no mirror-symmetric sheet passes through a branch point"
    );
}
