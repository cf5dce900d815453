//! `bpm compare-compaction`: several compaction studies side by side
//! (rough against smoother grains, different `nu`, engines, rates): the
//! curves of each in one set of plots, their fits in one table, and where
//! each study's pressure joins the first's (the source study finds that
//! friction stops mattering near `phi = 0.7`). Studies of DEM spheres
//! (`bpm compact --model dem`) sit beside grains as in the source study's
//! Figs. 6-8: their `phi_sphere` in its own panel, and the volume fractions
//! of every study at common pressures.

use super::{is_jammed, read_report, CompactionError, CompactionReport, CompactionRun, StateRow};
use crate::analysis::plot::{Mark, Panel, Series};
use crate::studies::output::StudyOutput;
use std::path::Path;

/// One study to compare: its report and its label.
pub struct Study {
    /// Legend and table label.
    pub label: String,
    /// The study's `compaction.json`.
    pub report: CompactionReport,
}

/// Reads `dir/compaction.json`, refitted with this version's analysis.
pub fn read_study(dir: &Path, label: &str) -> Result<Study, CompactionError> {
    Ok(Study {
        label: label.into(),
        report: read_report(dir)?,
    })
}

/// Largest factor between two studies' pressures at the same `phi_MC`
/// that counts as agreement in [`joins_at`].
pub const AGREEMENT_FACTOR: f64 = 1.1;

/// `(phi_MC, P / E_eff)` of a run's compression states with `P > 0`,
/// sorted.
fn pressure_curve(run: &CompactionRun) -> Vec<(f64, f64)> {
    let mut points: Vec<(f64, f64)> = run
        .states
        .iter()
        .filter(|s| s.stage.starts_with("compress") && s.p_over_e_eff > 0.0)
        .map(|s| (s.packing.phi_mc, s.p_over_e_eff))
        .collect();
    points.sort_by(|a, b| a.0.total_cmp(&b.0));
    points
}

/// `ln y` of a `(x, y)` curve at `x = phi`, linear in `ln y` between
/// neighbouring points; `None` outside the curve.
fn log_value_at(curve: &[(f64, f64)], phi: f64) -> Option<f64> {
    let k = curve.partition_point(|p| p.0 < phi);
    if curve.get(k).is_some_and(|p| p.0 == phi) {
        return Some(curve[k].1.ln());
    }
    if k == 0 || k == curve.len() {
        return None;
    }
    let ((x0, y0), (x1, y1)) = (curve[k - 1], curve[k]);
    let t = (phi - x0) / (x1 - x0);
    Some(y0.ln() + t * (y1.ln() - y0.ln()))
}

/// The smallest `phi_MC` from which every state of `other` has a pressure
/// within [`AGREEMENT_FACTOR`] of `reference`'s at the same `phi_MC`
/// (interpolated), taken over every pair of their runs (seeds are not
/// pooled: each run's curve is compared with each of the other study's,
/// and the latest join counts); `None` when some pair still differs at its
/// last comparable state or no pair overlaps.
pub fn joins_at(reference: &CompactionReport, other: &CompactionReport) -> Option<f64> {
    let mut latest: Option<f64> = None;
    for a in &reference.runs {
        for b in &other.runs {
            let join = curves_join_at(&pressure_curve(a), &pressure_curve(b))?;
            latest = Some(latest.map_or(join, |l| l.max(join)));
        }
    }
    latest
}

/// Volume fractions at which [`comparison_table`] lists pressure ratios.
const RATIO_AT: [f64; 6] = [0.6, 0.65, 0.7, 0.8, 0.9, 0.95];

/// `P_other / P_reference` at `phi` (interpolated in `ln P`), the
/// geometric mean over every pair of their runs; `None` where no pair
/// covers `phi`.
pub fn pressure_ratio(
    reference: &CompactionReport,
    other: &CompactionReport,
    phi: f64,
) -> Option<f64> {
    let logs: Vec<f64> = reference
        .runs
        .iter()
        .flat_map(|a| other.runs.iter().map(move |b| (a, b)))
        .filter_map(|(a, b)| {
            Some(log_value_at(&pressure_curve(b), phi)? - log_value_at(&pressure_curve(a), phi)?)
        })
        .collect();
    (!logs.is_empty()).then(|| (logs.iter().sum::<f64>() / logs.len() as f64).exp())
}

/// Distances from jamming at which [`comparison_table`] lists pressure,
/// grain strain and shape.
const DISTANCE_AT: [f64; 4] = [0.01, 0.03, 0.1, 0.3];

/// `pick` of a study's jammed states at `phi - phi_c = x` (each run at its
/// own `phi_c`, interpolated linearly in log-log), the geometric mean over
/// runs; `None` where no run covers `x`.
pub fn mean_at_distance(
    report: &CompactionReport,
    x: f64,
    pick: fn(&StateRow) -> f64,
) -> Option<f64> {
    let logs: Vec<f64> = report
        .runs
        .iter()
        .filter_map(|r| {
            let phi_c = r.fits.pressure?.phi_c;
            let mut curve: Vec<(f64, f64)> = r
                .states
                .iter()
                .filter(|s| is_jammed(s))
                .map(|s| (s.packing.phi_mc - phi_c, pick(s)))
                .filter(|&(d, y)| d > 0.0 && y > 0.0)
                .map(|(d, y)| (d.ln(), y))
                .collect();
            curve.sort_by(|a, b| a.0.total_cmp(&b.0));
            log_value_at(&curve, x.ln())
        })
        .collect();
    (!logs.is_empty()).then(|| (logs.iter().sum::<f64>() / logs.len() as f64).exp())
}

/// [`joins_at`] on two sorted `(phi, P)` curves.
fn curves_join_at(base: &[(f64, f64)], other: &[(f64, f64)]) -> Option<f64> {
    let compared: Vec<(f64, bool)> = other
        .iter()
        .copied()
        .filter_map(|(phi, p)| {
            log_value_at(base, phi).map(|lp| (phi, (p.ln() - lp).abs() <= AGREEMENT_FACTOR.ln()))
        })
        .collect();
    let first = compared.iter().rposition(|c| !c.1).map_or(0, |k| k + 1);
    compared.get(first).map(|c| c.0)
}

type Point = dyn Fn(&Study, &CompactionRun, &StateRow) -> Option<(f64, f64)>;

/// One series per run of every study, of the compression states' points
/// (every panel lists the runs in one order, so each keeps its colour).
fn series(studies: &[Study], f: &Point) -> Vec<Series> {
    studies
        .iter()
        .flat_map(|s| {
            s.report.runs.iter().map(move |r| {
                Series::new(
                    format!("{}, seed {}", s.label, r.seed),
                    r.states
                        .iter()
                        .filter(|st| st.stage.starts_with("compress"))
                        .filter_map(|st| f(s, r, st))
                        .collect(),
                    Mark::LinePoints,
                )
            })
        })
        .collect()
}

/// Pressures at which [`comparison_table`] lists volume fractions.
const PHI_AT_PRESSURE: [f64; 6] = [1e-5, 1e-4, 1e-3, 1e-2, 3e-2, 1e-1];

/// The volume fraction `pick` of a run where its pressure first reaches
/// `p` (`P / E_eff`) during compression, interpolated linearly in `ln P`
/// between the two states around that crossing; `None` if no compression
/// state lies at or below `p` (the jam ended above it) or none above.
fn phi_at_pressure(run: &CompactionRun, p: f64, pick: fn(&StateRow) -> f64) -> Option<f64> {
    let path: Vec<(f64, f64)> = run
        .states
        .iter()
        .filter(|s| s.stage.starts_with("compress") && s.p_over_e_eff > 0.0)
        .map(|s| (s.p_over_e_eff, pick(s)))
        .collect();
    first_crossing(&path, p)
}

/// `x` where a path of `(P, x)` points (positive `P`, in order) first
/// steps from `P <= p` to `P > p`, linear in `ln P` between the two.
fn first_crossing(path: &[(f64, f64)], p: f64) -> Option<f64> {
    path.windows(2).find_map(|w| {
        let ((pa, xa), (pb, xb)) = (w[0], w[1]);
        (pa <= p && p < pb).then(|| xa + (p / pa).ln() / (pb / pa).ln() * (xb - xa))
    })
}

/// The mean of [`phi_at_pressure`] over a study's runs that reach `p`.
fn mean_phi_at_pressure(
    report: &CompactionReport,
    p: f64,
    pick: fn(&StateRow) -> f64,
) -> Option<f64> {
    let v: Vec<f64> = report
        .runs
        .iter()
        .filter_map(|r| phi_at_pressure(r, p, pick))
        .collect();
    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
}

/// `Some` for a study of grains, `None` for spheres (which keep their
/// shape: no grain strain or asphericity).
fn grains(study: &Study) -> Option<()> {
    study.report.options.dem.is_none().then_some(())
}

/// The volume fraction a DEM study usually reports: `phi_sphere` for
/// spheres; `phi_MC` for grains (the source study's Fig. 6a).
fn nominal_phi(study: &Study, state: &StateRow) -> f64 {
    if study.report.options.dem.is_some() {
        state.packing.phi_sphere
    } else {
        state.packing.phi_mc
    }
}

/// `phi - phi_c` of a state, at its run's fitted `phi_c`.
fn distance(run: &CompactionRun, state: &StateRow) -> Option<f64> {
    let d = state.packing.phi_mc - run.fits.pressure?.phi_c;
    (d > 0.0).then_some(d)
}

/// Writes `comparison.svg` and `comparison.txt` into `dir`; returns the
/// table.
pub fn write_comparison(
    studies: &[Study],
    dir: &Path,
    command: &str,
) -> Result<String, CompactionError> {
    let out = StudyOutput::create(dir)?;
    let mut panels = vec![
        Panel {
            title: "pressure (paper Fig. 6, 11)".into(),
            x_label: "phi_MC".into(),
            y_label: "P / E_eff".into(),
            log_y: true,
            series: series(studies, &|_, _, s| Some((s.packing.phi_mc, s.p_over_e_eff))),
            ..Panel::default()
        },
        Panel {
            title: "force coordination, rattlers removed (paper Fig. 8)".into(),
            x_label: "phi_MC".into(),
            y_label: "Z_force".into(),
            series: series(studies, &|_, _, s| {
                Some((s.packing.phi_mc, s.packing.z_force))
            }),
            ..Panel::default()
        },
        Panel {
            title: "grain volumetric strain (paper Fig. 12a)".into(),
            x_label: "phi_MC - phi_c".into(),
            y_label: "mean eps_V".into(),
            log_x: true,
            log_y: true,
            series: series(studies, &|study, r, s| {
                grains(study)?;
                Some((distance(r, s)?, s.packing.eps_v_mean))
            }),
        },
        Panel {
            title: "grain asphericity (paper Fig. 12b)".into(),
            x_label: "phi_MC - phi_c".into(),
            y_label: "mean alpha - alpha0".into(),
            log_x: true,
            log_y: true,
            series: series(studies, &|study, r, s| {
                grains(study)?;
                Some((distance(r, s)?, s.packing.asphericity_excess_mean))
            }),
        },
    ];
    if studies.iter().any(|s| s.report.options.dem.is_some()) {
        panels.extend([
            Panel {
                title: "pressure, phi_sphere for spheres, phi_MC for grains (paper Fig. 6a)".into(),
                x_label: "phi".into(),
                y_label: "P / E_eff".into(),
                log_y: true,
                series: series(studies, &|study, _, s| {
                    Some((nominal_phi(study, s), s.p_over_e_eff))
                }),
                ..Panel::default()
            },
            Panel {
                title: "pressure near jamming (paper Fig. 7)".into(),
                x_label: "phi_MC - phi_c".into(),
                y_label: "P / E_eff".into(),
                log_x: true,
                log_y: true,
                series: series(studies, &|_, r, s| Some((distance(r, s)?, s.p_over_e_eff))),
            },
            Panel {
                title: "force coordination near jamming (paper Fig. 8a)".into(),
                x_label: "phi_MC - phi_c".into(),
                y_label: "Z_force".into(),
                log_x: true,
                series: series(studies, &|_, r, s| {
                    Some((distance(r, s)?, s.packing.z_force))
                }),
                ..Panel::default()
            },
        ]);
    }
    out.svg("comparison.svg", &panels)?;
    let text = comparison_table(studies, command);
    out.text("comparison.txt", &text)?;
    Ok(text)
}

/// The fits of every study side by side (means over their runs), with the
/// mean and sample sd over every run of every study (meaningful when the
/// studies are realisations of one system), and where each study's
/// pressure joins the first's.
pub fn comparison_table(studies: &[Study], command: &str) -> String {
    use std::fmt::Write as _;
    let mut t = format!("# bpm compare-compaction\n# {command}\n\n");
    let mean = |study: &Study, f: &dyn Fn(&CompactionRun) -> Option<f64>| {
        let v: Vec<f64> = study.report.runs.iter().filter_map(f).collect();
        if v.is_empty() {
            "-".to_string()
        } else {
            format!("{:.4}", v.iter().sum::<f64>() / v.len() as f64)
        }
    };
    let _ = write!(t, "{:<24}", "quantity (mean of runs)");
    for s in studies {
        let _ = write!(t, " {:>16}", s.label);
    }
    t.push_str("   every run: mean +- sd (runs; a spread only if the studies are realisations of one system)");
    let _ = write!(t, "\n{:<24}", "a_B (k d)");
    for s in studies {
        let _ = write!(t, " {:>16.2}", s.report.options.a_b);
    }
    t.push('\n');
    type Pick = fn(&CompactionRun) -> Option<f64>;
    let rows: [(&str, Pick); 12] = [
        ("phi_c", |r| r.fits.pressure.map(|p| p.phi_c)),
        ("P exponent", |r| r.fits.pressure.map(|p| p.exponent)),
        ("Z_c (force)", |r| r.fits.z_force.map(|z| z.z_c)),
        ("Z exponent", |r| r.fits.z_force.map(|z| z.law.exponent)),
        ("eps_V exponent", |r| r.fits.eps_v.map(|p| p.exponent)),
        ("alpha exponent", |r| r.fits.asphericity.map(|p| p.exponent)),
        ("P leaves its law at", |r| r.fits.pressure_departure),
        ("K_P exponent", |r| r.fits.bulk_modulus.map(|p| p.exponent)),
        ("G_P exponent", |r| r.fits.shear_modulus.map(|p| p.exponent)),
        ("nu_P minimum", |r| {
            super::report::poisson_minimum(r).map(|m| m.moduli.poisson)
        }),
        ("phi - phi_c there", |r| {
            let phi_c = r.fits.pressure?.phi_c;
            super::report::poisson_minimum(r).map(|m| m.phi_mc - phi_c)
        }),
        ("last phi_MC", |r| {
            r.states
                .iter()
                .rev()
                .find(|s| s.stage.starts_with("compress"))
                .map(|s| s.packing.phi_mc)
        }),
    ];
    for (name, pick) in rows {
        let _ = write!(t, "{name:<24}");
        for s in studies {
            let _ = write!(t, " {:>16}", mean(s, &pick));
        }
        let every: Vec<f64> = studies
            .iter()
            .flat_map(|s| s.report.runs.iter().filter_map(pick))
            .collect();
        let (m, sd) = crate::studies::calibration::mean_sd(&every);
        match every.len() {
            0 => {}
            1 => {
                let _ = write!(t, "   {m:.4} (1, no spread)");
            }
            n => {
                let _ = write!(t, "   {m:.4} +- {sd:.4} ({n})");
            }
        }
        t.push('\n');
    }
    for (name, pick) in [
        (
            "P / E_eff",
            (|s: &StateRow| s.p_over_e_eff) as fn(&StateRow) -> f64,
        ),
        ("mean eps_V", |s| s.packing.eps_v_mean),
        ("mean alpha - alpha0", |s| s.packing.asphericity_excess_mean),
    ] {
        let header: Vec<String> = DISTANCE_AT.iter().map(|x| format!("{x:>8}")).collect();
        let rows: Vec<&Study> = studies.iter().collect();
        append_grid(
            &mut t,
            &format!("{name} at phi - phi_c ="),
            &header,
            &rows,
            8,
            &|s, k| mean_at_distance(&s.report, DISTANCE_AT[k], pick).map(|v| format!("{v:.2e}")),
        );
    }
    for (name, pick) in [
        (
            "phi_MC",
            (|s: &StateRow| s.packing.phi_mc) as fn(&StateRow) -> f64,
        ),
        ("phi_sphere (spheres)", |s| s.packing.phi_sphere),
    ] {
        let spheres_only = name.ends_with("(spheres)");
        let shown: Vec<&Study> = studies
            .iter()
            .filter(|s| !spheres_only || s.report.options.dem.is_some())
            .collect();
        if shown.is_empty() {
            continue;
        }
        let header: Vec<String> = PHI_AT_PRESSURE
            .iter()
            .map(|p| format!("{p:>7.0e}"))
            .collect();
        let title = format!("{name} where P / E_eff first reaches");
        append_grid(&mut t, &title, &header, &shown, 7, &|s, k| {
            mean_phi_at_pressure(&s.report, PHI_AT_PRESSURE[k], pick).map(|v| format!("{v:.4}"))
        });
    }
    if let Some((first, rest)) = studies.split_first() {
        let header: Vec<String> = RATIO_AT.iter().map(|phi| format!("{phi:>7.2}")).collect();
        let rows: Vec<&Study> = rest.iter().collect();
        let title = format!("P / P({}) at phi_MC =", first.label);
        append_grid(&mut t, &title, &header, &rows, 7, &|s, k| {
            pressure_ratio(&first.report, &s.report, RATIO_AT[k]).map(|r| format!("{r:.3}"))
        });
        let _ = writeln!(
            t,
            "\npressure within a factor {AGREEMENT_FACTOR} of {}'s at the same phi_MC from (paper: rough and smoother grains from about phi = 0.7):",
            first.label
        );
        for s in rest {
            let _ = writeln!(
                t,
                "  {:<20} {}",
                s.label,
                joins_at(&first.report, &s.report)
                    .map_or("never".to_string(), |phi| format!("phi_MC = {phi:.4}"))
            );
        }
    }
    t
}

/// Appends a table to `t`: a blank line, `title` and the column
/// headers, then a row per study of its label and `cell(study, column)`
/// right-aligned in `width` ("-" where `None`).
fn append_grid(
    t: &mut String,
    title: &str,
    header: &[String],
    studies: &[&Study],
    width: usize,
    cell: &dyn Fn(&Study, usize) -> Option<String>,
) {
    use std::fmt::Write as _;
    let _ = write!(t, "\n{title}");
    for h in header {
        let _ = write!(t, " {h}");
    }
    t.push('\n');
    for s in studies {
        let _ = write!(t, "  {:<20}", s.label);
        for k in 0..header.len() {
            let c = cell(s, k).unwrap_or_else(|| "-".into());
            let _ = write!(t, " {c:>width$}");
        }
        t.push('\n');
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn curves_join_where_they_stay_within_the_factor() {
        // P = phi^10 against 2 phi^10 below 0.7 and 1.05 phi^10 above.
        let base: Vec<(f64, f64)> = (0..=40)
            .map(|k| 0.55 + 0.01 * k as f64)
            .map(|phi| (phi, phi.powi(10)))
            .collect();
        let other: Vec<(f64, f64)> = (0..=35)
            .map(|k| 0.555 + 0.01 * k as f64)
            .map(|phi| (phi, phi.powi(10) * if phi < 0.7 { 2.0 } else { 1.05 }))
            .collect();
        assert_eq!(curves_join_at(&base, &other), Some(0.555 + 0.01 * 15.0));
        // Interpolation in ln P is exact for an exponential.
        let exp: Vec<(f64, f64)> = vec![(0.5, 1.0), (0.7, 2f64.exp())];
        let lp = log_value_at(&exp, 0.6).unwrap();
        assert!((lp - 1.0).abs() < 1e-12);
        assert!(log_value_at(&exp, 0.8).is_none());
        assert!((log_value_at(&exp, 0.5).unwrap()).abs() < 1e-15);
        assert!((log_value_at(&exp, 0.7).unwrap() - 2.0).abs() < 1e-15);
        // Log-log interpolation is exact for a power law.
        let power: Vec<(f64, f64)> = [0.01f64, 0.1]
            .iter()
            .map(|d| (d.ln(), d.powf(1.5)))
            .collect();
        let y = log_value_at(&power, 0.03f64.ln()).unwrap().exp();
        assert!((y / 0.03f64.powf(1.5) - 1.0).abs() < 1e-12, "{y}");
        // The first upward crossing counts, interpolated in ln P.
        let path = [(1e-6, 0.60), (4e-6, 0.61), (2e-6, 0.62), (1e-4, 0.70)];
        let x = first_crossing(&path, 2e-6).unwrap();
        assert!((x - 0.605).abs() < 1e-12, "{x}");
        let x = first_crossing(&path, 1e-5).unwrap();
        let t = (1e-5f64 / 2e-6).ln() / (1e-4f64 / 2e-6).ln();
        assert!((x - (0.62 + t * 0.08)).abs() < 1e-12, "{x}");
        assert_eq!(first_crossing(&path, 1e-3), None);
        assert_eq!(first_crossing(&path, 1e-7), None);
        // Still apart at the end: never joins.
        let apart: Vec<(f64, f64)> = base.iter().map(|&(x, y)| (x + 0.001, 2.0 * y)).collect();
        assert_eq!(curves_join_at(&base, &apart), None);
    }
}
