//! The commands that read a scene (`diagram` with or without `--param`, `report`, `solve`,
//! `compare --scene`, `converge`, `phase`), dispatched once: [`load`] turns the scene's engine
//! kind (`crate::engine`) into a [`SceneEngine`], and the entry points here call its method
//! for the command. `main` calls these entry points; the commands themselves never ask which
//! engine they run on, and nothing below imports this module back. `converge`, `phase` and
//! `diagram --param` are built on the surface model's O(N) factorisation and its diagram: the
//! enclosed engine answers them with [`surface_only`].

use std::path::Path;
use std::time::Instant;

use anyhow::{anyhow, bail, Result};
use rodloop_scene::Scene;

use crate::engine::EngineKind;

/// What each command does with a scene of one engine.
trait SceneEngine {
    /// `rodloop diagram` in `L̄`.
    fn diagram(&self, args: &crate::diagram::Args, scene: &Scene) -> Result<()>;
    /// `rodloop report` (`t_start`: when the command started, for its timing line).
    fn report(&self, args: &crate::report::Args, scene: &Scene, t_start: Instant) -> Result<()>;
    /// `rodloop solve`.
    fn solve(&self, args: &crate::solve::Args, scene: &Scene) -> Result<()>;
    /// `rodloop compare --scene <file>` (`out` the output directory).
    fn compare(&self, scene: &Scene, out: &Path) -> Result<()>;
    /// `rodloop diagram --param` (its arguments checked before the scene is read).
    fn diagram_param(
        &self,
        args: &crate::diagram::Args,
        checked: crate::diagram::param::Checked,
        scene: &Scene,
    ) -> Result<()>;
    /// `rodloop converge`.
    fn converge(&self, args: &crate::converge::Args, scene: &Scene) -> Result<()>;
    /// `rodloop phase` (`t_start`: when the command started, for its timing line).
    fn phase(&self, args: &crate::phase::Args, scene: &Scene, t_start: Instant) -> Result<()>;
}

/// Loops on the sphere.
struct Surface;

/// Loops in the ball.
struct Enclosed;

impl SceneEngine for Surface {
    fn diagram(&self, args: &crate::diagram::Args, scene: &Scene) -> Result<()> {
        crate::diagram::run_surface(args, scene)
    }
    fn report(&self, args: &crate::report::Args, scene: &Scene, t_start: Instant) -> Result<()> {
        crate::report::run_surface(args, scene, t_start)
    }
    fn solve(&self, args: &crate::solve::Args, scene: &Scene) -> Result<()> {
        crate::solve::run_surface(args, scene.clone())
    }
    fn compare(&self, scene: &Scene, out: &Path) -> Result<()> {
        // A two-segment rod on the sphere: the paper's statements of Sec. 5.
        if !scene.stiffness.is_uniform() {
            return crate::compare_segments::run(scene, out);
        }
        bail!(
            "compare --scene needs an enclosed scene (confinement = \"enclosed\"); {} is not",
            scene.name
        )
    }
    fn diagram_param(
        &self,
        args: &crate::diagram::Args,
        checked: crate::diagram::param::Checked,
        scene: &Scene,
    ) -> Result<()> {
        crate::diagram::param::run(args, checked, scene)
    }
    fn converge(&self, args: &crate::converge::Args, scene: &Scene) -> Result<()> {
        crate::converge::run(args, scene)
    }
    fn phase(&self, args: &crate::phase::Args, scene: &Scene, t_start: Instant) -> Result<()> {
        crate::phase::run(args, scene, t_start)
    }
}

impl SceneEngine for Enclosed {
    fn diagram(&self, args: &crate::diagram::Args, scene: &Scene) -> Result<()> {
        if args.relative {
            bail!("--relative applies to surface diagrams; draw an enclosed diagram's branches.csv with `rodloop draw --relative` instead");
        }
        crate::diagram::enclosed::run(args, scene)
    }
    fn report(&self, args: &crate::report::Args, scene: &Scene, _t_start: Instant) -> Result<()> {
        crate::report::run_enclosed(args, scene)
    }
    fn solve(&self, args: &crate::solve::Args, scene: &Scene) -> Result<()> {
        crate::enclosed::run_solve(args, scene)
    }
    fn compare(&self, scene: &Scene, out: &Path) -> Result<()> {
        crate::enclosed::run_compare(scene, out)
    }
    fn diagram_param(
        &self,
        _args: &crate::diagram::Args,
        _checked: crate::diagram::param::Checked,
        scene: &Scene,
    ) -> Result<()> {
        Err(surface_only(scene))
    }
    fn converge(&self, args: &crate::converge::Args, scene: &Scene) -> Result<()> {
        crate::converge_enclosed::run(args, scene)
    }
    fn phase(&self, _args: &crate::phase::Args, scene: &Scene, _t_start: Instant) -> Result<()> {
        Err(surface_only(scene))
    }
}

/// The one-line error of a command that runs the surface model only, on an enclosed scene.
fn surface_only(scene: &Scene) -> anyhow::Error {
    anyhow!(
        "scene {}: confinement = \"enclosed\" is handled by `rodloop solve`, `rodloop diagram`, `rodloop report`, `rodloop converge` and `rodloop compare --scene enclosed`; this command runs the surface model only (its continuation in the stiffness follows the surface diagram's exchanges; the enclosed model has its own diagram). See the README, Enclosed loops",
        scene.name
    )
}

/// The engine of a kind: the one place the commands branch on the model.
fn of_kind(kind: EngineKind) -> &'static dyn SceneEngine {
    match kind {
        EngineKind::Surface => &Surface,
        EngineKind::Enclosed => &Enclosed,
    }
}

/// The scene of `--scene` (the default surface scene without one) and its engine.
fn load(path: Option<&Path>) -> Result<(Scene, &'static dyn SceneEngine)> {
    let (scene, kind) = crate::engine::load(path)?;
    Ok((scene, of_kind(kind)))
}

/// `rodloop diagram` on the scene's engine: `--param` (a sweep at a fixed length), else the
/// diagram in `L̄`.
pub fn diagram(args: &crate::diagram::Args) -> Result<()> {
    let param = crate::diagram::param_or_checked(args)?;
    let (scene, engine) = load(args.scene.as_deref())?;
    match param {
        Some(checked) => engine.diagram_param(args, checked, &scene),
        None => engine.diagram(args, &scene),
    }
}

/// `rodloop converge` on the scene's engine.
pub fn converge(args: &crate::converge::Args) -> Result<()> {
    let (scene, engine) = load(args.scene.as_deref())?;
    engine.converge(args, &scene)
}

/// `rodloop phase` on the scene's engine.
pub fn phase(args: &crate::phase::Args) -> Result<()> {
    let t_start = Instant::now();
    let (scene, engine) = load(Some(&args.scene))?;
    engine.phase(args, &scene, t_start)
}

/// `rodloop report` on the scene's engine.
pub fn report(args: &crate::report::Args) -> Result<()> {
    let t_start = Instant::now();
    let (scene, engine) = load(args.scene.as_deref())?;
    engine.report(args, &scene, t_start)
}

/// `rodloop solve` on the scene's engine.
pub fn solve(args: &crate::solve::Args) -> Result<()> {
    let (scene, engine) = load(args.scene.as_deref())?;
    engine.solve(args, &scene)
}

/// `rodloop compare`: a scene file on its engine, `enclosed` (the built-in homogeneous
/// enclosed scene), or without `--scene` the default scene against the exact layer and the
/// paper.
pub fn compare(args: &crate::compare::Args) -> Result<()> {
    match args.scene.as_deref() {
        Some("enclosed") => {
            crate::enclosed::run_compare(&crate::enclosed::builtin_enclosed()?, &args.out)
        }
        Some(s) => {
            let scene = Scene::from_file(Path::new(s))?;
            of_kind(crate::engine::kind_of(&scene)).compare(&scene, &args.out)
        }
        None => crate::compare::run(args),
    }
}
