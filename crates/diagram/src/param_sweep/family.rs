//! The families of one branch of a `--param` sweep: each seed marched both ways with the
//! generic stepping loop ([`march`]), joined into one family, its folds, branch points and
//! index changes re-solved with estimates, and the secondary families switched onto at its
//! branch points.

use rodloop_continuation::{Direction, SpecialKind};
use rodloop_exact::eta_of_branch;
use rodloop_solver::{Confinement, ParamProblem, SurfaceSolve};

use super::continued::Continued;
use super::seeds::{energy_with_estimate, seed_values, seeds, traced};
use super::{SweepFamily, SweepPoint, SweepSettings, SweepSpecial, SAME_STATE};
use crate::labels::Label;
use crate::march::{
    march, march_switch, FoldPolicy, March, MarchSettings, MarchSpecial, MarchStop,
};
use crate::states::INDEX_TOLERANCE;
use crate::DiagramError;

/// What the families of one branch share.
pub(super) struct Ctx<'a, M> {
    pub(super) s: &'a SweepSettings,
    pub(super) model: &'a M,
    pub(super) branch: u32,
    pub(super) cells: usize,
}

impl<M: SurfaceSolve> Ctx<'_, M> {
    /// The family of a march (with its seed first, when it has one); its folds, branch
    /// points and index changes (energies re-solved with their estimates; one that cannot be
    /// re-solved is left out with a warning).
    pub(super) fn family(
        &self,
        family: usize,
        seed: Option<SweepPoint>,
        seed_energy: Option<(f64, f64, f64)>,
        m: &March,
        special: &mut Vec<SweepSpecial>,
        warnings: &mut Vec<String>,
    ) -> Result<SweepFamily, DiagramError> {
        let (s, model, branch) = (self.s, self.model, self.branch);
        let mut points: Vec<SweepPoint> = seed.into_iter().collect();
        for p in &m.points {
            let mv = model.with_param(s.param, p.value)?;
            let index = match p.index {
                Some(i) => i,
                None => mv.index(&p.x, INDEX_TOLERANCE)?,
            };
            points.push(SweepPoint {
                value: p.value,
                energy: Confinement::energy(&mv, &p.x)?,
                index,
                label: Label::Unstable,
                arc: points.len(),
                state: p.x.clone(),
            });
        }
        let mut add = |kind: &str, x: &[f64], value: f64, index: Option<(usize, usize)>| {
            match energy_with_estimate(model, s.param, x, value, &s.solve) {
                Ok((energy, energy_error)) => special.push(SweepSpecial {
                    kind: kind.into(),
                    value,
                    energy,
                    energy_error,
                    branch,
                    family,
                    index,
                }),
                Err(e) => warnings.push(format!(
                    "branch {branch} family {family}: the {kind} at {} = {value:.8} could not be re-solved ({e}): left out",
                    s.param
                )),
            }
        };
        for sp in &m.special {
            let kind = match sp.kind {
                SpecialKind::Fold => "fold",
                SpecialKind::BranchPoint => "branch_point",
                _ => continue,
            };
            add(kind, &sp.x, sp.value, None);
        }
        for ic in &m.index_changes {
            if let Some(p) = m
                .points
                .iter()
                .find(|p| (p.value - ic.value).abs() <= 1e-12 * ic.value.abs().max(1.0))
            {
                add("index_change", &p.x, p.value, Some((ic.below, ic.above)));
            }
        }
        let end = match &m.stop {
            MarchStop::Reached => "reached the end of the range".to_string(),
            MarchStop::StepTooSmall { value, cause, .. } => format!(
                "the step fell below its minimum at {} = {value}{}",
                s.param,
                cause
                    .as_ref()
                    .map(|c| format!(" ({c})"))
                    .unwrap_or_default()
            ),
            MarchStop::MaxSteps => "the step budget (1500) was used up".into(),
            MarchStop::ClosedLoop => "the family closed a loop".into(),
            other => format!("{other:?}"),
        };
        if !matches!(m.stop, MarchStop::Reached | MarchStop::ClosedLoop) {
            warnings.push(format!("branch {branch} family {family}: {end}"));
        }
        Ok(SweepFamily {
            branch,
            eta: eta_of_branch(branch),
            family,
            cells: self.cells,
            seed_energy,
            points,
            end,
            notes: Vec::new(),
        })
    }
}

/// One branch of a sweep being traced: the families of its seeds, each marched both ways
/// from its seed, and the secondary families switched onto at their branch points; with the
/// special points and warnings they produce, in the order they are found.
pub(super) struct BranchTrace<'a, M> {
    ctx: Ctx<'a, M>,
    scene_value: f64,
    cont: Continued<M>,
    problem: ParamProblem<Continued<M>>,
    /// Unknowns of the state that the march scales (the Gauss values of `κ_g`).
    shape: usize,
    /// Every traced state of this branch `(value, x)`, to recognise seeds on known families.
    known: Vec<Vec<(f64, Vec<f64>)>>,
    /// Families numbered so far.
    family: usize,
    /// The traced families (secondary families before the family they switch from).
    pub(super) families: Vec<SweepFamily>,
    /// Folds, branch points and index changes.
    pub(super) special: Vec<SweepSpecial>,
    /// Seeds that failed, families that stopped early.
    pub(super) warnings: Vec<String>,
}

impl<'a, M: SurfaceSolve> BranchTrace<'a, M> {
    /// The branch `branch` of `s` on `model` (at the scene's value `scene_value`), with
    /// `shape` scaled unknowns.
    pub(super) fn new(
        s: &'a SweepSettings,
        scene_value: f64,
        branch: u32,
        model: &'a M,
        cells: usize,
        shape: usize,
    ) -> Result<Self, DiagramError> {
        let cont = Continued {
            model: model.clone(),
            // The parameter's own axis (Param::axis: d1 and gamma in their logarithm).
            axis: s.param.axis(),
        };
        let problem = ParamProblem::new(cont.clone(), s.param)?;
        Ok(Self {
            ctx: Ctx {
                s,
                model,
                branch,
                cells,
            },
            scene_value,
            cont,
            problem,
            shape,
            known: Vec::new(),
            family: 0,
            families: Vec::new(),
            special: Vec::new(),
            warnings: Vec::new(),
        })
    }

    /// March settings towards the parameter value `limit`, with `far` the other end of the
    /// range.
    fn toward(&self, limit: f64, far: f64) -> MarchSettings {
        let s = self.ctx.s;
        MarchSettings {
            limit: self.cont.p_of(limit),
            ds: 0.05,
            ds_min: 1e-7,
            ds_max: 0.25,
            max_steps: 1500,
            tol: 1e-10,
            locate_tol: 1e-8,
            scaled: self.shape,
            scale: s.radius / (self.shape as f64).sqrt(),
            folds: FoldPolicy::Follow,
            detect_branch_points: true,
            index_tolerance: INDEX_TOLERANCE,
            track_index: true,
            hermite_location: false,
            progress_every: usize::MAX,
            far_limit: Some(self.cont.p_of(far)),
            circles: Vec::new(),
            circle_distance: 0.0,
        }
    }

    /// Every family of the branch: seeds at each of [`seed_values`] (the scene's value
    /// first), each seed not on a family already traced marched into a family.
    pub(super) fn trace(mut self) -> Result<Self, DiagramError> {
        let (s, branch) = (self.ctx.s, self.ctx.branch);
        let eta = eta_of_branch(branch);
        for (vi, &v) in seed_values(s.param, self.scene_value, s.target)
            .iter()
            .enumerate()
        {
            let at_v = self.ctx.model.with_param(s.param, v)?;
            let (found, why) = seeds(&at_v, eta, &s.solve);
            if found.is_empty() && vi == 0 {
                self.warnings.push(format!(
                    "branch {branch} (eta = {eta}): no state found at L̄ = {} and {} = {v} ({})",
                    s.lbar,
                    s.param,
                    why.join("; ")
                ));
            }
            for (e0, x0) in &found {
                self.seed_family(vi, v, &at_v, *e0, x0)?;
            }
        }
        Ok(self)
    }

    /// The family of the seed `(e0, x0)` found at the `vi`-th seed value `v` (`at_v` the
    /// model there), unless it lies on a traced family or is not resolved; then the
    /// families switched onto at its branch points.
    fn seed_family(
        &mut self,
        vi: usize,
        v: f64,
        at_v: &M,
        e0: f64,
        x0: &[f64],
    ) -> Result<(), DiagramError> {
        let (s, branch, model) = (self.ctx.s, self.ctx.branch, self.ctx.model);
        if vi > 0 && traced(model, s.param, &self.known, v, e0, &s.solve) {
            return Ok(());
        }
        // A seed whose energy changes by more than 1e-4 (relative) at half the
        // resolution is not a resolved state.
        let seed_energy = match energy_with_estimate(model, s.param, x0, v, &s.solve) {
            Ok((e, est)) if est <= 1e-4 * e.abs() => (e, est),
            Ok((e, est)) => {
                self.warnings.push(format!(
                    "branch {branch}: a seed at {} = {v}, E = {e:.8} changes by {:.1e} at half the resolution: not a resolved state, left out",
                    s.param,
                    15.0 * est
                ));
                return Ok(());
            }
            Err(err) => {
                self.warnings.push(format!(
                    "branch {branch}: a seed at {} = {v}, E = {e0:.8} has no companion at half the resolution ({err}): left out",
                    s.param
                ));
                return Ok(());
            }
        };
        self.family += 1;
        let family = self.family;
        let seed = SweepPoint {
            value: v,
            energy: seed_energy.0,
            index: at_v.index(x0, INDEX_TOLERANCE)?,
            label: Label::Unstable,
            arc: 0,
            state: x0.to_vec(),
        };
        let marches = self.march_both_ways(family, v, x0);
        let mut fam: Option<SweepFamily> = None;
        for (k, (_, m)) in marches.iter().enumerate() {
            let f = self.ctx.family(
                family,
                (k == 0).then(|| seed.clone()),
                Some((v, seed_energy.0, seed_energy.1)),
                m,
                &mut self.special,
                &mut self.warnings,
            )?;
            fam = Some(match fam {
                None => f,
                // The backward march joins in front, reversed.
                Some(mut first) => {
                    let mut pts: Vec<SweepPoint> = f.points.into_iter().rev().collect();
                    pts.append(&mut first.points);
                    for (i, p) in pts.iter_mut().enumerate() {
                        p.arc = i;
                    }
                    first.points = pts;
                    first
                }
            });
        }
        let Some(mut fam) = fam else { return Ok(()) };
        if vi > 0 {
            fam.notes.push(format!(
                "seeded at {} = {v} (not connected to a state at the scene's value along the traced families)",
                s.param
            ));
        }
        for (raw, _) in &marches {
            for bp in raw.branch_points() {
                self.switch_at(bp, &mut fam)?;
            }
        }
        self.families.push(fam);
        Ok(())
    }

    /// The marches of family `family` from its seed `x0` at `v`: towards the target, and
    /// (seeds inside the range) back towards the scene; each as marched and in `θ`.
    fn march_both_ways(&mut self, family: usize, v: f64, x0: &[f64]) -> Vec<(March, March)> {
        let (s, branch) = (self.ctx.s, self.ctx.branch);
        let mut marches = Vec::new();
        for (limit, far) in [(s.target, self.scene_value), (self.scene_value, s.target)] {
            if limit == v {
                continue;
            }
            match march(
                &self.problem,
                x0,
                self.cont.p_of(v),
                &self.toward(limit, far),
                &mut |_, _| {},
            ) {
                Ok(raw) => {
                    let m = self.cont.in_theta(&raw);
                    let mut run = vec![(v, x0.to_vec())];
                    run.extend(m.points.iter().map(|p| (p.value, p.x.clone())));
                    self.known.push(run);
                    marches.push((raw, m))
                }
                Err(e) => self
                    .warnings
                    .push(format!("branch {branch} family {family}: {e}")),
            }
        }
        marches
    }

    /// The secondary families switched onto at the branch point `bp` of `fam` (both
    /// directions; a mirror pair of the first is noted on `fam` and traced once).
    fn switch_at(&mut self, bp: &MarchSpecial, fam: &mut SweepFamily) -> Result<(), DiagramError> {
        let (s, branch, model) = (self.ctx.s, self.ctx.branch, self.ctx.model);
        let bp_value = self.cont.theta(bp.value);
        let settings = self.toward(s.target, self.scene_value);
        let mut last_energies: Option<Vec<f64>> = None;
        for dir in [Direction::Forward, Direction::Backward] {
            let sw_raw = match march_switch(
                &self.problem,
                bp,
                dir,
                &settings,
                &|_, _| false,
                &mut |_, _| {},
            ) {
                Ok(sw) => sw,
                Err(e) => {
                    self.warnings.push(format!(
                        "branch {branch} family {}: switching at the branch point {} = {bp_value:.8}: {e}",
                        fam.family, s.param
                    ));
                    continue;
                }
            };
            let sw = self.cont.in_theta(&sw_raw);
            let energies: Vec<f64> = sw
                .points
                .iter()
                .filter_map(|p| {
                    model
                        .with_param(s.param, p.value)
                        .ok()
                        .and_then(|m| Confinement::energy(&m, &p.x).ok())
                })
                .collect();
            if let Some(prev) = &last_energies {
                if prev.len() == energies.len()
                    && prev
                        .iter()
                        .zip(&energies)
                        .all(|(a, b)| (a - b).abs() < SAME_STATE)
                {
                    fam.notes.push(format!(
                        "the branch point at {} = {bp_value:.8} has a mirror pair of secondary families (multiplicity 2, one traced)",
                        s.param
                    ));
                    continue;
                }
            }
            last_energies = Some(energies);
            self.known
                .push(sw.points.iter().map(|p| (p.value, p.x.clone())).collect());
            self.family += 1;
            let mut f = self.ctx.family(
                self.family,
                None,
                None,
                &sw,
                &mut self.special,
                &mut self.warnings,
            )?;
            f.notes.push(format!(
                "switched from family {} at its branch point {} = {bp_value:.8}",
                fam.family, s.param
            ));
            self.families.push(f);
        }
        Ok(())
    }
}
