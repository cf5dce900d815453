//! DEM spheres as a particle model of the engine: one rigid sphere per
//! grain, Hertz-Mindlin contacts with sliding, rolling and twisting
//! friction (`kernels::granular_contact`), integrated with rotation.
//!
//! The model owns the contact coefficients, the per-contact history of
//! pairs ([`ContactStore`]) and of the stage's flat granular walls, which it
//! applies too, and the optional multi-contact closure, a pass before the
//! contact forces that corrects every contact's overlap ([`ClosurePass`]).
//! LAMMPS's `pair_style granular` computes no energy, so neither does this
//! model: its recorded observables are the stress (the virial of the
//! contact forces) and the kinetic energies.

mod contact_pass;
mod contacts;
mod multicontact;
mod wall;

pub use contacts::ContactStore;
pub use multicontact::{BeyondReach, ClosurePass, ClosureReport, MultiContact};
pub use wall::ActiveGranularWall;

use super::external::{GranularWall, WallContact, WallSide};
use super::model::{EnergyTerm, ForceInput, ForceOutput, ModelTally, ParticleModel};
use super::neighbor::Exclusions;
use super::parallel::{Scratch, Vec3};
use super::timers::Stage;
use super::EngineError;
use crate::kernels::{BoxImage, ContactHistory, GranularCoeffs, GranularMaterial, Isa, Tally};
use contact_pass::{contact_forces, ContactPass};

/// DEM spheres of one material.
#[derive(Debug)]
pub struct DemModel {
    material: GranularMaterial,
    coeffs: GranularCoeffs,
    /// Largest sphere radius: contacts reach `2 max_radius`, and with the
    /// closure `2 max_radius (1 + reach)`.
    max_radius: f64,
    contacts: ContactStore,
    /// The stage's granular walls, resolved against the material.
    walls: Vec<ActiveGranularWall>,
    /// Per granular wall of the stage, one contact history per sphere.
    wall_histories: Vec<Vec<ContactHistory>>,
    /// Each wall's axis and side, for carrying loads across stages.
    wall_planes: Vec<(usize, WallSide)>,
    /// Whether the next evaluation starts a stage.
    stage_start: bool,
    /// The multi-contact closure, if on.
    closure: Option<ClosurePass>,
    /// What the last force evaluation found.
    report: DemReport,
    /// The instruction set of the contact blocks.
    isa: Isa,
    /// Whether Hertz-Mindlin contacts are formed four at a time (the
    /// default; rolling or twisting resistance is always one at a time).
    contact_blocks: bool,
    /// The contact pass's per-thread force and torque buffers.
    force_scratch: Scratch<Vec3>,
}

/// What a step or a stage changes in the model: the current force field,
/// the contact histories of pairs and walls, and whether the next
/// evaluation starts a stage. The closure's corrections follow from these.
#[derive(serde::Serialize, serde::Deserialize)]
struct DemState {
    material: GranularMaterial,
    multicontact: Option<MultiContact>,
    contacts: ContactStore,
    wall_histories: Vec<Vec<ContactHistory>>,
    wall_planes: Vec<(usize, WallSide)>,
    stage_start: bool,
}

/// What DEM spheres report of one force evaluation, beyond forces and
/// stress.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DemReport {
    /// What each granular wall of the stage felt, in order.
    pub walls: Vec<WallContact>,
    /// Each granular wall's position.
    pub wall_positions: Vec<f64>,
    /// The multi-contact closure's pass, if the model has one.
    pub closure: Option<ClosureReport>,
}

impl DemModel {
    /// Spheres of `material` whose largest radius is `max_radius`, with
    /// the multi-contact closure `multicontact` (`None` for plain Hertz).
    pub fn new(
        material: GranularMaterial,
        max_radius: f64,
        multicontact: Option<MultiContact>,
    ) -> Self {
        Self {
            material,
            coeffs: GranularCoeffs::of(&material),
            max_radius,
            contacts: ContactStore::default(),
            walls: Vec::new(),
            wall_histories: Vec::new(),
            wall_planes: Vec::new(),
            stage_start: true,
            closure: multicontact.map(|m| ClosurePass::new(m, &material)),
            report: DemReport::default(),
            isa: Isa::detect(),
            contact_blocks: true,
            force_scratch: Scratch::default(),
        }
    }

    /// What the last force evaluation found: the granular walls' loads
    /// and the closure's corrections.
    pub fn report(&self) -> &DemReport {
        &self.report
    }

    /// The stage's granular walls, resolved against the material.
    pub fn walls(&self) -> &[ActiveGranularWall] {
        &self.walls
    }

    /// The material.
    pub fn material(&self) -> &GranularMaterial {
        &self.material
    }

    /// The multi-contact closure's pass (its last corrections), if it is
    /// on.
    pub fn closure_pass(&self) -> Option<&ClosurePass> {
        self.closure.as_ref()
    }

    /// The multi-contact closure's settings, if it is on.
    pub fn multicontact(&self) -> Option<&MultiContact> {
        self.closure.as_ref().map(|c| c.settings())
    }

    /// Replaces the material and the closure (a stage's force-field
    /// change); contact histories are kept, as LAMMPS keeps them across
    /// `pair_coeff`.
    pub fn set_force_field(
        &mut self,
        material: GranularMaterial,
        multicontact: Option<MultiContact>,
    ) {
        self.material = material;
        self.coeffs = GranularCoeffs::of(&material);
        self.closure = multicontact.map(|m| ClosurePass::new(m, &material));
    }

    /// Forms contacts four at a time (`true`, the default) or one at a
    /// time: the same numbers bit for bit, at another speed (for tests and
    /// benchmarks).
    pub fn set_contact_blocks(&mut self, on: bool) {
        self.contact_blocks = on;
    }

    /// The per-contact histories.
    pub fn contacts(&self) -> &ContactStore {
        &self.contacts
    }

    /// The contact forces of every listed pair, on the model's thread
    /// team ([`contact_forces`]).
    fn forces(
        &mut self,
        sep: &BoxImage,
        input: &ForceInput<'_>,
        f: &mut [[f64; 3]],
        torque: Option<&mut [[f64; 3]]>,
    ) -> Tally {
        let pass = ContactPass {
            coeffs: &self.coeffs,
            isa: self.isa,
            blocks: self.coeffs.lanes_cover() && self.contact_blocks,
            sep,
            input,
            corrections: self.closure.as_ref().map(|c| c.pair_corrections()),
        };
        contact_forces(
            &pass,
            &mut self.contacts.history,
            &mut self.force_scratch,
            f,
            torque,
        )
    }
}

impl DemModel {
    /// A stage's walls start with fresh contact histories, as LAMMPS
    /// re-creates its walls each stage: their friction springs start
    /// unloaded. Only the load a wall at the same place in the list, on
    /// the same axis and side, carried at the last evaluation is kept, for
    /// the multi-contact closure, which would otherwise lose the walls'
    /// forces for the stage's first evaluation (it does not enter the
    /// contact force itself). A wall with `keep_history` keeps that
    /// wall's whole histories, springs included.
    fn renew_wall_histories(&mut self, n: usize) {
        let planes: Vec<(usize, WallSide)> = self
            .walls
            .iter()
            .map(|w| (w.wall.axis, w.wall.side))
            .collect();
        let fresh = (0..self.walls.len())
            .map(|w| {
                let mut history = vec![ContactHistory::default(); n];
                let same = self.wall_planes.get(w) == Some(&planes[w]);
                let (Some(old), true) = (self.wall_histories.get(w), same) else {
                    return history;
                };
                if self.walls[w].wall.keep_history && old.len() == n {
                    return old.clone();
                }
                for (h, o) in history.iter_mut().zip(old) {
                    h.normal_force = o.normal_force;
                }
                history
            })
            .collect();
        self.wall_histories = fresh;
        self.wall_planes = planes;
    }
}

impl ParticleModel for DemModel {
    fn name(&self) -> &'static str {
        "dem"
    }

    fn pair_cutoff(&self) -> Option<f64> {
        // The closure's corrections may bring pairs within its reach into
        // contact.
        let reach = self.closure.as_ref().map_or(0.0, |c| c.settings().reach);
        Some(2.0 * self.max_radius * (1.0 + reach))
    }

    fn exclusions(&self) -> Option<&Exclusions> {
        None
    }

    fn rotational(&self) -> bool {
        true
    }

    fn energy_terms(&self) -> &'static [EnergyTerm] {
        &[]
    }

    fn begin_stage(&mut self, granular_walls: &[GranularWall]) -> Result<(), EngineError> {
        self.walls = granular_walls
            .iter()
            .map(|w| ActiveGranularWall::new(w, &self.material))
            .collect();
        self.stage_start = true;
        Ok(())
    }

    fn verdict(&self, step: u64) -> Result<(), EngineError> {
        let through = self.report.walls.iter().enumerate();
        if let Some((wall, particle)) = through
            .filter_map(|(w, c)| c.through.map(|i| (w, i)))
            .next()
        {
            return Err(EngineError::ThroughGranularWall {
                step,
                wall,
                particle,
            });
        }
        let Some(closure) = &self.report.closure else {
            return Ok(());
        };
        if let Some((sphere, ratio)) = closure.collapsed {
            return Err(EngineError::ClosureCollapsed {
                step,
                sphere,
                ratio,
            });
        }
        if let Some(beyond) = closure.beyond_reach {
            return Err(EngineError::ClosureBeyondReach {
                step,
                sphere: beyond.sphere,
                partner: if beyond.wall {
                    format!("granular wall {}", beyond.partner)
                } else {
                    format!("sphere {}", beyond.partner)
                },
                ratio: beyond.ratio,
                reach: self.multicontact().map_or(f64::NAN, |m| m.reach),
            });
        }
        Ok(())
    }

    fn compute(&mut self, input: &ForceInput<'_>, out: &mut ForceOutput<'_>) -> ModelTally {
        let _t = out.timers.start(Stage::Pairs);
        let sep = BoxImage::of(&input.simbox.minimum_image());
        let n = input.x.len();
        if std::mem::take(&mut self.stage_start)
            || self.wall_histories.len() != self.walls.len()
            || self.wall_histories.iter().any(|h| h.len() != n)
        {
            self.renew_wall_histories(n);
        }
        self.contacts.align(input.neighbours);
        let mut report = std::mem::take(&mut self.report);
        report.closure = None;
        if let Some(closure) = &mut self.closure {
            closure.update(
                &sep,
                input,
                &self.contacts.history,
                &self.walls,
                &self.wall_histories,
            );
            report.closure = Some(*closure.report());
        }
        let mut tally = ModelTally::default();
        tally.terms[0] = self.forces(&sep, input, out.f, out.torque.as_deref_mut());
        report.walls.clear();
        report.wall_positions.clear();
        for (w, (wall, history)) in self.walls.iter().zip(&mut self.wall_histories).enumerate() {
            let corrections = self.closure.as_ref().map(|c| c.wall_corrections(w));
            report.walls.push(wall.apply(
                input,
                out.f,
                out.torque.as_deref_mut(),
                history,
                corrections,
                self.contact_blocks.then_some(self.isa),
            ));
            report
                .wall_positions
                .push(wall.wall.position_at(input.elapsed));
        }
        self.report = report;
        tally
    }

    fn save_state(&self) -> Result<ciborium::Value, EngineError> {
        let state = DemState {
            material: self.material,
            multicontact: self.multicontact().copied(),
            contacts: self.contacts.clone(),
            wall_histories: self.wall_histories.clone(),
            wall_planes: self.wall_planes.clone(),
            stage_start: self.stage_start,
        };
        ciborium::Value::serialized(&state).map_err(|e| EngineError::StateMismatch {
            what: format!("the DEM model's state could not be saved: {e}"),
        })
    }

    fn restore_state(&mut self, state: ciborium::Value) -> Result<(), EngineError> {
        let state: DemState = state
            .deserialized()
            .map_err(|e| EngineError::StateMismatch {
                what: format!("it is not a DEM model's state: {e}"),
            })?;
        self.set_force_field(state.material, state.multicontact);
        // The stage's walls were resolved against the material before it
        // was restored.
        self.walls = self
            .walls
            .iter()
            .map(|w| ActiveGranularWall::new(&w.wall, &self.material))
            .collect();
        self.contacts = state.contacts;
        self.wall_histories = state.wall_histories;
        self.wall_planes = state.wall_planes;
        self.stage_start = state.stage_start;
        Ok(())
    }

    fn as_any(&self) -> &dyn std::any::Any {
        self
    }

    fn as_any_mut(&mut self) -> &mut dyn std::any::Any {
        self
    }
}
