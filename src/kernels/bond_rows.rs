//! The bond pass in two steps, for an engine that owns every atom: each
//! bond's force into a row of its own, then each particle's rows summed.
//!
//! The scatter of [`super::bond_forces`] (`f_i += F`, `f_j -= F` bond by
//! bond) costs as many instructions as the force itself, and threads that
//! scatter need a copy of the force array each. Here the first step writes
//! bond `b`'s force on its atom `i` into row `b` (a pure map over bonds, four
//! at a time in vector instructions), and the second gives each particle the
//! sum of its rows, added where it is the bond's `i` and subtracted where it
//! is the `j`, in row order. That is the order in which the scatter over the
//! same rows adds them, so the forces are the same bit for bit; and since a
//! particle's sum no longer depends on how the rows are split between
//! threads, they are the same for every thread count. The per-particle
//! volume proxies `V_i` of the multibody term are summed the same way.
//!
//! The arithmetic per bond is that of [`super::bond_forces`], operation by
//! operation and without fused multiply-adds, on every instruction set.

use super::bond::{cube_root, reciprocal, BondCoeffs, CLOSE_TO_ONE, SERIES_AND_STEP_UP_TO};
use super::fault::{Fault, ForcePass, COLLAPSED_BELOW, OVERSTRETCHED_ABOVE};
use super::isa::Isa;
use super::tally::Tally;
use super::Separation;
use std::ops::Range;

/// The sign bit of an incidence entry: the particle is the row's `j`.
pub(super) const AS_J: u32 = 1 << 31;

/// The most rows, and particles, the 31 bits of an entry index.
const MAX_INDEX: usize = (AS_J - 1) as usize;

/// Bonds as rows, and for each particle the rows it takes part in.
///
/// Built once per layout (the engine rebuilds it when positions wrap);
/// every index is checked here, so the passes need no bounds checks.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BondRows {
    particles: usize,
    pub(super) i: Vec<u32>,
    pub(super) j: Vec<u32>,
    pub(super) r0: Vec<f64>,
    /// `1 / r0`, once per layout instead of a division per step.
    pub(super) inv_r0: Vec<f64>,
    /// `1 / (V0_i + V0_j)`, when the layout was given reference volumes.
    pub(super) inv_v0sum: Vec<f64>,
    /// Each row's bond in the caller's numbering (for fault reports).
    pub(super) bond: Vec<u32>,
    /// `offsets[p]..offsets[p + 1]` index `incidence` for particle `p`.
    offsets: Vec<usize>,
    /// Row indices, in increasing order per particle, with [`AS_J`] set
    /// where the particle is the row's `j`.
    incidence: Vec<u32>,
}

/// A row the layout refused.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum BondRowsError {
    /// An atom index at or beyond the particle count, or a bond of an atom
    /// with itself.
    #[error("bond row {row} joins atoms {i} and {j}, but there are {particles} particles")]
    BadAtom {
        /// The row.
        row: usize,
        /// First atom.
        i: usize,
        /// Second atom.
        j: usize,
        /// Particle count.
        particles: usize,
    },
    /// Reference volumes for another number of particles.
    #[error("{given} reference volumes for {particles} particles")]
    ReferenceVolumes {
        /// Volumes given.
        given: usize,
        /// Particle count.
        particles: usize,
    },
    /// More rows or particles than the layout's 31-bit indices hold.
    #[error("{what} ({count}) exceed the {limit} the bond rows can index")]
    TooMany {
        /// Rows or particles.
        what: &'static str,
        /// How many.
        count: usize,
        /// The most there can be.
        limit: usize,
    },
}

impl BondRows {
    /// Rows of `(i, j, r0, bond)` on `particles` particles, in the order
    /// given; `reference_volumes` (`V0` per particle) when the multibody
    /// term is on.
    pub fn new(
        particles: usize,
        rows: impl ExactSizeIterator<Item = (usize, usize, f64, usize)>,
        reference_volumes: Option<&[f64]>,
    ) -> Result<Self, BondRowsError> {
        if let Some(vol0) = reference_volumes.filter(|v| v.len() != particles) {
            return Err(BondRowsError::ReferenceVolumes {
                given: vol0.len(),
                particles,
            });
        }
        if particles > MAX_INDEX {
            return Err(BondRowsError::TooMany {
                what: "particles",
                count: particles,
                limit: MAX_INDEX,
            });
        }
        if rows.len() > MAX_INDEX {
            return Err(BondRowsError::TooMany {
                what: "bond rows",
                count: rows.len(),
                limit: MAX_INDEX,
            });
        }
        let mut layout = Self {
            particles,
            offsets: vec![0; particles + 1],
            ..Self::default()
        };
        for (row, (i, j, r0, bond)) in rows.enumerate() {
            if i >= particles || j >= particles || i == j {
                return Err(BondRowsError::BadAtom {
                    row,
                    i,
                    j,
                    particles,
                });
            }
            layout.i.push(i as u32);
            layout.j.push(j as u32);
            layout.r0.push(r0);
            layout.inv_r0.push(reciprocal(r0));
            if let Some(vol0) = reference_volumes {
                layout.inv_v0sum.push(reciprocal(vol0[i] + vol0[j]));
            }
            layout.bond.push(bond.min(u32::MAX as usize) as u32);
            layout.offsets[i + 1] += 1;
            layout.offsets[j + 1] += 1;
        }
        for p in 0..particles {
            layout.offsets[p + 1] += layout.offsets[p];
        }
        let mut cursor = layout.offsets.clone();
        layout.incidence = vec![0; layout.offsets[particles]];
        for (row, (&i, &j)) in layout.i.iter().zip(&layout.j).enumerate() {
            for (p, flag) in [(i as usize, 0), (j as usize, AS_J)] {
                layout.incidence[cursor[p]] = row as u32 | flag;
                cursor[p] += 1;
            }
        }
        Ok(layout)
    }

    /// Replaces the reference volumes the rows were built with by `vol0`
    /// (`V0` per particle): `1 / (V0_i + V0_j)` of every row anew.
    pub fn set_reference_volumes(&mut self, vol0: &[f64]) -> Result<(), BondRowsError> {
        if vol0.len() != self.particles {
            return Err(BondRowsError::ReferenceVolumes {
                given: vol0.len(),
                particles: self.particles,
            });
        }
        self.inv_v0sum.clear();
        self.inv_v0sum.extend(
            self.i
                .iter()
                .zip(&self.j)
                .map(|(&i, &j)| reciprocal(vol0[i as usize] + vol0[j as usize])),
        );
        Ok(())
    }

    /// Takes out the rows `doomed` (increasing, no repeats): the rows left
    /// keep their order, and each particle its entries' order, so the
    /// layout is the one [`BondRows::new`] builds from the rows left, and
    /// every pass over it gives the same bits. One pass over the rows and
    /// the entries, with `renumbering` as scratch (kept by the caller, so
    /// a step in which bonds break allocates nothing): what such a step
    /// costs instead of a new layout.
    ///
    /// # Panics
    /// If `doomed` is not increasing or names a row past the last.
    pub fn remove_rows(&mut self, doomed: &[usize], renumbering: &mut Vec<u32>) {
        let Some(&first) = doomed.first() else {
            return;
        };
        let rows = self.len();
        assert!(
            doomed.windows(2).all(|w| w[0] < w[1]) && doomed[doomed.len() - 1] < rows,
            "rows to remove must increase and lie below {rows}"
        );
        // Each row's index once the doomed ones are gone (GONE for them):
        // a load per entry below, where a search of `doomed` would be a
        // branch per step of the search.
        const GONE: u32 = u32::MAX;
        renumbering.clear();
        renumbering.extend(0..first as u32);
        let mut next = doomed.iter().copied().peekable();
        let mut kept = first as u32;
        for row in first..rows {
            if next.peek() == Some(&row) {
                next.next();
                renumbering.push(GONE);
            } else {
                renumbering.push(kept);
                kept += 1;
            }
        }
        drop_rows(&mut self.i, doomed);
        drop_rows(&mut self.j, doomed);
        drop_rows(&mut self.r0, doomed);
        drop_rows(&mut self.inv_r0, doomed);
        drop_rows(&mut self.inv_v0sum, doomed);
        drop_rows(&mut self.bond, doomed);
        let mut write = 0;
        let mut start = 0;
        for p in 0..self.particles {
            let end = self.offsets[p + 1];
            self.offsets[p] = write;
            for k in start..end {
                let entry = self.incidence[k];
                let row = renumbering[(entry & !AS_J) as usize];
                if row == GONE {
                    continue;
                }
                self.incidence[write] = row | (entry & AS_J);
                write += 1;
            }
            start = end;
        }
        self.offsets[self.particles] = write;
        self.incidence.truncate(write);
    }

    /// As [`BondRows::set_reference_volumes`], but only for the rows of
    /// the particles `changed` (the others' `V0` as last set): the same
    /// `1 / (V0_i + V0_j)` where it is computed, and no pass over every row.
    pub fn update_reference_volumes(
        &mut self,
        vol0: &[f64],
        changed: impl Iterator<Item = usize>,
    ) -> Result<(), BondRowsError> {
        if vol0.len() != self.particles || self.inv_v0sum.len() != self.len() {
            return Err(BondRowsError::ReferenceVolumes {
                given: vol0.len(),
                particles: self.particles,
            });
        }
        for p in changed {
            for &e in &self.incidence[self.offsets[p]..self.offsets[p + 1]] {
                let row = (e & !AS_J) as usize;
                let (i, j) = (self.i[row] as usize, self.j[row] as usize);
                self.inv_v0sum[row] = reciprocal(vol0[i] + vol0[j]);
            }
        }
        Ok(())
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.i.len()
    }

    /// Whether there are no rows.
    pub fn is_empty(&self) -> bool {
        self.i.is_empty()
    }

    /// Number of particles.
    pub fn particles(&self) -> usize {
        self.particles
    }

    /// Particle `p`'s incidence entries, in row order.
    #[inline(always)]
    fn entries(&self, p: usize) -> &[u32] {
        self.incidence().of(p)
    }

    /// Every particle's entries.
    #[inline(always)]
    pub(super) fn incidence(&self) -> Incidence<'_> {
        Incidence {
            offsets: &self.offsets,
            entries: &self.incidence,
        }
    }

    /// `offsets[p]..offsets[p + 1]` are particle `p`'s entries: with
    /// [`crate::engine`]'s balanced ranges, parts of the particles with
    /// about as many bond ends each.
    pub(crate) fn offsets(&self) -> &[usize] {
        &self.offsets
    }

    /// Row `row`'s two particles.
    #[inline(always)]
    pub(super) fn atoms(&self, row: usize) -> (usize, usize) {
        (self.i[row] as usize, self.j[row] as usize)
    }

    /// Row `row`'s reference length.
    #[inline(always)]
    pub(super) fn r0(&self, row: usize) -> f64 {
        self.r0[row]
    }

    /// Row `row`'s `1 / (V0_i + V0_j)` (rows built with reference volumes).
    #[inline(always)]
    pub(super) fn inv_v0sum(&self, row: usize) -> f64 {
        self.inv_v0sum[row]
    }

    /// Each row's bond in the caller's numbering.
    pub fn bonds(&self) -> impl ExactSizeIterator<Item = usize> + '_ {
        self.bond.iter().map(|&b| b as usize)
    }

    /// Checks what a force pass over `range` into `out` rows reads.
    pub(super) fn check_inputs(&self, range: &Range<usize>, out: usize, inputs: &RowInputs) {
        self.check_range(range, out);
        self.check_particles("positions", inputs.x.len());
        if let Some(v) = inputs.v {
            self.check_particles("velocities", v.len());
        }
        if let Some((vol, lengths)) = inputs.multibody {
            self.check_particles("volumes", vol.len());
            assert_eq!(lengths.len(), self.len(), "one length per row");
            assert_eq!(
                self.inv_v0sum.len(),
                self.len(),
                "the multibody term needs rows built with reference volumes"
            );
        }
    }

    fn check_range(&self, range: &Range<usize>, out: usize) {
        assert!(
            range.start <= range.end && range.end <= self.len() && out == range.len(),
            "rows {range:?} of {} into {out} outputs",
            self.len()
        );
    }

    fn check_particles(&self, what: &str, len: usize) {
        assert_eq!(len, self.particles, "{what} of {len} particles");
    }
}

/// `values` without the entries `doomed` (increasing, all below its
/// length, or `values` empty), in order.
pub(super) fn drop_rows<T: Copy>(values: &mut Vec<T>, doomed: &[usize]) {
    let (Some(&first), false) = (doomed.first(), values.is_empty()) else {
        return;
    };
    // The runs between doomed entries move down whole (a memmove each).
    let mut write = first;
    for (k, &gone) in doomed.iter().enumerate() {
        let next = doomed.get(k + 1).copied().unwrap_or(values.len());
        values.copy_within(gone + 1..next, write);
        write += next - gone - 1;
    }
    values.truncate(write);
}

/// Each particle's entries, compressed: particle `p`'s at
/// `offsets[p]..offsets[p + 1]`, each a row (or a slot holding it) with
/// [`AS_J`] set where the particle is the row's `j`, in row order.
#[derive(Clone, Copy, Debug)]
pub(super) struct Incidence<'a> {
    pub(super) offsets: &'a [usize],
    pub(super) entries: &'a [u32],
}

impl<'a> Incidence<'a> {
    /// Particle `p`'s entries.
    #[inline(always)]
    pub(super) fn of(&self, p: usize) -> &'a [u32] {
        &self.entries[self.offsets[p]..self.offsets[p + 1]]
    }
}

/// What the force rows read besides the layout.
#[derive(Clone, Copy, Debug)]
pub struct RowInputs<'a> {
    /// Positions.
    pub x: &'a [[f64; 3]],
    /// Velocities; `None` drops the damping term.
    pub v: Option<&'a [[f64; 3]]>,
    /// The coefficients (one bond type).
    pub coeffs: BondCoeffs,
    /// The multibody term's current volumes `V` per particle and the
    /// rows' lengths and `r^3` from [`row_volumes`] on the same positions
    /// (the lengths are not computed again); `None` drops the term. Needs
    /// rows built with reference volumes.
    pub multibody: Option<(&'a [f64], &'a [[f64; 2]])>,
    /// Whether to sum energy and virial.
    pub tally: bool,
}

/// Writes `[r, r^3]` of rows `range` into `out` (one entry per row of the
/// range), with `sep` forming the separations.
pub fn row_volumes<S: Separation>(
    sep: &S,
    rows: &BondRows,
    range: Range<usize>,
    x: &[[f64; 3]],
    out: &mut [[f64; 2]],
) {
    row_volumes_on(Isa::detect(), sep, rows, range, x, out)
}

/// [`row_volumes`] compiled for `isa` (the portable build when this
/// processor lacks it); every build gives the same values bit for bit.
pub fn row_volumes_on<S: Separation>(
    isa: Isa,
    sep: &S,
    rows: &BondRows,
    range: Range<usize>,
    x: &[[f64; 3]],
    out: &mut [[f64; 2]],
) {
    rows.check_range(&range, out.len());
    rows.check_particles("positions", x.len());
    #[cfg(target_arch = "x86_64")]
    if isa == Isa::Avx2 && Isa::Avx2.available() {
        // SAFETY: the processor has AVX2; indices were checked by the
        // layout and lengths just above.
        return unsafe { avx2::row_volumes(sep, rows, range, x, out) };
    }
    let _ = isa;
    for (out, row) in out.iter_mut().zip(range) {
        *out = scalar_length(sep, rows, row, x);
    }
}

/// `[r, r^3]` of one row.
#[inline(always)]
fn scalar_length<S: Separation>(sep: &S, rows: &BondRows, row: usize, x: &[[f64; 3]]) -> [f64; 2] {
    let del = sep.delta(&x[rows.i[row] as usize], &x[rows.j[row] as usize]);
    let rsq = del[0] * del[0] + del[1] * del[1] + del[2] * del[2];
    let r = rsq.sqrt();
    [r, rsq * r]
}

/// Writes each bond's force on its atom `i` into its row (`[fx, fy, fz,
/// 0]`, one row of `out` per row of `range`); returns energy and virial
/// (summed in four lanes, `LaneTally`), and the first row outside the
/// model's range.
pub fn row_forces<S: Separation>(
    sep: &S,
    rows: &BondRows,
    range: Range<usize>,
    inputs: &RowInputs,
    out: &mut [[f64; 4]],
) -> ForcePass {
    row_forces_on(Isa::detect(), sep, rows, range, inputs, out)
}

/// [`row_forces`] compiled for `isa` (the portable build when this
/// processor lacks it); every build gives the same rows bit for bit.
pub fn row_forces_on<S: Separation>(
    isa: Isa,
    sep: &S,
    rows: &BondRows,
    range: Range<usize>,
    inputs: &RowInputs,
    out: &mut [[f64; 4]],
) -> ForcePass {
    let mut lanes = LaneTally::default();
    row_forces_carried(isa, sep, rows, range, inputs, out, &mut lanes, true)
}

/// [`row_forces_on`] as one piece of a longer range: rows in blocks of four
/// add their energy and virial to `lanes` (row `k` of `range` into lane
/// `k % 4`), carried from the pieces before. The last piece (`last`) adds
/// the lanes up into the returned tally and then its own last rows (fewer
/// than four) one by one; every other piece must hold whole blocks of four
/// and returns no tally. Consecutive pieces then sum what one call over
/// their whole range sums, bit for bit.
#[allow(clippy::too_many_arguments)]
pub(super) fn row_forces_carried<S: Separation>(
    isa: Isa,
    sep: &S,
    rows: &BondRows,
    range: Range<usize>,
    inputs: &RowInputs,
    out: &mut [[f64; 4]],
    lanes: &mut LaneTally,
    last: bool,
) -> ForcePass {
    rows.check_inputs(&range, out.len(), inputs);
    assert!(
        last || range.len() % 4 == 0,
        "a piece of {} rows before the last",
        range.len()
    );
    let flags = (inputs.multibody.is_some(), inputs.v.is_some(), inputs.tally);
    macro_rules! dispatch {
        ($($mb:literal, $damped:literal, $tally:literal);*) => {
            match flags {
                $(($mb, $damped, $tally) => forces_on::<S, $mb, $damped, $tally>(
                    isa, sep, rows, range, inputs, out, lanes, last,
                ),)*
            }
        };
    }
    dispatch!(
        true, true, true; true, true, false; true, false, true; true, false, false;
        false, true, true; false, true, false; false, false, true; false, false, false
    )
}

#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn forces_on<S: Separation, const MB: bool, const DAMPED: bool, const TALLY: bool>(
    isa: Isa,
    sep: &S,
    rows: &BondRows,
    range: Range<usize>,
    inputs: &RowInputs,
    out: &mut [[f64; 4]],
    lanes: &mut LaneTally,
    last: bool,
) -> ForcePass {
    let full = range.len() / 4 * 4;
    let mut pass = ForcePass {
        fault: blocks_of_four::<S, MB, DAMPED, TALLY>(
            isa,
            sep,
            rows,
            range.start..range.start + full,
            inputs,
            &mut out[..full],
            lanes,
        ),
        ..ForcePass::default()
    };
    if !last {
        return pass;
    }
    if TALLY {
        pass.tally = lanes.total();
    }
    for (k, out) in out.iter_mut().enumerate().skip(full) {
        let row = range.start + k;
        let force = scalar_row::<S, MB, DAMPED>(sep, rows, row, inputs);
        settle_row::<TALLY>(rows, row, &force, &mut pass, out);
    }
    pass
}

/// Rows `range` (whole blocks of four) into `out`, their energy and virial
/// added to `lanes` (`TALLY`); returns the first row out of range.
#[inline(always)]
fn blocks_of_four<S: Separation, const MB: bool, const DAMPED: bool, const TALLY: bool>(
    isa: Isa,
    sep: &S,
    rows: &BondRows,
    range: Range<usize>,
    inputs: &RowInputs,
    out: &mut [[f64; 4]],
    lanes: &mut LaneTally,
) -> Option<Fault> {
    #[cfg(target_arch = "x86_64")]
    if isa == Isa::Avx2 && Isa::Avx2.available() {
        // SAFETY: the processor has AVX2; indices were checked by the
        // layout and lengths by the caller.
        return unsafe {
            avx2::row_forces::<S, MB, DAMPED, TALLY>(sep, rows, range, inputs, out, lanes)
        };
    }
    let _ = isa;
    let mut pass = ForcePass::default();
    for (k, out) in out.iter_mut().enumerate() {
        let row = range.start + k;
        let force = scalar_row::<S, MB, DAMPED>(sep, rows, row, inputs);
        settle_row::<false>(rows, row, &force, &mut pass, out);
        if TALLY {
            lanes.add(k % 4, &force);
        }
    }
    pass.fault
}

/// Energy and virial of the rows in blocks of four, summed per lane (row
/// `k` of a range into lane `k % 4`) and the lanes added at the end: four
/// independent chains of additions where one would wait on each result.
/// The vector build keeps the same lanes in registers, so both give the
/// same sums; a range's last rows (fewer than four) are added after, one by
/// one.
#[derive(Clone, Debug, Default)]
pub(super) struct LaneTally {
    /// Energy, then the virial `[xx, yy, zz, xy, xz, yz]`, per lane.
    pub(super) sums: [[f64; 4]; 7],
}

impl LaneTally {
    pub(super) fn add(&mut self, lane: usize, force: &RowForce) {
        let RowForce {
            del, fpair, energy, ..
        } = *force;
        let f = [del[0] * fpair, del[1] * fpair, del[2] * fpair];
        let terms = [
            energy,
            f[0] * del[0],
            f[1] * del[1],
            f[2] * del[2],
            f[0] * del[1],
            f[0] * del[2],
            f[1] * del[2],
        ];
        for (sum, term) in self.sums.iter_mut().zip(terms) {
            sum[lane] += term;
        }
    }

    /// The lanes added in order.
    pub(super) fn total(&self) -> Tally {
        let added = |s: &[f64; 4]| ((s[0] + s[1]) + s[2]) + s[3];
        Tally {
            energy: added(&self.sums[0]),
            virial: std::array::from_fn(|c| added(&self.sums[c + 1])),
        }
    }
}

/// One row's force, as the lanes of [`super::bond_forces`] compute it.
pub(super) struct RowForce {
    pub(super) del: [f64; 3],
    pub(super) r: f64,
    pub(super) fpair: f64,
    pub(super) energy: f64,
}

#[inline(always)]
fn scalar_row<S: Separation, const MB: bool, const DAMPED: bool>(
    sep: &S,
    rows: &BondRows,
    row: usize,
    inputs: &RowInputs,
) -> RowForce {
    let (i, j) = (rows.i[row] as usize, rows.j[row] as usize);
    let c = &inputs.coeffs;
    let r0 = rows.r0[row];
    let x = inputs.x;
    let del = sep.delta(&x[i], &x[j]);
    let r = match inputs.multibody {
        Some((_, lengths)) if MB => lengths[row][0],
        _ => (del[0] * del[0] + del[1] * del[1] + del[2] * del[2]).sqrt(),
    };
    let rinv = 1.0 / r;
    let dstretch = r - r0;
    let mut fmag = -c.k * dstretch;
    if MB {
        let vol = inputs.multibody.map_or(&[][..], |m| m.0);
        let q = (vol[i] + vol[j]) * rows.inv_v0sum[row];
        fmag += c.a * (cube_root(q) - r * rows.inv_r0[row]);
    }
    if DAMPED {
        let v = inputs.v.unwrap_or(&[]);
        let dv = [v[i][0] - v[j][0], v[i][1] - v[j][1], v[i][2] - v[j][2]];
        let del_dot_dv = del[0] * dv[0] + del[1] * dv[1] + del[2] * dv[2];
        fmag -= c.gamma * del_dot_dv * rinv;
    }
    RowForce {
        del,
        r,
        fpair: fmag * rinv,
        energy: 0.5 * c.k * dstretch * dstretch,
    }
}

/// Stores a row, tallies it and checks its range, as the scatter does.
#[inline(always)]
fn settle_row<const TALLY: bool>(
    rows: &BondRows,
    row: usize,
    force: &RowForce,
    pass: &mut ForcePass,
    out: &mut [f64; 4],
) {
    settle_checked_row::<TALLY>(rows, row, rows.r0[row], force, pass, out)
}

/// [`settle_row`] checking the length against `rest` (a bond's rest
/// length, which yielding moves away from `r0`).
#[inline(always)]
pub(super) fn settle_checked_row<const TALLY: bool>(
    rows: &BondRows,
    row: usize,
    rest: f64,
    force: &RowForce,
    pass: &mut ForcePass,
    out: &mut [f64; 4],
) {
    let RowForce {
        del,
        r,
        fpair,
        energy,
    } = *force;
    *out = [del[0] * fpair, del[1] * fpair, del[2] * fpair, 0.0];
    if TALLY {
        pass.tally.add(1.0, energy, &del, fpair);
    }
    let in_range =
        r > COLLAPSED_BELOW * rest && r < OVERSTRETCHED_ABOVE * rest && fpair.abs() < f64::INFINITY;
    if !in_range && pass.fault.is_none() {
        pass.fault = Fault::of_bond(
            rows.bond[row] as usize,
            rows.i[row] as usize,
            rows.j[row] as usize,
            r,
            rest,
            fpair,
        );
    }
}

/// How many particles a gather sums side by side (four measured no faster
/// than two on the compaction packing: the gather waits on its loads).
const CHAINS: usize = 2;

/// Calls `take(c, e)` for each incidence entry `e` of each particle
/// `first + c`, `c < CHAINS`, every particle's entries in row order. The
/// particles' entries alternate while all have some left: each particle's
/// sum is one chain of dependent additions, and one chain alone waits on the
/// adder's latency at every entry, where several keep it busy.
#[inline(always)]
fn interleaved_entries(incidence: Incidence, first: usize, mut take: impl FnMut(usize, u32)) {
    let lists: [&[u32]; CHAINS] = std::array::from_fn(|c| incidence.of(first + c));
    let common = lists.iter().map(|l| l.len()).min().unwrap_or(0);
    for m in 0..common {
        for (c, list) in lists.iter().enumerate() {
            // SAFETY: `m` is below every list's length.
            take(c, unsafe { *list.get_unchecked(m) });
        }
    }
    for (c, list) in lists.iter().enumerate() {
        for &e in &list[common..] {
            take(c, e);
        }
    }
}

/// Runs `group(first, values)` on the particles `first..first + CHAINS`
/// of `particles` in turn, then `single(p, value)` on the last few; `out`
/// holds one value per particle.
#[inline(always)]
fn in_groups<T>(
    particles: Range<usize>,
    out: &mut [T],
    mut group: impl FnMut(usize, &mut [T; CHAINS]),
    mut single: impl FnMut(usize, &mut T),
) {
    let mut groups = out.chunks_exact_mut(CHAINS);
    for (k, values) in (&mut groups).enumerate() {
        let values: &mut [T; CHAINS] = values.try_into().expect("chunks of CHAINS");
        group(particles.start + CHAINS * k, values);
    }
    let rest = groups.into_remainder();
    let first = particles.end - rest.len();
    for (k, value) in rest.iter_mut().enumerate() {
        single(first + k, value);
    }
}

/// Adds to `f[p]` for each particle `p` of `particles` (`f` holds exactly
/// those) its rows: `+row` where it is the bond's `i`, `-row` where it is
/// the `j`, in row order.
pub fn gather_forces(
    rows: &BondRows,
    particles: Range<usize>,
    forces: &[[f64; 4]],
    f: &mut [[f64; 3]],
) {
    gather_forces_on(Isa::detect(), rows, particles, forces, f)
}

/// [`gather_forces`] compiled for `isa`; every build gives the same sums.
pub fn gather_forces_on(
    isa: Isa,
    rows: &BondRows,
    particles: Range<usize>,
    forces: &[[f64; 4]],
    f: &mut [[f64; 3]],
) {
    check_gather(rows, &particles, forces.len(), f.len());
    // SAFETY: incidence entries index rows (checked by the layout), and
    // `forces` has one per row (checked above).
    unsafe { gather_rows_on(isa, rows.incidence(), particles, forces, f) }
}

/// Adds to `f[p]` for each particle `p` of `particles` (`f` holds exactly
/// those) the rows of `forces` its `incidence` entries name, `+row` where
/// it is the bond's `i` and `-row` where it is the `j`, in entry order.
///
/// # Safety
/// Every entry of the particles names a row of `forces`.
#[inline(always)]
pub(super) unsafe fn gather_rows_on(
    isa: Isa,
    incidence: Incidence,
    particles: Range<usize>,
    forces: &[[f64; 4]],
    f: &mut [[f64; 3]],
) {
    #[cfg(target_arch = "x86_64")]
    if isa == Isa::Avx2 && Isa::Avx2.available() {
        // SAFETY: the processor has AVX2; the slots, the caller's contract.
        return avx2::gather_forces(incidence, particles, forces, f);
    }
    let _ = isa;
    for (p, fp) in particles.zip(f.iter_mut()) {
        for &e in incidence.of(p) {
            let row = forces.get_unchecked((e & !AS_J) as usize);
            if e & AS_J == 0 {
                fp[0] += row[0];
                fp[1] += row[1];
                fp[2] += row[2];
            } else {
                fp[0] -= row[0];
                fp[1] -= row[1];
                fp[2] -= row[2];
            }
        }
    }
}

/// Sets `vol[p]` for each particle `p` of `particles` (`vol` holds exactly
/// those) to the sum of its rows' `r^3` (the second of each row's
/// `[r, r^3]` from [`row_volumes`]), in row order.
pub fn gather_volumes(
    rows: &BondRows,
    particles: Range<usize>,
    lengths: &[[f64; 2]],
    vol: &mut [f64],
) {
    check_gather(rows, &particles, lengths.len(), vol.len());
    // SAFETY: incidence entries index rows (checked by the layout), and
    // `lengths` has one per row (checked above).
    let term = |e: u32| unsafe { lengths.get_unchecked((e & !AS_J) as usize)[1] };
    gather_by_particle(rows, particles, vol, term);
}

/// Sets `out[p]` for each particle `p` of `particles` (`out` holds exactly
/// those) to the sum of `term(entry)` over its incidence entries, from 0
/// in row order, a few particles side by side.
#[inline(always)]
pub(super) fn gather_by_particle(
    rows: &BondRows,
    particles: Range<usize>,
    out: &mut [f64],
    term: impl Fn(u32) -> f64,
) {
    in_groups(
        particles,
        out,
        |first, out| {
            let mut sums = [0.0; CHAINS];
            interleaved_entries(rows.incidence(), first, |c, e| sums[c] += term(e));
            *out = sums;
        },
        |p, out| *out = rows.entries(p).iter().fold(0.0, |s, &e| s + term(e)),
    );
}

fn check_gather(rows: &BondRows, particles: &Range<usize>, values: usize, out: usize) {
    assert!(
        particles.start <= particles.end
            && particles.end <= rows.particles
            && out == particles.len()
            && values == rows.len(),
        "gather of particles {particles:?} of {} from {values} rows of {} into {out}",
        rows.particles,
        rows.len()
    );
}

#[cfg(target_arch = "x86_64")]
// Lane loops index several per-lane arrays at once.
#[allow(clippy::needless_range_loop)]
pub(super) mod avx2 {
    //! Four rows at a time. Positions and velocities are loaded as rows
    //! `[x, y, z, -]` (a masked load: the fourth lane is not read), the
    //! differences formed row-wise and turned into lanes of x, y and z by a
    //! 4x4 transpose; the force rows are turned back the same way.

    use super::super::geometry::{MinimumImage, ROUNDING_MAGIC};
    use super::*;
    use std::arch::x86_64::*;

    #[target_feature(enable = "avx2")]
    #[inline]
    unsafe fn load_row(p: *const [f64; 3]) -> __m256d {
        _mm256_maskload_pd(p as *const f64, _mm256_setr_epi64x(-1, -1, -1, 0))
    }

    /// `[x, y, z, -]` rows to lanes of x, y and z.
    #[target_feature(enable = "avx2")]
    #[inline]
    unsafe fn to_lanes(r0: __m256d, r1: __m256d, r2: __m256d, r3: __m256d) -> [__m256d; 3] {
        let xz01 = _mm256_unpacklo_pd(r0, r1);
        let yw01 = _mm256_unpackhi_pd(r0, r1);
        let xz23 = _mm256_unpacklo_pd(r2, r3);
        let yw23 = _mm256_unpackhi_pd(r2, r3);
        [
            _mm256_permute2f128_pd(xz01, xz23, 0x20),
            _mm256_permute2f128_pd(yw01, yw23, 0x20),
            _mm256_permute2f128_pd(xz01, xz23, 0x31),
        ]
    }

    /// Lanes of x, y and z to `[x, y, z, 0]` rows.
    #[target_feature(enable = "avx2")]
    #[inline]
    pub(in crate::kernels) unsafe fn to_rows(x: __m256d, y: __m256d, z: __m256d) -> [__m256d; 4] {
        to_rows_with(x, y, z, _mm256_setzero_pd())
    }

    /// Lanes of x, y, z and w to `[x, y, z, w]` rows.
    #[target_feature(enable = "avx2")]
    #[inline]
    pub(in crate::kernels) unsafe fn to_rows_with(
        x: __m256d,
        y: __m256d,
        z: __m256d,
        w: __m256d,
    ) -> [__m256d; 4] {
        let xy02 = _mm256_unpacklo_pd(x, y);
        let xy13 = _mm256_unpackhi_pd(x, y);
        let z02 = _mm256_unpacklo_pd(z, w);
        let z13 = _mm256_unpackhi_pd(z, w);
        [
            _mm256_permute2f128_pd(xy02, z02, 0x20),
            _mm256_permute2f128_pd(xy13, z13, 0x20),
            _mm256_permute2f128_pd(xy02, z02, 0x31),
            _mm256_permute2f128_pd(xy13, z13, 0x31),
        ]
    }

    /// `a[i] - a[j]` for the four rows' atoms, as lanes.
    #[target_feature(enable = "avx2")]
    #[inline]
    pub(in crate::kernels) unsafe fn differences(
        a: &[[f64; 3]],
        i: &[u32],
        j: &[u32],
    ) -> [__m256d; 3] {
        let p = a.as_ptr();
        let mut d = [_mm256_setzero_pd(); 4];
        for (l, d) in d.iter_mut().enumerate() {
            *d = _mm256_sub_pd(
                load_row(p.add(*i.get_unchecked(l) as usize)),
                load_row(p.add(*j.get_unchecked(l) as usize)),
            );
        }
        to_lanes(d[0], d[1], d[2], d[3])
    }

    /// A minimum-image convention broadcast to lanes.
    pub(in crate::kernels) struct LaneImage {
        lengths: [__m256d; 3],
        tilt: [__m256d; 3],
        inv: [__m256d; 3],
        magic: __m256d,
    }

    impl LaneImage {
        #[target_feature(enable = "avx2")]
        pub(in crate::kernels) unsafe fn new(image: &MinimumImage) -> Self {
            let lanes = |v: [f64; 3]| v.map(|c| _mm256_set1_pd(c));
            Self {
                lengths: lanes(image.lengths),
                tilt: lanes(image.tilt),
                inv: lanes(image.inv),
                magic: _mm256_set1_pd(ROUNDING_MAGIC),
            }
        }

        /// [`MinimumImage::delta_image`]'s operations, in its order, on
        /// four differences at once: the same separations bit for bit.
        #[target_feature(enable = "avx2")]
        #[inline]
        unsafe fn apply(&self, [mut dx, mut dy, mut dz]: [__m256d; 3]) -> [__m256d; 3] {
            let round = |v| _mm256_sub_pd(_mm256_add_pd(v, self.magic), self.magic);
            let shift = |v, k, length| _mm256_sub_pd(v, _mm256_mul_pd(k, length));
            let [lx, ly, lz] = self.lengths;
            let [xy, xz, yz] = self.tilt;
            let kz = round(_mm256_mul_pd(dz, self.inv[2]));
            dz = shift(dz, kz, lz);
            dy = shift(dy, kz, yz);
            dx = shift(dx, kz, xz);
            let ky = round(_mm256_mul_pd(dy, self.inv[1]));
            dy = shift(dy, ky, ly);
            dx = shift(dx, ky, xy);
            let kx = round(_mm256_mul_pd(dx, self.inv[0]));
            dx = shift(dx, kx, lx);
            [dx, dy, dz]
        }
    }

    /// The separations of four rows, as lanes: formed in vector registers
    /// when `image` holds the separation's minimum-image convention.
    #[target_feature(enable = "avx2")]
    #[inline]
    pub(in crate::kernels) unsafe fn separations<S: Separation>(
        sep: &S,
        image: Option<&LaneImage>,
        x: &[[f64; 3]],
        i: &[u32],
        j: &[u32],
    ) -> [__m256d; 3] {
        if S::PLAIN {
            return differences(x, i, j);
        }
        if let Some(image) = image {
            return image.apply(differences(x, i, j));
        }
        let mut d = [[0.0; 3]; 4];
        for (l, d) in d.iter_mut().enumerate() {
            *d = sep.delta(
                x.get_unchecked(*i.get_unchecked(l) as usize),
                x.get_unchecked(*j.get_unchecked(l) as usize),
            );
        }
        [
            _mm256_setr_pd(d[0][0], d[1][0], d[2][0], d[3][0]),
            _mm256_setr_pd(d[0][1], d[1][1], d[2][1], d[3][1]),
            _mm256_setr_pd(d[0][2], d[1][2], d[2][2], d[3][2]),
        ]
    }

    /// How many blocks [`Geometry`] computes ahead without the multibody
    /// term.
    pub(in crate::kernels) const AHEAD_BLOCKS: usize = 16;

    /// The separations and lengths of a pass's blocks of four rows.
    ///
    /// With the multibody term the lengths are the volume pass's, and each
    /// block's separations come as the block is reached. Without it, the
    /// lengths are square roots, and [`AHEAD_BLOCKS`] blocks' worth is
    /// computed ahead of their forces: a block's chain from the positions
    /// through the square root is long, and computed block by block too
    /// few blocks fit in flight to hide it (some 4% of the step at
    /// `a_B = 0`; with the lengths loaded, the buffer cost more than it
    /// saved).
    pub(in crate::kernels) struct Geometry<'a, S: Separation> {
        sep: &'a S,
        image: Option<LaneImage>,
        x: &'a [[f64; 3]],
        row_i: &'a [u32],
        row_j: &'a [u32],
        lengths: &'a [[f64; 2]],
        end: usize,
        // Borrowed, not owned: with the buffer inside, the compiled loop
        // read the other fields from the stack every block (a struct with
        // an array indexed at run time stayed in memory), 1-2% of the
        // step with the multibody term.
        ahead: &'a mut Ahead,
    }

    /// The lanes [`Geometry`] computes ahead: separations and lengths.
    pub(in crate::kernels) type Ahead = [[__m256d; 4]; AHEAD_BLOCKS];

    impl<'a, S: Separation> Geometry<'a, S> {
        /// The geometry of `rows` up to row `end`, with positions `x` and,
        /// with the multibody term, the volume pass's `lengths`; `ahead`
        /// holds the blocks computed ahead.
        ///
        /// # Safety
        /// AVX2.
        #[target_feature(enable = "avx2")]
        pub(in crate::kernels) unsafe fn new(
            sep: &'a S,
            rows: &'a BondRows,
            end: usize,
            x: &'a [[f64; 3]],
            lengths: &'a [[f64; 2]],
            ahead: &'a mut Ahead,
        ) -> Self {
            Self {
                sep,
                image: sep.minimum_image().map(|m| LaneImage::new(m)),
                x,
                row_i: &rows.i,
                row_j: &rows.j,
                lengths,
                end,
                ahead,
            }
        }

        /// The atoms of the block at `row`.
        ///
        /// # Safety
        /// `row + 4 <= end`, within the rows.
        #[inline(always)]
        pub(in crate::kernels) unsafe fn atoms(&self, row: usize) -> (&'a [u32], &'a [u32]) {
            (
                self.row_i.get_unchecked(row..row + 4),
                self.row_j.get_unchecked(row..row + 4),
            )
        }

        /// The separations and lengths of the block at `row`, the
        /// `block`-th of the pass.
        ///
        /// # Safety
        /// AVX2; whole blocks of four up to `end`, within the rows (and
        /// the lengths with `MB`); the atoms within the positions. Every
        /// block taken in order from 0, each row `4 * block` past the
        /// first: the blocks after a multiple of [`AHEAD_BLOCKS`] are read
        /// from what that one computed.
        #[target_feature(enable = "avx2")]
        #[inline]
        pub(in crate::kernels) unsafe fn block<const MB: bool>(
            &mut self,
            row: usize,
            block: usize,
        ) -> ([__m256d; 3], __m256d) {
            if MB {
                let (i, j) = self.atoms(row);
                let del = separations(self.sep, self.image.as_ref(), self.x, i, j);
                return (del, lengths_of(self.lengths.as_ptr().add(row)));
            }
            let slot = block % AHEAD_BLOCKS;
            if slot == 0 {
                for b in 0..AHEAD_BLOCKS {
                    let row = row + 4 * b;
                    if row >= self.end {
                        break;
                    }
                    let (i, j) = self.atoms(row);
                    let del = separations(self.sep, self.image.as_ref(), self.x, i, j);
                    self.ahead[b] = [del[0], del[1], del[2], _mm256_sqrt_pd(dot(&del, &del))];
                }
            }
            let [dx, dy, dz, r] = self.ahead[slot];
            ([dx, dy, dz], r)
        }
    }

    /// The damping term `gamma (del . dv) / r` of a block, from its
    /// separations `del`, `1 / r` and the velocities `v` of atoms `i` and
    /// `j`. Both row passes form it before the spring: its velocities and
    /// their transpose take many registers, and formed after the spring's
    /// values they pushed some of those to the stack (the yielding loop
    /// reloaded `r0` and a separation). The force's sum keeps its order:
    /// spring, multibody term, damping.
    ///
    /// # Safety
    /// AVX2; four atoms in each of `i` and `j`, within `v`.
    #[target_feature(enable = "avx2")]
    #[inline]
    pub(in crate::kernels) unsafe fn damping_term(
        v: &[[f64; 3]],
        i: &[u32],
        j: &[u32],
        del: &[__m256d; 3],
        gamma: __m256d,
        rinv: __m256d,
    ) -> __m256d {
        let del_dot_dv = dot(del, &differences(v, i, j));
        _mm256_mul_pd(_mm256_mul_pd(gamma, del_dot_dv), rinv)
    }

    #[target_feature(enable = "avx2")]
    #[inline]
    pub(in crate::kernels) unsafe fn dot(a: &[__m256d; 3], b: &[__m256d; 3]) -> __m256d {
        _mm256_add_pd(
            _mm256_add_pd(_mm256_mul_pd(a[0], b[0]), _mm256_mul_pd(a[1], b[1])),
            _mm256_mul_pd(a[2], b[2]),
        )
    }

    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn row_volumes<S: Separation>(
        sep: &S,
        rows: &BondRows,
        range: Range<usize>,
        x: &[[f64; 3]],
        out: &mut [[f64; 2]],
    ) {
        let image = sep.minimum_image().map(|m| LaneImage::new(m));
        let full = range.len() / 4 * 4;
        for k in (0..full).step_by(4) {
            let row = range.start + k;
            let (i, j) = (&rows.i[row..row + 4], &rows.j[row..row + 4]);
            let del = separations(sep, image.as_ref(), x, i, j);
            let rsq = dot(&del, &del);
            let r = _mm256_sqrt_pd(rsq);
            let r3 = _mm256_mul_pd(rsq, r);
            // Lanes to [r, r^3] pairs: rows 0, 1 then rows 2, 3.
            let (even, odd) = (_mm256_unpacklo_pd(r, r3), _mm256_unpackhi_pd(r, r3));
            let dst = out.as_mut_ptr().add(k) as *mut f64;
            _mm256_storeu_pd(dst, _mm256_permute2f128_pd(even, odd, 0x20));
            _mm256_storeu_pd(dst.add(4), _mm256_permute2f128_pd(even, odd, 0x31));
        }
        for k in full..range.len() {
            out[k] = scalar_length(sep, rows, range.start + k, x);
        }
    }

    /// The lengths of four rows from their `[r, r^3]` pairs, as lanes.
    #[target_feature(enable = "avx2")]
    #[inline]
    pub(in crate::kernels) unsafe fn lengths_of(pairs: *const [f64; 2]) -> __m256d {
        let p = pairs as *const f64;
        let (rows01, rows23) = (_mm256_loadu_pd(p), _mm256_loadu_pd(p.add(4)));
        // [r0, r2, r1, r3] in lane order 0, 1, 2, 3, then put in place.
        let mixed = _mm256_unpacklo_pd(rows01, rows23);
        _mm256_permute4x64_pd::<0b11_01_10_00>(mixed)
    }

    /// The series of `(1 + x)^(1/3)` of [`super::super::bond`], lane by
    /// lane: to degree 7 (the start of the Halley step beyond `1/32`), and
    /// to degree 9 (exact to round-off for `|x| <= 1/32`).
    #[target_feature(enable = "avx2")]
    #[inline]
    unsafe fn cube_root_series(x: __m256d) -> (__m256d, __m256d) {
        use crate::kernels::bond::CBRT_SERIES as C;
        // c0 + c1 x for the coefficients k, k + 1.
        macro_rules! pair {
            ($k:expr) => {
                _mm256_add_pd(
                    _mm256_set1_pd(C[$k]),
                    _mm256_mul_pd(_mm256_set1_pd(C[$k + 1]), x),
                )
            };
        }
        let x2 = _mm256_mul_pd(x, x);
        let x4 = _mm256_mul_pd(x2, x2);
        let low = _mm256_add_pd(pair!(0), _mm256_mul_pd(x2, pair!(2)));
        let high = _mm256_add_pd(pair!(4), _mm256_mul_pd(x2, pair!(6)));
        let degree_7 = _mm256_add_pd(low, _mm256_mul_pd(x4, high));
        let degree_9 = _mm256_add_pd(degree_7, _mm256_mul_pd(_mm256_mul_pd(x4, x4), pair!(8)));
        (degree_7, degree_9)
    }

    /// One Halley step towards the cube root of `q` from `y`, lane by lane,
    /// in the scalar step's order of operations (the same bits).
    #[target_feature(enable = "avx2")]
    #[inline]
    unsafe fn halley_cbrt_step(y: __m256d, q: __m256d) -> __m256d {
        let two = _mm256_set1_pd(2.0);
        let y3 = _mm256_mul_pd(_mm256_mul_pd(y, y), y);
        _mm256_div_pd(
            _mm256_mul_pd(y, _mm256_add_pd(y3, _mm256_mul_pd(two, q))),
            _mm256_add_pd(_mm256_mul_pd(two, y3), q),
        )
    }

    /// [`cube_root`] of four ratios `q` (`xq = q - 1`), the same bits lane
    /// by lane for every non-NaN `q` (a NaN lane takes the series and stays
    /// NaN, as before, where the scalar routine returns its own NaN): the
    /// degree-9 series where `|xq| <= 1/32`, else the degree-7 series and a
    /// Halley step where `|xq| <= 1/4` (a squeeze of a few percent puts a
    /// fraction of the bonds there, scattered over the blocks, so all four
    /// lanes take the step together rather than branch lane by lane), and
    /// the scalar routine for the rare rest.
    #[target_feature(enable = "avx2")]
    #[inline]
    pub(in crate::kernels) unsafe fn cube_roots(q: __m256d, xq: __m256d) -> __m256d {
        let magnitude = _mm256_and_pd(xq, _mm256_castsi256_pd(_mm256_set1_epi64x(i64::MAX)));
        let (degree_7, degree_9) = cube_root_series(xq);
        let far = _mm256_cmp_pd::<_CMP_GT_OQ>(magnitude, _mm256_set1_pd(CLOSE_TO_ONE));
        if _mm256_movemask_pd(far) == 0 {
            return degree_9;
        }
        let stepped = halley_cbrt_step(degree_7, q);
        let roots = _mm256_blendv_pd(degree_9, stepped, far);
        let beyond = _mm256_movemask_pd(_mm256_cmp_pd::<_CMP_GT_OQ>(
            magnitude,
            _mm256_set1_pd(SERIES_AND_STEP_UP_TO),
        ));
        if beyond == 0 {
            return roots;
        }
        let (mut lanes, mut qs) = ([0.0; 4], [0.0; 4]);
        _mm256_storeu_pd(lanes.as_mut_ptr(), roots);
        _mm256_storeu_pd(qs.as_mut_ptr(), q);
        for l in 0..4 {
            if beyond & (1 << l) != 0 {
                lanes[l] = cube_root(qs[l]);
            }
        }
        _mm256_loadu_pd(lanes.as_ptr())
    }

    /// Rows `range`, whole blocks of four, into `out`.
    ///
    /// # Safety
    /// The processor has AVX2; `range` lies within the layout's rows and
    /// holds whole blocks of four; `out` holds `range.len()` rows; `inputs`
    /// hold every atom the rows name and a length per row with the
    /// multibody term ([`BondRows::check_inputs`] checks these); and `MB`
    /// and `DAMPED` are set only when `inputs` carry the multibody term and
    /// the velocities (as the dispatch sets them). The loop indexes
    /// unchecked.
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn row_forces<
        S: Separation,
        const MB: bool,
        const DAMPED: bool,
        const TALLY: bool,
    >(
        sep: &S,
        rows: &BondRows,
        range: Range<usize>,
        inputs: &RowInputs,
        out: &mut [[f64; 4]],
        lanes: &mut LaneTally,
    ) -> Option<Fault> {
        debug_assert!(range.len() % 4 == 0 && out.len() == range.len());
        debug_assert!((!MB || inputs.multibody.is_some()) && (!DAMPED || inputs.v.is_some()));
        // Everything the loop reads, in locals: the rows are written
        // through raw pointers, which the compiler must otherwise assume
        // may alias the inputs and the layout, reloading them every block.
        let (r0s, inv_r0s, inv_v0sums) = (&rows.r0[..], &rows.inv_r0[..], &rows.inv_v0sum[..]);
        let v = inputs.v.unwrap_or(&[]);
        let (vol, lengths) = inputs.multibody.unwrap_or((&[], &[]));
        let mut ahead = [[_mm256_setzero_pd(); 4]; AHEAD_BLOCKS];
        let mut geometry = Geometry::new(sep, rows, range.end, inputs.x, lengths, &mut ahead);
        let c = &inputs.coeffs;
        let (neg_k, a, gamma, half_k) = (
            _mm256_set1_pd(-c.k),
            _mm256_set1_pd(c.a),
            _mm256_set1_pd(c.gamma),
            _mm256_set1_pd(0.5 * c.k),
        );
        let one = _mm256_set1_pd(1.0);
        // The first row out of range, found after the loop: a search in
        // the loop would be inlined there, crowding its registers.
        let mut first_rejected = None;
        let full = range.len();
        let mut sums = [_mm256_setzero_pd(); 7];
        if TALLY {
            for (sum, lane) in sums.iter_mut().zip(&lanes.sums) {
                *sum = _mm256_loadu_pd(lane.as_ptr());
            }
        }
        for k in (0..full).step_by(4) {
            let row = range.start + k;
            // In bounds: the caller checked the range against the layout
            // and the outputs, and the lengths against the rows.
            let (i, j) = geometry.atoms(row);
            let (del, r) = geometry.block::<MB>(row, k / 4);
            let r0 = _mm256_loadu_pd(r0s.as_ptr().add(row));
            let rinv = _mm256_div_pd(one, r);
            // The damping term first (damping_term says why).
            let damping = if DAMPED {
                damping_term(v, i, j, &del, gamma, rinv)
            } else {
                _mm256_setzero_pd()
            };
            let dstretch = _mm256_sub_pd(r, r0);
            let mut fmag = _mm256_mul_pd(neg_k, dstretch);
            if MB {
                let idx_i = _mm_loadu_si128(i.as_ptr() as *const __m128i);
                let idx_j = _mm_loadu_si128(j.as_ptr() as *const __m128i);
                let vsum = _mm256_add_pd(
                    _mm256_i32gather_pd::<8>(vol.as_ptr(), idx_i),
                    _mm256_i32gather_pd::<8>(vol.as_ptr(), idx_j),
                );
                let inv_v0sum = _mm256_loadu_pd(inv_v0sums.as_ptr().add(row));
                let q = _mm256_mul_pd(vsum, inv_v0sum);
                let xq = _mm256_sub_pd(q, one);
                let dilation = cube_roots(q, xq);
                let inv_r0 = _mm256_loadu_pd(inv_r0s.as_ptr().add(row));
                fmag = _mm256_add_pd(
                    fmag,
                    _mm256_mul_pd(a, _mm256_sub_pd(dilation, _mm256_mul_pd(r, inv_r0))),
                );
            }
            if DAMPED {
                fmag = _mm256_sub_pd(fmag, damping);
            }
            let fpair = _mm256_mul_pd(fmag, rinv);
            let force = [
                _mm256_mul_pd(del[0], fpair),
                _mm256_mul_pd(del[1], fpair),
                _mm256_mul_pd(del[2], fpair),
            ];
            let force_rows = to_rows(force[0], force[1], force[2]);
            let dst = out.as_mut_ptr().add(k) as *mut f64;
            for (l, fr) in force_rows.into_iter().enumerate() {
                _mm256_storeu_pd(dst.add(4 * l), fr);
            }
            if TALLY {
                let energy = _mm256_mul_pd(_mm256_mul_pd(half_k, dstretch), dstretch);
                for (sum, term) in sums.iter_mut().zip(tally_terms(energy, &force, &del)) {
                    *sum = _mm256_add_pd(*sum, term);
                }
            }
            let rejected = !_mm256_movemask_pd(in_range(r, r0, fpair)) & 0b1111;
            if rejected != 0 {
                note_rejected(&mut first_rejected, k, rejected);
            }
        }
        if TALLY {
            for (sum, lane) in sums.iter().zip(lanes.sums.iter_mut()) {
                _mm256_storeu_pd(lane.as_mut_ptr(), *sum);
            }
        }
        // The lanes' test rejects a length exactly at a limit, which is no
        // fault (as on the portable build): scan on to the first that is.
        first_rejected.and_then(|first| {
            (range.start + first..range.end)
                .find_map(|row| scalar_fault::<S, MB, DAMPED>(sep, rows, row, inputs))
        })
    }

    /// Keeps the first row the lanes' range test rejects (`rejected`, a
    /// lane mask of the block at `block`): out of line, so that the loop
    /// tests one mask and jumps rarely instead of updating the record
    /// every block.
    #[cold]
    #[inline(never)]
    pub(in crate::kernels) fn note_rejected(
        first: &mut Option<usize>,
        block: usize,
        rejected: i32,
    ) {
        first.get_or_insert(block + rejected.trailing_zeros() as usize);
    }

    /// The fault of row `row` as the portable build finds it.
    #[cold]
    #[inline(never)]
    fn scalar_fault<S: Separation, const MB: bool, const DAMPED: bool>(
        sep: &S,
        rows: &BondRows,
        row: usize,
        inputs: &RowInputs,
    ) -> Option<Fault> {
        let force = scalar_row::<S, MB, DAMPED>(sep, rows, row, inputs);
        let mut probe = ForcePass::default();
        settle_row::<false>(rows, row, &force, &mut probe, &mut [0.0; 4]);
        probe.fault
    }

    /// A block's energy and virial terms, in [`LaneTally`]'s order.
    #[target_feature(enable = "avx2")]
    #[inline]
    pub(in crate::kernels) unsafe fn tally_terms(
        energy: __m256d,
        force: &[__m256d; 3],
        del: &[__m256d; 3],
    ) -> [__m256d; 7] {
        [
            energy,
            _mm256_mul_pd(force[0], del[0]),
            _mm256_mul_pd(force[1], del[1]),
            _mm256_mul_pd(force[2], del[2]),
            _mm256_mul_pd(force[0], del[1]),
            _mm256_mul_pd(force[0], del[2]),
            _mm256_mul_pd(force[1], del[2]),
        ]
    }

    /// Lanes whose length `r` lies between [`COLLAPSED_BELOW`] and
    /// [`OVERSTRETCHED_ABOVE`] times `reference` and whose `fpair` is
    /// finite: the fault check of [`super::settle_checked_row`].
    #[target_feature(enable = "avx2")]
    #[inline]
    pub(in crate::kernels) unsafe fn in_range(
        r: __m256d,
        reference: __m256d,
        fpair: __m256d,
    ) -> __m256d {
        let magnitude = _mm256_castsi256_pd(_mm256_set1_epi64x(i64::MAX));
        _mm256_and_pd(
            _mm256_and_pd(
                _mm256_cmp_pd::<_CMP_GT_OQ>(
                    r,
                    _mm256_mul_pd(_mm256_set1_pd(COLLAPSED_BELOW), reference),
                ),
                _mm256_cmp_pd::<_CMP_LT_OQ>(
                    r,
                    _mm256_mul_pd(_mm256_set1_pd(OVERSTRETCHED_ABOVE), reference),
                ),
            ),
            _mm256_cmp_pd::<_CMP_LT_OQ>(
                _mm256_and_pd(fpair, magnitude),
                _mm256_set1_pd(f64::INFINITY),
            ),
        )
    }

    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn gather_forces(
        incidence: Incidence,
        particles: Range<usize>,
        forces: &[[f64; 4]],
        f: &mut [[f64; 3]],
    ) {
        let base = forces.as_ptr() as *const f64;
        let term = |e: u32| {
            let row = _mm256_loadu_pd(base.add(4 * (e & !AS_J) as usize));
            let sign = _mm256_castsi256_pd(_mm256_set1_epi64x(((e & AS_J) as i64) << 32));
            _mm256_xor_pd(row, sign)
        };
        let load = |fp: &[f64; 3]| {
            _mm256_insertf128_pd::<1>(
                _mm256_castpd128_pd256(_mm_loadu_pd(fp.as_ptr())),
                _mm_load_sd(fp.as_ptr().add(2)),
            )
        };
        let store = |fp: &mut [f64; 3], sum: __m256d| {
            _mm_storeu_pd(fp.as_mut_ptr(), _mm256_castpd256_pd128(sum));
            _mm_store_sd(fp.as_mut_ptr().add(2), _mm256_extractf128_pd::<1>(sum));
        };
        in_groups(
            particles,
            f,
            |first, out| {
                let mut sums = out.each_ref().map(&load);
                interleaved_entries(incidence, first, |c, e| {
                    sums[c] = _mm256_add_pd(sums[c], term(e));
                });
                for (fp, sum) in out.iter_mut().zip(sums) {
                    store(fp, sum);
                }
            },
            |p, fp| {
                let sum = incidence
                    .of(p)
                    .iter()
                    .fold(load(fp), |sum, &e| _mm256_add_pd(sum, term(e)));
                store(fp, sum);
            },
        );
    }
}
