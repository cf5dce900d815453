//! The exponent `beta` against shear rate and system size, gathered from
//! several shear studies (`bpm mc-shear-trend`): each study folder holds
//! one system size and two rates (its slow and fast stages), so a set of
//! folders traces `beta` from fast to slow shear and from small to large
//! boxes. Each curve is fitted over the volume fractions that every
//! folder holding it measured, so that the fits compare like with like.

use super::analysis::curve_pressures;
use super::beta::fit;
use super::report::{fmt_exponent, paper_beta_lines};
use super::{ContactLaw, SeriesSpec, ShearError, ShearReport};
use crate::analysis::jamming::PowerLaw;
use crate::analysis::plot::{Mark, Panel, Series};
use crate::reference::multicontact::PaperLaw;
use crate::studies::output::{self, OutputError, StudyOutput, StudyReport};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// One curve of one study at one of its two rates.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TrendRow {
    /// The study's folder.
    pub folder: String,
    /// Spheres in its box.
    pub spheres: usize,
    /// The packing's seed.
    pub seed: u64,
    /// Dimensionless shear rate `gamma_dot d / sqrt(k / rho)`.
    pub rate: f64,
    /// The jamming point the study assumed, at which the row is fitted.
    pub phi_c: f64,
    /// Whether this is the study's slow stage.
    pub slow: bool,
    /// The fit of the measured pressures (no extrapolation) at the
    /// study's assumed jamming point.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fit: Option<PowerLaw>,
}

/// One curve across the studies that hold it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TrendCurve {
    /// The curve.
    pub spec: SeriesSpec,
    /// The volume fractions every study holding the curve measured.
    pub fractions: Vec<f64>,
    /// The tables' law, if listed.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub paper: Option<PaperLaw>,
    /// One row per study and rate, in decreasing rate.
    pub rows: Vec<TrendRow>,
}

/// The gathered trend.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ShearTrend {
    /// The command that wrote it.
    pub command: String,
    /// The crate's version.
    pub version: String,
    /// The study folders read.
    pub folders: Vec<String>,
    /// Every curve that at least one folder holds.
    pub curves: Vec<TrendCurve>,
}

/// A curve's `(phi, p / k)` in one study: `[slow stage, fast stage]`.
type StagePressures = [Vec<(f64, f64)>; 2];

/// The positive pressures over `k` of one curve in one study, by volume
/// fraction.
fn measured(report: &ShearReport, spec: &SeriesSpec) -> StagePressures {
    let Some(series) = report.analysis.series.iter().find(|s| s.spec == *spec) else {
        return [Vec::new(), Vec::new()];
    };
    let pressures = curve_pressures(&series.points);
    [pressures.slow, pressures.fast]
        .map(|stage| stage.into_iter().filter(|(_, p)| *p > 0.0).collect())
}

/// Gathers the curves of `reports` (each with its folder's name).
pub fn gather(reports: &[(String, ShearReport)], command: &str) -> ShearTrend {
    let mut specs: Vec<SeriesSpec> = Vec::new();
    for (_, r) in reports {
        for s in &r.analysis.series {
            if !specs.contains(&s.spec) {
                specs.push(s.spec);
            }
        }
    }
    let curves = specs
        .iter()
        .map(|spec| {
            let holding: Vec<(&(String, ShearReport), StagePressures)> = reports
                .iter()
                .filter(|(_, r)| r.analysis.series.iter().any(|s| s.spec == *spec))
                .map(|study| (study, measured(&study.1, spec)))
                .collect();
            let mut fractions: Option<Vec<f64>> = None;
            for stage in holding.iter().flat_map(|(_, stages)| stages) {
                let have: Vec<f64> = stage.iter().map(|(phi, _)| *phi).collect();
                fractions = Some(match fractions {
                    None => have,
                    Some(f) => f.into_iter().filter(|phi| have.contains(phi)).collect(),
                });
            }
            let fractions = fractions.unwrap_or_default();
            let ((_, first), _) = holding[0];
            let paper = first
                .analysis
                .series
                .iter()
                .find(|s| s.spec == *spec)
                .and_then(|s| s.paper);
            let mut rows: Vec<TrendRow> = holding
                .iter()
                .flat_map(|((folder, r), stages)| {
                    [true, false].map(|slow| {
                        let stage = &stages[usize::from(!slow)];
                        let points: Vec<(f64, f64)> = stage
                            .iter()
                            .filter(|(phi, _)| fractions.contains(phi))
                            .copied()
                            .collect();
                        let rate = if slow {
                            r.options.rate
                        } else {
                            r.options.rate * r.options.rate_factor
                        };
                        let phi_c = r.options.jamming_point(spec.friction);
                        TrendRow {
                            folder: folder.clone(),
                            spheres: r.options.spheres,
                            seed: r.options.seed,
                            rate,
                            phi_c,
                            slow,
                            fit: fit(&points, phi_c),
                        }
                    })
                })
                .collect();
            rows.sort_by(|a, b| b.rate.total_cmp(&a.rate).then(a.spheres.cmp(&b.spheres)));
            TrendCurve {
                spec: *spec,
                fractions,
                paper,
                rows,
            }
        })
        .collect();
    ShearTrend {
        command: command.to_string(),
        version: crate::VERSION.to_string(),
        folders: reports.iter().map(|(f, _)| f.clone()).collect(),
        curves,
    }
}

/// Reads the shear study in each of `folders` and gathers them.
pub fn gather_folders(folders: &[&Path], command: &str) -> Result<ShearTrend, ShearError> {
    let reports = folders
        .iter()
        .map(|dir| {
            let report: ShearReport = output::read_report(&dir.join("shear.json"))?;
            Ok((dir.display().to_string(), report))
        })
        .collect::<Result<Vec<_>, OutputError>>()?;
    if reports.is_empty() {
        return Err(ShearError::Options("no study folder given".into()));
    }
    Ok(gather(&reports, command))
}

/// The trend as text: per curve, one line per study and rate.
pub fn trend_table(trend: &ShearTrend) -> String {
    let mut out = String::from(
        "beta of p/k = alpha (phi - phi_c)^beta from the measured pressures (no extrapolation), \
         at each study's assumed phi_c, over the volume fractions every study of the curve measured\n",
    );
    for c in &trend.curves {
        out += &format!(
            "\n{} friction {} Poisson's ratio {}: fractions {:?}, Table D.2 beta {}\n",
            c.spec.law.name(),
            c.spec.friction,
            c.spec.poisson_ratio,
            c.fractions,
            c.paper.map_or("-".into(), |p| format!("{:.3}", p.beta)),
        );
        out += &format!(
            "  {:>9} {:>7} {:>5} {:>5} {:>6} {:>14} {:>8}  folder\n",
            "rate", "spheres", "seed", "stage", "phi_c", "beta", "alpha"
        );
        for r in &c.rows {
            out += &format!(
                "  {:>9.3e} {:>7} {:>5} {:>5} {:>6.3} {:>14} {:>8}  {}\n",
                r.rate,
                r.spheres,
                r.seed,
                if r.slow { "slow" } else { "fast" },
                r.phi_c,
                fmt_exponent(r.fit),
                r.fit.map_or("-".into(), |f| format!("{:.4}", f.prefactor)),
                r.folder,
            );
        }
    }
    out
}

impl StudyReport for ShearTrend {
    const JSON: &'static str = "trend.json";

    /// `trend.txt` ([`trend_table`]) and `trend.svg`: per friction,
    /// `beta` against the rate for each curve and system size, and the
    /// tables' `beta`.
    fn draw(&self, out: &StudyOutput) -> Result<(), OutputError> {
        out.text("trend.txt", &trend_table(self))?;
        out.svg_rows("trend.svg", &trend_panels(self), 2)?;
        Ok(())
    }
}

fn trend_panels(trend: &ShearTrend) -> Vec<Panel> {
    let frictions = super::sorted_distinct(trend.curves.iter().map(|c| c.spec.friction));
    frictions
        .iter()
        .map(|&mu| {
            let curves: Vec<&TrendCurve> = trend
                .curves
                .iter()
                .filter(|c| c.spec.friction == mu)
                .collect();
            let rates = curves
                .iter()
                .flat_map(|c| c.rows.iter().map(|r| r.rate))
                .fold((f64::INFINITY, 0.0f64), |(lo, hi), r| {
                    (lo.min(r), hi.max(r))
                });
            let mut series = Vec::new();
            for c in &curves {
                let sizes = super::sorted_distinct(c.rows.iter().map(|r| r.spheres as f64));
                let smallest = sizes.first().copied().unwrap_or(0.0);
                for n in sizes {
                    let points: Vec<(f64, f64)> = c
                        .rows
                        .iter()
                        .filter(|r| r.spheres as f64 == n)
                        .filter_map(|r| r.fit.map(|f| (r.rate, f.exponent)))
                        .collect();
                    // Points, not lines: a rate can hold several rows
                    // (two stages, two seeds), which a line would zigzag
                    // through. Larger boxes are rings over them.
                    let mark = if n == smallest {
                        Mark::Points
                    } else {
                        Mark::Rings
                    };
                    series.push(Series::new(
                        format!("{}, nu {}, N {n}", c.spec.law.name(), c.spec.poisson_ratio),
                        points,
                        mark,
                    ));
                }
            }
            // The tables fit the advanced closure: their lines in its
            // curves' order.
            series.extend(paper_beta_lines(
                curves
                    .iter()
                    .filter(|c| c.spec.law == ContactLaw::Advanced)
                    .map(|c| (c.spec.poisson_ratio, c.paper)),
                rates.0,
                rates.1,
            ));
            Panel {
                title: format!("friction {mu}: beta against shear rate"),
                x_label: "gamma_dot d / sqrt(k / rho)".into(),
                y_label: "beta".into(),
                log_x: true,
                log_y: false,
                series,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::super::{analyse, RecordedRun, ShearOptions};
    use super::*;

    /// A report whose one curve follows `alpha (phi - phi_c)^beta` at the
    /// slow rate and twice that at the fast one, at `fractions`.
    fn report(spheres: usize, rate: f64, beta: f64, fractions: &[f64]) -> ShearReport {
        let mut opts = ShearOptions {
            spheres,
            rate,
            ..Default::default()
        };
        opts.series.truncate(1);
        let spec = opts.series[0];
        let phi_c = opts.jamming_point(spec.friction);
        let runs: Vec<RecordedRun> = fractions
            .iter()
            .map(|&phi| {
                let p = 0.1 * (phi - phi_c).powf(beta);
                RecordedRun::steady_for_tests(&opts, spec, phi, p + 0.01, p)
            })
            .collect();
        ShearReport {
            command: String::new(),
            version: String::new(),
            options: opts.clone(),
            packings: Vec::new(),
            analysis: analyse(&opts, &runs),
            ran: 0,
            seconds: 0.0,
        }
    }

    #[test]
    fn each_curve_is_fitted_over_the_fractions_every_study_measured() {
        let all = [0.65, 0.7, 0.75, 0.8, 0.85, 0.9];
        let reports = vec![
            ("a".to_string(), report(256, 2e-3, 1.2, &all)),
            ("b".to_string(), report(1024, 5e-4, 1.5, &all[1..])),
        ];
        let trend = gather(&reports, "test");
        assert_eq!(trend.curves.len(), 1);
        let c = &trend.curves[0];
        assert_eq!(c.fractions, all[1..].to_vec());
        // Two rows per study, by decreasing rate: a fast, a slow, b fast,
        // b slow.
        let rates: Vec<f64> = c.rows.iter().map(|r| r.rate).collect();
        assert_eq!(rates, vec![8e-3, 2e-3, 2e-3, 5e-4]);
        assert_eq!(c.rows[1].spheres, 256);
        assert!(c.rows[1].slow && !c.rows[2].slow);
        for r in &c.rows {
            let f = r.fit.unwrap();
            assert_eq!(f.points, 5, "{r:?}");
            let beta = if r.spheres == 256 { 1.2 } else { 1.5 };
            // The slow rows are the power law; the fast ones, raised by a
            // constant, are flatter.
            if r.slow {
                assert!((f.exponent - beta).abs() < 1e-9, "{r:?}");
            } else {
                assert!(f.exponent < beta - 0.1, "{r:?}");
            }
        }
        // The study's own diagnosis reads the slow and fast windows the
        // same way.
        let own = &reports[0].1.analysis.series[0].beta;
        assert!((own.slow.unwrap().exponent - 1.2).abs() < 1e-9);
        assert!(own.fast.unwrap().exponent < 1.1);
        let text = trend_table(&trend);
        assert!(text.contains("1024"), "{text}");
    }
}
