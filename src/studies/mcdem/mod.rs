//! Studies of the multi-contact closures (docs/protocols.md, "Multi-contact
//! closures"): DEM spheres with plain Hertz contacts against the standard
//! and the advanced closure, on the multi-contact study's hydrogel
//! parameters.
//!
//! - [`rigid_box`] (`bpm mc-box`): one sphere, and nine in a body-centred
//!   cubic cell, squeezed in a rigid box: plate and side-wall stress
//!   against the plate's displacement;
//! - [`compression`] (`bpm mc-compress`): a bed of 514 spheres compressed
//!   uniaxially to volume fraction 0.85 and back, twice;
//! - [`calibration`] (`bpm mc-calibrate`): the closures' `gamma` and `MPR`
//!   fitted to the pressure of bonded grains compressed from the same
//!   packing;
//! - [`shear`] (`bpm mc-shear`): monodisperse spheres sheared at constant
//!   volume above jamming; the quasi-static pressure's power law against
//!   the study's Tables D.1 and D.2.

pub mod calibration;
pub mod cli;
pub mod compression;
pub mod lid;
pub mod rigid_box;
pub mod shear;

use crate::engine::MultiContact;
use crate::kernels::GranularMaterial;
use crate::reference::multicontact;
use crate::scene::protocols::lid::liggghts_hertz_material;
pub use crate::scene::protocols::lid::WalledBox;
use crate::scene::{
    BoxSpec, ForceField, Mass, ModelKind, Particles, Scene, StageOutput, StageSpec,
};
use serde::Serialize;

/// A contact closure compared in a study: plain Hertz (`None`) or a
/// multi-contact closure.
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct Variant {
    /// Name in tables and legends.
    pub name: String,
    /// The closure, `None` for plain Hertz.
    pub multicontact: Option<MultiContact>,
}

/// The three contact laws a study compares: plain Hertz, the standard
/// closure with prefactor `gamma` and the advanced one with
/// `gamma_advanced` and `mpr`. The defaults are the values the
/// multi-contact study calibrated on its single-particle tests (its
/// Appendix B).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct Closures {
    /// Standard closure's prefactor.
    pub gamma: f64,
    /// Advanced closure's prefactor.
    pub gamma_advanced: f64,
    /// Advanced closure's maximum penetration ratio.
    pub mpr: f64,
}

impl Default for Closures {
    fn default() -> Self {
        Self {
            gamma: multicontact::STANDARD_GAMMA,
            gamma_advanced: multicontact::ADVANCED_GAMMA,
            mpr: multicontact::ADVANCED_MPR,
        }
    }
}

impl Closures {
    /// Checks the values; the error names the option at fault.
    pub fn validate(&self) -> Result<(), String> {
        for (name, v) in [
            ("--gamma", self.gamma),
            ("--gamma-advanced", self.gamma_advanced),
            ("--mpr", self.mpr),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(format!("{name} must be >= 0 (got {v})"));
            }
        }
        Ok(())
    }

    /// Plain Hertz, the standard closure and the advanced one.
    pub fn variants(&self) -> Vec<Variant> {
        vec![
            Variant {
                name: "Hertz".into(),
                multicontact: None,
            },
            Variant {
                name: format!("standard (gamma {})", self.gamma),
                multicontact: Some(MultiContact::standard(self.gamma)),
            },
            Variant {
                name: format!("advanced (gamma {}, MPR {})", self.gamma_advanced, self.mpr),
                multicontact: Some(MultiContact::advanced(self.gamma_advanced, self.mpr)),
            },
        ]
    }
}

impl WalledBox {
    /// A box of base `base` and highest lid `height` whose walls have the
    /// spheres' material but for a modulus of `wall_modulus` Pa.
    pub fn new(base: [f64; 2], height: f64, hydrogel: &Hydrogel, wall_modulus: f64) -> Self {
        Self {
            base,
            height,
            material: GranularMaterial {
                youngs_modulus: wall_modulus / hydrogel.youngs_modulus,
                ..hydrogel.material()
            },
            keep_history: false,
        }
    }

    /// A scene of hydrogel spheres at `positions` with `radius` and
    /// `mass` in this box, contacts by `variant`, running `stages`
    /// (reduced units; a closed simulation box half a diameter beyond the
    /// walls).
    #[allow(clippy::too_many_arguments)]
    pub fn scene(
        &self,
        description: String,
        seed: u64,
        positions: Vec<[f64; 3]>,
        radius: Vec<f64>,
        mass: Mass,
        hydrogel: &Hydrogel,
        variant: &Variant,
        stages: Vec<StageSpec>,
    ) -> Scene {
        let mut force_field = ForceField::dem(hydrogel.material());
        force_field.multicontact = variant.multicontact;
        // The skin is in d: a tenth of a diameter suits spheres this slow.
        force_field.skin = 0.1;
        Scene {
            version: crate::scene::SCENE_VERSION,
            model: ModelKind::Dem,
            description,
            seed,
            simbox: BoxSpec {
                lo: [-0.5; 3],
                lengths: [self.base[0] + 1.0, self.base[1] + 1.0, self.height + 1.0],
                tilt: [0.0; 3],
                periodic: [false; 3],
            },
            particles: Particles {
                positions,
                velocities: None,
                angular_velocities: None,
                grain: None,
                mass,
                radius: Some(radius),
                kind: None,
                ids: None,
            },
            bonds: Default::default(),
            force_field,
            stages,
            provenance: serde_json::Value::Null,
        }
    }
}

/// What a stage records of a box whose granular wall 0 is the floor, 1
/// the lid and 2 to 5 the side walls (x lo, x hi, y lo, y hi), per
/// recorded row.
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
pub struct BoxWalls {
    /// Lid position (d); not written out (the studies give the lid's
    /// displacement or the volume fraction instead).
    #[serde(skip)]
    pub lid: Vec<f64>,
    /// Lid force over the box's cross-section (Pa).
    #[serde(deserialize_with = "crate::json_nan::nan_if_null_each")]
    pub lid_stress: Vec<f64>,
    /// Mean over the four side walls of the force over the wall's area
    /// below the lid (Pa).
    #[serde(deserialize_with = "crate::json_nan::nan_if_null_each")]
    pub side_stress: Vec<f64>,
    /// The largest multi-contact correction over its sphere's radius (0
    /// for Hertz).
    #[serde(deserialize_with = "crate::json_nan::nan_if_null_each")]
    pub largest_correction: Vec<f64>,
    /// Contacts (or terms) the advanced closure switched off.
    #[serde(deserialize_with = "crate::json_nan::nan_if_null_each")]
    pub switched_off: Vec<f64>,
}

impl BoxWalls {
    /// Reads `stage` of a box of base `[lx, ly]` (d), stresses in units of
    /// `stress_unit` Pa (the spheres' Young's modulus, in reduced units
    /// 1).
    ///
    /// # Panics
    ///
    /// If the stage does not record six granular walls.
    pub fn read(stage: &StageOutput, base: [f64; 2], stress_unit: f64) -> Self {
        let column = |name: &str| {
            stage
                .column(name)
                .unwrap_or_else(|| panic!("a box's stage records {name}"))
        };
        // The closure's columns are absent under plain Hertz.
        let optional = |name: &str| {
            stage
                .column(name)
                .unwrap_or_else(|| vec![0.0; stage.rows.len()])
        };
        let lid = column("granular_wall1_position");
        let lid_force = column("granular_wall1_force");
        let sides: Vec<Vec<f64>> = (2..6)
            .map(|w| column(&format!("granular_wall{w}_force")))
            .collect();
        let side_stress = (0..lid.len())
            .map(|k| {
                let sum: f64 = (0..2)
                    .map(|axis| {
                        let area = base[1 - axis] * lid[k];
                        (sides[2 * axis][k] + sides[2 * axis + 1][k]) / area
                    })
                    .sum();
                0.25 * sum * stress_unit
            })
            .collect();
        Self {
            lid_stress: lid_force
                .iter()
                .map(|f| f / (base[0] * base[1]) * stress_unit)
                .collect(),
            side_stress,
            largest_correction: optional("mc_largest_correction"),
            switched_off: optional("mc_switched_off"),
            lid,
        }
    }

    /// The largest correction and switched-off count over every row.
    pub fn extremes(&self) -> (f64, f64) {
        let max = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
        (max(&self.largest_correction), max(&self.switched_off))
    }
}

/// The hydrogel spheres of the multi-contact study (its Table 1) and the
/// reduced units the studies run in: lengths in sphere diameters `d`,
/// stresses in the spheres' Young's modulus `E`, masses in sphere masses
/// `m`, so times are in `tau = sqrt(m / (E d))`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct Hydrogel {
    /// Sphere diameter (m).
    pub diameter: f64,
    /// Young's modulus (Pa).
    pub youngs_modulus: f64,
    /// Poisson's ratio.
    pub poisson_ratio: f64,
    /// Density less the surrounding water's (kg / m^3).
    pub effective_density: f64,
    /// Normal restitution coefficient.
    pub restitution: f64,
    /// Sliding friction coefficient (spheres and walls).
    pub friction: f64,
}

impl Hydrogel {
    /// Table 1 with spheres of diameter `diameter` (m): 2 mm in the
    /// study's single-particle tests, about 2.1 cm in its bed.
    pub fn table_1(diameter: f64) -> Self {
        Self {
            diameter,
            youngs_modulus: 23.3e3,
            poisson_ratio: 0.5,
            effective_density: 11.5,
            restitution: 0.95,
            friction: 0.03,
        }
    }

    /// A sphere's mass (kg), from the effective density: the beads move
    /// in water, and the studies give them the inertia the reference
    /// implementation gives them (without the water's added mass). With
    /// the beads' full density the time unit would be about 9.4 times
    /// longer, and a lid speed in m/s that many times faster in d / tau.
    pub fn mass(&self) -> f64 {
        self.effective_density * std::f64::consts::PI / 6.0 * self.diameter.powi(3)
    }

    /// The time unit `tau` (s).
    pub fn time_unit(&self) -> f64 {
        (self.mass() / (self.youngs_modulus * self.diameter)).sqrt()
    }

    /// A speed in m/s in d / tau.
    pub fn reduced_speed(&self, metres_per_second: f64) -> f64 {
        metres_per_second * self.time_unit() / self.diameter
    }

    /// A speed in d / tau in m/s.
    pub fn physical_speed(&self, reduced: f64) -> f64 {
        reduced * self.diameter / self.time_unit()
    }

    /// The sphere material in reduced units (`E = 1`). Damping and
    /// tangential stiffness follow the reference implementation of the
    /// closures (LIGGGHTS's Hertz model): the restitution form of the
    /// damping, and tangential damping `sqrt(2 (1 - nu) / (2 - nu))` times
    /// the normal one, which is its tangential dashpot in this contact law.
    pub fn material(&self) -> GranularMaterial {
        liggghts_hertz_material(self.poisson_ratio, self.restitution, self.friction)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A stage output recording six granular walls' forces and positions
    /// in one row.
    fn box_stage(forces: [f64; 6], lid: f64) -> StageOutput {
        let mut columns = Vec::new();
        let mut row = Vec::new();
        for (w, f) in forces.iter().enumerate() {
            for (what, value) in [("force", *f), ("position", lid)] {
                columns.push(serde_json::json!({
                    "name": format!("granular_wall{w}_{what}"),
                    "quantity": "time", "observable": "wall forces", "lammps": null
                }));
                row.push(value);
            }
        }
        serde_json::from_value(serde_json::json!({
            "name": "squeeze", "steps": 1, "columns": columns, "rows": [row],
            "checkpoints": [], "wall_seconds": 0.0, "timers": {}, "neighbour_builds": 0
        }))
        .unwrap()
    }

    #[test]
    fn side_stresses_divide_each_wall_force_by_its_own_area() {
        // Base 2 x 3, lid at height 4: the x walls are 3 x 4, the y walls
        // 2 x 4.
        let stage = box_stage([0.0, 6.0, 12.0, 12.0, 8.0, 8.0], 4.0);
        let walls = BoxWalls::read(&stage, [2.0, 3.0], 10.0);
        assert_eq!(walls.lid_stress, vec![6.0 / 6.0 * 10.0]);
        // x walls 12 / 12 = 1, y walls 8 / 8 = 1: mean 1, times 10.
        assert!((walls.side_stress[0] - 10.0).abs() < 1e-12);
        assert_eq!(walls.largest_correction, vec![0.0]);
        // Swapped forces give a different mean: the areas are not swapped.
        let swapped = BoxWalls::read(
            &box_stage([0.0, 6.0, 8.0, 8.0, 12.0, 12.0], 4.0),
            [2.0, 3.0],
            10.0,
        );
        let expected = 0.25 * (2.0 * 8.0 / 12.0 + 2.0 * 12.0 / 8.0) * 10.0;
        assert!((swapped.side_stress[0] - expected).abs() < 1e-12);
    }
}
