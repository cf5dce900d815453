//! The zero-net-multibody variant of the bond force (docs/model.md,
//! "Variant: zero net multibody force").
//!
//! In the plain model the multibody term of bond `ij`, `m_ij n_ij` with
//! `m_ij = a (D_ij - r / r0)`, is a central pair force, and its sum over a
//! particle's bonds, `M_i = sum_j m_ij n_ij`, need not vanish: a particle
//! whose neighbours sit unevenly around it is pushed by its own volume
//! term. The variant removes that push. Half of each bond's multibody force
//! is taken as exerted by each of its two particles, and what particle `i`
//! exerts is shifted by the same vector on every bond so that it sums to
//! zero. Bond `ij` then acts on `i` with
//!
//! `m_ij n_ij - (M_i / N_i - M_j / N_j) / 2`
//!
//! and on `j` with the opposite (`N_i` is the number of bonds of `i`), so
//! momentum is still conserved; the correction is not central, so angular
//! momentum is not. A particle's own multibody sum `M_i` is replaced by
//! `M_i / 2 + sum_j M_j / (2 N_j)`.
//!
//! The plain bond pass computes `m_ij n_ij`; this module adds the two passes
//! the variant needs between and after it: the per-particle sums
//! `(M_i, N_i)` ([`accumulate_multibody_sums`], which a caller with ghost
//! atoms communicates like the volumes), and the correction
//! ([`balance_multibody`]).

use super::bond::{dilation, reciprocal, BondCoeffs, BondEntry};
use super::tally::{Ownership, Tally};
use super::{dot, Separation};

/// Per particle: the vector sum of its bonds' multibody forces on it, and
/// its number of bonds (a float, so the four values communicate as one row).
pub type MultibodySum = [f64; 4];

/// Everything the sum pass reads: as [`super::BondInputs`] without
/// velocities, with the volumes required.
#[derive(Clone, Copy, Debug)]
pub struct MultibodyInputs<'a> {
    /// Positions of owned and ghost atoms.
    pub x: &'a [[f64; 3]],
    /// The bonds.
    pub bonds: &'a [BondEntry],
    /// Reference length of each bond, aligned with `bonds`.
    pub r0: &'a [f64],
    /// Coefficients per bond type (`coeffs[ty - 1]`).
    pub coeffs: &'a [BondCoeffs],
    /// Current and reference volume proxies `(V, V0)` per atom.
    pub volumes: (&'a [f64], &'a [f64]),
}

/// Adds every bond's multibody force `m_ij n_ij` to `sums[i]` (and its
/// opposite to `sums[j]`), and 1 to both bond counts, for the atoms the
/// caller applies forces to (`own`, as in the bond pass).
pub fn accumulate_multibody_sums<S: Separation>(
    sep: &S,
    inputs: &MultibodyInputs,
    own: Ownership,
    sums: &mut [MultibodySum],
) {
    let (vol, vol0) = inputs.volumes;
    for (bond, &r0) in inputs.bonds.iter().zip(inputs.r0) {
        let (i, j) = (bond.i as usize, bond.j as usize);
        let c = &inputs.coeffs[(bond.ty - 1) as usize];
        let del = sep.delta(&inputs.x[i], &inputs.x[j]);
        let r = dot(&del, &del).sqrt();
        let m = c.a * (dilation(vol[i], vol[j], vol0[i], vol0[j]) - r * reciprocal(r0));
        let s = m / r;
        let (on_i, on_j, _) = own.split(i, j);
        if on_i {
            add(&mut sums[i], [s * del[0], s * del[1], s * del[2]], 1.0);
        }
        if on_j {
            add(&mut sums[j], [-s * del[0], -s * del[1], -s * del[2]], 1.0);
        }
    }
}

#[inline(always)]
fn add(sum: &mut MultibodySum, force: [f64; 3], count: f64) {
    sum[0] += force[0];
    sum[1] += force[1];
    sum[2] += force[2];
    sum[3] += count;
}

/// The mean multibody force `M_i / N_i` of a particle (zero without bonds).
#[inline(always)]
fn mean(sum: &MultibodySum) -> [f64; 3] {
    if sum[3] > 0.0 {
        [sum[0] / sum[3], sum[1] / sum[3], sum[2] / sum[3]]
    } else {
        [0.0; 3]
    }
}

/// Adds the correction `-(M_i / N_i - M_j / N_j) / 2` of every bond to `i`
/// and its opposite to `j` (as owned), from complete sums on both atoms
/// (ghosts included), and returns its virial when `tally` is set. The
/// correction has no energy.
pub fn balance_multibody<S: Separation>(
    sep: &S,
    x: &[[f64; 3]],
    bonds: &[BondEntry],
    sums: &[MultibodySum],
    own: Ownership,
    f: &mut [[f64; 3]],
    tally: bool,
) -> Tally {
    let mut sum = Tally::default();
    for bond in bonds {
        let (i, j) = (bond.i as usize, bond.j as usize);
        let (mi, mj) = (mean(&sums[i]), mean(&sums[j]));
        let c = [
            -0.5 * (mi[0] - mj[0]),
            -0.5 * (mi[1] - mj[1]),
            -0.5 * (mi[2] - mj[2]),
        ];
        let (on_i, on_j, fraction) = own.split(i, j);
        if on_i {
            for k in 0..3 {
                f[i][k] += c[k];
            }
        }
        if on_j {
            for k in 0..3 {
                f[j][k] -= c[k];
            }
        }
        if tally {
            sum.add_vector(fraction, &sep.delta(&x[i], &x[j]), &c);
        }
    }
    sum
}
