//! The one place the CLI chooses the engine of a scene: the surface engine (any stiffness;
//! whether the rod has the shift symmetry of a uniform one is decided inside it), the enclosed
//! engine (`confinement = "enclosed"`), and the exact layer on request (`diagram --model
//! exact`, homogeneous surface scenes). Every command that runs a model asks [`kind_of`];
//! the enclosed engine and `solve` receive the scene's wall from [`wall_of`], the one place a
//! scene's [`WallSpec`] becomes the solver's [`Wall`].

use std::path::Path;
use std::sync::Arc;

use anyhow::Result;
use rodloop_scene::{Confinement, Scene, WallSpec};
use rodloop_solver::enclosed::{SphereWall, Wall};

/// The engine that answers a scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EngineKind {
    /// Loops on the sphere (`rodloop_diagram::SurfaceEngine`; `ExactEngine` on request).
    Surface,
    /// Loops in the ball (`rodloop_diagram::EnclosedEngine`).
    Enclosed,
}

/// The engine of `scene`.
pub fn kind_of(scene: &Scene) -> EngineKind {
    match scene.confinement {
        Confinement::Surface => EngineKind::Surface,
        Confinement::Enclosed => EngineKind::Enclosed,
    }
}

/// The scene of `--scene` (the default surface scene without one) and its engine.
pub fn load(path: Option<&Path>) -> Result<(Scene, EngineKind)> {
    let scene = match path {
        Some(p) => Scene::from_file(p)?,
        None => Scene::default(),
    };
    let kind = kind_of(&scene);
    Ok((scene, kind))
}

/// The wall of an enclosed scene (its `[wall]` table, in the scene's length units).
pub fn wall_of(scene: &Scene) -> Arc<dyn Wall> {
    match scene.wall {
        WallSpec::Sphere => Arc::new(SphereWall {
            radius: scene.radius,
        }),
    }
}
