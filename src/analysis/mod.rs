//! Analysis of recorded observables.

pub mod distribution;
pub mod fit;
pub mod fragments;
pub mod hertz;
pub mod jamming;
pub mod lid_force;
pub mod moduli;
pub mod packing;
pub mod plot;
pub mod slice;

pub use fit::{least_squares_line, Line};
pub use moduli::{bulk_modulus, poisson_ratio, shear_modulus};

/// A recorded stage as the analyses read it: its name and its columns by
/// name (the stage runner's `StageOutput` is one; tests build their own).
pub trait Recorded {
    /// The stage's name (errors name it).
    fn name(&self) -> &str;
    /// The column `name`, one value per recorded row; `None` if the stage
    /// did not record it.
    fn column(&self, name: &str) -> Option<Vec<f64>>;
}
