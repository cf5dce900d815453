//! `bpm hertz`: the Hertz squeeze from the command line.

use crate::scene::cli::GrainKindArg;
use crate::studies::hertz::{
    run_hertz, EngineAgreement, GrainSource, HertzOptions, Moduli, SqueezeEngine,
};
use crate::studies::RuntimeArgs;
use crate::verify::LammpsLauncher;
use anyhow::Result;
use clap::ValueEnum;
use std::path::PathBuf;

/// The engine that squeezes, as the command line names it.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SqueezeWith {
    /// The native Rust engine.
    Native,
    /// LAMMPS with this project's styles (a child process).
    Lammps,
    /// Both; the curve is the native one, and each squeeze reports how far
    /// LAMMPS's forces are from it.
    Both,
}

impl From<SqueezeWith> for SqueezeEngine {
    fn from(e: SqueezeWith) -> Self {
        match e {
            SqueezeWith::Native => SqueezeEngine::Native,
            SqueezeWith::Lammps => SqueezeEngine::Lammps,
            SqueezeWith::Both => SqueezeEngine::Both,
        }
    }
}

/// The arguments of `bpm hertz`.
#[derive(clap::Args)]
pub struct HertzArgs {
    /// Grain kind to build (ignored with --grain).
    #[arg(long, value_enum, default_value = "smoother")]
    kind: GrainKindArg,
    /// Grain radius R (d): built grains' radius, and the nominal R of
    /// the overlap and of the normalisation.
    #[arg(long, default_value_t = 10.0)]
    radius: f64,
    /// Squeeze this grain (a scene JSON or a LAMMPS data file) as given.
    #[arg(long)]
    grain: Option<PathBuf>,
    /// Multibody strength a_B (k d); the force field is the paper's.
    #[arg(long = "a-b", allow_hyphen_values = true)]
    a_b: f64,
    /// The engine that squeezes.
    #[arg(long, value_enum, default_value = "native")]
    engine: SqueezeWith,
    /// Overlap delta / R to reach.
    #[arg(long, default_value_t = 0.3)]
    max_overlap: f64,
    /// Random rotations per grain (0: squeeze as given).
    #[arg(long, default_value_t = 0)]
    rotations: usize,
    /// Seeds: one built grain per seed (comma separated).
    #[arg(long, value_delimiter = ',', default_value = "1")]
    seeds: Vec<u64>,
    /// Scale of the grain build's times (1 = the full protocol).
    #[arg(long, default_value_t = 1.0)]
    time_scale: f64,
    /// Bulk modulus K for E_eff (default: the paper's calibration fit at a_B).
    #[arg(long)]
    k: Option<f64>,
    /// Poisson ratio for E_eff (default: the paper's calibration fits at a_B).
    #[arg(long, allow_hyphen_values = true)]
    nu: Option<f64>,
    /// Records per squeeze.
    #[arg(long, default_value_t = 1000)]
    records: u64,
    /// Output folder.
    #[arg(short, long)]
    output: PathBuf,
    #[command(flatten)]
    runtime: RuntimeArgs,
}

impl HertzArgs {
    /// `bpm hertz`.
    pub fn run(self, threads: usize) -> Result<()> {
        let Self {
            kind,
            radius,
            grain,
            a_b,
            engine,
            max_overlap,
            rotations,
            seeds,
            time_scale,
            k,
            nu,
            records,
            output,
            runtime,
        } = self;
        let mut moduli = Moduli::paper_fits(a_b);
        if k.is_some() || nu.is_some() {
            moduli.k = k.unwrap_or(moduli.k);
            moduli.nu = nu.unwrap_or(moduli.nu);
            moduli.source = format!(
                "given on the command line (K = {}, nu = {})",
                moduli.k, moduli.nu
            );
        }
        let opts = HertzOptions {
            source: match grain {
                Some(path) => GrainSource::File { path, radius },
                None => GrainSource::Build {
                    kind: kind.into(),
                    radius,
                    time_scale,
                },
            },
            seeds,
            a_b,
            rotations,
            max_overlap,
            moduli,
            engine: engine.into(),
            records,
            threads,
        };
        let launcher = LammpsLauncher {
            bpm: std::env::current_exe()?,
            dir: output.join("lammps"),
        };
        println!(
            "{:>6} {:>8} {:>9} {:>9} {:>10} {:>10} {:>8} {:>8}",
            "seed", "rotation", "particles", "points", "rms", "rms rel", "slope", "seconds"
        );
        let runtime = runtime.runtime("hertz", &opts, threads)?;
        let report = run_hertz(&opts, &output, &launcher, &runtime, &mut |s| {
            let d = s.deviation;
            println!(
                "{:>6} {:>8} {:>9} {:>9} {:>10.4} {:>10.4} {:>8.3} {:>8.1}",
                s.seed,
                s.rotation,
                s.particles,
                d.map_or(0, |d| d.points),
                d.map_or(f64::NAN, |d| d.rms),
                d.map_or(f64::NAN, |d| d.rms_relative),
                d.map_or(f64::NAN, |d| d.loglog_slope),
                s.seconds
            );
            if let Some(reason) = &s.stopped {
                println!(
                    "{:>6} stopped at delta/R = {:.3}: {reason}",
                    "",
                    s.curve.overlap_over_r.last().copied().unwrap_or(f64::NAN)
                );
            }
            match &s.engines {
                Some(EngineAgreement {
                    force_deviation: Some(f),
                    gap_deviation: Some(g),
                    lammps_seconds,
                    ..
                }) => println!(
                    "{:>6} LAMMPS against native: largest force difference {f:.2e} of the largest force, wall gaps {g:.1e} d apart; LAMMPS {lammps_seconds:.1} s",
                    ""
                ),
                Some(EngineAgreement {
                    lammps_error: Some(e),
                    ..
                }) => println!("{:>6} LAMMPS stopped too: {e}", ""),
                _ => {}
            }
        })?;
        if let Some(d) = report.ensemble.deviation {
            println!(
                "ensemble of {}: rms deviation from Hertz {:.4} ({:.1}% relative), log-log slope {:.3} over delta/R in [0.02, 0.25]; E_eff = {:.4} from {}",
                report.squeezes.len(),
                d.rms,
                100.0 * d.rms_relative,
                d.loglog_slope,
                report.e_eff,
                report.options.moduli.source
            );
        }
        println!("wrote {}/hertz.json and hertz.svg", output.display());
        Ok(())
    }
}
