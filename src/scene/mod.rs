//! Scenes and protocols: the JSON scene, its validation, builders and the
//! stage runner of the native engine.

pub mod builders;
pub mod load;
pub mod model;
pub mod protocols;
pub mod run;
pub mod validate;

pub use load::{build_system, read_scene, write_scene};
pub use model::{Bonds, BoxSpec, ForceField, Particles, Record, Scene, StageSpec, VelocityInit};
pub use run::{run_scene, run_stage, RunOptions, StageOutput};
pub use validate::{validate, SceneError};
