//! Interaction kernels shared by the native engine and the LAMMPS plugin.
//!
//! Everything here is a pure function over flat arrays: no allocation, no
//! global state, no knowledge of who owns the memory. The same functions are
//! called by [`crate::engine`] and, through [`crate::ffi`], by the C++ shim in
//! `lammps-plugin/`, so a fix here reaches both engines.
//!
//! Conventions (docs/model.md): for a pair `i, j`, `r_ij = x_i - x_j`,
//! `n = r_ij / r`, `dv = v_i - v_j`; a force magnitude `F` acts on `i` along
//! `+n` (positive is repulsive) and on `j` along `-n`.

mod bond;
mod bond_failure;
mod bond_rows;
mod closure_lanes;
mod diagnosis;
mod failing_bond_list;
mod fault;
mod geometry;
mod granular;
mod granular_lanes;
mod granular_list;
mod isa;
mod list_rows;
mod multicontact;
mod pair;
mod plastic_rows;
mod row_window;
mod tally;
mod volume;
mod zero_net;

pub use bond::{
    bond_force_magnitude, bond_forces, bond_forces_on, cube_root, dilation, reciprocal, BondCoeffs,
    BondEntry, BondInputs,
};
pub use bond_failure::{
    failing_bond_energy, failing_bond_force, failing_row_forces, failing_row_forces_on,
    gather_rest_volumes, plastic_strain_after, row_broke, smoothing, BondFailure, BondFailureError,
    FailurePass,
};
pub use bond_rows::{
    gather_forces, gather_forces_on, gather_volumes, row_forces, row_forces_on, row_volumes,
    row_volumes_on, BondRows, BondRowsError, RowInputs,
};
pub use closure_lanes::SurfaceCorrections;
pub use diagnosis::{stable_timestep, verlet_limit, LIMIT_MARGIN, MULTIBODY_LIMIT, STIFFEST_MODE};
pub use failing_bond_list::{
    accumulate_intact_volumes, accumulate_intact_volumes_on, failing_list_forces,
    failing_list_forces_on, FailingListInputs, ListFailures,
};
pub use fault::{Fault, FaultKind, ForcePass, COLLAPSED_BELOW, DEEP_OVERLAP, OVERSTRETCHED_ABOVE};
pub use geometry::{BoxImage, MinimumImage, OrthogonalImage, Separation, Unwrapped};
pub use granular::{
    corrected_granular_contact, granular_contact, granular_wall_contact, restitution_prefactor,
    tsuji_prefactor, ContactForce, ContactHistory, GranularCoeffs, GranularMaterial, NormalDamping,
    Sphere, SpringDashpotSlider, Twisting, WallPlane, WallTouch,
};
pub use granular_lanes::{
    hertz_mindlin_block, hertz_mindlin_wall_block, BlockForces, ContactBlock, WallBlock,
    WallForces, CONTACT_LANES,
};
pub use granular_list::{
    CorrectionSummary, GranularList, Layout, ListAtoms, ListClosure, ListError, ListWall,
    HISTORY_VALUES,
};
pub use isa::Isa;
pub use list_rows::{ListRows, ListRowsError, ListStamp};
pub use multicontact::{
    group_by_sphere, pair_contact_points, surface_corrections, Closure, ContactPoint, HalfSpace,
    MprSwitch, MprTest, COINCIDENT_POINTS, NEGLIGIBLE, POINT_FLOOR,
};
pub use pair::{pair_energy, pair_force_magnitude, pair_forces, PairCoeffs, PairInputs};
pub use plastic_rows::{PlasticRows, PlasticSection, SharedPlasticRows};
pub use row_window::{window_forces, window_forces_on, RowWindow};
pub use tally::{Ownership, Tally};
pub use volume::{accumulate_reference_volumes, accumulate_volumes, accumulate_volumes_on};
pub use zero_net::{accumulate_multibody_sums, balance_multibody, MultibodyInputs, MultibodySum};

/// Bits of a LAMMPS neighbour index that carry the special-bond class.
pub const SPECIAL_SHIFT: u32 = 30;
/// Mask that strips the special-bond bits from a LAMMPS neighbour index.
pub const NEIGHMASK: i32 = 0x1FFF_FFFF;

#[inline(always)]
pub(crate) fn sub(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[inline(always)]
pub(crate) fn dot(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
