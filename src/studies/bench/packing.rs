//! The compaction workload of `bpm bench`: the jammed packing of bonded
//! grains that `bpm compact` builds, run through the protocol's own stages
//! (the barostat's jam, summing energies and virials every step, then an
//! isotropic compression), at a_B = 0 and -0.5 on one and two threads; and
//! the same packing, squeezed and held, in upstream LAMMPS's `bpm/spring`
//! beside the native engine in the same run ([`super::upstream_speeds`]).
//!
//! Unlike the bulk solid, a packing has contacts inside and between grains,
//! neighbour rebuilds, a box that changes every step and fewer bonds per
//! particle (grain surfaces): this is what the studies spend their time on.

use super::{
    check_copies, faster_on_1_and_2, scene_case, steps_on_copies, upstream_speeds, BenchCase,
    BenchError, UpstreamSpeed, BENCH_STRAIN,
};
use crate::scene::builders::grain::GrainKind;
use crate::scene::builders::packing::{build_packing, PackingParams};
use crate::scene::builders::replicate::replicate;
use crate::scene::protocols::CompactionProtocol;
use crate::scene::{ForceField, Scene};
use serde::Serialize;

/// Which packing the compaction workload times.
#[derive(Clone, Debug, Serialize)]
pub struct PackingWorkload {
    /// Grains (`bpm compact`'s default: 32).
    pub grains: usize,
    /// Grain radius R (d; `bpm compact`'s default: 3).
    pub radius: f64,
    /// Steps timed in each of the two stages (on the packing itself; its
    /// copies run about the same particle-steps, at least 20 steps).
    pub steps: u64,
    /// Copies of the packing per side for the cost against size (1 = the
    /// packing alone, which the goals and the upstream comparison use).
    pub replicas: Vec<usize>,
    /// Seed of the packing.
    pub seed: u64,
}

impl PackingWorkload {
    /// Refuses, naming the option, what the packing builder would refuse
    /// only after the bulk cases have run.
    pub fn validate(&self) -> Result<(), BenchError> {
        let bad = |option: &str, requirement: String| {
            Err(BenchError::Options(format!("{option} {requirement}")))
        };
        if !(self.radius.is_finite() && self.radius >= 1.5) {
            return bad(
                "--packing-radius",
                format!("must be at least 1.5 (d), got {}", self.radius),
            );
        }
        if self.grains < 2 {
            return bad(
                "--packing-grains",
                format!("must be 0 (skip) or at least 2, got {}", self.grains),
            );
        }
        if self.steps == 0 {
            return bad("--packing-steps", "must be at least 1".into());
        }
        check_copies("--packing-replicas", &self.replicas)
    }
}

/// What the compaction workload measured.
#[derive(Clone, Debug, Default, Serialize)]
pub struct PackingBench {
    /// Particles and bonds of the packing.
    pub particles: usize,
    /// Bonds.
    pub bonds: usize,
    /// The protocol's stages, per a_B and thread count.
    pub cases: Vec<BenchCase>,
    /// The squeezed packing held in upstream LAMMPS and natively.
    pub upstream: Vec<UpstreamSpeed>,
}

/// The jam stage of `bpm compact`'s default protocol (barostat at
/// 1e-6 k/d, gain 1) and one compression stage at its fourth rate
/// (10^-5.5 per tau), each `steps` long.
pub fn workload_protocol(steps: u64) -> CompactionProtocol {
    let dt = 0.1;
    let rate = 10f64.powf(-5.5);
    CompactionProtocol {
        dt,
        jam_pressure: 1e-6,
        jam_gain: 1.0,
        jam_time: steps as f64 * dt,
        rate_start: rate,
        rate_end: rate,
        rate_levels: 1,
        stage_time: steps as f64 * dt,
        // Exactly one compression stage at the rate.
        volumetric_strain: 1.0 - (-3.0 * rate * steps as f64 * dt).exp(),
        rows_per_stage: 2,
        states_per_stage: 1,
        unload_rate: 0.0,
    }
}

/// Builds the packing and times it; `log` receives each line.
pub fn bench_packing(
    workload: &PackingWorkload,
    threads: usize,
    log: &mut dyn FnMut(&str),
) -> Result<PackingBench, BenchError> {
    let params = PackingParams::new(
        workload.grains,
        GrainKind::Smoother,
        workload.radius,
        0.0,
        workload.seed,
    );
    let (packing, _) = build_packing(&params, threads, false)?;
    let mut bench = PackingBench {
        particles: packing.particles.positions.len(),
        bonds: packing.bonds.pairs.len(),
        ..PackingBench::default()
    };
    let name = format!("packing {} grains R={}", workload.grains, workload.radius);
    for &k in &workload.replicas {
        let copies = replicate(&packing, [k; 3])?;
        let steps = steps_on_copies(workload.steps, k);
        let name = match k {
            1 => name.clone(),
            _ => format!("{name} x{}", k * k * k),
        };
        for a_b in [0.0, -0.5] {
            bench.cases.extend(faster_on_1_and_2(log, |threads| {
                protocol_case(&copies, &name, a_b, threads, steps)
            }));
        }
    }
    bench.upstream = upstream_speeds(&packing, &name, workload.steps, BENCH_STRAIN, log);
    Ok(bench)
}

/// The protocol's jam and compression stages on `packing` at `a_b`, timed
/// together.
fn protocol_case(packing: &Scene, name: &str, a_b: f64, threads: usize, steps: u64) -> BenchCase {
    let mut scene = packing.clone();
    scene.force_field = ForceField::paper(a_b);
    scene.stages = workload_protocol(steps).stages();
    let name = format!("{name} a_B={a_b} threads={threads}");
    let ws = super::working_set_bytes(scene.particles.positions.len(), scene.bonds.pairs.len());
    scene_case(&scene, name, a_b, threads, ws)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn copies_per_side_must_be_at_least_one() {
        let workload = |replicas: Vec<usize>| PackingWorkload {
            grains: 32,
            radius: 3.0,
            steps: 100,
            replicas,
            seed: 1,
        };
        assert!(workload(vec![1, 2]).validate().is_ok());
        for bad in [vec![], vec![1, 0]] {
            let message = workload(bad).validate().unwrap_err().to_string();
            assert!(message.contains("--packing-replicas"), "{message}");
        }
    }

    #[test]
    fn the_workload_is_one_jam_and_one_compression_stage_of_the_given_steps() {
        let stages = workload_protocol(2000).stages();
        let names: Vec<&str> = stages.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(names, ["jam", "compress-0"]);
        assert!(stages.iter().all(|s| s.steps == 2000), "{stages:?}");
        assert!(stages[0].barostat.is_some() && stages[1].deformation.is_some());
    }
}
