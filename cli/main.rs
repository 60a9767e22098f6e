//! `rodloop`: equilibria, energies, forces and branch diagrams of elastic rod loops packed in
//! a sphere (Wang, Li & Yi, J. Mech. Phys. Solids, 2024).
//!
//! `main` parses arguments, runs one subcommand, prints the whole error chain on one line on
//! failure and returns a non-zero exit code; it never panics on bad input.

/// Print a line to stdout, ignoring write errors (a closed pipe, as in `rodloop … | head`,
/// must not turn into a panic).
macro_rules! outln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout(), $($arg)*);
    }};
}

mod analytic;
mod args;
mod atlas;
mod compare;
mod compare_segments;
mod converge;
mod converge_enclosed;
mod decimal;
mod diagram;
mod dispatch;
mod draw;
mod enclosed;
mod engine;
mod euler;
mod export;
mod output;
mod phase;
mod phase_figure;
mod phase_rows;
mod progress;
mod report;
mod solve;
mod staging;
mod states;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Command-line arguments.
#[derive(Parser, Debug)]
#[command(
    name = "rodloop",
    version,
    about = "Elastic rod loops packed in a sphere: exact and numerical equilibria, energies, forces, branch diagrams",
    long_about = None
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Every exact closed loop with eta periods of geodesic curvature at one length (Sec. 4.3).
    #[command(allow_negative_numbers = true)]
    Analytic(analytic::Args),
    /// One numerical equilibrium for any stiffness profile: shape, energy, forces, Hessian
    /// stability (index), with an error estimate.
    #[command(allow_negative_numbers = true)]
    Solve(solve::Args),
    /// The Euler rotation curve approximation (Eqs. 4-6) at one length.
    #[command(allow_negative_numbers = true)]
    Euler(euler::Args),
    /// The energy-versus-length diagram with its critical lengths (Fig. 3a).
    #[command(allow_negative_numbers = true)]
    Diagram(diagram::Args),
    /// The paper's printed values (critical lengths, buckling loads, winding numbers) next to
    /// rodloop's, with deviations.
    #[command(allow_negative_numbers = true)]
    Compare(compare::Args),
    /// One state on a ladder of resolutions: error against cells and time, observed order
    /// of convergence (the speed/accuracy trade).
    Converge(converge::Args),
    /// Pictures of a loop (four views on the sphere, coloured by a column, self-contacts
    /// marked) or of a diagram's branches.csv, as SVG and PNG.
    #[command(allow_negative_numbers = true)]
    Draw(draw::Args),
    /// One self-contained HTML page: the numeric diagram and its figures, the critical
    /// lengths with errors (and exact values for homogeneous scenes), the paper's values, a
    /// picture and the contact force of each branch's stable state, settings and timings.
    #[command(allow_negative_numbers = true)]
    Report(report::Args),
    /// Loop tables as VTK PolyData (.vtp) for ParaView: points, a closed polyline, and s, κ,
    /// τ, κ_g, λ, F_t, F_n, F_b (every column of the table) as point data.
    Export(export::Args),
    /// The critical lengths of a two-segment rod as curves in D1/D0 (or gamma, s0, s1):
    /// continuation of each exchange of the lowest branch, with error estimates.
    #[command(allow_negative_numbers = true)]
    Phase(phase::Args),
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            use clap::error::ErrorKind;
            if matches!(
                e.kind(),
                ErrorKind::DisplayHelp
                    | ErrorKind::DisplayVersion
                    | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
            ) {
                e.exit();
            }
            eprintln!("{}", one_line_usage_error(&e.render().to_string()));
            return ExitCode::from(2);
        }
    };
    let result = match cli.command {
        Command::Analytic(a) => analytic::run(&a),
        Command::Solve(a) => dispatch::solve(&a),
        Command::Euler(a) => euler::run(&a),
        Command::Diagram(a) => dispatch::diagram(&a),
        Command::Compare(a) => dispatch::compare(&a),
        Command::Converge(a) => dispatch::converge(&a),
        Command::Draw(a) => draw::run(&a),
        Command::Report(a) => dispatch::report(&a),
        Command::Phase(a) => dispatch::phase(&a),
        Command::Export(a) => export::run(&a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("error: {}", one_line(&err));
            ExitCode::FAILURE
        }
    }
}

/// The error and its causes on one line, `context: cause: cause`; a cause whose text the line
/// already holds (a library error that quotes its source) is not repeated.
fn one_line(err: &anyhow::Error) -> String {
    let mut line = err.to_string();
    for cause in err.chain().skip(1) {
        let cause = cause.to_string();
        if !line.contains(&cause) {
            line.push_str(": ");
            line.push_str(&cause);
        }
    }
    line
}

/// clap's message for a mistake on the command line (an unknown option, an invalid choice, a
/// missing argument) on one line: the error, its details and tip, and the usage.
fn one_line_usage_error(text: &str) -> String {
    let mut lines = text.lines().map(str::trim).filter(|l| !l.is_empty());
    let mut line = lines
        .next()
        .unwrap_or("error: invalid command line")
        .to_string();
    let mut details = Vec::new();
    let mut usage = None;
    for l in lines {
        if let Some(u) = l.strip_prefix("Usage:") {
            usage = Some(u.trim().to_string());
        } else if !l.starts_with("For more information") {
            details.push(l.to_string());
        }
    }
    if !details.is_empty() {
        if line.ends_with(':') {
            line = format!("{line} {}", details.join(", "));
        } else {
            line = format!("{line} ({})", details.join("; "));
        }
    }
    if let Some(u) = usage {
        line = format!("{line}; usage: {u}");
    }
    line
}
