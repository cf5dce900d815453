//! Hertz-Mindlin contacts four at a time: the contact law of
//! [`super::corrected_granular_contact`] without rolling or twisting
//! resistance, for blocks of four touching pairs.
//!
//! One contact's force is a chain of four square roots and three
//! divisions (more while it slides) that the processor cannot overlap
//! with much else. A block of four contacts is formed here in plain
//! per-lane loops, which the compiler turns into vector instructions (two
//! lanes of SSE2 in the portable build, four of AVX2 when the processor
//! has it, chosen at run time). The frame turn and the Coulomb cap become
//! selects between values both computed.
//!
//! Every lane performs the operations of the one-contact kernel in the
//! same order, without fused multiply-adds, and each select picks the
//! value the one-contact kernel's branch would have produced, so the
//! forces, torques and histories are the same bit for bit.

// Lanes are written `for l in 0..LANES` over several arrays at once, the
// form the compiler turns into vector instructions.
#![allow(clippy::needless_range_loop)]

use super::granular::{
    pair_contact, wall_contact, Contact, GranularCoeffs, Sphere, WallTouch, FRAME_EPSILON,
};
use super::isa::Isa;

/// Contacts per block.
pub const CONTACT_LANES: usize = 4;

type Lanes = [f64; CONTACT_LANES];

/// A block of touching pairs, component by component: what the contact law
/// reads, and the tangential history it turns, advances and caps.
#[derive(Clone, Copy, Debug, Default)]
pub struct ContactBlock {
    /// `x_i - x_j`.
    pub del: [Lanes; 3],
    /// Velocities of `i` and `j` (a Lees-Edwards image's included).
    pub v: [[Lanes; 3]; 2],
    /// Angular velocities of `i` and `j`.
    pub omega: [[Lanes; 3]; 2],
    /// Radii of `i` and `j`.
    pub radius: [Lanes; 2],
    /// Masses of `i` and `j`.
    pub mass: [Lanes; 2],
    /// Each sphere's surface moved out at the contact (the closure's
    /// corrections; 0 for plain Hertz).
    pub moved: [Lanes; 2],
    /// The tangential history `xi`, read and written.
    pub tangential: [Lanes; 3],
}

impl ContactBlock {
    /// Copies lane 0 into lanes `from..`: a partly filled block's spare
    /// lanes then form a finite contact, which the caller does not read.
    pub fn fill_from_first(&mut self, from: usize) {
        for d in 0..3 {
            spread(&mut self.del[d], from);
            spread(&mut self.tangential[d], from);
            for side in 0..2 {
                spread(&mut self.v[side][d], from);
                spread(&mut self.omega[side][d], from);
            }
        }
        for side in 0..2 {
            spread(&mut self.radius[side], from);
            spread(&mut self.mass[side], from);
            spread(&mut self.moved[side], from);
        }
    }
}

/// Copies lane 0 of `lanes` into lanes `from..`.
fn spread(lanes: &mut Lanes, from: usize) {
    for l in from..CONTACT_LANES {
        lanes[l] = lanes[0];
    }
}

/// What a block of contacts gives.
#[derive(Clone, Copy, Debug, Default)]
pub struct BlockForces {
    /// Force on `i` (on `j` it is the opposite).
    pub force: [Lanes; 3],
    /// Torques on `i` and `j`.
    pub torque: [[Lanes; 3]; 2],
    /// The total normal force's magnitude, which the history records.
    pub normal_force: Lanes,
}

/// Forms a block of contacts on `isa` (the portable build if the
/// processor lacks it): the forces, and the tangential histories advanced
/// over `dt` when `update` (an evaluation that completes a step). Panics if
/// `coeffs` has rolling or twisting resistance, which the lanes leave out.
pub fn hertz_mindlin_block(
    isa: Isa,
    coeffs: &GranularCoeffs,
    block: &mut ContactBlock,
    dt: f64,
    update: bool,
) -> BlockForces {
    assert!(
        coeffs.lanes_cover(),
        "the lanes do not cover these coefficients (GranularCoeffs::lanes_cover)"
    );
    #[cfg(target_arch = "x86_64")]
    if isa == Isa::Avx2 && Isa::Avx2.available() {
        // SAFETY: the processor has AVX2 (checked just above).
        return unsafe { block_avx2(coeffs, block, dt, update) };
    }
    let _ = isa;
    block_lanes(coeffs, block, dt, update)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn block_avx2(
    coeffs: &GranularCoeffs,
    block: &mut ContactBlock,
    dt: f64,
    update: bool,
) -> BlockForces {
    block_lanes(coeffs, block, dt, update)
}

/// `corrected_granular_contact` and `contact_law` (Hertz, Tsuji or
/// restitution damping, Mindlin with sliding), lane by lane: the scalar
/// kernel's own geometry (`pair_contact`), then [`lane_law`].
#[inline(always)]
fn block_lanes(c: &GranularCoeffs, block: &mut ContactBlock, dt: f64, update: bool) -> BlockForces {
    let mut out = BlockForces::default();
    let lane = |side: usize, l: usize| Sphere {
        v: std::array::from_fn(|d| block.v[side][d][l]),
        omega: std::array::from_fn(|d| block.omega[side][d][l]),
        radius: block.radius[side][l],
        mass: block.mass[side][l],
    };
    for l in 0..CONTACT_LANES {
        let del = std::array::from_fn(|d| block.del[d][l]);
        let moved = [block.moved[0][l], block.moved[1][l]];
        let contact = pair_contact(&del, &lane(0, l), &lane(1, l), moved);
        let mut h = [
            block.tangential[0][l],
            block.tangential[1][l],
            block.tangential[2][l],
        ];
        let lane = lane_law(c, &contact, &mut h, dt, update);
        for d in 0..3 {
            block.tangential[d][l] = h[d];
            out.force[d][l] = lane.force[d];
            out.torque[0][d][l] = lane.torque_i[d];
            out.torque[1][d][l] = lane.torque_j[d];
        }
        out.normal_force[l] = lane.normal_force;
    }
    out
}

/// Four spheres touching one flat wall, component by component.
#[derive(Clone, Copy, Debug, Default)]
pub struct WallBlock {
    /// Each centre's distance from the wall's plane.
    pub distance: Lanes,
    /// Each surface moved out at the wall (the closure's; 0 for Hertz).
    pub correction: Lanes,
    /// Velocities.
    pub v: [Lanes; 3],
    /// Angular velocities.
    pub omega: [Lanes; 3],
    /// Radii.
    pub radius: Lanes,
    /// Masses.
    pub mass: Lanes,
    /// The tangential history `xi`, read and written.
    pub tangential: [Lanes; 3],
}

impl WallBlock {
    /// Copies lane 0 into lanes `from..` (see
    /// [`ContactBlock::fill_from_first`]).
    pub fn fill_from_first(&mut self, from: usize) {
        let scalars = [
            &mut self.distance,
            &mut self.correction,
            &mut self.radius,
            &mut self.mass,
        ];
        for lanes in scalars {
            spread(lanes, from);
        }
        for d in 0..3 {
            spread(&mut self.v[d], from);
            spread(&mut self.omega[d], from);
            spread(&mut self.tangential[d], from);
        }
    }
}

/// What a block of wall contacts gives.
#[derive(Clone, Copy, Debug, Default)]
pub struct WallForces {
    /// Force on each sphere.
    pub force: [Lanes; 3],
    /// Torque on each sphere.
    pub torque: [Lanes; 3],
    /// The total normal force's magnitude, which the history records.
    pub normal_force: Lanes,
}

/// [`hertz_mindlin_block`] for four spheres touching the flat wall whose
/// unit normal (towards the spheres) is `normal` and whose velocity is
/// `velocity`: `granular_wall_contact` lane by lane, the same bits.
pub fn hertz_mindlin_wall_block(
    isa: Isa,
    coeffs: &GranularCoeffs,
    normal: &[f64; 3],
    velocity: &[f64; 3],
    block: &mut WallBlock,
    dt: f64,
    update: bool,
) -> WallForces {
    assert!(
        coeffs.lanes_cover(),
        "the lanes do not cover these coefficients (GranularCoeffs::lanes_cover)"
    );
    let wall = (normal, velocity);
    #[cfg(target_arch = "x86_64")]
    if isa == Isa::Avx2 && Isa::Avx2.available() {
        // SAFETY: the processor has AVX2 (checked just above).
        return unsafe { wall_block_avx2(coeffs, wall, block, dt, update) };
    }
    let _ = isa;
    wall_block_lanes(coeffs, wall, block, dt, update)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn wall_block_avx2(
    coeffs: &GranularCoeffs,
    wall: (&[f64; 3], &[f64; 3]),
    block: &mut WallBlock,
    dt: f64,
    update: bool,
) -> WallForces {
    wall_block_lanes(coeffs, wall, block, dt, update)
}

/// `granular_wall_contact` lane by lane: its geometry (`wall_contact`),
/// then [`lane_law`].
#[inline(always)]
fn wall_block_lanes(
    c: &GranularCoeffs,
    (normal, wall_velocity): (&[f64; 3], &[f64; 3]),
    block: &mut WallBlock,
    dt: f64,
    update: bool,
) -> WallForces {
    let mut out = WallForces::default();
    for l in 0..CONTACT_LANES {
        let touch = WallTouch {
            distance: block.distance[l],
            normal: *normal,
            velocity: *wall_velocity,
            correction: block.correction[l],
        };
        let sphere = Sphere {
            v: std::array::from_fn(|d| block.v[d][l]),
            omega: std::array::from_fn(|d| block.omega[d][l]),
            radius: block.radius[l],
            mass: block.mass[l],
        };
        let contact = wall_contact(&touch, &sphere);
        let mut h = [
            block.tangential[0][l],
            block.tangential[1][l],
            block.tangential[2][l],
        ];
        let lane = lane_law(c, &contact, &mut h, dt, update);
        for d in 0..3 {
            block.tangential[d][l] = h[d];
            out.force[d][l] = lane.force[d];
            out.torque[d][l] = lane.torque_i[d];
        }
        out.normal_force[l] = lane.normal_force;
    }
    out
}

/// One lane's result.
struct LaneForce {
    force: [f64; 3],
    torque_i: [f64; 3],
    torque_j: [f64; 3],
    normal_force: f64,
}

/// `contact_law` without rolling or twisting, its branches as selects;
/// `h` is the tangential history.
#[inline(always)]
fn lane_law(
    c: &GranularCoeffs,
    contact: &Contact,
    h: &mut [f64; 3],
    dt: f64,
    update: bool,
) -> LaneForce {
    let Contact {
        n,
        delta,
        reff,
        meff,
        vr,
        wr,
        arm_i,
        arm_j,
        ..
    } = *contact;
    let vnnr = vr[0] * n[0] + vr[1] * n[1] + vr[2] * n[2];
    let vn = [n[0] * vnnr, n[1] * vnnr, n[2] * vnnr];
    let a = (delta * reff).sqrt();
    let fne = c.normal_stiffness * delta * a;
    let knfac = c.normal_stiffness * a;
    let damp_normal = c.normal_damping * (meff * knfac).sqrt();
    let fntot = fne - damp_normal * vnnr;
    let fncrit = fntot.abs();
    let vt = [vr[0] - vn[0], vr[1] - vn[1], vr[2] - vn[2]];
    let vtr = [
        vt[0] - (n[2] * wr[1] - n[1] * wr[2]),
        vt[1] - (n[0] * wr[2] - n[2] * wr[0]),
        vt[2] - (n[1] * wr[0] - n[0] * wr[1]),
    ];
    let damp_tangential = c.tangential_damping * damp_normal;
    let k_tangential = c.tangential_stiffness * a;
    let fscrit = c.sliding_friction * fncrit;

    // The history's turn into the tangent plane and its advance
    // (`rotate_into_plane`), taken only on a step.
    let along = h[0] * n[0] + h[1] * n[1] + h[2] * n[2];
    let turn = update && along.abs() * k_tangential > FRAME_EPSILON * fscrit;
    let before = (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).sqrt();
    let flat = [
        h[0] - along * n[0],
        h[1] - along * n[1],
        h[2] - along * n[2],
    ];
    let after = (flat[0] * flat[0] + flat[1] * flat[1] + flat[2] * flat[2]).sqrt();
    let s = if after > 0.0 { before / after } else { 0.0 };
    for d in 0..3 {
        h[d] = if turn { flat[d] * s } else { h[d] };
        h[d] = if update { h[d] + vtr[d] * dt } else { h[d] };
    }

    // The spring-dashpot-slider (`slider`).
    let mut fs = [
        -k_tangential * h[0] - damp_tangential * vtr[0],
        -k_tangential * h[1] - damp_tangential * vtr[1],
        -k_tangential * h[2] - damp_tangential * vtr[2],
    ];
    let magnitude = (fs[0] * fs[0] + fs[1] * fs[1] + fs[2] * fs[2]).sqrt();
    let capped = magnitude > fscrit;
    // `|h| != 0` exactly when `h . h != 0` (a square root is zero only at
    // zero, and NaN either way).
    let loaded = h[0] * h[0] + h[1] * h[1] + h[2] * h[2] != 0.0;
    for d in 0..3 {
        let slid = -1.0 / k_tangential * (fscrit * fs[d] / magnitude + damp_tangential * vtr[d]);
        let scaled = fs[d] * (fscrit / magnitude);
        h[d] = if capped && loaded { slid } else { h[d] };
        fs[d] = if capped {
            if loaded {
                scaled
            } else {
                0.0
            }
        } else {
            fs[d]
        };
    }

    let tor = [
        n[1] * fs[2] - n[2] * fs[1],
        n[2] * fs[0] - n[0] * fs[2],
        n[0] * fs[1] - n[1] * fs[0],
    ];
    LaneForce {
        force: [
            n[0] * fntot + fs[0],
            n[1] * fntot + fs[1],
            n[2] * fntot + fs[2],
        ],
        torque_i: tor.map(|t| -arm_i * t),
        torque_j: tor.map(|t| -arm_j * t),
        normal_force: fncrit,
    }
}

#[cfg(test)]
mod tests {
    use super::super::granular::{
        corrected_granular_contact, ContactHistory, GranularMaterial, NormalDamping, Sphere,
        Twisting,
    };
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// A touching pair with random speeds, spins, sizes, closure
    /// corrections and tangential history: some histories zero, some out
    /// of the tangent plane, some large enough to slide.
    fn random_contact(rng: &mut ChaCha8Rng) -> ([f64; 3], Sphere, Sphere, [f64; 2], [f64; 3]) {
        fn vector(rng: &mut ChaCha8Rng, scale: f64) -> [f64; 3] {
            std::array::from_fn(|_| scale * rng.gen_range(-1.0..1.0))
        }
        let direction = vector(rng, 1.0);
        let (v_i, v_j) = (vector(rng, 0.5), vector(rng, 0.5));
        let (w_i, w_j) = (vector(rng, 2.0), vector(rng, 2.0));
        let length = direction.iter().map(|c| c * c).sum::<f64>().sqrt();
        let si = Sphere {
            v: v_i,
            omega: w_i,
            radius: rng.gen_range(0.4..1.0),
            mass: rng.gen_range(0.5..2.0),
        };
        let sj = Sphere {
            v: v_j,
            omega: w_j,
            radius: rng.gen_range(0.4..1.0),
            mass: rng.gen_range(0.5..2.0),
        };
        let moved = if rng.gen_bool(0.5) {
            [0.0; 2]
        } else {
            [rng.gen_range(-0.02..0.02), rng.gen_range(-0.02..0.02)]
        };
        // Touching: the corrected surfaces overlap.
        let r = (si.radius + moved[0] + sj.radius + moved[1]) * rng.gen_range(0.9..0.999);
        let del = direction.map(|c| r * c / length);
        let history = match rng.gen_range(0..3) {
            0 => [0.0; 3],
            1 => vector(rng, 1e-3),
            _ => vector(rng, 1.0),
        };
        (del, si, sj, moved, history)
    }

    #[test]
    fn blocks_give_the_one_contact_kernels_results_bit_for_bit() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let materials = [
            GranularMaterial {
                youngs_modulus: 30.0,
                poisson_ratio: 0.25,
                restitution: 0.5,
                damping: NormalDamping::Tsuji,
                tangential_damping: 1.0,
                sliding_friction: 0.3,
                rolling: None,
                twisting: Twisting::None,
            },
            GranularMaterial {
                youngs_modulus: 5.0,
                poisson_ratio: 0.5,
                restitution: 0.95,
                damping: NormalDamping::CoeffRestitution,
                tangential_damping: 0.8,
                sliding_friction: 0.03,
                rolling: None,
                twisting: Twisting::None,
            },
        ];
        let (mut slid, mut stuck) = (0, 0);
        for material in &materials {
            let coeffs = GranularCoeffs::of(material);
            for isa in [Isa::Portable, Isa::Avx2] {
                for update in [true, false] {
                    for _ in 0..200 {
                        let contacts: Vec<_> = (0..CONTACT_LANES)
                            .map(|_| random_contact(&mut rng))
                            .collect();
                        let mut block = ContactBlock::default();
                        for (l, (del, si, sj, moved, history)) in contacts.iter().enumerate() {
                            for d in 0..3 {
                                block.del[d][l] = del[d];
                                block.v[0][d][l] = si.v[d];
                                block.v[1][d][l] = sj.v[d];
                                block.omega[0][d][l] = si.omega[d];
                                block.omega[1][d][l] = sj.omega[d];
                                block.tangential[d][l] = history[d];
                            }
                            block.radius[0][l] = si.radius;
                            block.radius[1][l] = sj.radius;
                            block.mass[0][l] = si.mass;
                            block.mass[1][l] = sj.mass;
                            block.moved[0][l] = moved[0];
                            block.moved[1][l] = moved[1];
                        }
                        let out = hertz_mindlin_block(isa, &coeffs, &mut block, 0.01, update);
                        for (l, (del, si, sj, moved, history)) in contacts.iter().enumerate() {
                            let mut h = ContactHistory {
                                tangential: *history,
                                ..ContactHistory::default()
                            };
                            let expected = corrected_granular_contact(
                                &coeffs, del, si, sj, *moved, &mut h, 0.01, update,
                            );
                            let lane = |v: &[Lanes; 3]| -> [u64; 3] {
                                std::array::from_fn(|d| v[d][l].to_bits())
                            };
                            let bits = |v: &[f64; 3]| -> [u64; 3] { v.map(f64::to_bits) };
                            let case = format!("{isa:?} update {update} lane {l}");
                            assert_eq!(lane(&out.force), bits(&expected.force), "{case}");
                            assert_eq!(lane(&out.torque[0]), bits(&expected.torque_i), "{case}");
                            assert_eq!(lane(&out.torque[1]), bits(&expected.torque_j), "{case}");
                            assert_eq!(lane(&block.tangential), bits(&h.tangential), "{case}");
                            assert_eq!(out.normal_force[l].to_bits(), h.normal_force.to_bits());
                            // Sliding when the tangential force is at the
                            // Coulomb cap.
                            let r = del.iter().map(|c| c * c).sum::<f64>().sqrt();
                            let f = expected.force;
                            let along = f.iter().zip(del).map(|(f, d)| f * d / r).sum::<f64>();
                            let tangential = f
                                .iter()
                                .zip(del)
                                .map(|(f, d)| (f - along * d / r).powi(2))
                                .sum::<f64>()
                                .sqrt();
                            let cap = material.sliding_friction * h.normal_force;
                            if tangential > 0.999 * cap {
                                slid += 1;
                            } else {
                                stuck += 1;
                            }
                        }
                    }
                }
            }
        }
        assert!(
            slid > 100 && stuck > 100,
            "{slid} contacts sliding, {stuck} sticking"
        );
    }

    #[test]
    fn wall_blocks_give_the_one_contact_kernels_results_bit_for_bit() {
        use super::super::granular::{granular_wall_contact, WallPlane};
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let coeffs = GranularCoeffs::of(&GranularMaterial {
            youngs_modulus: 30.0,
            poisson_ratio: 0.3,
            restitution: 0.6,
            damping: NormalDamping::Tsuji,
            tangential_damping: 1.0,
            sliding_friction: 0.2,
            rolling: None,
            twisting: Twisting::None,
        });
        let mut capped = 0;
        for isa in [Isa::Portable, Isa::Avx2] {
            for (axis, sign) in [(0, 1.0), (2, -1.0), (1, 1.0)] {
                let plane = WallPlane {
                    axis,
                    sign,
                    position: 0.3,
                    velocity: -0.05,
                };
                for update in [true, false] {
                    for _ in 0..100 {
                        let spheres: Vec<_> = (0..CONTACT_LANES)
                            .map(|_| random_contact(&mut rng))
                            .collect();
                        let mut block = WallBlock::default();
                        let mut touches = Vec::new();
                        for (l, (_, s, _, moved, history)) in spheres.iter().enumerate() {
                            let distance = (s.radius + moved[0]) * rng.gen_range(0.9..0.999);
                            let touch = plane.touch(distance, moved[0]);
                            block.distance[l] = distance;
                            block.correction[l] = moved[0];
                            block.radius[l] = s.radius;
                            block.mass[l] = s.mass;
                            for d in 0..3 {
                                block.v[d][l] = s.v[d];
                                block.omega[d][l] = s.omega[d];
                                block.tangential[d][l] = history[d];
                            }
                            touches.push(touch);
                        }
                        let (normal, velocity) = (touches[0].normal, touches[0].velocity);
                        let out = hertz_mindlin_wall_block(
                            isa, &coeffs, &normal, &velocity, &mut block, 0.01, update,
                        );
                        for (l, ((_, s, _, _, history), touch)) in
                            spheres.iter().zip(&touches).enumerate()
                        {
                            let mut h = ContactHistory {
                                tangential: *history,
                                ..ContactHistory::default()
                            };
                            let expected =
                                granular_wall_contact(&coeffs, touch, s, &mut h, 0.01, update);
                            let lane = |v: &[Lanes; 3]| -> [u64; 3] {
                                std::array::from_fn(|d| v[d][l].to_bits())
                            };
                            let bits = |v: &[f64; 3]| -> [u64; 3] { v.map(f64::to_bits) };
                            let case = format!("{isa:?} axis {axis} update {update} lane {l}");
                            assert_eq!(lane(&out.force), bits(&expected.force), "{case}");
                            assert_eq!(lane(&out.torque), bits(&expected.torque_i), "{case}");
                            assert_eq!(lane(&block.tangential), bits(&h.tangential), "{case}");
                            assert_eq!(out.normal_force[l].to_bits(), h.normal_force.to_bits());
                            let f = expected.force;
                            let tangential = (0..3)
                                .filter(|&d| d != axis)
                                .map(|d| f[d] * f[d])
                                .sum::<f64>()
                                .sqrt();
                            capped += usize::from(tangential > 0.999 * 0.2 * h.normal_force);
                        }
                    }
                }
            }
        }
        assert!(capped > 50, "{capped} sliding wall contacts");
    }

    #[test]
    #[should_panic(expected = "the lanes do not cover these coefficients")]
    fn blocks_refuse_rolling_resistance() {
        let coeffs = GranularCoeffs::of(&GranularMaterial {
            youngs_modulus: 1.0,
            poisson_ratio: 0.3,
            restitution: 0.5,
            damping: NormalDamping::Tsuji,
            tangential_damping: 1.0,
            sliding_friction: 0.3,
            rolling: None,
            twisting: Twisting::Marshall,
        });
        hertz_mindlin_block(
            Isa::Portable,
            &coeffs,
            &mut ContactBlock::default(),
            0.1,
            true,
        );
    }
}
