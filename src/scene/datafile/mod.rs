//! LAMMPS data files (`atom_style bond`, and `atom_style sphere` for DEM)
//! in and out, so users can bring their own grains and packings and take
//! scenes to LAMMPS.
//!
//! Reading accepts what LAMMPS's and LIGGGHTS's `write_data` produce: any
//! header lines (counts, box, tilt; others are skipped), coefficient
//! sections (skipped: the scene's force field is set separately; but
//! `Pair Coeffs`, `PairIJ Coeffs` and `Bond Coeffs` that differ between
//! types are refused, since a scene holds one material), `Masses`, `Atoms`
//! (`id mol type x y z`, optional image flags `ix iy iz`; or, for spheres,
//! `id type diameter density x y z [ix iy iz]`, recognised by the `#
//! sphere` (LIGGGHTS: `# granular`) comment or by its 7 or 10 columns),
//! `Velocities` (spheres: with angular velocities `wx wy wz`) and `Bonds`,
//! atom ids in any order and not necessarily 1..N. The particles are
//! ordered by atom id and the scene keeps the ids (`particles.ids`, left
//! out when they are 1..N). Molecule ids become grain ids (the distinct
//! molecule ids in increasing order become grains 0, 1, ...). Reference
//! lengths are the bond lengths in the file (minimum image). What a scene
//! cannot hold is refused with a message saying so: `Angles`, `Dihedrals`,
//! `Impropers` and body sections (`Ellipsoids`, `Lines`, `Triangles`,
//! `Bodies`), duplicate atom ids, unknown sections. Malformed input is an
//! error naming the line.
//!
//! `read.rs` parses a file into a scene ([`read_data_file`]); `write.rs`
//! writes a scene as a file ([`write_data_file`]).

mod read;
mod write;

pub use read::{read_data_file, DataFileError};
pub use write::{write_data_file, write_data_file_with_ids, AtomIds};

use super::model::Scene;
use crate::engine::Deformation;

/// Whether LAMMPS needs a triclinic box for `scene` (tilted, or sheared later).
pub fn needs_triclinic(scene: &Scene) -> bool {
    scene.simbox.tilt.iter().any(|&t| t != 0.0)
        || scene
            .stages
            .iter()
            .any(|s| matches!(s.deformation, Some(Deformation::SimpleShear { .. })))
}

/// The mass of each particle type `1..=ntypes` of `scene`, or `None` when
/// two particles of one type differ in mass (LAMMPS's `atom_style bond`
/// keeps one mass per type).
pub fn type_masses(scene: &Scene) -> Option<Vec<f64>> {
    let pa = &scene.particles;
    let n = pa.positions.len();
    let masses = pa.mass.values(n);
    let kind = |i: usize| pa.kind.as_ref().map_or(1, |t| t[i]) as usize;
    let ntypes = (0..n).map(kind).max().unwrap_or(1);
    let mut by_type: Vec<Option<f64>> = vec![None; ntypes];
    for (i, &m) in masses.iter().enumerate() {
        match by_type[kind(i) - 1] {
            Some(prev) if prev != m => return None,
            _ => by_type[kind(i) - 1] = Some(m),
        }
    }
    // A type no particle has still needs a mass in LAMMPS.
    Some(by_type.into_iter().map(|m| m.unwrap_or(1.0)).collect())
}
