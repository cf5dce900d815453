//! `bpm bench`: whole-run throughput of the native engine, per stage.

use crate::engine::{Stage, StageDrivers, System};
use crate::scene::builders::bulk::{build_bulk, BulkParams};
use crate::scene::{build_system, ForceField, Scene, StageSpec};
use crate::verify::single_point::SinglePointError;
use serde::Serialize;

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
