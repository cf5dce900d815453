//! The particle system and its velocity-Verlet step.
//!
//! One step follows LAMMPS's order so both engines can be compared step for
//! step: half kick and drift, neighbour check, forces (model, then external),
//! half kick, then box changes (deformation, barostat) with affine remap.

use super::bpm::{BpmModel, InteractionTally};
use super::deform::{Barostat, Deformation};
use super::external::{apply_viscous, ActiveTether, FlatWall, SphereWall};
use super::neighbor::NeighbourList;
use super::simbox::SimBox;
use super::timers::{Stage, Timers};
use super::topology::BondTopology;
use super::EngineError;
use crate::kernels::Tally;

/// The interaction model of a system. A second model (DEM spheres with
/// rotation) becomes a second variant; dispatch happens once per step.
#[derive(Debug)]
pub enum ForceModel {
    /// Bonded particle model with the multibody volume term.
    Bpm(BpmModel),
}

impl ForceModel {
    fn pair_cutoff(&self) -> Option<f64> {
        match self {
            ForceModel::Bpm(m) => m.pair_cutoff(),
        }
    }
}

/// Everything a stage adds on top of the interaction model.
#[derive(Debug, Default)]
pub struct StageDrivers {
    /// Time step (tau).
    pub dt: f64,
    /// Flat walls.
    pub walls: Vec<FlatWall>,
    /// A spherical wall.
    pub sphere_wall: Option<SphereWall>,
    /// A centre-of-mass tether, resolved against the particles.
    pub tether: Option<ActiveTether>,
    /// Viscous damping coefficient (m / tau), 0 for none.
    pub viscous: f64,
    /// Box deformation.
    pub deformation: Option<Deformation>,
    /// Barostat.
    pub barostat: Option<Barostat>,
    /// Sum energy and virial on stage steps that are multiples of this
    /// (0 = never); a barostat forces it on every step.
    pub tally_every: u64,
}

impl StageDrivers {
    fn tally_at(&self, stage_step: u64) -> bool {
        self.barostat.is_some() || (self.tally_every > 0 && stage_step % self.tally_every == 0)
    }
}

/// Observables of the last force evaluation.
#[derive(Clone, Debug, Default)]
pub struct StepReport {
    /// Bond and pair energy and virial.
    pub interactions: InteractionTally,
    /// Normal force on each flat wall (k d units, >= 0).
    pub wall_forces: Vec<f64>,
    /// Position of each flat wall.
    pub wall_positions: Vec<f64>,
    /// Summed force magnitude on the spherical wall.
    pub sphere_wall_force: f64,
    /// Energy of walls and tether.
    pub external_energy: f64,
    /// Whether energies and virials were summed in this evaluation; when
    /// not, `interactions` is zero and the pressure tensor is not available.
    pub tallied: bool,
}

/// Particles, bonds, box and model, with the state of a run.
#[derive(Debug)]
pub struct System {
    /// The box.
    pub simbox: SimBox,
    /// Positions (wrapped into the box along periodic dimensions).
    pub x: Vec<[f64; 3]>,
    /// Velocities.
    pub v: Vec<[f64; 3]>,
    /// Forces of the last evaluation.
    pub f: Vec<[f64; 3]>,
    /// Periodic image counters: unwrapped = x + box image vector.
    pub image: Vec<[i32; 3]>,
    /// Grain id per particle.
    pub grain: Vec<u32>,
    /// Particle mass (uniform).
    pub mass: f64,
    /// The bonds.
    pub bonds: BondTopology,
    /// The interaction model.
    pub model: ForceModel,
    /// The pair neighbour list.
    pub neighbours: NeighbourList,
    /// Neighbour skin (d units).
    pub skin: f64,
    /// Threads used for force passes (1 = serial, no rayon).
    pub threads: usize,
    /// Steps taken.
    pub step: u64,
    /// Simulated time (tau).
    pub time: f64,
    /// Time per part of the step.
    pub timers: Timers,
    /// Observables of the last force evaluation.
    pub report: StepReport,
    /// How many times positions were wrapped into the box.
    pub wraps: u64,
}

impl System {
    /// Kinetic energy.
    pub fn kinetic_energy(&self) -> f64 {
        0.5 * self.mass
            * self
                .v
                .iter()
                .map(|v| v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
                .sum::<f64>()
    }

    /// Pressure tensor `[xx, yy, zz, xy, xz, yz]` from kinetic and virial
    /// parts, positive in compression (LAMMPS `compute pressure`).
    pub fn pressure_tensor(&self) -> [f64; 6] {
        let mut p = self.interaction_tally().virial;
        for v in &self.v {
            p[0] += self.mass * v[0] * v[0];
            p[1] += self.mass * v[1] * v[1];
            p[2] += self.mass * v[2] * v[2];
            p[3] += self.mass * v[0] * v[1];
            p[4] += self.mass * v[0] * v[2];
            p[5] += self.mass * v[1] * v[2];
        }
        let inv = 1.0 / self.simbox.volume();
        p.map(|c| c * inv)
    }

    /// Scalar pressure, the mean of the diagonal of the pressure tensor.
    pub fn pressure(&self) -> f64 {
        let p = self.pressure_tensor();
        (p[0] + p[1] + p[2]) / 3.0
    }

    /// Wraps positions and rebuilds the pair list if atoms may have moved
    /// into range. Does nothing for a model without pair contacts.
    fn update_neighbours(&mut self, force: bool) {
        let Some(cutoff) = self.model.pair_cutoff() else {
            return;
        };
        let _t = self.timers.start(Stage::Neighbours);
        if force
            || self
                .neighbours
                .needs_rebuild(&self.simbox, &self.x, self.skin)
        {
            for (x, n) in self.x.iter_mut().zip(self.image.iter_mut()) {
                self.simbox.wrap(x, n);
            }
            self.wraps += 1;
            self.neighbours
                .build(&self.simbox, &self.x, cutoff, self.skin, Some(&self.bonds));
        }
    }

    /// Zeroes and recomputes all forces for the stage's drivers at
    /// `elapsed` time into the stage.
    pub fn compute_forces(&mut self, drivers: &StageDrivers, elapsed: f64, tally: bool) {
        for f in &mut self.f {
            *f = [0.0; 3];
        }
        let interactions = match &mut self.model {
            ForceModel::Bpm(m) => m.compute(
                self.wraps,
                &self.simbox,
                &self.x,
                &self.v,
                &self.bonds,
                &self.neighbours,
                self.threads,
                tally,
                &mut self.timers,
                &mut self.f,
            ),
        };
        let _t = self.timers.start(Stage::External);
        let mut report = StepReport {
            interactions,
            tallied: tally,
            ..StepReport::default()
        };
        for wall in &drivers.walls {
            let (force, energy) = wall.apply(elapsed, &self.x, &mut self.f);
            report.wall_forces.push(force);
            report.wall_positions.push(wall.position_at(elapsed));
            report.external_energy += energy;
        }
        if let Some(sphere) = &drivers.sphere_wall {
            let (force, energy) = sphere.apply(elapsed, &self.x, &mut self.f);
            report.sphere_wall_force = force;
            report.external_energy += energy;
        }
        if let Some(tether) = &drivers.tether {
            report.external_energy += tether.apply(&self.simbox, &self.x, &self.image, &mut self.f);
        }
        if drivers.viscous != 0.0 {
            apply_viscous(drivers.viscous, &self.v, &mut self.f);
        }
        self.report = report;
    }

    /// Prepares a stage: forces the list build and evaluates forces once.
    pub fn setup(&mut self, drivers: &StageDrivers) {
        self.update_neighbours(true);
        self.compute_forces(drivers, 0.0, true);
    }

    /// One velocity-Verlet step; `stage_step` counts steps within the stage
    /// (1 for the first) and `stage_box` is the box at the stage's start.
    pub fn step(
        &mut self,
        drivers: &StageDrivers,
        stage_step: u64,
        stage_box: &SimBox,
    ) -> Result<(), EngineError> {
        let dt = drivers.dt;
        let half = 0.5 * dt / self.mass;
        {
            let _t = self.timers.start(Stage::Integrate);
            for ((x, v), f) in self.x.iter_mut().zip(self.v.iter_mut()).zip(&self.f) {
                for d in 0..3 {
                    v[d] += half * f[d];
                    x[d] += dt * v[d];
                }
            }
        }
        self.update_neighbours(false);
        let elapsed = stage_step as f64 * dt;
        self.compute_forces(drivers, elapsed, drivers.tally_at(stage_step));
        {
            let _t = self.timers.start(Stage::Integrate);
            for (v, f) in self.v.iter_mut().zip(&self.f) {
                for d in 0..3 {
                    v[d] += half * f[d];
                }
            }
        }
        self.step += 1;
        self.time += dt;
        if let Some(deformation) = &drivers.deformation {
            let new_box = deformation.box_at(stage_box, elapsed);
            self.remap_into(new_box);
        }
        if let Some(barostat) = &drivers.barostat {
            let pressure = self.pressure();
            let new_box =
                barostat
                    .step(&self.simbox, pressure)
                    .ok_or(EngineError::BarostatCollapse {
                        step: self.step,
                        pressure,
                    })?;
            self.remap_into(new_box);
        }
        Ok(())
    }

    /// Changes the box and maps positions affinely into it.
    pub fn remap_into(&mut self, new_box: SimBox) {
        let _t = self.timers.start(Stage::Integrate);
        for x in &mut self.x {
            new_box.remap_from(&self.simbox, x);
        }
        self.simbox = new_box;
    }

    /// Checks that positions, velocities and forces are finite and that no
    /// particle left a closed dimension of the box.
    pub fn check_finite(&self) -> Result<(), EngineError> {
        let bad = |a: &[[f64; 3]]| a.iter().position(|r| !r.iter().all(|c| c.is_finite()));
        if let Some(i) = bad(&self.x)
            .or_else(|| bad(&self.v))
            .or_else(|| bad(&self.f))
        {
            return Err(EngineError::NonFinite {
                step: self.step,
                particle: i,
            });
        }
        // A closed dimension confines particles, as LAMMPS's fixed boundary
        // does (it loses atoms that leave): same scene, same verdict.
        if !self.simbox.periodic.iter().all(|&p| p) {
            for (i, x) in self.x.iter().enumerate() {
                let s = self.simbox.to_fractional(x);
                if let Some(d) =
                    (0..3).find(|&d| !self.simbox.periodic[d] && !(0.0..=1.0).contains(&s[d]))
                {
                    return Err(EngineError::LeftBox {
                        step: self.step,
                        particle: i,
                        dimension: d,
                    });
                }
            }
        }
        Ok(())
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// Whether the system has no particles.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// Sets every bond's reference length to its current length.
    pub fn reset_bond_reference(&mut self) {
        self.bonds.reset_reference(&self.simbox, &self.x);
        let n = self.x.len();
        match &mut self.model {
            ForceModel::Bpm(m) => m.set_reference(n, &self.bonds),
        }
    }

    /// Energy and virial of bonds and pairs together.
    pub fn interaction_tally(&self) -> Tally {
        self.report
            .interactions
            .bonds
            .merged(&self.report.interactions.pairs)
    }
}
