//! Flat frictional walls for DEM spheres: a plane normal to one axis,
//! moving along it at constant speed, touching spheres with the same
//! contact law as sphere pairs (`kernels::granular_wall_contact`), with
//! one contact history per sphere.

use super::super::external::{GranularWall, WallContact};
use super::super::model::ForceInput;
use crate::kernels::{
    granular_wall_contact, hertz_mindlin_wall_block, ContactHistory, GranularCoeffs,
    GranularMaterial, Isa, Sphere, WallBlock, WallPlane, CONTACT_LANES,
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
    /// `blocks` forms Hertz-Mindlin contacts four at a time on that
    /// instruction set (`None`: one at a time; the same bits).
    pub fn apply(
        &self,
        input: &ForceInput<'_>,
        f: &mut [[f64; 3]],
        torque: Option<&mut [[f64; 3]]>,
        history: &mut [ContactHistory],
        corrections: Option<&[f64]>,
        blocks: Option<Isa>,
    ) -> WallContact {
        match blocks {
            Some(isa) if self.coeffs.lanes_cover() => {
                self.apply_in_blocks(isa, input, f, torque, history, corrections)
            }
            _ => self.apply_one_by_one(input, f, torque, history, corrections),
        }
    }

    /// [`Self::apply`] with the touching spheres gathered four at a time
    /// into [`hertz_mindlin_wall_block`]: the same bits, added in sphere
    /// order.
    fn apply_in_blocks(
        &self,
        isa: Isa,
        input: &ForceInput<'_>,
        f: &mut [[f64; 3]],
        mut torque: Option<&mut [[f64; 3]]>,
        history: &mut [ContactHistory],
        corrections: Option<&[f64]>,
    ) -> WallContact {
        let plane = self.plane(input.elapsed);
        let (step, update) = input.history_step();
        let touch = plane.touch(1.0, 0.0);
        let mut contact = WallContact::default();
        let (x, radius) = (input.x, input.radius);
        let mut block = WallBlock::default();
        let mut spheres = [0usize; CONTACT_LANES];
        let mut filled = 0;
        let mut flush = |block: &mut WallBlock,
                         spheres: &[usize],
                         history: &mut [ContactHistory],
                         load: &mut f64| {
            let out = hertz_mindlin_wall_block(
                isa,
                &self.coeffs,
                &touch.normal,
                &touch.velocity,
                block,
                step,
                update,
            );
            for (l, &i) in spheres.iter().enumerate() {
                let force: [f64; 3] = std::array::from_fn(|d| out.force[d][l]);
                history[i].tangential = std::array::from_fn(|d| block.tangential[d][l]);
                history[i].normal_force = out.normal_force[l];
                for (fd, force) in f[i].iter_mut().zip(force) {
                    *fd += force;
                }
                if let Some(t) = torque.as_deref_mut() {
                    for (d, td) in t[i].iter_mut().enumerate() {
                        *td += out.torque[d][l];
                    }
                }
                *load += plane.load(&force);
            }
        };
        for i in 0..x.len() {
            let Some((distance, correction)) =
                touching(&plane, input, corrections, i, &mut history[i], &mut contact)
            else {
                continue;
            };
            let l = filled;
            let omega = input.omega.map_or([0.0; 3], |o| o[i]);
            block.distance[l] = distance;
            block.correction[l] = correction;
            block.radius[l] = radius[i];
            block.mass[l] = input.mass[i];
            let state = [input.v[i], omega, history[i].tangential];
            let lanes = [&mut block.v, &mut block.omega, &mut block.tangential];
            for (lanes, value) in lanes.into_iter().zip(state) {
                for (lane, component) in lanes.iter_mut().zip(value) {
                    lane[l] = component;
                }
            }
            spheres[l] = i;
            filled += 1;
            if filled == CONTACT_LANES {
                flush(&mut block, &spheres, history, &mut contact.force);
                filled = 0;
            }
        }
        if filled > 0 {
            // The spare lanes repeat the first sphere and are not read.
            block.fill_from_first(filled);
            flush(&mut block, &spheres[..filled], history, &mut contact.force);
        }
        contact
    }

    /// [`Self::apply`] one sphere at a time (rolling or twisting
    /// resistance, or blocks off).
    fn apply_one_by_one(
        &self,
        input: &ForceInput<'_>,
        f: &mut [[f64; 3]],
        mut torque: Option<&mut [[f64; 3]]>,
        history: &mut [ContactHistory],
        corrections: Option<&[f64]>,
    ) -> WallContact {
        let plane = self.plane(input.elapsed);
        let (step, update) = input.history_step();
        let mut contact = WallContact::default();
        let (x, radius) = (input.x, input.radius);
        for i in 0..x.len() {
            let Some((distance, correction)) =
                touching(&plane, input, corrections, i, &mut history[i], &mut contact)
            else {
                continue;
            };
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

/// Sphere `i`'s distance from `plane` and its surface's correction there,
/// when it touches the wall. Otherwise a sphere apart has its `history`
/// cleared, and one whose centre is on or behind the plane is recorded in
/// `contact`.
#[inline(always)]
fn touching(
    plane: &WallPlane,
    input: &ForceInput<'_>,
    corrections: Option<&[f64]>,
    i: usize,
    history: &mut ContactHistory,
    contact: &mut WallContact,
) -> Option<(f64, f64)> {
    let distance = plane.distance(&input.x[i]);
    let correction = corrections.map_or(0.0, |c| c[i]);
    let surface = input.radius[i] + correction;
    // A surface moved past the centre is caught by the closure's report;
    // it is no contact here.
    if surface <= 0.0 || distance >= surface {
        *history = ContactHistory::default();
        return None;
    }
    if distance <= 0.0 {
        contact.through.get_or_insert(i);
        return None;
    }
    Some((distance, correction))
}
