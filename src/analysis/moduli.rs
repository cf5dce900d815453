//! Bulk and shear moduli from recorded compression and shear series
//! (docs/protocols.md, "Calibration"): least-squares slopes of stress against strain.

use super::fit::least_squares_line;
use crate::scene::run::StageOutput;

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

fn column(stage: &StageOutput, name: &'static str) -> Result<Vec<f64>, ModulusError> {
    stage.column(name).ok_or(ModulusError::MissingColumn {
        stage: stage.name.clone(),
        column: name,
    })
}

fn slope(stage: &StageOutput, x: &[f64], y: &[f64]) -> Result<f64, ModulusError> {
    least_squares_line(x, y)
        .map(|l| l.slope)
        .filter(|s| s.is_finite())
        .ok_or(ModulusError::NoSlope {
            stage: stage.name.clone(),
            rows: x.len(),
        })
}

/// Bulk modulus `K`: slope of the pressure against the volumetric strain
/// `(V0 - V) / V0` of an isotropic compression stage.
pub fn bulk_modulus(stage: &StageOutput) -> Result<f64, ModulusError> {
    let (lx, ly, lz) = (
        column(stage, "lx")?,
        column(stage, "ly")?,
        column(stage, "lz")?,
    );
    let p = column(stage, "pressure")?;
    let volume: Vec<f64> = (0..lx.len()).map(|k| lx[k] * ly[k] * lz[k]).collect();
    let v0 = *volume.first().ok_or(ModulusError::NoSlope {
        stage: stage.name.clone(),
        rows: 0,
    })?;
    let strain: Vec<f64> = volume.iter().map(|v| (v0 - v) / v0).collect();
    slope(stage, &strain, &p)
}

/// Shear modulus `G`: slope of `-P_xy` against the shear strain `xy / ly`
/// of a simple-shear stage (LAMMPS's pressure tensor is minus the stress).
pub fn shear_modulus(stage: &StageOutput) -> Result<f64, ModulusError> {
    let (xy, ly, pxy) = (
        column(stage, "xy")?,
        column(stage, "ly")?,
        column(stage, "pxy")?,
    );
    let strain: Vec<f64> = xy.iter().zip(&ly).map(|(t, l)| t / l).collect();
    let stress: Vec<f64> = pxy.iter().map(|p| -p).collect();
    slope(stage, &strain, &stress)
}

/// Poisson's ratio of an isotropic solid with moduli `k` and `g`.
pub fn poisson_ratio(k: f64, g: f64) -> f64 {
    (3.0 * k - 2.0 * g) / (2.0 * (3.0 * k + g))
}

/// The paper's fits (reference_data/paper_fits.json): `K(a_B)`.
pub fn paper_bulk_modulus(a_b: f64) -> f64 {
    1.365 - 0.14 / (a_b + 1.168)
}

/// The paper's fits (reference_data/paper_fits.json): `G/K(a_B)`.
pub fn paper_shear_to_bulk(a_b: f64) -> f64 {
    0.6 + 0.475 * a_b
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stage(columns: &[&str], rows: Vec<Vec<f64>>) -> StageOutput {
        StageOutput {
            name: "t".into(),
            steps: 0,
            columns: columns
                .iter()
                .map(|c| crate::scene::observables::standard_column(c).expect("a standard column"))
                .collect(),
            rows,
            rows_file: None,
            checkpoints: vec![],
            wall_seconds: 0.0,
            timers: Default::default(),
            neighbour_builds: 0,
        }
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
    fn paper_fits_at_a_b_zero() {
        assert!((paper_bulk_modulus(0.0) - 1.2451).abs() < 1e-4);
        assert!((paper_shear_to_bulk(0.0) - 0.6).abs() < 1e-15);
    }
}
