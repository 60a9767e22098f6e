//! Time and accuracy of the numeric diagram on the default scene, per accuracy level.
//!
//! `cargo run --release -p rodloop-diagram --example accuracy_table [-- RUNS [THREADS]]`
//!
//! For every level: the median wall time of `RUNS` runs of `rodloop_diagram::compute`
//! (default 5; `THREADS` worker threads, default all), the largest deviation of a critical
//! length from the exact layer (and the largest reported error estimate), the largest
//! deviation of a buckling load from Eqs. (33)–(34), and the largest error of a traced energy
//! against the exact loops. Prints a Markdown table.

use std::time::Instant;

use rodloop_diagram::{compute, DiagramOptions, NumericDiagram};
use rodloop_solver::Accuracy;

fn main() {
    let mut args = std::env::args().skip(1);
    let runs: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(5).max(1);
    let threads: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(0);
    let exact = rodloop_exact::diagram::compute(&Default::default()).expect("exact diagram");
    println!(
        "| level | median time (s) | min / max (s) | max critical-length error | max error estimate \
         | max buckling-load deviation | max traced-energy error (relative) | tracing / crossings / \
         great circles (s) |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for level in [Accuracy::Fast, Accuracy::Default, Accuracy::High] {
        let opts = DiagramOptions {
            threads,
            ..DiagramOptions::with_accuracy(level)
        };
        let mut times = Vec::new();
        let mut last: Option<NumericDiagram> = None;
        for _ in 0..runs {
            let t = Instant::now();
            let d = compute(&opts, &mut (), &mut |_| {}).expect("diagram");
            times.push(t.elapsed().as_secs_f64());
            last = Some(d);
        }
        let d = last.expect("at least one run");
        times.sort_by(f64::total_cmp);
        let median = times[times.len() / 2];
        assert_eq!(d.critical.len(), exact.critical.len(), "critical lengths");
        let crit_err = d
            .critical
            .iter()
            .zip(&exact.critical)
            .map(|(c, e)| (c.lbar_cr - e.lbar_cr).abs())
            .fold(0.0, f64::max);
        let crit_est = d
            .critical
            .iter()
            .map(|c| c.error_estimate)
            .fold(0.0, f64::max);
        let buckling = d
            .great_circles
            .as_ref()
            .map(|g| {
                g.loads
                    .iter()
                    .filter_map(|l| l.deviation)
                    .fold(0.0, f64::max)
            })
            .unwrap_or(f64::NAN);
        let energy = d
            .branches
            .iter()
            .flat_map(|b| {
                b.points.iter().map(move |p| {
                    let e = rodloop_exact::paper_branch_loop(b.eta, p.value)
                        .and_then(|l| l.energy())
                        .expect("exact loop");
                    ((p.energy - e) / e).abs()
                })
            })
            .fold(0.0, f64::max);
        println!(
            "| {level:?} | {median:.3} | {:.3} / {:.3} | {crit_err:.1e} | {crit_est:.1e} | {buckling:.1e} \
             | {energy:.1e} | {:.3} / {:.3} / {:.3} |",
            times[0],
            times[times.len() - 1],
            d.timings.tracing,
            d.timings.critical,
            d.timings.great_circles
        );
    }
    println!(
        "\n(tracing is wall time; crossings and great circles are summed over tasks that run in \
         parallel; {} worker threads)",
        DiagramOptions {
            threads,
            ..Default::default()
        }
        .worker_threads()
    );
}
