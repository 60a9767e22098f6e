//! One state of a traced branch solved accurately at a chosen length: from the Euler curve
//! `l = η` (as `rodloop solve` starts), and where that fails from the diagram's own traced
//! state there (re-solved at the tracing resolution and passed on as points), each result
//! checked to have converged onto branch `η` (identified from the periods of its own `κ_g`).

use rodloop_solver::identify::identify_equilibrium;
use rodloop_solver::start::from_points;
use rodloop_solver::{
    solve_with_accuracy, Accuracy, AccurateEquilibrium, SolveOptions, SolverError, StartShape,
};

use crate::{DiagramError, DiagramOptions, NumericDiagram};

/// An error and its causes on one line, `error: cause: cause`.
fn chain(e: &dyn std::error::Error) -> String {
    let mut line = e.to_string();
    let mut cause = e.source();
    while let Some(c) = cause {
        line.push_str(": ");
        line.push_str(&c.to_string());
        cause = c.source();
    }
    line
}

/// An accurate equilibrium of branch `eta` at `lbar` of the diagram's scene (radius and
/// stiffness of `opts`) from `start`, converged and on branch `eta`.
fn solve_checked(
    opts: &DiagramOptions,
    accuracy: Accuracy,
    eta: u32,
    lbar: f64,
    start: &StartShape,
) -> Result<AccurateEquilibrium, String> {
    let res = solve_with_accuracy(
        opts.radius,
        lbar,
        &opts.stiffness,
        start,
        accuracy,
        &SolveOptions::default(),
    )
    .map_err(|e| chain(&e))?;
    let report = res.equilibrium.report();
    if !report.converged {
        return Err(format!(
            "the solve did not converge (KKT residual {:.1e})",
            report.residual
        ));
    }
    rodloop_solver::verify_accurate(&res, Some(eta)).map_err(|e| chain(&e))?;
    let periods = identify_equilibrium(&res.equilibrium).map_err(|e| chain(&e))?;
    if periods.eta != eta {
        return Err(format!(
            "the solve converged onto a state with eta = {} instead of {eta}",
            periods.eta
        ));
    }
    Ok(res)
}

/// Branch `eta` of diagram `d` (traced with `opts`) solved at `lbar` and `accuracy`, and how
/// it was started (`the Euler curve l = η`, or the diagram's traced state with why the Euler
/// start failed).
pub fn solve_on_branch(
    d: &NumericDiagram,
    opts: &DiagramOptions,
    accuracy: Accuracy,
    eta: u32,
    lbar: f64,
) -> Result<(AccurateEquilibrium, String), DiagramError> {
    let euler = match solve_checked(opts, accuracy, eta, lbar, &StartShape::Euler { l: eta }) {
        Ok(r) => return Ok((r, format!("the Euler curve l = {eta}"))),
        Err(e) => e,
    };
    let traced = d
        .branch_by_eta(eta)
        .ok_or_else(|| "the branch is not traced".to_string())
        .and_then(|b| b.solve_at(opts, lbar).map_err(|e| chain(&e)))
        .and_then(|eq| {
            let pts: Vec<[f64; 3]> = eq.profile().iter().map(|p| [p.x, p.y, p.z]).collect();
            from_points(&pts)
                .map(|s| s.0)
                .map_err(|e: SolverError| chain(&e))
        })
        .and_then(|start| solve_checked(opts, accuracy, eta, lbar, &start));
    match traced {
        Ok(r) => Ok((
            r,
            format!("the diagram's traced state (from the Euler curve: {euler})"),
        )),
        Err(e) => Err(DiagramError::Unsolved(format!(
            "from the Euler curve: {euler}; from the diagram's traced state: {e}"
        ))),
    }
}
