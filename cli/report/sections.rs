//! The sections of the surface report page (`report.html`): the energy figures, the
//! critical lengths with the great circles' buckling loads, the branch atlas, the
//! representative states and the comparison with the paper's printed values; each writes its
//! `<section>` into the [`Page`].

use std::fmt::Write as _;

use rodloop_diagram::BucklingReport;
use rodloop_figures::svg::esc;

use super::args::ATLAS_SHAPES;
use super::page::{Entry, Page};
use super::states::SolvedState;
use super::tables::{compare_html, critical_html, exact_cells, num, sci, td, HtmlTable};
use crate::compare::CompareRow;

/// Section 1: energy, energy split and force extremes against length (`figs`), and `k²`
/// (`fig_k2`, homogeneous scenes).
pub(super) fn energy(page: &mut Page, figs: [&str; 3], fig_k2: Option<&str>, uniform: bool) {
    let [fig_energy, fig_split, fig_lambda] = figs;
    page.h
        .push_str("<section id=\"diagram\">\n<h2>1. Energy against length</h2>\n");
    page.fig(
        fig_energy,
        "bending energy against normalised length",
        "Bending energy E R/(πD₀) of every traced state against L̄ = L/(2πR) (paper Fig. 3a). One colour per branch; solid: stable (lowest energy), dashed: metastable (a local minimum with higher energy), dotted: unstable (Hessian index &gt; 0). Diamonds: crossings E<sub>a</sub> = E<sub>b</sub>; open squares: collapses onto an m-fold great circle.",
        "fig-energy",
    );
    page.fig(
        fig_split,
        "geodesic and normal energy split",
        "The energy split E = E<sub>g</sub> + E<sub>n</sub> into its geodesic-curvature and normal-curvature parts (paper Fig. 3b).",
        "fig-split",
    );
    page.fig(
        fig_lambda,
        "contact force extremes against length",
        &if uniform {
            "Largest and smallest contact force λR³/D₀ of every state (paper Fig. 7), with the great-circle buckling loads of Eqs. (33)–(34) at L̄ = m.".to_string()
        } else {
            "Largest and smallest contact force λR³/D₀ of every state (paper Fig. 7). The great-circle buckling loads of Eqs. (33)–(34) hold for a uniform rod only and are not marked. Where a few states have sharp force peaks at the stiffness steps, the axis shows the bulk of the values and the note under it gives the full range.".to_string()
        },
        "fig-lambda",
    );
    if let Some(k2) = fig_k2 {
        page.fig(
            k2,
            "elliptic modulus against length",
            "k² of the exact loops of every branch against L̄ (paper Fig. 11), with the small-k² formula Eq. (B.4) dashed, evaluated with each branch's (η, p). The numeric model has no k; this figure is the exact layer's.",
            "fig-k2",
        );
    } else {
        page.h.push_str("<p class=\"note\" id=\"no-k2\">No k² figure (paper Fig. 11): the elliptic modulus k belongs to the closed-form loops of a uniform rod (Eq. (35)); this scene's stiffness is not uniform, so its loops have no k and Eq. (B.4) does not apply.</p>\n");
    }
    page.h.push_str("</section>\n");
}

/// Section 2: the critical lengths of the diagram directory `dir` (with the exact values
/// where the scene is homogeneous) and the great circles' buckling loads `great_circles`
/// (the diagram's schema, `great_circles`).
pub(super) fn critical(
    page: &mut Page,
    dir: &rodloop_schema::Diagram,
    exact: Option<&rodloop_schema::Diagram>,
    great_circles: Option<&BucklingReport>,
) {
    page.h.push_str("<section id=\"critical\">\n<h2>2. Critical lengths</h2>\n<p>Where the globally stable branch changes: crossings solve E<sub>a</sub>(L̄) = E<sub>b</sub>(L̄) on re-solved, Richardson-extrapolated equilibria; collapses are the lengths L̄ = m where the lowest branch ends on the m-fold great circle. Branch 0 is the planar circle below L̄ = 1. The error estimate is that of L̄<sub>cr</sub> itself.");
    if exact.is_some() {
        page.h.push_str(" For this homogeneous scene the exact layer (closed-form elliptic-function loops, error ≈ 1e−14) gives the exact values.");
    }
    page.h
        .push_str(" The same numbers are in <code>critical.csv</code>.</p>\n");
    let exact_heads: &[&str] = if exact.is_some() {
        &["exact L̄<sub>cr</sub>", "numeric − exact"]
    } else {
        &[]
    };
    page.h
        .push_str(&critical_html(&dir.critical, exact_heads, |c| {
            exact.map_or(Vec::new(), |e| exact_cells(c, e))
        }));
    if let Some(gc) = great_circles {
        let loads: Vec<_> = gc
            .loads
            .iter()
            .filter_map(|l| Some((l, l.lambda_formula?, l.equation.as_ref()?)))
            .collect();
        if !loads.is_empty() {
            page.h.push_str("<p>Buckling loads of the m-fold great circles, found numerically where the constrained Hessian becomes singular, against Eqs. (33)–(34):</p>\n");
            let mut t = HtmlTable::new(
                "buckling-table",
                &[
                    "m",
                    "mode (periods of κ<sub>g</sub>)",
                    "numeric λR³/D₀",
                    "error estimate",
                    "formula",
                    "value",
                ],
            );
            for (l, f, eq) in loads {
                t.row([
                    td(l.m),
                    td(l.mode_periods),
                    num(format!("{:.10}", l.lambda_numeric)),
                    num(sci(l.lambda_error)),
                    td(format!("Eq. ({})", esc(eq))),
                    num(format!("{f:.10}")),
                ]);
            }
            page.h.push_str(&t.finish());
        }
    }
    page.h.push_str("</section>\n");
}

/// Section 3: the branch atlas (or why there is none).
pub(super) fn atlas(page: &mut Page, fig_atlas: &Result<String, String>) {
    page.h
        .push_str("<section id=\"atlas\">\n<h2>3. Branch atlas</h2>\n");
    match fig_atlas {
        Ok(svg) => page.fig(
            svg,
            "branch atlas: shapes along every branch",
            &format!("The traced states along every branch (one row per branch, or per family of a non-uniform rod), {ATLAS_SHAPES} per row spread evenly over its traced range (paper Figs. 2, 9, 10), each labelled with L̄, its stability and E R/(πD₀). Every traced state is in <code>states/</code> (column <code>state_file</code> of <code>branches.csv</code>); <code>rodloop diagram --shapes K</code> draws this atlas with K columns."),
            "fig-atlas",
        ),
        Err(e) => {
            let _ = writeln!(page.h, "<p class=\"note\">no atlas: {}</p>", esc(e));
        }
    }
    page.h.push_str("</section>\n");
}

/// Section 4: the representative state of each branch, its pictures and Fig. 5.
pub(super) fn states(page: &mut Page, states: &[Entry<SolvedState>]) {
    page.h.push_str("<section id=\"states\">\n<h2>4. The stable state of each branch</h2>\n<p>Each branch solved at one length (the middle of the widest stretch where the diagram finds it the lowest branch), from the Euler rotation curve with l = η at the report's accuracy, as <code>rodloop solve</code> does; the converged state's branch is checked from the periods of its κ<sub>g</sub>. Each picture shows the loop on the sphere from an oblique view and along the three axes, coloured by the contact force λR³/D₀ (uniform rods) or by the stiffness D/D₀ (other profiles); nearer strands are darker and thicker. Red circles: self-contacts in 3-D.</p>\n");
    page.states_table(
        &[
            "branch",
            "η",
            "L̄",
            "chosen as",
            "solved from",
            "E R/(πD₀)",
            "error",
            "index",
            "state",
            "λR³/D₀ range",
            "point group",
            "self-contacts",
            "cells",
        ],
        states,
        |st, s| {
            vec![
                td(st.branch),
                td(st.eta),
                td(st.lbar),
                td(esc(&st.why)),
                td(esc(&s.start)),
                num(format!("{:.10}", s.energy)),
                num(sci(s.energy_error)),
                td(s.index),
                td(s.label),
                num(format!(
                    "[{:.6}, {:.6}] ± {}",
                    s.lambda_range.0,
                    s.lambda_range.1,
                    sci(s.lambda_error)
                )),
                td(s.point_group
                    .as_deref()
                    .map(esc)
                    .unwrap_or_else(|| "–".into())),
                td(s.self_contacts),
                td(s.cells),
            ]
        },
    );
    // Fig. 5 for the first solved state: its shape against the Euler curve.
    if let Some((st, (svg, dist))) = states.iter().find_map(|st| {
        st.outcome
            .as_ref()
            .ok()
            .and_then(|s| s.shape.as_ref())
            .map(|x| (st, x))
    }) {
        page.fig(
            svg,
            &format!("shape of branch {} against its Euler curve", st.branch),
            &format!(
                "Position, curvature, torsion and geodesic curvature along the loop of branch {} at L̄ = {} (solid) and the Euler rotation curve l = η of Eqs. (4)–(8) at the same length (dashed; paper Fig. 5), aligned by arclength shift, direction, mirror and rotation. The two curves are at most {:.3} R apart.",
                st.branch, st.lbar, dist
            ),
            "fig-shape",
        );
    }
    page.state_pictures(states, |st, s| {
        [
            (
                format!("loop of branch {} at length {}", st.branch, st.lbar),
                format!(
                    "Branch {} (η = {}) at L̄ = {}: {}, E R/(πD₀) = {:.8} ± {}{}, {}.",
                    st.branch,
                    st.eta,
                    st.lbar,
                    s.label,
                    s.energy,
                    sci(s.energy_error),
                    s.point_group
                        .as_deref()
                        .map(|g| format!(", point group {}", esc(g)))
                        .unwrap_or_default(),
                    crate::output::plural(s.self_contacts as u64, "self-contact"),
                ),
            ),
            (
                format!("contact force along the loop of branch {}", st.branch),
                format!(
                    "Contact force λR³/D₀ along the loop of branch {} at L̄ = {} (paper Fig. 6): from {:.6} to {:.6} ± {}.",
                    st.branch,
                    st.lbar,
                    s.lambda_range.0,
                    s.lambda_range.1,
                    sci(s.lambda_error)
                ),
            ),
        ]
    });
    page.h.push_str("</section>\n");
}

/// Section 5: the paper's printed values next to rodloop's.
pub(super) fn paper(page: &mut Page, compare: &[CompareRow], uniform: bool) {
    page.h.push_str("<section id=\"paper\">\n<h2>5. Comparison with the paper's printed values</h2>\n<p>Values printed in the paper (<code>data/reference/paper_values.csv</code>, with their sources), next to rodloop's. “Agrees” means within half a unit of the last printed digit (exact statements: within 1e−6).");
    if !uniform {
        page.h.push_str(" The paper's values are for homogeneous loops; this scene's stiffness is not uniform, so only the exact (homogeneous) layer is compared.");
    }
    page.h
        .push_str(" Winding numbers and symmetries are compared on the exact layer only.</p>\n");
    page.h.push_str(&compare_html(compare, uniform));
    page.h.push_str("</section>\n");
}
