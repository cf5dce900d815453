//! A scene as a LAMMPS data file: `atom_style bond` for bonded grains,
//! `atom_style sphere` for DEM spheres.

use super::type_masses;
use crate::scene::model::{ModelKind, Scene};
use std::fmt::Write as _;

/// How a written data file numbers its atoms.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AtomIds {
    /// The scene's `particles.ids` (`1..=N` when it has none): files for
    /// users, which read back to the same scene.
    Scene,
    /// `1..=N` in particle order, whatever the scene's ids: the LAMMPS
    /// harness's run files, whose atoms LAMMPS hands back by id.
    Sequential,
}

/// The data file text of `scene`: atoms (id, grain + 1 as molecule, type,
/// x y z), velocities and bonds (type 1), with the scene's atom ids
/// (`particles.ids`, else particle `i` is atom `i + 1`). Masses are per
/// type ([`type_masses`]; the harness refuses scenes where that fails, and
/// here the first particle's mass stands in).
pub fn write_data_file(scene: &Scene) -> String {
    write_data_file_with_ids(scene, AtomIds::Scene)
}

/// [`write_data_file`] with the atoms numbered as `ids` says.
pub fn write_data_file_with_ids(scene: &Scene, ids: AtomIds) -> String {
    let pa = &scene.particles;
    let id = |i: usize| match ids {
        AtomIds::Scene => pa.id(i),
        AtomIds::Sequential => i as u64 + 1,
    };
    if scene.model == ModelKind::Dem {
        return write_sphere_data_file(scene, id);
    }
    let n = pa.positions.len();
    let masses = type_masses(scene).unwrap_or_else(|| vec![pa.mass.values(n)[0]]);
    let mut s = header(
        scene,
        &format!(
            "{n} atoms\n{} bonds\n{} atom types\n1 bond types",
            scene.bonds.pairs.len(),
            masses.len()
        ),
    );
    let _ = writeln!(s, "\nMasses\n");
    for (t, m) in masses.iter().enumerate() {
        let _ = writeln!(s, "{} {m:.17e}", t + 1);
    }
    let _ = writeln!(s, "\nAtoms # bond\n");
    for (i, x) in pa.positions.iter().enumerate() {
        let grain = pa.grain.as_ref().map_or(0, |g| g[i]);
        let kind = pa.kind.as_ref().map_or(1, |t| t[i]);
        let _ = writeln!(
            s,
            "{} {} {kind} {:.17e} {:.17e} {:.17e}",
            id(i),
            grain + 1,
            x[0],
            x[1],
            x[2]
        );
    }
    if let Some(v) = &pa.velocities {
        let _ = writeln!(s, "\nVelocities\n");
        for (i, v) in v.iter().enumerate() {
            let _ = writeln!(s, "{} {:.17e} {:.17e} {:.17e}", id(i), v[0], v[1], v[2]);
        }
    }
    if !scene.bonds.pairs.is_empty() {
        let _ = writeln!(s, "\nBonds\n");
        for (k, [i, j]) in scene.bonds.pairs.iter().enumerate() {
            let _ = writeln!(s, "{} 1 {} {}", k + 1, id(*i), id(*j));
        }
    }
    s
}

/// Header and box lines of a data file for `scene` with `counts` (the
/// lines after the title, e.g. `"8 atoms\n1 atom types"`).
fn header(scene: &Scene, counts: &str) -> String {
    let b = &scene.simbox;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "LAMMPS data file written by bpm {} (scene seed {})\n\n{counts}\n",
        crate::VERSION,
        scene.seed
    );
    let hi = |d: usize| b.lo[d] + b.lengths[d];
    let _ = writeln!(s, "{:.17e} {:.17e} xlo xhi", b.lo[0], hi(0));
    let _ = writeln!(s, "{:.17e} {:.17e} ylo yhi", b.lo[1], hi(1));
    let _ = writeln!(s, "{:.17e} {:.17e} zlo zhi", b.lo[2], hi(2));
    if super::needs_triclinic(scene) {
        let _ = writeln!(
            s,
            "{:.17e} {:.17e} {:.17e} xy xz yz",
            b.tilt[0], b.tilt[1], b.tilt[2]
        );
    }
    s
}

/// `4 pi / 3`, formed as LAMMPS forms it when it turns a density into a
/// mass (`(4 pi / 3) r^3 rho`).
const SPHERE_VOLUME_FACTOR: f64 = 4.0 * std::f64::consts::PI / 3.0;

/// The data file text of a DEM scene (`atom_style sphere`): atoms (id,
/// type, diameter, density, x y z), and velocities with angular velocities.
/// LAMMPS keeps a mass per sphere, made from the density; the density
/// written is the scene's mass over the sphere's volume, so LAMMPS's mass
/// matches the scene's to round-off. Particle `i` is atom `id(i)`.
fn write_sphere_data_file(scene: &Scene, id: impl Fn(usize) -> u64) -> String {
    let pa = &scene.particles;
    let n = pa.positions.len();
    let ntypes = pa
        .kind
        .as_ref()
        .map_or(1, |t| t.iter().copied().max().unwrap_or(1));
    let mut s = header(scene, &format!("{n} atoms\n{ntypes} atom types"));
    let mass = pa.mass.values(n);
    let _ = writeln!(s, "\nAtoms # sphere\n");
    for (i, x) in pa.positions.iter().enumerate() {
        let kind = pa.kind.as_ref().map_or(1, |t| t[i]);
        let r = pa
            .radius
            .as_ref()
            .map_or(crate::engine::particles::DEFAULT_RADIUS, |r| r[i]);
        let density = mass[i] / (SPHERE_VOLUME_FACTOR * r * r * r);
        let _ = writeln!(
            s,
            "{} {kind} {:.17e} {:.17e} {:.17e} {:.17e} {:.17e}",
            id(i),
            2.0 * r,
            density,
            x[0],
            x[1],
            x[2]
        );
    }
    if pa.velocities.is_some() || pa.angular_velocities.is_some() {
        let _ = writeln!(s, "\nVelocities\n");
        for i in 0..n {
            let v = pa.velocities.as_ref().map_or([0.0; 3], |v| v[i]);
            let w = pa.angular_velocities.as_ref().map_or([0.0; 3], |w| w[i]);
            let _ = writeln!(
                s,
                "{} {:.17e} {:.17e} {:.17e} {:.17e} {:.17e} {:.17e}",
                id(i),
                v[0],
                v[1],
                v[2],
                w[0],
                w[1],
                w[2]
            );
        }
    }
    s
}
