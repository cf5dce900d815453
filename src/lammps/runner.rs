//! Runs a scene in LAMMPS in this process and returns the same observables
//! as the native engine (`scene::run::StageOutput`).
//!
//! Debian's LAMMPS ends the process on an error, so callers that must
//! survive a rejected input run this in a child process
//! (`bpm run --engine lammps`, see `verify::engines`).

use super::instance::{Lammps, LammpsError, LammpsVersion};
use super::script::{write_driver, DriverLine, ScriptError, StagePlan};
use crate::scene::observables::column_names;
use crate::scene::observables::Quantity;
use crate::scene::run::{Checkpoint, OutputFiles, Recorders, StageOutput};
use crate::scene::trajectory::{Frame, TrajectoryError};
use crate::scene::Scene;
use std::path::Path;

/// A failure of a LAMMPS run.
#[derive(Debug, thiserror::Error)]
pub enum LammpsRunError {
    /// The scene cannot be expressed as a LAMMPS input.
    #[error(transparent)]
    Script(#[from] ScriptError),
    /// LAMMPS reported an error (only with a LAMMPS built with exceptions).
    #[error(transparent)]
    Lammps(#[from] LammpsError),
    /// A trajectory or thermo file could not be written.
    #[error(transparent)]
    Output(#[from] TrajectoryError),
    /// LAMMPS produced non-finite observables.
    #[error("stage `{stage}`: LAMMPS produced a non-finite {what}")]
    NotFinite {
        /// Stage name.
        stage: String,
        /// What.
        what: String,
    },
}

/// Result of [`run_scene_lammps`].
pub struct LammpsRun {
    /// Observables per stage (complete on MPI rank 0 only).
    pub stages: Vec<StageOutput>,
    /// This process's MPI rank.
    pub rank: i32,
    /// MPI ranks of the run.
    pub ranks: i32,
    /// The LAMMPS that ran it (`lammps_version()`).
    pub lammps_version: LammpsVersion,
}

/// Runs `scene` in LAMMPS: writes `<dir>/<tag>.{in,data,data.r0,log}` and
/// returns the observables. `newton` sets LAMMPS's `newton` (bond and
/// pair). Thermo rows and snapshots go to `files` (on rank 0) through the
/// same writers as the native engine's.
pub fn run_scene_lammps(
    scene: &Scene,
    dir: &Path,
    tag: &str,
    newton: bool,
    files: &OutputFiles,
) -> Result<LammpsRun, LammpsRunError> {
    let driver = write_driver(scene, dir, tag, newton)?;
    let log = dir.join(format!("{tag}.log")).display().to_string();
    // LAMMPS's screen output stays on: with Debian's LAMMPS an error ends
    // the process, and its ERROR line on the terminal is the explanation.
    let mut lmp = Lammps::open(&["-log", &log])?;
    let rank = lmp.setting("world_rank");
    let ranks = lmp.setting("world_size");
    let lammps_version = lmp.version();
    // LAMMPS numbers the atoms 1..N in particle order (the run's data
    // file); frames are written with the scene's own ids.
    let mut recorders = if rank == 0 {
        Recorders::open(files)?.with_ids(scene.particles.ids.clone())
    } else {
        Recorders::default()
    };
    let mut stage_index = 0;
    let mut stages = Vec::with_capacity(driver.stages.len());
    let mut step0 = 0u64;
    let mut time0 = 0.0;
    for line in &driver.lines {
        match line {
            DriverLine::Command(c) => lmp.commands(c)?,
            DriverLine::Run { stage } => {
                let plan = &driver.stages[*stage];
                let mut out = run_stage(&mut lmp, plan, step0, time0, &mut recorders)?;
                if let Some(t) = recorders.thermo() {
                    t.begin_stage(stage_index, &plan.name, &column_names(&plan.columns))?;
                    for row in &out.rows {
                        t.row(row)?;
                    }
                    t.flush()?;
                    out.rows_file = Some(t.path().to_path_buf());
                    out.rows.clear();
                }
                stage_index += 1;
                step0 += plan.steps;
                time0 += plan.steps as f64 * plan.dt;
                stages.push(out);
            }
        }
    }
    Ok(LammpsRun {
        stages,
        rank,
        ranks,
        lammps_version,
    })
}

/// Runs one stage in chunks that end at the position checkpoints and the
/// dump steps; `run ... start 0 stop <steps>` keeps `fix deform` and `fix
/// vector` anchored at the stage start across chunks, as in one run.
fn run_stage(
    lmp: &mut Lammps,
    plan: &StagePlan,
    step0: u64,
    time0: f64,
    recorders: &mut Recorders,
) -> Result<StageOutput, LammpsRunError> {
    let start = std::time::Instant::now();
    let mut checkpoints = Vec::new();
    let dump = recorders.dump_schedule();
    // Stage steps (0..=steps) where something is gathered.
    let wanted = |k: u64| {
        (plan.positions_every > 0 && k % plan.positions_every == 0)
            || dump.is_some_and(|(every, _)| (step0 + k) % every == 0)
    };
    // Positions and image flags are gathered once per step, whether a
    // checkpoint, a dump frame or both need them.
    let mut gather =
        |lmp: &Lammps, k: u64, recorders: &mut Recorders| -> Result<(), LammpsRunError> {
            let (lo, hi, tilt) = lmp.box_geometry();
            let lengths = [hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]];
            let x = lmp.gather_vectors("x")?;
            let image = lmp.gather_images()?;
            let frame_wanted = dump.filter(|(every, _)| (step0 + k) % every == 0);
            if let Some((_, forces)) = frame_wanted {
                let frame = Frame {
                    step: step0 + k,
                    id: None,
                    simbox: crate::engine::SimBox {
                        lo,
                        lengths,
                        tilt,
                        periodic: lmp.periodicity(),
                    },
                    grain: lmp
                        .gather_ints("molecule")?
                        .into_iter()
                        .map(|m| m.max(1) as u32 - 1)
                        .collect(),
                    kind: lmp
                        .gather_ints("type")?
                        .into_iter()
                        .map(|t| t as u32)
                        .collect(),
                    x: x.clone(),
                    image: image.clone(),
                    v: lmp.gather_vectors("v")?,
                    f: if forces {
                        Some(lmp.gather_vectors("f")?)
                    } else {
                        None
                    },
                };
                recorders.write_frame(frame)?;
            }
            if plan.positions_every > 0 && k % plan.positions_every == 0 {
                checkpoints.push(Checkpoint {
                    step: step0 + k,
                    simbox: [lo, lengths, tilt],
                    positions: x,
                    images: image,
                    broken_bonds: Vec::new(),
                });
            }
            Ok(())
        };
    // Before the stage's first run, as the native engine records its
    // stage start (forces in a frame there are the last evaluation's).
    if wanted(0) {
        gather(lmp, 0, recorders)?;
    }
    let mut done = 0;
    while done < plan.steps {
        let mut n = 1;
        while done + n < plan.steps && !wanted(done + n) {
            n += 1;
        }
        let tail = if done == 0 { "" } else { " pre no post no" };
        lmp.commands(&format!("run {n} start 0 stop {}{tail}", plan.steps))?;
        done += n;
        if wanted(done) {
            gather(lmp, done, recorders)?;
        }
    }
    let mut rows: Vec<Vec<f64>> = Vec::new();
    if let Some(intervals) = plan.steps.checked_div(plan.every) {
        let recorded = plan.columns.iter().filter(|c| c.lammps.is_some()).count();
        let values = lmp.fix_array("bpm_record", intervals + 1, recorded)?;
        let stress: Vec<usize> = (0..3)
            .filter_map(|k| {
                plan.columns
                    .iter()
                    .filter(|c| c.lammps.is_some())
                    .position(|c| c.quantity == Quantity::Stress(k))
            })
            .collect();
        for (r, values) in values.into_iter().enumerate() {
            let k = r as u64 * plan.every;
            let mut next = values.iter();
            let row = plan
                .columns
                .iter()
                .map(|c| match (c.quantity, &c.lammps) {
                    (_, Some(_)) => next.next().copied().unwrap_or(f64::NAN),
                    (Quantity::Step, None) => (step0 + k) as f64,
                    (Quantity::Time, None) => time0 + k as f64 * plan.dt,
                    // The mean of the recorded diagonal, as the native
                    // engine's (LAMMPS's scalar counts 3N - 3 kinetic
                    // degrees of freedom).
                    (Quantity::Pressure, None) if stress.len() == 3 => {
                        stress.iter().map(|&i| values[i]).sum::<f64>() / 3.0
                    }
                    _ => f64::NAN,
                })
                .collect();
            rows.push(row);
        }
    }
    let not_finite = |what: &str| LammpsRunError::NotFinite {
        stage: plan.name.clone(),
        what: what.to_string(),
    };
    if rows.iter().flatten().any(|v| !v.is_finite()) {
        return Err(not_finite("thermo value"));
    }
    if checkpoints
        .iter()
        .flat_map(|c| c.positions.iter().flatten())
        .any(|v| !v.is_finite())
    {
        return Err(not_finite("position"));
    }
    Ok(StageOutput {
        name: plan.name.clone(),
        steps: plan.steps,
        columns: plan.columns.clone(),
        rows,
        rows_file: None,
        checkpoints,
        wall_seconds: start.elapsed().as_secs_f64(),
        timers: Default::default(),
        neighbour_builds: 0,
        stopped_at: None,
    })
}
