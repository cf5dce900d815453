//! Builders that make scenes from a few parameters and a seed.

pub mod bulk;
pub mod grain;
pub mod packing;
pub mod replicate;
pub mod spheres;

use crate::engine::System;
use crate::scene::load::build_system;
use crate::scene::model::Scene;
use crate::scene::run::{run_scene, RunOptions};
use crate::scene::validate::{validate, SceneError};

/// A scene of model `bpm` in the periodic cube `[0, length)^3`: unit
/// masses, no velocities, grains, bonds or stages; builders fill in the
/// rest (and change the model).
pub(crate) fn periodic_cube(
    description: String,
    seed: u64,
    length: f64,
    positions: Vec<[f64; 3]>,
    force_field: crate::scene::ForceField,
) -> Scene {
    Scene {
        version: crate::scene::SCENE_VERSION,
        model: crate::scene::ModelKind::Bpm,
        description,
        seed,
        simbox: crate::scene::model::BoxSpec {
            lo: [0.0; 3],
            lengths: [length; 3],
            tilt: [0.0; 3],
            periodic: [true; 3],
        },
        particles: crate::scene::model::Particles {
            positions,
            velocities: None,
            angular_velocities: None,
            grain: None,
            mass: crate::scene::Mass::Uniform(1.0),
            radius: None,
            kind: None,
            ids: None,
        },
        bonds: crate::scene::model::Bonds::default(),
        force_field,
        stages: Vec::new(),
        provenance: serde_json::Value::Null,
    }
}

/// Runs the stages of a builder's working scene and returns the final
/// system; a failure is reported as an error of the builder `what`.
fn run_build_stages(
    scene: &Scene,
    what: &str,
    threads: usize,
    progress: bool,
) -> Result<System, SceneError> {
    validate(scene)?;
    let mut sys = build_system(scene, threads);
    let opts = RunOptions {
        progress: crate::progress::Progress::bars(progress),
        ..RunOptions::quiet(threads)
    };
    match run_scene(&mut sys, scene, &opts) {
        (_, Some(e)) => Err(SceneError::Invalid {
            field: what.into(),
            reason: e.to_string(),
        }),
        (_, None) => Ok(sys),
    }
}
