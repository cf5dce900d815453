//! Twisting resistance about the contact normal: Marshall's model
//! (LAMMPS 2021's `twisting marshall`) or explicit coefficients (`twisting
//! sds`), and its moment on the accumulated twist angle.

use serde::{Deserialize, Serialize};

use super::rolling::SpringDashpotSlider;
use super::tangential::Mindlin;

/// Twisting resistance about the contact normal.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Twisting {
    /// None.
    #[default]
    None,
    /// Marshall's model: stiffness `k_t a^2 / 2` with the contact's
    /// tangential stiffness `k_t = 8 G_eff a` (so it grows as `a^3`),
    /// damping `eta_t a^2 / 2` and friction `2/3 a mu_s` (LAMMPS 2021
    /// `twisting marshall`).
    Marshall,
    /// Explicit coefficients (LAMMPS `twisting sds`).
    Sds(SpringDashpotSlider),
}

impl Twisting {
    /// The twisting spring-dashpot-slider at a contact of radius `a` with
    /// `mindlin`'s tangential spring and dashpot and sliding friction
    /// `mu_s`; None without twisting.
    #[inline(always)]
    pub(super) fn at(&self, mindlin: &Mindlin, a: f64, mu_s: f64) -> Option<SpringDashpotSlider> {
        // Marshall's twisting stiffness is k_t a^2 / 2 with the contact's
        // tangential stiffness k_t = 8 G_eff a, so it grows as a^3 (the
        // torsional stiffness of a circular contact), as LAMMPS 2021 has it.
        match *self {
            Twisting::None => None,
            Twisting::Marshall => Some(SpringDashpotSlider {
                stiffness: 0.5 * mindlin.stiffness * a * a,
                damping: 0.5 * mindlin.damping * a * a,
                friction: 2.0 / 3.0 * a * mu_s,
            }),
            Twisting::Sds(t) => Some(t),
        }
    }
}

impl SpringDashpotSlider {
    /// The twisting moment about `n` on the twist angle `twist` of spheres
    /// turning at `relrot` against each other, capped at `friction` times
    /// the total normal force `fncrit`.
    #[inline(always)]
    pub(super) fn twisting_moment(
        &self,
        twist: &mut f64,
        n: &[f64; 3],
        relrot: &[f64; 3],
        fncrit: f64,
        (dt, update): (f64, bool),
    ) -> f64 {
        let (k_twist, damp_twist, mu_twist) = (self.stiffness, self.damping, self.friction);
        let magtwist = relrot[0] * n[0] + relrot[1] * n[1] + relrot[2] * n[2];
        if update {
            *twist += magtwist * dt;
        }
        let mut moment = -k_twist * *twist - damp_twist * magtwist;
        let mtcrit = mu_twist * fncrit;
        if moment.abs() > mtcrit {
            let sign = f64::from(i8::from(magtwist > 0.0) - i8::from(magtwist < 0.0));
            *twist = 1.0 / k_twist * (mtcrit * sign - damp_twist * magtwist);
            moment = -mtcrit * sign;
        }
        moment
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::{at_rest, material};
    use super::super::{
        granular_contact, ContactHistory, GranularCoeffs, GranularMaterial, Sphere,
    };
    use super::*;

    /// A twist over its cap turns against the twisting velocity, whatever
    /// the sign of the spring's stretch.
    #[test]
    fn a_slipping_twist_resists_the_twisting_velocity() {
        let c = GranularCoeffs::of(&GranularMaterial {
            twisting: Twisting::Sds(SpringDashpotSlider {
                stiffness: 10.0,
                damping: 0.0,
                friction: 1e-4,
            }),
            ..material()
        });
        let del = [1.99, 0.0, 0.0];
        for (spin, stretch) in [(-0.1, 5.0), (0.1, -5.0), (0.1, 5.0)] {
            let si = Sphere {
                omega: [spin, 0.0, 0.0],
                ..at_rest(1.0, 1.0)
            };
            let mut h = ContactHistory {
                twist: stretch,
                ..Default::default()
            };
            let out = granular_contact(&c, &del, &si, &at_rest(1.0, 1.0), &mut h, 0.01, false);
            let (delta, a) = (0.01f64, (0.5f64 * 0.01).sqrt());
            let cap = 1e-4 * c.normal_stiffness * delta * a;
            // The torque on i about n is -cap sign(spin).
            assert!(
                (out.torque_i[0] + cap * spin.signum()).abs() < 1e-15,
                "{spin} {stretch}: {:?}",
                out.torque_i
            );
        }
    }
}
