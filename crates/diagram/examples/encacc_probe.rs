use rodloop_diagram::enclosed_state::solve_state;
use rodloop_solver::enclosed::centre::placed_levels;
use rodloop_solver::enclosed::EnclosedOptions;
use rodloop_solver::{Accuracy, Stiffness};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let lbar: f64 = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(1.357968);
    let branch: u32 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(2);
    let n0: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(32);
    let k: usize = args.get(4).and_then(|s| s.parse().ok()).unwrap_or(3);
    let stiff = Stiffness::Tanh {
        d0: 1.0,
        d1: 0.5,
        s0: 0.3,
        s1: 0.8,
        gamma: 200.0,
    };
    let t = std::time::Instant::now();
    let res = solve_state(1.0, &stiff, lbar, branch, Accuracy::Default).expect("solve");
    println!(
        "solve {:.2}s: N = {}, E = {:.10} ± {:.1e}",
        t.elapsed().as_secs_f64(),
        res.state.model.cells(),
        res.energy.0,
        res.energy.1
    );
    let t = std::time::Instant::now();
    let lv = placed_levels(&res.state, n0, k, &EnclosedOptions::default()).expect("levels");
    println!("placed {:.2}s", t.elapsed().as_secs_f64());
    let e: Vec<f64> = lv.iter().map(|s| s.energy()).collect();
    for s in &lv {
        println!(
            "N = {} E = {:.12} it {}",
            s.model.cells(),
            s.energy(),
            s.iterations
        );
    }
    for w in e.windows(3) {
        println!("order {:.2}", ((w[1] - w[0]) / (w[2] - w[1])).abs().log2());
    }
}
