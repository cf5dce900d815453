//! The contact forces of every listed pair, on the thread team.
//!
//! The half pair list (`j > i`) is split by its rows `i` into the team's
//! chunks, each with about as many list entries
//! ([`NeighbourList::balanced_rows`]). A chunk forms the contacts of its
//! rows, advances their histories (the list entries of its rows: disjoint
//! from every other chunk's) and adds forces and torques into its own
//! buffers, from its first row on ([`Scratch::scatter_many`]); the buffers
//! are then summed in chunk order. One thread adds straight into the outputs in list order;
//! for a fixed number of threads every run gives the same bits.

use super::super::model::ForceInput;
#[cfg(doc)]
use super::super::neighbor::NeighbourList;
use super::super::parallel::{as_rows, as_vec3, Scratch, Vec3};
use super::super::team::SharedSlice;
use crate::kernels::{
    corrected_granular_contact, hertz_mindlin_block, BoxImage, ContactBlock, ContactForce,
    ContactHistory, GranularCoeffs, Isa, Sphere, Tally, CONTACT_LANES,
};
use std::ops::Range;

/// What every chunk of a contact pass reads.
pub(super) struct ContactPass<'a> {
    /// The contact law's coefficients.
    pub coeffs: &'a GranularCoeffs,
    /// The instruction set of the contact blocks.
    pub isa: Isa,
    /// Whether contacts are formed four at a time ([`hertz_mindlin_block`]:
    /// Hertz-Mindlin without rolling or twisting) or one at a time.
    pub blocks: bool,
    /// The box's minimum image.
    pub sep: &'a BoxImage,
    /// The state the forces are evaluated for.
    pub input: &'a ForceInput<'a>,
    /// The closure's corrections of each list entry's two surfaces.
    pub corrections: Option<&'a [[f64; 2]]>,
}

/// Adds the contact force of every touching listed pair to `f` (and its
/// torques to `torque`), advances every touching pair's history in
/// `history` (one per list entry) and clears every other's; returns the
/// virial when the input asks for it.
pub(super) fn contact_forces(
    pass: &ContactPass<'_>,
    history: &mut [ContactHistory],
    scratch: &mut Scratch<Vec3>,
    f: &mut [[f64; 3]],
    torque: Option<&mut [[f64; 3]]>,
) -> Tally {
    let input = pass.input;
    let (team, list) = (input.team, input.neighbours);
    let chunks = team.threads();
    let history = SharedSlice::new(history);
    // An empty torque array stands for none, so that both arrays go
    // through one scatter.
    let torque = torque.unwrap_or(&mut []);
    let first = |c| list.balanced_rows(chunks, c).start;
    scratch.scatter_many(
        team,
        [as_vec3(f), as_vec3(torque)],
        first,
        Tally::default(),
        |c, [f, torque]| {
            let rows = list.balanced_rows(chunks, c);
            let entries = list.entries(rows.clone());
            // SAFETY: the chunks' rows, and so their list entries, are
            // disjoint.
            let history = Section {
                first: entries.start,
                history: unsafe { history.range(entries) },
            };
            let torque = (!torque.is_empty()).then_some(as_rows(torque));
            if pass.blocks {
                pass.in_blocks(rows, history, as_rows(f), torque)
            } else {
                pass.one_by_one(rows, history, as_rows(f), torque)
            }
        },
        |a, b| a.merged(&b),
    )
}

/// The histories of a chunk's list entries, from entry `first` on.
struct Section<'a> {
    first: usize,
    history: &'a mut [ContactHistory],
}

impl Section<'_> {
    #[inline(always)]
    fn entry(&mut self, k: usize) -> &mut ContactHistory {
        &mut self.history[k - self.first]
    }
}

impl ContactPass<'_> {
    /// The contacts of `rows`, touching pairs gathered four at a time into
    /// [`hertz_mindlin_block`]: the same forces, torques and histories as
    /// one pair at a time, bit for bit, added in the same order.
    fn in_blocks(
        &self,
        rows: Range<usize>,
        mut history: Section<'_>,
        f: &mut [[f64; 3]],
        torque: Option<&mut [[f64; 3]]>,
    ) -> Tally {
        let input = self.input;
        let omega = input.omega.unwrap_or(&[]);
        let (v, radius, mass) = (input.v, input.radius, input.mass);
        let (dt, update) = input.history_step();
        let mut tally = Tally::default();
        let mut block = ContactBlock::default();
        // Each lane's pair (i, j) and list entry.
        let mut pairs = [(0usize, 0usize, 0usize); CONTACT_LANES];
        let mut filled = 0;
        let mut sink = BlockSink {
            isa: self.isa,
            coeffs: self.coeffs,
            dt,
            update,
            f,
            torque,
            tally: input.tally.then_some(&mut tally),
        };
        let spin = |i: usize| omega.get(i).copied().unwrap_or([0.0; 3]);
        self.touching_pairs(rows, &mut history, |pair, history| {
            let TouchingPair {
                i,
                j,
                entry,
                del,
                partner_velocity,
                moved,
            } = pair;
            let (l, wi, wj, h) = (filled, spin(i), spin(j), history.entry(entry).tangential);
            for d in 0..3 {
                block.del[d][l] = del[d];
                block.v[0][d][l] = v[i][d];
                block.v[1][d][l] = partner_velocity[d];
                block.omega[0][d][l] = wi[d];
                block.omega[1][d][l] = wj[d];
                block.tangential[d][l] = h[d];
            }
            for (side, sphere) in [i, j].into_iter().enumerate() {
                block.radius[side][l] = radius[sphere];
                block.mass[side][l] = mass[sphere];
                block.moved[side][l] = moved[side];
            }
            pairs[l] = (i, j, entry);
            filled += 1;
            if filled == CONTACT_LANES {
                sink.flush(&mut block, &pairs, history);
                filled = 0;
            }
        });
        if filled > 0 {
            // The spare lanes repeat the first contact and are not read.
            block.fill_from_first(filled);
            sink.flush(&mut block, &pairs[..filled], &mut history);
        }
        tally
    }

    /// The contacts of `rows` one pair at a time: the law with rolling or
    /// twisting resistance.
    fn one_by_one(
        &self,
        rows: Range<usize>,
        mut history: Section<'_>,
        f: &mut [[f64; 3]],
        mut torque: Option<&mut [[f64; 3]]>,
    ) -> Tally {
        let input = self.input;
        // The engine gives rotational models angular velocities; without
        // them (a caller's choice) spheres count as not spinning.
        let omega = input.omega.unwrap_or(&[]);
        let (v, radius, mass) = (input.v, input.radius, input.mass);
        let (dt, update) = input.history_step();
        let mut tally = Tally::default();
        let sphere = |i: usize| Sphere {
            v: v[i],
            omega: omega.get(i).copied().unwrap_or([0.0; 3]),
            radius: radius[i],
            mass: mass[i],
        };
        self.touching_pairs(rows, &mut history, |pair, history| {
            let (i, j) = (pair.i, pair.j);
            let sj = Sphere {
                v: pair.partner_velocity,
                ..sphere(j)
            };
            let ContactForce {
                force,
                torque_i,
                torque_j,
            } = corrected_granular_contact(
                self.coeffs,
                &pair.del,
                &sphere(i),
                &sj,
                pair.moved,
                history.entry(pair.entry),
                dt,
                update,
            );
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
                tally.add_vector(1.0, &pair.del, &force);
            }
        });
        tally
    }

    /// Calls `touch` for every listed pair of `rows` whose surfaces (moved
    /// by the closure's corrections) overlap, in list order, with the
    /// histories; clears the history of every other pair.
    #[inline(always)]
    fn touching_pairs<'h>(
        &self,
        rows: Range<usize>,
        history: &mut Section<'h>,
        mut touch: impl FnMut(TouchingPair, &mut Section<'h>),
    ) {
        let input = self.input;
        let (x, v, radius, list) = (input.x, input.v, input.radius, input.neighbours);
        for i in rows {
            let xi = x[i];
            for k in list.offsets[i]..list.offsets[i + 1] {
                let j = list.neighbours[k] as usize;
                let (del, image) = self.sep.delta_image(&xi, &x[j]);
                let rsq = del[0] * del[0] + del[1] * del[1] + del[2] * del[2];
                let moved = self.corrections.map_or([0.0; 2], |c| c[k]);
                let radsum = (radius[i] + moved[0]) + (radius[j] + moved[1]);
                // A surface moved past its centre (radsum <= 0) is caught
                // by the closure's report; it is no contact here.
                if radsum <= 0.0 || rsq >= radsum * radsum {
                    *history.entry(k) = Default::default();
                    continue;
                }
                let mut partner_velocity = v[j];
                // A partner across a Lees-Edwards face is an image moving
                // with the boundary.
                if let (Some(le), true) = (&input.lees_edwards, image != [0.0; 3]) {
                    for (v, w) in partner_velocity.iter_mut().zip(le.image_velocity(&image)) {
                        *v += w;
                    }
                }
                let pair = TouchingPair {
                    i,
                    j,
                    entry: k,
                    del,
                    partner_velocity,
                    moved,
                };
                touch(pair, history);
            }
        }
    }
}

/// A listed pair whose surfaces overlap.
struct TouchingPair {
    i: usize,
    j: usize,
    /// Its pair-list entry (and contact history).
    entry: usize,
    /// `x_i - x_j`, the minimum image.
    del: [f64; 3],
    /// `j`'s velocity, or its image's across a Lees-Edwards face.
    partner_velocity: [f64; 3],
    /// The closure's corrections of the two surfaces (0 without it).
    moved: [f64; 2],
}

/// Where a block of contacts goes: the forces, torques and virial of the
/// chunk. (Components are added `for d in 0..3` over several arrays.)
struct BlockSink<'a> {
    isa: Isa,
    coeffs: &'a GranularCoeffs,
    dt: f64,
    update: bool,
    f: &'a mut [[f64; 3]],
    torque: Option<&'a mut [[f64; 3]]>,
    tally: Option<&'a mut Tally>,
}

#[allow(clippy::needless_range_loop)]
impl BlockSink<'_> {
    /// Forms `block` and adds the contacts of its first `pairs.len()`
    /// lanes (each `(i, j, list entry)`), in lane order.
    fn flush(
        &mut self,
        block: &mut ContactBlock,
        pairs: &[(usize, usize, usize)],
        history: &mut Section<'_>,
    ) {
        let out = hertz_mindlin_block(self.isa, self.coeffs, block, self.dt, self.update);
        for (l, &(i, j, k)) in pairs.iter().enumerate() {
            let h = history.entry(k);
            h.tangential = std::array::from_fn(|d| block.tangential[d][l]);
            h.normal_force = out.normal_force[l];
            let force: [f64; 3] = std::array::from_fn(|d| out.force[d][l]);
            for d in 0..3 {
                self.f[i][d] += force[d];
                self.f[j][d] -= force[d];
            }
            if let Some(t) = self.torque.as_deref_mut() {
                for d in 0..3 {
                    t[i][d] += out.torque[0][d][l];
                    t[j][d] += out.torque[1][d][l];
                }
            }
            if let Some(tally) = self.tally.as_deref_mut() {
                let del = std::array::from_fn(|d| block.del[d][l]);
                tally.add_vector(1.0, &del, &force);
            }
        }
    }
}
