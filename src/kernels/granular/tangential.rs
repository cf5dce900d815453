//! The tangential force: Mindlin's spring on the accumulated tangential
//! displacement (LAMMPS's `tangential mindlin NULL x_gt mu_s`), capped by
//! sliding friction. The spring-dashpot-slider on a history vector and the
//! history's turn into the tangent plane serve rolling too; the contact law
//! (`contact_law` in mod.rs) calls [`Mindlin`].

// Vector components are written `for d in 0..3` over several arrays at
// once, as the equations read.
#![allow(clippy::needless_range_loop)]

/// Below this, a history component out of the tangent plane is left as is
/// (LAMMPS's `EPSILON` in the frame update test).
pub(crate) const FRAME_EPSILON: f64 = 1e-10;

/// One body's share `(2 - nu) / G = 2 (2 - nu) (1 + nu) / E` of Mindlin's
/// tangential compliance (formed as LAMMPS forms it): `G_eff = 1 / (sum of
/// both shares)`.
pub(super) fn shear_compliance(e: f64, nu: f64) -> f64 {
    2.0 * (2.0 - nu) * (1.0 + nu) / e
}

#[inline(always)]
pub(super) fn norm(a: &[f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

/// Turns a history vector into the tangent plane of `n`, keeping its
/// length, when its normal part is not negligible (`|h . n| scale >
/// FRAME_EPSILON limit`).
#[inline(always)]
pub(super) fn rotate_into_plane(h: &mut [f64; 3], n: &[f64; 3], scale: f64, limit: f64) {
    let along = h[0] * n[0] + h[1] * n[1] + h[2] * n[2];
    if along.abs() * scale > FRAME_EPSILON * limit {
        let before = norm(h);
        for d in 0..3 {
            h[d] -= along * n[d];
        }
        let after = norm(h);
        let s = if after > 0.0 { before / after } else { 0.0 };
        for c in h.iter_mut() {
            *c *= s;
        }
    }
}

/// A spring-dashpot-slider on a history vector `h` moving at velocity `w`
/// with stiffness `k`, dashpot `eta` and cap `limit`: returns the force
/// and, when the cap is reached, resets `h` to the spring stretch that
/// gives the capped force (sliding).
#[inline(always)]
pub(super) fn slider(h: &mut [f64; 3], w: &[f64; 3], k: f64, eta: f64, limit: f64) -> [f64; 3] {
    let mut f = [
        -k * h[0] - eta * w[0],
        -k * h[1] - eta * w[1],
        -k * h[2] - eta * w[2],
    ];
    let magnitude = norm(&f);
    if magnitude > limit {
        if norm(h) != 0.0 {
            for d in 0..3 {
                h[d] = -1.0 / k * (limit * f[d] / magnitude + eta * w[d]);
                f[d] *= limit / magnitude;
            }
        } else {
            f = [0.0; 3];
        }
    }
    f
}

/// [`slider`] on a history vector `h` that turns with the contact normal
/// `n`: in a step (`update`), `h` is first turned into the tangent plane
/// and advanced by `w dt`.
#[inline(always)]
pub(super) fn history_slider(
    h: &mut [f64; 3],
    n: &[f64; 3],
    w: &[f64; 3],
    k: f64,
    eta: f64,
    limit: f64,
    (dt, update): (f64, bool),
) -> [f64; 3] {
    if update {
        rotate_into_plane(h, n, k, limit);
        for d in 0..3 {
            h[d] += w[d] * dt;
        }
    }
    slider(h, w, k, eta, limit)
}

/// Mindlin's tangential spring and dashpot at one contact, and the
/// sliding cap.
pub(super) struct Mindlin {
    /// Spring `k_t a`.
    pub(super) stiffness: f64,
    /// Dashpot `eta_t = x_gt eta_n`.
    pub(super) damping: f64,
    /// Cap `mu_s |F_n|`.
    pub(super) limit: f64,
}

impl Mindlin {
    /// With coefficients `k_t = 8 G_eff`, `x_gt` and `mu_s`, at a contact
    /// of radius `a`, normal dashpot `eta_n` and total normal force
    /// `fncrit` in magnitude.
    #[inline(always)]
    pub(super) fn at(k_t: f64, x_gt: f64, mu_s: f64, a: f64, eta_n: f64, fncrit: f64) -> Self {
        Self {
            damping: x_gt * eta_n,
            stiffness: k_t * a,
            limit: mu_s * fncrit,
        }
    }

    /// The tangential force on the tangential displacement `xi`, the
    /// surfaces moving at `vtr` against each other at the contact.
    #[inline(always)]
    pub(super) fn force(
        &self,
        xi: &mut [f64; 3],
        n: &[f64; 3],
        vtr: &[f64; 3],
        step: (f64, bool),
    ) -> [f64; 3] {
        history_slider(xi, n, vtr, self.stiffness, self.damping, self.limit, step)
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::{at_rest, dot3, effective, material};
    use super::super::{
        granular_contact, tsuji_prefactor, ContactForce, ContactHistory, GranularCoeffs,
        GranularMaterial, Sphere,
    };
    use super::*;

    #[test]
    fn stuck_contact_pulls_back_with_mindlin_stiffness_until_coulomb() {
        let m = material();
        let c = GranularCoeffs::of(&m);
        let (_, g_eff) = effective(&m);
        let (radius, delta): (f64, f64) = (1.0, 0.01);
        let reff = 0.5 * radius;
        let a = (reff * delta).sqrt();
        let del = [2.0 * radius - delta, 0.0, 0.0];
        let fne = 4.0 / 3.0 * effective(&m).0 * a * delta;
        // Sphere i slides along y at speed u for n steps: xi = u n dt.
        let (u, dt) = (1e-3, 0.01);
        let si = Sphere {
            v: [0.0, u, 0.0],
            ..at_rest(radius, 1.0)
        };
        let mut h = ContactHistory::default();
        let mut steps = 0;
        let mut last = ContactForce::default();
        let mut stuck_checked = false;
        while steps < 100_000 {
            last = granular_contact(&c, &del, &si, &at_rest(radius, 1.0), &mut h, dt, true);
            steps += 1;
            let ft = last.force[1];
            let expect_damped = -8.0 * g_eff * a * (u * steps as f64 * dt)
                - m.tangential_damping
                    * tsuji_prefactor(m.restitution)
                    * (0.5 * 4.0 / 3.0 * effective(&m).0 * a).sqrt()
                    * u;
            if ft.abs() < 0.5 * m.sliding_friction * fne {
                assert!(
                    (ft - expect_damped).abs() < 1e-12 * fne,
                    "{ft} vs {expect_damped}"
                );
                stuck_checked = true;
            } else if ft.abs() >= m.sliding_friction * fne * (1.0 - 1e-12) {
                break;
            }
        }
        assert!(stuck_checked);
        // Sliding: the force stays at the Coulomb limit and the spring
        // holds only what the limit allows.
        for _ in 0..100 {
            last = granular_contact(&c, &del, &si, &at_rest(radius, 1.0), &mut h, dt, true);
        }
        let limit = m.sliding_friction * fne;
        assert!((last.force[1].abs() - limit).abs() < 1e-12 * limit);
        assert!(last.force[1] < 0.0, "friction opposes the sliding");
        // Torques: the tangential force at the contact point, arm R - delta/2.
        let arm = radius - 0.5 * delta;
        assert!((last.torque_i[2] + arm * last.force[1]).abs() < 1e-14 * limit);
        assert_eq!(last.torque_i, last.torque_j);
    }

    #[test]
    fn history_turns_with_a_rotating_contact_and_keeps_its_length() {
        let c = GranularCoeffs::of(&GranularMaterial {
            sliding_friction: 1e3, // never slides
            ..material()
        });
        let radius = 1.0;
        let r = 2.0 * radius - 0.01;
        let mut h = ContactHistory {
            tangential: [0.0, 1e-3, 0.0],
            ..Default::default()
        };
        // The contact normal turns by 0.1 rad about z; the history, which
        // was tangent to the old normal, is turned into the new tangent
        // plane with its length kept.
        let angle: f64 = 0.1;
        let n = [angle.cos(), angle.sin(), 0.0];
        let del = n.map(|c| c * r);
        granular_contact(
            &c,
            &del,
            &at_rest(radius, 1.0),
            &at_rest(radius, 1.0),
            &mut h,
            0.01,
            true,
        );
        assert!((norm(&h.tangential) - 1e-3).abs() < 1e-18);
        assert!(dot3(&h.tangential, &n).abs() < 1e-18);
    }

    /// A sliding contact that is also closing: the Coulomb limit follows
    /// the total normal force, damping included (LAMMPS's `|F_ntot|`).
    #[test]
    fn coulomb_limit_includes_the_normal_damping() {
        let c = GranularCoeffs::of(&material());
        let del = [1.99, 0.0, 0.0];
        // Closing at 0.05 along n, sliding fast along y.
        let si = Sphere {
            v: [-0.05, 1.0, 0.0],
            ..at_rest(1.0, 1.0)
        };
        let mut h = ContactHistory {
            tangential: [0.0, 1.0, 0.0],
            ..Default::default()
        };
        let out = granular_contact(&c, &del, &si, &at_rest(1.0, 1.0), &mut h, 0.01, true);
        let delta: f64 = 0.01;
        let a = (0.5 * delta).sqrt();
        let fne = c.normal_stiffness * delta * a;
        let fntot = fne + c.normal_damping * (0.5 * c.normal_stiffness * a).sqrt() * 0.05;
        assert!((out.force[0] - fntot).abs() < 1e-14 * fntot);
        let ft = (out.force[1].powi(2) + out.force[2].powi(2)).sqrt();
        assert!(
            (ft - 0.3 * fntot).abs() < 1e-13 * fntot,
            "{ft} vs {}",
            0.3 * fntot
        );
        assert!(
            (ft - 0.3 * fne).abs() > 1e-3 * fne,
            "the elastic force alone would differ"
        );
    }

    /// Outside a step (a stage's set-up) the history does not advance, but
    /// a slider over its cap still rewrites it; one with no history whose
    /// dashpot alone exceeds the cap gives no force at all (LAMMPS 2021).
    #[test]
    fn set_up_evaluations_clip_but_do_not_advance_the_history() {
        let c = GranularCoeffs::of(&GranularMaterial {
            sliding_friction: 1e-3,
            ..material()
        });
        let del = [1.99, 0.0, 0.0];
        let si = Sphere {
            v: [0.0, 0.5, 0.0],
            ..at_rest(1.0, 1.0)
        };
        let sj = at_rest(1.0, 1.0);
        let mut fresh = ContactHistory::default();
        let out = granular_contact(&c, &del, &si, &sj, &mut fresh, 0.01, false);
        assert_eq!((out.force[1], out.force[2]), (0.0, 0.0));
        assert_eq!(fresh.tangential, [0.0; 3]);
        assert!(
            (fresh.normal_force - out.force[0]).abs() < 1e-15,
            "the load is recorded"
        );
        let mut loaded = ContactHistory {
            tangential: [0.0, 0.2, 0.0],
            ..Default::default()
        };
        let out = granular_contact(&c, &del, &si, &sj, &mut loaded, 0.01, false);
        let (delta, a) = (0.01f64, (0.5f64 * 0.01).sqrt());
        let fne = c.normal_stiffness * delta * a;
        assert!((out.force[1].abs() - 1e-3 * fne).abs() < 1e-12 * fne);
        // The stored stretch now gives exactly the capped force.
        let k = c.tangential_stiffness * a;
        let eta = c.tangential_damping * c.normal_damping * (0.5 * c.normal_stiffness * a).sqrt();
        let again = -k * loaded.tangential[1] - eta * 0.5;
        assert!(
            (again - out.force[1]).abs() < 1e-12 * fne,
            "{again} vs {}",
            out.force[1]
        );
    }
}
