//! Writes a scene as a LAMMPS data file (`atom_style bond`) plus the
//! `-var` values of the input templates in `lammps_inputs/` (embedded in
//! the binary, written next to each run by [`super::templates`]).

pub use crate::scene::datafile::{type_masses, write_data_file};
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
            (
                "zeronet",
                super::script::yes_no(ff.zero_net_multibody).to_string(),
            ),
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
