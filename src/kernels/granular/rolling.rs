//! Rolling resistance (LAMMPS's `rolling sds`): its coefficients, a
//! spring-dashpot-slider, which twisting's `sds` form shares, and its
//! force on the accumulated rolling displacement with the slider in
//! tangential.rs.

use serde::{Deserialize, Serialize};

use super::tangential::history_slider;

/// A spring-dashpot-slider on rolling or twisting motion.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpringDashpotSlider {
    /// Spring stiffness (k units for rolling; k d^2 for twisting).
    pub stiffness: f64,
    /// Dashpot coefficient (sqrt(k m) units for rolling; d^2 sqrt(k m)
    /// for twisting).
    pub damping: f64,
    /// Friction coefficient: the spring force (torque for twisting) is
    /// capped at this times the total normal force `|F_n|`, damping
    /// included (for twisting the coefficient is a length, d).
    pub friction: f64,
}

impl SpringDashpotSlider {
    /// The rolling force `F_r` (the torque is `R n x F_r`) at a contact of
    /// effective radius `reff` whose spheres turn at `relrot` (`omega_i -
    /// omega_j`) against each other, on the rolling displacement
    /// `history`, capped at `friction` times the total normal force
    /// `fncrit`.
    #[inline(always)]
    pub(super) fn rolling_force(
        &self,
        history: &mut [f64; 3],
        n: &[f64; 3],
        relrot: &[f64; 3],
        reff: f64,
        fncrit: f64,
        step: (f64, bool),
    ) -> [f64; 3] {
        // Rolling velocity R (relrot x n) (Wang et al. 2015, eq. 31).
        let vrl = [
            reff * (relrot[1] * n[2] - relrot[2] * n[1]),
            reff * (relrot[2] * n[0] - relrot[0] * n[2]),
            reff * (relrot[0] * n[1] - relrot[1] * n[0]),
        ];
        let frcrit = self.friction * fncrit;
        history_slider(history, n, &vrl, self.stiffness, self.damping, frcrit, step)
    }
}
