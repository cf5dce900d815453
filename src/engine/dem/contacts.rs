//! Per-contact history kept beside the pair list and carried across its
//! rebuilds (the role of LAMMPS's `fix NEIGH_HISTORY`).
//!
//! Entry `k` of the history belongs to entry `k` of the half pair list. A
//! rebuild reorders and replaces the list, so the store keeps the list it
//! was aligned with and, on the next rebuild, moves every remembered
//! contact to its pair's new slot; pairs new to the list start at zero.

use super::super::neighbor::NeighbourList;
use crate::kernels::ContactHistory;

/// Contact histories aligned with one build of the pair list.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct ContactStore {
    /// The list build the store is aligned with (`None` before the first).
    build: Option<u64>,
    offsets: Vec<usize>,
    partners: Vec<i32>,
    /// One history per pair-list entry.
    pub history: Vec<ContactHistory>,
}

impl ContactStore {
    /// Aligns the store with `list`, carrying every history of a pair that
    /// is still listed; a no-op when `list` is the build already aligned.
    pub fn align(&mut self, list: &NeighbourList) {
        if self.build == Some(list.builds) && self.history.len() == list.neighbours.len() {
            return;
        }
        let n = list.offsets.len().saturating_sub(1);
        let mut history = vec![ContactHistory::default(); list.neighbours.len()];
        let zero = ContactHistory::default();
        // The list is a half list with j > i: a pair always sits in the row
        // of its lower index, so only that row is searched.
        let old_rows = self.offsets.len().saturating_sub(1);
        for i in 0..n.min(old_rows) {
            let old = self.offsets[i]..self.offsets[i + 1];
            if self.history[old.clone()].iter().all(|h| *h == zero) {
                continue;
            }
            let new = list.offsets[i]..list.offsets[i + 1];
            for (slot, &j) in history[new.clone()].iter_mut().zip(&list.neighbours[new]) {
                if let Some(o) = old.clone().find(|&o| self.partners[o] == j) {
                    *slot = self.history[o];
                }
            }
        }
        self.offsets = list.offsets.clone();
        self.partners = list.neighbours.clone();
        self.history = history;
        self.build = Some(list.builds);
    }

    /// Number of contacts whose springs (tangential, rolling, twisting)
    /// are loaded: the history a lost contact would lose. The recorded
    /// normal force does not count (every touching contact has one).
    pub fn remembered(&self) -> usize {
        self.history
            .iter()
            .filter(|h| h.tangential != [0.0; 3] || h.rolling != [0.0; 3] || h.twist != 0.0)
            .count()
    }
}
