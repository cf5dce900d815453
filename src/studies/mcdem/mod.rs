//! Studies of the multi-contact closures (docs/protocols.md, "Multi-contact
//! closures"): DEM spheres with plain Hertz contacts against the standard
//! and the advanced closure, on the multi-contact study's hydrogel
//! parameters.
//!
//! - [`rigid_box`] (`bpm mc-box`): one sphere, and nine in a body-centred
//!   cubic cell, squeezed in a rigid box: plate and side-wall stress
//!   against the plate's displacement.

pub mod rigid_box;

use crate::engine::MultiContact;
use crate::kernels::{GranularMaterial, NormalDamping};
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

impl Variant {
    /// Plain Hertz, the standard closure with `gamma` and the advanced one
    /// with `gamma_advanced` and `mpr`.
    pub fn trio(gamma: f64, gamma_advanced: f64, mpr: f64) -> Vec<Variant> {
        vec![
            Variant {
                name: "Hertz".into(),
                multicontact: None,
            },
            Variant {
                name: format!("standard (gamma {gamma})"),
                multicontact: Some(MultiContact::standard(gamma)),
            },
            Variant {
                name: format!("advanced (gamma {gamma_advanced}, MPR {mpr})"),
                multicontact: Some(MultiContact::advanced(gamma_advanced, mpr)),
            },
        ]
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
    /// Table 1 with the 2 mm diameter of the study's single-particle
    /// tests.
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
