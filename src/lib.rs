//! Bonded particle model (BPM) with a multibody volume term for deformable
//! grains (Clemmer, Monti and Lechman 2024), shared between a native Rust
//! engine and a LAMMPS plugin.
//!
//! - [`kernels`]: the interaction kernels, pure functions over flat arrays;
//! - [`ffi`]: the same kernels behind a C ABI for the LAMMPS shim;
//! - [`engine`]: the native integrator;
//! - [`scene`]: the JSON scene, its validation, builders and the stage runner;
//! - [`analysis`]: fits, moduli and plots of recorded observables;
//! - [`options`]: checks of user options, with errors naming the argument;
//! - [`progress`]: progress bars and the JSON-lines progress log;
//! - [`reference`]: the published numbers the studies compare against;
//! - `lammps`, `verify`, `studies` (feature `lammps`, on by default): the
//!   LAMMPS bridge, the cross-check harness, and the studies (calibration,
//!   Hertz squeeze, comparison with upstream LAMMPS, benchmarks).
#![warn(missing_docs)]

pub mod analysis;
pub mod engine;
pub mod ffi;
pub mod file_error;
pub mod json_nan;
pub mod kernels;
#[cfg(feature = "lammps")]
pub mod lammps;
pub mod options;
pub mod progress;
pub mod reference;
pub mod scene;
#[cfg(feature = "lammps")]
pub mod studies;
#[cfg(feature = "lammps")]
pub mod verify;
pub mod whole_file;

/// The crate version, recorded in every output file.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");
