//! `bpm`: build scenes, run them on the native engine, benchmark it.

use anyhow::{bail, Context, Result};
use bpm::scene::builders::bulk::{build_bulk, BulkParams};
use bpm::scene::{build_system, protocols, read_scene, run_scene, write_scene, RunOptions};
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
        what: BuildWhat,
    },
    /// Run a scene on the native engine and write the recorded observables.
    Run {
        /// Scene file (JSON).
        scene: PathBuf,
        /// Output file (JSON).
        #[arg(short, long)]
        output: PathBuf,
        /// Also write the final state as a scene.
        #[arg(long)]
        final_scene: Option<PathBuf>,
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
    /// Cross-check the LAMMPS plugin against the native engine on the
    /// built-in scenes (forces and pressure at one step, 1 and 2 MPI ranks).
    Crosscheck {
        /// Box side of the built-in contact solid (d).
        #[arg(long, default_value_t = 8.0)]
        size: f64,
        /// Seed of the built-in scenes.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Write the verdicts as JSON.
        #[arg(short, long)]
        output: Option<PathBuf>,
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
    /// The periodic bulk solid of MODEL.md "Bulk solid".
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
        } => {
            let (scene, hash) =
                read_scene(&path).with_context(|| format!("reading scene {}", path.display()))?;
            let mut sys = build_system(&scene, cli.threads);
            let start = std::time::Instant::now();
            let (stages, error) = run_scene(
                &mut sys,
                &scene,
                &RunOptions {
                    threads: cli.threads,
                    progress,
                },
            );
            let report = serde_json::json!({
                "program": "bpm run",
                "version": bpm::VERSION,
                "scene_file": path.display().to_string(),
                "scene_fnv1a": format!("{hash:016x}"),
                "seed": scene.seed,
                "threads": cli.threads,
                "particles": sys.len(),
                "bonds": sys.bonds.len(),
                "force_field": scene.force_field,
                "protocol": scene.stages,
                "provenance": scene.provenance,
                "wall_seconds": start.elapsed().as_secs_f64(),
                "error": error.as_ref().map(|e| e.to_string()),
                "stages": stages,
            });
            std::fs::write(&output, serde_json::to_string(&report)?)
                .with_context(|| format!("writing {}", output.display()))?;
            if let Some(final_path) = final_scene {
                let mut fin = scene.clone();
                fin.particles.positions = sys.x.clone();
                fin.particles.velocities = Some(sys.v.clone());
                fin.simbox.lo = sys.simbox.lo;
                fin.simbox.lengths = sys.simbox.lengths;
                fin.simbox.tilt = sys.simbox.tilt;
                fin.bonds.pairs = sys
                    .bonds
                    .entries
                    .iter()
                    .map(|b| [b.i as usize, b.j as usize])
                    .collect();
                fin.bonds.r0 = Some(sys.bonds.r0.clone());
                write_scene(&final_path, &fin)?;
            }
            for s in &stages {
                println!(
                    "stage {:<12} {:>9} steps  {:>8.2} s  neighbour builds {}",
                    s.name, s.steps, s.wall_seconds, s.neighbour_builds
                );
            }
            if let Some(e) = error {
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
        Command::Crosscheck { size, seed, output } => {
            crosscheck(size, seed, output)?;
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

/// Tolerances of the single-step cross-check. Both engines call the same
/// kernels on the same numbers and differ only in summation order: measured
/// 4e-16 to 1e-14 relative on the built-in scenes, 1 or 2 ranks. The
/// tolerances leave two decades (one rank) and four (two ranks, where
/// ghost contributions are also summed in another order) of margin.
const SINGLE_RANK_TOLERANCE: f64 = 1e-12;
const TWO_RANK_TOLERANCE: f64 = 1e-10;

fn crosscheck(size: f64, seed: u64, output: Option<PathBuf>) -> Result<()> {
    use bpm::verify::{
        contact_solid, lammps_single_point, max_relative_deviation, native_single_point,
    };
    let lmp = std::env::current_exe()?.with_file_name("lmp-bpm");
    let dir = std::env::temp_dir().join(format!("bpm-crosscheck-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    println!(
        "{:<34} {:>5} {:>6} {:>12} {:>12} {:>9} {:>7} {:>9} {:>9}",
        "scene",
        "ranks",
        "newton",
        "force dev",
        "press. dev",
        "tolerance",
        "verdict",
        "native s",
        "lammps s"
    );
    let mut rows = Vec::new();
    let mut failed = 0;
    let base = contact_solid(size, seed, 0.0)?;
    for a_b in [0.0, -0.5, 1.0] {
        let mut scene = base.clone();
        scene.force_field = bpm::scene::ForceField::paper(a_b);
        let t0 = std::time::Instant::now();
        let native = native_single_point(&scene);
        let native_s = t0.elapsed().as_secs_f64();
        for (ranks, newton) in [(1, true), (2, true), (2, false)] {
            let t1 = std::time::Instant::now();
            let lammps = lammps_single_point(
                &lmp,
                &scene,
                newton,
                ranks,
                &dir,
                &format!("x{a_b}-{ranks}-{newton}"),
            )?;
            let lammps_s = t1.elapsed().as_secs_f64();
            let force_dev = max_relative_deviation(&lammps.forces, &native.forces);
            let pscale = native.pressure.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let press_dev = lammps
                .pressure
                .iter()
                .zip(&native.pressure)
                .map(|(a, b)| (a - b).abs() / pscale)
                .fold(0.0f64, f64::max);
            let tol = if ranks == 1 {
                SINGLE_RANK_TOLERANCE
            } else {
                TWO_RANK_TOLERANCE
            };
            let pass = force_dev < tol && press_dev < tol;
            failed += usize::from(!pass);
            let name = format!("contact solid L={size} a_B={a_b}");
            println!(
                "{:<34} {:>5} {:>6} {:>12.3e} {:>12.3e} {:>9.0e} {:>7} {:>9.3} {:>9.3}",
                name,
                ranks,
                if newton { "on" } else { "off" },
                force_dev,
                press_dev,
                tol,
                if pass { "pass" } else { "FAIL" },
                native_s,
                lammps_s
            );
            rows.push(serde_json::json!({
                "scene": name, "a_B": a_b, "ranks": ranks, "newton": newton,
                "max_force_deviation": force_dev, "max_pressure_deviation": press_dev,
                "tolerance": tol, "pass": pass, "native_seconds": native_s, "lammps_seconds": lammps_s,
            }));
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    if let Some(path) = output {
        let report = serde_json::json!({
            "program": "bpm crosscheck", "version": bpm::VERSION, "size": size, "seed": seed,
            "lammps": "Debian 29Sep2021 update 2 + lammps-plugin", "rows": rows,
        });
        std::fs::write(&path, serde_json::to_string_pretty(&report)?)?;
        println!("wrote {}", path.display());
    }
    if failed > 0 {
        bail!("{failed} cross-check rows failed");
    }
    println!("all {} cross-check rows pass", rows.len());
    Ok(())
}
