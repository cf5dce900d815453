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

mod contacts;
mod multicontact;
mod wall;

pub use contacts::ContactStore;
pub use multicontact::{BeyondReach, ClosurePass, ClosureReport, MultiContact};
pub use wall::ActiveGranularWall;

use super::external::{GranularWall, WallContact, WallSide};
use super::model::{EnergyTerm, ForceInput, ForceOutput, ModelTally, ParticleModel};
use super::neighbor::Exclusions;
use super::simbox::MinimumImage;
use super::timers::Stage;
use super::EngineError;
use crate::kernels::{
    corrected_granular_contact, hertz_mindlin_block, ContactBlock, ContactForce, ContactHistory,
    GranularCoeffs, GranularMaterial, Isa, Sphere, Tally, CONTACT_LANES,
};

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

    fn forces(
        &mut self,
        sep: &MinimumImage,
        input: &ForceInput<'_>,
        f: &mut [[f64; 3]],
        torque: Option<&mut [[f64; 3]]>,
    ) -> Tally {
        if !self.coeffs.lanes_cover() || !self.contact_blocks {
            self.forces_one_by_one(sep, input, f, torque)
        } else {
            self.forces_in_blocks(sep, input, f, torque)
        }
    }

    /// The contact forces of Hertz-Mindlin without rolling or twisting,
    /// touching pairs gathered four at a time into
    /// [`hertz_mindlin_block`]: the same forces, torques and histories as
    /// one pair at a time, bit for bit, added in the same order.
    fn forces_in_blocks(
        &mut self,
        sep: &MinimumImage,
        input: &ForceInput<'_>,
        f: &mut [[f64; 3]],
        torque: Option<&mut [[f64; 3]]>,
    ) -> Tally {
        let omega = input.omega.unwrap_or(&[]);
        let (v, radius, mass) = (input.v, input.radius, input.mass);
        let corrections = self.closure.as_ref().map(|c| c.pair_corrections());
        let (dt, update) = input.history_step();
        let history = &mut self.contacts.history;
        let mut tally = Tally::default();
        let mut block = ContactBlock::default();
        // Each lane's pair (i, j) and list entry.
        let mut pairs = [(0usize, 0usize, 0usize); CONTACT_LANES];
        let mut filled = 0;
        let mut sink = BlockSink {
            isa: self.isa,
            coeffs: &self.coeffs,
            dt,
            update,
            f,
            torque,
            tally: input.tally.then_some(&mut tally),
        };
        let spin = |i: usize| omega.get(i).copied().unwrap_or([0.0; 3]);
        touching_pairs(sep, input, corrections, history, |pair, history| {
            let TouchingPair {
                i,
                j,
                entry,
                del,
                partner_velocity,
                moved,
            } = pair;
            let (l, wi, wj, h) = (filled, spin(i), spin(j), history[entry].tangential);
            for d in 0..3 {
                block.del[d][l] = del[d];
                block.v[0][d][l] = v[i][d];
                block.v[1][d][l] = partner_velocity[d];
                block.omega[0][d][l] = wi[d];
                block.omega[1][d][l] = wj[d];
                block.tangential[d][l] = h[d];
            }
            for (side, sphere) in [i, j].into_iter().enumerate() {
                block.radius[side][l] = radius[sphere];
                block.mass[side][l] = mass[sphere];
                block.moved[side][l] = moved[side];
            }
            pairs[l] = (i, j, entry);
            filled += 1;
            if filled == CONTACT_LANES {
                sink.flush(&mut block, &pairs, history);
                filled = 0;
            }
        });
        if filled > 0 {
            // The spare lanes repeat the first contact and are not read.
            block.fill_from_first(filled);
            sink.flush(&mut block, &pairs[..filled], history);
        }
        tally
    }

    /// The contact forces one pair at a time: the law with rolling or
    /// twisting resistance.
    fn forces_one_by_one(
        &mut self,
        sep: &MinimumImage,
        input: &ForceInput<'_>,
        f: &mut [[f64; 3]],
        mut torque: Option<&mut [[f64; 3]]>,
    ) -> Tally {
        // The engine gives rotational models angular velocities; without
        // them (a caller's choice) spheres count as not spinning.
        let omega = input.omega.unwrap_or(&[]);
        let (v, radius, mass) = (input.v, input.radius, input.mass);
        let corrections = self.closure.as_ref().map(|c| c.pair_corrections());
        let (dt, update) = input.history_step();
        let mut tally = Tally::default();
        let sphere = |i: usize| Sphere {
            v: v[i],
            omega: omega.get(i).copied().unwrap_or([0.0; 3]),
            radius: radius[i],
            mass: mass[i],
        };
        let history = &mut self.contacts.history;
        touching_pairs(sep, input, corrections, history, |pair, history| {
            let TouchingPair {
                i,
                j,
                entry,
                del,
                partner_velocity,
                moved,
            } = pair;
            let sj = Sphere {
                v: partner_velocity,
                ..sphere(j)
            };
            let ContactForce {
                force,
                torque_i,
                torque_j,
            } = corrected_granular_contact(
                &self.coeffs,
                &del,
                &sphere(i),
                &sj,
                moved,
                &mut history[entry],
                dt,
                update,
            );
            for d in 0..3 {
                f[i][d] += force[d];
                f[j][d] -= force[d];
            }
            if let Some(t) = torque.as_deref_mut() {
                for d in 0..3 {
                    t[i][d] += torque_i[d];
                    t[j][d] += torque_j[d];
                }
            }
            if input.tally {
                tally.add_vector(1.0, &del, &force);
            }
        });
        tally
    }
}

/// A listed pair whose surfaces overlap.
struct TouchingPair {
    i: usize,
    j: usize,
    /// Its pair-list entry (and contact history).
    entry: usize,
    /// `x_i - x_j`, the minimum image.
    del: [f64; 3],
    /// `j`'s velocity, or its image's across a Lees-Edwards face.
    partner_velocity: [f64; 3],
    /// The closure's corrections of the two surfaces (0 without it).
    moved: [f64; 2],
}

/// Calls `touch` for every listed pair whose surfaces (moved by the
/// closure's `corrections`) overlap, in list order, with the histories;
/// clears the history of every other pair.
#[inline(always)]
fn touching_pairs(
    sep: &MinimumImage,
    input: &ForceInput<'_>,
    corrections: Option<&[[f64; 2]]>,
    history: &mut [ContactHistory],
    mut touch: impl FnMut(TouchingPair, &mut [ContactHistory]),
) {
    let (x, v, radius, list) = (input.x, input.v, input.radius, input.neighbours);
    for i in 0..x.len() {
        let xi = x[i];
        for k in list.offsets[i]..list.offsets[i + 1] {
            let j = list.neighbours[k] as usize;
            let (del, image) = sep.delta_image(&xi, &x[j]);
            let rsq = del[0] * del[0] + del[1] * del[1] + del[2] * del[2];
            let moved = corrections.map_or([0.0; 2], |c| c[k]);
            let radsum = (radius[i] + moved[0]) + (radius[j] + moved[1]);
            // A surface moved past its centre (radsum <= 0) is caught by
            // the closure's report; it is no contact here.
            if radsum <= 0.0 || rsq >= radsum * radsum {
                history[k] = Default::default();
                continue;
            }
            let mut partner_velocity = v[j];
            // A partner across a Lees-Edwards face is an image moving with
            // the boundary.
            if let (Some(le), true) = (&input.lees_edwards, image != [0.0; 3]) {
                for (v, w) in partner_velocity.iter_mut().zip(le.image_velocity(&image)) {
                    *v += w;
                }
            }
            let pair = TouchingPair {
                i,
                j,
                entry: k,
                del,
                partner_velocity,
                moved,
            };
            touch(pair, history);
        }
    }
}

/// Where a block of contacts goes: the forces, torques and virial of the
/// pass. (Components are added `for d in 0..3` over several arrays.)
struct BlockSink<'a> {
    isa: Isa,
    coeffs: &'a GranularCoeffs,
    dt: f64,
    update: bool,
    f: &'a mut [[f64; 3]],
    torque: Option<&'a mut [[f64; 3]]>,
    tally: Option<&'a mut Tally>,
}

#[allow(clippy::needless_range_loop)]
impl BlockSink<'_> {
    /// Forms `block` and adds the contacts of its first `pairs.len()`
    /// lanes (each `(i, j, list entry)`), in lane order.
    fn flush(
        &mut self,
        block: &mut ContactBlock,
        pairs: &[(usize, usize, usize)],
        history: &mut [ContactHistory],
    ) {
        let out = hertz_mindlin_block(self.isa, self.coeffs, block, self.dt, self.update);
        for (l, &(i, j, k)) in pairs.iter().enumerate() {
            let h = &mut history[k];
            h.tangential = std::array::from_fn(|d| block.tangential[d][l]);
            h.normal_force = out.normal_force[l];
            let force: [f64; 3] = std::array::from_fn(|d| out.force[d][l]);
            for d in 0..3 {
                self.f[i][d] += force[d];
                self.f[j][d] -= force[d];
            }
            if let Some(t) = self.torque.as_deref_mut() {
                for d in 0..3 {
                    t[i][d] += out.torque[0][d][l];
                    t[j][d] += out.torque[1][d][l];
                }
            }
            if let Some(tally) = self.tally.as_deref_mut() {
                let del = std::array::from_fn(|d| block.del[d][l]);
                tally.add_vector(1.0, &del, &force);
            }
        }
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
        let sep = input.simbox.minimum_image();
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
