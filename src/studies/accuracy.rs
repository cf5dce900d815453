//! Run time against error (`bpm accuracy`, docs/protocols.md "Run time
//! against error"): the calibration (K and G of the bulk solid) and the
//! Hertz squeeze force, each repeated with one parameter changed from its
//! default at a time: timestep, loading rate (strain rate, wall speed),
//! neighbour skin and resolution (box side L, grain radius R).
//!
//! Errors are relative and measured against the most accurate case of the
//! same sweep (the smallest timestep, the slowest loading; the skin, which
//! changes only which pairs are listed, against the default): what the
//! faster setting gives up. Resolution is different: a small solid or
//! grain is not a poorer solution of the same problem, so its error is
//! against the largest box (calibration) and against Hertz's law (squeeze).
//! Cost is the wall-clock time of the runs and, to compare without the
//! machine's noise, particles times steps.

pub mod cli;

use crate::analysis::fit::interpolate;
use crate::analysis::hertz::{effective_modulus, hertz_deviation, squeeze_curve};
use crate::analysis::plot::{Mark, Panel, Series};
use crate::file_error::FileError;
use crate::options::{require_positive_up_to, require_within, validate_a_b_values, InvalidOption};
use crate::scene::builders::grain::{GrainKind, GrainParams};
use crate::scene::protocols::{hertz_squeeze, SqueezeParams};
use crate::scene::{ForceField, Scene};
use crate::studies::calibration::{measure_moduli, paper_solid, CalibrationEngine, Loading};
use crate::studies::hertz::{built_grain, gap_and_force, squeeze_native, HertzError, Moduli};
use crate::studies::output::{self, OutputError, Provenance, StudyOutput, StudyReport};
use crate::verify::engines::HarnessError;
use serde::{Deserialize, Deserializer, Serialize};
use std::path::Path;

/// Why the study could not finish.
#[derive(Debug, thiserror::Error)]
pub enum AccuracyError {
    /// An option is out of range.
    #[error(transparent)]
    Invalid(#[from] InvalidOption),
    /// A solid or a calibration run failed.
    #[error(transparent)]
    Harness(#[from] HarnessError),
    /// A grain or a squeeze failed.
    #[error(transparent)]
    Hertz(#[from] HertzError),
    /// The report could not be written or read.
    #[error(transparent)]
    File(#[from] FileError),
    /// The report or its drawings could not be written or read back.
    #[error(transparent)]
    Output(#[from] OutputError),
}

/// What `bpm accuracy` runs. Every sweep holds the other parameters at
/// their defaults (the first four fields' defaults, the docs' defaults).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct AccuracyOptions {
    /// Multibody strength a_B of every run (k d).
    pub a_b: f64,
    /// Seed of the solids and grains.
    pub seed: u64,
    /// Default timestep (tau).
    pub dt: f64,
    /// Default neighbour skin (d).
    pub skin: f64,
    /// Default box side of the calibration (d).
    pub size: f64,
    /// Default strain rate of the calibration (1 / tau).
    pub rate: f64,
    /// Default grain radius of the squeeze (d).
    pub radius: f64,
    /// Default wall speed of the squeeze (d / tau, each wall).
    pub wall_speed: f64,
    /// Timesteps of both sweeps (tau).
    pub dts: Vec<f64>,
    /// Neighbour skins of both sweeps (d).
    pub skins: Vec<f64>,
    /// Box sides of the calibration's resolution sweep (d).
    pub sizes: Vec<f64>,
    /// Strain rates of the calibration (1 / tau).
    pub rates: Vec<f64>,
    /// Grain radii of the squeeze's resolution sweep (d).
    pub radii: Vec<f64>,
    /// Wall speeds of the squeeze (d / tau).
    pub wall_speeds: Vec<f64>,
    /// Kind of the squeezed grains.
    pub kind: GrainKind,
    /// Overlap delta / R each squeeze reaches.
    pub max_overlap: f64,
    /// Run the calibration sweeps.
    pub calibration: bool,
    /// Run the squeeze sweeps.
    pub hertz: bool,
}

impl Default for AccuracyOptions {
    fn default() -> Self {
        Self {
            a_b: 0.0,
            seed: 1,
            dt: 0.1,
            skin: 0.3,
            size: 10.0,
            rate: 1e-5,
            radius: 6.0,
            wall_speed: 5e-4,
            dts: vec![0.025, 0.05, 0.1, 0.15, 0.2],
            skins: vec![0.1, 0.3, 0.6, 1.0],
            sizes: vec![6.0, 8.0, 10.0, 14.0, 20.0],
            rates: vec![1e-4, 3e-5, 1e-5, 3e-6],
            radii: vec![4.0, 6.0, 8.0],
            wall_speeds: vec![2e-3, 1e-3, 5e-4, 2.5e-4, 1.25e-4],
            kind: GrainKind::Smoother,
            max_overlap: 0.25,
            calibration: true,
            hertz: true,
        }
    }
}

/// The overlap window of the squeeze's force comparison (delta / R), as
/// in the Hertz study.
const WINDOW: (f64, f64) = (0.02, 0.25);

impl AccuracyOptions {
    /// Checks every option; the message names the option.
    pub fn validate(&self) -> Result<(), InvalidOption> {
        validate_a_b_values("--a-b", [&self.a_b])?;
        require_positive_up_to("--dt", &[self.dt], 0.3, "tau")?;
        require_positive_up_to("--dts", &self.dts, 0.3, "tau")?;
        require_positive_up_to("--skin", &[self.skin], 3.0, "d")?;
        require_positive_up_to("--skins", &self.skins, 3.0, "d")?;
        require_within("--size", &[self.size], (4.0, 40.0), false, "d")?;
        require_within("--sizes", &self.sizes, (4.0, 40.0), false, "d")?;
        require_positive_up_to("--rate", &[self.rate], 1e-2, "/ tau")?;
        require_positive_up_to("--rates", &self.rates, 1e-2, "/ tau")?;
        require_within("--radius", &[self.radius], (3.0, 20.0), false, "d")?;
        require_within("--radii", &self.radii, (3.0, 20.0), false, "d")?;
        require_positive_up_to("--wall-speed", &[self.wall_speed], 0.05, "d/tau")?;
        require_positive_up_to("--wall-speeds", &self.wall_speeds, 0.05, "d/tau")?;
        if !(self.max_overlap >= 0.1 && self.max_overlap < 0.5) {
            return Err(InvalidOption::new(
                "--max-overlap",
                format!("must be in [0.1, 0.5), got {}", self.max_overlap),
            ));
        }
        Ok(())
    }
}

/// What a sweep changes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Knob {
    /// The timestep (tau).
    Timestep,
    /// Strain rate (calibration) or wall speed (squeeze).
    Loading,
    /// The neighbour skin (d).
    Skin,
    /// Box side L (calibration) or grain radius R (squeeze), d.
    Resolution,
}

impl Knob {
    fn name(self, hertz: bool) -> &'static str {
        match (self, hertz) {
            (Knob::Timestep, _) => "timestep dt (tau)",
            (Knob::Loading, false) => "strain rate (1/tau)",
            (Knob::Loading, true) => "wall speed (d/tau)",
            (Knob::Skin, _) => "skin (d)",
            (Knob::Resolution, false) => "box side L (d)",
            (Knob::Resolution, true) => "grain radius R (d)",
        }
    }
}

/// One run of a sweep. JSON writes NaN (a failed run's figures) as null,
/// and reads null back as NaN.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Case {
    /// What the sweep changes.
    pub knob: Knob,
    /// Its value in this run.
    pub value: f64,
    /// Whether every parameter is at its default.
    pub default: bool,
    /// Particles.
    pub particles: usize,
    /// Steps of the run(s).
    pub steps: u64,
    /// Wall-clock seconds of the run(s) (not the build).
    #[serde(deserialize_with = "crate::json_nan::nan_if_null")]
    pub seconds: f64,
    /// Calibration: K, G and nu. Squeeze: none.
    #[serde(deserialize_with = "moduli_nan_if_null")]
    pub moduli: Option<[f64; 3]>,
    /// Squeeze: the rms relative deviation of the force from Hertz over
    /// the window.
    pub hertz_deviation: Option<f64>,
    /// Relative error of K (calibration) or of the force (squeeze, rms
    /// over the window) against the sweep's reference.
    #[serde(deserialize_with = "crate::json_nan::nan_if_null")]
    pub error: f64,
    /// Calibration: relative error of G.
    pub error_g: Option<f64>,
    /// What the error is measured against.
    pub reference: String,
    /// Why the run did not finish (a blow-up at a large timestep); its
    /// figures are then NaN.
    pub failed: Option<String>,
}

fn moduli_nan_if_null<'de, D: Deserializer<'de>>(d: D) -> Result<Option<[f64; 3]>, D::Error> {
    let values = Option::<[Option<f64>; 3]>::deserialize(d)?;
    Ok(values.map(|m| m.map(|v| v.unwrap_or(f64::NAN))))
}

/// The study's record (`accuracy.json`).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct AccuracyReport {
    /// Program, version and the command that wrote it.
    #[serde(flatten)]
    pub provenance: Provenance,
    /// The options.
    pub options: AccuracyOptions,
    /// The calibration runs.
    pub calibration: Vec<Case>,
    /// The squeezes.
    pub hertz: Vec<Case>,
}

/// Runs the study; `log` receives each line of progress.
pub fn run_accuracy(
    opts: &AccuracyOptions,
    threads: usize,
    command: &str,
    log: &mut dyn FnMut(&str),
) -> Result<AccuracyReport, AccuracyError> {
    opts.validate()?;
    let mut report = AccuracyReport {
        provenance: Provenance::new(command),
        options: opts.clone(),
        calibration: Vec::new(),
        hertz: Vec::new(),
    };
    if opts.calibration {
        report.calibration = calibration_sweeps(opts, threads, log)?;
    }
    if opts.hertz {
        report.hertz = hertz_sweeps(opts, threads, log)?;
    }
    Ok(report)
}

impl Knobs for CalibrationSetting {
    fn set(&mut self, knob: Knob, value: f64) {
        match knob {
            Knob::Timestep => self.dt = value,
            Knob::Loading => self.rate = value,
            Knob::Skin => self.skin = value,
            Knob::Resolution => self.size = value,
        }
    }
}

impl Knobs for SqueezeSetting {
    fn set(&mut self, knob: Knob, value: f64) {
        match knob {
            Knob::Timestep => self.dt = value,
            Knob::Loading => self.speed = value,
            Knob::Skin => self.skin = value,
            Knob::Resolution => self.radius = value,
        }
    }
}

/// A finished calibration: particles, steps, seconds and `[K, G, nu]`.
type CalibrationRun = (usize, u64, f64, [f64; 3]);

/// Settings a sweep can change, one knob at a time.
trait Knobs: Copy + PartialEq {
    fn set(&mut self, knob: Knob, value: f64);
}

/// One sweep: which knob, its values, and the value whose run is the
/// reference (none: an outside reference).
struct Sweep<'a> {
    knob: Knob,
    values: &'a [f64],
    reference: Option<f64>,
}

/// The four sweeps of a study: the shared timestep and skin lists, and
/// the study's own loading and resolution values. Timestep and loading are
/// judged against their most accurate value (the smallest), the skin
/// against the default, resolution against `resolution_reference`.
fn four_sweeps<'a>(
    opts: &'a AccuracyOptions,
    loading: &'a [f64],
    resolution: &'a [f64],
    resolution_reference: Option<f64>,
) -> Vec<Sweep<'a>> {
    vec![
        Sweep {
            knob: Knob::Timestep,
            values: &opts.dts,
            reference: Some(min(&opts.dts)),
        },
        Sweep {
            knob: Knob::Loading,
            values: loading,
            reference: Some(min(loading)),
        },
        Sweep {
            knob: Knob::Skin,
            values: &opts.skins,
            reference: Some(opts.skin),
        },
        Sweep {
            knob: Knob::Resolution,
            values: resolution,
            reference: resolution_reference,
        },
    ]
}

/// A sweep's runs: value, whether every setting is the default, and the
/// outcome (an engine failure as its message).
type SweepRuns<R> = Vec<(f64, bool, Result<R, String>)>;

/// A finished sweep: its knob, its reference value and its runs.
type SweepResult<R> = (Knob, Option<f64>, SweepRuns<R>);

/// Runs every sweep from `default`, each setting once (a setting shared by
/// sweeps, such as the defaults, is reused), the reference value added
/// when a sweep lacks it.
fn run_sweeps<S: Knobs, R: Clone>(
    default: S,
    sweeps: Vec<Sweep<'_>>,
    run: &mut dyn FnMut(S) -> Result<Result<R, String>, AccuracyError>,
) -> Result<Vec<SweepResult<R>>, AccuracyError> {
    let mut done: Vec<(S, Result<R, String>)> = Vec::new();
    let mut out = Vec::new();
    for sweep in sweeps {
        let mut values = sweep.values.to_vec();
        if let Some(r) = sweep.reference {
            if !values.contains(&r) {
                values.push(r);
            }
        }
        let mut runs = Vec::new();
        for v in values {
            let mut s = default;
            s.set(sweep.knob, v);
            let r = match done.iter().find(|(d, _)| *d == s) {
                Some((_, r)) => r.clone(),
                None => {
                    let r = run(s)?;
                    done.push((s, r.clone()));
                    r
                }
            };
            runs.push((v, s == default, r));
        }
        out.push((sweep.knob, sweep.reference, runs));
    }
    Ok(out)
}

/// The finished run of `runs` at `value`.
fn run_at<R: Clone>(runs: &SweepRuns<R>, value: f64) -> Option<R> {
    runs.iter()
        .find(|(v, _, _)| *v == value)
        .and_then(|(_, _, r)| r.clone().ok())
}

/// One calibration run's settings.
#[derive(Clone, Copy, Debug, PartialEq)]
struct CalibrationSetting {
    dt: f64,
    rate: f64,
    skin: f64,
    size: f64,
}

fn calibration_sweeps(
    opts: &AccuracyOptions,
    threads: usize,
    log: &mut dyn FnMut(&str),
) -> Result<Vec<Case>, AccuracyError> {
    let default = CalibrationSetting {
        dt: opts.dt,
        rate: opts.rate,
        skin: opts.skin,
        size: opts.size,
    };
    let mut solids: Vec<(f64, Scene)> = Vec::new();
    let mut solid = |size: f64, log: &mut dyn FnMut(&str)| -> Result<Scene, AccuracyError> {
        if let Some((_, s)) = solids.iter().find(|(l, _)| *l == size) {
            return Ok(s.clone());
        }
        let (s, summary) = paper_solid(size, opts.seed, threads)?;
        log(&format!(
            "calibration: solid L={size} seed {}: {} particles",
            opts.seed, summary.particles
        ));
        solids.push((size, s.clone()));
        Ok(s)
    };
    let mut run = |s: CalibrationSetting,
                   log: &mut dyn FnMut(&str)|
     -> Result<Result<CalibrationRun, String>, AccuracyError> {
        let mut scene = solid(s.size, log)?;
        scene.force_field.skin = s.skin;
        let loading = Loading {
            dt: s.dt,
            rate: s.rate,
            ..Loading::default()
        };
        let tag = format!(
            "accuracy-L{}-dt{}-rate{}-skin{}",
            s.size, s.dt, s.rate, s.skin
        );
        let measured = measure_moduli(
            &scene,
            opts.a_b,
            false,
            &loading,
            &CalibrationEngine::Native(threads),
            &tag,
        );
        let (m, runs) = match measured {
            Ok(measured) => measured,
            // An engine that stopped (a blow-up) is a result of the sweep;
            // anything else is a failure of the study.
            Err(e @ HarnessError::Native { .. }) => {
                log(&format!(
                    "  L={} dt={} rate={} skin={}: failed: {e}",
                    s.size, s.dt, s.rate, s.skin
                ));
                return Ok(Err(e.to_string()));
            }
            Err(e) => return Err(e.into()),
        };
        let steps: u64 = runs
            .iter()
            .map(|r| r.stages.iter().map(|st| st.steps).sum::<u64>())
            .sum();
        let particles = scene.particles.positions.len();
        log(&format!(
            "  L={} dt={} rate={} skin={}: K = {:.5}, G = {:.5}, nu = {:.4}, {} particles x {steps} steps, {:.1} s",
            s.size, s.dt, s.rate, s.skin, m.k, m.g, m.nu, particles, m.seconds
        ));
        Ok(Ok((particles, steps, m.seconds, [m.k, m.g, m.nu])))
    };
    let sweeps = four_sweeps(opts, &opts.rates, &opts.sizes, Some(max(&opts.sizes)));
    let mut cases = Vec::new();
    for (knob, reference, runs) in run_sweeps(default, sweeps, &mut |s| run(s, log))? {
        let reference = reference.expect("every calibration sweep has a reference run");
        let m_ref = run_at(&runs, reference).map(|r| r.3);
        let what = match knob {
            Knob::Resolution => format!("the largest box, L = {reference}"),
            Knob::Skin => format!("the default skin {reference} (bonded solid: no pair in reach)"),
            _ => format!("{} = {reference}", knob.name(false)),
        };
        let what = if m_ref.is_some() {
            what
        } else {
            format!("{what}, which failed: no errors")
        };
        let m_ref = m_ref.unwrap_or([f64::NAN; 3]);
        for (v, is_default, r) in runs {
            let ((particles, steps, seconds, m), failed) = match r {
                Ok(r) => (r, None),
                Err(e) => ((0, 0, f64::NAN, [f64::NAN; 3]), Some(e)),
            };
            cases.push(Case {
                knob,
                value: v,
                default: is_default,
                particles,
                steps,
                seconds,
                moduli: Some(m),
                hertz_deviation: None,
                error: (m[0] / m_ref[0] - 1.0).abs(),
                error_g: Some((m[1] / m_ref[1] - 1.0).abs()),
                reference: what.clone(),
                failed,
            });
        }
    }
    Ok(cases)
}

/// One squeeze's settings.
#[derive(Clone, Copy, Debug, PartialEq)]
struct SqueezeSetting {
    dt: f64,
    speed: f64,
    skin: f64,
    radius: f64,
}

/// A squeeze's curve: `delta / R` and the normalised force from first
/// contact on, with the run's size and cost.
#[derive(Clone, Debug)]
struct SqueezeRun {
    overlap: Vec<f64>,
    force: Vec<f64>,
    particles: usize,
    steps: u64,
    seconds: f64,
    hertz: f64,
}

impl SqueezeRun {
    /// A squeeze that did not finish: no curve, NaN figures.
    fn failed() -> Self {
        Self {
            overlap: Vec::new(),
            force: Vec::new(),
            particles: 0,
            steps: 0,
            seconds: f64::NAN,
            hertz: f64::NAN,
        }
    }
}

fn hertz_sweeps(
    opts: &AccuracyOptions,
    threads: usize,
    log: &mut dyn FnMut(&str),
) -> Result<Vec<Case>, AccuracyError> {
    let moduli = Moduli::paper_fits(opts.a_b);
    let e_eff = effective_modulus(moduli.k, moduli.nu);
    let default = SqueezeSetting {
        dt: opts.dt,
        speed: opts.wall_speed,
        skin: opts.skin,
        radius: opts.radius,
    };
    let mut grains: Vec<(f64, Scene)> = Vec::new();
    let mut grain = |radius: f64, log: &mut dyn FnMut(&str)| -> Result<Scene, AccuracyError> {
        if let Some((_, g)) = grains.iter().find(|(r, _)| *r == radius) {
            return Ok(g.clone());
        }
        let p = GrainParams::new(opts.kind, radius, opts.seed, opts.a_b);
        let (g, summary) = built_grain(&p, threads)?;
        log(&format!(
            "squeeze: {} grain R={radius} seed {}: {} particles",
            opts.kind.name(),
            opts.seed,
            summary.particles
        ));
        grains.push((radius, g.clone()));
        Ok(g)
    };
    let mut run = |s: SqueezeSetting,
                   log: &mut dyn FnMut(&str)|
     -> Result<Result<SqueezeRun, String>, AccuracyError> {
        let mut g = grain(s.radius, log)?;
        g.force_field = ForceField {
            skin: s.skin,
            ..ForceField::paper(opts.a_b)
        };
        let mut params = SqueezeParams::paper(s.radius, opts.max_overlap);
        params.dt = s.dt;
        params.wall_speed = s.speed;
        let scene = hertz_squeeze(&g, &params);
        let steps = scene.stages[0].steps;
        let tag = format!(
            "accuracy-R{}-dt{}-v{}-skin{}",
            s.radius, s.dt, s.speed, s.skin
        );
        let t = std::time::Instant::now();
        let squeezed = squeeze_native(
            &scene,
            &tag,
            &crate::studies::StudyRuntime::plain(threads, false),
            &tag,
        );
        let seconds = t.elapsed().as_secs_f64();
        let stage = match squeezed {
            Ok((stage, None)) => stage,
            Ok((_, Some(why)))
            | Err(HertzError::Run(HarnessError::Native { message: why, .. })) => {
                log(&format!(
                    "  R={} dt={} wall speed={} skin={}: failed: {why}",
                    s.radius, s.dt, s.speed, s.skin
                ));
                return Ok(Err(why));
            }
            Err(e) => return Err(e.into()),
        };
        let (gap, force) = gap_and_force(&stage);
        let curve = squeeze_curve(&gap, &force, s.radius, e_eff);
        let hertz = hertz_deviation(
            &curve.overlap_over_r,
            &curve.normalised_force,
            WINDOW.0,
            WINDOW.1,
        )
        .map_or(f64::NAN, |d| d.rms_relative);
        let particles = g.particles.positions.len();
        log(&format!(
            "  R={} dt={} wall speed={} skin={}: {:.2}% from Hertz, {} particles x {steps} steps, {seconds:.1} s",
            s.radius, s.dt, s.speed, s.skin, 100.0 * hertz, particles
        ));
        Ok(Ok(SqueezeRun {
            overlap: curve.overlap_over_r,
            force: curve.normalised_force,
            particles,
            steps,
            seconds,
            hertz,
        }))
    };
    // Resolution against Hertz's law, not against a run.
    let sweeps = four_sweeps(opts, &opts.wall_speeds, &opts.radii, None);
    let mut cases = Vec::new();
    for (knob, reference, runs) in run_sweeps(default, sweeps, &mut |s| run(s, log))? {
        let reference_run = reference.map(|value| run_at(&runs, value));
        for (v, is_default, r) in runs {
            let (r, failed) = match r {
                Ok(r) => (r, None),
                Err(e) => (SqueezeRun::failed(), Some(e)),
            };
            let (error, what) = match (&reference_run, reference) {
                (Some(reference_run), Some(value)) => (
                    reference_run.as_ref().map_or(f64::NAN, |reference_run| {
                        curve_difference(&r, reference_run)
                    }),
                    match (knob, reference_run.is_some()) {
                        (_, false) => {
                            format!("{} = {value}, which failed: no errors", knob.name(true))
                        }
                        (Knob::Skin, true) => format!("the default skin {value}"),
                        (_, true) => format!("{} = {value}", knob.name(true)),
                    },
                ),
                _ => (r.hertz, "Hertz's law".into()),
            };
            cases.push(Case {
                knob,
                value: v,
                default: is_default,
                particles: r.particles,
                steps: r.steps,
                seconds: r.seconds,
                moduli: None,
                hertz_deviation: Some(r.hertz),
                error,
                error_g: None,
                reference: what,
                failed,
            });
        }
    }
    Ok(cases)
}

/// Rms relative difference of `run`'s force from `reference`'s over the
/// window, `run` interpolated linearly at the reference's overlaps.
fn curve_difference(run: &SqueezeRun, reference: &SqueezeRun) -> f64 {
    let diffs: Vec<f64> = reference
        .overlap
        .iter()
        .zip(&reference.force)
        .filter(|(d, f)| (WINDOW.0..=WINDOW.1).contains(*d) && **f > 0.0)
        .filter_map(|(&d, &f)| interpolate(&run.overlap, &run.force, d).map(|g| g / f - 1.0))
        .collect();
    if diffs.is_empty() {
        return f64::NAN;
    }
    (diffs.iter().map(|d| d * d).sum::<f64>() / diffs.len() as f64).sqrt()
}

fn min(values: &[f64]) -> f64 {
    values.iter().copied().fold(f64::INFINITY, f64::min)
}

fn max(values: &[f64]) -> f64 {
    values.iter().copied().fold(f64::NEG_INFINITY, f64::max)
}

/// Writes `DIR/accuracy.json` and `DIR/accuracy.svg` (error against
/// seconds, one panel per sweep, the defaults ringed).
pub fn write_report(report: &AccuracyReport, dir: &Path) -> Result<(), AccuracyError> {
    output::write_report(report, dir)?;
    Ok(())
}

impl StudyReport for AccuracyReport {
    const JSON: &'static str = "accuracy.json";

    fn check(&self) -> Result<(), String> {
        self.options.validate().map_err(|e| e.to_string())
    }

    /// `accuracy.svg`: error against seconds, one panel per sweep, the
    /// defaults ringed.
    fn draw(&self, out: &StudyOutput) -> Result<(), OutputError> {
        let report = self;
        let mut panels = Vec::new();
        for (hertz, cases) in [(false, &report.calibration), (true, &report.hertz)] {
            for knob in [Knob::Timestep, Knob::Loading, Knob::Skin, Knob::Resolution] {
                let sweep: Vec<&Case> = cases.iter().filter(|c| c.knob == knob).collect();
                if sweep.is_empty() {
                    continue;
                }
                // A sweep that changes no result (the skin: it only changes
                // which pairs are listed) has nothing to draw on a log scale of
                // error; its cost against the value says what it does.
                let exact = sweep
                    .iter()
                    .all(|c| c.error == 0.0 && c.error_g.unwrap_or(0.0) == 0.0);
                if exact {
                    panels.push(Panel {
                        title: format!(
                            "{}: {} changes no result (every error 0): cost only",
                            if hertz {
                                "Hertz squeeze"
                            } else {
                                "calibration"
                            },
                            knob.name(hertz)
                        ),
                        x_label: knob.name(hertz).into(),
                        y_label: "wall-clock seconds".into(),
                        series: vec![Series::new(
                            "seconds",
                            sweep
                                .iter()
                                .map(|c| (c.value, c.seconds))
                                .filter(|(_, y)| y.is_finite())
                                .collect(),
                            Mark::LinePoints,
                        )],
                        ..Panel::default()
                    });
                    continue;
                }
                let mut panel = Panel {
                    title: format!(
                        "{}: {} (against {}; the reference, error 0, not drawn)",
                        if hertz {
                            "Hertz squeeze force"
                        } else {
                            "calibration"
                        },
                        knob.name(hertz),
                        sweep[0].reference
                    ),
                    x_label: "wall-clock seconds".into(),
                    y_label: "relative error".into(),
                    log_x: true,
                    log_y: true,
                    ..Panel::default()
                };
                let points = |f: &dyn Fn(&Case) -> Option<f64>| -> Vec<(f64, f64)> {
                    sweep
                        .iter()
                        .filter_map(|c| f(c).map(|e| (c.seconds, e)))
                        .filter(|(x, y)| x.is_finite() && y.is_finite())
                        .collect()
                };
                let label = |what: &str| {
                    let values: Vec<String> =
                        sweep.iter().map(|c| format!("{}", c.value)).collect();
                    format!("{what}, {} = {}", knob.name(hertz), values.join(", "))
                };
                if hertz {
                    panel.series.push(Series::new(
                        label("force"),
                        points(&|c| Some(c.error)),
                        Mark::LinePoints,
                    ));
                } else {
                    panel.series.push(Series::new(
                        label("K"),
                        points(&|c| Some(c.error)),
                        Mark::LinePoints,
                    ));
                    panel.series.push(Series::new(
                        label("G"),
                        points(&|c| c.error_g),
                        Mark::LinePoints,
                    ));
                }
                let defaults: Vec<(f64, f64)> = sweep
                    .iter()
                    .filter(|c| c.default)
                    .flat_map(|c| {
                        [Some(c.error), c.error_g]
                            .into_iter()
                            .flatten()
                            .map(|e| (c.seconds, e))
                    })
                    .filter(|(x, y)| x.is_finite() && y.is_finite())
                    .collect();
                panel
                    .series
                    .push(Series::new("default", defaults, Mark::Rings));
                panels.push(panel);
            }
        }
        out.svg("accuracy.svg", &panels)?;
        Ok(())
    }
}

/// Rewrites `DIR/accuracy.svg` (and the JSON) from an earlier
/// `accuracy.json` without running anything.
pub fn replot(json: &Path, dir: &Path) -> Result<AccuracyReport, AccuracyError> {
    Ok(output::replot(json, dir)?)
}

/// The report as a table, one line per run.
pub fn table(report: &AccuracyReport) -> String {
    let mut out = String::new();
    for (name, hertz, cases) in [
        ("calibration (K, G)", false, &report.calibration),
        ("Hertz squeeze force", true, &report.hertz),
    ] {
        if cases.is_empty() {
            continue;
        }
        out.push_str(&format!(
            "\n{name}\n{:<22} {:>9} {:>8} {:>9} {:>12} {:>9} {:>11} {:>11}  reference\n",
            "sweep", "value", "default", "particles", "steps", "seconds", "error", "error G/Hz"
        ));
        for c in cases {
            let second = if hertz { c.hertz_deviation } else { c.error_g };
            out.push_str(&format!(
                "{:<22} {:>9} {:>8} {:>9} {:>12} {:>9.2} {:>11.3e} {:>11.3e}  {}\n",
                c.knob.name(hertz),
                c.value,
                if c.default { "yes" } else { "" },
                c.particles,
                c.steps,
                c.seconds,
                c.error,
                second.unwrap_or(f64::NAN),
                match &c.failed {
                    Some(why) => format!("FAILED: {}", why.lines().next().unwrap_or_default()),
                    None => c.reference.clone(),
                }
            ));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_curve_ten_percent_higher_differs_by_ten_percent() {
        let overlap: Vec<f64> = (0..100).map(|k| k as f64 * 0.003).collect();
        let force: Vec<f64> = overlap.iter().map(|d: &f64| d.powf(1.5)).collect();
        let run = |scale: f64| SqueezeRun {
            overlap: overlap.clone(),
            force: force.iter().map(|f| f * scale).collect(),
            particles: 1,
            steps: 1,
            seconds: 0.0,
            hertz: 0.0,
        };
        let d = curve_difference(&run(1.1), &run(1.0));
        assert!((d - 0.1).abs() < 1e-12, "{d}");
        assert_eq!(curve_difference(&run(1.0), &run(1.0)), 0.0);
    }

    #[test]
    fn sweeps_add_their_reference_and_run_each_setting_once() {
        let opts = AccuracyOptions {
            dts: vec![0.1, 0.2],
            skins: vec![0.3],
            rates: vec![1e-4],
            sizes: vec![10.0],
            ..AccuracyOptions::default()
        };
        let default = CalibrationSetting {
            dt: 0.1,
            rate: 1e-5,
            skin: 0.3,
            size: 10.0,
        };
        let mut calls = Vec::new();
        let sweeps = four_sweeps(&opts, &opts.rates, &opts.sizes, Some(10.0));
        let out = run_sweeps(default, sweeps, &mut |s: CalibrationSetting| {
            calls.push(s);
            Ok(if s.dt > 0.15 {
                Err("blew up".to_string())
            } else {
                Ok(s.dt)
            })
        })
        .unwrap();
        // The default runs once although three sweeps hold it; the rate
        // sweep gains no reference (1e-4 is its own smallest value).
        assert_eq!(calls.len(), 3, "{calls:?}");
        let (knob, reference, runs) = &out[0];
        assert_eq!((*knob, *reference), (Knob::Timestep, Some(0.1)));
        assert_eq!(runs.len(), 2);
        assert!(runs[0].1 && !runs[1].1, "only dt = 0.1 is the default");
        assert_eq!(runs[1].2, Err("blew up".to_string()));
        assert_eq!(run_at(runs, 0.1), Some(0.1));
        assert_eq!(run_at(runs, 0.2), None);
        // The skin sweep's reference is the default, already run.
        assert_eq!(out[2].2.len(), 1);
    }

    #[test]
    fn a_failed_run_reads_back_with_nan_figures() {
        let failed = Case {
            knob: Knob::Timestep,
            value: 0.2,
            default: false,
            particles: 0,
            steps: 0,
            seconds: f64::NAN,
            moduli: Some([f64::NAN; 3]),
            hertz_deviation: None,
            error: f64::NAN,
            error_g: Some(f64::NAN),
            reference: "dt = 0.025".into(),
            failed: Some("blew up".into()),
        };
        let text = serde_json::to_string(&failed).unwrap();
        let back: Case = serde_json::from_str(&text).unwrap();
        assert!(back.seconds.is_nan() && back.error.is_nan());
        assert!(back.moduli.unwrap().iter().all(|m| m.is_nan()));
        assert_eq!(back.error_g, None, "null reads as no value");
        assert_eq!(back.failed.as_deref(), Some("blew up"));
    }

    #[test]
    fn every_list_option_is_checked_by_name() {
        let mut o = AccuracyOptions {
            dts: vec![0.1, 0.5],
            ..AccuracyOptions::default()
        };
        assert!(o.validate().unwrap_err().to_string().contains("--dts"));
        o.dts = vec![0.1];
        o.radii = vec![];
        assert!(o.validate().unwrap_err().to_string().contains("--radii"));
        assert!(AccuracyOptions::default().validate().is_ok());
    }
}
