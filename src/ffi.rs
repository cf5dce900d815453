//! The C ABI of the kernels: the only `extern "C"` functions in the crate.
//!
//! Each call works on a whole bond list or neighbour list. Inputs are
//! checked before any work (null pointers, indices, types), panics are
//! caught, and the result is a status code, never an unwind into C++.
//! The declarations are in `lammps-plugin/bpm_kernels.h`.

use crate::kernels::{
    accumulate_reference_volumes, accumulate_volumes, bond_forces, pair_forces, BondCoeffs,
    BondEntry, BondInputs, Ownership, PairCoeffs, PairInputs, Tally, Unwrapped, NEIGHMASK,
};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::slice;

/// Success.
pub const BPM_OK: i32 = 0;
/// A required pointer was null or a count negative.
pub const BPM_ERR_NULL: i32 = 1;
/// An atom index was outside `0..nall`.
pub const BPM_ERR_INDEX: i32 = 2;
/// A bond or atom type had no coefficients.
pub const BPM_ERR_TYPE: i32 = 3;
/// A Rust panic was caught (a bug: please report).
pub const BPM_ERR_PANIC: i32 = 4;

fn guard(f: impl FnOnce() -> i32) -> i32 {
    catch_unwind(AssertUnwindSafe(f)).unwrap_or(BPM_ERR_PANIC)
}

unsafe fn rows<'a>(p: *const f64, n: usize) -> &'a [[f64; 3]] {
    if n == 0 {
        &[]
    } else {
        slice::from_raw_parts(p as *const [f64; 3], n)
    }
}

unsafe fn opt_rows<'a>(p: *const f64, n: usize) -> Option<&'a [[f64; 3]]> {
    (!p.is_null()).then(|| rows(p, n))
}

unsafe fn list<'a, T>(p: *const T, n: usize) -> &'a [T] {
    if n == 0 {
        &[]
    } else {
        slice::from_raw_parts(p, n)
    }
}

fn check_bonds(bonds: &[BondEntry], nall: usize, ntypes: usize) -> i32 {
    for b in bonds {
        if b.i < 0 || b.j < 0 || b.i as usize >= nall || b.j as usize >= nall {
            return BPM_ERR_INDEX;
        }
        if b.ty < 1 || b.ty as usize > ntypes {
            return BPM_ERR_TYPE;
        }
    }
    BPM_OK
}

fn counts(values: &[i64]) -> Option<Vec<usize>> {
    values.iter().map(|&v| usize::try_from(v).ok()).collect()
}

/// Adds `r^3` (into `vol`) and `r0^3` (into `vol0`, if not null) of each bond
/// to its atoms; see [`accumulate_volumes`].
///
/// # Safety
/// `x` holds `3 nall` doubles; `bonds` `nbonds` rows; `r0` `nbonds`
/// doubles; `vol` and `vol0` `nall` doubles each.
#[no_mangle]
pub unsafe extern "C" fn bpm_bond_volumes(
    x: *const f64,
    nall: i64,
    bonds: *const BondEntry,
    nbonds: i64,
    r0: *const f64,
    n_owned: i64,
    newton: i32,
    vol: *mut f64,
    vol0: *mut f64,
) -> i32 {
    guard(|| {
        let Some([nall, nbonds, n_owned]) =
            counts(&[nall, nbonds, n_owned]).map(|c| [c[0], c[1], c[2]])
        else {
            return BPM_ERR_NULL;
        };
        if (nall > 0 && (x.is_null() || vol.is_null()))
            || (nbonds > 0 && (bonds.is_null() || r0.is_null()))
        {
            return BPM_ERR_NULL;
        }
        let bonds = list(bonds, nbonds);
        let status = check_bonds(bonds, nall, i32::MAX as usize);
        if status != BPM_OK {
            return status;
        }
        let own = Ownership {
            n_owned,
            newton: newton != 0,
        };
        let x = rows(x, nall);
        accumulate_volumes(
            &Unwrapped,
            x,
            bonds,
            own,
            slice::from_raw_parts_mut(vol, nall),
        );
        if !vol0.is_null() {
            accumulate_reference_volumes(
                bonds,
                list(r0, nbonds),
                own,
                slice::from_raw_parts_mut(vol0, nall),
            );
        }
        BPM_OK
    })
}

/// Adds bond forces to `f` and writes energy and virial to `tally` (a
/// null `tally`, for steps that record nothing, is not written; with
/// `newton` on, the sums are then skipped too); see
/// [`bond_forces`]. A null `v` drops damping; null `vol` drops the
/// multibody term.
///
/// # Safety
/// Array sizes as for [`bpm_bond_volumes`]; `coeffs` holds `ncoeffs`
/// entries (index = type - 1); `f` holds `3 nall` doubles; `tally` is
/// null or valid.
#[no_mangle]
pub unsafe extern "C" fn bpm_bond_forces(
    x: *const f64,
    v: *const f64,
    nall: i64,
    bonds: *const BondEntry,
    nbonds: i64,
    r0: *const f64,
    coeffs: *const BondCoeffs,
    ncoeffs: i64,
    vol: *const f64,
    vol0: *const f64,
    n_owned: i64,
    newton: i32,
    f: *mut f64,
    tally: *mut Tally,
) -> i32 {
    guard(|| {
        let Some([nall, nbonds, ncoeffs, n_owned]) =
            counts(&[nall, nbonds, ncoeffs, n_owned]).map(|c| [c[0], c[1], c[2], c[3]])
        else {
            return BPM_ERR_NULL;
        };
        if (nall > 0 && (x.is_null() || f.is_null()))
            || (nbonds > 0 && (bonds.is_null() || r0.is_null() || coeffs.is_null()))
            || (!vol.is_null() && vol0.is_null())
        {
            return BPM_ERR_NULL;
        }
        let bonds = list(bonds, nbonds);
        let status = check_bonds(bonds, nall, ncoeffs);
        if status != BPM_OK {
            return status;
        }
        let volumes = (!vol.is_null()).then(|| (list(vol, nall), list(vol0, nall)));
        let inputs = BondInputs {
            x: rows(x, nall),
            v: opt_rows(v, nall),
            bonds,
            r0: list(r0, nbonds),
            coeffs: list(coeffs, ncoeffs),
            volumes,
            tally: !tally.is_null(),
        };
        let own = Ownership {
            n_owned,
            newton: newton != 0,
        };
        let f = slice::from_raw_parts_mut(f as *mut [f64; 3], nall);
        let sums = bond_forces(&Unwrapped, &inputs, own, f);
        if let Some(tally) = tally.as_mut() {
            *tally = sums;
        }
        BPM_OK
    })
}

/// Adds pair forces over a LAMMPS half neighbour list to `f` and writes
/// energy and virial to `tally` (a null `tally` skips summing and writing
/// them); see
/// [`pair_forces`]. A null `v` drops damping; a null `types` means all
/// atoms are type 1.
///
/// # Safety
/// `ilist` and `numneigh` hold `inum` entries, `firstneigh[ilist[k]]`
/// points to `numneigh[ilist[k]]` neighbour indices; `coeffs` holds
/// `ntypes^2` entries; `special` holds 4 doubles; other arrays as above.
#[no_mangle]
pub unsafe extern "C" fn bpm_pair_forces(
    x: *const f64,
    v: *const f64,
    types: *const i32,
    nall: i64,
    ntypes: i64,
    coeffs: *const PairCoeffs,
    inum: i64,
    ilist: *const i32,
    numneigh: *const i32,
    firstneigh: *const *const i32,
    special: *const f64,
    n_owned: i64,
    newton: i32,
    f: *mut f64,
    tally: *mut Tally,
) -> i32 {
    guard(|| {
        let Some([nall, ntypes, inum, n_owned]) =
            counts(&[nall, ntypes, inum, n_owned]).map(|c| [c[0], c[1], c[2], c[3]])
        else {
            return BPM_ERR_NULL;
        };
        if special.is_null() || coeffs.is_null() || ntypes == 0 {
            return BPM_ERR_NULL;
        }
        if inum > 0
            && (x.is_null()
                || f.is_null()
                || ilist.is_null()
                || numneigh.is_null()
                || firstneigh.is_null())
        {
            return BPM_ERR_NULL;
        }
        let ilist = list(ilist, inum);
        let types = (!types.is_null()).then(|| list(types, nall));
        // Validate every row first, so the pass itself needs no allocation.
        for &i in ilist {
            if i < 0 || i as usize >= nall {
                return BPM_ERR_INDEX;
            }
            let count = *numneigh.add(i as usize);
            let first = *firstneigh.add(i as usize);
            if count < 0 || (count > 0 && first.is_null()) {
                return BPM_ERR_NULL;
            }
            if list(first, count as usize)
                .iter()
                .any(|&j| (j & NEIGHMASK) as usize >= nall)
            {
                return BPM_ERR_INDEX;
            }
        }
        let rows_in = ilist.iter().map(|&i| {
            let i = i as usize;
            // SAFETY: checked above: i < nall, count >= 0, first non-null when count > 0.
            let js = unsafe { list(*firstneigh.add(i), *numneigh.add(i) as usize) };
            (i, js)
        });
        if let Some(t) = types {
            if t.iter().any(|&t| t < 1 || t as usize > ntypes) {
                return BPM_ERR_TYPE;
            }
        }
        let special = list(special, 4);
        let inputs = PairInputs {
            x: rows(x, nall),
            v: opt_rows(v, nall),
            types,
            ntypes,
            coeffs: list(coeffs, ntypes * ntypes),
            special: [special[0], special[1], special[2], special[3]],
            tally: !tally.is_null(),
        };
        let own = Ownership {
            n_owned,
            newton: newton != 0,
        };
        let f = slice::from_raw_parts_mut(f as *mut [f64; 3], nall);
        let sums = pair_forces(&Unwrapped, &inputs, rows_in, own, f);
        if let Some(tally) = tally.as_mut() {
            *tally = sums;
        }
        BPM_OK
    })
}

/// Force over distance (`fforce`, LAMMPS's convention) and spring-proxy
/// energy of one bond, for LAMMPS's `Bond::single`: the force
/// [`bond_forces`] gives that bond without damping (`single()` gets no
/// velocities), with the multibody term of `dilation` (the shim passes
/// `r / r0`, which leaves the term out: `single()` gets no volumes).
///
/// # Safety
/// `coeffs` and `fforce` must be valid pointers.
#[no_mangle]
pub unsafe extern "C" fn bpm_bond_single(
    r: f64,
    r0: f64,
    dilation: f64,
    coeffs: *const BondCoeffs,
    fforce: *mut f64,
) -> f64 {
    if coeffs.is_null() || fforce.is_null() || r <= 0.0 || r0 <= 0.0 {
        return 0.0;
    }
    let c = &*coeffs;
    *fforce = crate::kernels::bond_force_magnitude(r, r0, dilation, 0.0, c) / r;
    0.5 * c.k * (r - r0) * (r - r0)
}
