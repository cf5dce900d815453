//! Bonds that break and yield over a LAMMPS bond list: the plugin's
//! `bpm/spring/rs` and `bpm/spring/plastic/rs` styles.
//!
//! The rules are those of [`super::bond_failure`], applied bond by bond in
//! list order, as LAMMPS's own bond styles walk `neighbor->bondlist`. A
//! bond that breaks gets type 0 in the list, which later passes over the
//! same list skip (LAMMPS's convention for a broken bond until the list is
//! rebuilt), and its index is reported so that the caller can take it out
//! of its atoms' arrays. The multibody term's volumes are those of the
//! intact bonds, and the reference volumes those of their rest lengths
//! `r_eq = (1 + e_p) r0`, as in the native engine.

use super::bond::{dilation, BondCoeffs, BondEntry};
use super::bond_failure::{failing_bond_energy, failing_bond_force, BondFailure};
use super::fault::{Fault, ForcePass};
use super::tally::{apply_pair_force, Ownership, Tally};
use super::{dot, sub, Separation};

/// Everything a pass over a failing bond list reads.
#[derive(Clone, Copy, Debug)]
pub struct FailingListInputs<'a> {
    /// Positions of owned and ghost atoms.
    pub x: &'a [[f64; 3]],
    /// Velocities; `None` drops the damping term.
    pub v: Option<&'a [[f64; 3]]>,
    /// First length `r0` of each bond, aligned with the list.
    pub r0: &'a [f64],
    /// Coefficients per bond type (`coeffs[ty - 1]`).
    pub coeffs: &'a [BondCoeffs],
    /// How bonds of each type break and yield (`rules[ty - 1]`).
    pub rules: &'a [BondFailure],
    /// Whether a bond may break in this pass (LAMMPS's plastic style lets
    /// none break while it sets a run up).
    pub may_break: bool,
    /// `(V, V0)` per atom from [`accumulate_intact_volumes`]; `None` drops
    /// the multibody term.
    pub volumes: Option<(&'a [f64], &'a [f64])>,
    /// Whether to sum energy and virial.
    pub tally: bool,
}

/// What a pass over a failing bond list found.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ListFailures {
    /// Energy, virial and the first bond out of range.
    pub pass: ForcePass,
    /// Bonds that broke in this pass: their list indices are the first
    /// `broken` entries of the caller's buffer.
    pub broken: usize,
    /// Bonds whose plastic strain changed in this pass.
    pub yielded: usize,
}

/// Adds the forces of the intact bonds of `bonds` (type above 0) to `f`.
///
/// `plastic` holds each bond's plastic strain `e_p` (read, and written
/// where it yields); it may be empty when no rule yields. A bond that
/// breaks gets type 0 and its list index goes to `broken`, which must hold
/// a slot per bond (an `i32`, as the list's atom indices).
///
/// # Panics
/// If a slice is shorter than the list needs, an index is out of range or
/// a type has no coefficients or rule (the C ABI checks these first).
pub fn failing_list_forces<S: Separation>(
    sep: &S,
    inputs: &FailingListInputs,
    bonds: &mut [BondEntry],
    plastic: &mut [f64],
    own: Ownership,
    f: &mut [[f64; 3]],
    broken: &mut [i32],
) -> ListFailures {
    let yields = inputs.rules.iter().any(|r| r.plastic_strain.is_some());
    assert!(
        inputs.r0.len() >= bonds.len()
            && (!yields || plastic.len() >= bonds.len())
            && broken.len() >= bonds.len(),
        "failing bond list of {} bonds with {} lengths, {} plastic strains, {} broken slots",
        bonds.len(),
        inputs.r0.len(),
        plastic.len(),
        broken.len()
    );
    let x = inputs.x;
    let mut out = ListFailures::default();
    let mut tally = Tally::default();
    for (n, bond) in bonds.iter_mut().enumerate() {
        if bond.ty <= 0 {
            continue;
        }
        let (i, j) = (bond.i as usize, bond.j as usize);
        let ty = (bond.ty - 1) as usize;
        let (c, rule) = (&inputs.coeffs[ty], &inputs.rules[ty]);
        let rule = BondFailure {
            breaks: rule.breaks && inputs.may_break,
            ..*rule
        };
        let r0 = inputs.r0[n];
        let del = sep.delta(&x[i], &x[j]);
        let r = dot(&del, &del).sqrt();
        let rinv = 1.0 / r;
        let dilation = inputs
            .volumes
            .map(|(vol, vol0)| dilation(vol[i], vol[j], vol0[i], vol0[j]));
        let damping = inputs
            .v
            .map_or(0.0, |v| c.gamma * dot(&del, &sub(&v[i], &v[j])) * rinv);
        let before = if rule.plastic_strain.is_some() {
            plastic[n]
        } else {
            0.0
        };
        let mut e_p = before;
        let Some(fmag) = failing_bond_force(r, r0, &mut e_p, dilation, damping, c, &rule) else {
            bond.ty = 0;
            broken[out.broken] = n as i32;
            out.broken += 1;
            continue;
        };
        if e_p != before {
            plastic[n] = e_p;
            out.yielded += 1;
        }
        let fpair = fmag * rinv;
        if out.pass.fault.is_none() {
            out.pass.fault = Fault::of_bond(n, i, j, r, r0, fpair);
        }
        let (on_i, on_j, frac) = own.split(i, j);
        apply_pair_force(f, i, j, on_i, on_j, &del, fpair);
        if inputs.tally {
            tally.add(frac, failing_bond_energy(r, r0, e_p, c, &rule), &del, fpair);
        }
    }
    out.pass.tally = tally;
    out
}

/// Adds `r^3` of each intact bond (type above 0) to `vol` and `r_eq^3`,
/// with `r_eq = (1 + e_p) r0` from its first length and plastic strain,
/// to `vol0` (`plastic` empty: `e_p = 0`).
pub fn accumulate_intact_volumes<S: Separation>(
    sep: &S,
    x: &[[f64; 3]],
    bonds: &[BondEntry],
    (r0, plastic): (&[f64], &[f64]),
    own: Ownership,
    (vol, vol0): (&mut [f64], &mut [f64]),
) {
    for (n, bond) in bonds.iter().enumerate() {
        if bond.ty <= 0 {
            continue;
        }
        let (i, j) = (bond.i as usize, bond.j as usize);
        let del = sep.delta(&x[i], &x[j]);
        let rsq = dot(&del, &del);
        let r_eq = r0[n] * (1.0 + plastic.get(n).copied().unwrap_or(0.0));
        let (on_i, on_j, _) = own.split(i, j);
        for (atom, on) in [(i, on_i), (j, on_j)] {
            if on {
                vol[atom] += rsq * rsq.sqrt();
                vol0[atom] += r_eq * r_eq * r_eq;
            }
        }
    }
}
