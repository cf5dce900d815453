//! Blow-ups are caught and named: the kernels flag the first bond out of
//! the model's range (collapsed, overstretched, non-finite) at the
//! documented thresholds on every instruction set; the C ABI reports it with
//! its own status and a message; the native engine stops with the step, the
//! particles and the likely cause; the plugin stops LAMMPS with the atoms'
//! IDs.

use bpm::ffi::{bpm_bond_forces, bpm_describe_fault, RawFault, BPM_ERR_UNSTABLE, BPM_OK};
use bpm::kernels::*;

/// A straight chain of `n` unit bonds along x, every bond at its
/// reference length except the ones `stretch` lists: `(bond, r / r0)`.
fn chain(n: usize, stretch: &[(usize, f64)]) -> (Vec<[f64; 3]>, Vec<BondEntry>, Vec<f64>) {
    let mut x = vec![[0.0; 3]];
    for b in 0..n {
        let ratio = stretch
            .iter()
            .find(|(s, _)| *s == b)
            .map_or(1.0, |(_, r)| *r);
        let last = x[b][0];
        x.push([last + ratio, 0.0, 0.0]);
    }
    let bonds = (0..n)
        .map(|b| BondEntry {
            i: b as i32,
            j: b as i32 + 1,
            ty: 1,
        })
        .collect();
    (x, bonds, vec![1.0; n])
}

/// The fault of one bond pass over the chain on `isa`, with the multibody
/// and damping terms on or off.
fn fault_of(
    isa: Isa,
    x: &[[f64; 3]],
    bonds: &[BondEntry],
    r0: &[f64],
    multibody: bool,
    damped: bool,
) -> Option<Fault> {
    let n = x.len();
    let all = Ownership::all(n);
    let (mut vol, mut vol0) = (vec![0.0; n], vec![0.0; n]);
    accumulate_volumes(&Unwrapped, x, bonds, all, &mut vol);
    accumulate_reference_volumes(bonds, r0, all, &mut vol0);
    let v = vec![[0.01, 0.0, 0.0]; n];
    let coeffs = [BondCoeffs {
        k: 1.0,
        a: if multibody { -0.5 } else { 0.0 },
        gamma: 1.0,
    }];
    let inputs = BondInputs {
        x,
        v: damped.then_some(&v[..]),
        bonds,
        r0,
        coeffs: &coeffs,
        volumes: multibody.then_some((&vol[..], &vol0[..])),
        tally: false,
    };
    let mut f = vec![[0.0; 3]; n];
    bond_forces_on(isa, &Unwrapped, &inputs, all, &mut f).fault
}

fn every_variant(
    mut check: impl FnMut(&dyn Fn(&[[f64; 3]], &[BondEntry], &[f64]) -> Option<Fault>),
) {
    for isa in [Isa::Portable, Isa::Avx2] {
        if !isa.available() {
            continue;
        }
        for multibody in [false, true] {
            for damped in [false, true] {
                check(&|x, b, r0| fault_of(isa, x, b, r0, multibody, damped));
            }
        }
    }
}

#[test]
fn bonds_at_the_thresholds_are_judged_on_either_side_in_every_kernel_variant() {
    // 20 bonds: three blocks of 8 lanes, the last one partly filled.
    every_variant(|pass| {
        let (x, b, r0) = chain(20, &[]);
        assert_eq!(pass(&x, &b, &r0), None, "an unstrained chain");
        for (ratio, kind) in [
            (COLLAPSED_BELOW * 1.01, None),
            (COLLAPSED_BELOW * 0.99, Some(FaultKind::BondCollapsed)),
            (OVERSTRETCHED_ABOVE * 0.99, None),
            (
                OVERSTRETCHED_ABOVE * 1.01,
                Some(FaultKind::BondOverstretched),
            ),
        ] {
            for bond in [0, 7, 8, 19] {
                let (x, b, r0) = chain(20, &[(bond, ratio)]);
                let found = pass(&x, &b, &r0);
                assert_eq!(found.map(|f| f.kind), kind, "bond {bond} at {ratio} r0");
                if let Some(f) = found {
                    assert_eq!(
                        (f.bond, f.i, f.j),
                        (bond as i64, bond as i64, bond as i64 + 1)
                    );
                    assert!(f.bonded);
                    assert!((f.r - ratio).abs() < 1e-12 && f.reference == 1.0);
                }
            }
        }
    });
}

#[test]
fn the_first_faulty_bond_in_list_order_is_reported() {
    every_variant(|pass| {
        let (x, b, r0) = chain(20, &[(17, 5.0), (11, 0.1), (13, 0.1)]);
        let f = pass(&x, &b, &r0).expect("three faulty bonds");
        assert_eq!((f.bond, f.kind), (11, FaultKind::BondCollapsed));
    });
}

#[test]
fn a_non_finite_position_is_a_fault_of_its_bond() {
    every_variant(|pass| {
        let (mut x, b, r0) = chain(20, &[]);
        x[9][1] = f64::NAN;
        let f = pass(&x, &b, &r0).expect("NaN position");
        // Bond 8 holds particle 9; with the multibody term the NaN volume
        // of particle 8 already spoils bond 7, first in list order.
        assert_eq!(f.kind, FaultKind::NonFinite);
        assert!(f.bond == 8 || f.bond == 7, "bond {}", f.bond);
        x[9][1] = f64::INFINITY;
        assert_eq!(
            pass(&x, &b, &r0).map(|f| f.kind),
            Some(FaultKind::NonFinite)
        );
    });
}

#[test]
fn pairs_fault_only_on_non_finite_values_not_on_deep_overlap() {
    // A random fill starts with particles nearly on top of each other: the
    // contact force is bounded, so overlap alone must not stop a run.
    let x = [[0.0, 0.0, 0.0], [0.05, 0.0, 0.0], [f64::NAN, 0.0, 0.0]];
    let coeffs = [PairCoeffs {
        k: 1.0,
        d: 1.0,
        a: 50.0,
        gamma: 0.0,
    }];
    let inputs = PairInputs {
        x: &x,
        v: None,
        types: None,
        ntypes: 1,
        coeffs: &coeffs,
        special: [1.0; 4],
        tally: false,
        damping_taper: false,
    };
    // The fault of particle 0's contact with `partner`.
    let fault_with = |partner: i32| {
        let mut f = vec![[0.0; 3]; 3];
        let row = [partner];
        pair_forces(
            &Unwrapped,
            &inputs,
            [(0usize, &row[..])].into_iter(),
            Ownership::all(3),
            &mut f,
        )
        .fault
    };
    assert_eq!(fault_with(1), None, "deep overlap");
    let fault = fault_with(2).expect("NaN partner");
    assert_eq!(
        (fault.kind, fault.i, fault.j, fault.bonded),
        (FaultKind::NonFinite, 0, 2, false)
    );
}

#[test]
fn the_c_abi_reports_a_fault_with_its_own_status_and_a_message() {
    let (x, bonds, r0) = chain(10, &[(4, 0.1)]);
    let coeffs = [BondCoeffs {
        k: 1.0,
        a: 0.0,
        gamma: 0.0,
    }];
    let call = |x: &[[f64; 3]], fault: *mut Fault, f: &mut Vec<[f64; 3]>| unsafe {
        bpm_bond_forces(
            x.as_ptr() as *const f64,
            std::ptr::null(),
            x.len() as i64,
            bonds.as_ptr(),
            bonds.len() as i64,
            r0.as_ptr(),
            coeffs.as_ptr(),
            1,
            std::ptr::null(),
            std::ptr::null(),
            x.len() as i64,
            1,
            f.as_mut_ptr() as *mut f64,
            std::ptr::null_mut(),
            fault,
        )
    };
    let mut f = vec![[0.0; 3]; x.len()];
    let mut fault = std::mem::MaybeUninit::<Fault>::uninit();
    assert_eq!(call(&x, fault.as_mut_ptr(), &mut f), BPM_ERR_UNSTABLE);
    let fault = unsafe { fault.assume_init() };
    assert_eq!(
        (fault.kind, fault.bond, fault.i, fault.j),
        (FaultKind::BondCollapsed, 4, 4, 5)
    );
    assert!(f[4][0] != 0.0, "the forces are still computed");
    // A null fault still gets the status.
    assert_eq!(call(&x, std::ptr::null_mut(), &mut f), BPM_ERR_UNSTABLE);
    let (ok_x, _, _) = chain(10, &[]);
    let mut g = vec![[0.0; 3]; ok_x.len()];
    assert_eq!(call(&ok_x, std::ptr::null_mut(), &mut g), BPM_OK);

    // The message, as the plugin asks for it: atom IDs, step, cause.
    let raw = RawFault {
        kind: fault.kind as i32,
        i: fault.i,
        j: fault.j,
        r: fault.r,
        reference: fault.reference,
        bonded: 1,
        bond: fault.bond,
    };
    let describe = |raw: &RawFault, len: usize, dt: f64| {
        let mut buf = vec![1u8; len.max(1)];
        let n = unsafe {
            bpm_describe_fault(
                raw,
                105,
                106,
                4242,
                dt,
                coeffs.as_ptr(),
                1.0,
                buf.as_mut_ptr() as *mut std::ffi::c_char,
                len as i64,
            )
        };
        (n, buf)
    };
    let (n, buf) = describe(&raw, 1024, 0.1);
    let text = std::ffi::CStr::from_bytes_until_nul(&buf)
        .unwrap()
        .to_str()
        .unwrap();
    assert_eq!(n as usize, text.len());
    for words in [
        "step 4242",
        "atoms with IDs 105 and 106",
        "collapsed to 0.100",
        "Likely cause",
    ] {
        assert!(text.contains(words), "`{words}` missing from: {text}");
    }
    // dt far above the limit: the timestep is named.
    let (_, buf) = describe(&raw, 1024, 5.0);
    let text = std::ffi::CStr::from_bytes_until_nul(&buf)
        .unwrap()
        .to_str()
        .unwrap();
    assert!(text.contains("timestep dt = 5"), "{text}");
    // Cut to the buffer, always terminated.
    let (n, buf) = describe(&raw, 16, 0.1);
    assert!(n > 16);
    assert_eq!(buf.iter().position(|&c| c == 0), Some(15));
    // A kind C made up is refused, not trusted.
    let bogus = RawFault { kind: 99, ..raw };
    assert!(describe(&bogus, 64, 0.1).0 < 0);
}

/// The error of a native run of a small bulk solid (quick build) at `a_b`,
/// given random velocities and compressed by `strain` at timestep `dt`.
fn native_blow_up(a_b: f64, dt: f64, strain: f64) -> (String, u64) {
    use bpm::scene::builders::bulk::{build_bulk, BulkParams};
    use bpm::scene::{protocols, run_native_report, ForceField, RunOptions, VelocityInit};
    let mut scene = build_bulk(&BulkParams::shortened(6.0, 5, 0.0), 1, false)
        .unwrap()
        .0;
    scene.force_field = ForceField::paper(a_b);
    let mut stage = protocols::isotropic_compression(strain, 1e-3, dt, 10);
    stage.set_velocities = Some(VelocityInit { rms_speed: 0.03 });
    let planned = stage.steps;
    scene.stages = vec![stage];
    let (report, _) = run_native_report(
        &scene,
        std::path::Path::new("blow-up"),
        0,
        &RunOptions::quiet(1),
    );
    (report.error.unwrap_or_default(), planned)
}

#[test]
fn the_native_engine_names_the_step_the_particles_and_a_too_large_timestep() {
    // Paper damping: the limit is about 0.18 tau (results/stability).
    let (err, planned) = native_blow_up(0.0, 0.5, 0.01);
    assert!(err.contains("simulation became unstable at step"), "{err}");
    assert!(err.contains("the bond between particles"), "{err}");
    assert!(err.contains("timestep dt = 0.5"), "{err}");
    let step: u64 = err["simulation became unstable at step ".len()..]
        .split(':')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(step < planned, "stopped at step {step} of {planned}");
    // The paper's timestep runs the same compression to the end.
    let (err, _) = native_blow_up(0.0, 0.1, 0.01);
    assert_eq!(err, "", "dt = 0.1 is stable");
}

#[test]
fn the_native_engine_names_a_b_beyond_the_incompressible_limit() {
    let (err, _) = native_blow_up(-1.3, 0.05, 0.05);
    assert!(err.contains("collapsed"), "{err}");
    assert!(
        err.contains("a_B = -1.3 is at or beyond the incompressible limit"),
        "{err}"
    );
}

#[test]
fn the_timestep_estimate_is_the_verlet_limit_of_the_stiffest_mode() {
    // a_B = 0: damping and stiffness share their modes, c = Gamma lambda.
    let c = BondCoeffs {
        k: 1.0,
        a: 0.0,
        gamma: 1.0,
    };
    let lambda = STIFFEST_MODE;
    let dt = stable_timestep(&c, 1.0, 1.0);
    assert!((lambda * dt * dt + 2.0 * lambda * dt - 4.0).abs() < 1e-12);
    // Undamped: 2 / sqrt(lambda); heavier particles allow longer steps.
    let undamped = BondCoeffs { gamma: 0.0, ..c };
    assert!((stable_timestep(&undamped, 1.0, 1.0) - 2.0 / lambda.sqrt()).abs() < 1e-12);
    assert!((stable_timestep(&undamped, 1.0, 4.0) - 4.0 / lambda.sqrt()).abs() < 1e-12);
    // A positive a_B stiffens the bonds; a negative one is not credited
    // (the measured limit falls again near the incompressible end); no
    // stiffness at all means no limit.
    let stiff = BondCoeffs { a: 2.0, ..c };
    assert!(stable_timestep(&stiff, 1.0, 1.0) < dt);
    let soft = BondCoeffs { a: -0.9, ..c };
    assert_eq!(stable_timestep(&soft, 1.0, 1.0), dt);
    let none = BondCoeffs {
        k: 0.0,
        a: -0.5,
        ..c
    };
    assert_eq!(stable_timestep(&none, 1.0, 1.0), f64::INFINITY);
}
