//! Parsing a LAMMPS data file into a scene: the header (counts, box,
//! tilt), then section by section (`Masses`, `Atoms`, `Velocities`,
//! `Bonds`; coefficient sections checked or skipped), then the scene
//! assembled from what was read. Every error names the file and the line.

use crate::kernels::BondCoeffs;
use crate::scene::model::{
    is_default_numbering, Bonds, BoxSpec, ForceField, Mass, ModelKind, Particles, Scene,
};
use std::collections::BTreeMap;
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

/// Where the lines come from: every error names the file and the line
/// (line 0 for what concerns the whole file).
struct Source<'a> {
    path: &'a Path,
}

impl Source<'_> {
    fn bad(&self, line: usize, reason: String) -> DataFileError {
        DataFileError::Malformed {
            path: self.path.to_path_buf(),
            line,
            reason,
        }
    }

    fn number(&self, line: usize, w: &str) -> Result<f64, DataFileError> {
        w.parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| self.bad(line, format!("`{w}` is not a finite number")))
    }

    fn integer(&self, line: usize, w: &str) -> Result<i64, DataFileError> {
        w.parse::<i64>()
            .map_err(|_| self.bad(line, format!("`{w}` is not an integer")))
    }

    /// Three finite numbers from `w[first..first + 3]` (a position, a
    /// velocity), the first bad one named.
    fn vector(&self, line: usize, w: &[&str], first: usize) -> Result<[f64; 3], DataFileError> {
        Ok([
            self.number(line, w[first])?,
            self.number(line, w[first + 1])?,
            self.number(line, w[first + 2])?,
        ])
    }
}

/// The header: counts and the box.
struct Header {
    atoms: usize,
    bonds: usize,
    lo: [f64; 3],
    hi: [f64; 3],
    tilt: [f64; 3],
}

impl Header {
    fn lengths(&self) -> [f64; 3] {
        [
            self.hi[0] - self.lo[0],
            self.hi[1] - self.lo[1],
            self.hi[2] - self.lo[2],
        ]
    }
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

/// What the sections gave, before the scene is assembled.
#[derive(Default)]
struct Sections {
    masses: BTreeMap<u32, f64>,
    atoms: Vec<Atom>,
    velocities: BTreeMap<i64, [f64; 3]>,
    angular: BTreeMap<i64, [f64; 3]>,
    /// Whether the atoms are spheres (`atom_style sphere`).
    sphere: bool,
    /// Bonds as (line, atom id, atom id).
    bonds: Vec<(usize, i64, i64)>,
}

/// A data line: its number in the file and its text without the comment.
type Line<'t> = (usize, &'t str);

/// Reads a data file as a scene with the periodicity `periodic` (data
/// files do not record it), the force field `force_field`, no stages and the given
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
    let src = Source { path };
    let raw: Vec<&str> = text.lines().collect();
    let lines: Vec<Line> = raw
        .iter()
        .enumerate()
        .map(|(k, l)| (k + 1, l.split('#').next().unwrap_or("").trim()))
        .collect();
    // The first line is a title; the header runs to the first keyword.
    let mut next = 1;
    let header = read_header(&src, &lines, &mut next)?;
    let sections = read_sections(&src, &raw, &lines[next..], &header)?;
    assemble(&src, header, sections, periodic, force_field, seed)
}

/// Reads the header lines from `lines[*next]` up to the first section
/// keyword, leaving `*next` at that keyword.
fn read_header(src: &Source, lines: &[Line], next: &mut usize) -> Result<Header, DataFileError> {
    let mut counts: BTreeMap<&str, usize> = BTreeMap::new();
    let mut lo = [f64::NAN; 3];
    let mut hi = [f64::NAN; 3];
    let mut tilt = [0.0; 3];
    while *next < lines.len() && !is_keyword_line(lines[*next].1) {
        let (k, l) = lines[*next];
        *next += 1;
        let w: Vec<&str> = l.split_whitespace().collect();
        match w.as_slice() {
            [] => {}
            [n, "atoms"] | [n, "bonds"] | [n, "atom", "types"] | [n, "bond", "types"] => {
                let key = w[1..].join(" ");
                let v = src.integer(k, n)?;
                if v < 0 {
                    return Err(src.bad(k, format!("negative count {v}")));
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
                    _ => return Err(src.bad(k, format!("unknown box line `{l}`"))),
                };
                lo[d] = src.number(k, a)?;
                hi[d] = src.number(k, b)?;
            }
            [a, b, c, "xy", "xz", "yz"] => {
                tilt = [src.number(k, a)?, src.number(k, b)?, src.number(k, c)?];
            }
            // Other header keywords (angles, extra bond per atom, ellipsoids,
            // ...) do not concern this model.
            _ if w.first().is_some_and(|v| v.parse::<f64>().is_ok()) => {}
            _ => return Err(src.bad(k, format!("unrecognised header line `{l}`"))),
        }
    }
    for d in 0..3 {
        if !(lo[d].is_finite() && hi[d] > lo[d]) {
            return Err(src.bad(
                0,
                format!(
                    "the header lacks a valid {}lo {}hi line",
                    ["x", "y", "z"][d],
                    ["x", "y", "z"][d]
                ),
            ));
        }
    }
    let atoms = *counts
        .get("atoms")
        .ok_or_else(|| src.bad(0, "the header lacks the `atoms` count".into()))?;
    Ok(Header {
        atoms,
        bonds: counts.get("bonds").copied().unwrap_or(0),
        lo,
        hi,
        tilt,
    })
}

/// Reads the sections in `lines`: each a keyword line, a blank line, then
/// data lines until the next keyword. `raw` holds the file's lines with
/// their comments (the `Atoms` keyword's comment names the atom style).
fn read_sections(
    src: &Source,
    raw: &[&str],
    lines: &[Line],
    header: &Header,
) -> Result<Sections, DataFileError> {
    let mut read = Sections::default();
    let mut i = 0;
    while i < lines.len() {
        let (k, l) = lines[i];
        i += 1;
        if l.is_empty() {
            continue;
        }
        if !is_keyword_line(l) {
            return Err(src.bad(k, format!("expected a section keyword, found `{l}`")));
        }
        let name = section_name(src, k, l)?;
        let mut body = Vec::new();
        while i < lines.len() && !is_keyword_line(lines[i].1) {
            if !lines[i].1.is_empty() {
                body.push(lines[i]);
            }
            i += 1;
        }
        if UNIFORM_SECTIONS.contains(&name) {
            uniform_coefficients(name, &body).map_err(|(k, reason)| src.bad(k, reason))?;
            continue;
        }
        match name {
            "Masses" => read.masses(src, &body)?,
            "Atoms" => {
                let style = raw[k - 1].split('#').nth(1).map(str::trim);
                read.atoms(src, k, style, &body, header)?
            }
            "Velocities" => read.velocities(src, &body)?,
            "Bonds" => read.bonds(src, &body)?,
            _ => {} // coefficient and other sections: skipped
        }
    }
    Ok(read)
}

/// The section keyword line `l` (line `k`) opens, if this reader knows it
/// and a scene can hold what it holds.
fn section_name(src: &Source, k: usize, l: &str) -> Result<&'static str, DataFileError> {
    let Some(name) = known_section(l) else {
        return Err(src.bad(
            k,
            format!(
                "unknown section `{l}`: bpm reads {}, and coefficient sections",
                READ_SECTIONS.join(", ")
            ),
        ));
    };
    if REFUSED_SECTIONS.contains(&name) {
        return Err(src.bad(
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
    Ok(name)
}

impl Sections {
    /// `Masses`: `type mass`.
    fn masses(&mut self, src: &Source, body: &[Line]) -> Result<(), DataFileError> {
        for &(k, l) in body {
            let w: Vec<&str> = l.split_whitespace().collect();
            if w.len() < 2 {
                return Err(src.bad(k, "a mass line needs `type mass`".into()));
            }
            let t = src.integer(k, w[0])?;
            let m = src.number(k, w[1])?;
            if t < 1 || m <= 0.0 {
                return Err(src.bad(
                    k,
                    format!("type {t} with mass {m}: types count from 1, masses are positive"),
                ));
            }
            self.masses.insert(t as u32, m);
        }
        Ok(())
    }

    /// `Atoms` (keyword on line `k`, its comment `style`): `id mol type x
    /// y z` or, for spheres, `id type diameter density x y z`, each with
    /// optional image flags.
    fn atoms(
        &mut self,
        src: &Source,
        k: usize,
        style: Option<&str>,
        body: &[Line],
        header: &Header,
    ) -> Result<(), DataFileError> {
        let width = body
            .first()
            .map_or(0, |(_, l)| l.split_whitespace().count());
        let sphere = match style {
            // LIGGGHTS calls its sphere style `granular`.
            Some("sphere") | Some("granular") => true,
            Some("bond") | Some("molecular") => false,
            Some(style) => {
                return Err(src.bad(
                    k,
                    format!(
                        "atom style `{style}`: only `bond` (id mol type x y z) and `sphere` (id type diameter density x y z) are read"
                    ),
                ))
            }
            None => width == 7 || width == 10,
        };
        self.sphere = sphere;
        for &(k, l) in body {
            self.atoms.push(atom(src, k, l, sphere, header)?);
        }
        Ok(())
    }

    /// `Velocities`: `id vx vy vz`, and for spheres `wx wy wz`.
    fn velocities(&mut self, src: &Source, body: &[Line]) -> Result<(), DataFileError> {
        for &(k, l) in body {
            let w: Vec<&str> = l.split_whitespace().collect();
            if w.len() < 4 {
                return Err(src.bad(k, "a velocity line needs `id vx vy vz`".into()));
            }
            let id = src.integer(k, w[0])?;
            let v = src.vector(k, &w, 1)?;
            if self.velocities.insert(id, v).is_some() {
                return Err(src.bad(k, format!("atom {id} has two velocities")));
            }
            // Spheres carry their angular velocity too.
            if self.sphere && w.len() >= 7 {
                let omega = src.vector(k, &w, 4)?;
                self.angular.insert(id, omega);
            }
        }
        Ok(())
    }

    /// `Bonds`: `id type atom1 atom2`.
    fn bonds(&mut self, src: &Source, body: &[Line]) -> Result<(), DataFileError> {
        for &(k, l) in body {
            let w: Vec<&str> = l.split_whitespace().collect();
            if w.len() != 4 {
                return Err(src.bad(k, "a bond line needs `id type atom1 atom2`".into()));
            }
            src.integer(k, w[0])?;
            src.integer(k, w[1])?;
            self.bonds
                .push((k, src.integer(k, w[2])?, src.integer(k, w[3])?));
        }
        Ok(())
    }
}

/// One line `l` (line `k`) of `Atoms`, its position unwrapped through its
/// image flags.
fn atom(
    src: &Source,
    k: usize,
    l: &str,
    sphere: bool,
    header: &Header,
) -> Result<Atom, DataFileError> {
    let line: Vec<&str> = l.split_whitespace().collect();
    let (columns, images) = if sphere { (7, 10) } else { (6, 9) };
    if line.len() != columns && line.len() != images {
        let expected = if sphere {
            "id type diameter density x y z [ix iy iz]"
        } else {
            "id mol type x y z [ix iy iz]"
        };
        return Err(src.bad(
            k,
            format!(
                "an atom line needs `{expected}`, found {} values",
                line.len()
            ),
        ));
    }
    // Spheres have no molecule column: each is its own grain. `w` is the
    // line without its molecule, diameter and density columns.
    let (mol, w) = if sphere {
        (src.integer(k, line[0])?, [&line[..2], &line[4..]].concat())
    } else {
        (src.integer(k, line[1])?, [&line[..1], &line[2..]].concat())
    };
    let kind = src.integer(k, w[1])?;
    if kind < 1 {
        return Err(src.bad(k, format!("atom type {kind}: types count from 1")));
    }
    let x = src.vector(k, &w, 2)?;
    let image = if w.len() == 8 {
        [
            src.integer(k, w[5])?,
            src.integer(k, w[6])?,
            src.integer(k, w[7])?,
        ]
    } else {
        [0; 3]
    };
    let sphere = if sphere {
        let (diameter, density) = (src.number(k, line[2])?, src.number(k, line[3])?);
        if diameter <= 0.0 || density <= 0.0 {
            return Err(src.bad(
                k,
                format!("diameter {diameter} and density {density} must be positive"),
            ));
        }
        let r = 0.5 * diameter;
        // LAMMPS's mass of a sphere, formed in its order.
        Some((r, density * (4.0 * std::f64::consts::PI / 3.0 * r * r * r)))
    } else {
        None
    };
    // Positions whole: grains crossing periodic faces are unwrapped
    // through their image flags.
    let (l, tilt) = (header.lengths(), header.tilt);
    let x = [
        x[0] + image[0] as f64 * l[0] + image[1] as f64 * tilt[0] + image[2] as f64 * tilt[1],
        x[1] + image[1] as f64 * l[1] + image[2] as f64 * tilt[2],
        x[2] + image[2] as f64 * l[2],
    ];
    let id = src.integer(k, w[0])?;
    if id < 1 {
        return Err(src.bad(k, format!("atom id {id}: ids count from 1")));
    }
    Ok(Atom {
        id,
        mol,
        kind: kind as u32,
        x,
        sphere,
    })
}

/// The scene of what was read: atoms ordered by id, molecules as grains,
/// bonds as particle pairs with the file's lengths as reference.
fn assemble(
    src: &Source,
    header: Header,
    read: Sections,
    periodic: [bool; 3],
    force_field: ForceField,
    seed: u64,
) -> Result<Scene, DataFileError> {
    let Sections {
        masses,
        mut atoms,
        velocities,
        angular,
        sphere,
        bonds,
    } = read;
    if atoms.len() != header.atoms {
        return Err(src.bad(
            0,
            format!(
                "the header says {} atoms, the Atoms section has {}",
                header.atoms,
                atoms.len()
            ),
        ));
    }
    if bonds.len() != header.bonds {
        return Err(src.bad(
            0,
            format!(
                "the header says {} bonds, the Bonds section has {}",
                header.bonds,
                bonds.len()
            ),
        ));
    }
    atoms.sort_by_key(|a| a.id);
    if let Some(w) = atoms.windows(2).find(|w| w[0].id == w[1].id) {
        return Err(src.bad(0, format!("atom id {} appears twice", w[0].id)));
    }
    let pairs = bond_pairs(src, &atoms, &bonds)?;
    let mass = particle_masses(src, &atoms, &masses, sphere)?;
    let velocities = per_atom(&atoms, &velocities)
        .ok_or_else(|| src.bad(0, "the Velocities section does not list every atom".into()))?;
    let angular_velocities = per_atom(&atoms, &angular).ok_or_else(|| {
        src.bad(
            0,
            "the Velocities section gives angular velocities for some atoms only".into(),
        )
    })?;
    if sphere && !pairs.is_empty() {
        return Err(src.bad(0, "a sphere (DEM) data file has no bonds".into()));
    }
    let force_field = model_force_field(src, sphere, force_field)?;
    let uniform = mass.iter().all(|&m| m == mass[0]);
    let mut scene = Scene {
        version: crate::scene::SCENE_VERSION,
        model: if sphere {
            ModelKind::Dem
        } else {
            ModelKind::Bpm
        },
        description: format!("imported from {}", src.path.display()),
        seed,
        simbox: BoxSpec {
            lo: header.lo,
            lengths: header.lengths(),
            tilt: header.tilt,
            periodic,
        },
        particles: Particles {
            positions: atoms.iter().map(|a| a.x).collect(),
            velocities,
            angular_velocities,
            grain: (!sphere).then(|| grain_indices(&atoms)),
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
        bonds: Bonds {
            pairs,
            r0: None,
            plastic_strain: None,
        },
        force_field,
        stages: Vec::new(),
        provenance: serde_json::json!({"imported_from": src.path.display().to_string()}),
    };
    // The reference: the bond lengths in the file.
    if !sphere {
        let r0 = crate::scene::load::reference_lengths(&scene);
        scene.bonds.r0 = Some(r0);
    }
    Ok(scene)
}

/// The grain of each atom: the distinct molecule ids in increasing order
/// become grains 0, 1, ...
fn grain_indices(atoms: &[Atom]) -> Vec<u32> {
    let mut mols: Vec<i64> = atoms.iter().map(|a| a.mol).collect();
    mols.sort_unstable();
    mols.dedup();
    atoms
        .iter()
        .map(|a| mols.binary_search(&a.mol).unwrap_or(0) as u32)
        .collect()
}

/// The bonds (line, atom id, atom id) as pairs of indices into `atoms`
/// (ordered by id).
fn bond_pairs(
    src: &Source,
    atoms: &[Atom],
    bonds: &[(usize, i64, i64)],
) -> Result<Vec<[usize; 2]>, DataFileError> {
    let index_of = |id: i64| atoms.binary_search_by_key(&id, |a| a.id).ok();
    let mut pairs = Vec::with_capacity(bonds.len());
    for &(k, a, b) in bonds {
        match (index_of(a), index_of(b)) {
            (Some(i), Some(j)) if i != j => pairs.push([i, j]),
            (Some(_), Some(_)) => return Err(src.bad(k, format!("bond joins atom {a} to itself"))),
            _ => {
                return Err(src.bad(
                    k,
                    format!("bond ({a}, {b}) names an atom that is not in Atoms"),
                ))
            }
        }
    }
    Ok(pairs)
}

/// Each atom's mass: a sphere's own, else its type's in `Masses` (1 when
/// the file has no `Masses`; a type missing from it is an error).
fn particle_masses(
    src: &Source,
    atoms: &[Atom],
    masses: &BTreeMap<u32, f64>,
    sphere: bool,
) -> Result<Vec<f64>, DataFileError> {
    let mass_of = |t: u32| masses.get(&t).copied();
    if !masses.is_empty() && !sphere {
        if let Some(a) = atoms.iter().find(|a| mass_of(a.kind).is_none()) {
            return Err(src.bad(
                0,
                format!("atom {} has type {} with no mass in Masses", a.id, a.kind),
            ));
        }
    }
    Ok(atoms
        .iter()
        .map(|a| {
            a.sphere
                .map_or_else(|| mass_of(a.kind).unwrap_or(1.0), |(_, m)| m)
        })
        .collect())
}

/// `values` for every atom in order: `Some(None)` when the file gave
/// none, `None` when it gave some atoms only.
fn per_atom(atoms: &[Atom], values: &BTreeMap<i64, [f64; 3]>) -> Option<Option<Vec<[f64; 3]>>> {
    if values.is_empty() {
        return Some(None);
    }
    atoms
        .iter()
        .map(|a| values.get(&a.id).copied())
        .collect::<Option<Vec<_>>>()
        .map(Some)
}

/// The scene's force field: the file decides the model; everything else
/// of the caller's force field (skin, gravity, the multi-contact closure)
/// stays.
fn model_force_field(
    src: &Source,
    sphere: bool,
    force_field: ForceField,
) -> Result<ForceField, DataFileError> {
    match (sphere, force_field.granular) {
        (true, Some(_)) => Ok(ForceField {
            bond: BondCoeffs::default(),
            pair: None,
            zero_net_multibody: false,
            ..force_field
        }),
        (true, None) => Err(src.bad(
            0,
            "this is a DEM data file (atom_style sphere): give the sphere material (`bpm import --granular`)".into(),
        )),
        (false, Some(_)) => Err(src.bad(
            0,
            "a sphere material was given, but this is a bonded-particle data file (atom_style bond)".into(),
        )),
        (false, None) => Ok(force_field),
    }
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
