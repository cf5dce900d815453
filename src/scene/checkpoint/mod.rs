//! Checkpoints of a native run: everything needed to continue it, written
//! at an interval and when the run is stopped, so a run killed or
//! interrupted continues from its last checkpoint and ends bit for bit as
//! it would have without the interruption.
//!
//! A checkpoint holds the finished stages' records, the current stage's
//! records and its start (box and tether), the engine's whole state
//! ([`EngineState`]) and how far the streamed thermo and dump files had
//! got. It is written to a temporary file beside the target and renamed
//! over it, so a kill during the write leaves the previous checkpoint
//! whole. It is refused for another scene, another thread count (results
//! are bit-reproducible for a fixed count only), another format or
//! another version of this program.

mod args;
mod study;

pub use args::CheckpointArgs;
pub use study::StudyCheckpoint;

use super::model::Scene;
use super::records::StageOutput;
use crate::engine::{ActiveTether, EngineState, SimBox};
use serde::{Deserialize, Serialize};
use std::borrow::Cow;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// The first bytes of every checkpoint file, before its header line
/// `format F version V`.
const MAGIC: &[u8] = b"bpm checkpoint ";

/// The layout of [`RunCheckpoint`]; raised whenever it changes.
pub const CHECKPOINT_FORMAT: u32 = 2;

/// Why a checkpoint could not be written, read or used.
#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    /// The file could not be written or read.
    #[error("checkpoint {path}: {cause}")]
    Io {
        /// The checkpoint file.
        path: PathBuf,
        /// The cause.
        cause: std::io::Error,
    },
    /// The file is not a checkpoint of this program, or is damaged.
    #[error("checkpoint {path} cannot be read: {reason}")]
    Malformed {
        /// The checkpoint file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// The checkpoint belongs to another run.
    #[error("checkpoint {path} does not belong to this run: {reason}")]
    Refused {
        /// The checkpoint file.
        path: PathBuf,
        /// What differs.
        reason: String,
    },
}

/// When checkpoints are written.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CheckpointEvery {
    /// Whenever the global step count is a multiple of this.
    Steps(u64),
    /// Whenever this much wall-clock time has passed since the last one.
    Wall(Duration),
}

impl FromStr for CheckpointEvery {
    type Err = String;

    /// A number of steps (`20000`) or a time with its unit: `90s`, `10m`,
    /// `2h`.
    fn from_str(s: &str) -> Result<Self, String> {
        let s = s.trim();
        let bad = || {
            format!(
                "`{s}` is neither a number of steps (20000) nor a time with a unit (90s, 10m, 2h)"
            )
        };
        let (number, unit) = match s.find(|c: char| !c.is_ascii_digit() && c != '.') {
            Some(at) => s.split_at(at),
            None => {
                let steps: u64 = s.parse().map_err(|_| bad())?;
                if steps == 0 {
                    return Err("a checkpoint every 0 steps: give at least 1".into());
                }
                return Ok(Self::Steps(steps));
            }
        };
        let value: f64 = number.parse().map_err(|_| bad())?;
        let seconds = match unit {
            "s" => value,
            "m" | "min" => value * 60.0,
            "h" => value * 3600.0,
            _ => return Err(bad()),
        };
        if !(seconds.is_finite() && seconds > 0.0) {
            return Err(format!("`{s}`: the interval must be positive"));
        }
        Ok(Self::Wall(Duration::from_secs_f64(seconds)))
    }
}

/// Where a run's checkpoints go.
#[derive(Clone, Debug)]
pub enum CheckpointTarget {
    /// A file of the run's own.
    File(PathBuf),
    /// A part of a study's checkpoint, under this key: the study's file
    /// holds it beside the study's finished parts.
    Part(StudyCheckpoint, String),
}

impl CheckpointTarget {
    /// The file written.
    pub fn path(&self) -> PathBuf {
        match self {
            Self::File(path) => path.clone(),
            Self::Part(study, _) => study.path(),
        }
    }
}

/// Checkpointing of one run.
#[derive(Clone, Debug)]
pub struct CheckpointOptions {
    /// Where the checkpoints go.
    pub target: CheckpointTarget,
    /// When to write it (also when the run is stopped, and at its end).
    pub every: CheckpointEvery,
    /// Continue from the file instead of starting afresh.
    pub resume: bool,
    /// Set (by a signal handler) to stop the run at the next step, after
    /// writing a checkpoint.
    pub stop: Arc<AtomicBool>,
    /// Stop after this global step, as if asked to: a run split into
    /// pieces of known length (and the tests' interruptions).
    pub stop_at_step: Option<u64>,
}

impl CheckpointOptions {
    /// Checkpoints to `path` at `every`; `resume` to continue from it.
    pub fn new(path: PathBuf, every: CheckpointEvery, resume: bool) -> Self {
        Self {
            target: CheckpointTarget::File(path),
            every,
            resume,
            stop: Arc::new(AtomicBool::new(false)),
            stop_at_step: None,
        }
    }

    /// The checkpoint to continue from: for a file of its own, the file
    /// (an error if it is missing); for a part of a study, the part's run
    /// if the study's checkpoint has one (`None`: the run starts afresh).
    pub fn saved_run(
        &self,
        scene: &Scene,
        threads: usize,
    ) -> Result<Option<RunCheckpoint<'static>>, CheckpointError> {
        let saved = match &self.target {
            CheckpointTarget::File(path) => RunCheckpoint::read(path, scene, threads)?,
            CheckpointTarget::Part(study, key) => match study.take_run(key) {
                Some(saved) => saved,
                None => return Ok(None),
            },
        };
        saved.check(&self.target.path(), scene, threads)?;
        Ok(Some(saved))
    }

    /// Whether the run should stop after global step `step`.
    pub fn stop_requested(&self, step: u64) -> bool {
        self.stop_at_step == Some(step) || self.stop.load(Ordering::Relaxed)
    }
}

/// How far a streamed file had got at the checkpoint.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StreamedFile {
    /// The file.
    pub path: PathBuf,
    /// Its length (bytes).
    pub length: u64,
    /// For a dump: the global step of its last frame.
    pub last_step: Option<u64>,
}

/// Where the current stage stood.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct StageProgress<'a> {
    /// The stage's index in the scene.
    pub index: usize,
    /// Steps of the stage done.
    pub step: u64,
    /// The box at the stage's start (deformations are relative to it).
    pub stage_box: Cow<'a, SimBox>,
    /// The stage's tether, resolved at its start.
    pub tether: Cow<'a, Option<ActiveTether>>,
    /// What the stage recorded so far, with its wall time, timers and
    /// list builds up to here.
    pub output: Cow<'a, StageOutput>,
}

/// Everything needed to continue a native run.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RunCheckpoint<'a> {
    /// The scene's identity ([`scene_identity`]).
    pub scene: String,
    /// Threads of the force passes.
    pub threads: usize,
    /// Stages finished, in order.
    pub finished: Cow<'a, [StageOutput]>,
    /// The stage under way, or `None` when the next one starts afresh (or
    /// every stage has finished).
    pub current: Option<StageProgress<'a>>,
    /// The engine between two steps.
    pub engine: EngineState,
    /// The thermo file, if rows are streamed.
    pub thermo: Option<StreamedFile>,
    /// The dump file, if any.
    pub dump: Option<StreamedFile>,
    /// Wall-clock seconds of the run so far, over every session.
    pub wall_seconds: f64,
    /// The global steps at which earlier sessions resumed the run.
    pub resumed_at: Vec<u64>,
}

/// A scene's identity in checkpoints: FNV-1a of its canonical JSON, so
/// the same scene matches however its file was formatted.
pub fn scene_identity(scene: &Scene) -> String {
    let text = serde_json::to_vec(scene).unwrap_or_default();
    format!("{:016x}", super::load::fnv1a(&text))
}

impl RunCheckpoint<'_> {
    /// Writes the checkpoint to `path` through a temporary file renamed
    /// over it, synced to disk first: a kill at any moment leaves either
    /// the old checkpoint or the new one, whole.
    pub fn write(&self, path: &Path) -> Result<(), CheckpointError> {
        write_atomically(path, self)
    }

    /// Reads a checkpoint and checks that it continues a run of `scene` on
    /// `threads` threads by this version.
    pub fn read(
        path: &Path,
        scene: &Scene,
        threads: usize,
    ) -> Result<RunCheckpoint<'static>, CheckpointError> {
        let checkpoint: RunCheckpoint<'static> = read_checked(path)?;
        checkpoint.check(path, scene, threads)?;
        Ok(checkpoint)
    }

    /// Whether the checkpoint continues a run of `scene` on `threads`
    /// threads (`path` names it in the error).
    fn check(&self, path: &Path, scene: &Scene, threads: usize) -> Result<(), CheckpointError> {
        let refused = |reason: String| CheckpointError::Refused {
            path: path.to_path_buf(),
            reason,
        };
        let identity = scene_identity(scene);
        if self.scene != identity {
            return Err(refused(format!(
                "it was written for another scene (identity {}, this scene's is {identity})",
                self.scene
            )));
        }
        if self.threads != threads {
            return Err(refused(other_threads(self.threads)));
        }
        Ok(())
    }
}

/// Why a checkpoint written with `--threads saved` is refused for another
/// count.
fn other_threads(saved: usize) -> String {
    format!(
        "it was written with --threads {saved}; resume with --threads {saved} (results are bit-reproducible for a fixed thread count only)"
    )
}

/// Writes `value` as a checkpoint file at `path`, through a temporary
/// file synced to disk and renamed over it: a kill at any moment leaves
/// either the old file or the new one, whole.
fn write_atomically<T: Serialize>(path: &Path, value: &T) -> Result<(), CheckpointError> {
    let io = |cause| CheckpointError::Io {
        path: path.to_path_buf(),
        cause,
    };
    let mut name = path.file_name().unwrap_or_default().to_os_string();
    name.push(".partial");
    let partial = path.with_file_name(name);
    let file = std::fs::File::create(&partial).map_err(io)?;
    let mut out = std::io::BufWriter::new(file);
    out.write_all(MAGIC)
        .and_then(|_| writeln!(out, "format {CHECKPOINT_FORMAT} version {}", crate::VERSION))
        .map_err(io)?;
    ciborium::into_writer(value, &mut out).map_err(|e| CheckpointError::Io {
        path: path.to_path_buf(),
        cause: std::io::Error::other(e.to_string()),
    })?;
    let file = out.into_inner().map_err(|e| io(e.into_error()))?;
    file.sync_all().map_err(io)?;
    drop(file);
    std::fs::rename(&partial, path).map_err(io)
}

/// Reads a checkpoint file of this format and version.
fn read_checked<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T, CheckpointError> {
    let bytes = std::fs::read(path).map_err(|cause| CheckpointError::Io {
        path: path.to_path_buf(),
        cause,
    })?;
    let malformed = |reason: String| CheckpointError::Malformed {
        path: path.to_path_buf(),
        reason,
    };
    let not_ours = || malformed("it is not a bpm checkpoint file".into());
    let rest = bytes.strip_prefix(MAGIC).ok_or_else(not_ours)?;
    // The header line names the format and version, so a checkpoint of
    // another layout is refused by name, before its body is decoded.
    let end = rest.iter().position(|&b| b == b'\n').ok_or_else(not_ours)?;
    let (header, body) = (String::from_utf8_lossy(&rest[..end]), &rest[end + 1..]);
    let ours = format!("format {CHECKPOINT_FORMAT} version {}", crate::VERSION);
    if header != ours {
        let words: Vec<&str> = header.split(' ').collect();
        let (format, version) = match words[..] {
            ["format", f, "version", v] => (f, v),
            _ => return Err(not_ours()),
        };
        return Err(CheckpointError::Refused {
            path: path.to_path_buf(),
            reason: format!(
                "it was written by bpm {version} (checkpoint format {format}); this is bpm {} (format {CHECKPOINT_FORMAT}): rerun from the start with this version",
                crate::VERSION
            ),
        });
    }
    ciborium::from_reader(body).map_err(|e| malformed(format!("damaged or truncated ({e})")))
}

/// Decides when to write checkpoints and writes them.
#[derive(Debug)]
pub struct Checkpointer {
    options: CheckpointOptions,
    scene: String,
    threads: usize,
    last_write: Instant,
    /// Wall-clock seconds of earlier sessions of the run.
    earlier_seconds: f64,
    session_start: Instant,
    resumed_at: Vec<u64>,
}

impl Checkpointer {
    /// Checkpointing of a run of `scene` on `threads` threads; a resumed
    /// run passes what its checkpoint had of earlier sessions.
    pub fn new(
        options: CheckpointOptions,
        scene: &Scene,
        threads: usize,
        earlier_seconds: f64,
        resumed_at: Vec<u64>,
    ) -> Self {
        let now = Instant::now();
        Self {
            options,
            scene: scene_identity(scene),
            threads,
            last_write: now,
            earlier_seconds,
            session_start: now,
            resumed_at,
        }
    }

    /// The options.
    pub fn options(&self) -> &CheckpointOptions {
        &self.options
    }

    /// Whether a checkpoint is due after global step `step`.
    pub fn due(&self, step: u64) -> bool {
        match self.options.every {
            CheckpointEvery::Steps(every) => step % every == 0,
            CheckpointEvery::Wall(every) => self.last_write.elapsed() >= every,
        }
    }

    /// Wall-clock seconds of the run so far, over every session.
    pub fn wall_seconds(&self) -> f64 {
        self.earlier_seconds + self.session_start.elapsed().as_secs_f64()
    }

    /// Writes a checkpoint of these parts.
    pub fn write(
        &mut self,
        finished: &[StageOutput],
        current: Option<StageProgress<'_>>,
        engine: EngineState,
        thermo: Option<StreamedFile>,
        dump: Option<StreamedFile>,
    ) -> Result<(), CheckpointError> {
        let checkpoint = RunCheckpoint {
            scene: self.scene.clone(),
            threads: self.threads,
            finished: Cow::Borrowed(finished),
            current,
            engine,
            thermo,
            dump,
            wall_seconds: self.wall_seconds(),
            resumed_at: self.resumed_at.clone(),
        };
        match &self.options.target {
            CheckpointTarget::File(path) => checkpoint.write(path)?,
            CheckpointTarget::Part(study, key) => study.write_run(key, &checkpoint)?,
        }
        self.last_write = Instant::now();
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn intervals_parse_as_steps_or_times() {
        assert_eq!("20000".parse(), Ok(CheckpointEvery::Steps(20000)));
        assert_eq!(
            "10m".parse(),
            Ok(CheckpointEvery::Wall(Duration::from_secs(600)))
        );
        assert_eq!(
            "1.5h".parse(),
            Ok(CheckpointEvery::Wall(Duration::from_secs(5400)))
        );
        assert_eq!(
            "90s".parse(),
            Ok(CheckpointEvery::Wall(Duration::from_secs(90)))
        );
        for bad in ["0", "10 parsecs", "m", "-5m", "0s", ""] {
            assert!(bad.parse::<CheckpointEvery>().is_err(), "{bad}");
        }
    }
}
