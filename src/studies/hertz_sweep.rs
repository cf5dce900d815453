//! Deviation from Hertz against grain size: one grain per radius, built
//! once and squeezed at every a_B asked for, with the build and squeeze
//! times of each, so the cost of a smaller error can be read off
//! (run time against error).

pub mod cli;

use crate::analysis::hertz::HertzDeviation;
use crate::analysis::plot::{Mark, Panel, Series};
use crate::file_error::FileError;
use crate::scene::builders::grain::{build_grain, GrainKind, GrainParams, GrainSummary};
use crate::scene::write_scene;
use crate::studies::hertz::{
    squeeze_grains, write_report, Grain, GrainSource, HertzError, HertzOptions, Moduli,
    SqueezeEngine, MIN_GRAIN_RADIUS,
};
use crate::studies::output::{self, OutputError, StudyOutput, StudyReport};
use crate::studies::StudyRuntime;
use crate::verify::LammpsLauncher;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Options of the sweep.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SweepOptions {
    /// Rough or smoother grains.
    pub kind: GrainKind,
    /// Radii R (d), one grain each.
    pub radii: Vec<f64>,
    /// Multibody strengths a_B (k d) each grain is squeezed at.
    pub a_bs: Vec<f64>,
    /// Seed of every grain (and of its rotations).
    pub seed: u64,
    /// Random rotations per squeeze (0: as built).
    pub rotations: usize,
    /// Overlap delta / R to reach.
    pub max_overlap: f64,
    /// Records per squeeze.
    pub records: u64,
    /// The engine that squeezes.
    pub engine: SqueezeEngine,
    /// Threads of the native engine (builds and squeezes).
    pub threads: usize,
    /// Scale of the grain builds' times (1 = the full protocol).
    pub time_scale: f64,
}

/// One radius at one a_B.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SweepCase {
    /// Radius R (d).
    pub radius: f64,
    /// Multibody strength a_B (k d).
    pub a_b: f64,
    /// Poisson ratio behind E_eff.
    pub nu: f64,
    /// The grain builder's summary (particles, bonds, roughness, build time).
    pub grain: GrainSummary,
    /// Squeezes (rotations).
    pub squeezes: usize,
    /// Mean wall-clock seconds per squeeze.
    pub seconds_per_squeeze: f64,
    /// Deviation of the ensemble mean from Hertz over delta / R in [0.02, 0.25].
    pub deviation: Option<HertzDeviation>,
    /// Largest relative rms deviation of a single squeeze.
    pub worst_squeeze_rms_relative: f64,
    /// Folder of this case's `hertz.json` and `hertz.svg`, relative to the
    /// sweep's folder.
    pub folder: String,
}

/// The sweep's result, written as `sweep.json`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SweepReport {
    /// `bpm hertz-sweep`.
    pub program: String,
    /// Crate version.
    pub version: String,
    /// The options.
    pub options: SweepOptions,
    /// Every radius at every a_B, radius-major.
    pub cases: Vec<SweepCase>,
    /// Wall-clock seconds of the sweep.
    pub wall_seconds: f64,
}

/// Builds one grain per radius, squeezes it at every a_B, and writes into
/// `out`: `grains/` (each grain as a scene, to squeeze again with
/// `bpm hertz --grain`), one folder per case with its `hertz.json` and
/// `hertz.svg`, and `sweep.json` with `sweep.svg`.
pub fn run_hertz_sweep(
    opts: &SweepOptions,
    out: &Path,
    launcher: &LammpsLauncher,
    runtime: &StudyRuntime,
    progress: &mut dyn FnMut(&SweepCase),
) -> Result<SweepReport, HertzError> {
    if opts.radii.is_empty() || opts.a_bs.is_empty() {
        return Err(HertzError::Options(
            "--radii and --a-b need at least one value each".into(),
        ));
    }
    if let Some(r) = opts
        .radii
        .iter()
        .find(|r| !(r.is_finite() && **r >= MIN_GRAIN_RADIUS))
    {
        return Err(HertzError::Options(format!(
            "--radii must all be at least {MIN_GRAIN_RADIUS} (d), got {r}"
        )));
    }
    let case_opts = |radius: f64, a_b: f64| HertzOptions {
        source: GrainSource::Build {
            kind: opts.kind,
            radius,
            time_scale: opts.time_scale,
        },
        seeds: vec![opts.seed],
        a_b,
        rotations: opts.rotations,
        max_overlap: opts.max_overlap,
        moduli: Moduli::paper_fits(a_b),
        engine: opts.engine,
        records: opts.records,
        threads: opts.threads,
    };
    // Every case's options are checked before the first grain is built.
    for &radius in &opts.radii {
        for &a_b in &opts.a_bs {
            case_opts(radius, a_b).validate()?;
        }
    }
    let start = std::time::Instant::now();
    let grains_dir = out.join("grains");
    std::fs::create_dir_all(&grains_dir).map_err(FileError::on("creating", &grains_dir))?;
    let mut cases = Vec::new();
    for &radius in &opts.radii {
        // The grain's build has no bonds in force until it is bonded, and
        // its a_B only sets the force field it is written with.
        let mut params = GrainParams::new(opts.kind, radius, opts.seed, opts.a_bs[0]);
        params.time_scale = opts.time_scale;
        let (scene, summary) = runtime.part(&format!("R{radius}/grain"), || {
            build_grain(&params, opts.threads, false).map_err(|e| HertzError::Grain(e.to_string()))
        })?;
        let grain_file = grains_dir.join(format!(
            "{}-R{radius}-s{}.json",
            opts.kind.name(),
            opts.seed
        ));
        write_scene(&grain_file, &scene).map_err(|e| HertzError::Grain(e.to_string()))?;
        let grain = Grain {
            seed: opts.seed,
            scene,
            summary: Some(summary.clone()),
        };
        for &a_b in &opts.a_bs {
            let hertz_opts = case_opts(radius, a_b);
            let folder = format!("R{radius}-aB{a_b}");
            let report = squeeze_grains(
                &hertz_opts,
                vec![grain.clone()],
                launcher,
                runtime,
                &format!("{folder}/"),
                &mut |_| {},
            )?;
            write_report(&report, &out.join(&folder))?;
            let n = report.squeezes.len();
            let case = SweepCase {
                radius,
                a_b,
                nu: hertz_opts.moduli.nu,
                grain: summary.clone(),
                squeezes: n,
                seconds_per_squeeze: report.squeezes.iter().map(|s| s.seconds).sum::<f64>()
                    / n.max(1) as f64,
                deviation: report.ensemble.deviation,
                worst_squeeze_rms_relative: report
                    .squeezes
                    .iter()
                    .filter_map(|s| s.deviation.map(|d| d.rms_relative))
                    .fold(f64::NAN, f64::max),
                folder,
            };
            progress(&case);
            cases.push(case);
        }
    }
    let report = SweepReport {
        program: "bpm hertz-sweep".into(),
        version: crate::VERSION.into(),
        options: opts.clone(),
        cases,
        wall_seconds: start.elapsed().as_secs_f64(),
    };
    output::write_report(&report, out)?;
    Ok(report)
}

impl StudyReport for SweepReport {
    const JSON: &'static str = "sweep.json";

    /// `sweep.svg`: [`sweep_panels`].
    fn draw(&self, out: &StudyOutput) -> Result<(), OutputError> {
        out.svg("sweep.svg", &sweep_panels(self))?;
        Ok(())
    }
}

/// Relative rms deviation from Hertz against R, and against the squeeze
/// time, one series per a_B.
pub fn sweep_panels(report: &SweepReport) -> Vec<Panel> {
    let series = |x: &dyn Fn(&SweepCase) -> f64| -> Vec<Series> {
        report
            .options
            .a_bs
            .iter()
            .map(|&a_b| {
                let points = report
                    .cases
                    .iter()
                    .filter(|c| c.a_b == a_b)
                    .filter_map(|c| c.deviation.map(|d| (x(c), 100.0 * d.rms_relative)))
                    .collect();
                let nu = report
                    .cases
                    .iter()
                    .find(|c| c.a_b == a_b)
                    .map_or(f64::NAN, |c| c.nu);
                Series::new(
                    format!("a_B = {a_b} (nu = {nu:.2})"),
                    points,
                    Mark::LinePoints,
                )
            })
            .collect()
    };
    let title = format!(
        "{} grains, seed {}, {} rotations each: deviation of the mean curve from Hertz over delta/R in [0.02, 0.25]",
        report.options.kind.name(), report.options.seed, report.options.rotations
    );
    vec![
        Panel {
            title: title.clone(),
            x_label: "grain radius R (d)".into(),
            y_label: "relative rms deviation (%)".into(),
            log_x: false,
            log_y: false,
            series: series(&|c| c.radius),
        },
        Panel {
            title: "run time against error".into(),
            x_label: format!(
                "wall-clock seconds per squeeze ({} thread(s))",
                report.options.threads
            ),
            y_label: "relative rms deviation (%)".into(),
            log_x: true,
            log_y: false,
            series: series(&|c| c.seconds_per_squeeze),
        },
    ]
}
