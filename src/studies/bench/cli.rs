//! `bpm bench` and `bpm bench-lammps` from the command line.

use crate::studies::bench::{self, BenchOptions};
use crate::studies::print_line;
use anyhow::Result;
use std::path::PathBuf;

/// The arguments of `bpm bench`.
#[derive(clap::Args)]
pub struct BenchArgs {
    /// Box side of the bulk solid (d).
    #[arg(long, default_value_t = 14.0)]
    size: f64,
    /// Seed of the bulk solid.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Steps timed per case on the solid itself (fewer on its copies:
    /// about the same particle-steps per case, at least 20 steps).
    #[arg(long, default_value_t = 2000)]
    steps: u64,
    /// Copies of the solid per side for the cost against size (1 = the
    /// solid alone; 7 gives about 1.2 million particles at --size 14).
    #[arg(long, value_delimiter = ',', default_value = "1,2,4,7")]
    replicas: Vec<usize>,
    /// Grains of the compaction workload: the packing `bpm compact`
    /// builds, timed through the protocol's jam (barostat) and
    /// compression stages and against upstream LAMMPS (0 skips it)
    #[arg(long, default_value_t = 32)]
    packing_grains: usize,
    /// Grain radius R of the compaction workload (d)
    #[arg(long, default_value_t = 3.0)]
    packing_radius: f64,
    /// Steps timed in each stage of the compaction workload (fewer on its
    /// copies: about the same particle-steps per case, at least 20 steps)
    #[arg(long, default_value_t = 2000)]
    packing_steps: u64,
    /// Copies of the compaction workload's packing per side, for its cost
    /// against size (1 = the packing alone; 4 gives about 280,000 particles
    /// at the default packing)
    #[arg(long, value_delimiter = ',', default_value = "1")]
    packing_replicas: Vec<usize>,
    /// Spheres of the periodic DEM bed: the template of `bpm compact
    /// --model dem` squeezed into contact, held with plain Hertz and with
    /// the standard closure (0 skips it)
    #[arg(long, default_value_t = 1000)]
    dem_spheres: usize,
    /// Steps timed on the DEM bed (fewer on its copies: about the same
    /// sphere-steps per case, at least 20 steps)
    #[arg(long, default_value_t = 400)]
    dem_steps: u64,
    /// Copies of the DEM bed per side, for its cost against size (10 gives
    /// a million spheres at the default bed)
    #[arg(long, value_delimiter = ',', default_value = "1")]
    dem_replicas: Vec<usize>,
    /// Steps of the LIGGGHTS case: LIGGGHTS's hydrogel tutorial (514
    /// beads) under its closing lid, plain Hertz and the closure, in
    /// LIGGGHTS and natively (at most 30000, the lid's first pass; 0 skips
    /// it; skipped with a note when liggghts is not installed)
    #[arg(long, default_value_t = 30_000)]
    liggghts_steps: u64,
    /// Write the results as JSON too, and the plot beside it (.svg).
    #[arg(short, long)]
    output: Option<PathBuf>,
}

impl BenchArgs {
    /// `bpm bench`.
    pub fn run(self, threads: usize) -> Result<()> {
        let Self {
            size,
            seed,
            steps,
            replicas,
            packing_grains,
            packing_radius,
            packing_steps,
            packing_replicas,
            dem_spheres,
            dem_steps,
            dem_replicas,
            liggghts_steps,
            output,
        } = self;
        let opts = BenchOptions {
            size,
            seed,
            steps,
            replicas,
            packing: (packing_grains > 0).then_some(bench::PackingWorkload {
                grains: packing_grains,
                radius: packing_radius,
                steps: packing_steps,
                replicas: packing_replicas,
                seed,
            }),
            dem_bed: (dem_spheres > 0).then_some(bench::DemBedWorkload {
                spheres: dem_spheres,
                steps: dem_steps,
                replicas: dem_replicas,
                seed,
            }),
            liggghts_steps,
        };
        let lmp = std::env::current_exe()?.with_file_name("lmp-bpm");
        let bench = bench::run_bench(
            &opts,
            threads,
            Some(&lmp),
            output.as_deref(),
            &mut print_line,
        )?;
        println!("{}", bench.summary());
        for goal in bench.goals() {
            println!("{}", goal.line());
        }
        if let Some(path) = &output {
            bench.write(&opts, path)?;
            println!("wrote {} and its plot (.svg)", path.display());
        }
        Ok(())
    }
}

/// The arguments of `bpm bench-lammps`.
#[derive(clap::Args)]
pub struct BenchLammpsArgs {
    /// Box side of the bulk solid (d).
    #[arg(long, default_value_t = 14.0)]
    size: f64,
    /// Seed of the bulk solid.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Steps per variant.
    #[arg(long, default_value_t = 1000)]
    steps: u64,
}

impl BenchLammpsArgs {
    /// `bpm bench-lammps`.
    pub fn run(self, threads: usize) -> Result<()> {
        let Self { size, seed, steps } = self;
        let opts = BenchOptions {
            size,
            seed,
            steps,
            replicas: vec![1],
            packing: None,
            dem_bed: None,
            liggghts_steps: 0,
        };
        let lmp = std::env::current_exe()?.with_file_name("lmp-bpm");
        let bench = bench::run_bench_lammps(&opts, &lmp, threads, &mut print_line)?;
        for line in bench.ratios() {
            println!("{line}");
        }
        Ok(())
    }
}
