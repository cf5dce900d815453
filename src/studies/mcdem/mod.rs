//! Studies of the multi-contact closures (docs/protocols.md, "Multi-contact
//! closures"): DEM spheres with plain Hertz contacts against the standard
//! and the advanced closure, on the multi-contact study's hydrogel
//! parameters.
//!
//! - [`rigid_box`] (`bpm mc-box`): one sphere, and nine in a body-centred
//!   cubic cell, squeezed in a rigid box: plate and side-wall stress
//!   against the plate's displacement;
//! - [`compression`] (`bpm mc-compress`): a bed of 514 spheres compressed
//!   uniaxially to volume fraction 0.85 and back, twice.

pub mod compression;
pub mod rigid_box;

use crate::engine::MultiContact;
use crate::kernels::{GranularMaterial, NormalDamping};
use crate::scene::StageOutput;
use serde::Serialize;

/// A contact closure compared in a study: plain Hertz (`None`) or a
/// multi-contact closure.
#[derive(Clone, Debug, PartialEq, Serialize)]
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
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
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
            gamma: 0.82,
            gamma_advanced: 0.81,
            mpr: 0.11,
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

/// What a stage records of a box whose granular wall 0 is the floor, 1
/// the lid and 2 to 5 the side walls (x lo, x hi, y lo, y hi), per
/// recorded row.
#[derive(Clone, Debug, Serialize)]
pub struct BoxWalls {
    /// Lid position (d); not written out (the studies give the lid's
    /// displacement or the volume fraction instead).
    #[serde(skip)]
    pub lid: Vec<f64>,
    /// Lid force over the box's cross-section (Pa).
    pub lid_stress: Vec<f64>,
    /// Mean over the four side walls of the force over the wall's area
    /// below the lid (Pa).
    pub side_stress: Vec<f64>,
    /// The largest multi-contact correction over its sphere's radius (0
    /// for Hertz).
    pub largest_correction: Vec<f64>,
    /// Contacts (or terms) the advanced closure switched off.
    pub switched_off: Vec<f64>,
}

impl BoxWalls {
    /// Reads `stage` of a box of base `[lx, ly]` (d), stresses in units of
    /// `pascal` Pa (the spheres' Young's modulus in reduced units).
    pub fn read(stage: &StageOutput, base: [f64; 2], pascal: f64) -> Self {
        let lid = column(stage, "granular_wall1_position");
        let lid_force = column(stage, "granular_wall1_force");
        let sides: Vec<Vec<f64>> = (2..6)
            .map(|w| column(stage, &format!("granular_wall{w}_force")))
            .collect();
        let side_stress = (0..lid.len())
            .map(|k| {
                let sum: f64 = (0..2)
                    .map(|axis| {
                        let area = base[1 - axis] * lid[k];
                        (sides[2 * axis][k] + sides[2 * axis + 1][k]) / area
                    })
                    .sum();
                0.25 * sum * pascal
            })
            .collect();
        Self {
            lid_stress: lid_force
                .iter()
                .map(|f| f / (base[0] * base[1]) * pascal)
                .collect(),
            side_stress,
            largest_correction: optional_column(stage, "mc_largest_correction"),
            switched_off: optional_column(stage, "mc_switched_off"),
            lid,
        }
    }

    /// The largest correction and switched-off count over every row.
    pub fn extremes(&self) -> (f64, f64) {
        let max = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
        (max(&self.largest_correction), max(&self.switched_off))
    }
}

fn column(stage: &StageOutput, name: &str) -> Vec<f64> {
    let c = stage
        .columns
        .iter()
        .position(|c| c.name == name)
        .expect("a granular-wall stage records its walls");
    stage.rows.iter().map(|r| r[c]).collect()
}

/// The column `name`, or zeros where the stage does not record it (the
/// closure's columns under plain Hertz).
fn optional_column(stage: &StageOutput, name: &str) -> Vec<f64> {
    match stage.columns.iter().position(|c| c.name == name) {
        Some(c) => stage.rows.iter().map(|r| r[c]).collect(),
        None => vec![0.0; stage.rows.len()],
    }
}

/// The hydrogel spheres of the multi-contact study (its Table 1) and the
/// reduced units the studies run in: lengths in sphere diameters `d`,
/// stresses in the spheres' Young's modulus `E`, masses in sphere masses
/// `m`, so times are in `tau = sqrt(m / (E d))`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
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

    /// A sphere's mass (kg).
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

    /// The sphere material in reduced units (`E = 1`). Damping and
    /// tangential stiffness follow the reference implementation of the
    /// closures (LIGGGHTS's Hertz model): the restitution form of the
    /// damping, and tangential damping `sqrt(2 (1 - nu) / (2 - nu))` times
    /// the normal one, which is its tangential dashpot in this contact law.
    pub fn material(&self) -> GranularMaterial {
        let nu = self.poisson_ratio;
        GranularMaterial {
            youngs_modulus: 1.0,
            poisson_ratio: nu,
            restitution: self.restitution,
            damping: NormalDamping::CoeffRestitution,
            tangential_damping: (2.0 * (1.0 - nu) / (2.0 - nu)).sqrt(),
            sliding_friction: self.friction,
            rolling: None,
            twisting: Default::default(),
        }
    }
}
