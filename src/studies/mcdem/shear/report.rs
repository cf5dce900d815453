//! The study's report as text and plots.

use super::beta::MIN_DISTANCE;
use super::{ContactLaw, Regime, ShearError, ShearReport};
use crate::analysis::jamming::PowerLaw;
use crate::analysis::plot::{Mark, Panel, Series};
use crate::reference::multicontact::PaperLaw;
use crate::scene::Scene;
use crate::studies::output::{self, OutputError, StudyOutput, StudyReport};
use std::path::Path;

fn fmt_opt(v: Option<f64>, digits: usize) -> String {
    v.map_or("-".into(), |v| format!("{v:.digits$}"))
}

/// A fit's exponent with its standard error, or `-` without a fit.
pub(super) fn fmt_exponent(f: Option<PowerLaw>) -> String {
    f.map_or("-".into(), |f| {
        format!("{:.3}+-{:.3}", f.exponent, f.exponent_error)
    })
}

/// Table D.2's `beta` as a flat line over `[from, to]`, once for each
/// Poisson's ratio of `curves` (`(nu, the tables' law)`) the tables list;
/// none when the span is empty.
pub(super) fn paper_beta_lines(
    curves: impl IntoIterator<Item = (f64, Option<PaperLaw>)>,
    from: f64,
    to: f64,
) -> Vec<Series> {
    let mut listed: Vec<f64> = Vec::new();
    let mut lines = Vec::new();
    for (nu, paper) in curves {
        if let Some(p) = paper {
            if from < to && !listed.contains(&nu) {
                listed.push(nu);
                lines.push(Series::new(
                    format!("Table D.2, nu {nu}"),
                    vec![(from, p.beta), (to, p.beta)],
                    Mark::Line,
                ));
            }
        }
    }
    lines
}

/// The report as text: every point, the fits against the tables, and the
/// trend checks.
pub fn table(report: &ShearReport) -> String {
    let mut out = format!(
        "{:<9} {:>4} {:>5} {:>5} {:>10} {:>10} {:>7} {:>10} {:>6} {:>7}  status\n",
        "law", "mu", "nu", "phi", "p_slow/k", "+-", "fast/sl", "p_QS/k", "s/p", "corr/R"
    );
    for s in &report.analysis.series {
        for p in &s.points {
            let status = match (&p.stopped, p.regime) {
                (Some(why), _) => format!("stopped: {why}"),
                (None, Some(Regime::QuasiStatic)) => "quasi-static".into(),
                (None, Some(Regime::RateDependent)) => "rate-dependent".into(),
                (None, Some(Regime::Unsettled)) => "unsettled".into(),
                (None, Some(Regime::Unresolved)) => "unresolved (noise above tolerance)".into(),
                (None, None) => "no pressure".into(),
            };
            let drifts = [("fast", p.fast), ("slow", p.slow)]
                .iter()
                .filter(|(_, w)| w.is_some_and(|w| w.drifts))
                .map(|(name, _)| format!(", {name} window drifts"))
                .collect::<String>();
            let status = status + &drifts;
            out += &format!(
                "{:<9} {:>4} {:>5} {:>5} {:>10} {:>10} {:>7} {:>10} {:>6} {:>7}  {status}\n",
                s.spec.law.name(),
                s.spec.friction,
                s.spec.poisson_ratio,
                p.fraction,
                fmt_opt(p.slow.map(|w| w.mean), 6),
                fmt_opt(p.slow.map(|w| w.error), 6),
                fmt_opt(p.rate_effect.map(|r| 1.0 + r), 3),
                fmt_opt(p.quasi_static, 6),
                fmt_opt(p.stress_ratio, 3),
                format!("{:.3}", p.largest_correction),
            );
        }
    }
    let fit_cells = |f: Option<PowerLaw>, paper: Option<PaperLaw>| {
        format!(
            "{:>8} {:>12} {:>2} {:>6} {:>6}",
            fmt_opt(f.map(|f| f.prefactor), 4),
            fmt_exponent(f),
            f.map_or(0, |f| f.points),
            fmt_opt(f.zip(paper).map(|(f, p)| f.prefactor / p.alpha), 2),
            fmt_opt(f.zip(paper).map(|(f, p)| f.exponent - p.beta), 2),
        )
    };
    out += &format!("\nfits p/k = alpha (phi - phi_c)^beta at the assumed phi_c, points more than {MIN_DISTANCE} above it:\n");
    out += "quasi-static points only | every point, rate-dependent ones extrapolated | the tables | every point at the Hertz curves' phi_c\n";
    let heads = format!(
        "{:>8} {:>12} {:>2} {:>6} {:>6}",
        "alpha", "beta", "n", "a/D.1", "b-D.2"
    );
    out += &format!(
        "{:<9} {:>4} {:>5} {:>6} | {heads} | {heads} | {:>7} {:>6} | {:>6} {:>8} {:>6}\n",
        "law", "mu", "nu", "phi_c", "D.1", "D.2", "phi_cH", "alpha_H", "beta_H"
    );
    for s in &report.analysis.series {
        let h = s.fit_hertz_jamming;
        out += &format!(
            "{:<9} {:>4} {:>5} {:>6.3} | {} | {} | {:>7} {:>6} | {:>6} {:>8} {:>6}\n",
            s.spec.law.name(),
            s.spec.friction,
            s.spec.poisson_ratio,
            report.options.jamming_point(s.spec.friction),
            fit_cells(s.fit, s.paper),
            fit_cells(s.fit_extrapolated, s.paper),
            fmt_opt(s.paper.map(|p| p.alpha), 4),
            fmt_opt(s.paper.map(|p| p.beta), 3),
            fmt_opt(h.map(|h| h.phi_c), 3),
            fmt_opt(h.map(|h| h.prefactor), 4),
            fmt_opt(h.map(|h| h.exponent), 3),
        );
    }
    out += "\np/k over the tables' law at the assumed phi_c (* rate-dependent, extrapolated; ~ unsettled or unresolved, slow pressure); log-rms over the row\n";
    out += &format!("{:<9} {:>4} {:>5} |", "law", "mu", "nu");
    for phi in &report.options.fractions {
        out += &format!(" {phi:>7}");
    }
    out += " | log-rms\n";
    for s in report.analysis.series.iter().filter(|s| s.paper.is_some()) {
        out += &format!(
            "{:<9} {:>4} {:>5} |",
            s.spec.law.name(),
            s.spec.friction,
            s.spec.poisson_ratio
        );
        for phi in &report.options.fractions {
            let cell = s
                .paper_ratio
                .iter()
                .find(|r| r.fraction == *phi)
                .map_or("-".into(), |r| {
                    let mark = match r.regime {
                        Regime::QuasiStatic => " ",
                        Regime::RateDependent => "*",
                        Regime::Unsettled | Regime::Unresolved => "~",
                    };
                    format!("{:.3}{mark}", r.ratio)
                });
            out += &format!(" {cell:>7}");
        }
        out += &format!(" | {}\n", fmt_opt(s.paper_log_rms, 3));
    }
    out += "\njamming point fitted to the Hertz curves (free phi_c):\n";
    for (mu, law) in &report.analysis.hertz_jamming {
        out += &format!(
            "  friction {mu}: {}\n",
            law.map_or("too few points".into(), |l| format!(
                "phi_c {:.4}, beta {:.3} +- {:.3} ({} points); assumed {:.3}",
                l.phi_c,
                l.exponent,
                l.exponent_error,
                l.points,
                report.options.jamming_point(*mu)
            ))
        );
    }
    out += &beta_section(report);
    out += "\ntrends the study reports (quasi-static points only):\n";
    for c in &report.analysis.checks {
        let verdict = match c.holds {
            Some(true) => "yes",
            Some(false) => "NO",
            None => "n/a",
        };
        out += &format!("  [{verdict}] {}: {}\n", c.claim, c.detail);
    }
    let seconds: f64 = report
        .analysis
        .series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.seconds))
        .sum();
    out += &format!(
        "\n{} runs ({} run now, the others reused), {:.0} s of run time in all; this invocation {:.0} s\n",
        report.analysis.series.iter().map(|s| s.points.len()).sum::<usize>(),
        report.ran,
        seconds,
        report.seconds
    );
    out
}

/// Jamming points at which the text shows the scanned `beta`.
const SHOWN_JAMMING_POINTS: [f64; 5] = [0.55, 0.58, 0.6, 0.62, 0.64];

/// The section on why `beta` differs from Table D.2: the exponent of the
/// measured pressures at each rate, against the jamming point assumed,
/// and the jamming point that would give the tables' exponent.
fn beta_section(report: &ShearReport) -> String {
    let opts = &report.options;
    let mut out = format!(
        "\nwhy beta differs: every point fitted at the measured slow rate ({}) and fast rate ({}), \
         unextrapolated, at the assumed phi_c; every point (extrapolated) at other phi_c; \
         the phi_c at which that fit gives Table D.2's beta, and its alpha there over D.1\n",
        opts.rate,
        opts.rate * opts.rate_factor
    );
    out += &format!(
        "{:<9} {:>4} {:>5} {:>6} | {:>6} {:>12} {:>12} |",
        "law", "mu", "nu", "D.2", "phi_c", "beta slow", "beta fast"
    );
    for c in SHOWN_JAMMING_POINTS {
        out += &format!(" {:>6}", format!("@{c}"));
    }
    out += &format!(" | {:>9} {:>7}\n", "phi_c(D.2)", "a/D.1");
    for s in &report.analysis.series {
        let b = &s.beta;
        out += &format!(
            "{:<9} {:>4} {:>5} {:>6} | {:>6.3} {:>12} {:>12} |",
            s.spec.law.name(),
            s.spec.friction,
            s.spec.poisson_ratio,
            fmt_opt(s.paper.map(|p| p.beta), 3),
            opts.jamming_point(s.spec.friction),
            fmt_exponent(b.slow),
            fmt_exponent(b.fast),
        );
        for c in SHOWN_JAMMING_POINTS {
            let at = b
                .scan
                .iter()
                .find(|(phi_c, _)| (phi_c - c).abs() < 1e-9)
                .map(|(_, beta)| *beta);
            out += &format!(" {:>6}", fmt_opt(at, 3));
        }
        let m = b.paper_phi_c;
        out += &format!(
            " | {:>9} {:>7}\n",
            fmt_opt(m.map(|m| m.phi_c), 4),
            fmt_opt(m.zip(s.paper).map(|(m, p)| m.prefactor / p.alpha), 3),
        );
    }
    out
}

/// Writes `shear.json`, `table.txt`, `shear.svg`, `beta.svg` and the first
/// run's scene (`scene.json`) into `dir` (the runs are already under
/// `dir/runs`).
pub fn write_report(report: &ShearReport, scene: &Scene, dir: &Path) -> Result<(), ShearError> {
    let out = output::write_report(report, dir)?;
    out.json("scene.json", scene)?;
    Ok(())
}

impl StudyReport for ShearReport {
    const JSON: &'static str = "shear.json";

    /// `table.txt` ([`table`]) and `shear.svg` ([`panels`], three to a row).
    fn draw(&self, out: &StudyOutput) -> Result<(), OutputError> {
        out.text("table.txt", &table(self))?;
        out.svg_rows("shear.svg", &panels(self), 3)?;
        out.svg_rows("beta.svg", &beta_panels(self), 3)?;
        Ok(())
    }
}

/// One panel per friction coefficient and Poisson's ratio: `p / k`
/// against `phi - phi_c` (log-log) under each law, every point with a
/// positive pressure (rate-dependent ones at their extrapolation), and the
/// tables' law over the same range. The series keep their order, and so
/// their colours, in every panel.
fn panels(report: &ShearReport) -> Vec<Panel> {
    let opts = &report.options;
    let mut curves: Vec<(f64, f64)> = Vec::new();
    for s in &report.analysis.series {
        let c = (s.spec.friction, s.spec.poisson_ratio);
        if !curves.contains(&c) {
            curves.push(c);
        }
    }
    curves.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    curves
        .iter()
        .map(|&(mu, nu)| {
            let phi_c = opts.jamming_point(mu);
            let distances: Vec<f64> = opts
                .fractions
                .iter()
                .map(|phi| phi - phi_c)
                .filter(|x| *x > MIN_DISTANCE)
                .collect();
            let mut series = Vec::new();
            for law in [
                ContactLaw::Hertz,
                ContactLaw::Standard,
                ContactLaw::Advanced,
            ] {
                let points = report
                    .analysis
                    .series
                    .iter()
                    .find(|s| {
                        s.spec.law == law && s.spec.friction == mu && s.spec.poisson_ratio == nu
                    })
                    .map(|s| {
                        s.points
                            .iter()
                            .filter(|p| p.fraction > phi_c + MIN_DISTANCE)
                            .filter_map(|p| {
                                p.fitted_pressure(true).map(|v| (p.fraction - phi_c, v))
                            })
                            .collect()
                    })
                    .unwrap_or_default();
                series.push(Series::new(law.name(), points, Mark::LinePoints));
            }
            let tables = report
                .analysis
                .series
                .iter()
                .find(|s| s.spec.friction == mu && s.spec.poisson_ratio == nu)
                .and_then(|s| s.paper);
            let (lo, hi) = distances
                .iter()
                .fold((f64::INFINITY, 0.0f64), |(lo, hi), &x| {
                    (lo.min(x), hi.max(x))
                });
            let line = match tables {
                Some(law) if hi > 0.0 => (0..=40)
                    .map(|k| {
                        let x = (lo.ln() + (hi.ln() - lo.ln()) * k as f64 / 40.0).exp();
                        (x, law.alpha * x.powf(law.beta))
                    })
                    .collect(),
                _ => Vec::new(),
            };
            series.push(Series::new("Tables D.1/D.2", line, Mark::Line));
            Panel {
                title: format!("friction {mu}, Poisson's ratio {nu} (phi_c {phi_c:.3})"),
                x_label: "phi - phi_c".into(),
                y_label: "p / k".into(),
                log_x: true,
                log_y: true,
                series,
            }
        })
        .collect()
}

/// One panel per friction coefficient: each curve's `beta` (every point)
/// against the jamming point assumed, and Table D.2's `beta` at each
/// Poisson's ratio drawn, as a flat line.
fn beta_panels(report: &ShearReport) -> Vec<Panel> {
    let series = &report.analysis.series;
    let frictions = super::sorted_distinct(series.iter().map(|s| s.spec.friction));
    frictions
        .iter()
        .map(|&mu| {
            let curves: Vec<_> = series.iter().filter(|s| s.spec.friction == mu).collect();
            let mut drawn: Vec<Series> = curves
                .iter()
                .map(|s| {
                    Series::new(
                        format!("{}, nu {}", s.spec.law.name(), s.spec.poisson_ratio),
                        s.beta.scan.clone(),
                        Mark::LinePoints,
                    )
                })
                .collect();
            let span = curves
                .iter()
                .flat_map(|s| s.beta.scan.iter().map(|(c, _)| *c))
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), c| {
                    (lo.min(c), hi.max(c))
                });
            drawn.extend(paper_beta_lines(
                curves.iter().map(|s| (s.spec.poisson_ratio, s.paper)),
                span.0,
                span.1,
            ));
            Panel {
                title: format!(
                    "friction {mu}: beta against the assumed phi_c (ours {:.3})",
                    report.options.jamming_point(mu)
                ),
                x_label: "assumed phi_c".into(),
                y_label: "beta".into(),
                log_x: false,
                log_y: false,
                series: drawn,
            }
        })
        .collect()
}
