//! Turning a grain about its centre of mass: the centre, a uniformly random
//! rotation and the rotated scene. The grain and packing builders and the
//! Hertz squeeze's rotations share it; it needs only the scene model, so
//! builders and protocols can both use it without using each other.

use super::model::Scene;

/// The centre of mass of `x` (unit masses, no periodic images).
pub fn centre_of(x: &[[f64; 3]]) -> [f64; 3] {
    let n = x.len().max(1) as f64;
    let mut c = [0.0; 3];
    for p in x {
        for d in 0..3 {
            c[d] += p[d] / n;
        }
    }
    c
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
    let c = centre_of(&scene.particles.positions);
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
