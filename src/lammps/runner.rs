//! Runs a scene in LAMMPS in this process and returns the same observables
//! as the native engine (`scene::run::StageOutput`).
//!
//! Debian's LAMMPS ends the process on an error, so callers that must
//! survive a rejected input run this in a child process
//! (`bpm run --engine lammps`, see `verify::engines`).

use super::instance::{Lammps, LammpsError, LammpsVersion};
use super::script::{write_driver, DriverLine, ScriptError, StagePlan, RECORDED_VALUES};
use crate::scene::run::{Checkpoint, StageOutput, BOX_COLUMNS, STRESS_COLUMNS};
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
/// returns the observables. `newton` sets LAMMPS's `newton` (bond and pair).
pub fn run_scene_lammps(
    scene: &Scene,
    dir: &Path,
    tag: &str,
    newton: bool,
) -> Result<LammpsRun, LammpsRunError> {
    let driver = write_driver(scene, dir, tag, newton)?;
    let log = dir.join(format!("{tag}.log")).display().to_string();
    // LAMMPS's screen output stays on: with Debian's LAMMPS an error ends
    // the process, and its ERROR line on the terminal is the explanation.
    let mut lmp = Lammps::open(&["-log", &log])?;
    let rank = lmp.setting("world_rank");
    let ranks = lmp.setting("world_size");
    let lammps_version = lmp.version();
    let mut stages = Vec::with_capacity(driver.stages.len());
    let mut step0 = 0u64;
    let mut time0 = 0.0;
    for line in &driver.lines {
        match line {
            DriverLine::Command(c) => lmp.commands(c)?,
            DriverLine::Run { stage } => {
                let plan = &driver.stages[*stage];
                let out = run_stage(&mut lmp, plan, step0, time0)?;
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

/// Runs one stage in chunks that end at the position checkpoints; `run
/// ... start 0 stop <steps>` keeps `fix deform` and `fix vector` anchored at
/// the stage start across chunks, as in one run.
fn run_stage(
    lmp: &mut Lammps,
    plan: &StagePlan,
    step0: u64,
    time0: f64,
) -> Result<StageOutput, LammpsRunError> {
    let start = std::time::Instant::now();
    let mut checkpoints = Vec::new();
    let mut checkpoint = |lmp: &Lammps, k: u64| -> Result<(), LammpsRunError> {
        let (lo, hi, tilt) = lmp.box_geometry();
        checkpoints.push(Checkpoint {
            step: step0 + k,
            simbox: [lo, [hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]], tilt],
            positions: lmp.gather_vectors("x")?,
        });
        Ok(())
    };
    let chunk = if plan.positions_every > 0 {
        checkpoint(lmp, 0)?;
        plan.positions_every.min(plan.steps.max(1))
    } else {
        plan.steps
    };
    let mut done = 0;
    loop {
        let n = chunk.min(plan.steps - done);
        let tail = if done == 0 { "" } else { " pre no post no" };
        lmp.commands(&format!("run {n} start 0 stop {}{tail}", plan.steps))?;
        done += n;
        if plan.positions_every > 0 && done > 0 && done % plan.positions_every == 0 {
            checkpoint(lmp, done)?;
        }
        if done >= plan.steps {
            break;
        }
    }
    let mut rows = Vec::new();
    if let Some(intervals) = plan.steps.checked_div(plan.every) {
        let columns = RECORDED_VALUES + 2 * plan.walls;
        let recorded = lmp.fix_array("bpm_record", intervals + 1, columns)?;
        // Box and stress values, then energies and walls; the native row has
        // the mean of the diagonal stress between them.
        let stress = BOX_COLUMNS.len();
        let energies = stress + STRESS_COLUMNS.len();
        for (r, values) in recorded.into_iter().enumerate() {
            let k = r as u64 * plan.every;
            let mut row = vec![(step0 + k) as f64, time0 + k as f64 * plan.dt];
            row.extend_from_slice(&values[..energies]);
            row.push(values[stress..stress + 3].iter().sum::<f64>() / 3.0);
            row.extend_from_slice(&values[energies..]);
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
        checkpoints,
        wall_seconds: start.elapsed().as_secs_f64(),
        timers: Default::default(),
        neighbour_builds: 0,
    })
}
