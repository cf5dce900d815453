//! The grain-crushing study (docs/protocols.md, "Grain crushing"): a
//! grain of breakable (or yielding) bonds squeezed between two flat walls
//! far beyond the Hertz range, at each a_B asked for. Each squeeze gives
//! the force against the overlap (Hertz's until the first break), the
//! first break, the crushing force, the broken bonds against the overlap,
//! and the fragments the intact bonds still hold together at the end.

pub mod cli;

use crate::analysis::fragments::Fragments;
use crate::analysis::hertz::{
    effective_modulus, hertz_deviation, hertz_normalised_force, squeeze_curve, HertzDeviation,
    SqueezeCurve,
};
use crate::analysis::plot::{Mark, Panel, Series};
use crate::engine::external::{FlatWall, WallSide};
use crate::engine::BpmModel;
use crate::kernels::BondFailure;
use crate::scene::builders::grain::GrainSummary;
use crate::scene::protocols::{hertz_squeeze, SqueezeParams};
use crate::scene::{ForceField, Scene};
use crate::studies::hertz::{
    built_grain, gap_and_force, read_grain_file, rotation_draws, squeeze_native_system, turned,
    Grain, GrainSource, HertzError, Moduli, MAX_ROTATIONS,
};
use crate::studies::output::{self, OutputError, StudyOutput, StudyReport};
use crate::studies::StudyRuntime;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The fall of the wall force from the largest force reached so far that
/// marks the grain's failure: a crushing force is the peak before the
/// force first drops below `1 - FAILURE_DROP` of it. Bonds breaking one
/// by one shave a few per cent off the force; a grain splitting loses
/// most of it.
pub const FAILURE_DROP: f64 = 0.2;

/// Fragments this share of the grain's particles or more are counted
/// apart from the debris (`Crush::large_fragments`).
pub const LARGE_FRAGMENT: f64 = 0.01;

/// Options of the study.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct CrushOptions {
    /// The grains (one per seed when built; the one file otherwise).
    pub source: GrainSource,
    /// Seeds of the built grains.
    pub seeds: Vec<u64>,
    /// Multibody strengths a_B (k d): every grain is crushed at each
    /// (built grains are built at the first).
    pub a_bs: Vec<f64>,
    /// Random rotations per grain (0: crushed as given).
    pub rotations: usize,
    /// How the bonds break and yield.
    pub failure: BondFailure,
    /// The walls' travel, as the Hertz squeeze's: each moves its force
    /// range plus `(max_overlap + 0.05) R`. The overlap counted from first
    /// contact (a force of 1e-3 E_eff R^2, reached within about 0.1 d of
    /// travel) ends near `max_overlap + 0.05 + 0.9 d / R`.
    pub max_overlap: f64,
    /// The overlap `delta/R` at which the bonds broken and the fragments
    /// are counted too, the same for every grain size: the end of a
    /// squeeze lies further for small grains (`0.9 d / R`), and their
    /// counts at the end are not comparable. At most `max_overlap + 0.05`,
    /// which every squeeze that runs to its end passes; none: the smaller
    /// of [`DEFAULT_COMPARE_AT`] and that ([`CrushOptions::compared_at`]).
    #[serde(default)]
    pub compare_at: Option<f64>,
    /// Records per squeeze.
    pub records: u64,
    /// Threads of the native engine.
    pub threads: usize,
}

/// The overlap the counts are compared at when none is given (and
/// `max_overlap` allows it).
pub const DEFAULT_COMPARE_AT: f64 = 0.5;

impl CrushOptions {
    /// The overlap the counts are compared at: `compare_at`, or
    /// [`DEFAULT_COMPARE_AT`], or `max_overlap + 0.05` if that is less.
    pub fn compared_at(&self) -> f64 {
        self.compare_at
            .unwrap_or(DEFAULT_COMPARE_AT.min(self.reached_overlap()))
    }

    /// The overlap every squeeze that runs to its end passes.
    fn reached_overlap(&self) -> f64 {
        self.max_overlap + 0.05
    }

    /// Checks the options; the error names the one at fault.
    pub fn validate(&self) -> Result<(), HertzError> {
        let bad = |m: String| Err(HertzError::Options(m));
        self.source.validate()?;
        if self.a_bs.is_empty() {
            return bad("--a-b needs at least one value".into());
        }
        if let Some(a) = self.a_bs.iter().find(|a| !(a.is_finite() && **a > -1.0)) {
            return bad(format!(
                "--a-b values must be finite and above -1 (k d), got {a}"
            ));
        }
        if let Err(e) = self.failure.check() {
            return bad(format!("bond failure: {e}"));
        }
        if !self.failure.is_live() {
            return bad(
                "bonds neither break nor yield (--no-break without --plastic-strain): \
                 that is `bpm hertz`"
                    .into(),
            );
        }
        if self.rotations > MAX_ROTATIONS {
            return bad(format!(
                "--rotations must be at most {MAX_ROTATIONS}, got {}",
                self.rotations
            ));
        }
        if !(self.max_overlap.is_finite() && self.max_overlap > 0.0 && self.max_overlap < 1.0) {
            return bad(format!(
                "--max-overlap must be in (0, 1), got {}",
                self.max_overlap
            ));
        }
        let reached = self.reached_overlap();
        // Allowed up to round-off: 0.35 + 0.05 falls just short of 0.4.
        if let Some(at) = self
            .compare_at
            .filter(|&at| !(at.is_finite() && at > 0.0 && at <= reached + 1e-9))
        {
            return bad(format!(
                "--compare-at must be in (0, --max-overlap + 0.05 = {reached:.6}], got {at}"
            ));
        }
        if self.seeds.is_empty() {
            return bad("--seeds needs at least one value".into());
        }
        if self.records < 2 {
            return bad(format!(
                "--records must be at least 2, got {}",
                self.records
            ));
        }
        Ok(())
    }

    fn radius(&self) -> f64 {
        self.source.radius()
    }
}

/// A point of the force curve.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CurvePoint {
    /// delta / R.
    pub overlap_over_r: f64,
    /// Mean wall force (k d).
    pub force: f64,
    /// `3 f / (8 R^2 E_eff)`.
    pub normalised_force: f64,
    /// Share of the grain's bonds broken by then.
    pub broken_fraction: f64,
}

/// One crushed grain.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Crush {
    /// a_B (k d).
    pub a_b: f64,
    /// Grain seed (also the seed of its rotations).
    pub seed: u64,
    /// Rotation index (0 when crushed as given).
    pub rotation: usize,
    /// The rotation's three uniform numbers (none: as given).
    pub rotation_draw: Option<[f64; 3]>,
    /// The builder's summary, for built grains.
    pub grain: Option<GrainSummary>,
    /// Particles.
    pub particles: usize,
    /// Bonds before the squeeze.
    pub bonds: usize,
    /// Bonds intact at the end (the engine's count).
    pub intact_bonds: usize,
    /// The force curve: wall_gap, force, overlap_over_r, normalised_force.
    pub curve: SqueezeCurve,
    /// Share of the bonds broken at each record of `curve.overlap_over_r`.
    pub broken_fraction: Vec<f64>,
    /// The first record with a bond broken (none: no bond broke).
    pub first_break: Option<CurvePoint>,
    /// Deviation from Hertz over delta / R from 0.02 to the first break
    /// (or 0.25, whichever comes first); none with fewer than three records
    /// there.
    pub hertz_before_break: Option<HertzDeviation>,
    /// The peak before the force first falls by [`FAILURE_DROP`] (none:
    /// the force never fell so far, the grain was not crushed).
    pub crushing: Option<CurvePoint>,
    /// The largest force of the squeeze.
    pub peak: Option<CurvePoint>,
    /// The fragments at the end of the squeeze.
    pub fragments: Fragments,
    /// Fragments of at least [`LARGE_FRAGMENT`] of the particles.
    pub large_fragments: usize,
    /// The bonds broken and the fragments at the first record at or past
    /// `delta/R =` [`CrushOptions::compared_at`] (none if the squeeze
    /// stopped before it).
    #[serde(default)]
    pub compared: Option<CrushState>,
    /// Wall-clock seconds.
    pub seconds: f64,
    /// Why the squeeze stopped before the overlap asked for, if it did.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stopped: Option<String>,
}

/// The bonds broken and the fragments at one record of a squeeze.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CrushState {
    /// delta / R of the record.
    pub overlap_over_r: f64,
    /// Share of the grain's bonds broken by then.
    pub broken_fraction: f64,
    /// The fragments the bonds intact then hold together.
    pub fragments: Fragments,
    /// Fragments of at least [`LARGE_FRAGMENT`] of the particles.
    pub large_fragments: usize,
}

/// The fragments of `particles` particles when only the first `count` of
/// the bonds `broken` (in the order they broke) had broken, the others
/// still standing beside the bonds `intact` at the end.
///
/// # Panics
/// If `count` exceeds the bonds broken.
pub fn fragments_when_broken(
    particles: usize,
    intact: impl IntoIterator<Item = [usize; 2]>,
    broken: &[[usize; 2]],
    count: usize,
) -> Fragments {
    let standing = broken[count..].iter().copied();
    Fragments::of(particles, intact.into_iter().chain(standing))
}

/// The smallest fragment counted apart from the debris in a grain of
/// `particles` particles.
fn large_fragment_size(particles: usize) -> usize {
    ((LARGE_FRAGMENT * particles as f64).ceil() as usize).max(2)
}

/// Mean and sample standard deviation (0 for one value) of some values;
/// none for no value.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MeanSd {
    /// Mean.
    pub mean: f64,
    /// Sample standard deviation.
    pub sd: f64,
    /// How many values.
    pub count: usize,
}

impl MeanSd {
    /// Of `values`; none when there are none.
    pub fn of(values: &[f64]) -> Option<Self> {
        if values.is_empty() {
            return None;
        }
        let (mean, sd) = crate::studies::calibration::mean_sd(values);
        Some(Self {
            mean,
            sd,
            count: values.len(),
        })
    }
}

/// Every grain crushed at one a_B, and their means.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct CrushCase {
    /// a_B (k d).
    pub a_b: f64,
    /// The elastic constants of E_eff.
    pub moduli: Moduli,
    /// E_eff (k / d).
    pub e_eff: f64,
    /// The squeezes, one per grain.
    pub crushes: Vec<Crush>,
    /// delta / R of the first break.
    pub first_break_overlap: Option<MeanSd>,
    /// Crushing force over `E_eff R^2`, of the grains that were crushed.
    pub crushing_force: Option<MeanSd>,
    /// delta / R at the crushing force.
    pub crushing_overlap: Option<MeanSd>,
    /// Grains crushed (the force fell by [`FAILURE_DROP`]).
    pub crushed: usize,
    /// Share of the bonds broken at the end.
    pub broken_fraction: Option<MeanSd>,
    /// Fragments of at least [`LARGE_FRAGMENT`] of the grain, at the end.
    pub large_fragments: Option<MeanSd>,
    /// The largest fragment's share of the grain, at the end.
    pub largest_fragment: Option<MeanSd>,
    /// Share of the bonds broken at `delta/R = compare_at`.
    #[serde(default)]
    pub compared_broken_fraction: Option<MeanSd>,
    /// Fragments of at least [`LARGE_FRAGMENT`] of the grain there.
    #[serde(default)]
    pub compared_large_fragments: Option<MeanSd>,
    /// The largest fragment's share of the grain there.
    #[serde(default)]
    pub compared_largest_fragment: Option<MeanSd>,
}

/// The study's result, written as `crush.json`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct CrushReport {
    /// `bpm crush`.
    pub program: String,
    /// Crate version.
    pub version: String,
    /// The options.
    pub options: CrushOptions,
    /// The squeeze protocol (the Hertz squeeze's, further).
    pub squeeze: SqueezeParams,
    /// One case per a_B.
    pub cases: Vec<CrushCase>,
    /// Wall-clock seconds of the study.
    pub wall_seconds: f64,
}

/// The grains, one per seed: built at the first a_B (the bulk they are
/// cut from relaxes with it), or the file's.
fn grains(opts: &CrushOptions, runtime: &StudyRuntime) -> Result<Vec<Grain>, HertzError> {
    match &opts.source {
        GrainSource::Build {
            kind,
            radius,
            time_scale,
        } => opts
            .seeds
            .iter()
            .map(|&seed| {
                runtime.part(&format!("grains/seed{seed}"), || {
                    let mut p = crate::scene::builders::grain::GrainParams::new(
                        *kind,
                        *radius,
                        seed,
                        opts.a_bs[0],
                    );
                    p.time_scale = *time_scale;
                    let (scene, summary) = built_grain(&p, opts.threads)?;
                    Ok(Grain {
                        seed,
                        scene,
                        summary: Some(summary),
                    })
                })
            })
            .collect(),
        GrainSource::File { path, .. } => Ok(vec![Grain {
            seed: opts.seeds[0],
            scene: read_grain_file(path, opts.a_bs[0], opts.seeds[0])?,
            summary: None,
        }]),
    }
}

/// Runs the study: every grain at every a_B, natively; writes
/// `crush.json` and `crush.svg` into `out`. With a checkpoint in
/// `runtime`, grains and squeezes are kept as they finish and the squeeze
/// under way is checkpointed, so the same call resumed ends with the same
/// report.
pub fn run_crush(
    opts: &CrushOptions,
    out: &Path,
    runtime: &StudyRuntime,
    progress: &mut dyn FnMut(&Crush),
) -> Result<CrushReport, HertzError> {
    opts.validate()?;
    let start = std::time::Instant::now();
    let runtime = &StudyRuntime {
        threads: opts.threads,
        ..runtime.clone()
    };
    let grains = grains(opts, runtime)?;
    let radius = opts.radius();
    let mut squeeze = SqueezeParams::paper(radius, opts.max_overlap);
    squeeze.records = opts.records;
    let mut cases = Vec::new();
    for &a_b in &opts.a_bs {
        let moduli = Moduli::paper_fits(a_b);
        let e_eff = effective_modulus(moduli.k, moduli.nu);
        let mut force_field = ForceField::paper(a_b);
        force_field.bond_failure = Some(opts.failure);
        let mut crushes = Vec::new();
        for grain in &grains {
            for (rotation, draw) in rotation_draws(grain.seed, opts.rotations)
                .into_iter()
                .enumerate()
            {
                let mut scene = widened(&turned(&grain.scene, draw), radius, &squeeze);
                scene.force_field = force_field.clone();
                let scene = with_side_walls(hertz_squeeze(&scene, &squeeze));
                let key = format!("aB{a_b}/seed{}-rot{rotation}", grain.seed);
                let c = runtime.part(&key, || {
                    let mut c = crush_grain(&scene, grain, a_b, e_eff, opts, runtime, &key)?;
                    (c.rotation, c.rotation_draw) = (rotation, draw);
                    Ok::<_, HertzError>(c)
                })?;
                progress(&c);
                crushes.push(c);
            }
        }
        cases.push(case_of(a_b, moduli, e_eff, radius, crushes));
    }
    let report = CrushReport {
        program: "bpm crush".into(),
        version: crate::VERSION.into(),
        // The overlap compared at as used, given or not.
        options: CrushOptions {
            compare_at: Some(opts.compared_at()),
            ..opts.clone()
        },
        squeeze,
        cases,
        wall_seconds: start.elapsed().as_secs_f64(),
    };
    output::write_report(&report, out)?;
    Ok(report)
}

/// How far the box reaches beside the grain's centre, in x and y, in
/// grain radii: a crushed grain spreads, and its debris flies, sideways.
pub const LATERAL_REACH: f64 = 4.0;

/// `squeeze` (the Hertz squeeze) with four walls at rest on the box's
/// faces in x and y, as the squeezing walls: debris a crushed grain throws
/// sideways stays in the box. They come after the squeezing walls, whose
/// forces stay columns `wall0` and `wall1`. The squeeze runs on to a
/// whole number of record intervals, so its last record is its end, where
/// the fragments are counted.
fn with_side_walls(mut squeeze: Scene) -> Scene {
    let b = squeeze.simbox.clone();
    let stage = &mut squeeze.stages[0];
    stage.steps = stage.steps.div_ceil(stage.record.every) * stage.record.every;
    let template = stage.walls[0].clone();
    for axis in 0..2 {
        for (side, position) in [
            (WallSide::Lo, b.lo[axis]),
            (WallSide::Hi, b.lo[axis] + b.lengths[axis]),
        ] {
            stage.walls.push(FlatWall {
                axis,
                side,
                position,
                velocity: 0.0,
                ..template.clone()
            });
        }
    }
    squeeze
}

/// `grain` in a box reaching [`LATERAL_REACH`] radii (and one wall cutoff
/// more) from its centre in x and y, wider than the box it came in if
/// that was narrower; z as it was.
fn widened(grain: &Scene, radius: f64, squeeze: &SqueezeParams) -> Scene {
    let mut scene = grain.clone();
    let x = &scene.particles.positions;
    let n = x.len().max(1) as f64;
    for k in 0..2 {
        let centre = x.iter().map(|p| p[k]).sum::<f64>() / n;
        let reach = LATERAL_REACH * radius + squeeze.wall_cutoff;
        let lo = scene.simbox.lo[k].min(centre - reach);
        let hi = (scene.simbox.lo[k] + scene.simbox.lengths[k]).max(centre + reach);
        scene.simbox.lo[k] = lo;
        scene.simbox.lengths[k] = hi - lo;
    }
    scene
}

fn crush_grain(
    scene: &Scene,
    grain: &Grain,
    a_b: f64,
    e_eff: f64,
    opts: &CrushOptions,
    runtime: &StudyRuntime,
    key: &str,
) -> Result<Crush, HertzError> {
    let radius = opts.radius();
    let tag = key.replace('/', "-");
    let t = std::time::Instant::now();
    let (stage, stopped, sys) = squeeze_native_system(scene, &tag, runtime, key)?;
    let seconds = t.elapsed().as_secs_f64();
    let (gap, force) = gap_and_force(&stage);
    let broken = stage
        .column("broken_bonds")
        .filter(|b| b.len() == force.len())
        .ok_or_else(|| {
            HertzError::Grain(format!(
                "{tag}: the squeeze recorded no broken-bond count per record"
            ))
        })?;
    let particles = scene.particles.positions.len();
    let bonds = scene.bonds.pairs.len();
    let model = sys.model_as::<BpmModel>().ok_or_else(|| {
        HertzError::Grain(format!("{tag}: the crushed grain is not a bonded model"))
    })?;
    let intact = model.bonds();
    let fragments = Fragments::of(particles, intact.pairs());
    let large = large_fragment_size(particles);
    let curve = squeeze_curve(&gap, &force, radius, e_eff);
    let share = |b: f64| if bonds == 0 { 0.0 } else { b / bonds as f64 };
    let broken_fraction: Vec<f64> = match curve.contact_record {
        Some(c) => broken[c.min(broken.len())..]
            .iter()
            .map(|&b| share(b))
            .collect(),
        None => Vec::new(),
    };
    let points = CurvePoints {
        curve: &curve,
        broken_fraction: &broken_fraction,
    };
    let first_break_record = broken_fraction.iter().position(|&b| b > 0.0);
    let first_break = first_break_record.and_then(|k| points.at(k));
    let compared = match curve.contact_record {
        Some(c) => curve
            .overlap_over_r
            .iter()
            .position(|&x| x >= opts.compared_at())
            .map(|k| {
                // The count recorded then names the bonds broken by then:
                // the engine keeps them in the order they broke.
                let count = broken[c + k] as usize;
                let all = model.broken_bonds();
                if count > all.len() {
                    return Err(HertzError::Grain(format!(
                        "{tag}: record {} counts {count} broken bonds, the engine lists {}",
                        c + k,
                        all.len()
                    )));
                }
                let fragments = fragments_when_broken(particles, intact.pairs(), all, count);
                Ok(CrushState {
                    overlap_over_r: curve.overlap_over_r[k],
                    broken_fraction: share(broken[c + k]),
                    large_fragments: fragments.count_at_least(large),
                    fragments,
                })
            })
            .transpose()?,
        None => None,
    };
    let hertz_end = first_break.map_or(0.25, |b| b.overlap_over_r.min(0.25));
    let hertz_before_break = hertz_deviation(
        &curve.overlap_over_r,
        &curve.normalised_force,
        0.02,
        hertz_end,
    );
    Ok(Crush {
        a_b,
        seed: grain.seed,
        rotation: 0,
        rotation_draw: None,
        grain: grain.summary.clone(),
        particles,
        bonds,
        intact_bonds: intact.len(),
        first_break,
        hertz_before_break,
        // A grain is crushed by bonds breaking: a fall of the force
        // before the first break (a rattle at first touch) is not it.
        crushing: first_break_record
            .and_then(|b| crushing_record(&curve.normalised_force[b..]).map(|k| b + k))
            .and_then(|k| points.at(k)),
        peak: largest(&curve.normalised_force).and_then(|k| points.at(k)),
        large_fragments: fragments.count_at_least(large),
        fragments,
        compared,
        broken_fraction,
        curve,
        seconds,
        stopped,
    })
}

/// The records of a curve with their broken shares.
struct CurvePoints<'a> {
    curve: &'a SqueezeCurve,
    broken_fraction: &'a [f64],
}

impl CurvePoints<'_> {
    /// Record `k` from first contact on.
    fn at(&self, k: usize) -> Option<CurvePoint> {
        let c = self.curve.contact_record?;
        Some(CurvePoint {
            overlap_over_r: *self.curve.overlap_over_r.get(k)?,
            force: *self.curve.force.get(c + k)?,
            normalised_force: *self.curve.normalised_force.get(k)?,
            broken_fraction: *self.broken_fraction.get(k)?,
        })
    }
}

/// The record of the peak before `force` first falls below
/// `1 - FAILURE_DROP` of its largest value so far; none if it never does.
pub fn crushing_record(force: &[f64]) -> Option<usize> {
    let mut peak: Option<usize> = None;
    for (k, &f) in force.iter().enumerate() {
        match peak {
            Some(p) if f < (1.0 - FAILURE_DROP) * force[p] => return Some(p),
            Some(p) if f <= force[p] => {}
            _ => peak = Some(k),
        }
    }
    None
}

/// The record of the largest value (the first of equals); none for none
/// or a NaN.
fn largest(values: &[f64]) -> Option<usize> {
    if values.iter().any(|v| v.is_nan()) {
        return None;
    }
    values
        .iter()
        .enumerate()
        .fold(None, |best: Option<usize>, (k, &v)| match best {
            Some(b) if values[b] >= v => Some(b),
            _ => Some(k),
        })
}

fn case_of(a_b: f64, moduli: Moduli, e_eff: f64, radius: f64, crushes: Vec<Crush>) -> CrushCase {
    let stat = |f: &dyn Fn(&Crush) -> Option<f64>| {
        MeanSd::of(&crushes.iter().filter_map(f).collect::<Vec<_>>())
    };
    CrushCase {
        a_b,
        e_eff,
        first_break_overlap: stat(&|c| c.first_break.map(|p| p.overlap_over_r)),
        crushing_force: stat(&|c| c.crushing.map(|p| p.force / (e_eff * radius * radius))),
        crushing_overlap: stat(&|c| c.crushing.map(|p| p.overlap_over_r)),
        crushed: crushes.iter().filter(|c| c.crushing.is_some()).count(),
        broken_fraction: stat(&|c| c.broken_fraction.last().copied()),
        large_fragments: stat(&|c| Some(c.large_fragments as f64)),
        largest_fragment: stat(&|c| Some(c.fragments.largest_fraction())),
        compared_broken_fraction: stat(&|c| c.compared.as_ref().map(|s| s.broken_fraction)),
        compared_large_fragments: stat(&|c| c.compared.as_ref().map(|s| s.large_fragments as f64)),
        compared_largest_fragment: stat(&|c| {
            c.compared.as_ref().map(|s| s.fragments.largest_fraction())
        }),
        moduli,
        crushes,
    }
}

impl StudyReport for CrushReport {
    const JSON: &'static str = "crush.json";

    fn check(&self) -> Result<(), String> {
        self.options.validate().map_err(|e| e.to_string())
    }

    /// `crush.svg`: [`panels`].
    fn draw(&self, out: &StudyOutput) -> Result<(), OutputError> {
        out.svg_rows("crush.svg", &panels(self), 2)?;
        Ok(())
    }
}

/// The force against the overlap with Hertz's law and the first breaks,
/// the broken bonds against the overlap, and the fragments' sizes by
/// rank at the end.
pub fn panels(report: &CrushReport) -> Vec<Panel> {
    let mut force = Vec::new();
    let mut broken = Vec::new();
    let mut sizes = Vec::new();
    let mut first_breaks = Vec::new();
    let mut crushing = Vec::new();
    for case in &report.cases {
        for c in &case.crushes {
            let label = format!("a_B = {}, seed {} rot {}", c.a_b, c.seed, c.rotation);
            let x = &c.curve.overlap_over_r;
            force.push(Series::new(
                label.clone(),
                x.iter()
                    .copied()
                    .zip(c.curve.normalised_force.iter().copied())
                    .collect(),
                Mark::Line,
            ));
            broken.push(Series::new(
                label.clone(),
                x.iter()
                    .copied()
                    .zip(c.broken_fraction.iter().copied())
                    .collect(),
                Mark::Line,
            ));
            let n = c.particles.max(1) as f64;
            sizes.push(Series::new(
                label,
                c.fragments
                    .sizes
                    .iter()
                    .enumerate()
                    .map(|(k, &s)| ((k + 1) as f64, s as f64 / n))
                    .collect(),
                Mark::LinePoints,
            ));
            first_breaks.extend(
                c.first_break
                    .map(|p| (p.overlap_over_r, p.normalised_force)),
            );
            crushing.extend(c.crushing.map(|p| (p.overlap_over_r, p.normalised_force)));
        }
    }
    let hertz: Vec<(f64, f64)> = (1..=100)
        .map(|k| {
            let x = k as f64 * report.options.max_overlap / 100.0;
            (x, hertz_normalised_force(x))
        })
        .collect();
    force.push(Series::new("Hertz (delta/R)^3/2", hertz, Mark::Line));
    force.push(Series::new("first break", first_breaks, Mark::Points));
    force.push(Series::new("crushing force", crushing, Mark::Rings));
    let f = &report.options.failure;
    let rule = match f.plastic_strain {
        Some(p) if f.breaks => format!("eps_c = {}, eps_p = {p}", f.critical_strain),
        Some(p) => format!("eps_p = {p}, no breaking"),
        None => format!("eps_c = {}", f.critical_strain),
    };
    let radius = report.options.radius();
    vec![
        Panel {
            title: format!("R = {radius} d, {rule}: wall force"),
            x_label: "delta / R".into(),
            y_label: "3 f / (8 R^2 E_eff)".into(),
            series: force,
            ..Panel::default()
        },
        Panel {
            title: "bonds broken".into(),
            x_label: "delta / R".into(),
            y_label: "share of the grain's bonds".into(),
            series: broken,
            ..Panel::default()
        },
        Panel {
            title: "fragments at the end (two particles or more)".into(),
            x_label: "rank".into(),
            y_label: "size / particles".into(),
            log_x: true,
            log_y: true,
            series: sizes,
        },
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The crushing record is the peak before the first fall by the
    /// failure drop, not a later higher peak; small dips do not count.
    #[test]
    fn crushing_is_the_peak_before_the_first_large_fall() {
        let f = [0.0, 1.0, 2.0, 1.9, 2.5, 1.9, 3.0, 4.0];
        // 1.9 after 2.5 is 76% of it: below 80%.
        assert_eq!(crushing_record(&f), Some(4));
        assert_eq!(crushing_record(&[0.0, 1.0, 0.9, 1.2]), None);
        assert_eq!(crushing_record(&[]), None);
        assert_eq!(largest(&[1.0, 3.0, 3.0, 2.0]), Some(1));
        assert_eq!(largest(&[1.0, f64::NAN]), None);
    }

    fn options() -> CrushOptions {
        CrushOptions {
            source: GrainSource::File {
                path: "grain.json".into(),
                radius: 4.0,
            },
            seeds: vec![1],
            a_bs: vec![0.0],
            rotations: 0,
            failure: BondFailure::breaking(0.05),
            max_overlap: 0.5,
            compare_at: None,
            records: 100,
            threads: 1,
        }
    }

    /// Bad options are refused with the value at fault named.
    #[test]
    fn bad_options_are_named() {
        options().validate().unwrap();
        let refused = |change: &dyn Fn(&mut CrushOptions), said: &str| {
            let mut o = options();
            change(&mut o);
            let message = o.validate().unwrap_err().to_string();
            assert!(message.contains(said), "{message:?} lacks {said:?}");
        };
        refused(&|o| o.failure.critical_strain = 0.0, "eps_c = 0");
        refused(&|o| o.failure.plastic_strain = Some(0.06), "eps_p = 0.06");
        refused(
            &|o| {
                o.failure.breaks = false;
                o.failure.smooth = false;
            },
            "neither break nor yield",
        );
        refused(&|o| o.a_bs = vec![0.0, -1.0], "got -1");
        refused(&|o| o.a_bs.clear(), "--a-b");
        refused(&|o| o.max_overlap = 1.0, "--max-overlap");
        refused(
            &|o| o.compare_at = Some(0.56),
            "--compare-at must be in (0, --max-overlap + 0.05 = 0.550000], got 0.56",
        );
        refused(&|o| o.compare_at = Some(0.0), "got 0");
        // Up to the end, round-off aside; a shorter squeeze compares at its
        // end unless told otherwise.
        let mut o = options();
        (o.max_overlap, o.compare_at) = (0.35, Some(0.4));
        o.validate().unwrap();
        o.compare_at = None;
        o.validate().unwrap();
        assert_eq!(o.compared_at(), 0.35 + 0.05);
        assert_eq!(options().compared_at(), DEFAULT_COMPARE_AT);
        refused(&|o| o.records = 1, "--records");
        refused(
            &|o| {
                o.source = GrainSource::File {
                    path: "g".into(),
                    radius: 1.0,
                }
            },
            "--radius",
        );
    }

    /// The fragments at an earlier record put back the bonds broken
    /// after it, and only those.
    #[test]
    fn fragments_when_broken_put_back_the_later_breaks() {
        // A chain 0-1-2-3-4 that lost 1-2, then 3-4; 0-1 and 2-3 stand.
        let intact = [[0, 1], [2, 3]];
        let broken = [[1, 2], [3, 4]];
        let at = |count| fragments_when_broken(5, intact, &broken, count);
        assert_eq!(at(0).sizes, vec![5]);
        assert_eq!(
            (at(1).sizes.clone(), at(1).single_particles),
            (vec![3, 2], 0)
        );
        assert_eq!(
            (at(2).sizes.clone(), at(2).single_particles),
            (vec![2, 2], 1)
        );
        assert_eq!(at(2), Fragments::of(5, intact));
    }

    #[test]
    fn mean_and_spread() {
        assert_eq!(MeanSd::of(&[]), None);
        let m = MeanSd::of(&[1.0, 3.0]).unwrap();
        assert_eq!((m.mean, m.count), (2.0, 2));
        assert!((m.sd - 2f64.sqrt()).abs() < 1e-15);
        assert_eq!(MeanSd::of(&[5.0]).unwrap().sd, 0.0);
    }
}
