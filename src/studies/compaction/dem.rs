//! The DEM side of the compaction comparison (docs/protocols.md, "DEM
//! comparison"): one Hertz-Mindlin sphere per grain, of the grains'
//! material and the friction coefficients `{mu_s, mu_r, mu_t}`.
//!
//! The sphere material follows from the bonded solid's calibration: the
//! solid's bulk modulus `K` and Poisson ratio `nu` at `a_B` give Young's
//! modulus `E = 3 K (1 - 2 nu)`, so both models share `E_eff`, the scale
//! every pressure is divided by.
//!
//! The source study gives the three friction coefficients but not the
//! stiffness or damping of the rolling and twisting springs, and its
//! twisting coefficient `mu_t` differs from `mu_s`, which Marshall's model
//! (twisting friction `2/3 a mu_s`) cannot express. Both springs are
//! therefore the contact's own tangential spring frozen at a reference
//! overlap `delta_ref = reference_overlap R_eff`, contact radius `a_ref =
//! sqrt(R_eff delta_ref)`:
//!
//! - rolling: stiffness `k_t a_ref`, damping `eta_t(a_ref)`, friction
//!   `mu_r` (a force coefficient, as the sliding one);
//! - twisting: Marshall's form at `a_ref` with `mu_t` in place of `mu_s`:
//!   stiffness `k_t a_ref^3 / 2`, damping `eta_t(a_ref) a_ref^2 / 2`,
//!   friction `2/3 a_ref mu_t` (a length: the cap is on a torque).
//!
//! Here `k_t a = 8 G_eff a` is the Mindlin stiffness and `eta_t(a) = x_gt
//! c_e sqrt(m_eff k_n a)` the tangential damping of two equal spheres.

use crate::engine::dem::MultiContact;
use crate::kernels::{
    GranularCoeffs, GranularMaterial, NormalDamping, SpringDashpotSlider, Twisting,
};
use crate::options::InvalidOption;
use crate::scene::ForceField;
use crate::studies::hertz::Moduli;
use serde::{Deserialize, Serialize};

/// The DEM contact of `bpm compact --model dem`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DemContact {
    /// `{mu_s, mu_r, mu_t}`: sliding, rolling and twisting friction.
    pub friction: [f64; 3],
    /// Normal restitution coefficient `e` (Tsuji's damping).
    pub restitution: f64,
    /// Tangential over normal damping, `x_gt`.
    pub tangential_damping: f64,
    /// `delta_ref / R_eff` of the rolling and twisting springs.
    pub reference_overlap: f64,
    /// The multi-contact closure, if any (docs/model.md, "Multi-contact
    /// closures"); plain Hertz without.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub multicontact: Option<MultiContact>,
}

impl Default for DemContact {
    /// Sliding friction 0.3 alone (the source study's first rough-grain
    /// match), `e = 0.5`, `x_gt = 1`, `delta_ref = 0.01 R_eff`.
    fn default() -> Self {
        Self {
            friction: [0.3, 0.0, 0.0],
            restitution: 0.5,
            tangential_damping: 1.0,
            reference_overlap: 0.01,
            multicontact: None,
        }
    }
}

impl DemContact {
    /// Checks the values; the error names the option at fault.
    pub fn validate(&self) -> Result<(), InvalidOption> {
        if !self.friction.iter().all(|m| m.is_finite() && *m >= 0.0) {
            return Err(InvalidOption::new(
                "--friction",
                format!(
                    "mu_s, mu_r and mu_t must be finite and >= 0, got {:?}",
                    self.friction
                ),
            ));
        }
        let e = self.restitution;
        if !(e > 0.0 && e <= 1.0) {
            return Err(InvalidOption::new(
                "--restitution",
                format!("must be in (0, 1], got {e}"),
            ));
        }
        let x = self.tangential_damping;
        if !(x.is_finite() && x >= 0.0) {
            return Err(InvalidOption::new(
                "--tangential-damping",
                format!("must be finite and >= 0, got {x}"),
            ));
        }
        let r = self.reference_overlap;
        if !(r > 0.0 && r <= 1.0) {
            return Err(InvalidOption::new(
                "--reference-overlap",
                format!("must be in (0, 1], got {r}"),
            ));
        }
        if let Some(m) = &self.multicontact {
            if !(m.prefactor.is_finite() && m.prefactor >= 0.0) {
                return Err(InvalidOption::new(
                    "--gamma",
                    format!("must be finite and >= 0, got {}", m.prefactor),
                ));
            }
            if let Some(mpr) = m.max_penetration_ratio {
                if !(mpr.is_finite() && mpr >= 0.0) {
                    return Err(InvalidOption::new(
                        "--mpr",
                        format!("must be finite and >= 0, got {mpr}"),
                    ));
                }
            }
            if !(m.reach.is_finite() && m.reach > 0.0) {
                return Err(InvalidOption::new(
                    "--reach",
                    format!("must be finite and > 0, got {}", m.reach),
                ));
            }
        }
        Ok(())
    }

    /// The DEM force field of spheres of `material`, with the closure.
    pub fn force_field(&self, material: GranularMaterial) -> ForceField {
        ForceField {
            multicontact: self.multicontact,
            ..ForceField::dem(material)
        }
    }

    /// The material of equal spheres of `radius` and `mass` made of the
    /// bonded solid whose calibration is `moduli` (`E = 3 K (1 - 2 nu)`).
    pub fn material_of(&self, moduli: &Moduli, radius: f64, mass: f64) -> GranularMaterial {
        self.material(youngs_modulus(moduli.k, moduli.nu), moduli.nu, radius, mass)
    }

    /// The material of equal spheres of `radius` and `mass` made of a solid
    /// with Young's modulus `youngs_modulus` and Poisson ratio
    /// `poisson_ratio`; rolling and twisting only where their friction is
    /// non-zero.
    pub fn material(
        &self,
        youngs_modulus: f64,
        poisson_ratio: f64,
        radius: f64,
        mass: f64,
    ) -> GranularMaterial {
        let [mu_s, mu_r, mu_t] = self.friction;
        let mut m = GranularMaterial {
            youngs_modulus,
            poisson_ratio,
            restitution: self.restitution,
            damping: NormalDamping::Tsuji,
            tangential_damping: self.tangential_damping,
            sliding_friction: mu_s,
            rolling: None,
            twisting: Twisting::None,
        };
        let c = GranularCoeffs::of(&m);
        let r_eff = 0.5 * radius;
        let m_eff = 0.5 * mass;
        let a = r_eff * self.reference_overlap.sqrt();
        let k_t = c.tangential_stiffness * a;
        let eta_t =
            c.tangential_damping * c.normal_damping * (m_eff * c.normal_stiffness * a).sqrt();
        if mu_r > 0.0 {
            m.rolling = Some(SpringDashpotSlider {
                stiffness: k_t,
                damping: eta_t,
                friction: mu_r,
            });
        }
        if mu_t > 0.0 {
            m.twisting = Twisting::Sds(SpringDashpotSlider {
                stiffness: 0.5 * k_t * a * a,
                damping: 0.5 * eta_t * a * a,
                friction: 2.0 / 3.0 * a * mu_t,
            });
        }
        m
    }
}

/// Young's modulus of a solid of bulk modulus `k` and Poisson ratio `nu`.
pub fn youngs_modulus(k: f64, nu: f64) -> f64 {
    3.0 * k * (1.0 - 2.0 * nu)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::hertz::effective_modulus;

    /// The spheres' Hertz modulus is the bonded solid's `E_eff`, which
    /// normalises both models' pressures.
    #[test]
    fn spheres_share_the_solids_effective_modulus() {
        let (k, nu) = (0.8, 0.25);
        let m = DemContact::default().material(youngs_modulus(k, nu), nu, 3.0, 100.0);
        let c = GranularCoeffs::of(&m);
        let e_eff = effective_modulus(k, nu);
        assert!((c.normal_stiffness - 4.0 / 3.0 * e_eff).abs() < 1e-14 * e_eff);
    }

    /// Rolling and twisting appear only with their friction, and the
    /// twisting spring is Marshall's at the reference contact radius.
    #[test]
    fn rolling_and_twisting_follow_their_friction() {
        let plain = DemContact::default().material(1.0, 0.25, 3.0, 100.0);
        assert!(plain.rolling.is_none());
        assert_eq!(plain.twisting, Twisting::None);
        let dem = DemContact {
            friction: [0.15, 0.1, 0.05],
            ..DemContact::default()
        };
        let m = dem.material(1.0, 0.25, 3.0, 100.0);
        let c = GranularCoeffs::of(&m);
        let a = 1.5 * 0.1;
        let rolling = m.rolling.unwrap();
        assert!((rolling.stiffness - c.tangential_stiffness * a).abs() < 1e-15);
        // eta_t = x_gt c_e sqrt(m_eff k_n a), m_eff = m / 2 (Tsuji, e = 1/2).
        let eta_t = crate::kernels::tsuji_prefactor(0.5) * (50.0 * c.normal_stiffness * a).sqrt();
        assert!((rolling.damping - eta_t).abs() < 1e-14 * eta_t);
        assert_eq!(rolling.friction, 0.1);
        let Twisting::Sds(t) = m.twisting else {
            panic!("expected sds twisting, got {:?}", m.twisting)
        };
        assert!((t.stiffness - 0.5 * rolling.stiffness * a * a).abs() < 1e-15);
        assert!((t.damping - 0.5 * rolling.damping * a * a).abs() < 1e-15);
        assert!((t.friction - 2.0 / 3.0 * a * 0.05).abs() < 1e-15);
    }

    #[test]
    fn bad_values_name_their_option() {
        let bad = |c: DemContact| c.validate().unwrap_err().to_string();
        let d = DemContact::default();
        assert!(bad(DemContact {
            friction: [0.1, -0.1, 0.0],
            ..d
        })
        .contains("--friction"));
        assert!(bad(DemContact {
            restitution: 0.0,
            ..d
        })
        .contains("--restitution"));
        assert!(bad(DemContact {
            tangential_damping: f64::NAN,
            ..d
        })
        .contains("--tangential-damping"));
        assert!(bad(DemContact {
            reference_overlap: 2.0,
            ..d
        })
        .contains("--reference-overlap"));
    }
}
