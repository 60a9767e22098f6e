//! One state of a traced branch solved accurately at a chosen length: from the Euler curve
//! `l = η` (as `rodloop solve` starts), and where that fails from the diagram's own traced
//! state there (re-solved at the tracing resolution and passed on as points), each result
//! checked to have converged onto branch `η` (identified from the periods of its own `κ_g`);
//! and where each branch of a diagram is shown ([`surface_choices`], [`enclosed_choices`]):
//! the middle of a stretch where the diagram finds it the lowest branch.

use rodloop_solver::identify::identify_equilibrium;
use rodloop_solver::start::from_points;
use rodloop_solver::{
    solve_with_accuracy, Accuracy, AccurateEquilibrium, SolveOptions, SolverError, StartShape,
};

use crate::{DiagramError, DiagramOptions, DiagramRow, Label, NumericDiagram};

/// An error and its causes on one line, `error: cause: cause`.
fn chain(e: &dyn std::error::Error) -> String {
    let mut line = e.to_string();
    let mut cause = e.source();
    while let Some(c) = cause {
        line.push_str(": ");
        line.push_str(&c.to_string());
        cause = c.source();
    }
    line
}

/// An accurate equilibrium of branch `eta` at `lbar` of the diagram's scene (radius and
/// stiffness of `opts`) from `start`, converged and on branch `eta`.
fn solve_checked(
    opts: &DiagramOptions,
    accuracy: Accuracy,
    eta: u32,
    lbar: f64,
    start: &StartShape,
) -> Result<AccurateEquilibrium, String> {
    let res = solve_with_accuracy(
        opts.radius,
        lbar,
        &opts.stiffness,
        start,
        accuracy,
        &SolveOptions::default(),
    )
    .map_err(|e| chain(&e))?;
    let report = res.equilibrium.report();
    if !report.converged {
        return Err(format!(
            "the solve did not converge (KKT residual {:.1e})",
            report.residual
        ));
    }
    rodloop_solver::verify_accurate(&res, Some(eta)).map_err(|e| chain(&e))?;
    let periods = identify_equilibrium(&res.equilibrium).map_err(|e| chain(&e))?;
    if periods.eta != eta {
        return Err(format!(
            "the solve converged onto a state with eta = {} instead of {eta}",
            periods.eta
        ));
    }
    Ok(res)
}

/// Branch `eta` of diagram `d` (traced with `opts`) solved at `lbar` and `accuracy`, and how
/// it was started (`the Euler curve l = η`, or the diagram's traced state with why the Euler
/// start failed).
pub fn solve_on_branch(
    d: &NumericDiagram,
    opts: &DiagramOptions,
    accuracy: Accuracy,
    eta: u32,
    lbar: f64,
) -> Result<(AccurateEquilibrium, String), DiagramError> {
    let euler = match solve_checked(opts, accuracy, eta, lbar, &StartShape::Euler { l: eta }) {
        Ok(r) => return Ok((r, format!("the Euler curve l = {eta}"))),
        Err(e) => e,
    };
    let traced = d
        .branch_by_eta(eta)
        .ok_or_else(|| "the branch is not traced".to_string())
        .and_then(|b| b.solve_at(opts, lbar).map_err(|e| chain(&e)))
        .and_then(|eq| {
            let pts: Vec<[f64; 3]> = eq.profile().iter().map(|p| [p.x, p.y, p.z]).collect();
            from_points(&pts)
                .map(|s| s.0)
                .map_err(|e: SolverError| chain(&e))
        })
        .and_then(|start| solve_checked(opts, accuracy, eta, lbar, &start));
    match traced {
        Ok(r) => Ok((
            r,
            format!("the diagram's traced state (from the Euler curve: {euler})"),
        )),
        Err(e) => Err(DiagramError::Unsolved(format!(
            "from the Euler curve: {euler}; from the diagram's traced state: {e}"
        ))),
    }
}

/// A surface diagram's representative states, reached through its traced branches: where the
/// report shows each branch ([`surface_choices`]) and the branch solved accurately there
/// ([`solve_on_branch`]). Implemented by the surface engine's result, so that the report holds
/// that result without naming it.
pub trait Representatives: Sync {
    /// One length per traced branch ([`surface_choices`]).
    fn choices(&self) -> Vec<Choice>;
    /// Branch `eta` solved at `lbar` and `accuracy` ([`solve_on_branch`]).
    fn solve_on_branch(
        &self,
        opts: &DiagramOptions,
        accuracy: Accuracy,
        eta: u32,
        lbar: f64,
    ) -> Result<(AccurateEquilibrium, String), DiagramError>;
}

impl Representatives for NumericDiagram {
    fn choices(&self) -> Vec<Choice> {
        surface_choices(self)
    }

    fn solve_on_branch(
        &self,
        opts: &DiagramOptions,
        accuracy: Accuracy,
        eta: u32,
        lbar: f64,
    ) -> Result<(AccurateEquilibrium, String), DiagramError> {
        solve_on_branch(self, opts, accuracy, eta, lbar)
    }
}

/// Where one branch of a diagram is shown: the length, why that length, and whether the
/// diagram finds the branch the lowest there.
#[derive(Clone, Debug, PartialEq)]
pub struct Choice {
    /// Paper branch number.
    pub branch: u32,
    /// Periods of `κ_g`.
    pub eta: u32,
    /// The length `L̄`.
    pub lbar: f64,
    /// Why this length, as a phrase (`middle of …`).
    pub why: String,
    /// Whether the diagram finds the branch the lowest state at `lbar`.
    pub lowest: bool,
}

impl Choice {
    /// The stability label of a state of this choice with constrained-Hessian index `index`:
    /// unstable for `index > 0`, else stable where the branch is the lowest, metastable
    /// otherwise.
    pub fn label(&self, index: usize) -> &'static str {
        match (index, self.lowest) {
            (0, true) => "stable",
            (0, false) => "metastable",
            _ => "unstable",
        }
    }
}

/// The middle of `(a, b)`, rounded to 0.01 when that stays well inside (in the middle half).
pub fn middle(a: f64, b: f64) -> f64 {
    let m = 0.5 * (a + b);
    let r = (m * 100.0).round() / 100.0;
    if r > a + 0.25 * (b - a) && r < b - 0.25 * (b - a) {
        r
    } else {
        m
    }
}

/// A row of a diagram as the stable-stretch helpers read it: its branch, its length and
/// whether it is labelled stable (a traced [`DiagramRow`], or a point of the result schema).
pub trait StableRow {
    /// Paper branch.
    fn branch(&self) -> u32;
    /// `L̄`.
    fn lbar(&self) -> f64;
    /// Labelled stable.
    fn stable(&self) -> bool;
}

impl StableRow for DiagramRow {
    fn branch(&self) -> u32 {
        self.branch
    }
    fn lbar(&self) -> f64 {
        self.lbar
    }
    fn stable(&self) -> bool {
        self.stability == Label::Stable
    }
}

/// The stretches of lengths over which the diagram labels branch `branch` stable, in
/// increasing `L̄`: the stable rows of every branch in increasing `L̄`, split where another
/// branch's stable row comes between (a non-uniform rod's branch has several families, so the
/// rows of the branch alone interleave); the lengths of the first and last row of each run.
pub fn stable_stretches<R: StableRow>(rows: &[R], branch: u32) -> Vec<(f64, f64)> {
    let mut stable: Vec<&R> = rows.iter().filter(|r| r.stable()).collect();
    stable.sort_by(|a, b| a.lbar().total_cmp(&b.lbar()));
    stable
        .chunk_by(|a, b| (a.branch() == branch) == (b.branch() == branch))
        .filter(|run| run[0].branch() == branch)
        .map(|run| (run[0].lbar(), run[run.len() - 1].lbar()))
        .collect()
}

/// The stable row nearest each half-integer length `m + ½` strictly inside `(lo, hi)` (of any
/// branch), in increasing `m + ½`; none where the diagram has no stable row.
pub fn stable_near_half_integers<R: StableRow>(rows: &[R], lo: f64, hi: f64) -> Vec<&R> {
    let mut out = Vec::new();
    let mut t = lo.floor() + 0.5;
    while t < hi {
        if t > lo {
            if let Some(r) = nearest_stable(rows.iter(), t) {
                out.push(r);
            }
        }
        t += 1.0;
    }
    out
}

/// The stable row of branch `branch` nearest the middle of its first stable stretch
/// ([`stable_stretches`]).
pub fn middle_of_first_stable<R: StableRow>(rows: &[R], branch: u32) -> Option<&R> {
    let &(a, b) = stable_stretches(rows, branch).first()?;
    nearest_stable(rows.iter().filter(|r| r.branch() == branch), 0.5 * (a + b))
}

/// The stable row of `rows` nearest `lbar`.
fn nearest_stable<'a, R: StableRow + 'a>(
    rows: impl Iterator<Item = &'a R>,
    lbar: f64,
) -> Option<&'a R> {
    rows.filter(|r| r.stable())
        .min_by(|a, b| (a.lbar() - lbar).abs().total_cmp(&(b.lbar() - lbar).abs()))
}

/// One length per traced branch of a surface diagram, in increasing branch number: the
/// middle of its widest stable stretch ([`stable_stretches`]), or of its traced range (the
/// union of its families' and sheets') when it is never the lowest.
pub fn surface_choices(d: &NumericDiagram) -> Vec<Choice> {
    let rows = d.rows();
    let mut spans: std::collections::BTreeMap<u32, (u32, f64, f64)> = Default::default();
    for b in &d.branches {
        let (a, c) = b.span();
        let e = spans
            .entry(b.branch)
            .or_insert((b.eta, f64::INFINITY, f64::NEG_INFINITY));
        e.1 = e.1.min(a);
        e.2 = e.2.max(c);
    }
    spans
        .into_iter()
        .map(|(branch, (eta, lo, hi))| {
            let widest = stable_stretches(&rows, branch)
                .into_iter()
                .max_by(|a, b| (a.1 - a.0).total_cmp(&(b.1 - b.0)));
            let (lbar, why) = match widest {
                Some((a, c)) if c > a => (
                    middle(a, c),
                    format!("middle of its widest stable stretch (traced states at {a:.4} ≤ L̄ ≤ {c:.4})"),
                ),
                Some((a, _)) => (
                    a,
                    format!("the one length where the diagram finds it the lowest branch (L̄ = {a:.4})"),
                ),
                None => (
                    middle(lo, hi),
                    format!("middle of its traced range {lo:.4} ≤ L̄ ≤ {hi:.4} (never the lowest branch there)"),
                ),
            };
            Choice {
                branch,
                eta,
                lbar,
                why,
                lowest: d.lowest_at(lbar).contains(&branch),
            }
        })
        .collect()
}

/// One length per branch of an enclosed diagram (its schema `d`), in increasing branch
/// number: the middle of a stretch of `d.lowest_lifted_off` (the lengths where the lowest
/// state has lifted off the wall, [`crate::engine::lowest_lifted_off`]) where the branch is
/// the lowest state and off the wall, else of its first stable stretch, else of its sampled
/// range. A branch sampled at one length only has none.
pub fn enclosed_choices(d: &rodloop_schema::Diagram) -> Vec<Choice> {
    let mut branches: Vec<(u32, u32)> = d.points.iter().map(|p| (p.branch, p.eta)).collect();
    branches.sort_unstable();
    branches.dedup();
    let lifted = d.lowest_lifted_off.as_deref().unwrap_or_default();
    branches
        .into_iter()
        .filter_map(|(branch, eta)| {
            let (lbar, why, lowest) = enclosed_pick(d, branch, lifted)?;
            Some(Choice {
                branch,
                eta,
                lbar,
                why,
                lowest,
            })
        })
        .collect()
}

/// A sampled state of an enclosed diagram's schema, as [`enclosed_pick`] reads it.
struct Sample {
    lbar: f64,
    lowest: bool,
    attached: bool,
    stable: bool,
}

/// The length of [`enclosed_choices`] for branch `b`, why, and whether it is the lowest.
fn enclosed_pick(
    d: &rodloop_schema::Diagram,
    b: u32,
    lifted: &[(f64, f64)],
) -> Option<(f64, String, bool)> {
    let flag = |p: &rodloop_schema::Point, key: &str| matches!(p.extra.get(key), Some(rodloop_schema::Cell::I(v)) if *v != 0);
    let mut pts: Vec<Sample> = d
        .points
        .iter()
        .filter(|p| p.branch == b)
        .filter_map(|p| {
            Some(Sample {
                lbar: *p.coords.first()?,
                lowest: flag(p, "lowest"),
                attached: flag(p, "attached"),
                stable: p.label.as_deref() == Some(Label::Stable.as_str()),
            })
        })
        .collect();
    pts.sort_by(|a, c| a.lbar.total_cmp(&c.lbar));
    let (lo, hi) = (pts.first()?.lbar, pts.last()?.lbar);
    if hi <= lo {
        return None;
    }
    for &(a, c) in lifted {
        let inside: Vec<_> = pts.iter().filter(|p| p.lbar > a && p.lbar < c).collect();
        if !inside.is_empty() && inside.iter().all(|p| p.lowest && !p.attached) {
            return Some((
                middle(a, c),
                format!("middle of the stretch {a:.6} < L̄ < {c:.6} where it is the lowest state and has lifted off the wall"),
                true,
            ));
        }
    }
    if let Some(start) = pts.iter().position(|p| p.stable) {
        let len = pts[start..].iter().take_while(|p| p.stable).count();
        let (a, c) = (pts[start].lbar, pts[start + len - 1].lbar);
        let at = if c > a { middle(a, c) } else { a };
        return Some((
            at,
            format!("middle of its first stable stretch (samples at {a:.4} ≤ L̄ ≤ {c:.4})"),
            true,
        ));
    }
    Some((
        middle(lo, hi),
        format!("middle of its sampled range {lo:.4} ≤ L̄ ≤ {hi:.4} (never the lowest state there)"),
        false,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::StateShape;

    fn row(branch: u32, lbar: f64, stability: Label) -> DiagramRow {
        DiagramRow {
            branch,
            eta: branch,
            family: 0,
            arc: 0,
            multiplicity: 1,
            lbar,
            energy: lbar,
            energy_g: 0.0,
            energy_error: None,
            stability,
            index: 0,
            lambda_min: 0.0,
            lambda_max: 0.0,
            shape: StateShape {
                point_group: None,
                self_intersections: None,
            },
        }
    }

    /// Branch 1 stable on 1.1–1.3 and 1.7–2.2, branch 2 stable at 1.5 between them (its two
    /// families' rows interleave with branch 1's in `rows`), branch 1 unstable at 1.4.
    fn rows() -> Vec<DiagramRow> {
        use Label::*;
        vec![
            row(1, 2.2, Stable),
            row(1, 1.1, Stable),
            row(2, 1.5, Stable),
            row(1, 1.4, Unstable),
            row(1, 1.3, Stable),
            row(1, 1.7, Stable),
            row(2, 1.45, Metastable),
        ]
    }

    #[test]
    fn stable_stretches_split_where_another_branch_is_stable() {
        let rows = rows();
        assert_eq!(stable_stretches(&rows, 1), vec![(1.1, 1.3), (1.7, 2.2)]);
        assert_eq!(stable_stretches(&rows, 2), vec![(1.5, 1.5)]);
        assert!(stable_stretches(&rows, 3).is_empty());
        // Branch 1 nearest 1.2, the middle of its first stretch: the row at 1.1 or 1.3 (equally
        // near), the first of them in `rows` order.
        let r = middle_of_first_stable(&rows, 1).unwrap();
        assert!(r.lbar == 1.1 || r.lbar == 1.3, "{}", r.lbar);
        // Half-integer lengths inside (1.0, 2.6): 1.5 (branch 2's row) and 2.5 (1.7–2.2: 2.2).
        let near: Vec<(u32, f64)> = stable_near_half_integers(&rows, 1.0, 2.6)
            .iter()
            .map(|r| (r.branch, r.lbar))
            .collect();
        assert_eq!(near, vec![(2, 1.5), (1, 2.2)]);
    }

    #[test]
    fn a_choice_labels_its_state_by_index_and_lowest() {
        let mut c = Choice {
            branch: 1,
            eta: 1,
            lbar: 1.2,
            why: String::new(),
            lowest: true,
        };
        assert_eq!((c.label(0), c.label(1)), ("stable", "unstable"));
        c.lowest = false;
        assert_eq!((c.label(0), c.label(2)), ("metastable", "unstable"));
    }

    #[test]
    fn middle_rounds_only_inside_the_middle_half() {
        assert_eq!(middle(1.0, 2.0), 1.5);
        // 0.5·(1.003 + 1.017) = 1.01 exactly once rounded, and 1.01 is inside the middle half.
        assert_eq!(middle(1.0031, 1.0171), 1.01);
        // The rounded value 0.99 would leave the middle half (0.9915, 0.9945): kept unrounded.
        let m = middle(0.99, 0.996);
        assert!((m - 0.993).abs() < 1e-15, "{m}");
    }
}
