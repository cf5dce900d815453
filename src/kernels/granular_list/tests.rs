use super::*;
use crate::kernels::{corrected_granular_contact, granular_wall_contact, pair_contact_points};
use crate::kernels::{granular_contact, GranularMaterial, NormalDamping, SpringDashpotSlider};
use crate::kernels::{surface_corrections, ContactPoint, WallTouch};
use crate::kernels::{ContactHistory, WallPlane};
use crate::kernels::{MprSwitch, MprTest, Twisting};

fn material() -> GranularMaterial {
    GranularMaterial {
        youngs_modulus: 1e3,
        poisson_ratio: 0.3,
        restitution: 0.5,
        damping: NormalDamping::Tsuji,
        tangential_damping: 1.0,
        sliding_friction: 0.5,
        rolling: Some(SpringDashpotSlider {
            stiffness: 300.0,
            damping: 5.0,
            friction: 0.2,
        }),
        twisting: Twisting::Marshall,
    }
}

fn sphere(v: [f64; 3], omega: [f64; 3], radius: f64) -> Sphere {
    Sphere {
        v,
        omega,
        radius,
        mass: radius.powi(3),
    }
}

/// The mirrored memory is the same contact: seen from `j`, a step
/// gives the opposite force, the torques swapped, and a memory that is
/// the mirror of the one seen from `i`, for sticking and sliding
/// springs alike (rolling and twisting included).
#[test]
fn a_contact_seen_from_either_sphere_is_one_contact() {
    let c = GranularCoeffs::of(&material());
    let del = [0.83, -0.21, 0.34];
    let si = sphere([0.3, -0.1, 0.2], [0.7, 0.4, -1.1], 0.5);
    let sj = sphere([-0.2, 0.25, 0.05], [-0.3, 0.9, 0.6], 0.45);
    for scale in [1e-4, 1.0] {
        let mut hi = ContactHistory {
            tangential: [1e-3 * scale, 2e-3 * scale, -1e-3 * scale],
            rolling: [-4e-3 * scale, 1e-3 * scale, 2e-3 * scale],
            twist: 3e-2 * scale,
            normal_force: 0.0,
        };
        let mut hj = hi.mirrored();
        let mut tally = 0.0;
        for _ in 0..3 {
            let a = granular_contact(&c, &del, &si, &sj, &mut hi, 1e-3, true);
            let b = granular_contact(&c, &del.map(|v| -v), &sj, &si, &mut hj, 1e-3, true);
            for d in 0..3 {
                let tol = 1e-13 * (1.0 + a.force[d].abs());
                assert!((a.force[d] + b.force[d]).abs() <= tol, "{a:?} {b:?}");
                assert!(
                    (a.torque_i[d] - b.torque_j[d]).abs() <= 1e-13,
                    "{a:?} {b:?}"
                );
                assert!(
                    (a.torque_j[d] - b.torque_i[d]).abs() <= 1e-13,
                    "{a:?} {b:?}"
                );
            }
            let m = hi.mirrored();
            for (x, y) in m.to_values().iter().zip(hj.to_values()) {
                assert!((x - y).abs() <= 1e-13 * (1.0 + x.abs()), "{m:?} {hj:?}");
            }
            tally += a.force[0].abs();
        }
        assert!(tally > 0.0);
    }
}

/// A wall below atom 10 (x lo wall at z = 0), atom 20 pressing it
/// down: pass 1 gives atom 10 corrections from both of its contacts,
/// the wall's among them, as `surface_corrections` does; pass 2 gives
/// it the wall's force of `granular_wall_contact` with its correction
/// there, and reports the load on the wall.
#[test]
fn a_wall_is_a_contact_of_the_closure_in_both_passes() {
    let m = material();
    let coeffs = GranularCoeffs::of(&m);
    let closure = ListClosure {
        closure: Closure::Standard,
        half_space: HalfSpace::new(0.82, m.youngs_modulus, m.poisson_ratio),
        reach: 0.25,
    };
    let wall_material = GranularMaterial {
        youngs_modulus: 1e4,
        ..m
    };
    let wall = ListWall {
        number: 1,
        plane: WallPlane {
            axis: 2,
            sign: 1.0,
            position: 0.0,
            velocity: -0.01,
        },
        coeffs: GranularCoeffs::between(&m, &wall_material),
        keep_history: false,
    };
    let x = [[0.0, 0.0, 0.46], [0.02, 0.01, 1.41]];
    let v = [[0.01, 0.0, -0.02], [0.0, 0.01, -0.03]];
    let omega = [[0.1, -0.2, 0.05], [0.0; 3]];
    let (radius, mass, tag) = ([0.5; 2], [1.0; 2], [10, 20]);
    let atoms = ListAtoms {
        x: &x,
        v: &v,
        omega: &omega,
        radius: &radius,
        mass: &mass,
        tag: &tag,
        n_owned: 2,
    };
    let slots = 4;
    let (hist, corr) = (Layout::history(slots), Layout::corrections(slots));
    let mut list = GranularList::new(coeffs, Some(closure), slots);
    let mut history = vec![0.0; 2 * hist.stride()];
    let mut corrections = vec![0.0; 2 * corr.stride()];
    let rows = || [(1usize, &[0i32][..])].into_iter();
    list.set_walls(&[wall], &[true], &mut history, 2).unwrap();
    let step = |list: &mut GranularList, history: &mut Vec<f64>, corrections: &mut Vec<f64>| {
        list.corrections(&atoms, rows(), history, corrections, 0)
            .unwrap();
        let (mut f, mut t) = (vec![[0.0; 3]; 2], vec![[0.0; 3]; 2]);
        list.forces(
            &atoms,
            rows(),
            corrections,
            history,
            &mut f,
            &mut t,
            1e-3,
            true,
            false,
            0,
        )
        .unwrap();
        (f, t)
    };
    // No loads remembered: no corrections; the wall's contact is the
    // plain one.
    let before = hist.get(&history, 0, -1.0).is_none();
    let (f, t) = step(&mut list, &mut history, &mut corrections);
    assert!(before && corrections[0] == 0.0);
    let sphere0 = Sphere {
        v: v[0],
        omega: omega[0],
        radius: 0.5,
        mass: 1.0,
    };
    let touch = |correction| WallTouch {
        distance: 0.46,
        normal: [0.0, 0.0, 1.0],
        velocity: [0.0, 0.0, -0.01],
        correction,
    };
    let mut h = ContactHistory::default();
    let plain = granular_wall_contact(&wall.coeffs, &touch(0.0), &sphere0, &mut h, 1e-3, true);
    assert!(plain.force[2] > 0.0);
    assert_eq!(list.wall_forces(), &[plain.force[2]]);
    assert_eq!(hist.get(&history, 0, -1.0), Some(&h.to_values()[..]));
    assert!(t[0] != [0.0; 3] && f[1][2] > 0.0);
    // Second evaluation: atom 10's two loads correct each other.
    let wall_load = h.normal_force;
    let pair_load = hist.get(&history, 0, 20.0).unwrap()[7];
    let del = super::super::sub(&x[1], &x[0]);
    let r = super::super::dot(&del, &del).sqrt();
    let [_, from_pair] = pair_contact_points(&del, r, 0.5, 0.5, pair_load);
    let from_wall = ContactPoint::new([0.0, 0.0, -0.46], wall_load, 0.5);
    let mut expect = [0.0; 2];
    surface_corrections(
        &closure.half_space,
        &closure.closure,
        0.5,
        &[from_pair, from_wall],
        &mut expect,
    );
    assert!(expect.iter().all(|&d| d > 0.0), "{expect:?}");
    let (f2, _) = step(&mut list, &mut history, &mut corrections);
    assert_eq!(corr.get(&corrections, 0, 20.0).unwrap()[0], expect[0]);
    assert_eq!(corr.get(&corrections, 0, -1.0).unwrap()[0], expect[1]);
    let corrected = granular_wall_contact(
        &wall.coeffs,
        &touch(expect[1]),
        &sphere0,
        &mut h,
        1e-3,
        true,
    );
    assert_eq!(list.wall_forces(), &[corrected.force[2]]);
    assert!(corrected.force[2] > plain.force[2] && f2[0][2] > f[0][2]);
    // A pass after a rebuild keeps the wall's contact (a set-up pass:
    // nothing advances).
    let mut renewed = history.clone();
    let (mut f, mut t) = (vec![[0.0; 3]; 2], vec![[0.0; 3]; 2]);
    list.forces(
        &atoms,
        rows(),
        &corrections,
        &mut renewed,
        &mut f,
        &mut t,
        0.0,
        false,
        true,
        3,
    )
    .unwrap();
    assert_eq!(
        hist.get(&renewed, 0, -1.0),
        hist.get(&history, 0, -1.0),
        "{renewed:?}"
    );
    // A correction at the wall beyond the reach stops the pass.
    let mut far = corrections.clone();
    assert!(corr.put(&mut far, 0, -1.0, &[0.2]));
    let err = list
        .forces(
            &atoms,
            rows(),
            &far,
            &mut renewed,
            &mut f,
            &mut t,
            0.0,
            false,
            false,
            5,
        )
        .unwrap_err();
    assert_eq!(
        err,
        ListError::WallBeyondReach {
            atom: 10,
            wall: 1,
            ratio: 0.4,
            reach: 0.25,
            step: 5
        }
    );
    // An atom moved through the plane stops the pass, naming it.
    let mut through = x;
    through[0][2] = -0.01;
    let atoms = ListAtoms {
        x: &through,
        ..atoms
    };
    let (mut f, mut t) = (vec![[0.0; 3]; 2], vec![[0.0; 3]; 2]);
    let err = list
        .forces(
            &atoms,
            rows(),
            &corrections,
            &mut history,
            &mut f,
            &mut t,
            1e-3,
            true,
            false,
            7,
        )
        .unwrap_err();
    assert_eq!(
        err,
        ListError::ThroughWall {
            atom: 10,
            wall: 1,
            step: 7
        }
    );
}

/// A resting wall of [`material`] at z = 0, its atoms on side `sign`.
fn z_wall(number: i64, sign: f64, keep_history: bool) -> ListWall {
    ListWall {
        number,
        plane: WallPlane {
            axis: 2,
            sign,
            position: 0.0,
            velocity: 0.0,
        },
        coeffs: GranularCoeffs::of(&material()),
        keep_history,
    }
}

/// A wall defined anew restarts its springs and keeps its load if it
/// has the number, axis and side of a wall at the last evaluation;
/// otherwise its entries are forgotten. Walls sharing a number are
/// refused.
#[test]
fn a_wall_defined_anew_keeps_only_its_load() {
    let m = material();
    let wall = |number, sign| z_wall(number, sign, false);
    let slots = 2;
    let hist = Layout::history(slots);
    let loaded = ContactHistory {
        tangential: [1e-3, 2e-3, 0.0],
        rolling: [0.0, 1e-3, 0.0],
        twist: 0.1,
        normal_force: 4.0,
    };
    let mut list = GranularList::new(GranularCoeffs::of(&m), None, slots);
    let mut history = vec![0.0; hist.stride()];
    list.set_walls(
        &[wall(1, 1.0), wall(2, -1.0)],
        &[true, true],
        &mut history,
        1,
    )
    .unwrap();
    for key in [-1.0, -2.0] {
        assert!(hist.put(&mut history, 0, key, &loaded.to_values()));
    }
    // Not fresh: untouched.
    let kept = history.clone();
    list.set_walls(
        &[wall(1, 1.0), wall(2, -1.0)],
        &[false, false],
        &mut history,
        1,
    )
    .unwrap();
    assert_eq!(history, kept);
    // Wall 1 anew on the same side; wall 2 anew on the other side.
    list.set_walls(
        &[wall(1, 1.0), wall(2, 1.0)],
        &[true, true],
        &mut history,
        1,
    )
    .unwrap();
    let load = ContactHistory {
        normal_force: 4.0,
        ..ContactHistory::default()
    };
    assert_eq!(hist.get(&history, 0, -1.0), Some(&load.to_values()[..]));
    assert_eq!(hist.get(&history, 0, -2.0), None);
    let err = list
        .set_walls(
            &[wall(3, 1.0), wall(3, -1.0)],
            &[true, true],
            &mut history,
            1,
        )
        .unwrap_err();
    assert!(err.to_string().contains("share a number"), "{err}");
    assert!(list
        .set_walls(&[wall(0, 1.0)], &[true], &mut history, 1)
        .is_err());
}

/// A wall defined anew with `keep_history` keeps its whole entries, friction
/// springs too, when it has the number, axis and side of the wall it
/// replaces; on the other side its entries are forgotten all the same.
#[test]
fn a_wall_defined_anew_keeping_its_history_keeps_its_springs() {
    let m = material();
    let wall = z_wall;
    let hist = Layout::history(2);
    let loaded = ContactHistory {
        tangential: [1e-3, 2e-3, 0.0],
        rolling: [0.0, 1e-3, 0.0],
        twist: 0.1,
        normal_force: 4.0,
    };
    let mut list = GranularList::new(GranularCoeffs::of(&m), None, 2);
    let mut history = vec![0.0; hist.stride()];
    let first = [wall(1, 1.0, false), wall(2, -1.0, false)];
    list.set_walls(&first, &[true, true], &mut history, 1)
        .unwrap();
    for key in [-1.0, -2.0] {
        assert!(hist.put(&mut history, 0, key, &loaded.to_values()));
    }
    let anew = [wall(1, 1.0, true), wall(2, 1.0, true)];
    list.set_walls(&anew, &[true, true], &mut history, 1)
        .unwrap();
    assert_eq!(hist.get(&history, 0, -1.0), Some(&loaded.to_values()[..]));
    assert_eq!(hist.get(&history, 0, -2.0), None);
}

#[test]
fn a_row_stores_replaces_forgets_and_refuses_when_full() {
    let l = Layout::history(2);
    let mut data = vec![0.0; 2 * l.stride()];
    let v = |x: f64| [x; HISTORY_VALUES];
    assert!(l.put(&mut data, 1, 7.0, &v(1.0)));
    assert!(l.put(&mut data, 1, 9.0, &v(2.0)));
    assert!(l.put(&mut data, 1, 7.0, &v(3.0)));
    assert!(!l.put(&mut data, 1, 11.0, &v(4.0)));
    assert_eq!(l.get(&data, 1, 7.0), Some(&v(3.0)[..]));
    assert_eq!(l.get(&data, 0, 7.0), None);
    l.remove(&mut data, 1, 7.0);
    assert_eq!(l.get(&data, 1, 7.0), None);
    assert_eq!(l.get(&data, 1, 9.0), Some(&v(2.0)[..]));
    assert!(l.put(&mut data, 1, 11.0, &v(4.0)));
    l.remove(&mut data, 1, 5.0);
    assert_eq!(data[l.stride()], 2.0);
}

/// Three spheres in a row, the middle one squeezed by both: the pair
/// forces over a list that puts either sphere first equal the plain
/// pair kernel's with the corrections of `surface_corrections` on the
/// middle sphere, and a row too small for them is an error naming the
/// atom.
#[test]
fn a_squeezed_middle_sphere_gets_its_closure_through_the_list() {
    let m = material();
    let coeffs = GranularCoeffs::of(&m);
    let closure = ListClosure {
        closure: Closure::Advanced {
            max_penetration_ratio: 0.1,
            switch: MprSwitch::WholeContact,
            test: MprTest::Signed,
        },
        half_space: HalfSpace::new(0.8, m.youngs_modulus, m.poisson_ratio),
        reach: 0.25,
    };
    let x = [[0.0, 0.0, 0.0], [0.95, 0.01, 0.0], [1.9, 0.0, 0.03]];
    let zero = [[0.0; 3]; 3];
    let v = [[0.01, 0.02, 0.0], [-0.01, 0.0, 0.01], [0.0, -0.02, 0.0]];
    let radius = [0.5; 3];
    let mass = [1.0; 3];
    let tag = [10, 20, 30];
    let atoms = ListAtoms {
        x: &x,
        v: &v,
        omega: &zero,
        radius: &radius,
        mass: &mass,
        tag: &tag,
        n_owned: 3,
    };
    let slots = 4;
    let mut list = GranularList::new(coeffs, Some(closure), slots);
    let hist = Layout::history(slots);
    let corr = Layout::corrections(slots);
    let mut history = vec![0.0; 3 * hist.stride()];
    let mut corrections = vec![0.0; 3 * corr.stride()];
    // Atom 1 is never first in the list: its contacts reach it through
    // its partners' rows.
    let rows = || [(0usize, &[1i32][..]), (2usize, &[1i32][..])].into_iter();
    // First evaluation: no forces remembered, so no corrections.
    list.corrections(&atoms, rows(), &history, &mut corrections, 0)
        .unwrap();
    assert!(corrections.iter().all(|&c| c == 0.0));
    let (mut f, mut t) = (vec![[0.0; 3]; 3], vec![[0.0; 3]; 3]);
    list.forces(
        &atoms,
        rows(),
        &corrections,
        &mut history,
        &mut f,
        &mut t,
        1e-3,
        true,
        true,
        0,
    )
    .unwrap();
    // Both contacts remembered on both sides, with the normal force.
    let f01 = hist.get(&history, 0, 20.0).unwrap()[7];
    let f21 = hist.get(&history, 2, 20.0).unwrap()[7];
    assert!(f01 > 0.0 && f21 > 0.0);
    assert_eq!(hist.get(&history, 1, 10.0).unwrap()[7], f01);
    assert_eq!(hist.get(&history, 1, 30.0).unwrap()[7], f21);
    // The middle sphere keeps each contact from its own side.
    let from_0 = ContactHistory::from_values(hist.get(&history, 0, 20.0).unwrap());
    let from_1 = ContactHistory::from_values(hist.get(&history, 1, 10.0).unwrap());
    assert!(from_0.tangential != [0.0; 3]);
    assert_eq!(from_1, from_0.mirrored());
    // A stale entry (a partner no longer listed) survives a pass
    // without a rebuild and is dropped by one that follows a rebuild.
    assert!(hist.put(&mut history, 0, 99.0, &[1.0; HISTORY_VALUES]));
    let saved = history.clone();
    for renew in [false, true] {
        let mut h = saved.clone();
        let (mut f, mut t) = (vec![[0.0; 3]; 3], vec![[0.0; 3]; 3]);
        list.forces(
            &atoms,
            rows(),
            &corrections,
            &mut h,
            &mut f,
            &mut t,
            0.0,
            false,
            renew,
            0,
        )
        .unwrap();
        assert_eq!(hist.get(&h, 0, 99.0).is_some(), !renew);
        // Both sides of each listed contact are kept.
        for (atom, partner) in [(0, 20.0), (1, 10.0), (1, 30.0), (2, 20.0)] {
            assert_eq!(
                hist.get(&h, atom, partner),
                hist.get(&saved, atom, partner),
                "renew {renew}: atom {atom}, partner {partner}"
            );
        }
    }
    hist.remove(&mut history, 0, 99.0);
    // Second evaluation: the middle sphere's two contacts correct each
    // other as surface_corrections says.
    list.corrections(&atoms, rows(), &history, &mut corrections, 1)
        .unwrap();
    let del = |a: usize, b: usize| super::super::sub(&x[a], &x[b]);
    let r = |d: [f64; 3]| super::super::dot(&d, &d).sqrt();
    let [_, p10] = pair_contact_points(&del(0, 1), r(del(0, 1)), 0.5, 0.5, f01);
    let [_, p12] = pair_contact_points(&del(2, 1), r(del(2, 1)), 0.5, 0.5, f21);
    let mut expect = [0.0; 2];
    surface_corrections(
        &closure.half_space,
        &closure.closure,
        0.5,
        &[p10, p12],
        &mut expect,
    );
    assert!(expect[0] > 0.0 && expect[1] > 0.0, "{expect:?}");
    assert_eq!(corr.get(&corrections, 1, 10.0).unwrap()[0], expect[0]);
    assert_eq!(corr.get(&corrections, 1, 30.0).unwrap()[0], expect[1]);
    // The end spheres have one contact each: nothing to correct.
    assert_eq!(corrections[0], 0.0);
    assert_eq!(corrections[2 * corr.stride()], 0.0);
    // The forces use them: sphere 0's is the kernel's with the middle
    // sphere's surface moved out by its correction.
    let mut h = ContactHistory::from_values(hist.get(&history, 0, 20.0).unwrap());
    let (mut f, mut t) = (vec![[0.0; 3]; 3], vec![[0.0; 3]; 3]);
    list.forces(
        &atoms,
        rows(),
        &corrections,
        &mut history,
        &mut f,
        &mut t,
        1e-3,
        true,
        false,
        1,
    )
    .unwrap();
    let s = |i: usize| sphere(v[i], zero[i], radius[i]);
    let mut s0 = s(0);
    s0.mass = 1.0;
    let mut s1 = s(1);
    s1.mass = 1.0;
    let c01 = corrected_granular_contact(
        &coeffs,
        &del(0, 1),
        &s0,
        &s1,
        [0.0, expect[0]],
        &mut h,
        1e-3,
        true,
    );
    assert_eq!(f[0], c01.force);
    let plain = granular_contact(&coeffs, &del(0, 1), &s0, &s1, &mut h.clone(), 1e-3, true);
    assert!(c01.force[0] < 1.05 * plain.force[0] && c01.force[0] < plain.force[0]);
    // A one-slot row cannot hold the middle sphere's two contacts.
    let mut small = GranularList::new(coeffs, Some(closure), 1);
    let mut h1 = vec![0.0; 3 * Layout::history(1).stride()];
    let c1 = vec![0.0; 3 * Layout::corrections(1).stride()];
    let err = small
        .forces(
            &atoms,
            rows(),
            &c1,
            &mut h1,
            &mut f,
            &mut t,
            1e-3,
            true,
            true,
            0,
        )
        .unwrap_err();
    assert_eq!(err, ListError::RowFull { atom: 20, slots: 1 });
}
