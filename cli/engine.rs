//! The one place the CLI chooses the engine of a scene: the surface engine (any stiffness;
//! whether the rod has the shift symmetry of a uniform one is decided inside it), the enclosed
//! engine (`confinement = "enclosed"`), and the exact layer on request (`diagram --model
//! exact`, homogeneous surface scenes). Every command that runs a model asks [`kind_of`];
//! the enclosed engine and `solve` receive the scene's wall from [`wall_of`], the one place a
//! scene's [`WallSpec`] becomes the solver's [`Wall`]; [`exact_layer`] is the one place that
//! decides whether a scene's diagram has exact values beside it (a homogeneous rod on the
//! sphere).

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

/// The exact diagram of `[lbar_min, lbar_max]` in the schema (without shapes), the exact
/// values a numeric diagram of `scene` is shown beside: `None` unless the rod is homogeneous
/// (the exact layer's closed-form loops are those of a uniform rod on the sphere).
pub fn exact_layer(
    scene: &Scene,
    lbar_min: f64,
    lbar_max: f64,
) -> Result<Option<rodloop_schema::Diagram>> {
    if !scene.stiffness.is_uniform() {
        return Ok(None);
    }
    Ok(Some(rodloop_diagram::engine::exact_window_schema(
        lbar_min,
        lbar_max,
        0.01,
        &scene.name,
    )?))
}
