//! Interactions outside the range where the model means anything: the first
//! sign of a blow-up, caught while the state is still finite.
//!
//! A run that goes unstable (timestep too large, multibody term beyond the
//! incompressible limit, particles driven into each other) shows it first as
//! a bond squeezed or stretched far beyond any elastic state; a few steps
//! later the numbers overflow. The force kernels flag the first such bond of
//! each pass, and any non-finite force, at the cost of two comparisons per
//! interaction, so both engines can stop on the step it happens, name the
//! particles, and say why. Unbonded overlap alone is not a fault (a random
//! fill starts with particles on top of each other, and the contact force
//! stays bounded); it is one of the causes [`Fault::likely_cause`] (in `diagnosis.rs`) weighs.

use super::Tally;
use serde::Serialize;

/// A bond shorter than this fraction of its reference length has collapsed.
///
/// Elastic states stay far above it: 60% volumetric strain shortens bonds
/// by about 26% on average.
pub const COLLAPSED_BELOW: f64 = 0.2;

/// A bond longer than this multiple of its reference length is torn apart
/// (only a blow-up gets there: a bond that may break breaks long before).
pub const OVERSTRETCHED_ABOVE: f64 = 3.0;

/// Unbonded particles closer than this fraction of the contact distance
/// `d` near a fault make overlap its likely cause: the contact stiffness
/// there, `k_P + 3 a_P (d - r)^2`, is some 38 times `k_P` with the paper's
/// `a_P`, too stiff for the timestep chosen for the bonds.
pub const DEEP_OVERLAP: f64 = 0.5;

/// What was wrong with an interaction.
#[repr(i32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FaultKind {
    /// A position, velocity or force was NaN or infinite.
    NonFinite = 1,
    /// A bond shorter than [`COLLAPSED_BELOW`] times its reference length.
    BondCollapsed = 2,
    /// A bond longer than [`OVERSTRETCHED_ABOVE`] times its reference length.
    BondOverstretched = 3,
}

impl FaultKind {
    /// The kind with C code `code` (the values of `BPM_FAULT_*`).
    pub fn from_code(code: i32) -> Option<Self> {
        [
            Self::NonFinite,
            Self::BondCollapsed,
            Self::BondOverstretched,
        ]
        .into_iter()
        .find(|k| *k as i32 == code)
    }
}

/// The first interaction of a force pass outside the model's range.
///
/// `#[repr(C)]`: the plugin receives it as `bpm_fault`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Fault {
    /// What was wrong.
    pub kind: FaultKind,
    /// First particle (local index).
    pub i: i64,
    /// Second particle (local index).
    pub j: i64,
    /// Their distance (d).
    pub r: f64,
    /// The bond's reference length, or the contact distance `d` of a pair.
    pub reference: f64,
    /// Whether the two are bonded (a bond) or not (a pair contact).
    pub bonded: bool,
    /// The bond's position in the bond list (-1 for a pair).
    pub bond: i64,
}

impl Fault {
    /// The verdict on a bond of length `r` and reference length `r0` whose
    /// force came out as `force`; `None` when all is well.
    #[inline(always)]
    pub(crate) fn of_bond(
        bond: usize,
        i: usize,
        j: usize,
        r: f64,
        r0: f64,
        force: f64,
    ) -> Option<Self> {
        let kind = if !(r.is_finite() && force.is_finite()) {
            FaultKind::NonFinite
        } else if r < COLLAPSED_BELOW * r0 {
            FaultKind::BondCollapsed
        } else if r > OVERSTRETCHED_ABOVE * r0 {
            FaultKind::BondOverstretched
        } else {
            return None;
        };
        Some(Self {
            kind,
            i: i as i64,
            j: j as i64,
            r,
            reference: r0,
            bonded: true,
            bond: bond as i64,
        })
    }

    /// The verdict on an unbonded pair at distance `r` with contact
    /// distance `d` whose force came out as `force`: only a non-finite
    /// value is a fault.
    #[inline(always)]
    pub(crate) fn of_pair(i: usize, j: usize, r: f64, d: f64, force: f64) -> Option<Self> {
        if r.is_finite() && force.is_finite() {
            return None;
        }
        Some(Self {
            kind: FaultKind::NonFinite,
            i: i as i64,
            j: j as i64,
            r,
            reference: d,
            bonded: false,
            bond: -1,
        })
    }

    /// What happened, in words, naming the two as `who` (e.g. "particles
    /// 3 and 17" in the native engine, "atoms with IDs 4 and 18" in LAMMPS).
    pub fn what(&self, who: &str) -> String {
        let ratio = self.r / self.reference;
        match self.kind {
            FaultKind::NonFinite => format!(
                "{who} ({}) have a non-finite position, velocity or force",
                if self.bonded { "bonded" } else { "in contact" }
            ),
            FaultKind::BondCollapsed => format!(
                "the bond between {who} collapsed to {ratio:.3} of its reference length {:.4} d \
                 (limit {COLLAPSED_BELOW})",
                self.reference
            ),
            FaultKind::BondOverstretched => format!(
                "the bond between {who} stretched to {ratio:.2} times its reference length {:.4} d \
                 (limit {OVERSTRETCHED_ABOVE})",
                self.reference
            ),
        }
    }
}

/// What a force pass returns: energy and virial, and the first interaction
/// outside the model's range, if any.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ForcePass {
    /// Energy and virial (zero when not asked for).
    pub tally: Tally,
    /// The first faulty interaction in list order.
    pub fault: Option<Fault>,
}

impl ForcePass {
    /// This pass followed by `later`: sums added, the earlier fault kept.
    pub fn merged(&self, later: &Self) -> Self {
        Self {
            tally: self.tally.merged(&later.tally),
            fault: self.fault.or(later.fault),
        }
    }
}
