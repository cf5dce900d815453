//! `bpm run`: a scene through the native engine, or through LAMMPS with
//! our styles in this process (under `mpirun`, on every rank).

use crate::progress::ProgressArgs;
use crate::scene::checkpoint::CheckpointArgs;
use crate::scene::{
    final_scene as final_scene_of, read_scene, run_native_report, write_scene, DumpOptions,
    EngineInfo, OutputFiles, RunOptions, RunReport, Scene,
};
use anyhow::{bail, Context, Result};
use clap::ValueEnum;
use std::path::{Path, PathBuf};

/// The engine a command runs its scenes in.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum EngineArg {
    /// The native Rust engine.
    Native,
    /// LAMMPS with the plugin's styles, in this process.
    Lammps,
}

/// The arguments of `bpm run`.
#[derive(clap::Args)]
pub struct RunArgs {
    /// Scene file (JSON).
    scene: PathBuf,
    /// Output file (JSON).
    #[arg(short, long)]
    output: PathBuf,
    /// Also write the final state as a scene (native engine only).
    #[arg(long)]
    final_scene: Option<PathBuf>,
    /// The engine: native, or LAMMPS with our styles in this process
    /// (under `mpirun` it runs on every rank).
    #[arg(long, value_enum, default_value = "native")]
    engine: EngineArg,
    /// LAMMPS's `newton` setting (LAMMPS only).
    #[arg(long, default_value = "on", value_parser = ["on", "off"])]
    newton: String,
    /// Folder for the LAMMPS driver script, data file and log (LAMMPS
    /// only; default: beside the output, named after it).
    #[arg(long)]
    workdir: Option<PathBuf>,
    /// Stream the thermo rows to this text file as they are recorded
    /// (they are then not kept in memory or in the report).
    #[arg(long)]
    thermo: Option<PathBuf>,
    /// Write snapshots to this LAMMPS dump file (`id mol type x y z ix
    /// iy iz vx vy vz`), readable by OVITO and `read_dump`.
    #[arg(long)]
    dump: Option<PathBuf>,
    /// Steps between snapshots (global step count).
    #[arg(long, default_value_t = 1000)]
    dump_every: u64,
    /// Add forces (`fx fy fz`) to the snapshots.
    #[arg(long)]
    dump_forces: bool,
    #[command(flatten)]
    checkpoint: CheckpointArgs,
    #[command(flatten)]
    progress: ProgressArgs,
}

impl RunArgs {
    /// `bpm run`.
    pub fn run(self, threads: usize) -> Result<()> {
        let Self {
            scene: path,
            output,
            final_scene,
            engine,
            newton,
            workdir,
            thermo,
            dump,
            dump_every,
            dump_forces,
            checkpoint,
            progress,
        } = self;
        let progress = progress.progress().context("opening the progress log")?;
        let files = OutputFiles {
            thermo,
            dump: dump.map(|path| DumpOptions {
                path,
                every: dump_every,
                forces: dump_forces,
            }),
        };
        files.validate()?;
        let (scene, hash) =
            read_scene(&path).with_context(|| format!("reading scene {}", path.display()))?;
        if engine == EngineArg::Lammps {
            if final_scene.is_some() {
                bail!("--final-scene is only available with --engine native");
            }
            if checkpoint.checkpoint.is_some() {
                bail!("--checkpoint is only available with --engine native");
            }
            return run_lammps(
                &scene,
                &path,
                hash,
                &output,
                newton == "on",
                workdir,
                &files,
            );
        }
        let checkpoint = checkpoint.run()?;
        let opts = RunOptions {
            threads,
            progress,
            files,
            checkpoint,
        };
        let (report, sys) = run_native_report(&scene, &path, hash, &opts);
        report.write(&output)?;
        if let Some(final_path) = final_scene {
            write_scene(&final_path, &final_scene_of(&scene, &sys))?;
        }
        for s in &report.stages {
            let steps = match s.stopped_at {
                Some(done) => format!("{done} of {}", s.steps),
                None => s.steps.to_string(),
            };
            println!(
                "stage {:<12} {:>9} steps  {:>8.2} s  neighbour builds {}",
                s.name, steps, s.wall_seconds, s.neighbour_builds
            );
        }
        if let Some(e) = report.error {
            bail!(
                "{e} (stages finished before it are saved in {})",
                output.display()
            );
        }
        println!("wrote {}", output.display());
        Ok(())
    }
}

/// `bpm run --engine lammps`: the scene in LAMMPS in this process. LAMMPS
/// errors end the process with LAMMPS's message (Debian's LAMMPS has no
/// exceptions); `bpm check` runs this as a child process for that reason.
fn run_lammps(
    scene: &Scene,
    path: &Path,
    hash: u64,
    output: &Path,
    newton: bool,
    workdir: Option<PathBuf>,
    files: &OutputFiles,
) -> Result<()> {
    let stem = output
        .file_stem()
        .map_or("run".into(), |s| s.to_string_lossy().to_string());
    let dir = workdir.unwrap_or_else(|| output.with_file_name(format!("{stem}.lammps")));
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let start = std::time::Instant::now();
    let run = super::runner::run_scene_lammps(scene, &dir, "scene", newton, files)?;
    super::finalize_mpi();
    if run.rank != 0 {
        return Ok(());
    }
    let driver = dir.join("scene.in").display().to_string();
    let mut report = RunReport::new(
        EngineInfo::Lammps {
            lammps_version: run.lammps_version.0,
            lammps: format!("{} + lammps-plugin", run.lammps_version),
            mpi_ranks: run.ranks,
            newton,
            driver: driver.clone(),
        },
        path,
        hash,
        scene,
    );
    report.wall_seconds = start.elapsed().as_secs_f64();
    report.files = files.paths();
    report.stages = run.stages;
    report.write(output)?;
    println!("wrote {} (LAMMPS driver {driver})", output.display());
    Ok(())
}
