//! A study's checkpoint: the parts of a study already finished (a packing
//! built, a run's records, a measurement), each under a key, and the run
//! under way, in one file. A resumed study takes its finished parts from
//! the file instead of computing them again, and continues the run under
//! way from its last checkpoint.

use super::{
    other_threads, read_checked, write_atomically, CheckpointError, CheckpointEvery,
    CheckpointOptions, CheckpointTarget, RunCheckpoint,
};
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use std::borrow::Cow;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::sync::{Arc, Mutex, MutexGuard};

/// The checkpoint of one study, shared by the runs it makes.
#[derive(Clone, Debug)]
pub struct StudyCheckpoint {
    state: Arc<Mutex<State>>,
    every: CheckpointEvery,
    stop: Arc<AtomicBool>,
    stop_at_step: Arc<Mutex<Option<u64>>>,
}

#[derive(Debug)]
struct State {
    path: PathBuf,
    study: String,
    options: String,
    threads: usize,
    parts: BTreeMap<String, ciborium::Value>,
    /// The run under way when the file was read, by its part's key, until
    /// the run that continues it takes it.
    saved_run: Option<(String, RunCheckpoint<'static>)>,
}

/// The file's layout.
#[derive(Serialize, Deserialize)]
struct StudyFile<'a> {
    study: Cow<'a, str>,
    options: Cow<'a, str>,
    threads: usize,
    parts: Cow<'a, BTreeMap<String, ciborium::Value>>,
    run: Option<(Cow<'a, str>, Cow<'a, RunCheckpoint<'a>>)>,
}

impl StudyCheckpoint {
    /// The checkpoint of study `study` run with `options` on `threads`
    /// threads, written to `path` (runs at `every`): a new one, or with
    /// `resume` the one in the file, refused if it was written for
    /// another study, other options or another thread count.
    pub fn open(
        path: &Path,
        every: CheckpointEvery,
        resume: bool,
        study: &str,
        options: &impl Serialize,
        threads: usize,
    ) -> Result<Self, CheckpointError> {
        let options = serde_json::to_string(options).map_err(|e| CheckpointError::Io {
            path: path.to_path_buf(),
            cause: std::io::Error::other(e.to_string()),
        })?;
        let mut state = State {
            path: path.to_path_buf(),
            study: study.to_string(),
            options,
            threads,
            parts: BTreeMap::new(),
            saved_run: None,
        };
        if resume {
            let file: StudyFile<'static> = read_checked(path)?;
            let refused = |reason: String| CheckpointError::Refused {
                path: path.to_path_buf(),
                reason,
            };
            if file.study != state.study {
                return Err(refused(format!(
                    "it is a checkpoint of `bpm {}`, not of `bpm {study}`",
                    file.study
                )));
            }
            if file.options != state.options {
                return Err(refused(format!(
                    "it was written with other options: {}",
                    file.options
                )));
            }
            if file.threads != threads {
                return Err(refused(other_threads(file.threads)));
            }
            state.parts = file.parts.into_owned();
            state.saved_run = file
                .run
                .map(|(key, run)| (key.into_owned(), run.into_owned()));
        }
        Ok(Self {
            state: Arc::new(Mutex::new(state)),
            every,
            stop: Arc::new(AtomicBool::new(false)),
            stop_at_step: Arc::new(Mutex::new(None)),
        })
    }

    fn lock(&self) -> MutexGuard<'_, State> {
        // A panic while holding the lock leaves the state as it was
        // before the write: still a valid checkpoint.
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The checkpoint file.
    pub fn path(&self) -> PathBuf {
        self.lock().path.clone()
    }

    /// The flag that stops the study's runs at their next step, after a
    /// checkpoint (set it from a signal handler).
    pub fn stop_flag(&self) -> Arc<AtomicBool> {
        self.stop.clone()
    }

    /// Makes the study's runs started from now on stop after global step
    /// `step` (as [`CheckpointOptions::stop_at_step`]): a study split into
    /// pieces of known length.
    pub fn stop_runs_at(&self, step: Option<u64>) {
        *self.stop_at_step.lock().unwrap_or_else(|e| e.into_inner()) = step;
    }

    /// Whether a stop was asked for.
    pub fn stop_requested(&self) -> bool {
        self.stop.load(std::sync::atomic::Ordering::Relaxed)
    }

    /// What the checkpoint holds: the keys of the finished parts, and the
    /// run under way (its part's key and global step), if any.
    pub fn summary(&self) -> (Vec<String>, Option<(String, u64)>) {
        let state = self.lock();
        let run = state
            .saved_run
            .as_ref()
            .map(|(key, run)| (key.clone(), run.engine.step));
        (state.parts.keys().cloned().collect(), run)
    }

    /// The finished part `key`, if the checkpoint has it.
    pub fn finished<T: DeserializeOwned>(&self, key: &str) -> Result<Option<T>, CheckpointError> {
        let state = self.lock();
        let Some(value) = state.parts.get(key) else {
            return Ok(None);
        };
        value
            .deserialized()
            .map(Some)
            .map_err(|e| CheckpointError::Malformed {
                path: state.path.clone(),
                reason: format!("its part `{key}` cannot be read: {e}"),
            })
    }

    /// Records part `key` as finished with `value` and writes the file
    /// (without a run under way). The parts under it (`key/...`), the
    /// steps it was made of, are dropped: a resumed study takes `value`
    /// and never asks for them, and a part's steps can be large (a
    /// measurement's relaxed state).
    pub fn finish<T: Serialize>(&self, key: &str, value: &T) -> Result<(), CheckpointError> {
        let mut state = self.lock();
        let value = ciborium::Value::serialized(value).map_err(|e| CheckpointError::Io {
            path: state.path.clone(),
            cause: std::io::Error::other(e.to_string()),
        })?;
        let beneath = format!("{key}/");
        state.parts.retain(|k, _| !k.starts_with(&beneath));
        state.parts.insert(key.to_string(), value);
        state.write(None)
    }

    /// Drops every part whose key `stale` names (written with the next
    /// write): the steps of a part that will not be finished, such as a
    /// measurement made by other options than the study now runs with.
    pub fn drop_parts(&self, stale: impl Fn(&str) -> bool) {
        self.lock().parts.retain(|k, _| !stale(k));
    }

    /// The checkpointing of the study's run `key`: into this file,
    /// continuing the run if the file holds it under that key.
    pub fn run_options(&self, key: &str) -> CheckpointOptions {
        CheckpointOptions {
            target: CheckpointTarget::Part(self.clone(), key.to_string()),
            every: self.every,
            resume: true,
            stop: self.stop.clone(),
            stop_at_step: *self.stop_at_step.lock().unwrap_or_else(|e| e.into_inner()),
        }
    }

    /// Takes the saved run of part `key`, if the file held one.
    pub(super) fn take_run(&self, key: &str) -> Option<RunCheckpoint<'static>> {
        let mut state = self.lock();
        match &state.saved_run {
            Some((saved, _)) if saved == key => state.saved_run.take().map(|(_, run)| run),
            _ => None,
        }
    }

    /// Writes the file with `run` as the run under way, part `key`.
    pub(super) fn write_run(
        &self,
        key: &str,
        run: &RunCheckpoint<'_>,
    ) -> Result<(), CheckpointError> {
        self.lock().write(Some((key, run)))
    }
}

impl State {
    fn write(&self, run: Option<(&str, &RunCheckpoint<'_>)>) -> Result<(), CheckpointError> {
        let file = StudyFile {
            study: Cow::Borrowed(&self.study),
            options: Cow::Borrowed(&self.options),
            threads: self.threads,
            parts: Cow::Borrowed(&self.parts),
            run: run.map(|(key, run)| (Cow::Borrowed(key), Cow::Borrowed(run))),
        };
        write_atomically(&self.path, &file)
    }
}
