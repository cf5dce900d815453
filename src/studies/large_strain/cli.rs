//! `bpm large-strain`: the large compression from the command line.

use crate::studies::large_strain;
use crate::studies::{command_line, print_line};
use anyhow::{Context, Result};
use std::path::PathBuf;

/// The arguments of `bpm large-strain`.
#[derive(clap::Args)]
pub struct LargeStrainArgs {
    /// Output folder [default: results/large-strain; with --from, the JSON's own
    /// folder, whose report and plot are rewritten]
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Multibody strengths a_B (k d).
    #[arg(
        long = "a-b",
        value_delimiter = ',',
        default_value = "3,0,-0.5,-0.9",
        allow_hyphen_values = true
    )]
    a_b: Vec<f64>,
    /// Use the zero-net-multibody variant (docs/model.md).
    #[arg(long)]
    zero_net: bool,
    /// Seed of the solid and the grain.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Volumetric strain to reach.
    #[arg(long, default_value_t = 0.6)]
    strain: f64,
    /// Box side of the bulk solid (d); 0 skips it.
    #[arg(long, default_value_t = 10.0)]
    size: f64,
    /// True strain rate of the bulk compression per dimension (1/tau).
    #[arg(long, default_value_t = 1e-4)]
    rate: f64,
    /// Grain radius (d); 0 skips the grain.
    #[arg(long, default_value_t = 6.0)]
    radius: f64,
    /// Inward speed of the grain's spherical wall (d/tau).
    #[arg(long, default_value_t = 5e-4)]
    wall_speed: f64,
    /// Timestep (tau).
    #[arg(long, default_value_t = 0.1)]
    dt: f64,
    /// Rewrite the plot from an earlier large_strain.json without running
    /// anything (other options are ignored).
    #[arg(long)]
    from: Option<PathBuf>,
}

impl LargeStrainArgs {
    /// `bpm large-strain`.
    pub fn run(self, threads: usize) -> Result<()> {
        let Self {
            output,
            a_b,
            zero_net,
            seed,
            strain,
            size,
            rate,
            radius,
            wall_speed,
            dt,
            from,
        } = self;
        if let Some(path) = from {
            let output = output.unwrap_or_else(|| crate::studies::output::replot_folder(&path));
            let report = large_strain::replot(&path, &output)?;
            println!(
                "{} compressions replotted; wrote {}/large_strain.json and large_strain.svg",
                report.compressions.len(),
                output.display()
            );
            return Ok(());
        }
        let output = output.unwrap_or_else(|| PathBuf::from("results/large-strain"));
        let opts = large_strain::LargeStrainOptions {
            a_b,
            zero_net,
            seed,
            volumetric_strain: strain,
            size,
            rate,
            radius,
            wall_speed,
            dt,
            ..Default::default()
        };
        opts.validate()?;
        std::fs::create_dir_all(&output)
            .with_context(|| format!("creating {}", output.display()))?;
        let report =
            large_strain::run_large_strain(&opts, threads, &command_line(), &mut print_line)?;
        large_strain::write_report(&report, &output)?;
        let complete = report.compressions.iter().filter(|c| c.complete).count();
        println!(
            "{complete} of {} compressions reached volumetric strain {strain} with nothing lost; wrote {}/large_strain.json and large_strain.svg",
            report.compressions.len(),
            output.display()
        );
        Ok(())
    }
}
