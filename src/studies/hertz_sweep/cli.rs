//! `bpm hertz-sweep`: the deviation from Hertz against grain size from
//! the command line.

use crate::scene::cli::GrainKindArg;
use crate::studies::hertz::cli::SqueezeWith;
use crate::studies::hertz_sweep::{run_hertz_sweep, SweepOptions};
use crate::studies::RuntimeArgs;
use crate::verify::LammpsLauncher;
use anyhow::Result;
use std::path::PathBuf;

/// The arguments of `bpm hertz-sweep`.
#[derive(clap::Args)]
pub struct HertzSweepArgs {
    /// Grain kind.
    #[arg(long, value_enum, default_value = "smoother")]
    kind: GrainKindArg,
    /// Radii R (d), comma separated.
    #[arg(long, value_delimiter = ',', default_value = "4,6,8,10")]
    radii: Vec<f64>,
    /// Multibody strengths a_B (k d), comma separated.
    #[arg(
        long = "a-b",
        value_delimiter = ',',
        allow_hyphen_values = true,
        default_value = "0"
    )]
    a_b: Vec<f64>,
    /// Seed of every grain and of its rotations.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Random rotations per squeeze (0: as built).
    #[arg(long, default_value_t = 4)]
    rotations: usize,
    /// Overlap delta / R to reach.
    #[arg(long, default_value_t = 0.3)]
    max_overlap: f64,
    /// The engine that squeezes.
    #[arg(long, value_enum, default_value = "native")]
    engine: SqueezeWith,
    /// Scale of the grain builds' times (1 = the full protocol).
    #[arg(long, default_value_t = 1.0)]
    time_scale: f64,
    /// Records per squeeze.
    #[arg(long, default_value_t = 1000)]
    records: u64,
    /// Output folder.
    #[arg(short, long)]
    output: PathBuf,
    #[command(flatten)]
    runtime: RuntimeArgs,
}

impl HertzSweepArgs {
    /// `bpm hertz-sweep`.
    pub fn run(self, threads: usize) -> Result<()> {
        let Self {
            kind,
            radii,
            a_b,
            seed,
            rotations,
            max_overlap,
            engine,
            time_scale,
            records,
            output,
            runtime,
        } = self;
        let opts = SweepOptions {
            kind: kind.into(),
            radii,
            a_bs: a_b,
            seed,
            rotations,
            max_overlap,
            records,
            engine: engine.into(),
            threads,
            time_scale,
        };
        let launcher = LammpsLauncher {
            bpm: std::env::current_exe()?,
            dir: output.join("lammps"),
        };
        println!(
            "{:>5} {:>5} {:>6} {:>9} {:>9} {:>8} {:>9} {:>9} {:>8} {:>10}",
            "R",
            "a_B",
            "nu",
            "particles",
            "roughness",
            "build s",
            "squeeze s",
            "rms rel",
            "slope",
            "worst rel"
        );
        let runtime = runtime.runtime("hertz-sweep", &opts, threads)?;
        let report = run_hertz_sweep(&opts, &output, &launcher, &runtime, &mut |c| {
            let d = c.deviation;
            println!(
                "{:>5} {:>5} {:>6.3} {:>9} {:>9.4} {:>8.1} {:>9.1} {:>9.4} {:>8.3} {:>10.4}",
                c.radius,
                c.a_b,
                c.nu,
                c.grain.particles,
                c.grain.roughness.sd_height,
                c.grain.seconds,
                c.seconds_per_squeeze,
                d.map_or(f64::NAN, |d| d.rms_relative),
                d.map_or(f64::NAN, |d| d.loglog_slope),
                c.worst_squeeze_rms_relative
            );
        })?;
        println!(
            "{} cases in {:.0} s; wrote {}/sweep.json and sweep.svg",
            report.cases.len(),
            report.wall_seconds,
            output.display()
        );
        Ok(())
    }
}
