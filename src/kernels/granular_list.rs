//! DEM contacts and the multi-contact closure over a LAMMPS half
//! neighbour list, for the plugin's `pair_style bpm/granular`: the native
//! engine's contact law ([`corrected_granular_contact`]) and closure
//! ([`surface_corrections`], [`pair_contact_points`]), with the contact
//! memory a LAMMPS run needs.
//!
//! **Contact memory moves with the atoms.** Each owned atom carries one
//! row of doubles, `[count, (partner tag, history) x slots]`, which the
//! plugin's fix copies when the atom changes rank and writes to restart
//! files ([`Layout::history`]). A contact is stored with both of its
//! owned atoms, each from its own side ([`ContactHistory::mirrored`]), so
//! whichever atom a later list puts first finds it, and ranks sharing a
//! pair (newton off computes it on both) each keep their own copy.
//!
//! **Two passes per force evaluation** (the closure's only):
//! 1. [`GranularList::corrections`]: every owned atom's contacts within
//!    reach, from its list rows (with newton off a rank lists every pair
//!    that has one of its atoms), their last normal forces from the
//!    memory, and the correction of each into the atom's correction row
//!    `[count, (partner tag, Delta) x slots]` ([`Layout::corrections`]).
//!    The plugin then copies the rows of owned atoms to their ghosts.
//! 2. [`GranularList::forces`]: each listed pair with both sides'
//!    corrections (a ghost's from its copied row), its force and torques
//!    on owned atoms, the memory updated.
//!
//! **Flat walls** (`fix bpm/granular/wall`, [`GranularList::set_walls`])
//! are contacts of their atoms in both passes, as in the native engine:
//! each is kept in the same rows under the partner key `-number`, its
//! correction comes from pass 1 with the atom's other contacts, and its
//! force from [`granular_wall_contact`] in pass 2.

// Atom indices address several per-atom arrays at once.
#![allow(clippy::needless_range_loop)]

use super::granular::{
    corrected_granular_contact, granular_wall_contact, ContactForce, ContactHistory,
    GranularCoeffs, WallPlane,
};
use super::multicontact::{group_by_sphere, pair_contact_points, Closure, ContactPoint};
use super::{HalfSpace, Ownership, Sphere, SurfaceCorrections, Tally, NEIGHMASK};

/// Values per contact in the memory: `xi` (3), rolling (3), twist and the
/// normal force.
pub const HISTORY_VALUES: usize = 8;

/// The layout of a per-atom table: rows of `1 + slots * width` doubles,
/// a count then `count` entries of a partner tag (exact as a double up to
/// 2^53) and `width - 1` values.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layout {
    /// Entries a row holds.
    pub slots: usize,
    /// Doubles per entry, the tag included.
    pub width: usize,
}

impl Layout {
    /// The contact memory: tag and [`HISTORY_VALUES`] per contact.
    pub const fn history(slots: usize) -> Self {
        Self {
            slots,
            width: 1 + HISTORY_VALUES,
        }
    }

    /// The corrections: tag and `Delta` per contact.
    pub const fn corrections(slots: usize) -> Self {
        Self { slots, width: 2 }
    }

    /// Doubles per atom.
    pub const fn stride(&self) -> usize {
        1 + self.slots * self.width
    }

    /// The offset of the entry of `atom` for partner `tag`.
    #[inline]
    fn find(&self, data: &[f64], atom: usize, tag: f64) -> Option<usize> {
        let row = atom * self.stride();
        let count = data[row] as usize;
        (0..count.min(self.slots))
            .map(|s| row + 1 + s * self.width)
            .find(|&o| data[o] == tag)
    }

    /// The values stored for `atom`'s partner `tag`.
    #[inline]
    fn get<'d>(&self, data: &'d [f64], atom: usize, tag: f64) -> Option<&'d [f64]> {
        self.find(data, atom, tag)
            .map(|o| &data[o + 1..o + self.width])
    }

    /// The normal force the contact memory (rows of [`Layout::history`])
    /// holds for `atom`'s partner `tag`, 0 if none.
    #[inline]
    fn load(&self, data: &[f64], atom: usize, tag: f64) -> f64 {
        self.get(data, atom, tag)
            .map_or(0.0, |v| v[HISTORY_VALUES - 1])
    }

    /// Stores `values` for `atom`'s partner `tag`; false if the row is full.
    #[inline]
    fn put(&self, data: &mut [f64], atom: usize, tag: f64, values: &[f64]) -> bool {
        let o = match self.find(data, atom, tag) {
            Some(o) => o,
            None => {
                let row = atom * self.stride();
                let count = data[row] as usize;
                if count >= self.slots {
                    return false;
                }
                data[row] = (count + 1) as f64;
                let o = row + 1 + count * self.width;
                data[o] = tag;
                o
            }
        };
        data[o + 1..o + self.width].copy_from_slice(values);
        true
    }

    /// Forgets `atom`'s partner `tag` (the last entry takes its place).
    #[inline]
    fn remove(&self, data: &mut [f64], atom: usize, tag: f64) {
        if let Some(o) = self.find(data, atom, tag) {
            let row = atom * self.stride();
            let last = data[row] as usize - 1;
            let from = row + 1 + last * self.width;
            data.copy_within(from..from + self.width, o);
            data[row] = last as f64;
        }
    }
}

impl ContactHistory {
    /// The same contact seen from the other sphere: the tangential
    /// displacement of one surface against the other changes sign; the
    /// rolling displacement `R_eff (omega_i - omega_j) x n` and the twist
    /// about `n` do not (both factors change sign), nor does the load.
    pub fn mirrored(&self) -> Self {
        Self {
            tangential: self.tangential.map(|c| -c),
            ..*self
        }
    }

    fn to_values(self) -> [f64; HISTORY_VALUES] {
        let (t, r) = (self.tangential, self.rolling);
        [
            t[0],
            t[1],
            t[2],
            r[0],
            r[1],
            r[2],
            self.twist,
            self.normal_force,
        ]
    }

    fn from_values(v: &[f64]) -> Self {
        Self {
            tangential: [v[0], v[1], v[2]],
            rolling: [v[3], v[4], v[5]],
            twist: v[6],
            normal_force: v[7],
        }
    }
}

/// Why a pass stopped: each names atoms by their LAMMPS IDs.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum ListError {
    /// An atom has more contacts than its memory row holds.
    #[error("atom {atom} has more than {slots} contacts (or pairs within the closure's reach): raise `slots` of pair_style bpm/granular")]
    RowFull {
        /// The atom's ID.
        atom: i64,
        /// The row's capacity.
        slots: usize,
    },
    /// A correction moved a surface onto or past its centre.
    #[error("the multi-contact correction of atom {atom} is {ratio:.3} of its radius at step {step}: its surface moved onto or past its centre (the standard closure's feedback runs away at large overlaps: use the advanced closure, a smaller prefactor or less compression)")]
    Collapsed {
        /// The atom's ID.
        atom: i64,
        /// Correction over radius.
        ratio: f64,
        /// The time step.
        step: i64,
    },
    /// Two corrections of a pair add up beyond the closure's reach.
    #[error("the multi-contact corrections of atoms {atom} and {partner} add up to {ratio:.3} of their radii at step {step}, beyond the closure's reach {reach}: raise `reach` (or lower the prefactor, or use the advanced closure, whose ratio bounds each term)")]
    BeyondReach {
        /// The atoms' IDs.
        atom: i64,
        /// The partner's ID.
        partner: i64,
        /// Corrections over the radii.
        ratio: f64,
        /// The closure's reach.
        reach: f64,
        /// The time step.
        step: i64,
    },
    /// An atom's centre reached a wall's plane.
    #[error("atom {atom} reached the plane of fix bpm/granular/wall number {wall} at step {step}: it overlapped the wall by its whole radius (the wall moved too fast, pressed too hard for its stiffness, or the time step is too long; or the atom started on the wrong side: check the wall's position and side)")]
    ThroughWall {
        /// The atom's ID.
        atom: i64,
        /// The wall's number.
        wall: i64,
        /// The time step.
        step: i64,
    },
    /// An atom's correction at a wall exceeds the closure's reach.
    #[error("the multi-contact correction of atom {atom} at fix bpm/granular/wall number {wall} is {ratio:.3} of its radius at step {step}, beyond the closure's reach {reach}: raise `reach` (or lower the prefactor, or use the advanced closure, whose ratio bounds each term)")]
    WallBeyondReach {
        /// The atom's ID.
        atom: i64,
        /// The wall's number.
        wall: i64,
        /// Correction over radius.
        ratio: f64,
        /// The closure's reach.
        reach: f64,
        /// The time step.
        step: i64,
    },
    /// A wall's force came out NaN or infinite.
    #[error("the contact force between atom {atom} and fix bpm/granular/wall number {wall} is not finite at step {step} (overlap {overlap:.4}): the run has blown up; reduce the timestep")]
    NonFiniteWall {
        /// The atom's ID.
        atom: i64,
        /// The wall's number.
        wall: i64,
        /// The overlap.
        overlap: f64,
        /// The time step.
        step: i64,
    },
    /// Two walls share a number, or a wall's axis is not 0, 1 or 2.
    #[error("{0}")]
    BadWalls(&'static str),
    /// A force came out NaN or infinite.
    #[error("the contact force between atoms {atom} and {partner} is not finite at step {step} (overlap {overlap:.4}): the run has blown up; reduce the timestep")]
    NonFinite {
        /// The atoms' IDs.
        atom: i64,
        /// The partner's ID.
        partner: i64,
        /// The overlap.
        overlap: f64,
        /// The time step.
        step: i64,
    },
}

/// The closure of the style: how terms combine, the half-space response
/// of the spheres' material, and how far beyond touching pairs receive
/// corrections.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ListClosure {
    /// Standard or advanced.
    pub closure: Closure,
    /// The spheres' half-space response.
    pub half_space: HalfSpace,
    /// Fraction of the radii beyond touching within which pairs receive
    /// corrections.
    pub reach: f64,
}

/// The per-atom state a pass reads: owned atoms first, then ghosts.
#[derive(Clone, Copy, Debug)]
pub struct ListAtoms<'a> {
    /// Positions (ghosts as images).
    pub x: &'a [[f64; 3]],
    /// Velocities (ghosts' included: `comm_modify vel yes`).
    pub v: &'a [[f64; 3]],
    /// Angular velocities.
    pub omega: &'a [[f64; 3]],
    /// Radii.
    pub radius: &'a [f64],
    /// Masses.
    pub mass: &'a [f64],
    /// Atom IDs.
    pub tag: &'a [i64],
    /// Atoms `0..n_owned` are owned.
    pub n_owned: usize,
}

impl ListAtoms<'_> {
    fn sphere(&self, i: usize) -> Sphere {
        Sphere {
            v: self.v[i],
            omega: self.omega[i],
            radius: self.radius[i],
            mass: self.mass[i],
        }
    }
}

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
}

impl ListWall {
    /// The partner key of the wall's contacts in the rows: negative, so
    /// it is no atom ID.
    fn key(&self) -> f64 {
        -(self.number as f64)
    }
}

/// What pass 1 found over this rank's atoms.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CorrectionSummary {
    /// Largest correction over its atom's radius (0 if none is positive).
    pub largest: f64,
    /// Contacts (whole-contact switch) or terms (per-term switch) the
    /// advanced closure switched off.
    pub switched_off: usize,
}

/// One owned atom's contact within reach, before grouping by atom.
#[derive(Clone, Copy, Debug)]
struct Entry {
    atom: u32,
    partner: f64,
    point: ContactPoint,
}

/// The contact law and closure of `pair_style bpm/granular` and their
/// reusable buffers (so passes allocate only while lists grow).
#[derive(Clone, Debug)]
pub struct GranularList {
    /// The contact coefficients.
    pub coeffs: GranularCoeffs,
    /// The closure, if on.
    pub closure: Option<ListClosure>,
    /// Capacity of the memory and correction rows.
    pub slots: usize,
    entries: Vec<Entry>,
    offsets: Vec<usize>,
    grouped: Vec<Entry>,
    points: Vec<ContactPoint>,
    deltas: Vec<f64>,
    lanes: SurfaceCorrections,
    /// The memory rows before a pass that renews them.
    previous: Vec<f64>,
    /// The walls of the coming passes.
    walls: Vec<ListWall>,
    /// Per wall, the normal force on it from this rank's atoms in the
    /// last forces pass (positive when pushed).
    wall_forces: Vec<f64>,
}

impl GranularList {
    /// Contacts with `coeffs`, corrected by `closure`, with rows of
    /// `slots` entries.
    pub fn new(coeffs: GranularCoeffs, closure: Option<ListClosure>, slots: usize) -> Self {
        Self {
            coeffs,
            closure,
            slots,
            entries: Vec::new(),
            offsets: Vec::new(),
            grouped: Vec::new(),
            points: Vec::new(),
            deltas: Vec::new(),
            lanes: SurfaceCorrections::default(),
            previous: Vec::new(),
            walls: Vec::new(),
            wall_forces: Vec::new(),
        }
    }

    /// Sets the walls of the coming passes. A wall marked `fresh` was
    /// (re)defined since the last evaluation, as a LAMMPS script defines
    /// its walls anew each stage: its friction springs restart unloaded,
    /// as the native engine's walls do at each stage. Only the normal
    /// force an owned atom's entry carried is kept, for the closure's
    /// first pass, when a wall of the same number, axis and side was set
    /// at the last evaluation (the native engine keeps a wall's load
    /// under the same condition); otherwise the entry is forgotten.
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
                let del = super::sub(&x[i], &x[j]);
                let r = super::dot(&del, &del).sqrt();
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
                let del = super::sub(&x[i], &x[j]);
                let rsq = super::dot(&del, &del);
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

    /// The contacts of `wall` with the owned atoms (the native engine's
    /// `ActiveGranularWall::apply`): forces and torques added to `f` and
    /// `torque`, the memory advanced as in [`Self::forces_from`]. Returns
    /// the normal force on the wall (positive when pushed).
    #[allow(clippy::too_many_arguments)]
    fn wall_forces_on(
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernels::{granular_contact, GranularMaterial, NormalDamping, SpringDashpotSlider};
    use crate::kernels::{surface_corrections, ContactPoint, WallTouch};
    use crate::kernels::{MprSwitch, MprTest, Twisting};

    fn material() -> GranularMaterial {
        GranularMaterial {
            youngs_modulus: 1e3,
            poisson_ratio: 0.3,
            restitution: 0.5,
            damping: NormalDamping::Tsuji,
            tangential_damping: 1.0,
            sliding_friction: 0.5,
            rolling: Some(SpringDashpotSlider {
                stiffness: 300.0,
                damping: 5.0,
                friction: 0.2,
            }),
            twisting: Twisting::Marshall,
        }
    }

    fn sphere(v: [f64; 3], omega: [f64; 3], radius: f64) -> Sphere {
        Sphere {
            v,
            omega,
            radius,
            mass: radius.powi(3),
        }
    }

    /// The mirrored memory is the same contact: seen from `j`, a step
    /// gives the opposite force, the torques swapped, and a memory that is
    /// the mirror of the one seen from `i`, for sticking and sliding
    /// springs alike (rolling and twisting included).
    #[test]
    fn a_contact_seen_from_either_sphere_is_one_contact() {
        let c = GranularCoeffs::of(&material());
        let del = [0.83, -0.21, 0.34];
        let si = sphere([0.3, -0.1, 0.2], [0.7, 0.4, -1.1], 0.5);
        let sj = sphere([-0.2, 0.25, 0.05], [-0.3, 0.9, 0.6], 0.45);
        for scale in [1e-4, 1.0] {
            let mut hi = ContactHistory {
                tangential: [1e-3 * scale, 2e-3 * scale, -1e-3 * scale],
                rolling: [-4e-3 * scale, 1e-3 * scale, 2e-3 * scale],
                twist: 3e-2 * scale,
                normal_force: 0.0,
            };
            let mut hj = hi.mirrored();
            let mut tally = 0.0;
            for _ in 0..3 {
                let a = granular_contact(&c, &del, &si, &sj, &mut hi, 1e-3, true);
                let b = granular_contact(&c, &del.map(|v| -v), &sj, &si, &mut hj, 1e-3, true);
                for d in 0..3 {
                    let tol = 1e-13 * (1.0 + a.force[d].abs());
                    assert!((a.force[d] + b.force[d]).abs() <= tol, "{a:?} {b:?}");
                    assert!(
                        (a.torque_i[d] - b.torque_j[d]).abs() <= 1e-13,
                        "{a:?} {b:?}"
                    );
                    assert!(
                        (a.torque_j[d] - b.torque_i[d]).abs() <= 1e-13,
                        "{a:?} {b:?}"
                    );
                }
                let m = hi.mirrored();
                for (x, y) in m.to_values().iter().zip(hj.to_values()) {
                    assert!((x - y).abs() <= 1e-13 * (1.0 + x.abs()), "{m:?} {hj:?}");
                }
                tally += a.force[0].abs();
            }
            assert!(tally > 0.0);
        }
    }

    /// A wall below atom 10 (x lo wall at z = 0), atom 20 pressing it
    /// down: pass 1 gives atom 10 corrections from both of its contacts,
    /// the wall's among them, as `surface_corrections` does; pass 2 gives
    /// it the wall's force of `granular_wall_contact` with its correction
    /// there, and reports the load on the wall.
    #[test]
    fn a_wall_is_a_contact_of_the_closure_in_both_passes() {
        let m = material();
        let coeffs = GranularCoeffs::of(&m);
        let closure = ListClosure {
            closure: Closure::Standard,
            half_space: HalfSpace::new(0.82, m.youngs_modulus, m.poisson_ratio),
            reach: 0.25,
        };
        let wall_material = GranularMaterial {
            youngs_modulus: 1e4,
            ..m
        };
        let wall = ListWall {
            number: 1,
            plane: WallPlane {
                axis: 2,
                sign: 1.0,
                position: 0.0,
                velocity: -0.01,
            },
            coeffs: GranularCoeffs::between(&m, &wall_material),
        };
        let x = [[0.0, 0.0, 0.46], [0.02, 0.01, 1.41]];
        let v = [[0.01, 0.0, -0.02], [0.0, 0.01, -0.03]];
        let omega = [[0.1, -0.2, 0.05], [0.0; 3]];
        let (radius, mass, tag) = ([0.5; 2], [1.0; 2], [10, 20]);
        let atoms = ListAtoms {
            x: &x,
            v: &v,
            omega: &omega,
            radius: &radius,
            mass: &mass,
            tag: &tag,
            n_owned: 2,
        };
        let slots = 4;
        let (hist, corr) = (Layout::history(slots), Layout::corrections(slots));
        let mut list = GranularList::new(coeffs, Some(closure), slots);
        let mut history = vec![0.0; 2 * hist.stride()];
        let mut corrections = vec![0.0; 2 * corr.stride()];
        let rows = || [(1usize, &[0i32][..])].into_iter();
        list.set_walls(&[wall], &[true], &mut history, 2).unwrap();
        let step = |list: &mut GranularList, history: &mut Vec<f64>, corrections: &mut Vec<f64>| {
            list.corrections(&atoms, rows(), history, corrections, 0)
                .unwrap();
            let (mut f, mut t) = (vec![[0.0; 3]; 2], vec![[0.0; 3]; 2]);
            list.forces(
                &atoms,
                rows(),
                corrections,
                history,
                &mut f,
                &mut t,
                1e-3,
                true,
                false,
                0,
            )
            .unwrap();
            (f, t)
        };
        // No loads remembered: no corrections; the wall's contact is the
        // plain one.
        let before = hist.get(&history, 0, -1.0).is_none();
        let (f, t) = step(&mut list, &mut history, &mut corrections);
        assert!(before && corrections[0] == 0.0);
        let sphere0 = Sphere {
            v: v[0],
            omega: omega[0],
            radius: 0.5,
            mass: 1.0,
        };
        let touch = |correction| WallTouch {
            distance: 0.46,
            normal: [0.0, 0.0, 1.0],
            velocity: [0.0, 0.0, -0.01],
            correction,
        };
        let mut h = ContactHistory::default();
        let plain = granular_wall_contact(&wall.coeffs, &touch(0.0), &sphere0, &mut h, 1e-3, true);
        assert!(plain.force[2] > 0.0);
        assert_eq!(list.wall_forces(), &[plain.force[2]]);
        assert_eq!(hist.get(&history, 0, -1.0), Some(&h.to_values()[..]));
        assert!(t[0] != [0.0; 3] && f[1][2] > 0.0);
        // Second evaluation: atom 10's two loads correct each other.
        let wall_load = h.normal_force;
        let pair_load = hist.get(&history, 0, 20.0).unwrap()[7];
        let del = super::super::sub(&x[1], &x[0]);
        let r = super::super::dot(&del, &del).sqrt();
        let [_, from_pair] = pair_contact_points(&del, r, 0.5, 0.5, pair_load);
        let from_wall = ContactPoint::new([0.0, 0.0, -0.46], wall_load, 0.5);
        let mut expect = [0.0; 2];
        surface_corrections(
            &closure.half_space,
            &closure.closure,
            0.5,
            &[from_pair, from_wall],
            &mut expect,
        );
        assert!(expect.iter().all(|&d| d > 0.0), "{expect:?}");
        let (f2, _) = step(&mut list, &mut history, &mut corrections);
        assert_eq!(corr.get(&corrections, 0, 20.0).unwrap()[0], expect[0]);
        assert_eq!(corr.get(&corrections, 0, -1.0).unwrap()[0], expect[1]);
        let corrected = granular_wall_contact(
            &wall.coeffs,
            &touch(expect[1]),
            &sphere0,
            &mut h,
            1e-3,
            true,
        );
        assert_eq!(list.wall_forces(), &[corrected.force[2]]);
        assert!(corrected.force[2] > plain.force[2] && f2[0][2] > f[0][2]);
        // A pass after a rebuild keeps the wall's contact (a set-up pass:
        // nothing advances).
        let mut renewed = history.clone();
        let (mut f, mut t) = (vec![[0.0; 3]; 2], vec![[0.0; 3]; 2]);
        list.forces(
            &atoms,
            rows(),
            &corrections,
            &mut renewed,
            &mut f,
            &mut t,
            0.0,
            false,
            true,
            3,
        )
        .unwrap();
        assert_eq!(
            hist.get(&renewed, 0, -1.0),
            hist.get(&history, 0, -1.0),
            "{renewed:?}"
        );
        // A correction at the wall beyond the reach stops the pass.
        let mut far = corrections.clone();
        assert!(corr.put(&mut far, 0, -1.0, &[0.2]));
        let err = list
            .forces(
                &atoms,
                rows(),
                &far,
                &mut renewed,
                &mut f,
                &mut t,
                0.0,
                false,
                false,
                5,
            )
            .unwrap_err();
        assert_eq!(
            err,
            ListError::WallBeyondReach {
                atom: 10,
                wall: 1,
                ratio: 0.4,
                reach: 0.25,
                step: 5
            }
        );
        // An atom moved through the plane stops the pass, naming it.
        let mut through = x;
        through[0][2] = -0.01;
        let atoms = ListAtoms {
            x: &through,
            ..atoms
        };
        let (mut f, mut t) = (vec![[0.0; 3]; 2], vec![[0.0; 3]; 2]);
        let err = list
            .forces(
                &atoms,
                rows(),
                &corrections,
                &mut history,
                &mut f,
                &mut t,
                1e-3,
                true,
                false,
                7,
            )
            .unwrap_err();
        assert_eq!(
            err,
            ListError::ThroughWall {
                atom: 10,
                wall: 1,
                step: 7
            }
        );
    }

    /// A wall defined anew restarts its springs and keeps its load if it
    /// has the number, axis and side of a wall at the last evaluation;
    /// otherwise its entries are forgotten. Walls sharing a number are
    /// refused.
    #[test]
    fn a_wall_defined_anew_keeps_only_its_load() {
        let m = material();
        let wall = |number, sign| ListWall {
            number,
            plane: WallPlane {
                axis: 2,
                sign,
                position: 0.0,
                velocity: 0.0,
            },
            coeffs: GranularCoeffs::of(&m),
        };
        let slots = 2;
        let hist = Layout::history(slots);
        let loaded = ContactHistory {
            tangential: [1e-3, 2e-3, 0.0],
            rolling: [0.0, 1e-3, 0.0],
            twist: 0.1,
            normal_force: 4.0,
        };
        let mut list = GranularList::new(GranularCoeffs::of(&m), None, slots);
        let mut history = vec![0.0; hist.stride()];
        list.set_walls(
            &[wall(1, 1.0), wall(2, -1.0)],
            &[true, true],
            &mut history,
            1,
        )
        .unwrap();
        for key in [-1.0, -2.0] {
            assert!(hist.put(&mut history, 0, key, &loaded.to_values()));
        }
        // Not fresh: untouched.
        let kept = history.clone();
        list.set_walls(
            &[wall(1, 1.0), wall(2, -1.0)],
            &[false, false],
            &mut history,
            1,
        )
        .unwrap();
        assert_eq!(history, kept);
        // Wall 1 anew on the same side; wall 2 anew on the other side.
        list.set_walls(
            &[wall(1, 1.0), wall(2, 1.0)],
            &[true, true],
            &mut history,
            1,
        )
        .unwrap();
        let load = ContactHistory {
            normal_force: 4.0,
            ..ContactHistory::default()
        };
        assert_eq!(hist.get(&history, 0, -1.0), Some(&load.to_values()[..]));
        assert_eq!(hist.get(&history, 0, -2.0), None);
        let err = list
            .set_walls(
                &[wall(3, 1.0), wall(3, -1.0)],
                &[true, true],
                &mut history,
                1,
            )
            .unwrap_err();
        assert!(err.to_string().contains("share a number"), "{err}");
        assert!(list
            .set_walls(&[wall(0, 1.0)], &[true], &mut history, 1)
            .is_err());
    }

    #[test]
    fn a_row_stores_replaces_forgets_and_refuses_when_full() {
        let l = Layout::history(2);
        let mut data = vec![0.0; 2 * l.stride()];
        let v = |x: f64| [x; HISTORY_VALUES];
        assert!(l.put(&mut data, 1, 7.0, &v(1.0)));
        assert!(l.put(&mut data, 1, 9.0, &v(2.0)));
        assert!(l.put(&mut data, 1, 7.0, &v(3.0)));
        assert!(!l.put(&mut data, 1, 11.0, &v(4.0)));
        assert_eq!(l.get(&data, 1, 7.0), Some(&v(3.0)[..]));
        assert_eq!(l.get(&data, 0, 7.0), None);
        l.remove(&mut data, 1, 7.0);
        assert_eq!(l.get(&data, 1, 7.0), None);
        assert_eq!(l.get(&data, 1, 9.0), Some(&v(2.0)[..]));
        assert!(l.put(&mut data, 1, 11.0, &v(4.0)));
        l.remove(&mut data, 1, 5.0);
        assert_eq!(data[l.stride()], 2.0);
    }

    /// Three spheres in a row, the middle one squeezed by both: the pair
    /// forces over a list that puts either sphere first equal the plain
    /// pair kernel's with the corrections of `surface_corrections` on the
    /// middle sphere, and a row too small for them is an error naming the
    /// atom.
    #[test]
    fn a_squeezed_middle_sphere_gets_its_closure_through_the_list() {
        let m = material();
        let coeffs = GranularCoeffs::of(&m);
        let closure = ListClosure {
            closure: Closure::Advanced {
                max_penetration_ratio: 0.1,
                switch: MprSwitch::WholeContact,
                test: MprTest::Signed,
            },
            half_space: HalfSpace::new(0.8, m.youngs_modulus, m.poisson_ratio),
            reach: 0.25,
        };
        let x = [[0.0, 0.0, 0.0], [0.95, 0.01, 0.0], [1.9, 0.0, 0.03]];
        let zero = [[0.0; 3]; 3];
        let v = [[0.01, 0.02, 0.0], [-0.01, 0.0, 0.01], [0.0, -0.02, 0.0]];
        let radius = [0.5; 3];
        let mass = [1.0; 3];
        let tag = [10, 20, 30];
        let atoms = ListAtoms {
            x: &x,
            v: &v,
            omega: &zero,
            radius: &radius,
            mass: &mass,
            tag: &tag,
            n_owned: 3,
        };
        let slots = 4;
        let mut list = GranularList::new(coeffs, Some(closure), slots);
        let hist = Layout::history(slots);
        let corr = Layout::corrections(slots);
        let mut history = vec![0.0; 3 * hist.stride()];
        let mut corrections = vec![0.0; 3 * corr.stride()];
        // Atom 1 is never first in the list: its contacts reach it through
        // its partners' rows.
        let rows = || [(0usize, &[1i32][..]), (2usize, &[1i32][..])].into_iter();
        // First evaluation: no forces remembered, so no corrections.
        list.corrections(&atoms, rows(), &history, &mut corrections, 0)
            .unwrap();
        assert!(corrections.iter().all(|&c| c == 0.0));
        let (mut f, mut t) = (vec![[0.0; 3]; 3], vec![[0.0; 3]; 3]);
        list.forces(
            &atoms,
            rows(),
            &corrections,
            &mut history,
            &mut f,
            &mut t,
            1e-3,
            true,
            true,
            0,
        )
        .unwrap();
        // Both contacts remembered on both sides, with the normal force.
        let f01 = hist.get(&history, 0, 20.0).unwrap()[7];
        let f21 = hist.get(&history, 2, 20.0).unwrap()[7];
        assert!(f01 > 0.0 && f21 > 0.0);
        assert_eq!(hist.get(&history, 1, 10.0).unwrap()[7], f01);
        assert_eq!(hist.get(&history, 1, 30.0).unwrap()[7], f21);
        // The middle sphere keeps each contact from its own side.
        let from_0 = ContactHistory::from_values(hist.get(&history, 0, 20.0).unwrap());
        let from_1 = ContactHistory::from_values(hist.get(&history, 1, 10.0).unwrap());
        assert!(from_0.tangential != [0.0; 3]);
        assert_eq!(from_1, from_0.mirrored());
        // A stale entry (a partner no longer listed) survives a pass
        // without a rebuild and is dropped by one that follows a rebuild.
        assert!(hist.put(&mut history, 0, 99.0, &[1.0; HISTORY_VALUES]));
        let saved = history.clone();
        for renew in [false, true] {
            let mut h = saved.clone();
            let (mut f, mut t) = (vec![[0.0; 3]; 3], vec![[0.0; 3]; 3]);
            list.forces(
                &atoms,
                rows(),
                &corrections,
                &mut h,
                &mut f,
                &mut t,
                0.0,
                false,
                renew,
                0,
            )
            .unwrap();
            assert_eq!(hist.get(&h, 0, 99.0).is_some(), !renew);
            // Both sides of each listed contact are kept.
            for (atom, partner) in [(0, 20.0), (1, 10.0), (1, 30.0), (2, 20.0)] {
                assert_eq!(
                    hist.get(&h, atom, partner),
                    hist.get(&saved, atom, partner),
                    "renew {renew}: atom {atom}, partner {partner}"
                );
            }
        }
        hist.remove(&mut history, 0, 99.0);
        // Second evaluation: the middle sphere's two contacts correct each
        // other as surface_corrections says.
        list.corrections(&atoms, rows(), &history, &mut corrections, 1)
            .unwrap();
        let del = |a: usize, b: usize| super::super::sub(&x[a], &x[b]);
        let r = |d: [f64; 3]| super::super::dot(&d, &d).sqrt();
        let [_, p10] = pair_contact_points(&del(0, 1), r(del(0, 1)), 0.5, 0.5, f01);
        let [_, p12] = pair_contact_points(&del(2, 1), r(del(2, 1)), 0.5, 0.5, f21);
        let mut expect = [0.0; 2];
        surface_corrections(
            &closure.half_space,
            &closure.closure,
            0.5,
            &[p10, p12],
            &mut expect,
        );
        assert!(expect[0] > 0.0 && expect[1] > 0.0, "{expect:?}");
        assert_eq!(corr.get(&corrections, 1, 10.0).unwrap()[0], expect[0]);
        assert_eq!(corr.get(&corrections, 1, 30.0).unwrap()[0], expect[1]);
        // The end spheres have one contact each: nothing to correct.
        assert_eq!(corrections[0], 0.0);
        assert_eq!(corrections[2 * corr.stride()], 0.0);
        // The forces use them: sphere 0's is the kernel's with the middle
        // sphere's surface moved out by its correction.
        let mut h = ContactHistory::from_values(hist.get(&history, 0, 20.0).unwrap());
        let (mut f, mut t) = (vec![[0.0; 3]; 3], vec![[0.0; 3]; 3]);
        list.forces(
            &atoms,
            rows(),
            &corrections,
            &mut history,
            &mut f,
            &mut t,
            1e-3,
            true,
            false,
            1,
        )
        .unwrap();
        let s = |i: usize| sphere(v[i], zero[i], radius[i]);
        let mut s0 = s(0);
        s0.mass = 1.0;
        let mut s1 = s(1);
        s1.mass = 1.0;
        let c01 = corrected_granular_contact(
            &coeffs,
            &del(0, 1),
            &s0,
            &s1,
            [0.0, expect[0]],
            &mut h,
            1e-3,
            true,
        );
        assert_eq!(f[0], c01.force);
        let plain = granular_contact(&coeffs, &del(0, 1), &s0, &s1, &mut h.clone(), 1e-3, true);
        assert!(c01.force[0] < 1.05 * plain.force[0] && c01.force[0] < plain.force[0]);
        // A one-slot row cannot hold the middle sphere's two contacts.
        let mut small = GranularList::new(coeffs, Some(closure), 1);
        let mut h1 = vec![0.0; 3 * Layout::history(1).stride()];
        let c1 = vec![0.0; 3 * Layout::corrections(1).stride()];
        let err = small
            .forces(
                &atoms,
                rows(),
                &c1,
                &mut h1,
                &mut f,
                &mut t,
                1e-3,
                true,
                true,
                0,
            )
            .unwrap_err();
        assert_eq!(err, ListError::RowFull { atom: 20, slots: 1 });
    }
}
