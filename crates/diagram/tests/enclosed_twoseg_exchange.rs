//! The exchange 3 → 1 of the two-segment enclosed diagram (`D1/D0 = 0.5`, `γ = 200`), whose
//! states have contact arcs and re-solve on the ladder of meshes: located on the ladder, its
//! estimate is below `10⁻⁵` (the trace's levels alone give `3·10⁻⁵`), and it agrees within
//! the estimates with the root of `E_1 − E_3` from independent solves (`rodloop solve`'s
//! states, each refined twice on uniform graded meshes: 512 and 640 cells).

mod common;
use common::sharp;
use rodloop_diagram::enclosed::{enclosed_diagram, EnclosedDiagramOptions};
use rodloop_diagram::enclosed_state::solve_state;
use rodloop_exact::diagram::CriticalKind;
use rodloop_solver::enclosed::{solve_enclosed, EnclosedOptions};
use rodloop_solver::Accuracy;

/// Energy of `branch` at `lbar`: `rodloop solve`'s state prolonged and re-solved twice;
/// the finest energy and its last difference (an error bound where the differences fall at
/// least twofold, as they do here).
fn refined(branch: u32, lbar: f64) -> (f64, f64) {
    let res = solve_state(1.0, &sharp(), lbar, branch, Accuracy::Default).expect("solve");
    let opts = EnclosedOptions {
        watchdog: 2,
        ..EnclosedOptions::default()
    };
    let mut cur = res.state;
    let mut e = vec![cur.energy()];
    for _ in 0..2 {
        let (m, z) = cur.refine().expect("prolong");
        cur = solve_enclosed(&m, z, &opts).expect("refined solve");
        e.push(cur.energy());
    }
    let d = [(e[1] - e[0]).abs(), (e[2] - e[1]).abs()];
    assert!(
        d[1] < 0.5 * d[0],
        "branch {branch} at {lbar}: differences {d:?}"
    );
    (e[2], d[1])
}

#[test]
fn exchange_three_to_one_on_the_ladder_agrees_with_refined_solves() {
    let mut o = EnclosedDiagramOptions::new(1.0, sharp(), 2.38, 2.45);
    o.branches = Some(vec![1, 3]);
    let d = enclosed_diagram(&o).expect("two-segment enclosed diagram, 2.38 to 2.45");
    let c = d
        .critical
        .iter()
        .find(|c| {
            c.critical.kind == CriticalKind::Crossing
                && c.critical.from_branch == 3
                && c.critical.to_branch == 1
        })
        .expect("the exchange 3 -> 1");
    let (x, err) = (c.critical.lbar_cr, c.critical.error_estimate);
    assert!(err < 1e-5, "estimate {err:.2e} ({})", c.method);
    // The root of E_1 − E_3 from refined solves at x and x ± 1e-3 (slope from the chord).
    let h = 1e-3;
    let diff = |l: f64| {
        let (a, da) = refined(1, l);
        let (b, db) = refined(3, l);
        (a - b, da + db)
    };
    let (f0, df0) = diff(x);
    let (fm, _) = diff(x - h);
    let (fp, _) = diff(x + h);
    let slope = (fp - fm) / (2.0 * h);
    let curvature = (fp - 2.0 * f0 + fm).abs();
    let x_ref = x - f0 / slope;
    let err_ref = (df0 + curvature) / slope.abs();
    println!("diagram {x:.10} ± {err:.2e}; refined solves {x_ref:.10} ± {err_ref:.2e}");
    assert!(
        (x - x_ref).abs() <= err + err_ref,
        "diagram {x} ± {err:.2e}, refined solves {x_ref} ± {err_ref:.2e}"
    );
}

/// The far lifted-off figure-eight at the exchange 1 → 2 (`L̄ = 1.357968`) touches the wall
/// at points that lie between nodes; prolonged from `N = 96`, semismooth Newton on the
/// min-function makes its contact set cycle and stalls (KKT residual `5·10⁻⁷` after 80
/// iterations at 192 cells). Newton hands over to Fischer–Burmeister there: every level of
/// the ladder `96 … 768` converges, meets the first-order conditions, and its energies
/// converge at one consistent order.
#[test]
fn far_lifted_figure_eight_converges_on_every_level_of_its_ladder() {
    let res = solve_state(1.0, &sharp(), 1.357968, 2, Accuracy::Default).expect("solve");
    let opts = EnclosedOptions {
        watchdog: 2,
        ..EnclosedOptions::default()
    };
    let mut cur = res.state;
    let mut e = vec![cur.energy()];
    for _ in 0..3 {
        let (m, z) = cur.refine().expect("prolong");
        cur = solve_enclosed(&m, z, &opts).expect("Newton converges on the prolonged level");
        let n = cur.model.cells();
        // The solver's acceptance: the tolerance, or 100 times it at its round-off floor on
        // meshes of 256 cells and more.
        // The wall rows hold to that residual: a gap of `-1.5e-8 R` at 384 cells.
        let (tol, gap) = if n >= 256 {
            (1e-8, 5e-8)
        } else {
            (1e-10, 1e-9)
        };
        assert!(
            cur.residual < tol,
            "N = {n}: KKT residual {:.2e}",
            cur.residual
        );
        let (lmin, gmin, comp, stat) = cur.optimality().expect("optimality");
        assert!(
            lmin > -1e-6 && gmin > -gap,
            "N = {n}: lambda {lmin:.2e}, gap {gmin:.2e}"
        );
        assert!(
            comp < 1e-7 && stat < 1e-6,
            "N = {n}: comp {comp:.2e}, stat {stat:.2e}"
        );
        e.push(cur.energy());
    }
    let d: Vec<f64> = e.windows(2).map(|w| (w[1] - w[0]).abs()).collect();
    let p = [(d[0] / d[1]).log2(), (d[1] / d[2]).log2()];
    println!("energies {e:?}, differences {d:?}, observed orders {p:?}");
    assert!(
        p.iter().all(|&q| (2.0..=4.5).contains(&q)) && (p[0] - p[1]).abs() < 0.75,
        "observed orders {p:?} (energies {e:?})"
    );
}
