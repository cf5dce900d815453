//! Per-atom volume proxies `V_i = sum_bonds r_ij^3` (docs/model.md).
//!
//! Only ratios of volumes enter the force, so the constant prefactor of a
//! sphere's volume is dropped. With `newton` on, a bond adds to both atoms
//! including ghosts (the caller sums ghost parts back to owners); with it
//! off, only owned atoms are written, and every rank that holds the bond
//! computes it, so each owner still sees all of its bonds.

use super::bond::BondEntry;
use super::tally::Ownership;
use super::{dot, Separation};

/// Adds `r^3` of every bond to both of its atoms' current volume proxy.
pub fn accumulate_volumes<S: Separation>(
    sep: &S,
    x: &[[f64; 3]],
    bonds: &[BondEntry],
    own: Ownership,
    vol: &mut [f64],
) {
    for bond in bonds {
        let (i, j) = (bond.i as usize, bond.j as usize);
        let del = sep.delta(&x[i], &x[j]);
        let rsq = dot(&del, &del);
        let r3 = rsq * rsq.sqrt();
        add_to_both(vol, i, j, r3, own);
    }
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
