//! Builders that make scenes from a few parameters and a seed.

pub mod bulk;
pub mod grain;
