//! Power laws near jamming: `y = A (phi - phi_c)^beta` (pressure, grain
//! strain, asphericity) and `Z - Z_c = B (phi - phi_c)^gamma`.
//!
//! The jamming point is not measured directly; as in the source study it
//! is chosen so that the power law holds: for each candidate `phi_c` below
//! the smallest jammed volume fraction, `log y` is fitted linearly against
//! `log (phi - phi_c)` over the states with `phi - phi_c` up to the fit
//! window, and the candidate with the smallest residual wins. The exponent
//! comes with the standard error of the fitted slope.

use super::fit::fit_line;
use serde::{Deserialize, Serialize};

/// A fitted power law `y = prefactor (phi - phi_c)^exponent`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PowerLaw {
    /// The jamming point `phi_c` (given or fitted).
    pub phi_c: f64,
    /// The exponent.
    pub exponent: f64,
    /// Standard error of the exponent (from the linear fit in log-log).
    pub exponent_error: f64,
    /// The prefactor.
    pub prefactor: f64,
    /// Root-mean-square residual of `ln y` about the fit.
    pub rms_residual: f64,
    /// Points in the fit.
    pub points: usize,
    /// Largest `phi - phi_c` fitted.
    pub window: f64,
}

/// Least squares `ln y = ln A + beta ln x` over the points with
/// `0 < x <= window` and `y > 0`; `None` with fewer than three.
pub fn fit_power_law(x: &[f64], y: &[f64], window: f64) -> Option<PowerLaw> {
    let (lx, ly): (Vec<f64>, Vec<f64>) = x
        .iter()
        .zip(y)
        .filter(|(&x, &y)| x > 0.0 && x <= window && y > 0.0 && y.is_finite())
        .map(|(&x, &y)| (x.ln(), y.ln()))
        .unzip();
    let fit = fit_line(&lx, &ly)?;
    Some(PowerLaw {
        phi_c: 0.0,
        exponent: fit.line.slope,
        exponent_error: fit.slope_error,
        prefactor: fit.line.intercept.exp(),
        rms_residual: fit.rms_residual,
        points: fit.points,
        window,
    })
}

/// `y = A (phi - phi_c)^beta` with `phi_c` known.
pub fn power_law_at(phi: &[f64], y: &[f64], phi_c: f64, window: f64) -> Option<PowerLaw> {
    let x: Vec<f64> = phi.iter().map(|p| p - phi_c).collect();
    fit_power_law(&x, y, window).map(|f| PowerLaw { phi_c, ..f })
}

/// `y = A (phi - phi_c)^beta` with `phi_c` chosen, among `candidates`
/// values spread geometrically in `phi_min - phi_c` from `1e-5` to `span`
/// (`phi_min` the smallest `phi` with `y > 0`), as the one whose fit over
/// `phi - phi_c <= window` leaves the smallest residual. At least
/// `min_points` states must fall in the window.
pub fn power_law_with_jamming_point(
    phi: &[f64],
    y: &[f64],
    window: f64,
    span: f64,
    min_points: usize,
) -> Option<PowerLaw> {
    let phi_min = phi
        .iter()
        .zip(y)
        .filter(|(_, &y)| y > 0.0)
        .map(|(&p, _)| p)
        .fold(f64::INFINITY, f64::min);
    if !phi_min.is_finite() {
        return None;
    }
    const CANDIDATES: usize = 400;
    let (lo, hi) = (1e-5f64.ln(), span.ln());
    (0..CANDIDATES)
        .map(|k| phi_min - (lo + (hi - lo) * k as f64 / (CANDIDATES - 1) as f64).exp())
        .filter_map(|phi_c| power_law_at(phi, y, phi_c, window))
        .filter(|f| f.points >= min_points)
        .min_by(|a, b| a.rms_residual.total_cmp(&b.rms_residual))
}

/// Where `y` leaves the power law `law` for good: the smallest
/// `phi - phi_c` from which every state lies above `factor` times the law
/// (the source study finds the pressure rising faster than its 3/2 law
/// beyond about 0.1). `None` when the last state is still within.
pub fn departure(phi: &[f64], y: &[f64], law: &PowerLaw, factor: f64) -> Option<f64> {
    let mut points: Vec<(f64, f64)> = phi
        .iter()
        .zip(y)
        .map(|(p, y)| (p - law.phi_c, *y))
        .filter(|(x, y)| *x > 0.0 && y.is_finite())
        .collect();
    points.sort_by(|a, b| a.0.total_cmp(&b.0));
    let above = |&(x, y): &(f64, f64)| y > factor * law.prefactor * x.powf(law.exponent);
    let first_of_run = points.iter().rposition(|p| !above(p)).map_or(0, |k| k + 1);
    points.get(first_of_run).map(|p| p.0)
}

/// `Z - Z_c = B (phi - phi_c)^gamma` at a known `phi_c`. A free `Z_c`
/// and a free exponent are not both determined by a few noisy states (the
/// residual keeps falling as `Z_c` drops and the exponent with it), so
/// `Z_c` is the intercept of `Z` against `sqrt(phi - phi_c)` (the
/// expected law, least squares over the window), and the exponent is then
/// fitted freely in log-log at that `Z_c`: near 1/2 when the law holds.
/// Returns the fit and `Z_c`.
pub fn coordination_law(
    phi: &[f64],
    z: &[f64],
    phi_c: f64,
    window: f64,
    min_points: usize,
) -> Option<(PowerLaw, f64)> {
    let (root, zs): (Vec<f64>, Vec<f64>) = phi
        .iter()
        .zip(z)
        .filter(|(&p, _)| p - phi_c > 0.0 && p - phi_c <= window)
        .map(|(&p, &z)| ((p - phi_c).sqrt(), z))
        .unzip();
    if root.len() < min_points {
        return None;
    }
    let z_c = crate::analysis::fit::least_squares_line(&root, &zs)?.intercept;
    let dz: Vec<f64> = z.iter().map(|z| z - z_c).collect();
    power_law_at(phi, &dz, phi_c, window).map(|f| (f, z_c))
}
