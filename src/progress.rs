//! Progress of long runs: a bar on the terminal (indicatif), and JSON lines
//! in a log file for batch jobs, where no terminal is watched.
//!
//! Each line of the log is one JSON object with `event` (`start`,
//! `progress` or `finish`), `task`, `done` and `total` (steps), `elapsed_s`
//! (of this task in this session), `rate_per_s`, `eta_s` and `unix_time`;
//! `progress` lines come at most every [`Progress::log_every`].

use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;
use std::io::{IsTerminal, LineWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

/// `--quiet` and `--progress-log`, as every long command takes them.
#[derive(Clone, Debug, Default, clap::Args)]
pub struct ProgressArgs {
    /// No progress bars (they are drawn only when stderr is a terminal).
    #[arg(long)]
    pub quiet: bool,
    /// Append progress as JSON lines to this file (for batch jobs): a line
    /// per stage start and finish, and one every 10 s.
    #[arg(long)]
    pub progress_log: Option<PathBuf>,
}

impl ProgressArgs {
    /// The progress these options ask for.
    pub fn progress(&self) -> std::io::Result<Progress> {
        Progress::new(self.quiet, self.progress_log.as_deref())
    }
}

/// Where progress goes: bars on stderr, a JSON-lines log, both or neither.
#[derive(Clone, Debug, Default)]
pub struct Progress {
    bars: bool,
    log: Option<Arc<Mutex<Log>>>,
    log_every: Duration,
}

#[derive(Debug)]
struct Log {
    path: PathBuf,
    out: LineWriter<std::fs::File>,
    /// The first write error, reported once: progress must not stop a run.
    failed: bool,
}

/// One line of the progress log.
#[derive(Serialize)]
struct LogLine<'a> {
    event: &'a str,
    task: &'a str,
    done: u64,
    total: u64,
    elapsed_s: f64,
    rate_per_s: Option<f64>,
    eta_s: Option<f64>,
    unix_time: f64,
}

impl Progress {
    /// No bars, no log.
    pub fn hidden() -> Self {
        Self::default()
    }

    /// Bars when `wanted` and stderr is a terminal; no log.
    pub fn bars(wanted: bool) -> Self {
        Self {
            bars: wanted && std::io::stderr().is_terminal(),
            ..Self::default()
        }
    }

    /// What a command's `--quiet` and `--progress-log` ask for: bars on a
    /// terminal unless `quiet`, and JSON lines appended to `log`.
    pub fn new(quiet: bool, log: Option<&Path>) -> std::io::Result<Self> {
        let log = match log {
            Some(path) => {
                let file = std::fs::OpenOptions::new()
                    .create(true)
                    .append(true)
                    .open(path)
                    .map_err(|e| {
                        std::io::Error::new(e.kind(), format!("{}: {e}", path.display()))
                    })?;
                Some(Arc::new(Mutex::new(Log {
                    path: path.to_path_buf(),
                    out: LineWriter::new(file),
                    failed: false,
                })))
            }
            None => None,
        };
        Ok(Self {
            bars: !quiet && std::io::stderr().is_terminal(),
            log,
            log_every: Duration::from_secs(10),
        })
    }

    /// The same, with `progress` log lines at most every `every`.
    pub fn log_every(mut self, every: Duration) -> Self {
        self.log_every = every;
        self
    }

    /// Whether bars are drawn.
    pub fn shows_bars(&self) -> bool {
        self.bars
    }

    /// A task of `total` steps, `done` of them already done (a resumed
    /// run); `bar` says whether it deserves a bar (short tasks do not).
    pub fn task(&self, name: &str, total: u64, done: u64, bar: bool) -> Task {
        let progress_bar = if self.bars && bar {
            let b = ProgressBar::new(total);
            b.set_style(
                ProgressStyle::with_template(
                    "{prefix:>12} [{bar:40}] {pos}/{len} steps {per_sec} eta {eta}",
                )
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> "),
            );
            b.set_prefix(name.to_string());
            b.set_position(done);
            b.reset_eta();
            b
        } else {
            ProgressBar::hidden()
        };
        let now = Instant::now();
        let task = Task {
            bar: progress_bar,
            log: self.log.clone(),
            log_every: self.log_every,
            name: name.to_string(),
            total,
            first: done,
            done,
            started: now,
            last_log: now,
        };
        task.write("start");
        task
    }
}

/// One task's bar and log lines.
#[derive(Debug)]
pub struct Task {
    bar: ProgressBar,
    log: Option<Arc<Mutex<Log>>>,
    log_every: Duration,
    name: String,
    total: u64,
    /// Steps done when this session's task started.
    first: u64,
    done: u64,
    started: Instant,
    last_log: Instant,
}

impl Task {
    /// `done` steps of the task are done.
    pub fn set(&mut self, done: u64) {
        self.done = done;
        self.bar.set_position(done);
        if self.log.is_some() && self.last_log.elapsed() >= self.log_every {
            self.last_log = Instant::now();
            self.write("progress");
        }
    }

    /// The task ended at `done` steps (all of them, unless it failed).
    pub fn finish(mut self, done: u64) {
        self.done = done;
        self.bar.finish_and_clear();
        self.write("finish");
    }

    fn write(&self, event: &str) {
        let Some(log) = &self.log else {
            return;
        };
        let elapsed = self.started.elapsed().as_secs_f64();
        let this_session = self.done.saturating_sub(self.first) as f64;
        let rate = (elapsed > 0.0 && this_session > 0.0).then(|| this_session / elapsed);
        let line = LogLine {
            event,
            task: &self.name,
            done: self.done,
            total: self.total,
            elapsed_s: elapsed,
            rate_per_s: rate,
            eta_s: rate.map(|r| self.total.saturating_sub(self.done) as f64 / r),
            unix_time: SystemTime::now()
                .duration_since(UNIX_EPOCH)
                .map_or(0.0, |d| d.as_secs_f64()),
        };
        let Ok(mut log) = log.lock() else {
            return;
        };
        let written = serde_json::to_string(&line)
            .map_err(std::io::Error::other)
            .and_then(|text| writeln!(log.out, "{text}"));
        if let (Err(e), false) = (written, log.failed) {
            log.failed = true;
            eprintln!(
                "warning: progress log {}: {e} (the run goes on without it)",
                log.path.display()
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_log_has_a_line_per_start_update_and_finish_with_rate_and_time_left() {
        let path = std::env::temp_dir().join(format!("bpm-progress-{}.jsonl", std::process::id()));
        let _ = std::fs::remove_file(&path);
        let progress = Progress::new(true, Some(&path))
            .unwrap()
            .log_every(Duration::ZERO);
        assert!(!progress.shows_bars());
        // A resumed task: 100 of 400 steps done before this session.
        let mut task = progress.task("stage", 400, 100, true);
        std::thread::sleep(Duration::from_millis(20));
        task.set(200);
        task.finish(400);
        let lines: Vec<serde_json::Value> = std::fs::read_to_string(&path)
            .unwrap()
            .lines()
            .map(|l| serde_json::from_str(l).unwrap())
            .collect();
        let events: Vec<(&str, u64)> = lines
            .iter()
            .map(|l| (l["event"].as_str().unwrap(), l["done"].as_u64().unwrap()))
            .collect();
        assert_eq!(events, [("start", 100), ("progress", 200), ("finish", 400)]);
        assert!(lines[0]["rate_per_s"].is_null(), "no rate before a step");
        // The rate counts this session's 100 steps only, and the time left
        // is the 200 steps to go at that rate.
        let rate = lines[1]["rate_per_s"].as_f64().unwrap();
        let elapsed = lines[1]["elapsed_s"].as_f64().unwrap();
        assert!(
            (rate * elapsed - 100.0).abs() < 1e-6 * 100.0,
            "{rate} {elapsed}"
        );
        let eta = lines[1]["eta_s"].as_f64().unwrap();
        assert!((eta * rate - 200.0).abs() < 1e-6 * 200.0, "{eta} {rate}");
        assert_eq!(lines[2]["eta_s"].as_f64(), Some(0.0));
        let _ = std::fs::remove_file(&path);
    }
}
