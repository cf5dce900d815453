//! The contract between the engine and a particle model.
//!
//! A model (the bonded particle model in [`super::bpm`], DEM spheres in
//! [`super::dem`]) owns its own state (bonds, reference lengths and
//! volumes; radii, contact history) and adds its forces to the particles;
//! what only one model measures (the multi-contact closure's corrections)
//! it keeps in its own report, read through its own type. The engine owns what every
//! model shares: positions, velocities, forces, masses, the box, the pair
//! list, the integrator and the external drivers. The engine calls a model
//! through this trait once per step, never per interaction, so the hot
//! loops stay monomorphic inside the model.

use super::deform::LeesEdwards;
use super::external::GranularWall;
use super::neighbor::{Exclusions, NeighbourList};
use super::simbox::SimBox;
use super::team::Team;
use super::timers::Timers;
use super::EngineError;
use crate::kernels::{Fault, Tally};
use std::any::Any;

/// Most energy terms a model may report (bond and pair for the BPM; normal,
/// tangential, rolling, twisting for DEM).
pub const MAX_ENERGY_TERMS: usize = 4;

/// One energy term a model reports, and how each engine measures it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EnergyTerm {
    /// Column name in recorded rows, e.g. `e_bond`.
    pub column: &'static str,
    /// The compared observable (tolerance key), e.g. `bond energy`.
    pub observable: &'static str,
    /// Arguments of the LAMMPS `compute` that measures it, e.g. `pe bond`.
    pub lammps_compute: &'static str,
}

/// Energy per term and the summed virial of one force evaluation.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ModelTally {
    /// Energy and virial per term, in the order of
    /// [`ParticleModel::energy_terms`]; unused entries are zero.
    pub terms: [Tally; MAX_ENERGY_TERMS],
}

impl ModelTally {
    /// Energy and virial of every term together (terms merged in order).
    pub fn total(&self) -> Tally {
        self.terms[1..]
            .iter()
            .fold(self.terms[0], |acc, t| acc.merged(t))
    }
}

/// What a model reads in a force evaluation.
#[derive(Clone, Copy, Debug)]
pub struct ForceInput<'a> {
    /// The box.
    pub simbox: &'a SimBox,
    /// Positions.
    pub x: &'a [[f64; 3]],
    /// Velocities.
    pub v: &'a [[f64; 3]],
    /// Angular velocities (rotational models only).
    pub omega: Option<&'a [[f64; 3]]>,
    /// Particle radii (d).
    pub radius: &'a [f64],
    /// Particle masses (m).
    pub mass: &'a [f64],
    /// The time step this evaluation completes, or `None` for an
    /// evaluation that is not part of a step (a stage's set-up): models
    /// with per-contact history advance it only on a step, as LAMMPS does
    /// outside its set-up.
    pub step_dt: Option<f64>,
    /// The pair list (empty when the model has no pair cutoff).
    pub neighbours: &'a NeighbourList,
    /// How many times positions were wrapped into the box; a change
    /// invalidates anything cached on the stored positions.
    pub wraps: u64,
    /// The threads of the force passes (one thread: serial).
    pub team: &'a Team,
    /// Whether to sum energies and virials in this evaluation.
    pub tally: bool,
    /// Lees-Edwards boundaries, if the box is sheared with them: a pair
    /// across a sheared face sees its partner's image moving at
    /// [`LeesEdwards::image_velocity`]. Only models with velocity-dependent
    /// pair forces read it (the scene refuses it for the others).
    pub lees_edwards: Option<LeesEdwards>,
    /// Time into the stage (tau): where moving walls are.
    pub elapsed: f64,
}

impl ForceInput<'_> {
    /// What a per-contact history advances by in this evaluation: `(dt,
    /// true)` when it completes a step of `dt`, `(0, false)` otherwise.
    pub fn history_step(&self) -> (f64, bool) {
        (self.step_dt.unwrap_or(0.0), self.step_dt.is_some())
    }
}

/// Where a model adds its forces (and torques).
#[derive(Debug)]
pub struct ForceOutput<'a> {
    /// Forces, added to.
    pub f: &'a mut [[f64; 3]],
    /// Torques, added to (rotational models only).
    pub torque: Option<&'a mut [[f64; 3]]>,
    /// Per-part wall-clock timers.
    pub timers: &'a mut Timers,
    /// The first interaction outside the model's range, set by the model.
    pub fault: Option<Fault>,
}

/// A particle model: its state, its forces, its observables.
pub trait ParticleModel: std::fmt::Debug + Send + Any {
    /// The model's name in scenes and reports (`"bpm"`).
    fn name(&self) -> &'static str;

    /// Range of the pair interaction (d) beyond which no non-excluded pair
    /// interacts, or `None` when the model has no pair forces (then the
    /// engine builds no pair list at all).
    fn pair_cutoff(&self) -> Option<f64>;

    /// Pairs the pair list leaves out (for the BPM, bonded pairs, unless
    /// the contacts are overlaid on the bonds).
    fn exclusions(&self) -> Option<&Exclusions>;

    /// Pairs joined by bonds, whatever the pair list does with them (error
    /// reports tell them from unbonded neighbours).
    fn bonded_pairs(&self) -> Option<&Exclusions> {
        self.exclusions()
    }

    /// Whether particles carry angular velocity and torque (integrated as
    /// solid spheres).
    fn rotational(&self) -> bool {
        false
    }

    /// The energy terms of [`ModelTally::terms`], in order; these are the
    /// model's recorded columns.
    fn energy_terms(&self) -> &'static [EnergyTerm];

    /// Called when a stage starts, with the stage's granular walls, which
    /// touch particles through the model's own contact law: per-stage
    /// state (such as the walls' contact histories, which LAMMPS
    /// re-creates each stage) starts afresh. A model without such a law
    /// refuses walls.
    fn begin_stage(&mut self, granular_walls: &[GranularWall]) -> Result<(), EngineError> {
        if granular_walls.is_empty() {
            Ok(())
        } else {
            Err(EngineError::Unsupported {
                what: "granular walls (they need DEM spheres)",
            })
        }
    }

    /// Adds the model's forces for the state in `input` to `out`.
    fn compute(&mut self, input: &ForceInput<'_>, out: &mut ForceOutput<'_>) -> ModelTally;

    /// The model's verdict on its last force evaluation, beyond the
    /// interactions' faults (for example a sphere through a granular wall):
    /// an error stops the run at `step`.
    fn verdict(&self, step: u64) -> Result<(), EngineError> {
        let _ = step;
        Ok(())
    }

    /// The likely cause of `fault` at timestep `dt`, in words; `mass` is
    /// the first particle's, `nearest_unbonded` the distance from either
    /// particle to its nearest unbonded neighbour over the contact
    /// distance.
    fn likely_cause(&self, fault: &Fault, dt: f64, mass: f64, nearest_unbonded: f64) -> String {
        fault.likely_cause(dt, None, mass, nearest_unbonded)
    }

    /// Everything of the model that a step or a stage changes (contact
    /// histories, reference lengths, the force field of the current
    /// stage), in the model's own serialised form, for checkpoints.
    fn save_state(&self) -> Result<ciborium::Value, EngineError>;

    /// Puts back a state that [`ParticleModel::save_state`] saved from a
    /// model of the same kind on the same scene.
    fn restore_state(&mut self, state: ciborium::Value) -> Result<(), EngineError>;

    /// The model as [`Any`], to reach model-specific state (e.g. a stage
    /// that resets bond reference lengths).
    fn as_any(&self) -> &dyn Any;

    /// Mutable [`ParticleModel::as_any`].
    fn as_any_mut(&mut self) -> &mut dyn Any;
}
