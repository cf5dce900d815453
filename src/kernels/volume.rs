//! Per-atom volume proxies `V_i = sum_bonds r_ij^3` (docs/model.md).
//!
//! Only ratios of volumes enter the force, so the constant prefactor of a
//! sphere's volume is dropped. With `newton` on, a bond adds to both atoms
//! including ghosts (the caller sums ghost parts back to owners); with it
//! off, only owned atoms are written, and every rank that holds the bond
//! computes it, so each owner still sees all of its bonds.

use super::bond::{BondEntry, LANES};
use super::isa::Isa;
use super::tally::{Ownership, RunningSum};
use super::{dot, Separation};

/// Adds `r^3` of every bond to both of its atoms' current volume proxy.
///
/// Runs on the widest instruction set this processor has; see
/// [`accumulate_volumes_on`].
pub fn accumulate_volumes<S: Separation>(
    sep: &S,
    x: &[[f64; 3]],
    bonds: &[BondEntry],
    own: Ownership,
    vol: &mut [f64],
) {
    accumulate_volumes_on(Isa::detect(), sep, x, bonds, own, vol)
}

/// [`accumulate_volumes`] compiled for `isa` (the portable build when this
/// processor lacks it); every build gives the same volumes bit for bit.
pub fn accumulate_volumes_on<S: Separation>(
    isa: Isa,
    sep: &S,
    x: &[[f64; 3]],
    bonds: &[BondEntry],
    own: Ownership,
    vol: &mut [f64],
) {
    #[cfg(target_arch = "x86_64")]
    if isa == Isa::Avx2 && Isa::Avx2.available() {
        // SAFETY: the processor has AVX2 and FMA (checked just above).
        return unsafe { volumes_avx2(sep, x, bonds, own, vol) };
    }
    let _ = isa;
    volume_blocks(sep, x, bonds, own, vol)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn volumes_avx2<S: Separation>(
    sep: &S,
    x: &[[f64; 3]],
    bonds: &[BondEntry],
    own: Ownership,
    vol: &mut [f64],
) {
    volume_blocks(sep, x, bonds, own, vol)
}

/// Blocks of [`LANES`] bonds, as in the bond pass: separations gathered,
/// `r^3` computed lane by lane (the square roots in vector instructions),
/// then added to the atoms in bond order, as a scalar loop would (each
/// first atom's sum held over its run of bonds, [`RunningSum`]).
#[inline(always)]
fn volume_blocks<S: Separation>(
    sep: &S,
    x: &[[f64; 3]],
    bonds: &[BondEntry],
    own: Ownership,
    vol: &mut [f64],
) {
    let mut rsq = [0.0; LANES];
    let mut r3 = [0.0; LANES];
    let mut run = RunningSum::new();
    for block in bonds.chunks(LANES) {
        for (l, bond) in block.iter().enumerate() {
            let del = sep.delta(&x[bond.i as usize], &x[bond.j as usize]);
            rsq[l] = dot(&del, &del);
        }
        for l in 0..LANES {
            r3[l] = rsq[l] * rsq[l].sqrt();
        }
        for (l, bond) in block.iter().enumerate() {
            let (i, j) = (bond.i as usize, bond.j as usize);
            let (on_i, on_j, _) = own.split(i, j);
            let vi = run.first(i, vol);
            if on_i {
                *vi += r3[l];
            }
            if on_j {
                *run.second(j, vol) += r3[l];
            }
        }
    }
    run.finish(vol);
}

/// Adds `r0^3` of every bond to both of its atoms' reference volume proxy.
pub fn accumulate_reference_volumes(
    bonds: &[BondEntry],
    r0: &[f64],
    own: Ownership,
    vol0: &mut [f64],
) {
    for (bond, &r0) in bonds.iter().zip(r0) {
        add_to_both(vol0, bond.i as usize, bond.j as usize, r0 * r0 * r0, own);
    }
}

#[inline(always)]
fn add_to_both(vol: &mut [f64], i: usize, j: usize, value: f64, own: Ownership) {
    let (on_i, on_j, _) = own.split(i, j);
    if on_i {
        vol[i] += value;
    }
    if on_j {
        vol[j] += value;
    }
}
