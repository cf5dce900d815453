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

// Vector components are written `for d in 0..3` over several arrays at
// once, as the equations read.
#![allow(clippy::needless_range_loop)]

use serde::{Deserialize, Serialize};

/// Below this, a history component out of the tangent plane is left as is
/// (LAMMPS's `EPSILON` in the frame update test).
const FRAME_EPSILON: f64 = 1e-10;

/// How the normal damping coefficient follows from the restitution
/// coefficient `e`. Both scale as `sqrt(m_eff k_n a)`, which keeps `e`
/// independent of the impact speed for Hertzian contacts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum NormalDamping {
    /// Tsuji, Tanaka and Ishida: `c_e` is a sixth-order polynomial fitted
    /// so that a Hertzian collision rebounds with `e` (LAMMPS `damping
    /// tsuji`).
    #[default]
    Tsuji,
    /// `c_e = sqrt(5) |ln e| / sqrt(ln^2 e + pi^2)` (LIGGGHTS's Hertz
    /// model; LAMMPS `damping coeff_restitution`, which the Debian LAMMPS of
    /// 2021 lacks): two spheres rebound with `e` (measured to 1e-4, at any
    /// impact speed).
    CoeffRestitution,
}

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

/// Tsuji, Tanaka and Ishida's damping prefactor for restitution `e`, the
/// polynomial LAMMPS's `damping tsuji` uses.
pub fn tsuji_prefactor(e: f64) -> f64 {
    // Powers formed and summed as LAMMPS forms them, so both round alike.
    let sq = e * e;
    let cu = sq * e;
    let p4 = sq * sq;
    let p5 = e * p4;
    let p6 = sq * p4;
    1.2728 - 4.2783 * e + 11.087 * sq - 22.348 * cu + 27.467 * p4 - 18.022 * p5 + 4.8218 * p6
}

/// The linear-spring damping prefactor `sqrt(5) |ln e| / sqrt(ln^2 e +
/// pi^2)` for restitution `e`.
pub fn restitution_prefactor(e: f64) -> f64 {
    let l = e.ln();
    5f64.sqrt() * l.abs() / (l * l + std::f64::consts::PI * std::f64::consts::PI).sqrt()
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
    /// skips their terms).
    pub fn has_rolling_or_twisting(&self) -> bool {
        self.rolling.is_some() || self.twisting != Twisting::None
    }
}

/// One body's share `(1 - nu^2) / E` of the Hertz contact compliance:
/// `E_eff = 1 / (sum of both shares)`.
fn youngs_compliance(e: f64, nu: f64) -> f64 {
    (1.0 - nu * nu) / e
}

/// One body's share `(2 - nu) / G = 2 (2 - nu) (1 + nu) / E` of Mindlin's
/// tangential compliance (formed as LAMMPS forms it): `G_eff = 1 / (sum of
/// both shares)`.
fn shear_compliance(e: f64, nu: f64) -> f64 {
    2.0 * (2.0 - nu) * (1.0 + nu) / e
}

/// What a contact remembers between steps.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
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

#[inline(always)]
fn norm(a: &[f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

/// Turns a history vector into the tangent plane of `n`, keeping its
/// length, when its normal part is not negligible (`|h . n| scale >
/// FRAME_EPSILON limit`).
#[inline(always)]
fn rotate_into_plane(h: &mut [f64; 3], n: &[f64; 3], scale: f64, limit: f64) {
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
fn slider(h: &mut [f64; 3], w: &[f64; 3], k: f64, eta: f64, limit: f64) -> [f64; 3] {
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

/// What the contact law reads of one contact, whatever its two bodies
/// are: two spheres, or a sphere and a flat wall.
struct Contact {
    /// Unit normal, towards `i`.
    n: [f64; 3],
    /// Overlap (d).
    delta: f64,
    /// Effective radius (d).
    reff: f64,
    /// Effective mass (m).
    meff: f64,
    /// Relative velocity of the centres, `v_i - v_j`.
    vr: [f64; 3],
    /// `R_i omega_i + R_j omega_j` (with each surface's moved radius):
    /// the surfaces' spin at the contact.
    wr: [f64; 3],
    /// Relative angular velocity, `omega_i - omega_j`.
    relrot: [f64; 3],
    /// Lever arms of the tangential force about each centre.
    arm_i: f64,
    arm_j: f64,
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
    let rsq = del[0] * del[0] + del[1] * del[1] + del[2] * del[2];
    let r = rsq.sqrt();
    let rinv = 1.0 / r;
    let radsum = si.radius + sj.radius;
    let (surface_i, surface_j) = (si.radius + corrections[0], sj.radius + corrections[1]);
    let delta = (surface_i + surface_j) - r;
    let contact = Contact {
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
    };
    contact_law(c, &contact, history, dt, update)
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
    let contact = Contact {
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
    };
    let mut out = contact_law(c, &contact, history, dt, update);
    out.torque_j = [0.0; 3];
    out
}

/// Hertz normal force with damping, Mindlin tangential force, rolling and
/// twisting resistance for one contact.
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

    // Hertz, with damping that scales as sqrt(k_n a).
    let a = (delta * reff).sqrt();
    let fne = c.normal_stiffness * delta * a;
    let knfac = c.normal_stiffness * a;
    let damp_normal = c.normal_damping * (meff * knfac).sqrt();
    let fntot = fne - damp_normal * vnnr;
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
    let damp_tangential = c.tangential_damping * damp_normal;
    let k_tangential = c.tangential_stiffness * a;
    let fscrit = c.sliding_friction * fncrit;
    if update {
        rotate_into_plane(&mut history.tangential, &n, k_tangential, fscrit);
        for d in 0..3 {
            history.tangential[d] += vtr[d] * dt;
        }
    }
    let fs = slider(
        &mut history.tangential,
        &vtr,
        k_tangential,
        damp_tangential,
        fscrit,
    );

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
        // Rolling velocity R (relrot x n) (Wang et al. 2015, eq. 31).
        let vrl = [
            reff * (relrot[1] * n[2] - relrot[2] * n[1]),
            reff * (relrot[2] * n[0] - relrot[0] * n[2]),
            reff * (relrot[0] * n[1] - relrot[1] * n[0]),
        ];
        let frcrit = roll.friction * fncrit;
        if update {
            rotate_into_plane(&mut history.rolling, &n, roll.stiffness, frcrit);
            for d in 0..3 {
                history.rolling[d] += vrl[d] * dt;
            }
        }
        let fr = slider(
            &mut history.rolling,
            &vrl,
            roll.stiffness,
            roll.damping,
            frcrit,
        );
        roll_torque = Some(cross(&n, &fr).map(|t| reff * t));
    }
    // Marshall's twisting stiffness is k_t a^2 / 2 with the contact's
    // tangential stiffness k_t = 8 G_eff a, so it grows as a^3 (the
    // torsional stiffness of a circular contact), as LAMMPS 2021 has it.
    let twist = match c.twisting {
        Twisting::None => None,
        Twisting::Marshall => Some((
            0.5 * k_tangential * a * a,
            0.5 * damp_tangential * a * a,
            2.0 / 3.0 * a * c.sliding_friction,
        )),
        Twisting::Sds(t) => Some((t.stiffness, t.damping, t.friction)),
    };
    if let Some((k_twist, damp_twist, mu_twist)) = twist {
        let magtwist = relrot[0] * n[0] + relrot[1] * n[1] + relrot[2] * n[2];
        if update {
            history.twist += magtwist * dt;
        }
        let mut moment = -k_twist * history.twist - damp_twist * magtwist;
        let mtcrit = mu_twist * fncrit;
        if moment.abs() > mtcrit {
            let sign = f64::from(i8::from(magtwist > 0.0) - i8::from(magtwist < 0.0));
            history.twist = 1.0 / k_twist * (mtcrit * sign - damp_twist * magtwist);
            moment = -mtcrit * sign;
        }
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
    use super::*;

    fn material() -> GranularMaterial {
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

    fn at_rest(radius: f64, mass: f64) -> Sphere {
        Sphere {
            v: [0.0; 3],
            omega: [0.0; 3],
            radius,
            mass,
        }
    }

    fn dot3(a: &[f64; 3], b: &[f64; 3]) -> f64 {
        a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
    }

    /// `E_eff` and `G_eff` of two spheres of one material, by their
    /// textbook definitions.
    fn effective(m: &GranularMaterial) -> (f64, f64) {
        let (e, nu) = (m.youngs_modulus, m.poisson_ratio);
        let g = e / (2.0 * (1.0 + nu));
        (e / (2.0 * (1.0 - nu * nu)), g / (2.0 * (2.0 - nu)))
    }

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

    /// A head-on collision of two equal spheres, integrated with velocity
    /// Verlet at a step far below the contact time: the rebound speed over
    /// the impact speed.
    fn restitution_of(m: &GranularMaterial, speed: f64) -> f64 {
        let c = GranularCoeffs::of(m);
        let (radius, mass) = (0.5, 1.0);
        let mut x = 1.0 - 1e-12; // just touching
        let mut v = -speed; // x = x_i - x_j, v = v_i - v_j
        let meff = 0.5 * mass;
        // Contact time ~ 3 (meff^2 / (k_n^2 R v)) ^ (1/5).
        let kn = c.normal_stiffness;
        let t_contact = 3.2 * (meff * meff / (kn * kn * 0.25 * speed)).powf(0.2);
        let dt = t_contact / 20000.0;
        let force = |x: f64, v: f64| {
            let si = Sphere {
                v: [v, 0.0, 0.0],
                ..at_rest(radius, mass)
            };
            let mut h = ContactHistory::default();
            if x >= 2.0 * radius {
                return 0.0;
            }
            granular_contact(
                &c,
                &[x, 0.0, 0.0],
                &si,
                &at_rest(radius, mass),
                &mut h,
                dt,
                true,
            )
            .force[0]
        };
        let mut f = force(x, v);
        for _ in 0..1_000_000 {
            // Relative coordinate: x'' = F / m_eff.
            v += 0.5 * dt * f / meff;
            x += dt * v;
            f = force(x, v);
            v += 0.5 * dt * f / meff;
            if x >= 2.0 * radius && v > 0.0 {
                return v / speed;
            }
        }
        panic!("the spheres did not part");
    }

    #[test]
    fn restitution_form_rebounds_with_the_restitution_asked_for_at_any_speed() {
        for e in [0.1, 0.3, 0.5, 0.7, 0.9, 1.0] {
            let m = GranularMaterial {
                damping: NormalDamping::CoeffRestitution,
                restitution: e,
                ..material()
            };
            for speed in [1e-3, 1e-1] {
                let measured = restitution_of(&m, speed);
                assert!(
                    (measured - e).abs() < 1e-4,
                    "e = {e}, v = {speed}: {measured}"
                );
            }
        }
    }

    /// Tsuji's polynomial damps two equal spheres by 1/sqrt(2) of what `e`
    /// needs (the ratio a fit made with the mass of one sphere, where the
    /// force uses the reduced mass, would give): they rebound with more
    /// than `e`, at any speed. LAMMPS 2021 does the same;
    /// docs/model.md tabulates the rebound.
    #[test]
    fn tsuji_damping_is_the_restitution_form_over_sqrt_two_and_speed_independent() {
        for e in [0.1, 0.3, 0.5, 0.7, 0.9] {
            let ratio = restitution_prefactor(e) / tsuji_prefactor(e);
            assert!(
                (ratio - 2f64.sqrt()).abs() < 3e-3 * 2f64.sqrt(),
                "e = {e}: {ratio}"
            );
            let m = GranularMaterial {
                restitution: e,
                ..material()
            };
            let (slow, fast) = (restitution_of(&m, 1e-3), restitution_of(&m, 1e-1));
            assert!(slow > e, "e = {e}: rebound {slow}");
            assert!((slow - fast).abs() < 1e-4, "{slow} vs {fast}");
            eprintln!("tsuji e = {e}: rebound {slow:.4}");
        }
    }

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

    #[test]
    fn contact_torques_conserve_angular_momentum() {
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
        // A rotation by 90 degrees about z: (x, y, z) -> (-y, x, z).
        let turn = |a: [f64; 3]| [-a[1], a[0], a[2]];
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
