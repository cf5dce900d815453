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
