//! Simple shear above jamming (the multi-contact study's Section 4 and
//! Appendix D): monodisperse spheres in a periodic cube sheared at constant
//! volume with Lees-Edwards boundaries, at volume fractions from 0.65 to
//! 0.9, under plain Hertz and the two closures, at several friction
//! coefficients and Poisson's ratios. The quasi-static pressure is fitted
//! to `p / k = alpha |phi - phi_c|^beta` (`k = 4/3 E*`) and compared with
//! the study's Tables D.1 and D.2 (`reference_data/`).
//!
//! Reduced units: diameter `d = 1`, Young's modulus `E = 1`, sphere mass
//! `m = 1` (density `6 / pi`), so times are in `tau = sqrt(m / (E d))`.
//! The study gives neither its rates nor its strains, time step,
//! restitution, packing preparation or jamming points: the readings taken
//! here are in docs/protocols.md ("Simple shear above jamming").
//!
//! Each run is one scene of two stages: a fast shear at `rate_factor`
//! times the rate (which also carries the start-up transient) and the
//! slow shear at the rate. Their mean pressures test the quasi-static
//! limit: when they differ by no more than `quasi_static_tolerance` the
//! slow one is the quasi-static pressure. Every run's recorded series is
//! kept in its own file under `runs/`, so an interrupted study resumes and
//! the analysis can be redone without running anything.

mod analysis;
mod beta;
mod protocol;
mod report;
mod trend;

pub use analysis::{
    analyse, window_mean, Analysis, Regime, SeriesResult, ShearPoint, TrendCheck, WindowMean,
    BLOCKS,
};
pub use beta::BetaDiagnosis;
pub use protocol::{
    cube_edge, material, prepare_packings, run_point, shear_rate, shear_scene, stage_rates,
    stiffness, Packing, RecordedRun, RunKey, StageSeries,
};
pub use report::{table, write_report};
pub use trend::{gather_folders, trend_table, ShearTrend, TrendCurve, TrendRow};

use super::Closures;
use crate::analysis::fit::interpolate;
use crate::engine::MultiContact;
use crate::file_error::FileError;
use crate::reference::multicontact::ASSUMED_JAMMING_POINTS;
use crate::scene::{validate, Scene};
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The contact laws compared (`bpm mc-shear --laws`: the variants' docs
/// are its help).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
pub enum ContactLaw {
    /// Plain Hertz-Mindlin.
    Hertz,
    /// The standard closure.
    Standard,
    /// The advanced closure.
    Advanced,
}

impl ContactLaw {
    /// Name in tables, legends and file names.
    pub fn name(self) -> &'static str {
        match self {
            ContactLaw::Hertz => "hertz",
            ContactLaw::Standard => "standard",
            ContactLaw::Advanced => "advanced",
        }
    }

    /// The closure of this law with the study's prefactors and reach.
    pub fn multicontact(self, closures: &Closures, reach: f64) -> Option<MultiContact> {
        let closure = match self {
            ContactLaw::Hertz => return None,
            ContactLaw::Standard => MultiContact::standard(closures.gamma),
            ContactLaw::Advanced => MultiContact::advanced(closures.gamma_advanced, closures.mpr),
        };
        Some(MultiContact { reach, ..closure })
    }
}

/// One curve of the study: a contact law at one friction coefficient and
/// Poisson's ratio, run at every volume fraction.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SeriesSpec {
    /// The contact law.
    pub law: ContactLaw,
    /// Sliding friction coefficient.
    pub friction: f64,
    /// Poisson's ratio.
    pub poisson_ratio: f64,
}

/// The study's named grids.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Grid {
    /// 21 curves of 6 volume fractions: Hertz at friction 0, 0.1, 0.5 and
    /// 1 and Poisson's ratio 0.25 and 0.5 (the study's claim that Hertz
    /// does not depend on it); the standard closure at friction 0 and 0.5
    /// at the same ratios; the advanced closure at friction 0 and Poisson's
    /// ratio 0.25, 0.4 and 0.5 (the tables' strongest trend), and at
    /// friction 0.1, 0.5 and 1 at 0.25 and 0.5.
    Default,
    /// Three curves (one per law) at friction 0.5, Poisson's ratio 0.5 and
    /// volume fractions 0.75 and 0.9, 108 spheres, short strains: a check
    /// that runs in seconds.
    Quick,
}

impl Grid {
    /// The curves of the grid.
    pub fn series(self) -> Vec<SeriesSpec> {
        let cross = |law, frictions: &[f64], poissons: &[f64]| {
            frictions
                .iter()
                .flat_map(|&friction| {
                    poissons.iter().map(move |&poisson_ratio| SeriesSpec {
                        law,
                        friction,
                        poisson_ratio,
                    })
                })
                .collect::<Vec<_>>()
        };
        match self {
            Grid::Default => [
                cross(ContactLaw::Hertz, &[0.0, 0.1, 0.5, 1.0], &[0.25, 0.5]),
                cross(ContactLaw::Standard, &[0.0, 0.5], &[0.25, 0.5]),
                cross(ContactLaw::Advanced, &[0.0], &[0.25, 0.4, 0.5]),
                cross(ContactLaw::Advanced, &[0.1, 0.5, 1.0], &[0.25, 0.5]),
            ]
            .concat(),
            Grid::Quick => [
                ContactLaw::Hertz,
                ContactLaw::Standard,
                ContactLaw::Advanced,
            ]
            .map(|law| SeriesSpec {
                law,
                friction: 0.5,
                poisson_ratio: 0.5,
            })
            .to_vec(),
        }
    }

    /// The grid's volume fractions.
    pub fn fractions(self) -> Vec<f64> {
        match self {
            Grid::Default => vec![0.65, 0.7, 0.75, 0.8, 0.85, 0.9],
            Grid::Quick => vec![0.75, 0.9],
        }
    }
}

/// Options of `bpm mc-shear`.
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct ShearOptions {
    /// Spheres in the periodic cube.
    pub spheres: usize,
    /// Volume fractions sheared.
    pub fractions: Vec<f64>,
    /// The curves.
    pub series: Vec<SeriesSpec>,
    /// The slow shear's dimensionless rate `gamma_dot d / sqrt(k / rho)`.
    pub rate: f64,
    /// The fast shear runs this many times faster.
    pub rate_factor: f64,
    /// Shear strain of the fast stage; its second half is averaged.
    pub strain_fast: f64,
    /// Shear strain of the slow stage.
    pub strain_slow: f64,
    /// Strain at the start of the slow stage left out of its average.
    pub discard: f64,
    /// Recorded rows per unit strain.
    pub records_per_strain: f64,
    /// Time step (tau).
    pub dt: f64,
    /// Normal restitution coefficient.
    pub restitution: f64,
    /// Neighbour skin (d).
    pub skin: f64,
    /// Prefactors and MPR of the closures.
    pub closures: Closures,
    /// How far beyond touching a closure still corrects a pair (fraction
    /// of the two radii).
    pub reach: f64,
    /// Largest relative difference of the fast and slow pressure of a
    /// quasi-static point.
    pub quasi_static_tolerance: f64,
    /// The jamming point used for each friction coefficient.
    pub jamming_points: Vec<(f64, f64)>,
    /// Seed of the packing.
    pub seed: u64,
    /// Runs at a time (each on one thread).
    pub workers: usize,
}

impl ShearOptions {
    /// The options of a named grid, every other option at its default.
    pub fn grid(grid: Grid) -> Self {
        let mut opts = Self {
            spheres: 256,
            fractions: grid.fractions(),
            series: grid.series(),
            rate: 2e-3,
            rate_factor: 4.0,
            strain_fast: 1.5,
            strain_slow: 1.25,
            discard: 0.25,
            records_per_strain: 100.0,
            dt: 0.05,
            restitution: 0.7,
            skin: 0.15,
            // The closures' Appendix B prefactors; the MPR in the middle of
            // the range the study found for its bed (0.07 to 0.09).
            closures: Closures {
                mpr: 0.08,
                ..Closures::default()
            },
            reach: 0.25,
            quasi_static_tolerance: 0.05,
            jamming_points: ASSUMED_JAMMING_POINTS.to_vec(),
            seed: 1,
            workers: 2,
        };
        if grid == Grid::Quick {
            opts.spheres = 108;
            opts.strain_fast = 0.4;
            opts.strain_slow = 0.3;
            opts.discard = 0.1;
        }
        opts
    }
}

impl Default for ShearOptions {
    fn default() -> Self {
        Self::grid(Grid::Default)
    }
}

/// What can go wrong.
#[derive(Debug, thiserror::Error)]
pub enum ShearError {
    /// Bad options.
    #[error("{0}")]
    Options(String),
    /// The packings could not be prepared.
    #[error("preparing the packings: {0}")]
    Preparation(String),
    /// A file could not be written.
    #[error(transparent)]
    File(#[from] FileError),
    /// The report or its drawings could not be written or read back.
    #[error(transparent)]
    Output(#[from] crate::studies::output::OutputError),
}

/// Volume fraction the packing starts from before it is compressed.
const START_FRACTION: f64 = 0.45;
/// True strain rate per dimension of the preparing compression (1 / tau).
const PREPARATION_RATE: f64 = 2e-4;
/// Time (tau) the packing rests at each volume fraction before it is
/// saved.
const PREPARATION_HOLD: f64 = 100.0;
/// Largest volume fraction a run may ask for.
const MAX_FRACTION: f64 = 0.95;
/// Version of the protocol a run's file records: a run recorded under
/// another one is run again.
const PROTOCOL: u32 = 3;
/// Most steps of one run.
const MAX_RUN_STEPS: f64 = 1e8;

impl ShearOptions {
    /// Checks the options; the error names the one at fault.
    pub fn validate(&self) -> Result<(), ShearError> {
        let bad = |m: String| Err(ShearError::Options(m));
        for (name, v) in [
            ("--rate", self.rate),
            ("--strain-fast", self.strain_fast),
            ("--strain-slow", self.strain_slow),
            ("--records-per-strain", self.records_per_strain),
            ("--dt", self.dt),
            ("--skin", self.skin),
            ("--reach", self.reach),
            ("--quasi-static-tolerance", self.quasi_static_tolerance),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return bad(format!("{name} must be > 0 (got {v})"));
            }
        }
        if !(self.rate_factor.is_finite() && self.rate_factor > 1.0) {
            return bad(format!(
                "--rate-factor must be > 1 (got {}): the fast shear tests the slow one",
                self.rate_factor
            ));
        }
        if !(self.discard.is_finite() && self.discard >= 0.0 && self.discard < self.strain_slow) {
            return bad(format!(
                "--discard must lie in [0, --strain-slow) (got {})",
                self.discard
            ));
        }
        if !(self.restitution > 0.0 && self.restitution <= 1.0) {
            return bad(format!(
                "--restitution must lie in (0, 1] (got {})",
                self.restitution
            ));
        }
        if self.spheres < 2 {
            return bad("--spheres must be at least 2".into());
        }
        if self.workers == 0 {
            return bad("--workers must be at least 1".into());
        }
        if self.fractions.is_empty() || self.series.is_empty() {
            return bad("the grid is empty: give --fractions, --frictions, --poissons and --laws at least one value each".into());
        }
        for &phi in &self.fractions {
            if !(phi > START_FRACTION && phi <= MAX_FRACTION) {
                return bad(format!(
                    "--fractions must lie in ({START_FRACTION}, {MAX_FRACTION}] (got {phi})"
                ));
            }
        }
        if has_duplicates(&self.fractions) {
            return bad(format!(
                "--fractions lists a value twice ({:?})",
                self.fractions
            ));
        }
        for s in &self.series {
            if !(s.friction.is_finite() && s.friction >= 0.0) {
                return bad(format!("--frictions must be >= 0 (got {})", s.friction));
            }
            if !(s.poisson_ratio > -1.0 && s.poisson_ratio < 0.5 + 1e-12) {
                return bad(format!(
                    "--poissons must lie in (-1, 0.5] (got {})",
                    s.poisson_ratio
                ));
            }
        }
        for (i, a) in self.series.iter().enumerate() {
            if self.series[..i].contains(a) {
                return bad(format!("the grid lists the curve {a:?} twice"));
            }
        }
        // Each average needs rows enough for its block error.
        let rows = [
            ("--strain-fast", 0.5 * self.strain_fast),
            (
                "--strain-slow minus --discard",
                self.strain_slow - self.discard,
            ),
        ];
        for (name, strain) in rows {
            // The recording interval is rounded to whole steps, which can
            // leave two thirds of the nominal rows.
            if strain * self.records_per_strain < 1.5 * BLOCKS as f64 {
                return bad(format!(
                    "{name} ({strain} averaged) at --records-per-strain {} gives too few rows to average ({:.1}; at least {:.1})",
                    self.records_per_strain,
                    strain * self.records_per_strain,
                    1.5 * BLOCKS as f64
                ));
            }
        }
        let densest = self.fractions.iter().copied().fold(0.0, f64::max);
        let preparation = ((densest / START_FRACTION).ln() / (3.0 * PREPARATION_RATE)
            + PREPARATION_HOLD * self.fractions.len() as f64)
            / self.dt;
        if preparation > MAX_RUN_STEPS {
            return bad(format!(
                "preparing the packings would take {preparation:.3e} steps, more than {MAX_RUN_STEPS:e}: raise --dt"
            ));
        }
        for s in &self.series {
            let slow = shear_rate(self.rate, s.poisson_ratio);
            let steps = (self.strain_fast / self.rate_factor + self.strain_slow) / (slow * self.dt);
            if steps.is_nan() || steps > MAX_RUN_STEPS {
                return bad(format!(
                    "a run would take {steps:.3e} steps, more than {MAX_RUN_STEPS:e}: raise --rate or --dt, or shorten the strains"
                ));
            }
        }
        // A sheared box flips its tilt at half an edge, where its faces lie
        // L / sqrt(1.25) apart; the pair range (the closures' reach and the
        // skin included, whatever the laws) must stay within half of that.
        let range = 1.0 + self.reach + self.skin;
        let edge = cube_edge(self.spheres, densest);
        if 0.5 * edge / 1.25f64.sqrt() <= range {
            let needed =
                (2.0 * 1.25f64.sqrt() * range).powi(3) * 6.0 * densest / std::f64::consts::PI;
            return bad(format!(
                "--spheres {} at volume fraction {densest} fill a cube of edge {edge:.2} d: sheared, its faces come closer than twice the pair range {range} d; use at least {} spheres",
                self.spheres,
                needed.ceil()
            ));
        }
        if self.jamming_points.is_empty()
            || self
                .jamming_points
                .iter()
                .any(|&(mu, phi)| !(mu >= 0.0 && mu.is_finite() && phi > 0.0 && phi < 1.0))
            || self.jamming_points.windows(2).any(|w| w[1].0 <= w[0].0)
        {
            return bad(format!(
                "--phi-c takes friction:phi_c pairs in increasing friction, phi_c in (0, 1) (got {:?})",
                self.jamming_points
            ));
        }
        self.closures.validate().map_err(ShearError::Options)
    }

    /// The jamming point assumed at friction `mu`: linear between the
    /// listed frictions, constant beyond their ends.
    pub fn jamming_point(&self, mu: f64) -> f64 {
        let (frictions, phis): (Vec<f64>, Vec<f64>) = self.jamming_points.iter().copied().unzip();
        let (Some(&lo), Some(&hi)) = (frictions.first(), frictions.last()) else {
            return f64::NAN;
        };
        interpolate(&frictions, &phis, mu.clamp(lo, hi)).unwrap_or(f64::NAN)
    }
}

fn has_duplicates(values: &[f64]) -> bool {
    values
        .iter()
        .enumerate()
        .any(|(i, a)| values[..i].iter().any(|b| (a - b).abs() < 1e-12))
}

/// The distinct values of `values`, in increasing order.
pub fn sorted_distinct(values: impl IntoIterator<Item = f64>) -> Vec<f64> {
    let mut v: Vec<f64> = values.into_iter().collect();
    v.sort_by(f64::total_cmp);
    v.dedup();
    v
}

/// The study's result.
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
pub struct ShearReport {
    /// The command that wrote it.
    pub command: String,
    /// The crate's version.
    pub version: String,
    /// The options.
    pub options: ShearOptions,
    /// The packings.
    pub packings: Vec<Packing>,
    /// Curves, fits and checks.
    #[serde(flatten)]
    pub analysis: Analysis,
    /// Runs that ran in this invocation (the others were reused).
    pub ran: usize,
    /// Wall-clock seconds of this invocation.
    pub seconds: f64,
}
/// Where the study's files go.
fn run_path(dir: &Path, key: &RunKey) -> PathBuf {
    dir.join("runs").join(key.file_name())
}

/// A run's file, if it holds a run of `key`. A file is written only when
/// its run has ended, so it holds either a complete run or one the engine
/// stopped (which the same run would stop again); a file cut short does
/// not parse.
fn reusable(path: &Path, key: &RunKey) -> Option<RecordedRun> {
    let text = std::fs::read_to_string(path).ok()?;
    let run: RecordedRun = serde_json::from_str(&text).ok()?;
    (run.key == *key).then_some(run)
}

/// Runs the study: prepares the packings, runs (or reuses) every point,
/// `opts.workers` at a time, saving each as it finishes, and analyses
/// them. `progress` shows a bar.
pub fn run_shear(
    opts: &ShearOptions,
    dir: &Path,
    command: &str,
    progress: bool,
) -> Result<(ShearReport, Scene), ShearError> {
    opts.validate()?;
    let start = std::time::Instant::now();
    let packings = prepare_packings(opts)?;
    let runs_dir = dir.join("runs");
    std::fs::create_dir_all(&runs_dir).map_err(FileError::on("creating", &runs_dir))?;
    let jobs: Vec<(RunKey, &Packing)> = opts
        .series
        .iter()
        .flat_map(|s| packings.iter().map(move |p| (RunKey::new(opts, s, p), p)))
        .collect();
    // Every scene is checked before anything runs: an error found after
    // an hour would waste it.
    for (key, packing) in &jobs {
        validate(&shear_scene(key, packing)).map_err(|e| {
            ShearError::Options(format!(
                "{} at volume fraction {}: {e}",
                key.series.law.name(),
                key.fraction
            ))
        })?;
    }
    let example = shear_scene(&jobs[0].0, jobs[0].1);
    let (reused, todo): (Vec<_>, Vec<_>) = jobs
        .iter()
        .map(|(key, packing)| (key, packing, reusable(&run_path(dir, key), key)))
        .partition(|(_, _, run)| run.is_some());
    let bar = if progress {
        let bar = ProgressBar::new(todo.len() as u64);
        bar.set_style(
            ProgressStyle::with_template(
                "mc-shear {bar:30} {pos}/{len} runs, {elapsed} elapsed, ETA {eta} {msg}",
            )
            .expect("valid template"),
        );
        bar
    } else {
        ProgressBar::hidden()
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(opts.workers)
        .build()
        .map_err(|e| ShearError::Options(format!("--workers: {e}")))?;
    let fresh: Vec<Result<RecordedRun, ShearError>> = pool.install(|| {
        todo.par_iter()
            .map(|(key, packing, _)| {
                let run = run_point(key, packing);
                let path = run_path(dir, key);
                crate::verify::write_json(&path, &run).map_err(FileError::on("writing", &path))?;
                bar.inc(1);
                Ok(run)
            })
            .collect()
    });
    bar.finish_and_clear();
    let ran = fresh.len();
    let mut runs: Vec<RecordedRun> = reused.into_iter().filter_map(|(_, _, r)| r).collect();
    for run in fresh {
        runs.push(run?);
    }
    let analysis = analyse(opts, &runs);
    Ok((
        ShearReport {
            command: command.to_string(),
            version: crate::VERSION.to_string(),
            options: opts.clone(),
            packings,
            analysis,
            ran,
            seconds: start.elapsed().as_secs_f64(),
        },
        example,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jamming_points_interpolate_between_frictions() {
        let opts = ShearOptions::default();
        assert_eq!(opts.jamming_point(0.0), 0.636);
        assert!((opts.jamming_point(0.2) - 0.603).abs() < 1e-12);
        assert_eq!(opts.jamming_point(2.0), 0.587);
    }

    #[test]
    fn bad_options_are_refused_by_name() {
        let refused = |change: &dyn Fn(&mut ShearOptions), name: &str| {
            let mut opts = ShearOptions::default();
            change(&mut opts);
            let err = opts.validate().unwrap_err().to_string();
            assert!(err.contains(name), "{name}: {err}");
        };
        refused(&|o| o.rate = 0.0, "--rate");
        refused(&|o| o.rate_factor = 1.0, "--rate-factor");
        refused(&|o| o.discard = 2.0, "--discard");
        refused(&|o| o.fractions = vec![0.7, 0.7], "--fractions");
        refused(&|o| o.fractions = vec![0.99], "--fractions");
        refused(&|o| o.series[0].poisson_ratio = 0.6, "--poissons");
        refused(&|o| o.series[0].friction = f64::NAN, "--frictions");
        refused(&|o| o.workers = 0, "--workers");
        refused(
            &|o| o.jamming_points = vec![(0.5, 0.6), (0.1, 0.6)],
            "--phi-c",
        );
        refused(&|o| o.closures.mpr = -1.0, "--mpr");
        refused(&|o| o.series.push(o.series[0]), "twice");
        refused(&|o| o.spheres = 40, "use at least 53 spheres");
        refused(&|o| o.records_per_strain = 5.0, "too few rows");
        refused(&|o| o.dt = 1e-7, "preparing");
        refused(&|o| o.rate = 1e-12, "steps");
        assert!(ShearOptions::default().validate().is_ok());
        assert!(ShearOptions::grid(Grid::Quick).validate().is_ok());
    }
}
