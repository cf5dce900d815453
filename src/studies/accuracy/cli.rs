//! `bpm accuracy`: run time against error from the command line.

use crate::scene::cli::GrainKindArg;
use crate::studies::accuracy;
use crate::studies::{command_line, print_line};
use anyhow::{Context, Result};
use std::path::PathBuf;

/// The arguments of `bpm accuracy`.
#[derive(clap::Args)]
pub struct AccuracyArgs {
    /// Output folder [default: results/accuracy; with --from, the JSON's own
    /// folder, whose report and plot are rewritten]
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Multibody strength a_B of every run (k d).
    #[arg(long = "a-b", default_value_t = 0.0, allow_hyphen_values = true)]
    a_b: f64,
    /// Seed of the solids and grains.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Timesteps (tau); the default 0.1 is held in the other sweeps.
    #[arg(long, value_delimiter = ',', default_value = "0.025,0.05,0.1,0.15,0.2")]
    dts: Vec<f64>,
    /// Neighbour skins (d); the default 0.3 is held in the other sweeps.
    #[arg(long, value_delimiter = ',', default_value = "0.1,0.3,0.6,1")]
    skins: Vec<f64>,
    /// Box sides of the calibration (d); 10 is held in the other sweeps.
    #[arg(long, value_delimiter = ',', default_value = "6,8,10,14,20")]
    sizes: Vec<f64>,
    /// Strain rates of the calibration (1/tau); 1e-5 is held in the other sweeps.
    #[arg(long, value_delimiter = ',', default_value = "1e-4,3e-5,1e-5,3e-6")]
    rates: Vec<f64>,
    /// Grain radii of the squeeze (d); 6 is held in the other sweeps.
    #[arg(long, value_delimiter = ',', default_value = "4,6,8")]
    radii: Vec<f64>,
    /// Wall speeds of the squeeze (d/tau); 5e-4 is held in the other sweeps.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "2e-3,1e-3,5e-4,2.5e-4,1.25e-4"
    )]
    wall_speeds: Vec<f64>,
    /// Grain kind of the squeeze.
    #[arg(long, value_enum, default_value = "smoother")]
    kind: GrainKindArg,
    /// Skip the squeeze sweeps.
    #[arg(long)]
    no_hertz: bool,
    /// Skip the calibration sweeps.
    #[arg(long)]
    no_calibration: bool,
    /// Rewrite the plot from an earlier accuracy.json without running
    /// anything (other options are ignored).
    #[arg(long)]
    from: Option<PathBuf>,
}

impl AccuracyArgs {
    /// `bpm accuracy`.
    pub fn run(self, threads: usize) -> Result<()> {
        let Self {
            output,
            a_b,
            seed,
            dts,
            skins,
            sizes,
            rates,
            radii,
            wall_speeds,
            kind,
            no_hertz,
            no_calibration,
            from,
        } = self;
        if let Some(path) = from {
            let output = output.unwrap_or_else(|| crate::studies::output::replot_folder(&path));
            let report = accuracy::replot(&path, &output)?;
            print!("{}", accuracy::table(&report));
            println!("wrote {}/accuracy.json and accuracy.svg", output.display());
            return Ok(());
        }
        let output = output.unwrap_or_else(|| PathBuf::from("results/accuracy"));
        let opts = accuracy::AccuracyOptions {
            a_b,
            seed,
            dts,
            skins,
            sizes,
            rates,
            radii,
            wall_speeds,
            kind: kind.into(),
            hertz: !no_hertz,
            calibration: !no_calibration,
            ..Default::default()
        };
        opts.validate()?;
        std::fs::create_dir_all(&output)
            .with_context(|| format!("creating {}", output.display()))?;
        let report = accuracy::run_accuracy(&opts, threads, &command_line(), &mut print_line)?;
        accuracy::write_report(&report, &output)?;
        print!("{}", accuracy::table(&report));
        println!("wrote {}/accuracy.json and accuracy.svg", output.display());
        Ok(())
    }
}
