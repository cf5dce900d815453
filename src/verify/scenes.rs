//! Built-in cross-check scenes.

use crate::scene::builders::bulk::{build_bulk, BulkParams};
use crate::scene::{ForceField, Scene, SceneError, StageSpec};
use rand::{Rng, SeedableRng};

/// A small bulk solid, compressed 1.5% with a small seeded jitter, with
/// random velocities (rms about 0.05), and its bonds across the plane
/// `z = L/2` removed: bonds carry force, damping acts, and the two halves
/// touch through pair contacts only (two bodies with surface contacts).
/// The build is [`BulkParams::shortened`].
pub fn contact_solid(size: f64, seed: u64, a_b: f64) -> Result<Scene, SceneError> {
    let mut s = build_bulk(&BulkParams::shortened(size, seed, 0.0), 1, false)?.0;
    s.force_field = ForceField::paper(a_b);
    let squeeze = 0.985;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed ^ 0x5EED);
    for x in s.particles.positions.iter_mut() {
        for c in x.iter_mut() {
            *c = *c * squeeze + rng.gen_range(-5e-3..5e-3);
        }
    }
    s.simbox.lengths = s.simbox.lengths.map(|l| l * squeeze);
    let n = s.particles.positions.len();
    s.particles.velocities = Some(
        (0..n)
            .map(|_| {
                [
                    rng.gen_range(-0.05..0.05),
                    rng.gen_range(-0.05..0.05),
                    rng.gen_range(-0.05..0.05),
                ]
            })
            .collect(),
    );
    let cut = 0.5 * size * squeeze;
    let z = &s.particles.positions;
    let r0 = s.bonds.r0.clone().unwrap_or_default();
    let keep: Vec<usize> = (0..s.bonds.pairs.len())
        .filter(|&k| {
            let [i, j] = s.bonds.pairs[k];
            (z[i][2] < cut) == (z[j][2] < cut)
        })
        .collect();
    s.bonds.pairs = keep.iter().map(|&k| s.bonds.pairs[k]).collect();
    s.bonds.r0 = Some(keep.iter().map(|&k| r0[k]).collect());
    s.stages = vec![StageSpec::hold("point", 0, 0.1)];
    s.description = format!("contact solid L = {size} d, seed {seed}, a_B = {a_b}");
    Ok(s)
}
