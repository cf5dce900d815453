//! How Gaussian a sample is: z-scores, sample skewness and excess
//! kurtosis with their standard errors under a Gaussian, and normalised
//! histograms (for the per-grain strain and shape distributions).

/// All values equal (their mean can round away from them, leaving a tiny
/// spurious spread), or some not finite.
fn no_spread(values: &[f64]) -> bool {
    let (lo, hi) = values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    values.iter().any(|v| !v.is_finite()) || lo == hi
}

/// `(x - mean) / sd` of each value (sample sd, `n - 1`); empty when there
/// are fewer than two values or they are all equal.
pub fn z_scores(values: &[f64]) -> Vec<f64> {
    let n = values.len();
    if n < 2 {
        return Vec::new();
    }
    if no_spread(values) {
        return Vec::new();
    }
    let mean = values.iter().sum::<f64>() / n as f64;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
    if var <= 0.0 || !var.is_finite() {
        return Vec::new();
    }
    let sd = var.sqrt();
    values.iter().map(|v| (v - mean) / sd).collect()
}

/// Shape of a sample against a Gaussian.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shape {
    /// Sample size.
    pub n: usize,
    /// Skewness `m3 / m2^(3/2)` (0 for a Gaussian).
    pub skewness: f64,
    /// Its standard error for a Gaussian sample, `sqrt(6 / n)`.
    pub skewness_error: f64,
    /// Excess kurtosis `m4 / m2^2 - 3` (0 for a Gaussian).
    pub excess_kurtosis: f64,
    /// Its standard error for a Gaussian sample, `sqrt(24 / n)`.
    pub excess_kurtosis_error: f64,
}

/// Skewness and excess kurtosis from the central moments of `values`
/// (biased moment estimators); `None` for fewer than four values or no
/// spread.
pub fn shape(values: &[f64]) -> Option<Shape> {
    let n = values.len();
    if n < 4 || no_spread(values) {
        return None;
    }
    let nf = n as f64;
    let mean = values.iter().sum::<f64>() / nf;
    let moment = |k: i32| values.iter().map(|v| (v - mean).powi(k)).sum::<f64>() / nf;
    let m2 = moment(2);
    if m2 <= 0.0 || !m2.is_finite() {
        return None;
    }
    Some(Shape {
        n,
        skewness: moment(3) / m2.powf(1.5),
        skewness_error: (6.0 / nf).sqrt(),
        excess_kurtosis: moment(4) / (m2 * m2) - 3.0,
        excess_kurtosis_error: (24.0 / nf).sqrt(),
    })
}

/// Probability density of `values` in `bins` equal bins over `[lo, hi)`,
/// as `(bin centre, density)`; values outside are counted in the
/// normalisation but not drawn, so the densities stay comparable with a
/// normalised curve.
pub fn density_histogram(values: &[f64], lo: f64, hi: f64, bins: usize) -> Vec<(f64, f64)> {
    if values.is_empty() || bins == 0 || lo.is_nan() || hi.is_nan() || hi <= lo {
        return Vec::new();
    }
    let width = (hi - lo) / bins as f64;
    let mut counts = vec![0usize; bins];
    for &v in values {
        if v >= lo && v < hi {
            counts[(((v - lo) / width) as usize).min(bins - 1)] += 1;
        }
    }
    let norm = 1.0 / (values.len() as f64 * width);
    counts
        .iter()
        .enumerate()
        .map(|(k, &c)| (lo + (k as f64 + 0.5) * width, c as f64 * norm))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moments_of_known_samples() {
        // Symmetric: skewness 0; two points at +-1 have m4/m2^2 = 1.
        let s = shape(&[-1.0, 1.0, -1.0, 1.0]).unwrap();
        assert!(s.skewness.abs() < 1e-15 && (s.excess_kurtosis + 2.0).abs() < 1e-15);
        // 0, 0, 0, 4: mean 1, m2 = 3, m3 = 6 * ... by hand:
        // deviations -1, -1, -1, 3: m2 = 12/4 = 3, m3 = 24/4 = 6,
        // m4 = 84/4 = 21.
        let s = shape(&[0.0, 0.0, 0.0, 4.0]).unwrap();
        assert!((s.skewness - 6.0 / 3f64.powf(1.5)).abs() < 1e-12);
        assert!((s.excess_kurtosis - (21.0 / 9.0 - 3.0)).abs() < 1e-12);
        assert!((s.skewness_error - 1.5f64.sqrt()).abs() < 1e-15);
        assert!(shape(&[1.0, 1.0, 1.0, 1.0]).is_none());
        // Equal values whose mean rounds away from them.
        assert!(shape(&[0.1; 7]).is_none() && z_scores(&[0.1; 3]).is_empty());
        assert!(shape(&[0.0, 1.0, f64::NAN, 2.0]).is_none());
        assert!(shape(&[1.0, 2.0, 3.0]).is_none());
    }

    #[test]
    fn z_scores_have_zero_mean_and_unit_sd() {
        let z = z_scores(&[2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0]);
        let mean = z.iter().sum::<f64>() / z.len() as f64;
        let var = z.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (z.len() - 1) as f64;
        assert!(mean.abs() < 1e-15 && (var - 1.0).abs() < 1e-14);
        assert!(z_scores(&[3.0, 3.0]).is_empty());
    }

    #[test]
    fn a_histogram_integrates_to_the_fraction_inside() {
        let v = [0.1, 0.2, 0.6, 0.9, 1.5];
        let h = density_histogram(&v, 0.0, 1.0, 4);
        let integral: f64 = h.iter().map(|(_, d)| d * 0.25).sum();
        assert!((integral - 0.8).abs() < 1e-15);
        assert_eq!(h[0], (0.125, 2.0 / (5.0 * 0.25)));
    }
}
