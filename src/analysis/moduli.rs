//! Bulk and shear moduli from recorded compression and shear series
//! (docs/protocols.md, "Calibration"): least-squares slopes of stress against strain.

use super::fit::least_squares_line;
use super::Recorded;
use crate::reference::paper;
use serde::{Deserialize, Serialize};

/// Why a modulus could not be measured.
#[derive(Debug, thiserror::Error)]
pub enum ModulusError {
    /// The stage did not record a needed column.
    #[error("stage `{stage}` recorded no `{column}` column")]
    MissingColumn {
        /// Stage name.
        stage: String,
        /// Column.
        column: &'static str,
    },
    /// Too few distinct strains, or a non-finite slope.
    #[error("stage `{stage}`: no finite slope through {rows} rows")]
    NoSlope {
        /// Stage name.
        stage: String,
        /// Rows recorded.
        rows: usize,
    },
}

fn column(stage: &impl Recorded, name: &'static str) -> Result<Vec<f64>, ModulusError> {
    stage.column(name).ok_or(ModulusError::MissingColumn {
        stage: stage.name().into(),
        column: name,
    })
}

fn slope(stage: &impl Recorded, x: &[f64], y: &[f64]) -> Result<f64, ModulusError> {
    least_squares_line(x, y)
        .map(|l| l.slope)
        .filter(|s| s.is_finite())
        .ok_or(ModulusError::NoSlope {
            stage: stage.name().into(),
            rows: x.len(),
        })
}

/// Volumetric strain `(V0 - V) / V0` (from the first row) and pressure of
/// an isotropic compression stage.
pub fn compression_series(stage: &impl Recorded) -> Result<(Vec<f64>, Vec<f64>), ModulusError> {
    let (lx, ly, lz) = (
        column(stage, "lx")?,
        column(stage, "ly")?,
        column(stage, "lz")?,
    );
    let p = column(stage, "pressure")?;
    let volume: Vec<f64> = (0..lx.len()).map(|k| lx[k] * ly[k] * lz[k]).collect();
    let v0 = *volume.first().ok_or(ModulusError::NoSlope {
        stage: stage.name().into(),
        rows: 0,
    })?;
    let strain: Vec<f64> = volume.iter().map(|v| (v0 - v) / v0).collect();
    Ok((strain, p))
}

/// Shear strain `xy / ly` and shear stress `-P_xy` of a simple-shear stage
/// (LAMMPS's pressure tensor is minus the stress).
pub fn shear_series(stage: &impl Recorded) -> Result<(Vec<f64>, Vec<f64>), ModulusError> {
    let (xy, ly, pxy) = (
        column(stage, "xy")?,
        column(stage, "ly")?,
        column(stage, "pxy")?,
    );
    let strain: Vec<f64> = xy.iter().zip(&ly).map(|(t, l)| t / l).collect();
    let stress: Vec<f64> = pxy.iter().map(|p| -p).collect();
    Ok((strain, stress))
}

/// Bulk modulus `K`: slope of the pressure against the volumetric strain
/// `(V0 - V) / V0` of an isotropic compression stage.
pub fn bulk_modulus(stage: &impl Recorded) -> Result<f64, ModulusError> {
    let (strain, p) = compression_series(stage)?;
    slope(stage, &strain, &p)
}

/// Shear modulus `G`: slope of `-P_xy` against the shear strain `xy / ly`
/// of a simple-shear stage.
pub fn shear_modulus(stage: &impl Recorded) -> Result<f64, ModulusError> {
    let (strain, stress) = shear_series(stage)?;
    slope(stage, &strain, &stress)
}

/// Poisson's ratio of an isotropic solid with moduli `k` and `g`.
pub fn poisson_ratio(k: f64, g: f64) -> f64 {
    (3.0 * k - 2.0 * g) / (2.0 * (3.0 * k + g))
}

/// Standard error of [`poisson_ratio`] from those of `k` and `g`
/// (independent): `9 sqrt(G^2 sK^2 + K^2 sG^2) / (2 (3K + G)^2)`.
pub fn poisson_ratio_error(k: f64, g: f64, k_error: f64, g_error: f64) -> f64 {
    9.0 * (g * g * k_error * k_error + k * k * g_error * g_error).sqrt()
        / (2.0 * (3.0 * k + g).powi(2))
}

/// K, G and what follows from them, for one solid and `a_B`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Moduli {
    /// Multibody strength (k d).
    pub a_b: f64,
    /// Bulk modulus (k / d).
    pub k: f64,
    /// Shear modulus (k / d).
    pub g: f64,
    /// G / K.
    pub g_over_k: f64,
    /// Poisson's ratio.
    pub nu: f64,
    /// The paper's fit of K at this a_B.
    pub paper_k: f64,
    /// The paper's fit of G/K at this a_B.
    pub paper_g_over_k: f64,
    /// Wall seconds of the two runs.
    pub seconds: f64,
}

impl Moduli {
    /// The moduli of one solid at `a_b` from its compression and shear
    /// stages (run in `seconds` together), beside the paper's fits.
    pub fn measured(
        a_b: f64,
        compression: &impl Recorded,
        shear: &impl Recorded,
        seconds: f64,
    ) -> Result<Self, ModulusError> {
        let k = bulk_modulus(compression)?;
        let g = shear_modulus(shear)?;
        Ok(Self {
            a_b,
            k,
            g,
            g_over_k: g / k,
            nu: poisson_ratio(k, g),
            paper_k: paper::bulk_modulus(a_b),
            paper_g_over_k: paper::shear_to_bulk(a_b),
            seconds,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A recorded table: named columns, one row per record.
    struct Table {
        columns: Vec<&'static str>,
        rows: Vec<Vec<f64>>,
    }

    impl Recorded for Table {
        fn name(&self) -> &str {
            "t"
        }

        fn column(&self, name: &str) -> Option<Vec<f64>> {
            let k = self.columns.iter().position(|c| *c == name)?;
            Some(self.rows.iter().map(|r| r[k]).collect())
        }
    }

    fn stage(columns: &[&'static str], rows: Vec<Vec<f64>>) -> Table {
        Table {
            columns: columns.to_vec(),
            rows,
        }
    }

    #[test]
    fn poisson_ratio_error_matches_finite_differences() {
        let (k, g, sk, sg) = (1.3, 0.4, 0.02, 0.03);
        let h = 1e-6;
        let dk = (poisson_ratio(k + h, g) - poisson_ratio(k - h, g)) / (2.0 * h);
        let dg = (poisson_ratio(k, g + h) - poisson_ratio(k, g - h)) / (2.0 * h);
        let expected = ((dk * sk).powi(2) + (dg * sg).powi(2)).sqrt();
        assert!((poisson_ratio_error(k, g, sk, sg) / expected - 1.0).abs() < 1e-8);
    }

    #[test]
    fn moduli_of_exact_linear_series() {
        // Volume strain e: lengths (1 - e)^(1/3), pressure 2 e.
        let rows = (0..5)
            .map(|k| {
                let e = 1e-3 * k as f64;
                let l = (1.0 - e).cbrt();
                vec![l, l, l, 2.0 * e]
            })
            .collect();
        let k = bulk_modulus(&stage(&["lx", "ly", "lz", "pressure"], rows)).unwrap();
        assert!((k - 2.0).abs() < 1e-9, "K = {k}");
        let rows = (0..5)
            .map(|k| {
                let g = 1e-3 * k as f64;
                vec![3.0 * g, 3.0, -0.7 * g]
            })
            .collect();
        let g = shear_modulus(&stage(&["xy", "ly", "pxy"], rows)).unwrap();
        assert!((g - 0.7).abs() < 1e-12, "G = {g}");
        assert!((poisson_ratio(1.0, 0.0) - 0.5).abs() < 1e-15);
        assert!(bulk_modulus(&stage(&["lx"], vec![vec![1.0]])).is_err());
    }

    #[test]
    fn poisson_ratio_is_the_reference_fits_formula_bit_for_bit() {
        for a_b in [-0.8, -0.5, 0.0, 0.5, 1.0, 3.0] {
            let (k, nu) = paper::elastic_constants(a_b);
            let g = paper::shear_to_bulk(a_b) * k;
            assert_eq!(poisson_ratio(k, g).to_bits(), nu.to_bits(), "a_B = {a_b}");
        }
    }
}
