//! The LAMMPS bridge: scene to data file and input variables, the input
//! templates (embedded), and the registration of our styles
//! (`lammps-plugin/`) in a LAMMPS instance.

pub mod cli;
pub mod datafile;
pub mod instance;
pub mod runner;
pub mod script;
pub mod sys;
pub mod templates;

pub use datafile::{write_reference_lengths, write_run_data_file, ScriptVars};
pub use instance::{Lammps, LammpsError, LammpsVersion};
pub use runner::{run_scene_lammps, LammpsRun, LammpsRunError};
pub use script::{write_driver, Driver, ScriptError};
pub use templates::write_templates;

extern "C" {
    /// Registers `bond_style bpm/multibody`, `pair_style bpm/contact` and
    /// the internal fix in the LAMMPS instance behind `handle` (a
    /// `LAMMPS_NS::LAMMPS *`, e.g. from `lammps_open_no_mpi`).
    pub fn bpm_register_styles(handle: *mut std::ffi::c_void);
}

/// Finalises MPI if LAMMPS initialised it (call once, after the last
/// LAMMPS instance is closed; every rank must call it before exiting).
pub fn finalize_mpi() {
    // SAFETY: no LAMMPS instance is open; LAMMPS checks whether MPI is
    // initialised and not yet finalised.
    unsafe { sys::lammps_mpi_finalize() };
}
