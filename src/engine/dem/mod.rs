//! DEM spheres as a particle model of the engine: one rigid sphere per
//! grain, Hertz-Mindlin contacts with sliding, rolling and twisting
//! friction (`kernels::granular_contact`), integrated with rotation.
//!
//! The model owns the contact coefficients and the per-contact history
//! ([`ContactStore`]). LAMMPS's `pair_style granular` computes no energy,
//! so neither does this model: its recorded observables are the stress
//! (the virial of the contact forces) and the kinetic energies.

mod contacts;
mod wall;

pub use contacts::ContactStore;
pub use wall::{ActiveGranularWall, GranularWall};

use super::model::{EnergyTerm, ForceInput, ForceOutput, ModelTally, ParticleModel};
use super::neighbor::Exclusions;
use super::simbox::MinimumImage;
use super::timers::Stage;
use crate::kernels::{
    granular_contact, ContactForce, GranularCoeffs, GranularMaterial, Sphere, Tally,
};

/// DEM spheres of one material.
#[derive(Debug)]
pub struct DemModel {
    material: GranularMaterial,
    coeffs: GranularCoeffs,
    /// Largest sphere radius: contacts reach `2 max_radius`.
    max_radius: f64,
    contacts: ContactStore,
}

impl DemModel {
    /// Spheres of `material` whose largest radius is `max_radius`.
    pub fn new(material: GranularMaterial, max_radius: f64) -> Self {
        Self {
            material,
            coeffs: GranularCoeffs::of(&material),
            max_radius,
            contacts: ContactStore::default(),
        }
    }

    /// The material.
    pub fn material(&self) -> &GranularMaterial {
        &self.material
    }

    /// Replaces the material (a stage's force-field change); contact
    /// histories are kept, as LAMMPS keeps them across `pair_coeff`.
    pub fn set_material(&mut self, material: GranularMaterial) {
        self.material = material;
        self.coeffs = GranularCoeffs::of(&material);
    }

    /// The per-contact histories.
    pub fn contacts(&self) -> &ContactStore {
        &self.contacts
    }

    fn forces(
        &mut self,
        sep: &MinimumImage,
        input: &ForceInput<'_>,
        f: &mut [[f64; 3]],
        mut torque: Option<&mut [[f64; 3]]>,
    ) -> Tally {
        // The engine gives rotational models angular velocities; without
        // them (a caller's choice) spheres count as not spinning.
        let omega = input.omega.unwrap_or(&[]);
        let (x, v, radius, mass) = (input.x, input.v, input.radius, input.mass);
        let list = input.neighbours;
        self.contacts.align(list);
        let (dt, update) = match input.step_dt {
            Some(dt) => (dt, true),
            None => (0.0, false),
        };
        let mut tally = Tally::default();
        let sphere = |i: usize| Sphere {
            v: v[i],
            omega: omega.get(i).copied().unwrap_or([0.0; 3]),
            radius: radius[i],
            mass: mass[i],
        };
        for i in 0..x.len() {
            let (si, xi) = (sphere(i), x[i]);
            for k in list.offsets[i]..list.offsets[i + 1] {
                let j = list.neighbours[k] as usize;
                let (del, image) = sep.delta_image(&xi, &x[j]);
                let rsq = del[0] * del[0] + del[1] * del[1] + del[2] * del[2];
                let radsum = si.radius + radius[j];
                let history = &mut self.contacts.history[k];
                if rsq >= radsum * radsum {
                    *history = Default::default();
                    continue;
                }
                let mut sj = sphere(j);
                // A partner across a Lees-Edwards face is an image moving
                // with the boundary.
                if let (Some(le), true) = (&input.lees_edwards, image != [0.0; 3]) {
                    for (v, w) in sj.v.iter_mut().zip(le.image_velocity(&image)) {
                        *v += w;
                    }
                }
                let ContactForce {
                    force,
                    torque_i,
                    torque_j,
                } = granular_contact(&self.coeffs, &del, &si, &sj, history, dt, update);
                for d in 0..3 {
                    f[i][d] += force[d];
                    f[j][d] -= force[d];
                }
                if let Some(t) = torque.as_deref_mut() {
                    for d in 0..3 {
                        t[i][d] += torque_i[d];
                        t[j][d] += torque_j[d];
                    }
                }
                if input.tally {
                    tally.add_vector(1.0, &del, &force);
                }
            }
        }
        tally
    }
}

impl ParticleModel for DemModel {
    fn name(&self) -> &'static str {
        "dem"
    }

    fn pair_cutoff(&self) -> Option<f64> {
        Some(2.0 * self.max_radius)
    }

    fn exclusions(&self) -> Option<&Exclusions> {
        None
    }

    fn rotational(&self) -> bool {
        true
    }

    fn energy_terms(&self) -> &'static [EnergyTerm] {
        &[]
    }

    fn compute(&mut self, input: &ForceInput<'_>, out: &mut ForceOutput<'_>) -> ModelTally {
        let _t = out.timers.start(Stage::Pairs);
        let sep = input.simbox.minimum_image();
        let mut tally = ModelTally::default();
        tally.terms[0] = self.forces(&sep, input, out.f, out.torque.as_deref_mut());
        tally
    }

    fn as_any(&self) -> &dyn std::any::Any {
        self
    }

    fn as_any_mut(&mut self) -> &mut dyn std::any::Any {
        self
    }
}
