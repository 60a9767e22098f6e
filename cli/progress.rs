//! Progress reporting on stderr (indicatif): bars when stderr is a terminal; when it is not
//! (logs, pipes), one line per finished branch or stage; nothing with `--quiet`.
//!
//! One bar counts one kind of thing, and a step is one of those things finished:
//! `Progress::new(branches, "branches", quiet)`, then `message("tracing branch 2")` while
//! working and `done("branch 2 traced (…)")` once per finished branch (a branch traced as
//! several families or sheets is still one step), `finish()` at the end.

use std::io::IsTerminal;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// A progress bar that is hidden when it should not draw.
pub struct Progress {
    bar: ProgressBar,
    /// Print one line per finished stage instead (stderr is not a terminal, not `--quiet`).
    lines: bool,
}

impl Progress {
    /// A bar of `len` steps labelled `what`; hidden if `quiet` or stderr is not a terminal.
    pub fn new(len: u64, what: &str, quiet: bool) -> Self {
        let bar = if quiet || !std::io::stderr().is_terminal() {
            ProgressBar::hidden()
        } else {
            let bar = ProgressBar::new(len);
            bar.set_draw_target(ProgressDrawTarget::stderr());
            if let Ok(style) = ProgressStyle::with_template(
                "{prefix:>10} [{bar:30}] {pos}/{len} {elapsed_precise} (about {eta} left) {msg}",
            ) {
                bar.set_style(style.progress_chars("=> "));
            }
            bar
        };
        bar.set_prefix(what.to_string());
        Self {
            bar,
            lines: !quiet && !std::io::stderr().is_terminal(),
        }
    }

    /// Report a finished branch or stage: one line on stderr when there is no bar to show it
    /// (stderr is not a terminal), the bar's message otherwise; nothing with `--quiet`.
    pub fn done(&self, msg: String) {
        if self.lines {
            eprintln!("{msg}");
        }
        self.step(msg);
    }

    /// Advance by one step with a message.
    pub fn step(&self, msg: String) {
        self.bar.set_message(msg);
        self.bar.inc(1);
    }

    /// Change the message without advancing.
    pub fn message(&self, msg: String) {
        self.bar.set_message(msg);
    }

    /// Grow the total.
    pub fn set_length(&self, len: u64) {
        self.bar.set_length(len);
    }

    /// Finish and clear the bar.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}
