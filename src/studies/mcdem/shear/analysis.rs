//! The analysis of recorded runs: mean pressures over strain windows,
//! the quasi-static test, the power-law fits, the comparison with the
//! study's tables and its trends.

use super::beta::{diagnose, fit, BetaDiagnosis, CurvePressures, MIN_DISTANCE};
use super::protocol::{stage_rates, stiffness};
use super::{sorted_distinct, ContactLaw, RecordedRun, SeriesSpec, ShearOptions, StageSeries};
use crate::analysis::jamming::{power_law_with_jamming_point, PowerLaw};
use crate::reference::multicontact::{PaperLaw, PaperTables};
use serde::{Deserialize, Serialize};

/// Mean of a series over a strain window, with its standard error from
/// block averages.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct WindowMean {
    /// Mean.
    pub mean: f64,
    /// Standard error: the spread of the means of [`BLOCKS`] consecutive
    /// blocks over the square root of their number.
    pub error: f64,
    /// Rows averaged.
    pub rows: usize,
    /// The means of the window's two halves differ by more than three
    /// standard errors and 3%.
    pub drifts: bool,
}

/// Round-off allowed at a window's edges (strain).
const WINDOW_EDGE: f64 = 1e-9;

/// Blocks of a block average.
pub const BLOCKS: usize = 5;

/// The mean of `values` at `strain` within `[from, to]`; `None` with
/// fewer rows than [`BLOCKS`].
pub fn window_mean(strain: &[f64], values: &[f64], from: f64, to: f64) -> Option<WindowMean> {
    const EDGE: f64 = WINDOW_EDGE;
    let inside: Vec<f64> = strain
        .iter()
        .zip(values)
        .filter(|(&s, _)| s >= from - EDGE && s <= to + EDGE)
        .map(|(_, &v)| v)
        .collect();
    let n = inside.len();
    if n < BLOCKS || inside.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let mean_of = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let mean = mean_of(&inside);
    let blocks: Vec<f64> = (0..BLOCKS)
        .map(|b| mean_of(&inside[b * n / BLOCKS..(b + 1) * n / BLOCKS]))
        .collect();
    let spread = blocks.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / (BLOCKS - 1) as f64;
    let error = (spread / BLOCKS as f64).sqrt();
    let (first, second) = (mean_of(&inside[..n / 2]), mean_of(&inside[n / 2..]));
    let gap = (first - second).abs();
    Some(WindowMean {
        mean,
        error,
        rows: n,
        drifts: gap > 3.0 * error && gap > 0.03 * mean.abs(),
    })
}

/// Whether a point reached the quasi-static limit.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Regime {
    /// The two rates agree within the tolerance (or within their
    /// noise): the slow pressure is the quasi-static one.
    QuasiStatic,
    /// The fast pressure is higher: the quasi-static pressure is
    /// extrapolated to zero rate.
    RateDependent,
    /// A window drifts, or the fast pressure is lower beyond tolerance
    /// and noise: the fast window (earlier in strain) had not reached the
    /// steady state, so the rates cannot be compared; the slow pressure
    /// stands, unextrapolated.
    Unsettled,
    /// The two agree only within noise larger than the tolerance: a rate
    /// effect of the tolerance's size could not be seen. The slow
    /// pressure stands.
    Unresolved,
}

/// One volume fraction of a curve, analysed.
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct ShearPoint {
    /// Volume fraction.
    pub fraction: f64,
    /// Fast shear's pressure over `k` (second half of its strain).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fast: Option<WindowMean>,
    /// Slow shear's pressure over `k` (after the discarded strain).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub slow: Option<WindowMean>,
    /// Slow shear's shear stress over its pressure.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stress_ratio: Option<f64>,
    /// `p_fast / p_slow - 1`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rate_effect: Option<f64>,
    /// Quasi-static or not.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub regime: Option<Regime>,
    /// The quasi-static pressure over `k`: the slow one when quasi-static
    /// or unsettled, else the extrapolation `p_slow - (p_fast - p_slow) /
    /// (f^n - 1)` with `n = 1/2`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub quasi_static: Option<f64>,
    /// The same extrapolation with `n = 1` (a bracket).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub extrapolated_linear: Option<f64>,
    /// The largest closure correction over the radius in the slow window
    /// (in every recorded row, if the run stopped).
    pub largest_correction: f64,
    /// The most contacts the advanced closure switched off in a row of
    /// the slow window (in any recorded row, if the run stopped).
    pub switched_off: f64,
    /// Wall-clock seconds of the run.
    pub seconds: f64,
    /// Why the run stopped, if it did.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stopped: Option<String>,
}

impl ShearPoint {
    /// Analyses a recorded run.
    pub fn analyse(run: &RecordedRun, opts: &ShearOptions) -> Self {
        let stage = |name: &str| run.stages.iter().find(|s| s.name == name);
        let complete = |s: &&StageSeries| s.complete;
        let fast_stage = stage("fast").filter(complete);
        let slow_stage = stage("slow").filter(complete);
        let [strain_fast, strain_slow] = run.key.strains;
        let fast = fast_stage
            .and_then(|s| window_mean(&s.strain, &s.pressure, 0.5 * strain_fast, strain_fast));
        let window =
            |s: &StageSeries, v: &[f64]| window_mean(&s.strain, v, opts.discard, strain_slow);
        let slow = slow_stage.and_then(|s| window(s, &s.pressure));
        let stress_ratio = slow_stage
            .and_then(|s| window(s, &s.shear_stress))
            .zip(slow.filter(|p| p.mean > 0.0))
            .map(|(t, p)| t.mean / p.mean);
        let largest = |v: fn(&StageSeries) -> &[f64]| match slow_stage {
            Some(s) => s
                .strain
                .iter()
                .zip(v(s))
                .filter(|(&e, _)| e >= opts.discard - WINDOW_EDGE)
                .map(|(_, &v)| v)
                .fold(0.0, f64::max),
            // A stopped run shows how far it got.
            None => run
                .stages
                .iter()
                .flat_map(|s| v(s).iter().copied())
                .fold(0.0, f64::max),
        };
        let largest_correction = largest(|s| &s.largest_correction);
        let switched_off = largest(|s| &s.switched_off);
        let mut point = Self {
            fraction: run.key.fraction,
            fast,
            slow,
            stress_ratio,
            rate_effect: None,
            regime: None,
            quasi_static: None,
            extrapolated_linear: None,
            largest_correction,
            switched_off,
            seconds: run.seconds,
            stopped: run.stopped.clone(),
        };
        if let (Some(f), Some(s)) = (fast, slow) {
            if s.mean > 0.0 {
                let gap = f.mean - s.mean;
                // Two standard errors of the difference count as noise.
                let noise = 2.0 * f.error.hypot(s.error);
                let tolerance = (opts.quasi_static_tolerance * s.mean).max(noise);
                // Drifting windows are not steady: their rates cannot be
                // compared.
                let extrapolate = |n: f64| s.mean - gap / (run.key.rate_factor.powf(n) - 1.0);
                point.rate_effect = Some(gap / s.mean);
                let (regime, pressure) = if f.drifts || s.drifts {
                    (Regime::Unsettled, s.mean)
                } else if gap.abs() <= tolerance && noise > opts.quasi_static_tolerance * s.mean {
                    (Regime::Unresolved, s.mean)
                } else if gap.abs() <= tolerance {
                    (Regime::QuasiStatic, s.mean)
                } else if gap > 0.0 {
                    point.extrapolated_linear = Some(extrapolate(1.0));
                    (Regime::RateDependent, extrapolate(0.5))
                } else {
                    (Regime::Unsettled, s.mean)
                };
                point.regime = Some(regime);
                point.quasi_static = Some(pressure);
            }
        }
        point
    }

    /// The pressure the fits use: the quasi-static one, and a
    /// rate-dependent point's extrapolation or an unsettled point's slow
    /// pressure only if `every_point`.
    pub fn fitted_pressure(&self, every_point: bool) -> Option<f64> {
        match self.regime? {
            Regime::QuasiStatic => self.quasi_static,
            _ if every_point => self.quasi_static,
            _ => None,
        }
        .filter(|p| *p > 0.0)
    }
}

/// One curve, analysed and fitted.
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
pub struct SeriesResult {
    /// The curve.
    pub spec: SeriesSpec,
    /// `k = 4/3 E*` (E).
    pub stiffness: f64,
    /// Fast and slow shear rates (1 / tau).
    pub shear_rates: [f64; 2],
    /// One point per volume fraction.
    pub points: Vec<ShearPoint>,
    /// `p / k = alpha (phi - phi_c)^beta` at the assumed jamming point,
    /// from the quasi-static points only.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fit: Option<PowerLaw>,
    /// The same from every point, the rate-dependent ones at their
    /// extrapolated pressure.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fit_extrapolated: Option<PowerLaw>,
    /// The same (every point) at the jamming point fitted to the Hertz
    /// curves at this friction.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fit_hertz_jamming: Option<PowerLaw>,
    /// The tables' law at this friction and Poisson's ratio, if listed.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub paper: Option<PaperLaw>,
    /// Our pressure (every point) over the tables' law at the assumed
    /// jamming point, at each volume fraction more than 0.005 above it.
    pub paper_ratio: Vec<PaperRatio>,
    /// Root mean square of the log of those ratios.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub paper_log_rms: Option<f64>,
    /// The exponent fitted at the measured rates and at other jamming
    /// points.
    #[serde(default)]
    pub beta: BetaDiagnosis,
}

/// Our pressure over the tables' law at one volume fraction.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct PaperRatio {
    /// Volume fraction.
    pub fraction: f64,
    /// The ratio.
    pub ratio: f64,
    /// The point's regime.
    pub regime: Regime,
}

/// A yes-or-no check of a trend the study reports.
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
pub struct TrendCheck {
    /// What is checked.
    pub claim: String,
    /// Whether it holds here (`None`: not enough points to tell).
    pub holds: Option<bool>,
    /// The numbers behind it.
    pub detail: String,
}

/// Fits `points` to `p / k = alpha (phi - phi_c)^beta` at `phi_c`, from
/// points more than 0.005 above it.
pub fn fit_at(points: &[ShearPoint], phi_c: f64, use_extrapolated: bool) -> Option<PowerLaw> {
    let pressures: Vec<(f64, f64)> = points
        .iter()
        .filter_map(|pt| {
            pt.fitted_pressure(use_extrapolated)
                .map(|p| (pt.fraction, p))
        })
        .collect();
    fit(&pressures, phi_c)
}

/// A curve's pressures as the exponent's diagnosis fits them.
pub(super) fn curve_pressures(points: &[ShearPoint]) -> CurvePressures {
    let measured = |window: fn(&ShearPoint) -> Option<f64>| -> Vec<(f64, f64)> {
        points
            .iter()
            .filter_map(|pt| window(pt).map(|p| (pt.fraction, p)))
            .collect()
    };
    CurvePressures {
        slow: measured(|pt| pt.slow.map(|w| w.mean)),
        fast: measured(|pt| pt.fast.map(|w| w.mean)),
        every: measured(|pt| pt.fitted_pressure(true)),
    }
}

/// The analysed study.
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
pub struct Analysis {
    /// Jamming point fitted to the Hertz curves at each friction, every
    /// Poisson's ratio together (`None` when too few points).
    pub hertz_jamming: Vec<(f64, Option<PowerLaw>)>,
    /// Every curve.
    pub series: Vec<SeriesResult>,
    /// The study's trends, checked.
    pub checks: Vec<TrendCheck>,
}

/// Analyses every recorded run into curves, fits and checks.
pub fn analyse(opts: &ShearOptions, runs: &[RecordedRun]) -> Analysis {
    let tables = PaperTables::stored();
    let mut series: Vec<SeriesResult> = opts
        .series
        .iter()
        .map(|spec| {
            let mut points: Vec<ShearPoint> = runs
                .iter()
                .filter(|r| r.key.series == *spec)
                .map(|r| ShearPoint::analyse(r, opts))
                .collect();
            points.sort_by(|a, b| a.fraction.total_cmp(&b.fraction));
            let phi_c = opts.jamming_point(spec.friction);
            let fit = fit_at(&points, phi_c, false);
            let fit_extrapolated = fit_at(&points, phi_c, true);
            let paper = tables.law(spec.friction, spec.poisson_ratio);
            let paper_ratio: Vec<PaperRatio> = paper
                .map(|law| {
                    points
                        .iter()
                        .filter(|pt| pt.fraction > phi_c + MIN_DISTANCE)
                        .filter_map(|pt| {
                            let p = pt.fitted_pressure(true)?;
                            let table = law.alpha * (pt.fraction - phi_c).powf(law.beta);
                            Some(PaperRatio {
                                fraction: pt.fraction,
                                ratio: p / table,
                                regime: pt.regime?,
                            })
                        })
                        .collect()
                })
                .unwrap_or_default();
            let paper_log_rms = (!paper_ratio.is_empty()).then(|| {
                (paper_ratio
                    .iter()
                    .map(|r| r.ratio.ln().powi(2))
                    .sum::<f64>()
                    / paper_ratio.len() as f64)
                    .sqrt()
            });
            let beta = diagnose(&curve_pressures(&points), phi_c, paper);
            SeriesResult {
                spec: *spec,
                stiffness: stiffness(spec.poisson_ratio),
                shear_rates: stage_rates(opts.rate, opts.rate_factor, spec.poisson_ratio),
                points,
                fit,
                fit_extrapolated,
                fit_hertz_jamming: None,
                paper,
                paper_ratio,
                paper_log_rms,
                beta,
            }
        })
        .collect();
    let frictions = sorted_distinct(opts.series.iter().map(|s| s.friction));
    let hertz_jamming: Vec<(f64, Option<PowerLaw>)> = frictions
        .iter()
        .map(|&mu| {
            let (phi, p): (Vec<f64>, Vec<f64>) = series
                .iter()
                .filter(|s| s.spec.law == ContactLaw::Hertz && s.spec.friction == mu)
                .flat_map(|s| {
                    s.points
                        .iter()
                        .filter_map(|pt| pt.fitted_pressure(true).map(|p| (pt.fraction, p)))
                })
                .unzip();
            (mu, power_law_with_jamming_point(&phi, &p, 0.5, 0.2, 4))
        })
        .collect();
    for s in &mut series {
        if let Some((_, Some(law))) = hertz_jamming.iter().find(|(mu, _)| *mu == s.spec.friction) {
            s.fit_hertz_jamming = fit_at(&s.points, law.phi_c, true);
        }
    }
    let checks = trend_checks(&series, opts);
    Analysis {
        hertz_jamming,
        series,
        checks,
    }
}

/// The quasi-static pressure of the curve `(law, mu, nu)` at `phi`, if
/// the point is quasi-static: the trends are checked on measured
/// pressures, not on extrapolations.
fn pressure_of(
    series: &[SeriesResult],
    law: ContactLaw,
    mu: f64,
    nu: f64,
    phi: f64,
) -> Option<f64> {
    series
        .iter()
        .find(|s| s.spec.law == law && s.spec.friction == mu && s.spec.poisson_ratio == nu)?
        .points
        .iter()
        .find(|p| p.fraction == phi)?
        .fitted_pressure(false)
}

/// The study's trends: Hertz does not depend on Poisson's ratio; the
/// advanced closure's pressure rises with it, most at zero friction. Only
/// quasi-static points are compared.
fn trend_checks(series: &[SeriesResult], opts: &ShearOptions) -> Vec<TrendCheck> {
    let mut checks = Vec::new();
    let frictions = sorted_distinct(series.iter().map(|s| s.spec.friction));
    let nus = |law: ContactLaw, mu: f64| {
        let mut v: Vec<f64> = series
            .iter()
            .filter(|s| s.spec.law == law && s.spec.friction == mu)
            .map(|s| s.spec.poisson_ratio)
            .collect();
        v.sort_by(f64::total_cmp);
        v
    };
    for &mu in &frictions {
        let hertz = nus(ContactLaw::Hertz, mu);
        if let (Some(&lo), Some(&hi)) = (hertz.first(), hertz.last()) {
            if hi > lo {
                let ratios: Vec<(f64, f64)> = opts
                    .fractions
                    .iter()
                    .filter_map(|&phi| {
                        let p = |nu| pressure_of(series, ContactLaw::Hertz, mu, nu, phi);
                        Some((phi, p(hi)? / p(lo)?))
                    })
                    .collect();
                checks.push(TrendCheck {
                    claim: format!(
                        "Hertz, friction {mu}: p/k at Poisson's ratio {hi} within 10% of {lo} at every volume fraction"
                    ),
                    holds: (!ratios.is_empty())
                        .then(|| ratios.iter().all(|(_, r)| (r - 1.0).abs() <= 0.1)),
                    detail: format_ratios(&ratios),
                });
            }
        }
        let advanced = nus(ContactLaw::Advanced, mu);
        if advanced.len() >= 2 {
            let mut rises = Vec::new();
            let mut detail = Vec::new();
            for &phi in &opts.fractions {
                let p: Option<Vec<f64>> = advanced
                    .iter()
                    .map(|&nu| pressure_of(series, ContactLaw::Advanced, mu, nu, phi))
                    .collect();
                if let Some(p) = p {
                    rises.push(p.windows(2).all(|w| w[1] > w[0]));
                    detail.push(format!(
                        "{phi}: {}",
                        p.iter()
                            .map(|v| format!("{v:.4}"))
                            .collect::<Vec<_>>()
                            .join(", ")
                    ));
                }
            }
            checks.push(TrendCheck {
                claim: format!(
                    "advanced, friction {mu}: p/k rises with Poisson's ratio ({advanced:?}) at every volume fraction"
                ),
                holds: (!rises.is_empty()).then(|| rises.iter().all(|&r| r)),
                detail: detail.join("; "),
            });
        }
    }
    // The tables' Poisson effect is by far largest without friction: p at
    // 0.5 over p at 0.25 at the largest volume fraction.
    let Some(&phi) = opts.fractions.iter().max_by(|a, b| a.total_cmp(b)) else {
        return checks;
    };
    let tables = PaperTables::stored();
    let effects: Vec<(f64, Option<f64>, Option<f64>)> = frictions
        .iter()
        .map(|&mu| {
            let p = |nu| pressure_of(series, ContactLaw::Advanced, mu, nu, phi);
            let ours = p(0.5).zip(p(0.25)).map(|(hi, lo)| hi / lo);
            let phi_c = opts.jamming_point(mu);
            let table = tables
                .law(mu, 0.5)
                .zip(tables.law(mu, 0.25))
                .map(|(hi, lo)| {
                    hi.alpha * (phi - phi_c).powf(hi.beta)
                        / (lo.alpha * (phi - phi_c).powf(lo.beta))
                });
            (mu, ours, table)
        })
        .filter(|e| e.1.is_some() || e.2.is_some())
        .collect();
    if effects.len() >= 2 {
        let measured: Vec<(f64, f64)> = effects
            .iter()
            .filter_map(|&(mu, ours, _)| ours.map(|o| (mu, o)))
            .collect();
        let smallest_friction = effects[0].0;
        // Without the smallest friction's own ratio there is nothing to say.
        let holds = (measured.len() >= 2 && measured[0].0 == smallest_friction).then(|| {
            measured
                .iter()
                .max_by(|a, b| a.1.total_cmp(&b.1))
                .is_some_and(|m| m.0 == smallest_friction)
        });
        checks.push(TrendCheck {
            claim: format!(
                "advanced: p/k at Poisson's ratio 0.5 over 0.25 at volume fraction {phi} is largest at friction {smallest_friction}"
            ),
            holds,
            detail: effects
                .iter()
                .map(|(mu, ours, table)| {
                    format!(
                        "friction {mu}: {} (tables {})",
                        ours.map_or("-".into(), |o| format!("{o:.2}")),
                        table.map_or("-".into(), |t| format!("{t:.2}"))
                    )
                })
                .collect::<Vec<_>>()
                .join(", "),
        });
    }
    checks
}

fn format_ratios(ratios: &[(f64, f64)]) -> String {
    ratios
        .iter()
        .map(|(phi, r)| format!("{phi}: {r:.3}"))
        .collect::<Vec<_>>()
        .join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::studies::mcdem::shear::{cube_edge, Grid, Packing, RunKey};

    #[test]
    fn a_window_mean_has_the_block_error_and_sees_drift() {
        let strain: Vec<f64> = (0..=100).map(|k| k as f64 * 0.01).collect();
        // Alternating +-1 about 3: every block mean is 3 up to one row.
        let flat: Vec<f64> = (0..=100)
            .map(|k| 3.0 + if k % 2 == 0 { 1.0 } else { -1.0 })
            .collect();
        let w = window_mean(&strain, &flat, 0.0, 0.99).unwrap();
        assert_eq!(w.rows, 100);
        assert!((w.mean - 3.0).abs() < 1e-12);
        assert!(w.error < 1e-12, "{w:?}");
        assert!(!w.drifts);
        // A ramp from 1 to 2 drifts: the halves differ by 0.5.
        let ramp: Vec<f64> = strain.iter().map(|s| 1.0 + s).collect();
        let w = window_mean(&strain, &ramp, 0.0, 1.0).unwrap();
        assert!(w.drifts, "{w:?}");
        assert!((w.mean - 1.5).abs() < 1e-12);
        // Five blocks of 20 rows, their means 0.2 apart: a standard
        // deviation of 0.2 sqrt(10 / 4), over sqrt(5).
        let w = window_mean(&strain[..100], &ramp[..100], 0.0, 1.0).unwrap();
        let expected = 0.2 * (10.0f64 / 4.0 / 5.0).sqrt();
        assert!(
            (w.error - expected).abs() < 1e-12,
            "{} vs {expected}",
            w.error
        );
        assert!(window_mean(&strain, &ramp, 0.0, 0.03).is_none());
    }

    fn recorded(fast: f64, slow: f64) -> RecordedRun {
        let opts = ShearOptions::grid(Grid::Quick);
        RecordedRun::steady_for_tests(&opts, opts.series[0], 0.9, fast, slow)
    }

    #[test]
    fn hertz_is_checked_against_poisson_ratio_on_quasi_static_points_only() {
        let mut opts = ShearOptions::grid(Grid::Quick);
        let spec = |poisson_ratio| SeriesSpec {
            law: ContactLaw::Hertz,
            friction: 0.5,
            poisson_ratio,
        };
        opts.series = vec![spec(0.25), spec(0.5)];
        let packing = Packing {
            fraction: 0.9,
            length: cube_edge(108, 0.9),
            reached: 0.9,
            centres: Vec::new(),
        };
        let run = |nu, fast, slow| RecordedRun {
            key: RunKey::new(&opts, &spec(nu), &packing),
            ..recorded(fast, slow)
        };
        let holds = |runs: &[RecordedRun]| analyse(&opts, runs).checks[0].holds;
        assert_eq!(
            holds(&[run(0.25, 0.1, 0.1), run(0.5, 0.105, 0.105)]),
            Some(true)
        );
        assert_eq!(
            holds(&[run(0.25, 0.1, 0.1), run(0.5, 0.12, 0.12)]),
            Some(false)
        );
        // A rate-dependent point is not compared.
        assert_eq!(holds(&[run(0.25, 0.1, 0.1), run(0.5, 0.2, 0.12)]), None);
    }

    #[test]
    fn the_quasi_static_test_and_the_extrapolation() {
        let opts = ShearOptions::grid(Grid::Quick);
        let p = ShearPoint::analyse(&recorded(0.104, 0.1), &opts);
        assert_eq!(p.regime, Some(Regime::QuasiStatic));
        assert!((p.quasi_static.unwrap() - 0.1).abs() < 1e-15);
        assert!((p.stress_ratio.unwrap() - 0.25).abs() < 1e-12);
        assert_eq!(p.fitted_pressure(false), p.quasi_static);
        // 20% apart at a rate factor of 4: p = p_QS + A rate^(1/2) gives
        // p_QS = 0.1 - 0.02 / (2 - 1); linear, 0.1 - 0.02 / 3.
        let p = ShearPoint::analyse(&recorded(0.12, 0.1), &opts);
        assert_eq!(p.regime, Some(Regime::RateDependent));
        assert!((p.quasi_static.unwrap() - 0.08).abs() < 1e-12);
        assert!((p.extrapolated_linear.unwrap() - (0.1 - 0.02 / 3.0)).abs() < 1e-12);
        assert_eq!(p.fitted_pressure(false), None);
        assert!((p.fitted_pressure(true).unwrap() - 0.08).abs() < 1e-12);
        // A fast pressure below the slow one is not extrapolated upwards:
        // the point is unsettled and keeps its slow pressure.
        let p = ShearPoint::analyse(&recorded(0.08, 0.1), &opts);
        assert_eq!(p.regime, Some(Regime::Unsettled));
        assert!((p.quasi_static.unwrap() - 0.1).abs() < 1e-15);
        assert_eq!(p.fitted_pressure(false), None);
        // A gap within the noise of the two means is quasi-static.
        let mut noisy = recorded(0.12, 0.1);
        // Rows 14 to 40 are averaged: runs of six alternately 0.04 above
        // and below, the mean unchanged.
        for (k, p) in noisy.stages[1].pressure.iter_mut().enumerate() {
            *p += match k {
                14..=19 | 26..=31 => 0.04,
                20..=25 | 32..=37 => -0.04,
                _ => 0.0,
            };
        }
        let p = ShearPoint::analyse(&noisy, &opts);
        assert!(p.slow.unwrap().error > 0.01, "{:?}", p.slow);
        assert!(!p.slow.unwrap().drifts);
        // ... but that noise is above the 5% tolerance: unresolved.
        assert_eq!(p.regime, Some(Regime::Unresolved));
        assert_eq!(p.fitted_pressure(false), None);
        assert!((p.fitted_pressure(true).unwrap() - p.slow.unwrap().mean).abs() < 1e-15);
        // A slow window that drifts is not steady, whatever the rates say.
        let mut drifting = recorded(0.1, 0.1);
        for (k, p) in drifting.stages[1].pressure.iter_mut().enumerate() {
            *p *= 1.0 + 0.005 * k as f64;
        }
        let p = ShearPoint::analyse(&drifting, &opts);
        assert!(p.slow.unwrap().drifts);
        assert_eq!(p.regime, Some(Regime::Unsettled));
        // A run that stopped in its slow stage has no pressure to fit.
        let mut stopped = recorded(0.1, 0.1);
        stopped.stages[1].complete = false;
        stopped.stopped = Some("beyond reach".into());
        let p = ShearPoint::analyse(&stopped, &opts);
        assert_eq!((p.slow, p.regime), (None, None));
        assert!(p.fitted_pressure(true).is_none());
    }

    #[test]
    fn the_fit_recovers_a_power_law_at_the_assumed_jamming_point() {
        let opts = ShearOptions::grid(Grid::Quick);
        let phi_c = opts.jamming_point(0.5);
        let (alpha, beta) = (0.2157, 0.7794);
        let points: Vec<ShearPoint> = [0.6, 0.65, 0.7, 0.8, 0.9]
            .iter()
            .map(|&phi| {
                let mut pt = ShearPoint::analyse(&recorded(0.1, 0.1), &opts);
                pt.fraction = phi;
                pt.quasi_static = Some(alpha * (phi - phi_c).powf(beta));
                pt
            })
            .collect();
        let fit = fit_at(&points, phi_c, false).unwrap();
        assert_eq!(fit.points, 5);
        assert!((fit.prefactor - alpha).abs() < 1e-12, "{fit:?}");
        assert!((fit.exponent - beta).abs() < 1e-12, "{fit:?}");
        // A point within 0.005 of phi_c is left out.
        let mut near = points.clone();
        near[0].fraction = phi_c + 0.004;
        assert_eq!(fit_at(&near, phi_c, false).unwrap().points, 4);
    }
}
