//! The kernels against hand-computed values, analytic cases, finite
//! differences and conservation laws.

mod common;

use approx::assert_relative_eq;
use bpm::kernels::*;
use common::*;

// Tolerances of these analytic and finite-difference tests, local (they
// compare the kernels with mathematics, not two engines) and each with the
// reason for its value. Measured figures: this file's cases (the worst over
// each test's loop).

/// Hand values of order 0.1 to 1 from a few operations: each rounding is at
/// most half an ulp of 1 (1.1e-16), so a handful stays below 1e-15, while a
/// wrong coefficient, sign or factor misses by 1e-2 or more.
const HAND: f64 = 1e-15;

/// The multibody triangle by hand: `powf(1/3)` for the kernel's cube root
/// (both within 2 ulp) and the bond sums in another order, forces of order
/// 0.1 to 1: a few ulp, below 1e-14; the multibody part alone is above
/// 1e-3 (asserted in the test).
const HAND_MULTIBODY: f64 = 1e-14;

/// Uniform dilation: `a (D - r / r0)` is zero analytically; numerically `D`
/// (a cube root of summed cubed lengths) and `r / r0` are each rounded, so
/// per atom a few ulp of `a` over its ~16 bonds remain: measured 1.2e-14 of
/// the largest force (990 bonds); 1e-12 of it is 90 times that and five
/// decades below the multibody force a lost cancellation would leave.
const DILATION_CANCELS: f64 = 1e-12;

/// Central differences with h = 1e-6: truncation (h^2 times the third
/// derivative) ~ 1e-12; the energy difference loses eps E / h (E = 46 for
/// the spring network: 1e-8); measured 1.4e-8, relative to 1 + |F|. A wrong
/// force factor misses by |F|.
const SPRING_GRADIENT: f64 = 1e-7;

/// As [`SPRING_GRADIENT`] with the contact energy E = 195 (a_P = 50):
/// eps E / h = 4e-8, measured 1.5e-8.
const PAIR_GRADIENT: f64 = 1e-6;

/// Net force: a sum of N forces each at most max|F|, rounded N times: below
/// N eps max|F| = 2.2e-16 of `N max|F|` (measured 7e-18); the torque adds
/// lever arms up to 4 d (measured 1.7e-17). A force applied to one atom of
/// a bond only leaves max|F|, i.e. 1/N = 5e-3 of the scale.
const NET_FORCE: f64 = 1e-14;
/// See [`NET_FORCE`].
const NET_TORQUE: f64 = 1e-13;

/// Newton-off energy against the same sum by hand over ~940 bonds in
/// another order: relative N eps = 2e-13 at most (measured 0); half-counting
/// a shared bond wrongly changes it by percents.
const SUM_ORDER: f64 = 1e-12;

/// `cube_root`'s documented accuracy (src/kernels/bond.rs): within 2 ulp of
/// `f64::cbrt`.
const CUBE_ROOT_ULP: f64 = 2.0 * f64::EPSILON;

const SPRING: BondCoeffs = BondCoeffs {
    k: 2.0,
    a: 0.0,
    gamma: 0.0,
};

fn forces(
    x: &[[f64; 3]],
    v: Option<&[[f64; 3]]>,
    bonds: &[BondEntry],
    r0: &[f64],
    c: BondCoeffs,
    own: Ownership,
) -> (Vec<[f64; 3]>, Tally) {
    let n = x.len();
    let mut vol = vec![0.0; n];
    let mut vol0 = vec![0.0; n];
    let all = Ownership::all(n);
    accumulate_volumes(&Unwrapped, x, bonds, all, &mut vol);
    accumulate_reference_volumes(bonds, r0, all, &mut vol0);
    let coeffs = [c];
    let inputs = BondInputs {
        x,
        v,
        bonds,
        r0,
        coeffs: &coeffs,
        volumes: (c.a != 0.0).then_some((&vol[..], &vol0[..])),
        tally: true,
    };
    let mut f = vec![[0.0; 3]; n];
    let t = bond_forces(&Unwrapped, &inputs, own, &mut f).tally;
    (f, t)
}

/// Pair forces of `rows` (atom, LAMMPS-style neighbour indices) with one
/// coefficient set, no damping.
fn pair_on(
    x: &[[f64; 3]],
    c: PairCoeffs,
    special: [f64; 4],
    rows: &[(usize, Vec<i32>)],
) -> (Vec<[f64; 3]>, Tally) {
    let coeffs = [c];
    let inputs = PairInputs {
        x,
        v: None,
        types: None,
        ntypes: 1,
        coeffs: &coeffs,
        special,
        tally: true,
        damping_taper: false,
    };
    let mut f = vec![[0.0; 3]; x.len()];
    let t = pair_forces(
        &Unwrapped,
        &inputs,
        rows.iter().map(|(i, js)| (*i, &js[..])),
        Ownership::all(x.len()),
        &mut f,
    )
    .tally;
    (f, t)
}

fn one_bond() -> Vec<BondEntry> {
    vec![BondEntry { i: 0, j: 1, ty: 1 }]
}

#[test]
fn stretched_spring_pulls_the_atoms_together_with_k_times_stretch() {
    let x = [[0.0, 0.0, 0.0], [1.2, 0.0, 0.0]];
    let (f, t) = forces(&x, None, &one_bond(), &[1.0], SPRING, Ownership::all(2));
    // F = k (r0 - r) = -0.4 (attractive): atom 0 is pulled towards +x.
    assert_relative_eq!(f[0][0], 0.4, epsilon = HAND);
    assert_relative_eq!(f[1][0], -0.4, epsilon = HAND);
    assert_relative_eq!(t.energy, 0.5 * 2.0 * 0.2 * 0.2, epsilon = HAND);
    // Tension gives a negative virial: W_xx = r_x F_x = (-1.2)(0.4).
    assert_relative_eq!(t.virial[0], -0.48, epsilon = HAND);
    assert_eq!(&t.virial[1..], &[0.0; 5]);
}

#[test]
fn damping_resists_approach_along_the_bond_only() {
    let x = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]];
    // Atom 0 approaches atom 1 at 0.1 and slides sideways at 0.3.
    let v = [[0.1, 0.3, 0.0], [0.0, 0.0, 0.0]];
    let c = BondCoeffs {
        k: 1.0,
        a: 0.0,
        gamma: 0.5,
    };
    let (f, _) = forces(&x, Some(&v), &one_bond(), &[1.0], c, Ownership::all(2));
    // n = (-1, 0, 0), n.dv = -0.1, F = -gamma n.dv = +0.05 (repulsive).
    assert_relative_eq!(f[0][0], -0.05, epsilon = HAND);
    assert_eq!(f[0][1], 0.0);
    assert_relative_eq!(f[1][0], 0.05, epsilon = HAND);
}

#[test]
fn multibody_force_matches_a_hand_computed_triangle() {
    // A chain 0-1-2 plus bond 0-2; compress bond 0-1 only.
    let x0 = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.1, 0.0]];
    let bonds = vec![
        BondEntry { i: 0, j: 1, ty: 1 },
        BondEntry { i: 1, j: 2, ty: 1 },
        BondEntry { i: 0, j: 2, ty: 1 },
    ];
    let r0: Vec<f64> = bonds
        .iter()
        .map(|b| dist(&x0[b.i as usize], &x0[b.j as usize]))
        .collect();
    let x = [[0.0, 0.0, 0.0], [0.9, 0.0, 0.0], [0.0, 1.1, 0.0]];
    let c = BondCoeffs {
        k: 1.0,
        a: 0.7,
        gamma: 0.0,
    };
    let (f, _) = forces(&x, None, &bonds, &r0, c, Ownership::all(3));
    // By hand: V_i = sum of cubed bond lengths at atom i.
    let r01 = 0.9f64;
    let r12 = (0.81f64 + 1.21).sqrt();
    let r02 = 1.1f64;
    let (v0, v1, v2) = (
        r01.powi(3) + r02.powi(3),
        r01.powi(3) + r12.powi(3),
        r12.powi(3) + r02.powi(3),
    );
    let (w0, w1, w2) = (
        r0[0].powi(3) + r0[2].powi(3),
        r0[0].powi(3) + r0[1].powi(3),
        r0[1].powi(3) + r0[2].powi(3),
    );
    let mag = |r: f64, r0: f64, va: f64, vb: f64, wa: f64, wb: f64| {
        c.k * (r0 - r) + c.a * (((va + vb) / (wa + wb)).powf(1.0 / 3.0) - r / r0)
    };
    let f01 = mag(r01, r0[0], v0, v1, w0, w1);
    let f12 = mag(r12, r0[1], v1, v2, w1, w2);
    let f02 = mag(r02, r0[2], v0, v2, w0, w2);
    // Force on atom 0 along +n of each of its bonds (n points from the partner to 0).
    let n01 = [-1.0, 0.0, 0.0];
    let n02 = [0.0, -1.0, 0.0];
    let expected0 = [
        f01 * n01[0] + f02 * n02[0],
        f01 * n01[1] + f02 * n02[1],
        0.0,
    ];
    let n12 = [(0.9 - 0.0) / r12, (0.0 - 1.1) / r12, 0.0];
    let expected1 = [
        -f01 * n01[0] + f12 * n12[0],
        -f01 * n01[1] + f12 * n12[1],
        0.0,
    ];
    for d in 0..3 {
        assert_relative_eq!(f[0][d], expected0[d], epsilon = HAND_MULTIBODY);
        assert_relative_eq!(f[1][d], expected1[d], epsilon = HAND_MULTIBODY);
    }
    // The multibody part is non-zero here, so this pins its sign and factor.
    assert!((f02 - c.k * (r0[2] - r02)).abs() > 1e-3);
}

#[test]
fn uniform_dilation_cancels_the_multibody_term() {
    let (x0, bonds, r0) = random_network(120, 4.0, 1.5, 3);
    for scale in [0.97, 1.02] {
        let x: Vec<[f64; 3]> = x0.iter().map(|p| p.map(|c| c * scale)).collect();
        let with = BondCoeffs {
            k: 1.0,
            a: 1.3,
            gamma: 0.0,
        };
        let without = BondCoeffs { a: 0.0, ..with };
        let (fa, _) = forces(&x, None, &bonds, &r0, with, Ownership::all(x.len()));
        let (f0, _) = forces(&x, None, &bonds, &r0, without, Ownership::all(x.len()));
        let scale_of_forces = max_abs(&f0);
        assert!(scale_of_forces > 1e-3, "the dilation must load the network");
        for (a, b) in fa.iter().zip(&f0) {
            for d in 0..3 {
                assert!(
                    (a[d] - b[d]).abs() < DILATION_CANCELS * scale_of_forces,
                    "{a:?} vs {b:?}"
                );
            }
        }
    }
}

#[test]
fn positive_a_b_stiffens_shear_and_negative_softens_it() {
    // Paper 1, Fig. 1: under simple shear the multibody term raises the
    // shear stress for a_B > 0 and lowers it for a_B < 0.
    let (x0, bonds, r0) = random_network(300, 5.0, 1.5, 11);
    let gamma = 1e-3;
    let x: Vec<[f64; 3]> = x0
        .iter()
        .map(|p| [p[0] + gamma * p[1], p[1], p[2]])
        .collect();
    let shear_virial = |a: f64| {
        let c = BondCoeffs {
            k: 1.0,
            a,
            gamma: 0.0,
        };
        forces(&x, None, &bonds, &r0, c, Ownership::all(x.len()))
            .1
            .virial[3]
    };
    let (soft, plain, stiff) = (shear_virial(-0.5), shear_virial(0.0), shear_virial(1.0));
    // Positive shear strain gives positive shear stress, i.e. negative W_xy.
    assert!(plain < 0.0, "plain spring network resists shear: {plain}");
    assert!(
        stiff < plain,
        "a_B > 0 must raise shear stress: {stiff} vs {plain}"
    );
    assert!(
        soft > plain && soft < 0.0,
        "a_B < 0 must lower it: {soft} vs {plain}"
    );
}

#[test]
fn spring_force_is_minus_the_gradient_of_its_energy() {
    let (x0, bonds, _) = random_network(60, 3.0, 1.5, 5);
    let r0: Vec<f64> = (0..bonds.len())
        .map(|k| 0.8 + 0.01 * (k % 17) as f64)
        .collect();
    let c = BondCoeffs {
        k: 1.7,
        a: 0.0,
        gamma: 0.0,
    };
    let n = x0.len();
    let (f, _) = forces(&x0, None, &bonds, &r0, c, Ownership::all(n));
    let energy = |x: &[[f64; 3]]| forces(x, None, &bonds, &r0, c, Ownership::all(n)).1.energy;
    let h = 1e-6;
    for i in (0..n).step_by(7) {
        for d in 0..3 {
            let mut xp = x0.clone();
            let mut xm = x0.clone();
            xp[i][d] += h;
            xm[i][d] -= h;
            let fd = -(energy(&xp) - energy(&xm)) / (2.0 * h);
            assert!(
                (fd - f[i][d]).abs() < SPRING_GRADIENT * (1.0 + f[i][d].abs()),
                "atom {i} dim {d}: {fd} vs {}",
                f[i][d]
            );
        }
    }
}

#[test]
fn pair_force_is_minus_the_gradient_of_its_energy() {
    let (x0, _, _) = random_network(80, 3.0, 0.0, 9);
    let c = PairCoeffs {
        k: 1.0,
        d: 1.0,
        a: 50.0,
        gamma: 0.0,
    };
    let n = x0.len();
    let rows: Vec<(usize, Vec<i32>)> = (0..n)
        .map(|i| (i, ((i + 1) as i32..n as i32).collect()))
        .collect();
    let compute = |x: &[[f64; 3]]| pair_on(x, c, [1.0; 4], &rows);
    let (f, t) = compute(&x0);
    assert!(t.energy > 0.0, "the random cloud must have overlaps");
    let h = 1e-6;
    for i in (0..n).step_by(5) {
        for d in 0..3 {
            let mut xp = x0.clone();
            let mut xm = x0.clone();
            xp[i][d] += h;
            xm[i][d] -= h;
            let fd = -(compute(&xp).1.energy - compute(&xm).1.energy) / (2.0 * h);
            assert!(
                (fd - f[i][d]).abs() < PAIR_GRADIENT * (1.0 + f[i][d].abs()),
                "atom {i} dim {d}: {fd} vs {}",
                f[i][d]
            );
        }
    }
}

#[test]
fn pair_force_has_the_cubic_term_and_stops_at_d() {
    let c = PairCoeffs {
        k: 1.0,
        d: 1.0,
        a: 50.0,
        gamma: 0.0,
    };
    assert_relative_eq!(
        pair_force_magnitude(0.9, 0.0, &c),
        0.1 + 50.0 * 0.001,
        epsilon = HAND
    );
    let x = [[0.0, 0.0, 0.0], [1.0 + 1e-12, 0.0, 0.0]];
    let (f, _) = pair_on(&x, c, [1.0; 4], &[(0, vec![1])]);
    assert_eq!(f, vec![[0.0; 3]; 2]);
}

#[test]
fn special_bits_select_the_weight_and_zero_weight_skips() {
    let c = PairCoeffs {
        k: 1.0,
        d: 1.0,
        a: 0.0,
        gamma: 0.0,
    };
    let x = [[0.0, 0.0, 0.0], [0.5, 0.0, 0.0], [0.0, 0.5, 0.0]];
    // Atom 1 listed as a 1-2 special (weight 0), atom 2 as 1-3 (weight 0.25).
    let (f, _) = pair_on(
        &x,
        c,
        [1.0, 0.0, 0.25, 1.0],
        &[(0, vec![1 | (1 << 30), 2 | (2 << 30)])],
    );
    assert_eq!(f[1], [0.0; 3]);
    assert_relative_eq!(f[2][1], 0.25 * 0.5, epsilon = HAND);
}

#[test]
fn net_force_and_torque_vanish_for_any_network() {
    let (x0, bonds, r0) = random_network(200, 4.0, 1.5, 21);
    let x: Vec<[f64; 3]> = x0
        .iter()
        .zip(random_rows(x0.len(), 0.05, 22))
        .map(|(p, d)| [p[0] + d[0], p[1] + d[1], p[2] + d[2]])
        .collect();
    let v = random_rows(x.len(), 0.3, 23);
    let c = BondCoeffs {
        k: 1.0,
        a: -0.6,
        gamma: 1.0,
    };
    let (f, _) = forces(&x, Some(&v), &bonds, &r0, c, Ownership::all(x.len()));
    let mut net = [0.0; 3];
    let mut torque = [0.0; 3];
    for (p, fi) in x.iter().zip(&f) {
        for d in 0..3 {
            net[d] += fi[d];
        }
        torque[0] += p[1] * fi[2] - p[2] * fi[1];
        torque[1] += p[2] * fi[0] - p[0] * fi[2];
        torque[2] += p[0] * fi[1] - p[1] * fi[0];
    }
    let scale = max_abs(&f) * x.len() as f64;
    assert!(max_abs(&f) > 1e-2);
    assert!(
        net.iter().all(|c| c.abs() < NET_FORCE * scale),
        "net force {net:?}"
    );
    assert!(
        torque.iter().all(|c| c.abs() < NET_TORQUE * scale),
        "net torque {torque:?}"
    );
}

#[test]
fn newton_off_gives_owners_the_same_forces_and_half_of_shared_tallies() {
    let (x0, bonds, r0) = random_network(100, 3.5, 1.5, 31);
    let x: Vec<[f64; 3]> = x0.iter().map(|p| p.map(|c| c * 1.01)).collect();
    let c = BondCoeffs {
        k: 1.0,
        a: 0.5,
        gamma: 0.0,
    };
    let n = x.len();
    let (full, tfull) = forces(&x, None, &bonds, &r0, c, Ownership::all(n));
    let owned = n / 2;
    let own = Ownership {
        n_owned: owned,
        newton: false,
    };
    let (part, tpart) = forces(&x, None, &bonds, &r0, c, own);
    for i in 0..n {
        let expect = if i < owned { full[i] } else { [0.0; 3] };
        assert_eq!(part[i], expect, "atom {i}");
    }
    // Each bond's energy counts 1, 1/2 or 0 by how many of its atoms are owned.
    let frac: f64 = bonds
        .iter()
        .zip(&r0)
        .map(|(b, &r0)| {
            let r = dist(&x[b.i as usize], &x[b.j as usize]);
            let w = 0.5 * (((b.i as usize) < owned) as u8 + ((b.j as usize) < owned) as u8) as f64;
            w * 0.5 * (r - r0) * (r - r0)
        })
        .sum();
    assert_relative_eq!(tpart.energy, frac, max_relative = SUM_ORDER);
    assert!(tpart.energy < tfull.energy);
}

#[test]
fn cube_root_is_within_two_ulp_of_the_library() {
    let mut q = 1e-200;
    while q < 1e200 {
        for m in [1.0, 1.37, 2.9, 0.51] {
            let v = q * m;
            let ours = cube_root(v);
            let lib = v.cbrt();
            assert!(
                (ours - lib).abs() <= CUBE_ROOT_ULP * lib,
                "{v}: {ours} vs {lib}"
            );
        }
        q *= 7.3;
    }
    // The fast paths near 1 (|q - 1| <= 1/4) and both sides of their edges.
    for k in 0..=200_000 {
        let v = 0.7 + 0.6 * k as f64 / 200_000.0;
        let (ours, lib) = (cube_root(v), v.cbrt());
        assert!(
            (ours - lib).abs() <= CUBE_ROOT_ULP * lib,
            "{v}: {ours} vs {lib}"
        );
    }
    // The division-free path (|q - 1| <= 1/32), densely.
    for k in 0..=200_000 {
        let v = 1.0 - 1.0 / 32.0 + (1.0 / 16.0) * k as f64 / 200_000.0;
        let (ours, lib) = (cube_root(v), v.cbrt());
        assert!(
            (ours - lib).abs() <= CUBE_ROOT_ULP * lib,
            "{v}: {ours} vs {lib}"
        );
    }
    for v in [
        0.75,
        0.75 - 1e-16,
        1.25,
        1.25 + 1e-15,
        1.0,
        1.0 + f64::EPSILON,
        1.0 - 1.0 / 32.0,
        1.0 - 1.0 / 32.0 - 1e-16,
        1.0 + 1.0 / 32.0,
        1.0 + 1.0 / 32.0 + 2e-16,
    ] {
        assert!((cube_root(v) - v.cbrt()).abs() <= CUBE_ROOT_ULP, "{v}");
    }
    assert!(cube_root(-8.0) == -2.0 && cube_root(0.0) == 0.0);
}

/// How many bonds have a volume ratio outside the cube root's series
/// range (`|q - 1| > 1/32`), asserting that some do and most do not, so a
/// test covers both paths of the cube root.
fn some_far_volume_ratios(bonds: &[BondEntry], vol: &[f64], vol0: &[f64]) -> usize {
    let far = bonds
        .iter()
        .filter(|b| {
            let (i, j) = (b.i as usize, b.j as usize);
            ((vol[i] + vol[j]) / (vol0[i] + vol0[j]) - 1.0).abs() > 1.0 / 32.0
        })
        .count();
    assert!(
        far > 0 && far < bonds.len() / 2,
        "{far} of {} volume ratios outside the series range: want some, not most",
        bonds.len()
    );
    far
}

/// The bond kernel works on blocks of bonds; checked bond by bond against
/// the force law written out directly (`bond_force_magnitude`,
/// `dilation`), on a network whose bond count is not a multiple of the
/// block, with two bond types, damping, and strains large enough that some
/// volume ratios leave the cube root's series range. Every instruction
/// set gives the same volumes, forces and tallies bit for bit.
#[test]
fn blocked_bond_kernel_matches_the_force_law_bond_by_bond_on_every_instruction_set() {
    let (x0, mut bonds, r0) = random_network(300, 5.0, 1.5, 41);
    for (k, b) in bonds.iter_mut().enumerate() {
        b.ty = 1 + (k % 2) as i32;
    }
    assert!(
        bonds.len() % 8 != 0 && bonds.len() > 100,
        "{} bonds",
        bonds.len()
    );
    let x: Vec<[f64; 3]> = x0
        .iter()
        .zip(random_rows(x0.len(), 0.03, 42))
        .map(|(p, d)| [p[0] + d[0], p[1] + d[1], p[2] + d[2]])
        .collect();
    let v = random_rows(x.len(), 0.3, 43);
    let n = x.len();
    let all = Ownership::all(n);
    let (mut vol, mut vol0) = (vec![0.0; n], vec![0.0; n]);
    accumulate_volumes(&Unwrapped, &x, &bonds, all, &mut vol);
    accumulate_reference_volumes(&bonds, &r0, all, &mut vol0);
    let far = some_far_volume_ratios(&bonds, &vol, &vol0);
    let coeffs = [
        BondCoeffs {
            k: 1.0,
            a: -0.6,
            gamma: 1.0,
        },
        BondCoeffs {
            k: 1.7,
            a: 2.5,
            gamma: 0.3,
        },
    ];
    let inputs = BondInputs {
        x: &x,
        v: Some(&v),
        bonds: &bonds,
        r0: &r0,
        coeffs: &coeffs,
        volumes: Some((&vol, &vol0)),
        tally: true,
    };
    let mut expected = vec![[0.0; 3]; n];
    for (b, &r0) in bonds.iter().zip(&r0) {
        let (i, j) = (b.i as usize, b.j as usize);
        let c = &coeffs[(b.ty - 1) as usize];
        let del = [0, 1, 2].map(|d| x[i][d] - x[j][d]);
        let r = dist(&x[i], &x[j]);
        let dv = [0, 1, 2].map(|d| v[i][d] - v[j][d]);
        let n_dot_dv = (del[0] * dv[0] + del[1] * dv[1] + del[2] * dv[2]) / r;
        let d = dilation(vol[i], vol[j], vol0[i], vol0[j]);
        let fmag = bond_force_magnitude(r, r0, d, n_dot_dv, c);
        for k in 0..3 {
            expected[i][k] += fmag * del[k] / r;
            expected[j][k] -= fmag * del[k] / r;
        }
    }
    let scale = max_abs(&expected);
    let mut results = Vec::new();
    for isa in [Isa::Portable, Isa::Avx2] {
        if !isa.available() {
            eprintln!("{isa:?} not available here: skipped");
            continue;
        }
        let mut vol_isa = vec![0.0; n];
        accumulate_volumes_on(isa, &Unwrapped, &x, &bonds, all, &mut vol_isa);
        assert_eq!(vol_isa, vol, "{isa:?} volumes");
        let mut f = vec![[0.0; 3]; n];
        let tally = bond_forces_on(isa, &Unwrapped, &inputs, all, &mut f).tally;
        let worst = f
            .iter()
            .zip(&expected)
            .flat_map(|(a, b)| (0..3).map(move |k| (a[k] - b[k]).abs()))
            .fold(0.0f64, f64::max);
        eprintln!(
            "{isa:?}: {far} far bonds, worst deviation {:e} of {scale:e}",
            worst / scale
        );
        assert!(
            worst <= 1e-13 * scale,
            "{isa:?}: {worst:e} against {scale:e}"
        );
        results.push((f, tally));
    }
    for pair in results.windows(2) {
        assert_eq!(
            pair[0].0, pair[1].0,
            "forces differ between instruction sets"
        );
        assert_eq!(
            pair[0].1, pair[1].1,
            "tallies differ between instruction sets"
        );
    }
}

/// A box, positions, bonds, reference lengths and velocities.
type Network = (
    bpm::engine::SimBox,
    Vec<[f64; 3]>,
    Vec<BondEntry>,
    Vec<f64>,
    Vec<[f64; 3]>,
);

/// A periodic, tilted box whose minimum image differs from the plain
/// difference for bonds across its faces: `(box, bonded positions, bonds,
/// r0, velocities)`.
fn periodic_network(seed: u64) -> Network {
    let l = 6.0;
    let simbox = bpm::engine::SimBox {
        lo: [0.0; 3],
        lengths: [l; 3],
        tilt: [0.9, -0.7, 0.4],
        periodic: [true; 3],
    };
    let (x0, _, _) = random_network(260, l, 0.0, seed);
    let sep = simbox.minimum_image();
    let mut bonds = Vec::new();
    let mut r0 = Vec::new();
    for i in 0..x0.len() {
        for j in i + 1..x0.len() {
            let r = sep.distance(&x0[i], &x0[j]);
            if r < 1.4 && r > 0.3 {
                bonds.push(BondEntry {
                    i: i as i32,
                    j: j as i32,
                    ty: 1,
                });
                r0.push(r);
            }
        }
    }
    let x: Vec<[f64; 3]> = x0
        .iter()
        .zip(random_rows(x0.len(), 0.04, seed + 1))
        .map(|(p, d)| [p[0] + d[0], p[1] + d[1], p[2] + d[2]])
        .collect();
    let v = random_rows(x.len(), 0.3, seed + 2);
    (simbox, x, bonds, r0, v)
}

/// Bonds as the native engine lays them out in rows: those whose plain
/// difference is the minimum image ("interior") first, the rest after,
/// each in bond order, built with the reference volumes `V0`.
struct EngineRows {
    rows: BondRows,
    interior: Vec<usize>,
    boundary: Vec<usize>,
    vol0: Vec<f64>,
}

fn engine_rows(sep: &MinimumImage, x: &[[f64; 3]], bonds: &[BondEntry], r0: &[f64]) -> EngineRows {
    let plain = |b: &BondEntry| {
        let (xi, xj) = (&x[b.i as usize], &x[b.j as usize]);
        sep.delta(xi, xj) == Unwrapped.delta(xi, xj)
    };
    let (interior, boundary): (Vec<usize>, Vec<usize>) =
        (0..bonds.len()).partition(|&b| plain(&bonds[b]));
    let mut vol0 = vec![0.0; x.len()];
    accumulate_reference_volumes(bonds, r0, Ownership::all(x.len()), &mut vol0);
    let order: Vec<usize> = interior.iter().chain(&boundary).copied().collect();
    let rows = BondRows::new(
        x.len(),
        order
            .iter()
            .map(|&b| (bonds[b].i as usize, bonds[b].j as usize, r0[b], b)),
        Some(&vol0),
    )
    .unwrap();
    EngineRows {
        rows,
        interior,
        boundary,
        vol0,
    }
}

/// The largest difference between two tallies' energy and virial
/// components, and the largest magnitude among `want`'s.
fn tally_deviation(got: &Tally, want: &Tally) -> (f64, f64) {
    let scale = want
        .virial
        .iter()
        .fold(want.energy.abs(), |m, v| m.max(v.abs()));
    let deviation = got
        .virial
        .iter()
        .zip(&want.virial)
        .map(|(a, b)| (a - b).abs())
        .fold((got.energy - want.energy).abs(), f64::max);
    (deviation, scale)
}

/// The two-step bond pass (rows, then each particle's sum) against the
/// scatter kernel on the same bonds, split as the native engine splits
/// them: bonds whose plain difference is the minimum image first, the rest
/// after. Forces and volumes are equal bit for bit, for every combination
/// of terms and on every instruction set, since each particle receives its
/// rows in the order the scatter adds them. Energy and virial, summed in
/// four lanes by the rows, agree to round-off, and bit for bit between
/// instruction sets.
#[test]
fn bond_rows_give_the_scatter_kernels_forces_bit_for_bit() {
    let (simbox, x, bonds, r0, v) = periodic_network(51);
    let sep = simbox.minimum_image();
    let n = x.len();
    let EngineRows {
        rows,
        interior,
        boundary,
        vol0,
    } = engine_rows(&sep, &x, &bonds, &r0);
    assert!(
        boundary.len() > 20 && interior.len() % 4 != 0,
        "{} interior, {} boundary bonds",
        interior.len(),
        boundary.len()
    );
    let pick = |set: &[usize]| -> (Vec<BondEntry>, Vec<f64>) {
        (
            set.iter().map(|&b| bonds[b]).collect(),
            set.iter().map(|&b| r0[b]).collect(),
        )
    };
    let (bonds_in, r0_in) = pick(&interior);
    let (bonds_out, r0_out) = pick(&boundary);
    let order: Vec<usize> = interior.iter().chain(&boundary).copied().collect();
    let ni = interior.len();
    let all = Ownership::all(n);

    // Volumes: the scatter's, and the rows' (whose lengths the force rows
    // then reuse).
    let mut vol = vec![0.0; n];
    accumulate_volumes(&Unwrapped, &x, &bonds_in, all, &mut vol);
    accumulate_volumes(&sep, &x, &bonds_out, all, &mut vol);
    let mut lengths = vec![[0.0; 2]; rows.len()];
    for isa in [Isa::Portable, Isa::Avx2]
        .into_iter()
        .filter(|i| i.available())
    {
        let mut out = vec![[f64::NAN; 2]; rows.len()];
        let (a, b) = out.split_at_mut(ni);
        row_volumes_on(isa, &Unwrapped, &rows, 0..ni, &x, a);
        row_volumes_on(isa, &sep, &rows, ni..rows.len(), &x, b);
        let mut from_rows = vec![f64::NAN; n];
        gather_volumes(&rows, 0..n, &out, &mut from_rows);
        assert_eq!(from_rows, vol, "{isa:?} volumes");
        for (k, &bond) in order.iter().enumerate() {
            let (i, j) = (bonds[bond].i as usize, bonds[bond].j as usize);
            let r = sep.distance(&x[i], &x[j]);
            assert_eq!(out[k][0], r, "{isa:?}: length of row {k}");
        }
        lengths = out;
    }

    some_far_volume_ratios(&bonds, &vol, &vol0);
    let coeffs = BondCoeffs {
        k: 1.3,
        a: -0.55,
        gamma: 0.8,
    };
    for (multibody, damped, tally) in [
        (true, true, true),
        (true, false, false),
        (false, true, true),
        (false, false, true),
        (false, false, false),
    ] {
        let volumes = multibody.then_some((&vol[..], &vol0[..]));
        let velocities = damped.then_some(&v[..]);
        let interior_inputs = BondInputs {
            x: &x,
            v: velocities,
            bonds: &bonds_in,
            r0: &r0_in,
            coeffs: std::slice::from_ref(&coeffs),
            volumes,
            tally,
        };
        let boundary_inputs = BondInputs {
            bonds: &bonds_out,
            r0: &r0_out,
            ..interior_inputs
        };
        let mut expected = vec![[0.0; 3]; n];
        let expected_pass = bond_forces(&Unwrapped, &interior_inputs, all, &mut expected)
            .merged(&bond_forces(&sep, &boundary_inputs, all, &mut expected));
        let inputs = RowInputs {
            x: &x,
            v: velocities,
            coeffs,
            multibody: multibody.then_some((&vol[..], &lengths[..])),
            tally,
        };
        let mut tallies = Vec::new();
        for isa in [Isa::Portable, Isa::Avx2]
            .into_iter()
            .filter(|i| i.available())
        {
            let mut force_rows = vec![[f64::NAN; 4]; rows.len()];
            let (a, b) = force_rows.split_at_mut(ni);
            let pass = row_forces_on(isa, &Unwrapped, &rows, 0..ni, &inputs, a)
                .merged(&row_forces_on(isa, &sep, &rows, ni..rows.len(), &inputs, b));
            let mut f = vec![[0.0; 3]; n];
            // In two parts, as two threads would.
            let (f1, f2) = f.split_at_mut(n / 3);
            gather_forces_on(isa, &rows, 0..n / 3, &force_rows, f1);
            gather_forces_on(isa, &rows, n / 3..n, &force_rows, f2);
            let case = format!("{isa:?}, multibody {multibody}, damped {damped}, tally {tally}");
            assert_eq!(f, expected, "{case}: forces");
            // The rows sum energy and virial in four lanes, the scatter
            // bond by bond: the same terms, added in another order.
            let (got, want) = (pass.tally, expected_pass.tally);
            let (deviation, scale) = tally_deviation(&got, &want);
            assert!(
                deviation <= 1e-13 * scale,
                "{case}: tally {got:?} against {want:?}"
            );
            assert!(!tally || scale > 0.0, "{case}: nothing tallied");
            tallies.push(got);
            assert!(
                pass.fault.is_none() && expected_pass.fault.is_none(),
                "{case}"
            );
        }
        assert!(
            tallies.windows(2).all(|w| w[0] == w[1]),
            "every instruction set sums the same lanes: {tallies:?}"
        );
    }
}

/// Twelve particles a unit apart along x.
fn chain_positions() -> Vec<[f64; 3]> {
    (0..12).map(|k| [k as f64, 0.0, 0.0]).collect()
}

/// The rows of [`chain_positions`]'s eleven neighbour bonds, bond `b`
/// joining `b` and `b + 1` with reference length `r0[b]`, numbered
/// `100 + b`.
fn chain_rows(r0: &[f64]) -> BondRows {
    BondRows::new(12, (0..11).map(|b| (b, b + 1, r0[b], 100 + b)), None).unwrap()
}

/// A bond squeezed below the collapse limit in the middle of a block of
/// rows is reported with its own bond number and atoms, on every
/// instruction set; a row list with a bad atom is refused.
#[test]
fn bond_rows_report_a_collapsed_bond_and_refuse_bad_atoms() {
    let x = chain_positions();
    let mut r0: Vec<f64> = vec![1.0; 11];
    r0[6] = 10.0;
    // Exactly at the collapse limit (0.2 x 5 = 1): outside the lanes'
    // open range, but no fault; the report must go on to bond 106. (With
    // the yielding rule below it yields too: 2 yielded.)
    r0[2] = 5.0;
    let rows = chain_rows(&r0);
    let inputs = unit_springs(&x);
    for isa in [Isa::Portable, Isa::Avx2]
        .into_iter()
        .filter(|i| i.available())
    {
        let mut out = vec![[0.0; 4]; 11];
        let fault = row_forces_on(isa, &Unwrapped, &rows, 0..11, &inputs, &mut out)
            .fault
            .expect("the squeezed bond is a fault");
        assert_eq!(
            (fault.kind, fault.i, fault.j, fault.bond),
            (FaultKind::BondCollapsed, 6, 7, 106),
            "{isa:?}"
        );
        // Bonds that break and yield: the squeezed bond (strain -0.9)
        // yields in the pass that reports it, beside a bond that breaks
        // (strain 1) in the same block of four, and the report is the same.
        let rule = BondFailure {
            plastic_strain: Some(0.05),
            ..BondFailure::breaking(0.95)
        };
        let mut breaking_rows = r0.clone();
        breaking_rows[5] = 0.5;
        let rows = chain_rows(&breaking_rows);
        let mut plastic = banded(&rows, &rule, vec![0.0; 11]);
        let pass = plastic_pass(isa, &rows, &inputs, &rule, &mut plastic, &mut out);
        let fault = pass.pass.fault.expect("the squeezed bond is a fault");
        assert_eq!(
            (fault.kind, fault.i, fault.j, fault.bond, fault.reference),
            (FaultKind::BondCollapsed, 6, 7, 106, 10.0),
            "{isa:?}, bonds that break and yield"
        );
        assert_eq!((pass.broken, pass.yielded), (1, 2), "{isa:?}");
        assert!(row_broke(&out[5]) && out[6][3] == 0.0, "{isa:?}: {out:?}");
        assert_eq!(plastic.strains()[6], -0.85, "{isa:?}");
    }
    assert!(matches!(
        BondRows::new(3, [(0, 3, 1.0, 0)].into_iter(), None),
        Err(BondRowsError::BadAtom { .. })
    ));
    assert!(matches!(
        BondRows::new(3, [(1, 1, 1.0, 0)].into_iter(), None),
        Err(BondRowsError::BadAtom { .. })
    ));
    assert!(matches!(
        BondRows::new(3, [(0, 1, 1.0, 0)].into_iter(), Some(&[1.0, 1.0])),
        Err(BondRowsError::ReferenceVolumes {
            given: 2,
            particles: 3
        })
    ));
}

/// The failing pass's vector build tests one calm condition (every strain
/// within half the reference length, every force finite) for breaking and
/// faults alike; a block that is not calm must still get both right. A
/// bond stretched to twice its length that neither breaks nor faults sits
/// before one torn beyond the limit (both in blocks of four, not the
/// scalar tail), and a calm block with a velocity that
/// is not a number is a fault: on every instruction set.
#[test]
fn failing_rows_find_faults_past_the_calm_strain_and_in_non_finite_forces() {
    let x = chain_positions();
    let mut r0: Vec<f64> = vec![1.0; 11];
    r0[2] = 0.5;
    r0[6] = 0.3;
    let (torn, calm) = (chain_rows(&r0), chain_rows(&[1.0; 11]));
    let mut v = vec![[0.0; 3]; 12];
    v[7][1] = f64::NAN;
    let inputs = |v| RowInputs {
        x: &x,
        v,
        coeffs: BondCoeffs {
            k: 1.0,
            a: 0.0,
            gamma: 0.5,
        },
        multibody: None,
        tally: true,
    };
    let yielding = BondFailure {
        breaks: false,
        smooth: false,
        plastic_strain: Some(0.05),
        ..BondFailure::breaking(0.5)
    };
    for isa in [Isa::Portable, Isa::Avx2]
        .into_iter()
        .filter(|i| i.available())
    {
        let mut out = vec![[0.0; 4]; 11];
        let mut plastic = banded(&torn, &yielding, vec![0.0; 11]);
        let pass = plastic_pass(isa, &torn, &inputs(None), &yielding, &mut plastic, &mut out);
        let fault = pass.pass.fault.expect("the torn bond is a fault");
        assert_eq!(
            (fault.kind, fault.bond),
            (FaultKind::BondOverstretched, 106),
            "{isa:?}"
        );
        // Both stretched bonds yield; the one at strain 1 is whole.
        assert_eq!((pass.broken, pass.yielded), (0, 2), "{isa:?}");
        assert_eq!(plastic.strains()[2], 0.95, "{isa:?}");
        let mut out = vec![[0.0; 4]; 11];
        let pass = failing_row_forces_on(
            isa,
            &Unwrapped,
            &calm,
            0..11,
            &inputs(Some(&v)),
            &BondFailure::breaking(0.5),
            None,
            &mut out,
        );
        let fault = pass
            .pass
            .fault
            .expect("a force that is not a number is a fault");
        assert_eq!(
            (fault.kind, fault.bond),
            (FaultKind::NonFinite, 106),
            "{isa:?}"
        );
        assert_eq!(pass.broken, 0, "{isa:?}");
    }
}

/// The yield test compares the strain with the rounded band edges
/// `e_p +- eps_p`, as upstream's plastic style does, on every instruction
/// set: a bond whose `e - e_p` rounds above `eps_p` but whose `e` does not
/// exceed the rounded `e_p + eps_p` keeps its plastic strain; one a length
/// ulp longer yields, in the same block.
#[test]
fn rows_yield_past_the_rounded_band_edge_on_every_instruction_set() {
    // r0 = 1, so e = r - 1 exactly.
    let (at_edge, e_p, eps_p) = (1.1313187299795122_f64, 0.0813187299795122_f64, 0.05);
    let beyond = f64::from_bits(at_edge.to_bits() + 1);
    assert!(at_edge - 1.0 - e_p > eps_p && at_edge - 1.0 <= e_p + eps_p);
    assert!(beyond - 1.0 > e_p + eps_p);
    // Eight bonds, at the edge and beyond in turn, apart along y so that
    // each separation is exactly the bond's length along x: two whole
    // blocks of four.
    let length = |b: usize| if b % 2 == 0 { at_edge } else { beyond };
    let x: Vec<[f64; 3]> = (0..16)
        .map(|p| {
            let along = if p % 2 == 1 { length(p / 2) } else { 0.0 };
            [along, (p / 2) as f64 * 5.0, 0.0]
        })
        .collect();
    let rows = BondRows::new(16, (0..8).map(|b| (2 * b, 2 * b + 1, 1.0, b)), None).unwrap();
    let inputs = RowInputs {
        x: &x,
        v: None,
        coeffs: BondCoeffs {
            k: 3.0,
            a: 0.0,
            gamma: 0.0,
        },
        multibody: None,
        tally: false,
    };
    let rule = BondFailure {
        smooth: false,
        plastic_strain: Some(eps_p),
        ..BondFailure::breaking(0.5)
    };
    let mut rows_of = vec![];
    for isa in [Isa::Portable, Isa::Avx2]
        .into_iter()
        .filter(|i| i.available())
    {
        let mut out = vec![[0.0; 4]; 8];
        let mut plastic = banded(&rows, &rule, vec![e_p; 8]);
        let pass = plastic_pass(isa, &rows, &inputs, &rule, &mut plastic, &mut out);
        assert_eq!((pass.broken, pass.yielded), (0, 4), "{isa:?}");
        for (b, &strain) in plastic.strains().iter().enumerate() {
            let want = if b % 2 == 0 {
                e_p
            } else {
                beyond - 1.0 - eps_p
            };
            assert_eq!(strain, want, "{isa:?}, bond {b}");
        }
        rows_of.push(out);
    }
    for out in &rows_of[1..] {
        assert_eq!(row_bits(out), row_bits(&rows_of[0]));
    }
}

/// The bits of each force row (three force components and the fourth
/// value), to compare rows exactly, NaN markers included.
fn row_bits(rows: &[[f64; 4]]) -> Vec<[u64; 4]> {
    rows.iter().map(|r| r.map(f64::to_bits)).collect()
}

/// The row kernel's and the scatter kernel's cube roots on every
/// instruction set give the bits of the scalar `cube_root` whatever mix of
/// volume ratios a block holds: near 1 (the series alone), beyond 1/32
/// (series and one Halley step), beyond 1/4 (the scalar routine), in the
/// same block.
#[test]
fn row_kernel_cube_roots_match_the_scalar_routine_across_its_ranges() {
    let (x0, bonds, r0) = random_network(400, 5.0, 1.5, 51);
    // Untouched up to x = 2, then squeezed up to 13% (linear) at x = 5:
    // every range of the volume ratio, alone and mixed along the rows.
    let x: Vec<[f64; 3]> = x0
        .iter()
        .map(|p| {
            let s = 1.0 - 0.13 * ((p[0] - 2.0) / 3.0).max(0.0);
            [p[0] * s, p[1] * s, p[2] * s]
        })
        .collect();
    let n = x.len();
    let all = Ownership::all(n);
    let mut vol0 = vec![0.0; n];
    accumulate_reference_volumes(&bonds, &r0, all, &mut vol0);
    let rows = BondRows::new(
        n,
        bonds
            .iter()
            .zip(&r0)
            .enumerate()
            .map(|(k, (b, &r))| (b.i as usize, b.j as usize, r, k)),
        Some(&vol0),
    )
    .unwrap();
    let mut lengths = vec![[0.0; 2]; rows.len()];
    row_volumes_on(
        Isa::Portable,
        &Unwrapped,
        &rows,
        0..rows.len(),
        &x,
        &mut lengths,
    );
    let mut vol = vec![0.0; n];
    gather_volumes(&rows, 0..n, &lengths, &mut vol);
    // The range of each row's ratio, as the rows list them.
    let class: Vec<u8> = (0..rows.len())
        .map(|k| {
            let (i, j) = (bonds[k].i as usize, bonds[k].j as usize);
            let d = ((vol[i] + vol[j]) / (vol0[i] + vol0[j]) - 1.0).abs();
            u8::from(d > 1.0 / 32.0) + u8::from(d > 0.25)
        })
        .collect();
    for c in 0..3 {
        let count = class.iter().filter(|&&k| k == c).count();
        assert!(count >= 20, "{count} rows in range {c} of {}", rows.len());
    }
    let mixed = class
        .chunks_exact(4)
        .filter(|b| b.iter().any(|&k| k != b[0]))
        .count();
    assert!(mixed >= 20, "{mixed} blocks mix ranges");
    // Each of the vector kernel's three ways through a block of four is
    // taken: all near 1, some beyond 1/32 and none beyond 1/4, some
    // beyond 1/4.
    for (way, test) in [
        (
            "all near",
            &(|b: &[u8]| b.iter().all(|&k| k == 0)) as &dyn Fn(&[u8]) -> bool,
        ),
        ("stepped", &|b: &[u8]| b.contains(&1) && !b.contains(&2)),
        ("scalar", &|b: &[u8]| b.contains(&2)),
    ] {
        let blocks = class.chunks_exact(4).filter(|b| test(b)).count();
        assert!(blocks >= 5, "{blocks} blocks of four take the {way} way");
    }
    let inputs = RowInputs {
        x: &x,
        v: None,
        coeffs: BondCoeffs {
            k: 1.0,
            a: -0.7,
            gamma: 0.0,
        },
        multibody: Some((&vol[..], &lengths[..])),
        tally: false,
    };
    let forces = |isa: Isa| {
        let mut out = vec![[f64::NAN; 4]; rows.len()];
        let pass = row_forces_on(isa, &Unwrapped, &rows, 0..rows.len(), &inputs, &mut out);
        assert!(pass.fault.is_none(), "{isa:?}: {:?}", pass.fault);
        out
    };
    let portable = forces(Isa::Portable);
    // The portable rows are the force law itself, bond by bond.
    for (k, b) in bonds.iter().enumerate() {
        let (i, j) = (b.i as usize, b.j as usize);
        let r = dist(&x[i], &x[j]);
        let fmag = -(r - r0[k]) - 0.7 * (dilation(vol[i], vol[j], vol0[i], vol0[j]) - r / r0[k]);
        assert_relative_eq!(
            portable[k][0] * r / (x[i][0] - x[j][0]),
            fmag,
            max_relative = 1e-9
        );
    }
    if Isa::Avx2.available() {
        assert_eq!(forces(Isa::Avx2), portable);
    }
    // The scatter kernel (the plugin's) on every instruction set: the same
    // forces as the rows, bit for bit.
    let mut gathered = vec![[0.0; 3]; n];
    gather_forces_on(Isa::Portable, &rows, 0..n, &portable, &mut gathered);
    let coeffs = [inputs.coeffs];
    let scatter = BondInputs {
        x: &x,
        v: None,
        bonds: &bonds,
        r0: &r0,
        coeffs: &coeffs,
        volumes: Some((&vol[..], &vol0[..])),
        tally: false,
    };
    for isa in [Isa::Portable, Isa::Avx2]
        .into_iter()
        .filter(|i| i.available())
    {
        let mut f = vec![[0.0; 3]; n];
        let pass = bond_forces_on(isa, &Unwrapped, &scatter, all, &mut f);
        assert!(pass.fault.is_none(), "{isa:?}");
        assert_eq!(f, gathered, "{isa:?}: scatter kernel");
    }
}

/// The windowed bond pass (each part's interior rows computed into a ring
/// a block at a time and gathered as soon as a particle's rows are done)
/// against the full-size pass of [`bond_rows_give_the_scatter_kernels_forces_bit_for_bit`],
/// on the periodic network renumbered along x (partners close in the
/// numbering, as in a cell-sorted solid) so that small rings wrap many
/// times: forces equal bit for bit for every split into parts, block size
/// and instruction set; one part sums energy and virial bit for bit as the
/// full-size pass does, several to round-off. A ring too small for the
/// numbering's span is refused.
#[test]
fn windowed_bond_pass_gives_the_full_size_forces_bit_for_bit() {
    let (simbox, x0, bonds0, r0_0, v0) = periodic_network(52);
    let sep = simbox.minimum_image();
    let n = x0.len();
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| x0[a][0].total_cmp(&x0[b][0]));
    let mut new_index = vec![0; n];
    for (k, &p) in order.iter().enumerate() {
        new_index[p] = k;
    }
    let x: Vec<[f64; 3]> = order.iter().map(|&p| x0[p]).collect();
    let v: Vec<[f64; 3]> = order.iter().map(|&p| v0[p]).collect();
    let mut renumbered: Vec<(usize, usize, f64)> = bonds0
        .iter()
        .zip(&r0_0)
        .map(|(b, &r0)| {
            let (i, j) = (new_index[b.i as usize], new_index[b.j as usize]);
            (i.min(j), i.max(j), r0)
        })
        .collect();
    renumbered.sort_by_key(|b| (b.0, b.1));
    let bonds: Vec<BondEntry> = renumbered
        .iter()
        .map(|&(i, j, _)| BondEntry {
            i: i as i32,
            j: j as i32,
            ty: 1,
        })
        .collect();
    let r0: Vec<f64> = renumbered.iter().map(|b| b.2).collect();
    let EngineRows {
        rows,
        interior,
        boundary,
        ..
    } = engine_rows(&sep, &x, &bonds, &r0);
    let ni = interior.len();
    assert!(boundary.len() > 20, "{} boundary rows", boundary.len());
    let mut lengths = vec![[0.0; 2]; rows.len()];
    let (a, b) = lengths.split_at_mut(ni);
    row_volumes(&Unwrapped, &rows, 0..ni, &x, a);
    row_volumes(&sep, &rows, ni..rows.len(), &x, b);
    let mut vol = vec![0.0; n];
    gather_volumes(&rows, 0..n, &lengths, &mut vol);
    let coeffs = BondCoeffs {
        k: 1.3,
        a: -0.55,
        gamma: 0.8,
    };
    // Empty parts first, in the middle and last; parts of one particle.
    let splits: [&[usize]; 6] = [
        &[0, n],
        &[0, n / 3, n],
        &[0, 0, n / 2, n],
        &[0, 7, 90, 91, n],
        &[0, 100, 100, n],
        &[0, n - 1, n, n],
    ];
    for (multibody, damped, tally) in [
        (true, true, true),
        (false, true, false),
        (false, false, true),
    ] {
        let inputs = RowInputs {
            x: &x,
            v: damped.then_some(&v[..]),
            coeffs,
            multibody: multibody.then_some((&vol[..], &lengths[..])),
            tally,
        };
        for isa in [Isa::Portable, Isa::Avx2]
            .into_iter()
            .filter(|i| i.available())
        {
            let mut full_rows = vec![[f64::NAN; 4]; rows.len()];
            let (a, b) = full_rows.split_at_mut(ni);
            let interior_pass = row_forces_on(isa, &Unwrapped, &rows, 0..ni, &inputs, a);
            let boundary_pass = row_forces_on(isa, &sep, &rows, ni..rows.len(), &inputs, b);
            let full_pass = interior_pass.merged(&boundary_pass);
            let mut expected = vec![[0.0; 3]; n];
            gather_forces_on(isa, &rows, 0..n, &full_rows, &mut expected);
            for split in splits {
                let parts: Vec<_> = split.windows(2).map(|w| w[0]..w[1]).collect();
                for block in [4, 12, 64] {
                    let case = format!(
                        "{isa:?}, multibody {multibody}, damped {damped}, tally {tally}, \
                         parts {parts:?}, blocks of {block}"
                    );
                    let window = RowWindow::plan(&rows, ni, &parts, block, 1 << 20)
                        .unwrap_or_else(|| panic!("{case}: no window"));
                    assert!(
                        window.ring() < ni / 2,
                        "{case}: a ring of {} for {ni} rows does not wrap",
                        window.ring()
                    );
                    let refused = RowWindow::plan(&rows, ni, &parts, block, window.ring() / 2);
                    assert!(refused.is_none(), "{case}: a ring too small was planned");
                    let mut f = vec![[0.0; 3]; n];
                    let mut tally_sum = Tally::default();
                    for (c, part) in parts.iter().enumerate() {
                        let mut buffer = vec![[f64::NAN; 4]; window.buffer_len()];
                        let pass = window_forces_on(
                            isa,
                            &rows,
                            &window,
                            c,
                            &inputs,
                            &full_rows[ni..],
                            &mut buffer,
                            &mut f[part.clone()],
                        );
                        assert!(pass.fault.is_none(), "{case}");
                        tally_sum = tally_sum.merged(&pass.tally);
                    }
                    let differ = (0..n).find(|&p| f[p] != expected[p]);
                    assert!(
                        differ.is_none(),
                        "{case}: forces differ first at {differ:?}"
                    );
                    let total = tally_sum.merged(&boundary_pass.tally);
                    if parts.len() == 1 {
                        assert_eq!(total, full_pass.tally, "{case}: one part's sums");
                    } else {
                        let want = full_pass.tally;
                        let (deviation, scale) = tally_deviation(&total, &want);
                        assert!(
                            deviation <= 1e-13 * scale,
                            "{case}: {total:?} against {want:?}"
                        );
                    }
                    assert!(
                        !tally || full_pass.tally.energy > 0.0,
                        "{case}: nothing tallied"
                    );
                }
            }
        }
    }
}

/// The failing bond pass (breaking, smoothing, yielding): a rule that never
/// acts gives the elastic rows bit for bit, energy and virial included;
/// a rule that breaks and yields some rows gives the same rows, counts and
/// sums on every instruction set, each row what the per-bond kernel gives.
#[test]
fn failing_rows_match_the_elastic_rows_and_agree_between_instruction_sets() {
    let (simbox, x, bonds, r0, v) = periodic_network(52);
    let sep = simbox.minimum_image();
    let n = x.len();
    let EngineRows {
        rows,
        interior,
        vol0,
        ..
    } = engine_rows(&sep, &x, &bonds, &r0);
    let ni = interior.len();
    let mut lengths = vec![[0.0; 2]; rows.len()];
    let (a, b) = lengths.split_at_mut(ni);
    row_volumes(&Unwrapped, &rows, 0..ni, &x, a);
    row_volumes(&sep, &rows, ni..rows.len(), &x, b);
    let mut vol = vec![0.0; n];
    gather_volumes(&rows, 0..n, &lengths, &mut vol);
    let coeffs = BondCoeffs {
        k: 1.3,
        a: -0.55,
        gamma: 0.8,
    };
    let isas: Vec<Isa> = [Isa::Portable, Isa::Avx2]
        .into_iter()
        .filter(|i| i.available())
        .collect();
    // Plastic strains on entry, some nonzero, and every other block of
    // four all zero (bonds that never yielded).
    let entry: Vec<f64> = (0..rows.len())
        .map(|k| {
            if k / 4 % 2 == 0 {
                0.0
            } else {
                [0.0, 0.004, -0.003][k % 3]
            }
        })
        .collect();
    let never = BondFailure {
        smooth: false,
        ..BondFailure::breaking(50.0)
    };
    let acting = |normalize| BondFailure {
        plastic_strain: Some(0.01),
        normalize,
        ..BondFailure::breaking(0.035)
    };
    for (multibody, damped, tally) in [
        (true, true, true),
        (false, true, true),
        (false, false, false),
    ] {
        let inputs = RowInputs {
            x: &x,
            v: damped.then_some(&v[..]),
            coeffs,
            multibody: multibody.then_some((&vol[..], &lengths[..])),
            tally,
        };
        // The two sections through shared rows, as the engine's threads
        // take them.
        let run = |isa: Isa, rule: &BondFailure, start: &[f64]| {
            let mut out = vec![[f64::NAN; 4]; start.len()];
            let mut plastic = PlasticRows::new(&rows, start.to_vec());
            let yields = rule.plastic_strain.is_some();
            if yields {
                plastic.band_for(rule);
            }
            let shared = yields.then(|| plastic.shared());
            // SAFETY: the two sections do not overlap.
            let section =
                |r: std::ops::Range<usize>| shared.as_ref().map(|s| unsafe { s.section(r) });
            let (a, b) = out.split_at_mut(ni);
            let (pa, pb) = (section(0..ni), section(ni..rows.len()));
            let pass =
                failing_row_forces_on(isa, &Unwrapped, &rows, 0..ni, &inputs, rule, pa, a).merged(
                    &failing_row_forces_on(isa, &sep, &rows, ni..rows.len(), &inputs, rule, pb, b),
                );
            (out, plastic.strains().to_vec(), pass)
        };
        let case = format!("multibody {multibody}, damped {damped}, tally {tally}");
        for &isa in &isas {
            let mut elastic = vec![[0.0; 4]; rows.len()];
            let (a, b) = elastic.split_at_mut(ni);
            let want = row_forces_on(isa, &Unwrapped, &rows, 0..ni, &inputs, a)
                .merged(&row_forces_on(isa, &sep, &rows, ni..rows.len(), &inputs, b));
            let (got, _, pass) = run(isa, &never, &vec![0.0; rows.len()]);
            assert_eq!(
                got, elastic,
                "{isa:?}, {case}: rows of a rule that never acts"
            );
            assert_eq!(
                pass.pass, want,
                "{isa:?}, {case}: its energy, virial and faults"
            );
            assert_eq!((pass.broken, pass.yielded), (0, 0));
        }
        for normalize in [false, true] {
            let rule = acting(normalize);
            let results: Vec<_> = isas.iter().map(|&isa| run(isa, &rule, &entry)).collect();
            let (out, strains, pass) = &results[0];
            assert!(
                pass.broken > 10 && pass.yielded > 10 && pass.broken + pass.yielded < rows.len(),
                "{case}: {} broken, {} yielded of {}",
                pass.broken,
                pass.yielded,
                rows.len()
            );
            for (other, other_strains, other_pass) in &results[1..] {
                let first = row_bits(other)
                    .iter()
                    .zip(row_bits(out))
                    .position(|(a, b)| *a != b);
                assert_eq!(first, None, "{case}, normalize {normalize}: first row that differs between instruction sets");
                let bits = |s: &[f64]| s.iter().map(|e| e.to_bits()).collect::<Vec<_>>();
                assert_eq!(
                    bits(other_strains),
                    bits(strains),
                    "{case}, normalize {normalize}: plastic strains"
                );
                assert_eq!(
                    other_pass, pass,
                    "{case}, normalize {normalize}: counts and sums"
                );
            }
            // Each row is the per-bond kernel's force.
            for (k, row) in out.iter().enumerate() {
                let b = rows.bonds().nth(k).unwrap();
                let bond = &bonds[b];
                let (i, j) = (bond.i as usize, bond.j as usize);
                let del = sep.delta(&x[i], &x[j]);
                let r = lengths[k][0];
                let dv = [v[i][0] - v[j][0], v[i][1] - v[j][1], v[i][2] - v[j][2]];
                let damping = if damped {
                    coeffs.gamma * dot3(&del, &dv) / r
                } else {
                    0.0
                };
                let d = multibody.then(|| dilation(vol[i], vol[j], vol0[i], vol0[j]));
                let mut e_p = entry[k];
                match failing_bond_force(r, r0[b], &mut e_p, d, damping, &coeffs, &rule) {
                    None => assert!(row_broke(row), "row {k} should have broken"),
                    Some(f) => {
                        assert!(!row_broke(row) && row[3] == 0.0);
                        assert_eq!(strains[k], e_p, "row {k}: plastic strain");
                        for c in 0..3 {
                            assert_relative_eq!(
                                row[c],
                                del[c] * f / r,
                                max_relative = 1e-12,
                                epsilon = 1e-14
                            );
                        }
                    }
                }
            }
        }
    }
}

/// The vector build reads each row's band (the strains in which it
/// neither yields nor can break) from the plastic rows: bands drawn for a
/// wide yield strain are redrawn for a narrow one, so that bonds at a
/// strain between the two yield on every instruction set; rows banded for
/// another rule are refused.
#[test]
fn plastic_rows_are_banded_anew_for_another_rule() {
    let x = chain_positions();
    // Chain bonds of length 1 at r0 = 1 / 1.05: strain 0.05 (to rounding).
    let rows = chain_rows(&[1.0 / 1.05; 11]);
    let inputs = unit_springs(&x);
    let rule = |eps_p| BondFailure {
        smooth: false,
        plastic_strain: Some(eps_p),
        ..BondFailure::breaking(0.4)
    };
    let (wide, narrow) = (rule(0.2), rule(0.01));
    for isa in [Isa::Portable, Isa::Avx2]
        .into_iter()
        .filter(|i| i.available())
    {
        let mut out = vec![[0.0; 4]; 11];
        let mut plastic = banded(&rows, &wide, vec![0.0; 11]);
        let pass = |plastic: &mut PlasticRows, rule, out: &mut [[f64; 4]]| {
            plastic_pass(isa, &rows, &inputs, rule, plastic, out)
        };
        assert_eq!(pass(&mut plastic, &wide, &mut out).yielded, 0, "{isa:?}");
        let refused = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            pass(&mut plastic.clone(), &narrow, &mut out.clone())
        }));
        assert!(refused.is_err(), "{isa:?}: bands of another rule");
        plastic.band_for(&narrow);
        assert_eq!(pass(&mut plastic, &narrow, &mut out).yielded, 11, "{isa:?}");
        for &e_p in plastic.strains() {
            assert_relative_eq!(e_p, 0.04, max_relative = 1e-12);
        }
    }
}

/// A band is cut to the calm strain: bonds whose plastic strain lies
/// near the critical strain, pulled past it but within their yield band,
/// break on every instruction set.
#[test]
fn bands_are_cut_to_the_calm_strain() {
    let x: Vec<[f64; 3]> = (0..12).map(|k| [k as f64 * 1.062, 0.0, 0.0]).collect();
    let rows = chain_rows(&[1.0; 11]);
    let inputs = unit_springs(&x);
    let rule = BondFailure {
        smooth: false,
        plastic_strain: Some(0.01),
        ..BondFailure::breaking(0.06)
    };
    for isa in [Isa::Portable, Isa::Avx2]
        .into_iter()
        .filter(|i| i.available())
    {
        let mut out = vec![[0.0; 4]; 11];
        let mut plastic = banded(&rows, &rule, vec![0.055; 11]);
        let pass = plastic_pass(isa, &rows, &inputs, &rule, &mut plastic, &mut out);
        assert_eq!((pass.broken, pass.yielded), (11, 0), "{isa:?}");
        assert!(out.iter().all(row_broke), "{isa:?}");
    }
}

/// The bands follow the plastic strains from pass to pass: a chain
/// stretched, held, relaxed and compressed yields as the rule says bond by
/// bond, each pass from the strains the last one left, on every
/// instruction set, the rows split between two sections as two threads
/// take them (not at a block boundary).
#[test]
fn bands_follow_the_plastic_strains_over_passes() {
    let rows = chain_rows(&[1.0; 11]);
    let eps_p = 0.01;
    let rule = BondFailure {
        smooth: false,
        plastic_strain: Some(eps_p),
        ..BondFailure::breaking(0.5)
    };
    let scales = [1.08, 1.065, 1.005, 0.99, 1.03];
    let mut strains_of = vec![];
    for isa in [Isa::Portable, Isa::Avx2]
        .into_iter()
        .filter(|i| i.available())
    {
        let mut plastic = banded(&rows, &rule, vec![0.0; 11]);
        let mut want = [0.0; 11];
        for scale in scales {
            let x: Vec<[f64; 3]> = (0..12).map(|k| [k as f64 * scale, 0.0, 0.0]).collect();
            let inputs = unit_springs(&x);
            let mut out = vec![[0.0; 4]; 11];
            let (a, b) = out.split_at_mut(5);
            let shared = plastic.shared();
            // SAFETY: the two sections do not overlap.
            let (pa, pb) = unsafe { (shared.section(0..5), shared.section(5..11)) };
            let pass =
                failing_row_forces_on(isa, &Unwrapped, &rows, 0..5, &inputs, &rule, Some(pa), a)
                    .merged(&failing_row_forces_on(
                        isa,
                        &Unwrapped,
                        &rows,
                        5..11,
                        &inputs,
                        &rule,
                        Some(pb),
                        b,
                    ));
            let mut yielded = 0;
            for (b, e_p) in want.iter_mut().enumerate() {
                let e = (x[b + 1][0] - x[b][0]) - 1.0;
                let after = plastic_strain_after(e, *e_p, eps_p);
                yielded += usize::from(after != *e_p);
                *e_p = after;
            }
            assert_eq!(plastic.strains(), &want[..], "{isa:?}, scale {scale}");
            assert_eq!(
                (pass.broken, pass.yielded),
                (0, yielded),
                "{isa:?}, scale {scale}"
            );
            assert!(yielded > 0 || scale == 1.065, "{isa:?}, scale {scale}");
        }
        strains_of.push(plastic.strains().to_vec());
    }
    for strains in &strains_of[1..] {
        let bits = |s: &[f64]| s.iter().map(|e| e.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(strains), bits(&strains_of[0]));
    }
}

/// Springs of stiffness 1 alone (no multibody term, damping or tally)
/// between the particles at `x`.
fn unit_springs(x: &[[f64; 3]]) -> RowInputs<'_> {
    RowInputs {
        x,
        v: None,
        coeffs: BondCoeffs {
            k: 1.0,
            a: 0.0,
            gamma: 0.0,
        },
        multibody: None,
        tally: false,
    }
}

/// The failing pass on `isa` over all of `rows` (unwrapped) with a rule
/// that yields, its plastic strains in `plastic`.
fn plastic_pass(
    isa: Isa,
    rows: &BondRows,
    inputs: &RowInputs,
    rule: &BondFailure,
    plastic: &mut PlasticRows,
    out: &mut [[f64; 4]],
) -> FailurePass {
    let section = Some(plastic.section(0..rows.len()));
    failing_row_forces_on(
        isa,
        &Unwrapped,
        rows,
        0..rows.len(),
        inputs,
        rule,
        section,
        out,
    )
}

/// Plastic strains `e_p` of `rows`, banded for `rule`.
fn banded(rows: &BondRows, rule: &BondFailure, e_p: Vec<f64>) -> PlasticRows {
    let mut plastic = PlasticRows::new(rows, e_p);
    plastic.band_for(rule);
    plastic
}

fn dot3(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
