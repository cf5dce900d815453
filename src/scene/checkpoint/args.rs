//! The command-line options of checkpointing, shared by `bpm run` and the
//! studies, and the signal handling that stops a run cleanly.

use super::{CheckpointEvery, CheckpointOptions, StudyCheckpoint};
use anyhow::{Context, Result};
use serde::Serialize;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// `--checkpoint`, `--checkpoint-every` and `--resume`.
#[derive(Clone, Debug, clap::Args)]
pub struct CheckpointArgs {
    /// Write a checkpoint to this file every --checkpoint-every, when
    /// stopped (Ctrl-C, SIGTERM or SIGHUP) and at the end; with --resume,
    /// continue from it. A resumed run ends bit for bit as an
    /// uninterrupted one.
    #[arg(long)]
    pub checkpoint: Option<PathBuf>,
    /// How often to write the checkpoint: a number of steps (20000) or a
    /// wall-clock time (90s, 10m, 2h).
    #[arg(long, default_value = "10m", value_parser = parse_every)]
    pub checkpoint_every: CheckpointEvery,
    /// Continue from --checkpoint: the same scene or study options, thread
    /// count and output files as when it was written.
    #[arg(long, requires = "checkpoint")]
    pub resume: bool,
}

fn parse_every(text: &str) -> Result<CheckpointEvery, String> {
    text.parse()
}

impl CheckpointArgs {
    /// The checkpointing of one run, stopped cleanly by a signal.
    pub fn run(&self) -> Result<Option<CheckpointOptions>> {
        let Some(path) = &self.checkpoint else {
            return Ok(None);
        };
        let options = CheckpointOptions::new(path.clone(), self.checkpoint_every, self.resume);
        stop_on_signal(options.stop.clone())?;
        Ok(Some(options))
    }

    /// The checkpoint of study `study` run with `options` on `threads`
    /// threads, stopped cleanly by a signal.
    pub fn study(
        &self,
        study: &str,
        options: &impl Serialize,
        threads: usize,
    ) -> Result<Option<StudyCheckpoint>> {
        let Some(path) = &self.checkpoint else {
            return Ok(None);
        };
        let checkpoint = StudyCheckpoint::open(
            path,
            self.checkpoint_every,
            self.resume,
            study,
            options,
            threads,
        )?;
        stop_on_signal(checkpoint.stop_flag())?;
        if self.resume {
            let (parts, run) = checkpoint.summary();
            let run = run.map_or(String::new(), |(key, step)| {
                format!("; continuing `{key}` from step {step}")
            });
            eprintln!(
                "resuming from {}: {} part(s) finished{run}",
                path.display(),
                parts.len()
            );
        }
        Ok(Some(checkpoint))
    }
}

/// Makes Ctrl-C, SIGTERM and SIGHUP set `stop` (a run then stops at its
/// next step, after a checkpoint); a second signal ends the process at
/// once.
fn stop_on_signal(stop: Arc<AtomicBool>) -> Result<()> {
    ctrlc::set_handler(move || {
        if stop.swap(true, Ordering::SeqCst) {
            std::process::exit(130);
        }
        eprintln!(
            "\nstopping after the next step and writing the checkpoint (signal again to quit at once)"
        );
    })
    .context("installing the signal handler")
}
