//! Contact force and torques between DEM spheres (docs/model.md, "DEM
//! spheres"), term for term as LAMMPS's `pair_style granular` computes
//! `hertz/material E e nu tangential mindlin NULL x_gt mu_s damping tsuji
//! rolling sds k_r g_r mu_r twisting marshall` (or `twisting sds`).
//!
//! For spheres `i`, `j` with radii `R_i`, `R_j`, `r_ij = x_i - x_j`,
//! `n = r_ij / r` and overlap `delta = R_i + R_j - r > 0`:
//!
//! - normal: `F_ne = k_n a delta` with `a = sqrt(R delta)`,
//!   `R = R_i R_j / (R_i + R_j)` and `k_n = 4/3 E_eff`; damping
//!   `-eta_n (n . dv)` with `eta_n = c_e sqrt(m_eff k_n a)`, where `c_e` is
//!   Tsuji's polynomial in the restitution coefficient `e` or, in the
//!   restitution form, `sqrt(5) |ln e| / sqrt(ln^2 e + pi^2)`;
//! - tangential (Mindlin, no slip): a spring on the accumulated tangential
//!   displacement `xi`, `F_t = -k_t a xi - eta_t v_t` with `k_t = 8 G_eff`
//!   and `eta_t = x_gt eta_n`, capped at `mu_s |F_n|` (Coulomb), where
//!   `F_n` is the total normal force, damping included;
//! - rolling: a spring-dashpot-slider on the accumulated rolling
//!   displacement, capped at `mu_r |F_n|`, torque `R n x F_r`;
//! - twisting: a spring-dashpot-slider on the accumulated twist angle,
//!   capped at `mu_t |F_n|` (Marshall: stiffness, damping and friction
//!   derived from the tangential ones and the contact radius `a`).
//!
//! Two details follow LAMMPS 2021 exactly: a force evaluation outside a
//! step does not advance the history but a slider at its cap still
//! rewrites it, and a slider whose history is zero and whose dashpot alone
//! exceeds the cap gives no force at all.
//!
//! The history (`xi`, the rolling displacement, the twist angle) belongs to
//! the contact: it starts at zero when the spheres touch, is rotated into
//! the tangent plane as the contact turns, and is cleared when they part.
//!
//! The sub-models live in their own files, as LAMMPS's GRANULAR package
//! splits them: `normal.rs` (Hertz), `damping.rs` (Tsuji, coefficient of
//! restitution), `tangential.rs` (Mindlin's history spring, sliding
//! friction), `rolling.rs` (SDS) and `twisting.rs` (Marshall, SDS), each
//! with its part of the force. `contact_law` here calls them in one pass,
//! inlined, so a contact's arithmetic is that of one function.

// Vector components are written `for d in 0..3` over several arrays at
// once, as the equations read.
#![allow(clippy::needless_range_loop)]

mod damping;
mod normal;
mod rolling;
mod tangential;
mod twisting;

pub use damping::{restitution_prefactor, tsuji_prefactor, NormalDamping};
pub use rolling::SpringDashpotSlider;
pub use twisting::Twisting;

use normal::{hertz, youngs_compliance};
use serde::{Deserialize, Serialize};
pub(crate) use tangential::FRAME_EPSILON;
use tangential::{shear_compliance, Mindlin};

/// Material and friction of DEM spheres of one material: the scene's
/// `force_field.granular`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GranularMaterial {
    /// Young's modulus `E` of the sphere material (k / d units), > 0.
    pub youngs_modulus: f64,
    /// Poisson's ratio `nu`, in (-1, 1/2].
    pub poisson_ratio: f64,
    /// Normal restitution coefficient `e`, in (0, 1].
    pub restitution: f64,
    /// How the normal damping follows from `e`; default Tsuji.
    #[serde(default)]
    pub damping: NormalDamping,
    /// Tangential damping over normal damping, `x_gt` (LAMMPS's `xgammat`),
    /// >= 0.
    pub tangential_damping: f64,
    /// Sliding friction coefficient `mu_s`, >= 0.
    pub sliding_friction: f64,
    /// Rolling resistance; default none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rolling: Option<SpringDashpotSlider>,
    /// Twisting resistance; default none.
    #[serde(default, skip_serializing_if = "is_no_twisting")]
    pub twisting: Twisting,
}

fn is_no_twisting(t: &Twisting) -> bool {
    *t == Twisting::None
}

/// The coefficients of one kind of contact (two spheres, or a sphere and
/// a wall), derived once.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GranularCoeffs {
    /// `k_n = 4/3 E_eff`, `1 / E_eff = (1 - nu_a^2)/E_a + (1 - nu_b^2)/E_b`
    /// (`E / (2 (1 - nu^2))` for one material).
    pub normal_stiffness: f64,
    /// `c_e`: `eta_n = c_e sqrt(m_eff k_n a)`.
    pub normal_damping: f64,
    /// `k_t = 8 G_eff`, `1 / G_eff = (2 - nu_a)/G_a + (2 - nu_b)/G_b`, `G =
    /// E / (2 (1 + nu))` (`G / (2 (2 - nu))` for one material).
    pub tangential_stiffness: f64,
    /// `x_gt`: `eta_t = x_gt eta_n`.
    pub tangential_damping: f64,
    /// `mu_s`.
    pub sliding_friction: f64,
    /// Rolling spring-dashpot-slider, if any.
    pub rolling: Option<SpringDashpotSlider>,
    /// Twisting model.
    pub twisting: Twisting,
}

impl GranularCoeffs {
    /// The coefficients of `m` against itself.
    pub fn of(m: &GranularMaterial) -> Self {
        Self::between(m, m)
    }

    /// The coefficients of a contact between bodies of materials `a` and
    /// `b`: the elastic moduli mix by Hertz's and Mindlin's rules; damping
    /// and friction are `b`'s (the contact's own, e.g. a wall's against
    /// the spheres).
    pub fn between(a: &GranularMaterial, b: &GranularMaterial) -> Self {
        let e_eff = 1.0
            / (youngs_compliance(a.youngs_modulus, a.poisson_ratio)
                + youngs_compliance(b.youngs_modulus, b.poisson_ratio));
        let g_eff = 1.0
            / (shear_compliance(a.youngs_modulus, a.poisson_ratio)
                + shear_compliance(b.youngs_modulus, b.poisson_ratio));
        Self {
            normal_stiffness: 4.0 / 3.0 * e_eff,
            normal_damping: match b.damping {
                NormalDamping::Tsuji => tsuji_prefactor(b.restitution),
                NormalDamping::CoeffRestitution => restitution_prefactor(b.restitution),
            },
            tangential_stiffness: 8.0 * g_eff,
            tangential_damping: b.tangential_damping,
            sliding_friction: b.sliding_friction,
            rolling: b.rolling,
            twisting: b.twisting,
        }
    }

    /// Whether rolling or twisting resistance is on (else the kernel
    /// skips their terms). Where the lanes may run is
    /// [`GranularCoeffs::lanes_cover`]'s to decide, which names every field.
    pub fn has_rolling_or_twisting(&self) -> bool {
        self.rolling.is_some() || self.twisting != Twisting::None
    }

    /// Whether the four-at-a-time lanes (`granular_lanes`) implement
    /// every sub-model of these coefficients, so the native engine may
    /// take them; otherwise it takes the one-at-a-time law. The
    /// destructuring names every field, so a sub-model added to the
    /// coefficients does not compile until it is decided here: a new
    /// contact law needs its own file and a scene variant, and the lanes
    /// are never silently wrong for it.
    pub fn lanes_cover(&self) -> bool {
        let Self {
            normal_stiffness: _,
            normal_damping: _,
            tangential_stiffness: _,
            tangential_damping: _,
            sliding_friction: _,
            rolling,
            twisting,
        } = self;
        rolling.is_none() && *twisting == Twisting::None
    }
}

/// What a contact remembers between steps.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ContactHistory {
    /// Accumulated tangential displacement `xi` (d).
    pub tangential: [f64; 3],
    /// Accumulated rolling displacement (d).
    pub rolling: [f64; 3],
    /// Accumulated twist angle (rad).
    pub twist: f64,
    /// Magnitude of the total normal force (damping included) at the
    /// contact's last evaluation (k d): what the multi-contact closure
    /// takes as the contact's load on the sphere in the next one.
    pub normal_force: f64,
}

/// One sphere of a contact: what the force reads.
#[derive(Clone, Copy, Debug)]
pub struct Sphere {
    /// Velocity (d / tau).
    pub v: [f64; 3],
    /// Angular velocity (1 / tau).
    pub omega: [f64; 3],
    /// Radius (d).
    pub radius: f64,
    /// Mass (m).
    pub mass: f64,
}

/// Force on `i` (the opposite acts on `j`) and the torques on both.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ContactForce {
    /// Force on `i` (k d).
    pub force: [f64; 3],
    /// Torque on `i` (k d^2).
    pub torque_i: [f64; 3],
    /// Torque on `j` (k d^2).
    pub torque_j: [f64; 3],
}

#[inline(always)]
fn cross(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// What the contact law reads of one contact, whatever its two bodies
/// are: two spheres, or a sphere and a flat wall.
pub(crate) struct Contact {
    /// Unit normal, towards `i`.
    pub(crate) n: [f64; 3],
    /// Overlap (d).
    pub(crate) delta: f64,
    /// Effective radius (d).
    pub(crate) reff: f64,
    /// Effective mass (m).
    pub(crate) meff: f64,
    /// Relative velocity of the centres, `v_i - v_j`.
    pub(crate) vr: [f64; 3],
    /// `R_i omega_i + R_j omega_j` (with each surface's moved radius):
    /// the surfaces' spin at the contact.
    pub(crate) wr: [f64; 3],
    /// Relative angular velocity, `omega_i - omega_j`.
    pub(crate) relrot: [f64; 3],
    /// Lever arms of the tangential force about each centre.
    pub(crate) arm_i: f64,
    pub(crate) arm_j: f64,
}

/// The contact force of touching spheres `i` and `j` at separation
/// `del = x_i - x_j` (`|del| < R_i + R_j`), advancing `history` over the
/// step `dt` when `update` (a force evaluation that is not a step, such as
/// a stage's set-up, does not advance it, though a slider at its cap still
/// rewrites it). Either way the history records the normal force.
#[inline(always)]
pub fn granular_contact(
    c: &GranularCoeffs,
    del: &[f64; 3],
    si: &Sphere,
    sj: &Sphere,
    history: &mut ContactHistory,
    dt: f64,
    update: bool,
) -> ContactForce {
    corrected_granular_contact(c, del, si, sj, [0.0; 2], history, dt, update)
}

/// [`granular_contact`] with each sphere's surface at this contact moved
/// out by `corrections` (the multi-contact closure's `Delta`, negative
/// inwards): the overlap is `R_i + Delta_i + R_j + Delta_j - |del|` (which
/// must be positive) and the contact point and lever arms follow the
/// moved surfaces, while the effective radius of the Hertz and Mindlin
/// stiffnesses stays that of the spheres (the spheres do not change size;
/// only where their surfaces meet does). Zero corrections give
/// [`granular_contact`] exactly.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub fn corrected_granular_contact(
    c: &GranularCoeffs,
    del: &[f64; 3],
    si: &Sphere,
    sj: &Sphere,
    corrections: [f64; 2],
    history: &mut ContactHistory,
    dt: f64,
    update: bool,
) -> ContactForce {
    let contact = pair_contact(del, si, sj, corrections);
    contact_law(c, &contact, history, dt, update)
}

/// The contact of touching spheres `si` and `sj` at separation `del`,
/// their surfaces moved out by `corrections` (see
/// [`corrected_granular_contact`]): what the contact law reads. The
/// one-contact kernel and the four-at-a-time lanes both form it here.
#[inline(always)]
pub(crate) fn pair_contact(
    del: &[f64; 3],
    si: &Sphere,
    sj: &Sphere,
    corrections: [f64; 2],
) -> Contact {
    let rsq = del[0] * del[0] + del[1] * del[1] + del[2] * del[2];
    let r = rsq.sqrt();
    let rinv = 1.0 / r;
    let radsum = si.radius + sj.radius;
    let (surface_i, surface_j) = (si.radius + corrections[0], sj.radius + corrections[1]);
    let delta = (surface_i + surface_j) - r;
    Contact {
        n: [del[0] * rinv, del[1] * rinv, del[2] * rinv],
        delta,
        reff: si.radius * sj.radius / radsum,
        meff: si.mass * sj.mass / (si.mass + sj.mass),
        vr: [si.v[0] - sj.v[0], si.v[1] - sj.v[1], si.v[2] - sj.v[2]],
        wr: [
            surface_i * si.omega[0] + surface_j * sj.omega[0],
            surface_i * si.omega[1] + surface_j * sj.omega[1],
            surface_i * si.omega[2] + surface_j * sj.omega[2],
        ],
        relrot: [
            si.omega[0] - sj.omega[0],
            si.omega[1] - sj.omega[1],
            si.omega[2] - sj.omega[2],
        ],
        // The tangential force acts at the contact point, R + Delta -
        // delta/2 from either centre.
        arm_i: surface_i - 0.5 * delta,
        arm_j: surface_j - 0.5 * delta,
    }
}

/// A flat wall's plane at one evaluation: normal to `axis`, at
/// `position`, moving along its normal at `velocity`, its spheres on the
/// side `sign` points to. Both engines place their walls by it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WallPlane {
    /// Axis normal to the plane: 0, 1 or 2.
    pub axis: usize,
    /// +1 when the spheres are on the +axis side (a `lo` wall), else -1.
    pub sign: f64,
    /// The plane's position along the axis.
    pub position: f64,
    /// Its speed along the axis (d / tau).
    pub velocity: f64,
}

impl WallPlane {
    /// Distance of a centre at `x` from the plane, positive on the
    /// spheres' side.
    #[inline]
    pub fn distance(&self, x: &[f64; 3]) -> f64 {
        self.sign * (x[self.axis] - self.position)
    }

    /// The point of the plane nearest a centre `distance` from it,
    /// relative to that centre (a rigid wall's contact point).
    #[inline]
    pub fn contact_point(&self, distance: f64) -> [f64; 3] {
        let mut point = [0.0; 3];
        point[self.axis] = -self.sign * distance;
        point
    }

    /// The wall's touch on a sphere whose centre is `distance` from it and
    /// whose surface there moved out by `correction`.
    #[inline]
    pub fn touch(&self, distance: f64, correction: f64) -> WallTouch {
        let mut normal = [0.0; 3];
        normal[self.axis] = self.sign;
        let mut velocity = [0.0; 3];
        velocity[self.axis] = self.velocity;
        WallTouch {
            distance,
            normal,
            velocity,
            correction,
        }
    }

    /// The normal component of `force` on a sphere, as the load on the
    /// wall (positive when the sphere pushes it).
    #[inline]
    pub fn load(&self, force: &[f64; 3]) -> f64 {
        self.sign * force[self.axis]
    }
}

/// Where a flat wall touches a sphere.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WallTouch {
    /// Distance of the sphere's centre from the wall's plane, `0 <
    /// distance < R + correction`.
    pub distance: f64,
    /// The wall's unit normal, pointing towards the sphere.
    pub normal: [f64; 3],
    /// The wall's velocity (d / tau).
    pub velocity: [f64; 3],
    /// The sphere's surface at this contact moved out by this much (the
    /// multi-contact closure's `Delta`; 0 for plain Hertz): the overlap is
    /// `R + correction - distance`, and the effective radius stays `R`.
    pub correction: f64,
}

/// The contact force on sphere `s` from a flat wall touching it at
/// `wall`; `torque_j` of the result is 0.
///
/// The wall is a body of infinite radius and mass: `R_eff = R`, `m_eff =
/// m`, and it does not spin. The tangential force acts at the full radius
/// `R + correction` (not at the contact point, `R + correction - delta`
/// from the centre), as the reference LAMMPS implementation has it; the
/// two differ by `delta / R`.
#[inline(always)]
pub fn granular_wall_contact(
    c: &GranularCoeffs,
    wall: &WallTouch,
    s: &Sphere,
    history: &mut ContactHistory,
    dt: f64,
    update: bool,
) -> ContactForce {
    let contact = wall_contact(wall, s);
    let mut out = contact_law(c, &contact, history, dt, update);
    out.torque_j = [0.0; 3];
    out
}

/// The contact of sphere `s` with the flat wall touching it at `wall`
/// (see [`granular_wall_contact`]): what the contact law reads. The
/// one-contact kernel and the four-at-a-time lanes both form it here.
#[inline(always)]
pub(crate) fn wall_contact(wall: &WallTouch, s: &Sphere) -> Contact {
    let WallTouch {
        distance,
        normal,
        velocity: wall_velocity,
        correction,
    } = *wall;
    let surface = s.radius + correction;
    // The normal as the reference forms it from the separation vector
    // `distance * normal`, so both round alike.
    let rinv = 1.0 / distance;
    Contact {
        n: normal.map(|c| distance * c * rinv),
        delta: surface - distance,
        reff: s.radius,
        meff: s.mass,
        vr: [
            s.v[0] - wall_velocity[0],
            s.v[1] - wall_velocity[1],
            s.v[2] - wall_velocity[2],
        ],
        wr: s.omega.map(|w| surface * w),
        relrot: s.omega,
        arm_i: surface,
        arm_j: 0.0,
    }
}

/// Hertz normal force with damping, Mindlin tangential force, rolling and
/// twisting resistance for one contact, each from its sub-model's file.
#[inline(always)]
fn contact_law(
    c: &GranularCoeffs,
    contact: &Contact,
    history: &mut ContactHistory,
    dt: f64,
    update: bool,
) -> ContactForce {
    let Contact {
        n,
        delta,
        reff,
        meff,
        vr,
        wr,
        relrot,
        arm_i,
        arm_j,
    } = *contact;
    let vnnr = vr[0] * n[0] + vr[1] * n[1] + vr[2] * n[2];
    let vn = [n[0] * vnnr, n[1] * vnnr, n[2] * vnnr];
    let step = (dt, update);

    let normal = hertz(
        c.normal_stiffness,
        c.normal_damping,
        delta,
        reff,
        meff,
        vnnr,
    );
    let fntot = normal.force;
    // Friction limits follow the total normal force, damping included.
    let fncrit = fntot.abs();
    history.normal_force = fncrit;

    // Relative velocity of the surfaces at the contact.
    let vt = [vr[0] - vn[0], vr[1] - vn[1], vr[2] - vn[2]];
    let vtr = [
        vt[0] - (n[2] * wr[1] - n[1] * wr[2]),
        vt[1] - (n[0] * wr[2] - n[2] * wr[0]),
        vt[2] - (n[1] * wr[0] - n[0] * wr[1]),
    ];

    // Mindlin: a spring on the tangential displacement, stiffness 8 G_eff a.
    let mindlin = Mindlin::at(
        c.tangential_stiffness,
        c.tangential_damping,
        c.sliding_friction,
        normal.a,
        normal.damping,
        fncrit,
    );
    let fs = mindlin.force(&mut history.tangential, &n, &vtr, step);

    let mut out = ContactForce {
        force: [
            n[0] * fntot + fs[0],
            n[1] * fntot + fs[1],
            n[2] * fntot + fs[2],
        ],
        ..ContactForce::default()
    };
    let tor = cross(&n, &fs);
    for d in 0..3 {
        out.torque_i[d] = -arm_i * tor[d];
        out.torque_j[d] = -arm_j * tor[d];
    }
    if !c.has_rolling_or_twisting() {
        return out;
    }

    let mut roll_torque = None;
    if let Some(roll) = &c.rolling {
        let fr = roll.rolling_force(&mut history.rolling, &n, &relrot, reff, fncrit, step);
        roll_torque = Some(cross(&n, &fr).map(|t| reff * t));
    }
    if let Some(twist) = c.twisting.at(&mindlin, normal.a, c.sliding_friction) {
        let moment = twist.twisting_moment(&mut history.twist, &n, &relrot, fncrit, step);
        for d in 0..3 {
            out.torque_i[d] += moment * n[d];
            out.torque_j[d] -= moment * n[d];
        }
    }
    if let Some(t) = roll_torque {
        for d in 0..3 {
            out.torque_i[d] += t[d];
            out.torque_j[d] -= t[d];
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::tangential::norm;
    use super::*;

    pub(super) fn material() -> GranularMaterial {
        GranularMaterial {
            youngs_modulus: 30.0,
            poisson_ratio: 0.25,
            restitution: 0.5,
            damping: NormalDamping::Tsuji,
            tangential_damping: 1.0,
            sliding_friction: 0.3,
            rolling: None,
            twisting: Twisting::None,
        }
    }

    #[test]
    fn the_lanes_cover_plain_hertz_mindlin_only() {
        let plain = GranularCoeffs::of(&material());
        assert!(plain.lanes_cover());
        let slider = SpringDashpotSlider {
            stiffness: 1.0,
            damping: 0.1,
            friction: 0.2,
        };
        let rolling = GranularCoeffs {
            rolling: Some(slider),
            ..plain
        };
        assert!(!rolling.lanes_cover());
        for twisting in [Twisting::Marshall, Twisting::Sds(slider)] {
            let twisted = GranularCoeffs { twisting, ..plain };
            assert!(!twisted.lanes_cover(), "{:?}", twisted.twisting);
        }
    }

    pub(super) fn at_rest(radius: f64, mass: f64) -> Sphere {
        Sphere {
            v: [0.0; 3],
            omega: [0.0; 3],
            radius,
            mass,
        }
    }

    pub(super) fn dot3(a: &[f64; 3], b: &[f64; 3]) -> f64 {
        a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
    }

    /// `E_eff` and `G_eff` of two spheres of one material, by their
    /// textbook definitions.
    pub(super) fn effective(m: &GranularMaterial) -> (f64, f64) {
        let (e, nu) = (m.youngs_modulus, m.poisson_ratio);
        let g = e / (2.0 * (1.0 + nu));
        (e / (2.0 * (1.0 - nu * nu)), g / (2.0 * (2.0 - nu)))
    }

    /// Two spheres in contact, sliding and spinning, with rolling and
    /// twisting friction on: coefficients, the spheres and their
    /// separation.
    fn spinning_pair() -> (GranularCoeffs, Sphere, Sphere, [f64; 3]) {
        let m = GranularMaterial {
            rolling: Some(SpringDashpotSlider {
                stiffness: 20.0,
                damping: 0.3,
                friction: 0.1,
            }),
            twisting: Twisting::Marshall,
            ..material()
        };
        let c = GranularCoeffs::of(&m);
        let si = Sphere {
            v: [0.01, -0.02, 0.03],
            omega: [0.1, 0.2, -0.3],
            radius: 0.8,
            mass: 1.3,
        };
        let sj = Sphere {
            v: [-0.01, 0.04, 0.0],
            omega: [-0.2, 0.05, 0.1],
            radius: 1.1,
            mass: 2.0,
        };
        let del = [1.2, 0.9, -0.7];
        (c, si, sj, del)
    }

    #[test]
    fn contact_torques_conserve_angular_momentum() {
        let (c, si, sj, del) = spinning_pair();
        let mut h = ContactHistory::default();
        for _ in 0..50 {
            let out = granular_contact(&c, &del, &si, &sj, &mut h, 0.01, true);
            // Total torque about the origin: x_i x F + x_j x (-F) + tau_i + tau_j.
            let l = cross(&del, &out.force);
            let total: Vec<f64> = (0..3)
                .map(|d| l[d] + out.torque_i[d] + out.torque_j[d])
                .collect();
            let scale = norm(&out.force) * norm(&del);
            assert!(total.iter().all(|t| t.abs() < 1e-14 * scale), "{total:?}");
        }
        assert!(norm(&h.rolling) > 0.0 && h.twist != 0.0);
    }

    #[test]
    fn forces_turn_with_the_frame() {
        let (c, si, sj, del) = spinning_pair();
        // A rotation by 90 degrees about z: (x, y, z) -> (-y, x, z).
        let turn = |a: [f64; 3]| [-a[1], a[0], a[2]];
        let rot = |s: &Sphere| Sphere {
            v: turn(s.v),
            omega: turn(s.omega),
            ..*s
        };
        let (mut h, mut g) = (ContactHistory::default(), ContactHistory::default());
        for _ in 0..20 {
            let a = granular_contact(&c, &del, &si, &sj, &mut h, 0.01, true);
            let b = granular_contact(&c, &turn(del), &rot(&si), &rot(&sj), &mut g, 0.01, true);
            for (p, q) in [
                (a.force, b.force),
                (a.torque_i, b.torque_i),
                (a.torque_j, b.torque_j),
            ] {
                let p = turn(p);
                assert!(
                    (0..3).all(|d| (p[d] - q[d]).abs() < 1e-13 * (1.0 + norm(&q))),
                    "{p:?} {q:?}"
                );
            }
        }
    }

    #[test]
    fn one_material_mixes_with_itself_and_a_rigid_wall_takes_the_limit() {
        let m = material();
        let (e_eff, g_eff) = effective(&m);
        let c = GranularCoeffs::of(&m);
        assert!((c.normal_stiffness - 4.0 / 3.0 * e_eff).abs() < 1e-14 * e_eff);
        assert!((c.tangential_stiffness - 8.0 * g_eff).abs() < 1e-14 * g_eff);
        // A wall 1e12 times stiffer: E_eff -> E / (1 - nu^2), G_eff -> G /
        // (2 - nu); damping and friction are the wall's.
        let wall = GranularMaterial {
            youngs_modulus: 1e12 * m.youngs_modulus,
            restitution: 0.9,
            sliding_friction: 0.05,
            ..m
        };
        let c = GranularCoeffs::between(&m, &wall);
        let nu = m.poisson_ratio;
        let g = m.youngs_modulus / (2.0 * (1.0 + nu));
        let rigid_e = m.youngs_modulus / (1.0 - nu * nu);
        assert!((c.normal_stiffness / (4.0 / 3.0 * rigid_e) - 1.0).abs() < 1e-11);
        assert!((c.tangential_stiffness / (8.0 * g / (2.0 - nu)) - 1.0).abs() < 1e-11);
        assert_eq!(c.normal_damping, tsuji_prefactor(0.9));
        assert_eq!(c.sliding_friction, 0.05);
    }

    /// A sphere of radius 1 against a wall of the same material, and
    /// against a sphere so large and heavy that it is that wall.
    fn wall_and_giant(
        overlap: f64,
        s: &Sphere,
        wall_velocity: [f64; 3],
        steps: usize,
    ) -> (ContactForce, ContactForce) {
        let mut m = material();
        m.rolling = Some(SpringDashpotSlider {
            stiffness: 10.0,
            damping: 0.5,
            friction: 0.1,
        });
        m.twisting = Twisting::Marshall;
        let c = GranularCoeffs::of(&m);
        let normal = [0.0, 0.6, 0.8];
        let touch = WallTouch {
            correction: 0.0,
            distance: s.radius - overlap,
            normal,
            velocity: wall_velocity,
        };
        let big = 1e7;
        let giant = Sphere {
            v: wall_velocity,
            omega: [0.0; 3],
            radius: big,
            mass: 1e30,
        };
        let del = normal.map(|n| n * (big + s.radius - overlap));
        let (mut hw, mut hg) = (ContactHistory::default(), ContactHistory::default());
        let (mut fw, mut fg) = (ContactForce::default(), ContactForce::default());
        for _ in 0..steps {
            fw = granular_wall_contact(&c, &touch, s, &mut hw, 0.01, true);
            fg = granular_contact(&c, &del, s, &giant, &mut hg, 0.01, true);
        }
        (fw, fg)
    }

    #[test]
    fn a_wall_is_the_limit_of_an_infinitely_large_and_heavy_sphere() {
        // Sliding, spinning and approaching a moving wall: every term acts.
        let s = Sphere {
            v: [0.02, -0.03, -0.01],
            omega: [0.05, -0.02, 0.04],
            radius: 1.0,
            mass: 2.0,
        };
        for steps in [1, 50] {
            let (wall, giant) = wall_and_giant(0.01, &s, [0.01, 0.0, 0.0], steps);
            let scale = norm(&giant.force);
            for d in 0..3 {
                // The giant's R_eff is 1e-7 short of R, and its overlap,
                // formed from distances of 1e7, rounds to about 1e-7 of
                // itself.
                assert!(
                    (wall.force[d] - giant.force[d]).abs() < 1e-6 * scale,
                    "{steps} steps: {:?} vs {:?}",
                    wall.force,
                    giant.force
                );
            }
            assert_eq!(wall.torque_j, [0.0; 3]);
        }
    }

    #[test]
    fn a_wall_contact_depends_only_on_the_velocity_relative_to_the_wall() {
        let s = Sphere {
            v: [0.02, -0.03, -0.01],
            omega: [0.05, -0.02, 0.04],
            radius: 1.0,
            mass: 2.0,
        };
        let u = [0.3, -0.1, 0.2];
        let moved = Sphere {
            v: [s.v[0] + u[0], s.v[1] + u[1], s.v[2] + u[2]],
            ..s
        };
        let (still, _) = wall_and_giant(0.02, &s, [0.0; 3], 20);
        let (moving, _) = wall_and_giant(0.02, &moved, u, 20);
        for d in 0..3 {
            assert!((still.force[d] - moving.force[d]).abs() < 1e-13);
            assert!((still.torque_i[d] - moving.torque_i[d]).abs() < 1e-13);
        }
        // And it does depend on it: the wall's velocity is not ignored.
        let (dragged, _) = wall_and_giant(0.02, &s, u, 20);
        assert!((dragged.force[0] - still.force[0]).abs() > 1e-4);
    }

    #[test]
    fn a_static_wall_contact_is_hertz_with_the_sphere_radius() {
        let m = material();
        let c = GranularCoeffs::of(&m);
        let (e_eff, _) = effective(&m);
        let radius = 0.7;
        for overlap in [1e-4, 1e-2, 0.1] {
            let touch = WallTouch {
                correction: 0.0,
                distance: radius - overlap,
                normal: [0.0, 0.0, -1.0],
                velocity: [0.0; 3],
            };
            let mut h = ContactHistory::default();
            let out = granular_wall_contact(&c, &touch, &at_rest(radius, 3.0), &mut h, 0.01, true);
            let hertz = 4.0 / 3.0 * e_eff * radius.sqrt() * overlap.powf(1.5);
            assert!((-out.force[2] - hertz).abs() < 1e-12 * hertz);
            assert_eq!(out.force[0], 0.0);
            assert_eq!(out.torque_i, [0.0; 3]);
        }
    }

    #[test]
    fn a_spinning_sphere_on_a_wall_feels_friction_at_its_full_radius() {
        let m = material();
        let c = GranularCoeffs::of(&m);
        let (radius, overlap) = (1.0, 0.01);
        let touch = WallTouch {
            correction: 0.0,
            distance: radius - overlap,
            normal: [0.0, 0.0, 1.0],
            velocity: [0.0; 3],
        };
        // Spinning about y, the contact point (below the centre) moves
        // along -x: friction pushes the sphere along +x.
        let s = Sphere {
            omega: [0.0, 0.1, 0.0],
            ..at_rest(radius, 1.0)
        };
        let mut h = ContactHistory::default();
        let mut out = ContactForce::default();
        for _ in 0..10_000 {
            out = granular_wall_contact(&c, &touch, &s, &mut h, 0.01, true);
        }
        let fn_ = out.force[2];
        assert!(fn_ > 0.0);
        assert!((out.force[0] - m.sliding_friction * fn_).abs() < 1e-12 * fn_);
        // Torque -R n x F_t about y: opposes the spin.
        assert!((out.torque_i[1] + radius * out.force[0]).abs() < 1e-14 * fn_);
        assert!(out.torque_i[1] < 0.0);
    }
}
