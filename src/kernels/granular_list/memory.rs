//! The contact memory and the correction rows: per-atom tables of
//! entries keyed by partner tag, plain doubles so that the plugin's fix can
//! move them with their atoms and write them to restart files.

use crate::kernels::granular::ContactHistory;

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
    pub(super) fn get<'d>(&self, data: &'d [f64], atom: usize, tag: f64) -> Option<&'d [f64]> {
        self.find(data, atom, tag)
            .map(|o| &data[o + 1..o + self.width])
    }

    /// The normal force the contact memory (rows of [`Layout::history`])
    /// holds for `atom`'s partner `tag`, 0 if none.
    #[inline]
    pub(super) fn load(&self, data: &[f64], atom: usize, tag: f64) -> f64 {
        self.get(data, atom, tag)
            .map_or(0.0, |v| v[HISTORY_VALUES - 1])
    }

    /// Stores `values` for `atom`'s partner `tag`; false if the row is full.
    #[inline]
    pub(super) fn put(&self, data: &mut [f64], atom: usize, tag: f64, values: &[f64]) -> bool {
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
    pub(super) fn remove(&self, data: &mut [f64], atom: usize, tag: f64) {
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

    pub(super) fn to_values(self) -> [f64; HISTORY_VALUES] {
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

    pub(super) fn from_values(v: &[f64]) -> Self {
        Self {
            tangential: [v[0], v[1], v[2]],
            rolling: [v[3], v[4], v[5]],
            twist: v[6],
            normal_force: v[7],
        }
    }
}
