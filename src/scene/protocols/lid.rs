//! The lid protocol on a bed of spheres: a box of granular walls (a floor
//! at z = 0 and side walls at x = 0, x = X, y = 0, y = Y) under a flat lid
//! that moves from a start height to an end height and back, `cycles`
//! times, at constant speed. The bed comes from a LAMMPS or LIGGGHTS data
//! file (`atom_style sphere`), in the file's own units.
//!
//! Nothing is converted: lengths, times, moduli and gravity are in the
//! units of the data file (SI for LIGGGHTS's `units si`). The lid's speed
//! is the one LIGGGHTS's decks form, `(end - start) / (steps dt)`, with the
//! steps per pass rounded from the requested speed, so a deck that moves
//! its lid a given number of steps is reproduced exactly.

use crate::engine::{GranularWall, MultiContact, WallSide};
use crate::kernels::{GranularMaterial, NormalDamping};
use crate::scene::datafile::{read_data_file, DataFileError};
use crate::scene::{validate, ForceField, Scene, StageOutput, StageSpec};
use serde::Serialize;
use std::path::PathBuf;

/// A closed box of granular walls: a floor at 0, four side walls around
/// the base `[0, lx] x [0, ly]`, and a lid; all of one material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WalledBox {
    /// Base edges `[lx, ly]`.
    pub base: [f64; 2],
    /// The lid's highest position: the simulation box reaches above it.
    pub height: f64,
    /// The walls' material.
    pub material: GranularMaterial,
    /// Whether the walls keep their contacts' friction springs from one
    /// pass of the lid to the next ([`GranularWall::keep_history`]).
    pub keep_history: bool,
}

impl WalledBox {
    /// The walls with the lid at `lid` moving at `velocity`: floor 0, lid
    /// 1, side walls 2 to 5 (x lo, x hi, y lo, y hi).
    pub fn walls(&self, lid: f64, velocity: f64) -> Vec<GranularWall> {
        let wall = |axis, side, position, velocity| GranularWall {
            axis,
            side,
            position,
            velocity,
            material: self.material,
            keep_history: self.keep_history,
        };
        let mut walls = vec![
            wall(2, WallSide::Lo, 0.0, 0.0),
            wall(2, WallSide::Hi, lid, velocity),
        ];
        for axis in 0..2 {
            walls.push(wall(axis, WallSide::Lo, 0.0, 0.0));
            walls.push(wall(axis, WallSide::Hi, self.base[axis], 0.0));
        }
        walls
    }
}

/// Spheres of Young's modulus 1 with LIGGGHTS's Hertz contact law: the
/// restitution form of the damping, tangential damping `sqrt(2 (1 - nu) /
/// (2 - nu))` times the normal one (its tangential dashpot in this contact
/// law), sliding friction only.
pub fn liggghts_hertz_material(
    poisson_ratio: f64,
    restitution: f64,
    friction: f64,
) -> GranularMaterial {
    let nu = poisson_ratio;
    GranularMaterial {
        youngs_modulus: 1.0,
        poisson_ratio: nu,
        restitution,
        damping: NormalDamping::CoeffRestitution,
        tangential_damping: (2.0 * (1.0 - nu) / (2.0 - nu)).sqrt(),
        sliding_friction: friction,
        rolling: None,
        twisting: Default::default(),
    }
}

/// The lid protocol's options, in the data file's units.
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct LidOptions {
    /// The bed: a data file of spheres (`id type diameter density x y z`).
    pub packing: PathBuf,
    /// The side walls: x = 0 and `base[0]`, y = 0 and `base[1]`; the
    /// floor is z = 0.
    pub base: [f64; 2],
    /// The lid's height at the start of each compression.
    pub lid_start: f64,
    /// The lid's height where it turns back.
    pub lid_end: f64,
    /// The requested lid speed (> 0); the steps per pass are rounded from
    /// it.
    pub lid_speed: f64,
    /// Compression and decompression cycles.
    pub cycles: usize,
    /// Time step.
    pub dt: f64,
    /// The spheres' Young's modulus.
    pub youngs_modulus: f64,
    /// The walls' Young's modulus.
    pub wall_modulus: f64,
    /// Poisson's ratio (spheres and walls).
    pub poisson_ratio: f64,
    /// Normal restitution coefficient (every contact).
    pub restitution: f64,
    /// Sliding friction coefficient (every contact).
    pub friction: f64,
    /// The standard closure's prefactor.
    pub gamma: f64,
    /// Gravity (an acceleration).
    pub gravity: [f64; 3],
    /// Steps between recorded rows.
    pub record_every: u64,
    /// Neighbour skin; `None`: a tenth of the mean diameter.
    pub skin: Option<f64>,
    /// Whether the walls keep their contacts' friction springs from one
    /// pass to the next, as LIGGGHTS's wall fixes do across `run`
    /// commands (otherwise they restart with each pass).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub keep_wall_histories: bool,
}

/// Why the lid protocol's scene could not be built.
#[derive(Debug, thiserror::Error)]
pub enum LidError {
    /// An option is out of range.
    #[error("{option}: {reason}")]
    Option {
        /// The option.
        option: &'static str,
        /// What is wrong.
        reason: String,
    },
    /// The data file could not be read.
    #[error(transparent)]
    Data(#[from] DataFileError),
    /// The bed does not fit the box.
    #[error("{0}")]
    Bed(String),
    /// The scene is not valid (a bed and options no check above caught).
    #[error("the lid scene is not valid: {0}")]
    Scene(String),
}

impl LidOptions {
    /// Checks every option; the error names the option.
    pub fn validate(&self) -> Result<(), LidError> {
        let bad = |option, reason: &str| {
            Err(LidError::Option {
                option,
                reason: reason.into(),
            })
        };
        let positive = [
            ("--base", self.base[0]),
            ("--base", self.base[1]),
            ("--lid-speed", self.lid_speed),
            ("--dt", self.dt),
            ("--youngs-modulus", self.youngs_modulus),
            ("--wall-modulus", self.wall_modulus),
            ("--restitution", self.restitution),
        ];
        for (option, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return bad(option, &format!("must be a positive number, got {v}"));
            }
        }
        for (option, v) in [
            ("--lid-start", self.lid_start),
            ("--lid-end", self.lid_end),
            ("--friction", self.friction),
            ("--gamma", self.gamma),
        ] {
            if !v.is_finite() {
                return bad(option, &format!("must be finite, got {v}"));
            }
        }
        if !(self.lid_end > 0.0 && self.lid_end < self.lid_start) {
            return bad(
                "--lid-end",
                &format!(
                    "the lid closes from --lid-start {} down to --lid-end {}: the end must lie between the floor (0) and the start",
                    self.lid_start, self.lid_end
                ),
            );
        }
        if !(0.0..=0.5).contains(&self.poisson_ratio) {
            return bad(
                "--poisson-ratio",
                &format!("must lie in [0, 0.5], got {}", self.poisson_ratio),
            );
        }
        if self.restitution > 1.0 {
            return bad("--restitution", "must not exceed 1");
        }
        if self.gravity.iter().any(|g| !g.is_finite()) {
            return bad("--gravity", "every component must be finite");
        }
        if self.cycles == 0 {
            return bad("--cycles", "must be at least 1");
        }
        if self.record_every == 0 {
            return bad("--record-every", "must be at least 1");
        }
        if let Some(skin) = self.skin {
            if !(skin.is_finite() && skin > 0.0) {
                return bad("--skin", &format!("must be a positive length, got {skin}"));
            }
        }
        if self.steps_per_pass() == 0 {
            return bad(
                "--lid-speed",
                "is so fast that a pass takes less than one step",
            );
        }
        Ok(())
    }

    /// Steps per pass of the lid, rounded from the requested speed.
    pub fn steps_per_pass(&self) -> u64 {
        ((self.lid_start - self.lid_end) / (self.lid_speed * self.dt)).round() as u64
    }

    /// The lid's closing velocity (negative), formed as a LIGGGHTS deck
    /// forms it: `(end - start) / (steps dt)`.
    pub fn lid_velocity(&self) -> f64 {
        (self.lid_end - self.lid_start) / (self.steps_per_pass() as f64 * self.dt)
    }
}

/// The bed in its box under the lid, with plain Hertz contacts or the
/// closure `multicontact` (`name` names the contact law in the scene's
/// description): one stage per pass of the lid (closing, then opening),
/// recording every `record_every` steps.
pub fn lid_scene(
    opts: &LidOptions,
    multicontact: Option<MultiContact>,
    name: &str,
) -> Result<Scene, LidError> {
    opts.validate()?;
    let sphere_material = GranularMaterial {
        youngs_modulus: opts.youngs_modulus,
        ..liggghts_hertz_material(opts.poisson_ratio, opts.restitution, opts.friction)
    };
    let mut force_field = ForceField::dem(sphere_material);
    force_field.multicontact = multicontact;
    force_field.gravity = (opts.gravity != [0.0; 3]).then_some(opts.gravity);
    let mut scene = read_data_file(&opts.packing, [false; 3], force_field, 1)?;
    check_bed(&scene, opts)?;
    // Radii are always there: `read_data_file` refuses a bonded-particle
    // file given a sphere material.
    let mean_diameter = scene.particles.mean_diameter().unwrap_or(0.0);
    scene.force_field.skin = opts.skin.unwrap_or(0.1 * mean_diameter);
    let walled = WalledBox {
        base: opts.base,
        height: opts.lid_start,
        material: GranularMaterial {
            youngs_modulus: opts.wall_modulus,
            ..sphere_material
        },
        keep_history: opts.keep_wall_histories,
    };
    let steps = opts.steps_per_pass();
    let velocity = opts.lid_velocity();
    let mut stages = Vec::new();
    for cycle in 1..=opts.cycles {
        for (name, from, v) in [
            ("compress", opts.lid_start, velocity),
            ("release", opts.lid_end, -velocity),
        ] {
            let mut stage = StageSpec::hold(&format!("{name}-{cycle}"), steps, opts.dt);
            stage.granular_walls = walled.walls(from, v);
            stage.record.every = opts.record_every;
            stages.push(stage);
        }
    }
    scene.stages = stages;
    scene.description = format!(
        "{} under a lid from {} to {} and back {} times, {}",
        opts.packing.display(),
        opts.lid_start,
        opts.lid_end,
        opts.cycles,
        name
    );
    validate(&scene).map_err(|e| LidError::Scene(e.to_string()))?;
    Ok(scene)
}

/// Every sphere's centre inside the walled box and below the lid's start.
/// A sphere may overlap a wall (a bed poured against its walls does, and
/// LIGGGHTS's example starts with its lid 0.12 mm into its highest bead):
/// that is a contact. A centre on a wall's far side is not.
fn check_bed(scene: &Scene, opts: &LidOptions) -> Result<(), LidError> {
    for (i, x) in scene.particles.positions.iter().enumerate() {
        if x[2] >= opts.lid_start {
            return Err(LidError::Bed(format!(
                "--lid-start {} is inside the bed: the centre of sphere {i} ({}) is at z = {}; start the lid above the spheres' centres (an overlap smaller than a radius is a contact)",
                opts.lid_start,
                opts.packing.display(),
                x[2]
            )));
        }
        let outside = x[2] <= 0.0
            || !(x[0] > 0.0 && x[0] < opts.base[0])
            || !(x[1] > 0.0 && x[1] < opts.base[1]);
        if outside {
            return Err(LidError::Bed(format!(
                "the centre of sphere {i} ({}) at {x:?} is outside the walled box 0 < x < {}, 0 < y < {} above the floor z = 0 (--base)",
                opts.packing.display(),
                opts.base[0],
                opts.base[1]
            )));
        }
    }
    Ok(())
}

/// The lid's history over every pass of a lid scene's run.
#[derive(Clone, Debug, Default, PartialEq, Serialize, serde::Deserialize)]
pub struct LidRows {
    /// Steps since the start of the first pass, per row (LIGGGHTS's
    /// `step` column for a deck that starts at step 0).
    pub step: Vec<u64>,
    /// Time since the start of the first pass, per row.
    #[serde(deserialize_with = "crate::json_nan::nan_if_null_each")]
    pub time: Vec<f64>,
    /// The lid's height, per row.
    #[serde(deserialize_with = "crate::json_nan::nan_if_null_each")]
    pub lid_position: Vec<f64>,
    /// The normal force on the lid (positive when the bed pushes it).
    #[serde(deserialize_with = "crate::json_nan::nan_if_null_each")]
    pub lid_force: Vec<f64>,
}

impl LidRows {
    /// The rows of every stage of a lid scene's run, in order; the error
    /// names a column a stage did not record.
    pub fn read(stages: &[StageOutput]) -> Result<Self, String> {
        let mut rows = Self::default();
        for stage in stages {
            let column = |name: &str| {
                stage
                    .column(name)
                    .ok_or_else(|| format!("stage {} recorded no {name}", stage.name))
            };
            // A pass's first row repeats the previous pass's last state.
            let skip = usize::from(!rows.time.is_empty());
            rows.step
                .extend(column("step")?.into_iter().skip(skip).map(|s| s as u64));
            rows.time.extend(column("time")?.into_iter().skip(skip));
            rows.lid_position
                .extend(column("granular_wall1_position")?.into_iter().skip(skip));
            rows.lid_force
                .extend(column("granular_wall1_force")?.into_iter().skip(skip));
        }
        Ok(rows)
    }
}
