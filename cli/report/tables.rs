//! The tables and the style sheet of `rodloop report`'s pages: the one table markup
//! ([`HtmlTable`]), the critical lengths and special points of a diagram directory read through
//! the schema, the paper's printed values, the settings and the timings.

use std::fmt::Write as _;

use rodloop_figures::svg::esc;
use rodloop_schema::{Critical, SpecialPoint};

use crate::compare::CompareRow;

/// A number in scientific notation for error columns (`0` stays `0`).
pub fn sci(v: f64) -> String {
    if v == 0.0 {
        "0".into()
    } else {
        format!("{v:.1e}")
    }
}

/// An HTML table `<table id=…>` with its header row, built row by row: the one table markup
/// of the report pages.
pub struct HtmlTable(String);

impl HtmlTable {
    /// The table `id` with the column heads `heads` (HTML).
    pub fn new(id: &str, heads: &[&str]) -> Self {
        let mut h = format!("<table id=\"{id}\"><thead><tr>");
        for t in heads {
            let _ = write!(h, "<th>{t}</th>");
        }
        h.push_str("</tr></thead><tbody>\n");
        Self(h)
    }

    /// One row of cells ([`td`], [`num`] or any `<td …>…</td>`).
    pub fn row(&mut self, cells: impl IntoIterator<Item = String>) {
        self.0.push_str("<tr>");
        for c in cells {
            self.0.push_str(&c);
        }
        self.0.push_str("</tr>\n");
    }

    /// The table's HTML.
    pub fn finish(mut self) -> String {
        self.0.push_str("</tbody></table>\n");
        self.0
    }
}

/// A table cell (`v` is HTML).
pub fn td(v: impl std::fmt::Display) -> String {
    format!("<td>{v}</td>")
}

/// A numeric table cell, right-aligned in a monospace font (`v` is HTML).
pub fn num(v: impl std::fmt::Display) -> String {
    format!("<td class=\"num\">{v}</td>")
}

/// A cell of an optional value (`–` where there is none).
fn or_dash(v: Option<String>) -> String {
    v.unwrap_or_else(|| "–".into())
}

/// The critical-length table of a diagram directory (the rows of its `critical.csv` as
/// [`rodloop_schema::Diagram::read`] reads them): index, `L̄_cr`, kind, branches, energy and
/// the error estimate of `L̄_cr`, then the columns `heads` with the cells `extra` gives each
/// row.
pub fn critical_html(
    critical: &[Critical],
    heads: &[&str],
    extra: impl Fn(&Critical) -> Vec<String>,
) -> String {
    let mut all = vec![
        "i",
        "L̄<sub>cr</sub>",
        "kind",
        "from → to",
        "E R/(πD₀)",
        "error estimate of L̄<sub>cr</sub>",
    ];
    all.extend(heads);
    let mut t = HtmlTable::new("critical-table", &all);
    for c in critical {
        let mut cells = vec![
            td(c.index),
            num(format!("{:.12}", c.lbar_cr)),
            td(esc(&c.kind)),
            td(format!("{} → {}", c.from_branch, c.to_branch)),
            num(format!("{:.10}", c.energy)),
            num(sci(c.error_estimate)),
        ];
        cells.extend(extra(c));
        t.row(cells);
    }
    t.finish()
}

/// The cells of the exact layer's value of critical length `c` and the difference to it, or
/// one cell saying there is no exact match.
pub fn exact_cells(c: &Critical, exact: &rodloop_schema::Diagram) -> Vec<String> {
    match crate::diagram::exact_counterpart(c, exact) {
        Some(x) => vec![
            num(format!("{:.12}", x.lbar_cr)),
            num(sci(c.lbar_cr - x.lbar_cr)),
        ],
        None => vec!["<td colspan=\"2\">no exact match</td>".into()],
    }
}

/// The special points of a diagram directory (its `special_points.csv`): kind, branch, `L̄`,
/// error estimate, energy and the Hessian index on either side.
pub fn special_html(special: &[SpecialPoint]) -> String {
    let mut t = HtmlTable::new(
        "events-table",
        &[
            "event",
            "branch",
            "L̄",
            "error estimate",
            "E R/(πD₀)",
            "index below",
            "index above",
        ],
    );
    for e in special {
        t.row([
            td(esc(&e.kind)),
            td(e.branch),
            num(format!("{:.12}", e.lbar)),
            num(or_dash(e.error_estimate.map(sci))),
            num(format!("{:.10}", e.energy)),
            td(or_dash(e.index_before.map(|i| i.to_string()))),
            td(or_dash(e.index_after.map(|i| i.to_string()))),
        ]);
    }
    t.finish()
}

/// The comparison with the paper's printed values.
pub fn compare_html(rows: &[CompareRow], numeric: bool) -> String {
    let yes = |a: Option<bool>| {
        match a {
            Some(true) => "<td class=\"ok\">yes</td>",
            Some(false) => "<td class=\"bad\">NO</td>",
            None => "<td>–</td>",
        }
        .to_string()
    };
    let opt_sci = |v: Option<f64>| or_dash(v.map(sci));
    let mut heads = vec![
        "id",
        "quantity",
        "branch",
        "L̄",
        "paper",
        "exact layer",
        "exact − paper",
        "agrees",
    ];
    if numeric {
        heads.extend(["numeric", "numeric − paper", "agrees"]);
    }
    heads.push("source in the paper");
    let mut t = HtmlTable::new("compare-table", &heads);
    for r in rows {
        let mut cells = vec![
            td(esc(&r.id)),
            td(esc(&r.kind.replace('_', " "))),
            td(r.branch),
            td(r.lbar.map(|l| l.to_string()).unwrap_or_default()),
            num(esc(&r.paper)),
            num(esc(&r.exact_text())),
            num(opt_sci(r.exact_deviation)),
            yes(r.agrees_exact),
        ];
        if numeric {
            cells.extend([
                num(match r.numeric_text().as_str() {
                    "-" => "–".to_string(),
                    t => esc(t),
                }),
                num(opt_sci(r.numeric_deviation)),
                yes(r.agrees_numeric),
            ]);
        }
        cells.push(format!("<td class=\"src\">{}</td>", esc(&r.source)));
        t.row(cells);
    }
    t.finish()
}

pub const STYLE: &str = "body{font-family:'DejaVu Sans',Verdana,Arial,sans-serif;margin:0 auto;max-width:1240px;padding:16px 20px 40px;color:#1a1a1a;background:#fff;line-height:1.45}
h1{font-size:26px;margin:8px 0 4px}h2{font-size:20px;border-bottom:2px solid #d8dee8;padding-bottom:4px;margin-top:34px}
p.lead{color:#444;margin:4px 0 10px}nav a{margin-right:14px;color:#1f4fd1;text-decoration:none}
figure{margin:14px 0;padding:0}figure svg.fig{max-width:100%;height:auto;border:1px solid #e2e6ee;display:block}
figcaption{font-size:13px;color:#444;margin-top:4px;max-width:960px}
table{border-collapse:collapse;font-size:13px;margin:10px 0}th,td{border:1px solid #d5dae3;padding:3px 8px;text-align:left;vertical-align:top}
th{background:#f0f3f8}td.num{text-align:right;font-family:'DejaVu Sans Mono',Menlo,Consolas,monospace;white-space:nowrap}
td.ok{color:#1b7a1b}td.bad{color:#c01818;font-weight:bold}td.src{color:#555;font-size:12px}
.state{display:flex;flex-wrap:wrap;gap:0 18px;align-items:flex-start;margin-top:18px}.state figure{margin:0;display:table}.state figcaption{display:table-caption;caption-side:bottom}
.note{background:#fff6e0;border-left:4px solid #e0a800;padding:6px 10px;font-size:13px}
dl{display:grid;grid-template-columns:max-content auto;gap:2px 16px;font-size:14px}dt{font-weight:bold}dd{margin:0}
pre{background:#f6f8fa;padding:8px;font-size:12px;overflow-x:auto}";

/// The figures of a report page, numbered in page order (the number keeps the ids inside
/// each inlined SVG unique on the page).
#[derive(Default)]
pub struct Figures {
    /// Figures so far.
    pub count: usize,
}

impl Figures {
    /// One `<figure id=…>`: the SVG inlined ([`inline_svg`]) under `label`,
    /// with its caption.
    pub fn fig(&mut self, svg: &str, label: &str, caption: &str, id: &str) -> String {
        self.count += 1;
        format!(
            "<figure id=\"{id}\">\n{}\n<figcaption>{caption}</figcaption></figure>\n",
            inline_svg(svg, &format!("f{}", self.count), label)
        )
    }
}

/// The "Settings" section of a report page: the scene rows first, then `extra` (what only
/// this kind of report has), then the rows every report shows (accuracy and where it came
/// from, version, platform, command line, run id, units), then the scene file's text.
pub struct Settings<'a> {
    /// The section's number on the page.
    pub number: u32,
    /// The scene's name.
    pub scene_name: &'a str,
    /// The scene file given with `--scene`, if any.
    pub scene_file: Option<&'a std::path::Path>,
    /// Rows between the scene file and the accuracy (description, radius, range, …).
    pub extra: Vec<(&'a str, String)>,
    /// The accuracy used, and whether `--accuracy` chose it (else the scene did).
    pub accuracy: (rodloop_solver::Accuracy, bool),
    /// The units line.
    pub units: &'a str,
    /// The scene file's text, shown verbatim.
    pub scene_text: Option<&'a str>,
}

/// Write the settings section (see [`Settings`]).
pub fn settings_section(h: &mut String, run: &crate::output::OutputRun, s: &Settings) {
    let _ = writeln!(
        h,
        "<section id=\"settings\">\n<h2>{}. Settings</h2>\n<dl>",
        s.number
    );
    let command: Vec<String> = std::env::args().collect();
    let (accuracy, from_flag) = s.accuracy;
    let mut items: Vec<(&str, String)> = vec![
        ("scene", esc(s.scene_name)),
        (
            "scene file",
            s.scene_file
                .map(|p| format!("<code>{}</code>", esc(&p.display().to_string())))
                .unwrap_or_else(|| "built-in default".into()),
        ),
    ];
    items.extend(s.extra.iter().cloned());
    items.extend([
        (
            "accuracy",
            format!(
                "{}{}",
                format!("{accuracy:?}").to_lowercase(),
                if from_flag {
                    " (--accuracy)"
                } else {
                    " (scene)"
                }
            ),
        ),
        ("rodloop version", env!("CARGO_PKG_VERSION").into()),
        (
            "platform",
            format!("{}-{}", std::env::consts::ARCH, std::env::consts::OS),
        ),
        (
            "command",
            format!("<code>{}</code>", esc(&command.join(" "))),
        ),
        ("run id", format!("<code>{}</code>", esc(run.run_id()))),
        ("units", s.units.into()),
    ]);
    for (k, v) in items {
        let _ = writeln!(h, "<dt>{k}</dt><dd>{v}</dd>");
    }
    h.push_str("</dl>\n");
    if let Some(text) = s.scene_text {
        let _ = writeln!(h, "<pre>{}</pre>", esc(text));
    }
    h.push_str("</section>\n");
}

/// The end of a report page: the "Timings" section (numbered `number`) with the `stages`,
/// the representative states (`states`: how many were solved, in parallel, the wall time,
/// and one row per solved one `(branch, L̄, seconds)`), the page assembly and the total;
/// then the footer. Refuses (and writes nothing) if the page holds a non-finite number;
/// otherwise writes `report.html` into the run's staging directory.
pub fn finish_page(
    run: &crate::output::OutputRun,
    h: &mut String,
    number: u32,
    stages: &[(&str, f64)],
    states: (usize, f64, &[(u32, f64, f64)]),
    t_page: f64,
    total: f64,
) -> anyhow::Result<()> {
    let _ = writeln!(h, "<section id=\"timings\">\n<h2>{number}. Timings</h2>");
    let mut t = HtmlTable::new("timings-table", &["stage", "wall time (s)"]);
    let mut row = |k: &str, v: f64| t.row([td(k), num(format!("{v:.3}"))]);
    for (k, v) in stages {
        row(k, *v);
    }
    row(
        &format!("representative states ({} solves, in parallel)", states.0),
        states.1,
    );
    for &(branch, lbar, secs) in states.2 {
        row(
            &format!("&nbsp;&nbsp;branch {branch} at L̄ = {lbar} (solve and picture)"),
            secs,
        );
    }
    row("page assembly", t_page);
    row("total", total);
    h.push_str(&t.finish());
    h.push_str("</section>\n");
    let _ = writeln!(
        h,
        "<footer><p class=\"lead\">Written by rodloop {}. This page is self-contained: no scripts, no external style sheets, fonts or images.</p></footer>\n</body>\n</html>",
        env!("CARGO_PKG_VERSION")
    );
    if let Some(bad) = h
        .split(|c: char| !c.is_alphanumeric())
        .find(|t| *t == "NaN" || *t == "inf")
    {
        anyhow::bail!(
            "internal error: the report contains a non-finite number ({bad}); nothing was written"
        );
    }
    run.write_bytes("report.html", h.as_bytes())
}

/// Finish a report run: the staged `summary.json` (the diagram's) gains `report`, the run is
/// committed (moved into place), and a warning names how many of the `states` representative
/// states failed.
pub fn commit_report(
    run: crate::output::OutputRun,
    report: serde_json::Value,
    failed: usize,
    states: usize,
) -> anyhow::Result<()> {
    use anyhow::Context as _;
    let staged = std::fs::read_to_string(run.stage_dir().join("summary.json"))
        .context("reading the staged summary.json")?;
    let mut summary: serde_json::Value = serde_json::from_str(&staged)?;
    if let serde_json::Value::Object(map) = &mut summary {
        map.insert("report".into(), crate::output::strip_nulls(report));
    }
    run.write_json("summary.json", &summary)?;
    run.commit()?;
    if failed > 0 {
        eprintln!(
            "warning: {failed} of {states} representative states could not be solved (see the report)"
        );
    }
    Ok(())
}

/// Prepare a standalone SVG document for inlining into HTML: ids (clip paths, gradients) get
/// a per-figure prefix so that figures cannot take each other's definitions, the namespace
/// declaration goes (the HTML parser supplies it), and the root element gets a class and an
/// accessible name.
pub fn inline_svg(svg: &str, prefix: &str, label: &str) -> String {
    let body = svg
        .trim_start()
        .trim_start_matches(|c| c != '<')
        // HTML puts <svg> in the SVG namespace itself; the page names no URL at all.
        .replace(" xmlns=\"http://www.w3.org/2000/svg\"", "")
        .replace("id=\"", &format!("id=\"{prefix}-"))
        .replace("url(#", &format!("url(#{prefix}-"))
        .replace("href=\"#", &format!("href=\"#{prefix}-"));
    body.replacen(
        "<svg ",
        &format!(
            "<svg class=\"fig\" role=\"img\" aria-label=\"{}\" ",
            esc(label)
        ),
        1,
    )
}
