//! Copies of a periodic scene side by side (LAMMPS's `replicate`): a large
//! solid from a small one, with every bond that crossed a periodic face
//! joined to the neighbouring copy.

use crate::kernels::Separation;
use crate::scene::load::reference_lengths;
use crate::scene::model::{Bonds, Mass, Scene};
use crate::scene::validate::{simbox_of, SceneError};

/// `scene` repeated `copies[d]` times along each axis. The box must be
/// orthogonal and periodic in every replicated dimension. Particles come
/// copy by copy (each copy's particles contiguous, in the original order),
/// each copy's grains renumbered after the previous copy's; bonds keep
/// their reference lengths; stages are kept.
pub fn replicate(scene: &Scene, copies: [usize; 3]) -> Result<Scene, SceneError> {
    let bad = |reason: String| SceneError::Invalid {
        field: "replicate".into(),
        reason,
    };
    if copies.contains(&0) {
        return Err(bad(format!("copies must be at least 1, got {copies:?}")));
    }
    let b = &scene.simbox;
    if b.tilt != [0.0; 3] {
        return Err(bad("only orthogonal boxes can be replicated".into()));
    }
    if let Some(d) = (0..3).find(|&d| copies[d] > 1 && !b.periodic[d]) {
        return Err(bad(format!(
            "dimension {d} is not periodic: its bonds could not be joined across copies"
        )));
    }
    let n = scene.particles.positions.len();
    let total = n * copies.iter().product::<usize>();
    if total > u32::MAX as usize {
        return Err(bad(format!("{total} particles is too many")));
    }
    let simbox = simbox_of(scene);
    let x = &scene.particles.positions;
    let cells: Vec<[usize; 3]> = (0..copies[2])
        .flat_map(|c| (0..copies[1]).flat_map(move |b| (0..copies[0]).map(move |a| [a, b, c])))
        .collect();
    let cell_index = |c: [usize; 3]| (c[2] * copies[1] + c[1]) * copies[0] + c[0];
    let mut out = scene.clone();
    let p = &mut out.particles;
    p.positions = cells
        .iter()
        .flat_map(|c| {
            x.iter()
                .map(move |xi| [0, 1, 2].map(|d| xi[d] + c[d] as f64 * b.lengths[d]))
        })
        .collect();
    let times = cells.len();
    p.velocities = scene.particles.velocities.as_ref().map(|v| tiled(v, times));
    // Each copy's grains are grains of their own.
    p.grain = scene.particles.grain.as_ref().map(|g| {
        let per_copy = g.iter().max().map_or(0, |m| m + 1);
        (0..times as u32)
            .flat_map(|c| g.iter().map(move |id| id + c * per_copy))
            .collect()
    });
    p.radius = scene.particles.radius.as_ref().map(|v| tiled(v, times));
    p.kind = scene.particles.kind.as_ref().map(|v| tiled(v, times));
    if let Mass::PerParticle(m) = &scene.particles.mass {
        p.mass = Mass::PerParticle(tiled(m, times));
    }
    let r0 = reference_lengths(scene);
    let mut pairs = Vec::with_capacity(scene.bonds.pairs.len() * cells.len());
    for c in &cells {
        for &[i, j] in &scene.bonds.pairs {
            // The copy of j that the bond reaches: the minimum image of
            // x_j seen from x_i, counted in whole boxes.
            let d = simbox.delta(&x[j], &x[i]);
            let mut cj = *c;
            for k in 0..3 {
                let shift = ((x[i][k] + d[k] - x[j][k]) / b.lengths[k]).round() as i64;
                cj[k] = (c[k] as i64 + shift).rem_euclid(copies[k] as i64) as usize;
            }
            pairs.push([cell_index(*c) * n + i, cell_index(cj) * n + j]);
        }
    }
    out.bonds = Bonds {
        pairs,
        r0: Some(tiled(&r0, times)),
        plastic_strain: scene.bonds.plastic_strain.as_ref().map(|e| tiled(e, times)),
    };
    out.simbox.lengths = [0, 1, 2].map(|d| b.lengths[d] * copies[d] as f64);
    out.description = format!("{} (replicated {copies:?})", scene.description);
    Ok(out)
}

/// `v` repeated `times` times.
fn tiled<T: Clone>(v: &[T], times: usize) -> Vec<T> {
    let mut out = Vec::with_capacity(v.len() * times);
    for _ in 0..times {
        out.extend_from_slice(v);
    }
    out
}
