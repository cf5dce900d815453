//! DEM contacts and the multi-contact closure over a LAMMPS half
//! neighbour list, for the plugin's `pair_style bpm/granular`: the native
//! engine's contact law ([`corrected_granular_contact`]) and closure
//! ([`surface_corrections`], [`pair_contact_points`]), with the contact
//! memory a LAMMPS run needs.
//!
//! **Contact memory moves with the atoms.** Each owned atom carries one
//! row of doubles, `[count, (partner tag, history) x slots]`, which the
//! plugin's fix copies when the atom changes rank and writes to restart
//! files ([`Layout::history`]). A contact is stored with both of its
//! owned atoms, each from its own side ([`ContactHistory::mirrored`]), so
//! whichever atom a later list puts first finds it, and ranks sharing a
//! pair (newton off computes it on both) each keep their own copy.
//!
//! **Two passes per force evaluation** (the closure's only):
//! 1. [`GranularList::corrections`]: every owned atom's contacts within
//!    reach, from its list rows (with newton off a rank lists every pair
//!    that has one of its atoms), their last normal forces from the
//!    memory, and the correction of each into the atom's correction row
//!    `[count, (partner tag, Delta) x slots]` ([`Layout::corrections`]).
//!    The plugin then copies the rows of owned atoms to their ghosts.
//! 2. [`GranularList::forces`]: each listed pair with both sides'
//!    corrections (a ghost's from its copied row), its force and torques
//!    on owned atoms, the memory updated.
//!
//! **Flat walls** (`fix bpm/granular/wall`, [`GranularList::set_walls`])
//! are contacts of their atoms in both passes, as in the native engine:
//! each is kept in the same rows under the partner key `-number`, its
//! correction comes from pass 1 with the atom's other contacts, and its
//! force from [`granular_wall_contact`] in pass 2.
//!
//! [`corrected_granular_contact`]: crate::kernels::corrected_granular_contact
//! [`surface_corrections`]: crate::kernels::surface_corrections
//! [`pair_contact_points`]: crate::kernels::pair_contact_points
//! [`granular_wall_contact`]: crate::kernels::granular_wall_contact

// Atom indices address several per-atom arrays at once.
#![allow(clippy::needless_range_loop)]

mod corrections;
mod forces;
mod memory;
#[cfg(test)]
mod tests;
mod walls;

pub use corrections::CorrectionSummary;
pub use memory::{Layout, HISTORY_VALUES};
pub use walls::ListWall;

use super::granular::GranularCoeffs;
use super::multicontact::{Closure, ContactPoint};
use super::{HalfSpace, Sphere, SurfaceCorrections};

/// Why a pass stopped: each names atoms by their LAMMPS IDs.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum ListError {
    /// An atom has more contacts than its memory row holds.
    #[error("atom {atom} has more than {slots} contacts (or pairs within the closure's reach): raise `slots` of pair_style bpm/granular")]
    RowFull {
        /// The atom's ID.
        atom: i64,
        /// The row's capacity.
        slots: usize,
    },
    /// A correction moved a surface onto or past its centre.
    #[error("the multi-contact correction of atom {atom} is {ratio:.3} of its radius at step {step}: its surface moved onto or past its centre (the standard closure's feedback runs away at large overlaps: use the advanced closure, a smaller prefactor or less compression)")]
    Collapsed {
        /// The atom's ID.
        atom: i64,
        /// Correction over radius.
        ratio: f64,
        /// The time step.
        step: i64,
    },
    /// Two corrections of a pair add up beyond the closure's reach.
    #[error("the multi-contact corrections of atoms {atom} and {partner} add up to {ratio:.3} of their radii at step {step}, beyond the closure's reach {reach}: raise `reach` (or lower the prefactor, or use the advanced closure, whose ratio bounds each term)")]
    BeyondReach {
        /// The atoms' IDs.
        atom: i64,
        /// The partner's ID.
        partner: i64,
        /// Corrections over the radii.
        ratio: f64,
        /// The closure's reach.
        reach: f64,
        /// The time step.
        step: i64,
    },
    /// An atom's centre reached a wall's plane.
    #[error("atom {atom} reached the plane of fix bpm/granular/wall number {wall} at step {step}: it overlapped the wall by its whole radius (the wall moved too fast, pressed too hard for its stiffness, or the time step is too long; or the atom started on the wrong side: check the wall's position and side)")]
    ThroughWall {
        /// The atom's ID.
        atom: i64,
        /// The wall's number.
        wall: i64,
        /// The time step.
        step: i64,
    },
    /// An atom's correction at a wall exceeds the closure's reach.
    #[error("the multi-contact correction of atom {atom} at fix bpm/granular/wall number {wall} is {ratio:.3} of its radius at step {step}, beyond the closure's reach {reach}: raise `reach` (or lower the prefactor, or use the advanced closure, whose ratio bounds each term)")]
    WallBeyondReach {
        /// The atom's ID.
        atom: i64,
        /// The wall's number.
        wall: i64,
        /// Correction over radius.
        ratio: f64,
        /// The closure's reach.
        reach: f64,
        /// The time step.
        step: i64,
    },
    /// A wall's force came out NaN or infinite.
    #[error("the contact force between atom {atom} and fix bpm/granular/wall number {wall} is not finite at step {step} (overlap {overlap:.4}): the run has blown up; reduce the timestep")]
    NonFiniteWall {
        /// The atom's ID.
        atom: i64,
        /// The wall's number.
        wall: i64,
        /// The overlap.
        overlap: f64,
        /// The time step.
        step: i64,
    },
    /// Two walls share a number, or a wall's axis is not 0, 1 or 2.
    #[error("{0}")]
    BadWalls(&'static str),
    /// A force came out NaN or infinite.
    #[error("the contact force between atoms {atom} and {partner} is not finite at step {step} (overlap {overlap:.4}): the run has blown up; reduce the timestep")]
    NonFinite {
        /// The atoms' IDs.
        atom: i64,
        /// The partner's ID.
        partner: i64,
        /// The overlap.
        overlap: f64,
        /// The time step.
        step: i64,
    },
}

/// The closure of the style: how terms combine, the half-space response
/// of the spheres' material, and how far beyond touching pairs receive
/// corrections.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ListClosure {
    /// Standard or advanced.
    pub closure: Closure,
    /// The spheres' half-space response.
    pub half_space: HalfSpace,
    /// Fraction of the radii beyond touching within which pairs receive
    /// corrections.
    pub reach: f64,
}

/// The per-atom state a pass reads: owned atoms first, then ghosts.
#[derive(Clone, Copy, Debug)]
pub struct ListAtoms<'a> {
    /// Positions (ghosts as images).
    pub x: &'a [[f64; 3]],
    /// Velocities (ghosts' included: `comm_modify vel yes`).
    pub v: &'a [[f64; 3]],
    /// Angular velocities.
    pub omega: &'a [[f64; 3]],
    /// Radii.
    pub radius: &'a [f64],
    /// Masses.
    pub mass: &'a [f64],
    /// Atom IDs.
    pub tag: &'a [i64],
    /// Atoms `0..n_owned` are owned.
    pub n_owned: usize,
}

impl ListAtoms<'_> {
    fn sphere(&self, i: usize) -> Sphere {
        Sphere {
            v: self.v[i],
            omega: self.omega[i],
            radius: self.radius[i],
            mass: self.mass[i],
        }
    }
}

/// One owned atom's contact within reach, before grouping by atom.
#[derive(Clone, Copy, Debug)]
struct Entry {
    atom: u32,
    partner: f64,
    point: ContactPoint,
}

/// The contact law and closure of `pair_style bpm/granular` and their
/// reusable buffers (so passes allocate only while lists grow).
#[derive(Clone, Debug)]
pub struct GranularList {
    /// The contact coefficients.
    pub coeffs: GranularCoeffs,
    /// The closure, if on.
    pub closure: Option<ListClosure>,
    /// Capacity of the memory and correction rows.
    pub slots: usize,
    entries: Vec<Entry>,
    offsets: Vec<usize>,
    grouped: Vec<Entry>,
    points: Vec<ContactPoint>,
    deltas: Vec<f64>,
    lanes: SurfaceCorrections,
    /// The memory rows before a pass that renews them.
    previous: Vec<f64>,
    /// The walls of the coming passes.
    walls: Vec<ListWall>,
    /// Per wall, the normal force on it from this rank's atoms in the
    /// last forces pass (positive when pushed).
    wall_forces: Vec<f64>,
}

impl GranularList {
    /// Contacts with `coeffs`, corrected by `closure`, with rows of
    /// `slots` entries.
    pub fn new(coeffs: GranularCoeffs, closure: Option<ListClosure>, slots: usize) -> Self {
        Self {
            coeffs,
            closure,
            slots,
            entries: Vec::new(),
            offsets: Vec::new(),
            grouped: Vec::new(),
            points: Vec::new(),
            deltas: Vec::new(),
            lanes: SurfaceCorrections::default(),
            previous: Vec::new(),
            walls: Vec::new(),
            wall_forces: Vec::new(),
        }
    }
}
