//! Flat frictional walls for DEM spheres: a plane normal to one axis,
//! moving along it at constant speed, touching spheres with the same
//! contact law as sphere pairs (`kernels::granular_wall_contact`), with
//! one contact history per sphere.

use super::super::external::{GranularWall, WallContact};
use super::super::model::ForceInput;
use crate::kernels::{
    granular_wall_contact, ContactHistory, GranularCoeffs, GranularMaterial, Sphere, WallPlane,
};

/// A granular wall resolved for one stage against the spheres' material.
#[derive(Clone, Debug, PartialEq)]
pub struct ActiveGranularWall {
    /// The wall.
    pub wall: GranularWall,
    coeffs: GranularCoeffs,
}

impl ActiveGranularWall {
    /// `wall` against spheres of material `spheres`.
    pub fn new(wall: &GranularWall, spheres: &GranularMaterial) -> Self {
        Self {
            wall: wall.clone(),
            coeffs: GranularCoeffs::between(spheres, &wall.material),
        }
    }

    /// The contact coefficients of a sphere against this wall.
    pub fn coeffs(&self) -> &GranularCoeffs {
        &self.coeffs
    }

    /// The wall's plane after `elapsed` time.
    pub fn plane(&self, elapsed: f64) -> WallPlane {
        let w = &self.wall;
        WallPlane {
            axis: w.axis,
            sign: w.sign(),
            position: w.position_at(elapsed),
            velocity: w.velocity,
        }
    }

    /// Adds the wall's forces and torques on the spheres of `input`
    /// touching it to `f` and `torque`; `history` holds one contact per
    /// sphere and advances over the step `input.step_dt`, if this
    /// evaluation completes one, and `corrections` (if any) moves each
    /// sphere's surface at the wall (the multi-contact closure). Returns
    /// the normal force on the wall (positive when pushed) and the first
    /// sphere whose centre is on or behind the plane (which the engine
    /// reports as an error: the contact law has no meaning there).
    pub fn apply(
        &self,
        input: &ForceInput<'_>,
        f: &mut [[f64; 3]],
        mut torque: Option<&mut [[f64; 3]]>,
        history: &mut [ContactHistory],
        corrections: Option<&[f64]>,
    ) -> WallContact {
        let plane = self.plane(input.elapsed);
        let (step, update) = (input.step_dt.unwrap_or(0.0), input.step_dt.is_some());
        let mut contact = WallContact::default();
        let (x, radius) = (input.x, input.radius);
        for i in 0..x.len() {
            let distance = plane.distance(&x[i]);
            let correction = corrections.map_or(0.0, |c| c[i]);
            let surface = radius[i] + correction;
            // A surface moved past the centre is caught by the closure's
            // report; it is no contact here.
            if surface <= 0.0 || distance >= surface {
                history[i] = ContactHistory::default();
                continue;
            }
            if distance <= 0.0 {
                contact.through.get_or_insert(i);
                continue;
            }
            let sphere = Sphere {
                v: input.v[i],
                omega: input.omega.map_or([0.0; 3], |o| o[i]),
                radius: radius[i],
                mass: input.mass[i],
            };
            let touch = plane.touch(distance, correction);
            let out =
                granular_wall_contact(&self.coeffs, &touch, &sphere, &mut history[i], step, update);
            for (fd, force) in f[i].iter_mut().zip(out.force) {
                *fd += force;
            }
            if let Some(t) = torque.as_deref_mut() {
                for (td, moment) in t[i].iter_mut().zip(out.torque_i) {
                    *td += moment;
                }
            }
            contact.force += plane.load(&out.force);
        }
        contact
    }
}
