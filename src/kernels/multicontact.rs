//! The multi-contact closure for strongly deformed spheres (docs/model.md,
//! "Multi-contact closures"): each contact of a sphere sees its surface
//! moved by the forces on the sphere's other contacts.
//!
//! A force `F_k` pressing on the surface at contact `k` displaces the
//! surface at contact `c`, a distance `d_kc` away, by the elastic
//! half-space estimate (Brodu, Dijksman and Behringer)
//!
//! ```text
//! delta_kc = -gamma (1 + nu) F_k / (2 pi E d_kc)
//!            [ (n_k . u_kc)(n_c . u_kc) + (3 - 4 nu) n_k . n_c
//!              - (1 - 2 nu) (n_k + u_kc) . n_c / (1 + n_k . u_kc) ]
//! ```
//!
//! with `n` the inward surface normal at a contact point, `u_kc` the unit
//! vector from contact `k` to contact `c` and `gamma` an empirical
//! prefactor for the sphere's departure from a half-space. Contact `c`
//! then uses the radius `R + Delta_c`, `Delta_c = sum_{k != c} delta_kc`,
//! in its overlap (the standard closure). The advanced closure of Ghods et
//! al. switches the correction off where a term exceeds a maximum
//! penetration ratio `MPR` of the radius.
//!
//! Positive `delta_kc` grows the radius: two opposite contacts of a
//! squeezed sphere stiffen each other, and a sphere pressed at its poles
//! reaches out at its equator.

use serde::{Deserialize, Serialize};

/// Contact points closer than this fraction of the radius are one point:
/// the half-space estimate diverges as `1 / d_kc` and means nothing there.
pub const COINCIDENT_POINTS: f64 = 1e-10;

/// A contact point nearer the centre than this fraction of the radius
/// takes this distance when its normal is formed (the point is then
/// meaningless, but the normal stays finite).
pub const POINT_FLOOR: f64 = 1e-6;

/// Below this, `1 - 2 nu` or the denominator `1 + n_k . u_kc` counts as 0
/// and the `(1 - 2 nu)` term is left out: at `nu = 1/2` it vanishes, and
/// the denominator vanishes only for contact points that are not on one
/// convex surface.
pub const NEGLIGIBLE: f64 = 1e-6;

/// Which terms `delta_kc` exceeding the maximum penetration ratio switch
/// off (the advanced closure; Ghods et al. leave this open).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MprSwitch {
    /// The contact's whole correction: `Delta_c = 0` if any term is
    /// beyond the limit (the paper's eq. 3, where the contact falls back
    /// to plain Hertz).
    #[default]
    WholeContact,
    /// Only the terms beyond the limit; the others still add up.
    PerTerm,
}

impl MprSwitch {
    /// A contact's correction from the `sum` of its kept terms when
    /// `dropped` were beyond the limit, and how many this switched off
    /// (contacts or terms).
    #[inline]
    pub fn apply(self, sum: f64, dropped: usize) -> (f64, usize) {
        match self {
            MprSwitch::WholeContact if dropped > 0 => (0.0, 1),
            MprSwitch::WholeContact => (sum, 0),
            MprSwitch::PerTerm => (sum, dropped),
        }
    }
}

/// How a term is compared with the maximum penetration ratio.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MprTest {
    /// `delta_kc > MPR R`: only terms that grow the radius switch (the
    /// paper's algorithm as printed; `MPR = 0` is then not plain Hertz,
    /// since shrinking terms stay).
    #[default]
    Signed,
    /// `|delta_kc| > MPR R`: large terms of either sign switch, and `MPR =
    /// 0` is plain Hertz.
    Magnitude,
}

/// How the displacements from a sphere's other contacts combine into the
/// correction of one contact.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Closure {
    /// Every term adds up (Brodu et al.).
    Standard,
    /// Terms beyond `max_penetration_ratio` times the radius switch the
    /// correction off (Ghods et al.).
    Advanced {
        /// `MPR`: the largest term, over the sphere's radius, still taken.
        max_penetration_ratio: f64,
        /// What a term beyond the limit switches off.
        switch: MprSwitch,
        /// How a term is compared with the limit.
        test: MprTest,
    },
}

/// The half-space response of one sphere's material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HalfSpace {
    /// `-gamma (1 + nu) / (2 pi E)`.
    scale: f64,
    /// `3 - 4 nu`.
    in_plane: f64,
    /// `1 - 2 nu`, or 0 when negligible.
    compressible: f64,
}

impl HalfSpace {
    /// A sphere of Young's modulus `youngs_modulus` and Poisson's ratio
    /// `poisson_ratio`, with geometric prefactor `prefactor` (`gamma`).
    pub fn new(prefactor: f64, youngs_modulus: f64, poisson_ratio: f64) -> Self {
        let compressible = 1.0 - 2.0 * poisson_ratio;
        Self {
            scale: -prefactor * (1.0 + poisson_ratio)
                / (2.0 * std::f64::consts::PI * youngs_modulus),
            in_plane: 3.0 - 4.0 * poisson_ratio,
            compressible: if compressible.abs() > NEGLIGIBLE {
                compressible
            } else {
                0.0
            },
        }
    }

    /// `-gamma (1 + nu) / (2 pi E)`, the factor of every term.
    pub(super) fn scale(&self) -> f64 {
        self.scale
    }

    /// `1 - 2 nu`, or 0 when negligible.
    pub(super) fn compressible(&self) -> f64 {
        self.compressible
    }

    /// `delta_kc`: the displacement of the surface at contact `c` by the
    /// force on contact `k`; 0 for coincident points.
    #[inline]
    pub fn displacement(&self, k: &ContactPoint, c: &ContactPoint, radius: f64) -> f64 {
        let (source, scaled) = ((&k.point, &k.normal), self.scale * k.force);
        let (receiver, coincident) = ((&c.point, &c.normal), COINCIDENT_POINTS * radius);
        if self.compressible != 0.0 {
            self.term::<true>(source, scaled, receiver, coincident)
        } else {
            self.term::<false>(source, scaled, receiver, coincident)
        }
    }

    /// `delta_kc` from a `source` (point and inward normal) whose force
    /// times `scale` is `scaled_force` at a `receiver`, 0 for points
    /// closer than `coincident`; `COMPRESSIBLE` says whether the `1 - 2
    /// nu` term is on. Written without branches (selects between values
    /// both computed), so that the closure's lanes (`closure_lanes`) form
    /// their terms here too, vectorised.
    #[inline(always)]
    pub(super) fn term<const COMPRESSIBLE: bool>(
        &self,
        (k_point, k_normal): (&[f64; 3], &[f64; 3]),
        scaled_force: f64,
        (c_point, c_normal): (&[f64; 3], &[f64; 3]),
        coincident: f64,
    ) -> f64 {
        let w = [
            c_point[0] - k_point[0],
            c_point[1] - k_point[1],
            c_point[2] - k_point[2],
        ];
        let d = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
        // One division for the four quotients by `d`.
        let inv_d = 1.0 / d;
        let u = [w[0] * inv_d, w[1] * inv_d, w[2] * inv_d];
        let nk_u = dot(k_normal, &u);
        let nc_u = dot(c_normal, &u);
        let nk_nc = dot(k_normal, c_normal);
        let mut bracket = nk_u * nc_u + self.in_plane * nk_nc;
        if COMPRESSIBLE {
            let denominator = 1.0 + nk_u;
            let term = self.compressible * (nk_nc + nc_u) / denominator;
            // `x - 0` is `x` bit for bit: the select leaves the bracket as
            // a skipped subtraction would.
            bracket -= if denominator > NEGLIGIBLE { term } else { 0.0 };
        }
        let t = scaled_force * inv_d * bracket;
        if d <= coincident {
            0.0
        } else {
            t
        }
    }
}

#[inline(always)]
fn dot(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// One contact of a sphere, as the closure reads it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ContactPoint {
    /// The contact point relative to the sphere's centre (d).
    pub point: [f64; 3],
    /// The inward unit normal there, `-point / |point|`.
    pub normal: [f64; 3],
    /// Magnitude of the contact's normal force at the last evaluation
    /// (k d): 0 for a contact that is not a source.
    pub force: f64,
}

impl ContactPoint {
    /// A contact at `point` (relative to the centre of a sphere of radius
    /// `radius`) that pressed with `force`.
    #[inline]
    pub fn new(point: [f64; 3], force: f64, radius: f64) -> Self {
        let length = dot(&point, &point).sqrt().max(POINT_FLOOR * radius);
        Self {
            point,
            normal: point.map(|c| -c / length),
            force,
        }
    }
}

/// The contact points of spheres `i` and `j` (radii `radius_i`,
/// `radius_j`) at separation `del = x_i - x_j`, `r = |del| > 0`, whose
/// contact pressed with `force`: each relative to its own sphere's centre.
/// Halfway through the overlap, or each sphere's own surface point facing
/// the other while they are apart; never past a centre (a small sphere
/// deep in a large one). Both engines form the closure's points here.
#[inline]
pub fn pair_contact_points(
    del: &[f64; 3],
    r: f64,
    radius_i: f64,
    radius_j: f64,
    force: f64,
) -> [ContactPoint; 2] {
    let inset = 0.5 * (radius_i + radius_j - r).max(0.0);
    let towards_j = del.map(|c| -c / r);
    let si = (radius_i - inset).max(POINT_FLOOR * radius_i);
    let sj = (radius_j - inset).max(POINT_FLOOR * radius_j);
    [
        ContactPoint::new(towards_j.map(|c| si * c), force, radius_i),
        ContactPoint::new(towards_j.map(|c| -sj * c), force, radius_j),
    ]
}

/// Sorts `entries` by sphere (`sphere_of`, below `n`) into `grouped`,
/// keeping their order within a sphere (a counting sort): sphere `i`'s
/// entries are `grouped[offsets[i]..offsets[i + 1]]`, their points in
/// `points` likewise, for [`surface_corrections`]. Reuses the buffers.
pub fn group_by_sphere<E: Copy>(
    entries: &[E],
    n: usize,
    sphere_of: impl Fn(&E) -> usize,
    point_of: impl Fn(&E) -> ContactPoint,
    offsets: &mut Vec<usize>,
    grouped: &mut Vec<E>,
    points: &mut Vec<ContactPoint>,
) {
    offsets.clear();
    offsets.resize(n + 1, 0);
    for e in entries {
        offsets[sphere_of(e) + 1] += 1;
    }
    for i in 0..n {
        offsets[i + 1] += offsets[i];
    }
    // Placeholders, each overwritten below.
    grouped.clear();
    grouped.extend_from_slice(entries);
    points.clear();
    points.extend(entries.iter().map(&point_of));
    // `offsets[i]` serves as sphere i's cursor, then is restored.
    for e in entries {
        let slot = &mut offsets[sphere_of(e)];
        grouped[*slot] = *e;
        points[*slot] = point_of(e);
        *slot += 1;
    }
    for i in (1..=n).rev() {
        offsets[i] = offsets[i - 1];
    }
    offsets[0] = 0;
}

/// The radius correction `Delta_c` of each of one sphere's `contacts`
/// (radius `radius`), written to `corrections` (same length): the
/// displacements from every other contact that carried a force, combined
/// by `closure`. Returns how many the advanced closure switched off:
/// contacts (whole-contact switch) or terms (per-term switch).
pub fn surface_corrections(
    half_space: &HalfSpace,
    closure: &Closure,
    radius: f64,
    contacts: &[ContactPoint],
    corrections: &mut [f64],
) -> usize {
    assert_eq!(contacts.len(), corrections.len());
    let mut switched_off = 0;
    for (c, out) in contacts.iter().zip(corrections.iter_mut()) {
        let terms = contacts
            .iter()
            .filter(|k| k.force > 0.0 && !std::ptr::eq(*k, c))
            .map(|k| half_space.displacement(k, c, radius));
        *out = match *closure {
            Closure::Standard => terms.sum(),
            Closure::Advanced {
                max_penetration_ratio,
                switch,
                test,
            } => {
                let limit = max_penetration_ratio * radius;
                let beyond = |t: f64| match test {
                    MprTest::Signed => t > limit,
                    MprTest::Magnitude => t.abs() > limit,
                };
                let mut sum = 0.0;
                let mut dropped = 0;
                for t in terms {
                    if beyond(t) {
                        dropped += 1;
                    } else {
                        sum += t;
                    }
                }
                let (correction, off) = switch.apply(sum, dropped);
                switched_off += off;
                correction
            }
        };
    }
    switched_off
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn points(radius: f64, sites: &[([f64; 3], f64)]) -> Vec<ContactPoint> {
        sites
            .iter()
            .map(|&(p, f)| ContactPoint::new(p, f, radius))
            .collect()
    }

    fn corrections(hs: &HalfSpace, closure: &Closure, radius: f64, c: &[ContactPoint]) -> Vec<f64> {
        corrections_and_count(hs, closure, radius, c).0
    }

    fn corrections_and_count(
        hs: &HalfSpace,
        closure: &Closure,
        radius: f64,
        c: &[ContactPoint],
    ) -> (Vec<f64>, usize) {
        let mut out = vec![f64::NAN; c.len()];
        let count = surface_corrections(hs, closure, radius, c, &mut out);
        (out, count)
    }

    #[test]
    fn opposite_contacts_stiffen_each_other_by_the_closed_form() {
        // Poles of a sphere: n_k . u = 1, n_c . u = -1, n_k . n_c = -1, so
        // the bracket is -(3 - 2 nu) and delta = gamma (1 + nu) F (3 - 2 nu)
        // / (4 pi E R).
        let (r, e, gamma) = (1e-3, 5e7, 1.125);
        for nu in [0.0, 0.3, 0.5, -0.5] {
            let hs = HalfSpace::new(gamma, e, nu);
            let c = points(r, &[([r, 0.0, 0.0], 0.0), ([-r, 0.0, 0.0], 1.0)]);
            let got = corrections(&hs, &Closure::Standard, r, &c);
            let expected = gamma * (1.0 + nu) * 1.0 * (3.0 - 2.0 * nu) / (4.0 * PI * e * r);
            assert!(
                (got[0] - expected).abs() < 1e-14 * expected,
                "{got:?} {expected}"
            );
            assert_eq!(got[1], 0.0, "contact 0 carried no force");
        }
    }

    #[test]
    fn three_orthogonal_contacts_match_an_independent_derivation() {
        // Values from a separate re-derivation of the reference
        // implementation's loop (Python, kept beside the project notes).
        let r = 1e-3;
        let c = points(
            r,
            &[
                ([r, 0.0, 0.0], 1.0),
                ([0.0, r, 0.0], 2.0),
                ([0.0, 0.0, -r], 3.0),
            ],
        );
        for (nu, expected) in [
            (
                0.3,
                [
                    5.502_452_718_396_510_6e-6,
                    4.401_962_174_717_209e-6,
                    3.301_471_631_037_906_6e-6,
                ],
            ),
            (
                0.5,
                [
                    9.495_523_646_969_481e-6,
                    7.596_418_917_575_586e-6,
                    5.697_314_188_181_689e-6,
                ],
            ),
        ] {
            let got = corrections(&HalfSpace::new(1.125, 5e7, nu), &Closure::Standard, r, &c);
            for (g, e) in got.iter().zip(expected) {
                assert!(
                    (g - e).abs() < 1e-13 * e,
                    "nu {nu}: {got:?} vs {expected:?}"
                );
            }
        }
    }

    #[test]
    fn a_quarter_turn_term_by_hand() {
        // k on the +x pole, c on the +y pole: n_k = -x, n_c = -y, u = (-x +
        // y)/sqrt2, d = sqrt2 R; n_k.u = 1/sqrt2, n_c.u = -1/sqrt2, n_k.n_c
        // = 0; bracket = -1/2 - (1 - 2nu)(-1/sqrt2)/(1 + 1/sqrt2).
        let (r, e, nu, gamma, f) = (0.5, 30.0, 0.25, 0.82, 2.0);
        let hs = HalfSpace::new(gamma, e, nu);
        let k = ContactPoint::new([r, 0.0, 0.0], f, r);
        let c = ContactPoint::new([0.0, r, 0.0], 0.0, r);
        let s = 0.5f64.sqrt();
        let bracket = -0.5 + (1.0 - 2.0 * nu) * s / (1.0 + s);
        let expected = -gamma * (1.0 + nu) * f / (2.0 * PI * e * 2f64.sqrt() * r) * bracket;
        let got = hs.displacement(&k, &c, r);
        assert!((got - expected).abs() < 1e-15, "{got} vs {expected}");
        assert!(got > 0.0, "a side contact grows under a load at the pole");
    }

    #[test]
    fn displacements_turn_with_the_sphere_and_scale_with_force_over_modulus() {
        let r = 0.7;
        let hs = HalfSpace::new(1.0, 10.0, 0.35);
        let k = [0.3, -0.5, 0.4f64];
        let kn = (k[0] * k[0] + k[1] * k[1] + k[2] * k[2]).sqrt();
        let k = k.map(|v| v / kn * r);
        let c = [-0.6, 0.1, 0.2f64];
        let cn = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
        let c = c.map(|v| v / cn * r);
        let base = hs.displacement(
            &ContactPoint::new(k, 1.5, r),
            &ContactPoint::new(c, 0.0, r),
            r,
        );
        // A rotation about z by 40 degrees.
        let (s, co) = (40f64.to_radians().sin(), 40f64.to_radians().cos());
        let rot = |p: [f64; 3]| [co * p[0] - s * p[1], s * p[0] + co * p[1], p[2]];
        let turned = hs.displacement(
            &ContactPoint::new(rot(k), 1.5, r),
            &ContactPoint::new(rot(c), 0.0, r),
            r,
        );
        assert!((turned - base).abs() < 1e-14 * base.abs());
        let stiffer = HalfSpace::new(1.0, 20.0, 0.35).displacement(
            &ContactPoint::new(k, 3.0, r),
            &ContactPoint::new(c, 0.0, r),
            r,
        );
        assert!((stiffer - base).abs() < 1e-14 * base.abs());
    }

    #[test]
    fn coincident_points_and_forceless_contacts_add_nothing() {
        let r = 1.0;
        let hs = HalfSpace::new(1.0, 1.0, 0.3);
        let c = points(r, &[([r, 0.0, 0.0], 1.0), ([r, 0.0, 0.0], 1.0)]);
        assert_eq!(corrections(&hs, &Closure::Standard, r, &c), vec![0.0, 0.0]);
        let c = points(r, &[([r, 0.0, 0.0], 0.0), ([0.0, r, 0.0], 0.0)]);
        assert_eq!(corrections(&hs, &Closure::Standard, r, &c), vec![0.0, 0.0]);
        // A point at the centre still gives finite numbers.
        let c = points(r, &[([0.0; 3], 1.0), ([0.0, r, 0.0], 1.0)]);
        assert!(corrections(&hs, &Closure::Standard, r, &c)
            .iter()
            .all(|d| d.is_finite()));
    }

    #[test]
    fn the_advanced_closure_switches_large_terms_off() {
        // Four equatorial contacts pressed, the poles loaded harder: each
        // pole receives one large term (from the other pole) and four
        // smaller ones.
        let r = 1.0;
        let hs = HalfSpace::new(1.0, 1.0, 0.3);
        let c = points(
            r,
            &[
                ([0.0, 0.0, r], 0.2),
                ([0.0, 0.0, -r], 0.2),
                ([r, 0.0, 0.0], 0.01),
                ([-r, 0.0, 0.0], 0.01),
                ([0.0, r, 0.0], 0.01),
                ([0.0, -r, 0.0], 0.01),
            ],
        );
        let at_pole = |k: usize| hs.displacement(&c[k], &c[0], r);
        let large = at_pole(1);
        let small: Vec<f64> = (2..6).map(at_pole).collect();
        assert!(small.iter().all(|t| t.abs() < large));
        let standard = corrections(&hs, &Closure::Standard, r, &c);
        let sum = large + small.iter().sum::<f64>();
        assert!((standard[0] - sum).abs() < 1e-15);
        let mpr = 0.5 * large / r;
        let advanced = |switch, test| {
            corrections_and_count(
                &hs,
                &Closure::Advanced {
                    max_penetration_ratio: mpr,
                    switch,
                    test,
                },
                r,
                &c,
            )
        };
        let whole = advanced(MprSwitch::WholeContact, MprTest::Signed);
        assert_eq!(whole.0[0], 0.0, "the pole falls back to Hertz");
        assert_eq!(whole.0[1], 0.0, "and so does the other pole");
        assert_eq!(whole.0[2], standard[2], "the equator keeps its terms");
        assert_eq!(whole.1, 2, "two contacts switched off");
        let per_term = advanced(MprSwitch::PerTerm, MprTest::Signed);
        assert!((per_term.0[0] - small.iter().sum::<f64>()).abs() < 1e-15);
        assert_eq!(per_term.1, 2, "one term at each pole");
        // Below every term, the limit leaves the standard closure.
        let loose = corrections(
            &hs,
            &Closure::Advanced {
                max_penetration_ratio: 2.0 * large / r,
                switch: MprSwitch::WholeContact,
                test: MprTest::Signed,
            },
            r,
            &c,
        );
        assert_eq!(loose, standard);
    }

    #[test]
    fn a_zero_ratio_is_plain_hertz_only_with_the_magnitude_test() {
        let r = 1.0;
        let hs = HalfSpace::new(1.0, 1.0, 0.3);
        // Two contacts 60 degrees apart push each other in (a negative
        // term), the opposite pole out.
        let (s, c60) = (60f64.to_radians().sin(), 60f64.to_radians().cos());
        let c = points(
            r,
            &[
                ([0.0, 0.0, r], 1.0),
                ([s * r, 0.0, c60 * r], 1.0),
                ([0.0, 0.0, -r], 1.0),
            ],
        );
        assert!(hs.displacement(&c[1], &c[0], r) < 0.0);
        let zero = |test| {
            corrections(
                &hs,
                &Closure::Advanced {
                    max_penetration_ratio: 0.0,
                    switch: MprSwitch::PerTerm,
                    test,
                },
                r,
                &c,
            )
        };
        assert_eq!(zero(MprTest::Magnitude), vec![0.0; 3]);
        let signed = zero(MprTest::Signed);
        assert!(signed[0] < 0.0, "the signed test keeps shrinking terms");
    }

    /// Six equal contacts at the ends of three axes: each is corrected by
    /// its opposite contact and four at a quarter turn, in closed form.
    /// The quarter-turn term changes sign at nu = (1 - (1 + sqrt 2) / 2) / 2
    /// = -0.104, so at negative nu a crowded sphere gets little correction
    /// (the calibration against grains at nu = -0.10 shows it).
    #[test]
    fn six_axial_contacts_follow_the_closed_form_at_any_poisson_ratio() {
        let (r, e, f) = (1.5, 2.0, 0.7);
        let axes = [
            [r, 0.0, 0.0],
            [-r, 0.0, 0.0],
            [0.0, r, 0.0],
            [0.0, -r, 0.0],
            [0.0, 0.0, r],
            [0.0, 0.0, -r],
        ];
        let contacts: Vec<ContactPoint> =
            axes.iter().map(|&p| ContactPoint::new(p, f, r)).collect();
        let mut previous = f64::NEG_INFINITY;
        for nu in [-0.3, -0.1, 0.0, 0.25, 0.4] {
            let hs = HalfSpace::new(1.0, e, nu);
            let opposite = (3.0 - 2.0 * nu) / 2.0;
            let quarter = (0.5 - (1.0 - 2.0 * nu) / (1.0 + 2f64.sqrt())) / 2f64.sqrt();
            let expected = (1.0 + nu) * f / (2.0 * PI * e * r) * (opposite + 4.0 * quarter);
            let got = corrections(&hs, &Closure::Standard, r, &contacts);
            for g in &got {
                assert!(
                    (g - expected).abs() < 1e-14,
                    "nu {nu}: {g} against {expected}"
                );
            }
            assert!(got[0] > previous, "nu {nu}: the correction falls with nu");
            previous = got[0];
        }
        let flip = (1.0 - (1.0 + 2f64.sqrt()) / 2.0) / 2.0;
        let hs = HalfSpace::new(1.0, e, flip);
        let quarter = hs.displacement(&contacts[0], &contacts[2], r);
        assert!(quarter.abs() < 1e-15, "{quarter}");
    }

    #[test]
    fn incompressible_material_drops_the_compressibility_term() {
        // At nu = 1/2 the quarter-turn bracket is -1/2 exactly.
        let (r, e) = (1.0, 3.0);
        let hs = HalfSpace::new(1.0, e, 0.5);
        let k = ContactPoint::new([r, 0.0, 0.0], 1.0, r);
        let c = ContactPoint::new([0.0, r, 0.0], 0.0, r);
        let expected = -(1.5) / (2.0 * PI * e * 2f64.sqrt() * r) * -0.5;
        assert!((hs.displacement(&k, &c, r) - expected).abs() < 1e-15);
    }
}
