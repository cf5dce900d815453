//! Studies: each runs a protocol over scenes in one or both engines and
//! writes its JSON and plots.
//!
//! - [`hertz`]: the Hertz sphere squeeze of grains.

pub mod hertz;
