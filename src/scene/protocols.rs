//! Ready-made protocol stages (docs/protocols.md).

use super::model::{Record, Scene, StageSpec};
use crate::engine::{Deformation, FlatWall, Tether, TiltFactor, WallSide};
use serde::{Deserialize, Serialize};

/// Holds the configuration for `steps` steps, recording every `every`.
pub fn relax(steps: u64, dt: f64, every: u64) -> StageSpec {
    let mut s = StageSpec::hold("relax", steps, dt);
    s.record = Record {
        every,
        positions_every: 0,
    };
    s
}

/// Number of steps to reach `strain` at `rate` with time step `dt`.
pub fn steps_for_strain(strain: f64, rate: f64, dt: f64) -> u64 {
    (strain / (rate * dt)).abs().round().max(1.0) as u64
}

/// Isotropic compression to volumetric strain about `3 strain` at true
/// strain rate `rate` per dimension, affine remap.
pub fn isotropic_compression(strain: f64, rate: f64, dt: f64, records: u64) -> StageSpec {
    let steps = steps_for_strain(strain, rate, dt);
    let mut s = StageSpec::hold("compress", steps, dt);
    s.deformation = Some(Deformation::Isotropic {
        true_strain_rate: -rate.abs(),
    });
    s.record.every = (steps / records.max(1)).max(1);
    s
}

/// Simple shear by `xy` tilt to shear strain `strain` at rate `rate`.
pub fn simple_shear(strain: f64, rate: f64, dt: f64, records: u64) -> StageSpec {
    let steps = steps_for_strain(strain, rate, dt);
    let mut s = StageSpec::hold("shear", steps, dt);
    s.deformation = Some(Deformation::SimpleShear {
        tilt: TiltFactor::Xy,
        rate: rate.abs(),
    });
    s.record.every = (steps / records.max(1)).max(1);
    s
}

/// The Hertz squeeze of one grain (docs/protocols.md, "Hertz sphere
/// squeeze"); lengths in d, times in tau.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SqueezeParams {
    /// Speed of each wall towards the other (paper: 5e-4 d / tau).
    pub wall_speed: f64,
    /// Wall stiffness k and cutoff (paper: k = 1, cutoff d = 1).
    pub wall_stiffness: f64,
    /// Range of the wall force.
    pub wall_cutoff: f64,
    /// Lateral (x, y) tether of the centre of mass (paper: soft, 0.001 k).
    pub tether_stiffness: f64,
    /// Overlap `delta / R` to reach (each wall travels about its cutoff
    /// before contact, then `delta`).
    pub max_overlap: f64,
    /// Nominal grain radius R for the overlap target.
    pub radius: f64,
    /// Time step.
    pub dt: f64,
    /// Records over the run (wall forces and positions).
    pub records: u64,
}

impl SqueezeParams {
    /// The paper's squeeze of a grain of radius `radius` to `max_overlap`.
    pub fn paper(radius: f64, max_overlap: f64) -> Self {
        Self {
            wall_speed: 5e-4,
            wall_stiffness: 1.0,
            wall_cutoff: 1.0,
            tether_stiffness: 1e-3,
            max_overlap,
            radius,
            dt: 0.1,
            records: 1000,
        }
    }
}

/// `scene` (one grain in a closed box) with the squeeze stage: two flat
/// walls normal to z, one cutoff beyond the highest and lowest particles,
/// moving towards each other, and the centre of mass tethered in x and y.
pub fn hertz_squeeze(scene: &Scene, p: &SqueezeParams) -> Scene {
    let z = scene.particles.positions.iter().map(|x| x[2]);
    let (zmin, zmax) = z.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), z| {
        (a.min(z), b.max(z))
    });
    let travel = p.wall_cutoff + p.max_overlap * p.radius + 0.05 * p.radius;
    let steps = (travel / p.wall_speed / p.dt).ceil() as u64;
    let mut s = StageSpec::hold("squeeze", steps, p.dt);
    let wall = |side, position, velocity| FlatWall {
        axis: 2,
        side,
        position,
        velocity,
        stiffness: p.wall_stiffness,
        cutoff: p.wall_cutoff,
    };
    s.walls = vec![
        wall(WallSide::Lo, zmin - p.wall_cutoff, p.wall_speed),
        wall(WallSide::Hi, zmax + p.wall_cutoff, -p.wall_speed),
    ];
    s.tether = Some(Tether {
        grain: None,
        anchor: None,
        dims: [true, true, false],
        stiffness: p.tether_stiffness,
    });
    s.record.every = (steps / p.records.max(1)).max(1);
    let mut out = scene.clone();
    out.stages = vec![s];
    out
}

/// A rotation matrix uniform over all rotations, from three uniform
/// numbers in [0, 1) (Shoemake's quaternion method).
pub fn uniform_rotation(u: [f64; 3]) -> [[f64; 3]; 3] {
    use std::f64::consts::TAU;
    let (a, b) = ((1.0 - u[0]).sqrt(), u[0].sqrt());
    let q = [
        a * (TAU * u[1]).sin(),
        a * (TAU * u[1]).cos(),
        b * (TAU * u[2]).sin(),
        b * (TAU * u[2]).cos(),
    ];
    let [x, y, z, w] = q;
    [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - z * w),
            2.0 * (x * z + y * w),
        ],
        [
            2.0 * (x * y + z * w),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - x * w),
        ],
        [
            2.0 * (x * z - y * w),
            2.0 * (y * z + x * w),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ]
}

/// `scene` with its particles rotated by `rotation` about their centre of
/// mass (velocities too); the box is unchanged, so it must leave room.
pub fn rotated(scene: &Scene, rotation: &[[f64; 3]; 3]) -> Scene {
    let mut out = scene.clone();
    let c = super::builders::grain::centre_of(&scene.particles.positions);
    let apply =
        |v: &[f64; 3]| [0, 1, 2].map(|r| (0..3).map(|k| rotation[r][k] * v[k]).sum::<f64>());
    for x in &mut out.particles.positions {
        let d = apply(&[x[0] - c[0], x[1] - c[1], x[2] - c[2]]);
        *x = [c[0] + d[0], c[1] + d[1], c[2] + d[2]];
    }
    if let Some(v) = &mut out.particles.velocities {
        for vi in v.iter_mut() {
            *vi = apply(vi);
        }
    }
    out
}
