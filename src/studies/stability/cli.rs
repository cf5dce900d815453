//! `bpm stability`: the stability map from the command line.

use crate::studies::stability;
use crate::studies::RuntimeArgs;
use crate::studies::{command_line, print_line};
use anyhow::{Context, Result};
use std::path::PathBuf;

/// The arguments of `bpm stability`.
#[derive(clap::Args)]
pub struct StabilityArgs {
    /// Output folder [default: results/stability; with --from, the JSON's own
    /// folder, whose report and plot are rewritten]
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Box side L of the bulk solid (d).
    #[arg(long, default_value_t = 10.0)]
    size: f64,
    /// Seeds of the solids (one solid per seed).
    #[arg(long, value_delimiter = ',', default_value = "1")]
    seeds: Vec<u64>,
    /// a_B values (k d).
    #[arg(
        long = "a-b",
        value_delimiter = ',',
        allow_hyphen_values = true,
        default_value = "3,2,1,0.5,0,-0.25,-0.5,-0.75,-0.9,-1,-1.1,-1.2"
    )]
    a_b: Vec<f64>,
    /// Damping values Gamma of bonds and contacts (sqrt(k m)).
    #[arg(long, value_delimiter = ',', default_value = "1,0")]
    gamma: Vec<f64>,
    /// Smallest timestep of the bisection (tau).
    #[arg(long, default_value_t = 0.005)]
    dt_min: f64,
    /// Largest timestep of the bisection (tau).
    #[arg(long, default_value_t = 1.0)]
    dt_max: f64,
    /// Simulated time of every trial (tau).
    #[arg(long, default_value_t = 100.0)]
    time: f64,
    /// Energy over the initial kinetic plus imposed strain energy that
    /// counts as unstable.
    #[arg(long, default_value_t = 10.0)]
    growth: f64,
    /// Largest bond strain left at the end (beyond the imposed strain)
    /// that still counts as stable.
    #[arg(long, default_value_t = 0.1)]
    residual_strain: f64,
    /// Relative width of the final bracket.
    #[arg(long, default_value_t = 0.02)]
    precision: f64,
    /// Skip the moduli at each a_B.
    #[arg(long)]
    no_moduli: bool,
    /// Map the zero-net-multibody variant of the bond force
    /// (docs/model.md) instead of the paper's model.
    #[arg(long)]
    zero_net: bool,
    /// Rewrite the plot from an earlier stability.json without running
    /// anything (other options are ignored).
    #[arg(long)]
    from: Option<PathBuf>,
    #[command(flatten)]
    runtime: RuntimeArgs,
}

impl StabilityArgs {
    /// `bpm stability`.
    pub fn run(self, threads: usize) -> Result<()> {
        let Self {
            output,
            size,
            seeds,
            a_b,
            gamma,
            dt_min,
            dt_max,
            time,
            growth,
            residual_strain,
            precision,
            no_moduli,
            zero_net,
            from,
            runtime,
        } = self;
        if let Some(path) = from {
            let output = output.unwrap_or_else(|| crate::studies::output::replot_folder(&path));
            let report = stability::replot(&path, &output)?;
            print_limits(&report);
            println!(
                "wrote {}/stability.json and stability.svg",
                output.display()
            );
            return Ok(());
        }
        let output = output.unwrap_or_else(|| PathBuf::from("results/stability"));
        let opts = stability::StabilityOptions {
            size,
            seeds,
            a_b,
            gammas: gamma,
            dt_range: (dt_min, dt_max),
            growth_limit: growth,
            residual_strain_limit: residual_strain,
            time,
            precision,
            moduli: !no_moduli,
            zero_net,
            ..Default::default()
        };
        opts.validate()?;
        std::fs::create_dir_all(&output)
            .with_context(|| format!("creating {}", output.display()))?;
        let runtime = runtime.runtime("stability", &opts, threads)?;
        let report = stability::run_stability(&opts, &runtime, &command_line(), &mut print_line)?;
        stability::write_report(&report, &output)?;
        print_limits(&report);
        println!(
            "wrote {}/stability.json and stability.svg",
            output.display()
        );
        Ok(())
    }
}

/// The table of limits, one line per seed, a_B and Gamma.
fn print_limits(report: &stability::StabilityReport) {
    println!(
        "\n{:>6} {:>6} {:>5} {:>10} {:>11} {:>7}",
        "a_B", "Gamma", "seed", "dt stable", "dt unstable", "trials"
    );
    for limit in &report.limits {
        println!("{}", limit.row());
    }
}
