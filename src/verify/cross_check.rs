//! `bpm cross-check`: one scene of the user's through the native engine
//! and through LAMMPS with the plugin on each rank count, compared as `bpm
//! check` compares its built-in scenes, with the wall times of both.

use super::check::{print_header, print_verdict, verdict, CheckError, Verdict};
use super::compare::compare_runs;
use super::engines::{run_native, LammpsLauncher};
use crate::file_error::FileError;
use crate::lammps::datafile::uses_closure;
use crate::options::InvalidOption;
use crate::scene::Scene;
use serde::Serialize;
use std::path::PathBuf;

/// What `bpm cross-check` runs.
#[derive(Clone, Debug, Serialize)]
pub struct CrossCheckOptions {
    /// The scene file.
    pub scene: PathBuf,
    /// MPI rank counts of the LAMMPS runs.
    pub ranks: Vec<usize>,
    /// LAMMPS's newton setting (scenes with the multi-contact closure run
    /// with it off whatever it says; the report records the one used).
    pub newton: bool,
    /// Where the report and the LAMMPS files go.
    #[serde(skip)]
    pub out_dir: PathBuf,
    /// The `bpm` executable (for LAMMPS child runs).
    #[serde(skip)]
    pub bpm: PathBuf,
}

/// Everything `bpm cross-check` measured.
#[derive(Clone, Debug, Serialize)]
pub struct CrossCheckReport {
    /// Options.
    pub options: CrossCheckOptions,
    /// The scene's seed and description.
    pub seed: u64,
    /// The scene's description.
    pub description: String,
    /// Verdicts, per rank count and observable.
    pub verdicts: Vec<Verdict>,
    /// `(ranks, LAMMPS wall seconds over native wall seconds)`, process
    /// start included for LAMMPS.
    pub time_ratios: Vec<(usize, f64)>,
}

impl CrossCheckReport {
    /// Number of failed verdicts.
    pub fn failures(&self) -> usize {
        self.verdicts.iter().filter(|v| !v.pass).count()
    }
}

/// Runs `scene` (read from `opts.scene`) through both engines and writes
/// `cross_check.json` into `opts.out_dir`.
pub fn run_cross_check(
    opts: &CrossCheckOptions,
    scene: &Scene,
) -> Result<CrossCheckReport, CheckError> {
    if opts.ranks.is_empty() || opts.ranks.iter().any(|&r| r == 0 || r > 64) {
        return Err(InvalidOption::new("--ranks", "give rank counts from 1 to 64").into());
    }
    let work = opts.out_dir.join("lammps");
    std::fs::create_dir_all(&work).map_err(FileError::on("creating", &work))?;
    let launcher = LammpsLauncher {
        bpm: opts.bpm.clone(),
        dir: work,
    };
    let newton = opts.newton && !uses_closure(scene);
    let name = opts
        .scene
        .file_stem()
        .map_or("scene".into(), |s| s.to_string_lossy().into_owned());
    let native = run_native(scene, &name, 1)?;
    let mut verdicts = Vec::new();
    let mut time_ratios = Vec::new();
    print_header();
    for &ranks in &opts.ranks {
        let tag = format!("{name}-np{ranks}");
        let lammps = launcher.run(scene, &tag, ranks, newton)?;
        let how = format!("np{ranks} newton {}", if newton { "on" } else { "off" });
        for d in compare_runs(&native.stages, &lammps.stages)? {
            let v = verdict(
                &name,
                &how,
                &format!("trajectory {}", d.observable),
                d.max_deviation,
                (native.seconds, lammps.seconds),
            );
            print_verdict(&v);
            verdicts.push(v);
        }
        time_ratios.push((ranks, lammps.seconds / native.seconds));
    }
    let report = CrossCheckReport {
        // The setting the runs used.
        options: CrossCheckOptions {
            newton,
            ..opts.clone()
        },
        seed: scene.seed,
        description: scene.description.clone(),
        verdicts,
        time_ratios,
    };
    let path = opts.out_dir.join("cross_check.json");
    let text = serde_json::to_string_pretty(&report).expect("the report serialises");
    std::fs::write(&path, text).map_err(FileError::on("writing", &path))?;
    Ok(report)
}
