//! Reading a scene and turning it into an engine system.

use super::model::{ModelKind, Scene};
use super::validate::{simbox_of, validate, SceneError};
use crate::engine::particles::DEFAULT_RADIUS;
use crate::engine::{BondTopology, BpmModel, DemModel, Gravity, ParticleModel, Particles, System};
use crate::kernels::Separation;
use std::path::Path;

/// Reads and validates a scene file.
pub fn read_scene(path: &Path) -> Result<(Scene, u64), SceneError> {
    let bytes = std::fs::read(path).map_err(|cause| SceneError::Io {
        path: path.display().to_string(),
        cause,
    })?;
    let scene: Scene = serde_json::from_slice(&bytes)?;
    validate(&scene)?;
    Ok((scene, fnv1a(&bytes)))
}

/// Reads a scene file without validating it: for scenes that are inputs
/// to a study (a grain with no stages yet), validated once the study has
/// added its stages.
pub fn read_scene_unvalidated(path: &Path) -> Result<Scene, SceneError> {
    let bytes = std::fs::read(path).map_err(|cause| SceneError::Io {
        path: path.display().to_string(),
        cause,
    })?;
    Ok(serde_json::from_slice(&bytes)?)
}

/// Writes a scene as JSON.
pub fn write_scene(path: &Path, scene: &Scene) -> Result<(), SceneError> {
    let text = serde_json::to_string(scene)?;
    std::fs::write(path, text).map_err(|cause| SceneError::Io {
        path: path.display().to_string(),
        cause,
    })
}

/// 64-bit FNV-1a of the scene file, recorded in outputs to tie results to
/// the exact input.
pub fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// The engine model of a validated scene, with its own state (for the
/// bonded particle model: the bonds and their reference lengths).
///
/// # Panics
///
/// On a scene of model `dem` without `force_field.granular`, which
/// validation refuses.
pub fn model_of(scene: &Scene) -> Box<dyn ParticleModel> {
    let n = scene.particles.positions.len();
    match scene.model {
        ModelKind::Bpm => {
            let strains = scene.bonds.plastic_strain.as_deref();
            let bonds: Vec<(usize, usize, f64, f64)> = scene
                .bonds
                .pairs
                .iter()
                .zip(reference_lengths(scene))
                .enumerate()
                .map(|(k, (&[i, j], r0))| {
                    (
                        i,
                        j,
                        r0,
                        strains.and_then(|e| e.get(k)).copied().unwrap_or(0.0),
                    )
                })
                .collect();
            let bonds = BondTopology::with_plastic_strains(n, &bonds);
            let ff = &scene.force_field;
            Box::new(BpmModel::new(ff.bpm(), n, bonds))
        }
        ModelKind::Dem => {
            let max_radius = scene
                .particles
                .radius
                .as_deref()
                .map_or(DEFAULT_RADIUS, |r| r.iter().copied().fold(0.0, f64::max));
            // Validation requires the material for this model.
            let material = scene
                .force_field
                .granular
                .expect("a validated dem scene has force_field.granular");
            Box::new(DemModel::new(
                material,
                max_radius,
                scene.force_field.multicontact,
            ))
        }
    }
}

/// The particle arrays of a validated scene, defaults filled in.
pub fn particles_of(scene: &Scene) -> Particles {
    let pa = &scene.particles;
    let n = pa.positions.len();
    let mut p = Particles::at_rest(pa.positions.clone());
    if let Some(v) = &pa.velocities {
        p.v = v.clone();
    }
    if let Some(g) = &pa.grain {
        p.grain = g.clone();
    }
    if let Some(t) = &pa.kind {
        p.kind = t.clone();
    }
    if let Some(r) = &pa.radius {
        p.radius = r.clone();
    }
    if let Some(w) = &pa.angular_velocities {
        p.enable_rotation();
        if let Some(rotation) = &mut p.rotation {
            rotation.omega = w.clone();
        }
    }
    p.mass = pa.mass.values(n);
    p
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

/// `scene` with the state of `sys` after a run: positions, velocities,
/// box, bonds with their reference lengths; stages as before.
pub fn final_scene(scene: &Scene, sys: &System) -> Scene {
    let mut fin = scene.clone();
    fin.version = super::SCENE_VERSION;
    fin.particles.positions = sys.particles.x.clone();
    fin.particles.velocities = Some(sys.particles.v.clone());
    if let Some(rotation) = &sys.particles.rotation {
        fin.particles.angular_velocities = Some(rotation.omega.clone());
    }
    fin.simbox.lo = sys.simbox.lo;
    fin.simbox.lengths = sys.simbox.lengths;
    fin.simbox.tilt = sys.simbox.tilt;
    if let Some(bpm) = sys.model_as::<BpmModel>() {
        let bonds = bpm.bonds();
        fin.bonds.pairs = bonds.pairs().collect();
        fin.bonds.r0 = Some(bonds.r0.clone());
        let plastic = bpm.plastic_strains();
        fin.bonds.plastic_strain = plastic.iter().any(|&e| e != 0.0).then_some(plastic);
    }
    fin
}

/// Builds the engine system of a validated scene.
pub fn build_system(scene: &Scene, threads: usize) -> System {
    let mut sys = System::new(
        simbox_of(scene),
        particles_of(scene),
        model_of(scene),
        scene.force_field.skin,
        threads,
    );
    sys.gravity = scene.force_field.gravity.map(Gravity::new);
    sys
}
