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
    let mut f = vec![[0.0; 3]; n];
    let mut tally = Tally::default();
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
            &mut tally,
        )
    };
    assert_eq!(st, BPM_OK);
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
    let tr = bond_forces(&Unwrapped, &inputs, Ownership::all(n), &mut fr);
    assert_eq!(f, fr);
    assert_eq!(tally, tr);
    assert!(max_abs(&f) > 1e-3);
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
    let mut f = vec![[0.0f64; 3]; 3];
    let mut tally = Tally::default();
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
            &mut tally,
        )
    };
    assert_eq!(st, BPM_OK);
    // Pair 0-1 at r = 0.8: F = 0.2 + 50 * 0.008 = 0.6, pushing 0 towards -x.
    // Pair 0-2 at r = 0.9: F = 0.1 + 50 * 0.001 = 0.15; pair 1-2 at r > 1: none.
    assert!((f[0][0] + 0.6).abs() < 1e-14 && (f[0][1] + 0.15).abs() < 1e-14);
    assert!((f[1][0] - 0.6).abs() < 1e-14 && (f[2][1] - 0.15).abs() < 1e-14);
}
