//! Builders that make scenes from a few parameters and a seed.

pub mod bulk;
pub mod grain;
pub mod packing;
pub mod replicate;

use crate::engine::System;
use crate::scene::load::build_system;
use crate::scene::model::Scene;
use crate::scene::run::{run_scene, RunOptions};
use crate::scene::validate::{validate, SceneError};

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
        progress,
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
