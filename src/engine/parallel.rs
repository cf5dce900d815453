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
    pub fn scatter<F>(&mut self, team: &Team, out: &mut [T], work: F) -> ForcePass
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
                        let buf = buffers.get(c);
                        buf.clear();
                        buf.resize(len, T::default());
                        buf
                    }
                };
                let pass = work(c, target);
                unsafe { *passes.get(c) = pass };
            });
        }
        let buffers = &self.buffers[1..];
        team.run_split(out, |_, range, part| {
            for buf in buffers {
                for (o, b) in part.iter_mut().zip(&buf[range.clone()]) {
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
