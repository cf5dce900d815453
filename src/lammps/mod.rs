//! The LAMMPS bridge: scene to data file and input variables, and the
//! registration of our styles (`lammps-plugin/`) in a LAMMPS instance.

pub mod datafile;
pub mod instance;
pub mod sys;

pub use datafile::{write_data_file, write_reference_lengths, ScriptVars};
pub use instance::{Lammps, LammpsError};

extern "C" {
    /// Registers `bond_style bpm/multibody`, `pair_style bpm/contact` and
    /// the internal fix in the LAMMPS instance behind `handle` (a
    /// `LAMMPS_NS::LAMMPS *`, e.g. from `lammps_open_no_mpi`).
    pub fn bpm_register_styles(handle: *mut std::ffi::c_void);
}
