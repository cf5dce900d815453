//! The calibration study (`bpm calibrate`, docs/protocols.md
//! "Calibration", the paper's Fig. 2): K and G of bulk solids against
//! `a_B` on either engine (measured by [`measure_moduli`], which the
//! harness owns and `bpm check` uses too), the study over sizes, seeds and
//! engines ([`calibrate`]), and its tables and plots ([`write_report`],
//! [`replot`]).

pub mod cli;

pub use crate::analysis::moduli::Moduli;
use crate::analysis::plot::PlotError;
use crate::file_error::FileError;
use crate::options::{validate_a_b_values, validate_strain_and_rate, InvalidOption};
use crate::reference::paper;
use crate::scene::builders::bulk::{build_bulk, BulkParams, BulkSummary};
pub use crate::scene::protocols::{calibration_scenes, ModuliLoading as Loading};
use crate::scene::Scene;
use crate::verify::engines::{HarnessError, LammpsLauncher};
pub use crate::verify::moduli::{measure_moduli, CalibrationEngine};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Why the calibration study could not finish. Each message carries its
/// cause once.
#[derive(Debug, thiserror::Error)]
pub enum CalibrationError {
    /// An option is out of range.
    #[error(transparent)]
    Invalid(#[from] InvalidOption),
    /// A solid could not be built or a run failed.
    #[error(transparent)]
    Harness(#[from] HarnessError),
    /// A plot could not be written.
    #[error(transparent)]
    Plot(#[from] PlotError),
    /// A file or folder could not be created, written or read.
    #[error(transparent)]
    File(#[from] FileError),
    /// The study stopped before its end (its checkpoint continues it).
    #[error(transparent)]
    Stopped(#[from] crate::studies::StudyStop),
    /// An earlier `calibration.json` could not be parsed.
    #[error("{what}: {cause}")]
    Json {
        /// What was read ("parsing <file>", "reading `options`").
        what: String,
        /// The cause.
        cause: serde_json::Error,
    },
    /// The report could not be written.
    #[error(transparent)]
    Output(#[from] crate::studies::output::OutputError),
}

/// The bulk solid of the paper's protocol (the calibration's, and every
/// study's that measures the solid), side `size`, seed `seed`; a failed
/// build names the solid.
pub fn paper_solid(
    size: f64,
    seed: u64,
    threads: usize,
) -> Result<(Scene, BulkSummary), HarnessError> {
    build_bulk(&BulkParams::paper(size, seed, 0.0), threads, false).map_err(|cause| {
        HarnessError::Scene {
            scene: format!("bulk L={size} seed {seed}"),
            cause,
        }
    })
}

/// What `bpm calibrate` runs.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct StudyOptions {
    /// Box sides L (d); the largest is the main table's.
    pub sizes: Vec<f64>,
    /// Seeds (one bulk solid per size and seed).
    pub seeds: Vec<u64>,
    /// a_B values at the largest size.
    pub a_b: Vec<f64>,
    /// a_B values of the size-convergence runs (every size).
    pub convergence_a_b: Vec<f64>,
    /// Sizes at which LAMMPS repeats every case of the first seed.
    pub lammps_sizes: Vec<f64>,
    /// Loading of every run.
    pub loading: Loading,
    /// Repeat the first seed's cases at the largest size at half the rate.
    pub halve_rate: bool,
}

impl StudyOptions {
    /// Checks `--sizes` (at least 5 d), the a_B values (`--a-b` and
    /// `--convergence-a-b`: finite, above -1), that `--seeds` and `--a-b`
    /// are not empty, and `--rate` and `--strain` (positive).
    pub fn validate(&self) -> Result<(), InvalidOption> {
        if let Some(bad) = self.sizes.iter().find(|l| !(l.is_finite() && **l >= 5.0)) {
            return Err(InvalidOption::new(
                "--sizes",
                format!("must be at least 5 (d), got {bad}"),
            ));
        }
        if let Some(bad) = self.lammps_sizes.iter().find(|l| !self.sizes.contains(l)) {
            return Err(InvalidOption::new(
                "--lammps-sizes",
                format!("must be among --sizes, got {bad}"),
            ));
        }
        validate_a_b_values("a_B values", self.a_b.iter().chain(&self.convergence_a_b))?;
        if self.seeds.is_empty() || self.a_b.is_empty() {
            return Err(InvalidOption::new(
                "--seeds and --a-b",
                "need at least one value",
            ));
        }
        validate_strain_and_rate(self.loading.strain, self.loading.rate)
    }
}

/// One measured case.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Case {
    /// Box side (d).
    pub size: f64,
    /// Seed of the solid.
    pub seed: u64,
    /// Engine name.
    pub engine: String,
    /// Strain rate (1 / tau).
    pub rate: f64,
    /// Particles.
    pub particles: usize,
    /// Seconds to build the solid (shared by its cases).
    pub build_seconds: f64,
    /// The moduli.
    pub moduli: Moduli,
}

/// The header of the table of cases ([`Case::row`]).
pub fn case_header() -> String {
    format!(
        "{:>5} {:>5} {:>6} {:<11} {:>8} {:>8} {:>8} {:>7} {:>7} {:>8}",
        "L", "seed", "a_B", "engine", "rate", "K", "G", "G/K", "nu", "seconds"
    )
}

impl Case {
    /// The case as a row of the table of cases ([`case_header`]).
    pub fn row(&self) -> String {
        format!(
            "{:>5} {:>5} {:>6} {:<11} {:>8.1e} {:>8.4} {:>8.4} {:>7.3} {:>7.3} {:>8.2}",
            self.size,
            self.seed,
            self.moduli.a_b,
            self.engine,
            self.rate,
            self.moduli.k,
            self.moduli.g,
            self.moduli.g_over_k,
            self.moduli.nu,
            self.moduli.seconds
        )
    }
}

/// Runs the study's cases; `log` receives each case as it finishes.
/// With a checkpoint in `runtime`, each solid and case is kept in it as it
/// finishes, and a resumed study takes them from there.
pub fn run_study(
    opts: &StudyOptions,
    launcher: &LammpsLauncher,
    runtime: &crate::studies::StudyRuntime,
    log: &mut dyn FnMut(&Case),
) -> Result<Vec<Case>, CalibrationError> {
    let threads = runtime.threads;
    let largest = opts.sizes.iter().copied().fold(f64::NAN, f64::max);
    let mut cases = Vec::new();
    for &size in &opts.sizes {
        for (n, &seed) in opts.seeds.iter().enumerate() {
            let (solid, summary, build_seconds) =
                runtime.part(&format!("L{size}-s{seed}/solid"), || {
                    let start = std::time::Instant::now();
                    let (solid, summary) = paper_solid(size, seed, threads)?;
                    Ok::<_, CalibrationError>((solid, summary, start.elapsed().as_secs_f64()))
                })?;
            // Every a_B at the largest size, and for the LAMMPS comparison.
            let a_bs = if size == largest || (n == 0 && opts.lammps_sizes.contains(&size)) {
                &opts.a_b
            } else {
                &opts.convergence_a_b
            };
            let mut engines = vec![(CalibrationEngine::Native(threads), opts.loading)];
            if n == 0 && opts.lammps_sizes.contains(&size) {
                engines.push((CalibrationEngine::Lammps(launcher.clone(), 1), opts.loading));
            }
            if n == 0 && size == largest && opts.halve_rate {
                let mut slow = opts.loading;
                slow.rate *= 0.5;
                engines.push((CalibrationEngine::Native(threads), slow));
            }
            for &a_b in a_bs {
                for (engine, loading) in &engines {
                    let tag = format!("L{size}-s{seed}-aB{a_b}-rate{}", loading.rate);
                    let key = format!("{tag}-{}", engine.name());
                    let moduli = runtime.part(&key, || {
                        let (moduli, _) =
                            measure_moduli(&solid, a_b, false, loading, engine, &tag)?;
                        Ok::<_, CalibrationError>(moduli)
                    })?;
                    let case = Case {
                        size,
                        seed,
                        engine: engine.name(),
                        rate: loading.rate,
                        particles: summary.particles,
                        build_seconds,
                        moduli,
                    };
                    log(&case);
                    cases.push(case);
                }
            }
        }
    }
    Ok(cases)
}

/// Mean and sample standard deviation.
pub fn mean_sd(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = if values.len() > 1 {
        values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)
    } else {
        0.0
    };
    (mean, var.sqrt())
}

fn select<'a>(cases: &'a [Case], f: impl Fn(&Case) -> bool + 'a) -> Vec<&'a Case> {
    cases.iter().filter(|c| f(c)).collect()
}

/// The study's tables as Markdown, and its plots as SVG panels
/// (`moduli_vs_a_b`, `size_convergence`).
pub fn study_report(
    opts: &StudyOptions,
    cases: &[Case],
) -> (
    String,
    Vec<crate::analysis::plot::Panel>,
    Vec<crate::analysis::plot::Panel>,
) {
    use crate::analysis::plot::{Mark, Panel, Series};
    use std::fmt::Write as _;
    let largest = opts.sizes.iter().copied().fold(f64::NAN, f64::max);
    let rate = opts.loading.rate;
    let mut md = String::new();
    let _ = writeln!(
        md,
        "## Moduli at L = {largest} d ({} seed(s), native engine, strain {} at rate {rate:e} / tau)\n",
        opts.seeds.len(),
        opts.loading.strain
    );
    let _ = writeln!(md, "| a_B | K | G | G/K | nu | paper K | paper G/K | paper nu | dK/K | d(G/K)/(G/K) | LAMMPS vs native (K, G) |");
    let _ = writeln!(
        md,
        "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
    );
    let mut gk_points = Vec::new();
    let mut nu_points = Vec::new();
    let mut k_points = Vec::new();
    let mut lammps_gk = Vec::new();
    let mut lammps_nu = Vec::new();
    for &a_b in &opts.a_b {
        let native = select(cases, |c| {
            c.size == largest && c.engine == "native" && c.rate == rate && c.moduli.a_b == a_b
        });
        if native.is_empty() {
            continue;
        }
        let col = |f: &dyn Fn(&Moduli) -> f64| {
            mean_sd(&native.iter().map(|c| f(&c.moduli)).collect::<Vec<_>>())
        };
        let (k, k_sd) = col(&|m| m.k);
        let (g, g_sd) = col(&|m| m.g);
        let (gk, gk_sd) = col(&|m| m.g_over_k);
        let (nu, nu_sd) = col(&|m| m.nu);
        let lammps = select(cases, |c| {
            c.size == largest && c.engine.starts_with("lammps") && c.moduli.a_b == a_b
        });
        let agreement = lammps
            .iter()
            .filter_map(|l| {
                native.iter().find(|n| n.seed == l.seed).map(|n| {
                    (
                        ((l.moduli.k - n.moduli.k) / n.moduli.k).abs(),
                        ((l.moduli.g - n.moduli.g) / n.moduli.g).abs(),
                    )
                })
            })
            .fold(None, |acc: Option<(f64, f64)>, (a, b)| {
                Some(acc.map_or((a, b), |(x, y)| (x.max(a), y.max(b))))
            });
        for l in &lammps {
            lammps_gk.push((a_b, l.moduli.g_over_k));
            lammps_nu.push((a_b, l.moduli.nu));
        }
        let pk = paper::bulk_modulus(a_b);
        let pgk = paper::shear_to_bulk(a_b);
        let _ = writeln!(
            md,
            "| {a_b} | {k:.4} ± {k_sd:.4} | {g:.4} ± {g_sd:.4} | {gk:.3} ± {gk_sd:.3} | {nu:.3} ± {nu_sd:.3} | {pk:.3} | {pgk:.3} | {:.3} | {:+.1}% | {:+.1}% | {} |",
            paper::poisson_ratio(a_b),
            100.0 * (k - pk) / pk,
            100.0 * (gk - pgk) / pgk,
            agreement.map_or("not run".into(), |(a, b)| format!("{a:.1e}, {b:.1e}"))
        );
        gk_points.push((a_b, gk));
        nu_points.push((a_b, nu));
        k_points.push((a_b, k));
    }
    for &size in &opts.lammps_sizes {
        let _ = writeln!(
            md,
            "\n## LAMMPS + plugin against the native engine (L = {size} d, seed {}, same solid)\n",
            opts.seeds.first().copied().unwrap_or_default()
        );
        let _ = writeln!(
            md,
            "| a_B | K native | K LAMMPS | dK/K | G native | G LAMMPS | dG/G | within 0.5% |"
        );
        let _ = writeln!(md, "|---:|---:|---:|---:|---:|---:|---:|:---:|");
        for &a_b in &opts.a_b {
            let find = |lammps: bool| {
                cases.iter().find(|c| {
                    c.size == size
                        && c.rate == rate
                        && c.moduli.a_b == a_b
                        && c.engine.starts_with("lammps") == lammps
                        && Some(&c.seed) == opts.seeds.first()
                })
            };
            if let (Some(n), Some(l)) = (find(false), find(true)) {
                let dk = ((l.moduli.k - n.moduli.k) / n.moduli.k).abs();
                let dg = ((l.moduli.g - n.moduli.g) / n.moduli.g).abs();
                let _ = writeln!(
                    md,
                    "| {a_b} | {:.6} | {:.6} | {dk:.1e} | {:.6} | {:.6} | {dg:.1e} | {} |",
                    n.moduli.k,
                    l.moduli.k,
                    n.moduli.g,
                    l.moduli.g,
                    if dk < 5e-3 && dg < 5e-3 { "yes" } else { "NO" }
                );
            }
        }
    }
    if opts.halve_rate {
        let _ = writeln!(
            md,
            "\n## Quasistatic check: rate {rate:e} against {:e} (L = {largest} d, seed {})\n",
            rate * 0.5,
            opts.seeds.first().copied().unwrap_or_default()
        );
        let _ = writeln!(
            md,
            "| a_B | K | K at half rate | change | G | G at half rate | change |"
        );
        let _ = writeln!(md, "|---:|---:|---:|---:|---:|---:|---:|");
        for &a_b in &opts.a_b {
            let pick = |r: f64| {
                cases.iter().find(|c| {
                    c.size == largest
                        && c.engine == "native"
                        && c.rate == r
                        && c.moduli.a_b == a_b
                        && Some(&c.seed) == opts.seeds.first()
                })
            };
            if let (Some(a), Some(b)) = (pick(rate), pick(rate * 0.5)) {
                let _ = writeln!(
                    md,
                    "| {a_b} | {:.4} | {:.4} | {:+.2e} | {:.4} | {:.4} | {:+.2e} |",
                    a.moduli.k,
                    b.moduli.k,
                    (b.moduli.k - a.moduli.k) / a.moduli.k,
                    a.moduli.g,
                    b.moduli.g,
                    (b.moduli.g - a.moduli.g) / a.moduli.g
                );
            }
        }
    }
    let _ = writeln!(
        md,
        "\n## Size convergence (native engine, {} seed(s) per size)\n",
        opts.seeds.len()
    );
    let _ = writeln!(md, "| a_B | L | particles | K mean | K sd | G mean | G sd | (K - K_fit)/K_fit | (G - G_fit)/G_fit | s per case (K and G runs) | s per solid build |");
    let _ = writeln!(
        md,
        "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
    );
    let mut dev_series = Vec::new();
    let mut spread_series = Vec::new();
    let mut time_series = Vec::new();
    for &a_b in &opts.convergence_a_b {
        let (mut dk, mut dg, mut sk, mut sg, mut t) = (vec![], vec![], vec![], vec![], vec![]);
        for &size in &opts.sizes {
            let sel = select(cases, |c| {
                c.size == size && c.engine == "native" && c.rate == rate && c.moduli.a_b == a_b
            });
            if sel.is_empty() {
                continue;
            }
            let (k, k_sd) = mean_sd(&sel.iter().map(|c| c.moduli.k).collect::<Vec<_>>());
            let (g, g_sd) = mean_sd(&sel.iter().map(|c| c.moduli.g).collect::<Vec<_>>());
            let secs = mean_sd(&sel.iter().map(|c| c.moduli.seconds).collect::<Vec<_>>()).0;
            let build = mean_sd(&sel.iter().map(|c| c.build_seconds).collect::<Vec<_>>()).0;
            let pk = paper::bulk_modulus(a_b);
            let pg = pk * paper::shear_to_bulk(a_b);
            let _ = writeln!(
                md,
                "| {a_b} | {size} | {} | {k:.4} | {k_sd:.4} | {g:.4} | {g_sd:.4} | {:+.2}% | {:+.2}% | {secs:.2} | {build:.1} |",
                sel[0].particles,
                100.0 * (k - pk) / pk,
                100.0 * (g - pg) / pg
            );
            dk.push((size, ((k - pk) / pk).abs()));
            dg.push((size, ((g - pg) / pg).abs()));
            sk.push((size, k_sd / k));
            sg.push((size, g_sd / g));
            t.push((size, secs));
        }
        dev_series.push(Series::new(
            format!("|<K> - K_fit| / K_fit, a_B={a_b}"),
            dk,
            Mark::LinePoints,
        ));
        dev_series.push(Series::new(
            format!("|<G> - G_fit| / G_fit, a_B={a_b}"),
            dg,
            Mark::LinePoints,
        ));
        spread_series.push(Series::new(
            format!("sd(K) / <K>, a_B={a_b}"),
            sk,
            Mark::LinePoints,
        ));
        spread_series.push(Series::new(
            format!("sd(G) / <G>, a_B={a_b}"),
            sg,
            Mark::LinePoints,
        ));
        time_series.push(Series::new(
            format!("native, a_B={a_b}"),
            t,
            Mark::LinePoints,
        ));
    }
    let guide = |series: &[Series], power: f64, label: &str| -> Option<Series> {
        let first = series
            .iter()
            .flat_map(|s| s.points.first())
            .copied()
            .find(|p| p.1 > 0.0)?;
        let pts = opts
            .sizes
            .iter()
            .map(|&l| (l, first.1 * (l / first.0).powf(power)))
            .collect();
        Some(Series::new(label, pts, Mark::Line))
    };
    if let Some(g) = guide(&dev_series, -2.0, "L^-2 (paper)") {
        dev_series.push(g);
    }
    if let Some(g) = guide(&spread_series, -1.5, "L^-3/2 (paper)") {
        spread_series.push(g);
    }
    let fit = |f: &dyn Fn(f64) -> f64| -> Vec<(f64, f64)> {
        (0..=76)
            .map(|i| -0.8 + 0.05 * i as f64)
            .map(|a| (a, f(a)))
            .collect()
    };
    let mut gk_series = vec![
        Series::new(
            "paper fit 0.6 + 0.475 a_B",
            fit(&paper::shear_to_bulk),
            Mark::Line,
        ),
        Series::new(format!("native, L = {largest} d"), gk_points, Mark::Points),
    ];
    let mut nu_series = vec![
        Series::new(
            "from the paper's fits",
            fit(&paper::poisson_ratio),
            Mark::Line,
        ),
        Series::new(format!("native, L = {largest} d"), nu_points, Mark::Points),
    ];
    if !lammps_gk.is_empty() {
        gk_series.push(Series::new("LAMMPS + plugin", lammps_gk, Mark::Rings));
        nu_series.push(Series::new("LAMMPS + plugin", lammps_nu, Mark::Rings));
    }
    let moduli_panels = vec![
        Panel {
            title: "G/K against a_B".into(),
            x_label: "a_B (k d)".into(),
            y_label: "G/K".into(),
            series: gk_series,
            ..Default::default()
        },
        Panel {
            title: "Poisson ratio against a_B".into(),
            x_label: "a_B (k d)".into(),
            y_label: "nu".into(),
            series: nu_series,
            ..Default::default()
        },
        Panel {
            title: "K against a_B".into(),
            x_label: "a_B (k d)".into(),
            y_label: "K (k / d)".into(),
            series: vec![
                Series::new(
                    "paper fit 1.365 - 0.14 / (a_B + 1.168)",
                    fit(&paper::bulk_modulus),
                    Mark::Line,
                ),
                Series::new(format!("native, L = {largest} d"), k_points, Mark::Points),
            ],
            ..Default::default()
        },
    ];
    let convergence_panels = vec![
        Panel {
            title: "Mean against the paper's L = 50 fits".into(),
            x_label: "L (d)".into(),
            y_label: "relative deviation".into(),
            log_x: true,
            log_y: true,
            series: dev_series,
        },
        Panel {
            title: "Spread between seeds".into(),
            x_label: "L (d)".into(),
            y_label: "relative standard deviation".into(),
            log_x: true,
            log_y: true,
            series: spread_series,
        },
        Panel {
            title: "Run time of one K and G measurement".into(),
            x_label: "L (d)".into(),
            y_label: "seconds (1 thread)".into(),
            log_x: true,
            log_y: true,
            series: time_series,
        },
    ];
    (md, moduli_panels, convergence_panels)
}

/// What [`calibrate`] measured and wrote.
#[derive(Clone, Debug)]
pub struct Calibration {
    /// Every case, in the order run.
    pub cases: Vec<Case>,
    /// `calibration.json`: options, bulk protocol and every case.
    pub json: PathBuf,
    /// The tables and plots.
    pub report: CalibrationFiles,
}

/// The study's tables and plots ([`write_report`]).
#[derive(Clone, Debug)]
pub struct CalibrationFiles {
    /// The tables (Markdown), as written below the header of calibration.md.
    pub markdown: String,
    /// calibration.md, moduli_vs_a_b.svg and size_convergence.svg.
    pub files: Vec<PathBuf>,
}

/// `bpm calibrate`: validates `opts`, runs the study into `output` with `threads` threads
/// (LAMMPS cases through `bpm` = the `bpm` executable, files in
/// `output/lammps/`) and writes calibration.json, calibration.md and the
/// plots; `command` is recorded in both. `log` receives the lines of the
/// table of cases (header first) as the cases finish.
pub fn calibrate(
    opts: &StudyOptions,
    output: &Path,
    bpm: &Path,
    runtime: &crate::studies::StudyRuntime,
    command: &str,
    log: &mut dyn FnMut(&str),
) -> Result<Calibration, CalibrationError> {
    let threads = runtime.threads;
    opts.validate()?;
    std::fs::create_dir_all(output).map_err(FileError::on("creating", output))?;
    let launcher = LammpsLauncher {
        bpm: bpm.to_path_buf(),
        dir: output.join("lammps"),
    };
    let start = std::time::Instant::now();
    log(&case_header());
    let cases = run_study(opts, &launcher, runtime, &mut |c| log(&c.row()))?;
    let doc = serde_json::json!({
        "program": "bpm calibrate",
        "version": crate::VERSION,
        "command": command,
        "threads": threads,
        "options": opts,
        "bulk_protocol": crate::scene::builders::bulk::BulkParams::paper(0.0, 0, 0.0),
        "reference": paper::FITS_FILE,
        "wall_seconds": start.elapsed().as_secs_f64(),
        "cases": cases,
    });
    let json = output.join("calibration.json");
    crate::studies::output::write_json(&json, &doc)?;
    let report = write_report(output, opts, &cases, command)?;
    Ok(Calibration {
        cases,
        json,
        report,
    })
}

/// `bpm calibrate --from FILE`: the tables and plots of an earlier study
/// (its calibration.json) into `output`, without running anything.
pub fn replot(json: &Path, output: &Path) -> Result<CalibrationFiles, CalibrationError> {
    let text = std::fs::read_to_string(json).map_err(FileError::on("reading", json))?;
    let parse_error = |what: String| move |cause| CalibrationError::Json { what, cause };
    let doc: serde_json::Value =
        serde_json::from_str(&text).map_err(parse_error(format!("parsing {}", json.display())))?;
    let opts: StudyOptions = serde_json::from_value(doc["options"].clone())
        .map_err(parse_error("reading `options`".into()))?;
    let cases: Vec<Case> = serde_json::from_value(doc["cases"].clone())
        .map_err(parse_error("reading `cases`".into()))?;
    let command = doc["command"].as_str().unwrap_or("unknown").to_string();
    std::fs::create_dir_all(output).map_err(FileError::on("creating", output))?;
    write_report(output, &opts, &cases, &command)
}

/// Writes calibration.md (a header naming `command`, then the tables of
/// [`study_report`]) and the two plots into `output`.
pub fn write_report(
    output: &Path,
    opts: &StudyOptions,
    cases: &[Case],
    command: &str,
) -> Result<CalibrationFiles, CalibrationError> {
    let (markdown, moduli_panels, convergence_panels) = study_report(opts, cases);
    let header = format!(
        "# Calibration of K and G against a_B\n\nMade by `{command}` (bpm {}); every case is in `calibration.json`.\n\n",
        crate::VERSION
    );
    let table = output.join("calibration.md");
    crate::studies::output::write_whole(&table, (header + &markdown).as_bytes())?;
    let moduli = output.join("moduli_vs_a_b.svg");
    crate::analysis::plot::write_svg(&moduli, &moduli_panels)?;
    let convergence = output.join("size_convergence.svg");
    crate::analysis::plot::write_svg(&convergence, &convergence_panels)?;
    Ok(CalibrationFiles {
        markdown,
        files: vec![table, moduli, convergence],
    })
}
