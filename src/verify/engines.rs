//! One scene through either engine, with the same output type.
//!
//! LAMMPS runs in a child process (`bpm run --engine lammps`, optionally
//! under `mpirun`): Debian's LAMMPS ends its process on any error, and the
//! harness must turn that into an error value with LAMMPS's message.

use super::launch::{LammpsChild, LaunchError, Work};
use crate::scene::run::{RunOptions, StageOutput};
use crate::scene::{run_native_report, validate, write_scene, EngineInfo, RunReport, Scene};
use std::ffi::OsStr;
use std::path::{Path, PathBuf};

/// A failure of a harness run.
#[derive(Debug, thiserror::Error)]
pub enum HarnessError {
    /// The native engine failed (e.g. a blow-up).
    #[error("native engine on `{scene}`: {message}")]
    Native {
        /// Scene tag.
        scene: String,
        /// The engine's error.
        message: String,
    },
    /// LAMMPS, or the harness around it, rejected the scene.
    #[error("LAMMPS on `{scene}` ({ranks} rank(s)) failed: {message}\n  (driver, data and log in {dir})")]
    Lammps {
        /// Scene tag.
        scene: String,
        /// MPI ranks.
        ranks: usize,
        /// LAMMPS's or the harness's message.
        message: String,
        /// Folder with the driver script and log.
        dir: String,
    },
    /// The scene is invalid for both engines.
    #[error("scene `{scene}`: {cause}")]
    Scene {
        /// Scene tag.
        scene: String,
        /// The validation error (in the message, not chained).
        cause: crate::scene::SceneError,
    },
    /// A file could not be read or written.
    #[error("{0}")]
    Io(String),
}

/// Observables of one engine run and its wall time.
#[derive(Clone, Debug)]
pub struct EngineRun {
    /// Per stage.
    pub stages: Vec<StageOutput>,
    /// Wall-clock seconds, process start included for LAMMPS.
    pub seconds: f64,
    /// The LAMMPS that ran it, from the run's report (`None`: native).
    pub lammps_version: Option<crate::lammps::LammpsVersion>,
}

/// Runs `scene` on the native engine with `threads` threads.
pub fn run_native(scene: &Scene, tag: &str, threads: usize) -> Result<EngineRun, HarnessError> {
    validate(scene).map_err(|cause| HarnessError::Scene {
        scene: tag.into(),
        cause,
    })?;
    let (report, _) = run_native_report(scene, Path::new(tag), 0, &RunOptions::quiet(threads));
    if let Some(message) = report.error {
        return Err(HarnessError::Native {
            scene: tag.into(),
            message,
        });
    }
    Ok(EngineRun {
        stages: report.stages,
        seconds: report.wall_seconds,
        lammps_version: None,
    })
}

/// Runs scenes in LAMMPS: `bpm run --engine lammps` as a child process
/// ([`LammpsChild`], with its time-out policy), optionally under MPI.
#[derive(Clone, Debug)]
pub struct LammpsLauncher {
    /// The `bpm` executable (runs `bpm run --engine lammps`).
    pub bpm: PathBuf,
    /// Folder for scenes, drivers, data files and logs.
    pub dir: PathBuf,
}

impl LammpsLauncher {
    /// A launcher for an example program (`target/<profile>/examples/`):
    /// the `bpm` built beside it, and a fresh folder `bpm-<name>-<pid>`
    /// in the temporary directory, which the caller removes.
    pub fn for_example(name: &str) -> std::io::Result<Self> {
        let exe = std::env::current_exe()?;
        let bpm = exe
            .parent()
            .and_then(|p| p.parent())
            .map(|p| p.join("bpm"))
            .ok_or_else(|| {
                std::io::Error::other("cannot locate the bpm binary beside the example")
            })?;
        let dir = std::env::temp_dir().join(format!("bpm-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&dir)?;
        Ok(Self { bpm, dir })
    }

    /// Runs `scene` (named `tag`) in LAMMPS on `ranks` MPI ranks, within
    /// the time limit of its particles and steps ([`Work::time_limit`]).
    pub fn run(
        &self,
        scene: &Scene,
        tag: &str,
        ranks: usize,
        newton: bool,
    ) -> Result<EngineRun, HarnessError> {
        let io = |e: String| HarnessError::Io(e);
        let work = self.dir.join(tag);
        std::fs::create_dir_all(&work).map_err(|e| io(format!("{}: {e}", work.display())))?;
        let scene_path = work.join("scene.json");
        write_scene(&scene_path, scene).map_err(|e| io(e.to_string()))?;
        let output = work.join("lammps.out.json");
        let _ = std::fs::remove_file(&output);
        let args: [&OsStr; 10] = [
            "run".as_ref(),
            "--engine".as_ref(),
            "lammps".as_ref(),
            "--newton".as_ref(),
            (if newton { "on" } else { "off" }).as_ref(),
            "--workdir".as_ref(),
            work.as_os_str(),
            scene_path.as_os_str(),
            "-o".as_ref(),
            output.as_os_str(),
        ];
        let fail = |message: String| HarnessError::Lammps {
            scene: tag.into(),
            ranks,
            message,
            dir: work.display().to_string(),
        };
        let start = std::time::Instant::now();
        LammpsChild::debian(&self.bpm)
            .run(
                &scene_path.display().to_string(),
                args,
                ranks,
                Work::of_scene(scene),
                Some(&work.join("scene.log")),
            )
            .map_err(|e| match e {
                LaunchError::Failed { message, .. } => fail(message),
                start @ LaunchError::Start { .. } => io(start.to_string()),
            })?;
        let seconds = start.elapsed().as_secs_f64();
        let report =
            RunReport::read(&output).map_err(|e| fail(format!("reading the run report: {e}")))?;
        let lammps_version = match report.engine {
            EngineInfo::Lammps { lammps_version, .. } => {
                Some(crate::lammps::LammpsVersion(lammps_version))
            }
            EngineInfo::Native { .. } => None,
        };
        Ok(EngineRun {
            stages: report.stages,
            seconds,
            lammps_version,
        })
    }
}
