//! Deterministic chunked scatter-add over a [`Team`].
//!
//! Each chunk of a list writes into its own buffer (chunk 0 straight into the
//! output), then the buffers are summed in chunk order. For a fixed thread
//! count the result is the same bit for bit on every run.

use super::team::{SharedSlice, Team};
use crate::kernels::ForcePass;

pub use super::team::chunk_range;

/// The rows of the `c`-th of `chunks` parts of compressed rows (row `i`
/// holds entries `offsets[i]..offsets[i + 1]`, from `offsets[0] = 0`) with
/// nearly equal numbers of entries: consecutive, disjoint, and together
/// every row.
pub fn balanced_range(offsets: &[usize], chunks: usize, c: usize) -> std::ops::Range<usize> {
    let rows = offsets.len().saturating_sub(1);
    let total = offsets.last().copied().unwrap_or(0);
    let boundary = |c: usize| {
        if c >= chunks {
            rows
        } else {
            let target = total * c / chunks;
            offsets[..rows].partition_point(|&o| o < target)
        }
    };
    boundary(c)..boundary(c + 1)
}

/// Per-thread scratch buffers, kept between steps so no step allocates.
#[derive(Debug, Default)]
pub struct Scratch<T> {
    /// `K` per chunk, chunk `c`'s `k`-th at `c K + k`; chunk 0's stay
    /// empty (it writes into the outputs).
    buffers: Vec<Vec<T>>,
}

impl<T: Copy + Default + Send + Sync + std::ops::AddAssign> Scratch<T> {
    /// Runs `work(chunk, out)` for each of the team's chunks and adds every
    /// chunk's contributions into `out`; returns the chunks' sums merged in
    /// chunk order (the first fault in list order).
    ///
    /// A chunk `c` writes only at indices from `lowest(c)` on (a half
    /// neighbour list, `j > i`, split by `i`, writes from its first `i`), so
    /// its buffer is cleared and added only from there: the buffers of two
    /// threads cost half of the whole array instead of all of it.
    pub fn scatter<F>(
        &mut self,
        team: &Team,
        out: &mut [T],
        lowest: impl Fn(usize) -> usize + Sync,
        work: F,
    ) -> ForcePass
    where
        F: Fn(usize, &mut [T]) -> ForcePass + Sync,
    {
        self.scatter_many(
            team,
            [out],
            lowest,
            ForcePass::default(),
            |c, [out]| work(c, out),
            |a, b| a.merged(&b),
        )
    }

    /// [`Scratch::scatter`] into `K` arrays at once (forces and torques),
    /// each chunk's result folded with `merge` from `init` in chunk order.
    /// One thread runs `work(0, outs)` alone and returns its result as it
    /// is, unmerged: `init` must be `merge`'s identity for the two to
    /// agree. Every array follows the same `lowest`; an array may be empty.
    pub fn scatter_many<const K: usize, R, F, M>(
        &mut self,
        team: &Team,
        outs: [&mut [T]; K],
        lowest: impl Fn(usize) -> usize + Sync,
        init: R,
        work: F,
        merge: M,
    ) -> R
    where
        R: Send + Copy,
        F: Fn(usize, [&mut [T]; K]) -> R + Sync,
        M: Fn(R, R) -> R,
    {
        let chunks = team.threads();
        if chunks <= 1 {
            return work(0, outs);
        }
        self.buffers.resize_with(chunks * K, Vec::new);
        let outs = outs.map(SharedSlice::new);
        let result = {
            let buffers = SharedSlice::new(&mut self.buffers);
            team.reduce_chunks(
                init,
                |c| {
                    // SAFETY: chunk c alone touches buffers[c K..c K + K];
                    // chunk 0 alone touches the outputs.
                    let targets = std::array::from_fn(|k| unsafe {
                        if c == 0 {
                            outs[k].range(0..outs[k].len())
                        } else {
                            // Each chunk clears its own copy, on its own
                            // thread. Below `lowest(c)` nothing is written
                            // or read.
                            let (buf, len) = (buffers.get(c * K + k), outs[k].len());
                            buf.resize(len, T::default());
                            buf[lowest(c).min(len)..].fill(T::default());
                            &mut buf[..]
                        }
                    });
                    work(c, targets)
                },
                merge,
            )
        };
        let buffers = &self.buffers;
        team.run(|c| {
            for (k, out) in outs.iter().enumerate() {
                let range = chunk_range(out.len(), chunks, c);
                // SAFETY: the chunks' ranges are disjoint.
                let part = unsafe { out.range(range.clone()) };
                for b in 1..chunks {
                    let buf = &buffers[b * K + k];
                    let from = lowest(b).clamp(range.start, range.end);
                    let skip = from - range.start;
                    for (o, v) in part[skip..].iter_mut().zip(&buf[from..range.end]) {
                        *o += *v;
                    }
                }
            }
        });
        result
    }
}

/// A `[f64; 3]` that can be summed, for force buffers.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(transparent)]
pub struct Vec3(pub [f64; 3]);

impl std::ops::AddAssign for Vec3 {
    #[inline(always)]
    fn add_assign(&mut self, o: Vec3) {
        self.0[0] += o.0[0];
        self.0[1] += o.0[1];
        self.0[2] += o.0[2];
    }
}

/// Views a force buffer as plain `[f64; 3]` rows for the kernels.
pub fn as_rows(v: &mut [Vec3]) -> &mut [[f64; 3]] {
    // SAFETY: Vec3 is repr(transparent) over [f64; 3].
    unsafe { std::slice::from_raw_parts_mut(v.as_mut_ptr() as *mut [f64; 3], v.len()) }
}

/// Views plain rows as a summable force buffer.
pub fn as_vec3(v: &mut [[f64; 3]]) -> &mut [Vec3] {
    // SAFETY: Vec3 is repr(transparent) over [f64; 3].
    unsafe { std::slice::from_raw_parts_mut(v.as_mut_ptr() as *mut Vec3, v.len()) }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A half list `j > i` on 37 particles, scattered by 1, 2 and 3
    /// threads: every pair adds `+w` to `i` and `-w` to `j`.
    fn scattered(threads: usize, runs: usize) -> Vec<f64> {
        #[derive(Clone, Copy, Default)]
        struct Sum(f64);
        impl std::ops::AddAssign for Sum {
            fn add_assign(&mut self, o: Sum) {
                self.0 += o.0;
            }
        }
        let n = 37;
        let team = Team::new(threads);
        let mut scratch = Scratch::<Sum>::default();
        let mut out = vec![Sum(0.0); n];
        for _ in 0..runs {
            out.fill(Sum(0.0));
            let first = |c| chunk_range(n, team.threads(), c).start;
            scratch.scatter(&team, &mut out, first, |c, out| {
                for i in chunk_range(n, team.threads(), c) {
                    for j in i + 1..n.min(i + 9) {
                        let w = 1.0 / (1 + i * n + j) as f64;
                        out[i].0 += w;
                        out[j].0 -= w;
                    }
                }
                ForcePass::default()
            });
        }
        out.iter().map(|s| s.0).collect()
    }

    /// Two arrays at once (forces and torques), the second empty or not,
    /// on 1 to 3 threads: every chunk's contributions reach both, and
    /// the chunks' results fold in chunk order.
    #[test]
    fn several_arrays_are_scattered_at_once() {
        let n = 29;
        let pairs = |c: usize, chunks: usize| {
            chunk_range(n, chunks, c).flat_map(move |i| (i + 1..n.min(i + 5)).map(move |j| (i, j)))
        };
        let mut serial = None;
        for threads in [1, 2, 3] {
            let team = Team::new(threads);
            let chunks = team.threads();
            let mut scratch = Scratch::<Vec3>::default();
            // Each layout twice on the same buffers: a buffer must not
            // carry a pass's sums into the next.
            for torques in [true, true, false, false] {
                let mut f = vec![Vec3::default(); n];
                let mut t = vec![Vec3::default(); if torques { n } else { 0 }];
                let first = |c| chunk_range(n, chunks, c).start;
                let order = scratch.scatter_many(
                    &team,
                    [&mut f[..], &mut t[..]],
                    first,
                    0usize,
                    |c, [f, t]| {
                        for (i, j) in pairs(c, chunks) {
                            let w = 1.0 / (1 + i * n + j) as f64;
                            f[i].0[0] += w;
                            f[j].0[0] -= w;
                            if let (Some(ti), Some(tj)) = (t.get(i), t.get(j)) {
                                let (ti, tj) = (ti.0[1] + w, tj.0[1] + 2.0 * w);
                                t[i].0[1] = ti;
                                t[j].0[1] = tj;
                            }
                        }
                        c + 1
                    },
                    |acc, c| 10 * acc + c,
                );
                // One thread returns its chunk's result as it is.
                let expected_order = (1..=chunks).fold(0, |acc, c| 10 * acc + c);
                assert_eq!(order, expected_order, "{threads} threads");
                assert_eq!(t.len(), if torques { n } else { 0 });
                let sums: Vec<[f64; 2]> = (0..n)
                    .map(|i| [f[i].0[0], t.get(i).map_or(0.0, |t| t.0[1])])
                    .collect();
                let serial: &Vec<[f64; 2]> = serial.get_or_insert_with(|| sums.clone());
                // Without torques the forces are the same, the torques 0.
                let dims = if torques { 2 } else { 1 };
                for (got, want) in sums.iter().zip(serial.iter()) {
                    for d in 0..dims {
                        assert!((got[d] - want[d]).abs() <= 1e-15, "{threads} threads");
                    }
                }
                assert!(sums.iter().all(|s| s[0] != 0.0 && (s[1] != 0.0) == torques));
            }
        }
    }

    /// A half list's rows (row i of n holding about n - i entries, some
    /// empty) split into parts of nearly equal entries: consecutive
    /// parts that cover every row, each within one row of an equal share.
    #[test]
    fn balanced_parts_share_the_entries_not_the_rows() {
        let n = 101;
        let mut offsets = vec![0];
        for i in 0..n {
            let entries = if i % 7 == 3 { 0 } else { n - i };
            offsets.push(offsets[i] + entries);
        }
        let total = offsets[n];
        for chunks in [1, 2, 3, 8] {
            let mut next = 0;
            for c in 0..chunks {
                let rows = balanced_range(&offsets, chunks, c);
                assert_eq!(
                    rows.start, next,
                    "{chunks} chunks: part {c} starts elsewhere"
                );
                next = rows.end;
                let entries = offsets[rows.end] - offsets[rows.start];
                let share = total as f64 / chunks as f64;
                assert!(
                    (entries as f64 - share).abs() <= n as f64,
                    "{chunks} chunks: part {c} has {entries} of {total} entries"
                );
            }
            assert_eq!(next, n, "{chunks} chunks do not reach the last row");
        }
        // Equal numbers of rows would give the first of two parts three
        // quarters of the entries.
        let halves = chunk_range(n, 2, 0);
        assert!(offsets[halves.end] > total * 2 / 3);
        assert_eq!(balanced_range(&[0], 2, 1), 0..0, "no rows");
    }

    #[test]
    fn buffers_cleared_from_the_lowest_index_still_give_every_sum() {
        let serial = scattered(1, 1);
        assert!(serial.iter().all(|s| *s != 0.0));
        for threads in [2, 3] {
            // Three runs: a buffer must not carry a step's sums into the next.
            let parallel = scattered(threads, 3);
            for (p, s) in parallel.iter().zip(&serial) {
                assert!((p - s).abs() <= 1e-15 * s.abs().max(1.0), "{p} {s}");
            }
        }
    }
}
