//! The LIGGGHTS case of `bpm bench`: LIGGGHTS's hydrogel tutorial bed (514
//! beads, SI units, dt 1e-5 s, gravity) under its closing lid, plain Hertz
//! and the standard closure (gamma 1.125), timed in LIGGGHTS and in the
//! native engine in the same run, when LIGGGHTS is installed (Debian
//! packages `liggghts` and `liggghts-doc`, for the lid's mesh).
//!
//! LIGGGHTS runs the committed decks of
//! `reference_data/liggghts/hydrogel_multicontact/` trimmed to the first
//! pass of the lid ([`trimmed_deck`]: the same physics, `run N`, no output
//! files); its time is the `Loop time` of its log (the run alone, one
//! serial process). The native engine runs the scene of the cross-check
//! (`verify::liggghts`: [`tutorial_options`] and [`lid_scene`]) cut to the
//! same steps; its time is the stage's wall time (the steps and the
//! stage's set-up force evaluation; building the scene is not timed).
//! The advanced closure, which LIGGGHTS lacks, is timed natively beside
//! native Hertz, the cost its goal is measured against.

use super::REPEATS;
use crate::engine::MultiContact;
use crate::file_error::FileError;
use crate::reference::multicontact::{ADVANCED_GAMMA, ADVANCED_MPR};
use crate::scene::protocols::lid::{lid_scene, LidError};
use crate::scene::{build_system, run_scene, RunOptions, Scene};
use crate::verify::liggghts::{tutorial_options, write_tutorial_bed, LiggghtsLaw};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Where Debian's `liggghts-doc` installs the tutorial's lid mesh.
pub const MESH: &str = "/usr/share/doc/liggghts/examples/LIGGGHTS/Tutorials_public/hydrogel_multicontact/meshes/piston_hydrogel.stl";

/// Steps of the lid's first pass: the most the case runs.
pub const PASS_STEPS: u64 = 30_000;

/// Steps between LIGGGHTS's thermo lines in the decks; the native run
/// records a row as often.
const THERMO_EVERY: u64 = 1000;

/// The tutorial's beads.
const PARTICLES: usize = 514;

/// LIGGGHTS's binary and the tutorial's lid mesh.
#[derive(Clone, Debug)]
pub struct LiggghtsInstall {
    /// The `liggghts` executable.
    pub binary: PathBuf,
    /// `piston_hydrogel.stl`.
    pub mesh: PathBuf,
}

impl LiggghtsInstall {
    /// `liggghts` on `PATH` and the mesh at [`MESH`]; otherwise why the
    /// case cannot run.
    pub fn locate() -> Result<Self, String> {
        let binary = std::env::var_os("PATH")
            .and_then(|path| {
                std::env::split_paths(&path)
                    .map(|d| d.join("liggghts"))
                    .find(|p| p.is_file())
            })
            .ok_or("liggghts is not on PATH (Debian package liggghts)")?;
        let mesh = PathBuf::from(MESH);
        if !mesh.is_file() {
            return Err(format!(
                "the tutorial's lid mesh {MESH} is missing (Debian package liggghts-doc)"
            ));
        }
        Ok(Self { binary, mesh })
    }
}

/// The committed deck of `law` cut to its lid's first pass, `steps` long:
/// the physics as committed (bed, materials, walls, lid, gravity, the
/// closure's fix), the two runs of the first pass (`run 1`, `run
/// ${ts_move} upto`) as one `run steps`, and the output files (`fix
/// ave/time` file, the lid table, the position dumps) removed; thermo
/// every 1,000 steps stays.
pub fn trimmed_deck(law: LiggghtsLaw, steps: u64) -> String {
    let deck = law.deck();
    let mut out = format!(
        "# bpm bench: reference_data/liggghts/hydrogel_multicontact/in.{}_gravity cut to the\n\
         # lid's first pass, run {steps}; output files (ave/time file, lid table, dumps) removed\n",
        law.tag()
    );
    let outputs = [
        "fix piston_force",
        "variable lid_",
        "fix lid_table",
        "write_dump",
    ];
    for line in deck.lines() {
        let t = line.trim_start();
        if outputs.iter().any(|o| t.starts_with(o)) {
            continue;
        }
        let words: Vec<&str> = t.split_whitespace().collect();
        if words == ["run", "1"] {
            continue;
        }
        if words.first() == Some(&"run") {
            // `run ${ts_move} upto`: the first pass ends here.
            out.push_str(&format!("run\t\t{steps}\n"));
            break;
        }
        out.push_str(line);
        out.push('\n');
    }
    out
}

/// The `Loop time of X on P procs for N steps` lines of a LIGGGHTS log:
/// seconds and steps summed over the runs; the error says what is wrong.
pub fn loop_time(log: &str) -> Result<(f64, u64), String> {
    let mut total = (0.0, 0);
    let mut found = false;
    for line in log.lines().filter(|l| l.starts_with("Loop time of")) {
        let words: Vec<&str> = line.split_whitespace().collect();
        let (seconds, procs, steps) = match words.as_slice() {
            [_, _, _, s, "on", p, "procs", "for", n, "steps", ..] => (s, p, n),
            _ => return Err(format!("unexpected loop-time line: {line}")),
        };
        let seconds: f64 = seconds
            .parse()
            .map_err(|_| format!("no seconds in: {line}"))?;
        let steps: u64 = steps.parse().map_err(|_| format!("no steps in: {line}"))?;
        if *procs != "1" {
            return Err(format!("not one serial process: {line}"));
        }
        total.0 += seconds;
        total.1 += steps;
        found = true;
    }
    if found {
        Ok(total)
    } else {
        Err("no 'Loop time of' line in its log".into())
    }
}

/// One LIGGGHTS run: its loop time, its version line and the command.
struct LiggghtsRun {
    seconds: f64,
    version: String,
    command: String,
}

/// Runs [`trimmed_deck`] for `law` in `dir/<law>/`, beside the bed
/// (`data/input.data`) and the mesh (`meshes/piston_hydrogel.stl`).
fn run_liggghts(
    install: &LiggghtsInstall,
    law: LiggghtsLaw,
    steps: u64,
    dir: &Path,
) -> Result<LiggghtsRun, String> {
    let tag = law.tag();
    let run_dir = dir.join(tag);
    write_tutorial_bed(&run_dir.join("data"), "input.data").map_err(|e| e.to_string())?;
    let meshes = run_dir.join("meshes");
    std::fs::create_dir_all(&meshes)
        .map_err(|e| FileError::on("creating", &meshes)(e).to_string())?;
    let mesh = meshes.join("piston_hydrogel.stl");
    std::fs::copy(&install.mesh, &mesh)
        .map_err(|e| FileError::on("copying the mesh to", &mesh)(e).to_string())?;
    let deck = format!("in.bench_{tag}");
    let deck_path = run_dir.join(&deck);
    std::fs::write(&deck_path, trimmed_deck(law, steps))
        .map_err(|e| FileError::on("writing", &deck_path)(e).to_string())?;
    let log_path = run_dir.join("log.liggghts");
    let _ = std::fs::remove_file(&log_path);
    // Not `-screen none`: LIGGGHTS 3.8 then crashes reading the mesh (it
    // prints to the screen it has not got); its screen output is dropped.
    let args = ["-in", &deck, "-log", "log.liggghts"];
    let command = format!(
        "cd {} && {} {}",
        run_dir.display(),
        install.binary.display(),
        args.join(" ")
    );
    let out = Command::new(&install.binary)
        .args(args)
        .current_dir(&run_dir)
        .stdout(std::process::Stdio::null())
        .output()
        .map_err(|e| format!("{command}: could not start: {e}"))?;
    let log = std::fs::read_to_string(&log_path).unwrap_or_default();
    if !out.status.success() {
        let last = |text: &str| {
            let lines: Vec<&str> = text.lines().filter(|l| !l.trim().is_empty()).collect();
            lines[lines.len().saturating_sub(3)..].join(" / ")
        };
        return Err(format!(
            "{command}: {}; its log ends: {:?}; its error output ends: {:?}",
            out.status,
            last(&log),
            last(&String::from_utf8_lossy(&out.stderr))
        ));
    }
    let (seconds, ran) = loop_time(&log).map_err(|e| format!("{command}: {e}"))?;
    if ran != steps {
        return Err(format!("{command}: ran {ran} steps, not {steps}"));
    }
    let version = log
        .lines()
        .find(|l| l.starts_with("LIGGGHTS"))
        .unwrap_or("LIGGGHTS (no version line in its log)")
        .to_string();
    Ok(LiggghtsRun {
        seconds,
        version,
        command,
    })
}

/// The native side's scene: the tutorial's bed (the data file `bed`)
/// under the lid's first pass with `law`, cut to `steps` steps, a row
/// every [`THERMO_EVERY`].
pub fn native_scene(bed: &Path, law: LiggghtsLaw, steps: u64) -> Result<Scene, LidError> {
    closure_scene(bed, law.multicontact(), law.name(), steps)
}

/// [`native_scene`] with any closure (`None`: plain Hertz), named `name`.
pub fn closure_scene(
    bed: &Path,
    multicontact: Option<MultiContact>,
    name: &str,
    steps: u64,
) -> Result<Scene, LidError> {
    let mut scene = lid_scene(&tutorial_options(bed, 1), multicontact, name)?;
    scene.stages.truncate(1);
    scene.stages[0].steps = steps;
    scene.stages[0].record.every = THERMO_EVERY;
    Ok(scene)
}

/// The advanced closure as the multi-contact studies run it (prefactor
/// and maximum penetration ratio of the source study's calibration).
pub fn advanced_closure() -> MultiContact {
    MultiContact::advanced(ADVANCED_GAMMA, ADVANCED_MPR)
}

/// The native engine on the same bed, lid and law, `steps` steps of the
/// first pass on `threads`: the stage's wall seconds.
fn run_native(bed: &Path, law: LiggghtsLaw, steps: u64, threads: usize) -> Result<f64, String> {
    let scene = native_scene(bed, law, steps).map_err(|e| e.to_string())?;
    run_native_scene(&scene, threads)
}

/// `scene` on `threads`: its first stage's wall seconds.
fn run_native_scene(scene: &Scene, threads: usize) -> Result<f64, String> {
    let mut sys = build_system(scene, threads);
    let (stages, error) = run_scene(&mut sys, scene, &RunOptions::quiet(threads));
    if let Some(e) = error {
        return Err(e.to_string());
    }
    Ok(stages.first().map_or(f64::NAN, |s| s.wall_seconds))
}

/// One contact law in both programs.
#[derive(Clone, Debug, Serialize)]
pub struct LiggghtsSpeed {
    /// The contact law.
    pub law: LiggghtsLaw,
    /// Beads.
    pub particles: usize,
    /// Steps timed.
    pub steps: u64,
    /// LIGGGHTS's loop time (s), the fastest of its runs.
    pub liggghts_seconds: f64,
    /// LIGGGHTS, ns per particle-step.
    pub liggghts_ns: f64,
    /// The native run on one thread (s), the fastest.
    pub native_seconds: f64,
    /// The native engine on one thread, ns per particle-step.
    pub native_ns: f64,
    /// The native engine on two threads, ns per particle-step.
    pub native_2_threads_ns: f64,
    /// LIGGGHTS's time over the native engine's on one thread.
    pub liggghts_over_native: f64,
    /// The LIGGGHTS command (its folder is removed afterwards).
    pub command: String,
}

impl LiggghtsSpeed {
    /// The comparison as one line.
    pub fn line(&self) -> String {
        format!(
            "liggghts {} {} particles {} steps: LIGGGHTS {:.1} ns ({:.2} s), native {:.1} ns ({:.2} s) on 1 thread, {:.1} ns on 2, per particle-step; LIGGGHTS / native (1 thread) {:.2}x",
            self.law.name(),
            self.particles,
            self.steps,
            self.liggghts_ns,
            self.liggghts_seconds,
            self.native_ns,
            self.native_seconds,
            self.native_2_threads_ns,
            self.liggghts_over_native
        )
    }
}

/// What the LIGGGHTS case measured.
#[derive(Clone, Debug, Serialize)]
pub struct LiggghtsBench {
    /// LIGGGHTS's banner (`LIGGGHTS (Version ...)`), from its log.
    pub version: String,
    /// The binary run.
    pub binary: String,
    /// Steps timed per run.
    pub steps: u64,
    /// What the native side runs.
    pub native: String,
    /// Plain Hertz and the closure, each measured in both programs.
    pub speeds: Vec<LiggghtsSpeed>,
    /// The advanced closure ([`advanced_closure`]), natively on one thread,
    /// timed in plain Hertz's rounds (ns per particle-step; LIGGGHTS has
    /// no such closure): NaN when its runs failed or Hertz was not measured.
    pub advanced_native_ns: f64,
    /// What failed, one message per law (the other law still runs).
    pub failures: Vec<String>,
}

/// Times both laws, `steps` steps (1 to [`PASS_STEPS`]), in LIGGGHTS (in
/// `work`, removed afterwards) and in the native engine on 1 and 2
/// threads, [`REPEATS`] rounds, each side's fastest run kept, and in plain
/// Hertz's rounds the advanced closure natively on one thread (reported
/// when Hertz was measured). A law whose run fails is reported in
/// `failures` and by `log`; the other law runs.
pub fn bench_liggghts(
    install: &LiggghtsInstall,
    steps: u64,
    work: &Path,
    log: &mut dyn FnMut(&str),
) -> LiggghtsBench {
    let mut bench = LiggghtsBench {
        version: String::new(),
        binary: install.binary.display().to_string(),
        steps,
        native: format!(
            "verify::liggghts::tutorial_options(bed, 1) through lid_scene, the first stage cut to {steps} steps, a row every {THERMO_EVERY}; the stage's wall time"
        ),
        speeds: Vec::new(),
        advanced_native_ns: f64::NAN,
        failures: Vec::new(),
    };
    let bed = match write_tutorial_bed(work, "hydrogel-input.data") {
        Ok(bed) => bed,
        Err(e) => {
            let message = format!("LIGGGHTS case failed: {e}");
            log(&message);
            bench.failures.push(message);
            return bench;
        }
    };
    let per = |secs: f64| secs * 1e9 / (steps as f64 * PARTICLES as f64);
    let advanced_scene = closure_scene(&bed, Some(advanced_closure()), "advanced closure", steps)
        .map_err(|e| e.to_string());
    // The fastest native advanced run (s), timed in plain Hertz's rounds:
    // its goal is a ratio to native Hertz.
    let mut advanced: Result<f64, String> = Ok(f64::INFINITY);
    for law in [LiggghtsLaw::Hertz, LiggghtsLaw::Closure] {
        let mut best: Option<LiggghtsRun> = None;
        let mut native = [f64::INFINITY; 2];
        let mut failure = None;
        // LIGGGHTS, then the native engine on 1 and 2 threads (and, in
        // Hertz's rounds, the native advanced closure), alternately.
        'rounds: for _ in 0..REPEATS {
            match run_liggghts(install, law, steps, work) {
                Ok(run) => {
                    if best.as_ref().is_none_or(|b| run.seconds < b.seconds) {
                        best = Some(run);
                    }
                }
                Err(e) => {
                    failure = Some(format!("LIGGGHTS {} failed: {e}", law.name()));
                    break 'rounds;
                }
            }
            for (kept, threads) in native.iter_mut().zip([1, 2]) {
                match run_native(&bed, law, steps, threads) {
                    Ok(secs) => *kept = kept.min(secs),
                    Err(e) => {
                        failure = Some(format!(
                            "the native {} run on {threads} thread(s) failed: {e}",
                            law.name()
                        ));
                        break 'rounds;
                    }
                }
            }
            if law == LiggghtsLaw::Hertz {
                advanced = advanced.and_then(|kept| {
                    let scene = advanced_scene.as_ref().map_err(Clone::clone)?;
                    Ok(kept.min(run_native_scene(scene, 1)?))
                });
            }
        }
        let measured = best.filter(|_| native.iter().all(|s| s.is_finite()));
        match (measured, failure) {
            (Some(run), failure) => {
                if let Some(message) = failure {
                    // A failed later round leaves the earlier one standing.
                    log(&format!("{message}; the earlier round is kept"));
                }
                if bench.version.is_empty() {
                    bench.version = run.version.clone();
                }
                let s = LiggghtsSpeed {
                    law,
                    particles: PARTICLES,
                    steps,
                    liggghts_seconds: run.seconds,
                    liggghts_ns: per(run.seconds),
                    native_seconds: native[0],
                    native_ns: per(native[0]),
                    native_2_threads_ns: per(native[1]),
                    liggghts_over_native: run.seconds / native[0],
                    command: run.command,
                };
                log(&s.line());
                bench.speeds.push(s);
            }
            (None, failure) => {
                let message =
                    failure.unwrap_or_else(|| format!("LIGGGHTS {}: no round ran", law.name()));
                log(&message);
                bench.failures.push(message);
            }
        }
    }
    // Without native Hertz there is nothing to compare the advanced closure
    // with (and when LIGGGHTS failed first, it did not run).
    let hertz_measured = bench.speeds.iter().any(|s| s.law == LiggghtsLaw::Hertz);
    match advanced {
        Ok(seconds) if hertz_measured && seconds.is_finite() => {
            bench.advanced_native_ns = per(seconds);
            log(&format!(
                "liggghts advanced closure (native only) {PARTICLES} particles {steps} steps: native {:.1} ns ({seconds:.2} s) on 1 thread per particle-step",
                bench.advanced_native_ns
            ));
        }
        Err(e) if hertz_measured => {
            let message = format!("the native advanced closure run failed: {e}");
            log(&message);
            bench.failures.push(message);
        }
        _ => {}
    }
    let _ = std::fs::remove_dir_all(work);
    bench
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_trimmed_decks_keep_the_physics_and_run_the_first_pass_once() {
        for law in [LiggghtsLaw::Hertz, LiggghtsLaw::Closure] {
            let full = trimmed_deck(law, 200);
            // The commands, without the comments (which name what was removed).
            let deck: String = full
                .lines()
                .filter(|l| !l.trim_start().starts_with('#'))
                .map(|l| format!("{l}\n"))
                .collect();
            let runs: Vec<&str> = deck
                .lines()
                .filter(|l| l.trim_start().starts_with("run"))
                .collect();
            assert_eq!(runs, ["run\t\t200"], "{deck}");
            for gone in [
                "write_dump",
                "lid_table",
                "ave/time",
                "unfix",
                "linear 0. 0. ${rvel}",
            ] {
                assert!(!deck.contains(gone), "{gone}: {deck}");
            }
            for kept in [
                "read_data data/input.data",
                "file meshes/piston_hydrogel.stl",
                "fix		gravi all gravity 9.81",
                "fix piston_move all move/mesh mesh piston_m linear 0. 0. ${cvel}",
                "fix		integr all nve/sphere",
                "thermo		1000",
            ] {
                assert!(deck.contains(kept), "{kept}: {deck}");
            }
            let closure =
                deck.contains("fix mc all multicontact/halfspace geometric_prefactor 1.125");
            assert_eq!(closure, law == LiggghtsLaw::Closure);
            assert_eq!(
                deck.matches("surface multicontact").count(),
                if closure { 7 } else { 0 },
                "pair style, five walls and the lid"
            );
        }
    }

    #[test]
    fn loop_times_are_summed_over_the_runs_of_one_process() {
        let log = "LIGGGHTS (Version LIGGGHTS-PUBLIC 3.8.0)\n\
                   Loop time of 0.00011606 on 1 procs for 1 steps with 514 atoms, finish time Sat\n\
                   Loop time of 5.23007 on 1 procs for 29999 steps with 514 atoms, finish time Sat\n";
        let (seconds, steps) = loop_time(log).unwrap();
        assert!((seconds - 5.23018606).abs() < 1e-12);
        assert_eq!(steps, 30_000);
        assert!(loop_time("ERROR: bad deck\n")
            .unwrap_err()
            .contains("no 'Loop time"));
        let two = "Loop time of 1.0 on 2 procs for 10 steps with 514 atoms\n";
        assert!(loop_time(two).unwrap_err().contains("not one serial"));
    }
}
