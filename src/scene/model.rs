//! The scene document: one JSON file fully describes a run.
//!
//! It names no engine: the native engine runs it directly and the LAMMPS
//! harness turns it into a data file and an input script.

use crate::engine::{
    Barostat, Deformation, FlatWall, GranularWall, MultiContact, SphereWall, Tether,
};
use crate::kernels::{BondCoeffs, BondFailure, GranularMaterial, PairCoeffs};
use serde::{Deserialize, Serialize};

/// The scene format this build writes. Version 1 (files without a
/// `version` field) is version 2 without `model` and the per-particle
/// `radius`, `type` and mass arrays, so it loads unchanged.
pub const SCENE_VERSION: u32 = 2;

fn version_one() -> u32 {
    1
}

/// The particle model a scene is written for.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ModelKind {
    /// Bonded particle model with the multibody volume term.
    #[default]
    Bpm,
    /// DEM spheres: one rigid sphere per grain, Hertz-Mindlin contacts
    /// with friction (`force_field.granular`), integrated with rotation.
    Dem,
}

/// A complete run: particles, bonds, box, force field, protocol, seed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Scene format version ([`SCENE_VERSION`]); absent means 1.
    #[serde(default = "version_one")]
    pub version: u32,
    /// The particle model; default `bpm`.
    #[serde(default)]
    pub model: ModelKind,
    /// Free text.
    #[serde(default)]
    pub description: String,
    /// Seed of every random draw in the run (velocity initialisation).
    pub seed: u64,
    /// The simulation box.
    #[serde(rename = "box")]
    pub simbox: BoxSpec,
    /// The particles.
    pub particles: Particles,
    /// The bonds.
    #[serde(default)]
    pub bonds: Bonds,
    /// Bond and pair parameters.
    pub force_field: ForceField,
    /// The protocol, run in order.
    pub stages: Vec<StageSpec>,
    /// How the scene was made (builder, its parameters and seed).
    #[serde(default, skip_serializing_if = "serde_json::Value::is_null")]
    pub provenance: serde_json::Value,
}

/// Box geometry (LAMMPS restricted triclinic).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoxSpec {
    /// Lower corner (d units).
    pub lo: [f64; 3],
    /// Edge lengths (d units), > 0.
    pub lengths: [f64; 3],
    /// Tilt factors `xy, xz, yz` (d units); default 0.
    #[serde(default)]
    pub tilt: [f64; 3],
    /// Periodicity per dimension.
    pub periodic: [bool; 3],
}

/// Particle arrays (structure of arrays).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Particles {
    /// Positions (d units).
    pub positions: Vec<[f64; 3]>,
    /// Velocities (d / tau); default all zero.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub velocities: Option<Vec<[f64; 3]>>,
    /// Angular velocities (1 / tau) of DEM spheres; default all zero.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub angular_velocities: Option<Vec<[f64; 3]>>,
    /// Grain id per particle; default all 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub grain: Option<Vec<u32>>,
    /// Mass (m units): one number for every particle, or one per particle;
    /// default 1.
    #[serde(default)]
    pub mass: Mass,
    /// Radius per particle (d units); default 1/2. Bonded particles touch
    /// at the pair coefficient `d`, so the BPM ignores this; DEM spheres
    /// use it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius: Option<Vec<f64>>,
    /// Type per particle, from 1 (LAMMPS atom types); default all 1.
    #[serde(default, rename = "type", skip_serializing_if = "Option::is_none")]
    pub kind: Option<Vec<u32>>,
    /// Atom id per particle (LAMMPS atom ids, as the imported data file
    /// numbered them): positive and strictly increasing, since particles
    /// are kept in id order. Default `1..=N` (particle `i` is atom
    /// `i + 1`), and then not written, so scenes without ids of their own
    /// read and write as before. Data files and dumps written from the
    /// scene carry these ids.
    #[serde(default, skip_serializing_if = "ids_are_default")]
    pub ids: Option<Vec<u64>>,
}

/// Whether `ids` are the default numbering `1..=N` (absent, or `k + 1`
/// at index `k`): then the scene does not write them.
fn ids_are_default(ids: &Option<Vec<u64>>) -> bool {
    ids.as_deref().is_none_or(is_default_numbering)
}

/// Whether `ids` are `1..=N` (`k + 1` at index `k`).
pub(crate) fn is_default_numbering(ids: &[u64]) -> bool {
    ids.iter().enumerate().all(|(k, &id)| id == k as u64 + 1)
}

impl Particles {
    /// The atom id of particle `i`: `ids[i]`, or `i + 1` by default.
    pub fn id(&self, i: usize) -> u64 {
        self.ids.as_ref().map_or(i as u64 + 1, |ids| ids[i])
    }

    /// The spheres' mean diameter; `None` without radii (bonded particles)
    /// or without particles.
    pub fn mean_diameter(&self) -> Option<f64> {
        let r = self.radius.as_deref().filter(|r| !r.is_empty())?;
        Some(2.0 * r.iter().sum::<f64>() / r.len() as f64)
    }
}

/// Particle masses: one value for all, or one per particle.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Mass {
    /// Every particle has this mass.
    Uniform(f64),
    /// One mass per particle, in particle order.
    PerParticle(Vec<f64>),
}

impl Default for Mass {
    fn default() -> Self {
        Mass::Uniform(1.0)
    }
}

impl Mass {
    /// The mean mass: the uniform one, or the mean of those listed.
    pub fn mean(&self) -> f64 {
        match self {
            Mass::Uniform(m) => *m,
            Mass::PerParticle(m) => m.iter().sum::<f64>() / m.len().max(1) as f64,
        }
    }

    /// The masses of `n` particles.
    pub fn values(&self, n: usize) -> Vec<f64> {
        match self {
            Mass::Uniform(m) => vec![*m; n],
            Mass::PerParticle(m) => m.clone(),
        }
    }
}

/// Bonds as index pairs with optional reference lengths.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Bonds {
    /// Pairs of particle indices (0-based).
    pub pairs: Vec<[usize; 2]>,
    /// Reference length per bond; default the distance at load.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub r0: Option<Vec<f64>>,
    /// Plastic strain per bond (bonds that yield: the rest length is
    /// `(1 + e_p) r0`); default 0. A final scene of a run whose bonds
    /// yielded carries it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub plastic_strain: Option<Vec<f64>>,
}

/// Interaction parameters: bonds and contacts of the bonded particle
/// model, or the sphere material of DEM.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ForceField {
    /// Bond coefficients `k`, `a` (a_B), `gamma`; default all zero (no
    /// bond forces), as a DEM scene leaves them.
    #[serde(default, skip_serializing_if = "BondCoeffs::is_zero")]
    pub bond: BondCoeffs,
    /// How bonds break and yield (critical strain, smoothing, plastic
    /// strain); absent, they stay elastic and never break.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bond_failure: Option<BondFailure>,
    /// Pair coefficients `k`, `d`, `a` (a_P), `gamma`; absent for no contacts.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pair: Option<PairCoeffs>,
    /// Bonded particles also touch through the contact law (upstream
    /// LAMMPS's `overlay/pair yes`): a bond squeezed below the contact
    /// distance `d` is resisted by the contact's repulsion too. Default
    /// off: bonded particles have no contact force, and a broken bond's
    /// particles touch from the step after it breaks. Needs `pair`.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub overlay_pair: bool,
    /// Neighbour-list skin (d units); default 0.3.
    #[serde(default = "default_skin")]
    pub skin: f64,
    /// The zero-net-multibody variant of the bond force: each particle's
    /// multibody forces on its neighbours are shifted to sum to zero
    /// (docs/model.md). Default off, the paper's model.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub zero_net_multibody: bool,
    /// The sphere material and friction of model `dem`; absent for `bpm`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub granular: Option<GranularMaterial>,
    /// The multi-contact closure of model `dem` (each contact's overlap
    /// corrected by the sphere's other contact forces); absent for plain
    /// Hertz.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub multicontact: Option<MultiContact>,
    /// A uniform acceleration on every particle (gravity), in the scene's
    /// units of length over time squared (d / tau^2 in reduced units), e.g.
    /// `[0, 0, -9.81]` for an SI scene; absent for none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gravity: Option<[f64; 3]>,
}

fn default_skin() -> f64 {
    0.3
}

impl ForceField {
    /// The bonded model's part of the field.
    pub fn bpm(&self) -> crate::engine::BpmForceField {
        crate::engine::BpmForceField {
            bond: self.bond,
            failure: self.bond_failure,
            pair: self.pair,
            overlay_pair: self.overlay_pair,
            zero_net: self.zero_net_multibody,
        }
    }

    /// The paper's parameters: `k = 1`, `Gamma = 1`, `a_P = 50`, `d = 1`.
    pub fn paper(a_b: f64) -> Self {
        Self {
            bond: BondCoeffs {
                k: 1.0,
                a: a_b,
                gamma: 1.0,
            },
            pair: Some(PairCoeffs {
                k: 1.0,
                d: 1.0,
                a: 50.0,
                gamma: 1.0,
            }),
            overlay_pair: false,
            bond_failure: None,
            skin: default_skin(),
            zero_net_multibody: false,
            granular: None,
            multicontact: None,
            gravity: None,
        }
    }

    /// DEM spheres of `material`, no bonds, the default skin.
    pub fn dem(material: GranularMaterial) -> Self {
        Self {
            bond: BondCoeffs::default(),
            bond_failure: None,
            pair: None,
            overlay_pair: false,
            skin: default_skin(),
            zero_net_multibody: false,
            granular: Some(material),
            multicontact: None,
            gravity: None,
        }
    }
}

/// One stage of a protocol.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StageSpec {
    /// Name, for reports.
    pub name: String,
    /// Number of steps.
    pub steps: u64,
    /// Time step (tau); default 0.1.
    #[serde(default = "default_dt")]
    pub dt: f64,
    /// Replaces the force field from this stage on.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub force_field: Option<ForceField>,
    /// Sets random velocities at the stage start.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub set_velocities: Option<VelocityInit>,
    /// Zeroes velocities (and the angular velocities of spheres) at the
    /// stage start.
    #[serde(default)]
    pub zero_velocities: bool,
    /// Makes the current bond lengths the reference lengths at the stage start.
    #[serde(default)]
    pub reset_reference: bool,
    /// Viscous damping `-gamma v` (m / tau); default 0.
    #[serde(default)]
    pub viscous: f64,
    /// Flat harmonic walls.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub walls: Vec<FlatWall>,
    /// A spherical harmonic wall.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sphere_wall: Option<SphereWall>,
    /// Flat granular walls (model dem): frictional Hertz-Mindlin contacts.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub granular_walls: Vec<GranularWall>,
    /// A centre-of-mass tether.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tether: Option<Tether>,
    /// Box deformation with affine remap.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub deformation: Option<Deformation>,
    /// Berendsen barostat.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub barostat: Option<Barostat>,
    /// What to record.
    #[serde(default)]
    pub record: Record,
}

fn default_dt() -> f64 {
    0.1
}

/// Seeded random velocities: uniform components, zero net momentum,
/// rescaled to the given root-mean-square speed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VelocityInit {
    /// Root-mean-square speed (d / tau).
    pub rms_speed: f64,
}

/// Recording intervals (0 = never).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Record {
    /// Steps between thermo rows (stress, energies, walls); also records step 0.
    #[serde(default)]
    pub every: u64,
    /// Steps between position checkpoints.
    #[serde(default)]
    pub positions_every: u64,
}

impl StageSpec {
    /// A stage that only integrates.
    pub fn hold(name: &str, steps: u64, dt: f64) -> Self {
        Self {
            name: name.to_string(),
            steps,
            dt,
            force_field: None,
            set_velocities: None,
            zero_velocities: false,
            reset_reference: false,
            viscous: 0.0,
            walls: Vec::new(),
            sphere_wall: None,
            granular_walls: Vec::new(),
            tether: None,
            deformation: None,
            barostat: None,
            record: Record::default(),
        }
    }
}
