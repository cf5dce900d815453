//! Reading a scene and turning it into an engine system.

use super::model::{ForceField, Scene};
use super::validate::{simbox_of, validate, SceneError};
use crate::engine::{
    BondTopology, BpmModel, ForceModel, NeighbourList, StepReport, System, Timers,
};
use crate::kernels::Separation;
use std::path::Path;

/// Reads and validates a scene file.
pub fn read_scene(path: &Path) -> Result<(Scene, u64), SceneError> {
    let bytes = std::fs::read(path).map_err(|source| SceneError::Io {
        path: path.display().to_string(),
        source,
    })?;
    let scene: Scene = serde_json::from_slice(&bytes)?;
    validate(&scene)?;
    Ok((scene, fnv1a(&bytes)))
}

/// Writes a scene as JSON.
pub fn write_scene(path: &Path, scene: &Scene) -> Result<(), SceneError> {
    let text = serde_json::to_string(scene)?;
    std::fs::write(path, text).map_err(|source| SceneError::Io {
        path: path.display().to_string(),
        source,
    })
}

/// 64-bit FNV-1a of the scene file, recorded in outputs to tie results to
/// the exact input.
pub fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// The engine model for a force field over the given bonds.
pub fn model_of(ff: &ForceField, n: usize, bonds: &BondTopology) -> ForceModel {
    ForceModel::Bpm(BpmModel::new(ff.bond, ff.pair, n, bonds))
}

/// The reference length of every bond of a validated scene, in scene order:
/// the given `r0`, or else the bond's minimum-image length at load. Both
/// engines take their reference from here.
pub fn reference_lengths(scene: &Scene) -> Vec<f64> {
    if let Some(r0) = &scene.bonds.r0 {
        return r0.clone();
    }
    let simbox = simbox_of(scene);
    let x = &scene.particles.positions;
    scene
        .bonds
        .pairs
        .iter()
        .map(|&[i, j]| simbox.distance(&x[i], &x[j]))
        .collect()
}

/// Builds the engine system of a validated scene.
pub fn build_system(scene: &Scene, threads: usize) -> System {
    let simbox = simbox_of(scene);
    let pa = &scene.particles;
    let n = pa.positions.len();
    let triples: Vec<(usize, usize, f64)> = scene
        .bonds
        .pairs
        .iter()
        .zip(reference_lengths(scene))
        .map(|(&[i, j], r0)| (i, j, r0))
        .collect();
    let bonds = BondTopology::new(n, &triples);
    let model = model_of(&scene.force_field, n, &bonds);
    System {
        simbox,
        x: pa.positions.clone(),
        v: pa.velocities.clone().unwrap_or_else(|| vec![[0.0; 3]; n]),
        f: vec![[0.0; 3]; n],
        image: vec![[0; 3]; n],
        grain: pa.grain.clone().unwrap_or_else(|| vec![0; n]),
        mass: pa.mass,
        bonds,
        model,
        neighbours: NeighbourList::default(),
        skin: scene.force_field.skin,
        threads: threads.max(1),
        step: 0,
        time: 0.0,
        timers: Timers::default(),
        report: StepReport::default(),
        wraps: 0,
    }
}
