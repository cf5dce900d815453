//! `bpm upstream-check`: the comparison with upstream LAMMPS from the
//! command line.

use crate::studies::upstream;
use crate::studies::{command_line, print_line};
use anyhow::{bail, Result};
use std::path::PathBuf;

/// The arguments of `bpm upstream-check`.
#[derive(clap::Args)]
pub struct UpstreamCheckArgs {
    /// Output folder (report and LAMMPS files).
    #[arg(short, long, default_value = "results/upstream")]
    output: PathBuf,
    /// Box side of the contact solid (d).
    #[arg(long, default_value_t = 8.0)]
    size: f64,
    /// Grain radius of the grain pair (d).
    #[arg(long, default_value_t = 3.0)]
    grain_radius: f64,
    /// Steps of the trajectories.
    #[arg(long, default_value_t = 1000)]
    steps: u64,
    /// Box side of the solid for the speed comparison (0 = skip).
    #[arg(long, default_value_t = 14.0)]
    speed_size: f64,
    /// Seed of the scenes.
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

impl UpstreamCheckArgs {
    /// `bpm upstream-check`.
    pub fn run(self) -> Result<()> {
        let Self {
            output,
            size,
            grain_radius,
            steps,
            speed_size,
            seed,
        } = self;
        let opts = upstream::UpstreamOptions {
            size,
            grain_radius,
            steps,
            speed_size,
            seed,
        };
        let report =
            upstream::run_upstream_check(&opts, &output, &command_line(), &mut print_line)?;
        println!("wrote {}", report.json.display());
        let failed = report.failures();
        if failed > 0 {
            bail!("{failed} comparisons with upstream failed");
        }
        println!("all {} judged comparisons pass", report.judged());
        Ok(())
    }
}
