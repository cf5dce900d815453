//! Deterministic chunked scatter-add over threads.
//!
//! Each chunk of a list writes into its own buffer (chunk 0 straight into the
//! output), then the buffers are summed in chunk order. For a fixed thread
//! count the result is the same bit for bit on every run.

use crate::kernels::ForcePass;

/// Per-thread scratch buffers, kept between steps so no step allocates.
#[derive(Debug, Default)]
pub struct Scratch<T> {
    buffers: Vec<Vec<T>>,
    passes: Vec<ForcePass>,
}

impl<T: Copy + Default + Send + Sync + std::ops::AddAssign> Scratch<T> {
    /// Runs `work(chunk, out)` for `chunks` chunks and adds every chunk's
    /// contributions into `out`; returns the chunks' sums merged in chunk
    /// order (the first fault in list order).
    pub fn scatter<F>(&mut self, chunks: usize, out: &mut [T], work: F) -> ForcePass
    where
        F: Fn(usize, &mut [T]) -> ForcePass + Sync,
    {
        if chunks <= 1 {
            return work(0, out);
        }
        self.buffers.resize_with(chunks - 1, Vec::new);
        for buf in &mut self.buffers {
            buf.clear();
            buf.resize(out.len(), T::default());
        }
        self.passes.clear();
        self.passes.resize(chunks, ForcePass::default());
        let (first, rest) = self.passes.split_at_mut(1);
        let work = &work;
        rayon::scope(|s| {
            for ((c, buf), pass) in self.buffers.iter_mut().enumerate().zip(rest.iter_mut()) {
                s.spawn(move |_| *pass = work(c + 1, buf));
            }
            first[0] = work(0, out);
        });
        for buf in &self.buffers {
            for (o, b) in out.iter_mut().zip(buf) {
                *o += *b;
            }
        }
        self.passes
            .iter()
            .fold(ForcePass::default(), |acc, t| acc.merged(t))
    }
}

/// Splits `0..len` into `chunks` nearly equal contiguous ranges.
pub fn chunk_range(len: usize, chunks: usize, c: usize) -> std::ops::Range<usize> {
    let start = len * c / chunks;
    let end = len * (c + 1) / chunks;
    start..end
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
