//! The compaction report: `compaction.json`, the plots and the table of
//! fits beside the paper's values; `--refit` rewrites them from the JSON.

use super::{
    fit_run, CompactionError, CompactionReport, PackingModuli, RunFits, StateModuli, StateRow,
    FIT_WINDOW,
};
use crate::analysis::distribution::{density_histogram, shape, z_scores};
use crate::analysis::fragments::GrainFragments;
use crate::analysis::jamming::PowerLaw;
use crate::analysis::plot::{Mark, Panel, Series};
use crate::file_error::FileError;
use crate::studies::output::{self, OutputError, StudyOutput, StudyReport};
use std::path::Path;

/// Writes `compaction.json`, `compaction.svg`, `jamming.svg`,
/// `distributions.svg` (grains only), `moduli.svg` (when moduli were
/// measured), `fragments.svg` (when bonds break) and `compaction.txt`
/// into `dir`.
pub fn write_report(report: &CompactionReport, dir: &Path) -> Result<(), CompactionError> {
    output::write_report(report, dir)?;
    Ok(())
}

impl StudyReport for CompactionReport {
    const JSON: &'static str = "compaction.json";

    /// `compaction.svg`, `jamming.svg`, `distributions.svg` (grains only),
    /// `moduli.svg` (when moduli were measured), `fragments.svg` (when
    /// bonds break) and `compaction.txt`.
    fn draw(&self, out: &StudyOutput) -> Result<(), OutputError> {
        let report = self;
        let per_run = |f: &dyn Fn(&StateRow) -> Option<(f64, f64)>, mark| -> Vec<Series> {
            report
                .runs
                .iter()
                .map(|r| {
                    Series::new(
                        format!("seed {}", r.seed),
                        r.states.iter().filter_map(f).collect(),
                        mark,
                    )
                })
                .collect()
        };
        // The loading only: unloading states would fold the curves back.
        let compressed = |s: &StateRow| s.stage != "start" && !unloading(s);
        let mut z = per_run(
            &|s| compressed(s).then_some((s.packing.phi_mc, s.packing.z_force)),
            Mark::LinePoints,
        );
        for (series, run) in z.iter_mut().zip(&report.runs) {
            series.label = format!("Z_force, seed {}", run.seed);
        }
        let mut zg = per_run(
            &|s| compressed(s).then_some((s.packing.phi_mc, s.packing.z_geometry)),
            Mark::Rings,
        );
        for (series, run) in zg.iter_mut().zip(&report.runs) {
            series.label = format!("Z_geometry, seed {}", run.seed);
        }
        z.extend(zg);
        let spheres = report.options.dem.is_some();
        let mut panels = vec![
            Panel {
                title: "pressure against volume fraction".into(),
                x_label: "phi_MC".into(),
                y_label: "P / E_eff".into(),
                log_y: true,
                series: per_run(
                    &|s| compressed(s).then_some((s.packing.phi_mc, s.p_over_e_eff)),
                    Mark::LinePoints,
                ),
                ..Panel::default()
            },
            Panel {
                title: "coordination (rattlers removed)".into(),
                x_label: "phi_MC".into(),
                y_label: "Z".into(),
                series: z,
                ..Panel::default()
            },
        ];
        if spheres {
            panels.push(Panel {
                title: "pressure against the spheres' volume over the box's (paper Fig. 6a)".into(),
                x_label: "phi_sphere".into(),
                y_label: "P / E_eff".into(),
                log_y: true,
                series: per_run(
                    &|s| compressed(s).then_some((s.packing.phi_sphere, s.p_over_e_eff)),
                    Mark::LinePoints,
                ),
                ..Panel::default()
            });
        } else {
            panels.extend([
                Panel {
                    title: "grain volumetric strain".into(),
                    x_label: "phi_MC".into(),
                    y_label: "mean eps_V".into(),
                    series: per_run(
                        &|s| compressed(s).then_some((s.packing.phi_mc, s.packing.eps_v_mean)),
                        Mark::LinePoints,
                    ),
                    ..Panel::default()
                },
                Panel {
                    title: "grain asphericity".into(),
                    x_label: "phi_MC".into(),
                    y_label: "mean alpha - alpha0".into(),
                    log_y: true,
                    series: per_run(
                        &|s| {
                            compressed(s)
                                .then_some((s.packing.phi_mc, s.packing.asphericity_excess_mean))
                        },
                        Mark::LinePoints,
                    ),
                    ..Panel::default()
                },
            ]);
        }
        panels.push(Panel {
            title: "pressure and kinetic energy against time".into(),
            x_label: "time (tau)".into(),
            y_label: "P (k/d), KE per particle (k d^2)".into(),
            log_x: true,
            log_y: true,
            series: report
                .runs
                .iter()
                .flat_map(|r| {
                    let pts = |y: &[f64]| {
                        r.series
                            .time
                            .iter()
                            .zip(y)
                            .map(|(&t, &y)| (t, y))
                            .collect::<Vec<_>>()
                    };
                    [
                        Series::new(
                            format!("P, seed {}", r.seed),
                            pts(&r.series.pressure),
                            Mark::Line,
                        ),
                        Series::new(
                            format!("KE/particle, seed {}", r.seed),
                            pts(&r.series.ke_per_particle),
                            Mark::Line,
                        ),
                    ]
                })
                .collect(),
        });
        out.svg("compaction.svg", &panels)?;
        out.svg("jamming.svg", &jamming_panels(report, spheres))?;
        if !spheres {
            let bands = band_z_scores(report);
            out.svg("distributions.svg", &distribution_panels(&bands))?;
        }
        if report.runs.iter().any(|r| !r.moduli.is_empty()) {
            out.svg("moduli.svg", &moduli_panels(report))?;
        }
        if breaks(report) {
            out.svg("fragments.svg", &fragment_panels(report))?;
        }
        out.text("compaction.txt", &table(report))?;
        Ok(())
    }
}

/// Bands of `P / E_eff` in which the per-grain distributions are compared
/// with a Gaussian.
const PRESSURE_BANDS: [(f64, f64); 5] = [
    (1e-5, 1e-4),
    (1e-4, 1e-3),
    (1e-3, 1e-2),
    (1e-2, 1e-1),
    (1e-1, 1e1),
];

/// The pooled z-scores of one band of `P / E_eff`.
struct Band {
    range: (f64, f64),
    eps_v: Vec<f64>,
    asphericity: Vec<f64>,
}

/// Per band, the grains' z-scores of `eps_V` and of `alpha - alpha0`
/// (each grain against its own start: a packing reuses a few distinct
/// grains, whose different starting shapes would otherwise dominate the
/// spread), pooled over runs from one state each (the compression state
/// nearest the band's logarithmic centre), so no grain is counted twice.
fn band_z_scores(report: &CompactionReport) -> Vec<Band> {
    PRESSURE_BANDS
        .iter()
        .map(|&(lo, hi)| {
            let centre = (lo * hi).sqrt().ln();
            let (mut eps, mut alpha) = (Vec::new(), Vec::new());
            for r in &report.runs {
                let nearest = r
                    .states
                    .iter()
                    .filter(|s| s.stage.starts_with("compress"))
                    .filter(|s| s.p_over_e_eff >= lo && s.p_over_e_eff < hi)
                    .min_by(|a, b| {
                        (a.p_over_e_eff.ln() - centre)
                            .abs()
                            .total_cmp(&(b.p_over_e_eff.ln() - centre).abs())
                    });
                if let (Some(s), Some(start)) = (nearest, r.states.first()) {
                    let excess: Vec<f64> = s
                        .packing
                        .asphericity
                        .iter()
                        .zip(&start.packing.asphericity)
                        .map(|(a, a0)| a - a0)
                        .collect();
                    eps.extend(z_scores(&s.packing.eps_v));
                    alpha.extend(z_scores(&excess));
                }
            }
            Band {
                range: (lo, hi),
                eps_v: eps,
                asphericity: alpha,
            }
        })
        .collect()
}

/// Histograms of the z-scores per pressure band, beside a Gaussian
/// (paper: nearly Gaussian at every pressure).
fn distribution_panels(bands: &[Band]) -> Vec<Panel> {
    let gaussian: Vec<(f64, f64)> = (0..=80)
        .map(|k| {
            let z = -4.0 + 0.1 * k as f64;
            (
                z,
                (-0.5 * z * z).exp() / (2.0 * std::f64::consts::PI).sqrt(),
            )
        })
        .collect();
    let panel = |title: &str, pick: fn(&Band) -> &Vec<f64>| {
        let mut series: Vec<Series> = bands
            .iter()
            .filter(|b| !pick(b).is_empty())
            .map(|b| {
                Series::new(
                    format!(
                        "P/E_eff {:.0e} to {:.0e} ({} grains)",
                        b.range.0,
                        b.range.1,
                        pick(b).len()
                    ),
                    density_histogram(pick(b), -4.0, 4.0, 16),
                    Mark::LinePoints,
                )
            })
            .collect();
        series.push(Series::new("Gaussian", gaussian.clone(), Mark::Line));
        Panel {
            title: title.into(),
            x_label: "z-score".into(),
            y_label: "probability density".into(),
            series,
            ..Panel::default()
        }
    };
    vec![
        panel("grain volumetric strain eps_V", |b| &b.eps_v),
        panel("grain asphericity change alpha - alpha0", |b| {
            &b.asphericity
        }),
    ]
}

/// The Gaussian-ness table: skewness and excess kurtosis per band.
fn distribution_table(bands: &[Band]) -> String {
    use std::fmt::Write as _;
    let mut t = String::from(
        "\nper-grain distributions against a Gaussian (one state per run and band; errors are a Gaussian sample's)\n",
    );
    let _ = writeln!(
        t,
        "{:<18} {:>6} {:>14} {:>14} {:>14} {:>14}",
        "P/E_eff band", "grains", "eps_V skew", "eps_V kurt.", "dalpha skew", "dalpha kurt."
    );
    for band in bands {
        let (lo, hi) = band.range;
        let (e, a) = (shape(&band.eps_v), shape(&band.asphericity));
        if e.is_none() && a.is_none() {
            continue;
        }
        let pm = |v: Option<(f64, f64)>| {
            v.map_or("-".to_string(), |(v, err)| format!("{v:.2}+-{err:.2}"))
        };
        let _ = writeln!(
            t,
            "{:<18} {:>6} {:>14} {:>14} {:>14} {:>14}",
            format!("{lo:.0e} to {hi:.0e}"),
            band.eps_v.len().max(band.asphericity.len()),
            pm(e.map(|e| (e.skewness, e.skewness_error))),
            pm(e.map(|e| (e.excess_kurtosis, e.excess_kurtosis_error))),
            pm(a.map(|a| (a.skewness, a.skewness_error))),
            pm(a.map(|a| (a.excess_kurtosis, a.excess_kurtosis_error)))
        );
    }
    t
}

/// A fitted power law drawn over `1e-4 .. window`.
fn law_line(f: &PowerLaw) -> Vec<(f64, f64)> {
    (0..=40)
        .map(|k| {
            let x = 1e-4 * (f.window / 1e-4).powf(k as f64 / 40.0);
            (x, f.prefactor * x.powf(f.exponent))
        })
        .collect()
}

/// The packing's moduli and Poisson ratio against `phi - phi_c` (each run
/// at its own `phi_c`); measurements that fail
/// [`PackingModuli::bulk_is_reliable`], `shear_is_reliable` or
/// `poisson_is_reliable` are drawn as rings and left out of the fits.
fn moduli_panels(report: &CompactionReport) -> Vec<Panel> {
    let mut moduli = Vec::new();
    let mut poisson = Vec::new();
    for r in &report.runs {
        let Some(p) = &r.fits.pressure else { continue };
        type Reliable = fn(&PackingModuli) -> bool;
        let pick = |reliable: Reliable, wanted: bool, f: &dyn Fn(&PackingModuli) -> f64| {
            r.moduli
                .iter()
                .filter(|m| reliable(&m.moduli) == wanted)
                .map(|m| (m.phi_mc - p.phi_c, f(&m.moduli)))
                .collect::<Vec<(f64, f64)>>()
        };
        let e_eff = report.e_eff;
        for (name, f, reliable, law) in [
            (
                "K_P",
                &(move |m: &PackingModuli| m.bulk / e_eff) as &dyn Fn(&PackingModuli) -> f64,
                PackingModuli::bulk_is_reliable as Reliable,
                r.fits.bulk_modulus,
            ),
            (
                "G_P",
                &move |m: &PackingModuli| m.shear / e_eff,
                PackingModuli::shear_is_reliable,
                r.fits.shear_modulus,
            ),
        ] {
            moduli.push(Series::new(
                format!("{name}, seed {}", r.seed),
                pick(reliable, true, f),
                Mark::Points,
            ));
            moduli.push(Series::new(
                format!("{name}, seed {}, uncertain", r.seed),
                pick(reliable, false, f),
                Mark::Rings,
            ));
            if let Some(law) = law {
                moduli.push(Series::new(
                    format!(
                        "{name} fit, seed {}: exponent {:.2} +- {:.2}",
                        r.seed, law.exponent, law.exponent_error
                    ),
                    law_line(&law),
                    Mark::Line,
                ));
            }
        }
        poisson.push(Series::new(
            format!("seed {}", r.seed),
            pick(PackingModuli::poisson_is_reliable, true, &|m| m.poisson),
            Mark::LinePoints,
        ));
        poisson.push(Series::new(
            format!("seed {}, uncertain", r.seed),
            pick(PackingModuli::poisson_is_reliable, false, &|m| m.poisson),
            Mark::Rings,
        ));
    }
    vec![
        Panel {
            title: "packing moduli (paper: K_P exponent 1/2, G_P exponent 1)".into(),
            x_label: "phi_MC - phi_c".into(),
            y_label: "modulus / E_eff".into(),
            log_x: true,
            log_y: true,
            series: moduli,
        },
        Panel {
            title: "packing Poisson ratio (paper: 1/2 at jamming, minimum near 1/4)".into(),
            x_label: "phi_MC - phi_c".into(),
            y_label: "nu_P".into(),
            log_x: true,
            series: poisson,
            ..Panel::default()
        },
    ]
}

/// Log-log panels against `phi - phi_c` (each run at its own fitted
/// `phi_c`), with the fitted power laws as lines; for `spheres` only
/// pressure and coordination (a sphere keeps its shape, and its two
/// coordination numbers agree).
fn jamming_panels(report: &CompactionReport, spheres: bool) -> Vec<Panel> {
    type Pick = fn(&StateRow, &RunFits) -> Option<f64>;
    type Law = fn(&RunFits) -> Option<PowerLaw>;
    let panel = |title: &str, y_label: &str, pick: Pick, law: Law| {
        let mut series = Vec::new();
        for r in &report.runs {
            let Some(p) = &r.fits.pressure else { continue };
            let pts: Vec<(f64, f64)> = r
                .states
                .iter()
                .filter(|s| s.stage.starts_with("compress"))
                .filter_map(|s| Some((s.packing.phi_mc - p.phi_c, pick(s, &r.fits)?)))
                .filter(|(x, y)| *x > 0.0 && *y > 0.0)
                .collect();
            series.push(Series::new(format!("seed {}", r.seed), pts, Mark::Points));
            if let Some(f) = law(&r.fits) {
                let line = law_line(&f);
                series.push(Series::new(
                    format!(
                        "fit, seed {}: exponent {:.2} +- {:.2}",
                        r.seed, f.exponent, f.exponent_error
                    ),
                    line,
                    Mark::Line,
                ));
            }
        }
        Panel {
            title: title.into(),
            x_label: "phi_MC - phi_c".into(),
            y_label: y_label.into(),
            log_x: true,
            log_y: true,
            series,
        }
    };
    let mut panels = vec![
        panel(
            "pressure near jamming (paper: exponent 3/2)",
            "P / E_eff",
            |s, _| Some(s.p_over_e_eff),
            |f| f.pressure,
        ),
        panel(
            "force coordination (paper: exponent 1/2)",
            "Z_force - Z_c",
            |s, f| f.z_force.map(|z| s.packing.z_force - z.z_c),
            |f| f.z_force.map(|z| z.law),
        ),
    ];
    if spheres {
        return panels;
    }
    panels.extend([
        panel(
            "geometric coordination",
            "Z_geometry - Z_c",
            |s, f| f.z_geometry.map(|z| s.packing.z_geometry - z.z_c),
            |f| f.z_geometry.map(|z| z.law),
        ),
        panel(
            "grain volumetric strain (paper: exponent 3/2)",
            "mean eps_V",
            |s, _| Some(s.packing.eps_v_mean),
            |f| f.eps_v,
        ),
        panel(
            "grain asphericity (paper: exponent 5/2 at nu = 1/4)",
            "mean alpha - alpha0",
            |s, _| Some(s.packing.asphericity_excess_mean),
            |f| f.asphericity,
        ),
    ]);
    panels
}

/// The fits of every run and their mean and spread over runs, beside the
/// paper's values, as text.
pub fn table(report: &CompactionReport) -> String {
    use std::fmt::Write as _;
    let mut t = String::new();
    let _ = writeln!(
        t,
        "# bpm compact: power laws near jamming (fit window phi - phi_c <= {FIT_WINDOW})\n# {}",
        report.command
    );
    for w in &report.warnings {
        let _ = writeln!(t, "# warning: {w}");
    }
    t.push('\n');
    let _ = writeln!(
        t,
        "{:>6} {:>8} {:>9} {:>13} {:>8} {:>13} {:>8} {:>13} {:>13} {:>13} {:>8}",
        "seed",
        "grains",
        "phi_c",
        "P exponent",
        "Z_c",
        "Z exponent",
        "Zg_c",
        "Zg exponent",
        "eps_V exp.",
        "alpha exp.",
        "run s"
    );
    let fmt = |f: Option<PowerLaw>| {
        f.map_or("-".to_string(), |f| {
            format!("{:.2}+-{:.2}", f.exponent, f.exponent_error)
        })
    };
    let mut columns: [Vec<f64>; 12] = Default::default();
    for r in &report.runs {
        let f = &r.fits;
        let _ = writeln!(
            t,
            "{:>6} {:>8} {:>9} {:>13} {:>8} {:>13} {:>8} {:>13} {:>13} {:>13} {:>8.0}",
            r.seed,
            r.grains,
            f.pressure.map_or("-".into(), |p| format!("{:.4}", p.phi_c)),
            fmt(f.pressure),
            f.z_force.map_or("-".into(), |z| format!("{:.2}", z.z_c)),
            fmt(f.z_force.map(|z| z.law)),
            f.z_geometry.map_or("-".into(), |z| format!("{:.2}", z.z_c)),
            fmt(f.z_geometry.map(|z| z.law)),
            fmt(f.eps_v),
            fmt(f.asphericity),
            r.run_seconds
        );
        let values = [
            f.pressure.map(|p| p.phi_c),
            f.pressure.map(|p| p.exponent),
            f.z_force.map(|z| z.z_c),
            f.z_force.map(|z| z.law.exponent),
            f.z_geometry.map(|z| z.z_c),
            f.eps_v.map(|p| p.exponent),
            f.asphericity.map(|p| p.exponent),
            f.bulk_modulus.map(|p| p.exponent),
            f.shear_modulus.map(|p| p.exponent),
            poisson_minimum(r).map(|m| m.moduli.poisson),
            f.pressure
                .and_then(|p| poisson_minimum(r).map(|m| m.phi_mc - p.phi_c)),
            f.pressure_departure,
        ];
        for (c, v) in columns.iter_mut().zip(values) {
            c.extend(v);
        }
    }
    let stats = |v: &[f64]| {
        if v.is_empty() {
            return "-".to_string();
        }
        let n = v.len() as f64;
        let m = v.iter().sum::<f64>() / n;
        if v.len() < 2 {
            return format!("{m:.4}");
        }
        let sd = (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        format!("{m:.4} +- {sd:.4} (sd over {} runs)", v.len())
    };
    if report.options.dem.is_some() {
        let _ = writeln!(t, "\nquantity               ours                                 paper (DEM, 1,024 spheres)");
        for (name, k, paper) in [
            (
                "phi_c",
                0,
                "matched to the grains' (0.5836 rough, 0.5979 smoother) within +-0.003",
            ),
            ("P exponent", 1, "3/2"),
            (
                "Z_c",
                2,
                "4.52 to 4.57 (matches of rough grains), 4.91 to 4.98 (smoother)",
            ),
            ("Z exponent", 3, "1/2"),
            (
                "P leaves its law at",
                11,
                "phi - phi_c about 0.1 (here: P above 1.25 x the fit from there on)",
            ),
        ] {
            let _ = writeln!(t, "{name:<22} {:<36} {paper}", stats(&columns[k]));
        }
        return t;
    }
    let _ = writeln!(t, "\nquantity               ours                                 paper (R = 10 d, 1,024 grains)");
    for (name, k, paper) in [
        ("phi_c", 0, "0.5979 smoother, 0.5836 rough"),
        ("P exponent", 1, "3/2"),
        ("Z_c (force)", 2, "about 5.2 smoother, 5.05 rough"),
        ("Z exponent", 3, "1/2"),
        ("Z_c (geometry)", 4, "-"),
        ("eps_V exponent", 5, "3/2"),
        (
            "alpha exponent",
            6,
            "5/2 at nu = 1/4 (2.3 to 2.7 across nu)",
        ),
        (
            "P leaves its law at",
            11,
            "phi - phi_c about 0.1 (here: P above 1.25 x the fit from there on)",
        ),
        ("K_P exponent", 7, "1/2"),
        ("G_P exponent", 8, "1"),
        ("nu_P minimum", 9, "near 1/4 (1/2 at jamming)"),
        ("phi - phi_c there", 10, "about 0.1"),
    ] {
        let _ = writeln!(t, "{name:<22} {:<36} {paper}", stats(&columns[k]));
    }
    t.push_str(&distribution_table(&band_z_scores(report)));
    if breaks(report) {
        t.push_str(&fragment_table(report));
    }
    t.push_str(&unloading_table(report));
    t
}

/// What the unloading left, run by run: the last compressed state beside
/// the last state of the rest after it (nothing without an unloading).
fn unloading_table(report: &CompactionReport) -> String {
    use std::fmt::Write as _;
    let mut t = String::new();
    for r in &report.runs {
        let last = |prefix: &str| r.states.iter().rev().find(|s| s.stage.starts_with(prefix));
        let (Some(loaded), Some(rested)) = (last("compress"), last("rest")) else {
            continue;
        };
        if t.is_empty() {
            t.push_str("\n# unloaded: the box expanded back to its jammed size, then rested\n");
            let _ = writeln!(
                t,
                "{:>6} {:>10} {:>11} {:>8} {:>10} {:>13}",
                "seed", "state", "P/E_eff", "phi_MC", "mean eps_V", "alpha excess"
            );
        }
        for (name, s) in [("loaded", loaded), ("unloaded", rested)] {
            let _ = writeln!(
                t,
                "{:>6} {:>10} {:>11.3e} {:>8.4} {:>10.5} {:>13.3e}",
                r.seed,
                name,
                s.p_over_e_eff,
                s.packing.phi_mc,
                s.packing.eps_v_mean,
                s.packing.asphericity_excess_mean
            );
        }
    }
    t
}

/// Whether a state is of the unloading after the compression.
fn unloading(state: &StateRow) -> bool {
    state.stage == "unload" || state.stage == "rest"
}

/// Whether the report's states count broken bonds and fragments.
fn breaks(report: &CompactionReport) -> bool {
    report
        .runs
        .iter()
        .any(|r| r.states.iter().any(|s| s.fragments.is_some()))
}

/// The compressed states with their fragment counts.
fn compressed_fragments(
    run: &super::CompactionRun,
) -> impl Iterator<Item = (&StateRow, GrainFragments)> {
    run.states
        .iter()
        .filter(|s| s.stage.starts_with("compress"))
        .filter_map(|s| s.fragments.map(|f| (s, f)))
}

/// The bonds broken and the grains' fragments against the pressure.
fn fragment_panels(report: &CompactionReport) -> Vec<Panel> {
    let series = |label: &str, value: &dyn Fn(&GrainFragments) -> f64| -> Vec<Series> {
        report
            .runs
            .iter()
            .map(|r| {
                Series::new(
                    format!("{label}, seed {}", r.seed),
                    compressed_fragments(r)
                        .map(|(s, f)| (s.p_over_e_eff, value(&f)))
                        .filter(|p| p.0 > 0.0)
                        .collect(),
                    Mark::LinePoints,
                )
            })
            .collect()
    };
    let mut pieces = series("whole grains", &|f| f.whole_grains);
    pieces.extend(series("largest fragment / grain", &|f| f.largest_fragment));
    pieces.extend(series("loose particles", &|f| f.loose_particles));
    vec![
        Panel {
            title: "bonds broken".into(),
            x_label: "P / E_eff".into(),
            y_label: "share of the bonds".into(),
            log_x: true,
            series: series("broken", &|f| f.broken_fraction),
            ..Panel::default()
        },
        Panel {
            title: "the grains coming apart".into(),
            x_label: "P / E_eff".into(),
            y_label: "share".into(),
            log_x: true,
            series: pieces,
            ..Panel::default()
        },
        Panel {
            title: "fragments of two particles or more".into(),
            x_label: "P / E_eff".into(),
            y_label: "per grain".into(),
            log_x: true,
            series: series("fragments per grain", &|f| f.fragments_per_grain),
            ..Panel::default()
        },
    ]
}

/// The fragment counts of every compressed state, run by run.
fn fragment_table(report: &CompactionReport) -> String {
    use std::fmt::Write as _;
    let mut t = String::from("\n# bonds broken and the grains' fragments against the pressure\n");
    let _ = writeln!(
        t,
        "{:>6} {:>11} {:>8} {:>8} {:>8} {:>9} {:>11} {:>8}",
        "seed", "P/E_eff", "phi_MC", "broken", "whole", "largest", "fragments", "loose"
    );
    for r in &report.runs {
        for (s, f) in compressed_fragments(r) {
            let _ = writeln!(
                t,
                "{:>6} {:>11.3e} {:>8.4} {:>7.2}% {:>7.1}% {:>8.1}% {:>11.2} {:>7.2}%",
                r.seed,
                s.p_over_e_eff,
                s.packing.phi_mc,
                100.0 * f.broken_fraction,
                100.0 * f.whole_grains,
                100.0 * f.largest_fragment,
                f.fragments_per_grain,
                100.0 * f.loose_particles
            );
        }
    }
    t
}

/// The measured state with the smallest well-measured Poisson ratio.
pub(super) fn poisson_minimum(run: &super::CompactionRun) -> Option<&StateModuli> {
    run.moduli
        .iter()
        .filter(|m| m.moduli.poisson_is_reliable())
        .min_by(|a, b| a.moduli.poisson.total_cmp(&b.moduli.poisson))
}

/// Reads `dir/compaction.json` and refits its runs with this version's
/// analysis.
pub fn read_report(dir: &Path) -> Result<CompactionReport, CompactionError> {
    let json = dir.join("compaction.json");
    let text = std::fs::read_to_string(&json).map_err(FileError::on("reading", &json))?;
    let mut report: CompactionReport =
        serde_json::from_str(&text).map_err(|e| CompactionError::NotAReport {
            path: json.display().to_string(),
            message: e.to_string(),
        })?;
    for r in &mut report.runs {
        r.fits = fit_run(&r.states, &r.moduli, report.e_eff);
    }
    Ok(report)
}

/// Reads an earlier `compaction.json`, refits its runs and rewrites the
/// report, plots and table: the analysis can change without rerunning.
pub fn refit(dir: &Path) -> Result<CompactionReport, CompactionError> {
    let report = read_report(dir)?;
    write_report(&report, dir)?;
    Ok(report)
}
