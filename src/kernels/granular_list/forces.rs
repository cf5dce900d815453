//! Pass 2: the contact forces of the listed pairs with both sides'
//! corrections, and the contact memory advanced.

use super::memory::Layout;
use super::{GranularList, ListAtoms, ListError};
use crate::kernels::granular::{corrected_granular_contact, ContactForce, ContactHistory};
use crate::kernels::{dot, sub, Ownership, Tally, NEIGHMASK};

impl GranularList {
    /// Pass 2: the contact forces of the listed pairs, with the
    /// corrections of pass 1 (`corrections` complete on ghosts too),
    /// added to `f` and `torque` of owned atoms (newton off); `history`
    /// advanced over `dt` when `update` (a step, not a set-up). With
    /// `renew` (the list was rebuilt) the memory keeps only the contacts
    /// of this list, as the native engine's store does at a rebuild: a
    /// partner deleted or moved away by hand leaves no stale spring.
    /// Returns the virial of the forces.
    #[allow(clippy::too_many_arguments)]
    pub fn forces<'n>(
        &mut self,
        atoms: &ListAtoms,
        rows: impl Iterator<Item = (usize, &'n [i32])>,
        corrections: &[f64],
        history: &mut [f64],
        f: &mut [[f64; 3]],
        torque: &mut [[f64; 3]],
        dt: f64,
        update: bool,
        renew: bool,
        step: i64,
    ) -> Result<Tally, ListError> {
        let hist = Layout::history(self.slots);
        // Read from the rows as they were, write into emptied ones.
        let mut previous = std::mem::take(&mut self.previous);
        previous.clear();
        if renew {
            previous.extend_from_slice(history);
            for a in 0..atoms.n_owned {
                history[a * hist.stride()] = 0.0;
            }
        }
        let mut wall_forces = std::mem::take(&mut self.wall_forces);
        wall_forces.clear();
        wall_forces.resize(self.walls.len(), 0.0);
        let result = self.forces_from(
            atoms,
            rows,
            corrections,
            if renew { &previous } else { &[] },
            history,
            (f, torque),
            &mut wall_forces,
            (dt, update),
            step,
        );
        self.previous = previous;
        self.wall_forces = wall_forces;
        result
    }

    /// [`Self::forces`] reading the memory from `previous` when it is not
    /// empty.
    #[allow(clippy::too_many_arguments)]
    fn forces_from<'n>(
        &self,
        atoms: &ListAtoms,
        rows: impl Iterator<Item = (usize, &'n [i32])>,
        corrections: &[f64],
        previous: &[f64],
        history: &mut [f64],
        (f, torque): (&mut [[f64; 3]], &mut [[f64; 3]]),
        wall_forces: &mut [f64],
        (dt, update): (f64, bool),
        step: i64,
    ) -> Result<Tally, ListError> {
        let (hist, corr) = (Layout::history(self.slots), Layout::corrections(self.slots));
        let (x, radius, tag) = (atoms.x, atoms.radius, atoms.tag);
        let own = Ownership {
            n_owned: atoms.n_owned,
            newton: false,
        };
        let mut tally = Tally::default();
        for (i, js) in rows {
            let si = atoms.sphere(i);
            for &jraw in js {
                let j = (jraw & NEIGHMASK) as usize;
                let (ti, tj) = (tag[i] as f64, tag[j] as f64);
                let del = sub(&x[i], &x[j]);
                let rsq = dot(&del, &del);
                let moved = match self.closure {
                    None => [0.0; 2],
                    Some(c) => {
                        let moved = [
                            corr.get(corrections, i, tj).map_or(0.0, |v| v[0]),
                            corr.get(corrections, j, ti).map_or(0.0, |v| v[0]),
                        ];
                        let ratio = (moved[0] + moved[1]) / (radius[i] + radius[j]);
                        if ratio > c.reach {
                            return Err(ListError::BeyondReach {
                                atom: tag[i],
                                partner: tag[j],
                                ratio,
                                reach: c.reach,
                                step,
                            });
                        }
                        moved
                    }
                };
                let radsum = (radius[i] + moved[0]) + (radius[j] + moved[1]);
                let (on_i, on_j, fraction) = own.split(i, j);
                if radsum <= 0.0 || rsq >= radsum * radsum {
                    hist.remove(history, i, tj);
                    if on_j {
                        hist.remove(history, j, ti);
                    }
                    continue;
                }
                let source = if previous.is_empty() {
                    &*history
                } else {
                    previous
                };
                let mut h = hist
                    .get(source, i, tj)
                    .map_or_else(ContactHistory::default, ContactHistory::from_values);
                let ContactForce {
                    force,
                    torque_i,
                    torque_j,
                } = corrected_granular_contact(
                    &self.coeffs,
                    &del,
                    &si,
                    &atoms.sphere(j),
                    moved,
                    &mut h,
                    dt,
                    update,
                );
                if !force.iter().all(|c| c.is_finite()) {
                    return Err(ListError::NonFinite {
                        atom: tag[i],
                        partner: tag[j],
                        overlap: radsum - rsq.sqrt(),
                        step,
                    });
                }
                let full = |atom: i64| ListError::RowFull {
                    atom,
                    slots: self.slots,
                };
                if !hist.put(history, i, tj, &h.to_values()) {
                    return Err(full(tag[i]));
                }
                if on_j && !hist.put(history, j, ti, &h.mirrored().to_values()) {
                    return Err(full(tag[j]));
                }
                for d in 0..3 {
                    if on_i {
                        f[i][d] += force[d];
                        torque[i][d] += torque_i[d];
                    }
                    if on_j {
                        f[j][d] -= force[d];
                        torque[j][d] += torque_j[d];
                    }
                }
                tally.add_vector(fraction, &del, &force);
            }
        }
        for (wall, load) in self.walls.iter().zip(wall_forces) {
            *load = self.wall_forces_on(
                atoms,
                wall,
                corrections,
                previous,
                history,
                (f, torque),
                (dt, update),
                step,
            )?;
        }
        Ok(tally)
    }
}
