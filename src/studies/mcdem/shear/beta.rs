//! Why the exponent `beta` differs from Table D.2: the same points fitted
//! at other shear rates and at other jamming points.
//!
//! The study fits `p / k = alpha |phi - phi_c|^beta` but prints neither
//! its jamming points nor its rates. Both move the fitted exponent: a
//! pressure still raised by the shear rate near jamming, or a jamming
//! point assumed above the true one, bends the curve down in log-log and
//! lowers `beta`. The diagnosis measures both effects on our points, so a
//! disagreement can be put down to them or not.

use crate::analysis::jamming::{power_law_at, PowerLaw};
use crate::reference::multicontact::PaperLaw;
use serde::{Deserialize, Serialize};

/// Closest a fitted point may lie to the jamming point.
pub(super) const MIN_DISTANCE: f64 = 0.005;
/// Lowest jamming point the scan tries.
const SCAN_FROM: f64 = 0.50;
/// Step of the scan.
const SCAN_STEP: f64 = 0.0025;
/// Bisection steps refining where the scan crosses the tables' `beta`
/// (the scan's step over 2^40 is far below any meaningful `phi_c`).
const BISECTIONS: usize = 40;

/// The exponent of one curve, fitted other ways.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BetaDiagnosis {
    /// Every point's measured pressure at the slow rate (no
    /// extrapolation), at the assumed jamming point.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub slow: Option<PowerLaw>,
    /// Every point's measured pressure at the fast rate, at the assumed
    /// jamming point.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fast: Option<PowerLaw>,
    /// `(phi_c, beta)`: every point (rate-dependent ones extrapolated)
    /// fitted at jamming points from 0.50 up to more than 0.005 below the
    /// smallest volume fraction measured, so that every scan fit holds the
    /// same points.
    pub scan: Vec<(f64, f64)>,
    /// The jamming point at which the same fit gives the tables' `beta`,
    /// if the scan crosses it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub paper_phi_c: Option<PowerLaw>,
}

/// Fits `(phi, p)` at `phi_c` from the points more than [`MIN_DISTANCE`]
/// above it.
pub(super) fn fit(points: &[(f64, f64)], phi_c: f64) -> Option<PowerLaw> {
    let (phi, p): (Vec<f64>, Vec<f64>) = points
        .iter()
        .filter(|(phi, p)| *phi > phi_c + MIN_DISTANCE && *p > 0.0)
        .copied()
        .unzip();
    power_law_at(&phi, &p, phi_c, 1.0)
}

/// The pressures over `k` of one curve, `(phi, p)`, as the diagnosis
/// fits them.
pub struct CurvePressures {
    /// Measured at the slow rate.
    pub slow: Vec<(f64, f64)>,
    /// Measured at the fast rate.
    pub fast: Vec<(f64, f64)>,
    /// Every point's pressure as the study fits it (rate-dependent ones
    /// extrapolated).
    pub every: Vec<(f64, f64)>,
}

/// The diagnosis of one curve at its assumed jamming point `phi_c`,
/// against the tables' law `paper` where listed.
pub fn diagnose(curve: &CurvePressures, phi_c: f64, paper: Option<PaperLaw>) -> BetaDiagnosis {
    let slow = fit(&curve.slow, phi_c);
    let fast = fit(&curve.fast, phi_c);
    let every = &curve.every;
    // The jamming point lies below every volume fraction that carried a
    // measured pressure, whether or not its extrapolation stayed positive.
    let smallest = curve
        .slow
        .iter()
        .chain(every)
        .map(|(phi, _)| *phi)
        .fold(f64::INFINITY, f64::min);
    // Strictly below, so that round-off cannot drop the first point.
    let holds_every_point = |c: f64| c + MIN_DISTANCE < smallest;
    let steps = if smallest.is_finite() {
        ((smallest - SCAN_FROM) / SCAN_STEP).ceil().max(0.0) as usize
    } else {
        0
    };
    let scan: Vec<(f64, f64)> = (0..=steps)
        .map(|k| SCAN_FROM + k as f64 * SCAN_STEP)
        .filter(|&c| holds_every_point(c))
        .filter_map(|c| fit(every, c).map(|f| (c, f.exponent)))
        .collect();
    let paper_phi_c = paper.and_then(|law| crossing(every, &scan, law.beta));
    BetaDiagnosis {
        slow,
        fast,
        scan,
        paper_phi_c,
    }
}

/// The fit at the jamming point where the scan's `beta` first crosses
/// `target`, refined by bisection between the two scan points around it.
fn crossing(points: &[(f64, f64)], scan: &[(f64, f64)], target: f64) -> Option<PowerLaw> {
    let pair = scan
        .windows(2)
        .find(|w| (w[0].1 - target) * (w[1].1 - target) <= 0.0)?;
    let (mut lo, mut hi) = (pair[0].0, pair[1].0);
    let below_at_lo = pair[0].1 < target;
    for _ in 0..BISECTIONS {
        let mid = 0.5 * (lo + hi);
        let beta = fit(points, mid)?.exponent;
        if (beta < target) == below_at_lo {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    fit(points, 0.5 * (lo + hi))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A curve `0.2 (phi - 0.62)^1.4` at the slow rate, raised near
    /// jamming at the fast rate.
    fn curve() -> CurvePressures {
        let slow: Vec<(f64, f64)> = [0.65, 0.7, 0.75, 0.8, 0.85, 0.9]
            .iter()
            .map(|&phi: &f64| (phi, 0.2 * (phi - 0.62f64).powf(1.4)))
            .collect();
        CurvePressures {
            fast: slow.iter().map(|&(phi, p)| (phi, p + 0.002)).collect(),
            every: slow.clone(),
            slow,
        }
    }

    #[test]
    fn the_slow_fit_is_exact_and_the_rate_lowers_beta() {
        let d = diagnose(&curve(), 0.62, None);
        let slow = d.slow.unwrap();
        assert!((slow.exponent - 1.4).abs() < 1e-12, "{slow:?}");
        assert_eq!(slow.points, 6);
        // An offset that matters most near jamming flattens the curve.
        let fast = d.fast.unwrap();
        assert!(fast.exponent < 1.3, "{fast:?}");
        assert!(d.paper_phi_c.is_none());
        // A point within 0.005 of the jamming point is left out.
        assert_eq!(fit(&curve().slow, 0.646).unwrap().points, 5);
    }

    #[test]
    fn beta_falls_as_the_jamming_point_rises_and_the_crossing_is_found() {
        let law = PaperLaw {
            alpha: 0.1,
            beta: 0.9,
        };
        let d = diagnose(&curve(), 0.62, Some(law));
        // From 0.50 in steps of 0.0025 to the last step more than 0.005
        // below the first point (0.6425), each fit holding every point.
        assert_eq!(d.scan.len(), 58);
        assert!((d.scan.last().unwrap().0 - 0.6425).abs() < 1e-12);
        assert!(d.scan.windows(2).all(|w| w[1].1 < w[0].1), "{:?}", d.scan);
        let at_true = d
            .scan
            .iter()
            .find(|(c, _)| (c - 0.62).abs() < 1e-9)
            .unwrap();
        assert!((at_true.1 - 1.4).abs() < 1e-9);
        // The crossing lies above the true jamming point, and the fit
        // there has the tables' beta.
        let m = d.paper_phi_c.unwrap();
        assert!(m.phi_c > 0.62 && m.phi_c < 0.6425, "{m:?}");
        assert_eq!(m.points, 6);
        assert!((m.exponent - 0.9).abs() < 1e-9, "{m:?}");
        // A first point whose extrapolated pressure fell below zero (left
        // out of the fits) still bounds the scan: the jamming point lies
        // below every fraction that carried a pressure.
        let mut dropped = curve();
        dropped.every.remove(0);
        let d = diagnose(&dropped, 0.62, Some(law));
        assert!((d.scan.last().unwrap().0 - 0.6425).abs() < 1e-12);
        // A beta the scan never reaches has no crossing.
        let steep = PaperLaw {
            alpha: 0.1,
            beta: 9.0,
        };
        assert!(diagnose(&curve(), 0.62, Some(steep)).paper_phi_c.is_none());
    }
}
