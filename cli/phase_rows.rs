//! The rows of a phase diagram's curves, read from the schema: every critical length of
//! `rodloop phase` placed on its exchange curve, for the table (`phase.rs`) and the figure
//! (`phase_figure.rs`) alike.

use anyhow::{bail, Result};
use rodloop_schema::{Critical, CurveRow, Diagram, ExchangeCurve, Parameter};

/// The rows of every curve of a phase diagram in the schema: its critical lengths with their
/// places on their curves ([`CurveRow`]).
pub(crate) struct PhaseRows<'a> {
    /// The parameter.
    pub parameter: Parameter,
    /// The curves, in order.
    pub curves: Vec<CurveRows<'a>>,
}

/// A curve of a phase diagram and its rows (in the order of the schema's critical lengths).
pub(crate) struct CurveRows<'a> {
    /// The curve.
    pub curve: &'a ExchangeCurve,
    /// Its rows.
    pub rows: Vec<(&'a Critical, CurveRow)>,
}

/// The curves of the phase diagram `d` (the schema of `phase`), every critical length placed
/// on its curve.
pub(crate) fn curves_of(d: &Diagram) -> Result<PhaseRows<'_>> {
    let (Some(parameter), Some(curves)) = (&d.parameter, &d.exchange_curves) else {
        bail!("internal error: the phase diagram's schema has no parameter or curves");
    };
    let mut out: Vec<CurveRows> = curves
        .iter()
        .map(|curve| CurveRows {
            curve,
            rows: Vec::new(),
        })
        .collect();
    for c in &d.critical {
        let Some(at) = c.curve_row() else {
            bail!(
                "internal error: critical length {} of the phase diagram is on no curve",
                c.index
            );
        };
        let Some(curve) = at.curve.checked_sub(1).and_then(|k| out.get_mut(k)) else {
            bail!(
                "internal error: critical length {} names curve {}, of {}",
                c.index,
                at.curve,
                curves.len()
            );
        };
        curve.rows.push((c, at));
    }
    Ok(PhaseRows {
        parameter: parameter.clone(),
        curves: out,
    })
}
