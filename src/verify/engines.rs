//! One scene through either engine, with the same output type.
//!
//! LAMMPS runs in a child process (`bpm run --engine lammps`, optionally
//! under `mpirun`): Debian's LAMMPS ends its process on any error, and the
//! harness must turn that into an error value with LAMMPS's message.

use crate::scene::run::{run_scene, RunOptions, StageOutput};
use crate::scene::{build_system, validate, write_scene, EngineInfo, RunReport, Scene};
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
    let start = std::time::Instant::now();
    let mut sys = build_system(scene, threads);
    let (stages, error) = run_scene(&mut sys, scene, &RunOptions::quiet(threads));
    if let Some(e) = error {
        return Err(HarnessError::Native {
            scene: tag.into(),
            message: e.to_string(),
        });
    }
    Ok(EngineRun {
        stages,
        seconds: start.elapsed().as_secs_f64(),
        lammps_version: None,
    })
}

/// How to start LAMMPS runs.
#[derive(Clone, Debug)]
pub struct LammpsLauncher {
    /// The `bpm` executable (runs `bpm run --engine lammps`).
    pub bpm: PathBuf,
    /// Folder for scenes, drivers, data files and logs.
    pub dir: PathBuf,
    /// Wall-clock limit per run (s): a hung LAMMPS fails instead of stalling.
    pub limit_seconds: u32,
}

impl LammpsLauncher {
    /// Runs `scene` (named `tag`) in LAMMPS on `ranks` MPI ranks.
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
        let mut cmd = super::single_point::limited_launch(self.limit_seconds, ranks);
        cmd.arg(&self.bpm)
            .args(["run", "--engine", "lammps", "--newton"])
            .arg(if newton { "on" } else { "off" })
            .arg("--workdir")
            .arg(&work)
            .arg(&scene_path)
            .arg("-o")
            .arg(&output);
        let start = std::time::Instant::now();
        let out = cmd
            .output()
            .map_err(|e| io(format!("starting {}: {e}", self.bpm.display())))?;
        let seconds = start.elapsed().as_secs_f64();
        let fail = |message: String| HarnessError::Lammps {
            scene: tag.into(),
            ranks,
            message,
            dir: work.display().to_string(),
        };
        if !out.status.success() {
            return Err(fail(failure_message(
                &out,
                &work.join("scene.log"),
                self.limit_seconds,
            )));
        }
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

/// The best explanation of a failed child: LAMMPS's `ERROR` line from the
/// log, else the child's own `error:` line, else the exit status.
fn failure_message(out: &std::process::Output, log: &Path, limit: u32) -> String {
    if out.status.code() == Some(124) {
        return format!("no result within {limit} s (killed)");
    }
    let log_text = std::fs::read_to_string(log).unwrap_or_default();
    let streams = format!(
        "{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    for text in [&log_text, &streams] {
        if let Some(line) = text.lines().find(|l| l.starts_with("ERROR")) {
            return line.trim().to_string();
        }
    }
    if let Some(line) = streams.lines().find(|l| l.starts_with("error:")) {
        return line.trim_start_matches("error:").trim().to_string();
    }
    format!(
        "exit status {} without a message; output:\n{}",
        out.status,
        streams.trim()
    )
}
