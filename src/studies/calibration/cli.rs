//! `bpm calibrate`: the calibration study from the command line.

use crate::studies::calibration;
use crate::studies::RuntimeArgs;
use crate::studies::{command_line, print_line};
use anyhow::Result;
use std::path::PathBuf;

/// The arguments of `bpm calibrate`.
#[derive(clap::Args)]
pub struct CalibrateArgs {
    /// Output folder.
    #[arg(short, long, default_value = "results/calibration")]
    output: PathBuf,
    /// Box sides L (d); the largest gets the full a_B table.
    #[arg(long, value_delimiter = ',', default_value = "6,8,10,14,20")]
    sizes: Vec<f64>,
    /// Seeds of the bulk solids (one solid per size and seed).
    #[arg(long, value_delimiter = ',', default_value = "1,2,3,4")]
    seeds: Vec<u64>,
    /// a_B values at the largest size (k d).
    #[arg(
        long,
        value_delimiter = ',',
        allow_hyphen_values = true,
        default_value = "-0.8,-0.5,0,0.5,1,2,3"
    )]
    a_b: Vec<f64>,
    /// a_B values of the size-convergence runs.
    #[arg(
        long,
        value_delimiter = ',',
        allow_hyphen_values = true,
        default_value = "0,-0.5"
    )]
    convergence_a_b: Vec<f64>,
    /// Sizes at which LAMMPS repeats the first seed's cases.
    #[arg(long, value_delimiter = ',', default_value = "10")]
    lammps_sizes: Vec<f64>,
    /// Strain rate (1 / tau).
    #[arg(long, default_value_t = 1e-5)]
    rate: f64,
    /// Final strain.
    #[arg(long, default_value_t = 0.005)]
    strain: f64,
    /// Skip the half-rate repeat.
    #[arg(long)]
    no_rate_check: bool,
    /// Rewrite the tables and plots from an earlier calibration.json
    /// without running anything (other options are ignored).
    #[arg(long)]
    from: Option<PathBuf>,
    #[command(flatten)]
    runtime: RuntimeArgs,
}

impl CalibrateArgs {
    /// `bpm calibrate`.
    pub fn run(self, threads: usize) -> Result<()> {
        let Self {
            output,
            sizes,
            seeds,
            a_b,
            convergence_a_b,
            lammps_sizes,
            rate,
            strain,
            no_rate_check,
            from,
            runtime,
        } = self;
        if let Some(path) = from {
            print_calibration_report(&calibration::replot(&path, &output)?);
            return Ok(());
        }
        let opts = calibration::StudyOptions {
            sizes,
            seeds,
            a_b,
            convergence_a_b,
            lammps_sizes,
            loading: calibration::Loading {
                strain,
                rate,
                ..Default::default()
            },
            halve_rate: !no_rate_check,
        };
        opts.validate()?;
        let exe = std::env::current_exe()?;
        let runtime = runtime.runtime("calibrate", &opts, threads)?;
        let done = calibration::calibrate(
            &opts,
            &output,
            &exe,
            &runtime,
            &command_line(),
            &mut print_line,
        )?;
        println!("wrote {}", done.json.display());
        print_calibration_report(&done.report);
        Ok(())
    }
}

/// The calibration tables, then the files written.
fn print_calibration_report(report: &calibration::CalibrationFiles) {
    println!("\n{}", report.markdown);
    for f in &report.files {
        println!("wrote {}", f.display());
    }
}
