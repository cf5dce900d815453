//! Analysis of recorded observables.

pub mod fit;

pub use fit::{least_squares_line, Line};
