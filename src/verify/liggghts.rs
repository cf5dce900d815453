//! The standing cross-check against LIGGGHTS: its hydrogel tutorial (514
//! beads in SI units, gravity, a lid closing and opening twice) run by the
//! native engine through the lid protocol, and its lid force compared
//! with LIGGGHTS's own, committed in
//! `reference_data/liggghts/hydrogel_multicontact/` (how it was made: the
//! README there). The bed and the reference are built into the program,
//! so the check runs from any folder and needs no LIGGGHTS.

use crate::analysis::lid_force::{compare_lid_force, compare_lid_force_by_pass, LidComparison};
use crate::engine::MultiContact;
use crate::file_error::FileError;
use crate::scene::protocols::lid::{lid_scene, LidError, LidOptions, LidRows};
use crate::verify::{run_native, HarnessError};
use serde::Serialize;
use std::path::Path;

/// The tutorial's bed (`data/input.data`).
const BED: &str = include_str!("../../reference_data/liggghts/hydrogel_multicontact/input.data");
/// LIGGGHTS's lid force with plain Hertz contacts and gravity.
const HERTZ_GRAVITY: &str =
    include_str!("../../reference_data/liggghts/hydrogel_multicontact/lid_hertz_gravity.txt");
/// LIGGGHTS's lid force with the closure and gravity (the tutorial as
/// shipped).
const CLOSURE_GRAVITY: &str = include_str!(
    "../../reference_data/liggghts/hydrogel_multicontact/lid_multicontact_gravity.txt"
);

/// LIGGGHTS's deck of plain Hertz with gravity.
const HERTZ_DECK: &str =
    include_str!("../../reference_data/liggghts/hydrogel_multicontact/in.hertz_gravity");
/// LIGGGHTS's deck of the closure with gravity (the tutorial as shipped).
const CLOSURE_DECK: &str =
    include_str!("../../reference_data/liggghts/hydrogel_multicontact/in.multicontact_gravity");

/// Rows count as loaded where LIGGGHTS's force exceeds this fraction of
/// its peak: below it both forces are a few contacts flickering on and
/// off, and a relative error means nothing.
pub const LOADED_FRACTION: f64 = 0.01;

/// The contact laws LIGGGHTS ran.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum LiggghtsLaw {
    /// `pair_style gran model hertz tangential history`.
    Hertz,
    /// The same with `surface multicontact` and `fix
    /// multicontact/halfspace geometric_prefactor 1.125`.
    Closure,
}

impl LiggghtsLaw {
    /// The law's name in verdicts.
    pub fn name(self) -> &'static str {
        match self {
            Self::Hertz => "Hertz",
            Self::Closure => "standard closure",
        }
    }

    /// The closure the law runs with (`None`: plain Hertz).
    pub fn multicontact(self) -> Option<MultiContact> {
        match self {
            Self::Hertz => None,
            Self::Closure => Some(MultiContact::standard(TUTORIAL_PREFACTOR)),
        }
    }

    /// The law's part of the reference files' names (`in.<tag>_gravity`,
    /// `lid_<tag>_gravity.txt`).
    pub fn tag(self) -> &'static str {
        match self {
            Self::Hertz => "hertz",
            Self::Closure => "multicontact",
        }
    }

    /// LIGGGHTS's deck of the law with gravity, as committed.
    pub fn deck(self) -> &'static str {
        match self {
            Self::Hertz => HERTZ_DECK,
            Self::Closure => CLOSURE_DECK,
        }
    }

    fn reference(self) -> &'static str {
        match self {
            Self::Hertz => HERTZ_GRAVITY,
            Self::Closure => CLOSURE_GRAVITY,
        }
    }
}

/// The tutorial's `geometric_prefactor`, our `gamma`.
const TUTORIAL_PREFACTOR: f64 = 1.125;

/// Why the cross-check could not run (a large difference is not an error:
/// it is the result).
#[derive(Debug, thiserror::Error)]
pub enum LiggghtsError {
    /// The bed could not be written to the work folder.
    #[error(transparent)]
    File(#[from] FileError),
    /// The lid scene could not be built.
    #[error(transparent)]
    Lid(#[from] LidError),
    /// The native run failed.
    #[error(transparent)]
    Harness(#[from] HarnessError),
    /// The run recorded no lid rows.
    #[error("the {law} lid run: {message}")]
    Rows {
        /// The contact law.
        law: &'static str,
        /// What was missing.
        message: String,
    },
    /// A reference table line is malformed (the built-in table is
    /// corrupt).
    #[error("LIGGGHTS's lid table, line {line}: {message}")]
    Reference {
        /// 1-based line.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// No loaded row of the two runs falls on the same step.
    #[error("the {0} lid run shares no loaded step with LIGGGHTS's")]
    NoOverlap(&'static str),
}

/// The lid protocol of LIGGGHTS's hydrogel tutorial on the bed at
/// `bed` (SI units): walls of 5e7 Pa, spheres of 23.3e3 Pa, Poisson's
/// ratio 0.5, restitution 0.95, friction 0.03, gravity 9.81 m/s^2 down,
/// the lid from 0.1676430125 m to 0.1375165625 m in 30,000 steps of 1e-5 s
/// and back, `cycles` times; the walls keep their friction springs from
/// pass to pass, as LIGGGHTS's wall fixes do across its `run` commands.
pub fn tutorial_options(bed: &Path, cycles: usize) -> LidOptions {
    let lid_start = 0.1676430125;
    let lid_end = 0.1375165625;
    let dt = 1e-5;
    LidOptions {
        packing: bed.to_path_buf(),
        base: [0.165190844117647, 0.165833589215686],
        lid_start,
        lid_end,
        lid_speed: (lid_start - lid_end) / (30_000.0 * dt),
        cycles,
        dt,
        youngs_modulus: 23.3e3,
        wall_modulus: 5e7,
        poisson_ratio: 0.5,
        restitution: 0.95,
        friction: 0.03,
        gamma: TUTORIAL_PREFACTOR,
        gravity: [0.0, 0.0, -9.81],
        record_every: 100,
        skin: None,
        keep_wall_histories: true,
    }
}

/// Writes the tutorial's bed (LIGGGHTS's `data/input.data`, built into the
/// program) as `work/name`, creating `work`; returns the file's path.
pub fn write_tutorial_bed(work: &Path, name: &str) -> Result<std::path::PathBuf, FileError> {
    std::fs::create_dir_all(work).map_err(FileError::on("creating", work))?;
    let bed = work.join(name);
    std::fs::write(&bed, BED).map_err(FileError::on("writing", &bed))?;
    Ok(bed)
}

/// LIGGGHTS's lid force per step: the `step` and the instantaneous `fz`
/// columns of a committed lid table.
pub fn reference_lid_force(table: &str) -> Result<(Vec<u64>, Vec<f64>), LiggghtsError> {
    let mut steps = Vec::new();
    let mut forces = Vec::new();
    for (k, line) in table.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let bad = |message: &str| LiggghtsError::Reference {
            line: k + 1,
            message: message.into(),
        };
        let words: Vec<&str> = line.split_whitespace().collect();
        if words.len() < 5 {
            return Err(bad("fewer than 5 columns (step time fx fy fz ...)"));
        }
        let step = words[0]
            .parse()
            .map_err(|_| bad("the step is not an integer"))?;
        let fz: f64 = words[4].parse().map_err(|_| bad("fz is not a number"))?;
        if !fz.is_finite() {
            return Err(bad("fz is not finite"));
        }
        steps.push(step);
        forces.push(fz);
    }
    Ok((steps, forces))
}

/// One contact law's lid force against LIGGGHTS's.
#[derive(Clone, Debug, Serialize)]
pub struct LiggghtsLidCheck {
    /// The contact law.
    pub law: LiggghtsLaw,
    /// Lid cycles run (the reference has two).
    pub cycles: usize,
    /// The difference over the loaded rows.
    pub comparison: LidComparison,
    /// The same, pass by pass of the lid (closing, opening, ...), each
    /// against the whole run's peak; `None` for a pass with no loaded row.
    pub by_pass: Vec<Option<LidComparison>>,
    /// Our peak lid force.
    pub native_peak: f64,
    /// Native wall seconds.
    pub seconds: f64,
}

impl LiggghtsLidCheck {
    /// The RMS difference of each pass, in percent of the peak, in words.
    pub fn by_pass_line(&self) -> String {
        let passes: Vec<String> = self
            .by_pass
            .iter()
            .map(|p| {
                p.map_or("no loaded row".into(), |c| {
                    format!("{:.2}%", 100.0 * c.rms_of_peak)
                })
            })
            .collect();
        format!(
            "{} lid force by pass (closing, opening, ...), RMS of the peak: {}",
            self.law.name(),
            passes.join(", ")
        )
    }
}

/// Runs the tutorial's first `cycles` lid cycles (at most two) with `law`
/// on `threads` threads, writing the bed into `work`, and compares the lid
/// force with LIGGGHTS's at every step both recorded.
pub fn lid_cross_check(
    law: LiggghtsLaw,
    cycles: usize,
    work: &Path,
    threads: usize,
) -> Result<LiggghtsLidCheck, LiggghtsError> {
    let bed = write_tutorial_bed(work, "hydrogel-input.data")?;
    let opts = tutorial_options(&bed, cycles.clamp(1, 2));
    lid_cross_check_with(law, &opts, threads)
}

/// [`lid_cross_check`] with the protocol `opts` (the tutorial's, from
/// [`tutorial_options`], perhaps changed).
pub fn lid_cross_check_with(
    law: LiggghtsLaw,
    opts: &LidOptions,
    threads: usize,
) -> Result<LiggghtsLidCheck, LiggghtsError> {
    let scene = lid_scene(opts, law.multicontact(), law.name())?;
    let run = run_native(&scene, &format!("liggghts-{}", law.name()), threads)?;
    let rows = LidRows::read(&run.stages).map_err(|message| LiggghtsError::Rows {
        law: law.name(),
        message,
    })?;
    let (ref_step, ref_force) = reference_lid_force(law.reference())?;
    let comparison = compare_lid_force(
        &rows.step,
        &rows.lid_force,
        &ref_step,
        &ref_force,
        LOADED_FRACTION,
    )
    .ok_or(LiggghtsError::NoOverlap(law.name()))?;
    let mut by_pass = compare_lid_force_by_pass(
        &rows.step,
        &rows.lid_force,
        &ref_step,
        &ref_force,
        LOADED_FRACTION,
        opts.steps_per_pass(),
    );
    // The reference runs two cycles; this run may stop after one.
    by_pass.truncate(2 * opts.cycles);
    Ok(LiggghtsLidCheck {
        law,
        cycles: opts.cycles,
        comparison,
        by_pass,
        native_peak: rows.lid_force.iter().copied().fold(0.0, f64::max),
        seconds: run.seconds,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_built_in_tables_hold_every_hundredth_step_of_four_passes() {
        for law in [LiggghtsLaw::Hertz, LiggghtsLaw::Closure] {
            let (steps, forces) = reference_lid_force(law.reference()).unwrap();
            assert_eq!(steps.len(), 1200);
            assert_eq!(steps[0], 100);
            assert_eq!(*steps.last().unwrap(), 120_000);
            assert!(forces.iter().copied().fold(0.0, f64::max) > 1.0);
        }
    }

    #[test]
    fn a_malformed_reference_line_is_named() {
        let err = reference_lid_force("# header\n100 0.001 0 0 x\n").unwrap_err();
        assert_eq!(
            err.to_string(),
            "LIGGGHTS's lid table, line 2: fz is not a number"
        );
    }
}
