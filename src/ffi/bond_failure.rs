//! The C ABI of bonds that break and yield, for the plugin's
//! `bpm/spring/rs` and `bpm/spring/plastic/rs` bond styles; see
//! [`failing_list_forces`].

use super::{
    check_bond_atoms, check_bond_list, counts, guard, list, list_mut, opt_rows, report, rows,
    write_message,
};
use super::{BPM_ERR_NULL, BPM_ERR_STOPPED, BPM_ERR_TYPE, BPM_OK};
use crate::kernels::{
    accumulate_intact_volumes, failing_bond_energy, failing_bond_force, failing_list_forces,
    BondCoeffs, BondEntry, BondFailure, FailingListInputs, Fault, Ownership, Tally, Unwrapped,
};
use std::ffi::c_char;
use std::slice;

/// [`BondFailure`] as C passes it (`bpm_bond_failure`).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct RawBondFailure {
    /// `eps_c`.
    pub critical_strain: f64,
    /// `eps_p`, read when `yields` is not 0.
    pub plastic_strain: f64,
    /// Non-zero: bonds break.
    pub breaks: i32,
    /// Non-zero: the force is smoothed towards `eps_c`.
    pub smooth: i32,
    /// Non-zero: the spring acts on the strain.
    pub normalize: i32,
    /// Non-zero: bonds yield at `eps_p`.
    pub yields: i32,
}

impl RawBondFailure {
    pub(super) fn rule(&self) -> BondFailure {
        BondFailure {
            critical_strain: self.critical_strain,
            breaks: self.breaks != 0,
            smooth: self.smooth != 0,
            plastic_strain: (self.yields != 0).then_some(self.plastic_strain),
            normalize: self.normalize != 0,
        }
    }
}

/// What a failing pass found besides forces (`bpm_failure_counts`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct FailureCounts {
    /// Bonds that broke: their list indices lead the caller's buffer.
    pub broken: i64,
    /// Bonds whose plastic strain changed.
    pub yielded: i64,
}

/// `BPM_OK` if the model can use `rule`; else `BPM_ERR_STOPPED` with the
/// reason, naming the value, in `message` (`len` bytes).
///
/// # Safety
/// `rule` is null or valid; `message` is null or holds `len` bytes.
#[no_mangle]
pub unsafe extern "C" fn bpm_check_bond_failure(
    rule: *const RawBondFailure,
    message: *mut c_char,
    len: i64,
) -> i32 {
    guard(|| {
        let Some(rule) = rule.as_ref() else {
            return BPM_ERR_NULL;
        };
        match rule.rule().check() {
            Ok(()) => BPM_OK,
            Err(why) => {
                write_message(&why.to_string(), message, len);
                BPM_ERR_STOPPED
            }
        }
    })
}

/// Adds `r^3` of each intact bond (type above 0) to `vol` and `r_eq^3` to
/// `vol0`; see [`accumulate_intact_volumes`]. A null `plastic` means every
/// `e_p` is 0.
///
/// # Safety
/// `x`, `vol`, `vol0` as for `bpm_bond_volumes`; `plastic` null or
/// `nbonds` doubles.
#[no_mangle]
pub unsafe extern "C" fn bpm_intact_bond_volumes(
    x: *const f64,
    nall: i64,
    bonds: *const BondEntry,
    nbonds: i64,
    r0: *const f64,
    plastic: *const f64,
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
        if (nall > 0 && (x.is_null() || vol.is_null() || vol0.is_null()))
            || (nbonds > 0 && (bonds.is_null() || r0.is_null()))
        {
            return BPM_ERR_NULL;
        }
        let bonds = list(bonds, nbonds);
        let status = check_bond_atoms(bonds, nall);
        if status != BPM_OK {
            return status;
        }
        let plastic = if plastic.is_null() {
            &[][..]
        } else {
            list(plastic, nbonds)
        };
        accumulate_intact_volumes(
            &Unwrapped,
            rows(x, nall),
            bonds,
            (list(r0, nbonds), plastic),
            Ownership {
                n_owned,
                newton: newton != 0,
            },
            (
                slice::from_raw_parts_mut(vol, nall),
                slice::from_raw_parts_mut(vol0, nall),
            ),
        );
        BPM_OK
    })
}

/// Bond types whose rules [`bpm_failing_bond_forces`] converts on the stack.
const FEW_TYPES: usize = 16;

/// Adds the forces of the intact bonds (type above 0) to `f`; see
/// [`failing_list_forces`]. Bonds that break get type 0 in `bonds` and
/// their indices go to `broken` (`nbonds` slots); `plastic` (null when no
/// rule yields) holds each bond's `e_p`, updated. `rules[type - 1]` and
/// `coeffs[type - 1]` belong to bond type `type`; `may_break == 0` keeps
/// every bond (a run's set-up). Counts go to `counts` (if not null),
/// energy and virial to `tally` (if not null), the first bond out of range
/// to `fault` (status `BPM_ERR_UNSTABLE`).
///
/// # Safety
/// Array sizes as for `bpm_bond_forces`; `rules` holds `ncoeffs` entries,
/// `plastic` and `broken` `nbonds` each.
#[no_mangle]
pub unsafe extern "C" fn bpm_failing_bond_forces(
    x: *const f64,
    v: *const f64,
    nall: i64,
    bonds: *mut BondEntry,
    nbonds: i64,
    r0: *const f64,
    plastic: *mut f64,
    coeffs: *const BondCoeffs,
    rules: *const RawBondFailure,
    ncoeffs: i64,
    may_break: i32,
    vol: *const f64,
    vol0: *const f64,
    n_owned: i64,
    newton: i32,
    f: *mut f64,
    broken: *mut i32,
    found: *mut FailureCounts,
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
            || (nbonds > 0 && (bonds.is_null() || r0.is_null() || broken.is_null()))
            || (ncoeffs > 0 && (coeffs.is_null() || rules.is_null()))
            || (!vol.is_null() && vol0.is_null())
        {
            return BPM_ERR_NULL;
        }
        // The rules of the usual few bond types live on the stack: no
        // allocation per step.
        let raw = list(rules, ncoeffs);
        let mut few = [BondFailure::breaking(1.0); FEW_TYPES];
        let many: Vec<BondFailure>;
        let rules: &[BondFailure] = if ncoeffs <= FEW_TYPES {
            for (rule, raw) in few.iter_mut().zip(raw) {
                *rule = raw.rule();
            }
            &few[..ncoeffs]
        } else {
            many = raw.iter().map(|r| r.rule()).collect();
            &many
        };
        if rules.iter().any(|r| r.check().is_err()) {
            return BPM_ERR_TYPE;
        }
        let yields = rules.iter().any(|r| r.plastic_strain.is_some());
        if yields && nbonds > 0 && plastic.is_null() {
            return BPM_ERR_NULL;
        }
        let bonds = list_mut(bonds, nbonds);
        // Types 0 and below are bonds already broken: skipped, not refused.
        let status = check_bond_list(bonds, nall, i32::MIN, ncoeffs);
        if status != BPM_OK {
            return status;
        }
        let inputs = FailingListInputs {
            x: rows(x, nall),
            v: opt_rows(v, nall),
            r0: list(r0, nbonds),
            coeffs: list(coeffs, ncoeffs),
            rules,
            may_break: may_break != 0,
            volumes: (!vol.is_null()).then(|| (list(vol, nall), list(vol0, nall))),
            tally: !tally.is_null(),
        };
        let plastic = if yields {
            list_mut(plastic, nbonds)
        } else {
            &mut [][..]
        };
        let broken = list_mut(broken, nbonds);
        let own = Ownership {
            n_owned,
            newton: newton != 0,
        };
        let f = slice::from_raw_parts_mut(f as *mut [f64; 3], nall);
        let pass = failing_list_forces(&Unwrapped, &inputs, bonds, plastic, own, f, broken);
        if let Some(found) = found.as_mut() {
            *found = FailureCounts {
                broken: pass.broken as i64,
                yielded: pass.yielded as i64,
            };
        }
        report(&pass.pass, tally, fault)
    })
}

/// Force over distance (to `fforce`) and spring-proxy energy
/// ([`failing_bond_energy`]) of one intact bond without damping or
/// multibody term, for LAMMPS's `Bond::single`; both 0 for a bond past its
/// critical strain, a rule the model refuses, or a length not above 0.
///
/// # Safety
/// `coeffs` and `rule` are null or valid; `fforce` is null or valid.
#[no_mangle]
pub unsafe extern "C" fn bpm_failing_bond_single(
    r: f64,
    r0: f64,
    plastic_strain: f64,
    coeffs: *const BondCoeffs,
    rule: *const RawBondFailure,
    fforce: *mut f64,
) -> f64 {
    let Some(fforce) = fforce.as_mut() else {
        return 0.0;
    };
    *fforce = 0.0;
    let (Some(c), Some(rule)) = (coeffs.as_ref(), rule.as_ref().map(|r| r.rule())) else {
        return 0.0;
    };
    if !(r > 0.0 && r0 > 0.0) || rule.check().is_err() {
        return 0.0;
    }
    let mut e_p = plastic_strain;
    match failing_bond_force(r, r0, &mut e_p, None, 0.0, c, &rule) {
        Some(force) => {
            *fforce = force / r;
            failing_bond_energy(r, r0, e_p, c, &rule)
        }
        None => 0.0,
    }
}
