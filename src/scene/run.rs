//! Runs a scene's stages on the native engine and records observables.

use super::checkpoint::{
    CheckpointError, CheckpointOptions, Checkpointer, RunCheckpoint, StageProgress, StreamedFile,
};
use super::model::{Scene, StageSpec, VelocityInit};
use super::observables::{
    closure_columns, column_names, failure_columns, native_row, stage_columns,
};
pub use super::records::{Checkpoint, StageOutput};
use super::trajectory::{DumpWriter, Frame, ThermoWriter, TrajectoryError};
use crate::engine::{
    ActiveTether, BpmModel, DemModel, EngineError, EngineState, ExternalTerms, Gravity, Stage,
    StageDrivers, System,
};
use crate::progress::Progress;
use rand::{Rng, SeedableRng};
use std::borrow::Cow;
use std::path::{Path, PathBuf};

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
    /// Progress bars and log.
    pub progress: Progress,
    /// Files the run streams to.
    pub files: OutputFiles,
    /// Checkpoints to write, or to resume from; a stop asked for (a
    /// signal) reaches the run through them.
    pub checkpoint: Option<CheckpointOptions>,
}

impl RunOptions {
    /// `threads` threads, no progress bars, nothing streamed.
    pub fn quiet(threads: usize) -> Self {
        Self {
            threads,
            progress: Progress::hidden(),
            files: OutputFiles::default(),
            checkpoint: None,
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
    /// A checkpoint could not be written, read or used.
    #[error(transparent)]
    Checkpoint(#[from] CheckpointError),
    /// The run was asked to stop; the checkpoint it wrote (its own file,
    /// or the study's it is a part of) continues it.
    #[error("stopped at step {step} as asked; the checkpoint {} continues the run (the same command with --resume)", checkpoint.display())]
    Interrupted {
        /// The global step reached.
        step: u64,
        /// The checkpoint written.
        checkpoint: PathBuf,
    },
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

    /// Reopens the files of `files` where `checkpoint` left them: the
    /// same files must be asked for as when it was written.
    pub fn reopen(files: &OutputFiles, checkpoint: &RunCheckpoint<'_>) -> Result<Self, RunError> {
        let refused = |reason: String| {
            RunError::Checkpoint(CheckpointError::Refused {
                path: PathBuf::from("(resumed run)"),
                reason,
            })
        };
        // The files of the checkpoint, and those asked for now.
        let mismatch = |what: &str, saved: Option<&Path>, asked: Option<&Path>| {
            let name = |p: Option<&Path>| p.map_or("no file".into(), |p| p.display().to_string());
            refused(format!(
                "it {what} {}, this run asks for {}",
                name(saved),
                name(asked)
            ))
        };
        let thermo = match (&files.thermo, &checkpoint.thermo) {
            (None, None) => None,
            (Some(path), Some(saved)) if *path == saved.path => {
                Some(ThermoWriter::reopen(path, saved.length)?)
            }
            (asked, saved) => {
                return Err(mismatch(
                    "streamed thermo rows to",
                    saved.as_ref().map(|s| s.path.as_path()),
                    asked.as_deref(),
                ))
            }
        };
        let dump = match (&files.dump, &checkpoint.dump) {
            (None, None) => None,
            (Some(d), Some(saved)) if d.path == saved.path && d.every > 0 => Some((
                DumpWriter::reopen(&d.path, saved.length, saved.last_step)?,
                d.every,
                d.forces,
            )),
            (asked, saved) => {
                return Err(mismatch(
                    "wrote a dump to",
                    saved.as_ref().map(|s| s.path.as_path()),
                    asked.as_ref().map(|d| d.path.as_path()),
                ))
            }
        };
        Ok(Self {
            thermo,
            dump,
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

/// Where a stage starts.
enum StageStart<'a> {
    /// At its beginning: the stage's changes to the system, then a set-up.
    Fresh,
    /// Inside it, from a checkpoint.
    Resumed(Box<(StageProgress<'a>, EngineState)>),
}

/// A run's checkpointing, with the stages it finished before this one.
struct Saving<'a, 'b> {
    checkpointer: &'a mut Checkpointer,
    finished: &'b [StageOutput],
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
    run_stage_from(
        sys,
        spec,
        index,
        seed,
        opts,
        out_files,
        StageStart::Fresh,
        None,
    )
}

/// Makes the changes a stage makes at its start (force field, reference
/// reset, velocities) and resolves its tether.
fn begin_stage(
    sys: &mut System,
    spec: &StageSpec,
    index: usize,
    seed: u64,
) -> Result<Option<ActiveTether>, RunError> {
    let n = sys.len();
    if let Some(ff) = &spec.force_field {
        if let Some(bpm) = sys.model_as_mut::<BpmModel>() {
            bpm.set_force_field(ff.bpm(), n);
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
    Ok(spec
        .tether
        .as_ref()
        .map(|t| ActiveTether::new(t, &p.grain, &sys.simbox, &p.x, &p.image)))
}

/// How far the streamed files have got (flushed), for a checkpoint.
fn streamed(files: &mut Recorders) -> Result<[Option<StreamedFile>; 2], TrajectoryError> {
    let thermo = match &mut files.thermo {
        Some(t) => Some(StreamedFile {
            length: t.length()?,
            path: t.path().to_path_buf(),
            last_step: None,
        }),
        None => None,
    };
    let dump = match &mut files.dump {
        Some((d, _, _)) => Some(StreamedFile {
            length: d.length()?,
            path: d.path().to_path_buf(),
            last_step: d.last_step(),
        }),
        None => None,
    };
    Ok([thermo, dump])
}

#[allow(clippy::too_many_arguments)]
fn run_stage_from(
    sys: &mut System,
    spec: &StageSpec,
    index: usize,
    seed: u64,
    opts: &RunOptions,
    out_files: &mut Recorders,
    start: StageStart<'_>,
    mut saving: Option<Saving<'_, '_>>,
) -> Result<StageOutput, RunError> {
    let session_start = std::time::Instant::now();
    let timers_before = sys.timers.clone();
    let mut drivers = StageDrivers {
        dt: spec.dt,
        external: ExternalTerms {
            walls: spec.walls.clone(),
            sphere_wall: spec.sphere_wall.clone(),
            granular_walls: spec.granular_walls.clone(),
            tether: None,
            viscous: spec.viscous,
            gravity: None,
        },
        deformation: spec.deformation.clone(),
        barostat: spec.barostat.clone(),
        // Scenes do not clamp yet: the engine's clamps serve the drivers
        // of the cross-checks (the block pulled to fracture).
        clamps: Vec::new(),
        tally_every: spec.record.every,
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
                broken_bonds: sys
                    .model_as::<BpmModel>()
                    .map_or_else(Vec::new, |m| m.broken_bonds().to_vec()),
            });
        }
        if let Some((every, forces)) = dump {
            if sys.step % every == 0 {
                files.write_frame(frame_of(sys, forces))?;
            }
        }
        Ok(())
    };
    // What earlier sessions of a resumed stage spent and built.
    let (stage_box, mut out, mut k, builds_before, earlier) = match start {
        StageStart::Fresh => {
            let builds_before = sys.neighbours.builds;
            drivers.external.tether = begin_stage(sys, spec, index, seed)?;
            drivers.external.gravity = sys.gravity;
            let stage_box = sys.simbox.clone();
            sys.setup(&drivers)?;
            let mut columns = stage_columns(sys.model.energy_terms(), sys.model.rotational(), spec);
            if sys
                .model_as::<DemModel>()
                .is_some_and(|m| m.multicontact().is_some())
            {
                columns.extend(closure_columns());
            }
            if sys
                .model_as::<BpmModel>()
                .is_some_and(|m| m.force_field().live_failure().is_some())
            {
                columns.extend(failure_columns());
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
            sys.check_faults(spec.dt)?;
            sys.check_walls()?;
            record(sys, &mut out, out_files, 0)?;
            (stage_box, out, 0, builds_before, Default::default())
        }
        StageStart::Resumed(resumed) => {
            let (progress, engine) = *resumed;
            drivers.external.tether = progress.tether.into_owned();
            drivers.external.gravity = engine.gravity;
            sys.resume(&drivers, engine)?;
            let mut out = progress.output.into_owned();
            let earlier = (out.wall_seconds, std::mem::take(&mut out.timers));
            let builds_before = sys.neighbours.builds - out.neighbour_builds;
            (
                progress.stage_box.into_owned(),
                out,
                progress.step,
                builds_before,
                earlier,
            )
        }
    };
    let (earlier_seconds, earlier_timers): (f64, std::collections::BTreeMap<String, f64>) = earlier;
    // The wall time, timers and list builds of the stage so far, over
    // every session.
    let account = |sys: &System, out: &mut StageOutput| {
        out.wall_seconds = earlier_seconds + session_start.elapsed().as_secs_f64();
        for s in Stage::ALL {
            let secs = (sys.timers.total(s) - timers_before.total(s)).as_secs_f64();
            let before = earlier_timers.get(s.name()).copied().unwrap_or(0.0);
            out.timers.insert(s.name().to_string(), before + secs);
        }
        out.neighbour_builds = sys.neighbours.builds - builds_before;
    };
    let mut bar = opts
        .progress
        .task(&spec.name, spec.steps, k, spec.steps >= 1000);
    let mut steps = || -> Result<(), RunError> {
        while k < spec.steps {
            k += 1;
            sys.step(&drivers, k, &stage_box)?;
            record(sys, &mut out, out_files, k)?;
            if k % 256 == 0 {
                sys.check_finite()?;
                bar.set(k);
            }
            if let Some(saving) = &mut saving {
                let stop = saving.checkpointer.options().stop_requested(sys.step);
                if stop || saving.checkpointer.due(sys.step) {
                    // Only a finite state is worth continuing from.
                    sys.check_finite()?;
                    account(sys, &mut out);
                    let [thermo, dump] = streamed(out_files)?;
                    let progress = StageProgress {
                        index,
                        step: k,
                        stage_box: Cow::Borrowed(&stage_box),
                        tether: Cow::Borrowed(&drivers.external.tether),
                        output: Cow::Borrowed(&out),
                    };
                    saving.checkpointer.write(
                        saving.finished,
                        Some(progress),
                        sys.save_state()?,
                        thermo,
                        dump,
                    )?;
                    if stop {
                        return Err(RunError::Interrupted {
                            step: sys.step,
                            checkpoint: saving.checkpointer.options().target.path(),
                        });
                    }
                }
            }
        }
        sys.check_finite()?;
        Ok(())
    };
    let result = steps();
    bar.finish(k);
    // A failed flush must not hide why the stage stopped.
    let flushed = match out_files.thermo() {
        Some(t) => t.flush(),
        None => Ok(()),
    };
    account(sys, &mut out);
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
///
/// With [`RunOptions::checkpoint`], checkpoints are written as it asks
/// and at the end; resuming, `sys` must be the system built from `scene`
/// (its state is replaced by the checkpoint's) and the stages finished
/// before the checkpoint come back with the rest.
pub fn run_scene(
    sys: &mut System,
    scene: &Scene,
    opts: &RunOptions,
) -> (Vec<StageOutput>, Option<RunError>) {
    let outcome = run_scene_outcome(sys, scene, opts);
    (outcome.stages, outcome.error)
}

/// What a run did, over every session of a resumed one.
#[derive(Debug)]
pub struct RunOutcome {
    /// The stages finished (and the one that failed, cut where it did).
    pub stages: Vec<StageOutput>,
    /// Why the run stopped early, if it did.
    pub error: Option<RunError>,
    /// Wall-clock seconds, over every session.
    pub wall_seconds: f64,
    /// The global steps at which the run was resumed from checkpoints.
    pub resumed_at: Vec<u64>,
}

/// [`run_scene`], with the run's wall time and resumptions.
pub fn run_scene_outcome(sys: &mut System, scene: &Scene, opts: &RunOptions) -> RunOutcome {
    let start = std::time::Instant::now();
    let mut outcome = RunOutcome {
        stages: Vec::with_capacity(scene.stages.len()),
        error: None,
        wall_seconds: 0.0,
        resumed_at: Vec::new(),
    };
    let mut earlier_seconds = 0.0;
    outcome.error = run_stages(sys, scene, opts, &mut outcome, &mut earlier_seconds).err();
    outcome.wall_seconds = earlier_seconds + start.elapsed().as_secs_f64();
    outcome
}

/// [`run_scene`], appending finished stages to `outcome`.
fn run_stages(
    sys: &mut System,
    scene: &Scene,
    opts: &RunOptions,
    outcome: &mut RunOutcome,
    earlier_seconds: &mut f64,
) -> Result<(), RunError> {
    let done = &mut outcome.stages;
    let mut checkpointer = None;
    let mut resume = None;
    let saved = match &opts.checkpoint {
        Some(ck) if ck.resume => ck.saved_run(scene, opts.threads)?,
        _ => None,
    };
    let mut files = match (&opts.checkpoint, saved) {
        (Some(ck), Some(saved)) => {
            let files = Recorders::reopen(&opts.files, &saved)?;
            let mut resumed_at = saved.resumed_at;
            resumed_at.push(saved.engine.step);
            outcome.resumed_at.clone_from(&resumed_at);
            *earlier_seconds = saved.wall_seconds;
            checkpointer = Some(Checkpointer::new(
                ck.clone(),
                scene,
                opts.threads,
                saved.wall_seconds,
                resumed_at,
            ));
            done.extend(saved.finished.into_owned());
            match saved.current {
                Some(progress) => resume = Some((progress, saved.engine)),
                None => sys.restore(saved.engine)?,
            }
            files
        }
        (Some(ck), None) => {
            checkpointer = Some(Checkpointer::new(
                ck.clone(),
                scene,
                opts.threads,
                0.0,
                Vec::new(),
            ));
            Recorders::open(&opts.files)?
        }
        (None, _) => Recorders::open(&opts.files)?,
    }
    .with_ids(scene.particles.ids.clone());
    let first = resume.as_ref().map_or(done.len(), |(p, _)| p.index);
    for (i, stage) in scene.stages.iter().enumerate().skip(first) {
        let start = match resume.take() {
            Some(resumed) => StageStart::Resumed(Box::new(resumed)),
            None => StageStart::Fresh,
        };
        let saving = checkpointer.as_mut().map(|checkpointer| Saving {
            checkpointer,
            finished: done,
        });
        match run_stage_from(sys, stage, i, scene.seed, opts, &mut files, start, saving) {
            Ok(out) => done.push(out),
            Err(RunError::Stopped { error, partial }) => {
                done.push(*partial);
                return Err(*error);
            }
            Err(e) => return Err(e),
        }
    }
    if let Some(checkpointer) = &mut checkpointer {
        let [thermo, dump] = streamed(&mut files)?;
        checkpointer.write(done, None, sys.save_state()?, thermo, dump)?;
    }
    Ok(())
}
