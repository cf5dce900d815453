//! Analysis of recorded observables.

pub mod fit;
pub mod hertz;
pub mod moduli;
pub mod plot;

pub use fit::{least_squares_line, Line};
pub use moduli::{bulk_modulus, poisson_ratio, shear_modulus};
