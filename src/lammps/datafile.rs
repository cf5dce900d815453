//! Writes a scene as a LAMMPS data file (`atom_style bond`) plus the
//! `-var` values of the input templates in `lammps_inputs/` (embedded in
//! the binary, written next to each run by [`super::templates`]).

use crate::scene::load::reference_lengths;
use crate::scene::Scene;
use std::fmt::Write as _;
use std::path::Path;

/// Input-script variables derived from a scene.
#[derive(Clone, Debug)]
pub struct ScriptVars {
    /// `(name, value)` pairs for `-var name value`.
    pub vars: Vec<(String, String)>,
}

impl ScriptVars {
    /// The variables of `scene` for a data file at `data` (reference lengths
    /// at `data.r0`, see [`write_reference_lengths`]), `newton` setting and
    /// the templates in `inputs` (the folder
    /// [`write_templates`](super::templates::write_templates) returns).
    pub fn of(scene: &Scene, data: &str, newton: bool, inputs: &Path) -> Self {
        let ff = &scene.force_field;
        let pair = ff.pair.unwrap_or(crate::kernels::PairCoeffs {
            k: 0.0,
            d: 1.0,
            a: 0.0,
            gamma: 0.0,
        });
        let boundary: Vec<&str> = scene
            .simbox
            .periodic
            .iter()
            .map(|&p| if p { "p" } else { "f" })
            .collect();
        let max_r0 = reference_lengths(scene).into_iter().fold(0.0, f64::max);
        // Ghosts must reach every bond partner: the longest bond plus the skin.
        let comm_cutoff = (max_r0 * 1.2).max(pair.d) + ff.skin;
        let g = |v: f64| format!("{v:.17e}");
        let vars = [
            ("inputs", inputs.display().to_string()),
            ("data", data.to_string()),
            ("lengths", format!("{data}.r0")),
            ("boundary", boundary.join(" ")),
            ("newton", if newton { "on" } else { "off" }.to_string()),
            ("kB", g(ff.bond.k)),
            ("aB", g(ff.bond.a)),
            ("gB", g(ff.bond.gamma)),
            ("kP", g(pair.k)),
            ("d", g(pair.d)),
            ("aP", g(pair.a)),
            ("gP", g(pair.gamma)),
            ("skin", g(ff.skin)),
            ("commcut", g(comm_cutoff)),
        ];
        Self {
            vars: vars.into_iter().map(|(k, v)| (k.to_string(), v)).collect(),
        }
    }

    /// As command-line arguments: `-var name value ...`.
    pub fn args(&self) -> Vec<String> {
        self.vars
            .iter()
            .flat_map(|(k, v)| ["-var".to_string(), k.clone(), v.clone()])
            .collect()
    }
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

/// The data file text of `scene`: atoms (id, grain + 1 as molecule, type,
/// x y z), velocities and bonds (type 1). Particle `i` is atom `i + 1`.
/// Masses are per type ([`type_masses`]; the harness refuses scenes where
/// that fails, and here the first particle's mass stands in).
pub fn write_data_file(scene: &Scene) -> String {
    let b = &scene.simbox;
    let pa = &scene.particles;
    let n = pa.positions.len();
    let mut s = String::new();
    let _ = writeln!(
        s,
        "LAMMPS data file written by bpm {} (scene seed {})\n",
        crate::VERSION,
        scene.seed
    );
    let masses = type_masses(scene).unwrap_or_else(|| vec![pa.mass.values(n)[0]]);
    let _ = writeln!(
        s,
        "{n} atoms\n{} bonds\n{} atom types\n1 bond types\n",
        scene.bonds.pairs.len(),
        masses.len()
    );
    let hi = |d: usize| b.lo[d] + b.lengths[d];
    let _ = writeln!(s, "{:.17e} {:.17e} xlo xhi", b.lo[0], hi(0));
    let _ = writeln!(s, "{:.17e} {:.17e} ylo yhi", b.lo[1], hi(1));
    let _ = writeln!(s, "{:.17e} {:.17e} zlo zhi", b.lo[2], hi(2));
    if super::script::needs_triclinic(scene) {
        let _ = writeln!(
            s,
            "{:.17e} {:.17e} {:.17e} xy xz yz",
            b.tilt[0], b.tilt[1], b.tilt[2]
        );
    }
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
            i + 1,
            grain + 1,
            x[0],
            x[1],
            x[2]
        );
    }
    if let Some(v) = &pa.velocities {
        let _ = writeln!(s, "\nVelocities\n");
        for (i, v) in v.iter().enumerate() {
            let _ = writeln!(s, "{} {:.17e} {:.17e} {:.17e}", i + 1, v[0], v[1], v[2]);
        }
    }
    if !scene.bonds.pairs.is_empty() {
        let _ = writeln!(s, "\nBonds\n");
        for (k, [i, j]) in scene.bonds.pairs.iter().enumerate() {
            let _ = writeln!(s, "{} 1 {} {}", k + 1, i + 1, j + 1);
        }
    }
    s
}

/// The reference length of every bond as `tag_i tag_j r0` lines, read by
/// `fix_modify BPM_REFERENCE lengths FILE`. Bonds without an explicit `r0`
/// get their minimum-image length, as the native engine does.
pub fn write_reference_lengths(scene: &Scene) -> String {
    let mut s = String::from("# tag_i tag_j r0\n");
    for (&[i, j], r0) in scene.bonds.pairs.iter().zip(reference_lengths(scene)) {
        let _ = writeln!(s, "{} {} {:.17e}", i + 1, j + 1, r0);
    }
    s
}
