//! Bonded particle model (BPM) with a multibody volume term for deformable
//! grains (Clemmer, Monti and Lechman 2024), shared between a native Rust
//! engine and a LAMMPS plugin.
//!
//! - [`kernels`]: the interaction kernels, pure functions over flat arrays;
//! - [`ffi`]: the same kernels behind a C ABI for the LAMMPS shim;
//! - [`engine`]: the native integrator;
//! - [`scene`]: the JSON scene, its validation, builders and the stage runner;
//! - [`analysis`]: fits and summaries of recorded observables.
#![warn(missing_docs)]

pub mod analysis;
pub mod bench;
pub mod engine;
pub mod ffi;
pub mod kernels;
pub mod lammps;
pub mod scene;
pub mod verify;

/// The crate version, recorded in every output file.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");
