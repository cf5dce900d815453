//! Runs a scene's stages on the native engine and records observables.

use super::model::{Scene, StageSpec, VelocityInit};
use super::observables::{closure_columns, column_names, native_row, stage_columns, Column};
use super::trajectory::{DumpWriter, Frame, ThermoWriter, TrajectoryError};
use crate::engine::{
    ActiveTether, BpmModel, DemModel, EngineError, ExternalTerms, Gravity, Stage, StageDrivers,
    System,
};
use indicatif::{ProgressBar, ProgressStyle};
use rand::{Rng, SeedableRng};
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// Observables of one stage.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct StageOutput {
    /// Stage name.
    pub name: String,
    /// Steps run.
    pub steps: u64,
    /// The recorded columns (names, what they measure, how LAMMPS records
    /// them).
    pub columns: Vec<Column>,
    /// One row per recorded step; empty when rows were streamed to
    /// `rows_file`.
    pub rows: Vec<Vec<f64>>,
    /// The thermo file the rows were streamed to, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rows_file: Option<PathBuf>,
    /// Position checkpoints.
    pub checkpoints: Vec<Checkpoint>,
    /// Wall-clock time of the stage (s).
    pub wall_seconds: f64,
    /// Wall-clock seconds per part of the step.
    pub timers: std::collections::BTreeMap<String, f64>,
    /// How many times the pair list was built.
    pub neighbour_builds: u64,
    /// The step within the stage at which it failed, if it did; the rows
    /// and checkpoints run up to it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stopped_at: Option<u64>,
}

impl StageOutput {
    /// The recorded series of column `name`.
    pub fn column(&self, name: &str) -> Option<Vec<f64>> {
        let k = self.columns.iter().position(|c| c.name == name)?;
        Some(self.rows.iter().map(|r| r[k]).collect())
    }
}

impl crate::analysis::Recorded for StageOutput {
    fn name(&self) -> &str {
        &self.name
    }

    fn column(&self, name: &str) -> Option<Vec<f64>> {
        StageOutput::column(self, name)
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
    /// Periodic image flags: `positions + images . box vectors` are the
    /// unwrapped positions, so grains crossing periodic faces come out
    /// whole.
    #[serde(default)]
    pub images: Vec<[i32; 3]>,
}

/// Where a run streams its trajectory and thermo rows.
#[derive(Clone, Debug, Default)]
pub struct OutputFiles {
    /// Thermo rows go here as they are recorded (and are not kept in
    /// memory).
    pub thermo: Option<PathBuf>,
    /// Snapshots in LAMMPS dump format.
    pub dump: Option<DumpOptions>,
}

impl OutputFiles {
    /// Checks `--dump-every` (at least 1 when there is a dump).
    pub fn validate(&self) -> Result<(), crate::options::InvalidOption> {
        if self.dump.as_ref().is_some_and(|d| d.every == 0) {
            return Err(crate::options::InvalidOption::new(
                "--dump-every",
                "must be at least 1",
            ));
        }
        Ok(())
    }

    /// The files, as text for reports.
    pub fn paths(&self) -> Vec<String> {
        self.thermo
            .iter()
            .chain(self.dump.iter().map(|d| &d.path))
            .map(|p| p.display().to_string())
            .collect()
    }
}

/// A trajectory dump.
#[derive(Clone, Debug)]
pub struct DumpOptions {
    /// The dump file.
    pub path: PathBuf,
    /// Global steps between snapshots (step 0 included).
    pub every: u64,
    /// Also write forces (`fx fy fz`).
    pub forces: bool,
}

/// Options of a run that are not part of the physics.
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// Threads for the force passes.
    pub threads: usize,
    /// Show progress bars (on a terminal).
    pub progress: bool,
    /// Files the run streams to.
    pub files: OutputFiles,
}

impl RunOptions {
    /// `threads` threads, no progress bars, nothing streamed.
    pub fn quiet(threads: usize) -> Self {
        Self {
            threads,
            progress: false,
            files: OutputFiles::default(),
        }
    }
}

/// Why a native run stopped.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The simulation failed (blow-up, particle lost, ...).
    #[error(transparent)]
    Engine(#[from] EngineError),
    /// A trajectory or thermo file could not be written.
    #[error(transparent)]
    Output(#[from] TrajectoryError),
    /// A stage stopped part of the way: the error, and what the stage had
    /// recorded until then.
    #[error("{error}")]
    Stopped {
        /// Why it stopped.
        error: Box<RunError>,
        /// The stage's records up to the failure (`stopped_at` set).
        partial: Box<StageOutput>,
    },
}

/// The open output files of a run.
#[derive(Debug, Default)]
pub struct Recorders {
    thermo: Option<ThermoWriter>,
    dump: Option<(DumpWriter, u64, bool)>,
    /// The scene's atom ids, written in dump frames that carry none.
    ids: Option<Vec<u64>>,
}

impl Recorders {
    /// Opens the files of `files`.
    pub fn open(files: &OutputFiles) -> Result<Self, TrajectoryError> {
        Ok(Self {
            thermo: files
                .thermo
                .as_deref()
                .map(ThermoWriter::create)
                .transpose()?,
            dump: match &files.dump {
                Some(d) if d.every > 0 => Some((DumpWriter::create(&d.path)?, d.every, d.forces)),
                _ => None,
            },
            ids: None,
        })
    }

    /// Dump frames written from here on carry the atom ids `ids` (a
    /// scene's `particles.ids`; `None` for `1..=N`), whatever numbering the
    /// engine used: the LAMMPS harness numbers atoms `1..=N`, in particle
    /// order.
    pub fn with_ids(mut self, ids: Option<Vec<u64>>) -> Self {
        self.ids = ids;
        self
    }

    /// The thermo writer, if rows are streamed.
    pub fn thermo(&mut self) -> Option<&mut ThermoWriter> {
        self.thermo.as_mut()
    }

    /// Steps between dump frames and whether they carry forces.
    pub fn dump_schedule(&self) -> Option<(u64, bool)> {
        self.dump
            .as_ref()
            .map(|(_, every, forces)| (*every, *forces))
    }

    /// Writes `frame` to the dump, with the atom ids of [`Self::with_ids`]
    /// if the frame has none of its own.
    pub fn write_frame(&mut self, mut frame: Frame) -> Result<(), TrajectoryError> {
        match &mut self.dump {
            Some((w, _, _)) => {
                if frame.id.is_none() {
                    frame.id.clone_from(&self.ids);
                }
                w.write(&frame)
            }
            None => Ok(()),
        }
    }
}

/// The native system's current state as a dump frame (atom ids `1..=N`;
/// [`Recorders::write_frame`] puts in the scene's).
pub fn frame_of(sys: &System, forces: bool) -> Frame {
    let p = &sys.particles;
    Frame {
        step: sys.step,
        id: None,
        simbox: sys.simbox.clone(),
        grain: p.grain.clone(),
        kind: p.kind.clone(),
        x: p.x.clone(),
        image: p.image.clone(),
        v: p.v.clone(),
        f: forces.then(|| p.f.clone()),
    }
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

/// Runs one stage on `sys`, recording into `out_files`.
pub fn run_stage(
    sys: &mut System,
    spec: &StageSpec,
    index: usize,
    seed: u64,
    opts: &RunOptions,
    out_files: &mut Recorders,
) -> Result<StageOutput, RunError> {
    let start = std::time::Instant::now();
    let timers_before = sys.timers.clone();
    let builds_before = sys.neighbours.builds;
    let n = sys.len();
    if let Some(ff) = &spec.force_field {
        if let Some(bpm) = sys.model_as_mut::<BpmModel>() {
            bpm.set_coefficients(ff.bond, ff.pair, ff.zero_net_multibody, n);
        } else if let (Some(dem), Some(material)) = (sys.model_as_mut::<DemModel>(), ff.granular) {
            dem.set_force_field(material, ff.multicontact);
        } else {
            return Err(EngineError::Unsupported {
                what: "this force-field change (validation checks the model's fields)",
            }
            .into());
        }
        sys.skin = ff.skin;
        sys.gravity = ff.gravity.map(Gravity::new);
    }
    if spec.reset_reference {
        let (simbox, x) = (sys.simbox.clone(), sys.particles.x.clone());
        sys.model_as_mut::<BpmModel>()
            .ok_or(EngineError::Unsupported {
                what: "a reference reset of a model without bonds",
            })?
            .reset_reference(&simbox, &x);
    }
    if spec.zero_velocities {
        sys.particles.v.fill([0.0; 3]);
        if let Some(rotation) = &mut sys.particles.rotation {
            rotation.omega.fill([0.0; 3]);
        }
    }
    if let Some(init) = &spec.set_velocities {
        sys.particles.v = random_velocities(n, init, stage_seed(seed, index));
    }
    let p = &sys.particles;
    let tether = spec
        .tether
        .as_ref()
        .map(|t| ActiveTether::new(t, &p.grain, &sys.simbox, &p.x, &p.image));
    let drivers = StageDrivers {
        dt: spec.dt,
        external: ExternalTerms {
            walls: spec.walls.clone(),
            sphere_wall: spec.sphere_wall.clone(),
            granular_walls: spec.granular_walls.clone(),
            tether,
            viscous: spec.viscous,
            gravity: sys.gravity,
        },
        deformation: spec.deformation.clone(),
        barostat: spec.barostat.clone(),
        tally_every: spec.record.every,
    };
    let stage_box = sys.simbox.clone();
    sys.setup(&drivers)?;
    let mut columns = stage_columns(sys.model.energy_terms(), sys.model.rotational(), spec);
    if sys
        .model_as::<DemModel>()
        .is_some_and(|m| m.multicontact().is_some())
    {
        columns.extend(closure_columns());
    }
    if let Some(t) = out_files.thermo() {
        t.begin_stage(index, &spec.name, &column_names(&columns))?;
    }
    let mut out = StageOutput {
        name: spec.name.clone(),
        steps: spec.steps,
        rows_file: out_files.thermo().map(|t| t.path().to_path_buf()),
        columns,
        rows: Vec::new(),
        checkpoints: Vec::new(),
        wall_seconds: 0.0,
        timers: Default::default(),
        neighbour_builds: 0,
        stopped_at: None,
    };
    let dump = out_files.dump_schedule();
    let record = |sys: &System,
                  out: &mut StageOutput,
                  files: &mut Recorders,
                  k: u64|
     -> Result<(), TrajectoryError> {
        if spec.record.every > 0 && k % spec.record.every == 0 {
            let row = native_row(&out.columns, sys);
            match files.thermo() {
                Some(t) => t.row(&row)?,
                None => out.rows.push(row),
            }
        }
        if spec.record.positions_every > 0 && k % spec.record.positions_every == 0 {
            let b = &sys.simbox;
            out.checkpoints.push(Checkpoint {
                step: sys.step,
                simbox: [b.lo, b.lengths, b.tilt],
                positions: sys.particles.x.clone(),
                images: sys.particles.image.clone(),
            });
        }
        if let Some((every, forces)) = dump {
            if sys.step % every == 0 {
                files.write_frame(frame_of(sys, forces))?;
            }
        }
        Ok(())
    };
    sys.check_faults(spec.dt)?;
    sys.check_walls()?;
    record(sys, &mut out, out_files, 0)?;
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
    let mut k = 0;
    let mut steps = || -> Result<(), RunError> {
        while k < spec.steps {
            k += 1;
            sys.step(&drivers, k, &stage_box)?;
            record(sys, &mut out, out_files, k)?;
            if k % 256 == 0 {
                sys.check_finite()?;
                bar.set_position(k);
            }
        }
        sys.check_finite()?;
        Ok(())
    };
    let result = steps();
    bar.finish_and_clear();
    // A failed flush must not hide why the stage stopped.
    let flushed = match out_files.thermo() {
        Some(t) => t.flush(),
        None => Ok(()),
    };
    out.wall_seconds = start.elapsed().as_secs_f64();
    for s in Stage::ALL {
        let secs = (sys.timers.total(s) - timers_before.total(s)).as_secs_f64();
        out.timers.insert(s.name().to_string(), secs);
    }
    out.neighbour_builds = sys.neighbours.builds - builds_before;
    if let Err(error) = result {
        // The records up to the failure are kept (a squeeze that ends early
        // still has its curve), except those a blow-up had already made
        // non-finite: finiteness is checked every 256 steps.
        let finite = |v: &[f64]| v.iter().all(|c| c.is_finite());
        while out.rows.last().is_some_and(|r| !finite(r)) {
            out.rows.pop();
        }
        while out
            .checkpoints
            .last()
            .is_some_and(|c| !c.positions.iter().all(|p| finite(p)))
        {
            out.checkpoints.pop();
        }
        out.stopped_at = Some(k);
        return Err(RunError::Stopped {
            error: Box::new(error),
            partial: Box::new(out),
        });
    }
    flushed?;
    Ok(out)
}

/// Runs every stage of `scene` on `sys` in order. Stages that finished are
/// returned even when a later one fails, so nothing recorded is lost.
pub fn run_scene(
    sys: &mut System,
    scene: &Scene,
    opts: &RunOptions,
) -> (Vec<StageOutput>, Option<RunError>) {
    let mut files = match Recorders::open(&opts.files) {
        Ok(f) => f.with_ids(scene.particles.ids.clone()),
        Err(e) => return (Vec::new(), Some(e.into())),
    };
    let mut done = Vec::with_capacity(scene.stages.len());
    for (i, stage) in scene.stages.iter().enumerate() {
        match run_stage(sys, stage, i, scene.seed, opts, &mut files) {
            Ok(out) => done.push(out),
            Err(RunError::Stopped { error, partial }) => {
                done.push(*partial);
                return (done, Some(*error));
            }
            Err(e) => return (done, Some(e)),
        }
    }
    (done, None)
}
