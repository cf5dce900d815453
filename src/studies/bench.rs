//! The benchmarks: whole-run throughput of the native engine per part of
//! the step (`bpm bench`, [`run_bench`]), and the plugin's bond time in
//! LAMMPS against `bond_style harmonic` (`bpm bench-lammps`,
//! [`run_bench_lammps`]).

use crate::engine::{Stage, StageDrivers, System};
use crate::file_error::FileError;
use crate::scene::builders::bulk::{build_bulk, BulkParams};
use crate::scene::{build_system, ForceField, Scene, StageSpec};
use crate::verify::single_point::SinglePointError;
use serde::Serialize;
use std::path::Path;

/// Why a benchmark could not finish. Each message carries its cause once.
#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    /// The bulk solid could not be built.
    #[error(transparent)]
    Scene(#[from] crate::scene::SceneError),
    /// The LAMMPS run failed.
    #[error(transparent)]
    Lammps(#[from] SinglePointError),
    /// LAMMPS's timing breakdown lacks a line.
    #[error("{0}")]
    Timing(String),
    /// A file or folder could not be created, written or read.
    #[error(transparent)]
    File(#[from] FileError),
}

/// What both benchmarks run: the bulk solid and the steps timed.
#[derive(Clone, Debug)]
pub struct BenchOptions {
    /// Box side of the bulk solid (d).
    pub size: f64,
    /// Seed of the bulk solid.
    pub seed: u64,
    /// Steps timed per case (per variant in LAMMPS).
    pub steps: u64,
}

/// One measured case.
#[derive(Clone, Debug, Serialize)]
pub struct BenchCase {
    /// Case name.
    pub name: String,
    /// Multibody strength.
    pub a_b: f64,
    /// Threads.
    pub threads: usize,
    /// Particles.
    pub particles: usize,
    /// Bonds.
    pub bonds: usize,
    /// Steps timed.
    pub steps: u64,
    /// Nanoseconds per particle-step, whole step.
    pub ns_per_particle_step: f64,
    /// Nanoseconds per particle-step in each part of the step.
    pub breakdown: Vec<(String, f64)>,
}

impl BenchCase {
    /// The case as one line: ns per particle-step and the parts of the
    /// step above 0.05 ns.
    pub fn line(&self) -> String {
        let parts: Vec<String> = self
            .breakdown
            .iter()
            .filter(|(_, v)| *v > 0.05)
            .map(|(k, v)| format!("{k} {v:.1}"))
            .collect();
        format!(
            "{:<36} {:>5} particles {:>6} bonds  {:>7.1} ns per particle-step  [{}]",
            self.name,
            self.particles,
            self.bonds,
            self.ns_per_particle_step,
            parts.join(", ")
        )
    }
}

/// What [`run_bench`] measured.
#[derive(Clone, Debug)]
pub struct Bench {
    /// a_B = 0 and -0.5 on 1 and 2 threads.
    pub cases: Vec<BenchCase>,
}

impl Bench {
    fn ns(&self, a_b: f64, threads: usize) -> f64 {
        self.cases
            .iter()
            .find(|c| c.a_b == a_b && c.threads == threads)
            .map_or(f64::NAN, |c| c.ns_per_particle_step)
    }

    /// The multibody term's cost and the 2-thread speed-ups, as one line.
    pub fn summary(&self) -> String {
        format!(
            "multibody cost (a_B=-0.5 / a_B=0, 1 thread): {:.2}x   2-thread speed-up: {:.2}x (a_B=0), {:.2}x (a_B=-0.5)",
            self.ns(-0.5, 1) / self.ns(0.0, 1),
            self.ns(0.0, 1) / self.ns(0.0, 2),
            self.ns(-0.5, 1) / self.ns(-0.5, 2)
        )
    }
}

/// `bpm bench`: builds the bulk solid with `threads` threads and times it
/// at a_B = 0 and -0.5 on 1 and 2 threads; writes the cases as JSON to
/// `output` if given. `log` receives each case's line as it is measured.
pub fn run_bench(
    opts: &BenchOptions,
    threads: usize,
    output: Option<&Path>,
    log: &mut dyn FnMut(&str),
) -> Result<Bench, BenchError> {
    let solid = bench_solid(opts.size, opts.seed, threads)?;
    let mut cases = Vec::new();
    for a_b in [0.0, -0.5] {
        for threads in [1, 2] {
            let case = bench_case(&solid, a_b, threads, opts.steps);
            log(&case.line());
            cases.push(case);
        }
    }
    if let Some(path) = output {
        let report = serde_json::json!({
            "program": "bpm bench", "version": crate::VERSION, "size": opts.size, "seed": opts.seed, "steps": opts.steps, "cases": cases,
        });
        crate::verify::write_json(path, &report).map_err(FileError::on("writing", path))?;
    }
    Ok(Bench { cases })
}

/// Builds the bulk solid used by the benchmark (the L = 14 d system of
/// docs/reference-numbers.md, "Cost reference points" by default).
pub fn bench_solid(
    size: f64,
    seed: u64,
    threads: usize,
) -> Result<Scene, crate::scene::SceneError> {
    Ok(build_bulk(&BulkParams::paper(size, seed, 0.0), threads, false)?.0)
}

/// Times `steps` steps of `solid` at multibody `a_b` with `threads`, after
/// a short warm-up, with the paper's damping and contacts on.
pub fn bench_case(solid: &Scene, a_b: f64, threads: usize, steps: u64) -> BenchCase {
    let mut scene = solid.clone();
    scene.force_field = ForceField::paper(a_b);
    scene.stages = vec![StageSpec::hold("bench", steps, 0.1)];
    let mut sys: System = build_system(&scene, threads);
    // A small strain so bonds carry force and the multibody term is not 0 / 0.
    let mut strained = sys.simbox.clone();
    strained.resize_about_centre(sys.simbox.lengths.map(|l| l * 0.999), [0.0; 3]);
    sys.remap_into(strained);
    let drivers = StageDrivers {
        dt: 0.1,
        ..StageDrivers::default()
    };
    let stage_box = sys.simbox.clone();
    sys.setup(&drivers);
    for k in 1..=20 {
        let _ = sys.step(&drivers, k, &stage_box);
    }
    sys.timers = Default::default();
    let start = std::time::Instant::now();
    for k in 21..=20 + steps {
        let _ = sys.step(&drivers, k, &stage_box);
    }
    let total = start.elapsed().as_secs_f64();
    let per = |secs: f64| secs * 1e9 / (steps as f64 * sys.len() as f64);
    BenchCase {
        name: format!(
            "bulk L={} a_B={a_b} threads={threads}",
            solid.simbox.lengths[0]
        ),
        a_b,
        threads,
        particles: sys.len(),
        bonds: sys
            .model_as::<crate::engine::BpmModel>()
            .map_or(0, |m| m.bonds().len()),
        steps,
        ns_per_particle_step: per(total),
        breakdown: Stage::ALL
            .iter()
            .map(|s| {
                (
                    s.name().to_string(),
                    per(sys.timers.total(*s).as_secs_f64()),
                )
            })
            .collect(),
    }
}

/// Time spent in LAMMPS's bond computation, from its timing breakdown.
#[derive(Clone, Debug, Serialize)]
pub struct LammpsBondTiming {
    /// Variant: "harmonic", "bpm a_B=..." and so on.
    pub name: String,
    /// Bond time per particle-step (ns).
    pub bond_ns: f64,
    /// Whole loop per particle-step (ns).
    pub loop_ns: f64,
}

/// Runs `lmp-bpm` on `lammps_inputs/bench_bonds.in` for one variant and
/// reads the bond and loop times from LAMMPS's output.
pub fn lammps_bond_timing(
    lmp_bpm: &std::path::Path,
    solid: &Scene,
    dir: &std::path::Path,
    style: &str,
    a_b: f64,
    steps: u64,
) -> Result<LammpsBondTiming, BenchError> {
    let mut scene = solid.clone();
    scene.force_field = ForceField::paper(a_b);
    let vars = [("style", style.to_string()), ("steps", steps.to_string())];
    let text = crate::verify::run_lmp_bpm(
        lmp_bpm,
        &scene,
        "bench_bonds.in",
        true,
        1,
        dir,
        &format!("bench-{a_b}"),
        &vars,
        steps,
    )?;
    let field = |prefix: &str, col: usize| -> Option<f64> {
        let line = text.lines().find(|l| l.starts_with(prefix))?;
        line.split(['|', ' '])
            .filter(|t| !t.is_empty())
            .nth(col)?
            .parse()
            .ok()
    };
    let missing = |what: &str| BenchError::Timing(what.into());
    let bond = field("Bond    |", 2).ok_or_else(|| missing("no Bond line in LAMMPS timing"))?;
    let total = field("Loop time of", 3).ok_or_else(|| missing("no loop time"))?;
    let per = |secs: f64| secs * 1e9 / (steps as f64 * solid.particles.positions.len() as f64);
    Ok(LammpsBondTiming {
        name: format!("{style} a_B={a_b}"),
        bond_ns: per(bond),
        loop_ns: per(total),
    })
}

impl LammpsBondTiming {
    /// The variant as one line: bond and loop time per particle-step.
    pub fn line(&self) -> String {
        format!(
            "{:<24} bond {:>7.1} ns per particle-step   loop {:>7.1}",
            self.name, self.bond_ns, self.loop_ns
        )
    }
}

/// The variants of `bpm bench-lammps`: bond style (`harmonic`, ours
/// `bpm`, ours without damping `nodamp`) and a_B; the first is the
/// reference.
pub const LAMMPS_VARIANTS: [(&str, f64); 5] = [
    ("harmonic", 0.0),
    ("bpm", 0.0),
    ("nodamp", 0.0),
    ("bpm", -0.5),
    ("nodamp", -0.5),
];

/// What [`run_bench_lammps`] measured.
#[derive(Clone, Debug)]
pub struct LammpsBench {
    /// One timing per variant of [`LAMMPS_VARIANTS`], in order.
    pub timings: Vec<LammpsBondTiming>,
}

impl LammpsBench {
    /// Each variant's bond time against `bond_style harmonic`'s, one line
    /// per variant.
    pub fn ratios(&self) -> Vec<String> {
        let Some((harmonic, rest)) = self.timings.split_first() else {
            return Vec::new();
        };
        rest.iter()
            .map(|t| {
                format!(
                    "{:<24} bond time / harmonic = {:.2}x",
                    t.name,
                    t.bond_ns / harmonic.bond_ns
                )
            })
            .collect()
    }
}

/// `bpm bench-lammps`: builds the bulk solid with `threads` threads and
/// times every variant of [`LAMMPS_VARIANTS`] with `lmp_bpm`, in one
/// session, in a temporary folder removed afterwards. `log` receives each
/// variant's line as it is measured.
pub fn run_bench_lammps(
    opts: &BenchOptions,
    lmp_bpm: &Path,
    threads: usize,
    log: &mut dyn FnMut(&str),
) -> Result<LammpsBench, BenchError> {
    let solid = bench_solid(opts.size, opts.seed, threads)?;
    let dir = std::env::temp_dir().join(format!("bpm-bench-lammps-{}", std::process::id()));
    std::fs::create_dir_all(&dir).map_err(FileError::on("creating", &dir))?;
    let timings = LAMMPS_VARIANTS
        .iter()
        .map(|&(style, a_b)| {
            let t = lammps_bond_timing(lmp_bpm, &solid, &dir, style, a_b, opts.steps)?;
            log(&t.line());
            Ok(t)
        })
        .collect::<Result<Vec<_>, BenchError>>();
    let _ = std::fs::remove_dir_all(&dir);
    Ok(LammpsBench { timings: timings? })
}
