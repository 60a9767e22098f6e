//! Order of convergence of the enclosed model on a lifted-off state: the
//! figure-eight (η = 1) at a given L̄, solved at N = 32 … 2048 cells by the cascade
//! N/4, N/2, N; prints E_N, the difference to the finest, the observed order, the
//! three-level estimate and the time of each cascade.
//!
//! `cargo run --release -p rodloop-solver --example enclosed_order -- 1.4 1024 [32]`
//! (arguments: L̄, largest N, smallest N)

use std::time::Instant;

use rodloop_exact::paper_branch_loop;
use rodloop_solver::enclosed::{solve_branch, EnclosedOptions, SurfaceSource};
use rodloop_solver::Stiffness;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let lbar: f64 = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(1.4);
    let top: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(2048);
    let eta = 1;
    let l = paper_branch_loop(eta, lbar).expect("exact loop");
    let mut rows = Vec::new();
    let mut n: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(32);
    while n <= top {
        let t = Instant::now();
        let b = solve_branch(
            1.0,
            lbar,
            &Stiffness::uniform(1.0),
            &SurfaceSource::Exact(l),
            n,
            &EnclosedOptions::default(),
        );
        let b = match b {
            Ok(b) => b,
            Err(e) => {
                eprintln!("N = {n}: {e}");
                n *= 2;
                continue;
            }
        };
        let dt = t.elapsed().as_secs_f64();
        let c = b.fine.contact(1e-9).expect("contact");
        rows.push((
            n,
            b.energy,
            b.energy_error,
            b.order,
            dt,
            c.fraction,
            b.fine.iterations,
            b.centred_energy,
        ));
        n *= 2;
    }
    let e_ref = rows.last().map(|r| r.1).unwrap_or(f64::NAN);
    println!("lbar = {lbar}, surface E = {:.12}", l.energy().unwrap());
    println!("N\tE_N\t|E_N - E_ref|/E\torder\testimate/E\tp_obs\tcontact\titer\ttime_s\tE_centred\testimate_centred/E");
    for (k, r) in rows.iter().enumerate() {
        let err = (r.1 - e_ref).abs() / e_ref;
        let order = if k + 2 < rows.len() {
            let d1 = (rows[k + 1].1 - r.1).abs();
            let d2 = (rows[k + 2].1 - rows[k + 1].1).abs();
            format!("{:.2}", (d1 / d2).log2())
        } else {
            "-".into()
        };
        let centred =
            r.7.map(|(e, de)| format!("{e:.13}\t{:.2e}", de / e_ref))
                .unwrap_or_else(|| "-\t-".into());
        println!(
            "{}\t{:.13}\t{:.2e}\t{}\t{:.2e}\t{:.2}\t{:.4}\t{}\t{:.3}\t{centred}",
            r.0,
            r.1,
            err,
            order,
            r.2 / e_ref,
            r.3,
            r.5,
            r.6,
            r.4
        );
    }
}
