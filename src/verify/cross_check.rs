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
    /// Run only the scene's first this many steps (later stages dropped,
    /// the last one kept cut short): trajectories of many touching,
    /// rearranging spheres drift apart from round-off, and agree to
    /// round-off only so long.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub steps: Option<u64>,
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

/// The first `steps` steps of `scene`: the stages they reach, the last
/// one cut short.
pub fn first_steps(scene: &Scene, steps: u64) -> Result<Scene, InvalidOption> {
    let total: u64 = scene.stages.iter().map(|s| s.steps).sum();
    if steps == 0 || steps > total {
        return Err(InvalidOption::new(
            "--steps",
            format!("give 1 to the scene's {total} steps"),
        ));
    }
    let mut cut = scene.clone();
    let mut left = steps;
    cut.stages.clear();
    for stage in &scene.stages {
        if left == 0 {
            break;
        }
        let mut stage = stage.clone();
        stage.steps = stage.steps.min(left);
        left -= stage.steps;
        cut.stages.push(stage);
    }
    Ok(cut)
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
    let cut;
    let scene = match opts.steps {
        None => scene,
        Some(steps) => {
            cut = first_steps(scene, steps)?;
            &cut
        }
    };
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::StageSpec;
    use crate::verify::scenes::dem_lattice;

    #[test]
    fn the_first_steps_keep_the_stages_they_reach_and_cut_the_last() {
        let mut scene = dem_lattice(1, false);
        scene.stages = vec![
            StageSpec::hold("a", 100, 0.01),
            StageSpec::hold("b", 50, 0.01),
            StageSpec::hold("c", 10, 0.01),
        ];
        let steps = |s: &Scene| s.stages.iter().map(|s| s.steps).collect::<Vec<_>>();
        assert_eq!(steps(&first_steps(&scene, 120).unwrap()), [100, 20]);
        assert_eq!(steps(&first_steps(&scene, 100).unwrap()), [100]);
        assert_eq!(steps(&first_steps(&scene, 160).unwrap()), [100, 50, 10]);
        for bad in [0, 161] {
            let err = first_steps(&scene, bad).unwrap_err().to_string();
            assert!(err.contains("--steps") && err.contains("160"), "{err}");
        }
    }
}
