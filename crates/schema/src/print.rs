//! The one printer of a diagram's critical lengths: the table `rodloop diagram` prints for
//! every model (exact layer, surface, enclosed), read from the schema alone.

use crate::Diagram;

/// A column printed beside the critical lengths: its header and one text per critical length
/// (right-aligned in `width`), e.g. the surface critical length of an enclosed diagram or the
/// deviation from the exact layer's.
#[derive(Clone, Debug)]
pub struct SideColumn {
    /// Header text.
    pub header: String,
    /// Width the header and the cells are right-aligned in.
    pub width: usize,
    /// One text per critical length of the diagram, in its order.
    pub cells: Vec<String>,
}

impl SideColumn {
    /// The column `header` of the numbers `values` with `digits` decimals (fixed point).
    pub fn fixed(header: &str, width: usize, digits: usize, values: &[f64]) -> Self {
        SideColumn {
            header: header.into(),
            width,
            cells: values.iter().map(|x| format!("{x:.digits$}")).collect(),
        }
    }
}

/// Decimals of `L̄_cr`, decimals of the energy, width of the energy, width of the target
/// branch and the energy's unit, by model: the exact layer solves the closed-form closure to
/// machine precision (15 digits of both); a numeric model prints 12 of `L̄_cr` and 10 of
/// the energy, beside its error estimate. A surface diagram of any stiffness names its
/// energy unit by the reference stiffness `D0`.
fn style(model: &str) -> (usize, usize, usize, usize, &'static str) {
    match model {
        "exact" => (15, 15, 18, 2, "E R/(pi D)"),
        "numeric" => (12, 10, 16, 3, "E R/(pi D0)"),
        _ => (12, 10, 16, 3, "E R/(pi D)"),
    }
}

impl Diagram {
    /// The printed table of the critical lengths (one line per entry, the header first;
    /// every line starts with two spaces): index, `L̄_cr`, kind, branches, energy and error
    /// estimate, then the `side` column when there is one.
    pub fn critical_table(&self, side: Option<&SideColumn>) -> Vec<String> {
        let (lbar_digits, e_digits, e_width, to_width, unit) = style(&self.model);
        let side_cell = |i: usize| match side {
            Some(s) => format!(
                "  {:>w$}",
                s.cells.get(i).map_or("", String::as_str),
                w = s.width
            ),
            None => String::new(),
        };
        let mut lines = vec![format!(
            "  {:>2}  {:>18}  {:>9}  {:>8}  {:>e_width$}  {:>9}{}",
            "i",
            "lbar_cr",
            "kind",
            "from->to",
            unit,
            "error",
            side.map_or(String::new(), |s| format!(
                "  {:>w$}",
                s.header,
                w = s.width
            )),
        )];
        for (i, c) in self.critical.iter().enumerate() {
            lines.push(format!(
                "  {:>2}  {:>18.lbar_digits$}  {:>8}  {:>3}->{:<to_width$}  {:>e_width$.e_digits$}  {:>9.1e}{}",
                c.index,
                c.lbar_cr,
                c.kind,
                c.from_branch,
                c.to_branch,
                c.energy,
                c.error_estimate,
                side_cell(i),
            ));
        }
        lines
    }
}
