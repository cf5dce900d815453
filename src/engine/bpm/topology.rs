//! Bonds in CSR order, with their reference lengths and plastic strains.

use crate::engine::neighbor::Exclusions;
use crate::kernels::{BondEntry, Separation};

/// The bond network: each bond stored once with `i < j`, sorted by `i`
/// then `j` (CSR order), so a pass over bonds walks positions forward.
#[derive(Clone, Debug, Default)]
pub struct BondTopology {
    /// Bonds, type 1, in CSR order.
    pub entries: Vec<BondEntry>,
    /// Reference length `r0` of each bond (d units): its first length,
    /// from which its strain is measured.
    pub r0: Vec<f64>,
    /// Plastic strain `e_p` of each bond: its rest length is
    /// `(1 + e_p) r0` (0 unless bonds yield).
    pub plastic: Vec<f64>,
    /// `offsets[i]..offsets[i + 1]` are the bonds whose first atom is `i`.
    pub offsets: Vec<usize>,
    /// Bonded pairs, left out of the pair list.
    exclusions: Exclusions,
}

impl BondTopology {
    /// Builds the topology from `(i, j, r0)` triples on `n` atoms.
    ///
    /// Indices must be valid and distinct (the scene checks this first).
    pub fn new(n: usize, bonds: &[(usize, usize, f64)]) -> Self {
        let with_strain: Vec<_> = bonds.iter().map(|&(i, j, r0)| (i, j, r0, 0.0)).collect();
        Self::with_plastic_strains(n, &with_strain)
    }

    /// Builds the topology from `(i, j, r0, e_p)` on `n` atoms: bonds with
    /// plastic strains.
    pub fn with_plastic_strains(n: usize, bonds: &[(usize, usize, f64, f64)]) -> Self {
        let mut sorted: Vec<(usize, usize, f64, f64)> = bonds
            .iter()
            .map(|&(i, j, r0, e_p)| (i.min(j), i.max(j), r0, e_p))
            .collect();
        sorted.sort_by_key(|b| (b.0, b.1));
        let mut offsets = vec![0usize; n + 1];
        for &(i, ..) in &sorted {
            offsets[i + 1] += 1;
        }
        for i in 0..n {
            offsets[i + 1] += offsets[i];
        }
        let exclusions = Exclusions::from_pairs(n, sorted.iter().map(|&(i, j, ..)| (i, j)));
        Self {
            entries: sorted
                .iter()
                .map(|&(i, j, ..)| BondEntry {
                    i: i as i32,
                    j: j as i32,
                    ty: 1,
                })
                .collect(),
            r0: sorted.iter().map(|b| b.2).collect(),
            plastic: sorted.iter().map(|b| b.3).collect(),
            offsets,
            exclusions,
        }
    }

    /// Removes the bonds at positions `broken` and returns their particle
    /// pairs; the rest keep their order.
    pub fn remove(&mut self, broken: &[usize]) -> Vec<[usize; 2]> {
        let removed = broken
            .iter()
            .map(|&b| [self.entries[b].i as usize, self.entries[b].j as usize])
            .collect();
        let mut kept = vec![true; self.len()];
        for &b in broken {
            kept[b] = false;
        }
        retain_where(&mut self.entries, &kept);
        retain_where(&mut self.r0, &kept);
        retain_where(&mut self.plastic, &kept);
        let n = self.offsets.len() - 1;
        self.offsets.fill(0);
        for bond in &self.entries {
            self.offsets[bond.i as usize + 1] += 1;
        }
        for i in 0..n {
            self.offsets[i + 1] += self.offsets[i];
        }
        self.exclusions =
            Exclusions::from_pairs(n, self.entries.iter().map(|b| (b.i as usize, b.j as usize)));
        removed
    }

    /// Makes each bond's rest length its reference length: `r0` becomes
    /// `(1 + e_p) r0` and `e_p` 0.
    pub fn fold_plastic_strains(&mut self) {
        for (r0, e_p) in self.r0.iter_mut().zip(&mut self.plastic) {
            if *e_p != 0.0 {
                *r0 *= 1.0 + *e_p;
                *e_p = 0.0;
            }
        }
    }

    /// Each bond's atoms `[i, j]`, in CSR order.
    pub fn pairs(&self) -> impl ExactSizeIterator<Item = [usize; 2]> + '_ {
        self.entries.iter().map(|b| [b.i as usize, b.j as usize])
    }

    /// Each bond's rest length `(1 + e_p) r0`.
    pub fn rest_lengths(&self) -> impl ExactSizeIterator<Item = f64> + '_ {
        self.r0
            .iter()
            .zip(&self.plastic)
            .map(|(r0, e_p)| r0 * (1.0 + e_p))
    }

    /// Number of bonds.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether there are no bonds.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// Sorted bonded partners of atom `i`.
    pub fn partners(&self, i: usize) -> &[u32] {
        self.exclusions.partners(i)
    }

    /// Whether `i` and `j` are bonded.
    pub fn bonded(&self, i: usize, j: usize) -> bool {
        self.exclusions.excludes(i, j)
    }

    /// The bonded pairs as pair-list exclusions.
    pub fn exclusions(&self) -> &Exclusions {
        &self.exclusions
    }

    /// Sets every reference length to the current distance and every
    /// plastic strain to 0 (the stress-free reset of the compaction
    /// protocol).
    pub fn reset_reference<S: Separation>(&mut self, sep: &S, x: &[[f64; 3]]) {
        for (bond, r0) in self.entries.iter().zip(self.r0.iter_mut()) {
            *r0 = sep.distance(&x[bond.i as usize], &x[bond.j as usize]);
        }
        self.plastic.fill(0.0);
    }

    /// The longest reference length, or 0 without bonds.
    pub fn max_r0(&self) -> f64 {
        self.r0.iter().cloned().fold(0.0, f64::max)
    }
}

/// Keeps the items of `items` whose entry of `kept` is true, in order.
fn retain_where<T>(items: &mut Vec<T>, kept: &[bool]) {
    let mut k = kept.iter();
    items.retain(|_| k.next().copied().unwrap_or(true));
}
