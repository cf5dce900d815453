//! The cross-check: the same scene through LAMMPS with our plugin and
//! through the native engine, compared observable by observable.

pub mod check;
pub mod cli;
pub mod compare;
pub mod cross_check;
pub mod engines;
pub mod launch;
pub mod liggghts;
pub mod moduli;
pub mod scenes;
pub mod single_point;
pub mod tolerances;
pub mod upstream;

pub use compare::{compaction_deviation, compare_runs, Deviation};
pub use engines::{run_native, EngineRun, HarnessError, LammpsLauncher};
pub use launch::{LammpsChild, LaunchError, Work};
pub use scenes::{
    as_trajectory, contact_solid, contact_solid_reference, dem_check_material, dem_lattice,
    dem_trajectory, grain_pair, grain_squeeze, small_compaction, DemLoading,
};
pub use single_point::{
    lammps_single_point, max_relative_deviation, native_single_point, run_lmp_bpm, SinglePoint,
    SinglePointError,
};

/// Writes `value` as pretty-printed JSON (the check's report files, and
/// those of the commands built on the harness).
pub(crate) fn write_json(
    path: &std::path::Path,
    value: &impl serde::Serialize,
) -> std::io::Result<()> {
    let text = serde_json::to_string_pretty(value).map_err(std::io::Error::other)?;
    crate::whole_file::write_whole(path, text.as_bytes()).map_err(|e| e.cause)
}
