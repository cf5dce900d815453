//! The zero-net-multibody variant's kernels against the formula of
//! docs/model.md computed another way, conservation of momentum, its
//! virial, and ownership with ghost atoms.

mod common;

use approx::assert_relative_eq;
use bpm::kernels::*;
use common::*;

/// Sums over a particle's ~15 bonds of forces of order 0.1, in another
/// order than the kernels': a few ulp of the largest force, below 1e-14 of
/// it; a wrong factor or sign in the correction is of the order of the
/// force itself.
const REORDERED_SUMS: f64 = 1e-13;

/// Net force: N forces rounded N times, relative to `N max|F|` (as in
/// tests/kernels.rs).
const NET_FORCE: f64 = 1e-14;

/// A displaced random network with a compressed-and-sheared look: bonds
/// of every sign of strain, particles unevenly surrounded.
fn network() -> (Vec<[f64; 3]>, Vec<BondEntry>, Vec<f64>) {
    let (x0, bonds, r0) = random_network(150, 3.8, 1.5, 41);
    let x = x0
        .iter()
        .zip(random_rows(x0.len(), 0.06, 42))
        .map(|(p, d)| [p[0] + d[0], p[1] + d[1], p[2] + d[2]])
        .collect();
    (x, bonds, r0)
}

/// Current and reference volumes of every atom.
fn volumes(x: &[[f64; 3]], bonds: &[BondEntry], r0: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let n = x.len();
    let all = Ownership::all(n);
    let (mut vol, mut vol0) = (vec![0.0; n], vec![0.0; n]);
    accumulate_volumes(&Unwrapped, x, bonds, all, &mut vol);
    accumulate_reference_volumes(bonds, r0, all, &mut vol0);
    (vol, vol0)
}

/// The multibody term alone: no spring, no damping.
fn multibody_only(a: f64) -> [BondCoeffs; 1] {
    [BondCoeffs {
        k: 0.0,
        a,
        gamma: 0.0,
    }]
}

/// The multibody sums of every atom, all owned.
fn complete_sums(x: &[[f64; 3]], bonds: &[BondEntry], r0: &[f64], a: f64) -> Vec<MultibodySum> {
    let (vol, vol0) = volumes(x, bonds, r0);
    let mb = MultibodyInputs {
        x,
        bonds,
        r0,
        coeffs: &multibody_only(a),
        volumes: (&vol, &vol0),
    };
    let mut sums = vec![[0.0; 4]; x.len()];
    accumulate_multibody_sums(&Unwrapped, &mb, Ownership::all(x.len()), &mut sums);
    sums
}

/// Plain multibody forces (`k = 0`, no damping) and the variant's
/// correction, each per atom, with the correction's tally.
fn multibody_and_correction(
    x: &[[f64; 3]],
    bonds: &[BondEntry],
    r0: &[f64],
    a: f64,
    own: Ownership,
    ghost_sums_from_owners: bool,
) -> (Vec<[f64; 3]>, Vec<[f64; 3]>, Tally) {
    let n = x.len();
    let all = Ownership::all(n);
    let (vol, vol0) = volumes(x, bonds, r0);
    let coeffs = multibody_only(a);
    let inputs = BondInputs {
        x,
        v: None,
        bonds,
        r0,
        coeffs: &coeffs,
        volumes: Some((&vol, &vol0)),
        tally: false,
    };
    let mut plain = vec![[0.0; 3]; n];
    bond_forces(&Unwrapped, &inputs, all, &mut plain);
    let mut sums = vec![[0.0; 4]; n];
    let mb = MultibodyInputs {
        x,
        bonds,
        r0,
        coeffs: &coeffs,
        volumes: (&vol, &vol0),
    };
    accumulate_multibody_sums(&Unwrapped, &mb, own, &mut sums);
    if ghost_sums_from_owners {
        // What LAMMPS's forward communication does: ghosts get the sums of
        // the atoms they image, here computed with every atom owned.
        let full = complete_sums(x, bonds, r0, a);
        sums[own.n_owned..].copy_from_slice(&full[own.n_owned..]);
    }
    let mut correction = vec![[0.0; 3]; n];
    let tally = balance_multibody(&Unwrapped, x, bonds, &sums, own, &mut correction, true);
    (plain, correction, tally)
}

#[test]
fn each_particle_keeps_half_its_own_multibody_force_plus_half_its_neighbours_means() {
    let (x, bonds, r0) = network();
    let n = x.len();
    let (plain, correction, _) =
        multibody_and_correction(&x, &bonds, &r0, -0.8, Ownership::all(n), false);
    // From the plain forces alone: M_i is the plain multibody force on i,
    // N_i its bond count; the variant's force is M_i/2 + sum_j M_j/(2 N_j).
    let mut count = vec![0.0; n];
    let mut neighbours = vec![Vec::new(); n];
    for b in &bonds {
        let (i, j) = (b.i as usize, b.j as usize);
        count[i] += 1.0;
        count[j] += 1.0;
        neighbours[i].push(j);
        neighbours[j].push(i);
    }
    let scale = max_abs(&plain);
    assert!(scale > 1e-2, "the network must have multibody forces");
    let mut largest_change = 0.0f64;
    for i in 0..n {
        for d in 0..3 {
            let expect = 0.5 * plain[i][d]
                + neighbours[i]
                    .iter()
                    .map(|&j| 0.5 * plain[j][d] / count[j])
                    .sum::<f64>();
            let got = plain[i][d] + correction[i][d];
            assert!(
                (got - expect).abs() <= REORDERED_SUMS * scale,
                "atom {i}, component {d}: {got} against {expect}"
            );
            largest_change = largest_change.max(correction[i][d].abs());
        }
    }
    assert!(largest_change > 0.1 * scale, "the correction must matter");
}

#[test]
fn the_correction_conserves_momentum_and_its_virial_is_the_sum_of_x_times_f() {
    let (x, bonds, r0) = network();
    let n = x.len();
    let (_, correction, tally) =
        multibody_and_correction(&x, &bonds, &r0, 1.5, Ownership::all(n), false);
    let scale = max_abs(&correction) * n as f64;
    let mut net = [0.0; 3];
    // Without periodic images, sum_bonds r_ij (x) c_ij = sum_i x_i (x) F_i.
    let mut virial = [0.0; 6];
    for (p, c) in x.iter().zip(&correction) {
        for d in 0..3 {
            net[d] += c[d];
        }
        virial[0] += p[0] * c[0];
        virial[1] += p[1] * c[1];
        virial[2] += p[2] * c[2];
        virial[3] += p[0] * c[1];
        virial[4] += p[0] * c[2];
        virial[5] += p[1] * c[2];
    }
    assert!(
        net.iter().all(|c| c.abs() < NET_FORCE * scale),
        "net force {net:?}"
    );
    // The lever arms are up to 3.8 d, the sums in another order.
    let lever = 3.8 * scale;
    for (k, (got, expect)) in tally.virial.iter().zip(&virial).enumerate() {
        assert!(
            (got - expect).abs() < NET_FORCE * lever,
            "virial {k}: {got} against {expect}"
        );
    }
    assert!(tally.virial.iter().any(|v| v.abs() > 1e-3), "{tally:?}");
    assert_eq!(tally.energy, 0.0);
    // The correction is not central: its virial is not symmetric.
    let yx: f64 = x.iter().zip(&correction).map(|(p, c)| p[1] * c[0]).sum();
    assert!((yx - virial[3]).abs() > 1e-6, "xy {} yx {yx}", virial[3]);
}

#[test]
fn newton_off_with_communicated_ghost_sums_gives_owners_the_same_correction() {
    let (x, bonds, r0) = network();
    let n = x.len();
    let (_, full, tfull) =
        multibody_and_correction(&x, &bonds, &r0, -0.6, Ownership::all(n), false);
    let owned = n / 2;
    let own = Ownership {
        n_owned: owned,
        newton: false,
    };
    let (_, part, tpart) = multibody_and_correction(&x, &bonds, &r0, -0.6, own, true);
    let sums = complete_sums(&x, &bonds, &r0, -0.6);
    for i in 0..n {
        let expect = if i < owned { full[i] } else { [0.0; 3] };
        assert_eq!(part[i], expect, "atom {i}");
    }
    // The tally: each bond's correction virial weighted 1, 1/2 or 0 by how
    // many of its atoms are owned, the correction taken from the full run
    // (the force it puts on an owned atom).
    let mut expect = [0.0; 6];
    for b in &bonds {
        let (i, j) = (b.i as usize, b.j as usize);
        let weight = 0.5 * ((i < owned) as u8 + (j < owned) as u8) as f64;
        if weight == 0.0 {
            continue;
        }
        // This bond's correction alone, from the complete sums.
        let mut single = vec![[0.0; 3]; n];
        balance_multibody(
            &Unwrapped,
            &x,
            std::slice::from_ref(b),
            &sums,
            Ownership::all(n),
            &mut single,
            false,
        );
        let c = single[i];
        let del = [x[i][0] - x[j][0], x[i][1] - x[j][1], x[i][2] - x[j][2]];
        let terms = [
            del[0] * c[0],
            del[1] * c[1],
            del[2] * c[2],
            del[0] * c[1],
            del[0] * c[2],
            del[1] * c[2],
        ];
        for (e, t) in expect.iter_mut().zip(terms) {
            *e += weight * t;
        }
    }
    let scale = tfull.virial.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for (k, (got, want)) in tpart.virial.iter().zip(&expect).enumerate() {
        assert!(
            (got - want).abs() < REORDERED_SUMS * scale.max(1.0),
            "virial {k}: {got} against {want}"
        );
    }
    let (_, stale, _) = multibody_and_correction(&x, &bonds, &r0, -0.6, own, false);
    assert_ne!(stale[..owned], full[..owned], "ghost sums must matter");
    assert_relative_eq!(tpart.energy, 0.0);
}
