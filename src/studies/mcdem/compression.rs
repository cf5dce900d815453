//! Uniaxial compression of a bed of soft spheres (the multi-contact
//! study's calibration case): 514 hydrogel beads in a box with a lid that
//! closes at constant speed to volume fraction 0.85 and opens again, twice;
//! the lid's stress against the volume fraction under plain Hertz and the
//! two closures.
//!
//! The study's bed is a measured packing of 514 beads of diameter 2.1 +-
//! 0.2 cm in a 0.165 x 0.166 x 0.168 m box, volume fraction 0.58; the
//! closures' reference implementation ships it, with diameters 2.149 +-
//! 0.120 cm. Here the bed is built: diameters drawn from a normal
//! distribution of that mean and spread (cut at three standard deviations), centres
//! placed at random in a taller box at volume fraction 0.5, and overlaps
//! removed by moving spheres apart along their lines of centres; the
//! first compression packs it (a random bed jams below the 0.586 of the
//! full box).
//! There is no gravity: the beads' weight in water (density 11.5 kg/m^3
//! above the water's), 0.3 N in all, is 13% of the Hertz lid force at
//! volume fraction 0.65 and 1.4% at 0.85 (docs/protocols.md).

use super::{BoxWalls, Closures, Hydrogel, Variant, WalledBox};
use crate::analysis::plot::{Mark, Panel, Series};
use crate::file_error::FileError;
use crate::scene::{validate, Mass, Scene, StageOutput, StageSpec};
use crate::studies::output::{self, OutputError, StudyOutput, StudyReport};
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, Normal};
use serde::Serialize;
use std::path::Path;

/// Options of `bpm mc-compress`.
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct CompressionOptions {
    /// Number of spheres.
    pub spheres: usize,
    /// Mean sphere diameter (m): the length unit.
    pub mean_diameter: f64,
    /// Standard deviation of the diameters (m).
    pub diameter_sd: f64,
    /// Box edges (m); the lid starts at the top.
    pub box_size: [f64; 3],
    /// Lid speed (m/s).
    pub lid_speed: f64,
    /// Volume fraction at which the lid turns back.
    pub max_fraction: f64,
    /// Compression and decompression cycles.
    pub cycles: usize,
    /// Modulus of the box's walls (Pa).
    pub wall_modulus: f64,
    /// Time step (tau).
    pub dt: f64,
    /// Recorded states per pass of the lid.
    pub records: u64,
    /// Seed of the bed.
    pub seed: u64,
    /// The closures compared with plain Hertz.
    pub closures: Closures,
}

impl Default for CompressionOptions {
    fn default() -> Self {
        Self {
            spheres: 514,
            mean_diameter: 2.149e-2,
            diameter_sd: 0.120e-2,
            box_size: [0.165, 0.166, 0.168],
            lid_speed: 0.1,
            max_fraction: 0.85,
            cycles: 2,
            wall_modulus: 5e7,
            dt: 0.05,
            records: 200,
            seed: 1,
            closures: Closures::default(),
        }
    }
}

/// What can go wrong.
#[derive(Debug, thiserror::Error)]
pub enum CompressionError {
    /// Bad options.
    #[error("{0}")]
    Options(String),
    /// The bed could not be built.
    #[error("building the bed: {0}")]
    Bed(String),
    /// A run stopped.
    #[error("{variant}: {message}")]
    Run {
        /// The closure.
        variant: String,
        /// What stopped it.
        message: String,
    },
    /// A file could not be written.
    #[error(transparent)]
    File(#[from] FileError),
    /// The study stopped before its end (its checkpoint continues it).
    #[error(transparent)]
    Stopped(#[from] crate::studies::StudyStop),
    /// The report or its drawings could not be written or read back.
    #[error(transparent)]
    Output(#[from] crate::studies::output::OutputError),
}

impl CompressionOptions {
    /// Checks the options; the error names the one at fault.
    pub fn validate(&self) -> Result<(), CompressionError> {
        let bad = |m: String| Err(CompressionError::Options(m));
        for (name, v) in [
            ("--mean-diameter", self.mean_diameter),
            ("--lid-speed", self.lid_speed),
            ("--wall-modulus", self.wall_modulus),
            ("--dt", self.dt),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return bad(format!("{name} must be > 0 (got {v})"));
            }
        }
        if !(self.diameter_sd.is_finite() && self.diameter_sd >= 0.0)
            || self.diameter_sd > 0.2 * self.mean_diameter
        {
            return bad(format!(
                "--diameter-sd must lie in [0, 0.2 x --mean-diameter] (got {})",
                self.diameter_sd
            ));
        }
        if self.box_size.iter().any(|&l| !(l.is_finite() && l > 0.0)) {
            return bad(format!(
                "--box must be three positive lengths (got {:?})",
                self.box_size
            ));
        }
        let smallest = self.box_size.iter().copied().fold(f64::INFINITY, f64::min);
        if smallest < 2.0 * self.mean_diameter {
            return bad(format!(
                "--box edges must be at least two mean diameters (got {smallest} m)"
            ));
        }
        if self.spheres == 0 {
            return bad("--spheres must be at least 1".into());
        }
        let start = self.start_fraction();
        // The lid opens to the box's top between cycles: a bed that is
        // jammed there never unloads.
        if start.is_nan() || start >= 0.62 {
            return bad(format!(
                "{} spheres fill the box to volume fraction {start:.3}, at or above random close packing (about 0.62 here): the lid could not open the bed between cycles; use fewer spheres or a larger box",
                self.spheres
            ));
        }
        if self.spheres > MAX_SPHERES {
            return bad(format!(
                "--spheres must be at most {MAX_SPHERES} (got {}): the bed builder checks every pair",
                self.spheres
            ));
        }
        if !(self.max_fraction > start && self.max_fraction < 1.0) {
            return bad(format!(
                "--max-fraction must lie between the bed's starting volume fraction {start:.3} and 1 (got {})",
                self.max_fraction
            ));
        }
        if self.cycles == 0 || self.records == 0 {
            return bad("--cycles and --records must be at least 1".into());
        }
        self.closures.validate().map_err(CompressionError::Options)
    }

    /// The expected volume fraction of the bed in the full box (the mean
    /// sphere volume from the diameter distribution's first three moments,
    /// ignoring the cut at three standard deviations).
    pub fn start_fraction(&self) -> f64 {
        let (m, s) = (self.mean_diameter, self.diameter_sd);
        let mean_cube = m * m * m + 3.0 * m * s * s;
        let solid = self.spheres as f64 * std::f64::consts::PI / 6.0 * mean_cube;
        solid / self.box_size.iter().product::<f64>()
    }
}

/// The bed, in reduced units (lengths in mean diameters).
#[derive(Clone, Debug, Serialize)]
pub struct Bed {
    /// Sphere centres, in `[0, lx] x [0, ly] x [0, start_height]`.
    pub centres: Vec<[f64; 3]>,
    /// Sphere radii.
    pub radii: Vec<f64>,
    /// Box edges; the lid turns back at the top of the box when it opens.
    pub edges: [f64; 3],
    /// Where the lid starts, above the box's top: the bed is built dilute.
    pub start_height: f64,
    /// Sweeps of the overlap removal.
    pub sweeps: u64,
}

impl Bed {
    /// Total sphere volume.
    pub fn solid_volume(&self) -> f64 {
        sphere_volume(&self.radii)
    }
}

/// Most spheres of a bed (its builder checks every pair each sweep).
pub const MAX_SPHERES: usize = 5000;

/// Most steps of one pass of the lid.
const MAX_PASS_STEPS: u64 = 100_000_000;

/// Largest pair overlap left when the bed counts as built (mean
/// diameters): its Hertz force is some 1e-9 of the contact's stiffness.
const BED_OVERLAP: f64 = 1e-6;

/// Builds the bed: diameters, random centres, overlaps removed.
pub fn build_bed(opts: &CompressionOptions) -> Result<Bed, CompressionError> {
    let d = opts.mean_diameter;
    let edges = opts.box_size.map(|l| l / d);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(opts.seed);
    let normal =
        Normal::new(1.0, opts.diameter_sd / d).map_err(|e| CompressionError::Bed(e.to_string()))?;
    let cut = 3.0 * opts.diameter_sd / d;
    let radii: Vec<f64> = (0..opts.spheres)
        .map(|_| loop {
            let x: f64 = normal.sample(&mut rng);
            if (x - 1.0).abs() <= cut {
                break 0.5 * x;
            }
        })
        .collect();
    // A random bed at the study's volume fraction is jammed in this box:
    // it starts dilute in a taller box, and the first compression packs
    // it.
    let solid = sphere_volume(&radii);
    let area = edges[0] * edges[1];
    let tall = [
        edges[0],
        edges[1],
        edges[2].max(solid / (area * BUILT_FRACTION)),
    ];
    let mut centres: Vec<[f64; 3]> = radii
        .iter()
        .map(|&r| [0, 1, 2].map(|k| r + rng.gen::<f64>() * (tall[k] - 2.0 * r)))
        .collect();
    let sweeps = push_apart(&mut centres, &radii, &tall).ok_or_else(|| {
        CompressionError::Bed(format!(
            "spheres still overlap after {MAX_SWEEPS} sweeps at volume fraction {BUILT_FRACTION}"
        ))
    })?;
    Ok(Bed {
        centres,
        radii,
        edges,
        start_height: tall[2],
        sweeps,
    })
}

/// Volume fraction of the bed as built (or lower, if the box is emptier).
pub const BUILT_FRACTION: f64 = 0.5;

/// Total volume of spheres of `radii`.
fn sphere_volume(radii: &[f64]) -> f64 {
    radii
        .iter()
        .map(|r| 4.0 / 3.0 * std::f64::consts::PI * r * r * r)
        .sum()
}

/// Most sweeps of one push-apart.
const MAX_SWEEPS: u64 = 100_000;

/// Moves overlapping spheres apart along their lines of centres, and
/// spheres beyond a face back in, until no pair overlaps by more than
/// [`BED_OVERLAP`]; the sweeps taken, or `None` if they run out.
fn push_apart(centres: &mut [[f64; 3]], radii: &[f64], edges: &[f64; 3]) -> Option<u64> {
    let n = centres.len();
    for sweep in 1..=MAX_SWEEPS {
        for i in 0..n {
            for j in i + 1..n {
                let del = [0, 1, 2].map(|k| centres[j][k] - centres[i][k]);
                let r = (del[0] * del[0] + del[1] * del[1] + del[2] * del[2]).sqrt();
                let overlap = radii[i] + radii[j] - r;
                if overlap <= 0.0 {
                    continue;
                }
                // Each moves half the overlap and a little more, so that a
                // pair once apart stays apart under round-off; coincident
                // centres part along x.
                let (del, r) = if r > 0.0 {
                    (del, r)
                } else {
                    ([1.0, 0.0, 0.0], 1.0)
                };
                let push = 0.5 * overlap * 1.01 / r;
                for k in 0..3 {
                    centres[i][k] -= push * del[k];
                    centres[j][k] += push * del[k];
                }
            }
        }
        for (c, &r) in centres.iter_mut().zip(radii) {
            for k in 0..3 {
                c[k] = c[k].clamp(r, edges[k] - r);
            }
        }
        if largest_overlap(centres, radii) <= BED_OVERLAP {
            return Some(sweep);
        }
    }
    None
}

/// The largest overlap of any two spheres.
pub fn largest_overlap(centres: &[[f64; 3]], radii: &[f64]) -> f64 {
    let mut worst: f64 = 0.0;
    for i in 0..centres.len() {
        for j in i + 1..centres.len() {
            let r = (0..3)
                .map(|k| (centres[j][k] - centres[i][k]).powi(2))
                .sum::<f64>()
                .sqrt();
            worst = worst.max(radii[i] + radii[j] - r);
        }
    }
    worst
}

/// One pass of the lid, recorded.
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
pub struct Pass {
    /// "compress 1", "decompress 1", ...
    pub name: String,
    /// The lid's speed in this pass (m/s): the requested one, rounded so
    /// that the pass is a whole number of recording intervals.
    pub lid_speed: f64,
    /// Volume fraction (sphere volume over the box below the lid).
    pub fraction: Vec<f64>,
    /// Stresses on the walls and the closure's corrections.
    #[serde(flatten)]
    pub walls: BoxWalls,
}

/// One closure's run.
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
pub struct Run {
    /// The closure's name.
    pub variant: String,
    /// Every pass, in order (up to the one that failed, if one did).
    pub passes: Vec<Pass>,
    /// Wall-clock time of the run (s).
    pub seconds: f64,
    /// Why the run stopped early, if it did (the other closures still
    /// run).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stopped: Option<String>,
}

/// The study's result.
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
pub struct CompressionReport {
    /// The command that wrote it.
    pub command: String,
    /// The options.
    pub options: CompressionOptions,
    /// The beads, in physical units (diameter: the mean).
    pub hydrogel: Hydrogel,
    /// The time unit (s).
    pub time_unit: f64,
    /// Lid speed (d / tau).
    pub reduced_lid_speed: f64,
    /// Volume fraction of the bed in the full box.
    pub start_fraction: f64,
    /// Sweeps the bed's overlap removal took.
    pub bed_sweeps: u64,
    /// Volume fraction of the bed as built, below the lid's starting
    /// height.
    pub built_fraction: f64,
    /// Steps per pass of the lid after the first (which starts from the
    /// built bed's height).
    pub steps_per_pass: u64,
    /// The closures compared.
    pub variants: Vec<Variant>,
    /// One run per closure.
    pub runs: Vec<Run>,
}

/// The lid's turning points and steps.
#[derive(Clone, Copy, Debug, PartialEq)]
struct LidPlan {
    /// Where the lid turns back up (d): the bed at `max_fraction`.
    bottom: f64,
    /// Steps between recorded rows.
    every: u64,
    /// Steps of a pass between the box's top and the bottom.
    steps: u64,
    /// Steps of the first pass, from the built bed's height.
    first_steps: u64,
}

/// Whole recording intervals per pass, so the lid turns exactly at the top
/// of the box and at the bottom; the first pass starts at the built bed's
/// height and takes as many intervals as it needs at the same speed.
fn lid_plan(
    bed: &Bed,
    opts: &CompressionOptions,
    hydrogel: &Hydrogel,
) -> Result<LidPlan, CompressionError> {
    let [lx, ly, lz] = bed.edges;
    let bottom = bed.solid_volume() / (lx * ly * opts.max_fraction);
    if bottom >= lz {
        return Err(CompressionError::Options(format!(
            "the bed as built fills the box to {:.4}, at or above --max-fraction {}: raise it",
            bed.solid_volume() / (lx * ly * lz),
            opts.max_fraction
        )));
    }
    let speed = hydrogel.reduced_speed(opts.lid_speed);
    let intervals = |travel: f64, every: f64| (travel / speed / opts.dt / every).ceil();
    let every = intervals(lz - bottom, opts.records as f64);
    let first = intervals(bed.start_height - bottom, every);
    let steps = every * opts.records as f64;
    let longest = steps.max(first * every);
    if longest.is_nan() || longest > MAX_PASS_STEPS as f64 {
        return Err(CompressionError::Options(format!(
            "a pass of the lid would take {longest:.3e} steps, more than {MAX_PASS_STEPS}: raise --lid-speed or --dt"
        )));
    }
    Ok(LidPlan {
        bottom,
        every: every as u64,
        steps: steps as u64,
        first_steps: (first * every) as u64,
    })
}

/// The compression of `bed` with `variant` as a scene (reduced units:
/// mean diameter, E, the mass of a sphere of the mean diameter); the lid
/// is granular wall 1, the side walls 2 to 5. Fails if the lid's passes
/// cannot be planned (the bed too full, or too many steps).
pub fn scene(
    bed: &Bed,
    variant: &Variant,
    opts: &CompressionOptions,
    hydrogel: &Hydrogel,
) -> Result<Scene, CompressionError> {
    let [lx, ly, lz] = bed.edges;
    let walled = WalledBox::new([lx, ly], bed.start_height, hydrogel, opts.wall_modulus);
    let LidPlan {
        bottom,
        every,
        steps,
        first_steps,
    } = lid_plan(bed, opts, hydrogel)?;
    let mut stages = Vec::new();
    for cycle in 1..=opts.cycles {
        let (top, down_steps) = if cycle == 1 {
            (bed.start_height, first_steps)
        } else {
            (lz, steps)
        };
        let passes = [
            ("compress", top, bottom, down_steps),
            ("decompress", bottom, lz, steps),
        ];
        for (name, from, to, pass_steps) in passes {
            let velocity = (to - from) / (pass_steps as f64 * opts.dt);
            let mut stage = StageSpec::hold(&format!("{name} {cycle}"), pass_steps, opts.dt);
            stage.granular_walls = walled.walls(from, velocity);
            stage.record.every = every;
            stages.push(stage);
        }
    }
    Ok(walled.scene(
        format!(
            "{} hydrogel spheres compressed to volume fraction {} and back, {} (bpm mc-compress)",
            bed.radii.len(),
            opts.max_fraction,
            variant.name
        ),
        opts.seed,
        bed.centres.clone(),
        bed.radii.clone(),
        Mass::PerParticle(bed.radii.iter().map(|r| (2.0 * r).powi(3)).collect()),
        hydrogel,
        variant,
        stages,
    ))
}

/// Builds the bed and compresses it with every closure (on one thread);
/// `command` is recorded. With a checkpoint in `runtime`, each closure's
/// run is kept in it as it finishes, and the run under way is continued.
pub fn run_compression(
    opts: &CompressionOptions,
    command: &str,
    runtime: &crate::studies::StudyRuntime,
) -> Result<(CompressionReport, Scene), CompressionError> {
    // One thread: the bed is too small for two to pay.
    let runtime = crate::studies::StudyRuntime {
        threads: 1,
        ..runtime.clone()
    };
    opts.validate()?;
    let hydrogel = Hydrogel::table_1(opts.mean_diameter);
    let bed = build_bed(opts)?;
    let variants = opts.closures.variants();
    let [lx, ly, _] = bed.edges;
    let solid = bed.solid_volume();
    // Each pass turns at its end: one compression and one decompression
    // per cycle.
    let mut runs = Vec::new();
    let mut first_scene = None;
    let mut steps_per_pass = 0;
    let read_passes = |stages: &[StageOutput], specs: &[StageSpec]| -> Vec<Pass> {
        stages
            .iter()
            .zip(specs)
            .map(|(stage, spec)| {
                let walls = BoxWalls::read(stage, [lx, ly], hydrogel.youngs_modulus);
                Pass {
                    name: stage.name.clone(),
                    lid_speed: hydrogel.physical_speed(spec.granular_walls[1].velocity.abs()),
                    fraction: walls.lid.iter().map(|h| solid / (lx * ly * h)).collect(),
                    walls,
                }
            })
            .collect()
    };
    for variant in &variants {
        let scene = scene(&bed, variant, opts, &hydrogel)?;
        let fail = |message: String| CompressionError::Run {
            variant: variant.name.clone(),
            message,
        };
        validate(&scene).map_err(|e| fail(e.to_string()))?;
        steps_per_pass = scene.stages[1].steps;
        let run = runtime.part(&variant.name, || {
            let outcome = runtime.run_scene(&variant.name, &scene)?;
            let passes = read_passes(&outcome.stages, &scene.stages);
            Ok::<_, CompressionError>(Run {
                variant: variant.name.clone(),
                passes,
                seconds: outcome.wall_seconds,
                stopped: outcome.error.map(|e| e.to_string()),
            })
        })?;
        runs.push(run);
        first_scene.get_or_insert(scene);
    }
    let report = CompressionReport {
        command: command.to_string(),
        options: opts.clone(),
        hydrogel,
        time_unit: hydrogel.time_unit(),
        reduced_lid_speed: hydrogel.reduced_speed(opts.lid_speed),
        start_fraction: solid / bed.edges.iter().product::<f64>(),
        bed_sweeps: bed.sweeps,
        built_fraction: solid / (lx * ly * bed.start_height),
        steps_per_pass,
        variants,
        runs,
    };
    Ok((report, first_scene.expect("at least one closure ran")))
}

/// Interpolated lid stress of `pass` at volume fraction `phi` (fractions
/// in either order), `None` outside its range (with a margin of 1e-9 for
/// the round-off of the turning points).
pub fn stress_at(pass: &Pass, phi: f64) -> Option<f64> {
    const MARGIN: f64 = 1e-9;
    pass.fraction
        .windows(2)
        .zip(pass.walls.lid_stress.windows(2))
        .find_map(|(f, s)| {
            let (lo, hi) = (f[0].min(f[1]), f[0].max(f[1]));
            (lo - MARGIN <= phi && phi <= hi + MARGIN && hi > lo)
                .then(|| s[0] + (phi - f[0]) / (f[1] - f[0]) * (s[1] - s[0]))
        })
}

/// The lid stress (Pa) of each closure's last compression at volume
/// fractions 0.60 to 0.85, with its ratio to plain Hertz's.
pub fn table(report: &CompressionReport) -> String {
    let last_compression = |run: &Run| {
        run.passes
            .iter()
            .rev()
            .find(|p| p.name.starts_with("compress"))
            .cloned()
    };
    let hertz = report.runs.first().and_then(last_compression);
    let mut out = format!(
        "{:<34} {:>6} {:>11} {:>9}\n",
        "closure (last compression)", "phi", "lid (Pa)", "/ Hertz"
    );
    for run in &report.runs {
        let Some(pass) = last_compression(run) else {
            continue;
        };
        for phi in [0.60, 0.65, 0.70, 0.75, 0.80, 0.85] {
            let Some(s) = stress_at(&pass, phi) else {
                continue;
            };
            let ratio = hertz
                .as_ref()
                .and_then(|h| stress_at(h, phi))
                .map_or(f64::NAN, |h| s / h);
            out += &format!("{:<34} {phi:>6.2} {s:>11.4e} {ratio:>9.3}\n", run.variant);
        }
    }
    for run in &report.runs {
        let (largest, switched) = run
            .passes
            .iter()
            .map(|p| p.walls.extremes())
            .fold((0.0, 0.0), |a, b| (f64::max(a.0, b.0), f64::max(a.1, b.1)));
        out += &format!(
            "{}: {:.0} s; largest correction {largest:.4} R, at most {switched} contact ends switched off in a recorded state\n",
            run.variant, run.seconds
        );
        if let Some(why) = &run.stopped {
            out += &format!("{} stopped: {why}\n", run.variant);
        }
    }
    out
}

/// Writes `compression.json`, `compression.svg` and the Hertz run's scene
/// (`scene.json`, the bed and protocol) into `dir`.
pub fn write_report(
    report: &CompressionReport,
    scene: &Scene,
    dir: &Path,
) -> Result<(), CompressionError> {
    let out = output::write_report(report, dir)?;
    out.json("scene.json", scene)?;
    Ok(())
}

impl StudyReport for CompressionReport {
    const JSON: &'static str = "compression.json";

    /// `compression.svg`: the lid stress against the volume fraction in
    /// the last cycle, linear and logarithmic.
    fn draw(&self, out: &StudyOutput) -> Result<(), OutputError> {
        let report = self;
        let cycle_panel = |cycle: usize, log_y: bool| {
            let series = report
                .runs
                .iter()
                .flat_map(|run| {
                    run.passes
                        .iter()
                        .filter(move |p| p.name.ends_with(&format!(" {cycle}")))
                        .map(move |p| {
                            let points = p
                                .fraction
                                .iter()
                                .copied()
                                .zip(p.walls.lid_stress.iter().copied())
                                .collect();
                            let mark = if p.name.starts_with("compress") {
                                Mark::Line
                            } else {
                                Mark::Points
                            };
                            Series::new(format!("{}, {}", run.variant, p.name), points, mark)
                        })
                })
                .collect();
            Panel {
                title: format!("cycle {cycle}: lid stress"),
                x_label: "volume fraction".into(),
                y_label: "lid stress (Pa)".into(),
                log_y,
                series,
                ..Panel::default()
            }
        };
        let cycles = report.options.cycles;
        let panels = vec![cycle_panel(cycles, false), cycle_panel(cycles, true)];
        out.svg("compression.svg", &panels)?;
        Ok(())
    }
}
