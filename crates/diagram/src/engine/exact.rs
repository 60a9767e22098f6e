//! The exact engine ([`ExactEngine`]): the closed-form loops of a homogeneous rod on the
//! sphere in a window of lengths ([`exact_window`]), and their result in the schema (also
//! without shape descriptors, the exact values a numeric diagram is compared with:
//! [`exact_window_schema`], [`exact_counterpart`]).

use std::collections::BTreeMap;

use rodloop_schema::{Cell, Critical, Diagram, Point};

use super::{columns, critical_of, lbar_axis, Engine, UNITS};
use crate::DiagramError;

/// The exact engine: closed-form elliptic-function loops of a homogeneous rod on the sphere,
/// sampled every `step` in `L̄`, with the critical lengths solved to machine precision.
pub struct ExactEngine {
    /// Smallest length.
    pub lbar_min: f64,
    /// Largest length.
    pub lbar_max: f64,
    /// Sample spacing.
    pub step: f64,
    /// Only these paper branches (`None`: all).
    pub branches: Option<Vec<u32>>,
    /// Threads for the shape descriptors.
    pub threads: usize,
}

/// The exact engine's result.
#[derive(Clone, Debug)]
pub struct ExactOutput {
    /// The exact diagram of the window.
    pub diagram: rodloop_exact::diagram::Diagram,
    /// Shape descriptors of its points, in order.
    pub shapes: Vec<rodloop_exact::shape::LoopShape>,
    /// Seconds of the diagram.
    pub seconds: f64,
    /// Seconds of the shape descriptors.
    pub seconds_shapes: f64,
}

/// The exact diagram `d` of the window `lbar` in the schema: its loops as points (with the
/// shape descriptors of each, `shapes` in order, where they were computed) and its critical
/// lengths.
fn exact_schema(
    d: &rodloop_exact::diagram::Diagram,
    shapes: Option<&[rodloop_exact::shape::LoopShape]>,
    (lbar_min, lbar_max): (f64, f64),
    scene: &str,
) -> Result<Diagram, DiagramError> {
    let mut s = Diagram::new("exact", scene, lbar_axis(lbar_min, lbar_max), UNITS);
    let mut names = vec![
        "branch",
        "eta",
        "lbar",
        "energy",
        "energy_g",
        "lambda_min",
        "lambda_max",
        "p",
        "k",
        "c",
        "closure_residual",
        "lowest",
    ];
    if shapes.is_some() {
        names.extend(["point_group", "self_intersections"]);
    }
    s.columns = columns(&names);
    s.points = d
        .points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let mut extra = BTreeMap::from([
                ("energy_g".into(), Cell::F(p.energy_g)),
                ("lambda_min".into(), Cell::F(p.lambda_min)),
                ("lambda_max".into(), Cell::F(p.lambda_max)),
                ("p".into(), Cell::I(p.p.into())),
                ("k".into(), Cell::F(p.k)),
                ("c".into(), Cell::F(p.c)),
                ("closure_residual".into(), Cell::F(p.closure_residual)),
                ("lowest".into(), Cell::I(p.lowest.into())),
            ]);
            if let Some(sh) = shapes.and_then(|s| s.get(i)) {
                extra.insert("point_group".into(), Cell::S(sh.point_group.clone()));
                extra.insert(
                    "self_intersections".into(),
                    Cell::S(sh.self_intersections_label()),
                );
            }
            Point {
                branch: p.branch,
                eta: p.eta,
                coords: vec![p.lbar],
                energy: p.energy,
                extra,
                ..Point::default()
            }
        })
        .collect();
    s.critical = d
        .critical
        .iter()
        .map(critical_of)
        .collect::<Result<_, _>>()?;
    Ok(s)
}

/// The exact diagram of the window `[lbar_min, lbar_max]` ([`exact_window`], sampled every
/// `step`) in the schema, without shape descriptors: the exact values a numeric diagram of a
/// homogeneous scene is compared with ([`exact_counterpart`]), and the loops of the exact
/// layer's figures.
pub fn exact_window_schema(
    lbar_min: f64,
    lbar_max: f64,
    step: f64,
    scene: &str,
) -> Result<Diagram, DiagramError> {
    let d = exact_window(lbar_min, lbar_max, step)
        .map_err(|e| DiagramError::InvalidOptions(e.to_string()))?;
    let mut s = exact_schema(&d, None, (lbar_min, lbar_max), scene)?;
    s.put("step", &step)?;
    Ok(s)
}

/// The exact layer's counterpart of the critical length `c` in the exact diagram `exact`:
/// the same kind (`crossing`, `collapse`) between the same branches, within 0.05 in `L̄`,
/// the nearest one.
pub fn exact_counterpart<'a>(c: &Critical, exact: &'a Diagram) -> Option<&'a Critical> {
    exact
        .critical
        .iter()
        .filter(|x| {
            x.kind == c.kind
                && x.from_branch == c.from_branch
                && x.to_branch == c.to_branch
                && (x.lbar_cr - c.lbar_cr).abs() < 0.05
        })
        .min_by(|a, b| {
            (a.lbar_cr - c.lbar_cr)
                .abs()
                .total_cmp(&(b.lbar_cr - c.lbar_cr).abs())
        })
}

/// The branches `η` that meet the open length window `(lbar_min, lbar_max)`: branch `η`
/// lives for `η − 1 < L̄ < η + 1`.
pub fn etas_in(lbar_min: f64, lbar_max: f64) -> Vec<u32> {
    let top = lbar_max.ceil() as u32 + 1;
    (1..=top)
        .filter(|&e| {
            let e = f64::from(e);
            e - 1.0 < lbar_max && e + 1.0 > lbar_min
        })
        .collect()
}

/// The exact diagram restricted to `[lbar_min, lbar_max]`, equal to the full diagram there:
/// every branch that meets the window is sampled on it; the critical lengths are those of the
/// diagram from `min(lbar_min, 1)` to `lbar_max` with the same branches (so that the indices
/// are the paper's `L̄_icr`, counted from `L̄_1cr = 1`) that fall in the window; and below
/// `L̄ = 1` a state is the lowest only if it lies below the circle (branch 0,
/// `E R/(πD) = 1/L̄`).
pub fn exact_window(
    lbar_min: f64,
    lbar_max: f64,
    step: f64,
) -> Result<rodloop_exact::diagram::Diagram, rodloop_exact::ExactError> {
    use rodloop_exact::diagram::{compute, DiagramSettings};
    let etas = etas_in(lbar_min, lbar_max);
    let eta_max = etas.iter().copied().max().unwrap_or(1);
    let mut d = compute(&DiagramSettings {
        lbar_min,
        lbar_max,
        eta_max,
        step,
    })?;
    if lbar_min > 1.0 {
        let from_one = compute(&DiagramSettings {
            lbar_min: 1.0,
            lbar_max,
            eta_max,
            step: step.max(0.01),
        })?;
        let tol = 1e-12;
        d.critical = from_one
            .critical
            .into_iter()
            .filter(|c| c.lbar_cr >= lbar_min - tol && c.lbar_cr <= lbar_max + tol)
            .collect();
    }
    for p in &mut d.points {
        if p.lbar < 1.0 && 1.0 / p.lbar < p.energy {
            p.lowest = false;
        }
    }
    Ok(d)
}

impl Engine for ExactEngine {
    type Output = ExactOutput;
    type Progress = ();

    fn model(&self) -> &'static str {
        "exact"
    }

    fn run(&mut self, _progress: &mut dyn FnMut(())) -> Result<ExactOutput, DiagramError> {
        let t0 = std::time::Instant::now();
        let exact = |e: rodloop_exact::ExactError| DiagramError::InvalidOptions(e.to_string());
        let mut d = exact_window(self.lbar_min, self.lbar_max, self.step).map_err(exact)?;
        if let Some(sel) = &self.branches {
            d.points.retain(|p| sel.contains(&p.branch));
            d.critical
                .retain(|c| sel.contains(&c.from_branch) || sel.contains(&c.to_branch));
        }
        let seconds = t0.elapsed().as_secs_f64();
        let t1 = std::time::Instant::now();
        let shapes = rodloop_exact::shape::diagram_shapes(
            &d.points,
            rodloop_exact::shape::ShapeTolerances::default(),
            self.threads,
        )
        .map_err(exact)?;
        Ok(ExactOutput {
            diagram: d,
            shapes,
            seconds,
            seconds_shapes: t1.elapsed().as_secs_f64(),
        })
    }

    fn schema(&self, out: &ExactOutput, scene: &str) -> Result<Diagram, DiagramError> {
        let d = &out.diagram;
        let mut s = exact_schema(d, Some(&out.shapes), (self.lbar_min, self.lbar_max), scene)?;
        let branch_count = d
            .points
            .iter()
            .map(|p| p.branch)
            .collect::<std::collections::BTreeSet<_>>()
            .len();
        s.put("step", &self.step)?;
        s.put("branches", &branch_count)?;
        s.put("states", &d.points.len())?;
        s.put("continuation_points", &d.continuation_steps)?;
        s.put("seconds", &out.seconds)?;
        s.put("seconds_shapes", &out.seconds_shapes)?;
        s.put(
            "shape_tolerance",
            &rodloop_exact::shape::ShapeTolerances::default(),
        )?;
        Ok(s)
    }
}
