use rodloop_solver::enclosed::{
    branch::resample_state, nonuniform_cells, solve_enclosed, EnclosedOptions,
};
use rodloop_solver::{Accuracy, Stiffness};
fn sharp() -> Stiffness {
    Stiffness::Tanh {
        d0: 1.0,
        d1: 0.5,
        s0: 0.3,
        s1: 0.8,
        gamma: 200.0,
    }
}
fn main() {
    let eta = 1;
    let x0 = 1.35;
    let x1: f64 = std::env::args().nth(1).unwrap().parse().unwrap();
    let opts = EnclosedOptions::default();
    let n = nonuniform_cells(Accuracy::Default, eta);
    let (res, _) = rodloop_solver::solve_robust(
        1.0,
        x0,
        &sharp(),
        &rodloop_solver::StartShape::Euler { l: eta },
        Accuracy::Default,
        Some(eta),
        &rodloop_solver::SolveOptions::default(),
    )
    .unwrap();
    let src = rodloop_solver::enclosed::SurfaceSource::Numeric(Box::new(res.equilibrium));
    let ((b, _, _), _) = rodloop_solver::enclosed::descent::solve_branch_lowest(
        1.0,
        x0,
        eta,
        &sharp(),
        &src,
        &[n],
        &opts,
    )
    .unwrap();
    println!("x0 E={} ± {:.1e}", b.energy, b.energy_error);
    let f = b.fine.step_to(x1, &opts).unwrap();
    println!("N={} E={:.10}", f.model.cells(), f.energy());
    let wd = EnclosedOptions {
        watchdog: 2,
        ..opts.clone()
    };
    let (m, z) = f.refine().unwrap();
    match solve_enclosed(&m, z.clone(), &wd) {
        Ok(s) => println!("refine wd N={} E={:.10}", s.model.cells(), s.energy()),
        Err(e) => println!("refine wd fail {e}"),
    }
    match solve_enclosed(&m, z, &opts) {
        Ok(s) => println!("refine N={} E={:.10}", s.model.cells(), s.energy()),
        Err(e) => println!("refine fail {e}"),
    }
    for c in [128, 160, 192, 224, 256, 320, 384, 512] {
        let (m, z) = resample_state(&f, c).unwrap();
        match solve_enclosed(&m, z.clone(), &wd) {
            Ok(s) => {
                let ct = s.contact(1e-9).unwrap();
                println!(
                    "resample N={c} E={:.10} cf={:.4} runs={}",
                    s.energy(),
                    ct.fraction,
                    ct.intervals
                )
            }
            Err(e) => println!("resample N={c} fail {e}"),
        }
    }
}
