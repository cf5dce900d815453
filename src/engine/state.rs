//! A run's state between two steps, saved whole and restored whole, so a run
//! resumed from a checkpoint takes the same steps as one never interrupted.
//!
//! Bit-for-bit continuation needs more than positions and velocities: the
//! forces of the last evaluation (the next half kick uses them), the pair
//! list with its reference positions (its rebuild schedule and the order in
//! which pair forces are summed), the wrap count (the bond layout is cached
//! per wrap), and the model's own history. Scratch buffers and timers are
//! left out; they carry no state from one step to the next.

use super::deform::LeesEdwards;
use super::external::Gravity;
use super::neighbor::NeighbourList;
use super::particles::Particles;
use super::simbox::SimBox;
use super::system::{StageDrivers, System};
use super::EngineError;
use serde::{Deserialize, Serialize};

/// The state of a [`System`] between two steps.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct EngineState {
    /// The model's name ([`super::ParticleModel::name`]).
    pub model: String,
    /// The box.
    pub simbox: SimBox,
    /// Every per-particle array, forces and torques included.
    pub particles: Particles,
    /// The pair list and its rebuild reference.
    pub neighbours: NeighbourList,
    /// The neighbour skin of the current force field.
    pub skin: f64,
    /// The gravity of the current force field.
    pub gravity: Option<Gravity>,
    /// Steps taken.
    pub step: u64,
    /// Simulated time.
    pub time: f64,
    /// How many times positions were wrapped.
    pub wraps: u64,
    /// Simulated time at the start of the current stage.
    pub stage_start_time: f64,
    /// The current stage's Lees-Edwards boundaries.
    pub lees_edwards: Option<LeesEdwards>,
    /// The model's own state.
    pub model_state: ciborium::Value,
}

impl System {
    /// The state between two steps.
    pub fn save_state(&self) -> Result<EngineState, EngineError> {
        Ok(EngineState {
            model: self.model.name().to_string(),
            simbox: self.simbox.clone(),
            particles: self.particles.clone(),
            neighbours: self.neighbours.clone(),
            skin: self.skin,
            gravity: self.gravity,
            step: self.step,
            time: self.time,
            wraps: self.wraps,
            stage_start_time: self.stage_start_time,
            lees_edwards: self.lees_edwards,
            model_state: self.model.save_state()?,
        })
    }

    /// Continues a stage from `state`, saved by [`System::save_state`] from
    /// a system built from the same scene, in place of
    /// [`System::setup`]: the model takes the stage's walls, then every
    /// saved value replaces the current one. Nothing is recomputed, so the
    /// next step is the one the saved run would have taken.
    pub fn resume(
        &mut self,
        drivers: &StageDrivers,
        state: EngineState,
    ) -> Result<(), EngineError> {
        self.model.begin_stage(&drivers.external.granular_walls)?;
        self.restore(state)
    }

    /// Replaces the system's state by `state`, saved by
    /// [`System::save_state`] from a system built from the same scene
    /// (between stages; inside one, [`System::resume`]).
    pub fn restore(&mut self, state: EngineState) -> Result<(), EngineError> {
        let mismatch = |what: String| Err(EngineError::StateMismatch { what });
        if state.model != self.model.name() {
            return mismatch(format!(
                "it was saved from model `{}`, this system has `{}`",
                state.model,
                self.model.name()
            ));
        }
        let p = &state.particles;
        if p.len() != self.particles.len() {
            return mismatch(format!(
                "it has {} particles, this system {}",
                p.len(),
                self.particles.len()
            ));
        }
        if p.rotation.is_some() != self.particles.rotation.is_some() {
            return mismatch("one of them has rotating particles, the other not".into());
        }
        self.model.restore_state(state.model_state)?;
        self.simbox = state.simbox;
        self.particles = state.particles;
        self.neighbours = state.neighbours;
        self.skin = state.skin;
        self.gravity = state.gravity;
        self.step = state.step;
        self.time = state.time;
        self.wraps = state.wraps;
        self.stage_start_time = state.stage_start_time;
        self.lees_edwards = state.lees_edwards;
        Ok(())
    }
}
