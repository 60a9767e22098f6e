//! The tables and the style sheet of `rodloop report`'s page (cli/report.rs): the critical
//! lengths with their exact values, the paper's printed values.

use std::fmt::Write as _;

use rodloop_diagram::NumericDiagram;
use rodloop_exact::diagram::Diagram;
use rodloop_figures::svg::esc;

use crate::compare::CompareRow;

/// A number in scientific notation for error columns (`0` stays `0`).
pub fn sci(v: f64) -> String {
    if v == 0.0 {
        "0".into()
    } else {
        format!("{v:.1e}")
    }
}

/// The critical-length table.
pub fn critical_html(d: &NumericDiagram, exact: Option<&Diagram>) -> String {
    let mut h = String::new();
    h.push_str("<table id=\"critical-table\">\n<thead><tr><th>i</th><th>L̄<sub>cr</sub></th><th>kind</th><th>from → to</th><th>E R/(πD₀)</th><th>error estimate of L̄<sub>cr</sub></th>");
    if exact.is_some() {
        h.push_str("<th>exact L̄<sub>cr</sub></th><th>numeric − exact</th>");
    }
    h.push_str("</tr></thead>\n<tbody>\n");
    for c in &d.critical {
        let _ = write!(
            h,
            "<tr><td>{}</td><td class=\"num\">{:.12}</td><td>{}</td><td>{} → {}</td><td class=\"num\">{:.10}</td><td class=\"num\">{}</td>",
            c.index,
            c.lbar_cr,
            c.kind,
            c.from_branch,
            c.to_branch,
            c.energy,
            sci(c.error_estimate)
        );
        if let Some(e) = exact {
            match crate::diagram::exact_match(c, e) {
                Some(x) => {
                    let _ = write!(
                        h,
                        "<td class=\"num\">{:.12}</td><td class=\"num\">{}</td>",
                        x.lbar_cr,
                        sci(c.lbar_cr - x.lbar_cr)
                    );
                }
                None => h.push_str("<td colspan=\"2\">no exact match</td>"),
            }
        }
        h.push_str("</tr>\n");
    }
    h.push_str("</tbody></table>\n");
    h
}

/// The comparison with the paper's printed values.
pub fn compare_html(rows: &[CompareRow], numeric: bool) -> String {
    let yes = |a: Option<bool>| match a {
        Some(true) => "<td class=\"ok\">yes</td>",
        Some(false) => "<td class=\"bad\">NO</td>",
        None => "<td>–</td>",
    };
    let opt_sci = |v: Option<f64>| v.map(sci).unwrap_or_else(|| "–".into());
    let mut h = String::new();
    h.push_str("<table id=\"compare-table\">\n<thead><tr><th>id</th><th>quantity</th><th>branch</th><th>L̄</th><th>paper</th><th>exact layer</th><th>exact − paper</th><th>agrees</th>");
    if numeric {
        h.push_str("<th>numeric</th><th>numeric − paper</th><th>agrees</th>");
    }
    h.push_str("<th>source in the paper</th></tr></thead>\n<tbody>\n");
    for r in rows {
        let _ = write!(
            h,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td>{}",
            esc(&r.id),
            esc(&r.kind.replace('_', " ")),
            r.branch,
            r.lbar.map(|l| l.to_string()).unwrap_or_default(),
            esc(&r.paper),
            esc(&r.exact_text()),
            opt_sci(r.exact_deviation),
            yes(r.agrees_exact),
        );
        if numeric {
            let _ = write!(
                h,
                "<td class=\"num\">{}</td><td class=\"num\">{}</td>{}",
                match r.numeric_text().as_str() {
                    "-" => "–".to_string(),
                    t => esc(t),
                },
                opt_sci(r.numeric_deviation),
                yes(r.agrees_numeric)
            );
        }
        let _ = writeln!(h, "<td class=\"src\">{}</td></tr>", esc(&r.source));
    }
    h.push_str("</tbody></table>\n");
    h
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

/// A row of a representative-states table for a state that could not be solved: branch,
/// `η`, `L̄`, why that length was chosen, and the error across the `span` remaining columns.
pub fn not_solved_row(h: &mut String, state: (u32, u32, f64), why: &str, err: &str, span: usize) {
    let (branch, eta, lbar) = state;
    let _ = writeln!(
        h,
        "<tr><td>{branch}</td><td>{eta}</td><td>{lbar}</td><td>{}</td><td colspan=\"{span}\" class=\"bad\">not solved: {}</td></tr>",
        esc(why),
        esc(err)
    );
}

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
    let _ = writeln!(
        h,
        "<section id=\"timings\">\n<h2>{number}. Timings</h2>\n<table id=\"timings-table\"><thead><tr><th>stage</th><th>wall time (s)</th></tr></thead><tbody>"
    );
    let mut row = |k: &str, v: f64| {
        let _ = writeln!(h, "<tr><td>{k}</td><td class=\"num\">{v:.3}</td></tr>");
    };
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
    h.push_str("</tbody></table>\n</section>\n");
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
