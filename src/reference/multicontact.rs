//! The multi-contact study's published numbers the DEM studies compare
//! against (its Appendix B and Tables D.1 and D.2), and the jamming points
//! its shear fits assume: the one place they are written.

use serde::{Deserialize, Serialize};

/// Prefactor `gamma` of the standard closure, calibrated on the study's
/// single-particle tests (Appendix B).
pub const STANDARD_GAMMA: f64 = 0.82;

/// Prefactor `gamma` of the advanced closure (Appendix B).
pub const ADVANCED_GAMMA: f64 = 0.81;

/// Maximum penetration ratio of the advanced closure (Appendix B).
pub const ADVANCED_MPR: f64 = 0.11;

/// The tables' law at one friction and Poisson's ratio.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct PaperLaw {
    /// Table D.1.
    pub alpha: f64,
    /// Table D.2.
    pub beta: f64,
}

/// Tables D.1 and D.2 of the multi-contact study.
#[derive(Clone, Debug, Deserialize)]
pub struct PaperTables {
    /// Column heads.
    pub poisson_ratio: Vec<f64>,
    /// Row heads.
    pub friction: Vec<f64>,
    /// Table D.1, rows by friction.
    pub alpha_qs: Vec<Vec<f64>>,
    /// Table D.2, rows by friction.
    pub beta: Vec<Vec<f64>>,
}

const PAPER_TABLES_JSON: &str = include_str!("../../reference_data/multicontact_shear_tables.json");

impl PaperTables {
    /// The stored tables.
    pub fn stored() -> Self {
        serde_json::from_str(PAPER_TABLES_JSON)
            .expect("reference_data/multicontact_shear_tables.json is valid (a unit test reads it)")
    }

    /// The law at `friction` and `poisson_ratio`, if both are a row and
    /// a column of the tables.
    pub fn law(&self, friction: f64, poisson_ratio: f64) -> Option<PaperLaw> {
        let find = |heads: &[f64], x: f64| heads.iter().position(|h| (h - x).abs() < 1e-9);
        let (row, col) = (
            find(&self.friction, friction)?,
            find(&self.poisson_ratio, poisson_ratio)?,
        );
        Some(PaperLaw {
            alpha: self.alpha_qs[row][col],
            beta: self.beta[row][col],
        })
    }
}

/// The jamming point of sheared frictional spheres against the friction
/// coefficient, from the simple-shear simulations whose contact parameters
/// the multi-contact study adopted (Chialvo, Sun and Sundaresan, Phys.
/// Rev. E 85, 021305, 2012); the study's fit of eq. 8 needs it and does
/// not print it. Friction coefficients between the listed ones are
/// interpolated linearly, beyond them the last value holds.
pub const ASSUMED_JAMMING_POINTS: [(f64, f64); 5] = [
    (0.0, 0.636),
    (0.1, 0.61),
    (0.3, 0.596),
    (0.5, 0.59),
    (1.0, 0.587),
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stored_tables_read_and_look_up_by_row_and_column() {
        let t = PaperTables::stored();
        assert_eq!(t.alpha_qs.len(), t.friction.len());
        assert!(t.alpha_qs.iter().all(|r| r.len() == t.poisson_ratio.len()));
        let law = t.law(0.0, 0.5).unwrap();
        assert_eq!((law.alpha, law.beta), (0.916128, 0.916196));
        let law = t.law(0.5, 0.25).unwrap();
        assert_eq!((law.alpha, law.beta), (0.145432, 0.702005));
        assert!(t.law(0.2, 0.25).is_none());
        assert!(t.law(0.5, 0.33).is_none());
    }
}
