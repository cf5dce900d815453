//! A LAMMPS bond list kept as [`BondRows`] between neighbour builds: the
//! drop-in bond styles' pass with one bond type and no energy or virial.
//!
//! [`failing_list_forces`](super::failing_list_forces) walks the list every
//! step and scatters each bond's force to both atoms. Here the list's
//! intact bonds become rows once per neighbour build, and each step runs
//! the native engine's two-step pass: every row's force written on its
//! own, then each atom's rows gathered (see [`super::bond_rows`]). The
//! rows keep the list's order, so each atom sums its bonds in the order
//! the scatter adds them, and the forces, breaks and plastic strains are
//! the list pass's bit for bit (this module's tests). Bonds that break
//! leave the rows in the same step ([`BondRows::remove_rows`]); the
//! reference volumes `V0` are summed only when bonds broke or yielded
//! since the last time, not every step.

use super::bond::{BondCoeffs, BondEntry};
use super::bond_failure::{failing_row_forces, gather_rest_volumes, row_broke, BondFailure};
use super::bond_rows::{
    drop_rows, gather_forces, gather_volumes, row_volumes, BondRows, BondRowsError, RowInputs,
};
use super::failing_bond_list::ListFailures;
use super::geometry::Unwrapped;
use super::plastic_rows::PlasticRows;

/// Which list the rows mirror: the caller's count of neighbour builds and
/// of its own edits to the list, with the list's length and the atom
/// count. Rows built for another stamp are built anew.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ListStamp {
    /// How many times the caller built the list and its lengths (the
    /// plugin: its reference fix's rebuilds of the list-aligned lengths, at
    /// each neighbour build and run set-up).
    pub builds: i64,
    /// Changes to the list or its lengths made by others than these rows
    /// (e.g. a pass of the list kernel), counted by the caller.
    pub edits: i64,
    /// Entries in the list, broken ones included.
    pub entries: usize,
    /// Owned and ghost atoms.
    pub atoms: usize,
}

/// Why a list cannot be kept as rows.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ListRowsError {
    /// A bond of a type other than 1 (rows carry one type's coefficients).
    #[error("bond list entry {entry} has type {ty}; the rows take one bond type")]
    Type {
        /// The entry.
        entry: usize,
        /// Its type.
        ty: i32,
    },
    /// A length slice shorter than the list.
    #[error("{what} for {given} of the {entries} list entries")]
    Lengths {
        /// Which lengths.
        what: &'static str,
        /// How many were given.
        given: usize,
        /// Entries in the list.
        entries: usize,
    },
    /// An atom index outside the atoms, or a bond of an atom with itself.
    #[error(transparent)]
    Rows(#[from] BondRowsError),
}

/// The intact bonds of a bond list as rows, with what each step's pass
/// keeps: the rows' lengths, their forces and plastic strains.
#[derive(Clone, Debug, Default)]
pub struct ListRows {
    rows: BondRows,
    stamp: Option<ListStamp>,
    /// `[r, r^3]` per row, from [`ListRows::volumes`].
    lengths: Vec<[f64; 2]>,
    /// Each row's force on its `i`.
    forces: Vec<[f64; 4]>,
    /// Each row's plastic strain, as [`ListRows::sync`] gave it (moved only
    /// by a rule that yields).
    plastic: PlasticRows,
    /// Whether `V0` must be summed anew: the rows are new, or bonds broke
    /// or yielded since it was.
    reference_stale: bool,
    /// Whether every atom's `V0` must be summed (new rows, or bonds that
    /// yielded), not only those of `touched`.
    reference_full: bool,
    /// The atoms of the bonds broken since `V0` was last set.
    touched: Vec<usize>,
    /// `V0` of every atom as last set (empty: never).
    vol0_set: Vec<f64>,
    /// Whether `lengths` are those of the positions of the coming force
    /// pass: set by [`ListRows::volumes`], spent by [`ListRows::forces`].
    lengths_current: bool,
    /// Rows that broke in the last pass, and the rows' new indices after
    /// them (kept to reuse the allocations).
    doomed: Vec<usize>,
    renumbering: Vec<u32>,
}

impl ListRows {
    /// Rows of no list: the first [`ListRows::sync`] builds them.
    pub fn new() -> Self {
        Self::default()
    }

    /// Makes the rows those of `bonds` if `stamp` is not the one they were
    /// built for: each entry of type 1, in list order, with its first
    /// length from `r0` and its plastic strain from `plastic` (empty: 0).
    /// Entries of type 0 or below are broken bonds and skipped. Returns
    /// whether the reference volumes must be summed
    /// ([`ListRows::volumes`] with `vol0`) and set
    /// ([`ListRows::set_reference_volumes`]) before the next force pass
    /// with the multibody term.
    pub fn sync(
        &mut self,
        stamp: ListStamp,
        bonds: &[BondEntry],
        r0: &[f64],
        plastic: &[f64],
    ) -> Result<bool, ListRowsError> {
        if self.stamp == Some(stamp) {
            return Ok(self.reference_stale);
        }
        self.stamp = None;
        let entries = bonds.len();
        if r0.len() < entries {
            return Err(ListRowsError::Lengths {
                what: "first lengths",
                given: r0.len(),
                entries,
            });
        }
        if !plastic.is_empty() && plastic.len() < entries {
            return Err(ListRowsError::Lengths {
                what: "plastic strains",
                given: plastic.len(),
                entries,
            });
        }
        if let Some((entry, b)) = bonds.iter().enumerate().find(|(_, b)| b.ty > 1) {
            return Err(ListRowsError::Type { entry, ty: b.ty });
        }
        let intact = bonds.iter().enumerate().filter(|(_, b)| b.ty > 0);
        let atom = |index: i32| usize::try_from(index).unwrap_or(usize::MAX);
        self.rows = BondRows::new(
            stamp.atoms,
            ExactCount {
                items: intact
                    .clone()
                    .map(|(n, b)| (atom(b.i), atom(b.j), r0[n], n)),
                len: intact.count(),
            },
            None,
        )?;
        self.forces.clear();
        self.forces.resize(self.rows.len(), [0.0; 4]);
        let strains = self
            .rows
            .bonds()
            .map(|n| plastic.get(n).copied().unwrap_or(0.0));
        self.plastic = PlasticRows::new(&self.rows, strains.collect());
        self.lengths.clear();
        self.lengths.resize(self.rows.len(), [0.0; 2]);
        self.stamp = Some(stamp);
        self.reference_stale = true;
        self.reference_full = true;
        self.touched.clear();
        self.lengths_current = false;
        Ok(true)
    }

    /// The atom count the rows were last synced with (`None`: no list).
    pub fn atoms(&self) -> Option<usize> {
        self.stamp.map(|s| s.atoms)
    }

    /// The list length the rows were last synced with (`None`: no list).
    pub fn entries(&self) -> Option<usize> {
        self.stamp.map(|s| s.entries)
    }

    /// Whether the multibody term can run: [`ListRows::volumes`] was called
    /// since the last force pass or rebuild, and the reference volumes are
    /// set.
    pub fn ready_for_multibody(&self) -> bool {
        self.lengths_current && !self.reference_stale
    }

    /// Number of rows (intact bonds).
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    /// Whether there are no rows.
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// The multibody term's volumes: each row's length and `r^3` for the
    /// next force pass, `vol[p]` the sum of `r^3` over atom `p`'s rows for
    /// the atoms `0..vol.len()` (LAMMPS's owned atoms, or all with newton
    /// on), and with `vol0` the same atoms' sums of `r_eq^3`.
    ///
    /// `forwarded`: the caller completes `vol0` by copying owners' values
    /// to ghosts only (LAMMPS with newton off), not by summing ghosts' parts
    /// into owners. If bonds only broke since `V0` was last set, only the
    /// atoms of the broken bonds are summed then, the others keeping their
    /// values as set: the same bits as every atom summed anew.
    ///
    /// # Panics
    /// If `x` does not hold the stamp's atoms, `vol` more, or `vol0` is
    /// not as long as `vol`.
    pub fn volumes(
        &mut self,
        x: &[[f64; 3]],
        vol: &mut [f64],
        vol0: Option<&mut [f64]>,
        forwarded: bool,
    ) {
        let rows = &self.rows;
        row_volumes(&Unwrapped, rows, 0..rows.len(), x, &mut self.lengths);
        gather_volumes(rows, 0..vol.len(), &self.lengths, vol);
        self.lengths_current = true;
        let Some(vol0) = vol0 else {
            return;
        };
        let n = vol0.len();
        if forwarded && !self.reference_full && self.vol0_set.len() >= n {
            vol0.copy_from_slice(&self.vol0_set[..n]);
            for &p in self.touched.iter().filter(|&&p| p < n) {
                gather_rest_volumes(rows, p..p + 1, &self.plastic, &mut vol0[p..p + 1]);
            }
        } else {
            gather_rest_volumes(rows, 0..n, &self.plastic, vol0);
        }
    }

    /// Sets each row's `1 / (V0_i + V0_j)` from `vol0`, every atom's `V0`
    /// (ghosts included, after the caller's communication): after bonds
    /// only broke, only the rows of atoms whose `V0` changed.
    pub fn set_reference_volumes(&mut self, vol0: &[f64]) -> Result<(), ListRowsError> {
        if !self.reference_full && self.vol0_set.len() == vol0.len() {
            let changed = vol0
                .iter()
                .zip(&self.vol0_set)
                .enumerate()
                .filter(|(_, (now, before))| now.to_bits() != before.to_bits())
                .map(|(p, _)| p);
            self.rows.update_reference_volumes(vol0, changed)?;
        } else {
            self.rows.set_reference_volumes(vol0)?;
        }
        self.vol0_set.clear();
        self.vol0_set.extend_from_slice(vol0);
        self.reference_stale = false;
        self.reference_full = false;
        self.touched.clear();
        Ok(())
    }

    /// Adds the rows' forces to the atoms `0..f.len()` (owned atoms, or all
    /// with newton on), as [`failing_list_forces`](super::failing_list_forces)
    /// adds them with the rule `rule` and coefficients `coeffs` of type 1,
    /// without energy or virial. `volumes` is `V` per atom from
    /// [`ListRows::volumes`] on the same positions (communicated), `None`
    /// without the multibody term; `v` `None` drops damping. A bond that
    /// breaks gets type 0 in `bonds`, its list index goes to `broken` (in
    /// list order) and its row goes; a bond that yields gets its new `e_p`
    /// in `plastic` (which may be empty when the rule does not yield).
    ///
    /// # Panics
    /// If `x`, `v` or `volumes` do not hold the stamp's atoms, `f` more,
    /// `bonds`, `plastic` or `broken` are shorter than the list, or the
    /// multibody term is asked for when not
    /// [`ready`](ListRows::ready_for_multibody).
    // One argument per array the pass reads or writes, as its C ABI passes them.
    #[allow(clippy::too_many_arguments)]
    pub fn forces(
        &mut self,
        x: &[[f64; 3]],
        v: Option<&[[f64; 3]]>,
        volumes: Option<&[f64]>,
        coeffs: BondCoeffs,
        rule: &BondFailure,
        may_break: bool,
        f: &mut [[f64; 3]],
        bonds: &mut [BondEntry],
        plastic: &mut [f64],
        broken: &mut [i32],
    ) -> ListFailures {
        let rule = BondFailure {
            breaks: rule.breaks && may_break,
            ..*rule
        };
        assert!(
            volumes.is_none() || self.ready_for_multibody(),
            "the multibody term needs this step's volumes and the reference volumes set"
        );
        self.lengths_current = false;
        let inputs = RowInputs {
            x,
            v,
            coeffs,
            multibody: volumes.map(|vol| (vol, &self.lengths[..])),
            tally: false,
        };
        let rows = &self.rows;
        let yields = rule.plastic_strain.is_some();
        if yields {
            self.plastic.band_for(&rule);
        }
        let section = yields.then(|| self.plastic.section(0..rows.len()));
        let pass = failing_row_forces(
            &Unwrapped,
            rows,
            0..rows.len(),
            &inputs,
            &rule,
            section,
            &mut self.forces,
        );
        self.doomed.clear();
        if pass.broken > 0 {
            self.doomed.extend(
                self.forces
                    .iter()
                    .enumerate()
                    .filter(|(_, row)| row_broke(row))
                    .map(|(row, _)| row),
            );
            for (slot, &row) in broken.iter_mut().zip(&self.doomed) {
                if !self.vol0_set.is_empty() {
                    let (i, j) = self.rows.atoms(row);
                    self.touched.extend([i, j]);
                }
                let entry = self.rows.bond[row] as usize;
                bonds[entry].ty = 0;
                *slot = entry as i32;
            }
            self.rows.remove_rows(&self.doomed, &mut self.renumbering);
            drop_rows(&mut self.forces, &self.doomed);
            self.plastic.remove_rows(&self.doomed);
            drop_rows(&mut self.lengths, &self.doomed);
            self.reference_stale = true;
        }
        debug_assert_eq!(self.doomed.len(), pass.broken, "rows marked broken");
        gather_forces(&self.rows, 0..f.len(), &self.forces, f);
        if pass.yielded > 0 && rule.plastic_strain.is_some() {
            for (entry, &e_p) in self.rows.bonds().zip(self.plastic.strains()) {
                plastic[entry] = e_p;
            }
            self.reference_stale = true;
            self.reference_full = true;
        }
        ListFailures {
            pass: pass.pass,
            // The broken slots filled, whatever the pass counted.
            broken: self.doomed.len(),
            yielded: pass.yielded,
        }
    }
}

/// An iterator whose length is known beforehand (a filter's is not).
struct ExactCount<I> {
    items: I,
    len: usize,
}

impl<I: Iterator> Iterator for ExactCount<I> {
    type Item = I::Item;
    fn next(&mut self) -> Option<I::Item> {
        let item = self.items.next()?;
        self.len -= 1;
        Some(item)
    }
    fn size_hint(&self) -> (usize, Option<usize>) {
        (self.len, Some(self.len))
    }
}

impl<I: Iterator> ExactSizeIterator for ExactCount<I> {}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernels::{
        accumulate_intact_volumes, failing_list_forces, FailingListInputs, Ownership,
    };
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// A jiggled cubic block of `side^3` atoms, each bonded to the atoms
    /// within 1.5 spacings after it, in LAMMPS's order (runs of entries
    /// under each first atom); some entries already broken.
    fn block(side: usize, rng: &mut ChaCha8Rng) -> (Vec<[f64; 3]>, Vec<BondEntry>, Vec<f64>) {
        let mut x = Vec::new();
        for a in 0..side * side * side {
            let site = [a % side, a / side % side, a / (side * side)];
            x.push(site.map(|c| c as f64 + rng.gen_range(-0.05..0.05)));
        }
        let (mut bonds, mut r0) = (Vec::new(), Vec::new());
        for i in 0..x.len() {
            for j in i + 1..x.len() {
                let d: f64 = (0..3).map(|k| (x[i][k] - x[j][k]).powi(2)).sum::<f64>();
                if d.sqrt() < 1.5 {
                    let ty = if rng.gen_bool(0.05) { 0 } else { 1 };
                    bonds.push(BondEntry {
                        i: i as i32,
                        j: j as i32,
                        ty,
                    });
                    r0.push(d.sqrt() * rng.gen_range(0.99..1.01));
                }
            }
        }
        (x, bonds, r0)
    }

    fn bits(v: &[[f64; 3]]) -> Vec<u64> {
        v.iter().flatten().map(|c| c.to_bits()).collect()
    }

    #[test]
    fn removing_rows_gives_the_layout_built_from_the_rows_left() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let (_, bonds, r0) = block(5, &mut rng);
        let vol0: Vec<f64> = (0..125).map(|_| rng.gen_range(5.0..7.0)).collect();
        let all: Vec<_> = bonds
            .iter()
            .zip(&r0)
            .enumerate()
            .map(|(n, (b, &r))| (b.i as usize, b.j as usize, r, n))
            .collect();
        for share in [0.0, 0.01, 0.3, 1.0] {
            let doomed: Vec<usize> = (0..all.len()).filter(|_| rng.gen_bool(share)).collect();
            let mut rows = BondRows::new(125, all.iter().copied(), Some(&vol0)).unwrap();
            rows.remove_rows(&doomed, &mut Vec::new());
            let left: Vec<_> = all
                .iter()
                .enumerate()
                .filter(|(n, _)| !doomed.contains(n))
                .map(|(_, &row)| row)
                .collect();
            let want = BondRows::new(125, left.iter().copied(), Some(&vol0)).unwrap();
            assert_eq!(rows, want, "{} rows removed", doomed.len());
            // V0 changed on a few particles: their rows updated alone are
            // the rows of a layout built with the new V0.
            let mut changed_vol0 = vol0.clone();
            let changed = [3, 60, 124];
            for &p in &changed {
                changed_vol0[p] *= 0.9;
            }
            rows.update_reference_volumes(&changed_vol0, changed.into_iter())
                .unwrap();
            let want = BondRows::new(125, left.into_iter(), Some(&changed_vol0)).unwrap();
            assert_eq!(rows, want, "V0 updated, {} rows removed", doomed.len());
        }
    }

    /// Both passes over a block pulled apart along z step by step, with
    /// ghosts (the last third of the atoms) and `newton`: the same forces,
    /// breaks, types and plastic strains bit for bit each step.
    fn assert_rows_follow_the_list(rule: BondFailure, multibody: bool, damped: bool, newton: bool) {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let (mut x, mut list_bonds, r0) = block(6, &mut rng);
        let atoms = x.len();
        let own = Ownership {
            n_owned: atoms * 2 / 3,
            newton,
        };
        let gathered = if newton { atoms } else { own.n_owned };
        let coeffs = BondCoeffs {
            k: 2.0,
            a: if multibody { -0.7 } else { 0.0 },
            gamma: 0.3,
        };
        let entries = list_bonds.len();
        let mut row_bonds = list_bonds.clone();
        let yields = rule.plastic_strain.is_some();
        let mut list_plastic = vec![0.0; if yields { entries } else { 0 }];
        let mut row_plastic = list_plastic.clone();
        let mut rows = ListRows::new();
        let (mut broke, mut yielded) = (0, 0);
        for step in 0..40 {
            for p in x.iter_mut() {
                p[2] *= 1.002;
                p[0] += rng.gen_range(-0.002..0.002);
            }
            let v: Vec<[f64; 3]> = (0..atoms)
                .map(|_| [(); 3].map(|_| rng.gen_range(-0.1..0.1)))
                .collect();
            // Every atom's volumes, as the owners' passes and LAMMPS's
            // communication leave them.
            let (mut vol, mut vol0) = (vec![0.0; atoms], vec![0.0; atoms]);
            accumulate_intact_volumes(
                &Unwrapped,
                &x,
                &list_bonds,
                (&r0, &list_plastic),
                Ownership::all(atoms),
                (&mut vol, &mut vol0),
            );
            // Every seventh step the caller's list is new (rows rebuilt
            // from the list as the pass left it, broken entries and all).
            let stamp = ListStamp {
                builds: 1,
                edits: step / 7,
                entries,
                atoms,
            };
            let stale = rows.sync(stamp, &row_bonds, &r0, &row_plastic).unwrap();
            assert_eq!(stale, step % 7 == 0 || broke + yielded > 0, "step {step}");
            // The rows' volumes of the atoms they gather (owned ones, or
            // all with newton on), the ghosts' as communication brings them.
            let (mut row_vol, mut row_vol0) = (vol.clone(), vol0.clone());
            rows.volumes(
                &x,
                &mut row_vol[..gathered],
                stale.then_some(&mut row_vol0[..gathered]),
                !newton,
            );
            assert_eq!(row_vol, vol, "V of every atom, step {step}");
            if stale {
                assert_eq!(row_vol0, vol0, "V0 of every atom, step {step}");
                rows.set_reference_volumes(&row_vol0).unwrap();
            }
            // Now and then a set-up step, in which no bond may break.
            let may_break = step % 6 != 5;
            let inputs = FailingListInputs {
                x: &x,
                v: damped.then_some(&v[..]),
                r0: &r0,
                coeffs: &[coeffs],
                rules: &[rule],
                may_break,
                volumes: multibody.then_some((&vol[..], &vol0[..])),
                tally: false,
            };
            let mut f_list = vec![[0.5, -0.25, 0.125]; atoms];
            let mut f_rows = f_list.clone();
            let (mut broken_list, mut broken_rows) = (vec![-1; entries], vec![-1; entries]);
            let by_list = failing_list_forces(
                &Unwrapped,
                &inputs,
                &mut list_bonds,
                &mut list_plastic,
                own,
                &mut f_list,
                &mut broken_list,
            );
            let by_rows = rows.forces(
                &x,
                damped.then_some(&v[..]),
                multibody.then_some(&vol[..]),
                coeffs,
                &rule,
                may_break,
                &mut f_rows[..gathered],
                &mut row_bonds,
                &mut row_plastic,
                &mut broken_rows,
            );
            assert_eq!(by_rows, by_list, "step {step}");
            assert_eq!(bits(&f_rows), bits(&f_list), "forces, step {step}");
            assert_eq!(broken_rows, broken_list, "step {step}");
            assert_eq!(row_bonds, list_bonds, "step {step}");
            assert_eq!(row_plastic, list_plastic, "step {step}");
            assert_eq!(rows.len(), list_bonds.iter().filter(|b| b.ty > 0).count());
            broke = by_rows.broken;
            yielded = by_rows.yielded;
        }
        let left = list_bonds.iter().filter(|b| b.ty > 0).count();
        assert!(
            left < entries * 9 / 10 && left > 0,
            "the block must break in part: {left} of {entries} bonds left"
        );
        if yields {
            assert!(list_plastic.iter().any(|&e| e != 0.0), "bonds must yield");
        }
    }

    #[test]
    fn rows_give_the_list_pass_bit_for_bit_as_bonds_break_and_yield() {
        let breaking = BondFailure::breaking(0.04);
        let plain = BondFailure {
            smooth: false,
            ..breaking
        };
        let plastic = BondFailure {
            plastic_strain: Some(0.01),
            ..BondFailure::breaking(0.06)
        };
        let normalized = BondFailure {
            normalize: true,
            ..plastic
        };
        for rule in [breaking, plain, plastic, normalized] {
            for flags in 0..8u8 {
                let [multibody, damped, newton] = [0, 1, 2].map(|b| flags & (1 << b) != 0);
                assert_rows_follow_the_list(rule, multibody, damped, newton);
            }
        }
    }

    #[test]
    fn a_new_stamp_rebuilds_and_a_list_of_several_types_is_refused() {
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        let (_, mut bonds, r0) = block(3, &mut rng);
        let stamp = ListStamp {
            builds: 4,
            edits: 2,
            entries: bonds.len(),
            atoms: 27,
        };
        let mut rows = ListRows::new();
        assert!(rows.sync(stamp, &bonds, &r0, &[]).unwrap());
        let intact = bonds.iter().filter(|b| b.ty > 0).count();
        assert_eq!(rows.len(), intact);
        rows.set_reference_volumes(&[1.0; 27]).unwrap();
        assert!(
            !rows.sync(stamp, &bonds, &r0, &[]).unwrap(),
            "same stamp: kept"
        );
        bonds[0].ty = 0;
        let edited = ListStamp { edits: 3, ..stamp };
        assert!(rows.sync(edited, &bonds, &r0, &[]).unwrap());
        assert_eq!(rows.len(), bonds.iter().filter(|b| b.ty > 0).count());
        bonds[1].ty = 2;
        let err = rows.sync(stamp, &bonds, &r0, &[]).unwrap_err();
        assert_eq!(err, ListRowsError::Type { entry: 1, ty: 2 });
        bonds[1].ty = 1;
        bonds[2].j = 27;
        assert!(matches!(
            rows.sync(stamp, &bonds, &r0, &[]),
            Err(ListRowsError::Rows(BondRowsError::BadAtom { .. }))
        ));
        assert!(matches!(
            rows.sync(stamp, &bonds, &r0[..3], &[]),
            Err(ListRowsError::Lengths { .. })
        ));
    }
}
