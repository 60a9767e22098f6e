//! The one critical-length printer reproduces the tables the user guide shows (docs/src/
//! diagrams.md and enclosed.md) for the exact layer, the surface model with its deviation
//! from the exact layer, and the enclosed model with the surface critical length beside it.

use std::collections::BTreeMap;

use rodloop_schema::{Critical, Diagram, SideColumn};

fn diagram(model: &str, rows: &[(usize, f64, &str, u32, u32, f64, f64)]) -> Diagram {
    let mut d = Diagram::new(model, "scene", Vec::new(), "energy E R/(pi D0)");
    d.critical = rows
        .iter()
        .map(|&(index, lbar_cr, kind, from, to, energy, err)| Critical {
            index,
            lbar_cr,
            kind: kind.into(),
            from_branch: from,
            to_branch: to,
            energy,
            error_estimate: err,
            extra: BTreeMap::new(),
        })
        .collect();
    d
}

#[test]
fn exact_table_is_the_documented_one() {
    let d = diagram(
        "exact",
        &[
            (1, 1.0, "collapse", 0, 1, 1.0, 0.0),
            (
                2,
                1.3799411442868,
                "crossing",
                1,
                2,
                2.491482642014345,
                6.4e-15,
            ),
        ],
    );
    let want = [
        "   i             lbar_cr       kind  from->to          E R/(pi D)      error",
        "   1   1.000000000000000  collapse    0->1    1.000000000000000      0.0e0",
        "   2   1.379941144286800  crossing    1->2    2.491482642014345    6.4e-15",
    ];
    assert_eq!(d.critical_table(None), want);
}

#[test]
fn surface_table_with_exact_deviation_is_the_documented_one() {
    let d = diagram(
        "numeric",
        &[
            (1, 1.0, "collapse", 0, 1, 1.0, 0.0),
            (4, 2.425697732065, "crossing", 3, 1, 3.0476957565, 3.0e-10),
        ],
    );
    let side = SideColumn {
        header: "exact deviation".into(),
        width: 17,
        cells: vec![format!("{:.1e}", 0.0), format!("{:.1e}", -1.5e-10)],
    };
    let want = [
        "   i             lbar_cr       kind  from->to       E R/(pi D0)      error    exact deviation",
        "   1      1.000000000000  collapse    0->1        1.0000000000      0.0e0              0.0e0",
        "   4      2.425697732065  crossing    3->1        3.0476957565    3.0e-10           -1.5e-10",
    ];
    assert_eq!(d.critical_table(Some(&side)), want);
}

#[test]
fn enclosed_table_with_surface_column_is_the_documented_one() {
    let d = diagram(
        "enclosed",
        &[(2, 1.379891348293, "crossing", 1, 2, 2.4913841525, 1.4e-8)],
    );
    let side = SideColumn::fixed("surface lbar_cr", 18, 12, &[1.379941144287]);
    let want = [
        "   i             lbar_cr       kind  from->to        E R/(pi D)      error     surface lbar_cr",
        "   2      1.379891348293  crossing    1->2        2.4913841525     1.4e-8      1.379941144287",
    ];
    assert_eq!(d.critical_table(Some(&side)), want);
}
