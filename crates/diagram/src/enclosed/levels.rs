//! A lifted-off state of the enclosed diagram at its three resolutions `N/4, N/2, N`
//! ([`Levels`]): its energy with the three-level estimate, the natural-parameter steps of all
//! three levels together, and the diagram point it becomes. The tracer (`trace.rs`), the
//! special-point locator (`locate.rs`) and the exchanges build on it.

use rodloop_solver::enclosed::{
    point_like_contact, solve_enclosed, three_level_estimate, EnclosedOptions, EnclosedState,
    LIFTED_OFF_MAX_ORDER,
};
use rodloop_solver::SolverError;

use super::{BranchFrom, EnclosedPoint, PointShape, PointSource, TOUCH};
use crate::labels::Label;

thread_local! {
    /// The level whose solve failed last in [`Levels::solve_each`] on this thread.
    static FAILED_LEVEL: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

/// A traced lifted-off state at three resolutions `N/4, N/2, N`.
#[derive(Clone, Debug)]
pub(super) struct Levels {
    pub(super) lbar: f64,
    pub(super) states: [EnclosedState; 3],
}

impl Levels {
    pub(super) fn energy(&self) -> (f64, f64) {
        let e = [
            self.states[0].energy(),
            self.states[1].energy(),
            self.states[2].energy(),
        ];
        // Fourth order where no contact end lies between nodes: fully attached, or free;
        // point-like contact at order 1 with `solve_branch`'s safety factor
        // (`POINT_CONTACT_SAFETY`: its contact points move between nodes as `N` doubles).
        let (max_order, safety) = match self.states[2].contact(TOUCH) {
            Ok(c) if c.fraction >= 1.0 || c.fraction == 0.0 => (4.0, 1.0),
            Ok(c) if point_like_contact(&self.states[2], &c) => {
                (1.0, rodloop_solver::enclosed::branch::POINT_CONTACT_SAFETY)
            }
            _ => (LIFTED_OFF_MAX_ORDER, 1.0),
        };
        let (err, _) = three_level_estimate(e[0], e[1], e[2], max_order);
        (e[2], safety * err)
    }

    /// `true` when the levels are traced with the translations pinned (a loop off the wall).
    pub(super) fn free(&self) -> bool {
        self.states[2].model.gauge().pin.is_some()
    }

    /// The levels solved by `solve` (each from its own state and level index): the level
    /// that failed last on this thread first, then the others from the coarsest. A step
    /// fails where any level fails, and consecutive failures of a walk tend to fail on the
    /// same level (the coarsest in the creeps of the two-segment rod, the finest in most
    /// halved steps), so the solves of the other levels are not spent on a step that fails.
    /// The order does not change the result: each level is solved from its own state.
    fn solve_each<F>(&self, lbar: f64, mut solve: F) -> Result<Levels, SolverError>
    where
        F: FnMut(usize, &EnclosedState) -> Result<EnclosedState, SolverError>,
    {
        let first = FAILED_LEVEL.get();
        let order = std::iter::once(first).chain((0..3).filter(|&k| k != first));
        let mut out: [Option<EnclosedState>; 3] = [None, None, None];
        for k in order {
            match solve(k, &self.states[k]) {
                Ok(s) => out[k] = Some(s),
                Err(e) => {
                    FAILED_LEVEL.set(k);
                    return Err(e);
                }
            }
        }
        let [Some(a), Some(b), Some(c)] = out else {
            return Err(SolverError::InvalidInput("a level was not solved".into()));
        };
        Ok(Levels {
            lbar,
            states: [a, b, c],
        })
    }

    /// Natural-parameter step of each level to `lbar` (a free loop re-centred and pinned,
    /// [`EnclosedState::step_free`]).
    pub(super) fn step_to(&self, lbar: f64, opts: &EnclosedOptions) -> Result<Levels, SolverError> {
        let free = self.free();
        self.solve_each(lbar, |_, s| {
            if free {
                s.step_free(lbar, opts)
            } else {
                s.step_to(lbar, opts)
            }
        })
    }

    /// Natural-parameter step of each level to `lbar` from the secant predictor through
    /// `prev` ([`EnclosedState::predict_to`]); an error where it does not apply.
    pub(super) fn step_predicted(
        &self,
        prev: &Levels,
        lbar: f64,
        opts: &EnclosedOptions,
    ) -> Result<Levels, SolverError> {
        self.solve_each(lbar, |k, s| {
            let (model, z) = s.predict_to(&prev.states[k], lbar)?.ok_or_else(|| {
                SolverError::InvalidInput("no secant predictor for this pair of states".into())
            })?;
            solve_enclosed(&model, z, opts)
        })
    }

    /// A step to `lbar` that leaves the wall: every level stepped with the translations
    /// pinned ([`EnclosedState::step_free`]), accepted only where no level touches the wall
    /// any more (no wall force, every gap above [`TOUCH`]), so that the pin carries no
    /// force and the state is a free equilibrium. Tried where a trace with the wall's point
    /// contacts fails: as the contact forces of a loop held by the wall at isolated points
    /// go to zero, the translations across the contact normals lose their stiffness and the
    /// unpinned KKT matrix becomes singular.
    pub(super) fn leave_wall(
        &self,
        lbar: f64,
        opts: &EnclosedOptions,
    ) -> Result<Levels, SolverError> {
        self.solve_each(lbar, |_, s| {
            let t = s.step_free(lbar, opts)?;
            let touching =
                t.multipliers().iter().any(|&l| l != 0.0) || t.contact(TOUCH)?.fraction > 0.0;
            if touching {
                return Err(SolverError::InvalidInput(format!(
                    "the pinned state at lbar = {lbar} still touches the wall"
                )));
            }
            Ok(t)
        })
    }

    /// The stability index of the finest level, the state reported: counted on `N/2` (the
    /// dense inertia count, eight times cheaper than on `N`) and carried to `N` where the
    /// two levels' Newton Jacobians have determinants of one sign, counted on `N` where
    /// they do not ([`rodloop_solver::enclosed::EnclosedState::index_via`]). The levels'
    /// contacts sit differently on their nodes, and their indices can differ: on the
    /// two-segment scene 15 of its 164 sampled states have levels of different index (9 of
    /// them `N` against `N/4`, the index a count on the coarsest level would report).
    pub(super) fn index(&self) -> Result<usize, SolverError> {
        self.states[2].index_via(&self.states[1], 1e-6)
    }

    pub(super) fn point(&self, branch: u32, eta: u32) -> Result<EnclosedPoint, SolverError> {
        let fine = &self.states[2];
        let (energy, energy_error) = self.energy();
        let c = fine.contact(TOUCH)?;
        let (lmin, gmin, comp, stat) = fine.optimality()?;
        let index = self.index()?;
        Ok(EnclosedPoint {
            branch,
            eta,
            lbar: self.lbar,
            energy,
            energy_error,
            attached: c.fraction >= 1.0,
            contact_fraction: c.fraction,
            contact_intervals: c.intervals,
            max_gap: c.max_gap.0,
            lambda_min: lmin,
            gap_min: gmin,
            complementarity: comp,
            stationarity: stat,
            index,
            label: Label::Unstable,
            lowest: false,
            cells: fine.model.cells(),
            source: PointSource::Model,
            family: 0,
            sheet: 0,
            multiplicity: 1,
            branch_from: BranchFrom::Exact,
            surface_energy: None,
            shape: PointShape::Model(Box::new(fine.clone())),
        })
    }
}
