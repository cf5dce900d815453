//! Calibration of the multi-contact closures against resolved grains
//! (docs/protocols.md, "Calibrating the closures against bonded grains"):
//! the packing of a bonded-grain compaction study (`bpm compact`) is
//! compressed again as DEM spheres, one per grain at the grain's template
//! centre, with plain Hertz contacts and with the standard and advanced
//! closures over a grid of prefactors `gamma` and maximum penetration
//! ratios `MPR`; each variant's pressure is compared with the grains' at
//! the same distance from jamming, `phi_MC - phi_c` (each packing at its
//! own `phi_c`), and at the same `phi_MC`.
//!
//! A closure acts only on overlapping spheres, so it cannot move the
//! jamming point: where the spheres jam at a different `phi_c` from the
//! grains, no closure can match the grains' pressure at the same
//! `phi_MC` near jamming. The fit is therefore made in `phi_MC - phi_c`;
//! the ratios at the same `phi_MC` are reported beside it.
//!
//! Every variant is an ordinary compaction study in its own folder; a
//! folder whose `compaction.json` already holds the same options is reused,
//! so an interrupted calibration resumes where it stopped.

use crate::analysis::plot::{Mark, Panel, Series};
use crate::engine::dem::MultiContact;
use crate::file_error::FileError;
use crate::options::InvalidOption;
use crate::studies::compaction::compare::{mean_at_distance, pressure_ratio};
use crate::studies::compaction::{
    read_report, run_compaction, CompactOptions, CompactionEngine, CompactionError,
    CompactionReport, DemContact, ModuliOptions, PackingSource,
};
use crate::studies::output::{self, OutputError, StudyOutput, StudyReport};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// What `bpm mc-calibrate` runs.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct CalibrationOptions {
    /// Bonded-grain compaction studies (folders of `bpm compact`), each
    /// calibrated on its own.
    pub grains: Vec<PathBuf>,
    /// The spheres' friction `{mu_s, mu_r, mu_t}`.
    pub friction: [f64; 3],
    /// Prefactors of the standard closure.
    pub gammas: Vec<f64>,
    /// Prefactors of the advanced closure.
    pub advanced_gammas: Vec<f64>,
    /// Maximum penetration ratios of the advanced closure (every pair
    /// with `advanced_gammas`).
    pub mprs: Vec<f64>,
    /// The closures' reach (fraction of the two radii).
    pub reach: f64,
    /// Volumetric strain of the box after jamming at which the spheres
    /// stop (the grains' studies may go further).
    pub volumetric_strain: f64,
    /// `[lo, hi]` of `phi_MC - phi_c` over which the fit's error is taken.
    pub window: [f64; 2],
}

impl Default for CalibrationOptions {
    fn default() -> Self {
        Self {
            grains: Vec::new(),
            friction: [0.15, 0.0, 0.0],
            gammas: vec![0.5, 0.82, 1.0, 1.1, 1.25, 1.5, 2.0],
            advanced_gammas: vec![0.81, 1.25, 2.0],
            mprs: vec![0.05, 0.11],
            reach: 0.2,
            volumetric_strain: 0.48,
            window: [0.1, 0.3],
        }
    }
}

/// Distances from jamming at which the ratios are tabulated; the fit uses
/// those inside the window.
pub const DISTANCES: [f64; 9] = [0.01, 0.02, 0.03, 0.05, 0.1, 0.15, 0.2, 0.25, 0.3];

/// Volume fractions at which the ratios at the same `phi_MC` are
/// tabulated.
pub const FRACTIONS: [f64; 7] = [0.65, 0.7, 0.75, 0.8, 0.85, 0.9, 0.95];

/// A contact law in the grid.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Law {
    /// Plain Hertz.
    Hertz,
    /// The standard closure.
    Standard {
        /// Prefactor.
        gamma: f64,
    },
    /// The advanced closure.
    Advanced {
        /// Prefactor.
        gamma: f64,
        /// Maximum penetration ratio.
        mpr: f64,
    },
}

impl Law {
    /// Folder name of its study.
    pub fn folder(&self) -> String {
        match self {
            Law::Hertz => "hertz".into(),
            Law::Standard { gamma } => format!("standard-{gamma}"),
            Law::Advanced { gamma, mpr } => format!("advanced-{gamma}-{mpr}"),
        }
    }

    /// The closure with `reach`.
    fn multicontact(&self, reach: f64) -> Option<MultiContact> {
        let m = match *self {
            Law::Hertz => return None,
            Law::Standard { gamma } => MultiContact::standard(gamma),
            Law::Advanced { gamma, mpr } => MultiContact::advanced(gamma, mpr),
        };
        Some(MultiContact { reach, ..m })
    }
}

/// One variant against the grains.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct VariantFit {
    /// The contact law.
    pub law: Law,
    /// Its study's folder.
    pub folder: PathBuf,
    /// The `phi_c` the spheres are measured from: plain Hertz's (mean
    /// over runs).
    pub phi_c: Option<f64>,
    /// The spheres' own fitted `phi_c` (mean over runs), to show that the
    /// closure hardly moves it.
    pub own_phi_c: Option<f64>,
    /// Why a run of the spheres stopped early, if one did (the first).
    pub stopped: Option<String>,
    /// `P / P(grains)` at each of [`DISTANCES`].
    pub ratio_at_distance: Vec<Option<f64>>,
    /// `P / P(grains)` at each of [`FRACTIONS`] of `phi_MC`.
    pub ratio_at_fraction: Vec<Option<f64>>,
    /// Root mean square of `ln(P / P(grains))` over the distances inside
    /// the window (`None` if the spheres do not reach all of them).
    pub rms_log_error: Option<f64>,
    /// The longest run of consecutive [`DISTANCES`] at which the
    /// pressure is within 10% of the grains' (first and last distance).
    pub within_10_percent: Option<[f64; 2]>,
    /// `(phi_MC - phi_c, P / E_eff)` of the compression states.
    pub curve: Vec<(f64, f64)>,
}

/// The calibration of one grain study.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct GrainCalibration {
    /// The grains' study folder.
    pub grains: PathBuf,
    /// Its label (the folder's name).
    pub label: String,
    /// The grains' Poisson ratio (solid's calibration at their `a_B`).
    pub nu: f64,
    /// The grains' `a_B`.
    pub a_b: f64,
    /// The grains' `phi_c` (mean over runs).
    pub phi_c: Option<f64>,
    /// `(phi_MC - phi_c, P / E_eff)` of the grains' compression states.
    pub curve: Vec<(f64, f64)>,
    /// Every variant, Hertz first.
    pub variants: Vec<VariantFit>,
    /// The standard closure's best prefactor on the grid, and the minimum
    /// of a parabola through it and its neighbours (in `gamma`, of the rms
    /// error) when it is interior.
    pub best_standard: Option<BestFit>,
    /// The advanced closure's best grid point.
    pub best_advanced: Option<BestFit>,
}

/// A best fit.
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
pub struct BestFit {
    /// The grid's best law.
    pub law: Law,
    /// Its rms error of `ln P`.
    pub rms_log_error: f64,
    /// The parabola's minimum in `gamma` (standard closure only), when the
    /// best grid point has neighbours on both sides.
    pub refined_gamma: Option<f64>,
}

/// The calibration's record: `calibration.json`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct CalibrationReport {
    /// This program's version.
    pub version: String,
    /// The command that wrote it.
    pub command: String,
    /// The options.
    pub options: CalibrationOptions,
    /// Threads: the spheres' packings are the grains' only with the grain
    /// studies' thread count.
    pub threads: usize,
    /// What the reader should know (e.g. a grain study that did not record
    /// its thread count).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    /// One calibration per grain study.
    pub studies: Vec<GrainCalibration>,
}

impl CalibrationOptions {
    /// Checks the values; the error names the option at fault.
    pub fn validate(&self) -> Result<(), InvalidOption> {
        if self.grains.is_empty() {
            return Err(InvalidOption::new(
                "GRAINS",
                "give at least one grain study folder",
            ));
        }
        DemContact {
            friction: self.friction,
            ..DemContact::default()
        }
        .validate()?;
        let grid = self
            .gammas
            .iter()
            .map(|g| ("--gammas", *g))
            .chain(
                self.advanced_gammas
                    .iter()
                    .map(|g| ("--advanced-gammas", *g)),
            )
            .chain(self.mprs.iter().map(|m| ("--mprs", *m)));
        for (name, v) in grid {
            if !(v.is_finite() && v > 0.0) {
                return Err(InvalidOption::new(
                    name,
                    format!("every value must be finite and > 0, got {v}"),
                ));
            }
        }
        if self.advanced_gammas.is_empty() != self.mprs.is_empty() {
            return Err(InvalidOption::new(
                "--mprs",
                "goes with --advanced-gammas: give both or neither",
            ));
        }
        if !(self.reach.is_finite() && self.reach > 0.0) {
            return Err(InvalidOption::new(
                "--reach",
                format!("must be finite and > 0, got {}", self.reach),
            ));
        }
        let v = self.volumetric_strain;
        if !(v > 0.0 && v < 1.0) {
            return Err(InvalidOption::new(
                "--volumetric-strain",
                format!("must be in (0, 1), got {v}"),
            ));
        }
        for (name, grid) in [
            ("--gammas", &self.gammas),
            ("--advanced-gammas", &self.advanced_gammas),
            ("--mprs", &self.mprs),
        ] {
            let mut sorted = grid.clone();
            sorted.sort_by(f64::total_cmp);
            if sorted.windows(2).any(|w| w[0] == w[1]) {
                return Err(InvalidOption::new(
                    name,
                    format!("repeats a value: {grid:?}"),
                ));
            }
        }
        let [lo, hi] = self.window;
        let inside = DISTANCES.iter().filter(|&&x| self.in_window(x)).count();
        if !(lo > 0.0 && hi > lo && hi.is_finite()) || inside < 2 {
            return Err(InvalidOption::new(
                "--window",
                format!(
                    "must be two distances lo < hi holding at least two of {DISTANCES:?}, got {lo},{hi}"
                ),
            ));
        }
        Ok(())
    }

    /// Whether the fit counts the distance `x` (`phi_MC - phi_c`).
    fn in_window(&self, x: f64) -> bool {
        let [lo, hi] = self.window;
        x >= lo * (1.0 - 1e-12) && x <= hi * (1.0 + 1e-12)
    }

    /// Hertz, then the standard grid, then the advanced grid.
    pub fn laws(&self) -> Vec<Law> {
        let mut laws = vec![Law::Hertz];
        laws.extend(self.gammas.iter().map(|&gamma| Law::Standard { gamma }));
        for &gamma in &self.advanced_gammas {
            laws.extend(self.mprs.iter().map(|&mpr| Law::Advanced { gamma, mpr }));
        }
        laws
    }

    /// The spheres' compaction of the grains' packing under `law`.
    fn sphere_options(&self, grains: &CompactionReport, law: Law) -> CompactOptions {
        let g = &grains.options;
        CompactOptions {
            source: g.source.clone(),
            a_b: g.a_b,
            zero_net: false,
            seeds: g.seeds.clone(),
            protocol: crate::scene::protocols::CompactionProtocol {
                volumetric_strain: self.volumetric_strain,
                ..g.protocol.clone()
            },
            engine: CompactionEngine::Native,
            analysis: g.analysis.clone(),
            moduli: ModuliOptions {
                states: 0,
                ..g.moduli.clone()
            },
            dem: Some(DemContact {
                friction: self.friction,
                multicontact: law.multicontact(self.reach),
                ..DemContact::default()
            }),
            bond_failure: None,
            overlay_pair: false,
        }
    }
}

/// The study of `opts` in `dir`: the one recorded there if it ran with the
/// same options and threads and holds every seed (an interrupted study
/// holds fewer), else a new run.
fn study_in(
    opts: &CompactOptions,
    dir: &Path,
    runtime: &crate::studies::StudyRuntime,
    command: &str,
    print: &mut dyn FnMut(&str),
) -> Result<CompactionReport, CompactionError> {
    let threads = runtime.threads;
    if dir.join("compaction.json").exists() {
        match read_report(dir) {
            Ok(done) => {
                let same_options =
                    serde_json::to_value(&done.options).ok() == serde_json::to_value(opts).ok();
                let seeds: Vec<u64> = done.runs.iter().map(|r| r.seed).collect();
                let complete = seeds == opts.seeds;
                let same_threads = done.threads.is_none_or(|t| t == threads);
                if same_options && complete && same_threads {
                    print(&format!("{}: done before, reused", dir.display()));
                    return Ok(done);
                }
                let why = if !same_options {
                    "with other options"
                } else if !complete {
                    "incomplete"
                } else {
                    "with another thread count"
                };
                print(&format!("{}: recorded {why}, run again", dir.display()));
            }
            Err(e) => print(&format!("{}: unreadable ({e}), run again", dir.display())),
        }
    }
    run_compaction(opts, runtime, None, dir, command, print)
}

/// A grain study checked before any sphere runs: bonded grains from a
/// built packing (the spheres rebuild its template), jamming fitted in
/// every run, the same thread count if it recorded one.
fn grain_study(dir: &Path, threads: usize) -> Result<CompactionReport, CompactionError> {
    let grains = read_report(dir)?;
    let refuse = |why: String| {
        CompactionError::Invalid(InvalidOption::new(
            "GRAINS",
            format!("{}: {why}", dir.display()),
        ))
    };
    if grains.options.dem.is_some() {
        return Err(refuse(
            "a study of DEM spheres; give studies of bonded grains".into(),
        ));
    }
    if !matches!(grains.options.source, PackingSource::Build { .. }) {
        return Err(refuse(
            "its packing was read from a file; the spheres are placed at the template centres of a packing built by `bpm compact`".into(),
        ));
    }
    if let Some(run) = grains.runs.iter().find(|r| r.fits.pressure.is_none()) {
        return Err(refuse(format!(
            "seed {}: jamming point not fitted, so there is no distance from jamming to compare at",
            run.seed
        )));
    }
    if grains.runs.is_empty() {
        return Err(refuse("holds no run".into()));
    }
    if let Some(t) = grains.threads.filter(|&t| t != threads) {
        return Err(CompactionError::Invalid(InvalidOption::new(
            "--threads",
            format!(
                "{} ran with {t} threads, and its packing is rebuilt bit for bit only with the same count",
                dir.display()
            ),
        )));
    }
    Ok(grains)
}

/// `spheres` measured from the jamming points of `hertz` (seed by seed):
/// a closure does not move jamming, while a fit of `phi_c` together with
/// the exponent would turn part of its stiffening into a shift.
fn from_hertz_jamming(spheres: &CompactionReport, hertz: &CompactionReport) -> CompactionReport {
    let mut shifted = spheres.clone();
    for run in &mut shifted.runs {
        let hertz_phi_c = hertz
            .runs
            .iter()
            .find(|h| h.seed == run.seed)
            .and_then(|h| h.fits.pressure.map(|p| p.phi_c));
        if let (Some(fit), Some(phi_c)) = (&mut run.fits.pressure, hertz_phi_c) {
            fit.phi_c = phi_c;
        }
    }
    shifted
}

/// The mean over runs of their fitted `phi_c`.
fn mean_phi_c(report: &CompactionReport) -> Option<f64> {
    let phi: Vec<f64> = report
        .runs
        .iter()
        .filter_map(|r| r.fits.pressure.map(|p| p.phi_c))
        .collect();
    (!phi.is_empty()).then(|| phi.iter().sum::<f64>() / phi.len() as f64)
}

/// `(phi_MC - phi_c, P / E_eff)` of every run's compression states, each
/// run from its own `phi_c`.
fn curve_of(report: &CompactionReport) -> Vec<(f64, f64)> {
    report
        .runs
        .iter()
        .filter_map(|run| Some((run, run.fits.pressure?.phi_c)))
        .flat_map(|(run, phi_c)| {
            run.states
                .iter()
                .filter(|s| s.stage.starts_with("compress"))
                .map(move |s| (s.packing.phi_mc - phi_c, s.p_over_e_eff))
        })
        .filter(|&(x, p)| x > 0.0 && p > 0.0)
        .collect()
}

/// `ln(P / P(grains))` of `spheres` at each of `distances`.
fn log_errors(
    grains: &CompactionReport,
    spheres: &CompactionReport,
    at: &[f64],
) -> Vec<Option<f64>> {
    let p = |r: &CompactionReport, x| mean_at_distance(r, x, |s| s.p_over_e_eff);
    at.iter()
        .map(|&x| Some((p(spheres, x)? / p(grains, x)?).ln()))
        .collect()
}

/// The longest run of consecutive entries of `errors` (`ln` ratios)
/// within 10%, as index bounds.
fn longest_within_10_percent(errors: &[Option<f64>]) -> Option<(usize, usize)> {
    let within = |e: &Option<f64>| e.is_some_and(|e| e.abs() <= 1.1f64.ln());
    let mut longest: Option<(usize, usize)> = None;
    let mut start = None;
    for (k, e) in errors.iter().enumerate() {
        if !within(e) {
            start = None;
            continue;
        }
        let first = *start.get_or_insert(k);
        if longest.is_none_or(|(a, b)| k - first > b - a) {
            longest = Some((first, k));
        }
    }
    longest
}

/// The fit of one variant, `spheres` measured from `hertz`'s jamming.
fn fit_variant(
    opts: &CalibrationOptions,
    grains: &CompactionReport,
    law: Law,
    folder: PathBuf,
    spheres: &CompactionReport,
    hertz: &CompactionReport,
) -> VariantFit {
    let measured = from_hertz_jamming(spheres, hertz);
    let errors = log_errors(grains, &measured, &DISTANCES);
    let inside: Vec<Option<f64>> = DISTANCES
        .iter()
        .zip(&errors)
        .filter(|(x, _)| opts.in_window(**x))
        .map(|(_, e)| *e)
        .collect();
    let rms_log_error = inside
        .iter()
        .copied()
        .collect::<Option<Vec<f64>>>()
        .filter(|e| !e.is_empty())
        .map(|e| (e.iter().map(|v| v * v).sum::<f64>() / e.len() as f64).sqrt());
    VariantFit {
        law,
        folder,
        phi_c: mean_phi_c(&measured),
        own_phi_c: mean_phi_c(spheres),
        stopped: spheres.runs.iter().find_map(|r| r.stopped.clone()),
        ratio_at_distance: errors.iter().map(|e| e.map(f64::exp)).collect(),
        ratio_at_fraction: FRACTIONS
            .iter()
            .map(|&phi| pressure_ratio(grains, spheres, phi))
            .collect(),
        rms_log_error,
        within_10_percent: longest_within_10_percent(&errors)
            .map(|(a, b)| [DISTANCES[a], DISTANCES[b]]),
        curve: curve_of(&measured),
    }
}

/// The minimum of the parabola through three points, if it opens upwards.
fn parabola_minimum([(x0, y0), (x1, y1), (x2, y2)]: [(f64, f64); 3]) -> Option<f64> {
    let d01 = (y1 - y0) / (x1 - x0);
    let d12 = (y2 - y1) / (x2 - x1);
    let curvature = (d12 - d01) / (x2 - x0);
    if curvature <= 0.0 {
        return None;
    }
    // y = y1 + d(x - x1) + c (x - x1)^2 near x1, with d the slope at x1.
    let slope_at_x1 = d01 + curvature * (x1 - x0);
    Some(x1 - slope_at_x1 / (2.0 * curvature))
}

/// The best standard and advanced laws of a study's variants.
fn best_fits(variants: &[VariantFit]) -> (Option<BestFit>, Option<BestFit>) {
    let scored = |keep: fn(&Law) -> bool| -> Vec<(Law, f64)> {
        variants
            .iter()
            .filter(|v| keep(&v.law))
            .filter_map(|v| Some((v.law, v.rms_log_error?)))
            .collect()
    };
    let best = |list: &[(Law, f64)]| {
        list.iter()
            .copied()
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(law, rms)| BestFit {
                law,
                rms_log_error: rms,
                refined_gamma: None,
            })
    };
    let mut standard: Vec<(Law, f64)> = scored(|l| matches!(l, Law::Standard { .. }));
    let gamma = |l: &Law| match l {
        Law::Standard { gamma } | Law::Advanced { gamma, .. } => *gamma,
        Law::Hertz => 0.0,
    };
    standard.sort_by(|a, b| gamma(&a.0).total_cmp(&gamma(&b.0)));
    let mut best_standard = best(&standard);
    if let Some(b) = &mut best_standard {
        let k = standard.iter().position(|s| s.0 == b.law);
        if let Some(k) = k.filter(|&k| k > 0 && k + 1 < standard.len()) {
            // The mean square is smooth where the rms has a kink at zero.
            let point = |i: usize| (gamma(&standard[i].0), standard[i].1.powi(2));
            b.refined_gamma = parabola_minimum([point(k - 1), point(k), point(k + 1)]);
        }
    }
    let best_advanced = best(&scored(|l| matches!(l, Law::Advanced { .. })));
    (best_standard, best_advanced)
}

/// Runs (or reuses) every variant of every grain study, fits, and writes
/// `dir/calibration.json`, `dir/calibration.svg` and `dir/calibration.txt`;
/// each variant's study goes to `dir/<grains>/<law>/`.
///
/// With a checkpoint in `runtime`, each variant's compaction keeps its
/// parts in it, under `<grains>/<law>/`.
pub fn run_calibration(
    opts: &CalibrationOptions,
    runtime: &crate::studies::StudyRuntime,
    dir: &Path,
    command: &str,
    print: &mut dyn FnMut(&str),
) -> Result<CalibrationReport, CompactionError> {
    let threads = runtime.threads;
    opts.validate()?;
    let mut labels = std::collections::HashSet::new();
    let mut all_grains = Vec::new();
    let mut warnings = Vec::new();
    for grains_dir in &opts.grains {
        let grains = grain_study(grains_dir, threads)?;
        let label = grains_dir
            .file_name()
            .map_or("grains".into(), |n| n.to_string_lossy().into_owned());
        if !labels.insert(label.clone()) {
            return Err(CompactionError::Invalid(InvalidOption::new(
                "GRAINS",
                format!(
                    "two grain studies are named {label}: their spheres would share DIR/{label}/"
                ),
            )));
        }
        if grains.threads.is_none() {
            warnings.push(format!(
                "{} does not record its thread count; its spheres were built with {threads} (its command: {})",
                grains_dir.display(),
                grains.command
            ));
        }
        all_grains.push((grains_dir, label, grains));
    }
    std::fs::create_dir_all(dir).map_err(FileError::on("creating", dir))?;
    let mut report = CalibrationReport {
        version: crate::VERSION.into(),
        command: command.into(),
        options: opts.clone(),
        threads,
        warnings,
        studies: Vec::new(),
    };
    for (grains_dir, label, grains) in all_grains {
        let laws = opts.laws();
        let mut studies = Vec::with_capacity(laws.len());
        for &law in &laws {
            let folder = dir.join(&label).join(law.folder());
            let spheres = study_in(
                &opts.sphere_options(&grains, law),
                &folder,
                &runtime.scoped(&format!("{label}/{}", law.folder())),
                command,
                print,
            )?;
            studies.push((law, folder, spheres));
        }
        // laws() starts with plain Hertz.
        let hertz = studies[0].2.clone();
        let variants: Vec<VariantFit> = studies
            .into_iter()
            .map(|(law, folder, spheres)| fit_variant(opts, &grains, law, folder, &spheres, &hertz))
            .collect();
        let (best_standard, best_advanced) = best_fits(&variants);
        report.studies.push(GrainCalibration {
            grains: grains_dir.clone(),
            label,
            nu: grains.moduli.nu,
            a_b: grains.options.a_b,
            phi_c: mean_phi_c(&grains),
            curve: curve_of(&grains),
            variants,
            best_standard,
            best_advanced,
        });
        write_report(&report, dir)?;
    }
    Ok(report)
}

/// Writes `calibration.json`, `calibration.svg` and `calibration.txt`.
pub fn write_report(report: &CalibrationReport, dir: &Path) -> Result<(), CompactionError> {
    output::write_report(report, dir)?;
    Ok(())
}

impl StudyReport for CalibrationReport {
    const JSON: &'static str = "calibration.json";

    /// `calibration.svg` (one row per grain study: standard, advanced,
    /// pressures) and `calibration.txt` ([`table`]).
    fn draw(&self, out: &StudyOutput) -> Result<(), OutputError> {
        out.svg_rows("calibration.svg", &panels(self), 3)?;
        out.text("calibration.txt", &table(self))?;
        Ok(())
    }
}

/// A law's legend.
fn legend(law: &Law) -> String {
    match law {
        Law::Hertz => "Hertz".into(),
        Law::Standard { gamma } => format!("standard {gamma}"),
        Law::Advanced { gamma, mpr } => format!("advanced {gamma}, MPR {mpr}"),
    }
}

/// Per grain study: the pressures of the grains, Hertz and the best fits
/// against `phi_MC - phi_c`, and every variant's ratio to the grains.
fn panels(report: &CalibrationReport) -> Vec<Panel> {
    let mut panels = Vec::new();
    for study in &report.studies {
        let ratio_series = |v: &VariantFit| {
            Series::new(
                legend(&v.law),
                DISTANCES
                    .iter()
                    .zip(&v.ratio_at_distance)
                    .filter_map(|(x, r)| Some((*x, (*r)?)))
                    .collect(),
                Mark::LinePoints,
            )
        };
        // The grains' own level, drawn as a line across the distances.
        let parity = Series::new(
            "grains (1)",
            vec![(DISTANCES[0], 1.0), (DISTANCES[DISTANCES.len() - 1], 1.0)],
            Mark::Line,
        );
        for (closure, keep) in [
            (
                "standard",
                (|l: &Law| !matches!(l, Law::Advanced { .. })) as fn(&Law) -> bool,
            ),
            ("advanced", |l: &Law| !matches!(l, Law::Standard { .. })),
        ] {
            let mut series = vec![parity.clone()];
            series.extend(
                study
                    .variants
                    .iter()
                    .filter(|v| keep(&v.law))
                    .map(ratio_series),
            );
            panels.push(Panel {
                title: format!(
                    "{} (nu = {:.2}): {closure} closure, P / P(grains)",
                    study.label, study.nu
                ),
                x_label: "phi_MC - phi_c".into(),
                y_label: "P / P(grains)".into(),
                log_x: true,
                series,
                ..Panel::default()
            });
        }
        let chosen: Vec<&VariantFit> = study
            .variants
            .iter()
            .filter(|v| {
                v.law == Law::Hertz
                    || study.best_standard.is_some_and(|b| b.law == v.law)
                    || study.best_advanced.is_some_and(|b| b.law == v.law)
            })
            .collect();
        let mut series = vec![Series::new("grains", study.curve.clone(), Mark::LinePoints)];
        series.extend(
            chosen
                .iter()
                .map(|v| Series::new(legend(&v.law), v.curve.clone(), Mark::Line)),
        );
        panels.push(Panel {
            title: format!("{}: pressure, grains and best fits", study.label),
            x_label: "phi_MC - phi_c".into(),
            y_label: "P / E_eff".into(),
            log_x: true,
            log_y: true,
            series,
        });
    }
    panels
}

/// The calibration as text: per grain study, every variant's ratios and
/// error, and the best fits.
pub fn table(report: &CalibrationReport) -> String {
    use std::fmt::Write;
    let cell = |r: &Option<f64>| r.map_or("-".to_string(), |r| format!("{r:.3}"));
    let mut t = String::new();
    let _ = writeln!(t, "# bpm mc-calibrate: DEM closures against bonded grains");
    let _ = writeln!(t, "# {}", report.command);
    for w in &report.warnings {
        let _ = writeln!(t, "# warning: {w}");
    }
    let [lo, hi] = report.options.window;
    for s in &report.studies {
        let phi = |p: Option<f64>| p.map_or("not fitted".into(), |p| format!("{p:.4}"));
        let _ = writeln!(
            t,
            "\n## {} (a_B = {}, nu = {:.3}): grains' phi_c = {}, spheres' (plain Hertz) {}",
            s.label,
            s.a_b,
            s.nu,
            phi(s.phi_c),
            phi(s.variants.first().and_then(|v| v.phi_c))
        );
        let _ = write!(t, "\nP / P(grains) at phi - phi_c = ");
        for x in DISTANCES {
            let _ = write!(t, "{x:>7}");
        }
        let _ = writeln!(
            t,
            "   rms ln err [{lo}, {hi}]   within 10%   own phi_c   stopped"
        );
        for v in &s.variants {
            let _ = write!(t, "  {:<29}", legend(&v.law));
            for r in &v.ratio_at_distance {
                let _ = write!(t, "{:>7}", cell(r));
            }
            let _ = writeln!(
                t,
                "   {:>20}   {:>10}   {:>6}   {}",
                cell(&v.rms_log_error),
                v.within_10_percent
                    .map_or("-".into(), |[a, b]| format!("{a} to {b}")),
                v.own_phi_c.map_or("-".into(), |p| format!("{p:.4}")),
                v.stopped.as_deref().map_or("no", |_| "yes (see json)")
            );
        }
        let _ = write!(t, "\nP / P(grains) at phi_MC =       ");
        for phi in FRACTIONS {
            let _ = write!(t, "{phi:>7}");
        }
        let _ = writeln!(t);
        for v in &s.variants {
            let _ = write!(t, "  {:<29}", legend(&v.law));
            for r in &v.ratio_at_fraction {
                let _ = write!(t, "{:>7}", cell(r));
            }
            let _ = writeln!(t);
        }
        let _ = writeln!(t);
        if let Some(b) = &s.best_standard {
            let _ = writeln!(
                t,
                "best standard closure: {} (rms ln error {:.3}){}",
                legend(&b.law),
                b.rms_log_error,
                b.refined_gamma.map_or(String::new(), |g| format!(
                    "; parabola through its neighbours: gamma = {g:.3}"
                ))
            );
        }
        if let Some(b) = &s.best_advanced {
            let _ = writeln!(
                t,
                "best advanced closure: {} (rms ln error {:.3})",
                legend(&b.law),
                b.rms_log_error
            );
        }
        if let Some(h) = s.variants.iter().find(|v| v.law == Law::Hertz) {
            let _ = writeln!(t, "plain Hertz: rms ln error {}", cell(&h.rms_log_error));
        }
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parabola_finds_the_vertex() {
        let f = |x: f64| 2.0 * (x - 1.3).powi(2) + 0.5;
        let m = parabola_minimum([(0.5, f(0.5)), (1.0, f(1.0)), (2.0, f(2.0))]).unwrap();
        assert!((m - 1.3).abs() < 1e-12, "{m}");
        assert!(parabola_minimum([(0.0, 0.0), (1.0, 1.0), (2.0, 0.0)]).is_none());
    }

    fn scored(law: Law, rms: Option<f64>) -> VariantFit {
        VariantFit {
            law,
            folder: PathBuf::new(),
            phi_c: None,
            own_phi_c: None,
            stopped: None,
            ratio_at_distance: Vec::new(),
            ratio_at_fraction: Vec::new(),
            rms_log_error: rms,
            within_10_percent: None,
            curve: Vec::new(),
        }
    }

    /// The best standard prefactor is refined through its neighbours in
    /// gamma whatever the order of the grid; variants without an error
    /// (stopped early) take no part.
    #[test]
    fn the_best_prefactor_is_refined_on_the_mean_square() {
        let rms = |g: f64| (0.04 + (g - 1.1).powi(2)).sqrt();
        let variants = vec![
            scored(Law::Hertz, Some(0.5)),
            scored(Law::Standard { gamma: 1.5 }, Some(rms(1.5))),
            scored(Law::Standard { gamma: 0.5 }, Some(rms(0.5))),
            scored(Law::Standard { gamma: 1.0 }, Some(rms(1.0))),
            scored(Law::Standard { gamma: 1.2 }, None),
            scored(
                Law::Advanced {
                    gamma: 1.0,
                    mpr: 0.1,
                },
                Some(0.3),
            ),
            scored(
                Law::Advanced {
                    gamma: 2.0,
                    mpr: 0.05,
                },
                Some(0.25),
            ),
        ];
        let (standard, advanced) = best_fits(&variants);
        let standard = standard.unwrap();
        assert_eq!(standard.law, Law::Standard { gamma: 1.0 });
        // The mean square is a parabola in gamma, so its vertex is exact.
        let refined = standard.refined_gamma.unwrap();
        assert!((refined - 1.1).abs() < 1e-12, "{refined}");
        assert_eq!(
            advanced.unwrap().law,
            Law::Advanced {
                gamma: 2.0,
                mpr: 0.05
            }
        );
        // A best point at the grid's edge is not refined.
        let edge = best_fits(&variants[..3]).0.unwrap();
        assert_eq!(edge.law, Law::Standard { gamma: 1.5 });
        assert!(edge.refined_gamma.is_none());
    }

    #[test]
    fn the_longest_stretch_within_ten_percent_is_found() {
        let l = |r: f64| Some(r.ln());
        let errors = [
            l(0.5),
            l(0.95),
            l(1.05),
            None,
            l(1.0),
            l(1.09),
            l(0.92),
            l(1.2),
        ];
        assert_eq!(longest_within_10_percent(&errors), Some((4, 6)));
        assert_eq!(longest_within_10_percent(&[l(0.5), l(2.0)]), None);
        assert_eq!(longest_within_10_percent(&[l(1.0)]), Some((0, 0)));
    }

    #[test]
    fn laws_name_their_folders_and_grid() {
        let opts = CalibrationOptions {
            gammas: vec![1.0],
            advanced_gammas: vec![0.81],
            mprs: vec![0.05, 0.11],
            ..CalibrationOptions::default()
        };
        let names: Vec<String> = opts.laws().iter().map(Law::folder).collect();
        assert_eq!(
            names,
            [
                "hertz",
                "standard-1",
                "advanced-0.81-0.05",
                "advanced-0.81-0.11"
            ]
        );
    }

    #[test]
    fn bad_grids_are_refused() {
        let base = CalibrationOptions {
            grains: vec!["g".into()],
            ..CalibrationOptions::default()
        };
        assert!(base.validate().is_ok());
        let bad = |o: CalibrationOptions| o.validate().unwrap_err().to_string();
        assert!(bad(CalibrationOptions {
            gammas: vec![-1.0],
            ..base.clone()
        })
        .contains("--gammas"));
        assert!(bad(CalibrationOptions {
            mprs: vec![],
            ..base.clone()
        })
        .contains("--mprs"));
        assert!(bad(CalibrationOptions {
            window: [0.3, 0.1],
            ..base.clone()
        })
        .contains("--window"));
        assert!(bad(CalibrationOptions {
            window: [0.04, 0.045],
            ..base.clone()
        })
        .contains("--window"));
        assert!(bad(CalibrationOptions {
            gammas: vec![0.5, 1.0, 0.5],
            ..base.clone()
        })
        .contains("repeats"));
        assert!(bad(CalibrationOptions {
            grains: vec![],
            ..base
        })
        .contains("GRAINS"));
    }
}
