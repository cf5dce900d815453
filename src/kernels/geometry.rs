//! How the separation vector between two particles is formed.

/// Forms `r_ij = x_i - x_j` for two stored positions.
///
/// The kernels are generic over this so that the minimum-image convention of
/// the native engine and LAMMPS's ghost atoms (already the right image) share
/// one compiled loop each, with no branch on the convention per interaction.
pub trait Separation: Sync {
    /// Whether [`Separation::delta`] is the plain difference `x_i - x_j`,
    /// so that vector code may form it directly.
    const PLAIN: bool = false;

    /// The separation vector `x_i - x_j` under this convention.
    fn delta(&self, xi: &[f64; 3], xj: &[f64; 3]) -> [f64; 3];

    /// The distance `|x_i - x_j|` under this convention.
    #[inline]
    fn distance(&self, xi: &[f64; 3], xj: &[f64; 3]) -> f64 {
        let d = self.delta(xi, xj);
        super::dot(&d, &d).sqrt()
    }

    /// The minimum-image convention this separation follows, if it is one:
    /// vector code then forms four separations at once, with the same
    /// operations as [`Separation::delta`].
    #[inline(always)]
    fn minimum_image(&self) -> Option<&MinimumImage> {
        None
    }
}

/// Positions are already the interacting images (LAMMPS ghost atoms, or an
/// open box): the separation is the plain difference.
#[derive(Clone, Copy, Debug, Default)]
pub struct Unwrapped;

impl Separation for Unwrapped {
    const PLAIN: bool = true;

    #[inline(always)]
    fn delta(&self, xi: &[f64; 3], xj: &[f64; 3]) -> [f64; 3] {
        super::sub(xi, xj)
    }
}

/// Rounds to the nearest integer (ties to even) with two additions, valid
/// for |x| < 2^51: SSE2 has no rounding instruction and a libm call per
/// bond would dominate the bond loop.
#[inline(always)]
pub(crate) fn round_nearest(x: f64) -> f64 {
    (x + ROUNDING_MAGIC) - ROUNDING_MAGIC
}

/// `2^52 + 2^51`: adding it leaves no fraction bits (see [`round_nearest`]).
pub(crate) const ROUNDING_MAGIC: f64 = 6_755_399_441_055_744.0;

/// The minimum-image convention of a periodic box (LAMMPS's
/// restricted-triclinic vectors `a = (lx, 0, 0)`, `b = (xy, ly, 0)`,
/// `c = (xz, yz, lz)`), prepared for hot loops: inverse lengths are
/// precomputed and open dimensions have inverse 0, so the separation is
/// computed without branches.
#[derive(Clone, Copy, Debug)]
pub struct MinimumImage {
    pub(crate) lengths: [f64; 3],
    pub(crate) tilt: [f64; 3],
    pub(crate) inv: [f64; 3],
}

impl MinimumImage {
    /// The convention of a box with edge `lengths`, `tilt` factors
    /// `xy, xz, yz`, and periodicity per dimension.
    pub fn new(lengths: [f64; 3], tilt: [f64; 3], periodic: [bool; 3]) -> Self {
        let inv = std::array::from_fn(|d| if periodic[d] { 1.0 / lengths[d] } else { 0.0 });
        Self { lengths, tilt, inv }
    }

    /// The minimum-image separation `x_i - (x_j + h k)` and the image `k`
    /// of `j` it picks (as floats), for quantities that depend on which
    /// image interacts, such as the velocity of a Lees-Edwards image.
    #[inline(always)]
    pub fn delta_image(&self, xi: &[f64; 3], xj: &[f64; 3]) -> ([f64; 3], [f64; 3]) {
        let [lx, ly, lz] = self.lengths;
        let [xy, xz, yz] = self.tilt;
        let mut dx = xi[0] - xj[0];
        let mut dy = xi[1] - xj[1];
        let mut dz = xi[2] - xj[2];
        let kz = round_nearest(dz * self.inv[2]);
        dz -= kz * lz;
        dy -= kz * yz;
        dx -= kz * xz;
        let ky = round_nearest(dy * self.inv[1]);
        dy -= ky * ly;
        dx -= ky * xy;
        let kx = round_nearest(dx * self.inv[0]);
        dx -= kx * lx;
        ([dx, dy, dz], [kx, ky, kz])
    }
}

impl Separation for MinimumImage {
    /// Minimum image in LAMMPS's order: z, then y, then x.
    #[inline(always)]
    fn delta(&self, xi: &[f64; 3], xj: &[f64; 3]) -> [f64; 3] {
        self.delta_image(xi, xj).0
    }

    #[inline(always)]
    fn minimum_image(&self) -> Option<&MinimumImage> {
        Some(self)
    }
}

/// [`MinimumImage`] of a box without tilt: each dimension is imaged on its
/// own, so the three roundings do not wait on one another. In the contact
/// pass of a jammed packing the general image's chain of roundings (z,
/// then y, then x, each correcting the next dimension by the tilt) was a
/// quarter of the instructions, and the pass took 1.5 times as long with
/// it (results/bench/issue33-contact-image).
///
/// For finite positions the separations are those of [`MinimumImage`] bit
/// for bit, but for the sign of a component that is exactly zero: the tilt
/// terms it subtracts are products with zero, and subtracting `-0.0` turns
/// `-0.0` into `0.0`. It serves scalar loops: the bond rows' vector code
/// reads a [`MinimumImage`] ([`Separation::minimum_image`]) and would form
/// this type's separations one at a time.
#[derive(Clone, Copy, Debug)]
pub struct OrthogonalImage {
    lengths: [f64; 3],
    inv: [f64; 3],
}

impl OrthogonalImage {
    /// The convention of `image`, if its box has no tilt.
    pub fn of(image: &MinimumImage) -> Option<Self> {
        (image.tilt == [0.0; 3]).then_some(Self {
            lengths: image.lengths,
            inv: image.inv,
        })
    }
}

impl OrthogonalImage {
    /// [`MinimumImage::delta_image`] for a box without tilt.
    #[inline(always)]
    pub fn delta_image(&self, xi: &[f64; 3], xj: &[f64; 3]) -> ([f64; 3], [f64; 3]) {
        let mut image = [0.0; 3];
        let del = std::array::from_fn(|d| {
            let dd = xi[d] - xj[d];
            image[d] = round_nearest(dd * self.inv[d]);
            dd - image[d] * self.lengths[d]
        });
        (del, image)
    }
}

impl Separation for OrthogonalImage {
    #[inline(always)]
    fn delta(&self, xi: &[f64; 3], xj: &[f64; 3]) -> [f64; 3] {
        self.delta_image(xi, xj).0
    }
}

/// The minimum image a pass uses for its box: [`OrthogonalImage`] when it
/// has no tilt. The bonded contact pass and the neighbour search match on
/// it once and run a loop compiled for each; the DEM passes, which also
/// need each pair's image, keep it as one type, and a branch per pair that
/// always goes the same way costs less than the triclinic image's chain of
/// roundings.
#[derive(Clone, Copy, Debug)]
pub enum BoxImage {
    /// A tilted box.
    Tilted(MinimumImage),
    /// A box without tilt.
    Orthogonal(OrthogonalImage),
}

impl BoxImage {
    /// The image of `image`'s box: orthogonal if it has no tilt.
    pub fn of(image: &MinimumImage) -> Self {
        OrthogonalImage::of(image).map_or(BoxImage::Tilted(*image), BoxImage::Orthogonal)
    }

    /// [`MinimumImage::delta_image`].
    #[inline(always)]
    pub fn delta_image(&self, xi: &[f64; 3], xj: &[f64; 3]) -> ([f64; 3], [f64; 3]) {
        match self {
            BoxImage::Tilted(image) => image.delta_image(xi, xj),
            BoxImage::Orthogonal(image) => image.delta_image(xi, xj),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn orthogonal_image_gives_the_minimum_image_bit_for_bit() {
        let periodic = [true, false, true];
        let full = MinimumImage::new([7.0, 5.5, 3.25], [0.0; 3], periodic);
        let split = OrthogonalImage::of(&full).expect("no tilt");
        let tilted = MinimumImage::new([7.0, 5.5, 3.25], [0.5, 0.0, 0.0], periodic);
        assert!(OrthogonalImage::of(&tilted).is_none());
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 * 30.0 - 15.0
        };
        let either = BoxImage::of(&full);
        assert!(matches!(either, BoxImage::Orthogonal(_)));
        assert!(matches!(BoxImage::of(&tilted), BoxImage::Tilted(_)));
        let bits = |(del, image): ([f64; 3], [f64; 3])| (del.map(f64::to_bits), image);
        for _ in 0..10_000 {
            let (xi, xj) = ([next(), next(), next()], [next(), next(), next()]);
            let general = bits(full.delta_image(&xi, &xj));
            assert_eq!(general, bits(split.delta_image(&xi, &xj)), "{xi:?} {xj:?}");
            assert_eq!(general, bits(either.delta_image(&xi, &xj)), "{xi:?} {xj:?}");
            assert_eq!(general.0, split.delta(&xi, &xj).map(f64::to_bits));
        }
    }

    #[test]
    fn branchless_rounding_matches_round_half_even() {
        for x in [
            -2.5,
            -1.5,
            -0.5000001,
            -0.49,
            0.0,
            0.49,
            0.5,
            1.5,
            2.5,
            3.7,
            -1e6 - 0.2,
        ] {
            assert_eq!(round_nearest(x), x.round_ties_even(), "{x}");
        }
    }
}
