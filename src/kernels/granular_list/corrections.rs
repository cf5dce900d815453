//! Pass 1: the closure's corrections of every owned atom's contacts,
//! walls included, from the normal forces of the last step.

use super::memory::Layout;
use super::{Entry, GranularList, ListAtoms, ListError};
use crate::kernels::multicontact::{group_by_sphere, pair_contact_points, ContactPoint};
use crate::kernels::{dot, sub, NEIGHMASK};

/// What pass 1 found over this rank's atoms.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CorrectionSummary {
    /// Largest correction over its atom's radius (0 if none is positive).
    pub largest: f64,
    /// Contacts (whole-contact switch) or terms (per-term switch) the
    /// advanced closure switched off.
    pub switched_off: usize,
}

impl GranularList {
    /// Pass 1: the corrections of every owned atom's contacts into
    /// `corrections` (rows of [`Layout::corrections`], owned atoms only),
    /// from the normal forces in `history` (rows of [`Layout::history`]).
    /// `rows` yields each listed atom and its LAMMPS neighbour indices.
    /// Without a closure every row is emptied.
    pub fn corrections<'n>(
        &mut self,
        atoms: &ListAtoms,
        rows: impl Iterator<Item = (usize, &'n [i32])>,
        history: &[f64],
        corrections: &mut [f64],
        step: i64,
    ) -> Result<CorrectionSummary, ListError> {
        let (hist, corr) = (Layout::history(self.slots), Layout::corrections(self.slots));
        let n = atoms.n_owned;
        for a in 0..n {
            corrections[a * corr.stride()] = 0.0;
        }
        let Some(closure) = self.closure else {
            return Ok(CorrectionSummary::default());
        };
        let reach_factor = 1.0 + closure.reach;
        let (x, radius, tag) = (atoms.x, atoms.radius, atoms.tag);
        self.entries.clear();
        for (i, js) in rows {
            for &jraw in js {
                let j = (jraw & NEIGHMASK) as usize;
                let del = sub(&x[i], &x[j]);
                let r = dot(&del, &del).sqrt();
                if r >= reach_factor * (radius[i] + radius[j]) {
                    continue;
                }
                let force = hist.load(history, i, tag[j] as f64);
                let [pi, pj] = pair_contact_points(&del, r, radius[i], radius[j], force);
                self.entries.push(Entry {
                    atom: i as u32,
                    partner: tag[j] as f64,
                    point: pi,
                });
                if j < n {
                    self.entries.push(Entry {
                        atom: j as u32,
                        partner: tag[i] as f64,
                        point: pj,
                    });
                }
            }
        }
        for wall in &self.walls {
            for a in 0..n {
                let distance = wall.plane.distance(&x[a]);
                if distance <= 0.0 || distance >= reach_factor * radius[a] {
                    continue;
                }
                // On the wall's plane: a rigid wall does not give way.
                let point = wall.plane.contact_point(distance);
                self.entries.push(Entry {
                    atom: a as u32,
                    partner: wall.key(),
                    point: ContactPoint::new(point, hist.load(history, a, wall.key()), radius[a]),
                });
            }
        }
        self.group(n);
        let mut summary = CorrectionSummary::default();
        for a in 0..n {
            let range = self.offsets[a]..self.offsets[a + 1];
            // One contact, or none that pressed: nothing to correct.
            if range.len() < 2 || self.points[range.clone()].iter().all(|p| p.force == 0.0) {
                continue;
            }
            summary.switched_off += self.lanes.compute(
                &closure.half_space,
                &closure.closure,
                radius[a],
                &self.points[range.clone()],
                &mut self.deltas[range.clone()],
            );
            for (e, &delta) in self.grouped[range.clone()].iter().zip(&self.deltas[range]) {
                let ratio = delta / radius[a];
                if ratio <= -1.0 {
                    return Err(ListError::Collapsed {
                        atom: tag[a],
                        ratio,
                        step,
                    });
                }
                summary.largest = summary.largest.max(ratio);
                if !corr.put(corrections, a, e.partner, &[delta]) {
                    return Err(ListError::RowFull {
                        atom: tag[a],
                        slots: self.slots,
                    });
                }
            }
        }
        Ok(summary)
    }

    /// Groups the entries by atom.
    fn group(&mut self, n: usize) {
        group_by_sphere(
            &self.entries,
            n,
            |e| e.atom as usize,
            |e| e.point,
            &mut self.offsets,
            &mut self.grouped,
            &mut self.points,
        );
        self.deltas.clear();
        self.deltas.resize(self.entries.len(), 0.0);
    }
}
