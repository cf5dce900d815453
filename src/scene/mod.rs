//! Scenes and protocols: the JSON scene, its validation, builders, the
//! stage runner of the native engine, the recorded columns, trajectories
//! and the run report.

pub mod builders;
pub mod checkpoint;
pub mod cli;
pub mod datafile;
pub mod load;
pub mod model;
pub mod observables;
pub mod protocols;
pub mod records;
pub mod report;
pub mod rotation;
pub mod run;
pub mod trajectory;
pub mod validate;

pub use checkpoint::{CheckpointEvery, CheckpointOptions};
pub use load::{build_system, final_scene, read_scene, read_scene_unvalidated, write_scene};
pub use model::{
    Bonds, BoxSpec, ForceField, Mass, ModelKind, Particles, Record, Scene, StageSpec, VelocityInit,
    SCENE_VERSION,
};
pub use records::{Checkpoint, StageOutput};
pub use report::{run_native_report, EngineInfo, RunReport};
pub use run::{run_scene, run_stage, DumpOptions, OutputFiles, RunError, RunOptions};
pub use validate::{validate, SceneError};
