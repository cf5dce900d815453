//! The native engine: box, bonds, neighbour list, integrator and drivers.
//!
//! The layout follows the parts of a step: [`simbox`] and [`neighbor`] for
//! geometry, [`topology`] for bonds, [`bpm`] for the interaction model,
//! [`external`] and [`deform`] for what a protocol stage adds, [`system`]
//! for the state and the velocity-Verlet step.

pub mod bpm;
pub mod deform;
pub mod external;
pub mod neighbor;
pub mod parallel;
pub mod simbox;
pub mod system;
pub mod timers;
pub mod topology;

pub use bpm::{BpmModel, BpmTerms, InteractionTally};
pub use deform::{Barostat, Deformation, TiltFactor};
pub use external::{ActiveTether, FlatWall, SphereWall, Tether, WallSide};
pub use neighbor::NeighbourList;
pub use simbox::{MinimumImage, SimBox};
pub use system::{ForceModel, StageDrivers, StepReport, System};
pub use timers::{Stage, Timers};
pub use topology::BondTopology;

/// Failures of a running simulation.
#[derive(Debug, thiserror::Error)]
pub enum EngineError {
    /// A position, velocity or force became NaN or infinite.
    #[error("simulation became unstable at step {step}: particle {particle} has a non-finite position, velocity or force (reduce dt or check the scene)")]
    NonFinite {
        /// Step at which it was detected.
        step: u64,
        /// First offending particle.
        particle: usize,
    },
    /// A particle crossed a closed (non-periodic) face of the box.
    #[error("particle {particle} left the box through closed dimension {dimension} at step {step} (the box is not periodic there: enlarge it, or add walls)")]
    LeftBox {
        /// Step at which it was found (checked every 256 steps).
        step: u64,
        /// Particle index.
        particle: usize,
        /// Dimension (0 = x).
        dimension: usize,
    },
    /// The barostat asked for a non-positive box scale.
    #[error("barostat at step {step}: pressure {pressure:e} with this gain would invert the box (reduce the gain)")]
    BarostatCollapse {
        /// Step at which it happened.
        step: u64,
        /// The pressure that caused it.
        pressure: f64,
    },
}
