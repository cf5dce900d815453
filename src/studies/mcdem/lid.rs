//! The lid protocol on any bed (`bpm mc-compress --packing FILE.data`): a
//! bed read from a LAMMPS or LIGGGHTS data file (`atom_style sphere`), in
//! the file's own units, in a box of granular walls (a floor at z = 0 and
//! side walls at x = 0, x = X, y = 0, y = Y) under a flat lid that moves
//! from a start height to an end height and back, `cycles` times, at
//! constant speed; plain Hertz and the standard closure, with gravity.
//!
//! Nothing is converted: lengths, times, moduli and gravity are in the
//! units of the data file (SI for LIGGGHTS's `units si`). The lid's speed
//! is the one LIGGGHTS's decks form, `(end - start) / (steps dt)`, with the
//! steps per pass rounded from the requested speed, so a deck that moves
//! its lid a given number of steps is reproduced exactly.

use super::{reference_material, Variant, WalledBox};
use crate::analysis::plot::{write_svg, Mark, Panel, PlotError, Series};
use crate::engine::MultiContact;
use crate::file_error::FileError;
use crate::kernels::GranularMaterial;
use crate::scene::datafile::{read_data_file, DataFileError};
use crate::scene::{build_system, run_scene, validate, ForceField, RunOptions, Scene, StageSpec};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// The lid protocol's options, in the data file's units.
#[derive(Clone, Debug, PartialEq, Serialize)]
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
}

/// Why the lid protocol could not run.
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
    /// A run stopped.
    #[error("the {variant} run stopped: {message}")]
    Run {
        /// The contact law.
        variant: String,
        /// Why.
        message: String,
    },
    /// Writing the report.
    #[error(transparent)]
    File(#[from] FileError),
    /// Writing the plot.
    #[error(transparent)]
    Plot(#[from] PlotError),
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

    /// The contact laws compared: plain Hertz and the standard closure.
    pub fn variants(&self) -> Vec<Variant> {
        vec![
            Variant {
                name: "Hertz".into(),
                multicontact: None,
            },
            Variant {
                name: format!("standard (gamma {})", self.gamma),
                multicontact: Some(MultiContact::standard(self.gamma)),
            },
        ]
    }
}

/// The bed in its box under the lid, with contacts by `variant`: one stage
/// per pass of the lid (closing, then opening), recording every
/// `record_every` steps.
pub fn lid_scene(opts: &LidOptions, variant: &Variant) -> Result<Scene, LidError> {
    opts.validate()?;
    let sphere_material = GranularMaterial {
        youngs_modulus: opts.youngs_modulus,
        ..reference_material(opts.poisson_ratio, opts.restitution, opts.friction)
    };
    let mut scene = read_data_file(
        &opts.packing,
        [false; 3],
        ForceField::dem(sphere_material),
        1,
    )?;
    scene.force_field.multicontact = variant.multicontact;
    if opts.gravity != [0.0; 3] {
        scene.force_field.gravity = Some(opts.gravity);
    }
    check_bed(&scene, opts)?;
    let radius = scene.particles.radius.clone().unwrap_or_default();
    let mean_diameter = 2.0 * radius.iter().sum::<f64>() / radius.len().max(1) as f64;
    scene.force_field.skin = opts.skin.unwrap_or(0.1 * mean_diameter);
    let walled = WalledBox {
        base: opts.base,
        height: opts.lid_start,
        material: GranularMaterial {
            youngs_modulus: opts.wall_modulus,
            ..sphere_material
        },
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
        variant.name
    );
    validate(&scene).map_err(|e| LidError::Run {
        variant: variant.name.clone(),
        message: e.to_string(),
    })?;
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

/// One contact law's run: the lid's rows over every pass.
#[derive(Clone, Debug, Serialize)]
pub struct LidRun {
    /// The contact law.
    pub variant: String,
    /// Steps since the start of the first pass, per row (LIGGGHTS's
    /// `step` column for a deck that starts at step 0).
    pub step: Vec<u64>,
    /// Time since the start of the first pass, per row.
    pub time: Vec<f64>,
    /// The lid's height, per row.
    pub lid_position: Vec<f64>,
    /// The normal force on the lid (positive when the bed pushes it).
    pub lid_force: Vec<f64>,
    /// Wall-clock seconds of the run.
    pub seconds: f64,
    /// Why the run stopped early, if it did.
    pub stopped: Option<String>,
}

/// What `bpm mc-compress --packing` writes (`lid.json`).
#[derive(Clone, Debug, Serialize)]
pub struct LidReport {
    /// The command line.
    pub command: String,
    /// The options.
    pub options: LidOptions,
    /// Steps per pass of the lid.
    pub steps_per_pass: u64,
    /// The lid's closing speed as run.
    pub lid_velocity: f64,
    /// The neighbour skin used.
    pub skin: f64,
    /// Spheres in the bed.
    pub spheres: usize,
    /// One run per contact law.
    pub runs: Vec<LidRun>,
}

/// Runs the lid protocol with each contact law; `progress` shows progress
/// bars.
pub fn run_lid(
    opts: &LidOptions,
    command: &str,
    threads: usize,
    progress: bool,
) -> Result<(LidReport, Vec<Scene>), LidError> {
    let mut runs = Vec::new();
    let mut scenes = Vec::new();
    for variant in opts.variants() {
        let scene = lid_scene(opts, &variant)?;
        let start = std::time::Instant::now();
        let mut sys = build_system(&scene, threads);
        let run_opts = RunOptions {
            progress,
            ..RunOptions::quiet(threads)
        };
        let (outputs, err) = run_scene(&mut sys, &scene, &run_opts);
        let mut run = LidRun {
            variant: variant.name.clone(),
            step: Vec::new(),
            time: Vec::new(),
            lid_position: Vec::new(),
            lid_force: Vec::new(),
            seconds: 0.0,
            stopped: err.map(|e| e.to_string()),
        };
        for stage in &outputs {
            let column = |name: &str| {
                stage.column(name).ok_or_else(|| LidError::Run {
                    variant: variant.name.clone(),
                    message: format!("stage {} recorded no {name}", stage.name),
                })
            };
            // A pass's first row repeats the previous pass's last state.
            let skip = usize::from(!run.time.is_empty());
            run.step
                .extend(column("step")?.into_iter().skip(skip).map(|s| s as u64));
            run.time.extend(column("time")?.into_iter().skip(skip));
            run.lid_position
                .extend(column("granular_wall1_position")?.into_iter().skip(skip));
            run.lid_force
                .extend(column("granular_wall1_force")?.into_iter().skip(skip));
        }
        run.seconds = start.elapsed().as_secs_f64();
        runs.push(run);
        scenes.push(scene);
    }
    let report = LidReport {
        command: command.into(),
        options: opts.clone(),
        steps_per_pass: opts.steps_per_pass(),
        lid_velocity: opts.lid_velocity(),
        skin: scenes[0].force_field.skin,
        spheres: scenes[0].particles.positions.len(),
        runs,
    };
    Ok((report, scenes))
}

/// Writes `lid.json`, `lid.svg` (lid force against time) and the scene of
/// each contact law into `dir`.
pub fn write_lid_report(report: &LidReport, scenes: &[Scene], dir: &Path) -> Result<(), LidError> {
    std::fs::create_dir_all(dir).map_err(FileError::on("creating", dir))?;
    let json = dir.join("lid.json");
    let text = serde_json::to_string_pretty(report).expect("report serialises");
    std::fs::write(&json, text).map_err(FileError::on("writing", &json))?;
    for (k, scene) in scenes.iter().enumerate() {
        let path = dir.join(format!("scene-{k}.json"));
        let text = serde_json::to_string(scene).expect("a scene serialises");
        std::fs::write(&path, text).map_err(FileError::on("writing", &path))?;
    }
    let panel = Panel {
        title: format!(
            "lid on {} spheres, {} steps per pass",
            report.spheres, report.steps_per_pass
        ),
        x_label: "time".into(),
        y_label: "force on the lid".into(),
        series: report
            .runs
            .iter()
            .map(|r| {
                let points = r.time.iter().copied().zip(r.lid_force.iter().copied());
                Series::new(r.variant.clone(), points.collect(), Mark::Line)
            })
            .collect(),
        ..Panel::default()
    };
    write_svg(&dir.join("lid.svg"), &[panel])?;
    Ok(())
}

/// A table: per contact law, the peak lid force, the rows, the run time.
pub fn lid_table(report: &LidReport) -> String {
    let mut out = format!(
        "{:<28} {:>14} {:>8} {:>10}\n",
        "contact law", "peak lid force", "rows", "seconds"
    );
    for r in &report.runs {
        let peak = r.lid_force.iter().copied().fold(0.0, f64::max);
        out.push_str(&format!(
            "{:<28} {:>14.6e} {:>8} {:>10.1}{}\n",
            r.variant,
            peak,
            r.time.len(),
            r.seconds,
            r.stopped
                .as_ref()
                .map_or(String::new(), |s| format!("  stopped: {s}"))
        ));
    }
    out
}
