//! The particle system and its velocity-Verlet step.
//!
//! One step follows LAMMPS's order so both engines can be compared step for
//! step: half kick and drift, neighbour check, forces (model, then external),
//! half kick, then box changes (deformation, barostat) with affine remap
//! (or, for Lees-Edwards shear, none: the images move instead).

use super::clamp::{check_clamps, Clamp};
use super::deform::{Barostat, Deformation, LeesEdwards};
use super::external::{ExternalReport, ExternalTerms, Gravity};
use super::integrator::Integrator;
use super::model::{ForceInput, ForceOutput, ModelTally, ParticleModel};
use super::neighbor::NeighbourList;
use super::particles::Particles;
use super::simbox::SimBox;
use super::team::Team;
use super::timers::{Stage, Timers};
use super::EngineError;
use crate::kernels::{Fault, Separation, Tally};

/// Everything a stage adds on top of the interaction model.
#[derive(Debug, Default)]
pub struct StageDrivers {
    /// Time step (tau).
    pub dt: f64,
    /// Forces from outside the model: walls, tether, damping, gravity.
    pub external: ExternalTerms,
    /// Box deformation.
    pub deformation: Option<Deformation>,
    /// Barostat.
    pub barostat: Option<Barostat>,
    /// Groups moved at a constant velocity, out of the integrator's hands.
    pub clamps: Vec<Clamp>,
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
    /// Energy per model term and virial.
    pub interactions: ModelTally,
    /// What the external terms did (the model reports its granular walls).
    pub external: ExternalReport,
    /// Whether energies and virials were summed in this evaluation; when
    /// not, `interactions` is zero and the pressure tensor is not available.
    pub tallied: bool,
    /// The first interaction outside the model's range.
    pub fault: Option<Fault>,
}

/// Particles, box and model, with the state of a run.
#[derive(Debug)]
pub struct System {
    /// The box.
    pub simbox: SimBox,
    /// The particles.
    pub particles: Particles,
    /// The particle model (bonded particles, DEM spheres, ...).
    pub model: Box<dyn ParticleModel>,
    /// How particles move: translational, or with rotation.
    pub integrator: Integrator,
    /// The pair neighbour list.
    pub neighbours: NeighbourList,
    /// Neighbour skin (d units).
    pub skin: f64,
    /// The force field's gravity, which every stage's external terms
    /// include.
    pub gravity: Option<Gravity>,
    /// Threads used for force passes (1 = serial).
    pub threads: usize,
    /// The threads themselves, made anew when `threads` changes.
    team: Team,
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
    /// Simulated time at the start of the current stage (tau).
    pub(super) stage_start_time: f64,
    /// The current stage's Lees-Edwards boundaries, if it shears with them.
    pub(super) lees_edwards: Option<LeesEdwards>,
}

impl System {
    /// A system of `particles` in `simbox` with `model`; rotational
    /// models get angular velocities and the rotational integrator.
    pub fn new(
        simbox: SimBox,
        mut particles: Particles,
        model: Box<dyn ParticleModel>,
        skin: f64,
        threads: usize,
    ) -> Self {
        if model.rotational() {
            particles.enable_rotation();
        }
        Self {
            simbox,
            integrator: Integrator::for_particles(&particles),
            particles,
            model,
            neighbours: NeighbourList::default(),
            skin,
            gravity: None,
            threads: threads.max(1),
            team: Team::new(threads),
            step: 0,
            time: 0.0,
            timers: Timers::default(),
            report: StepReport::default(),
            wraps: 0,
            stage_start_time: 0.0,
            lees_edwards: None,
        }
    }

    /// The model as its concrete type, if it is one.
    pub fn model_as<M: ParticleModel>(&self) -> Option<&M> {
        self.model.as_any().downcast_ref::<M>()
    }

    /// Mutable [`System::model_as`].
    pub fn model_as_mut<M: ParticleModel>(&mut self) -> Option<&mut M> {
        self.model.as_any_mut().downcast_mut::<M>()
    }

    /// Translational kinetic energy.
    pub fn kinetic_energy(&self) -> f64 {
        self.particles.kinetic_energy()
    }

    /// Pressure tensor `[xx, yy, zz, xy, xz, yz]` from kinetic and virial
    /// parts, positive in compression (LAMMPS `compute pressure`). Under
    /// Lees-Edwards boundaries the kinetic part counts peculiar velocities,
    /// relative to the streaming profile (LAMMPS `compute temp/deform`).
    pub fn pressure_tensor(&self) -> [f64; 6] {
        let mut p = self.interaction_tally().virial;
        self.add_kinetic_tensor(&mut p);
        let inv = 1.0 / self.simbox.volume();
        p.map(|c| c * inv)
    }

    fn add_kinetic_tensor(&self, p: &mut [f64; 6]) {
        match &self.lees_edwards {
            Some(le) => self
                .particles
                .add_peculiar_kinetic_tensor(&self.simbox, le, p),
            None => self.particles.add_kinetic_tensor(p),
        }
    }

    /// Scalar pressure, the mean of the diagonal of the pressure tensor.
    pub fn pressure(&self) -> f64 {
        let p = self.pressure_tensor();
        (p[0] + p[1] + p[2]) / 3.0
    }

    /// LAMMPS's scalar pressure (`compute pressure` with `compute temp`):
    /// the kinetic part is `dof T` with `3N - 3` degrees of freedom, which
    /// equals `sum m v^2` except that a single particle has none; then
    /// `(dof T + W_xx + W_yy + W_zz) / 3 / V`, in LAMMPS's order of
    /// operations. The barostat drives this number.
    pub fn scalar_pressure(&self) -> f64 {
        let p = &self.particles;
        let dof = (3 * p.len()) as f64 - 3.0;
        let sum_mv2: f64 = match &self.lees_edwards {
            Some(_) => {
                let mut k = [0.0; 6];
                self.add_kinetic_tensor(&mut k);
                k[0] + k[1] + k[2]
            }
            // Each thread sums its own share of the velocities, which it
            // has just updated: read by one thread, the others' shares would
            // cross between the cores' caches twice a step.
            None => self.team.map_reduce(
                p.len(),
                0.0,
                |range| {
                    p.v[range.clone()]
                        .iter()
                        .zip(&p.mass[range])
                        .map(|(v, &m)| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) * m)
                        .sum::<f64>()
                },
                |a, b| a + b,
            ),
        };
        let temperature = if dof > 0.0 {
            sum_mv2 * (1.0 / dof)
        } else {
            0.0
        };
        let w = self.interaction_tally().virial;
        let [lx, ly, lz] = self.simbox.lengths;
        (dof * temperature + w[0] + w[1] + w[2]) / 3.0 * (1.0 / (lx * ly * lz))
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
                .needs_rebuild(&self.simbox, &self.particles.x, self.skin, &self.team)
        {
            self.particles
                .wrap(&self.simbox, self.lees_edwards.as_ref());
            self.wraps += 1;
            self.neighbours.build_on(
                &self.team,
                &self.simbox,
                &self.particles.x,
                cutoff,
                self.skin,
                self.model.exclusions(),
            );
        }
    }

    /// Zeroes and recomputes all forces for the stage's drivers at
    /// `elapsed` time into the stage.
    pub fn compute_forces(&mut self, drivers: &StageDrivers, elapsed: f64, tally: bool) {
        self.evaluate(drivers, elapsed, tally, None);
    }

    /// [`System::compute_forces`] as the end of a step of `step_dt` (the
    /// model advances its contact history) or, with `None`, outside one.
    fn evaluate(
        &mut self,
        drivers: &StageDrivers,
        elapsed: f64,
        tally: bool,
        step_dt: Option<f64>,
    ) {
        self.particles.clear_forces();
        self.renew_team();
        let p = &mut self.particles;
        let (omega, torque) = match &mut p.rotation {
            Some(r) => (Some(&r.omega[..]), Some(&mut r.torque[..])),
            None => (None, None),
        };
        let input = ForceInput {
            simbox: &self.simbox,
            x: &p.x,
            v: &p.v,
            omega,
            radius: &p.radius,
            mass: &p.mass,
            step_dt,
            neighbours: &self.neighbours,
            wraps: self.wraps,
            team: &self.team,
            tally,
            lees_edwards: self.lees_edwards,
            elapsed,
        };
        let mut output = ForceOutput {
            f: &mut p.f,
            torque,
            timers: &mut self.timers,
            fault: None,
        };
        let interactions = self.model.compute(&input, &mut output);
        let fault = output.fault;
        let _t = self.timers.start(Stage::External);
        let external = drivers.external.apply(elapsed, &self.simbox, p);
        self.report = StepReport {
            interactions,
            external,
            tallied: tally,
            fault,
        };
    }

    /// Makes the team anew if `threads` changed since it was made.
    fn renew_team(&mut self) {
        if self.team.threads() != self.threads.max(1) {
            self.team = Team::new(self.threads);
        }
    }

    /// Prepares a stage: checks its clamps (an error if the engine cannot
    /// hold them), hands the model the stage's granular walls (an error if
    /// it cannot apply them), forces the list build and evaluates forces
    /// once.
    pub fn setup(&mut self, drivers: &StageDrivers) -> Result<(), EngineError> {
        let box_changes = drivers.deformation.is_some() || drivers.barostat.is_some();
        check_clamps(
            &drivers.clamps,
            self.particles.len(),
            self.simbox.periodic,
            box_changes,
        )?;
        self.stage_start_time = self.time;
        self.lees_edwards = drivers
            .deformation
            .as_ref()
            .and_then(|d| d.lees_edwards(&self.simbox));
        self.model.begin_stage(&drivers.external.granular_walls)?;
        self.update_neighbours(true);
        self.compute_forces(drivers, 0.0, true);
        Ok(())
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
        self.renew_team();
        {
            let _t = self.timers.start(Stage::Integrate);
            self.integrator.initial(&mut self.particles, dt, &self.team);
        }
        let elapsed = stage_step as f64 * dt;
        for clamp in &drivers.clamps {
            clamp.place(elapsed, &mut self.particles);
        }
        self.update_neighbours(false);
        self.evaluate(drivers, elapsed, drivers.tally_at(stage_step), Some(dt));
        self.step += 1;
        self.check_faults(dt)?;
        self.check_walls()?;
        {
            let _t = self.timers.start(Stage::Integrate);
            self.integrator
                .final_half(&mut self.particles, dt, &self.team);
        }
        for clamp in &drivers.clamps {
            clamp.hold_velocity(&mut self.particles);
        }
        // Stage start plus steps times dt, not a running sum: no round-off
        // grows with the step count, and LAMMPS's harness computes the same.
        self.time = self.stage_start_time + stage_step as f64 * dt;
        if let Some(deformation) = &drivers.deformation {
            let new_box = deformation.box_at(stage_box, elapsed);
            if deformation.remaps_positions() {
                self.remap_into(new_box);
            } else {
                self.keep_unwrapped_through_flips(&new_box);
                self.simbox = new_box;
            }
        }
        if let Some(barostat) = &drivers.barostat {
            let pressure = self.scalar_pressure();
            let new_box =
                barostat
                    .step(&self.simbox, pressure)
                    .ok_or(EngineError::BarostatCollapse {
                        step: self.step,
                        pressure,
                    })?;
            self.remap_into(new_box);
        }
        // Only a deformed or barostatted box can have shrunk; check it
        // before the next evaluation uses it.
        if drivers.deformation.is_some() || drivers.barostat.is_some() {
            self.check_box()?;
        }
        Ok(())
    }

    /// The verdict of the last force evaluation on its interactions: an
    /// error naming the particles and the likely cause if one was outside
    /// the model's range (the onset of a blow-up).
    pub fn check_faults(&self, dt: f64) -> Result<(), EngineError> {
        match &self.report.fault {
            Some(fault) => {
                let pair = [fault.i as usize, fault.j as usize];
                let nearest = pair
                    .iter()
                    .map(|&p| self.nearest_unbonded(p))
                    .fold(f64::INFINITY, f64::min);
                let contact = self.model.pair_cutoff().unwrap_or(f64::NAN);
                Err(EngineError::Unstable {
                    step: self.step,
                    particles: pair,
                    what: fault.what(&format!("particles {} and {}", fault.i, fault.j)),
                    cause: self.model.likely_cause(
                        fault,
                        dt,
                        self.particles.mass[pair[0]],
                        nearest / contact,
                    ),
                })
            }
            None => Ok(()),
        }
    }

    /// Distance from particle `p` to its nearest particle not bonded to it
    /// (whether or not contacts are overlaid on bonds); a scan of all
    /// particles, for error reports only.
    fn nearest_unbonded(&self, p: usize) -> f64 {
        let sep = self.simbox.minimum_image();
        let bonded = self.model.bonded_pairs();
        let x = &self.particles.x;
        (0..x.len())
            .filter(|&q| q != p && !bonded.is_some_and(|e| e.excludes(p, q)))
            .map(|q| sep.distance(&x[p], &x[q]))
            .fold(f64::INFINITY, f64::min)
    }

    /// The verdict of the last force evaluation's walls and of the
    /// model's own checks: an error if a particle was on or behind a
    /// wall's plane or, for DEM spheres, the multi-contact corrections
    /// went beyond their reach.
    pub fn check_walls(&self) -> Result<(), EngineError> {
        if let Some((wall, particle)) = self.report.external.through_wall {
            return Err(EngineError::ThroughWall {
                step: self.step,
                wall,
                particle,
            });
        }
        self.model.verdict(self.step)
    }

    /// The box against the pair interactions' range, as the box deforms.
    /// The scene's check at load adds the skin; here the range alone
    /// counts, because forces use the minimum image at every evaluation:
    /// only a partner within range through two images at once is missed.
    fn check_box(&self) -> Result<(), EngineError> {
        let Some(cutoff) = self.model.pair_cutoff() else {
            return Ok(());
        };
        let faces = self.simbox.face_distances();
        match (0..3).find(|&d| self.simbox.periodic[d] && cutoff >= 0.5 * faces[d]) {
            Some(dimension) => Err(EngineError::BoxBelowCutoff {
                step: self.step,
                dimension,
                face: faces[dimension],
                cutoff,
            }),
            None => Ok(()),
        }
    }

    /// Before a Lees-Edwards box change that may flip the tilt: rewrites
    /// the image counters so that unwrapped positions `x + h n` stay where
    /// they are in the new box (a flip changes `h`, not the lattice).
    fn keep_unwrapped_through_flips(&mut self, new_box: &SimBox) {
        if new_box.tilt == self.simbox.tilt {
            return;
        }
        let old = &self.simbox;
        for n in &mut self.particles.image {
            if n[1] == 0 && n[2] == 0 {
                continue;
            }
            let w = old.image_vector(n);
            let at = [
                new_box.lo[0] + w[0],
                new_box.lo[1] + w[1],
                new_box.lo[2] + w[2],
            ];
            let s = new_box.to_fractional(&at);
            *n = s.map(|c| c.round() as i32);
        }
    }

    /// Changes the box and maps positions affinely into it.
    pub fn remap_into(&mut self, new_box: SimBox) {
        let _t = self.timers.start(Stage::Integrate);
        let remap = self.simbox.remap_to(&new_box);
        self.team.run_split(&mut self.particles.x, |_, _, x| {
            for x in x {
                remap.apply(x);
            }
        });
        self.simbox = new_box;
    }

    /// Checks that positions, velocities and forces are finite and that no
    /// particle left a closed dimension of the box.
    pub fn check_finite(&self) -> Result<(), EngineError> {
        let bad = |a: &[[f64; 3]]| a.iter().position(|r| !r.iter().all(|c| c.is_finite()));
        let p = &self.particles;
        let rotation = p.rotation.as_ref();
        if let Some(i) = bad(&p.x)
            .or_else(|| bad(&p.v))
            .or_else(|| bad(&p.f))
            .or_else(|| rotation.and_then(|r| bad(&r.omega).or_else(|| bad(&r.torque))))
        {
            return Err(EngineError::NonFinite {
                step: self.step,
                particle: i,
            });
        }
        // A closed dimension confines particles, as LAMMPS's fixed boundary
        // does (it loses atoms that leave): same scene, same verdict.
        if !self.simbox.periodic.iter().all(|&p| p) {
            for (i, x) in p.x.iter().enumerate() {
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
        self.particles.len()
    }

    /// Whether the system has no particles.
    pub fn is_empty(&self) -> bool {
        self.particles.is_empty()
    }

    /// Energy and virial of every model term together.
    pub fn interaction_tally(&self) -> Tally {
        self.report.interactions.total()
    }
}
