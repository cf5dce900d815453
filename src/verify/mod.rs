//! The cross-check: the same scene through LAMMPS with our plugin and
//! through the native engine, compared observable by observable.

pub mod scenes;
pub mod single_point;

pub use scenes::contact_solid;
pub use single_point::{
    lammps_single_point, max_relative_deviation, native_single_point, run_lmp_bpm, SinglePoint,
    CHECK_LIMIT_SECONDS,
};
