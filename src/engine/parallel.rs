//! Deterministic chunked scatter-add over a [`Team`].
//!
//! Each chunk of a list writes into its own buffer (chunk 0 straight into the
//! output), then the buffers are summed in chunk order. For a fixed thread
//! count the result is the same bit for bit on every run.

use super::team::{SharedSlice, Team};
use crate::kernels::ForcePass;

pub use super::team::chunk_range;

/// Per-thread scratch buffers, kept between steps so no step allocates.
#[derive(Debug, Default)]
pub struct Scratch<T> {
    /// One per chunk; chunk 0's stays empty (it writes into the output).
    buffers: Vec<Vec<T>>,
    passes: Vec<ForcePass>,
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
        let chunks = team.threads();
        if chunks <= 1 {
            return work(0, out);
        }
        self.buffers.resize_with(chunks, Vec::new);
        let len = out.len();
        self.passes.clear();
        self.passes.resize(chunks, ForcePass::default());
        {
            let out = SharedSlice::new(out);
            let buffers = SharedSlice::new(&mut self.buffers);
            let passes = SharedSlice::new(&mut self.passes);
            team.run(|c| {
                // SAFETY: chunk c alone touches passes[c] and buffers[c];
                // chunk 0 alone touches `out`.
                let target: &mut [T] = unsafe {
                    if c == 0 {
                        out.range(0..out.len())
                    } else {
                        // Each chunk clears its own copy, on its own thread.
                        // Below `lowest(c)` nothing is written or read.
                        let buf = buffers.get(c);
                        buf.resize(len, T::default());
                        buf[lowest(c).min(len)..].fill(T::default());
                        buf
                    }
                };
                let pass = work(c, target);
                unsafe { *passes.get(c) = pass };
            });
        }
        let buffers = &self.buffers[1..];
        team.run_split(out, |_, range, part| {
            for (c, buf) in (1..).zip(buffers) {
                let from = lowest(c).clamp(range.start, range.end);
                let skip = from - range.start;
                for (o, b) in part[skip..].iter_mut().zip(&buf[from..range.end]) {
                    *o += *b;
                }
            }
        });
        self.passes
            .iter()
            .fold(ForcePass::default(), |acc, t| acc.merged(t))
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
