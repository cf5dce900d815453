//! The native engine: box, pair list, integrator, particle models and the
//! drivers a protocol stage adds.
//!
//! - geometry: [`simbox`] (box, minimum image), [`neighbor`] (cell-list
//!   Verlet list and exclusions);
//! - state: [`particles`] (structure of arrays), [`system`] (one run's
//!   state and the velocity-Verlet step), [`integrator`];
//! - models: [`model`] (the contract), [`bpm`] (the bonded particle model),
//!   [`dem`] (DEM spheres and the multi-contact closure); a new model is a
//!   folder beside them implementing [`ParticleModel`];
//! - drivers: [`external`] (walls, tether, viscous damping, gravity: terms
//!   either model runs under), [`deform`] (box deformation, barostat),
//!   [`clamp`] (groups moved at a constant velocity);
//! - [`state`]: everything a step changes, saved and restored whole, so a
//!   run resumed from a checkpoint continues bit for bit;
//! - [`parallel`] and [`timers`]: threads and per-part timing.

pub mod bpm;
pub mod clamp;
pub mod deform;
pub mod dem;
pub mod external;
pub mod integrator;
pub mod model;
pub mod neighbor;
pub mod parallel;
pub mod particles;
pub mod simbox;
pub mod state;
pub mod system;
pub mod team;
pub mod timers;

pub use bpm::{BondTopology, BondWindow, BpmForceField, BpmModel, BpmTerms};
pub use clamp::{Clamp, ClampError};
pub use deform::{Barostat, Deformation, LeesEdwards, ShearRemap, TiltFactor};
pub use dem::{
    ActiveGranularWall, BeyondReach, ClosurePass, ClosureReport, ContactStore, DemModel, DemReport,
    MultiContact,
};
pub use external::{
    ActiveTether, ExternalReport, ExternalTerms, FlatWall, GranularWall, Gravity, SphereWall,
    Tether, WallSide,
};
pub use integrator::Integrator;
pub use model::{EnergyTerm, ForceInput, ForceOutput, ModelTally, ParticleModel, MAX_ENERGY_TERMS};
pub use neighbor::{pairs_within, Exclusions, NeighbourList};
pub use particles::{Particles, Rotation};
pub use simbox::{MinimumImage, SimBox};
pub use state::EngineState;
pub use system::{StageDrivers, StepReport, System};
pub use team::Team;
pub use timers::{Stage, Timers};

/// Failures of a running simulation.
#[derive(Debug, thiserror::Error)]
pub enum EngineError {
    /// A stage's clamps cannot be held.
    #[error(transparent)]
    Clamp(#[from] ClampError),
    /// A position, velocity or force became NaN or infinite.
    #[error("simulation became unstable at step {step}: particle {particle} has a non-finite position, velocity or force (reduce dt or check the scene)")]
    NonFinite {
        /// Step at which it was detected.
        step: u64,
        /// First offending particle.
        particle: usize,
    },
    /// An interaction left the model's range: a bond collapsed or tore, or
    /// a force turned non-finite (kernels' `Fault`), caught while the state
    /// is still finite.
    #[error("simulation became unstable at step {step}: {what}. Likely cause: {cause}")]
    Unstable {
        /// Step of the force evaluation that found it.
        step: u64,
        /// The two particles (indices).
        particles: [usize; 2],
        /// What was found, in words.
        what: String,
        /// The likely cause, in words.
        cause: String,
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
    /// A particle reached the plane of a flat wall (LAMMPS's
    /// `fix wall/harmonic` stops there too).
    #[error("particle {particle} reached the plane of flat wall {wall} at step {step}: a harmonic wall holds a particle off its plane with at most k times its cutoff, and the grain pressed harder (LAMMPS stops here too: \"Particle on or inside fix wall surface\")")]
    ThroughWall {
        /// Step of the force evaluation that found it.
        step: u64,
        /// Index of the wall in the stage's `walls`.
        wall: usize,
        /// Particle index.
        particle: usize,
    },
    /// A sphere's centre reached the plane of a granular wall: the
    /// sphere overlapped the wall by its whole radius.
    #[error("sphere {particle} reached the plane of granular wall {wall} at step {step}: it overlapped the wall by its whole radius (the wall moved too fast, pressed too hard for its stiffness, or the time step is too long; or the sphere started on the wrong side: check the wall's position and side)")]
    ThroughGranularWall {
        /// Step of the force evaluation that found it.
        step: u64,
        /// Index of the wall in the stage's `granular_walls`.
        wall: usize,
        /// Particle index.
        particle: usize,
    },
    /// The multi-contact closure moved surfaces further than its reach:
    /// pairs (or walls) beyond the reach could then touch unseen.
    #[error("the multi-contact corrections of sphere {sphere} at {partner} add up to {ratio:.3} of the radii at step {step}, beyond the closure's reach {reach}: raise `force_field.multicontact.reach` (or lower the prefactor, or use the advanced closure, whose ratio bounds each term)")]
    ClosureBeyondReach {
        /// Step of the force evaluation that found it.
        step: u64,
        /// The sphere.
        sphere: usize,
        /// Its partner, in words (`sphere 12`, `granular wall 0`).
        partner: String,
        /// The corrections over the radii.
        ratio: f64,
        /// The closure's reach.
        reach: f64,
    },
    /// The multi-contact closure moved a sphere's surface onto or past its
    /// centre: the half-space estimate means nothing there.
    #[error("the multi-contact correction of sphere {sphere} is {ratio:.3} of its radius at step {step}: its surface moved onto or past its centre (the standard closure's feedback runs away at large overlaps: use the advanced closure, a smaller prefactor or less compression)")]
    ClosureCollapsed {
        /// Step of the force evaluation that found it.
        step: u64,
        /// The sphere.
        sphere: usize,
        /// The correction over the radius.
        ratio: f64,
    },
    /// The box shrank or tilted until its periodic faces are closer than
    /// twice the pair interactions' range: a particle could then meet two
    /// images of one partner, and the minimum image would see only one.
    #[error("at step {step} the box's periodic faces normal to dimension {dimension} are {face:.4} apart, no more than twice the pair interactions' range {cutoff:.4}: compress or shear less, or use more particles (a larger box)")]
    BoxBelowCutoff {
        /// Step after which the box was too small.
        step: u64,
        /// The dimension (0 = x) whose face distance is too short.
        dimension: usize,
        /// The face distance.
        face: f64,
        /// The pair cutoff (largest contact range; for DEM with a
        /// multi-contact closure, including its reach).
        cutoff: f64,
    },
    /// The stage asks the model for something it does not have.
    #[error("the particle model does not support {what}")]
    Unsupported {
        /// What was asked.
        what: &'static str,
    },
    /// The barostat asked for a non-positive box scale.
    #[error("barostat at step {step}: pressure {pressure:e} with this gain would invert the box (reduce the gain)")]
    BarostatCollapse {
        /// Step at which it happened.
        step: u64,
        /// The pressure that caused it.
        pressure: f64,
    },
    /// A saved state does not fit the system it is restored into.
    #[error("the saved state does not fit this system: {what}")]
    StateMismatch {
        /// What differs.
        what: String,
    },
}
