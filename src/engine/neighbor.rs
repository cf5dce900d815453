//! Cell-list Verlet neighbour list with a skin, rebuilt on displacement.
//!
//! Atoms are binned in fractional coordinates with bins at least one
//! list cutoff thick (face to face), so every pair within the cutoff sits in
//! the same or an adjacent bin. Where a periodic dimension has one or two
//! bins the stencil reaches a bin twice; it is then deduplicated, which
//! keeps such boxes correct under the minimum image. Atoms a little
//! outside a periodic box (round-off at its faces) are binned where their
//! wrapped selves are.

use super::parallel::balanced_range;
use super::simbox::SimBox;
use super::team::{chunk_range, Team};
use crate::kernels::{BoxImage, Separation};
use nalgebra::{Matrix3, Vector3};

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

/// A half neighbour list (`j > i`) in CSR form. Serialised whole but for
/// the bins, a build's scratch, so a resumed run walks the same pairs in
/// the same order.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
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
    /// How many times a rigid motion of the reference positions saved a
    /// build since the last one (closed boxes only).
    pub reanchors: u64,
    /// Whether the rebuild test in a closed box discounts rigid motion
    /// (default; off only to measure what it saves).
    pub follow_rigid_motion: bool,
    /// Each atom's bin, per dimension.
    #[serde(skip)]
    bin_of: Vec<[usize; 3]>,
    #[serde(skip)]
    bin_start: Vec<usize>,
    #[serde(skip)]
    bin_atoms: Vec<usize>,
    /// Each thread's rows of the last build (one thread: its row lengths
    /// only, the rows going straight into `neighbours`), kept so that their
    /// buffers are reused.
    #[serde(skip)]
    parts: Vec<RowPart>,
}

/// One thread's share of a build: the rows of a contiguous range of atoms.
#[derive(Clone, Debug, Default)]
struct RowPart {
    /// The rows' neighbours, row after row.
    neighbours: Vec<i32>,
    /// Each row's length.
    lengths: Vec<usize>,
}

/// The flat index of bin `b` in a grid of `nbins`, x fastest.
fn flat_bin(b: [usize; 3], nbins: [usize; 3]) -> usize {
    (b[2] * nbins[1] + b[1]) * nbins[0] + b[0]
}

/// The bins next to bin `b` of `m` along one dimension, `b` included:
/// wrapped where the dimension is periodic, left out beyond its ends
/// where it is not. Returns the bins and how many there are.
fn axis_bins(b: usize, m: usize, periodic: bool) -> ([usize; 3], usize) {
    let mut bins = [0usize; 3];
    let mut k = 0;
    if b > 0 {
        bins[k] = b - 1;
        k += 1;
    } else if periodic {
        bins[k] = m - 1;
        k += 1;
    }
    bins[k] = b;
    k += 1;
    if b + 1 < m {
        bins[k] = b + 1;
        k += 1;
    } else if periodic {
        bins[k] = 0;
        k += 1;
    }
    (bins, k)
}

/// The bins of a build, as the row search reads them.
struct BinGrid<'a> {
    nbins: [usize; 3],
    periodic: [bool; 3],
    /// Whether a stencil can reach one bin twice (a periodic dimension of
    /// one or two bins).
    repeats: bool,
    /// Each atom's bin, per dimension.
    bin_of: &'a [[usize; 3]],
    /// Where each flat bin's atoms start in `bin_atoms`.
    bin_start: &'a [usize],
    /// The atoms, bin after bin, each bin's in increasing index.
    bin_atoms: &'a [usize],
}

/// Which candidate pairs a row keeps.
struct PairTest<'a, S: Separation> {
    image: &'a S,
    x: &'a [[f64; 3]],
    cut_sq: f64,
    exclude: Option<&'a Exclusions>,
}

/// Searches the rows of `atoms` into `part`: for each atom `i`, every
/// `j > i` in the 27 bins around its own within the cutoff and not
/// excluded, in increasing order. A plain function, not a closure, so
/// that the grid and positions reach it as arguments the compiler may
/// keep in registers across the row's pushes.
fn search_rows<S: Separation>(
    grid: &BinGrid,
    pairs: &PairTest<S>,
    atoms: std::ops::Range<usize>,
    part: &mut RowPart,
) {
    let x = pairs.x;
    part.neighbours.clear();
    part.lengths.clear();
    let mut stencil = [0usize; 27];
    for i in atoms {
        let b = grid.bin_of[i];
        let [(xs, nx), (ys, ny), (zs, nz)] =
            [0, 1, 2].map(|d| axis_bins(b[d], grid.nbins[d], grid.periodic[d]));
        let mut bins = 0;
        for &z in &zs[..nz] {
            for &y in &ys[..ny] {
                for &xb in &xs[..nx] {
                    stencil[bins] = flat_bin([xb, y, z], grid.nbins);
                    bins += 1;
                }
            }
        }
        if grid.repeats {
            stencil[..bins].sort_unstable();
            let mut kept = 0;
            for k in 0..bins {
                if k == 0 || stencil[k] != stencil[kept - 1] {
                    stencil[kept] = stencil[k];
                    kept += 1;
                }
            }
            bins = kept;
        }
        let row_start = part.neighbours.len();
        let xi = x[i];
        for &bin in &stencil[..bins] {
            for &j in &grid.bin_atoms[grid.bin_start[bin]..grid.bin_start[bin + 1]] {
                if j <= i {
                    continue;
                }
                let d = pairs.image.delta(&xi, &x[j]);
                if d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < pairs.cut_sq
                    && !pairs.exclude.is_some_and(|e| e.excludes(i, j))
                {
                    part.neighbours.push(j as i32);
                }
            }
        }
        part.neighbours[row_start..].sort_unstable();
        part.lengths.push(part.neighbours.len() - row_start);
    }
}

/// Searches every row into `neighbours`, the atoms split into contiguous
/// ranges over `team`'s threads (one `parts` entry each); every row is
/// found and sorted on its own, so the list is the same for any number of
/// threads.
fn search_list<S: Separation>(
    team: &Team,
    grid: &BinGrid,
    pairs: &PairTest<S>,
    parts: &mut [RowPart],
    neighbours: &mut Vec<i32>,
) {
    let n = pairs.x.len();
    if let [part] = parts {
        // One thread searches straight into the list's own buffer.
        std::mem::swap(&mut part.neighbours, neighbours);
        search_rows(grid, pairs, 0..n, part);
        std::mem::swap(&mut part.neighbours, neighbours);
    } else {
        let chunks = parts.len();
        team.run_on(parts, |c, part| {
            search_rows(grid, pairs, chunk_range(n, chunks, c), part)
        });
        neighbours.clear();
        for part in parts.iter() {
            neighbours.extend_from_slice(&part.neighbours);
        }
    }
}

impl Default for NeighbourList {
    fn default() -> Self {
        Self {
            offsets: Vec::new(),
            neighbours: Vec::new(),
            list_cutoff: 0.0,
            x_at_build: Vec::new(),
            box_at_build: None,
            builds: 0,
            reanchors: 0,
            follow_rigid_motion: true,
            bin_of: Vec::new(),
            bin_start: Vec::new(),
            bin_atoms: Vec::new(),
            parts: Vec::new(),
        }
    }
}

impl NeighbourList {
    /// Neighbours of atom `i`.
    pub fn of(&self, i: usize) -> &[i32] {
        &self.neighbours[self.offsets[i]..self.offsets[i + 1]]
    }

    /// The list entries of the rows `rows` (none before the first build).
    pub fn entries(&self, rows: std::ops::Range<usize>) -> std::ops::Range<usize> {
        let at = |i: usize| self.offsets.get(i).copied().unwrap_or(0);
        at(rows.start)..at(rows.end)
    }

    /// Iterator over `(i, neighbours of i)` for atoms in `range`.
    pub fn rows(&self, range: std::ops::Range<usize>) -> impl Iterator<Item = (usize, &[i32])> {
        range.map(move |i| (i, self.of(i)))
    }

    /// The rows of the `c`-th of `chunks` parts of the list with nearly
    /// equal numbers of entries. A half list (`j > i`) holds more entries
    /// in its first rows than in its last, the more so the less the
    /// particles' order follows space: equal numbers of rows would give
    /// the first chunk up to three quarters of the pairs.
    pub fn balanced_rows(&self, chunks: usize, c: usize) -> std::ops::Range<usize> {
        balanced_range(&self.offsets, chunks, c)
    }

    /// Whether an atom may have moved into range of one not listed: twice the
    /// largest displacement plus the drift of periodic images exceeds the skin.
    ///
    /// In a closed box only distances matter, so displacements are measured
    /// from the rigid image of the positions at the build that best fits the
    /// current ones: a grain that turns or drifts as a whole (a lone grain
    /// between walls does both) keeps its list. When the plain test fails but
    /// the rigid one passes, that rigid image becomes the new reference.
    pub fn needs_rebuild(
        &mut self,
        simbox: &SimBox,
        x: &[[f64; 3]],
        skin: f64,
        team: &Team,
    ) -> bool {
        let Some(old_box) = &self.box_at_build else {
            return true;
        };
        if self.x_at_build.len() != x.len() {
            return true;
        }
        let drift = simbox.periodic_drift(old_box);
        let reference = &self.x_at_build;
        let largest = team.map_reduce(
            x.len(),
            0.0,
            |range| max_displacement(&x[range.clone()], &reference[range]),
            f64::max,
        );
        if 2.0 * largest + drift <= skin {
            return false;
        }
        if !self.follow_rigid_motion || simbox.periodic.iter().any(|&p| p) || x.is_empty() {
            return true;
        }
        let moved = rigid_image(&self.x_at_build, x);
        if !moved.iter().flatten().all(|c| c.is_finite()) {
            return true;
        }
        // The reference drifts from an exact rigid image by round-off at each
        // re-anchoring; the margin keeps the test conservative.
        let margin = 1e-12 * (self.reanchors + 1) as f64;
        if 2.0 * max_displacement(x, &moved) + margin > skin {
            return true;
        }
        self.x_at_build = moved;
        self.reanchors += 1;
        false
    }

    /// Rebuilds the list for `cutoff + skin`, leaving out the pairs of
    /// `exclude`, on one thread. Positions should be wrapped; atoms an
    /// image or so outside a periodic box are still listed correctly.
    pub fn build(
        &mut self,
        simbox: &SimBox,
        x: &[[f64; 3]],
        cutoff: f64,
        skin: f64,
        exclude: Option<&Exclusions>,
    ) {
        self.build_on(&Team::new(1), simbox, x, cutoff, skin, exclude);
    }

    /// [`NeighbourList::build`] with the rows searched by `team`'s threads;
    /// the list is the same for any number of threads.
    pub fn build_on(
        &mut self,
        team: &Team,
        simbox: &SimBox,
        x: &[[f64; 3]],
        cutoff: f64,
        skin: f64,
        exclude: Option<&Exclusions>,
    ) {
        let list_cut = cutoff + skin;
        let cut_sq = list_cut * list_cut;
        // Prepared once: `SimBox::delta` would divide by the box lengths
        // at every candidate pair.
        let image = simbox.minimum_image();
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
                let m = nbins[d] as i64;
                // An integer floor: `f64::floor` is a library call on the
                // baseline instruction set. NaN lands in bin 0.
                let t = (s[d] - lo[d]) / span[d] * nbins[d] as f64;
                let mut k = t as i64;
                if (k as f64) > t {
                    // Saturating: a blown-up coordinate (-inf) must not
                    // overflow before the run's finiteness check sees it.
                    k = k.saturating_sub(1);
                }
                if simbox.periodic[d] && !(0..m).contains(&k) {
                    k = k.rem_euclid(m);
                }
                b[d] = k.clamp(0, m - 1) as usize;
            }
            b
        };
        let flat = |b: [usize; 3]| flat_bin(b, nbins);
        // A periodic dimension of one or two bins reaches the same bin
        // twice; only then must a stencil drop repeated bins.
        let repeats = (0..3).any(|d| simbox.periodic[d] && nbins[d] < 3);
        let total_bins = nbins[0] * nbins[1] * nbins[2];

        self.bin_of.clear();
        self.bin_of.extend(frac.iter().map(bin_index));
        self.bin_start.clear();
        self.bin_start.resize(total_bins + 1, 0);
        for &b in &self.bin_of {
            self.bin_start[flat(b) + 1] += 1;
        }
        for b in 0..total_bins {
            self.bin_start[b + 1] += self.bin_start[b];
        }
        self.bin_atoms.clear();
        self.bin_atoms.resize(n, 0);
        let mut cursor = self.bin_start.clone();
        for (i, &b) in self.bin_of.iter().enumerate() {
            let b = flat(b);
            self.bin_atoms[cursor[b]] = i;
            cursor[b] += 1;
        }

        // The rows, each thread searching a contiguous range of atoms;
        // every row is found and sorted on its own, so the list is the same
        // for any number of threads.
        let chunks = team.threads();
        self.parts.resize_with(chunks, RowPart::default);
        let grid = BinGrid {
            nbins,
            periodic: simbox.periodic,
            repeats,
            bin_of: &self.bin_of,
            bin_start: &self.bin_start,
            bin_atoms: &self.bin_atoms,
        };
        // Each candidate pair is imaged: per dimension when the box has
        // no tilt (the same separations, bit for bit).
        let (parts, neighbours) = (&mut self.parts, &mut self.neighbours);
        match BoxImage::of(&image) {
            BoxImage::Orthogonal(image) => {
                let pairs = PairTest {
                    image: &image,
                    x,
                    cut_sq,
                    exclude,
                };
                search_list(team, &grid, &pairs, parts, neighbours)
            }
            BoxImage::Tilted(image) => {
                let pairs = PairTest {
                    image: &image,
                    x,
                    cut_sq,
                    exclude,
                };
                search_list(team, &grid, &pairs, parts, neighbours)
            }
        }
        self.offsets.clear();
        self.offsets.reserve(n + 1);
        self.offsets.push(0);
        for part in &self.parts {
            for &length in &part.lengths {
                let last = self.offsets[self.offsets.len() - 1];
                self.offsets.push(last + length);
            }
        }
        self.list_cutoff = list_cut;
        self.x_at_build.clear();
        self.x_at_build.extend_from_slice(x);
        self.box_at_build = Some(simbox.clone());
        self.builds += 1;
        self.reanchors = 0;
    }

    /// Whether no pair is listed, so a pair pass has nothing to do.
    pub fn is_empty(&self) -> bool {
        self.neighbours.is_empty()
    }
}

/// Largest distance between matching points of `a` and `b`.
fn max_displacement(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    // Runs at every step. One running maximum is a chain of dependent
    // `max`es that waits on each result; four independent ones keep the
    // unit busy, and written as a comparison they vectorise (`f64::max`'s
    // NaN rule does not; a NaN distance is passed over either way, and
    // non-finite positions are caught by the run's own check). The maximum
    // is the same in any order.
    const LANES: usize = 4;
    let larger = |m: f64, d: f64| if d > m { d } else { m };
    let distance_sq = |p: &[f64; 3], q: &[f64; 3]| {
        let d = [p[0] - q[0], p[1] - q[1], p[2] - q[2]];
        d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
    };
    let n = a.len().min(b.len());
    let whole = n / LANES * LANES;
    let mut lanes = [0.0f64; LANES];
    for (p, q) in a[..whole]
        .chunks_exact(LANES)
        .zip(b[..whole].chunks_exact(LANES))
    {
        for l in 0..LANES {
            lanes[l] = larger(lanes[l], distance_sq(&p[l], &q[l]));
        }
    }
    let max_sq = a[whole..n]
        .iter()
        .zip(&b[whole..n])
        .fold(lanes.into_iter().fold(0.0, larger), |m, (p, q)| {
            larger(m, distance_sq(p, q))
        });
    max_sq.sqrt()
}

/// The rigid motion (rotation about the centroid, then translation) of
/// `from` that best fits `to` in least squares (Kabsch), applied to `from`.
fn rigid_image(from: &[[f64; 3]], to: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let centroid = |p: &[[f64; 3]]| {
        let sum = p
            .iter()
            .fold(Vector3::zeros(), |s, q| s + Vector3::from(*q));
        sum / p.len() as f64
    };
    let (c_from, c_to) = (centroid(from), centroid(to));
    let mut cov = Matrix3::zeros();
    for (p, q) in from.iter().zip(to) {
        cov += (Vector3::from(*p) - c_from) * (Vector3::from(*q) - c_to).transpose();
    }
    let svd = cov.svd(true, true);
    let (Some(u), Some(v_t)) = (svd.u, svd.v_t) else {
        return from.to_vec();
    };
    let mut v = v_t.transpose();
    if (v * u.transpose()).determinant() < 0.0 {
        // A reflection fits better than any rotation: turn the axis of the
        // smallest singular value round.
        v.column_mut(svd.singular_values.imin()).neg_mut();
    }
    let rotation = v * u.transpose();
    from.iter()
        .map(|p| (rotation * (Vector3::from(*p) - c_from) + c_to).into())
        .collect()
}

/// Every pair of `x` in `simbox` closer than `cutoff`, once with
/// `i < j`, with its (minimum-image) distance.
pub fn pairs_within(simbox: &SimBox, x: &[[f64; 3]], cutoff: f64) -> Vec<(usize, usize, f64)> {
    let mut list = NeighbourList::default();
    list.build(simbox, x, cutoff, 0.0, None);
    let mut pairs = Vec::new();
    for i in 0..x.len() {
        for &j in list.of(i) {
            let j = j as usize;
            pairs.push((i, j, simbox.distance(&x[i], &x[j])));
        }
    }
    pairs
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
            // One, three and four bins: a stencil that repeats its bin
            // along x only.
            ([2.9, 4.6, 6.2], [0.3, 0.0, -0.4], [true; 3]),
            // An open dimension of one bin beside periodic ones of two and
            // four.
            ([3.3, 2.2, 6.2], [0.0, 0.0, 0.0], [true, false, true]),
        ] {
            let simbox = SimBox {
                lo: [0.0; 3],
                lengths,
                tilt,
                periodic,
            };
            let mut x: Vec<[f64; 3]> = (0..150)
                .map(|_| simbox.to_cartesian(&[rng.gen(), rng.gen(), rng.gen()]))
                .collect();
            // Atoms an image away from the box (as round-off leaves them
            // at its faces) are binned where their wrapped selves are.
            for (k, p) in x.iter_mut().enumerate().step_by(7) {
                let n = [1 - (k % 3) as i32, (k % 2) as i32, -((k % 5 == 0) as i32)];
                let n = std::array::from_fn(|d| if periodic[d] { n[d] } else { 0 });
                let w = simbox.image_vector(&n);
                *p = [p[0] + w[0], p[1] + w[1], p[2] + w[2]];
            }
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
    fn the_largest_displacement_is_found_in_any_lane_and_in_the_tail() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        for n in 1..=11 {
            let a: Vec<[f64; 3]> = (0..n).map(|_| [rng.gen(), rng.gen(), rng.gen()]).collect();
            for largest in 0..n {
                let mut b: Vec<[f64; 3]> = a
                    .iter()
                    .map(|p| p.map(|c| c + 0.1 * rng.gen::<f64>()))
                    .collect();
                b[largest][1] -= 0.5;
                let expected = a
                    .iter()
                    .zip(&b)
                    .map(|(p, q)| (0..3).map(|d| (p[d] - q[d]).powi(2)).sum::<f64>())
                    .fold(0.0, f64::max)
                    .sqrt();
                assert!(expected > 0.4);
                assert_eq!(
                    max_displacement(&a, &b),
                    expected,
                    "{n} points, largest {largest}"
                );
            }
        }
        assert_eq!(max_displacement(&[], &[]), 0.0);
        // As `f64::max` does, a NaN distance is passed over and an infinite
        // one kept, in a lane or in the tail (the run's own finiteness
        // check catches both).
        let a = vec![[0.0; 3]; 6];
        for at in [1, 5] {
            let mut b = vec![[0.0, 0.25, 0.0]; 6];
            b[at] = [f64::NAN, 0.0, 0.0];
            assert_eq!(max_displacement(&a, &b), 0.25);
            b[at] = [f64::INFINITY, 0.0, 0.0];
            assert_eq!(max_displacement(&a, &b), f64::INFINITY);
        }
    }

    #[test]
    fn a_blown_up_atom_is_binned_without_overflow_and_pairs_with_nothing() {
        let simbox = SimBox {
            lo: [0.0; 3],
            lengths: [6.0; 3],
            tilt: [0.0; 3],
            periodic: [true, true, false],
        };
        let mut x = vec![[1.0, 1.0, 1.0], [1.5, 1.0, 1.0], [3.0, 3.0, 3.0]];
        x.push([f64::NEG_INFINITY, 1.0, 2.0]);
        let mut list = NeighbourList::default();
        list.build(&simbox, &x, 1.0, 0.0, None);
        assert_eq!(listed(&list, x.len()), vec![(0, 1)]);
    }

    #[test]
    fn the_list_is_the_same_on_any_number_of_threads() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let simbox = SimBox {
            lo: [0.0; 3],
            lengths: [9.0, 8.0, 7.0],
            tilt: [0.7, -0.4, 0.3],
            periodic: [true, true, false],
        };
        let x: Vec<[f64; 3]> = (0..1001)
            .map(|_| simbox.to_cartesian(&[rng.gen(), rng.gen(), rng.gen()]))
            .collect();
        let bonds = Exclusions::from_pairs(x.len(), (0..500).map(|k| (2 * k, 2 * k + 1)));
        let mut one = NeighbourList::default();
        one.build(&simbox, &x, 1.0, 0.3, Some(&bonds));
        assert!(
            one.neighbours.len() > 3000,
            "{} pairs",
            one.neighbours.len()
        );
        for threads in [2, 3, 4] {
            let mut many = NeighbourList::default();
            many.build_on(&Team::new(threads), &simbox, &x, 1.0, 0.3, Some(&bonds));
            assert_eq!(many.offsets, one.offsets, "{threads} threads");
            assert_eq!(many.neighbours, one.neighbours, "{threads} threads");
            // A second build into the same list reuses its parts.
            many.build_on(&Team::new(threads), &simbox, &x, 1.0, 0.3, Some(&bonds));
            assert_eq!(many.neighbours, one.neighbours, "{threads} threads, again");
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

    fn closed_grain(seed: u64) -> (SimBox, Vec<[f64; 3]>) {
        let simbox = SimBox {
            lo: [-20.0; 3],
            lengths: [40.0; 3],
            tilt: [0.0; 3],
            periodic: [false; 3],
        };
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let x = (0..200)
            .map(|_| [0.0; 3].map(|_: f64| rng.gen_range(-3.0..3.0)))
            .collect();
        (simbox, x)
    }

    fn turned(x: &[[f64; 3]], angle: f64, shift: [f64; 3]) -> Vec<[f64; 3]> {
        let (s, c) = angle.sin_cos();
        x.iter()
            .map(|p| {
                [
                    c * p[0] - s * p[1] + shift[0],
                    s * p[0] + c * p[1] + shift[1],
                    p[2] + shift[2],
                ]
            })
            .collect()
    }

    #[test]
    fn rigid_motion_in_a_closed_box_keeps_the_list_and_it_stays_exact() {
        let (simbox, x) = closed_grain(3);
        let mut list = NeighbourList::default();
        list.build(&simbox, &x, 1.0, 0.3, None);
        // A turn of 0.2 rad moves points 3 d out by 0.6 d, far beyond the
        // skin; done in steps, the reference re-anchors whenever the plain
        // test fails (about every other step).
        let mut current = x.clone();
        for step in 1..=10 {
            current = turned(&x, 0.02 * step as f64, [0.05 * step as f64, 0.0, -0.1]);
            assert!(
                !list.needs_rebuild(&simbox, &current, 0.3, &Team::new(1)),
                "step {step}"
            );
        }
        assert_eq!(list.builds, 1);
        assert!(list.reanchors >= 4, "{} re-anchorings", list.reanchors);
        // Every pair within the cutoff is still listed.
        let listed_now = listed(&list, x.len());
        for pair in brute_force(&simbox, &current, 1.0) {
            assert!(listed_now.binary_search(&pair).is_ok(), "{pair:?} lost");
        }
        // Without the rigid fit the same motion forces a rebuild.
        let mut plain = NeighbourList {
            follow_rigid_motion: false,
            ..NeighbourList::default()
        };
        plain.build(&simbox, &x, 1.0, 0.3, None);
        assert!(plain.needs_rebuild(&simbox, &turned(&x, 0.1, [0.0; 3]), 0.3, &Team::new(1)));
    }

    #[test]
    fn deformation_beyond_half_the_skin_still_rebuilds() {
        let (simbox, x) = closed_grain(4);
        let mut list = NeighbourList::default();
        list.build(&simbox, &x, 1.0, 0.3, None);
        let mut moved = turned(&x, 0.3, [1.0, 0.0, 0.0]);
        moved[17][2] += 0.16;
        assert!(list.needs_rebuild(&simbox, &moved, 0.3, &Team::new(1)));
        moved[17][2] -= 0.02;
        assert!(!list.needs_rebuild(&simbox, &moved, 0.3, &Team::new(1)));
    }

    #[test]
    fn periodic_boxes_do_not_discount_rotation() {
        let (mut simbox, x) = closed_grain(5);
        simbox.periodic = [true, true, false];
        let x: Vec<[f64; 3]> = x.iter().map(|p| [p[0] + 20.0, p[1] + 20.0, p[2]]).collect();
        let mut list = NeighbourList::default();
        list.build(&simbox, &x, 1.0, 0.3, None);
        let centre: Vec<[f64; 3]> = x.iter().map(|p| [p[0] - 20.0, p[1] - 20.0, p[2]]).collect();
        let back: Vec<[f64; 3]> = turned(&centre, 0.05, [20.0, 20.0, 0.0]);
        assert!(list.needs_rebuild(&simbox, &back, 0.3, &Team::new(1)));
    }
}
