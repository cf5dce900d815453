//! How a study runs, beside what it runs: threads, progress bars and log,
//! and the checkpoint that keeps its finished parts and its run under way;
//! and the command-line options that set them.

use crate::progress::{Progress, ProgressArgs};
use crate::scene::checkpoint::{CheckpointArgs, CheckpointError, StudyCheckpoint};
use anyhow::Context;

/// How a study runs, beside what it runs: threads, progress, and the
/// checkpoint that keeps its finished parts and its run under way.
#[derive(Clone, Debug, Default)]
pub struct StudyRuntime {
    /// Threads of the force passes.
    pub threads: usize,
    /// Progress bars and log.
    pub progress: Progress,
    /// The study's checkpoint, if it keeps one.
    pub checkpoint: Option<StudyCheckpoint>,
    /// Put before every key: a study run inside another keeps its parts
    /// apart ([`StudyRuntime::scoped`]).
    pub prefix: String,
}

impl StudyRuntime {
    /// `threads` threads, progress bars on a terminal when `bars`, no
    /// checkpoint.
    pub fn plain(threads: usize, bars: bool) -> Self {
        Self {
            threads,
            progress: Progress::bars(bars),
            checkpoint: None,
            prefix: String::new(),
        }
    }

    /// The same runtime, its keys under `scope/`: for a study run as a
    /// part of another (a compaction of each variant of a calibration).
    pub fn scoped(&self, scope: &str) -> Self {
        Self {
            prefix: format!("{}{scope}/", self.prefix),
            ..self.clone()
        }
    }

    /// `key` as the checkpoint files it: under this runtime's scope.
    pub fn key_in_checkpoint(&self, key: &str) -> String {
        format!("{}{key}", self.prefix)
    }

    /// Part `key` of the study: the value the checkpoint kept for it, or
    /// else `compute`'s, kept in the checkpoint (a computation that fails
    /// is not kept). A stop asked for (a signal) before a part starts
    /// ends the study with [`StudyStop::Interrupted`].
    pub fn part<T, E>(&self, key: &str, compute: impl FnOnce() -> Result<T, E>) -> Result<T, E>
    where
        T: serde::Serialize + serde::de::DeserializeOwned,
        E: From<StudyStop>,
    {
        let Some(checkpoint) = &self.checkpoint else {
            return compute();
        };
        let key = self.key_in_checkpoint(key);
        if let Some(value) = checkpoint.finished(&key).map_err(StudyStop::from)? {
            return Ok(value);
        }
        if checkpoint.stop_requested() {
            return Err(StudyStop::Interrupted(checkpoint.path()).into());
        }
        let value = compute()?;
        checkpoint.finish(&key, &value).map_err(StudyStop::from)?;
        Ok(value)
    }

    /// Runs `scene` natively as the study's run `key`, checkpointed into
    /// the study's checkpoint and continued from it. A stop asked for,
    /// or a checkpoint that cannot be written, ends the study; the run's
    /// own failures (a blow-up) are in the outcome, as without a
    /// checkpoint.
    pub fn run_scene(
        &self,
        key: &str,
        scene: &crate::scene::Scene,
    ) -> Result<crate::scene::run::RunOutcome, StudyStop> {
        let mut sys = crate::scene::build_system(scene, self.threads);
        self.run_system(key, &mut sys, scene)
    }

    /// [`StudyRuntime::run_scene`] on `sys`, a system of `scene` (in the
    /// state the run starts from, unless the checkpoint continues it),
    /// which is left in the run's final state.
    pub fn run_system(
        &self,
        key: &str,
        sys: &mut crate::engine::System,
        scene: &crate::scene::Scene,
    ) -> Result<crate::scene::run::RunOutcome, StudyStop> {
        use crate::scene::RunError;
        let mut outcome = crate::scene::run::run_scene_outcome(sys, scene, &self.run_options(key));
        match outcome.error.take() {
            Some(RunError::Interrupted { checkpoint, .. }) => {
                Err(StudyStop::Interrupted(checkpoint))
            }
            Some(RunError::Checkpoint(e)) => Err(StudyStop::Checkpoint(e)),
            error => {
                outcome.error = error;
                Ok(outcome)
            }
        }
    }

    /// The options of the study's native run `key`: checkpointed into the
    /// study's checkpoint (and continued from it) if there is one.
    pub fn run_options(&self, key: &str) -> crate::scene::RunOptions {
        crate::scene::RunOptions {
            threads: self.threads,
            progress: self.progress.clone(),
            files: Default::default(),
            checkpoint: self
                .checkpoint
                .as_ref()
                .map(|c| c.run_options(&self.key_in_checkpoint(key))),
        }
    }
}

/// Why a checkpointed study stopped before its end.
#[derive(Debug, thiserror::Error)]
pub enum StudyStop {
    /// Its checkpoint could not be written or read.
    #[error(transparent)]
    Checkpoint(#[from] CheckpointError),
    /// It was asked to stop (a signal) and its checkpoint holds its
    /// progress.
    #[error("stopped as asked; the checkpoint {} continues the study (the same command with --resume)", .0.display())]
    Interrupted(std::path::PathBuf),
}

/// The options every checkpointed study takes: `--checkpoint`,
/// `--checkpoint-every`, `--resume`, `--quiet` and `--progress-log`.
#[derive(Clone, Debug, clap::Args)]
pub struct RuntimeArgs {
    #[command(flatten)]
    checkpoint: CheckpointArgs,
    #[command(flatten)]
    progress: ProgressArgs,
}

impl RuntimeArgs {
    /// The runtime of study `study` (its command's name) with `options`
    /// on `threads` threads.
    pub fn runtime(
        &self,
        study: &str,
        options: &impl serde::Serialize,
        threads: usize,
    ) -> anyhow::Result<StudyRuntime> {
        Ok(StudyRuntime {
            threads,
            progress: self
                .progress
                .progress()
                .context("opening the progress log")?,
            checkpoint: self.checkpoint.study(study, options, threads)?,
            prefix: String::new(),
        })
    }
}
