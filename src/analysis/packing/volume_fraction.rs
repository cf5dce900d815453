//! The volume fraction of a packing by Monte Carlo: a random point is solid
//! if it lies inside the convex hull of a grain or inside a particle (a
//! sphere of radius d/2), which counts the gaps between surface particles
//! as solid, as the paper does.

use super::hull::Hull;
use crate::engine::SimBox;
use crate::kernels::Separation;
use rand::{Rng, SeedableRng};
use rayon::prelude::*;

/// A Monte Carlo estimate of a volume fraction.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct VolumeFraction {
    /// Fraction of the sampled points that are solid.
    pub phi: f64,
    /// Its standard error, `sqrt(phi (1 - phi) / points)`.
    pub error: f64,
    /// Points sampled.
    pub points: u64,
}

/// Indices of objects binned by position in a periodic box, for "which
/// objects lie within `reach` of this point" queries.
struct CellGrid {
    nbins: [usize; 3],
    start: Vec<usize>,
    items: Vec<usize>,
}

impl CellGrid {
    fn new(simbox: &SimBox, x: &[[f64; 3]], reach: f64) -> Self {
        let faces = simbox.face_distances();
        // Bins no finer than one object per bin on average: finer ones
        // only cost memory (a paper-scale box in bins of d/2 is 7e7 bins).
        let spacing = (simbox.volume() / x.len().max(1) as f64).cbrt();
        let width = reach.max(spacing);
        let nbins = [0, 1, 2].map(|d| ((faces[d] / width).floor() as usize).clamp(1, 512));
        let total = nbins[0] * nbins[1] * nbins[2];
        let bins: Vec<usize> = x
            .iter()
            .map(|p| Self::flat(nbins, Self::bin(nbins, simbox, p)))
            .collect();
        let mut start = vec![0usize; total + 1];
        for &b in &bins {
            start[b + 1] += 1;
        }
        for b in 0..total {
            start[b + 1] += start[b];
        }
        let mut cursor = start.clone();
        let mut items = vec![0usize; x.len()];
        for (i, &b) in bins.iter().enumerate() {
            items[cursor[b]] = i;
            cursor[b] += 1;
        }
        Self {
            nbins,
            start,
            items,
        }
    }

    fn bin(nbins: [usize; 3], simbox: &SimBox, p: &[f64; 3]) -> [usize; 3] {
        let s = simbox.to_fractional(p);
        [0, 1, 2].map(|d| {
            let t = (s[d].rem_euclid(1.0) * nbins[d] as f64).floor() as usize;
            t.min(nbins[d] - 1)
        })
    }

    fn flat(nbins: [usize; 3], b: [usize; 3]) -> usize {
        (b[2] * nbins[1] + b[1]) * nbins[0] + b[0]
    }

    /// Calls `visit` on every object in the 27 bins around `p` (each bin
    /// once), until it returns true; returns whether one did.
    fn any_near(
        &self,
        simbox: &SimBox,
        p: &[f64; 3],
        mut visit: impl FnMut(usize) -> bool,
    ) -> bool {
        let b = Self::bin(self.nbins, simbox, p);
        let mut seen = [usize::MAX; 27];
        let mut count = 0;
        for dz in -1i64..=1 {
            for dy in -1i64..=1 {
                for dx in -1i64..=1 {
                    let off = [dx, dy, dz];
                    let nb = [0, 1, 2]
                        .map(|d| (b[d] as i64 + off[d]).rem_euclid(self.nbins[d] as i64) as usize);
                    let f = Self::flat(self.nbins, nb);
                    if seen[..count].contains(&f) {
                        continue;
                    }
                    seen[count] = f;
                    count += 1;
                    for &i in &self.items[self.start[f]..self.start[f + 1]] {
                        if visit(i) {
                            return true;
                        }
                    }
                }
            }
        }
        false
    }
}

/// Points per independently seeded chunk: the estimate does not depend on
/// the number of threads.
const CHUNK: u64 = 1 << 14;

/// The volume fraction of a fully periodic box holding grains with convex
/// hulls `hulls` (their `centre`s may lie outside the box) and particles
/// at `x` of radius `particle_radius`, from `points` random points drawn
/// with `seed`.
pub fn monte_carlo_volume_fraction(
    simbox: &SimBox,
    hulls: &[Hull],
    x: &[[f64; 3]],
    particle_radius: f64,
    points: u64,
    seed: u64,
) -> VolumeFraction {
    let hull_reach = hulls.iter().map(|h| h.outer_radius).fold(0.0, f64::max);
    let centres: Vec<[f64; 3]> = hulls.iter().map(|h| h.centre).collect();
    let hull_grid = CellGrid::new(simbox, &centres, hull_reach.max(1e-9));
    let particle_grid = CellGrid::new(simbox, x, particle_radius.max(1e-9));
    let image = simbox.minimum_image();
    let r2 = particle_radius * particle_radius;
    let chunks = points.div_ceil(CHUNK);
    let solid: u64 = (0..chunks)
        .into_par_iter()
        .map(|c| {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
            rng.set_stream(c);
            let n = CHUNK.min(points - c * CHUNK);
            let mut hits = 0u64;
            for _ in 0..n {
                let s: [f64; 3] = [rng.gen(), rng.gen(), rng.gen()];
                let p = simbox.to_cartesian(&s);
                let inside = hull_grid.any_near(simbox, &p, |g| {
                    hulls[g].contains_offset(&image.delta(&p, &hulls[g].centre))
                }) || particle_grid.any_near(simbox, &p, |i| {
                    let d = image.delta(&p, &x[i]);
                    d[0] * d[0] + d[1] * d[1] + d[2] * d[2] <= r2
                });
                hits += u64::from(inside);
            }
            hits
        })
        .sum();
    let phi = solid as f64 / points.max(1) as f64;
    VolumeFraction {
        phi,
        error: (phi * (1.0 - phi) / points.max(1) as f64).sqrt(),
        points,
    }
}
