//! Cell-list Verlet neighbour list with a skin, rebuilt on displacement.
//!
//! Atoms are binned in fractional coordinates with bins at least one
//! list cutoff thick (face to face), so every pair within the cutoff sits in
//! the same or an adjacent bin. The stencil is deduplicated, which keeps
//! boxes of one or two bins per dimension correct under the minimum image.

use super::simbox::SimBox;
use crate::kernels::Separation;

/// Pairs a pair list leaves out: for each particle its sorted partners
/// (both directions), in CSR form. The bonded particle model excludes its
/// bonded pairs, as LAMMPS's `special_bonds lj 0 ...` does.
#[derive(Clone, Debug, Default)]
pub struct Exclusions {
    offsets: Vec<usize>,
    partners: Vec<u32>,
}

impl Exclusions {
    /// Exclusions of the pairs `(i, j)` on `n` particles; indices must be
    /// below `n`.
    pub fn from_pairs(n: usize, pairs: impl Iterator<Item = (usize, usize)> + Clone) -> Self {
        let mut offsets = vec![0usize; n + 1];
        for (i, j) in pairs.clone() {
            offsets[i + 1] += 1;
            offsets[j + 1] += 1;
        }
        for i in 0..n {
            offsets[i + 1] += offsets[i];
        }
        let mut cursor = offsets.clone();
        let mut partners = vec![0u32; offsets[n]];
        for (i, j) in pairs {
            partners[cursor[i]] = j as u32;
            cursor[i] += 1;
            partners[cursor[j]] = i as u32;
            cursor[j] += 1;
        }
        for i in 0..n {
            partners[offsets[i]..offsets[i + 1]].sort_unstable();
        }
        Self { offsets, partners }
    }

    /// Sorted excluded partners of particle `i`.
    pub fn partners(&self, i: usize) -> &[u32] {
        &self.partners[self.offsets[i]..self.offsets[i + 1]]
    }

    /// Whether the pair `(i, j)` is excluded.
    pub fn excludes(&self, i: usize, j: usize) -> bool {
        self.partners(i).binary_search(&(j as u32)).is_ok()
    }
}

/// A half neighbour list (`j > i`) in CSR form.
#[derive(Clone, Debug, Default)]
pub struct NeighbourList {
    /// `offsets[i]..offsets[i + 1]` index the neighbours of atom `i`.
    pub offsets: Vec<usize>,
    /// Neighbour indices.
    pub neighbours: Vec<i32>,
    /// Interaction cutoff plus skin used at the last build.
    pub list_cutoff: f64,
    x_at_build: Vec<[f64; 3]>,
    box_at_build: Option<SimBox>,
    /// How many times the list was built.
    pub builds: u64,
    bin_of: Vec<usize>,
    bin_start: Vec<usize>,
    bin_atoms: Vec<usize>,
}

impl NeighbourList {
    /// Neighbours of atom `i`.
    pub fn of(&self, i: usize) -> &[i32] {
        &self.neighbours[self.offsets[i]..self.offsets[i + 1]]
    }

    /// Iterator over `(i, neighbours of i)` for atoms in `range`.
    pub fn rows(&self, range: std::ops::Range<usize>) -> impl Iterator<Item = (usize, &[i32])> {
        range.map(move |i| (i, self.of(i)))
    }

    /// Whether an atom may have moved into range of one not listed: twice the
    /// largest displacement plus the drift of periodic images exceeds the skin.
    pub fn needs_rebuild(&self, simbox: &SimBox, x: &[[f64; 3]], skin: f64) -> bool {
        let Some(old_box) = &self.box_at_build else {
            return true;
        };
        if self.x_at_build.len() != x.len() {
            return true;
        }
        let mut max_sq: f64 = 0.0;
        for (a, b) in x.iter().zip(&self.x_at_build) {
            let d = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
            max_sq = max_sq.max(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        }
        2.0 * max_sq.sqrt() + simbox.periodic_drift(old_box) > skin
    }

    /// Rebuilds the list for `cutoff + skin`, leaving out the pairs of
    /// `exclude`. Positions must already be wrapped.
    pub fn build(
        &mut self,
        simbox: &SimBox,
        x: &[[f64; 3]],
        cutoff: f64,
        skin: f64,
        exclude: Option<&Exclusions>,
    ) {
        let list_cut = cutoff + skin;
        let cut_sq = list_cut * list_cut;
        let n = x.len();
        let frac: Vec<[f64; 3]> = x.iter().map(|p| simbox.to_fractional(p)).collect();
        let faces = simbox.face_distances();
        let mut lo = [0.0f64; 3];
        let mut span = [1.0f64; 3];
        let mut nbins = [1usize; 3];
        for d in 0..3 {
            if !simbox.periodic[d] {
                let (mn, mx) = frac
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), s| {
                        (a.min(s[d]), b.max(s[d]))
                    });
                lo[d] = if n > 0 { mn } else { 0.0 };
                span[d] = if n > 0 { (mx - mn).max(1e-12) } else { 1.0 };
            }
            let thickness = faces[d] * span[d];
            nbins[d] = ((thickness / list_cut).floor() as usize).clamp(1, 1 << 10);
        }
        let bin_index = |s: &[f64; 3]| -> [usize; 3] {
            let mut b = [0usize; 3];
            for d in 0..3 {
                let t = ((s[d] - lo[d]) / span[d] * nbins[d] as f64).floor();
                let t = if simbox.periodic[d] {
                    t.rem_euclid(nbins[d] as f64)
                } else {
                    t
                };
                b[d] = (t.max(0.0) as usize).min(nbins[d] - 1);
            }
            b
        };
        let flat = |b: [usize; 3]| (b[2] * nbins[1] + b[1]) * nbins[0] + b[0];
        let total_bins = nbins[0] * nbins[1] * nbins[2];

        self.bin_of.clear();
        self.bin_of.extend(frac.iter().map(|s| flat(bin_index(s))));
        self.bin_start.clear();
        self.bin_start.resize(total_bins + 1, 0);
        for &b in &self.bin_of {
            self.bin_start[b + 1] += 1;
        }
        for b in 0..total_bins {
            self.bin_start[b + 1] += self.bin_start[b];
        }
        self.bin_atoms.clear();
        self.bin_atoms.resize(n, 0);
        let mut cursor = self.bin_start.clone();
        for (i, &b) in self.bin_of.iter().enumerate() {
            self.bin_atoms[cursor[b]] = i;
            cursor[b] += 1;
        }

        self.offsets.clear();
        self.offsets.reserve(n + 1);
        self.offsets.push(0);
        self.neighbours.clear();
        let mut stencil: Vec<usize> = Vec::with_capacity(27);
        for i in 0..n {
            let b = bin_index(&frac[i]);
            stencil.clear();
            for dz in -1i64..=1 {
                for dy in -1i64..=1 {
                    for dx in -1i64..=1 {
                        let mut nb = [0usize; 3];
                        let mut inside = true;
                        for (d, off) in [dx, dy, dz].into_iter().enumerate() {
                            let t = b[d] as i64 + off;
                            let m = nbins[d] as i64;
                            if simbox.periodic[d] {
                                nb[d] = t.rem_euclid(m) as usize;
                            } else if (0..m).contains(&t) {
                                nb[d] = t as usize;
                            } else {
                                inside = false;
                            }
                        }
                        if inside {
                            stencil.push(flat(nb));
                        }
                    }
                }
            }
            stencil.sort_unstable();
            stencil.dedup();
            let row_start = self.neighbours.len();
            for &bin in &stencil {
                for &j in &self.bin_atoms[self.bin_start[bin]..self.bin_start[bin + 1]] {
                    if j <= i {
                        continue;
                    }
                    let d = simbox.delta(&x[i], &x[j]);
                    if d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < cut_sq
                        && !exclude.is_some_and(|e| e.excludes(i, j))
                    {
                        self.neighbours.push(j as i32);
                    }
                }
            }
            self.neighbours[row_start..].sort_unstable();
            self.offsets.push(self.neighbours.len());
        }
        self.list_cutoff = list_cut;
        self.x_at_build.clear();
        self.x_at_build.extend_from_slice(x);
        self.box_at_build = Some(simbox.clone());
        self.builds += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    fn brute_force(simbox: &SimBox, x: &[[f64; 3]], cut: f64) -> Vec<(usize, usize)> {
        let mut pairs = Vec::new();
        for i in 0..x.len() {
            for j in i + 1..x.len() {
                let d = simbox.delta(&x[i], &x[j]);
                if d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < cut * cut {
                    pairs.push((i, j));
                }
            }
        }
        pairs
    }

    fn listed(list: &NeighbourList, n: usize) -> Vec<(usize, usize)> {
        let mut pairs: Vec<(usize, usize)> = (0..n)
            .flat_map(|i| list.of(i).iter().map(move |&j| (i, j as usize)))
            .collect();
        pairs.sort_unstable();
        pairs
    }

    #[test]
    fn cell_list_matches_brute_force_in_small_and_tilted_boxes() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for (lengths, tilt, periodic) in [
            ([3.1, 3.1, 3.1], [0.0, 0.0, 0.0], [true; 3]),
            ([7.0, 5.0, 9.0], [1.2, -0.8, 0.5], [true; 3]),
            ([6.0, 6.0, 6.0], [0.0, 0.0, 0.0], [true, true, false]),
        ] {
            let simbox = SimBox {
                lo: [0.0; 3],
                lengths,
                tilt,
                periodic,
            };
            let x: Vec<[f64; 3]> = (0..150)
                .map(|_| simbox.to_cartesian(&[rng.gen(), rng.gen(), rng.gen()]))
                .collect();
            let mut list = NeighbourList::default();
            list.build(&simbox, &x, 1.2, 0.3, None);
            let mut expected = brute_force(&simbox, &x, 1.5);
            expected.sort_unstable();
            assert_eq!(
                listed(&list, x.len()),
                expected,
                "box {lengths:?} tilt {tilt:?}"
            );
        }
    }

    #[test]
    fn bonded_pairs_are_excluded() {
        let simbox = SimBox {
            lo: [0.0; 3],
            lengths: [5.0; 3],
            tilt: [0.0; 3],
            periodic: [true; 3],
        };
        let x = vec![[0.5, 0.5, 0.5], [1.2, 0.5, 0.5], [0.5, 1.2, 0.5]];
        let bonds = Exclusions::from_pairs(3, [(0, 1)].into_iter());
        let mut list = NeighbourList::default();
        list.build(&simbox, &x, 1.0, 0.2, Some(&bonds));
        assert_eq!(listed(&list, 3), vec![(0, 2), (1, 2)]);
    }
}
