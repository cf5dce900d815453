//! Fragments of a bonded body: the groups of particles its intact bonds
//! still hold together (the connected components of the bond graph).

use petgraph::unionfind::UnionFind;
use serde::{Deserialize, Serialize};

/// The fragments of `particles` particles joined by `bonds`, largest first.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Fragments {
    /// Particles in all.
    pub particles: usize,
    /// The sizes (in particles) of the fragments of two particles or
    /// more, largest first.
    pub sizes: Vec<usize>,
    /// Particles no intact bond holds: fragments of one.
    pub single_particles: usize,
}

impl Fragments {
    /// The fragments of particles `0..particles` over `bonds` (pairs of
    /// indices below `particles`).
    ///
    /// # Panics
    /// If a bond names an index at or above `particles`.
    pub fn of(particles: usize, bonds: impl IntoIterator<Item = [usize; 2]>) -> Self {
        let mut groups = UnionFind::<usize>::new(particles);
        for [i, j] in bonds {
            groups.union(i, j);
        }
        let mut members = vec![0usize; particles];
        for root in groups.into_labeling() {
            members[root] += 1;
        }
        let mut sizes: Vec<usize> = members.into_iter().filter(|&m| m >= 2).collect();
        sizes.sort_unstable_by(|a, b| b.cmp(a));
        let single_particles = particles - sizes.iter().sum::<usize>();
        Self {
            particles,
            sizes,
            single_particles,
        }
    }

    /// The fragments of each group of particles (`group[i]` is particle
    /// `i`'s, `0..groups`) over `bonds`, which join particles of one group
    /// (a grain's bonds): one union over all, counted group by group.
    ///
    /// # Panics
    /// If a bond or a group index is out of range.
    pub fn by_group(
        group: &[u32],
        groups: usize,
        bonds: impl IntoIterator<Item = [usize; 2]>,
    ) -> Vec<Self> {
        let n = group.len();
        let mut union = UnionFind::<usize>::new(n);
        for [i, j] in bonds {
            union.union(i, j);
        }
        let labels = union.into_labeling();
        let mut members = vec![0usize; n];
        for &root in &labels {
            members[root] += 1;
        }
        let mut out = vec![
            Self {
                particles: 0,
                sizes: Vec::new(),
                single_particles: 0,
            };
            groups
        ];
        for (i, &g) in group.iter().enumerate() {
            let f = &mut out[g as usize];
            f.particles += 1;
            match members[i] {
                0 => {}
                1 => f.single_particles += 1,
                m => f.sizes.push(m),
            }
        }
        for f in &mut out {
            f.sizes.sort_unstable_by(|a, b| b.cmp(a));
        }
        out
    }

    /// Fragments, single particles included.
    pub fn count(&self) -> usize {
        self.sizes.len() + self.single_particles
    }

    /// Fragments of at least `min` particles.
    pub fn count_at_least(&self, min: usize) -> usize {
        if min <= 1 {
            return self.count();
        }
        self.sizes.iter().filter(|&&s| s >= min).count()
    }

    /// The largest fragment's share of the particles (0 for none).
    pub fn largest_fraction(&self) -> f64 {
        let largest = self
            .sizes
            .first()
            .copied()
            .unwrap_or(usize::from(self.single_particles > 0));
        if self.particles == 0 {
            0.0
        } else {
            largest as f64 / self.particles as f64
        }
    }
}

/// How far the grains of a packing have come apart: each grain's
/// fragments over its intact bonds, as shares and averages over the
/// grains.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct GrainFragments {
    /// Share of the bonds broken.
    pub broken_fraction: f64,
    /// Share of the grains still in one piece.
    pub whole_grains: f64,
    /// Each grain's largest fragment's share of the grain, averaged over
    /// the grains.
    pub largest_fragment: f64,
    /// Fragments of two particles or more per grain, on average.
    pub fragments_per_grain: f64,
    /// Share of the particles no intact bond holds.
    pub loose_particles: f64,
}

impl GrainFragments {
    /// Of particles in grains `group` (`0..groups`), joined by `bonds`
    /// before any broke, of which `broken` (either order) have broken.
    /// A bond between two grains (a packing file may have one) holds no
    /// grain together and is left out of the fragments.
    pub fn of(group: &[u32], groups: usize, bonds: &[[usize; 2]], broken: &[[usize; 2]]) -> Self {
        let key = |[i, j]: [usize; 2]| (i.min(j), i.max(j));
        let gone: std::collections::HashSet<(usize, usize)> =
            broken.iter().map(|&b| key(b)).collect();
        let intact = bonds
            .iter()
            .copied()
            .filter(|&[i, j]| group[i] == group[j])
            .filter(|&b| !gone.contains(&key(b)));
        let grains: Vec<Fragments> = Fragments::by_group(group, groups, intact)
            .into_iter()
            .filter(|f| f.particles > 0)
            .collect();
        let count = grains.len().max(1) as f64;
        let particles = group.len().max(1) as f64;
        Self {
            broken_fraction: gone.len() as f64 / bonds.len().max(1) as f64,
            whole_grains: grains.iter().filter(|f| f.count() == 1).count() as f64 / count,
            largest_fragment: grains.iter().map(Fragments::largest_fraction).sum::<f64>() / count,
            fragments_per_grain: grains.iter().map(|f| f.sizes.len()).sum::<usize>() as f64 / count,
            loose_particles: grains.iter().map(|f| f.single_particles).sum::<usize>() as f64
                / particles,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A chain of four, a pair, a triangle closed twice and two loose
    /// particles: sizes 4, 3, 2 and two singles, whatever the bonds' order.
    #[test]
    fn components_are_counted_and_sorted() {
        let bonds = [
            [0, 1],
            [1, 2],
            [2, 3],
            [5, 6],
            [7, 8],
            [8, 9],
            [9, 7],
            [7, 9],
        ];
        let f = Fragments::of(11, bonds);
        assert_eq!(f.sizes, vec![4, 3, 2]);
        assert_eq!(f.single_particles, 2); // 4 and 10
        assert_eq!(f.count(), 5);
        assert_eq!(f.count_at_least(3), 2);
        assert_eq!(f.count_at_least(1), 5);
        assert!((f.largest_fraction() - 4.0 / 11.0).abs() < 1e-15);
        let mut reversed = bonds;
        reversed.reverse();
        assert_eq!(Fragments::of(11, reversed), f);
    }

    /// Two grains, one whole and one split in two, counted apart; the
    /// same as each grain's fragments on its own.
    #[test]
    fn fragments_are_counted_grain_by_grain() {
        let group = [0, 0, 0, 1, 1, 1, 1, 1];
        let bonds = [[0, 1], [1, 2], [3, 4], [5, 6], [6, 7]];
        let f = Fragments::by_group(&group, 2, bonds);
        assert_eq!(f[0], Fragments::of(3, [[0, 1], [1, 2]]));
        assert_eq!(f[1], Fragments::of(5, [[0, 1], [2, 3], [3, 4]]));
        assert_eq!((f[1].sizes.clone(), f[1].single_particles), (vec![3, 2], 0));
        assert_eq!(Fragments::by_group(&[0, 0], 2, [])[1].particles, 0);
    }

    /// Two triangles; one loses a bond (still whole), the other two
    /// (a pair and a loose particle).
    #[test]
    fn grains_coming_apart() {
        let group = [0, 0, 0, 1, 1, 1];
        let bonds = [[0, 1], [1, 2], [2, 0], [3, 4], [4, 5], [5, 3]];
        let none = GrainFragments::of(&group, 2, &bonds, &[]);
        assert_eq!((none.broken_fraction, none.whole_grains), (0.0, 1.0));
        assert_eq!(
            (none.largest_fragment, none.fragments_per_grain),
            (1.0, 1.0)
        );
        let some = GrainFragments::of(&group, 2, &bonds, &[[1, 0], [4, 5], [3, 5]]);
        assert_eq!(some.broken_fraction, 0.5);
        assert_eq!(some.whole_grains, 0.5);
        assert!((some.largest_fragment - 0.5 * (1.0 + 2.0 / 3.0)).abs() < 1e-15);
        assert_eq!(some.fragments_per_grain, 1.0);
        assert!((some.loose_particles - 1.0 / 6.0).abs() < 1e-15);
    }

    /// One body with no bond broken is one fragment; with none left, every
    /// particle is its own.
    #[test]
    fn whole_and_dust() {
        let whole = Fragments::of(3, [[0, 1], [1, 2]]);
        assert_eq!((whole.count(), whole.largest_fraction()), (1, 1.0));
        let dust = Fragments::of(3, []);
        assert_eq!(dust.count(), 3);
        assert!((dust.largest_fraction() - 1.0 / 3.0).abs() < 1e-15);
        assert_eq!(Fragments::of(0, []).largest_fraction(), 0.0);
    }
}
