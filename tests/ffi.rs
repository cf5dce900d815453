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
                0,
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

/// Three bonds of one type along x (k = 2, eps_c = 0.1, eps_p = 0.02, no
/// smoothing, no damping, no multibody term): stretched 5% (yields to
/// e_p = 0.03), stretched 15% (breaks), compressed 4% (yields to
/// e_p = -0.02); and a fourth, already broken (type 0), skipped.
#[test]
fn failing_bond_abi_breaks_yields_and_skips_broken_entries() {
    let x = [
        [0.0, 0.0, 0.0],
        [1.05, 0.0, 0.0],
        [10.0, 0.0, 0.0],
        [11.15, 0.0, 0.0],
        [20.0, 0.0, 0.0],
        [20.96, 0.0, 0.0],
    ];
    let mut bonds = [
        BondEntry { i: 0, j: 1, ty: 1 },
        BondEntry { i: 2, j: 3, ty: 1 },
        BondEntry { i: 4, j: 5, ty: 1 },
        BondEntry { i: 0, j: 5, ty: 0 },
    ];
    let r0 = [1.0, 1.0, 1.0, 1.0];
    let mut plastic = [0.0; 4];
    let coeffs = [BondCoeffs {
        k: 2.0,
        a: 0.0,
        gamma: 0.0,
    }];
    let rule = RawBondFailure {
        critical_strain: 0.1,
        plastic_strain: 0.02,
        breaks: 1,
        smooth: 0,
        normalize: 0,
        yields: 1,
    };
    let mut f = [[0.0f64; 3]; 6];
    let mut broken = [-1i32; 4];
    let mut found = FailureCounts::default();
    let mut tally = Tally::default();
    let call_with = |bonds: &mut [BondEntry; 4],
                     plastic: *mut f64,
                     rule: &RawBondFailure,
                     may_break: i32,
                     f: &mut [[f64; 3]; 6],
                     broken: &mut [i32; 4],
                     found: &mut FailureCounts,
                     tally: *mut Tally| unsafe {
        bpm_failing_bond_forces(
            x.as_ptr() as *const f64,
            std::ptr::null(),
            6,
            bonds.as_mut_ptr(),
            4,
            r0.as_ptr(),
            plastic,
            coeffs.as_ptr(),
            rule,
            1,
            may_break,
            std::ptr::null(),
            std::ptr::null(),
            6,
            1,
            f.as_mut_ptr() as *mut f64,
            broken.as_mut_ptr(),
            found,
            tally,
            std::ptr::null_mut(),
        )
    };
    let call = |bonds: &mut [BondEntry; 4],
                plastic: *mut f64,
                rule: &RawBondFailure,
                f: &mut [[f64; 3]; 6],
                broken: &mut [i32; 4],
                found: &mut FailureCounts| {
        call_with(
            bonds,
            plastic,
            rule,
            1,
            f,
            broken,
            found,
            std::ptr::null_mut(),
        )
    };
    let st = call_with(
        &mut bonds,
        plastic.as_mut_ptr(),
        &rule,
        1,
        &mut f,
        &mut broken,
        &mut found,
        &mut tally,
    );
    assert_eq!(st, BPM_OK);
    // Spring proxies k (r - r_eq)^2 / 2 of the two intact bonds, and their
    // virial r_x F_x: -1.05 x -0.04/1.05 ... summed, -0.042 + 0.0384.
    assert!((tally.energy - 8e-4).abs() < 1e-15, "{tally:?}");
    assert!((tally.virial[0] + 0.0036).abs() < 1e-15, "{tally:?}");
    assert_eq!((found.broken, found.yielded), (1, 2));
    assert_eq!(broken[0], 1);
    assert_eq!(
        bonds.iter().map(|b| b.ty).collect::<Vec<_>>(),
        vec![1, 0, 1, 0]
    );
    assert!((plastic[0] - 0.03).abs() < 1e-15 && (plastic[2] + 0.02).abs() < 1e-15);
    assert_eq!(plastic[1], 0.0);
    // Spring at the moved rest length: -k (r - r_eq) along +x on atom i.
    assert!((f[0][0] - 2.0 * (1.05 - 1.03)).abs() < 1e-14, "{:?}", f[0]);
    assert!((f[1][0] + f[0][0]).abs() < 1e-15);
    assert_eq!((f[2], f[3]), ([0.0; 3], [0.0; 3]));
    assert!((f[4][0] - 2.0 * (0.96 - 0.98)).abs() < 1e-14, "{:?}", f[4]);
    // While a run is set up (may_break 0) the 15% bond holds, its force
    // smoothing-free: -k (r - r_eq) with e_p moved to 0.13.
    let mut held = [
        BondEntry { i: 0, j: 1, ty: 1 },
        BondEntry { i: 2, j: 3, ty: 1 },
        BondEntry { i: 4, j: 5, ty: 1 },
        BondEntry { i: 0, j: 5, ty: 0 },
    ];
    let mut ep = [0.0; 4];
    let mut h = [[0.0; 3]; 6];
    let st = call_with(
        &mut held,
        ep.as_mut_ptr(),
        &rule,
        0,
        &mut h,
        &mut broken,
        &mut found,
        std::ptr::null_mut(),
    );
    assert_eq!((st, found.broken, held[1].ty), (BPM_OK, 0, 1));
    assert!((h[2][0] - 2.0 * (1.15 - 1.13)).abs() < 1e-14, "{:?}", h[2]);
    // One bond for LAMMPS's single(): r = 2.1, r0 = 2, e_p = 0.03.
    let mut fforce = f64::NAN;
    let energy =
        unsafe { bpm_failing_bond_single(2.1, 2.0, 0.03, coeffs.as_ptr(), &rule, &mut fforce) };
    assert!(
        (fforce + 2.0 * (2.1 - 2.06) / 2.1).abs() < 1e-15,
        "{fforce}"
    );
    assert!((energy - 0.0016).abs() < 1e-15, "{energy}");
    let strain = RawBondFailure {
        normalize: 1,
        ..rule
    };
    let energy =
        unsafe { bpm_failing_bond_single(2.1, 2.0, 0.03, coeffs.as_ptr(), &strain, &mut fforce) };
    assert!(
        (fforce + 2.0 * (0.05 - 0.03) / 2.1).abs() < 1e-15,
        "{fforce}"
    );
    assert!((energy - 0.0008).abs() < 1e-15, "{energy}");
    // Past the critical strain, and for a refused rule: nothing.
    let past_critical =
        unsafe { bpm_failing_bond_single(2.3, 2.0, 0.0, coeffs.as_ptr(), &rule, &mut fforce) };
    assert_eq!((past_critical, fforce), (0.0, 0.0));
    // Bad input: yielding without plastic strains, a rule the model
    // refuses, an atom out of range.
    let mut fresh = [
        BondEntry { i: 0, j: 1, ty: 1 },
        BondEntry { i: 2, j: 3, ty: 1 },
        BondEntry { i: 4, j: 5, ty: 1 },
        BondEntry { i: 0, j: 9, ty: 1 },
    ];
    let mut g = [[0.0; 3]; 6];
    let st = call(
        &mut fresh,
        std::ptr::null_mut(),
        &rule,
        &mut g,
        &mut broken,
        &mut found,
    );
    assert_eq!(st, BPM_ERR_NULL);
    let past = RawBondFailure {
        plastic_strain: 0.2,
        ..rule
    };
    let st = call(
        &mut fresh,
        plastic.as_mut_ptr(),
        &past,
        &mut g,
        &mut broken,
        &mut found,
    );
    assert_eq!(st, BPM_ERR_TYPE);
    let st = call(
        &mut fresh,
        plastic.as_mut_ptr(),
        &rule,
        &mut g,
        &mut broken,
        &mut found,
    );
    assert_eq!(st, BPM_ERR_INDEX);
    // The refused rule's reason, naming the values.
    let mut message = [0 as std::ffi::c_char; 256];
    let st = unsafe { bpm_check_bond_failure(&past, message.as_mut_ptr(), 256) };
    let text = unsafe { std::ffi::CStr::from_ptr(message.as_ptr()) }.to_string_lossy();
    assert_eq!(st, BPM_ERR_STOPPED);
    assert!(
        text.contains("eps_p = 0.2") && text.contains("eps_c = 0.1"),
        "{text}"
    );
    assert_eq!(
        unsafe { bpm_check_bond_failure(&rule, std::ptr::null_mut(), 0) },
        BPM_OK
    );
}

/// The multibody term over intact bonds: in a solid whose bonds all sit
/// at their rest lengths, yielded or not, it adds no force, and a broken
/// entry (type 0, given a rest length far from its length) counts in
/// neither volume.
#[test]
fn intact_volumes_leave_a_solid_at_its_rest_lengths_without_force() {
    let (x0, mut bonds, r0) = random_network(60, 3.0, 1.5, 7);
    let n = x0.len();
    // Rest lengths r_eq = r0 (1 + e_p) equal to the lengths as they are.
    let plastic: Vec<f64> = (0..bonds.len()).map(|k| 0.01 * (k % 5) as f64).collect();
    let mut first: Vec<f64> = r0
        .iter()
        .zip(&plastic)
        .map(|(r, e)| r / (1.0 + e))
        .collect();
    bonds[3].ty = 0;
    first[3] *= 0.5;
    let mut vol = vec![0.0; n];
    let mut vol0 = vec![0.0; n];
    let st = unsafe {
        bpm_intact_bond_volumes(
            x0.as_ptr() as *const f64,
            n as i64,
            bonds.as_ptr(),
            bonds.len() as i64,
            first.as_ptr(),
            plastic.as_ptr(),
            n as i64,
            1,
            vol.as_mut_ptr(),
            vol0.as_mut_ptr(),
        )
    };
    assert_eq!(st, BPM_OK);
    for (v, v0) in vol.iter().zip(&vol0) {
        assert!((v - v0).abs() <= 1e-13 * v0.max(1.0), "{v} {v0}");
    }
    let coeffs = [BondCoeffs {
        k: 0.0,
        a: -0.5,
        gamma: 0.0,
    }];
    let rule = RawBondFailure {
        critical_strain: 0.5,
        plastic_strain: 0.1,
        breaks: 1,
        smooth: 1,
        normalize: 0,
        yields: 1,
    };
    let mut ep = plastic.clone();
    let mut f = vec![[0.0f64; 3]; n];
    let mut broken = vec![0i32; bonds.len()];
    let st = unsafe {
        bpm_failing_bond_forces(
            x0.as_ptr() as *const f64,
            std::ptr::null(),
            n as i64,
            bonds.as_mut_ptr(),
            bonds.len() as i64,
            first.as_ptr(),
            ep.as_mut_ptr(),
            coeffs.as_ptr(),
            &rule,
            1,
            1,
            vol.as_ptr(),
            vol0.as_ptr(),
            n as i64,
            1,
            f.as_mut_ptr() as *mut f64,
            broken.as_mut_ptr(),
            std::ptr::null_mut(),
            std::ptr::null_mut(),
            std::ptr::null_mut(),
        )
    };
    assert_eq!(st, BPM_OK);
    let largest = f.iter().flatten().fold(0.0f64, |m, c| m.max(c.abs()));
    assert!(largest < 1e-12, "largest multibody force {largest:e}");
    assert_eq!(ep, plastic);
}

/// The rows' C ABI (`bpm_list_rows_*`): the list pass's forces, breaks
/// and types through it, and a status for each misuse: another bond type,
/// an atom outside the atoms, calls out of step with the sync.
#[test]
fn list_rows_abi_gives_the_list_pass_and_refuses_misuse() {
    let (x0, mut bonds, r0) = random_network(60, 3.2, 1.5, 17);
    // Stretched 6% along x: some bonds past eps_c = 0.05.
    let x: Vec<[f64; 3]> = x0.iter().map(|p| [p[0] * 1.06, p[1], p[2]]).collect();
    let v = random_rows(x.len(), 0.1, 18);
    let n = x.len();
    let nb = bonds.len();
    bonds[3].ty = 0;
    let coeffs = BondCoeffs {
        k: 1.0,
        a: -0.5,
        gamma: 0.5,
    };
    let rule = RawBondFailure {
        critical_strain: 0.05,
        plastic_strain: 0.0,
        breaks: 1,
        smooth: 1,
        normalize: 0,
        yields: 0,
    };
    let mut vol = vec![0.0; n];
    let mut vol0 = vec![0.0; n];
    // The list pass through its C ABI.
    let mut list_bonds = bonds.clone();
    let st = unsafe {
        bpm_intact_bond_volumes(
            x.as_ptr() as *const f64,
            n as i64,
            list_bonds.as_ptr(),
            nb as i64,
            r0.as_ptr(),
            std::ptr::null(),
            n as i64,
            0,
            vol.as_mut_ptr(),
            vol0.as_mut_ptr(),
        )
    };
    assert_eq!(st, BPM_OK);
    let mut f_list = vec![[0.0f64; 3]; n];
    let mut broken_list = vec![-1i32; nb];
    let mut found_list = FailureCounts::default();
    let st = unsafe {
        bpm_failing_bond_forces(
            x.as_ptr() as *const f64,
            v.as_ptr() as *const f64,
            n as i64,
            list_bonds.as_mut_ptr(),
            nb as i64,
            r0.as_ptr(),
            std::ptr::null_mut(),
            &coeffs,
            &rule,
            1,
            1,
            vol.as_ptr(),
            vol0.as_ptr(),
            n as i64,
            0,
            f_list.as_mut_ptr() as *mut f64,
            broken_list.as_mut_ptr(),
            &mut found_list,
            std::ptr::null_mut(),
            std::ptr::null_mut(),
        )
    };
    assert_eq!(st, BPM_OK);
    assert!(found_list.broken > 0, "some bonds must break");
    // The same through the rows.
    let rows = bpm_list_rows_create();
    let mut row_bonds = bonds.clone();
    let sync = |bonds: &[BondEntry], nall: i64, stale: &mut i32| unsafe {
        bpm_list_rows_sync(
            rows,
            1,
            0,
            bonds.as_ptr(),
            bonds.len() as i64,
            r0.as_ptr(),
            std::ptr::null(),
            nall,
            stale,
        )
    };
    let (mut row_vol, mut row_vol0) = (vec![0.0; n], vec![0.0; n]);
    let volumes = |nall: i64, vol: &mut [f64], vol0: *mut f64| unsafe {
        bpm_list_rows_volumes(
            rows,
            x.as_ptr() as *const f64,
            nall,
            n as i64,
            0,
            vol.as_mut_ptr(),
            vol0,
        )
    };
    let mut f_rows = vec![[0.0f64; 3]; n];
    let mut broken_rows = vec![-1i32; nb];
    let mut found_rows = FailureCounts::default();
    let forces = |bonds: &mut [BondEntry],
                  vol: *const f64,
                  f: &mut [[f64; 3]],
                  broken: &mut [i32],
                  found: &mut FailureCounts| unsafe {
        bpm_list_rows_forces(
            rows,
            x.as_ptr() as *const f64,
            v.as_ptr() as *const f64,
            n as i64,
            &coeffs,
            &rule,
            1,
            vol,
            n as i64,
            f.as_mut_ptr() as *mut f64,
            bonds.as_mut_ptr(),
            bonds.len() as i64,
            std::ptr::null_mut(),
            broken.as_mut_ptr(),
            found,
            std::ptr::null_mut(),
        )
    };
    let mut stale = 0;
    // Misuse first: nothing synced, another type, an atom outside.
    assert_eq!(
        volumes(n as i64, &mut row_vol, std::ptr::null_mut()),
        BPM_ERR_STALE
    );
    let mut typed = bonds.clone();
    typed[5].ty = 2;
    assert_eq!(sync(&typed, n as i64, &mut stale), BPM_ERR_TYPE);
    let mut outside = bonds.clone();
    outside[7].j = n as i32;
    assert_eq!(sync(&outside, n as i64, &mut stale), BPM_ERR_INDEX);
    assert_eq!(sync(&bonds, n as i64, &mut stale), BPM_OK);
    assert_eq!(stale, 1, "new rows need V0");
    // Forces with the multibody term before this step's volumes and V0.
    let mut scratch = vec![[0.0f64; 3]; n];
    assert_eq!(
        forces(
            &mut row_bonds,
            row_vol.as_ptr(),
            &mut scratch,
            &mut broken_rows,
            &mut found_rows
        ),
        BPM_ERR_STALE
    );
    assert_eq!(
        volumes(n as i64 + 1, &mut row_vol, std::ptr::null_mut()),
        BPM_ERR_STALE
    );
    assert_eq!(
        volumes(n as i64, &mut row_vol, row_vol0.as_mut_ptr()),
        BPM_OK
    );
    assert_eq!(row_vol, vol);
    assert_eq!(row_vol0, vol0);
    assert_eq!(
        unsafe { bpm_list_rows_set_reference(rows, row_vol0.as_ptr(), n as i64) },
        BPM_OK
    );
    assert_eq!(
        forces(
            &mut row_bonds,
            row_vol.as_ptr(),
            &mut f_rows,
            &mut broken_rows,
            &mut found_rows
        ),
        BPM_OK
    );
    let bits = |f: &[[f64; 3]]| f.iter().flatten().map(|c| c.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&f_rows), bits(&f_list));
    assert_eq!(
        (found_rows.broken, found_rows.yielded),
        (found_list.broken, 0)
    );
    assert_eq!(broken_rows, broken_list);
    assert_eq!(row_bonds, list_bonds);
    // The lengths are spent: a second pass needs this step's volumes.
    assert_eq!(
        forces(
            &mut row_bonds,
            row_vol.as_ptr(),
            &mut scratch,
            &mut broken_rows,
            &mut found_rows
        ),
        BPM_ERR_STALE
    );
    unsafe { bpm_list_rows_destroy(rows) };
}
