//! Writes a scene as a LAMMPS data file (`atom_style bond`) plus the
//! `-var` values of the input templates in `lammps_inputs/` (embedded in
//! the binary, written next to each run by [`super::templates`]).

use crate::engine::MultiContact;
use crate::kernels::{
    GranularCoeffs, GranularMaterial, MprSwitch, MprTest, NormalDamping, Twisting,
};
pub use crate::scene::datafile::type_masses;
use crate::scene::datafile::{write_data_file_with_ids, AtomIds};
use crate::scene::load::reference_lengths;
use crate::scene::Scene;
use std::fmt::Write as _;
use std::path::Path;

/// The data file of a LAMMPS run of `scene` (the harness's, the cross
/// checks'): atoms numbered `1..=N` in particle order, whatever the
/// scene's `particles.ids`, so LAMMPS's atom `i + 1` is particle `i` when
/// its state is gathered back (dump frames then get the scene's ids
/// again, see `scene::run::Recorders::with_ids`).
pub fn write_run_data_file(scene: &Scene) -> String {
    write_data_file_with_ids(scene, AtomIds::Sequential)
}

/// LAMMPS's spelling of a flag.
pub(crate) fn yes_no(flag: bool) -> &'static str {
    if flag {
        "yes"
    } else {
        "no"
    }
}

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
        let boundary: Vec<&str> = scene
            .simbox
            .periodic
            .iter()
            .map(|&p| if p { "p" } else { "f" })
            .collect();
        let g = |v: f64| format!("{v:.17e}");
        if let Some(material) = &ff.granular {
            // The closure's pair style computes each pair on every rank
            // that owns one of its spheres: newton off, whatever is asked.
            let closure = uses_closure(scene);
            let newton = newton && !closure;
            let vars = [
                ("inputs", inputs.display().to_string()),
                ("data", data.to_string()),
                ("boundary", boundary.join(" ")),
                ("newton", if newton { "on" } else { "off" }.to_string()),
                (
                    "pair",
                    if closure { "bpm/granular" } else { "granular" }.to_string(),
                ),
                (
                    "granular",
                    dem_pair_coeff(material, ff.multicontact.as_ref(), closure),
                ),
                ("skin", g(ff.skin)),
                ("integrator", "nve/sphere".to_string()),
            ];
            return Self {
                vars: vars.into_iter().map(|(k, v)| (k.to_string(), v)).collect(),
            };
        }
        let pair = ff.pair.unwrap_or(crate::kernels::PairCoeffs {
            k: 0.0,
            d: 1.0,
            a: 0.0,
            gamma: 0.0,
        });
        let max_r0 = reference_lengths(scene).into_iter().fold(0.0, f64::max);
        // Ghosts must reach every bond partner: the longest bond plus the skin.
        let comm_cutoff = (max_r0 * 1.2).max(pair.d) + ff.skin;
        let vars = [
            ("inputs", inputs.display().to_string()),
            ("data", data.to_string()),
            ("lengths", format!("{data}.r0")),
            ("boundary", boundary.join(" ")),
            ("newton", if newton { "on" } else { "off" }.to_string()),
            ("kB", g(ff.bond.k)),
            ("aB", g(ff.bond.a)),
            ("gB", g(ff.bond.gamma)),
            ("zeronet", yes_no(ff.zero_net_multibody).to_string()),
            ("kP", g(pair.k)),
            ("d", g(pair.d)),
            ("aP", g(pair.a)),
            ("gP", g(pair.gamma)),
            ("skin", g(ff.skin)),
            ("commcut", g(comm_cutoff)),
            ("integrator", "nve".to_string()),
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

/// The arguments of `pair_coeff * *` for spheres of `m` in LAMMPS's
/// `pair_style granular`: `hertz/material E e nu damping tsuji tangential
/// mindlin NULL x_gt mu_s` and the rolling and twisting models. The
/// restitution form of the damping has no keyword in LAMMPS 2021 (it is
/// written as `damping coeff_restitution`, which that LAMMPS refuses:
/// [`crate::lammps::script`] stops such scenes first).
pub fn granular_pair_coeff(m: &GranularMaterial) -> String {
    let g = |v: f64| format!("{v:.17e}");
    let damping = match m.damping {
        NormalDamping::Tsuji => "tsuji",
        NormalDamping::CoeffRestitution => "coeff_restitution",
    };
    format!(
        "hertz/material {} {} {} damping {damping} tangential mindlin NULL {} {}{}",
        g(m.youngs_modulus),
        g(m.restitution),
        g(m.poisson_ratio),
        g(m.tangential_damping),
        g(m.sliding_friction),
        rolling_twisting(m)
    )
}

/// Whether any force field of `scene` turns the multi-contact closure on:
/// then the whole scene runs with the plugin's `pair_style bpm/granular`
/// (a stage without the closure gives it plain Hertz), so the contact
/// memory carries across stages as in the native engine.
pub fn uses_closure(scene: &Scene) -> bool {
    scene.force_field.multicontact.is_some()
        || scene.stages.iter().any(|s| {
            s.force_field
                .as_ref()
                .is_some_and(|ff| ff.multicontact.is_some())
        })
}

/// The arguments of `pair_coeff * *` for spheres of `m`: LAMMPS's
/// `pair_style granular` ([`granular_pair_coeff`]), or with `bpm_style`
/// the plugin's `pair_style bpm/granular`, which reads the same words and
/// then the closure `mc`: `multicontact gamma [mpr MPR switch S test T]
/// reach R` (parsed by `bpm::ffi::parse_coeffs`).
pub fn dem_pair_coeff(m: &GranularMaterial, mc: Option<&MultiContact>, bpm_style: bool) -> String {
    let mut s = granular_pair_coeff(m);
    if let (true, Some(mc)) = (bpm_style, mc) {
        let g = |v: f64| format!("{v:.17e}");
        s += &format!(" multicontact {}", g(mc.prefactor));
        if let Some(mpr) = mc.max_penetration_ratio {
            let switch = match mc.switch {
                MprSwitch::WholeContact => "whole_contact",
                MprSwitch::PerTerm => "per_term",
            };
            let test = match mc.test {
                MprTest::Signed => "signed",
                MprTest::Magnitude => "magnitude",
            };
            s += &format!(" mpr {} switch {switch} test {test}", g(mpr));
        }
        s += &format!(" reach {}", g(mc.reach));
    }
    s
}

/// LAMMPS 2021's prefactor `4/3 E / (2 (1 - nu))` of a granular wall's
/// Hertz force, with its literal for 4/3 (one unit in the last place
/// below 4/3).
const LAMMPS_WALL_FOUR_THIRDS: f64 = 1.333333333333333;

/// The `granular` model of LAMMPS 2021's `fix wall/gran/region` for a
/// wall of material `wall` whose contacts with the spheres have the
/// coefficients `c` (native [`crate::engine::ActiveGranularWall::coeffs`]).
///
/// LAMMPS 2021's wall uses only its own E and nu, and forms the normal
/// prefactor as `4/3 E / (2 (1 - nu))` and its default Mindlin stiffness
/// from a compliance formula (both unlike its pair style); so it gets `nu
/// = 0` and the `E` whose prefactor is `k_n` (`2 k_n / 1.333333333333333`),
/// and `k_t` explicitly.
pub fn granular_wall_model(c: &GranularCoeffs, wall: &GranularMaterial) -> String {
    let g = |v: f64| format!("{v:.17e}");
    let youngs = c.normal_stiffness / LAMMPS_WALL_FOUR_THIRDS * 2.0;
    format!(
        "hertz/material {} {} 0 damping tsuji tangential mindlin {} {} {}{}",
        g(youngs),
        g(wall.restitution),
        g(c.tangential_stiffness),
        g(c.tangential_damping),
        g(c.sliding_friction),
        rolling_twisting(wall)
    )
}

/// The rolling and twisting keywords of a granular model.
fn rolling_twisting(m: &GranularMaterial) -> String {
    let g = |v: f64| format!("{v:.17e}");
    let mut s = String::new();
    if let Some(r) = &m.rolling {
        s += &format!(
            " rolling sds {} {} {}",
            g(r.stiffness),
            g(r.damping),
            g(r.friction)
        );
    }
    match &m.twisting {
        Twisting::None => {}
        Twisting::Marshall => s += " twisting marshall",
        Twisting::Sds(t) => {
            s += &format!(
                " twisting sds {} {} {}",
                g(t.stiffness),
                g(t.damping),
                g(t.friction)
            )
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

#[cfg(test)]
mod tests {
    use super::*;

    /// LAMMPS 2021's wall, given the model string, computes `k_n` as
    /// `E / (2 (1 - nu)) * 1.333333333333333` and takes `k_t` as given:
    /// both must come back as the native coefficients.
    #[test]
    fn the_wall_model_gives_lammps_the_native_coefficients() {
        let spheres = crate::verify::dem_check_material(false);
        let wall = GranularMaterial {
            youngs_modulus: 1e4,
            poisson_ratio: 0.35,
            ..crate::verify::dem_check_material(true)
        };
        let c = GranularCoeffs::between(&spheres, &wall);
        let model = granular_wall_model(&c, &wall);
        let words: Vec<&str> = model.split_whitespace().collect();
        assert_eq!(words[0], "hertz/material");
        let e: f64 = words[1].parse().unwrap();
        let nu: f64 = words[3].parse().unwrap();
        let k_n = e / (2.0 * (1.0 - nu)) * LAMMPS_WALL_FOUR_THIRDS;
        assert!((k_n - c.normal_stiffness).abs() <= 2.0 * f64::EPSILON * c.normal_stiffness);
        let at = |key: &str| words.iter().position(|w| *w == key).unwrap();
        let mindlin = at("mindlin");
        assert_eq!(
            words[mindlin + 1].parse::<f64>().unwrap(),
            c.tangential_stiffness
        );
        assert_eq!(
            words[mindlin + 3].parse::<f64>().unwrap(),
            wall.sliding_friction
        );
        assert_eq!(words[2].parse::<f64>().unwrap(), wall.restitution);
        assert!(model.contains("rolling sds") && model.ends_with("twisting marshall"));
    }

    /// The plugin's style reads back every setting the harness writes.
    #[test]
    fn the_closure_coefficients_round_trip_through_the_plugin_parser() {
        let material = crate::verify::dem_check_material(true);
        let other = GranularMaterial {
            damping: NormalDamping::CoeffRestitution,
            twisting: Twisting::Sds(crate::kernels::SpringDashpotSlider {
                stiffness: 2.0,
                damping: 0.25,
                friction: 0.125,
            }),
            ..material
        };
        let words = dem_pair_coeff(&other, Some(&MultiContact::standard(0.5)), true);
        let parsed =
            crate::ffi::parse_coeffs(&words.split_whitespace().collect::<Vec<_>>()).unwrap();
        assert_eq!(parsed.material, other);
        for mc in [
            MultiContact::standard(0.82),
            MultiContact {
                switch: MprSwitch::PerTerm,
                test: MprTest::Magnitude,
                reach: 0.4,
                ..MultiContact::advanced(0.81, 0.11)
            },
        ] {
            let words = dem_pair_coeff(&material, Some(&mc), true);
            let parsed =
                crate::ffi::parse_coeffs(&words.split_whitespace().collect::<Vec<_>>()).unwrap();
            assert_eq!(parsed.material, material);
            assert_eq!(parsed.multicontact, Some(mc));
        }
        assert_eq!(
            dem_pair_coeff(&material, Some(&MultiContact::standard(0.8)), false),
            granular_pair_coeff(&material)
        );
    }
}
