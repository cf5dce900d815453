//! The C ABI gives the kernels' results and reports bad input by status.

mod common;

use bpm::ffi::*;
use bpm::kernels::*;
use common::*;

#[test]
fn bond_abi_matches_the_kernel_with_volumes_and_damping() {
    let (x0, bonds, r0) = random_network(80, 3.5, 1.5, 41);
    let x: Vec<[f64; 3]> = x0
        .iter()
        .map(|p| [p[0] * 1.01, p[1], p[2] * 0.99])
        .collect();
    let v = random_rows(x.len(), 0.1, 42);
    let n = x.len();
    let coeffs = [BondCoeffs {
        k: 1.0,
        a: -0.5,
        gamma: 1.0,
    }];
    let mut vol = vec![0.0; n];
    let mut vol0 = vec![0.0; n];
    let st = unsafe {
        bpm_bond_volumes(
            x.as_ptr() as *const f64,
            n as i64,
            bonds.as_ptr(),
            bonds.len() as i64,
            r0.as_ptr(),
            n as i64,
            1,
            vol.as_mut_ptr(),
            vol0.as_mut_ptr(),
        )
    };
    assert_eq!(st, BPM_OK);
    // The forces through the C ABI, with energy and virial into `tally`
    // (or not summed when it is null).
    let forces = |tally: *mut Tally| {
        let mut f = vec![[0.0; 3]; n];
        let st = unsafe {
            bpm_bond_forces(
                x.as_ptr() as *const f64,
                v.as_ptr() as *const f64,
                n as i64,
                bonds.as_ptr(),
                bonds.len() as i64,
                r0.as_ptr(),
                coeffs.as_ptr(),
                1,
                vol.as_ptr(),
                vol0.as_ptr(),
                n as i64,
                1,
                f.as_mut_ptr() as *mut f64,
                tally,
                std::ptr::null_mut(),
            )
        };
        assert_eq!(st, BPM_OK);
        f
    };
    let mut tally = Tally::default();
    let f = forces(&mut tally);
    let mut fr = vec![[0.0; 3]; n];
    let inputs = BondInputs {
        x: &x,
        v: Some(&v),
        bonds: &bonds,
        r0: &r0,
        coeffs: &coeffs,
        volumes: Some((&vol, &vol0)),
        tally: true,
    };
    let tr = bond_forces(&Unwrapped, &inputs, Ownership::all(n), &mut fr).tally;
    assert_eq!(f, fr);
    assert_eq!(tally, tr);
    assert!(max_abs(&f) > 1e-3);
    assert!(tally.energy > 0.0);
    // A null tally (a step that records nothing) gives the same forces.
    assert_eq!(forces(std::ptr::null_mut()), f);
}

#[test]
fn bad_indices_types_and_nulls_return_status_codes() {
    let x = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]];
    let r0 = [1.0];
    let coeffs = [BondCoeffs {
        k: 1.0,
        a: 0.0,
        gamma: 0.0,
    }];
    let mut f = vec![[0.0; 3]; 2];
    let mut tally = Tally::default();
    let call = |bond: BondEntry, f: &mut Vec<[f64; 3]>, tally: &mut Tally| unsafe {
        bpm_bond_forces(
            x.as_ptr() as *const f64,
            std::ptr::null(),
            2,
            &bond,
            1,
            r0.as_ptr(),
            coeffs.as_ptr(),
            1,
            std::ptr::null(),
            std::ptr::null(),
            2,
            1,
            f.as_mut_ptr() as *mut f64,
            tally,
            std::ptr::null_mut(),
        )
    };
    assert_eq!(
        call(BondEntry { i: 0, j: 5, ty: 1 }, &mut f, &mut tally),
        BPM_ERR_INDEX
    );
    assert_eq!(
        call(BondEntry { i: 0, j: 1, ty: 2 }, &mut f, &mut tally),
        BPM_ERR_TYPE
    );
    assert_eq!(
        call(BondEntry { i: -1, j: 1, ty: 1 }, &mut f, &mut tally),
        BPM_ERR_INDEX
    );
    assert_eq!(f, vec![[0.0; 3]; 2], "nothing is written on error");
    let st = unsafe {
        bpm_bond_forces(
            std::ptr::null(),
            std::ptr::null(),
            2,
            std::ptr::null(),
            1,
            r0.as_ptr(),
            coeffs.as_ptr(),
            1,
            std::ptr::null(),
            std::ptr::null(),
            2,
            1,
            f.as_mut_ptr() as *mut f64,
            &mut tally,
            std::ptr::null_mut(),
        )
    };
    assert_eq!(st, BPM_ERR_NULL);
}

#[test]
fn pair_abi_reads_a_lammps_style_neighbour_list() {
    let x = [[0.0, 0.0, 0.0], [0.8, 0.0, 0.0], [0.0, 0.9, 0.0]];
    let coeffs = [PairCoeffs {
        k: 1.0,
        d: 1.0,
        a: 50.0,
        gamma: 0.0,
    }];
    let ilist = [0i32, 1, 2];
    let n0 = [1i32, 2];
    let n1 = [2i32];
    let numneigh = [2i32, 1, 0];
    let firstneigh = [n0.as_ptr(), n1.as_ptr(), std::ptr::null()];
    let special = [1.0, 0.0, 0.0, 0.0];
    // The forces through the C ABI, with energy and virial into `tally`
    // (or not summed when it is null).
    let forces = |tally: *mut Tally| {
        let mut f = vec![[0.0f64; 3]; 3];
        let st = unsafe {
            bpm_pair_forces(
                x.as_ptr() as *const f64,
                std::ptr::null(),
                std::ptr::null(),
                3,
                1,
                coeffs.as_ptr(),
                3,
                ilist.as_ptr(),
                numneigh.as_ptr(),
                firstneigh.as_ptr(),
                special.as_ptr(),
                3,
                1,
                f.as_mut_ptr() as *mut f64,
                tally,
                std::ptr::null_mut(),
            )
        };
        assert_eq!(st, BPM_OK);
        f
    };
    let mut tally = Tally::default();
    let f = forces(&mut tally);
    // Pair 0-1 at r = 0.8: F = 0.2 + 50 * 0.008 = 0.6, pushing 0 towards -x.
    // Pair 0-2 at r = 0.9: F = 0.1 + 50 * 0.001 = 0.15; pair 1-2 at r > 1: none.
    assert!((f[0][0] + 0.6).abs() < 1e-14 && (f[0][1] + 0.15).abs() < 1e-14);
    assert!((f[1][0] - 0.6).abs() < 1e-14 && (f[2][1] - 0.15).abs() < 1e-14);
    assert!(tally.energy > 0.0 && tally.virial[0] > 0.0);
    // A null tally (a step that records nothing) gives the same forces.
    assert_eq!(forces(std::ptr::null_mut()), f);
}

/// `bpm_bond_single`, behind LAMMPS's `Bond::single` (e.g. `compute
/// bond/local`), against the bulk loop `bond_forces` run on each bond alone.
/// What single() promises (src/ffi.rs, bpm_kernels.h): the force over
/// distance and the spring-proxy energy of the bond, without damping (it
/// gets no velocities), and the multibody term of the `dilation` it is given
/// (the shim passes r * (1 / r0), which leaves that term out).
#[test]
fn single_bond_abi_equals_the_bulk_bond_loop_without_damping() {
    let (x0, bonds, r0) = random_network(60, 3.2, 1.5, 11);
    let x: Vec<[f64; 3]> = x0
        .iter()
        .map(|p| [p[0] * 1.02, p[1] * 0.985, p[2]])
        .collect();
    let v = random_rows(x.len(), 0.1, 12);
    let n = x.len();
    let mut vol = vec![0.0; n];
    let mut vol0 = vec![0.0; n];
    accumulate_volumes(&Unwrapped, &x, &bonds, Ownership::all(n), &mut vol);
    accumulate_reference_volumes(&bonds, &r0, Ownership::all(n), &mut vol0);
    let damped = BondCoeffs {
        k: 1.3,
        a: -0.5,
        gamma: 1.0,
    };
    let undamped = BondCoeffs {
        gamma: 0.0,
        ..damped
    };
    // The bulk loop on one bond: the force on atom i.
    let bulk = |b: &BondEntry, r0: f64, c: BondCoeffs, v: Option<&[[f64; 3]]>, multibody: bool| {
        let mut f = vec![[0.0; 3]; n];
        let inputs = BondInputs {
            x: &x,
            v,
            bonds: std::slice::from_ref(b),
            r0: &[r0],
            coeffs: &[c],
            volumes: multibody.then_some((vol.as_slice(), vol0.as_slice())),
            tally: true,
        };
        let tally = bond_forces(&Unwrapped, &inputs, Ownership::all(n), &mut f).tally;
        assert_eq!(f[b.j as usize], f[b.i as usize].map(|c| -c));
        (f[b.i as usize], tally.energy)
    };
    let single = |r: f64, r0: f64, dilation: f64, c: &BondCoeffs| {
        let mut fforce = f64::NAN;
        let e = unsafe { bpm_bond_single(r, r0, dilation, c, &mut fforce) };
        (fforce, e)
    };
    // fforce = F / r against the bulk loop's F * (1 / r): one rounding
    // apart, so the force rows agree to a few ulp of their largest component.
    let close = |a: [f64; 3], b: [f64; 3]| {
        let scale = a.iter().chain(&b).fold(0.0f64, |m, v| m.max(v.abs()));
        (0..3).all(|k| (a[k] - b[k]).abs() <= 4.0 * f64::EPSILON * scale)
    };
    let mut largest = [0.0f64; 2];
    assert!(bonds.len() > 50, "{} bonds", bonds.len());
    for (b, &r0) in bonds.iter().zip(&r0) {
        let (xi, xj) = (&x[b.i as usize], &x[b.j as usize]);
        let del = Unwrapped.delta(xi, xj);
        let r = Unwrapped.distance(xi, xj);
        let along = |fforce: f64| del.map(|d| d * fforce);
        // The shim's call: dilation r * (1 / r0), no multibody term. The
        // bulk loop without velocities, i.e. without damping, whatever gamma.
        let (fforce, e) = single(r, r0, r * (1.0 / r0), &damped);
        let (f_bulk, e_bulk) = bulk(b, r0, damped, None, false);
        assert!(
            close(along(fforce), f_bulk),
            "bond {b:?}: single {:?}, bulk {f_bulk:?}",
            along(fforce)
        );
        assert!(
            (e - e_bulk).abs() <= 4.0 * f64::EPSILON * e_bulk,
            "bond {b:?}: energy single {e}, bulk {e_bulk}"
        );
        // Damping is left out: the same as the bulk loop with velocities
        // and gamma = 0, and gamma does not change the result.
        let (f_still, _) = bulk(b, r0, undamped, Some(&v), false);
        assert!(close(along(fforce), f_still), "bond {b:?}");
        assert_eq!(single(r, r0, r * (1.0 / r0), &undamped), (fforce, e));
        // Given the bond's dilation, the multibody term is the bulk loop's.
        let d = dilation(
            vol[b.i as usize],
            vol[b.j as usize],
            vol0[b.i as usize],
            vol0[b.j as usize],
        );
        let (fforce_mb, e_mb) = single(r, r0, d, &damped);
        let (f_mb, e_mb_bulk) = bulk(b, r0, damped, None, true);
        assert!(
            close(along(fforce_mb), f_mb),
            "bond {b:?} with multibody: single {:?}, bulk {f_mb:?}",
            along(fforce_mb)
        );
        assert_eq!(e_mb, e);
        assert!((e_mb - e_mb_bulk).abs() <= 4.0 * f64::EPSILON * e_mb_bulk);
        largest[0] = largest[0].max(fforce.abs() * r);
        largest[1] = largest[1].max((fforce_mb - fforce).abs() * r);
    }
    // Spring and multibody forces far above round-off.
    assert!(
        largest[0] > 1e-2 && largest[1] > 1e-3,
        "largest spring force {:e}, multibody term {:e}",
        largest[0],
        largest[1]
    );
}
