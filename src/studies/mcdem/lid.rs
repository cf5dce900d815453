//! `bpm mc-compress --packing FILE.data`: the lid protocol
//! (`scene::protocols::lid`) on a bed from a data file, run with plain
//! Hertz and with the standard closure; the lid's force per row, a table
//! and a plot.

use super::Variant;
use crate::analysis::plot::{Mark, Panel, Series};
use crate::engine::MultiContact;
use crate::file_error::FileError;
use crate::scene::protocols::lid::{lid_scene, LidError, LidOptions, LidRows};
use crate::scene::Scene;
use crate::studies::output::{self, OutputError, StudyOutput, StudyReport};
use serde::Serialize;
use std::path::Path;

/// Why the lid study could not finish.
#[derive(Debug, thiserror::Error)]
pub enum LidStudyError {
    /// The scene could not be built.
    #[error(transparent)]
    Protocol(#[from] LidError),
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
    /// The study stopped before its end (its checkpoint continues it).
    #[error(transparent)]
    Stopped(#[from] crate::studies::StudyStop),
    /// The report or its drawings could not be written or read back.
    #[error(transparent)]
    Output(#[from] crate::studies::output::OutputError),
}

/// The contact laws compared: plain Hertz and the standard closure at the
/// options' `gamma`.
pub fn lid_variants(opts: &LidOptions) -> Vec<Variant> {
    vec![
        Variant {
            name: "Hertz".into(),
            multicontact: None,
        },
        Variant {
            name: format!("standard (gamma {})", opts.gamma),
            multicontact: Some(MultiContact::standard(opts.gamma)),
        },
    ]
}

/// One contact law's run: the lid's rows over every pass.
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
pub struct LidRun {
    /// The contact law.
    pub variant: String,
    /// The lid's rows.
    #[serde(flatten)]
    pub rows: LidRows,
    /// Wall-clock seconds of the run.
    pub seconds: f64,
    /// Why the run stopped early, if it did.
    pub stopped: Option<String>,
}

/// What `bpm mc-compress --packing` writes (`lid.json`).
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
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

/// Runs the lid protocol with each contact law. With a checkpoint in
/// `runtime`, each law's run is kept in it as it finishes, and the run
/// under way is continued.
pub fn run_lid(
    opts: &LidOptions,
    command: &str,
    runtime: &crate::studies::StudyRuntime,
) -> Result<(LidReport, Vec<Scene>), LidStudyError> {
    let mut runs = Vec::new();
    let mut scenes = Vec::new();
    for variant in lid_variants(opts) {
        let scene = lid_scene(opts, variant.multicontact, &variant.name)?;
        let run = runtime.part(&variant.name, || {
            let outcome = runtime.run_scene(&variant.name, &scene)?;
            let rows = LidRows::read(&outcome.stages).map_err(|message| LidStudyError::Run {
                variant: variant.name.clone(),
                message,
            })?;
            Ok::<_, LidStudyError>(LidRun {
                variant: variant.name.clone(),
                rows,
                seconds: outcome.wall_seconds,
                stopped: outcome.error.map(|e| e.to_string()),
            })
        })?;
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
pub fn write_lid_report(
    report: &LidReport,
    scenes: &[Scene],
    dir: &Path,
) -> Result<(), LidStudyError> {
    let out = output::write_report(report, dir)?;
    for (k, scene) in scenes.iter().enumerate() {
        let text = serde_json::to_string(scene).expect("a scene serialises");
        out.text(&format!("scene-{k}.json"), &text)?;
    }
    Ok(())
}

impl StudyReport for LidReport {
    const JSON: &'static str = "lid.json";

    /// `lid.svg`: the lid force against time.
    fn draw(&self, out: &StudyOutput) -> Result<(), OutputError> {
        let report = self;
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
                    let points = r
                        .rows
                        .time
                        .iter()
                        .copied()
                        .zip(r.rows.lid_force.iter().copied());
                    Series::new(r.variant.clone(), points.collect(), Mark::Line)
                })
                .collect(),
            ..Panel::default()
        };
        out.svg("lid.svg", &[panel])?;
        Ok(())
    }
}

/// A table: per contact law, the peak lid force, the rows, the run time.
pub fn lid_table(report: &LidReport) -> String {
    let mut out = format!(
        "{:<28} {:>14} {:>8} {:>10}\n",
        "contact law", "peak lid force", "rows", "seconds"
    );
    for r in &report.runs {
        let peak = r.rows.lid_force.iter().copied().fold(0.0, f64::max);
        out.push_str(&format!(
            "{:<28} {:>14.6e} {:>8} {:>10.1}{}\n",
            r.variant,
            peak,
            r.rows.time.len(),
            r.seconds,
            r.stopped
                .as_ref()
                .map_or(String::new(), |s| format!("  stopped: {s}"))
        ));
    }
    out
}
