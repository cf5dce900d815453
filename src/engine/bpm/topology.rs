//! Bonds in CSR order, with their reference lengths.

use crate::engine::neighbor::Exclusions;
use crate::kernels::{BondEntry, Separation};

/// The bond network: each bond stored once with `i < j`, sorted by `i`
/// then `j` (CSR order), so a pass over bonds walks positions forward.
#[derive(Clone, Debug, Default)]
pub struct BondTopology {
    /// Bonds, type 1, in CSR order.
    pub entries: Vec<BondEntry>,
    /// Reference length `r0` of each bond (d units).
    pub r0: Vec<f64>,
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
        let mut sorted: Vec<(usize, usize, f64)> = bonds
            .iter()
            .map(|&(i, j, r0)| (i.min(j), i.max(j), r0))
            .collect();
        sorted.sort_by_key(|b| (b.0, b.1));
        let mut offsets = vec![0usize; n + 1];
        for &(i, _, _) in &sorted {
            offsets[i + 1] += 1;
        }
        for i in 0..n {
            offsets[i + 1] += offsets[i];
        }
        let exclusions = Exclusions::from_pairs(n, sorted.iter().map(|&(i, j, _)| (i, j)));
        Self {
            entries: sorted
                .iter()
                .map(|&(i, j, _)| BondEntry {
                    i: i as i32,
                    j: j as i32,
                    ty: 1,
                })
                .collect(),
            r0: sorted.iter().map(|b| b.2).collect(),
            offsets,
            exclusions,
        }
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

    /// Sets every reference length to the current distance (the stress-free
    /// reset of the compaction protocol).
    pub fn reset_reference<S: Separation>(&mut self, sep: &S, x: &[[f64; 3]]) {
        for (bond, r0) in self.entries.iter().zip(self.r0.iter_mut()) {
            *r0 = sep.distance(&x[bond.i as usize], &x[bond.j as usize]);
        }
    }

    /// The longest reference length, or 0 without bonds.
    pub fn max_r0(&self) -> f64 {
        self.r0.iter().cloned().fold(0.0, f64::max)
    }
}
