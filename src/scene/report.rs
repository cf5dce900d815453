//! The report of a run: what `bpm run` writes for either engine and what
//! the cross-check harness reads back.

use super::model::{ForceField, Scene, StageSpec};
use super::records::StageOutput;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Which engine ran, with its own settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "engine", rename_all = "lowercase")]
pub enum EngineInfo {
    /// The native Rust engine.
    Native {
        /// Threads of the force passes.
        threads: usize,
    },
    /// LAMMPS with this project's styles.
    Lammps {
        /// LAMMPS's version date as the instance reports it (e.g. 20210929).
        lammps_version: i32,
        /// The same, readable, with what was loaded into it.
        lammps: String,
        /// MPI ranks.
        mpi_ranks: i32,
        /// LAMMPS's `newton` setting.
        newton: bool,
        /// The driver script, runnable by hand with `lmp-bpm -in`.
        driver: String,
    },
}

/// Everything a run produced, with what is needed to repeat it.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RunReport {
    /// `bpm run`.
    pub program: String,
    /// Version of this crate.
    pub version: String,
    /// The engine and its settings.
    #[serde(flatten)]
    pub engine: EngineInfo,
    /// The scene file.
    pub scene_file: String,
    /// 64-bit FNV-1a of the scene file (hex).
    pub scene_fnv1a: String,
    /// The scene's seed.
    pub seed: u64,
    /// Number of particles.
    pub particles: usize,
    /// Number of bonds.
    pub bonds: usize,
    /// The scene's initial force field.
    pub force_field: ForceField,
    /// The stages as the scene gives them.
    pub protocol: Vec<StageSpec>,
    /// How the scene was made.
    pub provenance: serde_json::Value,
    /// Wall-clock seconds of the whole run.
    pub wall_seconds: f64,
    /// Why the run stopped early, if it did; finished stages are kept.
    pub error: Option<String>,
    /// Files the run streamed to (thermo rows, trajectory).
    #[serde(default)]
    pub files: Vec<String>,
    /// The global steps at which the run was resumed from a checkpoint.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub resumed_at: Vec<u64>,
    /// Observables per finished stage.
    pub stages: Vec<StageOutput>,
}

impl RunReport {
    /// The report of a run of `scene` (read from `path`, hash `hash`).
    pub fn new(engine: EngineInfo, path: &Path, hash: u64, scene: &Scene) -> Self {
        Self {
            program: "bpm run".into(),
            version: crate::VERSION.into(),
            engine,
            scene_file: path.display().to_string(),
            scene_fnv1a: format!("{hash:016x}"),
            seed: scene.seed,
            particles: scene.particles.positions.len(),
            bonds: scene.bonds.pairs.len(),
            force_field: scene.force_field.clone(),
            protocol: scene.stages.clone(),
            provenance: scene.provenance.clone(),
            wall_seconds: 0.0,
            error: None,
            files: Vec::new(),
            resumed_at: Vec::new(),
            stages: Vec::new(),
        }
    }

    /// Writes the report as JSON.
    pub fn write(&self, path: &Path) -> Result<(), super::SceneError> {
        let text = serde_json::to_string(self)?;
        std::fs::write(path, text).map_err(|cause| super::SceneError::Io {
            path: path.display().to_string(),
            cause,
        })
    }

    /// Reads a report written by [`RunReport::write`].
    pub fn read(path: &Path) -> Result<Self, super::SceneError> {
        let bytes = std::fs::read(path).map_err(|cause| super::SceneError::Io {
            path: path.display().to_string(),
            cause,
        })?;
        Ok(serde_json::from_slice(&bytes)?)
    }
}

/// Runs `scene` (read from `path`, hash `hash`) on the native engine and
/// returns its report (with the error, if a stage failed, and every
/// finished stage) and the final system.
pub fn run_native_report(
    scene: &Scene,
    path: &Path,
    hash: u64,
    opts: &super::RunOptions,
) -> (RunReport, crate::engine::System) {
    let mut sys = super::build_system(scene, opts.threads);
    let outcome = super::run::run_scene_outcome(&mut sys, scene, opts);
    let mut report = RunReport::new(
        EngineInfo::Native {
            threads: opts.threads,
        },
        path,
        hash,
        scene,
    );
    report.wall_seconds = outcome.wall_seconds;
    report.error = outcome.error.map(|e| e.to_string());
    report.files = opts.files.paths();
    report.resumed_at = outcome.resumed_at;
    report.stages = outcome.stages;
    (report, sys)
}
