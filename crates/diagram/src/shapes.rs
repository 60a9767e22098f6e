//! Point group and self-intersections of every traced state (the `point_group` and
//! `self_intersections` columns of `branches.csv`), from the state's unknowns by
//! the surface model's `shape`: the positions are integrated from `κ_g`, no
//! re-solve. Each state is a task of the crate's pool.

use rodloop_exact::shape::ShapeTolerances;
use serde::Serialize;

use crate::parallel::run_parallel;
use crate::types::TracedBranch;
use crate::DiagramOptions;

/// Shape descriptors of one traced state.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StateShape {
    /// Schoenflies symbol (`D2d`, `C2v`, `D3h`, `D∞h`, …); `None` if the state could not be
    /// reconstructed (a warning says why).
    pub point_group: Option<String>,
    /// Number of self-intersections; `None` for a multiply covered circle (it overlaps
    /// itself everywhere) or when `point_group` is `None`.
    pub self_intersections: Option<usize>,
}

impl StateShape {
    /// The count for a table cell: the number, `overlap`, or empty when unknown.
    pub fn self_intersections_label(&self) -> String {
        match (&self.point_group, self.self_intersections) {
            (_, Some(k)) => k.to_string(),
            (Some(_), None) => "overlap".into(),
            (None, None) => String::new(),
        }
    }
}

/// Shapes of every state of every branch (`[i][k]` for `branches[i].points[k]`), with the
/// warnings for states that could not be reconstructed.
pub(crate) fn state_shapes(
    opts: &DiagramOptions,
    branches: &[TracedBranch],
    tol: ShapeTolerances,
) -> (Vec<Vec<StateShape>>, Vec<String>) {
    let threads = if opts.threads == 0 {
        std::thread::available_parallelism().map_or(1, |n| n.get())
    } else {
        opts.threads
    };
    // One task per state (the branches differ in size), regrouped by branch below.
    let items: Vec<(&TracedBranch, usize)> = branches
        .iter()
        .flat_map(|b| (0..b.points.len()).map(move |k| (b, k)))
        .collect();
    let mut flat = run_parallel(
        threads,
        items,
        &mut |_| {},
        &mut |_| {},
        |(b, k): (&TracedBranch, usize), _| {
            let p = &b.points[k];
            opts.model(p.value, b.cells)
                .and_then(|m| m.shape(&p.state, tol))
                .map_err(|e| {
                    format!(
                        "branch {} (η = {}) at L̄ = {}: no shape ({e})",
                        b.branch, b.eta, p.value
                    )
                })
        },
    )
    .into_iter();
    let results: Vec<Vec<_>> = branches
        .iter()
        .map(|b| flat.by_ref().take(b.points.len()).collect())
        .collect();
    let mut warnings = Vec::new();
    let shapes = results
        .into_iter()
        .map(|states| {
            states
                .into_iter()
                .map(|r| match r {
                    Ok(sh) => StateShape {
                        point_group: Some(sh.point_group),
                        self_intersections: sh.self_intersections,
                    },
                    Err(w) => {
                        warnings.push(w);
                        StateShape {
                            point_group: None,
                            self_intersections: None,
                        }
                    }
                })
                .collect()
        })
        .collect();
    (shapes, warnings)
}
