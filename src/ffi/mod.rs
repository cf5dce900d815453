//! The C ABI of the kernels: the only `extern "C"` functions in the crate.
//!
//! Each call works on a whole bond list or neighbour list. Inputs are
//! checked before any work (null pointers, indices, types), panics are
//! caught, and the result is a status code, never an unwind into C++.
//! The declarations are in `lammps-plugin/bpm_kernels.h`.

use crate::kernels::{
    accumulate_multibody_sums, accumulate_reference_volumes, accumulate_volumes, balance_multibody,
    bond_forces, pair_forces, BondCoeffs, BondEntry, BondInputs, Fault, FaultKind, ForcePass,
    MultibodyInputs, MultibodySum, Ownership, PairCoeffs, PairInputs, Tally, Unwrapped, NEIGHMASK,
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
/// The forces were computed, but an interaction was outside the model's
/// range ([`Fault`], written to the `fault` argument): the run is blowing up.
pub const BPM_ERR_UNSTABLE: i32 = 5;
/// A pass stopped before its end; the message written says why (a
/// multi-contact correction beyond the model's range, a full contact row,
/// a bad coefficient).
pub const BPM_ERR_STOPPED: i32 = 6;
/// Rows kept between steps ([`crate::kernels::ListRows`]) were used with a
/// list or atom count other than the one they were synced with, or without
/// the reference volumes the pass needs.
pub const BPM_ERR_STALE: i32 = 7;

mod bond_failure;
mod granular;
mod list_rows;
pub use bond_failure::{
    bpm_check_bond_failure, bpm_failing_bond_forces, bpm_failing_bond_single,
    bpm_intact_bond_volumes, FailureCounts, RawBondFailure,
};
pub use granular::{parse_coeffs, GranularStyle, GranularStyleCoeffs, DEFAULT_SLOTS};
pub use list_rows::{
    bpm_list_rows_create, bpm_list_rows_destroy, bpm_list_rows_forces, bpm_list_rows_set_reference,
    bpm_list_rows_sync, bpm_list_rows_volumes,
};

/// Writes the first fault of `pass` to `fault` (if not null) and returns
/// the status of the call.
unsafe fn report(pass: &ForcePass, tally: *mut Tally, fault: *mut Fault) -> i32 {
    if let Some(t) = tally.as_mut() {
        *t = pass.tally;
    }
    match pass.fault {
        None => BPM_OK,
        Some(found) => {
            if !fault.is_null() {
                // A write, not a reference: the caller's memory may hold
                // no valid fault yet.
                fault.write(found);
            }
            BPM_ERR_UNSTABLE
        }
    }
}

// `bpm_fault` in bpm_kernels.h has this layout (checked there too).
const _: () = assert!(std::mem::size_of::<Fault>() == 56 && std::mem::align_of::<Fault>() == 8);
const _: () = assert!(std::mem::size_of::<RawFault>() == 56);

pub(crate) fn guard(f: impl FnOnce() -> i32) -> i32 {
    catch_unwind(AssertUnwindSafe(f)).unwrap_or(BPM_ERR_PANIC)
}

pub(crate) unsafe fn rows<'a>(p: *const f64, n: usize) -> &'a [[f64; 3]] {
    if n == 0 {
        &[]
    } else {
        slice::from_raw_parts(p as *const [f64; 3], n)
    }
}

unsafe fn opt_rows<'a>(p: *const f64, n: usize) -> Option<&'a [[f64; 3]]> {
    (!p.is_null()).then(|| rows(p, n))
}

pub(crate) unsafe fn list<'a, T>(p: *const T, n: usize) -> &'a [T] {
    if n == 0 {
        &[]
    } else {
        slice::from_raw_parts(p, n)
    }
}

/// [`list`], writable: `n` values at `p` (empty when `n` is 0, whatever `p`).
pub(crate) unsafe fn list_mut<'a, T>(p: *mut T, n: usize) -> &'a mut [T] {
    if n == 0 {
        &mut []
    } else {
        slice::from_raw_parts_mut(p, n)
    }
}

/// The rows of a LAMMPS neighbour list (`ilist`, `numneigh`,
/// `firstneigh`) as `(i, neighbour indices)`, each row checked first
/// (indices below `nall`, counts not negative, pointers not null), so the
/// passes over it need neither checks nor allocation.
///
/// # Safety
/// `numneigh` and `firstneigh` hold an entry for every index in `ilist`
/// below `nall`, and each `firstneigh[i]` points to `numneigh[i]` ints.
pub(crate) unsafe fn half_list<'a>(
    ilist: &'a [i32],
    numneigh: *const i32,
    firstneigh: *const *const i32,
    nall: usize,
) -> Result<impl Iterator<Item = (usize, &'a [i32])> + Clone + 'a, i32> {
    for &i in ilist {
        if i < 0 || i as usize >= nall {
            return Err(BPM_ERR_INDEX);
        }
        let count = *numneigh.add(i as usize);
        let first = *firstneigh.add(i as usize);
        if count < 0 || (count > 0 && first.is_null()) {
            return Err(BPM_ERR_NULL);
        }
        if list(first, count as usize)
            .iter()
            .any(|&j| (j & NEIGHMASK) as usize >= nall)
        {
            return Err(BPM_ERR_INDEX);
        }
    }
    Ok(ilist.iter().map(move |&i| {
        let i = i as usize;
        // SAFETY: checked above: i < nall, count >= 0, first non-null when count > 0.
        let js = unsafe { list(*firstneigh.add(i), *numneigh.add(i) as usize) };
        (i, js)
    }))
}

fn check_bonds(bonds: &[BondEntry], nall: usize, ntypes: usize) -> i32 {
    check_bond_list(bonds, nall, 1, ntypes)
}

fn check_bond_atoms(bonds: &[BondEntry], nall: usize) -> i32 {
    check_bond_list(bonds, nall, i32::MIN, usize::MAX)
}

/// `BPM_ERR_INDEX` if an atom index of `bonds` lies outside `0..nall`,
/// else `BPM_ERR_TYPE` if a type lies outside `min_type..=max_type`, else
/// `BPM_OK`. Runs every step on every bond, so it is one pass without a
/// branch per bond: unsigned comparisons (a negative index wraps past any
/// count) folded with `|`, which the compiler keeps in vector registers.
pub(crate) fn check_bond_list(
    bonds: &[BondEntry],
    nall: usize,
    min_type: i32,
    max_type: usize,
) -> i32 {
    // Any i32 index is below 2^31 and any negative one, as u32, at or
    // above it: a larger count changes nothing.
    let nall = nall.min(1 << 31) as u32;
    let max_type = i32::try_from(max_type).unwrap_or(i32::MAX);
    let (outside, bad_type) = bonds.iter().fold((false, false), |(o, t), b| {
        (
            o | (b.i as u32 >= nall) | (b.j as u32 >= nall),
            t | (b.ty < min_type) | (b.ty > max_type),
        )
    });
    if outside {
        BPM_ERR_INDEX
    } else if bad_type {
        BPM_ERR_TYPE
    } else {
        BPM_OK
    }
}

/// Writes `message` into `buf` (`len` bytes) as a NUL-terminated string,
/// cut to fit.
///
/// # Safety
/// `buf` is null or holds `len` bytes.
pub(crate) unsafe fn write_message(message: &str, buf: *mut std::ffi::c_char, len: i64) {
    if buf.is_null() || len <= 0 {
        return;
    }
    let bytes = message.as_bytes();
    let n = bytes.len().min(len as usize - 1);
    std::ptr::copy_nonoverlapping(bytes.as_ptr(), buf as *mut u8, n);
    *buf.add(n) = 0;
}

pub(crate) fn counts(values: &[i64]) -> Option<Vec<usize>> {
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
    fault: *mut Fault,
) -> i32 {
    guard(|| {
        let Some([nall, nbonds, ncoeffs, n_owned]) =
            counts(&[nall, nbonds, ncoeffs, n_owned]).map(|c| [c[0], c[1], c[2], c[3]])
        else {
            return BPM_ERR_NULL;
        };
        if (nall > 0 && (x.is_null() || f.is_null()))
            || (nbonds > 0 && (bonds.is_null() || r0.is_null()))
            || (ncoeffs > 0 && coeffs.is_null())
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
        report(&bond_forces(&Unwrapped, &inputs, own, f), tally, fault)
    })
}

/// Adds each bond's multibody force and a count of 1 to the sums
/// `[Mx, My, Mz, N]` (4 doubles per atom) of its atoms, as owned; the first
/// pass of the zero-net-multibody variant, see
/// [`accumulate_multibody_sums`]. Needs complete volumes on every atom.
///
/// # Safety
/// Array sizes as for [`bpm_bond_forces`]; `vol` and `vol0` hold `nall`
/// doubles, `sums` `4 nall`.
#[no_mangle]
pub unsafe extern "C" fn bpm_multibody_sums(
    x: *const f64,
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
    sums: *mut f64,
) -> i32 {
    guard(|| {
        let Some([nall, nbonds, ncoeffs, n_owned]) =
            counts(&[nall, nbonds, ncoeffs, n_owned]).map(|c| [c[0], c[1], c[2], c[3]])
        else {
            return BPM_ERR_NULL;
        };
        if (nall > 0 && (x.is_null() || vol.is_null() || vol0.is_null() || sums.is_null()))
            || (nbonds > 0 && (bonds.is_null() || r0.is_null()))
            || (ncoeffs > 0 && coeffs.is_null())
        {
            return BPM_ERR_NULL;
        }
        let bonds = list(bonds, nbonds);
        let status = check_bonds(bonds, nall, ncoeffs);
        if status != BPM_OK {
            return status;
        }
        let inputs = MultibodyInputs {
            x: rows(x, nall),
            bonds,
            r0: list(r0, nbonds),
            coeffs: list(coeffs, ncoeffs),
            volumes: (list(vol, nall), list(vol0, nall)),
        };
        let own = Ownership {
            n_owned,
            newton: newton != 0,
        };
        let sums = slice::from_raw_parts_mut(sums as *mut MultibodySum, nall);
        accumulate_multibody_sums(&Unwrapped, &inputs, own, sums);
        BPM_OK
    })
}

/// Adds the zero-net-multibody correction of every bond to `f` from the
/// complete sums of [`bpm_multibody_sums`] on all atoms (ghosts included),
/// and writes its virial (no energy) to `tally` if not null; see
/// [`balance_multibody`].
///
/// # Safety
/// `x` and `f` hold `3 nall` doubles, `sums` `4 nall`, `bonds` `nbonds`
/// rows; `tally` is null or valid.
#[no_mangle]
pub unsafe extern "C" fn bpm_balance_multibody(
    x: *const f64,
    nall: i64,
    bonds: *const BondEntry,
    nbonds: i64,
    sums: *const f64,
    n_owned: i64,
    newton: i32,
    f: *mut f64,
    tally: *mut Tally,
) -> i32 {
    guard(|| {
        let Some([nall, nbonds, n_owned]) =
            counts(&[nall, nbonds, n_owned]).map(|c| [c[0], c[1], c[2]])
        else {
            return BPM_ERR_NULL;
        };
        if (nall > 0 && (x.is_null() || sums.is_null() || f.is_null()))
            || (nbonds > 0 && bonds.is_null())
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
        let sums = list(sums as *const MultibodySum, nall);
        let f = slice::from_raw_parts_mut(f as *mut [f64; 3], nall);
        let sum = balance_multibody(
            &Unwrapped,
            rows(x, nall),
            bonds,
            sums,
            own,
            f,
            !tally.is_null(),
        );
        if let Some(t) = tally.as_mut() {
            *t = sum;
        }
        BPM_OK
    })
}

/// Adds pair forces over a LAMMPS half neighbour list to `f` and writes
/// energy and virial to `tally` (a null `tally` skips summing and writing
/// them); see
/// [`pair_forces`]. A null `v` drops damping; a null `types` means all
/// atoms are type 1. `damping_taper != 0` fades the damping as upstream
/// LAMMPS's `pair_style bpm/spring` does ([`PairInputs::damping_taper`]).
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
    damping_taper: i32,
    n_owned: i64,
    newton: i32,
    f: *mut f64,
    tally: *mut Tally,
    fault: *mut Fault,
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
        let rows_in = match half_list(ilist, numneigh, firstneigh, nall) {
            Ok(rows) => rows,
            Err(status) => return status,
        };
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
            damping_taper: damping_taper != 0,
        };
        let own = Ownership {
            n_owned,
            newton: newton != 0,
        };
        let f = slice::from_raw_parts_mut(f as *mut [f64; 3], nall);
        report(
            &pair_forces(&Unwrapped, &inputs, rows_in, own, f),
            tally,
            fault,
        )
    })
}

/// Force over distance (`fforce`, LAMMPS's convention) and spring-proxy
/// energy of one bond, for LAMMPS's `Bond::single`: the force
/// [`bond_forces`] gives that bond without damping (`single()` gets no
/// velocities), with the multibody term of `dilation` (the shim passes
/// `r * (1 / r0)`, which leaves the term out: `single()` gets no volumes).
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

/// [`Fault`] as C hands it back: every field a plain number, checked before
/// use.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct RawFault {
    /// [`FaultKind`] code.
    pub kind: i32,
    /// First particle (local index).
    pub i: i64,
    /// Second particle (local index).
    pub j: i64,
    /// Their distance.
    pub r: f64,
    /// Reference length or contact distance.
    pub reference: f64,
    /// Non-zero for a bond.
    pub bonded: u8,
    /// The bond's position in its list (-1 for a pair).
    pub bond: i64,
}

/// Writes the message for a fault the force calls reported (what happened
/// at `step`, naming the atoms `name_i` and `name_j`, and the likely cause
/// at timestep `dt` with the bond coefficients of the interaction (null
/// for a pair) and the first atom's `mass`) into `buf` as a NUL-terminated
/// string cut to `len` bytes. Returns the full message length in bytes, or
/// a negative status.
///
/// # Safety
/// `fault` points to a fault; `bond` is null or valid; `buf` holds `len`
/// bytes.
#[no_mangle]
pub unsafe extern "C" fn bpm_describe_fault(
    fault: *const RawFault,
    name_i: i64,
    name_j: i64,
    step: i64,
    dt: f64,
    bond: *const BondCoeffs,
    mass: f64,
    buf: *mut std::ffi::c_char,
    len: i64,
) -> i64 {
    if fault.is_null() || buf.is_null() || len <= 0 {
        return -(BPM_ERR_NULL as i64);
    }
    let raw = *fault;
    let Some(kind) = FaultKind::from_code(raw.kind) else {
        return -(BPM_ERR_TYPE as i64);
    };
    let found = Fault {
        kind,
        i: raw.i,
        j: raw.j,
        r: raw.r,
        reference: raw.reference,
        bonded: raw.bonded != 0,
        bond: raw.bond,
    };
    let bond = bond.as_ref();
    let Ok(message) = catch_unwind(|| {
        format!(
            "simulation became unstable at step {step}: {}. Likely cause: {}",
            found.what(&format!("atoms with IDs {name_i} and {name_j}")),
            found.likely_cause(dt, bond, mass, f64::NAN)
        )
    }) else {
        return -(BPM_ERR_PANIC as i64);
    };
    let bytes = message.as_bytes();
    let n = bytes.len().min(len as usize - 1);
    std::ptr::copy_nonoverlapping(bytes.as_ptr(), buf as *mut u8, n);
    *buf.add(n) = 0;
    bytes.len() as i64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bond_list_is_refused_for_the_first_index_or_type_out_of_range() {
        let bond = |i, j, ty| BondEntry { i, j, ty };
        let ok = [bond(0, 1, 1), bond(2, 1, 2)];
        assert_eq!(check_bond_list(&ok, 3, 1, 2), BPM_OK);
        assert_eq!(check_bond_list(&ok, 2, 1, 2), BPM_ERR_INDEX);
        assert_eq!(check_bond_list(&ok, 3, 1, 1), BPM_ERR_TYPE);
        // A negative index is outside whatever the count, even beyond i32.
        for nall in [3, 1 << 31, usize::MAX] {
            for bad in [-1, -2, i32::MIN] {
                let list = [bond(0, 1, 1), bond(1, bad, 1)];
                assert_eq!(
                    check_bond_list(&list, nall, 1, 2),
                    BPM_ERR_INDEX,
                    "{nall} {bad}"
                );
            }
        }
        // An index error wins over a type error; broken bonds (type 0)
        // pass where the minimum allows them.
        assert_eq!(check_bond_list(&[bond(0, 5, 9)], 3, 1, 2), BPM_ERR_INDEX);
        assert_eq!(check_bond_list(&[bond(0, 1, 0)], 3, 1, 2), BPM_ERR_TYPE);
        assert_eq!(check_bond_list(&[bond(0, 1, 0)], 3, i32::MIN, 2), BPM_OK);
    }
}
