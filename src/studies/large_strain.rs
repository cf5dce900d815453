//! Large compression (`bpm large-strain`, docs/protocols.md "Large
//! compression"): the bulk solid compressed isotropically, and one grain
//! squeezed by a shrinking spherical wall, to 60% volumetric strain, with
//! the pressure against the strain and checks that nothing is lost on the
//! way (every particle kept and finite, no bond collapsed or torn, no
//! engine error).
//!
//! The compression runs in equal chunks of strain; after each chunk the
//! state is measured: the material's volumetric strain from the bonds,
//! `1 - sum r^3 / sum r0^3` (the multibody term's own volume measure, summed
//! over the whole body), the shortest and longest bond against its
//! reference length, and the pressure. For the bulk solid the pressure is
//! the virial pressure and the box gives the imposed strain; for the
//! grain it is the wall's total force over the area of the sphere through
//! the outermost particle centres plus d/2, and the wall's radius gives
//! the imposed strain.

pub mod cli;

use crate::analysis::plot::{Mark, Panel, Series};
use crate::engine::SphereWall;
use crate::file_error::FileError;
use crate::kernels::Separation;
use crate::options::{require_positive_up_to, require_within, InvalidOption};
use crate::scene::builders::grain::{GrainKind, GrainParams};
use crate::scene::{build_system, protocols, run_scene, ForceField, RunOptions, Scene, StageSpec};
use crate::studies::calibration::paper_solid;
use crate::studies::hertz::{built_grain, HertzError};
use crate::studies::output::{self, OutputError, Provenance, StudyOutput, StudyReport};
use crate::verify::engines::HarnessError;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Why the study could not finish (a run that blows up is a result, not an
/// error: it is recorded with its message).
#[derive(Debug, thiserror::Error)]
pub enum LargeStrainError {
    /// An option is out of range.
    #[error(transparent)]
    Invalid(#[from] InvalidOption),
    /// The solid could not be built.
    #[error(transparent)]
    Harness(#[from] HarnessError),
    /// The grain could not be built.
    #[error(transparent)]
    Grain(#[from] HertzError),
    /// The report could not be written.
    #[error(transparent)]
    File(#[from] FileError),
    /// The report or its drawings could not be written or read back.
    #[error(transparent)]
    Output(#[from] OutputError),
}

/// What `bpm large-strain` runs.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct LargeStrainOptions {
    /// Multibody strengths (k d).
    pub a_b: Vec<f64>,
    /// The zero-net-multibody variant instead of the paper's model.
    pub zero_net: bool,
    /// Seed of the solid and the grain.
    pub seed: u64,
    /// Volumetric strain to reach.
    pub volumetric_strain: f64,
    /// Timestep (tau).
    pub dt: f64,
    /// Box side of the bulk solid (d); 0 skips it.
    pub size: f64,
    /// True strain rate of the bulk compression, per dimension (1 / tau).
    pub rate: f64,
    /// Grain radius (d); 0 skips the grain.
    pub radius: f64,
    /// Grain kind.
    pub kind: GrainKind,
    /// Speed of the spherical wall (d / tau, inwards).
    pub wall_speed: f64,
    /// Stiffness of the spherical wall (k): stiff, so the grain's surface
    /// stays close to the wall under pressures of order K.
    pub wall_stiffness: f64,
    /// Measured states along the compression.
    pub chunks: usize,
}

impl Default for LargeStrainOptions {
    fn default() -> Self {
        Self {
            a_b: vec![3.0, 0.0, -0.5, -0.9],
            zero_net: false,
            seed: 1,
            volumetric_strain: 0.6,
            dt: 0.1,
            size: 10.0,
            rate: 1e-4,
            radius: 6.0,
            kind: GrainKind::Smoother,
            wall_speed: 5e-4,
            wall_stiffness: 20.0,
            chunks: 30,
        }
    }
}

impl LargeStrainOptions {
    /// Checks every option; the message names the option.
    pub fn validate(&self) -> Result<(), InvalidOption> {
        if self.a_b.is_empty() || self.a_b.iter().any(|a| !a.is_finite()) {
            return Err(InvalidOption::new("--a-b", "needs finite values (k d)"));
        }
        require_positive_up_to("--strain", &[self.volumetric_strain], 0.8, "")?;
        require_positive_up_to("--dt", &[self.dt], 0.3, "tau")?;
        require_within("--size", &[self.size], (4.0, 40.0), true, "d")?;
        require_within("--radius", &[self.radius], (3.0, 20.0), true, "d")?;
        require_positive_up_to("--rate", &[self.rate], 1e-2, "/ tau")?;
        require_positive_up_to("--wall-speed", &[self.wall_speed], 0.05, "d/tau")?;
        require_positive_up_to("--wall-stiffness", &[self.wall_stiffness], 100.0, "k")?;
        if !(2..=1000).contains(&self.chunks) {
            return Err(InvalidOption::new(
                "--chunks",
                format!("must be in [2, 1000], got {}", self.chunks),
            ));
        }
        Ok(())
    }
}

/// One measured state (the first: the stress-free start, pressure 0).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct State {
    /// Simulated time since the compression began (tau).
    #[serde(deserialize_with = "crate::json_nan::nan_if_null")]
    pub time: f64,
    /// Imposed volumetric strain: from the box (bulk) or the wall (grain).
    #[serde(deserialize_with = "crate::json_nan::nan_if_null")]
    pub imposed_strain: f64,
    /// The material's volumetric strain, `1 - sum r^3 / sum r0^3` over bonds.
    #[serde(deserialize_with = "crate::json_nan::nan_if_null")]
    pub bond_strain: f64,
    /// Pressure (k / d^2): virial (bulk) or wall force over area (grain).
    #[serde(deserialize_with = "crate::json_nan::nan_if_null")]
    pub pressure: f64,
    /// Shortest bond over its reference length.
    #[serde(deserialize_with = "crate::json_nan::nan_if_null")]
    pub shortest_bond: f64,
    /// Longest bond over its reference length.
    #[serde(deserialize_with = "crate::json_nan::nan_if_null")]
    pub longest_bond: f64,
}

/// One compression.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Compression {
    /// "bulk" or "grain".
    pub body: String,
    /// a_B (k d).
    pub a_b: f64,
    /// Particles.
    pub particles: usize,
    /// Measured states, from the start.
    pub states: Vec<State>,
    /// Whether it reached the target strain with every particle kept and
    /// finite and no bond collapsed or torn.
    pub complete: bool,
    /// The engine's error or the check that failed, if any.
    pub failure: Option<String>,
    /// Wall-clock seconds.
    pub seconds: f64,
}

/// The study's record (`large_strain.json`).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct LargeStrainReport {
    /// Program, version and the command that wrote it.
    #[serde(flatten)]
    pub provenance: Provenance,
    /// The options.
    pub options: LargeStrainOptions,
    /// Every compression.
    pub compressions: Vec<Compression>,
}

/// The bonds' volume measure and extreme strains of a system's state:
/// `(sum r^3 / sum r0^3, shortest r / r0, longest r / r0)`.
fn bond_state(sys: &crate::engine::System) -> (f64, f64, f64) {
    let Some(bpm) = sys.model_as::<crate::engine::BpmModel>() else {
        return (f64::NAN, f64::NAN, f64::NAN);
    };
    let sep = sys.simbox.minimum_image();
    let x = &sys.particles.x;
    let bonds = bpm.bonds();
    let (mut v, mut v0) = (0.0, 0.0);
    let (mut shortest, mut longest) = (f64::INFINITY, 0.0f64);
    for (b, &r0) in bonds.entries.iter().zip(&bonds.r0) {
        let r = sep.distance(&x[b.i as usize], &x[b.j as usize]);
        v += r * r * r;
        v0 += r0 * r0 * r0;
        shortest = shortest.min(r / r0);
        longest = longest.max(r / r0);
    }
    (v / v0, shortest, longest)
}

/// Runs the study; `log` receives each line of progress.
pub fn run_large_strain(
    opts: &LargeStrainOptions,
    threads: usize,
    command: &str,
    log: &mut dyn FnMut(&str),
) -> Result<LargeStrainReport, LargeStrainError> {
    opts.validate()?;
    let mut report = LargeStrainReport {
        provenance: Provenance::new(command),
        options: opts.clone(),
        compressions: Vec::new(),
    };
    let field = |a_b: f64| ForceField {
        zero_net_multibody: opts.zero_net,
        ..ForceField::paper(a_b)
    };
    if opts.size > 0.0 {
        let (solid, summary) = paper_solid(opts.size, opts.seed, threads)?;
        log(&format!(
            "bulk solid L={} seed {}: {} particles",
            opts.size, opts.seed, summary.particles
        ));
        for &a_b in &opts.a_b {
            let mut scene = solid.clone();
            scene.force_field = field(a_b);
            scene.particles.velocities = None;
            let c = compress_bulk(&scene, a_b, opts, threads, log);
            report.compressions.push(c);
        }
    }
    if opts.radius > 0.0 {
        let p = GrainParams::new(opts.kind, opts.radius, opts.seed, 0.0);
        let (grain, summary) = built_grain(&p, threads)?;
        log(&format!(
            "{} grain R={} seed {}: {} particles",
            opts.kind.name(),
            opts.radius,
            opts.seed,
            summary.particles
        ));
        for &a_b in &opts.a_b {
            let mut scene = grain.clone();
            scene.force_field = field(a_b);
            scene.particles.velocities = None;
            let c = compress_grain(&scene, a_b, opts, threads, log);
            report.compressions.push(c);
        }
    }
    Ok(report)
}

/// Runs `stages` one at a time on one system, measuring after each with
/// `measure`; stops at the first engine error or failed check.
fn compress_in_chunks(
    scene: &Scene,
    body: &str,
    a_b: f64,
    stages: Vec<StageSpec>,
    threads: usize,
    measure: &dyn Fn(&crate::engine::System, &crate::scene::StageOutput, f64) -> State,
    log: &mut dyn FnMut(&str),
) -> Compression {
    let start = std::time::Instant::now();
    let mut sys = build_system(scene, threads);
    let n = sys.particles.len();
    let (ratio, shortest, longest) = bond_state(&sys);
    let mut states = vec![State {
        time: 0.0,
        imposed_strain: 0.0,
        bond_strain: 1.0 - ratio,
        pressure: 0.0,
        shortest_bond: shortest,
        longest_bond: longest,
    }];
    let mut failure = None;
    let mut time = 0.0;
    for stage in stages {
        let mut chunk = scene.clone();
        chunk.stages = vec![stage];
        let (outputs, error) = run_scene(&mut sys, &chunk, &RunOptions::quiet(threads));
        if let Some(e) = error {
            failure = Some(e.to_string());
            break;
        }
        time += chunk.stages[0].steps as f64 * chunk.stages[0].dt;
        let state = measure(&sys, &outputs[0], time);
        let lost =
            sys.particles.len() != n || sys.particles.x.iter().flatten().any(|c| !c.is_finite());
        let out_of_range = !(state.shortest_bond > crate::kernels::COLLAPSED_BELOW
            && state.longest_bond < crate::kernels::OVERSTRETCHED_ABOVE);
        states.push(state);
        if lost {
            failure = Some("a particle was lost or became non-finite".into());
            break;
        }
        if out_of_range {
            failure = Some("a bond left [0.2, 3] r0".into());
            break;
        }
    }
    let last = states.last().expect("the initial state");
    log(&format!(
        "  {body} a_B={a_b}: imposed volumetric strain {:.3}, bonds' {:.3}, P = {:.4} k/d^2, bonds {:.3}..{:.3} r0, {:.1} s{}",
        last.imposed_strain,
        last.bond_strain,
        last.pressure,
        last.shortest_bond,
        last.longest_bond,
        start.elapsed().as_secs_f64(),
        failure.as_deref().map(|f| format!(": FAILED: {f}")).unwrap_or_default()
    ));
    Compression {
        body: body.into(),
        a_b,
        particles: n,
        states,
        complete: failure.is_none(),
        failure,
        seconds: start.elapsed().as_secs_f64(),
    }
}

fn compress_bulk(
    scene: &Scene,
    a_b: f64,
    opts: &LargeStrainOptions,
    threads: usize,
    log: &mut dyn FnMut(&str),
) -> Compression {
    // Volume ratio exp(-3 eps) = 1 - volumetric strain.
    let linear = -(1.0 - opts.volumetric_strain).ln() / 3.0;
    let chunk = linear / opts.chunks as f64;
    let stages = (0..opts.chunks)
        .map(|_| protocols::isotropic_compression(chunk, opts.rate, opts.dt, 1))
        .collect();
    let v0 = crate::scene::validate::simbox_of(scene).volume();
    let measure = |sys: &crate::engine::System, _: &crate::scene::StageOutput, time: f64| {
        let (ratio, shortest, longest) = bond_state(sys);
        State {
            time,
            imposed_strain: 1.0 - sys.simbox.volume() / v0,
            bond_strain: 1.0 - ratio,
            pressure: sys.pressure(),
            shortest_bond: shortest,
            longest_bond: longest,
        }
    };
    compress_in_chunks(scene, "bulk", a_b, stages, threads, &measure, log)
}

fn compress_grain(
    scene: &Scene,
    a_b: f64,
    opts: &LargeStrainOptions,
    threads: usize,
    log: &mut dyn FnMut(&str),
) -> Compression {
    let x = &scene.particles.positions;
    let n = x.len() as f64;
    let centre = [0, 1, 2].map(|k| x.iter().map(|p| p[k]).sum::<f64>() / n);
    let distance = |p: &[f64; 3]| {
        ((p[0] - centre[0]).powi(2) + (p[1] - centre[1]).powi(2) + (p[2] - centre[2]).powi(2))
            .sqrt()
    };
    let outer = x.iter().map(distance).fold(0.0, f64::max);
    // The body's radius is the outermost centre plus d/2. The wall starts
    // one cutoff outside the outermost centre (its force reaches a centre
    // within one cutoff, so it touches the grain from the start) and moves
    // in until the sphere one cutoff inside it, plus d/2, holds the target
    // volume.
    let cutoff = 1.0;
    let body0 = outer + 0.5;
    let body_end = body0 * (1.0 - opts.volumetric_strain).cbrt();
    let travel = body0 - body_end;
    let total_steps = (travel / opts.wall_speed / opts.dt).ceil() as u64;
    let per_chunk = total_steps.div_ceil(opts.chunks as u64).max(1);
    let chunk_time = per_chunk as f64 * opts.dt;
    let stages = (0..opts.chunks)
        .map(|k| {
            let mut s = StageSpec::hold("squeeze", per_chunk, opts.dt);
            s.sphere_wall = Some(SphereWall {
                centre,
                radius: outer + cutoff - opts.wall_speed * chunk_time * k as f64,
                velocity: -opts.wall_speed,
                amplitude: 0.0,
                period: 1.0,
                decay_time: 1.0,
                stiffness: opts.wall_stiffness,
                cutoff,
            });
            s.record.every = per_chunk;
            s
        })
        .collect();
    let measure = |sys: &crate::engine::System, out: &crate::scene::StageOutput, time: f64| {
        let (ratio, shortest, longest) = bond_state(sys);
        // The wall's sphere minus its cutoff passes through the outermost
        // centres of a grain that just touches it.
        let wall = outer + cutoff - opts.wall_speed * time;
        let body = (wall - cutoff + 0.5).max(0.0);
        let force = out
            .column("sphere_wall_force")
            .and_then(|c| c.last().copied())
            .unwrap_or(f64::NAN);
        State {
            time,
            imposed_strain: 1.0 - (body / body0).powi(3),
            bond_strain: 1.0 - ratio,
            pressure: force / (4.0 * std::f64::consts::PI * body * body),
            shortest_bond: shortest,
            longest_bond: longest,
        }
    };
    compress_in_chunks(scene, "grain", a_b, stages, threads, &measure, log)
}

/// Writes `DIR/large_strain.json` and `DIR/large_strain.svg` (pressure
/// against the bonds' volumetric strain, and bond extremes, per body).
pub fn write_report(report: &LargeStrainReport, dir: &Path) -> Result<(), LargeStrainError> {
    output::write_report(report, dir)?;
    Ok(())
}

/// Rewrites `DIR/large_strain.svg` (and the JSON) from an earlier
/// `large_strain.json` without running anything.
pub fn replot(json: &Path, dir: &Path) -> Result<LargeStrainReport, LargeStrainError> {
    Ok(output::replot(json, dir)?)
}

impl StudyReport for LargeStrainReport {
    const JSON: &'static str = "large_strain.json";

    fn check(&self) -> Result<(), String> {
        self.options.validate().map_err(|e| e.to_string())
    }

    /// `large_strain.svg`: pressure against the bonds' volumetric strain,
    /// and the bond extremes, per body.
    fn draw(&self, out: &StudyOutput) -> Result<(), OutputError> {
        let report = self;
        let variant = if report.options.zero_net {
            ", zero-net variant"
        } else {
            ""
        };
        let mut panels = Vec::new();
        for body in ["bulk", "grain"] {
            let runs: Vec<&Compression> = report
                .compressions
                .iter()
                .filter(|c| c.body == body)
                .collect();
            if runs.is_empty() {
                continue;
            }
            let imposed = if body == "bulk" {
                "imposed volumetric strain (box)"
            } else {
                "imposed volumetric strain (wall)"
            };
            let mut pressure = Panel {
                title: format!("{body}: pressure against volumetric strain{variant}"),
                x_label: imposed.into(),
                y_label: "P (k/d^2)".into(),
                ..Panel::default()
            };
            let mut material = Panel {
                title: format!("{body}: the bonds' volumetric strain{variant}"),
                x_label: imposed.into(),
                y_label: "1 - sum r^3 / sum r0^3".into(),
                ..Panel::default()
            };
            let mut bonds = Panel {
                title: format!("{body}: shortest and longest bond{variant}"),
                x_label: imposed.into(),
                y_label: "r / r0".into(),
                ..Panel::default()
            };
            for c in runs {
                let tag = format!(
                    "a_B = {}{}",
                    c.a_b,
                    if c.complete { "" } else { " (failed)" }
                );
                let against_strain = |label: String, y: fn(&State) -> f64, mark: Mark| {
                    let points = c.states.iter().map(|s| (s.imposed_strain, y(s))).collect();
                    Series::new(label, points, mark)
                };
                pressure.series.push(against_strain(
                    tag.clone(),
                    |s| s.pressure,
                    Mark::LinePoints,
                ));
                material.series.push(against_strain(
                    tag.clone(),
                    |s| s.bond_strain,
                    Mark::LinePoints,
                ));
                bonds.series.push(against_strain(
                    format!("{tag}, shortest"),
                    |s| s.shortest_bond,
                    Mark::Line,
                ));
                bonds.series.push(against_strain(
                    format!("{tag}, longest"),
                    |s| s.longest_bond,
                    Mark::Line,
                ));
            }
            panels.push(pressure);
            panels.push(material);
            panels.push(bonds);
        }
        out.svg("large_strain.svg", &panels)?;
        Ok(())
    }
}
