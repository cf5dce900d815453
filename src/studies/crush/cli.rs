//! `bpm crush`: grains of breakable or yielding bonds squeezed to failure,
//! from the command line.

use crate::scene::cli::{BondFailureArgs, GrainKindArg};
use crate::studies::crush::{run_crush, CrushOptions, CrushReport, MeanSd};
use crate::studies::hertz::GrainSource;
use crate::studies::RuntimeArgs;
use anyhow::Result;
use std::path::PathBuf;

/// eps_c when none is given.
const DEFAULT_CRITICAL_STRAIN: f64 = 0.05;

/// The arguments of `bpm crush`.
#[derive(clap::Args)]
pub struct CrushArgs {
    /// Grain kind to build (ignored with --grain).
    #[arg(long, value_enum, default_value = "smoother")]
    kind: GrainKindArg,
    /// Grain radius R (d): built grains' radius, and the nominal R of the
    /// overlap and of the normalisation.
    #[arg(long, default_value_t = 4.0)]
    radius: f64,
    /// Crush this grain (a scene JSON or a LAMMPS data file) as given.
    #[arg(long)]
    grain: Option<PathBuf>,
    /// Multibody strengths a_B (k d), comma separated: every grain is
    /// crushed at each (the paper's Poisson range is -0.8 to 3).
    #[arg(
        long = "a-b",
        value_delimiter = ',',
        allow_hyphen_values = true,
        default_value = "-0.8,0,3"
    )]
    a_bs: Vec<f64>,
    /// How the bonds break and yield (eps_c is 0.05 unless given).
    #[command(flatten)]
    failure: BondFailureArgs,
    /// How far the walls travel: their range plus (this + 0.05) R each,
    /// as the Hertz squeeze; the overlap from first contact ends near
    /// this + 0.05 + 0.9 d / R.
    #[arg(long, default_value_t = 0.5)]
    max_overlap: f64,
    /// Count the bonds broken and the fragments at this delta/R too, the
    /// same for every grain size (at most --max-overlap + 0.05, which every
    /// squeeze that runs to its end passes): the squeeze of a small grain
    /// ends further. Default: 0.5, or --max-overlap + 0.05 if smaller.
    #[arg(long)]
    compare_at: Option<f64>,
    /// Random rotations per grain (0: crushed as given).
    #[arg(long, default_value_t = 0)]
    rotations: usize,
    /// Seeds: one built grain per seed (comma separated).
    #[arg(long, value_delimiter = ',', default_value = "1")]
    seeds: Vec<u64>,
    /// Scale of the grain build's times (1 = the full protocol).
    #[arg(long, default_value_t = 1.0)]
    time_scale: f64,
    /// Records per squeeze.
    #[arg(long, default_value_t = 1000)]
    records: u64,
    /// Output folder.
    #[arg(short, long, required_unless_present = "from")]
    output: Option<PathBuf>,
    /// Rewrite the plot from an earlier crush.json without running
    /// anything (other options are ignored).
    #[arg(long)]
    from: Option<PathBuf>,
    #[command(flatten)]
    runtime: RuntimeArgs,
}

impl CrushArgs {
    /// `bpm crush`.
    pub fn run(self, threads: usize) -> Result<()> {
        if let Some(path) = &self.from {
            let output = self
                .output
                .clone()
                .unwrap_or_else(|| crate::studies::output::replot_folder(path));
            let report: CrushReport = crate::studies::output::replot(path, &output)?;
            print_cases(&report);
            println!("wrote {}/crush.json and crush.svg", output.display());
            return Ok(());
        }
        let Some(output) = self.output.clone() else {
            anyhow::bail!("give the output folder: -o DIR");
        };
        let Some(failure) = self.failure.failure(Some(DEFAULT_CRITICAL_STRAIN))? else {
            anyhow::bail!("give how the bonds break or yield: --critical-strain, --plastic-strain");
        };
        let opts = CrushOptions {
            source: match self.grain {
                Some(path) => GrainSource::File {
                    path,
                    radius: self.radius,
                },
                None => GrainSource::Build {
                    kind: self.kind.into(),
                    radius: self.radius,
                    time_scale: self.time_scale,
                },
            },
            seeds: self.seeds,
            a_bs: self.a_bs,
            rotations: self.rotations,
            failure,
            max_overlap: self.max_overlap,
            compare_at: self.compare_at,
            records: self.records,
            threads,
        };
        println!(
            "{:>6} {:>5} {:>4} {:>9} {:>14} {:>14} {:>9} {:>9} {:>10} {:>19} {:>8}",
            "a_B",
            "seed",
            "rot",
            "particles",
            "first break",
            "crushing",
            "broken",
            "fragments",
            "largest",
            format!("at delta/R {:.3}", opts.compared_at()),
            "seconds"
        );
        let runtime = self.runtime.runtime("crush", &opts, threads)?;
        let report = run_crush(&opts, &output, &runtime, &mut |c| {
            let point = |p: Option<crate::studies::crush::CurvePoint>| {
                p.map_or("-".to_string(), |p| {
                    format!("{:.3} ({:.3})", p.overlap_over_r, p.normalised_force)
                })
            };
            println!(
                "{:>6} {:>5} {:>4} {:>9} {:>14} {:>14} {:>8.2}% {:>9} {:>9.1}% {:>19} {:>8.1}",
                c.a_b,
                c.seed,
                c.rotation,
                c.particles,
                point(c.first_break),
                point(c.crushing),
                100.0 * c.broken_fraction.last().copied().unwrap_or(0.0),
                c.large_fragments,
                100.0 * c.fragments.largest_fraction(),
                c.compared.as_ref().map_or("-".to_string(), |s| format!(
                    "{:.2}% {} {:.1}%",
                    100.0 * s.broken_fraction,
                    s.large_fragments,
                    100.0 * s.fragments.largest_fraction()
                )),
                c.seconds
            );
            if let Some(reason) = &c.stopped {
                println!(
                    "{:>6} stopped at delta/R = {:.3}: {reason}",
                    "",
                    c.curve.overlap_over_r.last().copied().unwrap_or(f64::NAN)
                );
            }
        })?;
        println!(
            "(points: delta/R (3 f / (8 R^2 E_eff)); fragments of at least 1% of the grain; \
         at delta/R {:.3}: broken, fragments, largest)",
            opts.compared_at()
        );
        print_cases(&report);
        println!("wrote {}/crush.json and crush.svg", output.display());
        Ok(())
    }
}

/// Each a_B's means and spreads.
fn print_cases(report: &CrushReport) {
    let show =
        |m: Option<MeanSd>| m.map_or("-".to_string(), |m| format!("{:.4} +- {:.4}", m.mean, m.sd));
    for case in &report.cases {
        println!(
            "a_B = {} (nu {:.3}, E_eff {:.4}): crushed {} of {}; first break at delta/R {}; \
                 crushing force / (E_eff R^2) {} at delta/R {}; broken {}; large fragments {}; \
                 largest fragment {}; at delta/R {:.3} ({}): broken {}, large fragments {}, \
                 largest {}",
            case.a_b,
            case.moduli.nu,
            case.e_eff,
            case.crushed,
            case.crushes.len(),
            show(case.first_break_overlap),
            show(case.crushing_force),
            show(case.crushing_overlap),
            show(case.broken_fraction),
            show(case.large_fragments),
            show(case.largest_fragment),
            report.options.compared_at(),
            case.compared_broken_fraction
                .map_or("no squeeze counted there".into(), |m| format!(
                    "{} of {} squeezes reached it",
                    m.count,
                    case.crushes.len()
                )),
            show(case.compared_broken_fraction),
            show(case.compared_large_fragments),
            show(case.compared_largest_fragment),
        );
    }
}
