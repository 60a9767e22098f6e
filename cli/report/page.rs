//! The one page builder of `rodloop report`, for surface and enclosed scenes alike: the head
//! of the page (style sheet, title, lead paragraph, section links), the notes, the figures,
//! the representative states ([`Entry`]) with their pictures, and the end of the page (settings,
//! timings, footer) with the `report` object of `summary.json` and the commit of the run.

use std::fmt::Write as _;

use anyhow::Result;
use rodloop_diagram::representative::Choice;
use rodloop_figures::svg::esc;

use super::tables::{self, td, Figures, HtmlTable, Settings, STYLE};
use crate::output::{checked_json, OutputRun};

/// The representative state of one branch: where it was taken (a [`Choice`]) and what came
/// out.
pub struct Entry<T> {
    /// Paper branch number.
    pub branch: u32,
    /// Periods of `κ_g`.
    pub eta: u32,
    /// The length solved at.
    pub lbar: f64,
    /// Why this length.
    pub why: String,
    /// The solved state, or why it could not be solved.
    pub outcome: Result<T, String>,
}

impl<T: Send> Entry<T> {
    /// Every choice solved by `solve` on the available cores, in the order of `choices`, each
    /// error on one line.
    pub fn solve_all(
        choices: Vec<Choice>,
        solve: impl Fn(&Choice) -> Result<T> + Sync,
    ) -> Vec<Self> {
        let solved =
            rodloop_diagram::parallel_map(&choices, |c| solve(c).map_err(|e| format!("{e:#}")));
        choices
            .into_iter()
            .zip(solved)
            .map(|(c, outcome)| Entry {
                branch: c.branch,
                eta: c.eta,
                lbar: c.lbar,
                why: c.why,
                outcome,
            })
            .collect()
    }
}

/// A solved representative state as the page's timings and `summary.json` need it.
pub trait Solved {
    /// Wall time of the solve and its pictures, seconds.
    fn seconds(&self) -> f64;
    /// The state's fields in `summary.json` (`report.states`), besides branch, `η`, `L̄`.
    fn note(&self) -> Result<serde_json::Value>;
    /// The loop picture and the profile along the loop (SVG).
    fn pictures(&self) -> (&str, &str);
}

/// A report page being written.
pub struct Page {
    /// The HTML so far.
    pub h: String,
    /// The figures so far.
    pub figs: Figures,
}

impl Page {
    /// The head of the page for scene `name`: the style sheet, the title, the lead paragraph
    /// (`lead`, HTML) and the links to the `sections` (`(id, title)`).
    pub fn begin(name: &str, lead: &str, sections: &[(&str, &str)]) -> Self {
        let mut h = String::with_capacity(1 << 20);
        let name = esc(name);
        let _ = write!(
            h,
            "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n<title>rodloop report: {name}</title>\n<style>\n{STYLE}\n</style>\n</head>\n<body>\n<h1>rodloop report: scene {name}</h1>\n<p class=\"lead\">{lead} Elastic rod loops in a sphere after Wang, Li &amp; Yi, J. Mech. Phys. Solids (2024); equation and figure numbers refer to that paper.</p>\n<nav>"
        );
        for (id, title) in sections {
            let _ = write!(h, "<a href=\"#{id}\">{title}</a>");
        }
        h.push_str("</nav>\n");
        Self {
            h,
            figs: Figures::default(),
        }
    }

    /// One note paragraph per item, `kind: item`.
    pub fn notes(&mut self, kind: &str, items: &[String]) {
        for w in items {
            let _ = writeln!(self.h, "<p class=\"note\">{kind}: {}</p>", esc(w));
        }
    }

    /// One figure ([`Figures::fig`]).
    pub fn fig(&mut self, svg: &str, label: &str, caption: &str, id: &str) {
        let f = self.figs.fig(svg, label, caption, id);
        self.h.push_str(&f);
    }

    /// The table `states-table` of the representative states under the column heads
    /// `heads` (the first four: branch, `η`, `L̄`, why that length): `row` gives the cells of
    /// a solved state; a state that could not be solved has the error across the rest.
    pub fn states_table<T>(
        &mut self,
        heads: &[&str],
        states: &[Entry<T>],
        row: impl Fn(&Entry<T>, &T) -> Vec<String>,
    ) {
        let mut t = HtmlTable::new("states-table", heads);
        for st in states {
            match &st.outcome {
                Ok(s) => t.row(row(st, s)),
                Err(e) => t.row([
                    td(st.branch),
                    td(st.eta),
                    td(st.lbar),
                    td(esc(&st.why)),
                    format!(
                        "<td colspan=\"{}\" class=\"bad\">not solved: {}</td>",
                        heads.len().saturating_sub(4),
                        esc(e)
                    ),
                ]),
            }
        }
        self.h.push_str(&t.finish());
    }

    /// The two pictures of every solved state side by side in `<div class="state">`: the loop
    /// (`fig-loop-B`) and its profile along the loop (`fig-force-B`), with the labels and
    /// captions `text` gives (`[(label, caption); 2]`).
    pub fn state_pictures<T: Solved>(
        &mut self,
        states: &[Entry<T>],
        text: impl Fn(&Entry<T>, &T) -> [(String, String); 2],
    ) {
        for st in states {
            if let Ok(s) = &st.outcome {
                let _ = writeln!(self.h, "<div class=\"state\" id=\"state-{}\">", st.branch);
                let [(loop_label, loop_caption), (force_label, force_caption)] = text(st, s);
                let (picture, profile) = s.pictures();
                self.fig(
                    picture,
                    &loop_label,
                    &loop_caption,
                    &format!("fig-loop-{}", st.branch),
                );
                self.fig(
                    profile,
                    &force_label,
                    &force_caption,
                    &format!("fig-force-{}", st.branch),
                );
                self.h.push_str("</div>\n");
            }
        }
    }

    /// The end of the page and of the run: the settings (section `settings.number`), the
    /// timings (the next section: `stages`, the states solved in `t_states` seconds, the page
    /// assembly, `total`), the footer; `report.html` written, `summary.json` given the
    /// `report` object (`fields`, the states, the files, `seconds` (`times` with states, page
    /// and total) and the page's size and figures), the run committed. Returns the page's
    /// size in bytes, its figures and how many states could not be solved.
    #[allow(clippy::too_many_arguments)]
    pub fn finish<T: Solved>(
        mut self,
        run: OutputRun,
        settings: &Settings,
        stages: &[(&str, f64)],
        times: &[(&str, f64)],
        states: &[Entry<T>],
        t_states: f64,
        t_page: f64,
        total: f64,
        fields: serde_json::Value,
    ) -> Result<(usize, usize, usize)> {
        let serde_json::Value::Object(mut fields) = fields else {
            anyhow::bail!("internal error: the report fields are not an object");
        };
        tables::settings_section(&mut self.h, &run, settings);
        let state_rows: Vec<(u32, f64, f64)> = states
            .iter()
            .filter_map(|st| {
                st.outcome
                    .as_ref()
                    .ok()
                    .map(|s| (st.branch, st.lbar, s.seconds()))
            })
            .collect();
        tables::finish_page(
            &run,
            &mut self.h,
            settings.number + 1,
            stages,
            (states.len(), t_states, &state_rows),
            t_page,
            total,
        )?;
        let notes = states
            .iter()
            .map(|st| {
                let mut v = match &st.outcome {
                    Ok(s) => s.note()?,
                    Err(e) => checked_json!({"error": e})?,
                };
                if let serde_json::Value::Object(m) = &mut v {
                    m.insert("branch".into(), st.branch.into());
                    m.insert("eta".into(), st.eta.into());
                    m.insert("lbar".into(), checked_json!({"v": st.lbar})?["v"].clone());
                }
                Ok(v)
            })
            .collect::<Result<Vec<_>>>()?;
        // The tracer's branches/*.json stay in the staging directory (removed at commit).
        let mut files = crate::states::files_in(run.stage_dir())?;
        files.retain(|f| !f.starts_with("branches/"));
        let mut seconds = serde_json::Map::new();
        for (k, v) in
            times
                .iter()
                .copied()
                .chain([("states", t_states), ("page", t_page), ("total", total)])
        {
            seconds.insert(k.into(), checked_json!({"v": v})?["v"].clone());
        }
        let (bytes, figures) = (self.h.len(), self.figs.count);
        fields.extend([
            ("file".to_string(), "report.html".into()),
            ("states_dir".to_string(), "states".into()),
            ("files".to_string(), serde_json::to_value(files)?),
            ("bytes".to_string(), bytes.into()),
            ("figures".to_string(), figures.into()),
            ("states".to_string(), notes.into()),
            ("version".to_string(), env!("CARGO_PKG_VERSION").into()),
            ("seconds".to_string(), seconds.into()),
        ]);
        let failed = states.iter().filter(|s| s.outcome.is_err()).count();
        tables::commit_report(run, fields.into(), failed, states.len())?;
        Ok((bytes, figures, failed))
    }
}
