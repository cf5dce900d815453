//! Spheres squeezed in a rigid box (the multi-contact study's Appendix B):
//! one sphere, and nine in a body-centred cubic cell (eight corners and the
//! centre), in a box whose walls touch them; the lid closes at constant
//! speed. The stress on the lid and on the side walls against the lid's
//! displacement over the radius shows how far each closure lets a sphere
//! spread sideways: plain Hertz gives a single sphere no side stress at
//! all.
//!
//! The study gives the box only as "rigid", so its walls here touch the
//! spheres at the start: edge `d` for one sphere, `(1 + 2 / sqrt 3) d` for
//! the cell, whose centre touches all eight corners. Its walls are of
//! modulus 5e7 Pa (the study's Fig. B.1), with the spheres' Poisson's
//! ratio, restitution and friction.

use super::{BoxWalls, Closures, Hydrogel, Variant, WalledBox};
use crate::analysis::plot::{Mark, Panel, Series};
use crate::file_error::FileError;
use crate::scene::{validate, Mass, Scene, StageSpec};
use crate::studies::output::{self, OutputError, StudyOutput, StudyReport};
use serde::Serialize;
use std::path::Path;

/// Options of `bpm mc-box`.
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct BoxOptions {
    /// Sphere diameter (m); 2 mm in the study.
    pub diameter: f64,
    /// Lid speed (m/s); 0.01 in the study.
    pub lid_speed: f64,
    /// Modulus of the box's walls (Pa).
    pub wall_modulus: f64,
    /// How far the lid goes, over the sphere radius.
    pub max_displacement: f64,
    /// Time step (tau).
    pub dt: f64,
    /// Recorded states per run.
    pub records: u64,
    /// The closures compared with plain Hertz.
    pub closures: Closures,
}

impl Default for BoxOptions {
    fn default() -> Self {
        Self {
            diameter: 2e-3,
            lid_speed: 0.01,
            wall_modulus: 5e7,
            max_displacement: 0.5,
            dt: 0.05,
            records: 100,
            closures: Closures::default(),
        }
    }
}

/// Most steps of one squeeze.
const MAX_STEPS: f64 = 1e8;

/// What can go wrong.
#[derive(Debug, thiserror::Error)]
pub enum BoxError {
    /// Bad options.
    #[error("{0}")]
    Options(String),
    /// A run stopped.
    #[error("{arrangement} with {variant}: {message}")]
    Run {
        /// The arrangement.
        arrangement: &'static str,
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

impl BoxOptions {
    /// Checks the options; the error names the one at fault.
    pub fn validate(&self) -> Result<(), BoxError> {
        let positive = [
            ("--diameter", self.diameter),
            ("--lid-speed", self.lid_speed),
            ("--wall-modulus", self.wall_modulus),
            ("--max-displacement", self.max_displacement),
            ("--dt", self.dt),
        ];
        for (name, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return Err(BoxError::Options(format!("{name} must be > 0 (got {v})")));
            }
        }
        if self.max_displacement >= 1.0 {
            return Err(BoxError::Options(format!(
                "--max-displacement must be below 1 radius (got {}): the lid would reach the sphere's centre",
                self.max_displacement
            )));
        }
        if self.records == 0 {
            return Err(BoxError::Options("--records must be at least 1".into()));
        }
        let hydrogel = Hydrogel::table_1(self.diameter);
        let steps = 0.5 * self.max_displacement / hydrogel.reduced_speed(self.lid_speed) / self.dt;
        if steps.is_nan() || steps > MAX_STEPS {
            return Err(BoxError::Options(format!(
                "the squeeze would take {steps:.3e} steps, more than {MAX_STEPS:e}: raise --lid-speed or --dt"
            )));
        }
        self.closures.validate().map_err(BoxError::Options)
    }
}

/// The two arrangements.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Arrangement {
    /// One sphere in a cube of edge `d`.
    Single,
    /// Eight corner spheres and a centre one in a cube of edge `(1 + 2 /
    /// sqrt 3) d`.
    Bcc,
}

impl Arrangement {
    /// Its name.
    pub fn name(self) -> &'static str {
        match self {
            Arrangement::Single => "single sphere",
            Arrangement::Bcc => "bcc cell",
        }
    }

    /// Sphere centres (d units) and the box edge.
    fn spheres(self) -> (Vec<[f64; 3]>, f64) {
        let r = 0.5;
        match self {
            Arrangement::Single => (vec![[r; 3]], 1.0),
            Arrangement::Bcc => {
                // Corner to centre is half the cube diagonal: one diameter.
                let a = 2.0 / 3f64.sqrt();
                let mut x = Vec::with_capacity(9);
                for k in 0..8 {
                    let at = |bit: usize| r + a * ((k >> bit) & 1) as f64;
                    x.push([at(0), at(1), at(2)]);
                }
                x.push([r + 0.5 * a; 3]);
                (x, 1.0 + a)
            }
        }
    }
}

/// One squeeze: stresses against the lid's displacement.
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
pub struct Curve {
    /// The arrangement.
    pub arrangement: Arrangement,
    /// The closure's name.
    pub variant: String,
    /// Lid displacement over the sphere radius.
    pub displacement: Vec<f64>,
    /// Stresses on the walls and the closure's corrections.
    #[serde(flatten)]
    pub walls: BoxWalls,
}

/// The study's result.
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
pub struct BoxReport {
    /// The command that wrote it.
    pub command: String,
    /// The options.
    pub options: BoxOptions,
    /// The spheres, in physical units.
    pub hydrogel: Hydrogel,
    /// The time unit (s).
    pub time_unit: f64,
    /// The lid speed (d / tau).
    pub reduced_lid_speed: f64,
    /// Steps per run.
    pub steps: u64,
    /// The closures compared.
    pub variants: Vec<Variant>,
    /// One curve per arrangement and closure.
    pub curves: Vec<Curve>,
}

/// The squeeze of `arrangement` with `variant`, as a scene (reduced units:
/// d, E and the sphere mass); the lid is wall 1, the side walls 2 to 5.
pub fn scene(
    arrangement: Arrangement,
    variant: &Variant,
    opts: &BoxOptions,
    hydrogel: &Hydrogel,
) -> Scene {
    let (positions, edge) = arrangement.spheres();
    let n = positions.len();
    let walled = WalledBox::new([edge; 2], edge, hydrogel, opts.wall_modulus);
    let speed = hydrogel.reduced_speed(opts.lid_speed);
    let travel = opts.max_displacement * 0.5;
    // A whole number of recording intervals, so the last row is at the
    // full travel.
    let every = (travel / speed / opts.dt / opts.records as f64).ceil() as u64;
    let steps = every * opts.records;
    let mut stage = StageSpec::hold("squeeze", steps, opts.dt);
    stage.granular_walls = walled.walls(edge, -speed);
    stage.record.every = every;
    walled.scene(
        format!(
            "{} squeezed in a rigid box, {} (bpm mc-box)",
            arrangement.name(),
            variant.name
        ),
        1,
        positions,
        vec![0.5; n],
        Mass::Uniform(1.0),
        hydrogel,
        variant,
        vec![stage],
    )
}

/// Runs every arrangement with every closure (on one thread); `command`
/// is recorded. With a checkpoint in `runtime`, each squeeze is kept in it
/// as it finishes, and the one under way is continued.
pub fn run_box(
    opts: &BoxOptions,
    command: &str,
    runtime: &crate::studies::StudyRuntime,
) -> Result<BoxReport, BoxError> {
    let runtime = crate::studies::StudyRuntime {
        threads: 1,
        ..runtime.clone()
    };
    opts.validate()?;
    let hydrogel = Hydrogel::table_1(opts.diameter);
    let variants = opts.closures.variants();
    let mut curves = Vec::new();
    let mut steps = 0;
    for arrangement in [Arrangement::Single, Arrangement::Bcc] {
        for variant in &variants {
            let scene = scene(arrangement, variant, opts, &hydrogel);
            let fail = |message: String| BoxError::Run {
                arrangement: arrangement.name(),
                variant: variant.name.clone(),
                message,
            };
            validate(&scene).map_err(|e| fail(e.to_string()))?;
            steps = scene.stages[0].steps;
            let key = format!("{}/{}", arrangement.name(), variant.name);
            let curve = runtime.part(&key, || {
                let outcome = runtime.run_scene(&key, &scene)?;
                if let Some(err) = outcome.error {
                    return Err(fail(err.to_string()));
                }
                let edge = scene.simbox.lengths[0] - 1.0;
                let walls = BoxWalls::read(&outcome.stages[0], [edge; 2], hydrogel.youngs_modulus);
                Ok(Curve {
                    arrangement,
                    variant: variant.name.clone(),
                    displacement: walls.lid.iter().map(|z| (edge - z) / 0.5).collect(),
                    walls,
                })
            })?;
            curves.push(curve);
        }
    }
    Ok(BoxReport {
        command: command.to_string(),
        options: opts.clone(),
        hydrogel,
        time_unit: hydrogel.time_unit(),
        reduced_lid_speed: hydrogel.reduced_speed(opts.lid_speed),
        steps,
        variants,
        curves,
    })
}

/// Linear interpolation of `y(x)` at `at` (x increasing), `None` outside.
pub fn at_displacement(x: &[f64], y: &[f64], at: f64) -> Option<f64> {
    let k = x.windows(2).position(|w| w[0] <= at && at <= w[1])?;
    let t = (at - x[k]) / (x[k + 1] - x[k]);
    Some(y[k] + t * (y[k + 1] - y[k]))
}

/// The lid and side stresses (Pa) of every curve at lid displacements
/// 0.1 to 0.5 R (as far as the curves reach), with the ratio of each
/// closure's lid stress to plain Hertz's.
pub fn table(report: &BoxReport) -> String {
    let marks = [0.1, 0.2, 0.3, 0.4, 0.5];
    let mut out = format!("{:<14} {:<34} {:>6}", "arrangement", "closure", "u/R");
    out += &format!(
        " {:>11} {:>11} {:>9}\n",
        "lid (Pa)", "sides (Pa)", "lid/Hertz"
    );
    for c in &report.curves {
        let hertz = report
            .curves
            .iter()
            .find(|h| h.arrangement == c.arrangement && h.variant == report.variants[0].name);
        for &u in &marks {
            let (Some(lid), Some(side)) = (
                at_displacement(&c.displacement, &c.walls.lid_stress, u),
                at_displacement(&c.displacement, &c.walls.side_stress, u),
            ) else {
                continue;
            };
            let ratio = hertz
                .and_then(|h| at_displacement(&h.displacement, &h.walls.lid_stress, u))
                .map_or(f64::NAN, |h| lid / h);
            out += &format!(
                "{:<14} {:<34} {u:>6.2} {lid:>11.4e} {side:>11.4e} {ratio:>9.3}\n",
                c.arrangement.name(),
                c.variant
            );
        }
    }
    for c in &report.curves {
        let (largest, switched) = c.walls.extremes();
        out += &format!(
            "{} with {}: largest correction {largest:.4} R, at most {switched} contact ends switched off in a recorded state\n",
            c.arrangement.name(),
            c.variant
        );
    }
    out
}

/// Writes `rigid_box.json`, `rigid_box.svg` and each run's scene
/// (`scenes/<arrangement>-<law>.json`) into `dir`.
pub fn write_report(report: &BoxReport, dir: &Path) -> Result<(), BoxError> {
    let out = output::write_report(report, dir)?;
    write_scenes(report, &out)
}

impl StudyReport for BoxReport {
    const JSON: &'static str = "rigid_box.json";

    /// `rigid_box.svg`: lid and side-wall stress against the lid's
    /// displacement, per arrangement.
    fn draw(&self, out: &StudyOutput) -> Result<(), OutputError> {
        let report = self;
        let mut panels = Vec::new();
        for arrangement in [Arrangement::Single, Arrangement::Bcc] {
            let curves = || {
                report
                    .curves
                    .iter()
                    .filter(move |c| c.arrangement == arrangement)
            };
            let pts = |c: &Curve, y: &[f64]| {
                c.displacement
                    .iter()
                    .copied()
                    .zip(y.iter().copied())
                    .collect()
            };
            for (what, lid) in [("lid", true), ("side walls", false)] {
                panels.push(Panel {
                    title: format!("{}: {what}", arrangement.name()),
                    x_label: "lid displacement / R".into(),
                    y_label: format!("{what} stress (Pa)"),
                    series: curves()
                        .map(|c| {
                            let y = if lid {
                                &c.walls.lid_stress
                            } else {
                                &c.walls.side_stress
                            };
                            Series::new(c.variant.clone(), pts(c, y), Mark::Line)
                        })
                        .collect(),
                    ..Panel::default()
                });
            }
        }
        out.svg("rigid_box.svg", &panels)?;
        Ok(())
    }
}

/// Each run's scene, for `bpm cross-check` (a few kB each), as
/// `scenes/<arrangement>-<law>.json`.
fn write_scenes(report: &BoxReport, out: &StudyOutput) -> Result<(), BoxError> {
    let dir = out.dir();
    let hydrogel = Hydrogel::table_1(report.options.diameter);
    let scenes = dir.join("scenes");
    std::fs::create_dir_all(&scenes).map_err(FileError::on("creating", &scenes))?;
    for arrangement in [Arrangement::Single, Arrangement::Bcc] {
        for variant in &report.variants {
            let law = variant
                .name
                .split(' ')
                .next()
                .unwrap_or("law")
                .to_lowercase();
            let shape = arrangement.name().split(' ').next().unwrap_or("box");
            let path = scenes.join(format!("{shape}-{law}.json"));
            let text =
                serde_json::to_string(&scene(arrangement, variant, &report.options, &hydrogel))
                    .expect("a scene serialises");
            crate::whole_file::write_whole(&path, text.as_bytes())?;
        }
    }
    Ok(())
}
