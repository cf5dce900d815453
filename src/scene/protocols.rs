//! Ready-made protocol stages (docs/protocols.md).

use super::model::{Record, StageSpec};
use crate::engine::{Deformation, TiltFactor};

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
