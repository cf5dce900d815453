//! Runs a scene's stages on the native engine and records observables.

use super::load::model_of;
use super::model::{Scene, StageSpec, VelocityInit};
use crate::engine::{ActiveTether, EngineError, Stage, StageDrivers, System};
use indicatif::{ProgressBar, ProgressStyle};
use rand::{Rng, SeedableRng};
use serde::{Deserialize, Serialize};

/// Observables of one stage.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct StageOutput {
    /// Stage name.
    pub name: String,
    /// Steps run.
    pub steps: u64,
    /// Column names of `rows`.
    pub columns: Vec<String>,
    /// One row per recorded step.
    pub rows: Vec<Vec<f64>>,
    /// Position checkpoints.
    pub checkpoints: Vec<Checkpoint>,
    /// Wall-clock time of the stage (s).
    pub wall_seconds: f64,
    /// Wall-clock seconds per part of the step.
    pub timers: std::collections::BTreeMap<String, f64>,
    /// How many times the pair list was built.
    pub neighbour_builds: u64,
}

impl StageOutput {
    /// The recorded series of column `name`.
    pub fn column(&self, name: &str) -> Option<Vec<f64>> {
        let k = self.columns.iter().position(|c| c == name)?;
        Some(self.rows.iter().map(|r| r[k]).collect())
    }
}

/// Positions at one step.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Checkpoint {
    /// Global step.
    pub step: u64,
    /// Box lower corner, edge lengths and tilts at that step (d).
    pub simbox: [[f64; 3]; 3],
    /// Positions; wrapped into the box at the last neighbour-list build, so
    /// compare them through the minimum image.
    pub positions: Vec<[f64; 3]>,
}

/// Options of a run that are not part of the physics.
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// Threads for the force passes.
    pub threads: usize,
    /// Show progress bars (on a terminal).
    pub progress: bool,
}

/// Box columns of a thermo row: edge lengths and tilts.
pub const BOX_COLUMNS: [&str; 6] = ["lx", "ly", "lz", "xy", "xz", "yz"];
/// Pressure-tensor columns of a thermo row (then their mean, "pressure").
pub const STRESS_COLUMNS: [&str; 6] = ["pxx", "pyy", "pzz", "pxy", "pxz", "pyz"];
/// Energy columns of a thermo row.
pub const ENERGY_COLUMNS: [&str; 4] = ["e_bond", "e_pair", "e_kinetic", "e_external"];

/// The thermo columns recorded for a stage: step, time, box, stress,
/// pressure, energies, then each wall's force and position and the sphere
/// wall's force.
pub fn thermo_columns(stage: &StageSpec) -> Vec<String> {
    let mut c: Vec<String> = ["step", "time"]
        .iter()
        .chain(&BOX_COLUMNS)
        .chain(&STRESS_COLUMNS)
        .chain(&["pressure"])
        .chain(&ENERGY_COLUMNS)
        .map(|s| s.to_string())
        .collect();
    for w in 0..stage.walls.len() {
        c.push(format!("wall{w}_force"));
        c.push(format!("wall{w}_position"));
    }
    if stage.sphere_wall.is_some() {
        c.push("sphere_wall_force".into());
    }
    c
}

/// One row of the columns of [`columns`] for `stage`.
fn thermo_row(sys: &System, stage: &StageSpec) -> Vec<f64> {
    let b = &sys.simbox;
    let p = sys.pressure_tensor();
    let it = &sys.report.interactions;
    let mut row = vec![
        sys.step as f64,
        sys.time,
        b.lengths[0],
        b.lengths[1],
        b.lengths[2],
        b.tilt[0],
        b.tilt[1],
        b.tilt[2],
    ];
    row.extend_from_slice(&p);
    row.push((p[0] + p[1] + p[2]) / 3.0);
    row.extend_from_slice(&[
        it.bonds.energy,
        it.pairs.energy,
        sys.kinetic_energy(),
        sys.report.external_energy,
    ]);
    for (f, x) in sys
        .report
        .wall_forces
        .iter()
        .zip(&sys.report.wall_positions)
    {
        row.push(*f);
        row.push(*x);
    }
    if stage.sphere_wall.is_some() {
        row.push(sys.report.sphere_wall_force);
    }
    row
}

/// Seeded uniform velocity components for `n` particles, zero net
/// momentum, exact rms speed. The LAMMPS harness passes these same numbers
/// to LAMMPS, so both engines start a stage from identical velocities.
pub fn random_velocities(n: usize, init: &VelocityInit, seed: u64) -> Vec<[f64; 3]> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut v: Vec<[f64; 3]> = (0..n)
        .map(|_| {
            [
                rng.gen_range(-1.0..1.0),
                rng.gen_range(-1.0..1.0),
                rng.gen_range(-1.0..1.0),
            ]
        })
        .collect();
    let count = n as f64;
    let mut mean = [0.0; 3];
    for vi in &v {
        for d in 0..3 {
            mean[d] += vi[d] / count;
        }
    }
    let mut sq = 0.0;
    for vi in &mut v {
        for d in 0..3 {
            vi[d] -= mean[d];
            sq += vi[d] * vi[d];
        }
    }
    let scale = if sq > 0.0 {
        init.rms_speed / (sq / count).sqrt()
    } else {
        0.0
    };
    for vi in &mut v {
        for c in vi.iter_mut() {
            *c *= scale;
        }
    }
    v
}

/// Seed of the random draws of stage `index`: distinct per stage, fixed by
/// the scene seed.
pub fn stage_seed(seed: u64, index: usize) -> u64 {
    seed ^ (0x9E37_79B9_7F4A_7C15u64.wrapping_mul(index as u64 + 1))
}

/// Runs one stage on `sys`.
pub fn run_stage(
    sys: &mut System,
    spec: &StageSpec,
    index: usize,
    seed: u64,
    opts: &RunOptions,
) -> Result<StageOutput, EngineError> {
    let start = std::time::Instant::now();
    let timers_before = sys.timers.clone();
    let builds_before = sys.neighbours.builds;
    if let Some(ff) = &spec.force_field {
        sys.model = model_of(ff, sys.len(), &sys.bonds);
        sys.skin = ff.skin;
    }
    if spec.reset_reference {
        sys.reset_bond_reference();
    }
    if spec.zero_velocities {
        sys.v.iter_mut().for_each(|v| *v = [0.0; 3]);
    }
    if let Some(init) = &spec.set_velocities {
        sys.v = random_velocities(sys.len(), init, stage_seed(seed, index));
    }
    let tether = spec
        .tether
        .as_ref()
        .map(|t| ActiveTether::new(t, &sys.grain, &sys.simbox, &sys.x, &sys.image));
    let drivers = StageDrivers {
        dt: spec.dt,
        walls: spec.walls.clone(),
        sphere_wall: spec.sphere_wall.clone(),
        tether,
        viscous: spec.viscous,
        deformation: spec.deformation.clone(),
        barostat: spec.barostat.clone(),
        tally_every: spec.record.every,
    };
    let stage_box = sys.simbox.clone();
    sys.setup(&drivers);
    let mut out = StageOutput {
        name: spec.name.clone(),
        steps: spec.steps,
        columns: thermo_columns(spec),
        rows: Vec::new(),
        checkpoints: Vec::new(),
        wall_seconds: 0.0,
        timers: Default::default(),
        neighbour_builds: 0,
    };
    let record = |sys: &System, out: &mut StageOutput, k: u64| {
        if spec.record.every > 0 && k % spec.record.every == 0 {
            out.rows.push(thermo_row(sys, spec));
        }
        if spec.record.positions_every > 0 && k % spec.record.positions_every == 0 {
            let b = &sys.simbox;
            out.checkpoints.push(Checkpoint {
                step: sys.step,
                simbox: [b.lo, b.lengths, b.tilt],
                positions: sys.x.clone(),
            });
        }
    };
    record(sys, &mut out, 0);
    let bar = if opts.progress && spec.steps >= 1000 {
        let bar = ProgressBar::new(spec.steps);
        bar.set_style(
            ProgressStyle::with_template(
                "{prefix:>12} [{bar:40}] {pos}/{len} steps {per_sec} eta {eta}",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
        );
        bar.set_prefix(spec.name.clone());
        bar
    } else {
        ProgressBar::hidden()
    };
    for k in 1..=spec.steps {
        sys.step(&drivers, k, &stage_box)?;
        record(sys, &mut out, k);
        if k % 256 == 0 {
            sys.check_finite()?;
            bar.set_position(k);
        }
    }
    sys.check_finite()?;
    bar.finish_and_clear();
    out.wall_seconds = start.elapsed().as_secs_f64();
    for s in Stage::ALL {
        let secs = (sys.timers.total(s) - timers_before.total(s)).as_secs_f64();
        out.timers.insert(s.name().to_string(), secs);
    }
    out.neighbour_builds = sys.neighbours.builds - builds_before;
    Ok(out)
}

/// Runs every stage of `scene` on `sys` in order. Stages that finished are
/// returned even when a later one fails, so nothing recorded is lost.
pub fn run_scene(
    sys: &mut System,
    scene: &Scene,
    opts: &RunOptions,
) -> (Vec<StageOutput>, Option<EngineError>) {
    let mut done = Vec::with_capacity(scene.stages.len());
    for (i, stage) in scene.stages.iter().enumerate() {
        match run_stage(sys, stage, i, scene.seed, opts) {
            Ok(out) => done.push(out),
            Err(e) => return (done, Some(e)),
        }
    }
    (done, None)
}
