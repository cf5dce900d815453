//! Analysis of recorded observables.

pub mod distribution;
pub mod fit;
pub mod hertz;
pub mod jamming;
pub mod lid_force;
pub mod moduli;
pub mod packing;
pub mod plot;
pub mod slice;

pub use fit::{least_squares_line, Line};
pub use moduli::{bulk_modulus, poisson_ratio, shear_modulus};
