//! The enclosed engine ([`EnclosedEngine`], `|r| ≤ R`, paper Sec. 3.2) and its result in the
//! schema, with the stretches where the lowest state has lifted off ([`lowest_lifted_off`])
//! and the completeness certificate of a non-uniform rod's diagram
//! ([`EnclosedEngine::certificate`]: `solve`'s search at a few lowest states).

use std::collections::BTreeMap;

use rodloop_schema::{Cell, Diagram, Point, SpecialPoint};
use serde::Serialize;

use super::{columns, critical_of, lbar_axis, Engine, PointState, PointStates, StateSource, UNITS};
use crate::enclosed::{
    enclosed_diagram_with, EnclosedDiagram, EnclosedDiagramOptions, EnclosedProgress,
};
use crate::DiagramError;

/// The enclosed engine (`|r| ≤ R`, paper Sec. 3.2): attached parts from the exact layer (or
/// the surface families of a non-uniform rod), lifted-off parts from the 3-D model, events
/// where `λ_min` crosses zero, exchanges re-solved where a branch has lifted off.
pub struct EnclosedEngine {
    /// What to compute.
    pub opts: EnclosedDiagramOptions,
}

impl EnclosedEngine {
    /// The engine for the diagram of `stiffness` inside `wall` over `lbar_min ≤ L̄ ≤ lbar_max`
    /// with the default settings of [`EnclosedDiagramOptions::new`] (set the others on
    /// `opts`).
    pub fn new(
        wall: impl rodloop_solver::enclosed::IntoWall,
        stiffness: rodloop_solver::Stiffness,
        lbar_min: f64,
        lbar_max: f64,
    ) -> Self {
        Self {
            opts: EnclosedDiagramOptions::new(wall, stiffness, lbar_min, lbar_max),
        }
    }
}

impl Engine for EnclosedEngine {
    type Output = EnclosedDiagram;
    type Progress = EnclosedProgress;

    fn model(&self) -> &'static str {
        "enclosed"
    }

    fn run(
        &mut self,
        progress: &mut dyn FnMut(EnclosedProgress),
    ) -> Result<EnclosedDiagram, DiagramError> {
        enclosed_diagram_with(&self.opts, progress)
    }

    fn schema(&self, d: &EnclosedDiagram, scene: &str) -> Result<Diagram, DiagramError> {
        let opts = &self.opts;
        let mut out = Diagram::new(
            "enclosed",
            scene,
            lbar_axis(opts.lbar_min, opts.lbar_max),
            UNITS,
        );
        out.accuracy = Some(format!("{:?}", opts.accuracy).to_lowercase());
        out.columns = columns(&[
            "branch",
            "eta",
            "lbar",
            "energy",
            "energy_error",
            "attached",
            "contact_fraction",
            "contact_intervals",
            "max_gap",
            "lambda_min",
            "gap_min",
            "complementarity",
            "stationarity",
            "index",
            "label",
            "lowest",
            "cells",
            "source",
            "family",
            "sheet",
            "multiplicity",
            "surface_energy",
            "branch_from",
            "state_file",
        ]);
        let mut points = Vec::with_capacity(d.points.len());
        for p in &d.points {
            let source = serde_json::to_value(p.source)
                .ok()
                .and_then(|v| v.as_str().map(str::to_string))
                .unwrap_or_default();
            points.push(Point {
                branch: p.branch,
                eta: p.eta,
                family: Some(p.family),
                sheet: Some(p.sheet),
                coords: vec![p.lbar],
                energy: p.energy,
                energy_error: Some(p.energy_error),
                index: Some(p.index),
                label: Some(p.label.as_str().into()),
                state_file: Some(String::new()),
                extra: BTreeMap::from([
                    ("attached".into(), Cell::I(p.attached.into())),
                    ("contact_fraction".into(), Cell::F(p.contact_fraction)),
                    (
                        "contact_intervals".into(),
                        Cell::I(p.contact_intervals as i64),
                    ),
                    ("max_gap".into(), Cell::F(p.max_gap)),
                    ("lambda_min".into(), Cell::F(p.lambda_min)),
                    ("gap_min".into(), Cell::F(p.gap_min)),
                    ("complementarity".into(), Cell::F(p.complementarity)),
                    ("stationarity".into(), Cell::F(p.stationarity)),
                    ("lowest".into(), Cell::I(p.lowest.into())),
                    ("cells".into(), Cell::I(p.cells as i64)),
                    ("source".into(), Cell::S(source)),
                    ("multiplicity".into(), Cell::I(p.multiplicity.into())),
                    (
                        "surface_energy".into(),
                        p.surface_energy.map_or(Cell::Empty, Cell::F),
                    ),
                    ("branch_from".into(), Cell::S(p.branch_from.as_str().into())),
                ]),
            });
        }
        out.points = points;
        out.critical = d
            .critical
            .iter()
            .map(critical_of)
            .collect::<Result<_, _>>()?;
        out.special = Some(
            d.events
                .iter()
                .map(|e| SpecialPoint {
                    kind: e.kind.as_str().into(),
                    lbar: e.lbar,
                    energy: e.energy,
                    error_estimate: Some(e.error_estimate),
                    branch: e.branch,
                    family: e.family,
                    index_before: Some(e.index_before),
                    index_after: Some(e.index_after),
                    value: None,
                    energy_error: None,
                    extra: BTreeMap::new(),
                })
                .collect(),
        );
        out.warnings = Some(d.warnings.clone());
        out.set_timings(&d.seconds)?;
        let solves: std::collections::BTreeMap<&str, _> =
            d.solves.iter().map(|(s, c)| (s.name(), *c)).collect();
        out.put("solves", &solves)?;
        out.states_dir = Some("states".into());
        out.put("step", &opts.step)?;
        out.put("states", &d.points.len())?;
        // With a branch selection, "lowest" is among the selected branches only: no
        // hypothesis verdict.
        out.lowest_lifted_off = opts.branches.is_none().then(|| lowest_lifted_off(d));
        out.put("cells", &d.cells)?;
        out.notes = Some(d.notes.clone());
        Ok(out)
    }
}

/// The states of an enclosed diagram by point (the schema's points): every point, the
/// lifted-off 3-D states as they are and attached ones as their surface loop, in
/// `states/enclosed-branch-B-KKK.csv`, or `states/enclosed-branch-B-family-F-sheet-S-KKK.csv`
/// for a family of a non-uniform rod (`k` counts the points of the branch, family and sheet
/// in increasing `L̄`).
impl PointStates for EnclosedDiagram {
    fn point_states(&self) -> Vec<Option<PointState<'_>>> {
        let points = &self.points;
        let key = |i: usize| (points[i].branch, points[i].family, points[i].sheet);
        let mut order: Vec<usize> = (0..points.len()).collect();
        order.sort_by(|&a, &b| {
            key(a)
                .cmp(&key(b))
                .then(points[a].lbar.total_cmp(&points[b].lbar))
        });
        let mut out: Vec<Option<PointState<'_>>> = points.iter().map(|_| None).collect();
        let mut count = 0;
        for (pos, &i) in order.iter().enumerate() {
            if pos > 0 && key(order[pos - 1]) != key(i) {
                count = 0;
            }
            let p = &points[i];
            out[i] = Some(PointState {
                name: super::state_file_name("enclosed-branch", p.branch, p.family, p.sheet, count),
                source: StateSource::Enclosed(p),
            });
            count += 1;
        }
        out
    }
}

/// A lowest state of the diagram as the certificate names it: branch, family, energy, error
/// estimate.
pub type LowestState = (u32, u32, f64, f64);

/// One check of the enclosed completeness certificate: `solve`'s state of a branch at the
/// length of a lowest state of the diagram.
#[derive(Clone, Debug, Serialize)]
pub struct CertificateCheck {
    /// `L̄` (that of the diagram's lowest state).
    pub lbar: f64,
    /// The branch `solve` was asked for.
    pub branch: u32,
    /// `solve`'s energy and error estimate (`None` where it found no state).
    pub solve_energy: Option<(f64, f64)>,
    /// The diagram's lowest state there: branch, family, energy, error estimate.
    pub lowest: LowestState,
    /// `solve`'s state lies below the lowest state by more than the two estimates.
    pub below: bool,
    /// `solve` was asked for the lowest state's branch and its state (or none) lies above the
    /// lowest state by more than the two estimates: `solve --branch` misses the stable state.
    pub misses: bool,
    /// Why `solve` found no state (empty otherwise).
    pub note: String,
}

impl CertificateCheck {
    /// The check of `solve`'s result `solve_energy` for `branch` at `lbar` against the
    /// diagram's `lowest` state there: below it, or (for its own branch) above it, by more
    /// than the two estimates; `solve` finding no state misses the lowest state of its branch.
    pub fn new(
        lbar: f64,
        branch: u32,
        solve_energy: Option<(f64, f64)>,
        lowest: LowestState,
        note: String,
    ) -> Self {
        let (_, _, e0, de0) = lowest;
        let (below, misses) = match solve_energy {
            Some((e, de)) => (e + de < e0 - de0, branch == lowest.0 && e - de > e0 + de0),
            None => (false, branch == lowest.0),
        };
        Self {
            lbar,
            branch,
            solve_energy,
            lowest,
            below,
            misses,
            note,
        }
    }
}

/// One check of the certificate at a located exchange `E_a = E_b`: `solve`'s state of each
/// of the two branches at `L̄_cr` against the exchange's energy `E_c`, within the solve's
/// estimate, the diagram's there and the slope of the branch times the exchange's estimate.
/// A state of either branch below `E_c` is one the diagram did not trace next to the
/// exchange (the exchange is then elsewhere); a state above it, or none, is `solve --branch`
/// not reaching the traced one (a state whose own periods name no branch, which `solve`
/// refuses, or a saddle there).
#[derive(Clone, Debug, Serialize)]
pub struct ExchangeCheck {
    /// `L̄_cr`.
    pub lbar: f64,
    /// The exchange's error estimate in `L̄`.
    pub error_estimate: f64,
    /// The branches lowest below and above it.
    pub branches: [u32; 2],
    /// The diagram's energy at the exchange and its estimate.
    pub energy: (f64, f64),
    /// `solve`'s energy and error estimate for each branch (`None` where it found no local
    /// minimum).
    pub solve_energies: [Option<(f64, f64)>; 2],
    /// `|E − E_c|` allowed for each branch: the two estimates plus the slope times the
    /// exchange's estimate.
    pub allowed: [f64; 2],
    /// A state of `solve` lies below `E_c` beyond its allowance: the diagram missed it.
    pub below: bool,
    /// `solve` finds no local minimum of a branch, or one above `E_c` beyond its allowance.
    pub misses: bool,
    /// Why `solve` found no local minimum (empty otherwise).
    pub note: String,
}

impl ExchangeCheck {
    /// The check of `solve`'s states `found` (energy and estimate, or why there is none) of
    /// the two `branches` at an exchange `lbar ± error_estimate` of energy `energy` (and its
    /// estimate), where the branches' energies have the slopes `slopes`.
    pub fn new(
        lbar: f64,
        error_estimate: f64,
        branches: [u32; 2],
        energy: (f64, f64),
        slopes: [f64; 2],
        found: [Result<(f64, f64), String>; 2],
    ) -> Self {
        let (mut below, mut misses) = (false, false);
        let mut allowed = [0.0; 2];
        for k in 0..2 {
            allowed[k] = energy.1 + slopes[k].abs() * error_estimate;
            match &found[k] {
                Ok((e, de)) => {
                    allowed[k] += de;
                    below |= e - energy.0 < -allowed[k];
                    misses |= e - energy.0 > allowed[k];
                }
                Err(_) => misses = true,
            }
        }
        let note = found
            .iter()
            .zip(branches)
            .filter_map(|(f, b)| f.as_ref().err().map(|e| format!("branch {b}: {e}")))
            .collect::<Vec<_>>()
            .join("; ");
        Self {
            lbar,
            error_estimate,
            branches,
            energy,
            solve_energies: [found[0].clone().ok(), found[1].clone().ok()],
            allowed,
            below,
            misses,
            note,
        }
    }
}

/// The enclosed completeness certificate: at lowest states and at located exchanges.
#[derive(Clone, Debug, Default, Serialize)]
pub struct EnclosedCertificate {
    /// `solve` for every branch at a few lowest states.
    pub at_lowest: Vec<CertificateCheck>,
    /// `solve` for the two branches at each located exchange.
    pub at_exchanges: Vec<ExchangeCheck>,
}

/// Lowest states at which the certificate runs `solve`: three, spread over the range.
const CERTIFICATE_SAMPLES: usize = 3;

impl EnclosedEngine {
    /// The completeness certificate of a non-uniform rod's diagram `d`: at the lengths of
    /// `CERTIFICATE_SAMPLES` lowest states of the diagram spread over its range, `solve`'s
    /// search ([`crate::enclosed_state::solve_state`]: the surface loop of each branch that
    /// exists there, then the enclosed loop from it) for every selected branch, in parallel; a
    /// state of `solve` below the diagram's lowest one by more than the two error estimates is
    /// a state the diagram missed. A uniform rod's diagram and `solve` start from the same
    /// exact surface loops: no check there (empty).
    ///
    /// At each located exchange `E_a = E_b` the same search for the two branches
    /// ([`ExchangeCheck`]): the lowest states next to an exchange are the ones least sampled
    /// by the lengths above (random seed 22 of `tests/random_enclosed.rs`: a branch-1 family
    /// reached only by a search from a saddle moves its exchange 1 → 2 by `5.6·10⁻⁴`).
    pub fn certificate(&self, d: &EnclosedDiagram) -> EnclosedCertificate {
        let opts = &self.opts;
        if opts.stiffness.is_uniform() {
            return EnclosedCertificate::default();
        }
        let mut lowest: Vec<_> = d
            .points
            .iter()
            .filter(|p| p.lowest && p.branch > 0)
            .collect();
        lowest.sort_by(|a, b| a.lbar.total_cmp(&b.lbar));
        if lowest.is_empty() {
            return EnclosedCertificate::default();
        }
        let n = lowest.len();
        let mut picks: Vec<usize> = (0..CERTIFICATE_SAMPLES)
            .map(|i| ((2 * i + 1) * n / (2 * CERTIFICATE_SAMPLES)).min(n - 1))
            .collect();
        picks.dedup();
        let wanted = |b: u32| opts.branches.as_ref().is_none_or(|s| s.contains(&b));
        // The solves: `(L̄, branch)`, at the picked lowest states (each with that state),
        // then two at each exchange.
        let mut at_picks: Vec<(f64, u32, LowestState)> = Vec::new();
        for &i in &picks {
            let p = lowest[i];
            let top = p.lbar.floor() as u32 + 1;
            for eta in 1..=top {
                let e = f64::from(eta);
                let branch = rodloop_exact::branch_of_eta(eta);
                if p.lbar > e - 1.0 && p.lbar < e + 1.0 && wanted(branch) {
                    at_picks.push((
                        p.lbar,
                        branch,
                        (p.branch, p.family, p.energy, p.energy_error),
                    ));
                }
            }
        }
        let exchanges: Vec<_> = d
            .critical
            .iter()
            .map(|c| &c.critical)
            .filter(|c| {
                c.kind == crate::critical::CriticalKind::Crossing
                    && c.from_branch > 0
                    && c.to_branch > 0
            })
            .collect();
        let jobs: Vec<(f64, u32)> = at_picks
            .iter()
            .map(|&(x, b, _)| (x, b))
            .chain(
                exchanges
                    .iter()
                    .flat_map(|c| [(c.lbar_cr, c.from_branch), (c.lbar_cr, c.to_branch)]),
            )
            .collect();
        let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
        let solved = crate::parallel::run_parallel(
            threads,
            jobs,
            &mut |_| {},
            &mut |_| {},
            |(x, branch), _| {
                crate::enclosed_state::solve_state(
                    &opts.wall,
                    &opts.stiffness,
                    x,
                    branch,
                    opts.accuracy,
                )
                .map(|res| (res.energy, res.stability.0))
                .map_err(|e| error_chain(&e))
            },
        );
        let (at_lowest_solved, at_exchange_solved) = solved.split_at(at_picks.len());
        let at_lowest = at_picks
            .iter()
            .zip(at_lowest_solved)
            .map(|(&(x, b, lowest), found)| match found {
                Ok((e, _)) => CertificateCheck::new(x, b, Some(*e), lowest, String::new()),
                Err(why) => CertificateCheck::new(x, b, None, lowest, why.clone()),
            })
            .collect();
        let minimum = |found: &Result<((f64, f64), usize), String>| {
            found.clone().and_then(|(e, index)| {
                if index == 0 {
                    Ok(e)
                } else {
                    Err(format!("solve finds no local minimum (index {index})"))
                }
            })
        };
        let at_exchanges = exchanges
            .iter()
            .zip(at_exchange_solved.chunks(2))
            .map(|(c, found)| {
                let (x, b) = (c.lbar_cr, [c.from_branch, c.to_branch]);
                let (slopes, de) = exchange_slopes(d, x, b);
                ExchangeCheck::new(
                    x,
                    c.error_estimate,
                    b,
                    (c.energy, de),
                    slopes,
                    [minimum(&found[0]), minimum(&found[1])],
                )
            })
            .collect();
        EnclosedCertificate {
            at_lowest,
            at_exchanges,
        }
    }
}

/// The least energy of branch `b`'s rows at `x`, each family's sheet interpolated linearly
/// between its samples (`None` where no sheet of the branch spans `x`).
fn branch_energy(d: &EnclosedDiagram, b: u32, x: f64) -> Option<f64> {
    let mut sheets: BTreeMap<(u32, u32), Vec<(f64, f64)>> = BTreeMap::new();
    for p in d.points.iter().filter(|p| p.branch == b) {
        sheets
            .entry((p.family, p.sheet))
            .or_default()
            .push((p.lbar, p.energy));
    }
    sheets
        .values_mut()
        .filter_map(|pts| {
            pts.sort_by(|u, v| u.0.total_cmp(&v.0));
            let k = pts.partition_point(|q| q.0 < x);
            let v = pts.get(k)?;
            if v.0 == x {
                return Some(v.1);
            }
            let u = pts.get(k.checked_sub(1)?)?;
            Some(u.1 + (x - u.0) / (v.0 - u.0) * (v.1 - u.1))
        })
        .min_by(f64::total_cmp)
}

/// The slopes `dE/dL̄` of the two branches at the exchange `x` (the chords of
/// [`branch_energy`] between the nearest lowest rows on either side), and the larger energy
/// estimate of those two rows.
fn exchange_slopes(d: &EnclosedDiagram, x: f64, branches: [u32; 2]) -> ([f64; 2], f64) {
    let lows: Vec<_> = d.points.iter().filter(|p| p.lowest).collect();
    let left = lows
        .iter()
        .filter(|p| p.lbar < x)
        .max_by(|a, b| a.lbar.total_cmp(&b.lbar));
    let right = lows
        .iter()
        .filter(|p| p.lbar > x)
        .min_by(|a, b| a.lbar.total_cmp(&b.lbar));
    let (Some(l), Some(r)) = (left, right) else {
        return ([0.0; 2], 0.0);
    };
    let slope = |b: u32| {
        let (el, er) = (branch_energy(d, b, l.lbar), branch_energy(d, b, r.lbar));
        el.zip(er)
            .map_or(0.0, |(el, er)| (er - el) / (r.lbar - l.lbar))
    };
    (
        [slope(branches[0]), slope(branches[1])],
        l.energy_error.max(r.energy_error),
    )
}

/// The `L̄` intervals where the lowest state of an enclosed diagram is a paper branch that has
/// lifted off (branch 0, the free circle below `L̄ = 1`, is not counted): from each critical
/// length or event to the next, when the lowest branch there is lifted off at the samples
/// between.
pub fn lowest_lifted_off(d: &EnclosedDiagram) -> Vec<(f64, f64)> {
    use crate::enclosed::EventKind;
    let mut cuts: Vec<f64> = d
        .critical
        .iter()
        .map(|c| c.critical.lbar_cr)
        .chain(
            d.events
                .iter()
                .filter(|e| matches!(e.kind, EventKind::LiftOff | EventKind::Landing))
                .map(|e| e.lbar),
        )
        .collect();
    cuts.push(
        d.points
            .iter()
            .map(|p| p.lbar)
            .fold(f64::INFINITY, f64::min),
    );
    cuts.push(
        d.points
            .iter()
            .map(|p| p.lbar)
            .fold(f64::NEG_INFINITY, f64::max),
    );
    cuts.sort_by(f64::total_cmp);
    cuts.dedup_by(|a, b| (*a - *b).abs() < 1e-12);
    let mut out: Vec<(f64, f64)> = Vec::new();
    for w in cuts.windows(2) {
        let inside: Vec<_> = d
            .points
            .iter()
            .filter(|p| p.lowest && p.branch > 0 && p.lbar > w[0] + 1e-9 && p.lbar < w[1] - 1e-9)
            .collect();
        if !inside.is_empty() && inside.iter().all(|p| !p.attached) {
            match out.last_mut() {
                Some(last) if (last.1 - w[0]).abs() < 1e-12 => last.1 = w[1],
                _ => out.push((w[0], w[1])),
            }
        }
    }
    out
}

/// An error and its sources, `: `-separated (as `anyhow` prints a chain with `{:#}`).
fn error_chain(e: &dyn std::error::Error) -> String {
    let mut out = e.to_string();
    let mut source = e.source();
    while let Some(s) = source {
        out.push_str(": ");
        out.push_str(&s.to_string());
        source = s.source();
    }
    out
}

#[cfg(test)]
mod tests {
    use super::{CertificateCheck, ExchangeCheck};

    /// At an exchange `1.5 ± 1e-4` of energy `2 ± 1e-5` where the slopes are 1 and −1,
    /// `solve`'s state of each branch is level with it within its own estimate, `10⁻⁵` and
    /// `10⁻⁴`; below that a state the diagram missed, above it (or none) `solve` missing the
    /// traced one.
    #[test]
    fn exchange_checks_allow_the_estimates_and_the_shift_of_the_exchange() {
        let check = |ea: f64, eb: f64| {
            let c = ExchangeCheck::new(
                1.5,
                1e-4,
                [1, 2],
                (2.0, 1e-5),
                [1.0, -1.0],
                [Ok((ea, 2e-5)), Ok((eb, 3e-5))],
            );
            (c.below, c.misses)
        };
        assert_eq!(check(2.0 + 1.2e-4, 2.0 - 1.3e-4), (false, false));
        assert_eq!(check(2.0 - 1.4e-4, 2.0), (true, false));
        assert_eq!(check(2.0, 2.0 + 1.5e-4), (false, true));
        let none = ExchangeCheck::new(
            1.5,
            1e-4,
            [1, 2],
            (2.0, 1e-5),
            [1.0, -1.0],
            [Ok((2.0, 1e-5)), Err("x".into())],
        );
        assert!(none.misses && !none.below && none.note == "branch 2: x");
        assert!(none.solve_energies[1].is_none());
    }

    /// A state of `solve` counts as below or above the lowest state only beyond the sum of
    /// the two estimates, and above only for the lowest state's own branch.
    #[test]
    fn certificate_checks_compare_beyond_both_estimates() {
        let lowest = (2, 1, 1.0, 1e-3);
        let check = |branch, e: f64, de: f64| {
            let c = CertificateCheck::new(1.5, branch, Some((e, de)), lowest, String::new());
            (c.below, c.misses)
        };
        // Within the two estimates either way: the same state.
        assert_eq!(check(2, 1.0 + 1.5e-3, 1e-3), (false, false));
        assert_eq!(check(2, 1.0 - 1.5e-3, 1e-3), (false, false));
        // Beyond them: a state the diagram missed, or the stable state `solve` missed.
        assert_eq!(check(2, 1.0 - 2.5e-3, 1e-3), (true, false));
        assert_eq!(check(2, 1.0 + 2.5e-3, 1e-3), (false, true));
        // Another branch above the lowest state is expected.
        assert_eq!(check(1, 1.5, 1e-3), (false, false));
        assert_eq!(check(1, 0.9, 1e-3), (true, false));
        // No state of the lowest state's branch misses it; of another branch, says nothing.
        let none = |branch| CertificateCheck::new(1.5, branch, None, lowest, "x".into());
        assert!(none(2).misses && !none(2).below);
        assert!(!none(1).misses);
    }
}
