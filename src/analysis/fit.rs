//! Least-squares straight lines: moduli from stress-strain series, power
//! laws in log-log; and linear interpolation along a sampled curve.

/// A fitted line `y = slope x + intercept`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Line {
    /// Slope.
    pub slope: f64,
    /// Intercept.
    pub intercept: f64,
}

/// Ordinary least squares through `(x, y)`; `None` for fewer than two
/// distinct `x` values.
pub fn least_squares_line(x: &[f64], y: &[f64]) -> Option<Line> {
    let n = x.len().min(y.len());
    if n < 2 {
        return None;
    }
    let mx = x[..n].iter().sum::<f64>() / n as f64;
    let my = y[..n].iter().sum::<f64>() / n as f64;
    let sxx: f64 = x[..n].iter().map(|a| (a - mx) * (a - mx)).sum();
    let sxy: f64 = x[..n]
        .iter()
        .zip(&y[..n])
        .map(|(a, b)| (a - mx) * (b - my))
        .sum();
    if sxx <= 0.0 {
        return None;
    }
    let slope = sxy / sxx;
    Some(Line {
        slope,
        intercept: my - slope * mx,
    })
}

/// A least-squares line with its uncertainty.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LineFit {
    /// The line.
    pub line: Line,
    /// Standard error of the slope (residual variance over `n - 2`).
    pub slope_error: f64,
    /// Root-mean-square residual about the line.
    pub rms_residual: f64,
    /// Points fitted.
    pub points: usize,
}

/// [`least_squares_line`] with the slope's standard error; `None` for
/// fewer than three points (no residual degrees of freedom) or a single
/// distinct `x`.
pub fn fit_line(x: &[f64], y: &[f64]) -> Option<LineFit> {
    let n = x.len().min(y.len());
    if n < 3 {
        return None;
    }
    let line = least_squares_line(x, y)?;
    let mx = x[..n].iter().sum::<f64>() / n as f64;
    let sxx: f64 = x[..n].iter().map(|a| (a - mx) * (a - mx)).sum();
    let ss: f64 = x[..n]
        .iter()
        .zip(&y[..n])
        .map(|(a, b)| (b - line.intercept - line.slope * a).powi(2))
        .sum();
    Some(LineFit {
        line,
        slope_error: (ss / (n as f64 - 2.0) / sxx).sqrt(),
        rms_residual: (ss / n as f64).sqrt(),
        points: n,
    })
}

/// `y(x0)` by linear interpolation in increasing `x`; `None` outside it.
pub fn interpolate(x: &[f64], y: &[f64], x0: f64) -> Option<f64> {
    let k = x.partition_point(|&v| v < x0);
    if k == 0 || k >= x.len() {
        return (x.first() == Some(&x0)).then(|| y[0]);
    }
    let (x1, x2) = (x[k - 1], x[k]);
    let w = if x2 > x1 { (x0 - x1) / (x2 - x1) } else { 0.0 };
    Some(y[k - 1] + w * (y[k] - y[k - 1]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolation_is_exact_on_a_line_and_refuses_outside() {
        let x = [0.0, 1.0, 3.0];
        let y = [1.0, 3.0, 7.0];
        assert_eq!(interpolate(&x, &y, 2.0), Some(5.0));
        assert_eq!(interpolate(&x, &y, 0.0), Some(1.0));
        assert_eq!(interpolate(&x, &y, 3.0), Some(7.0));
        assert_eq!(interpolate(&x, &y, 3.5), None);
        assert_eq!(interpolate(&x, &y, -0.5), None);
    }

    #[test]
    fn recovers_an_exact_line() {
        let x = [0.0, 1.0, 2.0, 3.0];
        let y: Vec<f64> = x.iter().map(|v| 2.5 * v - 1.0).collect();
        let l = least_squares_line(&x, &y).unwrap();
        assert!((l.slope - 2.5).abs() < 1e-12 && (l.intercept + 1.0).abs() < 1e-12);
        assert!(least_squares_line(&[1.0, 1.0], &[0.0, 2.0]).is_none());
    }

    #[test]
    fn slope_error_matches_the_textbook_formula() {
        // slope 0.2, intercept 0.2, residuals -0.2, 0.6, -0.6, 0.2:
        // ss = 0.8, sxx = 5, so the error is sqrt(0.8 / 2 / 5).
        let f = fit_line(&[0.0, 1.0, 2.0, 3.0], &[0.0, 1.0, 0.0, 1.0]).unwrap();
        assert!((f.line.slope - 0.2).abs() < 1e-12);
        assert!((f.slope_error - 0.08f64.sqrt()).abs() < 1e-12);
        assert!((f.rms_residual - 0.2f64.sqrt()).abs() < 1e-12);
        assert!(fit_line(&[0.0, 1.0], &[0.0, 1.0]).is_none());
    }
}
