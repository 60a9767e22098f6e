//! The convergence figure of `rodloop converge`: the energy error of one state against the
//! number of cells and against the wall time of the solve, both on log-log axes (base-10
//! logarithms on the axes), with the least-squares order of convergence drawn as a dashed
//! line and stated in the legend.

use crate::plot::{LegendItem, Mark, Plot, Series, Shape};
use crate::svg::Svg;
use crate::FigureError;

/// One rung of the ladder.
#[derive(Clone, Copy, Debug)]
pub struct Rung {
    /// Cells of the discretisation.
    pub cells: usize,
    /// Energy error (against the exact value, or the finest rung).
    pub error: f64,
    /// Wall time of the solve, seconds.
    pub seconds: f64,
}

/// Least-squares slope and intercept of `y` against `x`.
fn fit(pts: &[(f64, f64)]) -> Option<(f64, f64)> {
    let n = pts.len() as f64;
    if pts.len() < 2 {
        return None;
    }
    let (sx, sy) = pts
        .iter()
        .fold((0.0, 0.0), |(a, b), &(x, y)| (a + x, b + y));
    let (mx, my) = (sx / n, sy / n);
    let sxx: f64 = pts.iter().map(|&(x, _)| (x - mx) * (x - mx)).sum();
    if sxx <= 0.0 {
        return None;
    }
    let sxy: f64 = pts.iter().map(|&(x, y)| (x - mx) * (y - my)).sum();
    let slope = sxy / sxx;
    Some((slope, my - slope * mx))
}

/// The observed order of convergence `p` in `error ≈ C N^{−p}`: the least-squares slope of
/// `log error` against `log N` over the rungs whose error lies above `floor` (rounding: the
/// finest rungs of a high-order scheme reach the error of double precision, where the slope
/// means nothing). `None` with fewer than two such rungs.
pub fn fitted_order(rungs: &[Rung], floor: f64) -> Option<f64> {
    let pts: Vec<(f64, f64)> = rungs
        .iter()
        .filter(|r| r.error.is_finite() && r.error > floor && r.cells > 0)
        .map(|r| ((r.cells as f64).log10(), r.error.log10()))
        .collect();
    fit(&pts).map(|(slope, _)| -slope)
}

/// The figure: error against cells (left) and against seconds (right), log-log; `what` names
/// the error (`|E − E_exact|` or `|E − E_finest|`), `floor` is the rounding level excluded
/// from the fit.
pub fn convergence_figure(
    rungs: &[Rung],
    what: &str,
    floor: f64,
    title: &str,
    w: f64,
    h: f64,
) -> Result<String, FigureError> {
    crate::diagram::check_size(w, h)?;
    let used: Vec<&Rung> = rungs
        .iter()
        .filter(|r| r.error.is_finite() && r.error > 0.0 && r.seconds > 0.0 && r.cells > 0)
        .collect();
    if used.len() < 2 {
        return Err(FigureError::Invalid(format!(
            "a convergence figure needs two rungs with a positive error, got {}",
            used.len()
        )));
    }
    let order = fitted_order(rungs, floor);
    let mut svg = Svg::new(w, h);
    svg.rect(0.0, 0.0, w, h, "white", "none", 0.0);
    for (k, (xlabel, x_of)) in [
        (
            "log₁₀ cells N",
            (|r: &Rung| (r.cells as f64).log10()) as fn(&Rung) -> f64,
        ),
        (
            "log₁₀ wall time of the solve (s)",
            (|r: &Rung| r.seconds.log10()) as fn(&Rung) -> f64,
        ),
    ]
    .into_iter()
    .enumerate()
    {
        let pts: Vec<(f64, f64)> = used.iter().map(|r| (x_of(r), r.error.log10())).collect();
        let mut series = vec![Series {
            color: "#1f4fd1".into(),
            width: 1.8,
            dash: String::new(),
            points: pts.clone(),
        }];
        let marks = pts
            .iter()
            .map(|&at| Mark {
                at,
                shape: Shape::Circle,
                color: "#1f4fd1".into(),
                size: 3.5,
            })
            .collect();
        let mut legend = vec![LegendItem::Line {
            label: what.into(),
            color: "#1f4fd1".into(),
            width: 1.8,
            dash: String::new(),
        }];
        // The fitted line over the rungs above the rounding level.
        let fitted: Vec<(f64, f64)> = used
            .iter()
            .filter(|r| r.error > floor)
            .map(|r| (x_of(r), r.error.log10()))
            .collect();
        if let Some((slope, icpt)) = fit(&fitted) {
            let (a, b) = fitted
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
                    (a.min(p.0), b.max(p.0))
                });
            series.push(Series {
                color: "#d8600c".into(),
                width: 1.4,
                dash: "6 4".into(),
                points: vec![(a, icpt + slope * a), (b, icpt + slope * b)],
            });
            legend.push(LegendItem::Line {
                label: if k == 0 {
                    format!("fit: order p = {:.2} (error ∝ N^−p)", -slope)
                } else {
                    format!("fit: error ∝ time^{slope:.2}")
                },
                color: "#d8600c".into(),
                width: 1.4,
                dash: "6 4".into(),
            });
        }
        let plot = Plot {
            title: if k == 0 {
                "Error against cells".into()
            } else {
                "Error against time".into()
            },
            xlabel: xlabel.into(),
            ylabel: format!("log₁₀ {what}"),
            series,
            marks,
            legend,
            note: if k == 0 {
                match order {
                    Some(p) => format!(
                        "observed order {p:.2} (least squares over errors above {floor:.0e})"
                    ),
                    None => "too few rungs above the rounding level for an order".into(),
                }
            } else {
                "one timed solve per rung: wall time, which varies with the machine's load".into()
            },
            ..Default::default()
        };
        plot.render(
            &mut svg,
            k as f64 * w / 2.0,
            24.0,
            w / 2.0,
            h - 24.0,
            &format!("conv{k}"),
        );
    }
    svg.text_bold(12.0, 20.0, 15.0, crate::svg::Anchor::Start, title);
    Ok(svg.finish())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An exact power law gives its exponent back; rungs at the rounding level are left out.
    #[test]
    fn order_of_a_power_law() {
        let mut rungs: Vec<Rung> = [16usize, 32, 64, 128]
            .iter()
            .map(|&n| Rung {
                cells: n,
                error: 3.0 * (n as f64).powi(-6),
                seconds: 1e-3 * n as f64,
            })
            .collect();
        rungs.push(Rung {
            cells: 256,
            error: 1e-16,
            seconds: 0.256,
        });
        let p = fitted_order(&rungs, 1e-14).unwrap();
        assert!((p - 6.0).abs() < 1e-12, "{p}");
        let svg = convergence_figure(&rungs, "|E − E_exact|", 1e-14, "t", 900.0, 400.0).unwrap();
        assert!(svg.contains("order p = 6.00"));
    }
}
