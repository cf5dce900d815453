//! Rolling resistance (LAMMPS's `rolling sds`): its coefficients, a
//! spring-dashpot-slider, which twisting's `sds` form shares. The contact
//! law (`contact_law` in mod.rs) applies it on the accumulated rolling
//! displacement with the slider in tangential.rs.

use serde::{Deserialize, Serialize};

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
