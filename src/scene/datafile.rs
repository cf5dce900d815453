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

use super::model::{
    is_default_numbering, Bonds, BoxSpec, ForceField, Mass, ModelKind, Particles, Scene,
};
use crate::engine::Deformation;
use crate::kernels::BondCoeffs;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

/// Why a data file could not be read.
pub use crate::file_error::TextFileError as DataFileError;

/// The sections read.
const READ_SECTIONS: [&str; 4] = ["Masses", "Atoms", "Velocities", "Bonds"];

/// Coefficient sections whose values must agree between types (a scene
/// holds one bond law and one contact law), then skipped.
const UNIFORM_SECTIONS: [&str; 3] = ["Pair Coeffs", "PairIJ Coeffs", "Bond Coeffs"];

/// Coefficient sections of interactions the scene has no use for: skipped.
const SKIPPED_SECTIONS: [&str; 10] = [
    "Angle Coeffs",
    "Dihedral Coeffs",
    "Improper Coeffs",
    "BondBond Coeffs",
    "BondAngle Coeffs",
    "MiddleBondTorsion Coeffs",
    "EndBondTorsion Coeffs",
    "AngleTorsion Coeffs",
    "AngleAngleTorsion Coeffs",
    "BondBond13 Coeffs",
];

/// Sections of what a scene cannot hold (many-body interactions, bodies of
/// other shapes): refused.
const REFUSED_SECTIONS: [&str; 7] = [
    "Angles",
    "Dihedrals",
    "Impropers",
    "Ellipsoids",
    "Lines",
    "Triangles",
    "Bodies",
];

/// A section keyword line: it starts with a word (data and header lines
/// start with numbers; `nan` and `inf` are numbers gone wrong, not
/// keywords).
fn is_keyword_line(l: &str) -> bool {
    l.starts_with(|c: char| c.is_ascii_alphabetic())
        && l.split_whitespace()
            .next()
            .is_some_and(|w| w.parse::<f64>().is_err())
}

/// The section a keyword line opens (`Pair Coeffs # bpm/contact` opens
/// `Pair Coeffs`), if it is one this reader knows.
fn known_section(l: &str) -> Option<&'static str> {
    READ_SECTIONS
        .iter()
        .chain(UNIFORM_SECTIONS.iter())
        .chain(SKIPPED_SECTIONS.iter())
        .chain(REFUSED_SECTIONS.iter())
        .copied()
        .find(|s| {
            l.strip_prefix(s)
                .is_some_and(|rest| rest.is_empty() || rest.starts_with(char::is_whitespace))
        })
}

/// One atom line.
struct Atom {
    id: i64,
    mol: i64,
    kind: u32,
    x: [f64; 3],
    /// Radius and mass of a sphere (`atom_style sphere`).
    sphere: Option<(f64, f64)>,
}

/// Reads a data file as a scene with `boundary` periodicity (data files do
/// not record it), the force field `force_field`, no stages and the given
/// seed. A sphere file needs `force_field.granular`; its scene keeps the
/// rest of `force_field` (skin, gravity, multi-contact closure) and drops
/// only the bonded model's terms (`bond`, `pair`, `zero_net_multibody`).
pub fn read_data_file(
    path: &Path,
    periodic: [bool; 3],
    force_field: ForceField,
    seed: u64,
) -> Result<Scene, DataFileError> {
    let text = std::fs::read_to_string(path).map_err(|cause| DataFileError::Io {
        path: path.to_path_buf(),
        cause,
    })?;
    parse(&text, path, periodic, force_field, seed)
}

fn parse(
    text: &str,
    path: &Path,
    periodic: [bool; 3],
    force_field: ForceField,
    seed: u64,
) -> Result<Scene, DataFileError> {
    let bad = |line: usize, reason: String| DataFileError::Malformed {
        path: path.to_path_buf(),
        line,
        reason,
    };
    let raw: Vec<&str> = text.lines().collect();
    let lines: Vec<(usize, &str)> = text
        .lines()
        .enumerate()
        .map(|(k, l)| (k + 1, l.split('#').next().unwrap_or("").trim()))
        .collect();
    let number = |k: usize, w: &str| -> Result<f64, DataFileError> {
        w.parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| bad(k, format!("`{w}` is not a finite number")))
    };
    let integer = |k: usize, w: &str| -> Result<i64, DataFileError> {
        w.parse::<i64>()
            .map_err(|_| bad(k, format!("`{w}` is not an integer")))
    };
    // Header: up to the first section keyword. The first line is a title.
    let mut counts: BTreeMap<&str, usize> = BTreeMap::new();
    let mut lo = [f64::NAN; 3];
    let mut hi = [f64::NAN; 3];
    let mut tilt = [0.0; 3];
    let mut i = 1;
    while i < lines.len() && !is_keyword_line(lines[i].1) {
        let (k, l) = lines[i];
        i += 1;
        let w: Vec<&str> = l.split_whitespace().collect();
        match w.as_slice() {
            [] => {}
            [n, "atoms"] | [n, "bonds"] | [n, "atom", "types"] | [n, "bond", "types"] => {
                let key = w[1..].join(" ");
                let v = integer(k, n)?;
                if v < 0 {
                    return Err(bad(k, format!("negative count {v}")));
                }
                counts.insert(
                    match key.as_str() {
                        "atoms" => "atoms",
                        "bonds" => "bonds",
                        "atom types" => "atom types",
                        _ => "bond types",
                    },
                    v as usize,
                );
            }
            [a, b, lo_name, hi_name] if lo_name.ends_with("lo") && hi_name.ends_with("hi") => {
                let d = match *lo_name {
                    "xlo" => 0,
                    "ylo" => 1,
                    "zlo" => 2,
                    _ => return Err(bad(k, format!("unknown box line `{l}`"))),
                };
                lo[d] = number(k, a)?;
                hi[d] = number(k, b)?;
            }
            [a, b, c, "xy", "xz", "yz"] => {
                tilt = [number(k, a)?, number(k, b)?, number(k, c)?];
            }
            // Other header keywords (angles, extra bond per atom, ellipsoids,
            // ...) do not concern this model.
            _ if w.first().is_some_and(|v| v.parse::<f64>().is_ok()) => {}
            _ => return Err(bad(k, format!("unrecognised header line `{l}`"))),
        }
    }
    for d in 0..3 {
        if !(lo[d].is_finite() && hi[d] > lo[d]) {
            return Err(bad(
                0,
                format!(
                    "the header lacks a valid {}lo {}hi line",
                    ["x", "y", "z"][d],
                    ["x", "y", "z"][d]
                ),
            ));
        }
    }
    let natoms = *counts
        .get("atoms")
        .ok_or_else(|| bad(0, "the header lacks the `atoms` count".into()))?;
    let nbonds = counts.get("bonds").copied().unwrap_or(0);
    let mut masses: BTreeMap<u32, f64> = BTreeMap::new();
    let mut atoms: Vec<Atom> = Vec::new();
    let mut velocities: BTreeMap<i64, [f64; 3]> = BTreeMap::new();
    let mut angular: BTreeMap<i64, [f64; 3]> = BTreeMap::new();
    let mut sphere = false;
    let mut bond_ids: Vec<(usize, i64, i64)> = Vec::new();
    // Sections: a keyword line, a blank line, then data lines until the
    // next keyword.
    while i < lines.len() {
        let (k, l) = lines[i];
        i += 1;
        if l.is_empty() {
            continue;
        }
        if !is_keyword_line(l) {
            return Err(bad(k, format!("expected a section keyword, found `{l}`")));
        }
        let Some(name) = known_section(l) else {
            return Err(bad(
                k,
                format!(
                    "unknown section `{l}`: bpm reads {}, and coefficient sections",
                    READ_SECTIONS.join(", ")
                ),
            ));
        };
        if REFUSED_SECTIONS.contains(&name) {
            return Err(bad(
                k,
                format!(
                    "section `{name}`: a scene holds particles, bonds between two of them and spheres; it has no {}",
                    match name {
                        "Angles" => "angles",
                        "Dihedrals" => "dihedrals",
                        "Impropers" => "impropers",
                        _ => "ellipsoids, lines, triangles or bodies",
                    }
                ),
            ));
        }
        let mut body = Vec::new();
        while i < lines.len() && !is_keyword_line(lines[i].1) {
            if !lines[i].1.is_empty() {
                body.push(lines[i]);
            }
            i += 1;
        }
        if UNIFORM_SECTIONS.contains(&name) {
            uniform_coefficients(name, &body).map_err(|(k, reason)| bad(k, reason))?;
            continue;
        }
        match name {
            "Masses" => {
                for &(k, l) in &body {
                    let w: Vec<&str> = l.split_whitespace().collect();
                    if w.len() < 2 {
                        return Err(bad(k, "a mass line needs `type mass`".into()));
                    }
                    let t = integer(k, w[0])?;
                    let m = number(k, w[1])?;
                    if t < 1 || m <= 0.0 {
                        return Err(bad(
                            k,
                            format!(
                                "type {t} with mass {m}: types count from 1, masses are positive"
                            ),
                        ));
                    }
                    masses.insert(t as u32, m);
                }
            }
            "Atoms" => {
                let style = raw[k - 1].split('#').nth(1).map(str::trim);
                let width = body
                    .first()
                    .map_or(0, |(_, l)| l.split_whitespace().count());
                sphere = match style {
                    // LIGGGHTS calls its sphere style `granular`.
                    Some("sphere") | Some("granular") => true,
                    Some("bond") | Some("molecular") => false,
                    Some(style) => {
                        return Err(bad(
                            k,
                            format!(
                                "atom style `{style}`: only `bond` (id mol type x y z) and `sphere` (id type diameter density x y z) are read"
                            ),
                        ))
                    }
                    None => width == 7 || width == 10,
                };
                let (columns, images) = if sphere { (7, 10) } else { (6, 9) };
                for &(k, l) in &body {
                    let w: Vec<&str> = l.split_whitespace().collect();
                    if w.len() != columns && w.len() != images {
                        let expected = if sphere {
                            "id type diameter density x y z [ix iy iz]"
                        } else {
                            "id mol type x y z [ix iy iz]"
                        };
                        return Err(bad(
                            k,
                            format!("an atom line needs `{expected}`, found {} values", w.len()),
                        ));
                    }
                    // Spheres have no molecule column: each is its own grain.
                    let (mol, w) = if sphere {
                        (integer(k, w[0])?, [&w[..2], &w[4..]].concat())
                    } else {
                        (integer(k, w[1])?, [&w[..1], &w[2..]].concat())
                    };
                    let kind = integer(k, w[1])?;
                    if kind < 1 {
                        return Err(bad(k, format!("atom type {kind}: types count from 1")));
                    }
                    let x = [number(k, w[2])?, number(k, w[3])?, number(k, w[4])?];
                    let image = if w.len() == 8 {
                        [integer(k, w[5])?, integer(k, w[6])?, integer(k, w[7])?]
                    } else {
                        [0; 3]
                    };
                    let sphere = if sphere {
                        let line: Vec<&str> = l.split_whitespace().collect();
                        let (diameter, density) = (number(k, line[2])?, number(k, line[3])?);
                        if diameter <= 0.0 || density <= 0.0 {
                            return Err(bad(
                                k,
                                format!(
                                    "diameter {diameter} and density {density} must be positive"
                                ),
                            ));
                        }
                        let r = 0.5 * diameter;
                        // LAMMPS's mass of a sphere, formed in its order.
                        Some((r, density * (4.0 * std::f64::consts::PI / 3.0 * r * r * r)))
                    } else {
                        None
                    };
                    // Positions whole: grains crossing periodic faces are
                    // unwrapped through their image flags.
                    let l = [hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]];
                    let x = [
                        x[0] + image[0] as f64 * l[0]
                            + image[1] as f64 * tilt[0]
                            + image[2] as f64 * tilt[1],
                        x[1] + image[1] as f64 * l[1] + image[2] as f64 * tilt[2],
                        x[2] + image[2] as f64 * l[2],
                    ];
                    let id = integer(k, w[0])?;
                    if id < 1 {
                        return Err(bad(k, format!("atom id {id}: ids count from 1")));
                    }
                    atoms.push(Atom {
                        id,
                        mol,
                        kind: kind as u32,
                        x,
                        sphere,
                    });
                }
            }
            "Velocities" => {
                for &(k, l) in &body {
                    let w: Vec<&str> = l.split_whitespace().collect();
                    if w.len() < 4 {
                        return Err(bad(k, "a velocity line needs `id vx vy vz`".into()));
                    }
                    let id = integer(k, w[0])?;
                    let v = [number(k, w[1])?, number(k, w[2])?, number(k, w[3])?];
                    if velocities.insert(id, v).is_some() {
                        return Err(bad(k, format!("atom {id} has two velocities")));
                    }
                    // Spheres carry their angular velocity too.
                    if sphere && w.len() >= 7 {
                        let omega = [number(k, w[4])?, number(k, w[5])?, number(k, w[6])?];
                        angular.insert(id, omega);
                    }
                }
            }
            "Bonds" => {
                for &(k, l) in &body {
                    let w: Vec<&str> = l.split_whitespace().collect();
                    if w.len() != 4 {
                        return Err(bad(k, "a bond line needs `id type atom1 atom2`".into()));
                    }
                    integer(k, w[0])?;
                    integer(k, w[1])?;
                    bond_ids.push((k, integer(k, w[2])?, integer(k, w[3])?));
                }
            }
            _ => {} // coefficient and other sections: skipped
        }
    }
    if atoms.len() != natoms {
        return Err(bad(
            0,
            format!(
                "the header says {natoms} atoms, the Atoms section has {}",
                atoms.len()
            ),
        ));
    }
    if bond_ids.len() != nbonds {
        return Err(bad(
            0,
            format!(
                "the header says {nbonds} bonds, the Bonds section has {}",
                bond_ids.len()
            ),
        ));
    }
    atoms.sort_by_key(|a| a.id);
    if let Some(w) = atoms.windows(2).find(|w| w[0].id == w[1].id) {
        return Err(bad(0, format!("atom id {} appears twice", w[0].id)));
    }
    let index_of = |id: i64| atoms.binary_search_by_key(&id, |a| a.id).ok();
    let mut mols: Vec<i64> = atoms.iter().map(|a| a.mol).collect();
    mols.sort_unstable();
    mols.dedup();
    let grain: Vec<u32> = atoms
        .iter()
        .map(|a| mols.binary_search(&a.mol).unwrap_or(0) as u32)
        .collect();
    let mut pairs = Vec::with_capacity(bond_ids.len());
    for &(k, a, b) in &bond_ids {
        match (index_of(a), index_of(b)) {
            (Some(i), Some(j)) if i != j => pairs.push([i, j]),
            (Some(_), Some(_)) => return Err(bad(k, format!("bond joins atom {a} to itself"))),
            _ => {
                return Err(bad(
                    k,
                    format!("bond ({a}, {b}) names an atom that is not in Atoms"),
                ))
            }
        }
    }
    let mass_of = |t: u32| masses.get(&t).copied();
    let mass: Vec<f64> = atoms
        .iter()
        .map(|a| {
            a.sphere
                .map_or_else(|| mass_of(a.kind).unwrap_or(1.0), |(_, m)| m)
        })
        .collect();
    if !masses.is_empty() && !sphere {
        if let Some(a) = atoms.iter().find(|a| mass_of(a.kind).is_none()) {
            return Err(bad(
                0,
                format!("atom {} has type {} with no mass in Masses", a.id, a.kind),
            ));
        }
    }
    let velocities = if velocities.is_empty() {
        None
    } else {
        let v: Option<Vec<[f64; 3]>> = atoms
            .iter()
            .map(|a| velocities.get(&a.id).copied())
            .collect();
        Some(v.ok_or_else(|| bad(0, "the Velocities section does not list every atom".into()))?)
    };
    let angular_velocities = if angular.is_empty() {
        None
    } else {
        let w: Option<Vec<[f64; 3]>> = atoms.iter().map(|a| angular.get(&a.id).copied()).collect();
        Some(w.ok_or_else(|| {
            bad(
                0,
                "the Velocities section gives angular velocities for some atoms only".into(),
            )
        })?)
    };
    if sphere && !pairs.is_empty() {
        return Err(bad(0, "a sphere (DEM) data file has no bonds".into()));
    }
    // The file decides the model; everything else of the caller's force
    // field (skin, gravity, the multi-contact closure) stays.
    let force_field = match (sphere, force_field.granular) {
        (true, Some(_)) => ForceField {
            bond: BondCoeffs::default(),
            pair: None,
            zero_net_multibody: false,
            ..force_field
        },
        (true, None) => {
            return Err(bad(
                0,
                "this is a DEM data file (atom_style sphere): give the sphere material (`bpm import --granular`)".into(),
            ))
        }
        (false, Some(_)) => {
            return Err(bad(
                0,
                "a sphere material was given, but this is a bonded-particle data file (atom_style bond)".into(),
            ))
        }
        (false, None) => force_field,
    };
    let uniform = mass.iter().all(|&m| m == mass[0]);
    let mut scene = Scene {
        version: super::SCENE_VERSION,
        model: if sphere {
            ModelKind::Dem
        } else {
            ModelKind::Bpm
        },
        description: format!("imported from {}", path.display()),
        seed,
        simbox: BoxSpec {
            lo,
            lengths: [hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]],
            tilt,
            periodic,
        },
        particles: Particles {
            positions: atoms.iter().map(|a| a.x).collect(),
            velocities,
            angular_velocities,
            grain: (!sphere).then_some(grain),
            mass: if uniform {
                Mass::Uniform(mass.first().copied().unwrap_or(1.0))
            } else {
                Mass::PerParticle(mass)
            },
            radius: sphere.then(|| {
                atoms
                    .iter()
                    .map(|a| {
                        a.sphere
                            .map_or(crate::engine::particles::DEFAULT_RADIUS, |s| s.0)
                    })
                    .collect()
            }),
            kind: Some(atoms.iter().map(|a| a.kind).collect()),
            ids: Some(atoms.iter().map(|a| a.id as u64).collect())
                .filter(|ids: &Vec<u64>| !is_default_numbering(ids)),
        },
        bonds: Bonds { pairs, r0: None },
        force_field,
        stages: Vec::new(),
        provenance: serde_json::json!({"imported_from": path.display().to_string()}),
    };
    // The reference: the bond lengths in the file.
    if !sphere {
        let r0 = super::load::reference_lengths(&scene);
        scene.bonds.r0 = Some(r0);
    }
    Ok(scene)
}

/// Checks that the lines of coefficient section `name` give every type
/// (`Pair Coeffs`, `Bond Coeffs`: `type c1 c2 ...`) or pair of types
/// (`PairIJ Coeffs`: `i j c1 c2 ...`) the same coefficients; the error
/// names the first line that differs from the first.
fn uniform_coefficients(name: &str, body: &[(usize, &str)]) -> Result<(), (usize, String)> {
    let skip = if name == "PairIJ Coeffs" { 2 } else { 1 };
    // Numbers compare as numbers (`1` and `1.0` agree), words as words.
    let values = |l: &str| -> Vec<Result<f64, String>> {
        l.split_whitespace()
            .skip(skip)
            .map(|w| w.parse::<f64>().map_err(|_| w.to_string()))
            .collect()
    };
    let Some(&(_, first)) = body.first() else {
        return Ok(());
    };
    let reference = values(first);
    for &(k, l) in &body[1..] {
        if values(l) != reference {
            let types = |l: &str| {
                l.split_whitespace()
                    .take(skip)
                    .collect::<Vec<_>>()
                    .join(" ")
            };
            return Err((
                k,
                format!(
                    "`{name}` differ between types ({} and {}): a scene holds one material for all particles; give its force field on the command line",
                    types(first),
                    types(l)
                ),
            ));
        }
    }
    Ok(())
}

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
    if needs_triclinic(scene) {
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
