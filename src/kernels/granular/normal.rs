//! The normal force: Hertz (LAMMPS's `hertz/material`), `F_ne = k_n a
//! delta` with `k_n = 4/3 E_eff`, on the overlap the sphere-sphere or wall
//! contact hands it (the multi-contact closure's corrected one included),
//! with the normal damping; and how two materials' moduli mix into
//! `E_eff`.

/// One body's share `(1 - nu^2) / E` of the Hertz contact compliance:
/// `E_eff = 1 / (sum of both shares)`.
pub(super) fn youngs_compliance(e: f64, nu: f64) -> f64 {
    (1.0 - nu * nu) / e
}

/// Hertz's normal force at one contact, and what the other sub-models
/// derive from it.
pub(super) struct Hertz {
    /// Contact radius `a = sqrt(R delta)`.
    pub(super) a: f64,
    /// Normal dashpot `eta_n = c_e sqrt(m_eff k_n a)`.
    pub(super) damping: f64,
    /// Total normal force along `n`, `F_ne - eta_n (n . dv)`.
    pub(super) force: f64,
}

/// The normal force of a contact with stiffness `k_n` and damping
/// prefactor `c_e` at overlap `delta`, effective radius `reff` and mass
/// `meff`, its centres moving apart at `vnnr = n . dv`.
#[inline(always)]
pub(super) fn hertz(k_n: f64, c_e: f64, delta: f64, reff: f64, meff: f64, vnnr: f64) -> Hertz {
    // Damping that scales as sqrt(k_n a).
    let a = (delta * reff).sqrt();
    let fne = k_n * delta * a;
    let knfac = k_n * a;
    let damp_normal = c_e * (meff * knfac).sqrt();
    let fntot = fne - damp_normal * vnnr;
    Hertz {
        a,
        damping: damp_normal,
        force: fntot,
    }
}

#[cfg(test)]
mod tests {
    use super::super::tangential::norm;
    use super::super::tests::{at_rest, dot3, effective, material};
    use super::super::{
        corrected_granular_contact, granular_contact, ContactHistory, GranularCoeffs, Sphere,
    };

    #[test]
    fn static_normal_force_is_hertz_and_derives_from_the_hertz_energy() {
        let m = material();
        let c = GranularCoeffs::of(&m);
        let (ri, rj) = (1.0, 3.0);
        let reff = ri * rj / (ri + rj);
        let (e_eff, _) = effective(&m);
        let energy = |r: f64| {
            let delta = ri + rj - r;
            8.0 / 15.0 * e_eff * reff.sqrt() * delta.powf(2.5)
        };
        for overlap in [1e-4, 1e-2, 0.3] {
            let dir = [0.48, -0.6, 0.64];
            let del = dir.map(|d| d * (ri + rj - overlap));
            // The overlap the kernel sees, without the round-off of
            // forming `del` (which the subtraction would magnify).
            let r = norm(&del);
            let delta = ri + rj - r;
            let mut h = ContactHistory::default();
            let out = granular_contact(
                &c,
                &del,
                &at_rest(ri, 1.0),
                &at_rest(rj, 2.0),
                &mut h,
                0.01,
                true,
            );
            let hertz = 4.0 / 3.0 * e_eff * reff.sqrt() * delta.powf(1.5);
            let along = dot3(&out.force, &dir);
            assert!((along - hertz).abs() < 1e-13 * hertz, "{along} vs {hertz}");
            // F = -dU/dr by central differences.
            let step = 1e-6 * delta;
            let fd = -(energy(r + step) - energy(r - step)) / (2.0 * step);
            assert!((along - fd).abs() < 1e-6 * hertz, "{along} vs {fd}");
            assert_eq!(out.torque_i, [0.0; 3]);
            assert!((h.normal_force - hertz).abs() < 1e-13 * hertz);
            assert_eq!(
                h,
                ContactHistory {
                    normal_force: h.normal_force,
                    ..ContactHistory::default()
                },
                "no tangential motion, no history but the normal force"
            );
        }
    }

    #[test]
    fn moved_surfaces_change_the_overlap_and_arms_but_not_the_effective_radius() {
        let m = material();
        let c = GranularCoeffs::of(&m);
        let (ri, rj) = (0.5, 0.8);
        let reff = ri * rj / (ri + rj);
        let (e_eff, _) = effective(&m);
        let del = [1.27, 0.0, 0.0];
        let (di, dj) = (0.02, -0.01);
        let delta = ri + di + rj + dj - del[0];
        let spin = Sphere {
            omega: [0.0, 0.0, 0.3],
            ..at_rest(ri, 1.0)
        };
        let mut h = ContactHistory::default();
        let out = corrected_granular_contact(
            &c,
            &del,
            &spin,
            &at_rest(rj, 2.0),
            [di, dj],
            &mut h,
            0.01,
            true,
        );
        let hertz = 4.0 / 3.0 * e_eff * (reff * delta).sqrt() * delta;
        assert!((out.force[0] - hertz).abs() < 1e-13 * hertz);
        assert!((h.normal_force - hertz).abs() < 1e-13 * hertz);
        // The spin drags the contact point, (R_i + Delta_i) from the
        // centre; the tangential force's moments balance about the contact
        // point: arm_i + arm_j = |del|.
        let ft = out.force[1];
        assert!(ft != 0.0);
        let arm_i = -out.torque_i[2] / ft;
        let arm_j = -out.torque_j[2] / ft;
        assert!((arm_i - (ri + di - 0.5 * delta)).abs() < 1e-14);
        assert!((arm_i + arm_j - del[0]).abs() < 1e-14);
        // Zero corrections are the plain contact, bit for bit.
        let (mut a, mut b) = (ContactHistory::default(), ContactHistory::default());
        let plain = granular_contact(&c, &del, &spin, &at_rest(rj, 2.0), &mut a, 0.01, true);
        let zero = corrected_granular_contact(
            &c,
            &del,
            &spin,
            &at_rest(rj, 2.0),
            [0.0; 2],
            &mut b,
            0.01,
            true,
        );
        assert_eq!((plain, a), (zero, b));
    }
}
