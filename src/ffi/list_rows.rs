//! The C ABI of a bond list kept as rows ([`ListRows`]): the drop-in bond
//! styles' pass for one bond type on steps without energy or virial. The
//! caller owns the rows through an opaque pointer, syncs them with its
//! list each step (they are built anew only when the list changed), and
//! then runs the volume and force passes on them.

use super::bond_failure::{FailureCounts, RawBondFailure};
use super::{guard, list, list_mut, opt_rows, report, rows};
use super::{BPM_ERR_INDEX, BPM_ERR_NULL, BPM_ERR_STALE, BPM_ERR_TYPE, BPM_OK};
use crate::kernels::{BondCoeffs, BondEntry, Fault, ListRows, ListRowsError, ListStamp};

/// New rows of no list, for [`bpm_list_rows_sync`]; free them with
/// [`bpm_list_rows_destroy`].
#[no_mangle]
pub extern "C" fn bpm_list_rows_create() -> *mut ListRows {
    Box::into_raw(Box::new(ListRows::new()))
}

/// Frees rows from [`bpm_list_rows_create`] (null: nothing).
///
/// # Safety
/// `rows` is null or from [`bpm_list_rows_create`], not freed before.
#[no_mangle]
pub unsafe extern "C" fn bpm_list_rows_destroy(rows: *mut ListRows) {
    if !rows.is_null() {
        drop(Box::from_raw(rows));
    }
}

/// Makes `rows` those of the list unless they already are: see
/// [`ListRows::sync`]. `builds` and `edits` are the caller's counts of
/// neighbour builds and of its own changes to the list; `plastic` is null
/// when no bond yields. `*stale` (if not null) gets 1 when the reference
/// volumes must be summed and set before the next pass with the multibody
/// term. `BPM_ERR_TYPE` for an entry of a type above 1, `BPM_ERR_INDEX`
/// for an atom outside `0..nall`.
///
/// # Safety
/// `rows` from [`bpm_list_rows_create`]; `bonds` `nbonds` entries; `r0`
/// and `plastic` (if not null) `nbonds` doubles.
#[no_mangle]
pub unsafe extern "C" fn bpm_list_rows_sync(
    rows: *mut ListRows,
    builds: i64,
    edits: i64,
    bonds: *const BondEntry,
    nbonds: i64,
    r0: *const f64,
    plastic: *const f64,
    nall: i64,
    stale: *mut i32,
) -> i32 {
    guard(|| {
        let (Some(rows), Ok(entries), Ok(atoms)) = (
            rows.as_mut(),
            usize::try_from(nbonds),
            usize::try_from(nall),
        ) else {
            return BPM_ERR_NULL;
        };
        if entries > 0 && (bonds.is_null() || r0.is_null()) {
            return BPM_ERR_NULL;
        }
        let plastic = if plastic.is_null() {
            &[][..]
        } else {
            list(plastic, entries)
        };
        let stamp = ListStamp {
            builds,
            edits,
            entries,
            atoms,
        };
        match rows.sync(stamp, list(bonds, entries), list(r0, entries), plastic) {
            Ok(needs) => {
                if let Some(stale) = stale.as_mut() {
                    *stale = i32::from(needs);
                }
                BPM_OK
            }
            Err(ListRowsError::Type { .. }) => BPM_ERR_TYPE,
            Err(ListRowsError::Lengths { .. }) => BPM_ERR_NULL,
            Err(ListRowsError::Rows(_)) => BPM_ERR_INDEX,
        }
    })
}

/// The multibody term's volumes from the rows: `V` of atoms `0..ngather`
/// into `vol`, and with `vol0` not null their `V0` (rest lengths) into
/// `vol0`; see [`ListRows::volumes`] (`newton == 0`: ghosts get their
/// owners' values, none is summed into owners, so that after breaks only
/// the atoms of broken bonds need summing). `BPM_ERR_STALE` if the rows
/// were synced with another `nall`, or `ngather` exceeds it.
///
/// # Safety
/// `rows` from [`bpm_list_rows_create`]; `x` `3 nall` doubles; `vol` and
/// `vol0` (if not null) `ngather` doubles.
#[no_mangle]
pub unsafe extern "C" fn bpm_list_rows_volumes(
    rows: *mut ListRows,
    x: *const f64,
    nall: i64,
    ngather: i64,
    newton: i32,
    vol: *mut f64,
    vol0: *mut f64,
) -> i32 {
    guard(|| {
        let (Some(rows), Ok(nall), Ok(ngather)) = (
            rows.as_mut(),
            usize::try_from(nall),
            usize::try_from(ngather),
        ) else {
            return BPM_ERR_NULL;
        };
        if nall > 0 && (x.is_null() || vol.is_null()) {
            return BPM_ERR_NULL;
        }
        if rows.atoms() != Some(nall) || ngather > nall {
            return BPM_ERR_STALE;
        }
        let vol = list_mut(vol, ngather);
        let vol0 = (!vol0.is_null()).then(|| list_mut(vol0, ngather));
        rows.volumes(self::rows(x, nall), vol, vol0, newton == 0);
        BPM_OK
    })
}

/// Sets the rows' reference volumes from `vol0` (every atom's `V0`,
/// ghosts included); see [`ListRows::set_reference_volumes`].
///
/// # Safety
/// `rows` from [`bpm_list_rows_create`]; `vol0` `nall` doubles.
#[no_mangle]
pub unsafe extern "C" fn bpm_list_rows_set_reference(
    rows: *mut ListRows,
    vol0: *const f64,
    nall: i64,
) -> i32 {
    guard(|| {
        let (Some(rows), Ok(nall)) = (rows.as_mut(), usize::try_from(nall)) else {
            return BPM_ERR_NULL;
        };
        if nall > 0 && vol0.is_null() {
            return BPM_ERR_NULL;
        }
        match rows.set_reference_volumes(list(vol0, nall)) {
            Ok(()) => BPM_OK,
            Err(_) => BPM_ERR_STALE,
        }
    })
}

/// Adds the rows' forces to atoms `0..ngather` of `f`, as
/// `bpm_failing_bond_forces` does for a list of one bond type without
/// energy or virial; see [`ListRows::forces`]. `vol` null drops the
/// multibody term; `BPM_ERR_STALE` if the rows were synced with another
/// list or `nall`, `ngather` exceeds `nall`, or the term is asked for
/// before this step's volumes or the reference volumes were set. Bonds that break get type 0 in `bonds` and their indices go
/// to `broken` (in list order); `plastic` (null when the rule does not
/// yield) gets the new `e_p` of bonds that yield.
///
/// # Safety
/// `rows` from [`bpm_list_rows_create`]; `x`, `v` (if not null), `f` and
/// `vol` (if not null) as for `bpm_failing_bond_forces` (`f` at least
/// `ngather` atoms); `bonds`, `plastic` (if not null) and `broken` the
/// `nbonds` entries the rows were synced with.
#[no_mangle]
pub unsafe extern "C" fn bpm_list_rows_forces(
    rows: *mut ListRows,
    x: *const f64,
    v: *const f64,
    nall: i64,
    coeffs: *const BondCoeffs,
    rule: *const RawBondFailure,
    may_break: i32,
    vol: *const f64,
    ngather: i64,
    f: *mut f64,
    bonds: *mut BondEntry,
    nbonds: i64,
    plastic: *mut f64,
    broken: *mut i32,
    found: *mut FailureCounts,
    fault: *mut Fault,
) -> i32 {
    guard(|| {
        let (Some(rows), Some(coeffs), Some(rule)) = (
            rows.as_mut(),
            coeffs.as_ref(),
            rule.as_ref().map(|r| r.rule()),
        ) else {
            return BPM_ERR_NULL;
        };
        let (Ok(nall), Ok(ngather), Ok(entries)) = (
            usize::try_from(nall),
            usize::try_from(ngather),
            usize::try_from(nbonds),
        ) else {
            return BPM_ERR_NULL;
        };
        let yields = rule.plastic_strain.is_some();
        if (nall > 0 && (x.is_null() || f.is_null()))
            || (entries > 0 && (bonds.is_null() || broken.is_null()))
            || (yields && entries > 0 && plastic.is_null())
        {
            return BPM_ERR_NULL;
        }
        if rule.check().is_err() {
            return BPM_ERR_TYPE;
        }
        if rows.atoms() != Some(nall)
            || rows.entries() != Some(entries)
            || ngather > nall
            || (!vol.is_null() && !rows.ready_for_multibody())
        {
            return BPM_ERR_STALE;
        }
        let plastic = if yields {
            list_mut(plastic, entries)
        } else {
            &mut [][..]
        };
        let pass = rows.forces(
            self::rows(x, nall),
            opt_rows(v, nall),
            (!vol.is_null()).then(|| list(vol, nall)),
            *coeffs,
            &rule,
            may_break != 0,
            list_mut(f as *mut [f64; 3], ngather),
            list_mut(bonds, entries),
            plastic,
            list_mut(broken, entries),
        );
        if let Some(found) = found.as_mut() {
            *found = FailureCounts {
                broken: pass.broken as i64,
                yielded: pass.yielded as i64,
            };
        }
        report(&pass.pass, std::ptr::null_mut(), fault)
    })
}
