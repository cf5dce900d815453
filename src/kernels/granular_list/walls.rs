//! Flat walls (`fix bpm/granular/wall`): contacts of their atoms, kept in
//! the same rows as the atoms' other contacts. Pass 1 takes a wall's
//! contact point with the atom's others; its force is formed here.

use super::memory::Layout;
use super::{GranularList, ListAtoms, ListError};
use crate::kernels::granular::{granular_wall_contact, ContactHistory, GranularCoeffs, WallPlane};

/// A flat wall as the passes see it: its plane now, and the contact
/// coefficients `coeffs` (its material mixed with the spheres'). Its
/// contacts are kept in the atoms' rows under the partner key `-number`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ListWall {
    /// The wall's number, >= 1.
    pub number: i64,
    /// The plane.
    pub plane: WallPlane,
    /// The sphere-wall contact coefficients.
    pub coeffs: GranularCoeffs,
    /// Whether, defined anew, it keeps its contacts' whole histories
    /// (friction springs too) from the wall it replaces.
    pub keep_history: bool,
}

impl ListWall {
    /// The partner key of the wall's contacts in the rows: negative, so
    /// it is no atom ID.
    pub(super) fn key(&self) -> f64 {
        -(self.number as f64)
    }
}

impl GranularList {
    /// Sets the walls of the coming passes. A wall marked `fresh` was
    /// (re)defined since the last evaluation, as a LAMMPS script defines
    /// its walls anew each stage: its friction springs restart unloaded,
    /// as the native engine's walls do at each stage. Only the normal
    /// force an owned atom's entry carried is kept, for the closure's
    /// first pass, when a wall of the same number, axis and side was set
    /// at the last evaluation (the native engine keeps a wall's load
    /// under the same condition); otherwise the entry is forgotten. A
    /// wall with `keep_history` keeps the whole entry, springs too, under
    /// that condition.
    pub fn set_walls(
        &mut self,
        walls: &[ListWall],
        fresh: &[bool],
        history: &mut [f64],
        n_owned: usize,
    ) -> Result<(), ListError> {
        for (k, w) in walls.iter().enumerate() {
            if w.number < 1 || w.plane.axis > 2 || w.plane.sign.abs() != 1.0 {
                return Err(ListError::BadWalls(
                    "a wall needs a number >= 1, an axis 0, 1 or 2 and a side +1 or -1",
                ));
            }
            if walls[..k].iter().any(|o| o.number == w.number) {
                return Err(ListError::BadWalls(
                    "two fix bpm/granular/wall share a number: each wall's contacts are kept under its own",
                ));
            }
        }
        let hist = Layout::history(self.slots);
        for (w, _) in walls.iter().zip(fresh).filter(|(_, &f)| f) {
            let kept = self.walls.iter().any(|o| {
                o.number == w.number && o.plane.axis == w.plane.axis && o.plane.sign == w.plane.sign
            });
            if kept && w.keep_history {
                continue;
            }
            for a in 0..n_owned {
                let Some(values) = hist.get(history, a, w.key()) else {
                    continue;
                };
                if kept {
                    let load = ContactHistory {
                        normal_force: ContactHistory::from_values(values).normal_force,
                        ..ContactHistory::default()
                    };
                    hist.put(history, a, w.key(), &load.to_values());
                } else {
                    hist.remove(history, a, w.key());
                }
            }
        }
        self.walls.clear();
        self.walls.extend_from_slice(walls);
        self.wall_forces.clear();
        self.wall_forces.resize(walls.len(), 0.0);
        Ok(())
    }

    /// Takes over the walls `other` set last, as if they had been set on
    /// this one: a style made anew (LAMMPS's `pair_coeff` of a later
    /// stage) then keeps the loads of walls defined anew, as the native
    /// engine does across a change of force field.
    pub fn inherit_walls(&mut self, other: &GranularList) {
        self.walls.clone_from(&other.walls);
        self.wall_forces.clone_from(&other.wall_forces);
    }

    /// Per wall of [`Self::set_walls`], the normal force on it from this
    /// rank's atoms in the last forces pass (positive when pushed).
    pub fn wall_forces(&self) -> &[f64] {
        &self.wall_forces
    }

    /// The contacts of `wall` with the owned atoms (the native engine's
    /// `ActiveGranularWall::apply`): forces and torques added to `f` and
    /// `torque`, the memory advanced as in [`Self::forces_from`]. Returns
    /// the normal force on the wall (positive when pushed).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn wall_forces_on(
        &self,
        atoms: &ListAtoms,
        wall: &ListWall,
        corrections: &[f64],
        previous: &[f64],
        history: &mut [f64],
        (f, torque): (&mut [[f64; 3]], &mut [[f64; 3]]),
        (dt, update): (f64, bool),
        step: i64,
    ) -> Result<f64, ListError> {
        let (hist, corr) = (Layout::history(self.slots), Layout::corrections(self.slots));
        let (key, plane) = (wall.key(), wall.plane);
        let mut load = 0.0;
        for a in 0..atoms.n_owned {
            let radius = atoms.radius[a];
            let distance = plane.distance(&atoms.x[a]);
            let correction = match self.closure {
                None => 0.0,
                Some(c) => {
                    let moved = corr.get(corrections, a, key).map_or(0.0, |v| v[0]);
                    if moved > c.reach * radius {
                        return Err(ListError::WallBeyondReach {
                            atom: atoms.tag[a],
                            wall: wall.number,
                            ratio: moved / radius,
                            reach: c.reach,
                            step,
                        });
                    }
                    moved
                }
            };
            let surface = radius + correction;
            // A surface moved past the centre is pass 1's error; it is no
            // contact here.
            if surface <= 0.0 || distance >= surface {
                hist.remove(history, a, key);
                continue;
            }
            if distance <= 0.0 {
                return Err(ListError::ThroughWall {
                    atom: atoms.tag[a],
                    wall: wall.number,
                    step,
                });
            }
            let source = if previous.is_empty() {
                &*history
            } else {
                previous
            };
            let mut h = hist
                .get(source, a, key)
                .map_or_else(ContactHistory::default, ContactHistory::from_values);
            let touch = plane.touch(distance, correction);
            let out =
                granular_wall_contact(&wall.coeffs, &touch, &atoms.sphere(a), &mut h, dt, update);
            if !out.force.iter().all(|c| c.is_finite()) {
                return Err(ListError::NonFiniteWall {
                    atom: atoms.tag[a],
                    wall: wall.number,
                    overlap: surface - distance,
                    step,
                });
            }
            if !hist.put(history, a, key, &h.to_values()) {
                return Err(ListError::RowFull {
                    atom: atoms.tag[a],
                    slots: self.slots,
                });
            }
            for d in 0..3 {
                f[a][d] += out.force[d];
                torque[a][d] += out.torque_i[d];
            }
            load += plane.load(&out.force);
        }
        Ok(load)
    }
}
