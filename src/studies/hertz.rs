//! The Hertz sphere-squeeze study (docs/protocols.md, "Hertz sphere
//! squeeze"): grains built here or brought by the user, squeezed between
//! two flat walls in either engine, their force-overlap curves against
//! Hertz's law, ensemble mean and spread, JSON and plots.

pub mod cli;

use crate::analysis::fit::interpolate;
use crate::analysis::hertz::{
    effective_modulus, hertz_deviation, hertz_normalised_force, squeeze_curve, HertzDeviation,
    SqueezeCurve, CONTACT_THRESHOLD,
};
use crate::analysis::plot::{Mark, Panel, Series};
use crate::file_error::FileError;
use crate::reference::paper;
use crate::scene::builders::grain::{build_grain, GrainKind, GrainParams, GrainSummary};
use crate::scene::protocols::{hertz_squeeze, SqueezeParams};
use crate::scene::rotation::{rotated, uniform_rotation};
use crate::scene::StageOutput;
use crate::scene::{ForceField, Scene};
use crate::studies::output::{self, OutputError, StudyOutput, StudyReport};
use crate::studies::StudyRuntime;
use crate::verify::single_point::nan_max;
use crate::verify::{HarnessError, LammpsLauncher};
use rand::{Rng, SeedableRng};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Where the squeezed grains come from.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GrainSource {
    /// Built here, one grain per seed.
    Build {
        /// Rough or smoother.
        kind: GrainKind,
        /// Radius R (d).
        radius: f64,
        /// Scale of the build's times (1 = full protocol).
        time_scale: f64,
    },
    /// One grain from a scene (JSON) or a LAMMPS data file, squeezed as
    /// given; `radius` is its nominal R.
    File {
        /// The file.
        path: PathBuf,
        /// Nominal radius R (d).
        radius: f64,
    },
}

impl GrainSource {
    /// The nominal radius R (d).
    pub fn radius(&self) -> f64 {
        match self {
            GrainSource::Build { radius, .. } | GrainSource::File { radius, .. } => *radius,
        }
    }

    /// Checks the radius and the build's time scale; the error names the
    /// option at fault.
    pub fn validate(&self) -> Result<(), HertzError> {
        if let GrainSource::Build { time_scale, .. } = self {
            if !(time_scale.is_finite() && *time_scale > 0.0) {
                return Err(HertzError::Options(format!(
                    "--time-scale must be positive, got {time_scale}"
                )));
            }
        }
        let radius = self.radius();
        if !(radius.is_finite() && radius >= MIN_GRAIN_RADIUS) {
            return Err(HertzError::Options(format!(
                "--radius must be at least {MIN_GRAIN_RADIUS} (d), got {radius}"
            )));
        }
        Ok(())
    }
}

/// The grain in `path`: a scene (JSON) as written, or a LAMMPS data file
/// read with the paper's force field at `a_b` (the squeeze sets its own).
pub fn read_grain_file(path: &Path, a_b: f64, seed: u64) -> Result<Scene, HertzError> {
    if path.extension().is_some_and(|e| e == "json") {
        crate::scene::read_scene_unvalidated(path).map_err(|e| HertzError::Grain(e.to_string()))
    } else {
        crate::scene::datafile::read_data_file(path, [false; 3], ForceField::paper(a_b), seed)
            .map_err(|e| HertzError::Grain(e.to_string()))
    }
}

/// The elastic constants that set E_eff.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Moduli {
    /// Bulk modulus K (k / d).
    pub k: f64,
    /// Poisson ratio.
    pub nu: f64,
    /// Where they come from.
    pub source: String,
}

impl Moduli {
    /// The paper's calibration fits at `a_b` (reference_data/paper_fits.json).
    pub fn paper_fits(a_b: f64) -> Self {
        let (k, nu) = paper::elastic_constants(a_b);
        Self {
            k,
            nu,
            source: paper::elastic_constants_source(a_b),
        }
    }
}

/// Which engine squeezes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SqueezeEngine {
    /// The native engine.
    Native,
    /// LAMMPS with this project's styles (child process).
    Lammps,
    /// Both: the curve is the native one, and each squeeze records how far
    /// LAMMPS's force curve is from it.
    Both,
}

/// Options of the study.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct HertzOptions {
    /// The grains.
    pub source: GrainSource,
    /// Seeds: one built grain per seed (ignored for a file, except as the
    /// seed of its rotations).
    pub seeds: Vec<u64>,
    /// Multibody strength a_B (k d); the force field is the paper's.
    pub a_b: f64,
    /// Random rotations per grain (0: squeeze as given).
    pub rotations: usize,
    /// Overlap delta / R to reach.
    pub max_overlap: f64,
    /// E_eff's constants.
    pub moduli: Moduli,
    /// The engine.
    pub engine: SqueezeEngine,
    /// Records per squeeze.
    pub records: u64,
    /// Threads of the native engine.
    pub threads: usize,
}

/// Why the study failed.
#[derive(Debug, thiserror::Error)]
pub enum HertzError {
    /// Bad options (names the option).
    #[error("{0}")]
    Options(String),
    /// A grain could not be built or read.
    #[error("grain: {0}")]
    Grain(String),
    /// A squeeze failed in an engine.
    #[error(transparent)]
    Run(#[from] HarnessError),
    /// A file or folder could not be written.
    #[error(transparent)]
    File(#[from] FileError),
    /// The report or its drawings could not be written or read back.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// The study stopped before its end (its checkpoint continues it).
    #[error(transparent)]
    Stopped(#[from] crate::studies::StudyStop),
}

impl HertzOptions {
    /// Checks the options; the error names the one at fault.
    pub fn validate(&self) -> Result<(), HertzError> {
        let bad = |m: String| Err(HertzError::Options(m));
        self.source.validate()?;
        if self.rotations > MAX_ROTATIONS {
            return bad(format!(
                "--rotations must be at most {MAX_ROTATIONS}, got {}",
                self.rotations
            ));
        }
        if !(self.a_b.is_finite() && self.a_b > -1.0) {
            return bad(format!(
                "--a-b must be finite and above -1 (k d), got {}",
                self.a_b
            ));
        }
        if !(self.max_overlap.is_finite() && self.max_overlap > 0.0 && self.max_overlap < 1.0) {
            return bad(format!(
                "--max-overlap must be in (0, 1), got {}",
                self.max_overlap
            ));
        }
        if self.seeds.is_empty() {
            return bad("--seeds needs at least one value".into());
        }
        let e = effective_modulus(self.moduli.k, self.moduli.nu);
        if !(e.is_finite() && e > 0.0) {
            return bad(format!(
                "K = {} and nu = {} give E_eff = {e}: need K > 0 and -1 < nu < 1/2",
                self.moduli.k, self.moduli.nu
            ));
        }
        Ok(())
    }

    fn radius(&self) -> f64 {
        self.source.radius()
    }
}

/// One squeezed grain.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Squeeze {
    /// Grain seed.
    pub seed: u64,
    /// Rotation index (0 = as given when no rotations were asked).
    pub rotation: usize,
    /// The rotation's three uniform numbers (none: as given).
    pub rotation_draw: Option<[f64; 3]>,
    /// The builder's summary, for built grains.
    pub grain: Option<GrainSummary>,
    /// Particles.
    pub particles: usize,
    /// The curve: wall_gap, force, overlap_over_r, normalised_force.
    pub curve: SqueezeCurve,
    /// Deviation from Hertz over delta / R in [0.02, 0.25].
    pub deviation: Option<HertzDeviation>,
    /// Wall-clock seconds of the squeeze.
    pub seconds: f64,
    /// With both engines: the largest difference between their wall
    /// forces, relative to the largest force, and LAMMPS's wall-clock
    /// seconds.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub engines: Option<EngineAgreement>,
    /// Why the squeeze stopped before the overlap asked for, if it did;
    /// the curve runs up to there.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stopped: Option<String>,
}

/// How closely LAMMPS repeats the native squeeze.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct EngineAgreement {
    /// Largest |f_native - f_lammps| over the records, over the largest |f|
    /// (none when LAMMPS failed).
    pub force_deviation: Option<f64>,
    /// Largest |gap_native - gap_lammps| (d): the walls are prescribed.
    pub gap_deviation: Option<f64>,
    /// LAMMPS's wall-clock seconds.
    pub lammps_seconds: f64,
    /// LAMMPS's error, when it stopped.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lammps_error: Option<String>,
}

/// LAMMPS's error when a particle reaches a flat wall's plane: the one
/// way a squeeze may stop in both engines.
const LAMMPS_WALL_ERROR: &str = "Particle on or inside fix wall surface";

/// The squeeze's wall gap and mean wall force per record.
pub(crate) fn gap_and_force(stage: &StageOutput) -> (Vec<f64>, Vec<f64>) {
    let col = |name: &str| stage.column(name).unwrap_or_default();
    let force = col("wall0_force")
        .iter()
        .zip(col("wall1_force"))
        .map(|(a, b)| 0.5 * (a + b))
        .collect();
    let gap = col("wall0_position")
        .iter()
        .zip(col("wall1_position"))
        .map(|(a, b)| b - a)
        .collect();
    (gap, force)
}

/// Squeezes natively. A squeeze that stops part of the way (a particle
/// pushed onto a wall's plane) keeps its records up to there, with the
/// reason; one stopped as asked (a signal, with a checkpoint in
/// `runtime`, the run's part `key`) ends the study.
pub(crate) fn squeeze_native(
    scene: &Scene,
    tag: &str,
    runtime: &StudyRuntime,
    key: &str,
) -> Result<(StageOutput, Option<String>), HertzError> {
    squeeze_native_system(scene, tag, runtime, key).map(|(stage, stopped, _)| (stage, stopped))
}

/// [`squeeze_native`], also returning the system in its final state (the
/// squeezed grain, its bonds as the squeeze left them).
pub(crate) fn squeeze_native_system(
    scene: &Scene,
    tag: &str,
    runtime: &StudyRuntime,
    key: &str,
) -> Result<(StageOutput, Option<String>, crate::engine::System), HertzError> {
    crate::scene::validate(scene).map_err(|cause| HarnessError::Scene {
        scene: tag.into(),
        cause,
    })?;
    let mut sys = crate::scene::build_system(scene, runtime.threads);
    let outcome = runtime.run_system(key, &mut sys, scene)?;
    match (
        outcome.stages.into_iter().next(),
        outcome.error.map(|e| e.to_string()),
    ) {
        (Some(stage), error) if stage.rows.len() > 1 => Ok((stage, error, sys)),
        (_, error) => Err(HertzError::Run(HarnessError::Native {
            scene: tag.into(),
            message: error.unwrap_or_else(|| "the squeeze recorded nothing".into()),
        })),
    }
}

/// Largest |a - b| (NaN if any difference is NaN; infinite when the
/// series differ in length).
fn largest_difference(a: &[f64], b: &[f64]) -> f64 {
    if a.len() != b.len() {
        return f64::INFINITY;
    }
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, nan_max)
}

/// The ensemble on a common overlap grid.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Ensemble {
    /// delta / R.
    pub overlap_over_r: Vec<f64>,
    /// Mean normalised force over the squeezes that reach that overlap
    /// (NaN where none does: squeezes that stopped early).
    #[serde(deserialize_with = "crate::json_nan::nan_if_null_each")]
    pub mean: Vec<f64>,
    /// Standard deviation (0 where fewer than two squeezes reach).
    pub sd: Vec<f64>,
    /// How many squeezes contribute.
    pub count: Vec<usize>,
    /// Deviation of the mean from Hertz over delta / R in [0.02, 0.25].
    pub deviation: Option<HertzDeviation>,
}

/// The study's result, written as `hertz.json`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct HertzReport {
    /// `bpm hertz`.
    pub program: String,
    /// Crate version.
    pub version: String,
    /// The options.
    pub options: HertzOptions,
    /// The squeeze protocol.
    pub squeeze: SqueezeParams,
    /// E_eff (k / d).
    pub e_eff: f64,
    /// Contact threshold (E_eff R^2).
    pub contact_threshold: f64,
    /// Every squeeze.
    pub squeezes: Vec<Squeeze>,
    /// Mean and spread.
    pub ensemble: Ensemble,
    /// Wall-clock seconds of the study.
    pub wall_seconds: f64,
}

/// The smallest grain radius (d) a squeeze accepts: below it a grain is a
/// handful of particles.
pub const MIN_GRAIN_RADIUS: f64 = 1.5;

/// The most rotations per grain a squeeze study takes (each is a
/// squeeze of its own).
pub const MAX_ROTATIONS: usize = 10_000;

/// Window of the deviation from Hertz.
pub const HERTZ_WINDOW: (f64, f64) = (0.02, 0.25);

/// A grain to squeeze: its seed (also the seed of its rotations), the
/// scene, and the builder's summary when it was built here.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Grain {
    /// Seed.
    pub seed: u64,
    /// The grain (positions, bonds; no stages).
    pub scene: Scene,
    /// The builder's summary.
    pub summary: Option<GrainSummary>,
}

/// A grain built from `params`; a failed build is a [`HertzError::Grain`].
pub fn built_grain(
    params: &GrainParams,
    threads: usize,
) -> Result<(Scene, GrainSummary), HertzError> {
    build_grain(params, threads, false).map_err(|e| HertzError::Grain(e.to_string()))
}

fn grains(opts: &HertzOptions) -> Result<Vec<Grain>, HertzError> {
    match &opts.source {
        GrainSource::Build {
            kind,
            radius,
            time_scale,
        } => opts
            .seeds
            .iter()
            .map(|&seed| {
                let mut p = GrainParams::new(*kind, *radius, seed, opts.a_b);
                p.time_scale = *time_scale;
                let (scene, summary) = built_grain(&p, opts.threads)?;
                Ok(Grain {
                    seed,
                    scene,
                    summary: Some(summary),
                })
            })
            .collect(),
        GrainSource::File { path, .. } => Ok(vec![Grain {
            seed: opts.seeds[0],
            scene: read_grain_file(path, opts.a_b, opts.seeds[0])?,
            summary: None,
        }]),
    }
}

/// Runs the study: every grain, every rotation, in the chosen engine;
/// writes `hertz.json` and `hertz.svg` into `out`.
///
/// With a checkpoint in `runtime`, the grains and each squeeze are kept in
/// it as they finish and the native squeeze under way is checkpointed into
/// it, so the same call with the checkpoint resumed ends with the same
/// report.
pub fn run_hertz(
    opts: &HertzOptions,
    out: &Path,
    launcher: &LammpsLauncher,
    runtime: &StudyRuntime,
    progress: &mut dyn FnMut(&Squeeze),
) -> Result<HertzReport, HertzError> {
    opts.validate()?;
    let start = std::time::Instant::now();
    let grains = runtime.part("grains", || grains(opts))?;
    let mut report = squeeze_grains(opts, grains, launcher, runtime, "", progress)?;
    report.wall_seconds = start.elapsed().as_secs_f64();
    write_report(&report, out)?;
    Ok(report)
}

/// Squeezes `grains` (every rotation the options ask for) in the chosen
/// engine. The options must be valid; `wall_seconds` counts the squeezes.
/// Each squeeze is a part of `runtime`'s checkpoint, its key
/// `{key_prefix}seed{seed}-rot{r}`.
pub fn squeeze_grains(
    opts: &HertzOptions,
    grains: Vec<Grain>,
    launcher: &LammpsLauncher,
    runtime: &StudyRuntime,
    key_prefix: &str,
    progress: &mut dyn FnMut(&Squeeze),
) -> Result<HertzReport, HertzError> {
    let start = std::time::Instant::now();
    let radius = opts.radius();
    let e_eff = effective_modulus(opts.moduli.k, opts.moduli.nu);
    let mut params = SqueezeParams::paper(radius, opts.max_overlap);
    params.records = opts.records;
    let runtime = &StudyRuntime {
        threads: opts.threads,
        ..runtime.clone()
    };
    let mut squeezes = Vec::new();
    for Grain {
        seed,
        scene: mut grain,
        summary,
    } in grains
    {
        grain.force_field = ForceField::paper(opts.a_b);
        for (r, draw) in rotation_draws(seed, opts.rotations).into_iter().enumerate() {
            let g = turned(&grain, draw);
            let scene = hertz_squeeze(&g, &params);
            let tag = format!("seed{seed}-rot{r}");
            let key = format!("{key_prefix}{tag}");
            let s = runtime.part(&key, || -> Result<Squeeze, HertzError> {
                let t = std::time::Instant::now();
                let (stage, stopped) = match opts.engine {
                    SqueezeEngine::Native | SqueezeEngine::Both => {
                        squeeze_native(&scene, &tag, runtime, &key)?
                    }
                    SqueezeEngine::Lammps => {
                        let mut run = launcher.run(&scene, &tag, 1, true)?;
                        (run.stages.remove(0), None)
                    }
                };
                let seconds = t.elapsed().as_secs_f64();
                let (gap, force) = gap_and_force(&stage);
                let engines = if opts.engine == SqueezeEngine::Both {
                    let t = std::time::Instant::now();
                    let lammps = launcher.run(&scene, &tag, 1, true);
                    let lammps_seconds = t.elapsed().as_secs_f64();
                    Some(match lammps {
                        Ok(_) if stopped.is_some() => {
                            let why = stopped.unwrap_or_default();
                            return Err(HertzError::Run(HarnessError::Native {
                                scene: tag.clone(),
                                message: format!(
                                    "the engines disagree: LAMMPS ran the squeeze \
                                     through, the native engine stopped ({why})"
                                ),
                            }));
                        }
                        Ok(run) => {
                            let (gap_l, force_l) = gap_and_force(&run.stages[0]);
                            let scale = force.iter().map(|f| f.abs()).fold(0.0, nan_max);
                            EngineAgreement {
                                force_deviation: Some(largest_difference(&force, &force_l) / scale),
                                gap_deviation: Some(largest_difference(&gap, &gap_l)),
                                lammps_seconds,
                                lammps_error: None,
                            }
                        }
                        // Only a native squeeze that stopped too may see LAMMPS
                        // stop: otherwise the engines disagree.
                        Err(e)
                            if stopped.is_some() && e.to_string().contains(LAMMPS_WALL_ERROR) =>
                        {
                            EngineAgreement {
                                force_deviation: None,
                                gap_deviation: None,
                                lammps_seconds,
                                lammps_error: Some(e.to_string()),
                            }
                        }
                        Err(e) => return Err(e.into()),
                    })
                } else {
                    None
                };
                let curve = squeeze_curve(&gap, &force, radius, e_eff);
                let deviation = hertz_deviation(
                    &curve.overlap_over_r,
                    &curve.normalised_force,
                    HERTZ_WINDOW.0,
                    HERTZ_WINDOW.1,
                );
                Ok(Squeeze {
                    seed,
                    rotation: r,
                    rotation_draw: draw,
                    grain: summary.clone(),
                    particles: g.particles.positions.len(),
                    curve,
                    deviation,
                    seconds,
                    engines,
                    stopped,
                })
            })?;
            progress(&s);
            squeezes.push(s);
        }
    }
    let ensemble = ensemble(&squeezes, opts.max_overlap);
    Ok(HertzReport {
        program: "bpm hertz".into(),
        version: crate::VERSION.into(),
        options: opts.clone(),
        squeeze: params,
        e_eff,
        contact_threshold: CONTACT_THRESHOLD,
        squeezes,
        ensemble,
        wall_seconds: start.elapsed().as_secs_f64(),
    })
}

/// The uniform numbers of `rotations` random rotations of the grain of
/// seed `seed` (seeded by it), or one `None` (as given) for 0 rotations.
pub fn rotation_draws(seed: u64, rotations: usize) -> Vec<Option<[f64; 3]>> {
    if rotations == 0 {
        return vec![None];
    }
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed ^ 0x4E27_0000);
    (0..rotations)
        .map(|_| Some([rng.gen(), rng.gen(), rng.gen()]))
        .collect()
}

/// `grain` turned by the rotation of `draw` (as given for `None`).
pub fn turned(grain: &Scene, draw: Option<[f64; 3]>) -> Scene {
    match draw {
        Some(u) => rotated(grain, &uniform_rotation(u)),
        None => grain.clone(),
    }
}

fn ensemble(squeezes: &[Squeeze], max_overlap: f64) -> Ensemble {
    let steps = (max_overlap / 0.0025).round() as usize;
    let grid: Vec<f64> = (0..=steps).map(|k| k as f64 * 0.0025).collect();
    let (mut mean, mut sd, mut count) = (Vec::new(), Vec::new(), Vec::new());
    for &x in &grid {
        let v: Vec<f64> = squeezes
            .iter()
            .filter_map(|s| interpolate(&s.curve.overlap_over_r, &s.curve.normalised_force, x))
            .collect();
        let n = v.len();
        let m = v.iter().sum::<f64>() / n.max(1) as f64;
        let var = if n > 1 {
            v.iter().map(|y| (y - m) * (y - m)).sum::<f64>() / (n - 1) as f64
        } else {
            0.0
        };
        mean.push(if n > 0 { m } else { f64::NAN });
        sd.push(var.sqrt());
        count.push(n);
    }
    let full: Vec<usize> = (0..grid.len()).filter(|&k| count[k] > 0).collect();
    let deviation = hertz_deviation(
        &full.iter().map(|&k| grid[k]).collect::<Vec<_>>(),
        &full.iter().map(|&k| mean[k]).collect::<Vec<_>>(),
        HERTZ_WINDOW.0,
        HERTZ_WINDOW.1,
    );
    Ensemble {
        overlap_over_r: grid,
        mean,
        sd,
        count,
        deviation,
    }
}

/// Writes `hertz.json` and `hertz.svg` into `out`.
pub fn write_report(report: &HertzReport, out: &Path) -> Result<(), HertzError> {
    output::write_report(report, out)?;
    Ok(())
}

impl StudyReport for HertzReport {
    const JSON: &'static str = "hertz.json";

    /// `hertz.svg`: [`panels`].
    fn draw(&self, out: &StudyOutput) -> Result<(), OutputError> {
        out.svg("hertz.svg", &panels(self))?;
        Ok(())
    }
}

/// Fig. 4-like panels: normalised force against delta / R, linear and
/// log-log, with Hertz's line, the contact threshold and mean +- one sd.
pub fn panels(report: &HertzReport) -> Vec<Panel> {
    let e = &report.ensemble;
    let pts = |f: &dyn Fn(usize) -> f64| -> Vec<(f64, f64)> {
        (0..e.overlap_over_r.len())
            .filter(|&k| e.count[k] > 0 && e.overlap_over_r[k] > 0.0)
            .map(|k| (e.overlap_over_r[k], f(k)))
            .filter(|p| p.1 > 0.0)
            .collect()
    };
    let hertz: Vec<(f64, f64)> = (1..=100)
        .map(|k| {
            let x = k as f64 * report.options.max_overlap / 100.0;
            (x, hertz_normalised_force(x))
        })
        .collect();
    let threshold = CONTACT_THRESHOLD * 3.0 / 8.0;
    let n = report.squeezes.len();
    let series = vec![
        Series::new(
            format!("mean of {n} squeezes"),
            pts(&|k| e.mean[k]),
            Mark::Line,
        ),
        Series::new("mean + sd", pts(&|k| e.mean[k] + e.sd[k]), Mark::Line),
        Series::new("mean - sd", pts(&|k| e.mean[k] - e.sd[k]), Mark::Line),
        Series::new("Hertz (delta/R)^3/2", hertz, Mark::Line),
        Series::new(
            "contact threshold",
            vec![(1e-3, threshold), (report.options.max_overlap, threshold)],
            Mark::Line,
        ),
    ];
    let title = format!(
        "a_B = {}, E_eff = {:.4} ({})",
        report.options.a_b, report.e_eff, report.options.moduli.source
    );
    vec![
        Panel {
            title: title.clone(),
            x_label: "delta / R".into(),
            y_label: "3 f / (8 R^2 E_eff)".into(),
            log_x: false,
            log_y: false,
            series: series.clone(),
        },
        Panel {
            title: format!("{title}, log-log"),
            x_label: "delta / R".into(),
            y_label: "3 f / (8 R^2 E_eff)".into(),
            log_x: true,
            log_y: true,
            series,
        },
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Where no squeeze reaches an overlap the ensemble's mean is
    /// undefined: written as null, read back as NaN.
    #[test]
    fn an_ensemble_with_unreached_overlaps_reads_back() {
        let empty = ensemble(&[], 0.01);
        assert!(empty.mean.iter().all(|m| m.is_nan()));
        let json = serde_json::to_string(&empty).unwrap();
        let read: Ensemble = serde_json::from_str(&json).unwrap();
        assert_eq!(read.count, empty.count);
        assert!(read.mean.iter().all(|m| m.is_nan()));
    }
}
